/* sluice-analyze: the hydraulic-jump measurements (tools/analyze/hydraulics.c)
 * against answers that cannot be fitted, and the program itself on a small
 * synthetic run directory.
 *  - reference relations at the hand values the seeds print: Belanger's
 *    d2 = 0.0864 m for Fr1 = 3.39, d1 = 0.02 m (seed 000), and conservation of
 *    the momentum function across the jump to round-off; Hager's
 *    L_r = 0.2988 m for Fr1 = 3.4 (seed 000, section 3); the constants of the
 *    Chanson, Murzyn & Chanson and Chachereau & Chanson relations at points
 *    where they reduce to the bare constant;
 *  - seed 000's A and P: A = 1, P = 0 on the theory, the analytic values for a
 *    constant offset and for a sinusoid sampled over whole periods;
 *  - FFT: against a direct DFT, Parseval, inverse; a bin-centred tone gives
 *    its frequency and amplitude exactly (detrending and the Hann window
 *    included), an off-bin tone with zero padding its frequency within half a
 *    bin and its amplitude within the Hann scalloping loss;
 *  - Pearson r: 1 with itself, -1 with its negative, 1/sqrt(1 + c^2) for
 *    sin and sin + c cos over whole periods;
 *  - toe detection on a tanh front moving at a known speed: every x1(t)
 *    within the linear-interpolation bound derived below;
 *  - roller end and Vmax decay on synthetic time-dependent velocity fields;
 *  - free-surface mean/std; seed 002's L2 and RMSE on profiles with a known
 *    error;
 *  - the momentum limits at an abrupt drop: Belanger at s = 0, and the order
 *    they give seed 004's table 1 (see drop_table1);
 *  - the CLI: headline numbers, CSV written, and one message with exit 2 on
 *    a missing run, file or column;
 *  - stepped chutes (seed 001): the velocity along the pseudo-bottom and the
 *    distance along its normal; Y90, the clear-water depth d and C_mean to
 *    the trapezoid rule's known error on a quadratic air-concentration
 *    profile (exact on a linear one); step-profiles on a synthetic point
 *    gauge CSV (power-law velocity, stepped air-concentration profiles,
 *    dry samples, rows outside the window): the time means, Y90, d,
 *    C_mean, the inception edge, the shallow-Y90 warning and bad input. */
#include <math.h>
#include <stdint.h>

#include "hydraulics.h"
#include "test_util.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define G 9.81

/* ---------------------------------------------------- reference relations */

START_TEST(belanger_seed000)
{
    /* seed 000, section 1: v1 = 1.5 m/s, d1 = 0.02 m, Fr1 ~ 3.39, d2 = 0.0864 m
     * (printed to 4 decimals: +-5e-5 m) */
    double fr = sluice_hyd_froude(1.5, 0.02, G);
    double d2 = sluice_hyd_belanger_depth(0.02, 3.39);
    fprintf(stderr, "belanger: Fr1(1.5 m/s, 0.02 m) = %.5f, d2(Fr1 = 3.39) = %.6f m\n", fr, d2);
    ck_assert_double_eq_tol(fr, 3.39, 5e-3);
    ck_assert_double_eq_tol(d2, 0.0864, 5e-5);
    /* momentum function M = d^2/2 + q^2/(g d) per unit width is the same on
     * both sides of the jump (the definition Belanger's relation solves) */
    const double frs[] = {1.2, 3.39, 8.0, 15.0};
    for (size_t i = 0; i < sizeof frs / sizeof *frs; i++) {
        double d1 = 0.02, v1 = frs[i] * sqrt(G * d1), q = v1 * d1;
        double d2i = sluice_hyd_belanger_depth(d1, frs[i]);
        double m1 = d1 * d1 / 2 + q * q / (G * d1), m2 = d2i * d2i / 2 + q * q / (G * d2i);
        ck_assert_double_eq_tol(m2 / m1, 1.0, 1e-13);
        ck_assert(d2i > d1);
    }
    ck_assert_double_eq_tol(sluice_hyd_belanger_depth(0.02, 1.0), 0.02, 1e-16);
}
END_TEST

START_TEST(reference_relations)
{
    /* seed 000, section 3: L_r,THEORY = 0.2988 m from eq. 2 with Fr1 ~ 3.4 */
    double lr = sluice_hyd_hager_roller_length(0.02, 3.4);
    fprintf(stderr, "hager: L_r(d1 = 0.02, Fr1 = 3.4) = %.5f m (seed 000: 0.2988 m)\n", lr);
    ck_assert_double_eq_tol(lr, 0.2988, 5e-5);
    /* Chanson: 1 at the toe, 1/e at (x - x1)/d1 = 1/0.028 */
    ck_assert_double_eq_tol(sluice_hyd_chanson_vmax_ratio(0.0), 1.0, 1e-15);
    ck_assert_double_eq_tol(sluice_hyd_chanson_vmax_ratio(1.0 / 0.028), exp(-1.0), 1e-15);
    /* Murzyn & Chanson: 0.116 at Fr1 = 2 ((Fr1 - 1)^1.235 = 1), and the
     * exponent from the ratio at Fr1 = 3 and 2 (2^1.235) */
    ck_assert_double_eq_tol(sluice_hyd_murzyn_chanson_eta_std(2.0), 0.116, 1e-15);
    ck_assert_double_eq_tol(log(sluice_hyd_murzyn_chanson_eta_std(3.0) / 0.116) / log(2.0),
                            1.235, 1e-12);
    /* Chachereau & Chanson: 0.143 exp(-0.27 Fr1): 0.143/e at Fr1 = 1/0.27 */
    ck_assert_double_eq_tol(sluice_hyd_chachereau_chanson_strouhal(1.0 / 0.27),
                            0.143 * exp(-1.0), 1e-15);
    ck_assert_double_eq_tol(sluice_hyd_chachereau_chanson_strouhal(0.0), 0.143, 1e-15);
}
END_TEST

/* ------------------------------------------------------------ A and P */

START_TEST(conjugate_statistics)
{
    enum { N = 400 };
    double d[N], A, P, th = 0.0864;
    size_t used;
    for (int i = 0; i < N; i++)
        d[i] = th;
    /* A = 1 up to the round-off of summing N equal squares (N eps), P = 0
     * exactly (every difference is 0) */
    ck_assert_int_eq(sluice_hyd_conjugate_statistics(d, N, th, &A, &P, &used), 0);
    ck_assert_double_eq_tol(A, 1.0, N * 2.3e-16);
    ck_assert(P == 0.0);
    /* constant offset: A = 1 + delta/th, P = |delta|/th */
    double delta = -0.004;
    for (int i = 0; i < N; i++)
        d[i] = th + delta;
    sluice_hyd_conjugate_statistics(d, N, th, &A, &P, &used);
    ck_assert_double_eq_tol(A, 1.0 + delta / th, 1e-14);
    ck_assert_double_eq_tol(P, -delta / th, 1e-14);
    /* d = th (1 + a sin) over 8 whole periods: sum sin = 0, sum sin^2 = N/2,
     * so A = sqrt(1 + a^2/2), P = a/sqrt(2) */
    double a = 0.07;
    for (int i = 0; i < N; i++)
        d[i] = th * (1.0 + a * sin(2.0 * M_PI * 8.0 * i / N));
    sluice_hyd_conjugate_statistics(d, N, th, &A, &P, &used);
    fprintf(stderr, "A, P (sinusoid a = %.2f): %.15f %.15f\n", a, A, P);
    ck_assert_double_eq_tol(A, sqrt(1.0 + a * a / 2.0), 1e-13);
    ck_assert_double_eq_tol(P, a / sqrt(2.0), 1e-13);
    /* NaN samples (a dry gauge) are left out of both sums */
    d[3] = NAN;
    d[7] = NAN;
    ck_assert_int_eq(sluice_hyd_conjugate_statistics(d, N, th, &A, &P, &used), 0);
    ck_assert_uint_eq(used, N - 2);
    ck_assert_int_eq(sluice_hyd_conjugate_statistics(d, N, 0.0, &A, &P, &used), -1);
}
END_TEST

/* ----------------------------------------------------------------- FFT */

/* Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG, Knuth's MMIX). */
static double lcg(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) / 4503599627370496.0 - 1.0;
}

START_TEST(fft_dft_parseval)
{
    enum { N = 256 };
    double re[N], im[N], xr[N], xi[N];
    uint64_t s = 12345;
    double energy = 0.0;
    for (int k = 0; k < N; k++) {
        xr[k] = re[k] = lcg(&s);
        xi[k] = im[k] = lcg(&s);
        energy += xr[k] * xr[k] + xi[k] * xi[k];
    }
    ck_assert_int_eq(sluice_hyd_fft(re, im, N, 0), 0);
    /* direct DFT: the FFT's round-off is O(eps log2 N) times the norm */
    double worst = 0.0, spectral = 0.0;
    for (int j = 0; j < N; j++) {
        double sr = 0.0, si = 0.0;
        for (int k = 0; k < N; k++) {
            double angle = -2.0 * M_PI * (double)((j * k) % N) / N;
            sr += xr[k] * cos(angle) - xi[k] * sin(angle);
            si += xr[k] * sin(angle) + xi[k] * cos(angle);
        }
        worst = fmax(worst, hypot(re[j] - sr, im[j] - si));
        spectral += re[j] * re[j] + im[j] * im[j];
    }
    fprintf(stderr, "fft: max |FFT - DFT| = %.3g, Parseval rel. error = %.3g\n", worst,
            fabs(spectral / N - energy) / energy);
    ck_assert(worst < 1e-12 * sqrt(energy) * N);
    ck_assert_double_eq_tol(spectral / N, energy, 1e-12 * energy);
    ck_assert_int_eq(sluice_hyd_fft(re, im, N, 1), 0);
    for (int k = 0; k < N; k++) {
        ck_assert_double_eq_tol(re[k] / N, xr[k], 1e-13);
        ck_assert_double_eq_tol(im[k] / N, xi[k], 1e-13);
    }
    ck_assert_int_eq(sluice_hyd_fft(re, im, 100, 0), -1);
    ck_assert_uint_eq(sluice_hyd_next_pow2(1000), 1024);
    ck_assert_uint_eq(sluice_hyd_next_pow2(1024), 1024);
}
END_TEST

START_TEST(spectrum_bin_centred)
{
    /* n = 1024 samples, dt = 0.01 s: df = 1/(n dt); a tone at bin 37 plus an
     * offset and a linear trend. The tone is a cosine symmetric about the
     * window's centre, so it is orthogonal to the least-squares line: the
     * detrending removes exactly offset + trend and the Hann window (periodic,
     * coherent gain sum w) leaves amplitude a at bin 37, zero elsewhere except
     * bins 36 and 38 (a/2: the Hann main lobe). */
    enum { N = 1024 };
    static double x[N], re[N], im[N], amp[N / 2 + 1];
    double dt = 0.01, a = 0.3, df;
    double f0 = 37.0 / (N * dt), tc = 0.5 * (N - 1) * dt;
    for (int k = 0; k < N; k++)
        x[k] = 2.0 + 0.5 * k * dt + a * cos(2.0 * M_PI * f0 * (k * dt - tc));
    ck_assert_int_eq(sluice_hyd_amplitude_spectrum(x, N, dt, re, im, amp, &df), 0);
    size_t peak = sluice_hyd_spectrum_peak(amp, N / 2 + 1, df, 0.0, 0.0);
    fprintf(stderr, "spectrum: peak bin %zu at %.6f Hz (tone %.6f Hz), amplitude %.15f (a = %g)\n",
            peak, peak * df, f0, amp[peak], a);
    ck_assert_uint_eq(peak, 37);
    ck_assert_double_eq_tol(peak * df, f0, 1e-12);
    ck_assert_double_eq_tol(amp[peak], a, 1e-12);
    ck_assert_double_eq_tol(amp[36], a / 2, 1e-12);
    ck_assert_double_eq_tol(amp[38], a / 2, 1e-12);
    for (int j = 0; j <= N / 2; j++)
        if (j < 36 || j > 38)
            ck_assert(amp[j] < 1e-12);
    /* the band limits restrict the search: above 36.5 bins the peak is 37,
     * below it the main-lobe bin 36 (a/2 against round-off elsewhere) */
    ck_assert_uint_eq(sluice_hyd_spectrum_peak(amp, N / 2 + 1, df, 36.5 * df, 0.0), 37);
    ck_assert_uint_eq(sluice_hyd_spectrum_peak(amp, N / 2 + 1, df, 0.0, 36.5 * df), 36);
}
END_TEST

