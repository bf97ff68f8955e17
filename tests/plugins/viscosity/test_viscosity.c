/* Laminar viscosity (plugins/viscosity/laminar_viscosity.c), both forms:
 *  - the pair sums agree with a brute-force evaluation of the published
 *    formulas (Morris et al. 1997; Lo & Shao 2002) on a random periodic box;
 *  - total linear momentum is conserved to round-off over 100 steps, while
 *    the random velocity field is damped;
 *  - a decaying shear wave in a periodic box (no walls) decays at the rate
 *    the lattice sums predict, within 2 % of nu k^2 at 40 particles per
 *    wavelength;
 *  - 2D Poiseuille flow between DBC plates driven by a body force
 *    (configs/poiseuille_2d.yaml): the particles reach the steady state of the
 *    same discrete equations, and the transient and steady profiles converge
 *    to the analytic solution (Morris et al. 1997) under refinement; between
 *    ghost-particle walls (no-slip) the steady profile is within 2 % of it
 *    at 40 particles across;
 *  - the viscous time-step limit 0.125 h^2 / nu, and the published constant.
 * Setting SLUICE_POISEUILLE_STUDY="10 20 40 80" adds a test case `study`
 * that runs the Poiseuille flow at those resolutions (tools/poiseuille-study.sh);
 * SLUICE_POISEUILLE_WALLS replaces the scene's `dbc: {}` line in it. */
#include <math.h>

#include "sim_util.h"
/* Internal: calls the loaded kernel on its state; published constants, dt_limit, support (not
 * in sim.h) */
#include "sim_internal.h"

static const char *const forms[] = {"morris", "lo_shao"};

/* -------------------------------------------------------- random state -- */

static double uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

static double kernel_value(sluice_sim *sim, double r2, double *f)
{
    const sluice_instance *k = &sim->instances[sim->kernel];
    sluice_real rr = (sluice_real)r2, r = 0, w = 0, ff = 0;
    k->component->kernel(k->state, 1, &rr, &r, &w, &ff);
    *f = (double)ff;
    return (double)w;
}

/* --------------------------------------------------- periodic box tests -- */

/* A periodic box without walls (Tait, continuity, laminar viscosity only: the
 * acceleration is the viscous term alone), random velocities and a random
 * 1 % density field. */
static sluice_sim *periodic_box(int dims, const char *form, double nu, uint64_t seed)
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
             "  continuity: {}\n"
             "  laminar_viscosity: {kinematic_viscosity: %g, form: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dims, dims == 2 ? "0.04" : "0.06", lo, hi, dims == 2 ? "xy" : "xyz", lo, hi, nu, form);
    sluice_sim *sim = test_load("viscosity-box", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < v->count; i++) {
        rho[i] = (sluice_real)(1000 * (1 + 0.01 * (uniform(&seed) - 0.5)));
        for (int d = 0; d < dims; d++)
            test_column(sim, "velocity", (uint32_t)d)[i] = (sluice_real)(uniform(&seed) - 0.3);
    }
    return sim;
}

/* The acceleration the core computes equals a brute-force O(N^2) sum of the
 * published formula over minimum-image pairs within the support. */
static void check_against_formula(int dims, const char *form)
{
    const double nu = 0.5;
    sluice_sim *sim = periodic_box(dims, form, nu, 7 + (uint64_t)dims);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_index n = v->count;
    const sluice_real *rho = test_column(sim, "density", 0), *m = test_column(sim, "mass", 0);
    const sluice_real *u[3], *a[3];
    for (int d = 0; d < dims; d++) {
        u[d] = test_column(sim, "velocity", (uint32_t)d);
        a[d] = test_column(sim, "acceleration", (uint32_t)d);
    }
    const double h = (double)sim->smoothing_length, support = (double)sim->support;
    const double box = dims == 2 ? 1.0 : 0.6, eta2 = 0.01 * h * h;
    const int morris = strcmp(form, "morris") == 0;
    double worst = 0, scale = 0;
    for (sluice_index i = 0; i < n; i++) {
        double sum[3] = {0, 0, 0};
        for (sluice_index j = 0; j < n; j++) {
            if (j == i)
                continue;
            double r[3] = {0, 0, 0}, r2 = 0;
            for (int d = 0; d < dims; d++) {
                r[d] = (double)v->position[d][i] - (double)v->position[d][j];
                r[d] -= box * round(r[d] / box); /* minimum image */
                r2 += r[d] * r[d];
            }
            if (r2 >= support * support)
                continue;
            double F;
            kernel_value(sim, r2, &F);
            double rdotgrad = r2 * F; /* r_ij . grad_i W_ij */
            double weight;
            if (morris) /* m_j (mu_i + mu_j) / (rho_i rho_j), mu = rho nu */
                weight = m[j] * (rho[i] * nu + rho[j] * nu) / (rho[i] * rho[j]);
            else /* m_j 4 nu / (rho_i + rho_j) */
                weight = m[j] * 4 * nu / (rho[i] + rho[j]);
            for (int d = 0; d < dims; d++)
                sum[d] += weight * rdotgrad / (r2 + eta2) * (u[d][i] - u[d][j]);
        }
        for (int d = 0; d < dims; d++) {
            worst = fmax(worst, fabs(sum[d] - a[d][i]));
            scale = fmax(scale, fabs(sum[d]));
        }
    }
    fprintf(stderr, "%s %dD: batch sums vs brute-force formula over %u particles: largest "
                    "difference %.2e of max |a| = %.3e m/s^2\n",
            form, dims, (unsigned)n, worst / scale, scale);
    /* the same sums in another order: round-off of ~25 terms */
    ck_assert_msg(scale > 0 && worst <= 1e-12 * scale, "%s %dD: acceleration differs by %g of %g",
                  form, dims, worst, scale);
    sluice_sim_free(sim);
}

