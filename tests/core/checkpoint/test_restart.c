/* Checkpoints and restart (core/checkpoint/checkpoint.c, docs/reliability.md): a run
 * continued from a checkpoint is bit-identical to the uninterrupted run
 * (every field of every particle, ids included, compared with memcmp), with
 * open boundaries that add and remove particles and with a dam break on dbc
 * walls; tables continue as documented; SIGINT stops a run after a whole
 * step with a checkpoint that does not perturb the run; damaged, foreign
 * and mismatched checkpoints are refused with one message (exit 2). */
#include <dirent.h>
#include <hdf5.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "sim_util.h"
/* Internal: compares the restored particle columns and fields with the saved ones byte by byte (not in sim.h) */
#include "file_checksum.h"
#include "sim_internal.h"

/* A horizontal frictionless channel (penalty_contact) between an inlet at
 * x = 0 and an outlet at x = 1 m (particles added and removed every step),
 * with HDF5 snapshots, the flux tables and the case's gauges and models. */
typedef struct channel_case {
    const char *name;
    const char *inlet, *outlet; /* the plugin lines */
    const char *wall;           /* wall scheme line */
    const char *integrator;
    const char *extra;          /* more plugin lines (gauges, models) */
    const char *tables[8];      /* tables the run writes, NULL-terminated */
} channel_case;

static const channel_case channel_cases[] = {
    {"buffer-free",
     "inlet: {form: buffer, position: 0, depth: 0.1, velocity: 0.5, interval: 0.05}",
     "outlet: {form: free, position: 1.0, interval: 0.05}", "penalty_contact: {}",
     "predictor_corrector: {}",
     "  point_gauge: {points: [[0.5, 0.05]], fields: 'pressure, velocity', interval: 0.02}\n",
     {"inlet.csv", "outlet.csv", "points.csv", NULL}},
    /* seed 000's boundaries: the pre-placed block and the frozen outlet; every
     * gauge that keeps state across steps */
    {"block-frozen",
     "inlet: {form: block, position: 0, depth: 0.1, velocity: 0.5, interval: 0.05}",
     "outlet: {form: frozen, position: 1.0, interval: 0.05}", "penalty_contact: {}",
     "symplectic: {}",
     "  section_gauge: {positions: [0.3, 0.7], interval: 0.02}\n"
     "  free_surface_gauge: {positions: [0.5], interval: 0.02}\n"
     "  energy_gauge: {interval: 0.02}\n"
     "  wall_monitor: {interval: 0.02}\n"
     "  vorticity: {interval: 0.1}\n",
     {"inlet.csv", "outlet.csv", "sections.csv", "free_surface.csv", "energy.csv", "walls.csv",
      NULL}},
    /* seed 004's boundaries: the inlet buffer and the tailwater buffer, with
     * k-epsilon (the inlet sets k and epsilon) on DBC walls and Verlet */
    {"buffer-buffer",
     "inlet: {form: buffer, position: 0, depth: 0.1, velocity: 0.5, interval: 0.05}",
     "outlet: {form: buffer, position: 1.0, depth: 0.1, velocity: 0.5, interval: 0.05}",
     "dbc: {}", "verlet: {euler_every: 7}",
     "  velocity_gradient: {}\n"
     "  k_epsilon: {length_scale: 0.05}\n"
     "  turbulent_stress: {form: eddy_viscosity}\n",
     {"inlet.csv", "outlet.csv", NULL}},
    /* the one-evaluation predictor-corrector with particles entering (zero
     * lagged rates) and leaving; that its restart continues with the lagged
     * rates rather than evaluating afresh is checked on the dam break, where
     * the two differ (dam_break_restart_bit_identical) */
    {"buffer-free-pec",
     "inlet: {form: buffer, position: 0, depth: 0.1, velocity: 0.5, interval: 0.05}",
     "outlet: {form: free, position: 1.0, interval: 0.05}", "penalty_contact: {}",
     "predictor_corrector: {mode: pec}",
     "  point_gauge: {points: [[0.5, 0.05]], fields: 'pressure, velocity', interval: 0.02}\n",
     {"inlet.csv", "outlet.csv", "points.csv", NULL}},
};

static char *channel_scene(const channel_case *c, double end, double checkpoint)
{
    char *yaml = NULL;
    /* the block inlet holds the whole inflow upstream */
    const double upstream = strcmp(c->name, "block-frozen") == 0 ? 0.5 * end + 0.3 : 0.5;
    ck_assert_int_ge(
        asprintf(&yaml,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
                 "time: {end: %.17g}\n"
                 "domain: {min: [%.17g, -0.2], max: [1.5, 0.6]}\n"
                 "checkpoint: {interval: %.17g, keep: 0}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [1.0, 0.1], velocity: [0.5, 0]}\n"
                 "  walls:\n"
                 "    - {shape: polyline, points: [[%.17g, 0], [1.4, 0]], name: bed}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  tait: {speed_of_sound: 20}\n"
                 "  continuity: {}\n"
                 "  delta_sph: {delta: 0.1, form: fourtakas}\n"
                 "  pressure_gradient: {}\n"
                 "  artificial_viscosity: {alpha: 0.02}\n"
                 "  gravity: {}\n"
                 "  %s\n"
                 "  time_step: {courant: 0.25}\n"
                 "  %s\n"
                 "  %s\n"
                 "  %s\n"
                 "%s"
                 "  hdf5: {interval: 0.1}\n",
                 end, -upstream - 0.2, checkpoint, -upstream - 0.16, c->wall, c->integrator,
                 c->inlet, c->outlet, c->extra),
        0);
    return yaml;
}

/* The 2D dam break of configs/dam_break_2d.yaml at dx = 0.04 m on dbc walls,
 * with the Verlet integrator (its Euler-step cycle is plugin state), the
 * periodic pressure filter and the front gauge. */
