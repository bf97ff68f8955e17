/* Tests of the correction and smoothing terms, loaded through the real core:
 *  - xsph (position and velocity_smoothing forms): zero for a uniform flow on
 *    a disordered set, the hand-computed correction of three particles,
 *    conservation of the momentum the position form moves;
 *  - kernel_correction: exact gradients of linear fields on disordered sets
 *    in 2D and 3D (and not without it), the blend to the identity for
 *    singular moment matrices;
 *  - pressure_smoothing: a tank at rest is unchanged, a checkerboard pressure
 *    decays by the lattice factor of the Shepard filter, the density written
 *    is the EOS inverse of the smoothed pressure, masses are untouched;
 *  - api->evaluation->density_from_pressure (ABI 1.2) without an equation of state. */
#include <math.h>

#include "sim_util.h"
/* Internal: calls the loaded kernel and the tait, transport_velocity and pressure_smoothing
 * instances on their state; dt, support, the grid (not in sim.h) */
#include "sim_internal.h"

static uint64_t rng = 7;
static double uniform(void)
{
    rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

static sluice_instance *instance(sluice_sim *sim, const char *name)
{
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if (strcmp(sim->instances[k].name, name) == 0)
            return &sim->instances[k];
    ck_abort_msg("no plugin '%s' in the scene", name);
    return NULL;
}

/* W(r) and F(r) = (dW/dr)/r from the scene's kernel. */
static double kernel_wf(sluice_sim *sim, double r, double *f)
{
    const sluice_instance *k = &sim->instances[sim->kernel];
    sluice_real rr = (sluice_real)(r * r), distance = 0, w = 0, ff = 0;
    k->component->kernel(k->state, 1, &rr, &distance, &w, &ff);
    if (f)
        *f = (double)ff;
    return (double)w;
}

/* Wendland C2 in 2D written out (physics notes): the hand computations do
 * not go through the kernel plugin. */
static double wendland_2d(double r, double h)
{
    double q = r / h;
    if (q >= 2)
        return 0;
    double a = 7.0 / (4.0 * M_PI * h * h), s = 1 - q / 2;
    return a * s * s * s * s * (2 * q + 1);
}

/* Re-sorts the particles and rebuilds the neighbour list after the test
 * moved them. */
static void rebuild(sluice_sim *sim)
{
    sluice_index bad = 0;
    sluice_sim_refresh_view(sim);
    ck_assert_int_eq(
        sluice_grid_build(&sim->grid, &sim->particles, (uint32_t)sim->position.column, &bad), 0);
    sluice_sim_refresh_view(sim);
}

/* Moves every particle by a uniform random offset in [-a, a] dx per axis and
 * multiplies its density by 1 + noise (uniform in [-1, 1]) times `density`. */
static void disorder(sluice_sim *sim, double a, double density)
{
    const sluice_view *v = sluice_sim_view(sim);
    const double dx = (double)v->spacing;
    for (uint32_t d = 0; d < v->dimensions; d++) {
        sluice_real *x = test_column(sim, "position", d);
        for (sluice_index i = 0; i < v->count; i++)
            x[i] += (sluice_real)(a * dx * (2 * uniform() - 1));
    }
    sluice_real *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < v->count; i++)
        rho[i] *= (sluice_real)(1 + density * (2 * uniform() - 1));
    rebuild(sim);
}

/* ----------------------------------------------------------------- xsph -- */

static const char *xsph_box =
    "dimensions: %d\n"
    "particles: {spacing: %g, smoothing_length_ratio: 1.3}\n"
    "time: {end: 1.0, max_step: 0.001}\n"
    "domain: {min: %s, max: %s, periodic: %s}\n"
    "geometry: {fluid: [{shape: box, min: %s, max: %s}]}\n"
    "initial: {density: rest}\n"
    "plugins: {wendland_c2: {}, xsph: {form: %s}, symplectic: {}}\n";

static sluice_sim *xsph_periodic(int dims, const char *form)
{
    char yaml[2048];
    const char *lo = dims == 2 ? "[0, 0]" : "[0, 0, 0]";
    const char *hi = dims == 2 ? "[0.8, 0.8]" : "[0.5, 0.5, 0.5]";
    snprintf(yaml, sizeof yaml, xsph_box, dims, dims == 2 ? 0.04 : 0.05, lo, hi,
             dims == 2 ? "xy" : "xyz", lo, hi, form);
    return test_load("xsph", yaml, NULL, 0);
}

/* A uniform velocity on a disordered periodic set: both forms give exactly
 * no correction (every v_ji vanishes). */
static void xsph_uniform(int dims, const char *form)
{
    sluice_sim *sim = xsph_periodic(dims, form);
    disorder(sim, 0.2, 0.01);
    const sluice_view *v = sluice_sim_view(sim);
    const double u[3] = {0.7, -0.3, 0.45};
    for (int d = 0; d < dims; d++) {
        sluice_real *vel = test_column(sim, "velocity", (uint32_t)d);
        for (sluice_index i = 0; i < v->count; i++)
            vel[i] = (sluice_real)u[d];
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    double worst = 0;
    for (int d = 0; d < dims; d++) {
        const sluice_real *du = test_column(sim, "transport_velocity_correction", (uint32_t)d);
        for (sluice_index i = 0; i < v->count; i++) {
            ck_assert_msg(isfinite(du[i]), "non-finite correction");
            worst = fabs(du[i]) > worst ? fabs(du[i]) : worst;
        }
    }
    fprintf(stderr, "xsph %s %dD: uniform flow on %u disordered particles: max |du| = %.3g m/s\n",
            form, dims, v->count, worst);
    /* v_j - v_i = 0 exactly: any round-off would be below 1e-15 |u| */
    ck_assert_msg(worst <= 1e-15, "xsph %s: uniform flow corrected by %g m/s", form, worst);
    sluice_sim_free(sim);
}

START_TEST(xsph_uniform_position_2d) { xsph_uniform(2, "position"); }
END_TEST
START_TEST(xsph_uniform_smoothing_2d) { xsph_uniform(2, "velocity_smoothing"); }
END_TEST
START_TEST(xsph_uniform_position_3d) { xsph_uniform(3, "position"); }
END_TEST
START_TEST(xsph_uniform_smoothing_3d) { xsph_uniform(3, "velocity_smoothing"); }
END_TEST

/* Three particles on a line, spacing dx, h = 1.3 dx (the outer two are 2 dx
 * < 2h apart): the corrections written out by hand. With coefficient <= 0
 * the key is left out, and the form's default applies. */
static void xsph_three(const char *form, double coefficient)
{
    char yaml[2048], given[64] = "";
    const double dx = 0.1;
    const int position = strcmp(form, "position") == 0;
    if (coefficient > 0)
        snprintf(given, sizeof given, ", %s: %.17g", position ? "epsilon" : "phi", coefficient);
    else
        coefficient = position ? 0.3 : 0.01;
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: %g, smoothing_length_ratio: 1.3, rest_density: 1000}\n"
             "time: {end: 1.0, max_step: 0.001}\n"
             "domain: {min: [-1, -1], max: [1, 1]}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [%g, %g]}]}\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, xsph: {form: %s%s}, symplectic: {}}\n",
             dx, 3 * dx, dx, form, given);
    sluice_sim *sim = test_load("xsph3", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK); /* settles the particle order */
    const sluice_view *v = sluice_sim_view(sim);
    ck_assert_int_eq(v->count, 3);
    /* particle k sits at x = (k + 1/2) dx */
    const double vx[3] = {0.3, -0.2, 0.9}, vy[3] = {-0.5, 0.1, 0.25};
    const double rho[3] = {1003.0, 996.5, 1010.0};
    const double m = 1000 * dx * dx, h = 1.3 * dx;
    sluice_index at[3];
    for (sluice_index i = 0; i < 3; i++) {
        int k = (int)lround(v->position[0][i] / dx - 0.5);
        ck_assert(k >= 0 && k < 3);
        at[k] = i;
    }
    for (int k = 0; k < 3; k++) {
        test_column(sim, "velocity", 0)[at[k]] = (sluice_real)vx[k];
        test_column(sim, "velocity", 1)[at[k]] = (sluice_real)vy[k];
        test_column(sim, "density", 0)[at[k]] = (sluice_real)rho[k];
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const int smoothing = strcmp(form, "velocity_smoothing") == 0;
    const double w0 = wendland_2d(0, h);
    double momentum[2] = {0, 0}, scale = 0;
    for (int i = 0; i < 3; i++) {
        double sx = 0, sy = 0, shepard = m / rho[i] * w0;
        for (int j = 0; j < 3; j++) {
            if (j == i)
                continue;
            double w = wendland_2d(fabs((double)(i - j)) * dx, h);
            double weight = smoothing ? m / rho[j] * w : m / (0.5 * (rho[i] + rho[j])) * w;
            sx += weight * (vx[j] - vx[i]);
            sy += weight * (vy[j] - vy[i]);
            shepard += weight;
        }
        double ex = coefficient * sx, ey = coefficient * sy;
        if (smoothing) {
            ex /= shepard;
            ey /= shepard;
        }
        double gx = test_column(sim, "transport_velocity_correction", 0)[at[i]];
        double gy = test_column(sim, "transport_velocity_correction", 1)[at[i]];
        fprintf(stderr, "xsph %s, three particles, #%d: du = (%.12g, %.12g), by hand (%.12g, "
                        "%.12g)\n",
                form, i, gx, gy, ex, ey);
        double size = fabs(ex) + fabs(ey);
        ck_assert_msg(size > 1e-3, "the hand case must move particles");
        /* a handful of operations: 1e-14 relative */
        ck_assert_msg(fabs(gx - ex) <= 1e-14 * size && fabs(gy - ey) <= 1e-14 * size,
                      "xsph %s particle %d: (%g, %g) vs (%g, %g)", form, i, gx, gy, ex, ey);
        momentum[0] += m * gx;
        momentum[1] += m * gy;
        scale += m * size;
    }
    fprintf(stderr, "xsph %s, three particles: sum m du = (%.3g, %.3g) kg m/s (sum m|du| %.3g)\n",
            form, momentum[0], momentum[1], scale);
    if (!smoothing)
        ck_assert(fabs(momentum[0]) <= 1e-15 * scale && fabs(momentum[1]) <= 1e-15 * scale);
    sluice_sim_free(sim);
}

