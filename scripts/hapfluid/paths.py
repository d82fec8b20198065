"""Where the package finds the project's data: the checkout it lives in (an editable install in the
project venv), or the data folder of an installed package."""
import os
import pathlib

_CHECKOUT = pathlib.Path(__file__).resolve().parents[2]


def _root() -> pathlib.Path:
    override = os.environ.get("HAPFLUID_ROOT")
    if override:
        return pathlib.Path(override)
    if (_CHECKOUT / "config" / "scenes").is_dir():
        return _CHECKOUT
    return pathlib.Path("/usr/share/hapfluid")


ROOT = _root()
SCENES = ROOT / "config" / "scenes"
RIGS = ROOT / "config" / "rigs"
DBC = ROOT / "firmware_bridge" / "dbc" / "hapfluid.dbc"
