/* A grid of cells over a box, each cell with a list of wall elements: the
 * structure the watchdog's wall check (wall_watch.h) and api->walls->wall_distance
 * (wall_distance.h) both stand on.
 *
 * A cell's list holds the elements that can be nearest to some point of the
 * cell: those within dmin + 2 r of its centre, dmin the centre's distance to
 * the nearest element and r the cell's half-diagonal (the nearest element
 * e* of a point p of the cell has d(c, e*) <= d(p, e*) + r <= d(p, e_c) + r
 * <= dmin + 2 r). So a query over the list gives the query over every
 * element exactly. The lists are kept in one array (by cell, then wall,
 * then element) with a start per cell.
 *
 * Pure data built from the fixed wall geometry; read-only during the run
 * (thread-safe). */
#ifndef SLUICE_WALL_CELLS_H
#define SLUICE_WALL_CELLS_H

#include <stddef.h>
#include <stdint.h>

#include "geometry.h"

typedef struct sluice_wall_cells {
    uint32_t dimensions;
    size_t wall_count;
    const sluice_wall_geometry *const *walls; /* not owned */
    double lo[3], cell_size, inverse_cell_size;
    int64_t cells[3];
    size_t cell_count;           /* 0: no cells, every query asks every element */
    uint32_t *candidate_begin;   /* per cell + 1: range in the candidates */
    uint32_t *candidate_wall;    /* candidates: wall index ... */
    uint32_t *candidate_element; /* ... and element, sorted by wall then element */
    size_t candidate_count;
} sluice_wall_cells;

/* Lays the cells over [lo, hi]: cells of `cell_size`, enlarged by steps of
 * 1.25 until there are at most `max_cells` and cells x `work_per_cell` is at
 * most `max_work`. No lists yet (sluice_wall_cells_fill). */
void sluice_wall_cells_layout(sluice_wall_cells *grid, uint32_t dimensions,
                              const sluice_wall_geometry *const *walls, size_t wall_count,
                              const double lo[3], const double hi[3], double cell_size,
                              double work_per_cell, size_t max_cells, double max_work);

/* One cell's list: its count, and when wall_out is not NULL the candidates
 * themselves (by wall, then element). */
typedef uint32_t (*sluice_wall_cells_list)(const sluice_wall_cells *grid, size_t cell,
                                           void *context, uint32_t *wall_out,
                                           uint32_t *element_out);

/* Builds the lists in two passes over the cells (counts, then candidates),
 * OpenMP across cells. Returns 0, or -1 (out of memory, or more than 2^32
 * candidates): the lists are then freed and cell_count is 0. */
int sluice_wall_cells_fill(sluice_wall_cells *grid, sluice_wall_cells_list list, void *context);

void sluice_wall_cells_free(sluice_wall_cells *grid);

/* The cell holding p, or SIZE_MAX when p is outside the cells (or NaN, or
 * there are no cells). */
size_t sluice_wall_cells_locate(const sluice_wall_cells *grid, const sluice_real p[3]);

/* The centre of a cell; its half-diagonal. */
void sluice_wall_cells_centre(const sluice_wall_cells *grid, size_t cell, sluice_real centre[3]);
double sluice_wall_cells_half_diagonal(const sluice_wall_cells *grid);

/* The elements that can be nearest to some point of the cell centred at
 * `centre`, whose nearest element is `nearest` away (the rule above, with a
 * margin for the rounding of the element distances): the list function of
 * both users. */
uint32_t sluice_wall_cells_near_elements(const sluice_wall_cells *grid, const sluice_real centre[3],
                                         double nearest, uint32_t *wall_out,
                                         uint32_t *element_out);

#endif
