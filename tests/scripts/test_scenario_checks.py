"""scripts/scenario_checks.py: each of the paper's qualitative results is judged on a run folder's
histories, holds on histories that show it and fails, saying why, on histories that do not.
Synthetic run folders as the launcher leaves them (summary.json, scene.toml, sim/couplings.csv,
device_<name>.csv), on the shipped scenes' scripts."""
import json
import math
import shutil
import tomllib

import numpy as np
import pytest

OFFSET_S = 0.2   # scene time 0 at 0.2 s of the sim's wall clock
LEAD_IN_S = 1.5
FLUID_MASS_KG = 0.14  # 1.37 N of fluid: the synthetic load shifts below are sized against it


@pytest.fixture(scope="module")
def checks(script):
    return script("scenario_checks")


def make_run(folder, source_dir, scene, wrench, end_s, device_log=None, batch=False, fluid_mass_kg=FLUID_MASS_KG):
    """wrench(device, t) -> (fx, fy, fz, tx, ty, tz) at scene time t, sampled at 500 Hz up to end_s.
    batch: the history is a batch run's (batch/couplings.csv, t = scene time; a live run's sim/
    beside it holds a contrary history, which must not be judged). fluid_mass_kg: the fluid
    the sim reports in its stats.json, which the load checks weigh against."""
    (folder / "sim").mkdir(parents=True)
    stats = json.dumps({"fluid_mass_kg": fluid_mass_kg})
    (folder / "sim" / "stats.json").write_text(stats)
    if batch:
        make_run(folder / "batch-tmp", source_dir, scene, wrench, end_s)
        rows = (folder / "batch-tmp" / "sim" / "couplings.csv").read_text().splitlines()
        (folder / "batch").mkdir()
        shifted = [f"{float(r.split(',')[0]) - OFFSET_S:.4f}," + r.split(",", 1)[1] for r in rows[1:]]
        (folder / "batch" / "couplings.csv").write_text("\n".join([rows[0]] + shifted) + "\n")
        (folder / "batch" / "stats.json").write_text(stats)
        (folder / "sim" / "stats.json").write_text(json.dumps({"fluid_mass_kg": 0.0}))  # must not be judged either
        wrench = lambda d, t: (0,) * 6  # noqa: E731  (the live history: no load anywhere)
    shutil.copy(source_dir / "config" / "scenes" / f"{scene}.toml", folder / "scene.toml")
    (folder / "summary.json").write_text(json.dumps({"script_offset_s": OFFSET_S, "lead_in_s": LEAD_IN_S}))
    devices = [d["name"] for d in tomllib.loads((folder / "scene.toml").read_text())["devices"]]
    lines = ["t,device,body,fx,fy,fz,tx,ty,tz,wall_s,device_tick,publish_ns"]
    for k, t in enumerate(np.arange(-OFFSET_S, end_s, 0.002)):
        for d in devices:
            w = ",".join(f"{v:.6f}" for v in wrench(d, t))
            lines.append(f"{t + OFFSET_S:.4f},{d},b,{w},{t + OFFSET_S:.4f},{k},{k}")
    (folder / "sim" / "couplings.csv").write_text("\n".join(lines) + "\n")
    if device_log:  # (t, px, fx) or (t, px, fx, tz)
        rows = ["t_s,px,applied_fx,applied_tx,applied_ty,applied_tz"] + [
            f"{r[0] + LEAD_IN_S:.4f},{r[1]:.6f},{r[2]:.6f},0,0,{(r[3] if len(r) > 3 else 0.0):.6f}" for r in device_log]
        (folder / "device_hand.csv").write_text("\n".join(rows) + "\n")
    return folder


def stroke_log(sign):
    # spoon_stirring: 0.08 m at 0.5 Hz from 1 s; the fluid's drag -c v (sign -1) or a force along v (+1).
    out = []
    for t in np.arange(-LEAD_IN_S, 8.0, 0.001):
        w = 2 * math.pi * 0.5
        px = 0.08 * math.sin(w * (t - 1.0)) if t > 1.0 else 0.0
        vx = 0.08 * w * math.cos(w * (t - 1.0)) if t > 1.0 else 0.0
        out.append((t, px, sign * 3.0 * vx))
    return out


@pytest.mark.parametrize("sign, holds", [(-1, True), (+1, False)])
def test_stirring_holds_only_when_the_force_opposes_the_stroke(checks, source_dir, tmp_path, sign, holds):
    run = make_run(tmp_path / "run", source_dir, "spoon_stirring", lambda d, t: (0,) * 6, 8.0, stroke_log(sign))
    verdict = checks.check("stirring", [run])
    assert verdict.holds is holds, verdict.text
    assert ("opposes the stroke" if holds else "does NOT oppose") in verdict.text
    assert (verdict.numbers["mean_force_times_velocity_w"] < 0) is holds


