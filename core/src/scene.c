#define _GNU_SOURCE
#include "scene.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "schema.h"

#define OFF(type, member) offsetof(type, member)

/* ------------------------------------------------------------ sections -- */

typedef struct {
    sluice_real spacing, smoothing_length_ratio, rest_density;
    sluice_real lattice_origin[3];
} particles_config;

static const sluice_param_spec particles_specs[] = {
    {"spacing", SLUICE_PARAM_REAL, OFF(particles_config, spacing), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m",
     "initial particle spacing dx of the lattice every region is filled on", NULL, 0},
    {"smoothing_length_ratio", SLUICE_PARAM_REAL, OFF(particles_config, smoothing_length_ratio),
     "1.3", 0.5, 4.0, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "smoothing length h as a multiple of the spacing (kernel support is 2h)", NULL, 0},
    {"rest_density", SLUICE_PARAM_REAL, OFF(particles_config, rest_density), "1000", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "kg m^-3",
     "reference density rho0 of the fluid; particle mass is rho0 dx^d", NULL, 0},
    {"lattice_origin", SLUICE_PARAM_VECTOR, OFF(particles_config, lattice_origin),
     "[0, 0] | [0, 0, 0]", 0, 0, 0, "m",
     "origin of the lattice: particles sit at origin + (k + 1/2) dx", NULL, SLUICE_LENGTH_DIM},
};

typedef struct {
    sluice_real end, max_step;
} time_config;

static const sluice_param_spec time_specs[] = {
    {"end", SLUICE_PARAM_REAL, OFF(time_config, end), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "s", "simulated time at which the run ends",
     NULL, 0},
    {"max_step", SLUICE_PARAM_REAL, OFF(time_config, max_step), "0", 0, 0, SLUICE_PARAM_HAS_MIN,
     "s", "upper limit of the time step (0: no limit beyond the stability conditions)", NULL, 0},
};

typedef struct {
    sluice_real min[3], max[3];
    const char *periodic;
} domain_config;

static const sluice_param_spec domain_specs[] = {
    {"min", SLUICE_PARAM_VECTOR, OFF(domain_config, min), NULL, 0, 0, 0, "m",
     "lower corner of the computational domain", NULL, SLUICE_LENGTH_DIM},
    {"max", SLUICE_PARAM_VECTOR, OFF(domain_config, max), NULL, 0, 0, 0, "m",
     "upper corner of the computational domain; a particle leaving a non-periodic side stops "
     "the run",
     NULL, SLUICE_LENGTH_DIM},
    {"periodic", SLUICE_PARAM_STRING, OFF(domain_config, periodic), "none", 0, 0, 0, NULL,
     "periodic directions: none, or the axes, e.g. x, xy, xyz", NULL, 0},
};

typedef struct {
    int density;
} initial_config;

static const sluice_param_spec initial_specs[] = {
    {"density", SLUICE_PARAM_ENUM, OFF(initial_config, density), "hydrostatic", 0, 0, 0, NULL,
     "initial fluid density: hydrostatic (from the equation of state and gravity, below each "
     "region's free surface) or rest (rho0 everywhere)",
     "hydrostatic|rest", 0},
};

typedef struct {
    sluice_real skin;
    int64_t batch_pairs;
} neighbour_config;

static const sluice_param_spec neighbour_specs[] = {
    {"skin", SLUICE_PARAM_REAL, OFF(neighbour_config, skin), "0.1", 0, 2,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "extra radius of the neighbour list as a fraction of the kernel support; the list is rebuilt "
     "when a particle has moved half of it",
     NULL, 0},
    {"batch_pairs", SLUICE_PARAM_INT, OFF(neighbour_config, batch_pairs), "1024", 64, 1 << 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "pairs per batch handed to the pair terms", NULL, 0},
};

typedef struct {
    sluice_real density_band, min_time_step, wall_penetration;
    int64_t every;
} watchdog_config;

