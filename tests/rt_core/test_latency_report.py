"""hapfluid.latency_report: statistics from a known trace, cyclictest histogram parsing, and a
short real side-by-side run."""
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest


@pytest.fixture(scope="module")
def report():
    from hapfluid import latency_report
    return latency_report


def write_trace(path, wake_latency_ns, compute_ns, io_ns=1000, fresh=None):
    n = len(wake_latency_ns)
    fresh = np.ones(n, dtype=int) if fresh is None else fresh
    miss = np.zeros(n, dtype=int)
    for i in range(1, n):
        miss[i] = 0 if fresh[i] else miss[i - 1] + 1
    with open(path, "w") as f:
        f.write("tick,scheduled_ns,wake_ns,wake_latency_ns,compute_ns,io_ns,sim_age_ns,loop_flags,overruns,"
                "d0_flags,d0_faults,d0_fx,d0_fy,d0_fz,d0_tx,d0_ty,d0_tz,d0_fresh,d0_miss_run\n")
        for i in range(n):
            scheduled = 1_000_000_000 + i * 1_000_000
            f.write(f"{i + 1},{scheduled},{scheduled + wake_latency_ns[i]},{wake_latency_ns[i]},{compute_ns[i]},"
                    f"{io_ns},5000000,8,0,0,0,0,0,1,0,0,0,{fresh[i]},{miss[i]}\n")


def test_percentiles_deadline_misses_and_link_quality_from_a_known_trace(report, tmp_path):
    # 10 000 ticks: wake latency 10 µs except 5 ticks at 2 ms (those end after the next tick's
    # deadline); compute 5 µs; the device misses 100 frames in one run of 100 ticks.
    wake = np.full(10_000, 10_000)
    wake[[3000, 4000, 5000, 6000, 7000]] = 2_000_000
    compute = np.full(10_000, 5_000)
    fresh = np.ones(10_000, dtype=int)
    fresh[5000:5100] = 0
    path = tmp_path / "trace.csv"
    write_trace(path, wake, compute, fresh=fresh)
    s = report.summarize(report.load_trace(path), skip_ms=0)
    assert s["ticks"] == 10_000
    assert s["wake_latency_us"]["p50"] == pytest.approx(10.0)
    assert s["wake_latency_us"]["max"] == pytest.approx(2000.0)
    assert s["compute_us"]["p99.9"] == pytest.approx(5.0)
    assert s["loop_time_us"]["p50"] == pytest.approx(6.0)
    assert s["deadline_misses"] == 5
    assert s["devices"][0]["fresh_share"] == pytest.approx(0.99)
    assert s["devices"][0]["longest_miss_run_ticks"] == 100
    assert not s["preempt_rt"] and s["degraded"] == []
    text = report.format_report(s)
    assert "deadline misses: 5" in text and "longest miss run 100 ticks" in text


def test_cyclictest_histogram_percentiles(report):
    # 985 samples at 5 µs, 14 at 50 µs, 1 overflow beyond the histogram (max 3000 µs).
    text = "# /dev/cpu_dma_latency set to 0us\n000005 000985\n000050 000014\n" \
           "# Total: 000000999\n# Histogram Overflows: 00001\n# Max Latencies: 03000\n"
    us, counts, overflows, max_latency = report.parse_cyclictest_histogram(text)
    p = report.cyclictest_percentiles(us, counts, overflows, max_latency)
    assert p["p50"] == 5 and p["p99"] == 50 and p["max"] == 3000 and p["n"] == 1000


def test_bad_trace_is_refused_with_its_name(source_dir, tmp_path):
    bad = tmp_path / "nope.csv"
    bad.write_text("a,b\n1,2\n")
    result = subprocess.run([sys.executable, "-m", "hapfluid.latency_report", str(bad)],
                            capture_output=True, text=True)
    assert result.returncode != 0 and "nope.csv: not a haptic-rt trace" in result.stderr


@pytest.mark.skipif(not shutil.which("cyclictest"), reason="cyclictest (rt-tests) not installed")
@pytest.mark.slow
def test_side_by_side_run_with_cyclictest(source_dir, build_dir, tmp_path):
    trace = tmp_path / "trace.csv"
    result = subprocess.run([sys.executable, "-m", "hapfluid.latency_report", str(trace),
                             "--with-cyclictest", "--rig", str(source_dir / "tests/rt_core/rigs/bench_two_arms.toml"),
                             "--build", str(build_dir), "--duration", "2", "--json", str(tmp_path / "s.json")],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert "wake latency (µs)" in result.stdout and "cyclictest (µs)" in result.stdout
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["ticks"] > 1500 and summary["cyclictest_us"]["n"] > 1500
    assert (tmp_path / "trace.png").stat().st_size > 1000
    assert len(summary["devices"]) == 2
