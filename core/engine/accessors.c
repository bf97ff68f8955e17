/* The simulation's figures for programs and tests (sim.h). */
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

/* --------------------------------------------------------- introspection -- */

int sluice_sim_rank(const sluice_sim *sim)
{
    return sim->comm.rank;
}

int sluice_sim_rank_count(const sluice_sim *sim)
{
    return sim->comm.size;
}

uint64_t sluice_sim_particle_total(const sluice_sim *sim)
{
    return sluice_comm_sum_u64(&sim->comm, sim->particles.count);
}

const sluice_view *sluice_sim_view(sluice_sim *sim)
{
    sluice_sim_refresh_view(sim);
    return &sim->view;
}

int sluice_sim_field(sluice_sim *sim, const char *name, sluice_field *out)
{
    return sluice_sim_handle_of(sim, name, out);
}

double sluice_sim_time(const sluice_sim *sim)
{
    return sim->time;
}

double sluice_sim_end_time(const sluice_sim *sim)
{
    return sim->end;
}

int64_t sluice_sim_steps(const sluice_sim *sim)
{
    return sim->step;
}

uint32_t sluice_sim_dimensions(const sluice_sim *sim)
{
    return sim->scene.dimensions;
}

const char *sluice_sim_resolved_scene(const sluice_sim *sim)
{
    return sim->resolved_scene;
}

const char *sluice_sim_instance(const sluice_sim *sim, uint32_t index, const char **component)
{
    if (index >= sim->instance_count)
        return NULL;
    if (component)
        *component = sim->instances[index].component->name;
    return sim->instances[index].name;
}

const char *sluice_sim_variant(const sluice_sim *sim)
{
    return sim->scene.variant;
}

const char *sluice_sim_scene_variant(const sluice_sim *sim, size_t index,
                                     const char **description)
{
    if (index >= sim->scene.variant_count)
        return NULL;
    if (description)
        *description = sim->scene.variants[index].description;
    return sim->scene.variants[index].name;
}

uint32_t sluice_sim_field_count(const sluice_sim *sim)
{
    return sim->field_count;
}

const char *sluice_sim_field_name(const sluice_sim *sim, uint32_t index)
{
    return index < sim->field_count ? sim->fields[index].name : NULL;
}

size_t sluice_sim_bytes(const sluice_sim *sim)
{
    return sluice_particles_bytes(&sim->particles) + sluice_grid_bytes(&sim->grid) +
           sluice_pair_engine_bytes(&sim->engine);
}

uint64_t sluice_sim_pair_count(const sluice_sim *sim)
{
    return sluice_pair_engine_pairs(&sim->engine);
}

uint64_t sluice_sim_neighbour_rebuilds(const sluice_sim *sim)
{
    return sim->grid.rebuilds;
}

uint64_t sluice_sim_particle_steps(const sluice_sim *sim)
{
    return sim->particle_steps;
}

int sluice_sim_threads(const sluice_sim *sim)
{
    return sim->threads;
}

const char *sluice_sim_failure(const sluice_sim *sim)
{
    return sim->failure;
}
