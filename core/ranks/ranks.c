#include "ranks.h"

#ifdef SLUICE_MPI

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <stdarg.h>
#include <stdio.h>

/* Keeps the first cause of a failure in the run's message buffer. */
static void fail(sluice_ranks_run *run, const char *format, ...) SLUICE_PRINTF(2, 3);
static void fail(sluice_ranks_run *run, const char *format, ...)
{
    if (run->failure[0])
        return;
    va_list ap;
    va_start(ap, format);
    vsnprintf(run->failure, run->failure_size, format, ap);
    va_end(ap);
}

void sluice_ranks_free(sluice_halo_lists *h)
{
    free(h->cuts);
    free(h->boxes);
    free(h->neighbour);
    free(h->send);
    free(h->send_begin);
    free(h->receive_begin);
    free(h->sent);
    free(h->got);
    free(h->requests);
    free(h->slot);
    free(h->columns);
    free(h->real_column);
    for (int s = 0; s < 2; s++)
        free(h->buffer[s]);
    memset(h, 0, sizeof *h);
}

int sluice_ranks_gather(sluice_ranks_run *run, sluice_particles *all)
{
    const sluice_comm *c = run->comm;
    const sluice_particles *p = run->particles;
    memset(all, 0, sizeof *all);
    int *counts = c->rank == 0 ? calloc((size_t)c->size, sizeof *counts) : NULL;
    int *bytes = c->rank == 0 ? calloc((size_t)c->size, sizeof *bytes) : NULL;
    int *offsets = c->rank == 0 ? calloc((size_t)c->size, sizeof *offsets) : NULL;
    int failed = c->rank == 0 && (!counts || !bytes || !offsets);
    const int own = (int)p->count;
    if (MPI_Gather(&own, 1, MPI_INT, counts, 1, MPI_INT, 0, c->comm) != MPI_SUCCESS)
        failed = 1;
    uint64_t total = 0;
    if (c->rank == 0 && !failed) {
        for (int r = 0; r < c->size; r++)
            total += (uint64_t)counts[r];
        if (total > (uint64_t)INT_MAX / 8 ||
            sluice_particles_init(all, p->column_count, p->element_size) != 0 ||
            sluice_particles_append(all, (sluice_index)total, NULL) != 0)
            failed = 1;
    }
    if (sluice_comm_any(c, failed)) {
        free(counts), free(bytes), free(offsets);
        sluice_particles_free(all);
        memset(all, 0, sizeof *all);
        return -1;
    }
    for (uint32_t col = 0; col < p->column_count && !failed; col++) {
        const int size = p->element_size[col];
        if (c->rank == 0)
            for (int r = 0, at = 0; r < c->size; r++) {
                bytes[r] = counts[r] * size;
                offsets[r] = at;
                at += bytes[r];
            }
        if (MPI_Gatherv(p->columns[col], own * size, MPI_BYTE,
                        c->rank == 0 ? all->columns[col] : NULL, bytes, offsets, MPI_BYTE, 0,
                        c->comm) != MPI_SUCCESS)
            failed = 1;
    }
    free(counts), free(bytes), free(offsets);
    if (failed) {
        sluice_particles_free(all);
        memset(all, 0, sizeof *all);
        return -1;
    }
    return 0;
}


static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The columns of an exchange: `columns` (count of them), or every column
 * when columns is NULL. */
typedef struct column_set {
    const uint32_t *columns;
    uint32_t count;
} column_set;

static uint32_t set_count(const sluice_particles *p, column_set set)
{
    return set.columns ? set.count : p->column_count;
}

static uint32_t set_column(column_set set, uint32_t k)
{
    return set.columns ? set.columns[k] : k;
}

static size_t row_bytes(const sluice_particles *p, column_set set)
{
    size_t b = 0;
    for (uint32_t k = 0; k < set_count(p, set); k++)
        b += p->element_size[set_column(set, k)];
    return b;
}

static const column_set every_column = {NULL, 0};

static int grow(void **block, size_t *capacity, size_t bytes)
{
    if (bytes <= *capacity && *block)
        return 0;
    size_t cap = bytes + bytes / 4 + 64;
    void *b = realloc(*block, cap);
    if (!b)
        return -1;
    *block = b;
    *capacity = cap;
    return 0;
}

/* ------------------------------------------------------------- geometry -- */

static uint32_t dims_of(const sluice_ranks_run *run)
{
    return run->grid->dimensions;
}

/* x along axis d, wrapped into the domain on a periodic axis */
static double wrap_axis(const sluice_grid *g, uint32_t d, double x)
{
    if (!g->periodic[d])
        return x;
    double v = x - g->length[d] * floor((x - g->lo[d]) / g->length[d]);
    return v >= g->hi[d] ? g->lo[d] : v;
}

/* The gap along axis d between [a0, a1] and [b0, b1) (0 when they meet); on
 * a periodic axis the shortest over the images of the second. */
static double interval_gap(const sluice_grid *g, uint32_t d, double a0, double a1, double b0,
                           double b1)
{
    double best = INFINITY;
    const int images = g->periodic[d] ? 1 : 0;
    for (int k = -images; k <= images; k++) {
        const double shift = k * g->length[d];
        const double lo = b0 + shift, hi = b1 + shift;
        const double gap = a1 < lo ? lo - a1 : hi < a0 ? a0 - hi : 0;
        best = gap < best ? gap : best;
    }
    return best;
}

