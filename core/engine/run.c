/* Running a simulation: the time loop, the stability watchdog, outputs that
 * are never left half-written, run.json and the progress line. */
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

/* ------------------------------------------------------------------ I/O -- */

int sluice_write_file_atomic(const char *path, const void *data, size_t size, char *error,
                             size_t error_size)
{
    size_t n = strlen(path) + 32;
    char *tmp = malloc(n);
    if (!tmp) {
        snprintf(error, error_size, "out of memory writing '%s'", path);
        return -1;
    }
    snprintf(tmp, n, "%s.tmp.%ld", path, (long)getpid());
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
        free(tmp);
        return -1;
    }
    const char *p = data;
    size_t left = size;
    while (left > 0) {
        ssize_t w = write(fd, p, left);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
            close(fd);
            unlink(tmp);
            free(tmp);
            return -1;
        }
        p += w;
        left -= (size_t)w;
    }
    if (close(fd) != 0) {
        snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
        unlink(tmp);
        free(tmp);
        return -1;
    }
    if (rename(tmp, path) != 0) {
        snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
        unlink(tmp);
        free(tmp);
        return -1;
    }
    free(tmp);
    return 0;
}

static int write_all(int fd, const char *data, size_t size)
{
    while (size > 0) {
        ssize_t w = write(fd, data, size);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            return -1;
        }
        data += w;
        size -= (size_t)w;
    }
    return 0;
}

/* The FNV-1a hash of the file's first `bytes` bytes; 0 when it cannot be
 * read. */
static int file_hash(int fd, uint64_t bytes, uint64_t *hash)
{
    char buffer[65536];
    uint64_t h = SLUICE_TABLE_HASH_START, offset = 0;
    while (offset < bytes) {
        size_t want = bytes - offset < sizeof buffer ? (size_t)(bytes - offset) : sizeof buffer;
        ssize_t got = pread(fd, buffer, want, (off_t)offset);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            return 0;
        h = sluice_table_hash_bytes(h, buffer, (size_t)got);
        offset += (uint64_t)got;
    }
    *hash = h;
    return 1;
}

/* A restarted run continues a table that is in the output directory (the
 * same directory as the checkpointed run) from its length at the checkpoint:
 * the rows written after the checkpoint (by the run that went on, or by
 * its finish) are cut off. The file must start with the checkpointed bytes
 * (their hash, when the checkpoint has it): another run's table left in the
 * directory is not cut in the middle of a row but started anew, with a
 * note. Returns the open descriptor, or -1 when the file is missing, shorter
 * or different (then a new file with the header is started). */
static int resume_table(sluice_table *table)
{
    int fd = open(table->path, O_RDWR | O_APPEND | O_CLOEXEC);
    if (fd < 0)
        return -1;
    struct stat st;
    uint64_t hash = 0;
    int same = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
               (uint64_t)st.st_size >= table->resume_bytes &&
               file_hash(fd, table->resume_bytes, &hash) &&
               (!table->resume_hashed || hash == table->resume_hash);
    if (!same || ftruncate(fd, (off_t)table->resume_bytes) != 0) {
        if (!same && !table->sim->quiet)
            fprintf(stderr,
                    "sluice: note: '%s' is not the checkpointed run's table (its first %llu "
                    "bytes differ or are missing): it is started anew\n",
                    table->path, (unsigned long long)table->resume_bytes);
        close(fd);
        return -1;
    }
    table->bytes = table->resume_bytes;
    table->hash = hash;
    return fd;
}

/* Appends one complete line (one write call) to a table, creating the file
 * with its header first. */
