#include "particles.h"

#include <stdlib.h>
#include <string.h>

static size_t padded(size_t bytes)
{
    return (bytes + SLUICE_ALIGNMENT - 1) / SLUICE_ALIGNMENT * SLUICE_ALIGNMENT;
}

static void *aligned_block(size_t bytes)
{
    return aligned_alloc(SLUICE_ALIGNMENT, padded(bytes ? bytes : 1));
}

static int size_class(uint8_t size)
{
    switch (size) {
    case 1: return 0;
    case 2: return 1;
    case 4: return 2;
    default: return 3;
    }
}

int sluice_particles_init(sluice_particles *p, uint32_t column_count, const uint8_t *element_sizes)
{
    memset(p, 0, sizeof *p);
    p->column_count = column_count;
    p->columns = calloc(column_count ? column_count : 1, sizeof *p->columns);
    p->element_size = malloc(column_count ? column_count : 1);
    if (!p->columns || !p->element_size) {
        sluice_particles_free(p);
        return -1;
    }
    memcpy(p->element_size, element_sizes, column_count);
    return 0;
}

void sluice_particles_free(sluice_particles *p)
{
    if (p->columns)
        for (uint32_t c = 0; c < p->column_count; c++)
            free(p->columns[c]);
    for (int s = 0; s < 4; s++)
        free(p->scratch[s]);
    free(p->columns);
    free(p->element_size);
    memset(p, 0, sizeof *p);
}

int sluice_particles_reserve(sluice_particles *p, sluice_index capacity)
{
    if (capacity <= p->capacity)
        return 0;
    /* grown by a quarter: amortised appends, at most 25 % of the columns
     * reserved beyond the particles (doubling left up to half unused) */
    sluice_index cap = p->capacity ? p->capacity : 1024;
    while (cap < capacity)
        cap = cap > UINT32_MAX / 5 * 4 ? capacity : cap + cap / 4;
    void **fresh = calloc(p->column_count ? p->column_count : 1, sizeof *fresh);
    if (!fresh)
        return -1;
    for (uint32_t c = 0; c < p->column_count; c++) {
        fresh[c] = aligned_block((size_t)cap * p->element_size[c]);
        if (!fresh[c]) {
            for (uint32_t k = 0; k < c; k++)
                free(fresh[k]);
            free(fresh);
            return -1;
        }
        if (p->count)
            memcpy(fresh[c], p->columns[c], (size_t)p->count * p->element_size[c]);
    }
    for (uint32_t c = 0; c < p->column_count; c++) {
        free(p->columns[c]);
        p->columns[c] = fresh[c];
    }
    free(fresh);
    /* scratch buffers follow the capacity lazily (in permute) */
    p->capacity = cap;
    return 0;
}

int sluice_particles_append(sluice_particles *p, sluice_index n, sluice_index *first)
{
    if ((uint64_t)p->count + n > UINT32_MAX - 1)
        return -1;
    if (sluice_particles_reserve(p, p->count + n) != 0)
        return -1;
    for (uint32_t c = 0; c < p->column_count; c++)
        memset((char *)p->columns[c] + (size_t)p->count * p->element_size[c], 0,
               (size_t)n * p->element_size[c]);
    if (first)
        *first = p->count;
    p->count += n;
    return 0;
}

#define GATHER(type)                                                                            \
    do {                                                                                        \
        const type *src = (const type *)old;                                                    \
        type *dst = (type *)fresh;                                                              \
        _Pragma("omp parallel for schedule(static) if (n >= p->parallel_min)")                 \
        for (sluice_index i = 0; i < n; i++)                                                    \
            dst[i] = src[order[i]];                                                             \
    } while (0)

int sluice_particles_permute(sluice_particles *p, const sluice_index *order)
{
    sluice_index n = p->count;
    for (uint32_t c = 0; c < p->column_count; c++) {
        int s = size_class(p->element_size[c]);
        if (p->scratch_capacity[s] < p->capacity) {
            void *b = aligned_block((size_t)p->capacity * p->element_size[c]);
            if (!b)
                return -1;
            free(p->scratch[s]);
            p->scratch[s] = b;
            p->scratch_capacity[s] = p->capacity;
        }
        void *old = p->columns[c];
        void *fresh = p->scratch[s];
        switch (p->element_size[c]) {
        case 1: GATHER(uint8_t); break;
        case 2: GATHER(uint16_t); break;
        case 4: GATHER(uint32_t); break;
        default: GATHER(uint64_t); break;
        }
        p->columns[c] = fresh;
        p->scratch[s] = old;
    }
    return 0;
}

void sluice_particles_compact(sluice_particles *p, const uint8_t *remove)
{
    sluice_index first = 0;
    while (first < p->count && !remove[first])
        first++;
    if (first == p->count)
        return;
    sluice_index kept = first;
    /* column by column: one pass of element copies of a fixed size each */
    for (uint32_t c = 0; c < p->column_count; c++) {
        const size_t s = p->element_size[c];
        char *base = p->columns[c];
        kept = first;
        for (sluice_index i = first; i < p->count; i++)
            if (!remove[i]) {
                memcpy(base + (size_t)kept * s, base + (size_t)i * s, s);
                kept++;
            }
    }
    p->count = kept;
}

size_t sluice_particles_bytes(const sluice_particles *p)
{
    size_t bytes = 0;
    for (uint32_t c = 0; c < p->column_count; c++)
        bytes += padded((size_t)p->capacity * p->element_size[c]);
    for (int s = 0; s < 4; s++)
        if (p->scratch[s])
            bytes += padded((size_t)p->scratch_capacity[s] * (s == 0 ? 1 : s == 1 ? 2 : s == 2 ? 4 : 8));
    return bytes;
}
