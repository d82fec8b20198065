"""haptic-render as a user runs it: headless PNG output, buffer dumps, replay of a recorded run,
and clear errors for bad input. Every run has the Vulkan validation layer on (exit code 3 if it
reports anything)."""
import json
import os
import pathlib
import shutil
import struct
import subprocess

import pytest

SMALL = ["--width", "160", "--height", "120", "--validation", "--no-mp4"]


def run(binary, *args, timeout=60):
    return subprocess.run([str(binary("haptic-render")), *map(str, args)], capture_output=True, text=True,
                          timeout=timeout)


def write_recorded_run(run_dir: pathlib.Path, frames: int, scene_in_stats: bool = False) -> None:
    """A run laid out exactly as `haptic-sim --out DIR` writes it (sim_gpu/src/outputs.cpp): binary
    POLYDATA frames titled "hapfluid <scene> t=<s> s" with VERTICES, a velocity vector and the
    density/pressure/kind/body/id scalars (kind 0 fluid, 1 wall, 2 body), bodies.csv with poses,
    twists and wrenches, and stats.json naming the scene file."""
    (run_dir / "particles").mkdir(parents=True)
    (run_dir / "cube.obj").write_text(
        "".join(f"v {x} {y} {z}\n" for z in (-0.05, 0.05) for y in (-0.05, 0.05) for x in (-0.05, 0.05))
        + "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n")
    scene = (run_dir / "cli_replay.toml") if scene_in_stats else (run_dir / "scene.toml")
    scene.write_text(
        'name = "cli_replay"\n[domain]\nmin_m = [-0.3, -0.3, 0.0]\nmax_m = [0.3, 0.3, 0.5]\n'
        '[fluid]\nsolver = "wcsph"\nparticle_spacing_m = 0.02\nspeed_of_sound_m_s = 20.0\nlook = "syrup"\n'
        '[time]\nframe_rate_hz = 30.0\n'
        '[[bodies]]\nname = "spoon"\nmesh = "cube.obj"\nposition_m = [0.0, 0.0, 0.25]\ndensity_kg_m3 = 500.0\n')
    if scene_in_stats:
        (run_dir / "stats.json").write_text(json.dumps({"scene": str(scene), "frames_exported": frames}, indent=2))
    fluid = [(x * 0.02, y * 0.02, 0.01 + z * 0.02) for x in range(-4, 5) for y in range(-4, 5) for z in range(3)]
    wall = [(x * 0.02, y * 0.02, -0.01) for x in range(-6, 7) for y in range(-6, 7)]
    for f in range(frames):
        points = [(x, y, z + 0.005 * f) for x, y, z in fluid] + wall
        kinds = [0] * len(fluid) + [1] * len(wall)
        n = len(points)
        be = lambda fmt, values: b"".join(struct.pack(">" + fmt, *v) if isinstance(v, tuple) else struct.pack(">" + fmt, v)
                                          for v in values)
        data = (f"# vtk DataFile Version 3.0\nhapfluid cli_replay t={f / 30.0:.6f} s\nBINARY\nDATASET POLYDATA\n"
                f"POINTS {n} float\n").encode() + be("fff", points)
        data += f"\nVERTICES {n} {2 * n}\n".encode() + be("ii", [(1, i) for i in range(n)])
        data += f"\nPOINT_DATA {n}\nVECTORS velocity float\n".encode() + be("fff", [(0.0, 0.0, 0.0)] * n)
        for name, fmt, values in (("density", "f", [1000.0] * n), ("pressure", "f", [0.0] * n),
                                  ("kind", "i", kinds), ("body", "i", [-1] * n), ("id", "i", list(range(n)))):
            data += f"\nSCALARS {name} {'float' if fmt == 'f' else 'int'} 1\nLOOKUP_TABLE default\n".encode()
            data += be(fmt, values)
        (run_dir / "particles" / f"frame_{f:06d}.vtk").write_bytes(data + b"\n")
    rows = [f"{f / 30.0},spoon,{0.01 * f},0,0.25,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0" for f in range(frames)]
    (run_dir / "bodies.csv").write_text("t,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz\n"
                                        + "\n".join(rows) + "\n")