int sluice_sim_table_flush_row(sluice_table *table, const char *line, size_t length)
{
    if (table->fd < 0) {
        size_t n = strlen(table->sim->output_directory) + strlen(table->path) + 2;
        char *full = malloc(n);
        if (!full) {
            table->failed = 1;
            return SLUICE_ERROR;
        }
        snprintf(full, n, "%s/%s", table->sim->output_directory, table->path);
        free(table->path);
        table->path = full;
        if (table->resume && table->resume_bytes > 0 &&
            (table->fd = resume_table(table)) >= 0) {
            if (write_all(table->fd, line, length) != 0) {
                table->failed = 1;
                sluice_sim_fail(table->sim, "cannot write '%s': %s", table->path,
                                strerror(errno));
                return SLUICE_ERROR;
            }
            table->bytes += length;
            table->hash = sluice_table_hash_bytes(table->hash, line, length);
            return SLUICE_OK;
        }
        table->fd = open(table->path, O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0644);
        if (table->fd < 0) {
            table->failed = 1;
            sluice_sim_fail(table->sim, "cannot write '%s': %s", table->path, strerror(errno));
            return SLUICE_ERROR;
        }
        size_t hl = strlen(table->header);
        char *header = malloc(hl + 2);
        if (!header) {
            table->failed = 1;
            return SLUICE_ERROR;
        }
        memcpy(header, table->header, hl);
        header[hl] = '\n';
        int rc = write_all(table->fd, header, hl + 1);
        table->bytes = hl + 1;
        table->hash = sluice_table_hash_bytes(SLUICE_TABLE_HASH_START, header, hl + 1);
        free(header);
        if (rc != 0) {
            table->failed = 1;
            sluice_sim_fail(table->sim, "cannot write '%s': %s", table->path, strerror(errno));
            return SLUICE_ERROR;
        }
    }
    if (write_all(table->fd, line, length) != 0) {
        table->failed = 1;
        sluice_sim_fail(table->sim, "cannot write '%s': %s", table->path, strerror(errno));
        return SLUICE_ERROR;
    }
    table->bytes += length;
    table->hash = sluice_table_hash_bytes(table->hash, line, length);
    return SLUICE_OK;
}

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

static int make_directory(const char *path, char *error, size_t size)
{
    char *copy = strdup(path);
    if (!copy) {
        snprintf(error, size, "out of memory");
        return -1;
    }
    for (char *p = copy + 1; *p; p++) {
        if (*p != '/')
            continue;
        *p = '\0';
        if (mkdir(copy, 0755) != 0 && errno != EEXIST) {
            snprintf(error, size, "cannot create output directory '%s': %s", copy,
                     strerror(errno));
            free(copy);
            return -1;
        }
        *p = '/';
    }
    if (mkdir(copy, 0755) != 0 && errno != EEXIST) {
        snprintf(error, size, "cannot create output directory '%s': %s", copy, strerror(errno));
        free(copy);
        return -1;
    }
    free(copy);
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) {
        snprintf(error, size, "output path '%s' is not a directory", path);
        return -1;
    }
    if (access(path, W_OK) != 0) {
        snprintf(error, size, "cannot write to output directory '%s': %s", path, strerror(errno));
        return -1;
    }
    return 0;
}

/* ------------------------------------------------------------- watchdog -- */

/* Checks the state after a step: non-finite values in integrated fields,
 * density outside the band, particles outside the domain, collapsed time
 * step. Returns 0 when healthy, else fills sim->failure. */
