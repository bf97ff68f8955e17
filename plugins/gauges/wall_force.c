/* Wall force gauge: the pressure force of the fluid on walls, as a CSV
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
 * In 3D the walls are triangles: each is cut into m^2 congruent
 * sub-triangles, m = ceil(longest edge / (sample_spacing dx)), whose
 * centroids are the pieces' midpoints and whose areas are their ds; the
 * columns are Fx, Fy, Fz (N) and the wet area (m^2). With `moment_about`
 * the gauge also gives the moment of the same pressure forces about that
 * point, M = sum (x_w - x_0) x p_w (-n) ds: Mz_<name> in 2D (N m per
 * metre of width), Mx, My, Mz in 3D (N m).
 *
 * The gauge evaluates the current state first (as point_gauge), so the
 * pressure is the sampled state's, at t = 0 too. Across MPI ranks each rank
 * sums its own particles, the gauge adds the ranks' sums (one
 * api->ranks->reduce) before it divides; rank 0 writes the row. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sluice/phase_filter.h>

#define MAX_SAMPLES 1000000u
#define MAX_WALLS 32

typedef struct wf_config {
    const char *walls;
    sluice_real box_min[3], box_max[3], moment_about[3];
    int moments;
    sluice_real offset, sample_spacing, min_kernel_sum, interval;
    const char *file;
    int phase;
} wf_config;

typedef struct wf_state {
    const sluice_api *api;
    char *wall_text;                 /* the `walls` list, split in place */
    uint32_t wanted_count;
    char *wanted[MAX_WALLS];         /* the names asked for (none: every wall) */
    int box, moments;
    uint32_t dims, columns; /* columns per wall: D forces, wet, [moments] */
    double box_min[3], box_max[3], moment_about[3];
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
    double *geometry;      /* 5 per sample: -n ds (3), ds, hydrostatic shift (Pa) */
    double *arm;           /* 3 per sample: x_w - moment_about (with moments) */
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
     SLUICE_LENGTH_DIM},
    {"box_max", SLUICE_PARAM_VECTOR, offsetof(wf_config, box_max), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m", "upper corner of that box", NULL, SLUICE_LENGTH_DIM},
    {"moments", SLUICE_PARAM_BOOL, offsetof(wf_config, moments), "false", 0, 0, 0, NULL,
     "also the moment of the pressure forces about moment_about: columns Mz_<name> (2D, N m "
     "per metre of width) or Mx_, My_, Mz_<name> (3D, N m)",
     NULL, 0},
    {"moment_about", SLUICE_PARAM_VECTOR, offsetof(wf_config, moment_about), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m", "the point the moments are taken about (default: the origin)",
     NULL, SLUICE_LENGTH_DIM},
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
    free(s->arm);
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
    wf_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->dims = dims == 3 ? 3 : 2;
    s->offset = (double)c->offset * (double)dx;
    s->spacing = (double)c->sample_spacing * (double)dx;
    s->min_kernel_sum = (double)c->min_kernel_sum;
    s->rows = sluice_schedule_every(c->interval);
    s->file = c->file;
    s->phase_filter = c->phase;
    int has_box = 0, box_ordered = 1;
    for (uint32_t d = 0; d < s->dims; d++) {
        has_box |= c->box_min[d] != 0 || c->box_max[d] != 0;
        box_ordered &= c->box_max[d] > c->box_min[d];
    }
    if (has_box) {
        if (!box_ordered) {
            api->messages->error(host, "box_max (%g, %g, %g) m must exceed box_min (%g, %g, %g) m in "
                                       "every direction (give both, or neither for the whole walls)",
                                 (double)c->box_max[0], (double)c->box_max[1],
                                 (double)c->box_max[2], (double)c->box_min[0],
                                 (double)c->box_min[1], (double)c->box_min[2]);
            free(s);
            return SLUICE_ERROR;
        }
        s->box = 1;
        for (uint32_t d = 0; d < s->dims; d++) {
            s->box_min[d] = (double)c->box_min[d];
            s->box_max[d] = (double)c->box_max[d];
        }
    }
    s->moments = c->moments;
    for (int d = 0; d < 3; d++)
        s->moment_about[d] = (double)c->moment_about[d];
    s->columns = s->dims + 1 + (s->moments ? (s->dims == 3 ? 3u : 1u) : 0u);
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

static int in_box(const wf_state *s, const double x[3])
{
    if (!s->box)
        return 1;
    for (uint32_t d = 0; d < s->dims; d++)
        if (!(x[d] >= s->box_min[d] && x[d] <= s->box_max[d]))
            return 0;
    return 1;
}

/* The pieces of element e of a wall: their midpoints x_w (3 each), normal
 * and length or area ds. 2D: a segment cut into m pieces at most `spacing`
 * long; 3D: a triangle cut into m^2 congruent sub-triangles, m = ceil(longest
 * edge / spacing), at their centroids. Returns the count, or 0 for a
 * degenerate element; with `out` NULL only counts (and checks the bound). */
static size_t element_pieces(const wf_state *s, const sluice_wall *wall, uint32_t e,
                             double (*out)[4])
{
    const uint32_t nv = s->dims;
    const sluice_real *v = wall->points + 3 * (size_t)nv * e;
    if (s->dims == 2) {
        const double ex = (double)v[3] - (double)v[0], ey = (double)v[4] - (double)v[1];
        const double length = sqrt(ex * ex + ey * ey);
        if (!(length > 0))
            return 0;
        const double real_m = ceil(length / s->spacing * (1 - 1e-12));
        if (!(real_m < MAX_SAMPLES))
            return MAX_SAMPLES + 1;
        const size_t m = real_m < 1 ? 1 : (size_t)real_m;
        for (size_t k = 0; out && k < m; k++) {
            const double t = ((double)k + 0.5) / (double)m;
            out[k][0] = (double)v[0] + t * ex;
            out[k][1] = (double)v[1] + t * ey;
            out[k][2] = 0;
            out[k][3] = length / (double)m;
        }
        return m;
    }
    double a[3], b[3], c[3], longest = 0;
    for (int d = 0; d < 3; d++) {
        a[d] = (double)v[d];
        b[d] = (double)v[3 + d] - a[d];
        c[d] = (double)v[6 + d] - a[d];
    }
    const double bc[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
    longest = fmax(sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]),
                   fmax(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                        sqrt(bc[0] * bc[0] + bc[1] * bc[1] + bc[2] * bc[2])));
    const double cross[3] = {b[1] * c[2] - b[2] * c[1], b[2] * c[0] - b[0] * c[2],
                             b[0] * c[1] - b[1] * c[0]};
    const double area = 0.5 * sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]);
    if (!(area > 0))
        return 0;
    const double real_m = ceil(longest / s->spacing * (1 - 1e-12));
    if (!(real_m * real_m < MAX_SAMPLES))
        return MAX_SAMPLES + 1;
    const size_t m = real_m < 1 ? 1 : (size_t)real_m;
    size_t n = 0;
    /* sub-triangle (i, j) pointing up: centroid at barycentric ((i + 1/3), (j + 1/3)) / m;
     * pointing down (i + j < m - 1): ((i + 2/3), (j + 2/3)) / m */
    for (size_t i = 0; i < m; i++)
        for (size_t j = 0; i + j < m; j++)
            for (int down = 0; down < 2; down++) {
                if (down && i + j + 1 >= m)
                    continue;
                const double u = ((double)i + (down ? 2.0 : 1.0) / 3) / (double)m;
                const double w = ((double)j + (down ? 2.0 : 1.0) / 3) / (double)m;
                if (out) {
                    for (int d = 0; d < 3; d++)
                        out[n][d] = a[d] + u * b[d] + w * c[d];
                    out[n][3] = area / (double)(m * m);
                }
                n++;
            }
    return n;
}

