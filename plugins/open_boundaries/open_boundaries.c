/* Open boundaries for channel flows along +x: `inlet` and `outlet`.
 *
 * Both work between steps (after_step hooks) on particles of the core's kind
 * SLUICE_KIND_OPEN: fluid whose state the boundary imposes, which the
 * integrators do not move and which every term sees as a fluid neighbour, so
 * the fluid next to a boundary keeps a full kernel support.
 *
 * inlet (x < position): a lattice of open particles, spacing dx, `width`
 * long (default: the kernel support rounded up to whole spacings), rows
 * from the bed up to the inflow depth d1 (the vertical axis is the last one;
 * in 3D the lateral axis y spans `span`). They move at the inflow velocity
 * V1 (given, or q / d1 from the discharge q) with the hydrostatic density of
 * depth d1 (through the scene's equation of state), and with k = 1.5 (I V1)^2
 * and eps = c_mu^(3/4) k^(3/2) / (l_f d1) when a k-epsilon model is loaded
 * (seed 004: I = 10 %, l = 0.5 d1); with `submergence` s > 0 the inflow is
 * submerged under a gate (a reservoir fed below its surface) and the
 * hydrostatic density is that of depth d1 + s. A particle that passes x = position
 * becomes fluid with that state. Fluid that flows back upstream across the
 * plane within the inflow's section (below its top row's top) is removed:
 * it leaves through the inlet, a negative mass flux in inlet.csv (an open
 * channel's reverse flow). With `backflow: hold` it stays on the plane with
 * the velocity V1 along x instead (and so does the integrator's stored
 * v^(n-1)), so that a discharge-controlled feed delivers q whatever the
 * water downstream does: a reservoir's sloshing is of the order of a
 * submerged feed's slow V1 and, removed, took half of Cheng's q back.
 * Above the section such fluid is removed once dx/2 upstream of the plane
 * (less is fluid touching a gate's face).
 *   form buffer (seed 004, De Padova et al. 2017): the layer stays `width`
 *     long: a new column enters at its back every dx / V1.
 *   form block (seed 000, Jonsson et al. 2016): the whole inflow of the run
 *     is placed at the start, V1 x end time (+ width) long, upstream of the
 *     inlet (the domain must hold it); nothing is created later.
 *   Two-phase scenes (the field `phase` of two_phase: 0 water, 1 air): the
 *   water rows get phase 0; with air_depth = a > 0 every column also has
 *   rows of air (phase 1, mass rho0_a dx^d) above the water, up to
 *   bed + d1 + a (round((d1 + a) / dx) rows in all), moving at V1 like the
 *   water. The pressure is hydrostatic with p_b (two_phase's
 *   reference_pressure) at the top of the air:
 *       air    p = p_b + rho0_a g (bed + d1 + a - z),
 *       water  p = p_b + rho0_a g a + rho0_w g (bed + d1 - z),
 *   the water's density through the scene's inverse (two_phase's water
 *   law), the air's through the air's law inverted with two_phase's
 *   constants: rho = rho0_a ((p - p_b) / B + 1)^(1 / gamma_a),
 *   B = rho0_a c0_a^2 / gamma_a (= the water's B). air_depth > 0 needs the
 *   field `phase` (checked at load); two_phase's start leaves the phase of
 *   open particles alone, so the order of the two in the scene is free.
 *   Particles the inlet creates have every other field zero (the core's
 *   rule): dissolved_oxygen gives them their concentration by phase.
 *
 * outlet (x >= position): fluid that passes x = position
 *   form free (seed 002, Lin et al. 2025): is removed;
 *   form frozen (seed 000): becomes open with its velocity and density
 *     frozen, moves on with that velocity, and is removed `width` past the
 *     outlet or at the domain's edge;
 *   form buffer (seed 004): becomes open with the imposed tailwater velocity
 *     Vt and the hydrostatic density of the tailwater depth yt, moves at Vt,
 *     and is removed `width` past the outlet. In a two-phase scene air that
 *     enters the buffer takes the air's density at the tailwater column's
 *     pressure, p_b at its surface bed + yt: p = p_b + rho0_w g (bed + yt -
 *     z) below it, p_b - rho0_a g (z - bed - yt) above it.
 *   phase (all|water|air, phase_filter.h): only fluid of that phase crosses
 *   into the outlet's treatment; the other phase stays ordinary fluid past
 *   the plane (e.g. the air of a closed box over a channel whose water
 *   leaves through the outlet).
 *
 * air_vent (two-phase scenes): the atmosphere for air in a box. The fluid
 *   in its box becomes open air at rest with the air's density at p_b (at
 *   the box's bottom face, hydrostatic within), where it stands. After each
 *   step fluid whose centre is in the box leaves the domain, and so does air
 *   within dx/2 of the box while the air's mean pressure (over every air
 *   particle, averaged exponentially over response_time) exceeds p_b: air
 *   the water displaces leaves, and the box's air stays near p_b. One way:
 *   no air is drawn in. It lies between the inlet's and the outlet's planes
 *   (each moves the open particles on its side). air_vent.csv: time,
 *   mass_flux, volume_flux (/ rho0_a), mass_total, water_mass_total (water
 *   that reached it, warned of), air_pressure_near and air_particles_near
 *   (the air within the kernel support of the box).
 *
 * Each boundary writes the mass and x-momentum flux through its plane to a
 * CSV (`inlet.csv`, `outlet.csv`): time, mass_flux (kg s^-1; per metre of
 * width in 2D), discharge (mass_flux / rho0: m^2 s^-1 in 2D, m^3 s^-1 in 3D),
 * momentum_flux (sum of m u_x crossing per second: N, per metre in 2D),
 * mass_total (kg since the start), open_particles (in its buffer), averaged
 * over each `interval`. When the scene has the field `phase` they count the
 * water only (air crosses, but is not counted), so that discharge is the
 * water's.
 *
 * Across MPI ranks (1.2.0, SLUICE_COMPONENT_ACROSS_RANKS): each rank moves,
 * converts and removes its own particles; every step the boundary sums its
 * ranks' mass and momentum through the plane and its open particles
 * (api->ranks->reduce), so its sums, its table and its checkpoint state are alike on
 * every rank; the inlet's new column is added by the rank that owns its place
 * (api->ranks->owns); the vent sums the air's pressure over the ranks before it
 * decides to let air out. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sluice/phase_filter.h>
#include <sluice/plugin_util.h>

enum { INLET_BUFFER = 0, INLET_BLOCK = 1 };
enum { OUTLET_FREE = 0, OUTLET_FROZEN = 1, OUTLET_BUFFER = 2 };
enum { TAILWATER_IMPOSED = 0, TAILWATER_CONTROLLED = 1 };
enum { BACKFLOW_LEAVE = 0, BACKFLOW_HOLD = 1 };

typedef struct boundary_config {
    int form;
    sluice_real position, bed, depth, velocity, discharge, width;
    sluice_real span[3];
    sluice_real turbulence_intensity, mixing_length_factor;
    sluice_real interval;
    const char *file;
    sluice_real air_depth, submergence; /* inlet */
    int backflow;                       /* inlet: BACKFLOW_* */
    int phase;             /* outlet: SLUICE_PHASE_* */
    sluice_real box_min[3], box_max[3]; /* air_vent */
    sluice_real response_time;          /* air_vent */
    int tailwater;                      /* outlet buffer: TAILWATER_* */
    sluice_real control_position, control_time;
} boundary_config;

typedef struct boundary_state {
    const sluice_api *api;
    int inlet, form;
    uint32_t dims, vertical;
    double position, bed, depth, velocity, width, dx, rho0, g, p_ref;
    double span[2];
    double turbulence_k, turbulence_epsilon, mixing_length;
    const char *file;
    double domain_min[3], domain_max[3];
    sluice_field velocity_field, density_field, mass_field, pressure_field;
    int has_k, has_pressure;
    sluice_field k_field, epsilon_field;
    /* two-phase scenes: the field `phase` (0 water, 1 air) of two_phase */
    int has_phase;       /* the field exists: the fluxes count water only */
    sluice_field phase_field;
    int phase_filter;    /* outlet: the phase it treats (SLUICE_PHASE_*) */
    double air_depth;    /* inlet: depth of the air layer above the water */
    double submergence;  /* inlet: water standing above the inflow's top */
    int backflow;        /* inlet: BACKFLOW_* */
    int has_velocity_previous; /* the integrator's v^(n-1) (verlet), set with v when held: */
    int velocity_previous_known; /* looked up at the first step (declared in bind) */
    sluice_field velocity_previous_field;
    double rho_a, gamma_a, B, air_mass; /* rho0_a, gamma_a, Tait B, rho0_a dx^d */
    /* inlet lattice */
    uint32_t rows, lanes;   /* vertical rows of water, lateral lanes (3D) */
    uint32_t air_rows;      /* rows of air above the water rows */
    double newest_column;   /* x of the last column created */
    double *column_density; /* hydrostatic density per row (water, then air) */
    sluice_real *scratch;   /* positions of a new column */
    /* outlet tailwater density by height: computed per particle */
    /* between-step bookkeeping */
    double last_time;
    sluice_index *to_convert, *to_remove;
    sluice_index capacity;
    /* fluxes */
    double mass_interval, momentum_interval, mass_total, row_time;
    sluice_schedule table_rows; /* the next row is due at count x interval */
    sluice_index open_count;
    sluice_table *table;
    /* air_vent: its box, the water that reached it, and the mean pressure
     * of the air next to it at the last row */
    double box_min[3], box_max[3];
    int vent;
    double response_time, air_pressure; /* the air's mean pressure, filtered */
    double water_total;
    int water_warned;
    /* outlet buffer with a controlled tailwater: the depth at the control
     * section (filtered) and the imposed velocity, the integral part of
     * the controller and whether the filter has its first value */
    int controlled;
    double control_position, control_time, control_strip;
    double control_depth, velocity_integral;
    int control_started;
} boundary_state;

