/* Hydraulic-jump measurements: the numerical functions of sluice-analyze
 * (declarations and contracts in hydraulics.h, definitions and references in
 * docs/analysis.md). Pure functions: no I/O, no allocation, no global state. */
#include "hydraulics.h"

#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ----------------------------------------------------- reference relations */

double sluice_hyd_froude(double v, double d, double g)
{
    return v / sqrt(g * d);
}

/* Seed 000 eq. 1 (Belanger): momentum conserved across the jump in a
 * horizontal rectangular channel, d2/d1 = (sqrt(1 + 8 Fr1^2) - 1)/2. */
double sluice_hyd_belanger_depth(double d1, double fr1)
{
    return 0.5 * d1 * (sqrt(1.0 + 8.0 * fr1 * fr1) - 1.0);
}

/* Seed 000 eq. 2: Hager, W.H., Bremen, R., Kawagoshi, N. (1990), "Classical
 * hydraulic jump: length of roller", J. Hydraul. Res. 28(5), 591-608:
 * L_r/d1 = 160 tanh(Fr1/20) - 12, 2 < Fr1 < 16. */
double sluice_hyd_hager_roller_length(double d1, double fr1)
{
    return d1 * (160.0 * tanh(fr1 / 20.0) - 12.0);
}

/* Seed 000 eq. 3: Chanson, H. (2010), "Convective transport of air bubbles in
 * strong hydraulic jumps", Int. J. Multiphase Flow 36, 798-814 (seed 000 ref.
 * [9]): Vmax/V1 = exp(-0.028 (x - x1)/d1), the decay of the maximum velocity
 * of the wall jet under the roller. */
double sluice_hyd_chanson_vmax_ratio(double xi)
{
    return exp(-0.028 * xi);
}

/* Seed 000 eq. 4: Murzyn, F., Chanson, H. (2009), "Free-surface fluctuations
 * in hydraulic jumps: experimental observations", Exp. Therm. Fluid Sci. 33,
 * 1055-1064 (seed 000 ref. [17]): (eta'/d1)_max = 0.116 (Fr1 - 1)^1.235. */
double sluice_hyd_murzyn_chanson_eta_std(double fr1)
{
    return 0.116 * pow(fr1 - 1.0, 1.235);
}

/* Seed 000 eq. 5: Chachereau, Y., Chanson, H. (2011), "Free-surface
 * fluctuations and turbulence in hydraulic jumps", Exp. Therm. Fluid Sci. 35,
 * 896-909 (seed 000 refs. [19], [20]): St_fs = 0.143 exp(-0.27 Fr1),
 * 2.4 < Fr1 < 6.5. */
double sluice_hyd_chachereau_chanson_strouhal(double fr1)
{
    return 0.143 * exp(-0.27 * fr1);
}

/* ------------------------------------------------------------- statistics */

int sluice_hyd_mean_std(const double *x, size_t n, double *mean, double *std, size_t *used)
{
    /* deviations from the first finite value: a constant series has exactly
     * its value as mean and 0 as standard deviation */
    size_t count = 0;
    double x0 = 0.0, sum = 0.0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(x[i])) {
            if (count == 0)
                x0 = x[i];
            sum += x[i] - x0;
            count++;
        }
    if (used)
        *used = count;
    if (count == 0)
        return -1;
    double m = sum / (double)count, s2 = 0.0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(x[i]))
            s2 += (x[i] - x0 - m) * (x[i] - x0 - m);
    *mean = x0 + m;
    *std = sqrt(s2 / (double)count);
    return 0;
}

/* Seed 000 eqs. 19-20, the sums taken over the samples of the window; with a
 * constant d2_theory, sum_i d2_th^2 = N d2_th^2. */
int sluice_hyd_conjugate_statistics(const double *d2, size_t n, double d2_theory, double *A,
                                    double *P, size_t *used)
{
    size_t count = 0;
    double s2 = 0.0, e2 = 0.0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(d2[i])) {
            s2 += d2[i] * d2[i];
            e2 += (d2[i] - d2_theory) * (d2[i] - d2_theory);
            count++;
        }
    if (used)
        *used = count;
    if (count == 0 || !(d2_theory > 0.0))
        return -1;
    double th2 = (double)count * d2_theory * d2_theory;
    *A = sqrt(s2 / th2);
    *P = sqrt(e2 / th2);
    return 0;
}

