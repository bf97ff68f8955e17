/* Tests of the turbulence plugins (seed 004): velocity_gradient,
 * mixing_length, k_epsilon and turbulent_stress, loaded through the real core.
 *  - the velocity gradient of a linear field against the kernel's moment
 *    matrix computed here by brute force (renormalised: exact);
 *  - mixing length and eddy viscosity against the formula on a shear state
 *    with a wall below and a free surface above;
 *  - homogeneous decay of k and eps against the analytic solution, with the
 *    integrator's second order;
 *  - conservation of linear momentum by both forms of the turbulent stress;
 *  - the wall shear stress each form produces over dynamic-boundary walls;
 *  - a coarse turbulent open-channel flow: steady state, momentum balance and
 *    the log-law slope u* / kappa. */
#include <math.h>

#include "sim_util.h"
/* Internal: calls the loaded kernel on its state (not in sim.h) */
#include "sim_internal.h"

static uint64_t rng = 4004;
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

static int has_component(const char *name)
{
    char *out = NULL;
    char args[256];
    snprintf(args, sizeof args, "inspect %s", name);
    int rc = test_sluice(args, &out);
    int ok = rc == 0 && out && !strstr(out, "PLACEHOLDER") && !strstr(out, "no component");
    free(out);
    return ok;
}

/* ----------------------------------------------------- velocity gradient -- */

/* A block of fluid without walls, positions perturbed by up to 20 % of dx,
 * velocity v = A x. For every particle whose support lies inside the block,
 * G must equal A M_i, M_i,cb = -sum_j V_j r_ij,c r_ij,b F_ij computed here by
 * brute force (without renormalisation), or A itself (renormalised). */
static void check_linear_gradient(int dims, int renormalise)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: %d\n"
             "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
             "time: {end: 1.0}\n"
             "domain: {min: %s, max: %s}\n"
             "geometry: {fluid: [{shape: box, min: %s, max: %s}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "%s"
             "  velocity_gradient: {renormalise: %s}\n"
             "  mixing_length: {l_max: 0.1}\n"
             "  turbulent_stress: {}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dims, dims == 2 ? "[-1, -1]" : "[-1, -1, -1]", dims == 2 ? "[2, 2]" : "[2, 2, 2]",
             dims == 2 ? "[0, 0]" : "[0, 0, 0]", dims == 2 ? "[0.8, 0.8]" : "[0.5, 0.5, 0.5]",
             renormalise ? "  kernel_correction: {}\n" : "", renormalise ? "true" : "false");
    sluice_sim *sim = test_load("velocity-gradient", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const double A[3][3] = {{0.3, -1.7, 0.4}, {2.1, 0.5, -0.9}, {-0.6, 1.1, -0.8}};
    const double dx = 0.05;
    for (sluice_index i = 0; i < v->count; i++)
        for (int d = 0; d < dims; d++)
            test_column(sim, "position", (uint32_t)d)[i] +=
                (sluice_real)(0.2 * dx * (uniform() - 0.5));
    for (sluice_index i = 0; i < v->count; i++)
        for (int a = 0; a < dims; a++) {
            double value = 0;
            for (int b = 0; b < dims; b++)
                value += A[a][b] * test_column(sim, "position", (uint32_t)b)[i];
            test_column(sim, "velocity", (uint32_t)a)[i] = (sluice_real)value;
        }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const double support = 2 * (double)sim->smoothing_length;
    const double hi = dims == 2 ? 0.8 : 0.5;
    const sluice_real *m = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    double worst = 0, moment_error = 0;
    int checked = 0, surface = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        int inside = 1;
        for (int d = 0; d < dims; d++)
            inside &= v->position[d][i] > support + dx && v->position[d][i] < hi - support - dx;
        if (!inside && !renormalise)
            continue;
        double M[3][3] = {{0}};
        for (sluice_index j = 0; j < v->count; j++) {
            if (j == i)
                continue;
            double r[3] = {0, 0, 0}, r2 = 0;
            for (int d = 0; d < dims; d++) {
                r[d] = (double)v->position[d][i] - (double)v->position[d][j];
                r2 += r[d] * r[d];
            }
            if (r2 >= support * support)
                continue;
            double F;
            kernel_eval(sim, sqrt(r2), &F);
            for (int c = 0; c < dims; c++)
                for (int b = 0; b < dims; b++)
                    M[c][b] -= (double)m[j] / (double)rho[j] * r[c] * r[b] * F;
        }
        if (!inside) {
            /* renormalised: every particle whose M is regular (smallest
             * eigenvalue above kernel_correction's regular_above = 0.15, so that
             * L = M^-1 there: edges and corners of the block included) */
            double tr = M[0][0] + M[1][1], det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
            double lambda = 0.5 * tr - sqrt(fmax(0.25 * tr * tr - det, 0));
            if (dims != 2 || lambda < 0.15)
                continue;
            surface++;
        }
        for (int a = 0; a < dims; a++)
            for (int b = 0; b < dims; b++) {
                moment_error = fmax(moment_error, fabs(M[a][b] - (a == b)));
                double expected = 0;
                for (int c = 0; c < dims; c++)
                    expected += A[a][c] * (renormalise ? (c == b) : M[c][b]);
                double got = test_column(sim, "velocity_gradient", (uint32_t)(a * dims + b))[i];
                worst = fmax(worst, fabs(got - expected));
            }
        checked++;
    }
    fprintf(stderr,
            "velocity_gradient %dD renormalise=%d: %d particles (%d of them within 2h of the "
            "free surface), max |G - %s| = %.2e s^-1, max |M - I| = %.3f (|A| ~ 1 s^-1)\n",
            dims, renormalise, checked, surface, renormalise ? "A" : "A M", worst, moment_error);
    ck_assert_int_ge(checked, dims == 2 ? 50 : 8);
    if (renormalise)
        ck_assert_int_gt(surface, 100);
    /* both are sums of ~30-60 terms of size |A| V r^2 |F| ~ 1: round-off */
    ck_assert_msg(worst < 1e-12, "velocity gradient off by %g", worst);
    /* the check is not vacuous: the perturbed lattice's M differs from I */
    ck_assert_msg(moment_error > 1e-3, "M = I: the unrenormalised check would be vacuous");
    sluice_sim_free(sim);
}

START_TEST(gradient_linear_2d) { check_linear_gradient(2, 0); }
END_TEST
START_TEST(gradient_linear_3d) { check_linear_gradient(3, 0); }
END_TEST
START_TEST(gradient_linear_renormalised_2d)
{
    if (!has_component("kernel_correction")) {
        fprintf(stderr, "kernel_correction is not available: renormalised gradient not tested\n");
        return;
    }
    check_linear_gradient(2, 1);
}
END_TEST

/* --------------------------------------------------------- mixing length -- */

/* Shear u = gamma y over a DBC bed at y = 0, free surface at y = H. Every
 * fluid particle: l = min(1, s^3) min(kappa y, l_max) with the Shepard sum s
 * (fluid and wall neighbours and the particle itself) and y computed here,
 * and nu_T = c_mu l^2 sqrt(2 S:S) from the velocity_gradient field. */
/* A layer 0.4 m deep on a dbc bed, periodic in x, dx = 0.02 m, with the
 * eddy-viscosity model `model` (a plugins entry) and turbulent_stress. */
