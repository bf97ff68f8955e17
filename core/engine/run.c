/* Running a simulation: the time loop (begin, step, end), hooks before and
 * after each step, periodic checkpoints through the checkpoint service,
 * SIGINT/SIGTERM, run.json and the progress line. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "build_config.h"
#include "sim_internal.h"

/* ------------------------------------------------------------- signals -- */

/* The only global mutable state of Sluice: SIGINT and SIGTERM set it (a
 * handler may do nothing else safely: C11 7.14.1.1, a volatile sig_atomic_t),
 * and sluice_sim_run reads it between steps, then stops after the current
 * step and writes a checkpoint. A second signal gets the default action
 * (SA_RESETHAND): it ends the process at once. */
static volatile sig_atomic_t stop_signal = 0;

static void on_stop_signal(int signum)
{
    stop_signal = signum;
}

int sluice_install_stop_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART | SA_RESETHAND;
    if (sigaction(SIGINT, &sa, NULL) != 0 || sigaction(SIGTERM, &sa, NULL) != 0)
        return -1;
    return 0;
}

int sluice_stop_requested(void)
{
    return stop_signal != 0;
}

/* ------------------------------------------------------------ the loop -- */

static int call_hooks(sluice_sim *sim, int after)
{
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        sluice_instance *in = &sim->instances[k];
        int (*hook)(void *, sluice_host *) =
            after ? in->component->after_step : in->component->before_step;
        if (!hook)
            continue;
        if (hook(in->state, &in->host) != SLUICE_OK) {
            sluice_sim_fail(sim, "plugin '%s' failed in its %s hook at step %lld, t = %.9g s",
                            in->name, after ? "after-step" : "before-step", (long long)sim->step,
                            sim->time);
            return -1;
        }
        if (sim->failure[0])
            return -1;
    }
    return 0;
}

/* Moves checkpoint_next to the first multiple of checkpoint.interval after
 * the current time (to round-off) and asks the core to end a step on it. */
static void schedule_next_checkpoint(sluice_sim *sim)
{
    const double interval = (double)sim->scene.checkpoint.interval;
    while ((double)sim->checkpoint_next * interval <= sim->time + 1e-9 * interval)
        sim->checkpoint_next++;
    sluice_sim_request_time(sim, (double)sim->checkpoint_next * interval);
}

static int end_every_rank_on_failure(sluice_sim *sim, int status);

