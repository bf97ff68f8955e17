/* Time integrators and time-step conditions, checked through the real core
 * with the test plugin harmonic_force (tests/sdk/fixtures/harmonic_force.c): every
 * fluid particle is an independent harmonic oscillator
 *   dv/dt = -omega^2 (x - c),  dx/dt = v (+ u_T, a transport correction),
 * with the exact solution y(t) = y0 cos(omega t) + (v0 + u_T)/omega sin(omega t),
 * y = x - c. No pair term is loaded, so the particles do not interact.
 *
 *  - order of convergence in dt of the position (and density) error at a
 *    fixed time, over a dt halving sequence (time.max_step forces dt);
 *  - energy E = sum 1/2 |v|^2 + 1/2 omega^2 |y|^2 over many periods, against
 *    what theory gives for each scheme on a linear oscillator;
 *  - the density rate, walls, the XSPH transport correction, a variable dt;
 *  - the time-step conditions on a hand-made state, and the seeds' combinations.
 */
#include <math.h>

#include "sim_util.h"
/* Internal: reads the integrators' instance state by name; dt, dt_limit (not in sim.h) */
#include "sim_internal.h"

#define PI 3.14159265358979323846
#define OMEGA (2 * PI) /* period 1 s */
#define EPS 2.220446049250313e-16

typedef struct scheme {
    const char *label;
    const char *yaml; /* the integrator's entry in `plugins` */
    int order;
} scheme;

static const scheme schemes[] = {
    {"symplectic", "symplectic: {}", 2},
    {"euler semi_implicit", "euler: {}", 1},
    {"euler explicit", "euler: {form: explicit}", 1},
    {"verlet euler_every 40", "verlet: {}", 2},
    {"verlet euler_every 3", "verlet: {euler_every: 3}", 1},
    {"predictor_corrector", "predictor_corrector: {}", 2},
    {"predictor_corrector pec", "predictor_corrector: {mode: pec}", 2},
};
#define SCHEME_COUNT ((int)(sizeof schemes / sizeof schemes[0]))

/* ------------------------------------------------------------ the scene -- */

typedef struct options {
    int dims;
    double max_step; /* time.max_step, 0: none */
    double end;
    const char *fixture; /* extra harmonic_force parameters, starting with ", " */
    int walls;           /* a solid box of dbc wall particles, away from the orbits */
} options;

static const double centre[3] = {0.1, -0.05, 0.02};

static sluice_sim *load(const char *tag, const scheme *s, const options *o)
{
    const char *fixtures = getenv("SLUICE_FIXTURE_DIR");
    ck_assert_msg(fixtures != NULL, "SLUICE_FIXTURE_DIR is not set");
    char max_step[64] = "";
    if (o->max_step > 0)
        snprintf(max_step, sizeof max_step, ", max_step: %.17g", o->max_step);
    const int three = o->dims == 3;
    char yaml[4096];
    snprintf(yaml, sizeof yaml,
             "dimensions: %d\n"
             "particles: {spacing: 0.1}\n"
             "time: {end: %.17g%s}\n"
             "domain: {min: %s, max: %s}\n"
             "plugin_path: %s\n"
             "initial: {density: rest}\n"
             "geometry:\n"
             "  fluid:\n"
             "    - {shape: box, min: %s, max: %s, velocity: %s}\n"
             "    - {shape: box, min: %s, max: %s, velocity: %s}\n"
             "%s"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  harmonic_force: {omega: %.17g, centre: %s%s}\n"
             "%s"
             "  %s\n",
             o->dims, o->end, max_step, three ? "[-3, -3, -3]" : "[-3, -3]",
             three ? "[3, 3, 3]" : "[3, 3]", fixtures, three ? "[0.5, 0, 0]" : "[0.5, 0]",
             three ? "[0.7, 0.2, 0.2]" : "[0.7, 0.2]", three ? "[0, 1, 0.3]" : "[0, 1]",
             three ? "[-0.7, -0.4, -0.2]" : "[-0.7, -0.4]", three ? "[-0.5, -0.2, 0]" : "[-0.5, -0.2]",
             three ? "[0.5, -0.5, 0]" : "[0.5, -0.5]",
             !o->walls ? ""
             : three   ? "  walls: [{shape: box, min: [1.5, -0.3, -0.3], max: [1.8, 0.3, 0.3]}]\n"
                       : "  walls: [{shape: box, min: [1.5, -0.3], max: [1.8, 0.3]}]\n",
             OMEGA, three ? "[0.1, -0.05, 0.02]" : "[0.1, -0.05]", o->fixture ? o->fixture : "",
             o->walls ? "  dbc: {}\n" : "", s->yaml);
    return test_load(tag, yaml, NULL, 0);
}

/* Initial state of every particle, by id, for the exact solution. */
typedef struct initial {
    int dims;
    size_t n;
    double *x, *v, *rho; /* 3 per id, 3 per id, 1 per id */
    uint8_t *kind;
} initial;

static void record(sluice_sim *sim, initial *in)
{
    const sluice_view *v = sluice_sim_view(sim);
    in->dims = (int)v->dimensions;
    sluice_id top = 0;
    for (sluice_index i = 0; i < v->count; i++)
        top = v->id[i] > top ? v->id[i] : top;
    in->n = (size_t)top + 1;
    in->x = calloc(3 * in->n, sizeof(double));
    in->v = calloc(3 * in->n, sizeof(double));
    in->rho = calloc(in->n, sizeof(double));
    in->kind = calloc(in->n, 1);
    ck_assert(in->x && in->v && in->rho && in->kind);
    sluice_field density;
    int has_density = sluice_sim_field(sim, "density", &density) == SLUICE_OK;
    for (sluice_index i = 0; i < v->count; i++) {
        size_t k = (size_t)v->id[i];
        for (int d = 0; d < in->dims; d++) {
            in->x[3 * k + d] = (double)v->position[d][i];
            in->v[3 * k + d] = (double)test_column(sim, "velocity", (uint32_t)d)[i];
        }
        in->rho[k] = has_density ? (double)sluice_real_column(v, density, 0)[i] : 0;
        in->kind[k] = v->kind[i];
    }
}

