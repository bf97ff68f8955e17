/* Hydraulic gauges (issue 5): free_surface_gauge, section_gauge, vorticity,
 * on states whose answer is known.
 *  - A still tank (hydrostatic start, dbc walls): eta within dx/2 of the
 *    water level H at several x, at the start and after 0.05 s. Criterion:
 *    the fluid lattice fills [0, H] with its top row at H - dx/2 and the
 *    first empty row at H + dx/2; a surface estimate must lie between them.
 *    The section gauge of the same tank at rest: d within dx/2 of H, q = 0.
 *  - A lattice block at rest density (V_j = dx^2 exactly, no walls): the
 *    gauge's eta against references computed here by brute force (the
 *    kernel sum of every fluid particle with the Wendland C2 formula written
 *    out): (a) the linear interpolation of that S at the gauge's own two
 *    samples around the surface, to the CSV's 10 digits; (b) the crossing
 *    of S with 1/2 (bisection), within the interpolation bound
 *    (dy^2 / 8) max|S''| / min|S'| on the bracketing interval (derivatives
 *    analytic; maxima over 41 points, doubled); (c) H within dx/2. 3D too.
 *  - Section gauge on that block with u = U0: the Shepard velocity is U0
 *    exactly, so q = U0 times the wet length, to the CSV's digits. The block
 *    and the sample column are symmetric about H/2, so when eta < H the lower
 *    crossing is H - eta and the wet part is [H - eta, eta]; hence
 *    q = U0 (2 d - H) exactly, and |q - U0 d| <= U0 eps with
 *    eps = |eta_ref - H| + the interpolation bound; U = q / d and
 *    Fr = |U| / sqrt(g d) to the CSV's digits, |Fr - U0/sqrt(g d)| <=
 *    U0 eps / (d sqrt(g d)).
 *  - Section gauge with u = a y: the Shepard bias of a linear field near the
 *    bed and the surface (about 0.2 % of q each, one-sided supports) is
 *    antisymmetric about H/2 on the symmetric wet part, and so is the
 *    trapezoid error, so q = a/2 (d^2 - (H - d)^2) = a H (2 d - H) / 2 to the
 *    CSV's digits when d < H (a H^2/2 plus at most a H (d - H) otherwise);
 *    generally |q - a d^2/2| <= 2 a H eps + a eps^2.
 *  - Section gauge with forces on that block under hydrostatic pressure
 *    (linear EOS, reference pressure subtracted) moving at U0: the pressure
 *    force P and momentum flux M exactly as the shear case predicts, and
 *    within the surface's bound of rho0 g d^2/2 and rho0 U0^2 d (with the
 *    compression); see section_momentum_and_pressure.
 *  - Still water over an abrupt drop: the face column's P is the hydrostatic
 *    force on the face's height within rho0 g s dx/2 (the surface's
 *    bound); see section_face_force_at_rest.
 *  - wall_force: the still tank's bottom carries the water's weight and its
 *    side rho0 g H^2/2 (t = 0), the drop's face the same force as the
 *    section column; see wall_force_still_tank, section_face_force_at_rest.
 *  - vorticity: a uniform flow gives 0 to round-off; a rigid rotation
 *    v = Omega x (r - c) gives, at particles with a full support on the
 *    lattice, 2 m Omega with m the lattice second moment of the kernel,
 *    computed here from the formula: equal to round-off, and within
 *    2 |m - 1| Omega of 2 Omega; with renormalise (kernel_correction) 2 Omega
 *    at every fluid particle, free surface and corners included. 2D and 3D.
 *    On demand: the field is not recomputed between output times.
 *  - wall_force in 3D (triangles cut into sub-triangles): the still tank's
 *    floor carries the water's weight, its side rho0 g H^2/2 W, and the
 *    side's moments about the origin rho0 g W H^3/6 and rho0 g H^2 W^2/4;
 *    see wall_force_still_tank_3d.
 *  - Refusals: empty positions, a section gauge in 3D, vorticity listed
 *    after the hdf5 writer. */
#include <math.h>

#include "sim_util.h"

/* ------------------------------------------------------------ helpers -- */

/* Wendland C2 written out (docs/physics.md), support 2h: W and F = (dW/dr)/r. */
static double wendland_norm(double h, int dims)
{
    return dims == 3 ? 21.0 / (16.0 * M_PI * h * h * h) : 7.0 / (4.0 * M_PI * h * h);
}

static double wendland_w(double r, double h, int dims)
{
    double q = r / h;
    if (q >= 2)
        return 0;
    double t = 1 - q / 2;
    return wendland_norm(h, dims) * t * t * t * t * (2 * q + 1);
}

static double wendland_f(double r, double h, int dims)
{
    double q = r / h;
    if (q >= 2)
        return 0;
    double t = 1 - q / 2;
    return -5 * wendland_norm(h, dims) * t * t * t / (h * h);
}

/* dF/dr */
static double wendland_df(double r, double h, int dims)
{
    double q = r / h;
    if (q >= 2)
        return 0;
    double t = 1 - q / 2;
    return 7.5 * wendland_norm(h, dims) * t * t / (h * h * h);
}

/* The core writes CSV values with "%.10g": relative rounding at most 5e-10
 * per value, so a relation of three printed values holds to 1.5e-9. */
#define CSV_DIGITS 2e-9

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

/* Reads the last data row of a CSV into values; returns the count. */
static int last_row(const char *path, double *values, int max)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char line[16384], last[16384] = "";
    int rows = 0;
    while (fgets(line, sizeof line, f))
        if (rows++ > 0)
            memcpy(last, line, sizeof last);
    fclose(f);
    int n = 0;
    char *p = last;
    while (*p && n < max) {
        char *end;
        double value = strtod(p, &end);
        if (end == p)
            break;
        values[n++] = value;
        p = *end == ',' ? end + 1 : end;
    }
    return n;
}

static char *out_file(const char *dir, const char *name)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", dir, name), 0);
    return path;
}

/* Runs begin (the gauges sample t = 0) and end; returns the output dir. */
static char *sample_now(sluice_sim *sim, const char *tag)
{
    char *dir = test_scratch(tag);
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    return dir;
}

/* Brute-force kernel sum of the fluid at (x, y) and its first and second
 * derivatives along y (2D). */
typedef struct column_ref {
    sluice_sim *sim;
    double h;
} column_ref;

static void kernel_sum(const column_ref *c, double x, double y, double *S, double *dS,
                       double *d2S)
{
    const sluice_view *v = sluice_sim_view(c->sim);
    const sluice_real *m = test_column(c->sim, "mass", 0);
    const sluice_real *rho = test_column(c->sim, "density", 0);
    double s = 0, ds = 0, d2s = 0;
    for (sluice_index j = 0; j < v->count; j++) {
        if (v->kind[j] != SLUICE_KIND_FLUID)
            continue;
        double ex = x - (double)v->position[0][j], ey = y - (double)v->position[1][j];
        double r = sqrt(ex * ex + ey * ey);
        if (r >= 2 * c->h)
            continue;
        double V = (double)m[j] / (double)rho[j];
        double F = wendland_f(r, c->h, 2);
        s += V * wendland_w(r, c->h, 2);
        ds += V * F * ey;
        /* d/dy (F ey) = F + (dF/dr) ey^2 / r */
        d2s += V * (F + (r > 0 ? wendland_df(r, c->h, 2) * ey * ey / r : 0));
    }
    *S = s;
    if (dS)
        *dS = ds;
    if (d2S)
        *d2S = d2s;
}

