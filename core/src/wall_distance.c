/* The nearest-wall distance index (see wall_distance.h). */
#include "wall_distance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Cells at most: about this many per element, and never more than this. */
#define INDEX_CELLS_PER_ELEMENT 16.0
#define INDEX_MAX_CELLS ((double)((size_t)4 << 20))

double sluice_wall_distance_full(const sluice_wall_distance_index *index, const sluice_real p[3])
{
    double best = HUGE_VAL;
    for (size_t w = 0; w < index->wall_count; w++)
        for (uint32_t e = 0; e < index->walls[w]->element_count; e++) {
            const double d = (double)sluice_wall_element_distance(index->walls[w], e, p);
            if (d < best)
                best = d;
        }
    return best;
}

void sluice_wall_distance_free(sluice_wall_distance_index *index)
{
    free(index->entry_begin);
    free(index->entry_wall);
    free(index->entry_element);
    memset(index, 0, sizeof *index);
}

/* The bounding box of element e of wall g. */
static void element_box(const sluice_wall_geometry *g, uint32_t e, double lo[3], double hi[3])
{
    const size_t corners = g->dimensions == 2 ? 2 : 3;
    const sluice_real *v = g->points + 3 * corners * (size_t)e;
    for (int d = 0; d < 3; d++) {
        lo[d] = hi[d] = (double)v[d];
        for (size_t j = 1; j < corners; j++) {
            const double x = (double)v[3 * j + (size_t)d];
            lo[d] = fmin(lo[d], x);
            hi[d] = fmax(hi[d], x);
        }
    }
}

/* The cell of coordinate x along an axis, clamped to the grid. */
static int64_t clamped_cell(double x, double lo, double inverse, int64_t cells)
{
    const double u = floor((x - lo) * inverse);
    if (!(u >= 0))
        return 0;
    if (u >= (double)cells)
        return cells - 1;
    return (int64_t)u;
}

/* The cells [first, last] along each axis that the box [lo, hi] meets. */
static void box_cells(const sluice_wall_distance_index *index, const double lo[3],
                      const double hi[3], int64_t first[3], int64_t last[3])
{
    for (uint32_t d = 0; d < 3; d++) {
        if (d >= index->dimensions) {
            first[d] = last[d] = 0;
            continue;
        }
        first[d] = clamped_cell(lo[d], index->lo[d], index->inverse_cell_size, index->cells[d]);
        last[d] = clamped_cell(hi[d], index->lo[d], index->inverse_cell_size, index->cells[d]);
    }
}

int sluice_wall_distance_init(sluice_wall_distance_index *index, uint32_t dimensions,
                              const sluice_wall_geometry *const *walls, size_t wall_count,
                              double cell_size)
{
    memset(index, 0, sizeof *index);
    index->dimensions = dimensions;
    index->walls = walls;
    index->wall_count = wall_count;
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    double elements = 0;
    for (size_t w = 0; w < wall_count; w++)
        for (uint32_t e = 0; e < walls[w]->element_count; e++) {
            double a[3], b[3];
            element_box(walls[w], e, a, b);
            for (int d = 0; d < 3; d++) {
                lo[d] = fmin(lo[d], a[d]);
                hi[d] = fmax(hi[d], b[d]);
            }
            elements++;
        }
    if (elements == 0 || !(cell_size > 0))
        return 0; /* no walls: every query is HUGE_VAL (cell_count 0) */
    /* a grid over the walls' bounding box: points outside it start from
     * the nearest cell */
    const double budget = fmin(INDEX_MAX_CELLS, fmax(64.0, INDEX_CELLS_PER_ELEMENT * elements));
    for (;;) {
        double count = 1;
        for (uint32_t d = 0; d < dimensions; d++)
            count *= floor((hi[d] - lo[d]) / cell_size) + 1;
        if (count <= budget)
            break;
        cell_size *= 1.25;
    }
    index->cell_size = cell_size;
    index->inverse_cell_size = 1.0 / cell_size;
    index->cell_count = 1;
    for (uint32_t d = 0; d < 3; d++) {
        index->lo[d] = d < dimensions ? lo[d] : 0;
        index->cells[d] = d < dimensions ? (int64_t)floor((hi[d] - lo[d]) / cell_size) + 1 : 1;
        index->cell_count *= (size_t)index->cells[d];
    }
    const size_t n = index->cell_count;
    index->entry_begin = calloc(n + 1, sizeof *index->entry_begin);
    if (!index->entry_begin) {
        sluice_wall_distance_free(index);
        return -1;
    }
    /* two passes over the elements: the count per cell, then the entries */
    uint64_t total = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t w = 0; w < wall_count; w++)
            for (uint32_t e = 0; e < walls[w]->element_count; e++) {
                double a[3], b[3];
                int64_t first[3], last[3];
                element_box(walls[w], e, a, b);
                box_cells(index, a, b, first, last);
                for (int64_t k = first[2]; k <= last[2]; k++)
                    for (int64_t j = first[1]; j <= last[1]; j++)
                        for (int64_t i = first[0]; i <= last[0]; i++) {
                            const size_t c = (size_t)((k * index->cells[1] + j) *
                                                          index->cells[0] + i);
                            if (pass == 0) {
                                index->entry_begin[c + 1]++;
                                total++;
                            } else {
                                const uint32_t at = index->entry_begin[c]++;
                                index->entry_wall[at] = (uint32_t)w;
                                index->entry_element[at] = e;
                            }
                        }
            }
        if (pass == 0) {
            if (total > UINT32_MAX) {
                sluice_wall_distance_free(index);
                return -1;
            }
            for (size_t c = 0; c < n; c++)
                index->entry_begin[c + 1] += index->entry_begin[c];
            index->entry_count = (size_t)total;
            index->entry_wall = malloc((size_t)(total ? total : 1) * sizeof *index->entry_wall);
            index->entry_element =
                malloc((size_t)(total ? total : 1) * sizeof *index->entry_element);
            if (!index->entry_wall || !index->entry_element) {
                sluice_wall_distance_free(index);
                return -1;
            }
        }
    }
    /* the fill advanced each cell's begin to the next cell's: shift back */
    for (size_t c = n; c > 0; c--)
        index->entry_begin[c] = index->entry_begin[c - 1];
    index->entry_begin[0] = 0;
    return 0;
}

