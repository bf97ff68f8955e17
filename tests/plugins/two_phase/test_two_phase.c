/* Two-phase air-water SPH (plugins/two_phase/two_phase.c; seed 001 after
 * Colagrossi & Landrini 2003 and Nugent & Posch 2000):
 *  - the air's speed of sound from one B, c0_a = sqrt(gamma_a B / rho0_a)
 *    (379.3 m/s and 474.1 m/s in seed 001's table 1), and the equation of
 *    state of each phase against its formula;
 *  - the initial state: phases from the air description, masses rho0_k dx^d,
 *    the hydrostatic pressure continuous across the interface;
 *  - a still two-layer column (water under air, dbc walls and a lid): the
 *    time-averaged water pressure is hydrostatic up to the kernel's lattice
 *    moment, the interface stays, no air gets into the water, the kinetic
 *    energy stays below the elastic energy of the start;
 *  - a dam break in air: the front follows the single-phase front, and no
 *    air is entrained into the water nor water broken off into the air;
 *  - the air's cohesion against a brute-force sum with W(r, H) (H up to 2h,
 *    pairs beyond the kernel support), its momentum balance, and its
 *    refusal of a cohesion pressure above the background pressure;
 *  - the phase field survives a checkpoint and restart;
 *  - bad input: one clear message each. */
#include <math.h>

#include "diag.h"
#include "sim_util.h"

#define G 9.81

/* ------------------------------------------------------------- helpers -- */

static const uint8_t *phase_column(sluice_sim *sim)
{
    sluice_field f;
    ck_assert_int_eq(sluice_sim_field(sim, "phase", &f), SLUICE_OK);
    ck_assert_int_eq(f.type, SLUICE_TYPE_UINT8);
    return sluice_sim_view(sim)->columns[f.column];
}

/* --------------------------------------------------------- small scene -- */

/* A closed 2D box, water below y = 0.1, air above; `plugins` appended. */
static char *box_scene(const char *two_phase, const char *extra)
{
    char *text = NULL;
    ck_assert_int_ge(
        asprintf(&text,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.02, smoothing_length_ratio: 1.225, rest_density: 1000}\n"
                 "time: {end: 1.0, max_step: 1e-5}\n"
                 "domain: {min: [-0.1, -0.1], max: [0.3, 0.3]}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [0.2, 0.1]}\n"
                 "    - {shape: box, min: [0, 0.1], max: [0.2, 0.2]}\n"
                 "initial: {density: hydrostatic}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  two_phase: {%s}\n"
                 "  gravity: {}\n"
                 "  symplectic: {}\n"
                 "%s",
                 two_phase, extra ? extra : ""),
        0);
    return text;
}

/* box_scene without gravity (the terms under test alone move it), and with
 * `verlet` on Verlet instead of symplectic. The lines are blanked in a copy
 * (box_scene's own text is freed). */
static char *box_scene_without_gravity(const char *two_phase, const char *extra, int verlet)
{
    char *yaml = box_scene(two_phase, extra);
    char *edited = NULL;
    ck_assert_int_ge(
        asprintf(&edited, "%s%s", yaml, verlet ? "  verlet: {euler_every: 40}\n" : ""), 0);
    free(yaml);
    const char *blank[2] = {"  gravity: {}", verlet ? "  symplectic: {}" : NULL};
    for (int k = 0; k < 2 && blank[k]; k++) {
        char *line = strstr(edited, blank[k]);
        ck_assert_ptr_nonnull(line);
        memset(line, ' ', strlen(blank[k]));
    }
    return edited;
}

/* ----------------------------------------------- equation of state -- */

/* c0 of the air from one B: seed 001's table 1 lists 379.3 m/s for the
 * Chanson chute (c0_w = 28 m/s) and 474.1 m/s for the Cheng spillway
 * (c0_w = 35 m/s), with rho 1000 / 1.09 and gamma 7 / 1.4. The sound
 * speed field at the air's rest density is c0_a. */
static void check_air_speed(double c_w, double table)
{
    char settings[200];
    snprintf(settings, sizeof settings,
             "speed_of_sound: %g, background_pressure: 100, air_above: [[0, 0.1]]", c_w);
    char *yaml = box_scene(settings, NULL);
    sluice_sim *sim = test_load("air-speed", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_column(sim);
    sluice_real *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < v->count; i++)
        rho[i] = phase[i] ? (sluice_real)1.09 : 1000;
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    phase = phase_column(sim);
    const sluice_real *c = test_column(sim, "sound_speed", 0);
    const double B = c_w * c_w * 1000 / 7, expected = sqrt(1.4 * B / 1.09);
    int air = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const double want = phase[i] ? expected : c_w;
        ck_assert_msg(fabs(c[i] - want) <= 1e-13 * want, "c0 = %.17g, expected %.17g", c[i],
                      want);
        if (phase[i] && !air++)
            fprintf(stderr, "c0_w = %g m/s: c0_air = %.6f m/s (sqrt(gamma_a B / rho_a) = %.6f, "
                            "seed 001 table 1: %.1f)\n",
                    c_w, c[i], expected, table);
    }
    ck_assert_int_gt(air, 0);
    /* the table prints one decimal: within half a unit of it */
    ck_assert_msg(fabs(expected - table) <= 0.05, "c0_air %.4f against the table's %.1f",
                  expected, table);
    sluice_sim_free(sim);
    free(yaml);
}

START_TEST(air_speed_of_sound_from_one_B)
{
    check_air_speed(28, 379.3); /* Chanson chute */
    check_air_speed(35, 474.1); /* Cheng spillway */
}
END_TEST

/* p = B ((rho/rho0_k)^gamma_k - 1) + p_b and c^2 = dp/drho for both phases,
 * over +/- 3 % of each rest density. */
START_TEST(equation_of_state_values)
{
    char *yaml = box_scene("speed_of_sound: 28, background_pressure: 350, air_above: [[0, 0.1]]",
                           NULL);
    sluice_sim *sim = test_load("eos", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_column(sim);
    sluice_real *rho = test_column(sim, "density", 0);
    const double rest[2] = {1000, 1.09}, gamma[2] = {7, 1.4}, B = 28.0 * 28.0 * 1000 / 7;
    const double pb = 350;
    for (sluice_index i = 0; i < v->count; i++)
        rho[i] = (sluice_real)(rest[phase[i]] * (0.97 + 0.06 * i / (double)v->count));
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    phase = phase_column(sim);
    rho = test_column(sim, "density", 0);
    const sluice_real *p = test_column(sim, "pressure", 0);
    const sluice_real *c = test_column(sim, "sound_speed", 0);
    double worst_p = 0, worst_c = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const int k = phase[i];
        const double x = rho[i] / rest[k], expected = B * (pow(x, gamma[k]) - 1) + pb;
        worst_p = fmax(worst_p, fabs(p[i] - expected) / B);
        ck_assert_msg(fabs(p[i] - expected) <= 1e-12 * B, "phase %d: p(%g) = %.17g, expected %.17g",
                      k, rho[i], p[i], expected);
        const double eps = 1e-6 * rest[k];
        const double dpdrho = B *
                              (pow((rho[i] + eps) / rest[k], gamma[k]) -
                               pow((rho[i] - eps) / rest[k], gamma[k])) /
                              (2 * eps);
        worst_c = fmax(worst_c, fabs(c[i] * c[i] - dpdrho) / dpdrho);
        /* central difference: relative error (eps/rho)^2 gamma^2 ~ 5e-11 */
        ck_assert_msg(fabs(c[i] * c[i] - dpdrho) <= 1e-7 * dpdrho,
                      "phase %d: c^2 = %g, dp/drho = %g", k, c[i] * c[i], dpdrho);
    }
    fprintf(stderr, "equation of state: |p - formula| / B <= %.2e, |c^2 - dp/drho| / (dp/drho) "
                    "<= %.2e\n",
            worst_p, worst_c);
    sluice_sim_free(sim);
    free(yaml);
}
END_TEST

/* -------------------------------------------------- the initial state -- */

