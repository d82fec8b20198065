"""The protocol's shared files: the test vectors every codec is checked against, and the DBC."""
import pathlib

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
VECTORS = SOURCE_DIR / "firmware_bridge" / "test_vectors" / "vectors.json"
DBC = SOURCE_DIR / "firmware_bridge" / "dbc" / "hapfluid.dbc"