START_TEST(formula_2d) { check_against_formula(2, forms[_i]); }
END_TEST
START_TEST(formula_3d) { check_against_formula(3, forms[_i]); }
END_TEST

/* 100 steps: total momentum changes only by round-off, and the random
 * velocity field decays. With nu = 0.5 m^2/s and dx = 0.04 m the
 * particle-scale modes (k ~ pi/dx) decay as exp(-nu k^2 t) with nu k^2 dt
 * of order one per step, so after 100 steps the kinetic energy of the
 * fluctuations must be a small fraction of the initial one. */
static void check_momentum(int dims, const char *form)
{
    sluice_sim *sim = periodic_box(dims, form, 0.5, 2024 + (uint64_t)dims);
    const sluice_view *v = sluice_sim_view(sim);
    double p0[3] = {0, 0, 0}, scale = 0, mass = 0, e0 = 0;
    const sluice_real *m = test_column(sim, "mass", 0);
    for (sluice_index i = 0; i < v->count; i++)
        mass += m[i];
    for (int d = 0; d < dims; d++)
        for (sluice_index i = 0; i < v->count; i++) {
            double u = test_column(sim, "velocity", (uint32_t)d)[i];
            p0[d] += m[i] * u;
            scale += m[i] * fabs(u);
        }
    /* kinetic energy relative to the (conserved) mean motion */
    for (int d = 0; d < dims; d++)
        for (sluice_index i = 0; i < v->count; i++) {
            double u = test_column(sim, "velocity", (uint32_t)d)[i] - p0[d] / mass;
            e0 += 0.5 * m[i] * u * u;
        }
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    for (int s = 0; s < 100; s++)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    v = sluice_sim_view(sim);
    m = test_column(sim, "mass", 0);
    double e1 = 0;
    for (int d = 0; d < dims; d++) {
        double p = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            double u = test_column(sim, "velocity", (uint32_t)d)[i];
            p += m[i] * u;
            e1 += 0.5 * m[i] * (u - p0[d] / mass) * (u - p0[d] / mass);
        }
        fprintf(stderr, "%s %dD periodic box, 100 steps: momentum[%d] change %.2e (sum m|v| "
                        "%.2e)\n",
                form, dims, d, p - p0[d], scale);
        /* round-off: each step adds O(eps) relative error per particle sum */
        ck_assert_msg(fabs(p - p0[d]) <= 1e-12 * scale, "%s %dD: momentum[%d] drifted by %g",
                      form, dims, d, p - p0[d]);
    }
    fprintf(stderr, "%s %dD periodic box: fluctuation kinetic energy %.3e -> %.3e J after "
                    "%.3e s\n",
            form, dims, e0, e1, sluice_sim_time(sim));
    ck_assert_msg(e1 < 0.1 * e0, "%s %dD: viscosity did not damp the random field (%g -> %g)",
                  form, dims, e0, e1);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}

START_TEST(momentum_2d) { check_momentum(2, forms[_i]); }
END_TEST
START_TEST(momentum_3d) { check_momentum(3, forms[_i]); }
END_TEST

/* ----------------------------------------------------------- Poiseuille -- */

