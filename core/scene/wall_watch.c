/* The watchdog's wall check (see wall_watch.h). */
#include "wall_watch.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Cells at most, and element-distance evaluations the classing may take. */
#define WATCH_MAX_CELLS ((size_t)4 << 20)
#define WATCH_MAX_WORK 1.5e8

double sluice_wall_watch_distance_full(const sluice_wall_watch *watch, const sluice_real p[3],
                                       int *beyond_end, uint32_t *wall, uint32_t *element)
{
    double best = HUGE_VAL, signed_best = HUGE_VAL;
    int beyond_best = 0;
    uint32_t best_wall = UINT32_MAX, best_element = UINT32_MAX;
    for (size_t w = 0; w < watch->cells.wall_count; w++) {
        int beyond = 0;
        uint32_t e = UINT32_MAX;
        double d = (double)sluice_wall_signed_distance(watch->cells.walls[w], p, &beyond, &e);
        if (e != UINT32_MAX && fabs(d) < best) {
            best = fabs(d);
            signed_best = d;
            beyond_best = beyond;
            best_wall = (uint32_t)w;
            best_element = e;
        }
    }
    *beyond_end = beyond_best;
    *wall = best_wall;
    *element = best_element;
    return beyond_best ? HUGE_VAL : signed_best;
}

/* The query over the candidates [begin, end) (grouped by wall). */
static double distance_among(const sluice_wall_watch *watch, const sluice_real p[3], uint32_t begin,
                             uint32_t end, int *beyond_end, uint32_t *wall, uint32_t *element)
{
    double best = HUGE_VAL, signed_best = HUGE_VAL;
    int beyond_best = 0;
    uint32_t best_wall = UINT32_MAX, best_element = UINT32_MAX;
    const sluice_wall_cells *grid = &watch->cells;
    for (uint32_t k = begin; k < end;) {
        uint32_t w = grid->candidate_wall[k], last = k;
        while (last < end && grid->candidate_wall[last] == w)
            last++;
        int beyond = 0;
        uint32_t e = UINT32_MAX;
        double d = (double)sluice_wall_signed_distance_among(
            grid->walls[w], p, grid->candidate_element + k, last - k, &beyond, &e);
        if (e != UINT32_MAX && fabs(d) < best) {
            best = fabs(d);
            signed_best = d;
            beyond_best = beyond;
            best_wall = w;
            best_element = e;
        }
        k = last;
    }
    *beyond_end = beyond_best;
    *wall = best_wall;
    *element = best_element;
    return beyond_best ? HUGE_VAL : signed_best;
}

double sluice_wall_watch_distance(const sluice_wall_watch *watch, const sluice_real p[3],
                                  int *beyond_end, uint32_t *wall, uint32_t *element)
{
    *beyond_end = 0;
    *wall = *element = UINT32_MAX;
    if (watch->cells.wall_count == 0)
        return HUGE_VAL;
    const size_t cell = sluice_wall_cells_locate(&watch->cells, p);
    if (cell == SIZE_MAX) /* outside the watched box: ask every element */
        return sluice_wall_watch_distance_full(watch, p, beyond_end, wall, element);
    switch (watch->state[cell]) {
    case SLUICE_WALL_CELL_FRONT:
        return HUGE_VAL;
    case SLUICE_WALL_CELL_BEHIND:
        return sluice_wall_watch_distance_full(watch, p, beyond_end, wall, element);
    default:
        return distance_among(watch, p, watch->cells.candidate_begin[cell],
                              watch->cells.candidate_begin[cell + 1], beyond_end, wall, element);
    }
}

void sluice_wall_watch_free(sluice_wall_watch *watch)
{
    sluice_wall_cells_free(&watch->cells);
    free(watch->state);
    watch->state = NULL;
}

/* The classing of one cell, the list function of sluice_wall_cells_fill:
 * in the first pass (wall_out NULL) its state, in both its candidates (a
 * near cell's; none for the others). */
typedef struct {
    sluice_wall_watch *watch;
    double depth;
} class_context;

