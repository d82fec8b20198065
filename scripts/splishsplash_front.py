"""SPlisHSPlasH's DFSPH on a dam break, its surge front sampled as hapfluid measures its own.

Run by splishsplash.run_front in the interpreter that has the pysplishsplash wheel, with the
wheel's libGLdispatch preloaded (the import crashes on Debian 12 otherwise):

    splishsplash_front.py SCENE.json --every S --duration S --out front.csv --output-dir DIR

At t = 0 and every --every s of simulated time after it, the x coordinates of the third-farthest
fluid particle along +x (one or two droplets thrown ahead are not the front) and of the particle
with 1 % of the fluid beyond it (a thin jet is not either) go to the CSV (splishsplash.FRONT_COLUMNS).
"""
import argparse
import pathlib
import sys

import numpy as np
import pysplishsplash as sph

import splishsplash  # beside this file


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", type=pathlib.Path)
    parser.add_argument("--every", type=float, required=True, help="simulated seconds between samples")
    parser.add_argument("--duration", type=float, required=True, help="simulated seconds")
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--output-dir", type=pathlib.Path, required=True, help="SPlisHSPlasH's own output folder")
    args = parser.parse_args()
    if args.every <= 0:
        sys.exit(f"splishsplash_front: --every {args.every}: must be positive")

    base, model, clock = splishsplash.start_simulator(sph, "splishsplash_front", args.scene, args.output_dir, args.duration)
    n = model.numActiveParticles()
    rows = []
    next_sample = [0.0]

    def sample():
        x = np.array([model.getPosition(i)[0] for i in range(n)])
        rows.append((clock.getTime(), *splishsplash.front_positions(x)))
        next_sample[0] += args.every

    def after_step():
        if clock.getTime() + 1e-9 >= next_sample[0]:
            sample()
            print(f"splishsplash_front: t = {rows[-1][0]:.3f} / {args.duration} s, front particle at "
                  f"x = {rows[-1][1]:.4f} m", flush=True)

    sample()  # the column as it stands
    base.setTimeStepCB(after_step)
    base.runSimulation()
    base.cleanup()
    splishsplash.write_rows(args.out, splishsplash.FRONT_COLUMNS, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
