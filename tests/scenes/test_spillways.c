/* Seed 001's stepped-spillway scenes end to end, through the plugin sets of
 * the full scenes (configs/stepped_chute_chanson.yaml,
 * configs/stepped_spillway_cheng.yaml), in their `reduced` variants run for
 * a few thousand steps (the CI's budget; the validations are long runs,
 * docs/validation.md), with the scenes' model (transport velocity) and with
 * seed 001's as published (variant seed_model at the reduced spacing and
 * length):
 *  - the run completes: two phases with one Tait B, the transport velocity
 *    or cohesion pairs reaching 2H = 4h, an inlet under a gate, a drain
 *    that takes the water only;
 *  - the particles balance exactly, phase by phase: the air's box is closed
 *    but for the air vent, so the air count never grows and the air now +
 *    the air the vent let out (mass_total of air_vent.csv, in whole
 *    particles of mass rho0_a dx^2, two_phase's rho0_a = 1.09 kg m^-3) +
 *    the unresolved bubbles taken out (particles_removed_total of
 *    unresolved_bubbles.csv) is the air at the start; the water now = the water at the start
 *    + the inlet's net inflow - the outlet's outflow, in whole particles of
 *    mass rho0 dx^2 (mass_total of inlet.csv and outlet.csv; in the CI's
 *    few thousand steps no inflow column has crossed yet: the crossings'
 *    accounting is tested in the suite open_boundaries);
 *  - no fluid lies upstream of the inlet's plane after any step (the inlet
 *    removes it within the inflow's section; above it the gate, a dbc wall,
 *    holds it within the watchdog's dx/2);
 *  - Cheng: dissolved oxygen stays within [Cu, Cs] in the water (diffusion
 *    with positive weights and the source's relaxation towards Cs, each
 *    stable at the plugin's time step, keep it there) and is 0 in the air;
 *    the water touching the air has gained oxygen (max C > Cu);
 *  - the single-phase variants load from the same files: no field `phase`,
 *    the water particles only, and they run. */
#include <math.h>

#include "sim_util.h"

/* Checks inside the per-particle loops call ck_abort_msg only on failure:
 * every ck_assert writes its location to Check's pipe, a system call per
 * particle and step. */
static sluice_sim *load_variant(const char *config, const char *variant,
                                const char *const *sets, size_t set_count)
{
    char *path = test_config(config);
    ck_assert_ptr_nonnull(path);
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {.overrides = sets, .override_count = set_count};
    sluice_sim *sim = sluice_sim_load_variant(path, variant, &options, diag);
    if (!sim)
        for (size_t i = 0; i < sluice_diag_count(diag); i++)
            fprintf(stderr, "%s\n", sluice_diag_message(diag, i));
    ck_assert_msg(sim != NULL, "%s --variant %s failed to load", config, variant);
    sluice_diag_destroy(diag);
    free(path);
    return sim;
}

typedef struct census {
    long water, air;
} census;

static census count_phases(sluice_sim *sim)
{
    sluice_field f;
    ck_assert_int_eq(sluice_sim_field(sim, "phase", &f), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = v->columns[f.column];
    census c = {0, 0};
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            phase[i] ? c.air++ : c.water++;
    return c;
}

static double last_value(const char *dir, const char *file, int column)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", dir, file), 0);
    FILE *f = fopen(path, "r");
    ck_assert_msg(f != NULL, "no %s", path);
    char line[4096];
    double value = NAN;
    while (fgets(line, sizeof line, f)) {
        if (line[0] < '0' || line[0] > '9')
            continue;
        char *p = line;
        for (int c = 0; c < column && p; c++) {
            p = strchr(p, ',');
            if (p)
                p++;
        }
        if (p)
            value = strtod(p, NULL);
    }
    fclose(f);
    free(path);
    return value;
}

/* Runs `config` --variant `variant` with `sets`; checks the balances after
 * every step; with `oxygen`, the concentration's bounds. */
