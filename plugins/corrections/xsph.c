/* XSPH transport-velocity corrections, between fluid particles. The term
 * adds to transport_velocity_correction, du_i (with transport_velocity's
 * background-pressure term, if loaded): the integrators move fluid
 * particles with v_i + du_i, while the velocity field v itself is the
 * solution of the momentum equation and is left untouched.
 *
 *  - form position (Monaghan 1989; seed 001, Wan et al. 2017, epsilon = 0.3):
 *      dr_i/dt = v_i + epsilon sum_j (m_j / rhobar_ij) v_ji W_ij,
 *      v_ji = v_j - v_i,  rhobar_ij = (rho_i + rho_j) / 2,
 *    so du_i = epsilon sum_j (m_j / rhobar_ij) v_ji W_ij. The pair weight
 *    m_i m_j W_ij / rhobar_ij is symmetric, hence sum_i m_i du_i = 0: the
 *    correction moves no net momentum.
 *
 *  - form velocity_smoothing (seed 004, De Padova et al. 2017, section 3,
 *    after Monaghan 1992's two-stage XSPH, phi_v = 0.01): each particle is
 *    moved with
 *      v^X_i = phi sum_j V_j v_j What_ij + (1 - phi) v_i,   V_j = m_j / rho_j,
 *    where v_i is "the value obtained by solution of the [momentum]
 *    equation": the paper smooths the velocity particles are moved with, not
 *    the velocity that is integrated. What_ij = W_ij / sum_k V_k W_ik is the
 *    Shepard-normalised kernel, both sums including the particle itself
 *    (W_ii = W(0)), so that a uniform velocity is reproduced exactly even
 *    where the support is incomplete (free surface, walls):
 *      du_i = v^X_i - v_i = phi sum_{j != i} V_j W_ij (v_j - v_i)
 *                           / (V_i W(0) + sum_{j != i} V_j W_ij).
 *
 * Both forms vanish identically for a uniform velocity field. */
#include <sluice/plugin_util.h>

typedef struct xsph_config {
    int form;
    sluice_real epsilon, phi;
    int phases;
} xsph_config;

enum { PHASES_ALL = 0, PHASES_SAME = 1 };

enum { FORM_POSITION = 0, FORM_VELOCITY_SMOOTHING = 1 };

typedef struct xsph_state {
    const sluice_api *api;
    int form;
    sluice_real epsilon, phi;
    int same_phase; /* phases: same, between particles of one phase only */
    sluice_field velocity, density, mass, correction, phase;
} xsph_state;

static const sluice_param_spec params[] = {
    {"form", SLUICE_PARAM_ENUM, offsetof(xsph_config, form), "position", 0, 0, 0, NULL,
     "position: dr/dt = v + epsilon sum_j (m_j/rhobar_ij) v_ji W_ij (Monaghan 1989, seed 001); "
     "velocity_smoothing: particles move with phi <v>_Shepard + (1 - phi) v (seed 004)",
     "position|velocity_smoothing", 0},
    /* optional, without a default in the table: each belongs to one form,
     * and the other form's coefficient is refused, not silently ignored */
    {"epsilon", SLUICE_PARAM_REAL, offsetof(xsph_config, epsilon), NULL, 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX |
         SLUICE_PARAM_OPTIONAL,
     "1",
     "XSPH coefficient of the position form only (default 0.3, seed 001); refused with form "
     "velocity_smoothing",
     NULL, 0},
    {"phi", SLUICE_PARAM_REAL, offsetof(xsph_config, phi), NULL, 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX |
         SLUICE_PARAM_OPTIONAL,
     "1",
     "velocity smoothing coefficient phi_v of the velocity_smoothing form only (default 0.01, "
     "seed 004); refused with form position",
     NULL, 0},
    {"phases", SLUICE_PARAM_ENUM, offsetof(xsph_config, phases), "all", 0, 0, 0, NULL,
     "all: every fluid neighbour (seed 001); same: with two_phase loaded, neighbours of the "
     "target's phase only, so that the air next to the water is not moved with it (the position "
     "form's pair weight stays symmetric: momentum is still conserved)",
     "all|same", 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    {"transport_velocity_correction", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1",
     SLUICE_ACCUMULATE, 0, NULL, 0,
     "XSPH correction: fluid particles move with velocity + this"},
};

static int xsph_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const xsph_config *c = config;
    xsph_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->form = c->form;
    /* an optional parameter that is absent reads 0, which its range excludes */
    if (c->form == FORM_POSITION && c->phi > 0) {
        api->messages->error(host, "phi = %g is the coefficient of form velocity_smoothing, which this "
                         "scene does not use; form position takes epsilon (default 0.3)",
                   (double)c->phi);
        free(s);
        return SLUICE_ERROR;
    }
    if (c->form == FORM_VELOCITY_SMOOTHING && c->epsilon > 0) {
        api->messages->error(host, "epsilon = %g is the coefficient of form position, which this scene "
                         "does not use; form velocity_smoothing takes phi (default 0.01)",
                   (double)c->epsilon);
        free(s);
        return SLUICE_ERROR;
    }
    s->same_phase = c->phases == PHASES_SAME;
    s->epsilon = c->epsilon > 0 ? c->epsilon : (sluice_real)0.3;
    s->phi = c->phi > 0 ? c->phi : (sluice_real)0.01;
    *state = s;
    return SLUICE_OK;
}

