/* Riemann-solver SPH (plugins/riemann/riemann.c: riemann_pressure,
 * riemann_continuity; Zhang, Hu & Adams 2017):
 *  - the pair sums agree with a brute-force evaluation of the published
 *    formulas on a random periodic box, for both limiters, 2D and 3D;
 *  - total linear momentum is conserved to round-off over 100 steps;
 *  - two blocks of water meeting at +-U (a periodic strip) build the
 *    acoustic pressure of linear theory, rho0 c0 U, between the two
 *    compression waves;
 *  - a tank at rest stays at rest on dbc walls, with the walls mirrored
 *    (the default) and as particles: the flow the discretisation stirs up
 *    stays small against (g H)^(1/2), and the pressure at the floor is
 *    rho0 g H within the weakly compressible offset;
 *  - refusals: with the term each one replaces, and with two phases. */
#include <math.h>

#include "sim_util.h"
/* Internal: calls the loaded kernel on its state (not in sim.h) */
#include "sim_internal.h"

#define G 9.81

static const char *const limiters[] = {"low_dissipation", "acoustic"};

static double kernel_gradient_factor(sluice_sim *sim, double r2)
{
    const sluice_instance *k = &sim->instances[sim->kernel];
    sluice_real rr = (sluice_real)r2, r = 0, w = 0, ff = 0;
    k->component->kernel(k->state, 1, &rr, &r, &w, &ff);
    return (double)ff;
}

/* A periodic box without walls or gravity: the Riemann terms alone, random
 * velocities and a random 2 % density field. */
static sluice_sim *periodic_box(int dims, const char *limiter, uint64_t seed)
{
    char yaml[2048];
    const char *lo = dims == 2 ? "[0, 0]" : "[0, 0, 0]";
    const char *hi = dims == 2 ? "[1, 1]" : "[0.6, 0.6, 0.6]";
    snprintf(yaml, sizeof yaml,
             "dimensions: %d\n"
             "particles: {spacing: %s}\n"
             "time: {end: 1.0}\n"
             "domain: {min: %s, max: %s, periodic: %s}\n"
             "geometry: {fluid: [{shape: box, min: %s, max: %s}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  riemann_continuity: {}\n"
             "  riemann_pressure: {limiter: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dims, dims == 2 ? "0.04" : "0.06", lo, hi, dims == 2 ? "xy" : "xyz", lo, hi,
             limiter);
    sluice_sim *sim = test_load("riemann-box", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < v->count; i++) {
        rho[i] = (sluice_real)(1000 * (1 + 0.02 * (test_uniform(&seed) - 0.5)));
        for (int d = 0; d < dims; d++)
            test_column(sim, "velocity", (uint32_t)d)[i] = (sluice_real)(test_uniform(&seed) - 0.3);
    }
    return sim;
}

/* The published pair terms for i, j (r = x_i - x_j, F = (dW/dr)/r):
 * acceleration -2 m_j P* / (rho_i rho_j) F r and density rate
 * rho_i (m_j / rho_j) F [(v_i - v_j) . r + |r| (p_i - p_j) / (rho_bar c_bar)]. */
static void pair_terms(int dims, int acoustic, const double r[3], double F, double mj,
                       double rhoi, double rhoj, double pi, double pj, double ci, double cj,
                       const double vi[3], const double vj[3], double acc[3], double *rate)
{
    double d2 = 0, dvr = 0;
    for (int a = 0; a < dims; a++) {
        d2 += r[a] * r[a];
        dvr += (vi[a] - vj[a]) * r[a];
    }
    const double d = sqrt(d2), du = -dvr / d; /* u_L - u_R along e = -r / |r| */
    const double rho_bar = 0.5 * (rhoi + rhoj), c_bar = 0.5 * (ci + cj);
    const double beta = acoustic ? c_bar : fmin(3 * fmax(du, 0), c_bar);
    const double pstar = 0.5 * (pi + pj) + 0.5 * rho_bar * beta * du;
    for (int a = 0; a < dims; a++)
        acc[a] -= 2 * mj * pstar / (rhoi * rhoj) * F * r[a];
    *rate += rhoi * mj / rhoj * F * (dvr + d * (pi - pj) / (rho_bar * c_bar));
}