START_TEST(spectrum_off_bin_zero_padded)
{
    /* n = 1000 samples padded to m = 1024: bins every 1/(m dt). A tone
     * between bins is found at the nearest bin, within half a bin, with an
     * amplitude between a H(d) and a, H the Hann window's response at the
     * largest offset d = n/(2m) (in bins of n), computed here by direct
     * summation of the window (-> sinc(d)/(1 - d^2) = 0.8488 at d = 1/2 for
     * large n). The negative-frequency image (2 x 123 bins away) and the
     * detrended mean leak through Hann side lobes of order 1/(pi d^3) < 1e-6. */
    enum { N = 1000, M = 1024 };
    static double x[N], re[M], im[M], amp[M / 2 + 1];
    double dt = 0.01, a = 1.7, df;
    double f0 = 123.4567 / (N * dt), tc = 0.5 * (N - 1) * dt;
    for (int k = 0; k < N; k++)
        x[k] = a * cos(2.0 * M_PI * f0 * (k * dt - tc));
    ck_assert_int_eq(sluice_hyd_amplitude_spectrum(x, N, dt, re, im, amp, &df), 0);
    ck_assert_double_eq_tol(df, 1.0 / (M * dt), 1e-15);
    size_t peak = sluice_hyd_spectrum_peak(amp, M / 2 + 1, df, 0.0, 0.0);
    double d = 0.5 * (double)N / M, sr = 0.0, si = 0.0, sw = 0.0;
    for (int k = 0; k < N; k++) {
        double w = 0.5 * (1.0 - cos(2.0 * M_PI * k / N));
        sr += w * cos(2.0 * M_PI * d * k / N);
        si += w * sin(2.0 * M_PI * d * k / N);
        sw += w;
    }
    double loss = hypot(sr, si) / sw;
    fprintf(stderr,
            "spectrum (padded): peak %.5f Hz vs tone %.5f Hz (df %.5f), amplitude %.5f, bound "
            "[%.5f, %.5f]\n",
            peak * df, f0, df, amp[peak], a * loss, a);
    ck_assert(fabs(peak * df - f0) <= 0.5 * df + 1e-12);
    ck_assert(amp[peak] >= a * loss * (1.0 - 1e-6));
    ck_assert(amp[peak] <= a * (1.0 + 1e-6));
    ck_assert(loss > 0.8488 && loss < 0.8489 + 0.02);
}
END_TEST

START_TEST(detrend_and_resample)
{
    enum { N = 50 };
    double x[N];
    for (int k = 0; k < N; k++)
        x[k] = 3.0 - 0.25 * k;
    sluice_hyd_detrend(x, N);
    for (int k = 0; k < N; k++)
        ck_assert_double_eq_tol(x[k], 0.0, 1e-13);
    /* resampling a linear signal with gaps (NaN) is exact */
    double t[N], y[N], out[37];
    for (int k = 0; k < N; k++) {
        t[k] = 0.1 * k + 0.01 * (k % 3);
        y[k] = (k % 7 == 3) ? NAN : 2.0 * t[k] - 1.0;
    }
    ck_assert_int_eq(sluice_hyd_resample(t, y, N, 0.3, 4.5, 37, out), 0);
    for (int k = 0; k < 37; k++)
        ck_assert_double_eq_tol(out[k], 2.0 * (0.3 + k * (4.2 / 36)) - 1.0, 1e-12);
}
END_TEST

/* --------------------------------------------------------- correlation */

START_TEST(pearson)
{
    enum { N = 360 };
    double a[N], b[N], c[N];
    for (int i = 0; i < N; i++) {
        double phase = 2.0 * M_PI * 5.0 * i / N; /* five whole periods */
        a[i] = sin(phase);
        b[i] = -3.0 * a[i] + 1.0;
        c[i] = cos(phase);
    }
    size_t used;
    ck_assert_double_eq_tol(sluice_hyd_pearson(a, a, N, &used), 1.0, 1e-14);
    ck_assert_double_eq_tol(sluice_hyd_pearson(a, b, N, &used), -1.0, 1e-14);
    /* sin and cos are orthogonal over whole periods */
    ck_assert_double_eq_tol(sluice_hyd_pearson(a, c, N, &used), 0.0, 1e-13);
    /* sin against sin + k cos: r = 1/sqrt(1 + k^2) */
    double k = 0.75;
    for (int i = 0; i < N; i++)
        b[i] = a[i] + k * c[i];
    double r = sluice_hyd_pearson(a, b, N, &used);
    fprintf(stderr, "pearson(sin, sin + 0.75 cos) = %.15f (exact %.15f)\n", r,
            1.0 / sqrt(1.0 + k * k));
    ck_assert_double_eq_tol(r, 1.0 / sqrt(1.0 + k * k), 1e-13);
    /* a pair with a NaN is left out; a constant series has no r */
    b[10] = NAN;
    sluice_hyd_pearson(a, b, N, &used);
    ck_assert_uint_eq(used, N - 1);
    for (int i = 0; i < N; i++)
        c[i] = 2.0;
    ck_assert(isnan(sluice_hyd_pearson(a, c, N, &used)));
}
END_TEST

/* ------------------------------------------------------------------ toe */

/* Depth of a front d1 + (d2 - d1)/2 (1 + tanh((x - X)/L)) crossing the
 * threshold d1 + f (d2 - d1) at x_c = X + L atanh(2f - 1). Linear
 * interpolation between gauges Delta apart differs from the depth by at most
 * E = Delta^2/8 max|h''|, max|h''| = (d2 - d1)/(2 L^2) 4/(3 sqrt 3); the
 * interpolated crossing is then within E / min h' of x_c, the minimum of
 * h' = (d2 - d1)/(2L) sech^2 over |x - X| <= |x_c - X| + Delta:
 *   |x1 - x_c| <= Delta^2 (4/(3 sqrt 3)) / (8 L sech^2(|x_c - X|/L + Delta/L)). */
static double toe_bound(double delta, double L, double offset)
{
    double s = 1.0 / cosh(fabs(offset) / L + delta / L);
    return delta * delta * (4.0 / (3.0 * sqrt(3.0))) / (8.0 * L * s * s);
}

START_TEST(toe_moving_front)
{
    enum { K = 101, T = 301 };
    double x[K], depth[K], d1 = 0.02, d2 = sluice_hyd_belanger_depth(0.02, 3.39);
    double L = 0.05, delta = 0.01, x0 = 0.3, c = 0.1;
    for (int k = 0; k < K; k++)
        x[k] = k * delta;
    const double fractions[] = {0.5, 0.25};
    for (size_t fi = 0; fi < 2; fi++) {
        double f = fractions[fi], threshold = d1 + f * (d2 - d1);
        double offset = L * atanh(2.0 * f - 1.0), bound = toe_bound(delta, L, offset);
        double t[T], x1[T], exact[T], worst = 0.0;
        for (int i = 0; i < T; i++) {
            t[i] = 0.01 * i;
            double front = x0 + c * t[i];
            for (int k = 0; k < K; k++)
                depth[k] = d1 + 0.5 * (d2 - d1) * (1.0 + tanh((x[k] - front) / L));
            depth[2] = NAN; /* a dry gauge upstream is skipped */
            x1[i] = sluice_hyd_toe_position(x, depth, K, threshold);
            exact[i] = front + offset;
            worst = fmax(worst, fabs(x1[i] - exact[i]));
        }
        double m, s, me, se;
        size_t used;
        sluice_hyd_mean_std(x1, T, &m, &s, &used);
        sluice_hyd_mean_std(exact, T, &me, &se, &used);
        double speed = sluice_hyd_slope(t, x1, T);
        /* slope error <= bound sum|t - tbar| / sum (t - tbar)^2 */
        double tbar = 0.5 * (T - 1) * 0.01, sa = 0.0, s2 = 0.0;
        for (int i = 0; i < T; i++) {
            sa += fabs(t[i] - tbar);
            s2 += (t[i] - tbar) * (t[i] - tbar);
        }
        fprintf(stderr,
                "toe (fraction %.2f): max |x1 - exact| = %.3g m (bound %.3g), mean %.6f "
                "(exact %.6f), std %.6f (exact %.6f), speed %.6f (exact %.2f)\n",
                f, worst, bound, m, me, s, se, speed, c);
        ck_assert(worst <= bound);
        ck_assert(fabs(m - me) <= bound);
        ck_assert(fabs(s - se) <= bound);
        ck_assert(fabs(speed - c) <= bound * sa / s2);
    }
    /* the first wet gauge already in the jump, or no crossing: NaN */
    for (int k = 0; k < K; k++)
        depth[k] = d2;
    ck_assert(isnan(sluice_hyd_toe_position(x, depth, K, 0.5 * (d1 + d2))));
    for (int k = 0; k < K; k++)
        depth[k] = d1;
    ck_assert(isnan(sluice_hyd_toe_position(x, depth, K, 0.5 * (d1 + d2))));
}
END_TEST

/* ------------------------------------------------------ roller and vmax */

/* Point gauges on sections x_s = 0.05 s (s = 0..20) at y = 0.01, 0.03, ...,
 * 0.09, listed in a scrambled order; u(t) = mean + A sin(2 pi 2 t) sampled
 * over whole periods, so the time mean is the mean to round-off. */
enum { SECTIONS = 21, LEVELS = 5, POINTS = SECTIONS * LEVELS, STEPS = 200 };

static void scrambled_points(double *px, double *py)
{
    for (int i = 0; i < POINTS; i++) {
        int j = (i * 37) % POINTS; /* 37 is prime to 105: a permutation */
        px[i] = 0.05 * (j / LEVELS);
        py[i] = 0.01 + 0.02 * (j % LEVELS);
    }
}

static double time_mean(double mean, double amplitude, int nan_fraction_of_10, double *series)
{
    for (int i = 0; i < STEPS; i++) {
        double t = 0.005 * i; /* 1 s: two whole periods */
        series[i] = (i % 10) < nan_fraction_of_10 ? NAN
                                                  : mean + amplitude * sin(2.0 * M_PI * 2.0 * t);
    }
    return sluice_hyd_wet_mean(series, STEPS, 0.5);
}

START_TEST(roller_synthetic)
{
    double px[POINTS], py[POINTS], u[POINTS], sx[POINTS], series[STEPS];
    size_t of[POINTS];
    scrambled_points(px, py);
    size_t sections = sluice_hyd_group_sections(px, POINTS, 1e-9, of, sx);
    ck_assert_uint_eq(sections, SECTIONS);
    for (size_t s = 0; s < sections; s++)
        ck_assert_double_eq_tol(sx[s], 0.05 * s, 1e-15);
    /* near surface: the point at y = 0.07 (the one at 0.09 is dry in 8 of 10
     * samples, below --min-wet 0.5, so it has no mean); its mean velocity is
     * +1 upstream of the toe x1 = 0.22, then U (x - xr)/0.1 with xr = 0.5337,
     * the reverse flow of the roller; below it a positive jet */
    double x1 = 0.22, xr = 0.5337;
    for (int i = 0; i < POINTS; i++) {
        double mean;
        int dry = 0;
        if (py[i] > 0.08) {
            mean = 5.0; /* would be chosen if its dryness were ignored */
            dry = 8;
        } else if (py[i] > 0.06)
            mean = px[i] <= x1 ? 1.0 : 0.4 * (px[i] - xr) / 0.1;
        else
            mean = 1.2;
        u[i] = time_mean(mean, 0.3, dry, series);
    }
    double top[SECTIONS], ytop[SECTIONS], xs = NAN, xc = NAN;
    sluice_hyd_section_top(of, py, u, POINTS, sections, top, ytop);
    for (size_t s = 0; s < sections; s++)
        ck_assert_double_eq_tol(ytop[s], 0.07, 1e-15);
    ck_assert_int_eq(sluice_hyd_roller_end(sx, top, sections, x1, &xs, &xc), 0);
    fprintf(stderr, "roller: end section %.4f m, zero crossing %.10f m (exact %.4f)\n", xs, xc,
            xr);
    ck_assert_double_eq_tol(xs, 0.55, 1e-15);
    ck_assert_double_eq_tol(xc, xr, 1e-12);
    /* a jet still positive just downstream of the toe does not end the
     * roller: the end follows the reverse flow */
    top[5] = top[6] = 0.8; /* x = 0.25, 0.30 */
    ck_assert_int_eq(sluice_hyd_roller_end(sx, top, sections, x1, &xs, &xc), 0);
    ck_assert_double_eq_tol(xs, 0.55, 1e-15);
    /* no reverse flow at all: no roller */
    for (size_t s = 0; s < sections; s++)
        top[s] = 0.5;
    ck_assert_int_eq(sluice_hyd_roller_end(sx, top, sections, x1, &xs, &xc), 1);
}
END_TEST

START_TEST(vmax_synthetic)
{
    /* u = V1 exp(-k xi) phi(y) + oscillation, phi = 1 - ((y - 0.03)/0.05)^2:
     * maximum 1 at the sample y = 0.03; the dry point at y = 0.09 carries a
     * larger value that must be ignored. Vmax/V1 = exp(-k xi) and the
     * least-squares decay rate is k, both to round-off. */
    double px[POINTS], py[POINTS], u[POINTS], sx[POINTS], series[STEPS], vmax[SECTIONS];
    size_t of[POINTS];
    scrambled_points(px, py);
    size_t sections = sluice_hyd_group_sections(px, POINTS, 1e-9, of, sx);
    double v1 = 1.5, d1 = 0.02, x1 = 0.1234, k = 0.05;
    for (int i = 0; i < POINTS; i++) {
        double xi = (px[i] - x1) / d1, phi = 1.0 - pow((py[i] - 0.03) / 0.05, 2);
        int dry = py[i] > 0.08 ? 8 : 0;
        u[i] = time_mean(dry ? 10.0 : v1 * exp(-k * xi) * phi, 0.2, dry, series);
    }
    sluice_hyd_section_max(of, u, POINTS, sections, vmax);
    double xi[SECTIONS], ratio[SECTIONS];
    for (size_t s = 0; s < sections; s++) {
        xi[s] = (sx[s] - x1) / d1;
        ratio[s] = xi[s] >= 0 ? vmax[s] / v1 : NAN;
        if (xi[s] >= 0)
            ck_assert_double_eq_tol(ratio[s], exp(-k * xi[s]), 1e-13);
    }
    double rate = sluice_hyd_decay_rate(xi, ratio, sections);
    fprintf(stderr, "vmax: fitted decay rate %.12f (exact %.3f; Chanson 0.028)\n", rate, k);
    ck_assert_double_eq_tol(rate, k, 1e-12);
}
END_TEST

