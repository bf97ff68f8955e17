/* The field and constant registry: declarations merged over components
 * (one writer, any accumulators, conflicts reported with both names),
 * handles by name, published constants. */
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

uint8_t sluice_sim_type_size(sluice_type t)
{
    switch (t) {
    case SLUICE_TYPE_REAL: return sizeof(sluice_real);
    case SLUICE_TYPE_INT32: return 4;
    case SLUICE_TYPE_UINT8: return 1;
    case SLUICE_TYPE_ID: return sizeof(sluice_id);
    }
    return 8;
}

void sluice_sim_report(sluice_sim *sim, uint32_t instance, const char *format, ...)
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
int sluice_sim_declare(sluice_sim *sim, uint32_t instance, const sluice_field_spec *spec)
{
    const char *who = sluice_sim_instance_name(sim, instance);
    if (!spec->name || !*spec->name) {
        sluice_sim_report(sim, instance, "plugin '%s' declares a field without a name", who);
        return -1;
    }
    if (spec->type < SLUICE_TYPE_REAL || spec->type > SLUICE_TYPE_ID) {
        sluice_sim_report(sim, instance, "plugin '%s' declares field '%s' with an unknown type", who,
               spec->name);
        return -1;
    }
    if (sim->phase > SLUICE_PHASE_CREATE) {
        /* the integrated fields are fixed when the integrator is created
         * (after every other component), the schedule and the particle store
         * when bind() ends: a field declared later would be accepted and
         * silently never integrated, scheduled or stored */
        sluice_sim_report(sim, instance,
                          "plugin '%s' declares field '%s' after create(); declare fields "
                          "statically (the component's `fields`) or in create(), where every "
                          "component's static fields can be looked up (field_info)",
                          who, spec->name);
        return -1;
    }
    uint32_t components =
        spec->components == SLUICE_COMPONENTS_DIM ? sim->scene.dimensions : spec->components;
    if (components > 16) {
        sluice_sim_report(sim, instance, "plugin '%s' declares field '%s' with %u components (at most 16)",
               who, spec->name, components);
        return -1;
    }
    sluice_field_entry *f = sluice_sim_find_field(sim, spec->name);
    if (f) {
        const char *first = f->declarer_count ? sluice_sim_instance_name(sim, f->declarers[0].instance) : "?";
        const char *units = spec->units ? spec->units : "";
        if (f->type != spec->type || f->components != components || strcmp(f->units, units) != 0) {
            sluice_sim_report(sim, instance,
                   "field '%s' is declared by '%s' as %s[%u] in %s and by '%s' as %s[%u] in %s; "
                   "these plugins cannot be combined",
                   spec->name, first, type_name(f->type), f->components, f->units[0] ? f->units : "1",
                   who, type_name(spec->type), components, units[0] ? units : "1");
            return -1;
        }
        if (spec->rate_of) {
            if (f->rate_of && strcmp(f->rate_of, spec->rate_of) != 0) {
                sluice_sim_report(sim, instance,
                       "field '%s' is declared the rate of '%s' by '%s' and of '%s' by '%s'",
                       spec->name, f->rate_of, first, spec->rate_of, who);
                return -1;
            }
            if (!f->rate_of && !(f->rate_of = sluice_sim_copy_string(spec->rate_of)))
                return -1;
            f->kinds |= spec->kinds;
        }
        f->flags |= spec->flags;
        if (!f->doc[0] && spec->doc) {
            char *doc = sluice_sim_copy_string(spec->doc);
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
        f->name = sluice_sim_copy_string(spec->name);
        f->units = sluice_sim_copy_string(spec->units ? spec->units : "");
        f->doc = sluice_sim_copy_string(spec->doc ? spec->doc : "");
        f->rate_of = spec->rate_of ? sluice_sim_copy_string(spec->rate_of) : NULL;
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

int sluice_sim_handle_of(const sluice_sim *sim, const char *name, sluice_field *out)
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

/* ------------------------------------------------------------- constants -- */

int sluice_sim_publish(sluice_sim *sim, uint32_t instance, const char *name, const sluice_real *values,
                   uint32_t count, const char *unit)
{
    if (count == 0 || count > 3) {
        sluice_sim_report(sim, instance, "plugin '%s' publishes constant '%s' with %u values (1 to 3)",
               sluice_sim_instance_name(sim, instance), name, count);
        return -1;
    }
    for (uint32_t i = 0; i < sim->constant_count; i++)
        if (strcmp(sim->constants[i].name, name) == 0) {
            sluice_sim_report(sim, instance,
                   "constant '%s' is published by both '%s' and '%s'; load only one of them", name,
                   sluice_sim_instance_name(sim, sim->constants[i].publisher), sluice_sim_instance_name(sim, instance));
            return -1;
        }
    sluice_constant_entry *grown =
        realloc(sim->constants, (sim->constant_count + 1) * sizeof *grown);
    if (!grown)
        return -1;
    sim->constants = grown;
    sluice_constant_entry *c = &grown[sim->constant_count];
    memset(c, 0, sizeof *c);
    c->name = sluice_sim_copy_string(name);
    c->unit = sluice_sim_copy_string(unit ? unit : "1");
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

uint32_t sluice_sim_get_constant(const sluice_sim *sim, const char *name, sluice_real *values,
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