START_TEST(initial_phases_masses_and_pressure)
{
    /* the air: above y = 0.1, plus a box and a polygon reaching into the
     * water (a corner and a triangle) */
    char *yaml = box_scene("speed_of_sound: 28, background_pressure: 250,"
                           " air_above: [[0, 0.1]],"
                           " air_box_min: [[0.0, 0.0]], air_box_max: [[0.06, 0.04]],"
                           " air_polygon: [[0.12, 0.0], [0.2, 0.0], [0.2, 0.06]]",
                           NULL);
    sluice_sim *sim = test_load("initial", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_column(sim);
    const sluice_real *m = test_column(sim, "mass", 0);
    const double dx = 0.02, B = 28.0 * 28.0 * 1000 / 7, pb = 250;
    int air = 0, water = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const double x = v->position[0][i], y = v->position[1][i];
        /* the polygon's hypotenuse: y < 0.06 (x - 0.12) / 0.08 */
        const int expected = y > 0.1 || (x <= 0.06 && y <= 0.04) ||
                             (x >= 0.12 && y < 0.06 * (x - 0.12) / 0.08);
        ck_assert_msg(phase[i] == expected, "particle at (%g, %g): phase %d, expected %d", x, y,
                      phase[i], expected);
        ck_assert_msg(fabs(m[i] - (expected ? 1.09 : 1000) * dx * dx) <= 1e-15 * m[i],
                      "mass %g at phase %d", m[i], phase[i]);
        expected ? air++ : water++;
    }
    fprintf(stderr, "initial state: %d air, %d water particles\n", air, water);
    ck_assert_int_eq(air, 10 * 5 + 3 * 2 + 6);
    /* pressures at t = 0: water p_b + rho_w g (0.1 - y) (the core's
     * hydrostatic start), air p_b - rho_a g (y - 0.1) (the water's top is
     * at 0.09 + dx/2 = 0.1); the air inside the water is p_b - rho_a g
     * (y - 0.1) > p_b as well, as the rule says */
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    phase = phase_column(sim);
    const sluice_real *p = test_column(sim, "pressure", 0);
    double top_water = 0, bottom_air = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const double y = v->position[1][i];
        const double expected = phase[i] ? pb - 1.09 * G * (y - 0.1) : pb + 1000 * G * (0.1 - y);
        ck_assert_msg(fabs(p[i] - expected) <= 1e-10 * B,
                      "phase %d at y = %g: p = %.12g, expected %.12g", phase[i], y, p[i],
                      expected);
        if (fabs(y - 0.09) < 1e-9 && !phase[i])
            top_water = p[i];
        if (fabs(y - 0.11) < 1e-9 && phase[i])
            bottom_air = p[i];
    }
    /* continuity at the interface: the rows dx/2 below and above it differ
     * by (rho_w + rho_a) g dx / 2 */
    const double jump = top_water - bottom_air, expected_jump = (1000 + 1.09) * G * dx / 2;
    fprintf(stderr, "interface at t = 0: p(water, y = 0.09) - p(air, y = 0.11) = %.6f Pa "
                    "(rho_w + rho_a) g dx/2 = %.6f Pa)\n",
            jump, expected_jump);
    ck_assert(fabs(jump - expected_jump) <= 1e-9 * B);
    sluice_sim_free(sim);
    free(yaml);
}
END_TEST

/* ----------------------------------------------- still two-layer column -- */

/* Water (0.2 m wide, H = 0.15 m deep) under 0.1 m of air, dbc walls and a
 * lid; or (air = 0) the same water alone with a free surface. c0_w = 20 m/s
 * >= 10 sqrt(g H). */
/* `two_phase`: the scene's two_phase line with air (NULL: the column's
 * own, p_b = 100 Pa, air above 0.15 m) */
static char *column_scene(int air, const char *two_phase, const char *extra)
{
    char *text = NULL;
    ck_assert_int_ge(
        asprintf(&text,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.01, smoothing_length_ratio: 1.225, rest_density: 1000}\n"
                 "time: {end: 1.0}\n"
                 "domain: {min: [-0.1, -0.1], max: [0.3, 0.4]}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [0.2, 0.15]}\n"
                 "%s"
                 "  walls:\n"
                 "    - {shape: tank, min: [0, 0], max: [0.2, 0.3], name: tank}\n"
                 "%s"
                 "initial: {density: hydrostatic}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "%s"
                 "  continuity: {form: volume}\n"
                 "  pressure_gradient: {form: density_product}\n"
                 "  artificial_viscosity: {alpha: 0.1}\n"
                 "  gravity: {}\n"
                 "  dbc: {}\n"
                 "  time_step: {}\n"
                 "  symplectic: {}\n"
                 "%s",
                 air ? "    - {shape: box, min: [0, 0.15], max: [0.2, 0.25]}\n" : "",
                 air ? "    - {shape: polyline, points: [[0.2, 0.25], [0, 0.25]], name: lid}\n"
                     : "",
                 !air        ? "  tait: {speed_of_sound: 20}\n"
                 : two_phase ? two_phase
                             : "  two_phase: {speed_of_sound: 20, background_pressure: 100,"
                               " air_above: [[0, 0.15]]}\n",
                 extra),
        0);
    return text;
}

/* The first moment of the kernel gradient over the lattice, M = -sum_j
 * dx^2 x_j^2 F(r_j) (Wendland C2, h = ratio dx): the SPH gradient of a
 * linear field on the lattice is M times the exact one, so a lattice at
 * rest balances gravity with dp/dy = -rho g / M. */
static double lattice_moment(double ratio)
{
    const double a = 7 / (4 * M_PI * ratio * ratio);
    double sum = 0;
    for (int i = -4; i <= 4; i++)
        for (int j = -4; j <= 4; j++) {
            const double r = hypot(i, j), t = 1 - r / (2 * ratio);
            if ((i || j) && t > 0)
                sum += i * i * 5 * a * t * t * t / (ratio * ratio);
        }
    return sum;
}

typedef struct column_result {
    int steps;
    double time;
    double slope, surface;  /* fit p = surface + slope (H - y) of the averaged water pressure */
    double residual;        /* rms of the averaged pressure about the fit, Pa */
    double shift;           /* largest displacement of an interface row's mean height, m */
    int air_in_water, water_in_air;
    double energy, momentum; /* peaks of the kinetic energy (J/m), |vertical momentum| */
} column_result;

/* Runs the column for `duration` s; the pressure of every water particle is
 * averaged over the second half (every 20 steps, evaluated at the sampled
 * state) and fitted away from the walls and the surface (3 dx). */
