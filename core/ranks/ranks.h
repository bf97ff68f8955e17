/* Domain decomposition of a distributed run (docs/scaling.md). The domain is
 * cut into one box per rank: along x into split[0] slabs, each slab along y
 * into split[1], each of those along z into split[2] (the scene's
 * ranks.split names the axes; the counts follow from the rank count and the
 * particles' extent). Each rank owns the particles of its box, kept in the
 * store's [0, count); copies of the other ranks' particles within the halo
 * width of its box (the halo) follow them in [count, count + halo). The
 * neighbours of a rank are the ranks whose box, widened by the halo width,
 * meets its box (periodic images included), so a box may be narrower than
 * the halo. The cuts are set from the initial particles (equal counts) and
 * move during the run to balance the ranks' work. Particles that leave a box
 * move to the rank that owns their place at each neighbour-list rebuild;
 * between rebuilds the halo's fields are refreshed before every pair pass.
 * With one rank nothing here is called. */
#ifndef SLUICE_RANKS_H
#define SLUICE_RANKS_H

#include "comm.h"
#include "neighbours.h"
#include "particles.h"
#include "scene.h"

typedef struct sluice_halo_lists {
    int split[3];            /* ranks along x, y, z (their product: the rank count) */
    double *cuts;            /* the cuts, by level (ranks.c: cut_x, cut_y, cut_z) */
    size_t cut_count;
    double *boxes;           /* 6 per rank: lo x y z, hi x y z (+-inf at a closed outer side) */
    double lo[3], hi[3];     /* this rank's box */
    double width;            /* halo width: reach + point margin + skin (ranks.c) */
    int neighbour_count;
    int *neighbour;          /* the neighbouring ranks, in rank order */
    sluice_index *send;      /* own particles sent to neighbour k: send[send_begin[k] ..) */
    sluice_index *send_begin, *receive_begin; /* neighbour_count + 1 each */
    sluice_index send_capacity;
    unsigned long long *sent, *got; /* per neighbour, for the exchange */
    void *requests;          /* MPI_Request[2 * neighbour_count] */
    sluice_index *slot;      /* received entry k -> halo slot (after the cell sort) */
    sluice_index slot_capacity;
    uint64_t slot_valid_at;  /* grid.rebuilds when slot was computed */
    uint64_t arrived;        /* particles received from other ranks by migration */
    /* load balance (sluice_ranks_balance) */
    double busy_seconds;     /* this rank's time in the passes since the last balance */
    int64_t balance_step;    /* the step of the last balance */
    uint64_t balances;       /* times the cuts moved */
    /* the columns a refresh sends: what other ranks' particles are read
     * for (position, kind, the fields declared SLUICE_READ_NEIGHBOUR, those
     * a component reads in its local point passes, a reach's selection);
     * the other real columns of the halo hold NaN between rebuilds */
    uint32_t *columns;
    uint32_t column_count;
    uint8_t *real_column;    /* per column: 1 for a column of a real field */
    char *buffer[2];         /* send and receive */
    size_t buffer_capacity[2];
} sluice_halo_lists;

/* What the decomposition sees of a run: this rank's particle store and
 * cells, the lists above, the scene's ranks settings and where a failure's
 * message goes (the first cause is kept). The engine fills it once; the
 * pointers stay valid for the run. Before sluice_ranks_split the engine
 * sets the halo's width and the columns a refresh sends (halo->width,
 * columns, real_column): what other ranks' particles are read for is the
 * engine's knowledge, not this library's. */
typedef struct sluice_ranks_run {
    sluice_comm *comm;
    sluice_particles *particles;
    sluice_grid *grid;
    sluice_halo_lists *halo;
    int32_t position_column, kind_column;
    double spacing;            /* lattice spacing, m: the extent of a flat axis */
    int split_axes;            /* ranks.split: bit d for axis d */
    int balance;               /* ranks.balance: SLUICE_BALANCE_TIME, _COUNT or _NONE */
    int64_t balance_every;     /* ranks.every, steps */
    double balance_tolerance;  /* ranks.tolerance */
    char *failure;             /* message of the first failure */
    size_t failure_size;
} sluice_ranks_run;

#ifdef SLUICE_MPI
/* Splits the initial particles (every rank built all of them, or read them
 * all from a checkpoint) into boxes of equal counts along the scene's
 * ranks.split axes and keeps this rank's. Fails (message in sim) when the
 * split cannot be made. Collective. */
int sluice_ranks_split(sluice_ranks_run *run);
/* Every ranks.every steps (scene), before the neighbour search: when the
 * ranks' work since the last balance (their measured time in the passes,
 * or their particle counts: ranks.balance) differs by more than
 * ranks.tolerance of the mean, moves every cut half the way towards equal
 * shares (weighted quantiles of the particles, axis by axis). Returns 1
 * when they moved (the caller rebuilds: the migration moves the
 * particles), 0 when not, -1 on failure. Collective. */
int sluice_ranks_balance(sluice_ranks_run *run, int64_t step);
/* Before a rebuild: sends the particles that left the box to the rank that
 * owns their place now. Collective. */
int sluice_ranks_migrate(sluice_ranks_run *run);
/* The grid's halo function (sluice_grid_halo_fn): sends copies of the
 * particles within the halo width of each neighbour's box, receives the
 * neighbours' after the sorted particles. Collective. */
int sluice_ranks_collect_halo(void *run, sluice_particles *particles, sluice_index *halo_count);
/* Refreshes every field of the halo from its owners. Collective. */
int sluice_ranks_refresh_halo(sluice_ranks_run *run);
void sluice_ranks_free(sluice_halo_lists *lists);
/* Every rank's own particles, in rank order, into `all` on rank 0 (a store
 * of the same columns, initialised here; left empty on the other ranks).
 * Collective. 0, or -1 (out of memory or MPI; on any rank, every rank). */
int sluice_ranks_gather(sluice_ranks_run *run, sluice_particles *all);
/* 1 when this rank's box holds the point (3 reals; periodic axes wrapped). */
int sluice_ranks_owns(const sluice_ranks_run *run, const double point[3]);
/* How far the point lies outside this rank's box: the largest gap along an
 * axis (periodic images included), 0 inside. */
double sluice_ranks_outside(const sluice_ranks_run *run, const double point[3]);
#else
static inline void sluice_ranks_free(sluice_halo_lists *lists) { (void)lists; }
#endif

#endif
