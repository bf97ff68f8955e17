/* Tests of the dissolved_oxygen plugin (seed 001), through the real core:
 *  - conservation: with the source off, the diffusion exchanges solute in
 *    equal and opposite amounts, so sum_i m_i C_i is conserved to round-off
 *    over a collapsing water column with random C (constant D, and with the
 *    eddy diffusivity of mixing_length and the harmonic pair mean); the
 *    volume-weighted total stays within the bound the water's compression
 *    allows; the variance decays (it is diffusion); the rate equals the
 *    formula summed by brute force (walls excluded);
 *  - 1D diffusion of a step between still particles against the erf
 *    solution (with periodic images), second order in dx once D carries the
 *    lattice factor M of the Brookshaw Laplacian, computed here from the
 *    kernel; against the nominal D within the bound |M - 1| gives;
 *  - the source alone (D = 0): every water particle relaxes as
 *    C_s - (C_s - C_0) exp(-K a_i t), a_i counted here by brute force, within
 *    the local truncation bound of a second-order step; no air within R, no
 *    change; the Reynolds-number law of K against its formula; with diffusion
 *    and source together (2D and 3D) the water exchanges nothing with the air;
 *  - particles an inlet creates start at initial_concentration;
 *  - bad input gives one clear message; a single-phase scene warns.
 * The source needs the field `phase`: it comes from the fixture plugin
 * tests/sdk/fixtures/do_phase_fixture.c, built with the tests. */
#include <math.h>

#include "sim_util.h"
/* Internal: calls the loaded kernel on its state; rest_density (not in sim.h) */
#include "sim_internal.h"

static uint64_t rng = 1001;
static double uniform(void)
{
    rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

static double kernel_eval(sluice_sim *sim, double r, double *f)
{
    const sluice_instance *k = &sim->instances[sim->kernel];
    sluice_real rr = (sluice_real)(r * r), distance = 0, w = 0, ff = 0;
    k->component->kernel(k->state, 1, &rr, &distance, &w, &ff);
    if (f)
        *f = (double)ff;
    return (double)w;
}

static void run_to(sluice_sim *sim, double end)
{
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < end - 1e-12)
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step failed: %s",
                      sluice_sim_failure(sim));
}

/* ---------------------------------------------------------- conservation -- */

typedef struct totals {
    double mass_weighted, volume_weighted, volume_abs, variance, rho_deviation;
} totals;

static totals measure(sluice_sim *sim)
{
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *m = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    const sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
    const double rho0 = (double)sim->rest_density;
    totals t = {0, 0, 0, 0, 0};
    double mass = 0, mean = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        t.mass_weighted += (double)m[i] * (double)c[i];
        t.volume_weighted += (double)m[i] / (double)rho[i] * (double)c[i];
        t.volume_abs += (double)m[i] / rho0 * fabs((double)c[i]);
        t.rho_deviation = fmax(t.rho_deviation, fabs(rho0 / (double)rho[i] - 1));
        mass += (double)m[i];
    }
    mean = t.mass_weighted / mass;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            t.variance += (double)m[i] * ((double)c[i] - mean) * ((double)c[i] - mean) / mass;
    return t;
}

/* The rate of every fluid particle after one evaluation against the formula
 * summed here by brute force over its fluid neighbours (walls take no part):
 * sum_j m_j (1/rho_i + 1/rho_j) D_ij r^2 F / (r^2 + 0.01 h^2) (C_i - C_j),
 * D_ij = 2 D_i D_j / (D_i + D_j), D = D_m + nu_t / Sc_t. Returns the largest
 * difference relative to the sum of the magnitudes of the pair terms. */
static double rate_against_formula(sluice_sim *sim, double dm, int eddy)
{
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *m = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    const sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
    const sluice_real *rate = test_column(sim, "dissolved_oxygen_rate", 0);
    const sluice_real *nu = eddy ? test_column(sim, "eddy_viscosity", 0) : NULL;
    const double h = (double)sim->smoothing_length, support = 2 * h;
    double worst = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const double di = dm + (eddy ? (double)nu[i] : 0);
        double sum = 0, scale = 0;
        for (sluice_index j = 0; j < v->count; j++) {
            if (j == i || v->kind[j] == SLUICE_KIND_WALL)
                continue;
            const double x = (double)v->position[0][i] - (double)v->position[0][j];
            const double y = (double)v->position[1][i] - (double)v->position[1][j];
            const double r2 = x * x + y * y;
            if (r2 >= support * support)
                continue;
            double f;
            kernel_eval(sim, sqrt(r2), &f);
            const double dj = dm + (eddy ? (double)nu[j] : 0);
            const double term = (double)m[j] * (1 / (double)rho[i] + 1 / (double)rho[j]) *
                                (2 * di * dj / (di + dj)) * r2 * f / (r2 + 0.01 * h * h) *
                                ((double)c[i] - (double)c[j]);
            sum += term;
            scale += fabs(term);
        }
        if (scale > 0)
            worst = fmax(worst, fabs((double)rate[i] - sum) / scale);
    }
    return worst;
}