START_TEST(xsph_three_position) { xsph_three("position", 0.45); }
END_TEST

START_TEST(xsph_three_position_default) { xsph_three("position", 0); }
END_TEST
START_TEST(xsph_three_smoothing) { xsph_three("velocity_smoothing", 0.2); }
END_TEST

START_TEST(xsph_three_smoothing_default) { xsph_three("velocity_smoothing", 0); }
END_TEST

/* each form's coefficient belongs to it: the other form's is refused, not
 * ignored (a scene giving phi with the position form ran with epsilon's
 * default without a word) */
START_TEST(xsph_other_forms_coefficient_refused)
{
    const char *head = "dimensions: 2\n"
                       "particles: {spacing: 0.1, smoothing_length_ratio: 1.3, rest_density: 1000}\n"
                       "time: {end: 1.0, max_step: 0.001}\n"
                       "domain: {min: [-1, -1], max: [1, 1]}\n"
                       "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.3, 0.1]}]}\n"
                       "initial: {density: rest}\n";
    char yaml[1024];
    snprintf(yaml, sizeof yaml, "%splugins: {wendland_c2: {}, xsph: {phi: 0.3}, symplectic: {}}\n",
             head);
    test_load_refused("xsph-phi-position", yaml, "form position takes epsilon");
    snprintf(yaml, sizeof yaml,
             "%splugins: {wendland_c2: {}, xsph: {form: velocity_smoothing, epsilon: 0.3}, "
             "symplectic: {}}\n",
             head);
    test_load_refused("xsph-epsilon-smoothing", yaml, "form velocity_smoothing takes phi");
    /* 0 is out of range: XSPH off is a scene without the plugin */
    snprintf(yaml, sizeof yaml,
             "%splugins: {wendland_c2: {}, xsph: {epsilon: 0}, symplectic: {}}\n", head);
    test_load_refused("xsph-epsilon-zero", yaml, "epsilon");
}
END_TEST

/* Random velocities and densities on a disordered periodic set: the position
 * form's pair weight m_i m_j W_ij / rhobar_ij is symmetric, so
 * sum_i m_i du_i = 0 to round-off. The Shepard form is not symmetric: its
 * figure is printed for information. */
static void xsph_momentum(int dims, const char *form, int conserving)
{
    sluice_sim *sim = xsph_periodic(dims, form);
    disorder(sim, 0.2, 0.01);
    const sluice_view *v = sluice_sim_view(sim);
    for (int d = 0; d < dims; d++) {
        sluice_real *vel = test_column(sim, "velocity", (uint32_t)d);
        for (sluice_index i = 0; i < v->count; i++)
            vel[i] = (sluice_real)(uniform() - 0.4);
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const sluice_real *m = test_column(sim, "mass", 0);
    for (int d = 0; d < dims; d++) {
        const sluice_real *du = test_column(sim, "transport_velocity_correction", (uint32_t)d);
        double sum = 0, scale = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            sum += m[i] * du[i];
            scale += m[i] * fabs(du[i]);
        }
        fprintf(stderr, "xsph %s %dD, random velocities: sum m du[%d] = %.3g (sum m |du| = %.3g)\n",
                form, dims, d, sum, scale);
        ck_assert(scale > 0);
        /* each pair contributes +w and -w: only summation round-off remains,
         * O(sqrt(N) eps) of the scale */
        if (conserving)
            ck_assert_msg(fabs(sum) <= 1e-13 * scale, "momentum moved: %g of %g", sum, scale);
    }
    sluice_sim_free(sim);
}

START_TEST(xsph_momentum_position)
{
    xsph_momentum(2, "position", 1);
    xsph_momentum(3, "position", 1);
    xsph_momentum(2, "velocity_smoothing", 0);
}
END_TEST

/* ---------------------------------------------------- transport_velocity -- */

/* A periodic box of fluid with transport_velocity alone (no force: the
 * particles move only with the correction). */
static sluice_sim *tv_periodic(int dims, double background_pressure, const char *extra,
                               const char *integrator)
{
    char yaml[2048];
    const char *lo = dims == 2 ? "[0, 0]" : "[0, 0, 0]";
    const char *hi = dims == 2 ? "[0.8, 0.8]" : "[0.5, 0.5, 0.5]";
    snprintf(yaml, sizeof yaml,
             "dimensions: %d\n"
             "particles: {spacing: %g, smoothing_length_ratio: 1.3}\n"
             "time: {end: 10.0, max_step: 0.001}\n"
             "domain: {min: %s, max: %s, periodic: %s}\n"
             "geometry: {fluid: [{shape: box, min: %s, max: %s}]}\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, transport_velocity: {background_pressure: %g%s}, "
             "%s: {}}\n",
             dims, dims == 2 ? 0.04 : 0.05, lo, hi, dims == 2 ? "xy" : "xyz", lo, hi,
             background_pressure, extra ? extra : "", integrator);
    return test_load("transport-velocity", yaml, NULL, 0);
}

/* Sets the last step's size to dt as a step would (the term reads it in its
 * before_step hook), for an evaluation outside a step. */
static void tv_last_step(sluice_sim *sim, double dt)
{
    sim->dt = dt;
    sluice_instance *in = instance(sim, "transport_velocity");
    ck_assert_int_eq(in->component->before_step(in->state, &in->host), SLUICE_OK);
}

/* The largest |du| the term can give at this step: dt p_b / (rho h) times
 * the kernel's largest |grad W| h^(d+1) (order 1), for the scale of the
 * round-off bounds. */
static double tv_scale(sluice_sim *sim, double pb)
{
    const sluice_view *v = sluice_sim_view(sim);
    const double h = (double)v->smoothing_length;
    return sim->dt * pb / (1000 * h);
}

