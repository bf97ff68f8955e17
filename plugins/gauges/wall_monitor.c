/* Wall monitor: how the fluid sits against the walls, for comparing wall
 * schemes. At every `interval`, for each fluid particle, the signed distance
 * d to the nearest wall of the scene (api->walls->wall_nearest; d < 0 behind a wall,
 * ignoring points past an open end of a polyline) gives:
 *   crossed        fluid particles behind a wall now;
 *   crossed_total  distinct particles (ids) seen behind a wall at any sample
 *                  so far;
 *   gap_min        the smallest d (m; negative when a particle is behind;
 *                  past an open end d is the unsigned distance from the end);
 *   gap_layer      the mean d of the first fluid layer: the particles with
 *                  d < gap_min + dx/2 among those within 2 h of a wall (m).
 *                  On the initial lattice it is dx/2; a wall scheme that
 *                  pushes the fluid away from the wall (DBC) raises it.
 *   near_wall      particles within 2 h of a wall.
 * Written to `file` as time,crossed,crossed_total,gap_min,gap_layer,near_wall.
 * With stop_on_crossing the run stops at the first sample with a particle
 * behind a wall, naming the particle, its position and the wall.
 *
 * Across MPI ranks (ABI 1.8, SLUICE_COMPONENT_ACROSS_RANKS): each rank
 * measures its own fluid particles. The gauge takes the smallest gap over the
 * ranks before it selects the first layer (which depends on it), then adds
 * the ranks' counts and layer sums; two api->ranks->reduce calls per sample. The
 * ids newly seen behind a wall are gathered from every rank in the same
 * reduction (each rank fills its own slots of a zeroed array, id + 1 as an
 * exact double, and the sum is the concatenation), so every rank keeps the
 * same set of ids and crossed_total counts a particle once even when it
 * changes rank; the checkpoint (rank 0's) is that set. rank 0 writes the row;
 * the rows are the one-rank rows up to the order of the layer sum. With
 * stop_on_crossing every rank stops at the same sample; each rank holding a
 * particle behind a wall names its first one. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sluice/plugin_util.h>

typedef struct monitor_config {
    sluice_real interval;
    int stop_on_crossing;
    const char *file;
} monitor_config;

typedef struct monitor_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_real dx, h;
    int stop;
    const char *file;
    sluice_table *table;
    sluice_schedule rows; /* the next row is due at rows.count x rows.interval */
    sluice_id *crossed_ids; /* sorted */
    size_t crossed_count, crossed_capacity;
    double *distance;
    uint8_t *behind;
    sluice_id *fresh; /* this sample's ids behind a wall not yet in crossed_ids */
    sluice_index capacity;
    /* across ranks (api->ranks->ranks, at the first sample): this rank and how many */
    int ranks_known;
    uint32_t rank, rank_count;
    double *gather; /* the reduction's array */
    size_t gather_capacity;
} monitor_state;

static const sluice_param_spec params[] = {
    {"interval", SLUICE_PARAM_REAL, offsetof(monitor_config, interval), "0.01", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between samples", NULL, 0},
    {"stop_on_crossing", SLUICE_PARAM_BOOL, offsetof(monitor_config, stop_on_crossing), "false",
     0, 0, 0, NULL, "stop the run when a fluid particle is found behind a wall", NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(monitor_config, file), "walls.csv", 0, 0, 0, NULL,
     "output file in the run directory", NULL, 0},
};

static int monitor_create(const sluice_api *api, sluice_host *host, const void *config,
                          void **state)
{
    const monitor_config *c = config;
    monitor_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    sluice_real dims;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &s->dx) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->rows = sluice_schedule_every(c->interval);
    s->stop = c->stop_on_crossing;
    s->file = c->file;
    *state = s;
    return SLUICE_OK;
}

static void monitor_destroy(void *state)
{
    monitor_state *s = state;
    if (!s)
        return;
    free(s->crossed_ids);
    free(s->distance);
    free(s->behind);
    free(s->fresh);
    free(s->gather);
    free(s);
}

static int monitor_initialise(void *state, sluice_host *host)
{
    monitor_state *s = state;
    if (s->api->walls->wall_count(host) == 0) {
        s->api->messages->error(host, "the scene has no walls to monitor");
        return SLUICE_ERROR;
    }
    s->table = s->api->output->table_open(host, s->file,
                                  "time,crossed,crossed_total,gap_min,gap_layer,near_wall");
    if (!s->table)
        return SLUICE_ERROR;
    const sluice_column_doc columns[] = {
        {"s", "simulated time"},
        {"1", "fluid particles behind a wall now"},
        {"1", "distinct fluid particles seen behind a wall so far"},
        {"m", "smallest signed distance of a fluid particle to a wall"},
        {"m", "mean distance of the first fluid layer to the walls"},
        {"1", "fluid particles within 2 h of a wall"},
    };
    return sluice_util_describe_columns(s->api, s->table, 0, columns, SLUICE_COUNT(columns));
}