static void check_conservation(int eddy)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.02, smoothing_length_ratio: 1.3}\n"
             "time: {end: 1.0}\n"
             "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [0.4, 0.4]}]\n"
             "  walls: [{shape: tank, min: [0, 0], max: [1.0, 0.8]}]\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  artificial_viscosity: {alpha: 0.1}\n"
             "  gravity: {}\n"
             "  dbc: {}\n"
             "%s"
             "  dissolved_oxygen: {initial_concentration: 5, molecular_diffusivity: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             eddy ? "  velocity_gradient: {}\n  mixing_length: {l_max: 0.05}\n" : "",
             eddy ? "2.1e-9" : "1e-2");
    sluice_sim *sim = test_load(eddy ? "do-conservation-eddy" : "do-conservation", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
    for (sluice_index i = 0; i < v->count; i++)
        c[i] = v->kind[i] == SLUICE_KIND_FLUID ? (sluice_real)(10 * uniform()) : 0;
    const totals start = measure(sim);
    const int steps = 400;
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    double nu_max = 0;
    for (int n = 0; n < steps; n++) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step failed: %s",
                      sluice_sim_failure(sim));
        if (eddy) {
            v = sluice_sim_view(sim);
            const sluice_real *nu = test_column(sim, "eddy_viscosity", 0);
            for (sluice_index i = 0; i < v->count; i++)
                if (v->kind[i] == SLUICE_KIND_FLUID)
                    nu_max = fmax(nu_max, (double)nu[i]);
        }
    }
    const totals end = measure(sim);
    /* after the collapse has begun, so that nu_t differs between particles
     * (the harmonic mean at work) */
    const double formula = rate_against_formula(sim, eddy ? 2.1e-9 : 1e-2, eddy);
    const double drift = fabs(end.mass_weighted - start.mass_weighted) / start.mass_weighted;
    const double volume_drift = fabs(end.volume_weighted - start.volume_weighted);
    const double volume_bound = (start.rho_deviation + end.rho_deviation) * start.volume_abs;
    fprintf(stderr,
            "dissolved_oxygen conservation%s: %d steps to t = %.4f s, relative change of "
            "sum m C %.2e; sum (m/rho) C changed by %.3e (bound from max |rho0/rho - 1| = %.2e: "
            "%.3e); variance %.4f -> %.4f (mg/L)^2; final rate against the brute-force "
            "formula %.1e (relative to the sum of |pair terms|)\n",
            eddy ? " (eddy diffusivity, harmonic mean)" : "", steps, sluice_sim_time(sim), drift,
            volume_drift, end.rho_deviation, volume_bound, start.variance, end.variance,
            formula);
    if (eddy)
        fprintf(stderr, "  largest nu_t seen: %.3e m^2/s\n", nu_max);
    ck_assert_msg(formula < 1e-12, "rate differs from the formula by %.3e", formula);
    /* each step adds O(N) rate contributions rounded at 1e-16 relative: a
     * random walk of a few 1e-16 per step stays far below 1e-12 */
    ck_assert_msg(drift < 1e-12, "sum m C drifted by %.3e", drift);
    ck_assert_msg(volume_drift <= volume_bound + 1e-12 * start.volume_abs,
                  "sum (m/rho) C changed by %.3e, more than the compression allows (%.3e)",
                  volume_drift, volume_bound);
    /* diffusion: the variance of C decays; with D = 1e-2 m^2/s every
     * lattice-scale mode (D k^2 t > 20) is gone */
    ck_assert_msg(end.variance < start.variance, "variance grew: %.4f -> %.4f", start.variance,
                  end.variance);
    if (!eddy)
        ck_assert_msg(end.variance < 0.5 * start.variance, "variance %.4f -> %.4f",
                      start.variance, end.variance);
    else
        ck_assert_msg(nu_max > 0, "no eddy viscosity: the eddy path was not exercised");
    sluice_sim_end(sim, SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}