static sluice_sim *sheared_layer(const char *tag, const char *model)
{
    char yaml[1024];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
             "time: {end: 1.0}\n"
             "domain: {min: [0, -0.1], max: [0.4, 0.6], periodic: x}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [0.4, 0.4]}]\n"
             "  walls: [{shape: polyline, points: [[0, 0], [0.4, 0]]}]\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "  dbc: {}\n"
             "  velocity_gradient: {}\n"
             "  %s\n"
             "  turbulent_stress: {}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             model);
    return test_load(tag, yaml, NULL, 0);
}

START_TEST(mixing_length_values)
{
    const double H = 0.4, gamma = 2.0, kappa = 0.41, c_mu = 0.7, l_max = 0.1;
    sluice_sim *sim =
        sheared_layer("mixing-length", "mixing_length: {c_mu: 0.7, kappa: 0.41, l_max: 0.1}");
    const sluice_view *v = sluice_sim_view(sim);
    /* a non-uniform density makes V_j differ from dx^2 */
    for (sluice_index i = 0; i < v->count; i++) {
        test_column(sim, "density", 0)[i] = (sluice_real)(1000 * (1 + 0.02 * (uniform() - 0.5)));
        if (v->kind[i] == SLUICE_KIND_FLUID)
            test_column(sim, "velocity", 0)[i] = (sluice_real)(gamma * v->position[1][i]);
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const double support = 2 * (double)sim->smoothing_length, L = 0.4;
    const sluice_real *m = test_column(sim, "mass", 0), *rho = test_column(sim, "density", 0);
    const sluice_real *nu = test_column(sim, "eddy_viscosity", 0);
    const sluice_real *length = test_column(sim, "mixing_length", 0);
    double worst_l = 0, worst_nu = 0, shepard_top = 1;
    int damped = 0, capped = 0, wall_limited = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        double s = (double)m[i] / (double)rho[i] * kernel_eval(sim, 0, NULL);
        for (sluice_index j = 0; j < v->count; j++) {
            if (j == i)
                continue;
            double rx = (double)v->position[0][i] - (double)v->position[0][j];
            rx -= L * round(rx / L); /* periodic in x */
            double ry = (double)v->position[1][i] - (double)v->position[1][j];
            double r = sqrt(rx * rx + ry * ry);
            if (r < support)
                s += (double)m[j] / (double)rho[j] * kernel_eval(sim, r, NULL);
        }
        double y = v->position[1][i];
        double l = fmin(1, s * s * s) * fmin(kappa * y, l_max);
        double G[4];
        for (int c = 0; c < 4; c++)
            G[c] = test_column(sim, "velocity_gradient", (uint32_t)c)[i];
        double S2 = 2 * (G[0] * G[0] + G[3] * G[3]) + (G[1] + G[2]) * (G[1] + G[2]);
        double expected = c_mu * l * l * sqrt(S2);
        worst_l = fmax(worst_l, fabs(length[i] - l) / l_max);
        worst_nu = fmax(worst_nu, fabs(nu[i] - expected) / (c_mu * l_max * l_max * gamma));
        damped += s < 1 && y > H - support;
        capped += kappa * y > l_max && s >= 1;
        wall_limited += kappa * y < l_max && s >= 1;
        if (y > H - 0.5 * 0.02 - 1e-9)
            shepard_top = fmin(shepard_top, s);
        /* the interior shear rate is gamma up to the kernel moment error */
        if (y > support && y < H - support)
            ck_assert_msg(fabs(sqrt(S2) - gamma) < 0.05 * gamma, "|S| = %g at y = %g",
                          sqrt(S2), y);
    }
    fprintf(stderr,
            "mixing_length: max |l - formula| / l_max = %.1e, max |nu_T - formula| / (c_mu l_max^2 "
            "gamma) = %.1e; %d particles damped at the free surface (top-row Shepard sum %.3f), "
            "%d capped by l_max, %d with l = kappa y\n",
            worst_l, worst_nu, damped, shepard_top, capped, wall_limited);
    ck_assert_msg(worst_l < 1e-12 && worst_nu < 1e-12, "mixing length off by %g, nu_T by %g",
                  worst_l, worst_nu);
    ck_assert_int_gt(damped, 20);
    ck_assert_int_gt(capped, 20);
    ck_assert_int_gt(wall_limited, 20);
    ck_assert_msg(shepard_top < 0.8, "the Shepard sum at the free surface should be well below 1");
    sluice_sim_free(sim);
}
END_TEST

/* ----------------------------------------------------- k-eps: free decay -- */

/* Uniform k0, eps0 in a periodic box at rest: dk/dt = -eps,
 * deps/dt = -C2 eps^2/k, whose solution is
 * k = k0 (1 + (C2 - 1) eps0 t / k0)^(-1/(C2 - 1)). Returns the largest
 * relative error of k and eps at t_end over all particles. */
static double decay_error(double max_step, double *k_end)
{
    const double k0 = 0.01, e0 = 0.01, C2 = 1.92, t_end = 2.0;
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.05, smoothing_length_ratio: 1.3}\n"
             "time: {end: %g, max_step: %g}\n"
             "domain: {min: [0, 0], max: [0.6, 0.6], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.6, 0.6]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  gravity: {acceleration: [0, 0]}\n"
             "  velocity_gradient: {}\n"
             "  k_epsilon: {initial_k: %g, initial_epsilon: %g, wall_function: false}\n"
             "  time_step: {acoustic: false, force: false}\n"
             "  symplectic: {}\n",
             t_end, max_step, k0, e0);
    sluice_sim *sim = test_load("k-epsilon-decay", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < t_end * (1 - 1e-12))
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    const double t = sluice_sim_time(sim);
    const double base = 1 + (C2 - 1) * e0 * t / k0;
    const double k_exact = k0 * pow(base, -1 / (C2 - 1));
    const double e_exact = e0 * pow(base, -C2 / (C2 - 1));
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *k = test_column(sim, "turbulent_kinetic_energy", 0);
    const sluice_real *e = test_column(sim, "turbulent_dissipation_rate", 0);
    double worst = 0;
    for (sluice_index i = 0; i < v->count; i++)
        worst = fmax(worst, fmax(fabs(k[i] / k_exact - 1), fabs(e[i] / e_exact - 1)));
    *k_end = k[0];
    fprintf(stderr, "k-epsilon decay, max step %g s (k0/eps0 = 1 s), t = %g s: k = %.6e (exact "
                    "%.6e), max relative error of k, eps %.2e after %lld steps\n",
            max_step, t, (double)k[0], k_exact, worst, (long long)sluice_sim_steps(sim));
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return worst;
}

/* Smagorinsky: nu_T = (C_s dx)^2 |S| from the field velocity_gradient, for
 * every fluid particle of a sheared layer (the formula to round-off), and
 * |S| = gamma in the interior (the SPH gradient of a linear field). */