/* du_i by brute force over every particle (minimum image in the periodic
 * box): -dt (p_b / m_i) sum_j (V_i^2 + V_j^2) F(r_ij) r_ij. */
static void tv_brute_force(sluice_sim *sim, double pb, sluice_index i, const double box[3],
                           double du[3])
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint32_t dims = v->dimensions;
    const sluice_real *mass = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    const double support = (double)sim->support, Vi = (double)mass[i] / (double)rho[i];
    double s[3] = {0, 0, 0};
    for (sluice_index j = 0; j < v->count; j++) {
        if (j == i)
            continue;
        double r[3] = {0, 0, 0}, r2 = 0;
        for (uint32_t d = 0; d < dims; d++) {
            r[d] = (double)v->position[d][i] - (double)v->position[d][j];
            r[d] -= box[d] * round(r[d] / box[d]);
            r2 += r[d] * r[d];
        }
        if (!(r2 < support * support))
            continue;
        double f;
        kernel_wf(sim, sqrt(r2), &f);
        const double Vj = (double)mass[j] / (double)rho[j];
        for (uint32_t d = 0; d < dims; d++)
            s[d] += (Vi * Vi + Vj * Vj) * f * r[d];
    }
    for (uint32_t d = 0; d < dims; d++)
        du[d] = -sim->dt * pb / (double)mass[i] * s[d];
}

/* On a disordered periodic set (positions +-0.2 dx, densities +-1 %) the
 * correction is the brute-force sum over every particle to round-off, and it
 * moves no momentum: (V_i^2 + V_j^2) is symmetric and grad_i W_ij
 * antisymmetric, so sum_i m_i du_i = 0. On the regular lattice at rest
 * density (complete support everywhere) it vanishes. */
static void tv_sums(int dims)
{
    const double pb = 1000, dt = 1e-4;
    const double box[3] = {dims == 2 ? 0.8 : 0.5, dims == 2 ? 0.8 : 0.5, 0.5};
    for (int disordered = 0; disordered <= 1; disordered++) {
        /* min_kernel_sum 0: on the disordered set some Shepard sums are
         * below the default 0.9, which would leave those particles out */
        sluice_sim *sim = tv_periodic(dims, pb, ", min_kernel_sum: 0", "symplectic");
        if (disordered)
            disorder(sim, 0.2, 0.01);
        tv_last_step(sim, dt);
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *mass = test_column(sim, "mass", 0);
        const sluice_real *du[3];
        for (int d = 0; d < dims; d++)
            du[d] = test_column(sim, "transport_velocity_correction", (uint32_t)d);
        const double scale = tv_scale(sim, pb);
        double worst = 0, largest = 0, momentum[3] = {0, 0, 0}, moved = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            double expected[3];
            tv_brute_force(sim, pb, i, box, expected);
            for (int d = 0; d < dims; d++) {
                ck_assert_msg(isfinite(du[d][i]), "non-finite correction");
                worst = fmax(worst, fabs((double)du[d][i] - expected[d]));
                largest = fmax(largest, fabs((double)du[d][i]));
                momentum[d] += (double)mass[i] * (double)du[d][i];
                moved += (double)mass[i] * fabs((double)du[d][i]);
            }
        }
        fprintf(stderr,
                "transport_velocity %dD, %s: %u particles, max |du| %.3g m/s (scale dt p_b / "
                "(rho h) = %.3g), max difference from the brute-force sum %.3g, "
                "|sum m du| = %.3g of sum m |du| = %.3g\n",
                dims, disordered ? "disordered" : "regular lattice", v->count, largest, scale,
                worst, sqrt(momentum[0] * momentum[0] + momentum[1] * momentum[1] +
                            momentum[2] * momentum[2]),
                moved);
        /* sums of ~50 terms of size scale: round-off 1e-13 of the scale */
        ck_assert_msg(worst <= 1e-12 * scale, "differs from the brute-force sum by %g", worst);
        if (disordered) {
            ck_assert_msg(largest > 1e-3 * scale, "no correction on a disordered set");
            for (int d = 0; d < dims; d++)
                ck_assert_msg(fabs(momentum[d]) <= 1e-12 * moved, "momentum %g of %g moved",
                              momentum[d], moved);
        } else {
            ck_assert_msg(largest <= 1e-12 * scale, "regular lattice corrected by %g m/s",
                          largest);
        }
        sluice_sim_free(sim);
    }
}

START_TEST(tv_sums_2d) { tv_sums(2); }
END_TEST
START_TEST(tv_sums_3d) { tv_sums(3); }
END_TEST

/* sum_j w_j W_ij over every particle j of the periodic 0.8 m box, i
 * included, by brute force: w = m (volume 0, the summation density) or
 * V = m / rho (volume 1, the Shepard sum). */
static void periodic_kernel_sums(sluice_sim *sim, int volume, double *out)
{
    const sluice_view *v = sluice_sim_view(sim);
    const double box = 0.8, support = (double)sim->support;
    const sluice_real *mass = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < v->count; i++) {
        double sum = 0;
        for (sluice_index j = 0; j < v->count; j++) {
            double r2 = 0;
            for (uint32_t d = 0; d < 2; d++) {
                double r = (double)v->position[d][i] - (double)v->position[d][j];
                r -= box * round(r / box);
                r2 += r * r;
            }
            if (r2 < support * support)
                sum += (double)mass[j] / (volume ? (double)rho[j] : 1) *
                       kernel_wf(sim, sqrt(r2), NULL);
        }
        out[i] = sum;
    }
}

static void summation_density(sluice_sim *sim, double *out)
{
    periodic_kernel_sums(sim, 0, out);
}

/* The spread of the Shepard sum sum_j V_j W_ij (1 on a regular lattice) */
static double shepard_spread(sluice_sim *sim)
{
    const sluice_index n = sluice_sim_view(sim)->count;
    double *shepard = malloc(n * sizeof *shepard);
    ck_assert_ptr_nonnull(shepard);
    periodic_kernel_sums(sim, 1, shepard);
    double sum = 0, sum2 = 0;
    for (sluice_index i = 0; i < n; i++) {
        sum += shepard[i];
        sum2 += shepard[i] * shepard[i];
    }
    free(shepard);
    const double mean = sum / n;
    return sqrt(fmax(sum2 / n - mean * mean, 0));
}

/* What the term is for: particles at rest on a disordered set (+-0.25 dx)
 * and moved by it alone relax towards a regular distribution. The spread
 * of the Shepard sum falls at every 50 steps and to a fifth of its start
 * in 1000 steps. The shift of a step is dt^2 p_b / rho times a sum of
 * order 1/h: with p_b = 20 kPa, dt = 1 ms it is 0.015 of the spacing per
 * unit of disorder, so 1000 steps relax it many times over. With symplectic
 * (two evaluations a step, the second after the core has chosen the step)
 * and with verlet (one evaluation, before it: the term then works with the
 * last step's size; it once read the current one there, 0, and did
 * nothing). */
static void tv_relaxes(const char *integrator)
{
    sluice_sim *sim = tv_periodic(2, 20000, NULL, integrator);
    rng = 11;
    disorder(sim, 0.25, 0);
    const double start = shepard_spread(sim);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    double previous = start;
    for (int block = 1; block <= 20; block++) {
        for (int s = 0; s < 50; s++)
            ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        const double spread = shepard_spread(sim);
        fprintf(stderr,
                "transport_velocity relaxation (%s): step %d, Shepard spread %.4g (start %.4g)\n",
                integrator, block * 50, spread, start);
        ck_assert_msg(spread < previous, "spread %g after %d steps, %g before", spread,
                      block * 50, previous);
        previous = spread;
    }
    ck_assert_msg(previous < 0.2 * start, "spread %g, start %g", previous, start);
    /* at rest: the velocity field is untouched */
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *u = test_column(sim, "velocity", 0), *w = test_column(sim, "velocity", 1);
    for (sluice_index i = 0; i < v->count; i++)
        ck_assert(u[i] == 0 && w[i] == 0);
    sluice_sim_free(sim);
}

