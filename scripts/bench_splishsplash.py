#!/usr/bin/env python3
"""hapfluid against SPlisHSPlasH's DFSPH on the same cases, one after the other (`make bench`).

Cases: the Martin & Moyce dam break (config/scenes/dam_break.toml, its 0.6 s) and the 32k fluid
pool of §6.2.1 (sim_gpu/bench/pool_32k.toml, its 0.2 s), water on hapfluid's incompressible
solver, each also as a `_wcsph` case (sim_gpu/bench/*_wcsph.toml: the same geometry on the paper's
weakly compressible solver, the reference method). Each scene file runs as it is through
`haptic-sim --backend cpu` (so whichever solver its fluid.solver selects) and, translated by
splishsplash.py, through SPlisHSPlasH's `splash --no-gui` (the pysplishsplash wheel,
`scripts/install-deps.sh bench`), both on the same number of threads.

The figure of merit is wall time per simulated second per fluid particle (µs): the cost of
advancing one particle through one second of flow, whatever step each solver needs for it.
It is given for the time in the steps (haptic-sim's loop; SPlisHSPlasH's 'Time sum: SimStep')
and for the whole process (set-up included: SPlisHSPlasH builds its boundary volume map there).
Writes a JSON list of {"bench", "params", "metrics"} records: one per case and code, and one
ratio hapfluid / SPlisHSPlasH per case (> 1: hapfluid is slower). Runs are kept in
OUT_DIR/splishsplash/<case>/ (scene JSON, splash.log, stats.json).

A case of AT_REST_CASES is a tank of water at rest: both codes settle it alike (the scene's
fluid.settle_s, velocities x 0.8 after each step; for SPlisHSPlasH through its Python API,
splishsplash_at_rest.py), at the scene's viscosity (mu / rho0 as SPlisHSPlasH's coefficient),
then run it free for its duration_s. Its records give the rms and largest fluid speed at the end
and over the last second, each code's samples go to <case>/<code>/speeds.csv and both to
<case>/speeds.png.

A case of FRONT_CASES is the Martin & Moyce dam break judged by its surge front: both codes run
the scene to the last measured time, the front (the third-farthest fluid particle plus half a
spacing, from the column's back wall, over the column's width a; also where 1 % of the fluid
lies beyond, which a thin jet along the floor does not move) is sampled every 10 ms, and each
sample from T = 0.5 on is compared with the measurement (../shared/data, linear between its
points). Its records give the largest and the mean relative front error of each code;
<case>/front.png plots both against the measurement.

    bench_splishsplash.py --build build --out out/bench/bench_splishsplash.json [--case dam_break]
"""
import argparse
import json
import math
import os
import pathlib
import subprocess
import sys
import time

import numpy as np

import splishsplash
from hapfluid import vtk_frames

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASES = {
    "dam_break": ROOT / "config/scenes/dam_break.toml",
    "pool_32k": ROOT / "sim_gpu/bench/pool_32k.toml",
    "dam_break_wcsph": ROOT / "sim_gpu/bench/dam_break_wcsph.toml",
    "pool_32k_wcsph": ROOT / "sim_gpu/bench/pool_32k_wcsph.toml",
}
# Cases judged by how still the fluid stays, not by cost (below).
AT_REST_CASES = {
    "tank_at_rest_dfsph": ROOT / "sim_gpu/bench/tank_at_rest_dfsph.toml",
}
# Cases judged by where the dam break's surge front runs against the measurement (below).
FRONT_CASES = {
    "dam_break_front": ROOT / "config/scenes/dam_break.toml",
}
FRONT_DATA = ROOT.parent / "shared/data/martin_moyce_1952_n2_2_front.csv"
FRONT_EVERY_S = 0.01  # both codes' samples of the front (the scene's frame period: haptic-sim exports on frames)
FRONT_FROM_T = 0.5     # earlier, the experiment's gate was still being removed (its T < 0.5)
AT_REST_EXPORT_EVERY_S = 0.1  # hapfluid's frames, as often as splishsplash_at_rest.py samples
AT_REST_LAST_S = 1.0          # the summary's window: the last second of the run
THREADS = 2
RUN_TIMEOUT_S = 1800


