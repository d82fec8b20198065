"""The SPlisHSPlasH comparison runs the same case as our scene file and reads SPlisHSPlasH's own
timing: the scene JSON must carry the TOML's geometry in our coordinates, and the exit summary
of `splash` (a captured 2.19.0 run) must give the step time, step count and iterations. None of
this needs the pysplishsplash wheel."""
import math

import numpy as np
import pytest

SAMPLE_LOG = "tests/scripts/splishsplash/dam_break_splash.log"


@pytest.fixture(scope="module")
def splishsplash(script):
    return script("splishsplash")


def test_timing_summary_gives_step_time_steps_dt_and_iterations(splishsplash, source_dir):
    # Numbers as printed by that run: 276 steps of 90.77 ms in 25.05 s, dt 0.106 ms, 4.2 iterations.
    s = splishsplash.parse_timing_summary((source_dir / SAMPLE_LOG).read_text())
    assert s["fluid_particles"] == 6669
    assert s["step_time_sum_ms"] == pytest.approx(25053.2)
    assert s["steps"] == 276
    assert s["mean_dt_s"] == pytest.approx(0.000105583)
    assert s["simulated_time_s"] == pytest.approx(0.029141)
    assert s["mean_pressure_iterations"] == pytest.approx(4.19565)
    assert s["mean_divergence_iterations"] == pytest.approx(1.31522)
    assert s["volume_map_ms"] == pytest.approx(14468.3)


def test_a_run_cut_before_its_summary_is_rejected_naming_what_is_missing(splishsplash, source_dir):
    text = (source_dir / SAMPLE_LOG).read_text()
    cut = text[:text.index("Average time: SimStep")]
    with pytest.raises(ValueError, match="step_time_sum_ms"):
        splishsplash.parse_timing_summary(cut)


@pytest.fixture
def dam_break_json(splishsplash, source_dir, tmp_path):
    return splishsplash.scene_json(source_dir / "config/scenes/dam_break.toml", tmp_path / "box.obj")


def test_dam_break_fluid_is_the_tomls_column_a_by_2a(dam_break_json):
    # Martin & Moyce: a = 0.1 m column, 2a high, 0.05 m slab, at the tank's x = 0 corner.
    (block,) = dam_break_json["FluidBlocks"]
    assert block["start"] == pytest.approx([0.0, 0.0, 0.0])
    assert block["end"] == pytest.approx([0.10, 0.05, 0.20])
    assert block["denseMode"] == 0  # a regular lattice, as hapfluid's


def test_dam_break_wall_box_is_the_tomls_tank(dam_break_json):
    # The unit box scaled and centred onto the 0.5 x 0.05 x 0.3 m domain: its faces are the walls.
    (box,) = dam_break_json["RigidBodies"]
    lo = [c - 0.5 * e for c, e in zip(box["translation"], box["scale"])]
    hi = [c + 0.5 * e for c, e in zip(box["translation"], box["scale"])]
    assert lo == pytest.approx([0.0, 0.0, 0.0])
    assert hi == pytest.approx([0.50, 0.05, 0.30])
    assert box["isWall"] and not box["isDynamic"] and box["mapInvert"]
    # A wall thickness of one particle radius: the lattice starts at rest against it.
    assert box["mapThickness"] == pytest.approx(0.0025)


def test_dam_break_runs_dfsph_at_the_tomls_resolution_gravity_and_step_cap(dam_break_json):
    c = dam_break_json["Configuration"]
    assert c["simulationMethod"] == 4  # DFSPH
    assert c["particleRadius"] == pytest.approx(0.0025)  # half the 5 mm spacing: support 4 r = h = 10 mm
    assert c["gravitation"] == pytest.approx([0.0, 0.0, -9.81])  # z up, as our scenes
    assert c["cflMaxTimeStepSize"] == pytest.approx(0.002)  # hapfluid's default time.max_dt_s
    assert dam_break_json["Materials"][0]["density0"] == pytest.approx(1000.0)


