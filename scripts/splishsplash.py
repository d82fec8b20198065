"""SPlisHSPlasH (the `pysplishsplash` wheel) as a reference solver for hapfluid's scenes.

Three things, each a function of its inputs except `run`:
  - `scene_json(scene_toml, box_obj)`: the same case as one of our scene files, in
    SPlisHSPlasH's scene format: the TOML's fluid blocks, the domain box as a wall, DFSPH;
  - `parse_timing_summary(text)`: the timing summary `splash` prints at exit;
  - `run(scene_json_path, ...)`: `splash --no-gui` on it, with the wheel's own libGLdispatch
    preloaded, timed as a whole process.

Coordinates are ours (z up): SPlisHSPlasH takes any gravity vector, so nothing is rotated and
the JSON's numbers can be compared with the TOML's directly.
"""
import csv
import glob
import importlib.util
import math
import os
import pathlib
import re
import subprocess
import sys
import time
import tomllib

import numpy as np

SIMULATION_METHOD_DFSPH = 4
BOUNDARY_VOLUME_MAPS = 2  # Bender et al. 2019, as SPlisHSPlasH's own DamBreakModel scene
VISCOSITY_STANDARD = 1
DFSPH_MAX_DENSITY_ERROR_PERCENT = 0.05  # SPlisHSPlasH's DamBreakModel values
DFSPH_MAX_DIVERGENCE_ERROR_PERCENT = 0.1
WATER_VISCOSITY = 0.01  # SPlisHSPlasH's standard viscosity coefficient in its water scenes
# SPlisHSPlasH's volume map covers the box plus 8 support radii on each side (its log: "Domain -
# min"); its own scenes give it cells of 1.4-2 support radii (DamBreakModel: 40 x 30 x 15 over
# 5.6 x 4.6 x 3.1 m, h = 0.1 m); a resolution of the box's extent / h would leave the dam
# break's 5 cm slab (21 cm with the padding) 5 cells of 4 h across.
VOLUME_MAP_PADDING_SUPPORTS = 8
VOLUME_MAP_CELL_SUPPORTS = 2
DEFAULT_MAX_DT_S = 0.002  # hapfluid's time.max_dt_s default (config/include/hapfluid/config/scene.hpp)
DEFAULT_SETTLE_S = 0.5    # its fluid.settle_s default (the same header)
SETTLE_VELOCITY_KEPT = 0.8  # the velocity fraction its settling keeps after each step (sim_gpu/include/hapfluid/sim/dfsph_solver.hpp)

# A unit cube centred on the origin, faces wound outward; scaled and moved onto the domain box.
UNIT_BOX_OBJ = """# unit cube centred on the origin (hapfluid bench: SPlisHSPlasH wall box)
v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
f 1 4 3
f 1 3 2
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 4 8 7
f 4 7 3
f 1 5 8
f 1 8 4
f 2 3 7
f 2 7 6
"""


class SceneError(ValueError):
    """A scene file that this translation cannot express; the message names file and key."""


def _vec3(table: dict, key: str, where: str) -> tuple:
    value = table.get(key)
    if not (isinstance(value, list) and len(value) == 3 and all(isinstance(v, (int, float)) for v in value)):
        raise SceneError(f"{where}.{key} = {value!r}: expected three numbers")
    return tuple(float(v) for v in value)


def load_case(scene_toml: pathlib.Path) -> dict:
    """The parts of a hapfluid scene the translation uses, checked; SceneError names what is missing."""
    path = pathlib.Path(scene_toml)
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as error:
        raise SceneError(f"{path}: {error}") from error
    if data.get("bodies"):
        raise SceneError(f"{path}: [[bodies]]: the SPlisHSPlasH comparison takes fluid-only scenes")
    domain, fluid, time_table = data.get("domain", {}), data.get("fluid", {}), data.get("time", {})
    spacing = fluid.get("particle_spacing_m")
    if not isinstance(spacing, (int, float)) or spacing <= 0:
        raise SceneError(f"{path}: fluid.particle_spacing_m = {spacing!r}: must be > 0")
    spacing = float(spacing)
    support = float(fluid.get("support_radius_m", 0.0)) or 2.0 * spacing
    if not math.isclose(support, 2.0 * spacing, rel_tol=1e-9):
        # SPlisHSPlasH's kernels reach 4 particle radii = 2 spacings; anything else is another case.
        raise SceneError(f"{path}: fluid.support_radius_m = {support}: the comparison needs 2 x particle_spacing_m")
    blocks = []
    for i, b in enumerate(fluid.get("blocks", [])):
        where = f"{path}: fluid.blocks[{i}]"
        lo, hi = _vec3(b, "min_m", where), _vec3(b, "max_m", where)
        blocks.append((lo, hi))
    if not blocks:
        raise SceneError(f"{path}: fluid.blocks: no fluid")
    return {
        "name": data.get("name", path.stem),
        "duration_s": float(data.get("duration_s", 10.0)),
        "domain_min_m": _vec3(domain, "min_m", f"{path}: domain"),
        "domain_max_m": _vec3(domain, "max_m", f"{path}: domain"),
        "spacing_m": spacing,
        "rest_density_kg_m3": float(fluid.get("rest_density_kg_m3", 1000.0)),
        "gravity_m_s2": _vec3(fluid, "gravity_m_s2", f"{path}: fluid") if "gravity_m_s2" in fluid else (0.0, 0.0, -9.81),
        "max_dt_s": float(time_table.get("max_dt_s", DEFAULT_MAX_DT_S)),
        "viscosity_pa_s": float(fluid.get("viscosity_pa_s", 0.0)),
        "settle_s": float(fluid.get("settle_s", DEFAULT_SETTLE_S)),
        "blocks": blocks,
    }


