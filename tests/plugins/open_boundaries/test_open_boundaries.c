/* Open boundaries (plugins/open_boundaries): inlet and outlet forms, particle
 * counts that change during a run, fluxes, and a uniform open-channel flow
 * held between an inlet and an outlet. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sim_util.h"
/* Internal: the particle bookkeeping: next_id, particles_initial, removed (not in sim.h) */
#include "sim_internal.h"

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

/* The inlet's net inflow and the outlet's outflow of a run (their tables'
 * last mass_total), in particles of rho0 dx^2 with rho0 = 1000 kg/m^3 */
static void particle_fluxes(const char *dir, double dx, double *net_in, double *out)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/inlet.csv", dir);
    *net_in = csv_last(path, 4) / (1000 * dx * dx);
    snprintf(path, sizeof path, "%s/outlet.csv", dir);
    *out = csv_last(path, 4) / (1000 * dx * dx);
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

/* Fluid flowing back upstream across the inlet plane leaves through the
 * inlet: a channel whose water starts at -0.4 m/s against an inflow of
 * 0.1 m/s (dx = 0.02 m, d = 0.1 m). After every step no fluid particle lies
 * upstream of the plane within the inflow's section (it would run into the
 * lattice and on out of the domain), nor more than dx/2 upstream above it; the inlet's mass_total is the net inflow, negative here (about
 * 0.4 d 0.2 s / dx^2 = 20 particles back against 5 in), in whole
 * particles; the particle count balances exactly. */
START_TEST(backflow_leaves_through_the_inlet)
{
    const double dx = 0.02, end = 0.2;
    char *yaml = channel_scene(dx, 0.1, -0.4, 1.0, 20,
                               "inlet: {form: buffer, position: 0, depth: 0.1, velocity: 0.1, "
                               "interval: 0.05}",
                               "outlet: {position: 1.0}", end, 0.5);
    sluice_sim *sim = test_load("backflow", yaml, NULL, 0);
    free(yaml);
    char *dir = test_scratch("backflow-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const section start = measure(sim, 0, 1.0);
    while (sluice_sim_time(sim) < end - 1e-9) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "run stopped: %s",
                      sluice_sim_failure(sim));
        const sluice_view *v = sluice_sim_view(sim);
        for (sluice_index i = 0; i < v->count; i++)
            ck_assert_msg(v->kind[i] != SLUICE_KIND_FLUID ||
                              v->position[0][i] >= (v->position[1][i] < 0.1 ? 0 : -dx / 2),
                          "fluid particle at (%g, %g) m, upstream of the inlet plane",
                          (double)v->position[0][i], (double)v->position[1][i]);
    }
    const section final = measure(sim, 0, 1.0);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    double net_in, out;
    particle_fluxes(dir, dx, &net_in, &out);
    fprintf(stderr,
            "backflow through the inlet: fluid %u -> %u, net inflow %.6g particles, outflow "
            "%.6g\n",
            start.fluid, final.fluid, net_in, out);
    ck_assert_msg(fabs(net_in - nearbyint(net_in)) < 1e-6, "net inflow %g particles", net_in);
    ck_assert_msg(net_in < 0, "net inflow %g particles: the backflow was not counted", net_in);
    ck_assert_int_eq((long long)final.fluid,
                     (long long)start.fluid + llround(net_in) - llround(out));
    sluice_sim_free(sim);
    free(dir);
}
END_TEST

/* With `backflow: hold` the same reverse flow is held on the plane: a
 * discharge-controlled feed takes nothing back. The channel of the test
 * above (water at -0.4 m/s against an inflow of 0.1 m/s, dx = 0.02 m,
 * d = 0.1 m: five rows), with a gate over the inflow as over a reservoir's
 * feed, runs 0.3 s with the Verlet integrator (whose stored v^(n-1) the hold
 * sets too). After every step no fluid lies upstream of
 * the plane within the section; the inlet's mass_total is whole columns of
 * five particles, V1 t / dx = 1.5 columns: one or two, never less (nothing
 * left through the inlet, where the test above lost about 20 particles);
 * the particle count balances exactly. */
START_TEST(backflow_held_on_the_inlet_plane)
{
    const double dx = 0.02, end = 0.3;
    char *yaml = channel_scene(dx, 0.1, -0.4, 1.0, 20,
                               "inlet: {form: buffer, position: 0, depth: 0.1, velocity: 0.1, "
                               "interval: 0.05, backflow: hold}",
                               "outlet: {position: 1.0}", end, 0.5);
    char *integrator = strstr(yaml, "symplectic: {}");
    ck_assert_ptr_nonnull(integrator);
    memcpy(integrator, "verlet: {}    ", 14);
    /* a gate over the inflow, as over a reservoir's feed: above the section
     * the reverse flow would otherwise run back over the buffer and leave */
    const char *bed = "name: bed}\n";
    char *after_bed = strstr(yaml, bed);
    ck_assert_ptr_nonnull(after_bed);
    after_bed += strlen(bed);
    const char *gate = "    - {shape: polyline, points: [[0, 0.4], [0, 0.1]], name: gate}\n";
    ck_assert_uint_lt(strlen(yaml) + strlen(gate), 8192);
    memmove(after_bed + strlen(gate), after_bed, strlen(after_bed) + 1);
    memcpy(after_bed, gate, strlen(gate));
    sluice_sim *sim = test_load("backflow-hold", yaml, NULL, 0);
    free(yaml);
    char *dir = test_scratch("backflow-hold-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const section start = measure(sim, 0, 1.0);
    uint64_t held_steps = 0;
    while (sluice_sim_time(sim) < end - 1e-9) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "run stopped: %s",
                      sluice_sim_failure(sim));
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *u = test_column(sim, "velocity", 0);
        int on_plane = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_FLUID)
                continue;
            ck_assert_msg(v->position[0][i] >= (v->position[1][i] < 0.1 ? 0 : -dx / 2),
                          "fluid particle at (%g, %g) m, upstream of the inlet plane",
                          (double)v->position[0][i], (double)v->position[1][i]);
            if (v->position[0][i] == 0 && v->position[1][i] < 0.1) {
                ck_assert_msg(fabs(u[i] - 0.1) < 1e-12, "held particle at %g m/s", (double)u[i]);
                on_plane = 1;
            }
        }
        held_steps += (uint64_t)on_plane;
    }
    const section final = measure(sim, 0, 1.0);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    double net_in, out;
    particle_fluxes(dir, dx, &net_in, &out);
    fprintf(stderr,
            "backflow held on the inlet plane: fluid %u -> %u, net inflow %.6g particles, "
            "outflow %.6g, steps with a particle held %llu\n",
            start.fluid, final.fluid, net_in, out, (unsigned long long)held_steps);
    ck_assert_msg(held_steps > 0, "the reverse flow never reached the plane: nothing tested");
    ck_assert_msg(fabs(net_in - nearbyint(net_in)) < 1e-6, "net inflow %g particles", net_in);
    ck_assert_msg(nearbyint(net_in) == 5 || nearbyint(net_in) == 10,
                  "net inflow %g particles, not one or two columns of five", net_in);
    ck_assert_int_eq((long long)final.fluid,
                     (long long)start.fluid + llround(net_in) - llround(out));
    sluice_sim_free(sim);
    free(dir);
}
END_TEST

