"""Time-series tables of a run: the CSV files the gauges and boundaries
write, with each column's unit, description and position from the run's
index of tables (RUN/tables.json)."""

import json
import os
import warnings

import numpy as np


class Column:
    """One column of a table: its values (a numpy array, ``.values`` or
    ``numpy.asarray(column)``) and what the run says of it.

    ``unit`` is an SI unit in Sluice's notation ("s", "m", "m s^-1", "Pa",
    "N m^-1", "1" for a count or a dimensionless number); ``description`` a
    short phrase; ``position`` the point it is measured at (a tuple of the
    scene's dimension count of coordinates, m) or None. ``unit`` and
    ``description`` are None when the run did not describe the column (a
    run written before tables.json existed)."""

    __slots__ = ("name", "values", "unit", "description", "position")

    def __init__(self, name, values, unit=None, description=None, position=None):
        self.name = name
        self.values = np.asarray(values, dtype=float)
        self.unit = unit
        self.description = description
        self.position = tuple(float(c) for c in position) if position is not None else None

    def __array__(self, dtype=None, copy=None):
        if dtype is None:
            return self.values
        return self.values.astype(dtype)

    def __len__(self):
        return len(self.values)

    def __getitem__(self, index):
        return self.values[index]

    def __iter__(self):
        return iter(self.values)

    def label(self):
        """The column's name and unit as an axis label: "eta_x0 [m]"."""
        return "%s [%s]" % (self.name, self.unit) if self.unit else self.name

    def __repr__(self):
        where = " at %s" % (self.position,) if self.position is not None else ""
        return "<Column %s [%s]%s: %d values>" % (self.name, self.unit, where, len(self.values))


class Table:
    """A CSV time series of a run: ``table["eta_x0"]`` is a Column,
    ``table.time`` the time column's values, ``table.columns`` the columns in
    the file's order. ``instance`` and ``component`` name the plugin that
    wrote it (None without tables.json)."""

    def __init__(self, name, path, columns, instance=None, component=None):
        self.name = name
        self.path = path
        self.instance = instance
        self.component = component
        self.columns = list(columns)
        self._by_name = {c.name: c for c in self.columns}

    @property
    def names(self):
        """The column names, in the file's order (the CSV header)."""
        return [c.name for c in self.columns]

    @property
    def time(self):
        """The values of the column 'time' (s)."""
        return self["time"].values

    @property
    def described(self):
        """True when every column has a unit and a description."""
        return all(c.unit is not None and c.description is not None for c in self.columns)

    def __getitem__(self, name):
        try:
            return self._by_name[name]
        except KeyError:
            raise KeyError("table '%s' has no column '%s' (it has %s)"
                           % (self.name, name, ", ".join(self.names))) from None

    def __contains__(self, name):
        return name in self._by_name

    def __len__(self):
        """The number of rows."""
        return len(self.columns[0].values) if self.columns else 0

    def __iter__(self):
        return iter(self.columns)

    def select(self, unit=None, positioned=None, prefix=None):
        """The columns with this unit, with (positioned=True) or without a
        position, whose names start with prefix; None matches any."""
        chosen = []
        for c in self.columns:
            if unit is not None and c.unit != unit:
                continue
            if positioned is not None and (c.position is not None) != positioned:
                continue
            if prefix is not None and not c.name.startswith(prefix):
                continue
            chosen.append(c)
        return chosen

    def row_at(self, time):
        """The index of the row nearest to `time` (s)."""
        t = self.time
        if len(t) == 0:
            raise ValueError("table '%s' has no rows" % self.name)
        return int(np.argmin(np.abs(t - time)))

    def window(self, start, end):
        """A boolean mask of the rows with start <= time <= end."""
        t = self.time
        return (t >= start) & (t <= end)

    def __repr__(self):
        return "<Table %s (%s): %d columns, %d rows>" % (self.name, self.component,
                                                         len(self.columns), len(self))


def read_csv(path):
    """The header and the values (rows x columns, float) of a table's CSV."""
    with open(path, "r", encoding="utf-8") as f:
        header = f.readline().strip()
        if not header:
            raise ValueError("%s: no header line" % path)
        names = header.split(",")
        rows = []
        for number, line in enumerate(f, start=2):
            line = line.strip()
            if not line:
                continue
            fields = line.split(",")
            if len(fields) != len(names):
                raise ValueError("%s:%d: %d values, the header has %d columns"
                                 % (path, number, len(fields), len(names)))
            rows.append([float(v) for v in fields])
    values = np.array(rows, dtype=float).reshape(len(rows), len(names))
    return names, values


def read_index(run_dir):
    """RUN/tables.json as a dict {file name: table entry}, or None when the
    run has none."""
    path = os.path.join(run_dir, "tables.json")
    if not os.path.exists(path):
        return None
    with open(path, "r", encoding="utf-8") as f:
        index = json.load(f)
    if index.get("format") != "sluice-tables":
        raise ValueError("%s is not an index of Sluice tables" % path)
    return {entry["file"]: entry for entry in index.get("tables", [])}


def table_name(file_name):
    """A table's name: its file name without '.csv'."""
    return file_name[:-4] if file_name.endswith(".csv") else file_name


def load_table(run_dir, file_name, entry=None):
    """A Table from RUN/file_name, its columns described by `entry` (the
    file's entry of tables.json) or, without one, by the header alone."""
    path = os.path.join(run_dir, file_name)
    names, values = read_csv(path)
    described = entry["columns"] if entry else []
    if entry and [c["name"] for c in described] != names:
        warnings.warn("%s: the header differs from tables.json's columns; using the header only"
                      % path, stacklevel=3)
        described = []
    columns = []
    for k, name in enumerate(names):
        meta = described[k] if described else {}
        columns.append(Column(name, values[:, k], meta.get("unit"), meta.get("description"),
                              meta.get("position")))
    return Table(table_name(file_name), path, columns,
                 entry.get("instance") if entry else None,
                 entry.get("component") if entry else None)
