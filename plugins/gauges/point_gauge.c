/* Point gauges: fields interpolated at fixed points, as a CSV time series.
 *
 * At every `interval` the gauge brings the rates and the equation of state to
 * the current state (one evaluation), then interpolates each listed field at
 * each point from the fluid particles with the Shepard-normalised kernel sum
 *   f(x) = sum_j V_j f_j W(x - x_j) / sum_j V_j W(x - x_j),  V_j = m_j / rho_j,
 * (exact for a constant field). A point whose kernel sum sum_j V_j W is below
 * `min_kernel_sum` lies outside the fluid (or at its edge, where the estimate
 * is biased): its values are written as nan. Columns: time, then for each
 * point k and field f: pK_f (vectors: pK_f_x, pK_f_y[, pK_f_z]).
 *
 * In a two-phase scene (the field `phase` of the two_phase plugin: 0 water,
 * 1 air) `phase: water` or `phase: air` sums over the particles of that phase
 * only: the dissolved oxygen of the water, or the water's velocity, next to
 * the interface, where the default sums over both.
 *
 * The pseudo-field `air_fraction` (two-phase scenes; column pK_air_fraction)
 * is the kernel-weighted volume fraction of air at the point,
 *   C(x) = sum_{j air} V_j W(x - x_j) / sum_{j fluid} V_j W(x - x_j),
 * always summed over every fluid particle whatever `phase` says (so that one
 * gauge with `phase: water` gives the water's velocity and the air fraction
 * at the same points), and nan where the sum over all fluid particles is
 * below `min_kernel_sum`. It is 0 where no air particle lies within the
 * kernel support (2h) of the point and 1 where no water particle does.
 *
 * Across MPI ranks (ABI 1.8, SLUICE_COMPONENT_ACROSS_RANKS): each rank's
 * point pass sums over its own particles only, so the gauge adds the ranks'
 * sums (every numerator and denominator of every point, one api->ranks->reduce)
 * before it divides or compares with min_kernel_sum; rank 0 writes the row.
 * The rows are the one-rank rows up to the order of the sums. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sluice/phase_filter.h>

#define MAX_FIELDS 16

/* The name of the pseudo-field; no plugin may declare a field of that name
 * for a point gauge to read (the gauge computes it). */
static const char air_fraction_name[] = "air_fraction";

typedef struct gauge_config {
    sluice_real_list points;
    const char *fields;
    sluice_real interval, min_kernel_sum;
    const char *file;
    int phase;
} gauge_config;

typedef struct gauge_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_index count;
    sluice_real *points;
    sluice_real min_kernel_sum;
    const char *file;
    char *field_text;
    uint32_t field_count, value_count; /* value_count: columns per point */
    char *names[MAX_FIELDS];
    /* the real fields read from the particles (air_fraction excluded), in
     * the order of `names`; slot[f] is the first sum slot of names[f]
     * (0 for air_fraction, whose slots are the last two) */
    uint32_t real_count, real_values;
    sluice_field real[MAX_FIELDS];
    uint32_t slot[MAX_FIELDS];
    int is_air[MAX_FIELDS];
    int air_fraction; /* 1 when `fields` lists air_fraction */
    sluice_field density, mass, phase, air_phase;
    int phase_filter; /* SLUICE_PHASE_* (phase_filter.h) */
    uint32_t stride;  /* sums per point */
    /* per point: the (phase-filtered) kernel sum, the real_values weighted
     * sums and, with air_fraction, the kernel sums over all fluid particles
     * and over the air particles */
    double *sums;
    double *row;
    sluice_table *table;
    sluice_schedule rows; /* the next row is due at rows.count x rows.interval */
} gauge_state;

