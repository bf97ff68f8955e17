/* Monaghan artificial viscosity (Monaghan 1992; seeds 000, 001, 002):
 *   dv_i/dt += - sum_j m_j Pi_ij grad_i W_ij,
 *   Pi_ij = (-alpha cbar_ij mu_ij + beta mu_ij^2) / rhobar_ij  when v_ij . r_ij < 0, else 0,
 *   mu_ij = h v_ij . r_ij / (r^2 + eta^2),  eta^2 = 0.01 h^2.
 * It also limits the time step with the viscous condition of Monaghan (1989)
 * as used by DualSPHysics: dt <= C h / (c_i + max_j |mu_ij|), with the
 * Courant number C published by the time-step plugin. With time_step_limit:
 * false it sets no limit (and computes no max |mu_ij|), so that the acoustic
 * condition alone sets the step (seed 000, eq. 18). With speed_of_sound
 * given, cbar_ij is that constant for every pair: in a two-phase scene the
 * water's c0, so that the air's artificial viscosity (nu = alpha c h / 8)
 * is the water's and not c0_air / c0_water = 13.5 times it. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct av_config {
    sluice_real alpha, beta, speed_of_sound;
    int time_step_limit;
    int phases;
} av_config;

enum { PHASES_ALL = 0, PHASES_SAME = 1 };

typedef struct av_state {
    const sluice_api *api;
    sluice_real alpha, beta, h, eta2, courant;
    sluice_real speed; /* > 0: cbar for every pair; 0: the pair's mean */
    int limit;         /* the viscous time-step limit is on */
    int same_phase;    /* phases: same, pairs of one phase only */
    sluice_field velocity, density, sound_speed, mass, acceleration, mu_max, phase;
} av_state;

static const sluice_param_spec params[] = {
    {"alpha", SLUICE_PARAM_REAL, offsetof(av_config, alpha), "0.1", 0, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "linear coefficient (seed 000: 0.1, seed 002: 0.06)", NULL, 0},
    {"beta", SLUICE_PARAM_REAL, offsetof(av_config, beta), "0", 0, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1", "quadratic coefficient (seeds: 0)", NULL, 0},
    {"time_step_limit", SLUICE_PARAM_BOOL, offsetof(av_config, time_step_limit), "true", 0, 0, 0,
     NULL,
     "limit the time step to C h / (c_i + max_j |mu_ij|), with max_j |mu_ij| kept in the field "
     "viscous_mu_max (m s^-1); false leaves the step to the other conditions (seed 000: the "
     "acoustic condition alone)",
     NULL, 0},
    {"speed_of_sound", SLUICE_PARAM_REAL, offsetof(av_config, speed_of_sound), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_OPTIONAL, "m s^-1",
     "c in Pi_ij for every pair instead of the pair's mean sound speed; two phases: the water's "
     "c0, so that the air's artificial viscosity alpha c h / 8 is the water's and not 13.5 times "
     "it (default: the pair's mean)",
     NULL, 0},
    {"phases", SLUICE_PARAM_ENUM, offsetof(av_config, phases), "all", 0, 0, 0, NULL,
     "all: every fluid and wall neighbour (seed 001); same: with two_phase loaded, water with "
     "water and walls, air with air and walls, so that no artificial viscosity couples the air "
     "to the water (Pi_ij stays symmetric: momentum is still conserved)",
     "all|same", 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_SOUND_SPEED_DOC(SLUICE_READ | SLUICE_READ_NEIGHBOUR, "local speed of sound"),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
};

/* declared only when the time-step limit is on */
static const sluice_field_spec mu_max_field = {
    "viscous_mu_max", SLUICE_TYPE_REAL, 1, "m s^-1", SLUICE_WRITE, 0, NULL, 0,
    "largest |mu_ij| over the neighbours (viscous time-step condition)"};

static int av_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const av_config *c = config;
    av_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->alpha = c->alpha;
    s->beta = c->beta;
    s->speed = c->speed_of_sound;
    s->limit = c->time_step_limit;
    s->same_phase = c->phases == PHASES_SAME;
    if (sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        (s->limit && api->fields->declare_field(host, &mu_max_field) != SLUICE_OK)) {
        free(s);
        return SLUICE_ERROR;
    }
    s->eta2 = (sluice_real)0.01 * s->h * s->h;
    *state = s;
    return SLUICE_OK;
}

static int av_bind(void *state, sluice_host *host)
{
    av_state *s = state;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity}, {"density", &s->density},
        {"sound_speed", &s->sound_speed}, {"mass", &s->mass},
        {"acceleration", &s->acceleration}, {"viscous_mu_max", &s->mu_max}};
    /* viscous_mu_max only with the time-step limit */
    if (sluice_util_bind(s->api, host, fields, s->limit ? 6 : 5) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->same_phase && sluice_util_phase_field(s->api, host, &s->phase) != SLUICE_OK)
        return SLUICE_ERROR;
    if (!s->limit)
        return SLUICE_OK;
    if (sluice_util_constant(s->api, host, "courant_number", &s->courant) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static void av_destroy(void *state)
{
    free(state);
}

/* limit: also record max_j |mu_ij| for the time-step limit (specialised) */
static inline void av_pairs(const av_state *s, const sluice_view *v, const sluice_pair_batch *b,
                            const uint32_t dims, const int limit, const int fixed_speed,
                            const int same_phase)
{
    const uint8_t *restrict phase =
        same_phase ? (const uint8_t *)v->columns[s->phase.column] : NULL;
    const sluice_index *restrict nb = b->neighbour;
    const uint8_t *restrict kj = b->neighbour_kind;
    const sluice_real *vel[3], *vj[3];
    for (uint32_t d = 0; d < dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        vj[d] = b->gathered[s->velocity.column + (int32_t)d];
    }
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict cs = sluice_real_column(v, s->sound_speed, 0);
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict cj = b->gathered[s->sound_speed.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const sluice_real *restrict r = b->distance;
    const sluice_real *restrict vxj = vj[0], *restrict vyj = vj[1];
    const sluice_real *restrict vzj = dims == 3 ? vj[2] : vj[1];
    sluice_real *restrict ax = sluice_real_column(v, s->acceleration, 0);
    sluice_real *restrict ay = sluice_real_column(v, s->acceleration, 1);
    sluice_real *restrict az = dims == 3 ? sluice_real_column(v, s->acceleration, 2) : ay;
    sluice_real *restrict mu_max = limit ? sluice_real_column(v, s->mu_max, 0) : NULL;
    const sluice_real h = s->h, eta2 = s->eta2, alpha = s->alpha, beta = s->beta;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vxi = vel[0][i], vyi = vel[1][i], vzi = dims == 3 ? vel[2][i] : 0;
        const sluice_real rhoi = rho[i], ci = cs[i];
        sluice_real sx = 0, sy = 0, sz = 0;
        int64_t worst = 0; /* bits of the largest |mu| */

        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            sluice_real dot = (vxi - vxj[k]) * rx[k] + (vyi - vyj[k]) * ry[k];
            if (dims == 3)
                dot += (vzi - vzj[k]) * rz[k];
            /* one division per pair: 1 / ((r^2 + eta^2) rhobar) gives both
             * mu = h v.r / (r^2 + eta^2) and the 1 / rhobar of Pi (the divider
             * bounds the pair loop, docs/performance.md) */
            const sluice_real cbar = fixed_speed ? s->speed : (sluice_real)0.5 * (ci + cj[k]);
            const sluice_real sum_rho = rhoi + rhoj[k]; /* 2 rhobar */
            const sluice_real denominator = r[k] * r[k] + eta2;
            const sluice_real inverse = 1 / (denominator * sum_rho);
            const sluice_real mu = h * dot * sum_rho * inverse;
            if (limit) {
                const int64_t amu = sluice_util_bits(mu < 0 ? -mu : mu);
                worst = amu > worst ? amu : worst;
            }
            sluice_real pi =
                dot < 0 ? 2 * (-alpha * cbar * mu + beta * mu * mu) * denominator * inverse : 0;
            if (same_phase) /* walls act on both phases */
                pi = kj[k] == SLUICE_KIND_WALL || phase[nb[k]] == phase[i] ? pi : 0;
            const sluice_real c = mj[k] * pi * F[k];
            sx += c * rx[k];
            sy += c * ry[k];
            if (dims == 3)
                sz += c * rz[k];
        }
        ax[i] -= sx;
        ay[i] -= sy;
        if (dims == 3)
            az[i] -= sz;
        if (limit)
            mu_max[i] = sluice_util_from_bits(worst);
    }
}

