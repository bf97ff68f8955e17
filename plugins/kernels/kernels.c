/* Smoothing kernels with support 2h: Wendland C2 and the cubic B-spline.
 * Each evaluates W and F = (dW/dr)/r for a batch of distances, so that the
 * gradient is grad_i W_ij = r_ij F. Normalisation (integral of W = 1):
 *   Wendland C2: a = 7/(4 pi h^2) (2D), 21/(16 pi h^3) (3D)
 *   cubic B-spline: a = 10/(7 pi h^2) (2D), 1/(pi h^3) (3D)
 * (seed 000 prints constants 9/4 too large; these are the normalised ones). */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct kernel_state {
    sluice_real h, inverse_h, normalisation, gradient_normalisation;
} kernel_state;

static int kernel_create(const sluice_api *api, sluice_host *host, double n2, double n3,
                         void **state)
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
    sluice_real support = 2;
    if (api->fields->publish_constant(host, "kernel_support", &support, 1, "1") != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
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
        .name = "cubic_spline",
        .summary = "cubic B-spline kernel, support 2h (seed 000)",
        .reference = "Monaghan & Lattanzio (1985); seed 000 eq. 10 with normalised constants",
        .dimensions = SLUICE_DIMS_ALL,
        .create = cubic_create,
        .destroy = kernel_destroy,
        .kernel = cubic_kernel,
    },
};

SLUICE_DEFINE_LIBRARY("kernels", "1.0.0", "SPH smoothing kernels", SLUICE_DIMS_ALL, components)
