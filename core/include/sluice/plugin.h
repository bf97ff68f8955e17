/*
 * Sluice plugin ABI.
 *
 * This is the only header a plugin needs. A plugin is a shared object that
 * exports one function, sluice_plugin_entry(), returning a static
 * sluice_library descriptor. The descriptor lists one or more components
 * (a kernel, an equation of state, a pair force, an integrator, a writer, ...).
 * Plugins never link against the core: every service of the core is reached
 * through the sluice_api table handed to each component's create().
 *
 * Compatibility rules (see docs/plugin-abi.md):
 *  - SLUICE_ABI_MAJOR changes when anything existing changes; the core refuses
 *    a plugin with another major version.
 *  - SLUICE_ABI_MINOR grows when members are appended at the end of
 *    sluice_api or sluice_component; the core refuses a plugin built for a
 *    newer minor than its own, and accepts older ones (members the plugin does
 *    not know about read as absent).
 *  - The build signature (size of sluice_real, of sluice_index, supported
 *    dimensions) must match the core exactly.
 *
 * Units are SI throughout: m, s, kg, Pa.
 */
#ifndef SLUICE_PLUGIN_H
#define SLUICE_PLUGIN_H

#include <stddef.h>
#include <stdint.h>

#include "sluice/config.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SLUICE_ABI_MAJOR 1
#define SLUICE_ABI_MINOR 9
#define SLUICE_PLUGIN_MAGIC 0x534c4349u /* "SLCI" */

#if defined(__GNUC__)
#define SLUICE_EXPORT __attribute__((visibility("default")))
#define SLUICE_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define SLUICE_EXPORT
#define SLUICE_PRINTF(f, a)
#endif

/* sluice_real is double unless the core was configured otherwise; it is part
 * of the build signature. */
typedef SLUICE_REAL_TYPE sluice_real;
/* Index of a particle in the current (sorted) particle order. */
typedef uint32_t sluice_index;
/* Global, permanent particle identity (survives sorting, restarts). */
typedef uint64_t sluice_id;

enum { SLUICE_OK = 0, SLUICE_ERROR = -1 };

/* ---------------------------------------------------------------- kinds -- */

/* Every particle has a kind, owned by the core. Masks are (1u << kind).
 *
 * SLUICE_KIND_OPEN (1.4) is fluid in an inlet or outlet buffer whose state
 * (position, velocity, density) an open-boundary plugin imposes: the
 * integrators do not move it and no term targets it unless it asks for the
 * kind, but it is fluid to its neighbours. A component whose neighbour_kinds
 * (or a point_pass whose kinds) include SLUICE_KIND_FLUID also receives
 * SLUICE_KIND_OPEN neighbours: test a neighbour with `kind != SLUICE_KIND_WALL`
 * (not `== SLUICE_KIND_FLUID`) where fluid is meant. */
enum sluice_kind {
    SLUICE_KIND_FLUID = 0, /* moves with the flow, integrated */
    SLUICE_KIND_WALL = 1,  /* wall particle (dynamic boundary), fixed or prescribed motion */
    SLUICE_KIND_OPEN = 2,  /* 1.4: fluid with an imposed state in an open-boundary buffer */
    SLUICE_KIND_COUNT = 3
};
#define SLUICE_KIND_MASK(k) (1u << (k))
#define SLUICE_KINDS_ALL ((1u << SLUICE_KIND_COUNT) - 1u)

/* Supported spatial dimensions, as a mask. */
#define SLUICE_DIMS_2 (1u << 2)
#define SLUICE_DIMS_3 (1u << 3)
#define SLUICE_DIMS_ALL (SLUICE_DIMS_2 | SLUICE_DIMS_3)

/* --------------------------------------------------------------- fields -- */

typedef enum sluice_type {
    SLUICE_TYPE_REAL = 1, /* sluice_real */
    SLUICE_TYPE_INT32 = 2,
    SLUICE_TYPE_UINT8 = 3,
    SLUICE_TYPE_ID = 4 /* sluice_id */
} sluice_type;

/* 1.5: element types of the plugin state arrays stored in checkpoints
 * (api->state_write / state_read). */