/* A submerged inflow: an inlet 0.1 m deep under a gate, with 0.2 m of water
 * standing above its top (submergence), feeding a tank 0.3 m deep. The
 * lattice has the Tait density of the full depth, rho0 (1 + rho0 g (0.3 - y)
 * / B)^(1/7), B = rho0 c0^2 / 7, to round-off (1e-12 relative: a sum and a
 * root); without submergence it would be that of 0.1 m, 2e-4 lower at the
 * bed. The tank then runs for 0.1 s with no fluid upstream of the plane in
 * the inflow's section (y < 0.1 m; above it the gate holds the fluid). */
START_TEST(submerged_inlet_density)
{
    const char *yaml =
        "dimensions: 2\n"
        "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
        "time: {end: 0.1}\n"
        "domain: {min: [-0.2, -0.1], max: [0.8, 0.5]}\n"
        "geometry:\n"
        "  fluid:\n"
        "    - {shape: box, min: [0, 0], max: [0.6, 0.3]}\n"
        "  walls:\n"
        "    - {shape: polyline, points: [[-0.16, 0], [0.6, 0], [0.6, 0.4]], name: bed}\n"
        "    - {shape: polyline, points: [[0, 0.4], [0, 0.1]], name: gate}\n"
        "plugins:\n"
        "  wendland_c2: {}\n"
        "  tait: {speed_of_sound: 20}\n"
        "  continuity: {}\n"
        "  pressure_gradient: {}\n"
        "  artificial_viscosity: {alpha: 0.1}\n"
        "  gravity: {}\n"
        "  dbc: {}\n"
        "  time_step: {courant: 0.25}\n"
        "  symplectic: {}\n"
        "  inlet: {position: 0, depth: 0.1, submergence: 0.2, velocity: 0.02}\n";
    sluice_sim *sim = test_load("submerged-inlet", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *rho = test_column(sim, "density", 0);
    const double B = 1000.0 * 20 * 20 / 7;
    double worst = 0;
    int open = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_OPEN)
            continue;
        const double y = v->position[1][i];
        const double expected = 1000 * pow(1 + 1000 * 9.81 * (0.3 - y) / B, 1.0 / 7);
        worst = fmax(worst, fabs(rho[i] - expected) / expected);
        open++;
    }
    ck_assert_int_gt(open, 0);
    ck_assert_msg(worst <= 1e-12, "open particle density off by %.3g relative", worst);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < 0.1 - 1e-9) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "run stopped: %s",
                      sluice_sim_failure(sim));
        v = sluice_sim_view(sim);
        for (sluice_index i = 0; i < v->count; i++)
            ck_assert_msg(v->kind[i] != SLUICE_KIND_FLUID || v->position[0][i] >= 0 ||
                              v->position[1][i] >= 0.1,
                          "fluid at (%g, %g) m, upstream of the plane in the inflow's section",
                          (double)v->position[0][i], (double)v->position[1][i]);
    }
    fprintf(stderr, "submerged inlet: %d open particles with the density of 0.3 m of water "
                    "(worst %.2e relative); 0.1 s run with no fluid upstream of the plane in the "
                    "inflow's section\n",
            open, worst);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}
END_TEST

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
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5, backflow: return}",
            "outlet: {position: 1}", 1, "expected one of: leave, hold");
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
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5}",
            "outlet: {position: 1, tailwater: controlled, control_position: 0.6}", 1,
            "needs form: buffer");
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5}",
            "outlet: {form: buffer, position: 1, depth: 0.1, velocity: 0.5, "
            "tailwater: controlled, control_position: 1.2}",
            1, "upstream of the outlet plane");
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5}",
            "outlet: {form: buffer, position: 1, depth: 0.1, tailwater: controlled, "
            "control_position: 0.6}",
            1, "give 'velocity' > 0");
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5}",
            "outlet: {form: buffer, position: 1, depth: 0.1, velocity: 0.5, "
            "tailwater: controlled, control_position: -3}",
            1, "outside the domain");
    refused("inlet: {position: 0, depth: 0.1, velocity: 0.5}",
            "outlet: {form: buffer, position: 1, depth: 0.1, velocity: 0.5, "
            "tailwater: gated, control_position: 0.6}",
            1, "tailwater");
}
END_TEST

/* The hydraulic-jump scenes of configs/ load and take their first steps
 * (the reduced CI version: 100 steps; their physics is measured
 * by configs/studies/jump_jonsson.yaml, docs/validation.md): every open boundary,
 * gauge and writer starts, particles enter, and nothing is lost. */
static const char *const jump_scenes[] = {
    "hydraulic_jump_jonsson2016.yaml", "abrupt_drop_T1.yaml", "abrupt_drop_T2.yaml",
    "abrupt_drop_T3.yaml",             "abrupt_drop_T4.yaml", "abrupt_drop_T5.yaml",
    "abrupt_drop_T6.yaml",             "abrupt_drop_T7.yaml",
};

