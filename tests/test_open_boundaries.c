/* Open boundaries (plugins/open_boundaries): inlet and outlet forms, particle
 * counts that change during a run, fluxes, and a uniform open-channel flow
 * held between an inlet and an outlet. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sim_util.h"

/* A horizontal, frictionless (penalty_contact) channel: inflow at x = 0,
 * outflow at x = length; water of depth `depth` at velocity `velocity`
 * fills it at the start. `inlet` and `outlet` are the plugins' lines. */
static char *channel_scene(double dx, double depth, double velocity, double length,
                           double c0, const char *inlet, const char *outlet, double end,
                           double upstream)
{
    char *yaml = malloc(8192);
    ck_assert_ptr_nonnull(yaml);
    snprintf(yaml, 8192,
             "dimensions: 2\n"
             "particles: {spacing: %.17g, smoothing_length_ratio: 1.5}\n"
             "time: {end: %.17g}\n"
             "domain: {min: [%.17g, -0.1], max: [%.17g, %.17g]}\n"
             "geometry:\n"
             "  fluid:\n"
             "    - {shape: box, min: [0, 0], max: [%.17g, %.17g], velocity: [%.17g, 0]}\n"
             "  walls:\n"
             "    - {shape: polyline, points: [[%.17g, 0], [%.17g, 0]], name: bed}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: %.17g}\n"
             "  continuity: {}\n"
             "  delta_sph: {delta: 0.1, form: fourtakas}\n"
             "  pressure_gradient: {}\n"
             "  artificial_viscosity: {alpha: 0.02}\n"
             "  gravity: {}\n"
             "  penalty_contact: {}\n"
             "  time_step: {courant: 0.25}\n"
             "  symplectic: {}\n"
             "  %s\n"
             "  %s\n",
             dx, end, -upstream - 10 * dx, length + 0.5, 4 * depth + 0.2, length, depth, velocity,
             -upstream - 8 * dx, length + 0.4, c0, inlet, outlet);
    return yaml;
}

typedef struct section {
    double depth, discharge, mass;
    sluice_index fluid, open;
} section;

/* Reach-averaged depth and discharge per unit width over x in [a, b) from
 * the fluid particles there: d = sum m_i / (rho0 (b - a)), q = sum m_i u_i /
 * (rho0 (b - a)) (the mass and x-momentum of the reach). Over the whole
 * reach between the boundaries these are free of the sampling noise of a
 * window inside the fluid, where particles bunching along x move the sums
 * by +-2 % at 5 particles per depth even in a periodic channel whose
 * momentum is conserved exactly. */
static section measure(sluice_sim *sim, double a, double b)
{
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *m = test_column(sim, "mass", 0), *u = test_column(sim, "velocity", 0);
    section s = {0, 0, 0, 0, 0};
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] == SLUICE_KIND_OPEN)
            s.open++;
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        s.fluid++;
        s.mass += m[i];
        const double x = v->position[0][i];
        if (x >= a && x < b) {
            s.depth += m[i];
            s.discharge += m[i] * u[i];
        }
    }
    s.depth /= 1000.0 * (b - a);
    s.discharge /= 1000.0 * (b - a);
    return s;
}

/* last row's column `col` of a CSV in the run directory */
static double csv_last(const char *path, int col)
{
    FILE *f = fopen(path, "r");
    ck_assert_msg(f != NULL, "cannot open %s", path);
    char line[1024], last[1024] = "";
    while (fgets(line, sizeof line, f))
        strcpy(last, line);
    fclose(f);
    char *p = last;
    for (int c = 0; c < col; c++) {
        p = strchr(p, ',');
        ck_assert_ptr_nonnull(p);
        p++;
    }
    return atof(p);
}

/* A uniform flow of depth d and velocity V held between an inlet and an
 * outlet for `end` seconds. Every 0.1 s the reach between them gives its
 * mean depth and discharge (measure()); over each second (the averaging a
 * depth gauge does) both stay within 2 % of the imposed d and q = V d. The
 * instantaneous values, which move by one particle in 250 (0.4 %) and with
 * the particles' bunching, are printed. The particle count balances
 * exactly: fluid now = fluid at start + entered - left, with whole numbers
 * of particles in the boundaries' mass fluxes. */
