#!/usr/bin/env python3
"""End-to-end motion-to-force latency of the live stack: from the 1 kHz loop reading a device
pose to the loop sending the wrench the simulator computed FROM that pose.

Runs the stirring scene on the live stack (scripts/hapfluid.py: fake hand stroking, haptic-rt,
haptic-sim --live, haptic-trace) and measures every sim sample, one clock (CLOCK_MONOTONIC):

    pose read     wake_ns of the loop tick T whose device_states record the sim stepped with
                  (sim/couplings.csv: device_tick; trace.csv: tick -> wake_ns)
    force sent    wake_ns + io_ns of the first loop tick after the sample's publish_ns (the
                  loop picks up a new sample every tick, renders it and sends the command)
    latency       force sent - pose read  (loop -> shm -> sim step -> shm -> loop -> device)

plus, per the fake device's 1 kHz state period, up to 1 ms between the hand moving and the
loop reading the frame. In coupling mode the spring part of the local model (F0 - K (x - x0))
reacts within the tick; this is the latency of the fluid's reaction F0.

A cruder cross-check needs no clocks: the force the fake device applied lags its hand's stroke
velocity; the lag maximising their (anti-)correlation is printed as well.

    motion_to_force_latency.py [--build build] [--out out/latency] [--duration 8] [--run RUN_DIR]

Writes <out>/motion_to_force.png (histogram and latency over time) and <out>/motion_to_force.json.
"""
import argparse
import csv
import json
import pathlib
import subprocess
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent


def load_columns(path: pathlib.Path, names) -> dict:
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    return {n: np.array([float(r[n]) for r in rows]) for n in names}


def pipeline_latencies(run: pathlib.Path):
    """(sim_time_s, latency_ms) per sim sample that used a device pose."""
    trace = load_columns(run / "trace.csv", ("tick", "wake_ns", "io_ns"))
    sim = load_columns(run / "sim" / "couplings.csv", ("t", "device_tick", "publish_ns"))
    order = np.argsort(trace["tick"])
    ticks, wake, io = trace["tick"][order], trace["wake_ns"][order], trace["io_ns"][order]
    used = sim["device_tick"] > 0
    t, dtick, pub = sim["t"][used], sim["device_tick"][used], sim["publish_ns"][used]
    i_in = np.searchsorted(ticks, dtick)
    ok = (i_in < len(ticks)) & (ticks[np.minimum(i_in, len(ticks) - 1)] == dtick)
    # Ticks wake in order, so the first tick after a publish is a binary search on wake_ns.
    i_out = np.searchsorted(wake, pub, side="right")
    ok &= i_out < len(wake)
    i_in, i_out = i_in[ok], i_out[ok]
    sent = wake[i_out] + io[i_out]
    return t[ok], (sent - wake[i_in]) * 1e-6


def correlation_lag_ms(run: pathlib.Path):
    """Lag (ms) at which the applied force best anti-correlates with the hand's stroke velocity."""
    log = load_columns(run / "device_hand.csv", ("t_s", "px", "applied_fx"))
    t, px, fx = log["t_s"], log["px"], log["applied_fx"]
    vx = np.gradient(px, t)
    m = (t > 1.5) & (t < t[-1] - 1.0)
    vx, fx = vx[m] - vx[m].mean(), fx[m] - fx[m].mean()
    lags = np.arange(0, 120)
    corr = [np.corrcoef(vx[: len(vx) - k], fx[k:])[0, 1] for k in lags]
    k = int(np.argmin(corr))
    return float(lags[k]), float(corr[k])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default=str(ROOT / "out" / "latency"))
    ap.add_argument("--duration", type=float, default=8.0)
    ap.add_argument("--run", default=None, help="analyse an existing hapfluid.py run folder instead of running")
    args = ap.parse_args()
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    run = pathlib.Path(args.run).resolve() if args.run else out / "run"
    if not args.run:
        cmd = [sys.executable, str(ROOT / "scripts" / "hapfluid.py"), "run", "--scene", "spoon_stirring", "--build",
               args.build, "--out", str(run), "--no-render", "--duration", str(args.duration)]
        print("motion_to_force_latency: " + " ".join(cmd), file=sys.stderr, flush=True)
        if subprocess.run(cmd, stdout=subprocess.DEVNULL).returncode != 0:
            sys.exit(f"motion_to_force_latency: the run failed; see {run}/logs")
    t, lat = pipeline_latencies(run)
    if len(lat) == 0:
        sys.exit(f"motion_to_force_latency: no sim sample in {run} used a device pose (was haptic-rt running?)")
    lag_ms, corr = correlation_lag_ms(run)
    result = {"samples": int(len(lat)), "p50_ms": round(float(np.percentile(lat, 50)), 2),
              "p99_ms": round(float(np.percentile(lat, 99)), 2), "max_ms": round(float(lat.max()), 2),
              "device_frame_period_ms": 1.0, "stroke_force_lag_ms": lag_ms, "stroke_force_correlation": round(corr, 3),
              "run": str(run)}
    (out / "motion_to_force.json").write_text(json.dumps(result, indent=2) + "\n")
    print(f"motion-to-force latency (pose read by the loop -> sim wrench sent to the device), {len(lat)} samples: "
          f"p50 {result['p50_ms']} ms, p99 {result['p99_ms']} ms, max {result['max_ms']} ms "
          f"(+ up to 1 ms device frame period)")
    print(f"cross-check: applied force lags the stroke velocity by {lag_ms:.0f} ms (correlation {corr:.2f})")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    a.hist(lat, bins=60, color="tab:blue")
    for q, style in (("p50_ms", "--"), ("p99_ms", ":")):
        a.axvline(result[q], color="k", ls=style, label=f"{q[:3]} {result[q]} ms")
    a.set_xlabel("motion-to-force latency (ms)")
    a.set_ylabel("sim samples")
    a.set_title("pose read by the loop -> sim wrench sent")
    a.legend()
    b.plot(t, lat, ".", ms=2)
    b.set_xlabel("simulated time (s)")
    b.set_ylabel("latency (ms)")
    b.set_title("per sample")
    b.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "motion_to_force.png", dpi=110)
    print(f"motion_to_force_latency: {out / 'motion_to_force.png'}, {out / 'motion_to_force.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