static void run_jump_scene(const char *config, const char *variant)
{
    char *path = test_config(config);
    ck_assert_ptr_nonnull(path);
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {0};
    sluice_sim *sim = sluice_sim_load_variant(path, variant, &options, diag);
    if (!sim)
        for (size_t i = 0; i < sluice_diag_count(diag); i++)
            fprintf(stderr, "%s\n", sluice_diag_message(diag, i));
    ck_assert_msg(sim != NULL, "%s (variant %s) failed to load", config,
                  variant ? variant : "none");
    sluice_diag_destroy(diag);
    char *dir = test_scratch("jump-scene-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const sluice_index start = sluice_sim_view(sim)->count;
    for (int step = 0; step < 100; step++) {
        const int status = sluice_sim_step(sim);
        ck_assert_msg(status == SLUICE_RUN_COMPLETE, "%s stopped at step %d: %s", config, step,
                      sluice_sim_failure(sim));
    }
    const sluice_index end = sluice_sim_view(sim)->count;
    fprintf(stderr, "%s%s%s: 100 steps to t = %.4f s, particles %u -> %u\n", config,
            variant ? " --variant " : "", variant ? variant : "", sluice_sim_time(sim), start,
            end);
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

START_TEST(jump_scenes_start)
{
    run_jump_scene(jump_scenes[_i], NULL);
}
END_TEST

/* The abrupt drop on seed 004's walls (variant ghost_walls: no-slip ghost
 * particles, continuity at the walls' rest velocity) loads and starts. */
START_TEST(abrupt_drop_ghost_walls_start)
{
    run_jump_scene("abrupt_drop_T3.yaml", "ghost_walls");
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

/* ----------------------------------------------- two-phase boundaries -- */

/* Two-phase scenes (plugins/two_phase): c0_w = 10 m/s, so one B =
 * c0_w^2 rho_w / 7 for both phases; p_b = 100 Pa; air 1.09 kg m^-3,
 * gamma 1.4. */
#define TP_DX 0.02
#define TP_RHO_W 1000.0
#define TP_RHO_A 1.09
#define TP_PB 100.0
#define TP_G 9.81
#define TP_B (10.0 * 10.0 * TP_RHO_W / 7)
#define TP_END 0.12 /* s: three inflow columns cross (at 0.02, 0.06, 0.1 s) */

/* The two laws inverted: the density at p = p_b + excess. */
static double water_at(double excess)
{
    return TP_RHO_W * pow(1 + excess / TP_B, 1 / 7.0);
}

static double air_at(double excess)
{
    return TP_RHO_A * pow(1 + excess / TP_B, 1 / 1.4);
}

static const uint8_t *phase_of(sluice_sim *sim)
{
    sluice_field f;
    ck_assert_int_eq(sluice_sim_field(sim, "phase", &f), SLUICE_OK);
    ck_assert_int_eq(f.type, SLUICE_TYPE_UINT8);
    return sluice_sim_view(sim)->columns[f.column];
}

/* Column `col` of every data row of a CSV (header skipped); returns the
 * row count (at most `max`). */
static int csv_column(const char *path, int col, double *out, int max)
{
    FILE *f = fopen(path, "r");
    ck_assert_msg(f != NULL, "cannot open %s", path);
    char line[1024];
    int n = 0;
    ck_assert_ptr_nonnull(fgets(line, sizeof line, f));
    while (n < max && fgets(line, sizeof line, f)) {
        char *p = line;
        for (int c = 0; c < col && p; c++)
            p = strchr(p, ',') ? strchr(p, ',') + 1 : NULL;
        ck_assert_ptr_nonnull(p);
        out[n++] = strtod(p, NULL);
    }
    fclose(f);
    return n;
}

#define AIR_CHANNEL_TWO_PHASE                                                                  \
    "  two_phase: {speed_of_sound: 10, background_pressure: 100, air_above: [[0, 0.1]]}\n"

/* A channel under a lid at y = 0.2 m: water 0.1 m deep under 0.1 m of air,
 * both at 0.5 m/s, fed by an inlet (`inlet`: its parameters) at x = 0 and
 * drained by a free outlet at x = 0.6 m; dbc bed and lid; `first` (the
 * equation of state) listed first, `extra` plugins last. */
static char *air_channel_with(const char *first, const char *inlet, const char *extra)
{
    char *text = NULL;
    ck_assert_int_ge(
        asprintf(&text,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: 1000}\n"
                 "time: {end: 0.12}\n"
                 "domain: {min: [-0.3, -0.1], max: [1.0, 0.4]}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [0.6, 0.1], velocity: [0.5, 0]}\n"
                 "    - {shape: box, min: [0, 0.1], max: [0.6, 0.2], velocity: [0.5, 0]}\n"
                 "  walls:\n"
                 "    - {shape: polyline, points: [[-0.26, 0], [0.6, 0]], name: bed}\n"
                 "    - {shape: polyline, points: [[0.6, 0.2], [-0.26, 0.2]], name: lid}\n"
                 "initial: {density: hydrostatic}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "%s"
                 "  continuity: {form: volume}\n"
                 "  pressure_gradient: {form: density_product}\n"
                 "  artificial_viscosity: {alpha: 0.1}\n"
                 "  gravity: {}\n"
                 "  dbc: {}\n"
                 "  time_step: {courant: 0.25}\n"
                 "  symplectic: {}\n"
                 "  inlet: {%s}\n"
                 "  outlet: {position: 0.6}\n"
                 "%s",
                 first, inlet, extra ? extra : ""),
        0);
    return text;
}

static char *air_channel_scene(const char *inlet, const char *extra)
{
    return air_channel_with(AIR_CHANNEL_TWO_PHASE, inlet, extra);
}

typedef struct lattice_count {
    int water, air;
} lattice_count;

/* The inlet's open particles (x < 0, the plane): water (phase 0) below the
 * depth d = 0.1 m, air (phase 1) up to d + a = 0.2 m, each with its mass
 * rho0_k dx^2 and the hydrostatic density of its law, p_b at the top of the
 * air: air p = p_b + rho_a g (0.2 - y), water p = p_b + rho_a g a +
 * rho_w g (0.1 - y). Tolerance: a few ulps of the pressure sums, divided by
 * B and under the 1/gamma root, stay below 1e-15; 1e-12 relative is round-
 * off with room. The masses are the products rho0_k dx^2 (1e-14). */
static lattice_count check_inlet_lattice(sluice_sim *sim, double top, double depth,
                                         double *worst)
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_of(sim);
    const sluice_real *rho = test_column(sim, "density", 0);
    const sluice_real *m = test_column(sim, "mass", 0);
    const uint32_t up = v->dimensions - 1;
    const double volume = pow(TP_DX, v->dimensions);
    lattice_count n = {0, 0};
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_OPEN || !(v->position[0][i] < 0))
            continue;
        const double y = v->position[up][i];
        const int air = y > depth;
        const double expected = air ? air_at(TP_RHO_A * TP_G * (top - y))
                                    : water_at(TP_RHO_A * TP_G * (top - depth) +
                                               TP_RHO_W * TP_G * (depth - y));
        const double mass = (air ? TP_RHO_A : TP_RHO_W) * volume;
        ck_assert_msg(phase[i] == air, "open particle at y = %g m: phase %d", y, phase[i]);
        const double error = fabs(rho[i] - expected) / expected;
        *worst = fmax(*worst, error);
        ck_assert_msg(error <= 1e-12, "%s at y = %g m: density %.17g, expected %.17g",
                      air ? "air" : "water", y, rho[i], expected);
        ck_assert_msg(fabs(m[i] - mass) <= 1e-14 * mass, "mass %.17g, expected %.17g", m[i],
                      mass);
        air ? n.air++ : n.water++;
    }
    return n;
}

/* (a) An inlet with an air layer (air_depth = 0.1 m over d = 0.1 m, V1 =
 * 0.5 m/s, dx = 0.02 m: 5 rows of each), buffer and block forms: at the
 * start and after every step its open particles have the phase, mass and
 * hydrostatic density of their row (check_inlet_lattice); air from it
 * enters the channel; and inlet.csv counts the water only: with interval
 * = dx / V1 = 0.04 s and the first column crossing at dx / (2 V1), one
 * column crosses in each interval, so every row's discharge is the
 * lattice's V1 rows dx = 0.05 m^2/s and mass_total after 0.12 s is 3
 * columns x 5 water rows x rho_w dx^2 = 6 kg, to the CSV's 10 digits
 * (1e-9). Counting the air would add 5 rho_a dx^2 = 2.2e-3 kg a column
 * (1.1e-3 relative). */
