"""Force/torque plots like the paper's figures 8-11, from wrench histories.

Reads any CSV with a time column `t` (s) and force/torque columns `fx,fy,fz,tx,ty,tz` (N, N·m),
optionally a `device` column — `couplings.csv` from haptic-sim (what the sim asks the device to
render) or the fake device's own log (what the hand felt). One run gives one figure with a force
panel and a torque panel per device (fig. 8, 9, 11); several runs are overlaid, one colour per run
(fig. 10: the four container viscosities).

    hapfluid-plot-wrenches RUN_OR_CSV [RUN_OR_CSV ...] --out plot.png [--title T] [--labels a,b,...]
                     [--scene NAME] [--component norm|x|y|z] [--torque-component norm|x|y|z]

--scene picks the components the paper's figure of that scene shows (SCENE_COMPONENTS); --component
and --torque-component override it. Without either: the norms. Where the scene says so (the spinning
glass), a third panel shows the fluid's own torque on the held body, from the bodies.csv beside
couplings.csv: the hand's torque is mostly the body's own inertia, the same in every run.
"""
import argparse
import csv
import pathlib
import sys
import textwrap
import tomllib
from collections import defaultdict

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLUMNS = ("t", "fx", "fy", "fz", "tx", "ty", "tz")
from .paths import SCENES


class Components:
    """Which force and torque component a scene's figure shows, and what that component means;
    torque_by_device: {device: (component, meaning)} where one hand turns about another axis."""

    def __init__(self, force="norm", torque="norm", force_meaning="", torque_meaning="", torque_by_device=None,
                 hand_velocity=False, fluid_torque=False):
        self.force, self.torque = force, torque
        self.force_meaning, self.torque_meaning = force_meaning, torque_meaning
        self.torque_by_device = torque_by_device or {}
        self.hand_velocity = hand_velocity  # draw the hand's velocity along the force component (--hand)
        self.fluid_torque = fluid_torque  # a panel of the fluid's torque on the held body (bodies.csv)

    def torque_for(self, device: str) -> tuple[str, str]:
        return self.torque_by_device.get(device, (self.torque, self.torque_meaning))


# The one place a scene's plot components are chosen (make run's wrenches.png, run_scenarios.py's
# figures). A norm hides the sign: fig. 8b shows the force against the stroke, so the stirring plot
# shows the stroke axis (x) and the torque about the horizontal axis across it (y). Keys are scene
# names or their prefix before a trailing _<number> (spinning_glass_10 -> spinning_glass).
SCENE_COMPONENTS = {
    "spoon_stirring": Components("x", "y", "along the stroke", "across the stroke", hand_velocity=True),
    # A 3-DoF probe renders forces only: its torque panel shows the zero the device gets.
    "probe_3dof": Components("x", "norm", "along the stroke", "3-DoF: forces only", hand_velocity=True),
    "bowl_pouring": Components("z", "y", "vertical, - = down", "tilt axis"),
    "spinning_glass": Components("norm", "z", "", "spin axis", fluid_torque=True),
    "bucket_bimanual": Components("z", "y", "vertical, - = down", "tilt axis"),
    # The bowl is tilted about y to pour, the pan about x (its handle) to spread the batter.
    "crepe": Components("z", "y", "vertical, - = down", "pouring tilt axis", {"right": ("x", "spreading tilt axis")}),
}


def scene_components(scene: str) -> Components:
    name = pathlib.Path(scene).stem
    base = name.rsplit("_", 1)[0] if name.rsplit("_", 1)[-1].isdigit() else name
    return SCENE_COMPONENTS.get(name) or SCENE_COMPONENTS.get(base) or Components()


def axis_label(quantity: str, which: str, meaning: str, unit: str) -> str:
    name = f"|{quantity}|" if which == "norm" else f"{quantity} {which}"
    return f"{name} ({unit})" if not meaning else f"{name}: {meaning} ({unit})"


