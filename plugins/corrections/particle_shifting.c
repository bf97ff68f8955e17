/* Particle shifting in its Fickian form (Lind, Xu, Stansby & Rogers 2012,
 * J. Comput. Phys. 231:1499-1523): particles are moved down the gradient of
 * their own concentration,
 *     dr_i = -D_i grad C_i,   grad C_i = sum_j V_j grad_i W_ij,
 * with the diffusion coefficient
 *   form skillen (default; Skillen, Lind, Stansby & Rogers 2013, Comput.
 *                Methods Appl. Mech. Engrg. 265:163-173, as DualSPHysics has
 *                it): D_i = A h |v_i| dt, A = `coefficient` (default 2): the
 *                shift follows how far a particle travels in the step; it
 *                vanishes at stagnation points;
 *   form lind    (Lind et al. 2012): D = A h^2 per step, A default 0.5,
 *                whatever the velocity: it also orders the particles at
 *                stagnation points, where a straining flow (a vortex array,
 *                the Taylor-Green vortex) lines them up; dt is the last
 *                step's (recorded before each step; the first step is not
 *                shifted),
 * over every neighbour (fluid, wall and open-boundary particles: a wall's
 * particles keep the fluid's lattice up to it). The shift is written as a
 * velocity, du_i = dr_i / dt = -A h |v_i| grad C_i, into
 * transport_velocity_correction, which the integrators add to the velocity
 * a particle is moved with (as transport_velocity and xsph do); the
 * momentum equation and the velocity field are left as they are. On a
 * regular lattice with a complete support grad C = 0; where particles bunch
 * or open gaps it moves them towards the gaps, in proportion to how far
 * they travel in the step, so that a flow stays on a regular distribution
 * and a fluid at rest is not moved at all.
 *
 * At a free surface grad C points into the fluid and would pull the surface
 * particles inwards. The surface is detected by the divergence of position,
 *     div r_i = -sum_j V_j r_ij . grad_i W_ij
 * (the dimension d inside the fluid, about d/2 at a flat surface): a
 * particle with div r below `surface_divergence` (default d - 0.5: 1.5 in
 * 2D, 2.5 in 3D) is not shifted (DualSPHysics' free-surface threshold).
 * Lind et al.'s alternative, the shift projected on the surface, needs a
 * surface normal other than grad C (to which the shift is parallel, so the
 * projection would leave nothing); it is not offered.
 * Particles that see no other particle (a droplet) are not shifted. */
#include <math.h>

#include <sluice/plugin_util.h>

enum { FORM_SKILLEN = 0, FORM_LIND = 1 };

typedef struct shifting_config {
    int form;
    sluice_real coefficient, surface_divergence;
} shifting_config;

typedef struct shifting_state {
    const sluice_api *api;
    int form;
    sluice_real coefficient, surface_divergence, h;
    double dt; /* form lind: the last step's size, recorded before each step */
    sluice_field density, mass, velocity, correction;
} shifting_state;