static const sluice_param_spec watchdog_specs[] = {
    {"density_band", SLUICE_PARAM_REAL, OFF(watchdog_config, density_band), "0.5", 0, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "a density outside rho0 (1 +/- band) stops the run", NULL, 0},
    {"min_time_step", SLUICE_PARAM_REAL, OFF(watchdog_config, min_time_step), "1e-9", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "s",
     "a time step below this stops the run", NULL, 0},
    {"every", SLUICE_PARAM_INT, OFF(watchdog_config, every), "1", 1, 1000000,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1", "check the state every this many steps",
     NULL, 0},
    {"wall_penetration", SLUICE_PARAM_REAL, OFF(watchdog_config, wall_penetration), "0.5", 0,
     1000, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "spacings",
     "a fluid particle deeper than this behind a wall surface (in particle spacings) has gone "
     "through the wall and stops the run",
     NULL, 0},
};

typedef struct {
    sluice_real interval;
    int64_t keep;
} checkpoint_config;

static const sluice_param_spec checkpoint_specs[] = {
    {"interval", SLUICE_PARAM_REAL, OFF(checkpoint_config, interval), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "s",
     "simulated time between checkpoints (DIR/checkpoint_<step>.h5, at t = interval, 2 interval, "
     "...; steps end exactly on them); 0: none (a run stopped by SIGINT or SIGTERM still writes "
     "one)",
     NULL, 0},
    {"keep", SLUICE_PARAM_INT, OFF(checkpoint_config, keep), "2", 0, 1000000,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "checkpoints of this run kept on disk, the newest (older ones are deleted); 0: keep all",
     NULL, 0},
};

/* ------------------------------------------------------------ geometry -- */

typedef struct {
    int shape;
    sluice_real min[3], max[3];
    sluice_real_list points;
    sluice_real velocity[3];
    sluice_real surface;
    sluice_real lattice_origin[3];
} fluid_config;

#define FLUID_SHAPES "box|polygon"
#define FLUID_COMMON                                                                            \
    {"velocity", SLUICE_PARAM_VECTOR, OFF(fluid_config, velocity), "[0, 0] | [0, 0, 0]", 0, 0, \
     0, "m s^-1", "initial velocity of the region's particles", NULL, SLUICE_LENGTH_DIM},      \
    {                                                                                           \
        "surface", SLUICE_PARAM_REAL, OFF(fluid_config, surface), NULL, 0, 0,                   \
            SLUICE_PARAM_OPTIONAL, "m",                                                         \
            "free-surface level (vertical coordinate) for the hydrostatic initial density; "    \
            "default: the top of the region",                                                  \
            NULL, 0                                                                             \
    },                                                                                          \
    {                                                                                           \
        "lattice_origin", SLUICE_PARAM_VECTOR, OFF(fluid_config, lattice_origin), NULL, 0, 0,   \
            SLUICE_PARAM_OPTIONAL, "m",                                                         \
            "this region's lattice: points at lattice_origin + (k + 1/2) dx (default: "         \
            "particles.lattice_origin); align a region with its own bed",                      \
            NULL, SLUICE_LENGTH_DIM                                                             \
    }

static const sluice_param_spec fluid_box_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(fluid_config, shape), NULL, 0, 0, 0, NULL,
     "shape of the region", FLUID_SHAPES, 0},
    {"min", SLUICE_PARAM_VECTOR, OFF(fluid_config, min), NULL, 0, 0, 0, "m", "lower corner", NULL,
     SLUICE_LENGTH_DIM},
    {"max", SLUICE_PARAM_VECTOR, OFF(fluid_config, max), NULL, 0, 0, 0, "m", "upper corner", NULL,
     SLUICE_LENGTH_DIM},
    FLUID_COMMON,
};

static const sluice_param_spec fluid_polygon_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(fluid_config, shape), NULL, 0, 0, 0, NULL,
     "shape of the region", FLUID_SHAPES, 0},
    {"points", SLUICE_PARAM_POINT_LIST, OFF(fluid_config, points), NULL, 0, 0, 0, "m",
     "vertices of the polygon (2D)", NULL, 0},
    FLUID_COMMON,
};

typedef struct {
    int shape;
    sluice_real min[3], max[3];
    sluice_real_list points;
    const char *scheme, *name;
    sluice_real lattice_origin[3];
} wall_config;

