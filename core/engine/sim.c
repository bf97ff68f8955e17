/* Loading a simulation: scene, plugins, fields, constants, the evaluation
 * schedule, the initial particles; and the API table plugins call. */
#define _GNU_SOURCE
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
#include "sim_internal.h"
#include "yaml_tree.h"

static const sluice_api api_table;

double sluice_wall_clock(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static char *copy_string(const char *s)
{
    if (!s)
        return NULL;
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

static const char *instance_name(const sluice_sim *sim, uint32_t instance)
{
    return instance == SLUICE_CORE_INSTANCE ? "core" : sim->instances[instance].name;
}

/* -------------------------------------------------------------- messages -- */

void sluice_sim_fail(sluice_sim *sim, const char *format, ...)
{
    if (sim->failure[0])
        return; /* keep the first cause */
    va_list ap;
    va_start(ap, format);
    vsnprintf(sim->failure, sizeof sim->failure, format, ap);
    va_end(ap);
}

/* A component written for runs across ranks (SLUICE_COMPONENT_ACROSS_RANKS, 1.8). */
static int across_ranks_component(const sluice_sim *sim, uint32_t instance)
{
    if (instance >= sim->instance_count)
        return 0;
    const sluice_instance *in = &sim->instances[instance];
    return in->library->abi_minor >= 8 && (in->component->flags & SLUICE_COMPONENT_ACROSS_RANKS);
}

static void host_message(sluice_host *host, sluice_severity severity, const char *format,
                         va_list ap)
{
    sluice_sim *sim = host->sim;
    char text[2048];
    vsnprintf(text, sizeof text, format, ap);
    const char *name = instance_name(sim, host->instance);
    omp_set_lock(&sim->message_lock);
    {
        if (sim->diag && severity == SLUICE_SEVERITY_ERROR && sim->creating >= 0 &&
            (uint32_t)sim->creating == host->instance) {
            size_t used = strlen(sim->pending);
            snprintf(sim->pending + used, sizeof sim->pending - used, "%s%s", used ? "; " : "",
                     text);
        } else if (sim->diag) {
            const sluice_node *key =
                host->instance == SLUICE_CORE_INSTANCE ? NULL : sim->instances[host->instance].key;
            sluice_diag_add(sim->diag, severity, key ? key->file : sim->scene.path,
                            key ? key->line : 0, key ? key->column : 0, "plugin '%s': %s", name,
                            text);
        } else if (severity == SLUICE_SEVERITY_ERROR && !sim->failure[0]) {
            /* the first error of a run is its failure, printed once by the caller */
            sluice_sim_fail(sim, "plugin '%s': %s", name, text);
        } else if (sim->comm.size == 1) {
            fprintf(stderr, "%ssluice: %s: plugin '%s': %s\n", sim->progress ? "\n" : "",
                    severity == SLUICE_SEVERITY_ERROR ? "error" : "warning", name, text);
        } else if (sim->comm.rank == 0 || !across_ranks_component(sim, host->instance)) {
            /* across ranks a component written for it warns alike on every
             * rank: rank 0 speaks for it; any other says which rank it is */
            fprintf(stderr, "%ssluice: rank %d: %s: plugin '%s': %s\n",
                    sim->progress ? "\n" : "", sim->comm.rank,
                    severity == SLUICE_SEVERITY_ERROR ? "error" : "warning", name, text);
        }
    }
    omp_unset_lock(&sim->message_lock);
}

static void api_error(sluice_host *host, const char *format, ...)
{
    va_list ap;
    va_start(ap, format);
    host_message(host, SLUICE_SEVERITY_ERROR, format, ap);
    va_end(ap);
}

static void api_warning(sluice_host *host, const char *format, ...)
{
    va_list ap;
    va_start(ap, format);
    host_message(host, SLUICE_SEVERITY_WARNING, format, ap);
    va_end(ap);
}

static void api_info(sluice_host *host, const char *format, ...)
{
    /* across ranks every rank loads the same scene: rank 0 informs */
    if (host->sim->quiet || host->sim->comm.rank != 0)
        return;
    va_list ap;
    va_start(ap, format);
    char text[2048];
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    fprintf(stderr, "sluice: %s: %s\n", instance_name(host->sim, host->instance), text);
}

/* ---------------------------------------------------------------- fields -- */

sluice_field_entry *sluice_sim_find_field(const sluice_sim *sim, const char *name)
{
    for (uint32_t i = 0; i < sim->field_count; i++)
        if (strcmp(sim->fields[i].name, name) == 0)
            return &sim->fields[i];
    return NULL;
}

static const char *type_name(sluice_type t)
{
    switch (t) {
    case SLUICE_TYPE_REAL: return "real";
    case SLUICE_TYPE_INT32: return "int32";
    case SLUICE_TYPE_UINT8: return "uint8";
    case SLUICE_TYPE_ID: return "id";
    }
    return "unknown";
}

static uint8_t type_size(sluice_type t)
{
    switch (t) {
    case SLUICE_TYPE_REAL: return sizeof(sluice_real);
    case SLUICE_TYPE_INT32: return 4;
    case SLUICE_TYPE_UINT8: return 1;
    case SLUICE_TYPE_ID: return sizeof(sluice_id);
    }
    return 8;
}

static void report(sluice_sim *sim, uint32_t instance, const char *format, ...) SLUICE_PRINTF(3, 4);
static void report(sluice_sim *sim, uint32_t instance, const char *format, ...)
{
    char text[2048];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    const sluice_node *key =
        instance == SLUICE_CORE_INSTANCE ? NULL : sim->instances[instance].key;
    if (sim->diag)
        sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, key ? key->file : sim->scene.path,
                        key ? key->line : 1, key ? key->column : 1, "%s", text);
    else
        sluice_sim_fail(sim, "%s", text);
}

/* Merges one declaration into the field table. */
static int declare(sluice_sim *sim, uint32_t instance, const sluice_field_spec *spec)
{
    const char *who = instance_name(sim, instance);
    if (!spec->name || !*spec->name) {
        report(sim, instance, "plugin '%s' declares a field without a name", who);
        return -1;
    }
    if (spec->type < SLUICE_TYPE_REAL || spec->type > SLUICE_TYPE_ID) {
        report(sim, instance, "plugin '%s' declares field '%s' with an unknown type", who,
               spec->name);
        return -1;
    }
    if (sim->phase > SLUICE_PHASE_BIND) {
        report(sim, instance,
               "plugin '%s' declares field '%s' after binding; declare fields in create() or "
               "bind()",
               who, spec->name);
        return -1;
    }
    uint32_t components =
        spec->components == SLUICE_COMPONENTS_DIM ? sim->scene.dimensions : spec->components;
    if (components > 16) {
        report(sim, instance, "plugin '%s' declares field '%s' with %u components (at most 16)",
               who, spec->name, components);
        return -1;
    }
    sluice_field_entry *f = sluice_sim_find_field(sim, spec->name);
    if (f) {
        const char *first = f->declarer_count ? instance_name(sim, f->declarers[0].instance) : "?";
        const char *units = spec->units ? spec->units : "";
        if (f->type != spec->type || f->components != components || strcmp(f->units, units) != 0) {
            report(sim, instance,
                   "field '%s' is declared by '%s' as %s[%u] in %s and by '%s' as %s[%u] in %s; "
                   "these plugins cannot be combined",
                   spec->name, first, type_name(f->type), f->components, f->units[0] ? f->units : "1",
                   who, type_name(spec->type), components, units[0] ? units : "1");
            return -1;
        }
        if (spec->rate_of) {
            if (f->rate_of && strcmp(f->rate_of, spec->rate_of) != 0) {
                report(sim, instance,
                       "field '%s' is declared the rate of '%s' by '%s' and of '%s' by '%s'",
                       spec->name, f->rate_of, first, spec->rate_of, who);
                return -1;
            }
            if (!f->rate_of && !(f->rate_of = copy_string(spec->rate_of)))
                return -1;
            f->kinds |= spec->kinds;
        }
        f->flags |= spec->flags;
        if (!f->doc[0] && spec->doc) {
            char *doc = copy_string(spec->doc);
            if (!doc)
                return -1;
            free(f->doc);
            f->doc = doc;
        }
    } else {
        sluice_field_entry *grown = realloc(sim->fields, (sim->field_count + 1) * sizeof *grown);
        if (!grown)
            return -1;
        sim->fields = grown;
        f = &sim->fields[sim->field_count];
        memset(f, 0, sizeof *f);
        f->name = copy_string(spec->name);
        f->units = copy_string(spec->units ? spec->units : "");
        f->doc = copy_string(spec->doc ? spec->doc : "");
        f->rate_of = spec->rate_of ? copy_string(spec->rate_of) : NULL;
        if (!f->name || !f->units || !f->doc || (spec->rate_of && !f->rate_of)) {
            free(f->name);
            free(f->units);
            free(f->doc);
            free(f->rate_of);
            return -1;
        }
        f->type = spec->type;
        f->components = components;
        f->flags = spec->flags;
        f->kinds = spec->rate_of ? spec->kinds : 0;
        f->column = (int32_t)sim->column_count;
        sim->column_count += components;
        sim->field_count++;
    }
    sluice_declarer *d = realloc(f->declarers, (f->declarer_count + 1) * sizeof *d);
    if (!d)
        return -1;
    f->declarers = d;
    d[f->declarer_count].instance = instance;
    d[f->declarer_count].access = spec->access;
    f->declarer_count++;
    return 0;
}

static int api_declare_field(sluice_host *host, const sluice_field_spec *spec)
{
    return declare(host->sim, host->instance, spec) == 0 ? SLUICE_OK : SLUICE_ERROR;
}

static int handle_of(const sluice_sim *sim, const char *name, sluice_field *out)
{
    const sluice_field_entry *f = sluice_sim_find_field(sim, name);
    if (!f) {
        out->column = -1;
        out->components = 0;
        out->type = SLUICE_TYPE_REAL;
        return SLUICE_ERROR;
    }
    out->column = f->column;
    out->components = f->components;
    out->type = f->type;
    return SLUICE_OK;
}

static int api_field(sluice_host *host, const char *name, sluice_field *out)
{
    if (handle_of(host->sim, name, out) != SLUICE_OK) {
        api_error(host, "asks for field '%s', which no loaded plugin declares", name);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

/* ------------------------------------------------------------- constants -- */

static int publish(sluice_sim *sim, uint32_t instance, const char *name, const sluice_real *values,
                   uint32_t count, const char *unit)
{
    if (count == 0 || count > 3) {
        report(sim, instance, "plugin '%s' publishes constant '%s' with %u values (1 to 3)",
               instance_name(sim, instance), name, count);
        return -1;
    }
    for (uint32_t i = 0; i < sim->constant_count; i++)
        if (strcmp(sim->constants[i].name, name) == 0) {
            report(sim, instance,
                   "constant '%s' is published by both '%s' and '%s'; load only one of them", name,
                   instance_name(sim, sim->constants[i].publisher), instance_name(sim, instance));
            return -1;
        }
    sluice_constant_entry *grown =
        realloc(sim->constants, (sim->constant_count + 1) * sizeof *grown);
    if (!grown)
        return -1;
    sim->constants = grown;
    sluice_constant_entry *c = &grown[sim->constant_count];
    memset(c, 0, sizeof *c);
    c->name = copy_string(name);
    c->unit = copy_string(unit ? unit : "1");
    if (!c->name || !c->unit) {
        free(c->name);
        free(c->unit);
        return -1;
    }
    memcpy(c->values, values, count * sizeof *values);
    c->count = count;
    c->publisher = instance;
    sim->constant_count++;
    return 0;
}

static int api_publish_constant(sluice_host *host, const char *name, const sluice_real *values,
                                uint32_t count, const char *unit)
{
    return publish(host->sim, host->instance, name, values, count, unit) == 0 ? SLUICE_OK
                                                                               : SLUICE_ERROR;
}

static uint32_t get_constant(const sluice_sim *sim, const char *name, sluice_real *values,
                             uint32_t max_count)
{
    for (uint32_t i = 0; i < sim->constant_count; i++)
        if (strcmp(sim->constants[i].name, name) == 0) {
            const sluice_constant_entry *c = &sim->constants[i];
            for (uint32_t k = 0; k < c->count && k < max_count; k++)
                values[k] = c->values[k];
            return c->count;
        }
    return 0;
}

static uint32_t api_constant(sluice_host *host, const char *name, sluice_real *values,
                             uint32_t max_count)
{
    return get_constant(host->sim, name, values, max_count);
}

static uint32_t api_rate_count(sluice_host *host)
{
    return host->sim->rate_count;
}

static int api_rate(sluice_host *host, uint32_t index, sluice_rate *out)
{
    if (index >= host->sim->rate_count)
        return SLUICE_ERROR;
    *out = host->sim->rates[index];
    return SLUICE_OK;
}

/* ------------------------------------------------------------- particles -- */

void sluice_sim_refresh_view(sluice_sim *sim)
{
    sluice_view *v = &sim->view;
    v->count = sim->particles.count;
    v->dimensions = sim->scene.dimensions;
    v->columns = sim->particles.columns;
    for (int d = 0; d < 3; d++)
        v->position[d] = (uint32_t)d < sim->scene.dimensions && sim->particles.columns
                             ? sim->particles.columns[sim->position.column + d]
                             : NULL;
    v->kind = sim->particles.columns ? sim->particles.columns[sim->kind.column] : NULL;
    v->id = sim->particles.columns ? sim->particles.columns[sim->id.column] : NULL;
    v->smoothing_length = sim->smoothing_length;
    v->spacing = sim->spacing;
    v->time = sim->time;
    v->dt = sim->dt;
    v->step = sim->step;
}

static const sluice_view *api_view(sluice_host *host)
{
    sluice_sim_refresh_view(host->sim);
    return &host->sim->view;
}

/* Appends particles with the core's initial values; `density` may be NULL
 * (rest density). */
static int add_particles(sluice_sim *sim, uint8_t kind, const sluice_real *positions,
                         const sluice_real *velocity, const sluice_real *density,
                         sluice_index count, sluice_index *first)
{
    sluice_index start;
    if (sluice_particles_append(&sim->particles, count, &start) != 0)
        return -1;
    void **col = sim->particles.columns;
    const uint32_t dims = sim->scene.dimensions;
    double volume = pow((double)sim->spacing, (double)dims);
    for (sluice_index k = 0; k < count; k++) {
        sluice_index i = start + k;
        for (uint32_t d = 0; d < dims; d++)
            ((sluice_real *)col[sim->position.column + d])[i] = positions[3 * (size_t)k + d];
        ((uint8_t *)col[sim->kind.column])[i] = kind;
        /* across ranks, during the run, rank r of R takes the ids
         * next_id + r, + R, + 2R, ...: unique without a message, and the
         * same ids as on one rank while the scene loads (every rank builds
         * every particle then) */
        if (sim->comm.size > 1 && sim->phase == SLUICE_PHASE_RUN) {
            ((sluice_id *)col[sim->id.column])[i] = sim->next_id + (sluice_id)sim->comm.rank;
            sim->next_id += (sluice_id)sim->comm.size;
        } else {
            ((sluice_id *)col[sim->id.column])[i] = sim->next_id++;
        }
        if (sim->mass.column >= 0)
            ((sluice_real *)col[sim->mass.column])[i] =
                (sluice_real)((double)sim->rest_density * volume);
        if (sim->density.column >= 0)
            ((sluice_real *)col[sim->density.column])[i] = density ? density[k] : sim->rest_density;
        if (sim->velocity.column >= 0 && velocity)
            for (uint32_t d = 0; d < dims; d++)
                ((sluice_real *)col[sim->velocity.column + d])[i] = velocity[d];
    }
    if (first)
        *first = start;
    sim->grid.valid = 0;
    sluice_sim_refresh_view(sim);
    return 0;
}

/* Output and point passes across ranks: only for a component written for
 * them (SLUICE_COMPONENT_ACROSS_RANKS, 1.8), which combines its ranks'
 * figures with api->reduce; any other is refused, never left to write one
 * rank's part as if it were the whole. */
static int across_ranks_only(sluice_host *host, const char *what)
{
    const sluice_sim *sim = host->sim;
    if (sim->comm.size == 1)
        return SLUICE_OK;
    if (across_ranks_component(sim, host->instance))
        return SLUICE_OK;
    api_error(host, "%s in a run across %d ranks needs a component written for it (flag "
                    "SLUICE_COMPONENT_ACROSS_RANKS: it combines its ranks' figures with "
                    "api->reduce; docs/plugin-abi.md)",
              what, sim->comm.size);
    return SLUICE_ERROR;
}

static int api_add_particles(sluice_host *host, uint8_t kind, const sluice_real *positions,
                             sluice_index count, sluice_index *first)
{
    sluice_sim *sim = host->sim;
    /* while the scene loads, every rank builds every particle; the split
     * into slabs comes after */
    if (sim->phase == SLUICE_PHASE_RUN &&
        across_ranks_only(host, "adding particles (api->add_particles)") != SLUICE_OK)
        return SLUICE_ERROR;
    if (sim->phase < SLUICE_PHASE_INITIALISE) {
        api_error(host, "adds particles before initialise(); add them in initialise() or later");
        return SLUICE_ERROR;
    }
    if (kind >= SLUICE_KIND_COUNT) {
        api_error(host, "adds particles of unknown kind %u", kind);
        return SLUICE_ERROR;
    }
    if (sim->evaluating) {
        api_error(host, "adds particles inside an evaluation; add them in a before-step or "
                        "after-step hook");
        return SLUICE_ERROR;
    }
    if (add_particles(sim, kind, positions, NULL, NULL, count, first) != 0) {
        api_error(host, "cannot add %u particles: out of memory", count);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int check_indices(sluice_host *host, const char *what, const sluice_index *indices,
                         sluice_index count)
{
    sluice_sim *sim = host->sim;
    if (sim->phase < SLUICE_PHASE_INITIALISE || sim->evaluating) {
        api_error(host, "%s outside a before-step or after-step hook", what);
        return SLUICE_ERROR;
    }
    if (count > 0 && !indices) {
        api_error(host, "%s without a list of particles", what);
        return SLUICE_ERROR;
    }
    for (sluice_index k = 0; k < count; k++)
        if (indices[k] >= sim->particles.count) {
            api_error(host, "%s: particle index %u is out of range (%u particles)", what,
                      indices[k], sim->particles.count);
            return SLUICE_ERROR;
        }
    return SLUICE_OK;
}

static int api_remove_particles(sluice_host *host, const sluice_index *indices, sluice_index count)
{
    sluice_sim *sim = host->sim;
    if (sim->phase == SLUICE_PHASE_RUN &&
        across_ranks_only(host, "removing particles (api->remove_particles)") != SLUICE_OK)
        return SLUICE_ERROR;
    if (check_indices(host, "removes particles", indices, count) != SLUICE_OK)
        return SLUICE_ERROR;
    if (count == 0)
        return SLUICE_OK;
    uint8_t *remove = calloc(sim->particles.count, 1);
    if (!remove) {
        api_error(host, "cannot remove %u particles: out of memory", count);
        return SLUICE_ERROR;
    }
    sluice_index distinct = 0;
    for (sluice_index k = 0; k < count; k++) {
        distinct += !remove[indices[k]];
        remove[indices[k]] = 1;
    }
    sluice_particles_compact(&sim->particles, remove);
    free(remove);
    sim->removed += distinct;
    sim->grid.valid = 0;
    sluice_sim_refresh_view(sim);
    return SLUICE_OK;
}

static int api_set_kind(sluice_host *host, const sluice_index *indices, sluice_index count,
                        uint8_t kind)
{
    sluice_sim *sim = host->sim;
    if (kind >= SLUICE_KIND_COUNT) {
        api_error(host, "sets the unknown particle kind %u", kind);
        return SLUICE_ERROR;
    }
    if (check_indices(host, "changes particle kinds", indices, count) != SLUICE_OK)
        return SLUICE_ERROR;
    uint8_t *k = sim->particles.columns[sim->kind.column];
    for (sluice_index n = 0; n < count; n++)
        k[indices[n]] = kind;
    if (count > 0)
        sim->grid.valid = 0;
    return SLUICE_OK;
}

static uint64_t api_removed_count(sluice_host *host)
{
    return host->sim->removed;
}

static uint32_t api_wall_count(sluice_host *host)
{
    return (uint32_t)host->sim->scene.wall_count;
}

static const sluice_wall *api_wall(sluice_host *host, uint32_t index)
{
    if (index >= host->sim->scene.wall_count)
        return NULL;
    return &host->sim->walls[index];
}

static int api_wall_layer_points(sluice_host *host, uint32_t wall_index, sluice_real thickness,
                                 sluice_real **points, sluice_index *count)
{
    sluice_sim *sim = host->sim;
    *points = NULL;
    *count = 0;
    if (wall_index >= sim->scene.wall_count)
        return SLUICE_ERROR;
    sluice_points out = {0};
    if (sluice_wall_layer_points(&sim->scene.walls[wall_index].geometry, sim->spacing,
                                 sim->scene.walls[wall_index].lattice_origin, thickness, &out) != 0) {
        sluice_points_free(&out);
        api_error(host, "out of memory generating wall layer points");
        return SLUICE_ERROR;
    }
    if (out.count > UINT32_MAX - 1) {
        sluice_points_free(&out);
        return SLUICE_ERROR;
    }
    *points = out.xyz;
    *count = (sluice_index)out.count;
    return SLUICE_OK;
}

static void api_release(void *memory)
{
    free(memory);
}

/* ----------------------------------------------------------- evaluation -- */

static void zero_accumulators(sluice_sim *sim)
{
    const sluice_index n = sim->particles.count;
    for (uint32_t a = 0; a < sim->accumulate_count; a++) {
        uint32_t c = sim->accumulate_columns[a];
        memset(sim->particles.columns[c], 0, (size_t)n * sim->particles.element_size[c]);
    }
}

typedef struct particle_call {
    const sluice_component *component;
    void *state;
} particle_call;

static void run_particle_pass(sluice_sim *sim, const sluice_component *component, void *state)
{
    const sluice_view *v = &sim->view;
    const sluice_index n = v->count, chunk = 2048;
    const sluice_index chunks = (n + chunk - 1) / chunk;
#pragma omp parallel for schedule(static)
    for (sluice_index c = 0; c < chunks; c++) {
        sluice_index a = c * chunk, b = a + chunk < n ? a + chunk : n;
        component->particle(state, v, a, b);
    }
}

static const char *describe_particle(const sluice_sim *sim, sluice_index i, char *buffer,
                                     size_t size)
{
    const sluice_view *v = &sim->view;
    if (v->dimensions == 3)
        snprintf(buffer, size, "particle id %llu (%s) at (%.6g, %.6g, %.6g) m",
                 (unsigned long long)v->id[i], sluice_kind_name(v->kind[i]),
                 (double)v->position[0][i], (double)v->position[1][i], (double)v->position[2][i]);
    else
        snprintf(buffer, size, "particle id %llu (%s) at (%.6g, %.6g) m",
                 (unsigned long long)v->id[i], sluice_kind_name(v->kind[i]),
                 (double)v->position[0][i], (double)v->position[1][i]);
    return buffer;
}

/* Rebuilds the neighbour list when a particle has moved beyond the skin or
 * the particle count changed. */
static int update_neighbours(sluice_sim *sim)
{
    sluice_sim_refresh_view(sim);
    int rebuild = sluice_grid_needs_rebuild(&sim->grid, &sim->view);
#ifdef SLUICE_MPI
    if (sim->comm.size > 1) {
        /* the slabs follow the work (docs/scaling.md); a move is decided
         * alike on every rank, and the rebuild migrates the particles */
        const int moved = sluice_ranks_balance(sim);
        if (moved < 0)
            return SLUICE_ERROR;
        rebuild = sluice_comm_any(&sim->comm, rebuild) || moved;
    }
#endif
    if (rebuild) {
        sluice_index bad = 0;
        int rc;
#ifdef SLUICE_MPI
        if (sim->comm.size > 1) {
            if (sluice_ranks_migrate(sim) != 0)
                return SLUICE_ERROR;
            rc = sluice_grid_build_with_halo(&sim->grid, &sim->particles,
                                             (uint32_t)sim->position.column, &bad,
                                             sluice_ranks_collect_halo, sim);
            if (rc == -3) {
                if (!sim->failure[0])
                    sluice_sim_fail(sim, "rank %d: the halo of the neighbour list failed",
                                    sim->comm.rank);
                return SLUICE_ERROR;
            }
        } else
#endif
            rc = sluice_grid_build(&sim->grid, &sim->particles, (uint32_t)sim->position.column,
                                   &bad);
        if (rc == -2) {
            char where[256];
            sluice_sim_refresh_view(sim);
            sluice_sim_fail(sim,
                            "step %lld, t = %.9g s: %s is outside the domain or not finite "
                            "(domain.min/max; field 'position', written by the integrator)",
                            (long long)sim->step, sim->time,
                            describe_particle(sim, bad, where, sizeof where));
            return SLUICE_ERROR;
        }
        if (rc != 0) {
            sluice_sim_fail(sim, "out of memory building the neighbour list (%u particles)",
                            sim->particles.count);
            return SLUICE_ERROR;
        }
        sluice_sim_refresh_view(sim);
    }
    return SLUICE_OK;
}

static int evaluate(sluice_sim *sim);

int sluice_sim_evaluate(sluice_sim *sim)
{
    sim->evaluating++;
    int status = evaluate(sim);
    sim->evaluating--;
    return status;
}

static int evaluate(sluice_sim *sim)
{
    if (update_neighbours(sim) != SLUICE_OK)
        return SLUICE_ERROR;
    for (uint32_t k = 0; k < sim->prepare_count; k++) {
        sluice_instance *in = &sim->instances[sim->prepare[k]];
        if (in->component->prepare(in->state, &in->host) != SLUICE_OK) {
            if (!sim->failure[0])
                sluice_sim_fail(sim, "plugin '%s' failed to prepare an evaluation", in->name);
            return SLUICE_ERROR;
        }
        sluice_sim_refresh_view(sim);
    }
    zero_accumulators(sim);
    /* across ranks: this rank's time in the passes, without the halo's
     * exchanges (the measured work that balances the slabs) */
    double busy_from = sim->comm.size > 1 ? sluice_wall_clock() : 0;
    for (uint32_t p = 0; p < sim->pass_count; p++) {
        const sluice_pass *pass = &sim->passes[p];
        if (pass->is_pair) {
#ifdef SLUICE_MPI
            /* the other ranks' particles as they are now, every field */
            if (sim->comm.size > 1) {
                const double now = sluice_wall_clock();
                sim->halo.busy_seconds += now - busy_from;
                if (sluice_ranks_refresh_halo(sim) != 0)
                    return SLUICE_ERROR;
                busy_from = sluice_wall_clock();
            }
#endif
            if (sluice_pair_pass_run(&sim->engine, &pass->pair, &sim->grid, &sim->view) != 0) {
                sluice_sim_fail(sim, "out of memory in a pair pass");
                return SLUICE_ERROR;
            }
        } else {
            const sluice_instance *in = &sim->instances[pass->instance];
            run_particle_pass(sim, in->component, in->state);
        }
    }
    if (sim->comm.size > 1)
        sim->halo.busy_seconds += sluice_wall_clock() - busy_from;
    return SLUICE_OK;
}

static int api_evaluate(sluice_host *host)
{
    return sluice_sim_evaluate(host->sim);
}

static double next_request(const sluice_sim *sim)
{
    double next = INFINITY;
    double eps = 1e-12 * (fabs(sim->time) > 1 ? fabs(sim->time) : 1);
    for (size_t i = 0; i < sim->request_count; i++)
        if (sim->requests[i] > sim->time + eps && sim->requests[i] < next)
            next = sim->requests[i];
    return next;
}

typedef struct limit_call {
    const sluice_component *component;
    void *state;
} limit_call;

static double api_time_step(sluice_host *host)
{
    sluice_sim *sim = host->sim;
    sluice_sim_refresh_view(sim);
    const sluice_view *v = &sim->view;
    double dt = INFINITY;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        const sluice_component *c = sim->instances[k].component;
        if (!c->time_step_limit)
            continue;
        void *state = sim->instances[k].state;
        const sluice_index n = v->count, chunk = 4096;
        const sluice_index chunks = (n + chunk - 1) / chunk;
        double limit = INFINITY;
#pragma omp parallel for schedule(static) reduction(min : limit)
        for (sluice_index ch = 0; ch < chunks; ch++) {
            sluice_index a = ch * chunk, b = a + chunk < n ? a + chunk : n;
            double l = (double)c->time_step_limit(state, v, a, b);
            if (l < limit || l != l)
                limit = l != l ? -1.0 : l;
        }
        if (limit < dt)
            dt = limit;
    }
    if (sim->comm.size > 1) /* NaN limits are -1: the minimum keeps them */
        dt = sluice_comm_min(&sim->comm, dt);
    if (sim->scene.time.max_step > 0 && dt > sim->scene.time.max_step)
        dt = sim->scene.time.max_step;
    sim->dt_limit = dt;
    double remaining = sim->end - sim->time;
    if (dt >= remaining)
        dt = remaining;
    double next = next_request(sim);
    if (sim->time + dt > next)
        dt = next - sim->time;
    sim->dt = dt;
    sim->view.dt = dt;
    return dt;
}

static void api_parallel_for(sluice_host *host, sluice_index count, sluice_range_fn fn,
                             void *context)
{
    sluice_sim *sim = host->sim;
    sluice_sim_refresh_view(sim);
    const sluice_view *v = &sim->view;
    const sluice_index chunk = 2048;
    const sluice_index chunks = (count + chunk - 1) / chunk;
#pragma omp parallel for schedule(static)
    for (sluice_index c = 0; c < chunks; c++) {
        sluice_index a = c * chunk, b = a + chunk < count ? a + chunk : count;
        fn(context, v, a, b);
    }
}

static void api_request_time(sluice_host *host, double t)
{
    sluice_sim_request_time(host->sim, t);
}

void sluice_sim_request_time(sluice_sim *sim, double t)
{
    /* times at or past the end are kept too: a checkpoint records them, and a
     * run restarted with a later time.end then stops on them as a run
     * started with that end would */
    if (!(t > sim->time) || !isfinite(t))
        return;
    for (size_t i = 0; i < sim->request_count; i++)
        if (sim->requests[i] == t)
            return;
    /* drop past requests first */
    size_t kept = 0;
    for (size_t i = 0; i < sim->request_count; i++)
        if (sim->requests[i] > sim->time)
            sim->requests[kept++] = sim->requests[i];
    sim->request_count = kept;
    if (sim->request_count == sim->request_capacity) {
        size_t cap = sim->request_capacity ? 2 * sim->request_capacity : 16;
        double *r = realloc(sim->requests, cap * sizeof *r);
        if (!r)
            return; /* a missed request only shifts an output by part of a step */
        sim->requests = r;
        sim->request_capacity = cap;
    }
    sim->requests[sim->request_count++] = t;
}

/* --------------------------------------------------------------- output -- */

static int api_output_path(sluice_host *host, const char *name, char *buffer, size_t size)
{
    sluice_sim *sim = host->sim;
    if (across_ranks_only(host, "writing output files (api->output_path)") != SLUICE_OK)
        return SLUICE_ERROR;
    if (!sim->output_directory) {
        if (size)
            buffer[0] = '\0';
        return SLUICE_ERROR;
    }
    int n = snprintf(buffer, size, "%s/%s", sim->output_directory, name);
    return n > 0 && (size_t)n < size ? SLUICE_OK : SLUICE_ERROR;
}

static const char *api_resolved_scene(sluice_host *host)
{
    return host->sim->resolved_scene ? host->sim->resolved_scene : "";
}

static uint32_t api_plugin_count(sluice_host *host)
{
    return host->sim->instance_count;
}

static int api_plugin(sluice_host *host, uint32_t index, sluice_plugin_info *out)
{
    const sluice_sim *sim = host->sim;
    if (index >= sim->instance_count)
        return SLUICE_ERROR;
    const sluice_instance *in = &sim->instances[index];
    out->component = in->component->name;
    out->library = in->library->name ? in->library->name : "";
    out->version = in->library->version ? in->library->version : "";
    out->path = in->path;
    return SLUICE_OK;
}

static uint32_t api_field_count(sluice_host *host)
{
    return host->sim->field_count;
}

static int api_field_info(sluice_host *host, uint32_t index, sluice_field_spec *spec,
                          sluice_field *field)
{
    const sluice_sim *sim = host->sim;
    if (index >= sim->field_count)
        return SLUICE_ERROR;
    const sluice_field_entry *f = &sim->fields[index];
    if (spec) {
        memset(spec, 0, sizeof *spec);
        spec->name = f->name;
        spec->type = f->type;
        spec->components = f->components;
        spec->units = f->units;
        spec->flags = f->flags;
        spec->rate_of = f->rate_of;
        spec->kinds = f->kinds;
        spec->doc = f->doc;
        for (uint32_t d = 0; d < f->declarer_count; d++)
            spec->access |= f->declarers[d].access;
    }
    if (field) {
        field->column = f->column;
        field->components = f->components;
        field->type = f->type;
    }
    return SLUICE_OK;
}

int sluice_sim_table_flush_row(sluice_table *table, const char *line, size_t length);

static sluice_table *api_table_open(sluice_host *host, const char *file_name, const char *header)
{
    sluice_sim *sim = host->sim;
    if (across_ranks_only(host, "writing tables (api->table_open)") != SLUICE_OK)
        return NULL;
    if (!file_name || !*file_name || strchr(file_name, '/')) {
        api_error(host, "table file name '%s' must be a plain file name in the run directory",
                  file_name ? file_name : "");
        return NULL;
    }
    sluice_table *t = calloc(1, sizeof *t);
    sluice_table **grown = realloc(sim->tables, (sim->table_count + 1) * sizeof *grown);
    if (grown)
        sim->tables = grown;
    if (!t || !grown) {
        free(t);
        api_error(host, "out of memory opening table '%s'", file_name);
        return NULL;
    }
    t->sim = sim;
    t->fd = -1;
    /* the path is resolved at the first row: the output directory is created
     * after the components are initialised */
    t->header = copy_string(header);
    t->path = copy_string(file_name);
    if (!t->header || !t->path) {
        free(t->header);
        free(t->path);
        free(t);
        api_error(host, "out of memory opening table '%s'", file_name);
        return NULL;
    }
    sim->tables[sim->table_count++] = t;
    return t;
}

static int api_table_row(sluice_table *table, const double *values, uint32_t count)
{
    if (!table)
        return SLUICE_ERROR;
    if (table->failed)
        return SLUICE_ERROR;
    if (!table->sim->output_directory)
        return SLUICE_OK; /* sluice check: nothing is written */
    if (table->sim->comm.rank != 0)
        return SLUICE_OK; /* across ranks, rank 0 writes the (reduced) rows */
    /* at most 24 characters a value ("%.10g" and a comma) */
    char stack[4096];
    size_t size = 24 * (size_t)count + 2;
    char *line = size <= sizeof stack ? stack : malloc(size);
    if (!line) {
        sluice_sim_fail(table->sim, "out of memory writing a row of %s", table->path);
        return SLUICE_ERROR;
    }
    size_t used = 0;
    for (uint32_t i = 0; i < count; i++) {
        int w = snprintf(line + used, size - used, "%s%.10g", i ? "," : "", values[i]);
        if (w < 0 || (size_t)w >= size - used) {
            if (line != stack)
                free(line);
            return SLUICE_ERROR;
        }
        used += (size_t)w;
    }
    line[used++] = '\n';
    int rc = sluice_sim_table_flush_row(table, line, used);
    if (line != stack)
        free(line);
    return rc;
}

static int api_write_file_atomic(sluice_host *host, const char *path, const void *data, size_t size)
{
    if (across_ranks_only(host, "writing files (api->write_file_atomic)") != SLUICE_OK)
        return SLUICE_ERROR;
    if (host->sim->comm.rank != 0)
        return SLUICE_OK; /* across ranks, rank 0 writes the file */
    char error[512];
    if (sluice_write_file_atomic(path, data, size, error, sizeof error) != 0) {
        api_error(host, "%s", error);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

/* api->wall_distance's cells over the domain, about a kernel support (2h)
 * wide, built at the first call: from a component's init, or from within a
 * pass, where the first thread to arrive builds them (with the threads of a
 * nested team: one) and the others wait. When the build runs out of memory
 * the index is left empty and every query asks every element: the same
 * numbers, slower. */
static const sluice_wall_distance_index *wall_distance_index(sluice_sim *sim)
{
    if (!atomic_load_explicit(&sim->wall_distance_built, memory_order_acquire)) {
#pragma omp critical(sluice_wall_distance_build)
        if (!atomic_load_explicit(&sim->wall_distance_built, memory_order_relaxed)) {
            const sluice_scene *scene = &sim->scene;
            double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
            for (uint32_t d = 0; d < scene->dimensions; d++) {
                lo[d] = (double)scene->domain.min[d];
                hi[d] = (double)scene->domain.max[d];
            }
            /* out of memory leaves the index without cells: every query
             * then asks every element */
            (void)sluice_wall_distance_init(&sim->wall_distance, scene->dimensions,
                                            sim->wall_geometries, scene->wall_count, lo, hi,
                                            2.0 * (double)sim->smoothing_length);
            atomic_store_explicit(&sim->wall_distance_built, 1, memory_order_release);
        }
    }
    return &sim->wall_distance;
}

static sluice_real api_wall_distance(sluice_host *host, const sluice_real *point)
{
    return (sluice_real)sluice_wall_distance(wall_distance_index(host->sim), point);
}

/* Across ranks: the other ranks' particles in the halo as they are now
 * (every field). Collective; nothing on one rank. */
static int refresh_halo(sluice_sim *sim)
{
#ifdef SLUICE_MPI
    if (sim->comm.size > 1 && sluice_ranks_refresh_halo(sim) != 0)
        return SLUICE_ERROR;
#else
    (void)sim;
#endif
    return SLUICE_OK;
}

static int api_pair_pass(sluice_host *host)
{
    sluice_sim *sim = host->sim;
    sluice_instance *in = &sim->instances[host->instance];
    if (!in->on_demand) {
        api_error(host, "calls api->pair_pass but is not flagged SLUICE_COMPONENT_ON_DEMAND");
        return SLUICE_ERROR;
    }
    if (update_neighbours(sim) != SLUICE_OK || refresh_halo(sim) != SLUICE_OK)
        return SLUICE_ERROR;
    sim->evaluating++;
    int failed = sluice_pair_pass_run(&sim->engine, in->on_demand, &sim->grid, &sim->view) != 0;
    sim->evaluating--;
    if (failed) {
        sluice_sim_fail(sim, "out of memory in the pair pass of '%s'", in->name);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

/* The scene's equation of state: the component with a density_from_pressure
 * callback (the last one in scene order), or NULL. */
static const sluice_instance *equation_of_state(const sluice_sim *sim)
{
    const sluice_instance *eos = NULL;
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if (sim->instances[k].component->density_from_pressure)
            eos = &sim->instances[k];
    return eos;
}

static int api_density_from_pressure(sluice_host *host, sluice_index n,
                                     const sluice_real *pressure, sluice_real *density)
{
    const sluice_instance *eos = equation_of_state(host->sim);
    if (!eos) {
        api_error(host, "needs the inverse of the equation of state (api->density_from_pressure), "
                        "but no loaded plugin provides an equation of state with one (load one, "
                        "e.g. tait)");
        return SLUICE_ERROR;
    }
    if (n == 0)
        return SLUICE_OK;
    if (!pressure || !density) {
        api_error(host, "api->density_from_pressure called with a NULL array");
        return SLUICE_ERROR;
    }
    eos->component->density_from_pressure(eos->state, n, pressure, density);
    return SLUICE_OK;
}

static int api_wall_nearest(sluice_host *host, const sluice_real *point, int32_t wall,
                            sluice_wall_point *out)
{
    const sluice_sim *sim = host->sim;
    const size_t walls = sim->scene.wall_count;
    if (walls == 0 || (wall >= 0 && (size_t)wall >= walls) || !point || !out)
        return SLUICE_ERROR;
    size_t first = wall >= 0 ? (size_t)wall : 0, last = wall >= 0 ? (size_t)wall + 1 : walls;
    double best = INFINITY;
    int found = 0;
    for (size_t w = first; w < last; w++) {
        const sluice_real *b = sim->wall_bounds + 6 * w;
        double lower = 0;
        for (uint32_t d = 0; d < sim->scene.dimensions; d++) {
            double below = (double)b[d] - (double)point[d], above = (double)point[d] - (double)b[3 + d];
            double gap = below > 0 ? below : above > 0 ? above : 0;
            lower += gap * gap;
        }
        if (found && lower >= best * best)
            continue;
        sluice_wall_point candidate;
        sluice_wall_nearest(&sim->scene.walls[w].geometry, point, &candidate);
        if (!found || fabs((double)candidate.distance) < best) {
            best = fabs((double)candidate.distance);
            *out = candidate;
            out->wall = (uint32_t)w;
            found = 1;
        }
    }
    return found ? SLUICE_OK : SLUICE_ERROR;
}

/* The pass of api->point_pass and api->point_pass_local, once the
 * neighbour search is up to date (with_halo: the halo's particles are pairs
 * too). */
static int run_point_pass(sluice_sim *sim, const sluice_host *host, const sluice_real *points,
                          sluice_index count, uint32_t kinds, int with_halo, sluice_point_fn fn,
                          void *context)
{
    sim->evaluating++;
    int failed = sluice_point_pass_run(&sim->engine, &sim->grid, &sim->view, points, count,
                                       sluice_neighbour_kinds(kinds), with_halo, fn,
                                       context) != 0;
    sim->evaluating--;
    if (failed) {
        sluice_sim_fail(sim, "out of memory in the point pass of '%s'",
                        instance_name(sim, host->instance));
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int api_point_pass(sluice_host *host, const sluice_real *points, sluice_index count,
                          uint32_t kinds, sluice_point_fn fn, void *context)
{
    sluice_sim *sim = host->sim;
    if (across_ranks_only(host, "a point pass (api->point_pass)") != SLUICE_OK)
        return SLUICE_ERROR;
    if (!fn || (count > 0 && !points)) {
        api_error(host, "api->point_pass called without points or without a callback");
        return SLUICE_ERROR;
    }
    if (count == 0)
        return SLUICE_OK;
    if (update_neighbours(sim) != SLUICE_OK)
        return SLUICE_ERROR;
    return run_point_pass(sim, host, points, count, kinds, 0, fn, context);
}

/* 1.9: points of the rank's own particles, with the halo's particles as
 * pairs: one rank's result at every point within the component's margin of
 * the rank's box. */
static int api_point_pass_local(sluice_host *host, const sluice_real *points, sluice_index count,
                                uint32_t kinds, sluice_point_fn fn, void *context)
{
    sluice_sim *sim = host->sim;
    if (!fn || (count > 0 && !points)) {
        api_error(host, "api->point_pass_local called without points or without a callback");
        return SLUICE_ERROR;
    }
    /* collective across ranks, whatever this rank's count */
    if (update_neighbours(sim) != SLUICE_OK || refresh_halo(sim) != SLUICE_OK)
        return SLUICE_ERROR;
#ifdef SLUICE_MPI
    if (sim->comm.size > 1 && host->instance != SLUICE_CORE_INSTANCE &&
        !sim->instances[host->instance].local_points) {
        /* the halo refreshes the fields of such a component (ranks.c) */
        sluice_sim_fail(sim,
                        "plugin '%s' calls api->point_pass_local without having called "
                        "api->request_point_margin (in create, bind or initialise; 0 when its "
                        "points lie at its particles)",
                        instance_name(sim, host->instance));
        return SLUICE_ERROR;
    }
    if (sim->comm.size > 1) {
        /* the halo holds every particle within the support of a point up to
         * point_margin outside the box (ranks.c: its width) */
        for (sluice_index q = 0; q < count; q++) {
            const double p[3] = {(double)points[3 * (size_t)q], (double)points[3 * (size_t)q + 1],
                                 (double)points[3 * (size_t)q + 2]};
            const double outside = sluice_ranks_outside(sim, p);
            if (!(outside <= (double)sim->point_margin)) {
                sluice_sim_fail(sim,
                                "step %lld: plugin '%s' interpolates at (%.6g, %.6g, %.6g) m on "
                                "rank %d, %.6g m outside the rank's box, beyond the %.6g m it "
                                "requested (api->request_point_margin)",
                                (long long)sim->step, instance_name(sim, host->instance), p[0],
                                p[1], p[2], sim->comm.rank, outside, (double)sim->point_margin);
                return SLUICE_ERROR;
            }
        }
    }
#endif
    if (count == 0)
        return SLUICE_OK;
    return run_point_pass(sim, host, points, count, kinds, 1, fn, context);
}

static int api_request_point_margin(sluice_host *host, sluice_real margin)
{
    sluice_sim *sim = host->sim;
    if (host->instance == SLUICE_CORE_INSTANCE || sim->phase > SLUICE_PHASE_INITIALISE) {
        api_error(host, "api->request_point_margin is for a component's create(), bind() or "
                        "initialise()");
        return SLUICE_ERROR;
    }
    if (!(margin >= 0) || !isfinite(margin)) {
        api_error(host, "api->request_point_margin: the margin %g m is not finite and >= 0",
                  (double)margin);
        return SLUICE_ERROR;
    }
    if (margin > sim->point_margin)
        sim->point_margin = margin;
    sim->instances[host->instance].local_points = 1;
    return SLUICE_OK;
}

static int api_request_reach(sluice_host *host, sluice_real radius)
{
    sluice_sim *sim = host->sim;
    if (host->instance == SLUICE_CORE_INSTANCE || sim->creating != (int64_t)host->instance) {
        api_error(host, "api->request_reach is for a component's create()");
        return SLUICE_ERROR;
    }
    sluice_instance *in = &sim->instances[host->instance];
    if (!in->component->pair) {
        api_error(host, "api->request_reach: '%s' has no pair term", in->name);
        return SLUICE_ERROR;
    }
    if (!(radius > 0) || !isfinite(radius)) {
        api_error(host, "api->request_reach: the radius %g m is not positive and finite",
                  (double)radius);
        return SLUICE_ERROR;
    }
    in->reach = radius;
    return SLUICE_OK;
}

static int api_restrict_reach(sluice_host *host, const char *field, uint32_t value)
{
    sluice_sim *sim = host->sim;
    if (host->instance == SLUICE_CORE_INSTANCE || sim->creating != (int64_t)host->instance) {
        api_error(host, "api->restrict_reach is for a component's create()");
        return SLUICE_ERROR;
    }
    sluice_instance *in = &sim->instances[host->instance];
    if (!(in->reach > 0)) {
        api_error(host, "api->restrict_reach: '%s' did not request a reach "
                        "(api->request_reach comes first)",
                  in->name);
        return SLUICE_ERROR;
    }
    if (!field || !field[0] || strlen(field) >= sizeof in->reach_field || value > 255) {
        api_error(host, "api->restrict_reach: needs a field name (under %zu characters) and a "
                        "value from 0 to 255",
                  sizeof in->reach_field);
        return SLUICE_ERROR;
    }
    memcpy(in->reach_field, field, strlen(field) + 1);
    in->reach_value = value;
    return SLUICE_OK;
}

/* ---------------------------------------------------------- across ranks -- */

static int api_reduce(sluice_host *host, double *values, uint32_t count, sluice_reduce_op op)
{
    sluice_sim *sim = host->sim;
    if (count > 0 && !values) {
        api_error(host, "reduce: no values");
        return SLUICE_ERROR;
    }
    if (op != SLUICE_REDUCE_SUM && op != SLUICE_REDUCE_MIN && op != SLUICE_REDUCE_MAX) {
        api_error(host, "reduce: unknown operation %d", (int)op);
        return SLUICE_ERROR;
    }
    if (sim->comm.size == 1 || count == 0)
        return SLUICE_OK;
    if (sluice_comm_reduce(&sim->comm, values, count, (int)op) != 0) {
        api_error(host, "reduce: MPI failed");
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int api_owns(sluice_host *host, const sluice_real *point)
{
    const sluice_sim *sim = host->sim;
    if (sim->comm.size == 1 || !point)
        return 1;
#ifdef SLUICE_MPI
    const double p[3] = {(double)point[0], (double)point[1], (double)point[2]};
    return sluice_ranks_owns(sim, p);
#else
    return 1;
#endif
}

static int api_ranks(sluice_host *host, sluice_ranks *out)
{
    sluice_sim *sim = host->sim;
    memset(out, 0, sizeof *out);
    out->rank = sim->comm.rank;
    out->count = sim->comm.size;
    out->particle_total = sim->particles.count;
    if (sim->comm.size > 1 &&
        sluice_comm_offset(&sim->comm, sim->particles.count, &out->particle_offset,
                           &out->particle_total) != 0) {
        api_error(host, "ranks: MPI failed");
        return SLUICE_ERROR;
    }
#ifdef SLUICE_MPI
    out->communicator = sim->comm.size > 1 ? (const void *)&sim->comm.comm : NULL;
#endif
    return SLUICE_OK;
}

static const sluice_api api_table = {
    sizeof(sluice_api),
    SLUICE_ABI_MAJOR,
    SLUICE_ABI_MINOR,
    api_error,
    api_warning,
    api_info,
    api_declare_field,
    api_field,
    api_publish_constant,
    api_constant,
    api_rate_count,
    api_rate,
    api_view,
    api_add_particles,
    api_wall_count,
    api_wall,
    api_wall_layer_points,
    api_release,
    api_evaluate,
    api_time_step,
    api_parallel_for,
    api_request_time,
    api_output_path,
    api_resolved_scene,
    api_plugin_count,
    api_plugin,
    api_field_count,
    api_field_info,
    api_table_open,
    api_table_row,
    api_write_file_atomic,
    api_wall_distance,
    api_pair_pass,
    api_density_from_pressure,
    api_wall_nearest,
    api_point_pass,
    api_remove_particles,
    api_set_kind,
    api_removed_count,
    sluice_api_state_write,
    sluice_api_state_read,
    sluice_api_state_length,
    api_request_reach,
    api_restrict_reach,
    api_reduce,
    api_ranks,
    api_owns,
    api_point_pass_local,
    api_request_point_margin,
};

/* ------------------------------------------------------------ schedule -- */

const char *sluice_field_writers(const sluice_sim *sim, const sluice_field_entry *field,
                                 char *buffer, size_t size)
{
    size_t used = 0;
    buffer[0] = '\0';
    for (uint32_t d = 0; d < field->declarer_count; d++) {
        if (!(field->declarers[d].access & (SLUICE_WRITE | SLUICE_ACCUMULATE)))
            continue;
        int w = snprintf(buffer + used, size - used, "%s%s", used ? ", " : "",
                         instance_name(sim, field->declarers[d].instance));
        if (w < 0 || (size_t)w >= size - used)
            break;
        used += (size_t)w;
    }
    if (!used)
        snprintf(buffer, size, "the core");
    return buffer;
}

/* a pair term of every evaluation (an on-demand pair callback runs only
 * when its component asks, from a hook) */
static int evaluation_pair(const sluice_component *c)
{
    return c->pair && !(c->flags & SLUICE_COMPONENT_ON_DEMAND);
}

static int is_evaluation(const sluice_component *c)
{
    return c->particle || evaluation_pair(c);
}

/* Describes a pair pass made of the given components: the terms, the
 * neighbour kinds per target kind, and the columns to gather at neighbours
 * per target kind. 0, or -1 on OOM (the pass is then freed by the caller). */
static int fill_pair_pass(sluice_sim *sim, sluice_pair_pass *p, const uint32_t *members,
                          uint32_t count)
{
    p->select_column = -1;
    p->terms = calloc(count ? count : 1, sizeof *p->terms);
    if (!p->terms)
        return -1;
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++) {
        p->gathered_columns[k] = calloc(sim->column_count + 1, sizeof *p->gathered_columns[k]);
        if (!p->gathered_columns[k])
            return -1;
    }
    const size_t stride = sim->column_count + 1;
    uint8_t *gather = calloc((size_t)SLUICE_KIND_COUNT * stride, 1);
    if (!gather)
        return -1;
    for (uint32_t m = 0; m < count; m++) {
        const uint32_t v = members[m];
        const sluice_component *c = sim->instances[v].component;
        sluice_pair_term *t = &p->terms[p->term_count++];
        t->component = c;
        t->state = sim->instances[v].state;
        t->target_kinds = c->target_kinds;
        t->neighbour_kinds = sluice_neighbour_kinds(c->neighbour_kinds);
        for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++) {
            if (!(c->target_kinds & SLUICE_KIND_MASK(k)))
                continue;
            p->neighbour_mask[k] |= t->neighbour_kinds;
            if (c->flags & SLUICE_COMPONENT_NEEDS_KERNEL)
                p->needs_kernel[k] = 1;
            for (uint32_t f = 0; f < sim->field_count; f++) {
                const sluice_field_entry *field = &sim->fields[f];
                for (uint32_t d = 0; d < field->declarer_count; d++)
                    if (field->declarers[d].instance == v &&
                        (field->declarers[d].access & SLUICE_READ_NEIGHBOUR) &&
                        field->type == SLUICE_TYPE_REAL)
                        for (uint32_t comp = 0; comp < field->components; comp++)
                            gather[(size_t)k * stride + (size_t)(field->column + (int32_t)comp)] = 1;
            }
        }
    }
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++) {
        for (uint32_t c = 0; c < sim->column_count; c++)
            if (gather[(size_t)k * stride + c])
                p->gathered_columns[k][p->gathered_count[k]++] = c;
        if (p->gathered_count[k] > p->gathered_max)
            p->gathered_max = p->gathered_count[k];
    }
    free(gather);
    return 0;
}

static void free_pair_pass(sluice_pair_pass *p)
{
    if (!p)
        return;
    free(p->terms);
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++)
        free(p->gathered_columns[k]);
    sluice_reach_list_free(p->reach_list);
    memset(p, 0, sizeof *p);
}

/* The order of the initialise calls: a component that writes a field
 * initialises before the components that only read it (two_phase sets each
 * particle's phase before the components that act on one phase look at
 * it), scene order otherwise; a cycle falls back to scene order. Returns a
 * malloc'd permutation of the instances, NULL when out of memory. */
static uint32_t *initialise_order(const sluice_sim *sim)
{
    const uint32_t n = sim->instance_count;
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    uint8_t *placed = calloc(n ? n : 1, 1);
    if (!order || !placed) {
        free(order);
        free(placed);
        return NULL;
    }
    for (uint32_t o = 0; o < n; o++) {
        /* the first instance in scene order that waits for no writer */
        uint32_t chosen = n;
        for (uint32_t k = 0; k < n && chosen == n; k++) {
            if (placed[k])
                continue;
            int waits = 0;
            for (uint32_t f = 0; f < sim->field_count && !waits; f++) {
                const sluice_field_entry *field = &sim->fields[f];
                int reads = 0;
                for (uint32_t d = 0; d < field->declarer_count; d++)
                    if (field->declarers[d].instance == k) {
                        const uint32_t access = field->declarers[d].access;
                        reads = (access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR)) &&
                                !(access & SLUICE_WRITE);
                    }
                for (uint32_t d = 0; d < field->declarer_count && reads; d++) {
                    const sluice_declarer *dec = &field->declarers[d];
                    if (dec->instance != SLUICE_CORE_INSTANCE && dec->instance != k &&
                        (dec->access & SLUICE_WRITE) && !placed[dec->instance])
                        waits = 1;
                }
            }
            if (!waits)
                chosen = k;
        }
        if (chosen == n) /* a cycle: scene order */
            for (uint32_t k = 0; k < n && chosen == n; k++)
                if (!placed[k])
                    chosen = k;
        placed[chosen] = 1;
        order[o] = chosen;
    }
    free(placed);
    return order;
}

/* The reach pass's selection (api->restrict_reach): a uint8 field of one
 * component that the instance declared it reads. 0, or 1 with the error
 * reported. */
static int reach_selection(sluice_sim *sim, uint32_t v, sluice_pair_pass *pass)
{
    const sluice_instance *in = &sim->instances[v];
    if (!in->reach_field[0])
        return 0;
    const sluice_field_entry *field = sluice_sim_find_field(sim, in->reach_field);
    int reads = 0;
    for (uint32_t d = 0; field && d < field->declarer_count; d++)
        reads |= field->declarers[d].instance == v &&
                 (field->declarers[d].access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR));
    if (!field || field->type != SLUICE_TYPE_UINT8 || field->components != 1 || !reads) {
        report(sim, v,
               "plugin '%s' restricts its reach to the field '%s', which must be a uint8 field "
               "of one component that it declares it reads",
               in->name, in->reach_field);
        return 1;
    }
    pass->select_column = field->column;
    pass->select_value = (uint8_t)in->reach_value;
    return 0;
}

/* Checks the declarations and orders the evaluation components into passes. */
static int build_schedule(sluice_sim *sim)
{
    const uint32_t n = sim->instance_count;
    int errors = 0;
    char missing[1024] = "";
    size_t missing_used = 0;
    uint32_t missing_count = 0, missing_reader = SLUICE_CORE_INSTANCE;
    /* conflicts and missing providers */
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        int64_t writer = -1, accumulator = -1;
        int provided = strcmp(field->name, "position") == 0 || strcmp(field->name, "kind") == 0 ||
                       strcmp(field->name, "id") == 0 || strcmp(field->name, "mass") == 0 ||
                       strcmp(field->name, "velocity") == 0 || strcmp(field->name, "density") == 0;
        for (uint32_t d = 0; d < field->declarer_count; d++) {
            const sluice_declarer *dec = &field->declarers[d];
            if (dec->access & (SLUICE_WRITE | SLUICE_ACCUMULATE))
                provided = 1;
            if (dec->instance == SLUICE_CORE_INSTANCE ||
                !is_evaluation(sim->instances[dec->instance].component))
                continue;
            if (dec->access & SLUICE_WRITE) {
                if (writer >= 0 && (uint32_t)writer != dec->instance) {
                    report(sim, dec->instance,
                           "plugins '%s' and '%s' both write field '%s' during the evaluation; "
                           "load only one of them",
                           sim->instances[writer].name, sim->instances[dec->instance].name,
                           field->name);
                    errors++;
                }
                writer = dec->instance;
            }
            if (dec->access & SLUICE_ACCUMULATE)
                accumulator = dec->instance;
        }
        if (writer >= 0 && accumulator >= 0 && writer != accumulator) {
            report(sim, (uint32_t)writer,
                   "plugin '%s' writes field '%s' while '%s' accumulates into it; a field is "
                   "either written by one plugin or accumulated",
                   sim->instances[writer].name, field->name, sim->instances[accumulator].name);
            errors++;
        }
        if (!provided) {
            /* gathered into one message below: one missing plugin (an
             * equation of state, a turbulence model) often leaves several
             * fields without a provider */
            for (uint32_t d = 0; d < field->declarer_count; d++) {
                const sluice_declarer *dec = &field->declarers[d];
                if (dec->access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR)) {
                    if (missing_count == 0)
                        missing_reader = dec->instance;
                    int w = snprintf(missing + missing_used, sizeof missing - missing_used,
                                     "%s'%s' (read by '%s')", missing_count ? ", " : "",
                                     field->name, instance_name(sim, dec->instance));
                    if (w > 0 && (size_t)w < sizeof missing - missing_used)
                        missing_used += (size_t)w;
                    missing_count++;
                    break;
                }
            }
        }
        if (field->rate_of && !sluice_sim_find_field(sim, field->rate_of)) {
            report(sim, field->declarers[0].instance,
                   "field '%s' is declared the rate of '%s', which no loaded plugin declares",
                   field->name, field->rate_of);
            errors++;
        }
    }
    if (missing_count == 1) {
        report(sim, missing_reader,
               "field %s is computed by no loaded plugin; load the plugin that provides it",
               missing);
        errors++;
    } else if (missing_count > 1) {
        report(sim, missing_reader,
               "fields %s are computed by no loaded plugin; load the plugins that provide them",
               missing);
        errors++;
    }
    if (errors)
        return errors;

    /* dependency edges between evaluation components: writer -> reader */
    uint8_t *edge = calloc((size_t)n * n + 1, 1);
    int *slot = malloc((n + 1) * sizeof *slot);
    int *done = calloc(n + 1, sizeof *done);
    if (!edge || !slot || !done) {
        free(edge);
        free(slot);
        free(done);
        return 1;
    }
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        for (uint32_t a = 0; a < field->declarer_count; a++) {
            const sluice_declarer *w = &field->declarers[a];
            if (w->instance == SLUICE_CORE_INSTANCE || !(w->access & (SLUICE_WRITE | SLUICE_ACCUMULATE)))
                continue;
            if (!is_evaluation(sim->instances[w->instance].component))
                continue;
            for (uint32_t b = 0; b < field->declarer_count; b++) {
                const sluice_declarer *r = &field->declarers[b];
                if (r->instance == SLUICE_CORE_INSTANCE || r->instance == w->instance ||
                    !(r->access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR)))
                    continue;
                if (!is_evaluation(sim->instances[r->instance].component))
                    continue;
                edge[(size_t)w->instance * n + r->instance] = 1;
            }
        }
    }
    /* longest-path slots: particle terms on even slots, pair passes on odd */
    int max_slot = -1;
    for (uint32_t round = 0; round < n; round++) {
        int progress = 0;
        for (uint32_t v = 0; v < n; v++) {
            if (done[v] || !is_evaluation(sim->instances[v].component))
                continue;
            int ready = 1, lower = 0;
            for (uint32_t u = 0; u < n; u++) {
                if (!edge[(size_t)u * n + v])
                    continue;
                if (!done[u]) {
                    ready = 0;
                    break;
                }
                if (slot[u] + 1 > lower)
                    lower = slot[u] + 1;
            }
            if (!ready)
                continue;
            int pair = evaluation_pair(sim->instances[v].component);
            if ((lower % 2 == 1) != pair)
                lower++;
            slot[v] = lower;
            done[v] = 1;
            progress = 1;
            if (lower > max_slot)
                max_slot = lower;
        }
        if (!progress)
            break;
    }
    for (uint32_t v = 0; v < n; v++)
        if (is_evaluation(sim->instances[v].component) && !done[v]) {
            char cycle[1024];
            size_t used = 0;
            for (uint32_t u = 0; u < n; u++)
                if (is_evaluation(sim->instances[u].component) && !done[u]) {
                    int w = snprintf(cycle + used, sizeof cycle - used, "%s%s", used ? ", " : "",
                                     sim->instances[u].name);
                    if (w > 0 && (size_t)w < sizeof cycle - used)
                        used += (size_t)w;
                }
            report(sim, v,
                   "the plugins %s depend on each other's fields in a cycle; no evaluation order "
                   "exists",
                   cycle);
            free(edge);
            free(slot);
            free(done);
            return 1;
        }

    /* Pair terms as late as their readers allow: a pair term whose results
     * nothing in the evaluation reads (rates, accelerations) joins the last
     * pair pass, and any other moves up to just before its first reader.
     * Every reader still comes after its writers, and terms that could share a
     * traversal do (the dbc clamp, a particle term, would otherwise split the
     * density terms from the forces into two neighbour traversals). Visited in
     * decreasing slot order, so that readers are placed before their writers. */
    int last_pair_slot = max_slot % 2 == 1 ? max_slot : max_slot - 1;
    for (int s = max_slot; s >= 0; s--)
        for (uint32_t v = 0; v < n; v++) {
            if (!is_evaluation(sim->instances[v].component) || slot[v] != s ||
                !evaluation_pair(sim->instances[v].component))
                continue;
            int latest = last_pair_slot;
            for (uint32_t u = 0; u < n; u++)
                if (edge[(size_t)v * n + u] && slot[u] - 1 < latest)
                    latest = slot[u] - 1;
            if (latest % 2 == 0)
                latest--;
            if (latest > slot[v])
                slot[v] = latest;
        }

    /* components that prepare every evaluation, in scene order */
    sim->prepare = calloc((size_t)n + 1, sizeof *sim->prepare);
    if (!sim->prepare)
        goto oom;
    for (uint32_t v = 0; v < n; v++)
        if (sim->instances[v].component->prepare)
            sim->prepare[sim->prepare_count++] = v;

    /* passes in slot order */
    sim->passes = calloc((size_t)n + 1, sizeof *sim->passes);
    if (!sim->passes)
        goto oom;
    for (int s = 0; s <= max_slot; s++) {
        if (s % 2 == 0) {
            for (uint32_t v = 0; v < n; v++)
                if (is_evaluation(sim->instances[v].component) && slot[v] == s) {
                    sluice_pass *p = &sim->passes[sim->pass_count++];
                    p->is_pair = 0;
                    p->instance = v;
                }
            continue;
        }
        /* the terms within the support share one pass; a term that reaches
         * beyond it (api->request_reach) gets a pass of its own, after */
        uint32_t terms = 0;
        for (uint32_t v = 0; v < n; v++)
            terms += is_evaluation(sim->instances[v].component) && slot[v] == s &&
                     !(sim->instances[v].reach > sim->support);
        if (terms) {
            sluice_pass *p = &sim->passes[sim->pass_count++];
            p->is_pair = 1;
            uint32_t *members = calloc(terms, sizeof *members);
            if (!members)
                goto oom;
            uint32_t m = 0;
            for (uint32_t v = 0; v < n; v++)
                if (is_evaluation(sim->instances[v].component) && slot[v] == s &&
                    !(sim->instances[v].reach > sim->support))
                    members[m++] = v;
            int rc = fill_pair_pass(sim, &p->pair, members, m);
            free(members);
            if (rc != 0)
                goto oom;
        }
        for (uint32_t v = 0; v < n; v++) {
            if (!is_evaluation(sim->instances[v].component) || slot[v] != s ||
                !(sim->instances[v].reach > sim->support))
                continue;
            sluice_pass *p = &sim->passes[sim->pass_count++];
            p->is_pair = 1;
            if (fill_pair_pass(sim, &p->pair, &v, 1) != 0)
                goto oom;
            p->pair.reach = sim->instances[v].reach;
            p->pair.reach_list = calloc(1, sizeof *p->pair.reach_list);
            if (!p->pair.reach_list)
                goto oom;
            if (reach_selection(sim, v, &p->pair) != 0)
                errors++;
        }
    }
    /* accumulated columns, zeroed before every evaluation */
    sim->accumulate_columns = calloc(sim->column_count + 1, sizeof *sim->accumulate_columns);
    if (!sim->accumulate_columns)
        goto oom;
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        int acc = 0;
        for (uint32_t d = 0; d < field->declarer_count; d++)
            acc |= (field->declarers[d].access & SLUICE_ACCUMULATE) != 0;
        if (acc)
            for (uint32_t comp = 0; comp < field->components; comp++)
                sim->accumulate_columns[sim->accumulate_count++] =
                    (uint32_t)field->column + comp;
    }
    /* on-demand pair terms: a pass of their own, run through api->pair_pass */
    for (uint32_t v = 0; v < n; v++) {
        sluice_instance *in = &sim->instances[v];
        if (!(in->component->flags & SLUICE_COMPONENT_ON_DEMAND))
            continue;
        in->on_demand = calloc(1, sizeof *in->on_demand);
        if (!in->on_demand || fill_pair_pass(sim, in->on_demand, &v, 1) != 0)
            goto oom;
        if (in->reach > sim->support) {
            in->on_demand->reach = in->reach;
            in->on_demand->reach_list = calloc(1, sizeof *in->on_demand->reach_list);
            if (!in->on_demand->reach_list)
                goto oom;
            if (reach_selection(sim, v, in->on_demand) != 0)
                errors++;
        }
    }
    free(edge);
    free(slot);
    free(done);
    return errors;
oom:
    free(edge);
    free(slot);
    free(done);
    report(sim, SLUICE_CORE_INSTANCE, "out of memory building the evaluation schedule");
    return 1;
}

static int build_rates(sluice_sim *sim)
{
    uint32_t count = 0;
    for (uint32_t f = 0; f < sim->field_count; f++)
        count += sim->fields[f].rate_of != NULL;
    sim->rates = calloc(count + 1, sizeof *sim->rates);
    if (!sim->rates)
        return -1;
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *rate = &sim->fields[f];
        if (!rate->rate_of)
            continue;
        const sluice_field_entry *state = sluice_sim_find_field(sim, rate->rate_of);
        if (!state)
            continue; /* reported by build_schedule */
        sluice_rate *r = &sim->rates[sim->rate_count++];
        handle_of(sim, state->name, &r->state);
        handle_of(sim, rate->name, &r->rate);
        r->kinds = rate->kinds;
        r->state_name = state->name;
        r->rate_name = rate->name;
        if (state->components != rate->components || state->type != SLUICE_TYPE_REAL ||
            rate->type != SLUICE_TYPE_REAL) {
            report(sim, rate->declarers[0].instance,
                   "field '%s' (%u components) cannot be the rate of '%s' (%u components)",
                   rate->name, rate->components, state->name, state->components);
            return 1;
        }
    }
    return 0;
}

