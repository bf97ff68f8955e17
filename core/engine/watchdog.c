/* The stability watchdog (docs/reliability.md): every watchdog.every
 * steps, a scan for a collapsed time step, non-finite fields, densities
 * out of range, particles through walls or out of the domain, naming the
 * step, the particle, the field and the plugin that wrote it. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "build_config.h"
#include "sim_internal.h"

/* --------------------------------------------------------------------- watchdog -- */

/* What the watchdog found first: the particle, the kind of fault and where. */
typedef struct watch_finding {
    sluice_index first;   /* the particle (view->count: none) */
    int what;             /* 0 none, 1 non-finite, 2 density band, 3 outside domain, 4 wall */
    const sluice_field_entry *field; /* 1: the field */
    uint32_t component;   /* 1: its component; 3: the axis */
    double wall_depth;    /* 4: how far behind the wall, m */
    uint32_t wall, element;
} watch_finding;

/* Each particle's own rest density, m_i / dx^d: the core gives every
 * particle rest_density dx^d, a two-phase plugin the air rho0_a dx^d. */
static double rest_density_of(const sluice_sim *sim, const sluice_real *mass, sluice_index i)
{
    const double inverse_volume =
        1.0 / pow((double)sim->spacing, (double)sim->view.dimensions);
    return mass ? (double)mass[i] * inverse_volume : (double)sim->rest_density;
}

static const sluice_real *column_or_null(const sluice_sim *sim, sluice_field f)
{
    return f.column >= 0 ? (const sluice_real *)sim->view.columns[f.column] : NULL;
}

/* Non-finite values in position and every integrated field. */
static void scan_non_finite(const sluice_sim *sim, watch_finding *w)
{
    const sluice_view *v = &sim->view;
    const sluice_index n = v->count;
    /* state fields: position and every integrated field */
    uint32_t fields = 0;
    const sluice_field_entry *checked[64];
    for (uint32_t f = 0; f < sim->field_count && fields < 64; f++) {
        const sluice_field_entry *e = &sim->fields[f];
        if (e->type != SLUICE_TYPE_REAL)
            continue;
        int state = strcmp(e->name, "position") == 0;
        for (uint32_t r = 0; r < sim->rate_count; r++)
            state |= strcmp(sim->rates[r].state_name, e->name) == 0 ||
                     strcmp(sim->rates[r].rate_name, e->name) == 0;
        if (state)
            checked[fields++] = e;
    }
    for (uint32_t k = 0; k < fields; k++) {
        const sluice_field_entry *e = checked[k];
        for (uint32_t c = 0; c < e->components; c++) {
            const sluice_real *x = v->columns[e->column + (int32_t)c];
            sluice_index found = n;
#pragma omp parallel for schedule(static) reduction(min : found) if (n >= sim->parallel_min)
            for (sluice_index i = 0; i < n; i++)
                if (!isfinite(x[i]) && i < found)
                    found = i;
            if (found < w->first) {
                w->first = found;
                w->what = 1;
                w->field = e;
                w->component = c;
            }
        }
    }
}

/* Densities outside the band about each particle's rest density; the
 * largest fluid deviation is kept for run.json. */
static void scan_density(sluice_sim *sim, watch_finding *w)
{
    const sluice_view *v = &sim->view;
    const sluice_index n = v->count;
    const double band = (double)sim->scene.watchdog.density_band;
    const sluice_real *density = column_or_null(sim, sim->density);
    const sluice_real *mass = column_or_null(sim, sim->mass);
    if (!density)
        return;
    const double rho0 = (double)sim->rest_density;
    const double inverse_volume = 1.0 / pow((double)sim->spacing, (double)v->dimensions);
    sluice_index found = n;
    double deviation = 0; /* fluid only: wall particles' densities are a wall model's */
    const uint8_t *kind = v->kind;
#pragma omp parallel for schedule(static) reduction(min : found) reduction(max : deviation) if (n >= sim->parallel_min)
    for (sluice_index i = 0; i < n; i++) {
        const double rest = mass ? (double)mass[i] * inverse_volume : rho0;
        double r = (double)density[i] / rest - 1.0;
        if (!(fabs(r) <= band) && i < found)
            found = i;
        if (kind[i] == SLUICE_KIND_FLUID && fabs(r) > deviation)
            deviation = fabs(r);
    }
    if (deviation > sim->max_density_deviation)
        sim->max_density_deviation = deviation;
    if (found < n) {
        w->first = found;
        w->what = 2;
    }
}