#define WALL_SHAPES "tank|box|polyline|polygon"
#define WALL_COMMON                                                                             \
    {"scheme", SLUICE_PARAM_STRING, OFF(wall_config, scheme), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, \
     NULL, "wall scheme plugin for this wall (default: the only one loaded)", NULL, 0},        \
    {                                                                                           \
        "name", SLUICE_PARAM_STRING, OFF(wall_config, name), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, \
            NULL, "name of the wall in reports", NULL, 0                                        \
    },                                                                                          \
    {                                                                                           \
        "lattice_origin", SLUICE_PARAM_VECTOR, OFF(wall_config, lattice_origin), NULL, 0, 0,    \
            SLUICE_PARAM_OPTIONAL, "m",                                                         \
            "lattice of this wall's particle layers (default: particles.lattice_origin)",       \
            NULL, SLUICE_LENGTH_DIM                                                             \
    }

static const sluice_param_spec wall_box_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(wall_config, shape), NULL, 0, 0, 0, NULL,
     "tank: open-top container with the fluid inside; box: solid block with the fluid outside",
     WALL_SHAPES, 0},
    {"min", SLUICE_PARAM_VECTOR, OFF(wall_config, min), NULL, 0, 0, 0, "m", "lower corner", NULL,
     SLUICE_LENGTH_DIM},
    {"max", SLUICE_PARAM_VECTOR, OFF(wall_config, max), NULL, 0, 0, 0, "m", "upper corner", NULL,
     SLUICE_LENGTH_DIM},
    WALL_COMMON,
};

static const sluice_param_spec wall_line_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(wall_config, shape), NULL, 0, 0, 0, NULL,
     "polyline: open line with the fluid on its left; polygon: closed solid with the fluid "
     "outside",
     WALL_SHAPES, 0},
    {"points", SLUICE_PARAM_POINT_LIST, OFF(wall_config, points), NULL, 0, 0, 0, "m",
     "vertices (2D)", NULL, 0},
    WALL_COMMON,
};

/* ------------------------------------------------------------- helpers -- */

static const char *const top_level_keys[] = {
    "title",    "description", "dimensions", "particles", "time",       "domain",
    "geometry", "initial",     "neighbour_search", "watchdog", "plugins", "plugin_path",
    "checkpoint",
};

const char *sluice_node_file(const sluice_node *node, const sluice_scene *scene)
{
    return node && node->file ? node->file : scene->path;
}

static void error_at(sluice_diag *diag, const sluice_scene *scene, const sluice_node *node,
                     const char *format, ...) SLUICE_PRINTF(4, 5);
#include <stdarg.h>
static void error_at(sluice_diag *diag, const sluice_scene *scene, const sluice_node *node,
                     const char *format, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    int line = node ? node->line : 1, column = node ? node->column : 1;
    if (line <= 0) {
        line = 1;
        column = 1;
    }
    sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sluice_node_file(node, scene), line, column, "%s",
                    text);
}

/* Slot of `key` in a mapping, creating an empty mapping entry when absent. */
static sluice_node **section_slot(sluice_node *mapping, const char *key, int create)
{
    for (size_t i = 0; i < mapping->count; i++)
        if (strcmp(mapping->keys[i]->value, key) == 0)
            return &mapping->items[i];
    if (!create)
        return NULL;
    sluice_node *fresh = sluice_node_new_mapping("default", 0, 0);
    if (!fresh || sluice_node_set(mapping, key, fresh) != 0)
        return NULL;
    for (size_t i = 0; i < mapping->count; i++)
        if (strcmp(mapping->keys[i]->value, key) == 0)
            return &mapping->items[i];
    return NULL;
}

static int bind_section(sluice_scene *scene, const char *key, const sluice_param_spec *specs,
                        uint32_t count, void *config, sluice_diag *diag)
{
    sluice_node **slot = section_slot(scene->root, key, 1);
    if (!slot) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 0, 0, "out of memory");
        return 1;
    }
    return sluice_schema_bind(specs, count, slot, scene->root, key, scene->dimensions, config,
                              scene->arena, diag);
}

static int parse_periodic(const char *text, uint32_t dims, int periodic[3])
{
    periodic[0] = periodic[1] = periodic[2] = 0;
    if (strcmp(text, "none") == 0)
        return 0;
    if (!*text)
        return -1;
    for (const char *c = text; *c; c++) {
        int axis = *c == 'x' ? 0 : *c == 'y' ? 1 : *c == 'z' ? 2 : -1;
        if (axis < 0 || (uint32_t)axis >= dims || periodic[axis])
            return -1;
        periodic[axis] = 1;
    }
    return 0;
}

