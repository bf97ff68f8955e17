/* Dynamic boundary particles (DBC; Crespo et al. 2007, seed 002): each wall of
 * the scene that uses this scheme becomes layers of wall particles on the
 * lattice behind it. They take part in the continuity equation and the
 * equation of state like fluid particles but keep their position and zero
 * velocity; the pressure they build up as fluid approaches repels it.
 * Optionally their density is kept >= rho0 (at every evaluation, before the
 * equation of state) so that walls never attract. */
#include <math.h>
#include <string.h>

#include "plugin_util.h"

typedef struct dbc_config {
    int64_t layers;
    int clamp_density;
} dbc_config;

typedef struct dbc_state {
    const sluice_api *api;
    const char *name;
    int64_t layers;
    int clamp;
    sluice_real rho0, dx, h;
    sluice_field density;
} dbc_state;

static const sluice_param_spec params[] = {
    {"layers", SLUICE_PARAM_INT, offsetof(dbc_config, layers), "0", 0, 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "layers of wall particles behind each wall; 0: enough to cover the kernel support "
     "(ceil(2h/dx))",
     NULL, 0},
    {"clamp_density", SLUICE_PARAM_BOOL, offsetof(dbc_config, clamp_density), "true", 0, 0, 0,
     NULL,
     "keep wall-particle density >= rest density at every evaluation and after every step (no "
     "attraction)",
     NULL,
     0},
};

static const sluice_field_spec fields[] = {
    {"density", SLUICE_TYPE_REAL, 1, "kg m^-3", SLUICE_READ | SLUICE_WRITE,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "mass density"},
};

static int dbc_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const dbc_config *c = config;
    dbc_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->layers = c->layers;
    s->clamp = c->clamp_density;
    if (sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &s->dx) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int dbc_bind(void *state, sluice_host *host)
{
    dbc_state *s = state;
    sluice_real support = 2;
    s->api->constant(host, "kernel_support", &support, 1);
    if (s->layers == 0)
        s->layers = (int64_t)ceil(support * s->h / s->dx - 1e-9);
    return s->api->field(host, "density", &s->density);
}

static void dbc_destroy(void *state)
{
    free(state);
}

typedef struct point_key {
    int64_t k[3];
    uint32_t index;
} point_key;

static int compare_points(const void *a, const void *b)
{
    const point_key *x = a, *y = b;
    for (int d = 0; d < 3; d++)
        if (x->k[d] != y->k[d])
            return x->k[d] < y->k[d] ? -1 : 1;
    return 0;
}

static int dbc_initialise(void *state, sluice_host *host)
{
    dbc_state *s = state;
    const sluice_api *api = s->api;
    sluice_real *all = NULL;
    size_t count = 0;
    uint32_t walls = api->wall_count(host);
    for (uint32_t w = 0; w < walls; w++) {
        const sluice_wall *wall = api->wall(host, w);
        if (!wall || strcmp(wall->scheme, "dbc") != 0)
            continue;
        sluice_real *points = NULL;
        sluice_index n = 0;
        if (api->wall_layer_points(host, w, (sluice_real)s->layers * s->dx, &points, &n) !=
            SLUICE_OK) {
            free(all);
            return SLUICE_ERROR;
        }
        sluice_real *grown = realloc(all, (count + n) * 3 * sizeof *grown + 1);
        if (!grown) {
            api->release(points);
            free(all);
            api->error(host, "out of memory");
            return SLUICE_ERROR;
        }
        all = grown;
        memcpy(all + 3 * count, points, (size_t)n * 3 * sizeof *points);
        count += n;
        api->release(points);
    }
    if (count == 0) {
        free(all);
        return SLUICE_OK;
    }
    /* walls that meet share lattice points: keep each once */
    point_key *keys = malloc(count * sizeof *keys);
    sluice_real *unique = malloc(count * 3 * sizeof *unique);
    if (!keys || !unique) {
        free(keys);
        free(unique);
        free(all);
        api->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    const double q = 0.01 * (double)s->dx;
    for (size_t i = 0; i < count; i++) {
        for (int d = 0; d < 3; d++)
            keys[i].k[d] = llround((double)all[3 * i + d] / q);
        keys[i].index = (uint32_t)i;
    }
    qsort(keys, count, sizeof *keys, compare_points);
    size_t kept = 0;
    for (size_t i = 0; i < count; i++) {
        if (i > 0 && compare_points(&keys[i - 1], &keys[i]) == 0)
            continue;
        memcpy(unique + 3 * kept, all + 3 * (size_t)keys[i].index, 3 * sizeof *unique);
        kept++;
    }
    int rc = api->add_particles(host, SLUICE_KIND_WALL, unique, (sluice_index)kept, NULL);
    free(keys);
    free(unique);
    free(all);
    return rc;
}

static void clamp(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const dbc_state *s = context;
    sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real rho0 = s->rho0;
    for (sluice_index i = begin; i < end; i++)
        if (v->kind[i] == SLUICE_KIND_WALL && rho[i] < rho0)
            rho[i] = rho0;
}

/* Particle term: the clamp at every evaluation, so that the mid-step state
 * of two-stage integrators sees the same walls as the step's start (a clamp
 * only after the step made them first order on the dam break). */
static void dbc_particle(void *state, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const dbc_state *s = state;
    if (s->clamp)
        clamp(state, v, begin, end);
}

static int dbc_after_step(void *state, sluice_host *host)
{
    dbc_state *s = state;
    if (s->clamp) {
        const sluice_view *v = s->api->view(host);
        s->api->parallel_for(host, v->count, clamp, s);
    }
    return SLUICE_OK;
}

static const sluice_component components[] = {{
    .name = "dbc",
    .summary = "dynamic boundary particles: layers of wall particles obeying continuity and EOS",
    .reference = "Crespo, Gomez-Gesteira & Dalrymple (2007); seed 002",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_WALL_SCHEME,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(dbc_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = dbc_create,
    .destroy = dbc_destroy,
    .bind = dbc_bind,
    .initialise = dbc_initialise,
    .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .particle = dbc_particle,
    .after_step = dbc_after_step,
}};

SLUICE_DEFINE_LIBRARY("dbc", "1.1.0", "dynamic boundary particles", SLUICE_DIMS_ALL, components)
