/* energy_gauge: the energy budget on states whose answer is known.
 *  - free fall of one particle (no other force, no walls): the symplectic
 *    (position-Verlet) step is exact for a constant acceleration
 *    (x^{n+1} = x^n + dt v^n + dt^2 g / 2, v^{n+1} = v^n + dt g), so
 *    K + P is conserved to round-off; the semi-implicit Euler step
 *    (v^{n+1} = v^n + dt g, x^{n+1} = x^n + dt v^{n+1}) changes it by exactly
 *    -m |g|^2 dt^2 / 2 per step, which the gauge must report;
 *  - the elastic energy of the hydrostatic start against the closed forms of
 *    e(rho) = int p/rho^2 drho for Tait and the linear equation of state,
 *    summed over the same densities: round-off;
 *  - a still-water tank on dbc walls for 0.5 s: bounded drift (bound below);
 *  - checkpoint and restart: the continued run's energy.csv rows are the
 *    uninterrupted run's (E_0, P_0 and S restored). */
#include <math.h>

#include "sim_util.h"

/* Tables are written with 10 significant digits ("%.10g"): a value read
 * back is within 5e-10 of the computed one, relatively. */
#define CSV 1e-9

/* Reads energy.csv (7 columns) into rows; returns the row count. */
static int read_energy(const char *dir, double (*rows)[7], int max)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/energy.csv", dir);
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char line[1024];
    int n = 0;
    if (!fgets(line, sizeof line, f)) {
        fclose(f);
        return 0;
    }
    ck_assert_str_eq(line, "time,kinetic,potential,elastic,total,drift,fluid_mass\n");
    while (n < max && fgets(line, sizeof line, f)) {
        double *r = rows[n];
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf", &r[0], &r[1], &r[2], &r[3], &r[4], &r[5],
                   &r[6]) == 7)
            n++;
    }
    fclose(f);
    return n;
}

static const char *fall_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.1, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.5, max_step: 0.001}\n"
    "domain: {min: [-1, -3], max: [1, 1]}\n"
    "geometry:\n"
    "  fluid: [{shape: box, min: [0, 0], max: [0.1, 0.1]}]\n"
    "initial: {density: rest}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  gravity: {acceleration: [0.3, -9.81]}\n"
    "  time_step: {acoustic: false}\n"
    "  %s: {}\n"
    "  energy_gauge: {interval: 0.1}\n";

/* Runs the free fall with `integrator`; returns the rows and sum of dt^2. */
static int run_fall(const char *integrator, double (*rows)[7], int max, double *dt2, double *mass,
                    long *steps)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml, fall_scene, integrator);
    sluice_sim *sim = test_load("energy-fall", yaml, NULL, 0);
    char *dir = test_scratch("energy-fall-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const sluice_view *v = sluice_sim_view(sim);
    ck_assert_uint_eq(v->count, 1);
    *mass = test_column(sim, "mass", 0)[0];
    *dt2 = 0;
    *steps = 0;
    while (sluice_sim_time(sim) < 0.5 - 1e-12) {
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        double dt = sluice_sim_view(sim)->dt;
        *dt2 += dt * dt;
        ++*steps;
    }
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    int n = read_energy(dir, rows, max);
    free(dir);
    sluice_sim_free(sim);
    return n;
}