double sluice_hyd_pearson(const double *a, const double *b, size_t n, size_t *used)
{
    /* sums of deviations from the first finite pair (shift-invariant, and a
     * constant series then has exactly zero variance) */
    size_t count = 0;
    double a0 = 0.0, b0 = 0.0, sa = 0.0, sb = 0.0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(a[i]) && isfinite(b[i])) {
            if (count == 0) {
                a0 = a[i];
                b0 = b[i];
            }
            sa += a[i] - a0;
            sb += b[i] - b0;
            count++;
        }
    if (used)
        *used = count;
    if (count < 2)
        return NAN;
    double ma = sa / (double)count, mb = sb / (double)count;
    double cab = 0.0, caa = 0.0, cbb = 0.0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(a[i]) && isfinite(b[i])) {
            double da = (a[i] - a0) - ma, db = (b[i] - b0) - mb;
            cab += da * db;
            caa += da * da;
            cbb += db * db;
        }
    if (!(caa > 0.0) || !(cbb > 0.0))
        return NAN;
    return cab / sqrt(caa * cbb);
}

/* Seed 002 (Lin et al. 2025), section 3.2: "L2 = [sqrt] (1/N) sum_i
 * ((h_i^n - h_i^e)/h_i^e)^2" -- the extracted text lost the root sign; the
 * name (an L2 norm of the relative error) and table 1 (L2 ~ 0.3 with RMSE
 * ~ 0.5-1.5 m on levels of metres) read as the root mean square. RMSE is
 * not written out in seed 002: the standard root mean square of h_n - h_e. */
int sluice_hyd_profile_errors(const double *h_num, const double *h_ref, size_t n, double *l2,
                              double *rmse, size_t *used)
{
    size_t count = 0;
    double r2 = 0.0, e2 = 0.0;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(h_num[i]) || !isfinite(h_ref[i]))
            continue;
        if (h_ref[i] == 0.0)
            return -1;
        double e = h_num[i] - h_ref[i];
        r2 += (e / h_ref[i]) * (e / h_ref[i]);
        e2 += e * e;
        count++;
    }
    if (used)
        *used = count;
    if (count == 0)
        return -1;
    *l2 = sqrt(r2 / (double)count);
    *rmse = sqrt(e2 / (double)count);
    return 0;
}

double sluice_hyd_decay_rate(const double *xi, const double *ratio, size_t n)
{
    double num = 0.0, den = 0.0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(xi[i]) && isfinite(ratio[i]) && xi[i] > 0.0 && ratio[i] > 0.0) {
            num += xi[i] * log(ratio[i]);
            den += xi[i] * xi[i];
        }
    return den > 0.0 ? -num / den : NAN;
}

double sluice_hyd_slope(const double *t, const double *y, size_t n)
{
    size_t count = 0;
    double st = 0.0, sy = 0.0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(t[i]) && isfinite(y[i])) {
            st += t[i];
            sy += y[i];
            count++;
        }
    if (count < 2)
        return NAN;
    double mt = st / (double)count, my = sy / (double)count, stt = 0.0, sty = 0.0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(t[i]) && isfinite(y[i])) {
            stt += (t[i] - mt) * (t[i] - mt);
            sty += (t[i] - mt) * (y[i] - my);
        }
    return stt > 0.0 ? sty / stt : NAN;
}

/* ---------------------------------------------------------- interpolation */

double sluice_hyd_interpolate(const double *x, const double *y, size_t n, double xq)
{
    if (n == 0 || !(xq >= x[0]) || !(xq <= x[n - 1]))
        return NAN;
    if (n == 1)
        return y[0];
    size_t lo = 0, hi = n - 1; /* x[lo] <= xq <= x[hi] */
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (x[mid] <= xq)
            lo = mid;
        else
            hi = mid;
    }
    if (xq == x[lo])
        return y[lo];
    if (xq == x[hi])
        return y[hi];
    double w = (xq - x[lo]) / (x[hi] - x[lo]);
    return y[lo] + w * (y[hi] - y[lo]);
}