/* continuity with transport_velocity: particles at rest moved by the
 * transport velocity alone (p_b = 20 kPa, dt = 1 ms, 200 steps, symplectic,
 * continuity's mass form) change their summation density, and the
 * continuity density follows: form mass with v + du is the time derivative
 * of the summation density along the paths, so the two changes differ by
 * the time integration's error only (second order: below 2 % of the
 * change). Without the option the continuity density does not move at all
 * (v = 0), whatever the particles do. */
START_TEST(tv_continuity_follows_the_shift)
{
    for (int transport = 1; transport >= 0; transport--) {
        char yaml[1024];
        snprintf(yaml, sizeof yaml,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.04, smoothing_length_ratio: 1.3}\n"
                 "time: {end: 10.0, max_step: 0.001}\n"
                 "domain: {min: [0, 0], max: [0.8, 0.8], periodic: xy}\n"
                 "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.8, 0.8]}]}\n"
                 "initial: {density: rest}\n"
                 "plugins: {wendland_c2: {}, continuity: {transport_velocity: %s}, "
                 "transport_velocity: {background_pressure: 20000}, symplectic: {}}\n",
                 transport ? "true" : "false");
        sluice_sim *sim = test_load("transport-continuity", yaml, NULL, 0);
        rng = 11;
        disorder(sim, 0.25, 0);
        const sluice_index n = sluice_sim_view(sim)->count;
        double *sum0 = malloc(n * sizeof *sum0), *sum1 = malloc(n * sizeof *sum1);
        double *rho0 = malloc(n * sizeof *rho0);
        sluice_id *id0 = malloc(n * sizeof *id0);
        ck_assert(sum0 && sum1 && rho0 && id0);
        summation_density(sim, sum0);
        const sluice_real *rho = test_column(sim, "density", 0);
        for (sluice_index i = 0; i < n; i++) {
            rho0[i] = (double)rho[i];
            id0[i] = sluice_sim_view(sim)->id[i];
        }
        ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
        for (int k = 0; k < 200; k++)
            ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        /* the neighbour search sorts the particles by cell: matched by id */
        const sluice_view *v = sluice_sim_view(sim);
        ck_assert_uint_eq(v->count, n);
        summation_density(sim, sum1);
        rho = test_column(sim, "density", 0);
        double change = 0, miss = 0;
        for (sluice_index i = 0; i < n; i++) {
            sluice_index k = 0;
            while (k < n && id0[k] != v->id[i])
                k++;
            ck_assert(k < n);
            const double ds = sum1[i] - sum0[k], dc = (double)rho[i] - rho0[k];
            change += ds * ds;
            miss += (dc - ds) * (dc - ds);
        }
        change = sqrt(change / n);
        miss = sqrt(miss / n);
        fprintf(stderr,
                "continuity transport_velocity %s: rms change of the summation density %.4g "
                "kg/m^3, of the continuity density minus it %.4g\n",
                transport ? "true" : "false", change, miss);
        ck_assert_msg(change > 1, "the shift changed the summation density by %g only", change);
        if (transport)
            ck_assert_msg(miss <= 0.02 * change, "continuity misses the change by %g of %g",
                          miss, change);
        else
            ck_assert_msg(miss >= 0.9 * change, "without the option: %g of %g", miss, change);
        free(sum0);
        free(sum1);
        free(rho0);
        free(id0);
        sluice_sim_free(sim);
    }
}
END_TEST

START_TEST(tv_relaxes_a_disordered_set)
{
    tv_relaxes("symplectic");
    tv_relaxes("verlet");
}
END_TEST

/* A free surface: a block of fluid 0.4 m x 0.2 m in an open domain. Its
 * surface particles have an incomplete support and the one-sided sum would
 * push them out; below min_kernel_sum (0.9) they are not moved (du = 0
 * exactly), while with min_kernel_sum = 0 the top row is pushed outwards. */
START_TEST(tv_free_surface_left_alone)
{
    for (int guard = 1; guard >= 0; guard--) {
        char yaml[1024];
        snprintf(yaml, sizeof yaml,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.02, smoothing_length_ratio: 1.3}\n"
                 "time: {end: 1.0, max_step: 0.001}\n"
                 "domain: {min: [-0.2, -0.2], max: [0.6, 0.4]}\n"
                 "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.4, 0.2]}]}\n"
                 "initial: {density: rest}\n"
                 "plugins: {wendland_c2: {}, transport_velocity: {background_pressure: 1000%s}, "
                 "symplectic: {}}\n",
                 guard ? "" : ", min_kernel_sum: 0");
        sluice_sim *sim = test_load("transport-velocity-surface", yaml, NULL, 0);
        tv_last_step(sim, 1e-4);
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *duy = test_column(sim, "transport_velocity_correction", 1);
        const sluice_real *dux = test_column(sim, "transport_velocity_correction", 0);
        const double scale = tv_scale(sim, 1000), dx = 0.02;
        int top = 0, inner = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            const double x = v->position[0][i], y = v->position[1][i];
            const int surface = y > 0.2 - dx || y < dx || x < dx || x > 0.4 - dx;
            const int deep = y > 3 * dx && y < 0.2 - 3 * dx && x > 3 * dx && x < 0.4 - 3 * dx;
            if (deep) {
                /* complete support on the regular lattice: no correction */
                ck_assert_msg(fabs(dux[i]) <= 1e-12 * scale && fabs(duy[i]) <= 1e-12 * scale,
                              "interior particle corrected by (%g, %g)", dux[i], duy[i]);
                inner++;
            }
            if (surface && guard)
                ck_assert_msg(dux[i] == 0 && duy[i] == 0, "surface particle at (%g, %g) moved",
                              x, y);
            if (y > 0.2 - dx && x > 3 * dx && x < 0.4 - 3 * dx) {
                if (!guard)
                    ck_assert_msg(duy[i] > 0.01 * scale, "top particle: du_y = %g", duy[i]);
                top++;
            }
        }
        ck_assert_int_gt(inner, 0);
        ck_assert_int_gt(top, 0);
        sluice_sim_free(sim);
    }
}
END_TEST