START_TEST(free_fall_energy)
{
    const double g2 = 0.3 * 0.3 + 9.81 * 9.81, eps = 2.220446049250313e-16;
    double rows[16][7], dt2, m;
    long steps;
    /* symplectic: exact trajectory, so K + P = 0 up to round-off. Each step
     * rounds x and v (a few ulp each); the error grows at most linearly, so
     * |K + P| <= 4 N eps (K + |P|) (N steps). */
    int n = run_fall("symplectic", rows, 16, &dt2, &m, &steps);
    ck_assert_int_eq(n, 6);
    for (int k = 0; k < n; k++) {
        const double t = rows[k][0];
        /* K = m |g|^2 t^2 / 2 (analytic, from rest) */
        const double K = 0.5 * m * g2 * t * t;
        const double bound = 4 * (double)steps * eps * (rows[k][1] + fabs(rows[k][2]));
        fprintf(stderr, "free fall symplectic t = %.2f s: K = %.12g (analytic %.12g), "
                        "K + P = %.3g J/m (bound %.3g), elastic %g\n",
                t, rows[k][1], K, rows[k][4], bound, rows[k][3]);
        ck_assert(fabs(rows[k][0] - 0.1 * k) < 1e-12);
        ck_assert_msg(fabs(rows[k][1] - K) <= bound + CSV * K, "K = %.17g, analytic %.17g",
                      rows[k][1], K);
        ck_assert_msg(fabs(rows[k][4]) <= bound, "K + P = %g, bound %g", rows[k][4], bound);
        ck_assert(rows[k][3] == 0);      /* no density field: no elastic energy */
        ck_assert(isnan(rows[k][5]));    /* one particle: no height range to normalise by */
        ck_assert(fabs(rows[k][6] - m) <= CSV * m);
    }
    /* semi-implicit Euler: dE = -m |g|^2 dt^2 / 2 per step, exactly */
    n = run_fall("euler", rows, 16, &dt2, &m, &steps);
    ck_assert_int_eq(n, 6);
    const double expected = -0.5 * m * g2 * dt2;
    const double bound = 4 * (double)steps * eps * (rows[5][1] + fabs(rows[5][2]));
    fprintf(stderr, "free fall euler: %ld steps, E - E0 = %.12g J/m, -m|g|^2 sum dt^2/2 = %.12g "
                    "(bound %.3g)\n", steps, rows[5][4], expected, bound);
    ck_assert_msg(fabs(rows[5][4] - expected) <= bound + CSV * fabs(expected),
                  "E - E0 = %.17g, expected %.17g",
                  rows[5][4], expected);
}
END_TEST

static const char *column_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.5}\n"
    "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
    "geometry:\n"
    "  fluid: [{shape: box, min: [0, 0], max: [1.0, 0.5]}]\n"
    "  walls: [{shape: tank, min: [0, 0], max: [1.0, 1.0]}]\n"
    "initial: {density: hydrostatic}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "%s"
    "  continuity: {}\n"
    "  delta_sph: {delta: 0.1, form: fourtakas}\n"
    "  pressure_gradient: {}\n"
    "  artificial_viscosity: {alpha: 0.1}\n"
    "  gravity: {acceleration: [0, -9.81]}\n"
    "  dbc: {}\n"
    "  time_step: {}\n"
    "  symplectic: {}\n"
    "  energy_gauge: {interval: %s}\n";

/* The elastic energy of the hydrostatic start, closed form, summed over the
 * fluid's densities: Tait p = B (x^g - 1) + pb (x = rho/rho0) gives
 * e = [B (x^(g-1) - 1)/(g - 1) + (B - pb)(1/x - 1)] / rho0; the linear form
 * p = p0 + c^2 (rho - rho0) gives e = c^2 (ln x + 1/x - 1) + p0 (1/rho0 - 1/rho). */
static double closed_form(sluice_sim *sim, int tait, double c, double gamma, double p_ref)
{
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *m = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    const double rho0 = 1000, B = c * c * rho0 / gamma;
    double sum = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const double x = rho[i] / rho0;
        const double e = tait ? (B * (pow(x, gamma - 1) - 1) / (gamma - 1) +
                                 (B - p_ref) * (1 / x - 1)) / rho0
                              : c * c * (log(x) + 1 / x - 1) + p_ref * (1 / rho0 - 1 / rho[i]);
        sum += m[i] * e;
    }
    return sum;
}

