/* sluice-study: comparative studies as one command (docs/studies.md).
 *
 * A study file names a base scene, the axes to vary (scene edits: plugins
 * swapped, keys removed or set; a parameter; the particle spacing; the thread
 * count) and the measures to take from each run (a gauge column reduced over
 * a time window, a figure of sluice-analyze, a figure of run.json). The study
 * runs the product as ordinary run directories, resumably and several at a
 * time, and writes one CSV, a Markdown table and PNG plots: each measure
 * against the run's CPU time and against the spacing with the observed order
 * of convergence.
 *
 *   study_file.c    reading and checking the study file
 *   study_run.c     the runs: checking, launching, resuming, progress
 *   study_report.c  the measures, the orders, the table and the plots
 */
#ifndef SLUICE_STUDY_H
#define SLUICE_STUDY_H

#include <stddef.h>
#include <sys/types.h>

#include "diag.h"
#include "yaml_tree.h"

/* One scene edit a run passes to `sluice run`, and the study-file node it
 * came from (messages about it are put there). */
typedef enum study_edit_kind { EDIT_REMOVE, EDIT_SWAP, EDIT_SET } study_edit_kind;
typedef struct study_edit {
    study_edit_kind kind;
    char *text; /* PATH, OLD=NEW or PATH=VALUE */
    const sluice_node *at;
} study_edit;

typedef struct study_edits {
    study_edit *items;
    size_t count;
    const char *variant; /* NULL: none */
    const sluice_node *variant_at;
    char *scene; /* an axis value's own scene (resolved), or NULL */
    const sluice_node *scene_at;
    /* an axis value run by another program (a peer code): its shell command
     * with {run_dir}, {spacing}, {threads}, {study_dir} in it, and the shell
     * command that tells whether that program is installed; or NULL */
    char *external, *requires;
    const sluice_node *external_at, *requires_at;
} study_edits;

typedef enum study_axis_kind {
    AXIS_EDITS,     /* values: label -> edits */
    AXIS_PARAMETER, /* one dotted path, a list of values */
    AXIS_SPACING,   /* particles.spacing: the axis of the observed orders */
    AXIS_THREADS    /* OpenMP threads per run */
} study_axis_kind;

typedef struct study_value {
    char *label; /* as written (a key, or the value's text) */
    study_edits edits;
    double number; /* spacing or threads; NAN otherwise */
    const sluice_node *at;
} study_value;

typedef struct study_axis {
    char *name;
    study_axis_kind kind;
    /* the axis of the observed orders: the spacing axis, or a parameter
     * axis of positive numbers marked `convergence: true` (a time step) */
    int convergence;
    study_value *values;
    size_t count;
    const sluice_node *at;
} study_axis;

typedef enum study_source { SOURCE_GAUGE, SOURCE_ANALYSIS, SOURCE_RUN } study_source;
typedef enum study_reduce {
    REDUCE_MEAN,
    REDUCE_MAX,
    REDUCE_MIN,
    REDUCE_FIRST,
    REDUCE_LAST,
    REDUCE_STD,
    REDUCE_RMS,
    REDUCE_INTEGRAL,
    REDUCE_TIME_OF_MAX,
    REDUCE_TIME_OF_MIN,
    REDUCE_COUNT
} study_reduce;
extern const char *const study_reduce_names[REDUCE_COUNT];

typedef struct study_measure {
    char *name, *unit;
    study_source source;
    char *file, *column; /* gauge: a CSV of the run directory and its column */
    study_reduce reduce;
    double from, to;  /* the time window (s); -inf, +inf: all */
    double last;      /* > 0: the window is the run's last `last` seconds */
    double last_share; /* > 0: the window is this share of the run, at its end */
    char **arguments; /* analysis: sluice-analyze COMMAND [ARGS]; the run
                         directory goes after COMMAND */
    size_t argument_count;
    char *key; /* analysis: the `key = value` line; run: run.json's key */
    double scale; /* the value is multiplied by it (default 1) */
    int has_reference;
    double reference;
    /* the reference taken from another measure of the same run:
     * reference_factor x its value (reference_measure: its name) */
    char *reference_measure;
    double reference_factor;
    size_t reference_index;
    const sluice_node *reference_measure_at;
    int absolute; /* error = value - reference (else relative) */
    /* the target a run meets (NAN: none): |error| <= within, value < below,
     * value > above */
    int has_target;
    double within, below, above;
    const sluice_node *at;
} study_measure;

typedef enum study_state {
    RUN_PENDING,
    RUN_RUNNING,
    RUN_DONE,
    RUN_FAILED,
    RUN_INTERRUPTED,
    RUN_SKIPPED /* an external program that is not installed here */
} study_state;

typedef struct study_run {
    char *name;
    size_t *choice;             /* the value of each axis */
    char **argv;                /* sluice run ..., or /bin/sh -c EXTERNAL (NULL-terminated) */
    const sluice_node **origin; /* per argv entry: the node behind it, or NULL */
    size_t argc;
    char *command;     /* argv as one line (the record of the run) */
    const char *scene; /* the run's scene: the study's or an axis value's */
    const study_edits *external; /* the axis value run by another program, or NULL */
    char *skipped;               /* why an external run is skipped, or NULL */
    int threads;
    double spacing;    /* NAN without a spacing axis */
    double resolution; /* the convergence axis's value (the spacing, or a
                          parameter's), NAN without one */
    /* from `sluice check` */
    double particles, end_time, work;
    int dimensions;
    /* the run */
    study_state state;
    int reused; /* finished before this invocation */
    char *restart;      /* the checkpoint an interrupted run continues from, or NULL */
    double cpu_before;  /* CPU seconds of its earlier parts */
    pid_t pid;
    double started;
    int exit_code;
    double cpu_seconds, wall_seconds;
    /* run.json */
    double steps, particle_steps;
    char failure[1024];
    /* the measures */
    double *values, *errors;
} study_run;

typedef struct study {
    sluice_node *root;
    sluice_diag *diag;
    char *path, *directory; /* the study file and its directory */
    char *title, *description;
    char *scene; /* resolved against the study file's directory */
    study_edits base;
    int threads, jobs;
    study_axis *axes;
    size_t axis_count;
    study_measure *measures;
    size_t measure_count;
    study_run *runs;
    size_t run_count;
    /* the command line */
    char *out;
    const char *profile; /* --profile NAME, or NULL */
    const char *sluice, *analyze;
    int dry_run, summary_only, retry_failed, quiet;
} study;

/* study_file.c */
int study_load(study *s, const char *path);
void study_free(study *s);
void study_error(study *s, const sluice_node *at, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
/* The runs of the study: every combination of the axes' values. 0 or -1. */
int study_expand(study *s);

/* study_run.c */
double study_clock(void);
int study_check_runs(study *s); /* sluice check of every run: 0 or errors */
int study_execute(study *s);    /* 0, or 1 when interrupted */
int study_read_run_json(study *s, study_run *r);
/* The top-level part of OUT/runs/NAME/run.json (its scalars, before
 * "plugins") into text: 0, or -1 without the file. */
int study_run_json_head(const study *s, const study_run *r, char *text, size_t size);

/* study_report.c */
int study_measure_runs(study *s);
int study_write_reports(study *s);

/* small helpers (study_file.c) */
char *study_strdup(const char *text);
char *study_printf(const char *format, ...) __attribute__((format(printf, 1, 2)));
int study_mkdirs(const char *path);

#endif
