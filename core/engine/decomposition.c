/* The engine's side of a run across ranks (docs/scaling.md): what the
 * decomposition library (core/ranks/) needs to know of the run and cannot
 * know itself, from the scene's components: how wide the halo must be and
 * which columns other ranks' particles are read for. */
#include "decomposition.h"

#include <stdlib.h>
#include <string.h>

#ifdef SLUICE_MPI

/* The columns a halo refresh sends (sluice_halo_lists.columns). */
static int halo_columns(sluice_sim *sim)
{
    sluice_halo_lists *h = &sim->halo;
    const uint32_t columns = sim->column_count;
    free(h->real_column), free(h->columns); /* a restart splits again */
    uint8_t *wanted = calloc((size_t)columns + 1, 1);
    h->real_column = calloc((size_t)columns + 1, 1);
    h->columns = malloc(((size_t)columns + 1) * sizeof *h->columns);
    if (!wanted || !h->real_column || !h->columns) {
        free(wanted);
        return -1;
    }
    for (uint32_t c = 0; c < columns; c++)
        wanted[c] = 1; /* columns of no field: sent */
    for (uint32_t f = 0; f < sim->field_count; f++)
        for (uint32_t c = 0; c < sim->fields[f].components && sim->fields[f].column >= 0; c++)
            wanted[(uint32_t)sim->fields[f].column + c] = 0;
    for (uint32_t d = 0; d < sim->scene.dimensions; d++)
        wanted[sim->position.column + (int32_t)d] = 1;
    wanted[sim->kind.column] = 1;
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        if (field->column < 0)
            continue;
        int read = 0;
        for (uint32_t k = 0; k < field->declarer_count; k++) {
            const sluice_declarer *dec = &field->declarers[k];
            const sluice_instance *in =
                dec->instance < sim->instance_count ? &sim->instances[dec->instance] : NULL;
            read |= (dec->access & SLUICE_READ_NEIGHBOUR) != 0;
            read |= in && in->local_points && (dec->access & (SLUICE_READ | SLUICE_WRITE)) != 0;
            read |= in && in->reach_field[0] && strcmp(in->reach_field, field->name) == 0;
        }
        /* columns of other types (kind, id, phase: a byte or eight each)
         * are always sent: they cannot hold NaN to catch an undeclared read */
        const int real = field->type == SLUICE_TYPE_REAL;
        for (uint32_t c = 0; c < field->components; c++) {
            const uint32_t column = (uint32_t)field->column + c;
            h->real_column[column] = (uint8_t)real;
            wanted[column] |= (uint8_t)(read || !real);
        }
    }
    h->column_count = 0;
    for (uint32_t c = 0; c < columns; c++)
        if (wanted[c])
            h->columns[h->column_count++] = c;
    free(wanted);
    return 0;
}

int sluice_sim_split_ranks(sluice_sim *sim)
{
    sim->ranks_run = (sluice_ranks_run){
        .comm = &sim->comm,
        .particles = &sim->particles,
        .grid = &sim->grid,
        .halo = &sim->halo,
        .position_column = sim->position.column,
        .kind_column = sim->kind.column,
        .spacing = (double)sim->spacing,
        .split_axes = sim->scene.ranks.split,
        .balance = sim->scene.ranks.balance,
        .balance_every = sim->scene.ranks.every,
        .balance_tolerance = (double)sim->scene.ranks.tolerance,
        .failure = sim->failure,
        .failure_size = sizeof sim->failure,
    };
    /* the halo holds every particle a pass of this rank's particles may
     * reach: the support, or the longest reach of a term beyond it
     * (api->evaluation->request_reach), from points up to the largest point margin
     * outside the box (api->evaluation->point_pass_local), plus the neighbour skin */
    double reach = (double)sim->grid.support;
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if ((double)sim->instances[k].reach > reach)
            reach = (double)sim->instances[k].reach;
    sim->halo.width = reach + (double)sim->point_margin + (double)sim->grid.skin;
    if (halo_columns(sim) != 0) {
        sluice_sim_fail(sim, "out of memory splitting %u particles across %d ranks",
                        sim->particles.count, sim->comm.size);
        return -1;
    }
    const int rc = sluice_ranks_split(&sim->ranks_run);
    sluice_sim_refresh_view(sim);
    return rc;
}

#endif
