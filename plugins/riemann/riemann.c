/* Riemann-solver SPH (Zhang, Hu & Adams 2017, "A weakly compressible SPH
 * method based on a low-dissipation Riemann solver", J. Comput. Phys. 335,
 * 605-620; the fluid formulation of SPHinXsys). Two components replace the
 * pressure term and the continuity equation of the standard weakly
 * compressible scheme; the dissipation that artificial viscosity and
 * density diffusion add there comes from the Riemann solver instead.
 *
 * Each pair (i, j) is the interface of a one-dimensional Riemann problem
 * along e = (x_j - x_i) / |x_j - x_i|, left state i, right state j:
 *     u_L = v_i . e,  u_R = v_j . e,  p_L = p_i,  p_R = p_j,
 * solved by the linearised (acoustic) solver with the pair means rho_bar,
 * c_bar (c the local speed of sound of the equation of state):
 *     U* = (u_L + u_R) / 2 + (p_L - p_R) / (2 rho_bar c_bar)
 *     P* = (p_L + p_R) / 2 + rho_bar beta (u_L - u_R) / 2
 * with beta = c_bar for the plain acoustic solver, and Zhang et al.'s
 * low-dissipation limiter (`limiter: low_dissipation`, the default)
 *     beta = min(eta max(u_L - u_R, 0), c_bar),   eta = 3,
 * which keeps the dissipation only where the pair compresses, and there in
 * proportion to the velocity jump (a shock-like compression gets the full
 * acoustic dissipation, a smooth flow almost none).
 *
 * riemann_pressure (momentum):
 *     dv_i/dt += -2 sum_j m_j P*_ij / (rho_i rho_j) grad_i W_ij
 * antisymmetric in i, j (P* is symmetric: swapping i and j reverses e and
 * both velocities), so linear momentum is conserved exactly.
 *
 * riemann_continuity:
 *     d rho_i/dt += 2 rho_i sum_j (m_j / rho_j) (v_i - v*_ij) . grad_i W_ij,
 *     v*_ij = U* e + (v_bar - u_bar e)   (only U* counts along grad W || e),
 * i.e. per pair rho_i V_j F_ij [(v_i - v_j) . r_ij + |r_ij| dp / (rho_bar c_bar)]
 * (r_ij = x_i - x_j, grad_i W_ij = r_ij F_ij): the standard continuity term
 * plus a pressure-difference diffusion from the solver. With `hydrostatic`
 * (default true) dp = p_i - p_j - rho_bar g . r_ij, the departure from
 * hydrostatics (g the gravity vector, 0 without gravity), so that a tank at
 * rest is not diffused towards uniform density (as delta_sph's Fourtakas
 * form does); without it dp = p_i - p_j as Zhang et al. write it.
 *
 * Walls. `walls: mirror` (default; Zhang et al. 2017; SPHinXsys' fluid-wall
 * coupling): a wall particle j only gives the interface's geometry; the
 * right state is the fluid particle's own, mirrored across the wall:
 *     rho_R = rho_i,  p_R = p_i + rho_i g . (x_j - x_i),
 * and the velocity reflected about the wall particle's velocity v_w (its
 * own: dbc's moving wall, or 0). In the momentum equation the compression is
 * the normal one, as Zhang et al. build the wall's Riemann problem along the
 * wall normal n_w (unit, into the fluid, of the wall point nearest to the
 * wall particle: field `wall_normal`, set once for the wall particles):
 *     u_L - u_R = -2 (v_i - v_w) . n_w,
 *     P* = p_i - rho_i g . r_ij / 2 + rho_i beta (u_L - u_R) / 2,
 * the pressure half-way to the wall plus the solver's compression term,
 * which vanishes for fluid sliding along the wall (the pair direction e
 * would count a tangential motion as compression ahead and expansion behind,
 * and the limiter, keeping only compression, would turn it into a drag). In
 * the continuity equation the mirror is the full reflection u_R = 2 u_w -
 * u_L along e, linear in the velocity, so a tangential motion cancels over
 * a wall's particles; the wall pair's interface velocity is U* = u_w (plus,
 * without `hydrostatic`, g . r_ij / (2 c_i)). Every particle wall scheme
 * works alike (dbc, mdbc, ghost_particles: their wall particles' own
 * density and pressure are not used). The wall particle's velocity must be
 * the wall's: with ghost_particles' or mdbc's mirrored no_slip / free_slip
 * velocities use `walls: particle`.
 * `walls: particle`: a wall particle is a neighbour like a fluid particle,
 * with the density, pressure and velocity its scheme gives it (dbc's
 * integrated density, mdbc's extrapolated one, ghost particles' mirrored
 * state). riemann_continuity then also targets wall particles (dbc walls
 * integrate their density from it, as from continuity); wall-wall pairs are
 * skipped. With `walls: mirror` wall particles get no density rate.
 *
 * Single-phase only (a scene with the two-phase plugin is refused), and not
 * together with the term it replaces (pressure_gradient, continuity). */