typedef enum sluice_state_type {
    SLUICE_STATE_DOUBLE = 1, /* double */
    SLUICE_STATE_INT64 = 2,  /* int64_t */
    SLUICE_STATE_UINT64 = 3  /* uint64_t (sluice_id) */
} sluice_state_type;

/* A field declaration's access, as seen by the component that declares it. */
enum sluice_access {
    SLUICE_READ = 1u << 0,           /* reads the value of particle i */
    SLUICE_READ_NEIGHBOUR = 1u << 1, /* pair term: reads values at neighbours j
                                        (gathered into the batch by the core) */
    SLUICE_WRITE = 1u << 2,          /* sets the field (one writer per field) */
    SLUICE_ACCUMULATE = 1u << 3      /* adds to the field; the core zeroes it before
                                        every evaluation; several may accumulate */
};

/* Field flags, merged over all declarations of a field. */
enum sluice_field_flags {
    SLUICE_FIELD_OUTPUT = 1u << 0, /* written by output writers */
    SLUICE_FIELD_RESTART = 1u << 1 /* part of the state a restart needs */
};

/* Use as `components` for a vector with one component per dimension. */
#define SLUICE_COMPONENTS_DIM 0

typedef struct sluice_field_spec {
    const char *name;    /* physics name: "density", "pressure", "acceleration" */
    sluice_type type;
    uint32_t components; /* 1 for scalars, SLUICE_COMPONENTS_DIM for vectors */
    const char *units;   /* SI, e.g. "kg m^-3" */
    uint32_t access;     /* sluice_access bits */
    uint32_t flags;      /* sluice_field_flags bits */
    const char *rate_of; /* if this field is the time derivative of another field
                            (integrated by the integrator), that field's name */
    uint32_t kinds;      /* with rate_of: the particle kinds that are integrated */
    const char *doc;
} sluice_field_spec;

/* A resolved field: filled by api->field(). `column` is the index of its first
 * component in sluice_view.columns; component c is column + c. */
typedef struct sluice_field {
    int32_t column;
    uint32_t components;
    sluice_type type;
} sluice_field;

/* ----------------------------------------------------------- parameters -- */

typedef enum sluice_param_type {
    SLUICE_PARAM_REAL = 1,       /* sluice_real */
    SLUICE_PARAM_INT = 2,        /* int64_t */
    SLUICE_PARAM_BOOL = 3,       /* int (0 or 1) */
    SLUICE_PARAM_STRING = 4,     /* const char * (owned by the core) */
    SLUICE_PARAM_ENUM = 5,       /* int: index into `choices` */
    SLUICE_PARAM_VECTOR = 6,     /* sluice_real[3]; `length` components are read */
    SLUICE_PARAM_REAL_LIST = 7,  /* sluice_real_list of scalars */
    SLUICE_PARAM_POINT_LIST = 8  /* sluice_real_list of points (3 reals each) */
} sluice_param_type;

enum sluice_param_flags {
    SLUICE_PARAM_HAS_MIN = 1u << 0,
    SLUICE_PARAM_HAS_MAX = 1u << 1,
    SLUICE_PARAM_MIN_EXCLUSIVE = 1u << 2,
    SLUICE_PARAM_MAX_EXCLUSIVE = 1u << 3,
    SLUICE_PARAM_OPTIONAL = 1u << 4 /* no default, may be absent (then zeroed) */
};

/* Use as `length` of a SLUICE_PARAM_VECTOR for one component per dimension. */
#define SLUICE_LENGTH_DIM 0

typedef struct sluice_real_list {
    const sluice_real *values; /* REAL_LIST: count values; POINT_LIST: 3 * count */
    uint32_t count;
} sluice_real_list;

typedef struct sluice_param_spec {
    const char *name;
    sluice_param_type type;
    size_t offset;             /* offsetof() in the component's config struct */
    const char *default_value; /* YAML text; NULL means required (unless OPTIONAL) */
    double min, max;           /* used with SLUICE_PARAM_HAS_MIN / HAS_MAX */
    uint32_t flags;
    const char *unit;          /* SI unit, "1" for dimensionless */
    const char *doc;
    const char *choices;       /* ENUM: "first|second|third" */
    uint32_t length;           /* VECTOR: component count, or SLUICE_LENGTH_DIM */
} sluice_param_spec;

/* ------------------------------------------------------------ the view -- */

