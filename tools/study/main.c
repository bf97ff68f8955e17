/* sluice-study (also `sluice study`): runs a comparative study (study.h,
 * docs/studies.md).
 *
 *   sluice study STUDY.yaml [STUDY.yaml ...] [--out DIR] [--profile NAME]
 *                [--jobs N] [--dry-run] [--summary] [--retry-failed] [--quiet]
 *
 * Exit status: 0 the study ran (runs that failed or went unstable are
 * recorded in its table), 2 bad input (every problem as file:line:column,
 * nothing run), 4 another failure, 5 stopped by SIGINT/SIGTERM (finished
 * runs are kept; the same command goes on). */
#define _GNU_SOURCE
#include <libgen.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "study.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: sluice study STUDY.yaml [STUDY.yaml ...] [OPTIONS]\n"
            "       (sluice-study, the same program)\n"
            "Runs every combination of the study's axes as a run directory DIR/runs/NAME, then\n"
            "writes DIR/study.csv, DIR/study.md, DIR/orders.csv and PNG plots in DIR/plots\n"
            "(gnuplot). A run finished by an earlier invocation with the same command is not\n"
            "redone; a failed one is kept as failed. docs/studies.md\n"
            "  -o, --out DIR        the study's directory (default runs/<study file\n"
            "                       name>[-<profile>]; with several study files,\n"
            "                       DIR/<study file name> for each and DIR/studies.md)\n"
            "  --profile NAME       one of the study's profiles (its edits and axis values,\n"
            "                       e.g. a quick one)\n"
            "  -j, --jobs N         runs at a time (default: the study's 'jobs', 1)\n"
            "  --dry-run            check the study and every run's scene, list the runs\n"
            "  --summary            no runs: the reports from what is there\n"
            "  --retry-failed       run the failed runs again\n"
            "  -q, --quiet          no progress messages\n"
            "  -h, --help           this text\n"
            "The sluice program and sluice-analyze are $SLUICE and $SLUICE_ANALYZE, else the\n"
            "ones beside this program.\n"
            "Exit status: 0 the study ran (failed runs are recorded in its table), 2 bad input,\n"
            "4 another failure, 5 stopped by SIGINT/SIGTERM (the same command goes on).\n");
}

/* The sluice program and sluice-analyze: $SLUICE and $SLUICE_ANALYZE, or
 * next to this program (the build tree: ../sluice; an install: ./sluice). */
static char *program_beside(const char *env, const char *const *relative, size_t count)
{
    const char *given = getenv(env);
    if (given && *given)
        return study_strdup(given);
    char self[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0)
        return NULL;
    self[n] = '\0';
    char *dir = dirname(self);
    for (size_t i = 0; i < count; i++) {
        char *path = study_printf("%s/%s", dir, relative[i]);
        struct stat st;
        if (stat(path, &st) == 0 && S_ISREG(st.st_mode) && access(path, X_OK) == 0)
            return path;
        free(path);
    }
    return NULL;
}

typedef struct command_line {
    const char **files;
    size_t file_count;
    const char *out, *profile;
    int jobs, dry_run, summary_only, retry_failed, quiet;
} command_line;

static int parse(int argc, char **argv, command_line *c)
{
    c->files = calloc((size_t)argc + 1, sizeof *c->files);
    if (!c->files)
        return -1;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (strcmp(arg, "--out") == 0 || strcmp(arg, "-o") == 0 || strcmp(arg, "--profile") == 0) {
            if (i + 1 >= argc) {
                fprintf(stderr, "sluice-study: error: %s needs a value\n", arg);
                return -1;
            }
            if (strcmp(arg, "--profile") == 0)
                c->profile = argv[++i];
            else
                c->out = argv[++i];
        } else if (strcmp(arg, "--jobs") == 0 || strcmp(arg, "-j") == 0) {
            char *end = NULL;
            long jobs = i + 1 < argc ? strtol(argv[++i], &end, 10) : 0;
            if (!end || *end || jobs < 1 || jobs > 4096) {
                fprintf(stderr, "sluice-study: error: --jobs needs a whole number from 1 to "
                                "4096\n");
                return -1;
            }
            c->jobs = (int)jobs;
        } else if (strcmp(arg, "--dry-run") == 0)
            c->dry_run = 1;
        else if (strcmp(arg, "--summary") == 0)
            c->summary_only = 1;
        else if (strcmp(arg, "--retry-failed") == 0)
            c->retry_failed = 1;
        else if (strcmp(arg, "--quiet") == 0 || strcmp(arg, "-q") == 0)
            c->quiet = 1;
        else if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0) {
            usage(stdout);
            exit(0);
        } else if (arg[0] == '-') {
            fprintf(stderr,
                    "sluice-study: error: unknown option '%s' ('sluice study --help' lists "
                    "them)\n",
                    arg);
            return -1;
        } else
            c->files[c->file_count++] = arg;
    }
    if (!c->file_count) {
        fprintf(stderr, "sluice-study: error: no study file given\n");
        return -1;
    }
    return 0;
}

static void list_runs(const study *s)
{
    double total = 0;
    for (size_t i = 0; i < s->run_count; i++)
        total += s->runs[i].work;
    printf("%s: %zu runs into %s/runs\n", s->path, s->run_count, s->out);
    for (size_t i = 0; i < s->run_count; i++) {
        const study_run *r = &s->runs[i];
        if (r->state == RUN_SKIPPED)
            printf("  %-40s skipped: %s\n", r->name, r->skipped);
        else if (r->reused)
            printf("  %-40s finished before (exit %d)\n", r->name, r->exit_code);
        else if (r->external)
            printf("  %-40s an external program\n", r->name);
        else
            printf("  %-40s %9.0f particles, %g s, %5.1f %% of the work\n", r->name, r->particles,
                   r->end_time, total > 0 ? 100 * r->work / total : 0);
        printf("    %s\n", r->command);
    }
}

