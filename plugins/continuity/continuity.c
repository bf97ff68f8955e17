/* Continuity equation, in the two forms of the seeds:
 *  - form mass (seeds 002, 004; Monaghan 1992):
 *      d rho_i / dt = sum_j m_j (v_i - v_j) . grad_i W_ij
 *  - form volume (seed 000 eq. 6, LS-DYNA):
 *      d rho_i / dt = rho_i sum_j (m_j / rho_j) (v_i - v_j) . grad_i W_ij
 * With `renormalise` the kernel gradient is the renormalised one,
 * L_i grad_i W_ij (seed 004 renormalises every term but the pressure
 * gradient); it needs the kernel_correction plugin.
 * Targets fluid and wall particles (dynamic boundary particles obey it too).
 * A wall particle is compressed only by the fluid: its neighbours are fluid
 * (and open) particles alone (neighbour_kinds_by_target, ABI 2.3; continuity
 * 1.4.0), as DualSPHysics' boundary particles are, so that two walls in
 * relative motion (a gate past its sill) do not compress each other and a
 * wall particle out of the fluid's reach has no pairs at all. A pair with an open
 * boundary's particle (kind OPEN, whose motion is imposed) may lower its
 * density rate (a negative pair term, the particle moving away) but not
 * raise it (a positive one, the particle approaching). Under a gate at an
 * inlet, the imposed stream flowing in on one side of the gate's lowest wall
 * particle and the free fluid leaving on the other leave a positive rate
 * whenever the fluid there thins, which dbc's clamp (rho >= rho0) rectifies
 * into a density that grows without bound (the Jonsson jump with dbc walls
 * stopped at 3.2 s this way; docs/validation.md). At an outlet the roles
 * swap: the fluid arrives at the end of the bed and the open layer leaves,
 * and its expanding pairs are what balance the fluid's compressing ones (a
 * bed ending under an outlet without them runs away as the gate did). The
 * batch's neighbour_kinds says whether an OPEN particle is among the pairs
 * at all: a scene without open boundaries never takes that path.
 * With wall_velocity: rest a wall neighbour counts with zero velocity, its
 * fixed wall's own, whatever its velocity field holds: no-slip ghost
 * particles carry the mirrored -v_m for the viscous terms, which Adami et
 * al. (2012) keep out of the continuity equation (on the abrupt drop's face
 * it compressed the fluid beside the wall; docs/validation.md). A batch
 * without wall neighbours takes the plain path.
 * With transport_velocity (continuity 1.3.0) the velocities are those the
 * particles move with, v + du (transport_velocity_correction: xsph,
 * transport_velocity): the density then follows the particles' actual
 * motion. Form mass is then exactly the time derivative of the summation
 * density sum_j m_j W_ij along the particles' paths; without it a
 * correction that moves particles apart or together (transport_velocity's
 * shift does, by design) changes the space they fill but not their
 * density. Not with renormalise.
 * Both forms vanish for a uniform velocity and are exact for the divergence
 * of a linear velocity field on a lattice (with renormalisation, on any
 * particle set). */
#include <sluice/plugin_util.h>

typedef struct continuity_config {
    int form;
    int renormalise;
    int wall_velocity;
    int transport;
} continuity_config;

enum { FORM_MASS = 0, FORM_VOLUME = 1 };

typedef struct continuity_state {
    const sluice_api *api;
    int form, renormalise, rest_walls, transport;
    sluice_field velocity, mass, density, density_rate, correction, shift;
} continuity_state;

