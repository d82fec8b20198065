"""The live stack with the simulator on Vulkan (lavapipe on CI): real haptic-rt, fake hand playing
the stirring scene's stroke, haptic-sim --live --backend vulkan. The hand feels the same physics
as with the cpu backend (tests/hil/test_live_scenes.py), and the run says which device computed it
and whether it kept up with the wall clock."""
import json
import time

import numpy as np

from hil_stack import LEAD_IN_S, SCENES, Stack, read_csv

RUN_S = 6.0  # lead-in 1.5 s, the stroke from 1 s of scene time (0.3 s ramp): ~3 s of stroke


def test_on_vulkan_the_stirring_force_opposes_the_spoons_motion(binary, tmp_path):
    # §6.4.1, fig. 8, as on the cpu backend: the fluid drags the spoon, so the force the hand
    # feels along the stroke is anti-correlated with the hand's velocity. Lavapipe on 2 cores
    # steps this scene slower than real time: the fluid then runs slower, which the sim must
    # report (never silently), but the wrench still comes from every step against the newest pose.
    stack = Stack(binary, tmp_path, tag="vkstir")
    try:
        stack.fake_device("hand", motion=f"scene:{SCENES / 'spoon_stirring.toml'}:hand")
        stack.rt()
        stack.sim("spoon_stirring", backend="vulkan")
        time.sleep(RUN_S)
        codes = {name: stack.stop(name) for name in ("rt", "sim", "fake-hand")}
    finally:
        stack.close()
    assert codes == {"rt": 0, "sim": 0, "fake-hand": 0}, {n: stack.log(n)[-600:] for n in codes}
    assert stack.leftovers() == []

    log = read_csv(stack.dir / "fake-hand.csv")
    t = np.array([r["t_s"] for r in log])
    vx = np.gradient(np.array([r["px"] for r in log]), t)
    fx = np.array([r["applied_fx"] for r in log])
    stroke = (t > LEAD_IN_S + 1.3) & (t < t[-1] - 0.3)
    assert np.mean(np.abs(vx[stroke])) > 0.05, "the scripted hand did not stroke (m/s)"
    assert np.max(np.abs(fx[stroke])) > 0.5, "the hand felt no fluid (N)"
    assert np.corrcoef(fx[stroke], vx[stroke])[0, 1] < -0.2

    stats = json.loads((stack.dir / "sim" / "stats.json").read_text())
    assert stats["complete"] and stats["backend"] == "vulkan"
    assert stats["device"]["name"] and stats["device"]["name"] in stack.log("sim")
    assert stats["device_matches"] == ["hand -> hand"]
    # Samples went out every step (what the 1 kHz loop renders), particles at the frame rate.
    assert stats["sim_samples_published"] == stats["steps"] > 500
    assert stats["particle_frames_published"] > 60 * stats["simulated_time_s"] * 0.9
    # Slower than real time is said, in stats.json and on stderr, never silent.
    if stats["real_time_factor"] < 0.9:
        assert not stats["kept_up_with_wall_clock"] and stats["dropped_backlog_s"] > 0
        assert "cannot keep up with the wall clock" in stack.log("sim")
