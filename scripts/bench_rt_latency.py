#!/usr/bin/env python3
"""Benchmark of haptic-rt's 1 kHz loop: a run with two (simulated) devices and a 100 Hz stand-in
sim, side by side with cyclictest at the same priority and period over the same window
(python -m hapfluid.latency_report --with-cyclictest). Target: loop compute p99.9 <= 20 µs.

    bench_rt_latency.py --build build --out out/bench/rt_latency.json [--duration 30 | --short]
"""
import argparse
import json
import pathlib
import sys

from hapfluid import latency_report

SOURCE_DIR = pathlib.Path(__file__).resolve().parent.parent
RIG = SOURCE_DIR / "tests" / "rt_core" / "rigs" / "bench_two_arms.toml"


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--build", default="build")
    p.add_argument("--out", default="out/bench/rt_latency.json")
    p.add_argument("--duration", type=float, default=30.0, help="seconds (default 30)")
    p.add_argument("--short", action="store_true", help="a 5 s run while developing")
    args = p.parse_args()
    duration = 5.0 if args.short else args.duration
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    trace = out.with_suffix(".trace.csv")

    cyclictest, hist, _ = latency_report.run_with_cyclictest(trace, RIG, args.build, duration, sim_rate_hz=100)
    summary = latency_report.summarize(latency_report.load_trace(trace))
    latency_report.histogram_png(latency_report.load_trace(trace), summary, out.with_suffix(".png"), hist)
    print(latency_report.format_report(summary, cyclictest), file=sys.stderr)

    w, c, lt = summary["wake_latency_us"], summary["compute_us"], summary["loop_time_us"]
    record = {
        "bench": "rt_latency",
        "params": {"duration_s": duration, "devices": 2, "period_us": summary["period_us"], "sim_rate_hz": 100,
                   "degraded": summary["degraded"], "preempt_rt": summary["preempt_rt"]},
        "metrics": {
            "wake_p50_us": w["p50"], "wake_p99_us": w["p99"], "wake_p999_us": w["p99.9"], "wake_max_us": w["max"],
            "cyclictest_p50_us": cyclictest["p50"], "cyclictest_p99_us": cyclictest["p99"],
            "cyclictest_p999_us": cyclictest["p99.9"], "cyclictest_max_us": cyclictest["max"],
            "compute_p99_us": c["p99"], "compute_p999_us": c["p99.9"], "compute_max_us": c["max"],
            "loop_time_p999_us": lt["p99.9"],
            "deadline_misses": summary["deadline_misses"], "overruns": summary["overruns"], "ticks": summary["ticks"],
            "compute_p999_target_met": c["p99.9"] <= 20.0,
        },
    }
    out.write_text(json.dumps([record], indent=2))
    print(f"bench_rt_latency: wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