static char *dam_break_scene(double end, double checkpoint, const char *integrator)
{
    char *yaml = NULL;
    ck_assert_int_ge(
        asprintf(&yaml,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.04, smoothing_length_ratio: 1.5}\n"
                 "time: {end: %.17g}\n"
                 "domain: {min: [-0.2, -0.2], max: [4.2, 8.0]}\n"
                 "checkpoint: {interval: %.17g, keep: 0}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [1.0, 2.0]}\n"
                 "  walls:\n"
                 "    - {shape: tank, min: [0, 0], max: [4.0, 3.0], name: tank}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  tait: {speed_of_sound: 62.6}\n"
                 "  continuity: {}\n"
                 "  delta_sph: {delta: 0.1, form: fourtakas}\n"
                 "  pressure_gradient: {}\n"
                 "  artificial_viscosity: {alpha: 0.1}\n"
                 "  gravity: {}\n"
                 "  dbc: {}\n"
                 "  pressure_smoothing: {every: 7}\n"
                 "  time_step: {courant: 0.2}\n"
                 "  %s\n"
                 "  front_gauge: {interval: 0.01, origin: 0.0}\n"
                 "  hdf5: {interval: 0.05}\n",
                 end, checkpoint, integrator),
        0);
    return yaml;
}

/* Runs a loaded simulation from its current state to the end. */
static void run_to_end(sluice_sim *sim, const char *dir)
{
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    const double end = sluice_sim_end_time(sim);
    while (sluice_sim_time(sim) < end - 1e-12 * (end > 1 ? end : 1)) {
        int status = sluice_sim_step(sim);
        ck_assert_msg(status == SLUICE_RUN_COMPLETE, "step failed: %s", sluice_sim_failure(sim));
    }
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
}

/* The whole file at `path` (malloc'd) and its size. */
static void *read_bytes(const char *path, long *size)
{
    FILE *f = fopen(path, "rb");
    ck_assert_ptr_nonnull(f);
    ck_assert_int_eq(fseek(f, 0, SEEK_END), 0);
    *size = ftell(f);
    ck_assert_int_ge(*size, 0);
    ck_assert_int_eq(fseek(f, 0, SEEK_SET), 0);
    void *bytes = malloc((size_t)*size + 1);
    ck_assert_ptr_nonnull(bytes);
    ck_assert_int_eq(fread(bytes, 1, (size_t)*size, f), (size_t)*size);
    fclose(f);
    return bytes;
}

/* The checkpoint of `dir` with the lowest step (the one at half time). */
static char *first_checkpoint(const char *dir, int *count)
{
    DIR *d = opendir(dir);
    ck_assert_ptr_nonnull(d);
    char best[256] = "";
    *count = 0;
    for (struct dirent *e; (e = readdir(d));) {
        size_t n = strlen(e->d_name);
        if (strncmp(e->d_name, "checkpoint_", 11) != 0 || n < 4 ||
            strcmp(e->d_name + n - 3, ".h5") != 0)
            continue;
        (*count)++;
        if (!best[0] || strcmp(e->d_name, best) < 0)
            snprintf(best, sizeof best, "%s", e->d_name);
    }
    closedir(d);
    ck_assert_msg(best[0], "no checkpoint in %s", dir);
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", dir, best), 0);
    return path;
}

/* Every field of every particle, ids included, bit for bit. */
static void assert_identical(sluice_sim *a, sluice_sim *b, const char *what)
{
    const sluice_view *va = sluice_sim_view(a), *vb = sluice_sim_view(b);
    ck_assert_msg(va->count == vb->count, "%s: %u particles against %u", what, va->count,
                  vb->count);
    ck_assert_msg(sluice_sim_steps(a) == sluice_sim_steps(b), "%s: %lld steps against %lld", what,
                  (long long)sluice_sim_steps(a), (long long)sluice_sim_steps(b));
    ck_assert_msg(memcmp(&a->time, &b->time, sizeof a->time) == 0, "%s: t = %.17g against %.17g",
                  what, a->time, b->time);
    ck_assert_msg(a->next_id == b->next_id && a->removed == b->removed,
                  "%s: next id %llu / %llu, removed %llu / %llu", what,
                  (unsigned long long)a->next_id, (unsigned long long)b->next_id,
                  (unsigned long long)a->removed, (unsigned long long)b->removed);
    ck_assert_uint_eq(a->field_count, b->field_count);
    for (uint32_t f = 0; f < a->field_count; f++) {
        const sluice_field_entry *e = &a->fields[f];
        for (uint32_t c = 0; c < e->components; c++) {
            const int32_t col = e->column + (int32_t)c;
            const size_t bytes = (size_t)va->count * a->particles.element_size[col];
            ck_assert_msg(memcmp(a->particles.columns[col], b->particles.columns[col], bytes) == 0,
                          "%s: field '%s' component %u differs", what, e->name, c);
        }
    }
}

static char *read_or_fail(const char *dir, const char *name)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", dir, name), 0);
    char *text = test_read_file(path);
    ck_assert_msg(text != NULL, "cannot read %s", path);
    free(path);
    return text;
}

/* Inlet and outlet add and remove particles every step; the run to T with a
 * checkpoint at T/2 and the run restarted from it into the same directory
 * end identical, and so do their tables (truncated at the checkpoint and
 * continued). One test per pair of open boundaries (_i: the case). */