static void release(initial *in)
{
    free(in->x);
    free(in->v);
    free(in->rho);
    free(in->kind);
}

/* Exact oscillator with a transport velocity u_T: y' = v + u_T, v' = -w^2 y. */
static void exact(const initial *in, size_t k, double t, const double *transport, double *x,
                  double *u)
{
    const double c = cos(OMEGA * t), s = sin(OMEGA * t);
    for (int d = 0; d < in->dims; d++) {
        const double y0 = in->x[3 * k + d] - centre[d];
        const double w0 = in->v[3 * k + d] + (transport ? transport[d] : 0);
        x[d] = centre[d] + y0 * c + w0 / OMEGA * s;
        u[d] = -OMEGA * y0 * s + w0 * c - (transport ? transport[d] : 0);
    }
}

typedef struct errors {
    double position, velocity, density; /* largest over fluid particles */
} errors;

/* Runs to the end and measures the errors against the exact solution;
 * density: rho(t) = rho(0) + rate t + gradient . (x(t) - x(0)). */
static errors run_errors(sluice_sim *sim, const double *transport, double density_rate,
                         const double *density_gradient)
{
    initial in;
    record(sim, &in);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    const double end = sluice_sim_end_time(sim);
    while (sluice_sim_time(sim) < end)
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "%s", sluice_sim_failure(sim));
    const double t = sluice_sim_time(sim);
    ck_assert(t == end);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_field density;
    const int has_density = sluice_sim_field(sim, "density", &density) == SLUICE_OK;
    errors e = {0, 0, 0};
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        size_t k = (size_t)v->id[i];
        double x[3], u[3], dx2 = 0, du2 = 0, drift = 0;
        exact(&in, k, t, transport, x, u);
        for (int d = 0; d < in.dims; d++) {
            double a = (double)v->position[d][i] - x[d];
            double b = (double)test_column(sim, "velocity", (uint32_t)d)[i] - u[d];
            dx2 += a * a;
            du2 += b * b;
            if (density_gradient)
                drift += density_gradient[d] * (x[d] - in.x[3 * k + d]);
        }
        e.position = fmax(e.position, sqrt(dx2));
        e.velocity = fmax(e.velocity, sqrt(du2));
        if (has_density && (density_rate != 0 || density_gradient)) {
            double rho = in.rho[k] + density_rate * t + drift;
            e.density = fmax(e.density,
                             fabs((double)sluice_real_column(v, density, 0)[i] - rho));
        }
    }
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    release(&in);
    return e;
}

/* The range a measured order must fall in: theory gives 1 or 2 as dt -> 0;
 * the margins cover the leading error term of the next order at these dt
 * (omega dt <= 2 pi / 256 = 0.025). */
static void check_order(const scheme *s, const char *what, double order)
{
    const double lo = s->order == 1 ? 0.9 : 1.8, hi = s->order == 1 ? 1.2 : 2.3;
    ck_assert_msg(order >= lo && order <= hi, "%s: %s order %.3f outside [%.1f, %.1f]", s->label,
                  what, order, lo, hi);
}

/* --------------------------------------------------- order of accuracy -- */

/* Position and density errors at t = 13/16 s (not a multiple of the half
 * period, where errors of some schemes cancel) for dt = 1/256 ... 1/2048 s. */
static void order_test(int which, int dims, const char *fixture, const double *transport,
                       double density_rate, const double *gradient, int levels)
{
    const scheme *s = &schemes[which];
    double ex[8], ed[8];
    for (int k = 0; k < levels; k++) {
        const double dt = 1.0 / (256 << k);
        options o = {dims, dt, 0.8125, fixture, 0};
        sluice_sim *sim = load("order", s, &o);
        errors e = run_errors(sim, transport, density_rate, gradient);
        sluice_sim_free(sim);
        ex[k] = e.position;
        ed[k] = e.density;
        fprintf(stderr, "%s %dD%s: dt 1/%d s: position error %.4e m, density error %.4e kg m^-3\n",
                s->label, dims, transport ? " (transport)" : "", 256 << k, e.position, e.density);
    }
    for (int k = 0; k + 1 < levels; k++) {
        double p = log2(ex[k] / ex[k + 1]);
        fprintf(stderr, "%s %dD: order (position) %.3f", s->label, dims, p);
        check_order(s, "position", p);
        if (gradient) {
            double q = log2(ed[k] / ed[k + 1]);
            fprintf(stderr, ", (density) %.3f", q);
            check_order(s, "density", q);
        }
        fputc('\n', stderr);
    }
}

/* dt halving, density rate 2 + (30, -20) . v kg m^-3 s^-1 */
START_TEST(order_2d)
{
    static const double gradient[3] = {30, -20, 0};
    order_test(_i, 2, ", density_rate: 2, density_gradient: [30, -20]", NULL, 2, gradient, 4);
}
END_TEST

