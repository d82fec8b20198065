"""`make run`'s launcher (`python -m hapfluid run`): the live stack as separate processes, stopped in
order, with every output a user opens afterwards: PNG frames, VTK particle frames (ParaView),
CSV histories, the latency report beside cyclictest's, summary.json."""
import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys

import matplotlib.image
import numpy as np
import pytest

from hapfluid.vtk_frames import read_vtk

FRAME_W, FRAME_H = 640, 480  # the launcher renders at this size
VTK_EVERY_S = 0.5            # the launcher's --export-every default
FLUID = 0                    # VTK "kind" (sim_gpu particles.hpp ParticleKind)


def launch(build_dir, out, *args, timeout=90):
    return subprocess.run([sys.executable, "-m", "hapfluid", "run", "--scene", "spoon_stirring",
                           "--build", str(build_dir), "--out", str(out), *args],
                          capture_output=True, text=True, timeout=timeout)


def shm_prefix(out):
    line = next(l for l in (out / "logs" / "haptic-rt.log").read_text().splitlines() if "shm /" in l)
    return line.split("shm /")[1].split(".*")[0]


def csv_rows(path):
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def rendered_run(build_dir, tmp_path_factory):
    """One short run as `make run` makes it: renderer on, VTK frames, cyclictest beside the loop
    (a 1 s lead-in: the outputs are judged here, not the settled fluid)."""
    out = tmp_path_factory.mktemp("launcher") / "run"
    result = launch(build_dir, out, "--duration", "5", "--backend", "cpu", "--lead-in", "1")
    assert result.returncode == 0, result.stdout + result.stderr
    return out, result, json.loads((out / "summary.json").read_text())


SHORT_RUN_S = 6  # devices to the sim's first sample: 1.5-2.7 s here (auto's probe ~1 s), 4.5 s at a third of the speed


def test_a_short_live_run_leaves_its_outputs_and_nothing_else(build_dir, tmp_path):
    # The hand rests through the whole run (a lead-in as long as the run), so the loop takes the
    # spoon's load up whenever the stack is up: a stroke that began before the sim's first sample
    # (a 1 s lead-in in a 3 s run, on a loaded VM) keeps a stirring hand at the engage gate, and
    # the hand felt nothing.
    out = tmp_path / "run"
    result = launch(build_dir, out, "--duration", str(SHORT_RUN_S), "--no-render", "--no-cyclictest",
                    "--lead-in", str(SHORT_RUN_S))
    assert result.returncode == 0, result.stdout + result.stderr
    for name in ("device_hand.csv", "sim/couplings.csv", "sim/bodies.csv", "sim/stats.json", "wrenches.png",
                 "trace.csv", "latency.png", "latency.json", "summary.json"):
        assert (out / name).exists() and (out / name).stat().st_size > 0, name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ok"] and summary["sim_steps_per_s"] > 0 and summary["max_force_on_hand_n"]["hand"] > 0
    assert summary["build_id"] == json.loads((out / "sim/stats.json").read_text())["build_id"]
    assert "p99" in summary["wake_latency_us"]
    assert "steps/s" in result.stdout and "wake latency" in result.stdout and "max force on the hand" in result.stdout
    # The sim's headroom: the steps' share of its wall clock (stats.json step_load), in (0, 1]
    # (a step that outlasts the run's wall clock cannot happen), printed beside the real-time factor.
    assert 0 < summary["sim_step_load"] <= 1.0
    assert f"{summary['sim_step_load']:.0%} of the wall clock" in result.stdout
    # With more than one thread the live sim steps with all or one, whichever it measured faster
    # (thread_choice.hpp): the summary gives the share on one.
    stats = json.loads((out / "sim/stats.json").read_text())
    if stats["backend"] == "cpu" and stats["threads"] > 1:
        assert 0 <= summary["sim_steps_on_one_thread"] <= 1 and summary["sim_threads"] == stats["threads"]
        assert f"{summary['sim_steps_on_one_thread']:.0%} on one" in result.stdout
    # --no-cyclictest: the loop's latency alone, said so; no cyclictest output left behind.
    assert summary["cyclictest_us"] is None and "no cyclictest" in result.stdout
    assert not (out / "cyclictest.txt").exists()
    # The summary names the backend the sim ran on and why (--backend auto: Vulkan only if it keeps up).
    assert summary["sim_backend"] in ("vulkan", "cpu") and summary["sim_device"] and summary["sim_backend_reason"]
    assert f"{summary['sim_backend']} backend on {summary['sim_device']}" in result.stdout
    # Every process stopped with exit 0 (the launcher checks) and took its segments with it.
    prefix = shm_prefix(out)
    assert not [n for n in os.listdir("/dev/shm") if n.startswith(prefix + ".")]


