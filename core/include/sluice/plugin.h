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
 * ABI 2.3, frozen (docs/plugin-abi.md; its history: docs/abi-changelog.md):
 *  - SLUICE_ABI_MAJOR changes when anything existing changes; the core refuses
 *    a plugin with another major version.
 *  - SLUICE_ABI_MINOR grows when members are appended at the end of a host
 *    sub-table, of sluice_component or of sluice_view, never elsewhere. Every
 *    host sub-table and the library descriptor carry their size: the core
 *    reads a plugin's components with the stride it was built with (members
 *    it does not know read as absent). The core refuses a plugin built for a
 *    newer minor than its own, so every host member a plugin's header
 *    declares is there when it loads.
 *  - The build signature (size of sluice_real, of sluice_index, supported
 *    dimensions) must match the core exactly.
 *
 * What each kind of component must provide is checked when the scene loads
 * (docs/plugin-abi.md, "What each kind of component provides"): a kernel
 * publishes 'kernel_support'; an equation of state (a component with
 * density_from_pressure) publishes 'speed_of_sound' and 'reference_pressure';
 * an integrator has advance and no pair callback.
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

#define SLUICE_ABI_MAJOR 2
#define SLUICE_ABI_MINOR 3
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
 * SLUICE_KIND_OPEN is fluid in an inlet or outlet buffer whose state
 * (position, velocity, density) an open-boundary plugin imposes: the
 * integrators do not move it and no term targets it unless it asks for the
 * kind, but it is fluid to its neighbours. A component whose neighbour_kinds
 * (or a point_pass whose kinds) include SLUICE_KIND_FLUID also receives
 * SLUICE_KIND_OPEN neighbours: test a neighbour with `kind != SLUICE_KIND_WALL`
 * (not `== SLUICE_KIND_FLUID`) where fluid is meant. */
