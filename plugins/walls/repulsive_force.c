/* Repulsive boundary force of the Lennard-Jones type (Monaghan 1994,
 * "Simulating free surface flows with SPH", J. Comput. Phys. 110, 399-406),
 * the analogue seed 000 (Jonsson et al. 2016, section 2.2) names for its
 * penalty walls. A fluid particle at distance r < r0 from a wall of this
 * scheme is accelerated along the contact normal n by
 *
 *   f(r) = D [(r0/r)^p1 - (r0/r)^p2] / r,     p1 = 12, p2 = 4,
 *
 * zero beyond r0 (an acceleration: D is in m^2 s^-2). Monaghan takes D of the
 * order of the square of the largest velocity, 5 g H for a dam break of
 * height H, and r0 the initial particle spacing.
 *
 * Differences from Monaghan (1994):
 *  - Smooth walls. Monaghan's walls are lines of boundary particles, each
 *    exerting a central force; their sum is corrugated along the wall (a
 *    particle sliding along it is slowed and deflected at every boundary
 *    particle, the reason Monaghan & Kos 1999 later weighted it). Here r is
 *    the distance to the wall surface itself (its nearest point), so the
 *    force is exactly normal to a face and the wall is frictionless. The
 *    contacts (one per face within r0, one along p - vertex at a convex
 *    vertex or edge, one along the nearest normal behind a wall) are those of
 *    penalty_contact (wall_contact.h).
 *  - r0 = dx/2 by default, not dx: Sluice's lattice starts the fluid dx/2
 *    from the walls (the spacing to a wall particle would be dx, to the wall
 *    surface it is dx/2), so that the initial state is force-free; with
 *    r0 = dx the force at dx/2 is 4080 D / r, which blasts the first layer
 *    away.
 *  - D = c0^2 / 40 by default: the scenes choose c0 = 10 v_max (Monaghan's
 *    rule too), and Monaghan's 5 g H is 2.5 v_max^2 for the dam break,
 *    where v_max^2 = 2 g H; so D = 2.5 (c0/10)^2, exactly 5 g H on the dam
 *    break (c0 = 10 sqrt(2 g H)) and 2.5 g H on a still tank
 *    (c0 = 10 sqrt(g H)).
 *  - Behind the wall (r < r0/2, including r <= 0 after a crossing) the force
 *    continues linearly from r0/2 with the slope there,
 *    f(r0/2) + kappa(r0/2) (r0/2 - r), so that it stays finite and pushes a
 *    particle that crossed the wall back out.
 *
 * Time step: the force's stiffness per unit mass at gap r is
 *   kappa(r) = -df/dr = D [(p1 + 1)(r0/r)^p1 - (p2 + 1)(r0/r)^p2] / r^2,
 * (p1 - p2) D / r0^2 at first contact (r = r0). A symplectic integrator is
 * stable for a spring while sqrt(kappa) dt < 2; the limit is
 *   dt <= C_p / sqrt(kappa_max),  C_p = 0.5 by default,
 * with kappa_max the largest over the fluid particles of the sum of kappa over
 * their current contacts (the closest approach of the step's start), and at
 * least kappa(r0) (a particle may come into contact within the step). */
#include <math.h>
#include <string.h>

#include <sluice/plugin_util.h>
#include "wall_contact.h"

typedef struct repulsive_config {
    sluice_real strength, cutoff, p1, p2, time_step_factor;
} repulsive_config;

typedef struct repulsive_state {
    const sluice_api *api;
    sluice_host *host;
    uint32_t dims;
    sluice_real dx, h;
    sluice_real D, r0, p1, p2, factor;
    int given_strength;
    sluice_real floor_r;      /* r0 / 2 */
    sluice_real floor_force;  /* f(r0/2), m s^-2 */
    sluice_real floor_kappa;  /* kappa(r0/2), s^-2 */
    sluice_real first_kappa;  /* kappa(r0) = (p1 - p2) D / r0^2 */
    sluice_real reach;
    contact_walls walls;
    sluice_field acceleration;
} repulsive_state;