def test_headless_ball_writes_the_frame_and_the_intermediate_buffers(binary, tmp_path):
    out = tmp_path / "out"
    r = run(binary, "--headless", "--out", out, "--synthetic", "ball", "--dump-buffers", *SMALL)
    assert r.returncode == 0, r.stderr
    assert (out / "frame_000000.png").is_file()
    for name in ("depth", "smoothed_depth", "thickness", "normals"):
        png = out / "buffers" / f"frame_000000_{name}.png"
        assert png.is_file(), f"missing {name} dump"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_replay_renders_one_png_per_recorded_frame(binary, tmp_path):
    run_dir = tmp_path / "run"
    write_recorded_run(run_dir, frames=4)
    out = tmp_path / "frames"
    r = run(binary, "--headless", "--replay", run_dir, "--out", out, *SMALL[:-1])
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.glob("frame_*.png")) == [f"frame_{i:06d}.png" for i in range(4)]
    if shutil.which("ffmpeg"):
        assert (out / "frames.mp4").is_file()
    else:
        assert "ffmpeg not found: skipping the MP4" in r.stderr


@pytest.mark.parametrize("folder", ["run", 'run "quoted" \\ dir'])
def test_replay_finds_the_scene_through_stats_json(binary, tmp_path, folder):
    # JSON escapes a quote or a backslash in the scene's path; the path read back is the real one.
    run_dir = tmp_path / folder
    write_recorded_run(run_dir, frames=2, scene_in_stats=True)
    r = run(binary, "--headless", "--replay", run_dir, "--out", tmp_path / "frames", *SMALL)
    assert r.returncode == 0, r.stderr
    assert len(list((tmp_path / "frames").glob("frame_*.png"))) == 2


def test_spheres_debug_mode_runs_clean(binary, tmp_path):
    r = run(binary, "--headless", "--out", tmp_path, "--synthetic", "ball", "--spheres", *SMALL)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "frame_000000.png").is_file()


@pytest.mark.parametrize("args, message", [
    (["--synthetic", "teapot"], "--synthetic: teapot not in {ball,pool}"),
    (["--frames", "-3"], '--frames: must be a number in [1, 1e+09], not "-3"'),
    (["--headless"], "--headless needs --out DIR"),
    (["--bogus"], "not expected: --bogus"),
    (["--look", "tar"], "--look: tar not in {water,batter,honey,syrup}"),
])
def test_bad_command_lines_are_refused_with_the_reason(binary, args, message):
    r = run(binary, *args)
    assert r.returncode == 2
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_replay_of_a_missing_run_names_the_folder(binary, tmp_path):
    run_dir = tmp_path / "nothing_here"
    run_dir.mkdir()
    (run_dir / "scene.toml").write_text(
        'name = "x"\n[domain]\nmin_m = [0, 0, 0]\nmax_m = [1, 1, 1]\n[fluid]\nsolver = "wcsph"\nparticle_spacing_m = 0.02\n'
        'speed_of_sound_m_s = 20.0\n')
    r = run(binary, "--headless", "--replay", run_dir, "--out", tmp_path / "o", *SMALL)
    assert r.returncode == 1
    assert f"{run_dir}/particles: no particle frames" in r.stderr


def test_window_presents_frames_under_xvfb(binary, tmp_path):
    """The windowed path: GLFW + xcb surface + FIFO swapchain on lavapipe, frames presented with the
    statistics overlay on top of the fluid."""
    if not shutil.which("xvfb-run"):
        pytest.skip("xvfb-run is not installed (apt-get install xvfb)")
    import matplotlib.image
    shot = tmp_path / "window.png"
    r = subprocess.run(["xvfb-run", "-a", str(binary("haptic-render")), "--synthetic", "ball", "--frames", "3",
                        "--width", "640", "--height", "480", "--validation", "--screenshot", str(shot)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "presented 3 frames" in r.stderr
    image = matplotlib.image.imread(str(shot))
    assert image.shape[:2] == (480, 640)
    panel = image[20:60, 20:200, :3].mean()   # the translucent statistics panel with its text
    sky = image[20:60, 560:630, :3].mean()    # plain background beside it
    assert panel < sky - 0.1, "the statistics overlay must darken its corner"
    centre = image[230:250, 310:330, :3].mean(axis=(0, 1))
    assert centre[2] > centre[0] + 0.05, "the ball of water in the middle is blue"


def test_sigterm_ends_a_headless_run_cleanly(binary, tmp_path):
    """The launcher and systemd stop the renderer with SIGTERM: it must finish the frame in hand
    (no half-written .partial PNG left behind), print its summary and exit 0 like a --duration end."""
    import signal
    import time
    proc = subprocess.Popen([str(binary("haptic-render")), "--headless", "--out", str(tmp_path), "--synthetic", "pool",
                             "--frames", "100000", "--width", "160", "--height", "120", "--no-mp4"],
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob("frame_*.png")) and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    assert proc.poll() is None, "the renderer ended before it was signalled"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0, err
    frames = sorted(tmp_path.glob("frame_*.png"))
    assert frames and "wrote %d frames" % len(frames) in err
    assert not list(tmp_path.glob("*.partial")), "a frame was left half-written"
    for f in frames:
        assert f.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