enum sluice_kind {
    SLUICE_KIND_FLUID = 0, /* moves with the flow, integrated */
    SLUICE_KIND_WALL = 1,  /* wall particle (dynamic boundary), fixed or prescribed motion */
    SLUICE_KIND_OPEN = 2,  /* fluid with an imposed state in an open-boundary buffer */
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

/* Element types of the plugin state arrays stored in checkpoints
 * (api->state->state_write / state_read). */
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

/* A resolved field: filled by api->fields->field(). `column` is the index of its first
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
 * particles (inside api->evaluation->evaluate) or changes their number; fetch it again with
 * api->particles->view() after those. */
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
    /* Inside an evaluation: the time the state being evaluated stands at
     * (s; e.g. time + dt/2 for a midpoint stage) and the evaluation's index
     * within the step (0, 1, ...), as the integrator passed them to
     * api->evaluation->evaluate. Between evaluations: time and 0. */
    double stage_time;
    uint32_t stage;
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

/* The point of a wall nearest to a query point (api->walls->wall_nearest). */
typedef struct sluice_wall_point {
    sluice_real distance;   /* signed, m: > 0 on the fluid side, < 0 behind the wall */
    sluice_real closest[3]; /* the nearest point of the wall */
    sluice_real normal[3];  /* unit normal into the fluid there (at a vertex or an edge the
                               pseudo-normal, the mean of the elements' normals) */
    uint32_t wall;          /* index of the wall (api->walls->wall) */
    uint32_t element;       /* segment (2D) or triangle (3D) */
    int32_t feature;        /* 0: interior of the element; 1..3: a vertex; 4..6: an edge (3D) */
    int32_t beyond_end;     /* 1 when the point lies past an open end of the wall (the end
                               of a polyline), where "behind" has no meaning */
} sluice_wall_point;

/* Called by api->evaluation->point_pass with batches of (point, particle) pairs. */
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

/* How values combine across the ranks of a distributed run (api->ranks->reduce). */
typedef enum sluice_reduce_op {
    SLUICE_REDUCE_SUM = 1,
    SLUICE_REDUCE_MIN = 2,
    SLUICE_REDUCE_MAX = 3
} sluice_reduce_op;

/* This rank's place in a distributed run (api->ranks->ranks). On one rank:
 * rank 0 of 1, offset 0, total = view->count, communicator NULL. */
typedef struct sluice_ranks {
    int32_t rank, count;      /* this rank, and how many there are */
    uint64_t particle_offset; /* particles of the ranks before this one */
    uint64_t particle_total;  /* particles of every rank */
    const void *communicator; /* the run's MPI_Comm (const MPI_Comm *), NULL without MPI */
} sluice_ranks;

/* The host API: the core's services, in sub-tables by concern. Each table
 * starts with its size (sizeof as the core was built): a later 2.x minor
 * appends members at the end of a table only, so no member ever moves and
 * a table's extent is known at run time. Every function taking a host must be called
 * from the thread that called the component, except those marked
 * "thread-safe". */

/* Messages, prefixed with the component's name. In create(), bind() and
 * initialise() an error becomes one diagnostic naming the plugin; during
 * the run it stops the run. */
typedef struct sluice_api_messages {
    uint32_t size;
    void (*error)(sluice_host *host, const char *format, ...) SLUICE_PRINTF(2, 3); /* thread-safe */
    void (*warning)(sluice_host *host, const char *format, ...) SLUICE_PRINTF(2, 3);
    void (*info)(sluice_host *host, const char *format, ...) SLUICE_PRINTF(2, 3);
} sluice_api_messages;

/* Fields and named constants. */
typedef struct sluice_api_fields {
    uint32_t size;
    /* Declares a field beyond the component's static `fields` (one whose
     * name or components depend on parameters, or on whether another plugin
     * declares some field: every component's static fields are declared
     * before any create() runs, so field_info finds them there). Only in
     * create(): a declaration after it is an error, since the integrated
     * fields are fixed when the integrator is created (after every other
     * component) and the schedule and particle store when bind() ends. */
    int (*declare_field)(sluice_host *host, const sluice_field_spec *spec);
    /* The handle of a declared field (its column is fixed when it is
     * declared: from bind() on for every field, in create() for those
     * declared already, as an integrator does); a field no component
     * declared is an error. */
    int (*field)(sluice_host *host, const char *name, sluice_field *out);
    /* Every field, in declaration order (writers). */
    uint32_t (*field_count)(sluice_host *host);
    int (*field_info)(sluice_host *host, uint32_t index, sluice_field_spec *spec,
                      sluice_field *field);
    /* The integrated fields: state, rate and kinds (integrators). */
    uint32_t (*rate_count)(sluice_host *host);
    int (*rate)(sluice_host *host, uint32_t index, sluice_rate *out);
    /* Named constants (smoothing_length, spacing, rest_density, dimensions,
     * end_time, domain_min, domain_max from the core; kernel_support,
     * speed_of_sound, reference_pressure, gravity, ... from plugins).
     * publish: in create(), once per name over the scene; constant: from
     * bind() on, returns the number of values, or 0 when nobody published
     * it. */
    int (*publish_constant)(sluice_host *host, const char *name, const sluice_real *values,
                            uint32_t count, const char *unit);
    uint32_t (*constant)(sluice_host *host, const char *name, sluice_real *values,
                         uint32_t max_count);
} sluice_api_fields;

/* Particles: the view, and particles that come and go. */
typedef struct sluice_api_particles {
    uint32_t size;
    const sluice_view *(*view)(sluice_host *host);
    /* Adds `count` particles of `kind` at positions (3 reals each); mass,
     * density (rest density) and a new id are set by the core, other fields
     * are zero. In initialise(), and between steps (before_step or
     * after_step), never inside an evaluation. *first receives the index of
     * the first one; indices of existing particles do not change. Across
     * ranks only components flagged SLUICE_COMPONENT_ACROSS_RANKS add or
     * remove particles during the run; new ids are unique over the ranks,
     * and a particle added outside the rank's box moves to its owner at the
     * next neighbour-list rebuild. */
    int (*add_particles)(sluice_host *host, uint8_t kind, const sluice_real *positions,
                         sluice_index count, sluice_index *first);
    /* Only between steps. Removes the particles at the listed indices (any
     * order, no duplicates); the others keep their ids and order but move to
     * lower indices, so indices held before the call are stale after it. Ids
     * are never reused. */
    int (*remove_particles)(sluice_host *host, const sluice_index *indices, sluice_index count);
    /* Only between steps: changes the kind of the listed particles (e.g.
     * SLUICE_KIND_OPEN -> SLUICE_KIND_FLUID when an inflow particle leaves
     * the inlet buffer). Fails on an index out of range. */
    int (*set_kind)(sluice_host *host, const sluice_index *indices, sluice_index count,
                    uint8_t kind);
    /* Particles removed since the start of the run (all kinds; across ranks,
     * by this rank). */
    uint64_t (*removed_count)(sluice_host *host);
    /* Runs fn over [0, count) in parallel chunks. */
    void (*parallel_for)(sluice_host *host, sluice_index count, sluice_range_fn fn, void *context);
} sluice_api_particles;

/* The scene's walls and distances to them. */
typedef struct sluice_api_walls {
    uint32_t size;
    uint32_t (*wall_count)(sluice_host *host);
    const sluice_wall *(*wall)(sluice_host *host, uint32_t index);
    /* Lattice points (spacing dx, aligned with the fluid lattice) behind a
     * wall, at a distance in (0, thickness] from it on the side away from
     * the fluid. The array (3 reals per point) is freed with release(). */
    int (*wall_layer_points)(sluice_host *host, uint32_t wall_index, sluice_real thickness,
                             sluice_real **points, sluice_index *count);
    void (*release)(void *memory);
    /* Distance from a point (3 reals) to the nearest wall of the scene, of
     * any scheme, in m; INFINITY when the scene has no walls. Thread-safe. */
    sluice_real (*wall_distance)(sluice_host *host, const sluice_real *point);
    /* The nearest point of wall `wall` (of every wall when wall < 0) to
     * `point` (3 reals). SLUICE_ERROR when the scene has no such wall.
     * Thread-safe. */
    int (*wall_nearest)(sluice_host *host, const sluice_real *point, int32_t wall,
                        sluice_wall_point *out);
    /* Since ABI 2.2. A wall that moves as a rigid body: the wall scheme that
     * handles wall `index` (its component is wall->scheme) sets the wall's
     * displacement from the scene's geometry (3 reals, m; the third 0 in 2D)
     * whenever it moves the wall. The first call, which marks the wall as
     * moving for the whole run, is made in create(), bind() or
     * initialise(); later ones between steps. wall() keeps the scene's
     * points, and wall_distance and wall_nearest measure to them: the
     * displacement is what writers show. */
    int (*set_wall_displacement)(sluice_host *host, uint32_t index,
                                 const sluice_real *displacement);
    /* Since ABI 2.2. 1 when wall `index` moves (its scheme set a
     * displacement), with the displacement last set in out (3 reals); 0 with
     * zeros for a fixed wall or an index out of range. */
    int (*wall_displacement)(sluice_host *host, uint32_t index, sluice_real *out);
} sluice_api_walls;

/* Evaluations, time steps and passes. */
typedef struct sluice_api_evaluation {
    uint32_t size;
    /* Integrators: evaluates every rate at the current state (updating the
     * neighbour search first when needed), for the stage of the step that
     * starts at view->time and whose state stands at `stage_time` (s);
     * `stage` counts the evaluations of the step from 0. Every callback of
     * the evaluation reads both in the view (stage_time, stage). */
    int (*evaluate)(sluice_host *host, double stage_time, uint32_t stage);
    /* Integrators: the step size after an evaluation: the minimum of every
     * component's limit, clamped to the end time and requested times. */
    double (*time_step)(sluice_host *host);
    /* Asks the core to end a step exactly at time t (outputs, gauges). */
    void (*request_time)(sluice_host *host, double t);
    /* For a component flagged SLUICE_COMPONENT_ON_DEMAND: runs its pair
     * callback over every particle now, on the current state (from a hook).
     * Across ranks the core first refreshes the halo: collective. */
    int (*pair_pass)(sluice_host *host);
    /* Interpolation at arbitrary points: calls fn with batches in which
     * target[t] is the index of a point (3 reals each in `points`) and the
     * pairs are the particles of a kind in `kinds` within the kernel support
     * of it: offset = point - x_j, distance (may be 0), kernel (W) and
     * kernel_gradient (F) always set, gathered NULL (read the view's columns
     * at neighbour[k]). Runs in parallel over chunks of points, so fn writes
     * only to what belongs to its points. From prepare() or a hook, never
     * from a particle or pair callback. */
    int (*point_pass)(sluice_host *host, const sluice_real *points, sluice_index count,
                      uint32_t kinds, sluice_point_fn fn, void *context);
    /* As point_pass at points of this rank's own particles (a wall
     * particle's mirror point), with, across ranks, the particles other
     * ranks own near the rank's box (the halo, refreshed first), so that
     * every point gets what it gets on one rank. Each point lies within the
     * margin the component requested (request_point_margin; 0 by default) of
     * the rank's box; a point beyond it fails with a message. Collective
     * across ranks; on one rank it is point_pass. */
    int (*point_pass_local)(sluice_host *host, const sluice_real *points, sluice_index count,
                            uint32_t kinds, sluice_point_fn fn, void *context);
    /* In create(), bind() or initialise(): the points of this component's
     * point_pass_local lie up to `margin` m (finite, >= 0; along any axis)
     * from the particle they belong to; across ranks the halo is widened by
     * the largest margin requested. */
    int (*request_point_margin)(sluice_host *host, sluice_real margin);
    /* In create(), once: a pair term that reaches beyond the kernel support
     * (a kernel of its own with a longer smoothing length, e.g. the air's
     * cohesion with H = 2h) receives every pair within `radius` m in passes
     * of its own (the Verlet list stays at the support, so no other term
     * pays for the reach); in its batches `kernel` and `kernel_gradient` are
     * NULL. Fails after create(), for a non-pair component, or for a radius
     * that is not finite and positive; a radius within the support changes
     * nothing. Across ranks the halo is as wide as the largest reach. */
    int (*request_reach)(sluice_host *host, sluice_real radius);
    /* In create(), after request_reach: the term contributes only where the
     * target and the neighbour both hold `value` in the uint8 field `field`
     * (which the component declares it reads); the core leaves every other
     * particle out of the term's pass. */
    int (*restrict_reach)(sluice_host *host, const char *field, uint32_t value);
    /* density[k] for pressure[k], k < n, through the inverse of the scene's
     * equation of state (the component with a density_from_pressure
     * callback, the one the core uses for the hydrostatic start). Fails with
     * a message when the scene loads none; n = 0 only checks that one is
     * loaded. */
    int (*density_from_pressure)(sluice_host *host, sluice_index n, const sluice_real *pressure,
                                 sluice_real *density);
} sluice_api_evaluation;

/* Writes a whole file to `path`, a temporary path that the core renames
 * to the file's own once the writer returns 0. On failure the writer puts
 * a message (without the path) in `error` and returns non-zero. */
typedef int (*sluice_file_writer)(void *context, const char *path, char *error,
                                  size_t error_size);

/* The run's output directory, tables and files. */
typedef struct sluice_api_output {
    uint32_t size;
    /* Path of `name` inside the run's output directory. */
    int (*output_path)(sluice_host *host, const char *name, char *buffer, size_t size);
    /* The fully resolved scene (every default filled in), YAML text. */
    const char *(*resolved_scene)(sluice_host *host);
    /* The loaded components: name, library, version, file. */
    uint32_t (*plugin_count)(sluice_host *host);
    int (*plugin)(sluice_host *host, uint32_t index, sluice_plugin_info *out);
    /* Time series in the output directory: a CSV file with a header line;
     * rows are written whole, and a restart continues the file. */
    sluice_table *(*table_open)(sluice_host *host, const char *file_name, const char *header);
    int (*table_row)(sluice_table *table, const double *values, uint32_t count);
    /* Writes `size` bytes to `path` atomically (temporary file, then rename). */
    int (*write_file_atomic)(sluice_host *host, const char *path, const void *data, size_t size);
    /* Since ABI 2.1. Writes `path` atomically through `writer`, which
     * writes the whole file to the temporary path it is given. The writer
     * runs in a child process that sees the run's memory as it is
     * (copy-on-write): it streams the data from the component's arrays, with
     * no copy of the file in memory, and a writer that crashes or a library
     * left broken by a failed write (HDF5 1.10 after a failed H5Fclose on a
     * full disk) fails this call only. The writer must not rely on changes
     * to memory surviving it (they stay in the child) and runs OpenMP on one
     * thread. Across ranks, rank 0 writes the file. */
    int (*write_file_with)(sluice_host *host, const char *path, sluice_file_writer writer,
                           void *context);
    /* Since ABI 2.2. What the core knows about the run, by name, as text
     * (NULL for a name it does not know): "version" (Sluice's), "git_revision"
     * (of the source the program was built from, "unknown" outside git),
     * "build" (compiler, build type, instruction set, MPI), "command_line",
     * "date" (the run's start, UTC, ISO 8601), "host", "kernel" (the scene's
     * kernel component, e.g. "cubic_spline"). Valid for the whole run. */
    const char *(*describe_run)(sluice_host *host, const char *name);
    /* Since ABI 2.2. Describes column `column` (0 for the first of the
     * header's columns) of a table the component opened: its unit (SI, in
     * the fields' notation: "s", "m", "m s^-1", "Pa", "N m^-1", "1" for a
     * dimensionless number), what it measures (a short phrase) and, for a
     * column measured at one place, its position (3 reals, m; NULL for none).
     * Call it after table_open, before the run's first step (in create(),
     * bind() or initialise()); describing a column again replaces what was
     * said. The core writes the run's tables and their columns to
     * tables.json in the output directory (docs/analysis.md); the CSV header
     * is unchanged. */
    int (*table_column)(sluice_table *table, uint32_t column, const char *unit,
                        const char *description, const sluice_real *position);
} sluice_api_output;

/* Plugin state in checkpoints (docs/reliability.md, "Checkpoints and
 * restart"). Only inside the component's own save_state (write) or
 * load_state (read, length). Arrays are named (a plain name, no '/'),
 * stored under the component's group of the checkpoint, with an element
 * type and count (0 is allowed). read fails with a message when the array
 * is missing or its type or count differ; length returns the element
 * count, or -1 when the array is missing. A checkpoint with no group for
 * the component still calls load_state, with every array missing. */
typedef struct sluice_api_state {
    uint32_t size;
    int (*state_write)(sluice_host *host, const char *name, sluice_state_type type,
                       uint64_t count, const void *data);
    int (*state_read)(sluice_host *host, const char *name, sluice_state_type type,
                      uint64_t count, void *data);
    int64_t (*state_length)(sluice_host *host, const char *name);
} sluice_api_state;

/* Runs across MPI ranks (docs/scaling.md). Each rank's components see the
 * rank's own particles (view->count) and, in pair batches, the neighbours
 * other ranks own. reduce and ranks are collective: every rank calls them
 * at the same point of the run, in the same order. */
typedef struct sluice_api_ranks {
    uint32_t size;
    /* Combines values[0 .. count) over the ranks, in place, on every rank;
     * the identity on one rank. */
    int (*reduce)(sluice_host *host, double *values, uint32_t count, sluice_reduce_op op);
    /* This rank's place and the offset of its particles in the global order
     * (ranks in order, each rank's particles in view order). */
    int (*ranks)(sluice_host *host, sluice_ranks *out);
    /* 1 when this rank's box holds `point` (3 reals), 0 otherwise; always 1
     * on one rank. Not collective. */
    int (*owns)(sluice_host *host, const sluice_real *point);
} sluice_api_ranks;

/* The host table handed to every component's create(). */
typedef struct sluice_api {
    uint32_t size;
    uint16_t abi_major, abi_minor;
    const sluice_api_messages *messages;
    const sluice_api_fields *fields;
    const sluice_api_particles *particles;
    const sluice_api_walls *walls;
    const sluice_api_evaluation *evaluation;
    const sluice_api_output *output;
    const sluice_api_state *state;
    const sluice_api_ranks *ranks;
} sluice_api;

/* ----------------------------------------------------------- components -- */

enum sluice_component_flags {
    SLUICE_COMPONENT_NEEDS_KERNEL = 1u << 0, /* pair term reads batch->kernel */
    SLUICE_COMPONENT_WALL_SCHEME = 1u << 1,  /* handles the scene's walls (api->walls->wall) */
    SLUICE_COMPONENT_ON_DEMAND = 1u << 2,    /* its pair callback is not part of every
                                                evaluation; it runs when the component calls
                                                api->evaluation->pair_pass() */
    SLUICE_COMPONENT_ACROSS_RANKS = 1u << 3  /* written for runs across ranks: it
                                                combines what it sums or finds over its
                                                rank's particles with api->ranks->reduce before it
                                                writes or decides, so its output is the
                                                one-rank output. Only such a component may
                                                write files, tables or point passes in a run
                                                across ranks; rank 0 alone writes its tables
                                                and write_file_atomic files, and a writer of
                                                shared files uses api->ranks->ranks. */
};

/* SLUICE_FINISH_INTERRUPTED: the run was stopped by SIGINT/SIGTERM after a
 * whole step and a checkpoint was written. */
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

