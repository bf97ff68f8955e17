/* Turbulent (Reynolds) stress in the momentum equation, Boussinesq closure
 * with the kinematic eddy viscosity nu_T (field eddy_viscosity, from
 * mixing_length or k_epsilon):
 *   dv_i/dt += (1/rho div T)_i,   T = 2 rho nu_T S^d,  S^d = S - (tr S / dims) I,
 *   S = (G + G^T)/2, G the field velocity_gradient.
 * Two discrete forms (parameter `form`):
 *  - tensor (seed 004, eq. 1, after Monaghan 2005 / De Padova et al. 2010):
 *      dv_i/dt += sum_j m_j (T_i/rho_i^2 + T_j/rho_j^2) . grad^_i W_ij,
 *    T_i / rho_i^2 = 2 nu_T,i S^d_i / rho_i. With grad^ = grad (renormalise false)
 *    it conserves linear momentum exactly (grad_i W_ij = -grad_j W_ji); with
 *    renormalise true (seed 004) grad^_i W_ij = L_i grad_i W_ij and momentum is
 *    no longer conserved exactly.
 *  - eddy_viscosity (Shao & Gotoh 2005; DualSPHysics laminar+SPS): the laminar
 *    operator of Lo & Shao (2002) with a pair viscosity,
 *      dv_i/dt += sum_j m_j 4 nubar_ij / (rho_i + rho_j) v_ij (r_ij . grad_i W_ij) / (r^2 + eta^2),
 *      nubar_ij = (nu_T,i + nu_T,j) / 2,   eta^2 = 0.01 h^2,
 *    i.e. div(nu_T grad v) (the part (grad nu_T) . (grad v)^T of div(2 nu_T S) is
 *    left out). The laminar part nu of Shao & Gotoh's nu_ij = nu + nubar_T is the
 *    same operator with a constant coefficient and is added by laminar_viscosity:
 *    the operator is linear in nu_ij, so the sum is their form. Conserves linear
 *    momentum exactly (pairwise antisymmetric).
 *
 * Walls. Neighbours are fluid and wall particles; wall (DBC) particles move at
 * v = 0 and have no eddy viscosity or strain rate of their own (no turbulence
 * plugin targets them). Parameter `wall_stress`:
 *  - mirror (default): a wall particle j takes the stress of the fluid particle
 *    i it interacts with, T_j = T_i (tensor) or nu_T,j = nu_T,i (eddy_viscosity),
 *    as the mirror (ghost) particle of seed 004's ghost-particle walls would:
 *    the stress is continuous across the wall;
 *  - zero: T_j = 0, nu_T,j = 0 in the wall.
 * For fluid in a linear shear u = gamma y above a flat wall at y = 0 with
 * uniform nu_T, the tangential force per unit wall area that the wall
 * particles exert is, in the continuum limit of the sums (eta -> 0), for any
 * radial kernel (w(s) = int W dx its 1D marginal, Omega(y) = int_y^inf w ds):
 *  - tensor: the SPH velocity gradient at height y is gamma (1 - Omega(y))
 *    (gamma/2 at the wall, exact beyond 2h) because the wall particles sit at
 *    rest instead of continuing the profile, and
 *    tau_w = c rho nu_T gamma int_0^inf (1 - Omega) w dy = c (3/8) rho nu_T gamma,
 *    c = 2 (mirror: 3/4) or 1 (zero: 3/8);
 *  - eddy_viscosity: tau_w = c rho nu_T gamma int_0^inf s^2 (-f(s))/2 ds
 *    = c (1/4) rho nu_T gamma, f(s) = int F dx, c = 2 (mirror: 1/2) or 1 (zero:
 *    1/4); the missing half is again the zero wall velocity.
 * With mirror the wall force is the stress of the first fluid layers, so the
 * discrete momentum balance of the first layer is that of the interior. With
 * zero the wall carries only half of it (the first fluid layer's stress must
 * double, and it outruns the second: the open-channel study shows a
 * non-monotonic profile). In both cases the SPH gradient next to the wall is
 * smaller than the actual one, so a steady flow needs a steeper near-wall
 * profile than a resolved no-slip wall (the study measures the resulting
 * log-law constant). The test measures these constants on the lattice.
 * Time-step limit: dt <= 0.125 h^2 / max_i nu_T,i (Morris et al. 1997). */
#include <math.h>

#include <sluice/plugin_util.h>

enum { FORM_TENSOR = 0, FORM_EDDY_VISCOSITY = 1 };

enum { WALL_MIRROR = 0, WALL_ZERO = 1 };

typedef struct ts_config {
    int form;
    int renormalise;
    int wall_stress;
} ts_config;

typedef struct ts_state {
    const sluice_api *api;
    uint32_t dims;
    int form, renormalise, mirror;
    sluice_real h, eta2;
    sluice_field velocity, mass, density, gradient, eddy_viscosity, acceleration, correction;
} ts_state;