/* The particle state as seen by callbacks. Valid until the core reorders
 * particles (inside api->evaluate) or changes their number; fetch it again with
 * api->view() after those. */
typedef struct sluice_view {
    sluice_index count;        /* particles */
    uint32_t dimensions;       /* 2 or 3 */
    void *const *columns;      /* base pointer of every field column */
    const sluice_real *position[3]; /* [2] is NULL in 2D */
    const uint8_t *kind;
    const sluice_id *id;
    sluice_real smoothing_length; /* h, m */
    sluice_real spacing;          /* initial particle spacing dx, m */
    double time;                  /* s, at the start of the current step */
    double dt;                    /* s, current step (0 before the first) */
    int64_t step;
} sluice_view;

static inline sluice_real *sluice_real_column(const sluice_view *v, sluice_field f, uint32_t c)
{
    return (sluice_real *)v->columns[f.column + (int32_t)c];
}

/* ----------------------------------------------------------- pair batch -- */

/* A batch of pairs (i, j) within the kernel support, built by the core for a
 * set of target particles i. Every pair term of a pass receives the same
 * batch; the core calls a term only with targets of the kinds it declared.
 * Pairs of target t are pair_begin[t] .. pair_begin[t + 1] - 1. i != j. */
typedef struct sluice_pair_batch {
    sluice_index target_count;
    const sluice_index *target;     /* particle index i of each target */
    const sluice_index *pair_begin; /* target_count + 1 offsets into the pair arrays */
    sluice_index pair_count;
    const sluice_index *neighbour;  /* particle index j of each pair */
    const uint8_t *neighbour_kind;  /* kind of j */
    uint32_t neighbour_kinds;       /* kinds that appear as j in this batch (a term may
                                       take a slower path only when a kind is present) */
    const sluice_real *offset[3];   /* r_ij = r_i - r_j (periodic image applied); [2] NULL in 2D */
    const sluice_real *distance;    /* |r_ij|, > 0 */
    const sluice_real *kernel;      /* W(r_ij), or NULL unless requested
                                       (SLUICE_COMPONENT_NEEDS_KERNEL) */
    const sluice_real *kernel_gradient; /* F_ij = (dW/dr) / r: grad_i W_ij = r_ij F_ij */
    const sluice_real *const *gathered; /* per column: value at j of every pair, for
                                           columns declared SLUICE_READ_NEIGHBOUR by
                                           a term of the pass; NULL otherwise */
    sluice_real kernel_self;        /* W(0) */
} sluice_pair_batch;

/* -------------------------------------------------------- host services -- */

typedef struct sluice_host sluice_host;

typedef struct sluice_rate {
    sluice_field state; /* the integrated field (e.g. density) */
    sluice_field rate;  /* its time derivative (e.g. density_rate) */
    uint32_t kinds;     /* particle kinds integrated */
    const char *state_name, *rate_name;
} sluice_rate;

typedef struct sluice_wall {
    const char *scheme; /* wall component that handles this wall */
    const char *name;   /* optional user name, or "" */
    uint32_t dimensions;
    /* 2D: segment_count segments, vertex pairs in `points` (x, y, 0 per point),
     * with the fluid on the left of each segment (counter-clockwise around the
     * fluid). 3D: triangles, three points each, fluid on the side of
     * (b - a) x (c - a). */
    uint32_t element_count;
    const sluice_real *points; /* 3 reals per point; 2 points (2D) or 3 (3D) per element */
    const sluice_real *normals; /* unit normal into the fluid, 3 reals per element */
} sluice_wall;

/* The point of a wall nearest to a query point (api->wall_nearest, 1.3). */
typedef struct sluice_wall_point {
    sluice_real distance;   /* signed, m: > 0 on the fluid side, < 0 behind the wall */
    sluice_real closest[3]; /* the nearest point of the wall */
    sluice_real normal[3];  /* unit normal into the fluid there (at a vertex or an edge the
                               pseudo-normal, the mean of the elements' normals) */
    uint32_t wall;          /* index of the wall (api->wall) */
    uint32_t element;       /* segment (2D) or triangle (3D) */
    int32_t feature;        /* 0: interior of the element; 1..3: a vertex; 4..6: an edge (3D) */
    int32_t beyond_end;     /* 1 when the point lies past an open end of the wall (the end
                               of a polyline), where "behind" has no meaning */
} sluice_wall_point;

