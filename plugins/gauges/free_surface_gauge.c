/* Free-surface gauges: the elevation eta (m) of the free surface above each of
 * a list of horizontal positions, as a CSV time series.
 *
 * Method (kernel-sum threshold, the one of DualSPHysics' MeasureTool, used by
 * seed 002, Lin et al. 2025, for its free-surface profiles): above each
 * position a vertical column of sample points y_0 = bottom, ..., y_n = top
 * (spacing at most `sample_spacing` dx) carries the kernel sum of the fluid
 *
 *   S(y) = sum_j V_j W(x - x_j),   V_j = m_j / rho_j   (no Shepard division),
 *
 * the fraction of the kernel support filled with fluid: 1 inside, 0 in the air
 * and 1/2 on a flat free surface (W is symmetric: the half-space holds half
 * of its unit integral). eta is the highest elevation where S crosses
 * `threshold` (default 1/2) from above: the highest sample y_i with
 * S_i >= threshold, refined by linear interpolation of S to the next sample,
 *
 *   eta = y_i + (S_i - threshold) / (S_i - S_i+1) (y_i+1 - y_i),
 *
 * (eta = top when the top sample is wet, nan when no sample is: no fluid
 * above that position). Spray above the surface counts when its kernel sum
 * reaches the threshold (a dense jet, not single droplets). The vertical is
 * the last axis (y in 2D, z in 3D: the gravity plugin's convention); in 3D
 * each position also needs its y (`lateral`). The state is the integrated one
 * (position, mass, density): no evaluation is needed.
 *
 * In a two-phase scene `phase: water` sums over the water only, so that the
 * surface is the water's, not the top of the air (phase_filter.h).
 *
 * Cost: one api->evaluation->point_pass over every sample of every column per output row;
 * the samples are bounded (MAX_SAMPLES; the scene is refused beyond it).
 * Columns: time, eta_x<k> (m) for k = 0, 1, ... in the order of `positions`.
 *
 * Across MPI ranks (ABI 1.8, SLUICE_COMPONENT_ACROSS_RANKS): each rank's
 * point pass sums over its own particles only, so the gauge adds the ranks'
 * kernel sums of every sample (one api->ranks->reduce) before it looks for the
 * threshold crossing; rank 0 writes the row. The rows are the one-rank rows
 * up to the order of the sums. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sluice/gauge_column.h>
#include <sluice/phase_filter.h>

#define MAX_SAMPLES 1000000u

typedef struct fs_config {
    sluice_real_list positions, lateral, bottom, top;
    sluice_real sample_spacing, threshold, interval;
    const char *file;
    int phase;
} fs_config;

typedef struct fs_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_index columns;
    sluice_index *first;   /* columns + 1: the samples of column k are first[k] .. first[k+1]-1 */
    sluice_real *points;   /* 3 reals per sample, bottom to top within a column */
    double *sum;           /* kernel sum per sample */
    double *row;
    sluice_real threshold;
    const char *file;
    sluice_field density, mass, phase;
    int phase_filter;
    sluice_table *table;
    sluice_schedule rows; /* the next row is due at rows.count x rows.interval */
} fs_state;

static const sluice_param_spec params[] = {
    {"positions", SLUICE_PARAM_REAL_LIST, offsetof(fs_config, positions), NULL, 0, 0, 0, "m",
     "x of each gauge", NULL, 0},
    {"lateral", SLUICE_PARAM_REAL_LIST, offsetof(fs_config, lateral), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m",
     "3D only (required there): y of each gauge, one value for all or one per position", NULL,
     0},
    {"bottom", SLUICE_PARAM_REAL_LIST, offsetof(fs_config, bottom), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m",
     "lowest sample elevation, one value for all or one per position (default: domain.min of "
     "the vertical axis)",
     NULL, 0},
    {"top", SLUICE_PARAM_REAL_LIST, offsetof(fs_config, top), NULL, 0, 0, SLUICE_PARAM_OPTIONAL,
     "m",
     "highest sample elevation, one value for all or one per position (default: domain.max of "
     "the vertical axis)",
     NULL, 0},
    {"sample_spacing", SLUICE_PARAM_REAL, offsetof(fs_config, sample_spacing), "0.25", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "largest vertical distance between samples, in particle spacings dx", NULL, 0},
    {"threshold", SLUICE_PARAM_REAL, offsetof(fs_config, threshold), "0.5", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX |
         SLUICE_PARAM_MAX_EXCLUSIVE,
     "1", "kernel sum sum_j V_j W at the free surface (1/2 on a flat surface)", NULL, 0},
    {"interval", SLUICE_PARAM_REAL, offsetof(fs_config, interval), "0.01", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between samples", NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(fs_config, file), "free_surface.csv", 0, 0, 0, NULL,
     "output file in the run directory", NULL, 0},
    SLUICE_PHASE_PARAM(fs_config, phase),
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_DENSITY(0),
    SLUICE_SPEC_MASS(0),
};

