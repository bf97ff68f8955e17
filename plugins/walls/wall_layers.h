/* Layers of wall particles behind the walls of one wall scheme, shared by
 * the schemes that represent walls by particles (dbc, ghost_particles, mdbc;
 * header only: plugins never link against each other).
 *
 * Every wall of the scene whose `scheme` is the given component name becomes
 * the lattice points behind it (api->walls->wall_layer_points: spacing dx, aligned
 * with the fluid lattice, at a distance in (0, thickness] on the side away
 * from the fluid). Walls that meet share lattice points: each point is kept
 * once. One wall may be marked as moving (dbc's prescribed motion): its points
 * (including those it shares with a fixed wall of the same scheme: the moving
 * body owns its whole cross-section) are added after the fixed ones, by a
 * second api->particles->add_particles call, so that the scheme's particles have the
 * consecutive ids
 *     [first_id, first_id + fixed_count)                       fixed walls
 *     [first_id + fixed_count, first_id + fixed + moving)       moving wall
 * (the core gives consecutive ids to the particles of one call, and nothing
 * else adds particles in between). Ids survive the reordering of particles,
 * so a scheme recognises its own particles by id - first_id < count. */
#ifndef SLUICE_WALL_LAYERS_H
#define SLUICE_WALL_LAYERS_H

#include <math.h>
#include <string.h>

#include <sluice/plugin_util.h>

typedef struct sluice_wall_layers {
    sluice_id first_id; /* id of the first particle added */
    sluice_index fixed_count, moving_count;
    sluice_real *positions; /* 3 reals per particle, in id order (fixed, then moving) */
} sluice_wall_layers;

/* Layers covering the kernel support: ceil(support h / dx). */
static inline int64_t sluice_wall_layers_default(const sluice_api *api, sluice_host *host,
                                                 sluice_real h, sluice_real dx)
{
    sluice_real support = 2;
    api->fields->constant(host, "kernel_support", &support, 1);
    return (int64_t)ceil(support * h / dx - 1e-9);
}

typedef struct sluice_wall_layer_key_ {
    int64_t k[3];
    uint32_t index;
} sluice_wall_layer_key_;

static inline int sluice_wall_layers_compare_(const void *a, const void *b)
{
    const sluice_wall_layer_key_ *x = a, *y = b;
    for (int d = 0; d < 3; d++)
        if (x->k[d] != y->k[d])
            return x->k[d] < y->k[d] ? -1 : 1;
    return 0;
}

/* Builds and adds the wall particles (kind SLUICE_KIND_WALL) of every wall
 * whose scheme is `scheme`, `thickness` deep; `moving_wall` is the index of
 * the moving wall (api->walls->wall) or -1. Call from initialise(). On success
 * `out` holds the ids and positions (free out->positions with free()). */
static inline int sluice_wall_layers_add(const sluice_api *api, sluice_host *host,
                                         const char *scheme, sluice_real thickness, sluice_real dx,
                                         int64_t moving_wall, sluice_wall_layers *out)
{
    memset(out, 0, sizeof *out);
    sluice_real *all = NULL;
    uint8_t *moving = NULL;
    size_t count = 0;
    uint32_t walls = api->walls->wall_count(host);
    for (uint32_t w = 0; w < walls; w++) {
        const sluice_wall *wall = api->walls->wall(host, w);
        if (!wall || strcmp(wall->scheme, scheme) != 0)
            continue;
        sluice_real *points = NULL;
        sluice_index n = 0;
        if (api->walls->wall_layer_points(host, w, thickness, &points, &n) != SLUICE_OK) {
            free(all);
            free(moving);
            api->messages->error(host, "cannot build the wall-particle layers of wall %u", w);
            return SLUICE_ERROR;
        }
        sluice_real *grown = realloc(all, (count + n) * 3 * sizeof *grown + 1);
        uint8_t *grown_flags = grown ? realloc(moving, count + n + 1) : NULL;
        if (!grown || !grown_flags) {
            api->walls->release(points);
            free(grown ? grown : all);
            free(moving);
            api->messages->error(host, "out of memory");
            return SLUICE_ERROR;
        }
        all = grown;
        moving = grown_flags;
        memcpy(all + 3 * count, points, (size_t)n * 3 * sizeof *points);
        memset(moving + count, (int64_t)w == moving_wall, n);
        count += n;
        api->walls->release(points);
    }
    if (count == 0) {
        free(all);
        free(moving);
        return SLUICE_OK;
    }
    sluice_wall_layer_key_ *keys = malloc(count * sizeof *keys);
    sluice_real *unique = malloc(count * 3 * sizeof *unique);
    uint8_t *unique_moving = malloc(count);
    if (!keys || !unique || !unique_moving) {
        free(keys);
        free(unique);
        free(unique_moving);
        free(all);
        free(moving);
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    /* lattice points coincide exactly up to round-off: a key on a grid of
     * dx / 100 identifies them */
    const double q = 0.01 * (double)dx;
    for (size_t i = 0; i < count; i++) {
        for (int d = 0; d < 3; d++)
            keys[i].k[d] = llround((double)all[3 * i + d] / q);
        keys[i].index = (uint32_t)i;
    }
    qsort(keys, count, sizeof *keys, sluice_wall_layers_compare_);
    /* one point per key; moving when any of its copies is */
    size_t kept = 0;
    for (size_t i = 0; i < count; i++) {
        if (i > 0 && sluice_wall_layers_compare_(&keys[i - 1], &keys[i]) == 0) {
            unique_moving[kept - 1] |= moving[keys[i].index];
            continue;
        }
        memcpy(unique + 3 * kept, all + 3 * (size_t)keys[i].index, 3 * sizeof *unique);
        unique_moving[kept] = moving[keys[i].index];
        kept++;
    }
    free(keys);
    free(all);
    free(moving);
    /* fixed points first, then the moving ones (stable partition) */
    sluice_real *ordered = malloc(kept * 3 * sizeof *ordered + 1);
    if (!ordered) {
        free(unique);
        free(unique_moving);
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    size_t fixed = 0, placed = 0;
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < kept; i++)
            if (unique_moving[i] == pass) {
                memcpy(ordered + 3 * placed, unique + 3 * i, 3 * sizeof *ordered);
                placed++;
                fixed += pass == 0;
            }
    free(unique);
    free(unique_moving);
    sluice_index first_fixed = 0, first_moving = 0;
    if (fixed > 0 && api->particles->add_particles(host, SLUICE_KIND_WALL, ordered, (sluice_index)fixed,
                                        &first_fixed) != SLUICE_OK) {
        free(ordered);
        return SLUICE_ERROR;
    }
    if (kept > fixed &&
        api->particles->add_particles(host, SLUICE_KIND_WALL, ordered + 3 * fixed,
                           (sluice_index)(kept - fixed), &first_moving) != SLUICE_OK) {
        free(ordered);
        return SLUICE_ERROR;
    }
    const sluice_view *v = api->particles->view(host);
    sluice_id first = v->id[fixed > 0 ? first_fixed : first_moving];
    /* the contract above: the ids are consecutive (checked, not assumed) */
    if (kept > fixed && v->id[first_moving] != first + fixed) {
        free(ordered);
        api->messages->error(host, "wall particles did not receive consecutive ids");
        return SLUICE_ERROR;
    }
    out->first_id = first;
    out->fixed_count = (sluice_index)fixed;
    out->moving_count = (sluice_index)(kept - fixed);
    out->positions = ordered;
    return SLUICE_OK;
}

#endif
