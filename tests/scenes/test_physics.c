/* Unit tests of the core physics plugins, loaded through the real core:
 * kernel normalisation and gradients, the Tait equation of state and its
 * inverse, the hydrostatic initial state, and conservation of linear
 * momentum in a periodic box. */
#include <math.h>

#include "sim_util.h"
/* Internal: evaluates the loaded kernel on its state; the grid and particles (not in sim.h) */
#include "sim_internal.h"

#define SCENE_HEAD                                                                              \
    "dimensions: %d\n"                                                                          \
    "particles: {spacing: 0.05, smoothing_length_ratio: 1.3}\n"                                 \
    "time: {end: 1.0, max_step: 0.001}\n"

/* ------------------------------------------------------------- kernels -- */

static sluice_sim *kernel_sim(const char *kernel, int dims)
{
    char yaml[1024];
    snprintf(yaml, sizeof yaml,
             SCENE_HEAD "domain: {min: %s, max: %s}\n"
                        "geometry: {fluid: [{shape: box, min: %s, max: %s}]}\n"
                        "initial: {density: rest}\n"
                        "plugins: {%s: {}, symplectic: {}}\n",
             dims, dims == 2 ? "[0, 0]" : "[0, 0, 0]", dims == 2 ? "[1, 1]" : "[1, 1, 1]",
             dims == 2 ? "[0.4, 0.4]" : "[0.4, 0.4, 0.4]",
             dims == 2 ? "[0.6, 0.6]" : "[0.6, 0.6, 0.6]", kernel);
    return test_load(kernel, yaml, NULL, 0);
}

static double kernel_w(sluice_sim *sim, double r, double *f)
{
    const sluice_instance *k = &sim->instances[sim->kernel];
    sluice_real rr = (sluice_real)(r * r), distance = 0, w = 0, ff = 0;
    k->component->kernel(k->state, 1, &rr, &distance, &w, &ff);
    if (f)
        *f = (double)ff;
    return (double)w;
}

/* Midpoint-rule integral of W over its support with lattice step h/n. */
static double integral(sluice_sim *sim, int dims, int n)
{
    double h = (double)sim->smoothing_length, d = h / n, sum = 0;
    int m = (int)ceil((double)sim->support / h) * n;
    for (int i = -m; i < m; i++)
        for (int j = -m; j < m; j++) {
            if (dims == 2) {
                double x = (i + 0.5) * d, y = (j + 0.5) * d;
                sum += kernel_w(sim, sqrt(x * x + y * y), NULL) * d * d;
            } else {
                for (int k = -m; k < m; k++) {
                    double x = (i + 0.5) * d, y = (j + 0.5) * d, z = (k + 0.5) * d;
                    sum += kernel_w(sim, sqrt(x * x + y * y + z * z), NULL) * d * d * d;
                }
            }
        }
    return sum;
}

static void check_kernel(const char *name, int dims, double support_ratio)
{
    sluice_sim *sim = kernel_sim(name, dims);
    /* normalisation: midpoint rule converges at second order to 1 */
    int coarse = dims == 2 ? 20 : 10;
    double e1 = fabs(integral(sim, dims, coarse) - 1);
    double e2 = fabs(integral(sim, dims, 2 * coarse) - 1);
    fprintf(stderr, "%s %dD: |integral of W - 1| = %.2e (step h/%d), %.2e (step h/%d)\n", name,
            dims, e1, coarse, e2, 2 * coarse);
    /* the midpoint rule on a smooth compact kernel converges fast: 1e-6 leaves
     * a wide margin, while a wrong normalisation constant errs by O(1) */
    ck_assert_msg(e2 < 1e-6, "%s %dD: integral of W differs from 1 by %g", name, dims, e2);
    ck_assert_msg(e2 < 0.5 * e1 || e2 < 1e-10, "%s %dD: quadrature does not converge (%g, %g)",
                  name, dims, e1, e2);
    /* F r = dW/dr (central differences, error O(eps^2)), W = 0 beyond the
     * support (kappa h: 2h, the quintic spline's 3h) */
    double h = (double)sim->smoothing_length, kappa = support_ratio;
    for (double q = 0.05; q < kappa; q += 0.0625) {
        double r = q * h, eps = 1e-5 * h, f;
        kernel_w(sim, r, &f);
        double dw = (kernel_w(sim, r + eps, NULL) - kernel_w(sim, r - eps, NULL)) / (2 * eps);
        double scale = fabs(kernel_w(sim, 0, NULL)) / h;
        ck_assert_msg(fabs(f * r - dw) < 1e-6 * scale, "%s: dW/dr at q = %g: %g vs %g", name, q,
                      f * r, dw);
        ck_assert_msg(f <= 0, "%s: kernel must decrease (q = %g)", name, q);
    }
    double f0;
    kernel_w(sim, 0, &f0);
    ck_assert_msg(isfinite(f0), "%s: F(0) must be finite", name);
    double f2;
    ck_assert(kernel_w(sim, kappa * h, &f2) == 0 && f2 == 0);
    ck_assert(kernel_w(sim, (kappa + 0.5) * h, &f2) == 0 && f2 == 0);
    ck_assert_msg(fabs((double)sim->support - kappa * h) < 1e-15, "support must be %gh", kappa);
    sluice_sim_free(sim);
}

