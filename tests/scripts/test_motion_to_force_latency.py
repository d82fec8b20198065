"""The motion-to-force chain is followed exactly through the three logs: a synthetic stack with known
clock stamps (fake device at 1 kHz with its own phase, loop at 1 kHz, sim every 3 ms) gives back
every point of every chain, across 8-bit sequence wraps, and leaves out what it cannot follow:
samples rendered while the device was waiting to engage, and ticks the trace lost."""
import csv
import json
import subprocess
import sys

import numpy as np
import pytest

from hapfluid.c_constants import Flag

T0 = 10_000_000_000  # ns, CLOCK_MONOTONIC
MS = 1_000_000
DEVICE_PHASE, LOOP_PHASE = 300_000, 250_000
TRANSIT = 60_000                # a frame's trip over the loopback bus
WAITING_TO_ENGAGE = Flag.waiting_to_engage
TICKS = 700                     # > 2 x 256: every sequence number wraps
WAITING = range(100, 150)       # loop ticks held at the engage gate
LOST = range(300, 303)          # loop ticks the trace lost


def synthetic_stack():
    """Device log rows, trace rows, sim log rows and the expected chains (a, b, c, e, f)."""
    device_ticks = [T0 + k * MS + DEVICE_PHASE for k in range(TICKS + 5)]
    loop_wake = [T0 + j * MS + LOOP_PHASE + 7_000 * (j % 3) for j in range(1, TICKS + 1)]  # tick j at [j-1]
    trace, samples = [], []
    state_seq, receive_ns = 0, 0
    sample = None  # (device_tick, publish_ns)
    next_sim_read = T0 + 5 * MS + 100_000
    published_ticks = []  # (tick, time its device_states became visible)
    for j, wake in enumerate(loop_wake, start=1):
        # poll: the newest STATE that has crossed the bus by now (16-bit device counter, 8 bits on the wire)
        newest = max(k for k, t in enumerate(device_ticks) if t + TRANSIT <= wake)
        fresh = newest != state_seq or j == 1
        if fresh:
            state_seq, receive_ns = newest, wake + 4_000
        read_ns = wake + 12_000
        while next_sim_read < read_ns:  # the sim: read the newest device_states, step 1.5 ms, publish
            if published_ticks:
                tick = max(t for t, at in published_ticks if at <= next_sim_read)
                samples.append((tick, next_sim_read + 1_500_000))
            next_sim_read += 3 * MS
        visible = [s for s in samples if s[1] < read_ns]
        sample = visible[-1] if visible else None
        send_ns = wake + 20_000
        trace.append({"tick": j, "wake_ns": wake, "io_ns": 15_000, "sim_device_tick": sample[0] if sample else 0,
                      "sim_publish_ns": sample[1] if sample else 0, "send_ns": send_ns,
                      "d0_flags": WAITING_TO_ENGAGE if j in WAITING else 0, "d0_faults": 0,
                      "d0_state_seq": state_seq % 256, "d0_state_receive_ns": receive_ns, "d0_cmd_seq": j % 65536})
        published_ticks.append((j, wake + 30_000))
    # the device: drains at tick + 15 us what the loop sent at least TRANSIT before
    device, taken = [], -1
    for k, t in enumerate(device_ticks):
        drained = t + 15_000
        arrived = [r["d0_cmd_seq"] for r in trace if r["send_ns"] + TRANSIT <= drained]
        got = bool(arrived) and arrived[-1] != taken
        taken = arrived[-1] if arrived else taken
        device.append({"t_s": (t - T0) * 1e-9, "cmd_received": int(got), "cmd_seq": max(taken, 0) % 256, "px": 0.0,
                       "applied_fx": 0.0, "tick_ns": t, "rx_ns": drained, "state_seq": k % 65536})
    # expected chains: the first tick rendering each sample on an engaged device, tick T in the trace
    by_tick = {r["tick"]: r for r in trace}
    expected = []
    for prev, r in zip(trace, trace[1:]):
        if r["sim_publish_ns"] == prev["sim_publish_ns"] or r["tick"] in WAITING or r["sim_device_tick"] == 0:
            continue
        if r["tick"] in LOST or r["tick"] - 1 in LOST or r["sim_device_tick"] in LOST:
            continue
        t = by_tick[r["sim_device_tick"]]
        b = t["d0_state_receive_ns"]
        k = max(k for k, d in enumerate(device_ticks) if d + TRANSIT <= b - 4_000)
        f = next(d["rx_ns"] for d in device if d["rx_ns"] >= r["send_ns"] + TRANSIT)
        expected.append((device_ticks[k], b, r["sim_publish_ns"], r["send_ns"], f))
    trace = [r for r in trace if r["tick"] not in LOST]
    return device, trace, samples, expected


