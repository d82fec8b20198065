#!/usr/bin/env python3
"""End-to-end motion-to-force latency of the live stack: the fake device's hand jumps, how long
until the wrench the device applies reacts?

The hand holds the stirring spoon in its pool and makes quick 3 cm moves (30 ms each, every
0.6 s, alternating direction). The spoon's coupling spring (K of the scene) turns a hand
displacement d into a force K d, so the pipeline delay of one move is

    latency = t(applied force has changed by F_thr) - t(hand displacement reached F_thr / K)

both read from the fake device's own 1 kHz log (one clock). Two runs:
  interpolate   the loop renders the sim's wrench only: device -> loop -> shm -> sim step -> shm ->
                loop -> device (what the fluid's reaction costs)
  coupling      the loop also renders the sim's local model F0 - K (x - x0) at 1 kHz (the
                spring part reacts without waiting for the sim)

    motion_to_force_latency.py [--build build] [--out out/latency] [--moves N] [--modes interpolate,coupling]

Writes <out>/motion_to_force.png (latencies per move and per mode, one example move) and
<out>/motion_to_force.json {mode: {p50_ms, p99_ms, max_ms, n}}.
"""
import argparse
import csv
import json
import pathlib
import re
import subprocess
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCENE = ROOT / "config" / "scenes" / "spoon_stirring.toml"
RIG = ROOT / "config" / "rigs" / "fake_single.toml"
STEP_M, MOVE_S, PERIOD_S, FIRST_S = 0.03, 0.03, 0.6, 1.5
FORCE_THRESHOLD_N = 1.5


def latency_scene(out: pathlib.Path, moves: int) -> tuple[pathlib.Path, float, float]:
    """spoon_stirring with the stroke replaced by keyframed jumps; returns (file, K, duration)."""
    text = SCENE.read_text()
    text = text.replace('"../meshes/', f'"{ROOT}/config/meshes/')
    start = [float(v) for v in re.search(r"start_position_m = \[([^\]]+)\]", text).group(1).split(",")]
    stiffness = float(re.search(r"linear_stiffness_n_per_m = ([0-9.]+)", text).group(1))
    head = text[:text.index("[[devices.motion]]")]
    tail = text[text.index("[[couplings]]"):]
    frames, x = [], start[0]
    frames.append((0.0, x))
    for i in range(moves):
        t = FIRST_S + i * PERIOD_S
        nx = start[0] + (STEP_M if i % 2 == 0 else 0.0)
        frames += [(t, x), (t + MOVE_S, nx)]
        x = nx
    lines = ["[[devices.motion]]", 'kind = "keyframes"', "start_s = 0.0", f"stop_s = {FIRST_S + moves * PERIOD_S + 1:.3f}"]
    for t, px in frames:
        lines += ["[[devices.motion.keyframes]]", f"t_s = {t:.4f}", f"position_m = [{px:.4f}, {start[1]}, {start[2]}]",
                  "orientation = [1.0, 0.0, 0.0, 0.0]"]
    path = out / "latency_scene.toml"
    path.write_text(head.replace('name = "spoon_stirring"', 'name = "motion_to_force_latency"') + "\n".join(lines) +
                    "\n\n" + tail)
    return path, stiffness, FIRST_S + moves * PERIOD_S + 0.5