/* ------------------------------------------------ surface, L2 and RMSE */

START_TEST(surface_statistics)
{
    enum { N = 500 };
    double eta[N], m, s;
    size_t used;
    for (int i = 0; i < N; i++)
        eta[i] = 0.061 + 0.004 * sin(2.0 * M_PI * 10.0 * i / N);
    ck_assert_int_eq(sluice_hyd_mean_std(eta, N, &m, &s, &used), 0);
    ck_assert_double_eq_tol(m, 0.061, 1e-15);
    ck_assert_double_eq_tol(s, 0.004 / sqrt(2.0), 1e-15);
    /* a gauge wet in fewer than min_wet of the samples has no mean */
    for (int i = 0; i < N; i++)
        if (i % 3)
            eta[i] = NAN;
    ck_assert(isnan(sluice_hyd_wet_mean(eta, N, 0.5)));
    ck_assert(isfinite(sluice_hyd_wet_mean(eta, N, 0.3)));
}
END_TEST

START_TEST(profile_errors)
{
    enum { N = 40 };
    double href[N], hnum[N], l2, rmse, msq = 0.0, minv2 = 0.0;
    size_t used;
    for (int i = 0; i < N; i++) {
        href[i] = 1.0 + 2.0 * i / N; /* levels of 1 to 3 m */
        msq += href[i] * href[i] / N;
        minv2 += 1.0 / (href[i] * href[i]) / N;
    }
    /* relative error eps everywhere: L2 = |eps|, RMSE = |eps| rms(h) */
    double eps = -0.12;
    for (int i = 0; i < N; i++)
        hnum[i] = href[i] * (1.0 + eps);
    ck_assert_int_eq(sluice_hyd_profile_errors(hnum, href, N, &l2, &rmse, &used), 0);
    ck_assert_double_eq_tol(l2, -eps, 1e-14);
    ck_assert_double_eq_tol(rmse, -eps * sqrt(msq), 1e-14);
    /* absolute offset delta: RMSE = delta, L2 = delta rms(1/h) */
    double delta = 0.3;
    for (int i = 0; i < N; i++)
        hnum[i] = href[i] + delta;
    hnum[5] = NAN; /* left out */
    sluice_hyd_profile_errors(hnum, href, N, &l2, &rmse, &used);
    double minv2_used = (minv2 * N - 1.0 / (href[5] * href[5])) / (N - 1);
    fprintf(stderr, "profile errors (offset 0.3 m): L2 = %.6f, RMSE = %.6f m, N = %zu\n", l2,
            rmse, used);
    ck_assert_uint_eq(used, N - 1);
    ck_assert_double_eq_tol(rmse, delta, 1e-14);
    ck_assert_double_eq_tol(l2, delta * sqrt(minv2_used), 1e-14);
    href[0] = 0.0;
    ck_assert_int_eq(sluice_hyd_profile_errors(hnum, href, N, &l2, &rmse, &used), -1);
}
END_TEST

/* ------------------------------------------------------ abrupt drop */

START_TEST(drop_limits_belanger)
{
    /* S = 0: both limits are Belanger's Y (Y + 1) = 2 F^2 */
    const double frs[] = {1.5, 2.8, 3.5, 6.0};
    for (int i = 0; i < 4; i++) {
        double Y = sluice_hyd_belanger_depth(1.0, frs[i]), fa, fb;
        ck_assert_int_eq(sluice_hyd_drop_limits(Y, 0.0, &fa, &fb), 0);
        ck_assert_double_eq_tol(fa, frs[i], 1e-12);
        ck_assert_double_eq_tol(fb, frs[i], 1e-12);
    }
    /* S > 0: F_B^2 - F_A^2 = Y S (Y - 1 - S)/(Y - 1) > 0 */
    double Y = 5.0, S = 0.9, fa, fb;
    ck_assert_int_eq(sluice_hyd_drop_limits(Y, S, &fa, &fb), 0);
    ck_assert_double_eq_tol(fb * fb - fa * fa, Y * S * (Y - 1 - S) / (Y - 1), 1e-12);
    ck_assert(fa < fb);
    ck_assert_int_eq(sluice_hyd_drop_limits(1.5, 0.9, &fa, &fb), -1);
    /* the face's force the balance needs: the hydrostatic one under the
     * tailwater at F_A (ratio 1), the one under the inflow's level at F_B */
    double ratio;
    ck_assert_int_eq(sluice_hyd_drop_face_ratio(fa, Y, S, &ratio), 0);
    ck_assert_double_eq_tol(ratio, 1.0, 1e-12);
    ck_assert_int_eq(sluice_hyd_drop_face_ratio(fb, Y, S, &ratio), 0);
    ck_assert_double_eq_tol(ratio, ((1 + S) * (1 + S) - 1) / (Y * Y - (Y - S) * (Y - S)), 1e-12);
    ck_assert_int_eq(sluice_hyd_drop_face_ratio(3.0, Y, 0.0, &ratio), -1);
    ck_assert_int_eq(sluice_hyd_drop_face_ratio(3.0, 1.5, S, &ratio), -1);
}
END_TEST


/* The instantaneous state at a drop from the upper reach's profile and the
 * type over a series: gauges every 0.1 m up to the edge at 0.8 m, y1 = 0.035
 * m, threshold 0.1 m, L_r = 0.5 m. */
START_TEST(drop_states_and_type)
{
    const double x[9] = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9};
    const double xd = 0.8, threshold = 0.1, Lr = 0.5;
    double depth[9], x1;
    /* supercritical to the edge: wave (the gauges past the edge are ignored
     * even when deep) */
    for (int k = 0; k < 9; k++)
        depth[k] = k < 7 ? 0.035 : 0.2;
    ck_assert_int_eq(sluice_hyd_drop_state_of(x, depth, 9, threshold, xd, Lr, &x1),
                     SLUICE_HYD_STATE_WAVE);
    ck_assert(isnan(x1));
    /* toe between 0.2 and 0.3 m (crossing at 0.25 m): 0.55 m >= L_r from the edge: A */
    for (int k = 0; k < 9; k++)
        depth[k] = k < 2 ? 0.035 : 0.165;
    ck_assert_int_eq(sluice_hyd_drop_state_of(x, depth, 9, threshold, xd, Lr, &x1),
                     SLUICE_HYD_STATE_A);
    ck_assert_double_eq_tol(x1, 0.25, 1e-12);
    /* toe at 0.55 m: 0.25 m from the edge: B */
    for (int k = 0; k < 9; k++)
        depth[k] = k < 5 ? 0.035 : 0.165;
    ck_assert_int_eq(sluice_hyd_drop_state_of(x, depth, 9, threshold, xd, Lr, &x1),
                     SLUICE_HYD_STATE_B);
    ck_assert_double_eq_tol(x1, 0.55, 1e-12);
    /* the first wet gauge already in the jump: toe upstream of the gauges, A */
    depth[0] = NAN;
    for (int k = 1; k < 9; k++)
        depth[k] = 0.15;
    ck_assert_int_eq(sluice_hyd_drop_state_of(x, depth, 9, threshold, xd, Lr, &x1),
                     SLUICE_HYD_STATE_A);
    ck_assert(isinf(x1) && x1 < 0);
    for (int k = 0; k < 9; k++)
        depth[k] = k < 7 ? NAN : 0.2;
    ck_assert_int_eq(sluice_hyd_drop_state_of(x, depth, 9, threshold, xd, Lr, &x1),
                     SLUICE_HYD_STATE_NONE);

    /* types: 20 samples */
    const sluice_hyd_drop_state A = SLUICE_HYD_STATE_A, B = SLUICE_HYD_STATE_B,
                                W = SLUICE_HYD_STATE_WAVE, N = SLUICE_HYD_STATE_NONE;
    sluice_hyd_drop_state series[20];
    double fa, fb, fw;
    size_t episodes;
    /* B with one wave sample in 20 (0.05 < 0.1) and a dry sample: B-jump */
    for (int i = 0; i < 20; i++)
        series[i] = i == 7 ? W : i == 3 ? N : B;
    ck_assert_str_eq(sluice_hyd_drop_type(series, 20, 0.1, &fa, &fb, &fw, &episodes), "B-jump");
    ck_assert_double_eq_tol(fw, 1.0 / 19, 1e-15);
    ck_assert_double_eq_tol(fb, 18.0 / 19, 1e-15);
    ck_assert_uint_eq(episodes, 1);
    /* alternating 5 B, 5 W, twice: B-wave, two wave episodes */
    for (int i = 0; i < 20; i++)
        series[i] = (i / 5) % 2 ? W : B;
    ck_assert_str_eq(sluice_hyd_drop_type(series, 20, 0.1, &fa, &fb, &fw, &episodes), "B-wave");
    ck_assert_double_eq_tol(fw, 0.5, 1e-15);
    ck_assert_uint_eq(episodes, 2);
    /* A with waves a quarter of the time: A-wave */
    for (int i = 0; i < 20; i++)
        series[i] = i % 4 == 0 ? W : A;
    ck_assert_str_eq(sluice_hyd_drop_type(series, 20, 0.1, &fa, &fb, &fw, &episodes), "A-wave");
    ck_assert_uint_eq(episodes, 5);
    for (int i = 0; i < 20; i++)
        series[i] = A;
    ck_assert_str_eq(sluice_hyd_drop_type(series, 20, 0.1, &fa, &fb, &fw, &episodes), "A-jump");
    for (int i = 0; i < 20; i++)
        series[i] = i ? W : B;
    ck_assert_str_eq(sluice_hyd_drop_type(series, 20, 0.1, &fa, &fb, &fw, &episodes),
                     "wave jump");
    for (int i = 0; i < 20; i++)
        series[i] = N;
    ck_assert_ptr_null(sluice_hyd_drop_type(series, 20, 0.1, &fa, &fb, &fw, &episodes));
}
END_TEST

/* Seed 004 table 1 (/work/shared/data/seed004_table1_abrupt_drop.csv): y1,
 * yt, s in cm, V1 in m/s, observed type. F1 = V1/sqrt(g y1) from the
 * columns, whose V1 y1 = Vt yt checks hold (the printed F1 of T6, 2.8,
 * disagrees with its own V1 and y1: 2.94). */
START_TEST(drop_table1)
{
    static const struct {
        const char *test;
        double y1, yt, v1, s;
        char family; /* A: A-jump or A-wave; B: B-jump or B-wave */
        const char *type;
    } rows[] = {
        {"T1", 3.51, 16.63, 1.93, 3.2, 'B', "B-wave"},
        {"T2", 3.71, 17.65, 1.81, 3.2, 'A', "A-wave"},
        {"T3", 3.48, 18.18, 1.87, 3.2, 'A', "A-wave"},
        {"T4", 3.14, 17.97, 2.09, 3.2, 'A', "A-jump"},
        {"T5", 3.19, 18.20, 2.04, 3.2, 'A', "A-jump"},
        {"T6", 3.78, 16.10, 1.79, 3.2, 'B', "B-jump"},
        {"T7", 3.39, 16.78, 2.02, 3.2, 'B', "B-jump"},
    };
    static const char *const regimes[] = {"A-jump", "wave-jump region", "B-jump"};
    double max_a = -INFINITY, min_b = INFINITY;
    int literal = 0;
    for (size_t i = 0; i < sizeof rows / sizeof *rows; i++) {
        double f1 = sluice_hyd_froude(rows[i].v1, rows[i].y1 / 100.0, G);
        double Y = rows[i].yt / rows[i].y1, S = rows[i].s / rows[i].y1, t, fa, fb;
        sluice_hyd_drop_regime regime;
        ck_assert_int_eq(sluice_hyd_drop_regime_of(f1, Y, S, &regime, &t), 0);
        sluice_hyd_drop_limits(Y, S, &fa, &fb);
        literal += strcmp(regimes[regime], rows[i].type) == 0;
        fprintf(stderr,
                "drop %s: F1 %.3f Y %.3f S %.3f F_A %.3f F_B %.3f t %+.3f -> %-16s observed "
                "%s\n",
                rows[i].test, f1, Y, S, fa, fb, t, regimes[regime], rows[i].type);
        if (rows[i].family == 'A')
            max_a = fmax(max_a, t);
        else
            min_b = fmin(min_b, t);
    }
    fprintf(stderr,
            "drop: the momentum limits' regime equals the observed type in %d of 7 rows; "
            "A-family t <= %.3f < B-family t >= %.3f\n",
            literal, max_a, min_b);
    /* what the momentum limits do get right: every A-family jump (A-jump,
     * A-wave) lies nearer the A limit than every B-family jump */
    ck_assert(max_a < min_b);
}
END_TEST

/* ----------------------------------------------------------------- CLI */

/* Runs build/tools/sluice-analyze with args; stdout into *out, stderr into
 * *err. Returns the exit status. */
static int analyze(const char *scratch, const char *args, char **out, char **err)
{
    char *errpath = NULL, *command = NULL;
    if (asprintf(&errpath, "%s/stderr.txt", scratch) < 0 ||
        asprintf(&command, "%s/tools/sluice-analyze %s 2>%s", test_build_dir(), args, errpath) <
            0)
        return -1;
    int status = test_popen(command, out);
    free(command);
    *err = test_read_file(errpath);
    free(errpath);
    return status;
}

