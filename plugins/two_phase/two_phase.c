/* Air-water two-phase weakly compressible SPH (seed 001, Wan et al. 2017,
 * after Colagrossi & Landrini 2003, J. Comput. Phys. 191, and Nugent & Posch
 * 2000, Phys. Rev. E 62). Two components:
 *
 *  two_phase: the particle phase and the equation of state of both phases.
 *    - field `phase` (uint8, 0 = water, 1 = air), set once at initialise
 *      from the air description (air_above, air_box_min/max, air_polygon):
 *      a fluid particle inside any of them is air. Air particles get the
 *      mass rho_a dx^d and the hydrostatic air density (below). Wall and
 *      open-boundary particles are water (phase 0).
 *    - the Tait equation of state of each phase k with one B (Colagrossi &
 *      Landrini 2003; seed 001 eq. 10):
 *          p = B ((rho / rho0_k)^gamma_k - 1) + p_b,
 *          B = c0_w^2 rho0_w / gamma_w,  c0_k = sqrt(gamma_k B / rho0_k),
 *          c = c0_k (rho / rho0_k)^((gamma_k - 1) / 2)   (c^2 = dp/drho).
 *      One B makes both phases equally stiff in pressure: at rest density
 *      both have p = p_b, so the pressure is continuous across an interface
 *      at rest, and c0_air = c0_w sqrt((gamma_a / gamma_w) (rho0_w / rho0_a))
 *      (379.3 m/s for seed 001's table 1: c0_w = 28 m/s, rho 1000 / 1.09,
 *      gamma 7 / 1.4). p_b, the background pressure, is the same for both
 *      phases: it keeps the air's pressure positive where the flow expands
 *      it, which removes the tensile instability of the light phase
 *      (Colagrossi & Landrini 2003), and it cancels from the pressure force
 *      wherever a particle's support is complete (sum_j V_j grad W = 0):
 *      where it is not (a disordered, shearing flow) 2 p_b sum_j V_j grad W
 *      / rho_i acts on every particle, so p_b is kept as small as the air
 *      allows (docs/physics.md). It is published as 'reference_pressure',
 *      so that the core's hydrostatic start puts p_b at the water's surface.
 *      Published constants: speed_of_sound (c0_w), air_speed_of_sound
 *      (c0_a), air_rest_density (rho0_a), air_gamma (gamma_a) and
 *      reference_pressure (p_b): with them another plugin inverts the air's
 *      law, rho_a(p) = rho0_a ((p - p_b) / B + 1)^(1 / gamma_a) with
 *      B = rho0_a c0_a^2 / gamma_a (the inlet's air layer); the API's
 *      density_from_pressure is the water's inverse.
 *    - initial air density: hydrostatic in the air, p = p_b - rho_a g (z -
 *      z_s), inverted exactly through the air's Tait law, with z_s the top
 *      of the highest water particle (its centre + dx/2): the pressure is
 *      p_b on both sides of a horizontal interface (the water below starts
 *      at p_b + rho_w g depth from the core). The air's weight is tiny
 *      (rho_a g = 10.7 Pa/m against B = 1.1e5 Pa for seed 001), but starting
 *      from it saves an acoustic transient in the air.
 *
 *  air_cohesion: the cohesion of the air (Nugent & Posch 2000; Colagrossi &
 *    Landrini 2003; seed 001 eq. 12): an attractive van der Waals pressure
 *    -a rho^2 in the air, evaluated with a longer smoothing length H, gives
 *        dv_i/dt += 2 a sum_{j air} m_j grad_i W(r_ij, H)     (i air)
 *    (water: a = 0; j: fluid air only, not an open boundary's particles,
 *    which hold an imposed state at rest, like walls: an air vent's lattice
 *    drew the air beside it in). The pair force is antisymmetric (momentum
 *    is conserved)
 *    and derives from the potential -a sum_i m_i rho^H_i, so it conserves
 *    energy. H = 2h in Nugent & Posch: the pairs reach 2H = 4h, beyond the
 *    scene kernel's support (2h); the term asks the core for them with
 *    api->evaluation->request_reach (plugin ABI 1.6) and evaluates W(r, H) itself from
 *    the pair distances (its batches carry no kernel values).
 *
 *  air_cohesion_held: the same cohesion, recomputed every `update_every`
 *    steps (before the step, on the positions it starts from) and held in
 *    between (multiple time stepping). The time step of a two-phase scene
 *    is set by the air's sound speed (379 m/s in seed 001: 5e-6 s at
 *    dx = 8 mm), while the cohesion changes with the interface, which moves
 *    at the flow's speed; its pass reaches 4h and costs about a third of a
 *    step. With update_every = 1 it is air_cohesion evaluated once a step
 *    (identical, to round-off, with a one-evaluation integrator such as
 *    Verlet; a two-stage integrator's mid-step evaluation gets the value of
 *    the step's start). The held acceleration is a field of its own
 *    (cohesion_acceleration, kept in checkpoints), refreshed when the step
 *    count is a multiple of update_every. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sluice/plugin_util.h>

enum { PHASE_WATER = 0, PHASE_AIR = 1 };

/* ================================================================ phase ==== */

typedef struct two_phase_config {
    sluice_real speed_of_sound, gamma, air_gamma, air_rest_density, background_pressure;
    sluice_real_list air_above, air_box_min, air_box_max, air_polygon;
} two_phase_config;

typedef struct two_phase_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_real dx;
    sluice_real rho_w, rho_a, inverse_rho_w, inverse_rho_a;
    sluice_real gamma_w, gamma_a, B, c_w, c_a, background;
    int seven;
    /* the air description, copied from the configuration (3 reals a point) */
    sluice_real *above, *box_min, *box_max, *polygon;
    uint32_t above_count, box_count, polygon_count;
    sluice_field phase, density, pressure, sound_speed, mass;
} two_phase_state;

