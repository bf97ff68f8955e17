#include "pairs.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#define TARGET_CHUNK 64

static void *aligned_array(size_t count, size_t size)
{
    size_t bytes = (count * size + 63) / 64 * 64;
    return aligned_alloc(64, bytes ? bytes : 64);
}

static void workspace_free(sluice_pair_workspace *w)
{
    free(w->target);
    free(w->pair_begin);
    free(w->neighbour);
    free(w->neighbour_kind);
    for (int d = 0; d < 3; d++)
        free(w->offset[d]);
    free(w->distance_squared);
    free(w->distance);
    free(w->kernel);
    free(w->gradient);
    free(w->gathered_storage);
    free(w->gathered);
    w->target = w->pair_begin = w->neighbour = NULL;
    w->neighbour_kind = NULL;
    w->offset[0] = w->offset[1] = w->offset[2] = NULL;
    w->distance_squared = w->distance = w->kernel = w->gradient = w->gathered_storage = NULL;
    w->gathered = NULL;
    w->pair_capacity = w->target_capacity = 0;
}

/* (Re)allocates a workspace for `pairs` pairs and `slots` gathered columns. */
static int workspace_reserve(sluice_pair_workspace *w, sluice_index pairs, uint32_t slots)
{
    if (w->pair_capacity >= pairs && w->gathered_slots >= slots && w->gathered)
        return 0;
    sluice_index cap = w->pair_capacity > pairs ? w->pair_capacity : pairs;
    uint32_t s = w->gathered_slots > slots ? w->gathered_slots : slots;
    uint32_t columns = w->column_count;
    uint64_t p = w->pairs, b = w->batches, kind_pairs[SLUICE_KIND_COUNT];
    double kind_seconds[SLUICE_KIND_COUNT];
    memcpy(kind_pairs, w->kind_pairs, sizeof kind_pairs);
    memcpy(kind_seconds, w->kind_seconds, sizeof kind_seconds);
    workspace_free(w);
    w->column_count = columns;
    w->pairs = p;
    w->batches = b;
    memcpy(w->kind_pairs, kind_pairs, sizeof kind_pairs);
    memcpy(w->kind_seconds, kind_seconds, sizeof kind_seconds);
    sluice_index targets = (cap > TARGET_CHUNK ? cap : TARGET_CHUNK) + 1;
    w->target = aligned_array(targets, sizeof(sluice_index));
    w->pair_begin = aligned_array(targets + 1, sizeof(sluice_index));
    w->neighbour = aligned_array(cap, sizeof(sluice_index));
    w->neighbour_kind = aligned_array(cap, 1);
    for (int d = 0; d < 3; d++)
        w->offset[d] = aligned_array(cap, sizeof(sluice_real));
    w->distance_squared = aligned_array(cap, sizeof(sluice_real));
    w->distance = aligned_array(cap, sizeof(sluice_real));
    w->kernel = aligned_array(cap, sizeof(sluice_real));
    w->gradient = aligned_array(cap, sizeof(sluice_real));
    w->gathered_storage = aligned_array((size_t)cap * (s ? s : 1), sizeof(sluice_real));
    w->gathered = calloc(columns ? columns : 1, sizeof *w->gathered);
    if (!w->target || !w->pair_begin || !w->neighbour || !w->neighbour_kind || !w->offset[0] ||
        !w->offset[1] || !w->offset[2] || !w->distance_squared || !w->distance || !w->kernel || !w->gradient ||
        !w->gathered_storage || !w->gathered) {
        workspace_free(w);
        return -1;
    }
    w->pair_capacity = cap;
    w->target_capacity = targets;
    w->gathered_slots = s;
    return 0;
}

int sluice_pair_engine_init(sluice_pair_engine *engine, int thread_count, sluice_index batch_pairs,
                            uint32_t column_count)
{
    memset(engine, 0, sizeof *engine);
    engine->thread_count = thread_count > 0 ? thread_count : 1;
    engine->batch_pairs = batch_pairs ? batch_pairs : 1024;
    engine->workspaces = calloc((size_t)engine->thread_count, sizeof *engine->workspaces);
    if (!engine->workspaces)
        return -1;
    for (int t = 0; t < engine->thread_count; t++)
        engine->workspaces[t].column_count = column_count;
    return 0;
}

void sluice_pair_engine_free(sluice_pair_engine *engine)
{
    if (engine->workspaces)
        for (int t = 0; t < engine->thread_count; t++)
            workspace_free(&engine->workspaces[t]);
    free(engine->workspaces);
    memset(engine, 0, sizeof *engine);
}

uint64_t sluice_pair_engine_pairs(const sluice_pair_engine *engine)
{
    uint64_t n = 0;
    for (int t = 0; t < engine->thread_count; t++)
        n += engine->workspaces[t].pairs;
    return n;
}

uint64_t sluice_pair_engine_kind_pairs(const sluice_pair_engine *engine, uint32_t kind)
{
    uint64_t n = 0;
    for (int t = 0; t < engine->thread_count && kind < SLUICE_KIND_COUNT; t++)
        n += engine->workspaces[t].kind_pairs[kind];
    return n;
}

double sluice_pair_engine_kind_seconds(const sluice_pair_engine *engine, uint32_t kind)
{
    double s = 0;
    for (int t = 0; t < engine->thread_count && kind < SLUICE_KIND_COUNT; t++)
        s += engine->workspaces[t].kind_seconds[kind];
    return s;
}

size_t sluice_pair_engine_bytes(const sluice_pair_engine *engine)
{
    size_t b = 0;
    for (int t = 0; t < engine->thread_count; t++) {
        const sluice_pair_workspace *w = &engine->workspaces[t];
        b += (size_t)w->pair_capacity * (2 * sizeof(sluice_index) + 1 + 7 * sizeof(sluice_real) +
                                         w->gathered_slots * sizeof(sluice_real));
    }
    return b;
}