/* Particles outside the domain along a closed axis. */
static void scan_domain(const sluice_sim *sim, watch_finding *w)
{
    const sluice_view *v = &sim->view;
    const sluice_scene *scene = &sim->scene;
    const sluice_index n = v->count;
    for (uint32_t d = 0; d < v->dimensions; d++) {
        if (scene->domain.periodic[d])
            continue;
        const sluice_real *x = v->position[d];
        const double lo = (double)scene->domain.min[d], hi = (double)scene->domain.max[d];
        sluice_index found = n;
#pragma omp parallel for schedule(static) reduction(min : found) if (n >= sim->parallel_min)
        for (sluice_index i = 0; i < n; i++)
            if (!((double)x[i] >= lo && (double)x[i] < hi) && i < found)
                found = i;
        if (found < w->first) {
            w->first = found;
            w->what = 3;
            w->component = d;
        }
    }
}

/* Fluid particles deeper than wall_penetration spacings behind the nearest
 * wall (wall_watch.h). */
static void scan_walls(const sluice_sim *sim, watch_finding *w)
{
    const sluice_view *v = &sim->view;
    const sluice_scene *scene = &sim->scene;
    const sluice_index n = v->count;
    if (sim->wall_watch.cells.wall_count == 0)
        return;
    const double allowed = (double)scene->watchdog.wall_penetration * (double)sim->spacing;
    const uint8_t *kind = v->kind;
    sluice_index found = n;
#pragma omp parallel for schedule(static) reduction(min : found) if (n >= sim->parallel_min)
    for (sluice_index i = 0; i < n; i++) {
        if (kind[i] != SLUICE_KIND_FLUID || i >= found)
            continue;
        sluice_real p[3] = {v->position[0][i], v->position[1][i],
                            v->dimensions == 3 ? v->position[2][i] : 0};
        int beyond;
        uint32_t w, e;
        double d = sluice_wall_watch_distance(&sim->wall_watch, p, &beyond, &w, &e);
        if (d < -allowed)
            found = i;
    }
    if (found < n) {
        w->first = found;
        w->what = 4;
        sluice_real p[3] = {v->position[0][found], v->position[1][found],
                            v->dimensions == 3 ? v->position[2][found] : 0};
        int beyond;
        w->wall_depth = -sluice_wall_watch_distance(&sim->wall_watch, p, &beyond, &w->wall,
                                                    &w->element);
    }
}

/* The diagnostic: the step, the particle, the quantity, the plugins that
 * wrote it and the integrator. */
