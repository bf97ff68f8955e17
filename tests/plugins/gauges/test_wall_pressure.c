/* Wall pressure sensors (plugins/gauges/wall_pressure.c) and plugin
 * instances (a plugin loaded several times under names of its own).
 *
 *  - Hydrostatic tank, every wall scheme (dbc, mdbc, ghost_particles,
 *    penalty_contact, repulsive_force), 2D and 3D: at t = 0 the fluid is at
 *    hydrostatic rest (initial density hydrostatic: p_j = rho0 g (H - y_j)
 *    exactly), and the sensor's extrapolation
 *        p(x_s) = sum_j V_j W [p_j + rho_j g . (x_s - x_j)] / sum_j V_j W
 *    gives rho0 g (H - y_s) up to (rho_j - rho0) g (y_j - y_s): at most
 *    (max rho_j / rho0 - 1) rho0 g 2h, below 0.2 % of rho0 g H here (the
 *    tank's largest density excess, rho0 g H / B = 7 g H / c0^2, is 0.7 %,
 *    over 2h = 3 dx = 0.06 m against H = 0.2 m). A face's mean of a
 *    linear field is the value at its centre, so segments, discs and
 *    rectangles centred at y_c read rho0 g (H - y_c) within the same bound.
 *  - A dry face (above the water) reads exactly 0 and wet fraction 0, in
 *    every row, never nan. A face that straddles the surface (0.03 m below
 *    it to 0.03 m above) reads the mean of rho0 g (H - y) over the whole
 *    face, dry half included (the extrapolation reads 0 above the surface),
 *    within the bound above plus the midpoint-rule error of the cell that
 *    holds the surface; its wet fraction lies strictly between 0 and 1.
 *  - The filtered column is the first-order filter of the raw one:
 *    y_k = y_{k-1} + (1 - exp(-(t_k - t_{k-1}) / tau)) (p_k - y_{k-1}), to
 *    the CSV's printed digits.
 *  - Face areas: a 3D rectangle's cells cover size x height exactly; a
 *    disc's cover pi D^2 / 4 within the cells along its rim (perimeter x
 *    cell side).
 *  - Instances: two instances of wall_pressure with files of their own
 *    read the same value at the same face; an instance of dbc under another
 *    name handles the walls that name it. Refusals, each at file:line:col:
 *    two instances writing one table, an instance named like another plugin,
 *    an unknown `plugin`, an invalid instance name, a sensor far from any
 *    wall, names that do not match the positions, 3D keys in 2D. */
#include <math.h>

#include "sim_util.h"

#define RHO0 1000.0
#define G 9.81
#define DEPTH 0.2

static const char *const schemes[] = {"dbc", "mdbc", "ghost_particles", "penalty_contact",
                                      "repulsive_force"};

/* A tank 0.4 m long (and 0.2 m across in 3D) with water DEPTH deep at
 * dx = 0.02 m, the wall scheme's line `scheme` ("dbc: {}"), `wall_keys`
 * added to the tank wall ("" or ", scheme: NAME"), and `extra` plugin lines. */
static char *scene_text(int dims, const char *scheme, const char *wall_keys, double end,
                        const char *extra)
{
    char *yaml = NULL;
    if (dims == 2)
        ck_assert_int_ge(
            asprintf(&yaml,
                     "dimensions: 2\n"
                     "particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: "
                     "1000}\n"
                     "time: {end: %g}\n"
                     "domain: {min: [-0.1, -0.1], max: [0.5, 0.4]}\n"
                     "geometry:\n"
                     "  fluid: [{shape: box, min: [0, 0], max: [0.4, %g]}]\n"
                     "  walls: [{shape: tank, min: [0, 0], max: [0.4, 0.3], name: tank%s}]\n"
                     "initial: {density: hydrostatic}\n"
                     "plugins:\n"
                     "  wendland_c2: {}\n"
                     "  tait: {speed_of_sound: 14}\n"
                     "  continuity: {}\n"
                     "  delta_sph: {delta: 0.1, form: fourtakas}\n"
                     "  pressure_gradient: {}\n"
                     "  artificial_viscosity: {alpha: 0.1}\n"
                     "  gravity: {}\n"
                     "  %s\n"
                     "  time_step: {}\n"
                     "  symplectic: {}\n"
                     "%s",
                     end, DEPTH, wall_keys, scheme, extra),
            0);
    else
        ck_assert_int_ge(
            asprintf(&yaml,
                     "dimensions: 3\n"
                     "particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: "
                     "1000}\n"
                     "time: {end: %g}\n"
                     "domain: {min: [-0.1, -0.1, -0.1], max: [0.5, 0.3, 0.4]}\n"
                     "geometry:\n"
                     "  fluid: [{shape: box, min: [0, 0, 0], max: [0.4, 0.2, %g]}]\n"
                     "  walls: [{shape: tank, min: [0, 0, 0], max: [0.4, 0.2, 0.3], name: "
                     "tank%s}]\n"
                     "initial: {density: hydrostatic}\n"
                     "plugins:\n"
                     "  wendland_c2: {}\n"
                     "  tait: {speed_of_sound: 14}\n"
                     "  continuity: {}\n"
                     "  delta_sph: {delta: 0.1, form: fourtakas}\n"
                     "  pressure_gradient: {}\n"
                     "  artificial_viscosity: {alpha: 0.1}\n"
                     "  gravity: {}\n"
                     "  %s\n"
                     "  time_step: {}\n"
                     "  symplectic: {}\n"
                     "%s",
                     end, DEPTH, wall_keys, scheme, extra),
            0);
    return yaml;
}