int sluice_hyd_resample(const double *t, const double *y, size_t n, double t0, double t1,
                        size_t m, double *out)
{
    if (m < 2 || !(t1 > t0))
        return -1;
    size_t finite = 0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(t[i]) && isfinite(y[i]))
            finite++;
    if (finite < 2)
        return -1;
    double dt = (t1 - t0) / (double)(m - 1);
    size_t next = 0;  /* first sample with t > tk */
    size_t lo = n;    /* last finite sample with t <= tk (n: none yet) */
    size_t hi = 0;    /* first finite sample at or after `next` (n: none) */
    int hi_valid = 0; /* hi was searched from the current `next` */
    for (size_t k = 0; k < m; k++) {
        double tk = k + 1 == m ? t1 : t0 + (double)k * dt;
        while (next < n && t[next] <= tk) {
            if (isfinite(t[next]) && isfinite(y[next]))
                lo = next;
            next++;
            hi_valid = 0;
        }
        if (!hi_valid) {
            hi = next;
            while (hi < n && !(isfinite(t[hi]) && isfinite(y[hi])))
                hi++;
            hi_valid = 1;
        }
        if (lo == n)
            out[k] = y[hi]; /* before the first finite sample: hold it */
        else if (hi == n || t[lo] == tk)
            out[k] = y[lo]; /* after the last finite sample: hold it */
        else {
            double w = (tk - t[lo]) / (t[hi] - t[lo]);
            out[k] = y[lo] + w * (y[hi] - y[lo]);
        }
    }
    return 0;
}

/* --------------------------------------------------------------- spectrum */

size_t sluice_hyd_next_pow2(size_t n)
{
    size_t m = 1;
    while (m < n)
        m <<= 1;
    return m;
}

/* Iterative radix-2 Cooley-Tukey: bit-reversal permutation, then log2(n)
 * butterfly passes with twiddles exp(-/+ 2 pi i k / len) computed directly
 * (cos/sin per twiddle: no accumulated recurrence error). */
int sluice_hyd_fft(double *re, double *im, size_t n, int inverse)
{
    if (n == 0 || (n & (n - 1)) != 0)
        return -1;
    for (size_t i = 1, j = 0; i < n; i++) {
        size_t bit = n >> 1;
        for (; j & bit; bit >>= 1)
            j ^= bit;
        j ^= bit;
        if (i < j) {
            double tr = re[i], ti = im[i];
            re[i] = re[j];
            im[i] = im[j];
            re[j] = tr;
            im[j] = ti;
        }
    }
    double sign = inverse ? 1.0 : -1.0;
    for (size_t len = 2; len <= n; len <<= 1) {
        size_t half = len >> 1;
        for (size_t k = 0; k < half; k++) {
            double angle = sign * 2.0 * M_PI * (double)k / (double)len;
            double wr = cos(angle), wi = sin(angle);
            for (size_t start = 0; start < n; start += len) {
                size_t a = start + k, b = a + half;
                double xr = re[b] * wr - im[b] * wi;
                double xi = re[b] * wi + im[b] * wr;
                re[b] = re[a] - xr;
                im[b] = im[a] - xi;
                re[a] += xr;
                im[a] += xi;
            }
        }
    }
    return 0;
}

/* Least squares on k = 0..n-1: slope b = sum (k - kbar)(x - xbar) / sum (k - kbar)^2. */
void sluice_hyd_detrend(double *x, size_t n)
{
    if (n == 0)
        return;
    /* deviations from x[0] first: a constant series detrends to exact zeros */
    double x0 = x[0];
    for (size_t k = 0; k < n; k++)
        x[k] -= x0;
    double kbar = 0.5 * (double)(n - 1), xbar = 0.0;
    for (size_t k = 0; k < n; k++)
        xbar += x[k];
    xbar /= (double)n;
    double skk = 0.0, skx = 0.0;
    for (size_t k = 0; k < n; k++) {
        double dk = (double)k - kbar;
        skk += dk * dk;
        skx += dk * (x[k] - xbar);
    }
    double b = skk > 0.0 ? skx / skk : 0.0;
    for (size_t k = 0; k < n; k++)
        x[k] -= xbar + b * ((double)k - kbar);
}

