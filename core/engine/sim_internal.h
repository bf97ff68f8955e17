/* Internal layout of a simulation, shared by sim.c (loading, API table),
 * run.c (time loop, watchdog, outputs) and inspect.c. Not installed. */
#ifndef SLUICE_SIM_INTERNAL_H
#define SLUICE_SIM_INTERNAL_H

#include <omp.h>
#include <stdatomic.h>

#include "comm.h"
#include "diag.h"
#include "neighbours.h"
#include "pairs.h"
#include "particles.h"
#include "ranks.h"
#include "registry.h"
#include "scene.h"
#include "sim.h"
#include "wall_distance.h"
#include "wall_watch.h"

#define SLUICE_CORE_INSTANCE UINT32_MAX

typedef struct sluice_declarer {
    uint32_t instance; /* SLUICE_CORE_INSTANCE for the core */
    uint32_t access;
} sluice_declarer;

typedef struct sluice_field_entry {
    char *name, *units, *doc, *rate_of;
    sluice_type type;
    uint32_t components;
    uint32_t flags;
    uint32_t kinds; /* integrated kinds (rate fields) */
    int32_t column;
    sluice_declarer *declarers;
    uint32_t declarer_count;
} sluice_field_entry;

typedef struct sluice_constant_entry {
    char *name, *unit;
    sluice_real values[3];
    uint32_t count;
    uint32_t publisher;
} sluice_constant_entry;

struct sluice_host {
    sluice_sim *sim;
    uint32_t instance;
};

typedef struct sluice_instance {
    const sluice_component *component;
    const sluice_library *library;
    const char *path;
    const char *name;
    sluice_node *key; /* position in the scene */
    void *config;
    void *state;
    int created;
    sluice_host host;
    sluice_pair_pass *on_demand; /* SLUICE_COMPONENT_ON_DEMAND: its own pass */
    sluice_real reach;           /* pair radius beyond the support (m), 0: the support */
    char reach_field[64];        /* the reach pass's particles: this uint8 field... */
    uint32_t reach_value;        /* ...holds this value ("" : every particle) */
    int local_points;            /* requested a point margin (reads its fields at
                                    other particles in api->evaluation->point_pass_local) */
} sluice_instance;

typedef struct sluice_pass {
    int is_pair;
    uint32_t instance; /* particle pass */
    sluice_pair_pass pair;
} sluice_pass;

/* One column of a table: its name (from the header) and what the component
 * said of it (api->output->table_column; unit NULL: not described). */
typedef struct sluice_table_column_info {
    char *name;
    char *unit;
    char *description;
    int has_position;
    double position[3]; /* m */
} sluice_table_column_info;

struct sluice_table {
    sluice_sim *sim;
    uint32_t instance; /* the component instance that writes it */
    char *name;        /* the file's name in the output directory */
    char *path;
    char *header;
    uint32_t column_count; /* the header's columns */
    sluice_table_column_info *columns;
    int fd;
    int failed;
    uint64_t bytes;         /* written so far, header included (checkpoints record it) */
    uint64_t hash;          /* FNV-1a of those bytes (checkpoints record it) */
    int resume;             /* restarted: continue the file at resume_bytes when it is there */
    int resume_hashed;      /* the checkpoint recorded resume_hash (older ones did not) */
    uint64_t resume_bytes, resume_hash;
};

/* FNV-1a, 64 bits: the fingerprint of a table's bytes. Start from
 * SLUICE_TABLE_HASH_START. */
#define SLUICE_TABLE_HASH_START 14695981039346656037ull
static inline uint64_t sluice_table_hash_bytes(uint64_t hash, const char *data, size_t size)
{
    for (size_t i = 0; i < size; i++) {
        hash ^= (unsigned char)data[i];
        hash *= 1099511628211ull;
    }
    return hash;
}

/* Where api->state->state_write / state_read / state_length go: the checkpoint
 * library (core/checkpoint/) sets it around a component's save_state or
 * load_state call; NULL otherwise. The engine itself writes no files. */
typedef struct sluice_state_store {
    int (*write)(sluice_host *host, const char *name, sluice_state_type type, uint64_t count,
                 const void *data);
    int (*read)(sluice_host *host, const char *name, sluice_state_type type, uint64_t count,
                void *data);
    int64_t (*length)(sluice_host *host, const char *name);
} sluice_state_store;