def scene_json(scene_toml: pathlib.Path, box_obj: pathlib.Path, kinematic_viscosity: float = WATER_VISCOSITY) -> dict:
    """SPlisHSPlasH's scene for the case of `scene_toml`; `box_obj` is where UNIT_BOX_OBJ is written.
    `kinematic_viscosity` (m^2/s) is its standard viscosity's coefficient: by default that of its
    own water scenes; `scene_kinematic_viscosity` gives the scene's fluid.viscosity_pa_s / rho0.

    Fluid: the TOML's blocks as they are. SPlisHSPlasH fills a block one particle diameter in
    from each face (start + d, ..., end - d), hapfluid from half a spacing in, so it starts
    with fewer particles for the same volume (dam break: 19 x 9 x 39 = 6669 against 20 x 10 x 40);
    the figure of merit is per particle. Walls: the domain box, closed (our domains' tops are
    open: a splash reaching the top meets SPlisHSPlasH's lid). Time step: SPlisHSPlasH's CFL
    step, capped at the scene's time.max_dt_s like hapfluid's (its scenes' usual 5 ms would let
    the first step of a fluid at rest, whose CFL bound is unbounded, be 2.5 times hapfluid's).
    """
    case = load_case(scene_toml)
    s, radius = case["spacing_m"], 0.5 * case["spacing_m"]
    lo, hi = case["domain_min_m"], case["domain_max_m"]
    extent = [hi[a] - lo[a] for a in range(3)]
    support = 2.0 * s
    fluid_blocks = [{"denseMode": 0, "start": list(lo_b), "end": list(hi_b)} for lo_b, hi_b in case["blocks"]]  # 0: lattice
    return {
        "Configuration": {
            "particleRadius": radius,
            "simulationMethod": SIMULATION_METHOD_DFSPH,
            "gravitation": list(case["gravity_m_s2"]),
            "timeStepSize": case["max_dt_s"],
            "cflMethod": 1,
            "cflFactor": 1,
            "cflMaxTimeStepSize": case["max_dt_s"],
            "boundaryHandlingMethod": BOUNDARY_VOLUME_MAPS,
            "enablePartioExport": False,
            "enableVTKExport": False,
            "enableRigidBodyExport": False,
            "DFSPH": {
                "minIterations": 2,
                "maxIterations": 100,
                "maxError": DFSPH_MAX_DENSITY_ERROR_PERCENT,
                "maxIterationsV": 100,
                "maxErrorV": DFSPH_MAX_DIVERGENCE_ERROR_PERCENT,
                "enableDivergenceSolver": True,
            },
        },
        "Materials": [{
            "id": "Fluid",
            "density0": case["rest_density_kg_m3"],
            "viscosityMethod": VISCOSITY_STANDARD,
            "Standard viscosity": {"viscosity": kinematic_viscosity},
        }],
        "RigidBodies": [{
            "geometryFile": str(pathlib.Path(box_obj).resolve()),
            "translation": [0.5 * (lo[a] + hi[a]) for a in range(3)],
            "rotationAxis": [1, 0, 0],
            "rotationAngle": 0,
            "scale": extent,
            "isDynamic": False,
            "isWall": True,
            "mapInvert": True,  # the fluid is inside the box
            # At thickness 0 this wall's density excess throws a lattice starting one spacing off it
            # apart in the first step (m/s after 1 ms); at one particle radius the same lattice
            # starts at rest (its first step is free fall, g dt), and the fluid keeps to the walls.
            "mapThickness": radius,
            "mapResolution": [math.ceil((e + 2 * VOLUME_MAP_PADDING_SUPPORTS * support) / (VOLUME_MAP_CELL_SUPPORTS * support))
                              for e in extent],
        }],
        "FluidBlocks": fluid_blocks,
    }


