"""haptic-sim batch mode from the command line: the outputs a user opens (VTK frames, body and
coupling CSV, stats.json), bit-for-bit repeatable runs, and clear failures without outputs
that look complete."""
import csv
import os
import json
import subprocess
import sys
import pathlib

import numpy as np
import pytest

from hapfluid.vtk_frames import read_vtk

BOX_OBJ = """v 0 0 0
v 0.04 0 0
v 0 0.04 0
v 0.04 0.04 0
v 0 0 0.06
v 0.04 0 0.06
v 0 0.04 0.06
v 0.04 0.04 0.06
f 1 3 2
f 2 3 4
f 5 6 7
f 6 8 7
f 1 2 5
f 2 6 5
f 3 7 4
f 4 7 8
f 1 5 3
f 3 5 7
f 2 4 6
f 4 8 6
"""

SCENE = """
name = "tiny_stir"
duration_s = 0.1
[domain]
min_m = [0.0, 0.0, 0.0]
max_m = [0.16, 0.1, 0.12]
[fluid]
solver = "wcsph"
particle_spacing_m = 0.01
speed_of_sound_m_s = 10.0
viscosity_pa_s = 1.0
[[fluid.blocks]]
min_m = [0.0, 0.0, 0.0]
max_m = [0.16, 0.1, 0.06]
[[bodies]]
name = "paddle"
mesh = "box.obj"
position_m = [0.06, 0.03, 0.03]
density_kg_m3 = 800.0
[[devices]]
name = "hand"
start_position_m = [0.08, 0.05, 0.09]
[[devices.motion]]
kind = "oscillate"
axis = [1.0, 0.0, 0.0]
amplitude_m = 0.02
frequency_hz = 3.0
[[couplings]]
device = "hand"
body = "paddle"
grasp_position_m = [0.02, 0.02, 0.06]
[time]
cfl = 0.2
frame_rate_hz = 100.0
"""


def write_scene(folder: pathlib.Path, text: str = SCENE) -> pathlib.Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "box.obj").write_text(BOX_OBJ)
    scene = folder / "scene.toml"
    scene.write_text(text)
    return scene


def run(binary, scene, out, *extra):
    return subprocess.run([str(binary("haptic-sim")), "--scene", str(scene), "--out", str(out), "--backend", "cpu",
                           "--threads", "2", *extra], capture_output=True, text=True, timeout=120)