static const sluice_param_spec params[] = {
    {"form", SLUICE_PARAM_ENUM, offsetof(continuity_config, form), "mass", 0, 0, 0, NULL,
     "mass: sum_j m_j v_ij . grad W (seeds 002, 004); volume: rho_i sum_j V_j v_ij . grad W "
     "(seed 000 eq. 6)",
     "mass|volume", 0},
    {"renormalise", SLUICE_PARAM_BOOL, offsetof(continuity_config, renormalise), "false", 0, 0, 0,
     NULL, "use the renormalised kernel gradient L_i grad W (seed 004; needs kernel_correction)",
     NULL, 0},
    {"wall_velocity", SLUICE_PARAM_ENUM, offsetof(continuity_config, wall_velocity), "particle",
     0, 0, 0, NULL,
     "particle: a wall neighbour counts with its velocity field (dbc's moving wall, ghost "
     "particles' mirrored velocity); rest: with zero velocity, the fixed wall's own (Adami et "
     "al. 2012: no-slip ghost velocities belong in the viscous terms only)",
     "particle|rest", 0},
    {"transport_velocity", SLUICE_PARAM_BOOL, offsetof(continuity_config, transport), "false", 0,
     0, 0, NULL,
     "use the velocity the particles move with, v + transport_velocity_correction (xsph, "
     "transport_velocity), so that the density follows their actual motion; not with "
     "renormalise",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(0),
    SLUICE_SPEC_DENSITY_RATE(SLUICE_ACCUMULATE),
};

static int continuity_create(const sluice_api *api, sluice_host *host, const void *config,
                             void **state)
{
    const continuity_config *c = config;
    continuity_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->form = c->form;
    s->renormalise = c->renormalise;
    s->rest_walls = c->wall_velocity == 1;
    s->transport = c->transport;
    if (s->transport && s->renormalise) {
        api->messages->error(host, "transport_velocity and renormalise together are not implemented: "
                         "choose one");
        free(s);
        return SLUICE_ERROR;
    }
    if (s->transport) {
        const sluice_field_spec shift = {
            "transport_velocity_correction", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1",
            SLUICE_READ | SLUICE_READ_NEIGHBOUR, 0, NULL, 0,
            "what the particles move with beyond their velocity"};
        if (api->fields->declare_field(host, &shift) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
    }
    /* only what the chosen form reads is declared (and gathered) */
    if (s->form == FORM_VOLUME) {
        const sluice_field_spec density = SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR);
        if (api->fields->declare_field(host, &density) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
    }
    if (s->renormalise) {
        sluice_real dims;
        if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
        const sluice_field_spec correction = SLUICE_SPEC_KERNEL_CORRECTION_DOC(
            dims, SLUICE_READ, "kernel-gradient correction matrix L_i");
        if (api->fields->declare_field(host, &correction) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
    }
    *state = s;
    return SLUICE_OK;
}

static int continuity_bind(void *state, sluice_host *host)
{
    continuity_state *s = state;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity}, {"mass", &s->mass}, {"density", &s->density},
        {"density_rate", &s->density_rate}};
    if (sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->renormalise && s->api->fields->field(host, "kernel_correction", &s->correction) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->transport && s->api->fields->field(host, "transport_velocity_correction", &s->shift) !=
                            SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static void continuity_destroy(void *state)
{
    free(state);
}

static inline void continuity_pairs(const continuity_state *s, const sluice_view *v,
                                    const sluice_pair_batch *b, const uint32_t dims,
                                    const int volume, const int renormalise,
                                    const int rest_walls)
{
    const sluice_real *vel[3], *vj[3];
    for (uint32_t d = 0; d < dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        vj[d] = b->gathered[s->velocity.column + (int32_t)d];
    }
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict rho = volume ? sluice_real_column(v, s->density, 0) : NULL;
    const sluice_real *restrict rhoj = volume ? b->gathered[s->density.column] : NULL;
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const sluice_real *restrict vxj = vj[0], *restrict vyj = vj[1];
    const sluice_real *restrict vzj = dims == 3 ? vj[2] : vj[1];
    sluice_real *restrict rate = sluice_real_column(v, s->density_rate, 0);
    const int open_pairs = (b->neighbour_kinds & SLUICE_KIND_MASK(SLUICE_KIND_OPEN)) != 0;
    const uint8_t *restrict kinds = b->neighbour_kind;
    /* transport_velocity: the shift du at i and at the neighbours */
    const sluice_real *du[3] = {NULL, NULL, NULL}, *duj[3] = {NULL, NULL, NULL};
    if (s->transport)
        for (uint32_t d = 0; d < dims; d++) {
            du[d] = sluice_real_column(v, s->shift, d);
            duj[d] = b->gathered[s->shift.column + (int32_t)d];
        }
    /* rest_walls: a wall neighbour's velocity counts as zero (keep = 0) */
#define KEEP(k) (rest_walls ? (sluice_real)(kinds[k] != SLUICE_KIND_WALL) : (sluice_real)1)
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vxi = vel[0][i], vyi = vel[1][i], vzi = dims == 3 ? vel[2][i] : 0;
        sluice_real sum = 0;
        if (open_pairs && v->kind[i] == SLUICE_KIND_WALL) {
            /* a wall particle next to an open boundary: the open boundary's
             * particles may expand it but not compress it (see the header) */
            const uint8_t *restrict kj = b->neighbour_kind;
            const sluice_real *L[9] = {NULL};
            if (renormalise)
                for (uint32_t a = 0; a < dims * dims; a++)
                    L[a] = sluice_real_column(v, s->correction, a) + i;
            for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
                const sluice_real weight = volume ? mj[k] / rhoj[k] * F[k] : mj[k] * F[k];
                const sluice_real keep = KEEP(k);
                const sluice_real u[3] = {vxi - keep * vxj[k], vyi - keep * vyj[k],
                                          dims == 3 ? vzi - keep * vzj[k] : 0};
                const sluice_real r[3] = {rx[k], ry[k], dims == 3 ? rz[k] : 0};
                sluice_real dot = 0;
                for (uint32_t a = 0; a < dims; a++) {
                    sluice_real ra = r[a];
                    if (renormalise) {
                        ra = 0;
                        for (uint32_t c = 0; c < dims; c++)
                            ra += *L[a * dims + c] * r[c];
                    }
                    dot += u[a] * ra;
                }
                const sluice_real term = weight * dot;
                if (kj[k] == SLUICE_KIND_OPEN && term > 0)
                    continue;
                sum += term;
            }
        } else if (!renormalise) {
            for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
                const sluice_real weight = volume ? mj[k] / rhoj[k] * F[k] : mj[k] * F[k];
                const sluice_real keep = KEEP(k);
                sluice_real dot = (vxi - keep * vxj[k]) * rx[k] + (vyi - keep * vyj[k]) * ry[k];
                if (dims == 3)
                    dot += (vzi - keep * vzj[k]) * rz[k];
                sum += weight * dot;
            }
        } else {
            /* sum_j w_j v_ij . (L_i r_ij) = sum_ab L_ab M_ab with
             * M_ab = sum_j w_j v_ij,a r_ij,b: the tensor is summed, then
             * contracted once with L_i */
            sluice_real m[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
            for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
                const sluice_real weight = volume ? mj[k] / rhoj[k] * F[k] : mj[k] * F[k];
                const sluice_real keep = KEEP(k);
                const sluice_real ux = (vxi - keep * vxj[k]) * weight,
                                  uy = (vyi - keep * vyj[k]) * weight;
                m[0] += ux * rx[k];
                m[1] += ux * ry[k];
                m[3] += uy * rx[k];
                m[4] += uy * ry[k];
                if (dims == 3) {
                    const sluice_real uz = (vzi - keep * vzj[k]) * weight;
                    m[2] += ux * rz[k];
                    m[5] += uy * rz[k];
                    m[6] += uz * rx[k];
                    m[7] += uz * ry[k];
                    m[8] += uz * rz[k];
                }
            }
            for (uint32_t a = 0; a < dims; a++)
                for (uint32_t c = 0; c < dims; c++)
                    sum += sluice_real_column(v, s->correction, a * dims + c)[i] * m[3 * a + c];
        }
        if (s->transport) {
            /* the shift's part of v_i - v_j (walls and open particles have
             * none: the field is the fluid's) */
            const sluice_real dxi = du[0][i], dyi = du[1][i], dzi = dims == 3 ? du[2][i] : 0;
            for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
                const sluice_real weight = volume ? mj[k] / rhoj[k] * F[k] : mj[k] * F[k];
                sluice_real dot = (dxi - duj[0][k]) * rx[k] + (dyi - duj[1][k]) * ry[k];
                if (dims == 3)
                    dot += (dzi - duj[2][k]) * rz[k];
                sum += weight * dot;
            }
        }
        rate[i] += volume ? rho[i] * sum : sum;
    }
