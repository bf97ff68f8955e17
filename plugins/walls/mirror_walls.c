/* Wall particles that take their values from the fluid across the wall
 * (issue 4). Two wall schemes share the wall-particle layers of dbc
 * (wall_layers.h: lattice points behind every wall of the scheme, kind
 * SLUICE_KIND_WALL, fixed) and differ in how the wall particles get their
 * values. Both set them in prepare() (ABI 1.3), at every evaluation, after
 * the neighbour update and before the passes, from the fluid at the mirror
 * image of each wall particle b across the wall:
 *
 *     x_m = 2 c_b - x_b,   c_b = the nearest point of the scheme's walls,
 *
 * i.e. x_m = x_b + 2 d n on a flat wall (d the distance behind the wall, n
 * the normal into the fluid); behind a concave corner the nearest point is
 * the vertex and the mirror is the point reflection through it (as
 * DualSPHysics does for corner particles). The wall particles themselves
 * never move, so x_m and the unit reflection direction
 * n_b = (x_m - x_b) / |x_m - x_b| are computed once, in initialise().
 *
 * Interpolation at x_m (api->evaluation->point_pass over fluid particles j within the
 * kernel support; V_j = m_j / rho_j, u_j = (x_j - x_m) / h, G_j = h grad W,
 * grad W = (x_m - x_j) F): the first-order consistent (corrected) SPH
 * interpolation of Liu & Liu (2006), as in English et al. (2021):
 *
 *   [ sum V W   sum V W u^T ] [ f        ]   [ sum V f W ]
 *   [ sum V G   sum V G u^T ] [ h grad f ] = [ sum V f G ],
 *
 * exact for linear fields. The Shepard value is exact only for constants:
 * next to a wall, where the support is one-sided, it misses a linear field
 * such as the hydrostatic pressure by grad f . (x_mean - x_m), x_mean the
 * Shepard-weighted mean position of the neighbours, of order rho g dx / 2,
 * which the hydrostatic correction below would then carry into every wall
 * particle. This is why the corrected form is used. The matrix
 * is dimensionless and about the identity in a full support; its
 * determinant is invariant under the scaling by h. Where |det| <
 * `determinant_threshold` (default 1e-3, the value of English et al. 2021
 * and DualSPHysics) the Shepard value sum V f W / sum V W is used, with zero
 * gradient; where the kernel sum sum V W <= `kernel_sum_threshold` (default
 * 0: no fluid particle within the support) the mirror point has no fluid and
 * the wall particle gets rest values.
 *
 * ghost_particles (seed 004: "the ghost particle method", Randles &
 * Libersky 1996; the fixed-ghost form of Adami et al. 2012 and Marrone et
 * al. 2011):
 *   velocity  no_slip:   v_b = 2 v_wall - v_m = -v_m (walls at rest)
 *             free_slip: v_b = v_m - 2 (v_m . n_b) n_b (normal reversed,
 *                        tangential kept)
 *   pressure  p_b = p_m + rho_m g . (x_b - x_m)  (hydrostatic correction: a
 *             tank at rest keeps rho g H down to the wall particles)
 *   density   rho_b = EOS^-1(p_b) (api->evaluation->density_from_pressure), so that the
 *             equation of state, which runs after prepare(), returns p_b.
 *   no fluid  v_b = 0, p_b = reference_pressure (the EOS's, 0 if none).
 *   clamp     with `clamp_pressure` (default true) p_b >= reference_pressure:
 *             the wall repels but never pulls fluid in tension (p < 0)
 *             towards itself, as dbc's density clamp.
 * p_m is the equation of state of the interpolated current density rho_m:
 * when prepare() runs, the pressure column still holds the EOS of the
 * previous evaluation's densities (the integrator has since moved them on),
 * so its interpolation is only the starting point of a secant iteration on
 * the EOS inverse, EOS^-1(p_m) = rho_m, converged to 1e-13 rho0.
 * Randles & Libersky create, at every step, mirror copies of the fluid
 * particles near a wall that move with the mirrored velocity. Here the ghost
 * particles are fixed and take the mirrored values of the fluid at their
 * mirror points. Across a flat wall both impose the same mirror condition;
 * the fixed form creates no particles per step, keeps the particle count and
 * neighbour lists unchanged, and handles corners through the nearest wall
 * point (point reflection at a concave vertex) instead of multiple copies.
 *
 * mdbc (modified dynamic boundary conditions, English et al. 2021, Comp.
 * Part. Mech. 9:1-15, doi:10.1007/s40571-021-00403-3; DualSPHysics): the
 * same layers; the density of each wall particle is extrapolated linearly
 * from its ghost node x_g = x_m:
 *     rho_b = rho_g + (x_b - x_g) . grad rho_g
 * with rho_g and grad rho_g from the corrected interpolation (Shepard rho_g
 * and no extrapolation where ill-conditioned; rho0 where there is no fluid).
 * Velocity `zero` (default; English et al. 2021: the boundary keeps the
 * wall's velocity, as DBC), or the mirrored no_slip / free_slip values of
 * ghost_particles (the later DualSPHysics slip modes). English et al. do not
 * clamp the extrapolated density (DualSPHysics' mDBC correction writes it
 * as it is); `clamp_density` (default false) keeps it >= rho0 as dbc does.
 *
 * Ordering: continuity accumulates a density rate for every wall particle
 * and the integrator applies it after the evaluation; prepare() overwrites
 * the density (and velocity) of these wall particles at the next evaluation,
 * before any pass reads them, so the integrated value is never used. Outputs
 * written between steps show that integrated wall density; the wall
 * pressure column is the one the last evaluation used. dbc's clamp acts only
 * on dbc's own particles (by id), so the schemes mix in one scene.
 *
 * Limitation (measured with tests/plugins/walls/test_wall_particles.c's study hooks): both
 * schemes hold the fluid at a wall only through the field they mirror, with
 * no memory of an approach. Particles in tension (p < 0) in the film the
 * dam break leaves on its left wall are pulled towards the wall by their own
 * negative pressure and, after t = 0.87 s, single ones drift through it:
 * ghost no_slip by up to 0.54, 0.49 and 0.29 dx at dx = 0.1, 0.08 and
 * 0.05 m by t = 1.5 s, mdbc by 0.40 dx at 0.05 m; ghost free_slip held at
 * all three, and so does dbc, whose wall density grows with every approach.
 * The impact on the far wall (t = 0.70-0.77 s) is passed without a
 * crossing by all. */