START_TEST(open_boundaries_restart_bit_identical)
{
    const channel_case *c = &channel_cases[_i];
    const double end = 0.4;
    char *yaml = channel_scene(c, end, end / 2);
    char tag[96], out[128];
    snprintf(tag, sizeof tag, "restart-%s", c->name);
    snprintf(out, sizeof out, "restart-%s-out", c->name);
    sluice_sim *full = test_load(tag, yaml, NULL, 0);
    char *dir = test_scratch(out);
    run_to_end(full, dir);
    int checkpoints = 0;
    char *checkpoint = first_checkpoint(dir, &checkpoints);
    ck_assert_int_eq(checkpoints, 2); /* T/2 and T, keep: 0 keeps both */
    int table_count = 0;
    while (c->tables[table_count])
        table_count++;
    char *before[8];
    for (int t = 0; t < table_count; t++)
        before[t] = read_or_fail(dir, c->tables[t]);
    char *xdmf_before = read_or_fail(dir, "particles.xdmf");

    sluice_sim *resumed = test_load(tag, yaml, NULL, 0);
    char error[2048];
    double t0 = sluice_wall_clock();
    ck_assert_msg(sluice_sim_restart(resumed, checkpoint, error, sizeof error) == SLUICE_OK, "%s",
                  error);
    const double read_seconds = sluice_wall_clock() - t0;
    ck_assert_msg(fabs(sluice_sim_time(resumed) - end / 2) < 1e-12, "checkpoint at t = %.17g",
                  sluice_sim_time(resumed));
    const uint64_t id_at_checkpoint = resumed->next_id, removed_at_checkpoint = resumed->removed;
    const int64_t step_at_checkpoint = sluice_sim_steps(resumed);
    run_to_end(resumed, dir);
    assert_identical(full, resumed, c->name);
    /* the continued half added particles (the block inlet placed them all
     * at the start), and removed some unless the outlet keeps them (frozen) */
    if (strstr(c->inlet, "block") == NULL)
        ck_assert_uint_gt(resumed->next_id, id_at_checkpoint);
    if (strstr(c->outlet, "frozen") == NULL)
        ck_assert_uint_gt(resumed->removed, removed_at_checkpoint);
    for (int t = 0; t < table_count; t++) {
        char *after = read_or_fail(dir, c->tables[t]);
        ck_assert_msg(strcmp(before[t], after) == 0,
                      "%s: %s of the continued run differs from the uninterrupted run's", c->name,
                      c->tables[t]);
        free(after);
        free(before[t]);
    }
    char *xdmf_after = read_or_fail(dir, "particles.xdmf");
    ck_assert_msg(strcmp(xdmf_before, xdmf_after) == 0,
                  "%s: the snapshot index of the continued run differs", c->name);
    free(xdmf_before);
    free(xdmf_after);
    struct stat st;
    ck_assert_int_eq(stat(checkpoint, &st), 0);
    fprintf(stderr,
            "restart, channel %s: %u particles at T = %g s, ids 0..%llu, %llu removed; checkpoint "
            "at step %lld (t = %g s): %lld bytes, read in %.3f s; steps %lld; every field "
            "identical, %d tables and the snapshot index identical\n",
            c->name, sluice_sim_view(full)->count, end, (unsigned long long)full->next_id,
            (unsigned long long)full->removed, (long long)step_at_checkpoint, end / 2,
            (long long)st.st_size, read_seconds, (long long)sluice_sim_steps(full), table_count);
    sluice_sim_free(full);
    sluice_sim_free(resumed);
    free(checkpoint);
    free(dir);
    free(yaml);
}
END_TEST

/* Rows of a table with time > t (the header first), as text. */
static char *rows_after(const char *text, double t)
{
    size_t n = strlen(text);
    char *out = calloc(n + 1, 1);
    ck_assert_ptr_nonnull(out);
    const char *line = text;
    int first = 1;
    while (*line) {
        const char *next = strchr(line, '\n');
        size_t len = next ? (size_t)(next - line + 1) : strlen(line);
        if (first || strtod(line, NULL) > t)
            strncat(out, line, len);
        first = 0;
        line += len;
    }
    return out;
}

/* The dam break on dbc walls (pressure filter every 7 steps) to T, restarted
 * from T/2 into a new directory: identical; its front table holds the header
 * and the rows after T/2, as the uninterrupted run's. The same restart on two
 * threads agrees within round-off. Two integrators whose state crosses the
 * checkpoint: Verlet (its Euler-step cycle and the previous velocity) and the
 * one-evaluation predictor-corrector (the previous step's rates, which an
 * evaluation at the restart would replace: 2e-6 m/s in velocity by T here). */
static const char *const restart_integrators[] = {"verlet: {euler_every: 40}",
                                                  "predictor_corrector: {mode: pec}"};