/* Splits "a|b|c" into names (pointers into buffer); returns the count. */
static size_t split_choices(const char *choices, char *buffer, size_t size, const char **names,
                            size_t max_names)
{
    snprintf(buffer, size, "%s", choices);
    size_t n = 0;
    char *save = NULL;
    for (char *tok = strtok_r(buffer, "|", &save); tok && n < max_names;
         tok = strtok_r(NULL, "|", &save))
        names[n++] = tok;
    return n;
}

/* Reads `shape` of a geometry item; returns its index in choices or -1 after
 * reporting the error. */
static int item_shape(sluice_scene *scene, const sluice_node *item, const char *list,
                      const char *choices, sluice_diag *diag)
{
    if (!item || item->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, item, "each entry of geometry.%s must be a mapping with a 'shape'",
                 list);
        return -1;
    }
    const sluice_node *shape = sluice_node_get(item, "shape");
    char buffer[128];
    const char *names[8];
    size_t count = split_choices(choices, buffer, sizeof buffer, names, 8);
    if (!shape) {
        error_at(diag, scene, item, "this entry of geometry.%s has no 'shape' (one of: %s)", list,
                 choices);
        return -1;
    }
    if (shape->kind == SLUICE_NODE_SCALAR)
        for (size_t i = 0; i < count; i++)
            if (strcmp(shape->value, names[i]) == 0)
                return (int)i;
    const char *close =
        shape->kind == SLUICE_NODE_SCALAR ? sluice_closest(shape->value, names, count) : NULL;
    if (close)
        error_at(diag, scene, shape, "unknown shape '%s' in geometry.%s; did you mean '%s'?",
                 shape->value, list, close);
    else
        error_at(diag, scene, shape, "unknown shape in geometry.%s (one of: %s)", list, choices);
    return -1;
}

static sluice_real *polygon_xy(sluice_arena *arena, const sluice_real_list *points, int reverse)
{
    sluice_real *xy = sluice_arena_alloc(arena, (size_t)points->count * 2 * sizeof *xy);
    if (!xy)
        return NULL;
    for (uint32_t k = 0; k < points->count; k++) {
        uint32_t src = reverse ? points->count - 1 - k : k;
        xy[2 * k] = points->values[3 * src];
        xy[2 * k + 1] = points->values[3 * src + 1];
    }
    return xy;
}

static double signed_area(const sluice_real_list *points)
{
    double a = 0;
    for (uint32_t k = 0; k < points->count; k++) {
        uint32_t m = (k + 1) % points->count;
        a += (double)points->values[3 * k] * (double)points->values[3 * m + 1] -
             (double)points->values[3 * m] * (double)points->values[3 * k + 1];
    }
    return 0.5 * a;
}

static int check_box(sluice_scene *scene, const sluice_node *item, const sluice_real *min,
                     const sluice_real *max, const char *what, sluice_diag *diag)
{
    for (uint32_t d = 0; d < scene->dimensions; d++)
        if (!(max[d] > min[d])) {
            error_at(diag, scene, sluice_node_get(item, "max"),
                     "%s: max must be greater than min along every axis (axis %c: %g <= %g)", what,
                     "xyz"[d], (double)max[d], (double)min[d]);
            return 1;
        }
    return 0;
}

/* The list geometry.<key>: NULL when absent or empty, after reporting an
 * error (*errors = 1) when it is not a list. */
static sluice_node *geometry_list(sluice_scene *scene, sluice_node *geometry, const char *key,
                                  const char *what, int *errors, sluice_diag *diag)
{
    *errors = 0;
    sluice_node **slot = section_slot(geometry, key, 0);
    if (!slot)
        return NULL;
    sluice_node *list = *slot;
    if (list->kind == SLUICE_NODE_SCALAR && list->plain && !*list->value)
        return NULL;
    if (list->kind != SLUICE_NODE_SEQUENCE) {
        error_at(diag, scene, list, "geometry.%s must be a list of %s", key, what);
        *errors = 1;
        return NULL;
    }
    return list;
}

