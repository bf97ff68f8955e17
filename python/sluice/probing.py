"""Fields interpolated at points from a run's snapshots, through the sluice
program's `probe` sub-command:

    sluice probe RUN --points "x,y[,z];..." --fields NAME[,NAME...]
                 [--times all|last|T1,T2,...]

which prints a CSV `time,point,x,y[,z],<field columns>,support` (vectors as
NAME_x, NAME_y[, NAME_z], other multi-component fields NAME_0, NAME_1, ...;
support the kernel sum sum_j V_j W, 0 outside the fluid)."""

import io
import os
import shutil
import subprocess

import numpy as np

from .tables import Column, Table


class SluiceError(RuntimeError):
    """The sluice program failed: its message is the error's."""


def find_program(program=None):
    """The sluice program: `program`, else the environment variable SLUICE,
    else `sluice` on the PATH."""
    candidate = program or os.environ.get("SLUICE") or shutil.which("sluice")
    if not candidate:
        raise SluiceError("the sluice program was not found: pass program=, set SLUICE, or put "
                          "it on the PATH")
    if os.sep not in candidate:
        found = shutil.which(candidate)
        if not found:
            raise SluiceError("the sluice program '%s' is not on the PATH" % candidate)
        candidate = found
    if not os.access(candidate, os.X_OK):
        raise SluiceError("'%s' is not an executable program" % candidate)
    return candidate


def _points_argument(points):
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if points.shape[1] not in (2, 3) or points.shape[0] == 0:
        raise ValueError("points: give one or more points of 2 or 3 coordinates")
    return ";".join(",".join(repr(float(c)) for c in p) for p in points)


def _fields_argument(fields):
    if isinstance(fields, str):
        fields = [f.strip() for f in fields.split(",")]
    fields = [f for f in fields if f]
    if not fields:
        raise ValueError("fields: name at least one field")
    return ",".join(fields)


def _times_argument(times):
    if isinstance(times, str):
        return times
    times = np.atleast_1d(np.asarray(times, dtype=float))
    return ",".join(repr(float(t)) for t in times)


def probe_command(run_dir, points, fields, times="last", program=None):
    """The command line of `sluice probe` for these arguments."""
    return [find_program(program), "probe", str(run_dir), "--points", _points_argument(points),
            "--fields", _fields_argument(fields), "--times", _times_argument(times)]


def probe(run_dir, points, fields, times="last", program=None, units=None):
    """Runs `sluice probe` and returns its CSV as a Table (name "probe"):
    columns time, point, x, y[, z], the fields' columns and support. `units`
    maps a field's name to its unit (a Run passes its snapshots' units)."""
    command = probe_command(run_dir, points, fields, times, program)
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, check=False)
    if done.returncode != 0:
        message = done.stderr.decode("utf-8", "replace").strip()
        raise SluiceError("%s probe failed (exit status %d): %s"
                          % (command[0], done.returncode, message or "no message"))
    return parse_probe_csv(done.stdout.decode("utf-8"), _fields_argument(fields).split(","),
                           units or {})


def _column_field(name, fields):
    """The field a probe column belongs to, and its vector component."""
    for field in fields:
        if name == field:
            return field, None
        suffix = name[len(field) + 1:]
        if name.startswith(field + "_") and (suffix in ("x", "y", "z") or suffix.isdigit()):
            return field, suffix
    return None, None


def parse_probe_csv(text, fields, units):
    """A Table from the CSV text `sluice probe` prints."""
    stream = io.StringIO(text)
    header = stream.readline().strip()
    if not header.startswith("time,point,"):
        raise SluiceError("sluice probe printed no table (its first line: '%s')" % header[:80])
    names = header.split(",")
    rows = [line.split(",") for line in stream.read().splitlines() if line.strip()]
    for number, row in enumerate(rows, start=2):
        if len(row) != len(names):
            raise SluiceError("sluice probe: line %d has %d values, the header %d"
                              % (number, len(row), len(names)))
    values = np.array([[float(v) for v in row] for row in rows], dtype=float)
    values = values.reshape(len(rows), len(names))
    fixed = {"time": ("s", "time of the snapshot"), "point": ("1", "index of the point"),
             "x": ("m", "x of the point"), "y": ("m", "y of the point"),
             "z": ("m", "z of the point"),
             "support": ("1", "kernel sum sum_j V_j W at the point (0 outside the fluid)")}
    columns = []
    for k, name in enumerate(names):
        if name in fixed:
            unit, description = fixed[name]
        else:
            field, component = _column_field(name, fields)
            unit = units.get(field)
            description = "%s%s, interpolated" % (field or name,
                                                  ", %s component" % component if component
                                                  else "")
        columns.append(Column(name, values[:, k], unit, description))
    return Table("probe", None, columns, None, "sluice probe")
