/* The background pressure of the transport-velocity formulation (Adami, Hu
 * & Adams 2013, J. Comput. Phys. 241, 292-307, eq. 13 and section 2.3):
 * particles are moved with a transport velocity
 *     v~_i = v_i + du_i,
 *     du_i = - dt (p_b / m_i) sum_j (V_i^2 + V_j^2) grad_i W_ij,
 * V = m / rho, over every neighbour (fluid, wall and open-boundary
 * particles), with dt the last step's size (recorded before each step: a
 * one-evaluation integrator such as verlet evaluates before the core picks
 * the new step; 0 at the first step, which is not shifted). The term writes du_i into
 * transport_velocity_correction, which the integrators add to the velocity
 * a particle is moved with; the momentum equation and the velocity field
 * are left as they are. On a regular lattice with a complete support the
 * sum vanishes; where particles bunch or open gaps it moves them towards
 * the gaps, so that a background pressure p_b keeps the particle
 * distribution regular (and with it away from the tensile instability)
 * without being added to the pressure of the momentum equation, where it
 * acts on the momentum wherever the particles are disordered.
 *
 * In two-phase flow (two_phase) that force is the drag of p_b on a
 * sheared water film (docs/validation.md, Cheng's spillway): with this
 * term the equation of state can take a small background pressure and
 * this one keeps the air's particles ordered. The shift per step is
 * dt^2 (p_b / rho_i) |sum_j 2 V_j grad W| ~ (p_b / rho_i c_i^2) (C dx)^2 / h
 * for a Courant number C and sound speed c_i: with the air's rho c^2
 * (2.4e5 Pa in seed 001) it acts on the light phase a thousand times more
 * than on the water, and p_b must stay well below the lightest phase's
 * rho0 c0^2 (Adami et al. take p_b = rho0 c0^2 with summation density and
 * a Courant number of 0.25).
 *
 * Published constant: transport_background_pressure (p_b), which the air's
 * cohesion (two_phase) counts with the equation of state's.
 *
 * The sum is one-sided at a free surface, where it would push particles
 * out of the fluid: particles whose Shepard sum V_i W(0) + sum_j V_j W_ij
 * is below min_kernel_sum (a free surface, a splash; 1 inside the fluid)
 * are not moved by it. The "artificial stress" A = rho v (v~ - v) of Adami
 * et al.'s momentum equation, of order dt p_b, is not included. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct transport_config {
    sluice_real background_pressure, min_kernel_sum;
} transport_config;

typedef struct transport_state {
    const sluice_api *api;
    sluice_real background_pressure, min_kernel_sum;
    double dt; /* the last step's size, recorded before each step */
    sluice_field density, mass, correction;
} transport_state;

static const sluice_param_spec params[] = {
    {"background_pressure", SLUICE_PARAM_REAL, offsetof(transport_config, background_pressure),
     NULL, 0, 0, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "Pa",
     "p_b of the transport velocity (Adami, Hu & Adams 2013): moves the particles towards a "
     "regular distribution without entering the momentum equation; keep it well below the "
     "lightest phase's rho0 c0^2",
     NULL, 0},
    {"min_kernel_sum", SLUICE_PARAM_REAL, offsetof(transport_config, min_kernel_sum), "0.9", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "particles whose Shepard sum V_i W(0) + sum_j V_j W_ij is below this (a free surface, a "
     "splash) are not moved by the term",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    {"transport_velocity_correction", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1",
     SLUICE_ACCUMULATE, 0, NULL, 0,
     "transport-velocity correction: fluid particles move with velocity + this"},
};

static int transport_create(const sluice_api *api, sluice_host *host, const void *config,
                            void **state)
{
    const transport_config *c = config;
    transport_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->background_pressure = c->background_pressure;
    s->min_kernel_sum = c->min_kernel_sum;
    /* published for the air's cohesion (two_phase), whose attraction the
     * ordering has to outweigh */
    if (api->fields->publish_constant(host, "transport_background_pressure", &s->background_pressure, 1,
                              "Pa") != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int transport_bind(void *state, sluice_host *host)
{
    transport_state *s = state;
    const sluice_field_binding fields[] = {
        {"density", &s->density}, {"mass", &s->mass},
        {"transport_velocity_correction", &s->correction}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void transport_destroy(void *state)
{
    free(state);
}

/* Before a step the view still holds the last step's size (after a
 * restart, the checkpoint's): during the step's first evaluation the core
 * has not chosen the new one yet (it depends on the rates being evaluated). */
static int transport_before_step(void *state, sluice_host *host)
{
    transport_state *s = state;
    s->dt = s->api->particles->view(host)->dt;
    return SLUICE_OK;
}

static inline void transport_pairs(const transport_state *s, const sluice_view *v,
                                   const sluice_pair_batch *b, const uint32_t dims)
{
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict mass = sluice_real_column(v, s->mass, 0);
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict W = b->kernel;
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    sluice_real *restrict ux = sluice_real_column(v, s->correction, 0);
    sluice_real *restrict uy = sluice_real_column(v, s->correction, 1);
    sluice_real *restrict uz = dims == 3 ? sluice_real_column(v, s->correction, 2) : uy;
    const sluice_real scale = (sluice_real)s->dt * s->background_pressure;
    const sluice_real w0 = b->kernel_self;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real Vi = mass[i] / rho[i], Vi2 = Vi * Vi;
        sluice_real sx = 0, sy = 0, sz = 0, shepard = Vi * w0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_real Vj = mj[k] / rhoj[k];
            const sluice_real c = (Vi2 + Vj * Vj) * F[k];
            sx += c * rx[k];
            sy += c * ry[k];
            if (dims == 3)
                sz += c * rz[k];
            shepard += Vj * W[k];
        }
        if (shepard < s->min_kernel_sum)
            continue;
        const sluice_real factor = -scale / mass[i];
        ux[i] += factor * sx;
        uy[i] += factor * sy;
        if (dims == 3)
            uz[i] += factor * sz;
    }
}

static void transport_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const transport_state *s = state;
    if (!(s->dt > 0))
        return; /* the first step: no step size yet */
    if (v->dimensions == 3)
        transport_pairs(s, v, b, 3);
    else
        transport_pairs(s, v, b, 2);
}

static const sluice_component components[] = {{
    .name = "transport_velocity",
    .summary = "background pressure of the transport velocity: moves particles towards a regular "
               "distribution, outside the momentum equation",
    .reference = "Adami, Hu & Adams (2013), J. Comput. Phys. 241, 292-307",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_NEEDS_KERNEL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(transport_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL) |
                       SLUICE_KIND_MASK(SLUICE_KIND_OPEN),
    .create = transport_create,
    .destroy = transport_destroy,
    .bind = transport_bind,
    .pair = transport_pair,
    .before_step = transport_before_step,
}};

SLUICE_DEFINE_LIBRARY("transport_velocity", "1.0.0",
                      "transport-velocity background pressure (Adami, Hu & Adams 2013)",
                      SLUICE_DIMS_ALL, components)
