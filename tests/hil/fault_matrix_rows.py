"""The rows of the fault matrix (test_fault_matrix.py judges them): for each fault of the live
stack, how it is injected at an instant the test knows on the trace's clock (CLOCK_MONOTONIC),
the safe state the hand must reach, and the rig keys that bound the time to it.

The sim is haptic-sim-standin (a steady 2 N, no physics: the loop cannot tell it from haptic-sim,
and its load is known exactly); test_fault_injection.py kills and stalls the real haptic-sim. The
device is haptic-fake-device, whose injected faults begin at SIGUSR1 (--inject-on-signal); a
second node on its loopback bus is a python-can peer (hapfluid.proto)."""
import csv
import io
import json
import os
import signal
import time
from dataclasses import dataclass
from typing import Callable

import can
import numpy as np

from hil_stack import (FAULT_COMMUNICATION_CONSTRAINTS, FAULT_DEVICE_NOT_LISTENING, FAULT_DEVICE_REPORTED, FAULT_ESTOP,
                       FAULT_FOREIGN_COMMAND, FAULT_LINK_LATENCY, FAULT_LINK_TIMEOUT, FAULT_SIM_STALE, FLAG_FORCE_NORM_LIMITED, FLAG_HARD_ZERO,
                       FLAG_NONFINITE_INPUT, FLAG_SIM_STALE_RAMP, FLAG_TORQUE_NORM_LIMITED, LINK_FAULTS, Stack,
                       TraceFollower, engaged, force, read_csv)
from hapfluid.c_constants import DeviceFault
from hapfluid.launcher import load_toml
from hapfluid.proto import can_encode
from hapfluid.proto.pycan_loopback import LoopbackBus

LOAD = "0,0,2"  # the stand-in's wrench (N): steady, so the hand engages through engage_hold_ms
LOAD_N = 2.0
SIM_RATE_HZ = 200
SIM_NICE = -5  # the sim's, as its systemd unit (Nice=-5)
# The foreign commander: for this many ms, a few COMMANDs a ms for our node, 20 N along x,
# enabled, their sequence this far ahead of the host's: the device takes them and drops the host's
# as late until its watchdog lets the host back in. Ahead by less than half the 8-bit modulus
# all along (64 + 2 x 20 < 128: ours run 3 a ms, the host's 1), else the host's count as newer.
# (A classic CAN COMMAND is two frames, and the device keeps one set at a time: a set interleaved
# with the host's is lost, with the host's. Several back to back get through.)
FOREIGN_MS = 20
FOREIGN_PER_MS = 3
FOREIGN_AHEAD = 64
FOREIGN_FORCE_N = (20.0, 0.0, 0.0)
# Invalid COMMAND sets a bus peer sends at once: twice the fake firmware's burst (10 in 100 ms,
# fake_firmware.hpp DeviceModel) that latches bad_commands.
BAD_COMMAND_SETS = 20
HF_FAULT_BAD_COMMANDS = DeviceFault.BAD_COMMANDS
DROP_PROBABILITY = 0.8  # of the device's STATEs: gaps beyond link_timeout_ms come every few ms
# Every device message, from the injection on: five times link_timeout_ms. The link timeout sees
# the gap the delay opens only at a tick inside it (a loop woken late through most of a gap just
# twice the timeout misses it); the late stream that follows is the command round trip's to see
# (docs/fault-matrix.md).
DELAY_MS = 25


@dataclass(frozen=True)
class Bound:
    text: str                          # the rig keys, as docs/fault-matrix.md prints them
    seconds: Callable[[dict], float]   # from the running rig's device table


def keys_ms(*keys):
    return Bound(" + ".join(keys), lambda d: sum(d[k] for k in keys) * 1e-3)


AT_ONCE = Bound("at once (the tick that sees it)", lambda d: 0.0)
# A non-finite command is replaced by zero, which the rate limit then approaches: at most the
# norm limit's way down at max_force_rate_n_per_s.
RATE_DOWN = Bound("max_force_n / max_force_rate_n_per_s", lambda d: d["max_force_n"] / d["max_force_rate_n_per_s"])