def progress(message: str):
    print(f"bench_splishsplash: {message}", flush=True)


def per_particle_us(wall_s: float, simulated_s: float, particles: int) -> float:
    """Wall time per simulated second per particle, µs."""
    return 1e6 * wall_s / simulated_s / particles


def run_hapfluid(build: pathlib.Path, scene: pathlib.Path, duration_s: float, out: pathlib.Path) -> dict:
    command = [str(build / "bin/haptic-sim"), "--scene", str(scene), "--backend", "cpu", "--duration", repr(duration_s),
               "--out", str(out), "--threads", str(THREADS), "--export-every", "0"]
    started = time.monotonic()
    result = subprocess.run(command, timeout=RUN_TIMEOUT_S)  # its progress lines go straight to the console
    process_wall = time.monotonic() - started
    if result.returncode != 0:
        raise RuntimeError(f"haptic-sim on {scene} exited {result.returncode}")
    stats = json.loads((out / "stats.json").read_text())
    if not stats.get("complete"):
        raise RuntimeError(f"{out / 'stats.json'}: run incomplete: {stats.get('error')}")
    record = {
        "solver": stats.get("solver", "wcsph"),
        "fluid_particles": stats["particles"]["fluid"],
        "simulated_s": stats["simulated_time_s"],
        "steps": stats["steps"],
        "mean_dt_s": stats["dt_s"]["mean"],
        "steps_wall_s": stats["wall_time_s"],
        "process_wall_s": process_wall,
    }
    # A solver that iterates reports how often; carried over under its own names.
    record.update({k: v for k, v in stats.items() if "iteration" in k and isinstance(v, (int, float))})
    return record


def run_splishsplash(scene: pathlib.Path, duration_s: float, out: pathlib.Path) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    box = out / "box.obj"
    box.write_text(splishsplash.UNIT_BOX_OBJ)
    scene_path = out / "scene.json"
    scene_path.write_text(json.dumps(splishsplash.scene_json(scene, box), indent=2) + "\n")
    s = splishsplash.run(scene_path, duration_s, out, THREADS, RUN_TIMEOUT_S)
    record = {
        "solver": "dfsph",
        "fluid_particles": s["fluid_particles"],
        "simulated_s": s["simulated_time_s"],
        "steps": s["steps"],
        "mean_dt_s": s["mean_dt_s"],
        "steps_wall_s": s["step_time_sum_ms"] / 1000.0,
        "process_wall_s": s["process_wall_s"],
    }
    for key in ("mean_pressure_iterations", "mean_divergence_iterations", "volume_map_ms"):
        if key in s:
            record[key] = s[key]
    return record


def with_machine_load(run_function, *args) -> dict:
    """Runs one code and records the 1-minute load average before it: on a shared 2-core machine
    the OpenMP threads of SPlisHSPlasH lose far more to other jobs than hapfluid's do."""
    load = os.getloadavg()[0]
    record = run_function(*args)
    record["load_average_1min"] = load
    return record


def metrics_of(run: dict) -> dict:
    m = {k: v for k, v in run.items() if k not in ("solver", "fluid_particles")}
    m["us_per_sim_s_per_particle_steps"] = per_particle_us(run["steps_wall_s"], run["simulated_s"], run["fluid_particles"])
    m["us_per_sim_s_per_particle_process"] = per_particle_us(run["process_wall_s"], run["simulated_s"], run["fluid_particles"])
    return m


