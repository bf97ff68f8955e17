/* Kernel gradient renormalisation (Randles & Libersky 1996; Bonet & Lok
 * 1999), used by seed 004 (De Padova et al. 2017) in every term except the
 * pressure gradient. For every fluid and wall particle i it writes the
 * matrix L_i of the shared contract (field kernel_correction, row-major,
 * component a*dims + b = L_ab):
 *
 *   M_i = sum_j V_j (grad_i W_ij) (x) (x_j - x_i) = - sum_j V_j F_ij r_ij (x) r_ij,
 *   L_i = M_i^-1,    V_j = m_j / rho_j,  grad_i W_ij = r_ij F_ij,
 *
 * over fluid and wall neighbours, so that the renormalised gradient
 * (grad^_i W_ij)_a = sum_b L_ab (r_ij F_ij)_b makes
 * sum_j V_j (f_j - f_i) grad^_i W_ij exact for every linear f. M is
 * symmetric and positive semi-definite (F <= 0), and close to the identity
 * wherever the kernel support is full.
 *
 * Near-singular M (free-surface spray, isolated particles, a single row of
 * particles): with lambda the smallest eigenvalue of M,
 *   lambda >= regular_above:  L = M^-1,
 *   lambda <= singular_below: L = I (the uncorrected gradient),
 *   between:                  L = s M^-1 + (1 - s) I,  s = t^2 (3 - 2 t),
 *                             t = (lambda - singular_below) / (regular_above - singular_below),
 * a C1 blend. M is inverted only when lambda > singular_below > 0, so the
 * largest entry of L is bounded (by 1/singular_below) and nothing divides by a
 * vanishing determinant. A lone particle (M = 0), one neighbour, or
 * neighbours on one line (2D) or in one plane (3D) give lambda = 0 and L = I.
 * On a lattice with h/dx in [1.2, 1.5] lambda is about 1 inside, 0.5 at a
 * flat free surface and 0.18 to 0.29 at a corner, so the defaults renormalise
 * all of these fully. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct kc_config {
    sluice_real singular_below, regular_above;
} kc_config;

typedef struct kc_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_real low, high;
    sluice_field density, mass, correction;
} kc_state;

static const sluice_param_spec params[] = {
    {"singular_below", SLUICE_PARAM_REAL, offsetof(kc_config, singular_below), "0.05", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "smallest eigenvalue of M = sum_j V_j grad_i W_ij (x) x_ji (about 1 in a full support) "
     "at or below which L = I",
     NULL, 0},
    {"regular_above", SLUICE_PARAM_REAL, offsetof(kc_config, regular_above), "0.15", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "smallest eigenvalue of M at or above which L = M^-1 (blended in between)", NULL, 0},
};

static int kc_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const kc_config *c = config;
    if (!(c->regular_above > c->singular_below)) {
        api->messages->error(host, "regular_above (%g) must be larger than singular_below (%g)",
                   (double)c->regular_above, (double)c->singular_below);
        return SLUICE_ERROR;
    }
    kc_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->low = c->singular_below;
    s->high = c->regular_above;
    if (sluice_util_dimensions(api, host, &s->dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    const sluice_field_spec fields[] = {
        SLUICE_SPEC_DENSITY(SLUICE_READ_NEIGHBOUR),
        SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
        SLUICE_SPEC_KERNEL_CORRECTION_DOC(
            s->dims, SLUICE_WRITE,
            "renormalisation matrix L = [sum_j V_j grad_i W_ij (x) (x_j - x_i)]^-1, row-major"),
    };
    for (int f = 0; f < 3; f++)
        if (api->fields->declare_field(host, &fields[f]) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
    *state = s;
    return SLUICE_OK;
}

static int kc_bind(void *state, sluice_host *host)
{
    kc_state *s = state;
    const sluice_field_binding fields[] = {
        {"density", &s->density}, {"mass", &s->mass}, {"kernel_correction", &s->correction}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void kc_destroy(void *state)
{
    free(state);
}

/* Weight of M^-1 in the blend from the smallest eigenvalue (NaN propagates). */
static inline sluice_real blend(sluice_real lambda, sluice_real low, sluice_real high)
{
    const sluice_real t = (lambda - low) / (high - low);
    if (t <= 0)
        return 0;
    if (t >= 1)
        return 1;
    return t * t * (3 - 2 * t);
}

/* Smallest eigenvalue of the symmetric 3x3 matrix [[a, d, e], [d, b, f], [e, f, c]]
 * (trigonometric solution of the characteristic cubic; Smith 1961). */
static sluice_real smallest_eigenvalue_3(sluice_real a, sluice_real b, sluice_real c,
                                         sluice_real d, sluice_real e, sluice_real f)
{
    const sluice_real off = d * d + e * e + f * f;
    if (off == 0) {
        sluice_real m = a < b ? a : b;
        return m < c ? m : c;
    }
    const sluice_real q = (a + b + c) / 3;
    const sluice_real p2 = (a - q) * (a - q) + (b - q) * (b - q) + (c - q) * (c - q) + 2 * off;
    const sluice_real p = sqrt(p2 / 6);
    /* B = (A - q I) / p; r = det(B) / 2 in [-1, 1] */
    const sluice_real ba = (a - q) / p, bb = (b - q) / p, bc = (c - q) / p;
    const sluice_real bd = d / p, be = e / p, bf = f / p;
    sluice_real r =
        (ba * (bb * bc - bf * bf) - bd * (bd * bc - bf * be) + be * (bd * bf - bb * be)) / 2;
    r = r < -1 ? -1 : r > 1 ? 1 : r;
    const sluice_real angle = acos(r) / 3;
    return q + 2 * p * cos(angle + (sluice_real)(2 * SLUICE_PI / 3));
}

