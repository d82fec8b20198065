"""hapfluid launcher: runs a scene on the live stack, every part a separate process.

    hapfluid run [--scene NAME|FILE] [--rig FILE] [--duration S] [--build DIR] [--out DIR]
                [--windowed] [--no-render] [--shm-prefix P] [--batch] [--export-every S]
                [--no-cyclictest] [--cyclictest-cpu N]

A live run starts, in this order:
  haptic-fake-device       one per rig device, playing the scene's scripted hand (--motion scene:...)
  haptic-rt                the 1 kHz loop on the rig's devices (loopback transport); it engages
                           the devices at zero wrench
  haptic-trace             drains the loop's trace ring to trace.csv
  haptic-sim --live        the fluid, simulated time following the wall clock; its wrench fades in
  haptic-render --live     headless PNG frames (or a window with --windowed)
and cyclictest (rt-tests) at the loop's priority and period beside them (cyclictest_placement); runs for
--duration seconds (default: the 3 s lead-in plus the scene's duration_s, 13 s for the default
scene; with headless rendering, at least until the first frame is drawn), stops them in reverse dependency order (render, loop, trace, sim, devices), checks every
exit code and leaves under out/<scene>-<timestamp>/:
  device_<name>.csv        what the fake device felt (its per-tick log)
  sim/couplings.csv        the coupling wrench the sim computed (on the hand), sim/bodies.csv, sim/stats.json
  sim/particles/frame_*.vtk  particle frames every --export-every s of simulated time (ParaView)
  sim/particles/particles.vtk.series  the frames' simulated times (open this in ParaView)
  wrenches.png             fig. 8b-style plot: the scene's force and torque components (hapfluid.plot_wrenches
                           SCENE_COMPONENTS, e.g. the stroke axis for stirring) of both histories against
                           the hand's clock, the script's motions shaded
  frames/frame_*.png       rendered frames
  trace.csv, latency.txt, latency.png, latency.json, cyclictest.txt
                           the 1 kHz loop's wake latency next to cyclictest's from the same window
  summary.json             the printed summary
The rig is copied with private loopback socket paths and a private shm prefix, so runs never
collide with each other or with installed services. --batch runs the batch simulator instead.
"""
import argparse
import csv
import datetime
import json
import math
import os
import pathlib
import signal
import socket
import subprocess
import sys
import tomllib
import time

import tomli_w

from . import latency_report  # cyclictest beside the loop, shared with latency_report --with-cyclictest

from .paths import BIN, RIGS, ROOT, SCENES

FIRST_FRAME_WAIT_S = 60.0  # how long a run waits past its time for the renderer's first frame
SETTLE_S = 0.5  # the sim's time before the script starts below which its fluid has not settled


def resolve_scene(name: str) -> pathlib.Path:
    path = pathlib.Path(name)
    if path.suffix == ".toml" and path.exists():
        return path.resolve()
    candidate = SCENES / f"{name}.toml"
    if candidate.exists():
        return candidate
    known = ", ".join(sorted(p.stem for p in SCENES.glob("*.toml")))
    sys.exit(f"hapfluid: no scene named '{name}' (config/scenes/{name}.toml does not exist); known scenes: {known}")


def load_toml(path: pathlib.Path) -> dict:
    with path.open("rb") as f:
        return tomllib.load(f)


def scene_device_for(scene: dict, rig_name: str):
    """The live sim's matching rule (sim_gpu/live/README.md): rig_device = N, else the name N."""
    devices = scene.get("devices", [])
    for d in devices:
        if d.get("source") == "rig" and d.get("rig_device") == rig_name:
            return d
    for d in devices:
        if d.get("name") == rig_name:
            return d
    return None


def device_scene(scene_path: pathlib.Path, out: pathlib.Path, delay_s: float, offsets: dict | None = None) -> pathlib.Path:
    """The scene as the fake devices play it:
      * every scripted motion segment starts delay_s later (lead-in): the hands hold their start
        poses while the loop engages and the fluid settles (the simulator starts last);
      * positions in the DEVICE frame: x_device = x_scene - offset for devices in `offsets`
        (private_rig_text), so the emulated arm stays inside its mechanical workspace;
      * mesh paths absolute, so the copy can live anywhere.
    Read with tomllib and written with tomli-w: the copy holds the same tables, not the comments."""
    offsets = offsets or {}
    scene = load_toml(scene_path)
    for device in scene.get("devices", []):
        offset = offsets.get(device.get("name"))
        if offset is not None and "start_position_m" in device:
            device["start_position_m"] = [a - b for a, b in zip(device["start_position_m"], offset)]
        for segment in device.get("motion", []):
            segment["start_s"] = segment.get("start_s", 0.0) + delay_s
            if "stop_s" in segment:
                segment["stop_s"] += delay_s
            if offset is not None:
                for key in segment.get("keyframes", []):
                    if "position_m" in key:
                        key["position_m"] = [a - b for a, b in zip(key["position_m"], offset)]
    for body in scene.get("bodies", []):
        if "mesh" in body and not pathlib.Path(body["mesh"]).is_absolute():
            body["mesh"] = str((scene_path.parent / body["mesh"]).resolve())
    path = out / "scene_devices.toml"
    path.write_text(f"# {scene_path.name} for the fake devices: motions {delay_s} s later (lead-in), device frame\n" +
                    tomli_w.dumps(scene))
    return path