START_TEST(dam_break_restart_bit_identical)
{
    const double end = 0.12;
    char *yaml = dam_break_scene(end, end / 2, restart_integrators[_i]);
    char name[4][64];
    snprintf(name[0], sizeof name[0], "restart-dam%d", _i);
    snprintf(name[1], sizeof name[1], "restart-dam%d-out", _i);
    snprintf(name[2], sizeof name[2], "restart-dam%d-new", _i);
    snprintf(name[3], sizeof name[3], "restart-dam%d-2", _i);
    sluice_sim *full = test_load(name[0], yaml, NULL, 0);
    char *dir = test_scratch(name[1]);
    double t0 = sluice_wall_clock();
    run_to_end(full, dir);
    const double full_seconds = sluice_wall_clock() - t0;
    int checkpoints = 0;
    char *checkpoint = first_checkpoint(dir, &checkpoints);

    sluice_sim *resumed = test_load(name[0], yaml, NULL, 0);
    char error[2048];
    ck_assert_msg(sluice_sim_restart(resumed, checkpoint, error, sizeof error) == SLUICE_OK, "%s",
                  error);
    const double t_checkpoint = sluice_sim_time(resumed);
    char *fresh = test_scratch(name[2]);
    run_to_end(resumed, fresh);
    assert_identical(full, resumed, "dam break");
    char *whole = read_or_fail(dir, "front.csv"), *continued = read_or_fail(fresh, "front.csv");
    char *expected = rows_after(whole, t_checkpoint);
    ck_assert_msg(strcmp(expected, continued) == 0,
                  "front.csv in a new directory: expected the header and the rows after t = %g s",
                  t_checkpoint);
    ck_assert_int_gt(test_count_lines(continued, ","), 3);
    /* a directory that holds another run's front.csv (the same header,
     * every digit of its rows changed, longer than the checkpointed table):
     * it is started anew, not cut at the checkpoint's length in the middle
     * of a row (the rows' bytes hash differently) */
    {
        char other_name[64];
        snprintf(other_name, sizeof other_name, "restart-dam%d-other", _i);
        char *other = test_scratch(other_name);
        char *alien = strdup(whole);
        ck_assert_ptr_nonnull(alien);
        for (char *c = strchr(alien, '\n') + 1; *c; c++)
            if (*c >= '0' && *c <= '8')
                (*c)++;
        free(test_write_file(other, "front.csv", alien));
        sluice_sim *again = test_load(name[0], yaml, NULL, 0);
        ck_assert_msg(sluice_sim_restart(again, checkpoint, error, sizeof error) == SLUICE_OK,
                      "%s", error);
        run_to_end(again, other);
        char *third = read_or_fail(other, "front.csv");
        ck_assert_msg(strcmp(expected, third) == 0,
                      "front.csv over another run's: expected the header and the rows after "
                      "t = %g s, got\n%s",
                      t_checkpoint, third);
        sluice_sim_free(again);
        free(third);
        free(alien);
        free(other);
    }
    /* the XDMF index of the new directory lists only its own snapshots */
    char *xdmf = read_or_fail(fresh, "particles.xdmf");
    ck_assert_int_eq(test_count_lines(xdmf, "particles_000000.h5"), 0);
    ck_assert_int_gt(test_count_lines(xdmf, "<Time Value"), 0);

    /* two threads (a child `sluice run --threads 2 --restart`, with passive
     * OpenMP waiting on this shared machine): its final checkpoint holds the
     * same state within round-off (the sums run in a fixed order, so in
     * practice bit for bit) */
    char *scene_dir = test_scratch(name[3]);
    char *scene = test_write_file(scene_dir, "scene.yaml", yaml);
    char *command = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&command,
                              "OMP_WAIT_POLICY=passive %s/sluice run %s --out %s/out --threads 2 "
                              "--restart %s --quiet 2>&1",
                              test_build_dir(), scene, scene_dir, checkpoint),
                     0);
    ck_assert_msg(test_popen(command, &output) == 0, "2-thread restart failed:\n%s", output);
    char *out2 = NULL;
    ck_assert_int_ge(asprintf(&out2, "%s/out", scene_dir), 0);
    char last[4096];
    snprintf(last, sizeof last, "%s/checkpoint_%09lld.h5", out2, (long long)sluice_sim_steps(full));
    char set[64];
    snprintf(set, sizeof set, "time.end=%.17g", 2 * end);
    const char *sets[] = {set};
    sluice_sim *two = test_load(name[3], yaml, sets, 1);
    ck_assert_msg(sluice_sim_restart(two, last, error, sizeof error) == SLUICE_OK, "%s", error);
    const sluice_view *va = sluice_sim_view(full);
    const sluice_view *vb = sluice_sim_view(two);
    ck_assert_uint_eq(va->count, vb->count);
    ck_assert_int_eq(sluice_sim_steps(full), sluice_sim_steps(two));
    double worst = 0;
    for (sluice_index i = 0; i < va->count; i++) {
        ck_assert(va->id[i] == vb->id[i]);
        for (uint32_t d = 0; d < 2; d++)
            worst = fmax(worst, fabs((double)va->position[d][i] - (double)vb->position[d][i]));
    }
    ck_assert_msg(worst <= 1e-9, "positions on 2 threads differ by %g m", worst);
    /* the restarted run's run.json: the whole run's counters, and this
     * invocation's particle-steps, over whose wall time the rate is taken
     * (the dam break neither adds nor removes particles) */
    char *json2 = read_or_fail(out2, "run.json");
    long long checkpoint_step = -1;
    const char *base = strrchr(checkpoint, '/');
    ck_assert_int_eq(sscanf(base ? base + 1 : checkpoint, "checkpoint_%lld.h5", &checkpoint_step),
                     1);
    const double particles = (double)va->count, steps = (double)sluice_sim_steps(full);
    ck_assert_double_eq(test_json_number(json2, "restarted_at_step"), (double)checkpoint_step);
    ck_assert_double_eq(test_json_number(json2, "steps"), steps);
    ck_assert_double_eq(test_json_number(json2, "particle_steps"), particles * steps);
    const double this_run = test_json_number(json2, "particle_steps_this_run");
    ck_assert_double_eq(this_run, particles * (steps - (double)checkpoint_step));
    const double rate = test_json_number(json2, "particle_steps_per_second"),
                 wall = test_json_number(json2, "wall_seconds");
    /* run.json prints the rate to 6 significant digits */
    ck_assert_msg(wall > 0 && fabs(rate * wall - this_run) <= 1e-5 * this_run,
                  "rate %g x wall %g s = %g, not this invocation's %g particle-steps", rate, wall,
                  rate * wall, this_run);
    free(json2);
    free(command);
    free(output);
    fprintf(stderr,
            "restart, dam break, %s: %u particles, %lld steps to T = %g s (%.2f s on 1 thread), "
            "checkpoint at t = %.9g s; every field identical; restarted on 2 threads: largest "
            "position difference %g m\n",
            restart_integrators[_i], va->count, (long long)sluice_sim_steps(full), end, full_seconds,
            t_checkpoint, worst);
    sluice_sim_free(full);
    sluice_sim_free(resumed);
    sluice_sim_free(two);
    free(whole);
    free(continued);
    free(expected);
    free(xdmf);
    free(checkpoint);
    free(dir);
    free(fresh);
    free(scene_dir);
    free(scene);
    free(out2);
    free(yaml);
}
END_TEST

/* SIGINT to a running `sluice run`: it stops after a whole step with exit
 * status 5 and a checkpoint; continuing from it gives the state an
 * uninterrupted run (which wrote no checkpoint) reaches: the signal
 * checkpoint does not perturb the run. */
