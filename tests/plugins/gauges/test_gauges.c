/* Gauges: point_gauge (fields interpolated at points) and wall_monitor
 * (particles behind walls, fluid-wall gap), on states whose answer is known:
 *  - the hydrostatic start: p = rho0 g (H - y) (the equation of state
 *    inverted exactly), which the Shepard interpolation reproduces in the
 *    interior up to the small variation of V_j = m_j / rho_j across the
 *    support (derived bound below); a uniform velocity exactly; nan outside
 *    the fluid; an unknown field refused at its line in the scene;
 *  - air_fraction in a still two-layer tank (two_phase, water under air): 0
 *    exactly more than one kernel support below the interface, 1 above it,
 *    1/2 on it and C(d) + C(-d) = 1 at the mirrored points, up to the spread
 *    of the particle volumes m/rho of the hydrostatic start (bound derived
 *    below); computed over both phases under `phase: water`, and refused
 *    without two_phase naming the parameter;
 *  - the lattice start of a tank: no particle behind a wall, smallest gap and
 *    first-layer gap dx/2; a particle moved behind the floor is counted, and
 *    with stop_on_crossing the run stops naming it. */
#include <math.h>

#include "sim_util.h"

static const char *tank_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.01}\n"
    "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
    "geometry:\n"
    "  fluid: [{shape: box, min: [0, 0], max: [1.0, 0.5]}]\n"
    "  walls: [{shape: tank, min: [0, 0], max: [1.0, 1.0]}]\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 22.1}\n"
    "  continuity: {}\n"
    "  pressure_gradient: {}\n"
    "  gravity: {acceleration: [0, -9.81]}\n"
    "  dbc: {}\n"
    "  time_step: {}\n"
    "  symplectic: {}\n"
    "%s";

/* Reads the first data row of a CSV into values; returns the count. */
static int first_row(const char *path, double *values, int max)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char line[16384];
    int n = 0;
    if (fgets(line, sizeof line, f) && fgets(line, sizeof line, f)) {
        char *p = line;
        while (*p && n < max) {
            char *end;
            double value = strtod(p, &end);
            if (end == p)
                break;
            values[n++] = value;
            p = *end == ',' ? end + 1 : end;
        }
    }
    fclose(f);
    return n;
}

START_TEST(point_gauge_hydrostatic_start)
{
    const double pts[][2] = {{0.5, 0.1}, {0.3, 0.25}, {0.7, 0.4}, {0.5, 0.8}};
    char gauge[512], yaml[4096];
    snprintf(gauge, sizeof gauge,
             "  point_gauge: {points: [[%g, %g], [%g, %g], [%g, %g], [%g, %g]], fields: "
             "\"pressure, velocity\"}\n",
             pts[0][0], pts[0][1], pts[1][0], pts[1][1], pts[2][0], pts[2][1], pts[3][0],
             pts[3][1]);
    snprintf(yaml, sizeof yaml, tank_scene, gauge);
    sluice_sim *sim = test_load("point-gauge", yaml, NULL, 0);
    /* a uniform velocity, which the interpolation must return exactly */
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *u = test_column(sim, "velocity", 0), *w = test_column(sim, "velocity", 1);
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            u[i] = 0.75;
            w[i] = -0.5;
        }
    char *dir = test_scratch("point-gauge-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/points.csv", dir), 0);
    double row[64];
    ck_assert_int_eq(first_row(path, row, 64), 13);
    ck_assert(row[0] == 0);
    const double rho0 = 1000, g = 9.81, H = 0.5;
    for (int k = 0; k < 3; k++) {
        double expected = rho0 * g * (H - pts[k][1]);
        double p = row[1 + 3 * k];
        /* Shepard interpolation of a linear field is exact for symmetric
         * weights; V_j varies by rho0 g 2h / c0^2 / rho0 = 1.2e-3 relative
         * across the support, which biases the estimate by at most that
         * fraction of the pressure change over the support, 2 h rho0 g */
        double bound = 1.2e-3 * 2 * 0.03 * rho0 * g + 1e-9 * expected;
        ck_assert_msg(fabs(p - expected) <= bound, "point %d: p = %.6f, expected %.6f (bound %g)",
                      k, p, expected, bound);
        ck_assert_msg(fabs(row[2 + 3 * k] - 0.75) <= 1e-12 && fabs(row[3 + 3 * k] + 0.5) <= 1e-12,
                      "point %d: velocity (%g, %g)", k, row[2 + 3 * k], row[3 + 3 * k]);
        fprintf(stderr, "point gauge at (%g, %g): p = %.4f Pa, rho g (H - y) = %.4f Pa\n",
                pts[k][0], pts[k][1], p, expected);
    }
    /* above the free surface: outside the fluid */
    ck_assert(isnan(row[10]) && isnan(row[11]) && isnan(row[12]));
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* Runs the tank (water up to 0.5 m) with the fixture
 * tests/sdk/fixtures/do_phase_fixture.c marking the fluid at or above y = 0.25 as
 * air, and the plugin lines `gauges`; with `velocities` the water carries
 * u = 1 and the air u = 2. Returns the output directory (free it). */