def default_rig(scene: dict) -> pathlib.Path:
    return RIGS / ("fake_dual.toml" if len(scene.get("devices", [])) >= 2 else "fake_single.toml")


def private_rig_text(text: str, scene: dict, tag: str) -> tuple[str, dict]:
    """The rig with loopback sockets private to this run (paths < 108 bytes), and for each loopback
    (emulated) device the translation from the scene frame to its device frame, so the fake arm
    plays the scene's hand inside its mechanical workspace (end stops at +-0.3 m around its origin):
    x_scene = workspace_centre + x_rig (haptic-sim, the scene's devices.workspace_centre_m, default
    the hand's start) and x_rig = offset + x_device (the rig's mapping). The rig's devices are
    otherwise unchanged. Returns (TOML text, {scene device: workspace_centre + offset})."""
    rig = tomllib.loads(text)
    offsets = {}
    loopbacks = [d for d in rig.get("devices", []) if d.get("transport", {}).get("kind") == "loopback"]
    for k, device in enumerate(loopbacks, start=1):
        device["transport"]["address"] = f"/tmp/hapfluid-{tag}-{k}.sock"
        name = device.get("name")
        sdev = scene_device_for(scene, name)
        if sdev is None:
            continue
        mapping = device.get("mapping", {})
        scale = float(mapping.get("scale", 1.0))
        rotation = [float(v) for v in mapping.get("rotation", [1.0, 0.0, 0.0, 0.0])]
        if abs(scale - 1.0) > 1e-12 or max(abs(a - b) for a, b in zip(rotation, [1.0, 0.0, 0.0, 0.0])) > 1e-12:
            raise SystemExit(f"hapfluid: rig device \"{name}\": an emulated arm plays the scene's scripted hand "
                             f"translated only; its mapping must have scale = 1 and no rotation (has scale = {scale}, "
                             f"rotation = {rotation})")
        centre = [float(v) for v in sdev.get("workspace_centre_m", sdev.get("start_position_m", [0.0, 0.0, 0.0]))]
        offset = [float(v) for v in mapping.get("offset_m", [0.0, 0.0, 0.0])]
        offsets[sdev["name"]] = [c + o for c, o in zip(centre, offset)]
    return tomli_w.dumps(rig), offsets


def private_rig(rig: pathlib.Path, out: pathlib.Path, tag: str, scene: dict) -> tuple[pathlib.Path, dict]:
    text, offsets = private_rig_text(rig.read_text(), scene, tag)
    copy = out / "rig.toml"
    copy.write_text(f"# {rig} with loopback sockets private to this run\n" + text)
    return copy, offsets


def try_nice(increment: int):
    """Lower (or, where permitted, raise) the scheduling priority of the child about to start."""
    try:
        os.nice(increment)
    except PermissionError:
        pass


def can_use_fifo(priority: int) -> bool:
    """True when this user may run a process under SCHED_FIFO (root, or RLIMIT_RTPRIO granted)."""
    try:
        return subprocess.run(["chrt", "-f", str(priority), "true"], capture_output=True).returncode == 0
    except FileNotFoundError:
        return False