static int load_fluids(sluice_scene *scene, sluice_node *geometry, sluice_diag *diag)
{
    int errors;
    sluice_node *list = geometry_list(scene, geometry, "fluid", "regions", &errors, diag);
    if (!list)
        return errors;
    scene->fluids = sluice_arena_alloc(scene->arena, (list->count ? list->count : 1) *
                                                         sizeof *scene->fluids);
    if (!scene->fluids)
        return 1;
    for (size_t i = 0; i < list->count; i++) {
        sluice_node *item = list->items[i];
        int shape = item_shape(scene, item, "fluid", FLUID_SHAPES, diag);
        if (shape < 0) {
            errors++;
            continue;
        }
        char path[64];
        snprintf(path, sizeof path, "geometry.fluid.%zu", i);
        fluid_config c;
        memset(&c, 0, sizeof c);
        int e = shape == 0 ? sluice_schema_bind(fluid_box_specs, SLUICE_COUNT(fluid_box_specs),
                                                &list->items[i], item, path, scene->dimensions, &c,
                                                scene->arena, diag)
                           : sluice_schema_bind(fluid_polygon_specs,
                                                SLUICE_COUNT(fluid_polygon_specs), &list->items[i],
                                                item, path, scene->dimensions, &c, scene->arena,
                                                diag);
        item = list->items[i];
        if (e) {
            errors += e;
            continue;
        }
        sluice_scene_fluid *f = &scene->fluids[scene->fluid_count];
        memset(f, 0, sizeof *f);
        f->node = item;
        memcpy(f->velocity, c.velocity, sizeof f->velocity);
        f->has_surface = sluice_node_get(item, "surface") != NULL;
        f->surface = c.surface;
        f->has_lattice_origin = sluice_node_get(item, "lattice_origin") != NULL;
        memcpy(f->lattice_origin,
               f->has_lattice_origin ? c.lattice_origin : scene->particles.lattice_origin,
               sizeof f->lattice_origin);
        if (shape == 0) {
            if (check_box(scene, item, c.min, c.max, path, diag)) {
                errors++;
                continue;
            }
            f->region.shape = SLUICE_REGION_BOX;
            memcpy(f->region.min, c.min, sizeof c.min);
            memcpy(f->region.max, c.max, sizeof c.max);
        } else {
            if (scene->dimensions != 2) {
                error_at(diag, scene, sluice_node_get(item, "shape"),
                         "shape 'polygon' in %s is only available in 2D", path);
                errors++;
                continue;
            }
            if (c.points.count < 3) {
                error_at(diag, scene, sluice_node_get(item, "points"),
                         "%s.points needs at least 3 vertices", path);
                errors++;
                continue;
            }
            f->region.shape = SLUICE_REGION_POLYGON;
            f->region.polygon = polygon_xy(scene->arena, &c.points, 0);
            f->region.vertex_count = c.points.count;
            if (!f->region.polygon)
                return errors + 1;
        }
        scene->fluid_count++;
    }
    return errors;
}