START_TEST(conservation_constant_diffusivity) { check_conservation(0); }
END_TEST

START_TEST(conservation_eddy_diffusivity) { check_conservation(1); }
END_TEST

/* --------------------------------------------------------- erf solution -- */

#define STRIP_HEIGHT 0.25
#define C_LEFT 2.0
#define C_RIGHT 8.0
#define DIFFUSIVITY 0.01
#define DT_PRODUCT 0.0025 /* D t at the end: 2 sqrt(D t) = 0.1 m */

/* Step of period 1 (C_RIGHT on (0, 0.5), C_LEFT on (-0.5, 0)) diffused for
 * D t = dt_product: the sum of the erf solutions of its jumps. */
static double periodic_erf(double x, double dt_product)
{
    const double s = 2 * sqrt(dt_product);
    double sum = 0;
    for (int n = -3; n <= 3; n++)
        sum += erf((x - n) / s) - erf((x - 0.5 - n) / s);
    return C_LEFT + 0.5 * (C_RIGHT - C_LEFT) * sum;
}

/* The lattice factor of the Brookshaw Laplacian with eta^2 = 0.01 h^2: on a
 * lattice the operator applied to C(x) is D M C'' + O(dx^2), with
 * M = -sum_j V_j x_j^2 F_j r_j^2 / (r_j^2 + eta^2) (1 in the continuum). */
static double lattice_factor(sluice_sim *sim, double dx)
{
    const double h = (double)sim->smoothing_length, support = 2 * h;
    const int reach = (int)ceil(support / dx) + 1;
    double m = 0;
    for (int a = -reach; a <= reach; a++)
        for (int b = -reach; b <= reach; b++) {
            const double x = a * dx, y = b * dx, r2 = x * x + y * y;
            if ((a == 0 && b == 0) || r2 >= support * support)
                continue;
            double f;
            kernel_eval(sim, sqrt(r2), &f);
            m -= dx * dx * x * x * f * r2 / (r2 + 0.01 * h * h);
        }
    return m;
}

typedef struct erf_result {
    double error_effective, error_nominal, factor;
    int particles, steps;
} erf_result;

