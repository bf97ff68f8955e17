/* Penalty contact between fluid particles and rigid wall segments (2D) or
 * triangles (3D): LS-DYNA's node-to-surface penalty contact as seed 000
 * (Jonsson et al. 2016, section 2.2) uses it, the particles being the slave
 * nodes and the scene's walls the master surface (rigid shells).
 *
 * A fluid particle closer than the contact distance d0 to a wall of this
 * scheme is connected to the wall by an interface spring along the contact
 * normal n (wall_contact.h defines the contacts: one per face within d0, one
 * along p - vertex at a convex vertex or edge, one along the nearest normal
 * for a particle behind the wall):
 *
 *   F_n = k (d0 - d) n,        d the gap (< 0 behind the wall),
 *   k   = f_s K A^2 / V,       K = rho0 c0^2 (the fluid's bulk modulus),
 *                              A = dx^(D-1), V = dx^D (the particle's face
 *                              and volume), so k = f_s rho0 c0^2 dx^(D-2),
 *
 * LS-DYNA's penalty stiffness of a solid segment (Theory Manual, "Penalty
 * method": k_i = f_si K_i A_i^2 / V_i) with the particle as the element and
 * f_s the penalty scale factor SLSFAC. The acceleration added is F / m with
 * m = rho0 dx^D, i.e. f_s c0^2 (d0 - d) / dx^2, the same in 2D and 3D.
 *
 * Default f_s = 1, not LS-DYNA's SLSFAC default of 0.1. Seed 000 chose the
 * spring stiffness "approximately in the order of magnitude as the
 * stiffness of the interface element", i.e. f_s ~ 1, and ran with the
 * physical c0 = 1484 m/s, where even 0.1 K is 56 times stiffer than K of a
 * weakly compressible fluid at c0 = 62.6 m/s. Relative to the pressures of
 * the flow (rho c0 v at impact) the wall is (c0_physical / c0)^2 softer
 * here: with f_s = 0.1 the dam break of configs/dam_break_2d.yaml
 * (dx = 0.02 m, c0 = 62.6 m/s) pushes particles 0.11 dx through the far
 * wall at impact; with f_s = 1 the smallest gap is 0.35 dx (suite
 * wall_forces, WALL_FORCES_DAM_DX=0.02).
 *
 * Friction (optional, Coulomb, coefficient mu): with v_t the particle's
 * velocity tangential to the contact (the walls are at rest),
 *
 *   F_t = - mu |F_n| v_t / sqrt(|v_t|^2 + v_s^2),   v_s = mu (|F_n| / m) dt_c,
 *
 * dt_c = C_p sqrt(m/k) the contact's time-step limit (below). It opposes
 * the slip and never exceeds mu |F_n|. Plain Coulomb friction, -mu |F_n|
 * v_t / |v_t|, switches sign with v_t and chatters in an explicit scheme:
 * a slip smaller than the velocity change mu (|F_n| / m) dt of one step is
 * reversed instead of stopped. Below v_s, that velocity change over dt_c,
 * the regularised force is viscous, -m v_t / dt_c: it removes the slip over
 * dt_c >= dt and never reverses it, whatever |F_n|; well above v_s it is
 * Coulomb's. No time-step limit of its own is needed.
 *
 * Time step: the explicit symplectic integrators (symplectic, verlet, euler
 * semi-implicit) are stable for a spring of frequency w = sqrt(k/m) while
 * w dt < 2. The limit is
 *
 *   dt <= C_p sqrt(m/k) = C_p dx / (c0 sqrt(f_s)),   C_p = 0.5 by default,
 *
 * i.e. w dt <= 0.5, a safety factor of 4 on one spring. n contacts acting
 * on one particle (a corner) stiffen it by at most n k (w dt <= 0.5 sqrt(n):
 * 0.87 for the three faces of a 3D corner), and the fluid's own pressure
 * stiffness acts on the same particle; both stay well inside the bound.
 * Against the time_step plugin's acoustic condition C h / c0 (C = 0.2,
 * h = 1.5 dx: 0.3 dx / c0) the contact limit is 1.7 times looser at the
 * default f_s = 1 (it costs nothing; 5.3 times at f_s = 0.1) and takes over
 * above f_s = (C_p / 0.3)^2 = 2.8.
 *
 * wall_backstop (second component of this library): the same spring, with
 * no friction, on the walls of every other scheme (dbc, mdbc,
 * ghost_particles, repulsive_force), as a safety net under a particle wall
 * scheme: d0 = `distance` (default dx/4, below the dx/2 at which the first
 * fluid layer sits, so that a fluid at rest against the wall never feels
 * it). The particle schemes hold the fluid only through the field they put
 * in the wall particles: mdbc and ghost particles mirror the fluid's
 * pressure, which is near zero in a thin supercritical stream pressed onto
 * a bed or in a free jet at a convex edge, so nothing pushes back a particle
 * that drifts onto the wall, and once behind it the mirrored field pushes it
 * further. The backstop catches it; the scene keeps its wall scheme
 * everywhere else. docs/validation.md gives the scenes that need it. */