/* The walls to measure, in scene order, with their column names; an error
 * for a name in `walls` that no wall has. */
static int select_walls(wf_state *s, sluice_host *host)
{
    const sluice_api *api = s->api;
    const uint32_t walls = api->walls->wall_count(host);
    int found[MAX_WALLS] = {0};
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
        s->wall_index[slot] = w;
        int repeated = 0;
        for (uint32_t k = 0; k < slot; k++)
            repeated |= *name && strcmp(s->column_name[k], name) == 0;
        if (*name && !repeated)
            snprintf(s->column_name[slot], sizeof s->column_name[slot], "%s", name);
        else if (*name)
            snprintf(s->column_name[slot], sizeof s->column_name[slot], "%.60s%u", name, w);
        else
            snprintf(s->column_name[slot], sizeof s->column_name[slot], "wall%u", w);
    }
    for (uint32_t k = 0; k < s->wanted_count; k++)
        if (!found[k]) {
            api->messages->error(host, "no wall is named '%s' (geometry.walls[].name)", s->wanted[k]);
            return SLUICE_ERROR;
        }
    if (s->wall_count == 0) {
        api->messages->error(host, "the scene has no walls to measure");
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

/* The sample points of the selected walls (pass 0 counts them, pass 1 fills
 * them in): x_s = x_w + offset n in front of each piece's midpoint. */
static int place_samples(wf_state *s, sluice_host *host, int pass, double rho0, const double g[3],
                         size_t *count)
{
    const sluice_api *api = s->api;
    size_t n = 0, capacity = 64;
    double(*pieces)[4] = malloc(capacity * sizeof *pieces);
    if (!pieces) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    for (uint32_t slot = 0; slot < s->wall_count; slot++) {
        const sluice_wall *wall = api->walls->wall(host, s->wall_index[slot]);
        for (uint32_t e = 0; e < wall->element_count; e++) {
            const size_t m = element_pieces(s, wall, e, NULL);
            if (m > MAX_SAMPLES || n + m > MAX_SAMPLES) {
                api->messages->error(host, "more than %u sample points: raise sample_spacing or "
                                           "measure fewer walls",
                                     MAX_SAMPLES);
                free(pieces);
                return SLUICE_ERROR;
            }
            if (m > capacity) {
                free(pieces);
                capacity = m;
                pieces = malloc(capacity * sizeof *pieces);
                if (!pieces) {
                    api->messages->error(host, "out of memory");
                    return SLUICE_ERROR;
                }
            }
            element_pieces(s, wall, e, pieces);
            const sluice_real *normal = wall->normals + 3 * (size_t)e;
            const double nrm[3] = {(double)normal[0], (double)normal[1], (double)normal[2]};
            for (size_t k = 0; k < m; k++) {
                if (!in_box(s, pieces[k]))
                    continue;
                if (pass == 1) {
                    sluice_real *p = s->points + 3 * n;
                    double *q = s->geometry + 5 * n;
                    double shift = 0;
                    for (int d = 0; d < 3; d++) {
                        p[d] = (sluice_real)(pieces[k][d] + s->offset * nrm[d]);
                        q[d] = -nrm[d] * pieces[k][3];
                        /* p_w = p_s - rho0 g . (x_s - x_w) */
                        shift -= rho0 * g[d] * s->offset * nrm[d];
                        if (s->arm)
                            s->arm[3 * n + (size_t)d] = pieces[k][d] - s->moment_about[d];
                    }
                    if (s->dims == 2)
                        p[2] = 0;
                    q[3] = pieces[k][3];
                    q[4] = shift;
                    s->owner[n] = slot;
                }
                n++;
            }
        }
    }
    free(pieces);
    *count = n;
    return SLUICE_OK;
}

/* Units and descriptions of the table's columns, in the header's order:
 * per wall the force, the wet length (area) and the moments. */
static int describe_columns(const wf_state *s)
{
    const sluice_api_output *out = s->api->output;
    const int plane = s->dims == 2;
    const char *force = plane ? "N m^-1" : "N", *moment = plane ? "N m m^-1" : "N m";
    static const char axes[] = "xyz";
    if (out->table_column(s->table, 0, "s", "simulated time", NULL) != SLUICE_OK)
        return SLUICE_ERROR;
    uint32_t column = 1;
    for (uint32_t k = 0; k < s->wall_count; k++) {
        const char *name = s->column_name[k];
        char text[200];
        for (uint32_t d = 0; d < s->dims; d++) {
            snprintf(text, sizeof text, "%c component of the fluid's pressure force on %s%s",
                     axes[d], name, plane ? " per metre of width" : "");
            if (out->table_column(s->table, column++, force, text, NULL) != SLUICE_OK)
                return SLUICE_ERROR;
        }
        snprintf(text, sizeof text, "wet %s of %s", plane ? "length" : "area", name);
        if (out->table_column(s->table, column++, plane ? "m" : "m^2", text, NULL) != SLUICE_OK)
            return SLUICE_ERROR;
        for (uint32_t d = plane ? 2 : 0; s->moments && d < 3; d++) {
            snprintf(text, sizeof text,
                     "%c component of the moment of the pressure force on %s about (%g, %g, %g) "
                     "m%s",
                     axes[d], name, s->moment_about[0], s->moment_about[1], s->moment_about[2],
                     plane ? " per metre of width" : "");
            if (out->table_column(s->table, column++, moment, text, NULL) != SLUICE_OK)
                return SLUICE_ERROR;
        }
    }
    return SLUICE_OK;
}

/* The walls to measure, their pieces and sample points, the table. */
static int wf_initialise(void *state, sluice_host *host)
{
    wf_state *s = state;
    const sluice_api *api = s->api;
    sluice_real g_real[3] = {0, 0, 0}, rho0 = 1000;
    api->fields->constant(host, "gravity", g_real, 3);
    if (sluice_util_constant(api, host, "rest_density", &rho0) != SLUICE_OK)
        return SLUICE_ERROR;
    const double g[3] = {(double)g_real[0], (double)g_real[1], (double)g_real[2]};
    size_t total = 0;
    if (select_walls(s, host) != SLUICE_OK ||
        place_samples(s, host, 0, (double)rho0, g, &total) != SLUICE_OK)
        return SLUICE_ERROR;
    if (total == 0) {
        api->messages->error(host, "no part of the measured walls lies in the box");
        return SLUICE_ERROR;
    }
    s->points = malloc(3 * total * sizeof *s->points);
    s->geometry = malloc(5 * total * sizeof *s->geometry);
    s->arm = s->moments ? malloc(3 * total * sizeof *s->arm) : NULL;
    s->owner = malloc(total * sizeof *s->owner);
    s->sums = calloc(2 * total, sizeof *s->sums);
    s->row = calloc((size_t)s->columns * s->wall_count + 1, sizeof *s->row);
    if (!s->points || !s->geometry || (s->moments && !s->arm) || !s->owner || !s->sums ||
        !s->row) {
        api->messages->error(host, "out of memory (%zu sample points)", total);
        return SLUICE_ERROR;
    }
    if (place_samples(s, host, 1, (double)rho0, g, &total) != SLUICE_OK)
        return SLUICE_ERROR;
    s->count = (sluice_index)total;
    size_t size = 16 + 8 * (80 + 8) * (size_t)s->wall_count;
    char *header = malloc(size);
    if (!header) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    size_t used = (size_t)snprintf(header, size, "time");
    for (uint32_t k = 0; k < s->wall_count; k++) {
        const char *n = s->column_name[k];
        if (s->dims == 2)
            used += (size_t)snprintf(header + used, size - used, ",Fx_%s,Fy_%s,wet_%s", n, n, n);
        else
            used += (size_t)snprintf(header + used, size - used, ",Fx_%s,Fy_%s,Fz_%s,wet_%s", n,
                                     n, n, n);
        if (s->moments && s->dims == 2)
            used += (size_t)snprintf(header + used, size - used, ",Mz_%s", n);
        else if (s->moments)
            used += (size_t)snprintf(header + used, size - used, ",Mx_%s,My_%s,Mz_%s", n, n, n);
    }
    s->table = api->output->table_open(host, s->file, header);
    free(header);
    if (!s->table)
        return SLUICE_ERROR;
    return describe_columns(s);
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
    const size_t length = (size_t)s->columns * s->wall_count + 1;
    memset(s->row, 0, length * sizeof *s->row);
    s->row[0] = v->time;
    const uint32_t D = s->dims;
    for (sluice_index i = 0; i < s->count; i++) {
        const double S = s->sums[2 * (size_t)i];
        if (!(S >= s->min_kernel_sum))
            continue;
        const double *q = s->geometry + 5 * (size_t)i;
        const double p_wall = s->sums[2 * (size_t)i + 1] / S + q[4];
        double *out = s->row + 1 + (size_t)s->columns * s->owner[i];
        const double f[3] = {p_wall * q[0], p_wall * q[1], p_wall * q[2]};
        for (uint32_t d = 0; d < D; d++)
            out[d] += f[d];
        out[D] += q[3];
        if (s->moments) {
            const double *r = s->arm + 3 * (size_t)i;
            const double mz = r[0] * f[1] - r[1] * f[0];
            if (D == 2) {
                out[D + 1] += mz;
            } else {
                out[D + 1] += r[1] * f[2] - r[2] * f[1];
                out[D + 2] += r[2] * f[0] - r[0] * f[2];
                out[D + 3] += mz;
            }
        }
    }
    if (api->output->table_row(s->table, s->row, (uint32_t)length) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->rows, api, host, v->time);
    return SLUICE_OK;
}

/* Checkpoints: the rows written (the next row is at rows_written x interval). */
SLUICE_DEFINE_SCHEDULE_STATE(wf_save, wf_load, wf_state, rows, "rows_written")

static const sluice_component components[] = {{
    .name = "wall_force",
    .summary = "pressure force (and optionally moment) of the fluid on named walls or their "
               "part in a box, 2D and 3D, from the fluid's pressure in front of them, whatever "
               "the wall scheme, as a CSV time series",
    .reference = "momentum balance of a jump at an abrupt drop (Hager 1985; seed 004, De Padova "
                 "et al. 2017); Shepard interpolation as point_gauge",
    .dimensions = SLUICE_DIMS_2 | SLUICE_DIMS_3,
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

SLUICE_DEFINE_LIBRARY("wall_force", "1.1.0", "pressure force and moment of the fluid on walls",
                      SLUICE_DIMS_2 | SLUICE_DIMS_3, components)