/* The number after "name = " at the start of a line of text, or NaN. */
static double headline(const char *text, const char *name)
{
    size_t len = strlen(name);
    for (const char *line = text; line && *line;) {
        if (strncmp(line, name, len) == 0 && strncmp(line + len, " = ", 3) == 0)
            return strtod(line + len + 3, NULL);
        line = strchr(line, '\n');
        if (line)
            line++;
    }
    return NAN;
}

/* A synthetic run: sections at x = 0.5 and 1.0 m, d at 1.0 m equal to
 * Belanger's d2 (1 + 0.02) plus a cosine of 2 Hz; free-surface gauges every
 * 2 cm with a steady tanh front centred at X = 0.4537 m (L = 0.05 m). */
static char *make_run(double d2b)
{
    char *dir = test_scratch("analysis");
    if (!dir)
        return NULL;
    FILE *f;
    char *path = NULL;
    if (asprintf(&path, "%s/scene.resolved.yaml", dir) < 0 || !(f = fopen(path, "w")))
        return NULL;
    fputs("dimensions: 2\nplugins:\n  inlet:\n    depth: 0.02\n    discharge: 0.03\n"
          "  section_gauge:\n    positions: [0.5, 1]\n"
          "  free_surface_gauge:\n    positions: [",
          f);
    for (int k = 0; k < 50; k++)
        fprintf(f, "%s%.2f", k ? ", " : "", 0.02 * (k + 1));
    fputs("]\n    file: free_surface.csv\n", f);
    /* point gauges in block style (as the core writes point lists): sections
     * x = 0.3 .. 0.6 m, a bottom point and a near-surface point each */
    fputs("  point_gauge:\n    fields: velocity\n    points:\n", f);
    for (int k = 0; k < 8; k++)
        fprintf(f, "      - [%.1f, %.2f]\n", 0.3 + 0.1 * (k / 2), k % 2 ? 0.05 : 0.01);
    fclose(f);
    free(path);
    if (asprintf(&path, "%s/sections.csv", dir) < 0 || !(f = fopen(path, "w")))
        return NULL;
    fputs("time,d_x0,q_x0,U_x0,Fr_x0,d_x1,q_x1,U_x1,Fr_x1\n", f);
    for (int i = 0; i <= 512; i++) {
        double t = i / 128.0;
        fprintf(f, "%.17g,0.05,0.03,0.6,0.86,%.17g,0.03,0.34,0.37\n", t,
                d2b * (1.02 + 0.01 * cos(2.0 * M_PI * 2.0 * t)));
    }
    fclose(f);
    free(path);
    if (asprintf(&path, "%s/free_surface.csv", dir) < 0 || !(f = fopen(path, "w")))
        return NULL;
    fputs("time", f);
    for (int k = 0; k < 50; k++)
        fprintf(f, ",eta_x%d", k);
    fputc('\n', f);
    for (int i = 0; i <= 100; i++) {
        fprintf(f, "%.17g", 0.01 * i);
        for (int k = 0; k < 50; k++) {
            double x = 0.02 * (k + 1);
            fprintf(f, ",%.17g", 0.02 + 0.5 * (d2b - 0.02) * (1.0 + tanh((x - 0.4537) / 0.05)));
        }
        fputc('\n', f);
    }
    fclose(f);
    free(path);
    /* point velocities: bottom u = 1.5 exp(-0.028 (x - 0.25)/0.02) (Chanson's
     * decay from x1 = 0.25 m), near-surface u = -0.2, -0.1, 0.1, 0.3 (reverse
     * flow ending between 0.4 and 0.5 m, zero at 0.45 m); the near-surface
     * points are outside the fluid (nan) in one row of ten */
    static const double surface_u[4] = {-0.2, -0.1, 0.1, 0.3};
    if (asprintf(&path, "%s/points.csv", dir) < 0 || !(f = fopen(path, "w")))
        return NULL;
    fputs("time", f);
    for (int k = 0; k < 8; k++)
        fprintf(f, ",p%d_velocity_x,p%d_velocity_y", k, k);
    fputc('\n', f);
    for (int i = 0; i <= 100; i++) {
        fprintf(f, "%.17g", 0.01 * i);
        for (int k = 0; k < 8; k++) {
            double x = 0.3 + 0.1 * (k / 2);
            if (k % 2 && i % 10 == 3)
                fputs(",nan,nan", f);
            else if (k % 2)
                fprintf(f, ",%.17g,0", surface_u[k / 2]);
            else
                fprintf(f, ",%.17g,0", 1.5 * exp(-0.028 * (x - 0.25) / 0.02));
        }
        fputc('\n', f);
    }
    fclose(f);
    free(path);
    return dir;
}

/* front: a synthetic front Z(T) = 1 + T^2 / 2 (a = 1 m, g = 9.81, sampled
 * every 1 ms) against "experimental" points of the same curve taken 0.2
 * later in T (the experiment lags): the raw errors are Z(T)/Z(T - 0.2) - 1
 * (linear interpolation of the 1 ms table: relative error < 1e-5), --shift 0.2
 * removes them, and the fitted shift is 0.2 on the search's 0.001 grid. */
static double synthetic_front(double T)
{
    return 1 + 0.5 * T * T;
}

START_TEST(cli_front)
{
    char *run = test_scratch("front");
    ck_assert_ptr_nonnull(run);
    char *path = NULL;
    ck_assert(asprintf(&path, "%s/front.csv", run) > 0);
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    double scale = sqrt(2 * G / 1.0); /* T = t sqrt(2 g / a) */
    fprintf(f, "time,x_front\n");
    for (int i = 0; i <= 700; i++) {
        double t = 0.001 * i;
        fprintf(f, "%.10g,%.12g\n", t, synthetic_front(t * scale));
    }
    fclose(f);
    free(path);
    static const double te[] = {0.8, 1.2, 1.6, 2.0, 2.4, 3.5};
    ck_assert(asprintf(&path, "%s/reference.csv", run) > 0);
    f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fprintf(f, "# synthetic\nT,Z\n");
    for (int i = 0; i < 6; i++)
        fprintf(f, "%g,%.12g\n", te[i], synthetic_front(te[i] - 0.2));
    fclose(f);
    char *args = NULL, *out = NULL, *err = NULL;
    ck_assert(asprintf(&args, "front %s --reference %s --width 1 --shift 0.2", run, path) > 0);
    int status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli front: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    /* T = 3.5 lies past the table's end (T = 0.7 x 4.43 = 3.1): 5 points */
    ck_assert_double_eq(headline(out, "points"), 5);
    double worst = 0, sum = 0, sum2 = 0;
    for (int i = 0; i < 5; i++) {
        double e = synthetic_front(te[i]) / synthetic_front(te[i] - 0.2) - 1;
        if (fabs(e) > fabs(worst))
            worst = e;
        sum += fabs(e);
        sum2 += e * e;
    }
    ck_assert_double_eq_tol(headline(out, "front_error_max"), worst, 1e-5);
    ck_assert_double_eq_tol(headline(out, "front_error_mean"), sum / 5, 1e-5);
    ck_assert_double_eq_tol(headline(out, "front_error_rms"), sqrt(sum2 / 5), 1e-5);
    ck_assert_double_lt(fabs(headline(out, "front_error_max_shifted")), 1e-5);
    ck_assert_double_eq_tol(headline(out, "shift_fitted"), 0.2, 1e-9);
    ck_assert_double_lt(headline(out, "front_error_rms_fitted"), 1e-5);
    free(args);
    free(out);
    free(err);
    /* without a reference: refused */
    ck_assert(asprintf(&args, "front %s --width 1", run) > 0);
    status = analyze(run, args, &out, &err);
    ck_assert_int_eq(status, 2);
    ck_assert_ptr_nonnull(strstr(err, "front needs --reference REF.csv"));
    free(args);
    free(out);
    free(err);
    free(path);
    free(run);
}
END_TEST