/* The crossing of S = level in [lo, hi] (S - level changes sign), by bisection. */
static double crossing(const column_ref *c, double x, double lo, double hi, double level)
{
    double slo;
    kernel_sum(c, x, lo, &slo, NULL, NULL);
    for (int it = 0; it < 80; it++) {
        double mid = 0.5 * (lo + hi), sm;
        kernel_sum(c, x, mid, &sm, NULL, NULL);
        if ((sm - level > 0) == (slo - level > 0)) {
            lo = mid;
            slo = sm;
        } else {
            hi = mid;
        }
    }
    return 0.5 * (lo + hi);
}

/* The gauge's samples: bottom + (top - bottom) i / n with n intervals of at
 * most dy. Returns the bound (dy'^2/8) max|S''| / min|S'| (doubled) of the
 * linear interpolation of S on the sample interval holding y. */
static double interpolation_bound(const column_ref *c, double x, double bottom, double top,
                                  double dy, double y)
{
    double n = ceil((top - bottom) / dy * (1 - 1e-12));
    double step = (top - bottom) / n;
    double i = floor((y - bottom) / step);
    double a = bottom + i * step, b = a + step;
    double max2 = 0, min1 = INFINITY;
    for (int k = 0; k <= 40; k++) {
        double S, d1, d2;
        kernel_sum(c, x, a + (b - a) * k / 40.0, &S, &d1, &d2);
        max2 = fmax(max2, fabs(d2));
        min1 = fmin(min1, fabs(d1));
    }
    return 2 * step * step / 8 * max2 / min1;
}

/* ---------------------------------------------------- the still tank -- */

static const char *tank_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.05}\n"
    "domain: {min: [-0.2, -0.2], max: [1.2, 1.0]}\n"
    "geometry:\n"
    "  fluid: [{shape: box, min: [0, 0], max: [1.0, 0.5]}]\n"
    "  walls: [{shape: tank, min: [0, 0], max: [1.0, 0.8]}]\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 22.1}\n"
    "  continuity: {}\n"
    "  delta_sph: {delta: 0.1, form: fourtakas}\n"
    "  pressure_gradient: {}\n"
    "  artificial_viscosity: {alpha: 0.1}\n"
    "  gravity: {}\n"
    "  dbc: {}\n"
    "  time_step: {}\n"
    "  symplectic: {}\n"
    "  free_surface_gauge: {positions: [0.1, 0.33, 0.5, 0.77, 0.9, 1.15], interval: 0.05}\n"
    "  section_gauge: {positions: [0.25, 0.5], interval: 0.05}\n";