START_TEST(inlet_air_layer)
{
    /* the third case lists two_phase after the inlet: its start must leave
     * the phase of the inlet's particles alone */
    const char *forms[3] = {"buffer", "block", "buffer"};
    char inlet[256];
    snprintf(inlet, sizeof inlet,
             "form: %s, position: 0, depth: 0.1, air_depth: 0.1, velocity: 0.5, interval: 0.04",
             forms[_i]);
    char *yaml = _i == 2 ? air_channel_with("", inlet, AIR_CHANNEL_TWO_PHASE)
                         : air_channel_scene(inlet, NULL);
    sluice_sim *sim = test_load("inlet-air", yaml, NULL, 0);
    free(yaml);
    const sluice_view *v = sluice_sim_view(sim);
    sluice_id first_inlet = UINT64_MAX;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_OPEN && v->id[i] < first_inlet)
            first_inlet = v->id[i];
    double worst = 0;
    const lattice_count start = check_inlet_lattice(sim, 0.2, 0.1, &worst);
    ck_assert_int_gt(start.water, 0);
    ck_assert_int_eq(start.air, start.water); /* 5 rows of each per column */
    ck_assert_int_eq(start.water % 5, 0);
    char *dir = test_scratch("inlet-air-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    int steps = 0;
    while (sluice_sim_time(sim) < TP_END - 1e-12) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step failed: %s",
                      sluice_sim_failure(sim));
        steps++;
        const lattice_count now = check_inlet_lattice(sim, 0.2, 0.1, &worst);
        ck_assert_int_eq(now.air, now.water);
    }
    /* air from the inlet is in the channel, as fluid of phase 1 */
    v = sluice_sim_view(sim);
    const uint8_t *phase = phase_of(sim);
    int air_in = 0, water_in = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && v->id[i] >= first_inlet)
            phase[i] ? air_in++ : water_in++;
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    char path[4096];
    snprintf(path, sizeof path, "%s/inlet.csv", dir);
    double discharge[16], total[16];
    const int rows = csv_column(path, 2, discharge, 16);
    ck_assert_int_eq(csv_column(path, 4, total, 16), rows);
    ck_assert_int_eq(rows, 4); /* t = 0, 0.04, 0.08, 0.12 */
    const double q = 0.5 * 5 * TP_DX, mass_total = 3 * 5 * TP_RHO_W * TP_DX * TP_DX;
    double worst_q = 0;
    for (int r = 1; r < rows; r++) {
        worst_q = fmax(worst_q, fabs(discharge[r] / q - 1));
        ck_assert_msg(fabs(discharge[r] - q) <= 1e-9 * q, "row %d: discharge %.10g, lattice's %g",
                      r, discharge[r], q);
    }
    fprintf(stderr,
            "inlet with air layer (%s%s): %d steps to 0.12 s; %d water + %d air open particles at "
            "the start, phases, masses and densities of every inflow row exact (worst density "
            "error %.2e relative); discharge rows within %.1e of V1 rows dx = %g m^2/s, "
            "mass_total %.10g kg (3 columns of water: %g kg); inflow particles now in the "
            "channel: %d water, %d air\n",
            forms[_i], _i == 2 ? ", two_phase listed after the inlet" : "", steps, start.water, start.air, worst, worst_q, q, total[rows - 1],
            mass_total, water_in, air_in);
    ck_assert_msg(fabs(total[rows - 1] - mass_total) <= 1e-9 * mass_total,
                  "mass_total %.10g kg, expected %g (water only)", total[rows - 1], mass_total);
    ck_assert_int_gt(air_in, 0);
    ck_assert_int_gt(water_in, 0);
    sluice_sim_free(sim);
    free(dir);
}
END_TEST

/* The same lattice in 3D: lanes across the span, rows of water then air,
 * each whole column created together (V1 = 1 m/s makes a new column within
 * 0.01 s). */
START_TEST(inlet_air_layer_3d)
{
    const char *yaml =
        "dimensions: 3\n"
        "particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: 1000}\n"
        "time: {end: 0.012}\n"
        "domain: {min: [-0.1, -0.02, -0.02], max: [0.3, 0.1, 0.12]}\n"
        "geometry:\n"
        "  fluid:\n"
        "    - {shape: box, min: [0, 0, 0], max: [0.1, 0.06, 0.04], velocity: [1, 0, 0]}\n"
        "    - {shape: box, min: [0, 0, 0.04], max: [0.1, 0.06, 0.1], velocity: [1, 0, 0]}\n"
        "initial: {density: hydrostatic}\n"
        "plugins:\n"
        "  wendland_c2: {}\n"
        "  two_phase: {speed_of_sound: 10, background_pressure: 100, air_above: [[0, 0, 0.04]]}\n"
        "  continuity: {form: volume}\n"
        "  pressure_gradient: {form: density_product}\n"
        "  gravity: {}\n"
        "  time_step: {courant: 0.25}\n"
        "  symplectic: {}\n"
        "  inlet: {position: 0, depth: 0.04, air_depth: 0.06, velocity: 1, span: [0, 0.06]}\n";
    sluice_sim *sim = test_load("inlet-air-3d", yaml, NULL, 0);
    double worst = 0;
    const lattice_count start = check_inlet_lattice(sim, 0.1, 0.04, &worst);
    /* 3 columns x 3 lanes x (2 water + 3 air rows) */
    ck_assert_int_eq(start.water, 3 * 3 * 2);
    ck_assert_int_eq(start.air, 3 * 3 * 3);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < 0.012 - 1e-12)
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step failed: %s",
                      sluice_sim_failure(sim));
    const lattice_count now = check_inlet_lattice(sim, 0.1, 0.04, &worst);
    /* the front column (x = -dx/2) crossed at 0.01 s, a new one entered at
     * the back: the layer is whole again */
    const uint64_t created = sim->next_id - sim->particles_initial;
    fprintf(stderr, "3D inlet with air layer: %d water + %d air open particles at the start, "
                    "%d + %d after 0.012 s, %llu created; worst density error %.2e\n",
            start.water, start.air, now.water, now.air, (unsigned long long)created, worst);
    ck_assert_int_eq(now.water, start.water);
    ck_assert_int_eq(now.air, start.air);
    ck_assert_uint_eq(created, 3 * 5);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}
END_TEST

/* A closed air box over a channel: water 0.1 m deep flows in at 0.5 m/s
 * under a gate at x = 0 (inlet, water only), air at rest above it up to a
 * lid at 0.2 m, an end wall at x = 0.8 m; the outlet at x = 0.6 m (its
 * line `outlet`). */