static char *run_tank_under_air(const char *gauges, int velocities)
{
    const char *fixtures = getenv("SLUICE_FIXTURE_DIR");
    ck_assert_ptr_nonnull(fixtures);
    char plugins[1024], body[4096], yaml[8192];
    snprintf(plugins, sizeof plugins, "  do_phase_fixture: {air_above: 0.25}\n%s", gauges);
    snprintf(body, sizeof body, tank_scene, plugins);
    snprintf(yaml, sizeof yaml, "plugin_path: %s\n%s", fixtures, body);
    sluice_sim *sim = test_load("tank-under-air", yaml, NULL, 0);
    if (velocities) {
        const sluice_view *v = sluice_sim_view(sim);
        sluice_real *u = test_column(sim, "velocity", 0);
        for (sluice_index i = 0; i < v->count; i++)
            if (v->kind[i] == SLUICE_KIND_FLUID)
                u[i] = v->position[1][i] >= 0.25 ? 2 : 1;
    }
    char *dir = test_scratch("tank-under-air-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return dir;
}

/* The first data row of dir/file, which must hold `count` values. */
static void first_row_of(const char *dir, const char *file, double *values, int count)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", dir, file), 0);
    ck_assert_int_eq(first_row(path, values, count), count);
    free(path);
}

/* A point gauge of the velocity with `phase_line` at (0.5, 0.25) (on the
 * interface) and (0.5, 0.35) (0.1 m inside the air, beyond the support
 * 0.06 m), min_kernel_sum 0.1 (a point on the interface has about half a
 * kernel sum in each phase); row: time, u and v at each point. */
static void phase_gauge_row(const char *phase_line, double row[5])
{
    char gauges[512];
    snprintf(gauges, sizeof gauges,
             "  point_gauge: {points: [[0.5, 0.25], [0.5, 0.35]], fields: velocity, "
             "min_kernel_sum: 0.1%s}\n",
             phase_line);
    char *dir = run_tank_under_air(gauges, 1);
    first_row_of(dir, "points.csv", row, 5);
    free(dir);
}

/* phase: water / air sums over that phase only: on the interface the water
 * gauge reads 1 and the air gauge 2 exactly (Shepard interpolation of a
 * constant), the unfiltered one something in between; inside the air there
 * is no water, so the water gauge writes nan there. */
START_TEST(point_gauge_phase_filter)
{
    double water[5], air[5], all[5];
    phase_gauge_row(", phase: water", water);
    phase_gauge_row(", phase: air", air);
    phase_gauge_row("", all);
    fprintf(stderr, "point gauge on the interface: u = %g (water), %g (air), %g (both)\n",
            water[1], air[1], all[1]);
    ck_assert_msg(fabs(water[1] - 1) <= 1e-12, "water gauge u = %.15g", water[1]);
    ck_assert_msg(fabs(air[1] - 2) <= 1e-12, "air gauge u = %.15g", air[1]);
    ck_assert_msg(all[1] > 1.1 && all[1] < 1.9, "unfiltered gauge u = %g", all[1]);
    ck_assert_msg(isnan(water[3]), "water gauge inside the air: %g", water[3]);
    ck_assert_msg(fabs(air[3] - 2) <= 1e-12 && fabs(all[3] - 2) <= 1e-12,
                  "inside the air: %g (air gauge), %g (unfiltered)", air[3], all[3]);
}
END_TEST

/* The surface gauges with a phase filter: in the tank (water up to 0.5 m) the
 * fixture marks the fluid at or above y = 0.25 as air, so the water's own
 * surface is the top of its last row, 0.24 m. free_surface_gauge and
 * section_gauge with `phase: water` must find it (within dx/2, the bound of
 * the single-phase gauge tests), and without the filter the top of the air,
 * 0.5 m. */