/* L from the moment matrix of one target, written row-major to out[c][i]. */
static inline void write_2d(const kc_state *s, sluice_real *const *out, sluice_index i,
                            sluice_real a, sluice_real b, sluice_real d)
{
    /* M = [[a, b], [b, d]]; Gershgorin's bound spares the eigenvalue inside */
    const sluice_real ab = b < 0 ? -b : b;
    const sluice_real bound = (a < d ? a : d) - ab;
    sluice_real w = 1;
    if (!(bound >= s->high)) {
        const sluice_real half = (sluice_real)0.5 * (a - d);
        const sluice_real lambda = (sluice_real)0.5 * (a + d) - sqrt(half * half + b * b);
        w = blend(lambda, s->low, s->high);
    }
    if (w == 0) {
        out[0][i] = 1;
        out[1][i] = 0;
        out[2][i] = 0;
        out[3][i] = 1;
        return;
    }
    const sluice_real scale = w / (a * d - b * b);
    out[0][i] = scale * d + (1 - w);
    out[1][i] = -scale * b;
    out[2][i] = -scale * b;
    out[3][i] = scale * a + (1 - w);
}

static inline void write_3d(const kc_state *s, sluice_real *const *out, sluice_index i,
                            sluice_real a, sluice_real b, sluice_real c, sluice_real d,
                            sluice_real e, sluice_real f)
{
    /* M = [[a, d, e], [d, b, f], [e, f, c]] */
    const sluice_real ad = d < 0 ? -d : d, ae = e < 0 ? -e : e, af = f < 0 ? -f : f;
    sluice_real bound = a - ad - ae;
    bound = b - ad - af < bound ? b - ad - af : bound;
    bound = c - ae - af < bound ? c - ae - af : bound;
    sluice_real w = 1;
    if (!(bound >= s->high))
        w = blend(smallest_eigenvalue_3(a, b, c, d, e, f), s->low, s->high);
    if (w == 0) {
        for (int k = 0; k < 9; k++)
            out[k][i] = k % 4 == 0 ? 1 : 0;
        return;
    }
    /* adjugate (symmetric) */
    const sluice_real c00 = b * c - f * f, c01 = e * f - d * c, c02 = d * f - b * e;
    const sluice_real c11 = a * c - e * e, c12 = d * e - a * f, c22 = a * b - d * d;
    const sluice_real scale = w / (a * c00 + d * c01 + e * c02);
    out[0][i] = scale * c00 + (1 - w);
    out[1][i] = scale * c01;
    out[2][i] = scale * c02;
    out[3][i] = scale * c01;
    out[4][i] = scale * c11 + (1 - w);
    out[5][i] = scale * c12;
    out[6][i] = scale * c02;
    out[7][i] = scale * c12;
    out[8][i] = scale * c22 + (1 - w);
}

static inline void kc_pairs(const kc_state *s, const sluice_view *v, const sluice_pair_batch *b,
                            const uint32_t dims)
{
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    sluice_real *out[9];
    for (uint32_t c = 0; c < dims * dims; c++)
        out[c] = sluice_real_column(v, s->correction, c);
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        sluice_real mxx = 0, myy = 0, mzz = 0, mxy = 0, mxz = 0, myz = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            /* M += V_j (r_ij F) (x) (-r_ij) */
            const sluice_real w = -mj[k] / rhoj[k] * F[k];
            mxx += w * rx[k] * rx[k];
            myy += w * ry[k] * ry[k];
            mxy += w * rx[k] * ry[k];
            if (dims == 3) {
                mzz += w * rz[k] * rz[k];
                mxz += w * rx[k] * rz[k];
                myz += w * ry[k] * rz[k];
            }
        }
        if (dims == 3)
            write_3d(s, out, i, mxx, myy, mzz, mxy, mxz, myz);
        else
            write_2d(s, out, i, mxx, mxy, myy);
    }
}

static void kc_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    if (v->dimensions == 3)
        kc_pairs(state, v, b, 3);
    else
        kc_pairs(state, v, b, 2);
}

static const sluice_component components[] = {{
    .name = "kernel_correction",
    .summary = "renormalised kernel gradient matrix L (first-order consistent gradients)",
    .reference = "Randles & Libersky (1996); Bonet & Lok (1999); seed 004 (De Padova et al. 2017)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(kc_config),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = kc_create,
    .destroy = kc_destroy,
    .bind = kc_bind,
    .pair = kc_pair,
}};

SLUICE_DEFINE_LIBRARY("kernel_correction", "1.0.0", "kernel gradient renormalisation",
                      SLUICE_DIMS_ALL, components)
