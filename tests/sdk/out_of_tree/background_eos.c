/* A linear equation of state with a background pressure, written out of tree
 * against the installed SDK: p = p_b + c0^2 (rho - rho0), c = c0. */
#include <sluice/plugin_util.h>

typedef struct config {
    sluice_real c0, background;
} config;
static const sluice_param_spec params[] = {
    {"speed_of_sound", SLUICE_PARAM_REAL, offsetof(config, c0), "20", 0, 0, SLUICE_PARAM_HAS_MIN,
     "m s^-1", "speed of sound c0", NULL, 0},
    {"background_pressure", SLUICE_PARAM_REAL, offsetof(config, background), "0", 0, 0, 0, "Pa",
     "background pressure p_b", NULL, 0},
};
static const sluice_field_spec fields[] = {SLUICE_SPECS_EQUATION_OF_STATE};

typedef struct state {
    const sluice_api *api;
    config c;
    sluice_real rho0;
    sluice_field density, pressure, sound_speed;
} state;

static int create(const sluice_api *api, sluice_host *host, const void *cfg, void **out)
{
    state *s = *out = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->c = *(const config *)cfg;
    if (sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK)
        return SLUICE_ERROR;
    return sluice_util_publish_eos(api, host, s->c.c0, s->c.background);
}
static int bind(void *st, sluice_host *host)
{
    state *s = st;
    const sluice_field_binding b[] = {
        {"density", &s->density}, {"pressure", &s->pressure}, {"sound_speed", &s->sound_speed}};
    return sluice_util_bind(s->api, host, b, SLUICE_COUNT(b));
}
static void particle(void *st, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const state *s = st;
    const sluice_real *rho = sluice_real_column(v, s->density, 0);
    sluice_real *p = sluice_real_column(v, s->pressure, 0), *c = sluice_real_column(v, s->sound_speed, 0);
    for (sluice_index i = begin; i < end; i++) {
        p[i] = s->c.background + s->c.c0 * s->c.c0 * (rho[i] - s->rho0);
        c[i] = s->c.c0;
    }
}
static void density_from_pressure(void *st, sluice_index n, const sluice_real *p, sluice_real *rho)
{
    const state *s = st;
    for (sluice_index k = 0; k < n; k++)
        rho[k] = s->rho0 + (p[k] - s->c.background) / (s->c.c0 * s->c.c0);
}
static const sluice_component components[] = {{
    .name = "background_eos", .summary = "linear EOS with a background pressure",
    .dimensions = SLUICE_DIMS_ALL, .params = params, .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(config), .fields = fields, .field_count = SLUICE_COUNT(fields),
    .create = create, .destroy = free, .bind = bind, .particle = particle,
    .density_from_pressure = density_from_pressure}};
SLUICE_DEFINE_LIBRARY("background_eos", "1.0.0", "out-of-tree EOS", SLUICE_DIMS_ALL, components)