static void surface_rows(const char *phase_line, double *fs, double *sec)
{
    char gauges[512];
    snprintf(gauges, sizeof gauges,
             "  free_surface_gauge: {positions: [0.5], top: [0.8]%s}\n"
             "  section_gauge: {positions: [0.5], top: [0.8]%s}\n",
             phase_line, phase_line);
    char *dir = run_tank_under_air(gauges, 0);
    first_row_of(dir, "free_surface.csv", fs, 2);
    first_row_of(dir, "sections.csv", sec, 5);
    free(dir);
}

START_TEST(surface_gauges_phase_filter)
{
    const double dx = 0.02;
    double fs_water[2], sec_water[5], fs_all[2], sec_all[5];
    surface_rows(", phase: water", fs_water, sec_water);
    surface_rows("", fs_all, sec_all);
    fprintf(stderr, "water under air from y = 0.25 m: free surface %.4f m (water), %.4f m (all); "
                    "section depth %.4f m (water), %.4f m (all)\n",
            fs_water[1], fs_all[1], sec_water[1], sec_all[1]);
    ck_assert_msg(fabs(fs_water[1] - 0.24) <= dx / 2, "water surface %g", fs_water[1]);
    ck_assert_msg(fabs(sec_water[1] - 0.24) <= dx / 2, "water depth %g", sec_water[1]);
    ck_assert_msg(fabs(fs_all[1] - 0.5) <= dx / 2, "unfiltered surface %g", fs_all[1]);
    ck_assert_msg(fabs(sec_all[1] - 0.5) <= dx / 2, "unfiltered depth %g", sec_all[1]);
}
END_TEST

/* ------------------------------------------------------- air fraction -- */

/* A still two-layer tank (as tests/plugins/two_phase/test_two_phase.c's column): water up to
 * H = 0.15 m under 0.1 m of air, dbc walls and a lid at 0.25 m, dx = 0.01 m,
 * h = 1.225 dx, the two_phase plugin with c0_w = 20 m/s and p_b = 100 Pa,
 * hydrostatic start. Rows lie at (k + 1/2) dx: the interface y = 0.15 m is
 * dx/2 from the top water row and the bottom air row, so the lattice is
 * mirror-symmetric about it. */
static const char two_layer_scene[] =
    "dimensions: 2\n"
    "particles: {spacing: 0.01, smoothing_length_ratio: 1.225, rest_density: 1000}\n"
    "time: {end: 0.001}\n"
    "domain: {min: [-0.1, -0.1], max: [0.3, 0.4]}\n"
    "geometry:\n"
    "  fluid:\n"
    "    - {shape: box, min: [0, 0], max: [0.2, 0.15]}\n"
    "    - {shape: box, min: [0, 0.15], max: [0.2, 0.25]}\n"
    "  walls:\n"
    "    - {shape: tank, min: [0, 0], max: [0.2, 0.3], name: tank}\n"
    "    - {shape: polyline, points: [[0.2, 0.25], [0, 0.25]], name: lid}\n"
    "initial: {density: hydrostatic}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  two_phase: {speed_of_sound: 20, background_pressure: 100, air_above: [[0, 0.15]]}\n"
    "  continuity: {form: volume}\n"
    "  pressure_gradient: {form: density_product}\n"
    "  gravity: {}\n"
    "  dbc: {}\n"
    "  time_step: {}\n"
    "  symplectic: {}\n"
    "  point_gauge: {points: [%s], fields: \"%s\", min_kernel_sum: 0.1%s}\n";

/* Heights of the gauge points at x = 0.1 m (between two particle columns):
 * 0.12 (deep water: 0.035 m from the bottom air row, more than the support
 * 2h = 0.0245 m), 0.145 / 0.15 / 0.155 and 0.14 / 0.16 (the interface band,
 * mirrored about 0.15), 0.18 (deep air, 0.035 m from the top water row),
 * 0.28 (above the lid, 0.035 m from the top air row: outside the fluid). */
#define AIR_POINTS 8
static const double air_y[AIR_POINTS] = {0.12, 0.14, 0.145, 0.15, 0.155, 0.16, 0.18, 0.28};

/* Runs the tank to its first gauge row (t = 0) with `fields` and the
 * `phase_line`, the water moving at u = 1 and the air at u = 2; returns the
 * output directory (free it). */
