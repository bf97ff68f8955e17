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
    for (size_t w = 0; w < watch->wall_count; w++) {
        int beyond = 0;
        uint32_t e = UINT32_MAX;
        double d = (double)sluice_wall_signed_distance(watch->walls[w], p, &beyond, &e);
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
    for (uint32_t k = begin; k < end;) {
        uint32_t w = watch->candidate_wall[k], last = k;
        while (last < end && watch->candidate_wall[last] == w)
            last++;
        int beyond = 0;
        uint32_t e = UINT32_MAX;
        double d = (double)sluice_wall_signed_distance_among(
            watch->walls[w], p, watch->candidate_element + k, last - k, &beyond, &e);
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

static int64_t cell_index(double x, double lo, double inverse, int64_t cells)
{
    double u = floor((x - lo) * inverse);
    if (!(u >= 0))
        return -1;
    if (u >= (double)cells)
        return -1;
    return (int64_t)u;
}

double sluice_wall_watch_distance(const sluice_wall_watch *watch, const sluice_real p[3],
                                  int *beyond_end, uint32_t *wall, uint32_t *element)
{
    *beyond_end = 0;
    *wall = *element = UINT32_MAX;
    if (watch->wall_count == 0)
        return HUGE_VAL;
    size_t cell = 0, stride = 1;
    for (uint32_t d = 0; d < watch->dimensions; d++) {
        int64_t k = cell_index((double)p[d], watch->lo[d], watch->inverse_cell_size,
                               watch->cells[d]);
        if (k < 0) /* outside the watched box: ask every element */
            return sluice_wall_watch_distance_full(watch, p, beyond_end, wall, element);
        cell += (size_t)k * stride;
        stride *= (size_t)watch->cells[d];
    }
    switch (watch->state[cell]) {
    case SLUICE_WALL_CELL_FRONT:
        return HUGE_VAL;
    case SLUICE_WALL_CELL_BEHIND:
        return sluice_wall_watch_distance_full(watch, p, beyond_end, wall, element);
    default:
        return distance_among(watch, p, watch->candidate_begin[cell],
                              watch->candidate_begin[cell + 1], beyond_end, wall, element);
    }
}

void sluice_wall_watch_free(sluice_wall_watch *watch)
{
    free(watch->state);
    free(watch->candidate_begin);
    free(watch->candidate_wall);
    free(watch->candidate_element);
    memset(watch, 0, sizeof *watch);
}

/* The classing of one cell: its state and its candidates (count, and when
 * wall_out is not NULL the candidates themselves). */
static uint32_t class_cell(const sluice_wall_watch *watch, size_t cell, double depth,
                           uint8_t *state, uint32_t *wall_out, uint32_t *element_out)
{
    const uint32_t dims = watch->dimensions;
    sluice_real centre[3] = {0, 0, 0};
    size_t rest = cell;
    for (uint32_t d = 0; d < dims; d++) {
        size_t k = rest % (size_t)watch->cells[d];
        rest /= (size_t)watch->cells[d];
        centre[d] = (sluice_real)(watch->lo[d] + ((double)k + 0.5) * watch->cell_size);
    }
    const double r = 0.5 * watch->cell_size * sqrt((double)dims);
    const double dmin = sluice_walls_nearest_distance(watch->walls, watch->wall_count, centre);
    if (dmin > r + depth) {
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
                                     ((corner >> d & 1u) ? 0.5 : -0.5) * watch->cell_size);
            double t = sluice_wall_watch_distance_full(watch, q, &beyond, &w, &e);
            consistent = !beyond && t != HUGE_VAL && (t > 0) == (s > 0);
        }
        if (consistent) {
            *state = s > 0 ? SLUICE_WALL_CELL_FRONT : SLUICE_WALL_CELL_BEHIND;
            return 0;
        }
    }
    *state = SLUICE_WALL_CELL_NEAR;
    const double scale = fabs((double)centre[0]) + fabs((double)centre[1]) +
                         fabs((double)centre[2]) + dmin + r;
    const double limit = dmin + 2 * r + 1e-9 * scale;
    return sluice_walls_elements_within(watch->walls, watch->wall_count, centre, limit, wall_out,
                                        element_out);
}

int sluice_wall_watch_init(sluice_wall_watch *watch, uint32_t dimensions,
                           const sluice_wall_geometry *const *walls, size_t wall_count,
                           const double lo[3], const double hi[3], double cell_size,
                           double depth)
{
    memset(watch, 0, sizeof *watch);
    watch->dimensions = dimensions;
    watch->walls = walls;
    watch->wall_count = wall_count;
    if (wall_count == 0)
        return 0;
    double elements = 0;
    for (size_t w = 0; w < wall_count; w++)
        elements += walls[w]->element_count;
    /* the classing asks every element at the centre and, for far cells, at
     * the 2^d corners: keep cells x elements x (2^d + 2) within the budget */
    const double per_cell = elements * (double)((1u << dimensions) + 2);
    for (;;) {
        double count = 1;
        for (uint32_t d = 0; d < dimensions; d++)
            count *= ceil((hi[d] - lo[d]) / cell_size) + 1;
        if (count <= (double)WATCH_MAX_CELLS && count * per_cell <= WATCH_MAX_WORK)
            break;
        cell_size *= 1.25;
    }
    watch->cell_size = cell_size;
    watch->inverse_cell_size = 1.0 / cell_size;
    watch->cell_count = 1;
    for (uint32_t d = 0; d < dimensions; d++) {
        watch->lo[d] = lo[d];
        watch->cells[d] = (int64_t)ceil((hi[d] - lo[d]) / cell_size) + 1;
        watch->cell_count *= (size_t)watch->cells[d];
    }
    const size_t n = watch->cell_count;
    watch->state = malloc(n);
    watch->candidate_begin = malloc((n + 1) * sizeof *watch->candidate_begin);
    if (!watch->state || !watch->candidate_begin) {
        sluice_wall_watch_free(watch);
        return -1;
    }
    /* first pass: states and candidate counts */
    int overflow = 0;
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t c = 0; c < n; c++)
        watch->candidate_begin[c + 1] = class_cell(watch, c, depth, &watch->state[c], NULL, NULL);
    watch->candidate_begin[0] = 0;
    uint64_t total = 0;
    for (size_t c = 0; c < n; c++) {
        uint32_t k = watch->candidate_begin[c + 1];
        if (k > watch->largest_list)
            watch->largest_list = k;
        total += k;
        if (total > UINT32_MAX)
            overflow = 1;
        watch->candidate_begin[c + 1] = (uint32_t)total;
    }
    if (overflow) {
        sluice_wall_watch_free(watch);
        return -1;
    }
    watch->candidate_count = (size_t)total;
    watch->candidate_wall = malloc((total ? total : 1) * sizeof *watch->candidate_wall);
    watch->candidate_element = malloc((total ? total : 1) * sizeof *watch->candidate_element);
    if (!watch->candidate_wall || !watch->candidate_element) {
        sluice_wall_watch_free(watch);
        return -1;
    }
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t c = 0; c < n; c++)
        if (watch->state[c] == SLUICE_WALL_CELL_NEAR) {
            uint8_t state;
            class_cell(watch, c, depth, &state, watch->candidate_wall + watch->candidate_begin[c],
                       watch->candidate_element + watch->candidate_begin[c]);
        }
    return 0;
}