START_TEST(elastic_energy_closed_forms)
{
    struct {
        const char *eos;
        int tait;
        double c, gamma, p_ref;
    } cases[] = {
        {"  tait: {speed_of_sound: 22.1}\n", 1, 22.1, 7, 0},
        {"  tait: {speed_of_sound: 15, gamma: 3, background_pressure: 2000}\n", 1, 15, 3, 2000},
        {"  linear_eos: {speed_of_sound: 22.1}\n", 0, 22.1, 1, 0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char yaml[4096];
        snprintf(yaml, sizeof yaml, column_scene, cases[k].eos, "0.01");
        sluice_sim *sim = test_load("energy-elastic", yaml, NULL, 0);
        char *dir = test_scratch("energy-elastic-out");
        ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
        const double expected = closed_form(sim, cases[k].tait, cases[k].c, cases[k].gamma,
                                            cases[k].p_ref);
        /* ... and once more after a few steps (densities off the lattice's) */
        for (int step = 0; step < 20; step++)
            ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        const double later_time = sluice_sim_time(sim);
        const double later = closed_form(sim, cases[k].tait, cases[k].c, cases[k].gamma,
                                         cases[k].p_ref);
        ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
        double rows[8][7];
        int n = read_energy(dir, rows, 8);
        ck_assert_int_ge(n, 2);
        /* the continuum column: rho0 g^2 H^3 W / (6 c^2) (small compression) */
        const double continuum = 1000 * 9.81 * 9.81 * 0.125 / (6 * cases[k].c * cases[k].c);
        fprintf(stderr, "%s elastic energy at t = 0: gauge %.15g, closed form %.15g J/m "
                        "(continuum %.4g); at t = %.4g s: gauge %.15g, closed form %.15g\n",
                cases[k].eos + 2, rows[0][3], expected, continuum, rows[n - 1][0],
                rows[n - 1][3], later);
        /* the quadrature and the secant iteration are good to ~1e-12
         * relative (the secant stops at |R(p) - rho| <= 1e-14 rho0, dp/p ~
         * 1e-14 c^2 rho0 / p ~ 1e-12; Gauss-Legendre's error is far below):
         * the table's 10 digits (CSV) are the limit of the assertion */
        ck_assert_msg(fabs(rows[0][3] - expected) <= CSV * expected, "%.17g vs %.17g",
                      rows[0][3], expected);
        /* a sample at the end of the 20 steps (finish() adds it) */
        ck_assert(fabs(rows[n - 1][0] - later_time) <= CSV * later_time);
        ck_assert_msg(fabs(rows[n - 1][3] - later) <= CSV * later, "%.17g vs %.17g",
                      rows[n - 1][3], later);
        free(dir);
        sluice_sim_free(sim);
    }
}
END_TEST

/* Still water on dbc walls over 0.5 s. The hydrostatic start is the
 * continuum's equilibrium, not exactly the discrete one: the column settles
 * with an acoustic oscillation (period ~ 4 H / c = 0.09 s) that exchanges
 * potential and elastic energy, and the dissipative terms and the wall
 * particles (whose own compression the gauge does not count) take some
 * energy out. The energy that mismatch can set free is of the order of the
 * compression energy the start holds, U_0 = rho0 g^2 H^3 W / (6 c^2) (~4 J/m
 * here): bound |E - E_0| <= U_0 at every sample, i.e. |drift| <= U_0 / S =
 * g H^2 / (3 c^2 (H - dx)) = 3.5e-3. The kinetic energy of the settling
 * comes from it too: K <= U_0. A growing instability (or a wrong potential
 * or elastic term: the swings of P, ~3.7 J/m, are twice those of E) breaks
 * the bound. */
START_TEST(still_water_bounded_drift)
{
    char yaml[4096];
    snprintf(yaml, sizeof yaml, column_scene, "  tait: {speed_of_sound: 22.1}\n", "0.025");
    sluice_sim *sim = test_load("energy-still", yaml, NULL, 0);
    char *dir = test_scratch("energy-still-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < 0.5 - 1e-12)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    double rows[32][7];
    int n = read_energy(dir, rows, 32);
    ck_assert_int_eq(n, 21);
    const double U0 = rows[0][3], S = 500 * 9.81 * (0.5 - 0.02) / 2;
    double worst = 0, worst_drift = 0, kmax = 0;
    for (int k = 0; k < n; k++) {
        worst = fmax(worst, fabs(rows[k][4] - rows[0][4]));
        worst_drift = fmax(worst_drift, fabs(rows[k][5]));
        kmax = fmax(kmax, rows[k][1]);
        ck_assert(fabs(rows[k][6] - 500) <= CSV * 500); /* 1250 particles x 0.4 kg/m */
    }
    fprintf(stderr, "still water 0.5 s: U0 = %.4g J/m, max |E - E0| = %.4g J/m, max |drift| = "
                    "%.3g (bound %.3g), max K = %.3g J/m, final drift %.3g\n",
                    U0, worst, worst_drift, U0 / S, kmax, rows[n - 1][5]);
    ck_assert(U0 > 0);
    ck_assert_msg(worst <= U0, "|E - E0| = %g > U0 = %g", worst, U0);
    ck_assert_msg(worst_drift <= U0 / S * (1 + 1e-12), "drift %g", worst_drift);
    ck_assert_msg(kmax <= U0, "K = %g > U0 = %g", kmax, U0);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* The continued run's table holds the uninterrupted run's rows after the
 * checkpoint, byte for byte: the drift and the potential energy depend on
 * E_0, P_0 and S, which must come back from the checkpoint. */
START_TEST(restart_rows_identical)
{
    char yaml[4096];
    snprintf(yaml, sizeof yaml, column_scene, "  tait: {speed_of_sound: 22.1}\n", "0.01");
    char *dir = test_scratch("energy-restart");
    char *scene = test_write_file(dir, "scene.yaml", yaml);
    ck_assert_ptr_nonnull(scene);
    char args[8192], *output = NULL;
    const char *common = "--quiet --no-progress --threads 1 --set particles.spacing=0.04 "
                         "--set time.end=0.1";
    snprintf(args, sizeof args, "run %s --out %s/whole %s", scene, dir, common);
    ck_assert_int_eq(test_sluice(args, NULL), 0);
    snprintf(args, sizeof args, "run %s --out %s/first %s --set checkpoint.interval=0.05", scene,
             dir, common);
    ck_assert_int_eq(test_sluice(args, NULL), 0);
    char command[4096];
    snprintf(command, sizeof command, "ls %s/first/checkpoint_*.h5 | head -n 1", dir);
    ck_assert_int_eq(test_popen(command, &output), 0);
    ck_assert_ptr_nonnull(output);
    output[strcspn(output, "\n")] = 0;
    ck_assert_msg(strlen(output) > 0, "no checkpoint");
    snprintf(args, sizeof args, "run %s --out %s/continued %s --restart %s", scene, dir, common,
             output);
    ck_assert_int_eq(test_sluice(args, NULL), 0);
    free(output);
    char path[4096];
    snprintf(path, sizeof path, "%s/whole/energy.csv", dir);
    char *whole = test_read_file(path);
    snprintf(path, sizeof path, "%s/continued/energy.csv", dir);
    char *continued = test_read_file(path);
    ck_assert_ptr_nonnull(whole);
    ck_assert_ptr_nonnull(continued);
    /* the uninterrupted table from the first row after t = 0.05 s */
    const char *after = strstr(whole, "\n0.06");
    ck_assert_ptr_nonnull(after);
    const char *header_end = strchr(continued, '\n');
    ck_assert_ptr_nonnull(header_end);
    fprintf(stderr, "restart: continued table (%zu bytes after its header) vs the uninterrupted "
                    "table after t = 0.05 s (%zu bytes)\n",
            strlen(header_end), strlen(after));
    ck_assert_str_eq(header_end, after);
    /* and the rows after 0.05 s carry a non-trivial drift (E_0 used) */
    ck_assert_int_ge(test_count_lines(after, ","), 5);
    free(whole);
    free(continued);
    free(scene);
    free(dir);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("energy");
    TCase *t = tcase_create("energy");
    tcase_set_timeout(t, 300);
    tcase_add_test(t, free_fall_energy);
    tcase_add_test(t, elastic_energy_closed_forms);
    tcase_add_test(t, still_water_bounded_drift);
    tcase_add_test(t, restart_rows_identical);
    suite_add_tcase(s, t);
    return test_run_suite(s);
}