/* Morris et al. (1997): plates at y = 0 and y = L, periodic in x, body
 * force F along x, fluid at rest at t = 0. u_max = F L^2 / (8 nu) =
 * 1.25e-5 m/s, Re = u_max L / nu = 0.0125. c0 = 0.01 m/s: Mach 1.3e-3, and
 * c0^2 = 1e-4 > F L / 0.01 (Morris's 1 % density criterion). With h = 1.5 dx
 * the steps are: viscous 0.125 h^2/nu = 2.8e-3 s .. 1.8e-4 s for 10 .. 40
 * particles across, acoustic 0.2 h / c0 = 3e-3 .. 7.5e-4 s, force
 * 0.2 sqrt(h/F) > 0.1 s: the viscous condition sets the step. The slowest
 * transient mode decays as exp(-pi^2 nu t / L^2): 4e-7 u_max at t = 1.5 s. */
#define P_L 1e-3
#define P_NU 1e-6
#define P_F 1e-4
#define P_UMAX (P_F * P_L * P_L / (8 * P_NU))
#define P_COLUMNS 12 /* periodic length 12 dx: 3 cells of the 3.3 dx list radius */

static double h_ratio(void)
{
    const char *r = getenv("SLUICE_POISEUILLE_H_RATIO");
    return r ? atof(r) : 1.5;
}

/* u(y, t): the series solution of Morris et al. (1997), u(y, 0) = 0. */
static double poiseuille_exact(double y, double t)
{
    double u = P_F / (2 * P_NU) * y * (P_L - y);
    for (int n = 1; n < 400; n += 2) {
        double k = n * M_PI / P_L, decay = exp(-k * k * P_NU * t);
        if (decay < 1e-18)
            break;
        u -= 4 * P_F * P_L * P_L / (P_NU * pow(M_PI * n, 3)) * sin(k * y) * decay;
    }
    return u;
}

static double poiseuille_steady(double y)
{
    return P_F / (2 * P_NU) * y * (P_L - y);
}

/* The discrete steady state of the same SPH equations, solved directly:
 * with every particle on its initial lattice row and uniform density, the
 * viscous acceleration of a particle of row i is nu sum_j K(y_i - y_j)
 * (u_i - u_j), where K(dy) = sum over one lattice row of
 * 2 V F r^2 / (r^2 + eta^2) (both forms reduce to this at uniform density);
 * wall rows (DBC layers at y = -(k + 1/2) dx and L + (k + 1/2) dx) have
 * u = 0. Steady state: nu sum_j K_ij (u_i - u_j) + F = 0, an N x N linear
 * system. `shift` offsets the neighbouring rows along x (sheared rows slide
 * past each other): the spread between shifts bounds that effect. With
 * `mirrored` the wall rows carry the mirrored velocity of ghost particles
 * instead (wall row k behind a wall: u = -u of fluid row k from that wall;
 * the ideal mirror, without the interpolation at the mirror points). */
static double row_sum(sluice_sim *sim, double dy, double shift, double dx)
{
    const double h = (double)sim->smoothing_length, support = (double)sim->support;
    double sum = 0;
    for (int m = -64; m <= 64; m++) {
        double x = (m + shift) * dx, r2 = x * x + dy * dy;
        if (r2 == 0 || r2 >= support * support)
            continue;
        double F;
        kernel_value(sim, r2, &F);
        sum += 2 * dx * dx * F * r2 / (r2 + 0.01 * h * h);
    }
    return sum;
}

static void discrete_steady(sluice_sim *sim, int n, double dx, double shift, int mirrored,
                            double *u)
{
    double *a = calloc((size_t)n * (size_t)n, sizeof *a);
    ck_assert_ptr_nonnull(a);
    const double support = (double)sim->support;
    for (int i = 0; i < n; i++) {
        double yi = (i + 0.5) * dx, diagonal = 0;
        for (int j = 0; j < n; j++) {
            if (j == i)
                continue;
            double k = row_sum(sim, yi - (j + 0.5) * dx, shift, dx);
            diagonal += k;
            a[(size_t)i * n + j] = -k;
        }
        for (int w = 0; (w + 1) * dx < support; w++) { /* rows within reach */
            double bottom = row_sum(sim, yi + (w + 0.5) * dx, shift, dx);
            double top = row_sum(sim, yi - P_L - (w + 0.5) * dx, shift, dx);
            diagonal += bottom + top;
            if (mirrored && w < n) { /* K (u_i - (-u_w)) */
                a[(size_t)i * n + w] += bottom;
                a[(size_t)i * n + (n - 1 - w)] += top;
            }
        }
        a[(size_t)i * n + i] += diagonal; /* the mirrored rows may include row i */
        u[i] = -P_F / P_NU;
    }
    /* Gaussian elimination; the matrix is diagonally dominant (symmetric
     * negative definite with walls at rest) */
    for (int k = 0; k < n; k++)
        for (int i = k + 1; i < n; i++) {
            double f = a[(size_t)i * n + k] / a[(size_t)k * n + k];
            for (int j = k; j < n; j++)
                a[(size_t)i * n + j] -= f * a[(size_t)k * n + j];
            u[i] -= f * u[k];
        }
    for (int i = n - 1; i >= 0; i--) {
        double s = u[i];
        for (int j = i + 1; j < n; j++)
            s -= a[(size_t)i * n + j] * u[j];
        u[i] = s / a[(size_t)i * n + i];
    }
    free(a);
}