static const sluice_param_spec params[] = {
    {"form", SLUICE_PARAM_ENUM, offsetof(ts_config, form), "tensor", 0, 0, 0, NULL,
     "tensor: sum_j m_j (T_i/rho_i^2 + T_j/rho_j^2) . grad W (seed 004); eddy_viscosity: "
     "Lo & Shao laminar operator with nubar_ij = (nu_T,i + nu_T,j)/2 (Shao & Gotoh 2005)",
     "tensor|eddy_viscosity", 0},
    {"renormalise", SLUICE_PARAM_BOOL, offsetof(ts_config, renormalise), "false", 0, 0, 0, NULL,
     "tensor form only: use the renormalised kernel gradient L_i grad_i W_ij (seed 004; reads "
     "kernel_correction; linear momentum is then not conserved exactly)",
     NULL, 0},
    {"wall_stress", SLUICE_PARAM_ENUM, offsetof(ts_config, wall_stress), "mirror", 0, 0, 0, NULL,
     "mirror: a wall particle takes the stress (tensor) or eddy viscosity (eddy_viscosity) of "
     "the fluid particle it interacts with, as seed 004's ghost particles; zero: none in the "
     "wall",
     "mirror|zero", 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_EDDY_VISCOSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_ACCELERATION(SLUICE_ACCUMULATE),
};

static int ts_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const ts_config *c = config;
    ts_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->form = c->form;
    s->renormalise = c->renormalise;
    s->mirror = c->wall_stress == WALL_MIRROR;
    sluice_real dims;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->eta2 = (sluice_real)0.01 * s->h * s->h;
    if (s->renormalise && s->form != FORM_TENSOR) {
        api->messages->error(host, "renormalise applies to form tensor only; the eddy_viscosity form uses "
                         "r_ij . grad W_ij, which renormalisation does not correct");
        free(s);
        return SLUICE_ERROR;
    }
    const sluice_field_spec gradient =
        SLUICE_SPEC_VELOCITY_GRADIENT(s->dims, SLUICE_READ | SLUICE_READ_NEIGHBOUR);
    const sluice_field_spec correction = SLUICE_SPEC_KERNEL_CORRECTION(s->dims, SLUICE_READ);
    if ((s->form == FORM_TENSOR && api->fields->declare_field(host, &gradient) != SLUICE_OK) ||
        (s->renormalise && api->fields->declare_field(host, &correction) != SLUICE_OK)) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int ts_bind(void *state, sluice_host *host)
{
    ts_state *s = state;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity}, {"mass", &s->mass}, {"density", &s->density},
        {"eddy_viscosity", &s->eddy_viscosity}, {"acceleration", &s->acceleration}};
    if (sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->form == FORM_TENSOR &&
        s->api->fields->field(host, "velocity_gradient", &s->gradient) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->renormalise && s->api->fields->field(host, "kernel_correction", &s->correction) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static void ts_destroy(void *state)
{
    free(state);
}

/* Tensor form. Q = T / rho^2 = 2 nu_T S^d / rho, symmetric: stored as
 * xx, xy, xz, yy, yz, zz. */
static inline void ts_tensor(const ts_state *s, const sluice_view *v, const sluice_pair_batch *b,
                             const uint32_t dims, const int renormalise, const int mirror)
{
    const sluice_real *G[9], *Gj[9], *L[9];
    for (uint32_t c = 0; c < dims * dims; c++) {
        G[c] = sluice_real_column(v, s->gradient, c);
        Gj[c] = b->gathered[s->gradient.column + (int32_t)c];
        L[c] = renormalise ? sluice_real_column(v, s->correction, c) : NULL;
    }
    /* neighbour components, named for 3D; in 2D the z entries alias unused ones */
    const sluice_real *restrict gxx = Gj[0], *restrict gxy = Gj[1];
    const sluice_real *restrict gyx = dims == 3 ? Gj[3] : Gj[2];
    const sluice_real *restrict gyy = dims == 3 ? Gj[4] : Gj[3];
    const sluice_real *restrict gxz = dims == 3 ? Gj[2] : Gj[0];
    const sluice_real *restrict gzx = dims == 3 ? Gj[6] : Gj[0];
    const sluice_real *restrict gyz = dims == 3 ? Gj[5] : Gj[0];
    const sluice_real *restrict gzy = dims == 3 ? Gj[7] : Gj[0];
    const sluice_real *restrict gzz = dims == 3 ? Gj[8] : Gj[0];
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict nu = sluice_real_column(v, s->eddy_viscosity, 0);
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict nuj = b->gathered[s->eddy_viscosity.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const uint8_t *restrict kj = b->neighbour_kind;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    sluice_real *restrict ax = sluice_real_column(v, s->acceleration, 0);
    sluice_real *restrict ay = sluice_real_column(v, s->acceleration, 1);
    sluice_real *restrict az = dims == 3 ? sluice_real_column(v, s->acceleration, 2) : ay;
    const sluice_real third = (sluice_real)1 / (sluice_real)dims;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        /* Q_i */
        const sluice_real ci = 2 * nu[i] / rho[i];
        sluice_real qxx, qxy, qxz = 0, qyy, qyz = 0, qzz = 0;
        {
            const sluice_real Gxx = G[0][i], Gxy = G[1][i];
            const sluice_real Gyx = G[dims][i], Gyy = G[dims + 1][i];
            const sluice_real Gzz = dims == 3 ? G[8][i] : 0;
            const sluice_real tr = (Gxx + Gyy + Gzz) * third;
            qxx = ci * (Gxx - tr);
            qyy = ci * (Gyy - tr);
            qxy = ci * (sluice_real)0.5 * (Gxy + Gyx);
            if (dims == 3) {
                qzz = ci * (Gzz - tr);
                qxz = ci * (sluice_real)0.5 * (G[2][i] + G[6][i]);
                qyz = ci * (sluice_real)0.5 * (G[5][i] + G[7][i]);
            }
        }
        /* grad^_i W_ij = e F with e = r_ij (or L_i r_ij when renormalised);
         * sum_j m_j (Q_i + Q_j) . e F = Q_i . sum_j m_j e F + sum_j m_j Q_j . e F;
         * mirror: Q_j = Q_i for wall neighbours, i.e. their m_j e F counts twice
         * in the first sum and they drop out of the second */
        sluice_real Lxx = 1, Lxy = 0, Lxz = 0, Lyx = 0, Lyy = 1, Lyz = 0, Lzx = 0, Lzy = 0,
                    Lzz = 1;
        if (renormalise) {
            Lxx = L[0][i];
            Lxy = L[1][i];
            Lyx = L[dims][i];
            Lyy = L[dims + 1][i];
            if (dims == 3) {
                Lxz = L[2][i];
                Lyz = L[5][i];
                Lzx = L[6][i];
                Lzy = L[7][i];
                Lzz = L[8][i];
            }
        }
        sluice_real mx = 0, my = 0, mz = 0; /* sum_j m_j e F */
        sluice_real sx = 0, sy = 0, sz = 0; /* sum_j m_j Q_j . e F */
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            sluice_real ex = rx[k], ey = ry[k], ez = dims == 3 ? rz[k] : 0;
            if (renormalise) {
                ex = Lxx * rx[k] + Lxy * ry[k] + (dims == 3 ? Lxz * rz[k] : 0);
                ey = Lyx * rx[k] + Lyy * ry[k] + (dims == 3 ? Lyz * rz[k] : 0);
                ez = dims == 3 ? Lzx * rx[k] + Lzy * ry[k] + Lzz * rz[k] : 0;
            }
            const sluice_real w = mj[k] * F[k];
            const int wall = mirror && kj[k] == SLUICE_KIND_WALL;
            const sluice_real wi = wall ? 2 * w : w;
            const sluice_real cj = wall ? 0 : 2 * nuj[k] / rhoj[k] * w;
            const sluice_real trj = (gxx[k] + gyy[k] + (dims == 3 ? gzz[k] : 0)) * third;
            const sluice_real pxx = cj * (gxx[k] - trj), pyy = cj * (gyy[k] - trj);
            const sluice_real pxy = cj * (sluice_real)0.5 * (gxy[k] + gyx[k]);
            mx += wi * ex;
            my += wi * ey;
            sx += pxx * ex + pxy * ey;
            sy += pxy * ex + pyy * ey;
            if (dims == 3) {
                const sluice_real pzz = cj * (gzz[k] - trj);
                const sluice_real pxz = cj * (sluice_real)0.5 * (gxz[k] + gzx[k]);
                const sluice_real pyz = cj * (sluice_real)0.5 * (gyz[k] + gzy[k]);
                mz += wi * ez;
                sx += pxz * ez;
                sy += pyz * ez;
                sz += pxz * ex + pyz * ey + pzz * ez;
            }
        }
        const sluice_real fx = qxx * mx + qxy * my + qxz * mz + sx;
        const sluice_real fy = qxy * mx + qyy * my + qyz * mz + sy;
        const sluice_real fz = qxz * mx + qyz * my + qzz * mz + sz;
        ax[i] += fx;
        ay[i] += fy;
        if (dims == 3)
            az[i] += fz;
    }
}