static int box_holds(const sluice_ranks_run *run, const double *box, const double *x)
{
    for (uint32_t d = 0; d < dims_of(run); d++) {
        const double v = wrap_axis(run->grid, d, x[d]);
        if (!(v >= box[d] && v < box[3 + d]))
            return 0;
    }
    return 1;
}

/* 1 when x lies within `width` of the box along every axis */
static int near_box(const sluice_ranks_run *run, const double *box, const double *x, double width)
{
    for (uint32_t d = 0; d < dims_of(run); d++)
        if (!(interval_gap(run->grid, d, x[d], x[d], box[d], box[3 + d]) < width))
            return 0;
    return 1;
}

int sluice_ranks_owns(const sluice_ranks_run *run, const double point[3])
{
    const sluice_halo_lists *h = run->halo;
    const double box[6] = {h->lo[0], h->lo[1], h->lo[2], h->hi[0], h->hi[1], h->hi[2]};
    return box_holds(run, box, point);
}

double sluice_ranks_outside(const sluice_ranks_run *run, const double point[3])
{
    const sluice_halo_lists *h = run->halo;
    double worst = 0;
    for (uint32_t d = 0; d < dims_of(run); d++) {
        const double v = wrap_axis(run->grid, d, point[d]);
        const double gap = interval_gap(run->grid, d, v, v, h->lo[d], h->hi[d]);
        worst = gap > worst || gap != gap ? gap : worst;
    }
    return worst;
}

static void position_of(const sluice_ranks_run *run, const sluice_particles *p, sluice_index i,
                        double x[3])
{
    x[0] = x[1] = x[2] = 0;
    for (uint32_t d = 0; d < dims_of(run); d++)
        x[d] = (double)((const sluice_real *)p->columns[run->position_column + d])[i];
}

/* ----------------------------------------------------------------- cuts -- */

/* The cuts by level: x slab i spans [cut_x(i), cut_x(i + 1)); in it, y
 * slab j spans [cut_y(i, j), cut_y(i, j + 1)); in that, z slab k spans
 * [cut_z(i, j, k), cut_z(i, j, k + 1)). Rank (i, j, k) is
 * (i split[1] + j) split[2] + k. */
static size_t cut_index(const int *s, int level, int i, int j, int k)
{
    const size_t nx = (size_t)s[0] + 1, ny = (size_t)s[0] * ((size_t)s[1] + 1);
    if (level == 0)
        return (size_t)i;
    if (level == 1)
        return nx + (size_t)i * ((size_t)s[1] + 1) + (size_t)j;
    return nx + ny + ((size_t)i * (size_t)s[1] + (size_t)j) * ((size_t)s[2] + 1) + (size_t)k;
}

static size_t cut_total(const int *s)
{
    return cut_index(s, 2, s[0] - 1, s[1] - 1, s[2]) + 1;
}

/* The outer ends of every level: the domain on a periodic axis, +-inf on a
 * closed one (particles outside the domain are reported by the grid). */
static void outer_cuts(const sluice_ranks_run *run, const int *s, double *cuts)
{
    const sluice_grid *g = run->grid;
    double lo[3], hi[3];
    for (int d = 0; d < 3; d++) {
        const int periodic = (uint32_t)d < dims_of(run) && g->periodic[d];
        lo[d] = periodic ? g->lo[d] : -INFINITY;
        hi[d] = periodic ? g->hi[d] : INFINITY;
    }
    cuts[cut_index(s, 0, 0, 0, 0)] = lo[0];
    cuts[cut_index(s, 0, s[0], 0, 0)] = hi[0];
    for (int i = 0; i < s[0]; i++) {
        cuts[cut_index(s, 1, i, 0, 0)] = lo[1];
        cuts[cut_index(s, 1, i, s[1], 0)] = hi[1];
        for (int j = 0; j < s[1]; j++) {
            cuts[cut_index(s, 2, i, j, 0)] = lo[2];
            cuts[cut_index(s, 2, i, j, s[2])] = hi[2];
        }
    }
}

/* The group of level `level` of the point x: its x slab (level 1) or its
 * (x, y) column (level 2); 0 at level 0. */
static int group_of(const sluice_ranks_run *run, const double *cuts, int level, const double *x)
{
    const int *s = run->halo->split;
    if (level == 0)
        return 0;
    const double vx = wrap_axis(run->grid, 0, x[0]);
    int i = 0;
    while (i + 1 < s[0] && !(vx < cuts[cut_index(s, 0, i + 1, 0, 0)]))
        i++;
    if (level == 1)
        return i;
    const double vy = wrap_axis(run->grid, 1, x[1]);
    int j = 0;
    while (j + 1 < s[1] && !(vy < cuts[cut_index(s, 1, i, j + 1, 0)]))
        j++;
    return i * s[1] + j;
}

static double *cut_at(const sluice_ranks_run *run, double *cuts, int level, int group, int k)
{
    const int *s = run->halo->split;
    if (level == 0)
        return &cuts[cut_index(s, 0, k, 0, 0)];
    if (level == 1)
        return &cuts[cut_index(s, 1, group, k, 0)];
    return &cuts[cut_index(s, 2, group / s[1], group % s[1], k)];
}