def test_the_rendered_frames_decode_at_the_launchers_size_and_show_the_fluid(rendered_run):
    # A frame of sky, walls and floor alone is no proof the fluid was drawn: the water look is a
    # saturated cyan (blue and green well above red) that neither the blue-grey sky (b - r = 0.15)
    # nor the grey walls and floor have. ~2000 such pixels in a frame of the settled pool.
    out, result, summary = rendered_run
    frames = sorted((out / "frames").glob("frame_*.png"))
    assert frames and summary["rendered_frames"] == len(frames)
    assert f"rendered frames: {len(frames)}" in result.stdout
    for path in (frames[0], frames[-1]):
        image = matplotlib.image.imread(path)[..., :3]
        assert image.shape == (FRAME_H, FRAME_W, 3), (path.name, image.shape)
        assert image.std() > 0.05, f"{path.name} is blank"
        r, g, b = image[..., 0], image[..., 1], image[..., 2]
        fluid_pixels = int(((b - r > 0.3) & (g - r > 0.2)).sum())
        assert fluid_pixels > 500, f"{path.name}: {fluid_pixels} fluid-coloured pixels"


def test_the_vtk_particle_frames_parse_and_hold_the_whole_fluid(rendered_run):
    # ParaView reads what hapfluid.vtk_frames reads (legacy binary POLYDATA). Every frame
    # holds every fluid particle, finite and inside the domain (0.40 x 0.22 m, walls at the edge),
    # one frame per 0.5 s of simulated time.
    out, result, summary = rendered_run
    frames = sorted((out / "sim" / "particles").glob("frame_*.vtk"))
    stats = json.loads((out / "sim" / "stats.json").read_text())
    assert len(frames) >= 2 and summary["vtk_frames"] == len(frames) == stats["vtk_frames_written"]
    assert f"VTK particle frames: {len(frames)}" in result.stdout
    assert len(frames) >= int(stats["simulated_time_s"] / VTK_EVERY_S), "fewer frames than the simulated time asks"
    times = []
    for path in frames:
        frame = read_vtk(path)
        points, kind = frame["points"], frame["kind"]
        fluid = points[kind == FLUID]
        assert len(fluid) == summary["fluid_particles"], path.name
        assert np.isfinite(points).all() and np.isfinite(frame["velocity"]).all(), path.name
        assert (fluid.min(axis=0) > [-0.02, -0.02, -0.02]).all() and (fluid.max(axis=0) < [0.42, 0.24, 0.42]).all()
        assert (kind == 2).any(), f"{path.name}: no spoon particles"
        times.append(float(re.search(r"t=([0-9.]+) s", frame["title"]).group(1)))
    steps = np.diff(times)
    assert np.all(steps > 0) and np.all(np.abs(steps - VTK_EVERY_S) < 1.5 / 60), times  # at most a scene frame late


def test_the_csv_histories_have_their_columns_and_rows(rendered_run):
    out, _, summary = rendered_run
    device = csv_rows(out / "device_hand.csv")
    assert len(device) > 2000 and {"t_s", "px", "applied_fx"} <= set(device[0])  # ~1 kHz for ~6 s
    couplings = csv_rows(out / "sim" / "couplings.csv")
    assert {"t", "device", "fx", "ty", "wall_s", "publish_ns"} <= set(couplings[0])
    stats = json.loads((out / "sim" / "stats.json").read_text())
    # One row per sim step, as many as samples published to the loop (at least 60 a second).
    assert len(couplings) == stats["sim_samples_published"] and {r["device"] for r in couplings} == {"hand"}
    assert len(couplings) > 60 * stats["simulated_time_s"]
    bodies = csv_rows(out / "sim" / "bodies.csv")
    assert {r["body"] for r in bodies} == {"spoon"} and len(bodies) > 60  # 60 Hz rows
    plotted = csv_rows(out / "device_wrenches.csv")
    assert {"t", "wall_s", "fx"} <= set(plotted[0])
    assert (out / "wrenches.png").stat().st_size > 10_000