/* positions move with v + u_T (the XSPH field transport_velocity_correction) */
START_TEST(order_transport)
{
    static const double transport[3] = {0.3, -0.2, 0};
    order_test(_i, 2, ", transport_velocity: [0.3, -0.2]", transport, 0, NULL, 4);
}
END_TEST

START_TEST(order_3d)
{
    static const double gradient[3] = {30, -20, 10};
    order_test(_i, 3, ", density_rate: 2, density_gradient: [30, -20, 10]", NULL, 2, gradient, 3);
}
END_TEST

/* With a smoothly varying step (the fixture's limit dt0 (1 + 0.5 P/E)), the
 * one-step schemes keep their order, and so does verlet thanks to its
 * (dt_{n-1} + dt_n) increment. Least-squares slope of log(error) against
 * log(dt0) over dt0 = 1/256 ... 1/4096 s (omega dt0 <= 0.025, the asymptotic
 * range): the step sequence changes with dt0 and the last step is shortened
 * to land on the end time, so single ratios scatter a little; the slope over
 * four halvings averages that out. */
START_TEST(order_variable_step)
{
    const scheme *s = &schemes[_i];
    double lx[8], ly[8];
    const int levels = 5;
    for (int k = 0; k < levels; k++) {
        const double dt0 = 1.0 / (256 << k);
        char fixture[128];
        snprintf(fixture, sizeof fixture, ", time_step: %.17g, time_step_variation: 0.5", dt0);
        options o = {2, 0, 0.8125, fixture, 0};
        sluice_sim *sim = load("variable", s, &o);
        errors e = run_errors(sim, NULL, 0, NULL);
        int64_t steps = sluice_sim_steps(sim);
        sluice_sim_free(sim);
        lx[k] = log2(dt0);
        ly[k] = log2(e.position);
        fprintf(stderr, "%s, variable dt0 = 1/%d s: %lld steps, position error %.4e m\n", s->label,
                256 << k, (long long)steps, e.position);
        /* the step really varies: a fixed dt0 would take 0.8125 / dt0 steps */
        ck_assert_msg((double)steps < 0.9 * 0.8125 / dt0, "the time step did not vary");
    }
    double mx = 0, my = 0, sxy = 0, sxx = 0;
    for (int k = 0; k < levels; k++) {
        mx += lx[k] / levels;
        my += ly[k] / levels;
    }
    for (int k = 0; k < levels; k++) {
        sxy += (lx[k] - mx) * (ly[k] - my);
        sxx += (lx[k] - mx) * (lx[k] - mx);
    }
    const double slope = sxy / sxx;
    fprintf(stderr, "%s, variable step: order (least squares) %.3f\n", s->label, slope);
    const double lo = s->order == 1 ? 0.9 : 1.7, hi = s->order == 1 ? 1.2 : 2.3;
    ck_assert_msg(slope >= lo && slope <= hi, "%s: variable-step order %.3f outside [%.1f, %.1f]",
                  s->label, slope, lo, hi);
}
END_TEST

/* ------------------------------------------------------------- energy -- */

typedef struct energy_trace {
    double *e;    /* energy after every step, e[0] initial */
    double *j;    /* the scheme's conserved quadratic form, if any */
    int64_t count;
} energy_trace;

/* J for the symplectic schemes: semi-implicit Euler (kick, then drift with
 * the new velocity) conserves |v|^2 + w^2 |y|^2 - w^2 dt y.v exactly;
 * position Verlet (drift-kick-drift) conserves w^2 |y|^2 + (1 - (w dt)^2/4) |v|^2. */
enum { INVARIANT_NONE, INVARIANT_SEMI_IMPLICIT, INVARIANT_POSITION_VERLET };

static void measure(sluice_sim *sim, double dt, int invariant, double *e, double *j)
{
    const sluice_view *v = sluice_sim_view(sim);
    double energy = 0, form = 0;
    const double w2 = OMEGA * OMEGA, z2 = w2 * dt * dt;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        double y2 = 0, u2 = 0, yu = 0;
        for (uint32_t d = 0; d < v->dimensions; d++) {
            double y = (double)v->position[d][i] - centre[d];
            double u = (double)test_column(sim, "velocity", d)[i];
            y2 += y * y;
            u2 += u * u;
            yu += y * u;
        }
        energy += 0.5 * u2 + 0.5 * w2 * y2;
        if (invariant == INVARIANT_SEMI_IMPLICIT)
            form += u2 + w2 * y2 - w2 * dt * yu;
        else if (invariant == INVARIANT_POSITION_VERLET)
            form += w2 * y2 + (1 - z2 / 4) * u2;
    }
    *e = energy;
    *j = form;
}

static energy_trace trace_energy(const scheme *s, double dt, double periods, int invariant)
{
    options o = {2, dt, periods, NULL, 0};
    sluice_sim *sim = load("energy", s, &o);
    const int64_t steps = (int64_t)llround(periods / dt);
    energy_trace t = {calloc((size_t)steps + 1, sizeof(double)),
                      calloc((size_t)steps + 1, sizeof(double)), steps + 1};
    ck_assert(t.e && t.j);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    measure(sim, dt, invariant, &t.e[0], &t.j[0]);
    for (int64_t n = 1; n <= steps; n++) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "%s", sluice_sim_failure(sim));
        measure(sim, dt, invariant, &t.e[n], &t.j[n]);
    }
    ck_assert(sluice_sim_time(sim) == periods);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return t;
}

/* largest |E/E0 - 1| and mean E/E0 over steps [a, b) */
static double window_error(const energy_trace *t, int64_t a, int64_t b)
{
    double worst = 0;
    for (int64_t n = a; n < b; n++)
        worst = fmax(worst, fabs(t->e[n] / t->e[0] - 1));
    return worst;
}