static void check_against_formula(int dims, const char *limiter)
{
    sluice_sim *sim = periodic_box(dims, limiter, 11 + (uint64_t)dims);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_index n = v->count;
    const sluice_real *rho = test_column(sim, "density", 0), *m = test_column(sim, "mass", 0);
    const sluice_real *p = test_column(sim, "pressure", 0), *c = test_column(sim, "sound_speed", 0);
    const sluice_real *rate = test_column(sim, "density_rate", 0);
    const sluice_real *u[3], *a[3];
    for (int d = 0; d < dims; d++) {
        u[d] = test_column(sim, "velocity", (uint32_t)d);
        a[d] = test_column(sim, "acceleration", (uint32_t)d);
    }
    const double support = (double)sim->support, box = dims == 2 ? 1.0 : 0.6;
    const int acoustic = strcmp(limiter, "acoustic") == 0;
    double worst_a = 0, scale_a = 0, worst_r = 0, scale_r = 0;
    for (sluice_index i = 0; i < n; i++) {
        double acc[3] = {0, 0, 0}, drho = 0, vi[3] = {0, 0, 0};
        for (int d = 0; d < dims; d++)
            vi[d] = u[d][i];
        for (sluice_index j = 0; j < n; j++) {
            if (j == i)
                continue;
            double r[3] = {0, 0, 0}, r2 = 0, vj[3] = {0, 0, 0};
            for (int d = 0; d < dims; d++) {
                r[d] = (double)v->position[d][i] - (double)v->position[d][j];
                r[d] -= box * round(r[d] / box); /* minimum image */
                r2 += r[d] * r[d];
                vj[d] = u[d][j];
            }
            if (r2 >= support * support)
                continue;
            pair_terms(dims, acoustic, r, kernel_gradient_factor(sim, r2), m[j], rho[i], rho[j],
                       p[i], p[j], c[i], c[j], vi, vj, acc, &drho);
        }
        for (int d = 0; d < dims; d++) {
            worst_a = fmax(worst_a, fabs(acc[d] - a[d][i]));
            scale_a = fmax(scale_a, fabs(acc[d]));
        }
        worst_r = fmax(worst_r, fabs(drho - rate[i]));
        scale_r = fmax(scale_r, fabs(drho));
    }
    fprintf(stderr,
            "riemann %s %dD: batch sums vs brute-force formulas over %u particles: "
            "acceleration %.2e of %.3e m/s^2, density rate %.2e of %.3e kg/m^3/s\n",
            limiter, dims, (unsigned)n, worst_a / scale_a, scale_a, worst_r / scale_r, scale_r);
    /* the same sums in another order: round-off of a few dozen terms */
    ck_assert_msg(scale_a > 0 && worst_a <= 1e-12 * scale_a, "%s %dD: acceleration off by %g",
                  limiter, dims, worst_a);
    ck_assert_msg(scale_r > 0 && worst_r <= 1e-12 * scale_r, "%s %dD: density rate off by %g",
                  limiter, dims, worst_r);
    sluice_sim_free(sim);
}

START_TEST(formula_2d) { check_against_formula(2, limiters[_i]); }
END_TEST
START_TEST(formula_3d) { check_against_formula(3, limiters[_i]); }
END_TEST

/* P* is symmetric in i and j, so the pressure force is antisymmetric: the
 * total momentum of the box changes only by round-off. */
static void check_momentum(int dims)
{
    sluice_sim *sim = periodic_box(dims, "low_dissipation", 99 + (uint64_t)dims);
    const sluice_view *v = sluice_sim_view(sim);
    double p0[3] = {0, 0, 0}, scale = 0;
    const sluice_real *m = test_column(sim, "mass", 0);
    for (int d = 0; d < dims; d++)
        for (sluice_index i = 0; i < v->count; i++) {
            double u = test_column(sim, "velocity", (uint32_t)d)[i];
            p0[d] += m[i] * u;
            scale += m[i] * fabs(u);
        }
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    for (int s = 0; s < 100; s++)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    v = sluice_sim_view(sim);
    m = test_column(sim, "mass", 0);
    for (int d = 0; d < dims; d++) {
        double p = 0;
        for (sluice_index i = 0; i < v->count; i++)
            p += m[i] * test_column(sim, "velocity", (uint32_t)d)[i];
        fprintf(stderr, "riemann %dD periodic box, 100 steps: momentum[%d] change %.2e (sum m|v| "
                        "%.2e)\n",
                dims, d, p - p0[d], scale);
        ck_assert_msg(fabs(p - p0[d]) <= 1e-12 * scale, "%dD: momentum[%d] drifted by %g", dims, d,
                      p - p0[d]);
    }
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}

START_TEST(momentum_2d) { check_momentum(2); }
END_TEST
START_TEST(momentum_3d) { check_momentum(3); }
END_TEST

/* Steps the scene to its end time (no outputs). */
static void run_to_end(sluice_sim *sim)
{
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    const double end = sluice_sim_end_time(sim);
    while (sluice_sim_time(sim) < end - 1e-12)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
}

