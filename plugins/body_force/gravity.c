/* Gravity: a uniform body force on fluid particles, dv/dt += g. Publishes the
 * constant 'gravity' (used by the core for the hydrostatic initial state). */
#include <sluice/plugin_util.h>

typedef struct gravity_config {
    sluice_real acceleration[3];
} gravity_config;

typedef struct gravity_state {
    const sluice_api *api;
    sluice_real g[3];
    uint32_t dims;
    sluice_field acceleration;
} gravity_state;

static const sluice_param_spec params[] = {
    {"acceleration", SLUICE_PARAM_VECTOR, offsetof(gravity_config, acceleration),
     "[0, -9.81] | [0, 0, -9.81]", 0, 0, 0, "m s^-2",
     "gravitational acceleration; the last axis is vertical", NULL, SLUICE_LENGTH_DIM},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(0),
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
};

static int gravity_create(const sluice_api *api, sluice_host *host, const void *config,
                          void **state)
{
    const gravity_config *c = config;
    gravity_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    if (sluice_util_dimensions(api, host, &s->dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    for (int d = 0; d < 3; d++)
        s->g[d] = c->acceleration[d];
    if (api->fields->publish_constant(host, "gravity", s->g, s->dims, "m s^-2") != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int gravity_bind(void *state, sluice_host *host)
{
    gravity_state *s = state;
    return s->api->fields->field(host, "acceleration", &s->acceleration);
}

static void gravity_destroy(void *state)
{
    free(state);
}

static void gravity_particle(void *state, const sluice_view *v, sluice_index begin,
                             sluice_index end)
{
    const gravity_state *s = state;
    const uint8_t *restrict kind = v->kind;
    for (uint32_t d = 0; d < s->dims; d++) {
        sluice_real *restrict a = sluice_real_column(v, s->acceleration, d);
        const sluice_real g = s->g[d];
#pragma omp simd
        for (sluice_index i = begin; i < end; i++)
            a[i] += kind[i] == SLUICE_KIND_FLUID ? g : 0;
    }
}

static const sluice_component components[] = {{
    .name = "gravity",
    .summary = "uniform gravity on fluid particles",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(gravity_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = gravity_create,
    .destroy = gravity_destroy,
    .bind = gravity_bind,
    .particle = gravity_particle,
}};

SLUICE_DEFINE_LIBRARY("gravity", "1.0.0", "gravity body force", SLUICE_DIMS_ALL, components)