void sluice_hyd_hann(double *w, size_t n)
{
    for (size_t k = 0; k < n; k++)
        w[k] = 0.5 * (1.0 - cos(2.0 * M_PI * (double)k / (double)n));
}

int sluice_hyd_amplitude_spectrum(const double *x, size_t n, double dt, double *work_re,
                                  double *work_im, double *amplitude, double *df)
{
    if (n < 2 || !(dt > 0.0))
        return -1;
    size_t m = sluice_hyd_next_pow2(n);
    for (size_t k = 0; k < n; k++)
        work_re[k] = x[k];
    sluice_hyd_detrend(work_re, n);
    double gain = 0.0;
    for (size_t k = 0; k < n; k++) {
        double w = 0.5 * (1.0 - cos(2.0 * M_PI * (double)k / (double)n));
        work_re[k] *= w;
        gain += w;
    }
    for (size_t k = n; k < m; k++)
        work_re[k] = 0.0;
    for (size_t k = 0; k < m; k++)
        work_im[k] = 0.0;
    if (sluice_hyd_fft(work_re, work_im, m, 0) != 0)
        return -1;
    for (size_t j = 0; j <= m / 2; j++) {
        double scale = (j == 0 || j == m / 2) ? 1.0 : 2.0;
        amplitude[j] = scale * hypot(work_re[j], work_im[j]) / gain;
    }
    *df = 1.0 / ((double)m * dt);
    return 0;
}

size_t sluice_hyd_spectrum_peak(const double *amplitude, size_t bins, double df, double fmin,
                                double fmax)
{
    size_t best = 0;
    for (size_t j = 1; j < bins; j++) {
        double f = (double)j * df;
        if (f < fmin || (fmax > 0.0 && f > fmax))
            continue;
        if (best == 0 || amplitude[j] > amplitude[best])
            best = j;
    }
    return best;
}

/* ----------------------------------------------------- jump measurements */

double sluice_hyd_toe_position(const double *x, const double *depth, size_t n,
                               double threshold)
{
    size_t previous = n; /* last finite gauge below the threshold */
    for (size_t k = 0; k < n; k++) {
        if (!isfinite(depth[k]) || !isfinite(x[k]))
            continue;
        if (depth[k] >= threshold) {
            if (previous == n)
                return NAN; /* the first wet gauge is already in the jump */
            double w = (threshold - depth[previous]) / (depth[k] - depth[previous]);
            return x[previous] + w * (x[k] - x[previous]);
        }
        previous = k;
    }
    return NAN;
}

size_t sluice_hyd_group_sections(const double *px, size_t n, double tolerance,
                                 size_t *section_of, double *section_x)
{
    size_t count = 0;
    for (size_t i = 0; i < n; i++) {
        size_t s = 0;
        while (s < count && fabs(px[i] - section_x[s]) > tolerance)
            s++;
        if (s == count) {
            /* insert keeping section_x ascending; shift later sections */
            size_t at = 0;
            while (at < count && section_x[at] < px[i])
                at++;
            for (size_t j = count; j > at; j--)
                section_x[j] = section_x[j - 1];
            section_x[at] = px[i];
            for (size_t j = 0; j < i; j++)
                if (section_of[j] >= at)
                    section_of[j]++;
            count++;
            s = at;
        }
        section_of[i] = s;
    }
    return count;
}

double sluice_hyd_wet_mean(const double *x, size_t n, double min_wet)
{
    double mean, std;
    size_t used = 0;
    if (sluice_hyd_mean_std(x, n, &mean, &std, &used) != 0)
        return NAN;
    return (double)used >= min_wet * (double)n ? mean : NAN;
}

