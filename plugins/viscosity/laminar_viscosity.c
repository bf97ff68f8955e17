/* Laminar (molecular) viscosity of a Newtonian fluid with constant kinematic
 * viscosity nu, as the SPH Laplacian of the velocity (pair term, fluid
 * targets, fluid and wall neighbours):
 *
 *  - form morris (Morris, Fox & Zhu 1997, J. Comput. Phys. 136):
 *      dv_i/dt += sum_j m_j (mu_i + mu_j) / (rho_i rho_j)
 *                       (r_ij . grad_i W_ij) / (r_ij^2 + eta^2) v_ij,   mu = rho nu;
 *  - form lo_shao (Lo & Shao 2002, Appl. Ocean Res. 24; the laminar term of
 *    DualSPHysics, Crespo et al. 2015):
 *      dv_i/dt += sum_j m_j 4 nu / (rho_i + rho_j)
 *                       (r_ij . grad_i W_ij) / (r_ij^2 + eta^2) v_ij,
 *
 * with r_ij = r_i - r_j, v_ij = v_i - v_j and eta^2 = 0.01 h^2. Since
 * r_ij . grad_i W_ij = r^2 F_ij = r dW/dr < 0, a particle faster than its
 * neighbours is slowed down. Both weights are symmetric in i and j and
 * v_ij is antisymmetric, so every pair exchanges equal and opposite momentum
 * (total linear momentum is conserved to round-off). Wall particles (dynamic
 * boundary particles) have zero velocity: the term then drags the fluid to
 * rest at the walls (no-slip). With DBC layers on the lattice behind a wall,
 * the effective no-slip position lies 0.6 to 0.9 dx behind the wall line
 * (Poiseuille flow, tests/plugins/viscosity/test_viscosity.c): first-order accurate walls.
 *
 * Time step: the explicit viscous condition of Morris et al. (1997),
 * dt <= 0.125 h^2 / nu over fluid particles. It is a stability bound of its
 * own, not a Courant condition, and is not multiplied by the Courant number.
 * (On a regular lattice with Wendland C2, h = 1.3 to 1.5 dx, the largest
 * eigenvalue of this operator is 6.2 to 6.8 nu / h^2 in 2D and 3D, so the
 * second-order integrators are stable to dt = 0.30 h^2 / nu: 0.125 leaves a
 * factor 2.4.)
 *
 * Not offered: a renormalised form. Substituting the renormalised gradient
 * L_i r_ij F_ij into this Laplacian does not make it consistent (a consistent
 * second derivative needs a different correction, Fatehi & Manzari 2011), and
 * it would break the pairwise symmetry that conserves momentum. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct laminar_config {
    sluice_real nu;
    int form;
} laminar_config;

enum { FORM_MORRIS = 0, FORM_LO_SHAO = 1 };

typedef struct laminar_state {
    const sluice_api *api;
    int form;
    sluice_real nu, eta2, limit;
    sluice_field velocity, density, mass, acceleration;
} laminar_state;

static const sluice_param_spec params[] = {
    {"kinematic_viscosity", SLUICE_PARAM_REAL, offsetof(laminar_config, nu), "1e-6", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m^2 s^-1",
     "kinematic viscosity nu (water at 20 C: 1.0e-6)", NULL, 0},
    {"form", SLUICE_PARAM_ENUM, offsetof(laminar_config, form), "morris", 0, 0, 0, NULL,
     "morris: m_j (mu_i + mu_j)/(rho_i rho_j) weights (Morris et al. 1997); lo_shao: "
     "m_j 4 nu/(rho_i + rho_j) (Lo & Shao 2002, DualSPHysics)",
     "morris|lo_shao", 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
};

static int laminar_create(const sluice_api *api, sluice_host *host, const void *config,
                          void **state)
{
    const laminar_config *c = config;
    laminar_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->form = c->form;
    s->nu = c->nu;
    sluice_real h;
    if (sluice_util_constant(api, host, "smoothing_length", &h) != SLUICE_OK ||
        api->fields->publish_constant(host, "kinematic_viscosity", &s->nu, 1, "m^2 s^-1") != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->eta2 = (sluice_real)0.01 * h * h;
    s->limit = (sluice_real)0.125 * h * h / s->nu;
    *state = s;
    return SLUICE_OK;
}

static int laminar_bind(void *state, sluice_host *host)
{
    laminar_state *s = state;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity}, {"density", &s->density}, {"mass", &s->mass},
        {"acceleration", &s->acceleration}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void laminar_destroy(void *state)
{
    free(state);
}

/* One loop per (form, dimensions); `form` and `dims` are compile-time
 * constants at every call, so the inner loop has no branch. */