static const sluice_param_spec params[] = {
    {"points", SLUICE_PARAM_POINT_LIST, offsetof(gauge_config, points), NULL, 0, 0, 0, "m",
     "where to measure", NULL, 0},
    {"fields", SLUICE_PARAM_STRING, offsetof(gauge_config, fields), "pressure,velocity", 0, 0,
     0, NULL,
     "comma-separated names of the real fields to interpolate; in a two-phase scene also "
     "air_fraction, the kernel-weighted volume fraction of air sum_{j air} V_j W / sum_{j fluid} "
     "V_j W (1; column pK_air_fraction), always summed over every fluid particle whatever "
     "`phase` says, and nan where that sum is below min_kernel_sum; it needs the field 'phase' "
     "of the two_phase plugin",
     NULL, 0},
    {"interval", SLUICE_PARAM_REAL, offsetof(gauge_config, interval), "0.01", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between samples", NULL, 0},
    {"min_kernel_sum", SLUICE_PARAM_REAL, offsetof(gauge_config, min_kernel_sum), "0.5", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "points whose kernel sum sum_j V_j W (over the particles `phase` selects; for "
     "air_fraction over every fluid particle) is below this are outside the fluid (nan)",
     NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(gauge_config, file), "points.csv", 0, 0, 0, NULL,
     "output file in the run directory", NULL, 0},
    SLUICE_PHASE_PARAM(gauge_config, phase),
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_DENSITY(0),
    SLUICE_SPEC_MASS(0),
};

static void gauge_destroy(void *state)
{
    gauge_state *s = state;
    if (!s)
        return;
    free(s->points);
    free(s->field_text);
    free(s->sums);
    free(s->row);
    free(s);
}

static int gauge_create(const sluice_api *api, sluice_host *host, const void *config,
                        void **state)
{
    const gauge_config *c = config;
    gauge_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    if (sluice_util_dimensions(api, host, &s->dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->count = c->points.count;
    s->rows = sluice_schedule_every(c->interval);
    s->min_kernel_sum = c->min_kernel_sum;
    s->file = c->file;
    s->phase_filter = c->phase;
    if (sluice_phase_declare(api, host, s->phase_filter) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->points = malloc((3 * (size_t)s->count + 3) * sizeof *s->points);
    size_t text_length = strlen(c->fields);
    s->field_text = malloc(text_length + 1);
    if (s->field_text)
        memcpy(s->field_text, c->fields, text_length + 1);
    if (!s->points || !s->field_text) {
        api->messages->error(host, "out of memory");
        gauge_destroy(s);
        return SLUICE_ERROR;
    }
    if (s->count == 0) {
        api->messages->error(host, "needs at least one point");
        gauge_destroy(s);
        return SLUICE_ERROR;
    }
    memcpy(s->points, c->points.values, 3 * (size_t)s->count * sizeof *s->points);
    /* split at commas and spaces, in place */
    for (char *p = s->field_text; *p;) {
        while (*p == ',' || *p == ' ')
            *p++ = '\0';
        if (!*p)
            break;
        if (s->field_count == MAX_FIELDS) {
            api->messages->error(host, "lists more than %d fields", MAX_FIELDS);
            gauge_destroy(s);
            return SLUICE_ERROR;
        }
        s->names[s->field_count++] = p;
        while (*p && *p != ',' && *p != ' ')
            p++;
    }
    if (s->field_count == 0) {
        api->messages->error(host, "lists no field");
        gauge_destroy(s);
        return SLUICE_ERROR;
    }
    for (uint32_t f = 0; f < s->field_count; f++) {
        s->is_air[f] = strcmp(s->names[f], air_fraction_name) == 0;
        if (s->is_air[f] && s->air_fraction) {
            api->messages->error(host, "fields: '%s' is listed twice", air_fraction_name);
            gauge_destroy(s);
            return SLUICE_ERROR;
        }
        s->air_fraction |= s->is_air[f];
    }
    *state = s;
    return SLUICE_OK;
}

static int gauge_bind(void *state, sluice_host *host)
{
    gauge_state *s = state;
    const sluice_api *api = s->api;
    if (api->fields->field(host, "density", &s->density) != SLUICE_OK ||
        api->fields->field(host, "mass", &s->mass) != SLUICE_OK ||
        sluice_phase_bind(api, host, s->phase_filter, &s->phase) != SLUICE_OK)
        return SLUICE_ERROR;
    s->air_phase.column = -1;
    if (s->air_fraction) {
        /* the phase written by two_phase (looked up, not declared: a missing
         * provider is reported here, naming the parameter) */
        if (!sluice_util_optional_field(api, host, "phase", &s->air_phase)) {
            api->messages->error(host,
                       "fields: '%s' needs the field 'phase' (0 water, 1 air) of the two_phase "
                       "plugin, which this scene does not load (load two_phase, or remove %s "
                       "from fields)",
                       air_fraction_name, air_fraction_name);
            return SLUICE_ERROR;
        }
        if (s->air_phase.type != SLUICE_TYPE_UINT8 || s->air_phase.components != 1) {
            api->messages->error(host, "fields: '%s' needs 'phase' as one uint8 per particle (0 water, 1 "
                             "air), as two_phase declares it",
                       air_fraction_name);
            return SLUICE_ERROR;
        }
    }
    s->value_count = 0;
    s->real_count = 0;
    s->real_values = 0;
    for (uint32_t f = 0; f < s->field_count; f++) {
        if (s->is_air[f]) {
            s->slot[f] = 0;
            s->value_count++;
            continue;
        }
        sluice_field field;
        if (!sluice_util_optional_field(api, host, s->names[f], &field)) {
            api->messages->error(host, "field '%s' is not declared by any loaded plugin (`sluice inspect` "
                             "lists each plugin's fields)",
                       s->names[f]);
            return SLUICE_ERROR;
        }
        if (field.type != SLUICE_TYPE_REAL) {
            api->messages->error(host, "field '%s' is not a real field", s->names[f]);
            return SLUICE_ERROR;
        }
        s->real[s->real_count++] = field;
        s->slot[f] = 1 + s->real_values;
        s->real_values += field.components;
        s->value_count += field.components;
    }
    s->stride = 1 + s->real_values + (s->air_fraction ? 2 : 0);
    if ((uint64_t)s->count * s->stride > UINT32_MAX) {
        api->messages->error(host, "%u points x %u sums are too many", (unsigned)s->count, s->stride);
        return SLUICE_ERROR;
    }
    s->sums = calloc((size_t)s->count * s->stride, sizeof *s->sums);
    s->row = calloc((size_t)s->count * s->value_count + 1, sizeof *s->row);
    if (!s->sums || !s->row) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

/* The declaration of the field `name` (its unit and description); the
 * pseudo-field air_fraction is a volume fraction. */
static void field_declaration(const sluice_api *api, sluice_host *host, const char *name,
                              const char **unit, const char **doc)
{
    *unit = "1";
    *doc = "kernel-weighted volume fraction of air";
    if (strcmp(name, air_fraction_name) == 0)
        return;
    const uint32_t count = api->fields->field_count(host);
    for (uint32_t i = 0; i < count; i++) {
        sluice_field_spec spec;
        if (api->fields->field_info(host, i, &spec, NULL) == SLUICE_OK &&
            strcmp(spec.name, name) == 0) {
            *unit = spec.units && *spec.units ? spec.units : "1";
            *doc = spec.doc && *spec.doc ? spec.doc : name;
            return;
        }
    }
}

/* Units and descriptions of the table's columns: each field's declared unit
 * and description (Shepard-interpolated), at its point. */
static int describe_columns(const gauge_state *s, sluice_host *host)
{
    static const char axes[] = "xyz";
    const sluice_api_output *out = s->api->output;
    if (out->table_column(s->table, 0, "s", "simulated time", NULL) != SLUICE_OK)
        return SLUICE_ERROR;
    uint32_t column = 1;
    for (sluice_index k = 0; k < s->count; k++)
        for (uint32_t f = 0, r = 0; f < s->field_count; f++) {
            const uint32_t components = s->is_air[f] ? 1 : s->real[r++].components;
            const char *unit, *doc;
            field_declaration(s->api, host, s->names[f], &unit, &doc);
            for (uint32_t c = 0; c < components; c++) {
                char description[320];
                if (components > 1)
                    snprintf(description, sizeof description, "%s, %c component, interpolated",
                             doc, c < 3 ? axes[c] : '?');
                else
                    snprintf(description, sizeof description, "%s, interpolated", doc);
                if (out->table_column(s->table, column++, unit, description,
                                      s->points + 3 * (size_t)k) != SLUICE_OK)
                    return SLUICE_ERROR;
            }
        }
    return SLUICE_OK;
}

static int gauge_initialise(void *state, sluice_host *host)
{
    gauge_state *s = state;
    size_t size = 16, used = 0;
    char *header = malloc(size);
    if (!header) {
        s->api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    static const char axes[] = "xyz";
    used = (size_t)snprintf(header, size, "time");
    for (sluice_index k = 0; k < s->count; k++)
        for (uint32_t f = 0, r = 0; f < s->field_count; f++) {
            const uint32_t components = s->is_air[f] ? 1 : s->real[r++].components;
            for (uint32_t c = 0; c < components; c++) {
                char column[160];
                int n = components > 1
                            ? snprintf(column, sizeof column, ",p%u_%s_%c", k, s->names[f],
                                       c < 3 ? axes[c] : '?')
                            : snprintf(column, sizeof column, ",p%u_%s", k, s->names[f]);
                if (n < 0)
                    continue;
                if (used + (size_t)n + 1 > size) {
                    size = 2 * (used + (size_t)n + 1);
                    char *grown = realloc(header, size);
                    if (!grown) {
                        free(header);
                        s->api->messages->error(host, "out of memory");
                        return SLUICE_ERROR;
                    }
                    header = grown;
                }
                memcpy(header + used, column, (size_t)n + 1);
                used += (size_t)n;
            }
        }
    s->table = s->api->output->table_open(host, s->file, header);
    free(header);
    if (!s->table)
        return SLUICE_ERROR;
    return describe_columns(s, host);
}

/* The sums of the listed real fields over the neighbours of one batch. */
static void accumulate(void *context, const sluice_view *v, const sluice_pair_batch *b)
{
    gauge_state *s = context;
    const sluice_real *rho = sluice_real_column(v, s->density, 0);
    const sluice_real *m = sluice_real_column(v, s->mass, 0);
    const uint32_t stride = s->stride;
    const uint8_t *phase = sluice_phase_column(v, s->phase);
    const uint8_t wanted = sluice_phase_wanted(s->phase_filter);
    for (sluice_index t = 0; t < b->target_count; t++) {
        double *sum = s->sums + (size_t)b->target[t] * stride;
        for (uint32_t c = 0; c < stride; c++)
            sum[c] = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_index j = b->neighbour[k];
            if (sluice_phase_skips(phase, wanted, j))
                continue;
            const double w = (double)m[j] / (double)rho[j] * (double)b->kernel[k];
            sum[0] += w;
            uint32_t slot = 1;
            for (uint32_t f = 0; f < s->real_count; f++)
                for (uint32_t c = 0; c < s->real[f].components; c++)
                    sum[slot++] += w * (double)sluice_real_column(v, s->real[f], c)[j];
        }
    }
}

/* The same with air_fraction: every fluid neighbour adds to the sum over all
 * fluid particles and, if air, to the sum over the air, before the phase
 * filter decides whether it enters the field sums. */
static void accumulate_air(void *context, const sluice_view *v, const sluice_pair_batch *b)
{
    gauge_state *s = context;
    const sluice_real *rho = sluice_real_column(v, s->density, 0);
    const sluice_real *m = sluice_real_column(v, s->mass, 0);
    const uint32_t stride = s->stride;
    const uint8_t *phase = sluice_phase_column(v, s->phase);
    const uint8_t *air_phase = sluice_phase_column(v, s->air_phase);
    const uint8_t wanted = sluice_phase_wanted(s->phase_filter);
    for (sluice_index t = 0; t < b->target_count; t++) {
        double *sum = s->sums + (size_t)b->target[t] * stride;
        for (uint32_t c = 0; c < stride; c++)
            sum[c] = 0;
        double all = 0, air = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_index j = b->neighbour[k];
            const double w = (double)m[j] / (double)rho[j] * (double)b->kernel[k];
            all += w;
            air += air_phase[j] == 1 ? w : 0.0;
            if (sluice_phase_skips(phase, wanted, j))
                continue;
            sum[0] += w;
            uint32_t slot = 1;
            for (uint32_t f = 0; f < s->real_count; f++)
                for (uint32_t c = 0; c < s->real[f].components; c++)
                    sum[slot++] += w * (double)sluice_real_column(v, s->real[f], c)[j];
        }
        sum[stride - 2] = all;
        sum[stride - 1] = air;
    }
}

static int gauge_after_step(void *state, sluice_host *host)
{
    gauge_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (!sluice_schedule_due(&s->rows, v->time))
        return SLUICE_OK;
    /* pressure and the other derived fields of the current state */
    if (api->evaluation->evaluate(host, api->particles->view(host)->time, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    const uint32_t stride = s->stride;
    memset(s->sums, 0, (size_t)s->count * stride * sizeof *s->sums);
    if (api->evaluation->point_pass(host, s->points, s->count, SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
                        s->air_fraction ? accumulate_air : accumulate, s) != SLUICE_OK)
        return SLUICE_ERROR;
    /* across ranks each rank summed its own particles: add the ranks' sums
     * (collective; the identity on one rank) before any division */
    if (api->ranks->reduce(host, s->sums, s->count * stride, SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host);
    s->row[0] = v->time;
    size_t column = 1;
    const double min_sum = (double)s->min_kernel_sum;
    for (sluice_index k = 0; k < s->count; k++) {
        const double *sum = s->sums + (size_t)k * stride;
        const int inside = sum[0] >= min_sum;
        for (uint32_t f = 0, r = 0; f < s->field_count; f++) {
            if (s->is_air[f]) {
                const double all = sum[stride - 2], air = sum[stride - 1];
                s->row[column++] = all >= min_sum ? air / all : NAN;
                continue;
            }
            const uint32_t components = s->real[r++].components;
            for (uint32_t c = 0; c < components; c++)
                s->row[column++] = inside ? sum[s->slot[f] + c] / sum[0] : NAN;
        }
    }
    if (api->output->table_row(s->table, s->row, (uint32_t)column) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->rows, api, host, v->time);
    return SLUICE_OK;
}

/* Checkpoints: the rows written (the next row is at rows_written x interval). */
SLUICE_DEFINE_SCHEDULE_STATE(gauge_save, gauge_load, gauge_state, rows, "rows_written")

static const sluice_component components[] = {{
    .name = "point_gauge",
    .summary = "fields interpolated at fixed points (Shepard kernel sum), as a CSV time series",
    .reference = "Shepard (1968) normalised SPH interpolation",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_ACROSS_RANKS,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(gauge_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = gauge_create,
    .destroy = gauge_destroy,
    .bind = gauge_bind,
    .initialise = gauge_initialise,
    .after_step = gauge_after_step,
    .save_state = gauge_save,
    .load_state = gauge_load,
}};

SLUICE_DEFINE_LIBRARY("point_gauge", "1.3.0", "point gauges", SLUICE_DIMS_ALL, components)