/* The output directory of one study: --out (DIR/<stem> with several study
 * files), else runs/<stem>[-<profile>]. */
static char *output_directory(const command_line *c, const char *file)
{
    char *copy = study_strdup(file);
    char *stem = basename(copy);
    char *dot = strrchr(stem, '.');
    if (dot && dot != stem)
        *dot = '\0';
    char *out = c->out && c->file_count == 1 ? study_strdup(c->out)
                : c->out                     ? study_printf("%s/%s", c->out, stem)
                         : study_printf("runs/%s%s%s", stem, c->profile ? "-" : "",
                                        c->profile ? c->profile : "");
    free(copy);
    return out;
}

/* Loads, expands and checks one study; 0 or 2 (messages in its diag). */
static int prepare(study *s, const command_line *c, const char *file)
{
    s->profile = c->profile;
    s->dry_run = c->dry_run;
    s->summary_only = c->summary_only;
    s->retry_failed = c->retry_failed;
    s->quiet = c->quiet;
    if (study_load(s, file) != 0)
        return 2;
    if (c->jobs)
        s->jobs = c->jobs;
    s->out = output_directory(c, file);
    if (study_expand(s) != 0 || study_check_runs(s) != 0)
        return 2;
    return 0;
}

/* Runs a prepared study and writes its reports: 0, 4 or 5. */
static int perform(study *s)
{
    int status = 0;
    if (!s->summary_only) {
        int rc = study_execute(s);
        if (rc < 0)
            return 4;
        if (rc > 0)
            status = 5;
    } else
        for (size_t i = 0; i < s->run_count; i++)
            if (!s->runs[i].reused && study_read_run_json(s, &s->runs[i]) == 0)
                s->runs[i].state = RUN_DONE;
    if (study_measure_runs(s) != 0 || study_write_reports(s) != 0) {
        fprintf(stderr, "sluice-study: error: cannot write the reports into %s\n", s->out);
        return 4;
    }
    if (!s->quiet)
        fprintf(stderr, "sluice-study: wrote %s/study.csv, %s/study.md, %s/orders.csv\n", s->out,
                s->out, s->out);
    return status;
}

/* With several study files and --out DIR: DIR/studies.md, every study's
 * study.md in one page (headings one level down, plots by their paths). */
static int write_index(const command_line *c, study *studies)
{
    char *path = study_printf("%s/studies.md", c->out);
    char *temporary = study_printf("%s.tmp", path);
    FILE *out = fopen(temporary, "w");
    int rc = out ? 0 : -1;
    if (out)
        fprintf(out, "# Studies\n\n");
    for (size_t i = 0; out && i < c->file_count; i++) {
        char *md = study_printf("%s/study.md", studies[i].out);
        const char *stem = studies[i].out + strlen(c->out) + 1;
        FILE *in = fopen(md, "r");
        free(md);
        if (!in) {
            rc = -1;
            continue;
        }
        char *line = NULL;
        size_t size = 0;
        while (getline(&line, &size, in) > 0) {
            if (line[0] == '#')
                fputc('#', out);
            char *plot = strstr(line, "](plots/");
            if (plot) {
                fprintf(out, "%.*s](%s/plots/%s", (int)(plot - line), line, stem, plot + 8);
            } else
                fputs(line, out);
        }
        fputc('\n', out);
        free(line);
        fclose(in);
    }
    if (out && (fclose(out) != 0 || rename(temporary, path) != 0))
        rc = -1;
    if (rc == 0 && !c->quiet)
        fprintf(stderr, "sluice-study: wrote %s\n", path);
    free(temporary);
    free(path);
    return rc;
}

int main(int argc, char **argv)
{
    command_line c;
    memset(&c, 0, sizeof c);
    if (parse(argc, argv, &c) != 0) {
        free(c.files);
        return 2;
    }
    static const char *const sluice_places[] = {"../sluice", "sluice"};
    static const char *const analyze_places[] = {"sluice-analyze", "../tools/sluice-analyze"};
    char *sluice = program_beside("SLUICE", sluice_places, 2);
    char *analyze = program_beside("SLUICE_ANALYZE", analyze_places, 2);
    study *studies = calloc(c.file_count, sizeof *studies);
    if (!sluice || !studies) {
        fprintf(stderr, "sluice-study: error: cannot find the sluice program (set SLUICE)\n");
        return 4;
    }
    /* every study is checked before any runs */
    int status = 0;
    for (size_t i = 0; i < c.file_count; i++) {
        study *s = &studies[i];
        s->diag = sluice_diag_create();
        s->sluice = sluice;
        s->analyze = analyze ? analyze : "sluice-analyze";
        if (!s->diag || prepare(s, &c, c.files[i]) != 0)
            status = 2;
        if (s->diag)
            sluice_diag_print(s->diag, stderr);
    }
    for (size_t i = 0; status == 0 && i < c.file_count; i++) {
        if (c.dry_run)
            list_runs(&studies[i]);
        else
            status = perform(&studies[i]);
    }
    if (status == 0 && !c.dry_run && c.out && c.file_count > 1 && write_index(&c, studies) != 0) {
        fprintf(stderr, "sluice-study: error: cannot write %s/studies.md\n", c.out);
        status = 4;
    }
    for (size_t i = 0; i < c.file_count; i++) {
        sluice_diag_destroy(studies[i].diag);
        study_free(&studies[i]);
    }
    free(studies);
    free(c.files);
    free(sluice);
    free(analyze);
    return status;
}
