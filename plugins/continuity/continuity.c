/* Continuity equation (seeds 002, 004; Monaghan 1992):
 *   d rho_i / dt = sum_j m_j (v_i - v_j) . grad_i W_ij
 * Targets fluid and wall particles (dynamic boundary particles obey it too).
 * Symmetric in i, j: total mass is conserved exactly. */
#include "plugin_util.h"

typedef struct continuity_state {
    const sluice_api *api;
    sluice_field velocity, mass, density_rate;
} continuity_state;

static const sluice_field_spec fields[] = {
    {"velocity", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1",
     SLUICE_READ | SLUICE_READ_NEIGHBOUR, SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0,
     "velocity"},
    {"mass", SLUICE_TYPE_REAL, 1, "kg", SLUICE_READ_NEIGHBOUR, SLUICE_FIELD_RESTART, NULL, 0,
     "particle mass"},
    {"density", SLUICE_TYPE_REAL, 1, "kg m^-3", 0, SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART,
     NULL, 0, "mass density"},
    {"density_rate", SLUICE_TYPE_REAL, 1, "kg m^-3 s^-1", SLUICE_ACCUMULATE, 0, "density",
     SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
     "time derivative of the density"},
};

static int continuity_create(const sluice_api *api, sluice_host *host, const void *config,
                             void **state)
{
    (void)config;
    continuity_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    *state = s;
    return SLUICE_OK;
}

static int continuity_bind(void *state, sluice_host *host)
{
    continuity_state *s = state;
    static const char *const names[] = {"velocity", "mass", "density_rate"};
    sluice_field f[3];
    if (sluice_util_fields(s->api, host, names, f, 3) != SLUICE_OK)
        return SLUICE_ERROR;
    s->velocity = f[0];
    s->mass = f[1];
    s->density_rate = f[2];
    return SLUICE_OK;
}

static void continuity_destroy(void *state)
{
    free(state);
}

static inline void continuity_pairs(const continuity_state *s, const sluice_view *v,
                                    const sluice_pair_batch *b, const uint32_t dims)
{
    const sluice_real *vel[3], *vj[3];
    for (uint32_t d = 0; d < dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        vj[d] = b->gathered[s->velocity.column + (int32_t)d];
    }
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const sluice_real *restrict vxj = vj[0], *restrict vyj = vj[1];
    const sluice_real *restrict vzj = dims == 3 ? vj[2] : vj[1];
    sluice_real *restrict rate = sluice_real_column(v, s->density_rate, 0);
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vxi = vel[0][i], vyi = vel[1][i], vzi = dims == 3 ? vel[2][i] : 0;
        sluice_real sum = 0;

        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            sluice_real dot = (vxi - vxj[k]) * rx[k] + (vyi - vyj[k]) * ry[k];
            if (dims == 3)
                dot += (vzi - vzj[k]) * rz[k];
            sum += mj[k] * dot * F[k];
        }
        rate[i] += sum;
    }
}

static void continuity_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    if (v->dimensions == 3)
        continuity_pairs(state, v, b, 3);
    else
        continuity_pairs(state, v, b, 2);
}

static const sluice_component components[] = {{
    .name = "continuity",
    .summary = "continuity equation d rho/dt = sum_j m_j v_ij . grad W",
    .reference = "Monaghan (1992); seeds 002 and 004",
    .dimensions = SLUICE_DIMS_ALL,
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = continuity_create,
    .destroy = continuity_destroy,
    .bind = continuity_bind,
    .pair = continuity_pair,
}};

SLUICE_DEFINE_LIBRARY("continuity", "1.0.0", "continuity equation", SLUICE_DIMS_ALL, components)
