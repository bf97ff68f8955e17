#!/usr/bin/env python3
"""The free surface of a run along x, as a PNG: the elevation at the end of
the run and its mean over a time window, from the free-surface gauge's table
(columns' positions from RUN/tables.json).

    python3 docs/examples/free_surface.py [RUN] [--out PNG] [--from T0] [--to T1]

RUN defaults to runs/jump (the README's first command writes it), PNG to
RUN/free_surface.png, the window to the second half of the run. Without an
installed package, run it from the source tree with PYTHONPATH=python."""

import argparse
import os

import sluice
from sluice import plot


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", nargs="?", default="runs/jump", help="run directory")
    parser.add_argument("--out", help="PNG to write (default RUN/free_surface.png)")
    parser.add_argument("--from", dest="start", type=float, help="window start (s)")
    parser.add_argument("--to", dest="end", type=float, help="window end (s)")
    parser.add_argument("--table", default="free_surface", help="the gauge's table")
    args = parser.parse_args()

    run = sluice.load(args.run)
    surface = run.table(args.table)
    end = args.end if args.end is not None else float(surface.time[-1])
    start = args.start if args.start is not None else end / 2

    ax = plot.free_surface(run, table=surface)              # the last row
    plot.free_surface(run, window=(start, end), table=surface, ax=ax)
    ax.set_title("%s: free surface, %s" % (os.path.basename(os.path.abspath(args.run)),
                                           run.scene.get("title", "")), fontsize="medium")
    out = args.out or os.path.join(args.run, "free_surface.png")
    ax.figure.savefig(out, dpi=110)
    print("wrote %s" % out)


if __name__ == "__main__":
    main()