START_TEST(smagorinsky_values)
{
    const double H = 0.4, gamma = 2.0, c_s = 0.15, dx = 0.02;
    sluice_sim *sim = sheared_layer("smagorinsky", "smagorinsky: {c_s: 0.15}");
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            test_column(sim, "velocity", 0)[i] = (sluice_real)(gamma * v->position[1][i]);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const sluice_real *nu = test_column(sim, "eddy_viscosity", 0);
    const double support = 2 * (double)sim->smoothing_length, scale = c_s * dx * c_s * dx * gamma;
    double worst = 0;
    int interior = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        double G[4];
        for (int c = 0; c < 4; c++)
            G[c] = test_column(sim, "velocity_gradient", (uint32_t)c)[i];
        const double S = sqrt(2 * (G[0] * G[0] + G[3] * G[3]) + (G[1] + G[2]) * (G[1] + G[2]));
        worst = fmax(worst, fabs(nu[i] - c_s * dx * c_s * dx * S) / scale);
        const double y = v->position[1][i];
        if (y > support && y < H - support) {
            ck_assert_msg(fabs(nu[i] / scale - 1) < 0.05, "nu_T = %g (C_s dx)^2 gamma at y = %g",
                          nu[i] / scale, y);
            interior++;
        }
    }
    fprintf(stderr, "smagorinsky: max |nu_T - (C_s dx)^2 |S|| / ((C_s dx)^2 gamma) = %.1e; "
                    "%d interior particles at (C_s dx)^2 gamma within 5 %%\n",
            worst, interior);
    ck_assert_msg(worst < 1e-12, "nu_T off the formula by %g", worst);
    ck_assert_int_gt(interior, 100);
    sluice_sim_free(sim);
}
END_TEST

START_TEST(k_epsilon_decay)
{
    double k1, k2, k3;
    double e1 = decay_error(0.1, &k1), e2 = decay_error(0.05, &k2), e3 = decay_error(0.025, &k3);
    double order1 = log2(e1 / e2), order2 = log2(e2 / e3);
    fprintf(stderr, "k-epsilon decay: observed order %.2f, %.2f\n", order1, order2);
    /* the symplectic scheme is the explicit midpoint rule for these ODEs:
     * second order */
    ck_assert_msg(order1 > 1.8 && order1 < 2.2 && order2 > 1.8 && order2 < 2.2,
                  "decay converges at order %g, %g, expected 2", order1, order2);
    /* k decayed substantially, so the comparison is not vacuous */
    ck_assert(k3 < 0.5 * 0.01);
}
END_TEST

/* --------------------------------------------------- k-eps: diffusion -- */

/* k = k0 (1 + a sin(q x)), eps = eps0 (1 + a cos(q x)) in a periodic box at
 * rest: the rates minus the sources must be the diffusion
 * d/dx(nu_T/sigma df/dx), nu_T = c_mu k^2 / eps. The SPH operator (Lo & Shao
 * pair mean, eta^2 = 0.01 h^2) has the consistency factor
 * -int s^2 F r^2/(r^2 + eta^2) d^2r = 0.98372 for the Wendland C2 kernel
 * (numerical quadrature); around it the lattice error (|M - 1| = 2.6e-3 at
 * h = 1.5 dx) and the truncation O((q h)^2) = 0.9 % (mu4 q^2 / 12 with
 * mu4 = 5/6 h^2, q h = 2 pi 1.5 / 40): tolerance 1.5 % of the largest
 * diffusion rate. */
START_TEST(k_epsilon_diffusion)
{
    const double k0 = 0.01, e0 = 0.002, a = 0.2, c_mu = 0.09, sk = 1.0, se = 1.3;
    const double dx = 0.01, lambda = 40 * dx, q = 2 * M_PI / lambda;
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: %g, smoothing_length_ratio: 1.5}\n"
             "time: {end: 1.0}\n"
             "domain: {min: [0, 0], max: [%g, %g], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [%g, %g]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  gravity: {acceleration: [0, 0]}\n"
             "  velocity_gradient: {}\n"
             "  k_epsilon: {initial_k: %g, initial_epsilon: %g, wall_function: false}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dx, lambda, 12 * dx, lambda, 12 * dx, k0, e0);
    sluice_sim *sim = test_load("k-epsilon-diffusion", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++) {
        double x = v->position[0][i];
        test_column(sim, "turbulent_kinetic_energy", 0)[i] =
            (sluice_real)(k0 * (1 + a * sin(q * x)));
        test_column(sim, "turbulent_dissipation_rate", 0)[i] =
            (sluice_real)(e0 * (1 + a * cos(q * x)));
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const sluice_real *kr = test_column(sim, "turbulent_kinetic_energy_rate", 0);
    const sluice_real *er = test_column(sim, "turbulent_dissipation_rate_rate", 0);
    const sluice_real *kk = test_column(sim, "turbulent_kinetic_energy", 0);
    const sluice_real *ee = test_column(sim, "turbulent_dissipation_rate", 0);
    const double factor = 0.98372;
    double worst_k = 0, worst_e = 0, scale_k = 0, scale_e = 0;
    for (int pass = 0; pass < 2; pass++)
        for (sluice_index i = 0; i < v->count; i++) {
            double x = v->position[0][i];
            double k = k0 * (1 + a * sin(q * x)), kx = k0 * a * q * cos(q * x),
                   kxx = -k0 * a * q * q * sin(q * x);
            double e = e0 * (1 + a * cos(q * x)), ex = -e0 * a * q * sin(q * x),
                   exx = -e0 * a * q * q * cos(q * x);
            double nu = c_mu * k * k / e, nux = c_mu * (2 * k * kx / e - k * k * ex / (e * e));
            double dk = (nux * kx + nu * kxx) / sk, de = (nux * ex + nu * exx) / se;
            if (pass == 0) {
                scale_k = fmax(scale_k, fabs(dk));
                scale_e = fmax(scale_e, fabs(de));
                continue;
            }
            /* sources: -eps in k; -C2 eps^2 / k in eps (no production at rest) */
            double sim_dk = kr[i] + ee[i];
            double sim_de = er[i] + 1.92 * ee[i] * ee[i] / kk[i];
            worst_k = fmax(worst_k, fabs(sim_dk - factor * dk) / scale_k);
            worst_e = fmax(worst_e, fabs(sim_de - factor * de) / scale_e);
        }
    fprintf(stderr, "k-epsilon diffusion, sine profiles (lambda = 40 dx): max |SPH - 0.98372 "
                    "div(nu grad f)| / max|div(nu grad f)| = %.2e (k), %.2e (eps)\n",
            worst_k, worst_e);
    ck_assert_msg(worst_k < 0.015 && worst_e < 0.015, "k-epsilon diffusion off by %g, %g",
                  worst_k, worst_e);
    sluice_sim_free(sim);
}
END_TEST

/* Uniform k and eps over a DBC bed, at rest, in a pass that also holds wall
 * neighbours (the pressure gradient reads them): the diffusion of k and eps
 * is between fluid particles only, so every fluid particle's rates are the
 * sources alone, -eps and -C2 eps^2 / k (no production at rest), to
 * round-off. Walls leaking into the diffusion pull k and eps towards the wall
 * particles' values and break this by orders of magnitude. */
