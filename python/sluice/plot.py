"""Plots of a run with matplotlib, drawn without a display: each function
draws into the Axes it is given (``ax=``) or into a new Figure of its own
(no pyplot, so no window and no backend to choose), and returns the Axes;
``ax.figure.savefig("out.png")`` writes it."""

import warnings

import numpy as np


def _axes(ax, size=(8, 4)):
    if ax is not None:
        return ax
    from matplotlib.figure import Figure

    figure = Figure(figsize=size, layout="constrained")
    return figure.add_subplot()


def _table(run, table):
    return run.table(table) if isinstance(table, str) else table


def surface_columns(table):
    """The free-surface columns of a table (unit m, with a position), in
    the order of x, and their x."""
    columns = [c for c in table.select(unit="m", positioned=True) if c.name != "time"]
    if not columns:
        raise ValueError("table '%s' has no positioned elevation columns (unit m): is it a "
                         "free_surface_gauge table of a run with tables.json?" % table.name)
    columns.sort(key=lambda c: c.position[0])
    return columns, np.array([c.position[0] for c in columns])


def free_surface_profile(run, time=None, window=None, table="free_surface"):
    """x (m) and the free-surface elevation (m) along x: at the row nearest
    to `time` (default: the last row), or averaged over the rows of
    `window` = (start, end) (nan rows, where a column was dry, left out)."""
    table = _table(run, table)
    columns, x = surface_columns(table)
    values = np.column_stack([c.values for c in columns])
    if len(values) == 0:
        raise ValueError("table '%s' has no rows" % table.name)
    if window is not None:
        rows = table.window(*window)
        if not rows.any():
            raise ValueError("no row of '%s' lies in %g-%g s" % (table.name, window[0],
                                                               window[1]))
        with warnings.catch_warnings():
            # a column dry over the whole window averages to nan, quietly
            warnings.simplefilter("ignore", RuntimeWarning)
            eta = np.nanmean(values[rows], axis=0)
        return x, eta
    row = len(table) - 1 if time is None else table.row_at(time)
    return x, values[row]


def free_surface(run, time=None, window=None, table="free_surface", ax=None, label=None):
    """The free-surface elevation along x (from a free_surface_gauge table
    and its columns' positions): at `time` (s; the nearest row, default the
    last) or averaged over `window` = (start, end) s."""
    table = _table(run, table)
    x, eta = free_surface_profile(run, time, window, table)
    ax = _axes(ax)
    if label is None:
        if window is not None:
            label = "mean over %g-%g s" % tuple(window)
        else:
            t = table.time[len(table) - 1 if time is None else table.row_at(time)]
            label = "t = %g s" % t
    ax.plot(x, eta, marker=".", label=label)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("free-surface elevation [m]")
    ax.set_title(table.name)
    ax.grid(True, alpha=0.3)
    ax.legend()
    return ax


def series(run, table, column, ax=None):
    """A column of a table against time, labelled with its unit,
    description and position."""
    table = _table(run, table)
    c = table[column]
    ax = _axes(ax)
    ax.plot(table.time, c.values, label=c.name)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(c.label())
    title = c.description or c.name
    if c.position is not None:
        title += " at (%s) m" % ", ".join("%g" % p for p in c.position)
    ax.set_title(title, fontsize="medium")
    ax.grid(True, alpha=0.3)
    return ax


def particles(snapshot, field, component=None, kind="fluid", ax=None, size=None, cmap="viridis"):
    """The particles of a snapshot (those of `kind`: "fluid", "wall",
    "open", or None for all) in the x-y plane (x-z in 3D), coloured by
    `field`: a scalar, a vector's magnitude, or its `component` (0, 1, 2)."""
    position = snapshot.field("position", kind=kind).values
    f = snapshot.field(field, kind=kind)
    if f.values.ndim == 2:
        values = f.values[:, component] if component is not None else f.magnitude()
        name = "%s_%s" % (field, "xyz"[component]) if component is not None else "|%s|" % field
    else:
        values = f.values
        name = field
    ax = _axes(ax, (9, 4))
    vertical = 2 if position.shape[1] == 3 else 1
    if size is None:
        size = max(0.3, min(8.0, 2e4 / max(len(values), 1)))
    drawn = ax.scatter(position[:, 0], position[:, vertical], c=values, s=size, cmap=cmap,
                       linewidths=0)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("%s [m]" % ("z" if vertical == 2 else "y"))
    ax.set_title("t = %g s" % snapshot.time)
    bar = ax.figure.colorbar(drawn, ax=ax)
    bar.set_label("%s [%s]" % (name, f.unit) if f.unit else name)
    return ax