class Run:
    """One row's stack, its rig's device table, and what the injection recorded."""

    def __init__(self, stack: Stack):
        self.stack = stack
        rig = load_toml(stack.rig)
        self.device = rig["devices"][0]
        self.period_s = rig["rt"]["period_ns"] * 1e-9
        self.triggered_ns = None  # when the test injected the fault (CLOCK_MONOTONIC)
        self.device_cut_ns = None  # the last command the device obeyed before its own watchdog took over
        self.device_enabled_at_cut = True  # that command enabled the motors
        self.ended = set()  # processes the row killed or expects to die
        self.operator_resets = []  # wait_engaged's, before the injection

    def log_line(self, name, text):
        """The first line of `name`'s log containing `text`, once it is there."""
        found = []

        def there():
            found[:] = [line for line in self.stack.log(name).splitlines() if text in line]
            return bool(found)
        self.stack.wait_until(f"{name} said {text!r}", there, timeout_s=10)
        return found[0]


@dataclass(frozen=True)
class Fault:
    name: str
    injection: str                     # what the test does
    safe_state: str                    # what the hand gets
    inject: Callable[[Run], int] = None  # injects it, returns the instant (CLOCK_MONOTONIC ns)
    bound: Bound | None = None         # injection -> safe state
    fault_bits: int = 0                # the safe state carries one of these safety::Fault bits ...
    flags: int = 0                     # ... and all of these safety::Flag bits
    zero: bool = True                  # zero wrench; False: within the limits, norm-limited
    detect: Bound | None = None        # injection -> fault bit, where a ramp leads to the zero
    device_zero: str = "host"          # host: its zero reaches the device; watchdog: the device's own
                                       # watchdog; device: the device's own rule, at once
    holds: str = "end"                 # end: to the end of the run; clears: until the fault clears
    recover: Callable[[Run], None] | None = None
    instant: Callable[[Run, int], int] | None = None  # the fault's start from the logs, if not the trigger
    check: Callable[[Run], dict] | None = None  # what else this row must show, after the run
    watchdog_needs_enable: bool = False  # the device's watchdog, the row's detection, runs only while enabled
    device_args: tuple = ()
    standin_args: tuple = ()
    kind: str = "live"                 # live | start-up | config | host
    config: tuple = ()                 # kind config: (key of the line replaced, key written, its value)


def read_device_log(path):
    """A fake device's CSV; one that was SIGKILLed lost its buffered tail, perhaps mid-line."""
    text = path.read_text()
    return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(io.StringIO(text[:text.rfind("\n") + 1]))]


# ---- injections ------------------------------------------------------------------------------
def kill_sim(run):
    at = time.monotonic_ns()
    run.stack.kill("standin")
    run.ended.add("standin")
    return at


def stop_sim(run):
    at = time.monotonic_ns()
    run.stack.procs["standin"].send_signal(signal.SIGSTOP)
    return at


def resume_sim(run):
    resumed = time.monotonic_ns()
    run.stack.procs["standin"].send_signal(signal.SIGCONT)
    wait_trace(run, "the stale fault cleared after SIGCONT", lambda r: r["sim_publish_ns"] > resumed
               and not int(r["d0_faults"]) & FAULT_SIM_STALE)


def switch_sim(run):
    """The stand-in's --on-signal pattern from its next sample: that sample's publish_ns."""
    run.stack.procs["standin"].send_signal(signal.SIGUSR1)
    return int(run.log_line("standin", "SIGUSR1: publishing").rsplit(" ", 1)[1])


def corrupt_sim_segment(run):
    # What a broken or hostile writer of the same user can do: rewrite the live segment's header
    # (magic, ABI, layout) under the loop, which validated it at attach.
    with open(f"/dev/shm/{run.stack.prefix}.sim_samples", "r+b") as f:
        at = time.monotonic_ns()
        f.write(b"\xff" * 64)
    return at