/* ------------------------------------------------------- initial state -- */

typedef struct lattice_key {
    int64_t k[3];
    uint32_t region;
} lattice_key;

static int compare_keys(const void *a, const void *b)
{
    const lattice_key *x = a, *y = b;
    for (int d = 0; d < 3; d++)
        if (x->k[d] != y->k[d])
            return x->k[d] < y->k[d] ? -1 : 1;
    return 0;
}

static int fill_fluid(sluice_sim *sim)
{
    const sluice_scene *scene = &sim->scene;
    const uint32_t dims = scene->dimensions;
    const double dx = (double)sim->spacing;
    sluice_real gravity[3] = {0, 0, 0};
    uint32_t has_gravity = get_constant(sim, "gravity", gravity, 3);
    int hydrostatic = scene->initial_density == SLUICE_INITIAL_HYDROSTATIC && has_gravity &&
                      gravity[dims - 1] != 0;
    const sluice_instance *eos = NULL;
    if (hydrostatic) {
        eos = equation_of_state(sim);
        if (!eos) {
            report(sim, SLUICE_CORE_INSTANCE,
                   "initial.density is hydrostatic, but no loaded plugin provides an equation of "
                   "state to turn the hydrostatic pressure into density (load one, e.g. tait, or "
                   "set initial.density: rest)");
            return 1;
        }
    }
    size_t total_keys = 0, key_capacity = 0;
    lattice_key *keys = NULL;
    int errors = 0;
    for (size_t r = 0; r < scene->fluid_count && !errors; r++) {
        const sluice_scene_fluid *fluid = &scene->fluids[r];
        /* a fluid region thinner than one spacing (to round-off) is
         * resolved by at most one row of particles: almost always a spacing
         * meant for another scale (mm for m) */
        sluice_real lo[3], hi[3];
        sluice_region_bounds(&fluid->region, dims, lo, hi);
        for (uint32_t d = 0; d < dims; d++)
            if (hi[d] - lo[d] < sim->spacing * (1 - 1e-9)) {
                const sluice_node *node = fluid->node;
                sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node->file, node->line,
                                node->column,
                                "geometry.fluid.%zu is %g m across in %c, less than "
                                "particles.spacing = %g m: refine the spacing (at least one "
                                "spacing, better several, across every fluid region)",
                                r, (double)(hi[d] - lo[d]), "xyz"[d], (double)sim->spacing);
                errors++;
                break;
            }
        if (errors)
            break;
        sluice_points pts = {0};
        if (sluice_region_fill(&fluid->region, dims, sim->spacing, fluid->lattice_origin, &pts) !=
            0) {
            sluice_points_free(&pts);
            free(keys);
            report(sim, SLUICE_CORE_INSTANCE, "out of memory filling fluid regions");
            return 1;
        }
        /* drop points in or too close to walls */
        size_t kept = 0;
        for (size_t i = 0; i < pts.count; i++) {
            const sluice_real *p = pts.xyz + 3 * i;
            int keep = 1;
            for (size_t w = 0; w < scene->wall_count && keep; w++) {
                int beyond = 0;
                double dist = (double)sluice_wall_signed_distance(&scene->walls[w].geometry, p,
                                                                  &beyond, NULL);
                if (beyond)
                    continue;
                if (dist < 0.5 * dx * (1 - 1e-9))
                    keep = 0;
            }
            if (keep) {
                memmove(pts.xyz + 3 * kept, p, 3 * sizeof *p);
                kept++;
            }
        }
        pts.count = kept;
        if (kept == 0) {
            const sluice_node *node = fluid->node;
            sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node->file, node->line, node->column,
                            "geometry.fluid.%zu holds no particle at spacing %g m (is it smaller "
                            "than the spacing, or entirely inside a wall?)",
                            r, dx);
            sluice_points_free(&pts);
            errors++;
            break;
        }
        /* lattice keys for the overlap check */
        if (total_keys + kept > key_capacity) {
            size_t cap = (total_keys + kept) * 2;
            lattice_key *grown = realloc(keys, cap * sizeof *grown);
            if (!grown) {
                sluice_points_free(&pts);
                free(keys);
                report(sim, SLUICE_CORE_INSTANCE, "out of memory filling fluid regions");
                return 1;
            }
            keys = grown;
            key_capacity = cap;
        }
        for (size_t i = 0; i < kept; i++) {
            lattice_key *key = &keys[total_keys + i];
            for (int d = 0; d < 3; d++)
                key->k[d] = (uint32_t)d < dims
                                ? (int64_t)llround(((double)pts.xyz[3 * i + d] -
                                                    (double)scene->particles.lattice_origin[d]) /
                                                       dx -
                                                   0.5)
                                : 0;
            key->region = (uint32_t)r;
        }
        total_keys += kept;
        /* initial density */
        sluice_real *density = NULL;
        if (hydrostatic && sim->density.column >= 0) {
            double level = fluid->has_surface ? (double)fluid->surface : -INFINITY;
            if (!fluid->has_surface) {
                sluice_real lo[3], hi[3];
                sluice_region_bounds(&fluid->region, dims, lo, hi);
                level = (double)hi[dims - 1];
            }
            sluice_real *pressure = malloc(kept * sizeof *pressure);
            density = malloc(kept * sizeof *density);
            if (!pressure || !density) {
                free(pressure);
                free(density);
                sluice_points_free(&pts);
                free(keys);
                report(sim, SLUICE_CORE_INSTANCE, "out of memory filling fluid regions");
                return 1;
            }
            double g = -(double)gravity[dims - 1];
            /* the pressure at the rest density (background or reference
             * pressure of the equation of state), when it publishes one */
            sluice_real reference = 0;
            get_constant(sim, "reference_pressure", &reference, 1);
            for (size_t i = 0; i < kept; i++) {
                double depth = level - (double)pts.xyz[3 * i + dims - 1];
                pressure[i] = (sluice_real)((double)reference +
                                            (depth > 0 ? (double)sim->rest_density * g * depth
                                                       : 0.0));
            }
            eos->component->density_from_pressure(eos->state, (sluice_index)kept, pressure, density);
            free(pressure);
        }
        int rc = add_particles(sim, SLUICE_KIND_FLUID, pts.xyz, fluid->velocity, density,
                               (sluice_index)kept, NULL);
        free(density);
        sluice_points_free(&pts);
        if (rc != 0) {
            free(keys);
            report(sim, SLUICE_CORE_INSTANCE, "out of memory adding fluid particles");
            return 1;
        }
    }
    if (!errors && total_keys > 1) {
        qsort(keys, total_keys, sizeof *keys, compare_keys);
        for (size_t i = 1; i < total_keys; i++)
            if (compare_keys(&keys[i - 1], &keys[i]) == 0) {
                uint32_t a = keys[i - 1].region, b = keys[i].region;
                if (a > b) {
                    uint32_t t = a;
                    a = b;
                    b = t;
                }
                const sluice_node *node = scene->fluids[b].node;
                sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node->file, node->line,
                                node->column,
                                "geometry.fluid.%u overlaps geometry.fluid.%u: regions must not "
                                "share particles",
                                b, a);
                errors++;
                break;
            }
    }
    free(keys);
    return errors;
}

