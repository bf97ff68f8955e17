/* A simulation: the scene, its loaded components, the particle store, the
 * neighbour search and the time loop. The `sluice` program is a thin command
 * line over this; tests and benchmarks drive it directly. */
#ifndef SLUICE_SIM_H
#define SLUICE_SIM_H

#include <stdint.h>
#include <stdio.h>

#include "diag.h"
#include "sluice/plugin.h"

typedef struct sluice_sim sluice_sim;

typedef struct sluice_load_options {
    const char *const *overrides; /* "dotted.key=value" (--set) */
    size_t override_count;
    int threads;                  /* 0: OpenMP default */
    int check_only;               /* validate and build the initial state, no output */
    double max_particles;         /* > 0: refuse a scene that would create more (the
                                     fuzzer's bound); 0: only the machine's memory */
    const void *communicator;     /* a distributed run: the MPI_Comm (address of) whose
                                     ranks share the scene (docs/scaling.md); needs a
                                     build with -Dmpi=enabled. NULL: one rank */
    const char *const *removals;  /* dotted paths (--remove), applied before the swaps */
    size_t removal_count;
    const char *const *swaps;     /* "OLD=NEW" (--swap), applied before the overrides */
    size_t swap_count;
    int quiet;                    /* no informational messages from the plugins while
                                     loading (warnings and errors still go to diag) */
    int timestamps;               /* the plugins' informational messages begin with a UTC
                                     timestamp (a batch log: SLUICE_PROGRESS_LOG) */
} sluice_load_options;

/* How a run reports its progress on stderr. */
typedef enum sluice_progress {
    SLUICE_PROGRESS_NONE = 0,
    SLUICE_PROGRESS_LINE = 1, /* one line rewritten in place (a terminal) */
    SLUICE_PROGRESS_LOG = 2   /* a plain line with a UTC timestamp every log_every s of
                                 wall time, and at the start and the end (a batch log) */
} sluice_progress;

typedef struct sluice_run_options {
    const char *output_directory;
    int progress;     /* a sluice_progress */
    int quiet;        /* no informational messages */
    double log_every; /* s of wall time between SLUICE_PROGRESS_LOG lines (<= 0: 10 s) */
} sluice_run_options;

typedef enum sluice_run_status {
    SLUICE_RUN_COMPLETE = 0,
    SLUICE_RUN_INPUT_ERROR = 2,   /* bad scene or plugin: nothing was run */
    SLUICE_RUN_UNSTABLE = 3,      /* the watchdog stopped the run */
    SLUICE_RUN_FAILED = 4,        /* I/O error, out of memory, a plugin failed */
    SLUICE_RUN_INTERRUPTED = 5    /* stopped by SIGINT/SIGTERM after a whole step; a
                                     checkpoint of that step was written */
} sluice_run_status;

/* Loads and validates a scene, loads its plugins and builds the initial
 * state. On failure returns NULL with the messages in diag. */
sluice_sim *sluice_sim_load(const char *scene_path, const sluice_load_options *options,
                            sluice_diag *diag);
/* The same with the scene's variant `variant` (NULL: the base scene),
 * applied before the overrides (docs/scene-format.md, Variants). */
sluice_sim *sluice_sim_load_variant(const char *scene_path, const char *variant,
                                    const sluice_load_options *options, sluice_diag *diag);
void sluice_sim_free(sluice_sim *sim);

/* Runs to the end time. Returns a sluice_run_status. */
int sluice_sim_run(sluice_sim *sim, const sluice_run_options *options);

/* Creates an output directory and its parents and checks it is a writable
 * directory: 0, or -1 with one message in error. */
int sluice_sim_make_directory(const char *path, char *error, size_t size);

/* Step-wise use (tests, benchmarks). begin() prepares outputs (may be NULL
 * directory for none), step() advances one step, end() finishes. */
int sluice_sim_begin(sluice_sim *sim, const char *output_directory);
int sluice_sim_step(sluice_sim *sim);
int sluice_sim_end(sluice_sim *sim, int status);
/* Evaluates every rate at the current state without taking a step (the
 * neighbour search brought up to date first): tests that set fields by hand
 * and read what the terms compute from them. */
int sluice_sim_evaluate(sluice_sim *sim);