/* L2 relative difference of two row profiles */
static double row_difference(const double *u, const double *reference, int n)
{
    double num = 0, den = 0;
    for (int i = 0; i < n; i++) {
        num += (u[i] - reference[i]) * (u[i] - reference[i]);
        den += reference[i] * reference[i];
    }
    return sqrt(num / den);
}

typedef struct poiseuille_result {
    unsigned particles;
    int64_t steps;
    double seconds;
    double transient_time, transient_error; /* L2 vs the series at t ~ 0.1 s */
    double steady_error;     /* L2 vs the steady parabola at t_end */
    double model_error;      /* the discrete steady state vs the parabola */
    double model_difference; /* the simulation vs the discrete steady state */
    double model_spread;     /* discrete steady state: shift 0 vs shift dx/2 */
    double transient_bound;  /* slowest discrete mode left at t_end (relative) */
    double wall_zero;        /* where the near-wall profile extrapolates to 0, in dx */
    double max_vy;           /* largest |v_y| / u_max */
} poiseuille_result;

/* L2 relative error of the fluid velocity over all fluid particles against
 * u(y, t); v_y; row means for the comparison with the discrete model. */
static double profile_error(sluice_sim *sim, int steady, double *max_vy, double *rows, int n,
                            double dx)
{
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *ux = test_column(sim, "velocity", 0), *uy = test_column(sim, "velocity", 1);
    double t = sluice_sim_time(sim), num = 0, den = 0, vy = 0;
    int *count = rows ? calloc((size_t)n, sizeof *count) : NULL;
    if (rows) {
        ck_assert_ptr_nonnull(count);
        for (int l = 0; l < n; l++)
            rows[l] = 0;
    }
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        double y = (double)v->position[1][i], u = (double)ux[i];
        double e = steady ? poiseuille_steady(y) : poiseuille_exact(y, t);
        num += (u - e) * (u - e);
        den += e * e;
        vy = fmax(vy, fabs((double)uy[i]));
        if (rows) {
            int l = (int)floor(y / dx);
            ck_assert_msg(l >= 0 && l < n, "a fluid particle left the channel (y = %g)", y);
            rows[l] += u;
            count[l]++;
        }
    }
    if (rows) {
        for (int l = 0; l < n; l++) {
            ck_assert_int_gt(count[l], 0);
            rows[l] /= count[l];
        }
        free(count);
    }
    if (max_vy)
        *max_vy = vy / P_UMAX;
    return sqrt(num / den);
}

/* `walls`: NULL for the scene's dbc, else the line that replaces `dbc: {}`
 * (one line of YAML switches the wall scheme) */