/* What the libraries above the engine lend it (core/sim/ fills them). */
/* The memory a scene needs (memory.c; docs/reliability.md, "Memory"). */
typedef struct sluice_memory_estimate {
    double particles;    /* counted before the set-up */
    double store;        /* bytes per particle: the declared fields' columns */
    double scratch;      /* one scratch column per element size (reordering) */
    double grid;         /* the cell grid's arrays */
    double neighbours;   /* neighbour-list entries per particle */
    double list;         /* their bytes */
    double per_particle; /* the sum of the five */
    double resident;     /* bytes the process holds at the estimate */
    double fixed;        /* resident, the cell starts and the pair buffers */
    double total;        /* fixed + particles * per_particle: the peak resident set */
    double available;    /* bytes the process may still take; < 0 unknown */
    const char *available_from;
} sluice_memory_estimate;

typedef struct sluice_sim_services {
    /* Writes a checkpoint of the state after the last whole step (path NULL:
     * DIR/checkpoint_<step>.h5); NULL: this program has no checkpoints. */
    int (*checkpoint)(sluice_sim *sim, const char *path);
} sluice_sim_services;

typedef enum sluice_phase {
    SLUICE_PHASE_CREATE = 0,
    SLUICE_PHASE_BIND = 1,
    SLUICE_PHASE_INITIALISE = 2,
    SLUICE_PHASE_RUN = 3
} sluice_phase;

struct sluice_sim {
    sluice_scene scene;
    sluice_registry registry;
    sluice_diag *diag; /* during loading only */
    int64_t creating;  /* instance inside create(), or -1: its errors are held in
                          pending and reported as one message naming the plugin */
    char pending[2048];
    omp_lock_t message_lock; /* api->messages->error may be called from parallel terms */
    sluice_phase phase;
    int check_only;

    sluice_instance *instances;
    uint32_t instance_count;
    int32_t kernel, integrator;

    sluice_field_entry *fields;
    uint32_t field_count, column_count;
    sluice_constant_entry *constants;
    uint32_t constant_count;
    sluice_rate *rates;
    uint32_t rate_count;
    sluice_wall *walls;
    sluice_real *wall_bounds; /* 6 per wall: min xyz, max xyz (wall_nearest) */
    /* 3 per wall: the displacement its scheme last set for a moving wall
     * (api->walls->set_wall_displacement); wall_moves[w] once it set one */
    sluice_real *wall_displacement;
    uint8_t *wall_moves;
    /* api->walls->wall_distance's cells, built at its first call (a scene whose
     * plugins never ask pays nothing); wall_distance_built is set once
     * they are (or once their build failed: the queries then ask every
     * element, the same numbers) */
    sluice_wall_distance_index wall_distance;
    atomic_int wall_distance_built;
    const sluice_wall_geometry **wall_geometries; /* wall_count: for the watch */
    sluice_wall_watch wall_watch; /* the watchdog's wall check, built by begin */

    sluice_particles particles;
    sluice_view view;
    sluice_field position, kind, id, mass, velocity, density; /* column -1 when absent */
    sluice_id next_id;
    sluice_real rest_density, spacing, smoothing_length, support;

    sluice_grid grid;
    sluice_pair_engine engine;
    sluice_comm comm;         /* the ranks of a distributed run (one by default) */
    sluice_halo_lists halo;   /* this rank's slab and halo (ranks.h) */
    sluice_ranks_run ranks_run; /* the decomposition's view of the run (decomposition.c) */
    sluice_real point_margin; /* the largest api->evaluation->request_point_margin, m */
    sluice_pass *passes;
    uint32_t pass_count;
    uint32_t *prepare; /* instances with a prepare callback, scene order */
    uint32_t prepare_count;
    uint32_t *accumulate_columns;
    uint32_t accumulate_count;

    /* time */
    double time, dt, dt_limit, end;
    /* the evaluation under way (api->evaluation->evaluate): the time its
     * state stands at and its index within the step (view.stage_time, stage) */
    int in_stage;
    double stage_time;
    uint32_t stage;
    int64_t step;
    double *requests;
    size_t request_count, request_capacity;