static void uniform_channel(const char *inlet_form, const char *outlet_form, double depth,
                            double velocity, double end, double dx)
{
    const double length = 1.0, c0 = 20, sample = 0.1, block = 1.0;
    char inlet[256], outlet[256];
    snprintf(inlet, sizeof inlet,
             "inlet: {form: %s, position: 0, depth: %.17g, velocity: %.17g, interval: 0.5}",
             inlet_form, depth, velocity);
    snprintf(outlet, sizeof outlet,
             "outlet: {form: %s, position: %.17g, depth: %.17g, velocity: %.17g, interval: 0.5}",
             outlet_form, length, depth, velocity);
    /* the block inlet holds the whole inflow upstream (seed 000) */
    const double upstream = strcmp(inlet_form, "block") == 0 ? velocity * end + 0.2 : 0.5;
    char *yaml = channel_scene(dx, depth, velocity, length, c0, inlet, outlet, end, upstream);
    char tag[64];
    snprintf(tag, sizeof tag, "channel-%s-%s", inlet_form, outlet_form);
    sluice_sim *sim = test_load(tag, yaml, NULL, 0);
    free(yaml);
    char *dir = test_scratch(tag);
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const section start = measure(sim, 0, length);
    const double q0 = depth * velocity;
    const int per_block = (int)lround(block / sample);
    double worst_depth = 0, worst_discharge = 0, worst_sample_depth = 0, worst_sample_q = 0;
    double next = sample, sum_depth = 0, sum_q = 0, t_depth = 0, t_q = 0;
    int samples = 0, blocks = 0;
    const int trace = getenv("OPEN_BOUNDARIES_TRACE") != NULL;
    while (sluice_sim_time(sim) < end - 1e-9) {
        int status = sluice_sim_step(sim);
        ck_assert_msg(status == SLUICE_RUN_COMPLETE, "channel run stopped: %s",
                      sluice_sim_failure(sim));
        if (sluice_sim_time(sim) + 1e-9 < next)
            continue;
        next += sample;
        const section s = measure(sim, 0, length);
        const double ed = s.depth / depth - 1, eq = s.discharge / q0 - 1;
        if (trace)
            fprintf(stderr, "t = %5.2f s: depth %+.2f %%, discharge %+.2f %%\n",
                    sluice_sim_time(sim), 100 * ed, 100 * eq);
        worst_sample_depth = fmax(worst_sample_depth, fabs(ed));
        worst_sample_q = fmax(worst_sample_q, fabs(eq));
        sum_depth += ed;
        sum_q += eq;
        if (++samples % per_block)
            continue;
        const double bd = sum_depth / per_block, bq = sum_q / per_block;
        sum_depth = sum_q = 0;
        blocks++;
        if (fabs(bd) > fabs(worst_depth)) {
            worst_depth = bd;
            t_depth = sluice_sim_time(sim);
        }
        if (fabs(bq) > fabs(worst_discharge)) {
            worst_discharge = bq;
            t_q = sluice_sim_time(sim);
        }
    }
    const section final = measure(sim, 0, length);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    char path[4096];
    snprintf(path, sizeof path, "%s/inlet.csv", dir);
    const double mass_in = csv_last(path, 4);
    snprintf(path, sizeof path, "%s/outlet.csv", dir);
    const double mass_out = csv_last(path, 4);
    const double particle_mass = 1000 * dx * dx;
    const double entered = mass_in / particle_mass, left = mass_out / particle_mass;
    fprintf(stderr,
            "uniform channel, inlet %s, outlet %s, d = %g m, V = %g m/s (Fr = %.3f), dx = %g m, "
            "%g s, %lld steps: %d one-second means; worst depth error %+.2f %% (second ending "
            "%.1f s), worst discharge error %+.2f %% (%.1f s); instantaneous (every 0.1 s) at "
            "worst %.2f %% / %.2f %%; final d = %.5f m, q = %.5f m^2/s; particles: fluid %u -> "
            "%u, entered %.0f, left %.0f, open now %u\n",
            inlet_form, outlet_form, depth, velocity, velocity / sqrt(9.81 * depth), dx, end,
            (long long)sluice_sim_steps(sim), blocks, 100 * worst_depth, t_depth,
            100 * worst_discharge, t_q, 100 * worst_sample_depth, 100 * worst_sample_q,
            final.depth, final.discharge, start.fluid, final.fluid, entered, left, final.open);
    ck_assert_int_eq(blocks, (int)lround(end / block));
    ck_assert_msg(fabs(worst_depth) < 0.02, "depth off by %.2f %%", 100 * worst_depth);
    ck_assert_msg(fabs(worst_discharge) < 0.02, "discharge off by %.2f %%",
                  100 * worst_discharge);
    /* every particle accounted for: whole numbers of particles crossed */
    ck_assert_msg(fabs(entered - nearbyint(entered)) < 1e-6 && fabs(left - nearbyint(left)) < 1e-6,
                  "fluxes are not whole particles: %g in, %g out", entered, left);
    ck_assert_int_eq((long long)final.fluid,
                     (long long)start.fluid + llround(entered) - llround(left));
    sluice_sim_free(sim);
    free(dir);
}