static poiseuille_result run_poiseuille(int across, const char *form, double t_end,
                                        double t_transient, const char *walls)
{
    const double L = P_L, dx = L / across, Lx = P_COLUMNS * dx;
    /* configs/poiseuille_2d.yaml with this resolution, form and end time */
    char *path = test_config("poiseuille_2d.yaml");
    ck_assert_ptr_nonnull(path);
    char *yaml = test_read_file(path);
    ck_assert_msg(yaml != NULL, "cannot read %s", path);
    free(path);
    if (walls) {
        const char *at = strstr(yaml, "  dbc: {}\n");
        ck_assert_ptr_nonnull(at);
        char *switched = NULL;
        ck_assert_int_ge(asprintf(&switched, "%.*s  %s\n%s", (int)(at - yaml), yaml, walls,
                                  at + strlen("  dbc: {}\n")),
                         0);
        free(yaml);
        yaml = switched;
    }
    char sets[10][160];
    snprintf(sets[0], sizeof sets[0], "particles.spacing=%.17g", dx);
    snprintf(sets[1], sizeof sets[1], "particles.smoothing_length_ratio=%g", h_ratio());
    snprintf(sets[2], sizeof sets[2], "time.end=%.17g", t_end);
    snprintf(sets[3], sizeof sets[3], "domain.max=[%.17g, %.17g]", Lx, 1.5 * L);
    snprintf(sets[4], sizeof sets[4], "geometry.fluid.0.max=[%.17g, %.17g]", Lx, L);
    snprintf(sets[5], sizeof sets[5], "geometry.walls.0.points=[[0, 0], [%.17g, 0]]", Lx);
    snprintf(sets[6], sizeof sets[6], "geometry.walls.1.points=[[%.17g, %.17g], [0, %.17g]]", Lx,
             L, L);
    snprintf(sets[7], sizeof sets[7], "plugins.laminar_viscosity.form=%s", form);
    snprintf(sets[8], sizeof sets[8], "plugins.laminar_viscosity.kinematic_viscosity=%g", P_NU);
    snprintf(sets[9], sizeof sets[9], "plugins.gravity.acceleration=[%g, 0]", P_F);
    const char *set_list[10];
    for (int k = 0; k < 10; k++)
        set_list[k] = sets[k];
    sluice_sim *sim = test_load("poiseuille", yaml, set_list, 10);
    free(yaml);
    const sluice_view *v = sluice_sim_view(sim);
    unsigned fluid = 0;
    for (sluice_index i = 0; i < v->count; i++)
        fluid += v->kind[i] == SLUICE_KIND_FLUID;
    ck_assert_int_eq(fluid, across * P_COLUMNS);
    poiseuille_result res;
    memset(&res, 0, sizeof res);
    res.particles = (unsigned)v->count;

    double *model = malloc((size_t)across * sizeof *model);
    double *shifted = malloc((size_t)across * sizeof *shifted);
    double *rows = malloc((size_t)across * sizeof *rows);
    double *parabola = malloc((size_t)across * sizeof *parabola);
    ck_assert(model && shifted && rows && parabola);
    discrete_steady(sim, across, dx, 0, walls != NULL, model);
    discrete_steady(sim, across, dx, 0.5, walls != NULL, shifted);
    for (int l = 0; l < across; l++)
        parabola[l] = poiseuille_steady((l + 0.5) * dx);
    res.model_error = row_difference(model, parabola, across);
    res.model_spread = row_difference(shifted, model, across);

    double start = sluice_wall_clock();
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    int transient_done = t_transient <= 0;
    while (sluice_sim_time(sim) < t_end * (1 - 1e-12)) {
        int status = sluice_sim_step(sim);
        ck_assert_msg(status == SLUICE_RUN_COMPLETE, "Poiseuille %d across (%s) stopped: %s",
                      across, form, sluice_sim_failure(sim));
        if (!transient_done && sluice_sim_time(sim) >= t_transient) {
            res.transient_error = profile_error(sim, 0, NULL, NULL, 0, dx);
            res.transient_time = sluice_sim_time(sim);
            transient_done = 1;
        }
    }
    res.seconds = sluice_wall_clock() - start;
    res.steps = sluice_sim_steps(sim);
    res.steady_error = profile_error(sim, 1, &res.max_vy, rows, across, dx);
    res.model_difference = row_difference(rows, model, across);
    /* the discrete system's slowest mode: its width is at most L + 2 dx
     * (the effective no-slip lies less than dx behind each wall line) */
    double width = L + 2 * dx;
    res.transient_bound = 32 / pow(M_PI, 3) * exp(-M_PI * M_PI * P_NU * t_end / (width * width));
    res.wall_zero = 0.5 - rows[0] / (rows[1] - rows[0]);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    fprintf(stderr,
            "poiseuille %s, %s, %d across, h = %g dx: %u particles, %lld steps, %.1f s\n"
            "  L2 error vs series at t = %.3f s: %.4f; vs steady parabola at t = %.2f s: %.4f\n"
            "  discrete steady state of the same equations: %.4f from the parabola; the "
            "simulation differs from it by %.1e (row shift spread %.1e, transient left %.1e)\n"
            "  near-wall profile extrapolates to zero at y = %+.3f dx; max |v_y| = %.1e u_max\n",
            form, walls ? walls : "dbc walls", across, h_ratio(), res.particles,
            (long long)res.steps, res.seconds, res.transient_time, res.transient_error, t_end,
            res.steady_error, res.model_error, res.model_difference, res.model_spread,
            res.transient_bound, res.wall_zero, res.max_vy);
    free(model);
    free(shifted);
    free(rows);
    free(parabola);
    return res;
}

/* Refinement 10, 20, 40 particles across, to t = 1.5 s, with the transient
 * checked against the series at t = 0.1 s. */