static column_result run_column(int air, double duration, const char *extra)
{
    const double dx = 0.01, H = 0.15, width = 0.2;
    char *yaml = column_scene(air, NULL, extra);
    sluice_sim *sim = test_load(air ? "column-air" : "column-water", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_id max_id = 0;
    for (sluice_index i = 0; i < v->count; i++)
        max_id = v->id[i] > max_id ? v->id[i] : max_id;
    /* the interface rows: the top water row (1) and the bottom air row (2) */
    uint8_t *row = calloc(max_id + 1, 1);
    double *p_sum = calloc(max_id + 1, sizeof *p_sum), *y_sum = calloc(max_id + 1, sizeof *y_sum);
    ck_assert(row && p_sum && y_sum);
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        if (fabs(v->position[1][i] - (H - dx / 2)) < 1e-9)
            row[v->id[i]] = 1;
        if (fabs(v->position[1][i] - (H + dx / 2)) < 1e-9)
            row[v->id[i]] = 2;
    }
    column_result out = {0};
    int samples = 0;
    while (sluice_sim_time(sim) < duration) {
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        if (++out.steps % 20)
            continue;
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK); /* pressure at this state */
        v = sluice_sim_view(sim);
        const uint8_t *phase = air ? phase_column(sim) : NULL;
        const sluice_real *m = test_column(sim, "mass", 0);
        const sluice_real *u = test_column(sim, "velocity", 0);
        const sluice_real *w = test_column(sim, "velocity", 1);
        const sluice_real *p = test_column(sim, "pressure", 0);
        const int averaging = sluice_sim_time(sim) > duration / 2;
        double energy = 0, momentum = 0, rows[3] = {0, 0, 0};
        int count[3] = {0, 0, 0};
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_FLUID)
                continue;
            const double y = v->position[1][i];
            const int is_air = phase && phase[i];
            energy += 0.5 * m[i] * (u[i] * u[i] + w[i] * w[i]);
            momentum += m[i] * w[i];
            rows[row[v->id[i]]] += y;
            count[row[v->id[i]]]++;
            /* a full spacing across the interface is inside the other phase */
            out.air_in_water += is_air && y < H - dx;
            out.water_in_air += !is_air && y > H + dx;
            if (averaging && !is_air) {
                p_sum[v->id[i]] += p[i];
                y_sum[v->id[i]] += y;
            }
        }
        for (int r = 1; r <= 2; r++)
            if (count[r])
                out.shift = fmax(out.shift, fabs(rows[r] / count[r] -
                                                 (H + (r == 1 ? -1 : 1) * dx / 2)));
        out.energy = fmax(out.energy, energy);
        out.momentum = fmax(out.momentum, fabs(momentum));
        samples += averaging;
    }
    out.time = sluice_sim_time(sim);
    /* least-squares line through the averaged pressures */
    v = sluice_sim_view(sim);
    double sy = 0, sp = 0, syy = 0, syp = 0, spp = 0;
    int n = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const sluice_id id = v->id[i];
        if (v->kind[i] != SLUICE_KIND_FLUID || y_sum[id] == 0)
            continue;
        const double depth = H - y_sum[id] / samples, p = p_sum[id] / samples;
        const double x = v->position[0][i];
        if (x < 3 * dx || x > width - 3 * dx || depth > H - 3 * dx || depth < 3 * dx)
            continue;
        sy += depth;
        sp += p;
        syy += depth * depth;
        syp += depth * p;
        spp += p * p;
        n++;
    }
    ck_assert_int_ge(n, 100);
    out.slope = (n * syp - sy * sp) / (n * syy - sy * sy);
    out.surface = (sp - out.slope * sy) / n;
    const double variance = (spp - 2 * out.surface * sp - 2 * out.slope * syp +
                             n * out.surface * out.surface + 2 * out.surface * out.slope * sy +
                             out.slope * out.slope * syy) /
                            n;
    out.residual = sqrt(fmax(variance, 0));
    free(row);
    free(p_sum);
    free(y_sum);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    free(yaml);
    return out;
}

START_TEST(still_two_layer_column)
{
    const double dx = 0.01, H = 0.15, width = 0.2, c0 = 20, rho_w = 1000, pb = 100;
    const double M = lattice_moment(1.225), rho_g = rho_w * G, scale = rho_g * H;
    const column_result two = run_column(1, 0.15, ""), one = run_column(0, 0.15, "");
    /* the elastic energy of the start: the dbc walls begin at rest density
     * (pressure p_b) under water at p_b + rho g (H - y): at most the energy
     * of that pressure misfit over the water, (rho g H)^2 / (2 rho c0^2)
     * times its area */
    const double elastic = scale * scale / (2 * rho_w * c0 * c0) * width * H;
    const double mass_w = rho_w * width * H;
    const column_result *r[2] = {&one, &two};
    for (int k = 0; k < 2; k++)
        fprintf(stderr,
                "still column, %s: %d steps (%.3f s, dt %.3g s); averaged water pressure -dp/dy "
                "= %.1f Pa/m (rho g = %.1f, rho g / M = %.1f, M = %.4f), surface %+.1f Pa over "
                "p_b, rms about the line %.1f Pa (rho g H = %.1f Pa); interface rows moved <= "
                "%.2e m (%.3f dx); air in water %d, water in air %d; kinetic energy <= %.3g J/m "
                "(elastic start %.3g), |vertical momentum| <= %.3g kg/s (bound %.3g)\n",
                k ? "water under air" : "water alone", r[k]->steps, r[k]->time,
                r[k]->time / r[k]->steps, r[k]->slope, rho_g, rho_g / M, M,
                r[k]->surface - (k ? pb : 0), r[k]->residual, scale, r[k]->shift,
                r[k]->shift / dx, r[k]->air_in_water, r[k]->water_in_air, r[k]->energy, elastic,
                r[k]->momentum, sqrt(2 * mass_w * elastic));
    /* hydrostatics: between the continuum's rho g and the lattice's rho g / M
     * (1 / M - 1 = 3.7 %), with 1 % for the compression of the lattice
     * (rho g H / (gamma B) = 0.5 %) and the residual acoustic oscillation */
    ck_assert_msg(two.slope >= (1 - 0.01) * rho_g && two.slope <= (1 + 0.01) * rho_g / M,
                  "pressure gradient %.1f Pa/m outside [rho g, rho g / M]", two.slope);
    /* the air on top changes nothing in the water: the same gradient as the
     * water alone, within the residual oscillation (1 %) */
    ck_assert_msg(fabs(two.slope - one.slope) <= 0.01 * one.slope,
                  "pressure gradient %.1f Pa/m under air, %.1f alone", two.slope, one.slope);
    /* the surface pressure is the air's, p_b, within the pressure of one
     * particle row, rho g dx */
    ck_assert_msg(fabs(two.surface - pb) <= rho_g * dx, "surface pressure %.1f Pa, p_b = %g",
                  two.surface, pb);
    /* the interface: the column's compression g H^2 / (2 c0^2) = 0.03 dx
     * plus the wall settling; a tenth of a spacing is three times that */
    ck_assert_msg(two.shift <= 0.1 * dx, "interface rows moved by %g m", two.shift);
    ck_assert_int_eq(two.air_in_water, 0);
    ck_assert_int_eq(two.water_in_air, 0);
    ck_assert_msg(two.energy <= elastic, "kinetic energy %g J/m above the elastic start %g",
                  two.energy, elastic);
    /* |P| <= sqrt(2 M E) for any velocity field of energy E */
    ck_assert(two.momentum <= sqrt(2 * mass_w * elastic));
}
END_TEST

/* delta-SPH in two phases acts within each phase only (each with its own
 * c0 and hydrostatic correction): with it loaded the still column stays at
 * rest (kinetic energy below the elastic energy of the start), the
 * interface moves less than 0.1 dx, the surface pressure is p_b within
 * rho g dx, and no particle crosses into the other phase. Across the
 * interface (before it was phase-aware) the air reached 275 m/s within 500
 * steps. */
START_TEST(still_two_layer_column_with_delta_sph)
{
    const double dx = 0.01, H = 0.15, width = 0.2, c0 = 20, rho_w = 1000, pb = 100;
    const double rho_g = rho_w * G, scale = rho_g * H;
    const char *delta = "  delta_sph: {delta: 0.1}\n";
    const column_result two = run_column(1, 0.15, delta), one = run_column(0, 0.15, delta);
    const double elastic = scale * scale / (2 * rho_w * c0 * c0) * width * H;
    fprintf(stderr,
            "still column with delta-SPH: -dp/dy = %.1f Pa/m under air, %.1f Pa/m alone (rho g = "
            "%.1f); surface %+.1f Pa over p_b; interface moved %.3f dx; air in water %d, water in "
            "air %d; kinetic energy <= %.3g J/m (elastic start %.3g); %d steps\n",
            two.slope, one.slope, rho_g, two.surface - pb, two.shift / dx, two.air_in_water,
            two.water_in_air, two.energy, elastic, two.steps);
    /* stability and a sharp interface are asserted; the water's pressure
     * gradient under air is not: with delta-SPH it comes out 1.9 % steeper
     * than the water alone's (0.6 % without delta-SPH), which is not
     * understood yet (docs/validation.md) */
    ck_assert_msg(fabs(two.surface - pb) <= rho_g * dx, "surface pressure %.1f Pa", two.surface);
    ck_assert_msg(two.shift <= 0.1 * dx, "interface rows moved by %g m", two.shift);
    ck_assert_int_eq(two.air_in_water, 0);
    ck_assert_int_eq(two.water_in_air, 0);
    ck_assert_msg(two.energy <= elastic, "kinetic energy %g J/m above the elastic start %g",
                  two.energy, elastic);
}
END_TEST

/* ------------------------------------------------------ dam break in air -- */

/* Water column a = 0.1 m wide, 2a high (Martin & Moyce's n^2 = 2) at the
 * left of a 0.4 m tank closed by a lid at 0.3 m, air everywhere else. */