class Stack:
    """The processes of one live run, started and stopped in order, exit codes checked."""

    def __init__(self, out: pathlib.Path):
        self.out = out
        self.procs = []  # (name, Popen, log file)
        self.started_at = {}

    def start(self, name, args, nice=0, stdout_pipe=False, fifo_priority=0, cpus=None):
        log = open(self.out / "logs" / f"{name}.log", "w")

        def preexec():
            # Every service must be stoppable by the SIGINT stop() sends, even when this launcher
            # inherited SIGINT ignored (a background job of a non-interactive shell).
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            if nice:
                try_nice(nice)
            if cpus:
                os.sched_setaffinity(0, cpus)
        if fifo_priority and can_use_fifo(fifo_priority):
            args = ["chrt", "-f", str(fifo_priority)] + list(args)
        p = subprocess.Popen([str(a) for a in args], stdout=subprocess.PIPE if stdout_pipe else log,
                             stderr=log, text=True, preexec_fn=preexec)
        self.procs.append((name, p, log))
        self.started_at[name] = time.monotonic()  # CLOCK_MONOTONIC, as the processes' *_ns stamps
        return p

    def running(self, name):
        return next(p for n, p, _ in self.procs if n == name)

    def wait_for_file(self, path: pathlib.Path, timeout_s: float, proc=None) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if path.exists():
                return True
            if proc is not None and proc.poll() is not None:
                return False
            time.sleep(0.02)
        return False

    def early_exits(self):
        return [(n, p.returncode) for n, p, _ in self.procs if p.poll() is not None]

    def stop(self, name, timeout_s=10.0, grace_s=0.0):
        for n, p, log in self.procs:
            if n != name:
                continue
            if grace_s > 0:  # a process that ends by itself (--duration) gets the chance to
                try:
                    p.wait(timeout=grace_s)
                except subprocess.TimeoutExpired:
                    pass
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
                try:
                    p.wait(timeout=timeout_s)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
                    log.write(f"\nhapfluid: {name} did not stop within {timeout_s} s of SIGINT: killed\n")
                if p.returncode == -signal.SIGINT:
                    # Stopped so early in its start that it had not taken over SIGINT yet: the
                    # stop asked for, not a failure.
                    log.write(f"\nhapfluid: {name} stopped by SIGINT while it started\n")
                    log.flush()
                    return 0
            log.flush()
            return p.returncode
        return None

    def stop_all(self, order, grace=None):
        codes = {}
        for name in order:
            if any(n == name for n, _, _ in self.procs):
                codes[name] = self.stop(name, grace_s=(grace or {}).get(name, 0.0))
        for n, p, log in self.procs:
            if n not in codes:
                codes[n] = self.stop(n)
            log.close()
        return codes


# cyclictest beside the live stack (summary: "1 kHz loop wake latency ... vs cyclictest ... in the
# same window"): one thread at the loop's SCHED_FIFO priority and period (the rig's [rt]) on the
# loop's own CPU (rt.cpu), so both see the same CPU's interrupts, ticks and neighbours: what the
# kernel gives a FIFO thread there against what the loop gets. It does not disturb the loop
# measurably (spoon_stirring, 10 s runs, this 2-core VM loaded by other sessions; loop
# p50/p99/p99.9 µs): without cyclictest 26.9/88/297, 38.5/92/144, 32.5/83/491, 26.0/68/4799; with
# it on CPU 1 26.0/82/321, 26.7/72/1370 (cyclictest there 29/112/326, 27/74/1360: it tracks the
# loop); on CPU 0 instead 34.9/100/268, 47.9/92/351, 27.4/65/1056, 40.0/82/740, where cyclictest
# measures the sim's CPU (p99.9 88 vs the loop's 351), not the loop's. The residual risk: both
# sleep on absolute 1 ms grids and cyclictest's phase is random, so in the few runs in a hundred
# where it lands within the loop's ~20 µs of work each tick one delays the other (cyclictest's own
# work is ~2 µs); --cyclictest-cpu moves it.
def cyclictest_placement(rt: dict) -> int:
    """The CPU cyclictest runs on beside a loop with the rig's rt settings (-1: any)."""
    return rt["cpu"]


def cpu_placement(rt: dict) -> tuple[set, set]:
    """(CPUs of the fake devices, CPUs of the trace logger and the renderer) beside a loop on
    rt["cpu"].

    As on a rig (scripts/systemd): the trace logger and the renderer stay off the loop's CPU; the
    sim is not pinned (it may use every core the loop does not need, and the loop's SCHED_FIFO
    preempts it). The fake devices stand in for hardware outside the host and go beside the loop,
    whose CPU is idle but for ~2% of loop work (they run below its priority): unpinned, their
    1 kHz FIFO ticks preempted the sim on the other CPU. Empty sets (no pinning) when the loop is
    not pinned or there is a single CPU."""
    cpus = os.sched_getaffinity(0)
    loop = rt.get("cpu", -1)
    if loop < 0 or loop not in cpus or len(cpus) < 2:
        return set(), set()
    return {loop}, cpus - {loop}