/* ---------------------------------------------------------------- load -- */

static int check_descriptor(sluice_sim *sim, uint32_t k)
{
    const sluice_instance *in = &sim->instances[k];
    const sluice_component *c = in->component;
    int errors = 0;
    uint32_t dims_mask = c->dimensions & in->library->signature.dimensions;
    if (!(dims_mask & (1u << sim->scene.dimensions))) {
        report(sim, k, "plugin '%s' (%s) does not support %uD scenes", in->name, in->path,
               sim->scene.dimensions);
        errors++;
    }
    if (c->pair && (c->target_kinds == 0 || c->neighbour_kinds == 0)) {
        report(sim, k, "plugin '%s' (%s) is a pair term but declares no target or neighbour kinds",
               in->name, in->path);
        errors++;
    }
    if ((c->flags & SLUICE_COMPONENT_ON_DEMAND) && !c->pair) {
        report(sim, k, "plugin '%s' (%s) is flagged on-demand but has no pair callback", in->name,
               in->path);
        errors++;
    }
    if (evaluation_pair(c) && c->particle) {
        report(sim, k,
               "plugin '%s' (%s) is both a particle and a pair term; split it into two "
               "components (or flag its pair callback on-demand)",
               in->name, in->path);
        errors++;
    }
    for (uint32_t f = 0; f < c->field_count; f++)
        if (c->fields[f].access & SLUICE_READ_NEIGHBOUR && !c->pair) {
            report(sim, k, "plugin '%s' reads field '%s' at neighbours but has no pair term",
                   in->name, c->fields[f].name);
            errors++;
        }
    return errors;
}

