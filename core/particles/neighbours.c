#include "neighbours.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define MAX_CELLS ((size_t)1 << 30)

int sluice_grid_init(sluice_grid *grid, uint32_t dimensions, const double lo[3], const double hi[3],
                     const int periodic[3], sluice_real support, sluice_real skin,
                     const char **reason)
{
    memset(grid, 0, sizeof *grid);
    grid->dimensions = dimensions;
    grid->support = support;
    grid->skin = skin;
    grid->kind_column = -1;
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++)
        grid->list_kinds[k] = SLUICE_KINDS_ALL;
    double cutoff = (double)support + (double)skin;
    size_t count = 1;
    for (int d = 0; d < 3; d++) {
        if ((uint32_t)d >= dimensions) {
            grid->cells[d] = 1;
            grid->cell_size[d] = 1.0;
            grid->inverse_cell_size[d] = 1.0;
            continue;
        }
        grid->lo[d] = lo[d];
        grid->hi[d] = hi[d];
        grid->length[d] = hi[d] - lo[d];
        grid->periodic[d] = periodic[d];
        if (!(grid->length[d] > 0)) {
            *reason = "the domain has zero or negative size";
            return -1;
        }
        double n = periodic[d] ? floor(grid->length[d] / cutoff) : ceil(grid->length[d] / cutoff);
        if (n < 1)
            n = 1;
        if (periodic[d] && n < 3) {
            *reason = "a periodic direction must be at least 3 times the kernel support plus the "
                      "neighbour skin long";
            return -1;
        }
        if (n > (double)MAX_CELLS) {
            *reason = "the domain is too large for the cell grid (more than 2^30 cells)";
            return -1;
        }
        grid->cells[d] = (int64_t)n;
        grid->cell_size[d] = periodic[d] ? grid->length[d] / n : cutoff;
        grid->inverse_cell_size[d] = 1.0 / grid->cell_size[d];
        count *= (size_t)n;
        if (count > MAX_CELLS) {
            *reason = "the domain is too large for the cell grid (more than 2^30 cells)";
            return -1;
        }
    }
    grid->cell_count = count;
    grid->cell_start = calloc(count + 1, sizeof *grid->cell_start);
    grid->cell_kinds = calloc(count, 1);
    grid->threads = omp_get_max_threads();
    grid->thread_counts = calloc((size_t)grid->threads + 1, sizeof *grid->thread_counts);
    if (!grid->cell_start || !grid->cell_kinds || !grid->thread_counts) {
        *reason = "out of memory";
        sluice_grid_free(grid);
        return -1;
    }
    return 0;
}

void sluice_grid_free(sluice_grid *grid)
{
    free(grid->cell_start);
    free(grid->cell_kinds);
    free(grid->order);
    free(grid->cell_of);
    for (int d = 0; d < 3; d++)
        free(grid->built[d]);
    free(grid->list_begin);
    free(grid->list);
    free(grid->thread_counts);
    free(grid->halo_start);
    free(grid->halo_order);
    for (int d = 0; d < 3; d++)
        free(grid->halo_built[d]);
    memset(grid, 0, sizeof *grid);
}

static inline double minimum_image(double dx, double length)
{
    return dx - length * nearbyint(dx / length);
}

int sluice_grid_needs_rebuild(const sluice_grid *grid, const sluice_view *view)
{
    if (!grid->valid || grid->count != view->count)
        return 1;
    double limit = 0.25 * (double)grid->skin * (double)grid->skin;
    double worst = 0;
    const uint32_t dims = grid->dimensions;
    sluice_index n = view->count;
#pragma omp parallel for schedule(static) reduction(max : worst) if (n >= grid->parallel_min)
    for (sluice_index i = 0; i < n; i++) {
        double s = 0;
        for (uint32_t d = 0; d < dims; d++) {
            double dx = (double)view->position[d][i] - (double)grid->built[d][i];
            if (grid->periodic[d])
                dx = minimum_image(dx, grid->length[d]);
            s += dx * dx;
        }
        if (!(s <= limit)) /* also catches NaN */
            worst = s == s ? (s > worst ? s : worst) : INFINITY;
    }
    return worst > limit;
}