#include <math.h>
#include <string.h>

#include <sluice/plugin_util.h>

enum { WALLS_MIRROR = 0, WALLS_PARTICLE = 1 };
enum { LIMITER_LOW_DISSIPATION = 0, LIMITER_ACOUSTIC = 1 };
enum { TERM_PRESSURE = 0, TERM_CONTINUITY = 1 };

typedef struct pressure_config {
    int walls, limiter;
    sluice_real eta;
} pressure_config;

typedef struct continuity_config {
    int walls, hydrostatic;
} continuity_config;

typedef struct riemann_state {
    const sluice_api *api;
    int term, walls, limiter, hydrostatic;
    sluice_real eta, gravity[3];
    sluice_field pressure, density, mass, velocity, sound_speed, acceleration, density_rate;
    sluice_field wall_normal; /* riemann_pressure with mirrored walls */
    int normals_set;
} riemann_state;

#define WALLS_PARAM(type)                                                                         \
    {"walls", SLUICE_PARAM_ENUM, offsetof(type, walls), "mirror", 0, 0, 0, NULL,                  \
     "mirror: a wall particle is the interface with the fluid particle's own state mirrored "    \
     "(Zhang et al. 2017; the wall particle's velocity is the wall's); particle: with the "       \
     "density, pressure and velocity its wall scheme gives it",                                   \
     "mirror|particle", 0}

static const sluice_param_spec pressure_params[] = {
    WALLS_PARAM(pressure_config),
    {"limiter", SLUICE_PARAM_ENUM, offsetof(pressure_config, limiter), "low_dissipation", 0, 0, 0,
     NULL,
     "low_dissipation: beta = min(eta max(u_L - u_R, 0), c) (Zhang et al. 2017); acoustic: "
     "beta = c (the linearised solver's full dissipation)",
     "low_dissipation|acoustic", 0},
    {"eta", SLUICE_PARAM_REAL, offsetof(pressure_config, eta), "3", 0, 0, SLUICE_PARAM_HAS_MIN,
     "1", "eta of the low-dissipation limiter (Zhang et al. 2017: 3)", NULL, 0},
};

static const sluice_param_spec continuity_params[] = {
    WALLS_PARAM(continuity_config),
    {"hydrostatic", SLUICE_PARAM_BOOL, offsetof(continuity_config, hydrostatic), "true", 0, 0, 0,
     NULL,
     "diffuse only the departure from hydrostatics, p_i - p_j - rho_bar g . r_ij (false: "
     "p_i - p_j, as Zhang et al. 2017)",
     NULL, 0},
};

static const sluice_field_spec pressure_fields[] = {
    SLUICE_SPEC_PRESSURE_DOC(SLUICE_READ | SLUICE_READ_NEIGHBOUR, SLUICE_FIELD_OUTPUT, "pressure"),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_SOUND_SPEED_DOC(SLUICE_READ | SLUICE_READ_NEIGHBOUR, "local speed of sound"),
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
};

