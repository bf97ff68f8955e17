/* Pressure gradient in the symmetric form that conserves linear momentum
 * (seeds 002, 004; Monaghan 1992):
 *   dv_i/dt += - sum_j m_j (p_i / rho_i^2 + p_j / rho_j^2) grad_i W_ij
 * Targets fluid particles; wall particles act through their pressure (DBC). */
#include "plugin_util.h"

typedef struct pressure_state {
    const sluice_api *api;
    sluice_field pressure, density, mass, acceleration;
} pressure_state;

static const sluice_field_spec fields[] = {
    {"pressure", SLUICE_TYPE_REAL, 1, "Pa", SLUICE_READ | SLUICE_READ_NEIGHBOUR,
     SLUICE_FIELD_OUTPUT, NULL, 0, "pressure"},
    {"density", SLUICE_TYPE_REAL, 1, "kg m^-3", SLUICE_READ | SLUICE_READ_NEIGHBOUR,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "mass density"},
    {"mass", SLUICE_TYPE_REAL, 1, "kg", SLUICE_READ_NEIGHBOUR, SLUICE_FIELD_RESTART, NULL, 0,
     "particle mass"},
    {"velocity", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1", 0,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "velocity"},
    {"acceleration", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-2", SLUICE_ACCUMULATE, 0,
     "velocity", SLUICE_KIND_MASK(SLUICE_KIND_FLUID), "time derivative of the velocity"},
};

static int pressure_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state)
{
    (void)config;
    pressure_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    *state = s;
    return SLUICE_OK;
}

static int pressure_bind(void *state, sluice_host *host)
{
    pressure_state *s = state;
    static const char *const names[] = {"pressure", "density", "mass", "acceleration"};
    sluice_field f[4];
    if (sluice_util_fields(s->api, host, names, f, 4) != SLUICE_OK)
        return SLUICE_ERROR;
    s->pressure = f[0];
    s->density = f[1];
    s->mass = f[2];
    s->acceleration = f[3];
    return SLUICE_OK;
}

static void pressure_destroy(void *state)
{
    free(state);
}

static inline void pressure_pairs(const pressure_state *s, const sluice_view *v,
                                  const sluice_pair_batch *b, const uint32_t dims)
{
    const sluice_real *restrict p = sluice_real_column(v, s->pressure, 0);
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict pj = b->gathered[s->pressure.column];
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    sluice_real *restrict ax = sluice_real_column(v, s->acceleration, 0);
    sluice_real *restrict ay = sluice_real_column(v, s->acceleration, 1);
    sluice_real *restrict az = dims == 3 ? sluice_real_column(v, s->acceleration, 2) : ay;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real pi_term = p[i] / (rho[i] * rho[i]);
        sluice_real sx = 0, sy = 0, sz = 0;

        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            sluice_real c = mj[k] * (pi_term + pj[k] / (rhoj[k] * rhoj[k])) * F[k];
            sx += c * rx[k];
            sy += c * ry[k];
            if (dims == 3)
                sz += c * rz[k];
        }
        ax[i] -= sx;
        ay[i] -= sy;
        if (dims == 3)
            az[i] -= sz;
    }
}

static void pressure_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    if (v->dimensions == 3)
        pressure_pairs(state, v, b, 3);
    else
        pressure_pairs(state, v, b, 2);
}

static const sluice_component components[] = {{
    .name = "pressure_gradient",
    .summary = "pressure force -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W",
    .reference = "Monaghan (1992); seeds 002 and 004",
    .dimensions = SLUICE_DIMS_ALL,
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = pressure_create,
    .destroy = pressure_destroy,
    .bind = pressure_bind,
    .pair = pressure_pair,
}};

SLUICE_DEFINE_LIBRARY("pressure_gradient", "1.0.0", "pressure gradient", SLUICE_DIMS_ALL,
                      components)