def measure(device_csv: pathlib.Path, stiffness: float, moves: int):
    with device_csv.open(newline="") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t_s"]) for r in rows])
    px = np.array([float(r["px"]) for r in rows])
    fx = np.array([float(r["applied_fx"]) for r in rows])
    lat, examples = [], []
    d_thr = FORCE_THRESHOLD_N / stiffness
    for i in range(moves):
        t0 = FIRST_S + i * PERIOD_S
        before = (t > t0 - 0.12) & (t < t0 - 0.01)
        window = (t >= t0 - 0.01) & (t < t0 + 0.3)
        if before.sum() < 50 or window.sum() < 100:
            continue
        x_ref, f_ref = np.mean(px[before]), np.mean(fx[before])
        tw, dx, df = t[window], np.abs(px[window] - x_ref), np.abs(fx[window] - f_ref)
        moved = np.nonzero(dx >= d_thr)[0]
        reacted = np.nonzero(df >= FORCE_THRESHOLD_N)[0]
        if len(moved) == 0 or len(reacted) == 0:
            continue
        lat.append((tw[reacted[0]] - tw[moved[0]]) * 1e3)
        if not examples:
            examples.append((tw - t0, px[window] - x_ref, fx[window] - f_ref))
    return np.array(lat), examples


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default=str(ROOT / "out" / "latency"))
    ap.add_argument("--moves", type=int, default=10)
    ap.add_argument("--modes", default="interpolate,coupling")
    args = ap.parse_args()
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    scene, stiffness, duration = latency_scene(out, args.moves)
    results, examples = {}, {}
    for mode in args.modes.split(","):
        rig = out / f"rig_{mode}.toml"
        rig.write_text(re.sub(r'wrench_mode = "\w+"', f'wrench_mode = "{mode}"', RIG.read_text()))
        run_dir = out / mode
        cmd = [sys.executable, str(ROOT / "scripts" / "hapfluid.py"), "run", "--scene", str(scene), "--rig", str(rig),
               "--build", args.build, "--out", str(run_dir), "--no-render", "--duration", f"{duration:.2f}"]
        print(f"motion_to_force_latency: {mode}: {' '.join(cmd)}", file=sys.stderr, flush=True)
        if subprocess.run(cmd, stdout=subprocess.DEVNULL).returncode != 0:
            sys.exit(f"motion_to_force_latency: the {mode} run failed; see {run_dir}/logs")
        lat, ex = measure(run_dir / "device_hand.csv", stiffness, args.moves)
        if len(lat) == 0:
            sys.exit(f"motion_to_force_latency: no move of the {mode} run produced a force change >= {FORCE_THRESHOLD_N} N")
        results[mode] = {"p50_ms": round(float(np.percentile(lat, 50)), 2), "p99_ms": round(float(np.percentile(lat, 99)), 2),
                         "max_ms": round(float(lat.max()), 2), "n": int(len(lat)), "latencies_ms": [round(float(v), 2) for v in lat]}
        examples[mode] = ex
        print(f"{mode:12s} motion-to-force latency: p50 {results[mode]['p50_ms']} ms, p99 {results[mode]['p99_ms']} ms "
              f"({len(lat)} moves)")
    (out / "motion_to_force.json").write_text(json.dumps(results, indent=2) + "\n")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    for mode, r in results.items():
        a.plot(range(1, r["n"] + 1), r["latencies_ms"], "o-", label=f"{mode}: p50 {r['p50_ms']} ms, p99 {r['p99_ms']} ms")
    a.set_xlabel("move")
    a.set_ylabel("motion-to-force latency (ms)")
    a.set_title("hand displacement -> applied force change")
    a.grid(alpha=0.3)
    a.legend(fontsize=8)
    for mode, ex in examples.items():
        if ex:
            tw, dx, df = ex[0]
            b.plot(tw * 1e3, df, label=f"force change ({mode})")
    if examples:
        first = next(iter(v for v in examples.values() if v))
        b.plot(first[0] * 1e3, first[1] * stiffness, "k--", label="K x displacement")
    b.axhline(FORCE_THRESHOLD_N, color="grey", lw=0.8)
    b.set_xlim(-10, 120)
    b.set_xlabel("time since the move started (ms)")
    b.set_ylabel("N")
    b.set_title("one move")
    b.grid(alpha=0.3)
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "motion_to_force.png", dpi=110)
    print(f"motion_to_force_latency: {out / 'motion_to_force.png'}, {out / 'motion_to_force.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
