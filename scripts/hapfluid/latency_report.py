"""Latency report of haptic-rt's 1 kHz loop from its trace CSV (rt_core/include/hapfluid/rt/trace_csv.hpp).

    hapfluid-latency-report TRACE [--png FILE] [--json FILE] [--skip-ms 200]
        percentiles (p50, p99, p99.9, max) of wake latency, loop time (compute + device I/O), compute
        time and sim sample age; deadline misses and overruns; link quality per device; a histogram PNG.

    hapfluid-latency-report TRACE --with-cyclictest --rig RIG [--build build] [--duration 30] [--sim-rate 100]
        runs haptic-rt (simulated devices unless --real-devices) writing TRACE, a stand-in sim, and
        cyclictest (rt-tests) at the rig's SCHED_FIFO priority, period and CPU over the same window,
        then prints haptic-rt's wake latency next to cyclictest's.

    hapfluid-latency-report TRACE --cyclictest-log FILE --window-ns START:END
        a run made elsewhere (the launcher: cyclictest beside the live stack, started with
        start_cyclictest): the trace's ticks scheduled in [START, END] (CLOCK_MONOTONIC ns, the
        window cyclictest ran) next to cyclictest's histogram output in FILE.

Times are reported in microseconds. A deadline miss is a tick whose work ended after the next
tick's scheduled wake time; overruns are the periods the loop skipped while re-phasing.
"""
import argparse
import json
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np

from .c_constants import LoopFlag
from .paths import ROOT as SOURCE_DIR
DEGRADED_FLAGS = {LoopFlag.no_fifo: "no SCHED_FIFO", LoopFlag.no_mlock: "memory not locked",
                  LoopFlag.no_affinity: "not pinned to its CPU"}
NOT_PREEMPT_RT = LoopFlag.not_preempt_rt


def percentiles(values_us: np.ndarray) -> dict:
    if values_us.size == 0:
        return {"p50": float("nan"), "p99": float("nan"), "p99.9": float("nan"), "max": float("nan"), "n": 0}
    p50, p99, p999 = np.percentile(values_us, [50, 99, 99.9])
    return {"p50": float(p50), "p99": float(p99), "p99.9": float(p999), "max": float(values_us.max()),
            "n": int(values_us.size)}


def load_trace(path) -> dict:
    path = pathlib.Path(path)
    if not path.exists():
        sys.exit(f"latency_report: {path}: no such trace file")
    with open(path) as f:
        header = f.readline().strip().split(",")
    if not header or header[0] != "tick":
        sys.exit(f"latency_report: {path}: not a haptic-rt trace (first column must be 'tick')")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    if data.shape[0] == 0:
        sys.exit(f"latency_report: {path}: the trace holds no ticks")
    return {name: data[:, i] for i, name in enumerate(header)}


def select_window(trace: dict, start_ns: float, end_ns: float) -> dict:
    """The ticks scheduled within [start_ns, end_ns] (CLOCK_MONOTONIC, as scheduled_ns)."""
    keep = (trace["scheduled_ns"] >= start_ns) & (trace["scheduled_ns"] <= end_ns)
    if not keep.any():
        sys.exit(f"latency_report: no tick of the trace lies in the window {start_ns:.0f}..{end_ns:.0f} ns "
                 f"(trace: {trace['scheduled_ns'][0]:.0f}..{trace['scheduled_ns'][-1]:.0f} ns)")
    return {k: v[keep] for k, v in trace.items()}