void sluice_hyd_section_top(const size_t *section_of, const double *py, const double *value,
                            size_t n, size_t sections, double *top_value, double *top_y)
{
    for (size_t s = 0; s < sections; s++)
        top_value[s] = top_y[s] = NAN;
    for (size_t i = 0; i < n; i++) {
        size_t s = section_of[i];
        if (s < sections && isfinite(value[i]) && !(py[i] <= top_y[s])) {
            top_y[s] = py[i];
            top_value[s] = value[i];
        }
    }
}

void sluice_hyd_section_max(const size_t *section_of, const double *value, size_t n,
                            size_t sections, double *max_value)
{
    for (size_t s = 0; s < sections; s++)
        max_value[s] = NAN;
    for (size_t i = 0; i < n; i++) {
        size_t s = section_of[i];
        if (s < sections && isfinite(value[i]) && !(value[i] <= max_value[s]))
            max_value[s] = value[i];
    }
}

int sluice_hyd_roller_end(const double *x, const double *u, size_t n, double x1,
                          double *x_section, double *x_crossing)
{
    int reverse_seen = 0;
    size_t previous = n;
    for (size_t k = 0; k < n; k++) {
        if (!(x[k] > x1) || !isfinite(u[k]))
            continue;
        if (u[k] < 0.0) {
            reverse_seen = 1;
        } else if (reverse_seen) {
            *x_section = x[k];
            double w = -u[previous] / (u[k] - u[previous]);
            *x_crossing = x[previous] + w * (x[k] - x[previous]);
            return 0;
        }
        previous = k;
    }
    return 1;
}

/* --------------------------------------------- jump type at an abrupt drop */

/* Momentum balance per unit width, divided by rho g y1^2, between the inflow
 * section (depth y1 on the upper bed, velocity V1) and the tailwater section
 * (depth yt above the lower bed, velocity Vt = V1 y1 / yt), with the step face
 * of height s pushing on the fluid with a hydrostatic pressure:
 *   1/2 + F1^2 + P_face = Y^2/2 + F1^2 / Y.
 * A-jump limit: the face is under the tailwater level (surface yt above the
 * lower bed): P_face = (Y^2 - (Y - S)^2)/2, giving
 *   F_A^2 (1 - 1/Y) = ((Y - S)^2 - 1)/2.
 * B-jump limit (maximum plunging): the face is under the inflow level (surface
 * y1 above the upper bed): P_face = ((1 + S)^2 - 1)/2, giving
 *   F_B^2 (1 - 1/Y) = (Y^2 - (1 + S)^2)/2.
 * F_B^2 - F_A^2 = Y S (Y - 1 - S)/(Y - 1) > 0 for Y > 1 + S. */
int sluice_hyd_drop_limits(double Y, double S, double *fa, double *fb)
{
    if (!(S >= 0.0) || !(Y > 1.0 + S))
        return -1;
    double c = Y / (2.0 * (Y - 1.0));
    *fa = sqrt(c * ((Y - S) * (Y - S) - 1.0));
    *fb = sqrt(c * (Y * Y - (1.0 + S) * (1.0 + S)));
    return 0;
}

int sluice_hyd_drop_face_ratio(double F1, double Y, double S, double *ratio)
{
    if (!(S > 0.0) || !(Y > 1.0 + S))
        return -1;
    const double required = 2.0 * F1 * F1 * (1.0 / Y - 1.0) + Y * Y - 1.0;
    const double hydrostatic = Y * Y - (Y - S) * (Y - S);
    *ratio = required / hydrostatic;
    return 0;
}

int sluice_hyd_drop_regime_of(double F1, double Y, double S, sluice_hyd_drop_regime *regime,
                              double *t)
{
    double fa, fb;
    if (sluice_hyd_drop_limits(Y, S, &fa, &fb) != 0)
        return -1;
    if (F1 <= fa)
        *regime = SLUICE_HYD_DROP_A_JUMP;
    else if (F1 >= fb)
        *regime = SLUICE_HYD_DROP_B_JUMP;
    else
        *regime = SLUICE_HYD_DROP_TRANSITION;
    *t = fb > fa ? (F1 - fa) / (fb - fa) : (F1 <= fa ? 0.0 : 1.0);
    return 0;
}

