/* Domain decomposition of a distributed run along x (docs/scaling.md). Each
 * rank owns the particles of its slab [slab_lo, slab_hi) of x, kept in the
 * store's [0, count); copies of the other ranks' particles within the list
 * cutoff of its slab (the halo) follow them in [count, count + halo). The
 * slabs are set once from the initial particles (equal counts). Particles
 * that leave a slab move to the neighbouring rank at each neighbour-list
 * rebuild; between rebuilds the halo's fields are refreshed before every
 * pair pass. With one rank nothing here is called. */
#ifndef SLUICE_RANKS_H
#define SLUICE_RANKS_H

#include "comm.h"
#include "particles.h"

typedef struct sluice_sim sluice_sim;

typedef struct sluice_halo_lists {
    double slab_lo, slab_hi; /* the slab, -inf / +inf at the ends */
    double width;            /* halo width: reach + point margin + skin (ranks.c) */
    sluice_index *send[2];   /* owned particles sent to the left (0) and right (1) rank */
    sluice_index send_count[2], send_capacity[2];
    sluice_index receive_count[2]; /* from the left and from the right */
    sluice_index *slot;      /* received entry k -> halo slot (after the cell sort) */
    sluice_index slot_capacity;
    uint64_t slot_valid_at;  /* grid.rebuilds when slot was computed */
    uint64_t arrived;        /* particles received from other ranks by migration */
    /* load balance by measured time (sluice_ranks_balance) */
    double busy_seconds;     /* this rank's time in the passes since the last balance */
    int64_t balance_step;    /* the step of the last balance */
    uint64_t balances;       /* slab boundaries moved so far (times) */
    char *buffer[2];         /* send and receive */
    size_t buffer_capacity[2];
} sluice_halo_lists;

#ifdef SLUICE_MPI
/* Splits the initial particles (every rank built all of them) into slabs of
 * equal counts and keeps this rank's. Fails (message in sim) when a slab
 * would be narrower than the halo width. */
int sluice_ranks_split(sluice_sim *sim);
/* Every ranks.every steps (scene), before the neighbour search: when the
 * ranks' work since the last balance (their measured time in the passes,
 * or their particle counts: ranks.balance) differs by more than
 * ranks.tolerance of the mean, moves the slab boundaries so that each
 * rank's share is equal (half the way, within the neighbouring slabs).
 * Returns 1 when they moved (the caller rebuilds: the migration moves the
 * particles), 0 when not, -1 on failure. Collective. */
int sluice_ranks_balance(sluice_sim *sim);
/* Before a rebuild: sends the particles that left the slab to the rank
 * that owns their x now. Collective. */
int sluice_ranks_migrate(sluice_sim *sim);
/* The grid's halo function (sluice_grid_halo_fn): sends copies of the
 * particles within the halo width of the slab's sides, receives the
 * neighbours' after the sorted particles. Collective. */
int sluice_ranks_collect_halo(void *sim, sluice_particles *particles, sluice_index *halo_count);
/* Refreshes every field of the halo from its owners. Collective. */
int sluice_ranks_refresh_halo(sluice_sim *sim);
void sluice_ranks_free(sluice_halo_lists *lists);
/* Every rank's own particles, in rank order, into `all` on rank 0 (a store
 * of the same columns, initialised here; left empty on the other ranks).
 * Collective. 0, or -1 (out of memory or MPI; on any rank, every rank). */
int sluice_ranks_gather(sluice_sim *sim, sluice_particles *all);
#else
static inline void sluice_ranks_free(sluice_halo_lists *lists) { (void)lists; }
#endif

#endif