_NUMBER = r"([-+0-9.eE]+)"
_SUMMARY = {
    "step_time_sum_ms": rf"^Time sum: SimStep: {_NUMBER} ms",
    "mean_step_time_ms": rf"^Average time: SimStep: {_NUMBER} ms",
    "mean_dt_s": rf"^Average number: Time step size: {_NUMBER}",
    "simulated_time_s": rf"^Total number: Time step size: {_NUMBER}",
    "mean_pressure_iterations": rf"^Average number: DFSPH - iterations: {_NUMBER}",
    "mean_divergence_iterations": rf"^Average number: DFSPH - iterationsV: {_NUMBER}",
    "fluid_particles": rf"^Number of fluid particles: {_NUMBER}",
    "volume_map_ms": rf"^time Volume Map Construction: {_NUMBER} ms",
}


def parse_timing_summary(text: str) -> dict:
    """The numbers of `splash`'s exit summary; ValueError names what is missing. Steps = time sum
    / average time of 'SimStep'; the simulated time is the sum of the timed steps' sizes ('Total
    number: Time step size')."""
    found = {}
    for key, pattern in _SUMMARY.items():
        matches = re.findall(pattern, text, flags=re.MULTILINE)
        if matches:
            found[key] = float(matches[-1])
    missing = [k for k in ("step_time_sum_ms", "mean_step_time_ms", "mean_dt_s", "simulated_time_s", "fluid_particles")
               if k not in found]
    if missing:
        raise ValueError(f"SPlisHSPlasH output lacks {', '.join(missing)} (did the run finish?)")
    found["fluid_particles"] = int(found["fluid_particles"])
    found["steps"] = round(found["step_time_sum_ms"] / found["mean_step_time_ms"]) if found["mean_step_time_ms"] > 0 else 0
    return found


def scene_kinematic_viscosity(scene_toml: pathlib.Path) -> float:
    """The scene's fluid viscosity as SPlisHSPlasH's coefficient: mu / rho0, m^2/s."""
    case = load_case(scene_toml)
    return case["viscosity_pa_s"] / case["rest_density_kg_m3"]


def installed_package_dir() -> pathlib.Path:
    spec = importlib.util.find_spec("pysplishsplash")
    if spec is None or spec.origin is None:
        raise RuntimeError("pysplishsplash is not installed in this Python: run scripts/install-deps.sh bench")
    return pathlib.Path(spec.origin).parent


def gl_dispatch_preload() -> str:
    """The wheel's own libGLdispatch: on Debian 12 the import crashes when the system's is met first."""
    found = sorted(glob.glob(str(installed_package_dir() / "pysplishsplash.libs" / "libGLdispatch-*.so*")))
    if not found:
        raise RuntimeError(f"{installed_package_dir() / 'pysplishsplash.libs'}: no libGLdispatch-*.so: is pysplishsplash 2.19 installed?")
    return found[0]


def run(scene_path: pathlib.Path, stop_at_s: float, out_dir: pathlib.Path, threads: int, timeout_s: float) -> dict:
    """Runs `splash --no-gui` on a scene JSON; the parsed summary plus the process's wall time.
    SPlisHSPlasH parallelises with OpenMP, so OMP_NUM_THREADS sets its thread count."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), LD_PRELOAD=gl_dispatch_preload())
    # The console script's entry point, run by this interpreter (its shebang may name another path).
    command = [sys.executable, "-c", "import sys; from pySPlisHSPlasH.scripts.simulator import main; sys.exit(main())",
               "--no-gui", "--stopAt", repr(stop_at_s), "--no-cache", "--output-dir", str(pathlib.Path(out_dir).resolve()),
               str(pathlib.Path(scene_path).resolve())]
    started = time.monotonic()
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=timeout_s)
    wall = time.monotonic() - started
    (pathlib.Path(out_dir) / "splash.log").write_text(result.stdout + result.stderr)
    if result.returncode != 0:
        raise RuntimeError(f"splash on {scene_path} exited {result.returncode}: {(result.stderr or result.stdout)[-2000:]}")
    summary = parse_timing_summary(result.stdout)
    summary["process_wall_s"] = wall
    return summary


AT_REST_DRIVER = pathlib.Path(__file__).resolve().parent / "splishsplash_at_rest.py"
FRONT_DRIVER = pathlib.Path(__file__).resolve().parent / "splishsplash_front.py"
FRONT_COLUMNS = ("t_s", "third_farthest_x_m", "one_percent_x_m")


def front_positions(x) -> tuple:
    """A dam break's front from its fluid particles' x: the third-farthest particle's x, and the x
    with 1 % of the particles beyond it."""
    x = np.sort(np.asarray(x, dtype=float))
    return float(x[-3]), float(x[int(0.99 * (len(x) - 1))])
SPEED_COLUMNS = ("t_s", "rms_speed_m_s", "max_speed_m_s", "mean_density_kg_m3")


def write_rows(path: pathlib.Path, columns: tuple, rows: list):
    """A CSV of samples: its header, one row per sample, written whole (a .part renamed)."""
    path = pathlib.Path(path)
    part = path.with_suffix(".part")
    with part.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(columns)
        writer.writerows(rows)
    part.rename(path)


def write_speeds(path: pathlib.Path, rows: list):
    """A tank-at-rest sample file, either code's: SPEED_COLUMNS, one row per sample."""
    write_rows(path, SPEED_COLUMNS, rows)