/* Two blocks of water meet: a periodic strip 2 m long, the left half moving
 * at +U, the right half at -U. Linear acoustics: the collision at x = 1 m
 * sends a compression wave each way at c0, and between them the water is at
 * rest at the pressure rho0 c0 U (the "water hammer"); the same happens,
 * as an expansion to -rho0 c0 U, at the periodic seam. U = 0.1 m/s, c0 = 20
 * m/s: Mach 0.005, so the nonlinear corrections of the Tait equation (of
 * relative order (gamma + 1) M / 4 = 1 %) stay inside the tolerance of 3 %,
 * which also bounds the spread of the wave fronts (a few h out of the 0.5 m
 * compressed zone read). */
static void check_collision(const char *limiter)
{
    const double U = 0.1, c0 = 20, rho0 = 1000, t_end = 0.025; /* fronts at 1 +- 0.5 m */
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.01}\n"
             "time: {end: %g}\n"
             "domain: {min: [0, 0], max: [2, 0.2], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [2, 0.2]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: %g}\n"
             "  riemann_continuity: {}\n"
             "  riemann_pressure: {limiter: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             t_end, c0, limiter);
    sluice_sim *sim = test_load("riemann-collision", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *ux = test_column(sim, "velocity", 0);
    for (sluice_index i = 0; i < v->count; i++)
        ux[i] = (sluice_real)(v->position[0][i] < 1 ? U : -U);
    run_to_end(sim);
    v = sluice_sim_view(sim);
    const sluice_real *p = test_column(sim, "pressure", 0);
    ux = test_column(sim, "velocity", 0);
    double sum = 0, usum = 0;
    int count = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (fabs(v->position[0][i] - 1) < 0.25) { /* the compressed zone, fronts excluded */
            sum += p[i];
            usum += fabs(ux[i]);
            count++;
        }
    const double mean = sum / count, expected = rho0 * c0 * U;
    fprintf(stderr,
            "riemann %s: two blocks at +-%.2f m/s, c0 = %g m/s: pressure between the fronts %.1f "
            "Pa against rho0 c0 U = %.1f Pa (%+.2f %%), mean |u| there %.2e m/s\n",
            limiter, U, c0, mean, expected, 100 * (mean / expected - 1), usum / count);
    ck_assert_msg(fabs(mean / expected - 1) < 0.03, "%s: %g Pa against %g", limiter, mean,
                  expected);
    /* the water behind the fronts is brought to rest */
    ck_assert_msg(usum / count < 0.03 * U, "%s: mean |u| %g behind the fronts", limiter,
                  usum / count);
    sluice_sim_free(sim);
}

START_TEST(collision) { check_collision(limiters[_i]); }
END_TEST

/* ---------------------------------------------------------- still tank -- */

/* A tank 0.5 m wide, water H = 0.25 m deep at dx = H/20 on dbc walls, c0 =
 * 10 (g H)^(1/2), for 2 s. */
static void check_still_tank(const char *walls)
{
    const double H = 0.25, c0 = 15.7, t_end = 2.0;
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.0125, smoothing_length_ratio: 1.5}\n"
             "time: {end: %g}\n"
             "domain: {min: [-0.1, -0.1], max: [0.6, 0.5]}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [0.5, %g]}]\n"
             "  walls: [{shape: tank, min: [0, 0], max: [0.5, 0.4]}]\n"
             "initial: {density: hydrostatic}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: %g}\n"
             "  riemann_continuity: {walls: %s}\n"
             "  riemann_pressure: {walls: %s}\n"
             "  gravity: {}\n"
             "  dbc: {}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             t_end, H, c0, walls, walls);
    sluice_sim *sim = test_load("riemann-tank", yaml, NULL, 0);
    run_to_end(sim);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *p = test_column(sim, "pressure", 0);
    const sluice_real *vel[2] = {test_column(sim, "velocity", 0), test_column(sim, "velocity", 1)};
    double vmax = 0, sum = 0, lowest = INFINITY;
    int count = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        double s2 = 0;
        for (int d = 0; d < 2; d++)
            s2 += (double)vel[d][i] * (double)vel[d][i];
        vmax = fmax(vmax, sqrt(s2));
        lowest = fmin(lowest, (double)v->position[1][i]);
        /* the bottom row: hydrostatic pressure at its depth */
        if (v->position[1][i] < 0.0125) {
            sum += p[i] / (1000 * G * (H - v->position[1][i]));
            count++;
        }
    }
    const double ratio = sum / count, scale = sqrt(G * H);
    fprintf(stderr,
            "riemann walls %s: still tank after %g s: largest speed %.3e m/s (%.2f %% of "
            "(g H)^(1/2)), bottom row's pressure / rho0 g (H - y) = %.4f, lowest particle y = "
            "%.4f m\n",
            walls, t_end, vmax, 100 * vmax / scale, ratio, lowest);
    ck_assert_msg(lowest > 0, "walls %s: a particle at y = %g, below the floor", walls, lowest);
    /* settling: the flow stirred up stays under 2 % of the long-wave speed */
    ck_assert_msg(vmax < 0.02 * scale, "walls %s: speed %g m/s", walls, vmax);
    /* the weakly compressible offset at c0 = 10 (g H)^(1/2) is a few per cent
     * (docs/loads.md: 7 g H / c0^2 = 7 %% bounds it) */
    ck_assert_msg(fabs(ratio - 1) < 0.07, "walls %s: bottom pressure ratio %g", walls, ratio);
    sluice_sim_free(sim);
}

