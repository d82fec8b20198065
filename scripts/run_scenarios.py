#!/usr/bin/env python3
"""The paper's scenarios end to end on the live stack (scripts/hapfluid.py: fake devices playing
the scripted hands, haptic-rt, haptic-sim --live, haptic-trace), each with its plot:

    stirring   fig. 8   spoon_stirring                  force opposes the stroke, torque about an orthogonal axis
    pouring    fig. 9   bowl_pouring (two devices)      the weight shifts from the bowl's hand to the pan's
    glass      fig. 10  spinning_glass_{2,10,20,40}     torque grows with the container's viscosity, overlaid
    bucket     fig. 11  bucket_bimanual (two devices)   both hands share the bucket's weight while it tilts
    crepe      §6.5     crepe (two devices)

    run_scenarios.py [--only stirring,glass,...] [--build build] [--out out/scenarios] [--render]

Writes out/scenarios/<scenario>/... (one hapfluid.py run folder per scene), fig8_stirring.png,
fig9_pouring.png, fig10_spinning_glass.png, fig11_bucket.png, crepe.png and scenarios.json (sim
steps/s, real-time factor, max force on the hands, loop wake latency per scene).
"""
import argparse
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
PY = sys.executable

SCENARIOS = {
    "stirring": (["spoon_stirring"], "fig8_stirring.png", "fig. 8: spoon stirring (live, fake hand)", "x", "y"),
    "pouring": (["bowl_pouring"], "fig9_pouring.png", "fig. 9: bowl to pan pouring, two hands", "z", "norm"),
    "glass": (["spinning_glass_2", "spinning_glass_10", "spinning_glass_20", "spinning_glass_40"],
              "fig10_spinning_glass.png", "fig. 10: spinning glass, container viscosity 2/10/20/40 Pa s", "norm", "z"),
    "bucket": (["bucket_bimanual"], "fig11_bucket.png", "fig. 11: bucket held by two hands, tilted", "z", "norm"),
    "crepe": (["crepe"], "crepe.png", "§6.5: crepe, two hands", "norm", "norm"),
}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", default=",".join(SCENARIOS), help="comma-separated: " + ",".join(SCENARIOS))
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default=str(ROOT / "out" / "scenarios"))
    ap.add_argument("--render", action="store_true", help="also render PNG frames (slower: lavapipe shares the CPU)")
    ap.add_argument("--duration", type=float, default=None, help="override every scene's duration_s")
    args = ap.parse_args()
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    table, failed = {}, []
    for key in args.only.split(","):
        if key not in SCENARIOS:
            sys.exit(f"run_scenarios: unknown scenario '{key}'; known: {', '.join(SCENARIOS)}")
        scenes, png, title, fcomp, tcomp = SCENARIOS[key]
        runs = []
        for scene in scenes:
            run_dir = out / key / scene
            cmd = [PY, str(ROOT / "scripts" / "hapfluid.py"), "run", "--scene", scene, "--build", args.build,
                   "--out", str(run_dir)]
            cmd += [] if args.render else ["--no-render"]
            cmd += ["--duration", str(args.duration)] if args.duration else []
            print(f"run_scenarios: {key}: {scene}", file=sys.stderr, flush=True)
            result = subprocess.run(cmd)
            summary = json.loads((run_dir / "summary.json").read_text()) if (run_dir / "summary.json").exists() else {}
            table[scene] = {k: summary.get(k) for k in ("ok", "sim_steps_per_s", "real_time_factor", "sim_kept_up",
                                                       "fluid_particles", "max_force_on_hand_n", "wake_latency_us")}
            if result.returncode != 0:
                failed.append(scene)
            runs.append(run_dir / "sim" / "couplings.csv")
        labels = ",".join(s.replace("spinning_glass_", "") + (" Pa s" if "glass" in s else "") for s in scenes)
        plot = [PY, str(ROOT / "scripts" / "plot_wrenches.py"), *map(str, runs), "--out", str(out / png), "--title", title,
                "--component", fcomp, "--torque-component", tcomp]
        if len(scenes) > 1:
            plot += ["--labels", labels]
        if subprocess.run(plot).returncode != 0:
            failed.append(f"plot {png}")
    (out / "scenarios.json").write_text(json.dumps(table, indent=2) + "\n")
    print(f"{'scene':22s}{'steps/s':>10s}{'RT factor':>11s}{'max |F| on hands (N)':>28s}")
    for scene, row in table.items():
        forces = ", ".join(f"{n} {f}" for n, f in (row.get("max_force_on_hand_n") or {}).items())
        print(f"{scene:22s}{row.get('sim_steps_per_s') or 0:10.0f}{row.get('real_time_factor') or 0:11.2f}  {forces}")
    if failed:
        print("run_scenarios: FAILED: " + ", ".join(failed), file=sys.stderr)
        return 1
    print(f"run_scenarios: plots and runs in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