static char *run_two_layer(const char *fields, const char *phase_line)
{
    char points[512] = "", yaml[4096];
    for (int k = 0; k < AIR_POINTS; k++) {
        size_t used = strlen(points);
        snprintf(points + used, sizeof points - used, "%s[0.1, %g]", k ? ", " : "", air_y[k]);
    }
    snprintf(yaml, sizeof yaml, two_layer_scene, points, fields, phase_line);
    sluice_sim *sim = test_load("air-fraction", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *u = test_column(sim, "velocity", 0);
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            u[i] = v->position[1][i] >= 0.15 ? 2 : 1;
    char *dir = test_scratch("air-fraction-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return dir;
}

/* air_fraction = sum_air V_j W / sum_all V_j W. With equal particle volumes
 * V_j the lattice's mirror symmetry about the interface gives C = 1/2 on it
 * and C(0.15 + d) + C(0.15 - d) = 1 exactly (each air particle's weight
 * equals that of its mirrored water particle). The hydrostatic start makes
 * the volumes unequal: a water particle at depth z below the top (0.15 m) has
 * rho = rho0 (1 + rho0 g z / B)^(1/7), so V = V0 (1 - beta) with
 * beta <= rho0 g z / (7 B); an air particle z above it has rho = rho0_a
 * (1 - rho0_a g z / B)^(1/1.4), V = V0 (1 + alpha), alpha = (1 - rho0_a g z
 * / B)^(-1/1.4) - 1, B = c0_w^2 rho0 / 7. Writing C = A/(A + W) with the
 * equal-volume sums A0, W0 and the weighted means abar <= alpha, bbar <=
 * beta: C - C0 = C0 (1 - C0) (abar + bbar) / (1 + C0 abar - (1 - C0) bbar)
 * <= (alpha + beta) / (4 (1 - beta)), z up to 2h + 0.01 m (the farthest
 * particle within the support of the points 0.01 m from the interface). So
 * |C - 1/2| <= that bound on the interface, and |C(d) + C(-d) - 1| <= twice
 * it. Deep in the water no air particle is within the support: C = 0
 * exactly; deep in the air the two sums add the same terms: C = 1 to the
 * last bit. Above the lid the kernel sum is 0 < min_kernel_sum: nan. */
static double air_fraction_bound(void)
{
    const double g = 9.81, rho_w = 1000, rho_a = 1.09, B = 20.0 * 20.0 * rho_w / 7.0;
    const double z = 2 * 1.225 * 0.01 + 0.01;
    const double beta = rho_w * g * z / (7 * B);
    const double alpha = pow(1 - rho_a * g * z / B, -1 / 1.4) - 1;
    return (alpha + beta) / (4 * (1 - beta));
}

static void check_air_fraction(const double *c, const char *label)
{
    const double bound = air_fraction_bound();
    fprintf(stderr, "air_fraction (%s) at y =", label);
    for (int k = 0; k < AIR_POINTS; k++)
        fprintf(stderr, " %g: %.9g%s", air_y[k], c[k], k + 1 < AIR_POINTS ? "," : "\n");
    fprintf(stderr, "  |C(0.15) - 1/2| = %.3g, |C(0.145) + C(0.155) - 1| = %.3g, "
                    "|C(0.14) + C(0.16) - 1| = %.3g (bound %.3g and twice it)\n",
            fabs(c[3] - 0.5), fabs(c[2] + c[4] - 1), fabs(c[1] + c[5] - 1), bound);
    ck_assert_msg(c[0] == 0, "deep in the water C = %.17g", c[0]);
    ck_assert_msg(fabs(c[6] - 1) <= 1e-15, "deep in the air C = %.17g", c[6]);
    ck_assert_msg(isnan(c[7]), "above the lid C = %g", c[7]);
    ck_assert_msg(fabs(c[3] - 0.5) <= bound, "on the interface C = %.17g (bound %g)", c[3],
                  bound);
    ck_assert_msg(fabs(c[2] + c[4] - 1) <= 2 * bound && fabs(c[1] + c[5] - 1) <= 2 * bound,
                  "mirror sums %.17g %.17g", c[2] + c[4], c[1] + c[5]);
    /* across the band the fraction rises with y (the kernel weights of the
     * air grow as the point rises) */
    for (int k = 1; k < 7; k++)
        ck_assert_msg(c[k] > c[k - 1], "C(%g) = %g <= C(%g) = %g", air_y[k], c[k],
                      air_y[k - 1], c[k - 1]);
}

START_TEST(point_gauge_air_fraction)
{
    /* every fluid particle: air_fraction alone */
    char *dir = run_two_layer("air_fraction", "");
    double row[1 + AIR_POINTS], all[AIR_POINTS];
    first_row_of(dir, "points.csv", row, 1 + AIR_POINTS);
    char *path = NULL, *text = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/points.csv", dir), 0);
    text = test_read_file(path);
    ck_assert_ptr_nonnull(text);
    ck_assert_msg(strncmp(text, "time,p0_air_fraction,p1_air_fraction,", 37) == 0, "header %.80s",
                  text);
    free(text);
    free(path);
    free(dir);
    for (int k = 0; k < AIR_POINTS; k++)
        all[k] = row[1 + k];
    check_air_fraction(all, "phase: all");

    /* phase: water with the velocity: the velocity is the water's (1 on the
     * interface exactly, nan where no water is within the support), the air
     * fraction still sums over both phases: the same numbers bit for bit */
    dir = run_two_layer("velocity, air_fraction", ", phase: water");
    double wrow[1 + 3 * AIR_POINTS], water[AIR_POINTS];
    first_row_of(dir, "points.csv", wrow, 1 + 3 * AIR_POINTS);
    ck_assert_int_ge(asprintf(&path, "%s/points.csv", dir), 0);
    text = test_read_file(path);
    ck_assert_ptr_nonnull(text);
    ck_assert_msg(strncmp(text, "time,p0_velocity_x,p0_velocity_y,p0_air_fraction,p1_velocity_x,",
                          63) == 0,
                  "header %.80s", text);
    free(text);
    free(path);
    free(dir);
    for (int k = 0; k < AIR_POINTS; k++)
        water[k] = wrow[3 + 3 * k];
    check_air_fraction(water, "phase: water");
    for (int k = 0; k < AIR_POINTS; k++)
        ck_assert_msg((isnan(water[k]) && isnan(all[k])) || water[k] == all[k],
                      "point %d: %.17g under phase: water, %.17g without", k, water[k], all[k]);
    fprintf(stderr, "phase: water: u = %g at y = 0.15 (C = %.6f), u = %g at y = 0.18 (C = %g)\n",
            wrow[1 + 3 * 3], water[3], wrow[1 + 3 * 6], water[6]);
    ck_assert_msg(fabs(wrow[1 + 3 * 3] - 1) <= 1e-12, "water u on the interface %.17g",
                  wrow[1 + 3 * 3]);
    ck_assert_msg(isnan(wrow[1 + 3 * 6]) && isnan(wrow[2 + 3 * 6]), "water u in the air %g",
                  wrow[1 + 3 * 6]);
}
END_TEST

/* air_fraction without the two_phase plugin: refused at the gauge's line,
 * naming the parameter and the plugin. */
START_TEST(point_gauge_air_fraction_needs_two_phase)
{
    char yaml[4096];
    snprintf(yaml, sizeof yaml, tank_scene,
             "  point_gauge: {points: [[0.5, 0.1]], fields: \"velocity, air_fraction\"}\n");
    test_load_refused("air-fraction-single-phase", yaml,
                      "fields: 'air_fraction' needs the field 'phase' (0 water, 1 air) of the "
                      "two_phase plugin");
    char *dir = test_scratch("air-fraction-check");
    char *path = test_write_file(dir, "scene.yaml", yaml);
    char *args = NULL, *out = NULL;
    ck_assert_int_ge(asprintf(&args, "check %s", path), 0);
    int status = test_sluice(args, &out);
    ck_assert_msg(status == 2 && strstr(out, "air_fraction") && strstr(out, "scene.yaml:17:"),
                  "exit %d:\n%s", status, out);
    free(args);
    free(out);
    free(path);
    free(dir);
}
END_TEST

START_TEST(point_gauge_unknown_field)
{
    char yaml[4096];
    snprintf(yaml, sizeof yaml, tank_scene,
             "  point_gauge: {points: [[0.5, 0.1]], fields: \"pressure, vorticity\"}\n");
    char *dir = test_scratch("point-gauge-bad");
    char *path = test_write_file(dir, "scene.yaml", yaml);
    char *args = NULL, *out = NULL;
    ck_assert_int_ge(asprintf(&args, "check %s", path), 0);
    int status = test_sluice(args, &out);
    ck_assert_msg(status == 2 && strstr(out, "field 'vorticity' is not declared") &&
                      strstr(out, "scene.yaml:17:"),
                  "exit %d:\n%s", status, out);
    free(args);
    free(out);
    free(path);
    free(dir);
}
END_TEST

static int read_monitor(const char *dir, double rows[][6], int max)
{
    char *path = NULL;
    if (asprintf(&path, "%s/walls.csv", dir) < 0)
        return -1;
    FILE *f = fopen(path, "r");
    free(path);
    if (!f)
        return -1;
    char line[1024];
    int n = 0;
    if (!fgets(line, sizeof line, f)) {
        fclose(f);
        return 0;
    }
    while (n < max && fgets(line, sizeof line, f))
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf", &rows[n][0], &rows[n][1], &rows[n][2],
                   &rows[n][3], &rows[n][4], &rows[n][5]) == 6)
            n++;
    fclose(f);
    return n;
}