/* Called by api->point_pass with batches of (point, particle) pairs. */
typedef void (*sluice_point_fn)(void *context, const sluice_view *view,
                                const sluice_pair_batch *batch);

/* One row of a time series. */
typedef struct sluice_table sluice_table;

typedef struct sluice_plugin_info {
    const char *component;
    const char *library;
    const char *version;
    const char *path;
} sluice_plugin_info;

typedef void (*sluice_range_fn)(void *context, const sluice_view *view, sluice_index begin,
                                sluice_index end);

/* 1.8: how values combine across the ranks of a distributed run (api->reduce). */
typedef enum sluice_reduce_op {
    SLUICE_REDUCE_SUM = 1,
    SLUICE_REDUCE_MIN = 2,
    SLUICE_REDUCE_MAX = 3
} sluice_reduce_op;

/* 1.8: this rank's place in a distributed run (api->ranks). On one rank:
 * rank 0 of 1, offset 0, total = view->count, communicator NULL. */
typedef struct sluice_ranks {
    int32_t rank, count;      /* this rank, and how many there are */
    uint64_t particle_offset; /* particles of the ranks before this one */
    uint64_t particle_total;  /* particles of every rank */
    const void *communicator; /* the run's MPI_Comm (const MPI_Comm *), NULL without MPI */
} sluice_ranks;

/* The table of core services. Grows only at its end; `size` tells how much of
 * it this core provides. Every function taking a host must be called from the
 * thread that called the component, except those marked "thread-safe". */