static double window_mean(const energy_trace *t, int64_t a, int64_t b)
{
    double sum = 0;
    for (int64_t n = a; n < b; n++)
        sum += t->e[n] / t->e[0];
    return sum / (double)(b - a);
}

/* Symplectic and semi-implicit Euler over 100 periods at omega dt = 2 pi/64:
 * their quadratic invariant J is conserved to round-off, which pins the
 * energy in a fixed band: |E/E0 - 1| <= 2z/(2 - z) (semi-implicit Euler,
 * from |2E - J| <= z E) or (z^2/4)/(1 - z^2/4) (position Verlet, from
 * J <= 2E <= J/(1 - z^2/4)), z = omega dt. No secular growth: the largest
 * error over periods 90-100 equals that over periods 0-10 up to the sampling
 * of the band's extremes at 64 phases per period (relative O((pi/64)^2)). */
START_TEST(energy_bounded)
{
    const scheme *s = &schemes[_i == 0 ? 0 : 1];
    const int invariant = _i == 0 ? INVARIANT_POSITION_VERLET : INVARIANT_SEMI_IMPLICIT;
    const double dt = 1.0 / 64, z = OMEGA * dt;
    energy_trace t = trace_energy(s, dt, 100, invariant);
    double drift = 0;
    for (int64_t n = 0; n < t.count; n++)
        drift = fmax(drift, fabs(t.j[n] / t.j[0] - 1));
    const double early = window_error(&t, 0, 640), late = window_error(&t, 5760, 6401);
    const double bound = invariant == INVARIANT_SEMI_IMPLICIT ? 2 * z / (2 - z)
                                                                : (z * z / 4) / (1 - z * z / 4);
    fprintf(stderr,
            "%s, omega dt = 2 pi/64, 100 periods: |J/J0 - 1| <= %.2e; max |E/E0 - 1| %.4e "
            "(periods 0-10), %.4e (periods 90-100), bound %.4e\n",
            s->label, drift, early, late, bound);
    /* round-off: a few roundings of relative size eps per step */
    ck_assert_msg(drift <= 16 * EPS * (double)t.count, "%s: J drifts by %g", s->label, drift);
    ck_assert_msg(early <= bound && late <= bound, "%s: energy error beyond its band", s->label);
    ck_assert_msg(fabs(late - early) <= z * z * early, "%s: energy error grows (%g -> %g)",
                  s->label, early, late);
    free(t.e);
    free(t.j);
}
END_TEST

/* Forward Euler multiplies the energy of an undamped oscillator by exactly
 * 1 + z^2 per step, the predictor-corrector (explicit midpoint) by exactly
 * 1 + z^4/4: both maps are polynomials in the oscillator's generator, which
 * is skew in the energy norm. Checked at every step to round-off. */
START_TEST(energy_growth_exact)
{
    const int explicit_euler = _i == 0;
    const scheme *s = &schemes[explicit_euler ? 2 : 5];
    const double dt = explicit_euler ? 1.0 / 256 : 1.0 / 64, z = OMEGA * dt;
    const double periods = explicit_euler ? 10 : 100;
    const double factor = explicit_euler ? 1 + z * z : 1 + z * z * z * z / 4;
    energy_trace t = trace_energy(s, dt, periods, INVARIANT_NONE);
    double worst = 0;
    for (int64_t n = 0; n < t.count; n++) {
        double expected = pow(factor, (double)n);
        worst = fmax(worst, fabs(t.e[n] / t.e[0] / expected - 1));
    }
    fprintf(stderr,
            "%s, omega dt = %.4f, %g periods: E/E0 = %.6f at the end, (1 + %s)^n = %.6f; "
            "largest relative deviation %.2e\n",
            s->label, z, periods, t.e[t.count - 1] / t.e[0],
            explicit_euler ? "z^2" : "z^4/4", pow(factor, (double)(t.count - 1)), worst);
    ck_assert_msg(worst <= 16 * EPS * (double)t.count, "%s: energy deviates by %g", s->label,
                  worst);
    free(t.e);
    free(t.j);
}
END_TEST

