/* Loading a simulation: the scene, its plugins and their descriptors, the
 * components' create / bind / initialise, fields, constants, the schedule
 * and the initial particles (sluice_engine_load); freeing it. */
#define _GNU_SOURCE
#include <ctype.h>
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

/* ---------------------------------------------------------------- load -- */

/* 1 when OpenMP's threads sleep at barriers (OMP_WAIT_POLICY=passive, any
 * case, as libgomp reads it): light loops then stay on one thread below
 * SLUICE_PARALLEL_MIN_ITEMS particles */
static int passive_wait_policy(void)
{
    const char *policy = getenv("OMP_WAIT_POLICY");
    static const char passive[] = "passive";
    if (!policy)
        return 0;
    size_t k = 0;
    for (; policy[k] && k < sizeof passive - 1; k++)
        if (tolower((unsigned char)policy[k]) != passive[k])
            return 0;
    return k == sizeof passive - 1 && !policy[k];
}

static int check_descriptor(sluice_sim *sim, uint32_t k)
{
    const sluice_instance *in = &sim->instances[k];
    const sluice_component *c = in->component;
    int errors = 0;
    uint32_t dims_mask = c->dimensions & in->library->signature.dimensions;
    if (!(dims_mask & (1u << sim->scene.dimensions))) {
        sluice_sim_report(sim, k, "plugin '%s' (%s) does not support %uD scenes", in->name, in->path,
               sim->scene.dimensions);
        errors++;
    }
    if (c->pair && (c->target_kinds == 0 || c->neighbour_kinds == 0)) {
        sluice_sim_report(sim, k, "plugin '%s' (%s) is a pair term but declares no target or neighbour kinds",
               in->name, in->path);
        errors++;
    }
    for (uint32_t kind = 0; kind < SLUICE_KIND_COUNT; kind++)
        if (c->neighbour_kinds_by_target[kind] &&
            (!c->pair || !(c->target_kinds & SLUICE_KIND_MASK(kind)) ||
             (c->neighbour_kinds_by_target[kind] & ~SLUICE_KINDS_ALL))) {
            sluice_sim_report(sim, k,
                              "plugin '%s' (%s) declares neighbour kinds for %s targets, which "
                              "it does not act on (neighbour_kinds_by_target)",
                              in->name, in->path, sluice_kind_name((uint8_t)kind));
            errors++;
        }
    if ((c->flags & SLUICE_COMPONENT_ON_DEMAND) && !c->pair) {
        sluice_sim_report(sim, k, "plugin '%s' (%s) is flagged on-demand but has no pair callback", in->name,
               in->path);
        errors++;
    }
    if (sluice_sim_evaluation_pair(c) && c->particle) {
        sluice_sim_report(sim, k,
               "plugin '%s' (%s) is both a particle and a pair term; split it into two "
               "components (or flag its pair callback on-demand)",
               in->name, in->path);
        errors++;
    }
    for (uint32_t f = 0; f < c->field_count; f++)
        if (c->fields[f].access & SLUICE_READ_NEIGHBOUR && !c->pair) {
            sluice_sim_report(sim, k, "plugin '%s' reads field '%s' at neighbours but has no pair term",
                   in->name, c->fields[f].name);
            errors++;
        }
    return errors;
}

static const char *library_version(const sluice_instance *in)
{
    return in->library->version ? in->library->version : "?";
}

/* Before the plugins are loaded: the particles the scene would create
 * (sluice_sim_count_particles, with SLUICE_SIZE_WALL_LAYERS layers behind
 * every wall), refused when a particle index cannot count them or past
 * `limit` (> 0; the fuzzer's). What they need in memory is checked once the
 * plugins have declared their fields (check_memory). */
#define SLUICE_SIZE_WALL_LAYERS 4.0
static int check_scene_size(sluice_sim *sim, double limit)
{
    double fluid = 0, wall = 0;
    sluice_sim_count_particles(sim, SLUICE_SIZE_WALL_LAYERS, &fluid, &wall);
    const double count = fluid + wall;
    if (count < 4e9 && !(limit > 0 && count > limit))
        return 0;
    const sluice_node *node = sluice_node_get(sim->scene.root, "particles");
    sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node ? node->file : sim->scene.path,
                    node ? node->line : 1, node ? node->column : 1,
                    "at particles.spacing = %g m the scene would create about %.3g particles "
                    "(%.3g fluid, %.3g wall), %s: use a larger spacing or smaller regions",
                    (double)sim->scene.particles.spacing, count, fluid, wall,
                    limit > 0 && count > limit ? "more than this run's limit"
                                               : "more than a particle index can count");
    return 1;
}

