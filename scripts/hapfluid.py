#!/usr/bin/env python3
"""hapfluid launcher: runs a scene with whatever parts of the stack are built.

    hapfluid.py run [--scene NAME|FILE] [--rig FILE] [--duration S] [--build DIR] [--out DIR]

Every run validates the rig and the scene first, then writes its outputs under
out/<scene>-<timestamp>/ and prints a short summary. With the simulator built, the scene runs as
a batch simulation (its scripted hands drive the devices); the live system (fake device, 1 kHz
loop, simulator and renderer as separate processes) is added on top of this launcher.
"""
import argparse
import datetime
import json
import pathlib
import shutil
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def resolve_scene(name: str) -> pathlib.Path:
    path = pathlib.Path(name)
    if path.suffix == ".toml" and path.exists():
        return path.resolve()
    candidate = ROOT / "config" / "scenes" / f"{name}.toml"
    if candidate.exists():
        return candidate
    known = ", ".join(sorted(p.stem for p in (ROOT / "config" / "scenes").glob("*.toml")))
    sys.exit(f"hapfluid: no scene named '{name}' (config/scenes/{name}.toml does not exist); known scenes: {known}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene")
    run.add_argument("--scene", default="spoon_stirring")
    run.add_argument("--rig", default=str(ROOT / "config" / "rigs" / "fake_single.toml"))
    run.add_argument("--duration", type=float, default=None, help="seconds (default: the scene's duration_s)")
    run.add_argument("--build", default="build")
    run.add_argument("--out", default=None, help="output folder (default: out/<scene>-<timestamp>)")
    args = parser.parse_args()

    build = (ROOT / args.build).resolve() if not pathlib.Path(args.build).is_absolute() else pathlib.Path(args.build)
    bin_dir = build / "bin"
    scene = resolve_scene(args.scene)
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    out = pathlib.Path(args.out) if args.out else ROOT / "out" / f"{scene.stem}-{stamp}"
    out.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()

    print(f"hapfluid: scene {scene.relative_to(ROOT) if scene.is_relative_to(ROOT) else scene}, rig {args.rig}")
    check = subprocess.run([str(bin_dir / "haptic-config"), "check", "--rig", args.rig, str(scene)],
                           capture_output=True, text=True)
    (out / "config-check.txt").write_text(check.stdout + check.stderr)
    sys.stdout.write(check.stdout)
    if check.returncode != 0:
        sys.stderr.write(check.stderr)
        sys.exit("hapfluid: the configuration has errors (listed above); nothing was run")
    shutil.copy(scene, out / "scene.toml")

    summary = {"scene": scene.stem, "out": str(out), "steps": []}
    sim = bin_dir / "haptic-sim"
    if sim.exists():
        command = [str(sim), "--scene", str(scene), "--backend", "cpu", "--out", str(out / "sim")]
        if args.duration:
            command += ["--duration", str(args.duration)]
        print("hapfluid: " + " ".join(command), flush=True)
        result = subprocess.run(command)
        summary["steps"].append({"haptic-sim": result.returncode})
        if result.returncode != 0:
            sys.exit(f"hapfluid: haptic-sim failed (exit {result.returncode}); see the messages above")
        stats = out / "sim" / "stats.json"
        if stats.exists():
            summary["sim"] = json.loads(stats.read_text())
    else:
        print("hapfluid: haptic-sim is not built yet: validated the configuration only")

    summary["wall_s"] = round(time.monotonic() - started, 3)
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(f"hapfluid: done in {summary['wall_s']} s; outputs in {out}")
    for path in sorted(out.rglob("*"))[:20]:
        if path.is_file():
            print(f"  {path.relative_to(out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