def read_device_log(path: pathlib.Path):
    """Rows of the fake device's --log CSV as floats."""
    with path.open(newline="") as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def sim_start_monotonic_s(couplings: pathlib.Path):
    """CLOCK_MONOTONIC second at which the live sim's time started (first row: publish_ns - wall_s)."""
    try:
        with couplings.open(newline="") as f:
            row = next(csv.DictReader(f))
        return float(row["publish_ns"]) * 1e-9 - float(row["wall_s"])
    except (OSError, StopIteration, KeyError, ValueError):
        return None


def device_wrench_csv(logs: dict, out: pathlib.Path, shift_s: dict | None = None) -> pathlib.Path:
    """The fake devices' logs as one t,wall_s,device,fx..tz CSV (force applied on the hand), for plotting.
    shift_s[name] moves a device's own clock onto the sim's wall clock (its start minus the sim's
    start), the wall_s axis of sim/couplings.csv; t is the same (a device has no simulated time)."""
    shift_s = shift_s or {}
    path = out / "device_wrenches.csv"
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t", "wall_s", "device", "fx", "fy", "fz", "tx", "ty", "tz"])
        for name, rows in logs.items():
            for r in rows[::5]:  # 200 Hz is plenty for a plot
                wall = f"{r['t_s'] + shift_s.get(name, 0.0):.6f}"
                w.writerow([wall, wall, name, r["applied_fx"], r["applied_fy"], r["applied_fz"],
                            r["applied_tx"], r["applied_ty"], r["applied_tz"]])
    return path