START_TEST(k_epsilon_diffusion_ignores_walls)
{
    const double k0 = 0.01, e0 = 0.001;
    const char *yaml = "dimensions: 2\n"
                       "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
                       "time: {end: 1.0}\n"
                       "domain: {min: [0, -0.1], max: [0.4, 0.6], periodic: x}\n"
                       "geometry:\n"
                       "  fluid: [{shape: box, min: [0, 0], max: [0.4, 0.2]}]\n"
                       "  walls: [{shape: polyline, points: [[0, 0], [0.4, 0]]}]\n"
                       "initial: {density: rest}\n"
                       "plugins:\n"
                       "  wendland_c2: {}\n"
                       "  tait: {speed_of_sound: 20}\n"
                       "  dbc: {}\n"
                       "  pressure_gradient: {}\n"
                       "  velocity_gradient: {}\n"
                       "  k_epsilon: {initial_k: 0.01, initial_epsilon: 0.001, wall_function: false}\n"
                       "  time_step: {}\n"
                       "  symplectic: {}\n";
    sluice_sim *sim = test_load("k-epsilon-walls", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *kr = test_column(sim, "turbulent_kinetic_energy_rate", 0);
    const sluice_real *er = test_column(sim, "turbulent_dissipation_rate_rate", 0);
    double worst_k = 0, worst_e = 0;
    int fluid = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        fluid++;
        worst_k = fmax(worst_k, fabs(kr[i] + e0) / e0);
        worst_e = fmax(worst_e, fabs(er[i] + 1.92 * e0 * e0 / k0) / (1.92 * e0 * e0 / k0));
    }
    fprintf(stderr, "k-epsilon over a DBC bed, uniform k and eps at rest: %d fluid particles, "
                    "largest relative departure of the rates from the sources %.2e (k), %.2e (eps)\n",
            fluid, worst_k, worst_e);
    ck_assert_int_gt(fluid, 0);
    ck_assert_msg(worst_k < 1e-12 && worst_e < 1e-12, "rates off the sources by %g, %g", worst_k,
                  worst_e);
    sluice_sim_free(sim);
}
END_TEST

/* ------------------------------------------------ k-eps: wall function -- */

/* Fluid at rest over a DBC bed at y = 0, uniform k0, eps0. After the start
 * (after_step runs once before the first step) the particles of the wall
 * layer (y < dx) carry eps = c_mu^(3/4) k0^(3/2) / (kappa y) and a zero eps
 * rate; the others keep eps0 and follow the equation (rate -C2 eps0^2/k0 at
 * rest, diffusion aside: it vanishes beyond the kernel radius of the layer). */
START_TEST(k_epsilon_wall_function)
{
    const double k0 = 0.01, e0 = 0.001, dx = 0.02, kappa = 0.41, c_mu = 0.09;
    const char *yaml = "dimensions: 2\n"
                       "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
                       "time: {end: 1.0}\n"
                       "domain: {min: [0, -0.1], max: [0.4, 0.6], periodic: x}\n"
                       "geometry:\n"
                       "  fluid: [{shape: box, min: [0, 0], max: [0.4, 0.4]}]\n"
                       "  walls: [{shape: polyline, points: [[0, 0], [0.4, 0]]}]\n"
                       "initial: {density: rest}\n"
                       "plugins:\n"
                       "  wendland_c2: {}\n"
                       "  tait: {speed_of_sound: 20}\n"
                       "  dbc: {}\n"
                       "  velocity_gradient: {}\n"
                       "  k_epsilon: {initial_k: 0.01, initial_epsilon: 0.001}\n"
                       "  turbulent_stress: {}\n"
                       "  time_step: {}\n"
                       "  symplectic: {}\n";
    sluice_sim *sim = test_load("k-epsilon-wall", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *e = test_column(sim, "turbulent_dissipation_rate", 0);
    const sluice_real *er = test_column(sim, "turbulent_dissipation_rate_rate", 0);
    const sluice_real *nu = test_column(sim, "eddy_viscosity", 0);
    int layer = 0, outside = 0;
    double worst = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        double y = v->position[1][i];
        if (y < dx) {
            double expected = pow(c_mu, 0.75) * pow(k0, 1.5) / (kappa * y);
            worst = fmax(worst, fabs(e[i] / expected - 1));
            worst = fmax(worst, fabs(nu[i] / (c_mu * k0 * k0 / expected) - 1));
            ck_assert_msg(er[i] == 0, "eps is integrated in the wall layer");
            layer++;
        } else if (y > 5 * dx) {
            worst = fmax(worst, fabs(e[i] / e0 - 1));
            worst = fmax(worst, fabs(er[i] / (-1.92 * e0 * e0 / k0) - 1));
            outside++;
        }
    }
    fprintf(stderr, "k-epsilon wall function: %d particles in the wall layer, %d outside; max "
                    "relative error %.1e\n",
            layer, outside, worst);
    ck_assert_int_eq(layer, 20);
    ck_assert_int_gt(outside, 200);
    ck_assert_msg(worst < 1e-12, "wall function off by %g", worst);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}
END_TEST

/* ------------------------------------------------ momentum conservation -- */

/* A periodic box with random velocities and a random 1 % density field; the
 * turbulent stress (and continuity) for 100 steps: total linear momentum must
 * not change beyond round-off, for either form and either eddy-viscosity
 * model. */
static void periodic_momentum(const char *model, const char *form)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.04}\n"
             "time: {end: 1.0}\n"
             "domain: {min: [0, 0], max: [1, 1], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 1]}]}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "  velocity_gradient: {}\n"
             "  %s\n"
             "  turbulent_stress: {form: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             model, form);
    sluice_sim *sim = test_load("turbulent-momentum", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++) {
        test_column(sim, "density", 0)[i] = (sluice_real)(1000 * (1 + 0.01 * (uniform() - 0.5)));
        for (int d = 0; d < 2; d++)
            test_column(sim, "velocity", (uint32_t)d)[i] = (sluice_real)(uniform() - 0.3);
    }
    double p0[2] = {0, 0}, scale = 0, e0 = 0;
    const sluice_real *m = test_column(sim, "mass", 0);
    for (int d = 0; d < 2; d++)
        for (sluice_index i = 0; i < v->count; i++) {
            double u = test_column(sim, "velocity", (uint32_t)d)[i];
            p0[d] += m[i] * u;
            scale += m[i] * fabs(u);
            e0 += 0.5 * m[i] * u * u;
        }
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    for (int s = 0; s < 100; s++)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    v = sluice_sim_view(sim);
    m = test_column(sim, "mass", 0);
    double e1 = 0, nu_max = 0;
    for (sluice_index i = 0; i < v->count; i++)
        nu_max = fmax(nu_max, test_column(sim, "eddy_viscosity", 0)[i]);
    for (int d = 0; d < 2; d++) {
        double p = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            double u = test_column(sim, "velocity", (uint32_t)d)[i];
            p += m[i] * u;
            e1 += 0.5 * m[i] * u * u;
        }
        fprintf(stderr, "turbulent_stress %s with %s, periodic box, 100 steps (t = %.3f s): "
                        "momentum[%d] change %.2e (sum m|v| %.2e)\n",
                form, model, sluice_sim_time(sim), d, p - p0[d], scale);
        ck_assert_msg(fabs(p - p0[d]) <= 1e-12 * scale, "momentum[%d] drifted by %g", d,
                      p - p0[d]);
    }
    fprintf(stderr, "  kinetic energy %.4g -> %.4g J/m, max nu_T %.3g m^2/s\n", e0, e1, nu_max);
    /* the stress did act: it is the only force, and it dissipates kinetic
     * energy (by several per cent over these 100 steps) */
    ck_assert_msg(e1 < 0.99 * e0 && nu_max > 0, "the turbulent stress did not act");
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}