static const char *library_version(const sluice_instance *in)
{
    return in->library->version ? in->library->version : "?";
}

/* Before anything is allocated: the particles the scene would create, from
 * the lattice points of every fluid region's bounding box (what filling it
 * visits) and wall layers along every wall (a few spacings deep; counted as
 * SLUICE_SIZE_WALL_LAYERS layers). A scene whose particles would not fit in
 * this machine's memory at SLUICE_SIZE_BYTES_PER_PARTICLE (docs/performance.md
 * measures 325-436 bytes per particle in 2D), or that exceeds `limit` (> 0;
 * the fuzzer's), is refused with the count instead of running out of memory
 * or time half-way through the set-up. */
#define SLUICE_SIZE_WALL_LAYERS 4.0
#define SLUICE_SIZE_BYTES_PER_PARTICLE 300.0
static int check_scene_size(sluice_sim *sim, double limit)
{
    const sluice_scene *scene = &sim->scene;
    const uint32_t dims = scene->dimensions;
    const double dx = (double)scene->particles.spacing;
    double fluid = 0, wall = 0;
    for (size_t r = 0; r < scene->fluid_count; r++) {
        sluice_real lo[3], hi[3];
        sluice_region_bounds(&scene->fluids[r].region, dims, lo, hi);
        double points = 1;
        for (uint32_t d = 0; d < dims; d++)
            points *= floor(((double)hi[d] - (double)lo[d]) / dx) + 1;
        fluid += points;
    }
    for (size_t w = 0; w < scene->wall_count; w++) {
        const sluice_wall_geometry *g = &scene->walls[w].geometry;
        for (uint32_t e = 0; e < g->element_count; e++) {
            const sluice_real *p = g->points + (size_t)e * dims * 3;
            double measure;
            if (dims == 2) {
                measure = hypot((double)(p[3] - p[0]), (double)(p[4] - p[1])) / dx + 1;
            } else {
                double a[3], b[3];
                for (int d = 0; d < 3; d++) {
                    a[d] = (double)(p[3 + d] - p[d]);
                    b[d] = (double)(p[6 + d] - p[d]);
                }
                double c0 = a[1] * b[2] - a[2] * b[1], c1 = a[2] * b[0] - a[0] * b[2],
                       c2 = a[0] * b[1] - a[1] * b[0];
                measure = 0.5 * sqrt(c0 * c0 + c1 * c1 + c2 * c2) / (dx * dx) + 1;
            }
            wall += SLUICE_SIZE_WALL_LAYERS * measure;
        }
    }
    const double count = fluid + wall;
    const long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGESIZE);
    const double memory = pages > 0 && page_size > 0 ? (double)pages * (double)page_size : 0;
    const double needed = count * SLUICE_SIZE_BYTES_PER_PARTICLE;
    const sluice_node *node = sluice_node_get(scene->root, "particles");
    if (!(count < 4e9) || (memory > 0 && needed > memory) || (limit > 0 && count > limit)) {
        sluice_diag_add(sim->diag, SLUICE_SEVERITY_ERROR, node ? node->file : scene->path,
                        node ? node->line : 1, node ? node->column : 1,
                        "at particles.spacing = %g m the scene would create about %.3g particles "
                        "(%.3g fluid, %.3g wall), %s: use a larger spacing or smaller regions",
                        dx, count, fluid, wall,
                        limit > 0 && count > limit ? "more than this run's limit"
                        : memory > 0 && needed > memory
                            ? "more than this machine's memory holds at about 300 bytes each"
                            : "more than a particle index can count");
        return 1;
    }
    return 0;
}