START_TEST(tv_refusals)
{
    const char *base = "dimensions: 2\n"
                       "particles: {spacing: 0.02}\n"
                       "time: {end: 1.0, max_step: 0.001}\n"
                       "domain: {min: [-0.2, -0.2], max: [0.6, 0.4]}\n"
                       "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.4, 0.2]}]}\n"
                       "plugins: {wendland_c2: {}, symplectic: {}, transport_velocity: ";
    const char *cases[][2] = {
        {"{background_pressure: 0}}\n", "background_pressure"},
        {"{background_pressure: -10}}\n", "background_pressure"},
        {"{}}\n", "background_pressure"},
        {"{background_pressure: 100, min_kernel_sum: 1.5}}\n", "min_kernel_sum"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char yaml[1024];
        snprintf(yaml, sizeof yaml, "%s%s", base, cases[k][0]);
        test_load_refused("transport-velocity-refused", yaml, cases[k][1]);
    }
}
END_TEST

/* ----------------------------------------------------- kernel_correction -- */

/* Smallest eigenvalue of a symmetric d x d matrix (cyclic Jacobi). */
static double smallest_eigenvalue(int d, const double m[3][3])
{
    double a[3][3];
    memcpy(a, m, sizeof a);
    for (int sweep = 0; sweep < 50; sweep++)
        for (int p = 0; p < d; p++)
            for (int q = p + 1; q < d; q++) {
                if (fabs(a[p][q]) < 1e-300)
                    continue;
                double th = (a[q][q] - a[p][p]) / (2 * a[p][q]);
                double t = (th >= 0 ? 1 : -1) / (fabs(th) + sqrt(th * th + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < d; k++) {
                    double kp = a[k][p], kq = a[k][q];
                    a[k][p] = c * kp - s * kq;
                    a[k][q] = s * kp + c * kq;
                }
                for (int k = 0; k < d; k++) {
                    double pk = a[p][k], qk = a[q][k];
                    a[p][k] = c * pk - s * qk;
                    a[q][k] = s * pk + c * qk;
                }
            }
    double low = a[0][0];
    for (int k = 1; k < d; k++)
        low = a[k][k] < low ? a[k][k] : low;
    return low;
}

/* The moment matrix M_i = sum_j V_j grad_i W_ij (x) (x_j - x_i), by brute force. */
static void moment(sluice_sim *sim, sluice_index i, double mm[3][3])
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint32_t dims = v->dimensions;
    const sluice_real *mass = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    const double support = (double)sim->support;
    memset(mm, 0, 9 * sizeof(double));
    for (sluice_index j = 0; j < v->count; j++) {
        if (j == i)
            continue;
        double r[3] = {0, 0, 0}, r2 = 0;
        for (uint32_t d = 0; d < dims; d++) {
            r[d] = (double)v->position[d][i] - (double)v->position[d][j];
            r2 += r[d] * r[d];
        }
        if (!(r2 < support * support))
            continue;
        double f;
        kernel_wf(sim, sqrt(r2), &f);
        for (uint32_t a = 0; a < dims; a++)
            for (uint32_t b = 0; b < dims; b++)
                mm[a][b] += (double)mass[j] / (double)rho[j] * r[a] * f * -r[b];
    }
}

/* Renormalised (or, with plain, uncorrected) gradient of f = c + b.x at i:
 * sum_j V_j (f_j - f_i) L (r_ij F_ij). */
static void linear_gradient(sluice_sim *sim, sluice_index i, const double *b, int plain,
                            double *g)
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint32_t dims = v->dimensions;
    const sluice_real *mass = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    const double support = (double)sim->support, c = 2.5;
    double L[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (!plain)
        for (uint32_t a = 0; a < dims; a++)
            for (uint32_t e = 0; e < dims; e++)
                L[a][e] = test_column(sim, "kernel_correction", a * dims + e)[i];
    double fi = c;
    for (uint32_t d = 0; d < dims; d++)
        fi += b[d] * (double)v->position[d][i];
    double raw[3] = {0, 0, 0};
    for (sluice_index j = 0; j < v->count; j++) {
        if (j == i)
            continue;
        double r[3] = {0, 0, 0}, r2 = 0, fj = c;
        for (uint32_t d = 0; d < dims; d++) {
            r[d] = (double)v->position[d][i] - (double)v->position[d][j];
            r2 += r[d] * r[d];
            fj += b[d] * (double)v->position[d][j];
        }
        if (!(r2 < support * support))
            continue;
        double f;
        kernel_wf(sim, sqrt(r2), &f);
        for (uint32_t d = 0; d < dims; d++)
            raw[d] += (double)mass[j] / (double)rho[j] * (fj - fi) * r[d] * f;
    }
    for (uint32_t a = 0; a < dims; a++) {
        g[a] = 0;
        for (uint32_t e = 0; e < dims; e++)
            g[a] += L[a][e] * raw[e];
    }
}

static sluice_sim *kc_sim(const char *tag, int dims, const char *fluid, const char *params)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: %d\n"
             "particles: {spacing: 0.05, smoothing_length_ratio: 1.3}\n"
             "time: {end: 1.0, max_step: 0.001}\n"
             "domain: {min: %s, max: %s}\n"
             "geometry: {fluid: [%s]}\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, kernel_correction: {%s}, symplectic: {}}\n",
             dims, dims == 2 ? "[-1, -1]" : "[-1, -1, -1]", dims == 2 ? "[2, 2]" : "[2, 2, 2]",
             fluid, params);
    return test_load(tag, yaml, NULL, 0);
}

/* Inverse of a symmetric positive-definite d x d matrix (Gauss-Jordan). */
static void invert(int d, const double m[3][3], double out[3][3])
{
    double a[3][6];
    for (int r = 0; r < d; r++)
        for (int c = 0; c < 2 * d; c++)
            a[r][c] = c < d ? m[r][c] : (c - d == r);
    for (int c = 0; c < d; c++) {
        int pivot = c;
        for (int r = c + 1; r < d; r++)
            if (fabs(a[r][c]) > fabs(a[pivot][c]))
                pivot = r;
        for (int k = 0; k < 2 * d; k++) {
            double t = a[c][k];
            a[c][k] = a[pivot][k];
            a[pivot][k] = t;
        }
        double inv = 1 / a[c][c];
        for (int k = 0; k < 2 * d; k++)
            a[c][k] *= inv;
        for (int r = 0; r < d; r++)
            if (r != c) {
                double f = a[r][c];
                for (int k = 0; k < 2 * d; k++)
                    a[r][k] -= f * a[c][k];
            }
    }
    for (int r = 0; r < d; r++)
        for (int c = 0; c < d; c++)
            out[r][c] = a[r][d + c];
}

/* Linear fields on a lattice disordered by up to 0.2 dx with 1 % density
 * noise. Every particle's L is checked against the rule of the plugin's
 * documentation, L = s M^-1 + (1 - s) I with s from the smallest eigenvalue
 * of a brute-force M; where s = 1 (all interior particles) the renormalised
 * gradient is exact to round-off, and the plain gradient is not. With the
 * default thresholds (0.05, 0.15) every particle of a box is renormalised
 * fully; thresholds (0.3, 0.6) put the free-surface particles (lambda ~ 0.5)
 * in the blend and the corners (lambda ~ 0.25) at the identity. */
static void kc_linear(int dims, double low, double high)
{
    const char *fluid = dims == 2 ? "{shape: box, min: [0, 0], max: [1, 1]}"
                                  : "{shape: box, min: [0, 0, 0], max: [0.5, 0.5, 0.5]}";
    char params[128];
    snprintf(params, sizeof params, "singular_below: %g, regular_above: %g", low, high);
    sluice_sim *sim = kc_sim("kc", dims, fluid, params);
    disorder(sim, 0.2, 0.01);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const double b[3] = {1.7, -0.6, 2.3};
    const double length = dims == 2 ? 1.0 : 0.5, margin = (double)sim->support + 0.2 * 0.05;
    double worst = 0, worst_plain_interior = 0, worst_all = 0, worst_rule = 0;
    double lambda_least = INFINITY;
    int interior = 0, exact = 0, blended = 0, identity = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        double mm[3][3], inverse[3][3], g[3];
        moment(sim, i, mm);
        double lambda = smallest_eigenvalue(dims, mm);
        lambda_least = lambda < lambda_least ? lambda : lambda_least;
        /* L from the documented rule */
        double t = (lambda - low) / (high - low);
        double w = t <= 0 ? 0 : t >= 1 ? 1 : t * t * (3 - 2 * t);
        if (w > 0)
            invert(dims, mm, inverse);
        for (int a = 0; a < dims; a++)
            for (int e = 0; e < dims; e++) {
                double expected = (w > 0 ? w * inverse[a][e] : 0) + (1 - w) * (a == e);
                double l = test_column(sim, "kernel_correction", (uint32_t)(a * dims + e))[i];
                /* M is well conditioned where w > 0 (lambda > low): round-off */
                double err = fabs(l - expected) / (1 + fabs(expected));
                worst_rule = err > worst_rule ? err : worst_rule;
                ck_assert_msg(err <= 1e-12, "L[%d][%d] = %.17g, rule %.17g (lambda %g)", a, e, l,
                              expected, lambda);
            }
        int inside = 1;
        for (int d = 0; d < dims; d++)
            inside &= v->position[d][i] > margin && v->position[d][i] < length - margin;
        linear_gradient(sim, i, b, 0, g);
        double err = 0, nb = 0;
        for (int d = 0; d < dims; d++) {
            err += (g[d] - b[d]) * (g[d] - b[d]);
            nb += b[d] * b[d];
        }
        err = sqrt(err / nb);
        if (w == 1) {
            exact++;
            worst_all = err > worst_all ? err : worst_all;
        } else if (w == 0) {
            identity++;
        } else {
            blended++;
        }
        ck_assert_msg(!inside || w == 1, "interior particle with lambda_min = %g", lambda);
        if (inside) {
            interior++;
            worst = err > worst ? err : worst;
            linear_gradient(sim, i, b, 1, g);
            double plain = 0;
            for (int d = 0; d < dims; d++)
                plain += (g[d] - b[d]) * (g[d] - b[d]);
            plain = sqrt(plain / nb);
            worst_plain_interior = plain > worst_plain_interior ? plain : worst_plain_interior;
        }
    }
    fprintf(stderr,
            "kernel_correction %dD (thresholds %g, %g), %u particles disordered by 0.2 dx: %d "
            "interior, max relative gradient error %.3g (uncorrected %.3g); %d with L = M^-1 (max "
            "error %.3g), %d blended, %d identity; max |L - rule| %.3g; smallest lambda_min "
            "%.3f\n",
            dims, low, high, v->count, interior, worst, worst_plain_interior, exact, worst_all,
            blended, identity, worst_rule, lambda_least);
    ck_assert_int_gt(interior, dims == 2 ? 100 : 60);
    ck_assert_msg(worst <= 1e-10, "renormalised gradient error %g", worst);
    ck_assert_msg(worst_all <= 1e-10, "renormalised gradient error %g (boundary)", worst_all);
    ck_assert_msg(worst_plain_interior > 1e-3,
                  "the uncorrected gradient is already exact (%g): the test proves nothing",
                  worst_plain_interior);
    if (low >= 0.3)
        ck_assert_msg(blended > 0 && identity > 0, "the blend was not exercised");
    sluice_sim_free(sim);
}