static int groups_of_level(const int *s, int level)
{
    return level == 0 ? 1 : level == 1 ? s[0] : s[0] * s[1];
}

/* Sets the boxes from the cuts, this rank's box, and its neighbours (the
 * ranks whose box meets this box widened by the halo width). */
static int boxes_from_cuts(sluice_ranks_run *run)
{
    sluice_halo_lists *h = run->halo;
    const int *s = h->split, size = run->comm->size;
    for (int i = 0; i < s[0]; i++)
        for (int j = 0; j < s[1]; j++)
            for (int k = 0; k < s[2]; k++) {
                double *b = h->boxes + 6 * (size_t)((i * s[1] + j) * s[2] + k);
                b[0] = h->cuts[cut_index(s, 0, i, 0, 0)];
                b[3] = h->cuts[cut_index(s, 0, i + 1, 0, 0)];
                b[1] = h->cuts[cut_index(s, 1, i, j, 0)];
                b[4] = h->cuts[cut_index(s, 1, i, j + 1, 0)];
                b[2] = h->cuts[cut_index(s, 2, i, j, k)];
                b[5] = h->cuts[cut_index(s, 2, i, j, k + 1)];
            }
    const double *own = h->boxes + 6 * (size_t)run->comm->rank;
    for (int d = 0; d < 3; d++) {
        h->lo[d] = own[d];
        h->hi[d] = own[3 + d];
    }
    int count = 0;
    for (int r = 0; r < size; r++) {
        if (r == run->comm->rank)
            continue;
        const double *b = h->boxes + 6 * (size_t)r;
        int meets = 1;
        for (uint32_t d = 0; d < dims_of(run) && meets; d++)
            meets = interval_gap(run->grid, d, own[d], own[3 + d], b[d], b[3 + d]) < h->width;
        if (meets)
            h->neighbour[count++] = r;
    }
    h->neighbour_count = count;
    return 0;
}

/* The split of the rank count over the axes of `mask` (bit d: axis d) that
 * gives the boxes the least surface for the particles' extent (ties: more
 * cuts along x, then y). */
static int choose_split(const sluice_ranks_run *run, int mask, const double *extent, int *split)
{
    const int size = run->comm->size;
    const uint32_t dims = dims_of(run);
    double best = INFINITY;
    split[0] = split[1] = split[2] = 0;
    for (int px = 1; px <= size; px++) {
        if (size % px || (px > 1 && !(mask & 1)))
            continue;
        for (int py = 1; py <= size / px; py++) {
            if ((size / px) % py || (py > 1 && !(mask & 2)))
                continue;
            const int pz = size / px / py;
            if (pz > 1 && (!(mask & 4) || dims < 3))
                continue;
            const double a = extent[0] / px, b = extent[1] / py, c = extent[2] / pz;
            const double surface = dims == 3 ? a * b + b * c + a * c : a + b;
            if (surface < best * (1 - 1e-12)) {
                best = surface;
                split[0] = px, split[1] = py, split[2] = pz;
            }
        }
    }
    return split[0] > 0 ? 0 : -1;
}

/* Cuts of equal counts from every particle of the store (every rank holds
 * all of them: the same cuts on every rank without a message), level by
 * level: the cut between the m-th and (m+1)-th coordinate of the group,
 * m = k n / parts. */
static int cuts_of_equal_counts(sluice_ranks_run *run)
{
    sluice_halo_lists *h = run->halo;
    const sluice_particles *p = run->particles;
    const sluice_index n = p->count;
    const int *s = h->split;
    double *values = malloc(((size_t)n + 1) * sizeof *values);
    int *group = malloc(((size_t)n + 1) * sizeof *group);
    if (!values || !group) {
        free(values);
        free(group);
        return -1;
    }
    outer_cuts(run, s, h->cuts);
    for (int level = 0; level < 3; level++) {
        const int parts = s[level], groups = groups_of_level(s, level);
        if (parts == 1)
            continue;
        for (sluice_index i = 0; i < n; i++) {
            double x[3];
            position_of(run, p, i, x);
            group[i] = group_of(run, h->cuts, level, x);
        }
        for (int gr = 0; gr < groups; gr++) {
            size_t m = 0;
            for (sluice_index i = 0; i < n; i++)
                if (group[i] == gr) {
                    double x[3];
                    position_of(run, p, i, x);
                    values[m++] = wrap_axis(run->grid, (uint32_t)level, x[level]);
                }
            qsort(values, m, sizeof *values, compare_double);
            for (int k = 1; k < parts; k++) {
                const size_t at = (size_t)((uint64_t)k * m / (uint64_t)parts);
                double cut;
                if (m == 0) /* an empty group: even cuts of the domain */
                    cut = run->grid->lo[level] +
                          (run->grid->hi[level] - run->grid->lo[level]) * k / parts;
                else if (at == 0)
                    cut = values[0];
                else if (at >= m)
                    cut = values[m - 1];
                else
                    cut = 0.5 * (values[at - 1] + values[at]);
                *cut_at(run, h->cuts, level, gr, k) = cut;
            }
        }
    }
    free(values);
    free(group);
    return 0;
}

