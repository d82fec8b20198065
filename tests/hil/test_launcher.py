"""`make run`'s launcher (scripts/hapfluid.py): the live stack as separate processes, stopped in
order, with every output a user opens afterwards."""
import json
import os
import subprocess
import sys

from hil_stack import ROOT


def test_a_short_live_run_leaves_its_outputs_and_nothing_else(build_dir, tmp_path):
    out = tmp_path / "run"
    result = subprocess.run([sys.executable, str(ROOT / "scripts" / "hapfluid.py"), "run", "--scene", "spoon_stirring",
                             "--build", str(build_dir), "--out", str(out), "--duration", "3", "--no-render"],
                            capture_output=True, text=True, timeout=90)
    assert result.returncode == 0, result.stdout + result.stderr
    for name in ("device_hand.csv", "sim/couplings.csv", "sim/bodies.csv", "sim/stats.json", "wrenches.png",
                 "trace.csv", "latency.png", "latency.json", "summary.json"):
        assert (out / name).exists() and (out / name).stat().st_size > 0, name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ok"] and summary["sim_steps_per_s"] > 0 and summary["max_force_on_hand_n"]["hand"] > 0
    assert "p99" in summary["wake_latency_us"]
    assert "steps/s" in result.stdout and "wake latency" in result.stdout and "max force on the hand" in result.stdout
    # The summary names the backend the sim ran on and why (--backend auto: Vulkan only if it keeps up).
    assert summary["sim_backend"] in ("vulkan", "cpu") and summary["sim_device"] and summary["sim_backend_reason"]
    assert f"{summary['sim_backend']} backend on {summary['sim_device']}" in result.stdout
    # Every process stopped with exit 0 (the launcher checks) and took its segments with it.
    prefix = next(l for l in (out / "logs" / "haptic-rt.log").read_text().splitlines() if "shm /" in l)
    prefix = prefix.split("shm /")[1].split(".*")[0]
    assert not [n for n in os.listdir("/dev/shm") if n.startswith(prefix + ".")]


def test_an_unknown_scene_is_named_with_the_known_ones(build_dir, tmp_path):
    result = subprocess.run([sys.executable, str(ROOT / "scripts" / "hapfluid.py"), "run", "--scene", "no_such_scene",
                             "--build", str(build_dir), "--out", str(tmp_path)], capture_output=True, text=True, timeout=30)
    assert result.returncode != 0 and "no_such_scene" in result.stderr and "spoon_stirring" in result.stderr
