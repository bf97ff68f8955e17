/* The simulation's shared state as every part of the engine sees it: the
 * first failure, the particle view, fields by name, requested times. */
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

double sluice_wall_clock(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

char *sluice_sim_copy_string(const char *s)
{
    if (!s)
        return NULL;
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

const char *sluice_sim_instance_name(const sluice_sim *sim, uint32_t instance)
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

/* ---------------------------------------------------------------- fields -- */

sluice_field_entry *sluice_sim_find_field(const sluice_sim *sim, const char *name)
{
    for (uint32_t i = 0; i < sim->field_count; i++)
        if (strcmp(sim->fields[i].name, name) == 0)
            return &sim->fields[i];
    return NULL;
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
    v->stage_time = sim->in_stage ? sim->stage_time : sim->time;
    v->stage = sim->in_stage ? sim->stage : 0;
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

/* ------------------------------------------------------------ schedule -- */

/* Whether instance `instance` writes a field for particles of `kind`: its
 * component targets that kind (pair terms) or says it is meant for it
 * (particle terms); a component that says neither may write any kind. */
static int writes_kind(const sluice_sim *sim, uint32_t instance, uint8_t kind)
{
    if (instance == SLUICE_CORE_INSTANCE || instance >= sim->instance_count)
        return 1;
    const sluice_component *c = sim->instances[instance].component;
    const uint32_t kinds = c->target_kinds | c->particle_kinds;
    return kinds == 0 || (kinds & SLUICE_KIND_MASK(kind)) != 0;
}

/* The writers of `field` for one kind of particle, the names joined by ", "
 * after `used` characters of buffer; returns the new length. */
static size_t kind_writers(const sluice_sim *sim, const sluice_field_entry *field, uint8_t kind,
                           char *buffer, size_t size, size_t used)
{
    const size_t start = used;
    for (uint32_t d = 0; d < field->declarer_count; d++) {
        const sluice_declarer *e = &field->declarers[d];
        if (!(e->access & (SLUICE_WRITE | SLUICE_ACCUMULATE)) || !writes_kind(sim, e->instance, kind))
            continue;
        int w = snprintf(buffer + used, size - used, "%s'%s'", used > start ? ", " : "",
                         sluice_sim_instance_name(sim, e->instance));
        if (w < 0 || (size_t)w >= size - used)
            break;
        used += (size_t)w;
    }
    return used;
}

const char *sluice_field_writers_for(const sluice_sim *sim, const sluice_field_entry *field,
                                     uint8_t kind, char *buffer, size_t size)
{
    const char *head = "written by ";
    snprintf(buffer, size, "%s", head);
    size_t used = kind_writers(sim, field, kind, buffer, size, strlen(head));
    if (used == strlen(head))
        used = 0, buffer[0] = '\0';
    /* an integrated field: the plugins that accumulate its rate for this kind */
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *rate = &sim->fields[f];
        if (!rate->rate_of || strcmp(rate->rate_of, field->name) != 0 ||
            !(rate->kinds & SLUICE_KIND_MASK(kind)))
            continue;
        char names[384];
        names[0] = '\0';
        if (kind_writers(sim, rate, kind, names, sizeof names, 0) == 0)
            continue;
        int w = snprintf(buffer + used, size - used, "%sfrom its rate '%s' accumulated by %s",
                         used ? ", " : "", rate->name, names);
        if (w > 0 && (size_t)w < size - used)
            used += (size_t)w;
    }
    if (!used)
        snprintf(buffer, size, "written by the core");
    return buffer;
}