typedef struct sluice_api {
    uint32_t size;
    uint16_t abi_major, abi_minor;

    /* -- 1.0: diagnostics. Messages are prefixed with the component name. */
    void (*error)(sluice_host *host, const char *format, ...) SLUICE_PRINTF(2, 3); /* thread-safe */
    void (*warning)(sluice_host *host, const char *format, ...) SLUICE_PRINTF(2, 3);
    void (*info)(sluice_host *host, const char *format, ...) SLUICE_PRINTF(2, 3);

    /* -- 1.0: fields and constants.
     * declare_field: only in create() or bind(). field: from bind() on; a field
     * no component declared is an error. */
    int (*declare_field)(sluice_host *host, const sluice_field_spec *spec);
    int (*field)(sluice_host *host, const char *name, sluice_field *out);
    /* Named constants (smoothing_length, spacing, rest_density, dimensions,
     * gravity, speed_of_sound, ...). publish: in create(); get: from bind() on.
     * get returns the number of values, or 0 when nobody published it. */
    int (*publish_constant)(sluice_host *host, const char *name, const sluice_real *values,
                            uint32_t count, const char *unit);
    uint32_t (*constant)(sluice_host *host, const char *name, sluice_real *values,
                         uint32_t max_count);
    uint32_t (*rate_count)(sluice_host *host);
    int (*rate)(sluice_host *host, uint32_t index, sluice_rate *out);

    /* -- 1.0: particles and geometry. */
    const sluice_view *(*view)(sluice_host *host);
    /* Add `count` particles of `kind` at positions (3 reals each); mass,
     * density (rest density) and a new id are set by the core, other fields
     * are zero. In initialise(), and (1.4) between steps: in before_step or
     * after_step hooks, never inside an evaluation. *first receives the index
     * of the first one; indices of existing particles do not change. */
    int (*add_particles)(sluice_host *host, uint8_t kind, const sluice_real *positions,
                         sluice_index count, sluice_index *first);
    /* (Across ranks, 1.8: during the run only components flagged
     * SLUICE_COMPONENT_ACROSS_RANKS add or remove particles; new ids are
     * unique over the ranks, and a particle added outside the rank's box
     * moves to its owner at the next neighbour-list rebuild.) */
    uint32_t (*wall_count)(sluice_host *host);
    const sluice_wall *(*wall)(sluice_host *host, uint32_t index);
    /* Lattice points (spacing dx, aligned with the fluid lattice) behind a wall,
     * at a distance in (0, thickness] from it on the side away from the fluid.
     * The array (3 reals per point) is freed with api->release(). */
    int (*wall_layer_points)(sluice_host *host, uint32_t wall_index, sluice_real thickness,
                             sluice_real **points, sluice_index *count);
    void (*release)(void *memory);

    /* -- 1.0: running. */
    /* Integrators: evaluate every rate at the current state (updating the
     * neighbour search first when needed). */
    int (*evaluate)(sluice_host *host);
    /* Integrators: the step size after an evaluation: the minimum of every
     * component's limit, clamped to the end time and requested times. */
    double (*time_step)(sluice_host *host);
    /* Run fn over [0, count) in parallel chunks. */
    void (*parallel_for)(sluice_host *host, sluice_index count, sluice_range_fn fn, void *context);
    /* Ask the core to end a step exactly at time t (outputs, gauges). */
    void (*request_time)(sluice_host *host, double t);

    /* -- 1.0: output. */
    /* Path of `name` inside the run's output directory. */
    int (*output_path)(sluice_host *host, const char *name, char *buffer, size_t size);
    /* The fully resolved scene (every default filled in), YAML text. */
    const char *(*resolved_scene)(sluice_host *host);
    uint32_t (*plugin_count)(sluice_host *host);
    int (*plugin)(sluice_host *host, uint32_t index, sluice_plugin_info *out);
    /* Field table for writers. */
    uint32_t (*field_count)(sluice_host *host);
    int (*field_info)(sluice_host *host, uint32_t index, sluice_field_spec *spec,
                      sluice_field *field);
    /* Time series in the output directory: a CSV file with a header line;
     * rows are written whole. */
    sluice_table *(*table_open)(sluice_host *host, const char *file_name, const char *header);
    int (*table_row)(sluice_table *table, const double *values, uint32_t count);
    /* Write `size` bytes to `path` atomically (temporary file, then rename). */
    int (*write_file_atomic)(sluice_host *host, const char *path, const void *data, size_t size);

    /* -- 1.1: geometry queries and on-demand pair passes. */
    /* Distance from a point (3 reals) to the nearest wall of the scene, of any
     * scheme, in m; INFINITY when the scene has no walls. Thread-safe. */
    sluice_real (*wall_distance)(sluice_host *host, const sluice_real *point);
    /* For a component flagged SLUICE_COMPONENT_ON_DEMAND: run its pair
     * callback over every particle now, on the current state (from a hook,
     * e.g. after_step every N steps). Across ranks (1.9) the core first
     * refreshes the halo, so the neighbours other ranks own are current:
     * collective, every rank calls it at the same point of the run. */
    int (*pair_pass)(sluice_host *host);

    /* -- 1.2: equation of state. */
    /* density[k] for pressure[k], k < n, through the inverse of the scene's
     * equation of state (the component with a density_from_pressure callback,
     * the one the core uses for the hydrostatic start). Fails with a message
     * when the scene loads none; n = 0 only checks that one is loaded. */
    int (*density_from_pressure)(sluice_host *host, sluice_index n, const sluice_real *pressure,
                                 sluice_real *density);

    /* -- 1.3: wall geometry and interpolation at points. */
    /* The nearest point of wall `wall` (or of every wall when wall < 0) to
     * `point` (3 reals). SLUICE_ERROR when the scene has no such wall.
     * Thread-safe. */
    int (*wall_nearest)(sluice_host *host, const sluice_real *point, int32_t wall,
                        sluice_wall_point *out);
    /* Interpolation at arbitrary points: calls fn with batches in which
     * target[t] is the index of a point (3 reals each in `points`) and the
     * pairs are the particles of a kind in `kinds` within the kernel
     * support of it: offset = point - x_j, distance (may be 0), kernel (W)
     * and kernel_gradient (F) always set, gathered NULL (read the view's
     * columns at neighbour[k]). Runs in parallel over chunks of points, so fn
     * writes only to what belongs to its points. Call from prepare() or a
     * hook, never from a particle or pair callback. */
    int (*point_pass)(sluice_host *host, const sluice_real *points, sluice_index count,
                      uint32_t kinds, sluice_point_fn fn, void *context);

    /* -- 1.4: particles that come and go (open boundaries). Only between
     * steps (before_step / after_step hooks), never inside an evaluation.
     * remove_particles: removes the particles at the listed indices (any
     * order, no duplicates); the others keep their ids and order but move
     * to lower indices, so indices held before the call are stale after it.
     * Their ids are never reused. set_kind: changes the kind of the listed
     * particles (e.g. SLUICE_KIND_OPEN -> SLUICE_KIND_FLUID when an inflow
     * particle leaves the inlet buffer). Both fail on an index out of range. */
    int (*remove_particles)(sluice_host *host, const sluice_index *indices, sluice_index count);
    int (*set_kind)(sluice_host *host, const sluice_index *indices, sluice_index count,
                    uint8_t kind);
    /* Particles removed since the start of the run (all kinds; across
     * ranks, by this rank). */
    uint64_t (*removed_count)(sluice_host *host);

    /* -- 1.5: plugin state in checkpoints (docs/reliability.md, "Checkpoints
     * and restart"). Only inside the component's own save_state (write) or
     * load_state (read, length) callback. Arrays are named (a plain name, no
     * '/'), stored under the component's group of the checkpoint, with an
     * element type and count (0 is allowed). state_read fails with a
     * message (the restart adds the plugin and the checkpoint) when the
     * array is missing or its type or count differ; state_length returns the
     * element count, or -1 when the array is missing. A checkpoint with no
     * group for the component (an older plugin version without state) still
     * calls load_state, with every array missing. */
    int (*state_write)(sluice_host *host, const char *name, sluice_state_type type,
                       uint64_t count, const void *data);
    int (*state_read)(sluice_host *host, const char *name, sluice_state_type type,
                      uint64_t count, void *data);
    int64_t (*state_length)(sluice_host *host, const char *name);

    /* -- 1.6: pair terms that reach beyond the kernel support (a kernel of
     * their own with a longer smoothing length, e.g. the air's cohesion with
     * H = 2h). Called in the component's create(), once: the term then
     * receives every pair within `radius` m (> the scene kernel's support)
     * instead of the support, in passes of its own that the core traverses
     * through the cell grid (the Verlet list stays at the support, so no
     * other term pays for the reach). In its batches `kernel` and
     * `kernel_gradient` are NULL: the term evaluates its own kernel from
     * `distance`. Fails after create(), for a non-pair component, or for a
     * radius that is not finite and positive; a radius within the support
     * changes nothing. Across ranks (1.9) the halo is as wide as the largest
     * reach (plus the neighbour skin). */
    int (*request_reach)(sluice_host *host, sluice_real radius);

    /* -- 1.7: the pairs a reaching term needs. Called in create(), after
     * request_reach: the term contributes only where the target and the
     * neighbour both hold `value` in the uint8 field `field` (which the
     * component declares it reads), e.g. the air's cohesion, phase = 1. The
     * core then leaves every other particle out of the term's pass, as
     * target and as neighbour, and the term is spared their traversal. */
    int (*restrict_reach)(sluice_host *host, const char *field, uint32_t value);

    /* -- 1.8: runs across MPI ranks (docs/scaling.md). Each rank's components
     * see the rank's own particles (view->count) and, in pair batches, the
     * neighbours other ranks own. Both calls are collective: every rank calls
     * them at the same point of the run, in the same order. */
    /* Combines values[0 .. count) over the ranks, in place, on every rank:
     * a gauge sums its particles' contributions with it before it writes.
     * The identity on one rank. */
    int (*reduce)(sluice_host *host, double *values, uint32_t count, sluice_reduce_op op);
    /* This rank's place and the offset of its particles in the global order
     * (ranks in order, each rank's particles in view order): where a writer
     * puts them in a shared file. */
    int (*ranks)(sluice_host *host, sluice_ranks *out);
    /* 1 when this rank owns the particles at `point` (3 reals; its box
     * holds the point, 1.9: the box of docs/scaling.md's decomposition;
     * 1.8: its slab along x), 0 otherwise; always 1 on one rank. Not
     * collective: the rank that owns a place adds the particles there (an
     * inlet's new column), the others leave it. */
    int (*owns)(sluice_host *host, const sluice_real *point);

    /* -- 1.9: interpolation at points of this rank's own particles (a wall
     * particle's mirror point, docs/scaling.md). As point_pass, but the
     * pairs include, across ranks, the particles other ranks own near the
     * rank's box (the halo, refreshed first), so that every point gets what it
     * gets on one rank: the caller passes only points that belong to its
     * rank's own particles (view->count), and it may run without
     * SLUICE_COMPONENT_ACROSS_RANKS (nothing is summed over ranks). Each
     * point must lie within the margin the component requested
     * (request_point_margin; 0 by default) of the rank's box; a point
     * beyond it fails with a message. Collective across ranks: every rank
     * calls it at the same point of the run, with its own points (count
     * may be 0). On one rank it is point_pass. Call from prepare() or a
     * hook, never from a particle or pair callback. */
    int (*point_pass_local)(sluice_host *host, const sluice_real *points, sluice_index count,
                            uint32_t kinds, sluice_point_fn fn, void *context);
    /* In create(), bind() or initialise(): the points of this component's
     * point_pass_local lie up to `margin` m (finite, >= 0; along any axis)
     * from the particle they belong to; across ranks the halo is widened by
     * the largest margin requested. */
    int (*request_point_margin)(sluice_host *host, sluice_real margin);
} sluice_api;