static void av_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const av_state *s = state;
    const int fixed = s->speed > 0;
    if (s->same_phase) {
        /* not vectorised: the phase is a byte gathered through the index */
        if (v->dimensions == 3)
            av_pairs(s, v, b, 3, s->limit, fixed, 1);
        else
            av_pairs(s, v, b, 2, s->limit, fixed, 1);
        return;
    }
    if (v->dimensions == 3) {
        if (s->limit)
            fixed ? av_pairs(s, v, b, 3, 1, 1, 0) : av_pairs(s, v, b, 3, 1, 0, 0);
        else
            fixed ? av_pairs(s, v, b, 3, 0, 1, 0) : av_pairs(s, v, b, 3, 0, 0, 0);
    } else {
        if (s->limit)
            fixed ? av_pairs(s, v, b, 2, 1, 1, 0) : av_pairs(s, v, b, 2, 1, 0, 0);
        else
            fixed ? av_pairs(s, v, b, 2, 0, 1, 0) : av_pairs(s, v, b, 2, 0, 0, 0);
    }
}

static sluice_real av_time_step_limit(void *state, const sluice_view *v, sluice_index begin,
                                      sluice_index end)
{
    const av_state *s = state;
    if (!s->limit)
        return (sluice_real)INFINITY;
    const sluice_real *mu = sluice_real_column(v, s->mu_max, 0);
    const sluice_real *c = sluice_real_column(v, s->sound_speed, 0);
    sluice_real limit = (sluice_real)INFINITY;
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        sluice_real dt = s->courant * s->h / (c[i] + mu[i]);
        if (dt < limit || dt != dt)
            limit = dt;
    }
    return limit;
}

static const sluice_component components[] = {{
    .name = "artificial_viscosity",
    .summary = "Monaghan artificial viscosity (alpha, beta) with its viscous time-step limit",
    .reference = "Monaghan (1992); seeds 000, 001, 002",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(av_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = av_create,
    .destroy = av_destroy,
    .bind = av_bind,
    .pair = av_pair,
    .time_step_limit = av_time_step_limit,
}};

SLUICE_DEFINE_LIBRARY("artificial_viscosity", "1.3.0", "Monaghan artificial viscosity",
                      SLUICE_DIMS_ALL, components)
