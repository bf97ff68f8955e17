/* Particle shifting (plugins/corrections/particle_shifting.c) and the
 * Taylor-Green vortex:
 *  - the correction equals a brute-force evaluation of du_i = -A h |v_i|
 *    sum_j V_j grad_i W_ij on a random periodic box;
 *  - a regular lattice in a periodic box is not shifted (grad C = 0), and
 *    neither is a fluid at rest (|v| = 0);
 *  - at a flat free surface the top row is not shifted, while the particles
 *    under it are. */
#include <math.h>

#include "sim_util.h"
/* Internal: calls the loaded kernel on its state; smoothing length and support (not in sim.h) */
#include "sim_internal.h"

static double uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

static double kernel_gradient_factor(sluice_sim *sim, double r2)
{
    const sluice_instance *k = &sim->instances[sim->kernel];
    sluice_real rr = (sluice_real)r2, r = 0, w = 0, ff = 0;
    k->component->kernel(k->state, 1, &rr, &r, &w, &ff);
    return (double)ff;
}

/* A periodic box [0, 1]^2 on a lattice of spacing dx: the kernel, Tait,
 * continuity, the pressure gradient, and `extra` plugins. */
static sluice_sim *periodic_box(const char *kernel, double dx, double h_ratio, double t_end,
                                const char *extra)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: %.17g, smoothing_length_ratio: %g}\n"
             "time: {end: %g}\n"
             "domain: {min: [0, 0], max: [1, 1], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 1]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  %s: {}\n"
             "  tait: {speed_of_sound: 10}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "%s"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dx, h_ratio, t_end, kernel, extra);
    return test_load("shifting-box", yaml, NULL, 0);
}

/* ------------------------------------------------------------- formula -- */

START_TEST(formula)
{
    sluice_sim *sim = periodic_box("wendland_c2", 0.04, 1.3, 1, "  particle_shifting: {}\n");
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_index n = v->count;
    uint64_t seed = 5;
    /* jitter the lattice by up to 0.2 dx and give random velocities */
    for (sluice_index i = 0; i < n; i++)
        for (int d = 0; d < 2; d++) {
            ((sluice_real *)v->position[d])[i] += (sluice_real)(0.008 * (uniform(&seed) - 0.5));
            test_column(sim, "velocity", (uint32_t)d)[i] = (sluice_real)(uniform(&seed) - 0.5);
        }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const sluice_real *rho = test_column(sim, "density", 0), *m = test_column(sim, "mass", 0);
    const sluice_real *u[2] = {test_column(sim, "velocity", 0), test_column(sim, "velocity", 1)};
    const sluice_real *du[2] = {test_column(sim, "transport_velocity_correction", 0),
                                test_column(sim, "transport_velocity_correction", 1)};
    const double h = (double)sim->smoothing_length, support = (double)sim->support;
    double worst = 0, scale = 0;
    for (sluice_index i = 0; i < n; i++) {
        double grad[2] = {0, 0}, div = 0;
        for (sluice_index j = 0; j < n; j++) {
            if (j == i)
                continue;
            double r[2], r2 = 0;
            for (int d = 0; d < 2; d++) {
                r[d] = (double)v->position[d][i] - (double)v->position[d][j];
                r[d] -= round(r[d]); /* minimum image in the unit box */
                r2 += r[d] * r[d];
            }
            if (r2 >= support * support)
                continue;
            const double c = (double)m[j] / (double)rho[j] * kernel_gradient_factor(sim, r2);
            grad[0] += c * r[0];
            grad[1] += c * r[1];
            div -= c * r2;
        }
        const double speed = hypot((double)u[0][i], (double)u[1][i]);
        const double shift[2] = {-2 * h * speed * grad[0], -2 * h * speed * grad[1]};
        /* no free surface in a periodic box: the plain form everywhere */
        ck_assert_msg(div > 1.5, "div r = %g inside a periodic box", div);
        for (int d = 0; d < 2; d++) {
            worst = fmax(worst, fabs(shift[d] - (double)du[d][i]));
            scale = fmax(scale, fabs(shift[d]));
        }
    }
    fprintf(stderr, "shifting: batch sums vs brute force over %u jittered particles: %.2e of "
                    "%.3e m/s\n",
            (unsigned)n, worst / scale, scale);
    ck_assert_msg(scale > 0 && worst <= 1e-12 * scale, "shift off by %g of %g", worst, scale);
    sluice_sim_free(sim);
}
END_TEST