static void run_reduced(const char *config, const char *variant, const char *tag,
                        const char *const *sets, size_t set_count, double dx, int oxygen)
{
    sluice_sim *sim = load_variant(config, variant, sets, set_count);
    char *dir = test_scratch(tag);
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const census start = count_phases(sim);
    ck_assert_int_gt(start.water, 0);
    ck_assert_int_gt(start.air, 0);
    const double cu = 1.29, cs = 10.48;
    double c_max = 0, c_min = INFINITY;
    int status;
    while ((status = sluice_sim_step(sim)) == SLUICE_RUN_COMPLETE &&
           sluice_sim_time(sim) < sluice_sim_end_time(sim) - 1e-12) {
        const census now = count_phases(sim);
        if (now.air > start.air)
            ck_abort_msg("air particles %ld, at the start %ld", now.air, start.air);
        const sluice_view *v = sluice_sim_view(sim);
        for (sluice_index i = 0; i < v->count; i++)
            if (!(v->kind[i] != SLUICE_KIND_FLUID || v->position[0][i] >= -dx / 2))
                ck_abort_msg("fluid at x = %g m, upstream of the inlet and the gate",
                             (double)v->position[0][i]);
        if (oxygen) {
            sluice_field f;
            ck_assert_int_eq(sluice_sim_field(sim, "phase", &f), SLUICE_OK);
            const uint8_t *phase = v->columns[f.column];
            const sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
            for (sluice_index i = 0; i < v->count; i++) {
                if (v->kind[i] != SLUICE_KIND_FLUID)
                    continue;
                if (phase[i]) {
                    if (c[i] != 0)
                        ck_abort_msg("air particle with C = %g", (double)c[i]);
                    continue;
                }
                if (!(c[i] >= cu - 1e-12 && c[i] <= cs + 1e-12))
                    ck_abort_msg("water particle with C = %.17g outside [Cu, Cs]", (double)c[i]);
                c_max = fmax(c_max, c[i]);
                c_min = fmin(c_min, c[i]);
            }
        }
    }
    ck_assert_msg(status == SLUICE_RUN_COMPLETE, "%s stopped: %s", tag, sluice_sim_failure(sim));
    const census final = count_phases(sim);
    const long long steps = (long long)sluice_sim_steps(sim);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    const double particle = 1000 * dx * dx;
    const double in = last_value(dir, "inlet.csv", 4) / particle;
    const double out = last_value(dir, "outlet.csv", 4) / particle;
    const double vented = last_value(dir, "air_vent.csv", 3) / (1.09 * dx * dx);
    const double bubbles = last_value(dir, "unresolved_bubbles.csv", 4);
    fprintf(stderr,
            "%s: %lld steps; water %ld -> %ld (inflow %.6g, outflow %.6g particles), air %ld -> "
            "%ld (%.6g vented, %.6g unresolved bubbles removed)",
            tag, steps, start.water, final.water, in, out, start.air, final.air, vented, bubbles);
    if (oxygen)
        fprintf(stderr, "; water C in [%.6g, %.6g] mg/L", c_min, c_max);
    fprintf(stderr, "\n");
    ck_assert_msg(fabs(in - nearbyint(in)) < 1e-6 && fabs(out - nearbyint(out)) < 1e-6,
                  "fluxes are not whole particles: %g in, %g out", in, out);
    ck_assert_msg(fabs(vented - nearbyint(vented)) < 1e-6, "the vent let out %.9g air particles",
                  vented);
    ck_assert_msg(bubbles >= 0 && bubbles == nearbyint(bubbles), "%g bubbles removed", bubbles);
    ck_assert_int_eq(final.air + llround(vented) + llround(bubbles), start.air);
    ck_assert_int_eq(final.water, start.water + llround(in) - llround(out));
    if (oxygen)
        ck_assert_msg(c_max > cu, "no reaeration anywhere: max C = %g", c_max);
    sluice_sim_free(sim);
    free(dir);
}

START_TEST(chanson_reduced)
{
    run_reduced("stepped_chute_chanson.yaml", "reduced", "chanson-reduced", NULL, 0, 0.02, 0);
}
END_TEST

START_TEST(cheng_reduced)
{
    run_reduced("stepped_spillway_cheng.yaml", "reduced", "cheng-reduced", NULL, 0, 0.0125, 1);
}
END_TEST

/* Seed 001's model as published (background pressure in the momentum
 * equation, the air's cohesion): the same balances at the reduced spacing
 * and length. */
START_TEST(chanson_seed_model_reduced)
{
    const char *const chanson[] = {"particles.spacing=0.02", "time.end=0.02"};
    run_reduced("stepped_chute_chanson.yaml", "seed_model", "chanson-seed-model", chanson, 2,
                0.02, 0);
}
END_TEST

