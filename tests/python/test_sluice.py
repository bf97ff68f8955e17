"""Tests of the Python package `sluice` (python/sluice) on real runs of the
built sluice program (unittest; meson test `python`).

 - A still tank (1 m x 0.5 m of water, dx = 0.02 m, 0.2 s) with a
   free-surface gauge and a point gauge of velocity and pressure: the
   particle counts against the geometry (50 x 25 fluid particles) and
   run.json, the fields' units, the gauge columns' units and positions
   against the scene; the t = 0 state against hydrostatics: the snapshot's
   fluid pressure is rho0 g (H - y) (the start is exactly hydrostatic: to
   1e-9 rho0 g H, as suite physics asserts for the same start), the point
   gauge's Shepard-interpolated pressure on the symmetric lattice within
   1.2e-3 (the relative spread of the particle volumes m/rho_j across a
   kernel support, rho0 g 2h / (7 B), bounds its bias) and the free surface
   at H within dx/4. A restart from the checkpoint at 0.1 s writes the same
   tables.json and the table continues without a repeated row.
 - The hydraulic jump scene (configs/hydraulic_jump_jonsson2016.yaml, its
   0.05 first seconds): every table of its seven gauges and boundaries is
   described, its columns are its CSV header, its gauge positions are the
   scene's (and the pressure sensors' are the centres in
   bed_pressure_sensors.csv); the plots and docs/examples/free_surface.py
   write PNG files.
 - run.probe through the built `sluice probe` at the tank's gauge points
   at t = 0 (the point gauge's values to 10 digits, hydrostatic within the
   tolerance above), and against a stand-in script printing the
   sub-command's CSV format: the command line it is given, the table parsed
   from its output, the units taken from the snapshots, a failure's
   message.
 - A run written before tables.json existed loads with a warning and
   header-only columns.

Environment (set by tests/meson.build): SLUICE (the built program),
SLUICE_SOURCE_DIR; the package is imported from SLUICE_SOURCE_DIR/python.
Exits 77 (meson: skipped) when numpy or h5py is missing."""

import csv
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import unittest
import warnings

try:
    import h5py  # noqa: F401
    import numpy as np
except ImportError as missing:
    print("skipped: %s (Debian: apt-get install python3-numpy python3-h5py)" % missing)
    sys.exit(77)

SOURCE = os.environ.get("SLUICE_SOURCE_DIR",
                        os.path.dirname(os.path.dirname(os.path.dirname(
                            os.path.abspath(__file__)))))
sys.path.insert(0, os.path.join(SOURCE, "python"))

import sluice  # noqa: E402
from sluice import plot  # noqa: E402

PROGRAM = os.environ.get("SLUICE") or shutil.which("sluice")
RHO0, G, H, DX = 1000.0, 9.81, 0.5, 0.02
SPEED_OF_SOUND = 22.1
TANK_SCENE = """\
title: still tank for the Python package's tests
dimensions: 2
particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: 1000}
time: {end: 0.2}
checkpoint: {interval: 0.1}
domain: {min: [-0.2, -0.2], max: [1.2, 1.0]}
geometry:
  fluid:
    - {shape: box, min: [0, 0], max: [1.0, 0.5]}
  walls:
    - {shape: tank, min: [0, 0], max: [1.0, 0.8], name: tank}
initial: {density: hydrostatic}
plugins:
  wendland_c2: {}
  tait: {speed_of_sound: 22.1}
  continuity: {}
  delta_sph: {delta: 0.1, form: fourtakas}
  pressure_gradient: {}
  artificial_viscosity: {alpha: 0.1}
  gravity: {}
  dbc: {}
  time_step: {}
  symplectic: {}
  free_surface_gauge: {positions: [0.75, 0.25, 0.5], interval: 0.01}
  point_gauge: {points: [[0.5, 0.1], [0.3, 0.25]], fields: "velocity,pressure", interval: 0.01}
  hdf5: {interval: 0.1}
"""

SCRATCH = None
TANK = {}


