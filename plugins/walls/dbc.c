/* Dynamic boundary particles (DBC; Crespo et al. 2007, seed 002): each wall of
 * the scene that uses this scheme becomes layers of wall particles on the
 * lattice behind it (wall_layers.h). They take part in the continuity
 * equation and the equation of state like fluid particles but keep their
 * position and zero velocity; the pressure they build up as fluid approaches
 * repels it. Optionally their density is kept >= rho0 (at every evaluation,
 * before the equation of state) so that walls never attract. The clamp acts
 * only on this scheme's own particles (recognised by id), so that a scene can
 * mix dbc with other particle wall schemes.
 *
 * Prescribed motion (issue 4): one wall of the scheme, named by `moving_wall`
 * (the wall's `name` in the scene), moves as a rigid body:
 *     tau = t - start,
 *     x(t) = x_rest + U tau + A (sin(2 pi f tau + phi) - sin(phi)),
 *     v(t) = U + 2 pi f A cos(2 pi f tau + phi)        for t >= start,
 *     x = x_rest, v = 0                                  before,
 * with x_rest the particle's position from the scene's wall geometry and phi
 * the parameter phase_deg (degrees, as every angle in a scene). This is
 * the law x0 + U tau + A sin(2 pi f tau + phi) with x0 = x_rest - A sin(phi),
 * so that the wall does not jump at t = start. Positions and velocities are
 * set from the law in before_step (right at the step's start whatever the
 * hook order) and again in after_step (so that outputs, gauges and the state
 * between steps are at the new time), with the wall's displacement for the
 * writers (api->walls->set_wall_displacement, ABI 2.2). The integrators never move wall
 * particles; within a step the wall stays where it was at the step's start
 * (the mid-step evaluation of two-stage integrators sees it there). */
#include <math.h>
#include <string.h>

#include <sluice/plugin_util.h>
#include "wall_layers.h"

typedef struct dbc_config {
    int64_t layers;
    int clamp_density;
    const char *moving_wall;
    sluice_real velocity[3], amplitude[3];
    sluice_real frequency, phase_deg, start;
} dbc_config;

typedef struct dbc_state {
    const sluice_api *api;
    int64_t layers;
    int clamp;
    uint32_t dims;
    sluice_real rho0, dx, h;
    sluice_field density, position, velocity;
    /* own particles: ids [first_id, first_id + count); the moving wall's are
     * the last moving_count of them */
    sluice_id first_id;
    sluice_index count, fixed_count, moving_count;
    sluice_real *rest; /* moving wall: rest positions, 3 reals per particle */
    const char *moving_wall;
    uint32_t moving_index; /* the moving wall's index (api->walls->wall) */
    double velocity_law[3], amplitude[3], frequency, phase, start;
} dbc_state;