def stroke_velocity(t):
    # stroke_log's hand velocity (0.08 m at 0.5 Hz from 1 s)
    return 0.08 * math.pi * math.cos(math.pi * (t - 1.0)) if t > 1.0 else 0.0


@pytest.mark.parametrize("sign, sim_sign, stray_torque, holds, says", [
    (-1, -1, 0.0, True, "no torque ever reached"), (+1, -1, 0.0, False, "does NOT oppose"),
    (-1, +1, 0.0, False, "the fluid does NOT resist"),  # only the loop's lagging spring resists
    (-1, -1, 0.002, False, "reached the 3-DoF device")])
def test_probe_holds_when_fluid_and_hand_oppose_the_stroke_and_no_torque_reaches_the_device(
        checks, source_dir, tmp_path, sign, sim_sign, stray_torque, holds, says):
    log = [(t, px, fx, stray_torque if 3.0 < t < 3.01 else 0.0) for t, px, fx in stroke_log(sign)]
    sim = lambda d, t: (sim_sign * 0.01 * stroke_velocity(t), 0, 0, 0, 0, 0)  # noqa: E731
    run = make_run(tmp_path / "run", source_dir, "probe_3dof", sim, 8.0, log)
    verdict = checks.check("probe", [run])
    assert verdict.holds is holds, verdict.text
    assert says in verdict.text
    assert verdict.numbers["max_applied_torque_nm"] == pytest.approx(stray_torque)


def test_a_run_too_short_for_the_stroke_cannot_be_judged(checks, source_dir, tmp_path):
    run = make_run(tmp_path / "run", source_dir, "spoon_stirring", lambda d, t: (0,) * 6, 1.8, stroke_log(-1))
    verdict = checks.check("stirring", [run])
    assert not verdict.holds and "too short" in verdict.text


def pour(shift_n):
    # bowl_pouring: tilt 1-8 s. The bowl hand's load falls by shift_n once poured, the pan's rises.
    def wrench(device, t):
        poured = shift_n * min(max((t - 2.0) / 2.0, 0.0), 1.0)
        load = {"left": 5.0 - poured, "right": 6.0 + poured}[device]
        return 0, 0, -load, 0, 0, 0
    return wrench


@pytest.mark.parametrize("shift_n, holds", [(1.2, True), (0.5, False), (0.0, False), (-1.2, False)])
def test_pouring_holds_when_the_load_moves_from_the_bowl_hand_to_the_pan_hand(checks, source_dir, tmp_path,
                                                                              shift_n, holds):
    run = make_run(tmp_path / "run", source_dir, "bowl_pouring", pour(shift_n), 9.0)
    verdict = checks.check("pouring", [run])
    assert verdict.holds is holds, verdict.text
    assert verdict.numbers["bowl_load_n"][0] == pytest.approx(5.0, abs=0.01)
    assert verdict.numbers["pan_load_n"][1] == pytest.approx(6.0 + shift_n, abs=0.01)


def test_the_fluid_weight_is_what_the_sim_made_not_the_blocks_box(checks, source_dir, tmp_path):
    # bowl_pouring's block is drawn around the bowl and filled only inside it: the sim's stats.json
    # says how much fluid there is. The same 1.2 N shift is too little of 0.5 kg of water.
    run = make_run(tmp_path / "run", source_dir, "bowl_pouring", pour(1.2), 9.0, fluid_mass_kg=0.5)
    verdict = checks.check("pouring", [run])
    assert not verdict.holds, verdict.text
    assert verdict.numbers["fluid_weight_n"] == pytest.approx(0.5 * 9.81, abs=0.001)


def test_pouring_judged_before_the_bowl_is_back_cannot_be_judged(checks, source_dir, tmp_path):
    run = make_run(tmp_path / "run", source_dir, "bowl_pouring", pour(1.2), 7.5)
    verdict = checks.check("pouring", [run])
    assert not verdict.holds and "run longer" in verdict.text


# The hand's torque about z during the start ramp (1-1.15 s; the stop ramp, 3.85-4 s, mirrors it)
# in the batch runs, N m: the glass's own inertia and the fluid's share together.
HAND = (0.0222, 0.0226, 0.0227, 0.0229)
# The fluid's share as the inertia it adds to the glass in a ramp, kg m^2 (batch runs: 0.85,
# 0.96, 1.00, 1.04 e-4).
GROWING = (0.85e-4, 0.96e-4, 1.00e-4, 1.04e-4)
SPIN_RAD_S = 6.283