static int ensure_capacity(sluice_grid *grid, sluice_index n)
{
    if (n <= grid->capacity && grid->list_begin)
        return 0;
    sluice_index cap = grid->capacity ? grid->capacity : 1024;
    while (cap < n)
        cap = cap > UINT32_MAX / 2 ? n : cap * 2;
    sluice_index *order = malloc((size_t)cap * sizeof *order);
    uint32_t *cell_of = malloc((size_t)cap * sizeof *cell_of);
    sluice_index *begin = malloc(((size_t)cap + 1) * sizeof *begin);
    sluice_real *built[3] = {NULL, NULL, NULL};
    int ok = order && cell_of && begin;
    for (uint32_t d = 0; d < grid->dimensions && ok; d++) {
        built[d] = malloc((size_t)cap * sizeof *built[d]);
        ok = built[d] != NULL;
    }
    if (!ok) {
        free(order);
        free(cell_of);
        free(begin);
        for (int d = 0; d < 3; d++)
            free(built[d]);
        return -1;
    }
    free(grid->order);
    free(grid->cell_of);
    free(grid->list_begin);
    grid->order = order;
    grid->cell_of = cell_of;
    grid->list_begin = begin;
    for (int d = 0; d < 3; d++) {
        free(grid->built[d]);
        grid->built[d] = built[d];
    }
    grid->capacity = cap;
    return 0;
}

void sluice_grid_wrap(const sluice_grid *grid, sluice_real *position[3], sluice_index count)
{
    for (uint32_t d = 0; d < grid->dimensions; d++) {
        if (!grid->periodic[d])
            continue;
        sluice_real *x = position[d];
        const double lo = grid->lo[d], length = grid->length[d];
#pragma omp parallel for schedule(static) if (count >= grid->parallel_min)
        for (sluice_index i = 0; i < count; i++) {
            double v = (double)x[i];
            if (v < lo || v >= lo + length) {
                v -= length * floor((v - lo) / length);
                if (v >= lo + length) /* rounding */
                    v = lo;
                x[i] = (sluice_real)v;
            }
        }
    }
}

/* Cell coordinate of x along d, or -1 outside a non-periodic side. */
static inline int64_t cell_coordinate(const sluice_grid *grid, int d, double x)
{
    if (grid->periodic[d])
        x -= grid->length[d] * floor((x - grid->lo[d]) / grid->length[d]);
    else if (!(x >= grid->lo[d] && x < grid->hi[d]))
        return -1;
    int64_t c = (int64_t)floor((x - grid->lo[d]) * grid->inverse_cell_size[d]);
    if (c < 0)
        c = 0;
    if (c >= grid->cells[d])
        c = grid->cells[d] - 1;
    return c;
}

/* What visit() lists: the kinds of the neighbours it keeps (kinds, when
 * `kind` is not NULL) */
typedef struct list_filter {
    const uint8_t *kind; /* NULL: every particle */
    uint32_t kinds;
} list_filter;

/* Appends (or, with out NULL, counts) the particles j in [a, b) within the
 * cutoff of (xi, yi, zi) and of a kind the filter keeps, minimum image
 * applied along periodic axes. */
static inline sluice_index scan_range(const sluice_grid *grid, sluice_real *const pos[3],
                                      sluice_index i, double xi, double yi, double zi,
                                      sluice_index a, sluice_index b, double cutoff2,
                                      list_filter filter, sluice_index *out, sluice_index found)
{
    const int three = grid->dimensions == 3;
    for (sluice_index j = a; j < b; j++) {
        double dx = xi - (double)pos[0][j];
        double dy = yi - (double)pos[1][j];
        double dz = three ? zi - (double)pos[2][j] : 0.0;
        if (grid->periodic[0])
            dx = minimum_image(dx, grid->length[0]);
        if (grid->periodic[1])
            dy = minimum_image(dy, grid->length[1]);
        if (three && grid->periodic[2])
            dz = minimum_image(dz, grid->length[2]);
        if (dx * dx + dy * dy + dz * dz < cutoff2 && j != i &&
            (!filter.kind || ((filter.kinds >> filter.kind[j]) & 1u))) {
            if (out)
                out[found] = j;
            found++;
        }
    }
    return found;
}

/* Visits the candidate neighbours of particle i (sorted order) within the list
 * cutoff, of the kinds its own kind lists (grid->list_kinds; every kind when
 * kind is NULL); with `out` NULL only counts them. Inlined into both passes. */
