/* Smoothing kernels: Wendland C2 (the "quintic Wendland" of DualSPHysics and
 * of seed 002, also loadable under that name) and the cubic B-spline, with
 * support 2h, and the quintic spline (Morris, Fox & Zhu 1997), support 3h.
 * Each evaluates W and F = (dW/dr)/r for a batch of distances, so that the
 * gradient is grad_i W_ij = r_ij F, and publishes its support
 * (`kernel_support`, in units of h). Normalisation (integral of W = 1):
 *   Wendland C2: a = 7/(4 pi h^2) (2D), 21/(16 pi h^3) (3D)
 *   cubic B-spline: a = 10/(7 pi h^2) (2D), 1/(pi h^3) (3D)
 *   quintic spline: a = 7/(478 pi h^2) (2D), 1/(120 pi h^3) (3D; the
 *   3/(359 pi h^3) often quoted integrates to 1.0028)
 * (seed 000 prints constants 9/4 too large; these are the normalised ones). */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct kernel_state {
    sluice_real h, inverse_h, normalisation, gradient_normalisation;
} kernel_state;

static int kernel_create_support(const sluice_api *api, sluice_host *host, double n2,
                                 double n3, sluice_real support, void **state)
{
    kernel_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    sluice_real h, dims;
    if (sluice_util_constant(api, host, "smoothing_length", &h) != SLUICE_OK ||
        sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->h = h;
    s->inverse_h = 1 / h;
    s->normalisation = dims == 3 ? (sluice_real)(n3 / (h * h * h)) : (sluice_real)(n2 / (h * h));
    s->gradient_normalisation = s->normalisation / (h * h);
    if (api->fields->publish_constant(host, "kernel_support", &support, 1, "1") != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int kernel_create(const sluice_api *api, sluice_host *host, double n2, double n3,
                         void **state)
{
    return kernel_create_support(api, host, n2, n3, 2, state);
}

static void kernel_destroy(void *state)
{
    free(state);
}

/* ------------------------------------------------------------ Wendland C2 -- */

static int wendland_create(const sluice_api *api, sluice_host *host, const void *config,
                           void **state)
{
    (void)config;
    return kernel_create(api, host, 7.0 / (4.0 * SLUICE_PI), 21.0 / (16.0 * SLUICE_PI), state);
}

/* W = a (1 - q/2)^4 (2q + 1), F = -5 a (1 - q/2)^3 / h^2, q = r/h <= 2 */
static void wendland_kernel(void *state, sluice_index n, const sluice_real *restrict r2,
                            sluice_real *restrict r, sluice_real *restrict w,
                            sluice_real *restrict f)
{
    const kernel_state *s = state;
    const sluice_real ih = s->inverse_h, a = s->normalisation, b = -5 * s->gradient_normalisation;
    if (w) {
#pragma omp simd
        for (sluice_index k = 0; k < n; k++) {
            r[k] = sqrt(r2[k]);
            sluice_real q = r[k] * ih;
            sluice_real t = 1 - (sluice_real)0.5 * q;
            t = t > 0 ? t : 0;
            sluice_real t3 = t * t * t;
            w[k] = a * t3 * t * (2 * q + 1);
            f[k] = b * t3;
        }
    } else {
#pragma omp simd
        for (sluice_index k = 0; k < n; k++) {
            r[k] = sqrt(r2[k]);
            sluice_real t = 1 - (sluice_real)0.5 * r[k] * ih;
            t = t > 0 ? t : 0;
            f[k] = b * t * t * t;
        }
    }
}

/* -------------------------------------------------------- cubic B-spline -- */

static int cubic_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    (void)config;
    return kernel_create(api, host, 10.0 / (7.0 * SLUICE_PI), 1.0 / SLUICE_PI, state);
}

/* W = a (1 - 1.5 q^2 + 0.75 q^3) for q < 1, a 0.25 (2 - q)^3 for 1 <= q < 2.
 * F = (a / h^2) (-3 + 2.25 q) for q < 1, (a / h^2) (-0.75 (2 - q)^2 / q) beyond. */
static void cubic_kernel(void *state, sluice_index n, const sluice_real *restrict r2,
                         sluice_real *restrict r, sluice_real *restrict w, sluice_real *restrict f)
{
    const kernel_state *s = state;
    const sluice_real ih = s->inverse_h, a = s->normalisation, g = s->gradient_normalisation;
#pragma omp simd
    for (sluice_index k = 0; k < n; k++) {
        r[k] = sqrt(r2[k]);
        sluice_real q = r[k] * ih;
        sluice_real t = 2 - q;
        t = t > 0 ? t : 0;
        sluice_real inner_f = -3 + (sluice_real)2.25 * q;
        sluice_real outer_f = (sluice_real)-0.75 * t * t / (q > (sluice_real)1e-12 ? q : 1);
        f[k] = g * (q < 1 ? inner_f : outer_f);
        if (w) {
            sluice_real inner_w = 1 - (sluice_real)1.5 * q * q + (sluice_real)0.75 * q * q * q;
            sluice_real outer_w = (sluice_real)0.25 * t * t * t;
            w[k] = a * (q < 1 ? inner_w : outer_w);
        }
    }
}

/* -------------------------------------------------------- quintic spline -- */

static int quintic_create(const sluice_api *api, sluice_host *host, const void *config,
                          void **state)
{
    (void)config;
    return kernel_create_support(api, host, 7.0 / (478.0 * SLUICE_PI), 1.0 / (120.0 * SLUICE_PI),
                                 3, state);
}

/* W = a [(3 - q)^5 - 6 (2 - q)^5 + 15 (1 - q)^5], each term only while its
 * base is positive (q < 3, 2, 1). dW/dq = -5 a [(3 - q)^4 - 6 (2 - q)^4 +
 * 15 (1 - q)^4]; for q < 1 it is a (-120 q + 120 q^3 - 50 q^4), so that
 * F = (dW/dq) / (h^2 q) = (a / h^2) (-120 + 120 q^2 - 50 q^3) there, finite
 * at q = 0; beyond, F = (dW/dq) / (h^2 q) with q >= 1. */
static void quintic_kernel(void *state, sluice_index n, const sluice_real *restrict r2,
                           sluice_real *restrict r, sluice_real *restrict w,
                           sluice_real *restrict f)
{
    const kernel_state *s = state;
    const sluice_real ih = s->inverse_h, a = s->normalisation, g = s->gradient_normalisation;
#pragma omp simd
    for (sluice_index k = 0; k < n; k++) {
        r[k] = sqrt(r2[k]);
        const sluice_real q = r[k] * ih;
        sluice_real t3 = 3 - q, t2 = 2 - q, t1 = 1 - q;
        t3 = t3 > 0 ? t3 : 0;
        t2 = t2 > 0 ? t2 : 0;
        t1 = t1 > 0 ? t1 : 0;
        const sluice_real t3_4 = t3 * t3 * t3 * t3, t2_4 = t2 * t2 * t2 * t2;
        const sluice_real inner_f = -120 + 120 * q * q - 50 * q * q * q;
        const sluice_real outer_f = -5 * (t3_4 - 6 * t2_4) / (q > 1 ? q : 1);
        f[k] = g * (q < 1 ? inner_f : outer_f);
        if (w) {
            const sluice_real t1_4 = t1 * t1 * t1 * t1;
            w[k] = a * (t3_4 * t3 - 6 * t2_4 * t2 + 15 * t1_4 * t1);
        }
    }
}

static const sluice_component components[] = {
    {
        .name = "wendland_c2",
        .summary = "Wendland C2 kernel, support 2h (seeds 001, 002, 004)",
        .reference = "Wendland (1995); W = a (1 - q/2)^4 (2q + 1)",
        .dimensions = SLUICE_DIMS_ALL,
        .create = wendland_create,
        .destroy = kernel_destroy,
        .kernel = wendland_kernel,
    },
    {
        .name = "quintic_wendland",
        .summary = "the Wendland C2 kernel under the name DualSPHysics gives it (a quintic "
                   "polynomial, support 2h; seed 002)",
        .reference = "Wendland (1995); W = a (1 - q/2)^4 (2q + 1), as wendland_c2",
        .dimensions = SLUICE_DIMS_ALL,
        .create = wendland_create,
        .destroy = kernel_destroy,
        .kernel = wendland_kernel,
    },
    {
        .name = "quintic_spline",
        .summary = "quintic spline kernel, support 3h",
        .reference = "Morris, Fox & Zhu (1997), J. Comput. Phys. 136:214-226",
        .dimensions = SLUICE_DIMS_ALL,
        .create = quintic_create,
        .destroy = kernel_destroy,
        .kernel = quintic_kernel,
    },
    {
        .name = "cubic_spline",
        .summary = "cubic B-spline kernel, support 2h (seed 000)",
        .reference = "Monaghan & Lattanzio (1985); seed 000 eq. 10 with normalised constants",
        .dimensions = SLUICE_DIMS_ALL,
        .create = cubic_create,
        .destroy = kernel_destroy,
        .kernel = cubic_kernel,
    },
};

SLUICE_DEFINE_LIBRARY("kernels", "1.1.0", "SPH smoothing kernels", SLUICE_DIMS_ALL, components)
