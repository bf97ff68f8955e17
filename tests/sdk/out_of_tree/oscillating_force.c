/* A time-dependent body force, written out of tree against the installed
 * SDK: a(t) = amplitude sin(2 pi t / period) on every fluid particle, at the
 * time of the stage being evaluated (view->stage_time), so that an
 * integrator's mid-step evaluation sees the force at mid-step. */
#include <math.h>
#include <sluice/plugin_util.h>

typedef struct config {
    sluice_real amplitude[3], period;
} config;
static const sluice_param_spec params[] = {
    {"amplitude", SLUICE_PARAM_VECTOR, offsetof(config, amplitude), NULL, 0, 0, 0, "m s^-2",
     "acceleration amplitude", NULL, SLUICE_LENGTH_DIM},
    {"period", SLUICE_PARAM_REAL, offsetof(config, period), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "s", "period of the oscillation", NULL, 0},
};
static const sluice_field_spec fields[] = {SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE)};

typedef struct state {
    const sluice_api *api;
    config c;
    uint32_t dims;
    sluice_field acceleration;
} state;

static int create(const sluice_api *api, sluice_host *host, const void *cfg, void **out)
{
    state *s = *out = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->c = *(const config *)cfg;
    return sluice_util_dimensions(api, host, &s->dims);
}
static int bind(void *st, sluice_host *host)
{
    state *s = st;
    return s->api->fields->field(host, "acceleration", &s->acceleration);
}
static void particle(void *st, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const state *s = st;
    const double phase = sin(2 * SLUICE_PI * v->stage_time / (double)s->c.period);
    for (uint32_t d = 0; d < s->dims; d++) {
        sluice_real *a = sluice_real_column(v, s->acceleration, d);
        for (sluice_index i = begin; i < end; i++)
            if (v->kind[i] == SLUICE_KIND_FLUID)
                a[i] += (sluice_real)(s->c.amplitude[d] * phase);
    }
}
static const sluice_component components[] = {{
    .name = "oscillating_force", .summary = "body force a sin(2 pi t / T)",
    .dimensions = SLUICE_DIMS_ALL, .params = params, .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(config), .fields = fields, .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = create, .destroy = free, .bind = bind, .particle = particle}};
SLUICE_DEFINE_LIBRARY("oscillating_force", "1.0.0", "out-of-tree body force", SLUICE_DIMS_ALL,
                      components)