/* ----------------------------------------------------------- components -- */

enum sluice_component_flags {
    SLUICE_COMPONENT_NEEDS_KERNEL = 1u << 0, /* pair term reads batch->kernel */
    SLUICE_COMPONENT_WALL_SCHEME = 1u << 1,  /* handles the scene's walls (api->wall) */
    SLUICE_COMPONENT_ON_DEMAND = 1u << 2,    /* 1.1: its pair callback is not part of every
                                                evaluation; it runs when the component calls
                                                api->pair_pass() */
    SLUICE_COMPONENT_ACROSS_RANKS = 1u << 3  /* 1.8: written for runs across ranks: it
                                                combines what it sums or finds over its
                                                rank's particles with api->reduce before it
                                                writes or decides, so its output is the
                                                one-rank output. Only such a component may
                                                write files, tables or point passes in a run
                                                across ranks; rank 0 alone writes its tables
                                                and write_file_atomic files, and a writer of
                                                shared files uses api->ranks. */
};

/* SLUICE_FINISH_INTERRUPTED (1.5): the run was stopped by SIGINT/SIGTERM after a
 * whole step and a checkpoint was written; plugins built for an older minor
 * receive SLUICE_FINISH_COMPLETE instead. */
enum sluice_finish_status {
    SLUICE_FINISH_COMPLETE = 0,
    SLUICE_FINISH_FAILED = 1,
    SLUICE_FINISH_INTERRUPTED = 2
};