START_TEST(kc_linear_2d) { kc_linear(2, 0.05, 0.15); }
END_TEST
START_TEST(kc_linear_3d) { kc_linear(3, 0.05, 0.15); }
END_TEST
START_TEST(kc_blend_2d) { kc_linear(2, 0.3, 0.6); }
END_TEST
START_TEST(kc_blend_3d) { kc_linear(3, 0.3, 0.6); }
END_TEST

/* Singular moment matrices give L = I exactly: a lone particle (M = 0), a
 * pair, three on a line (2D), four in a plane (3D), all farther than 2h from
 * each other. */
static void kc_singular(int dims)
{
    const char *fluid2 = "{shape: box, min: [0, 0], max: [0.05, 0.05]}, "
                         "{shape: box, min: [0.5, 0], max: [0.6, 0.05]}, "
                         "{shape: box, min: [1.0, 0], max: [1.15, 0.05]}, "
                         "{shape: box, min: [0, 0.5], max: [0.05, 0.65]}";
    const char *fluid3 = "{shape: box, min: [0, 0, 0], max: [0.05, 0.05, 0.05]}, "
                         "{shape: box, min: [0.5, 0, 0], max: [0.6, 0.05, 0.05]}, "
                         "{shape: box, min: [1.0, 0, 0], max: [1.1, 0.1, 0.05]}, "
                         "{shape: box, min: [0, 0.5, 0], max: [0.05, 0.65, 0.05]}";
    sluice_sim *sim = kc_sim("kc-singular", dims, dims == 2 ? fluid2 : fluid3, "");
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    ck_assert_int_eq(v->count, dims == 2 ? 9 : 10);
    for (sluice_index i = 0; i < v->count; i++) {
        double mm[3][3];
        moment(sim, i, mm);
        for (int a = 0; a < dims; a++)
            for (int e = 0; e < dims; e++) {
                double l = test_column(sim, "kernel_correction", (uint32_t)(a * dims + e))[i];
                ck_assert_msg(l == (a == e ? 1.0 : 0.0),
                              "%dD particle %u (lambda_min %g): L[%d][%d] = %g", dims, i,
                              smallest_eigenvalue(dims, mm), a, e, l);
            }
    }
    fprintf(stderr, "kernel_correction %dD: lone particle, pair, collinear/coplanar groups: "
                    "L = I exactly for all %u\n",
            dims, v->count);
    sluice_sim_free(sim);
}

START_TEST(kc_singular_2d) { kc_singular(2); }
END_TEST
START_TEST(kc_singular_3d) { kc_singular(3); }
END_TEST

/* ---------------------------------------------------- pressure_smoothing -- */

enum { RHO0 = 1000 };
static const double C0 = 30, G = 9.81;

static double tait_inverse(double p)
{
    const double B = C0 * C0 * RHO0 / 7;
    return RHO0 * pow(1 + p / B, 1.0 / 7);
}

static sluice_sim *tank(int dims, const char *tag, double *depth)
{
    char yaml[2048];
    const double H = dims == 2 ? 0.4 : 0.2;
    *depth = H;
    snprintf(yaml, sizeof yaml,
             "dimensions: %d\n"
             "particles: {spacing: 0.02, smoothing_length_ratio: 1.3, rest_density: %d}\n"
             "time: {end: 1.0, max_step: 0.001}\n"
             "domain: {min: %s, max: %s}\n"
             "geometry: {fluid: [{shape: box, min: %s, max: %s}]}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: %g}\n"
             "  gravity: {acceleration: %s}\n"
             "  pressure_smoothing: {every: 20}\n"
             "  symplectic: {}\n",
             dims, RHO0, dims == 2 ? "[-0.2, -0.2]" : "[-0.2, -0.2, -0.2]",
             dims == 2 ? "[1, 1]" : "[0.5, 0.5, 0.5]", dims == 2 ? "[0, 0]" : "[0, 0, 0]",
             dims == 2 ? "[0.6, 0.4]" : "[0.2, 0.2, 0.2]", C0,
             dims == 2 ? "[0, -9.81]" : "[0, 0, -9.81]");
    sluice_sim *sim = test_load(tag, yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK); /* settles the particle order */
    return sim;
}

/* Runs the smoothing hook as at step 20 (its period). */
static int smooth_now(sluice_sim *sim)
{
    sluice_instance *in = instance(sim, "pressure_smoothing");
    sim->step = 20;
    sluice_sim_refresh_view(sim);
    return in->component->after_step(in->state, &in->host);
}

static double total_mass(sluice_sim *sim)
{
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *m = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    double sum = 0;
    for (sluice_index i = 0; i < v->count; i++)
        sum += (double)m[i] / (double)rho[i] * (double)rho[i];
    return sum;
}

/* The exact hydrostatic state (the core's start: rho = EOS^-1(rho0 g (H - z)))
 * is a fixed point: p - p^h = 0 everywhere when eta = H, which the top
 * particle + dx/2 gives exactly on a flat lattice. */