static void report_finding(sluice_sim *sim, const watch_finding *w)
{
    const sluice_view *v = &sim->view;
    const sluice_scene *scene = &sim->scene;
    const double band = (double)scene->watchdog.density_band;
    char who[256], writers[512];
    const sluice_index i = w->first;
    if (v->dimensions == 3)
        snprintf(who, sizeof who, "particle id %llu (%s, index %u) at (%.6g, %.6g, %.6g) m",
                 (unsigned long long)v->id[i], sluice_kind_name(v->kind[i]),
                 i, (double)v->position[0][i], (double)v->position[1][i], (double)v->position[2][i]);
    else
        snprintf(who, sizeof who, "particle id %llu (%s, index %u) at (%.6g, %.6g) m",
                 (unsigned long long)v->id[i], sluice_kind_name(v->kind[i]),
                 i, (double)v->position[0][i], (double)v->position[1][i]);
    if (w->what == 1) {
        const sluice_real *x = v->columns[w->field->column + (int32_t)w->component];
        char comp[16] = "";
        if (w->field->components > 1)
            snprintf(comp, sizeof comp, "[%u]", w->component);
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: %s: field '%s'%s = %g is not finite (%s; "
                        "integrated by '%s')",
                        (long long)sim->step, sim->time, who, w->field->name, comp, (double)x[i],
                        sluice_field_writers_for(sim, w->field, v->kind[i], writers,
                                                 sizeof writers),
                        sim->instances[sim->integrator].name);
    } else if (w->what == 2) {
        const sluice_field_entry *e = sluice_sim_find_field(sim, "density");
        const double rest = rest_density_of(sim, column_or_null(sim, sim->mass), i);
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: %s: field 'density' = %.6g kg m^-3 is outside the "
                        "band [%.6g, %.6g] = its rest density (mass / spacing^d) x (1 -/+ "
                        "watchdog.density_band) (%s; integrated by '%s')",
                        (long long)sim->step, sim->time, who, (double)column_or_null(sim, sim->density)[i],
                        rest * (1 - band), rest * (1 + band),
                        e ? sluice_field_writers_for(sim, e, v->kind[i], writers, sizeof writers)
                          : "?",
                        sim->instances[sim->integrator].name);
    } else if (w->what == 4) {
        const sluice_scene_wall *wall = &scene->walls[w->wall];
        const sluice_field_entry *e = sluice_sim_find_field(sim, "position");
        char name[160] = "";
        if (wall->name && wall->name[0])
            snprintf(name, sizeof name, " ('%s')", wall->name);
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: %s has gone through wall %u%s (handled by '%s'): "
                        "it is %.4g m = %.3g spacings behind its %s %u, deeper than "
                        "watchdog.wall_penetration = %g spacings (field 'position', %s; "
                        "integrated by '%s')",
                        (long long)sim->step, sim->time, who, w->wall, name,
                        sim->walls[w->wall].scheme ? sim->walls[w->wall].scheme : "?",
                        w->wall_depth, w->wall_depth / (double)sim->spacing,
                        v->dimensions == 3 ? "triangle" : "segment", w->element,
                        (double)scene->watchdog.wall_penetration,
                        e ? sluice_field_writers_for(sim, e, v->kind[i], writers, sizeof writers)
                          : "?",
                        sim->instances[sim->integrator].name);
    } else {
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: %s left the domain along %c (domain.min/max = "
                        "%g/%g m; field 'position', integrated by '%s')",
                        (long long)sim->step, sim->time, who, "xyz"[w->component],
                        (double)scene->domain.min[w->component],
                        (double)scene->domain.max[w->component],
                        sim->instances[sim->integrator].name);
    }
}

/* Checks the state after a step: non-finite values in integrated fields,
 * density outside the band, particles outside the domain or through a wall,
 * collapsed time step. Returns 0 when healthy, else fills sim->failure. */
int sluice_sim_watchdog(sluice_sim *sim)
{
    const sluice_scene *scene = &sim->scene;
    if (sim->dt_limit < scene->watchdog.min_time_step || !(sim->dt_limit > 0)) {
        sluice_sim_fail(sim,
                        "step %lld, t = %.9g s: the time step collapsed to %.3g s, below "
                        "watchdog.min_time_step = %.3g s (the flow has gone unstable: velocities "
                        "or accelerations have grown without bound)",
                        (long long)sim->step, sim->time, sim->dt_limit,
                        (double)scene->watchdog.min_time_step);
        return -1;
    }
    watch_finding w = {.first = sim->view.count, .wall = UINT32_MAX, .element = UINT32_MAX};
    scan_non_finite(sim, &w);
    if (!w.what)
        scan_density(sim, &w);
    if (!w.what)
        scan_domain(sim, &w);
    if (!w.what)
        scan_walls(sim, &w);
    if (!w.what)
        return 0;
    report_finding(sim, &w);
    return -1;
}
