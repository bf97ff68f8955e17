/* SPH velocity gradient (seed 004, section 3; Bonet & Lok 1999 for the
 * renormalised form):
 *   G_i,ab = d v_a / d x_b |_i = sum_j V_j (v_j - v_i)_a (grad^_i W_ij)_b,   V_j = m_j / rho_j,
 * over fluid and wall neighbours (wall particles carry their own velocity:
 * zero for fixed dynamic-boundary walls, which is how they impose no-slip).
 *  - renormalise false: grad^_i W_ij = grad_i W_ij = r_ij F_ij. For a linear
 *    field v = A x the result is A M_i with M_i,cb = -sum_j V_j r_ij,c r_ij,b F_ij,
 *    the kernel's second moment over the actual neighbours (the identity in the
 *    continuum limit; on a regular lattice it differs from the identity by a
 *    lattice-sum error that depends only on h/dx).
 *  - renormalise true: (grad^_i W_ij)_b = sum_c L_i,bc (r_ij F_ij)_c with L_i from
 *    the field kernel_correction (component kernel_correction), so that G is
 *    exact for every linear velocity field wherever L_i exists (M_i L_i^T = I).
 * Writes the field velocity_gradient, component a*dims + b = d v_a / d x_b, for
 * fluid particles (wall particles keep zero). */
#include <sluice/plugin_util.h>

typedef struct vg_config {
    int renormalise;
} vg_config;

typedef struct vg_state {
    const sluice_api *api;
    uint32_t dims;
    int renormalise;
    sluice_field velocity, mass, density, gradient, correction;
} vg_state;

static const sluice_param_spec params[] = {
    {"renormalise", SLUICE_PARAM_BOOL, offsetof(vg_config, renormalise), "false", 0, 0, 0, NULL,
     "use the renormalised kernel gradient L_i grad_i W_ij (reads kernel_correction, written by "
     "the kernel_correction plugin): exact for linear velocity fields, also at free surfaces",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ_NEIGHBOUR),
};

static int vg_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const vg_config *c = config;
    vg_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->renormalise = c->renormalise;
    if (sluice_util_dimensions(api, host, &s->dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    const sluice_field_spec gradient = SLUICE_SPEC_VELOCITY_GRADIENT(s->dims, SLUICE_WRITE);
    const sluice_field_spec correction = SLUICE_SPEC_KERNEL_CORRECTION(s->dims, SLUICE_READ);
    if (api->fields->declare_field(host, &gradient) != SLUICE_OK ||
        (s->renormalise && api->fields->declare_field(host, &correction) != SLUICE_OK)) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int vg_bind(void *state, sluice_host *host)
{
    vg_state *s = state;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity}, {"mass", &s->mass}, {"density", &s->density},
        {"velocity_gradient", &s->gradient}};
    if (sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->renormalise && s->api->fields->field(host, "kernel_correction", &s->correction) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static void vg_destroy(void *state)
{
    free(state);
}

/* One loop per (dims, renormalise): no test of either inside. */
static inline void vg_pairs(const vg_state *s, const sluice_view *v, const sluice_pair_batch *b,
                            const uint32_t dims, const int renormalise)
{
    const sluice_real *vel[3];
    for (uint32_t d = 0; d < dims; d++)
        vel[d] = sluice_real_column(v, s->velocity, d);
    sluice_real *out[9];
    const sluice_real *L[9];
    for (uint32_t c = 0; c < dims * dims; c++) {
        out[c] = sluice_real_column(v, s->gradient, c);
        L[c] = renormalise ? sluice_real_column(v, s->correction, c) : NULL;
    }
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vi[3] = {vel[0][i], vel[1][i], dims == 3 ? vel[2][i] : 0};
        /* g_ab = sum_j V_j (v_j - v_i)_a (r_ij F_ij)_b */
        sluice_real g[9];
        sluice_velocity_gradient_sum(b, t, dims, s->velocity, s->mass, s->density, vi, g);
        for (uint32_t a = 0; a < dims; a++)
            for (uint32_t c = 0; c < dims; c++) {
                sluice_real value;
                if (renormalise) {
                    /* G_ac = sum_b g_ab L_cb: (grad^ W)_c = sum_b L_cb (r F)_b */
                    value = 0;
                    for (uint32_t bb = 0; bb < dims; bb++)
                        value += g[3 * a + bb] * L[c * dims + bb][i];
                } else {
                    value = g[3 * a + c];
                }
                out[a * dims + c][i] = value;
            }
    }
}

static void vg_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const vg_state *s = state;
    if (s->renormalise) {
        if (v->dimensions == 3)
            vg_pairs(s, v, b, 3, 1);
        else
            vg_pairs(s, v, b, 2, 1);
    } else {
        if (v->dimensions == 3)
            vg_pairs(s, v, b, 3, 0);
        else
            vg_pairs(s, v, b, 2, 0);
    }
}

static const sluice_component components[] = {{
    .name = "velocity_gradient",
    .summary = "SPH velocity gradient d v_a / d x_b (optionally with the renormalised kernel "
               "gradient)",
    .reference = "seed 004 (De Padova et al. 2017), section 3; Bonet & Lok (1999)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(vg_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = vg_create,
    .destroy = vg_destroy,
    .bind = vg_bind,
    .pair = vg_pair,
}};

SLUICE_DEFINE_LIBRARY("velocity_gradient", "1.0.0", "SPH velocity gradient", SLUICE_DIMS_ALL,
                      components)
