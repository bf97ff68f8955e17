/* delta-SPH density diffusion (seed 002 with delta = 0.1, as in DualSPHysics):
 *   d rho_i/dt += delta h c0 sum_j psi_ij . grad_i W_ij V_j,  V_j = m_j / rho_j,
 * between fluid particles only.
 *  - form molteni_colagrossi (Molteni & Colagrossi 2009):
 *      psi_ij = 2 (rho_j - rho_i) r_ji / (r^2 + eta^2)
 *    diffuses every density difference, including the hydrostatic one: a
 *    column at rest slowly loses its hydrostatic pressure.
 *  - form fourtakas (Fourtakas et al. 2019):
 *      psi_ij = 2 (rho_j - rho_i - rho^H_ji) r_ji / (r^2 + eta^2),
 *      rho^H_ji = rho0 (g . r_ji) / c0^2
 *    (the linearised hydrostatic density difference) diffuses only the
 *    departure from hydrostatics, so a tank at rest keeps rho g H.
 * It damps the high-frequency density (pressure) noise of weakly
 * compressible SPH.
 *
 * Two phases (the field `phase` of the two_phase plugin, 0 water, 1 air,
 * used whenever a plugin declares it): the diffusion acts between particles
 * of the same phase only, each phase with its own c0 (the constant
 * air_speed_of_sound for the air) and, in the Fourtakas form, its own
 * rho^H_ji = rho0_k (g . r_ji) / c0_k^2. Across the interface the density
 * jumps by the density ratio: diffusing it would drag air density into the
 * water and back. */
#include <sluice/plugin_util.h>

typedef struct delta_config {
    sluice_real delta;
    int form;
} delta_config;

enum { FORM_MOLTENI_COLAGROSSI = 0, FORM_FOURTAKAS = 1 };

typedef struct delta_state {
    const sluice_api *api;
    int form;
    uint32_t dims;
    sluice_real coefficient, eta2, hydrostatic[3];
    sluice_field density, mass, density_rate;
    /* two phases: per phase (0 water, 1 air) */
    int two_phase;
    sluice_field phase;
    sluice_real phase_coefficient[2], phase_hydrostatic[2][3];
} delta_state;