#include <math.h>
#include <string.h>

#include <sluice/plugin_util.h>
#include "wall_layers.h"

enum { SCHEME_GHOST = 0, SCHEME_MDBC = 1 };
enum { VELOCITY_ZERO = 0, VELOCITY_NO_SLIP = 1, VELOCITY_FREE_SLIP = 2 };
enum { STATUS_NONE = 0, STATUS_SHEPARD = 1, STATUS_CORRECTED = 2 };

/* interpolated quantities */
enum { Q_DENSITY = 0, Q_PRESSURE = 1, Q_VELOCITY = 2, Q_MAX = 5 };

typedef struct ghost_config {
    int64_t layers;
    int slip;
    sluice_real kernel_sum_threshold, determinant_threshold;
    int clamp_pressure;
} ghost_config;

typedef struct mdbc_config {
    int64_t layers;
    int velocity;
    sluice_real kernel_sum_threshold, determinant_threshold;
    int clamp_density;
} mdbc_config;

typedef struct mirror_state {
    const sluice_api *api;
    int scheme;
    const char *name;
    uint32_t dims;
    int64_t layers;
    int velocity_mode, clamp;
    double sum_threshold, det_threshold;
    sluice_real rho0, dx, h, c0, p_ref;
    double g[3];
    sluice_field density, mass, velocity, pressure;
    /* own particles: ids [first_id, first_id + count) */
    sluice_id first_id;
    sluice_index count;
    sluice_real *wall_position; /* x_b, 3 reals each */
    sluice_real *mirror;        /* x_m, 3 reals each */
    double *normal;             /* n_b, 3 each */
    /* the own particles this rank holds (all of them on one rank), in view
     * order, at each evaluation: local[m] is the k of the m-th, index[m]
     * its particle index, points its x_m; slot[k] = m */
    sluice_index local_count;
    sluice_index *local, *index, *slot;
    sluice_real *points;
    /* results of the point pass, per local point m */
    uint8_t *status;
    double *value;    /* Q_MAX per point */
    double *gradient; /* density gradient, 3 per point */
    /* EOS buffers */
    sluice_real *p0, *p1, *r0, *r1, *target;
} mirror_state;

/* ------------------------------------------------------------- params -- */

