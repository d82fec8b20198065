"""Hardware-in-the-loop harness: the real binaries (haptic-fake-device, haptic-rt, haptic-sim --live,
haptic-render, haptic-sim-standin) as separate processes over the loopback transport.

Every stack gets a private copy of a shipped rig (own loopback socket paths, own shm prefix) so
tests never collide with each other, with `make run` or with installed services. Processes are
tracked by the Popen objects the harness started and stopped by pid, never by name.

Start order, as `make run` and the systemd target: devices, then haptic-rt (it engages its
devices at zero wrench), then the simulator, whose wrench then fades in. A loop started under a
sim already pushing more than the rig's engage_threshold_n waits for the wrench to drop below it
or to hold steady for engage_hold_ms. Every other order works too (test_start_order.py): haptic-rt
holds a device that is not there yet at a link fault, the sim plays its scene's scripted hands
until the loop's device states appear, the renderer waits for the sim.

Tests wait for what the parts do (Stack.wait_until and the waits built on it: a simulated time,
the hand rendering the sim's wrench, read from the sim's status lines and the loop's trace as they
are written), not for fixed times tuned to one machine: CI machines run the sim at a third of this
VM's speed and lavapipe at a tenth, and delay the fake device now and then."""
import csv
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import numpy as np

from hapfluid.c_constants import Fault, Flag
from hapfluid.launcher import cpu_placement, device_scene, load_toml, private_rig_text  # shared with the launcher

ROOT = pathlib.Path(__file__).resolve().parents[2]

LEAD_IN_S = 1.5  # scripted hands hold still this long (the loop engages, the fluid settles)
SCENES = ROOT / "config" / "scenes"
RIGS = ROOT / "config" / "rigs"
# The stack tests' own scenes (their stirring workload, light enough for one sim thread).
HIL_SCENES = pathlib.Path(__file__).resolve().parent / "scenes"
STIR = "stirring_light"


def scene_file(scene) -> pathlib.Path:
    """A scene by path, or by name: the stack tests' own (tests/hil/scenes), else a shipped one."""
    if isinstance(scene, pathlib.Path):
        return scene
    own = HIL_SCENES / f"{scene}.toml"
    return own if own.exists() else SCENES / f"{scene}.toml"

# safety::Fault and Flag bits, generated from rt_core/include/hapfluid/safety/flags.hpp at build time
FAULT_ESTOP = Fault.estop
FAULT_LINK_TIMEOUT = Fault.link_timeout
FAULT_LINK_INVALID = Fault.link_invalid
FAULT_DEVICE_REPORTED = Fault.device_reported
FAULT_SIM_STALE = Fault.sim_stale
FAULT_FOREIGN_COMMAND = Fault.foreign_command
FAULT_COMMUNICATION_CONSTRAINTS = Fault.communication_constraints
FAULT_DEVICE_NOT_LISTENING = Fault.device_not_listening
FAULT_LINK_LATENCY = Fault.link_latency
LINK_FAULTS = (FAULT_LINK_TIMEOUT | FAULT_LINK_INVALID | FAULT_DEVICE_REPORTED | FAULT_DEVICE_NOT_LISTENING
               | FAULT_LINK_LATENCY)
FLAG_NONFINITE_INPUT = Flag.nonfinite_input
FLAG_FORCE_NORM_LIMITED = Flag.force_norm_limited
FLAG_TORQUE_NORM_LIMITED = Flag.torque_norm_limited
FLAG_WAITING_TO_ENGAGE = Flag.waiting_to_engage
FLAG_ENGAGING = Flag.engaging
FLAG_SIM_STALE_RAMP = Flag.sim_stale_ramp
FLAG_HARD_ZERO = Flag.hard_zero
# A loop recovering from a fault: zero until the load is small or steady, then a ramp; a sim
# back before its stale ramp-down ended fades in instead.
RECOVERY_FLAGS = FLAG_WAITING_TO_ENGAGE | FLAG_ENGAGING | FLAG_SIM_STALE_RAMP
# "The hand keeps the sim's wrench": this long without a lapse ...
KEEP_S = 1.5
# ... unless the fake device faulted the link before that by waking late (held_up): a device's MCU
# never misses its tick, the emulator shares a loaded VM's CPUs. A hand dropped so under a load
# kicks the sim's spoon, which may then swing too much for the engage gate for a long while (the
# rule); the waits give that recovery this long before the run is judged without it.
EMULATOR_RECOVERY_WAIT_S = 3.0
EMULATOR_LATE_MS = 4.0  # the fake device this late before a link fault (link_timeout_ms 5) caused it
# Waits for what a part does (a sim reaching a simulated time, the hand getting the sim's wrench)
# end here and fail, naming what never happened. The dev VM needs a few seconds; a machine three
# times slower (lavapipe ten times) still passes, a stack that never gets there fails in bounded time.
WAIT_TIMEOUT_S = 40.0
SIM_STATUS_EVERY_S = 0.2  # the sim's status lines (simulated time, samples) the waits read