def shrink_sim_segment(run):
    # ... or truncate the object under the reader's mapping (a read past its end is SIGBUS).
    at = time.monotonic_ns()
    os.truncate(f"/dev/shm/{run.stack.prefix}.sim_samples", 0)
    run.ended.add("standin")  # the writer's own next store into it is a SIGBUS
    return at


def rt_says_corrupt(run):
    log = run.stack.log("rt")
    assert "sim_samples: corrupt" in log, log[-1500:]
    said = [line for line in log.splitlines() if "sim_samples" in line]
    assert len(said) == len(set(said)), f"the corrupt segment is said again and again: {said[-4:]}"
    return {}


def device_signal(run):
    """The fake device's injected faults from its next tick: that tick's due time (tick_ns)."""
    run.stack.procs["fake-hand"].send_signal(signal.SIGUSR1)
    return int(run.log_line("fake-hand", "fault injection begins").split("tick_ns ")[1].split()[0])


def injecting_tick_ran(run, triggered_ns):
    """When the device's first faulty tick ran (rx_ns; the emulator may run a tick late, a real
    MCU does not): every message of the ticks before it had left by then."""
    log = read_device_log(run.stack.dir / "fake-hand.csv")
    at = int(next(r["rx_ns"] for r in log if r["tick_ns"] == triggered_ns))
    run.device_cut_ns = at  # its commands stop there (stops reading, bus-off)
    run.device_enabled_at_cut = bool(int([r for r in log if r["tick_ns"] < triggered_ns][-1]["cmd_flags"]) & 1)
    return at


def reboot_device(run):
    # A power cycle: gone without a word, back at once with fresh counters (its STATE sequence
    # restarts at 0, its motors off until the host enables them).
    at = time.monotonic_ns()
    run.stack.kill("fake-hand")
    run.ended.add("fake-hand")
    run.stack.fake_device("hand", motion="hold", name="fake-hand2")
    return at


class BusPeer:
    """Another node on the device's loopback bus (what any local user can open on a CAN bus): it
    hears every frame for our node but its own, and sends its own. It stays on the bus until it
    has heard the device act on what it sent: the bus drops a peer that left, and the frames it
    had not read from it yet, when it next sends to it."""
    # classic CAN functions (firmware_bridge/protocol.md 4.1); byte 0 of every frame is seq8
    CMD_FORCE, FAULT, STATE_POS = 0x3, 0x2, 0x5

    def __init__(self, run):
        self.node = run.device["transport"]["can_node_id"]
        self.bus = LoopbackBus(channel=run.stack.sockets[0], fd=False)

    def hear(self, what, function, predicate=lambda data: True, timeout_s=5.0):
        """The data of the next frame of `function` for our node that satisfies predicate."""
        can_id, deadline = (function << 4) | self.node, time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            heard = self.bus.recv(timeout=0.1)
            if heard is not None and heard.arbitration_id == can_id and predicate(heard.data):
                return heard.data
        raise AssertionError(f"never heard {what} on the bus")

    def command(self, seq, force_n, flags, bad_crc=False):
        """The frames of one COMMAND for our node, encoded ahead: the device keeps one set at a
        time, and a set the host's frames fall into is lost, so a set must go out in one piece."""
        message = {"type": "COMMAND", "seq": seq & 0xFF,
                   "fields": {"force_n": list(force_n), "torque_nm": [0.0, 0.0, 0.0], "flags": flags}}
        frames = can_encode(message, self.node)
        if bad_crc:  # the CRC-8 of the set ends its last frame
            can_id, data = frames[-1]
            frames[-1] = (can_id, data[:-1] + bytes([data[-1] ^ 0xFF]))
        return [can.Message(arbitration_id=can_id, data=data, is_extended_id=False) for can_id, data in frames]

    def send(self, frames):
        for frame in frames:
            self.bus.send(frame)

    def close(self):
        self.bus.shutdown()