static int load_walls(sluice_scene *scene, sluice_node *geometry, sluice_diag *diag)
{
    int errors;
    sluice_node *list = geometry_list(scene, geometry, "walls", "walls", &errors, diag);
    if (!list)
        return errors;
    scene->walls =
        sluice_arena_alloc(scene->arena, (list->count ? list->count : 1) * sizeof *scene->walls);
    if (!scene->walls)
        return 1;
    for (size_t i = 0; i < list->count; i++) {
        sluice_node *item = list->items[i];
        int shape = item_shape(scene, item, "walls", WALL_SHAPES, diag);
        if (shape < 0) {
            errors++;
            continue;
        }
        char path[64];
        snprintf(path, sizeof path, "geometry.walls.%zu", i);
        wall_config c;
        memset(&c, 0, sizeof c);
        int boxlike = shape <= 1;
        int e = boxlike ? sluice_schema_bind(wall_box_specs, SLUICE_COUNT(wall_box_specs),
                                             &list->items[i], item, path, scene->dimensions, &c,
                                             scene->arena, diag)
                        : sluice_schema_bind(wall_line_specs, SLUICE_COUNT(wall_line_specs),
                                             &list->items[i], item, path, scene->dimensions, &c,
                                             scene->arena, diag);
        item = list->items[i];
        if (e) {
            errors += e;
            continue;
        }
        sluice_scene_wall *w = &scene->walls[scene->wall_count];
        memset(w, 0, sizeof *w);
        w->node = item;
        memcpy(w->lattice_origin,
               sluice_node_get(item, "lattice_origin") ? c.lattice_origin
                                                       : scene->particles.lattice_origin,
               sizeof w->lattice_origin);
        w->scheme = c.scheme;
        w->name = c.name ? c.name : "";
        const char *reason = NULL;
        int rc;
        if (boxlike) {
            if (check_box(scene, item, c.min, c.max, path, diag)) {
                errors++;
                continue;
            }
            rc = shape == 0 ? sluice_wall_build_tank(&w->geometry, scene->dimensions, c.min, c.max,
                                                     &reason)
                            : sluice_wall_build_box(&w->geometry, scene->dimensions, c.min, c.max,
                                                    &reason);
        } else {
            if (scene->dimensions != 2) {
                error_at(diag, scene, sluice_node_get(item, "shape"),
                         "shape '%s' in %s is only available in 2D (3D walls: tank or box)",
                         shape == 2 ? "polyline" : "polygon", path);
                errors++;
                continue;
            }
            int closed = shape == 3;
            if (c.points.count < (closed ? 3u : 2u)) {
                error_at(diag, scene, sluice_node_get(item, "points"),
                         "%s.points needs at least %d vertices", path, closed ? 3 : 2);
                errors++;
                continue;
            }
            /* a closed polygon is a solid: the fluid is outside, i.e. on the left of a
             * clockwise boundary */
            int reverse = closed && signed_area(&c.points) > 0;
            sluice_real *xy = polygon_xy(scene->arena, &c.points, reverse);
            if (!xy)
                return errors + 1;
            rc = sluice_wall_build_polyline(&w->geometry, xy, c.points.count, closed, &reason);
        }
        if (rc != 0) {
            error_at(diag, scene, item, "%s: %s", path, reason ? reason : "out of memory");
            sluice_wall_geometry_free(&w->geometry);
            errors++;
            continue;
        }
        scene->wall_count++;
    }
    return errors;
}

static int load_plugins(sluice_scene *scene, sluice_diag *diag)
{
    sluice_node **slot = section_slot(scene->root, "plugins", 0);
    if (!slot || ((*slot)->kind == SLUICE_NODE_SCALAR && !*(*slot)->value)) {
        error_at(diag, scene, slot ? *slot : scene->root,
                 "the scene loads no plugins: 'plugins' must list at least a kernel, the "
                 "physics terms and an integrator");
        return 1;
    }
    sluice_node *map = *slot;
    if (map->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, map,
                 "'plugins' must be a mapping from plugin names to their parameters");
        return 1;
    }
    map->used = 1;
    scene->plugins = sluice_arena_alloc(scene->arena, (map->count ? map->count : 1) *
                                                          sizeof *scene->plugins);
    if (!scene->plugins)
        return 1;
    for (size_t i = 0; i < map->count; i++) {
        scene->plugins[i].name = map->keys[i]->value;
        scene->plugins[i].key = map->keys[i];
        scene->plugins[i].section = &map->items[i];
    }
    scene->plugin_count = map->count;
    if (map->count == 0) {
        error_at(diag, scene, map, "the scene loads no plugins");
        return 1;
    }
    return 0;
}

static int load_plugin_path(sluice_scene *scene, sluice_diag *diag)
{
    sluice_node *node = sluice_node_get(scene->root, "plugin_path");
    if (!node)
        return 0;
    node->used = 1;
    if (node->kind != SLUICE_NODE_SCALAR) {
        error_at(diag, scene, node,
                 "plugin_path must be a string of directories separated by ':'");
        return 1;
    }
    char *copy = sluice_arena_strdup(scene->arena, node->value);
    if (!copy)
        return 1;
    size_t count = 1;
    for (const char *c = copy; *c; c++)
        count += *c == ':';
    scene->plugin_path = sluice_arena_alloc(scene->arena, count * sizeof(char *));
    if (!scene->plugin_path)
        return 1;
    char *save = NULL;
    for (char *tok = strtok_r(copy, ":", &save); tok; tok = strtok_r(NULL, ":", &save)) {
        if (!*tok)
            continue;
        size_t len = strlen(scene->directory) + strlen(tok) + 2;
        char *full = sluice_arena_alloc(scene->arena, len);
        if (!full)
            return 1;
        if (tok[0] == '/')
            snprintf(full, len, "%s", tok);
        else
            snprintf(full, len, "%s/%s", scene->directory, tok);
        scene->plugin_path[scene->plugin_path_count++] = full;
    }
    return 0;
}