static char *air_box_scene(const char *outlet, const char *pocket)
{
    char *text = NULL;
    ck_assert_int_ge(
        asprintf(&text,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: 1000}\n"
                 "time: {end: 0.12}\n"
                 "domain: {min: [-0.3, -0.1], max: [1.0, 0.4]}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [%s, 0.1], velocity: [0.5, 0]}\n"
                 "    - {shape: box, min: [0, 0.1], max: [0.8, 0.2]}\n"
                 "%s"
                 "  walls:\n"
                 "    - {shape: polyline, points: [[-0.26, 0], [0.8, 0], [0.8, 0.2]], name: bed}\n"
                 "    - {shape: polyline, points: [[0.8, 0.2], [0, 0.2], [0, 0.1]], name: lid}\n"
                 "initial: {density: hydrostatic}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  two_phase: {speed_of_sound: 10, background_pressure: 100, "
                 "air_above: [[0, 0.1]]%s}\n"
                 "  continuity: {form: volume}\n"
                 "  pressure_gradient: {form: density_product}\n"
                 "  artificial_viscosity: {alpha: 0.1}\n"
                 "  gravity: {}\n"
                 "  dbc: {}\n"
                 "  time_step: {courant: 0.25}\n"
                 "  symplectic: {}\n"
                 "  inlet: {position: 0, depth: 0.1, velocity: 0.5, interval: 0.04}\n"
                 "  outlet: {%s}\n",
                 pocket ? "0.6" : "0.8",
                 pocket ? "    - {shape: box, min: [0.66, 0], max: [0.8, 0.1]}\n" : "",
                 pocket ? ", air_box_min: [[0.66, 0]], air_box_max: [[0.8, 0.1]]" : "", outlet),
        0);
    return text;
}

typedef struct box_count {
    int air, air_open, air_past, water, water_fluid_past;
} box_count;

static box_count count_box(sluice_sim *sim)
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_of(sim);
    box_count n = {0, 0, 0, 0, 0};
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] == SLUICE_KIND_WALL)
            continue;
        const int past = v->position[0][i] >= 0.6;
        if (phase[i]) {
            n.air++;
            n.air_open += v->kind[i] == SLUICE_KIND_OPEN;
            n.air_past += past && v->kind[i] == SLUICE_KIND_FLUID;
        } else {
            n.water++;
            n.water_fluid_past += past && v->kind[i] == SLUICE_KIND_FLUID;
        }
    }
    return n;
}

/* (b) The outlet's phase filter, 0.12 s of the closed air box:
 *  - phase: water, form frozen (layer 0.2 m, to the end wall): at the end
 *    of every step no water particle past the plane is ordinary fluid (it
 *    crossed into the layer), no air particle is open, and the number of
 *    air particles is the start's, exactly; air stays past the plane; every
 *    particle removed was water: water now = water at the start + created
 *    by the inlet (water only) - removed.
 *  - phase: all, form free: no fluid of either phase stays past the plane,
 *    air is removed too, and outlet.csv's mass_total is the removed water's
 *    mass (the water only: whole water particles, to the CSV's 10 digits). */
START_TEST(outlet_phase_filter)
{
    const char *outlets[2] = {"form: frozen, position: 0.6, width: 0.2, phase: water",
                              "form: free, position: 0.6, phase: all, interval: 0.05"};
    const int water_only = _i == 0;
    char *yaml = air_box_scene(outlets[_i], NULL);
    sluice_sim *sim = test_load("outlet-phase", yaml, NULL, 0);
    free(yaml);
    const box_count start = count_box(sim);
    const uint64_t ids_at_start = sim->next_id;
    char *dir = test_scratch("outlet-phase-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    box_count now = count_box(sim);
    int steps = 0, air_past_min = now.air_past;
    while (sluice_sim_time(sim) < TP_END - 1e-12) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step failed: %s",
                      sluice_sim_failure(sim));
        steps++;
        now = count_box(sim);
        ck_assert_int_eq(now.water_fluid_past, 0);
        ck_assert_int_eq(now.air_open, 0);
        if (water_only)
            ck_assert_int_eq(now.air, start.air);
        else
            ck_assert_int_eq(now.air_past, 0);
        air_past_min = now.air_past < air_past_min ? now.air_past : air_past_min;
    }
    const uint64_t created = sim->next_id - ids_at_start;
    const int air_removed = start.air - now.air;
    const int water_removed = (int)sim->removed - air_removed;
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    char path[4096];
    snprintf(path, sizeof path, "%s/outlet.csv", dir);
    double total[64];
    const int rows = csv_column(path, 4, total, 64);
    const double particle = TP_RHO_W * TP_DX * TP_DX, counted = total[rows - 1] / particle;
    fprintf(stderr,
            "outlet phase %s (%s): %d steps to 0.12 s; air %d -> %d (%d removed, at least %d "
            "stayed past the plane), water %d -> %d (%llu created, %d removed); outlet.csv: "
            "%.10g kg = %.6f water particles\n",
            water_only ? "water" : "all", water_only ? "frozen" : "free", steps, start.air,
            now.air, air_removed, air_past_min, start.water, now.water,
            (unsigned long long)created, water_removed, total[rows - 1], counted);
    ck_assert_int_gt(water_removed, 0);
    ck_assert_int_eq(now.water, start.water + (int)created - water_removed);
    ck_assert_msg(fabs(counted - nearbyint(counted)) < 1e-6, "the outlet counted %.9g water "
                  "particles: air counted", counted);
    if (water_only) {
        ck_assert_int_eq(air_removed, 0);
        ck_assert_int_gt(air_past_min, 0);
    } else {
        ck_assert_int_gt(air_removed, 0);
        /* free: the table counts each water particle removed, nothing else */
        ck_assert_int_eq((int)nearbyint(counted), water_removed);
    }
    sluice_sim_free(sim);
    free(dir);
}
END_TEST

/* A buffer outlet with phase: all in a two-phase scene imposes on the air
 * that crosses into it the tailwater velocity and the air's density at the
 * tailwater column's hydrostatic pressure, p_b at its surface yt = 0.1 m:
 * above it p = p_b - rho_a g (y - yt), below it (an air pocket) p = p_b +
 * rho_w g (yt - y); the water keeps the water's hydrostatic density. Tested
 * on the state the first after-step hook leaves (1e-12: round-off, as the
 * inlet's). */
START_TEST(outlet_buffer_air_density)
{
    char *yaml = air_box_scene("form: buffer, position: 0.6, depth: 0.1, velocity: 0.5", "pocket");
    sluice_sim *sim = test_load("outlet-buffer-air", yaml, NULL, 0);
    free(yaml);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_of(sim);
    const sluice_real *rho = test_column(sim, "density", 0);
    const sluice_real *u = test_column(sim, "velocity", 0);
    const sluice_real *w = test_column(sim, "velocity", 1);
    int water = 0, air_above = 0, air_below = 0;
    double worst = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_OPEN || !(v->position[0][i] >= 0.6))
            continue;
        const double y = v->position[1][i], below = 0.1 - y;
        double expected;
        if (!phase[i]) {
            expected = water_at(TP_RHO_W * TP_G * fmax(below, 0));
            water++;
        } else if (below > 0) {
            expected = air_at(TP_RHO_W * TP_G * below);
            air_below++;
        } else {
            expected = air_at(TP_RHO_A * TP_G * below);
            air_above++;
        }
        const double error = fabs(rho[i] - expected) / expected;
        worst = fmax(worst, error);
        ck_assert_msg(error <= 1e-12, "phase %d at y = %g m: density %.17g, expected %.17g",
                      phase[i], y, rho[i], expected);
        ck_assert(u[i] == 0.5 && w[i] == 0);
    }
    fprintf(stderr, "buffer outlet, phase all: %d water, %d air above and %d air below the "
                    "tailwater surface imposed; worst density error %.2e\n",
            water, air_above, air_below, worst);
    ck_assert_int_eq(water, 3 * 5);
    ck_assert_int_gt(air_above, 0);
    ck_assert_int_gt(air_below, 0);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}