static inline sluice_index visit(const sluice_grid *grid, sluice_real *const pos[3],
                                 const uint8_t *kind, sluice_index i, double cutoff2,
                                 sluice_index *out)
{
    list_filter filter = {NULL, SLUICE_KINDS_ALL};
    if (kind) {
        filter.kinds = grid->list_kinds[kind[i]];
        if (!filter.kinds)
            return 0;
        if ((filter.kinds & SLUICE_KINDS_ALL) != SLUICE_KINDS_ALL)
            filter.kind = kind;
    }
    const uint32_t dims = grid->dimensions;
    const uint32_t cell = grid->cell_of[i];
    int64_t c[3];
    c[0] = (int64_t)(cell % (uint32_t)grid->cells[0]);
    c[1] = (int64_t)((cell / (uint32_t)grid->cells[0]) % (uint32_t)grid->cells[1]);
    c[2] = (int64_t)(cell / ((uint32_t)grid->cells[0] * (uint32_t)grid->cells[1]));
    const double xi = (double)pos[0][i], yi = (double)pos[1][i];
    const double zi = dims == 3 ? (double)pos[2][i] : 0.0;
    sluice_index found = 0;
    const int64_t zr = dims == 3 ? 1 : 0;
    for (int64_t dz = -zr; dz <= zr; dz++) {
        int64_t cz = c[2] + dz;
        if (dims == 3 && (cz < 0 || cz >= grid->cells[2])) {
            if (!grid->periodic[2])
                continue;
            cz = (cz + grid->cells[2]) % grid->cells[2];
        }
        for (int64_t dy = -1; dy <= 1; dy++) {
            int64_t cy = c[1] + dy;
            if (cy < 0 || cy >= grid->cells[1]) {
                if (!grid->periodic[1])
                    continue;
                cy = (cy + grid->cells[1]) % grid->cells[1];
            }
            const size_t row = ((size_t)cz * (size_t)grid->cells[1] + (size_t)cy) *
                               (size_t)grid->cells[0];
            if (!grid->periodic[0]) {
                /* the (up to) three x cells are contiguous in memory: one range */
                int64_t x0 = c[0] > 0 ? c[0] - 1 : 0;
                int64_t x1 = c[0] + 1 < grid->cells[0] ? c[0] + 1 : grid->cells[0] - 1;
                if (filter.kind) {
                    uint32_t present = 0;
                    for (int64_t x = x0; x <= x1; x++)
                        present |= grid->cell_kinds[row + (size_t)x];
                    if (!(present & filter.kinds))
                        continue;
                }
                found =
                    scan_range(grid, pos, i, xi, yi, zi, grid->cell_start[row + (size_t)x0],
                               grid->cell_start[row + (size_t)x1 + 1], cutoff2, filter, out, found);
                if (grid->halo_count)
                    found = scan_range(grid, pos, i, xi, yi, zi, grid->halo_start[row + (size_t)x0],
                                       grid->halo_start[row + (size_t)x1 + 1], cutoff2, filter, out,
                                       found);
                continue;
            }
            for (int64_t k = -1; k <= 1; k++) {
                size_t cx = (size_t)((c[0] + k + grid->cells[0]) % grid->cells[0]);
                if (filter.kind && !(grid->cell_kinds[row + cx] & filter.kinds))
                    continue;
                found = scan_range(grid, pos, i, xi, yi, zi, grid->cell_start[row + cx],
                                   grid->cell_start[row + cx + 1], cutoff2, filter, out, found);
                if (grid->halo_count)
                    found = scan_range(grid, pos, i, xi, yi, zi, grid->halo_start[row + cx],
                                       grid->halo_start[row + cx + 1], cutoff2, filter, out, found);
            }
        }
    }
    return found;
}

