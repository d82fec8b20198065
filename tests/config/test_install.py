"""make install puts the binaries and the shipped configuration under a prefix, and the installed
scenes still validate there (their mesh paths are relative to the scene folder)."""
import subprocess


def test_install_tree_is_complete_and_valid(build_dir, tmp_path):
    subprocess.run(["cmake", "--install", str(build_dir), "--prefix", str(tmp_path)],
                   check=True, capture_output=True, timeout=120)
    tool = tmp_path / "bin" / "haptic-config"
    share = tmp_path / "share" / "hapfluid"
    assert tool.exists()
    scenes = sorted((share / "scenes").glob("*.toml"))
    rigs = sorted((share / "rigs").glob("*.toml"))
    assert (share / "meshes" / "spoon.obj").exists()
    result = subprocess.run([str(tool), "check", *map(str, rigs + scenes)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
