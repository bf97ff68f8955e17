/* Time-step control for weakly compressible SPH (Monaghan 1989; seed 002 via
 * DualSPHysics):
 *   force condition     dt_f = C min_i sqrt(h / |a_i|)
 *   acoustic condition  dt_c = C min_i h / (c_i + |v_i|)
 * over fluid particles. C is the Courant number, published as the constant
 * 'courant_number' so that other terms (viscosity) scale their own limits
 * with it. */
#include <math.h>

#include "plugin_util.h"

typedef struct step_config {
    sluice_real courant;
    int force, acoustic;
} step_config;

typedef struct step_state {
    const sluice_api *api;
    sluice_real courant, h;
    int force, acoustic;
    uint32_t dims;
    sluice_field acceleration, velocity, sound_speed;
} step_state;

static const sluice_param_spec params[] = {
    {"courant", SLUICE_PARAM_REAL, offsetof(step_config, courant), "0.2", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "Courant number C multiplying every stability condition", NULL, 0},
    {"force", SLUICE_PARAM_BOOL, offsetof(step_config, force), "true", 0, 0, 0, NULL,
     "apply the force condition C sqrt(h/|a|)", NULL, 0},
    {"acoustic", SLUICE_PARAM_BOOL, offsetof(step_config, acoustic), "true", 0, 0, 0, NULL,
     "apply the acoustic condition C h/(c + |v|)", NULL, 0},
};

static const sluice_field_spec fields[] = {
    {"acceleration", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-2", SLUICE_READ, 0,
     "velocity", SLUICE_KIND_MASK(SLUICE_KIND_FLUID), "time derivative of the velocity"},
    {"velocity", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1", SLUICE_READ,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "velocity"},
    {"sound_speed", SLUICE_TYPE_REAL, 1, "m s^-1", SLUICE_READ, 0, NULL, 0,
     "local speed of sound"},
};

static int step_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const step_config *c = config;
    step_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->courant = c->courant;
    s->force = c->force;
    s->acoustic = c->acoustic;
    sluice_real dims;
    if (sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        api->publish_constant(host, "courant_number", &s->courant, 1, "1") != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    if (!s->force && !s->acoustic)
        api->warning(host, "both conditions are off: only other plugins limit the time step");
    *state = s;
    return SLUICE_OK;
}

static int step_bind(void *state, sluice_host *host)
{
    step_state *s = state;
    static const char *const names[] = {"acceleration", "velocity", "sound_speed"};
    sluice_field f[3];
    if (sluice_util_fields(s->api, host, names, f, 3) != SLUICE_OK)
        return SLUICE_ERROR;
    s->acceleration = f[0];
    s->velocity = f[1];
    s->sound_speed = f[2];
    return SLUICE_OK;
}

static void step_destroy(void *state)
{
    free(state);
}

static sluice_real step_limit(void *state, const sluice_view *v, sluice_index begin,
                              sluice_index end)
{
    const step_state *s = state;
    sluice_real a_max2 = 0, speed_max = 0;
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        sluice_real a2 = 0, v2 = 0;
        for (uint32_t d = 0; d < s->dims; d++) {
            sluice_real a = sluice_real_column(v, s->acceleration, d)[i];
            sluice_real u = sluice_real_column(v, s->velocity, d)[i];
            a2 += a * a;
            v2 += u * u;
        }
        if (a2 > a_max2 || a2 != a2)
            a_max2 = a2 != a2 ? (sluice_real)INFINITY : a2;
        sluice_real speed = sluice_real_column(v, s->sound_speed, 0)[i] + sqrt(v2);
        if (speed > speed_max || speed != speed)
            speed_max = speed != speed ? (sluice_real)INFINITY : speed;
    }
    sluice_real limit = (sluice_real)INFINITY;
    if (s->force && a_max2 > 0)
        limit = s->courant * sqrt(s->h / sqrt(a_max2));
    if (s->acoustic && speed_max > 0) {
        sluice_real dt = s->courant * s->h / speed_max;
        if (dt < limit)
            limit = dt;
    }
    return limit;
}

static const sluice_component components[] = {{
    .name = "time_step",
    .summary = "variable time step: Courant number times the force and acoustic conditions",
    .reference = "Monaghan (1989); Crespo et al. (2015) DualSPHysics",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(step_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = step_create,
    .destroy = step_destroy,
    .bind = step_bind,
    .time_step_limit = step_limit,
}};

SLUICE_DEFINE_LIBRARY("time_step", "1.0.0", "time-step control", SLUICE_DIMS_ALL, components)