START_TEST(sigint_stops_with_a_checkpoint)
{
    char *yaml = dam_break_scene(100.0, 0, "symplectic: {}");
    char *scene_dir = test_scratch("restart-signal");
    char *scene = test_write_file(scene_dir, "scene.yaml", yaml);
    char *out = NULL, *front = NULL, *sluice = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", scene_dir), 0);
    ck_assert_int_ge(asprintf(&front, "%s/front.csv", out), 0);
    ck_assert_int_ge(asprintf(&sluice, "%s/sluice", test_build_dir()), 0);
    pid_t child = fork();
    ck_assert_int_ge(child, 0);
    if (child == 0) {
        freopen("/dev/null", "w", stdout);
        execl(sluice, sluice, "run", scene, "--out", out, "--threads", "1", "--quiet",
              "--no-progress", (char *)NULL);
        _exit(127);
    }
    /* wait until it is stepping (a few rows of the front table), then stop it */
    int rows = 0;
    for (int waited = 0; waited < 1200 && rows < 4; waited++) {
        struct timespec pause = {0, 50000000};
        nanosleep(&pause, NULL);
        char *text = test_read_file(front);
        rows = text ? test_count_lines(text, ",") : 0;
        free(text);
    }
    ck_assert_msg(rows >= 4, "the child run wrote no rows in 60 s");
    ck_assert_int_eq(kill(child, SIGINT), 0);
    int status = 0;
    ck_assert_int_eq(waitpid(child, &status, 0), child);
    ck_assert_msg(WIFEXITED(status) && WEXITSTATUS(status) == SLUICE_RUN_INTERRUPTED,
                  "exit status %d (signalled: %d)", WIFEXITED(status) ? WEXITSTATUS(status) : -1,
                  WIFSIGNALED(status));
    char *json = read_or_fail(out, "run.json");
    ck_assert_ptr_nonnull(strstr(json, "\"status\": \"interrupted\""));
    int checkpoints = 0;
    char *checkpoint = first_checkpoint(out, &checkpoints);
    ck_assert_int_eq(checkpoints, 1);

    /* continue 0.01 s past the checkpoint; an uninterrupted run to the same end */
    sluice_sim *resumed = test_load("restart-signal-a", yaml, NULL, 0);
    char error[2048];
    ck_assert_msg(sluice_sim_restart(resumed, checkpoint, error, sizeof error) == SLUICE_OK, "%s",
                  error);
    const double t_stop = sluice_sim_time(resumed);
    const int64_t step_stop = sluice_sim_steps(resumed);
    ck_assert(t_stop > 0 && step_stop > 0);
    char set[64];
    snprintf(set, sizeof set, "time.end=%.17g", t_stop + 0.01);
    const char *sets[] = {set};
    sluice_sim_free(resumed);
    resumed = test_load("restart-signal-a", yaml, sets, 1);
    ck_assert_msg(sluice_sim_restart(resumed, checkpoint, error, sizeof error) == SLUICE_OK, "%s",
                  error);
    char *dir_a = test_scratch("restart-signal-out-a"), *dir_b = test_scratch("restart-signal-out-b");
    run_to_end(resumed, dir_a);
    sluice_sim *full = test_load("restart-signal-b", yaml, sets, 1);
    run_to_end(full, dir_b);
    assert_identical(full, resumed, "after SIGINT");
    fprintf(stderr,
            "restart, SIGINT: stopped at step %lld, t = %.9g s (exit 5); continued to t = %.9g s: "
            "identical to the uninterrupted run\n",
            (long long)step_stop, t_stop, t_stop + 0.01);
    sluice_sim_free(resumed);
    sluice_sim_free(full);
    free(json);
    free(checkpoint);
    free(dir_a);
    free(dir_b);
    free(scene_dir);
    free(scene);
    free(out);
    free(front);
    free(sluice);
    free(yaml);
}
END_TEST

/* A restart whose scene has other neighbour cells (here another smoothing
 * length; likewise another kernel or skin) cannot take the run's neighbour
 * list: it builds one afresh, and each particle keeps its whole state. (The
 * fresh build sorts the particles anew; until 2026-11-23 the current
 * positions were then put back in the old order, under the other fields of
 * other particles, before the refusal that stopped such restarts.) */
START_TEST(restart_with_other_cells_keeps_each_particle)
{
    char *yaml = dam_break_scene(0.06, 0.03, "verlet: {euler_every: 40}");
    sluice_sim *run = test_load("restart-cells", yaml, NULL, 0);
    char *dir = test_scratch("restart-cells-out");
    run_to_end(run, dir);
    int checkpoints = 0;
    char *checkpoint = first_checkpoint(dir, &checkpoints);
    char error[2048];
    sluice_sim *same = test_load("restart-cells", yaml, NULL, 0);
    ck_assert_msg(sluice_sim_restart(same, checkpoint, error, sizeof error) == SLUICE_OK, "%s",
                  error);
    const char *sets[] = {"particles.smoothing_length_ratio=1.2"};
    sluice_sim *other = test_load("restart-cells", yaml, sets, 1);
    ck_assert_msg(sluice_sim_restart(other, checkpoint, error, sizeof error) == SLUICE_OK, "%s",
                  error);
    const sluice_view *va = sluice_sim_view(same), *vb = sluice_sim_view(other);
    ck_assert_uint_eq(va->count, vb->count);
    /* ids are the particles' identity: index them in `same` */
    sluice_id top = 0;
    for (sluice_index i = 0; i < va->count; i++)
        top = va->id[i] > top ? va->id[i] : top;
    sluice_index *at = malloc(((size_t)top + 1) * sizeof *at);
    ck_assert_ptr_nonnull(at);
    for (sluice_index i = 0; i < va->count; i++)
        at[va->id[i]] = i;
    sluice_index moved = 0;
    for (sluice_index k = 0; k < vb->count; k++) {
        ck_assert(vb->id[k] <= top);
        const sluice_index i = at[vb->id[k]];
        moved += i != k;
        ck_assert_uint_eq(va->kind[i], vb->kind[k]);
        for (uint32_t f = 0; f < same->field_count; f++) {
            const sluice_field_entry *e = &same->fields[f];
            for (uint32_t c = 0; c < e->components; c++) {
                const int32_t col = e->column + (int32_t)c;
                const size_t size = same->particles.element_size[col];
                const char *a = (const char *)same->particles.columns[col] + (size_t)i * size;
                const char *b = (const char *)other->particles.columns[col] + (size_t)k * size;
                ck_assert_msg(memcmp(a, b, size) == 0,
                              "particle id %llu: field '%s' component %u differs after the "
                              "restart with other cells",
                              (unsigned long long)vb->id[k], e->name, c);
            }
        }
    }
    /* the fresh build did reorder them, or the test tests nothing */
    ck_assert_uint_gt(moved, 0);
    /* and the run goes on */
    char *fresh = test_scratch("restart-cells-new");
    run_to_end(other, fresh);
    fprintf(stderr, "restart with other cells: %u particles, %u in another place after the "
                    "fresh neighbour build, every field of each kept\n",
            vb->count, moved);
    free(at);
    free(fresh);
    free(checkpoint);
    free(dir);
    free(yaml);
    sluice_sim_free(run);
    sluice_sim_free(same);
    sluice_sim_free(other);
}
END_TEST

/* One message naming the file, exit status 2, for every bad checkpoint. */
/* A copy of a checkpoint without the state group of one plugin: what a
 * version of that plugin without checkpoint state wrote. */