def foreign_commands(run):
    """A second process on the bus commands our node, its sequence ahead of the host's."""
    peer = BusPeer(run)
    try:
        seq = peer.hear("a command of the host", BusPeer.CMD_FORCE)[0] + FOREIGN_AHEAD
        ours = [(seq + i) & 0xFF for i in range(FOREIGN_MS * FOREIGN_PER_MS)]
        bursts = [[frame for i in ours[k:k + FOREIGN_PER_MS] for frame in peer.command(i, FOREIGN_FORCE_N, flags=1)]
                  for k in range(0, len(ours), FOREIGN_PER_MS)]
        at = time.monotonic_ns()
        for burst in bursts:
            peer.send(burst)
            time.sleep(0.001)  # (pacing a stimulus, as a sender on a bus would)
        run.device_cut_ns = time.monotonic_ns()
        # the STATE's command echo (byte 7 of STATE_POS): the device applied ours, then the host's again
        peer.hear("the device applying a foreign command", BusPeer.STATE_POS, lambda data: data[7] in ours)
        peer.hear("the device back on the host's commands", BusPeer.STATE_POS, lambda data: data[7] not in ours)
    finally:
        peer.close()
    return at


def bad_command_frames(run):
    """A failing transceiver, or a broken gateway: COMMAND sets for our node that fail their CRC."""
    peer = BusPeer(run)
    try:
        seq = peer.hear("a command of the host", BusPeer.CMD_FORCE)[0] + FOREIGN_AHEAD
        burst = [frame for i in range(BAD_COMMAND_SETS)
                 for frame in peer.command(seq + i, (1.0, 0.0, 0.0), flags=1, bad_crc=True)]
        run.device_cut_ns = time.monotonic_ns()
        peer.send(burst)
        # The fault is a burst: it exists once the burst is on the bus, not at its first frame.
        at = time.monotonic_ns()
        peer.hear("the device's bad_commands fault", BusPeer.FAULT, lambda data: data[1] & HF_FAULT_BAD_COMMANDS)
    finally:
        peer.close()
    return at


def device_latched_bad_commands(run):
    summary = json.loads((run.stack.dir / "fake-hand.json").read_text())
    assert summary["faults"] & HF_FAULT_BAD_COMMANDS and summary["frames_bad"] >= BAD_COMMAND_SETS // 2, summary
    return {"device_frames_bad": summary["frames_bad"]}


def estop(run):
    at = time.monotonic_ns()
    run.stack.procs["rt"].send_signal(signal.SIGUSR1)
    return at


def kill_host(run):
    at = time.monotonic_ns()
    run.stack.kill("rt")
    return at


def last_state_before_a_timeout(run, triggered_ns):
    """Drops: the fault begins with the last STATE that left the device before the first gap the
    link timeout must see (longer than link_timeout_ms plus a tick of each side's phase)."""
    log = [r for r in read_device_log(run.stack.dir / "fake-hand.csv") if r["tick_ns"] >= triggered_ns - 1e6]
    sent = [r["rx_ns"] for r in log if r["state_seq"] >= 0]  # (a tick sends after it took its commands)
    gap_ns = (run.device["link_timeout_ms"] * 1e-3 + 2 * run.period_s) * 1e9
    return int(next(a for a, b in zip(sent, sent[1:]) if b - a > gap_ns))


def link_clears(run):
    wait_trace(run, "the link fault cleared", lambda r: r["scheduled_ns"] > run.triggered_ns + 20e6
               and not int(r["d0_faults"]) & LINK_FAULTS)