START_TEST(uniform_subcritical_buffer_buffer)
{
    uniform_channel("buffer", "buffer", 0.1, 0.5, getenv("OPEN_BOUNDARIES_END") ? atof(getenv("OPEN_BOUNDARIES_END")) : 20, 0.02);
}
END_TEST

START_TEST(uniform_supercritical_block_frozen)
{
    /* seed 000's pair: the whole inflow pre-placed, the outflow frozen */
    uniform_channel("block", "frozen", 0.04, 1.5, 2, 0.01);
}
END_TEST

START_TEST(uniform_supercritical_free)
{
    /* Fr = 2.4: the outflow needs no downstream control (seed 002) */
    uniform_channel("buffer", "free", 0.04, 1.5, 4, 0.01);
}
END_TEST

/* A scene that must be refused: `sluice check` exits 2 with one message
 * naming the scene file, a line and a column, and containing `needle`. */
static void refused(const char *inlet, const char *outlet, double end, const char *needle)
{
    char *yaml = channel_scene(0.02, 0.1, 0.5, 1.0, 20, inlet, outlet, end, 0.5);
    char *dir = test_scratch("open-refused");
    char *path = test_write_file(dir, "scene.yaml", yaml);
    char args[4200], *output = NULL;
    snprintf(args, sizeof args, "check %s", path);
    const int status = test_sluice(args, &output);
    fprintf(stderr, "refused (exit %d): %s", status, output ? output : "");
    ck_assert_int_eq(status, 2);
    ck_assert_ptr_nonnull(output);
    ck_assert_msg(strstr(output, needle) != NULL, "message lacks '%s'", needle);
    ck_assert_msg(strstr(output, "scene.yaml:") != NULL, "message names no file:line:column");
    free(output);
    free(path);
    free(dir);
    free(yaml);
}

START_TEST(bad_input_refused)
{
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5, discharge: 0.05}",
            "outlet: {position: 1}", 1, "exactly one of 'velocity'");
    refused("inlet: {position: 0, depth: 0.1}", "outlet: {position: 1}", 1,
            "exactly one of 'velocity'");
    refused("inlet: {position: 0.5, depth: 0.1, velocity: 0.5}", "outlet: {position: 0.2}", 1,
            "downstream of the inlet");
    refused("inlet: {form: block, position: 0, depth: 0.1, velocity: 0.5}",
            "outlet: {position: 1}", 10, "enlarge the domain");
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5}", "outlet: {form: buffer, position: 1}",
            1, "tailwater 'depth'");
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5}",
            "outlet: {form: frozen, position: 1.45}", 1, "needs the domain to reach");
    refused("inlet: {position: 0, depth: 0.1, velocity: -1}", "outlet: {position: 1}", 1,
            "velocity");
}
END_TEST

/* The hydraulic-jump scenes of configs/ load and take their first steps
 * (the reduced CI version: 100 steps; their physics is measured
 * by tools/jump-study.sh and docs/validation.md): every open boundary,
 * gauge and writer starts, particles enter, and nothing is lost. */
static const char *const jump_scenes[] = {
    "hydraulic_jump_jonsson2016.yaml", "abrupt_drop_T1.yaml", "abrupt_drop_T2.yaml",
    "abrupt_drop_T3.yaml",             "abrupt_drop_T4.yaml", "abrupt_drop_T5.yaml",
    "abrupt_drop_T6.yaml",             "abrupt_drop_T7.yaml",
};