/* Weighted quantiles along axis `level` of the ranks' own particles, every
 * particle of this rank weighing `weight`, for every group of the level
 * (under the cuts of the levels above, already in `cuts`): target[g, k] is
 * where the weight left of it is k / parts of the group's. Two histograms
 * summed over the ranks: 512 bins over the group's extent, then 256 within
 * the bin of each target, and linear within the sub-bin. A group without
 * weight keeps its cuts. Collective. */
enum { COARSE_BINS = 512, FINE_BINS = 256 };

static int weighted_cuts(sluice_ranks_run *run, int level, double weight, double *cuts)
{
    const sluice_halo_lists *h = run->halo;
    const sluice_particles *p = run->particles;
    const sluice_index n = p->count;
    const int parts = h->split[level], groups = groups_of_level(h->split, level);
    const size_t targets = (size_t)groups * (size_t)(parts - 1);
    double *range = malloc(2 * (size_t)groups * sizeof *range);
    double *coarse = calloc((size_t)groups * COARSE_BINS, sizeof *coarse);
    double *fine = calloc(targets * FINE_BINS + 1, sizeof *fine);
    int *bin = malloc((targets + 1) * sizeof *bin);
    double *below = malloc((targets + 1) * sizeof *below);
    int *group = malloc(((size_t)n + 1) * sizeof *group);
    double *value = malloc(((size_t)n + 1) * sizeof *value);
    int failed = !range || !coarse || !fine || !bin || !below || !group || !value;
    if (sluice_comm_any(run->comm, failed)) {
        free(range), free(coarse), free(fine), free(bin), free(below), free(group), free(value);
        return -1;
    }
    for (int gr = 0; gr < groups; gr++)
        range[gr] = range[groups + gr] = INFINITY; /* min, -max */
    for (sluice_index i = 0; i < n; i++) {
        double x[3];
        position_of(run, p, i, x);
        group[i] = group_of(run, cuts, level, x);
        value[i] = wrap_axis(run->grid, (uint32_t)level, x[level]);
        if (value[i] == value[i]) {
            range[group[i]] = fmin(range[group[i]], value[i]);
            range[groups + group[i]] = fmin(range[groups + group[i]], -value[i]);
        }
    }
    sluice_comm_reduce(run->comm, range, 2 * (uint32_t)groups, SLUICE_REDUCE_MIN);
    for (sluice_index i = 0; i < n; i++) {
        const int gr = group[i];
        const double lo = range[gr], width = -range[groups + gr] - lo;
        if (!(value[i] == value[i]) || !(width > 0))
            continue;
        int b = (int)((value[i] - lo) / width * COARSE_BINS);
        b = b < 0 ? 0 : b >= COARSE_BINS ? COARSE_BINS - 1 : b;
        coarse[(size_t)gr * COARSE_BINS + (size_t)b] += weight;
    }
    sluice_comm_reduce(run->comm, coarse, (uint32_t)groups * COARSE_BINS, SLUICE_REDUCE_SUM);
    /* the coarse bin of every target, and the weight below it */
    for (int gr = 0; gr < groups; gr++) {
        const double *c = coarse + (size_t)gr * COARSE_BINS;
        double total = 0;
        for (int b = 0; b < COARSE_BINS; b++)
            total += c[b];
        for (int k = 1; k < parts; k++) {
            const size_t t = (size_t)gr * (size_t)(parts - 1) + (size_t)(k - 1);
            bin[t] = -1;
            if (!(total > 0) || !(-range[groups + gr] - range[gr] > 0))
                continue;
            const double goal = total * k / parts;
            double sum = 0;
            int b = 0;
            while (b + 1 < COARSE_BINS && sum + c[b] < goal)
                sum += c[b++];
            bin[t] = b;
            below[t] = sum;
        }
    }
    for (sluice_index i = 0; i < n; i++) {
        const int gr = group[i];
        const double lo = range[gr], width = -range[groups + gr] - lo;
        if (!(value[i] == value[i]) || !(width > 0))
            continue;
        const double u = (value[i] - lo) / width * COARSE_BINS;
        int b = (int)u;
        b = b < 0 ? 0 : b >= COARSE_BINS ? COARSE_BINS - 1 : b;
        for (int k = 1; k < parts; k++) {
            const size_t t = (size_t)gr * (size_t)(parts - 1) + (size_t)(k - 1);
            if (bin[t] != b)
                continue;
            int f = (int)((u - b) * FINE_BINS);
            f = f < 0 ? 0 : f >= FINE_BINS ? FINE_BINS - 1 : f;
            fine[t * FINE_BINS + (size_t)f] += weight;
        }
    }
    sluice_comm_reduce(run->comm, fine, (uint32_t)(targets * FINE_BINS), SLUICE_REDUCE_SUM);
    for (int gr = 0; gr < groups; gr++) {
        const double *c = coarse + (size_t)gr * COARSE_BINS;
        double total = 0;
        for (int b = 0; b < COARSE_BINS; b++)
            total += c[b];
        const double lo = range[gr], width = -range[groups + gr] - lo;
        for (int k = 1; k < parts; k++) {
            const size_t t = (size_t)gr * (size_t)(parts - 1) + (size_t)(k - 1);
            if (bin[t] < 0)
                continue;
            const double goal = total * k / parts, step = width / COARSE_BINS / FINE_BINS;
            double sum = below[t], at = lo + width * bin[t] / COARSE_BINS;
            const double *fb = fine + t * FINE_BINS;
            int f = 0;
            while (f + 1 < FINE_BINS && sum + fb[f] < goal)
                sum += fb[f++];
            const double fraction = fb[f] > 0 ? (goal - sum) / fb[f] : 0.5;
            *cut_at(run, cuts, level, gr, k) =
                at + step * (f + (fraction < 0 ? 0 : fraction > 1 ? 1 : fraction));
        }
    }
    free(range), free(coarse), free(fine), free(bin), free(below), free(group), free(value);
    return 0;
}