def case_records(name: str, hapfluid: dict, splash: dict) -> list:
    records = []
    for code, run in (("hapfluid", hapfluid), ("splishsplash", splash)):
        records.append({"bench": "bench_splishsplash",
                        "params": {"case": name, "code": code, "solver": run["solver"], "threads": THREADS,
                                   "fluid_particles": run["fluid_particles"]},
                        "metrics": metrics_of(run)})
    h, s = records[0]["metrics"], records[1]["metrics"]
    records.append({"bench": "bench_splishsplash",
                    "params": {"case": name, "code": "hapfluid/splishsplash",
                               "solver": f"{hapfluid['solver']}/{splash['solver']}", "threads": THREADS},
                    "metrics": {"ratio_steps": h["us_per_sim_s_per_particle_steps"] / s["us_per_sim_s_per_particle_steps"],
                                "ratio_process": h["us_per_sim_s_per_particle_process"] / s["us_per_sim_s_per_particle_process"],
                                "ratio_steps_count": h["steps"] / s["steps"]}})
    return records


def summary_line(code: str, run: dict) -> str:
    m = metrics_of(run)
    return (f"{code} ({run['solver']}): {run['fluid_particles']} fluid particles, {run['steps']} steps "
            f"(mean dt {1000 * run['mean_dt_s']:.3f} ms), {run['steps_wall_s']:.1f} s in steps, "
            f"{run['process_wall_s']:.1f} s process: {m['us_per_sim_s_per_particle_steps']:.2f} us/(sim s x particle); "
            f"load average {run['load_average_1min']:.1f} before")


def hapfluid_frames(build: pathlib.Path, scene: pathlib.Path, duration_s: float, out: pathlib.Path, every_s: float):
    """haptic-sim (cpu backend) on `scene` with VTK frames every `every_s`: [(t, frame)] of them."""
    command = [str(build / "bin/haptic-sim"), "--scene", str(scene), "--backend", "cpu", "--duration", repr(duration_s),
               "--out", str(out), "--threads", str(THREADS), "--export-every", repr(every_s)]
    result = subprocess.run(command, timeout=RUN_TIMEOUT_S)
    if result.returncode != 0:
        raise RuntimeError(f"haptic-sim on {scene} exited {result.returncode}")
    return [(t, vtk_frames.read_vtk(path)) for t, path in vtk_frames.read_series(out / "particles")]


def hapfluid_at_rest(build: pathlib.Path, scene: pathlib.Path, duration_s: float, out: pathlib.Path) -> list:
    """haptic-sim on a tank at rest: [(t, rms speed, max speed, mean density)] of its fluid, from
    its VTK frames (kind 0 is fluid), and its solver iterations per step (stats.json)."""
    rows = []
    for t, frame in hapfluid_frames(build, scene, duration_s, out, AT_REST_EXPORT_EVERY_S):
        fluid = frame["kind"] == 0
        speed = np.linalg.norm(frame["velocity"][fluid], axis=1)
        rows.append((t, math.sqrt(float(np.mean(speed ** 2))), float(speed.max()), float(frame["density"][fluid].mean())))
    splishsplash.write_speeds(out / "speeds.csv", rows)
    iterations = json.loads((out / "stats.json").read_text()).get("solver_iterations", {})
    return rows, {"mean_pressure_iterations": iterations.get("density_per_step"),
                  "mean_divergence_iterations": iterations.get("divergence_per_step")}


def at_rest_metrics(rows: list, duration_s: float, rest_density: float) -> dict:
    last = [r for r in rows if r[0] >= duration_s - AT_REST_LAST_S - 1e-9]
    if not last:
        raise ValueError(f"no samples in the last {AT_REST_LAST_S} s of {duration_s} s")
    return {
        "samples": len(rows),
        "rms_speed_final_m_s": rows[-1][1],
        "max_speed_final_m_s": rows[-1][2],
        "rms_speed_last_s_m_s": math.sqrt(sum(r[1] ** 2 for r in last) / len(last)),
        "max_speed_last_s_m_s": max(r[2] for r in last),
        "max_speed_after_settling_m_s": max(r[2] for r in rows),
        "mean_density_error_final": rows[-1][3] / rest_density - 1.0,
    }


