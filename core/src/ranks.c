#include "ranks.h"

#ifdef SLUICE_MPI

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"

void sluice_ranks_free(sluice_halo_lists *lists)
{
    for (int s = 0; s < 2; s++) {
        free(lists->send[s]);
        free(lists->buffer[s]);
    }
    free(lists->slot);
    memset(lists, 0, sizeof *lists);
}

int sluice_ranks_gather(sluice_sim *sim, sluice_particles *all)
{
    const sluice_comm *c = &sim->comm;
    const sluice_particles *p = &sim->particles;
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

static int compare_real(const void *a, const void *b)
{
    sluice_real x = *(const sluice_real *)a, y = *(const sluice_real *)b;
    return (x > y) - (x < y);
}

static size_t row_bytes(const sluice_particles *p)
{
    size_t b = 0;
    for (uint32_t c = 0; c < p->column_count; c++)
        b += p->element_size[c];
    return b;
}

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

static int list_push(sluice_halo_lists *h, int side, sluice_index i)
{
    if (h->send_count[side] == h->send_capacity[side]) {
        sluice_index cap = h->send_capacity[side] ? 2 * h->send_capacity[side] : 1024;
        sluice_index *grown = realloc(h->send[side], (size_t)cap * sizeof *grown);
        if (!grown)
            return -1;
        h->send[side] = grown;
        h->send_capacity[side] = cap;
    }
    h->send[side][h->send_count[side]++] = i;
    return 0;
}

/* Packs the rows send[0] (then send[1]) column by column into buffer[0]. */
static int pack(sluice_sim *sim, sluice_halo_lists *h)
{
    const sluice_particles *p = &sim->particles;
    const size_t row = row_bytes(p);
    const size_t total = (size_t)(h->send_count[0] + h->send_count[1]) * row;
    if (grow((void **)&h->buffer[0], &h->buffer_capacity[0], total) != 0)
        return -1;
    char *out = h->buffer[0];
    for (int side = 0; side < 2; side++)
        for (uint32_t c = 0; c < p->column_count; c++) {
            const size_t e = p->element_size[c];
            const char *base = p->columns[c];
            const sluice_index *list = h->send[side];
            for (sluice_index k = 0; k < h->send_count[side]; k++, out += e)
                memcpy(out, base + (size_t)list[k] * e, e);
        }
    return 0;
}

/* Sends buffer[0] (the left block, then the right) to the neighbours and
 * receives theirs into buffer[1] (from the left, then from the right);
 * receive_count[] gets their counts. Collective over the neighbours. */
static int swap(sluice_sim *sim, sluice_halo_lists *h)
{
    const sluice_comm *c = &sim->comm;
    const int left = c->rank > 0 ? c->rank - 1 : MPI_PROC_NULL;
    const int right = c->rank + 1 < c->size ? c->rank + 1 : MPI_PROC_NULL;
    const size_t row = row_bytes(&sim->particles);
    unsigned long long sent[2] = {h->send_count[0], h->send_count[1]}, got[2] = {0, 0};
    MPI_Sendrecv(&sent[0], 1, MPI_UNSIGNED_LONG_LONG, left, 11, &got[1], 1,
                 MPI_UNSIGNED_LONG_LONG, right, 11, c->comm, MPI_STATUS_IGNORE);
    MPI_Sendrecv(&sent[1], 1, MPI_UNSIGNED_LONG_LONG, right, 12, &got[0], 1,
                 MPI_UNSIGNED_LONG_LONG, left, 12, c->comm, MPI_STATUS_IGNORE);
    if ((sent[0] + sent[1]) * row > INT_MAX || (got[0] + got[1]) * row > INT_MAX) {
        sluice_sim_fail(sim, "rank %d: a halo or migration message exceeds 2 GB", c->rank);
        return -1;
    }
    h->receive_count[0] = (sluice_index)got[0];
    h->receive_count[1] = (sluice_index)got[1];
    if (grow((void **)&h->buffer[1], &h->buffer_capacity[1], (size_t)(got[0] + got[1]) * row) !=
        0) {
        sluice_sim_fail(sim, "out of memory for the halo of rank %d", c->rank);
        return -1;
    }
    /* blocks are column-major per side: [side 0: every column][side 1: ...] */
    char *send_left = h->buffer[0], *send_right = h->buffer[0] + (size_t)sent[0] * row;
    char *from_left = h->buffer[1], *from_right = h->buffer[1] + (size_t)got[0] * row;
    MPI_Sendrecv(send_left, (int)(sent[0] * row), MPI_BYTE, left, 13, from_right,
                 (int)(got[1] * row), MPI_BYTE, right, 13, c->comm, MPI_STATUS_IGNORE);
    MPI_Sendrecv(send_right, (int)(sent[1] * row), MPI_BYTE, right, 14, from_left,
                 (int)(got[0] * row), MPI_BYTE, left, 14, c->comm, MPI_STATUS_IGNORE);
    return 0;
}

/* Writes the received rows (from the left, then from the right) to the store
 * rows first + k, or first + slot[k] when slot is given. */
static void unpack(sluice_particles *p, const sluice_halo_lists *h, sluice_index first,
                   const sluice_index *slot)
{
    const char *in = h->buffer[1];
    sluice_index k0 = 0;
    for (int side = 0; side < 2; side++) {
        const sluice_index n = h->receive_count[side];
        for (uint32_t c = 0; c < p->column_count; c++) {
            const size_t e = p->element_size[c];
            char *base = p->columns[c];
            for (sluice_index k = 0; k < n; k++, in += e) {
                const sluice_index to = first + (slot ? slot[k0 + k] : k0 + k);
                memcpy(base + (size_t)to * e, in, e);
            }
        }
        k0 += n;
    }
}

enum { SEND_MIGRANTS, SEND_HALO };

/* Lists the rank's particles to send left and right (the particles that left
 * the slab, or those within the halo width of its sides), packs them and
 * swaps them with the neighbours' into buffer[1]. Collective. */
static int send_to_neighbours(sluice_sim *sim, int what)
{
    sluice_halo_lists *h = &sim->halo;
    const sluice_index n = sim->particles.count;
    const sluice_real *x = sim->particles.columns[sim->position.column];
    const int has_left = sim->comm.rank > 0, has_right = sim->comm.rank + 1 < sim->comm.size;
    h->send_count[0] = h->send_count[1] = 0;
    int failed = 0;
    for (sluice_index i = 0; i < n && !failed; i++) {
        const double xi = (double)x[i]; /* NaN stays: the grid build reports it */
        if (what == SEND_MIGRANTS) {
            if (xi < h->slab_lo)
                failed = list_push(h, 0, i);
            else if (xi >= h->slab_hi)
                failed = list_push(h, 1, i);
        } else {
            if (has_left && xi < h->slab_lo + h->width)
                failed = list_push(h, 0, i);
            if (!failed && has_right && xi >= h->slab_hi - h->width)
                failed = list_push(h, 1, i);
        }
    }
    if (failed || pack(sim, h) != 0) {
        sluice_sim_fail(sim, "out of memory %s on rank %d",
                        what == SEND_MIGRANTS ? "migrating particles" : "for the halo",
                        sim->comm.rank);
        return -1;
    }
    return swap(sim, h);
}

int sluice_ranks_split(sluice_sim *sim)
{
    const sluice_comm *c = &sim->comm;
    sluice_halo_lists *h = &sim->halo;
    sluice_particles *p = &sim->particles;
    /* the halo holds every particle a pass of this rank's particles may
     * reach: the support, or the longest reach of a term beyond it
     * (api->request_reach), from points up to the largest point margin
     * outside the slab (api->point_pass_local), plus the neighbour skin */
    double reach = (double)sim->grid.support;
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if ((double)sim->instances[k].reach > reach)
            reach = (double)sim->instances[k].reach;
    h->width = reach + (double)sim->point_margin + (double)sim->grid.skin;
    if (sim->grid.periodic[0]) {
        sluice_sim_fail(sim, "a periodic x axis cannot be split across ranks yet (%d ranks; "
                             "docs/scaling.md)", c->size);
        return -1;
    }
    const sluice_index n = p->count;
    const sluice_real *x = p->columns[sim->position.column];
    sluice_real *sorted = malloc(((size_t)n + 1) * sizeof *sorted);
    double *bound = malloc(((size_t)c->size + 1) * sizeof *bound);
    uint8_t *away = calloc((size_t)n + 1, 1);
    if (!sorted || !bound || !away) {
        free(sorted);
        free(bound);
        free(away);
        sluice_sim_fail(sim, "out of memory splitting %u particles across %d ranks", n, c->size);
        return -1;
    }
    memcpy(sorted, x, (size_t)n * sizeof *sorted);
    qsort(sorted, n, sizeof *sorted, compare_real);
    bound[0] = -INFINITY;
    bound[c->size] = INFINITY;
    for (int r = 1; r < c->size; r++) {
        size_t k = (size_t)((uint64_t)r * n / (uint64_t)c->size);
        bound[r] = k == 0 ? (double)sorted[0] : 0.5 * ((double)sorted[k - 1] + (double)sorted[k]);
    }
    int narrow = -1;
    for (int r = 1; r + 1 < c->size; r++)
        if (!(bound[r + 1] - bound[r] >= h->width))
            narrow = r;
    if (narrow >= 0) {
        sluice_sim_fail(sim,
                        "%d ranks split the %u particles into slabs along x narrower than the "
                        "halo (the kernel support or a longer reach, plus the point margin and "
                        "the neighbour skin: %.6g m): slab %d is [%.6g, %.6g) m; use fewer ranks",
                        c->size, n, h->width, narrow, bound[narrow], bound[narrow + 1]);
        free(sorted);
        free(bound);
        free(away);
        return -1;
    }
    h->slab_lo = bound[c->rank];
    h->slab_hi = bound[c->rank + 1];
    for (sluice_index i = 0; i < n; i++)
        away[i] = !((double)x[i] >= h->slab_lo && (double)x[i] < h->slab_hi);
    sluice_particles_compact(p, away);
    free(sorted);
    free(bound);
    free(away);
    sluice_sim_refresh_view(sim);
    return 0;
}

int sluice_ranks_balance(sluice_sim *sim)
{
    const sluice_comm *c = &sim->comm;
    sluice_halo_lists *h = &sim->halo;
    const int balance = sim->scene.ranks.balance;
    if (balance == SLUICE_BALANCE_NONE ||
        sim->step < h->balance_step + sim->scene.ranks.every)
        return 0;
    h->balance_step = sim->step;
    const int size = c->size;
    /* every rank's work (time, or particles) and particles */
    double mine[2] = {balance == SLUICE_BALANCE_TIME ? h->busy_seconds
                                                     : (double)sim->particles.count,
                      (double)sim->particles.count};
    double *all = malloc(2 * (size_t)size * sizeof *all);
    double *bound = malloc(((size_t)size + 1) * sizeof *bound);
    double *proposed = malloc(((size_t)size + 1) * sizeof *proposed);
    int failed = !all || !bound || !proposed;
    if (sluice_comm_any(c, failed)) {
        free(all), free(bound), free(proposed);
        sluice_sim_fail(sim, "out of memory balancing the ranks");
        return -1;
    }
    MPI_Allgather(mine, 2, MPI_DOUBLE, all, 2, MPI_DOUBLE, c->comm);
    /* the current boundaries: rank r's slab starts at bound[r] */
    double slab_lo = h->slab_lo;
    MPI_Allgather(&slab_lo, 1, MPI_DOUBLE, bound, 1, MPI_DOUBLE, c->comm);
    bound[size] = INFINITY;
    h->busy_seconds = 0;
    double total = 0, largest = 0;
    for (int r = 0; r < size; r++) {
        total += all[2 * r];
        largest = all[2 * r] > largest ? all[2 * r] : largest;
    }
    const double mean = total / size;
    for (int k = 0; k <= size; k++)
        proposed[k] = -INFINITY;
    if (mean > 0 && largest > (1 + (double)sim->scene.ranks.tolerance) * mean) {
        /* boundary k (between ranks k - 1 and k): the work left of it
         * against its share; the rank with the excess gives half of it, in
         * particles at its cost per particle, from its side of the boundary */
        double left = 0;
        for (int k = 1; k < size; k++) {
            left += all[2 * (k - 1)];
            const double excess = 0.5 * (left - k * mean);
            const int giver = excess > 0 ? k - 1 : k;
            if (giver != c->rank)
                continue;
            const double count = all[2 * giver + 1], cost = count > 0 ? all[2 * giver] / count : 0;
            if (!(cost > 0) || count < 2)
                continue;
            sluice_index move = (sluice_index)fmin(fabs(excess) / cost, count / 2);
            if (move == 0)
                continue;
            /* the cut among this rank's x, sorted */
            const sluice_index n = sim->particles.count;
            const sluice_real *x = sim->particles.columns[sim->position.column];
            sluice_real *sorted = malloc(((size_t)n + 1) * sizeof *sorted);
            if (!sorted)
                continue; /* no move: the balance waits for the next time */
            memcpy(sorted, x, (size_t)n * sizeof *sorted);
            qsort(sorted, n, sizeof *sorted, compare_real);
            const sluice_index at = excess > 0 ? n - move : move;
            double cut = 0.5 * ((double)sorted[at - 1] + (double)sorted[at]);
            /* within the old neighbouring slabs, each at least the halo
             * width wide, so that a particle crosses one boundary only */
            const double floor_at = bound[k - 1] + h->width, ceiling = bound[k + 1] - h->width;
            if (cut < floor_at)
                cut = floor_at;
            if (cut > ceiling)
                cut = ceiling;
            if (cut > floor_at && cut < ceiling)
                proposed[k] = cut;
            free(sorted);
        }
    }
    MPI_Allreduce(MPI_IN_PLACE, proposed, size + 1, MPI_DOUBLE, MPI_MAX, c->comm);
    /* boundaries moved both ways may come too close: keep the slabs wide */
    int moved = 0;
    for (int k = 1; k < size; k++) {
        if (!(proposed[k] > -INFINITY))
            continue;
        /* bound[k - 1] is final here, bound[k + 1] not yet moved */
        if (proposed[k] - bound[k - 1] < h->width || bound[k + 1] - proposed[k] < h->width)
            continue;
        bound[k] = proposed[k];
        moved = 1;
    }
    if (moved) {
        h->slab_lo = c->rank == 0 ? -INFINITY : bound[c->rank];
        h->slab_hi = c->rank + 1 == size ? INFINITY : bound[c->rank + 1];
        h->balances++;
    }
    free(all), free(bound), free(proposed);
    return moved;
}

int sluice_ranks_migrate(sluice_sim *sim)
{
    sluice_halo_lists *h = &sim->halo;
    sluice_particles *p = &sim->particles;
    const sluice_index n = p->count;
    if (send_to_neighbours(sim, SEND_MIGRANTS) != 0)
        return -1;
    const sluice_index leaving = h->send_count[0] + h->send_count[1];
    if (leaving) {
        uint8_t *away = calloc((size_t)n + 1, 1);
        if (!away) {
            sluice_sim_fail(sim, "out of memory migrating particles on rank %d", sim->comm.rank);
            return -1;
        }
        for (int side = 0; side < 2; side++)
            for (sluice_index k = 0; k < h->send_count[side]; k++)
                away[h->send[side][k]] = 1;
        sluice_particles_compact(p, away);
        free(away);
    }
    const sluice_index arriving = h->receive_count[0] + h->receive_count[1];
    if (arriving) {
        sluice_index first = 0;
        if (sluice_particles_append(p, arriving, &first) != 0) {
            sluice_sim_fail(sim, "out of memory migrating particles on rank %d", sim->comm.rank);
            return -1;
        }
        unpack(p, h, first, NULL);
        h->arrived += arriving;
        /* a particle may cross one slab boundary per rebuild (it moves less
         * than the skin between rebuilds, and slabs are wider) */
        const sluice_real *xn = p->columns[sim->position.column];
        for (sluice_index k = first; k < p->count; k++)
            if (!((double)xn[k] >= h->slab_lo && (double)xn[k] < h->slab_hi) &&
                xn[k] == xn[k]) {
                sluice_sim_fail(sim,
                                "step %lld: particle id %llu at x = %.6g m crossed more than one "
                                "slab (rank %d holds [%.6g, %.6g) m)",
                                (long long)sim->step,
                                (unsigned long long)((const sluice_id *)
                                                         p->columns[sim->id.column])[k],
                                (double)xn[k], sim->comm.rank, h->slab_lo, h->slab_hi);
                return -1;
            }
    }
    sluice_sim_refresh_view(sim);
    return 0;
}

int sluice_ranks_collect_halo(void *context, sluice_particles *p, sluice_index *halo_count)
{
    sluice_sim *sim = context;
    sluice_halo_lists *h = &sim->halo;
    const sluice_index n = p->count;
    if (send_to_neighbours(sim, SEND_HALO) != 0)
        return -1;
    const sluice_index got = h->receive_count[0] + h->receive_count[1];
    if (sluice_particles_reserve(p, n + got) != 0) {
        sluice_sim_fail(sim, "out of memory for the halo of rank %d", sim->comm.rank);
        return -1;
    }
    unpack(p, h, n, NULL);
    *halo_count = got;
    return 0;
}

/* After the grid sorted the halo: the slot of each received entry. */
static int halo_slots(sluice_sim *sim)
{
    sluice_halo_lists *h = &sim->halo;
    const sluice_index got = sim->grid.halo_count;
    if (got > h->slot_capacity) {
        sluice_index cap = got + got / 4 + 64;
        sluice_index *s = realloc(h->slot, (size_t)cap * sizeof *s);
        if (!s)
            return -1;
        h->slot = s;
        h->slot_capacity = cap;
    }
    for (sluice_index s = 0; s < got; s++)
        h->slot[sim->grid.halo_order[s]] = s;
    return 0;
}

int sluice_ranks_refresh_halo(sluice_sim *sim)
{
    sluice_halo_lists *h = &sim->halo;
    if (h->slot_valid_at != sim->grid.rebuilds) {
        if (halo_slots(sim) != 0) {
            sluice_sim_fail(sim, "out of memory for the halo of rank %d", sim->comm.rank);
            return -1;
        }
        h->slot_valid_at = sim->grid.rebuilds;
    }
    if (pack(sim, h) != 0) {
        sluice_sim_fail(sim, "out of memory for the halo of rank %d", sim->comm.rank);
        return -1;
    }
    const sluice_index expected0 = h->receive_count[0], expected1 = h->receive_count[1];
    if (swap(sim, h) != 0)
        return -1;
    if (h->receive_count[0] != expected0 || h->receive_count[1] != expected1) {
        sluice_sim_fail(sim, "rank %d: the halo changed size between rebuilds", sim->comm.rank);
        return -1;
    }
    unpack(&sim->particles, h, sim->particles.count, h->slot);
    return 0;
}

#else
typedef int sluice_ranks_unused;
#endif
