/* The plugin SDK: helpers for writing Sluice plugins, installed with
 * sluice/plugin.h (pkg-config sluice). Header only (static inline): plugins
 * never link against the core or each other, and nothing here holds state.
 *
 * This header has the small helpers (constants, field look-ups, state
 * allocation, named scalars in checkpoints) and includes the focused ones:
 *
 * - sluice/field_specs.h: the standard declarations of velocity, mass,
 *   density, pressure, acceleration, density_rate and other shared fields;
 * - sluice/output_schedule.h: output at regular intervals of simulated time
 *   (gauges, writers), with its checkpoint;
 * - sluice/integrator_util.h: what every integrator binds (positions,
 *   velocities, rate pairs, stored copies) and the position update;
 * - sluice/kernel_sums.h: kernel sums shared by pair terms (the velocity
 *   gradient);
 * - sluice/phase_filter.h: the `phase` parameter of gauges in two-phase
 *   scenes;
 * - sluice/gauge_column.h: columns of sample points (per-gauge list
 *   parameters, the free surface of a kernel sum). */
#ifndef SLUICE_PLUGIN_UTIL_H
#define SLUICE_PLUGIN_UTIL_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define SLUICE_PI 3.14159265358979323846

#include "sluice/plugin.h"

/* Reads a scalar constant; reports an error when no plugin publishes it. */
static inline int sluice_util_constant(const sluice_api *api, sluice_host *host, const char *name,
                                       sluice_real *value)
{
    sluice_real v[3];
    if (api->fields->constant(host, name, v, 3) < 1) {
        api->messages->error(host, "needs the constant '%s', which no loaded plugin publishes", name);
        return SLUICE_ERROR;
    }
    *value = v[0];
    return SLUICE_OK;
}

/* The core constant `dimensions` (2 or 3), as a count; reports an error when
 * absent (never, from create on). */
static inline int sluice_util_dimensions(const sluice_api *api, sluice_host *host, uint32_t *dims)
{
    sluice_real value;
    if (sluice_util_constant(api, host, "dimensions", &value) != SLUICE_OK)
        return SLUICE_ERROR;
    *dims = (uint32_t)value;
    return SLUICE_OK;
}

/* What every equation of state publishes in create(): `speed_of_sound`
 * (m s^-1, the reference sound speed of time-step limits and artificial
 * viscosity) and `reference_pressure` (Pa, its pressure at the rest density,
 * which the hydrostatic start inverts). */
static inline int sluice_util_publish_eos(const sluice_api *api, sluice_host *host,
                                          sluice_real speed_of_sound,
                                          sluice_real reference_pressure)
{
    if (api->fields->publish_constant(host, "speed_of_sound", &speed_of_sound, 1, "m s^-1") != SLUICE_OK)
        return SLUICE_ERROR;
    return api->fields->publish_constant(host, "reference_pressure", &reference_pressure, 1, "Pa");
}

/* Resolves several fields at once: names[i] -> fields[i]. */
static inline int sluice_util_fields(const sluice_api *api, sluice_host *host,
                                     const char *const *names, sluice_field *fields, int count)
{
    for (int i = 0; i < count; i++)
        if (api->fields->field(host, names[i], &fields[i]) != SLUICE_OK)
            return SLUICE_ERROR;
    return SLUICE_OK;
}

/* A field handle to look up by name in bind():
 *
 *     const sluice_field_binding fields[] = {
 *         {"density", &s->density}, {"pressure", &s->pressure}};
 *     return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
 */
typedef struct sluice_field_binding {
    const char *name;
    sluice_field *field;
} sluice_field_binding;

/* Resolves every binding (api->fields->field, which reports an unknown name). */
static inline int sluice_util_bind(const sluice_api *api, sluice_host *host,
                                   const sluice_field_binding *bindings, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (api->fields->field(host, bindings[i].name, bindings[i].field) != SLUICE_OK)
            return SLUICE_ERROR;
    return SLUICE_OK;
}

/* Looks up a field that may legitimately be absent (no error when it is):
 * returns 1 and fills *out when some loaded plugin declares it, else 0. */
static inline int sluice_util_optional_field(const sluice_api *api, sluice_host *host,
                                             const char *name, sluice_field *out)
{
    uint32_t count = api->fields->field_count(host);
    for (uint32_t f = 0; f < count; f++) {
        sluice_field_spec spec;
        sluice_field field;
        if (api->fields->field_info(host, f, &spec, &field) == SLUICE_OK && spec.name &&
            strcmp(spec.name, name) == 0) {
            *out = field;
            return 1;
        }
    }
    return 0;
}

