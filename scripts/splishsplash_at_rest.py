"""SPlisHSPlasH's DFSPH on a tank at rest, settled as hapfluid settles its fluid, and its speeds.

Run by splishsplash.run_at_rest in the interpreter that has the pysplishsplash wheel, with the
wheel's libGLdispatch preloaded (the import crashes on Debian 12 otherwise):

    splishsplash_at_rest.py SCENE.json --settle-s S --kept F --duration S --out speeds.csv

For the first --settle-s of simulated time every fluid velocity is multiplied by --kept after each
step (hapfluid's fluid.settle_s relaxation: a lattice is looser than the packing the fluid
relaxes to, and started from it a column sloshes); then the fluid runs free for --duration,
and every 0.1 s of that the rms and largest fluid speed and the mean density go to the CSV
(columns t_s, rms_speed_m_s, max_speed_m_s, mean_density_kg_m3; t = 0 at the end of settling).
"""
import argparse
import math
import pathlib
import sys

import numpy as np
import pysplishsplash as sph

import splishsplash  # beside this file

SAMPLE_EVERY_S = 0.1


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", type=pathlib.Path)
    parser.add_argument("--settle-s", type=float, required=True)
    parser.add_argument("--kept", type=float, required=True, help="velocity fraction kept after each settling step")
    parser.add_argument("--duration", type=float, required=True, help="simulated seconds after settling")
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--output-dir", type=pathlib.Path, required=True, help="SPlisHSPlasH's own output folder")
    args = parser.parse_args()
    if not (0.0 <= args.kept <= 1.0):
        sys.exit(f"splishsplash_at_rest: --kept {args.kept}: must be in [0, 1]")

    base, model, clock = splishsplash.start_simulator(sph, "splishsplash_at_rest", args.scene, args.output_dir, args.settle_s + args.duration)
    n = model.numActiveParticles()
    rows = []
    next_sample = [0.0]

    def after_step():
        t = clock.getTime()
        if t < args.settle_s:
            for i in range(n):
                model.setVelocity(i, args.kept * np.asarray(model.getVelocity(i)))
            return
        since = t - args.settle_s
        if since + 1e-9 < next_sample[0]:
            return
        speed = np.linalg.norm(np.array([model.getVelocity(i) for i in range(n)]), axis=1)
        density = np.array([model.getDensity(i) for i in range(n)])
        rows.append((since, math.sqrt(float(np.mean(speed ** 2))), float(speed.max()), float(density.mean())))
        next_sample[0] += SAMPLE_EVERY_S
        print(f"splishsplash_at_rest: t = {since:.2f} / {args.duration} s, rms {rows[-1][1]:.4f} m/s, "
              f"max {rows[-1][2]:.4f} m/s", flush=True)

    base.setTimeStepCB(after_step)
    base.runSimulation()
    base.cleanup()
    if not rows:
        sys.exit("splishsplash_at_rest: the run ended before settling did: no samples")
    splishsplash.write_speeds(args.out, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
