/* Wall friction from the log law (a wall function): the shear stress a
 * turbulent boundary layer puts on a wall, applied to the first layer of
 * fluid particles, so that a wall scheme without friction of its own (the
 * mirrored walls of Riemann-solver SPH, free-slip ghost or mdbc walls,
 * penalty contact) slows the flow along it as a wall does, without a
 * viscosity in the bulk.
 *
 * For a fluid particle i at distance y_i < `layer` x dx from the nearest wall
 * (api->walls->wall_nearest: its unit normal n into the fluid), with
 * tangential velocity u_t = v_i - (v_i . n) n (the walls at rest), the
 * friction velocity u* solves the log law at y_i:
 *   law smooth:  |u_t| / u* = (1/kappa) ln(E y_i u* / nu),  E = 9.8
 *                (solved by Newton's method; below y+ = 11.2 the viscous
 *                sublayer |u_t| = u*^2 y_i / nu is used instead);
 *   law rough:   |u_t| / u* = (1/kappa) ln(30 y_i / k_s)   (Nikuradse's
 *                fully rough wall, k_s = `roughness`; the logarithm is
 *                taken as at least 1, where y_i < e k_s / 30),
 * and the wall's shear stress tau_w = rho u*^2 acts on the layer of fluid
 * one spacing thick that the particle stands for: per unit mass
 *     dv_i/dt += -(u*^2 / (layer dx)) u_t / |u_t|.
 * No time-step limit is needed: the layer's relaxation time under its wall
 * stress, layer dx |u_t| / u*^2, is at least layer dx / (kappa^2 |u_t|) =
 * 6 layer dx / |u_t| on the log law (u* <= kappa |u_t|) and y_i layer dx /
 * nu in the viscous sublayer, far above the acoustic step 0.2 h / c0 with
 * |u_t| < c0 / 10. */
#include <math.h>

#include <sluice/plugin_util.h>

enum { LAW_SMOOTH = 0, LAW_ROUGH = 1 };

typedef struct friction_config {
    int law;
    sluice_real roughness, viscosity, kappa, layer;
} friction_config;

typedef struct friction_state {
    const sluice_api *api;
    sluice_host *host;
    int law;
    sluice_real roughness, viscosity, kappa, thickness; /* thickness = layer dx, m */
    sluice_field velocity, acceleration, friction_velocity;
} friction_state;

static const sluice_param_spec params[] = {
    {"law", SLUICE_PARAM_ENUM, offsetof(friction_config, law), "smooth", 0, 0, 0, NULL,
     "smooth: |u_t|/u* = (1/kappa) ln(E y u*/nu), E = 9.8; rough: (1/kappa) ln(30 y/k_s)",
     "smooth|rough", 0},
    {"roughness", SLUICE_PARAM_REAL, offsetof(friction_config, roughness), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL | SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m",
     "k_s, Nikuradse's equivalent sand roughness (law rough; required there)", NULL, 0},
    {"kinematic_viscosity", SLUICE_PARAM_REAL, offsetof(friction_config, viscosity), "1e-6", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m^2 s^-1",
     "nu of the smooth law (water at 20 C: 1.0e-6)", NULL, 0},
    {"kappa", SLUICE_PARAM_REAL, offsetof(friction_config, kappa), "0.41", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "von Karman constant", NULL, 0},
    {"layer", SLUICE_PARAM_REAL, offsetof(friction_config, layer), "1", 0, 3,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "thickness of the fluid layer that carries the wall stress, in spacings", NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ),
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
    {"friction_velocity", SLUICE_TYPE_REAL, 1, "m s^-1", SLUICE_WRITE, SLUICE_FIELD_OUTPUT, NULL, 0,
     "u* of the wall function at the particle (0 outside the wall layer)"},
};