/* The two_phase plugin's field `phase` (uint8, one component: 0 water, 1
 * air) for a term restricted to one phase (`phases: same`): SLUICE_OK and
 * *out when it is loaded, else an error naming the term's parameter. */
static inline int sluice_util_phase_field(const sluice_api *api, sluice_host *host,
                                          sluice_field *out)
{
    if (!sluice_util_optional_field(api, host, "phase", out)) {
        api->messages->error(host, "phases: same needs the field 'phase' of the two_phase plugin; load "
                         "two_phase or use phases: all");
        return SLUICE_ERROR;
    }
    if (out->type != SLUICE_TYPE_UINT8 || out->components != 1) {
        api->messages->error(host, "the field 'phase' must be uint8 with one component");
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

/* Allocates a zeroed state struct; reports OOM. */
static inline void *sluice_util_state(const sluice_api *api, sluice_host *host, size_t size)
{
    void *p = calloc(1, size);
    if (!p)
        api->messages->error(host, "out of memory");
    return p;
}

/* Largest of non-negative values in a form the compiler vectorises: IEEE
 * doubles >= 0 order exactly like their bit patterns read as integers (and a
 * NaN's pattern is above infinity, so NaN propagates). Floating-point max
 * reductions (a > b ? a : b, fmax) do not vectorise without -ffinite-math. */
_Static_assert(sizeof(sluice_real) == sizeof(int64_t), "sluice_util_bits assumes 8-byte reals");
static inline int64_t sluice_util_bits(sluice_real non_negative)
{
    int64_t bits;
    memcpy(&bits, &non_negative, sizeof bits);
    return bits;
}
static inline sluice_real sluice_util_from_bits(int64_t bits)
{
    sluice_real value;
    memcpy(&value, &bits, sizeof value);
    return value;
}

/* |S|^2 = 2 S:S of particle i, S = (G + G^T)/2 the strain rate of the
 * field velocity_gradient (G[a * dims + b] the column of dv_a/dx_b):
 * sum_a 2 G_aa^2 + sum_{a<b} (G_ab + G_ba)^2. The eddy-viscosity models'
 * |S| is its square root. */
static inline sluice_real sluice_util_strain_rate_squared(const sluice_real *const *G,
                                                          sluice_index i, uint32_t dims)
{
    sluice_real two_ss = 0;
    for (uint32_t a = 0; a < dims; a++) {
        const sluice_real gaa = G[a * dims + a][i];
        two_ss += 2 * gaa * gaa;
        for (uint32_t c = a + 1; c < dims; c++) {
            const sluice_real sum = G[a * dims + c][i] + G[c * dims + a][i];
            two_ss += sum * sum;
        }
    }
    return two_ss;
}

/* 1.5: named scalars of a component's state in a checkpoint, from its
 * save_state / load_state callbacks (api->state->state_write / state_read). */
static inline int sluice_util_save_double(const sluice_api *api, sluice_host *host,
                                          const char *name, double value)
{
    return api->state->state_write(host, name, SLUICE_STATE_DOUBLE, 1, &value);
}

static inline int sluice_util_load_double(const sluice_api *api, sluice_host *host,
                                          const char *name, double *value)
{
    return api->state->state_read(host, name, SLUICE_STATE_DOUBLE, 1, value);
}

static inline int sluice_util_save_int(const sluice_api *api, sluice_host *host, const char *name,
                                       int64_t value)
{
    return api->state->state_write(host, name, SLUICE_STATE_INT64, 1, &value);
}

static inline int sluice_util_load_int(const sluice_api *api, sluice_host *host, const char *name,
                                       int64_t *value)
{
    return api->state->state_read(host, name, SLUICE_STATE_INT64, 1, value);
}

/* A table column's unit and description (api->output->table_column). */
typedef struct sluice_column_doc {
    const char *unit, *description;
} sluice_column_doc;

/* Describes columns first .. first + count - 1 of a table, none at a
 * position (ABI 2.2). */
static inline int sluice_util_describe_columns(const sluice_api *api, sluice_table *table,
                                               uint32_t first, const sluice_column_doc *columns,
                                               uint32_t count)
{
    for (uint32_t k = 0; k < count; k++)
        if (api->output->table_column(table, first + k, columns[k].unit, columns[k].description,
                                      NULL) != SLUICE_OK)
            return SLUICE_ERROR;
    return SLUICE_OK;
}

/* The focused headers (each also includes this one). */
#include "sluice/field_specs.h"
#include "sluice/gauge_column.h"
#include "sluice/integrator_util.h"
#include "sluice/kernel_sums.h"
#include "sluice/output_schedule.h"
#include "sluice/phase_filter.h"

#endif