static char *dam_scene(int air)
{
    char *text = NULL;
    ck_assert_int_ge(
        asprintf(&text,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.01, smoothing_length_ratio: 1.225, rest_density: 1000}\n"
                 "time: {end: 0.15}\n"
                 "domain: {min: [-0.1, -0.1], max: [0.5, 0.45]}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [0.1, 0.2]}\n"
                 "%s"
                 "  walls:\n"
                 "    - {shape: tank, min: [0, 0], max: [0.4, 0.35], name: tank}\n"
                 "%s"
                 "initial: {density: hydrostatic}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "%s"
                 "  continuity: {form: volume}\n"
                 "  pressure_gradient: {form: density_product}\n"
                 "  artificial_viscosity: {alpha: 0.1}\n"
                 "  gravity: {}\n"
                 "  dbc: {}\n"
                 "  time_step: {}\n"
                 "  symplectic: {}\n",
                 air ? "    - {shape: box, min: [0, 0.2], max: [0.1, 0.3]}\n"
                       "    - {shape: box, min: [0.1, 0], max: [0.4, 0.3]}\n"
                     : "",
                 air ? "    - {shape: polyline, points: [[0.4, 0.3], [0, 0.3]], name: lid}\n" : "",
                 air ? "  two_phase: {speed_of_sound: 20, background_pressure: 100,"
                       " air_above: [[0, 0.2]], air_box_min: [[0.1, 0]],"
                       " air_box_max: [[0.4, 0.3]]}\n"
                     : "  tait: {speed_of_sound: 20}\n"),
        0);
    return text;
}

/* Fluid particles whose neighbours within 2h are at least three quarters of
 * the other phase: air entrained in the water, water broken into the air. */
static void count_isolated(sluice_sim *sim, int *air, int *water)
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_column(sim);
    const double reach2 = 4 * v->smoothing_length * v->smoothing_length;
    *air = *water = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        int same = 0, other = 0;
        for (sluice_index j = 0; j < v->count; j++) {
            if (j == i || v->kind[j] != SLUICE_KIND_FLUID)
                continue;
            const double dx = v->position[0][i] - v->position[0][j];
            const double dy = v->position[1][i] - v->position[1][j];
            if (dx * dx + dy * dy < reach2)
                phase[j] == phase[i] ? same++ : other++;
        }
        if (other > 0 && other >= 3 * same)
            phase[i] ? (*air)++ : (*water)++;
    }
}

/* The front: the largest x of a water particle, over a. */
static double front(sluice_sim *sim, int two_phase)
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = two_phase ? phase_column(sim) : NULL;
    double x = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && (!phase || !phase[i]))
            x = fmax(x, v->position[0][i]);
    return x / 0.1;
}

START_TEST(dam_break_in_air)
{
    const double a = 0.1, scale = sqrt(2 * G / a);
    const double T[] = {0.5, 1.0, 1.5, 2.0};
    double Z[2][4];
    int steps[2] = {0, 0}, worst_air = 0, worst_water = 0;
    for (int air = 0; air <= 1; air++) {
        char *yaml = dam_scene(air);
        sluice_sim *sim = test_load(air ? "dam-air" : "dam-water", yaml, NULL, 0);
        ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
        for (int k = 0; k < 4; k++) {
            while (sluice_sim_time(sim) * scale < T[k])
                ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
            Z[air][k] = front(sim, air);
            if (air) {
                int isolated_air, isolated_water;
                count_isolated(sim, &isolated_air, &isolated_water);
                worst_air = isolated_air > worst_air ? isolated_air : worst_air;
                worst_water = isolated_water > worst_water ? isolated_water : worst_water;
            }
        }
        steps[air] = (int)sluice_sim_steps(sim);
        ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
        sluice_sim_free(sim);
        free(yaml);
    }
    for (int k = 0; k < 4; k++)
        fprintf(stderr, "dam break T = %.1f: front Z = %.3f in air, %.3f water alone (%+.1f %%)\n",
                T[k], Z[1][k], Z[0][k], 100 * (Z[1][k] - Z[0][k]) / (Z[0][k] - 0.95));
    fprintf(stderr, "dam break: %d steps in air, %d alone (dt ratio %.1f); entrained air %d, "
                    "detached water %d particles at most\n",
            steps[1], steps[0], (double)steps[1] / steps[0], worst_air, worst_water);
    /* the air's inertia is 1e-3 of the water's: the front's travel matches
     * the water alone within the scatter of two runs at this resolution */
    for (int k = 1; k < 4; k++)
        ck_assert_msg(fabs(Z[1][k] - Z[0][k]) <= 0.1 * (Z[0][k] - 0.95),
                      "T = %.1f: front %.3f in air against %.3f", T[k], Z[1][k], Z[0][k]);
    ck_assert_int_eq(worst_air, 0);
    ck_assert_int_eq(worst_water, 0);
}
END_TEST

/* -------------------------------------------------------------- cohesion -- */