def _placed(nice, cpus):
    """A child's set-up before exec: its nice value and CPUs (empty: inherited)."""
    def preexec():
        if nice:
            try:
                os.nice(nice)
            except PermissionError:
                pass
        if cpus:
            os.sched_setaffinity(0, cpus)
    return preexec


def _fifo_prefix() -> list[str]:
    try:
        ok = subprocess.run(["chrt", "-f", "70", "true"], capture_output=True).returncode == 0
    except FileNotFoundError:
        ok = False
    return ["chrt", "-f", "70"] if ok else []


FIFO = _fifo_prefix()


def read_csv(path) -> list[dict]:
    with open(path, newline="") as f:
        return [{k: (float(v) if k not in ("device", "body") else v) for k, v in row.items()} for row in csv.DictReader(f)]


def norm3(row, prefix) -> float:
    return (row[prefix + "x"] ** 2 + row[prefix + "y"] ** 2 + row[prefix + "z"] ** 2) ** 0.5


def force(row, d=0) -> float:
    """|F| of device d's command in a trace row (N)."""
    return (row[f"d{d}_fx"] ** 2 + row[f"d{d}_fy"] ** 2 + row[f"d{d}_fz"] ** 2) ** 0.5


def trace_time_s(trace):
    t0 = trace[0]["scheduled_ns"]
    return np.array([(r["scheduled_ns"] - t0) * 1e-9 for r in trace])


def wall_to_trace_s(trace, monotonic_s):
    """A time.monotonic() instant (CLOCK_MONOTONIC, as the trace's scheduled_ns) on the trace's axis."""
    return monotonic_s - trace[0]["scheduled_ns"] * 1e-9


def engaged(row, d=0) -> bool:
    """Device d rendered its full wrench this tick: no fault, not held at or ramping through the engage gate."""
    return not int(row[f"d{d}_faults"]) and not int(row[f"d{d}_flags"]) & (FLAG_WAITING_TO_ENGAGE | FLAG_ENGAGING)


def sim_samples_in_use(trace, sim_dir):
    """Per trace row, (force (N), simulated time (s)) of the sim sample the loop rendered in that
    tick, from that sim's own log (<sim_dir>/couplings.csv, one coupling: the scene's hand), or
    None when the sample is another sim's, or none."""
    by_publish = {int(r["publish_ns"]): (np.array([r["fx"], r["fy"], r["fz"]]), r["t"])
                  for r in read_csv(sim_dir / "couplings.csv")}
    return [by_publish.get(int(r["sim_publish_ns"])) for r in trace]


def runs(flags):
    """(first, last) index of each run of True in flags."""
    out, first = [], None
    for i, flag in enumerate(flags):
        if flag and first is None:
            first = i
        elif not flag and first is not None:
            out.append((first, i - 1))
            first = None
    if first is not None:
        out.append((first, len(flags) - 1))
    return out


def held_up(device_log, min_late_ms=2.0):
    """[start_ns, end_ns] of each stretch in which the fake device was held up min_late_ms or more
    (its tick due at tick_ns ran at rx_ns): another process at a real-time priority, so a stall
    it shares with the loop is the machine's."""
    merged = []
    for a, b in ((r["tick_ns"], r["rx_ns"]) for r in device_log if r["rx_ns"] - r["tick_ns"] >= min_late_ms * 1e6):
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    return merged