START_TEST(momentum_tensor_mixing_length)
{
    periodic_momentum("mixing_length: {l_max: 0.05}", "tensor");
}
END_TEST
START_TEST(momentum_eddy_mixing_length)
{
    periodic_momentum("mixing_length: {l_max: 0.05}", "eddy_viscosity");
}
END_TEST
START_TEST(momentum_tensor_k_epsilon)
{
    periodic_momentum("k_epsilon: {initial_k: 0.2, initial_epsilon: 0.05}", "tensor");
}
END_TEST

/* ------------------------------------------- turbulent stress: interior -- */

/* u = (alpha y^2, 0) with uniform nu_T on a regular lattice: the stress
 * divergence is 2 nu_T alpha in x. Particles two kernel radii inside the
 * block (their neighbours' gradients are complete):
 *  - tensor, renormalised: the gradient of the quadratic field is exact on a
 *    symmetric neighbourhood, the renormalised divergence of the linear stress
 *    is exact, and sum_j m_j L_i grad W_ij vanishes by symmetry: round-off;
 *  - tensor: G_xy = 2 alpha y M_yy and the divergence adds another M_yy:
 *    2 nu alpha M_yy^2 (M_yy computed here by brute force);
 *  - eddy_viscosity: 2 nu alpha times the operator's factor
 *    -sum_j V_j s_y^2 F r^2/(r^2 + eta^2) (computed here by brute force). */
static void check_stress_interior(const char *form, int renormalise)
{
    const double dx = 0.02, alpha = 1.0, k = 0.01, eps = 0.01, nu = 0.09 * k * k / eps;
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: %g, smoothing_length_ratio: 1.5}\n"
             "time: {end: 1.0}\n"
             "domain: {min: [-1, -1], max: [2, 2]}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "%s"
             "  velocity_gradient: {renormalise: %s}\n"
             "  k_epsilon: {initial_k: %g, initial_epsilon: %g, wall_function: false}\n"
             "  turbulent_stress: {form: %s, renormalise: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dx, renormalise ? "  kernel_correction: {}\n" : "", renormalise ? "true" : "false",
             k, eps, form, renormalise ? "true" : "false");
    sluice_sim *sim = test_load("stress-interior", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++)
        test_column(sim, "velocity", 0)[i] =
            (sluice_real)(alpha * v->position[1][i] * v->position[1][i]);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const double h = 1.5 * dx, eta2 = 0.01 * h * h;
    double myy = 0, lap = 0;
    for (int a = -4; a <= 4; a++)
        for (int c = -4; c <= 4; c++) {
            double r = dx * sqrt((double)(a * a + c * c)), F;
            if (r == 0 || r >= 2 * h)
                continue;
            kernel_eval(sim, r, &F);
            myy -= dx * dx * (c * dx) * (c * dx) * F;
            lap -= dx * dx * (c * dx) * (c * dx) * F * r * r / (r * r + eta2);
        }
    double factor = strcmp(form, "eddy_viscosity") == 0 ? lap : renormalise ? 1 : myy * myy;
    const double expected = 2 * nu * alpha * factor;
    const sluice_real *ax = test_column(sim, "acceleration", 0);
    const sluice_real *ay = test_column(sim, "acceleration", 1);
    double worst = 0;
    int checked = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        double x = v->position[0][i], y = v->position[1][i];
        if (x < 4 * h + dx || x > 0.5 - 4 * h - dx || y < 4 * h + dx || y > 0.5 - 4 * h - dx)
            continue;
        worst = fmax(worst, fmax(fabs(ax[i] - expected), fabs(ay[i])) / expected);
        checked++;
    }
    fprintf(stderr, "turbulent_stress %s renormalise=%d, u = alpha y^2: %d interior particles, "
                    "a_x / (2 nu alpha) = %.6f expected (M_yy = %.6f), max relative error "
                    "%.1e\n",
            form, renormalise, checked, factor, myy, worst);
    ck_assert_int_gt(checked, 50);
    /* sums of ~30 terms of size 2 nu alpha y / h against 2 nu alpha:
     * round-off relative error about 1e-14 (h/y) per term */
    ck_assert_msg(worst < 1e-10, "stress divergence off by %g", worst);
    sluice_sim_free(sim);
}

START_TEST(stress_interior_tensor) { check_stress_interior("tensor", 0); }
END_TEST
START_TEST(stress_interior_eddy) { check_stress_interior("eddy_viscosity", 0); }
END_TEST
START_TEST(stress_interior_tensor_renormalised)
{
    if (!has_component("kernel_correction")) {
        fprintf(stderr, "kernel_correction is not available: renormalised stress not tested\n");
        return;
    }
    check_stress_interior("tensor", 1);
}
END_TEST

/* ----------------------------------------------------- wall shear stress -- */

/* Linear shear u = gamma y over a DBC bed at y = 0 (wall particles at rest),
 * uniform nu_T (k_epsilon with uniform k, eps and no wall function). The
 * fluid-fluid forces cancel in the total, so -sum_i m_i a_x,i / L is the shear
 * stress the wall particles exert. Also returns |M_yy - 1| of the regular
 * lattice (the second kernel moment, brute force), the scale of the lattice
 * error of every such sum. */
static double wall_stress(const char *form, const char *wall, double ratio, double *moment_error)
{
    const double gamma = 1.0, k = 0.01, eps = 0.01, rho0 = 1000, L = 0.6, dx = 0.02;
    const double nu = 0.09 * k * k / eps;
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: %g, smoothing_length_ratio: %g}\n"
             "time: {end: 1.0}\n"
             "domain: {min: [0, -0.2], max: [%g, 0.6], periodic: x}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [%g, 0.3]}]\n"
             "  walls: [{shape: polyline, points: [[0, 0], [%g, 0]]}]\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  dbc: {}\n"
             "  velocity_gradient: {}\n"
             "  k_epsilon: {initial_k: %g, initial_epsilon: %g, wall_function: false}\n"
             "  turbulent_stress: {form: %s, wall_stress: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dx, ratio, L, L, L, k, eps, form, wall);
    sluice_sim *sim = test_load("wall-stress", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            test_column(sim, "velocity", 0)[i] = (sluice_real)(gamma * v->position[1][i]);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const sluice_real *m = test_column(sim, "mass", 0), *ax = test_column(sim, "acceleration", 0);
    double force = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            force += (double)m[i] * (double)ax[i];
    double M = 0, h = ratio * dx;
    for (int a = -8; a <= 8; a++)
        for (int c = -8; c <= 8; c++) {
            double r = dx * sqrt((double)(a * a + c * c)), F;
            if (r == 0 || r >= 2 * h)
                continue;
            kernel_eval(sim, r, &F);
            M -= dx * dx * (c * dx) * (c * dx) * F;
        }
    *moment_error = fabs(M - 1);
    sluice_sim_free(sim);
    return -force / L / (rho0 * nu * gamma);
}