static erf_result erf_run(int cells)
{
    const double dx = 1.0 / cells;
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: %.17g, smoothing_length_ratio: 1.3}\n"
             "time: {end: %.17g}\n"
             "domain: {min: [-0.5, 0], max: [0.5, %g], periodic: xy}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [-0.5, 0], max: [0.5, %g]}]\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  dissolved_oxygen: {initial_concentration: 0, molecular_diffusivity: %g}\n"
             "  symplectic: {}\n",
             dx, DT_PRODUCT / DIFFUSIVITY, STRIP_HEIGHT, STRIP_HEIGHT, DIFFUSIVITY);
    sluice_sim *sim = test_load("do-erf", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
    for (sluice_index i = 0; i < v->count; i++)
        c[i] = v->position[0][i] < 0 ? C_LEFT : C_RIGHT;
    erf_result out = {0, 0, lattice_factor(sim, dx), (int)v->count, 0};
    run_to(sim, DT_PRODUCT / DIFFUSIVITY);
    out.steps = (int)sluice_sim_steps(sim);
    v = sluice_sim_view(sim);
    c = test_column(sim, "dissolved_oxygen", 0);
    const double t = sluice_sim_time(sim);
    for (sluice_index i = 0; i < v->count; i++) {
        const double x = (double)v->position[0][i];
        const double effective = periodic_erf(x, out.factor * DIFFUSIVITY * t);
        const double nominal = periodic_erf(x, DIFFUSIVITY * t);
        out.error_effective = fmax(out.error_effective, fabs((double)c[i] - effective));
        out.error_nominal = fmax(out.error_nominal, fabs((double)c[i] - nominal));
    }
    out.error_effective /= C_RIGHT - C_LEFT;
    out.error_nominal /= C_RIGHT - C_LEFT;
    sluice_sim_end(sim, SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return out;
}

START_TEST(erf_diffusion_second_order)
{
    const int cells[] = {40, 80, 160};
    erf_result r[3];
    for (int k = 0; k < 3; k++) {
        r[k] = erf_run(cells[k]);
        fprintf(stderr,
                "dissolved_oxygen erf: dx = 1/%d (%d particles, %d steps): max error / (C_R - "
                "C_L) %.3e against D_eff = M D (M = %.6f), %.3e against D%s",
                cells[k], r[k].particles, r[k].steps, r[k].error_effective, r[k].factor,
                r[k].error_nominal, k ? "" : "\n");
        if (k)
            fprintf(stderr, "; observed order %.2f\n",
                    log2(r[k - 1].error_effective / r[k].error_effective));
    }
    /* M depends only on h/dx and the kernel: the same at every resolution */
    ck_assert(fabs(r[0].factor - r[2].factor) < 1e-12);
    /* second-order consistency of the lattice Laplacian (4th moment of the
     * kernel) and of the time step (dt ~ dx^2): the error against the erf
     * solution with D M falls by about 4 per halving of dx */
    for (int k = 1; k < 3; k++) {
        const double order = log2(r[k - 1].error_effective / r[k].error_effective);
        ck_assert_msg(order > 1.7, "observed order %.2f between dx = 1/%d and 1/%d", order,
                      cells[k - 1], cells[k]);
    }
    ck_assert_msg(r[2].error_effective < 2e-3, "error %.3e at dx = 1/160", r[2].error_effective);
    /* against the nominal D the error is the lattice factor's: bounded by
     * |M - 1| times the largest sensitivity of the solution to D t, which for
     * an erf profile of a step is (C_R - C_L) / (2 sqrt(2 pi e)) per relative
     * change of D t (two jumps do not overlap at 2 sqrt(D t) = 0.1 m) */
    const double sensitivity = 1 / (2 * sqrt(2 * M_PI * M_E));
    ck_assert_msg(r[2].error_nominal <=
                      fabs(r[2].factor - 1) * sensitivity * 1.05 + r[2].error_effective,
                  "error against nominal D %.3e, |M - 1| = %.3e", r[2].error_nominal,
                  fabs(r[2].factor - 1));
}
END_TEST

/* ------------------------------------------------------------ the source -- */

/* Directory holding do_phase_fixture.so (built with the tests). */
static char *phase_fixture_dir(void)
{
    const char *built = getenv("SLUICE_FIXTURE_DIR");
    ck_assert_msg(built != NULL, "SLUICE_FIXTURE_DIR is not set (run through meson test)");
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/do_phase_fixture.so", built), 0);
    ck_assert_msg(test_exists(path), "%s is missing", path);
    free(path);
    return strdup(built);
}

#define SPACING 0.01 /* 2D; 3D: 2 SPACING */
#define AIR_ABOVE 0.1
#define SEARCH_RADIUS (2.5 * SPACING)

static double spacing_of(int dims)
{
    return dims == 3 ? 2 * SPACING : SPACING;
}

/* A still block, 0.2 m wide (periodic) and high, air above AIR_ABOVE, nothing
 * moves (no force); search radius 2.5 dx. */
static sluice_sim *source_scene(const char *tag, const char *fixture_dir, const char *law,
                                int dims)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: %d\n"
             "plugin_path: %s\n"
             "particles: {spacing: %g, smoothing_length_ratio: 1.3}\n"
             "time: {end: 10}\n"
             "domain: {min: %s, max: %s, periodic: %s}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: %s, max: %s}]\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  do_phase_fixture: {air_above: %g}\n"
             "  dissolved_oxygen:\n"
             "    initial_concentration: 1.29\n"
             "    saturation_concentration: 10.48\n"
             "    two_phase: yes\n"
             "    search_radius: %.17g\n"
             "%s"
             "  gravity: {acceleration: %s}\n"
             "  time_step: {acoustic: false}\n"
             "  symplectic: {}\n",
             dims, fixture_dir, spacing_of(dims), dims == 3 ? "[0, 0, -0.1]" : "[0, -0.1]",
             dims == 3 ? "[0.2, 0.2, 0.3]" : "[0.2, 0.3]", dims == 3 ? "xy" : "x",
             dims == 3 ? "[0, 0, 0]" : "[0, 0]", dims == 3 ? "[0.2, 0.2, 0.2]" : "[0.2, 0.2]",
             AIR_ABOVE, 2.5 * spacing_of(dims), law, dims == 3 ? "[0, 0, 0]" : "[0, 0]");
    return test_load(tag, yaml, NULL, 0);
}

/* a_i = N_air A_b / ((N_water + 1) dx^d) counted by brute force, d_b = dx,
 * A_b = pi d_b (2D) or pi d_b^2 (3D); the horizontal axes periodic of
 * period 0.2. */