/* Completes the batch in w (targets of kind `kind`) and hands it to the terms. */
static void flush(sluice_pair_engine *engine, const sluice_pair_pass *pass,
                  const sluice_view *view, sluice_pair_workspace *w, sluice_index targets,
                  sluice_index pairs, uint32_t kind)
{
    if (targets == 0)
        return;
    sluice_real *restrict r = w->distance;
    const int reach = pass->reach > 0; /* beyond the support: no kernel values */
    if (reach) {
        const sluice_real *restrict r2 = w->distance_squared;
        for (sluice_index p = 0; p < pairs; p++)
            r[p] = sqrt(r2[p]);
    } else {
        engine->kernel->kernel(engine->kernel_state, pairs, w->distance_squared, r,
                               pass->needs_kernel[kind] ? w->kernel : NULL, w->gradient);
    }
    const sluice_index *restrict nb = w->neighbour;
    const uint8_t *restrict kinds = view->kind;
    uint8_t *restrict nk = w->neighbour_kind;
    uint32_t present = 0; /* the kinds that do appear as j */
    for (sluice_index p = 0; p < pairs; p++) {
        nk[p] = kinds[nb[p]];
        present |= 1u << nk[p];
    }
    for (uint32_t g = 0; g < pass->gathered_count[kind]; g++) {
        uint32_t column = pass->gathered_columns[kind][g];
        const sluice_real *restrict src = view->columns[column];
        sluice_real *restrict dst = w->gathered_storage + (size_t)g * w->pair_capacity;
#pragma omp simd
        for (sluice_index p = 0; p < pairs; p++)
            dst[p] = src[nb[p]];
        w->gathered[column] = dst;
    }
    sluice_pair_batch batch;
    batch.target_count = targets;
    batch.target = w->target;
    batch.pair_begin = w->pair_begin;
    batch.pair_count = pairs;
    batch.neighbour = w->neighbour;
    batch.neighbour_kind = w->neighbour_kind;
    batch.neighbour_kinds = pass->neighbour_mask[kind] & present;
    batch.offset[0] = w->offset[0];
    batch.offset[1] = w->offset[1];
    batch.offset[2] = view->dimensions == 3 ? w->offset[2] : NULL;
    batch.distance = r;
    batch.kernel = !reach && pass->needs_kernel[kind] ? w->kernel : NULL;
    batch.kernel_gradient = reach ? NULL : w->gradient;
    batch.gathered = w->gathered;
    batch.kernel_self = engine->kernel_self;
    for (uint32_t t = 0; t < pass->term_count; t++) {
        const sluice_pair_term *term = &pass->terms[t];
        if (term->target_kinds & SLUICE_KIND_MASK(kind))
            term->component->pair(term->state, view, &batch);
    }
    w->pairs += pairs;
    w->batches++;
    /* a column gathered for this kind must not leak into a batch of another */
    for (uint32_t g = 0; g < pass->gathered_count[kind]; g++)
        w->gathered[pass->gathered_columns[kind][g]] = NULL;
}

/* Opens target i's segment of w's batch for up to `candidates` pairs:
 * flushes the batch (targets of kind `kind`) when they would not fit, and
 * grows the workspace when one target's do not fit an empty one. Returns 0,
 * or -1 when it could not grow. */
static inline int batch_open(sluice_pair_engine *engine, const sluice_pair_pass *pass,
                             const sluice_view *view, sluice_pair_workspace *w, sluice_index *t,
                             sluice_index *np, sluice_index candidates, uint32_t kind,
                             sluice_index i)
{
    if ((*np + candidates > w->pair_capacity || *t + 1 >= w->target_capacity) && *t > 0) {
        w->pair_begin[*t] = *np;
        flush(engine, pass, view, w, *t, *np, kind);
        *t = 0;
        *np = 0;
    }
    if (candidates > w->pair_capacity) {
        if (workspace_reserve(w, candidates, pass->gathered_max) != 0)
            return -1;
        for (uint32_t c = 0; c < w->column_count; c++)
            w->gathered[c] = NULL;
    }
    w->target[*t] = i;
    w->pair_begin[*t] = *np;
    return 0;
}

static inline double minimum_image(double dx, double length)
{
    return dx - length * nearbyint(dx / length);
}

/* Appends the pairs of target i within the support to the workspace, from
 * its Verlet-list candidates m0 .. m1 - 1; returns the new pair count. The
 * flags are compile-time constants in each specialisation below, so the
 * loop carries no test of the dimension, periodicity or kind mask. */
static inline sluice_index fill_target(sluice_pair_workspace *restrict w, const sluice_grid *grid,
                                       const sluice_view *view, sluice_index i,
                                       const sluice_index *restrict list, sluice_index m0,
                                       sluice_index m1, sluice_index np, double support2,
                                       uint32_t mask, const int dims, const int periodic,
                                       const int all_kinds)
{
    const sluice_real *restrict x = view->position[0], *restrict y = view->position[1];
    const sluice_real *restrict z = dims == 3 ? view->position[2] : view->position[1];
    const uint8_t *restrict kind = view->kind;
    sluice_index *restrict nb = w->neighbour;
    sluice_real *restrict ox = w->offset[0], *restrict oy = w->offset[1],
                          *restrict oz = w->offset[2];
    sluice_real *restrict r2 = w->distance_squared;
    const double xi = (double)x[i], yi = (double)y[i], zi = dims == 3 ? (double)z[i] : 0.0;
    const double lx = grid->length[0], ly = grid->length[1], lz = grid->length[2];
    const int px = periodic && grid->periodic[0], py = periodic && grid->periodic[1],
              pz = periodic && dims == 3 && grid->periodic[2];
    for (sluice_index m = m0; m < m1; m++) {
        const sluice_index j = list[m];
        double dx = xi - (double)x[j];
        double dy = yi - (double)y[j];
        double dz = dims == 3 ? zi - (double)z[j] : 0.0;
        if (periodic) {
            if (px)
                dx = minimum_image(dx, lx);
            if (py)
                dy = minimum_image(dy, ly);
            if (pz)
                dz = minimum_image(dz, lz);
        }
        const double s = dx * dx + dy * dy + dz * dz;
        nb[np] = j;
        ox[np] = (sluice_real)dx;
        oy[np] = (sluice_real)dy;
        if (dims == 3)
            oz[np] = (sluice_real)dz;
        r2[np] = (sluice_real)s;
        if (all_kinds)
            np += (sluice_index)(s < support2);
        else
            np += (sluice_index)((s < support2) & ((mask >> kind[j]) & 1u));
    }
    return np;
}

