#!/usr/bin/python3
"""Break-up of the free surface step by step on a two-phase stepped chute
(docs/validation.md, "Where the surface breaks up"), from HDF5 snapshots of
configs/stepped_chute_chanson.yaml (or any chute whose step edges are given).

Seed 001 places the inception of free-surface aeration on Chanson's chute
where "the air-water interface is clearly broken up and deformed" and
"water particles ... jump away from the water surface" (its figure 4): a
criterion read from the particles, not from a profile. This script counts,
over the treads of steps 1..N (step k: x between edge k-1 and edge k, the
weir's edge being edge 0), in each snapshot:

  drops          water particles that have left the flow: at most 5 water
                 neighbours within the kernel's support 2h and more air than
                 water neighbours (a water particle inside the flow has
                 about 18 water neighbours at h = 1.225 dx, one on a flat
                 free surface about 9);
  entrained air  air particles with more water than air neighbours within
                 2h (air carried inside the water);

and prints their means per snapshot. The inception step it reports is the
first step with at least one drop per snapshot on average; the counts of
every step are printed so that any other threshold can be read off.
Water is phase 0 and air phase 1 of the fluid particles (kind 0).

    tools/chute-surface-breakup.py --edges "x,y;x,y;..." --weir-edge X,Y \\
        [--plot FILE.png --box X0,X1,Y0,Y1] SNAPSHOT.h5 [...]

--plot draws the last snapshot's water, air and walls inside the box with
gnuplot (pngcairo).

Needs python3-h5py and python3-numpy.
"""
import argparse
import subprocess
import sys

import h5py
import numpy as np


def neighbour_counts(points, others, radius):
    """Number of `others` within `radius` of each of `points` (2D)."""
    if len(points) == 0 or len(others) == 0:
        return np.zeros(len(points), dtype=int)
    d2 = ((points[:, None, :] - others[None, :, :]) ** 2).sum(-1)
    return (d2 < radius * radius).sum(1)


def plot(path, out, box):
    """The particles of one snapshot inside box = (x0, x1, y0, y1), by kind."""
    x0, x1, y0, y1 = box
    with h5py.File(path, "r") as f:
        position = f["position"][:, :2]
        kind = f["kind"][:]
        phase = f["phase"][:]
        time = float(f.attrs["time"])
    inside = ((position[:, 0] > x0) & (position[:, 0] < x1)
              & (position[:, 1] > y0) & (position[:, 1] < y1))
    groups = [("air", (kind == 0) & (phase == 1), "#ffaaaa"),
              ("water", (kind == 0) & (phase == 0), "blue"),
              ("walls", kind != 0, "black")]
    width = 1600
    height = int(width * (y1 - y0) / (x1 - x0)) + 60
    script = ["set terminal pngcairo size %d,%d" % (width, height),
              "set output '%s'" % out, "set size ratio -1",
              "set xrange [%g:%g]" % (x0, x1), "set yrange [%g:%g]" % (y0, y1),
              "set xlabel 'x (m)'", "set ylabel 'y (m)'",
              "set title '%s, t = %.3f s' noenhanced" % (path, time)]
    for name, selected, _ in groups:
        script.append("$%s << EOD" % name)
        script += ["%.5f %.5f" % (px, py) for px, py in position[inside & selected]]
        script.append("EOD")
    script.append("plot " + ", ".join(
        "$%s with points pt 7 ps 0.3 lc rgb '%s' title '%s'" % (name, colour, name)
        for name, _, colour in groups))
    subprocess.run(["gnuplot"], input="\n".join(script) + "\n", text=True, check=True)


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--edges", required=True,
                        help="step edges x,y;x,y;... in m (edge 1 first)")
    parser.add_argument("--weir-edge", required=True,
                        help="x,y of the weir's downstream edge in m (edge 0)")
    parser.add_argument("--drops-threshold", type=float, default=1.0,
                        help="drops per snapshot that mark the inception (1)")
    parser.add_argument("--plot", help="PNG of the last snapshot's particles")
    parser.add_argument("--box", default="1.3,2.8,0.4,1.0",
                        help="x0,x1,y0,y1 of the plot in m (1.3,2.8,0.4,1.0)")
    parser.add_argument("snapshots", nargs="+")
    args = parser.parse_args()
    edges = [tuple(map(float, args.weir_edge.split(",")))]
    edges += [tuple(map(float, e.split(","))) for e in args.edges.strip().split(";")]
    steps = len(edges) - 1
    totals = np.zeros((steps, 3))
    frames = 0
    times = []
    for path in args.snapshots:
        with h5py.File(path, "r") as f:
            if "phase" not in f:
                sys.exit("%s: no phase field: the snapshot is not two-phase" % path)
            position = f["position"][:, :2]
            fluid = f["kind"][:] == 0
            water = fluid & (f["phase"][:] == 0)
            air = fluid & (f["phase"][:] == 1)
            support = 2.0 * float(f.attrs["smoothing_length"])
            times.append(float(f.attrs["time"]))
        x, y = position[:, 0], position[:, 1]
        for k in range(steps):
            (xa, ya), (xb, yb) = edges[k], edges[k + 1]
            # the tread of step k+1 and everything above it up to 0.2 m
            # over the upstream edge
            inside = (x >= xa) & (x < xb) & (y > yb - 0.01) & (y < ya + 0.2)
            near = ((x >= xa - support) & (x < xb + support)
                    & (y > yb - 0.01 - support) & (y < ya + 0.2 + support))
            water_near = position[near & water]
            air_near = position[near & air]
            w = position[inside & water]
            a = position[inside & air]
            w_water = neighbour_counts(w, water_near, support) - 1
            w_air = neighbour_counts(w, air_near, support)
            a_water = neighbour_counts(a, water_near, support)
            a_air = neighbour_counts(a, air_near, support) - 1
            totals[k, 0] += len(w)
            totals[k, 1] += np.count_nonzero((w_water <= 5) & (w_air > w_water))
            totals[k, 2] += np.count_nonzero(a_water > a_air)
        frames += 1
    means = totals / frames
    print("# %d snapshots, t = %.4g-%.4g s; per snapshot, on the tread of each step"
          % (frames, min(times), max(times)))
    print("step,edge_x,edge_y,water_particles,drops,entrained_air")
    for k in range(steps):
        print("%d,%.4f,%.4f,%.1f,%.2f,%.2f" % (k + 1, edges[k + 1][0], edges[k + 1][1],
                                              means[k, 0], means[k, 1], means[k, 2]))
    first = next((k + 1 for k in range(steps) if means[k, 1] >= args.drops_threshold), None)
    print("# inception (first step with >= %g drops per snapshot): %s"
          % (args.drops_threshold, first if first else "none"))
    if args.plot:
        plot(args.snapshots[-1], args.plot, tuple(map(float, args.box.split(","))))


if __name__ == "__main__":
    main()