static void specific_surface(const sluice_view *v, const uint8_t *phase, double *a)
{
    const int dims = (int)v->dimensions;
    const double dx = spacing_of(dims), radius = 2.5 * dx;
    for (sluice_index i = 0; i < v->count; i++) {
        int air = 0, water = 0;
        for (sluice_index j = 0; j < v->count; j++) {
            if (j == i)
                continue;
            double r2 = 0;
            for (int d = 0; d < dims; d++) {
                double x = (double)v->position[d][i] - (double)v->position[d][j];
                if (d < dims - 1)
                    x -= 0.2 * round(x / 0.2);
                r2 += x * x;
            }
            if (r2 < radius * radius)
                phase[j] ? air++ : water++;
        }
        a[i] = air * M_PI * pow(dx, dims - 1) / ((water + 1) * pow(dx, dims));
    }
}

START_TEST(source_relaxes_to_saturation)
{
    char *dir = phase_fixture_dir();
    const double k_transfer = 0.01, cs = 10.48, c0 = 1.29, end = 1.5;
    char law[128];
    snprintf(law, sizeof law, "    molecular_diffusivity: 0\n    transfer_velocity: %g\n",
             k_transfer);
    sluice_sim *sim = source_scene("do-source", dir, law, 2);
    sluice_field phase_field;
    ck_assert_int_eq(sluice_sim_field(sim, "phase", &phase_field), SLUICE_OK);
    double dts[4096];
    int steps = 0;
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < end - 1e-12) {
        const double before = sluice_sim_time(sim);
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step failed: %s",
                      sluice_sim_failure(sim));
        ck_assert(steps < 4096);
        dts[steps++] = sluice_sim_time(sim) - before;
    }
    /* nothing moves (no force, no velocity): a_i from the final positions is
     * the a_i of every step */
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = (const uint8_t *)v->columns[phase_field.column];
    double *a = calloc(v->count, sizeof *a);
    ck_assert_ptr_nonnull(a);
    specific_surface(v, phase, a);
    const sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
    const sluice_real *ka = test_column(sim, "reaeration_coefficient", 0);
    const double t = sluice_sim_time(sim);
    int water = 0, sourced = 0, air = 0;
    double worst = 0, worst_bound = 0, worst_ratio = -1, ka_max = 0, ka_error = 0,
           untouched = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (phase[i]) {
            air++;
            ck_assert_msg(c[i] == 0, "air particle with C = %g", (double)c[i]);
            continue;
        }
        water++;
        const double rate = k_transfer * a[i];
        ka_error = fmax(ka_error, fabs((double)ka[i] - rate));
        ka_max = fmax(ka_max, rate);
        if (rate == 0) {
            untouched = fmax(untouched, fabs((double)c[i] - c0));
            continue;
        }
        sourced++;
        const double exact = cs - (cs - c0) * exp(-rate * t);
        /* a second-order one-step method multiplies the deficit by
         * 1 - x + x^2/2 instead of exp(-x), x = K a dt: a local error below
         * x^3/6 of the deficit (both factors are in (0, 1)), summed over the
         * steps */
        double cubes = 0;
        for (int n = 0; n < steps; n++)
            cubes += pow(rate * dts[n], 3);
        const double bound = (cs - c0) * cubes / 6 + 1e-12;
        const double error = fabs((double)c[i] - exact);
        if (error / bound > worst_ratio) {
            worst_ratio = error / bound;
            worst = error;
            worst_bound = bound;
        }
        ck_assert_msg(error <= bound, "particle %u: C = %.12g, exact %.12g, bound %.3e",
                      (unsigned)i, (double)c[i], exact, bound);
    }
    fprintf(stderr,
            "dissolved_oxygen source: %d water particles (%d within R = %g m of air), %d air; "
            "t = %.3f s in %d steps, largest K a = %.4f 1/s; |C - C_exact| = %.3e mg/L at "
            "%.0f %% of its bound %.3e (worst ratio); |K a - K a_exact| <= %.1e; C away from "
            "air changed by %.1e\n",
            water, sourced, SEARCH_RADIUS, air, t, steps, ka_max, worst, 100 * worst_ratio,
            worst_bound, ka_error, untouched);
    ck_assert(sourced > 0 && water - sourced > 0 && air > 0);
    ck_assert_msg(ka_error <= 1e-12 * ka_max, "K a differs from K N_air A_b / V_w by %.3e",
                  ka_error);
    ck_assert_msg(untouched == 0, "C changed by %.3e with no air within R", untouched);
    /* the relaxation went a good way (K a t of order 1 at the interface) */
    ck_assert(ka_max * t > 1);
    sluice_sim_end(sim, SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    free(a);
    free(dir);
}
END_TEST