/* A lattice moving uniformly is regular (grad C = 0 to round-off); a
 * jittered one at rest is not moved (|v| = 0). */
START_TEST(regular_or_at_rest)
{
    sluice_sim *sim = periodic_box("wendland_c2", 0.04, 1.3, 1, "  particle_shifting: {}\n");
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++)
        test_column(sim, "velocity", 0)[i] = 1;
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    double largest = 0;
    for (sluice_index i = 0; i < v->count; i++)
        for (uint32_t d = 0; d < 2; d++)
            largest = fmax(largest,
                           fabs((double)test_column(sim, "transport_velocity_correction", d)[i]));
    fprintf(stderr, "shifting: regular lattice at 1 m/s: largest shift velocity %.2e m/s\n",
            largest);
    ck_assert_msg(largest < 1e-12, "a regular lattice is shifted at %g m/s", largest);
    uint64_t seed = 9;
    for (sluice_index i = 0; i < v->count; i++) {
        test_column(sim, "velocity", 0)[i] = 0;
        ((sluice_real *)v->position[0])[i] += (sluice_real)(0.008 * (uniform(&seed) - 0.5));
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    for (sluice_index i = 0; i < v->count; i++)
        for (uint32_t d = 0; d < 2; d++)
            ck_assert(test_column(sim, "transport_velocity_correction", d)[i] == 0);
    sluice_sim_free(sim);
}
END_TEST

/* ---------------------------------------------------------- free surface -- */

/* A layer 0.4 m deep, periodic in x, no walls (the particles below y = 0.04
 * are its bed only as neighbours: the layer floats, nothing is stepped), all
 * moving at 1 m/s along x and jittered: the top row is at the surface. */
START_TEST(surface)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.04, smoothing_length_ratio: 1.3}\n"
             "time: {end: 1}\n"
             "domain: {min: [0, -0.5], max: [1, 1], periodic: x}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 0.4]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 10}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  particle_shifting: {}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n");
    sluice_sim *sim = test_load("shifting-surface", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    uint64_t seed = 3;
    for (sluice_index i = 0; i < v->count; i++) {
        test_column(sim, "velocity", 0)[i] = 1;
        ((sluice_real *)v->position[0])[i] += (sluice_real)(0.008 * (uniform(&seed) - 0.5));
        ((sluice_real *)v->position[1])[i] += (sluice_real)(0.004 * (uniform(&seed) - 0.5));
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    double top_normal = 0, top_tangential = 0, inner = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const double ux = test_column(sim, "transport_velocity_correction", 0)[i];
        const double uy = test_column(sim, "transport_velocity_correction", 1)[i];
        if (v->position[1][i] > 0.37) { /* the top row, at 0.38 m */
            top_normal = fmax(top_normal, fabs(uy));
            top_tangential = fmax(top_tangential, fabs(ux));
        } else if (v->position[1][i] > 0.1 && v->position[1][i] < 0.3) {
            inner = fmax(inner, hypot(ux, uy));
        }
    }
    fprintf(stderr, "shifting at a surface: top row: largest normal %.3e, tangential %.3e m/s; "
                    "inside: %.3e m/s\n",
            top_normal, top_tangential, inner);
    ck_assert_msg(inner > 0, "the inner particles are not shifted");
    ck_assert_msg(top_normal == 0 && top_tangential == 0, "the surface moves");
    sluice_sim_free(sim);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("shifting");
    TCase *f = tcase_create("shifting");
    tcase_add_test(f, formula);
    tcase_add_test(f, regular_or_at_rest);
    tcase_add_test(f, surface);
    suite_add_tcase(s, f);
    return test_run_suite(s);
}