def find_csv(path: pathlib.Path) -> pathlib.Path:
    if path.is_file():
        return path
    for candidate in ("couplings.csv", "sim/couplings.csv", "device_wrenches.csv"):
        if (path / candidate).is_file():
            return path / candidate
    sys.exit(f"plot_wrenches: {path}: no couplings.csv (or device_wrenches.csv) found")


def read_wrenches(path: pathlib.Path, time_column: str = "t", time_offset_s: float = 0.0):
    """{device: {column: [values]}}, in file order; "t" is `time_column` minus time_offset_s."""
    series = defaultdict(lambda: defaultdict(list))
    columns = (time_column,) + COLUMNS[1:]
    with path.open(newline="") as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        missing = [c for c in columns if c not in (rows.fieldnames or [])]
        if missing:
            sys.exit(f"plot_wrenches: {path}: missing columns {', '.join(missing)} (has {rows.fieldnames})")
        for number, row in enumerate(rows, start=2):
            try:
                values = {c: float(row[c]) for c in columns}
            except (TypeError, ValueError):
                sys.exit(f"plot_wrenches: {path}:{number}: a value is not a number: {row}")
            values["t"] = values.pop(time_column) - time_offset_s
            device = row.get("device") or "device"
            for c, v in values.items():
                series[device][c].append(v)
    if not series:
        sys.exit(f"plot_wrenches: {path}: no rows")
    return series


def read_fluid_torque(couplings: pathlib.Path, body: str, device_rows: dict, time_column: str, time_offset_s: float):
    """{"t", "tx", "ty", "tz"} of the fluid's torque on `body` from the bodies.csv beside a
    couplings.csv (its rows in simulated time: on the wall clock they are placed by the device's
    coupling rows, which carry both clocks), or None when there is no such file or body."""
    path = couplings.parent / "bodies.csv"
    if not body or not path.is_file():
        return None
    with path.open(newline="") as f:
        rows = [r for r in csv.DictReader(f) if r.get("body") == body]
    if not rows:
        return None
    try:
        data = {c: np.array([float(r[c]) for r in rows]) for c in ("t", "tx", "ty", "tz")}
    except (KeyError, TypeError, ValueError):
        sys.exit(f"plot_wrenches: {path}: rows of '{body}' need numeric t, tx, ty, tz")
    if time_column != "t":
        with couplings.open(newline="") as f:
            clocks = [(float(r["t"]), float(r[time_column])) for r in csv.DictReader(f) if r.get("device") in device_rows]
        if len(clocks) < 2:
            return None
        sim_t, other = np.array(clocks).T
        data["t"] = np.interp(data["t"], sim_t, other)
    data["t"] = data["t"] - time_offset_s
    return data


def component(data, prefix, which):
    x, y, z = data[prefix + "x"], data[prefix + "y"], data[prefix + "z"]
    if which == "norm":
        return [(a * a + b * b + c * c) ** 0.5 for a, b, c in zip(x, y, z)]
    return {"x": x, "y": y, "z": z}[which]


def load_scene(scene: str) -> dict:
    """config/scenes/<scene>.toml (or a scene file) as a dict; {} when there is none."""
    path = pathlib.Path(scene)
    if path.suffix != ".toml":
        path = SCENES / f"{scene}.toml"
    if not scene or not path.is_file():
        return {}
    with path.open("rb") as f:
        return tomllib.load(f)


def scripted_motions(scene: dict) -> dict:
    """{scene device: [(kind, start_s, stop_s)]} of the scene's scripted hands."""
    return {d["name"]: [(m.get("kind", "motion"), float(m.get("start_s", 0.0)), float(m["stop_s"]))
                        for m in d.get("motion", []) if "stop_s" in m] for d in scene.get("devices", [])}


def held_bodies(scene: dict, device: str) -> str:
    """What the scene couples the device to ("bowl"), for the column title "left (bowl)"."""
    return ", ".join(c["body"] for c in scene.get("couplings", []) if c.get("device") == device)