static uint64_t rng = 7;
static double uniform(void)
{
    rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

/* (dW/dr)/r of Wendland C2 and of the cubic B-spline with smoothing length H
 * (2D), independent of the plugin. */
static double gradient_factor(int cubic, double r, double H)
{
    const double q = r / H;
    if (q >= 2)
        return 0;
    if (!cubic) {
        const double t = 1 - q / 2;
        return -5 * 7 / (4 * M_PI * H * H) * t * t * t / (H * H);
    }
    const double a = 10 / (7 * M_PI * H * H);
    return q < 1 ? a / (H * H) * (-3 + 2.25 * q) : a / (H * H) * (-0.75 * (2 - q) * (2 - q) / q);
}

/* Only the cohesion accelerates: a_i = 2 a sum_{j air} m_j F_H(r_ij) r_ij
 * for air particles, 0 for water, against a brute-force sum on jittered
 * positions; total momentum of the pair force is zero to round-off. */
static void check_cohesion(double ratio, int cubic)
{
    const double coefficient = 150, h = 1.225 * 0.02, H = ratio * h;
    char extra[300];
    snprintf(extra, sizeof extra,
             "  air_cohesion: {coefficient: %g, smoothing_length_ratio: %g, kernel: %s}\n",
             coefficient, ratio, cubic ? "cubic_spline" : "wendland_c2");
    /* no gravity: the cohesion alone */
    char *edited = box_scene_without_gravity(
        "speed_of_sound: 28, background_pressure: 400, air_above: [[0, 0.1]]", extra, 0);
    sluice_sim *sim = test_load("cohesion", edited, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *x = (sluice_real *)v->position[0], *y = (sluice_real *)v->position[1];
    for (sluice_index i = 0; i < v->count; i++) {
        x[i] += (sluice_real)(0.004 * (uniform() - 0.5));
        y[i] += (sluice_real)(0.004 * (uniform() - 0.5));
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const uint8_t *phase = phase_column(sim);
    const sluice_real *m = test_column(sim, "mass", 0);
    const sluice_real *ax = test_column(sim, "acceleration", 0);
    const sluice_real *ay = test_column(sim, "acceleration", 1);
    double worst = 0, scale = 0, px = 0, py = 0, momentum_scale = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        double ex = 0, ey = 0;
        if (phase[i])
            for (sluice_index j = 0; j < v->count; j++) {
                if (j == i || !phase[j] || v->kind[j] != SLUICE_KIND_FLUID)
                    continue;
                const double rx = v->position[0][i] - v->position[0][j];
                const double ry = v->position[1][i] - v->position[1][j];
                const double F = gradient_factor(cubic, hypot(rx, ry), H);
                ex += 2 * coefficient * m[j] * F * rx;
                ey += 2 * coefficient * m[j] * F * ry;
            }
        worst = fmax(worst, fmax(fabs(ax[i] - ex), fabs(ay[i] - ey)));
        scale = fmax(scale, fmax(fabs(ex), fabs(ey)));
        px += m[i] * ax[i];
        py += m[i] * ay[i];
        momentum_scale += m[i] * (fabs(ax[i]) + fabs(ay[i]));
    }
    fprintf(stderr, "cohesion %s, H = %g h: |a - brute force| <= %.2e of %.3g m/s^2; sum m a = "
                    "(%.2e, %.2e) of sum m |a| = %.3g\n",
            cubic ? "cubic" : "wendland", ratio, worst / scale, scale, px, py, momentum_scale);
    ck_assert(scale > 0);
    ck_assert_msg(worst <= 1e-12 * scale, "cohesion off the brute-force sum by %g", worst);
    ck_assert(fabs(px) <= 1e-13 * momentum_scale && fabs(py) <= 1e-13 * momentum_scale);
    sluice_sim_free(sim);
    free(edited);
}

START_TEST(cohesion_against_brute_force)
{
    check_cohesion(1.0, 0);
    check_cohesion(0.7, 0);
    check_cohesion(1.0, 1);
    /* Nugent & Posch's H = 2h: pairs up to 4h, beyond the kernel support */
    check_cohesion(2.0, 0);
    check_cohesion(2.0, 1);
}
END_TEST

/* air_cohesion_held against air_cohesion on the same jittered two-layer
 * box (no gravity: the pressure and the cohesion move it), Verlet with a
 * fixed step (max_step below every stability limit): the positions after
 * `steps` steps by particle id. `rng` is reset so that every run starts
 * from the same jitter. */
static double *run_cohesion(const char *cohesion, int steps, sluice_sim **out)
{
    char extra[512];
    snprintf(extra, sizeof extra,
             "  continuity: {form: volume}\n"
             "  pressure_gradient: {form: density_product}\n"
             "  time_step: {}\n"
             "%s",
             cohesion);
    char *edited = box_scene_without_gravity(
        "speed_of_sound: 28, background_pressure: 400, air_above: [[0, 0.1]]", extra, 1);
    sluice_sim *sim = test_load("cohesion-held", edited, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *x = (sluice_real *)v->position[0], *y = (sluice_real *)v->position[1];
    rng = 12345;
    for (sluice_index i = 0; i < v->count; i++) {
        x[i] += (sluice_real)(0.004 * (uniform() - 0.5));
        y[i] += (sluice_real)(0.004 * (uniform() - 0.5));
    }
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    for (int k = 0; k < steps; k++)
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "%s", sluice_sim_failure(sim));
    v = sluice_sim_view(sim);
    double *at = calloc(2 * (size_t)v->count, sizeof *at);
    ck_assert_ptr_nonnull(at);
    for (sluice_index i = 0; i < v->count; i++) {
        ck_assert(v->id[i] < v->count);
        at[2 * v->id[i]] = v->position[0][i];
        at[2 * v->id[i] + 1] = v->position[1][i];
    }
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    *out = sim;
    free(edited);
    return at;
}

static double largest_difference(const double *a, const double *b, sluice_index n)
{
    double worst = 0;
    for (size_t k = 0; k < 2 * (size_t)n; k++)
        worst = fmax(worst, fabs(a[k] - b[k]));
    return worst;
}

/* air_cohesion_held:
 *  - update_every 1 is air_cohesion with a one-evaluation integrator: the
 *    positions after 60 Verlet steps agree to round-off (the held
 *    acceleration is added after the other terms' sums, in another order);
 *  - held for N steps, the force lags by (k mod N) dt at step k, (N - 1)
 *    dt / 2 on average: the position difference from the every-step run
 *    after a fixed time is first order in the lag, at most (N - 1) times
 *    that of N = 2 (10 % allowed for the second-order part), and less when
 *    the hold spans the air's acoustic period dx / c0_a (5 steps here),
 *    whose oscillation the held force averages; it grows with N;
 *  - between updates the held field does not change, and it is zero in the
 *    water. */
START_TEST(cohesion_held_against_every_step)
{
    const int steps = 60;
    const char *every = "  air_cohesion: {coefficient: 150, smoothing_length_ratio: 2}\n";
    sluice_sim *reference_sim = NULL, *sim = NULL;
    double *reference = run_cohesion(every, steps, &reference_sim);
    const sluice_index n = sluice_sim_view(reference_sim)->count;
    double *moved = NULL;
    {
        /* the scale: how far the particles moved */
        sluice_sim *still = NULL;
        moved = run_cohesion(every, 0, &still);
        sluice_sim_free(still);
    }
    const double displacement = largest_difference(reference, moved, n);
    double errors[4] = {0, 0, 0, 0};
    const int holds[4] = {1, 2, 4, 8};
    for (int k = 0; k < 4; k++) {
        char line[160];
        snprintf(line, sizeof line,
                 "  air_cohesion_held: {coefficient: 150, smoothing_length_ratio: 2, "
                 "update_every: %d}\n",
                 holds[k]);
        double *held = run_cohesion(line, steps, &sim);
        errors[k] = largest_difference(reference, held, n);
        if (holds[k] == 8) {
            /* 60 steps: the last update was at step 56; two more steps leave
             * the held field as it is */
            sluice_field f;
            ck_assert_int_eq(sluice_sim_field(sim, "cohesion_acceleration", &f), SLUICE_OK);
            const sluice_view *v = sluice_sim_view(sim);
            const uint8_t *phase = phase_column(sim);
            double *before = malloc(2 * (size_t)v->count * sizeof *before);
            ck_assert_ptr_nonnull(before);
            for (sluice_index i = 0; i < v->count; i++) {
                before[2 * v->id[i]] = sluice_real_column(v, f, 0)[i];
                before[2 * v->id[i] + 1] = sluice_real_column(v, f, 1)[i];
                if (!phase[i])
                    ck_assert(sluice_real_column(v, f, 0)[i] == 0 &&
                              sluice_real_column(v, f, 1)[i] == 0);
            }
            ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
            ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
            ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
            v = sluice_sim_view(sim);
            double nonzero = 0;
            for (sluice_index i = 0; i < v->count; i++) {
                ck_assert(before[2 * v->id[i]] == sluice_real_column(v, f, 0)[i]);
                ck_assert(before[2 * v->id[i] + 1] == sluice_real_column(v, f, 1)[i]);
                nonzero = fmax(nonzero, fabs(sluice_real_column(v, f, 1)[i]));
            }
            ck_assert(nonzero > 0);
            ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
            free(before);
        }
        free(held);
        sluice_sim_free(sim);
    }
    fprintf(stderr,
            "cohesion held: %u particles moved up to %.3g m in %d steps; position difference "
            "from every step: N = 1 %.3g m, 2 %.3g, 4 %.3g, 8 %.3g (ratios %.3f, %.3f)\n",
            n, displacement, steps, errors[0], errors[1], errors[2], errors[3],
            errors[2] / errors[1], errors[3] / errors[2]);
    ck_assert(displacement > 1e-6);
    ck_assert_msg(errors[0] <= 1e-12 * displacement, "update_every 1 differs by %g m", errors[0]);
    ck_assert(errors[1] > 1e-9 * displacement);
    ck_assert(errors[1] < errors[2] && errors[2] < errors[3]);
    for (int k = 2; k < 4; k++)
        ck_assert_msg(errors[k] <= 1.1 * (holds[k] - 1) * errors[1],
                      "N = %d: %g m, more than first order (%g m from N = 2)", holds[k],
                      errors[k], (holds[k] - 1) * errors[1]);
    sluice_sim_free(reference_sim);
    free(reference);
    free(moved);
}
END_TEST

/* xsph and artificial_viscosity with `phases: same`: the water moving
 * uniformly at U over air at rest (no gravity, jittered positions, only the
 * term under test). Between particles of one phase the velocity is uniform,
 * so with `same` the XSPH correction and the artificial viscosity vanish
 * everywhere, exactly; with `all` the particles at the interface feel the
 * other phase (nonzero), and the pair terms still conserve momentum. */
static void check_phases(const char *term, const char *field)
{
    double largest[2] = {0, 0};
    for (int same = 0; same < 2; same++) {
        char extra[200];
        snprintf(extra, sizeof extra, "  %s: {phases: %s%s}\n", term, same ? "same" : "all",
                 strcmp(term, "artificial_viscosity") == 0 ? ", time_step_limit: false" : "");
        char *edited = box_scene_without_gravity(
            "speed_of_sound: 28, background_pressure: 400, air_above: [[0, 0.1]]", extra, 0);
        sluice_sim *sim = test_load("phases", edited, NULL, 0);
        const sluice_view *v = sluice_sim_view(sim);
        sluice_real *x = (sluice_real *)v->position[0], *y = (sluice_real *)v->position[1];
        rng = 99;
        for (sluice_index i = 0; i < v->count; i++) {
            x[i] += (sluice_real)(0.004 * (uniform() - 0.5));
            y[i] += (sluice_real)(0.004 * (uniform() - 0.5));
        }
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK); /* settles the order */
        v = sluice_sim_view(sim);
        const uint8_t *phase = phase_column(sim);
        sluice_real *u = test_column(sim, "velocity", 0), *w = test_column(sim, "velocity", 1);
        for (sluice_index i = 0; i < v->count; i++) {
            u[i] = phase[i] ? 0 : (sluice_real)0.7;
            w[i] = phase[i] ? 0 : (sluice_real)-0.2;
        }
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        v = sluice_sim_view(sim);
        const sluice_real *fx = test_column(sim, field, 0), *fy = test_column(sim, field, 1);
        const sluice_real *m = test_column(sim, "mass", 0);
        double px = 0, py = 0, scale = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            largest[same] = fmax(largest[same], fmax(fabs(fx[i]), fabs(fy[i])));
            px += m[i] * fx[i];
            py += m[i] * fy[i];
            scale += m[i] * (fabs(fx[i]) + fabs(fy[i]));
        }
        fprintf(stderr, "%s, phases %s: largest |%s| %.3g, sum m %s = (%.2e, %.2e) of %.3g\n",
                term, same ? "same" : "all", field, largest[same], field, px, py, scale);
        if (!same)
            ck_assert(fabs(px) <= 1e-13 * scale && fabs(py) <= 1e-13 * scale);
        sluice_sim_free(sim);
        free(edited);
    }
    ck_assert_msg(largest[0] > 0, "%s: with phases all the interface feels nothing", term);
    ck_assert_msg(largest[1] == 0, "%s: with phases same |%s| reaches %g", term, field,
                  largest[1]);
}