def write(path, rows):
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


@pytest.fixture(scope="module")
def script():
    from hapfluid import motion_to_force_latency
    return motion_to_force_latency


def test_every_chain_is_followed_to_the_exact_stamps_across_sequence_wraps(script, tmp_path):
    device, trace, samples, expected = synthetic_stack()
    write(tmp_path / "device.csv", device)
    write(tmp_path / "trace.csv", trace)
    write(tmp_path / "couplings.csv", [{"device_tick": t, "publish_ns": p} for t, p in samples])
    ch = script.chains(script.load_trace(tmp_path / "trace.csv", 0), script.load_device_log(tmp_path / "device.csv"),
                       0, script.sim_samples(tmp_path / "couplings.csv"))
    got = list(zip(*(ch[k].tolist() for k in "abcef")))
    assert len(expected) > 150, "the synthetic sim renders a sample every 3 ms"
    assert got == expected
    assert ch["confirmed"].all(), "every rendered sample is in the sim's own log"
    p = script.pieces_ms(ch)
    # device -> loop: the frame's trip plus the wait for the loop's tick (the two phases differ by 0.95 ms);
    # loop -> sim: up to one 3 ms sim period plus the 1.5 ms step; sim -> loop: < 1 tick + render;
    # loop -> device: the trip plus the wait for the device's drain.
    assert np.all(p["device_to_loop"] >= TRANSIT * 1e-6) and np.all(p["device_to_loop"] < 2.1)
    assert np.all(p["loop_to_sim"] >= 1.5) and np.all(p["loop_to_sim"] < 1.5 + 3 + 1.1)
    assert np.all(p["sim_to_loop"] >= 0) and np.all(p["sim_to_loop"] < 1.1)
    assert np.all(p["loop_to_device"] >= TRANSIT * 1e-6) and np.all(p["loop_to_device"] < 1.1)


def test_a_sample_missing_from_the_sim_log_is_not_confirmed(script, tmp_path):
    device, trace, samples, _ = synthetic_stack()
    write(tmp_path / "device.csv", device)
    write(tmp_path / "trace.csv", trace)
    write(tmp_path / "couplings.csv", [{"device_tick": t, "publish_ns": p + 1} for t, p in samples])
    ch = script.chains(script.load_trace(tmp_path / "trace.csv", 0), script.load_device_log(tmp_path / "device.csv"),
                       0, script.sim_samples(tmp_path / "couplings.csv"))
    assert len(ch["a"]) and not ch["confirmed"].any()


def test_the_command_line_writes_json_and_png_whose_pieces_add_up(source_dir, tmp_path):
    device, trace, samples, expected = synthetic_stack()
    write(tmp_path / "device.csv", device)
    write(tmp_path / "trace.csv", trace)
    write(tmp_path / "couplings.csv", [{"device_tick": t, "publish_ns": p} for t, p in samples])
    result = subprocess.run([sys.executable, "-m", "hapfluid.motion_to_force_latency", "--trace",
                             tmp_path / "trace.csv", "--device-log", tmp_path / "device.csv", "--couplings",
                             tmp_path / "couplings.csv", "--out", tmp_path / "out"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    report = json.loads((tmp_path / "out" / "motion_to_force.json").read_text())
    assert report["samples"] == len(expected) == report["confirmed_by_sim_log"]
    assert report["negative_pieces"] == 0 and report["sum_error_ms"] < 1e-9
    totals = [(f - a) * 1e-6 for a, _, _, _, f in expected]
    assert report["total_ms"]["max"] == round(max(totals), 3)
    assert report["total_ms"]["p50"] == round(float(np.percentile(totals, 50)), 3)
    assert set(report["pieces_ms"]) == {"device_to_loop", "loop_to_sim", "sim_to_loop", "loop_to_device"}
    assert (tmp_path / "out" / "motion_to_force.png").stat().st_size > 10_000


def test_logs_from_an_older_build_are_refused_naming_the_column(source_dir, tmp_path):
    device, trace, samples, _ = synthetic_stack()
    write(tmp_path / "device.csv", [{k: v for k, v in r.items() if k != "rx_ns"} for r in device])
    write(tmp_path / "trace.csv", trace)
    result = subprocess.run([sys.executable, "-m", "hapfluid.motion_to_force_latency", "--trace",
                             tmp_path / "trace.csv", "--device-log", tmp_path / "device.csv", "--out", tmp_path / "out"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode != 0 and "rx_ns" in result.stderr and "older build" in result.stderr
