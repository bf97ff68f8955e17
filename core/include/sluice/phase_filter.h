/* The phase filter of the gauges in two-phase scenes: `phase: all` (every
 * fluid particle, the default), `water` or `air` (that phase only, from the
 * field `phase` of the two_phase plugin: 0 water, 1 air, which the scene must
 * then load). A gauge adds SLUICE_PHASE_PARAM to its parameters, calls
 * sluice_phase_declare in create() and sluice_phase_bind in bind(), and skips
 * a neighbour j when sluice_phase_skips(phase, wanted, j). Header-only. */
#ifndef SLUICE_PHASE_FILTER_H
#define SLUICE_PHASE_FILTER_H

#include "sluice/field_specs.h"
#include "sluice/plugin_util.h"

enum { SLUICE_PHASE_ALL = 0, SLUICE_PHASE_WATER = 1, SLUICE_PHASE_AIR = 2 };

#define SLUICE_PHASE_PARAM(config_type, member)                                                  \
    {"phase", SLUICE_PARAM_ENUM, offsetof(config_type, member), "all", 0, 0, 0, NULL,            \
     "all: every fluid particle; water or air: that phase only (field 'phase' of the two_phase " \
     "plugin, which must then be loaded)",                                                       \
     "all|water|air", 0}

/* Declares the read of `phase` when the filter needs it. */
static inline int sluice_phase_declare(const sluice_api *api, sluice_host *host, int filter)
{
    static const sluice_field_spec phase =
        SLUICE_SPEC_PHASE_DOC(SLUICE_READ, 0, "phase of a fluid particle: 0 water, 1 air");
    return filter == SLUICE_PHASE_ALL ? SLUICE_OK : api->fields->declare_field(host, &phase);
}

/* Binds the field (column -1 without a filter). */
static inline int sluice_phase_bind(const sluice_api *api, sluice_host *host, int filter,
                                    sluice_field *out)
{
    out->column = -1;
    return filter == SLUICE_PHASE_ALL ? SLUICE_OK : api->fields->field(host, "phase", out);
}

/* The phase column, or NULL without a filter. */
static inline const uint8_t *sluice_phase_column(const sluice_view *v, sluice_field f)
{
    return f.column >= 0 ? (const uint8_t *)v->columns[f.column] : NULL;
}

/* The phase value a filter keeps (0 water, 1 air). */
static inline uint8_t sluice_phase_wanted(int filter)
{
    return filter == SLUICE_PHASE_AIR ? 1 : 0;
}

/* 1 when particle j is of the other phase. */
static inline int sluice_phase_skips(const uint8_t *phase, uint8_t wanted, sluice_index j)
{
    return phase && phase[j] != wanted;
}

#endif