/* Largest error of the Shepard-normalised SPH interpolation
 * sum_j V_j f_j W_ij / sum_j V_j W_ij of f = sin(2 pi x) sin(2 pi y) at the
 * points of an n x n periodic lattice of the unit square, h = 1.3 dx (the
 * loaded kernel rescaled from its own h). For a symmetric kernel the first
 * moments vanish on the lattice and the error is the second moment's,
 * O(h^2). */
static double interpolation_error(sluice_sim *sim, int n)
{
    const double h0 = (double)sim->smoothing_length, kappa = (double)sim->support / h0;
    const double dx = 1.0 / n, h = 1.3 * dx, scale = h0 / h;
    const int reach = (int)ceil(kappa * h / dx);
    double worst = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            const double xi = (i + 0.5) * dx, yi = (j + 0.5) * dx;
            double num = 0, den = 0;
            for (int a = -reach; a <= reach; a++)
                for (int b = -reach; b <= reach; b++) {
                    const double r = sqrt((double)(a * a + b * b)) * dx;
                    const double w = kernel_w(sim, r * scale, NULL) * scale * scale;
                    const double xj = xi + a * dx, yj = yi + b * dx;
                    num += w * sin(2 * M_PI * xj) * sin(2 * M_PI * yj);
                    den += w;
                }
            worst = fmax(worst, fabs(num / den - sin(2 * M_PI * xi) * sin(2 * M_PI * yi)));
        }
    return worst;
}

static void check_interpolation_order(const char *name)
{
    sluice_sim *sim = kernel_sim(name, 2);
    const double e20 = interpolation_error(sim, 20), e40 = interpolation_error(sim, 40),
                 e80 = interpolation_error(sim, 80);
    const double p1 = log2(e20 / e40), p2 = log2(e40 / e80);
    fprintf(stderr,
            "%s 2D: Shepard interpolation of sin(2 pi x) sin(2 pi y), h = 1.3 dx: largest error "
            "%.3e / %.3e / %.3e at 20 / 40 / 80 per unit, observed order %.3f, %.3f\n",
            name, e20, e40, e80, p1, p2);
    /* second order, as the second moment of the kernel predicts */
    ck_assert_msg(fabs(p1 - 2) < 0.1 && fabs(p2 - 2) < 0.1, "%s: orders %g, %g", name, p1, p2);
    sluice_sim_free(sim);
}

START_TEST(wendland_2d) { check_kernel("wendland_c2", 2, 2); }
END_TEST
START_TEST(wendland_3d) { check_kernel("wendland_c2", 3, 2); }
END_TEST
START_TEST(cubic_2d) { check_kernel("cubic_spline", 2, 2); }
END_TEST
START_TEST(cubic_3d) { check_kernel("cubic_spline", 3, 2); }
END_TEST
START_TEST(quintic_spline_2d) { check_kernel("quintic_spline", 2, 3); }
END_TEST
START_TEST(quintic_spline_3d) { check_kernel("quintic_spline", 3, 3); }
END_TEST
START_TEST(quintic_wendland_2d) { check_kernel("quintic_wendland", 2, 2); }
END_TEST
START_TEST(quintic_wendland_3d) { check_kernel("quintic_wendland", 3, 2); }
END_TEST