typedef struct distance_job {
    monitor_state *s;
    sluice_host *host;
} distance_job;

static void distances(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const distance_job *job = context;
    monitor_state *s = job->s;
    for (sluice_index i = begin; i < end; i++) {
        s->distance[i] = INFINITY;
        s->behind[i] = 0;
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        sluice_real p[3] = {v->position[0][i], v->position[1][i],
                            v->dimensions == 3 ? v->position[2][i] : 0};
        sluice_wall_point w;
        if (s->api->walls->wall_nearest(job->host, p, -1, &w) != SLUICE_OK)
            continue;
        /* past an open end a particle is on neither side of the wall: its
         * gap is its distance from the end */
        s->distance[i] = w.beyond_end ? fabs((double)w.distance) : (double)w.distance;
        s->behind[i] = w.distance < 0 && !w.beyond_end;
    }
}

static int compare_ids(const void *a, const void *b)
{
    sluice_id x = *(const sluice_id *)a, y = *(const sluice_id *)b;
    return x < y ? -1 : x > y;
}

static int remember(monitor_state *s, sluice_id id)
{
    if (s->crossed_count && bsearch(&id, s->crossed_ids, s->crossed_count, sizeof id, compare_ids))
        return 0;
    if (s->crossed_count == s->crossed_capacity) {
        size_t capacity = s->crossed_capacity ? 2 * s->crossed_capacity : 64;
        sluice_id *grown = realloc(s->crossed_ids, capacity * sizeof *grown);
        if (!grown)
            return -1;
        s->crossed_ids = grown;
        s->crossed_capacity = capacity;
    }
    size_t k = s->crossed_count;
    while (k > 0 && s->crossed_ids[k - 1] > id) {
        s->crossed_ids[k] = s->crossed_ids[k - 1];
        k--;
    }
    s->crossed_ids[k] = id;
    s->crossed_count++;
    return 0;
}

/* ids are gathered as id + 1 in doubles, exact below 2^53 */
#define ID_LIMIT 9007199254740991.0