START_TEST(xsph_and_viscosity_within_each_phase)
{
    check_phases("xsph", "transport_velocity_correction");
    check_phases("artificial_viscosity", "acceleration");
    /* `same` without the phases */
    test_load_refused("phases-without-two-phase",
                      "dimensions: 2\n"
                      "particles: {spacing: 0.02, smoothing_length_ratio: 1.225}\n"
                      "time: {end: 1.0, max_step: 1e-4}\n"
                      "domain: {min: [-0.1, -0.1], max: [0.3, 0.3]}\n"
                      "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.2, 0.1]}]}\n"
                      "plugins: {wendland_c2: {}, tait: {speed_of_sound: 20}, "
                      "xsph: {phases: same}, symplectic: {}}\n",
                      "phases: same needs the field 'phase'");
}
END_TEST

START_TEST(cohesion_refusals)
{
    char *yaml = box_scene("speed_of_sound: 28, background_pressure: 400, air_above: [[0, 0.1]]",
                           "  air_cohesion: {coefficient: 400, smoothing_length_ratio: 1}\n");
    test_load_refused("cohesion-pressure", yaml, "is not below the background pressure");
    free(yaml);
    /* the transport velocity's p_b counts with the equation of state's:
     * a rho0_a^2 = 475 Pa is below 400 + 100 Pa, not below 0 + 400 Pa */
    yaml = box_scene("speed_of_sound: 28, background_pressure: 400, air_above: [[0, 0.1]]",
                     "  air_cohesion: {coefficient: 400, smoothing_length_ratio: 1}\n"
                     "  transport_velocity: {background_pressure: 100}\n");
    sluice_sim *sim = test_load("cohesion-pressure-transport", yaml, NULL, 0);
    sluice_sim_free(sim);
    free(yaml);
    yaml = box_scene("speed_of_sound: 28, background_pressure: 0, air_above: [[0, 0.1]]",
                     "  air_cohesion: {coefficient: 400, smoothing_length_ratio: 1}\n"
                     "  transport_velocity: {background_pressure: 400}\n");
    test_load_refused("cohesion-pressure-transport-low", yaml,
                      "is not below the background pressure");
    free(yaml);
}
END_TEST

/* ------------------------------------------------------------- restart -- */

