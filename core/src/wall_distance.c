/* The nearest-wall distance index (see wall_distance.h). */
#include "wall_distance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Cells at most, and element-distance evaluations the build may take. */
#define INDEX_MAX_CELLS ((size_t)4 << 20)
#define INDEX_MAX_WORK 1.5e8

double sluice_wall_distance_full(const sluice_wall_distance_index *index, const sluice_real p[3])
{
    return sluice_walls_nearest_distance(index->walls, index->wall_count, p);
}

void sluice_wall_distance_free(sluice_wall_distance_index *index)
{
    free(index->candidate_begin);
    free(index->candidate_wall);
    free(index->candidate_element);
    memset(index, 0, sizeof *index);
}

double sluice_wall_distance(const sluice_wall_distance_index *index, const sluice_real p[3])
{
    if (index->cell_count == 0)
        return sluice_wall_distance_full(index, p);
    size_t cell = 0, stride = 1;
    for (uint32_t d = 0; d < index->dimensions; d++) {
        const double u = floor(((double)p[d] - index->lo[d]) * index->inverse_cell_size);
        if (!(u >= 0 && u < (double)index->cells[d])) /* outside the box (or NaN) */
            return sluice_wall_distance_full(index, p);
        cell += (size_t)u * stride;
        stride *= (size_t)index->cells[d];
    }
    double best = HUGE_VAL;
    for (uint32_t k = index->candidate_begin[cell]; k < index->candidate_begin[cell + 1]; k++) {
        const double d = (double)sluice_wall_element_distance(
            index->walls[index->candidate_wall[k]], index->candidate_element[k], p);
        if (d < best)
            best = d;
    }
    return best;
}

/* The candidates of one cell: their count, and when wall_out is not NULL the
 * candidates themselves (by wall, then element). */
static uint32_t cell_candidates(const sluice_wall_distance_index *index, size_t cell,
                                uint32_t *wall_out, uint32_t *element_out)
{
    const uint32_t dims = index->dimensions;
    sluice_real centre[3] = {0, 0, 0};
    size_t rest = cell;
    for (uint32_t d = 0; d < dims; d++) {
        const size_t k = rest % (size_t)index->cells[d];
        rest /= (size_t)index->cells[d];
        centre[d] = (sluice_real)(index->lo[d] + ((double)k + 0.5) * index->cell_size);
    }
    const double r = 0.5 * index->cell_size * sqrt((double)dims);
    const double dmin = sluice_wall_distance_full(index, centre);
    /* a rounding margin: the element distances are computed in sluice_real */
    const double scale = fabs((double)centre[0]) + fabs((double)centre[1]) +
                         fabs((double)centre[2]) + dmin + r;
    const double limit = dmin + 2 * r + 1e-9 * scale;
    return sluice_walls_elements_within(index->walls, index->wall_count, centre, limit, wall_out,
                                        element_out);
}

int sluice_wall_distance_init(sluice_wall_distance_index *index, uint32_t dimensions,
                              const sluice_wall_geometry *const *walls, size_t wall_count,
                              const double lo[3], const double hi[3], double cell_size)
{
    memset(index, 0, sizeof *index);
    index->dimensions = dimensions;
    index->walls = walls;
    index->wall_count = wall_count;
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
    /* each cell asks every element twice (its nearest, its list): keep
     * cells x elements within the budget */
    for (;;) {
        double count = 1;
        for (uint32_t d = 0; d < dimensions; d++)
            count *= floor((box_hi[d] - box_lo[d]) / cell_size) + 1;
        if (count <= (double)INDEX_MAX_CELLS && count * 2 * elements <= INDEX_MAX_WORK)
            break;
        cell_size *= 1.25;
    }
    index->cell_size = cell_size;
    index->inverse_cell_size = 1.0 / cell_size;
    index->cell_count = 1;
    for (uint32_t d = 0; d < 3; d++) {
        index->lo[d] = d < dimensions ? box_lo[d] : 0;
        index->cells[d] =
            d < dimensions ? (int64_t)floor((box_hi[d] - box_lo[d]) / cell_size) + 1 : 1;
        index->cell_count *= (size_t)index->cells[d];
    }
    const size_t n = index->cell_count;
    index->candidate_begin = malloc((n + 1) * sizeof *index->candidate_begin);
    if (!index->candidate_begin) {
        sluice_wall_distance_free(index);
        return -1;
    }
    /* first pass: the count per cell */
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t c = 0; c < n; c++)
        index->candidate_begin[c + 1] = cell_candidates(index, c, NULL, NULL);
    index->candidate_begin[0] = 0;
    uint64_t total = 0;
    for (size_t c = 0; c < n; c++) {
        total += index->candidate_begin[c + 1];
        if (total > UINT32_MAX) {
            sluice_wall_distance_free(index);
            return -1;
        }
        index->candidate_begin[c + 1] = (uint32_t)total;
    }
    index->candidate_count = (size_t)total;
    index->candidate_wall = malloc((size_t)(total ? total : 1) * sizeof *index->candidate_wall);
    index->candidate_element =
        malloc((size_t)(total ? total : 1) * sizeof *index->candidate_element);
    if (!index->candidate_wall || !index->candidate_element) {
        sluice_wall_distance_free(index);
        return -1;
    }
    /* second pass: the candidates */
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t c = 0; c < n; c++)
        cell_candidates(index, c, index->candidate_wall + index->candidate_begin[c],
                        index->candidate_element + index->candidate_begin[c]);
    return 0;
}