@pytest.mark.skipif(not shutil.which("cyclictest"), reason="cyclictest (rt-tests) not installed")
def test_the_loop_latency_is_reported_beside_cyclictest_from_the_same_window(rendered_run):
    # Same window: the loop's ticks counted are those scheduled while cyclictest ran (1 kHz both).
    # cyclictest takes one sample per period even when late; the loop skips the periods of a stall
    # (overruns: a 95 ms VM stall cost 99), so its ticks plus its overruns fill the window.
    out, result, summary = rendered_run
    loop, ct, placement = summary["wake_latency_us"], summary["cyclictest_us"], summary["cyclictest"]
    lat = json.loads((out / "latency.json").read_text())
    for p in (loop, ct):
        assert p["p50"] <= p["p99"] <= p["p99.9"] <= p["max"] and p["p50"] > 0
    assert placement["priority"] == 80 and placement["period_us"] == 1000 and placement["cpu"] == placement["loop_cpu"] == 1
    assert abs(loop["n"] + lat["overruns"] - ct["n"]) < 20, (loop["n"], lat["overruns"], ct["n"])
    assert ct["n"] == round(placement["window_s"] * 1000) and placement["window_s"] > 2
    assert "vs cyclictest in the same" in result.stdout and re.search(r"cyclictest \(CPU \d\)\s+p50", result.stdout)
    text = (out / "latency.txt").read_text()
    assert "wake latency (µs)" in text and "cyclictest (µs)" in text and f"CPU {placement['cpu']}" in text
    assert lat["cyclictest_us"] == ct and lat["window_s"] == placement["window_s"]


def test_a_rendered_run_stops_every_process_and_leaves_no_shared_memory(rendered_run):
    out, _, summary = rendered_run
    assert summary["ok"]
    prefix = shm_prefix(out)
    assert not [n for n in os.listdir("/dev/shm") if n.startswith(prefix + ".")]
    assert "haptic-render" in {p.stem for p in (out / "logs").glob("*.log")}


def test_a_run_whose_renderer_starts_late_ends_with_a_rendered_frame(build_dir, tmp_path):
    # The renderer runs at nice 19: on a busy machine it may not draw before the run's time is up.
    # Here it is held stopped (SIGSTOP before it starts) until the launcher says its time is up;
    # the run then goes on until the first frame is drawn, and ends with it.
    bin_dir = tmp_path / "build" / "bin"
    bin_dir.mkdir(parents=True)
    for tool in (build_dir / "bin").iterdir():
        if tool.name != "haptic-render":
            (bin_dir / tool.name).symlink_to(tool)
    held = bin_dir / "haptic-render"
    held.write_text(f'#!/bin/sh\necho $$ > "{tmp_path}/render.pid"\nkill -STOP $$\n'
                    f'exec "{build_dir / "bin" / "haptic-render"}" "$@"\n')
    held.chmod(0o755)
    out = tmp_path / "run"
    launcher = subprocess.Popen([sys.executable, "-m", "hapfluid", "run", "--scene", "spoon_stirring",
                                 "--build", str(tmp_path / "build"), "--out", str(out), "--duration", "3",
                                 "--lead-in", "3", "--no-cyclictest", "--no-dashboard", "--backend", "cpu"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lines = []
        for line in launcher.stdout:
            lines.append(line)
            if "waiting for the renderer's first frame" in line:
                assert not list((out / "frames").glob("frame_*.png"))
                os.kill(int((tmp_path / "render.pid").read_text()), signal.SIGCONT)
                break
        rest, errors = launcher.communicate(timeout=120)
    finally:
        if launcher.poll() is None:
            launcher.kill()
    stdout = "".join(lines) + rest
    assert launcher.returncode == 0, stdout + errors
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ok"] and summary["rendered_frames"] >= 1, stdout
    assert (out / "frames" / "frame_000000.png").stat().st_size > 0


def test_an_unknown_scene_is_named_with_the_known_ones(build_dir, tmp_path):
    result = subprocess.run([sys.executable, "-m", "hapfluid", "run", "--scene", "no_such_scene",
                             "--build", str(build_dir), "--out", str(tmp_path)], capture_output=True, text=True, timeout=30)
    assert result.returncode != 0 and "no_such_scene" in result.stderr and "spoon_stirring" in result.stderr
