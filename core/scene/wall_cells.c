/* Cells with lists of wall elements (see wall_cells.h). */
#include "wall_cells.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void sluice_wall_cells_layout(sluice_wall_cells *grid, uint32_t dimensions,
                              const sluice_wall_geometry *const *walls, size_t wall_count,
                              const double lo[3], const double hi[3], double cell_size,
                              double work_per_cell, size_t max_cells, double max_work)
{
    memset(grid, 0, sizeof *grid);
    grid->dimensions = dimensions;
    grid->walls = walls;
    grid->wall_count = wall_count;
    for (;;) {
        double count = 1;
        for (uint32_t d = 0; d < dimensions; d++)
            count *= floor((hi[d] - lo[d]) / cell_size) + 1;
        if (count <= (double)max_cells && count * work_per_cell <= max_work)
            break;
        cell_size *= 1.25;
    }
    grid->cell_size = cell_size;
    grid->inverse_cell_size = 1.0 / cell_size;
    grid->cell_count = 1;
    for (uint32_t d = 0; d < 3; d++) {
        grid->lo[d] = d < dimensions ? lo[d] : 0;
        grid->cells[d] = d < dimensions ? (int64_t)floor((hi[d] - lo[d]) / cell_size) + 1 : 1;
        grid->cell_count *= (size_t)grid->cells[d];
    }
}

void sluice_wall_cells_free(sluice_wall_cells *grid)
{
    free(grid->candidate_begin);
    free(grid->candidate_wall);
    free(grid->candidate_element);
    grid->candidate_begin = grid->candidate_wall = grid->candidate_element = NULL;
    grid->candidate_count = 0;
    grid->cell_count = 0;
}

int sluice_wall_cells_fill(sluice_wall_cells *grid, sluice_wall_cells_list list, void *context)
{
    const size_t n = grid->cell_count;
    grid->candidate_begin = malloc((n + 1) * sizeof *grid->candidate_begin);
    if (!grid->candidate_begin) {
        sluice_wall_cells_free(grid);
        return -1;
    }
    /* first pass: the count per cell */
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t c = 0; c < n; c++)
        grid->candidate_begin[c + 1] = list(grid, c, context, NULL, NULL);
    grid->candidate_begin[0] = 0;
    uint64_t total = 0;
    for (size_t c = 0; c < n; c++) {
        total += grid->candidate_begin[c + 1];
        if (total > UINT32_MAX) {
            sluice_wall_cells_free(grid);
            return -1;
        }
        grid->candidate_begin[c + 1] = (uint32_t)total;
    }
    grid->candidate_count = (size_t)total;
    grid->candidate_wall = malloc((size_t)(total ? total : 1) * sizeof *grid->candidate_wall);
    grid->candidate_element =
        malloc((size_t)(total ? total : 1) * sizeof *grid->candidate_element);
    if (!grid->candidate_wall || !grid->candidate_element) {
        sluice_wall_cells_free(grid);
        return -1;
    }
    /* second pass: the candidates (cells with an empty list are skipped) */
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t c = 0; c < n; c++)
        if (grid->candidate_begin[c + 1] > grid->candidate_begin[c])
            list(grid, c, context, grid->candidate_wall + grid->candidate_begin[c],
                 grid->candidate_element + grid->candidate_begin[c]);
    return 0;
}

size_t sluice_wall_cells_locate(const sluice_wall_cells *grid, const sluice_real p[3])
{
    if (grid->cell_count == 0)
        return SIZE_MAX;
    size_t cell = 0, stride = 1;
    for (uint32_t d = 0; d < grid->dimensions; d++) {
        const double u = floor(((double)p[d] - grid->lo[d]) * grid->inverse_cell_size);
        if (!(u >= 0 && u < (double)grid->cells[d])) /* outside (or NaN) */
            return SIZE_MAX;
        cell += (size_t)u * stride;
        stride *= (size_t)grid->cells[d];
    }
    return cell;
}

void sluice_wall_cells_centre(const sluice_wall_cells *grid, size_t cell, sluice_real centre[3])
{
    centre[0] = centre[1] = centre[2] = 0;
    size_t rest = cell;
    for (uint32_t d = 0; d < grid->dimensions; d++) {
        const size_t k = rest % (size_t)grid->cells[d];
        rest /= (size_t)grid->cells[d];
        centre[d] = (sluice_real)(grid->lo[d] + ((double)k + 0.5) * grid->cell_size);
    }
}

double sluice_wall_cells_half_diagonal(const sluice_wall_cells *grid)
{
    return 0.5 * grid->cell_size * sqrt((double)grid->dimensions);
}

uint32_t sluice_wall_cells_near_elements(const sluice_wall_cells *grid, const sluice_real centre[3],
                                         double nearest, uint32_t *wall_out, uint32_t *element_out)
{
    const double r = sluice_wall_cells_half_diagonal(grid);
    /* a rounding margin: the element distances are computed in sluice_real */
    const double scale = fabs((double)centre[0]) + fabs((double)centre[1]) +
                         fabs((double)centre[2]) + nearest + r;
    const double limit = nearest + 2 * r + 1e-9 * scale;
    return sluice_walls_elements_within(grid->walls, grid->wall_count, centre, limit, wall_out,
                                        element_out);
}