#include <math.h>
#include <string.h>

#include <sluice/plugin_util.h>
#include "wall_contact.h"

typedef struct penalty_config {
    sluice_real contact_distance, penalty_scale, friction, time_step_factor;
} penalty_config;

typedef struct penalty_state {
    const sluice_api *api;
    sluice_host *host;
    uint32_t dims;
    sluice_real dx, h, rho0, c0;
    sluice_real d0, scale, mu, factor;
    sluice_real k, mass;      /* N m^-1 (3D; per unit depth in 2D), kg */
    sluice_real k_over_m;     /* s^-2 */
    sluice_real reach;        /* m: how far behind a wall a particle is still pushed back */
    sluice_real limit;        /* s: dt_c = C_p sqrt(m/k) */
    contact_walls walls;
    sluice_field acceleration, velocity;
    const char *scheme; /* the walls: those of this scheme, or with exclude all others */
    int exclude;
} penalty_state;

#define POSITIVE (SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE)

static const sluice_param_spec params[] = {
    {"contact_distance", SLUICE_PARAM_REAL, offsetof(penalty_config, contact_distance), NULL, 0,
     0, POSITIVE | SLUICE_PARAM_OPTIONAL, "m",
     "d0: a particle closer than this to a wall gets the spring force k (d0 - d) (default dx/2, "
     "the fluid's initial distance to the walls)",
     NULL, 0},
    {"penalty_scale", SLUICE_PARAM_REAL, offsetof(penalty_config, penalty_scale), "1", 0, 0,
     POSITIVE, "1",
     "f_s in k = f_s K A^2 / V = f_s rho0 c0^2 dx^(D-2) (LS-DYNA's SLSFAC; its default 0.1 "
     "assumes the physical c0 and leaks at weakly compressible c0)",
     NULL, 0},
    {"friction", SLUICE_PARAM_REAL, offsetof(penalty_config, friction), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "1",
     "Coulomb friction coefficient mu (0: frictionless walls, as in seed 000); regularised "
     "below the slip speed mu |F_n| dt_c / m",
     NULL, 0},
    {"time_step_factor", SLUICE_PARAM_REAL, offsetof(penalty_config, time_step_factor), "0.5", 0,
     2, POSITIVE | SLUICE_PARAM_HAS_MAX, "1",
     "C_p in dt <= C_p sqrt(m/k); a spring is stable below 2 sqrt(m/k)", NULL, 0},
};

typedef struct backstop_config {
    sluice_real distance, penalty_scale, time_step_factor;
} backstop_config;

static const sluice_param_spec backstop_params[] = {
    {"distance", SLUICE_PARAM_REAL, offsetof(backstop_config, distance), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m",
     "d0: a fluid particle closer than this to a wall of another scheme (or behind it) gets "
     "the spring force k (d0 - d) (default dx/4: a fluid at rest, dx/2 from the wall, never "
     "feels it)",
     NULL, 0},
    {"penalty_scale", SLUICE_PARAM_REAL, offsetof(backstop_config, penalty_scale), "1", 0, 0,
     POSITIVE, "1", "f_s in k = f_s rho0 c0^2 dx^(D-2), as penalty_contact", NULL, 0},
    {"time_step_factor", SLUICE_PARAM_REAL, offsetof(backstop_config, time_step_factor), "0.5",
     0, 2, POSITIVE | SLUICE_PARAM_HAS_MAX, "1", "C_p in dt <= C_p sqrt(m/k)", NULL, 0},
};