static const char *const interpolated_kernels[] = {"wendland_c2", "cubic_spline",
                                                   "quintic_spline"};
START_TEST(interpolation_order) { check_interpolation_order(interpolated_kernels[_i]); }
END_TEST

/* The kernel gradient the core hands to pair terms is antisymmetric:
 * grad_i W_ij = r_ij F_ij = -grad_j W_ji, exactly, and points from j to i
 * with a negative slope. */
typedef struct gradients {
    sluice_index n;
    double *g[3];
    uint8_t *seen;
} gradients;

static void gradient_term(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    gradients *gr = state;
    for (sluice_index t = 0; t < b->target_count; t++) {
        sluice_index i = b->target[t];
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            size_t slot = (size_t)i * gr->n + b->neighbour[k];
            for (uint32_t d = 0; d < v->dimensions; d++)
                gr->g[d][slot] = (double)(b->offset[d][k] * b->kernel_gradient[k]);
            gr->seen[slot] = 1;
        }
    }
}

START_TEST(gradient_antisymmetry)
{
    sluice_sim *sim = kernel_sim("wendland_c2", 2);
    const sluice_index n = sim->particles.count;
    gradients gr = {n, {calloc((size_t)n * n, sizeof(double)), calloc((size_t)n * n, sizeof(double)),
                        NULL},
                    calloc((size_t)n * n, 1)};
    static sluice_component term = {.name = "gradients", .pair = gradient_term};
    sluice_pair_term t = {&term, &gr, SLUICE_KINDS_ALL};
    sluice_pair_pass pass;
    memset(&pass, 0, sizeof pass);
    pass.term_count = 1;
    pass.terms = &t;
    pass.neighbour_mask[0] = pass.neighbour_mask[1] = SLUICE_KINDS_ALL;
    /* a pass of the test's own, outside the scene's schedule: the list must
     * hold every kind (the scene has no pair term, so it lists none) */
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++)
        sim->grid.list_kinds[k] = SLUICE_KINDS_ALL;
    sluice_index bad;
    ck_assert_int_eq(
        sluice_grid_build(&sim->grid, &sim->particles, (uint32_t)sim->position.column, &bad), 0);
    sluice_sim_refresh_view(sim);
    ck_assert_int_eq(sluice_pair_pass_run(&sim->engine, &pass, &sim->grid, &sim->view), 0);
    int pairs = 0;
    for (sluice_index i = 0; i < n; i++)
        for (sluice_index j = 0; j < n; j++) {
            size_t ij = (size_t)i * n + j, ji = (size_t)j * n + i;
            ck_assert_int_eq(gr.seen[ij], gr.seen[ji]);
            if (!gr.seen[ij])
                continue;
            pairs++;
            double dot = 0;
            for (int d = 0; d < 2; d++) {
                ck_assert_msg(gr.g[d][ij] == -gr.g[d][ji], "gradient not antisymmetric");
                dot += gr.g[d][ij] *
                       ((double)sim->view.position[d][i] - (double)sim->view.position[d][j]);
            }
            ck_assert_msg(dot < 0, "grad_i W_ij must point from i towards j");
        }
    ck_assert_int_gt(pairs, 20);
    free(gr.g[0]);
    free(gr.g[1]);
    free(gr.seen);
    sluice_sim_free(sim);
}
END_TEST

/* ----------------------------------------------------------------- Tait -- */

static const char *tait_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.05, rest_density: 1000}\n"
    "time: {end: 1.0, max_step: 0.001}\n"
    "domain: {min: [-0.2, -0.2], max: [1.2, 2.0]}\n"
    "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 1]}]}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 30, gamma: 7}\n"
    "  gravity: {acceleration: [0, -9.81]}\n"
    "  symplectic: {}\n";