static const sluice_param_spec inlet_params[] = {
    {"form", SLUICE_PARAM_ENUM, offsetof(boundary_config, form), "buffer", 0, 0, 0, NULL,
     "buffer: a 2h layer renewed every dx/V1 (seed 004); block: the run's whole inflow placed "
     "upstream at the start (seed 000)",
     "buffer|block", 0},
    {"position", SLUICE_PARAM_REAL, offsetof(boundary_config, position), NULL, 0, 0, 0, "m",
     "x of the inlet plane: fluid starts here, the buffer lies upstream of it", NULL, 0},
    {"bed", SLUICE_PARAM_REAL, offsetof(boundary_config, bed), "0", 0, 0, 0, "m",
     "elevation of the bed under the inlet (vertical axis: the last one)", NULL, 0},
    {"depth", SLUICE_PARAM_REAL, offsetof(boundary_config, depth), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m", "inflow depth d1", NULL, 0},
    {"air_depth", SLUICE_PARAM_REAL, offsetof(boundary_config, air_depth), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "m",
     "two-phase scenes (two_phase loaded): rows of air (phase 1) from "
     "the water's surface up to bed + depth + air_depth, moving at V1, with the air's "
     "hydrostatic density (the background pressure p_b at their top); 0: water only",
     NULL, 0},
    {"submergence", SLUICE_PARAM_REAL, offsetof(boundary_config, submergence), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "m",
     "a submerged inflow under a gate (a reservoir fed from below its surface): the depth of "
     "water standing above the inflow's top, which sets the lattice's hydrostatic density; "
     "0: the inflow has a free surface",
     NULL, 0},
    {"velocity", SLUICE_PARAM_REAL, offsetof(boundary_config, velocity), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL | SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m s^-1",
     "inflow velocity V1 (give this or discharge)", NULL, 0},
    {"discharge", SLUICE_PARAM_REAL, offsetof(boundary_config, discharge), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL | SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m^2 s^-1",
     "discharge per unit width q = V1 d1 (give this or velocity)", NULL, 0},
    {"width", SLUICE_PARAM_REAL, offsetof(boundary_config, width), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "m",
     "buffer length along x (0: the kernel support 2h rounded up to whole spacings)", NULL, 0},
    {"span", SLUICE_PARAM_VECTOR, offsetof(boundary_config, span), "[0, 0]", 0, 0, 0, "m",
     "3D: the lateral (y) extent [y_min, y_max] of the inflow", NULL, 2},
    {"turbulence_intensity", SLUICE_PARAM_REAL, offsetof(boundary_config, turbulence_intensity),
     "0.1", 0, 1, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "with k-epsilon: k = 1.5 (I V1)^2 at the inflow (seed 004: 10 %)", NULL, 0},
    {"mixing_length_factor", SLUICE_PARAM_REAL,
     offsetof(boundary_config, mixing_length_factor), "0.5", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "1",
     "with k-epsilon: eps = c_mu^(3/4) k^(3/2) / (factor d1) (seed 004: 0.5)", NULL, 0},
    {"interval", SLUICE_PARAM_REAL, offsetof(boundary_config, interval), "0.05", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between flux rows", NULL, 0},
    {"backflow", SLUICE_PARAM_ENUM, offsetof(boundary_config, backflow), "leave", 0, 0, 0, NULL,
     "fluid flowing back upstream across the plane within the inflow's section. leave: it "
     "leaves through the inlet, a negative flux (an open channel's reverse flow); hold: it "
     "stays on the plane with the inflow velocity V1 along x, so the inlet delivers q whatever "
     "the water downstream does (a discharge-controlled feed, such as the pump under a "
     "reservoir, whose slow V1 the reservoir's sloshing would otherwise reverse)",
     "leave|hold", 0},
    {"file", SLUICE_PARAM_STRING, offsetof(boundary_config, file), "inlet.csv", 0, 0, 0, NULL,
     "flux time series in the run directory", NULL, 0},
};

static const sluice_param_spec outlet_params[] = {
    {"form", SLUICE_PARAM_ENUM, offsetof(boundary_config, form), "free", 0, 0, 0, NULL,
     "free: removed past the plane (seed 002); frozen: state frozen, moves on, removed `width` "
     "later (seed 000); buffer: tailwater velocity and depth imposed over `width` (seed 004)",
     "free|frozen|buffer", 0},
    {"position", SLUICE_PARAM_REAL, offsetof(boundary_config, position), NULL, 0, 0, 0, "m",
     "x of the outlet plane", NULL, 0},
    {"bed", SLUICE_PARAM_REAL, offsetof(boundary_config, bed), "0", 0, 0, 0, "m",
     "buffer: elevation of the bed under the outlet", NULL, 0},
    {"depth", SLUICE_PARAM_REAL, offsetof(boundary_config, depth), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "m", "buffer: tailwater depth yt", NULL, 0},
    {"velocity", SLUICE_PARAM_REAL, offsetof(boundary_config, velocity), "0", 0, 0, 0,
     "m s^-1", "buffer: tailwater velocity Vt", NULL, 0},
    {"width", SLUICE_PARAM_REAL, offsetof(boundary_config, width), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "m",
     "frozen, buffer: length of the outlet layer (0: the kernel support rounded up to whole "
     "spacings)",
     NULL, 0},
    {"span", SLUICE_PARAM_VECTOR, offsetof(boundary_config, span), "[0, 0]", 0, 0, 0, "m",
     "buffer, 3D: the lateral (y) extent [y_min, y_max] of the tailwater layer", NULL, 2},
    {"tailwater", SLUICE_PARAM_ENUM, offsetof(boundary_config, tailwater), "imposed", 0, 0, 0,
     NULL,
     "buffer: imposed: the velocity Vt and the depth yt's hydrostatic density are imposed in the "
     "layer; controlled: the layer's velocity is adjusted (a tailgate) until the water depth at "
     "control_position, upstream, is yt, starting from Vt",
     "imposed|controlled", 0},
    {"control_position", SLUICE_PARAM_REAL, offsetof(boundary_config, control_position), "0", 0,
     0, 0, "m",
     "controlled tailwater: x of the section where the depth is held at yt (upstream of the "
     "plane, downstream of the jump: where an experiment measures its tailwater)",
     NULL, 0},
    {"control_time", SLUICE_PARAM_REAL, offsetof(boundary_config, control_time), "2", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "s",
     "controlled tailwater: integral time of the controller (the depth is averaged over a "
     "quarter of it); longer than the reach's gravity-wave travel time",
     NULL, 0},
    {"phase", SLUICE_PARAM_ENUM, offsetof(boundary_config, phase), "all", 0, 0, 0, NULL,
     "the phase that crosses into the outlet's treatment (removed, frozen or imposed): all, or "
     "water or air only (field 'phase' of two_phase, which must then be loaded); the other "
     "phase stays ordinary fluid past the plane",
     "all|water|air", 0},
    {"interval", SLUICE_PARAM_REAL, offsetof(boundary_config, interval), "0.05", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between flux rows", NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(boundary_config, file), "outlet.csv", 0, 0, 0, NULL,
     "flux time series in the run directory", NULL, 0},
};

static const sluice_param_spec vent_params[] = {
    {"box_min", SLUICE_PARAM_VECTOR, offsetof(boundary_config, box_min), NULL, 0, 0, 0, "m",
     "lower corner of the vent's box (in the air, against the box's walls)", NULL,
     SLUICE_LENGTH_DIM},
    {"box_max", SLUICE_PARAM_VECTOR, offsetof(boundary_config, box_max), NULL, 0, 0, 0, "m",
     "upper corner of the vent's box", NULL, SLUICE_LENGTH_DIM},
    {"response_time", SLUICE_PARAM_REAL, offsetof(boundary_config, response_time), "0.05", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "s",
     "time over which the air's mean pressure is averaged before the vent lets air out "
     "(longer than the air box's acoustic period, length / c0_air)",
     NULL, 0},
    {"interval", SLUICE_PARAM_REAL, offsetof(boundary_config, interval), "0.05", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between rows", NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(boundary_config, file), "air_vent.csv", 0, 0, 0, NULL,
     "air outflow time series in the run directory", NULL, 0},
};

static const sluice_field_spec boundary_fields[] = {
    SLUICE_SPEC_VELOCITY_DOC(SLUICE_READ, "velocity (imposed on open particles)"),
    SLUICE_SPEC_DENSITY_DOC(SLUICE_READ, "density (imposed on open particles)"),
    SLUICE_SPEC_MASS(SLUICE_READ),
};

static int boundary_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state, int inlet)
{
    const boundary_config *c = config;
    boundary_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->inlet = inlet;
    s->form = c->form;
    sluice_real value;
    if (sluice_util_constant(api, host, "dimensions", &value) != SLUICE_OK)
        goto fail;
    s->dims = (uint32_t)value;
    s->vertical = s->dims - 1;
    s->position = c->position;
    s->bed = c->bed;
    s->depth = c->depth;
    s->width = c->width;
    s->table_rows = sluice_schedule_every(c->interval);
    s->file = c->file;
    s->span[0] = c->span[0];
    s->span[1] = c->span[1];
    if (inlet) {
        const int has_velocity = c->velocity > 0, has_discharge = c->discharge > 0;
        if (has_velocity == has_discharge) {
            api->messages->error(host, "give exactly one of 'velocity' (V1, m/s) and 'discharge' (q, m^2/s)");
            goto fail;
        }
        s->velocity = has_velocity ? c->velocity : c->discharge / c->depth;
        if (s->dims == 3 && !(c->span[1] > c->span[0])) {
            api->messages->error(host, "a 3D inlet needs 'span: [y_min, y_max]' with y_max > y_min");
            goto fail;
        }
        s->air_depth = c->air_depth;
        s->submergence = c->submergence;
        s->backflow = c->backflow;
        if (s->submergence > 0 && s->air_depth > 0) {
            api->messages->error(host, "give submergence (water above a gated inflow) or air_depth (air "
                             "above a free inflow), not both");
            goto fail;
        }
        s->turbulence_k = 1.5 * pow(c->turbulence_intensity * s->velocity, 2);
        s->mixing_length = c->mixing_length_factor * s->depth;
        sluice_real x = c->position;
        if (api->fields->publish_constant(host, "inlet_position", &x, 1, "m") != SLUICE_OK)
            goto fail;
    } else {
        s->velocity = c->velocity;
        s->phase_filter = c->phase;
        sluice_real x = c->position;
        if (api->fields->publish_constant(host, "outlet_position", &x, 1, "m") != SLUICE_OK)
            goto fail;
        /* a filter reads the phase: a scene without two_phase is refused by
         * the core (the field 'phase' is computed by no loaded plugin) */
        if (sluice_phase_declare(api, host, s->phase_filter) != SLUICE_OK)
            goto fail;
        if (s->form == OUTLET_BUFFER && !(c->depth > 0)) {
            api->messages->error(host, "form 'buffer' needs the tailwater 'depth' (yt, m) > 0");
            goto fail;
        }
        if (s->form == OUTLET_BUFFER && s->dims == 3 && !(c->span[1] > c->span[0])) {
            api->messages->error(host, "a 3D buffer outlet needs 'span: [y_min, y_max]' with y_max > y_min");
            goto fail;
        }
        if (c->tailwater == TAILWATER_CONTROLLED) {
            if (s->form != OUTLET_BUFFER) {
                api->messages->error(host, "tailwater: controlled needs form: buffer (the layer whose "
                                 "velocity is adjusted)");
                goto fail;
            }
            if (!(c->control_position < c->position)) {
                api->messages->error(host,
                           "control_position x = %g m must lie upstream of the outlet plane "
                           "(position x = %g m)",
                           (double)c->control_position, (double)c->position);
                goto fail;
            }
            if (!(c->velocity > 0)) {
                api->messages->error(host, "tailwater: controlled starts from the tailwater velocity Vt: "
                                 "give 'velocity' > 0");
                goto fail;
            }
            s->controlled = 1;
            s->control_position = c->control_position;
            s->control_time = c->control_time;
            s->velocity_integral = c->velocity;
        }
    }
    /* with two_phase loaded (its phase is a static field), the inlet writes
     * the phase on the particles it creates, between steps, and an outlet
     * that does not filter reads it (a filter declared it above already) */
    sluice_field phase;
    if ((inlet || s->phase_filter == SLUICE_PHASE_ALL) &&
        sluice_util_optional_field(api, host, "phase", &phase)) {
        static const sluice_field_spec spec = {
            "phase", SLUICE_TYPE_UINT8, 1, "1", SLUICE_READ, 0, NULL, 0,
            "phase of a fluid particle: 0 water, 1 air (set on the inflow particles)"};
        if (api->fields->declare_field(host, &spec) != SLUICE_OK)
            goto fail;
    }
    *state = s;
    return SLUICE_OK;
fail:
    free(s);
    return SLUICE_ERROR;
}

static int inlet_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    return boundary_create(api, host, config, state, 1);
}