int sluice_sim_begin(sluice_sim *sim, const char *output_directory)
{
    if (output_directory) {
        /* across ranks rank 0 makes the directory and writes the scene; the
         * others wait for it (the reduction) before anything is written */
        char error[1024] = "";
        int failed = 0;
        if (sim->comm.rank == 0) {
            if (sluice_sim_make_directory(output_directory, error, sizeof error) != 0) {
                failed = 1;
            } else {
                char path[4096];
                snprintf(path, sizeof path, "%s/scene.resolved.yaml", output_directory);
                if (sluice_write_file_atomic(path, sim->resolved_scene,
                                             strlen(sim->resolved_scene), error,
                                             sizeof error) != 0)
                    failed = 1;
            }
        }
        if (sluice_comm_any(&sim->comm, failed)) {
            if (failed)
                sluice_sim_fail(sim, "%s", error);
            else
                sluice_sim_fail(sim, "rank 0 could not prepare the output directory '%s'",
                                output_directory);
            return SLUICE_RUN_FAILED;
        }
        sim->output_directory = strdup(output_directory);
        if (!sim->output_directory)
            return SLUICE_RUN_FAILED;
        /* the index of the tables the components opened (rewritten at the
         * end of the run) */
        if (sluice_comm_any(&sim->comm, sluice_sim_write_table_index(sim) != 0)) {
            sluice_sim_fail(sim, "cannot write the index of the tables, %s/tables.json",
                            output_directory);
            return SLUICE_RUN_FAILED;
        }
    }
    sim->wall_start = sluice_wall_clock();
    (void)sluice_sim_describe(sim, "date"); /* the start date and host, now */
    sim->step_at_start = sim->step;
    sim->time_at_start = sim->time;
    sim->particle_steps_at_start = sim->particle_steps;
    /* the watchdog's wall check: cells about a kernel support wide */
    if (sim->scene.wall_count > 0 && sim->wall_watch.cells.wall_count == 0) {
        double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
        for (uint32_t d = 0; d < sim->scene.dimensions; d++) {
            lo[d] = (double)sim->scene.domain.min[d];
            hi[d] = (double)sim->scene.domain.max[d];
        }
        if (sluice_wall_watch_init(&sim->wall_watch, sim->scene.dimensions,
                                   sim->wall_geometries, sim->scene.wall_count, lo, hi,
                                   (double)sim->support,
                                   (double)sim->scene.watchdog.wall_penetration *
                                       (double)sim->spacing) != 0) {
            sluice_sim_fail(sim, "out of memory building the watchdog's wall cells");
            return SLUICE_RUN_FAILED;
        }
    }
    sluice_sim_refresh_view(sim);
    /* periodic checkpoints: the first scheduled after the current time (a
     * restart requested it already, in its saved requests) */
    if (sim->scene.checkpoint.interval > 0) {
        if (!sim->services.checkpoint) {
            sluice_sim_fail(sim, "checkpoint.interval asks for checkpoints, and this program "
                                 "was built without the checkpoint library");
            return SLUICE_RUN_FAILED;
        }
        sim->checkpoint_next = 1;
        schedule_next_checkpoint(sim);
    }
    /* after a restart the hooks ran already on this state, before the
     * checkpoint; a hook failing on one rank ends every rank */
    if (!sim->restarted && call_hooks(sim, 1) != 0)
        return end_every_rank_on_failure(sim, SLUICE_RUN_FAILED);
    return SLUICE_RUN_COMPLETE;
}

/* Writes the periodic checkpoint when the step ended on its time. */
static int periodic_checkpoint(sluice_sim *sim)
{
    const double interval = (double)sim->scene.checkpoint.interval;
    if (!(interval > 0))
        return SLUICE_OK;
    if (sim->time + 1e-9 * interval < (double)sim->checkpoint_next * interval)
        return SLUICE_OK;
    if (sim->output_directory && sim->checkpoint_step != sim->step &&
        sim->services.checkpoint(sim, NULL) != SLUICE_OK)
        return SLUICE_ERROR;
    schedule_next_checkpoint(sim);
    return SLUICE_OK;
}

static int step(sluice_sim *sim);

/* A rank that fails leaves the others waiting in a halo exchange or a
 * reduction: in a run across ranks a failure ends every rank, with the
 * failing rank's diagnostic (docs/scaling.md). */
static int end_every_rank_on_failure(sluice_sim *sim, int status)
{
#ifdef SLUICE_MPI
    if (status != SLUICE_RUN_COMPLETE && sim->comm.size > 1) {
        fprintf(stderr, "sluice: rank %d of %d: error: %s\n", sim->comm.rank, sim->comm.size,
                sim->failure[0] ? sim->failure : "the step failed");
        fflush(stderr);
        MPI_Abort(sim->comm.comm, status);
    }
#else
    (void)sim;
#endif
    return status;
}

int sluice_sim_step(sluice_sim *sim)
{
    return end_every_rank_on_failure(sim, step(sim));
}