static int load(sluice_sim *sim, const char *scene_path, const char *variant,
                const sluice_load_options *options)
{
    sluice_scene *scene = &sim->scene;
    sluice_diag *diag = sim->diag;
    int errors = sluice_scene_load_variant(scene, scene_path, variant,
                                           options ? options->overrides : NULL,
                                           options ? options->override_count : 0, diag);
    if (errors || !scene->root)
        return errors ? errors : 1;
    if (check_scene_size(sim, options ? options->max_particles : 0) != 0)
        return 1;

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
        const sluice_component_entry *entry = sluice_registry_find(&sim->registry, sp->name);
        if (!entry) {
            const char **names = calloc(sim->registry.component_count + 1, sizeof *names);
            for (size_t c = 0; names && c < sim->registry.component_count; c++)
                names[c] = sim->registry.components[c].component->name;
            const char *close =
                names ? sluice_closest(sp->name, names, sim->registry.component_count) : NULL;
            char refused[2048];
            sluice_registry_explain_missing(&sim->registry, sp->name, refused, sizeof refused);
            if (refused[0])
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sp->key->file, sp->key->line,
                                sp->key->column, "plugin '%s' could not be loaded: %s", sp->name,
                                refused);
            else if (close)
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sp->key->file, sp->key->line,
                                sp->key->column,
                                "no plugin named '%s' on the plugin path; did you mean '%s'? (run "
                                "'sluice inspect' to list plugins)",
                                sp->name, close);
            else
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sp->key->file, sp->key->line,
                                sp->key->column,
                                "no plugin named '%s' on the plugin path (%zu directories "
                                "searched; run 'sluice inspect' to list plugins)",
                                sp->name, sim->registry.directory_count);
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
        errors += sluice_schema_bind(in->component->params, in->component->param_count, sp->section,
                                     sp->key, path, scene->dimensions, in->config, scene->arena,
                                     diag);
    }
    if (errors)
        return errors;
    /* instances hold pointers into the registry arrays; release nothing that is used */
    sluice_registry_release_unused(&sim->registry);

    /* roles */
    sim->kernel = sim->integrator = -1;
    int wall_schemes = 0;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        const sluice_component *c = sim->instances[k].component;
        if (c->kernel) {
            if (sim->kernel >= 0) {
                report(sim, k, "two kernels are loaded ('%s' and '%s'); load exactly one",
                       sim->instances[sim->kernel].name, sim->instances[k].name);
                errors++;
            }
            sim->kernel = (int32_t)k;
        }
        if (c->advance) {
            if (sim->integrator >= 0) {
                report(sim, k, "two integrators are loaded ('%s' and '%s'); load exactly one",
                       sim->instances[sim->integrator].name, sim->instances[k].name);
                errors++;
            }
            sim->integrator = (int32_t)k;
        }
        wall_schemes += (c->flags & SLUICE_COMPONENT_WALL_SCHEME) != 0;
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
                        scheme = sim->instances[k].name;
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
            int found = 0;
            for (uint32_t k = 0; k < sim->instance_count; k++)
                found |= (sim->instances[k].component->flags & SLUICE_COMPONENT_WALL_SCHEME) &&
                         strcmp(sim->instances[k].name, scheme) == 0;
            if (!found) {
                const sluice_node *s = sluice_node_get(wall->node, "scheme");
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, s ? s->file : wall->node->file,
                                s ? s->line : wall->node->line, s ? s->column : wall->node->column,
                                "geometry.walls.%zu names wall scheme '%s', which is not a loaded "
                                "wall-scheme plugin",
                                w, scheme);
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
    if (!sim->wall_bounds || !sim->wall_geometries)
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
    if (errors)
        return errors;

    /* core fields and constants */
    sim->spacing = scene->particles.spacing;
    sim->smoothing_length = scene->particles.smoothing_length_ratio * scene->particles.spacing;
    sim->rest_density = scene->particles.rest_density;
    sim->end = scene->time.end;
    static const sluice_field_spec core_fields[] = {
        {"position", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m", SLUICE_WRITE,
         SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "particle position"},
        {"kind", SLUICE_TYPE_UINT8, 1, "1", SLUICE_WRITE,
         SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "particle kind: 0 fluid, 1 wall"},
        {"id", SLUICE_TYPE_ID, 1, "1", SLUICE_WRITE, SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART,
         NULL, 0, "permanent particle identity"},
    };
    for (size_t f = 0; f < SLUICE_COUNT(core_fields); f++)
        if (declare(sim, SLUICE_CORE_INSTANCE, &core_fields[f]) != 0)
            return 1;
    sluice_real value = (sluice_real)scene->dimensions;
    errors += publish(sim, SLUICE_CORE_INSTANCE, "dimensions", &value, 1, "1") != 0;
    errors += publish(sim, SLUICE_CORE_INSTANCE, "spacing", &sim->spacing, 1, "m") != 0;
    errors += publish(sim, SLUICE_CORE_INSTANCE, "smoothing_length", &sim->smoothing_length, 1,
                      "m") != 0;
    errors += publish(sim, SLUICE_CORE_INSTANCE, "rest_density", &sim->rest_density, 1,
                      "kg m^-3") != 0;
    /* 1.4: the run's end time and the domain box */
    sluice_real end_time = (sluice_real)scene->time.end;
    errors += publish(sim, SLUICE_CORE_INSTANCE, "end_time", &end_time, 1, "s") != 0;
    errors += publish(sim, SLUICE_CORE_INSTANCE, "domain_min", scene->domain.min,
                      scene->dimensions, "m") != 0;
    errors += publish(sim, SLUICE_CORE_INSTANCE, "domain_max", scene->domain.max,
                      scene->dimensions, "m") != 0;
    if (errors)
        return errors;

    /* static declarations, then create */
    sim->phase = SLUICE_PHASE_CREATE;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        const sluice_component *c = sim->instances[k].component;
        for (uint32_t f = 0; f < c->field_count; f++)
            if (declare(sim, k, &c->fields[f]) != 0)
                errors++;
    }
    if (errors)
        return errors;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        sluice_instance *in = &sim->instances[k];
        sim->creating = k;
        sim->pending[0] = '\0';
        size_t reported = sim->diag ? sluice_diag_error_count(sim->diag) : 0;
        int rc = in->component->create(&api_table, &in->host, in->config, &in->state);
        sim->creating = -1;
        if (rc != SLUICE_OK && !sim->pending[0] && sim->diag &&
            sluice_diag_error_count(sim->diag) > reported) {
            /* the core already said why (e.g. a constant published twice) */
            return errors + 1;
        }
        if (rc != SLUICE_OK || sim->pending[0]) {
            /* one message: the plugin, its library, versions and path, and why */
            report(sim, k,
                   "plugin '%s' (library '%s' %s, plugin ABI %u.%u, this sluice %u.%u; %s) failed "
                   "to initialise: %s",
                   in->name, in->library->name ? in->library->name : "?", library_version(in),
                   in->library->abi_major, in->library->abi_minor, SLUICE_ABI_MAJOR,
                   SLUICE_ABI_MINOR, in->path,
                   sim->pending[0] ? sim->pending : "its create function returned an error");
            if (rc == SLUICE_OK)
                in->created = 1; /* destroy what it made */
            return errors + 1;
        }
        in->created = 1;
    }
    sluice_real support_ratio = 0;
    if (get_constant(sim, "kernel_support", &support_ratio, 1) != 1 || !(support_ratio > 0)) {
        report(sim, (uint32_t)sim->kernel,
               "kernel '%s' did not publish its support radius (constant 'kernel_support', in "
               "units of h)",
               sim->instances[sim->kernel].name);
        return errors + 1;
    }
    sim->support = support_ratio * sim->smoothing_length;
    /* integrated fields are known once every plugin is created (integrators
     * read them in bind) */
    if (build_rates(sim) != 0)
        return errors + 1;

    sim->phase = SLUICE_PHASE_BIND;
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        sluice_instance *in = &sim->instances[k];
        if (!in->component->bind)
            continue;
        size_t before = sluice_diag_error_count(diag);
        if (in->component->bind(in->state, &in->host) != SLUICE_OK) {
            if (sluice_diag_error_count(diag) == before)
                report(sim, k, "plugin '%s' (%s) failed to bind", in->name, in->path);
            errors++;
        }
    }
    if (errors)
        return errors;
    handle_of(sim, "position", &sim->position);
    handle_of(sim, "kind", &sim->kind);
    handle_of(sim, "id", &sim->id);
    handle_of(sim, "mass", &sim->mass);
    handle_of(sim, "velocity", &sim->velocity);
    handle_of(sim, "density", &sim->density);
    errors += build_schedule(sim);
    if (errors)
        return errors;

    /* particle store */
    uint8_t *sizes = calloc(sim->column_count + 1, 1);
    if (!sizes)
        return 1;
    for (uint32_t f = 0; f < sim->field_count; f++)
        for (uint32_t c = 0; c < sim->fields[f].components; c++)
            sizes[sim->fields[f].column + (int32_t)c] = type_size(sim->fields[f].type);
    int rc = sluice_particles_init(&sim->particles, sim->column_count, sizes);
    free(sizes);
    if (rc != 0)
        return 1;
    sim->phase = SLUICE_PHASE_INITIALISE;
    sluice_sim_refresh_view(sim);
    errors += fill_fluid(sim);
    if (errors)
        return errors;
    uint32_t *order = initialise_order(sim);
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
                report(sim, k, "plugin '%s' (%s) failed to initialise its particles", in->name,
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
    /* passes beyond the support must not see a cell twice across a periodic side */
    for (uint32_t v = 0; v < sim->instance_count; v++) {
        const sluice_instance *in = &sim->instances[v];
        if (in->reach > sim->support && sluice_pair_reach_check(&sim->grid, in->reach) != 0) {
            report(sim, v,
                   "plugin '%s' reaches %g m, more than half the length of a periodic side of "
                   "the domain (plus a cell); lengthen the periodic side or shorten the reach",
                   in->name, (double)in->reach);
            return 1;
        }
    }
    sim->threads = omp_get_max_threads();
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
    if (sim->comm.size > 1 && !sim->check_only && sluice_ranks_split(sim) != 0) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 0, 0, "%s", sim->failure);
        return 1;
    }