typedef struct sluice_component {
    const char *name;    /* unique name used in scene files */
    const char *summary; /* one line */
    const char *reference; /* where the equations come from */
    uint32_t dimensions; /* SLUICE_DIMS_* mask */
    uint32_t flags;      /* sluice_component_flags */

    const sluice_param_spec *params;
    uint32_t param_count;
    size_t config_size;  /* the core fills a zeroed struct of this size */

    const sluice_field_spec *fields;
    uint32_t field_count;

    /* Pair terms: kinds of the targets i and of the neighbours j. */
    uint32_t target_kinds;
    uint32_t neighbour_kinds;
    /* Particle terms: kinds the callback is meant for (informative; the callback
     * receives every particle and filters itself). */
    uint32_t particle_kinds;

    /* Lifecycle. Return SLUICE_OK or SLUICE_ERROR (after api->error()). */
    int (*create)(const sluice_api *api, sluice_host *host, const void *config, void **state);
    void (*destroy)(void *state);
    int (*bind)(void *state, sluice_host *host);       /* all components exist */
    /* all fluid particles exist; writers of a field initialise before its
     * readers, scene order otherwise */
    int (*initialise)(void *state, sluice_host *host);

    /* Evaluation of rates (ordered by the core from declared reads/writes). */
    void (*particle)(void *state, const sluice_view *view, sluice_index begin, sluice_index end);
    void (*pair)(void *state, const sluice_view *view, const sluice_pair_batch *batch);

    /* Kernel: for n squared distances r2 (all below the support squared),
     * writes the distance r, W (unless w is NULL) and F = (dW/dr)/r. */
    void (*kernel)(void *state, sluice_index n, const sluice_real *r2, sluice_real *r,
                   sluice_real *w, sluice_real *f);

    /* Equation of state inverse: the density of each (absolute) pressure, as
     * the equation of state itself would output it. Used for the
     * hydrostatic initial state, where the core inverts the pressure at rest
     * density (the constant 'reference_pressure', 0 when no plugin publishes
     * it) plus rho0 g times the depth. */
    void (*density_from_pressure)(void *state, sluice_index n, const sluice_real *pressure,
                                  sluice_real *density);

    /* Integrator: advance the state by one step (uses api->evaluate/time_step). */
    int (*advance)(void *state, sluice_host *host);

    /* Largest stable step this component allows, over particles [begin, end). */
    sluice_real (*time_step_limit)(void *state, const sluice_view *view, sluice_index begin,
                                   sluice_index end);

    /* Once per step, before the integrator (inlets, prescribed motion). */
    int (*before_step)(void *state, sluice_host *host);
    /* Once per step, after the integrator (clamps, gauges, writers). */
    int (*after_step)(void *state, sluice_host *host);
    /* At the end of a run, complete or failed (final output, close files). */
    int (*finish)(void *state, sluice_host *host, int status);

    /* -- 1.3 (read only from plugins built for ABI 1.3 or later) */
    /* At every evaluation, once the neighbour search is up to date and before
     * the first pass, in scene order: set fields the passes read that depend
     * on the current positions and state of other particles (wall-particle
     * values from the fluid, with api->point_pass). Must not add, remove or
     * move particles. */
    int (*prepare)(void *state, sluice_host *host);

    /* -- 1.5 (read only from plugins built for ABI 1.5 or later) */
    /* Checkpoints: a component that keeps state across steps outside the
     * particle fields (counters, next output times, running sums) stores it
     * with api->state_write in save_state, and reads it back with
     * api->state_read in load_state. A restart loads the scene (create,
     * bind, initialise run as usual), replaces the particles, the time and
     * the core's counters with the checkpoint's, then calls load_state; the
     * after_step call before the first step is not repeated. Particle fields
     * are saved by the core (every field, not only those flagged
     * SLUICE_FIELD_RESTART). save_state is called after the after_step hooks
     * of the step the checkpoint holds; it must not change the state. */
    int (*save_state)(void *state, sluice_host *host);
    int (*load_state)(void *state, sluice_host *host);
} sluice_component;