/* ------------------------------------------------------------ exchange -- */

/* Packs, neighbour by neighbour, the rows send[send_begin[k] ..) column by
 * column (the columns of `set`) into buffer[0]. */
static int pack(sluice_ranks_run *run, sluice_halo_lists *h, column_set set)
{
    const sluice_particles *p = run->particles;
    const size_t row = row_bytes(p, set);
    const size_t total = (size_t)h->send_begin[h->neighbour_count] * row;
    if (grow((void **)&h->buffer[0], &h->buffer_capacity[0], total + 1) != 0)
        return -1;
    char *out = h->buffer[0];
    for (int k = 0; k < h->neighbour_count; k++)
        for (uint32_t q = 0; q < set_count(p, set); q++) {
            const uint32_t c = set_column(set, q);
            const size_t e = p->element_size[c];
            const char *base = p->columns[c];
            for (sluice_index m = h->send_begin[k]; m < h->send_begin[k + 1]; m++, out += e)
                memcpy(out, base + (size_t)h->send[m] * e, e);
        }
    return 0;
}

/* Sends each neighbour its block of buffer[0] and receives its block into
 * buffer[1] (in neighbour order); receive_begin gets the offsets. Collective
 * over the neighbours. */
static int exchange(sluice_ranks_run *run, sluice_halo_lists *h, column_set set)
{
    const sluice_comm *c = run->comm;
    const int count = h->neighbour_count;
    const size_t row = row_bytes(run->particles, set);
    MPI_Request *request = h->requests;
    for (int k = 0; k < count; k++) {
        h->sent[k] = h->send_begin[k + 1] - h->send_begin[k];
        MPI_Irecv(&h->got[k], 1, MPI_UNSIGNED_LONG_LONG, h->neighbour[k], 21, c->comm,
                  &request[k]);
        MPI_Isend(&h->sent[k], 1, MPI_UNSIGNED_LONG_LONG, h->neighbour[k], 21, c->comm,
                  &request[count + k]);
    }
    MPI_Waitall(2 * count, request, MPI_STATUSES_IGNORE);
    unsigned long long total = 0;
    int too_large = 0;
    h->receive_begin[0] = 0;
    for (int k = 0; k < count; k++) {
        too_large |= h->got[k] * row > INT_MAX || h->sent[k] * row > INT_MAX;
        total += h->got[k];
        h->receive_begin[k + 1] = (sluice_index)total;
    }
    if (too_large || total > UINT32_MAX / 2) {
        fail(run, "rank %d: a halo message exceeds 2 GB", c->rank);
        return -1;
    }
    if (grow((void **)&h->buffer[1], &h->buffer_capacity[1], (size_t)total * row + 1) != 0) {
        fail(run, "out of memory for the halo of rank %d", c->rank);
        return -1;
    }
    for (int k = 0; k < count; k++) {
        MPI_Irecv(h->buffer[1] + (size_t)h->receive_begin[k] * row, (int)(h->got[k] * row),
                  MPI_BYTE, h->neighbour[k], 22, c->comm, &request[k]);
        MPI_Isend(h->buffer[0] + (size_t)h->send_begin[k] * row, (int)(h->sent[k] * row),
                  MPI_BYTE, h->neighbour[k], 22, c->comm, &request[count + k]);
    }
    MPI_Waitall(2 * count, request, MPI_STATUSES_IGNORE);
    return 0;
}

/* Writes blocks of rows (each column by column) from `in` to the store rows
 * first + k, or first + slot[k] when slot is given; blocks[b] .. blocks[b +
 * 1] are the rows of block b. */
static void unpack(sluice_particles *p, const char *in, const sluice_index *blocks, int count,
                   sluice_index first, const sluice_index *slot, column_set set)
{
    for (int b = 0; b < count; b++) {
        const sluice_index k0 = blocks[b], rows = blocks[b + 1] - blocks[b];
        for (uint32_t q = 0; q < set_count(p, set); q++) {
            const uint32_t c = set_column(set, q);
            const size_t e = p->element_size[c];
            char *base = p->columns[c];
            for (sluice_index k = 0; k < rows; k++, in += e) {
                const sluice_index to = first + (slot ? slot[k0 + k] : k0 + k);
                memcpy(base + (size_t)to * e, in, e);
            }
        }
    }
}

