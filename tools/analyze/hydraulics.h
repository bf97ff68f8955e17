/* Hydraulic-jump measurements: pure numerical functions of sluice-analyze.
 *
 * No function here reads or writes a file or prints: they take arrays and
 * return numbers (main.c does the I/O). Every function that can fail returns
 * 0 on success and a negative value on bad arguments; functions returning a
 * double return NaN when the quantity does not exist (e.g. no crossing).
 * NaN samples (a gauge outside the fluid) are skipped where documented.
 * Units: SI throughout (m, s, m s^-1). See docs/analysis.md for the
 * definitions, references and the tests that verify each function
 * (tests/tools/analyze/test_analysis.c). */
#ifndef SLUICE_HYDRAULICS_H
#define SLUICE_HYDRAULICS_H

#include <stddef.h>

/* ----------------------------------------------------- reference relations */

/* Inflow Froude number Fr = v / sqrt(g d). */
double sluice_hyd_froude(double v, double d, double g);

/* Belanger's conjugate depth (seed 000 eq. 1, horizontal rectangular channel):
 * d2 = d1/2 (sqrt(1 + 8 Fr1^2) - 1). */
double sluice_hyd_belanger_depth(double d1, double fr1);

/* Roller length, Hager, Bremen & Kawagoshi (1990) as quoted by seed 000 eq. 2:
 * L_r = d1 (160 tanh(Fr1/20) - 12), stated for 2 < Fr1 < 16. */
double sluice_hyd_hager_roller_length(double d1, double fr1);

/* Decay of the maximum velocity, Chanson (seed 000 eq. 3):
 * Vmax/V1 = exp(-0.028 (x - x1)/d1), with xi = (x - x1)/d1. */
double sluice_hyd_chanson_vmax_ratio(double xi);

/* Maximum free-surface fluctuation, Murzyn & Chanson (seed 000 eq. 4):
 * (eta'/d1)_max = 0.116 (Fr1 - 1)^1.235. */
double sluice_hyd_murzyn_chanson_eta_std(double fr1);

/* Free-surface Strouhal number, Chachereau & Chanson (seed 000 eq. 5):
 * St = f d1 / V1 = 0.143 exp(-0.27 Fr1), stated for 2.4 < Fr1 < 6.5. */
double sluice_hyd_chachereau_chanson_strouhal(double fr1);

/* ------------------------------------------------------------- statistics */

/* Mean and population standard deviation (1/N) of the finite values of
 * x[0..n); *used = their count. Returns -1 when fewer than one is finite. */
int sluice_hyd_mean_std(const double *x, size_t n, double *mean, double *std, size_t *used);

/* Seed 000 eqs. 19-20 with a constant theoretical depth d2_theory:
 *   A = sqrt(sum d2_i^2 / sum d2_th^2),  P = sqrt(sum (d2_i - d2_th)^2 / sum d2_th^2),
 * over the finite d2_i (*used of them). Returns -1 when none or d2_theory <= 0. */
int sluice_hyd_conjugate_statistics(const double *d2, size_t n, double d2_theory, double *A,
                                    double *P, size_t *used);

/* Pearson correlation coefficient (seed 004's r):
 *   r = sum (a-abar)(b-bbar) / sqrt(sum (a-abar)^2 sum (b-bbar)^2)
 * over the pairs where both are finite (*used). NaN when fewer than two pairs
 * or a variance is zero. */
double sluice_hyd_pearson(const double *a, const double *b, size_t n, size_t *used);

/* Seed 002's free-surface errors between numerical h_num and measured h_ref
 * levels at N points (pairs where both are finite; h_ref must not be 0):
 *   L2   = sqrt( (1/N) sum ((h_num - h_ref)/h_ref)^2 ),
 *   RMSE = sqrt( (1/N) sum (h_num - h_ref)^2 ).
 * Returns -1 when no pair is usable or some h_ref is 0. */
int sluice_hyd_profile_errors(const double *h_num, const double *h_ref, size_t n, double *l2,
                              double *rmse, size_t *used);

/* Least-squares decay rate k of ratio = exp(-k xi) through (0, 1):
 *   k = -sum xi ln(ratio) / sum xi^2 over the points with xi > 0, ratio > 0.
 * NaN when there is none. */
double sluice_hyd_decay_rate(const double *xi, const double *ratio, size_t n);

/* Least-squares slope of y against t over the finite pairs (NaN if < 2). */
double sluice_hyd_slope(const double *t, const double *y, size_t n);

/* ---------------------------------------------------------- interpolation */

/* Linear interpolation of y(x) at xq, x strictly increasing. NaN outside
 * [x[0], x[n-1]] or when a bracketing value is NaN. */
double sluice_hyd_interpolate(const double *x, const double *y, size_t n, double xq);