static inline void ts_eddy(const ts_state *s, const sluice_view *v, const sluice_pair_batch *b,
                           const uint32_t dims, const int mirror)
{
    const sluice_real *vel[3], *vj[3];
    for (uint32_t d = 0; d < dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        vj[d] = b->gathered[s->velocity.column + (int32_t)d];
    }
    const sluice_real *restrict vxj = vj[0], *restrict vyj = vj[1];
    const sluice_real *restrict vzj = dims == 3 ? vj[2] : vj[1];
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict nu = sluice_real_column(v, s->eddy_viscosity, 0);
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict nuj = b->gathered[s->eddy_viscosity.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const uint8_t *restrict kj = b->neighbour_kind;
    const sluice_real *restrict r = b->distance;
    sluice_real *restrict ax = sluice_real_column(v, s->acceleration, 0);
    sluice_real *restrict ay = sluice_real_column(v, s->acceleration, 1);
    sluice_real *restrict az = dims == 3 ? sluice_real_column(v, s->acceleration, 2) : ay;
    const sluice_real eta2 = s->eta2;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vxi = vel[0][i], vyi = vel[1][i], vzi = dims == 3 ? vel[2][i] : 0;
        const sluice_real nui = nu[i], rhoi = rho[i];
        sluice_real sx = 0, sy = 0, sz = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            /* m_j 4 nubar_ij / (rho_i + rho_j) (r_ij . grad W) / (r^2 + eta^2),
             * 4 nubar_ij = 2 (nu_i + nu_j), r_ij . grad W = r^2 F */
            const sluice_real r2 = r[k] * r[k];
            const sluice_real nu_j = mirror && kj[k] == SLUICE_KIND_WALL ? nui : nuj[k];
            const sluice_real c =
                2 * mj[k] * (nui + nu_j) / (rhoi + rhoj[k]) * r2 * F[k] / (r2 + eta2);
            sx += c * (vxi - vxj[k]);
            sy += c * (vyi - vyj[k]);
            if (dims == 3)
                sz += c * (vzi - vzj[k]);
        }
        ax[i] += sx;
        ay[i] += sy;
        if (dims == 3)
            az[i] += sz;
    }
}

