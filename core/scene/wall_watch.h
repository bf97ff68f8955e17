/* The watchdog's wall check: which fluid particles have gone through a wall.
 *
 * A particle is "behind" a wall when its signed distance to the nearest wall
 * of the scene (the rule of api->walls->wall_nearest: the wall at the smallest
 * unsigned distance, its sign from the pseudo-normal of the closest feature;
 * points past an open end of a wall are never behind) is below zero. Asking
 * every wall element for every particle after every step would cost a
 * noticeable part of a step, so the domain is cut once into cells, classed
 * from the fixed geometry:
 *   in front: every point of the cell is on the fluid side, farther than the
 *             allowed depth from every wall: nothing to compute;
 *   behind:   every point of the cell is behind a wall, deeper than the
 *             allowed depth: any fluid particle there has gone through;
 *   near:     the rest, each with the list of elements that can be nearest
 *             to some point of the cell (wall_cells.h): the query over this
 *             list gives the full query's result exactly.
 * Pure data built from the scene; read-only during the run (thread-safe). */
#ifndef SLUICE_WALL_WATCH_H
#define SLUICE_WALL_WATCH_H

#include <stddef.h>
#include <stdint.h>

#include "wall_cells.h"

typedef struct sluice_wall_watch {
    sluice_wall_cells cells; /* the near cells' lists (the others' are empty) */
    uint8_t *state;          /* per cell: SLUICE_WALL_CELL_* */
} sluice_wall_watch;

enum { SLUICE_WALL_CELL_FRONT = 0, SLUICE_WALL_CELL_NEAR = 1, SLUICE_WALL_CELL_BEHIND = 2 };

/* Builds the cells over the box [lo, hi] (the domain) for the walls, with
 * cells of about `cell_size` (enlarged when the domain would need too many,
 * or the classing would cost too much) and the allowed depth `depth` (m,
 * > 0). walls[w] must outlive the watch. Returns 0, or -1 (out of memory). */
int sluice_wall_watch_init(sluice_wall_watch *watch, uint32_t dimensions,
                           const sluice_wall_geometry *const *walls, size_t wall_count,
                           const double lo[3], const double hi[3], double cell_size,
                           double depth);
void sluice_wall_watch_free(sluice_wall_watch *watch);
/* The bytes sluice_wall_watch_init will take for its cells (their class
 * and candidate range; the candidates near the walls are not counted). */
double sluice_wall_watch_bytes(uint32_t dimensions, const sluice_wall_geometry *const *walls,
                               size_t wall_count, const double lo[3], const double hi[3],
                               double cell_size);

/* The signed distance of p to the nearest wall, as api->walls->wall_nearest computes
 * it (exactly: the same value), when p is in a near or behind cell; +HUGE_VAL
 * in a front cell (farther than `depth` on the fluid side) and for points past
 * an open end (*beyond_end = 1). *wall and *element name the nearest element
 * when one was looked at (else UINT32_MAX). */
double sluice_wall_watch_distance(const sluice_wall_watch *watch, const sluice_real p[3],
                                  int *beyond_end, uint32_t *wall, uint32_t *element);

/* The same value by asking every element of every wall (for tests and for
 * points outside the watched box). */
double sluice_wall_watch_distance_full(const sluice_wall_watch *watch, const sluice_real p[3],
                                       int *beyond_end, uint32_t *wall, uint32_t *element);

#endif
