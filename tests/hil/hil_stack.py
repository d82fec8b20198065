"""Hardware-in-the-loop harness: the real binaries (haptic-fake-device, haptic-rt, haptic-sim --live,
haptic-render, haptic-sim-standin) as separate processes over the loopback transport.

Every stack gets a private copy of a shipped rig (own loopback socket paths, own shm prefix) so
tests never collide with each other, with `make run` or with installed services. Processes are
tracked by the Popen objects the harness started and stopped by pid, never by name.

Start order, as `make run` and the systemd target: devices, then haptic-rt (it engages its
devices at zero wrench), then the simulator, whose wrench then fades in. A loop started under a
sim already pushing more than the rig's engage_threshold_n waits for the wrench to drop below it
or to hold steady for engage_hold_ms."""
import csv
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

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