/* ---------------------------------------------------------------- load -- */

int sluice_scene_load(sluice_scene *scene, const char *path, const char *const *overrides,
                      size_t override_count, sluice_diag *diag)
{
    memset(scene, 0, sizeof *scene);
    scene->arena = sluice_arena_create();
    scene->path = strdup(path);
    if (!scene->arena || !scene->path) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, path, 0, 0, "out of memory");
        return 1;
    }
    char resolved[PATH_MAX];
    char *dir = strdup(path);
    if (!dir)
        return 1;
    char *slash = strrchr(dir, '/');
    const char *d = slash ? (slash == dir ? "/" : (*slash = '\0', dir)) : ".";
    scene->directory = strdup(realpath(d, resolved) ? resolved : d);
    free(dir);
    if (!scene->directory)
        return 1;

    scene->root = sluice_yaml_parse_file(path, diag);
    if (!scene->root)
        return (int)(sluice_diag_error_count(diag) ? sluice_diag_error_count(diag) : 1);
    if (scene->root->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, scene->root, "a scene must be a mapping of sections");
        return 1;
    }
    int errors = 0;
    for (size_t i = 0; i < override_count; i++) {
        char origin[32];
        snprintf(origin, sizeof origin, "--set #%zu", i + 1);
        if (sluice_yaml_override(scene->root, overrides[i], origin, diag) != 0)
            errors++;
    }
    if (errors)
        return errors;

    /* unknown top-level sections */
    for (size_t i = 0; i < scene->root->count; i++) {
        const char *key = scene->root->keys[i]->value;
        int known = 0;
        for (size_t k = 0; k < SLUICE_COUNT(top_level_keys); k++)
            known |= strcmp(key, top_level_keys[k]) == 0;
        if (known)
            continue;
        const char *close = sluice_closest(key, top_level_keys, SLUICE_COUNT(top_level_keys));
        if (close)
            error_at(diag, scene, scene->root->keys[i],
                     "unknown key '%s' at the top level; did you mean '%s'?", key, close);
        else
            error_at(diag, scene, scene->root->keys[i],
                     "unknown key '%s' at the top level (valid keys: title, description, "
                     "dimensions, particles, time, domain, geometry, initial, neighbour_search, "
                     "watchdog, checkpoint, plugins, plugin_path)",
                     key);
        errors++;
    }

    sluice_node *title = sluice_node_get(scene->root, "title");
    if (title) {
        if (title->kind != SLUICE_NODE_SCALAR) {
            error_at(diag, scene, title, "title must be a string");
            errors++;
        } else {
            scene->title = title->value;
        }
    }
    sluice_node *description = sluice_node_get(scene->root, "description");
    if (description && description->kind != SLUICE_NODE_SCALAR) {
        error_at(diag, scene, description, "description must be a string");
        errors++;
    }

    /* dimensions first: vectors depend on it */
    sluice_node *dims = sluice_node_get(scene->root, "dimensions");
    long long dimensions = 0;
    if (!dims) {
        error_at(diag, scene, scene->root, "missing required key 'dimensions' (2 or 3)");
        return errors + 1;
    }
    if (dims->kind != SLUICE_NODE_SCALAR || !dims->plain ||
        sluice_parse_int(dims->value, &dimensions) != 0 || (dimensions != 2 && dimensions != 3)) {
        error_at(diag, scene, dims, "dimensions must be 2 or 3, got '%s'",
                 dims->kind == SLUICE_NODE_SCALAR ? dims->value : "a collection");
        return errors + 1;
    }
    scene->dimensions = (uint32_t)dimensions;

    particles_config pc;
    memset(&pc, 0, sizeof pc);
    errors += bind_section(scene, "particles", particles_specs, SLUICE_COUNT(particles_specs), &pc,
                           diag);
    scene->particles.spacing = pc.spacing;
    scene->particles.smoothing_length_ratio = pc.smoothing_length_ratio;
    scene->particles.rest_density = pc.rest_density;
    memcpy(scene->particles.lattice_origin, pc.lattice_origin, sizeof pc.lattice_origin);

    time_config tc;
    memset(&tc, 0, sizeof tc);
    errors += bind_section(scene, "time", time_specs, SLUICE_COUNT(time_specs), &tc, diag);
    scene->time.end = tc.end;
    scene->time.max_step = tc.max_step;

    domain_config dc;
    memset(&dc, 0, sizeof dc);
    int domain_errors =
        bind_section(scene, "domain", domain_specs, SLUICE_COUNT(domain_specs), &dc, diag);
    errors += domain_errors;
    if (!domain_errors) {
        memcpy(scene->domain.min, dc.min, sizeof dc.min);
        memcpy(scene->domain.max, dc.max, sizeof dc.max);
        sluice_node *domain = sluice_node_get(scene->root, "domain");
        if (parse_periodic(dc.periodic, scene->dimensions, scene->domain.periodic) != 0) {
            error_at(diag, scene, sluice_node_get(domain, "periodic"),
                     "domain.periodic must be 'none' or axes among %s, each once (got '%s')",
                     scene->dimensions == 2 ? "x, y" : "x, y, z", dc.periodic);
            errors++;
        }
        errors += check_box(scene, domain, dc.min, dc.max, "domain", diag);
    }

    initial_config ic;
    memset(&ic, 0, sizeof ic);
    errors += bind_section(scene, "initial", initial_specs, SLUICE_COUNT(initial_specs), &ic, diag);
    scene->initial_density = ic.density == 0 ? SLUICE_INITIAL_HYDROSTATIC : SLUICE_INITIAL_REST;

    neighbour_config nc;
    memset(&nc, 0, sizeof nc);
    errors += bind_section(scene, "neighbour_search", neighbour_specs,
                           SLUICE_COUNT(neighbour_specs), &nc, diag);
    scene->neighbour_search.skin = nc.skin;
    scene->neighbour_search.batch_pairs = nc.batch_pairs;

    watchdog_config wc;
    memset(&wc, 0, sizeof wc);
    errors +=
        bind_section(scene, "watchdog", watchdog_specs, SLUICE_COUNT(watchdog_specs), &wc, diag);
    scene->watchdog.density_band = wc.density_band;
    scene->watchdog.min_time_step = wc.min_time_step;
    scene->watchdog.every = wc.every;
    scene->watchdog.wall_penetration = wc.wall_penetration;

    checkpoint_config kc;
    memset(&kc, 0, sizeof kc);
    errors += bind_section(scene, "checkpoint", checkpoint_specs, SLUICE_COUNT(checkpoint_specs),
                           &kc, diag);
    scene->checkpoint.interval = kc.interval;
    scene->checkpoint.keep = kc.keep;

    sluice_node **geometry_slot = section_slot(scene->root, "geometry", 0);
    if (geometry_slot) {
        sluice_node *geometry = *geometry_slot;
        geometry->used = 1;
        if (geometry->kind != SLUICE_NODE_MAPPING) {
            error_at(diag, scene, geometry, "geometry must be a mapping with 'fluid' and 'walls'");
            errors++;
        } else {
            for (size_t i = 0; i < geometry->count; i++) {
                const char *key = geometry->keys[i]->value;
                if (strcmp(key, "fluid") != 0 && strcmp(key, "walls") != 0) {
                    static const char *const keys[] = {"fluid", "walls"};
                    const char *close = sluice_closest(key, keys, 2);
                    if (close)
                        error_at(diag, scene, geometry->keys[i],
                                 "unknown key '%s' in geometry; did you mean '%s'?", key, close);
                    else
                        error_at(diag, scene, geometry->keys[i],
                                 "unknown key '%s' in geometry (valid keys: fluid, walls)", key);
                    errors++;
                }
            }
            errors += load_fluids(scene, geometry, diag);
            errors += load_walls(scene, geometry, diag);
        }
    }
    if (!errors && scene->fluid_count == 0)
        sluice_diag_add(diag, SLUICE_SEVERITY_WARNING, scene->path, 0, 0,
                        "the scene has no fluid regions");

    errors += load_plugin_path(scene, diag);
    errors += load_plugins(scene, diag);
    return errors;
}

void sluice_scene_free(sluice_scene *scene)
{
    for (size_t i = 0; i < scene->wall_count; i++)
        sluice_wall_geometry_free(&scene->walls[i].geometry);
    sluice_node_free(scene->root);
    sluice_arena_destroy(scene->arena);
    free(scene->path);
    free(scene->directory);
    memset(scene, 0, sizeof *scene);
}