START_TEST(tait_values)
{
    sluice_sim *sim = test_load("tait", tait_scene, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *rho = test_column(sim, "density", 0);
    const double rho0 = 1000, c0 = 30, B = c0 * c0 * rho0 / 7;
    for (sluice_index i = 0; i < v->count; i++)
        rho[i] = (sluice_real)(rho0 * (0.98 + 0.04 * i / (double)v->count));
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    rho = test_column(sim, "density", 0);
    const sluice_real *p = test_column(sim, "pressure", 0);
    const sluice_real *c = test_column(sim, "sound_speed", 0);
    for (sluice_index i = 0; i < v->count; i++) {
        double x = rho[i] / rho0;
        double expected = B * (pow(x, 7) - 1);
        ck_assert_msg(fabs(p[i] - expected) <= 1e-12 * B, "p(%g) = %g, expected %g", rho[i], p[i],
                      expected);
        /* c^2 = dp/drho */
        double eps = 1e-6 * rho0;
        double dpdrho = B * (pow((rho[i] + eps) / rho0, 7) - pow((rho[i] - eps) / rho0, 7)) /
                        (2 * eps);
        ck_assert_msg(fabs(c[i] * c[i] - dpdrho) <= 1e-7 * dpdrho, "c^2 = %g, dp/drho = %g",
                      c[i] * c[i], dpdrho);
    }
    sluice_sim_free(sim);
}
END_TEST

START_TEST(hydrostatic_initial_density)
{
    sluice_sim *sim = test_load("hydrostatic", tait_scene, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *rho = test_column(sim, "density", 0);
    const double rho0 = 1000, B = 30.0 * 30.0 * rho0 / 7, g = 9.81, H = 1.0;
    for (sluice_index i = 0; i < v->count; i++) {
        double p = rho0 * g * (H - v->position[1][i]);
        double expected = rho0 * pow(1 + p / B, 1.0 / 7);
        ck_assert_msg(fabs(rho[i] - expected) <= 1e-12 * rho0, "rho at y = %g: %g, expected %g",
                      v->position[1][i], rho[i], expected);
    }
    /* the equation of state maps it back to the hydrostatic pressure */
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const sluice_real *pressure = test_column(sim, "pressure", 0);
    for (sluice_index i = 0; i < v->count; i++) {
        double expected = rho0 * g * (H - v->position[1][i]);
        ck_assert_msg(fabs(pressure[i] - expected) <= 1e-9 * rho0 * g * H, "p = %g, expected %g",
                      pressure[i], expected);
    }
    sluice_sim_free(sim);
}
END_TEST

/* ------------------------------------------------ momentum conservation -- */

static uint64_t rng = 2024;
static double uniform(void)
{
    rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

/* Runs 100 steps of a periodic box without walls, random velocities and a
 * random 1 % density field, with the given pair forces (YAML lines under
 * plugins:), and checks that total linear momentum does not change beyond
 * round-off. */
static void periodic_box_forces(const char *kernel, int dims, const char *forces)
{
    char yaml[4096];
    const char *lo = dims == 2 ? "[0, 0]" : "[0, 0, 0]";
    const char *hi = dims == 2 ? "[1, 1]" : "[0.6, 0.6, 0.6]";
    snprintf(yaml, sizeof yaml,
             "dimensions: %d\n"
             "particles: {spacing: %s}\n"
             "time: {end: 1.0}\n"
             "domain: {min: %s, max: %s, periodic: %s}\n"
             "geometry: {fluid: [{shape: box, min: %s, max: %s}]}\n"
             "plugins:\n"
             "  %s: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "%s"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dims, dims == 2 ? "0.04" : "0.06", lo, hi, dims == 2 ? "xy" : "xyz", lo, hi, kernel,
             forces);
    sluice_sim *sim = test_load("periodic", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < v->count; i++) {
        rho[i] = (sluice_real)(1000 * (1 + 0.01 * (uniform() - 0.5)));
        for (int d = 0; d < dims; d++)
            test_column(sim, "velocity", (uint32_t)d)[i] = (sluice_real)(uniform() - 0.3);
    }
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
    double moved = 0;
    for (int d = 0; d < dims; d++) {
        double p = 0;
        for (sluice_index i = 0; i < v->count; i++)
            p += m[i] * test_column(sim, "velocity", (uint32_t)d)[i];
        /* round-off: each step adds O(eps) relative error per particle sum */
        ck_assert_msg(fabs(p - p0[d]) <= 1e-12 * scale,
                      "%s %dD: momentum[%d] drifted by %g (scale %g)", kernel, dims, d, p - p0[d],
                      scale);
        moved += fabs(p);
        fprintf(stderr, "%s %dD periodic box, 100 steps, forces {%s}: momentum[%d] change %.2e "
                        "(sum m|v| %.2e)\n",
                kernel, dims, forces, d, p - p0[d], scale);
    }
    (void)moved;
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}

static void periodic_box(const char *kernel, int dims, double beta)
{
    char forces[256];
    snprintf(forces, sizeof forces,
             "  pressure_gradient: {}\n  artificial_viscosity: {alpha: 0.5, beta: %g}\n", beta);
    periodic_box_forces(kernel, dims, forces);
}

START_TEST(momentum_2d_wendland) { periodic_box("wendland_c2", 2, 0); }
END_TEST
START_TEST(momentum_2d_cubic) { periodic_box("cubic_spline", 2, 1.0); }
END_TEST
START_TEST(momentum_3d) { periodic_box("wendland_c2", 3, 0.5); }
END_TEST

/* artificial_viscosity's speed_of_sound: one evaluation of a box at rest
 * density (every sound speed c0 = 20 m/s) in a converging shear flow, the
 * viscosity the only force (beta = 0, so Pi is linear in cbar): with
 * speed_of_sound = 20 the accelerations equal the pair-mean form's bit for
 * bit, and with 40 they are twice them (to round-off). */
static sluice_sim *av_box(const char *speed)
{
    char yaml[1024];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.05}\n"
             "time: {end: 0.1}\n"
             "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n  tait: {speed_of_sound: 20}\n"
             "  artificial_viscosity: {alpha: 0.3, time_step_limit: false%s}\n"
             "  symplectic: {}\n",
             speed);
    sluice_sim *sim = test_load("av-speed", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *vx = test_column(sim, "velocity", 0), *vy = test_column(sim, "velocity", 1);
    for (sluice_index i = 0; i < v->count; i++) {
        vx[i] = (sluice_real)(-0.8 * v->position[0][i] + 0.3 * v->position[1][i]);
        vy[i] = (sluice_real)(-0.5 * v->position[1][i]);
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    return sim;
}

START_TEST(artificial_viscosity_fixed_speed)
{
    sluice_sim *mean = av_box(""), *same = av_box(", speed_of_sound: 20"),
               *twice = av_box(", speed_of_sound: 40");
    const sluice_view *v = sluice_sim_view(mean);
    double largest = 0, worst_same = 0, worst_twice = 0;
    for (uint32_t d = 0; d < 2; d++) {
        const sluice_real *a = test_column(mean, "acceleration", d);
        const sluice_real *b = test_column(same, "acceleration", d);
        const sluice_real *c = test_column(twice, "acceleration", d);
        for (sluice_index i = 0; i < v->count; i++) {
            largest = fmax(largest, fabs(a[i]));
            worst_same = fmax(worst_same, fabs(b[i] - a[i]));
            worst_twice = fmax(worst_twice, fabs(c[i] - 2 * a[i]));
        }
    }
    fprintf(stderr,
            "artificial_viscosity speed_of_sound: largest |a| %.3e m/s^2; c = c0: differs by "
            "%.1e; c = 2 c0: differs from twice by %.1e\n",
            largest, worst_same, worst_twice);
    ck_assert(largest > 1e-3);
    ck_assert(worst_same == 0);
    ck_assert(worst_twice <= 1e-13 * largest);
    sluice_sim_free(mean);
    sluice_sim_free(same);
    sluice_sim_free(twice);
}
END_TEST

/* ------------------------------------------------------- plugin swap -- */

/* Two scenes that differ by one plugin: their field tables must agree except
 * for fields declared only by the differing plugins, and shared fields must
 * have the same type, components and units. */
static int declared_by(const sluice_sim *sim, const sluice_field_entry *f, const char *plugin)
{
    for (uint32_t d = 0; d < f->declarer_count; d++)
        if (f->declarers[d].instance != SLUICE_CORE_INSTANCE &&
            strcmp(sim->instances[f->declarers[d].instance].name, plugin) == 0)
            return 1;
    return 0;
}

static void check_swap(const char *a_plugin, const char *b_plugin, const char *integrator)
{
    char yaml_a[1024], yaml_b[1024];
    const char *head = "dimensions: 2\n"
                       "particles: {spacing: 0.05}\n"
                       "time: {end: 0.1}\n"
                       "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
                       "geometry:\n"
                       "  fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]\n"
                       "  walls: [{shape: tank, min: [0, 0], max: [1, 1]}]\n"
                       "plugins:\n"
                       "  wendland_c2: {}\n  tait: {speed_of_sound: 20}\n  continuity: {}\n"
                       "  pressure_gradient: {}\n  gravity: {}\n  dbc: {}\n  time_step: {}\n";
    char line_a[128] = "", line_b[128] = "";
    if (a_plugin[0])
        snprintf(line_a, sizeof line_a, "  %s: {}\n", a_plugin);
    if (b_plugin[0])
        snprintf(line_b, sizeof line_b, "  %s: {}\n", b_plugin);
    snprintf(yaml_a, sizeof yaml_a, "%s%s  %s: {}\n", head, line_a, integrator);
    snprintf(yaml_b, sizeof yaml_b, "%s%s  %s: {}\n", head, line_b, integrator);
    sluice_sim *a = test_load("swap-a", yaml_a, NULL, 0), *b = test_load("swap-b", yaml_b, NULL, 0);
    int differing = 0;
    for (int pass = 0; pass < 2; pass++) {
        sluice_sim *x = pass ? b : a, *y = pass ? a : b;
        const char *own = pass ? b_plugin : a_plugin;
        for (uint32_t i = 0; i < x->field_count; i++) {
            const sluice_field_entry *f = &x->fields[i];
            const sluice_field_entry *g = NULL;
            for (uint32_t k = 0; k < y->field_count; k++)
                if (strcmp(y->fields[k].name, f->name) == 0)
                    g = &y->fields[k];
            if (!g) {
                ck_assert_msg(own[0] && declared_by(x, f, own),
                              "field '%s' differs between the scenes but is not owned by '%s'",
                              f->name, own[0] ? own : "(nothing)");
                differing++;
                continue;
            }
            ck_assert_msg(f->type == g->type && f->components == g->components &&
                              strcmp(f->units, g->units) == 0,
                          "shared field '%s' changed its layout", f->name);
        }
    }
    fprintf(stderr, "swap '%s' <-> '%s': %d fields differ, all owned by them\n",
            a_plugin[0] ? a_plugin : "-", b_plugin[0] ? b_plugin : "-", differing);
    sluice_sim_free(a);
    sluice_sim_free(b);
}

START_TEST(swapping_a_plugin_changes_only_its_fields)
{
    check_swap("artificial_viscosity", "", "symplectic");
    check_swap("delta_sph", "", "symplectic");
    /* the seeds' menu (issue 3), also under the other integrators */
    check_swap("xsph", "", "symplectic");
    check_swap("laminar_viscosity", "", "symplectic");
    check_swap("kernel_correction", "", "symplectic");
    check_swap("pressure_smoothing", "", "symplectic");
    check_swap("xsph", "laminar_viscosity", "verlet");
    check_swap("delta_sph", "artificial_viscosity", "predictor_corrector");
    check_swap("artificial_viscosity", "laminar_viscosity", "euler");
}
END_TEST

int main(void)
{
    Suite *s = suite_create("physics");
    TCase *k = tcase_create("kernels");
    tcase_set_timeout(k, 120);
    tcase_add_test(k, wendland_2d);
    tcase_add_test(k, wendland_3d);
    tcase_add_test(k, cubic_2d);
    tcase_add_test(k, cubic_3d);
    tcase_add_test(k, quintic_spline_2d);
    tcase_add_test(k, quintic_spline_3d);
    tcase_add_test(k, quintic_wendland_2d);
    tcase_add_test(k, quintic_wendland_3d);
    tcase_add_loop_test(k, interpolation_order, 0, 3);
    tcase_add_test(k, gradient_antisymmetry);
    suite_add_tcase(s, k);
    TCase *e = tcase_create("equation of state");
    tcase_add_test(e, tait_values);
    tcase_add_test(e, hydrostatic_initial_density);
    suite_add_tcase(s, e);
    TCase *c = tcase_create("conservation");
    tcase_set_timeout(c, 120);
    tcase_add_test(c, momentum_2d_wendland);
    tcase_add_test(c, momentum_2d_cubic);
    tcase_add_test(c, momentum_3d);
    tcase_add_test(c, artificial_viscosity_fixed_speed);
    suite_add_tcase(s, c);
    TCase *l = tcase_create("layout");
    tcase_add_test(l, swapping_a_plugin_changes_only_its_fields);
    suite_add_tcase(s, l);
    return test_run_suite(s);
}