/* Resamples the finite samples of y(t) (t increasing) onto m = n_out uniform
 * times t0 + k dt, k = 0..m-1, dt = (t1 - t0)/(m - 1), by linear
 * interpolation between finite neighbours. Returns -1 when fewer than two
 * samples are finite or m < 2 or t1 <= t0. */
int sluice_hyd_resample(const double *t, const double *y, size_t n, double t0, double t1,
                        size_t m, double *out);

/* --------------------------------------------------------------- spectrum */

/* Smallest power of two >= n (n >= 1). */
size_t sluice_hyd_next_pow2(size_t n);

/* In-place radix-2 complex FFT (decimation in time), n a power of two:
 *   X_k = sum_j x_j exp(-/+ 2 pi i j k / n)   (sign -: forward, +: inverse),
 * unnormalised both ways (inverse(forward(x)) = n x). Returns -1 when n is not
 * a power of two. */
int sluice_hyd_fft(double *re, double *im, size_t n, int inverse);

/* Removes the least-squares straight line a + b k (k = 0..n-1) from x. */
void sluice_hyd_detrend(double *x, size_t n);

/* Periodic Hann window w_k = (1 - cos(2 pi k / n)) / 2, k = 0..n-1. */
void sluice_hyd_hann(double *w, size_t n);

/* One-sided amplitude spectrum of x[0..n) sampled every dt: detrended (linear
 * least squares), multiplied by the periodic Hann window, zero-padded to
 * m = sluice_hyd_next_pow2(n), transformed, and scaled by the window's
 * coherent gain so that a sine a sin(2 pi f t) whose f is a bin centre
 * j/(m dt) has amplitude exactly a at bin j:
 *   A_0 = |X_0| / sum w,  A_j = 2 |X_j| / sum w (0 < j < m/2),  A_{m/2} = |X_{m/2}| / sum w.
 * Between bin centres the peak is lower by at most the Hann scalloping loss
 * (sin(pi d)/(pi d))/(1 - d^2), d = n/(2m) <= 1/2 bins of n (0.8488 at d = 1/2).
 * work_re and work_im hold m values each; amplitude receives m/2 + 1 values
 * and *df = 1/(m dt). Returns -1 when n < 2 or dt <= 0. */
int sluice_hyd_amplitude_spectrum(const double *x, size_t n, double dt, double *work_re,
                                  double *work_im, double *amplitude, double *df);

/* Index of the largest amplitude among bins 1 .. bins-1 (DC excluded) whose
 * frequency j df lies in [fmin, fmax] (fmax <= 0: no upper bound). Returns
 * 0 when no bin qualifies. */
size_t sluice_hyd_spectrum_peak(const double *amplitude, size_t bins, double df, double fmin,
                                double fmax);

/* ----------------------------------------------------- jump measurements */

/* Jump toe from one free-surface profile: depth[k] = eta - bed at gauge
 * positions x[k] (strictly increasing, upstream to downstream). Going
 * downstream from the first gauge, the toe is where the depth first rises
 * through `threshold` (= d1 + fraction (d2_B - d1)): between the last gauge
 * below it and the next one at or above it, by linear interpolation of the
 * depth. NaN gauges (dry) are skipped. Returns NaN when no finite gauge
 * reaches the threshold, or when the first finite gauge already does (the
 * toe is upstream of the gauges). */
double sluice_hyd_toe_position(const double *x, const double *depth, size_t n,
                               double threshold);

/* Groups points by their x (|x - x_section| <= tolerance, in order of first
 * appearance sorted by x): section_of[i] receives the section of point i,
 * section_x the sections' x (ascending, at most n). Returns the number of
 * sections. */
size_t sluice_hyd_group_sections(const double *px, size_t n, double tolerance,
                                 size_t *section_of, double *section_x);

/* Time mean of a gauge series over a window: the mean of its finite samples
 * when they are at least min_wet of the n samples (a point outside the fluid
 * too often has no mean), else NaN. */
double sluice_hyd_wet_mean(const double *x, size_t n, double min_wet);

/* Per section s (section_of[i] of point i, as sluice_hyd_group_sections):
 * the value of its highest point (largest py) whose value is finite, and that
 * point's py; NaN for both when the section has none. */
void sluice_hyd_section_top(const size_t *section_of, const double *py, const double *value,
                            size_t n, size_t sections, double *top_value, double *top_y);

/* Per section: the largest finite value of its points (NaN when none). */
void sluice_hyd_section_max(const size_t *section_of, const double *value, size_t n,
                            size_t sections, double *max_value);

