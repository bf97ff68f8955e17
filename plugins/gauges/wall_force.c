/* Wall force gauge (2D): the pressure force of the fluid on walls, as a CSV
 * time series. A hydraulic structure is judged by the force on it (a
 * stilling basin's blocks, a gate, the face of an abrupt drop: seed 004's
 * jump types follow from the momentum balance with the face's force), and
 * the wall schemes differ in it (docs/boundary-study.md), so the gauge
 * measures it the same way whatever the scheme: from the fluid's pressure
 * at the wall, not from the scheme's own wall forces.
 *
 * Each wall segment of the selected walls (`walls`: names, comma-separated;
 * default every wall), optionally only where it lies in a box (`box_min`,
 * `box_max`), is cut into pieces at most `sample_spacing` dx long. Each
 * piece's midpoint x_w gets a sample point x_s = x_w + offset dx n, n the
 * segment's unit normal into the fluid (in front of the wall, where the
 * fluid's kernel sum is not cut in half by the wall), and there the
 * Shepard-normalised pressure from the fluid particles
 *     p_s = sum_j V_j (p_j - p_ref) W / S,  S = sum_j V_j W,
 * p_ref the equation of state's published `reference_pressure` (0 when
 * none). The pressure at the wall is p_s carried back to x_w hydrostatically,
 * p_w = p_s - rho0 g . (x_s - x_w) (g the gravity vector; nothing without
 * gravity). The force of the fluid on the wall is
 *     F = sum over pieces of p_w (-n) ds,
 * over the wet pieces only (S >= min_kernel_sum); a dry piece (above the
 * water, or in a corner too narrow for the fluid's kernel sum) adds
 * nothing, and its length is not in the wet length. Near a concave corner
 * the sample points of one wall lie close to the other: where S falls below
 * min_kernel_sum that part is missed. Columns per selected wall: Fx_<name>,
 * Fy_<name> (N per metre of width), wet_<name> (the wet length, m); an
 * unnamed wall is wall<k>, k its index in the scene, and a second wall of
 * the same name <name><k>.
 *
 * The gauge evaluates the current state first (as point_gauge), so the
 * pressure is the sampled state's, at t = 0 too. 2D only (3D walls are
 * triangles; not implemented: refused). Across MPI ranks each rank sums its
 * own particles, the gauge adds the ranks' sums (one api->ranks->reduce) before it
 * divides; rank 0 writes the row. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sluice/phase_filter.h>

#define MAX_SAMPLES 1000000u
#define MAX_WALLS 32

typedef struct wf_config {
    const char *walls;
    sluice_real box_min[3], box_max[3];
    sluice_real offset, sample_spacing, min_kernel_sum, interval;
    const char *file;
    int phase;
} wf_config;

typedef struct wf_state {
    const sluice_api *api;
    char *wall_text;                 /* the `walls` list, split in place */
    uint32_t wanted_count;
    char *wanted[MAX_WALLS];         /* the names asked for (none: every wall) */
    int box;
    double box_min[2], box_max[2];
    double offset, spacing, min_kernel_sum;
    const char *file;
    int phase_filter;
    /* the measured walls, in scene order */
    uint32_t wall_count;
    uint32_t wall_index[MAX_WALLS];
    char column_name[MAX_WALLS][80];
    /* samples */
    sluice_index count;
    sluice_real *points;   /* 3 per sample */
    double *geometry;      /* 4 per sample: -n_x ds, -n_y ds, ds, hydrostatic shift (Pa) */
    uint32_t *owner;       /* measured wall of each sample */
    double *sums;          /* 2 per sample: S, sum_j V_j (p_j - p_ref) W */
    double *row;
    double reference_pressure;
    sluice_field density, mass, pressure, phase;
    sluice_table *table;
    sluice_schedule rows; /* the next row is due at rows.count x rows.interval */
} wf_state;