sluice_hyd_drop_state sluice_hyd_drop_state_of(const double *x, const double *depth, size_t n,
                                               double threshold, double x_drop,
                                               double roller_length, double *x1)
{
    *x1 = NAN;
    size_t m = 0, first = n; /* gauges of the upper reach; its first wet one */
    while (m < n && x[m] < x_drop)
        m++;
    for (size_t k = 0; k < m && first == n; k++)
        if (isfinite(depth[k]))
            first = k;
    if (first == n)
        return SLUICE_HYD_STATE_NONE;
    if (depth[first] >= threshold) {
        *x1 = -INFINITY;
        return SLUICE_HYD_STATE_A;
    }
    const double toe = sluice_hyd_toe_position(x, depth, m, threshold);
    if (!isfinite(toe))
        return SLUICE_HYD_STATE_WAVE;
    *x1 = toe;
    return x_drop - toe >= roller_length ? SLUICE_HYD_STATE_A : SLUICE_HYD_STATE_B;
}

const char *sluice_hyd_drop_type(const sluice_hyd_drop_state *state, size_t n, double wave_min,
                                 double *fraction_a, double *fraction_b, double *fraction_wave,
                                 size_t *wave_episodes)
{
    size_t count[3] = {0, 0, 0}, used = 0, episodes = 0;
    int in_wave = 0;
    for (size_t i = 0; i < n; i++) {
        if (state[i] == SLUICE_HYD_STATE_NONE)
            continue;
        count[state[i]]++;
        used++;
        if (state[i] == SLUICE_HYD_STATE_WAVE && !in_wave)
            episodes++;
        in_wave = state[i] == SLUICE_HYD_STATE_WAVE;
    }
    *wave_episodes = episodes;
    if (used == 0) {
        *fraction_a = *fraction_b = *fraction_wave = NAN;
        return NULL;
    }
    *fraction_a = (double)count[SLUICE_HYD_STATE_A] / (double)used;
    *fraction_b = (double)count[SLUICE_HYD_STATE_B] / (double)used;
    *fraction_wave = (double)count[SLUICE_HYD_STATE_WAVE] / (double)used;
    const int a_family = count[SLUICE_HYD_STATE_A] >= count[SLUICE_HYD_STATE_B];
    if (*fraction_wave < wave_min)
        return a_family ? "A-jump" : "B-jump";
    if (*fraction_wave > 1 - wave_min)
        return "wave jump";
    return a_family ? "A-wave" : "B-wave";
}

/* ------------------------------------ aerated flow on a stepped chute */

double sluice_hyd_chute_velocity(double u, double v, double theta)
{
    return u * cos(theta) - v * sin(theta);
}

double sluice_hyd_normal_distance(double px, double py, double ex, double ey, double theta,
                                  double *offset)
{
    const double dx = px - ex, dy = py - ey, s = sin(theta), c = cos(theta);
    if (offset)
        *offset = dx * c - dy * s;
    return dx * s + dy * c;
}

/* The interpolant on [s, e] inside the segment (y0, c0) - (y1, c1), exactly
 * integrated (it is linear there). */
static double segment_integral(double y0, double c0, double y1, double c1, double s, double e)
{
    if (!(e > s))
        return 0.0;
    const double slope = (c1 - c0) / (y1 - y0);
    const double fs = c0 + slope * (s - y0), fe = c0 + slope * (e - y0);
    return 0.5 * (e - s) * (fs + fe);
}