/* The nearest of the elements registered in cell (i, j, k), if nearer than
 * *best. */
static void look_in_cell(const sluice_wall_distance_index *index, int64_t i, int64_t j, int64_t k,
                         const sluice_real p[3], double *best)
{
    const size_t c = (size_t)((k * index->cells[1] + j) * index->cells[0] + i);
    for (uint32_t at = index->entry_begin[c]; at < index->entry_begin[c + 1]; at++) {
        const double d = (double)sluice_wall_element_distance(index->walls[index->entry_wall[at]],
                                                              index->entry_element[at], p);
        if (d < *best)
            *best = d;
    }
}

double sluice_wall_distance(const sluice_wall_distance_index *index, const sluice_real p[3])
{
    if (index->cell_count == 0)
        return HUGE_VAL;
    int64_t centre[3] = {0, 0, 0}, widest = 0;
    for (uint32_t d = 0; d < index->dimensions; d++) {
        centre[d] = clamped_cell((double)p[d], index->lo[d], index->inverse_cell_size,
                                 index->cells[d]);
        if (index->cells[d] > widest)
            widest = index->cells[d];
    }
    double best = HUGE_VAL;
    /* shells of Chebyshev radius r around the point's cell (clamped to the
     * grid); after shell r every cell not yet looked at is at least r cell
     * sizes from p along some axis */
    for (int64_t r = 0; r < widest; r++) {
        int64_t first[3], last[3];
        for (uint32_t d = 0; d < 3; d++) {
            const int64_t reach = d < index->dimensions ? r : 0;
            first[d] = centre[d] - reach < 0 ? 0 : centre[d] - reach;
            last[d] = centre[d] + reach >= index->cells[d] ? index->cells[d] - 1
                                                           : centre[d] + reach;
        }
        for (int64_t k = first[2]; k <= last[2]; k++) {
            const int on_k = index->dimensions == 3 && (k == centre[2] - r || k == centre[2] + r);
            for (int64_t j = first[1]; j <= last[1]; j++) {
                const int on_jk = on_k || j == centre[1] - r || j == centre[1] + r;
                if (on_jk) { /* the whole row lies on the shell */
                    for (int64_t i = first[0]; i <= last[0]; i++)
                        look_in_cell(index, i, j, k, p, &best);
                } else { /* only its two ends */
                    if (centre[0] - r >= 0)
                        look_in_cell(index, centre[0] - r, j, k, p, &best);
                    if (r > 0 && centre[0] + r < index->cells[0])
                        look_in_cell(index, centre[0] + r, j, k, p, &best);
                }
            }
        }
        if (best <= (double)r * index->cell_size)
            break;
    }
    return best;
}
