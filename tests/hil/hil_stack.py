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
until the loop's device states appear, the renderer waits for the sim."""
import csv
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
from hapfluid import device_scene, load_toml, private_rig_text  # noqa: E402  (shared with the launcher)

LEAD_IN_S = 1.5  # scripted hands hold still this long (the loop engages, the fluid settles)
SCENES = ROOT / "config" / "scenes"
RIGS = ROOT / "config" / "rigs"

# safety::Fault bits (rt_core/include/hapfluid/safety/flags.hpp)
FAULT_LINK_TIMEOUT = 1 << 1
FAULT_LINK_INVALID = 1 << 2
FAULT_DEVICE_REPORTED = 1 << 3
FAULT_SIM_STALE = 1 << 4
LINK_FAULTS = FAULT_LINK_TIMEOUT | FAULT_LINK_INVALID | FAULT_DEVICE_REPORTED
# safety::Flag bits (rt_core/include/hapfluid/safety/flags.hpp)
FLAG_WAITING_TO_ENGAGE = 1 << 7
FLAG_ENGAGING = 1 << 8
# What a loop needs after a link fault or a late sim before it renders again (fake_single:
# link_recover_ms 100, engage_hold_ms 150, a ramp of >= engage_ramp_ms 200), with room for a
# loaded machine.
FAULT_RECOVERY_S = 0.8


def _try_nice(increment):
    try:
        os.nice(increment)
    except PermissionError:
        pass


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


def sim_force_in_use(trace, sim_dir):
    """Per trace row, the force (N) of the sim sample the loop rendered in that tick, from that
    sim's own log (<sim_dir>/couplings.csv, one coupling: the scene's hand), or None when the
    sample is another sim's, or none."""
    by_publish = {int(r["publish_ns"]): (r["fx"], r["fy"], r["fz"]) for r in read_csv(sim_dir / "couplings.csv")}
    return [by_publish.get(int(r["sim_publish_ns"])) for r in trace]


def assert_renders_the_sims_wrench(trace, sim_dir, from_s, bound_s, min_force_n=0.5):
    """A resting hand gets this sim's wrench: from trace time from_s, within bound_s, device 0 is
    engaged and renders the F0 the sim logged for the very sample in use (a median of at least
    min_force_n), from fresh samples, until the end. At rest F = F0 - K (x - x0) + D (v0 - v) is F0 but for the hand's yield since
    the sim's step (a 0.5 N change of load moves the fake arm's 400 N/m grip 1.2 mm: 0.4 N at the
    coupling's 300 N/m): each tick within 0.5 N, the median within 0.05 N. A lapse is allowed only
    as the recovery from a fault, and for at most half the time: a loaded 2-core machine
    without PREEMPT_RT now and then delays the fake device 5 ms (a link timeout) or the sim 50 ms
    (stale samples). Returns what it measured, for the log."""
    t = trace_time_s(trace)
    f0 = sim_force_in_use(trace, sim_dir)
    error = [np.linalg.norm(np.array([r["d0_fx"], r["d0_fy"], r["d0_fz"]]) - f0[i]) if f0[i] is not None else np.inf
             for i, r in enumerate(trace)]
    rendering = [t[i] >= from_s and engaged(r) and error[i] < 0.5 for i, r in enumerate(trace)]
    start = next((i for i, ok in enumerate(rendering) if ok), None)
    assert start is not None, f"the sim's wrench never reached the hand after t = {from_s:.2f} s"
    assert t[start] - from_s <= bound_s, f"rendered {t[start] - from_s:.2f} s after t = {from_s:.2f} s (bound {bound_s} s)"
    after = range(start, len(trace))
    assert t[-1] - t[start] > 0.5, "the run went on long enough to see it rendered"
    fault_at = [t[i] for i in after if int(trace[i]["d0_faults"]) & (LINK_FAULTS | FAULT_SIM_STALE)]
    lapses = [i for i in after if not rendering[i]]
    assert len(lapses) <= 0.5 * len(after), \
        f"the sim's wrench missing in {len(lapses)} of {len(after)} ticks ({len(fault_at)} with a fault)"
    unexplained = [i for i in lapses if not any(0 <= t[i] - tf <= FAULT_RECOVERY_S for tf in fault_at)]
    if unexplained:
        r = trace[unexplained[0]]
        raise AssertionError(f"{len(unexplained)} ticks without this sim's wrench, not after a fault, from t = "
                             f"{t[unexplained[0]]:.3f} s: flags {int(r['d0_flags']):#x}, faults {int(r['d0_faults'])}, "
                             f"|F| {force(r):.3f} N, |F - F0| {error[unexplained[0]]:.3f} N")
    sim_age_ms = float(np.median([trace[i]["sim_age_ns"] for i in after])) * 1e-6
    assert sim_age_ms < 20, f"samples {sim_age_ms:.1f} ms old (median)"
    ok = [i for i in after if rendering[i]]
    median_error = float(np.median([error[i] for i in ok]))
    assert median_error < 0.05, f"|F - F0| median {median_error:.3f} N"
    rendered_n = float(np.median([force(trace[i]) for i in ok]))
    assert rendered_n > min_force_n, f"|F| median {rendered_n:.3f} N"
    return {"rendered_after_s": round(float(t[start] - from_s), 3), "rendered_n": round(rendered_n, 3),
            "error_median_n": round(median_error, 4), "fault_ticks": len(fault_at)}


