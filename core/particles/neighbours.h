/* Neighbour search: a cell-linked grid (cell size >= support + skin) that
 * sorts particles by cell, and a Verlet list of every pair within
 * support + skin, rebuilt only when some particle has moved more than skin/2
 * since the last build. Each evaluation turns the list into pair batches (see
 * pairs.h). */
#ifndef SLUICE_NEIGHBOURS_H
#define SLUICE_NEIGHBOURS_H

#include <stddef.h>
#include <stdint.h>

#include "particles.h"
#include "sluice/plugin.h"

typedef struct sluice_grid {
    uint32_t dimensions;
    int periodic[3];
    double lo[3], hi[3], length[3];
    double cell_size[3], inverse_cell_size[3];
    int64_t cells[3];
    size_t cell_count;
    sluice_real support; /* kernel support radius (2h) */
    sluice_real skin;    /* extra radius of the list, m */

    /* State of the last build (particles in sorted order). */
    int valid;
    sluice_index count;
    sluice_index *cell_start; /* cell_count + 1 */
    sluice_index *order;      /* capacity: permutation scratch */
    uint32_t *cell_of;        /* capacity */
    sluice_real *built[3];    /* positions at the last build */
    sluice_index capacity;

    /* Verlet list: neighbours of particle i are list[list_begin[i] .. list_begin[i+1]) */
    sluice_index *list_begin; /* capacity + 1 */
    sluice_index *list;
    size_t list_capacity;
    /* the most entries a list may grow to (0: no limit), set by the engine
     * from the memory left before each build; a build that needs more
     * returns -4 with list_needed set, before allocating */
    size_t list_limit, list_needed;
    int threads;
    size_t *thread_counts; /* scratch */
    /* What the list holds: a particle of kind k lists its neighbours of the
     * kinds in list_kinds[k] alone (none when 0: no pair pass targets the
     * kind), so that kinds no term pairs cost nothing (a dry wall particle
     * has an empty list). kind_column: the store's uint8 kind column; -1
     * (the default): every particle lists every kind. Set by the engine from
     * its passes (sluice_sim_set_list_kinds); a change of kind invalidates
     * the grid. */
    int32_t kind_column;
    uint32_t list_kinds[SLUICE_KIND_COUNT];
    /* the kinds present in each cell at the last build (its particles and
     * halo; bit k for kind k), with kind_column set: a particle skips the
     * cells that hold none of the kinds it lists */
    uint8_t *cell_kinds;
    /* light loops over particles run on one thread below this many (0:
     * never; the engine sets it, particles.h) */
    sluice_index parallel_min;

    /* Halo of a distributed run (docs/scaling.md): particles [count, count +
     * halo_count) of the store, copies of other ranks' particles, sorted by
     * cell and indexed by halo_start (absolute indices, cell_count + 1).
     * They are neighbours only: the list holds no entries of their own.
     * halo_order[s]: the halo received k-th that went to slot count + s. */
    sluice_index halo_count;
    sluice_index *halo_start;
    sluice_index *halo_order;
    sluice_index halo_capacity;
    /* the halo's positions at the last build, slot s at halo_built[d][s]
     * (the passes beyond the support list their pairs from them) */
    sluice_real *halo_built[3];
    sluice_index halo_built_capacity;

    /* Figures for benchmarks. */
    uint64_t rebuilds;
} sluice_grid;

/* Appends the halo after the build has sorted the particles [0, count) by
 * cell: writes the other ranks' copies to [count, count + *halo_count) of
 * the store (reserving room for them). Returns 0 or -1 (with a message of
 * its own). */
typedef int (*sluice_grid_halo_fn)(void *context, sluice_particles *particles,
                                   sluice_index *halo_count);

/* Sets up the grid over the box [lo, hi). Returns 0, or -1 with *reason set
 * (a periodic direction shorter than 3 cells, a domain too large to index). */
int sluice_grid_init(sluice_grid *grid, uint32_t dimensions, const double lo[3], const double hi[3],
                     const int periodic[3], sluice_real support, sluice_real skin,
                     const char **reason);
void sluice_grid_free(sluice_grid *grid);

/* 1 when the list must be rebuilt before the next evaluation: never built,
 * particle count changed, or some particle moved more than skin/2. */
int sluice_grid_needs_rebuild(const sluice_grid *grid, const sluice_view *view);

/* Sorts the particles by cell (permuting every column of `particles`), then
 * rebuilds the cell index and the Verlet list. position_column: the first of
 * the position columns. Returns 0; -1 on OOM; -2 when a particle lies outside
 * a non-periodic side of the domain or is not finite (its index, in the order
 * before sorting, goes to *bad). */
int sluice_grid_build(sluice_grid *grid, sluice_particles *particles, uint32_t position_column,
                      sluice_index *bad);
/* The same for a distributed run: halo(context, ...) appends the halo once
 * the particles are sorted, and the Verlet list of [0, count) takes its
 * neighbours from both. -3: the halo function failed. */
int sluice_grid_build_with_halo(sluice_grid *grid, sluice_particles *particles,
                                uint32_t position_column, sluice_index *bad,
                                sluice_grid_halo_fn halo, void *context);

/* Particles within sqrt(radius2) <= support of the point p (3 reals), from the
 * last build's cells and the current positions (valid while the list is:
 * no particle has moved more than skin/2 since). Writes at most `capacity`
 * indices to out and returns how many there are (call again with a larger
 * array when that exceeds capacity). p may lie anywhere; periodic axes use
 * the minimum image. with_halo: the halo's particles too (after the own
 * ones of each cell row). */
sluice_index sluice_grid_near_point(const sluice_grid *grid, sluice_real *const pos[3],
                                    const double p[3], double radius2, int with_halo,
                                    sluice_index *out, sluice_index capacity);

/* Wraps coordinates of periodic directions into [lo, hi). */
void sluice_grid_wrap(const sluice_grid *grid, sluice_real *position[3], sluice_index count);

/* A list in CSR form, from its counts: turns the counts in begin[1 .. n]
 * into offsets (begin[0] = 0, begin[i + 1] the end of i's entries) and makes
 * *list (of *capacity entries, grown with a quarter's margin) hold them all.
 * Returns 0, -1 on OOM or when the total exceeds the index type, or -4
 * when growing would pass `limit` entries (> 0; *needed then holds the
 * total, and nothing is allocated). Used by the Verlet list and by the
 * reach passes' own lists (pairs.c). */
int sluice_list_offsets(sluice_index *begin, sluice_index n, sluice_index **list,
                        size_t *capacity, size_t limit, size_t *needed);

/* Bytes held by the grid and the list (memory figures). */
size_t sluice_grid_bytes(const sluice_grid *grid);

#endif