def run_live(args, scene_path, out, bin_dir):
    scene = load_toml(scene_path)
    rig_src = pathlib.Path(args.rig) if args.rig else default_rig(scene)
    tag = f"{os.getpid()}-{int(time.time()) % 100000}"
    rig_path, offsets = private_rig(rig_src, out, tag, scene)
    rig = load_toml(rig_path)
    prefix = args.shm_prefix or f"hapfluid-run-{tag}"
    # The scene's whole script plays: its duration_s after the hands' lead-in.
    duration = args.duration if args.duration else float(scene.get("duration_s", 10.0)) + args.lead_in
    (out / "logs").mkdir(exist_ok=True)
    (out / "frames").mkdir(exist_ok=True)

    check = subprocess.run([str(bin_dir / "haptic-config"), "check", "--rig", str(rig_path), str(scene_path)],
                           capture_output=True, text=True)
    (out / "config-check.txt").write_text(check.stdout + check.stderr)
    if check.returncode != 0:
        sys.stderr.write(check.stdout + check.stderr)
        sys.exit("hapfluid: the configuration has errors (listed above); nothing was run")

    stack = Stack(out)
    print(f"hapfluid: live run of {scene_path.stem} for {duration:g} s on rig {rig_src.name} "
          f"(shm prefix {prefix}); logs in {out / 'logs'}", flush=True)
    ok, cyclictest = True, None
    device_logs = {}
    device_scene_path = device_scene(scene_path, out, args.lead_in, offsets)
    started = time.monotonic()
    device_cpus, service_cpus = cpu_placement(latency_report.read_rig_rt(rig_path))
    try:
        for dev in rig.get("devices", []):
            name = dev["name"]
            sdev = scene_device_for(scene, name)
            motion = f"scene:{device_scene_path}:{sdev['name']}" if sdev else "hold"
            device_logs[name] = out / f"device_{name}.csv"
            p = stack.start(f"haptic-fake-device-{name}",
                            [bin_dir / "haptic-fake-device", "--rig", rig_path, "--device", name, "--motion", motion,
                             "--log", device_logs[name], "--summary", out / "logs" / f"device_{name}_summary.json"],
                            stdout_pipe=True, fifo_priority=70, cpus=device_cpus)
            line = p.stdout.readline()  # "haptic-fake-device: ready on ..."
            if "ready" not in line:
                raise RuntimeError(f"haptic-fake-device for '{name}' did not start: {line.strip()}")
        rt = stack.start("haptic-rt", [bin_dir / "haptic-rt", "--rig", rig_path, "--shm-prefix", prefix,
                                       "--flight-dir", out / "flight"])
        # The loop engages its devices at zero wrench before the sim's wrench fades in: a loop
        # started under a sim already pushing beyond the rig's engage_threshold_n would wait.
        if not stack.wait_for_file(pathlib.Path(f"/dev/shm/{prefix}.device_states"), 15, rt):
            raise RuntimeError("haptic-rt did not start (see logs/haptic-rt.log)")
        time.sleep(0.5)
        cyclictest = start_cyclictest_beside(args, rig_path, out)
        stack.start("haptic-trace", [bin_dir / "haptic-trace", "--out", out / "trace.csv", "--shm-prefix", prefix,
                                     "--wait", "10"], cpus=service_cpus)
        if not args.no_dashboard:
            # The operator's page, as on a rig: read-only, off the loop's CPU, at the rig's address
            # (another port when a second run holds it).
            listen = dashboard_listen(rig)
            stack.start("haptic-dashboard", [sys.executable, "-m", "hapfluid.dashboard", "--shm-prefix", prefix,
                                             "--listen", listen, "--flight-dir", out / "flight",
                                             "--status-binary", bin_dir / "haptic-status"],
                        cpus=service_cpus, nice=10)
            print(f"hapfluid: the operator's page: http://{listen}/", flush=True)
        sim = stack.start("haptic-sim", [bin_dir / "haptic-sim", "--live", "--scene", scene_path, "--rig", rig_path,
                                         "--shm-prefix", prefix, "--out", out / "sim", "--status-every", "2",
                                         "--threads", str(args.sim_threads), "--backend", args.backend,
                                         "--export-every", str(args.export_every)],
                          nice=-5)  # feeds the haptic loop: ahead of builds and the renderer, on every CPU (as its unit)
        if not stack.wait_for_file(pathlib.Path(f"/dev/shm/{prefix}.sim_samples"), 30, sim):
            raise RuntimeError("haptic-sim did not publish /%s.sim_samples (see logs/haptic-sim.log)" % prefix)
        awaited_frame = None
        if not args.no_render and not (bin_dir / "haptic-render").exists():
            print("hapfluid: haptic-render is not built: running without the renderer", file=sys.stderr)
        elif not args.no_render:
            render = [bin_dir / "haptic-render", "--live", "--scene", scene_path, "--shm-prefix", prefix]
            render += ["--width", "640", "--height", "480"]
            render += [] if args.windowed else ["--headless", "--out", out / "frames", "--no-mp4"]
            # It ends by itself (it has no SIGINT handler to save a last frame cleanly).
            render += ["--duration", f"{max(1.0, duration - (time.monotonic() - started)):.2f}"]
            # The renderer (lavapipe: CPU rasterisation) draws with the CPU time the loop and the
            # sim leave: nice 19, as its unit (a waking sim thread preempts it at once, and it is
            # never starved: SCHED_IDLE beside a busy machine drew nothing and missed its SIGINT).
            stack.start("haptic-render", render, cpus=service_cpus, nice=19)
            awaited_frame = None if args.windowed else out / "frames" / "frame_000000.png"
        deadline = started + duration
        waiting_said = False
        while time.monotonic() < deadline or (awaited_frame and not awaited_frame.exists()):
            dead = stack.early_exits()
            if dead:
                raise RuntimeError("stopped early: " + ", ".join(f"{n} (exit {c})" for n, c in dead))
            if time.monotonic() >= deadline:
                # At nice 19 on a busy machine the renderer may not have drawn yet: a run that asked
                # for frames ends with at least one, within a bound.
                if not waiting_said:
                    print("hapfluid: the run's time is up; waiting for the renderer's first frame", flush=True)
                    waiting_said = True
                if time.monotonic() >= deadline + FIRST_FRAME_WAIT_S:
                    raise RuntimeError(f"haptic-render drew no frame within {FIRST_FRAME_WAIT_S:g} s after the "
                                       "run's time was up (see logs/haptic-render.log)")
            time.sleep(0.1)
    except RuntimeError as e:
        ok = False
        print(f"hapfluid: {e}", file=sys.stderr)
    cyclictest_run = stop_cyclictest(cyclictest)
    codes = stack.stop_all(grace={"haptic-render": 8.0}, order=["haptic-render", "haptic-dashboard", "haptic-rt",
                                                                "haptic-trace", "haptic-sim"] +
                           [n for n, _, _ in stack.procs if n.startswith("haptic-fake-device")])
    for name, code in codes.items():
        if code != 0:
            ok = False
            print(f"hapfluid: {name} exited with {code}; its log: {out / 'logs' / (name + '.log')}", file=sys.stderr)
            sys.stderr.write("".join((out / "logs" / f"{name}.log").read_text().splitlines(True)[-8:]))
    leftovers = [n for n in os.listdir("/dev/shm") if n.startswith(prefix + ".")]
    if leftovers:
        ok = False
        print(f"hapfluid: shared memory left behind: {leftovers}", file=sys.stderr)
    return ok, rig, device_logs, stack.started_at, cyclictest_run