#else
    sim->particles_initial = sim->particles.count;
#endif

    sim->resolved_scene = sluice_yaml_emit(scene->root);
    if (!sim->resolved_scene)
        return 1;
    return 0;
}

sluice_sim *sluice_sim_load(const char *scene_path, const sluice_load_options *options,
                            sluice_diag *diag)
{
    return sluice_sim_load_variant(scene_path, NULL, options, diag);
}

sluice_sim *sluice_sim_load_variant(const char *scene_path, const char *variant,
                                    const sluice_load_options *options, sluice_diag *diag)
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
    sim->state_group = -1;
    sim->checkpoint_step = -1;
    sim->kernel = sim->integrator = -1;
    sim->position.column = sim->kind.column = sim->id.column = -1;
    sim->mass.column = sim->velocity.column = sim->density.column = -1;
    sim->check_only = options ? options->check_only : 0;
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
    for (size_t t = 0; t < sim->table_count; t++) {
        if (sim->tables[t]->fd >= 0)
            close(sim->tables[t]->fd);
        free(sim->tables[t]->path);
        free(sim->tables[t]->header);
        free(sim->tables[t]);
    }
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
            free_pair_pass(&sim->passes[p].pair);
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        free_pair_pass(sim->instances[k].on_demand);
        free(sim->instances[k].on_demand);
    }
    free(sim->wall_bounds);
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
    sluice_registry_close(&sim->registry);
    sluice_scene_free(&sim->scene);
    omp_destroy_lock(&sim->message_lock);
    free(sim);
}