END_TEST

/* (c) dissolved_oxygen with the air-layer inlet: particles created during
 * the run get initial_concentration Cu = 1.29 when water and 0 when air
 * (dissolved_oxygen's scan of new particles reads the phase the inlet
 * wrote). With D_m = 0 the diffusion and the reaeration source (K ~
 * sqrt(D_m nu)) are exactly zero, so after every step every particle holds
 * Cu or 0 by its phase, exactly. */
START_TEST(inlet_air_layer_dissolved_oxygen)
{
    char *yaml = air_channel_scene("position: 0, depth: 0.1, air_depth: 0.1, velocity: 0.5",
                                   "  dissolved_oxygen: {initial_concentration: 1.29, "
                                   "molecular_diffusivity: 0}\n");
    sluice_sim *sim = test_load("inlet-air-do", yaml, NULL, 0);
    free(yaml);
    const sluice_id first_new = sim->next_id;
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    int steps = 0, created_water = 0, created_air = 0, wrong = 0;
    while (sluice_sim_time(sim) < TP_END - 1e-12) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step failed: %s",
                      sluice_sim_failure(sim));
        steps++;
        const sluice_view *v = sluice_sim_view(sim);
        const uint8_t *phase = phase_of(sim);
        const sluice_real *c = test_column(sim, "dissolved_oxygen", 0);
        created_water = created_air = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] == SLUICE_KIND_WALL)
                continue;
            const sluice_real expected = phase[i] ? 0 : (sluice_real)1.29;
            wrong += c[i] != expected;
            if (v->id[i] >= first_new)
                phase[i] ? created_air++ : created_water++;
        }
    }
    fprintf(stderr, "dissolved oxygen with the air-layer inlet: %d steps to 0.12 s; particles "
                    "created during the run and present: %d water, %d air; %d values not Cu = "
                    "1.29 (water) or 0 (air)\n",
            steps, created_water, created_air, wrong);
    ck_assert_int_eq(wrong, 0);
    ck_assert_int_gt(created_water, 0);
    ck_assert_int_gt(created_air, 0);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}
END_TEST

/* (d) An air layer needs the phase: without two_phase the scene is refused
 * with one message naming air_depth. */
START_TEST(air_layer_refused)
{
    const char *inlet = "position: 0, depth: 0.1, air_depth: 0.1, velocity: 0.5";
    /* tait instead of two_phase */
    char *single = air_channel_with("  tait: {speed_of_sound: 10}\n", inlet, NULL);
    test_load_refused("air-depth-single-phase", single, "air_depth");
    free(single);
}
END_TEST

/* (e) The air vent. A closed box 0.6 x 0.4 m: water 0.2 m deep fed at
 * q = 0.04 m^2/s by an inlet under a gate (x = 0, the lower 0.1 m,
 * submerged 0.1 m), air above. In 0.4 s the inflow adds dV = 0.016 m^2 of
 * water to the box's A = 0.12 m^2 of air.
 *  - Without a vent (the control) the air is compressed: its mean pressure
 *    rises towards B ((A / (A - dV))^gamma_a - 1) above p_b (dV the
 *    water that came in; the water's sloshing rides on it); the test asks
 *    for half of that.
 *  - With the vent (a box in the air's top right corner) the mean air
 *    pressure ends within 20 % of that rise of p_b. From 0.2 s on (the
 *    start's sloshing, with c0 = 10 m/s, pushes air into the vent's lattice
 *    at rest: measured 0.0126 kg of air, 3.2 times the water's volume, in
 *    the first 0.1 s) the air that leaves through the vent (air_vent.csv's
 *    mass_total / rho0_a) is the water's volume that comes in (inlet.csv's
 *    mass_total / rho0_w), within what the change of the air's mean
 *    pressure over that time holds (A |dp| / (gamma_a B)) plus 3 particles
 *    (a particle leaves whole). Air mass balance is exact: the air now plus
 *    the air the vent took is the air at the start; no water reaches the
 *    vent. */
#define VENT_END 0.4
static char *vent_scene(int with_vent)
{
    char *text = NULL;
    ck_assert_int_ge(
        asprintf(&text,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: 1000}\n"
                 "time: {end: %g}\n"
                 "domain: {min: [-0.1, -0.1], max: [0.7, 0.5]}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [0.6, 0.2]}\n"
                 "    - {shape: box, min: [0, 0.2], max: [0.6, 0.4]}\n"
                 "  walls:\n"
                 "    - {shape: polyline, name: box, points: [[-0.1, 0], [0.6, 0], [0.6, 0.4], "
                 "[0, 0.4], [0, 0.1]]}\n"
                 "initial: {density: hydrostatic}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  two_phase: {speed_of_sound: 10, background_pressure: 100, "
                 "air_above: [[0, 0.2]]}\n"
                 "  continuity: {form: volume}\n"
                 "  pressure_gradient: {form: density_product}\n"
                 "  artificial_viscosity: {alpha: 0.1}\n"
                 "  gravity: {}\n"
                 "  dbc: {}\n"
                 "  time_step: {courant: 0.25}\n"
                 "  symplectic: {}\n"
                 "  inlet: {position: 0, depth: 0.1, submergence: 0.1, discharge: 0.04, "
                 "interval: 0.1}\n"
                 "%s",
                 VENT_END,
                 with_vent ? "  air_vent: {box_min: [0.4, 0.3], box_max: [0.6, 0.4], "
                             "interval: 0.1}\n"
                           : ""),
        0);
    return text;
}

static void air_state(sluice_sim *sim, int *count, double *mean_pressure)
{
    const sluice_view *v = sluice_sim_view(sim);
    const uint8_t *phase = phase_of(sim);
    const sluice_real *p = test_column(sim, "pressure", 0);
    double sum = 0;
    int n = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && phase[i]) {
            sum += (double)p[i];
            n++;
        }
    *count = n;
    *mean_pressure = n ? sum / n : 0;
}