static int step(sluice_sim *sim)
{
    if (call_hooks(sim, 0) != 0)
        return SLUICE_RUN_FAILED;
    sluice_instance *integrator = &sim->instances[sim->integrator];
    sim->dt = 0;
    if (integrator->component->advance(integrator->state, &integrator->host) != SLUICE_OK) {
        if (!sim->failure[0])
            sluice_sim_fail(sim, "integrator '%s' failed at step %lld, t = %.9g s", integrator->name,
                            (long long)sim->step, sim->time);
        /* a particle leaving the domain during an evaluation is instability */
        return strstr(sim->failure, "outside the domain") ? SLUICE_RUN_UNSTABLE : SLUICE_RUN_FAILED;
    }
    if (!(sim->dt > 0)) {
        /* a time-step limit that is not a number (or not positive) comes from
         * a particle's state: name the particle and the field when the
         * sluice_sim_watchdog's scan finds it */
        const double limit = sim->dt_limit;
        sim->dt_limit = INFINITY;
        const int found = sluice_sim_watchdog(sim) != 0;
        sim->dt_limit = limit;
        if (!found)
            sluice_sim_fail(sim,
                            "integrator '%s' did not take a step at t = %.9g s (time step %g s)",
                            integrator->name, sim->time, sim->dt);
        return SLUICE_RUN_UNSTABLE;
    }
    sim->time += sim->dt;
    if (fabs(sim->time - sim->end) <= 1e-12 * (sim->end > 1 ? sim->end : 1))
        sim->time = sim->end;
    sim->step++;
    sluice_grid_wrap(&sim->grid, (sluice_real **)sim->view.position, sim->particles.count);
    sluice_sim_refresh_view(sim);
    sim->particle_steps += sim->particles.count;
    if (sim->step % sim->scene.watchdog.every == 0 && sluice_sim_watchdog(sim) != 0)
        return SLUICE_RUN_UNSTABLE;
    if (call_hooks(sim, 1) != 0)
        return SLUICE_RUN_FAILED;
    if (periodic_checkpoint(sim) != SLUICE_OK)
        return SLUICE_RUN_FAILED;
    return SLUICE_RUN_COMPLETE;
}

static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (; s && *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(f, "\\%c", c);
        else if (c < 0x20)
            fprintf(f, "\\u%04x", c);
        else
            fputc(c, f);
    }
    fputc('"', f);
}

/* Per target kind: the pairs of the passes within the support, then the
 * thread-seconds they took (fill, kernel, gather, terms), this invocation's
 * (2 x SLUICE_KIND_COUNT figures); their share of wall_seconds x threads is
 * that kind's share of a step (docs/performance.md, "Walls"). */
static void write_kind_costs(FILE *f, const double *figures)
{
    for (uint32_t what = 0; what < 2; what++) {
        fprintf(f, "  \"%s\": {",
                what ? "pair_seconds_by_target_kind" : "pair_interactions_by_target_kind");
        for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++)
            fprintf(f, what ? "%s\"%s\": %.6g" : "%s\"%s\": %.0f", k ? ", " : "",
                    sluice_kind_name((uint8_t)k), figures[what * SLUICE_KIND_COUNT + k]);
        fprintf(f, "},\n");
    }
}