def emulator_link_faults(trace, device_log):
    """Trace indices at which a link fault began because the fake device had been held up for
    EMULATOR_LATE_MS or more just before (its 5 ms of silence, which the loop must treat as a
    fault, and does)."""
    late = held_up(device_log, EMULATOR_LATE_MS)
    onsets = [i for i in range(1, len(trace))
              if int(trace[i]["d0_faults"]) & LINK_FAULTS and not int(trace[i - 1]["d0_faults"]) & LINK_FAULTS]
    return [i for i in onsets if any(a <= trace[i]["scheduled_ns"] and b >= trace[i]["scheduled_ns"] - 5e6 for a, b in late)]


def assert_renders_the_sims_wrench(trace, sim_dir, from_s, bound_s, min_force_n=0.5, keep_s=KEEP_S, device_log=None):
    """A resting hand gets this sim's wrench: device 0 engaged, rendering the F0 the sim logged for
    the very sample in use (a median |F| of at least min_force_n) from fresh samples. At rest
    F = F0 - K (x - x0) + D (v0 - v) is F0 but for the hand's yield since the sim's step (a 0.5 N
    change of load moves the fake arm's 400 N/m grip 1.2 mm: 0.4 N at the coupling's 300 N/m):
    each tick within 0.5 N, the median within 0.05 N.

    When: within bound_s of simulated time from the moment it can: trace time from_s (the part
    that completes the stack is up), this sim's first sample in the loop, or the end of a fault
    before the first rendered tick, whichever is last. The engage gate waits for the load to
    steady, that is for the fluid around the spoon to settle, which takes the same simulated time
    on any machine (three times the wall time where the sim runs at a real-time factor of 0.3),
    and a fault restarts it (the rule).

    Then it keeps it: keep_s without a lapse, or (device_log given) until a link fault that the
    fake device caused by waking late (emulator_link_faults); and every lapse is the loop
    recovering from a fault: it starts at a tick with a link or sim-stale fault and is fault,
    engage gate or stale ramp throughout, never an engaged tick with another wrench. A loaded
    2-core machine without PREEMPT_RT now and then delays the fake device 5 ms (a link timeout) or
    the sim 50 ms (stale samples), and a disengaged hand then waits at the gate until its load is
    steady again (the rule: test_fault_injection.py). Returns what it measured, for the log."""
    t = trace_time_s(trace)
    in_use = sim_samples_in_use(trace, sim_dir)
    error = [np.linalg.norm(np.array([r["d0_fx"], r["d0_fy"], r["d0_fz"]]) - u[0]) if u is not None else np.inf
             for r, u in zip(trace, in_use)]
    rendering = [engaged(r) and error[i] < 0.5 for i, r in enumerate(trace)]
    first = next((i for i, u in enumerate(in_use) if u is not None and t[i] >= from_s), None)
    assert first is not None, f"no sample of this sim reached the loop after t = {from_s:.2f} s"
    start = next((i for i in range(first, len(trace)) if rendering[i]), None)
    assert start is not None, f"the sim's wrench never reached the hand after t = {t[first]:.2f} s"
    faulted = [i for i in range(first, start) if int(trace[i]["d0_faults"]) & (LINK_FAULTS | FAULT_SIM_STALE)]
    ready = faulted[-1] + 1 if faulted else first
    ready_sim_s = next(u[1] for u in in_use[ready:] if u is not None)
    waited_sim_s = in_use[start][1] - ready_sim_s
    assert waited_sim_s <= bound_s, (f"rendered after {waited_sim_s:.2f} s of simulated time ({t[start] - t[ready]:.2f} s "
                                     f"of wall time) from t = {t[ready]:.2f} s (bound {bound_s} s simulated)")
    after = range(start, len(trace))
    rendered = [(a, b) for a, b in runs(rendering) if b >= start]  # (the first may begin before from_s)
    kept = max(t[b] - t[a] for a, b in rendered)
    cut = set(emulator_link_faults(trace, device_log)) if device_log is not None else set()
    assert kept >= keep_s or all(b + 1 in cut for a, b in rendered), \
        f"the hand kept the sim's wrench for at most {kept:.2f} s after t = {t[start]:.2f} s (needs {keep_s} s)"
    lapses = [(start + a, start + b) for a, b in runs([not rendering[i] for i in after])]
    for a, b in lapses:
        recovering = all(int(trace[i]["d0_faults"]) or int(trace[i]["d0_flags"]) & RECOVERY_FLAGS for i in range(a, b + 1))
        if int(trace[a]["d0_faults"]) & (LINK_FAULTS | FAULT_SIM_STALE) and recovering:
            continue
        i = next((i for i in range(a, b + 1) if not int(trace[i]["d0_faults"]) and not int(trace[i]["d0_flags"]) & RECOVERY_FLAGS), a)
        r = trace[i]
        raise AssertionError(f"{b - a + 1} ticks without this sim's wrench from t = {t[a]:.3f} s, not the recovery from "
                             f"a fault: at t = {t[i]:.3f} s flags {int(r['d0_flags']):#x}, faults {int(r['d0_faults'])}, "
                             f"|F| {force(r):.3f} N, |F - F0| {error[i]:.3f} N")
    sim_age_ms = float(np.median([trace[i]["sim_age_ns"] for i in after])) * 1e-6
    assert sim_age_ms < 20, f"samples {sim_age_ms:.1f} ms old (median)"
    ok = [i for i in after if rendering[i]]
    median_error = float(np.median([error[i] for i in ok]))
    assert median_error < 0.05, f"|F - F0| median {median_error:.3f} N"
    rendered_n = float(np.median([force(trace[i]) for i in ok]))
    assert rendered_n > min_force_n, f"|F| median {rendered_n:.3f} N"
    return {"rendered_after_sim_s": round(float(waited_sim_s), 3), "rendered_after_s": round(float(t[start] - t[ready]), 3),
            "rendered_n": round(rendered_n, 3), "error_median_n": round(median_error, 4), "kept_s": round(float(kept), 3),
            "recoveries": len(lapses), "emulator_link_faults": len([i for i in cut if i > start])}


