/* Wall pressure sensors: what a pressure transducer set into a wall reads,
 * the mean pressure over its face, as a CSV time series.
 *
 * A sensor is a face on a wall: a segment of length `size` along the wall
 * in 2D; a disc of diameter `size` or a rectangle `size` x `height` in 3D,
 * centred at the wall point nearest to its `positions` entry. The face is
 * cut into cells at most `sample_spacing` dx wide; each cell's centre x_s is
 * put back onto the wall (the nearest point of the same wall), and there the
 * pressure is extrapolated from the fluid particles as Adami, Hu & Adams
 * (2012) extrapolate a wall particle's pressure:
 *     p(x_s) = sum_j V_j W_sj [p_j - p_ref + rho_j g . (x_s - x_j)] / S,
 *     S = sum_j V_j W_sj,   V_j = m_j / rho_j,
 * g the gravity vector (0 without gravity) and p_ref the equation of state's
 * published `reference_pressure` (0 when none): gauge pressure, exact for a
 * fluid at hydrostatic rest whatever the distance of the particles from the
 * wall. Only fluid particles enter, never the wall's own particles or
 * forces, so the sensor reads the same way for every wall scheme (dbc,
 * mdbc, ghost_particles, penalty_contact, repulsive_force).
 *
 * The extrapolation reaches below atmospheric pressure only as far as the
 * particles it uses do: p(x_s) >= min(0, min_j (p_j - p_ref)). Carried
 * hydrostatically above a free surface the pressure falls through 0 where
 * the surface is and would go on to invent suction (down to -rho g 2h at
 * the kernel's reach); there it reads 0, while under impact suction the
 * particles' own low pressures still come through.
 *
 * A cell is wet where S >= min_kernel_sum; a dry cell reads 0 (a transducer
 * in air reads the atmosphere's gauge pressure, 0). At a flat wall under
 * water S is about 0.45 (the fluid's first layer dx/2 from the wall), about
 * 0.1 when a wall scheme holds the fluid 1.5 dx away (dbc after an impact),
 * and less again in a concave corner: the default 0.05 counts those wet,
 * and a cell more than about 2h above the water dry. The sensor's pressure is
 * the area-weighted mean over its cells, dry ones included, and its wet
 * fraction the share of its area that is wet: a dry face reads 0, never nan.
 *
 * With `time_constant` tau > 0 the sensor also gives its series through a
 * first-order low-pass filter, as a transducer of that response time (or an
 * acquisition's analogue filter) records it:
 *     y_k = y_{k-1} + (1 - exp(-(t_k - t_{k-1}) / tau)) (p_k - y_{k-1}),
 * y_0 = p_0, on the samples (so `interval` should be well below tau).
 *
 * Columns: time, then per sensor <name>_Pa (mean pressure, Pa),
 * <name>_filtered_Pa (with time_constant > 0) and <name>_wet (1). Beside the
 * table, <file stem>_sensors.csv describes each sensor: name, the face
 * centre and its normal into the fluid, the shape, size, height (m), the
 * number of cells and its wall.
 *
 * The gauge evaluates the current state before each row (as point_gauge).
 * Across MPI ranks each rank sums its own particles and the gauge adds the
 * ranks' sums before dividing; rank 0 writes the row. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sluice/gauge_column.h>
#include <sluice/phase_filter.h>

#define MAX_SENSORS 1024
#define MAX_CELLS 1000000u
#define NAME_MAX_LENGTH 64

typedef struct wp_config {
    sluice_real_list positions, size, height;
    const char *names, *wall, *file;
    int shape;
    sluice_real sample_spacing, min_kernel_sum, interval, time_constant, max_distance;
    int phase;
} wp_config;

typedef struct wp_sensor {
    char name[NAME_MAX_LENGTH];
    double centre[3], normal[3], size, height, area;
    uint32_t wall, cells;
} wp_sensor;

typedef struct wp_state {
    const sluice_api *api;
    uint32_t dims;
    double dx, sample_spacing, min_kernel_sum, time_constant, max_distance;
    int shape; /* 0 disc, 1 rectangle (3D) */
    const char *file;
    int phase_filter;
    int32_t wall; /* the wall asked for, -1: the nearest of any */
    double gravity[3], reference_pressure;
    uint32_t sensor_count;
    wp_sensor *sensors;
    sluice_index count; /* cells of every sensor */
    sluice_real *points;
    double *weight; /* cell area (2D: length) */
    uint32_t *owner;
    double *sums; /* 2 per cell: S, sum_j V_j W (p_j - p_ref + rho_j g . (x_s - x_j)) */
    double *lowest; /* per cell: min_j (p_j - p_ref) over the particles with W > 0 */
    double *row;
    uint32_t row_length;
    /* the filter: its output per sensor and the time of the last sample */
    double *filtered;
    double last_time;
    int64_t filter_started;
    int described; /* <stem>_sensors.csv written */
    sluice_field density, mass, pressure, phase;
    sluice_table *table;
    sluice_schedule rows;
} wp_state;

