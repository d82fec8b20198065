"""Channel names squatted by another local user, with the real processes. Any user can create
/dev/shm/<prefix>.<channel> before the services start; such a segment must neither hijack the rig
(haptic-rt renders nothing from it) nor block it (every writer still starts). The other user is
uid 65534 (nobody), made by chown, which needs root."""
import os
import subprocess
import time

import pytest

from rt_helpers import RIGS, force, read_trace, start_rt, unique_prefix

NOBODY = 65534


def wait_for(condition, timeout_s, what):
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            pytest.fail(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(0.01)


def squat(path):
    os.chown(path, NOBODY, -1)
    os.chmod(path, 0o666)


@pytest.mark.skipif(os.geteuid() != 0, reason="chown to another user needs root")
@pytest.mark.slow
def test_squatted_channel_names_neither_hijack_nor_block_the_rig(binary, tmp_path):
    prefix = unique_prefix("squat")
    shm = "/dev/shm/" + prefix
    # The impostor: a live, well-formed sim_samples writer pushing 5 N along x, whose segment then
    # belongs to another user; and a device_states name taken by a plain file of that user.
    impostor = subprocess.Popen([str(binary("haptic-sim-standin")), "--shm-prefix", prefix, "--rate", "100",
                                 "--force", "5,0,0"], stderr=subprocess.DEVNULL)
    sim = rt = None
    try:
        wait_for(lambda: os.path.exists(shm + ".sim_samples"), 10, "the impostor's segment")
        squat(shm + ".sim_samples")
        with open(shm + ".device_states", "wb") as f:
            f.write(b"\0" * 4096)
        squat(shm + ".device_states")

        rt = start_rt(binary, RIGS / "one_arm.toml", prefix, tmp_path, 3.0)
        # The real sim pushes 2 N along z; it must start despite the live impostor on its name.
        sim = subprocess.Popen([str(binary("haptic-sim-standin")), "--shm-prefix", prefix, "--rate", "100",
                                "--force", "0,0,2"], stderr=subprocess.PIPE, text=True)
        _, rt_err = rt.communicate(timeout=20)
        sim.terminate()
        _, sim_err = sim.communicate(timeout=10)
    finally:
        for p in (sim, rt, impostor):
            if p and p.poll() is None:
                p.kill()
                p.wait()
        for name in os.listdir("/dev/shm"):
            if name.startswith(prefix + "."):
                os.unlink("/dev/shm/" + name)

    assert rt.returncode == 0, rt_err
    assert "held by uid 65534" in rt_err, "haptic-rt names who holds device_states: " + rt_err
    assert "held by uid 65534" in sim_err, "the sim names who holds sim_samples: " + sim_err
    attached = [line for line in rt_err.splitlines() if "sim_samples: attached" in line]
    assert attached and all(f"/{prefix}.sim_samples." in line for line in attached), rt_err
    rows = read_trace(tmp_path / "trace.csv")
    assert all(force(r)[0] == 0.0 for r in rows), "the impostor's 5 N along x reached the hand"
    assert max(force(r)[2] for r in rows) > 1.95, "the real sim's 2 N along z was rendered"