static void fs_destroy(void *state)
{
    fs_state *s = state;
    if (!s)
        return;
    free(s->first);
    free(s->points);
    free(s->sum);
    free(s->row);
    free(s);
}

static int fs_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const fs_config *c = config;
    if (c->positions.count == 0) {
        api->messages->error(host, "'positions' is empty: list the x of at least one gauge (m)");
        return SLUICE_ERROR;
    }
    fs_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    sluice_real dims, dx, lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &dx) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    const uint32_t up = s->dims - 1; /* the vertical axis */
    const int have_domain = api->fields->constant(host, "domain_min", lo, 3) == s->dims &&
                            api->fields->constant(host, "domain_max", hi, 3) == s->dims;
    s->columns = c->positions.count;
    s->threshold = c->threshold;
    s->rows = sluice_schedule_every(c->interval);
    s->file = c->file;
    s->phase_filter = c->phase;
    if (sluice_phase_declare(api, host, s->phase_filter) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    const char *per = "positions";
    if (sluice_gauge_check_list(api, host, "lateral", &c->lateral, s->columns, per) != SLUICE_OK ||
        sluice_gauge_check_list(api, host, "bottom", &c->bottom, s->columns, per) != SLUICE_OK ||
        sluice_gauge_check_list(api, host, "top", &c->top, s->columns, per) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    if (s->dims == 3 && c->lateral.count == 0) {
        api->messages->error(host, "needs 'lateral' in 3D: the y of each gauge (one value for all or one "
                         "per position; z is vertical)");
        free(s);
        return SLUICE_ERROR;
    }
    if (s->dims == 2 && c->lateral.count > 0) {
        api->messages->error(host, "'lateral' (the y of each gauge) is for 3D scenes; in 2D give only "
                         "'positions'");
        free(s);
        return SLUICE_ERROR;
    }
    if ((c->bottom.count == 0 || c->top.count == 0) && !have_domain) {
        api->messages->error(host, "needs 'bottom' and 'top' (the core does not publish the domain)");
        free(s);
        return SLUICE_ERROR;
    }
    s->first = calloc((size_t)s->columns + 1, sizeof *s->first);
    if (!s->first) {
        api->messages->error(host, "out of memory");
        fs_destroy(s);
        return SLUICE_ERROR;
    }
    const double step = (double)c->sample_spacing * (double)dx;
    size_t total = 0;
    for (sluice_index k = 0; k < s->columns; k++) {
        const double b = (double)sluice_gauge_list_value(&c->bottom, k, lo[up]);
        const double t = (double)sluice_gauge_list_value(&c->top, k, hi[up]);
        if (!(t > b)) {
            api->messages->error(host, "gauge %u at x = %g m: top %g m is not above bottom %g m", k,
                       (double)c->positions.values[k], t, b);
            fs_destroy(s);
            return SLUICE_ERROR;
        }
        /* n intervals of at most `step` (a hair of slack so that a span that
         * is a whole number of steps is not split into one more) */
        const double intervals = ceil((t - b) / step * (1 - 1e-12));
        total += (size_t)(intervals < 1 ? 1 : intervals) + 1;
        if (!(intervals < MAX_SAMPLES) || total > MAX_SAMPLES) {
            api->messages->error(host, "the sample columns hold more than %u points (sample_spacing %g dx "
                             "= %g m); narrow bottom/top or raise sample_spacing",
                       MAX_SAMPLES, (double)c->sample_spacing, step);
            fs_destroy(s);
            return SLUICE_ERROR;
        }
        s->first[k + 1] = (sluice_index)total;
    }
    s->points = malloc(3 * total * sizeof *s->points);
    s->sum = calloc(total, sizeof *s->sum);
    s->row = calloc((size_t)s->columns + 1, sizeof *s->row);
    if (!s->points || !s->sum || !s->row) {
        api->messages->error(host, "out of memory (%zu samples)", total);
        fs_destroy(s);
        return SLUICE_ERROR;
    }
    for (sluice_index k = 0; k < s->columns; k++) {
        const double b = (double)sluice_gauge_list_value(&c->bottom, k, lo[up]);
        const double t = (double)sluice_gauge_list_value(&c->top, k, hi[up]);
        const sluice_index n = s->first[k + 1] - s->first[k] - 1;
        for (sluice_index i = 0; i <= n; i++) {
            sluice_real *p = s->points + 3 * ((size_t)s->first[k] + i);
            p[0] = c->positions.values[k];
            p[1] = s->dims == 3 ? sluice_gauge_list_value(&c->lateral, k, 0) : 0;
            p[2] = 0;
            p[up] = (sluice_real)(i == n ? t : b + (t - b) * (double)i / (double)n);
        }
    }
    *state = s;
    return SLUICE_OK;
}

static int fs_bind(void *state, sluice_host *host)
{
    fs_state *s = state;
    if (s->api->fields->field(host, "density", &s->density) != SLUICE_OK ||
        s->api->fields->field(host, "mass", &s->mass) != SLUICE_OK ||
        sluice_phase_bind(s->api, host, s->phase_filter, &s->phase) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static int fs_initialise(void *state, sluice_host *host)
{
    fs_state *s = state;
    size_t size = 16 + 24 * (size_t)s->columns;
    char *header = malloc(size);
    if (!header) {
        s->api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    size_t used = (size_t)snprintf(header, size, "time");
    for (sluice_index k = 0; k < s->columns; k++)
        used += (size_t)snprintf(header + used, size - used, ",eta_x%u", k);
    s->table = s->api->output->table_open(host, s->file, header);
    free(header);
    if (!s->table)
        return SLUICE_ERROR;
    /* each column at the foot of its vertical line of samples */
    const sluice_api_output *out = s->api->output;
    if (out->table_column(s->table, 0, "s", "simulated time", NULL) != SLUICE_OK)
        return SLUICE_ERROR;
    for (sluice_index k = 0; k < s->columns; k++)
        if (out->table_column(s->table, 1 + k, "m",
                              "free-surface elevation: the vertical coordinate of the surface on the "
                              "vertical line of samples through the position (its lowest sample)",
                              s->points + 3 * (size_t)s->first[k]) != SLUICE_OK)
            return SLUICE_ERROR;
    return SLUICE_OK;
}

/* S = sum_j V_j W at each sample of the batch (fluid neighbours only). */
static void kernel_sums(void *context, const sluice_view *v, const sluice_pair_batch *b)
{
    fs_state *s = context;
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict m = sluice_real_column(v, s->mass, 0);
    const sluice_real *restrict W = b->kernel;
    const sluice_index *restrict nb = b->neighbour;
    const uint8_t *phase = sluice_phase_column(v, s->phase);
    const uint8_t wanted = sluice_phase_wanted(s->phase_filter);
    for (sluice_index t = 0; t < b->target_count; t++) {
        double sum = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_index j = nb[k];
            if (sluice_phase_skips(phase, wanted, j))
                continue;
            sum += (double)(m[j] / rho[j] * W[k]);
        }
        s->sum[b->target[t]] = sum;
    }
}

/* The highest crossing of the threshold in column k, or nan. */
static double surface(const fs_state *s, sluice_index k)
{
    const sluice_index a = s->first[k];
    return sluice_gauge_surface(s->first[k + 1] - a, s->sum + a, 1, s->points + 3 * (size_t)a,
                                s->dims - 1, (double)s->threshold);
}

static int fs_after_step(void *state, sluice_host *host)
{
    fs_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (!sluice_schedule_due(&s->rows, v->time))
        return SLUICE_OK;
    const sluice_index total = s->first[s->columns];
    if (api->evaluation->point_pass(host, s->points, total, SLUICE_KIND_MASK(SLUICE_KIND_FLUID), kernel_sums,
                        s) != SLUICE_OK)
        return SLUICE_ERROR;
    /* across ranks each rank summed its own particles: add the ranks' sums
     * (collective; the identity on one rank) before the threshold */
    if (api->ranks->reduce(host, s->sum, total, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host);
    s->row[0] = v->time;
    for (sluice_index k = 0; k < s->columns; k++)
        s->row[1 + k] = surface(s, k);
    if (api->output->table_row(s->table, s->row, s->columns + 1) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->rows, api, host, v->time);
    return SLUICE_OK;
}

/* Checkpoints: the rows written (the next row is at rows_written x interval). */
SLUICE_DEFINE_SCHEDULE_STATE(fs_save, fs_load, fs_state, rows, "rows_written")

static const sluice_component components[] = {{
    .name = "free_surface_gauge",
    .summary = "free-surface elevation above listed positions (kernel-sum threshold on a "
               "vertical column of samples), as a CSV time series",
    .reference = "seed 002 (Lin et al. 2025) free-surface profiles; DualSPHysics MeasureTool "
                 "(kernel sum 0.5)",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_ACROSS_RANKS,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(fs_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = fs_create,
    .destroy = fs_destroy,
    .bind = fs_bind,
    .initialise = fs_initialise,
    .after_step = fs_after_step,
    .save_state = fs_save,
    .load_state = fs_load,
}};

SLUICE_DEFINE_LIBRARY("free_surface_gauge", "1.2.0", "free-surface elevation gauges",
                      SLUICE_DIMS_ALL, components)
