/* Tait equation of state (seeds 001, 002; Monaghan 1994; Batchelor 1967):
 *   p = B ((rho / rho0)^gamma - 1) + p_b,  B = c0^2 rho0 / gamma,
 *   c = c0 (rho / rho0)^((gamma - 1) / 2)   (c^2 = dp/drho).
 * p_b is the background pressure of the two-phase form (Colagrossi &
 * Landrini 2003; seed 001): a uniform offset that leaves the pressure
 * gradient of a regular particle set unchanged but keeps the pressure
 * positive, which removes the tensile instability of the light phase. It is
 * 0 by default (single phase). gamma = 7 is evaluated with multiplications
 * only. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct tait_config {
    sluice_real speed_of_sound, gamma, background_pressure;
} tait_config;

typedef struct tait_state {
    const sluice_api *api;
    sluice_real c0, gamma, rho0, inverse_rho0, B, background;
    int seven;
    sluice_field density, pressure, sound_speed;
} tait_state;

static const sluice_param_spec params[] = {
    {"speed_of_sound", SLUICE_PARAM_REAL, offsetof(tait_config, speed_of_sound), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m s^-1",
     "numerical speed of sound c0 at the rest density; at least 10 times the largest flow "
     "speed keeps density variations below 1 %",
     NULL, 0},
    {"gamma", SLUICE_PARAM_REAL, offsetof(tait_config, gamma), "7", 1, 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1", "polytropic exponent (7 for water)", NULL, 0},
    {"background_pressure", SLUICE_PARAM_REAL, offsetof(tait_config, background_pressure), "0",
     0, 0, SLUICE_PARAM_HAS_MIN, "Pa",
     "p_b added to every pressure (two-phase form, Colagrossi & Landrini 2003; 0: single "
     "phase)",
     NULL, 0},
};

static const sluice_field_spec fields[] = {SLUICE_SPECS_EQUATION_OF_STATE};

static int tait_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const tait_config *c = config;
    tait_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    if (sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->c0 = c->speed_of_sound;
    s->gamma = c->gamma;
    s->inverse_rho0 = 1 / s->rho0;
    s->B = s->c0 * s->c0 * s->rho0 / s->gamma;
    s->background = c->background_pressure;
    s->seven = s->gamma == 7;
    if (sluice_util_publish_eos(api, host, s->c0, s->background) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int tait_bind(void *state, sluice_host *host)
{
    tait_state *s = state;
    const sluice_field_binding fields[] = {
        {"density", &s->density}, {"pressure", &s->pressure}, {"sound_speed", &s->sound_speed}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void tait_destroy(void *state)
{
    free(state);
}

static void tait_particle(void *state, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const tait_state *s = state;
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    sluice_real *restrict p = sluice_real_column(v, s->pressure, 0);
    sluice_real *restrict c = sluice_real_column(v, s->sound_speed, 0);
    const sluice_real i0 = s->inverse_rho0, B = s->B, c0 = s->c0, pb = s->background;
    if (s->seven) {
#pragma omp simd
        for (sluice_index i = begin; i < end; i++) {
            sluice_real x = rho[i] * i0, x2 = x * x, x3 = x2 * x;
            p[i] = B * (x3 * x3 * x - 1) + pb;
            c[i] = c0 * x3;
        }
    } else {
        const sluice_real g = s->gamma, e = (g - 1) / 2;
        for (sluice_index i = begin; i < end; i++) {
            sluice_real x = rho[i] * i0;
            p[i] = B * (pow(x, g) - 1) + pb;
            c[i] = c0 * pow(x, e);
        }
    }
}

static void tait_density_from_pressure(void *state, sluice_index n, const sluice_real *pressure,
                                       sluice_real *density)
{
    const tait_state *s = state;
    for (sluice_index i = 0; i < n; i++)
        density[i] = s->rho0 * pow(1 + (pressure[i] - s->background) / s->B, 1 / s->gamma);
}

static const sluice_component components[] = {{
    .name = "tait",
    .summary = "Tait equation of state p = B((rho/rho0)^gamma - 1) + p_b",
    .reference = "Monaghan (1994); Colagrossi & Landrini (2003); seeds 001 and 002",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(tait_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KINDS_ALL,
    .create = tait_create,
    .destroy = tait_destroy,
    .bind = tait_bind,
    .particle = tait_particle,
    .density_from_pressure = tait_density_from_pressure,
}};

SLUICE_DEFINE_LIBRARY("tait", "1.1.0", "Tait equation of state", SLUICE_DIMS_ALL, components)