static void check_poiseuille(const char *form)
{
    const int across[3] = {10, 20, 40};
    poiseuille_result r[3];
    for (int k = 0; k < 3; k++)
        r[k] = run_poiseuille(across[k], form, 1.5, 0.1, NULL);
    for (int k = 1; k < 3; k++)
        fprintf(stderr, "poiseuille %s: observed order from %d to %d across: steady %.2f, "
                        "transient %.2f\n",
                form, across[k - 1], across[k],
                log(r[k - 1].steady_error / r[k].steady_error) / log(2.0),
                log(r[k - 1].transient_error / r[k].transient_error) / log(2.0));
    for (int k = 0; k < 3; k++) {
        /* the time-stepped particles reach the steady state of the same
         * discrete equations: the difference is bounded by the sliding of
         * sheared rows and the transient left, with a round-off floor */
        double bound = 2 * r[k].model_spread + r[k].transient_bound + 1e-6;
        ck_assert_msg(r[k].model_difference < bound,
                      "%s %d across: simulation differs from the discrete steady state by %g "
                      "(bound %g)",
                      form, across[k], r[k].model_difference, bound);
        /* a layered flow: no cross-stream velocity beyond lattice noise */
        ck_assert_msg(r[k].max_vy < 0.01, "%s %d across: |v_y| up to %g u_max", form, across[k],
                      r[k].max_vy);
    }
    /* The no-slip of zero-velocity wall particles sits O(dx) behind the wall
     * line (0.67 dx at 40 across): first-order convergence to the analytic
     * profile, slowing towards the constant lattice error of the Laplacian at
     * fixed h/dx (1.6 %, see shear_wave). A ratio above 1.5 per halving of dx
     * (order > 0.58) is what the discrete model guarantees with margin (1.99
     * and 1.88 for h = 1.5 dx). The 2 % at 40 across is not reachable
     * with these walls (9.7 %): it is asserted with ghost-particle walls
     * (poiseuille_ghost_walls); see docs/validation.md. */
    for (int k = 1; k < 3; k++) {
        ck_assert_msg(r[k - 1].steady_error / r[k].steady_error > 1.5,
                      "%s: no convergence from %d to %d across (%g, %g)", form, across[k - 1],
                      across[k], r[k - 1].steady_error, r[k].steady_error);
        ck_assert_msg(r[k - 1].transient_error / r[k].transient_error > 1.5,
                      "%s: transient does not converge from %d to %d across (%g, %g)", form,
                      across[k - 1], across[k], r[k - 1].transient_error, r[k].transient_error);
    }
}

START_TEST(poiseuille) { check_poiseuille(forms[_i]); }
END_TEST

/* Issue 3's 2 % at 40 across, with the walls of seed 004: ghost particles
 * (plugins/walls/mirror_walls.c) carrying the mirrored no-slip velocity
 * v_b = -v_m put the no-slip on the wall line itself instead of O(dx) behind
 * it (DBC), which removes the first-order wall error. What remains is the
 * lattice error of the viscous term at fixed h/dx (1.6 % for h = 1.5 dx, see
 * shear_wave) plus a wall error that falls with dx: the discrete steady state
 * of ideal mirrored walls is 3.7, 2.1 and 1.7 % from the parabola at 10, 20
 * and 40 across, so 2 % is reachable at 40 across and the observed order
 * falls from about 1 towards 0 as the error approaches that floor. Asserted:
 * the 2 %, an error that decreases with every refinement, and a layered flow.
 * The order over three resolutions is printed (and 80 across in
 * tools/poiseuille-study.sh with SCHEME=ghost_particles). */
START_TEST(poiseuille_ghost_walls)
{
    const int across[3] = {10, 20, 40};
    const char *walls = "ghost_particles: {slip: no_slip}";
    poiseuille_result r[3];
    for (int k = 0; k < 3; k++)
        r[k] = run_poiseuille(across[k], "morris", 1.5, 0.1, walls);
    for (int k = 1; k < 3; k++)
        fprintf(stderr,
                "poiseuille morris, ghost walls: observed order from %d to %d across: steady "
                "%.2f, transient %.2f\n",
                across[k - 1], across[k], log(r[k - 1].steady_error / r[k].steady_error) / log(2.0),
                log(r[k - 1].transient_error / r[k].transient_error) / log(2.0));
    for (int k = 0; k < 3; k++) {
        ck_assert_msg(r[k].max_vy < 0.01, "ghost walls, %d across: |v_y| up to %g u_max",
                      across[k], r[k].max_vy);
        if (k > 0)
            ck_assert_msg(r[k].steady_error < r[k - 1].steady_error,
                          "ghost walls: no convergence from %d to %d across (%g, %g)",
                          across[k - 1], across[k], r[k - 1].steady_error, r[k].steady_error);
    }
    ck_assert_msg(r[2].steady_error <= 0.02, "ghost walls, 40 across: L2 error %g",
                  r[2].steady_error);
}
END_TEST

/* tools/poiseuille-study.sh: the resolutions in SLUICE_POISEUILLE_STUDY,
 * one CSV line each on stdout. */