/* 3x3 helpers for the Verlet cycle matrix on (y, v, v_previous). */
static void mat_mul(const double a[9], const double b[9], double c[9])
{
    double r[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    memcpy(c, r, sizeof r);
}

/* log of the spectral radius: (1/m) log ||M^m|| with m = 2^30, by squaring
 * with rescaling (the error is O(log(cond)/m)). */
static double log_spectral_radius(const double m[9])
{
    double a[9], scale = 0;
    memcpy(a, m, sizeof a);
    for (int k = 0; k < 30; k++) {
        mat_mul(a, a, a);
        double top = 0;
        for (int i = 0; i < 9; i++)
            top = fmax(top, fabs(a[i]));
        for (int i = 0; i < 9; i++)
            a[i] /= top;
        scale = 2 * scale + log(top);
    }
    return scale / 1073741824.0;
}

/* Verlet (euler_every 40) is not symplectic: theory for the linear
 * oscillator is the spectral radius rho of its cycle matrix
 * M = L^39 E (L the leapfrog step, E the Euler step on (y, v, v_previous));
 * the energy grows as rho^(2 m) over m cycles. Measured: the mean energy over
 * periods 90-100 against that over periods 0-10 (144 cycles apart). The
 * energy oscillates within each period by O(z); averaged over ten whole
 * periods its phase leaves a residue far below the 5e-3 allowed, while the
 * growth itself is of order one. */
START_TEST(energy_verlet)
{
    const scheme *s = &schemes[3];
    const double dt = 1.0 / 64, w2 = OMEGA * OMEGA, z2 = w2 * dt * dt;
    const double leapfrog[9] = {1 - z2 / 2, dt, 0, -2 * w2 * dt, 0, 1, 0, 1, 0};
    const double euler[9] = {1 - z2 / 2, dt, 0, -w2 * dt, 1, 0, 0, 1, 0};
    double cycle[9];
    memcpy(cycle, euler, sizeof cycle);
    for (int k = 1; k < 40; k++)
        mat_mul(leapfrog, cycle, cycle);
    const double log_rho = log_spectral_radius(cycle);
    energy_trace t = trace_energy(s, dt, 100, INVARIANT_NONE);
    const double early = window_mean(&t, 0, 640), late = window_mean(&t, 5760, 6400);
    const double predicted = exp(2 * 144 * log_rho), measured = late / early;
    fprintf(stderr,
            "%s, omega dt = 2 pi/64: spectral radius per cycle %.8f (energy x%.5f per period); "
            "mean E/E0 periods 0-10 %.5f, 90-100 %.5f: growth %.5f, predicted %.5f\n",
            s->label, exp(log_rho), exp(2 * log_rho * 64 / 40), early, late, measured, predicted);
    ck_assert_msg(predicted > 1.2, "theory: verlet's energy grows secularly");
    ck_assert_msg(fabs(measured / predicted - 1) <= 5e-3, "verlet energy growth %g, theory %g",
                  measured, predicted);
    free(t.e);
    free(t.j);
}
END_TEST

/* predictor_corrector in pec mode (one evaluation per step, the predictor
 * with the previous step's mid-step rates) is not an energy-norm rotation:
 * its step on (y, v, a_lagged),
 *   y* = y + dt/2 v,  v* = v + dt/2 a_lagged,  a* = -w^2 y*,
 *   y' = y + dt v*,   v' = v + dt a*,           a_lagged' = a*,
 * has two eigenvalues of modulus^2 1 + z^4/2 + O(z^6) and a parasitic one of
 * about z^2/2, which dies within a few steps (the first step evaluates at
 * t^0, so a_lagged starts as the true acceleration). The energy grows as
 * rho^(2n); measured as for verlet, the mean energy over periods 90-100
 * against that over periods 0-10 (5760 steps apart), to the same 5e-3. */
START_TEST(energy_pec)
{
    const scheme *s = &schemes[6];
    const double dt = 1.0 / 64, w2 = OMEGA * OMEGA, z2 = w2 * dt * dt;
    /* rows: y', v', a_lagged' in terms of (y, v, a_lagged) */
    const double step[9] = {1, dt, dt * dt / 2,         /* y + dt (v + dt/2 a) */
                            -w2 * dt, 1 - z2 / 2, 0,   /* v - w^2 dt (y + dt/2 v) */
                            -w2, -w2 * dt / 2, 0};      /* -w^2 (y + dt/2 v) */
    const double log_rho = log_spectral_radius(step);
    energy_trace t = trace_energy(s, dt, 100, INVARIANT_NONE);
    const double early = window_mean(&t, 0, 640), late = window_mean(&t, 5760, 6400);
    const double predicted = exp(2 * 5760 * log_rho), measured = late / early;
    const double z4 = z2 * z2;
    fprintf(stderr,
            "%s, omega dt = 2 pi/64: spectral radius^2 per step - 1 = %.4e (z^4/2 = %.4e); "
            "mean E/E0 periods 0-10 %.5f, 90-100 %.5f: growth %.5f, predicted %.5f\n",
            s->label, expm1(2 * log_rho), z4 / 2, early, late, measured, predicted);
    ck_assert_msg(fabs(expm1(2 * log_rho) / (z4 / 2) - 1) <= 2 * z2,
                  "theory: rho^2 - 1 = z^4/2 + O(z^6)");
    ck_assert_msg(predicted > 1.2, "theory: pec's energy grows secularly");
    ck_assert_msg(fabs(measured / predicted - 1) <= 5e-3, "pec energy growth %g, theory %g",
                  measured, predicted);
    free(t.e);
    free(t.j);
}
END_TEST

/* The energy gauge of the fixture library
 * on free fall: position Verlet integrates a constant acceleration exactly,
 * so the gauge's kinetic and potential energies must equal
 * sum 1/2 m |v0 + g t|^2 and sum m 9.81 (y0 + v0y t - 9.81 t^2 / 2) at every
 * sample, to the 10 digits of the table, and sample at the requested times. */
START_TEST(energy_gauge_free_fall)
{
    const char *fixtures = getenv("SLUICE_FIXTURE_DIR");
    ck_assert_ptr_nonnull(fixtures);
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.1}\n"
             "time: {end: 0.5, max_step: 0.00390625}\n"
             "domain: {min: [-3, -3], max: [3, 3]}\n"
             "plugin_path: %s\n"
             "initial: {density: rest}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.2, 0.2], velocity: [0.5, 2]}]}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  gravity: {acceleration: [0, -9.81]}\n"
             "  energy_gauge: {interval: 0.0625}\n"
             "  symplectic: {}\n",
             fixtures);
    sluice_sim *sim = test_load("energy-gauge", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const double m = 1000 * 0.1 * 0.1, g = 9.81;
    const int n = (int)v->count;
    double y0 = 0;
    for (sluice_index i = 0; i < v->count; i++)
        y0 += (double)v->position[1][i];
    char *dir = test_scratch("energy-gauge-out");
    ck_assert_ptr_nonnull(dir);
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < 0.5)
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "%s", sluice_sim_failure(sim));
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    char path[4096];
    snprintf(path, sizeof path, "%s/energy.csv", dir);
    FILE *f = fopen(path, "r");
    ck_assert_msg(f != NULL, "no %s", path);
    char line[512];
    ck_assert_ptr_nonnull(fgets(line, sizeof line, f));
    ck_assert_str_eq(line, "time,kinetic,potential,total\n");
    int rows = 0;
    double t, kinetic, potential, total, worst = 0;
    while (fscanf(f, "%lf,%lf,%lf,%lf", &t, &kinetic, &potential, &total) == 4) {
        const double vy = 2 - g * t;
        const double k = n * 0.5 * m * (0.25 + vy * vy);
        const double p = m * g * (y0 + n * (2 * t - 0.5 * g * t * t));
        const double scale = fabs(k) + fabs(p);
        ck_assert_msg(fabs(t - 0.0625 * rows) <= 1e-12, "sample %d at t = %.17g", rows, t);
        worst = fmax(worst, fmax(fabs(kinetic - k), fabs(potential - p)) / scale);
        ck_assert_msg(fabs(total - kinetic - potential) <= 1e-9 * scale, "total != sum");
        rows++;
    }
    fclose(f);
    fprintf(stderr, "energy gauge, free fall: %d samples, largest relative deviation %.2e\n", rows,
            worst);
    ck_assert_int_eq(rows, 9);
    /* tables hold 10 significant digits (relative rounding 5e-10 per value);
     * the integration itself is exact to round-off */
    ck_assert_msg(worst <= 1e-9, "energy gauge deviates by %g", worst);
    free(dir);
}
END_TEST