static const sluice_field_spec continuity_fields[] = {
    SLUICE_SPEC_PRESSURE_DOC(SLUICE_READ | SLUICE_READ_NEIGHBOUR, SLUICE_FIELD_OUTPUT, "pressure"),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_SOUND_SPEED_DOC(SLUICE_READ | SLUICE_READ_NEIGHBOUR, "local speed of sound"),
    SLUICE_SPEC_DENSITY_RATE(SLUICE_ACCUMULATE),
};

/* ------------------------------------------------------------ lifecycle -- */

static riemann_state *riemann_create(const sluice_api *api, sluice_host *host, int term,
                                     int walls)
{
    riemann_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return NULL;
    s->api = api;
    s->term = term;
    s->walls = walls;
    return s;
}

static int pressure_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state)
{
    const pressure_config *c = config;
    riemann_state *s = riemann_create(api, host, TERM_PRESSURE, c->walls);
    if (!s)
        return SLUICE_ERROR;
    s->limiter = c->limiter;
    s->eta = c->eta;
    if (s->walls == WALLS_MIRROR) {
        const sluice_field_spec normal = {
            "wall_normal", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "1",
            SLUICE_WRITE | SLUICE_READ_NEIGHBOUR, 0, NULL, 0,
            "wall particles: unit normal into the fluid at the nearest wall point (0 for fluid)"};
        if (api->fields->declare_field(host, &normal) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
    }
    *state = s;
    return SLUICE_OK;
}

static int continuity_create(const sluice_api *api, sluice_host *host, const void *config,
                             void **state)
{
    const continuity_config *c = config;
    riemann_state *s = riemann_create(api, host, TERM_CONTINUITY, c->walls);
    if (!s)
        return SLUICE_ERROR;
    s->hydrostatic = c->hydrostatic;
    *state = s;
    return SLUICE_OK;
}

/* the term this component replaces must not be loaded beside it */
static int refuse_replaced(const riemann_state *s, sluice_host *host)
{
    const char *replaced = s->term == TERM_PRESSURE ? "pressure_gradient" : "continuity";
    const char *self = s->term == TERM_PRESSURE ? "riemann_pressure" : "riemann_continuity";
    const uint32_t count = s->api->output->plugin_count(host);
    for (uint32_t k = 0; k < count; k++) {
        sluice_plugin_info info;
        if (s->api->output->plugin(host, k, &info) != SLUICE_OK || !info.component)
            continue;
        if (strcmp(info.component, replaced) == 0) {
            s->api->messages->error(host,
                                    "replaces '%s' (the same term in Riemann-solver form): load one "
                                    "of '%s' and '%s', not both",
                                    replaced, self, replaced);
            return SLUICE_ERROR;
        }
    }
    return SLUICE_OK;
}

static int riemann_bind(void *state, sluice_host *host)
{
    riemann_state *s = state;
    const sluice_api *api = s->api;
    sluice_field phase;
    if (sluice_util_optional_field(api, host, "phase", &phase)) {
        api->messages->error(host, "is single-phase: the pair means rho_bar and c_bar of its Riemann "
                                   "solver do not hold across an air-water interface; remove "
                                   "two_phase or use pressure_gradient and continuity");
        return SLUICE_ERROR;
    }
    if (refuse_replaced(s, host) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real g[3] = {0, 0, 0}; /* stays 0 without gravity */
    (void)api->fields->constant(host, "gravity", g, 3);
    for (int d = 0; d < 3; d++)
        s->gravity[d] = g[d];
    const sluice_field_binding common[] = {{"pressure", &s->pressure},
                                           {"density", &s->density},
                                           {"mass", &s->mass},
                                           {"velocity", &s->velocity},
                                           {"sound_speed", &s->sound_speed}};
    if (sluice_util_bind(api, host, common, SLUICE_COUNT(common)) != SLUICE_OK)
        return SLUICE_ERROR;
    const sluice_field_binding result[] = {
        s->term == TERM_PRESSURE ? (sluice_field_binding){"acceleration", &s->acceleration}
                                 : (sluice_field_binding){"density_rate", &s->density_rate}};
    if (sluice_util_bind(api, host, result, 1) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->term == TERM_PRESSURE && s->walls == WALLS_MIRROR &&
        api->fields->field(host, "wall_normal", &s->wall_normal) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

/* The wall particles' normals, at the first evaluation (the wall schemes
 * create their particles in initialise, after this component's). They move
 * with their particles through every reordering and into checkpoints; a
 * prescribed wall motion translates them, which keeps the normal. */
static int riemann_prepare(void *state, sluice_host *host)
{
    riemann_state *s = state;
    if (s->term != TERM_PRESSURE || s->walls != WALLS_MIRROR || s->normals_set)
        return SLUICE_OK;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    const uint32_t dims = v->dimensions;
    sluice_real *n[3];
    for (uint32_t d = 0; d < dims; d++)
        n[d] = sluice_real_column(v, s->wall_normal, d);
    for (sluice_index i = 0; i < v->count; i++) {
        for (uint32_t d = 0; d < dims; d++)
            n[d][i] = 0;
        if (v->kind[i] != SLUICE_KIND_WALL)
            continue;
        const sluice_real x[3] = {v->position[0][i], v->position[1][i],
                                  dims == 3 ? v->position[2][i] : 0};
        sluice_wall_point at;
        if (api->walls->wall_nearest(host, x, -1, &at) != SLUICE_OK) {
            api->messages->error(host, "wall particle %llu has no wall to take its normal from",
                                 (unsigned long long)v->id[i]);
            return SLUICE_ERROR;
        }
        for (uint32_t d = 0; d < dims; d++)
            n[d][i] = at.normal[d];
    }
    s->normals_set = 1;
    return SLUICE_OK;
}

static void riemann_destroy(void *state)
{
    free(state);
}

/* ------------------------------------------------------------ the pairs -- */

/* the neighbour columns of a batch and the target's own */
typedef struct pair_columns {
    const sluice_real *p, *rho, *c, *vel[3];
    const sluice_real *pj, *rhoj, *cj, *mj, *velj[3];
} pair_columns;

static void gather_columns(const riemann_state *s, const sluice_view *v, const sluice_pair_batch *b,
                           uint32_t dims, pair_columns *c)
{
    c->p = sluice_real_column(v, s->pressure, 0);
    c->rho = sluice_real_column(v, s->density, 0);
    c->c = sluice_real_column(v, s->sound_speed, 0);
    c->pj = b->gathered[s->pressure.column];
    c->rhoj = b->gathered[s->density.column];
    c->cj = b->gathered[s->sound_speed.column];
    c->mj = b->gathered[s->mass.column];
    for (uint32_t d = 0; d < 3; d++) {
        const uint32_t e = d < dims ? d : dims - 1;
        c->vel[d] = sluice_real_column(v, s->velocity, e);
        c->velj[d] = b->gathered[s->velocity.column + (int32_t)e];
    }
}

/* beta of the solver for a compression du = u_L - u_R and sound speed c */
static inline sluice_real limiter_beta(const riemann_state *s, sluice_real du, sluice_real c)
{
    if (s->limiter == LIMITER_ACOUSTIC)
        return c;
    const sluice_real b = s->eta * (du > 0 ? du : 0);
    return b < c ? b : c;
}

static inline void pressure_pairs(const riemann_state *s, const sluice_view *v,
                                  const sluice_pair_batch *b, const uint32_t dims,
                                  const int mirror)
{
    pair_columns c;
    gather_columns(s, v, b, dims, &c);
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict dist = b->distance;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const uint8_t *restrict kinds = b->neighbour_kind;
    const sluice_real gx = s->gravity[0], gy = s->gravity[1], gz = s->gravity[2];
    /* the wall neighbours' normals (mirrored walls only) */
    const sluice_real *nxj = mirror ? b->gathered[s->wall_normal.column] : NULL;
    const sluice_real *nyj = mirror ? b->gathered[s->wall_normal.column + 1] : NULL;
    const sluice_real *nzj = mirror && dims == 3 ? b->gathered[s->wall_normal.column + 2] : NULL;
    sluice_real *restrict ax = sluice_real_column(v, s->acceleration, 0);
    sluice_real *restrict ay = sluice_real_column(v, s->acceleration, 1);
    sluice_real *restrict az = dims == 3 ? sluice_real_column(v, s->acceleration, 2) : ay;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real pi = c.p[i], rhoi = c.rho[i], ci = c.c[i];
        const sluice_real vxi = c.vel[0][i], vyi = c.vel[1][i], vzi = c.vel[2][i];
        sluice_real sx = 0, sy = 0, sz = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            /* (v_i - v_j) . r_ij = -(u_L - u_R) |r_ij| */
            sluice_real dvr = (vxi - c.velj[0][k]) * rx[k] + (vyi - c.velj[1][k]) * ry[k];
            if (dims == 3)
                dvr += (vzi - c.velj[2][k]) * rz[k];
            sluice_real pstar, rho_right;
            if (mirror && kinds[k] == SLUICE_KIND_WALL) {
                /* right state: the fluid's own mirrored across the wall;
                 * compression along the wall normal */
                sluice_real un = (vxi - c.velj[0][k]) * nxj[k] + (vyi - c.velj[1][k]) * nyj[k];
                if (dims == 3)
                    un += (vzi - c.velj[2][k]) * nzj[k];
                const sluice_real du = -2 * un;
                sluice_real gr = gx * rx[k] + gy * ry[k];
                if (dims == 3)
                    gr += gz * rz[k];
                pstar = pi - (sluice_real)0.5 * rhoi * gr + (sluice_real)0.5 * rhoi *
                                                                 limiter_beta(s, du, ci) * du;
                rho_right = rhoi;
            } else {
                const sluice_real du = -dvr / dist[k];
                const sluice_real rho_bar = (sluice_real)0.5 * (rhoi + c.rhoj[k]);
                const sluice_real c_bar = (sluice_real)0.5 * (ci + c.cj[k]);
                pstar = (sluice_real)0.5 * (pi + c.pj[k]) +
                        (sluice_real)0.5 * rho_bar * limiter_beta(s, du, c_bar) * du;
                rho_right = c.rhoj[k];
            }
            const sluice_real f = 2 * c.mj[k] * pstar / (rhoi * rho_right) * F[k];
            sx += f * rx[k];
            sy += f * ry[k];
            if (dims == 3)
                sz += f * rz[k];
        }
        ax[i] -= sx;
        ay[i] -= sy;
        if (dims == 3)
            az[i] -= sz;
    }
}

static inline void continuity_pairs(const riemann_state *s, const sluice_view *v,
                                    const sluice_pair_batch *b, const uint32_t dims,
                                    const int mirror)
{
    pair_columns c;
    gather_columns(s, v, b, dims, &c);
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict dist = b->distance;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const uint8_t *restrict kinds = b->neighbour_kind;
    const sluice_real hydro = s->hydrostatic ? 1 : 0;
    const sluice_real gx = s->gravity[0], gy = s->gravity[1], gz = s->gravity[2];
    sluice_real *restrict rate = sluice_real_column(v, s->density_rate, 0);
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const int wall_target = v->kind[i] == SLUICE_KIND_WALL;
        if (wall_target && mirror)
            continue;
        const sluice_real pi = c.p[i], rhoi = c.rho[i], ci = c.c[i];
        const sluice_real vxi = c.vel[0][i], vyi = c.vel[1][i], vzi = c.vel[2][i];
        sluice_real sum = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const int wall_neighbour = kinds[k] == SLUICE_KIND_WALL;
            if (wall_target && wall_neighbour)
                continue;
            sluice_real dvr = (vxi - c.velj[0][k]) * rx[k] + (vyi - c.velj[1][k]) * ry[k];
            if (dims == 3)
                dvr += (vzi - c.velj[2][k]) * rz[k];
            sluice_real gr = gx * rx[k] + gy * ry[k];
            if (dims == 3)
                gr += gz * rz[k];
            if (mirror && wall_neighbour) {
                /* rho_R = rho_i, u_R = 2 u_w - u_L: 2 rho_i (m_j / rho_i) (u_L - U*),
                 * U* = u_w + (1 - hydro) g . r / (2 c_i) */
                sum += c.mj[k] * F[k] * (2 * dvr + (1 - hydro) * dist[k] * gr / ci);
            } else {
                const sluice_real rho_bar = (sluice_real)0.5 * (rhoi + c.rhoj[k]);
                const sluice_real c_bar = (sluice_real)0.5 * (ci + c.cj[k]);
                const sluice_real dp = pi - c.pj[k] - hydro * rho_bar * gr;
                sum += rhoi * c.mj[k] / c.rhoj[k] * F[k] *
                       (dvr + dist[k] * dp / (rho_bar * c_bar));
            }
        }
        rate[i] += sum;
    }
}