static const sluice_param_spec params[] = {
    {"layers", SLUICE_PARAM_INT, offsetof(dbc_config, layers), "0", 0, 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "layers of wall particles behind each wall; 0: enough to cover the kernel support "
     "(ceil(2h/dx))",
     NULL, 0},
    {"clamp_density", SLUICE_PARAM_BOOL, offsetof(dbc_config, clamp_density), "true", 0, 0, 0, NULL,
     "keep wall-particle density >= rest density at every evaluation and after every step (no "
     "attraction)",
     NULL, 0},
    {"moving_wall", SLUICE_PARAM_STRING, offsetof(dbc_config, moving_wall), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, NULL,
     "name of the one wall (geometry.walls[k].name, scheme dbc) that moves with the prescribed "
     "law x_rest + U tau + A (sin(2 pi f tau + phase) - sin(phase)), tau = t - start, phase = "
     "phase_deg; absent: "
     "no wall moves",
     NULL, 0},
    {"velocity", SLUICE_PARAM_VECTOR, offsetof(dbc_config, velocity), "[0, 0] | [0, 0, 0]", 0, 0, 0,
     "m s^-1", "U: constant velocity of the moving wall from t = start", NULL, SLUICE_LENGTH_DIM},
    {"amplitude", SLUICE_PARAM_VECTOR, offsetof(dbc_config, amplitude), "[0, 0] | [0, 0, 0]", 0, 0,
     0, "m", "A: displacement amplitude of the moving wall's oscillation", NULL, SLUICE_LENGTH_DIM},
    {"frequency", SLUICE_PARAM_REAL, offsetof(dbc_config, frequency), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "Hz", "f: frequency of the oscillation", NULL, 0},
    {"phase_deg", SLUICE_PARAM_REAL, offsetof(dbc_config, phase_deg), "0", 0, 0, 0, "deg",
     "phase of the oscillation at t = start, in degrees like every angle in a scene (formerly "
     "'phase', in radians)",
     NULL, 0},
    {"start", SLUICE_PARAM_REAL, offsetof(dbc_config, start), "0", 0, 0, 0, "s",
     "time the motion starts; the wall is at rest before", NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_WRITE),
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
    sluice_real dims = 0;
    if (sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &s->dx) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    int moves = 0;
    for (uint32_t d = 0; d < s->dims; d++) {
        s->velocity_law[d] = (double)c->velocity[d];
        s->amplitude[d] = (double)c->amplitude[d];
        moves |= c->velocity[d] != 0 || c->amplitude[d] != 0;
    }
    s->frequency = (double)c->frequency;
    s->phase = (double)c->phase_deg * (SLUICE_PI / 180); /* radians from here on */
    s->start = (double)c->start;
    s->moving_wall = c->moving_wall && c->moving_wall[0] ? c->moving_wall : NULL;
    if (moves && !s->moving_wall) {
        api->messages->error(host, "'velocity' or 'amplitude' is set but no 'moving_wall' names the wall "
                         "that moves");
        free(s);
        return SLUICE_ERROR;
    }
    if (s->moving_wall) {
        /* the moving wall's particles carry its velocity (continuity and
         * viscosity read it); written in the hooks, not during evaluation */
        const sluice_field_spec velocity = SLUICE_SPEC_VELOCITY(0);
        if (api->fields->declare_field(host, &velocity) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
    }
    *state = s;
    return SLUICE_OK;
}

static int dbc_bind(void *state, sluice_host *host)
{
    dbc_state *s = state;
    if (s->layers == 0)
        s->layers = sluice_wall_layers_default(s->api, host, s->h, s->dx);
    if (s->api->fields->field(host, "density", &s->density) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->moving_wall && (s->api->fields->field(host, "position", &s->position) != SLUICE_OK ||
                           s->api->fields->field(host, "velocity", &s->velocity) != SLUICE_OK))
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static void dbc_destroy(void *state)
{
    dbc_state *s = state;
    if (!s)
        return;
    free(s->rest);
    free(s);
}

/* The moving wall's displacement dx and velocity u at time t (3 each). */
static void motion_at(const dbc_state *s, double t, double dx[3], double u[3])
{
    const double tau = t - s->start, omega = 2 * SLUICE_PI * s->frequency;
    for (int d = 0; d < 3; d++)
        dx[d] = u[d] = 0;
    if (tau >= 0) {
        const double sine = sin(omega * tau + s->phase) - sin(s->phase);
        const double cosine = omega * cos(omega * tau + s->phase);
        for (uint32_t d = 0; d < s->dims; d++) {
            dx[d] = s->velocity_law[d] * tau + s->amplitude[d] * sine;
            u[d] = s->velocity_law[d] + s->amplitude[d] * cosine;
        }
    }
}

/* Sets the moving wall's particles to the law at time t, and its
 * displacement for the writers (api->walls->set_wall_displacement). */
static int apply_motion(const dbc_state *s, sluice_host *host, double t)
{
    const sluice_view *v = s->api->particles->view(host);
    double dx[3], u[3];
    motion_at(s, t, dx, u);
    const sluice_real displacement[3] = {(sluice_real)dx[0], (sluice_real)dx[1],
                                         (sluice_real)dx[2]};
    if (s->api->walls->set_wall_displacement(host, s->moving_index, displacement) != SLUICE_OK)
        return SLUICE_ERROR;
    const sluice_id first = s->first_id + s->fixed_count;
    for (uint32_t d = 0; d < s->dims; d++) {
        sluice_real *restrict x = sluice_real_column(v, s->position, d);
        sluice_real *restrict vel = sluice_real_column(v, s->velocity, d);
        for (sluice_index i = 0; i < v->count; i++) {
            const sluice_id k = v->id[i] - first; /* wraps for ids below first */
            if (k < s->moving_count) {
                x[i] = (sluice_real)((double)s->rest[3 * k + d] + dx[d]);
                vel[i] = (sluice_real)u[d];
            }
        }
    }
    return SLUICE_OK;
}

static int dbc_initialise(void *state, sluice_host *host)
{
    dbc_state *s = state;
    const sluice_api *api = s->api;
    int64_t moving = -1;
    if (s->moving_wall) {
        uint32_t walls = api->walls->wall_count(host);
        for (uint32_t w = 0; w < walls; w++) {
            const sluice_wall *wall = api->walls->wall(host, w);
            if (!wall || !wall->name || strcmp(wall->name, s->moving_wall) != 0)
                continue;
            if (moving >= 0) {
                api->messages->error(host,
                           "moving_wall: several walls are named '%s' (one moving wall per "
                           "scene)",
                           s->moving_wall);
                return SLUICE_ERROR;
            }
            if (strcmp(wall->scheme, "dbc") != 0) {
                api->messages->error(host, "moving_wall: wall '%s' uses the scheme '%s', not dbc",
                           s->moving_wall, wall->scheme);
                return SLUICE_ERROR;
            }
            moving = w;
        }
        if (moving < 0) {
            api->messages->error(host, "moving_wall: no wall is named '%s' (geometry.walls[k].name)",
                       s->moving_wall);
            return SLUICE_ERROR;
        }
    }
    sluice_wall_layers layers;
    if (sluice_wall_layers_add(api, host, "dbc", (sluice_real)s->layers * s->dx, s->dx, moving,
                               &layers) != SLUICE_OK)
        return SLUICE_ERROR;
    s->first_id = layers.first_id;
    s->fixed_count = layers.fixed_count;
    s->moving_count = layers.moving_count;
    s->count = layers.fixed_count + layers.moving_count;
    if (s->moving_wall) {
        if (s->moving_count == 0) {
            free(layers.positions);
            api->messages->error(host, "moving_wall: wall '%s' has no wall particles", s->moving_wall);
            return SLUICE_ERROR;
        }
        s->rest = malloc((size_t)s->moving_count * 3 * sizeof *s->rest);
        if (!s->rest) {
            free(layers.positions);
            api->messages->error(host, "out of memory");
            return SLUICE_ERROR;
        }
        memcpy(s->rest, layers.positions + 3 * (size_t)s->fixed_count,
               (size_t)s->moving_count * 3 * sizeof *s->rest);
        s->moving_index = (uint32_t)moving;
        free(layers.positions);
        return apply_motion(s, host, api->particles->view(host)->time);
    }
    free(layers.positions);
    return SLUICE_OK;
}

static void clamp(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const dbc_state *s = context;
    sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_id *restrict id = v->id;
    const sluice_real rho0 = s->rho0;
    const sluice_id first = s->first_id, count = s->count;
    for (sluice_index i = begin; i < end; i++)
        if (id[i] - first < count && rho[i] < rho0)
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

static int dbc_before_step(void *state, sluice_host *host)
{
    dbc_state *s = state;
    if (s->moving_count)
        return apply_motion(s, host, s->api->particles->view(host)->time);
    return SLUICE_OK;
}

static int dbc_after_step(void *state, sluice_host *host)
{
    dbc_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    if (s->moving_count && apply_motion(s, host, v->time) != SLUICE_OK)
        return SLUICE_ERROR;
    v = s->api->particles->view(host);
    if (s->clamp)
        s->api->particles->parallel_for(host, v->count, clamp, s);
    return SLUICE_OK;
}

static const sluice_component components[] = {{
    .name = "dbc",
    .summary = "dynamic boundary particles: layers of wall particles obeying continuity and EOS, "
               "optionally one wall with prescribed motion",
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
    .before_step = dbc_before_step,
    .after_step = dbc_after_step,
}};

SLUICE_DEFINE_LIBRARY("dbc", "2.1.0", "dynamic boundary particles", SLUICE_DIMS_ALL, components)