START_TEST(air_vent_holds_the_atmosphere)
{
    const double area = 0.6 * 0.2, gamma_a = 1.4;
    double closed_rise = 0;
    double rise[2] = {0, 0};
    for (int with_vent = 0; with_vent < 2; with_vent++) {
        char *yaml = vent_scene(with_vent);
        sluice_sim *sim = test_load(with_vent ? "air-vent" : "air-vent-control", yaml, NULL, 0);
        free(yaml);
        char *dir = test_scratch(with_vent ? "air-vent-run" : "air-vent-control-run");
        ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
        int air_start, air_middle = 0;
        double p_start, p_middle = 0;
        air_state(sim, &air_start, &p_start);
        while (sluice_sim_time(sim) < VENT_END - 1e-12) {
            ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "step failed: %s",
                          sluice_sim_failure(sim));
            if (air_middle == 0 && sluice_sim_time(sim) > VENT_END / 2 - 1e-12)
                air_state(sim, &air_middle, &p_middle);
        }
        int air_end;
        double p_end;
        air_state(sim, &air_end, &p_end);
        ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
        sluice_sim_free(sim);
        rise[with_vent] = p_end - TP_PB;
        char path[4096];
        double inflow[16];
        snprintf(path, sizeof path, "%s/inlet.csv", dir);
        const int inlet_rows = csv_column(path, 4, inflow, 16);
        ck_assert_int_gt(inlet_rows, 1);
        const double water_in = inflow[inlet_rows - 1] / TP_RHO_W;
        if (!with_vent) {
            closed_rise = TP_B * (pow(area / (area - water_in), gamma_a) - 1);
            fprintf(stderr,
                    "air vent control (closed box): %.4g m^2 of water in, air %d -> %d "
                    "particles, mean air pressure %.1f Pa at the end (p_b %g; closed-box rise "
                    "%.1f Pa)\n",
                    water_in, air_start, air_end, p_end, TP_PB, closed_rise);
            ck_assert_int_eq(air_end, air_start);
            ck_assert_double_gt(rise[0], 0.5 * closed_rise);
            free(dir);
            continue;
        }
        double vented[16], water[16];
        snprintf(path, sizeof path, "%s/air_vent.csv", dir);
        const int rows = csv_column(path, 3, vented, 16);
        ck_assert_int_eq(csv_column(path, 4, water, 16), rows);
        ck_assert_int_gt(rows, 1);
        const double air_particle = TP_RHO_A * TP_DX * TP_DX;
        const double out_particles = vented[rows - 1] / air_particle;
        /* the rows at 0.2 s and at the end (interval 0.1 s) */
        const int middle = rows / 2;
        const double air_out = (vented[rows - 1] - vented[middle]) / TP_RHO_A;
        const double water_later = (inflow[inlet_rows - 1] - inflow[inlet_rows / 2]) / TP_RHO_W;
        const double tolerance =
            area * fabs(p_end - p_middle) / (gamma_a * TP_B) + 3 * TP_DX * TP_DX;
        fprintf(stderr,
                "air vent: %.4g m^2 of water in, %.6f air particles out (%.4g kg in the first "
                "0.1 s); from 0.2 s: %.4g m^2 of water in, %.4g m^2 of air out (tolerance "
                "%.3g m^2); air %d -> %d particles, mean air pressure %.1f Pa at 0.2 s, %.1f Pa "
                "at the end (p_b %g; closed box %.1f Pa above it)\n",
                water_in, out_particles, vented[1], water_later, air_out, tolerance, air_start,
                air_end, p_middle, p_end, TP_PB, closed_rise);
        ck_assert_msg(fabs(rise[1]) < 0.2 * closed_rise,
                      "the air is %.1f Pa from p_b with the vent (closed box: %.1f)", rise[1],
                      closed_rise);
        ck_assert_msg(fabs(air_out - water_later) < tolerance,
                      "%.5g m^2 of air left for %.5g m^2 of water", air_out, water_later);
        ck_assert_msg(fabs(out_particles - nearbyint(out_particles)) < 1e-6,
                      "the vent counted %.9g air particles", out_particles);
        ck_assert_int_eq(air_start - air_end, (int)nearbyint(out_particles));
        ck_assert_double_eq(water[rows - 1], 0);
        free(dir);
    }
}
END_TEST

/* (f) The vent needs the phase, and lies between the inlet and the outlet. */
START_TEST(air_vent_refused)
{
    char *yaml = vent_scene(1);
    char *single = NULL;
    ck_assert_int_ge(asprintf(&single, "%s", yaml), 0);
    char *at = strstr(single, "  two_phase:");
    ck_assert_ptr_nonnull(at);
    char *end = strchr(at, '\n');
    memmove(at, end + 1, strlen(end + 1) + 1);
    char *with_tait = NULL;
    ck_assert_int_ge(asprintf(&with_tait, "%s  tait: {speed_of_sound: 10}\n", single), 0);
    test_load_refused("air-vent-single-phase", with_tait, "phase");
    char *upstream = NULL;
    ck_assert_int_ge(asprintf(&upstream, "%s", yaml), 0);
    char *box = strstr(upstream, "box_min: [0.4, 0.3]");
    ck_assert_ptr_nonnull(box);
    memcpy(box, "box_min: [-.1, 0.3]", 19);
    test_load_refused("air-vent-upstream", upstream, "upstream of the inlet");
    char *downstream = NULL;
    ck_assert_int_ge(asprintf(&downstream, "%s  outlet: {position: 0.5}\n", yaml), 0);
    test_load_refused("air-vent-downstream", downstream, "downstream of the outlet");
    /* in the water, and next to it (the water's surface at y = 0.2 m, the
     * kernel support 0.06 m); the vent listed before two_phase, which sets
     * the phases first all the same */
    const char *const boxes[2][2] = {{"box_min: [0.4, 0.05]", "box_max: [0.6, 0.15]"},
                                     {"box_min: [0.4, 0.24]", "box_max: [0.6, 0.40]"}};
    const char *const needles[2] = {"water particles and has", "holds 0 water particles"};
    for (int k = 0; k < 2; k++) {
        char *wet = NULL;
        ck_assert_int_ge(asprintf(&wet, "%s", yaml), 0);
        char *line = strstr(wet, "  air_vent:");
        ck_assert_ptr_nonnull(line);
        char *vent = strndup(line, (size_t)(strchr(line, '\n') + 1 - line));
        ck_assert_ptr_nonnull(vent);
        *line = '\0';
        char *plugins = strstr(wet, "plugins:\n");
        ck_assert_ptr_nonnull(plugins);
        plugins += strlen("plugins:\n");
        char *moved = NULL;
        ck_assert_int_ge(asprintf(&moved, "%.*s%s%s", (int)(plugins - wet), wet, vent, plugins),
                         0);
        char *min = strstr(moved, "box_min: [0.4, 0.3], box_max: [0.6, 0.4]");
        ck_assert_ptr_nonnull(min);
        char *placed = NULL;
        ck_assert_int_ge(asprintf(&placed, "%.*s%s, %s%s", (int)(min - moved), moved,
                                  boxes[k][0], boxes[k][1], min + 40),
                         0);
        free(moved);
        moved = placed;
        test_load_refused(k ? "air-vent-near-water" : "air-vent-in-water", moved, needles[k]);
        free(wet);
        free(vent);
        free(moved);
    }
    free(yaml);
    free(single);
    free(with_tait);
    free(upstream);
    free(downstream);
}
END_TEST

