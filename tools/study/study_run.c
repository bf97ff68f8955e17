/* The runs of a study: each checked by `sluice check` before any runs (a bad
 * edit is reported at its place in the study file), then run by `sluice run`
 * into OUT/runs/NAME, several at a time, with a record per finished run
 * (OUT/records/NAME.txt: the command, exit status, CPU and wall seconds)
 * that makes the study resumable: a run whose record matches its command is
 * not redone. Progress and an ETA for the whole study on stderr. A run of an
 * external value (another program, a peer code) runs its shell command
 * instead, where its `requires` command succeeds (else it is skipped with a
 * note). */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <dirent.h>
#include <ftw.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "study.h"

double study_clock(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* --------------------------------------------------------- subprocesses -- */

/* Runs argv with stdout and stderr captured (malloc'd, NUL-terminated);
 * returns the exit status, or -1 when it could not run. */
static int capture(char *const *argv, char **out, char **err)
{
    FILE *fo = tmpfile(), *fe = tmpfile();
    if (!fo || !fe) {
        if (fo)
            fclose(fo);
        if (fe)
            fclose(fe);
        return -1;
    }
    pid_t pid = fork();
    if (pid == 0) {
        dup2(fileno(fo), STDOUT_FILENO);
        dup2(fileno(fe), STDERR_FILENO);
        execv(argv[0], argv);
        fprintf(stderr, "cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    int status = -1;
    if (pid > 0)
        while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
            ;
    FILE *files[2] = {fo, fe};
    char **texts[2] = {out, err};
    for (int i = 0; i < 2; i++) {
        long size = (fseek(files[i], 0, SEEK_END), ftell(files[i]));
        rewind(files[i]);
        *texts[i] = calloc((size_t)(size > 0 ? size : 0) + 1, 1);
        if (*texts[i] && size > 0 && fread(*texts[i], 1, (size_t)size, files[i]) != (size_t)size)
            (*texts[i])[0] = '\0';
        fclose(files[i]);
    }
    if (pid < 0 || !*out || !*err)
        return -1;
    return WIFEXITED(status) ? WEXITSTATUS(status)
                             : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

/* Whether diag holds `message` already (the same edit fails in every run
 * that has it: reported once). */
static int reported(const study *s, const char *message)
{
    for (size_t d = 0; d < sluice_diag_count(s->diag); d++)
        if (strcmp(sluice_diag_message(s->diag, d), message) == 0)
            return 1;
    return 0;
}

/* A message of `sluice check` about one of the run's edits ("--set #3:1:7:
 * error: ...") put at the study-file node behind that edit; a message about
 * the scene itself (its own file:line:column) as it is. */
static void relay_message(study *s, const study_run *r, const char *line)
{
    static const char *const options[] = {"--remove", "--swap", "--set"};
    for (int o = 0; o < 3; o++) {
        size_t n = strlen(options[o]);
        unsigned k = 0;
        int offset = 0;
        if (strncmp(line, options[o], n) != 0 ||
            sscanf(line + n, " #%u:%*d:%*d:%n", &k, &offset) < 1 || offset == 0)
            continue;
        const char *text = line + n + offset;
        while (*text == ' ')
            text++;
        if (strncmp(text, "error: ", 7) == 0)
            text += 7;
        if (strncmp(text, options[o], n) == 0 && strncmp(text + n, ": ", 2) == 0)
            text += n + 2; /* "--swap: cannot swap ...": the study's line says where */
        unsigned seen = 0; /* the k-th occurrence of the option in the command */
        for (size_t i = 0; i + 1 < r->argc; i++)
            if (strcmp(r->argv[i], options[o]) == 0 && ++seen == k) {
                const sluice_node *at = r->origin[i + 1];
                char *message = study_printf("%s:%d:%d: error: %s", at->file ? at->file : s->path,
                                             at->line, at->column, text);
                if (!reported(s, message))
                    study_error(s, at, "%s", text);
                free(message);
                return;
            }
    }
    if (!strstr(line, "error") || reported(s, line))
        return;
    char file[4096];
    int l = 0, c = 0, offset = 0;
    if (sscanf(line, "%4095[^:]:%d:%d: error: %n", file, &l, &c, &offset) == 3 && offset > 0)
        sluice_diag_add(s->diag, SLUICE_SEVERITY_ERROR, file, l, c, "%s", line + offset);
    else if (strncmp(line, "sluice: error: ", 15) == 0)
        sluice_diag_add(s->diag, SLUICE_SEVERITY_ERROR, s->path, 1, 1, "run %s: %s", r->name,
                        line + 15);
    else
        sluice_diag_add(s->diag, SLUICE_SEVERITY_ERROR, s->path, 1, 1, "run %s: %s", r->name, line);
}

/* `sluice check` of one run: its particles, end time and dimensions. */
static int check_run(study *s, study_run *r)
{
    char **argv = calloc(r->argc + 1, sizeof *argv);
    if (!argv)
        return 1;
    size_t n = 0;
    argv[n++] = r->argv[0];
    argv[n++] = "check";
    argv[n++] = r->argv[2];
    for (size_t i = 5; i < r->argc; i++) {
        if (strcmp(r->argv[i], "--threads") == 0) {
            i++;
            continue;
        }
        if (strcmp(r->argv[i], "--progress") == 0)
            continue;
        argv[n++] = r->argv[i];
    }
    argv[n] = NULL;
    char *out = NULL, *err = NULL;
    int status = capture(argv, &out, &err);
    free(argv);
    int errors = 0;
    unsigned long long particles = 0;
    double end = 0;
    const char *valid = out ? strstr(out, ": valid ") : NULL;
    const char *count = valid ? strstr(valid, " scene") : NULL;
    count = count ? strchr(count, ',') : NULL;
    const char *end_time = valid ? strstr(valid, "end time ") : NULL;
    if (status == 0 && valid && count && end_time &&
        sscanf(valid, ": valid %dD", &r->dimensions) == 1 &&
        sscanf(count, ", %llu particles", &particles) == 1 &&
        sscanf(end_time + 9, "%lf", &end) == 1) {
        r->particles = (double)particles;
        r->end_time = end;
        /* steps grow as 1/dx, that is as N^(1/d) at a fixed geometry */
        r->work = r->particles * pow(r->particles, 1.0 / r->dimensions) * end;
    } else if (status < 0 || status == 127) {
        study_error(s, NULL, "cannot run '%s' (sluice check)", r->argv[0]);
        errors++;
    } else {
        for (char *save = NULL, *line = strtok_r(err ? err : "", "\n", &save); line;
             line = strtok_r(NULL, "\n", &save))
            relay_message(s, r, line);
        if (!sluice_diag_error_count(s->diag))
            study_error(s, NULL, "run %s: sluice check gave exit %d and no summary line", r->name,
                        status);
        errors++;
    }
    free(out);
    free(err);
    return errors;
}

/* An external run's `requires`: NULL when the program is there, else the
 * note why its runs are skipped (malloc'd). */
static char *check_requirement(const study_edits *e)
{
    if (!e->requires)
        return NULL;
    char *argv[] = {"/bin/sh", "-c", e->requires, NULL};
    char *out = NULL, *err = NULL;
    int status = capture(argv, &out, &err);
    char *note = NULL;
    if (status != 0) {
        const char *said = err && *err ? err : out && *out ? out : "";
        note = study_printf("not installed here: `%s` gave exit %d%s%.*s", e->requires, status,
                            *said ? ": " : "", (int)strcspn(said, "\n"), said);
    }
    free(out);
    free(err);
    return note;
}

/* ------------------------------------------------------------- records -- */

/* FNV-1a of the base scene's bytes: a run is redone when its scene changed
 * (an external run has no scene: its command alone says what it is). */
static unsigned long long scene_hash(const study_run *r)
{
    if (r->external)
        return 0;
    unsigned long long h = 1469598103934665603ULL;
    FILE *f = fopen(r->scene, "rb");
    if (!f)
        return 0;
    int c;
    while ((c = getc(f)) != EOF)
        h = (h ^ (unsigned char)c) * 1099511628211ULL;
    fclose(f);
    return h;
}

static char *record_path(const study *s, const study_run *r)
{
    return study_printf("%s/records/%s.txt", s->out, r->name);
}

/* The run directory's checkpoint of the latest step (malloc'd), or NULL. */
static char *latest_checkpoint(const study *s, const study_run *r)
{
    char *dir = study_printf("%s/runs/%s", s->out, r->name);
    DIR *d = opendir(dir);
    char *best = NULL;
    unsigned long long best_step = 0;
    for (struct dirent *e; d && (e = readdir(d));) {
        unsigned long long step = 0;
        int n = 0;
        if (sscanf(e->d_name, "checkpoint_%llu.h5%n", &step, &n) == 1 &&
            (size_t)n == strlen(e->d_name) && (!best || step > best_step)) {
            free(best);
            best = study_printf("%s/%s", dir, e->d_name);
            best_step = step;
        }
    }
    if (d)
        closedir(d);
    free(dir);
    return best;
}

/* A finished run of an earlier invocation with the same command: reused.
 * One stopped by a signal is continued from its checkpoint. */
static int read_record(study *s, study_run *r)
{
    char *path = record_path(s, r);
    FILE *f = fopen(path, "r");
    free(path);
    if (!f)
        return 0;
    char line[65536];
    int same = 0, have_exit = 0, same_scene = 0;
    unsigned long long hash = 0;
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = '\0';
        if (strncmp(line, "command: ", 9) == 0)
            same = strcmp(line + 9, r->command) == 0;
        else if (sscanf(line, "scene_hash: %llx", &hash) == 1)
            same_scene = hash == scene_hash(r);
        else if (sscanf(line, "exit: %d", &r->exit_code) == 1)
            have_exit = 1;
        else if (sscanf(line, "cpu_seconds: %lf", &r->cpu_seconds) != 1)
            sscanf(line, "wall_seconds: %lf", &r->wall_seconds);
    }
    fclose(f);
    if (!same || !same_scene || !have_exit)
        return 0;
    if (r->exit_code == 5 && !r->external) {
        /* stopped by a signal after a whole step: continue from its last checkpoint */
        r->restart = latest_checkpoint(s, r);
        r->cpu_before = r->restart ? r->cpu_seconds : 0;
        r->cpu_seconds = 0;
        return 0;
    }
    if (r->exit_code == 0) {
        if (study_read_run_json(s, r) != 0)
            return 0; /* the directory was changed since: run it again */
        r->state = RUN_DONE;
    } else {
        if (s->retry_failed)
            return 0;
        study_read_run_json(s, r);
        r->state = RUN_FAILED;
    }
    r->reused = 1;
    return 1;
}

static void write_record(study *s, const study_run *r)
{
    char *path = record_path(s, r);
    char *temporary = study_printf("%s.tmp", path);
    FILE *f = fopen(temporary, "w");
    if (f) {
        fprintf(f,
                "command: %s\nscene_hash: %llx\nexit: %d\ncpu_seconds: %.6f\nwall_seconds: "
                "%.6f\n",
                r->command, scene_hash(r), r->exit_code, r->cpu_seconds, r->wall_seconds);
        if (fclose(f) == 0)
            rename(temporary, path);
    }
    free(temporary);
    free(path);
}

/* The top-level figures of OUT/runs/NAME/run.json (the core writes it; its
 * scalars precede "plugins"). 0, or -1 without a complete run.json. */
int study_run_json_head(const study *s, const study_run *r, char *text, size_t size)
{
    char *path = study_printf("%s/runs/%s/run.json", s->out, r->name);
    FILE *f = fopen(path, "r");
    free(path);
    if (!f)
        return -1;
    size_t n = fread(text, 1, size - 1, f);
    fclose(f);
    text[n] = '\0';
    char *plugins = strstr(text, "\"plugins\"");
    if (plugins)
        *plugins = '\0';
    return 0;
}

int study_read_run_json(study *s, study_run *r)
{
    char text[8192];
    if (study_run_json_head(s, r, text, sizeof text) != 0)
        return -1;
    const char *status = strstr(text, "\"status\": \"");
    const char *failure = strstr(text, "\"failure\": \"");
    const char *steps = strstr(text, "\"steps\": ");
    const char *particle_steps = strstr(text, "\"particle_steps\": ");
    r->failure[0] = '\0';
    if (failure)
        sscanf(failure + 12, "%1023[^\"]", r->failure);
    const char *end_time = strstr(text, "\"end_time\": ");
    if (end_time && !(r->end_time > 0))
        r->end_time = strtod(end_time + 12, NULL);
    r->steps = steps ? strtod(steps + 9, NULL) : NAN;
    r->particle_steps = particle_steps ? strtod(particle_steps + 18, NULL) : NAN;
    /* an external program's own figures of its solver's CPU and wall time
     * (without its set-up, e.g. compiling kernels) replace the measured ones */
    const char *cpu = r->external ? strstr(text, "\"cpu_seconds\": ") : NULL;
    if (cpu && strtod(cpu + 15, NULL) > 0)
        r->cpu_seconds = strtod(cpu + 15, NULL);
    const char *wall = r->external ? strstr(text, "\"wall_seconds\": ") : NULL;
    if (wall && strtod(wall + 16, NULL) > 0)
        r->wall_seconds = strtod(wall + 16, NULL);
    return status && strncmp(status + 11, "complete\"", 9) == 0 ? 0 : -1;
}

/* ------------------------------------------------------------ launching -- */

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    (void)ftw;
    return remove(path);
}

static volatile sig_atomic_t stop_requested;
static void on_signal(int sig)
{
    stop_requested = sig;
}

static int launch(study *s, study_run *r)
{
    char *dir = study_printf("%s/runs/%s", s->out, r->name);
    if (!r->restart) /* a run not finished and not resumable: from the start */
        nftw(dir, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    if (r->external && study_mkdirs(dir) != 0) {
        free(dir);
        return -1;
    }
    char *record = record_path(s, r);
    unlink(record);
    free(record);
    /* the command, with --restart CHECKPOINT when it continues */
    char **argv = calloc(r->argc + 3, sizeof *argv);
    if (!argv) {
        free(dir);
        return -1;
    }
    memcpy(argv, r->argv, r->argc * sizeof *argv);
    if (r->restart) {
        argv[r->argc] = "--restart";
        argv[r->argc + 1] = r->restart;
    }
    char *log = study_printf("%s/logs/%s.log", s->out, r->name);
    int fd = open(log, O_WRONLY | O_CREAT | (r->restart ? O_APPEND : O_TRUNC) | O_CLOEXEC, 0666);
    free(log);
    free(dir);
    if (fd < 0) {
        free(argv);
        return -1;
    }
    pid_t pid = fork();
    if (pid == 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
        signal(SIGINT, SIG_DFL);
        signal(SIGTERM, SIG_DFL);
        /* a process group of its own: a terminal's Ctrl-C reaches the study,
         * which passes it on once (a second signal would end the run at once,
         * without its checkpoint) */
        setpgid(0, 0);
        execv(argv[0], argv);
        fprintf(stderr, "sluice-study: cannot run %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    close(fd);
    free(argv);
    if (pid < 0)
        return -1;
    r->pid = pid;
    r->state = RUN_RUNNING;
    r->started = study_clock();
    return 0;
}

/* The share of a running run done, from the last progress line of its log
 * ("\r  t 0.1234 / 1.0000 s ..."). */
static double running_fraction(const study *s, const study_run *r)
{
    char *log = study_printf("%s/logs/%s.log", s->out, r->name);
    FILE *f = fopen(log, "r");
    free(log);
    if (!f)
        return 0;
    char tail[1024];
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, size > (long)sizeof tail - 1 ? size - (long)sizeof tail + 1 : 0, SEEK_SET);
    size_t n = fread(tail, 1, sizeof tail - 1, f);
    fclose(f);
    tail[n] = '\0';
    double t = 0, end = 0, fraction = 0;
    for (char *p = tail; (p = strstr(p, "  t ")); p += 4)
        if (sscanf(p, "  t %lf / %lf s", &t, &end) == 2 && end > 0)
            fraction = t / end;
    return fraction < 0 ? 0 : fraction > 1 ? 1 : fraction;
}

static void format_duration(double seconds, char *out, size_t size)
{
    if (!isfinite(seconds) || seconds < 0)
        snprintf(out, size, "?");
    else if (seconds < 60)
        snprintf(out, size, "%.0fs", seconds);
    else if (seconds < 3600)
        snprintf(out, size, "%dm%02ds", (int)(seconds / 60), (int)fmod(seconds, 60));
    else
        snprintf(out, size, "%dh%02dm", (int)(seconds / 3600), (int)fmod(seconds / 60, 60));
}

static void progress(study *s, double start, int final)
{
    size_t done = 0, failed = 0, failed_before = 0, running = 0, reused = 0, skipped = 0;
    double total = 0, finished = 0, this_run = 0;
    for (size_t i = 0; i < s->run_count; i++) {
        study_run *r = &s->runs[i];
        if (r->state == RUN_SKIPPED) {
            skipped++;
            continue;
        }
        if (r->reused) {
            reused++;
            failed_before += r->state == RUN_FAILED;
            continue;
        }
        total += r->work;
        if (r->state == RUN_DONE || r->state == RUN_FAILED) {
            finished += r->work;
            this_run += r->work;
            done += r->state == RUN_DONE;
            failed += r->state == RUN_FAILED;
        } else if (r->state == RUN_RUNNING) {
            running++;
            this_run += r->work * running_fraction(s, r);
        }
    }
    (void)finished;
    double elapsed = study_clock() - start;
    double eta = this_run > 0 ? elapsed * (total - this_run) / this_run : NAN;
    char e[32], t[32];
    format_duration(elapsed, e, sizeof e);
    format_duration(eta, t, sizeof t);
    int tty = isatty(STDERR_FILENO);
    fprintf(stderr,
            "%sstudy: %zu/%zu runs done (%zu failed, %zu running, %zu from before%s), %.0f %% of "
            "the work, elapsed %s, ETA %s%s",
            tty ? "\r" : "", done + failed + reused + skipped, s->run_count,
            failed + failed_before, running, reused, skipped ? ", some skipped" : "",
            total > 0 ? 100 * this_run / total : 100.0, e, final ? "0s" : t,
            tty && !final ? "   " : "\n");
    fflush(stderr);
}

static void finish(study *s, study_run *r, int status, const struct rusage *usage)
{
    r->wall_seconds = study_clock() - r->started;
    r->cpu_seconds = (double)usage->ru_utime.tv_sec + 1e-6 * (double)usage->ru_utime.tv_usec +
                     (double)usage->ru_stime.tv_sec + 1e-6 * (double)usage->ru_stime.tv_usec;
    r->exit_code = WIFEXITED(status) ? WEXITSTATUS(status)
                                     : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    r->pid = 0;
    r->cpu_seconds += r->cpu_before; /* a continued run costs all its parts */
    if (r->exit_code == 5 && !r->external) {
        r->state = RUN_INTERRUPTED; /* recorded: the next invocation continues it */
        write_record(s, r);
        return;
    }
    if (stop_requested && r->exit_code != 0) {
        r->state = RUN_INTERRUPTED; /* not recorded: run again next time */
        return;
    }
    int complete = study_read_run_json(s, r) == 0;
    r->state = r->exit_code == 0 && complete ? RUN_DONE : RUN_FAILED;
    write_record(s, r);
    if (r->state == RUN_FAILED && !s->quiet)
        fprintf(stderr, "%sstudy: run %s failed (exit %d%s%s); its log: %s/logs/%s.log\n",
                isatty(STDERR_FILENO) ? "\n" : "", r->name, r->exit_code, r->failure[0] ? ": " : "",
                r->failure, s->out, r->name);
}

int study_check_runs(study *s)
{
    int errors = 0;
    double work = 0;
    size_t checked = 0;
    for (size_t i = 0; i < s->run_count; i++) {
        study_run *r = &s->runs[i];
        if (r->external) {
            /* its requirement, once per value */
            size_t j = 0;
            while (j < i && s->runs[j].external != r->external)
                j++;
            r->skipped = j < i ? (s->runs[j].skipped ? study_strdup(s->runs[j].skipped) : NULL)
                               : check_requirement(r->external);
            if (r->skipped) {
                r->state = RUN_SKIPPED;
                continue;
            }
        }
        if (read_record(s, r)) {
            r->work = 0;
            continue;
        }
        if (!r->external) {
            errors += check_run(s, r);
            work += r->work;
            checked++;
        }
    }
    /* an external run's work is unknown before it runs: the ETA counts it as
     * an average Sluice run */
    for (size_t i = 0; i < s->run_count; i++)
        if (s->runs[i].external && s->runs[i].state == RUN_PENDING)
            s->runs[i].work = checked ? work / (double)checked : 1;
    return errors;
}

int study_execute(study *s)
{
    const char *dirs[] = {"runs", "logs", "records"};
    for (int d = 0; d < 3; d++) {
        char *path = study_printf("%s/%s", s->out, dirs[d]);
        if (study_mkdirs(path) != 0) {
            fprintf(stderr, "sluice-study: error: cannot create %s: %s\n", path, strerror(errno));
            free(path);
            return -1;
        }
        free(path);
    }
    struct sigaction action = {.sa_handler = on_signal};
    sigaction(SIGINT, &action, NULL);
    sigaction(SIGTERM, &action, NULL);
    double start = study_clock(), last = 0;
    size_t next = 0, running = 0;
    int forwarded = 0;
    int jobs = s->jobs > 0 ? s->jobs : 1;
    for (;;) {
        while (!stop_requested && running < (size_t)jobs && next < s->run_count) {
            study_run *r = &s->runs[next++];
            if (r->state != RUN_PENDING)
                continue;
            if (launch(s, r) != 0) {
                fprintf(stderr, "sluice-study: error: cannot start run %s: %s\n", r->name,
                        strerror(errno));
                r->state = RUN_FAILED;
                continue;
            }
            running++;
        }
        if (running == 0 && (stop_requested || next >= s->run_count))
            break;
        int status = 0;
        struct rusage usage;
        pid_t pid = wait4(-1, &status, WNOHANG, &usage);
        if (pid > 0) {
            for (size_t i = 0; i < s->run_count; i++)
                if (s->runs[i].state == RUN_RUNNING && s->runs[i].pid == pid) {
                    finish(s, &s->runs[i], status, &usage);
                    running--;
                }
            if (!s->quiet && (running > 0 || next < s->run_count))
                progress(s, start, 0);
            continue;
        }
        if (stop_requested && !forwarded) {
            /* the runs stop too, after a whole step, with a checkpoint */
            for (size_t i = 0; i < s->run_count; i++)
                if (s->runs[i].state == RUN_RUNNING) /* an external one: its whole group */
                    kill(s->runs[i].external ? -s->runs[i].pid : s->runs[i].pid,
                         (int)stop_requested);
            forwarded = 1;
        }
        double now = study_clock();
        if (!s->quiet && now - last >= (isatty(STDERR_FILENO) ? 1.0 : 60.0)) {
            progress(s, start, 0);
            last = now;
        }
        usleep(100000);
    }
    if (!s->quiet)
        progress(s, start, !stop_requested);
    return stop_requested ? 1 : 0;
}
