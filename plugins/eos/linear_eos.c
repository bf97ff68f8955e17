/* Linear equation of state (seed 004, De Padova et al. 2017, eq. 1):
 *   p - p0 = c^2 (rho - rho0),   sound speed c constant.
 * p0 is the pressure at the rest density (0 for gauge pressure). It is the
 * LS-DYNA linear-polynomial form with C1 = p0, C2 = c^2 rho0 and no other
 * term (seed 000 eq. 13), with the density range unrestricted. */
#include <sluice/plugin_util.h>

typedef struct linear_config {
    sluice_real speed_of_sound, reference_pressure;
} linear_config;

typedef struct linear_state {
    const sluice_api *api;
    sluice_real c, c2, rho0, p0;
    sluice_field density, pressure, sound_speed;
} linear_state;

static const sluice_param_spec params[] = {
    {"speed_of_sound", SLUICE_PARAM_REAL, offsetof(linear_config, speed_of_sound), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m s^-1",
     "speed of sound c (seed 004: 30 m/s); at least 10 times the largest flow speed keeps "
     "density variations below 1 %",
     NULL, 0},
    {"reference_pressure", SLUICE_PARAM_REAL, offsetof(linear_config, reference_pressure), "0", 0,
     0, 0, "Pa", "p0, the pressure at the rest density", NULL, 0},
};

static const sluice_field_spec fields[] = {SLUICE_SPECS_EQUATION_OF_STATE};

static int linear_create(const sluice_api *api, sluice_host *host, const void *config,
                         void **state)
{
    const linear_config *c = config;
    linear_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->c = c->speed_of_sound;
    s->c2 = s->c * s->c;
    s->p0 = c->reference_pressure;
    if (sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK ||
        sluice_util_publish_eos(api, host, s->c, s->p0) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int linear_bind(void *state, sluice_host *host)
{
    linear_state *s = state;
    const sluice_field_binding fields[] = {
        {"density", &s->density}, {"pressure", &s->pressure}, {"sound_speed", &s->sound_speed}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void linear_destroy(void *state)
{
    free(state);
}

static void linear_particle(void *state, const sluice_view *v, sluice_index begin,
                            sluice_index end)
{
    const linear_state *s = state;
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    sluice_real *restrict p = sluice_real_column(v, s->pressure, 0);
    sluice_real *restrict c = sluice_real_column(v, s->sound_speed, 0);
    const sluice_real c2 = s->c2, rho0 = s->rho0, p0 = s->p0, cs = s->c;
#pragma omp simd
    for (sluice_index i = begin; i < end; i++) {
        p[i] = p0 + c2 * (rho[i] - rho0);
        c[i] = cs;
    }
}

static void linear_density_from_pressure(void *state, sluice_index n, const sluice_real *pressure,
                                         sluice_real *density)
{
    const linear_state *s = state;
    for (sluice_index i = 0; i < n; i++)
        density[i] = s->rho0 + (pressure[i] - s->p0) / s->c2;
}

static const sluice_component components[] = {{
    .name = "linear_eos",
    .summary = "linear equation of state p - p0 = c^2 (rho - rho0)",
    .reference = "De Padova et al. (2017), seed 004 eq. 1; Jonsson et al. (2016), seed 000 eq. 13",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(linear_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KINDS_ALL,
    .create = linear_create,
    .destroy = linear_destroy,
    .bind = linear_bind,
    .particle = linear_particle,
    .density_from_pressure = linear_density_from_pressure,
}};

SLUICE_DEFINE_LIBRARY("linear_eos", "1.0.0", "linear equation of state", SLUICE_DIMS_ALL,
                      components)