def latency_holds(run):
    """Once the delayed stream flows, every state echoes a command DELAY_MS old: the loop says
    link_latency and keeps the hand at zero for as long as the delay lasts (to the run's end)."""
    rows = [r for r in read_csv(run.stack.dir / "rt-trace.csv") if r["scheduled_ns"] >= run.triggered_ns]
    late = [i for i, r in enumerate(rows) if int(r["d0_faults"]) & FAULT_LINK_LATENCY]
    assert late, "the delayed stream never showed as link_latency"
    after = rows[late[0]:]
    assert all(int(r["d0_faults"]) & FAULT_LINK_LATENCY for r in after), "link_latency cleared while the delay lasted"
    assert all(force(r) == 0 for r in after)
    return {"link_latency_ms": round((rows[late[0]]["scheduled_ns"] - run.triggered_ns) * 1e-6, 1)}


def rebooted_device_engages(run):
    link_clears(run)
    wait_engaged(run, device="fake-hand2")


def took_foreign_commands(run):
    """The attack reached the motors (else the row shows nothing), and the device's own limits held."""
    log = read_device_log(run.stack.dir / "fake-hand.csv")
    taken = [r for r in log if r["cmd_fx"] == FOREIGN_FORCE_N[0]]
    assert taken, "the device never took a foreign command"
    return {"device_took_foreign_ticks": len(taken),
            "device_applied_max_n": round(max(np.linalg.norm([r["applied_fx"], r["applied_fy"], r["applied_fz"]])
                                              for r in taken), 3)}


def rebooted_device_taken_up(run):
    """The new device's STATE counter began at 0 and the loop followed it: the state each of its
    last fresh ticks rendered from is one the new device had just sent (classic CAN carries the low
    8 bits of the sequence; the loop stamps all frames of one poll with one clock read, so a state
    may look a tick early), and the new device carried the load again."""
    log = read_device_log(run.stack.dir / "fake-hand2.csv")
    assert log[0]["state_seq"] == 0
    sent = [(r["rx_ns"], int(r["state_seq"])) for r in log if r["state_seq"] >= 0]
    sent_ns = np.array([ns for ns, _ in sent])
    trace = [r for r in read_csv(run.stack.dir / "rt-trace.csv")[-200:] if r["d0_fresh"]]
    for r in trace:
        newest = max(0, int(np.searchsorted(sent_ns, r["d0_state_receive_ns"], side="right")) - 1)
        apart = (sent[newest][1] - int(r["d0_state_seq"]) + 128) % 256 - 128
        assert abs(apart) <= 2, f"the loop rendered state {int(r['d0_state_seq'])}, the new device had sent {sent[newest][1]}"
    carrying = [abs(np.linalg.norm([r["applied_fx"], r["applied_fy"], r["applied_fz"]]) - LOAD_N) < 0.05 for r in log]
    longest = max((len(run_) for run_ in "".join("1" if c else "0" for c in carrying).split("0")), default=0)
    assert longest >= 100, f"the rebooted device carried the load for at most {longest} ticks on end"
    return {"rebooted_states_taken": len(trace)}


# ---- waits  -----------------------------------------------------------------------------------
def wait_trace(run, what, predicate, rt="rt"):
    """Until a row of the loop's trace satisfies predicate (read as the loop writes it)."""
    follower = TraceFollower(run.stack.dir / f"{rt}-trace.csv")
    seen = [0]

    def found():
        rows = follower.poll()
        hit = any(predicate(r) for r in rows[seen[0]:])
        seen[0] = len(rows)
        return hit
    return run.stack.wait_until(what, found, watch=(rt,))


def wait_engaged(run, sim="standin", device="fake-hand", keep_s=0.2):
    """Until the hand has carried the stand-in's load, engaged, for keep_s on end.

    Before any injection, a loaded machine may hold the fake device up for tens of ms a few
    times in a row (seen while other processes started): it then applies only the newest of the
    commands that piled up, the loop counts the rest as lost and latches the communication
    constraint, which only the operator clears. The harness is that operator, once per row
    (SIGUSR2, the reset), and says so; a second latch fails the row."""
    follower = TraceFollower(run.stack.dir / "rt-trace.csv")
    started_ns = run.stack.started_at[sim] * 1e9

    def carrying():
        rows = follower.poll()
        if rows and int(rows[-1]["d0_faults"]) & FAULT_COMMUNICATION_CONSTRAINTS:
            assert not run.operator_resets, "the communication constraint latched again after the operator's reset"
            run.operator_resets.append(rows[-1]["scheduled_ns"])
            run.stack.procs["rt"].send_signal(signal.SIGUSR2)
            return False
        for r in reversed(rows):
            if not (engaged(r) and r["sim_publish_ns"] >= started_ns and abs(force(r) - LOAD_N) < 0.05):
                return False
            if rows[-1]["scheduled_ns"] - r["scheduled_ns"] >= keep_s * 1e9:
                return True
        return False
    return run.stack.wait_until(f"the hand carried the stand-in's {LOAD_N} N, engaged, for {keep_s} s", carrying,
                                watch=("rt", device, sim))


