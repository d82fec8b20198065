"""Every shipped scene is accepted by the simulator itself, not only by the schema: its set-up
checks (bodies clear of the walls, sampling spacing against the mesh, particle counts) pass and a
few steps run. A scene that validates but cannot run would only fail on a rig."""
import json
import subprocess

import pytest

from conftest import SOURCE_DIR

SCENES = sorted((SOURCE_DIR / "config" / "scenes").glob("*.toml"))


@pytest.mark.parametrize("scene", SCENES, ids=[s.stem for s in SCENES])
def test_scene_sets_up_and_steps(binary, scene, tmp_path):
    out = tmp_path / "run"
    result = subprocess.run([str(binary("haptic-sim")), "--scene", str(scene), "--backend", "cpu",
                             "--duration", "0.02", "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    stats = json.loads((out / "stats.json").read_text())
    assert stats["steps"] >= 1