static int write_run_json(sluice_sim *sim, int status)
{
    /* across ranks: the counts of every rank, written by rank 0 (the
     * reduction is collective, so every rank comes here) */
    const size_t state_bytes = sluice_particles_bytes(&sim->particles) +
                               sluice_grid_bytes(&sim->grid) +
                               sluice_pair_engine_bytes(&sim->engine);
    struct rusage usage;
    double peak = getrusage(RUSAGE_SELF, &usage) == 0 ? (double)usage.ru_maxrss * 1024 : -1;
    enum { SUMS = 6 + 2 * SLUICE_KIND_COUNT };
    double sums[SUMS] = {
        (double)sim->particles.count, (double)sim->removed,
        (double)sim->particle_steps,  (double)sluice_pair_engine_pairs(&sim->engine),
        (double)state_bytes,          (double)(sim->particle_steps - sim->particle_steps_at_start)};
    /* what each kind of target cost the passes within the support */
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++) {
        sums[6 + k] = (double)sluice_pair_engine_kind_pairs(&sim->engine, k);
        sums[6 + SLUICE_KIND_COUNT + k] = sluice_pair_engine_kind_seconds(&sim->engine, k);
    }
    double maxima[2] = {peak, sim->max_density_deviation};
    if (sluice_comm_reduce(&sim->comm, sums, SUMS, SLUICE_REDUCE_SUM) != 0 ||
        sluice_comm_reduce(&sim->comm, maxima, 2, SLUICE_REDUCE_MAX) != 0)
        return -1;
    /* the balance of the ranks: their fewest and most particles */
    double spread[2] = {-(double)sim->particles.count, (double)sim->particles.count};
    if (sluice_comm_reduce(&sim->comm, spread, 2, SLUICE_REDUCE_MAX) != 0)
        return -1;
    if (sim->comm.rank != 0)
        return 0;
    const double particles_final = sums[0], removed = sums[1], particle_steps = sums[2],
                 pairs = sums[3], bytes = sums[4], steps_this_run = sums[5],
                 max_deviation = maxima[1];
    peak = maxima[0];
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f)
        return -1;
    const char *names[] = {"complete", "?", "input_error", "unstable", "failed", "interrupted"};
    /* this invocation's particle-steps over its wall time (after a restart
     * particle_steps is the whole run's) */
    double rate = sim->wall_seconds > 0 ? steps_this_run / sim->wall_seconds : 0;
    fprintf(f, "{\n  \"status\": \"%s\",\n", status >= 0 && status <= 5 ? names[status] : "failed");
    fprintf(f, "  \"scene\": ");
    json_string(f, sim->scene.path);
    fprintf(f, ",\n  \"sluice_version\": \"%s\",\n", SLUICE_VERSION);
    /* provenance: what produced the run, where and when */
    static const char *const provenance[] = {"git_revision", "build", "command_line", "date",
                                             "host"};
    for (size_t k = 0; k < sizeof provenance / sizeof *provenance; k++) {
        fprintf(f, "  \"%s\": ", provenance[k]);
        json_string(f, sluice_sim_describe(sim, provenance[k]));
        fprintf(f, ",\n");
    }
    fprintf(f, "  \"kernel\": ");
    json_string(f, sluice_sim_describe(sim, "kernel"));
    fprintf(f, ",\n");
    fprintf(f, "  \"dimensions\": %u,\n", sim->scene.dimensions);
    fprintf(f, "  \"ranks\": %d,\n", sim->comm.size);
    if (sim->comm.size > 1)
        fprintf(f,
                "  \"rank_particles_fewest\": %.0f,\n  \"rank_particles_most\": %.0f,\n"
                "  \"slab_rebalances\": %llu,\n",
                -spread[0], spread[1], (unsigned long long)sim->halo.balances);
    fprintf(f, "  \"particles_initial\": %u,\n", sim->particles_initial);
    fprintf(f, "  \"particles_final\": %.0f,\n", particles_final);
    /* final = initial + added - removed (ids across ranks are interleaved:
     * next_id does not count them) */
    fprintf(f, "  \"particles_added\": %.0f,\n",
            particles_final + removed - (double)sim->particles_initial);
    fprintf(f, "  \"particles_removed\": %.0f,\n", removed);
    fprintf(f, "  \"steps\": %lld,\n", (long long)sim->step);
    fprintf(f, "  \"simulated_time\": %.12g,\n", sim->time);
    fprintf(f, "  \"end_time\": %.12g,\n", sim->end);
    fprintf(f, "  \"wall_seconds\": %.6f,\n", sim->wall_seconds);
    fprintf(f, "  \"restarted_at_step\": %lld,\n", (long long)sim->step_at_start);
    fprintf(f, "  \"particle_steps\": %.0f,\n", particle_steps);
    fprintf(f, "  \"particle_steps_this_run\": %.0f,\n", steps_this_run);
    fprintf(f, "  \"particle_steps_per_second\": %.6g,\n", rate);
    fprintf(f, "  \"pair_interactions\": %.0f,\n", pairs);
    fprintf(f, "  \"pair_interactions_per_second\": %.6g,\n",
            sim->wall_seconds > 0 ? pairs / sim->wall_seconds : 0.0);
    write_kind_costs(f, sums + 6);
    fprintf(f, "  \"neighbour_list_rebuilds\": %llu,\n", (unsigned long long)sim->grid.rebuilds);
    /* memory: the particle store, the grid and the Verlet list, and the
     * pair engine's buffers, per particle at the end (over every rank); the
     * process's peak resident set (program and libraries included, about
     * 10 MB; across ranks the largest rank's) */
    fprintf(f, "  \"state_bytes_per_particle\": %.1f,\n",
            particles_final > 0 ? bytes / particles_final : 0.0);
    fprintf(f, "  \"peak_memory_bytes\": %.0f,\n", peak);
    /* the estimate made before the set-up (docs/reliability.md, "Memory"):
     * its particle count, bytes per particle and total */
    const sluice_memory_estimate *m = &sim->memory;
    fprintf(f,
            "  \"memory_estimate\": {\"bytes\": %.0f, \"particles\": %.0f, "
            "\"bytes_per_particle\": %.1f, \"fields\": %.1f, \"neighbour_list\": %.1f, "
            "\"neighbours\": %.0f, \"grid_and_reordering\": %.1f, \"held_at_start\": %.0f, "
            "\"available\": %.0f},\n",
            m->total, m->particles, m->per_particle, m->store, m->list, m->neighbours,
            m->grid + m->scratch, m->fixed, m->available);
    fprintf(f, "  \"threads\": %d,\n", sim->threads);
    /* how the threads wait at barriers (sluice run sets passive on a busy
     * machine; docs/performance.md) */
    const char *policy = getenv("OMP_WAIT_POLICY"), *spin = getenv("GOMP_SPINCOUNT");
    fprintf(f, "  \"openmp_wait_policy\": ");
    json_string(f, policy ? policy : spin ? "GOMP_SPINCOUNT" : "default");
    fprintf(f, ",\n");
    fprintf(f, "  \"max_density_deviation\": %.6g,\n", max_deviation);
    fprintf(f, "  \"smoothing_length\": %.9g,\n", (double)sim->smoothing_length);
    fprintf(f, "  \"spacing\": %.9g,\n", (double)sim->spacing);
    fprintf(f, "  \"failure\": ");
    json_string(f, sim->failure);
    fprintf(f, ",\n  \"plugins\": [");
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        const sluice_instance *in = &sim->instances[k];
        fprintf(f, "%s\n    {\"component\": ", k ? "," : "");
        json_string(f, in->component->name);
        fprintf(f, ", \"instance\": ");
        json_string(f, in->name);
        fprintf(f, ", \"library\": ");
        json_string(f, in->library->name);
        fprintf(f, ", \"version\": ");
        json_string(f, in->library->version);
        fprintf(f, ", \"path\": ");
        json_string(f, in->path);
        fprintf(f, "}");
    }
    fprintf(f, "\n  ],\n  \"schedule\": ");
    sluice_sim_write_schedule(sim, f, 1);
    fprintf(f, "\n}\n");
    if (fclose(f) != 0) {
        free(text);
        return -1;
    }
    char path[4096], error[1024];
    snprintf(path, sizeof path, "%s/run.json", sim->output_directory);
    int rc = sluice_write_file_atomic(path, text, size, error, sizeof error);
    if (rc != 0)
        fprintf(stderr, "sluice: error: %s\n", error);
    free(text);
    return rc;
}