START_TEST(poiseuille_study)
{
    const char *list = getenv("SLUICE_POISEUILLE_STUDY");
    ck_assert_ptr_nonnull(list);
    int across[16], n = 0;
    for (const char *p = list; *p && n < 16;) {
        char *end;
        long a = strtol(p, &end, 10);
        if (end == p)
            break;
        across[n++] = (int)a;
        p = end;
    }
    ck_assert_int_gt(n, 0);
    for (int k = 0; k < n; k++) {
        poiseuille_result r =
            run_poiseuille(across[k], forms[_i], 1.5, 0.1, getenv("SLUICE_POISEUILLE_WALLS"));
        fprintf(stdout, "study,%s,%g,%d,%u,%lld,%.1f,%.5f,%.5f,%.5f,%.2e,%.3f\n", forms[_i],
                h_ratio(), across[k], r.particles, (long long)r.steps, r.seconds,
                r.transient_error, r.steady_error, r.model_error, r.model_difference,
                r.wall_zero);
        fflush(stdout);
    }
}
END_TEST

/* ---------------------------------------------------------- shear wave -- */

/* A decaying shear wave u_x = U sin(k y) in a doubly periodic box (no
 * walls): analytically u decays as exp(-nu k^2 t). On the lattice the SPH
 * term maps each row's sin(k y) onto itself, so the wave decays at
 * nu k^2 R with R = sum_rows K(dy) (1 - cos k dy) / (-k^2) (K as in
 * row_sum): R - 1 is the whole spatial error of the viscous term, the
 * lattice second moment with the eta^2 = 0.01 h^2 regularisation plus
 * O((k h)^2). U = 1e-6 m/s keeps the rows from sliding (U t << dx), and
 * time.max_step = 0.005 / (nu k^2) makes the time-integration error of the
 * decay rate, (nu k^2 R dt)^2 / 6 per step, below 5e-6: the measured rate must
 * follow R to 1e-4. */
static void check_shear_wave(const char *form, int per_wavelength, double *rate_ratio,
                             double *predicted)
{
    const double lambda = 1e-3, dx = lambda / per_wavelength, nu = 1e-6, U = 1e-6;
    const double k = 2 * M_PI / lambda, t_end = 1 / (nu * k * k);
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: %.17g, smoothing_length_ratio: 1.5}\n"
             "time: {end: %.17g, max_step: %.17g}\n"
             "domain: {min: [0, 0], max: [%.17g, %.17g], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [%.17g, %.17g]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 0.01}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  laminar_viscosity: {kinematic_viscosity: %g, form: %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             dx, t_end, 0.005 * t_end, P_COLUMNS * dx, lambda, P_COLUMNS * dx, lambda, nu, form);
    sluice_sim *sim = test_load("shear-wave", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *ux = test_column(sim, "velocity", 0);
    for (sluice_index i = 0; i < v->count; i++)
        ux[i] = (sluice_real)(U * sin(k * (double)v->position[1][i]));
    double sum = 0;
    for (int m = 1; m * dx < (double)sim->support; m++)
        sum += 2 * row_sum(sim, m * dx, 0, dx) * (1 - cos(k * m * dx));
    *predicted = sum / (-k * k);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < t_end * (1 - 1e-12))
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    v = sluice_sim_view(sim);
    ux = test_column(sim, "velocity", 0);
    double num = 0, den = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        double s = sin(k * (double)v->position[1][i]);
        num += ux[i] * s;
        den += s * s;
    }
    double amplitude = num / den, t = sluice_sim_time(sim);
    *rate_ratio = log(U / amplitude) / (nu * k * k * t);
    fprintf(stderr, "shear wave %s, %d particles per wavelength, h = 1.5 dx: decay rate / "
                    "(nu k^2) = %.6f, lattice prediction %.6f (%lld steps)\n",
            form, per_wavelength, *rate_ratio, *predicted, (long long)sluice_sim_steps(sim));
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}

START_TEST(shear_wave)
{
    const int n[3] = {10, 20, 40};
    double ratio[3], predicted[3];
    for (int k = 0; k < 3; k++) {
        check_shear_wave(forms[_i], n[k], &ratio[k], &predicted[k]);
        ck_assert_msg(fabs(ratio[k] - predicted[k]) < 1e-4, "%s, %d per wavelength: decay rate "
                      "%g nu k^2, lattice sums give %g", forms[_i], n[k], ratio[k], predicted[k]);
    }
    /* the viscous term alone meets 2 % at 40 particles per wavelength
     * (lattice prediction 1.9 % for Wendland C2, h = 1.5 dx), and its error
     * falls with resolution towards the fixed-h/dx floor (1.6 %) */
    ck_assert_msg(fabs(ratio[2] - 1) < 0.02, "%s: decay rate off by %g at 40 per wavelength",
                  forms[_i], ratio[2] - 1);
    ck_assert(fabs(ratio[0] - 1) > fabs(ratio[1] - 1) && fabs(ratio[1] - 1) > fabs(ratio[2] - 1));
}
END_TEST