#if defined(__AVX2__) && defined(__FMA__)
/* The same with AVX2, four candidates at a time: their positions loaded,
 * r^2 and the support test in vector registers, and the candidates within
 * the support (of a kind the pass asks for) moved to the front of the
 * vectors by a lane permutation and stored, four lanes at a time, at np
 * (the workspace has room for every candidate, so the lanes stored past
 * the kept ones lie within it and are overwritten next). Non-periodic
 * grids, double precision, fewer than 2^31 particles (callers check). */
static const int32_t compress_reals[16][8] = {
    {0, 0, 0, 0, 0, 0, 0, 0},
    {0, 1, 0, 0, 0, 0, 0, 0},
    {2, 3, 0, 0, 0, 0, 0, 0},
    {0, 1, 2, 3, 0, 0, 0, 0},
    {4, 5, 0, 0, 0, 0, 0, 0},
    {0, 1, 4, 5, 0, 0, 0, 0},
    {2, 3, 4, 5, 0, 0, 0, 0},
    {0, 1, 2, 3, 4, 5, 0, 0},
    {6, 7, 0, 0, 0, 0, 0, 0},
    {0, 1, 6, 7, 0, 0, 0, 0},
    {2, 3, 6, 7, 0, 0, 0, 0},
    {0, 1, 2, 3, 6, 7, 0, 0},
    {4, 5, 6, 7, 0, 0, 0, 0},
    {0, 1, 4, 5, 6, 7, 0, 0},
    {2, 3, 4, 5, 6, 7, 0, 0},
    {0, 1, 2, 3, 4, 5, 6, 7}};
static const int32_t compress_indices[16][8] = {
    {0, 0, 0, 0, 0, 0, 0, 0},
    {0, 0, 0, 0, 0, 0, 0, 0},
    {1, 0, 0, 0, 0, 0, 0, 0},
    {0, 1, 0, 0, 0, 0, 0, 0},
    {2, 0, 0, 0, 0, 0, 0, 0},
    {0, 2, 0, 0, 0, 0, 0, 0},
    {1, 2, 0, 0, 0, 0, 0, 0},
    {0, 1, 2, 0, 0, 0, 0, 0},
    {3, 0, 0, 0, 0, 0, 0, 0},
    {0, 3, 0, 0, 0, 0, 0, 0},
    {1, 3, 0, 0, 0, 0, 0, 0},
    {0, 1, 3, 0, 0, 0, 0, 0},
    {2, 3, 0, 0, 0, 0, 0, 0},
    {0, 2, 3, 0, 0, 0, 0, 0},
    {1, 2, 3, 0, 0, 0, 0, 0},
    {0, 1, 2, 3, 0, 0, 0, 0}};

static inline sluice_index fill_target_avx2(sluice_pair_workspace *restrict w,
                                            const sluice_grid *grid, const sluice_view *view,
                                            sluice_index i,
                                            const sluice_index *restrict list, sluice_index m0,
                                            sluice_index m1, sluice_index np, double support2,
                                            uint32_t mask, const int dims, const int all_kinds)
{
    const double *restrict x = (const double *)view->position[0];
    const double *restrict y = (const double *)view->position[1];
    const double *restrict z = dims == 3 ? (const double *)view->position[2] : y;
    const uint8_t *restrict kind = view->kind;
    sluice_index *restrict nb = w->neighbour;
    double *restrict ox = (double *)w->offset[0], *restrict oy = (double *)w->offset[1],
                     *restrict oz = (double *)w->offset[2];
    double *restrict r2 = (double *)w->distance_squared;
    const __m256d xi = _mm256_set1_pd(x[i]), yi = _mm256_set1_pd(y[i]),
                  zi = _mm256_set1_pd(dims == 3 ? z[i] : 0.0), s2 = _mm256_set1_pd(support2);
    sluice_index m = m0;
    for (; m + 4 <= m1; m += 4) {
        const __m128i j4 = _mm_loadu_si128((const __m128i *)(const void *)(list + m));
        /* four scalar loads per coordinate: faster than vgatherdpd on AMD's
         * cores of this machine kind, no slower on Intel's */
        const sluice_index j0 = list[m], j1 = list[m + 1], j2 = list[m + 2], j3 = list[m + 3];
        const __m256d dx = _mm256_sub_pd(xi, _mm256_set_pd(x[j3], x[j2], x[j1], x[j0]));
        const __m256d dy = _mm256_sub_pd(yi, _mm256_set_pd(y[j3], y[j2], y[j1], y[j0]));
        __m256d dz = _mm256_setzero_pd(), s = _mm256_mul_pd(dx, dx);
        s = _mm256_fmadd_pd(dy, dy, s);
        if (dims == 3) {
            dz = _mm256_sub_pd(zi, _mm256_set_pd(z[j3], z[j2], z[j1], z[j0]));
            s = _mm256_fmadd_pd(dz, dz, s);
        }
        int keep = _mm256_movemask_pd(_mm256_cmp_pd(s, s2, _CMP_LT_OQ));
        if (!all_kinds)
            keep &= (int)(((mask >> kind[j0]) & 1u) | (((mask >> kind[j1]) & 1u) << 1) |
                          (((mask >> kind[j2]) & 1u) << 2) | (((mask >> kind[j3]) & 1u) << 3));
        const __m256i lanes = _mm256_loadu_si256((const __m256i *)(const void *)compress_reals[keep]);
        _mm256_storeu_pd(ox + np, _mm256_castsi256_pd(_mm256_permutevar8x32_epi32(
                                      _mm256_castpd_si256(dx), lanes)));
        _mm256_storeu_pd(oy + np, _mm256_castsi256_pd(_mm256_permutevar8x32_epi32(
                                      _mm256_castpd_si256(dy), lanes)));
        if (dims == 3)
            _mm256_storeu_pd(oz + np, _mm256_castsi256_pd(_mm256_permutevar8x32_epi32(
                                          _mm256_castpd_si256(dz), lanes)));
        _mm256_storeu_pd(r2 + np, _mm256_castsi256_pd(_mm256_permutevar8x32_epi32(
                                      _mm256_castpd_si256(s), lanes)));
        const __m256i picked = _mm256_permutevar8x32_epi32(
            _mm256_castsi128_si256(j4),
            _mm256_loadu_si256((const __m256i *)(const void *)compress_indices[keep]));
        _mm_storeu_si128((__m128i *)(void *)(nb + np), _mm256_castsi256_si128(picked));
        np += (sluice_index)__builtin_popcount((unsigned)keep);
    }
    /* the last (up to three) candidates: the scalar fill */
    return fill_target(w, grid, view, i, list, m, m1, np, support2, mask, dims, 0, all_kinds);
}
#define SLUICE_FILL_AVX2 1
#else
#define SLUICE_FILL_AVX2 0
#endif