/* Room for the neighbour lists of up to `size` ranks. */
static int neighbour_arrays(sluice_ranks_run *run)
{
    sluice_halo_lists *h = run->halo;
    const size_t size = (size_t)run->comm->size;
    /* a restart splits again */
    free(h->cuts), free(h->boxes), free(h->neighbour), free(h->send_begin);
    free(h->receive_begin), free(h->sent), free(h->got), free(h->requests);
    h->cut_count = cut_total(h->split);
    h->cuts = malloc(h->cut_count * sizeof *h->cuts);
    h->boxes = malloc(6 * size * sizeof *h->boxes);
    h->neighbour = malloc(size * sizeof *h->neighbour);
    h->send_begin = calloc(size + 1, sizeof *h->send_begin);
    h->receive_begin = calloc(size + 1, sizeof *h->receive_begin);
    h->sent = malloc(size * sizeof *h->sent);
    h->got = malloc(size * sizeof *h->got);
    h->requests = malloc(2 * size * sizeof(MPI_Request));
    return h->cuts && h->boxes && h->neighbour && h->send_begin && h->receive_begin && h->sent &&
                   h->got && h->requests
               ? 0
               : -1;
}

/* ---------------------------------------------------------------- split -- */

int sluice_ranks_split(sluice_ranks_run *run)
{
    const sluice_comm *c = run->comm;
    sluice_halo_lists *h = run->halo;
    sluice_particles *p = run->particles;
    /* the split: the scene's axes, the counts from the particles' extent */
    const sluice_index n = p->count;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (sluice_index i = 0; i < n; i++) {
        double x[3];
        position_of(run, p, i, x);
        for (uint32_t d = 0; d < dims_of(run); d++) {
            lo[d] = fmin(lo[d], x[d]);
            hi[d] = fmax(hi[d], x[d]);
        }
    }
    double extent[3] = {1, 1, 1};
    for (uint32_t d = 0; d < dims_of(run); d++)
        extent[d] = hi[d] > lo[d] ? hi[d] - lo[d] : (double)run->spacing;
    if (choose_split(run, run->split_axes, extent, h->split) != 0) {
        fail(run, "%d ranks cannot be split along the axes of ranks.split", c->size);
        return -1;
    }
    uint8_t *away = calloc((size_t)n + 1, 1);
    if (!away || neighbour_arrays(run) != 0 || cuts_of_equal_counts(run) != 0) {
        free(away);
        fail(run, "out of memory splitting %u particles across %d ranks", n, c->size);
        return -1;
    }
    boxes_from_cuts(run);
    for (sluice_index i = 0; i < n; i++) {
        double x[3];
        position_of(run, p, i, x);
        const double box[6] = {h->lo[0], h->lo[1], h->lo[2], h->hi[0], h->hi[1], h->hi[2]};
        away[i] = !box_holds(run, box, x);
    }
    sluice_particles_compact(p, away);
    free(away);
    return 0;
}

/* -------------------------------------------------------------- balance -- */

int sluice_ranks_balance(sluice_ranks_run *run, int64_t step)
{
    const sluice_comm *c = run->comm;
    sluice_halo_lists *h = run->halo;
    const int balance = run->balance;
    if (balance == SLUICE_BALANCE_NONE ||
        step < h->balance_step + run->balance_every)
        return 0;
    h->balance_step = step;
    const double count = (double)run->particles->count;
    const double work = balance == SLUICE_BALANCE_TIME ? h->busy_seconds : count;
    h->busy_seconds = 0;
    const double total = sluice_comm_sum(c, work), largest = sluice_comm_max(c, work);
    const double mean = total / c->size;
    if (!(mean > 0 && largest > (1 + (double)run->balance_tolerance) * mean))
        return 0;
    /* every particle weighs its rank's work per particle; the new cuts, level
     * by level (each level's groups under the moved cuts of the levels
     * above), half the way from the old ones */
    const double weight = count > 0 ? work / count : 0;
    double *target = malloc(h->cut_count * sizeof *target);
    if (sluice_comm_any(c, target == NULL)) {
        free(target);
        fail(run, "out of memory balancing the ranks");
        return -1;
    }
    memcpy(target, h->cuts, h->cut_count * sizeof *target);
    int moved = 0;
    for (int level = 0; level < 3; level++) {
        if (h->split[level] == 1)
            continue;
        double *before = malloc(h->cut_count * sizeof *before);
        if (sluice_comm_any(c, before == NULL) ||
            (memcpy(before, target, h->cut_count * sizeof *before),
             weighted_cuts(run, level, weight, target) != 0)) {
            free(before);
            free(target);
            fail(run, "out of memory balancing the ranks");
            return -1;
        }
        const int groups = groups_of_level(h->split, level);
        for (int gr = 0; gr < groups; gr++)
            for (int k = 1; k < h->split[level]; k++) {
                double *t = cut_at(run, target, level, gr, k);
                const double old = *cut_at(run, before, level, gr, k);
                const double next = old + 0.5 * (*t - old);
                moved |= next != old;
                *t = next;
            }
        free(before);
    }
    if (moved) {
        memcpy(h->cuts, target, h->cut_count * sizeof *target);
        boxes_from_cuts(run);
        h->balances++;
    }
    free(target);
    return moved;
}

/* ------------------------------------------------------------ migration -- */