def summarize(trace: dict, skip_ms: float = 200.0) -> dict:
    """Statistics of a trace, skipping the first `skip_ms` (start-up: page faults, first attach)."""
    scheduled = trace["scheduled_ns"]
    keep = scheduled >= scheduled[0] + skip_ms * 1e6
    if not keep.any():
        keep = np.ones_like(scheduled, dtype=bool)
    t = {k: v[keep] for k, v in trace.items()}
    period_ns = float(np.median(np.diff(trace["scheduled_ns"]))) if len(scheduled) > 1 else 1e6
    wake_us = t["wake_latency_ns"] / 1e3
    compute_us = t["compute_ns"] / 1e3
    loop_us = (t["compute_ns"] + t["io_ns"]) / 1e3
    end_ns = t["wake_ns"] + t["compute_ns"] + t["io_ns"]
    deadline_misses = int(np.sum(end_ns > t["scheduled_ns"] + period_ns))
    sim_age = t["sim_age_ns"][t["sim_age_ns"] >= 0] / 1e3
    flags = np.bitwise_or.reduce(t["loop_flags"].astype(np.int64)) if t["loop_flags"].size else 0
    devices = []
    d = 0
    while f"d{d}_fresh" in t:
        fresh = t[f"d{d}_fresh"]
        if np.any(t[f"d{d}_flags"] != 0) or np.any(fresh != 0):
            devices.append({"device": d, "fresh_share": float(fresh.mean()),
                            "longest_miss_run_ticks": int(t[f"d{d}_miss_run"].max())})
        d += 1
    overruns = int(t["overruns"][-1] - t["overruns"][0]) if t["overruns"].size else 0
    return {
        "ticks": int(keep.sum()),
        "period_us": period_ns / 1e3,
        "wake_latency_us": percentiles(wake_us),
        "loop_time_us": percentiles(loop_us),
        "compute_us": percentiles(compute_us),
        "sim_sample_age_us": percentiles(sim_age),
        "deadline_misses": deadline_misses,
        "overruns": overruns,
        "degraded": [name for bit, name in DEGRADED_FLAGS.items() if flags & bit],
        "preempt_rt": not (flags & NOT_PREEMPT_RT),
        "devices": devices,
    }


def histogram_png(trace: dict, summary: dict, path, cyclictest_hist=None):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    wake_us = trace["wake_latency_ns"] / 1e3
    compute_us = trace["compute_ns"] / 1e3
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))

    def stats(p):
        return f"p50 {p['p50']:.0f}, p99 {p['p99']:.0f}, p99.9 {p['p99.9']:.0f}, max {p['max']:.0f} µs"
    # Log-spaced bins on a log axis: the bulk (µs) and the tail (ms) both readable in one panel.
    top = max(50.0, float(wake_us.max()) * 1.1)
    bins = np.geomspace(1.0, top, 120)
    axes[0].hist(np.clip(wake_us, 1.0, top), bins=bins, log=True, alpha=0.8,
                 label="haptic-rt: " + stats(summary["wake_latency_us"]))
    if cyclictest_hist is not None:
        us, counts = cyclictest_hist
        label = "cyclictest (histogram to 2 ms): " + stats(summary["cyclictest_us"]) if "cyclictest_us" in summary \
            else "cyclictest"
        axes[0].hist(np.clip(us, 1.0, top), bins=bins, weights=counts, log=True, alpha=0.5, label=label)
    axes[0].set_xscale("log")
    axes[0].set_xlabel("wake latency (µs, log scale)")
    axes[0].set_ylabel("ticks")
    axes[0].set_title("wake latency" + (" beside cyclictest, same window" if cyclictest_hist is not None else ""))
    axes[0].legend(fontsize=7, loc="upper right")
    top_c = max(5.0, float(np.percentile(compute_us, 99.99)) * 1.2)
    axes[1].hist(np.clip(compute_us, 0, top_c), bins=120, log=True, color="tab:green")
    axes[1].set_xlabel("loop compute per tick (µs)")
    axes[1].set_title(f"compute: p99.9 {summary['compute_us']['p99.9']:.1f} µs")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


# ---- cyclictest --------------------------------------------------------------------------------
def parse_cyclictest_histogram(text: str):
    """cyclictest -h output: '000123 000045' rows (µs bucket, count) and '# Histogram Overflows'."""
    us, counts = [], []
    for line in text.splitlines():
        m = re.match(r"^(\d+)\s+(\d+)\s*$", line)
        if m:
            us.append(int(m.group(1)))
            counts.append(int(m.group(2)))
    overflow = re.search(r"# Histogram Overflows:\s*(\d+)", text)
    max_latency = re.search(r"# Max Latencies:\s*(\d+)", text)
    return np.array(us, dtype=float), np.array(counts, dtype=float), \
        int(overflow.group(1)) if overflow else 0, int(max_latency.group(1)) if max_latency else None


def cyclictest_percentiles(us, counts, overflows, max_latency) -> dict:
    total = counts.sum() + overflows
    if total == 0:
        return percentiles(np.array([]))
    cumulative = np.cumsum(counts) / total

    def at(q):
        idx = np.searchsorted(cumulative, q)
        return float(us[idx]) if idx < len(us) else float(max_latency or us[-1])

    return {"p50": at(0.5), "p99": at(0.99), "p99.9": at(0.999),
            "max": float(max_latency) if max_latency is not None else float(us[counts > 0].max()), "n": int(total)}