/* Once every field is declared and before any particle is allocated: the
 * memory the run needs (sluice_sim_estimate_memory, kept for run.json),
 * with the wall layers that cover the kernel support behind every wall.
 * A scene that needs more than this process may still take is refused
 * with the figures (a failure for want of resources: exit 4). */
static int check_memory(sluice_sim *sim)
{
    const double dx = (double)sim->spacing;
    const double layers = ceil((double)sim->support / dx - 1e-9);
    double fluid = 0, wall = 0;
    sluice_sim_count_particles(sim, layers, &fluid, &wall);
    sluice_memory_estimate *m = &sim->memory;
    sluice_sim_estimate_memory(sim, fluid + wall, m);
    const double needed = m->total - m->resident;
    if (m->available < 0 || needed <= m->available)
        return 0;
    const sluice_node *node = sluice_node_get(sim->scene.root, "particles");
    sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node ? node->file : sim->scene.path,
                    node ? node->line : 1, node ? node->column : 1,
                    "at particles.spacing = %g m the run needs about %.3g GB: %.3g particles "
                    "(%.3g fluid, %.3g wall) of %.0f bytes each (fields %.0f, neighbour list "
                    "%.0f for %.0f neighbours, grid and reordering %.0f) and %.0f MB besides "
                    "(program, cell grid, wall check); %s leaves this process %.3g GB: use a "
                    "larger spacing or smaller regions, or run across more machines",
                    dx, m->total / 1e9, m->particles, fluid, wall, m->per_particle, m->store,
                    m->list, m->neighbours, m->grid + m->scratch, m->fixed / 1e6,
                    m->available_from ? m->available_from : "the machine", m->available / 1e9);
    sluice_diag_mark_resources(sim->diag);
    return 1;
}

/* The scene's plugins found on the plugin path, their descriptors checked and
 * their parameters bound; one message per missing or refused plugin. */
static int load_plugins(sluice_sim *sim)
{
    sluice_scene *scene = &sim->scene;
    sluice_diag *diag = sim->diag;
    int errors = 0;
    /* plugins */
    char **dirs = NULL;
    size_t dir_count = 0;
    if (sluice_registry_default_path(&dirs, &dir_count, (const char *const *)scene->plugin_path,
                                     scene->plugin_path_count) != 0 ||
        sluice_registry_open(&sim->registry, dirs, dir_count) != 0) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 0, 0,
                        "out of memory scanning the plugin path");
        return 1;
    }
    sim->instances = calloc(scene->plugin_count + 1, sizeof *sim->instances);
    if (!sim->instances)
        return 1;
    for (size_t p = 0; p < scene->plugin_count; p++) {
        const sluice_scene_plugin *sp = &scene->plugins[p];
        const sluice_component_entry *entry = sluice_registry_find(&sim->registry, sp->component);
        if (entry && strcmp(sp->name, sp->component) != 0 &&
            sluice_registry_find(&sim->registry, sp->name)) {
            sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sp->key->file, sp->key->line,
                            sp->key->column,
                            "'%s' names another plugin: give this instance of '%s' a name of "
                            "its own",
                            sp->name, sp->component);
            errors++;
            continue;
        }
        if (!entry) {
            const char **names = calloc(sim->registry.component_count + 1, sizeof *names);
            for (size_t c = 0; names && c < sim->registry.component_count; c++)
                names[c] = sim->registry.components[c].component->name;
            const char *close =
                names ? sluice_closest(sp->component, names, sim->registry.component_count) : NULL;
            char refused[2048];
            sluice_registry_explain_missing(&sim->registry, sp->component, refused, sizeof refused);
            if (refused[0])
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sp->component_node->file,
                                sp->component_node->line, sp->component_node->column,
                                "plugin '%s' could not be loaded: %s", sp->component, refused);
            else if (close)
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sp->component_node->file,
                                sp->component_node->line, sp->component_node->column,
                                "no plugin named '%s' on the plugin path; did you mean '%s'? (run "
                                "'sluice inspect' to list plugins)",
                                sp->component, close);
            else
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sp->component_node->file,
                                sp->component_node->line, sp->component_node->column,
                                "no plugin named '%s' on the plugin path (%zu directories "
                                "searched; run 'sluice inspect' to list plugins)",
                                sp->component, sim->registry.directory_count);
            free(names);
            errors++;
            continue;
        }
        sluice_instance *in = &sim->instances[sim->instance_count];
        in->component = entry->component;
        in->library = sim->registry.libraries[entry->library].library;
        in->path = sim->registry.libraries[entry->library].path;
        in->name = sp->name;
        in->key = sp->key;
        in->host.sim = sim;
        in->host.instance = sim->instance_count;
        sim->registry.libraries[entry->library].used = 1;
        sim->instance_count++;
        errors += check_descriptor(sim, sim->instance_count - 1);
        size_t size = in->component->config_size;
        in->config = sluice_arena_alloc(scene->arena, size ? size : 1);
        if (!in->config)
            return errors + 1;
        char path[256];
        snprintf(path, sizeof path, "plugins.%s", sp->name);
        errors += sluice_schema_bind_except(in->component->params, in->component->param_count,
                                            sp->section, sp->key, path, scene->dimensions,
                                            in->config, scene->arena, diag, "plugin");
    }
    if (errors)
        return errors;
    /* instances hold pointers into the registry arrays; release nothing that is used */
    sluice_registry_release_unused(&sim->registry);
    return errors;
}