static const sluice_param_spec ghost_params[] = {
    {"layers", SLUICE_PARAM_INT, offsetof(ghost_config, layers), "0", 0, 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "layers of wall particles behind each wall; 0: enough to cover the kernel support "
     "(ceil(2h/dx))",
     NULL, 0},
    {"slip", SLUICE_PARAM_ENUM, offsetof(ghost_config, slip), "no_slip", 0, 0, 0, NULL,
     "no_slip: v_b = -v_m; free_slip: v_b = v_m - 2 (v_m . n) n (normal component reversed)",
     "no_slip|free_slip", 0},
    {"kernel_sum_threshold", SLUICE_PARAM_REAL, offsetof(ghost_config, kernel_sum_threshold), "0",
     0, 1, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "mirror point without fluid when sum_j V_j W_j there is at or below this (about 1 in a "
     "full support, 0.5 at a flat free surface): rest values v = 0, p = reference pressure",
     NULL, 0},
    {"determinant_threshold", SLUICE_PARAM_REAL, offsetof(ghost_config, determinant_threshold),
     "1e-3", 0, 0, SLUICE_PARAM_HAS_MIN, "1",
     "first-order corrected interpolation where |det| of its (dimensionless) matrix is at "
     "least this, else Shepard (English et al. 2021)",
     NULL, 0},
    {"clamp_pressure", SLUICE_PARAM_BOOL, offsetof(ghost_config, clamp_pressure), "true", 0, 0, 0,
     NULL,
     "keep the wall-particle pressure >= the reference pressure: walls repel but never attract "
     "fluid under tension (as dbc's density clamp)",
     NULL, 0},
};

static const sluice_param_spec mdbc_params[] = {
    {"layers", SLUICE_PARAM_INT, offsetof(mdbc_config, layers), "0", 0, 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "layers of wall particles behind each wall; 0: enough to cover the kernel support "
     "(ceil(2h/dx))",
     NULL, 0},
    {"velocity", SLUICE_PARAM_ENUM, offsetof(mdbc_config, velocity), "zero", 0, 0, 0, NULL,
     "wall-particle velocity: zero (English et al. 2021, as DBC); no_slip: -v_g; free_slip: "
     "v_g - 2 (v_g . n) n",
     "zero|no_slip|free_slip", 0},
    {"kernel_sum_threshold", SLUICE_PARAM_REAL, offsetof(mdbc_config, kernel_sum_threshold), "0", 0,
     1, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "ghost node without fluid when sum_j V_j W_j there is at or below this: rho_b = rho0 "
     "(DualSPHysics' MdbcThreshold, default 0)",
     NULL, 0},
    {"determinant_threshold", SLUICE_PARAM_REAL, offsetof(mdbc_config, determinant_threshold),
     "1e-3", 0, 0, SLUICE_PARAM_HAS_MIN, "1",
     "linear extrapolation where |det| of the corrected-interpolation matrix is at least this, "
     "else the Shepard density (English et al. 2021)",
     NULL, 0},
    {"clamp_density", SLUICE_PARAM_BOOL, offsetof(mdbc_config, clamp_density), "false", 0, 0, 0,
     NULL, "keep the extrapolated wall density >= rest density (English et al. do not)", NULL, 0},
};

/* ------------------------------------------------------------ lifecycle -- */

static void mirror_destroy(void *state)
{
    mirror_state *s = state;
    if (!s)
        return;
    free(s->wall_position);
    free(s->mirror);
    free(s->normal);
    free(s->index);
    free(s->local);
    free(s->slot);
    free(s->points);
    free(s->status);
    free(s->value);
    free(s->gradient);
    free(s->p0);
    free(s->p1);
    free(s->r0);
    free(s->r1);
    free(s->target);
    free(s);
}

