#!/usr/bin/env python3
"""hapfluid against SPlisHSPlasH's DFSPH on the same cases, one after the other (`make bench`).

Cases: the Martin & Moyce dam break (config/scenes/dam_break.toml, its 0.6 s) and the 32k fluid
pool of §6.2.1 (sim_gpu/bench/pool_32k.toml, its 0.2 s), each also as a `_dfsph` case
(sim_gpu/bench/*_dfsph.toml: the same geometry on hapfluid's DFSPH at water's viscosity). Each scene file runs as it is through
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

    bench_splishsplash.py --build build --out out/bench/bench_splishsplash.json [--case dam_break]
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

import splishsplash

ROOT = pathlib.Path(__file__).resolve().parent.parent
CASES = {
    "dam_break": ROOT / "config/scenes/dam_break.toml",
    "pool_32k": ROOT / "sim_gpu/bench/pool_32k.toml",
    "dam_break_dfsph": ROOT / "sim_gpu/bench/dam_break_dfsph.toml",
    "pool_32k_dfsph": ROOT / "sim_gpu/bench/pool_32k_dfsph.toml",
}
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


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=pathlib.Path, default=ROOT / "build")
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--case", action="append", choices=sorted(CASES), help="run only this case (repeatable)")
    args = parser.parse_args()
    try:
        splishsplash.gl_dispatch_preload()
    except RuntimeError as error:
        sys.exit(f"bench_splishsplash: {error}")
    work = args.out.resolve().parent / "splishsplash"
    records = []
    for name in args.case or list(CASES):
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
