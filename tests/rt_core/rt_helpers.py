"""Helpers for the rt_core process tests: unique shm prefixes, running haptic-rt and the stand-in
sim, and reading trace CSVs (rt_core/include/hapfluid/rt/trace_csv.hpp)."""
import csv
import os
import pathlib
import subprocess
import time

from hapfluid.c_constants import Fault, Flag, LoopFlag

RIGS = pathlib.Path(__file__).resolve().parent / "rigs"

# The headers' bits, generated from them at build time.
LOOP_NO_FIFO = LoopFlag.no_fifo
LOOP_NO_MLOCK = LoopFlag.no_mlock
FLAG_NONFINITE = Flag.nonfinite_input
FAULT_ESTOP = Fault.estop
FAULT_LINK_TIMEOUT = Fault.link_timeout
FAULT_SIM_STALE = Fault.sim_stale


def unique_prefix(tag: str) -> str:
    return f"hapfluid-pytest-{tag}-{os.getpid()}-{time.monotonic_ns() % 1000000}"


def read_trace(path) -> list[dict]:
    with open(path, newline="") as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def force(row: dict, device: int = 0) -> tuple[float, float, float]:
    return (row[f"d{device}_fx"], row[f"d{device}_fy"], row[f"d{device}_fz"])


def norm(v) -> float:
    return sum(c * c for c in v) ** 0.5


def start_rt(binary, rig, prefix, tmp_path, duration_s, extra=(), env=None, trace=True):
    args = [str(binary("haptic-rt")), "--rig", str(rig), "--simulated-devices", "--shm-prefix", prefix,
            "--duration", str(duration_s), "--flight-dir", str(tmp_path / "flight")]
    if trace:
        args += ["--trace", str(tmp_path / "trace.csv")]
    return subprocess.Popen(args + list(extra), stderr=subprocess.PIPE, text=True, env=env)


def start_sim(binary, prefix, *args):
    return subprocess.Popen([str(binary("haptic-sim-standin")), "--shm-prefix", prefix, *args],
                            stderr=subprocess.DEVNULL)


def leftover_segments(prefix) -> list[str]:
    return [name for name in os.listdir("/dev/shm") if name.startswith(prefix)]
