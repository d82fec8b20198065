#!/usr/bin/env python3
"""The paper's scenarios end to end on the live stack (`python -m hapfluid run`: fake devices playing
the scripted hands, haptic-rt, haptic-sim --live, haptic-trace, cyclictest beside the loop), each
with its figure and its qualitative result checked (scenario_checks.py):

    stirring   fig. 8   spoon_stirring                  the force opposes the stroke (mean F_x v_x < 0)
    probe      Alg. 1   probe_3dof                      the same for a 3-DoF probe, and no torque on the device
    pouring    fig. 9   bowl_pouring (two devices)      the vertical load moves from the bowl's hand to the pan's
    glass      fig. 10  spinning_glass_{2,10,20,40}     the spin-axis torque at start and stop grows with the
                                                        container's viscosity; the steady spin costs ~nothing
    bucket     fig. 11  bucket_bimanual (two devices)   both hands share the bucket's weight while it is level
    crepe      §6.5     crepe (two devices)             the batter's weight moves to the pan and stays while spread

    run_scenarios.py [--only stirring,glass,...] [--build build] [--out out/scenarios] [--render] [--duration S]

Each scene runs live for its whole script (the launcher's default duration: the 3 s lead-in, so
the stack is up and the fluid settled before the script starts, plus the scene's duration_s).
The figures are drawn against the hands' clock (scene time, the script's motions shaded).

The heavy scenes run slower than real time on a small machine: the sim drops its backlog and says
so (RT factor in the table), while the fake hands play the script on the wall clock, so for the
fluid the hands move 1 / RT factor times faster than scripted: the glass at RT factor 0.2 spins
at 5x its speed and its torque says more about the machine than about the viscosity. A scenario
with a live run below RT factor 0.9 (LIVE_RTF_FOR_PHYSICS) is therefore also run in batch
(haptic-sim, the scene's scripted hands at their speed in simulated time, no wall clock): its
figure and its check are the batch run's, the live run's figure is <figure>_live.png, and the
table says which one was judged. Stirring and the probe are always judged live: what the hand
felt against its own velocity, one clock, a claim any real-time factor keeps. Fig. 10 is always
judged in batch: it compares four runs by a few per cent, which asks for the same hand motion in
each, and live each run sees the script through its own timing (one lagging step stretched a
glass's 0.12 s stop ramp to 0.30 s, and the fluid then takes more of the spin than a more viscous
container gives it).

Writes out/scenarios/<scenario>/<scene>/ (launcher run folders, batch/ beside sim/), fig8_stirring.png,
alg1_probe.png, fig9_pouring.png, fig10_spinning_glass.png, fig11_bucket.png, crepe.png and scenarios.json (per
scene: sim steps/s, real-time factor, max force on the hands, loop and cyclictest wake latency;
per scenario: the check's verdict and numbers). Exits 1 when a run fails or a result does not hold.
"""
import argparse
import json
import pathlib
import subprocess
import sys

import scenario_checks

ROOT = pathlib.Path(__file__).resolve().parent.parent
PY = sys.executable

SCENARIOS = {
    "stirring": (["spoon_stirring"], "fig8_stirring.png", "fig. 8: spoon stirring, one hand"),
    "probe": (["probe_3dof"], "alg1_probe.png", "§3.2, Algorithm 1: a 3-DoF probe stroked through a viscous pool"),
    "pouring": (["bowl_pouring"], "fig9_pouring.png", "fig. 9: bowl to pan pouring, two hands"),
    "glass": (["spinning_glass_2", "spinning_glass_10", "spinning_glass_20", "spinning_glass_40"],
              "fig10_spinning_glass.png", "fig. 10: spinning glass of 2 Pa·s fluid, container viscosity 2/10/20/40 Pa·s"),
    "bucket": (["bucket_bimanual"], "fig11_bucket.png", "fig. 11: bucket held by two hands, tilted left, right, left"),
    "crepe": (["crepe"], "crepe.png", "§6.5: crepe, batter poured from the bowl into the pan and spread"),
}
LIVE_RTF_FOR_PHYSICS = 0.9
LEAD_IN_S = 3.0  # as the launcher's default; the plots' --hand-offset
LIVE_ONLY = {"stirring", "probe"}
JUDGED_IN_BATCH = {"glass"}
SUMMARY_KEYS = ("ok", "sim_backend", "sim_steps_per_s", "real_time_factor", "sim_kept_up", "fluid_particles",
                "max_force_on_hand_n", "wake_latency_us", "cyclictest_us", "script_offset_s")


def run_scene(scene, run_dir, args) -> dict:
    cmd = [PY, "-m", "hapfluid", "run", "--scene", scene, "--build", args.build, "--out", str(run_dir),
           "--lead-in", str(LEAD_IN_S)]
    cmd += [] if args.render else ["--no-render"]
    cmd += ["--duration", str(args.duration)] if args.duration else []
    print(f"run_scenarios: {scene}", file=sys.stderr, flush=True)
    result = subprocess.run(cmd)
    summary = json.loads((run_dir / "summary.json").read_text()) if (run_dir / "summary.json").exists() else {}
    row = {k: summary.get(k) for k in SUMMARY_KEYS}
    row["ok"] = bool(row["ok"]) and result.returncode == 0
    return row