/* Continuum constants (turbulent_stress.c): tensor c 3/8, eddy_viscosity
 * c 1/4 (0.24593 with the eta^2 = 0.01 h^2 of the operator, integrated
 * numerically for the Wendland C2 kernel), c = 2 (mirror) or 1 (zero). The
 * wall sums are half-space versions of the second kernel moment: their
 * lattice error is measured at 2 |M_yy - 1| at h = 1.3, 1.5, 2 dx; the test
 * allows 3 |M_yy - 1|. */
START_TEST(wall_shear_stress)
{
    const double ratios[] = {1.3, 1.5, 2.0};
    const char *walls[] = {"mirror", "zero"};
    for (int w = 0; w < 2; w++)
        for (int r = 0; r < 3; r++) {
            const double c = w == 0 ? 2 : 1;
            double me;
            double t = wall_stress("tensor", walls[w], ratios[r], &me);
            double e = wall_stress("eddy_viscosity", walls[w], ratios[r], &me);
            double te = 0.375 * c, ee = 0.24593 * c;
            fprintf(stderr,
                    "wall shear stress / (rho nu_T gamma), wall_stress %s, h = %.1f dx: tensor "
                    "%.4f (continuum %.4f, %+.2f %%), eddy_viscosity %.4f (continuum %.4f, "
                    "%+.2f %%); lattice |M_yy - 1| = %.2e\n",
                    walls[w], ratios[r], t, te, 100 * (t / te - 1), e, ee, 100 * (e / ee - 1),
                    me);
            ck_assert_msg(fabs(t / te - 1) <= 3 * me && fabs(e / ee - 1) <= 3 * me,
                          "wall stress off its continuum value beyond the lattice error");
        }
}
END_TEST

/* ------------------------------------------------ open-channel flow -- */

/* Turbulent flow down a slope S = sin(theta) over a flat DBC bed, 2D,
 * periodic in x, free surface on top, depth H, gravity tilted by the slope:
 * g = (g S, -g cos(theta)). In a steady state the bed carries the weight
 * component of the whole column and every layer that of the water above it:
 *   tau(y) / rho = nu_T du/dy = u*^2 (1 - y/H),   u*^2 = g S H
 * (exact momentum balance; u*^2 from the fluid mass, M g S / (rho0 L)).
 * With the mixing length (c_mu = 1, l = kappa y, l_max above the depth)
 * nu_T = (kappa y)^2 du/dy, so
 *   u(y) = (u* / kappa) Phi(y/H) + const,
 *   Phi(eta) = 2 sqrt(1 - eta) + ln((1 - sqrt(1 - eta)) / (1 + sqrt(1 - eta)))
 *            = ln(eta) + 2 - 2 ln 2 + O(eta):
 * the log law with the correction of the linear stress distribution (no wake
 * term: seed 004 uses none). Near the bed, u/u* = (1/kappa) ln(y/dx) + B_dx
 * defines the log-law constant of the SPH wall (in units of the spacing: the
 * flow has no viscous sublayer). */
typedef struct oc_case {
    int across;        /* H / dx */
    const char *form;  /* turbulent_stress form */
    const char *model; /* mixing_length or k_epsilon */
    double t_end, t_average;
    double B_start; /* start from the profile with this B_dx; NaN: from rest */
    int verbose;
} oc_case;

typedef struct oc_result {
    int particles, bins;
    long long steps;
    double seconds, u_star, bulk, imbalance, u_surface, mach, slope_ratio, stress_error,
        stress_error_max, B_dx, fit_y_min, log_slope_ratio;
    double y[64], u[64], stress[64], nu[64], shear_ratio[64], k[64];
} oc_result;

static double oc_phi(double eta)
{
    double q = sqrt(1 - eta);
    return 2 * q + log((1 - q) / (1 + q));
}

static const double OC_H = 0.1, OC_SLOPE = 0.0025, OC_G = 9.81, OC_KAPPA = 0.41;
/* Phi = ln(eta) + OC_PHI0 + O(eta) */
#define OC_PHI0 (2 - 2 * M_LN2)