static const sluice_param_spec params[] = {
    {"delta", SLUICE_PARAM_REAL, offsetof(delta_config, delta), "0.1", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "diffusion coefficient delta (seed 002 and DualSPHysics: 0.1)", NULL, 0},
    {"form", SLUICE_PARAM_ENUM, offsetof(delta_config, form), "fourtakas", 0, 0, 0, NULL,
     "molteni_colagrossi: diffuse rho_j - rho_i; fourtakas: diffuse its departure from "
     "hydrostatics (needs gravity)",
     "molteni_colagrossi|fourtakas", 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY_RATE(SLUICE_ACCUMULATE),
};

static int delta_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const delta_config *c = config;
    delta_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    sluice_real h;
    if (sluice_util_constant(api, host, "smoothing_length", &h) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    if (sluice_util_dimensions(api, host, &s->dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->form = c->form;
    s->coefficient = c->delta * h; /* times c0, known in bind */
    s->eta2 = (sluice_real)0.01 * h * h;
    *state = s;
    return SLUICE_OK;
}

static int delta_bind(void *state, sluice_host *host)
{
    delta_state *s = state;
    sluice_real c0;
    if (sluice_util_constant(s->api, host, "speed_of_sound", &c0) != SLUICE_OK)
        return SLUICE_ERROR;
    s->coefficient *= 2 * c0;
    if (s->form == FORM_FOURTAKAS) {
        sluice_real g[3] = {0, 0, 0}, rho0;
        if (s->api->fields->constant(host, "gravity", g, 3) == 0) {
            s->api->messages->error(host, "form fourtakas removes the hydrostatic density difference and "
                                "needs gravity: load the gravity plugin or use form "
                                "molteni_colagrossi");
            return SLUICE_ERROR;
        }
        if (sluice_util_constant(s->api, host, "rest_density", &rho0) != SLUICE_OK)
            return SLUICE_ERROR;
        /* rho^H_ji = rho0 (g . r_ji) / c0^2 = -(rho0 / c0^2) g . r_ij */
        for (int d = 0; d < 3; d++)
            s->hydrostatic[d] = -rho0 * g[d] / (c0 * c0);
    }
    const sluice_field_binding fields[] = {
        {"density", &s->density}, {"mass", &s->mass}, {"density_rate", &s->density_rate}};
    if (sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    s->two_phase = sluice_util_optional_field(s->api, host, "phase", &s->phase);
    if (s->two_phase) {
        sluice_real c_air, rho_air;
        if (s->phase.type != SLUICE_TYPE_UINT8 || s->phase.components != 1) {
            s->api->messages->error(host, "the field 'phase' must be uint8 with one component (0 water, "
                                "1 air)");
            return SLUICE_ERROR;
        }
        if (sluice_util_constant(s->api, host, "air_speed_of_sound", &c_air) != SLUICE_OK ||
            sluice_util_constant(s->api, host, "air_rest_density", &rho_air) != SLUICE_OK)
            return SLUICE_ERROR;
        s->phase_coefficient[0] = s->coefficient;
        s->phase_coefficient[1] = s->coefficient / c0 * c_air;
        for (int d = 0; d < 3; d++) {
            s->phase_hydrostatic[0][d] = s->hydrostatic[d];
            /* rho0_a / c0_a^2 against rho0_w / c0_w^2 */
            sluice_real rho0 = 0;
            if (s->form == FORM_FOURTAKAS &&
                sluice_util_constant(s->api, host, "rest_density", &rho0) != SLUICE_OK)
                return SLUICE_ERROR;
            s->phase_hydrostatic[1][d] =
                s->form == FORM_FOURTAKAS ? s->hydrostatic[d] * (rho_air / rho0) * (c0 / c_air) *
                                                (c0 / c_air)
                                          : 0;
        }
    }
    return SLUICE_OK;
}

static void delta_destroy(void *state)
{
    free(state);
}

static inline void delta_pairs(const delta_state *s, const sluice_view *v,
                               const sluice_pair_batch *b, const int fourtakas, const uint32_t dims)
{
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict r = b->distance;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const uint8_t *restrict kj = b->neighbour_kind;
    sluice_real *restrict rate = sluice_real_column(v, s->density_rate, 0);
    const sluice_real eta2 = s->eta2, coefficient = s->coefficient;
    const sluice_real hx = s->hydrostatic[0], hy = s->hydrostatic[1], hz = s->hydrostatic[2];
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real rhoi = rho[i];
        sluice_real sum = 0;

        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            /* psi_ij . grad_i W_ij = 2 d_ji r_ji . r_ij F / (r^2 + eta^2)
             *                     = -2 d_ji r^2 F / (r^2 + eta^2) */
            sluice_real difference = rhoj[k] - rhoi;
            if (fourtakas) {
                sluice_real h = hx * rx[k] + hy * ry[k];
                if (dims == 3)
                    h += hz * rz[k];
                difference -= h;
            }
            /* one division per pair: r^2 / (r^2 + eta^2) and V_j = m_j / rho_j
             * share it (the divider bounds the pair loop, docs/performance.md) */
            const sluice_real r2 = r[k] * r[k];
            const sluice_real term = difference * r2 * F[k] * mj[k] / ((r2 + eta2) * rhoj[k]);
            sum += kj[k] != SLUICE_KIND_WALL ? term : 0;
        }
        rate[i] -= coefficient * sum;
    }
}

/* Two phases: same-phase pairs only, each phase with its own coefficient and
 * hydrostatic density difference (not vectorised: the phase is a byte
 * gathered through the neighbour index). */
static void delta_pairs_two_phase(const delta_state *s, const sluice_view *v,
                                  const sluice_pair_batch *b, const uint32_t dims)
{
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict r = b->distance;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const uint8_t *restrict kj = b->neighbour_kind;
    const uint8_t *restrict phase = (const uint8_t *)v->columns[s->phase.column];
    const sluice_index *restrict nb = b->neighbour;
    sluice_real *restrict rate = sluice_real_column(v, s->density_rate, 0);
    const sluice_real eta2 = s->eta2;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const uint8_t pi = phase[i] ? 1 : 0;
        const sluice_real *hydro = s->phase_hydrostatic[pi];
        const sluice_real rhoi = rho[i];
        sluice_real sum = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            sluice_real h = hydro[0] * rx[k] + hydro[1] * ry[k];
            if (dims == 3)
                h += hydro[2] * rz[k];
            const sluice_real difference = rhoj[k] - rhoi - h;
            const sluice_real r2 = r[k] * r[k];
            const sluice_real term = difference * r2 * F[k] * mj[k] / ((r2 + eta2) * rhoj[k]);
            const int same = kj[k] != SLUICE_KIND_WALL && (phase[nb[k]] ? 1 : 0) == pi;
            sum += same ? term : 0;
        }
        rate[i] -= s->phase_coefficient[pi] * sum;
    }
}

static void delta_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const delta_state *s = state;
    if (s->two_phase) {
        /* the hydrostatic terms are zero in the Molteni-Colagrossi form */
        if (v->dimensions == 3)
            delta_pairs_two_phase(s, v, b, 3);
        else
            delta_pairs_two_phase(s, v, b, 2);
        return;
    }
    if (s->form == FORM_FOURTAKAS) {
        if (v->dimensions == 3)
            delta_pairs(s, v, b, 1, 3);
        else
            delta_pairs(s, v, b, 1, 2);
    } else {
        delta_pairs(s, v, b, 0, v->dimensions);
    }
}

static const sluice_component components[] = {{
    .name = "delta_sph",
    .summary = "delta-SPH density diffusion (Molteni & Colagrossi or Fourtakas), fluid pairs",
    .reference = "Molteni & Colagrossi (2009); Fourtakas et al. (2019); seed 002 (delta = 0.1)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(delta_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = delta_create,
    .destroy = delta_destroy,
    .bind = delta_bind,
    .pair = delta_pair,
}};

SLUICE_DEFINE_LIBRARY("delta_sph", "1.1.0", "delta-SPH density diffusion", SLUICE_DIMS_ALL,
                      components)