double sluice_hyd_profile_integral(const double *y, const double *c, size_t n, double a,
                                   double b)
{
    size_t first = 0;
    while (first < n && !(isfinite(y[first]) && isfinite(c[first])))
        first++;
    if (first == n || !(b >= a))
        return NAN;
    size_t last = n - 1;
    while (!(isfinite(y[last]) && isfinite(c[last])))
        last--;
    if (b > y[last])
        return NAN;
    /* below the first finite point: C held at its value */
    double sum = fmax(0.0, fmin(b, y[first]) - a) * c[first];
    size_t prev = first;
    for (size_t k = first + 1; k <= last; k++) {
        if (!(isfinite(y[k]) && isfinite(c[k])))
            continue;
        sum += segment_integral(y[prev], c[prev], y[k], c[k], fmax(a, y[prev]), fmin(b, y[k]));
        prev = k;
    }
    return sum;
}

int sluice_hyd_aerated_depths(const double *y, const double *c, size_t n, double level,
                              double *y90, double *d, double *c_mean)
{
    *y90 = *d = *c_mean = NAN;
    long prev = -1;
    for (size_t k = 0; k < n; k++) {
        if (!(isfinite(y[k]) && isfinite(c[k])))
            continue;
        if (c[k] >= level) {
            if (prev < 0)
                return -1; /* the first finite point is already above the level */
            const double w = (level - c[prev]) / (c[k] - c[prev]);
            *y90 = y[prev] + w * (y[k] - y[prev]);
            break;
        }
        prev = (long)k;
    }
    if (!(*y90 > 0.0)) {
        *y90 = NAN;
        return -1;
    }
    /* trapezoids on the points up to Y90, the last one ending at Y90 with
     * C = level (the interpolant there) */
    const double integral = sluice_hyd_profile_integral(y, c, n, 0.0, *y90);
    *d = *y90 - integral;
    *c_mean = 1.0 - *d / *y90;
    return 0;
}

double sluice_hyd_band_mean(const double *y, const double *c, size_t n, double lo, double hi)
{
    if (!(hi > lo))
        return NAN;
    return sluice_hyd_profile_integral(y, c, n, lo, hi) / (hi - lo);
}

long sluice_hyd_first_above(const double *x, size_t n, double threshold)
{
    for (size_t k = 0; k < n; k++)
        if (isfinite(x[k]) && x[k] > threshold)
            return (long)k;
    return -1;
}

/* --------------------------------------------------- dissolved oxygen */

double sluice_hyd_do_scaled(double c, double cs, double cu, double f)
{
    if (isnan(c) || !(f > 0.0) || !(cs > cu))
        return NAN;
    if (c >= cs)
        return cs;
    return cs - (cs - cu) * pow((cs - c) / (cs - cu), f);
}

double sluice_hyd_do_station_mean(const double *readings, size_t samples, size_t per,
                                  double cs, double cu, double f, size_t *used)
{
    double sum = 0.0;
    size_t count = 0;
    for (size_t s = 0; s < samples; s++) {
        double line = 0.0;
        size_t wet = 0;
        for (size_t k = 0; k < per; k++) {
            const double c = readings[s * per + k];
            if (isnan(c))
                continue;
            line += sluice_hyd_do_scaled(c, cs, cu, f);
            wet++;
        }
        if (wet) {
            sum += line / (double)wet;
            count++;
        }
    }
    if (used)
        *used = count;
    return count ? sum / (double)count : NAN;
}

int sluice_hyd_do_calibrate(const double *readings, size_t samples, size_t per, double cs,
                            double cu, double target, double *f)
{
    if (!(cs > cu) || !(target > cu && target < cs))
        return -1;
    double lo = log(1e-4), hi = log(1e4);
    const double at_lo = sluice_hyd_do_station_mean(readings, samples, per, cs, cu, exp(lo), NULL);
    const double at_hi = sluice_hyd_do_station_mean(readings, samples, per, cs, cu, exp(hi), NULL);
    if (isnan(at_lo) || !(at_lo <= target && target <= at_hi))
        return -1;
    for (int k = 0; k < 200 && hi - lo > 1e-13; k++) {
        const double mid = 0.5 * (lo + hi);
        if (sluice_hyd_do_station_mean(readings, samples, per, cs, cu, exp(mid), NULL) < target)
            lo = mid;
        else
            hi = mid;
    }
    *f = exp(0.5 * (lo + hi));
    return 0;
}