START_TEST(wall_monitor_lattice_and_crossing)
{
    char yaml[4096];
    snprintf(yaml, sizeof yaml, tank_scene, "  wall_monitor: {interval: 0.001}\n");
    sluice_sim *sim = test_load("wall-monitor", yaml, NULL, 0);
    char *dir = test_scratch("wall-monitor-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    /* push one fluid particle 1 mm behind the floor */
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *y = (sluice_real *)v->position[1];
    sluice_index moved = v->count;
    for (sluice_index i = 0; i < v->count && moved == v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && fabs(v->position[0][i] - 0.51) < 1e-9 &&
            fabs(v->position[1][i] - 0.01) < 1e-9)
            moved = i;
    ck_assert_uint_lt(moved, v->count);
    y[moved] = -0.001;
    while (sluice_sim_time(sim) < 0.001 - 1e-12)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    double rows[16][6];
    int n = read_monitor(dir, rows, 16);
    ck_assert_int_ge(n, 2);
    /* t = 0: the lattice, dx/2 from every wall */
    ck_assert(rows[0][1] == 0 && rows[0][2] == 0);
    ck_assert_msg(fabs(rows[0][3] - 0.01) < 1e-12 && fabs(rows[0][4] - 0.01) < 1e-12,
                  "gaps %g %g", rows[0][3], rows[0][4]);
    /* the moved particle is behind the floor at the next sample */
    ck_assert_msg(rows[1][1] == 1 && rows[1][2] == 1 && rows[1][3] < 0, "crossed %g, total %g, gap %g",
                  rows[1][1], rows[1][2], rows[1][3]);
    free(dir);
    sluice_sim_free(sim);

    /* with stop_on_crossing the run stops and names the particle */
    snprintf(yaml, sizeof yaml, tank_scene,
             "  wall_monitor: {interval: 0.001, stop_on_crossing: true}\n");
    sim = test_load("wall-monitor-stop", yaml, NULL, 0);
    dir = test_scratch("wall-monitor-stop-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    v = sluice_sim_view(sim);
    y = (sluice_real *)v->position[1];
    sluice_id id = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && fabs(v->position[1][i] - 0.01) < 1e-9) {
            y[i] = -0.001;
            id = v->id[i];
            break;
        }
    int status = SLUICE_RUN_COMPLETE;
    while (status == SLUICE_RUN_COMPLETE && sluice_sim_time(sim) < 0.01)
        status = sluice_sim_step(sim);
    ck_assert_int_ne(status, SLUICE_RUN_COMPLETE);
    char expected[64];
    snprintf(expected, sizeof expected, "fluid particle id %llu", (unsigned long long)id);
    ck_assert_msg(strstr(sluice_sim_failure(sim), expected) &&
                      strstr(sluice_sim_failure(sim), "behind wall"),
                  "failure: %s", sluice_sim_failure(sim));
    sluice_sim_end(sim, SLUICE_RUN_FAILED);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("gauges");
    TCase *c = tcase_create("gauges");
    tcase_add_test(c, point_gauge_hydrostatic_start);
    tcase_add_test(c, point_gauge_phase_filter);
    tcase_add_test(c, surface_gauges_phase_filter);
    tcase_add_test(c, point_gauge_unknown_field);
    tcase_add_test(c, point_gauge_air_fraction);
    tcase_add_test(c, point_gauge_air_fraction_needs_two_phase);
    tcase_add_test(c, wall_monitor_lattice_and_crossing);
    suite_add_tcase(s, c);
    return test_run_suite(s);
}