/* Exactly one kernel and one integrator, and something that limits the
 * time step. */
static int check_roles(sluice_sim *sim)
{
    sluice_scene *scene = &sim->scene;
    sluice_diag *diag = sim->diag;
    int errors = 0;
    /* roles */
    sim->kernel = sim->integrator = -1;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        const sluice_component *c = sim->instances[k].component;
        if (c->kernel) {
            if (sim->kernel >= 0) {
                sluice_sim_report(sim, k, "two kernels are loaded ('%s' and '%s'); load exactly one",
                       sim->instances[sim->kernel].name, sim->instances[k].name);
                errors++;
            }
            sim->kernel = (int32_t)k;
        }
        if (c->advance && (c->pair || c->particle)) {
            sluice_sim_report(sim, k,
                              "integrator '%s' also has a %s callback; an integrator advances "
                              "the state (advance) and evaluates nothing itself",
                              sim->instances[k].name, c->pair ? "pair" : "particle");
            errors++;
        }
        if (c->advance) {
            if (sim->integrator >= 0) {
                sluice_sim_report(sim, k, "two integrators are loaded ('%s' and '%s'); load exactly one",
                       sim->instances[sim->integrator].name, sim->instances[k].name);
                errors++;
            }
            sim->integrator = (int32_t)k;
        }
    }
    if (sim->kernel < 0) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 1, 1,
                        "no kernel is loaded: add one to 'plugins' (e.g. wendland_c2 or "
                        "cubic_spline)");
        errors++;
    }
    if (sim->integrator < 0) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 1, 1,
                        "no integrator is loaded: add one to 'plugins' (e.g. symplectic)");
        errors++;
    }
    int limits = scene->time.max_step > 0;
    for (uint32_t k = 0; k < sim->instance_count; k++)
        limits |= sim->instances[k].component->time_step_limit != NULL;
    if (!limits) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 1, 1,
                        "nothing limits the time step: load a time-step plugin (e.g. time_step) "
                        "or set time.max_step");
        errors++;
    }
    return errors;
}

/* Every wall handled by a loaded wall scheme (the only one, or the one it
 * names), published as api->walls->wall, with its bounding box. */