    /* Lifecycle. Return SLUICE_OK or SLUICE_ERROR (after api->messages->error()). */
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

    /* Integrator: advance the state by one step (uses api->evaluation->evaluate/time_step). */
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

    /* At every evaluation, once the neighbour search is up to date and before
     * the first pass, in scene order: set fields the passes read that depend
     * on the current positions and state of other particles (wall-particle
     * values from the fluid, with api->evaluation->point_pass). Must not add, remove or
     * move particles. */
    int (*prepare)(void *state, sluice_host *host);

    /* Checkpoints: a component that keeps state across steps outside the
     * particle fields (counters, next output times, running sums) stores it
     * with api->state->state_write in save_state, and reads it back with
     * api->state->state_read in load_state. A restart loads the scene (create,
     * bind, initialise run as usual), replaces the particles, the time and
     * the core's counters with the checkpoint's, then calls load_state; the
     * after_step call before the first step is not repeated. Particle fields
     * are saved by the core (every field, not only those flagged
     * SLUICE_FIELD_RESTART). save_state is called after the after_step hooks
     * of the step the checkpoint holds; it must not change the state. */
    int (*save_state)(void *state, sluice_host *host);
    int (*load_state)(void *state, sluice_host *host);

    /* Since ABI 2.3. Pair terms: the neighbour kinds of a target of kind k, where
     * they differ from neighbour_kinds (0: neighbour_kinds; only for kinds
     * in target_kinds). The neighbour list holds, for each target kind, only
     * the kinds some term asks for, so a kind that needs few neighbours
     * costs little: continuity declares [SLUICE_KIND_WALL] = fluid (a wall
     * particle is compressed by the fluid alone), and a wall particle out
     * of the fluid's reach then has no pairs at all (docs/performance.md,
     * "Walls"). A term sharing a pass with others may still receive other
     * kinds (batch->neighbour_kinds says which are present). */
    uint32_t neighbour_kinds_by_target[SLUICE_KIND_COUNT];
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
    /* sizeof(sluice_component) as the library was built: the core reads its
     * components with this stride, and members a later 2.x minor appends
     * read as absent (zero) for a library built before them. */
    uint32_t component_size;
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
        (uint32_t)(sizeof(component_array) / sizeof((component_array)[0])), (component_array), \
        (uint32_t)sizeof(sluice_component)};                                                    \
    SLUICE_EXPORT const sluice_library *sluice_plugin_entry(void)                               \
    {                                                                                           \
        return &sluice_library_descriptor_;                                                     \
    }

#define SLUICE_COUNT(array) ((uint32_t)(sizeof(array) / sizeof((array)[0])))

#ifdef __cplusplus
}
#endif

#endif
