/* The nearest-wall distance index (see wall_distance.h). */
#include "wall_distance.h"

#include <math.h>
#include <string.h>

/* Cells at most, and element-distance evaluations the build may take. */
#define INDEX_MAX_CELLS ((size_t)4 << 20)
#define INDEX_MAX_WORK 1.5e8

double sluice_wall_distance_full(const sluice_wall_distance_index *index, const sluice_real p[3])
{
    return sluice_walls_nearest_distance(index->cells.walls, index->cells.wall_count, p);
}

void sluice_wall_distance_free(sluice_wall_distance_index *index)
{
    sluice_wall_cells_free(&index->cells);
}

double sluice_wall_distance(const sluice_wall_distance_index *index, const sluice_real p[3])
{
    const sluice_wall_cells *grid = &index->cells;
    const size_t cell = sluice_wall_cells_locate(grid, p);
    if (cell == SIZE_MAX) /* no cells, or outside the box */
        return sluice_wall_distance_full(index, p);
    double best = HUGE_VAL;
    for (uint32_t k = grid->candidate_begin[cell]; k < grid->candidate_begin[cell + 1]; k++) {
        const double d = (double)sluice_wall_element_distance(
            grid->walls[grid->candidate_wall[k]], grid->candidate_element[k], p);
        if (d < best)
            best = d;
    }
    return best;
}

/* A cell's list: every element that can be nearest to a point of it. */
static uint32_t cell_candidates(const sluice_wall_cells *grid, size_t cell, void *context,
                                uint32_t *wall_out, uint32_t *element_out)
{
    (void)context;
    sluice_real centre[3];
    sluice_wall_cells_centre(grid, cell, centre);
    const double nearest = sluice_walls_nearest_distance(grid->walls, grid->wall_count, centre);
    return sluice_wall_cells_near_elements(grid, centre, nearest, wall_out, element_out);
}

int sluice_wall_distance_init(sluice_wall_distance_index *index, uint32_t dimensions,
                              const sluice_wall_geometry *const *walls, size_t wall_count,
                              const double lo[3], const double hi[3], double cell_size)
{
    sluice_wall_cells *grid = &index->cells;
    memset(grid, 0, sizeof *grid);
    grid->dimensions = dimensions;
    grid->walls = walls;
    grid->wall_count = wall_count;
    /* the box: the domain's, widened to hold every wall element */
    double box_lo[3], box_hi[3], elements = 0;
    for (int d = 0; d < 3; d++) {
        box_lo[d] = lo[d];
        box_hi[d] = hi[d];
    }
    for (size_t w = 0; w < wall_count; w++) {
        const size_t points = (size_t)walls[w]->element_count * (dimensions == 3 ? 3 : 2);
        for (size_t q = 0; q < points; q++)
            for (uint32_t d = 0; d < dimensions; d++) {
                const double x = (double)walls[w]->points[3 * q + d];
                box_lo[d] = fmin(box_lo[d], x);
                box_hi[d] = fmax(box_hi[d], x);
            }
        elements += walls[w]->element_count;
    }
    if (elements == 0 || !(cell_size > 0))
        return 0; /* no cells: every query asks every element (none: HUGE_VAL) */
    for (uint32_t d = 0; d < dimensions; d++)
        if (!isfinite(box_lo[d]) || !isfinite(box_hi[d]) || !(box_hi[d] >= box_lo[d]))
            return 0;
    /* each cell asks every element twice (its nearest, its list) */
    sluice_wall_cells_layout(grid, dimensions, walls, wall_count, box_lo, box_hi, cell_size,
                             2 * elements, INDEX_MAX_CELLS, INDEX_MAX_WORK);
    return sluice_wall_cells_fill(grid, cell_candidates, NULL);
}