static int place_walls(sluice_sim *sim)
{
    sluice_scene *scene = &sim->scene;
    sluice_diag *diag = sim->diag;
    int errors = 0;
    int wall_schemes = 0;
    for (uint32_t k = 0; k < sim->instance_count; k++)
        wall_schemes += (sim->instances[k].component->flags & SLUICE_COMPONENT_WALL_SCHEME) != 0;
    /* walls and their schemes */
    sim->walls = calloc(scene->wall_count + 1, sizeof *sim->walls);
    if (!sim->walls)
        return errors + 1;
    for (size_t w = 0; w < scene->wall_count; w++) {
        sluice_scene_wall *wall = &scene->walls[w];
        const char *scheme = wall->scheme;
        if (!scheme) {
            if (wall_schemes == 1) {
                for (uint32_t k = 0; k < sim->instance_count; k++)
                    if (sim->instances[k].component->flags & SLUICE_COMPONENT_WALL_SCHEME)
                        scheme = sim->instances[k].component->name;
            } else {
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, wall->node->file, wall->node->line,
                                wall->node->column,
                                wall_schemes == 0
                                    ? "geometry.walls.%zu needs a wall scheme, but none is loaded "
                                      "(add one to 'plugins', e.g. dbc)"
                                    : "geometry.walls.%zu: several wall schemes are loaded; name "
                                      "one with 'scheme:'",
                                w);
                errors++;
                continue;
            }
        } else {
            /* named by its instance; published by its component's name (a wall scheme
             * recognises its walls by its own name) */
            const char *named = scheme;
            scheme = NULL;
            for (uint32_t k = 0; k < sim->instance_count; k++)
                if ((sim->instances[k].component->flags & SLUICE_COMPONENT_WALL_SCHEME) &&
                    strcmp(sim->instances[k].name, named) == 0)
                    scheme = sim->instances[k].component->name;
            if (!scheme) {
                const sluice_node *s = sluice_node_get(wall->node, "scheme");
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, s ? s->file : wall->node->file,
                                s ? s->line : wall->node->line, s ? s->column : wall->node->column,
                                "geometry.walls.%zu names wall scheme '%s', which is not a loaded "
                                "wall-scheme plugin",
                                w, named);
                errors++;
                continue;
            }
        }
        sluice_wall *pub = &sim->walls[w];
        pub->scheme = scheme;
        pub->name = wall->name;
        pub->dimensions = scene->dimensions;
        pub->element_count = wall->geometry.element_count;
        pub->points = wall->geometry.points;
        pub->normals = wall->geometry.normals;
    }
    sim->wall_bounds = calloc(6 * (scene->wall_count + 1), sizeof *sim->wall_bounds);
    sim->wall_geometries = calloc(scene->wall_count + 1, sizeof *sim->wall_geometries);
    sim->wall_displacement = calloc(3 * (scene->wall_count + 1), sizeof *sim->wall_displacement);
    sim->wall_moves = calloc(scene->wall_count + 1, 1);
    if (!sim->wall_bounds || !sim->wall_geometries || !sim->wall_displacement || !sim->wall_moves)
        return errors + 1;
    for (size_t w = 0; w < scene->wall_count; w++)
        sim->wall_geometries[w] = &scene->walls[w].geometry;
    for (size_t w = 0; w < scene->wall_count; w++) {
        const sluice_wall_geometry *g = &scene->walls[w].geometry;
        sluice_real *b = sim->wall_bounds + 6 * w;
        const uint32_t per = scene->dimensions == 3 ? 3 : 2;
        for (int d = 0; d < 3; d++) {
            b[d] = (sluice_real)INFINITY;
            b[3 + d] = (sluice_real)-INFINITY;
        }
        for (size_t q = 0; q < (size_t)g->element_count * per; q++)
            for (int d = 0; d < 3; d++) {
                sluice_real x = g->points[3 * q + (size_t)d];
                if (x < b[d])
                    b[d] = x;
                if (x > b[3 + d])
                    b[3 + d] = x;
            }
    }
    return errors;
}

/* The core's own fields (position, kind, id) and constants. */
static int publish_core(sluice_sim *sim)
{
    sluice_scene *scene = &sim->scene;
    int errors = 0;
    /* core fields and constants */
    sim->spacing = scene->particles.spacing;
    sim->smoothing_length = scene->particles.smoothing_length_ratio * scene->particles.spacing;
    sim->rest_density = scene->particles.rest_density;
    sim->end = scene->time.end;
    static const sluice_field_spec core_fields[] = {
        {"position", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m", SLUICE_WRITE,
         SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "particle position"},
        {"kind", SLUICE_TYPE_UINT8, 1, "1", SLUICE_WRITE,
         SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0,
         "particle kind: 0 fluid, 1 wall particle, 2 open-boundary fluid (in an inlet or "
         "outlet buffer, its state imposed)"},
        {"id", SLUICE_TYPE_ID, 1, "1", SLUICE_WRITE, SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART,
         NULL, 0, "permanent particle identity"},
    };
    for (size_t f = 0; f < SLUICE_COUNT(core_fields); f++)
        if (sluice_sim_declare(sim, SLUICE_CORE_INSTANCE, &core_fields[f]) != 0)
            return 1;
    sluice_real value = (sluice_real)scene->dimensions;
    errors += sluice_sim_publish(sim, SLUICE_CORE_INSTANCE, "dimensions", &value, 1, "1") != 0;
    errors += sluice_sim_publish(sim, SLUICE_CORE_INSTANCE, "spacing", &sim->spacing, 1, "m") != 0;
    errors += sluice_sim_publish(sim, SLUICE_CORE_INSTANCE, "smoothing_length", &sim->smoothing_length, 1,
                      "m") != 0;
    errors += sluice_sim_publish(sim, SLUICE_CORE_INSTANCE, "rest_density", &sim->rest_density, 1,
                      "kg m^-3") != 0;
    /* the run's end time and the domain box */
    sluice_real end_time = (sluice_real)scene->time.end;
    errors += sluice_sim_publish(sim, SLUICE_CORE_INSTANCE, "end_time", &end_time, 1, "s") != 0;
    errors += sluice_sim_publish(sim, SLUICE_CORE_INSTANCE, "domain_min", scene->domain.min,
                      scene->dimensions, "m") != 0;
    errors += sluice_sim_publish(sim, SLUICE_CORE_INSTANCE, "domain_max", scene->domain.max,
                      scene->dimensions, "m") != 0;
    return errors;
}