int sluice_sim_end(sluice_sim *sim, int status)
{
    sim->wall_seconds = sluice_wall_clock() - sim->wall_start;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        sluice_instance *in = &sim->instances[k];
        int finish_status = status == SLUICE_RUN_COMPLETE      ? SLUICE_FINISH_COMPLETE
                            : status == SLUICE_RUN_INTERRUPTED ? SLUICE_FINISH_INTERRUPTED
                                                               : SLUICE_FINISH_FAILED;
        if (in->component->finish && in->component->finish(in->state, &in->host, finish_status) != SLUICE_OK) {
            sluice_sim_fail(sim, "plugin '%s' failed to finish its output", in->name);
            if (status == SLUICE_RUN_COMPLETE || status == SLUICE_RUN_INTERRUPTED)
                status = SLUICE_RUN_FAILED;
        }
    }
    for (size_t t = 0; t < sim->table_count; t++)
        if (sim->tables[t]->fd >= 0) {
            close(sim->tables[t]->fd);
            sim->tables[t]->fd = -1;
        }
    if (sim->output_directory && sluice_sim_write_table_index(sim) != 0 &&
        (status == SLUICE_RUN_COMPLETE || status == SLUICE_RUN_INTERRUPTED))
        status = SLUICE_RUN_FAILED;
    if (sim->output_directory && write_run_json(sim, status) != 0 &&
        (status == SLUICE_RUN_COMPLETE || status == SLUICE_RUN_INTERRUPTED))
        status = SLUICE_RUN_FAILED;
    return status;
}