typedef sluice_index (*fill_fn)(sluice_pair_workspace *restrict, const sluice_grid *,
                                const sluice_view *, sluice_index, const sluice_index *restrict,
                                sluice_index, sluice_index, sluice_index, double, uint32_t);

#if SLUICE_FILL_AVX2
#define FILL_AVX2 fill_target_avx2
#else
/* never called: the condition above is constant false */
#define FILL_AVX2(w, grid, view, i, list, m0, m1, np, support2, mask, dims, all_kinds) (np)
#endif
#define FILL_VARIANT(name, dims, periodic, all_kinds)                                            \
    static sluice_index name(sluice_pair_workspace *restrict w, const sluice_grid *grid,         \
                             const sluice_view *view, sluice_index i,                           \
                             const sluice_index *restrict list, sluice_index m0, sluice_index m1, \
                             sluice_index np, double support2, uint32_t mask)                   \
    {                                                                                           \
        if (SLUICE_FILL_AVX2 && !(periodic) && sizeof(sluice_real) == sizeof(double) &&       \
            view->count + grid->halo_count < (sluice_index)INT32_MAX)                           \
            return FILL_AVX2(w, grid, view, i, list, m0, m1, np, support2, mask, dims,          \
                             all_kinds);                                                        \
        return fill_target(w, grid, view, i, list, m0, m1, np, support2, mask, dims, periodic,  \
                           all_kinds);                                                          \
    }
FILL_VARIANT(fill_2d, 2, 0, 0)
FILL_VARIANT(fill_2d_all, 2, 0, 1)
FILL_VARIANT(fill_2d_periodic, 2, 1, 0)
FILL_VARIANT(fill_2d_periodic_all, 2, 1, 1)
FILL_VARIANT(fill_3d, 3, 0, 0)
FILL_VARIANT(fill_3d_all, 3, 0, 1)
FILL_VARIANT(fill_3d_periodic, 3, 1, 0)
FILL_VARIANT(fill_3d_periodic_all, 3, 1, 1)

static fill_fn choose_fill(uint32_t dims, int periodic, int all_kinds)
{
    static const fill_fn table[2][2][2] = {
        {{fill_2d, fill_2d_all}, {fill_2d_periodic, fill_2d_periodic_all}},
        {{fill_3d, fill_3d_all}, {fill_3d_periodic, fill_3d_periodic_all}}};
    return table[dims == 3][periodic != 0][all_kinds != 0];
}

/* Cells per axis that the reach spans: a pair within `reach` now was within
 * reach + skin at the last build (each particle has moved at most skin/2),
 * and particles sit in the cells of that build. */
static int64_t reach_cells(const sluice_grid *grid, sluice_real reach, uint32_t d)
{
    return (int64_t)ceil(((double)reach + (double)grid->skin) * grid->inverse_cell_size[d]);
}

int sluice_pair_reach_check(const sluice_grid *grid, sluice_real reach)
{
    for (uint32_t d = 0; d < grid->dimensions; d++)
        if (grid->periodic[d] && grid->cells[d] < 2 * reach_cells(grid, reach, d) + 1)
            return -1;
    return 0;
}

/* Cell index c along an axis of n cells, wrapped across a periodic side;
 * -1 beyond a closed side. */
static inline int64_t wrap_cell(int64_t c, int64_t n, int periodic)
{
    if (c >= 0 && c < n)
        return c;
    return periodic ? (c % n + n) % n : -1;
}

void sluice_reach_list_free(sluice_reach_list *list)
{
    if (!list)
        return;
    free(list->begin);
    free(list->list);
    free(list);
}

/* The candidates of target i within `cutoff` (m) among the particles
 * j0 .. j1 (sorted by cell), whose positions at the last build are
 * position[d][j - base]; appends them to out (when not NULL) after `found`
 * and returns the new count. */