static const sluice_param_spec phase_params[] = {
    {"speed_of_sound", SLUICE_PARAM_REAL, offsetof(two_phase_config, speed_of_sound), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m s^-1",
     "numerical speed of sound of the water c0_w at its rest density (particles.rest_density); "
     "it sets the one B = c0_w^2 rho0_w / gamma and, through it, the air's c0_a (seed 001: 28 "
     "m/s, Chanson chute; 35 m/s, Cheng spillway)",
     NULL, 0},
    {"gamma", SLUICE_PARAM_REAL, offsetof(two_phase_config, gamma), "7", 1, 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1", "polytropic exponent of the water", NULL,
     0},
    {"air_gamma", SLUICE_PARAM_REAL, offsetof(two_phase_config, air_gamma), "1.4", 1, 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "polytropic exponent of the air (isentropic, seed 001: 1.4)", NULL, 0},
    {"air_rest_density", SLUICE_PARAM_REAL, offsetof(two_phase_config, air_rest_density), "1.09",
     0, 0, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "kg m^-3",
     "rest density of the air rho0_a (seed 001: 1.09); air particles have the mass rho0_a dx^d",
     NULL, 0},
    {"background_pressure", SLUICE_PARAM_REAL, offsetof(two_phase_config, background_pressure),
     NULL, 0, 0, SLUICE_PARAM_HAS_MIN, "Pa",
     "p_b added to the pressure of both phases (Colagrossi & Landrini 2003): it must exceed the "
     "largest drop of the pressure below its value at rest density, so that the air never "
     "reaches a negative pressure (tensile instability), and the cohesion pressure a rho0_a^2 "
     "(air_cohesion)",
     NULL, 0},
    {"air_above", SLUICE_PARAM_POINT_LIST, offsetof(two_phase_config, air_above), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m",
     "fluid particles above this line are air: one point gives a level (its vertical "
     "coordinate); in 2D several points give a polyline with increasing x, continued "
     "horizontally beyond its ends",
     NULL, 0},
    {"air_box_min", SLUICE_PARAM_POINT_LIST, offsetof(two_phase_config, air_box_min), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m",
     "lower corners of boxes whose fluid particles are air (one per box, with air_box_max)",
     NULL, 0},
    {"air_box_max", SLUICE_PARAM_POINT_LIST, offsetof(two_phase_config, air_box_max), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m", "upper corners of the air boxes, in the order of air_box_min",
     NULL, 0},
    {"air_polygon", SLUICE_PARAM_POINT_LIST, offsetof(two_phase_config, air_polygon), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m", "vertices of a polygon (2D) whose fluid particles are air", NULL,
     0},
};

static const sluice_field_spec phase_fields[] = {
    SLUICE_SPEC_PHASE_DOC(SLUICE_WRITE, SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART,
                          "phase of the particle: 0 water, 1 air (set at the start)"),
    SLUICE_SPEC_DENSITY(SLUICE_READ),
    SLUICE_SPEC_MASS(0),
    SLUICE_SPEC_PRESSURE_DOC(SLUICE_WRITE, SLUICE_FIELD_OUTPUT,
                             "pressure from the equation of state of the particle's phase"),
    SLUICE_SPEC_SOUND_SPEED_DOC(SLUICE_WRITE,
                                "local speed of sound c = sqrt(dp/drho) of the particle's phase"),
};

static void phase_destroy(void *state)
{
    two_phase_state *s = state;
    if (!s)
        return;
    free(s->above);
    free(s->box_min);
    free(s->box_max);
    free(s->polygon);
    free(s);
}

static sluice_real *copy_points(const sluice_real_list *list)
{
    if (list->count == 0)
        return NULL;
    sluice_real *copy = malloc((size_t)list->count * 3 * sizeof *copy);
    if (copy)
        memcpy(copy, list->values, (size_t)list->count * 3 * sizeof *copy);
    return copy;
}

/* Checks the air description; returns the error text or NULL. */
static const char *check_air(const two_phase_config *c, uint32_t dims, char *text, size_t size)
{
    if (c->air_above.count == 0 && c->air_box_min.count == 0 && c->air_box_max.count == 0 &&
        c->air_polygon.count == 0)
        return "no air is described: give air_above (a level or a polyline), air_box_min with "
               "air_box_max, or air_polygon";
    if (c->air_above.count > 1) {
        if (dims == 3)
            return "air_above takes one point (a level) in 3D; use air_box_min/air_box_max for "
                   "other shapes";
        for (uint32_t k = 1; k < c->air_above.count; k++)
            if (!(c->air_above.values[3 * k] > c->air_above.values[3 * (k - 1)])) {
                snprintf(text, size,
                         "air_above: the polyline's x must increase from point to point (point "
                         "%u at x = %g m follows x = %g m)",
                         k, (double)c->air_above.values[3 * k],
                         (double)c->air_above.values[3 * (k - 1)]);
                return text;
            }
    }
    if (c->air_box_min.count != c->air_box_max.count) {
        snprintf(text, size,
                 "air_box_min has %u corners and air_box_max %u: give one of each per box",
                 c->air_box_min.count, c->air_box_max.count);
        return text;
    }
    for (uint32_t b = 0; b < c->air_box_min.count; b++)
        for (uint32_t d = 0; d < dims; d++)
            if (!(c->air_box_min.values[3 * b + d] < c->air_box_max.values[3 * b + d])) {
                snprintf(text, size,
                         "air box %u: air_box_min %c = %g m is not below air_box_max %c = %g m",
                         b, "xyz"[d], (double)c->air_box_min.values[3 * b + d], "xyz"[d],
                         (double)c->air_box_max.values[3 * b + d]);
                return text;
            }
    if (c->air_polygon.count > 0) {
        if (dims == 3)
            return "air_polygon is 2D only; use air_box_min/air_box_max or air_above in 3D";
        if (c->air_polygon.count < 3) {
            snprintf(text, size, "air_polygon has %u points; a polygon needs at least 3",
                     c->air_polygon.count);
            return text;
        }
    }
    return NULL;
}

