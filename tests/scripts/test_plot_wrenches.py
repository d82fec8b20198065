"""The figure script reads wrench histories and draws one force and one torque panel per device;
bad CSVs are rejected with the file and the reason."""
import math
import subprocess
import sys

import matplotlib.image
import pytest


def write_history(path, devices, rows=200, gain=1.0):
    lines = ["t,device,body,fx,fy,fz,tx,ty,tz"]
    for i in range(rows):
        t = i * 0.01
        for d in devices:
            f = gain * math.sin(2 * math.pi * t)
            lines.append(f"{t:.3f},{d},b,{f:.5f},0,{-9.81 * 0.1:.5f},0,{0.1 * f:.5f},0")
    path.write_text("\n".join(lines) + "\n")


def run(source_dir, *args):
    return subprocess.run([sys.executable, "-m", "hapfluid.plot_wrenches", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def test_two_devices_give_two_columns_of_panels(source_dir, tmp_path):
    write_history(tmp_path / "couplings.csv", ["left", "right"])
    result = run(source_dir, tmp_path, "--out", tmp_path / "fig9.png", "--title", "pouring")
    assert result.returncode == 0, result.stderr
    image = matplotlib.image.imread(tmp_path / "fig9.png")
    assert image.shape[1] > image.shape[0]  # two device columns side by side: wider than tall


def test_several_runs_are_overlaid(source_dir, tmp_path):
    runs = []
    for v in (2, 10, 20, 40):
        run_dir = tmp_path / f"glass_{v}"
        run_dir.mkdir()
        write_history(run_dir / "couplings.csv", ["hand"], gain=v)
        runs.append(run_dir)
    result = run(source_dir, *runs, "--out", tmp_path / "fig10.png", "--labels", "2,10,20,40", "--torque-component", "y")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "fig10.png").stat().st_size > 10_000


def test_missing_columns_are_named(source_dir, tmp_path):
    (tmp_path / "couplings.csv").write_text("t,fx\n0,1\n")
    result = run(source_dir, tmp_path / "couplings.csv", "--out", tmp_path / "x.png")
    assert result.returncode != 0
    assert "missing columns fy, fz, tx, ty, tz" in result.stderr
    assert not (tmp_path / "x.png").exists()


def test_each_scene_plots_the_components_its_figure_shows(source_dir):
    # Fig. 8b: a norm hides the sign, so stirring plots the stroke axis (x) and the torque about
    # the axis across it (y); the glass its spin axis (fig. 10); scenes without an entry the norms.
    from hapfluid import plot_wrenches as plot
    stirring = plot.scene_components("spoon_stirring")
    assert (stirring.force, stirring.torque) == ("x", "y") and "stroke" in stirring.force_meaning
    assert plot.scene_components("spinning_glass_40").torque == "z"
    assert plot.scene_components(str(source_dir / "config" / "scenes" / "bowl_pouring.toml")).force == "z"
    other = plot.scene_components("dam_break")
    assert (other.force, other.torque) == ("norm", "norm")


def test_the_wall_clock_axis_needs_wall_s_and_says_so(source_dir, tmp_path):
    # --time wall plots against the hand's clock (column wall_s); a CSV without it is refused by name.
    write_history(tmp_path / "couplings.csv", ["hand"])
    result = run(source_dir, tmp_path / "couplings.csv", "--out", tmp_path / "x.png", "--time", "wall")
    assert result.returncode != 0 and "missing columns wall_s" in result.stderr


def test_a_scene_on_the_script_clock_gets_its_motions_marked(source_dir, tmp_path):
    lines = ["t,wall_s,device,body,fx,fy,fz,tx,ty,tz"]
    lines += [f"{i * 0.01:.2f},{i * 0.01 + 0.5:.2f},hand,spoon,{math.sin(i * 0.03):.4f},0,0,0,0.01,0" for i in range(900)]
    (tmp_path / "couplings.csv").write_text("\n".join(lines) + "\n")
    result = run(source_dir, tmp_path / "couplings.csv", "--out", tmp_path / "fig8.png", "--scene", "spoon_stirring",
                 "--time", "wall", "--time-offset", "0.5")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "fig8.png").stat().st_size > 10_000


def test_the_glass_figure_adds_the_fluids_torque_on_the_glass(source_dir, tmp_path):
    # Fig. 10: the hand's torque is mostly the glass's own inertia; with a bodies.csv beside the
    # couplings, a third panel shows the fluid's torque on the glass, placed on the wall clock by
    # the coupling rows (here the wall clock runs 0.5 s ahead of simulated time).
    lines = ["t,wall_s,device,body,fx,fy,fz,tx,ty,tz"]
    lines += [f"{i * 0.01:.2f},{i * 0.01 + 0.5:.2f},hand,glass,0,0,-4.4,0,0,{0.02 * math.sin(i * 0.03):.5f}"
              for i in range(600)]
    (tmp_path / "couplings.csv").write_text("\n".join(lines) + "\n")
    bodies = ["t,body,px,py,pz,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,fx,fy,fz,tx,ty,tz"]
    bodies += [f"{i * 0.04:.2f},glass,0,0,0,1,0,0,0,0,0,0,0,0,6.28,0,0,0,0,0,{0.004 * math.sin(i * 0.12):.5f}"
               for i in range(150)]
    figures = {}
    for name in ("without", "with"):
        if name == "with":
            (tmp_path / "bodies.csv").write_text("\n".join(bodies) + "\n")
        result = run(source_dir, tmp_path, "--out", tmp_path / f"{name}.png", "--scene", "spinning_glass_10",
                     "--time", "wall", "--time-offset", "0.5")
        assert result.returncode == 0, result.stderr
        figures[name] = matplotlib.image.imread(tmp_path / f"{name}.png").shape
    # Three panels instead of two, one column: half again as tall, as wide.
    assert figures["with"][1] == figures["without"][1]
    assert figures["with"][0] == round(figures["without"][0] * 1.5)

    from hapfluid import plot_wrenches as plot
    fluid = plot.read_fluid_torque(tmp_path / "couplings.csv", "glass", {"hand"}, "wall_s", 0.5)
    assert fluid["t"][:3].tolist() == pytest.approx([0.0, 0.04, 0.08])  # sim time on the wall clock, minus the offset
    assert fluid["tz"][10] == pytest.approx(0.004 * math.sin(1.2), abs=1e-5)
    assert plot.read_fluid_torque(tmp_path / "couplings.csv", "bucket", {"hand"}, "wall_s", 0.5) is None