    /* run */
    char *output_directory;
    int threads;
    /* light loops over particles run on one thread below this many
     * (SLUICE_PARALLEL_MIN_ITEMS with a passive wait policy, else 0) */
    sluice_index parallel_min;
    double wall_start, wall_seconds;
    uint64_t particle_steps;
    /* the step and particle-steps when this invocation's run began (a
     * restart carries the run's counters on; wall_seconds is this
     * invocation's, and so is the rate in run.json) */
    int64_t step_at_start;
    uint64_t particle_steps_at_start;
    double time_at_start;
    /* largest |density / rest density - 1| over fluid particles seen by the
     * watchdog during the run (run.json max_density_deviation) */
    double max_density_deviation;
    sluice_index particles_initial;
    /* the memory estimate made before the set-up (run.json) */
    sluice_memory_estimate memory;
    /* the memory left when the neighbour list's limit was last set
     * (evaluate.c), and where the figure came from */
    double list_room;
    const char *list_room_from;
    char *resolved_scene;
    char failure[4096];
    sluice_table **tables;
    size_t table_count;
    int progress, quiet, timestamps;
    /* provenance (run.json, api->output->describe_run): the program's command line
     * (sluice_sim_set_command_line), the start date (UTC, ISO 8601) and host */
    char *command_line;
    char start_date[40];
    char host_name[256];
    double last_progress, log_every;
    int evaluating;   /* inside an evaluation or a pass: particles may not come or go */
    uint64_t removed; /* particles removed since the start (api->particles->remove_particles) */

    /* checkpoints (core/checkpoint/) */
    sluice_sim_services services;
    const sluice_state_store *state_store; /* set around save_state / load_state */
    int64_t checkpoint_next;      /* the next scheduled one is at checkpoint_next * interval */
    int64_t checkpoint_step;      /* step of the last checkpoint written, or -1 */
    char **checkpoint_files;      /* written by this run, oldest first (checkpoint.keep) */
    size_t checkpoint_file_count;
    int restarted;                /* state restored from a checkpoint (begin() does not call
                                     the after_step hooks again) */
    int64_t state_group;          /* HDF5 group of api->state->state_write/read, or -1 */
    uint32_t state_instance;      /* the component whose save_state/load_state runs */
    int state_writing;
    int state_absent;             /* load_state of a plugin the checkpoint holds no state of */
    const char *state_file;       /* the checkpoint read or written (messages) */
    const void *state_context;    /* the checkpoint being written (checkpoint.c), or NULL */
};

/* The kinds a term that asked for `kinds` as neighbours receives: fluid
 * includes the open-boundary buffers (plugin.h, SLUICE_KIND_OPEN). */
static inline uint32_t sluice_neighbour_kinds(uint32_t kinds)
{
    return (kinds & SLUICE_KIND_MASK(SLUICE_KIND_FLUID)) ? kinds | SLUICE_KIND_MASK(SLUICE_KIND_OPEN)
                                                         : kinds;
}

/* The kinds component c declares as neighbours of a target of kind k
 * (neighbour_kinds_by_target where set, ABI 2.3), before the open buffers are
 * added; 0 when c does not act on kind k. */
static inline uint32_t sluice_declared_neighbour_kinds(const sluice_component *c, uint32_t k)
{
    if (!(c->target_kinds & SLUICE_KIND_MASK(k)))
        return 0;
    return c->neighbour_kinds_by_target[k] ? c->neighbour_kinds_by_target[k] : c->neighbour_kinds;
}

static inline const char *sluice_kind_name(uint8_t kind)
{
    return kind == SLUICE_KIND_FLUID ? "fluid"
           : kind == SLUICE_KIND_WALL ? "wall"
           : kind == SLUICE_KIND_OPEN ? "open-boundary"
                                      : "unknown";
}

/* host.c */
void sluice_sim_refresh_view(sluice_sim *sim);
void sluice_sim_fail(sluice_sim *sim, const char *format, ...) SLUICE_PRINTF(2, 3);
/* The plugins behind a field for one particle's kind, as a phrase ("written by 'mdbc'", "from its rate
 * 'density_rate' accumulated by 'continuity', 'delta_sph'"): the writers
 * that target that kind and, for an integrated field, the plugins that
 * accumulate its rate for it. */
const char *sluice_field_writers_for(const sluice_sim *sim, const sluice_field_entry *field,
                                     uint8_t kind, char *buffer, size_t size);
double sluice_wall_clock(void);
/* The registered field of that name, or NULL. */
sluice_field_entry *sluice_sim_find_field(const sluice_sim *sim, const char *name);
void sluice_sim_request_time(sluice_sim *sim, double t);
int sluice_write_file_atomic(const char *path, const void *data, size_t size, char *error,
                             size_t error_size);
/* Writes `path` through write_file(context, temporary, ...) in a child
 * process (fork), then renames the temporary file over `path`. The child
 * reads this process's memory as it is (copy-on-write), so the writer
 * streams from the live arrays without a copy of the file in memory, and a
 * library that fails badly after a failed write (HDF5 1.10 crashes at exit
 * after a failed H5Fclose) takes only the child down. The child runs OpenMP
 * on one thread. When no process can be started the writer runs here. 0, or
 * -1 with `error` naming `path`; no temporary file is left either way. */