START_TEST(jump_scenes_start)
{
    char *path = test_config(jump_scenes[_i]);
    char *text = test_read_file(path);
    ck_assert_ptr_nonnull(text);
    sluice_sim *sim = test_load("jump-scene", text, NULL, 0);
    free(text);
    char *dir = test_scratch("jump-scene-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const sluice_index start = sluice_sim_view(sim)->count;
    for (int step = 0; step < 100; step++) {
        const int status = sluice_sim_step(sim);
        ck_assert_msg(status == SLUICE_RUN_COMPLETE, "%s stopped at step %d: %s", jump_scenes[_i],
                      step, sluice_sim_failure(sim));
    }
    const sluice_index end = sluice_sim_view(sim)->count;
    fprintf(stderr, "%s: 100 steps to t = %.4f s, particles %u -> %u\n", jump_scenes[_i],
            sluice_sim_time(sim), start, end);
    /* every particle accounted for: the count changed only through the
     * boundaries */
    const uint64_t added = sim->next_id - sim->particles_initial;
    ck_assert_uint_eq(start, sim->particles_initial);
    ck_assert_uint_eq((uint64_t)end, (uint64_t)start + added - sim->removed);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    char file[4096];
    snprintf(file, sizeof file, "%s/run.json", dir);
    ck_assert(test_exists(file));
    sluice_sim_free(sim);
    free(path);
    free(dir);
}
END_TEST

/* dbc wall particles are compressed only by the fluid (plugins/continuity):
 * under an inlet buffer moving at 1 m/s over a dbc bed, with the fluid and
 * the walls at rest, the buffer's particles approaching a wall particle
 * (positive pair terms) are left out and those moving away from it are
 * kept, so every wall particle's rate is <= 0 and some are < 0, while the
 * fluid particles next to the buffer do see it move. Without the rule the
 * wall particles under the buffer's upstream end, which only see particles
 * arriving, get a positive rate: the one that, rectified by dbc's clamp,
 * made the density of the gate's lowest wall particle in the Jonsson jump
 * run away. */
START_TEST(dbc_walls_not_compressed_by_open_particles)
{
    const char *yaml = "dimensions: 2\n"
                       "particles: {spacing: 0.01, smoothing_length_ratio: 1.5}\n"
                       "time: {end: 1}\n"
                       "domain: {min: [-0.2, -0.1], max: [1.2, 0.3]}\n"
                       "geometry:\n"
                       "  fluid: [{shape: box, min: [0, 0], max: [1, 0.1]}]\n"
                       "  walls: [{shape: polyline, points: [[-0.2, 0], [1, 0]]}]\n"
                       "plugins:\n"
                       "  wendland_c2: {}\n"
                       "  tait: {speed_of_sound: 20}\n"
                       "  continuity: {}\n"
                       "  dbc: {}\n"
                       "  gravity: {}\n"
                       "  time_step: {}\n"
                       "  symplectic: {}\n"
                       "  inlet: {position: 0, depth: 0.1, velocity: 1}\n";
    sluice_sim *sim = test_load("dbc-open", yaml, NULL, 0);
    char *dir = test_scratch("dbc-open-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    /* the fluid at rest (the scene gives it no velocity): only the buffer moves */
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *rate = test_column(sim, "density_rate", 0);
    const sluice_real *u = test_column(sim, "velocity", 0);
    sluice_index open = 0, walls_near = 0, walls_expanded = 0, fluid_moved = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] == SLUICE_KIND_OPEN) {
            ck_assert(u[i] == 1);
            open++;
        } else if (v->kind[i] == SLUICE_KIND_WALL) {
            ck_assert_msg(rate[i] <= 0, "wall particle at (%g, %g): density rate %g",
                          (double)v->position[0][i], (double)v->position[1][i], (double)rate[i]);
            if (v->position[0][i] < 0.02)
                walls_near++;
            if (rate[i] < 0)
                walls_expanded++;
        } else if (v->position[0][i] < 0.02 && rate[i] != 0) {
            fluid_moved++;
        }
    }
    fprintf(stderr, "dbc under an inlet: %u open particles, %u wall particles near them (%u "
                    "with a negative rate), %u fluid particles with a rate\n",
            open, walls_near, walls_expanded, fluid_moved);
    ck_assert_uint_gt(walls_expanded, 0);
    ck_assert_uint_gt(open, 0);
    ck_assert_uint_gt(walls_near, 0);
    ck_assert_uint_gt(fluid_moved, 0);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    free(dir);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("open_boundaries");
    TCase *long_run = tcase_create("uniform_channel_20s");
    tcase_set_tags(long_run, "validation"); /* long: release pass only */
    tcase_set_timeout(long_run, 600);
    tcase_add_test(long_run, uniform_subcritical_buffer_buffer);
    suite_add_tcase(s, long_run);
    TCase *uniform = tcase_create("uniform_channel");
    tcase_set_timeout(uniform, 600);
    tcase_add_test(uniform, uniform_supercritical_block_frozen);
    tcase_add_test(uniform, uniform_supercritical_free);
    suite_add_tcase(s, uniform);
    TCase *scenes = tcase_create("jump_scenes");
    tcase_set_timeout(scenes, 300);
    tcase_add_loop_test(scenes, jump_scenes_start, 0,
                        (int)(sizeof jump_scenes / sizeof *jump_scenes));
    suite_add_tcase(s, scenes);
    TCase *kinds = tcase_create("open_particles");
    tcase_add_test(kinds, dbc_walls_not_compressed_by_open_particles);
    suite_add_tcase(s, kinds);
    TCase *input = tcase_create("bad_input");
    tcase_add_test(input, bad_input_refused);
    suite_add_tcase(s, input);
    return test_run_suite(s);
}