def cyclictest_result(text: str):
    """(percentiles, (µs buckets, counts)) of a finished cyclictest -h run's output."""
    us, counts, overflows, max_latency = parse_cyclictest_histogram(text)
    return cyclictest_percentiles(us, counts, overflows, max_latency), (us, counts)


def read_rig_rt(rig_path) -> dict:
    """The [rt] settings cyclictest must share (priority, period_ns, cpu), via haptic-config's schema
    defaults: priority 80, period 1 ms, no pinning."""
    import tomllib
    with open(rig_path, "rb") as f:
        rt = tomllib.load(f).get("rt", {})
    return {"priority": int(rt.get("priority", 80)), "period_ns": int(rt.get("period_ns", 1_000_000)),
            "cpu": int(rt.get("cpu", -1))}


def start_cyclictest(rt_settings: dict, cpu: int | None = None, duration_s: float | None = None,
                     stdout=subprocess.PIPE, stderr=subprocess.PIPE):
    """cyclictest as the loop runs: one thread, SCHED_FIFO at the rig's rt.priority, woken every
    rt.period_ns, memory locked, a 1 µs histogram up to 2 ms (output at its end), on `cpu` (default
    the rig's rt.cpu; -1: any). Ends after duration_s, or when sent SIGINT (then it prints its
    histogram too). None when cyclictest (rt-tests) is not installed.
    (--secaligned, to wake at a chosen phase, was tried: rt-tests 2.40 here counted 1.1 s of
    samples too many after one start in four, so its window could not be known.)"""
    cyclictest = shutil.which("cyclictest")
    if not cyclictest:
        return None
    cpu = rt_settings["cpu"] if cpu is None else cpu
    args = [cyclictest, "-m", "-q", "-t1", f"-p{rt_settings['priority']}", f"-i{rt_settings['period_ns'] // 1000}",
            "-h2000"]
    if duration_s:
        args.append(f"-D{int(round(duration_s))}")
    if cpu >= 0:
        args.append(f"-a{cpu}")
    return subprocess.Popen(args, stdout=stdout, stderr=stderr, text=True)


def run_with_cyclictest(trace_path, rig, build, duration_s, sim_rate_hz, real_devices=False, prefix=None):
    """Runs haptic-rt (+ stand-in sim) and cyclictest over the same window; returns cyclictest's stats."""
    if not shutil.which("cyclictest"):
        sys.exit("latency_report: --with-cyclictest needs cyclictest (apt install rt-tests)")
    rt_settings = read_rig_rt(rig)
    build = pathlib.Path(build)
    prefix = prefix or f"hapfluid-latency-{os.getpid()}"
    rt_args = [str(build / "bin" / "haptic-rt"), "--rig", str(rig), "--shm-prefix", prefix,
               "--duration", str(duration_s), "--trace", str(trace_path)]
    if not real_devices:
        rt_args.append("--simulated-devices")
    print(f"latency_report: running haptic-rt and cyclictest for {duration_s:g} s "
          f"(SCHED_FIFO {rt_settings['priority']}, period {rt_settings['period_ns'] / 1e3:g} µs)", file=sys.stderr)
    rt_proc = subprocess.Popen(rt_args, stderr=subprocess.PIPE, text=True)
    sim = None
    standin = build / "bin" / "haptic-sim-standin"
    if sim_rate_hz > 0 and standin.exists():
        sim = subprocess.Popen([str(standin), "--shm-prefix", prefix, "--rate", str(sim_rate_hz), "--devices", "4",
                                "--pattern", "sine", "--force", "0.5,0,0.5", "--stiffness", "300", "--damping", "2"],
                               stderr=subprocess.DEVNULL)
    ct = start_cyclictest(rt_settings, duration_s=duration_s)
    ct_out, ct_err = ct.communicate(timeout=duration_s + 60)
    _, rt_err = rt_proc.communicate(timeout=duration_s + 60)
    if sim:
        sim.send_signal(signal.SIGTERM)
        sim.wait(timeout=10)
    if rt_proc.returncode != 0:
        sys.exit(f"latency_report: haptic-rt failed ({rt_proc.returncode}):\n{rt_err}")
    if ct.returncode != 0:
        sys.exit(f"latency_report: cyclictest failed ({ct.returncode}): {ct_err.strip()}")
    stats, hist = cyclictest_result(ct_out)
    return stats, hist, rt_err