def last_kept_stretch(trace, sim_dir, keep_s=KEEP_S):
    """The trace rows of the last stretch of at least keep_s in which device 0 rendered this sim's
    samples, engaged, else of the longest (one an emulator's link fault cut short), for checks of
    what the hand felt while it had the sim's wrench."""
    in_use = sim_samples_in_use(trace, sim_dir)
    t = trace_time_s(trace)
    stretches = runs([engaged(r) and u is not None for r, u in zip(trace, in_use)])
    assert stretches, "no tick with this sim's wrench"
    kept = [(a, b) for a, b in stretches if t[b] - t[a] >= keep_s]
    a, b = kept[-1] if kept else max(stretches, key=lambda ab: t[ab[1]] - t[ab[0]])
    return trace[a:b + 1]


def assert_within_limits(device_log, max_force_n, max_torque_nm):
    """What the device's motors applied, every tick: finite and within the rig's limits."""
    applied = np.array([[r["applied_fx"], r["applied_fy"], r["applied_fz"]] for r in device_log])
    torque = np.array([[r["applied_tx"], r["applied_ty"], r["applied_tz"]] for r in device_log])
    assert np.all(np.isfinite(applied)) and np.all(np.isfinite(torque))
    assert np.max(np.linalg.norm(applied, axis=1)) <= max_force_n * 1.001
    assert np.max(np.linalg.norm(torque, axis=1)) <= max_torque_nm * 1.001


class TraceFollower:
    """A haptic-rt --trace CSV read while the loop writes it (its supervisor flushes the file every
    ~10 ms): the complete rows so far, the columns the waits need, each row parsed once."""
    COLUMNS = ("scheduled_ns", "sim_publish_ns", "sim_age_ns", "d0_flags", "d0_faults", "d0_fx", "d0_fy", "d0_fz")

    def __init__(self, path):
        self.path, self.offset, self.partial, self.index, self.rows = path, 0, b"", None, []

    def poll(self) -> list[dict]:
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                data = f.read()
        except FileNotFoundError:
            return self.rows
        self.offset += len(data)
        lines = (self.partial + data).split(b"\n")
        self.partial = lines.pop()  # a row the loop has not finished writing
        for line in lines:
            fields = line.decode().split(",")
            if self.index is None:
                self.index = {name: i for i, name in enumerate(fields)}
                continue
            self.rows.append({c: float(fields[self.index[c]]) for c in self.COLUMNS})
        return self.rows