def tank_run():
    """The still tank's run directory (run once)."""
    if "out" not in TANK:
        directory = os.path.join(SCRATCH, "tank")
        os.makedirs(directory)
        TANK["scene"] = os.path.join(directory, "scene.yaml")
        with open(TANK["scene"], "w") as f:
            f.write(TANK_SCENE)
        run_sluice(TANK["scene"], "--out", os.path.join(directory, "run"))
        TANK["out"] = os.path.join(directory, "run")
    return TANK["out"]


def setUpModule():
    global SCRATCH
    if not PROGRAM or not os.access(PROGRAM, os.X_OK):
        raise RuntimeError("the sluice program was not found: set SLUICE")
    SCRATCH = tempfile.mkdtemp(prefix="sluice-python-")


def tearDownModule():
    if SCRATCH:
        shutil.rmtree(SCRATCH, ignore_errors=True)


def run_sluice(*arguments):
    done = subprocess.run([PROGRAM, "run", *arguments], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, check=False)
    if done.returncode != 0:
        raise AssertionError("sluice run %s failed (%d): %s"
                             % (" ".join(arguments), done.returncode, done.stderr.decode()))


class StillTank(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.out = tank_run()
        cls.dir = os.path.dirname(cls.out)
        cls.scene = TANK["scene"]
        cls.result = sluice.load(cls.out)

    def test_info_scene_and_counts(self):
        run = self.result
        self.assertEqual(run.info["status"], "complete")
        self.assertAlmostEqual(run.info["simulated_time"], 0.2, places=9)
        self.assertEqual(run.dimensions, 2)
        self.assertEqual(run.scene["plugins"]["tait"]["speed_of_sound"], SPEED_OF_SOUND)
        self.assertEqual([round(s.time, 9) for s in run.snapshots], [0.0, 0.1, 0.2])
        first, last = run.snapshots[0], run.snapshots[-1]
        self.assertEqual(first.step, 0)
        self.assertEqual(first.particle_count, run.info["particles_initial"])
        self.assertEqual(last.particle_count, run.info["particles_final"])
        self.assertEqual(last.step, run.info["steps"])
        # the fluid box holds 50 x 25 particles of the lattice
        self.assertEqual(np.count_nonzero(first.mask("fluid")), 50 * 25)
        self.assertEqual(len(first.fluid("pressure")), 50 * 25)
        self.assertEqual(np.count_nonzero(first.mask("wall")), first.particle_count - 1250)
        self.assertEqual(np.count_nonzero(first.mask("open")), 0)
        self.assertEqual(first.status, "ok")

    def test_units(self):
        snapshot = self.result.snapshots[0]
        self.assertEqual(snapshot["pressure"].unit, "Pa")
        self.assertEqual(snapshot["velocity"].unit, "m s^-1")
        self.assertEqual(snapshot["density"].unit, "kg m^-3")
        self.assertEqual(snapshot["position"].unit, "m")
        self.assertEqual(snapshot["position"].shape, (snapshot.particle_count, 2))
        self.assertEqual(snapshot.unit("pressure"), "Pa")
        self.assertTrue(snapshot["pressure"].description)
        points = self.result.table("points")
        self.assertEqual(points.component, "point_gauge")
        self.assertEqual(points["time"].unit, "s")
        self.assertEqual(points["p0_pressure"].unit, "Pa")
        self.assertEqual(points["p1_velocity_y"].unit, "m s^-1")
        self.assertTrue(points.described)
        surface = self.result.tables["free_surface"]
        self.assertEqual(surface["eta_x2"].unit, "m")

    def test_positions_are_the_scene_s(self):
        gauge = self.result.plugin("point_gauge")
        points = self.result.table("points")
        for k, point in enumerate(gauge["points"]):
            for column in ("p%d_velocity_x" % k, "p%d_velocity_y" % k, "p%d_pressure" % k):
                self.assertEqual(points[column].position, tuple(point[:2]))
        self.assertIsNone(points["time"].position)
        positions = self.result.plugin("free_surface_gauge")["positions"]
        surface = self.result.table("free_surface")
        for k, x in enumerate(positions):
            self.assertEqual(surface["eta_x%d" % k].position[0], x)
        x, _ = plot.free_surface_profile(self.result, time=0)
        self.assertEqual(list(x), sorted(positions))

    def test_hydrostatic_start(self):
        first = self.result.snapshots[0]
        self.assertEqual(first.time, 0)
        p = first.fluid("pressure").values
        y = first.fluid("position").values[:, 1]
        np.testing.assert_allclose(p, RHO0 * G * (H - y), rtol=0, atol=1e-9 * RHO0 * G * H)
        points = self.result.table("points")
        self.assertEqual(points.time[0], 0)
        B = SPEED_OF_SOUND ** 2 * RHO0 / 7
        h = 1.5 * DX
        tolerance = RHO0 * G * 2 * h / (7 * B)
        for k, point in enumerate(self.result.plugin("point_gauge")["points"]):
            expected = RHO0 * G * (H - point[1])
            self.assertLess(abs(points["p%d_pressure" % k][0] / expected - 1), tolerance)
            self.assertLess(abs(points["p%d_velocity_x" % k][0]), 1e-9)
        surface = self.result.table("free_surface")
        for column in surface.select(unit="m", positioned=True):
            self.assertLess(abs(column[0] - H), DX / 4)

    def test_probe(self):
        # `sluice probe` at the point gauge's points from the t = 0 snapshot:
        # the gauge's rows to their 10 digits (the same point pass), the
        # hydrostatic pressure as above, inside the fluid
        gauge = self.result.plugin("point_gauge")["points"]
        probed = self.result.probe(gauge, ["pressure", "velocity"], times=0, program=PROGRAM)
        self.assertEqual(probed.names, ["time", "point", "x", "y", "pressure", "velocity_x",
                                        "velocity_y", "support"])
        self.assertEqual(probed["pressure"].unit, "Pa")
        self.assertEqual(probed["velocity_y"].unit, "m s^-1")
        np.testing.assert_array_equal(probed["point"].values, [0, 1])
        np.testing.assert_array_equal(probed.time, [0, 0])
        points = self.result.table("points")
        B = SPEED_OF_SOUND ** 2 * RHO0 / 7
        tolerance = RHO0 * G * 2 * 1.5 * DX / (7 * B)
        for k, point in enumerate(gauge):
            self.assertEqual((probed["x"][k], probed["y"][k]), tuple(point))
            self.assertAlmostEqual(probed["pressure"][k] / points["p%d_pressure" % k][0], 1,
                                   delta=1e-9)
            self.assertLess(abs(probed["pressure"][k] / (RHO0 * G * (H - point[1])) - 1),
                            tolerance)
            self.assertGreater(probed["support"][k], 0.9)

    def test_restart_keeps_the_index(self):
        # a copy of the run, restarted from its first checkpoint
        copy = os.path.join(self.dir, "restarted")
        shutil.copytree(self.out, copy)
        with open(os.path.join(copy, "tables.json")) as f:
            index = f.read()
        os.remove(os.path.join(copy, "tables.json"))
        checkpoints = sorted(n for n in os.listdir(copy) if n.startswith("checkpoint_"))
        self.assertEqual(len(checkpoints), 2)
        run_sluice(self.scene, "--out", copy, "--restart", os.path.join(copy, checkpoints[0]))
        with open(os.path.join(copy, "tables.json")) as f:
            self.assertEqual(f.read(), index)
        restarted = sluice.load(copy)
        self.assertEqual(restarted.info["restarted_at_step"], int(checkpoints[0][11:20]))
        time = restarted.table("free_surface").time
        np.testing.assert_allclose(time, np.arange(21) * 0.01, atol=1e-9)
        original = self.result.table("points")
        self.assertEqual(restarted.table("points").names, original.names)
        self.assertEqual(restarted.table("points")["p0_pressure"].position, (0.5, 0.1))

    def test_plots(self):
        snapshot = self.result.snapshots[-1]
        outputs = {
            "surface.png": plot.free_surface(self.result, window=(0.1, 0.2)),
            "series.png": plot.series(self.result, "points", "p0_pressure"),
            "particles.png": plot.particles(snapshot, "pressure"),
            "speed.png": plot.particles(snapshot, "velocity", kind=None),
        }
        for name, ax in outputs.items():
            path = os.path.join(self.dir, name)
            ax.figure.savefig(path)
            with open(path, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertEqual(outputs["series.png"].get_ylabel(), "p0_pressure [Pa]")
        # the window's mean is the mean of the window's rows
        table = self.result.table("free_surface")
        x, eta = plot.free_surface_profile(self.result, window=(0.1, 0.2))
        rows = (table.time >= 0.1) & (table.time <= 0.2)
        self.assertEqual(np.count_nonzero(rows), 11)
        self.assertAlmostEqual(eta[list(x).index(0.25)],
                               float(np.mean(table["eta_x1"].values[rows])), places=12)


class HydraulicJump(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.out = os.path.join(SCRATCH, "jump")
        run_sluice(os.path.join(SOURCE, "configs", "hydraulic_jump_jonsson2016.yaml"),
                   "--out", cls.out, "--set", "time.end=0.05")
        cls.result = sluice.load(cls.out)

    def test_every_table_described(self):
        names = self.result.table_names
        self.assertEqual(sorted(names), sorted(["inlet", "outlet", "sections", "free_surface",
                                                "points", "bed_pressure", "walls"]))
        for name in names:
            table = self.result.tables[name]
            with open(table.path) as f:
                header = next(csv.reader(f))
            self.assertEqual(table.names, header)
            self.assertTrue(table.described, name)
            self.assertEqual(table["time"].unit, "s")
            self.assertGreater(len(table), 0)
        self.assertEqual(self.result.table("inlet")["discharge"].unit, "m^2 s^-1")
        self.assertEqual(self.result.table("sections")["Fr_x3"].unit, "1")
        self.assertEqual(self.result.table("free_surface_gauge").name, "free_surface")

    def test_gauge_positions(self):
        scene = self.result.scene["plugins"]
        surface = self.result.table("free_surface")
        for k, x in enumerate(scene["free_surface_gauge"]["positions"]):
            self.assertEqual(surface["eta_x%d" % k].position[0], x)
        sections = self.result.table("sections")
        for k, x in enumerate(scene["section_gauge"]["positions"]):
            self.assertEqual(sections["q_x%d" % k].position[0], x)
        points = self.result.table("points")
        for k, point in enumerate(scene["point_gauge"]["points"]):
            self.assertEqual(points["p%d_velocity_x" % k].position, tuple(point))
        # the sensors' face centres, as the gauge's own description file has them
        floor = self.result.table("bed_pressure")
        with open(os.path.join(self.out, "bed_pressure_sensors.csv")) as f:
            sensors = list(csv.DictReader(f))
        self.assertEqual(len(sensors), 21)
        for sensor in sensors:
            position = floor[sensor["name"] + "_Pa"].position
            self.assertAlmostEqual(position[0], float(sensor["x_m"]), places=8)
            self.assertAlmostEqual(position[1], float(sensor["y_m"]), places=8)

    def test_snapshots_and_counts(self):
        last = self.result.snapshots[-1]
        self.assertAlmostEqual(last.time, self.result.info["simulated_time"], places=9)
        self.assertEqual(last.particle_count, self.result.info["particles_final"])
        kind = last["kind"].values
        self.assertEqual(len(kind), last.particle_count)
        self.assertTrue(set(np.unique(kind)) <= {0, 1, 2})
        self.assertEqual(np.count_nonzero(last.mask("fluid")) + np.count_nonzero(last.mask("wall"))
                         + np.count_nonzero(last.mask("open")), last.particle_count)
        # the inlet's buffer holds open particles
        self.assertGreater(np.count_nonzero(last.mask("open")), 0)
        self.assertEqual(np.count_nonzero(last.mask(2)), np.count_nonzero(last.mask("open")))

    def test_example_script(self):
        png = os.path.join(SCRATCH, "example.png")
        done = subprocess.run([sys.executable, os.path.join(SOURCE, "docs", "examples",
                                                            "free_surface.py"),
                               self.out, "--out", png, "--from", "0", "--to", "0.05"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, check=False,
                              env=dict(os.environ, PYTHONPATH=os.path.join(SOURCE, "python")))
        self.assertEqual(done.returncode, 0, done.stderr.decode())
        with open(png, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")


FAKE_PROBE = """\
#!{python}
# Stands in for `sluice probe` (its CSV format): records its arguments, then
# prints two points at the times asked for.
import sys
with open({record!r}, "w") as f:
    f.write("\\n".join(sys.argv[1:]))
if "--fail" in {fail!r}:
    sys.stderr.write("sluice: error: no field 'vorticity' in the snapshots\\n")
    sys.exit(2)
print("time,point,x,y,velocity_x,velocity_y,pressure,support")
for time in (0.0, 0.1):
    print("%g,0,0.5,0.1,0.25,-0.5,3924,0.98" % time)
    print("%g,1,0.5,0.9,nan,nan,nan,0" % time)
"""


class Probe(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = os.path.join(SCRATCH, "probe")
        os.makedirs(cls.dir)
        cls.record = os.path.join(cls.dir, "arguments")
        cls.fake = cls.write_fake("sluice", "")
        cls.failing = cls.write_fake("failing", "--fail")
        cls.result = sluice.load(tank_run())

    @classmethod
    def write_fake(cls, name, fail):
        path = os.path.join(cls.dir, name)
        with open(path, "w") as f:
            f.write(FAKE_PROBE.format(python=sys.executable, record=cls.record, fail=fail))
        os.chmod(path, 0o755)
        return path

    def arguments(self):
        with open(self.record) as f:
            return f.read().split("\n")

    def test_command_and_table(self):
        table = self.result.probe([(0.5, 0.1), (0.5, 0.9)], ["velocity", "pressure"],
                               times="all", program=self.fake)
        self.assertEqual(self.arguments(),
                         ["probe", self.result.path, "--points", "0.5,0.1;0.5,0.9",
                          "--fields", "velocity,pressure", "--times", "all"])
        self.assertEqual(table.names, ["time", "point", "x", "y", "velocity_x", "velocity_y",
                                       "pressure", "support"])
        self.assertEqual(len(table), 4)
        np.testing.assert_array_equal(table["point"].values, [0, 1, 0, 1])
        self.assertEqual(table["pressure"][0], 3924)
        self.assertTrue(np.isnan(table["pressure"][1]))
        # units from the run's snapshots
        self.assertEqual(table["pressure"].unit, "Pa")
        self.assertEqual(table["velocity_y"].unit, "m s^-1")
        self.assertEqual(table["x"].unit, "m")
        self.assertEqual(table["support"].unit, "1")

    def test_times_and_program_lookup(self):
        saved = dict(os.environ)
        try:
            os.environ["SLUICE"] = self.fake
            sluice.probe(self.result.path, [[0.1, 0.2, 0.3]], "pressure", times=[0.1, 0.2])
            self.assertEqual(self.arguments()[3:], ["0.1,0.2,0.3", "--fields", "pressure",
                                                    "--times", "0.1,0.2"])
            del os.environ["SLUICE"]
            os.environ["PATH"] = self.dir + os.pathsep + saved.get("PATH", "")
            self.result.probe([(0.5, 0.1)], "velocity", times=0.2)
            self.assertEqual(self.arguments()[-2:], ["--times", "0.2"])
        finally:
            os.environ.clear()
            os.environ.update(saved)

    def test_failure_message(self):
        with self.assertRaises(sluice.SluiceError) as caught:
            self.result.probe([(0.5, 0.1)], "vorticity", program=self.failing)
        self.assertIn("no field 'vorticity'", str(caught.exception))
        self.assertIn("exit status 2", str(caught.exception))
        with self.assertRaises(ValueError):
            self.result.probe([(0.5,)], "pressure", program=self.fake)


class BeforeTheIndex(unittest.TestCase):
    def test_header_only_with_a_warning(self):
        copy = os.path.join(SCRATCH, "old-run")
        shutil.copytree(tank_run(), copy)
        os.remove(os.path.join(copy, "tables.json"))
        run = sluice.load(copy)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            table = run.table("free_surface")
        self.assertTrue(any("tables.json" in str(w.message) for w in caught))
        self.assertEqual(table.names, ["time", "eta_x0", "eta_x1", "eta_x2"])
        self.assertIsNone(table["eta_x0"].unit)
        self.assertIsNone(table["eta_x0"].position)
        self.assertFalse(table.described)
        self.assertEqual(len(table), 21)


if __name__ == "__main__":
    unittest.main(verbosity=2)