static const sluice_param_spec params[] = {
    {"positions", SLUICE_PARAM_POINT_LIST, offsetof(wp_config, positions), NULL, 0, 0, 0, "m",
     "centre of each sensor's face: a point on or near a wall (the face is centred at the "
     "nearest wall point)",
     NULL, 0},
    {"names", SLUICE_PARAM_STRING, offsetof(wp_config, names), "", 0, 0, 0, NULL,
     "comma-separated sensor names, one per position (letters, digits, '_', '-'); empty: P1, "
     "P2, ...",
     NULL, 0},
    {"size", SLUICE_PARAM_REAL_LIST, offsetof(wp_config, size), "[0]", 0, 0, 0, "m",
     "face size, one value for all or one per sensor: 2D the segment's length along the wall; "
     "3D the disc's diameter or the rectangle's side along the horizontal tangent; 0: a point",
     NULL, 0},
    {"height", SLUICE_PARAM_REAL_LIST, offsetof(wp_config, height), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL, "m",
     "3D rectangles: the side along the second tangent (n x horizontal tangent: up a vertical "
     "wall, along y on a floor), one value for all or one per sensor (default: size)",
     NULL, 0},
    {"shape", SLUICE_PARAM_ENUM, offsetof(wp_config, shape), "disc", 0, 0, 0, NULL,
     "3D face shape (2D faces are segments)", "disc|rectangle", 0},
    {"wall", SLUICE_PARAM_STRING, offsetof(wp_config, wall), "", 0, 0, 0, NULL,
     "name of the wall the sensors sit on (geometry.walls[].name); empty: each sensor's "
     "nearest wall",
     NULL, 0},
    {"max_distance", SLUICE_PARAM_REAL, offsetof(wp_config, max_distance), "2", 0, 0,
     SLUICE_PARAM_HAS_MIN, "1",
     "a position farther than this from its wall, in particle spacings dx, is refused (a "
     "sensor must sit on a wall)",
     NULL, 0},
    {"sample_spacing", SLUICE_PARAM_REAL, offsetof(wp_config, sample_spacing), "0.25", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "largest side of a face cell, in particle spacings dx", NULL, 0},
    {"min_kernel_sum", SLUICE_PARAM_REAL, offsetof(wp_config, min_kernel_sum), "0.05", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "a cell whose fluid kernel sum sum_j V_j W is below this is dry and reads 0 (a flat wall "
     "under water: about 0.45; fluid held 1.5 dx from the wall: about 0.1)",
     NULL, 0},
    {"interval", SLUICE_PARAM_REAL, offsetof(wp_config, interval), "0.001", 1e-7, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between samples", NULL, 0},
    {"time_constant", SLUICE_PARAM_REAL, offsetof(wp_config, time_constant), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "s",
     "tau of the first-order low-pass filter giving the <name>_filtered_Pa columns (0: no "
     "filter); keep interval well below tau",
     NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(wp_config, file), "wall_pressure.csv", 0, 0, 0, NULL,
     "output file in the run directory; <stem>_sensors.csv beside it describes the sensors",
     NULL, 0},
    SLUICE_PHASE_PARAM(wp_config, phase),
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_DENSITY(0),
    SLUICE_SPEC_MASS(0),
    SLUICE_SPEC_PRESSURE_DOC(SLUICE_READ, 0, "pressure"),
};

static void wp_destroy(void *state)
{
    wp_state *s = state;
    if (!s)
        return;
    free(s->sensors);
    free(s->points);
    free(s->weight);
    free(s->owner);
    free(s->sums);
    free(s->lowest);
    free(s->row);
    free(s->filtered);
    free(s);
}

static int valid_name(const char *name)
{
    if (!*name)
        return 0;
    for (const char *c = name; *c; c++)
        if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
              *c == '_' || *c == '-'))
            return 0;
    return 1;
}