sluice_index sluice_grid_near_point(const sluice_grid *grid, sluice_real *const pos[3],
                                    const double p[3], double radius2, int with_halo,
                                    sluice_index *out, sluice_index capacity)
{
    const uint32_t dims = grid->dimensions;
    int64_t c[3] = {0, 0, 0};
    for (uint32_t d = 0; d < dims; d++) {
        double x = p[d];
        if (grid->periodic[d])
            x -= grid->length[d] * floor((x - grid->lo[d]) / grid->length[d]);
        double f = floor((x - grid->lo[d]) * grid->inverse_cell_size[d]);
        /* outside a closed side: the nearest cells hold whatever is in reach */
        c[d] = f < 0 ? 0 : f >= (double)grid->cells[d] ? grid->cells[d] - 1 : (int64_t)f;
        if (!grid->periodic[d] && (f < -1 || f > (double)grid->cells[d]))
            return 0; /* more than a cell outside: nothing within the support */
    }
    sluice_index found = 0;
    const int64_t zr = dims == 3 ? 1 : 0;
    for (int64_t dz = -zr; dz <= zr; dz++) {
        int64_t cz = c[2] + dz;
        if (dims == 3 && (cz < 0 || cz >= grid->cells[2])) {
            if (!grid->periodic[2])
                continue;
            cz = (cz + grid->cells[2]) % grid->cells[2];
        }
        for (int64_t dy = -1; dy <= 1; dy++) {
            int64_t cy = c[1] + dy;
            if (cy < 0 || cy >= grid->cells[1]) {
                if (!grid->periodic[1])
                    continue;
                cy = (cy + grid->cells[1]) % grid->cells[1];
            }
            for (int64_t dx = -1; dx <= 1; dx++) {
                int64_t cx = c[0] + dx;
                if (cx < 0 || cx >= grid->cells[0]) {
                    if (!grid->periodic[0])
                        continue;
                    cx = (cx + grid->cells[0]) % grid->cells[0];
                }
                /* a periodic axis of 3 cells visits no cell twice: cells >= 3 */
                size_t cell = ((size_t)cz * (size_t)grid->cells[1] + (size_t)cy) *
                                  (size_t)grid->cells[0] +
                              (size_t)cx;
                const int sources = with_halo && grid->halo_count ? 2 : 1;
                for (int source = 0; source < sources; source++) {
                    const sluice_index *start = source ? grid->halo_start : grid->cell_start;
                    for (sluice_index j = start[cell]; j < start[cell + 1]; j++) {
                        double s = 0;
                        for (uint32_t d = 0; d < dims; d++) {
                            double e = p[d] - (double)pos[d][j];
                            if (grid->periodic[d])
                                e = minimum_image(e, grid->length[d]);
                            s += e * e;
                        }
                        if (s < radius2) {
                            if (found < capacity)
                                out[found] = j;
                            found++;
                        }
                    }
                }
            }
        }
    }
    return found;
}

/* Stable counting sort of n items by cell: order[] receives the items cell
 * by cell, start[c] .. start[c + 1] the positions of cell c's, each plus
 * `first` (the store index of the sorted block's first particle). */
static void sort_by_cell(const sluice_grid *grid, const uint32_t *cell, sluice_index n,
                         sluice_index first, sluice_index *start, sluice_index *order)
{
    memset(start, 0, (grid->cell_count + 1) * sizeof *start);
    for (sluice_index i = 0; i < n; i++)
        start[cell[i] + 1]++;
    for (size_t c = 0; c < grid->cell_count; c++)
        start[c + 1] += start[c];
    for (sluice_index i = 0; i < n; i++)
        order[start[cell[i]]++] = i;
    /* restore start (it was advanced to the end of each cell) */
    for (size_t c = grid->cell_count; c > 0; c--)
        start[c] = start[c - 1] + first;
    start[0] = first;
}

/* Sorts the halo [n, n + h) of the store by cell (h is small: one
 * temporary per column) and indexes it in grid->halo_start. */
