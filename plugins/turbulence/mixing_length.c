/* Mixing-length eddy viscosity (seed 004, section 3, model (1); Prandtl 1925):
 *   nu_T,i = c_mu l_i^2 |S_i|,   |S| = sqrt(2 S:S),  S = (G + G^T) / 2,
 *   l_i = min(1, s_i^3) min(kappa y_i, l_max),   s_i = sum_j V_j W_ij + V_i W(0),
 * with G the field velocity_gradient, y_i the distance to the nearest wall of
 * the scene (api->walls->wall_distance) and s_i the Shepard sum over fluid and wall
 * neighbours plus the particle itself. s_i is close to 1 inside the fluid and
 * next to wall particles and drops towards 1/2 at a free surface, so the cube
 * damps l in the top kernel radius (seed 004's "damping function": its printed
 * operand is garbled; the Shepard sum is the reading that damps at the free
 * surface, see physics-notes).
 *
 * c_mu: with c_mu = 1, l = kappa y is Prandtl's mixing length, which gives the
 * log law u = (u_* / kappa) ln y + const with von Karman's kappa (the default).
 * Seed 004 prints c_mu = 0.09 with the same l: that is an effective mixing
 * length sqrt(0.09) kappa y = 0.123 y, i.e. a log-law slope 1/0.123 = 3.3 times
 * too steep near a wall (0.09 is the k-epsilon c_mu, which enters the
 * mixing-length form only as c_mu^(1/4) or ^(3/4) in k- or epsilon-based length
 * scales). The seed-004 scenes set c_mu: 0.09 explicitly.
 *
 * The wall distance is queried for every target at every evaluation, from its
 * current position, so it is right however the particles move; there is no
 * cache because the query is cheap: one bounding-box test per wall plus the
 * elements of the walls within reach (3.3 % of the run time of the 2D open
 * channel, one bed segment, 240 fluid particles; perf). */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct ml_config {
    sluice_real c_mu, kappa, l_max;
} ml_config;

typedef struct ml_state {
    const sluice_api *api;
    sluice_host *host;
    uint32_t dims;
    sluice_real c_mu, kappa, l_max;
    sluice_field mass, density, gradient, eddy_viscosity, mixing_length;
} ml_state;

static const sluice_param_spec params[] = {
    {"c_mu", SLUICE_PARAM_REAL, offsetof(ml_config, c_mu), "1", 0, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "coefficient of nu_T = c_mu l^2 |S|; 1 is Prandtl's mixing length (log law with kappa); "
     "seed 004 prints 0.09",
     NULL, 0},
    {"kappa", SLUICE_PARAM_REAL, offsetof(ml_config, kappa), "0.41", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "von Karman constant in l = kappa y", NULL, 0},
    {"l_max", SLUICE_PARAM_REAL, offsetof(ml_config, l_max), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m",
     "cut-off of the mixing length, l <= l_max (seed 004: 0.5 times the tailwater depth)", NULL,
     0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_MASS(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_EDDY_VISCOSITY(SLUICE_WRITE),
    {"mixing_length", SLUICE_TYPE_REAL, 1, "m", SLUICE_WRITE, SLUICE_FIELD_OUTPUT, NULL, 0,
     "mixing length l = min(1, s^3) min(kappa y, l_max)"},
};

static int ml_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const ml_config *c = config;
    ml_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->c_mu = c->c_mu;
    s->kappa = c->kappa;
    s->l_max = c->l_max;
    if (sluice_util_dimensions(api, host, &s->dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    const sluice_field_spec gradient = SLUICE_SPEC_VELOCITY_GRADIENT(s->dims, SLUICE_READ);
    if (api->fields->declare_field(host, &gradient) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int ml_bind(void *state, sluice_host *host)
{
    ml_state *s = state;
    s->host = host;
    const sluice_field_binding fields[] = {
        {"mass", &s->mass}, {"density", &s->density}, {"velocity_gradient", &s->gradient},
        {"eddy_viscosity", &s->eddy_viscosity}, {"mixing_length", &s->mixing_length}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void ml_destroy(void *state)
{
    free(state);
}

static inline void ml_pairs(const ml_state *s, const sluice_view *v, const sluice_pair_batch *b,
                            const uint32_t dims)
{
    const sluice_real *restrict m = sluice_real_column(v, s->mass, 0);
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict W = b->kernel;
    const sluice_real *G[9];
    for (uint32_t c = 0; c < dims * dims; c++)
        G[c] = sluice_real_column(v, s->gradient, c);
    sluice_real *restrict nu = sluice_real_column(v, s->eddy_viscosity, 0);
    sluice_real *restrict length = sluice_real_column(v, s->mixing_length, 0);
    const sluice_real w0 = b->kernel_self, c_mu = s->c_mu, kappa = s->kappa, l_max = s->l_max;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        sluice_real shepard = m[i] / rho[i] * w0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++)
            shepard += mj[k] / rhoj[k] * W[k];
        const sluice_real point[3] = {v->position[0][i], v->position[1][i],
                                      dims == 3 ? v->position[2][i] : 0};
        const sluice_real y = s->api->walls->wall_distance(s->host, point);
        sluice_real l = kappa * y < l_max ? kappa * y : l_max;
        const sluice_real s3 = shepard * shepard * shepard;
        l *= s3 < 1 ? s3 : 1;
        length[i] = l;
        nu[i] = c_mu * l * l * sqrt(sluice_util_strain_rate_squared(G, i, dims));
    }
}

static void ml_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    if (v->dimensions == 3)
        ml_pairs(state, v, b, 3);
    else
        ml_pairs(state, v, b, 2);
}

static const sluice_component components[] = {{
    .name = "mixing_length",
    .summary = "mixing-length eddy viscosity nu_T = c_mu l^2 |S|, l = min(1, s^3) min(kappa y, "
               "l_max)",
    .reference = "seed 004 (De Padova et al. 2017), model (1); Prandtl (1925)",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_NEEDS_KERNEL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(ml_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = ml_create,
    .destroy = ml_destroy,
    .bind = ml_bind,
    .pair = ml_pair,
}};

SLUICE_DEFINE_LIBRARY("mixing_length", "1.0.0", "mixing-length eddy viscosity", SLUICE_DIMS_ALL,
                      components)