/* penalty_contact (the walls of its scheme) and wall_backstop (every other
 * wall) share the state and the spring. */
static int penalty_create_common(const sluice_api *api, sluice_host *host, penalty_state **out,
                                 sluice_real contact_distance, sluice_real default_fraction,
                                 sluice_real scale, sluice_real friction, sluice_real factor,
                                 const char *scheme, int exclude)
{
    penalty_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->host = host;
    sluice_real dims;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &s->dx) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->d0 = contact_distance > 0 ? contact_distance : default_fraction * s->dx;
    s->scale = scale;
    s->mu = friction;
    s->factor = factor;
    s->scheme = scheme;
    s->exclude = exclude;
    const sluice_field_spec fields[] = {
        SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
        SLUICE_SPEC_VELOCITY(s->mu > 0 ? SLUICE_READ : 0u),
    };
    for (size_t f = 0; f < sizeof fields / sizeof fields[0]; f++)
        if (api->fields->declare_field(host, &fields[f]) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
    *out = s;
    return SLUICE_OK;
}

static int penalty_create(const sluice_api *api, sluice_host *host, const void *config,
                          void **state)
{
    const penalty_config *c = config;
    return penalty_create_common(api, host, (penalty_state **)state, c->contact_distance, 0.5,
                                 c->penalty_scale, c->friction, c->time_step_factor,
                                 "penalty_contact", 0);
}

static int backstop_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state)
{
    const backstop_config *c = config;
    return penalty_create_common(api, host, (penalty_state **)state, c->distance, 0.25,
                                 c->penalty_scale, 0, c->time_step_factor, "penalty_contact", 1);
}

static int penalty_bind(void *state, sluice_host *host)
{
    penalty_state *s = state;
    const sluice_api *api = s->api;
    if (api->fields->constant(host, "speed_of_sound", &s->c0, 1) < 1) {
        api->messages->error(host, "needs the constant 'speed_of_sound' (the fluid's bulk modulus rho0 c0^2 "
                         "sets the penalty stiffness), which no loaded plugin publishes (load an "
                         "equation of state, e.g. tait)");
        return SLUICE_ERROR;
    }
    if (api->fields->field(host, "acceleration", &s->acceleration) != SLUICE_OK ||
        api->fields->field(host, "velocity", &s->velocity) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real support = 2;
    api->fields->constant(host, "kernel_support", &support, 1);
    s->reach = s->d0 + support * s->h;
    const sluice_real K = s->rho0 * s->c0 * s->c0;
    const sluice_real A = s->dims == 2 ? s->dx : s->dx * s->dx;
    const sluice_real V = A * s->dx;
    s->k = s->scale * K * A * A / V;
    s->mass = s->rho0 * V;
    s->k_over_m = s->k / s->mass;
    s->limit = s->factor * sqrt(s->mass / s->k);
    if (contact_walls_select(&s->walls, api, host, s->scheme, s->exclude, s->dims) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->walls.count == 0)
        api->messages->warning(host, s->exclude ? "no wall of the scene uses another scheme than "
                                        "penalty_contact: the backstop adds no force"
                                      : "no wall of the scene uses this scheme: it adds no force");
    else
        api->messages->info(host,
                  "k = %.6g N m^-1%s, d0 = %.6g m, stable-step limit C_p sqrt(m/k) = %.6g s",
                  (double)s->k, s->dims == 2 ? " per metre of depth" : "", (double)s->d0,
                  (double)s->limit);
    return SLUICE_OK;
}

static void penalty_destroy(void *state)
{
    penalty_state *s = state;
    contact_walls_free(&s->walls);
    free(s);
}

/* The contact forces on fluid particles [begin, end), specialised for the
 * dimension and for friction. */
static inline void penalty_range(const penalty_state *s, const sluice_view *v, sluice_index begin,
                                 sluice_index end, const uint32_t dims, const int friction)
{
    sluice_real *a[3] = {NULL, NULL, NULL};
    const sluice_real *u[3] = {NULL, NULL, NULL};
    for (uint32_t d = 0; d < dims; d++) {
        a[d] = sluice_real_column(v, s->acceleration, d);
        if (friction)
            u[d] = sluice_real_column(v, s->velocity, d);
    }
    const sluice_real km = s->k_over_m, d0 = s->d0, mu = s->mu, dt_c = s->limit;
    contact contacts[CONTACT_MAX];
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const sluice_real p[3] = {v->position[0][i], v->position[1][i],
                                  dims == 3 ? v->position[2][i] : 0};
        const uint32_t n =
            contact_find(&s->walls, s->api, s->host, p, d0, s->reach, dims, contacts);
        for (uint32_t c = 0; c < n; c++) {
            const sluice_real normal = km * (d0 - contacts[c].gap); /* |F_n| / m */
            const sluice_real *dir = contacts[c].direction;
            for (uint32_t d = 0; d < dims; d++)
                a[d][i] += normal * dir[d];
            if (friction) {
                sluice_real vn = 0, vt[3] = {0, 0, 0}, vt2 = 0;
                for (uint32_t d = 0; d < dims; d++)
                    vn += u[d][i] * dir[d];
                for (uint32_t d = 0; d < dims; d++) {
                    vt[d] = u[d][i] - vn * dir[d];
                    vt2 += vt[d] * vt[d];
                }
                const sluice_real slip = mu * normal * dt_c; /* v_s */
                const sluice_real scale = mu * normal / sqrt(vt2 + slip * slip);
                for (uint32_t d = 0; d < dims; d++)
                    a[d][i] -= scale * vt[d];
            }
        }
    }
}