/* The tank with walls of the plugin `scheme` under its own name. */
static char *tank_scene(int dims, const char *scheme, double end, const char *extra)
{
    char *line = NULL;
    ck_assert_int_ge(asprintf(&line, "%s: {}", scheme), 0);
    char *yaml = scene_text(dims, line, "", end, extra);
    free(line);
    return yaml;
}

/* Runs `yaml` to its end time into a scratch directory; returns it. */
static char *run_scene(const char *tag, const char *yaml)
{
    sluice_sim *sim = test_load(tag, yaml, NULL, 0);
    char *dir = test_scratch(tag);
    ck_assert_ptr_nonnull(dir);
    char *out = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", dir), 0);
    sluice_run_options options = {out, 0, 1, 0};
    ck_assert_int_eq(sluice_sim_run(sim, &options), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    free(dir);
    return out;
}

/* The CSV `name` of run directory `dir`: its header and its rows, each of
 * `*columns` values. */
typedef struct csv {
    char header[8192];
    int rows, columns;
    double *values;
} csv;

static csv read_csv(const char *dir, const char *name)
{
    csv c;
    memset(&c, 0, sizeof c);
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", dir, name), 0);
    FILE *f = fopen(path, "r");
    ck_assert_msg(f != NULL, "no %s", path);
    ck_assert_ptr_nonnull(fgets(c.header, sizeof c.header, f));
    c.columns = 1;
    for (const char *p = c.header; *p; p++)
        c.columns += *p == ',';
    char line[16384];
    while (fgets(line, sizeof line, f)) {
        c.values = realloc(c.values, (size_t)(c.rows + 1) * (size_t)c.columns * sizeof *c.values);
        ck_assert_ptr_nonnull(c.values);
        char *p = line;
        for (int k = 0; k < c.columns; k++) {
            char *end;
            c.values[(size_t)c.rows * (size_t)c.columns + (size_t)k] = strtod(p, &end);
            ck_assert_msg(end != p, "%s: row %d has fewer than %d values", name, c.rows + 1,
                          c.columns);
            p = *end == ',' ? end + 1 : end;
        }
        c.rows++;
    }
    fclose(f);
    free(path);
    return c;
}

static double at(const csv *c, int row, int column)
{
    return c->values[(size_t)row * (size_t)c->columns + (size_t)column];
}

/* Sensors at 2D: the right wall at y = 0.05, 0.1, 0.15 (segments 0.02 m),
 * the floor's middle (0.1 m), a dry face at y = 0.25, a face across the
 * surface (y 0.17-0.23); 3D: rectangles on the right wall, a disc on the
 * floor, a dry disc. Expected readings rho0 g (H - y_c); -1: dry; -2: the
 * face across the surface. */
static const char sensors_2d[] =
    "  wall_pressure:\n"
    "    positions: [[0.4, 0.05], [0.4, 0.1], [0.4, 0.15], [0.2, 0], [0.4, 0.25], [0, 0.2]]\n"
    "    names: side05,side10,side15,floor,dry,surface\n"
    "    size: [0.02, 0.02, 0.02, 0.1, 0.02, 0.06]\n"
    "    interval: 0.002\n";
static const char sensors_3d[] =
    "  wall_pressure:\n"
    "    positions: [[0.4, 0.1, 0.05], [0.4, 0.1, 0.1], [0.4, 0.1, 0.15], [0.2, 0.1, 0], [0.4, "
    "0.1, 0.25], [0, 0.1, 0.2]]\n"
    "    names: side05,side10,side15,floor,dry,surface\n"
    "    shape: rectangle\n"
    "    size: [0.04]\n"
    "    height: [0.02, 0.02, 0.02, 0.06, 0.02, 0.06]\n"
    "    interval: 0.002\n";
static const double expected[] = {RHO0 * G * (DEPTH - 0.05), RHO0 * G * (DEPTH - 0.1),
                                  RHO0 * G * (DEPTH - 0.15), RHO0 * G * DEPTH, -1, -2};

START_TEST(hydrostatic_every_scheme)
{
    const double bound = 0.002 * RHO0 * G * DEPTH;
    for (int dims = 2; dims <= 3; dims++)
        for (size_t k = 0; k < sizeof schemes / sizeof *schemes; k++) {
            char tag[64];
            snprintf(tag, sizeof tag, "wp-hydro-%dd-%s", dims, schemes[k]);
            char *yaml = tank_scene(dims, schemes[k], 0.004, dims == 2 ? sensors_2d : sensors_3d);
            char *out = run_scene(tag, yaml);
            csv c = read_csv(out, "wall_pressure.csv");
            ck_assert_str_eq(c.header,
                             "time,side05_Pa,side05_wet,side10_Pa,side10_wet,side15_Pa,side15_"
                             "wet,floor_Pa,floor_wet,dry_Pa,dry_wet,surface_Pa,surface_wet\n");
            ck_assert_int_ge(c.rows, 3);
            for (int s = 0; s < 6; s++) {
                const double p = at(&c, 0, 1 + 2 * s), wet = at(&c, 0, 2 + 2 * s);
                fprintf(stderr, "%dD %-16s sensor %d: %.3f Pa (wet %.3f), expected %.3f\n", dims,
                        schemes[k], s, p, wet, expected[s]);
                if (expected[s] >= 0) {
                    ck_assert_msg(fabs(p - expected[s]) <= bound, "%s sensor %d: %g Pa, %g", tag,
                                  s, p, expected[s]);
                    ck_assert_msg(wet == 1, "%s sensor %d: wet %g", tag, s, wet);
                } else if (expected[s] == -1) {
                    /* dry in every row: exactly 0, never nan */
                    for (int r = 0; r < c.rows; r++)
                        ck_assert_msg(at(&c, r, 1 + 2 * s) == 0 && at(&c, r, 2 + 2 * s) == 0,
                                      "%s: dry face reads %g (wet %g) at row %d", tag,
                                      at(&c, r, 1 + 2 * s), at(&c, r, 2 + 2 * s), r);
                } else {
                    /* 0.06 m from 0.03 m below the surface to 0.03 m above it: the mean
                     * of rho0 g (H - y) over the wet half, rho0 g 0.03^2 / 2 / 0.06;
                     * its cells are dx/4 = 0.005 m long, and the one holding the
                     * surface adds a midpoint-rule error of at most
                     * rho0 g (0.005)^2 / 8 / 0.06 */
                    const double mean = RHO0 * G * 0.03 * 0.03 / 2 / 0.06;
                    const double cell = RHO0 * G * 0.005 * 0.005 / 8 / 0.06;
                    ck_assert_msg(fabs(p - mean) <= bound + cell && wet > 0 && wet < 1,
                                  "%s: the face across the surface reads %g Pa (wet %g), "
                                  "expected %g",
                                  tag, p, wet, mean);
                }
            }
            free(c.values);
            free(out);
            free(yaml);
        }
}
END_TEST

/* The filtered column against the filter applied to the raw one, and the
 * description file of 3D faces. */
START_TEST(filter_and_faces)
{
    const double tau = 0.005;
    char *extra = NULL;
    ck_assert_int_ge(asprintf(&extra,
                              "  wall_pressure:\n"
                              "    positions: [[0.4, 0.1, 0.05], [0.2, 0.1, 0], [0.2, 0.1, 0]]\n"
                              "    names: side,floor,floor_disc\n"
                              "    shape: rectangle\n"
                              "    size: [0.04, 0.06, 0.05]\n"
                              "    height: [0.02, 0.03, 0.05]\n"
                              "    interval: 0.001\n"
                              "    time_constant: %g\n"
                              "  discs:\n"
                              "    plugin: wall_pressure\n"
                              "    positions: [[0.2, 0.1, 0]]\n"
                              "    names: floor_disc\n"
                              "    size: [0.05]\n"
                              "    interval: 0.001\n"
                              "    file: discs.csv\n",
                              tau),
                     0);
    char *yaml = tank_scene(3, "dbc", 0.03, extra);
    char *out = run_scene("wp-filter", yaml);
    csv c = read_csv(out, "wall_pressure.csv");
    ck_assert_str_eq(c.header, "time,side_Pa,side_filtered_Pa,side_wet,floor_Pa,floor_filtered_"
                               "Pa,floor_wet,floor_disc_Pa,floor_disc_filtered_Pa,floor_disc_"
                               "wet\n");
    ck_assert_int_ge(c.rows, 25);
    double largest = 0;
    for (int s = 0; s < 3; s++) {
        double y = at(&c, 0, 1 + 3 * s);
        ck_assert_double_eq(at(&c, 0, 2 + 3 * s), y);
        for (int r = 1; r < c.rows; r++) {
            const double dt = at(&c, r, 0) - at(&c, r - 1, 0);
            /* the filter of the printed raw values; the printed filter carries its own
             * rounding, 5e-10 relative, through the recursion (gain < 1) */
            y += (1 - exp(-dt / tau)) * (at(&c, r, 1 + 3 * s) - y);
            const double printed = at(&c, r, 2 + 3 * s);
            largest = fmax(largest, fabs(printed - y) / fabs(y));
            ck_assert_msg(fabs(printed - y) <= 1e-8 * fabs(y) * (r + 1),
                          "sensor %d row %d: filtered %.10g, recursion %.10g", s, r, printed, y);
        }
    }
    fprintf(stderr, "filter: largest relative departure from the recursion %.2e\n", largest);
    /* the same face read by two instances: a rectangle 0.05 x 0.05 and a
     * disc of 0.05 are both centred on the floor's middle: both read rho0 g H
     * at t = 0 */
    csv d = read_csv(out, "discs.csv");
    ck_assert_str_eq(d.header, "time,floor_disc_Pa,floor_disc_wet\n");
    ck_assert_int_eq(d.rows, c.rows);
    ck_assert_msg(fabs(at(&d, 0, 1) - RHO0 * G * DEPTH) <= 0.002 * RHO0 * G * DEPTH, "disc %g",
                  at(&d, 0, 1));
    ck_assert_msg(fabs(at(&c, 0, 7) - RHO0 * G * DEPTH) <= 0.002 * RHO0 * G * DEPTH,
                  "square %g", at(&c, 0, 7));
    /* the faces' areas: rectangles exact, the disc within its rim's cells */
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/wall_pressure_sensors.csv", out), 0);
    char *text = test_read_file(path);
    ck_assert_ptr_nonnull(text);
    ck_assert_ptr_nonnull(strstr(text, "name,x_m,y_m,z_m,normal_x,normal_y,normal_z,shape,size_m,"
                                       "height_m,area_m2,cells,wall\n"));
    ck_assert_ptr_nonnull(strstr(text, "side,0.4,0.1,0.05,-1,0,0,rectangle,0.04,0.02,0.0008,"));
    ck_assert_ptr_nonnull(strstr(text, "floor,0.2,0.1,0,0,0,1,rectangle,0.06,0.03,0.0018,"));
    free(text);
    free(path);
    ck_assert_int_ge(asprintf(&path, "%s/discs_sensors.csv", out), 0);
    text = test_read_file(path);
    ck_assert_ptr_nonnull(text);
    const char *row = strstr(text, "floor_disc,");
    ck_assert_ptr_nonnull(row);
    double values[12];
    const char *p = row + strlen("floor_disc,");
    for (int k = 0; k < 11; k++) {
        if (k == 6) { /* shape */
            ck_assert_int_eq(strncmp(p, "disc,", 5), 0);
            p += 5;
            continue;
        }
        char *end;
        values[k] = strtod(p, &end);
        p = end + 1;
    }
    const double D = 0.05, cell = 0.25 * 0.02, area = values[9];
    fprintf(stderr, "disc of %g m: cells cover %.6g m^2, pi D^2/4 = %.6g m^2\n", D, area,
            M_PI * D * D / 4);
    ck_assert_msg(fabs(area - M_PI * D * D / 4) <= M_PI * D * cell, "disc area %g", area);
    free(text);
    free(path);
    free(c.values);
    free(d.values);
    free(out);
    free(yaml);
    free(extra);
}
END_TEST

/* An instance of dbc under a name of its own handles the walls that name it,
 * and reads as the plain dbc scene does. */
START_TEST(instances)
{
    char *plain = tank_scene(2, "dbc", 0.05, sensors_2d);
    char *named = scene_text(2, "tank_walls: {plugin: dbc}", ", scheme: tank_walls", 0.05,
                             sensors_2d);
    char *a = run_scene("wp-inst-plain", plain);
    char *b = run_scene("wp-inst-named", named);
    char *ta = NULL, *tb = NULL, *pa = NULL, *pb = NULL;
    ck_assert_int_ge(asprintf(&pa, "%s/wall_pressure.csv", a), 0);
    ck_assert_int_ge(asprintf(&pb, "%s/wall_pressure.csv", b), 0);
    ta = test_read_file(pa);
    tb = test_read_file(pb);
    ck_assert_ptr_nonnull(ta);
    ck_assert_ptr_nonnull(tb);
    ck_assert_str_eq(ta, tb); /* the same physics, bit for bit */
    free(pa);
    ck_assert_int_ge(asprintf(&pa, "%s/run.json", b), 0);
    char *json = test_read_file(pa);
    ck_assert_ptr_nonnull(json);
    ck_assert_ptr_nonnull(strstr(json, "{\"component\": \"dbc\", \"instance\": \"tank_walls\""));
    free(json);
    free(ta);
    free(tb);
    free(pa);
    free(pb);
    free(a);
    free(b);
    free(plain);
    free(named);
}
END_TEST

START_TEST(refusals)
{
    struct {
        const char *tag, *extra, *needle;
    } cases[] = {
        {"wp-two-tables",
         "  wall_pressure: {positions: [[0.4, 0.1]]}\n"
         "  more: {plugin: wall_pressure, positions: [[0.4, 0.05]]}\n",
         "scene.yaml:20:3): give one of them another 'file'"},
        {"wp-named-like", "  gravity2: {}\n  tait: {plugin: wall_pressure, positions: [[0.4, 0.1]]}\n",
         "duplicate key 'tait'"},
        {"wp-other-plugin", "  front_gauge: {plugin: wall_pressure, positions: [[0.4, 0.1]]}\n",
         "'front_gauge' names another plugin: give this instance of 'wall_pressure' a name of "
         "its own"},
        {"wp-unknown", "  sensors: {plugin: wall_presure, positions: [[0.4, 0.1]]}\n",
         "no plugin named 'wall_presure' on the plugin path; did you mean 'wall_pressure'?"},
        {"wp-bad-name", "  floor.sensors: {plugin: wall_pressure, positions: [[0.4, 0.1]]}\n",
         "'floor.sensors' is not a valid name in 'plugins'"},
        {"wp-bad-plugin", "  sensors: {plugin: [wall_pressure], positions: [[0.4, 0.1]]}\n",
         "plugins.sensors.plugin must name the plugin this instance loads"},
        {"wp-far", "  wall_pressure: {positions: [[0.2, 0.1]]}\n",
         "sensor 'P1' at (0.2, 0.1, 0) m is 0.1 m from the nearest wall, more than max_distance"},
        {"wp-names", "  wall_pressure: {positions: [[0.4, 0.1], [0.4, 0.2]], names: a}\n",
         "'names' lists 1 names for 2 positions"},
        {"wp-names-twice", "  wall_pressure: {positions: [[0.4, 0.1], [0.4, 0.2]], names: 'a,a'}\n",
         "two sensors are named 'a'"},
        {"wp-names-chars", "  wall_pressure: {positions: [[0.4, 0.1]], names: 'a b'}\n",
         "'a b' may hold only letters, digits"},
        {"wp-height-2d", "  wall_pressure: {positions: [[0.4, 0.1]], height: [0.01]}\n",
         "'height' and 'shape' describe 3D faces"},
        {"wp-no-wall", "  wall_pressure: {positions: [[0.4, 0.1]], wall: gate}\n",
         "no wall is named 'gate'"},
        {"wp-sizes", "  wall_pressure: {positions: [[0.4, 0.1], [0.4, 0.2]], size: [0.01, 0.02, "
                     "0.03]}\n",
         "'size' lists 3 values for 2 sensors"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char *yaml = tank_scene(2, "dbc", 0.01, cases[k].extra);
        test_load_refused(cases[k].tag, yaml, cases[k].needle);
        free(yaml);
    }
}
END_TEST

int main(void)
{
    Suite *s = suite_create("wall_pressure");
    TCase *c = tcase_create("wall_pressure");
    tcase_set_timeout(c, 300);
    tcase_add_test(c, hydrostatic_every_scheme);
    tcase_add_test(c, filter_and_faces);
    tcase_add_test(c, instances);
    tcase_add_test(c, refusals);
    suite_add_tcase(s, c);
    return test_run_suite(s);
}