/* What each kind of component must publish in create() (docs/plugin-abi.md,
 * "What each kind of component provides"): an equation of state (a
 * component with density_from_pressure) publishes the speed of sound the
 * time step and the diffusion terms read and the pressure at rest density
 * the hydrostatic start adds to rho0 g depth. (A kernel's kernel_support is
 * checked where the support is computed.) Returns the errors reported. */
static int check_published(sluice_sim *sim)
{
    static const char *const eos_constants[] = {"speed_of_sound", "reference_pressure"};
    int errors = 0;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        const sluice_instance *in = &sim->instances[k];
        if (!in->component->density_from_pressure)
            continue;
        for (size_t c = 0; c < SLUICE_COUNT(eos_constants); c++) {
            int published = 0;
            for (uint32_t e = 0; e < sim->constant_count; e++)
                published |= sim->constants[e].publisher == k &&
                             strcmp(sim->constants[e].name, eos_constants[c]) == 0;
            if (!published) {
                sluice_sim_report(sim, k,
                                  "equation of state '%s' did not publish the constant '%s' in "
                                  "create(); an equation of state publishes 'speed_of_sound' "
                                  "(m/s) and 'reference_pressure' (Pa, the pressure at rest "
                                  "density; sluice_util_publish_eos)",
                                  in->name, eos_constants[c]);
                errors++;
            }
        }
    }
    return errors;
}

/* Static field declarations, then every component's create(); the kernel's
 * support and the integrated rates once all exist. */
/* One component's create(): SLUICE_OK, or an error reported with one
 * message naming the plugin, its library, versions and file. */
static int create_one(sluice_sim *sim, uint32_t k)
{
    sluice_instance *in = &sim->instances[k];
    sim->creating = k;
    sim->pending[0] = '\0';
    size_t reported = sim->diag ? sluice_diag_error_count(sim->diag) : 0;
    int rc = in->component->create(&sluice_sim_api_table, &in->host, in->config, &in->state);
    sim->creating = -1;
    if (rc != SLUICE_OK && !sim->pending[0] && sim->diag &&
        sluice_diag_error_count(sim->diag) > reported) {
        /* the core already said why (e.g. a constant published twice) */
        return SLUICE_ERROR;
    }
    if (rc != SLUICE_OK || sim->pending[0]) {
        sluice_sim_report(sim, k,
                          "plugin '%s' (library '%s' %s, plugin ABI %u.%u, this sluice %u.%u; %s) "
                          "failed to initialise: %s",
                          in->name, in->library->name ? in->library->name : "?",
                          library_version(in), in->library->abi_major, in->library->abi_minor,
                          SLUICE_ABI_MAJOR, SLUICE_ABI_MINOR, in->path,
                          sim->pending[0] ? sim->pending : "its create function returned an error");
        if (rc == SLUICE_OK)
            in->created = 1; /* destroy what it made */
        return SLUICE_ERROR;
    }
    in->created = 1;
    return SLUICE_OK;
}

static uint32_t rate_fields(const sluice_sim *sim)
{
    uint32_t n = 0;
    for (uint32_t f = 0; f < sim->field_count; f++)
        n += sim->fields[f].rate_of != NULL;
    return n;
}

/* Static field declarations, then every component's create() in scene
 * order, the integrator last: once every other component exists, the
 * integrated fields are known (api->fields->rate_count / rate), and the
 * integrator declares what it stores per integrated field in its create().
 * Then the kernel's support and what each kind of component publishes. */
