/* A bump allocator for things that live as long as a scene (strings, lists). */
#ifndef SLUICE_ARENA_H
#define SLUICE_ARENA_H

#include <stddef.h>

typedef struct sluice_arena sluice_arena;

sluice_arena *sluice_arena_create(void);
void sluice_arena_destroy(sluice_arena *arena);
/* Zeroed memory aligned to 16 bytes, or NULL when out of memory. */
void *sluice_arena_alloc(sluice_arena *arena, size_t size);
char *sluice_arena_strdup(sluice_arena *arena, const char *text);

#endif