static int phase_create(const sluice_api *api, sluice_host *host, const void *config,
                        void **state)
{
    const two_phase_config *c = config;
    two_phase_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    sluice_real dims;
    if (sluice_util_constant(api, host, "rest_density", &s->rho_w) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &s->dx) != SLUICE_OK ||
        sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    char text[300];
    const char *problem = check_air(c, s->dims, text, sizeof text);
    if (problem) {
        api->messages->error(host, "%s", problem);
        free(s);
        return SLUICE_ERROR;
    }
    if (!(c->air_rest_density < s->rho_w)) {
        api->messages->error(host,
                   "air_rest_density = %g kg m^-3 is not below the water's rest density "
                   "(particles.rest_density = %g kg m^-3): the air is the light phase",
                   (double)c->air_rest_density, (double)s->rho_w);
        free(s);
        return SLUICE_ERROR;
    }
    s->rho_a = c->air_rest_density;
    s->inverse_rho_w = 1 / s->rho_w;
    s->inverse_rho_a = 1 / s->rho_a;
    s->gamma_w = c->gamma;
    s->gamma_a = c->air_gamma;
    s->seven = s->gamma_w == 7;
    s->c_w = c->speed_of_sound;
    s->B = s->c_w * s->c_w * s->rho_w / s->gamma_w;
    s->c_a = sqrt(s->gamma_a * s->B / s->rho_a);
    s->background = c->background_pressure;
    s->above_count = c->air_above.count;
    s->box_count = c->air_box_min.count;
    s->polygon_count = c->air_polygon.count;
    s->above = copy_points(&c->air_above);
    s->box_min = copy_points(&c->air_box_min);
    s->box_max = copy_points(&c->air_box_max);
    s->polygon = copy_points(&c->air_polygon);
    if ((s->above_count && !s->above) || (s->box_count && (!s->box_min || !s->box_max)) ||
        (s->polygon_count && !s->polygon)) {
        api->messages->error(host, "out of memory");
        phase_destroy(s);
        return SLUICE_ERROR;
    }
    if (api->fields->publish_constant(host, "speed_of_sound", &s->c_w, 1, "m s^-1") != SLUICE_OK ||
        api->fields->publish_constant(host, "air_speed_of_sound", &s->c_a, 1, "m s^-1") != SLUICE_OK ||
        api->fields->publish_constant(host, "air_rest_density", &s->rho_a, 1, "kg m^-3") != SLUICE_OK ||
        api->fields->publish_constant(host, "air_gamma", &s->gamma_a, 1, "1") != SLUICE_OK ||
        api->fields->publish_constant(host, "reference_pressure", &s->background, 1, "Pa") !=
            SLUICE_OK) {
        phase_destroy(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int phase_bind(void *state, sluice_host *host)
{
    two_phase_state *s = state;
    const sluice_field_binding fields[] = {
        {"phase", &s->phase}, {"density", &s->density}, {"pressure", &s->pressure},
        {"sound_speed", &s->sound_speed}, {"mass", &s->mass}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

/* Level of the air_above polyline at x (2D), or its one level. */
static sluice_real above_level(const two_phase_state *s, sluice_real x)
{
    const uint32_t up = s->dims - 1, n = s->above_count;
    const sluice_real *p = s->above;
    if (n == 1 || x <= p[0])
        return p[up];
    for (uint32_t k = 1; k < n; k++)
        if (x <= p[3 * k]) {
            const sluice_real x0 = p[3 * (k - 1)], x1 = p[3 * k];
            const sluice_real y0 = p[3 * (k - 1) + up], y1 = p[3 * k + up];
            return y0 + (y1 - y0) * (x - x0) / (x1 - x0);
        }
    return p[3 * (n - 1) + up];
}

/* Crossing-number test of a point against the air polygon (2D). */
static int in_polygon(const two_phase_state *s, sluice_real x, sluice_real y)
{
    int inside = 0;
    const uint32_t n = s->polygon_count;
    const sluice_real *p = s->polygon;
    for (uint32_t a = 0, b = n - 1; a < n; b = a++) {
        const sluice_real xa = p[3 * a], ya = p[3 * a + 1], xb = p[3 * b], yb = p[3 * b + 1];
        if ((ya > y) != (yb > y) && x < xa + (xb - xa) * (y - ya) / (yb - ya))
            inside = !inside;
    }
    return inside;
}

static int is_air(const two_phase_state *s, const sluice_real *x)
{
    const uint32_t up = s->dims - 1;
    if (s->above_count && x[up] > above_level(s, x[0]))
        return 1;
    for (uint32_t b = 0; b < s->box_count; b++) {
        int inside = 1;
        for (uint32_t d = 0; d < s->dims; d++)
            inside &= x[d] >= s->box_min[3 * b + d] && x[d] <= s->box_max[3 * b + d];
        if (inside)
            return 1;
    }
    return s->polygon_count && in_polygon(s, x[0], x[1]);
}

static int phase_initialise(void *state, sluice_host *host)
{
    two_phase_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    const uint32_t dims = s->dims, up = dims - 1;
    uint8_t *restrict phase = v->columns[s->phase.column];
    sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    sluice_real *restrict mass = sluice_real_column(v, s->mass, 0);
    sluice_index air = 0, water = 0;
    sluice_real top = -(sluice_real)INFINITY, bottom = (sluice_real)INFINITY;
    for (sluice_index i = 0; i < v->count; i++) {
        /* walls are water (zero-filled by the core); open particles keep
         * the phase their boundary gave them (an inlet's air rows) */
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        phase[i] = PHASE_WATER;
        sluice_real x[3] = {0, 0, 0};
        for (uint32_t d = 0; d < dims; d++)
            x[d] = v->position[d][i];
        if (is_air(s, x)) {
            phase[i] = PHASE_AIR;
            air++;
            bottom = x[up] < bottom ? x[up] : bottom;
        } else {
            water++;
            top = x[up] > top ? x[up] : top;
        }
    }
    if (air == 0) {
        api->messages->error(host, "the air description selects none of the %u fluid particles (are "
                         "air_above, air_box_min/max or air_polygon inside the fluid regions?)",
                   (unsigned)water);
        return SLUICE_ERROR;
    }
    if (water == 0)
        api->messages->warning(host, "every fluid particle is air: the scene has no water");
    /* the air's hydrostatic pressure, p_b at the top of the highest water
     * particle (or at the bottom of the lowest air particle without water) */
    const sluice_real surface = water ? top + s->dx / 2 : bottom - s->dx / 2;
    sluice_real g[3] = {0, 0, 0};
    const uint32_t gravity = api->fields->constant(host, "gravity", g, 3);
    const sluice_real weight = gravity >= dims ? -g[up] * s->rho_a : 0; /* rho_a g, Pa/m */
    const sluice_real volume = (sluice_real)pow((double)s->dx, (double)dims);
    for (sluice_index i = 0; i < v->count; i++) {
        if (phase[i] != PHASE_AIR || v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        mass[i] = s->rho_a * volume;
        const sluice_real excess = weight * (surface - v->position[up][i]); /* p - p_b */
        rho[i] = s->rho_a * (sluice_real)pow(1 + (double)(excess / s->B), 1 / (double)s->gamma_a);
    }
    api->messages->info(host,
              "%u air and %u water particles; B = %.6g Pa, c0 water %.6g m/s, c0 air %.6g m/s, "
              "p_b = %.6g Pa",
              (unsigned)air, (unsigned)water, (double)s->B, (double)s->c_w, (double)s->c_a,
              (double)s->background);
    return SLUICE_OK;
}

static void phase_particle(void *state, const sluice_view *v, sluice_index begin,
                           sluice_index end)
{
    const two_phase_state *s = state;
    const uint8_t *restrict phase = v->columns[s->phase.column];
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    sluice_real *restrict p = sluice_real_column(v, s->pressure, 0);
    sluice_real *restrict c = sluice_real_column(v, s->sound_speed, 0);
    const sluice_real iw = s->inverse_rho_w, ia = s->inverse_rho_a, B = s->B, pb = s->background;
    const sluice_real cw = s->c_w, ca = s->c_a, gw = s->gamma_w, ga = s->gamma_a;
    const sluice_real ew = (gw - 1) / 2;
    for (sluice_index i = begin; i < end; i++) {
        if (phase[i] == PHASE_AIR) {
            const sluice_real x = rho[i] * ia, xg = pow(x, ga);
            p[i] = B * (xg - 1) + pb;
            c[i] = ca * sqrt(xg / x);
        } else if (s->seven) {
            const sluice_real x = rho[i] * iw, x2 = x * x, x3 = x2 * x;
            p[i] = B * (x3 * x3 * x - 1) + pb;
            c[i] = cw * x3;
        } else {
            const sluice_real x = rho[i] * iw;
            p[i] = B * (pow(x, gw) - 1) + pb;
            c[i] = cw * pow(x, ew);
        }
    }
}

/* The water's inverse: the core's hydrostatic start fills every fluid
 * region with it before the phases are known; initialise then sets the air
 * particles' density with the air's law. */
static void phase_density_from_pressure(void *state, sluice_index n, const sluice_real *pressure,
                                        sluice_real *density)
{
    const two_phase_state *s = state;
    for (sluice_index i = 0; i < n; i++)
        density[i] = s->rho_w * (sluice_real)pow(1 + (double)((pressure[i] - s->background) / s->B),
                                                 1 / (double)s->gamma_w);
}

/* ============================================================= cohesion ==== */

typedef struct cohesion_config {
    sluice_real coefficient, smoothing_length_ratio;
    int kernel;
} cohesion_config;

enum { KERNEL_WENDLAND = 0, KERNEL_CUBIC = 1 };

typedef struct cohesion_state {
    const sluice_api *api;
    uint32_t dims;
    int kernel;
    sluice_real a, ratio, h, H, inverse_H, gradient_normalisation;
    sluice_field phase, mass, acceleration;
    /* air_cohesion_held: the pair pass writes `held`, the particle hook adds
     * it to the acceleration at every evaluation */
    int64_t update_every; /* 0: air_cohesion (every evaluation) */
    sluice_field held;
} cohesion_state;

typedef struct held_config {
    cohesion_config cohesion;
    int64_t update_every;
} held_config;

#define COHESION_PARAMS \
    {"coefficient", SLUICE_PARAM_REAL, offsetof(cohesion_config, coefficient), NULL, 0, 0, \
     SLUICE_PARAM_HAS_MIN, "m^5 kg^-1 s^-2", \
     "a of the cohesion pressure -a rho^2 of the air (Nugent & Posch 2000); a rho0_a^2 must " \
     "stay below two_phase's background_pressure", \
     NULL, 0}, \
    {"smoothing_length_ratio", SLUICE_PARAM_REAL, \
     offsetof(cohesion_config, smoothing_length_ratio), "2", 0, 0, \
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "1", \
     "H / h, the smoothing length of the cohesion kernel W(r, H) over the scene's h (Nugent & " \
     "Posch 2000: 2); the pairs reach 2H, beyond the kernel's support when H > h (the core then " \
     "gives this term passes of its own, with (H/h)^d times the pairs of a support pass)", \
     NULL, 0}, \
    {"kernel", SLUICE_PARAM_ENUM, offsetof(cohesion_config, kernel), "wendland_c2", 0, 0, 0, NULL, \
     "shape of W(r, H) (support 2H): the Wendland C2 kernel of seed 001 or the cubic B-spline", \
     "wendland_c2|cubic_spline", 0},

static const sluice_param_spec cohesion_params[] = {COHESION_PARAMS};

/* held_config begins with a cohesion_config: the same offsets */
static const sluice_param_spec held_params[] = {
    COHESION_PARAMS
    {"update_every", SLUICE_PARAM_INT, offsetof(held_config, update_every), "5", 1, 1000,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "recompute the cohesion every this many steps and hold it in between (1: once a step)",
     NULL, 0},
};

#define COHESION_FIELDS \
    SLUICE_SPEC_PHASE(SLUICE_READ), \
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR), \
    SLUICE_SPEC_VELOCITY(0), \
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),

static const sluice_field_spec cohesion_fields[] = {COHESION_FIELDS};

static const sluice_field_spec held_fields[] = {
    COHESION_FIELDS
    {"cohesion_acceleration", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-2",
     SLUICE_READ | SLUICE_WRITE, SLUICE_FIELD_RESTART, NULL, 0,
     "the air's cohesion acceleration of the last update, added at every evaluation "
     "(air_cohesion_held)"},
};

static int cohesion_setup(const sluice_api *api, sluice_host *host, const cohesion_config *c,
                          int64_t update_every, void **state)
{
    cohesion_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    sluice_real dims;
    if (sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->update_every = update_every;
    s->a = c->coefficient;
    s->ratio = c->smoothing_length_ratio;
    s->kernel = c->kernel;
    s->H = s->ratio * s->h;
    s->inverse_H = 1 / s->H;
    /* (dW/dr)/r = gradient_normalisation x shape(q), q = r / H */
    const int wendland = s->kernel == KERNEL_WENDLAND;
    const double n2 = wendland ? 7.0 / (4.0 * SLUICE_PI) : 10.0 / (7.0 * SLUICE_PI);
    const double n3 = wendland ? 21.0 / (16.0 * SLUICE_PI) : 1.0 / SLUICE_PI;
    const double H = (double)s->H;
    s->gradient_normalisation =
        (sluice_real)((s->dims == 3 ? n3 / (H * H * H) : n2 / (H * H)) / (H * H));
    /* the pairs within 2H: beyond the scene kernel's support the core gives
     * this term passes of its own (ABI 1.6); within it this changes nothing */
    /* ...and of those only the air's (ABI 1.7): the water, about half of
     * the particles, is neither traversed nor scanned as a neighbour */
    if (api->evaluation->request_reach(host, 2 * s->H) != SLUICE_OK ||
        api->evaluation->restrict_reach(host, "phase", PHASE_AIR) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int cohesion_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state)
{
    return cohesion_setup(api, host, config, 0, state);
}

static int held_create(const sluice_api *api, sluice_host *host, const void *config,
                       void **state)
{
    const held_config *c = config;
    return cohesion_setup(api, host, &c->cohesion, c->update_every, state);
}

static int cohesion_bind(void *state, sluice_host *host)
{
    cohesion_state *s = state;
    const sluice_api *api = s->api;
    const sluice_field_binding fields[] = {{"phase", &s->phase},
                                           {"mass", &s->mass},
                                           {"acceleration", &s->acceleration},
                                           {"cohesion_acceleration", &s->held}};
    /* the held acceleration only when it is updated every N steps */
    if (sluice_util_bind(api, host, fields, s->update_every ? 4 : 3) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real rho_a, background;
    if (api->fields->constant(host, "air_rest_density", &rho_a, 1) < 1 ||
        api->fields->constant(host, "reference_pressure", &background, 1) < 1) {
        api->messages->error(host, "needs the two_phase plugin, which sets the field 'phase' and publishes "
                         "'air_rest_density' and the background pressure: load two_phase");
        return SLUICE_ERROR;
    }
    /* the transport velocity's background pressure orders the particles
     * against the attraction as the equation of state's does (docs/physics.md) */
    sluice_real transport = 0;
    api->fields->constant(host, "transport_background_pressure", &transport, 1);
    background += transport;
    if (s->a > 0 && !(s->a * rho_a * rho_a < background)) {
        api->messages->error(host,
                   "the cohesion pressure a rho0_a^2 = %g Pa is not below the background "
                   "pressure p_b = %g Pa (two_phase's, plus transport_velocity's if loaded): "
                   "the attraction would make the air clump (tensile instability); lower the "
                   "coefficient below %g m^5 kg^-1 s^-2 or raise a background pressure",
                   (double)(s->a * rho_a * rho_a), (double)background,
                   (double)(background / (rho_a * rho_a)));
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static void cohesion_destroy(void *state)
{
    free(state);
}

/* (dW/dr)/r of the cohesion kernel at q = r/H, without its normalisation;
 * zero beyond q = 2. Wendland C2: -5 (1 - q/2)^3; cubic B-spline: -3 +
 * 2.25 q (q < 1), -0.75 (2 - q)^2 / q (1 <= q < 2). */
static inline sluice_real cohesion_shape(const sluice_real q, const int kernel)
{
    if (kernel == KERNEL_WENDLAND) {
        sluice_real t = 1 - (sluice_real)0.5 * q;
        t = t > 0 ? t : 0;
        return -5 * t * t * t;
    }
    sluice_real t = 2 - q;
    t = t > 0 ? t : 0;
    const sluice_real inner = -3 + (sluice_real)2.25 * q;
    const sluice_real outer = (sluice_real)-0.75 * t * t / (q > (sluice_real)1e-12 ? q : 1);
    return q < 1 ? inner : outer;
}

static inline void cohesion_pairs(const cohesion_state *s, const sluice_view *v,
                                  const sluice_pair_batch *b, const uint32_t dims,
                                  const int kernel, const int held)
{
    const uint8_t *restrict phase = v->columns[s->phase.column];
    const sluice_index *restrict nb = b->neighbour;
    const uint8_t *restrict kj = b->neighbour_kind;
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict r = b->distance;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const sluice_field out = held ? s->held : s->acceleration;
    sluice_real *restrict ax = sluice_real_column(v, out, 0);
    sluice_real *restrict ay = sluice_real_column(v, out, 1);
    sluice_real *restrict az = dims == 3 ? sluice_real_column(v, out, 2) : ay;
    const sluice_real iH = s->inverse_H;
    const sluice_real scale = 2 * s->a * s->gradient_normalisation; /* 2 a x normalisation */
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        if (phase[i] != PHASE_AIR)
            continue; /* a = 0 in the water */
        sluice_real sx = 0, sy = 0, sz = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_real air =
                (sluice_real)(phase[nb[k]] == PHASE_AIR && kj[k] != SLUICE_KIND_OPEN);
            const sluice_real c = air * mj[k] * cohesion_shape(r[k] * iH, kernel);
            sx += c * rx[k];
            sy += c * ry[k];
            if (dims == 3)
                sz += c * rz[k];
        }
        /* held: each air target comes once in the pass (the field was
         * zeroed before it) */
        ax[i] = (held ? 0 : ax[i]) + scale * sx;
        ay[i] = (held ? 0 : ay[i]) + scale * sy;
        if (dims == 3)
            az[i] = (held ? 0 : az[i]) + scale * sz;
    }
}

static void cohesion_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const cohesion_state *s = state;
    const int key = ((v->dimensions == 3) << 2) | ((s->kernel == KERNEL_CUBIC) << 1) |
                    (s->update_every > 0);
    switch (key) {
    case 0: cohesion_pairs(s, v, b, 2, KERNEL_WENDLAND, 0); break;
    case 1: cohesion_pairs(s, v, b, 2, KERNEL_WENDLAND, 1); break;
    case 2: cohesion_pairs(s, v, b, 2, KERNEL_CUBIC, 0); break;
    case 3: cohesion_pairs(s, v, b, 2, KERNEL_CUBIC, 1); break;
    case 4: cohesion_pairs(s, v, b, 3, KERNEL_WENDLAND, 0); break;
    case 5: cohesion_pairs(s, v, b, 3, KERNEL_WENDLAND, 1); break;
    case 6: cohesion_pairs(s, v, b, 3, KERNEL_CUBIC, 0); break;
    default: cohesion_pairs(s, v, b, 3, KERNEL_CUBIC, 1); break;
    }
}

/* air_cohesion_held: refresh before the step when the step count is a
 * multiple of update_every (so a restart keeps the schedule: the held field
 * is in the checkpoint) */
static int held_before_step(void *state, sluice_host *host)
{
    cohesion_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    if (v->step % s->update_every != 0)
        return SLUICE_OK;
    for (uint32_t d = 0; d < s->dims; d++) {
        sluice_real *a = sluice_real_column(v, s->held, d);
        memset(a, 0, (size_t)v->count * sizeof *a);
    }
    return s->api->evaluation->pair_pass(host);
}

/* every evaluation: the held cohesion joins the other accelerations */
static void held_particle(void *state, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const cohesion_state *s = state;
    for (uint32_t d = 0; d < s->dims; d++) {
        const sluice_real *restrict held = sluice_real_column(v, s->held, d);
        sluice_real *restrict a = sluice_real_column(v, s->acceleration, d);
        for (sluice_index i = begin; i < end; i++)
            a[i] += v->kind[i] == SLUICE_KIND_FLUID ? held[i] : 0;
    }
}

/* ================================================= unresolved bubbles ==== */

/* An air particle with no other air particle within the kernel support
 * stands for a bubble smaller than the resolution, which two-phase SPH
 * cannot carry: its acceleration -grad p / rho_a is that of the surrounding
 * water's pressure field divided by a density 900 times smaller, against up
 * to twenty water neighbours, and in the Chanson chute one such particle,
 * trapped in a step corner for six seconds while the water packed in around
 * it, was finally thrown out at 60 m/s and stopped the run at 7.78 s
 * (docs/validation.md). unresolved_bubbles takes such air out of the flow:
 * every `check_every` steps an on-demand pair pass over the kernel support
 * looks for air neighbours (fluid or an open boundary's air) of each air
 * particle; a particle without any adds the time since the last check to its
 * field isolation_time, one with any resets it to zero; a particle whose
 * isolation_time reaches `lifetime` leaves the domain. Its mass and volume
 * (mass / rho0_a) are counted in the table, so that the air balances, like
 * the vent's; the water closes the hole it leaves.
 *   With `max_compression` c > 0, an air particle whose density exceeds
 * rho0_a (1 + c) leaves too, at the end of the step that compressed it: a
 * pocket of air squeezed by the water beyond what any pressure of the flow
 * can do (Cheng's spillway: 7 % for the 6 m/s jet's stagnation pressure,
 * 3 % under the tank's 0.8 m of water) is air the resolution cannot carry
 * (a spin-up of it stopped at 0.12 and 0.16 s with air particles at 1.6 and
 * 2.2 rho0_a, docs/validation.md). They are counted with the isolated ones
 * and, on their own, in the column particles_compressed_total. */

typedef struct bubbles_config {
    sluice_real lifetime, interval, max_compression;
    int64_t check_every;
    const char *file;
} bubbles_config;

typedef struct bubbles_state {
    const sluice_api *api;
    sluice_real lifetime, rho_a, span, max_compression;
    int64_t check_every;
    const char *file;
    sluice_field phase, mass, isolation, density;
    sluice_table *table;
    sluice_index *to_remove;
    sluice_index capacity;
    /* bookkeeping, alike on every rank (reduced) and kept in checkpoints */
    double last_check, row_time, mass_total, mass_interval;
    int64_t removed_total, removed_interval, isolated, logged;
    sluice_schedule rows; /* the next row is due at rows.count x rows.interval */
    int64_t compressed_total;
} bubbles_state;

static const sluice_param_spec bubbles_params[] = {
    {"lifetime", SLUICE_PARAM_REAL, offsetof(bubbles_config, lifetime), "0.05", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "s",
     "time an air particle may spend without another air particle within the kernel support "
     "before it leaves the domain as an unresolved bubble",
     NULL, 0},
    {"check_every", SLUICE_PARAM_INT, offsetof(bubbles_config, check_every), "20", 1, 100000,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "steps between two searches for air neighbours (an on-demand pass over the kernel support)",
     NULL, 0},
    {"max_compression", SLUICE_PARAM_REAL, offsetof(bubbles_config, max_compression), "0", 0, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "c > 0: an air particle denser than rho0_a (1 + c) leaves at the end of the step, as air "
     "squeezed beyond what the flow's pressures can do (choose c well above the largest "
     "(1 + p_max / B)^(1 / gamma_a) - 1 of the flow); 0: off",
     NULL, 0},
    {"interval", SLUICE_PARAM_REAL, offsetof(bubbles_config, interval), "0.05", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between rows of the table", NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(bubbles_config, file), "unresolved_bubbles.csv", 0, 0,
     0, NULL, "the air removed, as a time series in the run directory", NULL, 0},
};

static const sluice_field_spec bubbles_fields[] = {
    SLUICE_SPEC_PHASE(SLUICE_READ),
    SLUICE_SPEC_MASS(SLUICE_READ),
    {"isolation_time", SLUICE_TYPE_REAL, 1, "s", SLUICE_READ | SLUICE_WRITE,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0,
     "time an air particle has spent without another air particle within the kernel support "
     "(0 in the water; unresolved_bubbles)"},
    SLUICE_SPEC_DENSITY_DOC(SLUICE_READ, "density (max_compression)"),
};

static int bubbles_create(const sluice_api *api, sluice_host *host, const void *config,
                          void **state)
{
    const bubbles_config *c = config;
    bubbles_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->lifetime = c->lifetime;
    s->rows = sluice_schedule_every(c->interval);
    s->check_every = c->check_every;
    s->max_compression = c->max_compression;
    s->file = c->file;
    *state = s;
    return SLUICE_OK;
}

static void bubbles_destroy(void *state)
{
    bubbles_state *s = state;
    if (s)
        free(s->to_remove);
    free(s);
}

static int bubbles_bind(void *state, sluice_host *host)
{
    bubbles_state *s = state;
    const sluice_api *api = s->api;
    const sluice_field_binding fields[] = {
        {"phase", &s->phase}, {"mass", &s->mass}, {"isolation_time", &s->isolation},
        {"density", &s->density}};
    if (sluice_util_bind(api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    if (api->fields->constant(host, "air_rest_density", &s->rho_a, 1) < 1) {
        api->messages->error(host, "needs the two_phase plugin, which sets the field 'phase' and publishes "
                         "'air_rest_density': load two_phase");
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int bubbles_initialise(void *state, sluice_host *host)
{
    bubbles_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    s->last_check = s->row_time = v->time;
    s->table = s->api->output->table_open(host, s->file,
                                  "time,particles_removed,mass_removed_total,"
                                  "volume_removed_total,particles_removed_total,isolated_air,"
                                  "particles_compressed_total");
    uint32_t dims = 2;
    if (!s->table || sluice_util_dimensions(s->api, host, &dims) != SLUICE_OK)
        return SLUICE_ERROR;
    /* per metre of span in 2D */
    const sluice_column_doc columns[] = {
        {"s", "simulated time"},
        {"1", "air particles removed since the previous row"},
        {dims == 2 ? "kg m^-1" : "kg", "mass of the air removed since the start"},
        {dims == 2 ? "m^2" : "m^3", "volume of the air removed since the start (mass / rho0_a)"},
        {"1", "air particles removed since the start"},
        {"1", "air particles without an air neighbour at the last check"},
        {"1", "air particles removed as over-compressed since the start"},
    };
    return sluice_util_describe_columns(s->api, s->table, 0, columns, SLUICE_COUNT(columns));
}

/* the pass: an air target with an air neighbour is not isolated (its time
 * was advanced before the pass, and is reset here) */
static void bubbles_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const bubbles_state *s = state;
    const uint8_t *restrict phase = v->columns[s->phase.column];
    sluice_real *restrict isolation = sluice_real_column(v, s->isolation, 0);
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        if (phase[i] != PHASE_AIR)
            continue;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++)
            if (phase[b->neighbour[k]] == PHASE_AIR) {
                isolation[i] = 0;
                break;
            }
    }
}

static int bubbles_row(bubbles_state *s, double time)
{
    const double row[7] = {time,
                           (double)s->removed_interval,
                           s->mass_total,
                           s->mass_total / s->rho_a,
                           (double)s->removed_total,
                           (double)s->isolated,
                           (double)s->compressed_total};
    if (s->api->output->table_row(s->table, row, 7) != SLUICE_OK)
        return SLUICE_ERROR;
    s->removed_interval = 0;
    s->mass_interval = 0;
    s->row_time = time;
    return SLUICE_OK;
}

static int bubbles_rows(bubbles_state *s, sluice_host *host, double time)
{
    if (!sluice_schedule_due(&s->rows, time))
        return SLUICE_OK;
    if (bubbles_row(s, time) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->rows, s->api, host, time);
    return SLUICE_OK;
}

static int bubbles_reserve(bubbles_state *s, sluice_host *host, sluice_index count)
{
    if (count <= s->capacity)
        return SLUICE_OK;
    sluice_index *grown = realloc(s->to_remove, (size_t)count * sizeof *grown);
    if (!grown) {
        s->api->messages->error(host, "out of memory for %llu particle indices", (unsigned long long)count);
        return SLUICE_ERROR;
    }
    s->to_remove = grown;
    s->capacity = count;
    return SLUICE_OK;
}

static void bubbles_log(bubbles_state *s, sluice_host *host, const sluice_view *v,
                        sluice_index i, const char *why)
{
    if (s->logged >= 10)
        return;
    char where[96];
    if (v->dimensions == 3)
        snprintf(where, sizeof where, "(%.4g, %.4g, %.4g)", (double)v->position[0][i],
                 (double)v->position[1][i], (double)v->position[2][i]);
    else
        snprintf(where, sizeof where, "(%.4g, %.4g)", (double)v->position[0][i],
                 (double)v->position[1][i]);
    s->api->messages->info(host, "t = %.6g s: air particle %llu at %s m %s; it leaves as an unresolved "
                       "bubble (%s%s)",
                 v->time, (unsigned long long)v->id[i], where, why, s->file,
                 s->logged == 9 ? "; further ones are counted there only" : "");
    s->logged++;
}

/* max_compression: air squeezed past rho0_a (1 + c) leaves now (every step,
 * on every rank: a collective sum) */
static int bubbles_compressed(bubbles_state *s, sluice_host *host)
{
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (bubbles_reserve(s, host, v->count) != SLUICE_OK)
        return SLUICE_ERROR;
    const uint8_t *phase = v->columns[s->phase.column];
    const sluice_real *density = sluice_real_column(v, s->density, 0);
    const sluice_real *mass = sluice_real_column(v, s->mass, 0);
    const sluice_real limit = s->rho_a * (1 + s->max_compression);
    sluice_index removed = 0;
    double removed_mass = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID || phase[i] != PHASE_AIR || !(density[i] > limit))
            continue;
        s->to_remove[removed++] = i;
        removed_mass += (double)mass[i];
        char why[96];
        snprintf(why, sizeof why, "was compressed to %.4g rho0_a (max_compression %g)",
                 (double)(density[i] / s->rho_a), (double)s->max_compression);
        bubbles_log(s, host, v, i, why);
    }
    double sums[2] = {(double)removed, removed_mass};
    if (api->ranks->reduce(host, sums, 2, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    s->removed_interval += (int64_t)sums[0];
    s->removed_total += (int64_t)sums[0];
    s->compressed_total += (int64_t)sums[0];
    s->mass_interval += sums[1];
    s->mass_total += sums[1];
    if (removed && api->particles->remove_particles(host, s->to_remove, removed) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static int bubbles_after_step(void *state, sluice_host *host)
{
    bubbles_state *s = state;
    const sluice_api *api = s->api;
    if (s->max_compression > 0 && bubbles_compressed(s, host) != SLUICE_OK)
        return SLUICE_ERROR;
    const sluice_view *v = api->particles->view(host);
    if (v->step % s->check_every != 0)
        return bubbles_rows(s, host, v->time);
    /* every air particle is isolated until the pass finds an air neighbour */
    const double span = v->time - s->last_check;
    {
        const uint8_t *phase = v->columns[s->phase.column];
        sluice_real *isolation = sluice_real_column(v, s->isolation, 0);
        for (sluice_index i = 0; i < v->count; i++)
            isolation[i] = v->kind[i] == SLUICE_KIND_FLUID && phase[i] == PHASE_AIR
                               ? isolation[i] + (sluice_real)span
                               : 0;
    }
    if (api->evaluation->pair_pass(host) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host); /* the pass may have reordered the particles */
    if (bubbles_reserve(s, host, v->count) != SLUICE_OK)
        return SLUICE_ERROR;
    const uint8_t *phase = v->columns[s->phase.column];
    const sluice_real *isolation = sluice_real_column(v, s->isolation, 0);
    const sluice_real *mass = sluice_real_column(v, s->mass, 0);
    sluice_index removed = 0, isolated = 0;
    double removed_mass = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID || phase[i] != PHASE_AIR || !(isolation[i] > 0))
            continue;
        if (isolation[i] + 1e-9 * s->lifetime < s->lifetime) {
            isolated++;
            continue;
        }
        s->to_remove[removed++] = i;
        removed_mass += (double)mass[i];
        char why[96];
        snprintf(why, sizeof why, "had no other air within the kernel support for %.3g s",
                 (double)isolation[i]);
        bubbles_log(s, host, v, i, why);
    }
    /* over the ranks: alike on every rank */
    double sums[3] = {(double)removed, removed_mass, (double)isolated};
    if (api->ranks->reduce(host, sums, 3, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    s->removed_interval += (int64_t)sums[0];
    s->removed_total += (int64_t)sums[0];
    s->mass_interval += sums[1];
    s->mass_total += sums[1];
    s->isolated = (int64_t)sums[2];
    s->last_check = v->time;
    const double time = v->time;
    if (removed && api->particles->remove_particles(host, s->to_remove, removed) != SLUICE_OK)
        return SLUICE_ERROR;
    return bubbles_rows(s, host, time);
}

static int bubbles_finish(void *state, sluice_host *host, int status)
{
    bubbles_state *s = state;
    (void)status;
    const double time = s->api->particles->view(host)->time;
    if (s->table && time > s->row_time)
        return bubbles_row(s, time);
    return SLUICE_OK;
}

static int bubbles_save(void *state, sluice_host *host)
{
    const bubbles_state *s = state;
    const double values[4] = {s->last_check, s->row_time, s->mass_total, s->mass_interval};
    const int64_t counts[5] = {s->removed_total, s->removed_interval, s->isolated, s->rows.count,
                               s->logged};
    if (s->api->state->state_write(host, "last_check,row_time,mass_total,mass_interval",
                            SLUICE_STATE_DOUBLE, 4, values) != SLUICE_OK ||
        s->api->state->state_write(host, "removed_total,removed_interval,isolated,rows_written,logged",
                            SLUICE_STATE_INT64, 5, counts) != SLUICE_OK ||
        s->api->state->state_write(host, "compressed_total", SLUICE_STATE_INT64, 1,
                            &s->compressed_total) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static int bubbles_load(void *state, sluice_host *host)
{
    bubbles_state *s = state;
    double values[4];
    int64_t counts[5];
    if (s->api->state->state_read(host, "last_check,row_time,mass_total,mass_interval",
                           SLUICE_STATE_DOUBLE, 4, values) != SLUICE_OK ||
        s->api->state->state_read(host, "removed_total,removed_interval,isolated,rows_written,logged",
                           SLUICE_STATE_INT64, 5, counts) != SLUICE_OK)
        return SLUICE_ERROR;
    /* checkpoints of unresolved_bubbles before max_compression (two_phase
     * 1.3.0) have none: nothing was removed for it */
    s->compressed_total = 0;
    if (s->api->state->state_length(host, "compressed_total") >= 0 &&
        s->api->state->state_read(host, "compressed_total", SLUICE_STATE_INT64, 1,
                           &s->compressed_total) != SLUICE_OK)
        return SLUICE_ERROR;
    s->last_check = values[0];
    s->row_time = values[1];
    s->mass_total = values[2];
    s->mass_interval = values[3];
    s->removed_total = counts[0];
    s->removed_interval = counts[1];
    s->isolated = counts[2];
    s->logged = counts[4];
    return sluice_schedule_restore(&s->rows, s->api, host,
                                   "removed_total,removed_interval,isolated,rows_written,logged",
                                   counts[3]);
}

static const sluice_component components[] = {
    {
        .name = "two_phase",
        .summary = "air-water phases: the phase field, the air's mass and density, and Tait's "
                   "equation of state of each phase with one B and a background pressure",
        .reference = "Colagrossi & Landrini (2003); Wan et al. (2017, seed 001) eq. 10",
        .dimensions = SLUICE_DIMS_ALL,
        .params = phase_params,
        .param_count = SLUICE_COUNT(phase_params),
        .config_size = sizeof(two_phase_config),
        .fields = phase_fields,
        .field_count = SLUICE_COUNT(phase_fields),
        .particle_kinds = SLUICE_KINDS_ALL,
        .create = phase_create,
        .destroy = phase_destroy,
        .bind = phase_bind,
        .initialise = phase_initialise,
        .particle = phase_particle,
        .density_from_pressure = phase_density_from_pressure,
    },
    {
        .name = "air_cohesion",
        .summary = "cohesion of the air: dv_i/dt += 2 a sum_{j air} m_j grad W(r_ij, H)",
        .reference = "Nugent & Posch (2000); Colagrossi & Landrini (2003); Wan et al. (2017, "
                     "seed 001) eq. 12",
        .dimensions = SLUICE_DIMS_ALL,
        .params = cohesion_params,
        .param_count = SLUICE_COUNT(cohesion_params),
        .config_size = sizeof(cohesion_config),
        .fields = cohesion_fields,
        .field_count = SLUICE_COUNT(cohesion_fields),
        .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .create = cohesion_create,
        .destroy = cohesion_destroy,
        .bind = cohesion_bind,
        .pair = cohesion_pair,
    },
    {
        .name = "air_cohesion_held",
        .summary = "air_cohesion recomputed every update_every steps and held in between "
                   "(multiple time stepping)",
        .reference = "Nugent & Posch (2000); Wan et al. (2017, seed 001) eq. 12; held between "
                     "updates as in multiple-time-step integration (Tuckerman et al. 1992)",
        .dimensions = SLUICE_DIMS_ALL,
        .params = held_params,
        .param_count = SLUICE_COUNT(held_params),
        .config_size = sizeof(held_config),
        .fields = held_fields,
        .field_count = SLUICE_COUNT(held_fields),
        .flags = SLUICE_COMPONENT_ON_DEMAND,
        .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .particle_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .create = held_create,
        .destroy = cohesion_destroy,
        .bind = cohesion_bind,
        .pair = cohesion_pair,
        .particle = held_particle,
        .before_step = held_before_step,
    },
    {
        .name = "unresolved_bubbles",
        .summary = "air particles with no other air within the kernel support for `lifetime` "
                   "leave the domain as bubbles below the resolution; their air is counted",
        .reference = "Sluice (docs/physics.md, \"Unresolved bubbles\")",
        .dimensions = SLUICE_DIMS_ALL,
        .params = bubbles_params,
        .param_count = SLUICE_COUNT(bubbles_params),
        .config_size = sizeof(bubbles_config),
        .fields = bubbles_fields,
        .field_count = SLUICE_COUNT(bubbles_fields),
        .flags = SLUICE_COMPONENT_ON_DEMAND | SLUICE_COMPONENT_ACROSS_RANKS,
        .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
        .create = bubbles_create,
        .destroy = bubbles_destroy,
        .bind = bubbles_bind,
        .initialise = bubbles_initialise,
        .pair = bubbles_pair,
        .after_step = bubbles_after_step,
        .finish = bubbles_finish,
        .save_state = bubbles_save,
        .load_state = bubbles_load,
    },
};

SLUICE_DEFINE_LIBRARY("two_phase", "1.5.0", "air-water two-phase SPH: phases, equation of state, "
                      "cohesion of the air, unresolved bubbles", SLUICE_DIMS_ALL, components)