static int outlet_create(const sluice_api *api, sluice_host *host, const void *config,
                         void **state)
{
    return boundary_create(api, host, config, state, 0);
}

static void boundary_destroy(void *state)
{
    boundary_state *s = state;
    if (!s)
        return;
    free(s->column_density);
    free(s->scratch);
    free(s->to_convert);
    free(s->to_remove);
    free(s);
}

/* The density of the hydrostatic pressure p = surface + rho0 g depth_below
 * (depth_below in m, clamped at 0) through the scene's equation of state
 * (in a two-phase scene: the water's). */
static int hydrostatic_density(boundary_state *s, sluice_host *host, sluice_index n,
                               const double *depth_below, double surface, double *density)
{
    for (sluice_index k = 0; k < n; k++) {
        sluice_real p = (sluice_real)(surface + s->rho0 * s->g * fmax(depth_below[k], 0.0));
        sluice_real rho;
        if (s->api->evaluation->density_from_pressure(host, 1, &p, &rho) != SLUICE_OK)
            return SLUICE_ERROR;
        density[k] = rho;
    }
    return SLUICE_OK;
}

/* The air's density at the pressure p_b + excess: the inverse of two_phase's
 * law for the air, rho_a = rho0_a ((p - p_b) / B + 1)^(1 / gamma_a). */
static double air_density(const boundary_state *s, double excess)
{
    return s->rho_a * pow(1 + excess / s->B, 1 / s->gamma_a);
}

/* The phase, and the air's law from two_phase's constants when the
 * boundary creates or imposes air (`needs_air`: the reason, or NULL). */
static int bind_phase(boundary_state *s, sluice_host *host, const char *needs_air)
{
    const sluice_api *api = s->api;
    sluice_field phase;
    s->has_phase = sluice_util_optional_field(api, host, "phase", &phase);
    if (!s->has_phase)
        return SLUICE_OK;
    if (phase.type != SLUICE_TYPE_UINT8 || phase.components != 1) {
        api->messages->error(host, "the field 'phase' must be uint8 with one component (0 water, 1 air)");
        return SLUICE_ERROR;
    }
    /* (declared in create() when two_phase is loaded) */
    if (api->fields->field(host, "phase", &s->phase_field) != SLUICE_OK)
        return SLUICE_ERROR;
    if (!needs_air)
        return SLUICE_OK;
    sluice_real rho_a, c_a, gamma_a;
    if (api->fields->constant(host, "air_rest_density", &rho_a, 1) < 1 ||
        api->fields->constant(host, "air_speed_of_sound", &c_a, 1) < 1 ||
        api->fields->constant(host, "air_gamma", &gamma_a, 1) < 1) {
        api->messages->error(host, "%s needs the air's equation of state: the constants "
                         "'air_rest_density', 'air_speed_of_sound' and 'air_gamma' of two_phase",
                   needs_air);
        return SLUICE_ERROR;
    }
    s->rho_a = rho_a;
    s->gamma_a = gamma_a;
    s->B = (double)rho_a * (double)c_a * (double)c_a / (double)gamma_a;
    s->air_mass = (double)(rho_a * (sluice_real)pow((double)s->dx, (double)s->dims));
    return SLUICE_OK;
}

