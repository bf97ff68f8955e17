/* Pressure gradient, in the two momentum-conserving forms of the seeds:
 *  - form symmetric (seeds 002, 004; Monaghan 1992):
 *      dv_i/dt += - sum_j m_j (p_i / rho_i^2 + p_j / rho_j^2) grad_i W_ij
 *  - form density_product (seed 000 eq. 17, LS-DYNA; Colagrossi & Landrini
 *    2003 for two phases, seed 001):
 *      dv_i/dt += - sum_j m_j (p_i + p_j) / (rho_i rho_j) grad_i W_ij
 * Both are antisymmetric in i, j, so linear momentum is conserved exactly.
 * The kernel gradient is never renormalised here (seed 004).
 * Targets fluid particles; wall particles act through their pressure (DBC). */
#include <sluice/plugin_util.h>

typedef struct pressure_config {
    int form;
} pressure_config;

enum { FORM_SYMMETRIC = 0, FORM_DENSITY_PRODUCT = 1 };

typedef struct pressure_state {
    const sluice_api *api;
    int form;
    sluice_field pressure, density, mass, acceleration;
} pressure_state;

static const sluice_param_spec params[] = {
    {"form", SLUICE_PARAM_ENUM, offsetof(pressure_config, form), "symmetric", 0, 0, 0, NULL,
     "symmetric: p_i/rho_i^2 + p_j/rho_j^2 (seeds 002, 004); density_product: "
     "(p_i + p_j)/(rho_i rho_j) (seed 000 eq. 17; two-phase flows, seed 001)",
     "symmetric|density_product", 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_PRESSURE_DOC(SLUICE_READ | SLUICE_READ_NEIGHBOUR, SLUICE_FIELD_OUTPUT, "pressure"),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_VELOCITY(0),
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
};

static int pressure_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state)
{
    const pressure_config *c = config;
    pressure_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->form = c->form;
    *state = s;
    return SLUICE_OK;
}

static int pressure_bind(void *state, sluice_host *host)
{
    pressure_state *s = state;
    const sluice_field_binding fields[] = {
        {"pressure", &s->pressure}, {"density", &s->density}, {"mass", &s->mass},
        {"acceleration", &s->acceleration}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void pressure_destroy(void *state)
{
    free(state);
}

static inline void pressure_pairs(const pressure_state *s, const sluice_view *v,
                                  const sluice_pair_batch *b, const uint32_t dims,
                                  const int product)
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
        const sluice_real pi_term = product ? p[i] : p[i] / (rho[i] * rho[i]);
        const sluice_real inverse_rhoi = 1 / rho[i];
        sluice_real sx = 0, sy = 0, sz = 0;

        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_real factor = product ? (pi_term + pj[k]) * inverse_rhoi / rhoj[k]
                                               : pi_term + pj[k] / (rhoj[k] * rhoj[k]);
            sluice_real c = mj[k] * factor * F[k];
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
    const pressure_state *s = state;
    const int product = s->form == FORM_DENSITY_PRODUCT;
    if (v->dimensions == 3)
        product ? pressure_pairs(s, v, b, 3, 1) : pressure_pairs(s, v, b, 3, 0);
    else
        product ? pressure_pairs(s, v, b, 2, 1) : pressure_pairs(s, v, b, 2, 0);
}

static const sluice_component components[] = {{
    .name = "pressure_gradient",
    .summary = "pressure force -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad W, or seed 000's form",
    .reference = "Monaghan (1992); seeds 002 and 004; Jonsson et al. (2016) eq. 17; "
                 "Colagrossi & Landrini (2003)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(pressure_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = pressure_create,
    .destroy = pressure_destroy,
    .bind = pressure_bind,
    .pair = pressure_pair,
}};

SLUICE_DEFINE_LIBRARY("pressure_gradient", "1.1.0", "pressure gradient", SLUICE_DIMS_ALL,
                      components)