START_TEST(cheng_seed_model_reduced)
{
    const char *const cheng[] = {"particles.spacing=0.0125", "time.end=0.008"};
    run_reduced("stepped_spillway_cheng.yaml", "seed_model", "cheng-seed-model", cheng, 2, 0.0125,
                1);
}
END_TEST

/* The single-phase variant: the same file without two_phase and the
 * transport velocity: no field phase, the water region only, and it runs. */
static void single_phase(const char *config, const char *spacing)
{
    const char *const sets[] = {spacing, "time.end=0.01"};
    sluice_sim *two = load_variant(config, "reduced", sets, 1);
    const census both = count_phases(two);
    sluice_sim_free(two);
    sluice_sim *sim = load_variant(config, "single_phase", sets, 2);
    sluice_field f;
    ck_assert_int_ne(sluice_sim_field(sim, "phase", &f), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    long fluid = 0;
    for (sluice_index i = 0; i < v->count; i++)
        fluid += v->kind[i] == SLUICE_KIND_FLUID;
    ck_assert_int_eq(fluid, both.water);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    int status;
    long steps = 0;
    while ((status = sluice_sim_step(sim)) == SLUICE_RUN_COMPLETE &&
           sluice_sim_time(sim) < sluice_sim_end_time(sim) - 1e-12)
        steps++;
    ck_assert_msg(status == SLUICE_RUN_COMPLETE, "single phase stopped: %s",
                  sluice_sim_failure(sim));
    fprintf(stderr, "%s single phase: %ld water particles (the two-phase scene's water), %ld "
                    "steps to 0.01 s\n",
            config, fluid, steps);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}

START_TEST(single_phase_variants)
{
    single_phase("stepped_chute_chanson.yaml", "particles.spacing=0.02");
    single_phase("stepped_spillway_cheng.yaml", "particles.spacing=0.0125");
}
END_TEST

/* Cheng's reduced spillway with the source's c_1 and with f c_1: oxygen
 * changes the flow nowhere (the same steps, bitwise), so the water
 * particles meet the same air; the deficit Cs - C decays by the source,
 * whose K is linear in c_1, and diffusion is molecular only (D_m dt / dx^2
 * ~ 1e-11 a step). Each water particle's log-deficit under f c_1 is then
 * f times that under c_1 (sluice-analyze dissolved-oxygen's calibration,
 * docs/analysis.md) up to the time stepping: per step the update factor
 * 1 - x (x = K a dt) against exp(-x) leaves (f^2 - f) x^2 / 2, summed to at
 * most (f^2 - f) x_max E / 2 for the exposure E = ln(D0 / D). c_1 is raised
 * (100 and 250) so that exposures of order 1 occur within the 0.008 s at
 * the tank's surface, the only water next to air so early. */
static void run_source(double c1, sluice_sim **out, double *x_max)
{
    char set[96];
    snprintf(set, sizeof set, "plugins.dissolved_oxygen.transfer_coefficient=%g", c1);
    const char *const sets[] = {set};
    sluice_sim *sim = load_variant("stepped_spillway_cheng.yaml", "reduced", sets, 1);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    int status;
    double worst = 0, previous = sluice_sim_time(sim);
    while ((status = sluice_sim_step(sim)) == SLUICE_RUN_COMPLETE) {
        const double dt = sluice_sim_time(sim) - previous;
        previous = sluice_sim_time(sim);
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *ka = test_column(sim, "reaeration_coefficient", 0);
        for (sluice_index i = 0; i < v->count; i++)
            worst = fmax(worst, (double)ka[i] * dt);
        if (sluice_sim_time(sim) >= sluice_sim_end_time(sim) - 1e-12)
            break;
    }
    ck_assert_msg(status == SLUICE_RUN_COMPLETE, "stopped: %s", sluice_sim_failure(sim));
    *out = sim;
    *x_max = worst;
}

START_TEST(cheng_source_scales_with_its_coefficient)
{
    const double c1 = 100, f = 2.5, cs = 10.48, cu = 1.29, d0 = cs - cu;
    sluice_sim *a, *b;
    double xa, xb;
    run_source(c1, &a, &xa);
    run_source(f * c1, &b, &xb);
    ck_assert_int_eq(sluice_sim_steps(a), sluice_sim_steps(b));
    const sluice_view *va = sluice_sim_view(a), *vb = sluice_sim_view(b);
    ck_assert_uint_eq(va->count, vb->count);
    sluice_field pa, ida, idb;
    ck_assert_int_eq(sluice_sim_field(a, "phase", &pa), SLUICE_OK);
    ck_assert_int_eq(sluice_sim_field(a, "id", &ida), SLUICE_OK);
    ck_assert_int_eq(sluice_sim_field(b, "id", &idb), SLUICE_OK);
    const uint8_t *phase = va->columns[pa.column];
    const sluice_id *id_a = va->columns[ida.column], *id_b = vb->columns[idb.column];
    const sluice_real *ca = test_column(a, "dissolved_oxygen", 0);
    const sluice_real *cb = test_column(b, "dissolved_oxygen", 0);
    /* particle order: the same in both runs (the same motion) */
    long water = 0, exposed = 0;
    double exposure_max = 0, worst_ratio = 0, worst_log = 0;
    for (sluice_index i = 0; i < va->count; i++) {
        if (id_a[i] != id_b[i])
            ck_abort_msg("particle %u: ids %llu and %llu", (unsigned)i,
                         (unsigned long long)id_a[i], (unsigned long long)id_b[i]);
        if (va->kind[i] != SLUICE_KIND_FLUID || phase[i])
            continue;
        if (va->position[0][i] != vb->position[0][i] || va->position[1][i] != vb->position[1][i])
            ck_abort_msg("particle %u moved differently", (unsigned)i);
        water++;
        const double exposure = log(d0 / (cs - (double)ca[i]));
        if (!(exposure > 1e-6))
            continue;
        exposed++;
        exposure_max = fmax(exposure_max, exposure);
        const double error = fabs(log(d0 / (cs - (double)cb[i])) - f * exposure);
        const double bound = (f * f - f) * fmax(xa, xb / f) * exposure / 2 + 1e-12;
        worst_log = fmax(worst_log, error);
        worst_ratio = fmax(worst_ratio, error / bound);
    }
    fprintf(stderr,
            "Cheng reduced, c1 = %g and %g: %ld water particles, %ld exposed (largest exposure "
            "ln(D0/D) = %.3f); |ln(D0/D_f) - f ln(D0/D)| <= %.3e, at most %.3f of the "
            "time-stepping bound (x_max = K a dt = %.3e)\n",
            c1, f * c1, water, exposed, exposure_max, worst_log, worst_ratio, xa);
    ck_assert_msg(exposure_max > 0.5, "exposures too small to test the map: %g", exposure_max);
    ck_assert_msg(exposed >= 20, "only %ld of %ld water particles exposed", exposed, water);
    ck_assert_msg(worst_ratio <= 1, "the map is off by %.3f of its bound", worst_ratio);
    sluice_sim_free(a);
    sluice_sim_free(b);
}
END_TEST

static Suite *spillway_suite(void)
{
    Suite *s = suite_create("spillways");
    TCase *c = tcase_create("reduced");
    tcase_set_timeout(c, 600);
    tcase_add_test(c, chanson_reduced);
    tcase_add_test(c, cheng_reduced);
    tcase_add_test(c, cheng_seed_model_reduced);
    tcase_add_test(c, single_phase_variants);
    suite_add_tcase(s, c);
    /* the seed's model on the other chute: the same plugins as Cheng's
     * above (tag `long`: the sanitizer pass of tools/run-tests.sh leaves it) */
    TCase *chanson_seed = tcase_create("reduced_chanson_seed_model");
    tcase_set_tags(chanson_seed, "long");
    tcase_set_timeout(chanson_seed, 600);
    tcase_add_test(chanson_seed, chanson_seed_model_reduced);
    suite_add_tcase(s, chanson_seed);
    TCase *source = tcase_create("reaeration_source");
    tcase_set_tags(source, "validation"); /* two runs of the reduced Cheng scene: release only */
    tcase_set_timeout(source, 600);
    tcase_add_test(source, cheng_source_scales_with_its_coefficient);
    suite_add_tcase(s, source);
    return s;
}

int main(void)
{
    return test_run_suite(spillway_suite());
}