def run_driver(driver: pathlib.Path, scene_path: pathlib.Path, args: list, out_dir: pathlib.Path, threads: int,
               timeout_s: float) -> str:
    """One of the Python-API drivers beside this file on a scene JSON, with the wheel's
    libGLdispatch preloaded and its own output in `out_dir` (splash.log: what it printed).
    Returns its standard output; RuntimeError names the driver and the scene if it failed."""
    out_dir = pathlib.Path(out_dir)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), LD_PRELOAD=gl_dispatch_preload())
    command = [sys.executable, str(driver), str(pathlib.Path(scene_path).resolve()), *args,
               "--output-dir", str(out_dir.resolve())]
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=timeout_s)
    (out_dir / "splash.log").write_text(result.stdout + result.stderr)
    if result.returncode != 0:
        raise RuntimeError(f"{driver.name} on {scene_path} exited {result.returncode}: "
                           f"{(result.stderr or result.stdout)[-2000:]}")
    return result.stdout


def start_simulator(sph, program: str, scene_path: pathlib.Path, output_dir: pathlib.Path, stop_at_s: float):
    """A driver's SPlisHSPlasH simulation, initialised, without a GUI: (simulator, fluid model, clock)."""
    base = sph.Exec.SimulatorBase()
    base.init([program, "--no-gui", "--no-cache", "--output-dir", str(pathlib.Path(output_dir).resolve()),
               "--stopAt", repr(stop_at_s), str(pathlib.Path(scene_path).resolve())], program)
    base.initSimulation()
    return base, sph.Simulation.getCurrent().getFluidModel(0), sph.TimeManager.getCurrent()


def run_at_rest(scene_path: pathlib.Path, settle_s: float, duration_s: float, out_dir: pathlib.Path, threads: int,
                timeout_s: float) -> tuple:
    """SPlisHSPlasH on a tank at rest (splishsplash_at_rest.py): settled for `settle_s` as hapfluid
    settles, then `duration_s` free. Returns its samples [(t, rms speed, max speed, mean density)]
    and its mean DFSPH iterations per step ({"mean_pressure_iterations", "mean_divergence_iterations"},
    over the whole run, settling included)."""
    speeds = pathlib.Path(out_dir) / "speeds.csv"
    stdout = run_driver(AT_REST_DRIVER, scene_path, ["--settle-s", repr(settle_s), "--kept", repr(SETTLE_VELOCITY_KEPT),
                                                     "--duration", repr(duration_s), "--out", str(speeds.resolve())],
                        out_dir, threads, timeout_s)
    with speeds.open() as f:
        rows = list(csv.DictReader(f))
    samples = [tuple(float(r[c]) for c in SPEED_COLUMNS) for r in rows]
    iterations = {}
    for key in ("mean_pressure_iterations", "mean_divergence_iterations"):
        found = re.findall(_SUMMARY[key], stdout, flags=re.MULTILINE)
        if found:
            iterations[key] = float(found[-1])
    return samples, iterations


def run_front(scene_path: pathlib.Path, every_s: float, duration_s: float, out_dir: pathlib.Path, threads: int,
              timeout_s: float) -> list:
    """SPlisHSPlasH on a dam break (splishsplash_front.py): [(t, x of the third-farthest fluid
    particle, x with 1 % of the fluid beyond)] at t = 0 and every `every_s` of simulated time."""
    front = pathlib.Path(out_dir) / "front.csv"
    run_driver(FRONT_DRIVER, scene_path, ["--every", repr(every_s), "--duration", repr(duration_s), "--out",
                                          str(front.resolve())], out_dir, threads, timeout_s)
    with front.open() as f:
        return [tuple(float(r[c]) for c in FRONT_COLUMNS) for r in csv.DictReader(f)]