static void ts_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const ts_state *s = state;
    const int three = v->dimensions == 3;
    /* a batch without wall neighbours needs no mirror */
    const int mirror = s->mirror && (b->neighbour_kinds & SLUICE_KIND_MASK(SLUICE_KIND_WALL));
    if (s->form == FORM_EDDY_VISCOSITY) {
        if (mirror)
            three ? ts_eddy(s, v, b, 3, 1) : ts_eddy(s, v, b, 2, 1);
        else
            three ? ts_eddy(s, v, b, 3, 0) : ts_eddy(s, v, b, 2, 0);
    } else if (s->renormalise) {
        if (mirror)
            three ? ts_tensor(s, v, b, 3, 1, 1) : ts_tensor(s, v, b, 2, 1, 1);
        else
            three ? ts_tensor(s, v, b, 3, 1, 0) : ts_tensor(s, v, b, 2, 1, 0);
    } else {
        if (mirror)
            three ? ts_tensor(s, v, b, 3, 0, 1) : ts_tensor(s, v, b, 2, 0, 1);
        else
            three ? ts_tensor(s, v, b, 3, 0, 0) : ts_tensor(s, v, b, 2, 0, 0);
    }
}

static sluice_real ts_time_step_limit(void *state, const sluice_view *v, sluice_index begin,
                                      sluice_index end)
{
    const ts_state *s = state;
    const sluice_real *nu = sluice_real_column(v, s->eddy_viscosity, 0);
    int64_t worst = 0;
    for (sluice_index i = begin; i < end; i++) {
        const int64_t bits =
            v->kind[i] == SLUICE_KIND_FLUID ? sluice_util_bits(nu[i] > 0 ? nu[i] : 0) : 0;
        worst = bits > worst ? bits : worst;
    }
    const sluice_real nu_max = sluice_util_from_bits(worst);
    if (nu_max != nu_max)
        return nu_max; /* NaN: let the watchdog stop the run */
    return nu_max > 0 ? (sluice_real)0.125 * s->h * s->h / nu_max : (sluice_real)INFINITY;
}

static const sluice_component components[] = {{
    .name = "turbulent_stress",
    .summary = "Reynolds stress 2 rho nu_T S in the momentum equation (tensor form of seed 004 "
               "or eddy-viscosity Laplacian form)",
    .reference = "seed 004 (De Padova et al. 2017), eq. 1; Lo & Shao (2002); Shao & Gotoh (2005)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(ts_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = ts_create,
    .destroy = ts_destroy,
    .bind = ts_bind,
    .pair = ts_pair,
    .time_step_limit = ts_time_step_limit,
}};

SLUICE_DEFINE_LIBRARY("turbulent_stress", "1.0.0", "turbulent (Reynolds) stress",
                      SLUICE_DIMS_ALL, components)
