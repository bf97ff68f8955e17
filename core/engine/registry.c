#define _GNU_SOURCE
#include "registry.h"

#include <dirent.h>
#include <dlfcn.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "build_config.h"

static char *dup_string(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

static char *format(const char *fmt, ...) SLUICE_PRINTF(1, 2);
#include <stdarg.h>
static char *format(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0)
        return NULL;
    char *s = malloc((size_t)n + 1);
    if (!s)
        return NULL;
    va_start(ap, fmt);
    vsnprintf(s, (size_t)n + 1, fmt, ap);
    va_end(ap);
    return s;
}

static int push_directory(char ***dirs, size_t *count, const char *dir)
{
    for (size_t i = 0; i < *count; i++)
        if (strcmp((*dirs)[i], dir) == 0)
            return 0;
    char **d = realloc(*dirs, (*count + 1) * sizeof *d);
    if (!d)
        return -1;
    *dirs = d;
    d[*count] = dup_string(dir);
    if (!d[*count])
        return -1;
    (*count)++;
    return 0;
}

static int is_directory(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

int sluice_registry_default_path(char ***directories, size_t *count, const char *const *extra,
                                 size_t extra_count)
{
    *directories = NULL;
    *count = 0;
    for (size_t i = 0; i < extra_count; i++)
        if (push_directory(directories, count, extra[i]) != 0)
            return -1;
    const char *env = getenv("SLUICE_PLUGIN_PATH");
    if (env && *env) {
        char *copy = dup_string(env);
        if (!copy)
            return -1;
        char *save = NULL;
        for (char *tok = strtok_r(copy, ":", &save); tok; tok = strtok_r(NULL, ":", &save))
            if (*tok && push_directory(directories, count, tok) != 0) {
                free(copy);
                return -1;
            }
        free(copy);
    }
    char exe[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) {
        exe[n] = '\0';
        char *slash = strrchr(exe, '/');
        if (slash) {
            *slash = '\0';
            const char *relative[] = {SLUICE_BUILD_RELATIVE_PLUGIN_DIR,
                                      SLUICE_BUILD_TOOLS_RELATIVE_PLUGIN_DIR,
                                      SLUICE_INSTALL_RELATIVE_PLUGIN_DIR};
            for (size_t i = 0; i < 3; i++) {
                char candidate[PATH_MAX];
                int w = snprintf(candidate, sizeof candidate, "%s/%s", exe, relative[i]);
                char resolved[PATH_MAX];
                if (w > 0 && (size_t)w < sizeof candidate && realpath(candidate, resolved) &&
                    is_directory(resolved) && push_directory(directories, count, resolved) != 0)
                    return -1;
            }
        }
    }
    if (is_directory(SLUICE_INSTALL_PLUGIN_DIR) &&
        push_directory(directories, count, SLUICE_INSTALL_PLUGIN_DIR) != 0)
        return -1;
    return 0;
}

static int compare_strings(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The stride of a library's component array: sizeof(sluice_component) as the
 * library was built (its descriptor says). A library built before members
 * were appended has the shorter stride; those members read as absent in the
 * copy the core keeps (registry.c, the loop below). */
static size_t component_size(const sluice_library *lib)
{
    return lib->component_size;
}

static const sluice_component *component_at(const sluice_library *lib, uint32_t i)
{
    return (const sluice_component *)(const void *)((const char *)lib->components +
                                                    (size_t)i * component_size(lib));
}

static const char *check_library(const sluice_library *lib, char **why)
{
    *why = NULL;
    if (lib->abi_major != SLUICE_ABI_MAJOR || lib->abi_minor > SLUICE_ABI_MINOR) {
        *why = format("was built for Sluice plugin ABI %u.%u, but this sluice provides ABI "
                      "%u.%u (%s)",
                      lib->abi_major, lib->abi_minor, SLUICE_ABI_MAJOR, SLUICE_ABI_MINOR,
                      lib->abi_major != SLUICE_ABI_MAJOR ? "major versions differ"
                                                         : "the plugin needs a newer sluice");
        return "abi";
    }
    const sluice_signature *s = &lib->signature;
    if (s->real_size != sizeof(sluice_real)) {
        *why = format("was built with a %u-byte real type, but this sluice uses %zu-byte reals",
                      s->real_size, sizeof(sluice_real));
        return "signature";
    }
    if (s->index_size != sizeof(sluice_index)) {
        *why = format("was built with %u-byte particle indices, but this sluice uses "
                      "%zu-byte indices",
                      s->index_size, sizeof(sluice_index));
        return "signature";
    }
    if ((s->dimensions & SLUICE_DIMS_ALL) == 0) {
        *why = format("has a build signature that supports neither 2D nor 3D");
        return "signature";
    }
    if (lib->component_count == 0 || !lib->components) {
        *why = format("has a descriptor that lists no components");
        return "descriptor";
    }
    if (lib->component_size < offsetof(sluice_component, load_state) + sizeof(void (*)(void))) {
        *why = format("has a descriptor whose component size (%u bytes) is smaller than ABI "
                      "2.0's sluice_component (%zu bytes): was it built with "
                      "SLUICE_DEFINE_LIBRARY?",
                      lib->component_size, offsetof(sluice_component, load_state) +
                                               sizeof(void (*)(void)));
        return "descriptor";
    }
    for (uint32_t i = 0; i < lib->component_count; i++) {
        const sluice_component *c = component_at(lib, i);
        if (!c->name || !*c->name) {
            *why = format("has a descriptor whose component %u has no name", i);
            return "descriptor";
        }
        for (uint32_t k = 0; k < i; k++)
            if (strcmp(component_at(lib, k)->name, c->name) == 0) {
                *why = format("has a descriptor that lists component '%s' twice", c->name);
                return "descriptor";
            }
        if (!c->create) {
            *why = format("has a component '%s' without a create function", c->name);
            return "descriptor";
        }
    }
    return NULL;
}

int sluice_registry_add_file(sluice_registry *registry, const char *path)
{
    sluice_library_entry entry;
    memset(&entry, 0, sizeof entry);
    entry.path = dup_string(path);
    if (!entry.path)
        return -1;
    dlerror();
    void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
        const char *e = dlerror();
        entry.refusal = format("cannot be loaded: %s", e ? e : "unknown dlopen error");
    } else {
        dlerror();
        void *symbol = dlsym(handle, SLUICE_ENTRY_SYMBOL);
        const sluice_library *lib = NULL;
        if (!symbol) {
            entry.refusal = format("is not a Sluice plugin: it has no entry point '%s'",
                                   SLUICE_ENTRY_SYMBOL);
        } else {
            sluice_entry_fn fn;
            memcpy(&fn, &symbol, sizeof fn);
            lib = fn();
            if (!lib || lib->magic != SLUICE_PLUGIN_MAGIC) {
                entry.refusal = format("is not a Sluice plugin: its entry point '%s' returned no "
                                       "valid descriptor",
                                       SLUICE_ENTRY_SYMBOL);
                lib = NULL;
            }
        }
        if (lib) {
            if (lib->name)
                entry.name = dup_string(lib->name);
            char *why = NULL;
            if (check_library(lib, &why)) {
                entry.refusal = why ? why : dup_string("refused");
                lib = NULL;
            }
        }
        if (lib) {
            entry.handle = handle;
            entry.library = lib;
        } else {
            dlclose(handle);
        }
    }
    sluice_library_entry *libs =
        realloc(registry->libraries, (registry->library_count + 1) * sizeof *libs);
    if (!libs) {
        if (entry.handle)
            dlclose(entry.handle);
        free(entry.path);
        free(entry.name);
        free(entry.refusal);
        return -1;
    }
    registry->libraries = libs;
    size_t index = registry->library_count++;
    libs[index] = entry;
    if (entry.library) {
        const sluice_library *lib = entry.library;
        sluice_component_entry *comps =
            realloc(registry->components,
                    (registry->component_count + lib->component_count) * sizeof *comps);
        if (!comps)
            return -1;
        registry->components = comps;
        for (uint32_t i = 0; i < lib->component_count; i++) {
            /* a full-size copy: members newer than the library's ABI read as 0 */
            sluice_component *copy = calloc(1, sizeof *copy);
            if (!copy)
                return -1;
            memcpy(copy, component_at(lib, i), component_size(lib) < sizeof *copy ? component_size(lib) : sizeof *copy);
            sluice_component_entry *c = &comps[registry->component_count++];
            c->component = copy;
            c->library = index;
            c->shadowed = sluice_registry_find(registry, copy->name) != c;
        }
    }
    return 0;
}

int sluice_registry_open(sluice_registry *registry, char **directories, size_t directory_count)
{
    memset(registry, 0, sizeof *registry);
    registry->directories = directories;
    registry->directory_count = directory_count;
    for (size_t d = 0; d < directory_count; d++) {
        DIR *dir = opendir(directories[d]);
        if (!dir)
            continue;
        char **names = NULL;
        size_t count = 0;
        struct dirent *e;
        int oom = 0;
        while ((e = readdir(dir))) {
            size_t len = strlen(e->d_name);
            if (len < 4 || strcmp(e->d_name + len - 3, ".so") != 0)
                continue;
            char **grown = realloc(names, (count + 1) * sizeof *names);
            if (!grown) {
                oom = 1;
                break;
            }
            names = grown;
            names[count] = format("%s/%s", directories[d], e->d_name);
            if (!names[count]) {
                oom = 1;
                break;
            }
            count++;
        }
        closedir(dir);
        if (!oom && count)
            qsort(names, count, sizeof *names, compare_strings);
        for (size_t i = 0; i < count && !oom; i++)
            if (sluice_registry_add_file(registry, names[i]) != 0)
                oom = 1;
        for (size_t i = 0; i < count; i++)
            free(names[i]);
        free(names);
        if (oom)
            return -1;
    }
    return 0;
}

void sluice_registry_close(sluice_registry *registry)
{
    for (size_t i = 0; i < registry->library_count; i++) {
        sluice_library_entry *e = &registry->libraries[i];
        if (e->handle)
            dlclose(e->handle);
        free(e->path);
        free(e->name);
        free(e->refusal);
    }
    free(registry->libraries);
    for (size_t c = 0; c < registry->component_count; c++)
        free((void *)registry->components[c].component);
    free(registry->components);
    for (size_t i = 0; i < registry->directory_count; i++)
        free(registry->directories[i]);
    free(registry->directories);
    memset(registry, 0, sizeof *registry);
}

const sluice_component_entry *sluice_registry_find(const sluice_registry *registry,
                                                   const char *name)
{
    for (size_t i = 0; i < registry->component_count; i++)
        if (strcmp(registry->components[i].component->name, name) == 0)
            return &registry->components[i];
    return NULL;
}

void sluice_registry_release_unused(sluice_registry *registry)
{
    for (size_t i = 0; i < registry->library_count; i++) {
        sluice_library_entry *e = &registry->libraries[i];
        if (e->handle && !e->used) {
            /* forget its components before closing it */
            size_t kept = 0;
            for (size_t c = 0; c < registry->component_count; c++) {
                if (registry->components[c].library != i)
                    registry->components[kept++] = registry->components[c];
                else
                    free((void *)registry->components[c].component);
            }
            registry->component_count = kept;
            dlclose(e->handle);
            e->handle = NULL;
            e->library = NULL;
        }
    }
}

void sluice_registry_explain_missing(const sluice_registry *registry, const char *name,
                                     char *buffer, size_t size)
{
    buffer[0] = '\0';
    size_t used = 0;
    for (size_t i = 0; i < registry->library_count; i++) {
        const sluice_library_entry *e = &registry->libraries[i];
        if (!e->refusal)
            continue;
        const char *base = strrchr(e->path, '/');
        base = base ? base + 1 : e->path;
        size_t len = strlen(name);
        int named = (e->name && strcmp(e->name, name) == 0) ||
                    (strncmp(base, name, len) == 0 && strcmp(base + len, ".so") == 0);
        if (!named)
            continue;
        int w = snprintf(buffer + used, size - used, "%splugin %s (%s%s%s) %s", used ? "; " : "",
                         e->path, e->name ? "library '" : "no readable name",
                         e->name ? e->name : "", e->name ? "'" : "", e->refusal);
        if (w < 0 || (size_t)w >= size - used)
            return;
        used += (size_t)w;
    }
}