/* ------------------------------------------------------------ time step -- */

/* The viscous limit is 0.125 h^2 / nu, independent of the Courant number,
 * and the core takes the smallest of all limits. */
static double step_limit(double nu, double courant, double c0)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.01, smoothing_length_ratio: 1.5}\n"
             "time: {end: 100}\n"
             "domain: {min: [0, 0], max: [0.2, 0.2], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.2, 0.2]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: %g}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  laminar_viscosity: {kinematic_viscosity: %g}\n"
             "  time_step: {courant: %g}\n"
             "  symplectic: {}\n",
             c0, nu, courant);
    sluice_sim *sim = test_load("viscosity-step", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    double limit = sim->dt_limit;
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return limit;
}

START_TEST(viscous_time_step)
{
    const double h = 1.5 * 0.01;
    for (int k = 0; k < 2; k++) {
        /* fluid at rest: the acoustic limit C h / c0 is 0.2 * 0.015 / 1e-3 = 3 s
         * (6 s with C = 0.4), above the viscous 0.28 s and 0.094 s */
        const double nu = k == 0 ? 1e-4 : 3e-4, courant = k == 0 ? 0.2 : 0.4;
        double expected = 0.125 * h * h / nu, dt = step_limit(nu, courant, 1e-3);
        fprintf(stderr, "viscous limit, nu = %g, C = %g: dt %.6e s, 0.125 h^2/nu = %.6e s\n", nu,
                courant, dt, expected);
        ck_assert_msg(fabs(dt - expected) <= 1e-14 * expected, "dt %.17g, expected %.17g", dt,
                      expected);
    }
    /* with a fast sound speed the acoustic condition is the smaller one */
    const double c0 = 1000, nu = 1e-6, dt = step_limit(nu, 0.2, c0), acoustic = 0.2 * h / c0;
    fprintf(stderr, "c0 = %g: dt %.6e s, acoustic %.6e s, viscous %.6e s\n", c0, dt, acoustic,
            0.125 * h * h / nu);
    ck_assert_msg(fabs(dt - acoustic) <= 1e-12 * acoustic, "dt %.17g, acoustic %.17g", dt,
                  acoustic);
}
END_TEST

/* the published constant */
START_TEST(publishes_kinematic_viscosity)
{
    sluice_sim *sim = periodic_box(2, "lo_shao", 2.5e-3, 1);
    sluice_real nu = 0;
    int found = 0;
    for (uint32_t c = 0; c < sim->constant_count; c++)
        if (strcmp(sim->constants[c].name, "kinematic_viscosity") == 0) {
            found = 1;
            nu = sim->constants[c].values[0];
            ck_assert_uint_eq(sim->constants[c].count, 1);
            ck_assert_str_eq(sim->constants[c].unit, "m^2 s^-1");
        }
    ck_assert_msg(found, "constant 'kinematic_viscosity' not published");
    ck_assert(nu == (sluice_real)2.5e-3);
    sluice_sim_free(sim);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("viscosity");
    TCase *f = tcase_create("formula");
    tcase_add_loop_test(f, formula_2d, 0, 2);
    tcase_add_loop_test(f, formula_3d, 0, 2);
    tcase_add_test(f, publishes_kinematic_viscosity);
    suite_add_tcase(s, f);
    TCase *c = tcase_create("conservation");
    tcase_set_timeout(c, 120);
    tcase_add_loop_test(c, momentum_2d, 0, 2);
    tcase_add_loop_test(c, momentum_3d, 0, 2);
    suite_add_tcase(s, c);
    TCase *p = tcase_create("poiseuille");
    tcase_set_tags(p, "validation"); /* long: release pass only */
    tcase_set_timeout(p, 300);
    tcase_add_loop_test(p, shear_wave, 0, 2);
    tcase_add_loop_test(p, poiseuille, 0, 2);
    tcase_add_test(p, poiseuille_ghost_walls);
    suite_add_tcase(s, p);
    TCase *t = tcase_create("time step");
    tcase_add_test(t, viscous_time_step);
    suite_add_tcase(s, t);
    if (getenv("SLUICE_POISEUILLE_STUDY")) {
        TCase *study = tcase_create("study");
        tcase_set_timeout(study, 36000);
        tcase_add_loop_test(study, poiseuille_study, 0, 2);
        suite_add_tcase(s, study);
    }
    return test_run_suite(s);
}
