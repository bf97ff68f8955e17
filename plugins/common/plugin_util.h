/* Small inline helpers shared by Sluice's own plugins (header only: plugins
 * never link against the core or each other). */
#ifndef SLUICE_PLUGIN_UTIL_H
#define SLUICE_PLUGIN_UTIL_H

#include <stdlib.h>

#define SLUICE_PI 3.14159265358979323846

#include "sluice/plugin.h"

/* Reads a scalar constant; reports an error naming `who` when absent. */
static inline int sluice_util_constant(const sluice_api *api, sluice_host *host, const char *name,
                                       sluice_real *value)
{
    sluice_real v[3];
    if (api->constant(host, name, v, 3) < 1) {
        api->error(host, "needs the constant '%s', which no loaded plugin publishes", name);
        return SLUICE_ERROR;
    }
    *value = v[0];
    return SLUICE_OK;
}

/* Resolves several fields at once: names[i] -> fields[i]. */
static inline int sluice_util_fields(const sluice_api *api, sluice_host *host,
                                     const char *const *names, sluice_field *fields, int count)
{
    for (int i = 0; i < count; i++)
        if (api->field(host, names[i], &fields[i]) != SLUICE_OK)
            return SLUICE_ERROR;
    return SLUICE_OK;
}

/* Allocates a zeroed state struct; reports OOM. */
static inline void *sluice_util_state(const sluice_api *api, sluice_host *host, size_t size)
{
    void *p = calloc(1, size);
    if (!p)
        api->error(host, "out of memory");
    return p;
}

#endif