def test_volume_map_cells_are_two_support_radii_over_the_padded_box(dam_break_json):
    # 8 h padding each side (h = 10 mm): 0.66 x 0.21 x 0.46 m in cells of 20 mm.
    assert dam_break_json["RigidBodies"][0]["mapResolution"] == [33, 11, 23]


def test_box_mesh_faces_point_out_of_the_box(splishsplash):
    # SPlisHSPlasH's mapInvert puts the fluid inside: that needs outward faces (as its UnitBox.obj).
    lines = splishsplash.UNIT_BOX_OBJ.splitlines()
    vertices = [tuple(map(float, l.split()[1:])) for l in lines if l.startswith("v ")]
    faces = [tuple(int(i) - 1 for i in l.split()[1:]) for l in lines if l.startswith("f ")]
    assert len(vertices) == 8 and len(faces) == 12
    for a, b, c in faces:
        pa, pb, pc = vertices[a], vertices[b], vertices[c]
        u = [pb[k] - pa[k] for k in range(3)]
        v = [pc[k] - pa[k] for k in range(3)]
        normal = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        centre = [(pa[k] + pb[k] + pc[k]) / 3 for k in range(3)]
        assert sum(n * x for n, x in zip(normal, centre)) > 0, f"face {a + 1} {b + 1} {c + 1} points inward"


def test_bench_pool_is_bench_scenes_32k_pool(splishsplash, source_dir):
    # bench_scenes.hpp pool_scene(n = 32000): spacing cbrt(0.25 m^3 / n), 1 x 1 m, 0.25 m deep.
    case = splishsplash.load_case(source_dir / "sim_gpu/bench/pool_32k.toml")
    assert case["spacing_m"] == pytest.approx(math.cbrt(0.25 / 32000), rel=1e-6)
    assert case["blocks"] == [((0.0, 0.0, 0.0), (1.0, 1.0, 0.25))]
    assert case["domain_max_m"] == (1.0, 1.0, 0.5)


def test_scene_with_bodies_is_refused_naming_file_and_key(splishsplash, tmp_path):
    scene = tmp_path / "stir.toml"
    scene.write_text('[domain]\nmin_m = [0,0,0]\nmax_m = [1,1,1]\n[fluid]\nparticle_spacing_m = 0.02\n'
                     '[[fluid.blocks]]\nmin_m = [0,0,0]\nmax_m = [1,1,0.5]\n[[bodies]]\nname = "spoon"\n')
    with pytest.raises(splishsplash.SceneError, match=r"stir\.toml: \[\[bodies\]\]"):
        splishsplash.load_case(scene)


def test_support_radius_other_than_two_spacings_is_refused(splishsplash, tmp_path):
    # SPlisHSPlasH's kernel support is fixed at 4 particle radii: another h is another case.
    scene = tmp_path / "wide.toml"
    scene.write_text('[domain]\nmin_m = [0,0,0]\nmax_m = [1,1,1]\n[fluid]\nparticle_spacing_m = 0.02\n'
                     'support_radius_m = 0.05\n[[fluid.blocks]]\nmin_m = [0,0,0]\nmax_m = [1,1,0.5]\n')
    with pytest.raises(splishsplash.SceneError, match=r"wide\.toml: fluid\.support_radius_m = 0\.05"):
        splishsplash.load_case(scene)