def dashboard_listen(rig: dict) -> str:
    """The rig's dashboard.address, or the same host on a free port when that one is taken."""
    host, _, port = rig.get("dashboard", {}).get("address", "127.0.0.1:8642").rpartition(":")
    with socket.socket(socket.AF_INET6 if ":" in host.strip("[]") else socket.AF_INET) as s:
        try:
            s.bind((host.strip("[]"), int(port)))
        except OSError:
            s.bind((host.strip("[]"), 0))
        return f"{host}:{s.getsockname()[1]}"


def start_cyclictest_beside(args, rig_path: pathlib.Path, out: pathlib.Path):
    """cyclictest at the loop's priority and period for the rest of the run (cyclictest_placement), or
    None (--no-cyclictest, or rt-tests not installed: said in one line)."""
    if args.no_cyclictest:
        return None
    rt = latency_report.read_rig_rt(rig_path)
    cpu = args.cyclictest_cpu if args.cyclictest_cpu is not None else cyclictest_placement(rt)
    stdout = open(out / "cyclictest.txt", "w")
    stderr = open(out / "logs" / "cyclictest.log", "w")
    proc = latency_report.start_cyclictest(rt, cpu=cpu, stdout=stdout, stderr=stderr)
    if proc is None:
        stdout.close(), stderr.close()
        (out / "cyclictest.txt").unlink()
        print("hapfluid: note: cyclictest not installed (apt install rt-tests): loop latency without it", file=sys.stderr)
        return None
    return {"proc": proc, "files": (stdout, stderr), "cpu": cpu, "loop_cpu": rt["cpu"], "priority": rt["priority"],
            "period_us": rt["period_ns"] / 1e3}


def stop_cyclictest(run):
    """Ends cyclictest (SIGINT: it prints its histogram) and returns its window, or None if it failed
    (its own problem, e.g. no right to SCHED_FIFO: said, never a failure of the run)."""
    if run is None:
        return None
    proc = run.pop("proc")
    run["stopped_s"] = time.monotonic()
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        code = proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        code = proc.wait()
    for f in run.pop("files"):
        f.close()
    if code != 0:
        print(f"hapfluid: note: cyclictest exited with {code} (see logs/cyclictest.log): loop latency without it",
              file=sys.stderr)
        return None
    return run


