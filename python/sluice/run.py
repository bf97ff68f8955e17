"""A run directory written by `sluice run SCENE --out RUN`."""

import json
import os
import warnings

import numpy as np

from . import probing
from .snapshots import find_snapshots
from .tables import load_table, read_index, table_name


class Run:
    """A run directory: ``info`` (run.json), ``scene`` (the resolved scene),
    ``tables`` (its CSV time series by name), ``snapshots`` (its HDF5
    particle snapshots, in time order). Use :func:`load`."""

    def __init__(self, path):
        if not os.path.isdir(path):
            raise FileNotFoundError("no run directory '%s'" % path)
        self.path = os.path.abspath(path)
        self._info = None
        self._scene = None
        self._index = None
        self._index_read = False
        self._tables = {}
        self._snapshots = None
        self._warned = False

    # -- run.json and the scene ------------------------------------------

    @property
    def info(self):
        """run.json as a dict (status, particle counts, steps, times,
        plugins, ...); {} while the run has not written it (it is written
        when a run ends)."""
        if self._info is None:
            path = os.path.join(self.path, "run.json")
            if not os.path.exists(path):
                return {}
            with open(path, "r", encoding="utf-8") as f:
                self._info = json.load(f)
        return self._info

    @property
    def scene(self):
        """scene.resolved.yaml (the scene with every default filled in) as a
        dict."""
        if self._scene is None:
            import yaml

            with open(os.path.join(self.path, "scene.resolved.yaml"), "r",
                      encoding="utf-8") as f:
                self._scene = yaml.safe_load(f)
        return self._scene

    @property
    def dimensions(self):
        return int(self.scene["dimensions"])

    def plugin(self, instance):
        """The resolved parameters of a plugin instance of the scene (a
        dict), e.g. run.plugin("free_surface_gauge")["positions"]."""
        plugins = self.scene.get("plugins") or {}
        if instance not in plugins:
            raise KeyError("the scene loads no plugin instance '%s' (it loads %s)"
                           % (instance, ", ".join(plugins)))
        return plugins[instance] or {}

    # -- tables ----------------------------------------------------------

    def _table_index(self):
        if not self._index_read:
            self._index = read_index(self.path)
            self._index_read = True
        return self._index

    def _table_files(self):
        index = self._table_index()
        if index is not None:
            return [name for name in index if os.path.exists(os.path.join(self.path, name))]
        if not self._warned:
            warnings.warn("%s has no tables.json (a run written before it existed): the tables' "
                          "columns have names only, no units, descriptions or positions"
                          % self.path, stacklevel=3)
            self._warned = True
        return sorted(name for name in os.listdir(self.path)
                      if name.endswith(".csv") and not name.endswith("_sensors.csv")
                      and os.path.isfile(os.path.join(self.path, name)))

    @property
    def table_names(self):
        """The names of the run's tables (file names without '.csv')."""
        return [table_name(f) for f in self._table_files()]

    def table(self, name):
        """The table `name` ("free_surface", "free_surface.csv", or the
        instance that writes it, "free_surface_gauge"), read from its CSV
        file when first asked for (a live run's table grows: ``refresh()``
        forgets what was read)."""
        files = self._table_files()
        index = self._table_index() or {}
        file_name = None
        for f in files:
            entry = index.get(f, {})
            if name in (f, table_name(f), entry.get("instance")):
                file_name = f
                break
        if file_name is None:
            raise KeyError("run %s has no table '%s' (it has %s)"
                           % (self.path, name, ", ".join(table_name(f) for f in files)))
        if file_name not in self._tables:
            self._tables[file_name] = load_table(self.path, file_name, index.get(file_name))
        return self._tables[file_name]

    @property
    def tables(self):
        """The run's tables by name, each read when first asked for."""
        return _Tables(self)

    # -- snapshots -------------------------------------------------------

    def _snapshot_prefix(self):
        try:
            plugins = self.scene.get("plugins") or {}
        except FileNotFoundError:
            return "particles"
        for instance, parameters in plugins.items():
            parameters = parameters or {}
            if parameters.get("plugin", instance) == "hdf5":
                return parameters.get("prefix", "particles") or "particles"
        return "particles"

    @property
    def snapshots(self):
        """The HDF5 snapshots, in time order (Snapshot objects: .time,
        .step, fields read lazily). Found once; ``refresh()`` looks again."""
        if self._snapshots is None:
            self._snapshots = find_snapshots(self.path, self._snapshot_prefix())
        return self._snapshots

    def snapshot_at(self, time):
        """The snapshot nearest to `time` (s)."""
        if not self.snapshots:
            raise ValueError("run %s has no snapshots" % self.path)
        times = np.array([s.time for s in self.snapshots])
        return self.snapshots[int(np.argmin(np.abs(times - time)))]

    def refresh(self):
        """Forgets what was read (a live run writes on)."""
        self._info = None
        self._index_read = False
        self._tables = {}
        self._snapshots = None

    # -- probe -----------------------------------------------------------

    def probe(self, points, fields, times="last", program=None):
        """Fields interpolated at `points` (a list of (x, y[, z])) from the
        snapshots at `times` ("last", "all", a time or a list of times, s),
        through `sluice probe`; `program` is the sluice program (default:
        the SLUICE environment variable, then the PATH). Returns a Table
        with columns time, point, x, y[, z], the fields' columns (vectors
        as NAME_x, NAME_y[, NAME_z]) and support (the kernel sum, 0 outside
        the fluid); the fields' units are the snapshots'."""
        units = {}
        if self.snapshots:
            last = self.snapshots[-1]
            names = [fields] if isinstance(fields, str) else list(fields)
            for name in ",".join(names).split(","):
                name = name.strip()
                if name in last:
                    units[name] = last.unit(name)
        return probing.probe(self.path, points, fields, times, program, units)

    def __repr__(self):
        return "<Run %s>" % self.path


class _Tables:
    """run.tables: a read-only mapping of the run's tables by name."""

    def __init__(self, run):
        self._run = run

    def __getitem__(self, name):
        return self._run.table(name)

    def __contains__(self, name):
        try:
            self._run.table(name)
            return True
        except KeyError:
            return False

    def __iter__(self):
        return iter(self._run.table_names)

    def __len__(self):
        return len(self._run.table_names)

    def keys(self):
        return self._run.table_names

    def items(self):
        return [(name, self._run.table(name)) for name in self._run.table_names]

    def values(self):
        return [self._run.table(name) for name in self._run.table_names]


def load(path):
    """The run in directory `path` (what `sluice run SCENE --out PATH`
    wrote)."""
    return Run(path)
