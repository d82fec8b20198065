#!/usr/bin/env python3
"""What the operator's page costs the 1 kHz loop (`make bench`): the live stack (`hapfluid run`,
the default scene, fake device, cyclictest beside the loop, no renderer) without the dashboard and
with it open in a browser (Debian's chromium, headless, through Playwright), alternated A B A B in
one session. Reports the loop's wake-latency p99.9 of each run, the ratio of their medians (target
<= 1.05) with cyclictest's p99.9 from the same windows as the machine's own reference, and the CPU
the dashboard used (its server and haptic-status; the browser's apart).

    bench_dashboard.py --build build --out out/bench/dashboard.json [--pairs 5] [--seconds 20]

A p99.9 of a 20 s run rests on its 20 slowest wake-ups, and this machine's own (cyclictest's)
p99.9 moves by several times between runs minutes apart: the ratio needs several pairs, and the
loop's p99.9 over cyclictest's from the same window is reported as well.
"""
import argparse
import json
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time

from hapfluid import latency_report
from hapfluid.launcher import cpu_placement
from hapfluid.paths import RIGS

CLK_TCK = os.sysconf("SC_CLK_TCK")
# The browser goes where the rig's other non-real-time parts go, off the loop's CPU (a browser on
# the rig itself is the worst case: an operator's is on another machine, through the tunnel).
SERVICE_CPUS = cpu_placement(latency_report.read_rig_rt(RIGS / "fake_single.toml"))[1]


def cpu_seconds(pid: int) -> float:
    """utime + stime of a process (/proc/PID/stat), 0 once it is gone."""
    try:
        fields = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / CLK_TCK


def pids_of(pattern: str) -> list[int]:
    r = subprocess.run(["pgrep", "-f", pattern], capture_output=True, text=True)
    return [int(p) for p in r.stdout.split()]


class CpuSampler(threading.Thread):
    """The CPU seconds of the processes matching each pattern, sampled every half second until
    stopped (the newest value each process reached: they are read before they exit)."""

    def __init__(self, patterns: dict):
        super().__init__(daemon=True)
        self.patterns, self.seen, self.stop = patterns, {k: {} for k in patterns}, threading.Event()

    def run(self):
        while not self.stop.is_set():
            for key, pattern in self.patterns.items():
                for pid in pids_of(pattern):
                    self.seen[key][pid] = max(self.seen[key].get(pid, 0.0), cpu_seconds(pid))
                    if key == "browser":
                        keep_off_the_loop(pid)
            self.stop.wait(0.5)

    def total(self, key) -> float:
        return round(sum(self.seen[key].values()), 3)


def keep_off_the_loop(pid: int):
    """Every thread of the process onto SERVICE_CPUS (new threads inherit it)."""
    if not SERVICE_CPUS:
        return
    for task in pathlib.Path(f"/proc/{pid}/task").glob("*"):
        try:
            os.sched_setaffinity(int(task.name), SERVICE_CPUS)
        except OSError:
            pass


def browse(url: str, stop: threading.Event):
    """The page open in Debian's chromium until stopped."""
    from playwright.sync_api import sync_playwright
    if SERVICE_CPUS:
        os.sched_setaffinity(0, SERVICE_CPUS)  # this thread: the driver and the browser it starts inherit it
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=shutil.which("chromium"), args=["--no-sandbox"])
        page = browser.new_page()
        page.goto(url)
        stop.wait()
        browser.close()


