/* sluice inspect: list the plugins on the search path, or describe one:
 * its roles, parameters (type, default, range, unit) and fields. */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "registry.h"
#include "schema.h"
#include "sim.h"

static const char *kind_names(uint32_t mask, char *buffer, size_t size)
{
    static const char *const names[SLUICE_KIND_COUNT] = {"fluid", "wall", "open"};
    size_t used = 0;
    buffer[0] = '\0';
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++)
        if (mask & SLUICE_KIND_MASK(k)) {
            int w = snprintf(buffer + used, size - used, "%s%s", used ? "+" : "", names[k]);
            if (w > 0 && (size_t)w < size - used)
                used += (size_t)w;
        }
    if (!used)
        snprintf(buffer, size, "none");
    return buffer;
}

/* "targets T, neighbours N", with the neighbours of the target kinds that
 * declare their own (neighbour_kinds_by_target) after it */
static const char *pairs_text(const sluice_component *c, char *buffer, size_t size)
{
    char targets[64], neighbours[64];
    int used = snprintf(buffer, size, "targets %s, neighbours %s",
                        kind_names(c->target_kinds, targets, sizeof targets),
                        kind_names(c->neighbour_kinds, neighbours, sizeof neighbours));
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT && used > 0 && (size_t)used < size; k++)
        if (c->neighbour_kinds_by_target[k] && (c->target_kinds & SLUICE_KIND_MASK(k))) {
            int w = snprintf(
                buffer + used, size - (size_t)used, " (of %s targets: %s)",
                kind_names(SLUICE_KIND_MASK(k), targets, sizeof targets),
                kind_names(c->neighbour_kinds_by_target[k], neighbours, sizeof neighbours));
            used = w > 0 ? used + w : used;
        }
    return buffer;
}

static const char *roles(const sluice_component *c, char *buffer, size_t size)
{
    size_t used = 0;
    buffer[0] = '\0';
    struct {
        int present;
        const char *name;
    } list[] = {
        {c->kernel != NULL, "kernel"},
        {c->particle != NULL, "particle term"},
        {c->pair != NULL && !(c->flags & SLUICE_COMPONENT_ON_DEMAND), "pair term"},
        {c->pair != NULL && (c->flags & SLUICE_COMPONENT_ON_DEMAND), "on-demand pair term"},
        {c->prepare != NULL, "prepare (every evaluation)"},
        {c->density_from_pressure != NULL, "equation of state"},
        {c->advance != NULL, "integrator"},
        {c->time_step_limit != NULL, "time-step limit"},
        {(c->flags & SLUICE_COMPONENT_WALL_SCHEME) != 0, "wall scheme"},
        {c->before_step != NULL, "before-step hook"},
        {c->after_step != NULL, "after-step hook"},
        {c->finish != NULL, "finish hook"},
        {c->save_state != NULL && c->load_state != NULL, "state in checkpoints"},
    };
    for (size_t i = 0; i < sizeof list / sizeof list[0]; i++)
        if (list[i].present) {
            int w = snprintf(buffer + used, size - used, "%s%s", used ? ", " : "", list[i].name);
            if (w > 0 && (size_t)w < size - used)
                used += (size_t)w;
        }
    return buffer;
}

static const char *access_names(uint32_t a, char *buffer, size_t size)
{
    snprintf(buffer, size, "%s%s%s%s", (a & SLUICE_READ) ? "read, " : "",
             (a & SLUICE_READ_NEIGHBOUR) ? "read at neighbours, " : "",
             (a & SLUICE_WRITE) ? "write, " : "", (a & SLUICE_ACCUMULATE) ? "accumulate, " : "");
    size_t n = strlen(buffer);
    if (n >= 2)
        buffer[n - 2] = '\0';
    else
        snprintf(buffer, size, "declares");
    return buffer;
}

static const char *type_label(sluice_type t)
{
    switch (t) {
    case SLUICE_TYPE_REAL: return "real";
    case SLUICE_TYPE_INT32: return "int32";
    case SLUICE_TYPE_UINT8: return "uint8";
    case SLUICE_TYPE_ID: return "id";
    }
    return "?";
}