static char *without_state_of(const char *checkpoint, const char *bytes, long size,
                              const char *dir, const char *plugin)
{
    char *path = NULL, *link = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/without_%s.h5", dir, plugin), 0);
    FILE *f = fopen(path, "wb");
    ck_assert_ptr_nonnull(f);
    /* the HDF5 file without its checksum trailer, edited, then summed again:
     * what that version of sluice would have written */
    const size_t hdf5_size = (size_t)size - SLUICE_CHECKSUM_BYTES;
    ck_assert_int_eq(fwrite(bytes, 1, hdf5_size, f), hdf5_size);
    fclose(f);
    hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert_msg(file >= 0, "cannot open %s (a copy of %s)", path, checkpoint);
    ck_assert_int_ge(asprintf(&link, "plugins/%s", plugin), 0);
    ck_assert_msg(H5Lexists(file, link, H5P_DEFAULT) > 0, "%s has no group %s", checkpoint, link);
    ck_assert_int_ge(H5Ldelete(file, link, H5P_DEFAULT), 0);
    H5Fclose(file);
    char error[600];
    ck_assert_msg(sluice_checksum_append(path, error, sizeof error) == 0, "%s", error);
    free(link);
    return path;
}

static void refused(const char *scene, const char *checkpoint, const char *needle)
{
    char *dir = test_scratch("restart-refused");
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/out --restart %s --quiet", scene, dir,
                              checkpoint),
                     0);
    int status = test_sluice(args, &output);
    ck_assert_msg(status == 2, "exit status %d for %s:\n%s", status, checkpoint, output);
    ck_assert_msg(strstr(output, needle) != NULL, "no '%s' in:\n%s", needle, output);
    ck_assert_msg(strstr(output, checkpoint) != NULL, "the message does not name the file:\n%s",
                  output);
    ck_assert_msg(test_count_lines(output, "error") == 1, "not one message:\n%s", output);
    fprintf(stderr, "refused: %s", output);
    free(args);
    free(output);
    free(dir);
}

START_TEST(bad_checkpoints_refused)
{
    /* a good checkpoint of a short channel run */
    char *yaml = channel_scene(&channel_cases[0], 0.02, 0.01);
    char *dir = test_scratch("restart-bad");
    char *scene = test_write_file(dir, "scene.yaml", yaml);
    char *args = NULL;
    ck_assert_int_ge(
        asprintf(&args, "run %s --out %s/out --quiet --set checkpoint.keep=1", scene, dir), 0);
    ck_assert_int_eq(test_sluice(args, NULL), 0);
    char *out = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", dir), 0);
    int checkpoints = 0;
    char *good = first_checkpoint(out, &checkpoints);
    ck_assert_int_eq(checkpoints, 1); /* at 0.01 s and 0.02 s, keep: 1 */

    /* truncated: the first half of it */
    long size = 0;
    char *bytes = read_bytes(good, &size);
    char *truncated = NULL, *text = NULL, *missing = NULL;
    ck_assert_int_ge(asprintf(&truncated, "%s/truncated_checkpoint.h5", dir), 0);
    FILE *f = fopen(truncated, "wb");
    fwrite(bytes, 1, (size_t)size / 2, f);
    fclose(f);
    refused(scene, truncated, "it does not end in a sluice checksum");
    /* not HDF5 at all */
    text = test_write_file(dir, "text_checkpoint.h5", "time,x\n0,1\n");
    refused(scene, text, "not a checkpoint");
    /* one bit changed anywhere in it: the checksum (before HDF5 reads a
     * byte); at the first byte, the middle and in the trailer's hash */
    const long at[3] = {0, size / 2, size - 1};
    for (int k = 0; k < 3; k++) {
        char *flipped = NULL;
        ck_assert_int_ge(asprintf(&flipped, "%s/flipped_%d.h5", dir, k), 0);
        bytes[at[k]] ^= 0x20;
        f = fopen(flipped, "wb");
        ck_assert_int_eq(fwrite(bytes, 1, (size_t)size, f), (size_t)size);
        fclose(f);
        bytes[at[k]] ^= 0x20;
        refused(scene, flipped, "its checksum does not match its");
        free(flipped);
    }
    ck_assert_int_ge(asprintf(&missing, "%s/no_such_checkpoint.h5", dir), 0);
    refused(scene, missing, "No such file");
    /* another scene: the dam break's plugins, and a 3D scene */
    char *dam = dam_break_scene(1, 0, "symplectic: {}");
    char *dam_path = test_write_file(dir, "dam.yaml", dam);
    refused(dam_path, good, "plugins do not match");
    char *three = NULL, *config = test_config("dam_break_3d.yaml");
    ck_assert_int_ge(asprintf(&three, "%s --set particles.spacing=0.1", config), 0);
    refused(three, good, "it holds a 2D run and the scene is 3D");
    /* another spacing: the particles' masses and lattice are the run's; the
     * message names the run's spacing (the scene's is 0.02 m) */
    char *finer = NULL;
    ck_assert_int_ge(asprintf(&finer, "%s --set particles.spacing=0.01", scene), 0);
    refused(finer, good, "--set particles.spacing=0.02");
    free(finer);
    /* a plugin whose state is missing (a checkpoint of an older version of
     * it): the gauge needs its rows count, and the message names the plugin,
     * the array and the file; the predictor-corrector (state since 1.1.0)
     * does without, so the restart goes on */
    char *later = NULL; /* the good checkpoint is the run's last, at its end */
    ck_assert_int_ge(asprintf(&later, "%s --set time.end=0.03", scene), 0);
    char *no_gauge = without_state_of(good, bytes, size, dir, "point_gauge");
    refused(later, no_gauge,
            "plugin 'point_gauge' could not load its state: state array 'rows_written'");
    refused(later, no_gauge, "holds no state of this plugin");
    char *no_pc = without_state_of(good, bytes, size, dir, "predictor_corrector");
    char *resumed = NULL, *resumed_dir = test_scratch("restart-older-plugin");
    ck_assert_int_ge(asprintf(&resumed, "run %s --out %s/out --restart %s --quiet", later,
                              resumed_dir, no_pc),
                     0);
    char *output = NULL;
    ck_assert_msg(test_sluice(resumed, &output) == 0, "restart without predictor_corrector's "
                  "state failed:\n%s", output);
    free(output);
    free(resumed);
    free(resumed_dir);
    free(no_gauge);
    free(no_pc);
    free(later);
    free(config);
    free(bytes);
    free(truncated);
    free(text);
    free(missing);
    free(dam);
    free(dam_path);
    free(three);
    free(good);
    free(out);
    free(args);
    free(scene);
    free(dir);
    free(yaml);
}
END_TEST

/* Edits of a checkpoint, made through HDF5 behind a valid checksum, that
 * the checkpoint fuzzer found crashing, hanging or allocating for sizes it
 * had not checked (tests/core/fuzz/fuzz_checkpoint.c, docs/reliability.md). */