def one_run(build: pathlib.Path, out: pathlib.Path, seconds: float, dashboard: bool) -> dict:
    command = [sys.executable, "-m", "hapfluid", "run", "--build", str(build), "--out", str(out), "--no-render",
               "--duration", str(seconds)] + ([] if dashboard else ["--no-dashboard"])
    run = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    url, lines, sampler, browsing, stop = None, [], None, None, threading.Event()
    for line in run.stdout:
        lines.append(line)
        if "(shm prefix " in line:
            prefix = line.split("(shm prefix ", 1)[1].split(")", 1)[0]
            sampler = CpuSampler({"dashboard": f"hapfluid.dashboard --shm-prefix {prefix} ",
                                  "status": f"haptic-status --shm-prefix {prefix} ",
                                  "browser": "chromium|playwright/driver"})
            sampler.start()
        if dashboard and "the operator's page: " in line:
            url = line.split("the operator's page: ", 1)[1].strip()
            browsing = threading.Thread(target=browse, args=(url, stop), daemon=True)
            browsing.start()
    code = run.wait()
    stop.set()
    if browsing:
        browsing.join(timeout=30)
    if sampler:
        sampler.stop.set()
        sampler.join()
    if code != 0:
        sys.exit(f"bench_dashboard: `{' '.join(command)}` exited {code}:\n{''.join(lines[-20:])}")
    summary = json.loads((out / "summary.json").read_text())
    return {"dashboard": dashboard, "url": url, "wake_p999_us": summary["wake_latency_us"]["p99.9"],
            "cyclictest_p999_us": (summary.get("cyclictest_us") or {}).get("p99.9"),
            "real_time_factor": summary["real_time_factor"], "wall_s": summary["wall_s"],
            "dashboard_cpu_s": round(sampler.total("dashboard") + sampler.total("status"), 3) if sampler else 0.0,
            "browser_cpu_s": sampler.total("browser") if sampler else 0.0}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--build", default="build")
    p.add_argument("--out", default="out/bench/dashboard.json")
    p.add_argument("--pairs", type=int, default=5)
    p.add_argument("--seconds", type=float, default=20.0, help="wall seconds of each run")
    args = p.parse_args()
    if not shutil.which("chromium"):
        sys.exit("bench_dashboard: chromium is missing (scripts/install-deps.sh)")
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    runs = []
    with tempfile.TemporaryDirectory(prefix="hapfluid-bench-dashboard-") as tmp:
        for k in range(2 * args.pairs):
            dashboard = k % 2 == 1  # A B A B: without, then with
            r = one_run(pathlib.Path(args.build).resolve(), pathlib.Path(tmp) / f"run{k}", args.seconds, dashboard)
            runs.append(r)
            print(f"bench_dashboard: run {k + 1}/{2 * args.pairs} ({'with' if dashboard else 'without'} the page): "
                  f"loop p99.9 {r['wake_p999_us']:.0f} us, cyclictest p99.9 {r['cyclictest_p999_us']} us, "
                  f"dashboard CPU {r['dashboard_cpu_s']} s", file=sys.stderr, flush=True)
    without = [r["wake_p999_us"] for r in runs if not r["dashboard"]]
    with_page = [r["wake_p999_us"] for r in runs if r["dashboard"]]
    ratio = statistics.median(with_page) / statistics.median(without)
    # The loop against the machine in the same window: cyclictest beside it sees the same noise.
    relative = {side: statistics.median(r["wake_p999_us"] / r["cyclictest_p999_us"] for r in runs
                                        if r["dashboard"] == side and r["cyclictest_p999_us"])
                for side in (False, True)} if all(r["cyclictest_p999_us"] for r in runs) else None
    dash_cpu = [r["dashboard_cpu_s"] / r["wall_s"] for r in runs if r["dashboard"]]
    browser_cpu = [r["browser_cpu_s"] / r["wall_s"] for r in runs if r["dashboard"]]
    record = {
        "bench": "dashboard_cost",
        "params": {"scene": "spoon_stirring", "pairs": args.pairs, "seconds": args.seconds, "renderer": False,
                   "order": "A B A B (without, with)", "browser_cpus": sorted(SERVICE_CPUS)},
        "metrics": {
            "wake_p999_us_without": without, "wake_p999_us_with": with_page,
            "cyclictest_p999_us_without": [r["cyclictest_p999_us"] for r in runs if not r["dashboard"]],
            "cyclictest_p999_us_with": [r["cyclictest_p999_us"] for r in runs if r["dashboard"]],
            "wake_p999_ratio_with_over_without": round(ratio, 3),
            "ratio_target_met": ratio <= 1.05,
            "wake_over_cyclictest_p999_without": round(relative[False], 3) if relative else None,
            "wake_over_cyclictest_p999_with": round(relative[True], 3) if relative else None,
            "dashboard_cpu_share_of_a_core": round(statistics.median(dash_cpu), 4),
            "browser_cpu_share_of_a_core": round(statistics.median(browser_cpu), 4),
        },
    }
    out.write_text(json.dumps([record], indent=2))
    if relative:
        print(f"bench_dashboard: loop p99.9 / cyclictest p99.9 in the same window, medians: without the page "
              f"{relative[False]:.2f}, with it {relative[True]:.2f}", file=sys.stderr)
    print(f"bench_dashboard: loop p99.9 with the page / without, medians: {ratio:.3f} (target <= 1.05); "
          f"dashboard {100 * statistics.median(dash_cpu):.1f} % of a core; wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