def save_plot(fig, ax, path: pathlib.Path):
    import matplotlib.pyplot as plt
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_speeds(path: pathlib.Path, name: str, runs: dict):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4))
    for (code, rows), colour in zip(runs.items(), ("tab:blue", "tab:orange")):
        t = [r[0] for r in rows]
        ax.plot(t, [r[1] for r in rows], color=colour, label=f"{code} rms")
        ax.plot(t, [r[2] for r in rows], color=colour, linestyle="--", label=f"{code} max")
    ax.axhline(0.01, color="grey", linewidth=0.8, label="0.01 m/s")
    ax.set_yscale("log")
    ax.set_xlabel("time after settling (s)")
    ax.set_ylabel("fluid speed (m/s)")
    ax.set_title(f"{name}: water at rest, same settling")
    save_plot(fig, ax, path)


def at_rest_case(name: str, scene: pathlib.Path, build: pathlib.Path, work: pathlib.Path) -> list:
    case = splishsplash.load_case(scene)
    duration = case["duration_s"]
    progress(f"{name}: hapfluid, {scene.relative_to(ROOT)}, settled {case['settle_s']} s, then {duration} s at rest ...")
    (work / "hapfluid").mkdir(parents=True, exist_ok=True)
    ours, our_iterations = hapfluid_at_rest(build, scene, duration, work / "hapfluid")
    out = work / "splishsplash"
    out.mkdir(parents=True, exist_ok=True)
    box = out / "box.obj"
    box.write_text(splishsplash.UNIT_BOX_OBJ)
    nu = splishsplash.scene_kinematic_viscosity(scene)
    scene_path = out / "scene.json"
    scene_path.write_text(json.dumps(splishsplash.scene_json(scene, box, kinematic_viscosity=nu), indent=2) + "\n")
    progress(f"{name}: SPlisHSPlasH DFSPH, same tank, viscosity {nu:g} m^2/s, same settling ...")
    theirs, their_iterations = splishsplash.run_at_rest(scene_path, case["settle_s"], duration, out, THREADS, RUN_TIMEOUT_S)
    plot_speeds(work / "speeds.png", name, {"hapfluid": ours, "SPlisHSPlasH": theirs})
    records = []
    for code, rows, iterations in (("hapfluid", ours, our_iterations), ("splishsplash", theirs, their_iterations)):
        metrics = at_rest_metrics(rows, duration, case["rest_density_kg_m3"])
        metrics.update({k: v for k, v in iterations.items() if v is not None})
        records.append({"bench": "bench_splishsplash",
                        "params": {"case": name, "code": code, "solver": "dfsph", "threads": THREADS,
                                   "settle_s": case["settle_s"], "duration_s": duration,
                                   "kinematic_viscosity_m2_s": nu},
                        "metrics": metrics})
        progress(f"{name}: {code}: last {AT_REST_LAST_S} s rms {metrics['rms_speed_last_s_m_s']:.4f} m/s, "
                 f"max {metrics['max_speed_last_s_m_s']:.4f} m/s")
    h, s = records[0]["metrics"], records[1]["metrics"]
    records.append({"bench": "bench_splishsplash",
                    "params": {"case": name, "code": "hapfluid/splishsplash", "solver": "dfsph/dfsph", "threads": THREADS},
                    "metrics": {"ratio_rms_speed_last_s": h["rms_speed_last_s_m_s"] / s["rms_speed_last_s_m_s"],
                                "ratio_max_speed_last_s": h["max_speed_last_s_m_s"] / s["max_speed_last_s_m_s"]}})
    return records