START_TEST(free_surface_still_tank)
{
    const double H = 0.5, dx = 0.02;
    const double xs[] = {0.1, 0.33, 0.5, 0.77, 0.9, 1.15};
    sluice_sim *sim = test_load("fs-tank", tank_scene, NULL, 0);
    char *dir = test_scratch("fs-tank-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < 0.05 - 1e-12)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    char *path = out_file(dir, "free_surface.csv");
    double rows[2][16];
    ck_assert_int_eq(first_row(path, rows[0], 16), 7);
    ck_assert_int_eq(last_row(path, rows[1], 16), 7);
    ck_assert(rows[0][0] == 0 && fabs(rows[1][0] - 0.05) < 1e-12);
    for (int r = 0; r < 2; r++) {
        for (int k = 0; k < 5; k++) {
            double eta = rows[r][1 + k];
            fprintf(stderr, "still tank t = %.2f s, x = %.2f m: eta = %.6f m, eta - H = %+.2e m "
                            "(%.4f dx)\n",
                    rows[r][0], xs[k], eta, eta - H, (eta - H) / dx);
            ck_assert_msg(fabs(eta - H) <= dx / 2, "t = %g, x = %g: eta = %.6f, H = %g",
                          rows[r][0], xs[k], eta, H);
        }
        /* behind the right wall: no fluid */
        ck_assert_msg(isnan(rows[r][6]), "x = 1.15: eta = %g, expected nan", rows[r][6]);
    }
    free(path);
    /* sections of the tank: at rest at t = 0 (q = U = Fr = 0 exactly), the
     * depth within dx/2 of H at both times */
    path = out_file(dir, "sections.csv");
    double s[2][16];
    ck_assert_int_eq(first_row(path, s[0], 16), 9);
    ck_assert_int_eq(last_row(path, s[1], 16), 9);
    for (int r = 0; r < 2; r++)
        for (int k = 0; k < 2; k++) {
            const double d = s[r][1 + 4 * k], q = s[r][2 + 4 * k], U = s[r][3 + 4 * k],
                         Fr = s[r][4 + 4 * k];
            fprintf(stderr, "still tank t = %.2f s, section %d: d = %.6f m, q = %.3e m^2/s, "
                            "U = %.3e m/s, Fr = %.3e\n",
                    s[r][0], k, d, q, U, Fr);
            ck_assert_msg(fabs(d - H) <= dx / 2, "section %d: d = %g", k, d);
            ck_assert_msg(r == 1 || (q == 0 && U == 0 && Fr == 0),
                          "section %d at rest: q = %g, U = %g, Fr = %g", k, q, U, Fr);
        }
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* ------------------------------------------------- the lattice block -- */

/* H = 0.2 m block at rest density, dx = 0.01 m, no walls: symmetric about
 * H/2; the section column [0, 0.3] at dy = dx/4 is too (H / dy = 80). */
#define BLOCK_SCENE(eos, gauges)                                                                  \
    "dimensions: 2\n"                                                                              \
    "particles: {spacing: 0.01, smoothing_length_ratio: 1.5}\n"                                    \
    "time: {end: 0.01}\n"                                                                          \
    "domain: {min: [-0.1, -0.1], max: [0.7, 0.3]}\n"                                               \
    "initial: {density: rest}\n"                                                                   \
    "geometry:\n"                                                                                  \
    "  fluid: [{shape: box, min: [0, 0], max: [0.6, 0.2]}]\n"                                      \
    "plugins:\n"                                                                                   \
    "  wendland_c2: {}\n"                                                                          \
    "  " eos "\n"                                                                                  \
    "  continuity: {}\n"                                                                           \
    "  pressure_gradient: {}\n"                                                                    \
    "  gravity: {}\n"                                                                              \
    "  time_step: {}\n"                                                                            \
    "  symplectic: {}\n" gauges

static const char *block_scene =
    BLOCK_SCENE("tait: {speed_of_sound: 20}",
                "  free_surface_gauge: {positions: [0.3, 0.3025]}\n"
                "  section_gauge: {positions: [0.3, 0.3025], bed_elevation: [0]}\n");

#define BLOCK_H 0.2
#define BLOCK_DX 0.01

/* The references at a gauge x on the block, for a sample column
 * [bottom, top]: eta_ref the crossing of the brute-force S with 1/2, bound
 * the interpolation bound on its sample interval, eta_lin the linear
 * interpolation of the brute-force S at the gauge's own two samples around
 * it (what the gauge must reproduce to round-off), eps = |eta_ref - H| +
 * bound. */
typedef struct block_ref {
    double eta_ref, bound, eta_lin, eps;
} block_ref;

static block_ref block_reference(sluice_sim *sim, double x, double bottom, double top)
{
    column_ref c = {sim, 1.5 * BLOCK_DX};
    block_ref r;
    r.eta_ref = crossing(&c, x, BLOCK_H - 2 * BLOCK_DX, BLOCK_H + 2 * BLOCK_DX, 0.5);
    r.bound = interpolation_bound(&c, x, bottom, top, BLOCK_DX / 4, r.eta_ref);
    r.eps = fabs(r.eta_ref - BLOCK_H) + r.bound;
    const double n = ceil((top - bottom) / (BLOCK_DX / 4) * (1 - 1e-12));
    const double i = floor((r.eta_ref - bottom) / ((top - bottom) / n));
    const double a = bottom + (top - bottom) * i / n, b = bottom + (top - bottom) * (i + 1) / n;
    double Sa, Sb;
    kernel_sum(&c, x, a, &Sa, NULL, NULL);
    kernel_sum(&c, x, b, &Sb, NULL, NULL);
    ck_assert(Sa >= 0.5 && Sb < 0.5);
    r.eta_lin = a + (Sa - 0.5) / (Sa - Sb) * (b - a);
    return r;
}

START_TEST(free_surface_against_kernel_sum)
{
    sluice_sim *sim = test_load("fs-block", block_scene, NULL, 0);
    const double xs[] = {0.3, 0.3025};
    block_ref ref[2];
    for (int k = 0; k < 2; k++)
        ref[k] = block_reference(sim, xs[k], -0.1, 0.3);
    char *dir = sample_now(sim, "fs-block-out");
    char *path = out_file(dir, "free_surface.csv");
    double row[8];
    ck_assert_int_eq(first_row(path, row, 8), 3);
    for (int k = 0; k < 2; k++) {
        const double eta = row[1 + k];
        const block_ref *r = &ref[k];
        fprintf(stderr, "block x = %.4f m: eta = %.9f m; crossing of the brute-force S %.9f m "
                        "(- H = %+.3e m), gauge - crossing = %+.3e m (interpolation bound "
                        "%.3e m); gauge - own interpolation of the brute-force S = %+.3e m\n",
                xs[k], eta, r->eta_ref, r->eta_ref - BLOCK_H, eta - r->eta_ref, r->bound,
                eta - r->eta_lin);
        ck_assert_msg(fabs(eta - r->eta_lin) <= CSV_DIGITS * eta, "x = %g: eta %.10f, %.10f",
                      xs[k], eta, r->eta_lin);
        ck_assert_msg(fabs(eta - r->eta_ref) <= r->bound, "x = %g: eta %.9f, reference %.9f, "
                                                           "bound %g",
                      xs[k], eta, r->eta_ref, r->bound);
        ck_assert_msg(fabs(eta - BLOCK_H) <= BLOCK_DX / 2, "x = %g: eta %.9f", xs[k], eta);
    }
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* 3D: the vertical is z; a 0.2 m cube of fluid at rest density, gauges at
 * (x, y) = (0.1, 0.1) and (0.05, 0.13): eta within dx/2 of 0.2 m. */
static char *vortex_scene(int dims, const char *extra);

START_TEST(free_surface_3d)
{
    char *yaml = vortex_scene(3, "  free_surface_gauge: {positions: [0.1, 0.05], lateral: [0.1, "
                                 "0.13]}\n");
    sluice_sim *sim = test_load("fs-3d", yaml, NULL, 0);
    free(yaml);
    char *dir = sample_now(sim, "fs-3d-out");
    char *path = out_file(dir, "free_surface.csv");
    double row[8];
    ck_assert_int_eq(first_row(path, row, 8), 3);
    for (int k = 0; k < 2; k++) {
        fprintf(stderr, "3D cube, gauge %d: eta = %.6f m, eta - H = %+.3e m (%.4f dx)\n", k,
                row[1 + k], row[1 + k] - 0.2, (row[1 + k] - 0.2) / 0.02);
        ck_assert_msg(fabs(row[1 + k] - 0.2) <= 0.02 / 2, "gauge %d: eta = %g", k, row[1 + k]);
    }
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* Sets u = U0 + a y, v = 0 on every fluid particle. */
static void set_flow(sluice_sim *sim, double U0, double a)
{
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *u = test_column(sim, "velocity", 0), *w = test_column(sim, "velocity", 1);
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            u[i] = (sluice_real)(U0 + a * (double)v->position[1][i]);
            w[i] = 0;
        }
}

/* The wet part of the section column on the symmetric block: [H - eta, eta]
 * when eta < H (S is symmetric about H/2, so is the sample column, and the
 * lower crossing mirrors the upper one), else [0, eta]. */
START_TEST(section_uniform_flow)
{
    const double U0 = 0.8, g = 9.81;
    sluice_sim *sim = test_load("section-uniform", block_scene, NULL, 0);
    set_flow(sim, U0, 0);
    const double xs[] = {0.3, 0.3025};
    block_ref ref[2];
    for (int k = 0; k < 2; k++)
        ref[k] = block_reference(sim, xs[k], 0, 0.3);
    char *dir = sample_now(sim, "section-uniform-out");
    char *path = out_file(dir, "sections.csv");
    double row[16];
    ck_assert_int_eq(first_row(path, row, 16), 9);
    for (int k = 0; k < 2; k++) {
        const double d = row[1 + 4 * k], q = row[2 + 4 * k], U = row[3 + 4 * k],
                     Fr = row[4 + 4 * k];
        const double Fr0 = U0 / sqrt(g * d), eps = ref[k].eps;
        const double wet = d < BLOCK_H ? 2 * d - BLOCK_H : d;
        fprintf(stderr, "uniform u = %g m/s, x = %.4f: d = %.9f m (own interpolation %.9f), "
                        "q = %.9f m^2/s, U0 d = %.9f, q - U0 d = %+.3e (bound U0 eps = %.3e), "
                        "q - U0 x wet length = %+.3e; U = %.9f m/s, Fr = %.9f, U0/sqrt(g d) = "
                        "%.9f\n",
                U0, xs[k], d, ref[k].eta_lin, q, U0 * d, q - U0 * d, U0 * eps, q - U0 * wet, U,
                Fr, Fr0);
        ck_assert_msg(fabs(d - ref[k].eta_lin) <= CSV_DIGITS * d, "d = %.10f, %.10f", d,
                      ref[k].eta_lin);
        ck_assert_msg(fabs(d - BLOCK_H) <= eps, "d = %.9f, eps %g", d, eps);
        /* the Shepard velocity is U0 exactly: q = U0 x the wet length */
        ck_assert_msg(fabs(q - U0 * wet) <= CSV_DIGITS * q, "q = %.10f, U0 wet = %.10f", q,
                      U0 * wet);
        ck_assert_msg(fabs(q - U0 * d) <= U0 * eps, "q = %.9f, U0 d = %.9f", q, U0 * d);
        ck_assert_msg(fabs(U - q / d) <= CSV_DIGITS * fabs(U), "U = %.12g, q/d = %.12g", U,
                      q / d);
        ck_assert_msg(fabs(Fr - fabs(U) / sqrt(g * d)) <= CSV_DIGITS * Fr, "Fr = %.12g", Fr);
        ck_assert_msg(fabs(Fr - Fr0) <= Fr0 * eps / d, "Fr = %.9f, U0/sqrt(g d) = %.9f", Fr,
                      Fr0);
    }
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

START_TEST(section_linear_shear)
{
    const double a = 2.0; /* s^-1 */
    sluice_sim *sim = test_load("section-shear", block_scene, NULL, 0);
    set_flow(sim, 0, a);
    const double xs[] = {0.3, 0.3025};
    block_ref ref[2];
    for (int k = 0; k < 2; k++)
        ref[k] = block_reference(sim, xs[k], 0, 0.3);
    char *dir = sample_now(sim, "section-shear-out");
    char *path = out_file(dir, "sections.csv");
    double row[16];
    ck_assert_int_eq(first_row(path, row, 16), 9);
    const double H = BLOCK_H;
    for (int k = 0; k < 2; k++) {
        const double d = row[1 + 4 * k], q = row[2 + 4 * k], eps = ref[k].eps;
        const double tol = 2 * a * H * eps + a * eps * eps;
        fprintf(stderr, "shear u = %g y, x = %.4f: d = %.9f m, q = %.9f m^2/s, a d^2/2 = %.9f, "
                        "difference %+.3e (relative %+.2e; bound %.3e); exact integral over the "
                        "wet part %.9f, q - it = %+.3e\n",
                a, xs[k], d, q, a * d * d / 2, q - a * d * d / 2, (q - a * d * d / 2) / q, tol,
                d < H ? a * H * (2 * d - H) / 2 : a * H * H / 2, d < H ? q - a * H * (2 * d - H) / 2
                                                                         : q - a * H * H / 2);
        ck_assert_msg(fabs(q - a * d * d / 2) <= tol, "q = %.9f, a d^2/2 = %.9f, bound %g", q,
                      a * d * d / 2, tol);
        /* sharp: the Shepard bias cancels over the symmetric wet part
         * [H - d, d] (d < H): q = a/2 (d^2 - (H - d)^2) = a H (2 d - H) / 2;
         * for d >= H, q = a H^2/2 + the part above H, between 0 and a H (d - H) */
        if (d < H)
            ck_assert_msg(fabs(q - a * H * (2 * d - H) / 2) <= 3 * CSV_DIGITS * q,
                          "q = %.10f, a H (2d - H)/2 = %.10f", q, a * H * (2 * d - H) / 2);
        else
            ck_assert_msg(q >= a * H * H / 2 * (1 - 3 * CSV_DIGITS) &&
                              q <= a * H * H / 2 + a * H * (d - H) + 3 * CSV_DIGITS * q,
                          "q = %.10f, d = %.10f", q, d);
    }
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* The block under hydrostatic pressure, moving at U0: linear equation of
 * state p - p0 = c^2 (rho - rho0) with p0 = 1000 Pa (which the gauge must
 * subtract), rho_j = rho0 (1 + g (H - y_j) / c^2) so that p_j - p0 =
 * rho0 g (H - y_j), and m_j = rho_j dx^2 so that V_j = dx^2 exactly (the
 * kernel sum, eta and the wet part are the rest block's).
 * p - p0 = rho0 g H - rho0 g y is a constant minus the shear of
 * section_linear_shear with a = rho0 g, so over the wet part
 *   P = rho0 g H wet - rho0 g q_shear:
 *   d < H:  P = rho0 g H (2 d - H) / 2 to the CSV's digits;
 *   d >= H: rho0 g H^2/2 <= P <= rho0 g H^2/2 + rho0 g H (d - H);
 * and |P - rho0 g d^2/2| <= rho0 g (H eps + eps^2/2) either way (the
 * hydrostatic force on the depth d). rho u^2 = U0^2 rho is linear in y too,
 * with rho = rho0 + (p - p0) / c^2, so M = U0^2 (rho0 wet + P / c^2) to the
 * CSV's digits, and |M - U0^2 (rho0 d + rho0 g d^2 / (2 c^2))| <=
 * U0^2 (rho0 eps + rho0 g (H eps + eps^2/2) / c^2). */
static const char *block_forces_scene =
    BLOCK_SCENE("linear_eos: {speed_of_sound: 20, reference_pressure: 1000}",
                "  section_gauge: {positions: [0.3, 0.3025], bed_elevation: [0], forces: true}\n");

START_TEST(section_momentum_and_pressure)
{
    const double U0 = 0.8, g = 9.81, c = 20, rho0 = 1000, H = BLOCK_H, dx = BLOCK_DX;
    sluice_sim *sim = test_load("section-forces", block_forces_scene, NULL, 0);
    set_flow(sim, U0, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *rho = test_column(sim, "density", 0), *m = test_column(sim, "mass", 0);
    /* the gauge evaluates the state before its t = 0 row: the equation of
     * state turns these densities into the pressures */
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            const double density = rho0 * (1 + g * (H - (double)v->position[1][i]) / (c * c));
            rho[i] = (sluice_real)density;
            m[i] = (sluice_real)(density * dx * dx);
        }
    const double xs[] = {0.3, 0.3025};
    block_ref ref[2];
    for (int k = 0; k < 2; k++)
        ref[k] = block_reference(sim, xs[k], 0, 0.3);
    char *dir = sample_now(sim, "section-forces-out");
    char *path = out_file(dir, "sections.csv");
    double row[16];
    ck_assert_int_eq(first_row(path, row, 16), 13);
    for (int k = 0; k < 2; k++) {
        const double d = row[1 + 6 * k], M = row[5 + 6 * k], P = row[6 + 6 * k];
        const double eps = ref[k].eps, wet = d < H ? 2 * d - H : d;
        const double P_h = rho0 * g * d * d / 2;
        const double M_h = U0 * U0 * (rho0 * d + rho0 * g * d * d / (2 * c * c));
        fprintf(stderr, "block under hydrostatic pressure, u = %g m/s, x = %.4f: d = %.9f m, "
                        "P = %.6f N/m (rho0 g d^2/2 = %.6f, difference %+.2e), M = %.6f N/m "
                        "(U0^2 integral of rho = %.6f, difference %+.2e); eps = %.2e m\n",
                U0, xs[k], d, P, P_h, P - P_h, M, M_h, M - M_h, eps);
        if (d < H)
            ck_assert_msg(fabs(P - rho0 * g * H * (2 * d - H) / 2) <= 3 * CSV_DIGITS * P,
                          "P = %.10f, rho0 g H (2d - H)/2 = %.10f", P,
                          rho0 * g * H * (2 * d - H) / 2);
        else
            ck_assert_msg(P >= rho0 * g * H * H / 2 * (1 - 3 * CSV_DIGITS) &&
                              P <= rho0 * g * H * H / 2 + rho0 * g * H * (d - H) +
                                       3 * CSV_DIGITS * P,
                          "P = %.10f, d = %.10f", P, d);
        ck_assert_msg(fabs(P - P_h) <= rho0 * g * (H * eps + eps * eps / 2), "P = %.9f, %.9f",
                      P, P_h);
        ck_assert_msg(fabs(M - U0 * U0 * (rho0 * wet + P / (c * c))) <= 3 * CSV_DIGITS * M,
                      "M = %.10f, U0^2 (rho0 wet + P/c^2) = %.10f", M,
                      U0 * U0 * (rho0 * wet + P / (c * c)));
        ck_assert_msg(fabs(M - M_h) <=
                          U0 * U0 * (rho0 * eps + rho0 * g * (H * eps + eps * eps / 2) / (c * c)),
                      "M = %.9f, %.9f", M, M_h);
    }
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* Still water over an abrupt drop (seed 004's geometry, scaled: a step
 * s = 0.04 m = 4 dx high, dbc walls, the lower bed starting inside the
 * step as in the abrupt_drop scenes), surface about 0.14 m above the lower
 * bed. A section column 1.5 dx in front of the face, from its foot to its
 * crest, is wet to its top, so its P is the pressure force on the face's
 * height; at rest it must be the hydrostatic rho0 g s (eta - s/2), eta the
 * surface read by a full section 0.15 m downstream. Means over 0.25-0.5 s
 * (the start's acoustic waves average out). Bound: the gauge locates eta
 * within dx/2 of the water's top (free_surface_still_tank), which moves
 * the hydrostatic force by rho0 g s dx/2; the full section's P against
 * rho0 g d^2/2 within rho0 g d dx/2 likewise. */
static const char *drop_still_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.01, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.5}\n"
    "domain: {min: [-0.1, -0.1], max: [0.7, 0.3]}\n"
    "geometry:\n"
    "  fluid:\n"
    "    - {shape: box, min: [0, 0.04], max: [0.3, 0.14], lattice_origin: [0, 0.04]}\n"
    "    - {shape: box, min: [0.3, 0], max: [0.6, 0.14]}\n"
    "  walls:\n"
    "    - {shape: polyline, points: [[0, 0.25], [0, 0.04], [0.3, 0.04], [0.3, 0]],\n"
    "       lattice_origin: [0, 0.04], name: step}\n"
    "    - {shape: polyline, points: [[0.26, 0], [0.6, 0], [0.6, 0.25]]}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  linear_eos: {speed_of_sound: 30}\n"
    "  continuity: {form: mass}\n"
    "  pressure_gradient: {form: symmetric}\n"
    "  artificial_viscosity: {alpha: 0.1}\n"
    "  gravity: {}\n"
    "  dbc: {}\n"
    "  time_step: {courant: 0.2}\n"
    "  predictor_corrector: {}\n"
    "  section_gauge: {positions: [0.315, 0.45], bed_elevation: [0, 0], top: [0.04, 0.3], "
    "forces: true, interval: 0.01}\n"
    "  wall_force: {walls: step, box_min: [0.29, 0.0005], box_max: [0.31, 0.0395], "
    "interval: 0.01}\n";

START_TEST(section_face_force_at_rest)
{
    const double rho0 = 1000, g = 9.81, s = 0.04, dx = 0.01;
    sluice_sim *sim = test_load("drop-still", drop_still_scene, NULL, 0);
    char *dir = test_scratch("drop-still-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < 0.5 - 1e-12)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    char *path = out_file(dir, "sections.csv");
    FILE *f = fopen(path, "r");
    ck_assert_ptr_nonnull(f);
    char line[4096];
    ck_assert_ptr_nonnull(fgets(line, sizeof line, f));
    ck_assert_ptr_nonnull(strstr(line, "time,d_x0,q_x0,U_x0,Fr_x0,M_x0,P_x0,d_x1"));
    double face = 0, depth = 0, full = 0, face_depth_min = 1, face_depth_max = 0;
    int rows = 0;
    while (fgets(line, sizeof line, f)) {
        double v[13];
        int n = 0;
        char *p = line;
        while (*p && n < 13) {
            char *end;
            v[n++] = strtod(p, &end);
            p = *end == ',' ? end + 1 : end;
        }
        ck_assert_int_eq(n, 13);
        if (v[0] < 0.25 - 1e-9)
            continue;
        face += v[6];
        depth += v[7];
        full += v[12];
        face_depth_min = fmin(face_depth_min, v[1]);
        face_depth_max = fmax(face_depth_max, v[1]);
        rows++;
    }
    fclose(f);
    ck_assert_int_ge(rows, 25);
    face /= rows;
    depth /= rows;
    full /= rows;
    const double hydrostatic = rho0 * g * s * (depth - s / 2);
    fprintf(stderr, "still water over a %.2f m drop, means over 0.25-0.5 s (%d rows): surface "
                    "%.5f m; face column P = %.4f N/m, rho0 g s (eta - s/2) = %.4f N/m (ratio "
                    "%.4f, bound %.4f N/m); full section P = %.4f N/m, rho0 g d^2/2 = %.4f "
                    "(bound %.4f)\n",
            s, rows, depth, face, hydrostatic, face / hydrostatic, rho0 * g * s * dx / 2, full,
            rho0 * g * depth * depth / 2, rho0 * g * depth * dx / 2);
    /* the face column is wet to its top in every row */
    ck_assert_msg(face_depth_min == s && face_depth_max == s, "face column depth %g .. %g",
                  face_depth_min, face_depth_max);
    ck_assert_msg(fabs(face - hydrostatic) <= rho0 * g * s * dx / 2, "face P = %.4f, %.4f", face,
                  hydrostatic);
    ck_assert_msg(fabs(full - rho0 * g * depth * depth / 2) <= rho0 * g * depth * dx / 2,
                  "full section P = %.4f, %.4f", full, rho0 * g * depth * depth / 2);
    free(path);
    /* wall_force on the face (the part of wall 'step' in the box): the
     * fluid pushes it in -x, by the same hydrostatic force within the same
     * bound; the face is wet over its whole height 0.04 m */
    path = out_file(dir, "wall_forces.csv");
    f = fopen(path, "r");
    ck_assert_ptr_nonnull(f);
    ck_assert_ptr_nonnull(fgets(line, sizeof line, f));
    ck_assert_str_eq(line, "time,Fx_step,Fy_step,wet_step\n");
    double fx = 0, fy = 0, wet_min = 1, wet_max = 0;
    int wall_rows = 0;
    while (fgets(line, sizeof line, f)) {
        double t, a, b, w;
        ck_assert_int_eq(sscanf(line, "%lf,%lf,%lf,%lf", &t, &a, &b, &w), 4);
        if (t < 0.25 - 1e-9)
            continue;
        fx += a;
        fy += b;
        wet_min = fmin(wet_min, w);
        wet_max = fmax(wet_max, w);
        wall_rows++;
    }
    fclose(f);
    ck_assert_int_eq(wall_rows, rows);
    fx /= wall_rows;
    fy /= wall_rows;
    fprintf(stderr, "wall_force on the face: Fx = %.4f N/m (hydrostatic -%.4f, ratio %.4f), Fy = "
                    "%.3g, wet %.4f .. %.4f m\n",
            fx, hydrostatic, -fx / hydrostatic, fy, wet_min, wet_max);
    ck_assert_msg(fabs(-fx - hydrostatic) <= rho0 * g * s * dx / 2, "Fx = %.4f, %.4f", fx,
                  hydrostatic);
    ck_assert_msg(fabs(fy) <= 1e-9 * fabs(fx), "Fy = %g on a vertical face", fy);
    ck_assert_msg(fabs(wet_min - s) <= 1e-12 && fabs(wet_max - s) <= 1e-12, "wet %g .. %g",
                  wet_min, wet_max);
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* wall_force on the still tank (dbc, 1 m wide, H = 0.5 m, dx = 0.02 m) at
 * t = 0, the hydrostatic start (p_j = rho0 g (H - y_j) to 1e-9): on the
 * whole tank Fx = 0 (the two sides cancel: the lattice and the tank are
 * symmetric) and Fy = -rho0 g H L (the water's weight on the bottom); on the
 * left side alone (a box) Fx = -rho0 g H^2/2. Bounds: the Shepard pressure
 * is exact for p linear in y where the kernel support is whole in y; it is
 * one-sided within 2h of the surface and of the bottom, where its bias is
 * at most rho0 g h (the support's centroid moves by at most h), over a
 * length of at most 2h at each end of a side: |dFx| <= 4 rho0 g h^2; along
 * the bottom the sample points (offset dx) are in the one-sided band, so
 * |dFy| <= rho0 g h L. The wet length of a side is H within 2h. */
static const char *wall_force_tank_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.01}\n"
    "domain: {min: [-0.2, -0.2], max: [1.2, 1.0]}\n"
    "geometry:\n"
    "  fluid: [{shape: box, min: [0, 0], max: [1.0, 0.5]}]\n"
    "  walls: [{shape: tank, min: [0, 0], max: [1.0, 0.8], name: tank}]\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 22.1}\n"
    "  continuity: {}\n"
    "  pressure_gradient: {}\n"
    "  gravity: {}\n"
    "  dbc: {}\n"
    "  time_step: {}\n"
    "  symplectic: {}\n"
    "  wall_force: {%s}\n";

START_TEST(wall_force_still_tank)
{
    const double rho0 = 1000, g = 9.81, H = 0.5, L = 1.0, h = 0.03;
    for (int side = 0; side < 2; side++) {
        char *yaml = NULL;
        ck_assert(asprintf(&yaml, wall_force_tank_scene,
                           side ? "walls: tank, box_min: [-0.1, -0.1], box_max: [0.001, 0.9]"
                                : "walls: tank") > 0);
        sluice_sim *sim = test_load(side ? "wf-side" : "wf-tank", yaml, NULL, 0);
        free(yaml);
        char *dir = sample_now(sim, side ? "wf-side-out" : "wf-tank-out");
        char *path = out_file(dir, "wall_forces.csv");
        double row[4];
        ck_assert_int_eq(first_row(path, row, 4), 4);
        fprintf(stderr, "wall_force, still tank at t = 0 (%s): Fx = %.4f N/m, Fy = %.4f N/m, wet "
                        "%.4f m; rho0 g H^2/2 = %.4f, rho0 g H L = %.4f\n",
                side ? "left side" : "whole tank", row[1], row[2], row[3],
                rho0 * g * H * H / 2, rho0 * g * H * L);
        if (side) {
            ck_assert_msg(fabs(row[1] + rho0 * g * H * H / 2) <= 4 * rho0 * g * h * h,
                          "Fx = %.4f", row[1]);
            ck_assert_msg(row[2] == 0, "Fy = %g on a vertical side", row[2]);
            ck_assert_msg(fabs(row[3] - H) <= 2 * h, "wet %g", row[3]);
        } else {
            ck_assert_msg(fabs(row[1]) <= 1e-9 * rho0 * g * H * H / 2, "Fx = %g", row[1]);
            ck_assert_msg(fabs(row[2] + rho0 * g * H * L) <= rho0 * g * h * L, "Fy = %.4f",
                          row[2]);
        }
        free(path);
        free(dir);
        sluice_sim_free(sim);
    }
}
END_TEST

/* wall_force in 3D on a tank 0.4 x 0.2 m, H = 0.2 m, dx = 0.02 m, at t = 0
 * (the hydrostatic start), with the same bounds as in 2D taken per metre
 * of width and times the width W = 0.2 m (or the floor's area A): the
 * whole tank gives Fz = -rho0 g H A, Fx = Fy = 0 to round-off (the tank and
 * the lattice are symmetric); the left side alone (a box) Fx = -rho0 g H^2/2 W
 * and, about the origin, My = sum z dFx = -rho0 g W H^3/6 and
 * Mz = -sum y dFx = rho0 g H^2/2 W^2/2, within the force bound times the
 * lever arm (H, and W/2). */
static const char *wall_force_tank_scene_3d =
    "dimensions: 3\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.01}\n"
    "domain: {min: [-0.1, -0.1, -0.1], max: [0.5, 0.3, 0.4]}\n"
    "geometry:\n"
    "  fluid: [{shape: box, min: [0, 0, 0], max: [0.4, 0.2, 0.2]}]\n"
    "  walls: [{shape: tank, min: [0, 0, 0], max: [0.4, 0.2, 0.3], name: tank}]\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 14}\n"
    "  continuity: {}\n"
    "  pressure_gradient: {}\n"
    "  gravity: {}\n"
    "  mdbc: {}\n"
    "  time_step: {}\n"
    "  symplectic: {}\n"
    "  wall_force: {%s}\n";

START_TEST(wall_force_still_tank_3d)
{
    const double rho0 = 1000, g = 9.81, H = 0.2, W = 0.2, A = 0.4 * 0.2, h = 0.03;
    for (int side = 0; side < 2; side++) {
        char *yaml = NULL;
        ck_assert(asprintf(&yaml, wall_force_tank_scene_3d,
                           side ? "walls: tank, box_min: [-0.1, -0.1, -0.1], box_max: [0.001, "
                                  "0.3, 0.5], moments: true"
                                : "walls: tank") > 0);
        sluice_sim *sim = test_load(side ? "wf3-side" : "wf3-tank", yaml, NULL, 0);
        free(yaml);
        char *dir = sample_now(sim, side ? "wf3-side-out" : "wf3-tank-out");
        char *path = out_file(dir, "wall_forces.csv");
        FILE *f = fopen(path, "r");
        ck_assert_ptr_nonnull(f);
        char line[512];
        ck_assert_ptr_nonnull(fgets(line, sizeof line, f));
        ck_assert_str_eq(line, side ? "time,Fx_tank,Fy_tank,Fz_tank,wet_tank,Mx_tank,My_tank,"
                                      "Mz_tank\n"
                                    : "time,Fx_tank,Fy_tank,Fz_tank,wet_tank\n");
        fclose(f);
        double row[8];
        ck_assert_int_eq(first_row(path, row, 8), side ? 8 : 5);
        const double force = 4 * rho0 * g * h * h * W;
        fprintf(stderr, "wall_force 3D at t = 0 (%s): F = (%.4f, %.4f, %.4f) N, wet %.5f m^2",
                side ? "left side" : "whole tank", row[1], row[2], row[3], row[4]);
        if (side) {
            fprintf(stderr, ", M = (%.5f, %.5f, %.5f) N m; -rho0 g H^2/2 W = %.4f, "
                            "-rho0 g W H^3/6 = %.5f, rho0 g H^2 W^2/4 = %.5f\n",
                    row[5], row[6], row[7], -rho0 * g * H * H / 2 * W,
                    -rho0 * g * W * H * H * H / 6, rho0 * g * H * H * W * W / 4);
            ck_assert_msg(fabs(row[1] + rho0 * g * H * H / 2 * W) <= force, "Fx = %.4f", row[1]);
            ck_assert_msg(row[2] == 0 && row[3] == 0, "Fy, Fz = %g, %g", row[2], row[3]);
            ck_assert_msg(fabs(row[4] - H * W) <= 2 * h * W, "wet %g", row[4]);
            ck_assert_msg(row[5] == 0, "Mx = %g", row[5]);
            ck_assert_msg(fabs(row[6] + rho0 * g * W * H * H * H / 6) <= force * H, "My = %.5f",
                          row[6]);
            ck_assert_msg(fabs(row[7] - rho0 * g * H * H * W * W / 4) <= force * W / 2,
                          "Mz = %.5f", row[7]);
        } else {
            fprintf(stderr, "; -rho0 g H A = %.4f\n", -rho0 * g * H * A);
            ck_assert_msg(fabs(row[1]) <= 1e-9 * rho0 * g * H * A &&
                              fabs(row[2]) <= 1e-9 * rho0 * g * H * A,
                          "Fx, Fy = %g, %g", row[1], row[2]);
            ck_assert_msg(fabs(row[3] + rho0 * g * H * A) <= rho0 * g * h * A, "Fz = %.4f",
                          row[3]);
        }
        free(path);
        free(dir);
        sluice_sim_free(sim);
    }
}
END_TEST

/* ------------------------------------------------------- vorticity -- */

/* -sum over lattice offsets of V F(r) r_x^2: the kernel's second moment m
 * (M = m I on the lattice by its cubic symmetry). */
static double lattice_moment(double dx, double h, int dims)
{
    const int reach = (int)ceil(2 * h / dx);
    const double V = dims == 3 ? dx * dx * dx : dx * dx;
    double m = 0;
    for (int a = -reach; a <= reach; a++)
        for (int b = -reach; b <= reach; b++)
            for (int c = dims == 3 ? -reach : 0; c <= (dims == 3 ? reach : 0); c++) {
                if (a == 0 && b == 0 && c == 0)
                    continue;
                double r = dx * sqrt((double)(a * a + b * b + c * c));
                m -= V * wendland_f(r, h, dims) * (a * dx) * (a * dx);
            }
    return m;
}

static char *vortex_scene(int dims, const char *extra)
{
    char *yaml = NULL;
    if (dims == 2)
        ck_assert_int_ge(
            asprintf(&yaml,
                     "dimensions: 2\n"
                     "particles: {spacing: 0.01, smoothing_length_ratio: 1.5}\n"
                     "time: {end: 0.01}\n"
                     "domain: {min: [-0.1, -0.1], max: [0.4, 0.4]}\n"
                     "initial: {density: rest}\n"
                     "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.3, 0.3]}]}\n"
                     "plugins:\n"
                     "  wendland_c2: {}\n"
                     "  tait: {speed_of_sound: 20}\n"
                     "  continuity: {}\n"
                     "  pressure_gradient: {}\n"
                     "  time_step: {}\n"
                     "  symplectic: {}\n"
                     "%s",
                     extra),
            0);
    else
        ck_assert_int_ge(
            asprintf(&yaml,
                     "dimensions: 3\n"
                     "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
                     "time: {end: 0.01}\n"
                     "domain: {min: [-0.1, -0.1, -0.1], max: [0.3, 0.3, 0.3]}\n"
                     "initial: {density: rest}\n"
                     "geometry: {fluid: [{shape: box, min: [0, 0, 0], max: [0.2, 0.2, 0.2]}]}\n"
                     "plugins:\n"
                     "  wendland_c2: {}\n"
                     "  tait: {speed_of_sound: 20}\n"
                     "  continuity: {}\n"
                     "  pressure_gradient: {}\n"
                     "  time_step: {}\n"
                     "  symplectic: {}\n"
                     "%s",
                     extra),
            0);
    return yaml;
}

/* v = Omega x (r - c) (2D: Omega along z) plus a uniform U. */
static void set_rotation(sluice_sim *sim, const double *omega, const double *centre,
                         const double *U)
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint32_t dims = v->dimensions;
    sluice_real *vel[3];
    for (uint32_t d = 0; d < dims; d++)
        vel[d] = test_column(sim, "velocity", d);
    for (sluice_index i = 0; i < v->count; i++) {
        double r[3] = {0, 0, 0};
        for (uint32_t d = 0; d < dims; d++)
            r[d] = (double)v->position[d][i] - centre[d];
        double o[3] = {dims == 3 ? omega[0] : 0, dims == 3 ? omega[1] : 0, omega[dims == 3 ? 2 : 0]};
        double c[3] = {o[1] * r[2] - o[2] * r[1], o[2] * r[0] - o[0] * r[2],
                       o[0] * r[1] - o[1] * r[0]};
        for (uint32_t d = 0; d < dims; d++)
            vel[d][i] = (sluice_real)(c[d] + U[d]);
    }
}

/* Distance from particle i to the nearest face of the block [0, L]^dims. */
static double inset(const sluice_view *v, sluice_index i, double L)
{
    double best = INFINITY;
    for (uint32_t d = 0; d < v->dimensions; d++) {
        double x = (double)v->position[d][i];
        best = fmin(best, fmin(x, L - x));
    }
    return best;
}

/* Checks omega of a rigid rotation: interior against 2 m Omega to round-off
 * and against 2 Omega within the lattice-moment error 2 |m - 1| |Omega|; with
 * renormalise, 2 Omega at every fluid particle. */
static void check_rotation(int dims, int renormalise)
{
    const double dx = dims == 3 ? 0.02 : 0.01, h = 1.5 * dx, L = dims == 3 ? 0.2 : 0.3;
    const double omega3[3] = {0.3, -0.7, 1.1}, omega2[1] = {1.5};
    const double *omega = dims == 3 ? omega3 : omega2;
    const int components = dims == 3 ? 3 : 1;
    const double centre[3] = {0.37 * L, 0.61 * L, 0.45 * L}, U[3] = {0.2, -0.1, 0.05};
    double norm = 0;
    for (int c = 0; c < components; c++)
        norm = fmax(norm, fabs(omega[c]));
    char *yaml = vortex_scene(dims, renormalise ? "  kernel_correction: {}\n"
                                                  "  vorticity: {renormalise: true}\n"
                                                : "  vorticity: {}\n");
    sluice_sim *sim = test_load(renormalise ? "vort-renorm" : "vort-rotation", yaml, NULL, 0);
    free(yaml);
    set_rotation(sim, omega, centre, U);
    char *dir = sample_now(sim, renormalise ? "vort-renorm-out" : "vort-rotation-out");
    const sluice_view *v = sluice_sim_view(sim);
    const double m = renormalise ? 1 : lattice_moment(dx, h, dims);
    double worst = 0, worst_edge = 0, worst_2omega = 0;
    sluice_index interior = 0, edge = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const int full = inset(v, i, L) > 2 * h;
        if (!renormalise && !full)
            continue;
        interior += full;
        edge += !full;
        for (int c = 0; c < components; c++) {
            const double w = (double)test_column(sim, "vorticity", (uint32_t)c)[i];
            const double error = fabs(w - 2 * m * omega[c]);
            if (full) {
                worst = fmax(worst, error);
                worst_2omega = fmax(worst_2omega, fabs(w - 2 * omega[c]));
            } else {
                worst_edge = fmax(worst_edge, error);
            }
        }
    }
    if (renormalise)
        fprintf(stderr, "%dD rigid rotation (renormalised): largest |omega - 2 Omega| = %.3e "
                        "s^-1 at %u interior particles, %.3e at %u near the free surface "
                        "(|Omega| = %g s^-1)\n",
                dims, worst, interior, worst_edge, edge, norm);
    else
        fprintf(stderr, "%dD rigid rotation: lattice moment m = %.12f (m - 1 = %+.3e); at %u "
                        "interior particles largest |omega - 2 m Omega| = %.3e s^-1, "
                        "|omega - 2 Omega| = %.3e s^-1 (|Omega| = %g s^-1)\n",
                dims, m, m - 1, interior, worst, worst_2omega, norm);
    ck_assert_uint_gt(interior, 0);
    /* round-off of sums of ~30 (2D) to ~100 (3D) terms of size |Omega| */
    ck_assert_msg(worst <= 1e-11 * norm, "interior: %g", worst);
    if (renormalise) {
        /* L = M^-1 with eigenvalues of M above 0.1: round-off times 10 */
        ck_assert_uint_gt(edge, 0);
        ck_assert_msg(worst_edge <= 1e-10 * norm, "free surface: %g", worst_edge);
    } else {
        ck_assert_msg(worst_2omega <= 2 * fabs(m - 1) * norm + 1e-11 * norm,
                      "interior against 2 Omega: %g", worst_2omega);
    }
    free(dir);
    sluice_sim_free(sim);
}

START_TEST(vorticity_rigid_rotation_2d)
{
    check_rotation(2, 0);
}
END_TEST

START_TEST(vorticity_rigid_rotation_3d)
{
    check_rotation(3, 0);
}
END_TEST

START_TEST(vorticity_renormalised)
{
    check_rotation(2, 1);
    check_rotation(3, 1);
}
END_TEST

/* A uniform flow: 0 to round-off; then on demand only: a rotation set after
 * t = 0 is not seen until the next output time, where a uniform flow set in
 * between gives 0 again. */
START_TEST(vorticity_uniform_and_on_demand)
{
    char *yaml = vortex_scene(2, "  vorticity: {interval: 0.001}\n");
    sluice_sim *sim = test_load("vort-uniform", yaml, NULL, 0);
    free(yaml);
    const double zero[1] = {0}, centre[3] = {0.15, 0.15, 0}, U[3] = {0.3, -0.2, 0};
    set_rotation(sim, zero, centre, U);
    char *dir = test_scratch("vort-uniform-out");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const sluice_view *v = sluice_sim_view(sim);
    double largest = 0;
    for (sluice_index i = 0; i < v->count; i++)
        largest = fmax(largest, fabs((double)test_column(sim, "vorticity", 0)[i]));
    fprintf(stderr, "uniform flow: largest |omega| = %.3e s^-1\n", largest);
    ck_assert_msg(largest <= 1e-12, "uniform flow: |omega| up to %g", largest);
    /* a rotation now: not computed before t = 0.001 */
    const double omega[1] = {2.0};
    set_rotation(sim, omega, centre, U);
    int stale_steps = 0;
    while (sluice_sim_time(sim) < 0.001 - 1e-12) {
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        if (sluice_sim_time(sim) < 0.001 - 1e-12) {
            v = sluice_sim_view(sim);
            for (sluice_index i = 0; i < v->count; i++)
                ck_assert((double)test_column(sim, "vorticity", 0)[i] == 0);
            stale_steps++;
        }
    }
    ck_assert_int_ge(stale_steps, 1);
    /* at t = 0.001: computed; the centre of the block rotates at 2 m Omega */
    v = sluice_sim_view(sim);
    const double m = lattice_moment(0.01, 0.015, 2);
    double worst = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (inset(v, i, 0.3) > 0.04)
            worst = fmax(worst, fabs((double)test_column(sim, "vorticity", 0)[i] - 2 * m * 2.0));
    fprintf(stderr, "on demand: %d steps kept the t = 0 field; at t = %.4f s the interior "
                    "vorticity is 2 m Omega within %.3e s^-1\n",
            stale_steps, sluice_sim_time(sim), worst);
    /* no force acts (uniform density, p = 0; the SPH divergence of a
     * rotation vanishes), so the particles move in straight lines: the
     * lattice is mapped by I + t Omega x, a rotation and a stretch by
     * sqrt(1 + (Omega t)^2), and v stays linear in the new positions with the
     * same curl to first order in Omega t = 0.002; bound: 2 Omega t relative */
    ck_assert_msg(worst <= 2 * (2.0 * 0.001) * (2 * m * 2.0), "vorticity at t = 0.001: error %g",
                  worst);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

/* ---------------------------------------------------------- refusals -- */

static void expect_refusal(const char *tag, const char *yaml, const char *needle)
{
    char *dir = test_scratch(tag);
    char *path = test_write_file(dir, "scene.yaml", yaml);
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {0};
    sluice_sim *sim = sluice_sim_load(path, &options, diag);
    if (sim)
        sluice_sim_free(sim);
    ck_assert_msg(sim == NULL, "%s: the scene loaded", tag);
    int found = 0;
    for (size_t i = 0; i < sluice_diag_count(diag); i++) {
        fprintf(stderr, "%s refused: %s\n", tag, sluice_diag_message(diag, i));
        found |= strstr(sluice_diag_message(diag, i), needle) != NULL;
    }
    ck_assert_msg(found, "%s: no message containing \"%s\"", tag, needle);
    sluice_diag_destroy(diag);
    free(path);
    free(dir);
}

START_TEST(refusals)
{
    char *yaml = vortex_scene(2, "  free_surface_gauge: {positions: []}\n");
    expect_refusal("fs-empty", yaml, "'positions' is empty");
    free(yaml);
    yaml = vortex_scene(2, "  gravity: {}\n  section_gauge: {positions: []}\n");
    expect_refusal("section-empty", yaml, "'positions' is empty");
    free(yaml);
    yaml = vortex_scene(2, "  gravity: {}\n  section_gauge: {positions: [0.1, 0.2], "
                           "bed_elevation: [0, 0.1, 0.2]}\n");
    expect_refusal("section-beds", yaml, "3 values for 2 sections");
    free(yaml);
    yaml = vortex_scene(3, "  gravity: {}\n  section_gauge: {positions: [0.1]}\n");
    expect_refusal("section-3d", yaml, "does not support 3D");
    static const struct {
        const char *tag, *settings, *message;
    } wall_force_refusals[] = {
        {"wf-name", "walls: 'tank, nosuch'", "no wall is named 'nosuch'"},
        {"wf-box-empty", "box_min: [5, 5], box_max: [6, 6]", "no part of the measured walls"},
        {"wf-box-order", "box_min: [0.5, 0], box_max: [0.2, 1]", "must exceed box_min"},
        {"wf-empty-name", "walls: 'tank,,'", "empty name"},
    };
    for (size_t k = 0; k < sizeof wall_force_refusals / sizeof *wall_force_refusals; k++) {
        char *scene = NULL;
        ck_assert(asprintf(&scene, wall_force_tank_scene, wall_force_refusals[k].settings) > 0);
        expect_refusal(wall_force_refusals[k].tag, scene, wall_force_refusals[k].message);
        free(scene);
    }
    free(yaml);
    yaml = vortex_scene(3, "  free_surface_gauge: {positions: [0.1]}\n");
    expect_refusal("fs-3d-lateral", yaml, "needs 'lateral' in 3D");
    free(yaml);
    yaml = vortex_scene(2, "  hdf5: {}\n  vorticity: {}\n");
    expect_refusal("vort-order", yaml, "list 'vorticity' before 'hdf5'");
    free(yaml);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("hydraulic_gauges");
    TCase *c = tcase_create("hydraulic_gauges");
    tcase_add_test(c, free_surface_still_tank);
    tcase_add_test(c, free_surface_against_kernel_sum);
    tcase_add_test(c, free_surface_3d);
    tcase_add_test(c, section_uniform_flow);
    tcase_add_test(c, section_linear_shear);
    tcase_add_test(c, section_momentum_and_pressure);
    tcase_add_test(c, section_face_force_at_rest);
    tcase_add_test(c, wall_force_still_tank);
    tcase_add_test(c, wall_force_still_tank_3d);
    tcase_add_test(c, vorticity_rigid_rotation_2d);
    tcase_add_test(c, vorticity_rigid_rotation_3d);
    tcase_add_test(c, vorticity_renormalised);
    tcase_add_test(c, vorticity_uniform_and_on_demand);
    tcase_add_test(c, refusals);
    suite_add_tcase(s, c);
    return test_run_suite(s);
}