/* Roller end from the time-mean near-surface horizontal velocity u[k] of
 * sections x[k] (ascending; NaN sections skipped) and the toe x1 (seed 000,
 * section 3: the first position downstream of the toe with non-negative mean
 * velocity). The search starts at the first section downstream of x1 with
 * u < 0 (inside the roller's reverse flow) and returns the first section after
 * it with u >= 0: *x_section = its x, *x_crossing = the zero of u linearly
 * interpolated from the section before it. Returns 0 when found, 1 when the
 * data show no reverse flow downstream of x1 or never recover u >= 0. */
int sluice_hyd_roller_end(const double *x, const double *u, size_t n, double x1,
                          double *x_section, double *x_crossing);

/* --------------------------------------------- jump type at an abrupt drop */

/* Momentum limits of the jump at an abrupt drop of height s (S = s/y1) with
 * tailwater depth yt above the lower bed (Y = yt/y1) and inflow Froude number
 * F1 on the upper bed, the classical pair of curves (Hsu 1950; Moore & Morgan
 * 1959, seed 004 ref. [3]; Hager & Bretz 1986, ref. [8]) re-derived in
 * hydraulics.c from the momentum balance between the inflow section and the
 * tailwater with hydrostatic pressure on the step face:
 *   A-jump limit (face under the tailwater level):  F_A^2 = Y ((Y - S)^2 - 1) / (2 (Y - 1)),
 *   B-jump limit (face under the inflow level):     F_B^2 = Y (Y^2 - (1 + S)^2) / (2 (Y - 1)).
 * Both reduce to Belanger's Y (Y + 1) = 2 F^2 at S = 0. Returns -1 when
 * Y <= 1 + S (no tailwater above the step) or S < 0. */
int sluice_hyd_drop_limits(double Y, double S, double *fa, double *fb);

/* The force on the step face that the momentum balance between the inflow
 * (y1, F1) and the tailwater (yt) needs, friction neglected, per unit width
 * in units of rho g y1^2 / 2:  R = 2 F1^2 (1/Y - 1) + Y^2 - 1,  as a share
 * of the hydrostatic force on the face under the tailwater level,
 * H = Y^2 - (Y - S)^2:  *ratio = R / H (1 at F1 = F_A; ((1 + S)^2 - 1) / H
 * at F_B). A run's measured face force (the wall_force plugin) compares
 * with it. Returns -1 when S <= 0 or Y <= 1 + S. */
int sluice_hyd_drop_face_ratio(double F1, double Y, double S, double *ratio);

typedef enum sluice_hyd_drop_regime {
    SLUICE_HYD_DROP_A_JUMP = 0,   /* F1 <= F_A: the jump stays upstream of the drop */
    SLUICE_HYD_DROP_TRANSITION,   /* F_A < F1 < F_B: wave-jump region */
    SLUICE_HYD_DROP_B_JUMP        /* F1 >= F_B: the jet plunges over the drop */
} sluice_hyd_drop_regime;

/* Regime of (F1, Y, S) by the momentum limits, and the position of F1 in the
 * band, t = (F1 - F_A) / (F_B - F_A) (t <= 0: A-jump region, t >= 1: B-jump
 * region). Returns -1 as sluice_hyd_drop_limits. */
int sluice_hyd_drop_regime_of(double F1, double Y, double S, sluice_hyd_drop_regime *regime,
                              double *t);

/* Instantaneous flow state at an abrupt drop, from one free-surface profile
 * of the upper reach (Ohtsu & Yasuda 1991, seed 004 Figure 1): depth[k] =
 * eta - upper-bed elevation at gauges x[k] < x_drop (ascending), the toe
 * threshold depth (y1 + fraction (d2_B - y1)) and the roller length L_r:
 *   WAVE    no gauge of the upper reach reaches the threshold: the
 *           supercritical stream runs to the edge and leaves it as a jet
 *           (wave jump);
 *   A       the toe x1 is at least L_r upstream of the edge (x_drop - x1 >=
 *           L_r), or upstream of the first gauge: the roller ends on the
 *           upper bed (A-jump);
 *   B       the toe is on the upper reach less than L_r from the edge: the
 *           roller reaches over the drop (B-jump).
 * NONE when every gauge is dry. *x1 receives the toe (NaN for WAVE and
 * NONE, -inf upstream of the first gauge). */
typedef enum sluice_hyd_drop_state {
    SLUICE_HYD_STATE_NONE = -1,
    SLUICE_HYD_STATE_A = 0,
    SLUICE_HYD_STATE_B = 1,
    SLUICE_HYD_STATE_WAVE = 2
} sluice_hyd_drop_state;

sluice_hyd_drop_state sluice_hyd_drop_state_of(const double *x, const double *depth, size_t n,
                                               double threshold, double x_drop,
                                               double roller_length, double *x1);