static void ps_rest(int dims)
{
    double H;
    sluice_sim *sim = tank(dims, "ps-rest", &H);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_index n = v->count;
    double *before = malloc(n * sizeof *before), *p_before = malloc(n * sizeof *p_before);
    ck_assert_ptr_nonnull(before);
    ck_assert_ptr_nonnull(p_before);
    for (sluice_index i = 0; i < n; i++) {
        before[i] = test_column(sim, "density", 0)[i];
        p_before[i] = test_column(sim, "pressure", 0)[i];
    }
    double mass0 = total_mass(sim);
    ck_assert_int_eq(smooth_now(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    ck_assert_int_eq(v->count, n);
    double worst_rho = 0, worst_p = 0, worst_ph = 0;
    const double scale = RHO0 * G * H;
    for (sluice_index i = 0; i < n; i++) {
        double z = v->position[dims - 1][i];
        double ph = test_column(sim, "hydrostatic_pressure", 0)[i];
        worst_ph = fmax(worst_ph, fabs(ph - RHO0 * G * (H - z)));
        worst_rho = fmax(worst_rho, fabs(test_column(sim, "density", 0)[i] - before[i]));
        worst_p = fmax(worst_p, fabs(test_column(sim, "pressure", 0)[i] - p_before[i]));
    }
    double mass1 = total_mass(sim);
    fprintf(stderr,
            "pressure_smoothing %dD tank at rest (%u particles, H = %g m): max |p^h - rho0 g "
            "(H - z)| = %.3g Pa, max |drho| = %.3g kg/m^3, max |dp| = %.3g Pa (rho0 g H = %g Pa); "
            "sum V rho %.15g -> %.15g kg\n",
            dims, n, H, worst_ph, worst_rho, worst_p, scale, mass0, mass1);
    /* round-off of the EOS round trip (pow, B ((rho/rho0)^7 - 1)) and of
     * Shepard sums of ~30 terms: 1e-12 of the pressure scale */
    ck_assert_msg(worst_ph <= 1e-12 * scale, "free-surface estimate off by %g Pa", worst_ph);
    ck_assert_msg(worst_p <= 1e-12 * (scale + C0 * C0 * RHO0 / 7), "pressure changed by %g Pa",
                  worst_p);
    ck_assert_msg(worst_rho <= 1e-13 * RHO0, "density changed by %g", worst_rho);
    ck_assert(mass1 == mass0 || fabs(mass1 - mass0) <= 1e-14 * mass0);
    free(before);
    free(p_before);
    sluice_sim_free(sim);
}

START_TEST(ps_rest_2d) { ps_rest(2); }
END_TEST
START_TEST(ps_rest_3d) { ps_rest(3); }
END_TEST

/* A checkerboard p = rho0 g (H - y) + A s_i, s_i = (-1)^(k_x + k_y) on the
 * lattice indices. The filter output is compared with a brute-force Shepard
 * sum with the test's own p^h = rho0 g (H - y); the density written must be
 * the Tait inverse of it; and in the interior, where the support is full and
 * V_j is uniform up to e (the relative spread of V over the support), the
 * checkerboard is multiplied by the lattice factor
 *   f0 = (W(0) + sum_k s_k W(|k| dx)) / (W(0) + sum_k W(|k| dx))
 * (sums over the lattice offsets k != 0 within 2h), to within e (1 + |f0|) / (1 - e). */
START_TEST(ps_checkerboard)
{
    double H;
    sluice_sim *sim = tank(2, "ps-check", &H);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_index n = v->count;
    const double dx = (double)v->spacing, A = 100.0, scale = RHO0 * G * H;
    int *sign = malloc(n * sizeof *sign);
    ck_assert_ptr_nonnull(sign);
    sluice_real *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < n; i++) {
        long kx = lround(v->position[0][i] / dx - 0.5), ky = lround(v->position[1][i] / dx - 0.5);
        double s = (kx + ky) % 2 ? -1 : 1;
        rho[i] = (sluice_real)tait_inverse(RHO0 * G * (H - v->position[1][i]) + A * s);
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    /* state before: ids, positions, pressure, V */
    sluice_id *id = malloc(n * sizeof *id);
    double *p = malloc(n * sizeof *p), *vol = malloc(n * sizeof *vol);
    double *ref = malloc(n * sizeof *ref);
    ck_assert(id && p && vol && ref);
    double mass0 = total_mass(sim);
    for (sluice_index i = 0; i < n; i++) {
        long kx = lround(v->position[0][i] / dx - 0.5), ky = lround(v->position[1][i] / dx - 0.5);
        sign[i] = (kx + ky) % 2 ? -1 : 1;
        id[i] = v->id[i];
        p[i] = test_column(sim, "pressure", 0)[i];
        vol[i] = test_column(sim, "mass", 0)[i] / test_column(sim, "density", 0)[i];
        double noise = p[i] - RHO0 * G * (H - v->position[1][i]);
        ck_assert_msg(fabs(noise - A * sign[i]) < 1e-9 * scale, "set-up: p - p^h = %g", noise);
    }
    /* brute-force reference */
    const double support = (double)sim->support, w0 = kernel_wf(sim, 0, NULL);
    for (sluice_index i = 0; i < n; i++) {
        double num = vol[i] * w0 * (p[i] - RHO0 * G * (H - v->position[1][i]));
        double den = vol[i] * w0;
        for (sluice_index j = 0; j < n; j++) {
            if (j == i)
                continue;
            double rx = v->position[0][i] - v->position[0][j];
            double ry = v->position[1][i] - v->position[1][j];
            double r = sqrt(rx * rx + ry * ry);
            if (!(r < support))
                continue;
            double w = kernel_wf(sim, r, NULL);
            num += vol[j] * w * (p[j] - RHO0 * G * (H - v->position[1][j]));
            den += vol[j] * w;
        }
        ref[i] = RHO0 * G * (H - v->position[1][i]) + num / den;
    }
    /* the lattice factor */
    double top = w0, bottom = w0;
    for (int kx = -3; kx <= 3; kx++)
        for (int ky = -3; ky <= 3; ky++) {
            double r = dx * sqrt((double)(kx * kx + ky * ky));
            if ((kx || ky) && r < support) {
                double w = kernel_wf(sim, r, NULL);
                top += ((kx + ky) % 2 ? -1 : 1) * w;
                bottom += w;
            }
        }
    const double f0 = top / bottom;

    ck_assert_int_eq(smooth_now(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    ck_assert_int_eq(v->count, n);
    double worst_ref = 0, worst_eos = 0, ratio_lo = INFINITY, ratio_hi = -INFINITY, worst_dev = 0;
    int interior = 0;
    for (sluice_index i = 0; i < n; i++) {
        ck_assert_msg(v->id[i] == id[i], "particles were re-sorted");
        double smoothed = test_column(sim, "pressure", 0)[i];
        ck_assert(smoothed == test_column(sim, "smoothed_pressure", 0)[i]);
        worst_ref = fmax(worst_ref, fabs(smoothed - ref[i]));
        double expected_rho = tait_inverse(smoothed);
        worst_eos = fmax(worst_eos, fabs(test_column(sim, "density", 0)[i] - expected_rho));
        double x = v->position[0][i], y = v->position[1][i];
        if (x > support && x < 0.6 - support && y > support && y < H - support) {
            interior++;
            double ratio = (smoothed - RHO0 * G * (H - y)) / (A * sign[i]);
            /* spread of V over the support of i */
            double e = 0;
            for (sluice_index j = 0; j < n; j++) {
                double rx = x - v->position[0][j], ry = y - v->position[1][j];
                if (rx * rx + ry * ry < support * support)
                    e = fmax(e, fabs(vol[j] / vol[i] - 1));
            }
            double bound = e * (1 + fabs(f0)) / (1 - e);
            worst_dev = fmax(worst_dev, fabs(ratio - f0) / bound);
            ck_assert_msg(fabs(ratio - f0) <= bound, "checkerboard factor %g, lattice %g (+- %g)",
                          ratio, f0, bound);
            ratio_lo = fmin(ratio_lo, ratio);
            ratio_hi = fmax(ratio_hi, ratio);
        }
    }
    double mass1 = total_mass(sim);
    fprintf(stderr,
            "pressure_smoothing checkerboard A = %g Pa: lattice factor f0 = %.6f; interior (%d "
            "particles) measured %.6f .. %.6f (at most %.2f of the V-spread bound); max |p~ - "
            "brute force| = %.3g Pa; max |rho - EOS^-1(p~)| = %.3g kg/m^3; sum V rho %.15g -> "
            "%.15g kg\n",
            A, f0, interior, ratio_lo, ratio_hi, worst_dev, worst_ref, worst_eos, mass0, mass1);
    ck_assert_int_gt(interior, 100);
    ck_assert_msg(fabs(f0) < 0.5, "the filter must damp the checkerboard (f0 = %g)", f0);
    /* Shepard sums of ~20 terms of size rho0 g H: 1e-12 of the scale */
    ck_assert_msg(worst_ref <= 1e-12 * scale, "smoothed pressure off the reference by %g",
                  worst_ref);
    /* pow round trip: a few ulps of rho0 */
    ck_assert_msg(worst_eos <= 1e-12 * RHO0, "density not the EOS inverse (%g)", worst_eos);
    ck_assert(fabs(mass1 - mass0) <= 1e-14 * mass0);
    /* the smoothed pressure persists: the next evaluation gives it back */
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    double worst_back = 0;
    for (sluice_index i = 0; i < n; i++)
        worst_back = fmax(worst_back, fabs(test_column(sim, "pressure", 0)[i] -
                                           test_column(sim, "smoothed_pressure", 0)[i]));
    fprintf(stderr, "pressure_smoothing: next evaluation's pressure differs from p~ by %.3g Pa\n",
            worst_back);
    ck_assert_msg(worst_back <= 1e-9 * scale, "pressure did not persist (%g Pa)", worst_back);
    free(sign);
    free(id);
    free(p);
    free(vol);
    free(ref);
    sluice_sim_free(sim);
}
END_TEST

/* The masses are never touched. */
START_TEST(ps_masses_untouched)
{
    double H;
    sluice_sim *sim = tank(2, "ps-mass", &H);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < v->count; i++)
        rho[i] *= (sluice_real)(1 + 0.002 * (uniform() - 0.5));
    const sluice_index n = v->count;
    double *m = malloc(n * sizeof *m);
    ck_assert_ptr_nonnull(m);
    for (sluice_index i = 0; i < n; i++)
        m[i] = test_column(sim, "mass", 0)[i];
    ck_assert_int_eq(smooth_now(sim), SLUICE_OK);
    for (sluice_index i = 0; i < n; i++)
        ck_assert(test_column(sim, "mass", 0)[i] == m[i]);
    free(m);
    sluice_sim_free(sim);
}
END_TEST

/* ------------------------------------------- api->evaluation->density_from_pressure -- */

/* With no equation of state, the API call is refused with a message: at load
 * (pressure_smoothing checks in bind with n = 0) and during a run (the EOS
 * callback removed after loading). */
START_TEST(density_from_pressure_without_eos)
{
    const char *yaml = "dimensions: 2\n"
                       "particles: {spacing: 0.05}\n"
                       "time: {end: 1.0, max_step: 0.001}\n"
                       "domain: {min: [-1, -1], max: [2, 2]}\n"
                       "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]}\n"
                       "initial: {density: rest}\n"
                       "plugins: {wendland_c2: {}, gravity: {}, pressure_smoothing: {}, "
                       "symplectic: {}}\n";
    char *dir = test_scratch("no-eos");
    char *path = test_write_file(dir, "scene.yaml", yaml);
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {0};
    sluice_sim *sim = sluice_sim_load(path, &options, diag);
    ck_assert_ptr_null(sim);
    int found = 0;
    for (size_t i = 0; i < sluice_diag_count(diag); i++) {
        fprintf(stderr, "refused at load: %s\n", sluice_diag_message(diag, i));
        found |= strstr(sluice_diag_message(diag, i), "pressure_smoothing") &&
                 strstr(sluice_diag_message(diag, i), "no loaded plugin provides an equation of "
                                                      "state");
    }
    ck_assert_msg(found, "no message naming the missing equation of state");
    sluice_diag_destroy(diag);
    free(path);
    free(dir);

    /* during a run */
    sim = tank(2, "ps-no-eos", &(double){0});
    sluice_instance *tait = instance(sim, "tait");
    const sluice_component *original = tait->component;
    sluice_component without = *original;
    without.density_from_pressure = NULL;
    tait->component = &without;
    ck_assert_int_eq(smooth_now(sim), SLUICE_ERROR);
    const char *failure = sluice_sim_failure(sim);
    fprintf(stderr, "refused during the run: %s\n", failure);
    ck_assert_msg(strstr(failure, "pressure_smoothing") &&
                      strstr(failure, "no loaded plugin provides an equation of state"),
                  "unexpected message '%s'", failure);
    tait->component = original;
    sluice_sim_free(sim);
}
END_TEST

/* --------------------------------------------------------- all together -- */

/* A water column at rest in a dbc tank with all three terms (seed 004's set:
 * Shepard XSPH, renormalisation matrix, pressure smoothing every 10 steps)
 * and the symplectic integrator, 60 steps (6 smoothings). The walls start at
 * the rest density under a hydrostatic column, a density mismatch of up to
 * rho0 g H / c0^2 that sets off an acoustic transient of velocity scale
 * c0 (g H / c0^2) = g H / c0: the fluid must stay below it. The same scene
 * without the three terms is run for comparison. */
static double tank_run(const char *label, const char *extra)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
             "time: {end: 10.0}\n"
             "domain: {min: [-0.2, -0.2], max: [1, 1]}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [0.4, 0.3]}]\n"
             "  walls: [{shape: tank, min: [0, 0], max: [0.4, 0.6]}]\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 30}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  artificial_viscosity: {alpha: 0.1}\n"
             "  gravity: {}\n"
             "  dbc: {}\n"
             "%s"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             extra);
    sluice_sim *sim = test_load("tank", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    for (int s = 0; s < 60; s++)
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step %d: %s", s,
                      sluice_sim_failure(sim));
    const sluice_view *v = sluice_sim_view(sim);
    double vmax = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        double s2 = 0;
        for (uint32_t d = 0; d < 2; d++) {
            double u = test_column(sim, "velocity", d)[i];
            ck_assert(isfinite(u));
            s2 += u * u;
        }
        vmax = fmax(vmax, sqrt(s2));
    }
    fprintf(stderr, "tank at rest, 60 steps to t = %.4g s, %s: max |v| = %.3g m/s\n",
            sluice_sim_time(sim), label, vmax);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return vmax;
}

