/* The host table plugins call (sluice_api, docs/plugin-abi.md): messages,
 * fields, particles, walls, passes, time, outputs, state, ranks. */
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
#include "decomposition.h"
#include "sim_internal.h"
#include "yaml_tree.h"


/* A component written for runs across ranks (SLUICE_COMPONENT_ACROSS_RANKS). */
static int across_ranks_component(const sluice_sim *sim, uint32_t instance)
{
    if (instance >= sim->instance_count)
        return 0;
    const sluice_instance *in = &sim->instances[instance];
    return (in->component->flags & SLUICE_COMPONENT_ACROSS_RANKS) != 0;
}

static void host_message(sluice_host *host, sluice_severity severity, const char *format,
                         va_list ap)
{
    sluice_sim *sim = host->sim;
    char text[2048];
    vsnprintf(text, sizeof text, format, ap);
    const char *name = sluice_sim_instance_name(sim, host->instance);
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
            char stamp[40] = "";
            if (sim->timestamps || sim->progress == SLUICE_PROGRESS_LOG) {
                sluice_utc_timestamp(stamp, sizeof stamp - 1);
                strcat(stamp, " ");
            }
            fprintf(stderr, "%s%ssluice: %s: plugin '%s': %s\n",
                    sim->progress == SLUICE_PROGRESS_LINE ? "\n" : "", stamp,
                    severity == SLUICE_SEVERITY_ERROR ? "error" : "warning", name, text);
        } else if (sim->comm.rank == 0 || !across_ranks_component(sim, host->instance)) {
            /* across ranks a component written for it warns alike on every
             * rank: rank 0 speaks for it; any other says which rank it is */
            fprintf(stderr, "%ssluice: rank %d: %s: plugin '%s': %s\n",
                    sim->progress == SLUICE_PROGRESS_LINE ? "\n" : "", sim->comm.rank,
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
    char stamp[40] = "";
    if (host->sim->timestamps || host->sim->progress == SLUICE_PROGRESS_LOG) {
        sluice_utc_timestamp(stamp, sizeof stamp - 1);
        strcat(stamp, " ");
    }
    fprintf(stderr, "%ssluice: %s: %s\n", stamp, sluice_sim_instance_name(host->sim, host->instance),
            text);
}

static int api_declare_field(sluice_host *host, const sluice_field_spec *spec)
{
    return sluice_sim_declare(host->sim, host->instance, spec) == 0 ? SLUICE_OK : SLUICE_ERROR;
}

static int api_field(sluice_host *host, const char *name, sluice_field *out)
{
    if (sluice_sim_handle_of(host->sim, name, out) != SLUICE_OK) {
        api_error(host, "asks for field '%s', which no loaded plugin declares", name);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int api_publish_constant(sluice_host *host, const char *name, const sluice_real *values,
                                uint32_t count, const char *unit)
{
    return sluice_sim_publish(host->sim, host->instance, name, values, count, unit) == 0 ? SLUICE_OK
                                                                               : SLUICE_ERROR;
}

static uint32_t api_constant(sluice_host *host, const char *name, sluice_real *values,
                             uint32_t max_count)
{
    return sluice_sim_get_constant(host->sim, name, values, max_count);
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

static const sluice_view *api_view(sluice_host *host)
{
    sluice_sim_refresh_view(host->sim);
    return &host->sim->view;
}

/* Appends particles with the core's initial values; `density` may be NULL
 * (rest density). */
int sluice_sim_add_particles(sluice_sim *sim, uint8_t kind, const sluice_real *positions,
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
 * them (SLUICE_COMPONENT_ACROSS_RANKS), which combines its ranks'
 * figures with api->ranks->reduce; any other is refused, never left to write one
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
                    "api->ranks->reduce; docs/plugin-abi.md)",
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
        across_ranks_only(host, "adding particles (api->particles->add_particles)") != SLUICE_OK)
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
    if (sluice_sim_add_particles(sim, kind, positions, NULL, NULL, count, first) != 0) {
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
        across_ranks_only(host, "removing particles (api->particles->remove_particles)") != SLUICE_OK)
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

static int api_evaluate(sluice_host *host, double stage_time, uint32_t stage)
{
    sluice_sim *sim = host->sim;
    if (!isfinite(stage_time)) {
        sluice_sim_fail(sim, "plugin '%s': api->evaluation->evaluate at a stage time that is "
                             "not finite",
                        sluice_sim_instance_name(sim, host->instance));
        return SLUICE_ERROR;
    }
    sim->in_stage = 1;
    sim->stage_time = stage_time;
    sim->stage = stage;
    sluice_sim_refresh_view(sim);
    const int status = sluice_sim_evaluate(sim);
    sim->in_stage = 0;
    sluice_sim_refresh_view(sim);
    return status;
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
#pragma omp parallel for schedule(static) reduction(min : limit) if (n >= sim->parallel_min)
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
    double next = sluice_sim_next_request(sim);
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
#pragma omp parallel for schedule(static) if (count >= sim->parallel_min)
    for (sluice_index c = 0; c < chunks; c++) {
        sluice_index a = c * chunk, b = a + chunk < count ? a + chunk : count;
        fn(context, v, a, b);
    }
}

static void api_request_time(sluice_host *host, double t)
{
    sluice_sim_request_time(host->sim, t);
}

/* --------------------------------------------------------------- output -- */

static int api_output_path(sluice_host *host, const char *name, char *buffer, size_t size)
{
    sluice_sim *sim = host->sim;
    if (across_ranks_only(host, "writing output files (api->output->output_path)") != SLUICE_OK)
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


static sluice_table *api_table_open(sluice_host *host, const char *file_name, const char *header)
{
    sluice_sim *sim = host->sim;
    if (across_ranks_only(host, "writing tables (api->output->table_open)") != SLUICE_OK)
        return NULL;
    if (!file_name || !*file_name || strchr(file_name, '/')) {
        api_error(host, "table file name '%s' must be a plain file name in the run directory",
                  file_name ? file_name : "");
        return NULL;
    }
    for (size_t k = 0; k < sim->table_count; k++)
        if (strcmp(sim->tables[k]->path, file_name) == 0) {
            const sluice_instance *other = &sim->instances[sim->tables[k]->instance];
            api_error(host,
                      "table '%s' is also written by '%s' (%s:%d:%d): give one of them another "
                      "'file'",
                      file_name, other->name, other->key->file, other->key->line,
                      other->key->column);
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
    t->instance = host->instance;
    t->fd = -1;
    /* the path is resolved at the first row: the output directory is created
     * after the components are initialised */
    t->header = sluice_sim_copy_string(header);
    t->path = sluice_sim_copy_string(file_name);
    t->name = sluice_sim_copy_string(file_name);
    if (!t->header || !t->path || !t->name || sluice_sim_table_split_header(t) != 0) {
        sluice_sim_table_free(t);
        api_error(host, "out of memory opening table '%s'", file_name);
        return NULL;
    }
    sim->tables[sim->table_count++] = t;
    return t;
}

static int api_table_column(sluice_table *table, uint32_t column, const char *unit,
                            const char *description, const sluice_real *position)
{
    if (!table)
        return SLUICE_ERROR;
    sluice_host *host = &table->sim->instances[table->instance].host;
    if (column >= table->column_count) {
        api_error(host, "table '%s': column %u described, and its header has %u columns (0 to %u)",
                  table->name, column, table->column_count, table->column_count - 1);
        return SLUICE_ERROR;
    }
    sluice_table_column_info *c = &table->columns[column];
    if (!unit || !*unit || !description || !*description) {
        api_error(host, "table '%s': column '%s' needs a unit and a description ('1' for a "
                        "dimensionless number)",
                  table->name, c->name);
        return SLUICE_ERROR;
    }
    if (position)
        for (int d = 0; d < 3; d++)
            if (!isfinite((double)position[d])) {
                api_error(host, "table '%s': column '%s' has a position that is not finite",
                          table->name, c->name);
                return SLUICE_ERROR;
            }
    char *unit_copy = sluice_sim_copy_string(unit);
    char *description_copy = sluice_sim_copy_string(description);
    if (!unit_copy || !description_copy) {
        free(unit_copy);
        free(description_copy);
        api_error(host, "out of memory describing table '%s'", table->name);
        return SLUICE_ERROR;
    }
    free(c->unit);
    free(c->description);
    c->unit = unit_copy;
    c->description = description_copy;
    c->has_position = position != NULL;
    for (int d = 0; d < 3; d++)
        c->position[d] = position ? (double)position[d] : 0.0;
    return SLUICE_OK;
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
    if (across_ranks_only(host, "writing files (api->output->write_file_atomic)") != SLUICE_OK)
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

static int api_write_file_with(sluice_host *host, const char *path, sluice_file_writer writer,
                               void *context)
{
    if (across_ranks_only(host, "writing files (api->output->write_file_with)") != SLUICE_OK)
        return SLUICE_ERROR;
    if (host->sim->comm.rank != 0)
        return SLUICE_OK; /* across ranks, rank 0 writes the file */
    char error[1400];
    if (sluice_write_file_with(path, writer, context, error, sizeof error) != 0) {
        api_error(host, "%s", error);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static const char *api_describe_run(sluice_host *host, const char *name)
{
    return name ? sluice_sim_describe(host->sim, name) : NULL;
}

/* api->walls->wall_distance's cells over the domain, about a kernel support (2h)
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

static int api_pair_pass(sluice_host *host)
{
    sluice_sim *sim = host->sim;
    sluice_instance *in = &sim->instances[host->instance];
    if (!in->on_demand) {
        api_error(host, "calls api->evaluation->pair_pass but is not flagged SLUICE_COMPONENT_ON_DEMAND");
        return SLUICE_ERROR;
    }
    if (sluice_sim_update_neighbours(sim) != SLUICE_OK || sluice_sim_refresh_halo(sim) != SLUICE_OK)
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
const sluice_instance *sluice_sim_equation_of_state(const sluice_sim *sim)
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
    const sluice_instance *eos = sluice_sim_equation_of_state(host->sim);
    if (!eos) {
        api_error(host, "needs the inverse of the equation of state (api->evaluation->density_from_pressure), "
                        "but no loaded plugin provides an equation of state with one (load one, "
                        "e.g. tait)");
        return SLUICE_ERROR;
    }
    if (n == 0)
        return SLUICE_OK;
    if (!pressure || !density) {
        api_error(host, "api->evaluation->density_from_pressure called with a NULL array");
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

static int api_point_pass(sluice_host *host, const sluice_real *points, sluice_index count,
                          uint32_t kinds, sluice_point_fn fn, void *context)
{
    sluice_sim *sim = host->sim;
    if (across_ranks_only(host, "a point pass (api->evaluation->point_pass)") != SLUICE_OK)
        return SLUICE_ERROR;
    if (!fn || (count > 0 && !points)) {
        api_error(host, "api->evaluation->point_pass called without points or without a callback");
        return SLUICE_ERROR;
    }
    if (count == 0)
        return SLUICE_OK;
    if (sluice_sim_update_neighbours(sim) != SLUICE_OK)
        return SLUICE_ERROR;
    return sluice_sim_run_point_pass(sim, host, points, count, kinds, 0, fn, context);
}

/* Points of the rank's own particles, with the halo's particles as
 * pairs: one rank's result at every point within the component's margin of
 * the rank's box. */
static int api_point_pass_local(sluice_host *host, const sluice_real *points, sluice_index count,
                                uint32_t kinds, sluice_point_fn fn, void *context)
{
    sluice_sim *sim = host->sim;
    if (!fn || (count > 0 && !points)) {
        api_error(host, "api->evaluation->point_pass_local called without points or without a callback");
        return SLUICE_ERROR;
    }
    /* collective across ranks, whatever this rank's count */
    if (sluice_sim_update_neighbours(sim) != SLUICE_OK || sluice_sim_refresh_halo(sim) != SLUICE_OK)
        return SLUICE_ERROR;
#ifdef SLUICE_MPI
    if (sim->comm.size > 1 && host->instance != SLUICE_CORE_INSTANCE &&
        !sim->instances[host->instance].local_points) {
        /* the halo refreshes the fields of such a component (ranks.c) */
        sluice_sim_fail(sim,
                        "plugin '%s' calls api->evaluation->point_pass_local without having called "
                        "api->evaluation->request_point_margin (in create, bind or initialise; 0 when its "
                        "points lie at its particles)",
                        sluice_sim_instance_name(sim, host->instance));
        return SLUICE_ERROR;
    }
    if (sim->comm.size > 1) {
        /* the halo holds every particle within the support of a point up to
         * point_margin outside the box (ranks.c: its width) */
        for (sluice_index q = 0; q < count; q++) {
            const double p[3] = {(double)points[3 * (size_t)q], (double)points[3 * (size_t)q + 1],
                                 (double)points[3 * (size_t)q + 2]};
            const double outside = sluice_ranks_outside(&sim->ranks_run, p);
            if (!(outside <= (double)sim->point_margin)) {
                sluice_sim_fail(sim,
                                "step %lld: plugin '%s' interpolates at (%.6g, %.6g, %.6g) m on "
                                "rank %d, %.6g m outside the rank's box, beyond the %.6g m it "
                                "requested (api->evaluation->request_point_margin)",
                                (long long)sim->step, sluice_sim_instance_name(sim, host->instance), p[0],
                                p[1], p[2], sim->comm.rank, outside, (double)sim->point_margin);
                return SLUICE_ERROR;
            }
        }
    }
#endif
    if (count == 0)
        return SLUICE_OK;
    return sluice_sim_run_point_pass(sim, host, points, count, kinds, 1, fn, context);
}

static int api_request_point_margin(sluice_host *host, sluice_real margin)
{
    sluice_sim *sim = host->sim;
    if (host->instance == SLUICE_CORE_INSTANCE || sim->phase > SLUICE_PHASE_INITIALISE) {
        api_error(host, "api->evaluation->request_point_margin is for a component's create(), bind() or "
                        "initialise()");
        return SLUICE_ERROR;
    }
    if (!(margin >= 0) || !isfinite(margin)) {
        api_error(host, "api->evaluation->request_point_margin: the margin %g m is not finite and >= 0",
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
        api_error(host, "api->evaluation->request_reach is for a component's create()");
        return SLUICE_ERROR;
    }
    sluice_instance *in = &sim->instances[host->instance];
    if (!in->component->pair) {
        api_error(host, "api->evaluation->request_reach: '%s' has no pair term", in->name);
        return SLUICE_ERROR;
    }
    if (!(radius > 0) || !isfinite(radius)) {
        api_error(host, "api->evaluation->request_reach: the radius %g m is not positive and finite",
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
        api_error(host, "api->evaluation->restrict_reach is for a component's create()");
        return SLUICE_ERROR;
    }
    sluice_instance *in = &sim->instances[host->instance];
    if (!(in->reach > 0)) {
        api_error(host, "api->evaluation->restrict_reach: '%s' did not request a reach "
                        "(api->evaluation->request_reach comes first)",
                  in->name);
        return SLUICE_ERROR;
    }
    if (!field || !field[0] || strlen(field) >= sizeof in->reach_field || value > 255) {
        api_error(host, "api->evaluation->restrict_reach: needs a field name (under %zu characters) and a "
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
    return sluice_ranks_owns(&sim->ranks_run, p);
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

/* api->state->state_*: only inside a component's own save_state or
 * load_state, where the checkpoint library lends its store. */
static int no_state_store(sluice_host *host, int writing)
{
    sluice_sim_fail(host->sim, "plugin '%s': api->state->state_%s outside its own %s callback",
                    sluice_sim_instance_name(host->sim, host->instance), writing ? "write" : "read",
                    writing ? "save_state" : "load_state");
    return SLUICE_ERROR;
}

static int api_state_write(sluice_host *host, const char *name, sluice_state_type type,
                           uint64_t count, const void *data)
{
    const sluice_state_store *store = host->sim->state_store;
    return store ? store->write(host, name, type, count, data) : no_state_store(host, 1);
}

static int api_state_read(sluice_host *host, const char *name, sluice_state_type type,
                          uint64_t count, void *data)
{
    const sluice_state_store *store = host->sim->state_store;
    return store ? store->read(host, name, type, count, data) : no_state_store(host, 0);
}

static int64_t api_state_length(sluice_host *host, const char *name)
{
    const sluice_state_store *store = host->sim->state_store;
    if (!store) {
        no_state_store(host, 0);
        return -1;
    }
    return store->length(host, name);
}

/* A moving wall's displacement, set by the wall scheme that handles it. */
static int api_set_wall_displacement(sluice_host *host, uint32_t index,
                                     const sluice_real *displacement)
{
    sluice_sim *sim = host->sim;
    if (index >= sim->scene.wall_count || !displacement) {
        api_error(host, "set_wall_displacement: no wall %u (the scene has %zu)", index,
                  sim->scene.wall_count);
        return SLUICE_ERROR;
    }
    const sluice_wall *wall = &sim->walls[index];
    const sluice_component *component =
        host->instance < sim->instance_count ? sim->instances[host->instance].component : NULL;
    if (!component || !(component->flags & SLUICE_COMPONENT_WALL_SCHEME) || !wall->scheme ||
        strcmp(component->name, wall->scheme) != 0) {
        api_error(host, "set_wall_displacement: wall %u is handled by '%s'; only its wall scheme "
                        "moves it",
                  index, wall->scheme ? wall->scheme : "(none)");
        return SLUICE_ERROR;
    }
    if (!sim->wall_moves[index] && sim->phase == SLUICE_PHASE_RUN) {
        api_error(host, "set_wall_displacement: wall %u was not marked as moving before the run "
                        "(the first call belongs in create(), bind() or initialise())",
                  index);
        return SLUICE_ERROR;
    }
    if (sim->evaluating) {
        api_error(host, "set_wall_displacement inside an evaluation; move walls between steps");
        return SLUICE_ERROR;
    }
    for (int d = 0; d < 3; d++) {
        if (!isfinite((double)displacement[d])) {
            api_error(host, "set_wall_displacement: wall %u: displacement %d is not finite",
                      index, d);
            return SLUICE_ERROR;
        }
        sim->wall_displacement[3 * index + d] =
            d < (int)sim->scene.dimensions ? displacement[d] : 0;
    }
    sim->wall_moves[index] = 1;
    return SLUICE_OK;
}

static int api_wall_displacement(sluice_host *host, uint32_t index, sluice_real *out)
{
    const sluice_sim *sim = host->sim;
    const int moves = index < sim->scene.wall_count && sim->wall_moves[index];
    for (int d = 0; d < 3; d++)
        out[d] = moves ? sim->wall_displacement[3 * index + d] : 0;
    return moves;
}

static const sluice_api_messages messages_table = {
    sizeof(sluice_api_messages), api_error, api_warning, api_info,
};

static const sluice_api_fields fields_table = {
    sizeof(sluice_api_fields), api_declare_field, api_field, api_field_count, api_field_info,
    api_rate_count, api_rate, api_publish_constant, api_constant,
};

static const sluice_api_particles particles_table = {
    sizeof(sluice_api_particles), api_view, api_add_particles, api_remove_particles,
    api_set_kind, api_removed_count, api_parallel_for,
};

static const sluice_api_walls walls_table = {
    sizeof(sluice_api_walls), api_wall_count, api_wall, api_wall_layer_points, api_release,
    api_wall_distance, api_wall_nearest, api_set_wall_displacement, api_wall_displacement,
};

static const sluice_api_evaluation evaluation_table = {
    sizeof(sluice_api_evaluation), api_evaluate, api_time_step, api_request_time,
    api_pair_pass, api_point_pass, api_point_pass_local, api_request_point_margin,
    api_request_reach, api_restrict_reach, api_density_from_pressure,
};

static const sluice_api_output output_table = {
    sizeof(sluice_api_output), api_output_path, api_resolved_scene, api_plugin_count,
    api_plugin, api_table_open, api_table_row, api_write_file_atomic, api_write_file_with,
    api_describe_run,
    api_table_column,
};

static const sluice_api_state state_table = {
    sizeof(sluice_api_state), api_state_write, api_state_read, api_state_length,
};

static const sluice_api_ranks ranks_table = {
    sizeof(sluice_api_ranks), api_reduce, api_ranks, api_owns,
};

const sluice_api sluice_sim_api_table = {
    sizeof(sluice_api), SLUICE_ABI_MAJOR, SLUICE_ABI_MINOR,
    &messages_table, &fields_table, &particles_table, &walls_table,
    &evaluation_table, &output_table, &state_table, &ranks_table,
};