def write_glass_bodies(folder, start_inertia, stop_inertia, ramp_s=0.15):
    """sim/bodies.csv of a glass spun about +z from 1 s of scene time (the shipped scenes' script),
    in the sim's own time (scene time + OFFSET_S), rows at 60 Hz as the sim writes them: its
    speed eases in and out over ramp_s at the start and at 4 s (half a cosine, as the coupling's
    spring smooths the script's linear ramp), and the fluid's torque on it is the inertia it adds
    times the glass's angular acceleration, against it."""
    def ramp(t, t0):  # speed fraction and its rate
        x = min(max((t - t0) / ramp_s, 0.0), 1.0)
        return 0.5 * (1 - math.cos(math.pi * x)), (0.5 * math.pi / ramp_s * math.sin(math.pi * x))
    lines = ["t,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz"]
    for t in np.arange(-OFFSET_S, 6.0, 1 / 60):
        (up, up_rate), (down, down_rate) = ramp(t, 1.0), ramp(t, 4.0 - ramp_s)
        w = SPIN_RAD_S * (up - down)
        torque = SPIN_RAD_S * (-start_inertia * up_rate + stop_inertia * down_rate)
        lines.append(f"{t + OFFSET_S:.5f},glass,0,0,0,1,0,0,0,0,0,0,0,0,{w:.6f},0,0,0,0,0,{torque:.8f}")
    (folder / "sim" / "bodies.csv").write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize("hand, start, stop, steady, holds, says", [
    (HAND, GROWING, GROWING, 1e-5, True, "grows"),
    (HAND, GROWING, GROWING, 0.006, False, "does NOT co-rotate"),  # a fluid driven ahead of its glass
    (HAND, (0.85e-4, 1.00e-4, 0.96e-4, 1.04e-4), GROWING, 1e-5, False, "does NOT grow"),
    (HAND, GROWING, GROWING[::-1], 1e-5, False, "does NOT grow"),
    (HAND, GROWING, (0.85e-4, 0.96e-4, 1.00e-4, -1.04e-4), 1e-5, False, "does NOT grow"),  # fluid drives the glass
    # The hand's ramp torques out of order (a live run's timing moves the glass's own inertia
    # against a fixed window) do not decide: the fluid's share does.
    ((0.0222, 0.0241, 0.0240, 0.0237), GROWING, GROWING, 1e-5, True, "grows"),
])
def test_glass_holds_when_the_fluids_share_grows_and_the_steady_spin_costs_nothing(
        checks, source_dir, tmp_path, hand, start, stop, steady, holds, says):
    # The scenes' containers: 2, 10, 20, 40 Pa s; spin 1-4 s about +z with 0.15 s ramps.
    runs = []
    for viscosity, torque, up, down in zip((2, 10, 20, 40), hand, start, stop):
        def spin(d, t, torque=torque):
            z = -torque if 1.0 < t <= 1.15 else torque if 3.86 < t <= 4.0 else -steady if 1.15 < t < 3.84 else 0.0
            return (0, 0, 0, 0, 0, z)
        runs.append(make_run(tmp_path / f"glass_{viscosity}", source_dir, f"spinning_glass_{viscosity}", spin, 6.0))
        write_glass_bodies(runs[-1], up, down)
    verdict = checks.check("glass", runs)
    assert verdict.holds is holds, verdict.text
    assert says in verdict.text
    assert verdict.numbers["viscosity_pa_s"] == [2, 10, 20, 40]
    # Rows 1/60 s apart: the trapezoid rule on the torque's half sine loses up to
    # (pi dt / ramp)^2 / 12 = 1.0 % of its integral; the added inertia is read back within twice that.
    rows = 2 * (math.pi / 60 / 0.15) ** 2 / 12
    assert verdict.numbers["fluid_start_inertia_kg_m2"] == pytest.approx(start, rel=rows)
    assert verdict.numbers["fluid_stop_inertia_kg_m2"] == pytest.approx(stop, rel=rows)
    # Half a cosine passes 5 % and 95 % of its rise at 0.144 and 0.856 of its time; a crossing
    # read between two rows 17 ms apart on its curve is off by a few ms.
    assert verdict.numbers["ramp_s"][0][0] == pytest.approx(0.15 * (1 - 2 * math.acos(0.9) / math.pi), abs=0.004)
    assert verdict.numbers["start_torque_nm"] == pytest.approx(hand, rel=0.02)
    assert verdict.numbers["steady_torque_nm"][0] == pytest.approx(steady, rel=0.05)  # the steady spin's own window