/* Two phases, diffusion and source together, one evaluation with random C in
 * the water: water-water diffusion alone is antisymmetric, so
 * sum_water m_i dC_i/dt must equal sum_water m_i K a_i (C_s - C_i) to
 * round-off (a flux into the air, whose C is 0, would break it); air
 * particles get no rate. */
static void two_phase_evaluation(const char *dir, int dims)
{
    const double k_transfer = 0.01;
    char law[128];
    snprintf(law, sizeof law, "    molecular_diffusivity: 1e-3\n    transfer_velocity: %g\n",
             k_transfer);
    sluice_sim *sim = source_scene(dims == 3 ? "do-two-phase-3d" : "do-two-phase", dir, law, dims);
    sluice_field phase_field;
    ck_assert_int_eq(sluice_sim_field(sim, "phase", &phase_field), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = (const uint8_t *)v->columns[phase_field.column];
    sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
    for (sluice_index i = 0; i < v->count; i++)
        c[i] = phase[i] ? 0 : (sluice_real)(10 * uniform());
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    phase = (const uint8_t *)v->columns[phase_field.column];
    c = test_column(sim, "dissolved_oxygen", 0);
    double *a = calloc(v->count, sizeof *a);
    ck_assert_ptr_nonnull(a);
    specific_surface(v, phase, a);
    const sluice_real *m = test_column(sim, "mass", 0);
    const sluice_real *rate = test_column(sim, "dissolved_oxygen_rate", 0);
    const sluice_real *ka = test_column(sim, "reaeration_coefficient", 0);
    double total = 0, source = 0, scale = 0, air_rate = 0, ka_error = 0, ka_max = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (phase[i]) {
            air_rate = fmax(air_rate, fabs((double)rate[i]));
            continue;
        }
        ka_error = fmax(ka_error, fabs((double)ka[i] - k_transfer * a[i]));
        ka_max = fmax(ka_max, k_transfer * a[i]);
        total += (double)m[i] * (double)rate[i];
        source += (double)m[i] * (double)ka[i] * (10.48 - (double)c[i]);
        scale += (double)m[i] * fabs((double)rate[i]);
    }
    fprintf(stderr,
            "dissolved_oxygen two phases %dD (%u particles): sum_water m dC/dt = %.6e, "
            "sum_water m K a (C_s - C) = %.6e (difference %.1e of sum m |dC/dt|); largest "
            "|dC/dt| in air %.1e; largest K a %.4f 1/s, |K a - K N_air A_b / V_w| <= %.1e\n",
            dims, (unsigned)v->count, total, source, fabs(total - source) / scale, air_rate,
            ka_max, ka_error);
    ck_assert(source > 0 && scale > 10 * source); /* diffusion dominates the sum of |rates| */
    ck_assert_msg(fabs(total - source) <= 1e-13 * scale, "water exchanges %.3e with the air",
                  total - source);
    ck_assert(air_rate == 0);
    ck_assert(ka_max > 0);
    ck_assert_msg(ka_error <= 1e-12 * ka_max, "K a off by %.3e", ka_error);
    sluice_sim_free(sim);
    free(a);
}

START_TEST(two_phase_diffusion_stays_in_water)
{
    char *dir = phase_fixture_dir();
    two_phase_evaluation(dir, 2);
    two_phase_evaluation(dir, 3);
    free(dir);
}
END_TEST

/* K = c_1 sqrt(D_m nu) / d_b Re^(1 + c_2), Re = |v_i - mean v_air| d_b / nu:
 * the air moves at u = 0.3 m/s over still water; one evaluation. */
