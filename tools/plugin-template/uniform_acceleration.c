/* A complete out-of-tree Sluice plugin: a uniform acceleration added to every
 * fluid particle (for example a pressure gradient driving a periodic channel).
 * Copy this directory, rename the component, and build it with `make`: it
 * needs only the installed SDK headers (pkg-config sluice), never the core.
 *
 * A plugin exports one function, sluice_plugin_entry(), returning a static
 * descriptor; SLUICE_DEFINE_LIBRARY writes it. The descriptor lists the
 * parameters (validated by the core from the scene's YAML before anything
 * runs), the fields the plugin reads and writes (so the core allocates them
 * and orders the plugins), and the callbacks. */
#include <sluice/plugin_util.h>

/* Parameters arrive in this struct, filled by the core from the scene. */
typedef struct config {
    sluice_real acceleration[3];
} config;

static const sluice_param_spec params[] = {
    {"acceleration", SLUICE_PARAM_VECTOR, offsetof(config, acceleration), "[0, 0] | [0, 0, 0]",
     0, 0, 0, "m s^-2", "acceleration added to every fluid particle", NULL, SLUICE_LENGTH_DIM},
};

/* It adds to 'acceleration', the rate of 'velocity', for fluid particles:
 * the integrator picks it up from this declaration. The SDK's standard
 * declarations (sluice/field_specs.h) carry the units and flags every plugin
 * gives these fields; the argument is this plugin's access. */
static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(0),
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
};

typedef struct state {
    const sluice_api *api;
    sluice_real acceleration[3];
    uint32_t dimensions;
    sluice_field field;
} state;

static int create(const sluice_api *api, sluice_host *host, const void *cfg, void **out)
{
    const config *c = cfg;
    state *s = sluice_util_state(api, host, sizeof *s); /* zeroed; reports out of memory */
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    if (sluice_util_dimensions(api, host, &s->dimensions) != SLUICE_OK) { /* the core's */
        free(s);
        return SLUICE_ERROR;
    }
    for (int d = 0; d < 3; d++)
        s->acceleration[d] = c->acceleration[d];
    *out = s;
    return SLUICE_OK;
}

/* Field handles are looked up once, never inside a loop. */
static int bind(void *st, sluice_host *host)
{
    state *s = st;
    return s->api->fields->field(host, "acceleration", &s->field);
}

static void destroy(void *st)
{
    free(st);
}

/* Called by the core in parallel on disjoint particle ranges. */
static void particle(void *st, const sluice_view *view, sluice_index begin, sluice_index end)
{
    const state *s = st;
    for (uint32_t d = 0; d < s->dimensions; d++) {
        sluice_real *a = sluice_real_column(view, s->field, d);
        for (sluice_index i = begin; i < end; i++)
            if (view->kind[i] == SLUICE_KIND_FLUID)
                a[i] += s->acceleration[d];
    }
}

static const sluice_component components[] = {{
    .name = "uniform_acceleration",
    .summary = "uniform acceleration of the fluid (out-of-tree plugin template)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = create,
    .destroy = destroy,
    .bind = bind,
    .particle = particle,
}};

SLUICE_DEFINE_LIBRARY("uniform_acceleration", "1.0.0", "plugin template", SLUICE_DIMS_ALL,
                      components)