def test_tank_at_rest_runs_at_the_scenes_water_viscosity_and_settling(splishsplash, source_dir, tmp_path):
    # The rest comparison gives SPlisHSPlasH the scene's viscosity, mu / rho0 (water: 1e-6 m^2/s),
    # not the 0.01 of its own water scenes, and settles it for the scene's fluid.settle_s.
    scene = source_dir / "sim_gpu/bench/tank_at_rest_dfsph.toml"
    case = splishsplash.load_case(scene)
    assert case["settle_s"] == 0.5 and case["duration_s"] == 5.0
    nu = splishsplash.scene_kinematic_viscosity(scene)
    assert nu == pytest.approx(0.001 / 1000.0)
    json_scene = splishsplash.scene_json(scene, tmp_path / "box.obj", kinematic_viscosity=nu)
    assert json_scene["Materials"][0]["Standard viscosity"]["viscosity"] == pytest.approx(1e-6)
    assert json_scene["Configuration"]["cflMaxTimeStepSize"] == 0.005
    default = splishsplash.scene_json(scene, tmp_path / "box.obj")
    assert default["Materials"][0]["Standard viscosity"]["viscosity"] == splishsplash.WATER_VISCOSITY


def test_settling_default_and_kept_fraction_are_hapfluids(splishsplash, source_dir):
    # Both codes must settle alike: the constants the comparison copies are the solver's own.
    header = (source_dir / "config/include/hapfluid/config/scene.hpp").read_text()
    assert f"double settle_s = {splishsplash.DEFAULT_SETTLE_S};" in header
    solver = (source_dir / "sim_gpu/include/hapfluid/sim/dfsph_solver.hpp").read_text()
    assert f"constexpr float kSettleVelocityKept = {splishsplash.SETTLE_VELOCITY_KEPT}f;" in solver


def test_at_rest_summary_is_the_last_seconds_rms_and_largest_speed(script):
    bench = script("bench_splishsplash")
    rows = [(0.0, 0.01, 0.05, 1000.0), (3.9, 0.5, 0.9, 1000.0), (4.0, 0.03, 0.2, 1001.0), (4.5, 0.04, 0.1, 1001.0),
            (5.0, 0.0, 0.3, 1002.0)]
    m = bench.at_rest_metrics(rows, 5.0, 1000.0)
    assert m["rms_speed_last_s_m_s"] == pytest.approx(math.sqrt((0.03 ** 2 + 0.04 ** 2 + 0.0) / 3))
    assert m["max_speed_last_s_m_s"] == 0.3
    assert m["max_speed_after_settling_m_s"] == 0.9
    assert m["rms_speed_final_m_s"] == 0.0 and m["mean_density_error_final"] == pytest.approx(0.002)
    with pytest.raises(ValueError, match="no samples in the last 1.0 s of 10.0 s"):
        bench.at_rest_metrics(rows, 10.0, 1000.0)


def test_front_errors_are_against_the_measurement_between_its_points_from_t_0_5(script, shared_dir, tmp_path):
    bench = script("bench_splishsplash")
    table = bench.read_front_table(shared_dir / "data/martin_moyce_1952_n2_2_front.csv")
    assert len(table[0]) == 15 and table[0][0] == 0.41 and table[1][-1] == 4.11
    T, Z = table
    # 10 % ahead everywhere from T = 0.5 on; the samples before it (the gate's transient) do not count.
    samples = [(0.0, 1.0), (0.45, 5.0)] + [(t, 1.1 * float(np.interp(t, T, Z))) for t in np.linspace(0.5, 3.3, 12)]
    m = bench.front_metrics(samples, table)
    assert m["front_samples"] == 12 and m["front_z_at_start"] == 1.0
    assert m["front_mean_error"] == pytest.approx(0.10) and m["front_worst_abs_error"] == pytest.approx(0.10)
    # Behind is negative, and the worst error keeps its sign.
    samples[5] = (samples[5][0], 0.8 * float(np.interp(samples[5][0], T, Z)))
    assert bench.front_metrics(samples, table)["front_worst_error"] == pytest.approx(-0.2)
    with pytest.raises(ValueError, match="3 front samples within T = 0.5-3.33; expected 10 or more"):
        bench.front_metrics(samples[:5], table)
    with pytest.raises(ValueError, match="the measured dam-break front is missing"):
        bench.read_front_table(tmp_path / "none.csv")
