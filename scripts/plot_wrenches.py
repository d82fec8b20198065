#!/usr/bin/env python3
"""Force/torque plots like the paper's figures 8-11, from wrench histories.

Reads any CSV with a time column `t` (s) and force/torque columns `fx,fy,fz,tx,ty,tz` (N, N·m),
optionally a `device` column — `couplings.csv` from haptic-sim (what the sim asks the device to
render) or the fake device's own log (what the hand felt). One run gives one figure with a force
panel and a torque panel per device (fig. 8, 9, 11); several runs are overlaid, one colour per run
(fig. 10: the four container viscosities).

    plot_wrenches.py RUN_OR_CSV [RUN_OR_CSV ...] --out plot.png [--title T] [--labels a,b,...]
                     [--component norm|x|y|z] [--torque-component norm|x|y|z]
"""
import argparse
import csv
import pathlib
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLUMNS = ("t", "fx", "fy", "fz", "tx", "ty", "tz")


def find_csv(path: pathlib.Path) -> pathlib.Path:
    if path.is_file():
        return path
    for candidate in ("couplings.csv", "sim/couplings.csv", "device_wrenches.csv"):
        if (path / candidate).is_file():
            return path / candidate
    sys.exit(f"plot_wrenches: {path}: no couplings.csv (or device_wrenches.csv) found")


def read_wrenches(path: pathlib.Path):
    """{device: {column: [values]}}, in file order."""
    series = defaultdict(lambda: defaultdict(list))
    with path.open(newline="") as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        missing = [c for c in COLUMNS if c not in (rows.fieldnames or [])]
        if missing:
            sys.exit(f"plot_wrenches: {path}: missing columns {', '.join(missing)} (has {rows.fieldnames})")
        for number, row in enumerate(rows, start=2):
            try:
                values = {c: float(row[c]) for c in COLUMNS}
            except (TypeError, ValueError):
                sys.exit(f"plot_wrenches: {path}:{number}: a value is not a number: {row}")
            device = row.get("device") or "device"
            for c, v in values.items():
                series[device][c].append(v)
    if not series:
        sys.exit(f"plot_wrenches: {path}: no rows")
    return series


def component(data, prefix, which):
    x, y, z = data[prefix + "x"], data[prefix + "y"], data[prefix + "z"]
    if which == "norm":
        return [(a * a + b * b + c * c) ** 0.5 for a, b, c in zip(x, y, z)]
    return {"x": x, "y": y, "z": z}[which]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="+", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--title", default="")
    parser.add_argument("--labels", default="", help="comma-separated legend labels, one per run")
    parser.add_argument("--component", default="norm", choices=("norm", "x", "y", "z"))
    parser.add_argument("--torque-component", default="norm", choices=("norm", "x", "y", "z"))
    args = parser.parse_args()

    labels = args.labels.split(",") if args.labels else [p.name if p.is_dir() else p.parent.name for p in args.runs]
    if len(labels) != len(args.runs):
        sys.exit("plot_wrenches: --labels needs one label per run")
    runs = [read_wrenches(find_csv(p)) for p in args.runs]
    devices = sorted({d for run in runs for d in run})

    fig, axes = plt.subplots(2, len(devices), figsize=(6 * len(devices), 6), sharex=True, squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for col, device in enumerate(devices):
        force_ax, torque_ax = axes[0][col], axes[1][col]
        for k, (run, label) in enumerate(zip(runs, labels)):
            if device not in run:
                continue
            data, colour = run[device], colours[k % len(colours)]
            name = label if len(runs) > 1 else None
            force_ax.plot(data["t"], component(data, "f", args.component), color=colour, label=name, lw=1.2)
            torque_ax.plot(data["t"], component(data, "t", args.torque_component), color=colour, label=name, lw=1.2)
        force_ax.set_title(device)
        force_ax.set_ylabel(f"force {args.component} (N)")
        torque_ax.set_ylabel(f"torque {args.torque_component} (N·m)")
        torque_ax.set_xlabel("time (s)")
        for ax in (force_ax, torque_ax):
            ax.grid(alpha=0.3)
            if len(runs) > 1:
                ax.legend(fontsize=8)
    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"plot_wrenches: wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