/* -------------------------------------------- density, walls, kinds -- */

/* Every integrator carries a constant density rate exactly (also through a
 * varying step: verlet's dt_{n-1} + dt_n increment), on fluid and on wall
 * particles (the rate is declared for both kinds), while wall particles keep
 * their position and zero velocity bit for bit. */
START_TEST(density_rate_and_walls)
{
    const scheme *s = &schemes[_i];
    const double rate = 3;
    options o = {2, 0, 2.0,
                 ", density_rate: 3, time_step: 0.015625, time_step_variation: 0.5", 1};
    sluice_sim *sim = load("density", s, &o);
    initial in;
    record(sim, &in);
    size_t walls = 0;
    for (size_t k = 0; k < in.n; k++)
        walls += in.kind[k] == SLUICE_KIND_WALL;
    ck_assert_uint_gt(walls, 10);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    double dt_min = INFINITY, dt_max = 0;
    while (sluice_sim_time(sim) < 2.0) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "%s", sluice_sim_failure(sim));
        if (sluice_sim_time(sim) < 2.0) { /* the last step is cut to the end */
            dt_min = fmin(dt_min, sim->dt);
            dt_max = fmax(dt_max, sim->dt);
        }
    }
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *rho = test_column(sim, "density", 0);
    double worst_fluid = 0, worst_wall = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        size_t k = (size_t)v->id[i];
        double error = fabs((double)rho[i] - (in.rho[k] + rate * 2.0));
        if (v->kind[i] == SLUICE_KIND_WALL) {
            worst_wall = fmax(worst_wall, error);
            for (uint32_t d = 0; d < 2; d++) {
                ck_assert_msg((double)v->position[d][i] == in.x[3 * k + d], "%s: a wall moved",
                              s->label);
                ck_assert_msg(test_column(sim, "velocity", d)[i] == 0, "%s: a wall has velocity",
                              s->label);
            }
        } else {
            worst_fluid = fmax(worst_fluid, error);
        }
    }
    fprintf(stderr,
            "%s: dt in [%.5f, %.5f] s, %lld steps; density error after 2 s: fluid %.2e, walls "
            "%.2e kg m^-3\n",
            s->label, dt_min, dt_max, (long long)sluice_sim_steps(sim), worst_fluid, worst_wall);
    ck_assert_msg(dt_max > 1.2 * dt_min, "the time step did not vary");
    /* round-off: one rounding of ulp(1000 kg m^-3) = 1.1e-13 per step */
    const double tolerance = 4 * 1000 * EPS * (double)sluice_sim_steps(sim);
    ck_assert_msg(worst_fluid <= tolerance && worst_wall <= tolerance,
                  "%s: density rate not carried exactly (%g, %g)", s->label, worst_fluid,
                  worst_wall);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    release(&in);
    sluice_sim_free(sim);
}
END_TEST

/* ---------------------------------------------------------- time step -- */

static const sluice_instance *instance(sluice_sim *sim, const char *name)
{
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if (strcmp(sim->instances[k].name, name) == 0)
            return &sim->instances[k];
    ck_abort_msg("no instance '%s'", name);
    return NULL;
}

static double limit_of(sluice_sim *sim, const char *name)
{
    const sluice_instance *in = instance(sim, name);
    const sluice_view *v = sluice_sim_view(sim);
    /* in two ranges, as the core's chunks would */
    sluice_index half = v->count / 2;
    double a = (double)in->component->time_step_limit(in->state, v, 0, half);
    double b = (double)in->component->time_step_limit(in->state, v, half, v->count);
    return fmin(a, b);
}

static int near(double a, double b)
{
    return (isinf(a) && isinf(b)) || fabs(a - b) <= 8 * EPS * fabs(b);
}