/* Jump type over a series of states (NONE samples left out): the fractions
 * of A, B and WAVE samples, and the type
 *   A-jump / B-jump   WAVE fraction < wave_min (stable; A or B by the larger
 *                     fraction),
 *   wave jump         WAVE fraction > 1 - wave_min,
 *   A-wave / B-wave   otherwise (oscillation between the wave jump and the
 *                     larger of A and B),
 * and the wave episodes (maximal runs of WAVE samples). Returns the type's
 * name, or NULL when no sample has a state. */
const char *sluice_hyd_drop_type(const sluice_hyd_drop_state *state, size_t n, double wave_min,
                                 double *fraction_a, double *fraction_b, double *fraction_wave,
                                 size_t *wave_episodes);

/* ------------------------------------ aerated flow on a stepped chute */

/* Velocity component along the pseudo-bottom (the line through the step
 * edges) of a chute descending at the angle theta (rad) in +x, downstream
 * positive: U = u cos(theta) - v sin(theta). */
double sluice_hyd_chute_velocity(double u, double v, double theta);

/* Distance of the point (px, py) from the step edge (ex, ey) along the
 * outward normal of that pseudo-bottom, n = (sin theta, cos theta):
 * y = (px - ex) sin(theta) + (py - ey) cos(theta); *offset receives the
 * component along the pseudo-bottom, (px - ex) cos(theta) - (py - ey)
 * sin(theta) (0 for a point on the normal). */
double sluice_hyd_normal_distance(double px, double py, double ex, double ey, double theta,
                                  double *offset);

/* Integral over [a, b] of the piecewise-linear interpolant of the finite
 * points (y[k], c[k]) (y strictly increasing; NaN points skipped), held at
 * the first finite value below the first finite point: the trapezoid rule
 * on the points, exact for a piecewise-linear profile. NaN when b lies
 * beyond the last finite point, b < a, or no point is finite. */
double sluice_hyd_profile_integral(const double *y, const double *c, size_t n, double a,
                                   double b);

/* Aerated depths of one time-mean air-concentration profile c[k] at y[k]
 * (distance from the pseudo-bottom, strictly increasing; NaN points
 * skipped), Chanson (2002), The Hydraulics of Stepped Chutes and Spillways:
 *   Y90: the y where C first reaches `level` (0.9) going up from the bottom,
 *        by linear interpolation between the last finite point below it and
 *        the first at or above it; NaN when no point reaches it or the first
 *        finite point already does (no clear-water region to start from);
 *   d = integral_0^Y90 (1 - C) dy, the equivalent clear-water depth, by the
 *        trapezoid rule on the points (sluice_hyd_profile_integral: C held
 *        at its first finite value below the first point, the last segment
 *        ending at Y90 where C = level);
 *   C_mean = 1 - d / Y90, the depth-averaged air concentration.
 * Returns 0, or -1 (all three NaN) when Y90 does not exist. */
int sluice_hyd_aerated_depths(const double *y, const double *c, size_t n, double level,
                              double *y90, double *d, double *c_mean);

/* Mean of the profile over lo <= y <= hi (lo < hi): the integral of
 * sluice_hyd_profile_integral divided by hi - lo. NaN as that function. */
double sluice_hyd_band_mean(const double *y, const double *c, size_t n, double lo, double hi);

/* Index of the first finite x[k] > threshold, or -1 when none. */
long sluice_hyd_first_above(const double *x, size_t n, double threshold);

/* --------------------------------------------------- dissolved oxygen */

/* A DO reading c (mg/L) of a run with the source K a (Cs - C) mapped to the
 * same run with K scaled by f: where the water's oxygen changes by the
 * source only (no diffusion between particles), its deficit D = Cs - C
 * decays as D0 exp(-integral K a dt) from D0 = Cs - Cu, so
 *   C_f = Cs - (Cs - Cu) ((Cs - c) / (Cs - Cu))^f.
 * c >= Cs gives Cs; NaN for NaN c, f <= 0, or Cs <= Cu. */
double sluice_hyd_do_scaled(double c, double cs, double cu, double f);

/* The station mean of a DO table: readings[s * per + k] is point k of the
 * station at sample s (NaN: no water there). Each sample with a finite
 * reading contributes the mean of its finite readings, mapped with
 * sluice_hyd_do_scaled(f); the result is the mean over those samples (NaN
 * when none), *used (may be NULL) their count. f = 1 is the run itself. */
double sluice_hyd_do_station_mean(const double *readings, size_t samples, size_t per,
                                  double cs, double cu, double f, size_t *used);

/* The scale f (within [1e-4, 1e4]) for which the station mean equals
 * `target` (Cu < target < Cs), by bisection on log f (the mean grows with
 * f). Returns 0 with *f, or -1: no reading, target outside (Cu, Cs), or
 * outside what f in that range reaches. */
int sluice_hyd_do_calibrate(const double *readings, size_t samples, size_t per, double cs,
                            double cu, double target, double *f);

#endif