static inline sluice_index reach_range(const sluice_grid *grid, const sluice_view *view,
                                       sluice_real *const position[3], sluice_index base,
                                       sluice_index j0, sluice_index j1, sluice_index i,
                                       const double xi[3], uint32_t mask, const uint8_t *select,
                                       uint8_t wanted, double cutoff2, sluice_index *out,
                                       sluice_index found)
{
    const uint32_t dims = view->dimensions;
    const uint8_t *restrict kinds = view->kind;
    const int periodic = grid->periodic[0] || grid->periodic[1] || grid->periodic[2];
    for (sluice_index j = j0; j < j1; j++) {
        if (j == i || !((mask >> kinds[j]) & 1u) || (select && select[j] != wanted))
            continue;
        const sluice_index at = j - base;
        double s2 = 0;
        for (uint32_t d = 0; d < dims; d++) {
            double e = xi[d] - (double)position[d][at];
            if (periodic && grid->periodic[d])
                e = minimum_image(e, grid->length[d]);
            s2 += e * e;
        }
        if (!(s2 < cutoff2))
            continue;
        if (out)
            out[found] = j;
        found++;
    }
    return found;
}

/* The candidates of target i within `cutoff` (m) at the positions of the
 * grid's last build (grid->built, and grid->halo_built for the halo of a
 * distributed run): the selected particles of the kinds in `mask` in the
 * cells around i's cell that the reach spans, in scan order (rows of cells,
 * then index; each row's own particles, then its halo). Writes them to out
 * when out is not NULL; returns their count. */
static sluice_index reach_scan(const sluice_pair_pass *pass, const sluice_grid *grid,
                               const sluice_view *view, sluice_index i, uint32_t mask,
                               double cutoff, sluice_index *out)
{
    sluice_real *const *position = grid->built;
    sluice_real *const *halo_position = grid->halo_built;
    const int halo = grid->halo_count > 0;
    const uint32_t dims = view->dimensions;
    const double cutoff2 = cutoff * cutoff;
    const uint32_t cell = grid->cell_of[i];
    int64_t c[3], range[3] = {0, 0, 0};
    c[0] = (int64_t)(cell % (uint32_t)grid->cells[0]);
    c[1] = (int64_t)((cell / (uint32_t)grid->cells[0]) % (uint32_t)grid->cells[1]);
    c[2] = (int64_t)(cell / ((uint32_t)grid->cells[0] * (uint32_t)grid->cells[1]));
    int closed = 1;
    for (uint32_t d = 0; d < dims; d++) {
        range[d] = reach_cells(grid, pass->reach, d);
        closed &= !grid->periodic[d];
    }
    const uint8_t *restrict select =
        pass->select_column >= 0 ? view->columns[pass->select_column] : NULL;
    const uint8_t wanted = pass->select_value;
    const double xi[3] = {(double)position[0][i], (double)position[1][i],
                          dims == 3 ? (double)position[2][i] : 0.0};
    sluice_index found = 0;
    if (closed) {
        /* no periodic side: the cells of a row of the range are
         * consecutive, and so are their particles (sorted by cell) */
        const int64_t x0 = c[0] - range[0] > 0 ? c[0] - range[0] : 0;
        const int64_t x1 = c[0] + range[0] < grid->cells[0] - 1 ? c[0] + range[0] : grid->cells[0] - 1;
        const int64_t y0 = c[1] - range[1] > 0 ? c[1] - range[1] : 0;
        const int64_t y1 = c[1] + range[1] < grid->cells[1] - 1 ? c[1] + range[1] : grid->cells[1] - 1;
        const int64_t z0 = c[2] - range[2] > 0 ? c[2] - range[2] : 0;
        const int64_t z1 = c[2] + range[2] < grid->cells[2] - 1 ? c[2] + range[2] : grid->cells[2] - 1;
        for (int64_t cz = z0; cz <= z1; cz++)
            for (int64_t cy = y0; cy <= y1; cy++) {
                const size_t row = ((size_t)cz * (size_t)grid->cells[1] + (size_t)cy) *
                                   (size_t)grid->cells[0];
                found = reach_range(grid, view, position, 0, grid->cell_start[row + (size_t)x0],
                                    grid->cell_start[row + (size_t)x1 + 1], i, xi, mask, select,
                                    wanted, cutoff2, out, found);
                if (halo)
                    found = reach_range(grid, view, halo_position, grid->count,
                                        grid->halo_start[row + (size_t)x0],
                                        grid->halo_start[row + (size_t)x1 + 1], i, xi, mask,
                                        select, wanted, cutoff2, out, found);
            }
        return found;
    }
    for (int64_t dz = -range[2]; dz <= range[2]; dz++) {
        const int64_t cz = wrap_cell(c[2] + dz, grid->cells[2], grid->periodic[2]);
        if (cz < 0)
            continue;
        for (int64_t dy = -range[1]; dy <= range[1]; dy++) {
            const int64_t cy = wrap_cell(c[1] + dy, grid->cells[1], grid->periodic[1]);
            if (cy < 0)
                continue;
            for (int64_t dx = -range[0]; dx <= range[0]; dx++) {
                const int64_t cx = wrap_cell(c[0] + dx, grid->cells[0], grid->periodic[0]);
                if (cx < 0)
                    continue;
                const size_t at = ((size_t)cz * (size_t)grid->cells[1] + (size_t)cy) *
                                      (size_t)grid->cells[0] +
                                  (size_t)cx;
                found = reach_range(grid, view, position, 0, grid->cell_start[at],
                                    grid->cell_start[at + 1], i, xi, mask, select, wanted, cutoff2,
                                    out, found);
                if (halo)
                    found = reach_range(grid, view, halo_position, grid->count,
                                        grid->halo_start[at], grid->halo_start[at + 1], i, xi,
                                        mask, select, wanted, cutoff2, out, found);
            }
        }
    }
    return found;
}

static inline int reach_target(const sluice_pair_pass *pass, const sluice_view *view,
                               sluice_index i)
{
    if (!pass->neighbour_mask[view->kind[i]])
        return 0;
    return pass->select_column < 0 ||
           ((const uint8_t *)view->columns[pass->select_column])[i] == pass->select_value;
}

