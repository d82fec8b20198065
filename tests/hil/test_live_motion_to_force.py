"""The end-to-end motion-to-force measurement on a short live run (hapfluid.motion_to_force_latency,
which runs the launcher): every rendered sample is followed from the fake device's pose to
the device taking the command computed from it, the pieces are causal (none negative) and add up
to the total. No speed is asserted beyond a sanity bound: CI machines are noisy."""
import json
import subprocess
import sys

import numpy as np


from hapfluid import motion_to_force_latency as m2f

# A 1 kHz loop, a sim at >= 60 Hz and a 1 kHz device: a chain matched wrongly puts most samples
# beyond this. Single samples may pass it when the VM host stalls a process for tens of ms (a
# clean-clone run saw one of 1251 at 106 ms, p99 5 ms), so the bound holds for the p99.
SANE_TOTAL_MS = 50.0


def test_every_rendered_sample_is_followed_from_the_pose_to_the_device_and_its_pieces_add_up(build_dir, tmp_path):
    out = tmp_path / "latency"
    result = subprocess.run([sys.executable, "-m", "hapfluid.motion_to_force_latency", "--build",
                             str(build_dir), "--out", str(out), "--duration", "3.5"],
                            capture_output=True, text=True, timeout=180)
    assert result.returncode == 0, result.stdout + result.stderr
    report = json.loads((out / "motion_to_force.json").read_text())
    # Enough followed samples for the percentiles below: the stirring scene publishes ~120 a
    # second (8.4 ms steps), of which the engaged part of this run renders a few hundred.
    assert report["samples"] >= 100, report
    # Nearly every sample rendered on the engaged device is followed to both ends (a broken
    # sequence match or clock would lose most of them), and the sim's own log has each one.
    assert report["samples"] >= 0.9 * report["rendered_samples"], report
    assert report["confirmed_by_sim_log"] == report["samples"]
    assert (out / "motion_to_force.png").stat().st_size > 10_000

    run = out / "run"
    result, pieces = m2f.analyse(run / "trace.csv", m2f.device_log_of(run), run / "sim" / "couplings.csv")
    for name in m2f.PIECES:
        assert np.all(pieces[name] >= 0), (name, float(pieces[name].min()))
    assert np.allclose(sum(pieces[k] for k in m2f.PIECES), pieces["total"], atol=1e-9)
    assert np.all(np.isfinite(pieces["total"])) and np.min(pieces["total"]) > 0, report["total_ms"]
    assert np.percentile(pieces["total"], 99) < SANE_TOTAL_MS, report["total_ms"]
    # The loop-only number the script used to report is one part of the chain, never all of it.
    assert np.median(pieces["total"]) > np.median(pieces["loop_pipeline"])
