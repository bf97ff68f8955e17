#!/usr/bin/python3
"""Mean water speed by reach of Cheng's stepped spillway (docs/validation.md,
"Cheng at the seed's spacing from a single-phase spin-up"), from one HDF5
snapshot of configs/stepped_spillway_cheng.yaml: the crest (0.3 m < x <
step 1's edge), steps 1-8, 9-16, 17-24, 25-32, 33-40 (by the x of their
edges, 0.7144 + 0.025 k m) and the toe (x > 1.7144 m). Water is every
fluid particle (kind 0) of phase 0, or every fluid particle when the
snapshot has no phase (single phase). Prints one line: the snapshot's time,
then "speed (count)" per reach. Needs python3-h5py and python3-numpy.

    tools/cheng-reach-speeds.py SNAPSHOT.h5 [...]
"""
import sys

import h5py
import numpy as np

EDGE0, STEP = 0.7144, 0.025
REACHES = [("crest", 0.3, EDGE0)] + [
    ("steps %d-%d" % (k + 1, k + 8), EDGE0 + STEP * k, EDGE0 + STEP * (k + 8))
    for k in range(0, 40, 8)] + [("toe", EDGE0 + STEP * 40, 2.1)]


def main(paths):
    if not paths:
        sys.exit(__doc__)
    print("time," + ",".join(name for name, _, _ in REACHES))
    for path in paths:
        with h5py.File(path, "r") as f:
            x = f["position"][:, 0]
            speed = np.hypot(f["velocity"][:, 0], f["velocity"][:, 1])
            water = f["kind"][:] == 0
            if "phase" in f:
                water &= f["phase"][:] == 0
            cells = []
            for _, lo, hi in REACHES:
                inside = water & (x >= lo) & (x < hi)
                n = int(inside.sum())
                cells.append("%.2f (%d)" % (speed[inside].mean() if n else 0.0, n))
            print("%.4f,%s" % (f.attrs["time"], ",".join(cells)))


if __name__ == "__main__":
    main(sys.argv[1:])