static const sluice_param_spec params[] = {
    {"walls", SLUICE_PARAM_STRING, offsetof(wf_config, walls), "", 0, 0, 0, NULL,
     "comma-separated names of the walls to measure (geometry.walls[].name); empty: every "
     "wall",
     NULL, 0},
    {"box_min", SLUICE_PARAM_VECTOR, offsetof(wf_config, box_min), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m",
     "with box_max: only the parts of the walls inside this box (e.g. a step's face)", NULL,
     2},
    {"box_max", SLUICE_PARAM_VECTOR, offsetof(wf_config, box_max), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m", "upper corner of that box", NULL, 2},
    {"offset", SLUICE_PARAM_REAL, offsetof(wf_config, offset), "1", 0, 2,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "distance of the sample points in front of the wall, in particle spacings dx (the "
     "pressure is carried back to the wall hydrostatically)",
     NULL, 0},
    {"sample_spacing", SLUICE_PARAM_REAL, offsetof(wf_config, sample_spacing), "0.25", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "largest length of a wall piece, in particle spacings dx", NULL, 0},
    {"min_kernel_sum", SLUICE_PARAM_REAL, offsetof(wf_config, min_kernel_sum), "0.2", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "a piece whose sample point has a smaller kernel sum sum_j V_j W is dry (no force)", NULL,
     0},
    {"interval", SLUICE_PARAM_REAL, offsetof(wf_config, interval), "0.01", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between samples", NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(wf_config, file), "wall_forces.csv", 0, 0, 0, NULL,
     "output file in the run directory", NULL, 0},
    SLUICE_PHASE_PARAM(wf_config, phase),
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_DENSITY(0),
    SLUICE_SPEC_MASS(0),
    SLUICE_SPEC_PRESSURE_DOC(SLUICE_READ, 0, "pressure"),
};

static void wf_destroy(void *state)
{
    wf_state *s = state;
    if (!s)
        return;
    free(s->wall_text);
    free(s->points);
    free(s->geometry);
    free(s->owner);
    free(s->sums);
    free(s->row);
    free(s);
}

static char *trim(char *text)
{
    while (*text == ' ' || *text == '\t')
        text++;
    char *end = text + strlen(text);
    while (end > text && (end[-1] == ' ' || end[-1] == '\t'))
        *--end = '\0';
    return text;
}

static int wf_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const wf_config *c = config;
    sluice_real dims, dx;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &dx) != SLUICE_OK)
        return SLUICE_ERROR;
    if (dims != 2) {
        api->messages->error(host, "measures 2D walls only (3D walls are triangles: not implemented)");
        return SLUICE_ERROR;
    }
    wf_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->offset = (double)c->offset * (double)dx;
    s->spacing = (double)c->sample_spacing * (double)dx;
    s->min_kernel_sum = (double)c->min_kernel_sum;
    s->rows = sluice_schedule_every(c->interval);
    s->file = c->file;
    s->phase_filter = c->phase;
    const int has_box = c->box_min[0] != 0 || c->box_min[1] != 0 || c->box_max[0] != 0 ||
                        c->box_max[1] != 0;
    if (has_box) {
        if (!(c->box_max[0] > c->box_min[0] && c->box_max[1] > c->box_min[1])) {
            api->messages->error(host, "box_max (%g, %g) m must exceed box_min (%g, %g) m in x and y "
                             "(give both, or neither for the whole walls)",
                       (double)c->box_max[0], (double)c->box_max[1], (double)c->box_min[0],
                       (double)c->box_min[1]);
            free(s);
            return SLUICE_ERROR;
        }
        s->box = 1;
        for (int d = 0; d < 2; d++) {
            s->box_min[d] = (double)c->box_min[d];
            s->box_max[d] = (double)c->box_max[d];
        }
    }
    const char *list = c->walls ? c->walls : "";
    s->wall_text = malloc(strlen(list) + 1);
    if (s->wall_text)
        memcpy(s->wall_text, list, strlen(list) + 1);
    if (!s->wall_text) {
        api->messages->error(host, "out of memory");
        free(s);
        return SLUICE_ERROR;
    }
    for (char *next = s->wall_text; next;) {
        char *comma = strchr(next, ',');
        if (comma)
            *comma = '\0';
        char *name = trim(next);
        if (*name) {
            if (s->wanted_count == MAX_WALLS) {
                api->messages->error(host, "'walls' lists more than %d names", MAX_WALLS);
                wf_destroy(s);
                return SLUICE_ERROR;
            }
            s->wanted[s->wanted_count++] = name;
        } else if (comma || s->wanted_count > 0) {
            api->messages->error(host, "'walls' has an empty name: list names separated by commas");
            wf_destroy(s);
            return SLUICE_ERROR;
        }
        next = comma ? comma + 1 : NULL;
    }
    if (sluice_phase_declare(api, host, s->phase_filter) != SLUICE_OK) {
        wf_destroy(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int wf_bind(void *state, sluice_host *host)
{
    wf_state *s = state;
    const sluice_api *api = s->api;
    const sluice_field_binding fields[] = {
        {"density", &s->density}, {"mass", &s->mass}, {"pressure", &s->pressure}};
    if (sluice_util_bind(api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    if (sluice_phase_bind(api, host, s->phase_filter, &s->phase) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real p_ref = 0;
    if (api->fields->constant(host, "reference_pressure", &p_ref, 1) == 1)
        s->reference_pressure = (double)p_ref;
    return SLUICE_OK;
}

static int in_box(const wf_state *s, double x, double y)
{
    return !s->box || (x >= s->box_min[0] && x <= s->box_max[0] && y >= s->box_min[1] &&
                       y <= s->box_max[1]);
}

/* The walls to measure, their pieces and sample points, the table. */
static int wf_initialise(void *state, sluice_host *host)
{
    wf_state *s = state;
    const sluice_api *api = s->api;
    sluice_real g[3] = {0, 0, 0}, rho0 = 1000;
    api->fields->constant(host, "gravity", g, 3);
    if (sluice_util_constant(api, host, "rest_density", &rho0) != SLUICE_OK)
        return SLUICE_ERROR;
    const uint32_t walls = api->walls->wall_count(host);
    int found[MAX_WALLS] = {0};
    size_t total = 0;
    for (int pass = 0; pass < 2; pass++) {
        size_t n = 0;
        s->wall_count = 0;
        for (uint32_t w = 0; w < walls; w++) {
            const sluice_wall *wall = api->walls->wall(host, w);
            if (!wall)
                continue;
            const char *name = wall->name ? wall->name : "";
            if (s->wanted_count > 0) {
                uint32_t k = 0;
                while (k < s->wanted_count && strcmp(s->wanted[k], name) != 0)
                    k++;
                if (k == s->wanted_count)
                    continue;
                found[k] = 1;
            }
            if (s->wall_count == MAX_WALLS) {
                api->messages->error(host, "measures at most %d walls: name the ones wanted in 'walls'",
                           MAX_WALLS);
                return SLUICE_ERROR;
            }
            const uint32_t slot = s->wall_count++;
            if (pass == 0) {
                s->wall_index[slot] = w;
                int repeated = 0;
                for (uint32_t k = 0; k < slot; k++)
                    repeated |= *name && strcmp(s->column_name[k], name) == 0;
                if (*name && !repeated)
                    snprintf(s->column_name[slot], sizeof s->column_name[slot], "%s", name);
                else if (*name)
                    snprintf(s->column_name[slot], sizeof s->column_name[slot], "%.60s%u", name,
                             w);
                else
                    snprintf(s->column_name[slot], sizeof s->column_name[slot], "wall%u", w);
            }
            for (uint32_t e = 0; e < wall->element_count; e++) {
                const sluice_real *a = wall->points + 6 * (size_t)e, *b = a + 3;
                const sluice_real *normal = wall->normals + 3 * (size_t)e;
                const double ex = (double)b[0] - (double)a[0], ey = (double)b[1] - (double)a[1];
                const double length = sqrt(ex * ex + ey * ey);
                if (!(length > 0))
                    continue;
                const double pieces_real = ceil(length / s->spacing * (1 - 1e-12));
                if (!(pieces_real < MAX_SAMPLES)) {
                    api->messages->error(host, "wall '%s' would need more than %u sample points",
                               s->column_name[slot], MAX_SAMPLES);
                    return SLUICE_ERROR;
                }
                const size_t pieces = pieces_real < 1 ? 1 : (size_t)pieces_real;
                const double ds = length / (double)pieces;
                for (size_t k = 0; k < pieces; k++) {
                    const double t = ((double)k + 0.5) / (double)pieces;
                    const double xw = (double)a[0] + t * ex, yw = (double)a[1] + t * ey;
                    if (!in_box(s, xw, yw))
                        continue;
                    if (pass == 1) {
                        const double nx = (double)normal[0], ny = (double)normal[1];
                        sluice_real *p = s->points + 3 * n;
                        p[0] = (sluice_real)(xw + s->offset * nx);
                        p[1] = (sluice_real)(yw + s->offset * ny);
                        p[2] = 0;
                        double *q = s->geometry + 4 * n;
                        q[0] = -nx * ds;
                        q[1] = -ny * ds;
                        q[2] = ds;
                        /* p_w = p_s - rho0 g . (x_s - x_w) */
                        q[3] = -(double)rho0 * ((double)g[0] * s->offset * nx +
                                                (double)g[1] * s->offset * ny);
                        s->owner[n] = slot;
                    }
                    if (++n > MAX_SAMPLES) {
                        api->messages->error(host, "more than %u sample points: raise sample_spacing or "
                                         "measure fewer walls",
                                   MAX_SAMPLES);
                        return SLUICE_ERROR;
                    }
                }
            }
        }
        if (pass == 0) {
            for (uint32_t k = 0; k < s->wanted_count; k++)
                if (!found[k]) {
                    api->messages->error(host, "no wall is named '%s' (geometry.walls[].name)",
                               s->wanted[k]);
                    return SLUICE_ERROR;
                }
            if (s->wall_count == 0) {
                api->messages->error(host, "the scene has no walls to measure");
                return SLUICE_ERROR;
            }
            if (n == 0) {
                api->messages->error(host, "no part of the measured walls lies in the box [%g, %g] x "
                                 "[%g, %g] m",
                           s->box_min[0], s->box_max[0], s->box_min[1], s->box_max[1]);
                return SLUICE_ERROR;
            }
            total = n;
            s->points = malloc(3 * total * sizeof *s->points);
            s->geometry = malloc(4 * total * sizeof *s->geometry);
            s->owner = malloc(total * sizeof *s->owner);
            s->sums = calloc(2 * total, sizeof *s->sums);
            s->row = calloc(3 * (size_t)s->wall_count + 1, sizeof *s->row);
            if (!s->points || !s->geometry || !s->owner || !s->sums || !s->row) {
                api->messages->error(host, "out of memory (%zu sample points)", total);
                return SLUICE_ERROR;
            }
        }
    }
    s->count = (sluice_index)total;
    size_t size = 16 + 3 * (80 + 8) * (size_t)s->wall_count;
    char *header = malloc(size);
    if (!header) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    size_t used = (size_t)snprintf(header, size, "time");
    for (uint32_t k = 0; k < s->wall_count; k++)
        used += (size_t)snprintf(header + used, size - used, ",Fx_%s,Fy_%s,wet_%s",
                                 s->column_name[k], s->column_name[k], s->column_name[k]);
    s->table = api->output->table_open(host, s->file, header);
    free(header);
    return s->table ? SLUICE_OK : SLUICE_ERROR;
}

/* S and sum_j V_j (p_j - p_ref) W at each sample of the batch. */
static void wall_sums(void *context, const sluice_view *v, const sluice_pair_batch *b)
{
    wf_state *s = context;
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict m = sluice_real_column(v, s->mass, 0);
    const sluice_real *restrict p = sluice_real_column(v, s->pressure, 0);
    const sluice_real *restrict W = b->kernel;
    const sluice_index *restrict nb = b->neighbour;
    const uint8_t *phase = sluice_phase_column(v, s->phase);
    const uint8_t wanted = sluice_phase_wanted(s->phase_filter);
    const double p_ref = s->reference_pressure;
    for (sluice_index t = 0; t < b->target_count; t++) {
        double sum = 0, force = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_index j = nb[k];
            if (sluice_phase_skips(phase, wanted, j))
                continue;
            const double w = (double)(m[j] / rho[j] * W[k]);
            sum += w;
            force += w * ((double)p[j] - p_ref);
        }
        s->sums[2 * (size_t)b->target[t]] = sum;
        s->sums[2 * (size_t)b->target[t] + 1] = force;
    }
}

static int wf_after_step(void *state, sluice_host *host)
{
    wf_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (!sluice_schedule_due(&s->rows, v->time))
        return SLUICE_OK;
    /* the pressure of the current state */
    if (api->evaluation->evaluate(host, api->particles->view(host)->time, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    memset(s->sums, 0, 2 * (size_t)s->count * sizeof *s->sums);
    if (api->evaluation->point_pass(host, s->points, s->count, SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
                        wall_sums, s) != SLUICE_OK)
        return SLUICE_ERROR;
    /* across ranks: add the ranks' sums before any division (collective) */
    if (api->ranks->reduce(host, s->sums, (uint32_t)(2 * s->count), SLUICE_REDUCE_SUM) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host);
    memset(s->row, 0, (3 * (size_t)s->wall_count + 1) * sizeof *s->row);
    s->row[0] = v->time;
    for (sluice_index i = 0; i < s->count; i++) {
        const double S = s->sums[2 * (size_t)i];
        if (!(S >= s->min_kernel_sum))
            continue;
        const double *q = s->geometry + 4 * (size_t)i;
        const double p_wall = s->sums[2 * (size_t)i + 1] / S + q[3];
        double *out = s->row + 1 + 3 * (size_t)s->owner[i];
        out[0] += p_wall * q[0];
        out[1] += p_wall * q[1];
        out[2] += q[2];
    }
    if (api->output->table_row(s->table, s->row, 3 * s->wall_count + 1) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->rows, api, host, v->time);
    return SLUICE_OK;
}

/* Checkpoints: the rows written (the next row is at rows_written x interval). */
SLUICE_DEFINE_SCHEDULE_STATE(wf_save, wf_load, wf_state, rows, "rows_written")

static const sluice_component components[] = {{
    .name = "wall_force",
    .summary = "2D pressure force of the fluid on named walls (or their part in a box), from "
               "the fluid's pressure in front of them, whatever the wall scheme, as a CSV time "
               "series",
    .reference = "momentum balance of a jump at an abrupt drop (Hager 1985; seed 004, De Padova "
                 "et al. 2017); Shepard interpolation as point_gauge",
    .dimensions = SLUICE_DIMS_2,
    .flags = SLUICE_COMPONENT_ACROSS_RANKS,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(wf_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = wf_create,
    .destroy = wf_destroy,
    .bind = wf_bind,
    .initialise = wf_initialise,
    .after_step = wf_after_step,
    .save_state = wf_save,
    .load_state = wf_load,
}};

SLUICE_DEFINE_LIBRARY("wall_force", "1.0.0", "2D pressure force of the fluid on walls",
                      SLUICE_DIMS_2, components)
