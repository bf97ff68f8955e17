/* Plugin discovery and loading. Every *.so in the search path is opened with
 * dlopen(RTLD_NOW | RTLD_LOCAL) and asked for its descriptor through the one
 * entry symbol; libraries whose ABI or build signature do not match are
 * refused (and remembered, to explain a missing component). Libraries that
 * provide nothing a scene uses are closed again. */
#ifndef SLUICE_REGISTRY_H
#define SLUICE_REGISTRY_H

#include <stddef.h>

#include "sluice/plugin.h"

typedef struct sluice_library_entry {
    char *path;
    void *handle;                 /* NULL once closed or when refused */
    const sluice_library *library; /* NULL when refused */
    char *name;                   /* library name (readable even when refused, if any) */
    char *refusal;                /* why it was refused, or NULL */
    int used;
} sluice_library_entry;

typedef struct sluice_component_entry {
    const sluice_component *component;
    size_t library; /* index into libraries */
    int shadowed;   /* a component of the same name appears earlier in the path */
} sluice_component_entry;

typedef struct sluice_registry {
    char **directories;
    size_t directory_count;
    sluice_library_entry *libraries;
    size_t library_count;
    sluice_component_entry *components;
    size_t component_count;
} sluice_registry;

/* The default search path: SLUICE_PLUGIN_PATH (colon-separated), then the
 * plugin directory of the build tree or installation next to the running
 * program, then the configured install directory. `extra` (scene
 * plugin_path, already absolute) come first. */
int sluice_registry_default_path(char ***directories, size_t *count, const char *const *extra,
                                 size_t extra_count);

/* Scans the directories. Never fails on a bad plugin (it is refused and
 * recorded); -1 only on OOM. */
int sluice_registry_open(sluice_registry *registry, char **directories, size_t directory_count);
/* Opens one file directly (used by tests and by `sluice inspect FILE.so`). */
int sluice_registry_add_file(sluice_registry *registry, const char *path);
void sluice_registry_close(sluice_registry *registry);

/* The first component of that name in the search order, or NULL. */
const sluice_component_entry *sluice_registry_find(const sluice_registry *registry,
                                                   const char *name);
/* Closes libraries none of whose components is marked used. */
void sluice_registry_release_unused(sluice_registry *registry);

/* Explains why `name` was not found: refused libraries named like it, or a
 * list of refused libraries; writes into buffer. */
void sluice_registry_explain_missing(const sluice_registry *registry, const char *name,
                                     char *buffer, size_t size);

#endif