/* The progress report: on a terminal one line rewritten every 0.5 s; in a
 * batch log a plain line with a UTC timestamp every log_every s of wall
 * time, the first at the start and the last at the end (time, share done,
 * step, dt, particles, steps per second and ETA of this invocation). */
static void progress_line(sluice_sim *sim, int final)
{
    const int log = sim->progress == SLUICE_PROGRESS_LOG;
    double now = sluice_wall_clock();
    if (!final && now - sim->last_progress < (log ? sim->log_every : 0.5) &&
        !(log && sim->last_progress == 0))
        return;
    sim->last_progress = now;
    double elapsed = now - sim->wall_start;
    /* this invocation's steps and simulated time (a restart begins past 0) */
    double rate = elapsed > 0 ? (double)(sim->step - sim->step_at_start) / elapsed : 0;
    double done = sim->time - sim->time_at_start;
    double eta = done > 0 ? elapsed * (sim->end - sim->time) / done : 0;
    int h = (int)(eta / 3600), m = (int)(fmod(eta, 3600) / 60), s = (int)fmod(eta, 60);
    if (log) {
        char stamp[40];
        sluice_utc_timestamp(stamp, sizeof stamp);
        fprintf(stderr,
                "%s sluice: t %.4f / %.4f s (%.1f %%)   step %lld   dt %.2e s   %u particles   "
                "%.0f steps/s   ETA %d:%02d:%02d\n",
                stamp, sim->time, sim->end, sim->end > 0 ? 100 * sim->time / sim->end : 100.0,
                (long long)sim->step, sim->dt, sim->particles.count, rate, h, m, s);
        fflush(stderr);
        return;
    }
    fprintf(stderr,
            "\r  t %.4f / %.4f s   step %lld   dt %.2e s   %u particles   %.0f steps/s   ETA "
            "%d:%02d:%02d  ",
            sim->time, sim->end, (long long)sim->step, sim->dt, sim->particles.count, rate, h, m, s);
    if (final)
        fputc('\n', stderr);
    fflush(stderr);
}

int sluice_sim_run(sluice_sim *sim, const sluice_run_options *options)
{
    sim->progress = options->progress;
    sim->quiet = options->quiet;
    sim->log_every = options->log_every > 0 ? options->log_every : 10;
    sim->last_progress = 0;
    int status = sluice_sim_begin(sim, options->output_directory);
    if (status != SLUICE_RUN_COMPLETE) {
        if (!sim->output_directory)
            return status; /* nothing was written */
        return sluice_sim_end(sim, status);
    }
    const double end = sim->end;
    while (sim->time < end - 1e-12 * (end > 1 ? end : 1)) {
        /* across ranks every rank stops after the same step */
        if (sim->comm.size > 1 ? sluice_comm_any(&sim->comm, stop_signal != 0) : stop_signal != 0) {
            /* SIGINT/SIGTERM: the last step is whole; keep it */
            status = SLUICE_RUN_INTERRUPTED;
            if (sim->output_directory && sim->checkpoint_step != sim->step &&
                sim->services.checkpoint && sim->services.checkpoint(sim, NULL) != SLUICE_OK)
                status = SLUICE_RUN_FAILED;
            break;
        }
        status = sluice_sim_step(sim);
        if (status != SLUICE_RUN_COMPLETE)
            break;
        if (sim->progress)
            progress_line(sim, 0);
    }
    if (sim->progress)
        progress_line(sim, 1);
    return sluice_sim_end(sim, status);
}