#undef KEEP
}

#define CONTINUITY_FORMS(dims, rest)                                                              \
    (s->renormalise ? (volume ? continuity_pairs(s, v, b, dims, 1, 1, rest)                      \
                              : continuity_pairs(s, v, b, dims, 0, 1, rest))                     \
                    : (volume ? continuity_pairs(s, v, b, dims, 1, 0, rest)                      \
                              : continuity_pairs(s, v, b, dims, 0, 0, rest)))

static void continuity_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const continuity_state *s = state;
    const int volume = s->form == FORM_VOLUME;
    /* rest_walls only where a wall is among the batch's neighbours */
    const int rest = s->rest_walls && (b->neighbour_kinds & SLUICE_KIND_MASK(SLUICE_KIND_WALL));
    if (v->dimensions == 3)
        rest ? CONTINUITY_FORMS(3, 1) : CONTINUITY_FORMS(3, 0);
    else
        rest ? CONTINUITY_FORMS(2, 1) : CONTINUITY_FORMS(2, 0);
}
#undef CONTINUITY_FORMS

static const sluice_component components[] = {{
    .name = "continuity",
    .summary = "continuity equation d rho/dt = sum_j m_j v_ij . grad W (or seed 000's volume form)",
    .reference = "Monaghan (1992); seeds 002 and 004; Jonsson et al. (2016) eq. 6",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(continuity_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .neighbour_kinds_by_target = {[SLUICE_KIND_WALL] = SLUICE_KIND_MASK(SLUICE_KIND_FLUID)},
    .create = continuity_create,
    .destroy = continuity_destroy,
    .bind = continuity_bind,
    .pair = continuity_pair,
}};

SLUICE_DEFINE_LIBRARY("continuity", "1.4.0", "continuity equation", SLUICE_DIMS_ALL, components)
