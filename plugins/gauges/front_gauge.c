/* Surge-front gauge for dam breaks: the largest x of any fluid particle,
 * measured from `origin` (the left wall), written to a CSV time series
 * `time,x_front` at a fixed interval (-inf when there is no fluid).
 *
 * Across MPI ranks (ABI 1.8, SLUICE_COMPONENT_ACROSS_RANKS): each rank finds
 * the largest x of its own fluid particles (-inf without any) and the gauge
 * takes the maximum over the ranks (api->ranks->reduce) before rank 0 writes the
 * row, which is exactly the one-rank row. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct front_config {
    sluice_real interval, origin;
    const char *file;
} front_config;

typedef struct front_state {
    const sluice_api *api;
    sluice_real origin;
    const char *file;
    sluice_table *table;
    sluice_schedule rows; /* the next row is due at rows.count x rows.interval */
} front_state;

static const sluice_param_spec params[] = {
    {"interval", SLUICE_PARAM_REAL, offsetof(front_config, interval), "0.01", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between samples", NULL, 0},
    {"origin", SLUICE_PARAM_REAL, offsetof(front_config, origin), "0", 0, 0, 0, "m",
     "x of the wall the front is measured from", NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(front_config, file), "front.csv", 0, 0, 0, NULL,
     "output file in the run directory", NULL, 0},
};

static int front_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const front_config *c = config;
    front_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->rows = sluice_schedule_every(c->interval);
    s->origin = c->origin;
    s->file = c->file;
    *state = s;
    return SLUICE_OK;
}

static int front_initialise(void *state, sluice_host *host)
{
    front_state *s = state;
    s->table = s->api->output->table_open(host, s->file, "time,x_front");
    if (!s->table)
        return SLUICE_ERROR;
    const sluice_column_doc columns[] = {
        {"s", "simulated time"},
        {"m", "surge front: largest x of any fluid particle, from the origin"},
    };
    return sluice_util_describe_columns(s->api, s->table, 0, columns, SLUICE_COUNT(columns));
}

static void front_destroy(void *state)
{
    free(state);
}

static int front_after_step(void *state, sluice_host *host)
{
    front_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    if (!sluice_schedule_due(&s->rows, v->time))
        return SLUICE_OK;
    double front = -INFINITY;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && (double)v->position[0][i] > front)
            front = (double)v->position[0][i];
    /* the largest over the ranks (collective; the identity on one rank) */
    if (s->api->ranks->reduce(host, &front, 1, SLUICE_REDUCE_MAX) != SLUICE_OK)
        return SLUICE_ERROR;
    double row[2] = {v->time, front - (double)s->origin};
    if (s->api->output->table_row(s->table, row, 2) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->rows, s->api, host, v->time);
    return SLUICE_OK;
}

/* Checkpoints: the rows written (the next row is at rows_written x interval). */
SLUICE_DEFINE_SCHEDULE_STATE(front_save, front_load, front_state, rows, "rows_written")

static const sluice_component components[] = {{
    .name = "front_gauge",
    .summary = "dam-break surge front: largest x of the fluid, as time,x_front",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_ACROSS_RANKS,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(front_config),
    .create = front_create,
    .destroy = front_destroy,
    .initialise = front_initialise,
    .after_step = front_after_step,
    .save_state = front_save,
    .load_state = front_load,
}};

SLUICE_DEFINE_LIBRARY("front_gauge", "1.1.0", "surge-front gauge", SLUICE_DIMS_ALL, components)