START_TEST(phase_survives_a_restart)
{
    char *yaml = box_scene("speed_of_sound: 28, background_pressure: 300,"
                           " air_above: [[0, 0.1]], air_box_min: [[0, 0]],"
                           " air_box_max: [[0.05, 0.05]]",
                           "  continuity: {form: volume}\n"
                           "  pressure_gradient: {form: density_product}\n"
                           "  time_step: {}\n");
    sluice_sim *sim = test_load("restart", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    for (int s = 0; s < 5; s++)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    char *dir = test_scratch("restart-file");
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/checkpoint.h5", dir), 0);
    ck_assert_int_eq(sluice_sim_checkpoint(sim, path), SLUICE_OK);
    sluice_sim *again = test_load("restart", yaml, NULL, 0);
    char error[512] = "";
    ck_assert_msg(sluice_sim_restart(again, path, error, sizeof error) == SLUICE_OK, "%s", error);
    const sluice_view *a = sluice_sim_view(sim), *b = sluice_sim_view(again);
    ck_assert_uint_eq(a->count, b->count);
    const uint8_t *pa = phase_column(sim), *pb = phase_column(again);
    const sluice_real *ma = test_column(sim, "mass", 0), *mb = test_column(again, "mass", 0);
    int air = 0;
    for (sluice_index i = 0; i < a->count; i++) {
        ck_assert(a->id[i] == b->id[i]);
        ck_assert_int_eq(pa[i], pb[i]);
        ck_assert(ma[i] == mb[i]);
        air += pa[i];
    }
    fprintf(stderr, "restart: %d air particles keep their phase and mass\n", air);
    ck_assert_int_gt(air, 0);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    sluice_sim_free(again);
    free(path);
    free(dir);
    free(yaml);
}
END_TEST

/* ----------------------------------------------------------- bad input -- */

START_TEST(bad_input)
{
    static const struct {
        const char *tag, *settings, *extra, *needle;
    } cases[] = {
        {"negative-density", "speed_of_sound: 28, background_pressure: 1, air_rest_density: -1,"
                             " air_above: [[0, 0.1]]",
         NULL, "air_rest_density"},
        {"heavy-air", "speed_of_sound: 28, background_pressure: 1, air_rest_density: 2000,"
                      " air_above: [[0, 0.1]]",
         NULL, "is not below the water's rest density"},
        {"no-air", "speed_of_sound: 28, background_pressure: 1", NULL, "no air is described"},
        {"unknown-key", "speed_of_sound: 28, background_pressure: 1, air_levl: 0.1", NULL,
         "air_levl"},
        {"no-background", "speed_of_sound: 28, air_above: [[0, 0.1]]", NULL,
         "background_pressure"},
        {"negative-background", "speed_of_sound: 28, background_pressure: -5,"
                                " air_above: [[0, 0.1]]",
         NULL, "background_pressure"},
        {"box-count", "speed_of_sound: 28, background_pressure: 1, air_box_min: [[0, 0]],"
                      " air_box_max: [[0.1, 0.1], [0.2, 0.2]]",
         NULL, "give one of each per box"},
        {"box-inside-out", "speed_of_sound: 28, background_pressure: 1,"
                           " air_box_min: [[0.1, 0]], air_box_max: [[0.05, 0.1]]",
         NULL, "is not below air_box_max"},
        {"polygon-two-points", "speed_of_sound: 28, background_pressure: 1,"
                               " air_polygon: [[0, 0], [0.1, 0.1]]",
         NULL, "a polygon needs at least 3"},
        {"polyline-backwards", "speed_of_sound: 28, background_pressure: 1,"
                               " air_above: [[0.2, 0.1], [0, 0.1]]",
         NULL, "must increase"},
        {"selects-nothing", "speed_of_sound: 28, background_pressure: 1,"
                            " air_above: [[0, 0.5]]",
         NULL, "selects none of the"},
        {"two-pressure-writers", "speed_of_sound: 28, background_pressure: 1,"
                                 " air_above: [[0, 0.1]]",
         "  tait: {speed_of_sound: 28}\n", "load only one of them"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char *yaml = box_scene(cases[k].settings, cases[k].extra);
        test_load_refused(cases[k].tag, yaml, cases[k].needle);
        free(yaml);
    }
    /* cohesion without the phases */
    char *yaml = NULL;
    ck_assert_int_ge(asprintf(&yaml,
                              "dimensions: 2\n"
                              "particles: {spacing: 0.02}\n"
                              "time: {end: 1.0, max_step: 1e-5}\n"
                              "domain: {min: [-0.1, -0.1], max: [0.3, 0.3]}\n"
                              "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.2, 0.1]}]}\n"
                              "plugins:\n"
                              "  wendland_c2: {}\n"
                              "  tait: {speed_of_sound: 28}\n"
                              "  air_cohesion: {coefficient: 1, smoothing_length_ratio: 1}\n"
                              "  symplectic: {}\n"),
                     0);
    test_load_refused("cohesion-alone", yaml, "load two_phase");
    free(yaml);
}
END_TEST

/* --------------------------------------------------- unresolved bubbles -- */

/* The still column of run_column (water 0.15 m deep under air, dx = 0.01)
 * with a lone air particle at (0.055, 0.055) and a pocket of two side by
 * side at (0.135, 0.055) and (0.145, 0.055), all deep in the water. */
static char *bubble_scene(double lifetime)
{
    char extra[128];
    snprintf(extra, sizeof extra,
             "  unresolved_bubbles: {lifetime: %g, check_every: 10, interval: 0.005}\n", lifetime);
    return column_scene(1,
                        "  two_phase: {speed_of_sound: 20, background_pressure: 2000,"
                        " air_above: [[0, 0.15]], air_box_min: [[0.05, 0.05], [0.13, 0.05]],"
                        " air_box_max: [[0.06, 0.06], [0.15, 0.06]]}\n",
                        extra);
}

static int find_id(const sluice_view *v, sluice_id id, sluice_index *at)
{
    for (sluice_index i = 0; i < v->count; i++)
        if (v->id[i] == id) {
            *at = i;
            return 1;
        }
    return 0;
}

/* The last row of a run's unresolved_bubbles.csv: its first n columns */
static void bubbles_last_row(const char *dir, double *row, int n)
{
    char *csv = NULL;
    ck_assert_int_ge(asprintf(&csv, "%s/unresolved_bubbles.csv", dir), 0);
    char *text = test_read_file(csv);
    ck_assert_ptr_nonnull(text);
    const char *last = text, *line = text;
    while ((line = strchr(line, '\n')) && line[1])
        last = ++line;
    for (int k = 0; k < n; k++) {
        char *end;
        row[k] = strtod(last, &end);
        ck_assert_msg(end != last && (k == n - 1 || *end == ','), "%s: column %d of the last row",
                      csv, k);
        last = end + 1;
    }
    free(text);
    free(csv);
}

/* The lone particle leaves once its isolation time reaches the lifetime
 * (between the lifetime and the lifetime plus one check's span, 10 steps);
 * until then its isolation time is the time elapsed, to within a check's
 * span; the pocket and the air above, which have air neighbours, stay at 0
 * and stay in the domain; the table counts the lone particle's mass,
 * rho0_a dx^2, exactly; a run restarted from a checkpoint before the
 * removal removes it at the same step with the same table. */
START_TEST(unresolved_bubble_leaves_after_its_lifetime)
{
    const double dx = 0.01, lifetime = 0.01, rho_a = 1.09, end = 0.02;
    char *yaml = bubble_scene(lifetime);
    sluice_sim *sim = test_load("bubbles", yaml, NULL, 0);
    char *dir = test_scratch("bubbles-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_column(sim);
    sluice_id lone = 0, pocket[2] = {0, 0};
    long air_start = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID || !phase[i])
            continue;
        air_start++;
        const double x = v->position[0][i], y = v->position[1][i];
        if (fabs(x - 0.055) < 1e-9 && fabs(y - 0.055) < 1e-9)
            lone = v->id[i];
        if (fabs(y - 0.055) < 1e-9 && fabs(x - 0.135) < 1e-9)
            pocket[0] = v->id[i];
        if (fabs(y - 0.055) < 1e-9 && fabs(x - 0.145) < 1e-9)
            pocket[1] = v->id[i];
    }
    ck_assert(lone && pocket[0] && pocket[1]);
    char *checkpoint = NULL;
    ck_assert_int_ge(asprintf(&checkpoint, "%s/checkpoint.h5", dir), 0);
    double removed_at = -1, largest_lag = 0, span = 0;
    int64_t removed_step = -1, checkpoint_step = -1;
    int status;
    while ((status = sluice_sim_step(sim)) == SLUICE_RUN_COMPLETE &&
           sluice_sim_time(sim) < end - 1e-12) {
        v = sluice_sim_view(sim);
        phase = phase_column(sim);
        const sluice_real *isolation = test_column(sim, "isolation_time", 0);
        const double t = sluice_sim_time(sim);
        span = fmax(span, 10 * v->dt);
        sluice_index at;
        const int present = find_id(v, lone, &at);
        if (removed_at < 0 && !present) {
            removed_at = t;
            removed_step = sluice_sim_steps(sim);
        }
        if (present && sluice_sim_steps(sim) % 10 == 0)
            largest_lag = fmax(largest_lag, fabs(t - isolation[at]));
        if (present)
            ck_assert_msg(isolation[at] <= t + 1e-12, "isolation %g s at t = %g s",
                          (double)isolation[at], t);
        for (int k = 0; k < 2; k++) {
            ck_assert_msg(find_id(v, pocket[k], &at), "pocket particle %d removed at t = %g s",
                          k, t);
            ck_assert_msg(isolation[at] == 0, "pocket particle %d isolated for %g s", k,
                          (double)isolation[at]);
        }
        for (sluice_index i = 0; i < v->count; i++)
            if (v->position[1][i] > 0.15 && phase[i] && isolation[i] != 0)
                ck_abort_msg("air above the water isolated for %g s at (%g, %g)",
                             (double)isolation[i], (double)v->position[0][i],
                             (double)v->position[1][i]);
        if (checkpoint_step < 0 && t > 0.5 * lifetime) {
            ck_assert_int_eq(sluice_sim_checkpoint(sim, checkpoint), SLUICE_OK);
            checkpoint_step = sluice_sim_steps(sim);
        }
    }
    ck_assert_msg(status == SLUICE_RUN_COMPLETE, "stopped: %s", sluice_sim_failure(sim));
    v = sluice_sim_view(sim);
    phase = phase_column(sim);
    long air_end = 0;
    for (sluice_index i = 0; i < v->count; i++)
        air_end += v->kind[i] == SLUICE_KIND_FLUID && phase[i];
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    fprintf(stderr,
            "unresolved bubble: removed at t = %.6g s (lifetime %g s, check span %.3g s); "
            "isolation time within %.3g s of t before; air %ld -> %ld\n",
            removed_at, lifetime, span, largest_lag, air_start, air_end);
    ck_assert_msg(removed_at >= lifetime - 1e-12 && removed_at <= lifetime + span + 1e-12,
                  "removed at %g s", removed_at);
    ck_assert_msg(largest_lag <= span * (1 + 1e-9), "isolation time lags %g s", largest_lag);
    ck_assert_int_eq(air_end, air_start - 1);
    /* the table: one particle, its mass and volume */
    double row[6];
    bubbles_last_row(dir, row, 6);
    ck_assert_msg(fabs(row[2] - rho_a * dx * dx) < 1e-12 * rho_a * dx * dx, "mass %g", row[2]);
    ck_assert_msg(fabs(row[3] - dx * dx) < 1e-12 * dx * dx, "volume %g", row[3]);
    ck_assert(row[4] == 1);
    /* restarted from the checkpoint: the same step, the same table */
    sluice_sim *again = test_load("bubbles", yaml, NULL, 0);
    char error[512] = "";
    ck_assert_msg(sluice_sim_restart(again, checkpoint, error, sizeof error) == SLUICE_OK, "%s",
                  error);
    char *dir2 = test_scratch("bubbles-restart");
    ck_assert_int_eq(sluice_sim_begin(again, dir2), SLUICE_RUN_COMPLETE);
    int64_t removed_again = -1;
    while ((status = sluice_sim_step(again)) == SLUICE_RUN_COMPLETE &&
           sluice_sim_time(again) < end - 1e-12) {
        sluice_index at;
        if (removed_again < 0 && !find_id(sluice_sim_view(again), lone, &at))
            removed_again = sluice_sim_steps(again);
    }
    ck_assert_int_eq(status, SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_end(again, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    fprintf(stderr, "restarted at step %lld: removed at step %lld (continuous run %lld)\n",
            (long long)checkpoint_step, (long long)removed_again, (long long)removed_step);
    ck_assert_int_eq(removed_again, removed_step);
    sluice_sim_free(again);
    sluice_sim_free(sim);
    free(checkpoint);
    free(dir);
    free(dir2);
    free(yaml);
}
END_TEST

/* max_compression: the scene above, whose three air particles 0.095 m deep
 * start at rho0_a; the water around them presses them toward their
 * hydrostatic density rho0_a (1 + rho0 g 0.095 / B)^(1/1.4) = 1.0116 rho0_a
 * (B = rho0 c0^2 / 7 = 57143 Pa) within a few steps (dx / c0_a = 4e-5 s),
 * while the air above the water stays within 2e-5 of rho0_a. With c = 0.002
 * the three leave within 0.005 s (less than the lifetime, 0.01 s), counted
 * in particles_compressed_total and in the mass removed (3 rho0_a dx^2), and
 * no other air does; with c = 0.05, above the compression the water can
 * cause even with an overshoot of 100 %, none leaves. */
static void run_compression(double c, long expected_removed)
{
    const double dx = 0.01, rho_a = 1.09, depth = 0.15 - 0.055;
    char extra[160];
    snprintf(extra, sizeof extra,
             "  unresolved_bubbles: {lifetime: 0.01, check_every: 10, interval: 0.001, "
             "max_compression: %g}\n",
             c);
    char *yaml = column_scene(1,
                              "  two_phase: {speed_of_sound: 20, background_pressure: 2000,"
                              " air_above: [[0, 0.15]], air_box_min: [[0.05, 0.05], [0.13, 0.05]],"
                              " air_box_max: [[0.06, 0.06], [0.15, 0.06]]}\n",
                              extra);
    sluice_sim *sim = test_load("compressed-bubbles", yaml, NULL, 0);
    char *dir = test_scratch("compressed-bubbles-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_column(sim);
    const sluice_real *rho = test_column(sim, "density", 0);
    const double B = 1000.0 * 20 * 20 / 7, deep = rho_a * pow(1 + 1000 * 9.81 * depth / B, 1 / 1.4);
    long air_start = 0, deep_count = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID || !phase[i])
            continue;
        air_start++;
        if (v->position[1][i] < 0.15) {
            deep_count++;
            ck_assert_msg(fabs(rho[i] - rho_a) < 1e-4 * rho_a, "deep air at %g kg/m^3 at the start",
                          (double)rho[i]);
        } else {
            ck_assert_msg(fabs(rho[i] - rho_a) < 2e-5 * rho_a, "air above at %g kg/m^3",
                          (double)rho[i]);
        }
    }
    ck_assert_int_eq(deep_count, 3);
    double densest = 0; /* the deep air's largest density while it is there */
    while (sluice_sim_time(sim) < 0.005 - 1e-12) {
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        v = sluice_sim_view(sim);
        phase = phase_column(sim);
        rho = test_column(sim, "density", 0);
        for (sluice_index i = 0; i < v->count; i++)
            if (v->kind[i] == SLUICE_KIND_FLUID && phase[i] && v->position[1][i] < 0.13)
                densest = fmax(densest, (double)rho[i] / rho_a);
    }
    v = sluice_sim_view(sim);
    phase = phase_column(sim);
    long air_end = 0;
    for (sluice_index i = 0; i < v->count; i++)
        air_end += v->kind[i] == SLUICE_KIND_FLUID && phase[i];
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    double row[7];
    bubbles_last_row(dir, row, 7);
    fprintf(stderr,
            "max_compression %g: deep air hydrostatic at %.6g rho0_a, densest %.6g rho0_a "
            "(after the step); air %ld -> %ld; table: %g compressed, %g kg/m removed\n",
            c, deep / rho_a, densest, air_start, air_end, row[6], row[2]);
    ck_assert_int_eq(air_end, air_start - expected_removed);
    ck_assert_msg(densest <= 1 + c, "air at %g rho0_a stayed", densest);
    ck_assert(row[6] == (double)expected_removed && row[4] == (double)expected_removed);
    ck_assert_msg(fabs(row[2] - (double)expected_removed * rho_a * dx * dx) <= 1e-12 * rho_a * dx * dx,
                  "mass removed %g", row[2]);
    sluice_sim_free(sim);
    free(dir);
    free(yaml);
}

START_TEST(compressed_air_leaves)
{
    run_compression(0.002, 3);
    run_compression(0.05, 0);
}
END_TEST

/* unresolved_bubbles without two_phase: refused, naming what to load. */
START_TEST(unresolved_bubbles_need_two_phase)
{
    char *yaml = NULL;
    ck_assert_int_ge(
        asprintf(&yaml, "dimensions: 2\n"
                        "particles: {spacing: 0.02, smoothing_length_ratio: 1.225}\n"
                        "time: {end: 0.1, max_step: 1e-4}\n"
                        "domain: {min: [-0.1, -0.1], max: [0.3, 0.3]}\n"
                        "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.2, 0.1]}]}\n"
                        "plugins:\n"
                        "  wendland_c2: {}\n"
                        "  tait: {speed_of_sound: 20}\n"
                        "  gravity: {}\n"
                        "  symplectic: {}\n"
                        "  unresolved_bubbles: {}\n"),
        0);
    test_load_refused("bubbles-alone", yaml, "two_phase");
    free(yaml);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("two_phase");
    TCase *eos = tcase_create("equation_of_state");
    tcase_add_test(eos, air_speed_of_sound_from_one_B);
    tcase_add_test(eos, equation_of_state_values);
    tcase_add_test(eos, initial_phases_masses_and_pressure);
    suite_add_tcase(s, eos);
    /* tag `long`: thousands of steps of the two-phase pair terms that the
     * bubble cases below and the spillway scenes' short runs reach too; left
     * out of the sanitizer pass of tools/run-tests.sh */
    TCase *flow = tcase_create("flow");
    tcase_set_tags(flow, "long");
    tcase_set_timeout(flow, 300);
    tcase_add_test(flow, still_two_layer_column);
    suite_add_tcase(s, flow);
    /* the still column again with the phase-aware delta-SPH (which the
     * spillway scenes' short runs also load), and the dam break in air and
     * in vacuum to t sqrt(2g/a) = 2: each two runs of thousands of steps */
    TCase *long_flow = tcase_create("flow_long");
    tcase_set_tags(long_flow, "validation"); /* release pass only */
    tcase_set_timeout(long_flow, 300);
    tcase_add_test(long_flow, still_two_layer_column_with_delta_sph);
    tcase_add_test(long_flow, dam_break_in_air);
    suite_add_tcase(s, long_flow);
    TCase *cohesion = tcase_create("cohesion");
    tcase_add_test(cohesion, cohesion_against_brute_force);
    tcase_add_test(cohesion, cohesion_refusals);
    tcase_add_test(cohesion, cohesion_held_against_every_step);
    tcase_add_test(cohesion, xsph_and_viscosity_within_each_phase);
    suite_add_tcase(s, cohesion);
    TCase *bubbles = tcase_create("bubbles");
    tcase_set_timeout(bubbles, 300);
    tcase_add_test(bubbles, unresolved_bubble_leaves_after_its_lifetime);
    tcase_add_test(bubbles, compressed_air_leaves);
    suite_add_tcase(s, bubbles);
    TCase *input = tcase_create("input");
    tcase_add_test(input, phase_survives_a_restart);
    tcase_add_test(input, unresolved_bubbles_need_two_phase);
    tcase_add_test(input, bad_input);
    suite_add_tcase(s, input);
    return test_run_suite(s);
}
