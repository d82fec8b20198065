"""A tool held still in a fluid at rest carries a steady load. That is what a person at the rig
feels first, and what the loop's engage gate waits for before any force reaches the hand (a load
that stays within the steady band for engage_hold_ms, rt_core/include/hapfluid/safety/
safety_layer.hpp): a fluid that keeps moving under a still hand buzzes in the hand and may never be
let through. Every shipped scene with a device, its scripted motions removed so each hand holds
its start pose, in batch mode on the cpu backend."""
import csv
import json
import subprocess

import numpy as np
import pytest

from conftest import SOURCE_DIR

SCENES = sorted(p for p in (SOURCE_DIR / "config" / "scenes").glob("*.toml") if "[[devices]]" in p.read_text())
HELD_S = 2.5  # simulated: the fluid settles from its start lattice in the first second
JUDGED_FROM_S = 1.0
# The default rig's steady band and hold window (safety_config.hpp): engage_steady_band_n,
# engage_steady_band_nm, engage_hold_ms.
BAND_N, BAND_NM, HOLD_S = 0.5, 0.025, 0.150


def held_variant(scene, folder):
    """The scene without its [[devices.motion]] tables, beside a link to the shipped meshes."""
    (folder / "scenes").mkdir(parents=True)
    (folder / "meshes").symlink_to(SOURCE_DIR / "config" / "meshes")
    kept, in_motion = [], False
    for line in scene.read_text().splitlines():
        stripped = line.split("#")[0].strip()
        if stripped.startswith("["):
            in_motion = stripped == "[[devices.motion]]"
        if not in_motion:
            kept.append(line)
    path = folder / "scenes" / scene.name
    path.write_text("\n".join(kept) + "\n")
    return path


def window_excursions(t, wrench):
    """Per 150 ms window (every 50 ms from JUDGED_FROM_S): the largest distance of the wrench
    from the window's first value, as the engage gate measures it."""
    out = []
    for start in np.arange(JUDGED_FROM_S, t[-1] - HOLD_S, 0.05):
        w = wrench[(t >= start) & (t < start + HOLD_S)]
        if len(w) >= 2:
            out.append(np.linalg.norm(w - w[0], axis=1).max())
    return np.array(out)


@pytest.mark.parametrize("scene", SCENES, ids=[s.stem for s in SCENES])
def test_a_tool_held_still_in_fluid_at_rest_carries_a_steady_load(binary, scene, tmp_path):
    out = tmp_path / "run"
    result = subprocess.run([str(binary("haptic-sim")), "--scene", str(held_variant(scene, tmp_path)), "--backend", "cpu",
                             "--duration", str(HELD_S), "--export-every", "0", "--out", str(out)],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    stats = json.loads((out / "stats.json").read_text())
    # The last-resort wall clamp acts only on a fluid that outruns its walls.
    assert stats["clamped_particle_events"] == 0, \
        f"{stats['clamped_particle_events']} wall clamp events under still hands: the fluid does not come to rest"
    rows = list(csv.DictReader(open(out / "couplings.csv")))
    devices = sorted({r["device"] for r in rows})
    assert devices, "no coupling was written"
    for device in devices:
        mine = [r for r in rows if r["device"] == device]
        t = np.array([float(r["t"]) for r in mine])
        force = np.array([[float(r[k]) for k in ("fx", "fy", "fz")] for r in mine])
        torque = np.array([[float(r[k]) for k in ("tx", "ty", "tz")] for r in mine])
        f, tau = window_excursions(t, force), window_excursions(t, torque)
        assert len(f) > 10
        # Most stretches of the held load are steady: the gate engages within a few windows.
        steady = np.mean((f <= BAND_N) & (tau <= BAND_NM))
        print(f"{scene.stem} {device}: median excursion {np.median(f):.3f} N, {np.median(tau):.4f} N m, "
              f"{steady:.0%} of {HOLD_S * 1e3:.0f} ms windows within the band")
        assert steady > 0.5, (f"{device}: {steady:.0%} of {HOLD_S * 1e3:.0f} ms windows within {BAND_N} N / {BAND_NM} N m "
                              f"(median excursion {np.median(f):.3f} N, {np.median(tau):.4f} N m)")
