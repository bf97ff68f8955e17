/* The initial particles: the scene's fluid regions filled on the lattice,
 * hydrostatic density through the equation of state, then the walls'
 * particles of the particle schemes. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "geometry.h"
#include "schema.h"
#include "decomposition.h"
#include "sim_internal.h"
#include "yaml_tree.h"

/* ------------------------------------------------------- initial state -- */

typedef struct lattice_key {
    int64_t k[3];
    uint32_t region;
} lattice_key;

static int compare_keys(const void *a, const void *b)
{
    const lattice_key *x = a, *y = b;
    for (int d = 0; d < 3; d++)
        if (x->k[d] != y->k[d])
            return x->k[d] < y->k[d] ? -1 : 1;
    return 0;
}

/* A fluid region thinner than one spacing (to round-off) is resolved by at
 * most one row of particles: almost always a spacing meant for another
 * scale (mm for m). Reports it and returns 1. */
static int region_too_thin(sluice_sim *sim, size_t r)
{
    const sluice_scene_fluid *fluid = &sim->scene.fluids[r];
    const uint32_t dims = sim->scene.dimensions;
    sluice_real lo[3], hi[3];
    sluice_region_bounds(&fluid->region, dims, lo, hi);
    for (uint32_t d = 0; d < dims; d++)
        if (hi[d] - lo[d] < sim->spacing * (1 - 1e-9)) {
            const sluice_node *node = fluid->node;
            sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node->file, node->line,
                            node->column,
                            "geometry.fluid.%zu is %g m across in %c, less than "
                            "particles.spacing = %g m: refine the spacing (at least one "
                            "spacing, better several, across every fluid region)",
                            r, (double)(hi[d] - lo[d]), "xyz"[d], (double)sim->spacing);
            return 1;
        }
    return 0;
}

/* Drops the lattice points in or closer than half a spacing to a wall;
 * returns how many are kept. */
static size_t drop_points_near_walls(const sluice_sim *sim, sluice_points *pts)
{
    const sluice_scene *scene = &sim->scene;
    const double dx = (double)sim->spacing;
    size_t kept = 0;
    for (size_t i = 0; i < pts->count; i++) {
        const sluice_real *p = pts->xyz + 3 * i;
        int keep = 1;
        for (size_t w = 0; w < scene->wall_count && keep; w++) {
            int beyond = 0;
            double dist = (double)sluice_wall_signed_distance(&scene->walls[w].geometry, p,
                                                              &beyond, NULL);
            if (beyond)
                continue;
            if (dist < 0.5 * dx * (1 - 1e-9))
                keep = 0;
        }
        if (keep) {
            memmove(pts->xyz + 3 * kept, p, 3 * sizeof *p);
            kept++;
        }
    }
    pts->count = kept;
    return kept;
}

/* The hydrostatic initial density of a region's points: the equation of
 * state's inverse of the pressure at rest density plus rho0 g times the depth
 * below the region's surface (its top when it names none). *out is
 * allocated; returns 0, or -1 out of memory. */
static int hydrostatic_density(const sluice_sim *sim, const sluice_instance *eos,
                               const sluice_real *gravity, const sluice_scene_fluid *fluid,
                               const sluice_points *pts, size_t kept, sluice_real **out)
{
    const uint32_t dims = sim->scene.dimensions;
    sluice_real *density = NULL;
    double level = fluid->has_surface ? (double)fluid->surface : -INFINITY;
    if (!fluid->has_surface) {
        sluice_real lo[3], hi[3];
        sluice_region_bounds(&fluid->region, dims, lo, hi);
        level = (double)hi[dims - 1];
    }
    sluice_real *pressure = malloc(kept * sizeof *pressure);
    density = malloc(kept * sizeof *density);
    if (!pressure || !density) {
        free(pressure);
        free(density);
        return -1;
    }
    double g = -(double)gravity[dims - 1];
    /* the pressure at the rest density (background or reference
     * pressure of the equation of state), when it publishes one */
    sluice_real reference = 0;
    sluice_sim_get_constant(sim, "reference_pressure", &reference, 1);
    for (size_t i = 0; i < kept; i++) {
        double depth = level - (double)pts->xyz[3 * i + dims - 1];
        pressure[i] = (sluice_real)((double)reference +
                                    (depth > 0 ? (double)sim->rest_density * g * depth
                                               : 0.0));
    }
    eos->component->density_from_pressure(eos->state, (sluice_index)kept, pressure, density);
    free(pressure);
    *out = density;
    return 0;
}