/* Rebuilds the pass's list from the grid's last build (its cells and the
 * positions it recorded, whenever this runs: a pair within reach now was
 * within reach + skin then). Returns 0, or -1 on OOM. */
static int reach_list_build(const sluice_pair_pass *pass, const sluice_grid *grid,
                            const sluice_view *view, int threads)
{
    sluice_reach_list *L = pass->reach_list;
    const sluice_index n = view->count;
    if (n + 1 > L->begin_capacity || !L->begin) {
        sluice_index cap = n + n / 4 + 64;
        sluice_index *begin = malloc((size_t)cap * sizeof *begin);
        if (!begin)
            return -1;
        free(L->begin);
        L->begin = begin;
        L->begin_capacity = cap;
    }
    const double cutoff = (double)pass->reach + (double)grid->skin;
    sluice_index *begin = L->begin;
#pragma omp parallel for num_threads(threads) schedule(guided, 256)
    for (sluice_index i = 0; i < n; i++)
        begin[i + 1] = reach_target(pass, view, i) ? reach_scan(pass, grid, view, i,
                                                                pass->neighbour_mask[view->kind[i]],
                                                                cutoff, NULL)
                                                   : 0;
    size_t needed = 0;
    const int listed =
        sluice_list_offsets(begin, n, &L->list, &L->capacity, grid->list_limit, &needed);
    if (listed != 0)
        return listed;
    sluice_index *list = L->list;
#pragma omp parallel for num_threads(threads) schedule(guided, 256)
    for (sluice_index i = 0; i < n; i++)
        if (begin[i + 1] > begin[i])
            (void)reach_scan(pass, grid, view, i, pass->neighbour_mask[view->kind[i]], cutoff,
                             list + begin[i]);
    L->count = n;
    L->built_at = grid->rebuilds + 1;
    return 0;
}

/* Appends the pairs of target i within `reach` from its list entries m0 ..
 * m1 - 1 (in the list's order); returns the new pair count. */
static sluice_index fill_reach(const sluice_pair_pass *pass, const sluice_grid *grid,
                               const sluice_view *view, sluice_pair_workspace *w, sluice_index i,
                               const sluice_index *restrict list, sluice_index m0,
                               sluice_index m1, sluice_index np)
{
    const uint32_t dims = view->dimensions;
    const double reach2 = (double)pass->reach * (double)pass->reach;
    const int periodic = grid->periodic[0] || grid->periodic[1] || grid->periodic[2];
    const double xi[3] = {(double)view->position[0][i], (double)view->position[1][i],
                          dims == 3 ? (double)view->position[2][i] : 0.0};
    if (!periodic) {
        /* every candidate is written and the count advances for those
         * within reach (the workspace holds m1 - m0 more pairs) */
        sluice_index *restrict nb = w->neighbour;
        sluice_real *restrict ox = w->offset[0], *restrict oy = w->offset[1];
        sluice_real *restrict oz = w->offset[2], *restrict d2 = w->distance_squared;
        const sluice_real *restrict px = view->position[0], *restrict py = view->position[1];
        if (dims == 2) {
            for (sluice_index m = m0; m < m1; m++) {
                const sluice_index j = list[m];
                const double e0 = xi[0] - (double)px[j], e1 = xi[1] - (double)py[j];
                const double s2 = e0 * e0 + e1 * e1;
                nb[np] = j;
                ox[np] = (sluice_real)e0;
                oy[np] = (sluice_real)e1;
                d2[np] = (sluice_real)s2;
                np += s2 < reach2;
            }
            return np;
        }
        const sluice_real *restrict pz = view->position[2];
        for (sluice_index m = m0; m < m1; m++) {
            const sluice_index j = list[m];
            const double e0 = xi[0] - (double)px[j], e1 = xi[1] - (double)py[j];
            const double e2 = xi[2] - (double)pz[j];
            const double s2 = e0 * e0 + e1 * e1 + e2 * e2;
            nb[np] = j;
            ox[np] = (sluice_real)e0;
            oy[np] = (sluice_real)e1;
            oz[np] = (sluice_real)e2;
            d2[np] = (sluice_real)s2;
            np += s2 < reach2;
        }
        return np;
    }
    for (sluice_index m = m0; m < m1; m++) {
        const sluice_index j = list[m];
        double e[3] = {0, 0, 0};
        for (uint32_t d = 0; d < dims; d++) {
            e[d] = xi[d] - (double)view->position[d][j];
            if (grid->periodic[d])
                e[d] = minimum_image(e[d], grid->length[d]);
        }
        const double s2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        if (!(s2 < reach2))
            continue;
        w->neighbour[np] = j;
        w->offset[0][np] = (sluice_real)e[0];
        w->offset[1][np] = (sluice_real)e[1];
        if (dims == 3)
            w->offset[2][np] = (sluice_real)e[2];
        w->distance_squared[np] = (sluice_real)s2;
        np++;
    }
    return np;
}

/* A pass of terms that reach beyond the support (api->evaluation->request_reach), from
 * the pass's own list (built on the first evaluation after each grid
 * build). */
