/* The distance from a point to the nearest wall of the scene (api->
 * wall_distance: the mixing length's and the wall functions' y, asked for
 * every fluid particle at every evaluation).
 *
 * Asking every element of every wall costs as many segment (triangle)
 * distances as the scene has elements: hundreds on a stepped chute. The
 * index cuts the box of the domain and the walls into cells (about a
 * kernel support wide) and keeps, per cell, the elements that can be
 * nearest to some point of it (wall_cells.h: the watchdog's near cells
 * have the same lists, wall_watch.h). A query looks at its cell's list
 * only. The answer is the minimum of the same element distances as asking
 * every element, so it is the same number, bit for bit; points outside the
 * box ask every element.
 *
 * Pure data built from the fixed wall geometry; read-only during the run
 * (thread-safe). */
#ifndef SLUICE_WALL_DISTANCE_H
#define SLUICE_WALL_DISTANCE_H

#include <stddef.h>
#include <stdint.h>

#include "wall_cells.h"

typedef struct sluice_wall_distance_index {
    sluice_wall_cells cells; /* a list for every cell of the box */
} sluice_wall_distance_index;

/* Builds the index over the box [lo, hi] (the domain; widened to hold the
 * walls) with cells of about `cell_size` (m, > 0; enlarged when the box
 * would need more than 4 M cells or the build too much work). walls[w]
 * must outlive the index. Returns 0, or -1 (out of memory: the index is
 * then without cells, and every query asks every element). */
int sluice_wall_distance_init(sluice_wall_distance_index *index, uint32_t dimensions,
                              const sluice_wall_geometry *const *walls, size_t wall_count,
                              const double lo[3], const double hi[3], double cell_size);
void sluice_wall_distance_free(sluice_wall_distance_index *index);

/* The unsigned distance from p to the nearest element of any wall (m);
 * HUGE_VAL without walls. */
double sluice_wall_distance(const sluice_wall_distance_index *index, const sluice_real p[3]);

/* The same by asking every element of every wall (for tests, and for points
 * outside the index's box). */
double sluice_wall_distance_full(const sluice_wall_distance_index *index, const sluice_real p[3]);

#endif