static int mirror_create_common(const sluice_api *api, sluice_host *host, mirror_state *s)
{
    sluice_real dims = 0;
    if (sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &s->dx) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK)
        return SLUICE_ERROR;
    s->dims = (uint32_t)dims;
    const sluice_field_spec density = SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_WRITE);
    const sluice_field_spec mass = SLUICE_SPEC_MASS(SLUICE_READ);
    if (api->fields->declare_field(host, &density) != SLUICE_OK ||
        api->fields->declare_field(host, &mass) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->velocity_mode != VELOCITY_ZERO) {
        const sluice_field_spec velocity = SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_WRITE);
        if (api->fields->declare_field(host, &velocity) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    if (s->scheme == SCHEME_GHOST) {
        const sluice_field_spec pressure = SLUICE_SPEC_PRESSURE(SLUICE_READ);
        if (api->fields->declare_field(host, &pressure) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int ghost_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const ghost_config *c = config;
    mirror_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->scheme = SCHEME_GHOST;
    s->name = "ghost_particles";
    s->layers = c->layers;
    s->velocity_mode = c->slip == 0 ? VELOCITY_NO_SLIP : VELOCITY_FREE_SLIP;
    s->clamp = c->clamp_pressure;
    s->sum_threshold = (double)c->kernel_sum_threshold;
    s->det_threshold = (double)c->determinant_threshold;
    if (mirror_create_common(api, host, s) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int mdbc_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const mdbc_config *c = config;
    mirror_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->scheme = SCHEME_MDBC;
    s->name = "mdbc";
    s->layers = c->layers;
    s->velocity_mode = c->velocity;
    s->clamp = c->clamp_density;
    s->sum_threshold = (double)c->kernel_sum_threshold;
    s->det_threshold = (double)c->determinant_threshold;
    if (mirror_create_common(api, host, s) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int mirror_bind(void *state, sluice_host *host)
{
    mirror_state *s = state;
    const sluice_api *api = s->api;
    if (s->layers == 0)
        s->layers = sluice_wall_layers_default(api, host, s->h, s->dx);
    if (api->fields->field(host, "density", &s->density) != SLUICE_OK ||
        api->fields->field(host, "mass", &s->mass) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->velocity_mode != VELOCITY_ZERO &&
        api->fields->field(host, "velocity", &s->velocity) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->scheme == SCHEME_GHOST) {
        if (api->fields->field(host, "pressure", &s->pressure) != SLUICE_OK ||
            api->evaluation->density_from_pressure(host, 0, NULL, NULL) != SLUICE_OK ||
            sluice_util_constant(api, host, "speed_of_sound", &s->c0) != SLUICE_OK)
            return SLUICE_ERROR;
        sluice_real p_ref = 0;
        api->fields->constant(host, "reference_pressure", &p_ref, 1);
        s->p_ref = p_ref;
        sluice_real g[3] = {0, 0, 0};
        api->fields->constant(host, "gravity", g, 3);
        for (int d = 0; d < 3; d++)
            s->g[d] = (double)g[d];
    }
    return SLUICE_OK;
}

/* 1 when the mirror of x_b across the wall point c (x_m = 2 c - x_b) lies
 * in the fluid: in front of every wall of the scene, of any scheme (a point
 * past an open end of a polyline counts as in front); 0 when it lies behind
 * one; -1 on error. Where two walls meet at a concave corner without
 * sharing a vertex (a bed that starts inside the solid under a step, as the
 * abrupt drop's lower bed does, so that its layers fill the corner block),
 * the nearest wall of a particle in the corner block can be the one whose
 * mirror lands inside the step, behind the other wall, where there is no
 * fluid to interpolate; the other wall's nearest point (the corner's vertex)
 * then gives the point reflection through the corner, in the fluid. */
static int mirror_in_fluid(const sluice_api *api, sluice_host *host, const sluice_real *xb,
                           const sluice_wall_point *c, uint32_t walls)
{
    sluice_real xm[3];
    for (int d = 0; d < 3; d++)
        xm[d] = 2 * c->closest[d] - xb[d];
    for (uint32_t w = 0; w < walls; w++) {
        sluice_wall_point at;
        if (!api->walls->wall(host, w))
            continue;
        if (api->walls->wall_nearest(host, xm, (int32_t)w, &at) != SLUICE_OK)
            return -1;
        if (at.distance < 0 && !at.beyond_end)
            return 0;
    }
    return 1;
}

static int mirror_initialise(void *state, sluice_host *host)
{
    mirror_state *s = state;
    const sluice_api *api = s->api;
    sluice_wall_layers layers;
    if (sluice_wall_layers_add(api, host, s->name, (sluice_real)s->layers * s->dx, s->dx, -1,
                               &layers) != SLUICE_OK)
        return SLUICE_ERROR;
    s->first_id = layers.first_id;
    s->count = layers.fixed_count;
    s->wall_position = layers.positions;
    if (s->count == 0)
        return SLUICE_OK;
    const size_t n = s->count;
    s->mirror = malloc(n * 3 * sizeof *s->mirror);
    s->normal = malloc(n * 3 * sizeof *s->normal);
    s->index = malloc(n * sizeof *s->index);
    s->local = malloc(n * sizeof *s->local);
    s->slot = malloc(n * sizeof *s->slot);
    s->points = malloc(n * 3 * sizeof *s->points);
    s->status = malloc(n);
    s->value = malloc(n * Q_MAX * sizeof *s->value);
    s->gradient = malloc(n * 3 * sizeof *s->gradient);
    s->p0 = malloc(n * sizeof *s->p0);
    s->p1 = malloc(n * sizeof *s->p1);
    s->r0 = malloc(n * sizeof *s->r0);
    s->r1 = malloc(n * sizeof *s->r1);
    s->target = malloc(n * sizeof *s->target);
    if (!s->mirror || !s->normal || !s->index || !s->local || !s->slot || !s->points ||
        !s->status || !s->value || !s->gradient ||
        !s->p0 || !s->p1 || !s->r0 || !s->r1 || !s->target) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    /* the mirror point of each wall particle across the nearest of the
     * scheme's walls whose mirror point lies in the fluid (see
     * mirror_in_fluid); when none does, across the nearest */
    const uint32_t walls = api->walls->wall_count(host);
    double margin = 0;
    size_t farther = 0, behind = 0;
    for (size_t k = 0; k < n; k++) {
        const sluice_real *xb = s->wall_position + 3 * k;
        sluice_wall_point best, nearest, candidate;
        memset(&best, 0, sizeof best);
        memset(&nearest, 0, sizeof nearest);
        int found = 0, found_valid = 0;
        for (uint32_t w = 0; w < walls; w++) {
            const sluice_wall *wall = api->walls->wall(host, w);
            if (!wall || strcmp(wall->scheme, s->name) != 0)
                continue;
            if (api->walls->wall_nearest(host, xb, (int32_t)w, &candidate) != SLUICE_OK)
                return SLUICE_ERROR;
            if (!found || fabs((double)candidate.distance) < fabs((double)nearest.distance)) {
                nearest = candidate;
                found = 1;
            }
            if (found_valid && fabs((double)candidate.distance) >= fabs((double)best.distance))
                continue;
            const int valid = mirror_in_fluid(api, host, xb, &candidate, walls);
            if (valid < 0)
                return SLUICE_ERROR;
            if (valid) {
                best = candidate;
                found_valid = 1;
            }
        }
        if (!found) {
            api->messages->error(host, "no wall of scheme '%s' for wall particle %zu", s->name, k);
            return SLUICE_ERROR;
        }
        if (!found_valid) {
            best = nearest;
            behind++;
        } else if (best.wall != nearest.wall)
            farther++;
        double length = 0, r[3] = {0, 0, 0};
        for (int d = 0; d < 3; d++) {
            s->mirror[3 * k + d] = 2 * best.closest[d] - xb[d];
            r[d] = (double)s->mirror[3 * k + d] - (double)xb[d];
            length += r[d] * r[d];
        }
        length = sqrt(length);
        for (int d = 0; d < 3; d++)
            s->normal[3 * k + d] =
                length > 1e-9 * (double)s->dx ? r[d] / length : (double)best.normal[d];
        for (int d = 0; d < 3; d++)
            if (fabs(r[d]) > margin)
                margin = fabs(r[d]);
    }
    if (farther || behind)
        api->messages->info(host,
                  "%zu wall particles mirrored across a farther wall (the nearest one's mirror "
                  "point lay behind a wall), %zu with no mirror point in front of every wall "
                  "(mirrored across the nearest)",
                  farther, behind);
    /* across ranks the rank of a wall particle interpolates at its mirror
     * point, up to `margin` along an axis outside its box */
    return api->evaluation->request_point_margin(host, (sluice_real)margin);
}

/* ------------------------------------------------------- interpolation -- */

/* Solves the (m x m) system a x = b for `nq` right-hand sides (rows of b)
 * by Gaussian elimination with partial pivoting; returns the determinant
 * (0 when singular, then x is not set). */
static double solve(int m, double a[4][4], int nq, double b[Q_MAX][4], double x[Q_MAX][4])
{
    double det = 1;
    for (int c = 0; c < m; c++) {
        int pivot = c;
        for (int r = c + 1; r < m; r++)
            if (fabs(a[r][c]) > fabs(a[pivot][c]))
                pivot = r;
        if (a[pivot][c] == 0)
            return 0;
        if (pivot != c) {
            det = -det;
            for (int k = 0; k < m; k++) {
                double t = a[c][k];
                a[c][k] = a[pivot][k];
                a[pivot][k] = t;
            }
            for (int q = 0; q < nq; q++) {
                double t = b[q][c];
                b[q][c] = b[q][pivot];
                b[q][pivot] = t;
            }
        }
        det *= a[c][c];
        for (int r = c + 1; r < m; r++) {
            double f = a[r][c] / a[c][c];
            for (int k = c; k < m; k++)
                a[r][k] -= f * a[c][k];
            for (int q = 0; q < nq; q++)
                b[q][r] -= f * b[q][c];
        }
    }
    for (int q = 0; q < nq; q++)
        for (int r = m - 1; r >= 0; r--) {
            double t = b[q][r];
            for (int k = r + 1; k < m; k++)
                t -= a[r][k] * x[q][k];
            x[q][r] = t / a[r][r];
        }
    return det;
}

static inline void interpolate(const mirror_state *s, const sluice_view *v,
                               const sluice_pair_batch *b, const uint32_t dims)
{
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict mass = sluice_real_column(v, s->mass, 0);
    const int with_pressure = s->scheme == SCHEME_GHOST;
    const int with_velocity = s->velocity_mode != VELOCITY_ZERO;
    const sluice_real *restrict p = with_pressure ? sluice_real_column(v, s->pressure, 0) : rho;
    const sluice_real *u[3] = {rho, rho, rho};
    if (with_velocity)
        for (uint32_t d = 0; d < dims; d++)
            u[d] = sluice_real_column(v, s->velocity, d);
    const double h = (double)s->h, inv_h = 1 / h;
    const int m = (int)dims + 1;
    const int nq = with_velocity ? Q_VELOCITY + (int)dims : Q_VELOCITY;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index k = b->target[t];
        double a[4][4] = {{0}}, rhs[Q_MAX][4] = {{0}};
        for (sluice_index q = b->pair_begin[t]; q < b->pair_begin[t + 1]; q++) {
            const sluice_index j = b->neighbour[q];
            const double V = (double)mass[j] / (double)rho[j], W = (double)b->kernel[q];
            const double F = (double)b->kernel_gradient[q];
            double row[4], col[4];
            row[0] = W;
            col[0] = 1;
            for (uint32_t d = 0; d < dims; d++) {
                const double e = (double)b->offset[d][q]; /* x_m - x_j */
                row[1 + d] = h * e * F;                   /* h grad W */
                col[1 + d] = -e * inv_h;                  /* (x_j - x_m) / h */
            }
            double f[Q_MAX];
            f[Q_DENSITY] = (double)rho[j];
            f[Q_PRESSURE] = (double)p[j];
            for (uint32_t d = 0; d < dims; d++)
                f[Q_VELOCITY + d] = (double)u[d][j];
            for (int r = 0; r < m; r++) {
                const double vr = V * row[r];
                for (int c = 0; c < m; c++)
                    a[r][c] += vr * col[c];
                for (int qq = 0; qq < nq; qq++)
                    rhs[qq][r] += vr * f[qq];
            }
        }
        double *value = s->value + (size_t)k * Q_MAX, *gradient = s->gradient + 3 * (size_t)k;
        const double sum = a[0][0];
        gradient[0] = gradient[1] = gradient[2] = 0;
        if (!(sum > s->sum_threshold) || sum <= 0) {
            s->status[k] = STATUS_NONE;
            continue;
        }
        double shepard[Q_MAX];
        for (int qq = 0; qq < nq; qq++)
            shepard[qq] = rhs[qq][0] / sum;
        double x[Q_MAX][4];
        const double det = solve(m, a, nq, rhs, x);
        if (det != 0 && fabs(det) >= s->det_threshold && isfinite(det)) {
            s->status[k] = STATUS_CORRECTED;
            for (int qq = 0; qq < nq; qq++)
                value[qq] = x[qq][0];
            for (uint32_t d = 0; d < dims; d++)
                gradient[d] = x[Q_DENSITY][1 + d] * inv_h;
        } else {
            s->status[k] = STATUS_SHEPARD;
            for (int qq = 0; qq < nq; qq++)
                value[qq] = shepard[qq];
        }
    }
}

static void interpolate_points(void *context, const sluice_view *v, const sluice_pair_batch *b)
{
    const mirror_state *s = context;
    if (v->dimensions == 3)
        interpolate(s, v, b, 3);
    else
        interpolate(s, v, b, 2);
}

/* ------------------------------------------------------------- prepare -- */

/* The density the EOS inverse gives for `count` pressures. */
static int eos_inverse(mirror_state *s, sluice_host *host, const sluice_real *p, sluice_real *rho)
{
    return s->api->evaluation->density_from_pressure(host, s->local_count, p, rho);
}

/* p_m = EOS(rho_m) for every point with fluid, by a secant iteration on the
 * EOS inverse started from the interpolated (previous-evaluation) pressure,
 * first slope 1 / c0^2. Leaves p_m in s->p1. */
static int pressure_of_density(mirror_state *s, sluice_host *host)
{
    const sluice_index n = s->local_count;
    const double tolerance = 1e-13 * (double)s->rho0, c2 = (double)s->c0 * (double)s->c0;
    for (sluice_index k = 0; k < n; k++) {
        const int fluid = s->status[k] != STATUS_NONE;
        s->target[k] = fluid ? (sluice_real)s->value[(size_t)k * Q_MAX + Q_DENSITY] : s->rho0;
        s->p0[k] = fluid ? (sluice_real)s->value[(size_t)k * Q_MAX + Q_PRESSURE] : s->p_ref;
    }
    if (eos_inverse(s, host, s->p0, s->r0) != SLUICE_OK)
        return SLUICE_ERROR;
    for (sluice_index k = 0; k < n; k++) {
        s->r0[k] -= s->target[k];
        s->p1[k] = s->p0[k] - (sluice_real)(c2 * (double)s->r0[k]);
    }
    for (int iteration = 0; iteration < 30; iteration++) {
        if (eos_inverse(s, host, s->p1, s->r1) != SLUICE_OK)
            return SLUICE_ERROR;
        int converged = 1;
        for (sluice_index k = 0; k < n; k++) {
            const double r1 = (double)s->r1[k] - (double)s->target[k];
            if (!isfinite(r1)) { /* outside the EOS's range: keep the last good value */
                s->p1[k] = s->p0[k];
                s->r1[k] = s->r0[k];
                continue;
            }
            const double dp = (double)s->p1[k] - (double)s->p0[k];
            const double dr = r1 - (double)s->r0[k];
            double slope = dp != 0 && dr != 0 ? dr / dp : 1 / c2; /* d rho / d p */
            if (!(slope > 0) || !isfinite(slope))
                slope = 1 / c2;
            s->p0[k] = s->p1[k];
            s->r0[k] = (sluice_real)r1;
            if (fabs(r1) > tolerance) {
                converged = 0;
                s->p1[k] = (sluice_real)((double)s->p1[k] - r1 / slope);
            }
        }
        if (converged)
            return SLUICE_OK;
    }
    return SLUICE_OK; /* within a few ulp: the last iterate stands */
}

/* The own particles this rank holds, in view order: local[], index[],
 * slot[] and their mirror points. */
static void list_local(mirror_state *s, const sluice_view *v)
{
    const sluice_index n = s->count;
    sluice_index m = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const sluice_id k = v->id[i] - s->first_id;
        if (k >= n)
            continue;
        s->local[m] = (sluice_index)k;
        s->index[m] = i;
        s->slot[k] = m;
        memcpy(s->points + 3 * (size_t)m, s->mirror + 3 * (size_t)k, 3 * sizeof *s->points);
        m++;
    }
    s->local_count = m;
}

static int mirror_prepare(void *state, sluice_host *host)
{
    mirror_state *s = state;
    const sluice_api *api = s->api;
    if (s->count == 0)
        return SLUICE_OK;
    list_local(s, api->particles->view(host));
    const sluice_index n = s->local_count;
    memset(s->status, STATUS_NONE, n);
    /* collective across ranks: every rank calls it, with its own points */
    if (api->evaluation->point_pass_local(host, s->points, n, SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
                              interpolate_points, s) != SLUICE_OK)
        return SLUICE_ERROR;
    /* where the own particles are now (a rebuild in the pass would have
     * sorted them anew; wall particles never change rank) */
    const sluice_view *v = api->particles->view(host);
    sluice_index seen = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const sluice_id k = v->id[i] - s->first_id;
        if (k < s->count) {
            const sluice_index m = s->slot[k];
            if (m >= n || s->local[m] != (sluice_index)k) {
                api->messages->error(host, "wall particle id %llu came to this rank during an evaluation",
                           (unsigned long long)v->id[i]);
                return SLUICE_ERROR;
            }
            s->index[m] = i;
            seen++;
        }
    }
    if (seen != n) {
        api->messages->error(host, "%u wall particles left this rank during an evaluation",
                   (unsigned)(n - seen));
        return SLUICE_ERROR;
    }
    const uint32_t dims = s->dims;
    sluice_real *rho = sluice_real_column(v, s->density, 0);

    if (s->scheme == SCHEME_GHOST) {
        if (pressure_of_density(s, host) != SLUICE_OK)
            return SLUICE_ERROR;
        /* p_b = p_m + rho_m g . (x_b - x_m); rest pressure without fluid */
        for (sluice_index m = 0; m < n; m++) {
            if (s->status[m] == STATUS_NONE) {
                s->p0[m] = s->p_ref;
                continue;
            }
            const size_t k = s->local[m];
            double correction = 0;
            for (uint32_t d = 0; d < dims; d++)
                correction += s->g[d] * ((double)s->wall_position[3 * k + d] -
                                         (double)s->mirror[3 * k + d]);
            s->p0[m] = (sluice_real)((double)s->p1[m] +
                                     s->value[(size_t)m * Q_MAX + Q_DENSITY] * correction);
            if (s->clamp && s->p0[m] < s->p_ref)
                s->p0[m] = s->p_ref;
        }
        if (eos_inverse(s, host, s->p0, s->r0) != SLUICE_OK)
            return SLUICE_ERROR;
        for (sluice_index m = 0; m < n; m++) {
            sluice_real value = s->r0[m];
            if (!(value > 0) || !isfinite(value)) /* beyond the EOS's range */
                value = s->status[m] == STATUS_NONE ? s->rho0 : s->target[m];
            rho[s->index[m]] = value;
        }
    } else {
        for (sluice_index m = 0; m < n; m++) {
            const size_t k = s->local[m];
            double value = (double)s->rho0;
            const double *q = s->value + (size_t)m * Q_MAX;
            if (s->status[m] != STATUS_NONE) {
                value = q[Q_DENSITY];
                if (s->status[m] == STATUS_CORRECTED)
                    for (uint32_t d = 0; d < dims; d++)
                        value += ((double)s->wall_position[3 * k + d] -
                                  (double)s->mirror[3 * k + d]) *
                                 s->gradient[3 * (size_t)m + d];
            }
            if (s->clamp && value < (double)s->rho0)
                value = (double)s->rho0;
            rho[s->index[m]] = (sluice_real)value;
        }
    }

    if (s->velocity_mode != VELOCITY_ZERO) {
        sluice_real *u[3] = {NULL, NULL, NULL};
        for (uint32_t d = 0; d < dims; d++)
            u[d] = sluice_real_column(v, s->velocity, d);
        for (sluice_index m = 0; m < n; m++) {
            const sluice_index i = s->index[m];
            const double *q = s->value + (size_t)m * Q_MAX + Q_VELOCITY;
            if (s->status[m] == STATUS_NONE) {
                for (uint32_t d = 0; d < dims; d++)
                    u[d][i] = 0;
                continue;
            }
            if (s->velocity_mode == VELOCITY_NO_SLIP) {
                for (uint32_t d = 0; d < dims; d++)
                    u[d][i] = (sluice_real)(-q[d]);
            } else {
                const double *nb = s->normal + 3 * (size_t)s->local[m];
                double normal = 0;
                for (uint32_t d = 0; d < dims; d++)
                    normal += q[d] * nb[d];
                for (uint32_t d = 0; d < dims; d++)
                    u[d][i] = (sluice_real)(q[d] - 2 * normal * nb[d]);
            }
        }
    }
    return SLUICE_OK;
}

/* ----------------------------------------------------------- components -- */

static const sluice_component components[] = {
    {
        .name = "ghost_particles",
        .summary = "fixed ghost wall particles with the fluid's mirrored velocity and "
                   "hydrostatically corrected pressure (no-slip or free-slip)",
        .reference = "Randles & Libersky (1996); Marrone et al. (2011); Adami et al. (2012); "
                     "seed 004",
        .dimensions = SLUICE_DIMS_ALL,
        .flags = SLUICE_COMPONENT_WALL_SCHEME,
        .params = ghost_params,
        .param_count = SLUICE_COUNT(ghost_params),
        .config_size = sizeof(ghost_config),
        .create = ghost_create,
        .destroy = mirror_destroy,
        .bind = mirror_bind,
        .initialise = mirror_initialise,
        .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_WALL),
        .prepare = mirror_prepare,
    },
    {
        .name = "mdbc",
        .summary = "modified dynamic boundary particles: density extrapolated linearly from a "
                   "ghost node mirrored into the fluid",
        .reference = "English et al. (2021), Comp. Part. Mech. 9:1-15; DualSPHysics",
        .dimensions = SLUICE_DIMS_ALL,
        .flags = SLUICE_COMPONENT_WALL_SCHEME,
        .params = mdbc_params,
        .param_count = SLUICE_COUNT(mdbc_params),
        .config_size = sizeof(mdbc_config),
        .create = mdbc_create,
        .destroy = mirror_destroy,
        .bind = mirror_bind,
        .initialise = mirror_initialise,
        .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_WALL),
        .prepare = mirror_prepare,
    },
};

SLUICE_DEFINE_LIBRARY("mirror_walls", "1.2.0",
                      "wall particles with values from the fluid at their mirror points: ghost "
                      "particles and modified DBC",
                      SLUICE_DIMS_ALL, components)