static int pair_pass_run_reach(sluice_pair_engine *engine, const sluice_pair_pass *pass,
                               const sluice_grid *grid, const sluice_view *view)
{
    const sluice_index n = view->count;
    const sluice_reach_list *L = pass->reach_list;
    if (L->built_at != grid->rebuilds + 1 || L->count != n)
        if (reach_list_build(pass, grid, view, engine->thread_count) != 0)
            return -1;
    const sluice_index *list = L->list, *begin = L->begin;
    sluice_index chunk_targets = engine->batch_pairs / 128;
    if (chunk_targets < 1)
        chunk_targets = 1;
    if (chunk_targets > TARGET_CHUNK)
        chunk_targets = TARGET_CHUNK;
    const sluice_index chunks = (n + chunk_targets - 1) / chunk_targets;
    int failed = 0;

#pragma omp parallel num_threads(engine->thread_count) reduction(| : failed)
    {
        sluice_pair_workspace *w = &engine->workspaces[omp_get_thread_num()];
        if (workspace_reserve(w, engine->batch_pairs, pass->gathered_max) != 0)
            failed = 1;
        for (uint32_t c = 0; c < w->column_count && !failed; c++)
            w->gathered[c] = NULL;
        const uint8_t *kind = view->kind;

#pragma omp for schedule(guided, 4)
        for (sluice_index chunk = 0; chunk < chunks; chunk++) {
            if (failed)
                continue;
            const sluice_index a = chunk * chunk_targets;
            const sluice_index b = a + chunk_targets < n ? a + chunk_targets : n;
            for (uint32_t k = 0; k < SLUICE_KIND_COUNT && !failed; k++) {
                if (!pass->neighbour_mask[k])
                    continue;
                sluice_index t = 0, np = 0;
                for (sluice_index i = a; i < b; i++) {
                    if (kind[i] != k || !reach_target(pass, view, i))
                        continue;
                    const sluice_index m0 = begin[i], m1 = begin[i + 1];
                    if (batch_open(engine, pass, view, w, &t, &np, m1 - m0, k, i) != 0) {
                        failed = 1;
                        break;
                    }
                    np = fill_reach(pass, grid, view, w, i, list, m0, m1, np);
                    t++;
                }
                if (failed)
                    break;
                w->pair_begin[t] = np;
                flush(engine, pass, view, w, t, np, k);
            }
        }
    }
    return failed ? -1 : 0;
}

/* The work of a target in a pass, in list entries: its entries plus this
 * (opening its segment, its terms' per-target work) */
#define TARGET_WORK 4.0

/* The first target of chunk c of chunks of work_per_chunk each: the first i
 * with begin[i] + TARGET_WORK i >= c work_per_chunk (the work is monotone in
 * i, so consecutive chunks tile [0, n)). */