# ---- the matrix ------------------------------------------------------------------------------
SIM_STALE = dict(fault_bits=FAULT_SIM_STALE, flags=FLAG_SIM_STALE_RAMP, detect=keys_ms("sim_stale_ms"),
                 bound=keys_ms("sim_stale_ms", "sim_ramp_down_ms"))
DEVICE = dict(inject=device_signal, instant=injecting_tick_ran)
LINK_TIMEOUT = dict(fault_bits=FAULT_LINK_TIMEOUT, flags=FLAG_HARD_ZERO, bound=keys_ms("link_timeout_ms"), **DEVICE)
CONFIG_ERROR = "exit 2 naming file, line, key and value; no frame on the bus"
MATRIX = [
    Fault("sim_killed", "SIGKILL haptic-sim-standin", "ramp to zero; sim_stale", inject=kill_sim, **SIM_STALE),
    Fault("sim_stalled", "SIGSTOP haptic-sim-standin (SIGCONT after the hold)", "ramp to zero; sim_stale",
          inject=stop_sim, holds="clears", recover=resume_sim, **SIM_STALE),
    Fault("sim_segment_corrupted", "overwrite the live sim_samples header (64 bytes of 0xff) in /dev/shm",
          "ramp to zero; sim_stale (nothing is read from a corrupt segment)", inject=corrupt_sim_segment,
          check=rt_says_corrupt, **SIM_STALE),
    Fault("sim_segment_shrunk", "truncate the live sim_samples object to 0 bytes in /dev/shm",
          "ramp to zero; sim_stale (the reader's SIGBUS guard marks it corrupt)", inject=shrink_sim_segment,
          check=rt_says_corrupt, **SIM_STALE),
    Fault("sim_nan", "the stand-in publishes NaN forces (--on-signal nan)", "zero; nonfinite_input",
          inject=switch_sim, bound=RATE_DOWN, flags=FLAG_NONFINITE_INPUT, standin_args=("--on-signal", "nan")),
    Fault("sim_huge", "the stand-in publishes 1e12 N and -1e9 N m (--on-signal huge)",
          "within max_force_n and max_torque_nm; force and torque norm-limited", inject=switch_sim, bound=AT_ONCE,
          zero=False, flags=FLAG_FORCE_NORM_LIMITED | FLAG_TORQUE_NORM_LIMITED, standin_args=("--on-signal", "huge")),
    Fault("sim_segment_squatted", "uid 65534 holds /<prefix>.sim_samples (a live writer's, 5 N along x) before "
          "the rig starts", "the rig comes up on its own segment; the squatter's wrench never reaches the hand",
          kind="start-up"),
    Fault("device_silent", "the fake device stops sending (--silent-after 0)", "zero; link_timeout",
          device_args=("--silent-after", "0"), **LINK_TIMEOUT),
    Fault("device_stops_reading", "the fake device stops reading commands (--stop-answering-after 0)",
          "device: motors off by its watchdog; host: zero, device_not_listening or device_reported", **DEVICE,
          bound=keys_ms("device_watchdog_ms"), fault_bits=FAULT_DEVICE_REPORTED | FAULT_DEVICE_NOT_LISTENING,
          flags=FLAG_HARD_ZERO,
          device_zero="watchdog", watchdog_needs_enable=True, device_args=("--stop-answering-after", "0")),
    Fault("device_crc_corrupt", "every STATE's CRC corrupted (--corrupt-every 1)", "zero; link_timeout",
          device_args=("--corrupt-every", "1"), **LINK_TIMEOUT),
    Fault("device_frame_drops", f"{DROP_PROBABILITY:.0%} of STATEs dropped (--drop-probability {DROP_PROBABILITY})",
          "zero; link_timeout", device_args=("--drop-probability", str(DROP_PROBABILITY)),
          **{**LINK_TIMEOUT, "instant": last_state_before_a_timeout}),
    Fault("device_frame_delay", f"every device message delayed {DELAY_MS} ms (--delay-ms {DELAY_MS})",
          "zero; link_timeout at the gap, then link_latency for as long as the delay lasts",
          device_args=("--delay-ms", str(DELAY_MS)), check=latency_holds,
          **{**LINK_TIMEOUT, "fault_bits": FAULT_LINK_TIMEOUT | FAULT_LINK_LATENCY}),
    Fault("device_bus_off", "a CAN bus-off error frame, then 200 ms silent both ways (--bus-off-at 0)",
          "host: zero, device_reported; device: motors off by its watchdog", **DEVICE, bound=AT_ONCE,
          fault_bits=FAULT_DEVICE_REPORTED, flags=FLAG_HARD_ZERO, device_zero="watchdog", holds="clears",
          recover=link_clears, device_args=("--bus-off-at", "0", "--bus-off-ms", "200")),
    Fault("device_reboot", "SIGKILL the fake device and start a new one at once (its counters restart at 0)",
          "zero; link fault, until the rebooted device is taken up", inject=reboot_device,
          bound=keys_ms("link_timeout_ms"), fault_bits=LINK_FAULTS, flags=FLAG_HARD_ZERO, holds="clears",
          recover=rebooted_device_engages, check=rebooted_device_taken_up),
    Fault("foreign_commander", f"a second peer on the bus commands our node for {FOREIGN_MS} ms: 20 N, enabled, "
          "sequence ahead of the host's", "host: zero, enable off, foreign_command latched; device: its own limits, "
          "then motors off", inject=foreign_commands, bound=AT_ONCE, fault_bits=FAULT_FOREIGN_COMMAND,
          flags=FLAG_HARD_ZERO, device_zero="watchdog", check=took_foreign_commands),
    Fault("bad_command_frames", f"a bus peer sends {BAD_COMMAND_SETS} COMMAND sets for our node with a bad CRC-8",
          "device: bad_commands latched, motors off; host: zero, device_reported (latched)",
          inject=bad_command_frames, bound=AT_ONCE, fault_bits=FAULT_DEVICE_REPORTED, flags=FLAG_HARD_ZERO,
          device_zero="device", check=device_latched_bad_commands),
    Fault("estop", "SIGUSR1 to haptic-rt (the operator's e-stop)", "zero; estop latched", inject=estop,
          bound=AT_ONCE, fault_bits=FAULT_ESTOP, flags=FLAG_HARD_ZERO),
    Fault("host_killed", "SIGKILL haptic-rt", "device: motors off by its watchdog", inject=kill_host,
          bound=keys_ms("device_watchdog_ms"), kind="host"),
    Fault("config_negative_limit", "haptic-rt on a rig with max_force_n = -8.0", CONFIG_ERROR, kind="config",
          config=("max_force_n", "max_force_n", "-8.0")),
    Fault("config_nan_limit", "haptic-rt on a rig with max_torque_nm = nan", CONFIG_ERROR, kind="config",
          config=("max_torque_nm", "max_torque_nm", "nan")),
    Fault("config_misspelt_watchdog", "haptic-rt on a rig with sim_stale_msx = 50.0 (a typo)", CONFIG_ERROR,
          kind="config", config=("sim_stale_ms", "sim_stale_msx", "50.0")),
]