/* --------------------------------------------------------- introspection -- */

int sluice_sim_rank(const sluice_sim *sim)
{
    return sim->comm.rank;
}

int sluice_sim_rank_count(const sluice_sim *sim)
{
    return sim->comm.size;
}

uint64_t sluice_sim_particle_total(const sluice_sim *sim)
{
    return sluice_comm_sum_u64(&sim->comm, sim->particles.count);
}

const sluice_view *sluice_sim_view(sluice_sim *sim)
{
    sluice_sim_refresh_view(sim);
    return &sim->view;
}

int sluice_sim_field(sluice_sim *sim, const char *name, sluice_field *out)
{
    return handle_of(sim, name, out);
}

double sluice_sim_time(const sluice_sim *sim)
{
    return sim->time;
}

double sluice_sim_end_time(const sluice_sim *sim)
{
    return sim->end;
}

int64_t sluice_sim_steps(const sluice_sim *sim)
{
    return sim->step;
}

uint32_t sluice_sim_dimensions(const sluice_sim *sim)
{
    return sim->scene.dimensions;
}

const char *sluice_sim_resolved_scene(const sluice_sim *sim)
{
    return sim->resolved_scene;
}

const char *sluice_sim_variant(const sluice_sim *sim)
{
    return sim->scene.variant;
}