START_TEST(source_reynolds_law)
{
    char *dir = phase_fixture_dir();
    const double c1 = 0.3, c2 = -0.3, dm = 2.1e-9, nu = 1.1e-6, d_b = SPACING, u_air = 0.3;
    char law[256];
    snprintf(law, sizeof law,
             "    transfer_coefficient: %g\n    reynolds_exponent: %g\n    kinematic_viscosity: "
             "%g\n    molecular_diffusivity: %g\n",
             c1, c2, nu, dm);
    sluice_sim *sim = source_scene("do-law", dir, law, 2);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_field phase_field;
    ck_assert_int_eq(sluice_sim_field(sim, "phase", &phase_field), SLUICE_OK);
    const uint8_t *phase = (const uint8_t *)v->columns[phase_field.column];
    sluice_real *vx = test_column(sim, "velocity", 0);
    for (sluice_index i = 0; i < v->count; i++)
        vx[i] = phase[i] ? (sluice_real)u_air : 0;
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    phase = (const uint8_t *)v->columns[phase_field.column];
    double *a = calloc(v->count, sizeof *a);
    ck_assert_ptr_nonnull(a);
    specific_surface(v, phase, a);
    const sluice_real *ka = test_column(sim, "reaeration_coefficient", 0);
    const sluice_real *rate = test_column(sim, "dissolved_oxygen_rate", 0);
    const double re = u_air * d_b / nu;
    const double k_transfer = c1 * sqrt(dm * nu) / d_b * pow(re, 1 + c2);
    double worst = 0, largest = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (phase[i])
            continue;
        const double expected = k_transfer * a[i];
        largest = fmax(largest, expected);
        worst = fmax(worst, fabs((double)ka[i] - expected));
        /* uniform C: the diffusion adds nothing, the rate is the source */
        ck_assert(fabs((double)rate[i] - expected * (10.48 - 1.29)) <=
                  1e-12 * (1 + expected * 10.48));
    }
    fprintf(stderr,
            "dissolved_oxygen Reynolds law: Re = %.1f, K = %.4e m/s; largest K a %.4e 1/s, "
            "|K a - formula| <= %.1e\n",
            re, k_transfer, largest, worst);
    ck_assert(largest > 0);
    ck_assert_msg(worst <= 1e-12 * largest, "K a off by %.3e", worst);
    sluice_sim_free(sim);
    free(a);
    free(dir);
}
END_TEST

/* ------------------------------------------------------------- inflow -- */

/* Particles an inlet creates during the run start at initial_concentration
 * (the core creates them with every other field zero): with D = 0 and no
 * source every fluid and open-boundary particle, old or new, must hold it
 * exactly. */
START_TEST(inflow_particles_start_at_initial)
{
    const char *yaml =
        "dimensions: 2\n"
        "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
        "time: {end: 0.3}\n"
        "domain: {min: [-0.7, -0.1], max: [1.1, 0.6]}\n"
        "geometry:\n"
        "  fluid: [{shape: box, min: [0, 0], max: [0.6, 0.1], velocity: [0.5, 0]}]\n"
        "  walls: [{shape: polyline, points: [[-0.66, 0], [1.0, 0]], name: bed}]\n"
        "plugins:\n"
        "  wendland_c2: {}\n"
        "  tait: {speed_of_sound: 10}\n"
        "  continuity: {}\n"
        "  pressure_gradient: {}\n"
        "  artificial_viscosity: {alpha: 0.02}\n"
        "  gravity: {}\n"
        "  penalty_contact: {}\n"
        "  time_step: {courant: 0.25}\n"
        "  symplectic: {}\n"
        "  inlet: {position: 0, depth: 0.1, velocity: 0.5}\n"
        "  outlet: {position: 0.6, depth: 0.1, velocity: 0.5}\n"
        "  dissolved_oxygen: {initial_concentration: 3.0, molecular_diffusivity: 0}\n";
    sluice_sim *sim = test_load("do-inflow", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_id first_new = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->id[i] >= first_new)
            first_new = v->id[i] + 1;
    run_to(sim, 0.3);
    v = sluice_sim_view(sim);
    const sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
    int created = 0, wrong = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] == SLUICE_KIND_WALL)
            continue;
        created += v->id[i] >= first_new;
        wrong += c[i] != (sluice_real)3.0;
    }
    fprintf(stderr,
            "dissolved_oxygen inflow: %d particles created by the inlet still present after "
            "0.3 s, %d particles (old or new) with C != 3\n",
            created, wrong);
    ck_assert_int_gt(created, 0);
    ck_assert_int_eq(wrong, 0);
    sluice_sim_end(sim, SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}
END_TEST

/* ------------------------------------------------------------ bad input -- */