static void riemann_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const riemann_state *s = state;
    /* the mirrored wall state only where a wall is among the batch's neighbours */
    const int mirror =
        s->walls == WALLS_MIRROR && (b->neighbour_kinds & SLUICE_KIND_MASK(SLUICE_KIND_WALL));
    if (s->term == TERM_PRESSURE) {
        if (v->dimensions == 3)
            mirror ? pressure_pairs(s, v, b, 3, 1) : pressure_pairs(s, v, b, 3, 0);
        else
            mirror ? pressure_pairs(s, v, b, 2, 1) : pressure_pairs(s, v, b, 2, 0);
    } else {
        if (v->dimensions == 3)
            mirror ? continuity_pairs(s, v, b, 3, 1) : continuity_pairs(s, v, b, 3, 0);
        else
            mirror ? continuity_pairs(s, v, b, 2, 1) : continuity_pairs(s, v, b, 2, 0);
    }
}

static const sluice_component components[] = {
    {
        .name = "riemann_pressure",
        .summary = "pressure force from a low-dissipation Riemann solver per pair: -2 sum_j m_j "
                   "P*/(rho_i rho_j) grad W",
        .reference = "Zhang, Hu & Adams (2017), J. Comput. Phys. 335:605-620",
        .dimensions = SLUICE_DIMS_ALL,
        .params = pressure_params,
        .param_count = SLUICE_COUNT(pressure_params),
        .config_size = sizeof(pressure_config),
        .fields = pressure_fields,
        .field_count = SLUICE_COUNT(pressure_fields),
        .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .neighbour_kinds =
            SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
        .create = pressure_create,
        .destroy = riemann_destroy,
        .bind = riemann_bind,
        .prepare = riemann_prepare,
        .pair = riemann_pair,
    },
    {
        .name = "riemann_continuity",
        .summary = "continuity equation with the Riemann solver's interface velocity: "
                   "2 rho_i sum_j V_j (v_i - v*) . grad W",
        .reference = "Zhang, Hu & Adams (2017), J. Comput. Phys. 335:605-620",
        .dimensions = SLUICE_DIMS_ALL,
        .params = continuity_params,
        .param_count = SLUICE_COUNT(continuity_params),
        .config_size = sizeof(continuity_config),
        .fields = continuity_fields,
        .field_count = SLUICE_COUNT(continuity_fields),
        .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
        .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
        /* a wall particle sums over the fluid alone */
        .neighbour_kinds_by_target = {[SLUICE_KIND_WALL] = SLUICE_KIND_MASK(SLUICE_KIND_FLUID)},
        .create = continuity_create,
        .destroy = riemann_destroy,
        .bind = riemann_bind,
        .pair = riemann_pair,
    },
};

SLUICE_DEFINE_LIBRARY("riemann", "1.1.0",
                      "Riemann-solver SPH: pressure force and continuity equation from a "
                      "low-dissipation Riemann solver per pair",
                      SLUICE_DIMS_ALL, components)