class Stack:
    def __init__(self, binary, tmp_path: pathlib.Path, rig="fake_single.toml", tag="hil", lead_in_s=LEAD_IN_S,
                 scene=STIR):
        """A private copy of a shipped rig, as `make run` makes it: own loopback sockets and shm
        prefix, emulated arms playing `scene`'s hands in their device frame (hapfluid.private_rig_text)."""
        self.binary = binary
        self.lead_in_s = lead_in_s
        self.dir = tmp_path
        self.tag = f"{tag}-{os.getpid()}-{time.monotonic_ns() % 10_000_000}"
        self.prefix = f"hapfluid-hil-{self.tag}"
        text, self.offsets = private_rig_text((RIGS / rig).read_text(), load_toml(scene_file(scene)), self.tag)
        self.sockets = re.findall(r'address = "(/tmp/hapfluid-[^"]+\.sock)"', text)
        self.rig = tmp_path / "rig.toml"
        self.rig.write_text(text)
        # As on a rig (the systemd units) and in `make run`: the loop alone on its CPU with the
        # emulated devices beside it (they stand in for hardware outside the host), everything
        # else off it: this harness too. On a kernel without full preemption a process in a long
        # system call holds its CPU, so a sim beside the loop delays the loop and the device.
        self.device_cpus, self.service_cpus = cpu_placement(load_toml(self.rig)["rt"])
        self.own_cpus = os.sched_getaffinity(0)
        if self.service_cpus:
            os.sched_setaffinity(0, self.service_cpus)
        self.procs = {}
        self.started_at = {}

    def scene_variant(self, scene, name, **motion):
        """A copy of a scene (a shipped scene's name, or a path) whose scripted device motions have
        these keys replaced (scene time, before the lead-in), e.g. stop_s=4.5 for a hand that
        comes to rest then (an oscillation fades out to its start pose). For fake_device's
        motion="scene:<path>:<device>", or for sim() (its scripted hands, played until the loop's
        device states appear). Lives in <dir>/scenes; its mesh paths are made absolute, so they
        resolve as they did beside the original."""
        source = scene_file(scene)
        scenes = self.dir / "scenes"
        scenes.mkdir(exist_ok=True)
        lines, in_motion = [], False
        for line in source.read_text().splitlines():
            stripped = line.split("#")[0].strip()
            if stripped.startswith("["):
                in_motion = stripped == "[[devices.motion]]"
            key, _, value = (part.strip() for part in stripped.partition("="))
            if in_motion and key in motion:
                line = f"{key} = {motion[key]}"
            elif key == "mesh" and value:
                line = f"mesh = \"{(source.parent / value.strip(chr(34))).resolve()}\""
            lines.append(line)
        path = scenes / f"{name}.toml"
        path.write_text("\n".join(lines) + "\n")
        return path

    # ---- processes -------------------------------------------------------------------------
    def _start(self, name, args, stdout=None, nice=0, cpus=None):
        """cpus: where the process runs (None: off the loop's CPU, as every non-real-time part)."""
        log = open(self.dir / f"{name}.log", "a")
        self.started_at[name] = time.monotonic()  # CLOCK_MONOTONIC, as the processes' *_ns stamps
        p = subprocess.Popen([str(a) for a in args], stdout=stdout or log, stderr=log, text=True,
                             preexec_fn=_placed(nice, self.service_cpus if cpus is None else cpus))
        self.procs[name] = p
        return p

    def fake_device(self, device="hand", motion="hold", name=None, extra=()):
        name = name or f"fake-{device}"
        if motion.startswith("scene:"):  # scene:FILE:DEVICE -> the same scene with the lead-in
            source, scene_device = motion[len("scene:"):].rsplit(":", 1)
            copy_dir = self.dir / f"{name}-scene"
            copy_dir.mkdir(exist_ok=True)
            motion = f"scene:{device_scene(pathlib.Path(source), copy_dir, self.lead_in_s, self.offsets)}:{scene_device}"
        # A real device's MCU never misses its 1 ms tick; where allowed, the emulator gets a
        # real-time priority (below haptic-rt's 80) so a loaded CI machine does not fake link faults.
        p = self._start(name, [*FIFO, self.binary("haptic-fake-device"), "--rig", self.rig, "--device", device, "--motion",
                               motion, "--log", self.dir / f"{name}.csv", "--summary", self.dir / f"{name}.json",
                               *extra], stdout=subprocess.PIPE, cpus=self.device_cpus)
        line = p.stdout.readline()
        assert "ready" in line, f"{name} did not start: {line!r} {self.log(name)}"
        return p

    def rt(self, name="rt", extra=(), settle_s=0.5):
        """Starts haptic-rt and returns once its loop publishes device states and has had settle_s
        to take its devices' frames and engage them (at zero wrench when no sim runs yet); a test
        that waits for the engaged hand itself passes 0."""
        p = self._start(name, [self.binary("haptic-rt"), "--rig", self.rig, "--shm-prefix", self.prefix,
                               "--trace", self.dir / f"{name}-trace.csv", "--flight-dir", self.dir / "flight", *extra],
                        cpus=self.own_cpus)  # it pins its loop and keeps its helpers off that CPU
        self.wait_for(lambda: os.path.exists(f"/dev/shm/{self.prefix}.device_states") or p.poll() is not None, 15)
        assert p.poll() is None, f"haptic-rt stopped: {self.log(name)}"
        time.sleep(settle_s)
        return p

    def sim(self, scene, name="sim", extra=(), backend="cpu", every_cpu=False):
        """haptic-sim --live on a scene (a name, scene_file(), or a file); the cpu backend unless
        asked (tests of other parts skip the ~1 s backend probe of `auto` and lavapipe's slower
        steps; test_live_vulkan.py covers those). One thread off the loop's CPU, or with
        every_cpu, as its systemd unit and `make run` place it: a thread per CPU, the loop's too."""
        threads = str(len(self.own_cpus)) if every_cpu else "1"
        p = self._start(name, [self.binary("haptic-sim"), "--live", "--scene", scene_file(scene),
                               "--shm-prefix", self.prefix, "--out", self.dir / name, "--threads", threads,
                               "--backend", backend, "--status-every", str(SIM_STATUS_EVERY_S), *extra],
                        nice=-5, cpus=self.own_cpus if every_cpu else None)  # as its systemd unit (Nice=-5)
        self.wait_for(lambda: os.path.exists(f"/dev/shm/{self.prefix}.sim_samples") or p.poll() is not None, 30)
        assert p.poll() is None, f"haptic-sim stopped: {self.log(name)}"
        return p

    def standin(self, *args, name="standin", nice=0):
        return self._start(name, [self.binary("haptic-sim-standin"), "--shm-prefix", self.prefix, *args], nice=nice)

    def render(self, scene, name="render"):
        return self._start(name, [self.binary("haptic-render"), "--live", "--scene", scene_file(scene),
                                  "--shm-prefix", self.prefix, "--headless", "--out", self.dir / "frames",
                                  "--no-mp4", "--width", "320", "--height", "240"],
                           nice=19)  # as its systemd unit (Nice=19)

    def stop(self, name, sig=signal.SIGINT, timeout=15):
        p = self.procs[name]
        if p.poll() is None:
            p.send_signal(sig)
        try:
            return p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
            raise AssertionError(f"{name} ignored {sig!r} for {timeout} s: {self.log(name)}")

    def kill(self, name):
        return self.stop(name, signal.SIGKILL)

    def close(self):
        """Stops whatever is still running (test failure paths) and gives this harness its CPUs back."""
        os.sched_setaffinity(0, self.own_cpus)
        for name, p in self.procs.items():
            if p.poll() is None:
                p.kill()
                p.wait()
            if p.stdout:
                p.stdout.close()
        # A test that failed half-way may have SIGKILLed writers: remove this stack's own segments
        # and sockets (private names) so nothing accumulates on the machine. Passing tests assert
        # leftovers() == [] before this runs.
        for name in self.leftovers():
            path = name if name.startswith("/") else f"/dev/shm/{name}"
            try:
                os.unlink(path)
            except FileNotFoundError:
                pass

    # ---- observations -----------------------------------------------------------------------
    def log(self, name) -> str:
        path = self.dir / f"{name}.log"
        return path.read_text() if path.exists() else ""

    def leftovers(self) -> list[str]:
        shm = [n for n in os.listdir("/dev/shm") if n.startswith(self.prefix + ".")]
        return shm + [s for s in self.sockets if os.path.exists(s)]

    def sim_time_s(self, name="sim") -> float:
        """The simulated time of the sim's newest status line (s), -1 before its first."""
        times = re.findall(r"^haptic-sim: t = ([0-9.]+) s,", self.log(name), re.M)
        return float(times[-1]) if times else -1.0

    @staticmethod
    def wait_for(predicate, timeout_s):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(0.02)
        return False

    def wait_until(self, what, predicate, timeout_s=WAIT_TIMEOUT_S, watch=()):
        """Returns time.monotonic() once predicate() holds. Fails naming `what` (a text, or a
        function giving one when it fails) when it has not after timeout_s, or at once when a
        process in `watch` stops."""
        deadline = time.monotonic() + timeout_s
        while not predicate():
            for name in watch:
                if self.procs[name].poll() is not None:
                    raise AssertionError(f"{name} stopped (exit {self.procs[name].returncode}) before "
                                         f"{what() if callable(what) else what}: {self.log(name)[-1500:]}")
            if time.monotonic() > deadline:
                raise AssertionError(f"{what() if callable(what) else what}: not within {timeout_s:.0f} s")
            time.sleep(0.05)
        return time.monotonic()

    def wait_for_sim_time(self, sim_time_s, name="sim", timeout_s=WAIT_TIMEOUT_S):
        """Until the sim has simulated sim_time_s (its status lines), however slowly it runs here."""
        return self.wait_until(lambda: f"{name} simulated {sim_time_s} s (it got to {self.sim_time_s(name):.2f} s)",
                               lambda: self.sim_time_s(name) >= sim_time_s, timeout_s, watch=(name,))

    def wait_until_healthy(self, sim="sim", rt="rt", keep_s=0.3, timeout_s=WAIT_TIMEOUT_S):
        """Until the loop has had device 0's frames and fresh samples of this sim, without a fault,
        for keep_s on end (engaged or not: the gate may wait for a steady load)."""
        follower = TraceFollower(self.dir / f"{rt}-trace.csv")
        sim_started_ns = self.started_at[sim] * 1e9

        def healthy_s():
            rows = follower.poll()
            since = None
            for r in reversed(rows):
                if int(r["d0_faults"]) or r["sim_publish_ns"] < sim_started_ns or r["sim_age_ns"] > 50e6:
                    break
                since = r
                if rows[-1]["scheduled_ns"] - r["scheduled_ns"] >= keep_s * 1e9:
                    break
            return (rows[-1]["scheduled_ns"] - since["scheduled_ns"]) * 1e-9 if since else 0.0

        return self.wait_until(f"{rt} had {sim}'s samples and its device's frames without a fault for {keep_s} s",
                               lambda: healthy_s() >= keep_s, timeout_s, watch=(rt, sim))

    def wait_until_rendering(self, sim="sim", rt="rt", keep_s=KEEP_S, timeout_s=WAIT_TIMEOUT_S):
        """Until device 0 has rendered this sim's samples, engaged and fresh, for keep_s on end
        (read from the loop's trace as it is written; what the hand got is judged afterwards, by
        assert_renders_the_sims_wrench on the whole trace)."""
        follower = TraceFollower(self.dir / f"{rt}-trace.csv")
        sim_started_ns = self.started_at[sim] * 1e9

        last_rendered_ns, link_fault_since = [None], [False]

        def kept():
            rows = follower.poll()
            since = None
            for r in reversed(rows):
                if not (engaged(r) and r["sim_publish_ns"] >= sim_started_ns and r["sim_age_ns"] < 50e6):
                    break
                since = r
                if rows[-1]["scheduled_ns"] - r["scheduled_ns"] >= keep_s * 1e9:
                    return True
            if since is not None:
                last_rendered_ns[0], link_fault_since[0] = rows[-1]["scheduled_ns"], False
            elif last_rendered_ns[0] is not None:
                link_fault_since[0] = link_fault_since[0] or any(
                    int(r["d0_faults"]) & LINK_FAULTS for r in rows[-300:] if r["scheduled_ns"] > last_rendered_ns[0])
                # a link fault cut the rendering: its recovery is the rule's, given a while (then judged)
                return link_fault_since[0] and rows[-1]["scheduled_ns"] - last_rendered_ns[0] > EMULATOR_RECOVERY_WAIT_S * 1e9
            return False

        return self.wait_until(f"the hand rendered {sim}'s wrench for {keep_s} s on end ({rt}'s trace)",
                               kept, timeout_s, watch=(rt, sim))
