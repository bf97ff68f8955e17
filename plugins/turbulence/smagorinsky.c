/* Smagorinsky sub-particle-scale (SPS) eddy viscosity (Smagorinsky 1963; in
 * SPH Gotoh, Shibahara & Sakai 2001 and Dalrymple & Rogers 2006, Coastal
 * Eng. 53:141-147, as DualSPHysics has it):
 *   nu_T,i = (C_s Delta)^2 |S_i|,   |S| = sqrt(2 S:S),  S = (G + G^T) / 2,
 * G the field velocity_gradient, Delta the filter width: the particle
 * spacing (`filter_width: spacing`, Dalrymple & Rogers) or the smoothing
 * length (`smoothing_length`); C_s = 0.12 (Dalrymple & Rogers). Written to
 * eddy_viscosity, which turbulent_stress turns into the stress 2 rho nu_T
 * S^d. Dalrymple & Rogers' isotropic part, -(2/3) rho C_I Delta^2 |S|^2 I
 * (C_I = 0.0066), is left out, as with mixing_length and k_epsilon: it is
 * a pressure of order C_I/C_s^2 = 0.46 times rho nu_T |S|, which the weakly
 * compressible pressure does not distinguish from its own.
 *
 * Unlike the mixing length, the length C_s Delta does not grow with the
 * distance from a wall: the model resolves no boundary layer on the scale
 * of the flow, and in an open channel it gives the log law only where
 * C_s Delta reaches kappa y (docs/validation.md measures it). No damping at
 * walls or at the free surface. */
#include <math.h>

#include <sluice/plugin_util.h>

enum { FILTER_SPACING = 0, FILTER_SMOOTHING_LENGTH = 1 };

typedef struct smagorinsky_config {
    sluice_real c_s;
    int filter;
} smagorinsky_config;

typedef struct smagorinsky_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_real length2; /* (C_s Delta)^2 */
    sluice_field gradient, eddy_viscosity;
} smagorinsky_state;

static const sluice_param_spec params[] = {
    {"c_s", SLUICE_PARAM_REAL, offsetof(smagorinsky_config, c_s), "0.12", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "Smagorinsky constant C_s (Dalrymple & Rogers 2006: 0.12)", NULL, 0},
    {"filter_width", SLUICE_PARAM_ENUM, offsetof(smagorinsky_config, filter), "spacing", 0, 0, 0,
     NULL, "Delta: spacing, the particle spacing dx (Dalrymple & Rogers 2006); smoothing_length, h",
     "spacing|smoothing_length", 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_EDDY_VISCOSITY(SLUICE_WRITE),
};

static int smagorinsky_create(const sluice_api *api, sluice_host *host, const void *config,
                              void **state)
{
    const smagorinsky_config *c = config;
    smagorinsky_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    sluice_real delta;
    if (sluice_util_dimensions(api, host, &s->dims) != SLUICE_OK ||
        sluice_util_constant(api, host,
                             c->filter == FILTER_SPACING ? "spacing" : "smoothing_length",
                             &delta) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->length2 = c->c_s * delta * c->c_s * delta;
    const sluice_field_spec gradient = SLUICE_SPEC_VELOCITY_GRADIENT(s->dims, SLUICE_READ);
    if (api->fields->declare_field(host, &gradient) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int smagorinsky_bind(void *state, sluice_host *host)
{
    smagorinsky_state *s = state;
    const sluice_field_binding fields[] = {{"velocity_gradient", &s->gradient},
                                           {"eddy_viscosity", &s->eddy_viscosity}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void smagorinsky_destroy(void *state)
{
    free(state);
}

static void smagorinsky_particles(void *state, const sluice_view *v, sluice_index begin,
                                  sluice_index end)
{
    const smagorinsky_state *s = state;
    const uint32_t dims = v->dimensions;
    const sluice_real *G[9];
    for (uint32_t c = 0; c < dims * dims; c++)
        G[c] = sluice_real_column(v, s->gradient, c);
    sluice_real *restrict nu = sluice_real_column(v, s->eddy_viscosity, 0);
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID) {
            nu[i] = 0;
            continue;
        }
        nu[i] = s->length2 * sqrt(sluice_util_strain_rate_squared(G, i, dims));
    }
}

static const sluice_component components[] = {{
    .name = "smagorinsky",
    .summary = "Smagorinsky sub-particle-scale eddy viscosity nu_T = (C_s Delta)^2 |S|",
    .reference = "Smagorinsky (1963); Dalrymple & Rogers (2006), Coastal Eng. 53:141-147",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(smagorinsky_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = smagorinsky_create,
    .destroy = smagorinsky_destroy,
    .bind = smagorinsky_bind,
    .particle = smagorinsky_particles,
}};

SLUICE_DEFINE_LIBRARY("smagorinsky", "1.0.0", "Smagorinsky sub-particle-scale eddy viscosity",
                      SLUICE_DIMS_ALL, components)