def read_front_table(path: pathlib.Path) -> tuple:
    """The measured front (T, Z) of a ../shared/data table; ValueError names a missing or short file."""
    if not path.exists():
        raise ValueError(f"{path}: the measured dam-break front is missing (../shared/data beside the checkout)")
    rows = []
    for line in path.read_text().splitlines():
        parts = line.split(",")
        if len(parts) == 2 and not line.startswith("#"):
            try:
                rows.append((float(parts[0]), float(parts[1])))
            except ValueError:
                continue  # the header
    if len(rows) < 10:
        raise ValueError(f"{path}: {len(rows)} rows of T, Z; expected the measurement's 15")
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows])


def front_metrics(samples: list, table: tuple) -> dict:
    """samples [(T, Z)] against the measured table from FRONT_FROM_T to its last T: the largest
    and the mean relative error (Z - Z_measured) / Z_measured (> 0: ahead of the experiment)."""
    T_table, Z_table = table
    errors = [(Z - np.interp(T, T_table, Z_table)) / np.interp(T, T_table, Z_table)
              for T, Z in samples if FRONT_FROM_T <= T <= T_table[-1]]
    if len(errors) < 10:
        raise ValueError(f"{len(errors)} front samples within T = {FRONT_FROM_T}-{T_table[-1]}; expected 10 or more")
    worst = max(errors, key=abs)
    return {"front_samples": len(errors), "front_worst_error": float(worst), "front_worst_abs_error": float(abs(worst)),
            "front_mean_error": float(np.mean(errors)), "front_z_at_start": float(samples[0][1])}


def plot_fronts(path: pathlib.Path, name: str, runs: dict, bulk_runs: dict, table: tuple):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4))
    for (code, samples), bulk, colour in zip(runs.items(), bulk_runs.values(), ("tab:blue", "tab:orange")):
        ax.plot([T for T, _ in samples], [Z for _, Z in samples], color=colour, label=f"{code}: third-farthest")
        ax.plot([T for T, _ in bulk], [Z for _, Z in bulk], color=colour, linestyle="--", label=f"{code}: 1 % beyond")
    ax.plot(table[0], table[1], "ko", markersize=4, label="Martin & Moyce 1952")
    ax.axvline(FRONT_FROM_T, color="grey", linewidth=0.8)
    ax.set_xlabel("T = t sqrt(2 g / a)")
    ax.set_ylabel("Z = front / a")
    ax.set_title(f"{name}: surge front, same column")
    save_plot(fig, ax, path)