/* Text inside a Markdown table cell: '|' must be escaped. */
static void md(FILE *out, const char *text)
{
    for (const char *c = text ? text : ""; *c; c++) {
        if (*c == '|')
            fputc('\\', out);
        fputc(*c, out);
    }
}

static void describe(FILE *out, const sluice_registry *registry, const sluice_component_entry *e,
                     int markdown)
{
    const sluice_component *c = e->component;
    const sluice_library_entry *lib = &registry->libraries[e->library];
    char buf[512], pairs[256];
    if (markdown) {
        fprintf(out, "### %s\n\n%s\n\n", c->name, c->summary ? c->summary : "");
        fprintf(out, "- library: `%s` %s\n", lib->library->name, lib->library->version);
        fprintf(out, "- roles: %s\n", roles(c, buf, sizeof buf));
        fprintf(out, "- dimensions: %s\n",
                (c->dimensions & SLUICE_DIMS_ALL) == SLUICE_DIMS_ALL
                    ? "2D, 3D"
                    : (c->dimensions & SLUICE_DIMS_2) ? "2D" : "3D");
        if (c->pair)
            fprintf(out, "- pairs: %s\n", pairs_text(c, pairs, sizeof pairs));
        if (c->reference)
            fprintf(out, "- reference: %s\n", c->reference);
        if (c->param_count) {
            fprintf(out, "\n| parameter | type | default | unit | description |\n|---|---|---|---|---|\n");
            for (uint32_t i = 0; i < c->param_count; i++) {
                const sluice_param_spec *p = &c->params[i];
                fprintf(out, "| `%s` | ", p->name);
                md(out, sluice_schema_describe(p, buf, sizeof buf));
                fprintf(out, " | ");
                md(out, p->default_value ? p->default_value
                                         : (p->flags & SLUICE_PARAM_OPTIONAL) ? "(optional)"
                                                                             : "(required)");
                fprintf(out, " | ");
                md(out, p->unit);
                fprintf(out, " | ");
                md(out, p->doc);
                fprintf(out, " |\n");
            }
        }
        if (c->field_count) {
            fprintf(out, "\n| field | type | units | access | description |\n|---|---|---|---|---|\n");
            for (uint32_t i = 0; i < c->field_count; i++) {
                const sluice_field_spec *f = &c->fields[i];
                char comps[16];
                if (f->components == SLUICE_COMPONENTS_DIM)
                    snprintf(comps, sizeof comps, "d");
                else
                    snprintf(comps, sizeof comps, "%u", f->components);
                fprintf(out, "| `%s` | %s[%s] | ", f->name, type_label(f->type), comps);
                md(out, f->units);
                fprintf(out, " | %s%s%s | ", access_names(f->access, buf, sizeof buf),
                        f->rate_of ? ", rate of " : "", f->rate_of ? f->rate_of : "");
                md(out, f->doc);
                fprintf(out, " |\n");
            }
        }
        fprintf(out, "\n");
        return;
    }
    fprintf(out, "%s: %s\n", c->name, c->summary ? c->summary : "");
    fprintf(out, "  library     %s %s (%s)\n", lib->library->name, lib->library->version, lib->path);
    fprintf(out, "  roles       %s\n", roles(c, buf, sizeof buf));
    fprintf(out, "  dimensions  %s\n",
            (c->dimensions & SLUICE_DIMS_ALL) == SLUICE_DIMS_ALL ? "2D, 3D"
            : (c->dimensions & SLUICE_DIMS_2)                  ? "2D"
                                                                : "3D");
    if (c->pair)
        fprintf(out, "  pairs       %s\n", pairs_text(c, pairs, sizeof pairs));
    if (c->reference)
        fprintf(out, "  reference   %s\n", c->reference);
    if (c->param_count) {
        fprintf(out, "  parameters:\n");
        for (uint32_t i = 0; i < c->param_count; i++) {
            const sluice_param_spec *p = &c->params[i];
            fprintf(out, "    %-24s %s; default %s\n", p->name,
                    sluice_schema_describe(p, buf, sizeof buf),
                    p->default_value ? p->default_value
                                     : (p->flags & SLUICE_PARAM_OPTIONAL) ? "none (optional)"
                                                                         : "none (required)");
            if (p->doc)
                fprintf(out, "    %-24s %s\n", "", p->doc);
        }
    }
    if (c->field_count) {
        fprintf(out, "  fields:\n");
        for (uint32_t i = 0; i < c->field_count; i++) {
            const sluice_field_spec *f = &c->fields[i];
            char comps[16];
            if (f->components == SLUICE_COMPONENTS_DIM)
                snprintf(comps, sizeof comps, "d");
            else
                snprintf(comps, sizeof comps, "%u", f->components);
            fprintf(out, "    %-24s %s[%s] %s, %s%s%s\n", f->name, type_label(f->type), comps,
                    f->units && *f->units ? f->units : "1", access_names(f->access, buf, sizeof buf),
                    f->rate_of ? ", rate of " : "", f->rate_of ? f->rate_of : "");
        }
    }
}