/* Hand-made state: accelerations, velocities, sound speeds and max |mu_ij|
 * set directly; the limits must equal the documented formulas:
 *   time_step: C min(sqrt(h/max|a|), h/max(c + |v|), 0.125 h^2/nu) over the
 *   conditions turned on; artificial_viscosity: C min h/(c + mu_max). */
START_TEST(time_step_formulas)
{
    static const struct {
        int force, acoustic, viscous, av_limit;
        double courant;
    } cases[] = {{1, 1, 0, 1, 0.2}, {1, 0, 0, 1, 0.3}, {0, 1, 0, 1, 1.0}, {0, 0, 1, 1, 0.2},
                 {1, 1, 1, 0, 0.25}};
    const int n_cases = (int)(sizeof cases / sizeof cases[0]);
    for (int c = 0; c < n_cases; c++) {
        const double nu = 0.02;
        char yaml[2048];
        snprintf(yaml, sizeof yaml,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.1, smoothing_length_ratio: 1.3}\n"
                 "time: {end: 1}\n"
                 "domain: {min: [-1, -1], max: [2, 2]}\n"
                 "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.4, 0.4]}]}\n"
                 "initial: {density: rest}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  tait: {speed_of_sound: 20}\n"
                 "  continuity: {}\n"
                 "  pressure_gradient: {}\n"
                 "  artificial_viscosity: {alpha: 0.1, time_step_limit: %s}\n"
                 "  laminar_viscosity: {kinematic_viscosity: %g}\n"
                 "  time_step: {courant: %g, force: %s, acoustic: %s, viscous: %s}\n"
                 "  euler: {}\n",
                 cases[c].av_limit ? "true" : "false", nu, cases[c].courant,
                 cases[c].force ? "true" : "false", cases[c].acoustic ? "true" : "false",
                 cases[c].viscous ? "true" : "false");
        sluice_sim *sim = test_load("time-step", yaml, NULL, 0);
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        const sluice_view *v = sluice_sim_view(sim);
        const double h = (double)v->smoothing_length, C = cases[c].courant;
        sluice_field mu_field;
        const int has_mu = sluice_sim_field(sim, "viscous_mu_max", &mu_field) == SLUICE_OK;
        ck_assert_msg(has_mu == cases[c].av_limit,
                      "viscous_mu_max must exist exactly when the limit is on");
        double a_max = 0, speed_max = 0, av = INFINITY;
        for (sluice_index i = 0; i < v->count; i++) {
            const double ax = 3 + 0.7 * i, ay = -2 - 0.5 * i;
            const double vx = 0.1 * i - 0.4, vy = -0.2 + 0.05 * (i % 3);
            const double cs = 20 + 0.25 * (i % 5), mu = 0.9 * (i % 7);
            test_column(sim, "acceleration", 0)[i] = (sluice_real)ax;
            test_column(sim, "acceleration", 1)[i] = (sluice_real)ay;
            test_column(sim, "velocity", 0)[i] = (sluice_real)vx;
            test_column(sim, "velocity", 1)[i] = (sluice_real)vy;
            test_column(sim, "sound_speed", 0)[i] = (sluice_real)cs;
            if (has_mu)
                sluice_real_column(v, mu_field, 0)[i] = (sluice_real)mu;
            a_max = fmax(a_max, hypot(ax, ay));
            speed_max = fmax(speed_max, cs + hypot(vx, vy));
            av = fmin(av, C * h / (cs + mu));
        }
        double expected = INFINITY;
        if (cases[c].force)
            expected = fmin(expected, C * sqrt(h / a_max));
        if (cases[c].acoustic)
            expected = fmin(expected, C * h / speed_max);
        if (cases[c].viscous)
            expected = fmin(expected, C * 0.125 * h * h / nu);
        const double got = limit_of(sim, "time_step");
        const double got_av = limit_of(sim, "artificial_viscosity");
        const double got_laminar = limit_of(sim, "laminar_viscosity");
        fprintf(stderr,
                "force %d acoustic %d viscous %d, C = %g: time_step %.10e s (formula %.10e); "
                "artificial_viscosity %.10e s (formula %.10e); laminar %.6e s\n",
                cases[c].force, cases[c].acoustic, cases[c].viscous, C, got, expected, got_av,
                cases[c].av_limit ? av : INFINITY, got_laminar);
        ck_assert_msg(near(got, expected), "time_step limit %.17g, formula %.17g", got, expected);
        ck_assert_msg(near(got_av, cases[c].av_limit ? av : INFINITY),
                      "artificial_viscosity limit %.17g", got_av);
        ck_assert_msg(near(got_laminar, 0.125 * h * h / nu), "laminar limit %.17g", got_laminar);
        sluice_sim_free(sim);
    }
}
END_TEST

/* The seeds' combinations through the core's step (sim->dt_limit, the
 * minimum of every plugin's limit), on the state at the start of the step:
 *  seed 000: time_step {courant: 1, force: false, acoustic: true} and
 *            artificial_viscosity {time_step_limit: false}:
 *            dt = min_i h/(c_i + |v_i|), although the artificial viscosity's
 *            own limit would be smaller here;
 *  seed 001: time_step {courant: 0.2, force: true, acoustic: false,
 *            viscous: true} with laminar_viscosity:
 *            dt = 0.2 min(min_i sqrt(h/|a_i|), 0.125 h^2/nu), for a nu where
 *            the force condition binds and one where the viscous one does. */