/* The sensor names: `names` split at commas, or P1, P2, ... */
static int read_names(wp_state *s, const sluice_api *api, sluice_host *host, const char *list)
{
    if (!list || !*list) {
        for (uint32_t k = 0; k < s->sensor_count; k++)
            snprintf(s->sensors[k].name, NAME_MAX_LENGTH, "P%u", k + 1);
        return SLUICE_OK;
    }
    uint32_t k = 0;
    const char *p = list;
    for (;;) {
        while (*p == ' ')
            p++;
        size_t n = strcspn(p, ",");
        size_t end = n;
        while (end > 0 && p[end - 1] == ' ')
            end--;
        if (k == s->sensor_count) {
            api->messages->error(host, "'names' lists more names than the %u positions",
                                 s->sensor_count);
            return SLUICE_ERROR;
        }
        if (end == 0 || end >= NAME_MAX_LENGTH) {
            api->messages->error(host, "'names': name %u is %s", k + 1,
                                 end == 0 ? "empty" : "longer than 63 characters");
            return SLUICE_ERROR;
        }
        memcpy(s->sensors[k].name, p, end);
        s->sensors[k].name[end] = '\0';
        if (!valid_name(s->sensors[k].name)) {
            api->messages->error(host,
                                 "'names': '%s' may hold only letters, digits, '_' and '-' (it "
                                 "names CSV columns)",
                                 s->sensors[k].name);
            return SLUICE_ERROR;
        }
        for (uint32_t q = 0; q < k; q++)
            if (strcmp(s->sensors[q].name, s->sensors[k].name) == 0) {
                api->messages->error(host, "'names': two sensors are named '%s'",
                                     s->sensors[k].name);
                return SLUICE_ERROR;
            }
        k++;
        if (!p[n])
            break;
        p += n + 1;
    }
    if (k != s->sensor_count) {
        api->messages->error(host, "'names' lists %u names for %u positions: give one per position",
                             k, s->sensor_count);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int wp_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const wp_config *c = config;
    sluice_real dx;
    uint32_t dims;
    if (sluice_util_dimensions(api, host, &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &dx) != SLUICE_OK)
        return SLUICE_ERROR;
    const uint32_t count = c->positions.count;
    if (count == 0 || count > MAX_SENSORS) {
        api->messages->error(host, "'positions' must list between 1 and %d sensors (it lists %u)",
                             MAX_SENSORS, count);
        return SLUICE_ERROR;
    }
    if (sluice_gauge_check_list(api, host, "size", &c->size, count, "sensors") != SLUICE_OK ||
        sluice_gauge_check_list(api, host, "height", &c->height, count, "sensors") != SLUICE_OK)
        return SLUICE_ERROR;
    if (dims == 2 && (c->height.count > 0 || c->shape != 0)) {
        api->messages->error(host, "'height' and 'shape' describe 3D faces; a 2D face is a segment "
                                   "of length 'size'");
        return SLUICE_ERROR;
    }
    if (dims == 3 && c->height.count > 0 && c->shape != 1) {
        api->messages->error(host, "'height' is the second side of a rectangle: set shape: rectangle");
        return SLUICE_ERROR;
    }
    wp_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->dims = dims;
    s->dx = (double)dx;
    s->sample_spacing = (double)c->sample_spacing * (double)dx;
    s->min_kernel_sum = (double)c->min_kernel_sum;
    s->time_constant = (double)c->time_constant;
    s->max_distance = (double)c->max_distance * (double)dx;
    s->shape = c->shape;
    s->file = c->file;
    s->phase_filter = c->phase;
    s->wall = -1;
    s->rows = sluice_schedule_every(c->interval);
    s->sensor_count = count;
    s->sensors = calloc(count, sizeof *s->sensors);
    s->filtered = calloc(count, sizeof *s->filtered);
    if (!s->sensors || !s->filtered) {
        api->messages->error(host, "out of memory");
        wp_destroy(s);
        return SLUICE_ERROR;
    }
    for (uint32_t k = 0; k < count; k++) {
        wp_sensor *sensor = &s->sensors[k];
        for (int d = 0; d < 3; d++)
            sensor->centre[d] = (double)c->positions.values[3 * k + d];
        sensor->size = (double)sluice_gauge_list_value(&c->size, k, 0);
        sensor->height = (double)sluice_gauge_list_value(&c->height, k, (sluice_real)sensor->size);
        if (!(sensor->size >= 0) || !(sensor->height >= 0)) {
            api->messages->error(host, "sensor %u: 'size' and 'height' must be >= 0 m", k + 1);
            wp_destroy(s);
            return SLUICE_ERROR;
        }
    }
    if (read_names(s, api, host, c->names) != SLUICE_OK ||
        sluice_phase_declare(api, host, s->phase_filter) != SLUICE_OK) {
        wp_destroy(s);
        return SLUICE_ERROR;
    }
    if (c->wall && *c->wall) {
        const uint32_t walls = api->walls->wall_count(host);
        for (uint32_t w = 0; w < walls && s->wall < 0; w++) {
            const sluice_wall *wall = api->walls->wall(host, w);
            if (wall && wall->name && strcmp(wall->name, c->wall) == 0)
                s->wall = (int32_t)w;
        }
        if (s->wall < 0) {
            api->messages->error(host, "no wall is named '%s' (geometry.walls[].name)", c->wall);
            wp_destroy(s);
            return SLUICE_ERROR;
        }
    }
    if (s->time_constant > 0 && c->interval > 0.2 * s->time_constant)
        api->messages->warning(host,
                            "interval %g s is more than a fifth of time_constant %g s: the "
                            "filtered series follows the samples, not the signal between them",
                            (double)c->interval, s->time_constant);
    *state = s;
    return SLUICE_OK;
}

static int wp_bind(void *state, sluice_host *host)
{
    wp_state *s = state;
    const sluice_api *api = s->api;
    const sluice_field_binding bindings[] = {
        {"density", &s->density}, {"mass", &s->mass}, {"pressure", &s->pressure}};
    if (sluice_util_bind(api, host, bindings, SLUICE_COUNT(bindings)) != SLUICE_OK ||
        sluice_phase_bind(api, host, s->phase_filter, &s->phase) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real p_ref = 0, g[3] = {0, 0, 0};
    if (api->fields->constant(host, "reference_pressure", &p_ref, 1) == 1)
        s->reference_pressure = (double)p_ref;
    if (api->fields->constant(host, "gravity", g, 3) > 0) /* D values; none: no gravity */
        for (int d = 0; d < 3; d++)
            s->gravity[d] = (double)g[d];
    return SLUICE_OK;
}

/* The face's two unit tangents (3D): t1 horizontal (z x n; x on a floor or
 * a ceiling), t2 = n x t1. In 2D t1 runs along the wall and t2 is unused. */
static void tangents(const double n[3], uint32_t dims, double t1[3], double t2[3])
{
    if (dims == 2) {
        t1[0] = -n[1], t1[1] = n[0], t1[2] = 0;
        t2[0] = t2[1] = t2[2] = 0;
        return;
    }
    double a[3] = {-n[1], n[0], 0}; /* z x n */
    double len = sqrt(a[0] * a[0] + a[1] * a[1]);
    if (len < 1e-6) {
        a[0] = 1, a[1] = 0, len = 1;
    }
    for (int d = 0; d < 3; d++)
        t1[d] = a[d] / len;
    t2[0] = n[1] * t1[2] - n[2] * t1[1];
    t2[1] = n[2] * t1[0] - n[0] * t1[2];
    t2[2] = n[0] * t1[1] - n[1] * t1[0];
}

/* The cells of sensor k, centred on its face at (u, v) along (t1, t2) with
 * area `area` each; with `out` NULL they are only counted. */
static uint32_t face_cells(const wp_state *s, const wp_sensor *sensor, double (*out)[3])
{
    const double delta = s->sample_spacing;
    uint32_t m1 = sensor->size > 0 ? (uint32_t)ceil(sensor->size / delta * (1 - 1e-12)) : 1;
    uint32_t m2 = s->dims == 3 && sensor->height > 0 && s->shape == 1
                      ? (uint32_t)ceil(sensor->height / delta * (1 - 1e-12))
                      : 1;
    if (s->dims == 3 && s->shape == 0)
        m2 = m1;
    if (m1 < 1)
        m1 = 1;
    if (m2 < 1)
        m2 = 1;
    const double side1 = sensor->size, side2 = s->dims == 3 ? (s->shape == 1 ? sensor->height : sensor->size) : 0;
    uint32_t n = 0;
    for (uint32_t a = 0; a < m1; a++)
        for (uint32_t b = 0; b < m2; b++) {
            const double u = ((a + 0.5) / m1 - 0.5) * side1, v = ((b + 0.5) / m2 - 0.5) * side2;
            if (s->dims == 3 && s->shape == 0 && m1 > 1 &&
                u * u + v * v > 0.25 * sensor->size * sensor->size)
                continue;
            if (out) {
                out[n][0] = u;
                out[n][1] = v;
                out[n][2] = (side1 > 0 ? side1 / m1 : 1) * (side2 > 0 ? side2 / m2 : 1);
            }
            n++;
        }
    return n;
}

/* Places sensor k on its wall: the face centre, normal and cells. */
static int place_sensor(wp_state *s, sluice_host *host, uint32_t k, sluice_index *next)
{
    const sluice_api *api = s->api;
    wp_sensor *sensor = &s->sensors[k];
    sluice_real at[3] = {(sluice_real)sensor->centre[0], (sluice_real)sensor->centre[1],
                         (sluice_real)sensor->centre[2]};
    sluice_wall_point near;
    if (api->walls->wall_nearest(host, at, s->wall, &near) != SLUICE_OK) {
        api->messages->error(host, "sensor '%s': the scene has no wall to put it on", sensor->name);
        return SLUICE_ERROR;
    }
    if (fabs((double)near.distance) > s->max_distance) {
        api->messages->error(host,
                             "sensor '%s' at (%g, %g, %g) m is %.3g m from the nearest wall, "
                             "more than max_distance (%.3g m): put it on a wall",
                             sensor->name, sensor->centre[0], sensor->centre[1],
                             sensor->centre[2], fabs((double)near.distance), s->max_distance);
        return SLUICE_ERROR;
    }
    sensor->wall = near.wall;
    for (int d = 0; d < 3; d++) {
        sensor->centre[d] = (double)near.closest[d];
        sensor->normal[d] = (double)near.normal[d];
    }
    double t1[3], t2[3];
    tangents(sensor->normal, s->dims, t1, t2);
    const uint32_t cells = face_cells(s, sensor, NULL);
    double(*uvw)[3] = malloc(cells * sizeof *uvw);
    if (!uvw) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    face_cells(s, sensor, uvw);
    sensor->cells = cells;
    sensor->area = 0;
    for (uint32_t c = 0; c < cells; c++) {
        sluice_real x[3];
        for (int d = 0; d < 3; d++)
            x[d] = (sluice_real)(sensor->centre[d] + uvw[c][0] * t1[d] + uvw[c][1] * t2[d]);
        sluice_wall_point on;
        if (api->walls->wall_nearest(host, x, (int32_t)sensor->wall, &on) != SLUICE_OK) {
            free(uvw);
            return SLUICE_ERROR;
        }
        sluice_real *p = s->points + 3 * (size_t)*next;
        for (int d = 0; d < 3; d++)
            p[d] = on.closest[d];
        if (s->dims == 2)
            p[2] = 0;
        s->weight[*next] = uvw[c][2];
        s->owner[*next] = k;
        sensor->area += uvw[c][2];
        (*next)++;
    }
    free(uvw);
    return SLUICE_OK;
}

static int write_description(wp_state *s, sluice_host *host)
{
    const sluice_api *api = s->api;
    size_t size = 160 + (size_t)s->sensor_count * (NAME_MAX_LENGTH + 2 * NAME_MAX_LENGTH + 220);
    char *text = malloc(size);
    if (!text) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    size_t used = (size_t)snprintf(text, size,
                                   "name,x_m,y_m,z_m,normal_x,normal_y,normal_z,shape,size_m,"
                                   "height_m,area_m2,cells,wall\n");
    for (uint32_t k = 0; k < s->sensor_count; k++) {
        const wp_sensor *q = &s->sensors[k];
        const sluice_wall *wall = api->walls->wall(host, q->wall);
        const char *shape = s->dims == 2 ? "segment" : s->shape ? "rectangle" : "disc";
        const double height = s->dims == 2 ? 0 : s->shape ? q->height : q->size;
        used += (size_t)snprintf(text + used, size - used,
                                 "%s,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%s,%.9g,%.9g,%.9g,%u,%.60s\n",
                                 q->name, q->centre[0], q->centre[1], q->centre[2], q->normal[0],
                                 q->normal[1], q->normal[2], shape, q->size, height, q->area,
                                 q->cells, wall && wall->name && *wall->name ? wall->name : "-");
    }
    char stem[512], path[4096];
    size_t len = strlen(s->file);
    if (len > 4 && strcmp(s->file + len - 4, ".csv") == 0)
        len -= 4;
    snprintf(stem, sizeof stem, "%.*s_sensors.csv", (int)(len < 480 ? len : 480), s->file);
    int rc = api->output->output_path(host, stem, path, sizeof path);
    if (rc == SLUICE_OK)
        rc = api->output->write_file_atomic(host, path, text, used);
    free(text);
    return rc;
}

/* Units and descriptions of the table's columns, each sensor's at the
 * centre of its face. */
static int describe_columns(const wp_state *s)
{
    const sluice_api_output *out = s->api->output;
    if (out->table_column(s->table, 0, "s", "simulated time", NULL) != SLUICE_OK)
        return SLUICE_ERROR;
    uint32_t column = 1;
    char text[160];
    for (uint32_t k = 0; k < s->sensor_count; k++) {
        const wp_sensor *q = &s->sensors[k];
        const sluice_real centre[3] = {(sluice_real)q->centre[0], (sluice_real)q->centre[1],
                                       (sluice_real)q->centre[2]};
        if (out->table_column(s->table, column++, "Pa",
                              "mean gauge pressure over the sensor's face", centre) != SLUICE_OK)
            return SLUICE_ERROR;
        if (s->time_constant > 0) {
            snprintf(text, sizeof text,
                     "mean gauge pressure over the sensor's face, low-pass filtered (tau = %g s)",
                     s->time_constant);
            if (out->table_column(s->table, column++, "Pa", text, centre) != SLUICE_OK)
                return SLUICE_ERROR;
        }
        if (out->table_column(s->table, column++, "1", "wet fraction of the sensor's face",
                              centre) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int wp_initialise(void *state, sluice_host *host)
{
    wp_state *s = state;
    const sluice_api *api = s->api;
    size_t total = 0;
    for (uint32_t k = 0; k < s->sensor_count; k++)
        total += face_cells(s, &s->sensors[k], NULL);
    if (total > MAX_CELLS) {
        api->messages->error(host, "the faces have %zu cells, more than %u: raise sample_spacing",
                             total, MAX_CELLS);
        return SLUICE_ERROR;
    }
    const int filter = s->time_constant > 0;
    s->row_length = 1 + s->sensor_count * (filter ? 3u : 2u);
    s->points = malloc(3 * total * sizeof *s->points);
    s->weight = malloc(total * sizeof *s->weight);
    s->owner = malloc(total * sizeof *s->owner);
    s->sums = calloc(2 * total, sizeof *s->sums);
    s->lowest = calloc(total ? total : 1, sizeof *s->lowest);
    s->row = calloc(s->row_length, sizeof *s->row);
    char *header = malloc(16 + (size_t)s->sensor_count * (3 * NAME_MAX_LENGTH + 40));
    if (!s->points || !s->weight || !s->owner || !s->sums || !s->lowest || !s->row || !header) {
        free(header);
        api->messages->error(host, "out of memory (%zu face cells)", total);
        return SLUICE_ERROR;
    }
    sluice_index next = 0;
    size_t used = (size_t)sprintf(header, "time");
    for (uint32_t k = 0; k < s->sensor_count; k++) {
        if (place_sensor(s, host, k, &next) != SLUICE_OK) {
            free(header);
            return SLUICE_ERROR;
        }
        const char *n = s->sensors[k].name;
        used += (size_t)sprintf(header + used, ",%s_Pa", n);
        if (filter)
            used += (size_t)sprintf(header + used, ",%s_filtered_Pa", n);
        used += (size_t)sprintf(header + used, ",%s_wet", n);
    }
    s->count = next;
    s->table = api->output->table_open(host, s->file, header);
    free(header);
    if (!s->table)
        return SLUICE_ERROR;
    return describe_columns(s);
}

/* S and the extrapolated pressure sum at each cell of the batch. */
static void cell_sums(void *context, const sluice_view *v, const sluice_pair_batch *b)
{
    wp_state *s = context;
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict m = sluice_real_column(v, s->mass, 0);
    const sluice_real *restrict p = sluice_real_column(v, s->pressure, 0);
    const sluice_real *restrict W = b->kernel;
    const sluice_index *restrict nb = b->neighbour;
    const uint8_t *phase = sluice_phase_column(v, s->phase);
    const uint8_t wanted = sluice_phase_wanted(s->phase_filter);
    const double p_ref = s->reference_pressure;
    const double *g = s->gravity;
    const int three = b->offset[2] != NULL;
    for (sluice_index t = 0; t < b->target_count; t++) {
        double sum = 0, pressure = 0, lowest = INFINITY;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_index j = nb[k];
            if (sluice_phase_skips(phase, wanted, j) || !(W[k] > 0))
                continue;
            const double w = (double)(m[j] / rho[j] * W[k]);
            double g_dot_r = g[0] * (double)b->offset[0][k] + g[1] * (double)b->offset[1][k];
            if (three)
                g_dot_r += g[2] * (double)b->offset[2][k];
            sum += w;
            pressure += w * ((double)p[j] - p_ref + (double)rho[j] * g_dot_r);
            lowest = fmin(lowest, (double)p[j] - p_ref);
        }
        s->sums[2 * (size_t)b->target[t]] = sum;
        s->sums[2 * (size_t)b->target[t] + 1] = pressure;
        s->lowest[b->target[t]] = lowest;
    }
}

static int wp_after_step(void *state, sluice_host *host)
{
    wp_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (!sluice_schedule_due(&s->rows, v->time))
        return SLUICE_OK;
    /* the description, once the run directory exists (at the first row, and again after a
     * restart: the same text) */
    if (!s->described) {
        if (write_description(s, host) != SLUICE_OK)
            return SLUICE_ERROR;
        s->described = 1;
    }
    if (api->evaluation->evaluate(host, v->time, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    memset(s->sums, 0, 2 * (size_t)s->count * sizeof *s->sums);
    for (sluice_index i = 0; i < s->count; i++)
        s->lowest[i] = INFINITY;
    if (api->evaluation->point_pass(host, s->points, s->count, SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
                                    cell_sums, s) != SLUICE_OK ||
        api->ranks->reduce(host, s->sums, (uint32_t)(2 * s->count), SLUICE_REDUCE_SUM) !=
            SLUICE_OK ||
        api->ranks->reduce(host, s->lowest, (uint32_t)s->count, SLUICE_REDUCE_MIN) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host);
    const int filter = s->time_constant > 0;
    const uint32_t stride = filter ? 3 : 2;
    memset(s->row, 0, s->row_length * sizeof *s->row);
    s->row[0] = v->time;
    for (sluice_index i = 0; i < s->count; i++) {
        const double S = s->sums[2 * (size_t)i];
        if (!(S >= s->min_kernel_sum))
            continue;
        double *out = s->row + 1 + stride * (size_t)s->owner[i];
        out[0] += s->weight[i] * fmax(s->sums[2 * (size_t)i + 1] / S, fmin(0, s->lowest[i]));
        out[stride - 1] += s->weight[i];
    }
    const double gain = s->filter_started && filter
                            ? 1 - exp(-(v->time - s->last_time) / s->time_constant)
                            : 1;
    for (uint32_t k = 0; k < s->sensor_count; k++) {
        double *out = s->row + 1 + stride * (size_t)k;
        const double area = s->sensors[k].area;
        out[0] /= area;
        out[stride - 1] /= area;
        if (filter) {
            s->filtered[k] += gain * (out[0] - s->filtered[k]);
            out[1] = s->filtered[k];
        }
    }
    s->filter_started = 1;
    s->last_time = v->time;
    if (api->output->table_row(s->table, s->row, s->row_length) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->rows, api, host, v->time);
    return SLUICE_OK;
}

/* Checkpoints: the rows written and the filter's state. */
static int wp_save(void *state, sluice_host *host)
{
    const wp_state *s = state;
    const sluice_api *api = s->api;
    if (sluice_schedule_save(&s->rows, api, host, "rows_written") != SLUICE_OK ||
        api->state->state_write(host, "filter_started", SLUICE_STATE_INT64, 1,
                                &s->filter_started) != SLUICE_OK ||
        api->state->state_write(host, "last_time", SLUICE_STATE_DOUBLE, 1, &s->last_time) !=
            SLUICE_OK)
        return SLUICE_ERROR;
    return api->state->state_write(host, "filtered_Pa", SLUICE_STATE_DOUBLE, s->sensor_count,
                                   s->filtered);
}

static int wp_load(void *state, sluice_host *host)
{
    wp_state *s = state;
    const sluice_api *api = s->api;
    if (sluice_schedule_load(&s->rows, api, host, "rows_written") != SLUICE_OK ||
        api->state->state_read(host, "filter_started", SLUICE_STATE_INT64, 1,
                               &s->filter_started) != SLUICE_OK ||
        api->state->state_read(host, "last_time", SLUICE_STATE_DOUBLE, 1, &s->last_time) !=
            SLUICE_OK)
        return SLUICE_ERROR;
    if (api->state->state_length(host, "filtered_Pa") != (int64_t)s->sensor_count) {
        api->messages->error(host, "the checkpoint holds the filter of another set of sensors");
        return SLUICE_ERROR;
    }
    return api->state->state_read(host, "filtered_Pa", SLUICE_STATE_DOUBLE, s->sensor_count,
                                  s->filtered);
}

static const sluice_component components[] = {{
    .name = "wall_pressure",
    .summary = "wall pressure sensors: the mean pressure over a transducer's face on a wall "
               "(segment, disc or rectangle), extrapolated from the fluid as Adami et al. "
               "(2012), the same for every wall scheme, raw and filtered, as a CSV time series",
    .reference = "Adami, Hu & Adams (2012), J. Comput. Phys. 231, 7057-7075 (wall pressure "
                 "extrapolation); compared with Lobovsky et al. (2014), J. Fluids Struct. 48, "
                 "407-434 in docs/loads.md",
    .dimensions = SLUICE_DIMS_2 | SLUICE_DIMS_3,
    .flags = SLUICE_COMPONENT_ACROSS_RANKS,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(wp_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = wp_create,
    .destroy = wp_destroy,
    .bind = wp_bind,
    .initialise = wp_initialise,
    .after_step = wp_after_step,
    .save_state = wp_save,
    .load_state = wp_load,
}};

SLUICE_DEFINE_LIBRARY("wall_pressure", "1.0.0", "wall pressure sensors",
                      SLUICE_DIMS_2 | SLUICE_DIMS_3, components)
