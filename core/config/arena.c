#include "arena.h"

#include <stdlib.h>
#include <string.h>

typedef struct arena_block {
    struct arena_block *next;
    size_t used, size;
    _Alignas(16) unsigned char data[];
} arena_block;

struct sluice_arena {
    arena_block *head;
};

sluice_arena *sluice_arena_create(void)
{
    return calloc(1, sizeof(sluice_arena));
}

void sluice_arena_destroy(sluice_arena *arena)
{
    if (!arena)
        return;
    arena_block *b = arena->head;
    while (b) {
        arena_block *next = b->next;
        free(b);
        b = next;
    }
    free(arena);
}

void *sluice_arena_alloc(sluice_arena *arena, size_t size)
{
    size = (size + 15u) & ~(size_t)15u;
    if (size == 0)
        size = 16;
    arena_block *b = arena->head;
    if (!b || b->size - b->used < size) {
        size_t block = size > 16384 ? size : 16384;
        b = malloc(sizeof(arena_block) + block);
        if (!b)
            return NULL;
        b->size = block;
        b->used = 0;
        b->next = arena->head;
        arena->head = b;
    }
    void *p = b->data + b->used;
    b->used += size;
    memset(p, 0, size);
    return p;
}

char *sluice_arena_strdup(sluice_arena *arena, const char *text)
{
    size_t n = strlen(text) + 1;
    char *s = sluice_arena_alloc(arena, n);
    if (s)
        memcpy(s, text, n);
    return s;
}