def run_batch(scene, run_dir, args) -> bool:
    """The scene in batch mode beside its live run (scenario_checks.BATCH_DIR): the script in simulated time."""
    print(f"run_scenarios: {scene}: batch (the script at its own speed in simulated time)", file=sys.stderr, flush=True)
    build = pathlib.Path(args.build)
    build = build if build.is_absolute() else ROOT / build  # as the launcher resolves it
    cmd = [str(build / "bin" / "haptic-sim"), "--scene", str(ROOT / "config" / "scenes" / f"{scene}.toml"),
           "--out", str(run_dir / scenario_checks.BATCH_DIR), "--backend", "cpu", "--export-every", "0"]
    return subprocess.run(cmd).returncode == 0


def plot(scenes, folders, table, png, title, batch) -> bool:
    """The figure against scene time: the batch runs' simulated time, or the live runs' wall clock
    (the RT factor in the title: below 1 the fluid saw the hands' script sped up)."""
    if batch:
        csvs, clock, offsets, title = [f / scenario_checks.BATCH_DIR for f in folders], "sim", "0", title + " (batch)"
    else:
        rtf = min(table[s].get("real_time_factor") or 0 for s in scenes)
        csvs, clock = [f / "sim" for f in folders], "wall"
        offsets = ",".join(str(table[s].get("script_offset_s") or 0) for s in scenes)
        title += " (live" + (f", fluid at {rtf:.2g}x real time)" if rtf < 0.95 else ")")
    hands = [] if batch or len(scenes) > 1 else [f"--hand={p}" for p in folders[0].glob("device_*.csv")]
    cmd = [PY, "-m", "hapfluid.plot_wrenches", *map(str, csvs), "--out", str(png), "--title", title,
           "--scene", scenes[0], "--time", clock, f"--time-offset={offsets}",  # = : an offset may start with -
           *hands, f"--hand-offset={LEAD_IN_S}"]
    if len(scenes) > 1:
        cmd += ["--labels", ",".join(s.replace("spinning_glass_", "container ") + " Pa·s" for s in scenes)]
    return subprocess.run(cmd).returncode == 0


def print_table(table, verdicts):
    def p(lat, key):
        return f"{lat[key]:.0f}" if lat else "-"
    print(f"{'scene':20s}{'backend':>8s}{'steps/s':>9s}{'RT factor':>10s}{'wake p50/p99/max µs':>22s}"
          f"{'cyclictest p50/p99/max':>24s}  max |F| on hands (N)")
    for scene, row in table.items():
        w, c = row.get("wake_latency_us"), row.get("cyclictest_us")
        forces = ", ".join(f"{n} {f}" for n, f in (row.get("max_force_on_hand_n") or {}).items())
        print(f"{scene:20s}{row.get('sim_backend') or '-':>8s}{row.get('sim_steps_per_s') or 0:9.0f}"
              f"{row.get('real_time_factor') or 0:10.2f}{p(w, 'p50') + '/' + p(w, 'p99') + '/' + p(w, 'max'):>22s}"
              f"{p(c, 'p50') + '/' + p(c, 'p99') + '/' + p(c, 'max'):>24s}  {forces}")
    for key, v in verdicts.items():
        print(f"{key:9s} {'holds ' if v.holds else 'FAILS '} [{v.numbers['judged_on']}] {v.text}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", default=",".join(SCENARIOS), help="comma-separated: " + ",".join(SCENARIOS))
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default=str(ROOT / "out" / "scenarios"))
    ap.add_argument("--render", action="store_true", help="also render PNG frames (slower: lavapipe shares the CPU)")
    ap.add_argument("--duration", type=float, default=None,
                    help="wall seconds of every run (default: each scene's lead-in plus duration_s, its whole script)")
    args = ap.parse_args()
    keys = args.only.split(",")
    unknown = [k for k in keys if k not in SCENARIOS]
    if unknown:
        sys.exit(f"run_scenarios: unknown scenario '{unknown[0]}'; known: {', '.join(SCENARIOS)}")
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    table, verdicts, failed = {}, {}, []
    for key in keys:
        scenes, png, title = SCENARIOS[key]
        folders = [out / key / scene for scene in scenes]
        for scene, folder in zip(scenes, folders):
            table[scene] = run_scene(scene, folder, args)
            if not table[scene]["ok"]:
                failed.append(f"{scene} (run failed: {folder / 'logs'})")
        slow = min(table[s].get("real_time_factor") or 0 for s in scenes) < LIVE_RTF_FOR_PHYSICS
        batch = (slow and key not in LIVE_ONLY) or key in JUDGED_IN_BATCH
        if batch and not all(run_batch(scene, folder, args) for scene, folder in zip(scenes, folders)):
            failed.append(f"{key}: batch run failed")
        live_png = out / (png.replace(".png", "_live.png") if batch else png)
        if not plot(scenes, folders, table, live_png, title, batch=False) or (
                batch and not plot(scenes, folders, table, out / png, title, batch=True)):
            failed.append(f"plot {png}")
        verdicts[key] = scenario_checks.check(key, folders, batch)
        if not verdicts[key].holds:
            failed.append(f"{key}: {SCENARIOS[key][2].split(':')[0]} result does not hold: {verdicts[key].text}")
    record = {"scenes": table, "checks": {k: {"holds": v.holds, "text": v.text, **v.numbers} for k, v in verdicts.items()}}
    (out / "scenarios.json").write_text(json.dumps(record, indent=2) + "\n")
    print_table(table, verdicts)
    if failed:
        print("run_scenarios: FAILED:\n  " + "\n  ".join(failed), file=sys.stderr)
        return 1
    print(f"run_scenarios: every result holds; plots and runs in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
