"""hapfluid's Python tools: the device wire codec (`hapfluid.proto`), the python-can interface of
the loopback bus, the launcher of the live stack (`python -m hapfluid run`), and the plots and
latency reports of its runs."""
from importlib import metadata

try:
    __version__ = metadata.version("hapfluid")
except metadata.PackageNotFoundError:  # imported from a checkout without installing it
    __version__ = "0+unknown"