static int monitor_after_step(void *state, sluice_host *host)
{
    monitor_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (!sluice_schedule_due(&s->rows, v->time))
        return SLUICE_OK;
    if (!s->ranks_known) {
        /* collective: every rank samples first at the same step */
        sluice_ranks ranks;
        if (api->ranks->ranks(host, &ranks) != SLUICE_OK)
            return SLUICE_ERROR;
        s->rank = (uint32_t)ranks.rank;
        s->rank_count = ranks.count > 0 ? (uint32_t)ranks.count : 1;
        s->ranks_known = 1;
        v = api->particles->view(host);
    }
    if (v->count > s->capacity) {
        double *d = realloc(s->distance, (size_t)v->count * sizeof *d);
        if (d)
            s->distance = d;
        uint8_t *b = realloc(s->behind, (size_t)v->count);
        if (b)
            s->behind = b;
        sluice_id *f = realloc(s->fresh, (size_t)v->count * sizeof *f);
        if (f)
            s->fresh = f;
        if (!d || !b || !f) {
            api->messages->error(host, "out of memory");
            return SLUICE_ERROR;
        }
        s->capacity = v->count;
    }
    distance_job job = {s, host};
    api->particles->parallel_for(host, v->count, distances, &job);
    double gap_min = INFINITY;
    sluice_index crossed = 0, near = 0, first_bad = v->count, fresh = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        if (s->distance[i] < gap_min)
            gap_min = s->distance[i];
        if (s->behind[i]) {
            crossed++;
            if (first_bad == v->count)
                first_bad = i;
            const sluice_id id = v->id[i];
            if (!(s->crossed_count &&
                  bsearch(&id, s->crossed_ids, s->crossed_count, sizeof id, compare_ids)))
                s->fresh[fresh++] = id;
        }
    }
    /* over the ranks (collective; the identity on one rank): the smallest
     * gap, which the first layer below depends on, and the largest number of
     * new ids of a rank (as its negative), which sizes the gathering */
    double smallest[2] = {gap_min, -(double)fresh};
    if (api->ranks->reduce(host, smallest, 2, SLUICE_REDUCE_MIN) != SLUICE_OK)
        return SLUICE_ERROR;
    gap_min = smallest[0];
    const size_t slots = (size_t)-smallest[1];
    const double band = 2 * (double)s->h;
    double layer_sum = 0;
    sluice_index layer = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID || !(s->distance[i] < band))
            continue;
        near++;
        if (s->distance[i] < gap_min + 0.5 * (double)s->dx) {
            layer_sum += s->distance[i];
            layer++;
        }
    }
    /* the sums, and the new ids of every rank: rank r fills slots
     * [r slots, (r + 1) slots) of a zeroed array with id + 1, so the sum
     * over the ranks holds every rank's ids exactly */
    const size_t length = 4 + (size_t)s->rank_count * slots;
    if (length > UINT32_MAX) {
        api->messages->error(host, "%zu particles newly behind walls on a rank: too many to gather", slots);
        return SLUICE_ERROR;
    }
    if (length > s->gather_capacity) {
        double *grown = realloc(s->gather, length * sizeof *grown);
        if (!grown) {
            api->messages->error(host, "out of memory");
            return SLUICE_ERROR;
        }
        s->gather = grown;
        s->gather_capacity = length;
    }
    double *gather = s->gather;
    memset(gather, 0, length * sizeof *gather);
    gather[0] = layer_sum;
    gather[1] = (double)layer;
    gather[2] = (double)near;
    gather[3] = (double)crossed;
    for (sluice_index k = 0; k < fresh; k++) {
        if (!((double)s->fresh[k] < ID_LIMIT)) {
            api->messages->error(host, "particle id %llu is too large to gather across ranks",
                       (unsigned long long)s->fresh[k]);
            return SLUICE_ERROR;
        }
        gather[4 + (size_t)s->rank * slots + k] = (double)s->fresh[k] + 1;
    }
    if (api->ranks->reduce(host, gather, (uint32_t)length, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    for (size_t k = 4; k < length; k++)
        if (gather[k] > 0 && remember(s, (sluice_id)gather[k] - 1) != 0) {
            api->messages->error(host, "out of memory");
            return SLUICE_ERROR;
        }
    layer_sum = gather[0];
    const double layer_count = gather[1], near_count = gather[2], crossed_count = gather[3];
    double row[6] = {v->time,
                     crossed_count,
                     (double)s->crossed_count,
                     isfinite(gap_min) ? gap_min : NAN,
                     layer_count > 0 ? layer_sum / layer_count : NAN,
                     near_count};
    if (api->output->table_row(s->table, row, 6) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->stop && crossed_count > 0) {
        /* every rank stops; those holding a particle behind a wall name one */
        if (crossed == 0) {
            api->messages->error(host,
                       "step %lld, t = %.9g s: %.0f fluid particles are behind walls, on other "
                       "ranks (whose messages name one)",
                       (long long)v->step, v->time, crossed_count);
            return SLUICE_ERROR;
        }
        const sluice_index i = first_bad;
        sluice_real p[3] = {v->position[0][i], v->position[1][i],
                            v->dimensions == 3 ? v->position[2][i] : 0};
        sluice_wall_point w;
        api->walls->wall_nearest(host, p, -1, &w);
        const sluice_wall *wall = api->walls->wall(host, w.wall);
        api->messages->error(host,
                   "step %lld, t = %.9g s: fluid particle id %llu at (%g, %g, %g) m is %.3g m "
                   "behind wall %u%s%s%s (scheme %s); %.0f fluid particles are behind walls",
                   (long long)v->step, v->time, (unsigned long long)v->id[i], (double)p[0],
                   (double)p[1], (double)p[2], -(double)w.distance, w.wall,
                   wall && wall->name[0] ? " '" : "", wall ? wall->name : "",
                   wall && wall->name[0] ? "'" : "", wall ? wall->scheme : "?", crossed_count);
        return SLUICE_ERROR;
    }
    sluice_schedule_advance(&s->rows, api, host, v->time);
    return SLUICE_OK;
}

/* Checkpoints: the rows written and the (sorted) ids of the particles already reported behind a wall. */
static int monitor_save(void *state, sluice_host *host)
{
    const monitor_state *s = state;
    if (sluice_schedule_save(&s->rows, s->api, host, "rows_written") != SLUICE_OK)
        return SLUICE_ERROR;
    return s->api->state->state_write(host, "crossed_ids", SLUICE_STATE_UINT64, s->crossed_count,
                               s->crossed_ids);
}

static int monitor_load(void *state, sluice_host *host)
{
    monitor_state *s = state;
    int64_t length = s->api->state->state_length(host, "crossed_ids");
    if (sluice_schedule_load(&s->rows, s->api, host, "rows_written") != SLUICE_OK ||
        length < 0)
        return SLUICE_ERROR;
    if ((size_t)length > s->crossed_capacity) {
        sluice_id *ids = realloc(s->crossed_ids, (size_t)length * sizeof *ids);
        if (!ids) {
            s->api->messages->error(host, "out of memory");
            return SLUICE_ERROR;
        }
        s->crossed_ids = ids;
        s->crossed_capacity = (size_t)length;
    }
    s->crossed_count = (size_t)length;
    return s->api->state->state_read(host, "crossed_ids", SLUICE_STATE_UINT64, (uint64_t)length,
                              s->crossed_ids);
}

static const sluice_component components[] = {{
    .name = "wall_monitor",
    .summary = "fluid against the walls: particles behind walls, smallest gap, first-layer gap",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_ACROSS_RANKS,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(monitor_config),
    .create = monitor_create,
    .destroy = monitor_destroy,
    .initialise = monitor_initialise,
    .after_step = monitor_after_step,
    .save_state = monitor_save,
    .load_state = monitor_load,
}};

SLUICE_DEFINE_LIBRARY("wall_monitor", "1.1.0", "wall monitor", SLUICE_DIMS_ALL, components)