static int boundary_bind(void *state, sluice_host *host)
{
    boundary_state *s = state;
    const sluice_api *api = s->api;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity_field}, {"density", &s->density_field}, {"mass", &s->mass_field}};
    if (sluice_util_bind(api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    s->has_pressure = sluice_util_optional_field(api, host, "pressure", &s->pressure_field);
    sluice_real value, vec[3] = {0, 0, 0};
    if (sluice_util_constant(api, host, "spacing", &value) != SLUICE_OK)
        return SLUICE_ERROR;
    s->dx = value;
    if (sluice_util_constant(api, host, "rest_density", &value) != SLUICE_OK)
        return SLUICE_ERROR;
    s->rho0 = value;
    sluice_real h, support_ratio;
    if (sluice_util_constant(api, host, "smoothing_length", &h) != SLUICE_OK ||
        sluice_util_constant(api, host, "kernel_support", &support_ratio) != SLUICE_OK)
        return SLUICE_ERROR;
    if (!(s->width > 0))
        s->width = ceil((double)(support_ratio * h) / s->dx - 1e-9) * s->dx;
    if (api->fields->constant(host, "gravity", vec, 3) == 0) {
        api->messages->error(host, "needs gravity (the hydrostatic state of its open particles): load "
                         "`gravity`");
        return SLUICE_ERROR;
    }
    s->g = fabs((double)vec[s->vertical]);
    s->p_ref = 0;
    if (api->fields->constant(host, "reference_pressure", &value, 1) == 1)
        s->p_ref = value;
    if (api->evaluation->density_from_pressure(host, 0, NULL, NULL) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    api->fields->constant(host, "domain_min", lo, 3);
    api->fields->constant(host, "domain_max", hi, 3);
    for (int d = 0; d < 3; d++) {
        s->domain_min[d] = lo[d];
        s->domain_max[d] = hi[d];
    }
    const char *needs_air = NULL;
    if (s->vent)
        needs_air = "air_vent";
    else if (s->inlet && s->air_depth > 0)
        needs_air = "air_depth";
    else if (!s->inlet && s->form == OUTLET_BUFFER && s->phase_filter != SLUICE_PHASE_WATER)
        needs_air = "a buffer outlet that takes air (phase: all or air)";
    if (bind_phase(s, host, needs_air) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->vent) {
        /* the inlet moves every open particle upstream of its plane, the
         * outlet every one downstream of its own: the vent lies between */
        sluice_real x_in, x_out;
        if (api->fields->constant(host, "inlet_position", &x_in, 1) == 1 && s->box_min[0] < x_in) {
            api->messages->error(host, "the vent's box (x from %g m) reaches upstream of the inlet's plane "
                             "(x = %g m): move it downstream",
                       s->box_min[0], (double)x_in);
            return SLUICE_ERROR;
        }
        if (api->fields->constant(host, "outlet_position", &x_out, 1) == 1 && s->box_max[0] > x_out) {
            api->messages->error(host, "the vent's box (x up to %g m) reaches downstream of the outlet's "
                             "plane (x = %g m): move it upstream",
                       s->box_max[0], (double)x_out);
            return SLUICE_ERROR;
        }
        return SLUICE_OK;
    }
    if (s->inlet) {
        if (s->air_depth > 0 && !s->has_phase) {
            api->messages->error(host,
                       "air_depth = %g m needs the field 'phase' (0 water, 1 air) of the "
                       "two_phase plugin: load two_phase, or set air_depth: 0",
                       s->air_depth);
            return SLUICE_ERROR;
        }
        /* the inflow's section must lie inside the domain: its plane, the
         * column bed .. bed + d1 (+ the air layer) and, in 3D, the span */
        const int v = (int)s->vertical;
        const double top = s->bed + s->depth + s->air_depth;
        if (!(s->position >= s->domain_min[0] && s->position < s->domain_max[0]) ||
            !(s->bed >= s->domain_min[v] && top <= s->domain_max[v]) ||
            (s->dims == 3 &&
             !(s->span[0] >= s->domain_min[1] && s->span[1] <= s->domain_max[1]))) {
            api->messages->error(host,
                       "the inflow section (x = %g m, %c from %g to %g m%s) lies outside the "
                       "domain [%g, %g) x [%g, %g) m: move the inlet or enlarge the domain",
                       s->position, "xyz"[v], s->bed, top,
                       s->dims == 3 ? ", across the span" : "", s->domain_min[0],
                       s->domain_max[0], s->domain_min[v], s->domain_max[v]);
            return SLUICE_ERROR;
        }
        if (s->position - s->width < s->domain_min[0] && s->form == INLET_BUFFER) {
            api->messages->error(host,
                       "the inlet buffer [%g, %g) m reaches below domain.min x = %g m: move the "
                       "inlet downstream or enlarge the domain",
                       s->position - s->width, s->position, s->domain_min[0]);
            return SLUICE_ERROR;
        }
        s->has_k = sluice_util_optional_field(api, host, "turbulent_kinetic_energy", &s->k_field) &&
                   sluice_util_optional_field(api, host, "turbulent_dissipation_rate",
                                              &s->epsilon_field);
        if (s->has_k) {
            /* the standard model's c_mu (seed 004) */
            const double c_mu = 0.09;
            s->turbulence_epsilon = pow(c_mu, 0.75) * pow(s->turbulence_k, 1.5) / s->mixing_length;
        }
    } else {
        sluice_real x_in;
        if (api->fields->constant(host, "inlet_position", &x_in, 1) == 1 && !(x_in < s->position)) {
            api->messages->error(host, "the outlet (x = %g m) must lie downstream of the inlet (x = %g m)",
                       s->position, (double)x_in);
            return SLUICE_ERROR;
        }
        const double reach = s->position + (s->form == OUTLET_FREE ? 0 : s->width) + s->dx;
        if (reach > s->domain_max[0]) {
            api->messages->error(host,
                       "the outlet (x = %g m, layer %g m) needs the domain to reach x = %g m "
                       "(domain.max x = %g m): fluid past it would leave the domain first",
                       s->position, s->form == OUTLET_FREE ? 0 : s->width, reach,
                       s->domain_max[0]);
            return SLUICE_ERROR;
        }
    }
    return SLUICE_OK;
}

static int reserve(boundary_state *s, sluice_host *host, sluice_index n)
{
    if (n <= s->capacity)
        return SLUICE_OK;
    sluice_index cap = n + n / 2 + 64;
    sluice_index *a = realloc(s->to_convert, (size_t)cap * sizeof *a);
    if (a)
        s->to_convert = a;
    sluice_index *b = a ? realloc(s->to_remove, (size_t)cap * sizeof *b) : NULL;
    if (b)
        s->to_remove = b;
    if (!a || !b) {
        s->api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    s->capacity = cap;
    return SLUICE_OK;
}

/* ---------------------------------------------------------------- inlet -- */

/* Sets the imposed state (velocity, hydrostatic density by row, k and eps;
 * in a two-phase scene the phase, and the air rows' mass rho0_a dx^d) of
 * lattice particles [first, first + n). */
static void impose_lattice_state(boundary_state *s, const sluice_view *v, sluice_index first,
                          sluice_index n)
{
    sluice_real *rho = sluice_real_column(v, s->density_field, 0);
    sluice_real *mass = sluice_real_column(v, s->mass_field, 0);
    uint8_t *phase = s->has_phase ? (uint8_t *)v->columns[s->phase_field.column] : NULL;
    const sluice_real *z = v->position[s->vertical];
    const uint32_t rows = s->rows + s->air_rows;
    for (sluice_index i = first; i < first + n; i++) {
        for (uint32_t d = 0; d < s->dims; d++)
            sluice_real_column(v, s->velocity_field, d)[i] = d == 0 ? (sluice_real)s->velocity : 0;
        uint32_t row = (uint32_t)floor(((double)z[i] - s->bed) / s->dx);
        row = row < rows ? row : rows - 1;
        rho[i] = (sluice_real)s->column_density[row];
        if (phase) {
            const int air = row >= s->rows;
            phase[i] = (uint8_t)air;
            if (air)
                mass[i] = (sluice_real)s->air_mass;
        }
        if (s->has_k) {
            sluice_real_column(v, s->k_field, 0)[i] = (sluice_real)s->turbulence_k;
            sluice_real_column(v, s->epsilon_field, 0)[i] = (sluice_real)s->turbulence_epsilon;
        }
    }
}

/* Adds one column of inflow particles at x. */
static int add_column(boundary_state *s, sluice_host *host, double x)
{
    const uint32_t rows = s->rows + s->air_rows;
    const sluice_index n = rows * s->lanes;
    for (uint32_t l = 0; l < s->lanes; l++)
        for (uint32_t r = 0; r < rows; r++) {
            sluice_real *p = s->scratch + 3 * ((size_t)l * rows + r);
            p[0] = (sluice_real)x;
            p[1] = p[2] = 0;
            p[s->vertical] = (sluice_real)(s->bed + (r + 0.5) * s->dx);
            if (s->dims == 3)
                p[1] = (sluice_real)(s->span[0] + (l + 0.5) * s->dx);
        }
    sluice_index first;
    if (s->api->particles->add_particles(host, SLUICE_KIND_OPEN, s->scratch, n, &first) != SLUICE_OK)
        return SLUICE_ERROR;
    impose_lattice_state(s, s->api->particles->view(host), first, n);
    return SLUICE_OK;
}

/* The lattice of a buffer: rows of water up to the depth (and of air up to
 * depth + air_depth), lanes across the span (3D), the hydrostatic density of
 * each row: water p = p_b + rho0_a g air_depth + rho0 g (depth - z'), air
 * p = p_b + rho0_a g (depth + air_depth - z'), z' the height above the
 * bed, each through its phase's law. */
/* Units and descriptions of an inlet's or outlet's table (per metre of
 * span in 2D), after table_open. */
static int describe_flux_columns(boundary_state *s)
{
    if (!s->table)
        return SLUICE_ERROR;
    const int plane = s->dims == 2;
    const sluice_column_doc columns[] = {
        {"s", "simulated time"},
        {plane ? "kg s^-1 m^-1" : "kg s^-1",
         "mass flux through the boundary's plane, averaged over the interval"},
        {plane ? "m^2 s^-1" : "m^3 s^-1", "discharge through the plane, mass flux / rho0"},
        {plane ? "N m^-1" : "N", "x-momentum flux through the plane"},
        {plane ? "kg m^-1" : "kg", "mass through the plane since the start"},
        {"1", "open particles in the boundary's buffer"},
        {"m s^-1", "velocity imposed on the outlet's buffer layer (controlled tailwater)"},
        {"m", "filtered water depth at the control section (controlled tailwater)"},
    };
    return sluice_util_describe_columns(s->api, s->table, 0, columns, s->controlled ? 8 : 6);
}

static int setup_lattice(boundary_state *s, sluice_host *host)
{
    const sluice_api *api = s->api;
    s->rows = (uint32_t)floor(s->depth / s->dx + 0.5);
    if (s->rows < 1) {
        api->messages->error(host, "the depth %g m is less than half a particle spacing (%g m)", s->depth,
                   s->dx);
        return SLUICE_ERROR;
    }
    s->air_rows = 0;
    if (s->air_depth > 0) {
        const uint32_t total = (uint32_t)floor((s->depth + s->air_depth) / s->dx + 0.5);
        if (total <= s->rows) {
            api->messages->error(host,
                       "air_depth = %g m adds no row of air above the %u rows of water (spacing "
                       "%g m): give at least half a spacing more",
                       s->air_depth, s->rows, s->dx);
            return SLUICE_ERROR;
        }
        s->air_rows = total - s->rows;
    }
    const uint32_t rows = s->rows + s->air_rows;
    s->lanes = 1;
    if (s->dims == 3) {
        s->lanes = (uint32_t)floor((s->span[1] - s->span[0]) / s->dx + 0.5);
        if (s->lanes < 1) {
            api->messages->error(host, "the span is narrower than a particle spacing");
            return SLUICE_ERROR;
        }
    }
    s->column_density = malloc(rows * sizeof *s->column_density);
    double *below = malloc(s->rows * sizeof *below);
    s->scratch = malloc((size_t)rows * s->lanes * 3 * sizeof *s->scratch);
    if (!s->column_density || !below || !s->scratch) {
        free(below);
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    for (uint32_t r = 0; r < s->rows; r++)
        below[r] = s->depth + s->submergence - (r + 0.5) * s->dx;
    /* the air layer's weight on the water (rho0_a g air_depth: p_b at its top) */
    const double air_weight = s->air_rows ? s->rho_a * s->g * s->air_depth : 0;
    int status = hydrostatic_density(s, host, s->rows, below, s->p_ref + air_weight,
                                     s->column_density);
    free(below);
    for (uint32_t r = s->rows; r < rows; r++)
        s->column_density[r] =
            air_density(s, s->rho_a * s->g * fmax(s->depth + s->air_depth - (r + 0.5) * s->dx, 0));
    return status;
}

static int inlet_initialise(void *state, sluice_host *host)
{
    boundary_state *s = state;
    const sluice_api *api = s->api;
    if (setup_lattice(s, host) != SLUICE_OK)
        return SLUICE_ERROR;
    const double effective = s->rows * s->dx;
    if (fabs(effective - s->depth) > 1e-6 * s->depth)
        api->messages->warning(host,
                     "the inflow depth %g m is not a whole number of spacings: %u rows carry "
                     "%g m (discharge %g m^2/s instead of %g)",
                     s->depth, s->rows, effective, s->velocity * effective,
                     s->velocity * s->depth);
    const double air_effective = s->air_rows * s->dx;
    if (s->air_rows && fabs(effective + air_effective - s->depth - s->air_depth) >
                           1e-6 * (s->depth + s->air_depth))
        api->messages->warning(host,
                     "depth + air_depth = %g m is not a whole number of spacings: the %u rows of "
                     "air reach %g m above the bed",
                     s->depth + s->air_depth, s->air_rows, effective + air_effective);
    double length = s->width;
    if (s->form == INLET_BLOCK) {
        sluice_real end;
        if (sluice_util_constant(api, host, "end_time", &end) != SLUICE_OK)
            return SLUICE_ERROR;
        length = ceil(((double)end * s->velocity + s->width) / s->dx) * s->dx;
        if (s->position - length < s->domain_min[0]) {
            api->messages->error(host,
                       "the inflow block for %g s is %g m long and reaches x = %g m, below "
                       "domain.min x = %g m: enlarge the domain (seed 000 placed the whole "
                       "inflow upstream of the inlet)",
                       (double)end, length, s->position - length, s->domain_min[0]);
            return SLUICE_ERROR;
        }
    }
    const uint32_t columns = (uint32_t)floor(length / s->dx + 0.5);
    for (uint32_t m = 0; m < columns; m++)
        if (add_column(s, host, s->position - length + (m + 0.5) * s->dx) != SLUICE_OK)
            return SLUICE_ERROR;
    s->newest_column = s->position - length + 0.5 * s->dx;
    s->open_count = columns * (s->rows + s->air_rows) * s->lanes;
    api->messages->info(host,
              "%s inflow: V1 = %g m/s, d1 = %g m (%u rows), q = %g m^2/s, Fr1 = %g; %u columns "
              "upstream of x = %g m",
              s->form == INLET_BUFFER ? "buffer" : "block", s->velocity, effective, s->rows,
              s->velocity * effective, s->velocity / sqrt(s->g * effective), columns,
              s->position);
    if (s->air_rows)
        api->messages->info(host,
                  "air layer: %u rows (%g m) above the water, densities %.9g (bottom) to %.9g "
                  "(top) kg m^-3",
                  s->air_rows, air_effective, s->column_density[s->rows],
                  s->column_density[s->rows + s->air_rows - 1]);
    s->table = api->output->table_open(host, s->file,
                               "time,mass_flux,discharge,momentum_flux,mass_total,open_particles");
    return describe_flux_columns(s);
}

static int write_flux_row(boundary_state *s, double time)
{
    const double span = time - s->row_time;
    double row[8] = {time,
                     span > 0 ? s->mass_interval / span : 0,
                     span > 0 ? s->mass_interval / span / s->rho0 : 0,
                     span > 0 ? s->momentum_interval / span : 0,
                     s->mass_total,
                     (double)s->open_count,
                     s->velocity,
                     s->control_started ? s->control_depth : s->depth};
    if (s->api->output->table_row(s->table, row, s->controlled ? 8 : 6) != SLUICE_OK)
        return SLUICE_ERROR;
    s->mass_interval = s->momentum_interval = 0;
    s->row_time = time;
    return SLUICE_OK;
}

static int vent_row(boundary_state *s, sluice_host *host, const sluice_view *v, double time);

/* A row of the boundary's table: the fluxes, or the vent's row. */
static int write_row(boundary_state *s, sluice_host *host, double time)
{
    return s->vent ? vent_row(s, host, s->api->particles->view(host), time) : write_flux_row(s, time);
}

/* Rows at multiples of the interval (the first at t = 0: zero flux). */
static int flux_rows(boundary_state *s, sluice_host *host, double time)
{
    if (!sluice_schedule_due(&s->table_rows, time))
        return SLUICE_OK;
    if (write_row(s, host, time) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->table_rows, s->api, host, time);
    return SLUICE_OK;
}

/* This step's water mass and x-momentum through the plane and the open
 * particles, over the ranks (each rank counts its own particles; the
 * identity on one rank), into the interval's sums: alike on every rank. */
static int add_step(boundary_state *s, sluice_host *host, double mass, double momentum,
                    sluice_index open)
{
    double sums[3] = {mass, momentum, (double)open};
    if (s->api->ranks->reduce(host, sums, 3, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    s->mass_interval += sums[0];
    s->momentum_interval += sums[1];
    s->mass_total += sums[0];
    s->open_count = (sluice_index)sums[2];
    return SLUICE_OK;
}

static int inlet_after_step(void *state, sluice_host *host)
{
    boundary_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    const double dt = v->time - s->last_time;
    s->last_time = v->time;
    if (reserve(s, host, v->count) != SLUICE_OK)
        return SLUICE_ERROR;
    /* move the inflow particles; those past the plane become fluid */
    sluice_real *x = (sluice_real *)v->position[0];
    const sluice_real *mass = sluice_real_column(v, s->mass_field, 0);
    const uint8_t *phase = s->has_phase ? (const uint8_t *)v->columns[s->phase_field.column] : NULL;
    const sluice_real shift = (sluice_real)(s->velocity * dt);
    const sluice_real plane = (sluice_real)s->position;
    sluice_index converted = 0, open = 0, returned = 0;
    double step_mass = 0, step_momentum = 0;
    const sluice_real section_top = (sluice_real)(s->bed + (s->rows + s->air_rows) * s->dx);
    const sluice_real half_dx = (sluice_real)(0.5 * s->dx);
    for (sluice_index i = 0; i < v->count; i++) {
        if (!(x[i] < plane))
            continue;
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            /* fluid flowing back upstream across the plane within the
             * inflow's section (a reservoir's sloshing) would run into the
             * lattice: it leaves through the inlet, a negative flux. Above
             * the section it leaves once dx/2 upstream: less is fluid
             * touching a gate's face, which dbc lets it do. */
            const int in_section = v->position[s->vertical][i] < section_top;
            if (!in_section && !(x[i] < plane - half_dx))
                continue;
            if (in_section && s->backflow == BACKFLOW_HOLD) {
                if (!s->velocity_previous_known) {
                    s->has_velocity_previous = sluice_util_optional_field(
                        api, host, "velocity_previous", &s->velocity_previous_field);
                    s->velocity_previous_known = 1;
                }
                /* a discharge-controlled feed takes nothing back: the
                 * particle stays on the plane, moving at V1 (and so does
                 * the integrator's v^(n-1), or the next leapfrog step
                 * would bring the reversed velocity back) */
                x[i] = plane;
                sluice_real_column(v, s->velocity_field, 0)[i] = (sluice_real)s->velocity;
                if (s->has_velocity_previous)
                    sluice_real_column(v, s->velocity_previous_field, 0)[i] =
                        (sluice_real)s->velocity;
                continue;
            }
            s->to_remove[returned++] = i;
            if (phase && phase[i])
                continue;
            const sluice_real *u = sluice_real_column(v, s->velocity_field, 0);
            step_mass -= mass[i];
            step_momentum -= mass[i] * u[i];
            continue;
        }
        if (v->kind[i] != SLUICE_KIND_OPEN)
            continue;
        x[i] += shift;
        if (x[i] >= plane) {
            s->to_convert[converted++] = i;
            if (phase && phase[i])
                continue; /* the fluxes are the water's */
            step_mass += mass[i];
            step_momentum += mass[i] * s->velocity;
        } else {
            open++;
        }
    }
    if (api->particles->set_kind(host, s->to_convert, converted, SLUICE_KIND_FLUID) != SLUICE_OK)
        return SLUICE_ERROR;
    if (returned && api->particles->remove_particles(host, s->to_remove, returned) != SLUICE_OK)
        return SLUICE_ERROR;
    if (add_step(s, host, step_mass, step_momentum, open) != SLUICE_OK)
        return SLUICE_ERROR;
    s->newest_column += s->velocity * dt;
    if (s->form == INLET_BUFFER) {
        const double back = s->position - s->width;
        while (s->newest_column - s->dx >= back - 1e-9 * s->dx) {
            s->newest_column -= s->dx;
            /* across ranks the rank that owns the column's place adds it */
            const sluice_real where[3] = {(sluice_real)s->newest_column, (sluice_real)s->bed,
                                          (sluice_real)s->span[0]};
            if (api->ranks->owns(host, where) && add_column(s, host, s->newest_column) != SLUICE_OK)
                return SLUICE_ERROR;
            s->open_count += (s->rows + s->air_rows) * s->lanes;
        }
    }
    return flux_rows(s, host, v->time);
}

/* --------------------------------------------------------------- outlet -- */

static int outlet_initialise(void *state, sluice_host *host)
{
    boundary_state *s = state;
    if (s->controlled) {
        /* the control section: a strip four spacings wide, within the domain */
        s->control_strip = 4 * s->dx;
        if (s->control_position - 0.5 * s->control_strip < s->domain_min[0]) {
            s->api->messages->error(host, "control_position x = %g m lies outside the domain (x from %g m)",
                          s->control_position, s->domain_min[0]);
            return SLUICE_ERROR;
        }
    }
    if (s->form == OUTLET_BUFFER) {
        /* the tailwater layer exists from the start, so that the fluid
         * reaching the outlet meets its imposed state, not a free end */
        if (setup_lattice(s, host) != SLUICE_OK)
            return SLUICE_ERROR;
        const uint32_t columns = (uint32_t)floor(s->width / s->dx + 0.5);
        for (uint32_t m = 0; m < columns; m++)
            if (add_column(s, host, s->position + (m + 0.5) * s->dx) != SLUICE_OK)
                return SLUICE_ERROR;
        s->open_count = columns * s->rows * s->lanes;
    }
    s->table = s->api->output->table_open(
        host, s->file,
        s->controlled ? "time,mass_flux,discharge,momentum_flux,mass_total,open_particles,"
                        "imposed_velocity,control_depth"
                      : "time,mass_flux,discharge,momentum_flux,mass_total,open_particles");
    return describe_flux_columns(s);
}

/* A controlled tailwater (a tailgate): the water depth at the control
 * section, d = sum m_i / (rho0 w) over the water in a strip w = 4 dx wide
 * (times the span in 3D) centred on control_position, is averaged
 * exponentially over control_time / 4; the layer's velocity is
 *     V = V_I (1 + e),  dV_I/dt = V_I e / control_time,  e = (d - yt) / yt
 * (proportional-integral: deeper water than yt opens the gate). At rest
 * (e = 0) the outflow V d_plane equals the inflow and the depth at the
 * section is yt. The sums are over every rank, so V is the same on all. */
static int control_tailwater(boundary_state *s, sluice_host *host, const sluice_view *v,
                             double dt)
{
    const sluice_real *mass = sluice_real_column(v, s->mass_field, 0);
    const uint8_t *phase = s->has_phase ? (const uint8_t *)v->columns[s->phase_field.column] : NULL;
    const double lo = s->control_position - 0.5 * s->control_strip,
                 hi = s->control_position + 0.5 * s->control_strip;
    double sum = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const double x = (double)v->position[0][i];
        if (v->kind[i] == SLUICE_KIND_FLUID && x >= lo && x < hi && !(phase && phase[i]))
            sum += (double)mass[i];
    }
    if (s->api->ranks->reduce(host, &sum, 1, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    const double lateral = s->dims == 3 ? s->span[1] - s->span[0] : 1.0;
    const double depth = sum / (s->rho0 * s->control_strip * lateral);
    if (!s->control_started) {
        s->control_depth = depth;
        s->control_started = 1;
    } else {
        s->control_depth += (depth - s->control_depth) * fmin(1.0, 4 * dt / s->control_time);
    }
    double e = (s->control_depth - s->depth) / s->depth;
    e = fmax(-0.5, fmin(0.5, e));
    s->velocity_integral *= 1 + e * fmin(1.0, dt / s->control_time);
    s->velocity = s->velocity_integral * (1 + e);
    return SLUICE_OK;
}

static int outlet_after_step(void *state, sluice_host *host)
{
    boundary_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    const double dt = v->time - s->last_time;
    s->last_time = v->time;
    if (reserve(s, host, v->count) != SLUICE_OK)
        return SLUICE_ERROR;
    const sluice_real plane = (sluice_real)s->position;
    const double end = s->position + s->width;
    const sluice_real *mass = sluice_real_column(v, s->mass_field, 0);
    sluice_real *rho = sluice_real_column(v, s->density_field, 0);
    const uint8_t *phase = s->has_phase ? (const uint8_t *)v->columns[s->phase_field.column] : NULL;
    const int filtered = s->phase_filter != SLUICE_PHASE_ALL;
    const uint8_t wanted = sluice_phase_wanted(s->phase_filter);
    sluice_real *u[3] = {NULL, NULL, NULL};
    sluice_real *pos[3] = {NULL, NULL, NULL};
    for (uint32_t d = 0; d < s->dims; d++) {
        u[d] = sluice_real_column(v, s->velocity_field, d);
        pos[d] = (sluice_real *)v->position[d];
    }
    if (s->controlled && dt > 0 && control_tailwater(s, host, v, dt) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_index converted = 0, removed = 0, open = 0;
    double step_mass = 0, step_momentum = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (!(pos[0][i] >= plane))
            continue;
        if (v->kind[i] == SLUICE_KIND_OPEN) {
            /* a controlled tailwater moves the whole layer at the gate's
             * velocity */
            if (s->controlled)
                u[0][i] = (sluice_real)s->velocity;
            /* already in the outlet layer: move on with its (frozen or
             * imposed) velocity; removed at the end of the layer or the
             * domain */
            int gone = 0;
            for (uint32_t d = 0; d < s->dims; d++) {
                pos[d][i] += u[d][i] * (sluice_real)dt;
                const double lo = s->domain_min[d] + 0.5 * s->dx,
                             hi = s->domain_max[d] - 0.5 * s->dx;
                gone |= !((double)pos[d][i] >= lo && (double)pos[d][i] < hi);
            }
            gone |= (double)pos[0][i] >= end || !(pos[0][i] >= plane);
            if (gone)
                s->to_remove[removed++] = i;
            else
                open++;
            continue;
        }
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        /* the other phase stays fluid (a filter implies the field) */
        if (filtered && phase[i] != wanted)
            continue;
        const int air = phase && phase[i];
        if (!air) { /* the fluxes are the water's */
            step_mass += mass[i];
            step_momentum += mass[i] * u[0][i];
        }
        if (s->form == OUTLET_FREE) {
            s->to_remove[removed++] = i;
            continue;
        }
        s->to_convert[converted++] = i;
        open++;
        if (s->form == OUTLET_BUFFER) {
            for (uint32_t d = 0; d < s->dims; d++)
                u[d][i] = d == 0 ? (sluice_real)s->velocity : 0;
            const double below = s->bed + s->depth - (double)pos[s->vertical][i];
            double density;
            if (air) {
                /* the tailwater column's pressure at its height, p_b at the
                 * surface (two_phase's start), through the air's law */
                density = air_density(s, below > 0 ? s->rho0 * s->g * below
                                                   : s->rho_a * s->g * below);
            } else if (hydrostatic_density(s, host, 1, &below, s->p_ref, &density) != SLUICE_OK) {
                return SLUICE_ERROR;
            }
            rho[i] = (sluice_real)density;
        }
    }
    /* kinds first (indices still valid), then removal */
    if (api->particles->set_kind(host, s->to_convert, converted, SLUICE_KIND_OPEN) != SLUICE_OK ||
        api->particles->remove_particles(host, s->to_remove, removed) != SLUICE_OK ||
        add_step(s, host, step_mass, step_momentum, open) != SLUICE_OK)
        return SLUICE_ERROR;
    return flux_rows(s, host, v->time);
}

/* ------------------------------------------------------------- air vent -- */

static int vent_create(const sluice_api *api, sluice_host *host, const void *config,
                       void **state)
{
    const boundary_config *c = config;
    boundary_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->vent = 1;
    s->table_rows = sluice_schedule_every(c->interval);
    s->response_time = c->response_time;
    s->file = c->file;
    /* the vent holds air: the field 'phase' of two_phase (the core refuses
     * a scene without it) */
    s->phase_filter = SLUICE_PHASE_AIR;
    sluice_real value;
    if (sluice_util_constant(api, host, "dimensions", &value) != SLUICE_OK ||
        sluice_phase_declare(api, host, SLUICE_PHASE_AIR) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)value;
    s->vertical = s->dims - 1;
    for (uint32_t d = 0; d < s->dims; d++) {
        s->box_min[d] = c->box_min[d];
        s->box_max[d] = c->box_max[d];
        if (!(s->box_max[d] > s->box_min[d])) {
            api->messages->error(host, "box_max %c = %g m must exceed box_min %c = %g m", "xyz"[d],
                       s->box_max[d], "xyz"[d], s->box_min[d]);
            free(s);
            return SLUICE_ERROR;
        }
    }
    *state = s;
    return SLUICE_OK;
}

static int in_box(const boundary_state *s, const sluice_view *v, sluice_index i)
{
    for (uint32_t d = 0; d < s->dims; d++) {
        const double x = (double)v->position[d][i];
        if (!(x >= s->box_min[d] && x < s->box_max[d]))
            return 0;
    }
    return 1;
}

/* The squared distance from particle i to the box (0 inside). */
static double box_gap2(const boundary_state *s, const sluice_view *v, sluice_index i)
{
    double distance2 = 0;
    for (uint32_t d = 0; d < s->dims; d++) {
        const double x = (double)v->position[d][i];
        const double gap = x < s->box_min[d] ? s->box_min[d] - x
                           : x > s->box_max[d] ? x - s->box_max[d]
                                               : 0;
        distance2 += gap * gap;
    }
    return distance2;
}

/* The air's pressure in the vent: p_b at the box's bottom face, the air's
 * hydrostatic weight above and below it. */
static double vent_density(const boundary_state *s, double z)
{
    return air_density(s, s->rho_a * s->g * (s->box_min[s->vertical] - z));
}

static int vent_initialise(void *state, sluice_host *host)
{
    boundary_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    double thinnest = INFINITY;
    for (uint32_t d = 0; d < s->dims; d++) {
        if (!(s->box_min[d] >= s->domain_min[d] && s->box_max[d] <= s->domain_max[d])) {
            api->messages->error(host,
                       "the vent's box (%c from %g to %g m) leaves the domain [%g, %g] m: move "
                       "it inside",
                       "xyz"[d], s->box_min[d], s->box_max[d], s->domain_min[d],
                       s->domain_max[d]);
            return SLUICE_ERROR;
        }
        thinnest = fmin(thinnest, s->box_max[d] - s->box_min[d]);
    }
    if (thinnest < s->width - 1e-9 * s->dx)
        api->messages->warning(host,
                     "the vent's box is %g m across at its thinnest, less than the kernel "
                     "support (%g m): the air next to it sees a truncated atmosphere unless "
                     "walls close that side",
                     thinnest, s->width);
    /* the fluid in the box becomes the vent's lattice, where it stands (so
     * that the vent is the air's own lattice, without a seam) */
    if (reserve(s, host, v->count) != SLUICE_OK)
        return SLUICE_ERROR;
    /* the vent belongs in the air: water in its box would become air, and
     * water within the kernel support of it would leave at once (two_phase,
     * which writes the phases, initialises first) */
    const uint8_t *phase_now = (const uint8_t *)v->columns[s->phase_field.column];
    sluice_index water_in = 0, water_near = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && !phase_now[i]) {
            const double gap2 = box_gap2(s, v, i);
            water_in += gap2 == 0;
            water_near += gap2 > 0 && gap2 < s->width * s->width;
        }
    if (water_in || water_near) {
        api->messages->error(host,
                   "the vent's box holds %u water particles and has %u more within the kernel "
                   "support (%g m) of it: place it in the air, at least %g m from the water",
                   (unsigned)water_in, (unsigned)water_near, s->width, s->width);
        return SLUICE_ERROR;
    }
    sluice_index inside = 0, open = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] != SLUICE_KIND_WALL && in_box(s, v, i)) {
            s->to_convert[inside++] = i;
            open += v->kind[i] == SLUICE_KIND_OPEN;
        }
    if (open) {
        api->messages->error(host, "the vent's box holds %u particles of an open boundary: keep it apart "
                         "from inlets and outlets",
                   (unsigned)open);
        return SLUICE_ERROR;
    }
    if (inside == 0) {
        api->messages->error(host, "the vent's box holds no fluid: place it in the air (its particles "
                         "become the vent)");
        return SLUICE_ERROR;
    }
    if (api->particles->set_kind(host, s->to_convert, inside, SLUICE_KIND_OPEN) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host);
    sluice_real *rho = sluice_real_column(v, s->density_field, 0);
    sluice_real *mass = sluice_real_column(v, s->mass_field, 0);
    uint8_t *phase = (uint8_t *)v->columns[s->phase_field.column];
    for (sluice_index k = 0; k < inside; k++) {
        const sluice_index i = s->to_convert[k];
        for (uint32_t d = 0; d < s->dims; d++)
            sluice_real_column(v, s->velocity_field, d)[i] = 0;
        rho[i] = (sluice_real)vent_density(s, (double)v->position[s->vertical][i]);
        mass[i] = (sluice_real)s->air_mass;
        phase[i] = 1;
    }
    s->open_count = inside;
    s->air_pressure = s->p_ref;
    api->messages->info(host,
              "%u particles in the box hold the atmosphere (p_b = %g Pa); air that enters "
              "leaves the domain",
              (unsigned)inside, s->p_ref);
    s->table = api->output->table_open(host, s->file,
                               "time,mass_flux,volume_flux,mass_total,water_mass_total,"
                               "air_pressure_near,air_particles_near");
    if (!s->table)
        return SLUICE_ERROR;
    /* per metre of span in 2D */
    const int plane = s->dims == 2;
    const sluice_column_doc columns[] = {
        {"s", "simulated time"},
        {plane ? "kg s^-1 m^-1" : "kg s^-1", "mass flux of the air leaving through the vent"},
        {plane ? "m^2 s^-1" : "m^3 s^-1", "volume flux of the air leaving (mass flux / rho0_a)"},
        {plane ? "kg m^-1" : "kg", "mass of the air that left since the start"},
        {plane ? "kg m^-1" : "kg", "mass of the water that reached the vent since the start"},
        {"Pa", "mean pressure of the air within the kernel support of the box"},
        {"1", "air particles within the kernel support of the box"},
    };
    return sluice_util_describe_columns(api, s->table, 0, columns, SLUICE_COUNT(columns));
}

/* The mean pressure of the air within the kernel support outside the box
 * (what the vent holds at p_b), and how many particles that is. */
static double vent_pressure_near(const boundary_state *s, sluice_host *host,
                                 const sluice_view *v, double *count)
{
    const sluice_real *p = sluice_real_column(v, s->pressure_field, 0);
    const uint8_t *phase = (const uint8_t *)v->columns[s->phase_field.column];
    double sum = 0;
    sluice_index n = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID || !phase[i])
            continue;
        if (box_gap2(s, v, i) < s->width * s->width) {
            sum += (double)p[i];
            n++;
        }
    }
    /* over the ranks: every rank's air next to the box */
    double sums[2] = {sum, (double)n};
    if (s->api->ranks->reduce(host, sums, 2, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return NAN;
    *count = sums[1];
    return sums[1] > 0 ? sums[0] / sums[1] : 0;
}

static int vent_row(boundary_state *s, sluice_host *host, const sluice_view *v, double time)
{
    const double span = time - s->row_time;
    double near = 0;
    const double pressure = s->has_pressure ? vent_pressure_near(s, host, v, &near) : 0;
    if (isnan(pressure))
        return SLUICE_ERROR;
    const double flux = span > 0 ? s->mass_interval / span : 0;
    const double row[7] = {time, flux, flux / s->rho_a, s->mass_total, s->water_total,
                           pressure, near};
    if (s->api->output->table_row(s->table, row, 7) != SLUICE_OK)
        return SLUICE_ERROR;
    s->mass_interval = 0;
    s->row_time = time;
    return SLUICE_OK;
}

static int vent_after_step(void *state, sluice_host *host)
{
    boundary_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (reserve(s, host, v->count) != SLUICE_OK)
        return SLUICE_ERROR;
    const sluice_real *mass = sluice_real_column(v, s->mass_field, 0);
    const uint8_t *phase = (const uint8_t *)v->columns[s->phase_field.column];
    /* the air as a whole above the atmosphere's pressure (the mean over
     * every air particle: one particle's pressure is noisy, and the air
     * right at the lattice, at rest, is pressed against it by the flow) */
    int compressed = 0;
    if (s->has_pressure) {
        const sluice_real *p = sluice_real_column(v, s->pressure_field, 0);
        double sum = 0;
        sluice_index n = 0;
        for (sluice_index i = 0; i < v->count; i++)
            if (v->kind[i] == SLUICE_KIND_FLUID && phase[i]) {
                sum += (double)p[i];
                n++;
            }
        /* over the ranks, so that every rank decides alike */
        double sums[2] = {sum, (double)n};
        if (api->ranks->reduce(host, sums, 2, SLUICE_REDUCE_SUM) != SLUICE_OK)
            return SLUICE_ERROR;
        /* an exponential average over the response time: the air's
         * acoustic sloshing, let out at its peaks only, would drain it */
        const double mean = sums[1] > 0 ? sums[0] / sums[1] : s->p_ref;
        const double dt = v->time - s->last_time, weight = fmin(1.0, dt / s->response_time);
        s->air_pressure += (mean - s->air_pressure) * weight;
        compressed = s->air_pressure > s->p_ref;
    }
    const double touch2 = 0.25 * s->dx * s->dx;
    sluice_index removed = 0;
    double air = 0, water = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        /* fluid whose centre is in the box leaves; so does air that
         * touches it (its centre within dx/2 of the box) while the air is
         * compressed (above): the lattice, at rest, would otherwise hold it
         * off like a wall */
        const double gap2 = box_gap2(s, v, i);
        if (gap2 > 0 && !(compressed && gap2 < touch2 && phase[i]))
            continue;
        s->to_remove[removed++] = i;
        if (phase[i])
            air += mass[i];
        else
            water += mass[i];
    }
    /* over the ranks: the air and water that left, alike on every rank */
    double left[2] = {air, water};
    if (api->ranks->reduce(host, left, 2, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    s->mass_interval += left[0];
    s->mass_total += left[0];
    water = left[1];
    if (water > 0) {
        s->water_total += water;
        if (!s->water_warned)
            api->messages->warning(host,
                         "water reached the air vent at t = %g s and left the domain through "
                         "it (water_mass_total in %s): move the vent away from the flow",
                         v->time, s->file);
        s->water_warned = 1;
    }
    const double time = v->time;
    s->last_time = time;
    if (removed && api->particles->remove_particles(host, s->to_remove, removed) != SLUICE_OK)
        return SLUICE_ERROR;
    return flux_rows(s, host, time);
}

static int vent_save(void *state, sluice_host *host)
{
    const boundary_state *s = state;
    const double values[6] = {s->last_time, s->mass_interval, s->mass_total, s->water_total,
                              s->row_time,  s->air_pressure};
    const int64_t counts[2] = {s->table_rows.count, s->water_warned};
    if (s->api->state->state_write(host,
                            "last_time,mass_interval,mass_total,water_mass_total,row_time,"
                            "air_pressure",
                            SLUICE_STATE_DOUBLE, 6, values) != SLUICE_OK ||
        s->api->state->state_write(host, "rows_written,water_warned", SLUICE_STATE_INT64, 2, counts) !=
            SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static int vent_load(void *state, sluice_host *host)
{
    boundary_state *s = state;
    double values[6];
    int64_t counts[2];
    if (s->api->state->state_read(host,
                           "last_time,mass_interval,mass_total,water_mass_total,row_time,"
                           "air_pressure",
                           SLUICE_STATE_DOUBLE, 6, values) != SLUICE_OK ||
        s->api->state->state_read(host, "rows_written,water_warned", SLUICE_STATE_INT64, 2, counts) !=
            SLUICE_OK)
        return SLUICE_ERROR;
    s->last_time = values[0];
    s->mass_interval = values[1];
    s->mass_total = values[2];
    s->water_total = values[3];
    s->row_time = values[4];
    s->air_pressure = values[5];
    s->water_warned = (int)counts[1];
    return sluice_schedule_restore(&s->table_rows, s->api, host, "rows_written,water_warned",
                                   counts[0]);
}

static int boundary_finish(void *state, sluice_host *host, int status)
{
    boundary_state *s = state;
    (void)status;
    if (s->table && s->last_time > s->row_time)
        return write_row(s, host, s->last_time);
    return SLUICE_OK;
}

/* Checkpoints: the between-step bookkeeping and the flux sums of the
 * interval under way (the open particles themselves are particles). */
static int boundary_save(void *state, sluice_host *host)
{
    const boundary_state *s = state;
    const sluice_api *api = s->api;
    const double values[6] = {s->last_time,        s->newest_column, s->mass_interval,
                              s->momentum_interval, s->mass_total,    s->row_time};
    const int64_t counts[2] = {s->table_rows.count, (int64_t)s->open_count};
    if (api->state->state_write(host, "last_time,newest_column,mass_interval,momentum_interval,"
                               "mass_total,row_time",
                         SLUICE_STATE_DOUBLE, 6, values) != SLUICE_OK ||
        api->state->state_write(host, "rows_written,open_count", SLUICE_STATE_INT64, 2, counts) !=
            SLUICE_OK)
        return SLUICE_ERROR;
    /* a controlled tailwater: the gate's state */
    const double control[4] = {s->velocity, s->velocity_integral, s->control_depth,
                               (double)s->control_started};
    if (s->controlled &&
        api->state->state_write(host, "velocity,velocity_integral,control_depth,control_started",
                         SLUICE_STATE_DOUBLE, 4, control) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static int boundary_load(void *state, sluice_host *host)
{
    boundary_state *s = state;
    const sluice_api *api = s->api;
    double values[6];
    int64_t counts[2];
    if (api->state->state_read(host, "last_time,newest_column,mass_interval,momentum_interval,"
                              "mass_total,row_time",
                        SLUICE_STATE_DOUBLE, 6, values) != SLUICE_OK ||
        api->state->state_read(host, "rows_written,open_count", SLUICE_STATE_INT64, 2, counts) !=
            SLUICE_OK)
        return SLUICE_ERROR;
    s->last_time = values[0];
    s->newest_column = values[1];
    s->mass_interval = values[2];
    s->momentum_interval = values[3];
    s->mass_total = values[4];
    s->row_time = values[5];
    /* a buffer inlet adds a column for every spacing its newest one has
     * moved since last_time: a damaged checkpoint could ask for 10^11 of
     * them. At a checkpoint last_time is its time (every step sets it) and
     * the newest column lies in the domain. */
    const double now = api->particles->view(host)->time;
    if (s->form == INLET_BUFFER &&
        (!(fabs(s->last_time - now) <= 1e-9 * fmax(1.0, fabs(now))) ||
         !(s->newest_column >= s->domain_min[0] && s->newest_column <= s->domain_max[0]))) {
        api->messages->error(host,
                             "its state holds last_time = %g s (the checkpoint's time is %g s) "
                             "and newest_column = %g m (the domain: x from %g to %g m)",
                             s->last_time, now, s->newest_column, s->domain_min[0],
                             s->domain_max[0]);
        return SLUICE_ERROR;
    }
    if (sluice_schedule_restore(&s->table_rows, api, host, "rows_written,open_count",
                                counts[0]) != SLUICE_OK)
        return SLUICE_ERROR;
    s->open_count = (sluice_index)counts[1];
    double control[4];
    if (s->controlled) {
        if (api->state->state_read(host, "velocity,velocity_integral,control_depth,control_started",
                            SLUICE_STATE_DOUBLE, 4, control) != SLUICE_OK)
            return SLUICE_ERROR;
        s->velocity = control[0];
        s->velocity_integral = control[1];
        s->control_depth = control[2];
        s->control_started = control[3] != 0;
    }
    return SLUICE_OK;
}

static const sluice_component components[] = {
    {
        .name = "inlet",
        .summary = "inflow of depth d1 and velocity V1 (or discharge q) through a buffer of "
                   "open particles (seed 004) or a pre-placed block (seed 000)",
        .reference = "De Padova et al. (2017) section 2.3; Jonsson et al. (2016) section 2.3",
        .dimensions = SLUICE_DIMS_ALL,
        .flags = SLUICE_COMPONENT_ACROSS_RANKS,
        .params = inlet_params,
        .param_count = SLUICE_COUNT(inlet_params),
        .config_size = sizeof(boundary_config),
        .fields = boundary_fields,
        .field_count = SLUICE_COUNT(boundary_fields),
        .create = inlet_create,
        .destroy = boundary_destroy,
        .bind = boundary_bind,
        .initialise = inlet_initialise,
        .after_step = inlet_after_step,
        .finish = boundary_finish,
        .save_state = boundary_save,
        .load_state = boundary_load,
    },
    {
        .name = "outlet",
        .summary = "outflow: removed (seed 002), frozen (seed 000) or a tailwater buffer "
                   "(seed 004), with the flux through the plane",
        .reference = "Lin et al. (2025); Jonsson et al. (2016); De Padova et al. (2017)",
        .dimensions = SLUICE_DIMS_ALL,
        .flags = SLUICE_COMPONENT_ACROSS_RANKS,
        .params = outlet_params,
        .param_count = SLUICE_COUNT(outlet_params),
        .config_size = sizeof(boundary_config),
        .fields = boundary_fields,
        .field_count = SLUICE_COUNT(boundary_fields),
        .create = outlet_create,
        .destroy = boundary_destroy,
        .bind = boundary_bind,
        .initialise = outlet_initialise,
        .after_step = outlet_after_step,
        .finish = boundary_finish,
        .save_state = boundary_save,
        .load_state = boundary_load,
    },
    {
        .name = "air_vent",
        .summary = "the atmosphere for a closed air box: open air particles held at the "
                   "background pressure p_b in a box; air that enters it leaves the domain",
        .reference = "Sluice (docs/physics.md, \"Air vent\"); p_b after Colagrossi & "
                     "Landrini (2003)",
        .dimensions = SLUICE_DIMS_ALL,
        .flags = SLUICE_COMPONENT_ACROSS_RANKS,
        .params = vent_params,
        .param_count = SLUICE_COUNT(vent_params),
        .config_size = sizeof(boundary_config),
        .fields = boundary_fields,
        .field_count = SLUICE_COUNT(boundary_fields),
        .create = vent_create,
        .destroy = boundary_destroy,
        .bind = boundary_bind,
        .initialise = vent_initialise,
        .after_step = vent_after_step,
        .finish = boundary_finish,
        .save_state = vent_save,
        .load_state = vent_load,
    },
};

SLUICE_DEFINE_LIBRARY("open_boundaries", "1.4.0",
                      "inlets and outlets for channel flows, and an air vent", SLUICE_DIMS_ALL,
                      components)