int sluice_inspect(FILE *out, const char *component, int markdown)
{
    char **dirs = NULL;
    size_t count = 0;
    sluice_registry registry;
    if (sluice_registry_default_path(&dirs, &count, NULL, 0) != 0 ||
        sluice_registry_open(&registry, dirs, count) != 0) {
        fprintf(stderr, "sluice: error: out of memory scanning the plugin path\n");
        return 1;
    }
    int status = 0;
    if (component) {
        const sluice_component_entry *e = sluice_registry_find(&registry, component);
        if (!e) {
            const char **names = calloc(registry.component_count + 1, sizeof *names);
            for (size_t i = 0; names && i < registry.component_count; i++)
                names[i] = registry.components[i].component->name;
            const char *close =
                names ? sluice_closest(component, names, registry.component_count) : NULL;
            char refused[2048];
            sluice_registry_explain_missing(&registry, component, refused, sizeof refused);
            if (refused[0])
                fprintf(stderr, "sluice: error: plugin '%s' could not be loaded: %s\n", component,
                        refused);
            else if (close)
                fprintf(stderr, "sluice: error: no plugin named '%s'; did you mean '%s'?\n",
                        component, close);
            else
                fprintf(stderr, "sluice: error: no plugin named '%s' on the plugin path\n",
                        component);
            free(names);
            status = 1;
        } else {
            describe(out, &registry, e, markdown);
        }
    } else {
        if (markdown) {
            for (size_t i = 0; i < registry.component_count; i++)
                if (!registry.components[i].shadowed)
                    describe(out, &registry, &registry.components[i], 1);
        } else {
            fprintf(out, "plugin search path:\n");
            for (size_t d = 0; d < registry.directory_count; d++)
                fprintf(out, "  %s\n", registry.directories[d]);
            fprintf(out, "\n%-24s %-16s %-8s %s\n", "component", "library", "version", "summary");
            for (size_t i = 0; i < registry.component_count; i++) {
                const sluice_component_entry *e = &registry.components[i];
                const sluice_library_entry *lib = &registry.libraries[e->library];
                fprintf(out, "%-24s %-16s %-8s %s%s\n", e->component->name, lib->library->name,
                        lib->library->version, e->component->summary ? e->component->summary : "",
                        e->shadowed ? " (shadowed by an earlier one)" : "");
            }
            int refused = 0;
            for (size_t i = 0; i < registry.library_count; i++)
                if (registry.libraries[i].refusal) {
                    if (!refused++)
                        fprintf(out, "\nrefused:\n");
                    fprintf(out, "  %s %s\n", registry.libraries[i].path,
                            registry.libraries[i].refusal);
                }
        }
    }
    sluice_registry_close(&registry);
    return status;
}