/* The rank whose box holds x: a neighbour, else any (a balance moves the
 * cuts by more than a neighbour's width); -1 for a position that is not a
 * number (the grid build reports it). */
static int owner_of(const sluice_ranks_run *run, const double *x)
{
    const sluice_halo_lists *h = run->halo;
    for (int k = 0; k < h->neighbour_count; k++)
        if (box_holds(run, h->boxes + 6 * (size_t)h->neighbour[k], x))
            return h->neighbour[k];
    for (int r = 0; r < run->comm->size; r++)
        if (box_holds(run, h->boxes + 6 * (size_t)r, x))
            return r;
    return -1;
}

int sluice_ranks_migrate(sluice_ranks_run *run)
{
    const sluice_comm *c = run->comm;
    sluice_halo_lists *h = run->halo;
    sluice_particles *p = run->particles;
    const sluice_index n = p->count;
    const int size = c->size;
    const double box[6] = {h->lo[0], h->lo[1], h->lo[2], h->hi[0], h->hi[1], h->hi[2]};
    int *destination = malloc(((size_t)n + 1) * sizeof *destination);
    int *counts = calloc(4 * (size_t)size, sizeof *counts);
    uint8_t *away = calloc((size_t)n + 1, 1);
    int failed = !destination || !counts || !away;
    sluice_index leaving = 0;
    for (sluice_index i = 0; i < n && !failed; i++) {
        double x[3];
        position_of(run, p, i, x);
        destination[i] = -1;
        if (box_holds(run, box, x))
            continue;
        const int r = owner_of(run, x);
        if (r < 0 || r == c->rank)
            continue;
        destination[i] = r;
        counts[r]++;
        away[i] = 1;
        leaving++;
    }
    if (sluice_comm_any(c, failed)) {
        free(destination), free(counts), free(away);
        fail(run, "out of memory migrating particles on rank %d", c->rank);
        return -1;
    }
    /* counts[0 .. size): sent to each rank; [size, 2 size): received from
     * each; then the byte counts and displacements */
    int *sent = counts, *got = counts + size, *sdisp = counts + 2 * size,
        *rdisp = counts + 3 * size;
    MPI_Alltoall(sent, 1, MPI_INT, got, 1, MPI_INT, c->comm);
    const size_t row = row_bytes(p, every_column);
    unsigned long long out_total = 0, in_total = 0;
    for (int r = 0; r < size; r++) {
        out_total += (unsigned long long)sent[r];
        in_total += (unsigned long long)got[r];
    }
    failed = out_total * row > INT_MAX || in_total * row > INT_MAX;
    if (sluice_comm_any(c, failed)) {
        free(destination), free(counts), free(away);
        fail(run, "rank %d: a migration message exceeds 2 GB", c->rank);
        return -1;
    }
    /* pack by destination, each block column by column */
    char *send_block = malloc((size_t)out_total * row + 1);
    char *receive_block = malloc((size_t)in_total * row + 1);
    sluice_index *blocks = malloc(((size_t)size + 1) * sizeof *blocks);
    failed = !send_block || !receive_block || !blocks;
    if (sluice_comm_any(c, failed)) {
        free(destination), free(counts), free(away), free(send_block), free(receive_block),
            free(blocks);
        fail(run, "out of memory migrating particles on rank %d", c->rank);
        return -1;
    }
    char *out = send_block;
    for (int r = 0; r < size; r++) {
        if (!sent[r])
            continue;
        for (uint32_t col = 0; col < p->column_count; col++) {
            const size_t e = p->element_size[col];
            const char *base = p->columns[col];
            for (sluice_index i = 0; i < n; i++)
                if (destination[i] == r) {
                    memcpy(out, base + (size_t)i * e, e);
                    out += e;
                }
        }
    }
    int at = 0, in_at = 0;
    blocks[0] = 0;
    for (int r = 0; r < size; r++) {
        sdisp[r] = at;
        rdisp[r] = in_at;
        at += sent[r] * (int)row;
        in_at += got[r] * (int)row;
        blocks[r + 1] = blocks[r] + (sluice_index)got[r];
    }
    /* byte counts in place of the particle counts */
    int *sbytes = malloc(2 * (size_t)size * sizeof *sbytes);
    if (sluice_comm_any(c, sbytes == NULL)) {
        free(destination), free(counts), free(away), free(send_block), free(receive_block),
            free(blocks), free(sbytes);
        fail(run, "out of memory migrating particles on rank %d", c->rank);
        return -1;
    }
    int *rbytes = sbytes + size;
    for (int r = 0; r < size; r++) {
        sbytes[r] = sent[r] * (int)row;
        rbytes[r] = got[r] * (int)row;
    }
    MPI_Alltoallv(send_block, sbytes, sdisp, MPI_BYTE, receive_block, rbytes, rdisp, MPI_BYTE,
                  c->comm);
    free(sbytes);
    if (leaving)
        sluice_particles_compact(p, away);
    const sluice_index arriving = (sluice_index)in_total;
    if (arriving) {
        sluice_index first = 0;
        if (sluice_particles_append(p, arriving, &first) != 0) {
            free(destination), free(counts), free(away), free(send_block), free(receive_block),
                free(blocks);
            fail(run, "out of memory migrating particles on rank %d", c->rank);
            return -1;
        }
        unpack(p, receive_block, blocks, size, first, NULL, every_column);
        h->arrived += arriving;
    }
    free(destination), free(counts), free(away), free(send_block), free(receive_block),
        free(blocks);
    return 0;
}