/* Build signature: must equal the core's. */
typedef struct sluice_signature {
    uint32_t real_size;  /* sizeof(sluice_real) */
    uint32_t index_size; /* sizeof(sluice_index) */
    uint32_t dimensions; /* SLUICE_DIMS_* the library supports */
} sluice_signature;

/* The descriptor returned by sluice_plugin_entry(). The first six members keep
 * their layout in every ABI version so that the core can read and report any
 * plugin's versions. */
typedef struct sluice_library {
    uint32_t magic; /* SLUICE_PLUGIN_MAGIC */
    uint16_t abi_major, abi_minor;
    sluice_signature signature;
    const char *name;    /* library name */
    const char *version; /* library version, e.g. "1.0.0" */
    const char *description;
    uint32_t component_count;
    const sluice_component *components;
} sluice_library;

#define SLUICE_SIGNATURE_INIT(dims) {sizeof(sluice_real), sizeof(sluice_index), (dims)}
#define SLUICE_ENTRY_SYMBOL "sluice_plugin_entry"

/* The one symbol every plugin exports. */
typedef const sluice_library *(*sluice_entry_fn)(void);
SLUICE_EXPORT const sluice_library *sluice_plugin_entry(void);

/* Handy declaration of a library with its components. */
#define SLUICE_DEFINE_LIBRARY(lib_name, lib_version, lib_description, dims, component_array)    \
    static const sluice_library sluice_library_descriptor_ = {                                  \
        SLUICE_PLUGIN_MAGIC, SLUICE_ABI_MAJOR, SLUICE_ABI_MINOR, SLUICE_SIGNATURE_INIT(dims),   \
        (lib_name), (lib_version), (lib_description),                                           \
        (uint32_t)(sizeof(component_array) / sizeof((component_array)[0])), (component_array)}; \
    SLUICE_EXPORT const sluice_library *sluice_plugin_entry(void)                               \
    {                                                                                           \
        return &sluice_library_descriptor_;                                                     \
    }

#define SLUICE_COUNT(array) ((uint32_t)(sizeof(array) / sizeof((array)[0])))

#ifdef __cplusplus
}
#endif

#endif
