/* One evaluation of the rates: the neighbour search brought up to date
 * (across ranks: balance, migration, halo), the accumulators zeroed, the
 * scheduled particle and pair passes run; point passes. */
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

/* ----------------------------------------------------------- evaluation -- */

static void zero_accumulators(sluice_sim *sim)
{
    const sluice_index n = sim->particles.count;
    for (uint32_t a = 0; a < sim->accumulate_count; a++) {
        uint32_t c = sim->accumulate_columns[a];
        memset(sim->particles.columns[c], 0, (size_t)n * sim->particles.element_size[c]);
    }
}

typedef struct particle_call {
    const sluice_component *component;
    void *state;
} particle_call;

static void run_particle_pass(sluice_sim *sim, const sluice_component *component, void *state)
{
    const sluice_view *v = &sim->view;
    const sluice_index n = v->count, chunk = 2048;
    const sluice_index chunks = (n + chunk - 1) / chunk;
#pragma omp parallel for schedule(static) if (n >= sim->parallel_min)
    for (sluice_index c = 0; c < chunks; c++) {
        sluice_index a = c * chunk, b = a + chunk < n ? a + chunk : n;
        component->particle(state, v, a, b);
    }
}

static const char *describe_particle(const sluice_sim *sim, sluice_index i, char *buffer,
                                     size_t size)
{
    const sluice_view *v = &sim->view;
    if (v->dimensions == 3)
        snprintf(buffer, size, "particle id %llu (%s) at (%.6g, %.6g, %.6g) m",
                 (unsigned long long)v->id[i], sluice_kind_name(v->kind[i]),
                 (double)v->position[0][i], (double)v->position[1][i], (double)v->position[2][i]);
    else
        snprintf(buffer, size, "particle id %llu (%s) at (%.6g, %.6g) m",
                 (unsigned long long)v->id[i], sluice_kind_name(v->kind[i]),
                 (double)v->position[0][i], (double)v->position[1][i]);
    return buffer;
}

/* Rebuilds the neighbour list when a particle has moved beyond the skin or
 * the particle count changed. */
int sluice_sim_update_neighbours(sluice_sim *sim)
{
    sluice_sim_refresh_view(sim);
    int rebuild = sluice_grid_needs_rebuild(&sim->grid, &sim->view);
#ifdef SLUICE_MPI
    if (sim->comm.size > 1) {
        /* the slabs follow the work (docs/scaling.md); a move is decided
         * alike on every rank, and the rebuild migrates the particles */
        const int moved = sluice_ranks_balance(&sim->ranks_run, sim->step);
        if (moved < 0)
            return SLUICE_ERROR;
        rebuild = sluice_comm_any(&sim->comm, rebuild) || moved;
    }
#endif
    if (rebuild) {
        sluice_index bad = 0;
        int rc;
        /* the list may grow into the memory this process may still take,
         * not past it (docs/reliability.md, "Memory"); the figure is read
         * again only when the list may grow: first, and once it fills more
         * than 85 % of what it holds (it is allocated 80 % full) */
        const sluice_grid *g = &sim->grid;
        if (!g->list || !g->valid ||
            (double)g->list_begin[g->count] > 0.85 * (double)g->list_capacity) {
            sim->list_room = sluice_memory_available(&sim->list_room_from);
            const double entries = sim->list_room / sizeof(sluice_index);
            sim->grid.list_limit =
                sim->list_room < 0 ? 0 : entries < 1e18 ? (size_t)entries + 1 : 0;
        }
        const double room = sim->list_room;
        const char *room_from = sim->list_room_from;
#ifdef SLUICE_MPI
        if (sim->comm.size > 1) {
            const int migrated = sluice_ranks_migrate(&sim->ranks_run);
            sluice_sim_refresh_view(sim);
            if (migrated != 0)
                return SLUICE_ERROR;
            rc = sluice_grid_build_with_halo(&sim->grid, &sim->particles,
                                             (uint32_t)sim->position.column, &bad,
                                             sluice_ranks_collect_halo, &sim->ranks_run);
            if (rc == -3) {
                if (!sim->failure[0])
                    sluice_sim_fail(sim, "rank %d: the halo of the neighbour list failed",
                                    sim->comm.rank);
                return SLUICE_ERROR;
            }
        } else
#endif
            rc = sluice_grid_build(&sim->grid, &sim->particles, (uint32_t)sim->position.column,
                                   &bad);
        if (rc == -2) {
            char where[256];
            sluice_sim_refresh_view(sim);
            sluice_sim_fail(sim,
                            "step %lld, t = %.9g s: %s is outside the domain or not finite "
                            "(domain.min/max; field 'position', written by the integrator)",
                            (long long)sim->step, sim->time,
                            describe_particle(sim, bad, where, sizeof where));
            return SLUICE_ERROR;
        }
        if (rc == -4) {
            sluice_sim_fail(sim,
                            "step %lld, t = %.9g s: the neighbour list of %u particles needs %zu "
                            "entries (%.3g GB, %.1f per particle), more than this process may "
                            "still take (%.3g GB, %s): use a larger spacing or run across more "
                            "machines",
                            (long long)sim->step, sim->time, sim->particles.count,
                            sim->grid.list_needed,
                            (double)sim->grid.list_needed * sizeof(sluice_index) / 1e9,
                            (double)sim->grid.list_needed / (double)sim->particles.count,
                            room / 1e9, room_from ? room_from : "unknown");
            return SLUICE_ERROR;
        }
        if (rc != 0) {
            sluice_sim_fail(sim, "out of memory building the neighbour list (%u particles)",
                            sim->particles.count);
            return SLUICE_ERROR;
        }
        sluice_sim_refresh_view(sim);
    }
    return SLUICE_OK;
}