def assert_within_limits(device_log, max_force_n, max_torque_nm):
    """What the device's motors applied, every tick: finite and within the rig's limits."""
    applied = np.array([[r["applied_fx"], r["applied_fy"], r["applied_fz"]] for r in device_log])
    torque = np.array([[r["applied_tx"], r["applied_ty"], r["applied_tz"]] for r in device_log])
    assert np.all(np.isfinite(applied)) and np.all(np.isfinite(torque))
    assert np.max(np.linalg.norm(applied, axis=1)) <= max_force_n * 1.001
    assert np.max(np.linalg.norm(torque, axis=1)) <= max_torque_nm * 1.001


class Stack:
    def __init__(self, binary, tmp_path: pathlib.Path, rig="fake_single.toml", tag="hil", lead_in_s=LEAD_IN_S,
                 scene="spoon_stirring"):
        """A private copy of a shipped rig, as `make run` makes it: own loopback sockets and shm
        prefix, emulated arms playing `scene`'s hands in their device frame (hapfluid.private_rig_text)."""
        self.binary = binary
        self.lead_in_s = lead_in_s
        self.dir = tmp_path
        self.tag = f"{tag}-{os.getpid()}-{time.monotonic_ns() % 10_000_000}"
        self.prefix = f"hapfluid-hil-{self.tag}"
        text, self.offsets = private_rig_text((RIGS / rig).read_text(), load_toml(SCENES / f"{scene}.toml"), self.tag)
        self.sockets = re.findall(r'address = "(/tmp/hapfluid-[^"]+\.sock)"', text)
        self.rig = tmp_path / "rig.toml"
        self.rig.write_text(text)
        self.procs = {}
        self.started_at = {}

    def scene_variant(self, scene, name, **motion):
        """A copy of a shipped scene whose scripted device motions have these keys replaced (scene
        time, before the lead-in), e.g. stop_s=4.5 for a hand that comes to rest then (an
        oscillation fades out to its start pose). For fake_device's motion="scene:<path>:<device>";
        the simulator keeps the shipped scene. Lives in <dir>/scenes beside a link to the shipped
        meshes, so the scene's relative mesh paths still resolve."""
        scenes, meshes = self.dir / "scenes", self.dir / "meshes"
        scenes.mkdir(exist_ok=True)
        if not meshes.exists():
            meshes.symlink_to(SCENES.parent / "meshes")
        lines, in_motion = [], False
        for line in (SCENES / f"{scene}.toml").read_text().splitlines():
            stripped = line.split("#")[0].strip()
            if stripped.startswith("["):
                in_motion = stripped == "[[devices.motion]]"
            key = stripped.split("=", 1)[0].strip()
            lines.append(f"{key} = {motion[key]}" if in_motion and "=" in stripped and key in motion else line)
        path = scenes / f"{name}.toml"
        path.write_text("\n".join(lines) + "\n")
        return path

    # ---- processes -------------------------------------------------------------------------
    def _start(self, name, args, stdout=None, nice=0):
        log = open(self.dir / f"{name}.log", "a")
        self.started_at[name] = time.monotonic()  # CLOCK_MONOTONIC, as the processes' *_ns stamps
        p = subprocess.Popen([str(a) for a in args], stdout=stdout or log, stderr=log, text=True,
                             preexec_fn=(lambda: _try_nice(nice)) if nice else None)
        self.procs[name] = p
        return p

    def fake_device(self, device="hand", motion="hold", name=None, extra=()):
        name = name or f"fake-{device}"
        if motion.startswith("scene:"):  # scene:FILE:DEVICE -> the same scene with the lead-in
            scene_file, scene_device = motion[len("scene:"):].rsplit(":", 1)
            copy_dir = self.dir / f"{name}-scene"
            copy_dir.mkdir(exist_ok=True)
            motion = f"scene:{device_scene(pathlib.Path(scene_file), copy_dir, self.lead_in_s, self.offsets)}:{scene_device}"
        # A real device's MCU never misses its 1 ms tick; where allowed, the emulator gets a
        # real-time priority (below haptic-rt's 80) so a loaded CI machine does not fake link faults.
        p = self._start(name, [*FIFO, self.binary("haptic-fake-device"), "--rig", self.rig, "--device", device, "--motion",
                               motion, "--log", self.dir / f"{name}.csv", "--summary", self.dir / f"{name}.json",
                               *extra], stdout=subprocess.PIPE)
        line = p.stdout.readline()
        assert "ready" in line, f"{name} did not start: {line!r} {self.log(name)}"
        return p

    def rt(self, name="rt", extra=()):
        """Starts haptic-rt and returns once its loop publishes device states and has had 0.5 s to
        take its devices' frames and engage them (at zero wrench when no sim runs yet)."""
        p = self._start(name, [self.binary("haptic-rt"), "--rig", self.rig, "--shm-prefix", self.prefix,
                               "--trace", self.dir / f"{name}-trace.csv", "--flight-dir", self.dir / "flight", *extra])
        self.wait_for(lambda: os.path.exists(f"/dev/shm/{self.prefix}.device_states") or p.poll() is not None, 15)
        assert p.poll() is None, f"haptic-rt stopped: {self.log(name)}"
        time.sleep(0.5)
        return p

    def sim(self, scene, name="sim", extra=(), backend="cpu"):
        """haptic-sim --live; the cpu backend unless asked (tests of other parts skip the ~1 s
        backend probe of `auto` and lavapipe's slower steps; test_live_vulkan.py covers those)."""
        p = self._start(name, [self.binary("haptic-sim"), "--live", "--scene", SCENES / f"{scene}.toml",
                               "--shm-prefix", self.prefix, "--out", self.dir / name, "--threads", "1",
                               "--backend", backend, "--status-every", "1", *extra],
                        nice=-5)  # as its systemd unit (Nice=-5)
        self.wait_for(lambda: os.path.exists(f"/dev/shm/{self.prefix}.sim_samples") or p.poll() is not None, 30)
        assert p.poll() is None, f"haptic-sim stopped: {self.log(name)}"
        return p

    def standin(self, *args, name="standin"):
        return self._start(name, [self.binary("haptic-sim-standin"), "--shm-prefix", self.prefix, *args])

    def render(self, scene, name="render"):
        return self._start(name, [self.binary("haptic-render"), "--live", "--scene", SCENES / f"{scene}.toml",
                                  "--shm-prefix", self.prefix, "--headless", "--out", self.dir / "frames",
                                  "--no-mp4", "--width", "320", "--height", "240"])

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
        """Stops whatever is still running (test failure paths)."""
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

    @staticmethod
    def wait_for(predicate, timeout_s):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(0.02)
        return False