int sluice_write_file_with(const char *path, sluice_file_writer write_file, void *context,
                           char *error, size_t error_size);

/* memory.c: the memory a scene needs (docs/reliability.md, "Memory") */
/* The particles the scene's fluid regions (the lattice points of their
 * bounding boxes) and walls (wall_layers layers along every wall) create. */
void sluice_sim_count_particles(const sluice_sim *sim, double wall_layers, double *fluid,
                                double *wall);
/* After the components are created (fields declared, support known). */
void sluice_sim_estimate_memory(const sluice_sim *sim, double particles,
                                sluice_memory_estimate *out);
/* This process's resident set now, in bytes (0 when unknown). */
double sluice_memory_resident(void);
/* The bytes this process may still take: the least of MemAvailable, the
 * control group's memory.max less its use, and the address-space limit
 * less the address space in use; -1 when none is known. *source names it. */
double sluice_memory_available(const char **source);

/* The engine's files, lowest first: host.c, memory.c, fields.c, evaluate.c, api.c,
 * schedule.c, fill.c, load.c; files.c, watchdog.c, run.c (the time loop);
 * accessors.c. Each calls only files before it (tools/core-graph.sh). */
/* api.c */
int sluice_sim_add_particles(sluice_sim *sim, uint8_t kind, const sluice_real *positions, const sluice_real *velocity, const sluice_real *density, sluice_index count, sluice_index *first);
const sluice_instance *sluice_sim_equation_of_state(const sluice_sim *sim);

/* host.c */
char *sluice_sim_copy_string(const char *s);
const char *sluice_sim_instance_name(const sluice_sim *sim, uint32_t instance);

/* fields.c */
int sluice_sim_publish(sluice_sim *sim, uint32_t instance, const char *name, const sluice_real *values, uint32_t count, const char *unit);
int sluice_sim_declare(sluice_sim *sim, uint32_t instance, const sluice_field_spec *spec);
uint32_t sluice_sim_get_constant(const sluice_sim *sim, const char *name, sluice_real *values, uint32_t max_count);
int sluice_sim_handle_of(const sluice_sim *sim, const char *name, sluice_field *out);
void sluice_sim_report(sluice_sim *sim, uint32_t instance, const char *format, ...) SLUICE_PRINTF(3, 4);
uint8_t sluice_sim_type_size(sluice_type t);

/* evaluate.c */
int sluice_sim_run_point_pass(sluice_sim *sim, const sluice_host *host, const sluice_real *points, sluice_index count, uint32_t kinds, int with_halo, sluice_point_fn fn, void *context);
int sluice_sim_refresh_halo(sluice_sim *sim);
double sluice_sim_next_request(const sluice_sim *sim);
int sluice_sim_update_neighbours(sluice_sim *sim);

/* schedule.c */
int sluice_sim_build_schedule(sluice_sim *sim);
uint32_t *sluice_sim_initialise_order(const sluice_sim *sim);
void sluice_sim_free_pair_pass(sluice_pair_pass *p);
int sluice_sim_evaluation_pair(const sluice_component *c);
int sluice_sim_build_rates(sluice_sim *sim);
/* Tells the grid (once initialised) which kinds each kind's neighbour list
 * holds: the union of the neighbour kinds of the passes within the kernel
 * support (the scheduled ones and the on-demand ones). */
void sluice_sim_set_list_kinds(sluice_sim *sim);

/* fill.c */
int sluice_sim_fill_fluid(sluice_sim *sim);

/* api.c */
extern const sluice_api sluice_sim_api_table;

/* files.c */
/* Appends one row to a table's file (api->output->table_row). */
int sluice_sim_table_flush_row(sluice_table *table, const char *line, size_t length);
/* Splits a table's header into its columns (table->columns); -1 when out of
 * memory. */
int sluice_sim_table_split_header(sluice_table *table);
/* Frees a table and what it holds (its file descriptor is closed). */
void sluice_sim_table_free(sluice_table *table);
/* Writes the index of the run's tables, OUTPUT/tables.json, atomically (rank 0;
 * nothing without an output directory); prints the error and returns -1 when
 * it cannot. */
int sluice_sim_write_table_index(sluice_sim *sim);

/* watchdog.c */
int sluice_sim_watchdog(sluice_sim *sim);

/* load.c: the engine's loader; sluice_sim_load (core/sim/) calls it with
 * the services of the libraries above the engine. */
sluice_sim *sluice_engine_load(const char *scene_path, const char *variant,
                               const sluice_load_options *options,
                               const sluice_sim_services *services, sluice_diag *diag);

#endif