/* Probing a saved state (tools/probe, `sluice probe`), on one rank:
 * replace_particles puts `count` particles, every field zero, in place of
 * the scene's (fill them through the view's columns; the neighbour search
 * is rebuilt at the next pass); point_pass runs the point pass of
 * api->evaluation->point_pass at `points` (3 reals each) over the particles
 * of `kinds` (SLUICE_KIND_MASK bits), with the scene's kernel. Both return
 * SLUICE_OK, or SLUICE_ERROR with the reason in sluice_sim_failure. */
int sluice_sim_replace_particles(sluice_sim *sim, sluice_index count);
int sluice_sim_point_pass(sluice_sim *sim, const sluice_real *points, sluice_index count,
                          uint32_t kinds, sluice_point_fn fn, void *context);

/* Checkpoints and restart: core/checkpoint/checkpoint.h (included at the
 * end: the embedding API is this header). */

/* SIGINT and SIGTERM set a flag (the only global mutable state of Sluice):
 * sluice_sim_run then stops after the current step, writes a checkpoint and
 * returns SLUICE_RUN_INTERRUPTED. Installed by the sluice program. */
int sluice_install_stop_handlers(void);
int sluice_stop_requested(void);

/* The program's command line, recorded in run.json and the snapshots
 * (api->output->describe_run "command_line"). Copied; 0 or -1 out of memory. */
int sluice_sim_set_command_line(sluice_sim *sim, const char *command_line);
/* What the core knows about the run, by name (api->output->describe_run):
 * version, git_revision, build, command_line, date, host, kernel; NULL for
 * a name it does not know. */
const char *sluice_sim_describe(sluice_sim *sim, const char *name);
/* Writes the current UTC time as "YYYY-MM-DDTHH:MM:SSZ" (at least 21 bytes). */
void sluice_utc_timestamp(char *buffer, size_t size);

/* Introspection. */
const sluice_view *sluice_sim_view(sluice_sim *sim);
int sluice_sim_field(sluice_sim *sim, const char *name, sluice_field *out);
double sluice_sim_time(const sluice_sim *sim);
double sluice_sim_end_time(const sluice_sim *sim);
int64_t sluice_sim_steps(const sluice_sim *sim);
uint32_t sluice_sim_dimensions(const sluice_sim *sim);
const char *sluice_sim_resolved_scene(const sluice_sim *sim);
/* The variant applied (NULL: the base scene); the variants the scene defines:
 * the name of the index-th (NULL past the last) and its description ("" when
 * none). */
const char *sluice_sim_variant(const sluice_sim *sim);
const char *sluice_sim_scene_variant(const sluice_sim *sim, size_t index,
                                     const char **description);
/* The loaded plugins in scene order: instance `index`'s name (its key in
 * `plugins`) and, in *component, the component it loads; NULL past the end. */
const char *sluice_sim_instance(const sluice_sim *sim, uint32_t index, const char **component);
/* Fields in declaration order: name and first column (for layout checks). */
uint32_t sluice_sim_field_count(const sluice_sim *sim);
const char *sluice_sim_field_name(const sluice_sim *sim, uint32_t index);
/* Memory and work figures. */
size_t sluice_sim_bytes(const sluice_sim *sim);
uint64_t sluice_sim_pair_count(const sluice_sim *sim);
uint64_t sluice_sim_neighbour_rebuilds(const sluice_sim *sim);
uint64_t sluice_sim_particle_steps(const sluice_sim *sim);
int sluice_sim_threads(const sluice_sim *sim);
/* Rank and rank count of a distributed run (0 and 1 otherwise). */
int sluice_sim_rank(const sluice_sim *sim);
int sluice_sim_rank_count(const sluice_sim *sim);
/* The particles of every rank (collective across ranks). */
uint64_t sluice_sim_particle_total(const sluice_sim *sim);
/* The messages of the last failure (watchdog, plugin error), or "". */
const char *sluice_sim_failure(const sluice_sim *sim);

/* The evaluation schedule (prepare, passes in order, on-demand terms,
 * integrated fields), as text or (json != 0) as a JSON object; run.json
 * holds the latter as "schedule". */
void sluice_sim_write_schedule(const sluice_sim *sim, FILE *out, int json);

/* Lists every plugin on the search path (sluice inspect). */
int sluice_inspect(FILE *out, const char *component, int markdown);

#include "checkpoint.h"

#endif
