"""Sluice's Python package: a run's tables, snapshots and probes.

    import sluice
    run = sluice.load("runs/jump")
    run.info["particles_final"]              # run.json
    run.scene["plugins"]["inlet"]            # scene.resolved.yaml
    eta = run.table("free_surface")          # a CSV table, its columns described
    eta["eta_x0"].unit, eta["eta_x0"].position
    snapshot = run.snapshots[-1]             # HDF5 snapshots, fields read lazily
    snapshot.fluid("pressure").values        # numpy array, .unit "Pa"
    run.probe([(0.5, 0.01)], "velocity")     # `sluice probe` at points

Plots (matplotlib, no display): sluice.plot. Reference: docs/python.md.
"""

from .probing import SluiceError, find_program, probe
from .run import Run, load
from .snapshots import KINDS, Field, Snapshot
from .tables import Column, Table

__all__ = ["load", "Run", "Table", "Column", "Snapshot", "Field", "KINDS", "probe",
           "find_program", "SluiceError"]