@pytest.mark.parametrize("felt_steady, holds", [(0.0002, True), (0.015, False)])
def test_glass_fails_when_the_hand_feels_a_steady_drag_the_sim_does_not_ask_for(
        checks, source_dir, tmp_path, felt_steady, holds):
    # The device's log of each live run: 30 mN m in the ramps and felt_steady in the steady spin.
    # 15 mN m is what a loop rendering the spring against a stale anchor gave (K w times the
    # sample's age) while the sim asked for nothing.
    def felt(t):
        return -0.030 if 1.0 < t <= 1.15 else 0.030 if 3.85 < t <= 4.0 else -felt_steady if 1.15 < t < 3.85 else 0.0
    log = [(t, 0.0, 0.0, felt(t)) for t in np.arange(-LEAD_IN_S, 6.0, 0.001)]
    runs = []
    for viscosity, torque, inertia in zip((2, 10, 20, 40), HAND, GROWING):
        def spin(d, t, torque=torque):
            return (0, 0, 0, 0, 0, -torque if 1.0 < t <= 1.15 else torque if 3.86 < t <= 4.0 else 0.0)
        runs.append(make_run(tmp_path / f"glass_{viscosity}", source_dir, f"spinning_glass_{viscosity}", spin, 6.0, log))
        write_glass_bodies(runs[-1], inertia, inertia)
    verdict = checks.check("glass", runs)
    assert verdict.holds is holds, verdict.text
    assert ("the hand feels no steady drag" if holds else "the sim does NOT ask for") in verdict.text
    assert verdict.numbers["felt_steady_torque_nm"] == pytest.approx([felt_steady] * 4, rel=0.01)
    assert verdict.numbers["felt_start_torque_nm"] == pytest.approx([0.030] * 4, rel=0.01)


def test_a_glass_that_never_stops_cannot_be_judged(checks, source_dir, tmp_path):
    runs = []
    for viscosity in (2, 10, 20, 40):
        runs.append(make_run(tmp_path / f"glass_{viscosity}", source_dir, f"spinning_glass_{viscosity}",
                             lambda d, t: (0,) * 6, 6.0))
        write_glass_bodies(runs[-1], 1e-4, 1e-4)
        rows = (runs[-1] / "sim" / "bodies.csv").read_text().splitlines()
        kept = [r for r in rows if r.startswith("t") or float(r.split(",")[0]) < 3.5]
        (runs[-1] / "sim" / "bodies.csv").write_text("\n".join(kept) + "\n")
    verdict = checks.check("glass", runs)
    assert not verdict.holds and "never falls through" in verdict.text and "run longer" in verdict.text


@pytest.mark.parametrize("left_share, holds", [(0.5, True), (0.35, True), (0.9, False)])
def test_bucket_holds_when_both_hands_carry_a_comparable_share(checks, source_dir, tmp_path, left_share, holds):
    weight = 15.0
    share = {"left": left_share, "right": 1 - left_share}
    run = make_run(tmp_path / "run", source_dir, "bucket_bimanual", lambda d, t: (0, 0, -weight * share[d], 0, 0, 0), 9.0)
    verdict = checks.check("bucket", [run])
    assert verdict.holds is holds, verdict.text
    assert verdict.numbers["total_n"] == pytest.approx(weight, abs=0.01)


@pytest.mark.parametrize("spilled, holds", [(False, True), (True, False)])
def test_crepe_holds_when_the_batter_moves_to_the_pan_and_stays_while_spread(checks, source_dir, tmp_path,
                                                                          spilled, holds):
    def wrench(device, t):
        poured = 1.0 * min(max((t - 2.0) / 2.0, 0.0), 1.0)
        lost = 1.0 if spilled and t > 10.0 else 0.0  # spread: the batter slides out of the pan
        load = {"left": 5.0 - poured, "right": 6.0 + poured - lost}[device]
        return 0, 0, -load, 0, 0, 0
    run = make_run(tmp_path / "run", source_dir, "crepe", wrench, 14.0)
    verdict = checks.check("crepe", [run])
    assert verdict.holds is holds, verdict.text
    assert "the load moves to the pan's hand" in verdict.text


def test_a_folder_without_a_run_is_named(checks, tmp_path):
    verdict = checks.check("stirring", [tmp_path / "nothing"])
    assert not verdict.holds and "cannot judge" in verdict.text and "nothing/scene.toml" in verdict.text


def test_a_batch_judged_scenario_reads_the_batch_history_on_simulated_time(checks, source_dir, tmp_path):
    # run_scenarios.py judges a scene whose live sim ran far slower than real time on its batch run.
    run = make_run(tmp_path / "run", source_dir, "bowl_pouring", pour(1.2), 9.0, batch=True)
    assert not checks.check("pouring", [run]).holds  # the live history (no load) fails
    verdict = checks.check("pouring", [run], batch=True)
    assert verdict.holds and verdict.numbers["judged_on"] == "batch", verdict.text
    assert verdict.numbers["pan_load_n"] == pytest.approx([6.0, 7.2], abs=0.01)