def mark_motions(ax, motions, label: bool):
    """The scripted hand's motion segments, shaded, so the phases of the figure can be read off."""
    for k, (kind, start, stop) in enumerate(motions):
        ax.axvspan(start, stop, color="0.5", alpha=0.08, lw=0)
        for x in (start, stop):
            ax.axvline(x, color="0.4", lw=0.8, ls=":")
        if label:
            # Successive segments' labels alternate in height so that adjacent ones never overlap.
            ax.annotate(f"{kind} {start:g}-{stop:g} s", xy=((start + stop) / 2, 0.98 - 0.07 * (k % 2)),
                        xycoords=("data", "axes fraction"),
                        ha="center", va="top", fontsize=7, color="0.3")


def hand_velocity(path: pathlib.Path, axis: str, offset_s: float):
    """(t, v) of a fake device's log (t_s, px, py, pz): the hand's velocity along `axis`, m/s."""
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows or "t_s" not in rows[0] or f"p{axis}" not in rows[0]:
        sys.exit(f"plot_wrenches: --hand {path}: not a device log (needs columns t_s, p{axis})")
    t = np.array([float(r["t_s"]) for r in rows]) - offset_s
    p = np.array([float(r[f"p{axis}"]) for r in rows])
    return t[::5], np.gradient(p, t)[::5]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="+", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--title", default="")
    parser.add_argument("--labels", default="", help="comma-separated legend labels, one per run")
    parser.add_argument("--scene", default="", help="scene name: its figure's components (SCENE_COMPONENTS)")
    parser.add_argument("--component", default=None, choices=("norm", "x", "y", "z"))
    parser.add_argument("--torque-component", default=None, choices=("norm", "x", "y", "z"))
    parser.add_argument("--time", default="sim", choices=("sim", "wall"),
                        help="time axis: sim (column t, simulated time) or wall (column wall_s: the wall clock, as "
                             "the hand moves; differs from simulated time when the sim runs slower than real time)")
    parser.add_argument("--time-offset", default=None,
                        help="seconds subtracted from the time axis, one value or one per run (the launcher's "
                             "summary.json script_offset_s: then 0 is the scene script's start, its motions marked)")
    parser.add_argument("--hand", action="append", default=[], type=pathlib.Path,
                        help="a fake device log device_<name>.csv: the hand's velocity along the force component "
                             "on a second axis, for scenes whose figure claims a force against the motion (stirring)")
    parser.add_argument("--hand-offset", type=float, default=0.0,
                        help="seconds subtracted from the device log's t_s (the lead-in: then 0 is the script's start)")
    args = parser.parse_args()
    chosen = scene_components(args.scene)
    if args.component and args.component != chosen.force:
        chosen.force, chosen.force_meaning = args.component, ""
    if args.torque_component and args.torque_component != chosen.torque:
        chosen.torque, chosen.torque_meaning, chosen.torque_by_device = args.torque_component, "", {}

    labels = args.labels.split(",") if args.labels else [p.name if p.is_dir() else p.parent.name for p in args.runs]
    if len(labels) != len(args.runs):
        sys.exit("plot_wrenches: --labels needs one label per run")
    on_script_clock = args.time_offset is not None
    try:
        offsets = [float(v) for v in (args.time_offset or "0").split(",")]
    except ValueError:
        sys.exit(f"plot_wrenches: --time-offset {args.time_offset}: not numbers")
    offsets = offsets * len(args.runs) if len(offsets) == 1 else offsets
    if len(offsets) != len(args.runs):
        sys.exit("plot_wrenches: --time-offset needs one value, or one per run")
    time_column = "t" if args.time == "sim" else "wall_s"
    csvs = [find_csv(p) for p in args.runs]
    runs = [read_wrenches(c, time_column, o) for c, o in zip(csvs, offsets)]
    devices = sorted({d for run in runs for d in run})
    scene = load_scene(args.scene)
    fluid = {}  # (run, device): the fluid's torque on the body the device holds
    if chosen.fluid_torque and chosen.torque != "norm":
        for k, (c, o) in enumerate(zip(csvs, offsets)):
            for device in devices:
                body = held_bodies(scene, device)
                data = read_fluid_torque(c, body, {device}, time_column, o) if "," not in body else None
                if data is not None:
                    fluid[(k, device)] = data
    motions = scripted_motions(scene) if on_script_clock else {}
    xlabel = {("sim", False): "simulated time (s)", ("wall", False): "wall-clock time since the sim started (s)",
              ("sim", True): "scene time: simulated time, 0 = the script's start (s)",
              ("wall", True): "scene time: the hand's clock, 0 = the script's start (s)"}[(args.time, on_script_clock)]

    panels = 3 if fluid else 2
    fig, axes = plt.subplots(panels, len(devices), figsize=(6.5 * len(devices), 3.25 * panels), sharex=True,
                             squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for col, device in enumerate(devices):
        force_ax, torque_ax = axes[0][col], axes[1][col]
        torque, torque_meaning = chosen.torque_for(device)
        fluid_ax = axes[2][col] if fluid else None
        for k, label in enumerate(labels):
            if (k, device) in fluid:
                fluid_ax.plot(fluid[(k, device)]["t"], fluid[(k, device)]["t" + torque], color=colours[k % len(colours)],
                              label=label if len(runs) > 1 else None, lw=1.2)
        for k, (run, label) in enumerate(zip(runs, labels)):
            if device not in run:
                continue
            data, colour = run[device], colours[k % len(colours)]
            name = label if len(runs) > 1 else None
            force_ax.plot(data["t"], component(data, "f", chosen.force), color=colour, label=name, lw=1.2)
            torque_ax.plot(data["t"], component(data, "t", torque), color=colour, label=name, lw=1.2)
        hand = next((h for h in args.hand if h.stem == f"device_{device}"), None)
        if hand is not None and chosen.hand_velocity and chosen.force != "norm":
            velocity_ax = force_ax.twinx()
            t_hand, v_hand = hand_velocity(hand, chosen.force, args.hand_offset)
            velocity_ax.plot(t_hand, v_hand, color="0.45", ls="--", lw=1.0)
            velocity_ax.set_ylabel(f"hand velocity {chosen.force} (m/s), dashed", color="0.35")
            # One zero line for both axes, so that "against the motion" reads as "opposite sides of it".
            for ax, top in ((force_ax, max(abs(v) for v in force_ax.get_ylim())), (velocity_ax, np.abs(v_hand).max())):
                ax.set_ylim(-1.05 * top, 1.05 * top)
        body = held_bodies(scene, device)
        force_ax.set_title(f"{device} ({body})" if body else device)
        force_ax.set_ylabel(axis_label("force", chosen.force, chosen.force_meaning, "N"))
        torque_ax.set_ylabel(axis_label("torque", torque, torque_meaning, "N·m"))
        if fluid_ax is not None:
            fluid_ax.set_ylabel(f"fluid's torque on {held_bodies(scene, device)} {torque}\n(of the hand's above) (N·m)")
        (fluid_ax or torque_ax).set_xlabel(xlabel)
        for ax in (force_ax, torque_ax, fluid_ax) if fluid_ax is not None else (force_ax, torque_ax):
            ax.grid(alpha=0.3)
            ax.axhline(0.0, color="0.3", lw=0.6)
            mark_motions(ax, motions.get(device, []), label=ax is force_ax)
            if len(runs) > 1:
                ax.legend(fontsize=8)
    if args.title:  # wrapped to the figure's width (~65 characters per 6-inch column)
        fig.suptitle("\n".join(textwrap.wrap(args.title, width=65 * len(devices))))
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"plot_wrenches: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