int sluice_sim_replace_particles(sluice_sim *sim, sluice_index count)
{
    if (sim->comm.size > 1) {
        sluice_sim_fail(sim, "particles can be replaced on one rank only");
        return SLUICE_ERROR;
    }
    sim->particles.count = 0;
    if (count > 0 && sluice_particles_append(&sim->particles, count, NULL) != 0) {
        sluice_sim_fail(sim, "out of memory for %u particles", count);
        return SLUICE_ERROR;
    }
    for (uint32_t c = 0; c < sim->particles.column_count; c++)
        memset(sim->particles.columns[c], 0,
               (size_t)count * sim->particles.element_size[c]);
    sim->grid.valid = 0;
    sluice_sim_refresh_view(sim);
    return SLUICE_OK;
}

int sluice_sim_point_pass(sluice_sim *sim, const sluice_real *points, sluice_index count,
                          uint32_t kinds, sluice_point_fn fn, void *context)
{
    if (sluice_sim_update_neighbours(sim) != SLUICE_OK)
        return SLUICE_ERROR;
    sim->evaluating++;
    const int failed =
        sluice_point_pass_run(&sim->engine, &sim->grid, &sim->view, points, count,
                              sluice_neighbour_kinds(kinds), 0, fn, context) != 0;
    sim->evaluating--;
    if (failed) {
        sluice_sim_fail(sim, "out of memory in a point pass");
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int evaluate(sluice_sim *sim);

int sluice_sim_evaluate(sluice_sim *sim)
{
    sim->evaluating++;
    int status = evaluate(sim);
    sim->evaluating--;
    return status;
}

static int evaluate(sluice_sim *sim)
{
    if (sluice_sim_update_neighbours(sim) != SLUICE_OK)
        return SLUICE_ERROR;
    for (uint32_t k = 0; k < sim->prepare_count; k++) {
        sluice_instance *in = &sim->instances[sim->prepare[k]];
        if (in->component->prepare(in->state, &in->host) != SLUICE_OK) {
            if (!sim->failure[0])
                sluice_sim_fail(sim, "plugin '%s' failed to prepare an evaluation", in->name);
            return SLUICE_ERROR;
        }
        sluice_sim_refresh_view(sim);
    }
    zero_accumulators(sim);
    /* across ranks: this rank's time in the passes, without the halo's
     * exchanges (the measured work that balances the slabs) */
    double busy_from = sim->comm.size > 1 ? sluice_wall_clock() : 0;
    for (uint32_t p = 0; p < sim->pass_count; p++) {
        const sluice_pass *pass = &sim->passes[p];
        if (pass->is_pair) {
#ifdef SLUICE_MPI
            /* the other ranks' particles as they are now, every field */
            if (sim->comm.size > 1) {
                const double now = sluice_wall_clock();
                sim->halo.busy_seconds += now - busy_from;
                if (sluice_ranks_refresh_halo(&sim->ranks_run) != 0)
                    return SLUICE_ERROR;
                busy_from = sluice_wall_clock();
            }
#endif
            if (sluice_pair_pass_run(&sim->engine, &pass->pair, &sim->grid, &sim->view) != 0) {
                sluice_sim_fail(sim, "out of memory in a pair pass");
                return SLUICE_ERROR;
            }
        } else {
            const sluice_instance *in = &sim->instances[pass->instance];
            run_particle_pass(sim, in->component, in->state);
        }
    }
    if (sim->comm.size > 1)
        sim->halo.busy_seconds += sluice_wall_clock() - busy_from;
    return SLUICE_OK;
}

double sluice_sim_next_request(const sluice_sim *sim)
{
    double next = INFINITY;
    double eps = 1e-12 * (fabs(sim->time) > 1 ? fabs(sim->time) : 1);
    for (size_t i = 0; i < sim->request_count; i++)
        if (sim->requests[i] > sim->time + eps && sim->requests[i] < next)
            next = sim->requests[i];
    return next;
}

/* Across ranks: the other ranks' particles in the halo as they are now
 * (every field). Collective; nothing on one rank. */
int sluice_sim_refresh_halo(sluice_sim *sim)
{
#ifdef SLUICE_MPI
    if (sim->comm.size > 1 && sluice_ranks_refresh_halo(&sim->ranks_run) != 0)
        return SLUICE_ERROR;
#else
    (void)sim;
#endif
    return SLUICE_OK;
}

/* The pass of api->evaluation->point_pass and api->evaluation->point_pass_local, once the
 * neighbour search is up to date (with_halo: the halo's particles are pairs
 * too). */
int sluice_sim_run_point_pass(sluice_sim *sim, const sluice_host *host, const sluice_real *points,
                          sluice_index count, uint32_t kinds, int with_halo, sluice_point_fn fn,
                          void *context)
{
    sim->evaluating++;
    int failed = sluice_point_pass_run(&sim->engine, &sim->grid, &sim->view, points, count,
                                       sluice_neighbour_kinds(kinds), with_halo, fn,
                                       context) != 0;
    sim->evaluating--;
    if (failed) {
        sluice_sim_fail(sim, "out of memory in the point pass of '%s'",
                        sluice_sim_instance_name(sim, host->instance));
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}