static oc_result run_open_channel(const oc_case *oc)
{
    const double H = OC_H, S = OC_SLOPE, g = OC_G, kappa = OC_KAPPA, rho0 = 1000;
    const double dx = H / oc->across, L = 12 * dx, c0 = 10.0, c_mu = 0.09;
    const int ke = strcmp(oc->model, "k_epsilon") == 0;
    oc_result res;
    memset(&res, 0, sizeof res);
    char model[256], yaml[4096];
    if (ke)
        snprintf(model, sizeof model, "k_epsilon: {initial_k: 1e-4, initial_epsilon: 1e-4}");
    else if (strcmp(oc->model, "smagorinsky") == 0)
        snprintf(model, sizeof model, "smagorinsky: {}");
    else
        snprintf(model, sizeof model, "mixing_length: {c_mu: 1, kappa: %g, l_max: 1.0}", kappa);
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: %.17g, smoothing_length_ratio: 1.5, rest_density: %g}\n"
             "time: {end: %g}\n"
             "domain: {min: [0, %.17g], max: [%.17g, %.17g], periodic: x}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [%.17g, %.17g]}]\n"
             "  walls: [{shape: polyline, points: [[0, 0], [%.17g, 0]]}]\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: %g}\n"
             "  continuity: {}\n"
             "  delta_sph: {delta: 0.1, form: fourtakas}\n"
             "  pressure_gradient: {}\n"
             "  gravity: {acceleration: [%.17g, %.17g]}\n"
             "  dbc: {}\n"
             "  velocity_gradient: {}\n"
             "  %s\n"
             "  turbulent_stress: {form: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dx, rho0, oc->t_end, -0.5 * H, L, 2 * H, L, H, L, c0, g * S, -g * sqrt(1 - S * S),
             model, oc->form);
    sluice_sim *sim = test_load("open-channel", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    double mass = 0;
    const sluice_real *m = test_column(sim, "mass", 0);
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            mass += m[i];
            res.particles++;
        }
    const double u_star = sqrt(g * S * mass / (rho0 * L));
    res.u_star = u_star;
    /* start: at rest, or from the profile u/u* = (Phi - ln(dx/H) - PHI0)/kappa + B_start
     * (k-epsilon: with its log-layer k = u*^2 (1 - eta) / sqrt(c_mu) and
     * eps = u*^3 (1 - eta) / (kappa y)) */
    if (oc->B_start == oc->B_start) {
        sluice_real *ux = test_column(sim, "velocity", 0);
        for (sluice_index i = 0; i < v->count; i++)
            if (v->kind[i] == SLUICE_KIND_FLUID) {
                double y = v->position[1][i], eta = y / H;
                ux[i] = (sluice_real)(u_star * ((oc_phi(eta) - log(dx / H) - OC_PHI0) / kappa +
                                                oc->B_start));
                if (ke) {
                    test_column(sim, "turbulent_kinetic_energy", 0)[i] =
                        (sluice_real)(u_star * u_star * (1 - eta) / sqrt(c_mu));
                    test_column(sim, "turbulent_dissipation_rate", 0)[i] =
                        (sluice_real)(u_star * u_star * u_star * (1 - eta) / (kappa * y));
                }
            }
    }
    double t0 = sluice_wall_clock();
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    const int bins = oc->across < 64 ? oc->across : 64;
    res.bins = bins;
    double su[64] = {0}, sst[64] = {0}, snu[64] = {0}, sg[64] = {0}, ss[64] = {0}, sk[64] = {0};
    long count[64] = {0};
    double next_sample = oc->t_end - oc->t_average, next_print = 0, surface = 0;
    double st = 0, stt = 0, sU = 0, stU = 0;
    long samples = 0;
    double bulk = 0;
    while (sluice_sim_time(sim) < oc->t_end * (1 - 1e-12)) {
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        double t = sluice_sim_time(sim);
        int sample = t >= next_sample;
        int print = oc->verbose && t >= next_print;
        if (!sample && !print)
            continue;
        v = sluice_sim_view(sim);
        m = test_column(sim, "mass", 0);
        const sluice_real *ux = test_column(sim, "velocity", 0);
        const sluice_real *nu = test_column(sim, "eddy_viscosity", 0);
        const sluice_real *G[4];
        for (int c = 0; c < 4; c++)
            G[c] = test_column(sim, "velocity_gradient", (uint32_t)c);
        const sluice_real *kk = ke ? test_column(sim, "turbulent_kinetic_energy", 0) : NULL;
        double p = 0, top = 0;
        long top_count = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_FLUID)
                continue;
            p += m[i] * ux[i];
            int k = (int)floor(v->position[1][i] / dx);
            if (k == bins - 1) {
                top += ux[i];
                top_count++;
            }
            if (sample && k >= 0 && k < bins) {
                su[k] += ux[i];
                sst[k] += nu[i] * (G[1][i] + G[2][i]);
                snu[k] += nu[i];
                sg[k] += G[1][i];
                ss[k] += sqrt(2 * (G[0][i] * G[0][i] + G[3][i] * G[3][i]) +
                              (G[1][i] + G[2][i]) * (G[1][i] + G[2][i]));
                sk[k] += ke ? kk[i] : 0;
                count[k]++;
            }
        }
        bulk = p / mass;
        if (sample) {
            /* U(t) regression over the averaging window: dU/dt */
            double tt = t - (oc->t_end - oc->t_average);
            st += tt;
            stt += tt * tt;
            sU += bulk;
            stU += tt * bulk;
            samples++;
            surface += top_count ? top / top_count : 0;
            next_sample = t + 0.02;
        }
        if (print) {
            fprintf(stderr,
                    "open channel %s/%s, H/dx = %d: t = %6.2f s (%.1f H/u*), bulk velocity "
                    "%.4f m/s = %.2f u*, surface %.4f m/s\n",
                    oc->model, oc->form, oc->across, t, t * u_star / H, bulk, bulk / u_star,
                    top_count ? top / top_count : 0);
            next_print = t + 2.0;
        }
    }
    res.seconds = sluice_wall_clock() - t0;
    res.steps = (long long)sluice_sim_steps(sim);
    res.bulk = bulk;
    double n_s = (double)samples;
    double dUdt = (n_s * stU - st * sU) / (n_s * stt - st * st);
    /* dU/dt = g S - tau_w / (rho H): the fraction of the driving force the bed
     * does not (yet) balance */
    res.imbalance = dUdt / (g * S);
    res.u_surface = surface / n_s;
    res.mach = res.u_surface / c0;
    for (int k = 0; k < bins; k++) {
        res.y[k] = (k + 0.5) * dx;
        double c = count[k] ? (double)count[k] : 1;
        res.u[k] = su[k] / c;
        res.stress[k] = sst[k] / c;
        res.nu[k] = snu[k] / c;
        res.shear_ratio[k] = sg[k] != 0 ? ss[k] / sg[k] : 0;
        res.k[k] = sk[k] / c;
    }
    /* least-squares u = a Phi + b over the bins at least a kernel radius from
     * the bed and from the free surface (where the Shepard factor damps l) */
    const double support = 2 * 1.5 * dx;
    double sx = 0, sy = 0, sxx = 0, sxy = 0, n = 0, err = 0, err_max = 0, bsum = 0;
    res.fit_y_min = H;
    for (int k = 0; k < bins; k++) {
        double y = res.y[k], eta = y / H;
        if (y < support || y > H - support)
            continue;
        res.fit_y_min = fmin(res.fit_y_min, y);
        double f = oc_phi(eta);
        sx += f;
        sy += res.u[k];
        sxx += f * f;
        sxy += f * res.u[k];
        n++;
        double e = fabs(res.stress[k] - u_star * u_star * (1 - eta)) / (u_star * u_star);
        err += e;
        err_max = fmax(err_max, e);
        bsum += res.u[k] / u_star - oc_phi(eta) / kappa;
    }
    double a = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    res.slope_ratio = a / (u_star / kappa);
    res.stress_error = err / n;
    res.stress_error_max = err_max;
    res.B_dx = bsum / n + (log(dx / H) + OC_PHI0) / kappa;
    /* the plain log law near the bed: slope of u against ln y over the bins
     * with 2h <= y <= 0.3 H (NaN with fewer than two) */
    double lx = 0, ly = 0, lxx = 0, lxy = 0, ln_ = 0;
    for (int k = 0; k < bins; k++)
        if (res.y[k] >= support && res.y[k] <= 0.3 * H) {
            double f = log(res.y[k]);
            lx += f;
            ly += res.u[k];
            lxx += f * f;
            lxy += f * res.u[k];
            ln_++;
        }
    res.log_slope_ratio =
        ln_ >= 2 ? (ln_ * lxy - lx * ly) / (ln_ * lxx - lx * lx) / (u_star / kappa) : NAN;
    if (oc->verbose) {
        fprintf(stderr, "  y/H     u/u*   log law  nu_T u_y/u*^2  1-y/H  nu_T/(u*H)  |S|/u_y%s\n",
                ke ? "  k sqrt(c_mu)/u*^2" : "");
        for (int k = 0; k < bins; k++) {
            fprintf(stderr, "  %.4f %7.3f %7.3f   %7.4f      %.4f  %.5f    %.3f", res.y[k] / H,
                    res.u[k] / u_star,
                    (oc_phi(res.y[k] / H) - log(dx / H) - OC_PHI0) / kappa + res.B_dx,
                    res.stress[k] / (u_star * u_star), 1 - res.y[k] / H,
                    res.nu[k] / (u_star * H), res.shear_ratio[k]);
            if (ke)
                fprintf(stderr, "  %.3f", res.k[k] * sqrt(c_mu) / (u_star * u_star));
            fprintf(stderr, "\n");
        }
    }
    fprintf(stderr,
            "open channel %s/%s, H/dx = %d (%d fluid particles), t = %g s = %.1f H/u* (%lld steps, "
            "%.1f s): u* = %.4f m/s; bulk U = %.4f m/s = %.2f u*; bed friction / driving force = "
            "%.4f (dU/dt over the last %g s); surface %.3f m/s (Mach %.3f); log-law slope / "
            "(u*/kappa) = %.3f (fit for y >= %.3f m), against ln y for y <= 0.3 H %.3f; nu_T "
            "du/dy vs u*^2 (1 - y/H): mean |error| %.3f, max %.3f u*^2; B_dx = %.2f\n",
            oc->model, oc->form, oc->across, res.particles, oc->t_end, oc->t_end * u_star / H,
            res.steps, res.seconds, u_star, res.bulk, res.bulk / u_star, 1 - res.imbalance,
            oc->t_average, res.u_surface, res.mach, res.slope_ratio, res.fit_y_min,
            res.log_slope_ratio, res.stress_error, res.stress_error_max, res.B_dx);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return res;
}