static inline void laminar_pairs(const laminar_state *s, const sluice_view *v,
                                 const sluice_pair_batch *b, const int form, const uint32_t dims)
{
    const sluice_real *vel[3], *vj[3];
    for (uint32_t d = 0; d < dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        vj[d] = b->gathered[s->velocity.column + (int32_t)d];
    }
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict r = b->distance;
    const sluice_real *restrict vxj = vj[0], *restrict vyj = vj[1];
    const sluice_real *restrict vzj = dims == 3 ? vj[2] : vj[1];
    sluice_real *restrict ax = sluice_real_column(v, s->acceleration, 0);
    sluice_real *restrict ay = sluice_real_column(v, s->acceleration, 1);
    sluice_real *restrict az = dims == 3 ? sluice_real_column(v, s->acceleration, 2) : ay;
    const sluice_real eta2 = s->eta2;
    /* morris: nu m_j (rho_i + rho_j) / (rho_i rho_j); lo_shao: 4 nu m_j / (rho_i + rho_j) */
    const sluice_real scale = form == FORM_MORRIS ? s->nu : 4 * s->nu;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vxi = vel[0][i], vyi = vel[1][i], vzi = dims == 3 ? vel[2][i] : 0;
        const sluice_real rhoi = rho[i];
        sluice_real sx = 0, sy = 0, sz = 0;

        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            /* (r_ij . grad_i W_ij) / (r^2 + eta^2) = r^2 F / (r^2 + eta^2), times the
             * weight of the form, with one division */
            const sluice_real r2 = r[k] * r[k];
            const sluice_real c =
                form == FORM_MORRIS
                    ? mj[k] * (rhoi + rhoj[k]) * r2 * F[k] / (rhoi * rhoj[k] * (r2 + eta2))
                    : mj[k] * r2 * F[k] / ((rhoi + rhoj[k]) * (r2 + eta2));
            sx += c * (vxi - vxj[k]);
            sy += c * (vyi - vyj[k]);
            if (dims == 3)
                sz += c * (vzi - vzj[k]);
        }
        ax[i] += scale * sx;
        ay[i] += scale * sy;
        if (dims == 3)
            az[i] += scale * sz;
    }
}

static void laminar_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const laminar_state *s = state;
    if (s->form == FORM_MORRIS) {
        if (v->dimensions == 3)
            laminar_pairs(s, v, b, FORM_MORRIS, 3);
        else
            laminar_pairs(s, v, b, FORM_MORRIS, 2);
    } else {
        if (v->dimensions == 3)
            laminar_pairs(s, v, b, FORM_LO_SHAO, 3);
        else
            laminar_pairs(s, v, b, FORM_LO_SHAO, 2);
    }
}

/* Morris et al. (1997): dt <= 0.125 h^2 / nu, whenever the range holds a
 * fluid particle (nu is uniform). */
static sluice_real laminar_time_step_limit(void *state, const sluice_view *v, sluice_index begin,
                                           sluice_index end)
{
    const laminar_state *s = state;
    for (sluice_index i = begin; i < end; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            return s->limit;
    return (sluice_real)INFINITY;
}

static const sluice_component components[] = {{
    .name = "laminar_viscosity",
    .summary = "laminar viscosity nu Laplacian(v) (Morris et al. or Lo & Shao form), no-slip "
               "at wall particles, with the viscous time-step limit 0.125 h^2/nu",
    .reference = "Morris, Fox & Zhu (1997) J. Comput. Phys. 136:214; Lo & Shao (2002) Appl. "
                 "Ocean Res. 24:275",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(laminar_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = laminar_create,
    .destroy = laminar_destroy,
    .bind = laminar_bind,
    .pair = laminar_pair,
    .time_step_limit = laminar_time_step_limit,
}};

SLUICE_DEFINE_LIBRARY("laminar_viscosity", "1.0.0", "laminar viscosity (Morris; Lo & Shao)",
                      SLUICE_DIMS_ALL, components)