static int sort_halo(sluice_grid *grid, sluice_particles *particles, uint32_t position_column,
                     sluice_index n, sluice_index h)
{
    const uint32_t dims = grid->dimensions;
    if (!grid->halo_start &&
        !(grid->halo_start = calloc(grid->cell_count + 1, sizeof *grid->halo_start)))
        return -1;
    if (h > grid->halo_capacity) {
        sluice_index cap = h + h / 4 + 64;
        sluice_index *order = malloc((size_t)cap * sizeof *order);
        if (!order)
            return -1;
        free(grid->halo_order);
        grid->halo_order = order;
        grid->halo_capacity = cap;
    }
    uint32_t *cell = malloc(((size_t)h + 1) * sizeof *cell);
    if (!cell)
        return -1;
    for (sluice_index k = 0; k < h; k++) {
        int64_t c[3] = {0, 0, 0};
        for (uint32_t d = 0; d < dims; d++) {
            const sluice_real *x = particles->columns[position_column + d];
            c[d] = cell_coordinate(grid, (int)d, (double)x[n + k]);
            if (c[d] < 0) { /* a halo particle outside the domain: its owner reports it */
                free(cell);
                return -2;
            }
        }
        cell[k] = (uint32_t)((c[2] * grid->cells[1] + c[1]) * grid->cells[0] + c[0]);
    }
    sort_by_cell(grid, cell, h, n, grid->halo_start, grid->halo_order);
    free(cell);
    /* permute the halo rows of every column */
    size_t widest = 1;
    for (uint32_t c = 0; c < particles->column_count; c++)
        if (particles->element_size[c] > widest)
            widest = particles->element_size[c];
    char *tmp = malloc((size_t)h * widest + 1);
    if (!tmp)
        return -1;
    for (uint32_t c = 0; c < particles->column_count; c++) {
        const size_t e = particles->element_size[c];
        char *base = (char *)particles->columns[c] + (size_t)n * e;
        for (sluice_index s = 0; s < h; s++)
            memcpy(tmp + (size_t)s * e, base + (size_t)grid->halo_order[s] * e, e);
        memcpy(base, tmp, (size_t)h * e);
    }
    free(tmp);
    return 0;
}

/* grid->cell_kinds from the sorted particles [0, n) and the halo after them */
static void mark_cell_kinds(sluice_grid *grid, const uint8_t *kind, sluice_index n)
{
    uint8_t *present = grid->cell_kinds;
    const sluice_index *start = grid->cell_start;
    const sluice_index *halo = grid->halo_count ? grid->halo_start : NULL;
#pragma omp parallel for schedule(static) if (grid->cell_count >= grid->parallel_min)
    for (size_t c = 0; c < grid->cell_count; c++) {
        uint32_t bits = 0;
        for (sluice_index i = start[c]; i < start[c + 1] && i < n; i++)
            bits |= 1u << kind[i];
        if (halo)
            for (sluice_index i = halo[c]; i < halo[c + 1]; i++)
                bits |= 1u << kind[i];
        present[c] = (uint8_t)bits;
    }
}

int sluice_grid_build(sluice_grid *grid, sluice_particles *particles, uint32_t position_column,
                      sluice_index *bad)
{
    return sluice_grid_build_with_halo(grid, particles, position_column, bad, NULL, NULL);
}