static const sluice_param_spec params[] = {
    {"form", SLUICE_PARAM_ENUM, offsetof(shifting_config, form), "skillen", 0, 0, 0, NULL,
     "skillen: D = A h |v| dt (Skillen et al. 2013, DualSPHysics); lind: D = A h^2 per step "
     "(Lind et al. 2012)",
     "skillen|lind", 0},
    {"coefficient", SLUICE_PARAM_REAL, offsetof(shifting_config, coefficient), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL | SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "1",
     "A of the diffusion coefficient; absent: 2 (skillen), 0.5 (lind)", NULL, 0},
    {"surface_divergence", SLUICE_PARAM_REAL, offsetof(shifting_config, surface_divergence),
     NULL, 0, 0, SLUICE_PARAM_OPTIONAL | SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "1",
     "div r below which a particle is at a free surface and not shifted (d inside the fluid, "
     "about d/2 at a flat surface); absent: d - 0.5",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_VELOCITY(SLUICE_READ),
    {"transport_velocity_correction", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1",
     SLUICE_ACCUMULATE, 0, NULL, 0,
     "transport-velocity correction: fluid particles move with velocity + this"},
};

static int shifting_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state)
{
    const shifting_config *c = config;
    shifting_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    uint32_t dims;
    if (sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_dimensions(api, host, &dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->api = api;
    s->form = c->form;
    s->coefficient = c->coefficient > 0 ? c->coefficient
                                        : (c->form == FORM_LIND ? (sluice_real)0.5 : 2);
    /* an absent optional parameter reads as 0 */
    s->surface_divergence =
        c->surface_divergence > 0 ? c->surface_divergence : (sluice_real)dims - (sluice_real)0.5;
    *state = s;
    return SLUICE_OK;
}

static int shifting_bind(void *state, sluice_host *host)
{
    shifting_state *s = state;
    const sluice_field_binding fields[] = {{"density", &s->density},
                                           {"mass", &s->mass},
                                           {"velocity", &s->velocity},
                                           {"transport_velocity_correction", &s->correction}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void shifting_destroy(void *state)
{
    free(state);
}

/* Before a step the view still holds the last step's size (after a
 * restart, the checkpoint's). */
static int shifting_before_step(void *state, sluice_host *host)
{
    shifting_state *s = state;
    s->dt = s->api->particles->view(host)->dt;
    return SLUICE_OK;
}

static inline void shifting_pairs(const shifting_state *s, const sluice_view *v,
                                  const sluice_pair_batch *b, const uint32_t dims)
{
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const sluice_real *vel[3];
    sluice_real *du[3];
    for (uint32_t d = 0; d < dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        du[d] = sluice_real_column(v, s->correction, d);
    }
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        if (b->pair_begin[t + 1] == b->pair_begin[t])
            continue; /* alone: nothing to shift towards */
        sluice_real grad[3] = {0, 0, 0}, divergence = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_real c = mj[k] / rhoj[k] * F[k];
            grad[0] += c * rx[k];
            grad[1] += c * ry[k];
            sluice_real r2 = rx[k] * rx[k] + ry[k] * ry[k];
            if (dims == 3) {
                grad[2] += c * rz[k];
                r2 += rz[k] * rz[k];
            }
            divergence -= c * r2;
        }
        if (divergence < s->surface_divergence)
            continue; /* at a free surface */
        sluice_real factor;
        if (s->form == FORM_LIND) {
            factor = -s->coefficient * s->h * s->h / (sluice_real)s->dt;
        } else {
            sluice_real speed2 = 0;
            for (uint32_t d = 0; d < dims; d++)
                speed2 += vel[d][i] * vel[d][i];
            factor = -s->coefficient * s->h * sqrt(speed2);
        }
        const sluice_real shift[3] = {factor * grad[0], factor * grad[1], factor * grad[2]};
        for (uint32_t d = 0; d < dims; d++)
            du[d][i] += shift[d];
    }
}

static void shifting_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const shifting_state *s = state;
    if (s->form == FORM_LIND && !(s->dt > 0))
        return; /* the first step: no step size yet */
    if (v->dimensions == 3)
        shifting_pairs(s, v, b, 3);
    else
        shifting_pairs(s, v, b, 2);
}

static const sluice_component components[] = {{
    .name = "particle_shifting",
    .summary = "Fickian particle shifting, du = -A h |v| grad C, none at a free surface",
    .reference = "Lind et al. (2012), J. Comput. Phys. 231:1499-1523; Skillen et al. (2013), "
                 "Comput. Methods Appl. Mech. Engrg. 265:163-173",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(shifting_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL) |
                       SLUICE_KIND_MASK(SLUICE_KIND_OPEN),
    .create = shifting_create,
    .destroy = shifting_destroy,
    .bind = shifting_bind,
    .pair = shifting_pair,
    .before_step = shifting_before_step,
}};

SLUICE_DEFINE_LIBRARY("particle_shifting", "1.0.0",
                      "Fickian particle shifting (Lind et al. 2012; Skillen et al. 2013)",
                      SLUICE_DIMS_ALL, components)
