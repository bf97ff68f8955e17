/* Pair passes: the core turns the Verlet list into batches of pairs within
 * the kernel support (a few hundred pairs sharing r_ij, |r_ij|, W, F and the
 * neighbour values of every gathered column) and calls each loaded pair term
 * once per batch: no function call per pair. Batches hold targets of one
 * kind; each target is handled by one thread, so terms only write to their
 * targets and need no atomics, and results do not depend on the thread count. */
#ifndef SLUICE_PAIRS_H
#define SLUICE_PAIRS_H

#include "neighbours.h"
#include "sluice/plugin.h"

typedef struct sluice_pair_term {
    const sluice_component *component;
    void *state;
    uint32_t target_kinds;
} sluice_pair_term;

/* A reach pass's own Verlet list: the neighbours of each target within
 * reach + skin at the grid's last build (the selected particles of kinds
 * the target's kind sees), in the order of the cell scan; rebuilt whenever
 * the grid is (particles moved skin/2, were added, removed or changed
 * kind), so between builds every pair within reach is on it. */
typedef struct sluice_reach_list {
    uint64_t built_at;   /* grid->rebuilds + 1 at the build; 0: never built */
    sluice_index count;  /* particles at the build */
    sluice_index *begin; /* count + 1 */
    sluice_index begin_capacity;
    sluice_index *list;
    size_t capacity;
} sluice_reach_list;

/* Releases a reach list and its arrays (NULL is fine). */
void sluice_reach_list_free(sluice_reach_list *list);

typedef struct sluice_pair_pass {
    uint32_t term_count;
    sluice_pair_term *terms;
    uint32_t neighbour_mask[SLUICE_KIND_COUNT]; /* per target kind; 0: kind is not a target */
    /* REAL columns gathered at j, per target kind: only those the terms that
     * act on that kind read */
    uint32_t gathered_count[SLUICE_KIND_COUNT];
    uint32_t *gathered_columns[SLUICE_KIND_COUNT];
    uint32_t gathered_max; /* largest gathered_count */
    int needs_kernel[SLUICE_KIND_COUNT];
    /* 0: pairs within the kernel support, from the Verlet list; > 0: pairs
     * within this radius (m, beyond the support), found through the cell
     * grid, with no kernel values (api->evaluation->request_reach) */
    sluice_real reach;
    /* reach passes (api->evaluation->restrict_reach): only particles whose uint8
     * column `select_column` holds `select_value`, as targets and as
     * neighbours; -1: every particle */
    int32_t select_column;
    uint8_t select_value;
    sluice_reach_list *reach_list; /* reach passes: allocated with the pass */
} sluice_pair_pass;

typedef struct sluice_pair_workspace {
    sluice_index pair_capacity, target_capacity;
    sluice_index *target, *pair_begin, *neighbour;
    uint8_t *neighbour_kind;
    sluice_real *offset[3], *distance_squared, *distance, *kernel, *gradient;
    sluice_real *gathered_storage;
    uint32_t gathered_slots;
    const sluice_real **gathered; /* column_count pointers */
    uint32_t column_count;
    /* statistics: pairs handed to terms and batches (all passes), and the
     * pairs and thread-seconds of the passes within the support per
     * target kind (fill, kernel, gather and terms of its batches) */
    uint64_t pairs, batches;
    uint64_t kind_pairs[SLUICE_KIND_COUNT];
    double kind_seconds[SLUICE_KIND_COUNT];
} sluice_pair_workspace;

typedef struct sluice_pair_engine {
    const sluice_component *kernel;
    void *kernel_state;
    sluice_real kernel_self;
    sluice_index batch_pairs; /* target batch size in pairs */
    int thread_count;
    sluice_pair_workspace *workspaces;
} sluice_pair_engine;

int sluice_pair_engine_init(sluice_pair_engine *engine, int thread_count, sluice_index batch_pairs,
                            uint32_t column_count);
void sluice_pair_engine_free(sluice_pair_engine *engine);

/* Runs one pass over every particle. Returns 0, or -1 on OOM. */
int sluice_pair_pass_run(sluice_pair_engine *engine, const sluice_pair_pass *pass,
                         const sluice_grid *grid, const sluice_view *view);

/* Point pass: for `count` points (3 reals each), batches of (point, particle
 * within the support of a kind in `kinds`) with offsets point - x_j, the
 * distance (may be 0), W and F, handed to fn; batch->target holds point
 * indices and batch->gathered is NULL. Parallel over chunks of points.
 * with_halo: the particles of the halo (other ranks') are pairs too.
 * Returns 0, or -1 on OOM. */
int sluice_point_pass_run(sluice_pair_engine *engine, const sluice_grid *grid,
                          const sluice_view *view, const sluice_real *points, sluice_index count,
                          uint32_t kinds, int with_halo,
                          void (*fn)(void *context, const sluice_view *view,
                                     const sluice_pair_batch *batch),
                          void *context);

/* 0 when a pass of radius `reach` visits no cell twice across a periodic
 * side (the periodic axes span at least 2 ceil((reach + skin) / cell) + 1
 * cells), -1 otherwise. */
int sluice_pair_reach_check(const sluice_grid *grid, sluice_real reach);

/* Pairs handed to terms since the engine was created (all threads). */
uint64_t sluice_pair_engine_pairs(const sluice_pair_engine *engine);
/* The pairs and the thread-seconds that the passes within the support spent
 * on targets of `kind` since the engine was created (all threads): what a
 * kind of particle costs (the wall share of a step, docs/performance.md). */
uint64_t sluice_pair_engine_kind_pairs(const sluice_pair_engine *engine, uint32_t kind);
double sluice_pair_engine_kind_seconds(const sluice_pair_engine *engine, uint32_t kind);
size_t sluice_pair_engine_bytes(const sluice_pair_engine *engine);

#endif