static int create_components(sluice_sim *sim)
{
    int errors = 0;
    sim->phase = SLUICE_PHASE_CREATE;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        const sluice_component *c = sim->instances[k].component;
        for (uint32_t f = 0; f < c->field_count; f++)
            if (sluice_sim_declare(sim, k, &c->fields[f]) != 0)
                errors++;
    }
    if (errors)
        return errors;
    const uint32_t integrator = (uint32_t)sim->integrator;
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if (k != integrator && create_one(sim, k) != SLUICE_OK)
            return 1;
    if (sluice_sim_build_rates(sim) != 0)
        return 1;
    const uint32_t rates = rate_fields(sim);
    if (create_one(sim, integrator) != SLUICE_OK)
        return 1;
    if (rate_fields(sim) != rates) {
        sluice_sim_report(sim, integrator,
                          "integrator '%s' declares a field that is the rate of another in its "
                          "create(); rates are declared by the terms that compute them",
                          sim->instances[integrator].name);
        return 1;
    }
    sluice_real support_ratio = 0;
    if (sluice_sim_get_constant(sim, "kernel_support", &support_ratio, 1) != 1 ||
        !(support_ratio > 0)) {
        sluice_sim_report(sim, (uint32_t)sim->kernel,
                          "kernel '%s' did not publish its support radius (constant "
                          "'kernel_support', in units of h)",
                          sim->instances[sim->kernel].name);
        return 1;
    }
    sim->support = support_ratio * sim->smoothing_length;
    return check_published(sim);
}

/* Every component's bind(), the core's field handles and the schedule. */
static int bind_components(sluice_sim *sim)
{
    sluice_diag *diag = sim->diag;
    int errors = 0;
    sim->phase = SLUICE_PHASE_BIND;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        sluice_instance *in = &sim->instances[k];
        if (!in->component->bind)
            continue;
        size_t before = sluice_diag_error_count(diag);
        if (in->component->bind(in->state, &in->host) != SLUICE_OK) {
            if (sluice_diag_error_count(diag) == before)
                sluice_sim_report(sim, k, "plugin '%s' (%s) failed to bind", in->name, in->path);
            errors++;
        }
    }
    if (errors)
        return errors;
    sluice_sim_handle_of(sim, "position", &sim->position);
    sluice_sim_handle_of(sim, "kind", &sim->kind);
    sluice_sim_handle_of(sim, "id", &sim->id);
    sluice_sim_handle_of(sim, "mass", &sim->mass);
    sluice_sim_handle_of(sim, "velocity", &sim->velocity);
    sluice_sim_handle_of(sim, "density", &sim->density);
    errors += sluice_sim_build_schedule(sim);
    return errors;
}

/* The particle store, the initial particles and every component's
 * initialise(), writers of a field before its readers; every particle
 * inside the domain. */
static int initialise_particles(sluice_sim *sim)
{
    sluice_scene *scene = &sim->scene;
    sluice_diag *diag = sim->diag;
    int errors = 0;
    /* particle store */
    uint8_t *sizes = calloc(sim->column_count + 1, 1);
    if (!sizes)
        return 1;
    for (uint32_t f = 0; f < sim->field_count; f++)
        for (uint32_t c = 0; c < sim->fields[f].components; c++)
            sizes[sim->fields[f].column + (int32_t)c] = sluice_sim_type_size(sim->fields[f].type);
    int rc = sluice_particles_init(&sim->particles, sim->column_count, sizes);
    free(sizes);
    if (rc != 0)
        return 1;
    sim->phase = SLUICE_PHASE_INITIALISE;
    sluice_sim_refresh_view(sim);
    errors += sluice_sim_fill_fluid(sim);
    if (errors)
        return errors;
    uint32_t *order = sluice_sim_initialise_order(sim);
    if (!order)
        return 1;
    for (uint32_t o = 0; o < sim->instance_count; o++) {
        const uint32_t k = order[o];
        sluice_instance *in = &sim->instances[k];
        if (!in->component->initialise)
            continue;
        size_t before = sluice_diag_error_count(diag);
        if (in->component->initialise(in->state, &in->host) != SLUICE_OK) {
            if (sluice_diag_error_count(diag) == before)
                sluice_sim_report(sim, k, "plugin '%s' (%s) failed to initialise its particles", in->name,
                       in->path);
            errors++;
        }
    }
    free(order);
    if (errors)
        return errors;
    if (sim->particles.count == 0) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 1, 1,
                        "the scene creates no particles");
        return 1;
    }
    /* every particle must start inside the domain */
    for (sluice_index i = 0; i < sim->particles.count; i++)
        for (uint32_t d = 0; d < scene->dimensions; d++) {
            double x = (double)sim->view.position[d][i];
            if (!scene->domain.periodic[d] &&
                !(x >= scene->domain.min[d] && x < scene->domain.max[d])) {
                const sluice_node *domain = sluice_node_get(scene->root, "domain");
                char hint[160] = "";
                if (sim->view.kind[i] == SLUICE_KIND_WALL)
                    snprintf(hint, sizeof hint,
                             " (wall particles lie in layers %g m apart behind each wall: is "
                             "particles.spacing too large for the geometry?)",
                             (double)sim->spacing);
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR,
                                domain ? domain->file : scene->path, domain ? domain->line : 1,
                                domain ? domain->column : 1,
                                "%s %s particle at %c = %g m lies outside the domain [%g, %g): "
                                "enlarge domain.min/max to hold the geometry and its walls%s",
                                sim->view.kind[i] == SLUICE_KIND_OPEN ? "an" : "a",
                                sluice_kind_name(sim->view.kind[i]), "xyz"[d],
                                x, (double)scene->domain.min[d], (double)scene->domain.max[d],
                                hint);
                return 1;
            }
        }
    return errors;
}