static void requests_declared_huge(hid_t file)
{
    /* 2^20 requested times declared, none stored (never written): the
     * restart took the fill values (zeros) as times; with the fuzzer's 2^31
     * it allocated 16 GB for them before reading */
    hsize_t huge[1] = {1ull << 20};
    hid_t space = H5Screate_simple(1, huge, NULL);
    ck_assert_int_ge(H5Ldelete(file, "core/requests", H5P_DEFAULT), 0);
    hid_t set = H5Dcreate2(file, "core/requests", H5T_NATIVE_DOUBLE, space, H5P_DEFAULT,
                           H5P_DEFAULT, H5P_DEFAULT);
    ck_assert_int_ge(set, 0);
    H5Dclose(set);
    H5Sclose(space);
}

static void record_times_declared_huge(hid_t file)
{
    hsize_t huge[1] = {1ull << 20};
    hid_t space = H5Screate_simple(1, huge, NULL);
    ck_assert_int_ge(H5Ldelete(file, "plugins/hdf5/record_times", H5P_DEFAULT), 0);
    hid_t set = H5Dcreate2(file, "plugins/hdf5/record_times", H5T_NATIVE_DOUBLE, space,
                           H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ck_assert_int_ge(set, 0);
    H5Dclose(set);
    H5Sclose(space);
}

static void set_root_count(hid_t file, const char *name, uint64_t value)
{
    hid_t attr = H5Aopen(file, name, H5P_DEFAULT);
    ck_assert_int_ge(attr, 0);
    ck_assert_int_ge(H5Awrite(attr, H5T_NATIVE_UINT64, &value), 0);
    H5Aclose(attr);
}

static void particle_count_2e31(hid_t file)
{
    /* 2^31 - 1 particles (and as many ids): the restart grew the particle
     * store to that count (hundreds of GB) before it read a dataset */
    set_root_count(file, "particle_count", INT32_MAX);
    set_root_count(file, "next_id", INT32_MAX);
}

static void step_int64_max(hid_t file)
{
    /* the step counter at 2^63 - 1: the first step overflowed it */
    const int64_t step = INT64_MAX;
    hid_t attr = H5Aopen(file, "step", H5P_DEFAULT);
    ck_assert_int_ge(attr, 0);
    ck_assert_int_ge(H5Awrite(attr, H5T_NATIVE_INT64, &step), 0);
    H5Aclose(attr);
}

/* Overwrites the int64 dataset at `path` of the file with `values`. */
static void put_int64(hid_t file, const char *path, const int64_t *values)
{
    hid_t set = H5Dopen2(file, path, H5P_DEFAULT);
    ck_assert_int_ge(set, 0);
    ck_assert_int_ge(H5Dwrite(set, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
    H5Dclose(set);
}

static void gauge_rows_negative(hid_t file)
{
    /* the point gauge's count of rows written: the first step counted it up
     * to the current time one by one, 2^63 times */
    const int64_t rows = INT64_MIN;
    put_int64(file, "plugins/point_gauge/rows_written", &rows);
}

static void inlet_rows_negative(hid_t file)
{
    /* the same count, stored beside the inlet's particle count */
    const int64_t counts[2] = {INT64_MIN, 0};
    put_int64(file, "plugins/inlet/rows_written,open_count", counts);
}

static void inlet_column_far(hid_t file)
{
    /* the buffer inlet's newest column 10^10 m upstream: the first step
     * added a column for every spacing down to the buffer, until memory ran
     * out */
    double values[6];
    hid_t set = H5Dopen2(file,
                         "plugins/inlet/last_time,newest_column,mass_interval,momentum_interval,"
                         "mass_total,row_time",
                         H5P_DEFAULT);
    ck_assert_int_ge(set, 0);
    ck_assert_int_ge(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
    values[1] = 1e10;
    ck_assert_int_ge(H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
    H5Dclose(set);
}

static void format_of_two_lines(hid_t file)
{
    /* the message quoted the file's text as it was: two lines */
    const char *text = "inlet.csv\noutlet.csv";
    hid_t type = H5Tcopy(H5T_C_S1), space = H5Screate(H5S_SCALAR);
    ck_assert_int_ge(H5Tset_size(type, H5T_VARIABLE), 0);
    ck_assert_int_ge(H5Adelete(file, "format"), 0);
    hid_t attr = H5Acreate2(file, "format", type, space, H5P_DEFAULT, H5P_DEFAULT);
    ck_assert_int_ge(attr, 0);
    ck_assert_int_ge(H5Awrite(attr, type, &text), 0);
    H5Aclose(attr);
    H5Sclose(space);
    H5Tclose(type);
}

/* A copy of a checkpoint (its bytes) edited through HDF5, with its checksum
 * added again. */
static char *edited_copy(const char *bytes, long size, const char *dir, const char *name,
                         void (*edit)(hid_t file))
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s.h5", dir, name), 0);
    FILE *f = fopen(path, "wb");
    ck_assert_ptr_nonnull(f);
    const size_t hdf5_size = (size_t)size - SLUICE_CHECKSUM_BYTES;
    ck_assert_int_eq(fwrite(bytes, 1, hdf5_size, f), hdf5_size);
    fclose(f);
    hid_t file = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    ck_assert_int_ge(file, 0);
    edit(file);
    ck_assert_int_ge(H5Fclose(file), 0);
    char error[600];
    ck_assert_msg(sluice_checksum_append(path, error, sizeof error) == 0, "%s", error);
    return path;
}

static void verlet_steps_int64_max(hid_t file)
{
    /* Verlet's count of steps taken at 2^63 - 1: its first step overflowed
     * it */
    const int64_t steps = INT64_MAX;
    put_int64(file, "plugins/verlet/steps", &steps);
}

typedef struct fuzzed_edit {
    const char *name;
    void (*edit)(hid_t file);
    const char *needle; /* in the one message */
} fuzzed_edit;

/* Runs a channel case to 0.02 s with a checkpoint at the end, then
 * restarts from each edited copy of it. */
static void refused_after_edits(const channel_case *c, const fuzzed_edit *edits, size_t count)
{
    char *yaml = channel_scene(c, 0.02, 0.02);
    char *dir = test_scratch("restart-fuzzed");
    char *scene = test_write_file(dir, "scene.yaml", yaml);
    char *args = NULL, *out = NULL, *later = NULL;
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/out --quiet", scene, dir), 0);
    ck_assert_int_eq(test_sluice(args, NULL), 0);
    ck_assert_int_ge(asprintf(&out, "%s/out", dir), 0);
    int checkpoints = 0;
    char *good = first_checkpoint(out, &checkpoints);
    ck_assert_int_eq(checkpoints, 1);
    long size = 0;
    char *bytes = read_bytes(good, &size);
    /* the checkpoint is the run's last, at its end */
    ck_assert_int_ge(asprintf(&later, "%s --set time.end=0.03", scene), 0);
    for (size_t k = 0; k < count; k++) {
        char *edited = edited_copy(bytes, size, dir, edits[k].name, edits[k].edit);
        refused(later, edited, edits[k].needle);
        free(edited);
    }
    free(bytes);
    free(good);
    free(later);
    free(out);
    free(args);
    free(scene);
    free(dir);
    free(yaml);
}

START_TEST(fuzzed_checkpoints_refused)
{
    static const fuzzed_edit channel[] = {
        {"requests_declared_huge", requests_declared_huge,
         "dataset 'requests' declares more values than the file holds"},
        {"record_times_declared_huge", record_times_declared_huge,
         "state array 'record_times': it declares more values than the file holds"},
        {"particle_count_2e31", particle_count_2e31, " x 2147483647"},
        {"step_int64_max", step_int64_max, "step 9223372036854775807"},
        {"gauge_rows_negative", gauge_rows_negative,
         "state array 'rows_written' holds -9223372036854775808 outputs made"},
        {"inlet_rows_negative", inlet_rows_negative,
         "state array 'rows_written,open_count' holds -9223372036854775808 outputs made"},
        {"inlet_column_far", inlet_column_far, "and newest_column = 1e+10 m (the domain"},
        {"format_of_two_lines", format_of_two_lines, "(format 'inlet.csv?outlet.csv')\n"},
    };
    refused_after_edits(&channel_cases[0], channel, sizeof channel / sizeof channel[0]);
    /* the channel with Verlet */
    static const fuzzed_edit verlet[] = {
        {"verlet_steps_int64_max", verlet_steps_int64_max,
         "state array 'steps' holds 9223372036854775807 steps taken"},
    };
    refused_after_edits(&channel_cases[2], verlet, sizeof verlet / sizeof verlet[0]);
}
END_TEST

/* Single bits flipped at places drawn over the whole checkpoint (a fixed
 * generator): every restart is refused by the checksum with exit 2, none
 * crashes, none goes on from a changed state. SLUICE_FLIP_COUNT sets a
 * longer campaign (docs/reliability.md: 260). */
START_TEST(bit_flips_never_accepted)
{
    char *dir = test_scratch("restart-flips");
    char *scene = test_config("dam_break_2d.yaml"), *args = NULL;
    ck_assert_int_ge(asprintf(&args,
                              "run %s --out %s/out --quiet --set particles.spacing=0.04 "
                              "--set time.end=0.02 --set checkpoint.interval=0.02",
                              scene, dir),
                     0);
    ck_assert_int_eq(test_sluice(args, NULL), 0);
    free(args);
    char *out = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", dir), 0);
    int count = 0;
    char *good = first_checkpoint(out, &count);
    ck_assert_int_ge(count, 1);
    long size = 0;
    unsigned char *bytes = read_bytes(good, &size);
    const char *requested = getenv("SLUICE_FLIP_COUNT");
    const int flips = requested && atoi(requested) > 0 ? atoi(requested) : 12;
    char *flipped = NULL;
    ck_assert_int_ge(asprintf(&flipped, "%s/flipped.h5", dir), 0);
    unsigned long long state = 88172645463325252ull;
    int refused_by_checksum = 0;
    for (int k = 0; k < flips; k++) {
        state ^= state << 13, state ^= state >> 7, state ^= state << 17; /* xorshift64 */
        const long at = (long)(state % (unsigned long long)size);
        const int bit = (int)((state >> 40) % 8);
        bytes[at] ^= (unsigned char)(1u << bit);
        FILE *f = fopen(flipped, "wb");
        ck_assert_int_eq(fwrite(bytes, 1, (size_t)size, f), (size_t)size);
        fclose(f);
        bytes[at] ^= (unsigned char)(1u << bit);
        char *output = NULL;
        ck_assert_int_ge(asprintf(&args, "run %s --out %s/again --quiet --set "
                                         "particles.spacing=0.04 --set time.end=0.03 "
                                         "--restart %s",
                                  scene, dir, flipped),
                         0);
        const int status = test_sluice(args, &output);
        ck_assert_msg(status == 2, "bit %d of byte %ld: exit %d\n%s", bit, at, status, output);
        refused_by_checksum += strstr(output, "its checksum does not match") != NULL;
        free(output);
        free(args);
    }
    fprintf(stderr, "bit flips: %d of %d refused by the checksum (%ld-byte checkpoint)\n",
            refused_by_checksum, flips, size);
    ck_assert_int_eq(refused_by_checksum, flips);
    free(flipped);
    free(bytes);
    free(good);
    free(out);
    free(scene);
    free(dir);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("restart");
    TCase *exact = tcase_create("bit_identical");
    tcase_set_timeout(exact, 300);
    tcase_add_loop_test(exact, open_boundaries_restart_bit_identical, 0,
                        (int)(sizeof channel_cases / sizeof channel_cases[0]));
    tcase_add_loop_test(exact, dam_break_restart_bit_identical, 0,
                        (int)(sizeof restart_integrators / sizeof restart_integrators[0]));
    tcase_add_test(exact, sigint_stops_with_a_checkpoint);
    tcase_add_test(exact, restart_with_other_cells_keeps_each_particle);
    suite_add_tcase(s, exact);
    TCase *bad = tcase_create("refused");
    tcase_set_timeout(bad, 120);
    tcase_add_test(bad, bad_checkpoints_refused);
    tcase_add_test(bad, fuzzed_checkpoints_refused);
    suite_add_tcase(s, bad);
    /* a dozen runs that stop at the checksum: not worth the sanitizer's time */
    TCase *flips = tcase_create("flips");
    tcase_set_timeout(flips, 120);
    tcase_set_tags(flips, "long");
    tcase_add_test(flips, bit_flips_never_accepted);
    suite_add_tcase(s, flips);
    return test_run_suite(s);
}