START_TEST(still_tank_mirror) { check_still_tank("mirror"); }
END_TEST
START_TEST(still_tank_particle) { check_still_tank("particle"); }
END_TEST

/* ------------------------------------------------------------ refusals -- */

static const char *refusal_scene(char *buffer, size_t size, const char *plugins)
{
    snprintf(buffer, size,
             "dimensions: 2\n"
             "particles: {spacing: 0.05}\n"
             "time: {end: 0.1}\n"
             "domain: {min: [0, 0], max: [1, 1], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 1]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "%s"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             plugins);
    return buffer;
}

START_TEST(refusals)
{
    char yaml[2048];
    test_load_refused("riemann-with-pressure-gradient",
                      refusal_scene(yaml, sizeof yaml,
                                    "  continuity: {}\n  pressure_gradient: {}\n"
                                    "  riemann_pressure: {}\n"),
                      "replaces 'pressure_gradient'");
    test_load_refused("riemann-with-continuity",
                      refusal_scene(yaml, sizeof yaml,
                                    "  continuity: {}\n  riemann_continuity: {}\n"
                                    "  riemann_pressure: {}\n"),
                      "replaces 'continuity'");
    test_load_refused("riemann-bad-limiter",
                      refusal_scene(yaml, sizeof yaml,
                                    "  riemann_continuity: {}\n"
                                    "  riemann_pressure: {limiter: roe}\n"),
                      "limiter");
    test_load_refused("riemann-negative-eta",
                      refusal_scene(yaml, sizeof yaml,
                                    "  riemann_continuity: {}\n"
                                    "  riemann_pressure: {eta: -1}\n"),
                      "eta");
    /* two phases: a closed box, water below y = 0.1 m and air above */
    test_load_refused("riemann-two-phase",
                      "dimensions: 2\n"
                      "particles: {spacing: 0.02, smoothing_length_ratio: 1.225}\n"
                      "time: {end: 0.1}\n"
                      "domain: {min: [-0.1, -0.1], max: [0.3, 0.3]}\n"
                      "geometry:\n"
                      "  fluid:\n"
                      "    - {shape: box, min: [0, 0], max: [0.2, 0.1]}\n"
                      "    - {shape: box, min: [0, 0.1], max: [0.2, 0.2]}\n"
                      "initial: {density: hydrostatic}\n"
                      "plugins:\n"
                      "  wendland_c2: {}\n"
                      "  two_phase: {speed_of_sound: 28, background_pressure: 350, air_above: "
                      "[[0, 0.1]]}\n"
                      "  riemann_continuity: {}\n"
                      "  riemann_pressure: {}\n"
                      "  gravity: {}\n"
                      "  time_step: {}\n"
                      "  symplectic: {}\n",
                      "single-phase");
}
END_TEST

int main(void)
{
    Suite *s = suite_create("riemann");
    TCase *f = tcase_create("formula");
    tcase_add_loop_test(f, formula_2d, 0, 2);
    tcase_add_loop_test(f, formula_3d, 0, 2);
    tcase_add_test(f, refusals);
    suite_add_tcase(s, f);
    TCase *c = tcase_create("conservation");
    tcase_add_test(c, momentum_2d);
    tcase_add_test(c, momentum_3d);
    tcase_add_loop_test(c, collision, 0, 2);
    suite_add_tcase(s, c);
    TCase *t = tcase_create("tank");
    tcase_set_timeout(t, 300);
    tcase_add_test(t, still_tank_mirror);
    tcase_add_test(t, still_tank_particle);
    suite_add_tcase(s, t);
    return test_run_suite(s);
}