def format_report(summary: dict, cyclictest: dict | None = None) -> str:
    lines = [f"haptic-rt trace: {summary['ticks']} ticks at {summary['period_us']:g} µs"]
    if summary["degraded"]:
        lines.append("DEGRADED run: " + ", ".join(summary["degraded"]))
    if not summary["preempt_rt"]:
        lines.append("note: kernel is not PREEMPT_RT")
    header = f"{'':24s}{'p50':>10s}{'p99':>10s}{'p99.9':>10s}{'max':>10s}"
    lines.append(header)

    def row(name, p):
        return f"{name:24s}" + "".join(f"{p[k]:10.1f}" for k in ("p50", "p99", "p99.9", "max"))

    lines.append(row("wake latency (µs)", summary["wake_latency_us"]))
    if cyclictest:
        lines.append(row("cyclictest (µs)", cyclictest))
    lines.append(row("loop time (µs)", summary["loop_time_us"]))
    lines.append(row("  compute only (µs)", summary["compute_us"]))
    if summary["sim_sample_age_us"]["n"]:
        lines.append(row("sim sample age (ms)", {k: v / 1e3 for k, v in summary["sim_sample_age_us"].items()}))
    lines.append(f"deadline misses: {summary['deadline_misses']}, overruns (skipped periods): {summary['overruns']}")
    for d in summary["devices"]:
        lines.append(f"device d{d['device']}: link quality {d['fresh_share']:.4f} fresh, "
                     f"longest miss run {d['longest_miss_run_ticks']} ticks")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("trace", help="trace CSV (read, or written when --with-cyclictest runs haptic-rt)")
    p.add_argument("--png", help="histogram PNG (default: TRACE with .png)")
    p.add_argument("--json", help="write the statistics as JSON")
    p.add_argument("--skip-ms", type=float, default=200.0, help="ignore the first ms of the run (start-up)")
    p.add_argument("--with-cyclictest", action="store_true", help="run haptic-rt and cyclictest side by side")
    p.add_argument("--rig", help="rig file for --with-cyclictest")
    p.add_argument("--build", default=str(SOURCE_DIR / "build"))
    p.add_argument("--duration", type=float, default=30.0, help="seconds, for --with-cyclictest")
    p.add_argument("--sim-rate", type=float, default=100.0, help="stand-in sim rate in Hz (0: no sim)")
    p.add_argument("--real-devices", action="store_true", help="open the rig's devices instead of simulating")
    p.add_argument("--cyclictest-log", help="cyclictest -h output of a run beside the loop (start_cyclictest)")
    p.add_argument("--window-ns", help="START:END, CLOCK_MONOTONIC ns: only the ticks scheduled in this window "
                                       "(the one cyclictest ran); no --skip-ms then")
    args = p.parse_args(argv)

    cyclictest, cyclictest_hist = None, None
    if args.with_cyclictest:
        if not args.rig:
            p.error("--with-cyclictest needs --rig RIG (haptic-rt and cyclictest run together)")
        cyclictest, cyclictest_hist, _ = run_with_cyclictest(args.trace, args.rig, args.build, args.duration,
                                                             args.sim_rate, args.real_devices)
    elif args.cyclictest_log:
        log = pathlib.Path(args.cyclictest_log)
        if not log.exists():
            sys.exit(f"latency_report: --cyclictest-log {log}: no such file")
        cyclictest, cyclictest_hist = cyclictest_result(log.read_text())
        if cyclictest["n"] == 0:
            sys.exit(f"latency_report: --cyclictest-log {log}: no histogram in it (was cyclictest run with -h "
                     f"and stopped by SIGINT or -D?)")
    trace = load_trace(args.trace)
    skip_ms = args.skip_ms
    if args.window_ns:
        try:
            start_ns, end_ns = (float(v) for v in args.window_ns.split(":"))
        except ValueError:
            p.error(f"--window-ns {args.window_ns}: must be START:END in ns")
        trace, skip_ms = select_window(trace, start_ns, end_ns), 0.0
    summary = summarize(trace, skip_ms)
    if args.window_ns:
        summary["window_s"] = round((end_ns - start_ns) * 1e-9, 3)
    if cyclictest:
        summary["cyclictest_us"] = cyclictest
    print(format_report(summary, cyclictest))
    png = args.png or str(pathlib.Path(args.trace).with_suffix(".png"))
    histogram_png(trace, summary, png, cyclictest_hist)
    print(f"histogram: {png}")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(summary, indent=2))
    return summary


if __name__ == "__main__":
    main()