const char *sluice_sim_scene_variant(const sluice_sim *sim, size_t index,
                                     const char **description)
{
    if (index >= sim->scene.variant_count)
        return NULL;
    if (description)
        *description = sim->scene.variants[index].description;
    return sim->scene.variants[index].name;
}

uint32_t sluice_sim_field_count(const sluice_sim *sim)
{
    return sim->field_count;
}

const char *sluice_sim_field_name(const sluice_sim *sim, uint32_t index)
{
    return index < sim->field_count ? sim->fields[index].name : NULL;
}

size_t sluice_sim_bytes(const sluice_sim *sim)
{
    return sluice_particles_bytes(&sim->particles) + sluice_grid_bytes(&sim->grid) +
           sluice_pair_engine_bytes(&sim->engine);
}

uint64_t sluice_sim_pair_count(const sluice_sim *sim)
{
    return sluice_pair_engine_pairs(&sim->engine);
}

uint64_t sluice_sim_neighbour_rebuilds(const sluice_sim *sim)
{
    return sim->grid.rebuilds;
}

uint64_t sluice_sim_particle_steps(const sluice_sim *sim)
{
    return sim->particle_steps;
}

int sluice_sim_threads(const sluice_sim *sim)
{
    return sim->threads;
}

const char *sluice_sim_failure(const sluice_sim *sim)
{
    return sim->failure;
}