#define POSITIVE (SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE)

static const sluice_param_spec params[] = {
    {"strength", SLUICE_PARAM_REAL, offsetof(repulsive_config, strength), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m^2 s^-2",
     "D, of the order of the largest velocity squared (Monaghan 1994: 5 g H for a dam break); "
     "default c0^2/40 = 2.5 (c0/10)^2",
     NULL, 0},
    {"cutoff", SLUICE_PARAM_REAL, offsetof(repulsive_config, cutoff), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m",
     "r0: no force beyond this distance from the wall (default dx/2, the fluid's initial "
     "distance to the walls)",
     NULL, 0},
    {"p1", SLUICE_PARAM_REAL, offsetof(repulsive_config, p1), "12", 0, 0, POSITIVE, "1",
     "repulsive exponent (Monaghan 1994: 12)", NULL, 0},
    {"p2", SLUICE_PARAM_REAL, offsetof(repulsive_config, p2), "4", 0, 0, POSITIVE, "1",
     "attractive exponent, < p1 (Monaghan 1994: 4)", NULL, 0},
    {"time_step_factor", SLUICE_PARAM_REAL, offsetof(repulsive_config, time_step_factor), "0.5",
     0, 2, POSITIVE | SLUICE_PARAM_HAS_MAX, "1",
     "C_p in dt <= C_p / sqrt(kappa_max), kappa = -df/dr at the closest approach", NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
    SLUICE_SPEC_VELOCITY(0),
};

/* f(r) for r0/2 <= r < r0 */
static sluice_real lj_force(const repulsive_state *s, sluice_real r)
{
    const sluice_real x = s->r0 / r;
    return s->D * (pow(x, s->p1) - pow(x, s->p2)) / r;
}

/* kappa(r) = -df/dr for r0/2 <= r <= r0 */
static sluice_real lj_kappa(const repulsive_state *s, sluice_real r)
{
    const sluice_real x = s->r0 / r;
    return s->D * ((s->p1 + 1) * pow(x, s->p1) - (s->p2 + 1) * pow(x, s->p2)) / (r * r);
}

static int repulsive_create(const sluice_api *api, sluice_host *host, const void *config,
                            void **state)
{
    const repulsive_config *c = config;
    repulsive_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->host = host;
    sluice_real dims;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &s->dx) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    if (!(c->p1 > c->p2)) {
        api->messages->error(host, "p1 (%g) must be larger than p2 (%g): the force must repel near the wall",
                   (double)c->p1, (double)c->p2);
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->D = c->strength;
    s->given_strength = c->strength > 0;
    s->r0 = c->cutoff > 0 ? c->cutoff : s->dx / 2;
    s->p1 = c->p1;
    s->p2 = c->p2;
    s->factor = c->time_step_factor;
    *state = s;
    return SLUICE_OK;
}

static int repulsive_bind(void *state, sluice_host *host)
{
    repulsive_state *s = state;
    const sluice_api *api = s->api;
    if (!s->given_strength) {
        sluice_real c0;
        if (api->fields->constant(host, "speed_of_sound", &c0, 1) < 1) {
            api->messages->error(host, "the default strength D = c0^2/40 needs the constant "
                             "'speed_of_sound', which no loaded plugin publishes: set strength "
                             "or load an equation of state (e.g. tait)");
            return SLUICE_ERROR;
        }
        s->D = c0 * c0 / 40;
    }
    if (api->fields->field(host, "acceleration", &s->acceleration) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real support = 2;
    api->fields->constant(host, "kernel_support", &support, 1);
    s->reach = s->r0 + support * s->h;
    s->floor_r = s->r0 / 2;
    s->floor_force = lj_force(s, s->floor_r);
    s->floor_kappa = lj_kappa(s, s->floor_r);
    s->first_kappa = (s->p1 - s->p2) * s->D / (s->r0 * s->r0);
    if (contact_walls_build(&s->walls, api, host, "repulsive_force", s->dims) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->walls.count == 0)
        api->messages->warning(host, "no wall of the scene uses this scheme: it adds no force");
    else
        api->messages->info(host, "D = %.6g m^2 s^-2, r0 = %.6g m, first-contact step limit %.6g s",
                  (double)s->D, (double)s->r0, (double)(s->factor / sqrt(s->first_kappa)));
    return SLUICE_OK;
}

static void repulsive_destroy(void *state)
{
    repulsive_state *s = state;
    contact_walls_free(&s->walls);
    free(s);
}

/* Acceleration magnitude at gap r (< r0). */
static inline sluice_real repulsive_magnitude(const repulsive_state *s, sluice_real r)
{
    if (r >= s->floor_r)
        return lj_force(s, r);
    return s->floor_force + s->floor_kappa * (s->floor_r - r);
}

static inline void repulsive_range(const repulsive_state *s, const sluice_view *v,
                                   sluice_index begin, sluice_index end, const uint32_t dims)
{
    sluice_real *a[3] = {NULL, NULL, NULL};
    for (uint32_t d = 0; d < dims; d++)
        a[d] = sluice_real_column(v, s->acceleration, d);
    contact contacts[CONTACT_MAX];
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const sluice_real p[3] = {v->position[0][i], v->position[1][i],
                                  dims == 3 ? v->position[2][i] : 0};
        const uint32_t n =
            contact_find(&s->walls, s->api, s->host, p, s->r0, s->reach, dims, contacts);
        for (uint32_t c = 0; c < n; c++) {
            const sluice_real f = repulsive_magnitude(s, contacts[c].gap);
            for (uint32_t d = 0; d < dims; d++)
                a[d][i] += f * contacts[c].direction[d];
        }
    }
}

static void repulsive_particle(void *state, const sluice_view *v, sluice_index begin,
                               sluice_index end)
{
    const repulsive_state *s = state;
    if (s->walls.count == 0)
        return;
    if (s->dims == 2)
        repulsive_range(s, v, begin, end, 2);
    else
        repulsive_range(s, v, begin, end, 3);
}

static sluice_real repulsive_limit(void *state, const sluice_view *v, sluice_index begin,
                                   sluice_index end)
{
    const repulsive_state *s = state;
    if (s->walls.count == 0)
        return (sluice_real)INFINITY;
    const uint32_t dims = s->dims;
    sluice_real kappa_max = s->first_kappa;
    contact contacts[CONTACT_MAX];
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const sluice_real p[3] = {v->position[0][i], v->position[1][i],
                                  dims == 3 ? v->position[2][i] : 0};
        const uint32_t n =
            contact_find(&s->walls, s->api, s->host, p, s->r0, s->reach, dims, contacts);
        sluice_real kappa = 0;
        for (uint32_t c = 0; c < n; c++)
            kappa += contacts[c].gap >= s->floor_r ? lj_kappa(s, contacts[c].gap) : s->floor_kappa;
        if (kappa > kappa_max)
            kappa_max = kappa;
    }
    return s->factor / sqrt(kappa_max);
}

static const sluice_component components[] = {{
    .name = "repulsive_force",
    .summary = "Lennard-Jones-type repulsive wall force D[(r0/r)^p1 - (r0/r)^p2]/r along the "
               "wall normal (smooth walls)",
    .reference = "Monaghan (1994), J. Comput. Phys. 110, 399-406; seed 000 section 2.2",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_WALL_SCHEME,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(repulsive_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = repulsive_create,
    .destroy = repulsive_destroy,
    .bind = repulsive_bind,
    .particle = repulsive_particle,
    .time_step_limit = repulsive_limit,
}};

SLUICE_DEFINE_LIBRARY("repulsive_force", "1.0.0", "Lennard-Jones-type repulsive walls "
                      "(Monaghan 1994)", SLUICE_DIMS_ALL, components)