static int watchdog(sluice_sim *sim)
{
    const sluice_view *v = &sim->view;
    const sluice_scene *scene = &sim->scene;
    const sluice_index n = v->count;
    if (sim->dt_limit < scene->watchdog.min_time_step || !(sim->dt_limit > 0)) {
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: the time step collapsed to %.3g s, below "
                        "watchdog.min_time_step = %.3g s (the flow has gone unstable: velocities "
                        "or accelerations have grown without bound)",
                        (long long)sim->step, sim->time, sim->dt_limit,
                        (double)scene->watchdog.min_time_step);
        return -1;
    }
    /* state fields: position and every integrated field */
    uint32_t fields = 0;
    const sluice_field_entry *checked[64];
    for (uint32_t f = 0; f < sim->field_count && fields < 64; f++) {
        const sluice_field_entry *e = &sim->fields[f];
        if (e->type != SLUICE_TYPE_REAL)
            continue;
        int state = strcmp(e->name, "position") == 0;
        for (uint32_t r = 0; r < sim->rate_count; r++)
            state |= strcmp(sim->rates[r].state_name, e->name) == 0 ||
                     strcmp(sim->rates[r].rate_name, e->name) == 0;
        if (state)
            checked[fields++] = e;
    }
    const double rho0 = (double)sim->rest_density, band = (double)scene->watchdog.density_band;
    const sluice_real *density =
        sim->density.column >= 0 ? (const sluice_real *)v->columns[sim->density.column] : NULL;
    /* each particle's own rest density, m_i / dx^d: the core gives every
     * particle rest_density dx^d, a two-phase plugin the air rho0_a dx^d */
    const sluice_real *mass =
        sim->mass.column >= 0 ? (const sluice_real *)v->columns[sim->mass.column] : NULL;
    const double inverse_volume = 1.0 / pow((double)sim->spacing, (double)v->dimensions);
    sluice_index first = n;
    int what = 0; /* 1 non-finite, 2 density band, 3 outside domain */
    const sluice_field_entry *bad_field = NULL;
    uint32_t bad_component = 0;
    for (uint32_t k = 0; k < fields; k++) {
        const sluice_field_entry *e = checked[k];
        for (uint32_t c = 0; c < e->components; c++) {
            const sluice_real *x = v->columns[e->column + (int32_t)c];
            sluice_index found = n;
#pragma omp parallel for schedule(static) reduction(min : found)
            for (sluice_index i = 0; i < n; i++)
                if (!isfinite(x[i]) && i < found)
                    found = i;
            if (found < first) {
                first = found;
                what = 1;
                bad_field = e;
                bad_component = c;
            }
        }
    }
    if (!what && density) {
        sluice_index found = n;
        double deviation = 0; /* fluid only: wall particles' densities are a wall model's */
        const uint8_t *kind = v->kind;
#pragma omp parallel for schedule(static) reduction(min : found) reduction(max : deviation)
        for (sluice_index i = 0; i < n; i++) {
            const double rest = mass ? (double)mass[i] * inverse_volume : rho0;
            double r = (double)density[i] / rest - 1.0;
            if (!(fabs(r) <= band) && i < found)
                found = i;
            if (kind[i] == SLUICE_KIND_FLUID && fabs(r) > deviation)
                deviation = fabs(r);
        }
        if (deviation > sim->max_density_deviation)
            sim->max_density_deviation = deviation;
        if (found < n) {
            first = found;
            what = 2;
        }
    }
    if (!what) {
        for (uint32_t d = 0; d < v->dimensions; d++) {
            if (scene->domain.periodic[d])
                continue;
            const sluice_real *x = v->position[d];
            const double lo = (double)scene->domain.min[d], hi = (double)scene->domain.max[d];
            sluice_index found = n;
#pragma omp parallel for schedule(static) reduction(min : found)
            for (sluice_index i = 0; i < n; i++)
                if (!((double)x[i] >= lo && (double)x[i] < hi) && i < found)
                    found = i;
            if (found < first) {
                first = found;
                what = 3;
                bad_component = d;
            }
        }
    }
    /* through a wall: fluid particles deeper than wall_penetration spacings
     * behind the nearest wall (wall_watch.h) */
    double wall_depth = 0;
    uint32_t bad_wall = UINT32_MAX, bad_element = UINT32_MAX;
    if (!what && sim->wall_watch.cells.wall_count > 0) {
        const double allowed = (double)scene->watchdog.wall_penetration * (double)sim->spacing;
        const uint8_t *kind = v->kind;
        sluice_index found = n;
#pragma omp parallel for schedule(static) reduction(min : found)
        for (sluice_index i = 0; i < n; i++) {
            if (kind[i] != SLUICE_KIND_FLUID || i >= found)
                continue;
            sluice_real p[3] = {v->position[0][i], v->position[1][i],
                                v->dimensions == 3 ? v->position[2][i] : 0};
            int beyond;
            uint32_t w, e;
            double d = sluice_wall_watch_distance(&sim->wall_watch, p, &beyond, &w, &e);
            if (d < -allowed)
                found = i;
        }
        if (found < n) {
            first = found;
            what = 4;
            sluice_real p[3] = {v->position[0][found], v->position[1][found],
                                v->dimensions == 3 ? v->position[2][found] : 0};
            int beyond;
            wall_depth = -sluice_wall_watch_distance(&sim->wall_watch, p, &beyond, &bad_wall,
                                                     &bad_element);
        }
    }
    if (!what)
        return 0;
    char who[256], writers[512];
    const sluice_index i = first;
    if (v->dimensions == 3)
        snprintf(who, sizeof who, "particle id %llu (%s, index %u) at (%.6g, %.6g, %.6g) m",
                 (unsigned long long)v->id[i], sluice_kind_name(v->kind[i]),
                 i, (double)v->position[0][i], (double)v->position[1][i], (double)v->position[2][i]);
    else
        snprintf(who, sizeof who, "particle id %llu (%s, index %u) at (%.6g, %.6g) m",
                 (unsigned long long)v->id[i], sluice_kind_name(v->kind[i]),
                 i, (double)v->position[0][i], (double)v->position[1][i]);
    if (what == 1) {
        const sluice_real *x = v->columns[bad_field->column + (int32_t)bad_component];
        char comp[16] = "";
        if (bad_field->components > 1)
            snprintf(comp, sizeof comp, "[%u]", bad_component);
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: %s: field '%s'%s = %g is not finite (written by "
                        "%s; integrated by '%s')",
                        (long long)sim->step, sim->time, who, bad_field->name, comp, (double)x[i],
                        sluice_field_writers(sim, bad_field, writers, sizeof writers),
                        sim->instances[sim->integrator].name);
    } else if (what == 2) {
        const sluice_field_entry *e = sluice_sim_find_field(sim, "density");
        const double rest = mass ? (double)mass[i] * inverse_volume : rho0;
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: %s: field 'density' = %.6g kg m^-3 is outside the "
                        "band [%.6g, %.6g] = its rest density (mass / spacing^d) x (1 -/+ "
                        "watchdog.density_band) (written by %s; integrated by '%s')",
                        (long long)sim->step, sim->time, who, (double)density[i],
                        rest * (1 - band), rest * (1 + band),
                        e ? sluice_field_writers(sim, e, writers, sizeof writers) : "?",
                        sim->instances[sim->integrator].name);
    } else if (what == 4) {
        const sluice_scene_wall *wall = &scene->walls[bad_wall];
        const sluice_field_entry *e = sluice_sim_find_field(sim, "position");
        char name[160] = "";
        if (wall->name && wall->name[0])
            snprintf(name, sizeof name, " ('%s')", wall->name);
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: %s has gone through wall %u%s (handled by '%s'): "
                        "it is %.4g m = %.3g spacings behind its %s %u, deeper than "
                        "watchdog.wall_penetration = %g spacings (field 'position', written by "
                        "%s; integrated by '%s')",
                        (long long)sim->step, sim->time, who, bad_wall, name,
                        sim->walls[bad_wall].scheme ? sim->walls[bad_wall].scheme : "?",
                        wall_depth, wall_depth / (double)sim->spacing,
                        v->dimensions == 3 ? "triangle" : "segment", bad_element,
                        (double)scene->watchdog.wall_penetration,
                        e ? sluice_field_writers(sim, e, writers, sizeof writers) : "?",
                        sim->instances[sim->integrator].name);
    } else {
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: %s left the domain along %c (domain.min/max = "
                        "%g/%g m; field 'position', integrated by '%s')",
                        (long long)sim->step, sim->time, who, "xyz"[bad_component],
                        (double)scene->domain.min[bad_component],
                        (double)scene->domain.max[bad_component],
                        sim->instances[sim->integrator].name);
    }
    return -1;
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
            if (make_directory(output_directory, error, sizeof error) != 0) {
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
    }
    sim->wall_start = sluice_wall_clock();
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
        sluice_sim_checkpoint(sim, NULL) != SLUICE_OK)
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
         * watchdog's scan finds it */
        const double limit = sim->dt_limit;
        sim->dt_limit = INFINITY;
        const int found = watchdog(sim) != 0;
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
    if (sim->step % sim->scene.watchdog.every == 0 && watchdog(sim) != 0)
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