static sluice_sim *seed_scene(const char *plugins)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.05, smoothing_length_ratio: 1.3}\n"
             "time: {end: 1}\n"
             "domain: {min: [-1, -1], max: [2, 2]}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.4, 0.4]}]}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 10}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  gravity: {}\n"
             "%s"
             "  euler: {}\n",
             plugins);
    sluice_sim *sim = test_load("seed-step", yaml, NULL, 0);
    /* a converging shear flow: |mu_ij| exceeds |v_i| where the step binds */
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++) {
        double x = (double)v->position[0][i], y = (double)v->position[1][i];
        test_column(sim, "velocity", 0)[i] = (sluice_real)(0.8 * sin(2 * PI * x / 0.2));
        test_column(sim, "velocity", 1)[i] = (sluice_real)(0.3 * cos(2 * PI * y / 0.2));
    }
    return sim;
}

START_TEST(seed_time_steps)
{
    /* seed 000 */
    for (int av_limit = 0; av_limit < 2; av_limit++) {
        char plugins[512];
        snprintf(plugins, sizeof plugins,
                 "  artificial_viscosity: {alpha: 0.1, time_step_limit: %s}\n"
                 "  time_step: {courant: 1, force: false, acoustic: true}\n",
                 av_limit ? "true" : "false");
        sluice_sim *sim = seed_scene(plugins);
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        const sluice_view *v = sluice_sim_view(sim);
        const double h = (double)v->smoothing_length;
        double acoustic = INFINITY, viscous = INFINITY;
        const sluice_real *cs = test_column(sim, "sound_speed", 0);
        for (sluice_index i = 0; i < v->count; i++) {
            double speed = hypot((double)test_column(sim, "velocity", 0)[i],
                                 (double)test_column(sim, "velocity", 1)[i]);
            acoustic = fmin(acoustic, h / ((double)cs[i] + speed));
            if (av_limit)
                viscous = fmin(viscous, h / ((double)cs[i] +
                                              (double)test_column(sim, "viscous_mu_max", 0)[i]));
        }
        ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        fprintf(stderr,
                "seed 000, artificial viscosity limit %s: dt %.10e s; min h/(c+|v|) = %.10e s, "
                "min h/(c+mu_max) = %.10e s\n",
                av_limit ? "on" : "off", sim->dt_limit, acoustic, viscous);
        if (av_limit) {
            ck_assert_msg(viscous < acoustic, "the test state must make the viscous limit bind");
            ck_assert_msg(near(sim->dt_limit, viscous), "dt %.17g", sim->dt_limit);
        } else {
            ck_assert_msg(near(sim->dt_limit, acoustic), "seed 000: dt %.17g, formula %.17g",
                          sim->dt_limit, acoustic);
        }
        sluice_sim_end(sim, SLUICE_RUN_COMPLETE);
        sluice_sim_free(sim);
    }
    /* seed 001 */
    const double nus[2] = {1e-6, 0.05};
    for (int k = 0; k < 2; k++) {
        char plugins[512];
        snprintf(plugins, sizeof plugins,
                 "  laminar_viscosity: {kinematic_viscosity: %g}\n"
                 "  time_step: {courant: 0.2, force: true, acoustic: false, viscous: true}\n",
                 nus[k]);
        sluice_sim *sim = seed_scene(plugins);
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        const sluice_view *v = sluice_sim_view(sim);
        const double h = (double)v->smoothing_length;
        double a_max = 0;
        for (sluice_index i = 0; i < v->count; i++)
            a_max = fmax(a_max, hypot((double)test_column(sim, "acceleration", 0)[i],
                                      (double)test_column(sim, "acceleration", 1)[i]));
        const double force = 0.2 * sqrt(h / a_max), viscous = 0.2 * 0.125 * h * h / nus[k];
        ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        fprintf(stderr,
                "seed 001, nu = %g: dt %.10e s; 0.2 sqrt(h/|a|max) = %.10e s, 0.2 * 0.125 h^2/nu "
                "= %.10e s\n",
                nus[k], sim->dt_limit, force, viscous);
        ck_assert_msg(k == 0 ? force < viscous : viscous < force, "nu must select the condition");
        ck_assert_msg(near(sim->dt_limit, fmin(force, viscous)), "seed 001: dt %.17g",
                      sim->dt_limit);
        sluice_sim_end(sim, SLUICE_RUN_COMPLETE);
        sluice_sim_free(sim);
    }
}
END_TEST

int main(void)
{
    Suite *s = suite_create("integrators");
    TCase *o = tcase_create("order");
    tcase_set_timeout(o, 120);
    tcase_add_loop_test(o, order_2d, 0, SCHEME_COUNT);
    tcase_add_loop_test(o, order_transport, 0, SCHEME_COUNT);
    tcase_add_loop_test(o, order_3d, 0, SCHEME_COUNT);
    tcase_add_loop_test(o, order_variable_step, 0, SCHEME_COUNT);
    suite_add_tcase(s, o);
    TCase *e = tcase_create("energy");
    tcase_set_timeout(e, 120);
    tcase_add_loop_test(e, energy_bounded, 0, 2);
    tcase_add_loop_test(e, energy_growth_exact, 0, 2);
    tcase_add_test(e, energy_verlet);
    tcase_add_test(e, energy_pec);
    tcase_add_test(e, energy_gauge_free_fall);
    suite_add_tcase(s, e);
    TCase *d = tcase_create("density and walls");
    tcase_add_loop_test(d, density_rate_and_walls, 0, SCHEME_COUNT);
    suite_add_tcase(s, d);
    TCase *t = tcase_create("time step");
    tcase_add_test(t, time_step_formulas);
    tcase_add_test(t, seed_time_steps);
    suite_add_tcase(s, t);
    return test_run_suite(s);
}