static uint32_t class_cell(const sluice_wall_cells *grid, size_t cell, void *context,
                           uint32_t *wall_out, uint32_t *element_out)
{
    const class_context *cx = context;
    const sluice_wall_watch *watch = cx->watch;
    const uint32_t dims = grid->dimensions;
    sluice_real centre[3];
    sluice_wall_cells_centre(grid, cell, centre);
    if (wall_out) /* the second pass: only near cells have candidates */
        return sluice_wall_cells_near_elements(
            grid, centre, sluice_walls_nearest_distance(grid->walls, grid->wall_count, centre),
            wall_out, element_out);
    const double r = sluice_wall_cells_half_diagonal(grid);
    const double dmin = sluice_walls_nearest_distance(grid->walls, grid->wall_count, centre);
    uint8_t *state = &cx->watch->state[cell];
    if (dmin > r + cx->depth) {
        /* far from every wall: one side, if the centre and the corners agree
         * (a sign that flips without crossing a wall only happens past an open
         * end, or where two walls disagree: such a cell is looked at closely) */
        int beyond = 0;
        uint32_t w, e;
        double s = sluice_wall_watch_distance_full(watch, centre, &beyond, &w, &e);
        int consistent = !beyond && s != HUGE_VAL;
        for (uint32_t corner = 0; consistent && corner < (1u << dims); corner++) {
            sluice_real q[3] = {centre[0], centre[1], centre[2]};
            for (uint32_t d = 0; d < dims; d++)
                q[d] = (sluice_real)((double)centre[d] +
                                     ((corner >> d & 1u) ? 0.5 : -0.5) * grid->cell_size);
            double t = sluice_wall_watch_distance_full(watch, q, &beyond, &w, &e);
            consistent = !beyond && t != HUGE_VAL && (t > 0) == (s > 0);
        }
        if (consistent) {
            *state = s > 0 ? SLUICE_WALL_CELL_FRONT : SLUICE_WALL_CELL_BEHIND;
            return 0;
        }
    }
    *state = SLUICE_WALL_CELL_NEAR;
    return sluice_wall_cells_near_elements(grid, centre, dmin, NULL, NULL);
}

double sluice_wall_watch_bytes(uint32_t dimensions, const sluice_wall_geometry *const *walls,
                               size_t wall_count, const double lo[3], const double hi[3],
                               double cell_size)
{
    if (wall_count == 0)
        return 0;
    double elements = 0;
    for (size_t w = 0; w < wall_count; w++)
        elements += walls[w]->element_count;
    sluice_wall_cells cells;
    sluice_wall_cells_layout(&cells, dimensions, walls, wall_count, lo, hi, cell_size,
                             elements * (double)((1u << dimensions) + 2), WATCH_MAX_CELLS,
                             WATCH_MAX_WORK);
    /* a class and a candidate range per cell */
    return (double)cells.cell_count * (1.0 + sizeof *cells.candidate_begin);
}

int sluice_wall_watch_init(sluice_wall_watch *watch, uint32_t dimensions,
                           const sluice_wall_geometry *const *walls, size_t wall_count,
                           const double lo[3], const double hi[3], double cell_size,
                           double depth)
{
    memset(watch, 0, sizeof *watch);
    watch->cells.dimensions = dimensions;
    watch->cells.walls = walls;
    watch->cells.wall_count = wall_count;
    if (wall_count == 0)
        return 0;
    double elements = 0;
    for (size_t w = 0; w < wall_count; w++)
        elements += walls[w]->element_count;
    /* the classing asks every element at the centre and, for far cells, at
     * the 2^d corners: keep cells x elements x (2^d + 2) within the budget */
    sluice_wall_cells_layout(&watch->cells, dimensions, walls, wall_count, lo, hi, cell_size,
                             elements * (double)((1u << dimensions) + 2), WATCH_MAX_CELLS,
                             WATCH_MAX_WORK);
    watch->state = malloc(watch->cells.cell_count);
    class_context cx = {watch, depth};
    if (!watch->state || sluice_wall_cells_fill(&watch->cells, class_cell, &cx) != 0) {
        sluice_wall_watch_free(watch);
        return -1;
    }
    return 0;
}