static sluice_index chunk_start(const sluice_index *begin, sluice_index n, double work_per_chunk,
                                sluice_index c)
{
    const double goal = work_per_chunk * (double)c;
    sluice_index lo = 0, hi = n;
    while (lo < hi) {
        const sluice_index mid = lo + (hi - lo) / 2;
        if ((double)begin[mid] + TARGET_WORK * (double)mid < goal)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

int sluice_pair_pass_run(sluice_pair_engine *engine, const sluice_pair_pass *pass,
                         const sluice_grid *grid, const sluice_view *view)
{
    if (pass->reach > 0)
        return pair_pass_run_reach(engine, pass, grid, view);
    const sluice_index n = view->count;
    const uint32_t dims = view->dimensions;
    const double support2 = (double)grid->support * (double)grid->support;
    const int periodic = grid->periodic[0] || grid->periodic[1] || grid->periodic[2];
    /* targets per chunk: about batch_pairs pairs at a typical 32 neighbours */
    sluice_index chunk_targets = engine->batch_pairs / 32;
    if (chunk_targets < 1)
        chunk_targets = 1;
    if (chunk_targets > TARGET_CHUNK)
        chunk_targets = TARGET_CHUNK;
    const sluice_index chunks = (n + chunk_targets - 1) / chunk_targets;
    /* chunks of about equal work (list entries plus a few per target), not
     * of equal target counts: a wall particle out of the fluid's reach has
     * an empty list, and in a 3D tank the dry walls and the fluid fill
     * distinct stretches of the sorted store, so that guided's first,
     * largest grabs would hand one thread most of the work */
    const double work_per_chunk =
        ((double)grid->list_begin[n] + TARGET_WORK * (double)n) / (double)chunks;
    int failed = 0;

#pragma omp parallel num_threads(engine->thread_count) reduction(| : failed)
    {
        int tid = omp_get_thread_num();
        sluice_pair_workspace *w = &engine->workspaces[tid];
        if (workspace_reserve(w, engine->batch_pairs, pass->gathered_max) != 0)
            failed = 1;
        for (uint32_t c = 0; c < w->column_count && !failed; c++)
            w->gathered[c] = NULL;
        const uint8_t *kind = view->kind;
        const sluice_index *list = grid->list, *begin = grid->list_begin;

        /* guided: each thread takes long runs of consecutive chunks
         * (shrinking towards the end for balance), so the neighbours its
         * targets read are still in its own cache from the chunk before;
         * interleaved small chunks (dynamic, 4) made the two threads of a
         * 2-core machine fetch each other's rows and cost 8 % at 86k-1M
         * particles (docs/performance.md) */
#pragma omp for schedule(guided, 4)
        for (sluice_index chunk = 0; chunk < chunks; chunk++) {
            if (failed)
                continue;
            const sluice_index a = chunk_start(begin, n, work_per_chunk, chunk);
            const sluice_index b = chunk + 1 < chunks
                                       ? chunk_start(begin, n, work_per_chunk, chunk + 1)
                                       : n;
            /* the clock is read once per chunk and once per kind with
             * targets in it (a kind's scan of a chunk without its targets
             * counts to the next kind's) */
            double clock = omp_get_wtime();
            for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++) {
                const uint32_t mask = pass->neighbour_mask[k];
                if (!mask)
                    continue;
                const fill_fn fill = choose_fill(dims, periodic, mask == SLUICE_KINDS_ALL);
                const uint64_t pairs_before = w->pairs;
                sluice_index t = 0, np = 0;
                int targets = 0;
                for (sluice_index i = a; i < b; i++) {
                    if (kind[i] != k)
                        continue;
                    targets = 1;
                    const sluice_index m0 = begin[i], m1 = begin[i + 1];
                    if (batch_open(engine, pass, view, w, &t, &np, m1 - m0, k, i) != 0) {
                        failed = 1;
                        break;
                    }
                    np = fill(w, grid, view, i, list, m0, m1, np, support2, mask);
                    t++;
                }
                if (failed)
                    break;
                if (!targets)
                    continue;
                w->pair_begin[t] = np;
                flush(engine, pass, view, w, t, np, k);
                w->kind_pairs[k] += w->pairs - pairs_before;
                const double now = omp_get_wtime();
                w->kind_seconds[k] += now - clock;
                clock = now;
            }
        }
    }
    return failed ? -1 : 0;
}

/* ----------------------------------------------------------- point pass -- */

/* Hands the batch of points in w to fn after computing W and F. */
static void flush_points(sluice_pair_engine *engine, const sluice_view *view,
                         sluice_pair_workspace *w, sluice_index targets, sluice_index pairs,
                         uint32_t kinds,
                         void (*fn)(void *, const sluice_view *, const sluice_pair_batch *),
                         void *context)
{
    if (targets == 0)
        return;
    engine->kernel->kernel(engine->kernel_state, pairs, w->distance_squared, w->distance,
                           w->kernel, w->gradient);
    const uint8_t *restrict kind = view->kind;
    for (sluice_index p = 0; p < pairs; p++)
        w->neighbour_kind[p] = kind[w->neighbour[p]];
    sluice_pair_batch batch;
    memset(&batch, 0, sizeof batch);
    batch.target_count = targets;
    batch.target = w->target;
    batch.pair_begin = w->pair_begin;
    batch.pair_count = pairs;
    batch.neighbour = w->neighbour;
    batch.neighbour_kind = w->neighbour_kind;
    batch.neighbour_kinds = kinds;
    batch.offset[0] = w->offset[0];
    batch.offset[1] = w->offset[1];
    batch.offset[2] = view->dimensions == 3 ? w->offset[2] : NULL;
    batch.distance = w->distance;
    batch.kernel = w->kernel;
    batch.kernel_gradient = w->gradient;
    batch.gathered = NULL;
    batch.kernel_self = engine->kernel_self;
    fn(context, view, &batch);
}

int sluice_point_pass_run(sluice_pair_engine *engine, const sluice_grid *grid,
                          const sluice_view *view, const sluice_real *points, sluice_index count,
                          uint32_t kinds, int with_halo,
                          void (*fn)(void *context, const sluice_view *view,
                                     const sluice_pair_batch *batch),
                          void *context)
{
    const uint32_t dims = view->dimensions;
    const double support2 = (double)grid->support * (double)grid->support;
    sluice_index chunk_points = engine->batch_pairs / 32;
    if (chunk_points < 1)
        chunk_points = 1;
    if (chunk_points > TARGET_CHUNK)
        chunk_points = TARGET_CHUNK;
    const sluice_index chunks = (count + chunk_points - 1) / chunk_points;
    sluice_real *pos[3] = {(sluice_real *)view->position[0], (sluice_real *)view->position[1],
                           (sluice_real *)(dims == 3 ? view->position[2] : view->position[1])};
    int failed = 0;

#pragma omp parallel num_threads(engine->thread_count) reduction(| : failed)
    {
        sluice_pair_workspace *w = &engine->workspaces[omp_get_thread_num()];
        if (workspace_reserve(w, engine->batch_pairs, 0) != 0)
            failed = 1;
        sluice_index found_capacity = 256;
        sluice_index *found = failed ? NULL : malloc(found_capacity * sizeof *found);
        if (!found)
            failed = 1;

#pragma omp for schedule(guided, 4)
        for (sluice_index chunk = 0; chunk < chunks; chunk++) {
            if (failed)
                continue;
            const sluice_index a = chunk * chunk_points;
            const sluice_index b = a + chunk_points < count ? a + chunk_points : count;
            sluice_index t = 0, np = 0;
            for (sluice_index q = a; q < b && !failed; q++) {
                const double p[3] = {(double)points[3 * (size_t)q], (double)points[3 * (size_t)q + 1],
                                     dims == 3 ? (double)points[3 * (size_t)q + 2] : 0.0};
                sluice_index n = sluice_grid_near_point(grid, pos, p, support2, with_halo, found,
                                                         found_capacity);
                if (n > found_capacity) {
                    sluice_index *grown = realloc(found, (size_t)n * sizeof *grown);
                    if (!grown) {
                        failed = 1;
                        break;
                    }
                    found = grown;
                    found_capacity = n;
                    n = sluice_grid_near_point(grid, pos, p, support2, with_halo, found,
                                                         found_capacity);
                }
                if (np + n > w->pair_capacity && t > 0) {
                    w->pair_begin[t] = np;
                    flush_points(engine, view, w, t, np, kinds, fn, context);
                    t = 0;
                    np = 0;
                }
                if (n > w->pair_capacity && workspace_reserve(w, n, 0) != 0) {
                    failed = 1;
                    break;
                }
                w->target[t] = q;
                w->pair_begin[t] = np;
                for (sluice_index k = 0; k < n; k++) {
                    const sluice_index j = found[k];
                    if (!((kinds >> view->kind[j]) & 1u))
                        continue;
                    double e[3] = {0, 0, 0}, s = 0;
                    for (uint32_t d = 0; d < dims; d++) {
                        e[d] = p[d] - (double)pos[d][j];
                        if (grid->periodic[d])
                            e[d] = minimum_image(e[d], grid->length[d]);
                        s += e[d] * e[d];
                    }
                    w->neighbour[np] = j;
                    w->offset[0][np] = (sluice_real)e[0];
                    w->offset[1][np] = (sluice_real)e[1];
                    w->offset[2][np] = (sluice_real)e[2];
                    w->distance_squared[np] = (sluice_real)s;
                    np++;
                }
                t++;
            }
            if (!failed) {
                w->pair_begin[t] = np;
                flush_points(engine, view, w, t, np, kinds, fn, context);
            }
        }
        free(found);
    }
    return failed ? -1 : 0;
}