static int write_run_json(sluice_sim *sim, int status)
{
    /* across ranks: the counts of every rank, written by rank 0 (the
     * reduction is collective, so every rank comes here) */
    const size_t state_bytes = sluice_particles_bytes(&sim->particles) +
                               sluice_grid_bytes(&sim->grid) +
                               sluice_pair_engine_bytes(&sim->engine);
    struct rusage usage;
    double peak = getrusage(RUSAGE_SELF, &usage) == 0 ? (double)usage.ru_maxrss * 1024 : -1;
    double sums[6] = {(double)sim->particles.count, (double)sim->removed,
                      (double)sim->particle_steps,
                      (double)sluice_pair_engine_pairs(&sim->engine), (double)state_bytes,
                      (double)(sim->particle_steps - sim->particle_steps_at_start)};
    double maxima[2] = {peak, sim->max_density_deviation};
    if (sluice_comm_reduce(&sim->comm, sums, 6, SLUICE_REDUCE_SUM) != 0 ||
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
    fprintf(f, "  \"neighbour_list_rebuilds\": %llu,\n", (unsigned long long)sim->grid.rebuilds);
    /* memory: the particle store, the grid and the Verlet list, and the
     * pair engine's buffers, per particle at the end (over every rank); the
     * process's peak resident set (program and libraries included, about
     * 10 MB; across ranks the largest rank's) */
    fprintf(f, "  \"state_bytes_per_particle\": %.1f,\n",
            particles_final > 0 ? bytes / particles_final : 0.0);
    fprintf(f, "  \"peak_memory_bytes\": %.0f,\n", peak);
    fprintf(f, "  \"threads\": %d,\n", sim->threads);
    fprintf(f, "  \"max_density_deviation\": %.6g,\n", max_deviation);
    fprintf(f, "  \"smoothing_length\": %.9g,\n", (double)sim->smoothing_length);
    fprintf(f, "  \"spacing\": %.9g,\n", (double)sim->spacing);
    fprintf(f, "  \"failure\": ");
    json_string(f, sim->failure);
    fprintf(f, ",\n  \"plugins\": [");
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        const sluice_instance *in = &sim->instances[k];
        fprintf(f, "%s\n    {\"component\": ", k ? "," : "");
        json_string(f, in->name);
        fprintf(f, ", \"library\": ");
        json_string(f, in->library->name);
        fprintf(f, ", \"version\": ");
        json_string(f, in->library->version);
        fprintf(f, ", \"path\": ");
        json_string(f, in->path);
        fprintf(f, "}");
    }
    fprintf(f, "\n  ]\n}\n");
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
        /* SLUICE_FINISH_INTERRUPTED is 1.5: older plugins see a complete run */
        int finish_status = status == SLUICE_RUN_COMPLETE ? SLUICE_FINISH_COMPLETE
                            : status != SLUICE_RUN_INTERRUPTED ? SLUICE_FINISH_FAILED
                            : in->library->abi_minor >= 5      ? SLUICE_FINISH_INTERRUPTED
                                                               : SLUICE_FINISH_COMPLETE;
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
    if (sim->output_directory && write_run_json(sim, status) != 0 &&
        (status == SLUICE_RUN_COMPLETE || status == SLUICE_RUN_INTERRUPTED))
        status = SLUICE_RUN_FAILED;
    return status;
}

static void progress_line(sluice_sim *sim, int final)
{
    double now = sluice_wall_clock();
    if (!final && now - sim->last_progress < 0.5)
        return;
    sim->last_progress = now;
    double elapsed = now - sim->wall_start;
    /* this invocation's steps and simulated time (a restart begins past 0) */
    double rate = elapsed > 0 ? (double)(sim->step - sim->step_at_start) / elapsed : 0;
    double done = sim->time - sim->time_at_start;
    double eta = done > 0 ? elapsed * (sim->end - sim->time) / done : 0;
    int h = (int)(eta / 3600), m = (int)(fmod(eta, 3600) / 60), s = (int)fmod(eta, 60);
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
                sluice_sim_checkpoint(sim, NULL) != SLUICE_OK)
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