static int friction_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state)
{
    const friction_config *c = config;
    if (c->law == LAW_ROUGH && !(c->roughness > 0)) {
        api->messages->error(host, "law rough needs roughness (k_s, m)");
        return SLUICE_ERROR;
    }
    friction_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    sluice_real dx;
    if (sluice_util_constant(api, host, "spacing", &dx) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->api = api;
    s->law = c->law;
    s->roughness = c->roughness;
    s->viscosity = c->viscosity;
    s->kappa = c->kappa;
    s->thickness = c->layer * dx;
    *state = s;
    return SLUICE_OK;
}

static int friction_bind(void *state, sluice_host *host)
{
    friction_state *s = state;
    s->host = host;
    const sluice_field_binding fields[] = {{"velocity", &s->velocity},
                                           {"acceleration", &s->acceleration},
                                           {"friction_velocity", &s->friction_velocity}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void friction_destroy(void *state)
{
    free(state);
}

/* u* of the log law for a tangential speed u at distance y (y > 0, u >= 0) */
static sluice_real friction_velocity(const friction_state *s, sluice_real u, sluice_real y)
{
    if (!(u > 0))
        return 0;
    if (s->law == LAW_ROUGH) {
        const sluice_real ratio = 30 * y / s->roughness;
        const sluice_real e = (sluice_real)2.718281828459045;
        const sluice_real log_term = ratio > e ? log(ratio) : 1;
        return s->kappa * u / log_term;
    }
    /* smooth: f(u*) = u* ln(E y u* / nu) - kappa u = 0; Newton from the
     * viscous estimate, the sublayer below y+ = 11.2 */
    const sluice_real E = (sluice_real)9.8, nu = s->viscosity;
    const sluice_real viscous = sqrt(u * nu / y);
    if (viscous * y / nu < (sluice_real)11.2)
        return viscous;
    sluice_real us = viscous;
    for (int k = 0; k < 30; k++) {
        const sluice_real l = log(E * y * us / nu);
        const sluice_real step = (us * l - s->kappa * u) / (l + 1);
        us -= step;
        if (us <= 0)
            us = viscous * (sluice_real)1e-3;
        if (fabs(step) < (sluice_real)1e-12 * us)
            break;
    }
    return us;
}

static void friction_particles(void *state, const sluice_view *v, sluice_index begin,
                               sluice_index end)
{
    const friction_state *s = state;
    const uint32_t dims = v->dimensions;
    sluice_real *a[3], *u[3];
    for (uint32_t d = 0; d < dims; d++) {
        a[d] = sluice_real_column(v, s->acceleration, d);
        u[d] = sluice_real_column(v, s->velocity, d);
    }
    sluice_real *restrict ustar = sluice_real_column(v, s->friction_velocity, 0);
    for (sluice_index i = begin; i < end; i++) {
        ustar[i] = 0;
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const sluice_real x[3] = {v->position[0][i], v->position[1][i],
                                  dims == 3 ? v->position[2][i] : 0};
        /* the cell-indexed distance first: most particles are far from every
         * wall, and the nearest point (with its normal) scans each wall's
         * elements */
        if (s->api->walls->wall_distance(s->host, x) >= s->thickness)
            continue;
        sluice_wall_point at;
        if (s->api->walls->wall_nearest(s->host, x, -1, &at) != SLUICE_OK || !(at.distance > 0) ||
            at.distance >= s->thickness)
            continue;
        sluice_real normal = 0;
        for (uint32_t d = 0; d < dims; d++)
            normal += u[d][i] * at.normal[d];
        sluice_real t[3] = {0, 0, 0}, speed2 = 0;
        for (uint32_t d = 0; d < dims; d++) {
            t[d] = u[d][i] - normal * at.normal[d];
            speed2 += t[d] * t[d];
        }
        const sluice_real speed = sqrt(speed2);
        const sluice_real us = friction_velocity(s, speed, at.distance);
        ustar[i] = us;
        if (!(speed > 0))
            continue;
        const sluice_real factor = us * us / (s->thickness * speed);
        for (uint32_t d = 0; d < dims; d++)
            a[d][i] -= factor * t[d];
    }
}

static const sluice_component components[] = {{
    .name = "wall_friction",
    .summary = "log-law wall function: the wall shear stress rho u*^2 on the first fluid layer",
    .reference = "the log law of the wall (smooth: E = 9.8; rough: Nikuradse, 30 y / k_s); "
                 "wall functions after Launder & Spalding (1974)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(friction_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = friction_create,
    .destroy = friction_destroy,
    .bind = friction_bind,
    .particle = friction_particles,
}};

SLUICE_DEFINE_LIBRARY("wall_friction", "1.0.0", "log-law wall function", SLUICE_DIMS_ALL,
                      components)