static int xsph_bind(void *state, sluice_host *host)
{
    xsph_state *s = state;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity}, {"density", &s->density}, {"mass", &s->mass},
        {"transport_velocity_correction", &s->correction}};
    if (sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->same_phase && sluice_util_phase_field(s->api, host, &s->phase) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static void xsph_destroy(void *state)
{
    free(state);
}

/* One specialisation per (form, dimensions, masked): `masked` is set when
 * the batch may hold wall neighbours (the pass is shared with a term that
 * asks for them), which this term leaves out. */
static inline void xsph_pairs(const xsph_state *s, const sluice_view *v, const sluice_pair_batch *b,
                              const int smoothing, const uint32_t dims, const int masked,
                              const int same_phase)
{
    const uint8_t *restrict phase =
        same_phase ? (const uint8_t *)v->columns[s->phase.column] : NULL;
    const sluice_index *restrict nb = b->neighbour;
    const sluice_real *vel[3], *vj[3];
    for (uint32_t d = 0; d < dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        vj[d] = b->gathered[s->velocity.column + (int32_t)d];
    }
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict mass = sluice_real_column(v, s->mass, 0);
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict W = b->kernel;
    const uint8_t *restrict kj = b->neighbour_kind;
    const sluice_real *restrict vxj = vj[0], *restrict vyj = vj[1];
    const sluice_real *restrict vzj = dims == 3 ? vj[2] : vj[1];
    sluice_real *restrict ux = sluice_real_column(v, s->correction, 0);
    sluice_real *restrict uy = sluice_real_column(v, s->correction, 1);
    sluice_real *restrict uz = dims == 3 ? sluice_real_column(v, s->correction, 2) : uy;
    const sluice_real w0 = b->kernel_self;
    const sluice_real coefficient = smoothing ? s->phi : s->epsilon;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vxi = vel[0][i], vyi = vel[1][i], vzi = dims == 3 ? vel[2][i] : 0;
        const sluice_real rhoi = rho[i];
        sluice_real sx = 0, sy = 0, sz = 0, shepard = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            /* weight of v_ji: (m_j / rhobar_ij) W_ij, or V_j W_ij */
            sluice_real weight = smoothing ? mj[k] / rhoj[k] * W[k]
                                           : 2 * mj[k] / (rhoi + rhoj[k]) * W[k];
            if (masked)
                weight = kj[k] != SLUICE_KIND_WALL ? weight : 0;
            if (same_phase)
                weight = phase[nb[k]] == phase[i] ? weight : 0;
            sx += weight * (vxj[k] - vxi);
            sy += weight * (vyj[k] - vyi);
            if (dims == 3)
                sz += weight * (vzj[k] - vzi);
            if (smoothing)
                shepard += weight;
        }
        /* velocity_smoothing: Shepard sum with the self term V_i W(0) > 0 */
        const sluice_real scale =
            smoothing ? coefficient / (mass[i] / rhoi * w0 + shepard) : coefficient;
        ux[i] += scale * sx;
        uy[i] += scale * sy;
        if (dims == 3)
            uz[i] += scale * sz;
    }
}

static void xsph_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const xsph_state *s = state;
    const int masked = b->neighbour_kinds != SLUICE_KIND_MASK(SLUICE_KIND_FLUID);
    const int smoothing = s->form == FORM_VELOCITY_SMOOTHING;
    if (s->same_phase) {
        /* not vectorised: the phase is a byte gathered through the index */
        if (v->dimensions == 3)
            smoothing ? xsph_pairs(s, v, b, 1, 3, 1, 1) : xsph_pairs(s, v, b, 0, 3, 1, 1);
        else
            smoothing ? xsph_pairs(s, v, b, 1, 2, 1, 1) : xsph_pairs(s, v, b, 0, 2, 1, 1);
        return;
    }
    const int key = (smoothing << 2) | ((v->dimensions == 3) << 1) | masked;
    switch (key) {
    case 0: xsph_pairs(s, v, b, 0, 2, 0, 0); break;
    case 1: xsph_pairs(s, v, b, 0, 2, 1, 0); break;
    case 2: xsph_pairs(s, v, b, 0, 3, 0, 0); break;
    case 3: xsph_pairs(s, v, b, 0, 3, 1, 0); break;
    case 4: xsph_pairs(s, v, b, 1, 2, 0, 0); break;
    case 5: xsph_pairs(s, v, b, 1, 2, 1, 0); break;
    case 6: xsph_pairs(s, v, b, 1, 3, 0, 0); break;
    default: xsph_pairs(s, v, b, 1, 3, 1, 0); break;
    }
}

static const sluice_component components[] = {{
    .name = "xsph",
    .summary = "XSPH transport velocity: Monaghan's position form or seed 004's Shepard velocity "
               "smoothing",
    .reference = "Monaghan (1989, 1992); Wan et al. (2017, seed 001, epsilon = 0.3); De Padova et "
                 "al. (2017, seed 004, phi_v = 0.01)",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_NEEDS_KERNEL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(xsph_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = xsph_create,
    .destroy = xsph_destroy,
    .bind = xsph_bind,
    .pair = xsph_pair,
}};

SLUICE_DEFINE_LIBRARY("xsph", "1.3.0", "XSPH transport-velocity corrections", SLUICE_DIMS_ALL,
                      components)