/* The cell grid, the pair engine with the kernel, and across ranks the
 * split into boxes. */
static int build_search(sluice_sim *sim)
{
    sluice_scene *scene = &sim->scene;
    sluice_diag *diag = sim->diag;
    int errors = 0;
    /* neighbour search and pair engine */
    const char *reason = NULL;
    double lo[3], hi[3];
    for (int d = 0; d < 3; d++) {
        lo[d] = (double)scene->domain.min[d];
        hi[d] = (double)scene->domain.max[d];
    }
    if (sluice_grid_init(&sim->grid, scene->dimensions, lo, hi, scene->domain.periodic,
                         sim->support, (sluice_real)(scene->neighbour_search.skin * sim->support),
                         &reason) != 0) {
        const sluice_node *domain = sluice_node_get(scene->root, "domain");
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, domain ? domain->file : scene->path,
                        domain ? domain->line : 1, domain ? domain->column : 1, "domain: %s",
                        reason);
        return 1;
    }
    sluice_sim_set_list_kinds(sim);
    /* passes beyond the support must not see a cell twice across a periodic side */
    for (uint32_t v = 0; v < sim->instance_count; v++) {
        const sluice_instance *in = &sim->instances[v];
        if (in->reach > sim->support && sluice_pair_reach_check(&sim->grid, in->reach) != 0) {
            sluice_sim_report(sim, v,
                   "plugin '%s' reaches %g m, more than half the length of a periodic side of "
                   "the domain (plus a cell); lengthen the periodic side or shorten the reach",
                   in->name, (double)in->reach);
            return 1;
        }
    }
    sim->threads = omp_get_max_threads();
    sim->parallel_min = passive_wait_policy() ? SLUICE_PARALLEL_MIN_ITEMS : 0;
    sim->grid.parallel_min = sim->particles.parallel_min = sim->parallel_min;
    if (sluice_pair_engine_init(&sim->engine, sim->threads,
                                (sluice_index)scene->neighbour_search.batch_pairs,
                                sim->column_count) != 0)
        return 1;
    const sluice_instance *kernel = &sim->instances[sim->kernel];
    sim->engine.kernel = kernel->component;
    sim->engine.kernel_state = kernel->state;
    sluice_real zero = 0, r0 = 0, w0 = 0, f0 = 0;
    kernel->component->kernel(kernel->state, 1, &zero, &r0, &w0, &f0);
    sim->engine.kernel_self = w0;
#ifdef SLUICE_MPI
    /* every rank built every particle: the scene's count, before the split */
    sim->particles_initial = sim->particles.count;
    if (sim->comm.size > 1 && !sim->check_only && sluice_sim_split_ranks(sim) != 0) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 0, 0, "%s", sim->failure);
        return 1;
    }
#else
    sim->particles_initial = sim->particles.count;
#endif
    return errors;
}

static int load(sluice_sim *sim, const char *scene_path, const char *variant,
                const sluice_load_options *options)
{
    sluice_scene *scene = &sim->scene;
    sluice_diag *diag = sim->diag;
    sluice_scene_edits edits = {0};
    if (options)
        edits = (sluice_scene_edits){options->removals, options->removal_count, options->swaps,
                                     options->swap_count, options->overrides,
                                     options->override_count};
    int errors = sluice_scene_load_edited(scene, scene_path, variant, &edits, diag);
    if (errors || !scene->root)
        return errors ? errors : 1;
    if (check_scene_size(sim, options ? options->max_particles : 0) != 0)
        return 1;

    errors = load_plugins(sim);
    if (errors)
        return errors;
    errors = check_roles(sim);
    errors += place_walls(sim);
    if (errors)
        return errors;
    int (*const stages[])(sluice_sim *) = {publish_core,         create_components,
                                           bind_components,      check_memory,
                                           initialise_particles, build_search};
    for (size_t k = 0; k < sizeof stages / sizeof stages[0]; k++)
        if ((errors = stages[k](sim)) != 0)
            return errors;
    sim->resolved_scene = sluice_yaml_emit(scene->root);
    if (!sim->resolved_scene)
        return 1;
    return 0;
}