/* Two regions that share a lattice point: reported, returns 1. */
static int regions_overlap(sluice_sim *sim, lattice_key *keys, size_t total_keys)
{
    const sluice_scene *scene = &sim->scene;
    qsort(keys, total_keys, sizeof *keys, compare_keys);
    for (size_t i = 1; i < total_keys; i++)
        if (compare_keys(&keys[i - 1], &keys[i]) == 0) {
            uint32_t a = keys[i - 1].region, b = keys[i].region;
            if (a > b) {
                uint32_t t = a;
                a = b;
                b = t;
            }
            const sluice_node *node = scene->fluids[b].node;
            sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node->file, node->line,
                            node->column,
                            "geometry.fluid.%u overlaps geometry.fluid.%u: regions must not "
                            "share particles",
                            b, a);
            return 1;
        }
    return 0;
}

int sluice_sim_fill_fluid(sluice_sim *sim)
{
    const sluice_scene *scene = &sim->scene;
    const uint32_t dims = scene->dimensions;
    const double dx = (double)sim->spacing;
    sluice_real gravity[3] = {0, 0, 0};
    uint32_t has_gravity = sluice_sim_get_constant(sim, "gravity", gravity, 3);
    int hydrostatic = scene->initial_density == SLUICE_INITIAL_HYDROSTATIC && has_gravity &&
                      gravity[dims - 1] != 0;
    const sluice_instance *eos = NULL;
    if (hydrostatic) {
        eos = sluice_sim_equation_of_state(sim);
        if (!eos) {
            sluice_sim_report(sim, SLUICE_CORE_INSTANCE,
                   "initial.density is hydrostatic, but no loaded plugin provides an equation of "
                   "state to turn the hydrostatic pressure into density (load one, e.g. tait, or "
                   "set initial.density: rest)");
            return 1;
        }
    }
    size_t total_keys = 0, key_capacity = 0;
    lattice_key *keys = NULL;
    int errors = 0;
    for (size_t r = 0; r < scene->fluid_count && !errors; r++) {
        const sluice_scene_fluid *fluid = &scene->fluids[r];
        if (region_too_thin(sim, r)) {
            errors++;
            break;
        }
        sluice_points pts = {0};
        if (sluice_region_fill(&fluid->region, dims, sim->spacing, fluid->lattice_origin, &pts) !=
            0) {
            sluice_points_free(&pts);
            free(keys);
            sluice_sim_report(sim, SLUICE_CORE_INSTANCE, "out of memory filling fluid regions");
            return 1;
        }
        const size_t kept = drop_points_near_walls(sim, &pts);
        if (kept == 0) {
            const sluice_node *node = fluid->node;
            sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node->file, node->line, node->column,
                            "geometry.fluid.%zu holds no particle at spacing %g m (is it smaller "
                            "than the spacing, or entirely inside a wall?)",
                            r, dx);
            sluice_points_free(&pts);
            errors++;
            break;
        }
        /* lattice keys for the overlap check */
        if (total_keys + kept > key_capacity) {
            size_t cap = (total_keys + kept) * 2;
            lattice_key *grown = realloc(keys, cap * sizeof *grown);
            if (!grown) {
                sluice_points_free(&pts);
                free(keys);
                sluice_sim_report(sim, SLUICE_CORE_INSTANCE, "out of memory filling fluid regions");
                return 1;
            }
            keys = grown;
            key_capacity = cap;
        }
        for (size_t i = 0; i < kept; i++) {
            lattice_key *key = &keys[total_keys + i];
            for (int d = 0; d < 3; d++)
                key->k[d] = (uint32_t)d < dims
                                ? (int64_t)llround(((double)pts.xyz[3 * i + d] -
                                                    (double)scene->particles.lattice_origin[d]) /
                                                       dx -
                                                   0.5)
                                : 0;
            key->region = (uint32_t)r;
        }
        total_keys += kept;
        /* initial density */
        sluice_real *density = NULL;
        if (hydrostatic && sim->density.column >= 0 &&
            hydrostatic_density(sim, eos, gravity, fluid, &pts, kept, &density) != 0) {
            sluice_points_free(&pts);
            free(keys);
            sluice_sim_report(sim, SLUICE_CORE_INSTANCE, "out of memory filling fluid regions");
            return 1;
        }
        int rc = sluice_sim_add_particles(sim, SLUICE_KIND_FLUID, pts.xyz, fluid->velocity, density,
                               (sluice_index)kept, NULL);
        free(density);
        sluice_points_free(&pts);
        if (rc != 0) {
            free(keys);
            sluice_sim_report(sim, SLUICE_CORE_INSTANCE, "out of memory adding fluid particles");
            return 1;
        }
    }
    if (!errors && total_keys > 1)
        errors += regions_overlap(sim, keys, total_keys);
    free(keys);
    return errors;
}