def post_process(out, rig, device_logs, scene_name, lead_in_s, started=None, cyclictest=None):
    started = started or {}
    py = sys.executable
    summary = {"scene": scene_name, "out": str(out)}
    stats_path = out / "sim" / "stats.json"
    if stats_path.exists():
        stats = json.loads(stats_path.read_text())
        summary["build_id"] = stats.get("build_id", "")
        summary["sim_steps_per_s"] = round(stats["steps_per_s"], 1)
        summary["real_time_factor"] = round(stats["real_time_factor"], 3)
        summary["sim_kept_up"] = stats["kept_up_with_wall_clock"]
        summary["sim_step_load"] = round(stats["step_load"], 3)
        choice = stats.get("thread_choice")
        if choice and stats.get("threads", 0) > 1:
            # The live sim steps with all its threads or one, whichever it measured faster.
            steps = max(choice["steps_with_all"] + choice["steps_with_one"], 1)
            summary["sim_threads"] = stats["threads"]
            summary["sim_steps_on_one_thread"] = round(choice["steps_with_one"] / steps, 3)
        summary["fluid_particles"] = stats["particles"]["fluid"]
        summary["sim_backend"] = stats.get("backend", "cpu")
        summary["sim_device"] = stats.get("device", {}).get("name", "")
        summary["sim_backend_reason"] = stats.get("backend_choice", {}).get("reason", "")
    logs = {n: read_device_log(p) for n, p in device_logs.items() if p.exists()}
    if logs:
        # One time axis: the sim's (wall clock since it started, = simulated time at real-time
        # factor 1); each device log moved by its start time (launcher's clock, +-10 ms).
        sim_start = sim_start_monotonic_s(out / "sim" / "couplings.csv")
        shift = {n: started[f"haptic-fake-device-{n}"] - sim_start for n in logs
                 if sim_start is not None and f"haptic-fake-device-{n}" in started}
        dev_csv = device_wrench_csv(logs, out, shift)
        summary["max_force_on_hand_n"] = {
            n: round(max((math.hypot(r["applied_fx"], r["applied_fy"], r["applied_fz"]) for r in rows), default=0), 3)
            for n, rows in logs.items()}
        # The scripted hands start their script lead_in after their own start: that instant on the
        # sim's wall clock is the scene's time 0 (the plot's and run_scenarios.py's phase windows).
        if shift:
            summary["script_offset_s"] = round(lead_in_s + min(shift.values()), 4)
            summary["lead_in_s"] = lead_in_s
            if summary["script_offset_s"] < SETTLE_S:
                summary["warning"] = (f"the scene's script started {summary['script_offset_s']:.2f} s after the sim's first "
                                      f"step (< {SETTLE_S} s): its fluid had not settled; run with a longer --lead-in")
        # Against the wall clock (as the hand moves), not simulated time: the two differ when the
        # sim runs slower than real time and drops its backlog, and the device's curve has only the wall.
        plot = subprocess.run([py, "-m", "hapfluid.plot_wrenches", str(out / "sim" / "couplings.csv"),
                               str(dev_csv), "--out", str(out / "wrenches.png"), "--labels", "sim coupling,device (applied)",
                               "--scene", scene_name, "--time", "wall", f"--time-offset={summary.get('script_offset_s', 0)}",
                               *[f"--hand={p}" for p in device_logs.values()], f"--hand-offset={lead_in_s}",
                               "--title", f"{scene_name}: wrench on the hand"], capture_output=True, text=True)
        if plot.returncode != 0:
            print("hapfluid: plot_wrenches failed:\n" + plot.stderr, file=sys.stderr)
    summary["rendered_frames"] = len(sorted((out / "frames").glob("frame_*.png")))
    summary["vtk_frames"] = len(sorted((out / "sim" / "particles").glob("frame_*.vtk")))
    if (out / "trace.csv").exists():
        report = [py, "-m", "hapfluid.latency_report", str(out / "trace.csv"),
                  "--png", str(out / "latency.png"), "--json", str(out / "latency.json")]
        if cyclictest:
            # The loop's ticks of the window cyclictest ran in, nothing before or after it: it takes
            # one sample per period (a late wake still counts one), so it began N periods before it stopped.
            samples = latency_report.cyclictest_result((out / "cyclictest.txt").read_text())[0]["n"]
            started_ns = cyclictest["stopped_s"] * 1e9 - samples * cyclictest["period_us"] * 1e3
            report += ["--cyclictest-log", str(out / "cyclictest.txt"),
                       "--window-ns", f"{started_ns:.0f}:{cyclictest['stopped_s'] * 1e9:.0f}"]
        rep = subprocess.run(report, capture_output=True, text=True)
        placement = ""
        if cyclictest:
            same = ("the loop's CPU" if cyclictest["cpu"] == cyclictest["loop_cpu"]
                    else f"the loop is on CPU {cyclictest['loop_cpu']}")
            placement = (f"cyclictest: CPU {cyclictest['cpu']} ({same}), SCHED_FIFO {cyclictest['priority']}, "
                         f"every {cyclictest['period_us']:g} µs, same window as the loop's ticks above\n")
        (out / "latency.txt").write_text(rep.stdout + placement + rep.stderr)
        if rep.returncode == 0 and (out / "latency.json").exists():
            lat = json.loads((out / "latency.json").read_text())
            summary["wake_latency_us"] = lat.get("wake_latency_us", lat)
            summary["cyclictest_us"] = lat.get("cyclictest_us")
            if cyclictest:
                summary["cyclictest"] = {k: cyclictest[k] for k in ("cpu", "loop_cpu", "priority", "period_us")}
                summary["cyclictest"]["window_s"] = lat.get("window_s")
        else:
            print("hapfluid: latency_report failed:\n" + rep.stderr, file=sys.stderr)
    return summary