/* The coarse version (H/dx = 10, eddy_viscosity form, about 8 s of run
 * time): it starts from the steady profile of this resolution, which the study
 * reaches from rest and from B_dx = 10 (B_dx = 7.49; tools/open-channel-study.sh),
 * to skip the spin-up of some 30 H/u*, and runs 4 H/u*. Asserted:
 *  - steady state: the bed friction balances the driving force g S to 2 %
 *    (dU/dt from the bulk velocity over the last 6 s);
 *  - momentum balance: nu_T du/dy = u*^2 (1 - y/H) in the interior bins, mean
 *    error below 2 e + 1 % (u*^2), with e the mean over the bins of the SPH
 *    gradient's consistency error for this profile, mu4 u'''/(6 u') =
 *    5 h^2 / (18 y^2) (mu4 = 5/6 h^2 the Wendland C2 fourth moment,
 *    u'''/u' = 2/y^2 for the log law; the stress is quadratic in the
 *    gradient), and 1 % the density variation g H / c0^2 that the kinematic
 *    stress ignores;
 *  - the log-law slope: the slope of u against Phi(y/H) equals u* / kappa
 *    within 5 h^2 / (18 y_min^2) + 1 %, the gradient error at the lowest fitted
 *    bin and the density variation;
 *  - Mach number below 0.1. */
START_TEST(open_channel)
{
    const oc_case oc = {10, "eddy_viscosity", "mixing_length", 8.0, 6.0, 7.49, 0};
    oc_result r = run_open_channel(&oc);
    const double h = 1.5 * OC_H / oc.across;
    double e = 0, n = 0;
    for (int k = 0; k < r.bins; k++)
        if (r.y[k] >= 2 * h && r.y[k] <= OC_H - 2 * h) {
            e += 5 * h * h / (18 * r.y[k] * r.y[k]);
            n++;
        }
    e /= n;
    const double slope_tolerance = 5 * h * h / (18 * r.fit_y_min * r.fit_y_min) + 0.01;
    fprintf(stderr, "  tolerances: friction / driving 5 %%, stress %.3f u*^2, slope %.3f\n",
            2 * e + 0.01, slope_tolerance);
    ck_assert_msg(fabs(r.imbalance) < 0.05, "not steady: bed friction / driving force = %g",
                  1 - r.imbalance);
    ck_assert_msg(r.stress_error < 2 * e + 0.01, "stress balance off by %g u*^2 (mean)",
                  r.stress_error);
    ck_assert_msg(fabs(r.slope_ratio - 1) < slope_tolerance,
                  "log-law slope %g u*/kappa, expected 1 within %g", r.slope_ratio,
                  slope_tolerance);
    ck_assert_msg(r.mach < 0.1, "c0 must stay above 10 u_max (Mach %g)", r.mach);
}
END_TEST

/* tools/open-channel-study.sh: cases "MODEL:FORM:ACROSS:T_END:T_AVERAGE:START"
 * (START: rest or B_dx of the starting profile) separated by spaces in
 * SLUICE_OPEN_CHANNEL_STUDY; one CSV line per case and its profile on stdout. */
START_TEST(open_channel_study)
{
    const char *list = getenv("SLUICE_OPEN_CHANNEL_STUDY");
    ck_assert_ptr_nonnull(list);
    for (const char *p = list; *p;) {
        char model[32], form[32], start[32];
        int across, used = 0;
        double t_end, t_average;
        if (sscanf(p, " %31[^:]:%31[^:]:%d:%lf:%lf:%31[^ ]%n", model, form, &across, &t_end,
                   &t_average, start, &used) != 6)
            break;
        p += used;
        oc_case oc = {across, form, model, t_end, t_average, NAN, 1};
        if (strcmp(start, "rest") != 0)
            oc.B_start = atof(start);
        oc_result r = run_open_channel(&oc);
        fprintf(stdout,
                "study,%s,%s,%d,%s,%d,%lld,%.1f,%g,%.5f,%.5f,%.3f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,"
                "%.3f\n",
                model, form, across, start, r.particles, r.steps, r.seconds, t_end, r.u_star,
                r.bulk, r.bulk / r.u_star, 1 - r.imbalance, r.mach, r.slope_ratio,
                r.log_slope_ratio, r.stress_error, r.stress_error_max, r.B_dx);
        for (int k = 0; k < r.bins; k++)
            fprintf(stdout, "profile,%s,%s,%d,%s,%.4f,%.4f,%.4f,%.4f,%.5f,%.3f,%.3f\n", model,
                    form, across, start, r.y[k] / OC_H, r.u[k] / r.u_star,
                    (oc_phi(r.y[k] / OC_H) - log(1.0 / across) - OC_PHI0) / OC_KAPPA + r.B_dx,
                    r.stress[k] / (r.u_star * r.u_star), r.nu[k] / (r.u_star * OC_H),
                    r.shear_ratio[k], r.k[k] * 0.3 / (r.u_star * r.u_star));
        fflush(stdout);
    }
}
END_TEST

int main(void)
{
    Suite *s = suite_create("turbulence");
    TCase *g = tcase_create("velocity gradient");
    tcase_set_timeout(g, 120);
    tcase_add_test(g, gradient_linear_2d);
    tcase_add_test(g, gradient_linear_3d);
    tcase_add_test(g, gradient_linear_renormalised_2d);
    suite_add_tcase(s, g);
    TCase *ml = tcase_create("mixing length");
    tcase_add_test(ml, mixing_length_values);
    tcase_add_test(ml, smagorinsky_values);
    suite_add_tcase(s, ml);
    TCase *ke = tcase_create("k-epsilon");
    tcase_set_timeout(ke, 120);
    tcase_add_test(ke, k_epsilon_decay);
    tcase_add_test(ke, k_epsilon_diffusion);
    tcase_add_test(ke, k_epsilon_diffusion_ignores_walls);
    tcase_add_test(ke, k_epsilon_wall_function);
    suite_add_tcase(s, ke);
    TCase *c = tcase_create("conservation");
    tcase_set_timeout(c, 120);
    tcase_add_test(c, momentum_tensor_mixing_length);
    tcase_add_test(c, momentum_eddy_mixing_length);
    tcase_add_test(c, momentum_tensor_k_epsilon);
    suite_add_tcase(s, c);
    TCase *w = tcase_create("stress");
    tcase_add_test(w, stress_interior_tensor);
    tcase_add_test(w, stress_interior_eddy);
    tcase_add_test(w, stress_interior_tensor_renormalised);
    tcase_add_test(w, wall_shear_stress);
    suite_add_tcase(s, w);
    TCase *oc = tcase_create("open channel");
    tcase_set_tags(oc, "validation"); /* long: release pass only */
    tcase_set_timeout(oc, 600);
    tcase_add_test(oc, open_channel);
    suite_add_tcase(s, oc);
    if (getenv("SLUICE_OPEN_CHANNEL_STUDY")) {
        TCase *study = tcase_create("study");
        tcase_set_timeout(study, 36000);
        tcase_add_test(study, open_channel_study);
        suite_add_tcase(s, study);
    }
    return test_run_suite(s);
}
