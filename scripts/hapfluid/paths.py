"""Where the package finds the project's data: the checkout it lives in (the editable install of
the project venv, or HAPFLUID_ROOT naming a checkout), else what `make install` or the
Debian package put under <prefix>/share/hapfluid (scenes/, rigs/, meshes/, hapfluid.dbc), with the
binaries in <prefix>/bin."""
import os
import pathlib

_CHECKOUT = pathlib.Path(__file__).resolve().parents[2]


def _checkout():
    override = os.environ.get("HAPFLUID_ROOT")
    if override:
        return pathlib.Path(override)
    return _CHECKOUT if (_CHECKOUT / "config" / "scenes").is_dir() else None


def _installed_data():
    for prefix in ("/usr", "/usr/local"):
        data = pathlib.Path(prefix) / "share" / "hapfluid"
        if (data / "scenes").is_dir():
            return data
    return None


_root = _checkout()
if _root is not None:
    # ROOT: builds and outputs are found and written under the checkout.
    ROOT = _root
    SCENES, RIGS = ROOT / "config" / "scenes", ROOT / "config" / "rigs"
    DBC = ROOT / "firmware_bridge" / "dbc" / "hapfluid.dbc"
    BIN = ROOT / "build" / "bin"  # the default build folder's (make)
else:
    # Installed: outputs go under the working directory, data comes from the install.
    ROOT = pathlib.Path.cwd()
    _data = _installed_data() or pathlib.Path("/usr/local/share/hapfluid")
    SCENES, RIGS, DBC = _data / "scenes", _data / "rigs", _data / "hapfluid.dbc"
    BIN = _data.parents[1] / "bin"  # <prefix>/bin beside <prefix>/share/hapfluid
