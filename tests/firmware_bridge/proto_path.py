"""Makes scripts/ importable so the tests use the very hapfluid_proto package the tools use."""
import pathlib
import sys

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
if str(SOURCE_DIR / "scripts") not in sys.path:
    sys.path.insert(0, str(SOURCE_DIR / "scripts"))
VECTORS = SOURCE_DIR / "firmware_bridge" / "test_vectors" / "vectors.json"
DBC = SOURCE_DIR / "firmware_bridge" / "dbc" / "hapfluid.dbc"
