/* The distance from a point to the nearest wall of the scene (api->
 * wall_distance: the mixing length's and the wall functions' y, asked for
 * every fluid particle at every evaluation).
 *
 * Asking every element of every wall costs as many segment (triangle)
 * distances as the scene has elements: hundreds on a stepped chute. The
 * index registers each element in the cells of a uniform grid that its
 * bounding box meets, and a query looks at the cells in square (cube) shells
 * of growing Chebyshev radius r around the point's cell: once the nearest
 * element found so far is no farther than r cell sizes, no element in a cell
 * outside the shells searched can be nearer (its nearest point lies in a
 * cell it is registered in, at least r cell sizes away). The answer is the
 * minimum of the same element distances as asking every element, so it is
 * the same number, bit for bit.
 *
 * Pure data built from the fixed wall geometry; read-only during the run
 * (thread-safe). */
#ifndef SLUICE_WALL_DISTANCE_H
#define SLUICE_WALL_DISTANCE_H

#include <stddef.h>
#include <stdint.h>

#include "geometry.h"

typedef struct sluice_wall_distance_index {
    uint32_t dimensions;
    size_t wall_count;
    const sluice_wall_geometry *const *walls; /* not owned */
    double lo[3], cell_size, inverse_cell_size;
    int64_t cells[3];
    size_t cell_count;
    uint32_t *entry_begin;   /* per cell + 1: range in the entries */
    uint32_t *entry_wall;    /* entries: wall index ... */
    uint32_t *entry_element; /* ... and element */
    size_t entry_count;
} sluice_wall_distance_index;

/* Builds the index for the walls with cells of about `cell_size` (m, > 0;
 * enlarged when the walls' extent would need more than about 16 cells per
 * element or 4 M cells). walls[w] must outlive the index. Returns 0, or -1
 * (out of memory). */
int sluice_wall_distance_init(sluice_wall_distance_index *index, uint32_t dimensions,
                              const sluice_wall_geometry *const *walls, size_t wall_count,
                              double cell_size);
void sluice_wall_distance_free(sluice_wall_distance_index *index);

/* The unsigned distance from p to the nearest element of any wall (m);
 * HUGE_VAL without walls. */
double sluice_wall_distance(const sluice_wall_distance_index *index, const sluice_real p[3]);

/* The same by asking every element of every wall (for tests). */
double sluice_wall_distance_full(const sluice_wall_distance_index *index, const sluice_real p[3]);

#endif