START_TEST(all_three_in_a_tank)
{
    const double scale = 9.81 * 0.3 / 30; /* g H / c0 */
    double base = tank_run("without the three terms", "");
    double all = tank_run("with xsph, kernel_correction, pressure_smoothing",
                          "  xsph: {form: velocity_smoothing}\n  kernel_correction: {}\n"
                          "  pressure_smoothing: {every: 10}\n");
    fprintf(stderr, "tank at rest: max |v| %.3g m/s with the three terms, %.3g without; g H / "
                    "c0 = %.3g m/s\n",
            all, base, scale);
    ck_assert_msg(all < scale, "max |v| = %g m/s above the acoustic scale %g", all, scale);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("corrections");
    TCase *x = tcase_create("xsph");
    tcase_add_test(x, xsph_uniform_position_2d);
    tcase_add_test(x, xsph_uniform_smoothing_2d);
    tcase_add_test(x, xsph_uniform_position_3d);
    tcase_add_test(x, xsph_uniform_smoothing_3d);
    tcase_add_test(x, xsph_three_position);
    tcase_add_test(x, xsph_three_smoothing);
    tcase_add_test(x, xsph_three_position_default);
    tcase_add_test(x, xsph_three_smoothing_default);
    tcase_add_test(x, xsph_other_forms_coefficient_refused);
    tcase_add_test(x, xsph_momentum_position);
    suite_add_tcase(s, x);
    TCase *tv = tcase_create("transport_velocity");
    tcase_set_timeout(tv, 120);
    tcase_add_test(tv, tv_sums_2d);
    tcase_add_test(tv, tv_sums_3d);
    tcase_add_test(tv, tv_relaxes_a_disordered_set);
    tcase_add_test(tv, tv_continuity_follows_the_shift);
    tcase_add_test(tv, tv_free_surface_left_alone);
    tcase_add_test(tv, tv_refusals);
    suite_add_tcase(s, tv);
    TCase *k = tcase_create("kernel_correction");
    tcase_set_timeout(k, 120);
    tcase_add_test(k, kc_linear_2d);
    tcase_add_test(k, kc_linear_3d);
    tcase_add_test(k, kc_blend_2d);
    tcase_add_test(k, kc_blend_3d);
    tcase_add_test(k, kc_singular_2d);
    tcase_add_test(k, kc_singular_3d);
    suite_add_tcase(s, k);
    TCase *p = tcase_create("pressure_smoothing");
    tcase_set_timeout(p, 120);
    tcase_add_test(p, ps_rest_2d);
    tcase_add_test(p, ps_rest_3d);
    tcase_add_test(p, ps_checkerboard);
    tcase_add_test(p, ps_masses_untouched);
    tcase_add_test(p, density_from_pressure_without_eos);
    suite_add_tcase(s, p);
    TCase *a = tcase_create("together");
    tcase_set_timeout(a, 120);
    tcase_add_test(a, all_three_in_a_tank);
    suite_add_tcase(s, a);
    return test_run_suite(s);
}