sluice_sim *sluice_engine_load(const char *scene_path, const char *variant,
                               const sluice_load_options *options,
                               const sluice_sim_services *services, sluice_diag *diag)
{
    sluice_sim *sim = calloc(1, sizeof *sim);
    if (!sim) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene_path, 0, 0, "out of memory");
        return NULL;
    }
    atomic_init(&sim->wall_distance_built, 0);
    sim->diag = diag;
    omp_init_lock(&sim->message_lock);
    sim->creating = -1;
    if (services)
        sim->services = *services;
    sim->state_group = -1;
    sim->checkpoint_step = -1;
    sim->kernel = sim->integrator = -1;
    sim->position.column = sim->kind.column = sim->id.column = -1;
    sim->mass.column = sim->velocity.column = sim->density.column = -1;
    sim->check_only = options ? options->check_only : 0;
    sim->quiet = options ? options->quiet : 0;
    sim->timestamps = options ? options->timestamps : 0;
    sim->comm = sluice_comm_self();
    if (options && options->communicator) {
#ifdef SLUICE_MPI
        if (sluice_comm_from_mpi(&sim->comm, *(const MPI_Comm *)options->communicator) != 0) {
            sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene_path, 0, 0,
                            "MPI could not set up the ranks of this run");
            sluice_sim_free(sim);
            return NULL;
        }
#else
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene_path, 0, 0,
                        "this Sluice was built without MPI (meson setup -Dmpi=enabled)");
        sluice_sim_free(sim);
        return NULL;
#endif
    }
    if (options && options->threads > 0)
        omp_set_num_threads(options->threads);
    int errors = load(sim, scene_path, variant, options);
    if (errors || sluice_diag_error_count(diag)) {
        if (!sluice_diag_error_count(diag))
            sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene_path, 0, 0,
                            "out of memory loading the scene");
        sluice_sim_free(sim);
        return NULL;
    }
    sim->diag = NULL;
    sim->phase = SLUICE_PHASE_RUN;
    sluice_sim_refresh_view(sim);
    return sim;
}

void sluice_sim_free(sluice_sim *sim)
{
    if (!sim)
        return;
    for (uint32_t k = sim->instance_count; k-- > 0;)
        if (sim->instances[k].created && sim->instances[k].component->destroy)
            sim->instances[k].component->destroy(sim->instances[k].state);
    for (size_t t = 0; t < sim->table_count; t++)
        sluice_sim_table_free(sim->tables[t]);
    free(sim->tables);
    for (size_t c = 0; c < sim->checkpoint_file_count; c++)
        free(sim->checkpoint_files[c]);
    free(sim->checkpoint_files);
    for (uint32_t f = 0; f < sim->field_count; f++) {
        free(sim->fields[f].name);
        free(sim->fields[f].units);
        free(sim->fields[f].doc);
        free(sim->fields[f].rate_of);
        free(sim->fields[f].declarers);
    }
    free(sim->fields);
    for (uint32_t c = 0; c < sim->constant_count; c++) {
        free(sim->constants[c].name);
        free(sim->constants[c].unit);
    }
    free(sim->constants);
    free(sim->rates);
    free(sim->walls);
    if (sim->passes)
        for (uint32_t p = 0; p < sim->pass_count; p++)
            sluice_sim_free_pair_pass(&sim->passes[p].pair);
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        sluice_sim_free_pair_pass(sim->instances[k].on_demand);
        free(sim->instances[k].on_demand);
    }
    free(sim->wall_bounds);
    free(sim->wall_displacement);
    free(sim->wall_moves);
    free(sim->passes);
    free(sim->prepare);
    free(sim->accumulate_columns);
    free(sim->requests);
    sluice_particles_free(&sim->particles);
    sluice_grid_free(&sim->grid);
    sluice_wall_watch_free(&sim->wall_watch);
    sluice_wall_distance_free(&sim->wall_distance);
    free(sim->wall_geometries);
    sluice_pair_engine_free(&sim->engine);
    sluice_ranks_free(&sim->halo);
    sluice_comm_free(&sim->comm);
    free(sim->instances);
    free(sim->resolved_scene);
    free(sim->output_directory);
    free(sim->command_line);
    sluice_registry_close(&sim->registry);
    sluice_scene_free(&sim->scene);
    omp_destroy_lock(&sim->message_lock);
    free(sim);
}