static const char *input_base =
    "dimensions: 2\n"
    "plugin_path: %s\n"
    "particles: {spacing: 0.05}\n"
    "time: {end: 0.01}\n"
    "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
    "geometry:\n"
    "  fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]\n"
    "  walls: [{shape: tank, min: [0, 0], max: [1, 1]}]\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 20}\n"
    "  continuity: {}\n"
    "  pressure_gradient: {}\n"
    "  gravity: {}\n"
    "  dbc: {}\n"
    "  symplectic: {}\n"
    "%s";

static void expect_refused(const char *dir, const char *extra, const char *needle)
{
    char *yaml = NULL;
    ck_assert_int_ge(asprintf(&yaml, input_base, dir, extra), 0);
    test_load_refused("do-input", yaml, needle);
    free(yaml);
}

START_TEST(bad_input)
{
    char *dir = phase_fixture_dir();
    expect_refused(dir,
                   "  time_step: {}\n"
                   "  dissolved_oxygen: {initial_concentration: 1, search_radius: 0.2}\n",
                   "larger than the kernel support");
    expect_refused(dir,
                   "  time_step: {}\n"
                   "  dissolved_oxygen: {initial_concentration: 1, molecular_diffusivity: "
                   "-1e-9}\n",
                   "molecular_diffusivity");
    expect_refused(dir,
                   "  time_step: {}\n"
                   "  dissolved_oxygen: {initial_concentration: 1, turbulent_schmidt_number: 0}\n",
                   "turbulent_schmidt_number");
    expect_refused(dir,
                   "  time_step: {}\n"
                   "  dissolved_oxygen: {initial_concentration: 1, reynolds_exponent: -1}\n",
                   "reynolds_exponent");
    expect_refused(dir,
                   "  time_step: {}\n"
                   "  dissolved_oxygen: {initial_concentration: -2}\n",
                   "initial_concentration");
    expect_refused(dir, "  time_step: {}\n  dissolved_oxygen: {}\n", "initial_concentration");
    expect_refused(dir,
                   "  time_step: {}\n"
                   "  dissolved_oxygen: {initial_concentration: 1, two_phase: yes}\n",
                   "'phase' (read by 'dissolved_oxygen')");
    expect_refused(dir,
                   "  laminar_viscosity: {}\n"
                   "  do_phase_fixture: {air_above: 0.4}\n"
                   "  dissolved_oxygen: {initial_concentration: 1}\n",
                   "courant_number");
    free(dir);
}
END_TEST

/* A scene without a phase field loads with a warning that says the source is
 * zero everywhere. */
START_TEST(single_phase_warns)
{
    char *dir = phase_fixture_dir(); /* on the path, not loaded */
    char *scratch = test_scratch("do-single");
    ck_assert_ptr_nonnull(scratch);
    char *yaml = NULL;
    ck_assert_int_ge(asprintf(&yaml, input_base, dir,
                              "  time_step: {}\n  dissolved_oxygen: {initial_concentration: 1}\n"),
                     0);
    char *path = test_write_file(scratch, "scene.yaml", yaml);
    char *args = NULL, *out = NULL;
    ck_assert_int_ge(asprintf(&args, "check %s", path), 0);
    const int rc = test_sluice(args, &out);
    fprintf(stderr, "%s", out ? out : "");
    ck_assert_msg(rc == 0, "sluice check failed (%d)", rc);
    ck_assert_msg(out && strstr(out, "warning") &&
                      strstr(out, "every fluid particle is water and the reaeration source is "
                                  "zero everywhere"),
                  "no single-phase warning in:\n%s", out ? out : "");
    free(out);
    free(args);
    free(path);
    free(yaml);
    free(scratch);
    free(dir);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("dissolved_oxygen");
    TCase *c = tcase_create("conservation");
    tcase_add_test(c, conservation_constant_diffusivity);
    tcase_add_test(c, conservation_eddy_diffusivity);
    suite_add_tcase(s, c);
    c = tcase_create("erf");
    tcase_add_test(c, erf_diffusion_second_order);
    suite_add_tcase(s, c);
    c = tcase_create("source");
    tcase_add_test(c, source_relaxes_to_saturation);
    tcase_add_test(c, source_reynolds_law);
    tcase_add_test(c, two_phase_diffusion_stays_in_water);
    suite_add_tcase(s, c);
    c = tcase_create("inflow");
    tcase_add_test(c, inflow_particles_start_at_initial);
    suite_add_tcase(s, c);
    c = tcase_create("input");
    tcase_add_test(c, bad_input);
    tcase_add_test(c, single_phase_warns);
    suite_add_tcase(s, c);
    return test_run_suite(s);
}