def test_batch_run_writes_every_output(binary, tmp_path):
    scene = write_scene(tmp_path / "scene")
    out = tmp_path / "out"
    result = run(binary, scene, out, "--export-every", "0.05")
    assert result.returncode == 0, result.stderr
    stats = json.loads((out / "stats.json").read_text())
    assert stats["complete"] is True
    assert stats["backend"] == "cpu"
    # Which build wrote it: the id `haptic-config --version` prints (both link the same library).
    version = subprocess.run([str(binary("haptic-config")), "--version"], capture_output=True, text=True).stdout.split()
    assert stats["build_id"] == version[1]
    assert stats["particles"]["fluid"] > 500 and stats["particles"]["body"] > 20
    assert abs(stats["simulated_time_s"] - 0.1) < 1e-9
    assert stats["steps"] >= 10 and stats["steps_per_s"] > 0 and stats["real_time_factor"] > 0
    assert set(stats["phase_ms_per_step"]) == {"neighbour_search", "density", "forces", "pressure_solve", "bodies",
                                               "integration"}
    assert stats["solver"] == "wcsph"

    frames = sorted((out / "particles").glob("frame_*.vtk"))
    assert [f.name for f in frames] == ["frame_000000.vtk", "frame_000001.vtk", "frame_000002.vtk"]
    frame = read_vtk(frames[-1])
    n = stats["particles"]["total"]
    assert frame["points"].shape == (n, 3)
    for field in ("velocity", "density", "pressure", "kind", "body", "id"):
        assert field in frame, field
    assert set(frame["kind"].tolist()) == {0, 1, 2}  # fluid, wall, body
    assert (frame["body"][frame["kind"] == 2] == 0).all()
    # ParaView's file series: every frame, in order, at the simulated time its header states.
    series = json.loads((out / "particles" / "particles.vtk.series").read_text())
    assert series["file-series-version"] == "1.0"
    assert [e["name"] for e in series["files"]] == [f.name for f in frames]
    for entry, f in zip(series["files"], frames):
        stated = float(f.read_bytes().split(b"\n")[1].split(b" t=")[1].split()[0])
        assert entry["time"] == pytest.approx(stated, abs=1e-6), f.name
    assert [e["time"] for e in series["files"]] == pytest.approx([0.0, 0.05, 0.1], abs=1e-9)
    # The bodies as a series of their own, at the same times, agreeing with bodies.csv.
    body_series = json.loads((out / "particles" / "bodies.vtk.series").read_text())
    assert [e["name"] for e in body_series["files"]] == ["bodies_000000.vtk", "bodies_000001.vtk", "bodies_000002.vtk"]
    assert [e["time"] for e in body_series["files"]] == [e["time"] for e in series["files"]]
    last = read_vtk(out / "particles" / "bodies_000002.vtk")
    assert last["points"].shape == (1, 3) and last["orientation"].shape == (1, 4)
    for field in ("velocity", "angular_velocity", "fluid_force", "fluid_torque", "coupling_force", "coupling_torque"):
        assert last[field].shape == (1, 3), field
    assert np.linalg.norm(last["orientation"][0]) == pytest.approx(1.0, abs=1e-5)

    with open(out / "bodies.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0].keys()) == "t,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz".split(",")
    assert len(rows) == 10 and rows[-1]["body"] == "paddle"
    for k, field in enumerate(("vx", "vy", "vz")):
        assert last["velocity"][0][k] == pytest.approx(float(rows[-1][field]), rel=1e-5, abs=1e-7)
    for k, field in enumerate(("fx", "fy", "fz")):
        assert last["fluid_force"][0][k] == pytest.approx(float(rows[-1][field]), rel=1e-5, abs=1e-7)
    with open(out / "couplings.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0].keys()) == "t,device,body,fx,fy,fz,tx,ty,tz".split(",")
    assert rows[-1]["device"] == "hand" and rows[-1]["body"] == "paddle"
    assert not list(out.rglob("*.part"))


def test_vtk_reads_every_frame_as_the_projects_reader_does(binary, tmp_path):
    """The reader ParaView itself uses (VTK's legacy polydata reader, from the vtk wheel) finds in
    every frame of both series what hapfluid.vtk_frames finds, and complains about nothing."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkIOLegacy import vtkPolyDataReader

    scene = write_scene(tmp_path / "scene")
    out = tmp_path / "out"
    result = run(binary, scene, out, "--export-every", "0.05")
    assert result.returncode == 0, result.stderr
    stats = json.loads((out / "stats.json").read_text())
    complaints = []
    for index, points in (("particles.vtk.series", stats["particles"]["total"]), ("bodies.vtk.series", 1)):
        entries = json.loads((out / "particles" / index).read_text())["files"]
        assert len(entries) == 3, index
        for entry in entries:
            path = out / "particles" / entry["name"]
            reader = vtkPolyDataReader()
            for event in ("ErrorEvent", "WarningEvent"):
                reader.AddObserver(event, lambda caller, event, name=entry["name"]: complaints.append((name, event)))
            reader.SetFileName(str(path))
            reader.ReadAllScalarsOn()
            reader.ReadAllVectorsOn()
            reader.Update()
            polydata = reader.GetOutput()
            ours = read_vtk(path)
            assert reader.GetHeader() == ours["title"]
            assert float(ours["title"].split(" t=")[1].split()[0]) == pytest.approx(entry["time"], abs=1e-6)
            assert polydata.GetNumberOfPoints() == polydata.GetNumberOfVerts() == points, entry["name"]
            np.testing.assert_array_equal(vtk_to_numpy(polydata.GetPoints().GetData()), ours["points"])
            data = polydata.GetPointData()
            arrays = {data.GetArrayName(k): vtk_to_numpy(data.GetArray(k)) for k in range(data.GetNumberOfArrays())}
            assert set(arrays) == set(ours) - {"title", "points"}, entry["name"]
            for name, values in arrays.items():
                np.testing.assert_array_equal(values, ours[name], err_msg=f"{entry['name']}: {name}")
    assert not complaints
    # The fluid the stats count is the fluid the frames hold.
    last = read_vtk(out / "particles" / "frame_000002.vtk")
    assert int((last["kind"] == 0).sum()) == stats["particles"]["fluid"]


def test_same_run_twice_gives_identical_outputs(binary, tmp_path):
    # Determinism for a given thread count: every particle and body value, bit for bit.
    scene = write_scene(tmp_path / "scene")
    outputs = []
    for name in ("a", "b"):
        result = run(binary, scene, tmp_path / name, "--export-every", "0.1")
        assert result.returncode == 0, result.stderr
        outputs.append(tmp_path / name)
    for rel in ("bodies.csv", "couplings.csv", "particles/frame_000001.vtk"):
        assert (outputs[0] / rel).read_bytes() == (outputs[1] / rel).read_bytes(), rel


def test_bad_scene_fails_clearly_without_complete_outputs(binary, tmp_path):
    text = SCENE.replace("position_m = [0.06, 0.03, 0.03]", "position_m = [0.0005, 0.03, 0.03]")
    scene = write_scene(tmp_path / "scene", text)
    out = tmp_path / "out"
    result = run(binary, scene, out)
    assert result.returncode == 1
    assert "bodies.paddle: the body overlaps the domain wall x_min" in result.stderr
    assert not (out / "stats.json").exists()
    assert not (out / "bodies.csv").exists()


def snapshot(folder: pathlib.Path) -> dict:
    """Every file under folder, by relative path, with its bytes."""
    return {str(f.relative_to(folder)): f.read_bytes() for f in sorted(folder.rglob("*")) if f.is_file()}


def complete_run(binary, tmp_path, *extra) -> pathlib.Path:
    out = tmp_path / "out"
    result = run(binary, write_scene(tmp_path / "scene"), out, *extra)
    assert result.returncode == 0, result.stderr
    assert json.loads((out / "stats.json").read_text())["complete"] is True
    return out


BAD_SCENES = {
    # load_scene refuses it (config error: file, line, key, value, reason)
    "load": (("particle_spacing_m = 0.01", "particle_spacing_m = -0.01"),
             "fluid.particle_spacing_m = -0.01: must be > 0"),
    # load_scene accepts it, build_model refuses it
    "build": (("position_m = [0.06, 0.03, 0.03]", "position_m = [0.0005, 0.03, 0.03]"),
              "bodies.paddle: the body overlaps the domain wall x_min"),
}


@pytest.mark.parametrize("stage", sorted(BAD_SCENES))
def test_rerun_with_a_bad_scene_leaves_the_previous_complete_run_untouched(binary, tmp_path, stage):
    # A typo in the scene must not cost the user the run already in the folder: the new run
    # fails before it touches DIR, and what is there is still the previous run, complete.
    out = complete_run(binary, tmp_path, "--export-every", "0.05")
    before = snapshot(out)
    assert "particles/frame_000002.vtk" in before and "bodies.csv" in before
    (old, new), message = BAD_SCENES[stage]
    bad = write_scene(tmp_path / "bad", SCENE.replace(old, new))
    result = run(binary, bad, out)
    assert result.returncode == 1
    assert message in result.stderr
    assert str(bad) in result.stderr  # the file to fix
    assert snapshot(out) == before
    assert json.loads((out / "stats.json").read_text())["complete"] is True


def test_rerun_that_diverges_midway_leaves_nothing_that_looks_complete(binary, source_dir, tmp_path):
    # The drop diverges on reaching the floor at t = 0.12 s (scenes/diverging_drop.toml), after
    # it has written frames: the previous run's outputs are gone, stats.json says the run did not
    # complete and why, the CSVs are .part only, and every frame is the new run's.
    out = complete_run(binary, tmp_path, "--export-every", "0.01")
    assert len(list((out / "particles").glob("frame_*.vtk"))) == 11
    scene = source_dir / "tests/sim_gpu/scenes/diverging_drop.toml"
    result = run(binary, scene, out, "--export-every", "0.05")
    assert result.returncode == 1, result.stderr
    assert "haptic-sim: error: simulation diverged at t = 0.12 s: fluid particle " in result.stderr
    assert "is not finite: lower time.dt_s (0.001 s; 0 chooses a stable CFL step), or the stiffness" in result.stderr
    stats = json.loads((out / "stats.json").read_text())
    assert stats["complete"] is False
    assert stats["error"].startswith("simulation diverged at t = 0.12 s: fluid particle ")
    assert stats["scene"] == str(scene) and stats["particles"]["fluid"] == 8
    # The mass of the lattice particle is rho0 s^3 up to the kernel's lattice sum (within 5 %).
    assert abs(stats["fluid_mass_kg"] - 8 * 1000.0 * 0.01 ** 3) < 0.05 * 8 * 1000.0 * 0.01 ** 3
    assert stats["steps"] == 110  # 11 frames of 10 steps passed the check; the 12th did not
    assert not (out / "bodies.csv").exists() and not (out / "couplings.csv").exists()
    assert (out / "bodies.csv.part").exists() and (out / "couplings.csv.part").exists()
    frames = sorted((out / "particles").glob("frame_*.vtk"))
    assert [f.name for f in frames] == ["frame_000000.vtk", "frame_000001.vtk", "frame_000002.vtk"]
    assert stats["frames_exported"] == 3
    for f in frames:
        assert read_vtk(f)["points"].shape[0] == stats["particles"]["total"], f.name


def test_rerun_that_succeeds_keeps_no_frame_of_the_previous_run(binary, tmp_path):
    # The previous run exported more frames than this one: none of them may remain.
    out = complete_run(binary, tmp_path, "--export-every", "0.01")
    assert len(list((out / "particles").glob("frame_*.vtk"))) == 11
    result = run(binary, write_scene(tmp_path / "scene"), out, "--export-every", "0.05")
    assert result.returncode == 0, result.stderr
    stats = json.loads((out / "stats.json").read_text())
    assert stats["complete"] is True and stats["frames_exported"] == 3
    assert [f.name for f in sorted((out / "particles").iterdir())] == \
        ["bodies.vtk.series", "bodies_000000.vtk", "bodies_000001.vtk", "bodies_000002.vtk",
         "frame_000000.vtk", "frame_000001.vtk", "frame_000002.vtk", "particles.vtk.series"]
    series = json.loads((out / "particles" / "particles.vtk.series").read_text())
    assert [e["name"] for e in series["files"]] == ["frame_000000.vtk", "frame_000001.vtk", "frame_000002.vtk"]
    assert not list(out.rglob("*.part"))


def test_a_scene_path_that_is_not_utf8_still_gives_a_readable_stats_file(binary, tmp_path):
    # Linux file names are bytes: a folder named in Latin-1 ("caf\xe9") is a valid path that JSON
    # cannot carry as it is. The run completes and its stats.json parses, the byte replaced.
    folder = pathlib.Path(os.fsdecode(bytes(tmp_path) + b"/caf\xe9"))
    scene = write_scene(folder)
    out = tmp_path / "out"
    result = run(binary, scene, out, "--export-every", "0", "--duration", "0.01")
    assert result.returncode == 0, result.stderr
    stats = json.loads((out / "stats.json").read_bytes().decode("utf-8"))
    assert stats["complete"] is True
    assert stats["scene"].endswith("caf\ufffd/scene.toml")


def test_missing_arguments_print_usage(binary):
    result = subprocess.run([str(binary("haptic-sim"))], capture_output=True, text=True)
    assert result.returncode == 2
    assert result.stderr.startswith("haptic-sim: --scene is required") and len(result.stderr.splitlines()) == 1


def test_an_option_given_twice_takes_its_last_value(binary, tmp_path):
    # Launchers and test harnesses append overrides to a base command line.
    out = tmp_path / "out"
    result = run(binary, write_scene(tmp_path / "scene"), out, "--threads", "3", "--export-every", "0")
    assert result.returncode == 0, result.stderr
    assert json.loads((out / "stats.json").read_text())["threads"] == 3


def test_batch_mode_needs_an_output_folder_and_live_options_need_live(binary, tmp_path):
    scene = str(write_scene(tmp_path / "scene"))
    result = subprocess.run([str(binary("haptic-sim")), "--scene", scene], capture_output=True, text=True)
    assert result.returncode == 2 and "--out is required in batch mode" in result.stderr
    result = subprocess.run([str(binary("haptic-sim")), "--scene", scene, "--out", str(tmp_path / "out"), "--max-lag",
                             "0.2"], capture_output=True, text=True)
    assert result.returncode == 2 and "--max-lag requires --live" in result.stderr, result.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("option, value, reason", [
    # Integer options take whole numbers only: 2.5 threads was silently run as 2.
    ("--threads", "2.5", "must be a whole number in 1..256"),
    ("--threads", "2threads", "not a number (must be a whole number in 1..256)"),
    ("--threads", " 2", "not a number (must be a whole number in 1..256)"),
    ("--threads", "-1", "must be a whole number in 1..256"),
    ("--threads", "0", "must be a whole number in 1..256"),
    ("--threads", "1e2", "must be a whole number in 1..256"),
    ("--threads", "99999999999", "must be a whole number in 1..256"),
    # Durations are finite seconds, and a batch run's is more than none.
    ("--duration", "inf", "must be a finite number of seconds >= 0"),
    ("--duration", "nan", "must be a finite number of seconds >= 0"),
    ("--duration", "-0.1", "must be >= 0 s"),
    ("--duration", "0", "must be > 0 s in batch mode"),
    ("--duration", "1s", "not a number (must be a number of seconds >= 0)"),
    ("--export-every", "-0.01", "must be >= 0 s"),
    ("--export-every", "inf", "must be a finite number of seconds >= 0"),
])
def test_numeric_options_are_strict_and_name_option_and_value(binary, tmp_path, option, value, reason):
    scene = write_scene(tmp_path / "scene")
    result = run(binary, scene, tmp_path / "out", option, value)
    assert result.returncode == 2
    assert result.stderr.startswith(f"haptic-sim: {option}: {reason}, not \"{value}\"")
    assert len(result.stderr.splitlines()) == 1
    assert not (tmp_path / "out").exists()  # refused before anything ran


@pytest.mark.parametrize("option, value, reason", [
    ("--threads", "1.5", "must be a whole number in 1..256"),
    ("--duration", "inf", "must be a finite number of seconds >= 0"),
    ("--max-lag", "0", "must be >= 0.001 s"),
    ("--status-every", "-1", "must be >= 0 s"),
])
def test_live_numeric_options_are_strict_too(binary, tmp_path, option, value, reason):
    result = subprocess.run([str(binary("haptic-sim")), "--live", "--scene", str(write_scene(tmp_path / "scene")),
                             option, value], capture_output=True, text=True, timeout=30)
    assert result.returncode == 2
    assert result.stderr.startswith(f"haptic-sim: {option}: {reason}, not \"{value}\"")


def live_run(binary, scene, out, prefix, duration_s="0.6"):
    return subprocess.run([str(binary("haptic-sim")), "--live", "--scene", str(scene), "--backend", "cpu", "--threads",
                           "1", "--duration", duration_s, "--status-every", "0.1", "--shm-prefix", prefix, "--out",
                           str(out)], capture_output=True, text=True, timeout=60)


def test_the_live_sim_tells_systemd_it_is_ready_alive_and_stopping(binary, tmp_path):
    # haptic-sim.service is Type=notify with a WatchdogSec: READY=1 once it publishes, WATCHDOG=1
    # at half of WATCHDOG_USEC while it runs, STOPPING=1 at the end (libsystemd's sd_notify). The
    # socket is read while it runs, as systemd does: a full datagram queue would hold the sender.
    import socket
    path = str(tmp_path / "notify.sock")
    server = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    server.bind(path)
    server.settimeout(0.2)
    env = dict(os.environ, NOTIFY_SOCKET=path, WATCHDOG_USEC="100000")
    sim = subprocess.Popen([str(binary("haptic-sim")), "--live", "--scene", str(write_scene(tmp_path / "scene")),
                            "--backend", "cpu", "--threads", "1", "--duration", "0.6", "--status-every", "0",
                            "--shm-prefix", f"hapfluid-test-notify-{os.getpid()}"],
                           env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    messages = []
    while True:
        try:
            messages.append(server.recv(4096).decode())
            if messages[-1] == "STOPPING=1":
                break
        except socket.timeout:
            if sim.poll() is not None:
                break
    _, err = sim.communicate(timeout=30)
    server.close()
    assert sim.returncode == 0, err
    assert messages and messages[0] == "READY=1", messages
    assert "WATCHDOG=1" in messages and messages[-1] == "STOPPING=1", messages


def test_the_live_runner_reports_the_wall_clamp_as_a_fault(binary, source_dir, tmp_path):
    # A drop that falls through its floor's pressure (clamping_drop.toml): the live run says so
    # once, when the clamp first acts, counts it in its status lines and in stats.json, as a
    # batch run does; a scene whose walls hold says nothing of it and counts 0.
    result = live_run(binary, source_dir / "tests/sim_gpu/scenes/clamping_drop.toml", tmp_path / "drop",
                      f"hapfluid-test-clamp-{os.getpid()}")
    assert result.returncode == 0, result.stderr
    warnings = [l for l in result.stderr.splitlines() if "last-resort clamp" in l]
    assert len(warnings) == 1 and warnings[0].startswith("haptic-sim: WARNING "), result.stderr
    assert any(l.startswith("haptic-sim: t = ") and "wall clamps" in l for l in result.stderr.splitlines()), result.stderr
    stats = json.loads((tmp_path / "drop" / "stats.json").read_text())
    assert stats["clamped_particle_events"] > 0 and stats["solver"] == "wcsph"
    batch = run(binary, source_dir / "tests/sim_gpu/scenes/clamping_drop.toml", tmp_path / "batch", "--export-every", "0")
    assert batch.returncode == 0, batch.stderr
    assert json.loads((tmp_path / "batch" / "stats.json").read_text())["clamped_particle_events"] > 0

    calm = live_run(binary, write_scene(tmp_path / "calm"), tmp_path / "calm-out", f"hapfluid-test-calm-{os.getpid()}",
                    duration_s="0.3")
    assert calm.returncode == 0, calm.stderr
    assert "clamp" not in calm.stderr
    assert json.loads((tmp_path / "calm-out" / "stats.json").read_text())["clamped_particle_events"] == 0


def test_the_live_sim_reports_how_many_threads_it_stepped_with(binary, tmp_path):
    # With two worker threads the live sim times both counts as it runs and steps with the faster
    # (live/thread_choice.hpp); stats.json and the status lines say what it used. One thread has
    # nothing to choose.
    scene = write_scene(tmp_path / "scene")
    for threads in ("2", "1"):
        out = tmp_path / f"out{threads}"
        result = subprocess.run([str(binary("haptic-sim")), "--live", "--scene", str(scene), "--backend", "cpu",
                                 "--threads", threads, "--duration", "0.6", "--status-every", "0.1", "--shm-prefix",
                                 f"hapfluid-test-threads-{threads}-{os.getpid()}", "--out", str(out)],
                                capture_output=True, text=True, timeout=60)
        assert result.returncode == 0, result.stderr
        stats = json.loads((out / "stats.json").read_text())
        choice = stats["thread_choice"]
        assert choice["steps_with_all"] + choice["steps_with_one"] == stats["steps"] > 0
        assert choice["chosen"] in (1, int(threads))
        # What the steps did, as a batch run's stats.json says it: a live run is diagnosed the same way.
        assert stats["phase_ms_per_step"]["neighbour_search"] > 0, stats
        assert set(stats["solver_iterations"]) >= {"density_per_step", "unconverged_solves"}, stats
        status = [l for l in result.stderr.splitlines() if l.startswith("haptic-sim: t = ")]
        assert status and all(" thread(s), " in l for l in status), result.stderr
        if threads == "1":
            assert choice == {"chosen": 1, "probes": 0, "steps_with_all": stats["steps"], "steps_with_one": 0}
        else:
            assert choice["steps_with_one"] > 0 and choice["steps_with_all"] > 0  # the first probe ran
