/* The particle store: one aligned array per field component (structure of
 * arrays). Columns are allocated only for fields that loaded plugins declare. */
#ifndef SLUICE_PARTICLES_H
#define SLUICE_PARTICLES_H

#include <stddef.h>
#include <stdint.h>

#include "sluice/plugin.h"

#define SLUICE_ALIGNMENT 64

/* With OpenMP's passive wait policy (threads sleep at every barrier, as a
 * shared machine needs), loops over particles with little work per
 * particle (particle terms, integrator updates, time-step limits, checks,
 * reordering) run on one thread below this many items: waking the other
 * threads costs more than the loop (docs/performance.md, "Threads"). With
 * spinning threads they are parallel at any size, and the pair passes and
 * the neighbour list's build always are. */
#ifndef SLUICE_PARALLEL_MIN_ITEMS
#define SLUICE_PARALLEL_MIN_ITEMS 32768
#endif

typedef struct sluice_particles {
    sluice_index count, capacity;
    uint32_t column_count;
    void **columns;          /* column_count base pointers */
    uint8_t *element_size;   /* bytes per element of each column */
    void *scratch[4];        /* permutation scratch, one per element size class */
    sluice_index scratch_capacity[4];
    sluice_index parallel_min; /* reordering: on one thread below this many (0: never) */
} sluice_particles;

/* element_sizes: one of 1, 4, 8 per column. 0 or -1 on OOM. */
int sluice_particles_init(sluice_particles *p, uint32_t column_count, const uint8_t *element_sizes);
void sluice_particles_free(sluice_particles *p);
/* Makes room for at least `capacity` particles (keeps contents). */
int sluice_particles_reserve(sluice_particles *p, sluice_index capacity);
/* Appends n zeroed particles; *first receives the index of the first. */
int sluice_particles_append(sluice_particles *p, sluice_index n, sluice_index *first);
/* Reorders every column: new[i] = old[order[i]] for i < count. */
int sluice_particles_permute(sluice_particles *p, const sluice_index *order);
/* Removes the particles with remove[i] != 0, keeping the order of the rest. */
void sluice_particles_compact(sluice_particles *p, const uint8_t *remove);
/* Bytes of particle storage currently allocated (for the memory figures). */
size_t sluice_particles_bytes(const sluice_particles *p);

#endif