def front_case(name: str, scene: pathlib.Path, build: pathlib.Path, work: pathlib.Path) -> list:
    table = read_front_table(FRONT_DATA)
    case = splishsplash.load_case(scene)
    lo, hi = case["blocks"][0]
    a = hi[0] - lo[0]                     # the column's width
    back = case["domain_min_m"][0]        # the wall the column stands against
    g = abs(case["gravity_m_s2"][2])
    to_T = math.sqrt(2 * g / a)
    duration = float(table[0][-1]) / to_T + FRONT_EVERY_S
    half = 0.5 * case["spacing_m"]

    def as_fronts(rows, column):
        return [(r[0] * to_T, (r[column] + half - back) / a) for r in rows]

    progress(f"{name}: hapfluid, {scene.relative_to(ROOT)}, {duration:.3f} s, the front every {FRONT_EVERY_S} s ...")
    out = work / "hapfluid"
    out.mkdir(parents=True, exist_ok=True)
    ours = [(t, *splishsplash.front_positions(frame["points"][frame["kind"] == 0][:, 0]))
            for t, frame in hapfluid_frames(build, scene, duration, out, FRONT_EVERY_S)]
    splishsplash.write_rows(out / "front.csv", splishsplash.FRONT_COLUMNS, ours)
    progress(f"{name}: SPlisHSPlasH DFSPH, same scene ...")
    theirs_out = work / "splishsplash"
    theirs_out.mkdir(parents=True, exist_ok=True)
    box = theirs_out / "box.obj"
    box.write_text(splishsplash.UNIT_BOX_OBJ)
    scene_path = theirs_out / "scene.json"
    scene_path.write_text(json.dumps(splishsplash.scene_json(scene, box), indent=2) + "\n")
    theirs = splishsplash.run_front(scene_path, FRONT_EVERY_S, duration, theirs_out, THREADS, RUN_TIMEOUT_S)
    fronts = {"hapfluid": as_fronts(ours, 1), "SPlisHSPlasH": as_fronts(theirs, 1)}
    bulk_fronts = {"hapfluid": as_fronts(ours, 2), "SPlisHSPlasH": as_fronts(theirs, 2)}
    plot_fronts(work / "front.png", name, fronts, bulk_fronts, table)
    records = []
    for code, samples, bulk in zip(("hapfluid", "splishsplash"), fronts.values(), bulk_fronts.values()):
        metrics = front_metrics(samples, table)
        metrics.update({f"{k}_one_percent": v for k, v in front_metrics(bulk, table).items() if k != "front_samples"})
        records.append({"bench": "bench_splishsplash",
                        "params": {"case": name, "code": code, "solver": "dfsph", "threads": THREADS,
                                   "column_width_m": a, "every_s": FRONT_EVERY_S},
                        "metrics": metrics})
        progress(f"{name}: {code}: front {100 * metrics['front_mean_error']:+.1f} % on average, "
                 f"at most {100 * metrics['front_worst_error']:+.1f} % (T >= {FRONT_FROM_T}); with 1 % of the fluid "
                 f"beyond it {100 * metrics['front_mean_error_one_percent']:+.1f} %, at most "
                 f"{100 * metrics['front_worst_error_one_percent']:+.1f} %")
    return records


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=pathlib.Path, default=ROOT / "build")
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--case", action="append", choices=sorted(CASES) + sorted(AT_REST_CASES) + sorted(FRONT_CASES),
                        help="run only this case (repeatable)")
    args = parser.parse_args()
    try:
        splishsplash.gl_dispatch_preload()
    except RuntimeError as error:
        sys.exit(f"bench_splishsplash: {error}")
    work = args.out.resolve().parent / "splishsplash"
    records = []
    for name in args.case or list(CASES) + list(AT_REST_CASES) + list(FRONT_CASES):
        judged = ((FRONT_CASES, front_case), (AT_REST_CASES, at_rest_case))
        special = next(((cases[name], run) for cases, run in judged if name in cases), None)
        if special:
            try:
                records += special[1](name, special[0], args.build.resolve(), work / name)
            except (RuntimeError, ValueError, OSError, subprocess.TimeoutExpired) as error:
                sys.exit(f"bench_splishsplash: {name}: {error}")
            continue
        scene = CASES[name]
        duration = splishsplash.load_case(scene)["duration_s"]
        try:
            progress(f"{name}: hapfluid, {scene.relative_to(ROOT)}, {duration} s simulated, {THREADS} threads ...")
            hapfluid = with_machine_load(run_hapfluid, args.build.resolve(), scene, duration, work / name / "hapfluid")
            progress(f"{name}: {summary_line('hapfluid', hapfluid)}")
            progress(f"{name}: SPlisHSPlasH DFSPH, same scene, {duration} s simulated, {THREADS} threads ...")
            splash = with_machine_load(run_splishsplash, scene, duration, work / name / "splishsplash")
            progress(f"{name}: {summary_line('SPlisHSPlasH', splash)}")
        except (RuntimeError, ValueError, OSError, subprocess.TimeoutExpired) as error:
            sys.exit(f"bench_splishsplash: {name}: {error}")
        records += case_records(name, hapfluid, splash)
        ratio = records[-1]["metrics"]
        progress(f"{name}: hapfluid / SPlisHSPlasH = {ratio['ratio_steps']:.2f} (in steps), "
                 f"{ratio['ratio_process']:.2f} (whole process)")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    part = args.out.with_suffix(".part")
    part.write_text(json.dumps(records, indent=2) + "\n")
    part.rename(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