int sluice_grid_build_with_halo(sluice_grid *grid, sluice_particles *particles,
                                uint32_t position_column, sluice_index *bad,
                                sluice_grid_halo_fn halo, void *context)
{
    const sluice_index n = particles->count;
    const uint32_t dims = grid->dimensions;
    if (ensure_capacity(grid, n) != 0)
        return -1;
    sluice_real *pos[3] = {NULL, NULL, NULL};
    for (uint32_t d = 0; d < dims; d++)
        pos[d] = particles->columns[position_column + d];
    if (dims == 2)
        pos[2] = pos[1]; /* never read in 2D; keeps pointers valid */

    /* 1. cell of every particle */
    sluice_index first_bad = n;
    uint32_t *cell_of = grid->cell_of;
#pragma omp parallel for schedule(static) reduction(min : first_bad) if (n >= grid->parallel_min)
    for (sluice_index i = 0; i < n; i++) {
        int64_t c[3] = {0, 0, 0};
        int ok = 1;
        for (uint32_t d = 0; d < dims; d++) {
            double x = (double)pos[d][i];
            if (!isfinite(x)) {
                ok = 0;
                break;
            }
            c[d] = cell_coordinate(grid, (int)d, x);
            if (c[d] < 0) {
                ok = 0;
                break;
            }
        }
        if (!ok) {
            if (i < first_bad)
                first_bad = i;
            cell_of[i] = 0;
            continue;
        }
        cell_of[i] = (uint32_t)((c[2] * grid->cells[1] + c[1]) * grid->cells[0] + c[0]);
    }
    if (first_bad < n) {
        *bad = first_bad;
        grid->valid = 0;
        return -2;
    }

    /* 2. stable counting sort by cell */
    sluice_index *start = grid->cell_start;
    sort_by_cell(grid, cell_of, n, 0, start, grid->order);
    if (sluice_particles_permute(particles, grid->order) != 0)
        return -1;
    for (uint32_t d = 0; d < dims; d++)
        pos[d] = particles->columns[position_column + d];
    if (dims == 2)
        pos[2] = pos[1];
    for (size_t c = 0; c < grid->cell_count; c++)
        for (sluice_index i = start[c]; i < start[c + 1]; i++)
            cell_of[i] = (uint32_t)c;

    /* 3. positions at this build */
    for (uint32_t d = 0; d < dims; d++)
        memcpy(grid->built[d], pos[d], (size_t)n * sizeof(sluice_real));

    /* 3b. the halo of a distributed run, sorted by cell after the particles */
    grid->halo_count = 0;
    if (halo) {
        sluice_index h = 0;
        if (halo(context, particles, &h) != 0)
            return -3;
        int rc = h ? sort_halo(grid, particles, position_column, n, h) : 0;
        if (rc != 0)
            return rc == -2 ? -3 : rc; /* -2: outside the domain, which its owner reports */
        grid->halo_count = h;
        for (uint32_t d = 0; d < dims; d++)
            pos[d] = particles->columns[position_column + d];
        if (dims == 2)
            pos[2] = pos[1];
        if (h > grid->halo_built_capacity) {
            const sluice_index cap = h + h / 4 + 64;
            for (uint32_t d = 0; d < dims; d++) {
                sluice_real *grown = realloc(grid->halo_built[d], (size_t)cap * sizeof *grown);
                if (!grown)
                    return -1;
                grid->halo_built[d] = grown;
            }
            grid->halo_built_capacity = cap;
        }
        for (uint32_t d = 0; d < dims; d++)
            memcpy(grid->halo_built[d], pos[d] + n, (size_t)h * sizeof(sluice_real));
    }

    /* 4. Verlet list: count, prefix sum, fill */
    const double cutoff = (double)grid->support + (double)grid->skin;
    const double cutoff2 = cutoff * cutoff;
    sluice_index *begin = grid->list_begin;
    const uint8_t *kind =
        grid->kind_column >= 0 ? (const uint8_t *)particles->columns[grid->kind_column] : NULL;
    if (kind)
        mark_cell_kinds(grid, kind, n);
#pragma omp parallel for schedule(guided, 256)
    for (sluice_index i = 0; i < n; i++)
        begin[i + 1] = visit(grid, pos, kind, i, cutoff2, NULL);
    int listed = sluice_list_offsets(begin, n, &grid->list, &grid->list_capacity, grid->list_limit,
                                     &grid->list_needed);
    if (listed != 0) {
        grid->valid = 0;
        return listed;
    }
    sluice_index *list = grid->list;
#pragma omp parallel for schedule(guided, 256)
    for (sluice_index i = 0; i < n; i++)
        (void)visit(grid, pos, kind, i, cutoff2, list + begin[i]);

    grid->count = n;
    grid->valid = 1;
    grid->rebuilds++;
    return 0;
}

int sluice_list_offsets(sluice_index *begin, sluice_index n, sluice_index **list,
                        size_t *capacity, size_t limit, size_t *needed)
{
    begin[0] = 0;
    size_t total = 0;
    for (sluice_index i = 0; i < n; i++) {
        total += begin[i + 1];
        if (total > UINT32_MAX)
            return -1;
        begin[i + 1] = (sluice_index)total;
    }
    if (total > *capacity || !*list) {
        size_t cap = total + total / 4 + 64;
        if (limit > 0 && cap > limit) {
            cap = total + 64; /* without the margin */
            if (cap > limit) {
                if (needed)
                    *needed = total;
                return -4;
            }
        }
        sluice_index *grown = malloc(cap * sizeof *grown);
        if (!grown)
            return -1;
        free(*list);
        *list = grown;
        *capacity = cap;
    }
    return 0;
}

size_t sluice_grid_bytes(const sluice_grid *grid)
{
    size_t b = (grid->cell_count + 1) * sizeof(sluice_index);
    b += (size_t)grid->capacity * (sizeof(sluice_index) + sizeof(uint32_t) + sizeof(sluice_index));
    b += (size_t)grid->capacity * grid->dimensions * sizeof(sluice_real);
    b += grid->list_capacity * sizeof(sluice_index);
    return b;
}