START_TEST(cli)
{
    double d2b = sluice_hyd_belanger_depth(0.02, sluice_hyd_froude(1.5, 0.02, G));
    char *run = make_run(d2b);
    ck_assert_ptr_nonnull(run);
    char *args = NULL, *out = NULL, *err = NULL, *path = NULL;

    /* conjugate: d2/d2_B = 1.02 + 0.01 cos(4 pi t) over [1, 3] s (257 rows):
     * A and P of the same series by sluice_hyd_conjugate_statistics; the
     * program prints 6 significant digits (relative rounding <= 5e-6) */
    ck_assert(asprintf(&args, "conjugate %s --d1 0.02 --v1 1.5 --x 1.0 --from 1 --to 3", run) > 0);
    int status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli conjugate: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    double series[257], A, P;
    size_t used;
    for (int i = 0; i <= 256; i++)
        series[i] = d2b * (1.02 + 0.01 * cos(2.0 * M_PI * 2.0 * (1.0 + i / 128.0)));
    sluice_hyd_conjugate_statistics(series, 257, d2b, &A, &P, &used);
    ck_assert_double_eq_tol(headline(out, "A"), A, 5e-6 * A);
    ck_assert_double_eq_tol(headline(out, "P"), P, 5e-6 * P);
    ck_assert_double_eq_tol(headline(out, "d2_Belanger"), d2b, 5e-6 * d2b);
    ck_assert_int_eq((int)headline(out, "samples"), 257);
    ck_assert(asprintf(&path, "%s/analysis/conjugate.csv", run) > 0);
    ck_assert(test_exists(path));
    free(path);
    if (system("command -v gnuplot >/dev/null 2>&1") == 0) {
        ck_assert(asprintf(&path, "%s/analysis/conjugate.png", run) > 0);
        ck_assert_msg(test_exists(path), "gnuplot is installed but %s is missing", path);
        free(path);
    }
    free(args);
    free(out);
    free(err);

    /* the same without --d1/--v1: the run's inlet (depth 0.02 m, discharge
     * 0.03 m^2/s, so V1 = 1.5 m/s) gives the inflow */
    ck_assert(asprintf(&args, "conjugate %s --x 1.0 --from 1 --to 3 --no-plot", run) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli conjugate from the inlet: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    ck_assert_double_eq_tol(headline(out, "Fr1"), sluice_hyd_froude(1.5, 0.02, G),
                            5e-6 * 3.4);
    ck_assert_double_eq_tol(headline(out, "A"), A, 5e-6 * A);
    free(args);
    free(out);
    free(err);

    /* toe: the steady front's crossing of (d1 + d2)/2 is X = 0.4537 m, within
     * the interpolation bound for 2 cm gauges and L = 5 cm */
    ck_assert(asprintf(&args, "toe %s --d1 0.02 --v1 1.5 --no-plot", run) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli toe: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    ck_assert(fabs(headline(out, "x1_mean") - 0.4537) <= toe_bound(0.02, 0.05, 0.0) + 1e-6);
    ck_assert_double_eq_tol(headline(out, "x1_std"), 0.0, 1e-6);
    ck_assert(asprintf(&path, "%s/analysis/toe.csv", run) > 0);
    ck_assert(test_exists(path));
    free(path);
    free(args);
    free(out);
    free(err);

    /* spectrum of the section depth: 512 samples at 1/128 s (window
     * [0, 3.9921875] s), df = 0.25 Hz: 2 Hz is bin 8 */
    ck_assert(asprintf(&args, "spectrum %s --column d_x1 --to 3.995 --no-plot --d1 0.02 --v1 1.5",
                       run) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli spectrum: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    ck_assert_double_eq_tol(headline(out, "f_peak"), 2.0, 1e-9);
    ck_assert_double_eq_tol(headline(out, "St"), 2.0 * 0.02 / 1.5, 1e-6);
    free(args);
    free(out);
    free(err);

    /* roller: near-surface mean u = -0.2, -0.1, 0.1, 0.3 at x = 0.3 .. 0.6 m
     * (the nan rows left out of the mean): the roller ends at the 0.5 m
     * section, L_r = 0.25 m from x1 = 0.25 m; the zero crossing is 0.45 m */
    ck_assert(asprintf(&args, "roller %s --d1 0.02 --v1 1.5 --x1 0.25 --no-plot", run) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli roller: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    ck_assert_double_eq_tol(headline(out, "L_r"), 0.25, 1e-12);
    ck_assert_double_eq_tol(headline(out, "L_r_crossing"), 0.2, 5e-6 * 0.2);
    ck_assert_double_eq_tol(headline(out, "L_r_Hager"),
                            sluice_hyd_hager_roller_length(0.02, sluice_hyd_froude(1.5, 0.02, G)),
                            5e-6 * 0.3);
    free(args);
    free(out);
    free(err);

    /* vmax: the bottom points follow Chanson's decay from x1 = 0.25 m exactly */
    ck_assert(asprintf(&args, "vmax %s --d1 0.02 --v1 1.5 --x1 0.25 --no-plot", run) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli vmax: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    ck_assert_double_eq_tol(headline(out, "decay_rate"), 0.028, 5e-6 * 0.028);
    ck_assert(headline(out, "rms_deviation_from_Chanson") < 1e-12);
    ck_assert_int_eq((int)headline(out, "sections_downstream"), 4);
    free(args);
    free(out);
    free(err);

    /* l2: a reference h_ref = 1.1 eta at five gauge positions (no
     * interpolation error): (eta - h_ref)/h_ref = -1/11 everywhere, so
     * L2 = 1/11 and RMSE = 0.1 rms(eta) */
    ck_assert(asprintf(&path, "%s/reference.csv", run) > 0);
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs("x,eta\n", f);
    double sq = 0.0;
    for (int k = 0; k < 5; k++) {
        double x = 0.1 + 0.2 * k;
        double eta = 0.02 + 0.5 * (d2b - 0.02) * (1.0 + tanh((x - 0.4537) / 0.05));
        fprintf(f, "%.17g,%.17g\n", x, 1.1 * eta);
        sq += (0.1 * eta) * (0.1 * eta) / 5;
    }
    fclose(f);
    ck_assert(asprintf(&args, "l2 %s --reference %s --time 0.5 --no-plot", run, path) > 0);
    free(path);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli l2: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    double l2 = NAN, rmse = NAN;
    unsigned points = 0;
    const char *line = strstr(out, "time = 0.5 s");
    ck_assert_ptr_nonnull(line);
    ck_assert_int_eq(sscanf(strstr(line, "L2 = "), "L2 = %lf, RMSE = %lf m, points = %u", &l2,
                            &rmse, &points),
                     3);
    ck_assert_uint_eq(points, 5);
    ck_assert_double_eq_tol(l2, 1.0 / 11.0, 5e-6 / 11.0);
    ck_assert_double_eq_tol(rmse, sqrt(sq), 5e-6 * sqrt(sq));
    free(args);
    free(out);
    free(err);

    /* correlate: the section depth with itself (r = 1) and with the steady
     * free surface (constant: no r, exit 1) */
    ck_assert(asprintf(&args, "correlate %s/sections.csv:d_x1 %s/sections.csv:d_x1 --no-plot",
                       run, run) > 0);
    status = analyze(run, args, &out, &err);
    ck_assert_int_eq(status, 0);
    ck_assert_double_eq_tol(headline(out, "r"), 1.0, 1e-12);
    free(args);
    free(out);
    free(err);
    ck_assert(asprintf(&args, "correlate %s/sections.csv:d_x1 %s/free_surface.csv:eta_x3 "
                              "--no-plot", run, run) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli correlate with a constant: exit %d, %s", status, err);
    ck_assert_int_eq(status, 1);
    free(args);
    free(out);
    free(err);

    /* classify: seed 004's T1 in metres */
    status = analyze(run, "classify --y1 0.0351 --yt 0.1663 --v1 1.93 --drop 0.032", &out, &err);
    fprintf(stderr, "cli classify: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    ck_assert_ptr_nonnull(strstr(out, "regime = wave-jump region"));
    {
        /* in the wave-jump region the face's needed force lies between the
         * B limit's share and the hydrostatic one (it falls as F1 rises) */
        const double Y = 0.1663 / 0.0351, S = 0.032 / 0.0351;
        const double b_share = ((1 + S) * (1 + S) - 1) / (Y * Y - (Y - S) * (Y - S));
        const double r = headline(out, "face_ratio");
        fprintf(stderr, "cli classify T1: face_ratio %.4f, B limit %.4f\n", r, b_share);
        ck_assert(r > b_share && r < 1);
        ck_assert_double_eq_tol(headline(out, "face_force_needed"),
                                r * headline(out, "face_force_hydrostatic"),
                                1e-5 * headline(out, "face_force_hydrostatic"));
    }
    ck_assert_double_eq_tol(headline(out, "F1"), sluice_hyd_froude(1.93, 0.0351, G), 5e-6 * 3.3);
    free(out);
    free(err);

    /* drop-type on a synthetic abrupt-drop run (inflow from its inlet: y1 =
     * 0.035 m over an upper bed at 0.032 m, V1 = 1.93 m/s; edge at 0.8 m):
     * 2 s of supercritical stream to the edge (wave), then 2 s with the toe
     * 0.26 m upstream of the edge, less than Hager's L_r (B): a B-wave, half
     * the samples in the wave state, one wave episode */
    {
        char *drop_run = test_scratch("analysis-drop");
        ck_assert_ptr_nonnull(drop_run);
        ck_assert(asprintf(&path, "%s/scene.resolved.yaml", drop_run) > 0);
        FILE *scene = fopen(path, "w");
        ck_assert_ptr_nonnull(scene);
        fputs("dimensions: 2\ngeometry:\n  fluid:\n"
              "    - {shape: box, min: [0.8, 0], max: [2, 0.16]}\n"
              "    - {shape: box, min: [0, 0.032], max: [0.8, 0.067]}\n"
              "plugins:\n  inlet:\n    bed: 0.032\n    depth: 0.035\n"
              "    velocity: 1.93\n  free_surface_gauge:\n    positions: [0.1, 0.2, 0.3, 0.4, "
              "0.5, 0.6, 0.7, 0.9, 1.0]\n",
              scene);
        fclose(scene);
        free(path);
        ck_assert(asprintf(&path, "%s/free_surface.csv", drop_run) > 0);
        FILE *fs = fopen(path, "w");
        ck_assert_ptr_nonnull(fs);
        fputs("time,eta_x0,eta_x1,eta_x2,eta_x3,eta_x4,eta_x5,eta_x6,eta_x7,eta_x8\n", fs);
        for (int i = 0; i < 400; i++) {
            fprintf(fs, "%.17g", 0.01 * i);
            for (int k = 0; k < 9; k++)
                fprintf(fs, ",%.17g",
                        k >= 7 ? 0.16 : (i >= 200 && k >= 5) ? 0.032 + 0.165 : 0.032 + 0.035);
            fputc('\n', fs);
        }
        fclose(fs);
        free(path);
        ck_assert(asprintf(&args, "drop-type %s --drop-x 0.8 --no-plot", drop_run) > 0);
        status = analyze(drop_run, args, &out, &err);
        fprintf(stderr, "cli drop-type: exit %d\n%s%s", status, out, err);
        ck_assert_int_eq(status, 0);
        ck_assert_ptr_nonnull(strstr(out, "type = B-wave"));
        ck_assert_double_eq_tol(headline(out, "fraction_wave"), 0.5, 1e-12);
        ck_assert_double_eq_tol(headline(out, "fraction_B"), 0.5, 1e-12);
        ck_assert_int_eq((int)headline(out, "wave_episodes"), 1);
        ck_assert_double_eq_tol(headline(out, "drop"), 0.032, 1e-12);
        free(args);
        free(out);
        free(err);
        /* without --drop-x: the edge is the downstream end of the fluid
         * region on the upper bed (the second region, at y = 0.032 m) */
        ck_assert(asprintf(&args, "drop-type %s --no-plot", drop_run) > 0);
        status = analyze(drop_run, args, &out, &err);
        ck_assert_msg(status == 0, "%s%s", out, err);
        ck_assert_double_eq_tol(headline(out, "drop_x"), 0.8, 1e-12);
        ck_assert_ptr_nonnull(strstr(out, "type = B-wave"));
        free(args);
        free(out);
        free(err);
        ck_assert(asprintf(&args, "rm -rf '%s'", drop_run) > 0);
        ck_assert_int_eq(system(args), 0);
        free(args);
        free(drop_run);
    }

    /* profile on a synthetic point_gauge line of 4 points across a channel
     * L = 1 mm wide (y = 0.125 .. 0.875 mm), velocity_x the steady
     * Poiseuille profile F / (2 nu) y (L - y), F = 1e-4 m s^-2, nu = 1e-6
     * m^2 s^-1 (u_max = F L^2 / (8 nu) = 1.25e-5 m/s), at two samples: the
     * error against it is 0, the first point over the largest 0.4375 / 0.9375;
     * with 10 % added to every value the error is 0.1 */
    for (int scaled = 0; scaled < 2; scaled++) {
        char *profile_run = test_scratch("analysis-profile");
        ck_assert_ptr_nonnull(profile_run);
        ck_assert(asprintf(&path, "%s/scene.resolved.yaml", profile_run) > 0);
        FILE *sc = fopen(path, "w");
        ck_assert_ptr_nonnull(sc);
        fputs("dimensions: 2\nplugins:\n  point_gauge:\n    points: [[1e-4, 1.25e-4], [1e-4, "
              "3.75e-4], [1e-4, 6.25e-4], [1e-4, 8.75e-4]]\n    fields: velocity\n    file: "
              "points.csv\n",
              sc);
        fclose(sc);
        free(path);
        ck_assert(asprintf(&path, "%s/points.csv", profile_run) > 0);
        FILE *pc = fopen(path, "w");
        ck_assert_ptr_nonnull(pc);
        fputs("time,p0_velocity_x,p0_velocity_y,p1_velocity_x,p1_velocity_y,p2_velocity_x,"
              "p2_velocity_y,p3_velocity_x,p3_velocity_y\n",
              pc);
        for (int i = 0; i < 2; i++) {
            fprintf(pc, "%d", i);
            for (int k = 0; k < 4; k++) {
                const double y = 2.5e-4 * (k + 0.5);
                fprintf(pc, ",%.17g,0", (scaled ? 1.1 : 1.0) * 1e-4 / 2e-6 * y * (1e-3 - y));
            }
            fputc('\n', pc);
        }
        fclose(pc);
        free(path);
        path = NULL;
        ck_assert(asprintf(&args, "profile %s --force 1e-4 --viscosity 1e-6 --width 1e-3",
                           profile_run) > 0);
        status = analyze(profile_run, args, &out, &err);
        ck_assert_msg(status == 0, "%s%s", out, err);
        ck_assert_double_eq_tol(headline(out, "l2_poiseuille"), scaled ? 0.1 : 0.0, 1e-12);
        ck_assert_double_eq_tol(headline(out, "first_over_max"), 0.4375 / 0.9375, 1e-6);
        ck_assert_double_eq_tol(headline(out, "u_max_poiseuille"), 1.25e-5, 1e-17);
        free(args);
        free(out);
        free(err);
        /* without the Poiseuille parameters: the profile alone */
        ck_assert(asprintf(&args, "profile %s", profile_run) > 0);
        status = analyze(profile_run, args, &out, &err);
        ck_assert_msg(status == 0, "%s%s", out, err);
        ck_assert_double_eq_tol(headline(out, "first_over_max"), 0.4375 / 0.9375, 1e-6);
        ck_assert_ptr_null(strstr(out, "l2_poiseuille"));
        free(args);
        free(out);
        free(err);
        ck_assert(asprintf(&args, "rm -rf '%s'", profile_run) > 0);
        ck_assert_int_eq(system(args), 0);
        free(args);
        free(profile_run);
    }

    /* impact on a synthetic sensor (wall_pressure.csv, every 1 ms): 0 to
     * t = 1 s, a linear rise to 10 Pa at 1.2 s, a fall to 2 Pa at 1.6 s,
     * then 2 Pa. Arrival above 1.06 Pa: the first sample past 1.0212 s,
     * 1.022 s; over [1.022, 1.522] s the peak 10 Pa at 1.2 s and the
     * impulse, exact for the trapezoid rule on the linear pieces:
     * 25 (0.2^2 - 0.022^2) + 10 x 0.322 - 10 x 0.322^2 = 3.17106 Pa s;
     * scaled by P0 = 2 Pa and T0 = 0.5 s: peak 5, t_peak 2.4, impulse
     * 3.17106 / (2 x 0.5). */
    {
        char *impact_run = test_scratch("analysis-impact");
        ck_assert_ptr_nonnull(impact_run);
        ck_assert(asprintf(&path, "%s/wall_pressure.csv", impact_run) > 0);
        FILE *wp = fopen(path, "w");
        ck_assert_ptr_nonnull(wp);
        fputs("time,p_Pa\n", wp);
        for (int i = 0; i <= 3000; i++) {
            const double t = 0.001 * i;
            const double pr = i <= 1000   ? 0.0
                              : i <= 1200 ? 50.0 * (t - 1.0)
                              : i <= 1600 ? 10.0 - 20.0 * (t - 1.2)
                                          : 2.0;
            fprintf(wp, "%.17g,%.17g\n", t, pr);
        }
        fclose(wp);
        free(path);
        path = NULL;
        ck_assert(asprintf(&args, "impact %s --column p_Pa --arrival 1.06 --duration 0.5 --scale 2 "
                                  "--time-scale 0.5",
                           impact_run) > 0);
        status = analyze(impact_run, args, &out, &err);
        ck_assert_msg(status == 0, "%s%s", out, err);
        ck_assert_double_eq_tol(headline(out, "t_arrival"), 1.022, 1e-9);
        ck_assert_double_eq_tol(headline(out, "peak"), 10.0, 1e-9);
        ck_assert_double_eq_tol(headline(out, "t_peak"), 1.2, 1e-9);
        ck_assert_double_eq_tol(headline(out, "impulse"), 3.17106, 1e-6);
        ck_assert_double_eq_tol(headline(out, "peak_scaled"), 5.0, 1e-9);
        ck_assert_double_eq_tol(headline(out, "t_peak_scaled"), 2.4, 1e-9);
        ck_assert_double_eq_tol(headline(out, "impulse_scaled"), 3.17106, 1e-6);
        free(args);
        free(out);
        free(err);
        /* a sensor the impact never reaches: exit 1 (not found), with the reason */
        ck_assert(asprintf(&args, "impact %s --column p_Pa --arrival 20", impact_run) > 0);
        status = analyze(impact_run, args, &out, &err);
        ck_assert_int_eq(status, 1);
        ck_assert_ptr_nonnull(strstr(err, "never exceeds --arrival 20"));
        free(args);
        free(out);
        free(err);
        ck_assert(asprintf(&args, "rm -rf '%s'", impact_run) > 0);
        ck_assert_int_eq(system(args), 0);
        free(args);
        free(impact_run);
    }

    /* momentum on a synthetic section table with forces: over [1, 3] s (rows
     * every 1/128 s) the sines average to zero, so the means are the
     * constants: section 0 (x = 0.5 m) d = 0.1 m, q = 0.05, M = 25, P = 49.05,
     * S = 74.05 N/m and rho0 g d^2/2 = 998 x 9.81 x 0.01 / 2 = 48.9519 N/m
     * with the scene's rest density; section 1 (x = 0.8 m, top 0.032 m) is
     * wet to its top: S = 41 N/m, no hydrostatic figure. Without the M and P
     * columns: refused, naming the setting. */
    {
        char *mrun = test_scratch("analysis-momentum");
        ck_assert_ptr_nonnull(mrun);
        ck_assert(asprintf(&path, "%s/scene.resolved.yaml", mrun) > 0);
        FILE *scene = fopen(path, "w");
        ck_assert_ptr_nonnull(scene);
        fputs("dimensions: 2\nparticles:\n  rest_density: 998\nplugins:\n  section_gauge:\n"
              "    positions: [0.5, 0.8, 1.2]\n    bed_elevation: [0, 0, 0]\n"
              "    top: [0.4, 0.032, 0.4]\n"
              "    forces: true\n  wall_force:\n    walls: step\n",
              scene);
        fclose(scene);
        free(path);
        /* the face's force: Fx = -30 + 5 sin(2 pi t) N/m, mean -30 over [1, 3] */
        ck_assert(asprintf(&path, "%s/wall_forces.csv", mrun) > 0);
        FILE *wf = fopen(path, "w");
        ck_assert_ptr_nonnull(wf);
        fputs("time,Fx_step,Fy_step,wet_step\n", wf);
        for (int i = 0; i <= 512; i++)
            fprintf(wf, "%.17g,%.17g,0,0.032\n", i / 128.0, -30 + 5 * sin(2 * M_PI * i / 128.0));
        fclose(wf);
        free(path);
        for (int with_forces = 1; with_forces >= 0; with_forces--) {
            ck_assert(asprintf(&path, "%s/sections.csv", mrun) > 0);
            FILE *t = fopen(path, "w");
            ck_assert_ptr_nonnull(t);
            fputs(with_forces ? "time,d_x0,q_x0,U_x0,Fr_x0,M_x0,P_x0,d_x1,q_x1,U_x1,Fr_x1,M_x1,"
                                "P_x1,d_x2,q_x2,U_x2,Fr_x2,M_x2,P_x2\n"
                              : "time,d_x0,q_x0,U_x0,Fr_x0,d_x1,q_x1,U_x1,Fr_x1,d_x2,q_x2,U_x2,"
                                "Fr_x2\n",
                  t);
            for (int i = 0; i <= 512; i++) {
                const double time = i / 128.0, s1 = sin(2 * M_PI * time), s2 = sin(4 * M_PI * time);
                if (with_forces)
                    fprintf(t, "%.17g,%.17g,0.05,0.5,0.5,%.17g,%.17g,0.032,0,0,0,1,40,0.15,0.05,"
                               "0.33,0.27,16,110\n",
                            time, 0.1 + 0.01 * s2, 25 + 2 * s1, 49.05 + 3 * s1);
                else
                    fprintf(t, "%.17g,%.17g,0.05,0.5,0.5,0.032,0,0,0,0.15,0.05,0.33,0.27\n", time,
                            0.1 + 0.01 * s2);
            }
            fclose(t);
            free(path);
            ck_assert(asprintf(&args, "momentum %s --from 1 --to 3 --no-plot", mrun) > 0);
            status = analyze(mrun, args, &out, &err);
            fprintf(stderr, "cli momentum (forces %d): exit %d\n%s%s", with_forces, status, out,
                    err);
            if (with_forces) {
                ck_assert_int_eq(status, 0);
                ck_assert_double_eq_tol(headline(out, "S_x0"), 74.05, 1e-9);
                ck_assert_double_eq_tol(headline(out, "S_x1"), 41, 1e-9);
                ck_assert_double_eq_tol(headline(out, "Fx_step"), -30, 1e-9);
                ck_assert_double_eq_tol(headline(out, "Fy_step"), 0, 1e-12);
                /* the budget between the full sections 0 and 2 with the face's
                 * force on the fluid, +30: 74.05 - 126 + 30 */
                ck_assert_double_eq_tol(headline(out, "S_x2"), 126, 1e-9);
                ck_assert_double_eq_tol(headline(out, "balance"), -21.95, 1e-9);
                ck_assert_double_eq(headline(out, "rest_density"), 998);
                ck_assert_ptr_nonnull(strstr(out, "0.5, 0, 0.1, 0.05, 25, 49.05, 74.05, 48.9519\n"));
                ck_assert_ptr_nonnull(strstr(out, "0.8, 0, 0.032, 0, 1, 40, 41, nan (wet to its top"));
            } else {
                ck_assert_int_eq(status, 2);
                ck_assert_ptr_nonnull(strstr(err, "forces: true"));
            }
            free(args);
            free(out);
            free(err);
        }
        ck_assert(asprintf(&args, "rm -rf '%s'", mrun) > 0);
        ck_assert_int_eq(system(args), 0);
        free(args);
        free(mrun);
    }

    /* bad input: one line on stderr naming the problem, exit 2 */
    static const struct {
        const char *args, *needle;
    } bad[] = {
        {"conjugate %s/nowhere --d1 0.02 --v1 1.5 --x 1", "does not exist"},
        {"spectrum %s --column nosuch", "nosuch"},
        {"spectrum %s --column missing.csv:d_x1", "missing.csv"},
        {"correlate %s/sections.csv:d_x7 %s/sections.csv:d_x1", "d_x7"},
        {"conjugate %s --d1 0.02 --v1 -1 --x 1", "--v1 must be positive"},
        {"toe %s --d1 0.02 --v1 1.5 --bogus 1", "--bogus"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        ck_assert(asprintf(&args, bad[i].args, run, run) > 0);
        status = analyze(run, args, &out, &err);
        fprintf(stderr, "cli bad input '%s': exit %d, stderr: %s", args, status, err);
        ck_assert_int_eq(status, 2);
        ck_assert_int_eq(test_count_lines(err, ""), 1);
        ck_assert_ptr_nonnull(strstr(err, bad[i].needle));
        free(args);
        free(out);
        free(err);
    }
    ck_assert(asprintf(&args, "rm -rf '%s'", run) > 0);
    ck_assert_int_eq(system(args), 0);
    free(args);
    free(run);
}
END_TEST

/* ------------------------------------------- stepped chute (seed 001) -- */

START_TEST(chute_geometry)
{
    const double theta = atan(0.4); /* Chanson's chute: 0.1 m steps, 0.25 m treads */
    /* a velocity U along the pseudo-bottom plus any normal component W */
    const double U = 1.7, W = 0.3, c = cos(theta), s = sin(theta);
    ck_assert_double_eq_tol(sluice_hyd_chute_velocity(U * c + W * s, -U * s + W * c, theta), U,
                            1e-15);
    /* a point y along the normal from the edge, shifted by t along the
     * pseudo-bottom */
    double offset;
    const double y = 0.037, t = -0.002;
    double d = sluice_hyd_normal_distance(0.5 + y * s + t * c, 0.2 + y * c - t * s, 0.5, 0.2,
                                          theta, &offset);
    ck_assert_double_eq_tol(d, y, 1e-16);
    ck_assert_double_eq_tol(offset, t, 1e-16);
}
END_TEST

/* The profile integral is the trapezoid rule on the finite points, with C
 * held below the first: exact on a piecewise-linear profile. Y90, d and
 * C_mean of a profile rising quadratically from C0 at y = a to 0.9 at
 * y = Yt (grid points, spacing Delta): the trapezoid rule on a quadratic
 * overestimates the integral of C by exactly L Delta^2 C''/12 =
 * (0.9 - C0) Delta^2 / (6 L), L = Yt - a, so
 *   d = Yt - [C0 Yt + (0.9 - C0) L/3 + (0.9 - C0) Delta^2 / (6 L)]
 * to round-off, against the exact Yt (1 - C0) - (0.9 - C0) L/3. */
START_TEST(aerated_depths)
{
    enum { N = 21 };
    const double delta = 0.005;
    double y[N], c[N];
    /* piecewise linear with a nan point and the first point at y = 2 Delta */
    for (int k = 0; k < N; k++) {
        y[k] = (k + 2) * delta;
        c[k] = y[k] < 0.05 ? 0.1 : 0.1 + 15.0 * (y[k] - 0.05);
    }
    c[4] = NAN;
    /* integral over [0, 0.07]: 0.1 x 0.05 + (0.1 + 0.4)/2 x 0.02 (C held
     * at 0.1 below the first point, 0.01 m) */
    ck_assert_double_eq_tol(sluice_hyd_profile_integral(y, c, N, 0.0, 0.07),
                            0.1 * 0.05 + 0.5 * (0.1 + 0.4) * 0.02, 1e-15);
    ck_assert(isnan(sluice_hyd_profile_integral(y, c, N, 0.0, 0.2)));
    ck_assert_double_eq_tol(sluice_hyd_band_mean(y, c, N, 0.01, 0.04), 0.1, 1e-15);
    /* linear part: the band mean is the midpoint value */
    ck_assert_double_eq_tol(sluice_hyd_band_mean(y, c, N, 0.06, 0.08), 0.1 + 15.0 * 0.02, 1e-14);
    /* Y90 on the linear part: 0.05 + 0.8/15 (between grid points) */
    double y90, d, cm;
    ck_assert_int_eq(sluice_hyd_aerated_depths(y, c, N, 0.9, &y90, &d, &cm), 0);
    const double y90_exact = 0.05 + 0.8 / 15.0;
    ck_assert_double_eq_tol(y90, y90_exact, 1e-15);
    const double d_exact = y90_exact - (0.1 * 0.05 + 0.5 * (0.1 + 0.9) * (y90_exact - 0.05));
    ck_assert_double_eq_tol(d, d_exact, 1e-15);
    ck_assert_double_eq_tol(cm, 1.0 - d_exact / y90_exact, 1e-14);

    /* quadratic rise: the trapezoid's known error */
    const double c0 = 0.15, a = 0.04, Yt = 0.075, L = Yt - a;
    for (int k = 0; k < N; k++) {
        y[k] = k * delta;
        const double z = (y[k] - a) / L;
        c[k] = y[k] <= a ? c0 : y[k] <= Yt + 1e-12 ? c0 + (0.9 - c0) * z * z : 1.0;
    }
    ck_assert_int_eq(sluice_hyd_aerated_depths(y, c, N, 0.9, &y90, &d, &cm), 0);
    const double trapezoid = Yt - (c0 * Yt + (0.9 - c0) * L / 3 + (0.9 - c0) * delta * delta /
                                                                      (6 * L));
    const double exact = Yt * (1 - c0) - (0.9 - c0) * L / 3;
    fprintf(stderr, "aerated depths (quadratic C): Y90 = %.6f m, d = %.9f m (trapezoid "
                    "expected %.9f, exact %.9f), C_mean = %.6f\n",
            y90, d, trapezoid, exact, cm);
    ck_assert_double_eq_tol(y90, Yt, 1e-15);
    ck_assert_double_eq_tol(d, trapezoid, 1e-15);
    ck_assert_double_eq_tol(cm, 1 - trapezoid / Yt, 1e-14);
    ck_assert_double_eq_tol(sluice_hyd_band_mean(y, c, N, 0.2 * y90, 0.5 * y90), c0, 1e-15);

    /* no Y90: never reaching 0.9, or already above it at the first point */
    for (int k = 0; k < N; k++)
        c[k] = 0.5;
    ck_assert_int_eq(sluice_hyd_aerated_depths(y, c, N, 0.9, &y90, &d, &cm), -1);
    ck_assert(isnan(y90) && isnan(d) && isnan(cm));
    c[0] = NAN;
    c[1] = 0.95;
    ck_assert_int_eq(sluice_hyd_aerated_depths(y, c, N, 0.9, &y90, &d, &cm), -1);
    /* the first value above a threshold, nan skipped */
    const double core[5] = {0.0, NAN, 0.03, 0.06, 0.2};
    ck_assert_int_eq(sluice_hyd_first_above(core, 5, 0.05), 3);
    ck_assert_int_eq(sluice_hyd_first_above(core, 5, 0.5), -1);
}
END_TEST

/* A synthetic chute: six lines of 21 points (y = 0 .. 0.1 m, Delta = 5 mm)
 * normal to a 21.8 deg pseudo-bottom at step edges 0.25 m apart (steps 3-8),
 * the odd lines listed from the top down. Along the pseudo-bottom
 * U = Umax_l (y/0.05)^(1/6) (Umax_l above 0.05 m), Umax_l = 1 + 0.2 l, plus a
 * normal component 0.3 m/s, times (1 + 0.2 s_i) with s = 1, 0.5, -1, -0.5
 * over the rows (zero mean over every 4 rows and over the even rows); the
 * points at y >= 0.085 m are dry (nan) in the odd rows, the top one in
 * every row. Air concentration (if with_air): C = C0 up to a, quadratic to
 * 0.9 at Yt, linear to 1 over 2 Delta (line 5: linear from C0 at a to 1 at
 * b, Y90 between grid points), plus 0.1 C (1 - C) s_i. Rows 100..199
 * (t = 1.00 .. 1.99 s) are the window; the others carry U = 100 m/s and
 * C = 0.5, which a wrong window would show. */
typedef struct step_line_spec {
    double c0, a, yt, b; /* b > 0: line 5's linear rise to 1 at b */
} step_line_spec;

static const step_line_spec step_lines[6] = {
    {0.00, 0.040, 0.060, 0}, {0.03, 0.035, 0.065, 0}, {0.06, 0.040, 0.070, 0},
    {0.15, 0.040, 0.075, 0}, {0.25, 0.045, 0.080, 0}, {0.30, 0.045, 0, 0.085},
};
#define STEP_N 21
#define STEP_DY 0.005
#define STEP_THETA_DEG 21.8

static double step_c(int l, double y)
{
    const step_line_spec *s = &step_lines[l];
    if (y <= s->a + 1e-12)
        return s->c0;
    if (s->b > 0)
        return y >= s->b - 1e-12 ? 1.0 : s->c0 + (1.0 - s->c0) * (y - s->a) / (s->b - s->a);
    if (y <= s->yt + 1e-12) {
        const double z = (y - s->a) / (s->yt - s->a);
        return s->c0 + (0.9 - s->c0) * z * z;
    }
    return y >= s->yt + 2 * STEP_DY - 1e-12 ? 1.0 : 0.9 + 0.1 * (y - s->yt) / (2 * STEP_DY);
}

static double step_u(int l, double y)
{
    const double umax = 1.0 + 0.2 * l;
    return y >= 0.05 ? umax : umax * pow(y / 0.05, 1.0 / 6.0);
}

/* Point k of the gauge: line l, grid index j (odd lines top down). */
static void step_point(int k, int *l, int *j)
{
    *l = k / STEP_N;
    *j = *l % 2 ? STEP_N - 1 - k % STEP_N : k % STEP_N;
}

static char *make_step_run(int with_air)
{
    char *dir = test_scratch("analysis-steps");
    if (!dir)
        return NULL;
    const double theta = STEP_THETA_DEG * M_PI / 180.0, s = sin(theta), c = cos(theta);
    char *path = NULL;
    FILE *f;
    if (asprintf(&path, "%s/scene.resolved.yaml", dir) < 0 || !(f = fopen(path, "w")))
        return NULL;
    fputs("dimensions: 2\nparticles:\n  spacing: 0.008\n  smoothing_length_ratio: 1.225\n"
          "plugins:\n  point_gauge:\n    fields: velocity, air_fraction\n    file: points.csv\n"
          "    points:\n",
          f);
    for (int k = 0; k < 6 * STEP_N; k++) {
        int l, j;
        step_point(k, &l, &j);
        const double ex = 0.6 + 0.25 * l, ey = 0.9 - 0.1 * l, y = j * STEP_DY;
        fprintf(f, "      - [%.17g, %.17g]\n", ex + y * s, ey + y * c);
    }
    fclose(f);
    free(path);
    if (asprintf(&path, "%s/points.csv", dir) < 0 || !(f = fopen(path, "w")))
        return NULL;
    fputs("time", f);
    for (int k = 0; k < 6 * STEP_N; k++) {
        fprintf(f, ",p%d_velocity_x,p%d_velocity_y", k, k);
        if (with_air)
            fprintf(f, ",p%d_air_fraction", k);
    }
    fputc('\n', f);
    static const double pattern[4] = {1.0, 0.5, -1.0, -0.5};
    for (int i = 0; i < 220; i++) {
        fprintf(f, "%.17g", 0.01 * i);
        const int inside = i >= 100 && i < 200;
        const double si = pattern[i % 4];
        for (int k = 0; k < 6 * STEP_N; k++) {
            int l, j;
            step_point(k, &l, &j);
            const double y = j * STEP_DY;
            const double U = inside ? step_u(l, y) * (1 + 0.2 * si) : 100.0, W = 0.3;
            if (j == STEP_N - 1 || (y >= 0.085 - 1e-12 && i % 4 == 3))
                fputs(",nan,nan", f);
            else
                fprintf(f, ",%.17g,%.17g", U * c + W * s, -U * s + W * c);
            if (with_air) {
                const double C = step_c(l, y);
                fprintf(f, ",%.17g", inside ? C + 0.1 * C * (1 - C) * si : 0.5);
            }
        }
        fputc('\n', f);
    }
    fclose(f);
    free(path);
    return dir;
}

/* The rows after the n-th (0-based) line equal to `header`. */
static const char *csv_section(const char *text, const char *header, int n)
{
    size_t len = strlen(header);
    for (const char *line = text; line && *line;) {
        if (strncmp(line, header, len) == 0 && line[len] == '\n' && n-- == 0)
            return line + len + 1;
        line = strchr(line, '\n');
        if (line)
            line++;
    }
    return NULL;
}

START_TEST(cli_step_profiles)
{
    char *run = make_step_run(1);
    ck_assert_ptr_nonnull(run);
    const double theta = STEP_THETA_DEG * M_PI / 180.0, s = sin(theta), c = cos(theta);
    const double dc = 0.07, uc = 0.668;
    char edges[512] = "";
    for (int l = 0; l < 6; l++) {
        size_t used = strlen(edges);
        snprintf(edges + used, sizeof edges - used, "%s%.17g,%.17g", l ? ";" : "",
                 0.6 + 0.25 * l, 0.9 - 0.1 * l);
    }
    char *args = NULL, *out = NULL, *err = NULL;
    ck_assert(asprintf(&args,
                       "step-profiles %s/points.csv --per-line 21 --edges '%s' --theta 21.8 "
                       "--dc 0.07 --uc 0.668 --from 0.995 --to 1.995 --first-step 3",
                       run, edges) > 0);
    int status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli step-profiles: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    ck_assert_int_eq(test_count_lines(err, "warning"), 0);
    /* the points: y, y/dc, the time means and their sample counts; the
     * program prints 10 significant digits */
    for (int l = 0; l < 6; l++) {
        const char *row = csv_section(out, "step,point,y,y_dc,U_Uc,U_samples,C,C_samples", l);
        ck_assert_ptr_nonnull(row);
        for (int j = 0; j < STEP_N; j++) {
            long step;
            size_t point, nu, nc;
            double y, ydc, u, cc;
            ck_assert_int_eq(sscanf(row, "%ld,%zu,%lf,%lf,%lf,%zu,%lf,%zu", &step, &point, &y,
                                    &ydc, &u, &nu, &cc, &nc),
                             8);
            const double ye = j * STEP_DY;
            /* sorted by y whatever the gauge order (odd lines top down) */
            ck_assert_uint_eq(point, (size_t)(l * STEP_N + (l % 2 ? STEP_N - 1 - j : j)));
            ck_assert_int_eq(step, 3 + l);
            ck_assert_double_eq_tol(y, ye, 1e-12);
            ck_assert_double_eq_tol(ydc, ye / dc, 1e-9);
            if (j == STEP_N - 1) {
                ck_assert(isnan(u));
                ck_assert_uint_eq(nu, 0);
            } else if (ye >= 0.085 - 1e-12) {
                /* wet at 3 of every 4 samples: the pattern's mean (1 + 0.5 - 1) / 3 */
                ck_assert_double_eq_tol(u, step_u(l, ye) * (1 + 0.2 / 6) / uc, 1e-9);
                ck_assert_uint_eq(nu, 75);
            } else {
                ck_assert_double_eq_tol(u, step_u(l, ye) / uc, 1e-9);
                ck_assert_uint_eq(nu, 100);
            }
            ck_assert_double_eq_tol(cc, step_c(l, ye), 1e-9);
            ck_assert_uint_eq(nc, 100);
            row = strchr(row, '\n') + 1;
        }
    }
    /* per edge: Y90 and d against the trapezoid's known value (quadratic
     * rise: error (0.9 - C0) Delta^2 / (6 L) in the integral of C; line 5
     * linear: exact), C_mean, max U/Uc = Umax/Uc, C_core = C0 */
    const char *row = csv_section(out, "step,edge_x,edge_y,Y90,Y90_dc,d,d_dc,C_mean,U_Uc_max,"
                                       "C_core,surface,surface_dc", 0);
    ck_assert_ptr_nonnull(row);
    for (int l = 0; l < 6; l++) {
        long step;
        double ex, ey, y90, y90dc, d, ddc, cm, um, core, surface, surface_dc;
        ck_assert_int_eq(sscanf(row, "%ld,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &step,
                                &ex, &ey, &y90, &y90dc, &d, &ddc, &cm, &um, &core, &surface,
                                &surface_dc),
                         12);
        /* the surface: wet 3/4 of the time at y = 0.095 m, never at 0.1 m,
         * so 1/2 is crossed a third of the way up, linearly */
        ck_assert_double_eq_tol(surface, 0.095 + STEP_DY / 3, 1e-11);
        ck_assert_double_eq_tol(surface_dc, (0.095 + STEP_DY / 3) / dc, 1e-9);
        const step_line_spec *sp = &step_lines[l];
        double y90e, de, exact;
        if (sp->b > 0) {
            y90e = sp->a + (0.9 - sp->c0) / (1 - sp->c0) * (sp->b - sp->a);
            de = exact = y90e - (sp->c0 * sp->a + 0.5 * (sp->c0 + 0.9) * (y90e - sp->a));
        } else {
            const double L = sp->yt - sp->a;
            y90e = sp->yt;
            de = y90e - (sp->c0 * sp->yt + (0.9 - sp->c0) * L / 3 +
                         (0.9 - sp->c0) * STEP_DY * STEP_DY / (6 * L));
            exact = y90e * (1 - sp->c0) - (0.9 - sp->c0) * L / 3;
        }
        fprintf(stderr, "step %ld: Y90 = %.6f m (expected %.6f), d = %.8f m (trapezoid %.8f, "
                        "exact %.8f), C_mean = %.5f, U/Uc max = %.5f, C_core = %.5f\n",
                step, y90, y90e, d, de, exact, cm, um, core);
        ck_assert_int_eq(step, 3 + l);
        ck_assert_double_eq_tol(y90, y90e, 1e-11);
        ck_assert_double_eq_tol(y90dc, y90e / dc, 1e-9);
        ck_assert_double_eq_tol(d, de, 1e-11);
        ck_assert_double_eq_tol(cm, 1 - de / y90e, 1e-9);
        ck_assert_double_eq_tol(um, (1.0 + 0.2 * l) * (1 + 0.2 / 6) / uc, 1e-9);
        ck_assert_double_eq_tol(core, sp->c0, 1e-9);
        row = strchr(row, '\n') + 1;
    }
    /* inception: the first edge whose C_core exceeds 0.05: step 5 (line 1's
     * 0.03 stays below) */
    row = csv_section(out, "inception_step,edge_x,edge_y,C_core,threshold", 0);
    ck_assert_ptr_nonnull(row);
    long inception = 0;
    double core = NAN;
    ck_assert_int_eq(sscanf(row, "%ld,%*f,%*f,%lf", &inception, &core), 2);
    ck_assert_int_eq(inception, 5);
    ck_assert_double_eq_tol(core, 0.06, 1e-9);
    free(args);
    free(out);
    free(err);

    /* a higher threshold moves it to step 7; above every C_core: none, exit
     * 1 after the profiles; a larger h warns about the shallowest edge only
     * (Y90 = 0.06 m < 5.4 h = 0.0648 m) */
    ck_assert(asprintf(&args,
                       "step-profiles %s/points.csv --per-line 21 --edges '%s' --theta 21.8 "
                       "--dc 0.07 --uc 0.668 --from 0.995 --to 1.995 --first-step 3 "
                       "--threshold 0.2 --h 0.012",
                       run, edges) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli step-profiles --threshold 0.2 --h 0.012: exit %d\n%s", status, err);
    ck_assert_int_eq(status, 0);
    row = csv_section(out, "inception_step,edge_x,edge_y,C_core,threshold", 0);
    ck_assert_ptr_nonnull(row);
    ck_assert_int_eq(atoi(row), 7);
    ck_assert_int_eq(test_count_lines(err, "warning"), 1);
    ck_assert_ptr_nonnull(strstr(err, "warning: step 3:"));
    free(args);
    free(out);
    free(err);
    ck_assert(asprintf(&args,
                       "step-profiles %s/points.csv --per-line 21 --edges '%s' --theta 21.8 "
                       "--dc 0.07 --uc 0.668 --threshold 0.5",
                       run, edges) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli step-profiles --threshold 0.5: exit %d, %s", status, err);
    ck_assert_int_eq(status, 1);
    ck_assert_ptr_nonnull(strstr(out, "\nnan,nan,nan,nan,0.5\n"));
    ck_assert_ptr_nonnull(strstr(err, "no step edge"));
    free(args);
    free(out);
    free(err);

    /* given the run directory: the same CSV in RUN/analysis/step_profiles.csv,
     * the figures as name = value lines (what a study reads); no inception
     * is the figure nan, exit 0 */
    char *csv_mode = NULL;
    for (int pass = 0; pass < 3; pass++) {
        ck_assert(asprintf(&args,
                           "step-profiles %s%s --per-line 21 --edges '%s' --theta 21.8 "
                           "--dc 0.07 --uc 0.668 --from 0.995 --to 1.995 --first-step 3%s",
                           run, pass == 0 ? "/points.csv" : "", edges,
                           pass == 2 ? " --threshold 0.5" : "") > 0);
        status = analyze(run, args, &out, &err);
        fprintf(stderr, "cli step-profiles (pass %d): exit %d\n%s%s", pass, status,
                pass ? out : "", err);
        ck_assert_int_eq(status, 0);
        free(args);
        if (pass == 0) {
            csv_mode = out;
            free(err);
            continue;
        }
        char *written = NULL;
        ck_assert(asprintf(&args, "%s/analysis/step_profiles.csv", run) > 0);
        written = test_read_file(args);
        free(args);
        ck_assert_ptr_nonnull(written);
        if (pass == 1)
            ck_assert_str_eq(written, csv_mode);
        free(written);
        ck_assert_ptr_nonnull(strstr(out, "/points.csv\n"));
        double figure = NAN;
        const char *at = strstr(out, "\nU_Uc_max_step4 = ");
        ck_assert_ptr_nonnull(at);
        ck_assert_double_eq_tol(strtod(strchr(at, '=') + 1, NULL), 1.2 * (1 + 0.2 / 6) / uc, 1e-9);
        at = strstr(out, "\nsurface_dc_step8 = ");
        ck_assert_ptr_nonnull(at);
        ck_assert_double_eq_tol(strtod(strchr(at, '=') + 1, NULL), (0.095 + STEP_DY / 3) / dc, 1e-9);
        at = strstr(out, "\nC_core_step5 = ");
        ck_assert_ptr_nonnull(at);
        ck_assert_double_eq_tol(strtod(strchr(at, '=') + 1, NULL), 0.06, 1e-9);
        at = strstr(out, "\ninception_step = ");
        ck_assert_ptr_nonnull(at);
        figure = strtod(strchr(at, '=') + 1, NULL);
        if (pass == 1)
            ck_assert_double_eq(figure, 5);
        else
            ck_assert(isnan(figure));
        free(out);
        free(err);
    }
    free(csv_mode);

    /* bad input: one line on stderr naming the problem, exit 2 */
    char points[8192] = "";
    for (int k = 0; k < 6 * STEP_N - 1; k++) {
        int l, j;
        step_point(k, &l, &j);
        size_t used = strlen(points);
        snprintf(points + used, sizeof points - used, "%s%.17g,%.17g", k ? ";" : "",
                 0.6 + 0.25 * l + j * STEP_DY * s, 0.9 - 0.1 * l + j * STEP_DY * c);
    }
    const char *common = "--edges '%s' --theta 21.8 --dc 0.07";
    static const struct {
        const char *args, *needle;
    } bad[] = {
        {"step-profiles %s/points.csv --per-line 21 %s", "needs --uc"},
        {"step-profiles %s/points.csv --per-line 20 %s --uc 0.668", "has 126 points"},
        {"step-profiles %s/points.csv --per-line 21 %s --uc 0.668 --points '%s'",
         "125 point coordinates"},
        {"step-profiles %s/points.csv --per-line 21 %s --uc 0.668 --theta 30", "off the normal"},
        {"step-profiles %s/points.csv --per-line 21 --theta 21.8 --dc 0.07 --uc 0.668 %.0s",
         "needs --edges"},
        {"step-profiles %s/nowhere.csv --per-line 21 %s --uc 0.668", "nowhere.csv"},
        {"step-profiles %s/points.csv --per-line 2.5 %s --uc 0.668", "whole number"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        char *opts = NULL;
        ck_assert(asprintf(&opts, common, edges) > 0);
        ck_assert(asprintf(&args, bad[i].args, run, opts, points) > 0);
        free(opts);
        status = analyze(run, args, &out, &err);
        fprintf(stderr, "cli step-profiles bad input %zu: exit %d, stderr: %s", i, status, err);
        ck_assert_int_eq(status, 2);
        ck_assert_int_eq(test_count_lines(err, ""), 1);
        ck_assert_ptr_nonnull(strstr(err, bad[i].needle));
        free(args);
        free(out);
        free(err);
    }
    ck_assert(asprintf(&args, "rm -rf '%s'", run) > 0);
    ck_assert_int_eq(system(args), 0);
    free(args);
    free(run);

    /* without air_fraction columns: the velocity profiles alone, exit 0 */
    run = make_step_run(0);
    ck_assert_ptr_nonnull(run);
    ck_assert(asprintf(&args,
                       "step-profiles %s/points.csv --per-line 21 --edges '%s' --theta 21.8 "
                       "--dc 0.07 --uc 0.668 --from 0.995 --to 1.995",
                       run, edges) > 0);
    status = analyze(run, args, &out, &err);
    fprintf(stderr, "cli step-profiles without air: exit %d, %s", status, err);
    ck_assert_int_eq(status, 0);
    ck_assert_ptr_nonnull(strstr(err, "no p<k>_air_fraction"));
    row = csv_section(out, "step,point,y,y_dc,U_Uc,U_samples,C,C_samples", 2);
    ck_assert_ptr_nonnull(row);
    for (int j = 0; j < 12; j++)
        row = strchr(row, '\n') + 1;
    double u12 = NAN;
    ck_assert_int_eq(sscanf(row, "%*d,%*u,%*f,%*f,%lf", &u12), 1);
    ck_assert_double_eq_tol(u12, step_u(2, 12 * STEP_DY) / uc, 1e-9);
    free(args);
    free(out);
    free(err);
    ck_assert(asprintf(&args, "rm -rf '%s'", run) > 0);
    ck_assert_int_eq(system(args), 0);
    free(args);
    free(run);
}
END_TEST

/* Dissolved oxygen: a particle under a constant exposure K a for a time t
 * has the deficit D0 exp(-K a t); scaling K by f is raising the deficit
 * ratio to the power f, so the map is the identity at f = 1, composes
 * (f1 then f2 is f1 f2) and is exact on the analytic relaxation. The
 * station mean averages each sample's wet points, then the samples; the
 * calibration recovers the scale that generated a target. */
START_TEST(dissolved_oxygen_scaling)
{
    const double cs = 10.48, cu = 1.29, d0 = cs - cu;
    for (int k = 0; k <= 20; k++) {
        const double c = cu + (cs - cu) * k / 21.0;
        ck_assert_double_eq_tol(sluice_hyd_do_scaled(c, cs, cu, 1.0), c, 1e-12);
        const double twice = sluice_hyd_do_scaled(sluice_hyd_do_scaled(c, cs, cu, 0.7), cs, cu, 1.9);
        ck_assert_double_eq_tol(twice, sluice_hyd_do_scaled(c, cs, cu, 0.7 * 1.9), 1e-12);
    }
    for (int k = 0; k <= 10; k++) {
        const double exposure = 0.15 * k; /* K a t */
        const double c = cs - d0 * exp(-exposure);
        ck_assert_double_eq_tol(sluice_hyd_do_scaled(c, cs, cu, 2.5), cs - d0 * exp(-2.5 * exposure),
                                1e-12);
    }
    ck_assert_double_eq(sluice_hyd_do_scaled(cs + 1, cs, cu, 3.0), cs);
    ck_assert(isnan(sluice_hyd_do_scaled(NAN, cs, cu, 1.0)));
    ck_assert(isnan(sluice_hyd_do_scaled(5.0, cs, cu, 0.0)));
    ck_assert(isnan(sluice_hyd_do_scaled(5.0, cu, cs, 1.0)));

    /* 3 samples of 2 points: (2, 4), (NaN, 6), (NaN, NaN) -> (3 + 6) / 2 */
    const double readings[6] = {2.0, 4.0, NAN, 6.0, NAN, NAN};
    size_t used = 0;
    ck_assert_double_eq_tol(sluice_hyd_do_station_mean(readings, 3, 2, cs, cu, 1.0, &used), 4.5,
                            1e-12);
    ck_assert_uint_eq(used, 2);
    const double nothing[2] = {NAN, NAN};
    ck_assert(isnan(sluice_hyd_do_station_mean(nothing, 1, 2, cs, cu, 1.0, &used)));
    ck_assert_uint_eq(used, 0);

    /* readings from exposures E; the target made with f = 1.7 */
    enum { SAMPLES = 40, PER = 5 };
    double r[SAMPLES * PER];
    double target = 0;
    for (int s = 0; s < SAMPLES; s++) {
        double line = 0;
        for (int k = 0; k < PER; k++) {
            const double exposure = 0.05 + 0.6 * fmod(0.6180339887 * (s * PER + k + 1), 1.0);
            r[s * PER + k] = (s + k) % 7 == 3 ? NAN : cs - d0 * exp(-exposure);
            if (!isnan(r[s * PER + k]))
                line += cs - d0 * exp(-1.7 * exposure);
        }
        int wet = 0;
        for (int k = 0; k < PER; k++)
            wet += !isnan(r[s * PER + k]);
        target += line / wet;
    }
    target /= SAMPLES;
    double f = 0;
    ck_assert_int_eq(sluice_hyd_do_calibrate(r, SAMPLES, PER, cs, cu, target, &f), 0);
    ck_assert_double_eq_tol(f, 1.7, 1e-9);
    ck_assert_int_eq(sluice_hyd_do_calibrate(r, SAMPLES, PER, cs, cu, cs + 0.1, &f), -1);
    ck_assert_int_eq(sluice_hyd_do_calibrate(r, SAMPLES, PER, cs, cu, cu, &f), -1);
    ck_assert_int_eq(sluice_hyd_do_calibrate(nothing, 1, 2, cs, cu, 5.0, &f), -1);
}
END_TEST

/* The command on a table of 2 stations of 2 points over 3 samples:
 * station means, the window, the rate at the last station and the
 * calibration on station 1 (its calibrated mean is the target). */
START_TEST(cli_dissolved_oxygen)
{
    char *dir = test_scratch("analysis-do");
    ck_assert_ptr_nonnull(dir);
    char *path = test_write_file(dir, "points.csv",
                                 "time,p0_dissolved_oxygen,p1_dissolved_oxygen,"
                                 "p2_dissolved_oxygen,p3_dissolved_oxygen\n"
                                 "0.5,9,9,9,9\n"
                                 "1.0,2,4,5,nan\n"
                                 "1.5,nan,3,7,5\n"
                                 "2.0,3,3,nan,nan\n");
    ck_assert_ptr_nonnull(path);
    char *args = NULL, *out = NULL, *err = NULL;
    ck_assert(asprintf(&args,
                       "dissolved-oxygen %s --per-line 2 --cs 10 --cu 1 --from 1 --to 2 "
                       "--calibrate 1 --target 4",
                       path) > 0);
    int status = analyze(dir, args, &out, &err);
    fprintf(stderr, "cli dissolved-oxygen: exit %d\n%s%s", status, out, err);
    ck_assert_int_eq(status, 0);
    const char *row = strstr(out, "station,mean_mg_L,samples,calibrated_mg_L\n");
    ck_assert_ptr_nonnull(row);
    row = strchr(row, '\n') + 1;
    size_t station, samples;
    double mean, calibrated;
    ck_assert_int_eq(sscanf(row, "%zu,%lf,%zu,%lf", &station, &mean, &samples, &calibrated), 4);
    ck_assert_uint_eq(station, 1);
    ck_assert_double_eq_tol(mean, (3.0 + 3.0 + 3.0) / 3, 1e-5);
    ck_assert_uint_eq(samples, 3);
    ck_assert_double_eq_tol(calibrated, 4.0, 1e-5);
    row = strchr(row, '\n') + 1;
    ck_assert_int_eq(sscanf(row, "%zu,%lf,%zu,%lf", &station, &mean, &samples, &calibrated), 4);
    ck_assert_uint_eq(station, 2);
    ck_assert_double_eq_tol(mean, (5.0 + 6.0) / 2, 1e-5);
    ck_assert_uint_eq(samples, 2);
    ck_assert(calibrated > mean && calibrated < 10);
    ck_assert_ptr_nonnull(strstr(out, "rate r = (Cs - Cu)/(Cs - C) at station 2: 2 (calibrated"));
    free(args);
    free(out);
    free(err);
    /* bad input: one message, exit 2 */
    ck_assert(asprintf(&args, "dissolved-oxygen %s --per-line 3 --cs 10 --cu 1", path) > 0);
    status = analyze(dir, args, &out, &err);
    ck_assert_int_eq(status, 2);
    ck_assert_ptr_nonnull(strstr(err, "not a whole number of stations"));
    free(args);
    free(out);
    free(err);
    ck_assert(asprintf(&args, "dissolved-oxygen %s --per-line 2 --cs 10 --cu 1 --calibrate 1",
                       path) > 0);
    status = analyze(dir, args, &out, &err);
    ck_assert_int_eq(status, 2);
    ck_assert_ptr_nonnull(strstr(err, "go together"));
    free(args);
    free(out);
    free(err);
    free(path);
    free(dir);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("analysis");
    TCase *c = tcase_create("analysis");
    tcase_add_test(c, belanger_seed000);
    tcase_add_test(c, reference_relations);
    tcase_add_test(c, conjugate_statistics);
    tcase_add_test(c, fft_dft_parseval);
    tcase_add_test(c, spectrum_bin_centred);
    tcase_add_test(c, spectrum_off_bin_zero_padded);
    tcase_add_test(c, detrend_and_resample);
    tcase_add_test(c, pearson);
    tcase_add_test(c, toe_moving_front);
    tcase_add_test(c, roller_synthetic);
    tcase_add_test(c, vmax_synthetic);
    tcase_add_test(c, surface_statistics);
    tcase_add_test(c, profile_errors);
    tcase_add_test(c, drop_limits_belanger);
    tcase_add_test(c, drop_table1);
    tcase_add_test(c, drop_states_and_type);
    tcase_add_test(c, cli);
    tcase_add_test(c, chute_geometry);
    tcase_add_test(c, aerated_depths);
    tcase_add_test(c, cli_step_profiles);
    tcase_add_test(c, dissolved_oxygen_scaling);
    tcase_add_test(c, cli_dissolved_oxygen);
    tcase_add_test(c, cli_front);
    suite_add_tcase(s, c);
    return test_run_suite(s);
}