/* ----------------------------------------------------------------- halo -- */

int sluice_ranks_collect_halo(void *context, sluice_particles *p, sluice_index *halo_count)
{
    sluice_ranks_run *run = context;
    sluice_halo_lists *h = run->halo;
    const sluice_index n = p->count;
    const double width = h->width;
    const uint32_t dims = dims_of(run);
    /* the particles within the halo width of this box's sides (the others
     * go to no neighbour), then the lists, neighbour by neighbour: those
     * within the halo width of its box */
    sluice_index *near = malloc(((size_t)n + 1) * sizeof *near), near_count = 0;
    int failed = near == NULL;
    for (sluice_index i = 0; i < n && !failed; i++) {
        double x[3];
        position_of(run, p, i, x);
        int interior = 1;
        for (uint32_t d = 0; d < dims && interior; d++) {
            const double v = wrap_axis(run->grid, d, x[d]);
            interior = v - h->lo[d] >= width && h->hi[d] - v >= width;
        }
        if (!interior)
            near[near_count++] = i;
    }
    sluice_index listed = 0;
    for (int k = 0; k < h->neighbour_count && !failed; k++) {
        h->send_begin[k] = listed;
        const double *box = h->boxes + 6 * (size_t)h->neighbour[k];
        for (sluice_index m = 0; m < near_count; m++) {
            double x[3];
            position_of(run, p, near[m], x);
            if (!near_box(run, box, x, width))
                continue;
            if (listed == h->send_capacity) {
                sluice_index cap = h->send_capacity ? 2 * h->send_capacity : 1024;
                sluice_index *grown = realloc(h->send, (size_t)cap * sizeof *grown);
                if (!grown) {
                    failed = 1;
                    break;
                }
                h->send = grown;
                h->send_capacity = cap;
            }
            h->send[listed++] = near[m];
        }
    }
    free(near);
    h->send_begin[h->neighbour_count] = listed;
    if (failed || pack(run, h, every_column) != 0) {
        fail(run, "out of memory for the halo of rank %d", run->comm->rank);
        return -1;
    }
    if (exchange(run, h, every_column) != 0)
        return -1;
    const sluice_index got = h->receive_begin[h->neighbour_count];
    if (sluice_particles_reserve(p, n + got) != 0) {
        fail(run, "out of memory for the halo of rank %d", run->comm->rank);
        return -1;
    }
    unpack(p, h->buffer[1], h->receive_begin, h->neighbour_count, n, NULL, every_column);
    /* the real columns no refresh sends hold NaN in the halo: a term that
     * reads one at a neighbour without declaring it fails loudly (the
     * watchdog's NaN) instead of using values one rebuild old */
    uint32_t next = 0;
    for (uint32_t c = 0; c < p->column_count; c++) {
        if (next < h->column_count && h->columns[next] == c) {
            next++;
            continue;
        }
        if (p->element_size[c] != sizeof(sluice_real) || !h->real_column[c])
            continue;
        sluice_real *column = p->columns[c];
        for (sluice_index k = 0; k < got; k++)
            column[n + k] = (sluice_real)NAN;
    }
    *halo_count = got;
    return 0;
}

/* After the grid sorted the halo: the slot of each received entry. */
static int halo_slots(sluice_ranks_run *run)
{
    sluice_halo_lists *h = run->halo;
    const sluice_index got = run->grid->halo_count;
    if (got > h->slot_capacity) {
        sluice_index cap = got + got / 4 + 64;
        sluice_index *s = realloc(h->slot, (size_t)cap * sizeof *s);
        if (!s)
            return -1;
        h->slot = s;
        h->slot_capacity = cap;
    }
    for (sluice_index s = 0; s < got; s++)
        h->slot[run->grid->halo_order[s]] = s;
    return 0;
}

int sluice_ranks_refresh_halo(sluice_ranks_run *run)
{
    sluice_halo_lists *h = run->halo;
    if (h->slot_valid_at != run->grid->rebuilds) {
        if (halo_slots(run) != 0) {
            fail(run, "out of memory for the halo of rank %d", run->comm->rank);
            return -1;
        }
        h->slot_valid_at = run->grid->rebuilds;
    }
    const column_set refreshed = {h->columns, h->column_count};
    if (pack(run, h, refreshed) != 0) {
        fail(run, "out of memory for the halo of rank %d", run->comm->rank);
        return -1;
    }
    const sluice_index expected = h->receive_begin[h->neighbour_count];
    if (exchange(run, h, refreshed) != 0)
        return -1;
    if (h->receive_begin[h->neighbour_count] != expected) {
        fail(run, "rank %d: the halo changed size between rebuilds", run->comm->rank);
        return -1;
    }
    unpack(run->particles, h->buffer[1], h->receive_begin, h->neighbour_count,
           run->particles->count, h->slot, refreshed);
    return 0;
}

#else
typedef int sluice_ranks_unused;
#endif
