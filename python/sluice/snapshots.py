"""Particle snapshots of a run (RUN/particles_NNNNNN.h5, written by the
hdf5 plugin): lazy access to their fields, with units."""

import glob
import os
import re

import numpy as np

# The particle kinds of the dataset `kind` (core/include/sluice/plugin.h).
KINDS = {"fluid": 0, "wall": 1, "open": 2}


def _text(value):
    """An HDF5 string attribute as str."""
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, np.ndarray) and value.shape == ():
        return _text(value[()])
    return value if isinstance(value, str) else str(value)


def _kind_code(kind):
    if isinstance(kind, str):
        try:
            return KINDS[kind]
        except KeyError:
            raise ValueError("unknown particle kind '%s' (fluid, wall or open)" % kind) from None
    return int(kind)


class Field:
    """A particle field of a snapshot: ``values`` (numpy array, [N] for a
    scalar, [N, components] for a vector), ``unit`` (as the field declares
    it: "Pa", "m s^-1", "kg m^-3", "1") and ``description``.
    ``numpy.asarray(field)`` is its values."""

    __slots__ = ("name", "values", "unit", "description")

    def __init__(self, name, values, unit, description):
        self.name = name
        self.values = values
        self.unit = unit
        self.description = description

    def __array__(self, dtype=None, copy=None):
        return self.values if dtype is None else self.values.astype(dtype)

    def __len__(self):
        return len(self.values)

    def __getitem__(self, index):
        return self.values[index]

    @property
    def shape(self):
        return self.values.shape

    def magnitude(self):
        """|v| per particle for a vector field; the values for a scalar."""
        v = np.asarray(self.values, dtype=float)
        return np.sqrt(np.sum(v * v, axis=1)) if v.ndim == 2 else v

    def label(self):
        return "%s [%s]" % (self.name, self.unit) if self.unit else self.name

    def __repr__(self):
        return "<Field %s [%s] %s>" % (self.name, self.unit, self.values.shape)


class Snapshot:
    """One HDF5 snapshot. Its root attributes (time, step, dimensions,
    particle_count, smoothing_length, spacing, scene, plugins, status) are
    read when first asked for; a field's dataset only when asked for
    (``snapshot["pressure"]``, ``snapshot.field("velocity", kind="fluid")``)
    and then kept."""

    def __init__(self, path):
        self.path = path
        self._attrs = None
        self._names = None
        self._cache = {}

    def _open(self):
        import h5py

        return h5py.File(self.path, "r")

    @property
    def attrs(self):
        """The root attributes, as a dict (strings decoded)."""
        if self._attrs is None:
            with self._open() as f:
                self._attrs = {k: (_text(v) if isinstance(v, (bytes, str)) else
                                   v.item() if isinstance(v, np.generic) else v)
                               for k, v in f.attrs.items()}
                self._names = sorted(f.keys())
        return self._attrs

    @property
    def time(self):
        """The simulated time of the snapshot (s)."""
        return float(self.attrs["time"])

    @property
    def step(self):
        return int(self.attrs["step"])

    @property
    def dimensions(self):
        return int(self.attrs["dimensions"])

    @property
    def particle_count(self):
        return int(self.attrs["particle_count"])

    @property
    def status(self):
        """"ok", or "failed" for the state a failed run stopped at."""
        return self.attrs.get("status", "ok")

    @property
    def fields(self):
        """The names of the fields written in the snapshot."""
        if self._names is None:
            self.attrs
        return list(self._names)

    def __contains__(self, name):
        return name in self.fields

    def __getitem__(self, name):
        return self.field(name)

    def unit(self, name):
        """The unit of the field `name`, without reading its values."""
        if name in self._cache:
            return self._cache[name].unit
        with self._open() as f:
            if name not in f:
                raise KeyError("%s has no field '%s'" % (self.path, name))
            return _text(f[name].attrs.get("units", "")) or None

    def field(self, name, kind=None):
        """The field `name` for every particle, or only for the particles of
        `kind` ("fluid", "wall", "open", or their codes 0, 1, 2)."""
        if name not in self._cache:
            if name not in self.fields:
                raise KeyError("%s has no field '%s' (it has %s)"
                               % (self.path, name, ", ".join(self.fields)))
            with self._open() as f:
                dataset = f[name]
                self._cache[name] = Field(name, dataset[()],
                                          _text(dataset.attrs.get("units", "")) or None,
                                          _text(dataset.attrs.get("description", "")) or None)
        whole = self._cache[name]
        if kind is None:
            return whole
        mask = self.mask(kind)
        return Field(name, whole.values[mask], whole.unit, whole.description)

    def mask(self, kind):
        """A boolean array: the particles of `kind`."""
        return self.field("kind").values == _kind_code(kind)

    def fluid(self, name):
        """The field `name` of the fluid particles (kind 0)."""
        return self.field(name, kind="fluid")

    def forget(self):
        """Drops the fields read so far (memory)."""
        self._cache.clear()

    def __repr__(self):
        return "<Snapshot %s>" % os.path.basename(self.path)


def find_snapshots(run_dir, prefix="particles"):
    """The snapshots <prefix>_<index>.h5 of a run, in the order of their
    index."""
    pattern = re.compile(re.escape(prefix) + r"_(\d+)\.h5$")
    found = []
    for path in glob.glob(os.path.join(glob.escape(run_dir), prefix + "_*.h5")):
        match = pattern.search(os.path.basename(path))
        if match:
            found.append((int(match.group(1)), path))
    return [Snapshot(path) for _, path in sorted(found)]
