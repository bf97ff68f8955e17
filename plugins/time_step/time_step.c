/* Time-step control for weakly compressible SPH. Conditions, each a bool
 * parameter, over fluid particles, multiplied by the Courant number C:
 *   force     dt_f = C min_i sqrt(h / |a_i|)           (Monaghan 1989)
 *   acoustic  dt_c = C min_i h / (c_i + |v_i|)         (Courant: c_i the local
 *             speed of sound, |v_i| the particle's speed)
 *   viscous   dt_v = C 0.125 h^2 / nu                  (Morris et al. 1997, with
 *             nu the constant 'kinematic_viscosity' of laminar_viscosity)
 * The step is the smallest of the conditions turned on and of the limits
 * other plugins set (artificial_viscosity: C h / (c_i + max_j |mu_ij|), unless
 * its time_step_limit is false; laminar_viscosity: 0.125 h^2 / nu without C).
 * C is published as the constant 'courant_number' so that other terms scale
 * their own limits with it.
 *
 * The seeds' conditions:
 *   seed 000 (Jonsson et al. 2016, eq. 18: dt = C_eff min_i h/(c_i + |v_i|),
 *     C_eff ~ 1): time_step {courant: 1, force: false, acoustic: true} and
 *     artificial_viscosity {time_step_limit: false};
 *   seed 001 (Wan et al. 2017, eqs. 21-23: dt = C_CFL min(dt_force, dt_visc),
 *     C_CFL = 0.2): time_step {courant: 0.2, force: true, acoustic: false,
 *     viscous: true} with laminar_viscosity (its own 0.125 h^2/nu is then the
 *     looser bound); with artificial viscosity instead, viscous: false and
 *     the artificial viscosity's own limit;
 *   seed 002 and DualSPHysics (Monaghan's CFL, the default): force and
 *     acoustic with the artificial viscosity's limit, C = 0.2. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct step_config {
    sluice_real courant;
    int force, acoustic, viscous;
} step_config;

typedef struct step_state {
    const sluice_api *api;
    sluice_real courant, h;
    int force, acoustic, viscous;
    sluice_real viscous_limit; /* C 0.125 h^2 / nu */
    uint32_t dims;
    sluice_field acceleration, velocity, sound_speed;
} step_state;

static const sluice_param_spec params[] = {
    {"courant", SLUICE_PARAM_REAL, offsetof(step_config, courant), "0.2", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "Courant number C multiplying every stability condition (seed 000: 1, seeds 001 and 002: "
     "0.2)",
     NULL, 0},
    {"force", SLUICE_PARAM_BOOL, offsetof(step_config, force), "true", 0, 0, 0, NULL,
     "apply the force condition C sqrt(h/|a|)", NULL, 0},
    {"acoustic", SLUICE_PARAM_BOOL, offsetof(step_config, acoustic), "true", 0, 0, 0, NULL,
     "apply the acoustic condition C h/(c + |v|), c from the field sound_speed (m s^-1)", NULL,
     0},
    {"viscous", SLUICE_PARAM_BOOL, offsetof(step_config, viscous), "false", 0, 0, 0, NULL,
     "apply the viscous condition C 0.125 h^2/nu of Morris et al. (1997) with the constant "
     "'kinematic_viscosity' (published by laminar_viscosity); seed 001",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_ACCELERATION(SLUICE_READ),
    SLUICE_SPEC_VELOCITY(SLUICE_READ),
};

static const sluice_field_spec sound_speed_field = {
    "sound_speed", SLUICE_TYPE_REAL, 1, "m s^-1", SLUICE_READ, 0, NULL, 0, "local speed of sound"};

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
    s->viscous = c->viscous;
    sluice_real dims;
    if (sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        api->fields->publish_constant(host, "courant_number", &s->courant, 1, "1") != SLUICE_OK ||
        (s->acoustic && api->fields->declare_field(host, &sound_speed_field) != SLUICE_OK)) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    if (!s->force && !s->acoustic && !s->viscous)
        api->messages->warning(host, "every condition is off: only other plugins limit the time step");
    *state = s;
    return SLUICE_OK;
}

static int step_bind(void *state, sluice_host *host)
{
    step_state *s = state;
    const sluice_api *api = s->api;
    if (api->fields->field(host, "acceleration", &s->acceleration) != SLUICE_OK ||
        api->fields->field(host, "velocity", &s->velocity) != SLUICE_OK ||
        (s->acoustic && api->fields->field(host, "sound_speed", &s->sound_speed) != SLUICE_OK))
        return SLUICE_ERROR;
    s->viscous_limit = (sluice_real)INFINITY;
    if (s->viscous) {
        sluice_real nu;
        if (api->fields->constant(host, "kinematic_viscosity", &nu, 1) < 1) {
            api->messages->error(host,
                       "viscous: true needs the constant 'kinematic_viscosity', which no loaded "
                       "plugin publishes (load laminar_viscosity)");
            return SLUICE_ERROR;
        }
        if (nu > 0)
            s->viscous_limit = s->courant * (sluice_real)0.125 * s->h * s->h / nu;
    }
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
    int fluid = 0;
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        fluid = 1;
        sluice_real a2 = 0, v2 = 0;
        for (uint32_t d = 0; d < s->dims; d++) {
            sluice_real a = sluice_real_column(v, s->acceleration, d)[i];
            sluice_real u = sluice_real_column(v, s->velocity, d)[i];
            a2 += a * a;
            v2 += u * u;
        }
        if (a2 > a_max2 || a2 != a2)
            a_max2 = a2 != a2 ? (sluice_real)INFINITY : a2;
        if (s->acoustic) {
            sluice_real speed = sluice_real_column(v, s->sound_speed, 0)[i] + sqrt(v2);
            if (speed > speed_max || speed != speed)
                speed_max = speed != speed ? (sluice_real)INFINITY : speed;
        }
    }
    sluice_real limit = (sluice_real)INFINITY;
    if (!fluid)
        return limit;
    if (s->force && a_max2 > 0)
        limit = s->courant * sqrt(s->h / sqrt(a_max2));
    if (s->acoustic && speed_max > 0) {
        sluice_real dt = s->courant * s->h / speed_max;
        if (dt < limit)
            limit = dt;
    }
    if (s->viscous_limit < limit)
        limit = s->viscous_limit;
    return limit;
}

static const sluice_component components[] = {{
    .name = "time_step",
    .summary = "variable time step: Courant number times the force, acoustic and viscous "
               "conditions",
    .reference = "Monaghan (1989); Morris, Fox & Zhu (1997); Crespo et al. (2015) DualSPHysics; "
                 "seeds 000 (eq. 18), 001 (eqs. 21-23), 002",
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

SLUICE_DEFINE_LIBRARY("time_step", "1.1.0", "time-step control", SLUICE_DIMS_ALL, components)