/* A controlled tailwater: the subcritical channel (d = 0.1 m, V = 0.5 m/s,
 * q = 0.05 m^2/s, dx = 0.02 m) with its buffer outlet asked for yt = 0.11 m
 * at x = 0.6 m, starting from Vt = 0.5 m/s. Imposed, that layer drains
 * Vt d_plane, so the water settles at q / Vt = 0.1 m and the section reads
 * 9 % under yt; controlled (control_time 1 s), the gate closes until the
 * section reads yt. Over 6-10 s the section's depth (the same strip sum as
 * the controller, sampled by the test every 0.05 s) averages within 2 % of
 * yt (its samples move by one particle in 22, 4.5 %), the outflow within
 * 2 % of q, and the gate's velocity within 3 % of q / yt. The run with the
 * imposed tailwater is the control: its section stays more than 5 % under
 * yt. */
static void tailwater_run(int controlled, double *depth, double *outflow, double *velocity)
{
    const double dx = 0.02, yt = 0.11, q = 0.05, end = 10, xc = 0.6, strip = 4 * dx;
    char outlet[512];
    snprintf(outlet, sizeof outlet,
             "outlet: {form: buffer, position: 1.0, depth: %g, velocity: 0.5, interval: 0.05%s}",
             yt, controlled ? ", tailwater: controlled, control_position: 0.6, control_time: 1"
                            : "");
    char *yaml = channel_scene(dx, 0.1, 0.5, 1.0, 20,
                               "inlet: {form: buffer, position: 0, depth: 0.1, velocity: 0.5, "
                               "interval: 0.05}",
                               outlet, end, 0.5);
    const char *tag = controlled ? "tailwater-controlled" : "tailwater-imposed";
    sluice_sim *sim = test_load(tag, yaml, NULL, 0);
    free(yaml);
    char *dir = test_scratch(tag);
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    double next = 6, sum = 0, lowest = INFINITY, highest = 0;
    int samples = 0;
    while (sluice_sim_time(sim) < end - 1e-9) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "run stopped: %s",
                      sluice_sim_failure(sim));
        if (sluice_sim_time(sim) + 1e-9 < next)
            continue;
        next += 0.05;
        const section at = measure(sim, xc - strip / 2, xc + strip / 2);
        sum += at.depth;
        lowest = fmin(lowest, at.depth);
        highest = fmax(highest, at.depth);
        samples++;
    }
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    char path[4096];
    snprintf(path, sizeof path, "%s/outlet.csv", dir);
    /* the outflow over 6-10 s from the cumulative mass */
    FILE *f = fopen(path, "r");
    ck_assert_ptr_nonnull(f);
    char line[1024];
    double m6 = NAN, m10 = NAN, t6 = NAN, t10 = NAN;
    while (fgets(line, sizeof line, f)) {
        double t, flux, discharge, momentum, mass;
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf", &t, &flux, &discharge, &momentum, &mass) != 5)
            continue;
        if (isnan(m6) && t >= 6 - 1e-9) {
            m6 = mass;
            t6 = t;
        }
        m10 = mass;
        t10 = t;
    }
    fclose(f);
    *depth = sum / samples;
    *outflow = (m10 - m6) / (1000 * (t10 - t6));
    *velocity = controlled ? csv_last(path, 6) : 0.5;
    fprintf(stderr,
            "tailwater %s: depth at x = %g m over 6-10 s %.5f m (samples %.4f-%.4f, yt %g), "
            "outflow %.5f m^2/s (q %g), layer velocity %.4f m/s (q / yt %.4f)\n",
            controlled ? "controlled" : "imposed", xc, *depth, lowest, highest, yt, *outflow, q,
            *velocity, q / yt);
    sluice_sim_free(sim);
    free(dir);
}

START_TEST(controlled_tailwater)
{
    const double yt = 0.11, q = 0.05;
    double depth, outflow, velocity;
    tailwater_run(1, &depth, &outflow, &velocity);
    ck_assert_msg(fabs(depth / yt - 1) < 0.02, "controlled: depth %g m at the section", depth);
    ck_assert_msg(fabs(outflow / q - 1) < 0.02, "controlled: outflow %g m^2/s", outflow);
    ck_assert_msg(fabs(velocity / (q / yt) - 1) < 0.03, "controlled: gate velocity %g m/s",
                  velocity);
    tailwater_run(0, &depth, &outflow, &velocity);
    ck_assert_msg(depth / yt - 1 < -0.05, "imposed: depth %g m at the section", depth);
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
    tcase_add_test(uniform, backflow_leaves_through_the_inlet);
    tcase_add_test(uniform, backflow_held_on_the_inlet_plane);
    tcase_add_test(uniform, submerged_inlet_density);
    suite_add_tcase(s, uniform);
    /* 4 s of the channel with the free outflow: tag `long` (thousands of
     * steps through the inlet and outlet code that
     * uniform_supercritical_block_frozen reaches in 2 s), left out of the
     * sanitizer pass of tools/run-tests.sh */
    TCase *free_outflow = tcase_create("uniform_channel_free_outflow");
    tcase_set_tags(free_outflow, "long");
    tcase_set_timeout(free_outflow, 600);
    tcase_add_test(free_outflow, uniform_supercritical_free);
    suite_add_tcase(s, free_outflow);
    TCase *tailwater = tcase_create("tailwater_10s");
    tcase_set_tags(tailwater, "validation"); /* 10 s of a channel: release pass only */
    tcase_set_timeout(tailwater, 600);
    tcase_add_test(tailwater, controlled_tailwater);
    suite_add_tcase(s, tailwater);

    TCase *scenes = tcase_create("jump_scenes");
    tcase_set_timeout(scenes, 300);
    tcase_add_loop_test(scenes, jump_scenes_start, 0,
                        (int)(sizeof jump_scenes / sizeof *jump_scenes));
    tcase_add_test(scenes, abrupt_drop_ghost_walls_start);
    suite_add_tcase(s, scenes);
    TCase *kinds = tcase_create("open_particles");
    tcase_add_test(kinds, dbc_walls_not_compressed_by_open_particles);
    suite_add_tcase(s, kinds);
    TCase *two_phase = tcase_create("two_phase");
    tcase_set_timeout(two_phase, 120);
    tcase_add_loop_test(two_phase, inlet_air_layer, 0, 3);
    tcase_add_test(two_phase, inlet_air_layer_3d);
    tcase_add_loop_test(two_phase, outlet_phase_filter, 0, 2);
    tcase_add_test(two_phase, outlet_buffer_air_density);
    tcase_add_test(two_phase, inlet_air_layer_dissolved_oxygen);
    tcase_add_test(two_phase, air_vent_holds_the_atmosphere);
    suite_add_tcase(s, two_phase);
    TCase *input = tcase_create("bad_input");
    tcase_add_test(input, bad_input_refused);
    tcase_add_test(input, air_layer_refused);
    tcase_add_test(input, air_vent_refused);
    suite_add_tcase(s, input);
    return test_run_suite(s);
}