def print_summary(summary):
    print("hapfluid: summary")
    if "sim_steps_per_s" in summary:
        kept = "kept up with the wall clock" if summary["sim_kept_up"] else "could NOT keep up with the wall clock"
        print(f"  sim: {summary['sim_backend']} backend on {summary['sim_device']} ({summary['sim_backend_reason']})")
        print(f"  sim: {summary['sim_steps_per_s']} steps/s, real-time factor {summary['real_time_factor']} "
              f"({kept}), {summary['fluid_particles']} fluid particles, steps took "
              f"{summary['sim_step_load']:.0%} of the wall clock")
        if "sim_threads" in summary:
            print(f"  sim: {1 - summary['sim_steps_on_one_thread']:.0%} of its steps on {summary['sim_threads']} threads, "
                  f"{summary['sim_steps_on_one_thread']:.0%} on one (it keeps the faster beside the loop)")
    print(f"  rendered frames: {summary.get('rendered_frames', 0)}, VTK particle frames: {summary.get('vtk_frames', 0)}")
    w, ct = summary.get("wake_latency_us"), summary.get("cyclictest_us")

    def row(p):
        return "  ".join(f"{k} {p[k]:7.1f}" for k in ("p50", "p99", "p99.9", "max"))
    if isinstance(w, dict) and "p99" in w:
        if ct:
            c = summary["cyclictest"]
            print(f"  1 kHz loop wake latency (µs) vs cyclictest in the same {c['window_s']:g} s window:")
            print(f"    loop (CPU {c['loop_cpu']})         {row(w)}")
            print(f"    cyclictest (CPU {c['cpu']})   {row(ct)}")
        else:
            print(f"  1 kHz loop wake latency (µs): {row(w)} (no cyclictest)")
    for n, f in summary.get("max_force_on_hand_n", {}).items():
        print(f"  max force on the hand '{n}': {f} N")
    if "warning" in summary:
        print(f"  WARNING: {summary['warning']}")
    print(f"  outputs: {summary['out']}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene")
    run.add_argument("--scene", default="spoon_stirring")
    run.add_argument("--rig", default=None, help="rig file (default: fake_single, fake_dual for two-hand scenes)")
    run.add_argument("--duration", type=float, default=None,
                     help="wall seconds from the start (default: the lead-in plus the scene's duration_s)")
    run.add_argument("--build", default=None,
                     help="build folder whose bin/ to run (default: build/ of this checkout; installed: <prefix>/bin)")
    run.add_argument("--out", default=None, help="output folder (default: out/<scene>-<timestamp>)")
    run.add_argument("--windowed", action="store_true", help="render in a window instead of PNG frames")
    run.add_argument("--no-render", action="store_true", help="run without the renderer")
    run.add_argument("--shm-prefix", default=None, help="shared-memory prefix (default: private to this run)")
    # The stack takes 1.5-2.5 s to publish its first sample (auto's backend probe ~1 s, the loop's
    # start, a loaded machine): at 1.5 s the stirring stroke began before the sim's first step.
    run.add_argument("--lead-in", type=float, default=3.0,
                     help="seconds the fake hands hold still before their script starts (loop engages, fluid settles)")
    run.add_argument("--sim-threads", type=int, default=len(os.sched_getaffinity(0)),
                     help="simulator threads (default: one per CPU; the loop's SCHED_FIFO preempts them)")
    run.add_argument("--export-every", type=float, default=0.5,
                     help="VTK particle frames (sim/particles/, ParaView) every S simulated seconds (0: none)")
    run.add_argument("--no-cyclictest", action="store_true",
                     help="do not run cyclictest beside the loop (its latency is then reported alone)")
    run.add_argument("--cyclictest-cpu", type=int, default=None,
                     help="CPU for cyclictest (default: the loop's rt.cpu; see cyclictest_placement)")
    run.add_argument("--batch", action="store_true", help="batch simulation only (no live processes)")
    run.add_argument("--no-dashboard", action="store_true", help="do not serve the operator's page beside the stack")
    run.add_argument("--backend", choices=("auto", "vulkan", "cpu"), default="auto",
                     help="simulator backend (auto: Vulkan if it keeps up with the wall clock on this machine and "
                          "scene, else the faster one, said in the sim's log and the summary; sim_gpu/live/README.md)")
    args = parser.parse_args()

    if args.build is None:
        bin_dir = BIN
    else:
        build = pathlib.Path(args.build)
        bin_dir = (build if build.is_absolute() else (ROOT / build).resolve()) / "bin"
    scene_path = resolve_scene(args.scene)
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    out = pathlib.Path(args.out).resolve() if args.out else ROOT / "out" / f"{scene_path.stem}-{stamp}"
    out.mkdir(parents=True, exist_ok=True)
    (out / "scene.toml").write_text(scene_path.read_text())
    missing = [b for b in ("haptic-sim", "haptic-rt", "haptic-fake-device", "haptic-trace", "haptic-config")
               if not (bin_dir / b).exists()]
    if missing:
        sys.exit(f"hapfluid: not built: {', '.join(missing)} (run `make`)")

    if args.batch:
        command = [str(bin_dir / "haptic-sim"), "--scene", str(scene_path), "--backend", args.backend,
                   "--out", str(out / "sim"), "--export-every", str(args.export_every)]
        if args.duration:
            command += ["--duration", str(args.duration)]
        return subprocess.run(command).returncode

    started = time.monotonic()
    ok, rig, device_logs, started_at, cyclictest = run_live(args, scene_path, out, bin_dir)
    summary = post_process(out, rig, device_logs, scene_path.stem, args.lead_in, started_at, cyclictest)
    summary["ok"] = ok
    summary["wall_s"] = round(time.monotonic() - started, 2)
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    print_summary(summary)
    if not ok:
        print("hapfluid: the run had errors (above)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