static void penalty_particle(void *state, const sluice_view *v, sluice_index begin,
                             sluice_index end)
{
    const penalty_state *s = state;
    if (s->walls.count == 0)
        return;
    const int friction = s->mu > 0;
    if (s->dims == 2) {
        if (friction)
            penalty_range(s, v, begin, end, 2, 1);
        else
            penalty_range(s, v, begin, end, 2, 0);
    } else {
        if (friction)
            penalty_range(s, v, begin, end, 3, 1);
        else
            penalty_range(s, v, begin, end, 3, 0);
    }
}

static sluice_real penalty_limit(void *state, const sluice_view *v, sluice_index begin,
                                 sluice_index end)
{
    const penalty_state *s = state;
    (void)v;
    (void)begin;
    (void)end;
    return s->walls.count > 0 ? s->limit : (sluice_real)INFINITY;
}

static const sluice_component components[] = {
    {
        .name = "penalty_contact",
        .summary = "penalty contact of fluid particles with rigid wall segments/triangles: spring "
                   "force k (d0 - d) along the contact normal, optional Coulomb friction",
        .reference = "Jonsson et al. (2016), seed 000, section 2.2; LS-DYNA Theory Manual, penalty "
                     "method (k = f_s K A^2 / V, f_s = SLSFAC)",
        .dimensions = SLUICE_DIMS_ALL,
        .flags = SLUICE_COMPONENT_WALL_SCHEME,
        .params = params,
        .param_count = SLUICE_COUNT(params),
        .config_size = sizeof(penalty_config),
        .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .create = penalty_create,
        .destroy = penalty_destroy,
        .bind = penalty_bind,
        .particle = penalty_particle,
        .time_step_limit = penalty_limit,
    },
    {
        .name = "wall_backstop",
        .summary = "penalty spring (penalty_contact's, frictionless) on fluid particles that come "
                   "closer than d0 = dx/4 to the walls of the other schemes: a safety net under "
                   "particle wall schemes",
        .reference = "penalty_contact; docs/validation.md (the hydraulic jump with ghost and "
                     "mdbc walls)",
        .dimensions = SLUICE_DIMS_ALL,
        .params = backstop_params,
        .param_count = SLUICE_COUNT(backstop_params),
        .config_size = sizeof(backstop_config),
        .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .create = backstop_create,
        .destroy = penalty_destroy,
        .bind = penalty_bind,
        .particle = penalty_particle,
        .time_step_limit = penalty_limit,
    },
};

SLUICE_DEFINE_LIBRARY("penalty_contact", "1.1.0", "penalty contact walls (seed 000) and a "
                      "penalty backstop for the other wall schemes",
                      SLUICE_DIMS_ALL, components)
