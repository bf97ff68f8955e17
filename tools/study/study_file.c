/* Reading and checking a study file (docs/studies.md). Every problem is one
 * message `file:line:column: error: ...`; nothing runs until the whole file
 * (and every run's scene, study_check_runs) is valid. */
#define _GNU_SOURCE
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "study.h"

const char *const study_reduce_names[REDUCE_COUNT] = {
    "mean", "max", "min", "first", "last", "std", "rms", "integral", "time_of_max", "time_of_min"};

char *study_strdup(const char *text)
{
    char *copy = strdup(text ? text : "");
    if (!copy) {
        fprintf(stderr, "sluice-study: error: out of memory\n");
        exit(4);
    }
    return copy;
}

char *study_printf(const char *format, ...)
{
    va_list ap;
    va_start(ap, format);
    char *text = NULL;
    int n = vasprintf(&text, format, ap);
    va_end(ap);
    if (n < 0) {
        fprintf(stderr, "sluice-study: error: out of memory\n");
        exit(4);
    }
    return text;
}

int study_mkdirs(const char *path)
{
    char *copy = study_strdup(path);
    for (char *p = copy + 1; *p; p++)
        if (*p == '/') {
            *p = '\0';
            if (mkdir(copy, 0777) != 0 && errno != EEXIST) {
                free(copy);
                return -1;
            }
            *p = '/';
        }
    int rc = mkdir(copy, 0777) != 0 && errno != EEXIST ? -1 : 0;
    free(copy);
    return rc;
}

void study_error(study *s, const sluice_node *at, const char *format, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    int line = at && at->line > 0 ? at->line : 1, column = at && at->line > 0 ? at->column : 1;
    sluice_diag_add(s->diag, SLUICE_SEVERITY_ERROR, at && at->file ? at->file : s->path, line,
                    column, "%s", text);
}

/* Unknown keys of a mapping, with the closest known one. */
static int check_keys(study *s, const sluice_node *map, const char *where, const char *const *known,
                      size_t count)
{
    int errors = 0;
    for (size_t i = 0; i < map->count; i++) {
        const char *key = map->keys[i]->value;
        size_t k = 0;
        while (k < count && strcmp(known[k], key) != 0)
            k++;
        if (k < count)
            continue;
        const char *close = sluice_closest(key, known, count);
        char list[512] = "";
        for (size_t j = 0, used = 0; j < count && used < sizeof list; j++)
            used +=
                (size_t)snprintf(list + used, sizeof list - used, "%s%s", j ? ", " : "", known[j]);
        if (close)
            study_error(s, map->keys[i], "unknown key '%s' in %s; did you mean '%s'?", key, where,
                        close);
        else
            study_error(s, map->keys[i], "unknown key '%s' in %s (valid keys: %s)", key, where,
                        list);
        errors++;
    }
    return errors;
}

static int is_string(const sluice_node *n)
{
    return n && n->kind == SLUICE_NODE_SCALAR && *n->value;
}

static int number_of(const sluice_node *n, double *out)
{
    if (!n || n->kind != SLUICE_NODE_SCALAR || !n->plain || !*n->value)
        return -1;
    char *end = NULL;
    errno = 0;
    double v = strtod(n->value, &end);
    if (*end || errno || !isfinite(v))
        return -1;
    *out = v;
    return 0;
}

/* A YAML value as the text `--set PATH=VALUE` parses back to it (flow style). */
static void flow_text(const sluice_node *n, FILE *f)
{
    if (n->kind == SLUICE_NODE_SCALAR) {
        if (n->plain) {
            fputs(n->value, f);
            return;
        }
        fputc('"', f);
        for (const char *c = n->value; *c; c++) {
            if (*c == '"' || *c == '\\')
                fputc('\\', f);
            fputc(*c, f);
        }
        fputc('"', f);
        return;
    }
    fputc(n->kind == SLUICE_NODE_SEQUENCE ? '[' : '{', f);
    for (size_t i = 0; i < n->count; i++) {
        if (i)
            fputs(", ", f);
        if (n->kind == SLUICE_NODE_MAPPING) {
            flow_text(n->keys[i], f);
            fputs(": ", f);
        }
        flow_text(n->items[i], f);
    }
    fputc(n->kind == SLUICE_NODE_SEQUENCE ? ']' : '}', f);
}

static char *value_text(const sluice_node *n)
{
    char *text = NULL;
    size_t length = 0;
    FILE *f = open_memstream(&text, &length);
    if (!f) {
        fprintf(stderr, "sluice-study: error: out of memory\n");
        exit(4);
    }
    flow_text(n, f);
    fclose(f);
    return text;
}

static void add_edit(study_edits *e, study_edit_kind kind, char *text, const sluice_node *at)
{
    study_edit *items = realloc(e->items, (e->count + 1) * sizeof *items);
    if (!items) {
        fprintf(stderr, "sluice-study: error: out of memory\n");
        exit(4);
    }
    e->items = items;
    e->items[e->count++] = (study_edit){kind, text, at};
}

/* The edits of a mapping with the optional keys remove, swap, set, variant
 * (the study's top level, or an axis value). */
static int read_edits(study *s, const sluice_node *map, const char *where, study_edits *e)
{
    int errors = 0;
    const sluice_node *remove = sluice_node_get(map, "remove");
    if (remove && remove->kind != SLUICE_NODE_SEQUENCE) {
        study_error(s, remove, "%s.remove must be a list of dotted paths, e.g. [plugins.xsph]",
                    where);
        errors++;
    }
    for (size_t i = 0; remove && remove->kind == SLUICE_NODE_SEQUENCE && i < remove->count; i++) {
        if (!is_string(remove->items[i])) {
            study_error(s, remove->items[i], "each entry of %s.remove must be a dotted path",
                        where);
            errors++;
        } else
            add_edit(e, EDIT_REMOVE, study_strdup(remove->items[i]->value), remove->items[i]);
    }
    const sluice_node *swap = sluice_node_get(map, "swap");
    if (swap && swap->kind != SLUICE_NODE_MAPPING) {
        study_error(s, swap,
                    "%s.swap must be a mapping from plugins the scene loads to the plugins that "
                    "replace them, e.g. {dbc: mdbc}",
                    where);
        errors++;
    }
    for (size_t i = 0; swap && swap->kind == SLUICE_NODE_MAPPING && i < swap->count; i++) {
        if (!is_string(swap->items[i])) {
            study_error(s, swap->items[i], "%s.swap.%s must be the name of a plugin", where,
                        swap->keys[i]->value);
            errors++;
        } else
            add_edit(e, EDIT_SWAP,
                     study_printf("%s=%s", swap->keys[i]->value, swap->items[i]->value),
                     swap->items[i]);
    }
    const sluice_node *set = sluice_node_get(map, "set");
    if (set && set->kind != SLUICE_NODE_MAPPING) {
        study_error(s, set,
                    "%s.set must be a mapping from dotted paths to values, e.g. "
                    "{time.end: 0.5}",
                    where);
        errors++;
    }
    for (size_t i = 0; set && set->kind == SLUICE_NODE_MAPPING && i < set->count; i++) {
        char *value = value_text(set->items[i]);
        add_edit(e, EDIT_SET, study_printf("%s=%s", set->keys[i]->value, value), set->keys[i]);
        free(value);
    }
    const sluice_node *variant = sluice_node_get(map, "variant");
    if (variant && !is_string(variant)) {
        study_error(s, variant, "%s.variant must be the name of one of the scene's variants",
                    where);
        errors++;
    } else if (variant) {
        e->variant = variant->value;
        e->variant_at = variant;
    }
    return errors;
}

static const char *const edit_keys[] = {"description", "remove",   "swap",    "set",
                                        "variant",     "scene",    "external", "requires"};

/* The placeholders an external command may hold. */
static const char *const external_placeholders[] = {"{run_dir}", "{spacing}", "{threads}",
                                                    "{study_dir}"};

/* An axis value's `external: COMMAND` (a run by another program, a peer
 * code: a shell command that writes the run directory {run_dir}) and its
 * optional `requires: COMMAND` (a shell command that succeeds where that
 * program is installed; where it fails, the value's runs are skipped with a
 * note). An external value takes no scene edits of its own. */
static int read_value_external(study *s, const sluice_node *map, const char *where,
                               study_edits *e)
{
    const sluice_node *external = sluice_node_get(map, "external");
    const sluice_node *requires = sluice_node_get(map, "requires");
    if (!external) {
        if (requires) {
            study_error(s, requires, "%s.requires belongs to an external value (give 'external')",
                        where);
            return 1;
        }
        return 0;
    }
    int errors = 0;
    if (!is_string(external) || !*external->value) {
        study_error(s, external,
                    "%s.external must be a shell command that writes the run directory "
                    "{run_dir}",
                    where);
        return 1;
    }
    if (!strstr(external->value, "{run_dir}")) {
        study_error(s, external,
                    "%s.external must name the run directory it writes as {run_dir}", where);
        errors++;
    }
    for (const char *p = strchr(external->value, '{'); p; p = strchr(p + 1, '{')) {
        int known = 0;
        for (size_t k = 0; k < sizeof external_placeholders / sizeof *external_placeholders; k++)
            known |= strncmp(p, external_placeholders[k], strlen(external_placeholders[k])) == 0;
        if (!known) {
            study_error(s, external,
                        "%s.external: unknown placeholder '%.*s' (known: {run_dir}, "
                        "{spacing}, {threads}, {study_dir})",
                        where, (int)(strchr(p, '}') ? strchr(p, '}') - p + 1 : 1), p);
            errors++;
        }
    }
    static const char *const scene_keys[] = {"remove", "swap", "set", "variant", "scene"};
    for (size_t k = 0; k < 5; k++)
        if (sluice_node_get(map, scene_keys[k])) {
            study_error(s, sluice_node_get(map, scene_keys[k]),
                        "%s: an external value runs another program and takes no scene edits "
                        "('%s')",
                        where, scene_keys[k]);
            errors++;
        }
    if (requires && (!is_string(requires) || !*requires->value)) {
        study_error(s, requires,
                    "%s.requires must be a shell command that succeeds where the program is "
                    "installed",
                    where);
        errors++;
    }
    e->external = study_strdup(external->value);
    e->external_at = external;
    if (requires && is_string(requires)) {
        e->requires = study_strdup(requires->value);
        e->requires_at = requires;
    }
    return errors;
}

/* An axis value's `scene`: another base scene for its runs (a model kept as
 * a scene file of its own), relative to the study file. */
static int read_value_scene(study *s, const sluice_node *map, const char *where, study_edits *e)
{
    const sluice_node *scene = sluice_node_get(map, "scene");
    if (!scene)
        return 0;
    if (!is_string(scene)) {
        study_error(s, scene, "%s.scene must be the path of a scene file", where);
        return 1;
    }
    e->scene = scene->value[0] == '/' ? study_strdup(scene->value)
                                      : study_printf("%s/%s", s->directory, scene->value);
    e->scene_at = scene;
    struct stat st;
    errno = 0;
    if (stat(e->scene, &st) != 0 || !S_ISREG(st.st_mode)) {
        study_error(s, scene, "the scene '%s' cannot be read (%s)", scene->value,
                    errno ? strerror(errno) : "not a file");
        return 1;
    }
    return 0;
}

/* An axis of values each with its edits: {label: {swap:.., set:..}, ...}. */
static int read_edit_values(study *s, study_axis *a, const sluice_node *values)
{
    int errors = 0;
    if (values->kind != SLUICE_NODE_MAPPING || values->count == 0) {
        study_error(s, values,
                    "axis '%s': values must be a mapping from labels to scene edits, e.g. "
                    "{dbc: {}, mdbc: {swap: {dbc: mdbc}}} (or give 'parameter' and a list)",
                    a->name);
        return 1;
    }
    a->values = calloc(values->count, sizeof *a->values);
    if (!a->values)
        return 1;
    for (size_t i = 0; i < values->count; i++) {
        study_value *v = &a->values[a->count++];
        v->label = study_strdup(values->keys[i]->value);
        v->number = NAN;
        v->at = values->keys[i];
        const sluice_node *edits = values->items[i];
        if (edits->kind == SLUICE_NODE_SCALAR && edits->plain && !*edits->value)
            continue; /* `label:` with nothing: the base scene */
        if (edits->kind != SLUICE_NODE_MAPPING) {
            study_error(s, edits,
                        "axis '%s', value '%s': a mapping with the optional keys description, "
                        "remove, swap, set, variant and scene (or external and requires)",
                        a->name, v->label);
            errors++;
            continue;
        }
        char *where = study_printf("axes.%s.values.%s", a->name, v->label);
        errors += check_keys(s, edits, where, edit_keys, 8);
        errors += read_value_external(s, edits, where, &v->edits);
        errors += read_value_scene(s, edits, where, &v->edits);
        errors += read_edits(s, edits, where, &v->edits);
        free(where);
    }
    return errors;
}

/* An axis of numbers or scalars: parameter, spacing or threads. */
static int read_list_values(study *s, study_axis *a, const sluice_node *list, const char *path)
{
    if (list->kind != SLUICE_NODE_SEQUENCE || list->count == 0) {
        study_error(s, list, "axis '%s': a non-empty list of values, e.g. [0.02, 0.01, 0.005]",
                    a->name);
        return 1;
    }
    a->values = calloc(list->count, sizeof *a->values);
    if (!a->values)
        return 1;
    int errors = 0;
    for (size_t i = 0; i < list->count; i++) {
        const sluice_node *item = list->items[i];
        study_value *v = &a->values[a->count++];
        v->number = NAN;
        v->at = item;
        v->label = item->kind == SLUICE_NODE_SCALAR ? study_strdup(item->value) : value_text(item);
        double number = NAN;
        if (a->kind == AXIS_SPACING && (number_of(item, &number) != 0 || !(number > 0))) {
            study_error(s, item, "axis '%s': a spacing is a positive number of metres, got '%s'",
                        a->name, v->label);
            errors++;
        } else if (a->kind == AXIS_THREADS && (number_of(item, &number) != 0 || number < 1 ||
                                               number > 4096 || number != floor(number))) {
            study_error(s, item,
                        "axis '%s': a thread count is a whole number from 1 to 4096, "
                        "got '%s'",
                        a->name, v->label);
            errors++;
        } else if (a->kind == AXIS_PARAMETER && a->convergence &&
                   (number_of(item, &number) != 0 || !(number > 0))) {
            study_error(s, item,
                        "axis '%s': the values of a convergence axis are positive numbers, "
                        "got '%s'",
                        a->name, v->label);
            errors++;
        }
        v->number = number;
        if (path) {
            char *value = value_text(item);
            add_edit(&v->edits, EDIT_SET, study_printf("%s=%s", path, value), item);
            free(value);
        }
    }
    return errors;
}

static int read_axis(study *s, const sluice_node *node, study_axis *a)
{
    static const char *const keys[] = {"name",    "values",  "parameter",
                                       "spacing", "threads", "convergence"};
    if (node->kind != SLUICE_NODE_MAPPING) {
        study_error(s, node,
                    "an axis is a mapping: name and one of values, parameter (with "
                    "values), spacing, threads");
        return 1;
    }
    int errors = check_keys(s, node, "an axis", keys, 6);
    const sluice_node *name = sluice_node_get(node, "name");
    a->at = node;
    if (!is_string(name)) {
        study_error(s, name ? name : node, "an axis needs a name (a column of the table)");
        return errors + 1;
    }
    a->name = study_strdup(name->value);
    const sluice_node *values = sluice_node_get(node, "values");
    const sluice_node *parameter = sluice_node_get(node, "parameter");
    const sluice_node *spacing = sluice_node_get(node, "spacing");
    const sluice_node *threads = sluice_node_get(node, "threads");
    int kinds = (values && !parameter) + !!parameter + !!spacing + !!threads;
    if (kinds != 1) {
        study_error(s, node,
                    "axis '%s' needs exactly one of: values (labels and their scene edits), "
                    "parameter with values (a list), spacing (a list), threads (a list)",
                    a->name);
        return errors + 1;
    }
    const sluice_node *convergence = sluice_node_get(node, "convergence");
    if (convergence && (!parameter || !is_string(convergence) ||
                        (strcmp(convergence->value, "true") && strcmp(convergence->value, "false")))) {
        study_error(s, convergence,
                    "axis '%s': convergence (true or false) marks a parameter axis of positive "
                    "numbers, such as time.max_step, as the axis of the observed orders",
                    a->name);
        return errors + 1;
    }
    if (spacing) {
        a->kind = AXIS_SPACING;
        a->convergence = 1;
        return errors + read_list_values(s, a, spacing, "particles.spacing");
    }
    if (threads) {
        a->kind = AXIS_THREADS;
        return errors + read_list_values(s, a, threads, NULL);
    }
    if (parameter) {
        a->kind = AXIS_PARAMETER;
        if (!is_string(parameter) || !values) {
            study_error(s, parameter,
                        "axis '%s': parameter is a dotted path of the scene, "
                        "with values a list, e.g. parameter: "
                        "plugins.tait.speed_of_sound, values: [20, 40]",
                        a->name);
            return errors + 1;
        }
        a->convergence = convergence && strcmp(convergence->value, "true") == 0;
        return errors + read_list_values(s, a, values, parameter->value);
    }
    a->kind = AXIS_EDITS;
    return errors + read_edit_values(s, a, values);
}

static int read_reduce(study *s, const sluice_node *node, study_measure *m)
{
    m->reduce = REDUCE_MEAN;
    if (!node)
        return 0;
    for (int r = 0; r < REDUCE_COUNT; r++)
        if (node->kind == SLUICE_NODE_SCALAR && strcmp(node->value, study_reduce_names[r]) == 0) {
            m->reduce = (study_reduce)r;
            return 0;
        }
    const char *close = node->kind == SLUICE_NODE_SCALAR
                            ? sluice_closest(node->value, study_reduce_names, REDUCE_COUNT)
                            : NULL;
    study_error(s, node,
                "measure '%s': reduce must be one of mean, max, min, first, last, std, rms, "
                "integral, time_of_max, time_of_min%s%s%s",
                m->name, close ? "; did you mean '" : "", close ? close : "", close ? "'?" : "");
    return 1;
}

/* The source of a measure: gauge (+ column), analysis (+ key) or run. */
static int read_source(study *s, const sluice_node *node, study_measure *m)
{
    const sluice_node *gauge = sluice_node_get(node, "gauge");
    const sluice_node *analysis = sluice_node_get(node, "analysis");
    const sluice_node *run = sluice_node_get(node, "run");
    const sluice_node *column = sluice_node_get(node, "column");
    const sluice_node *key = sluice_node_get(node, "key");
    if (!!gauge + !!analysis + !!run != 1) {
        study_error(s, node,
                    "measure '%s' needs exactly one source: gauge (a CSV file of the run, with "
                    "column), analysis (sluice-analyze arguments, with key) or run (a figure "
                    "of run.json)",
                    m->name);
        return 1;
    }
    if (gauge) {
        m->source = SOURCE_GAUGE;
        if (!is_string(gauge) || !is_string(column)) {
            study_error(s, is_string(gauge) ? node : gauge,
                        "measure '%s': gauge is a CSV file of the run directory (e.g. "
                        "wall_pressure.csv) and column one of its columns",
                        m->name);
            return 1;
        }
        m->file = study_strdup(gauge->value);
        m->column = study_strdup(column->value);
        return read_reduce(s, sluice_node_get(node, "reduce"), m);
    }
    if (run) {
        m->source = SOURCE_RUN;
        if (!is_string(run)) {
            study_error(s, run,
                        "measure '%s': run is a key of run.json, e.g. "
                        "particle_steps_per_second",
                        m->name);
            return 1;
        }
        m->key = study_strdup(run->value);
        return 0;
    }
    m->source = SOURCE_ANALYSIS;
    if (!is_string(analysis) || !is_string(key)) {
        study_error(s, is_string(analysis) ? node : analysis,
                    "measure '%s': analysis is the sluice-analyze command with its options "
                    "(the run directory is put after the command), e.g. \"conjugate --d1 0.02 "
                    "--v1 1.5 --x 1.0\", and key the figure it prints (d2_mean)",
                    m->name);
        return 1;
    }
    char *copy = study_strdup(analysis->value);
    for (char *save = NULL, *word = strtok_r(copy, " \t", &save); word;
         word = strtok_r(NULL, " \t", &save)) {
        char **more = realloc(m->arguments, (m->argument_count + 1) * sizeof *more);
        if (!more)
            exit(4);
        m->arguments = more;
        const char *mark = strstr(word, "{study_dir}");
        m->arguments[m->argument_count++] =
            mark ? study_printf("%.*s%s%s", (int)(mark - word), word, s->directory, mark + 11)
                 : study_strdup(word);
    }
    free(copy);
    m->key = study_strdup(key->value);
    return 0;
}

/* A measure's `scale`, and its reference: a number (`reference`), or
 * `reference_factor` (default 1) times another measure of the same run
 * (`reference_measure`, resolved in check_names). */
static int read_scale_and_reference(study *s, const sluice_node *node, study_measure *m)
{
    int errors = 0;
    m->scale = 1;
    const sluice_node *scale = sluice_node_get(node, "scale");
    if (scale && (number_of(scale, &m->scale) != 0 || m->scale == 0 || !isfinite(m->scale))) {
        study_error(s, scale,
                    "measure '%s': scale is a non-zero number the value is multiplied by "
                    "(e.g. 1 / (rho V^2 / 2) for a pressure coefficient)",
                    m->name);
        errors++;
    }
    const sluice_node *reference = sluice_node_get(node, "reference");
    const sluice_node *other = sluice_node_get(node, "reference_measure");
    const sluice_node *factor = sluice_node_get(node, "reference_factor");
    if (reference && other) {
        study_error(s, other, "measure '%s': give either reference or reference_measure",
                    m->name);
        return errors + 1;
    }
    if (reference) {
        m->has_reference = 1;
        if (number_of(reference, &m->reference) != 0) {
            study_error(s, reference,
                        "measure '%s': reference is a number (in the measure's "
                        "unit)",
                        m->name);
            errors++;
        }
    }
    m->reference_factor = 1;
    if (factor && !other) {
        study_error(s, factor, "measure '%s': reference_factor belongs to reference_measure",
                    m->name);
        errors++;
    } else if (factor && (number_of(factor, &m->reference_factor) != 0 ||
                          !isfinite(m->reference_factor) || m->reference_factor == 0)) {
        study_error(s, factor, "measure '%s': reference_factor is a non-zero number", m->name);
        errors++;
    }
    if (other) {
        if (!is_string(other)) {
            study_error(s, other, "measure '%s': reference_measure is the name of a measure",
                        m->name);
            return errors + 1;
        }
        m->has_reference = 1;
        m->reference_measure = study_strdup(other->value);
        m->reference_measure_at = other;
    }
    return errors;
}

/* A measure's target: within (the largest |error| against the reference,
 * a fraction, or in the measure's unit when the error is absolute), below
 * and above (bounds on the value itself); NAN where not given. */
static int read_target(study *s, const sluice_node *node, study_measure *m)
{
    static const char *const names[] = {"within", "below", "above"};
    double *slots[] = {&m->within, &m->below, &m->above};
    int errors = 0;
    for (int i = 0; i < 3; i++) {
        *slots[i] = NAN;
        const sluice_node *n = sluice_node_get(node, names[i]);
        if (!n)
            continue;
        if (number_of(n, slots[i]) != 0 || !isfinite(*slots[i])) {
            study_error(s, n, "measure '%s': %s is a number", m->name, names[i]);
            errors++;
        } else if (i == 0 && !(*slots[i] > 0)) {
            study_error(s, n,
                        "measure '%s': within is the largest error allowed, a positive number "
                        "(0.1: 10 %% of the reference)",
                        m->name);
            errors++;
        } else if (i == 0 && !m->has_reference) {
            study_error(s, n, "measure '%s': within needs a reference (or give below/above)",
                        m->name);
            errors++;
        }
        m->has_target = 1;
    }
    if (m->below <= m->above) {
        study_error(s, sluice_node_get(node, "below"),
                    "measure '%s': below %g is not above above %g: no value meets both",
                    m->name, m->below, m->above);
        errors++;
    }
    return errors;
}

static int read_measure(study *s, const sluice_node *node, study_measure *m)
{
    static const char *const keys[] = {"name",      "unit",      "gauge",
                                       "column",    "reduce",    "from",
                                       "to",        "last",      "analysis",
                                       "key",       "run",       "reference",
                                       "error",     "scale",     "reference_measure",
                                       "reference_factor", "within", "below", "above"};
    if (node->kind != SLUICE_NODE_MAPPING) {
        study_error(s, node, "a measure is a mapping: name and one source (gauge, analysis, run)");
        return 1;
    }
    int errors = check_keys(s, node, "a measure", keys, SLUICE_COUNT(keys));
    const sluice_node *name = sluice_node_get(node, "name");
    m->at = node;
    if (!is_string(name)) {
        study_error(s, name ? name : node, "a measure needs a name (a column of the table)");
        return errors + 1;
    }
    m->name = study_strdup(name->value);
    const sluice_node *unit = sluice_node_get(node, "unit");
    m->unit = study_strdup(is_string(unit) ? unit->value : "");
    errors += read_source(s, node, m);
    m->from = -INFINITY;
    m->to = INFINITY;
    const char *bounds[] = {"from", "to"};
    double *targets[] = {&m->from, &m->to};
    for (int b = 0; b < 2; b++) {
        const sluice_node *n = sluice_node_get(node, bounds[b]);
        if (n && number_of(n, targets[b]) != 0) {
            study_error(s, n, "measure '%s': %s is a time in seconds", m->name, bounds[b]);
            errors++;
        }
    }
    const sluice_node *last = sluice_node_get(node, "last");
    if (last && last->kind == SLUICE_NODE_SCALAR && *last->value &&
        last->value[strlen(last->value) - 1] == '%') {
        /* a share of the run: "50%" is its second half */
        char *end = NULL;
        double percent = strtod(last->value, &end);
        if (end == last->value + strlen(last->value) - 1 && percent > 0 && percent <= 100)
            m->last_share = percent / 100;
    } else if (last)
        number_of(last, &m->last);
    if (last && !(m->last > 0) && !(m->last_share > 0)) {
        study_error(s, last,
                    "measure '%s': last is a positive time in seconds (the run's last "
                    "seconds) or a share of the run such as 50%% (its second half)",
                    m->name);
        errors++;
    }
    if (last && (sluice_node_get(node, "from") || sluice_node_get(node, "to"))) {
        study_error(s, last, "measure '%s': give either last or from/to", m->name);
        errors++;
    }
    if (m->source == SOURCE_RUN &&
        (last || sluice_node_get(node, "from") || sluice_node_get(node, "to"))) {
        study_error(s, last ? last : node, "measure '%s': a figure of run.json has no time window",
                    m->name);
        errors++;
    }
    if (m->from >= m->to) {
        study_error(s, node, "measure '%s': the window from %g to %g s is empty", m->name, m->from,
                    m->to);
        errors++;
    }
    errors += read_scale_and_reference(s, node, m);
    const sluice_node *error = sluice_node_get(node, "error");
    m->absolute = m->has_reference && !m->reference_measure && m->reference == 0;
    if (error) {
        if (error->kind == SLUICE_NODE_SCALAR && strcmp(error->value, "absolute") == 0)
            m->absolute = 1;
        else if (error->kind == SLUICE_NODE_SCALAR && strcmp(error->value, "relative") == 0 &&
                 !(m->has_reference && m->reference == 0))
            m->absolute = 0;
        else {
            study_error(s, error,
                        "measure '%s': error is relative (value / reference - 1, "
                        "the default; not with a reference of 0) or absolute (value "
                        "- reference)",
                        m->name);
            errors++;
        }
        if (!m->has_reference) {
            study_error(s, error, "measure '%s': error needs a reference", m->name);
            errors++;
        }
    }
    return errors + read_target(s, node, m);
}

static int read_list(study *s, const char *key, int required)
{
    const sluice_node *list = sluice_node_get(s->root, key);
    if (!list) {
        if (!required)
            return 0;
        study_error(s, s->root, "a study needs '%s' (a list)", key);
        return 1;
    }
    if (list->kind != SLUICE_NODE_SEQUENCE || list->count == 0) {
        study_error(s, list, "'%s' must be a non-empty list", key);
        return 1;
    }
    int errors = 0;
    int axes = strcmp(key, "axes") == 0;
    if (axes) {
        s->axes = calloc(list->count, sizeof *s->axes);
        if (!s->axes)
            return 1;
    } else {
        s->measures = calloc(list->count, sizeof *s->measures);
        if (!s->measures)
            return 1;
    }
    for (size_t i = 0; i < list->count; i++)
        errors += axes ? read_axis(s, list->items[i], &s->axes[s->axis_count++])
                       : read_measure(s, list->items[i], &s->measures[s->measure_count++]);
    return errors;
}

/* Names that become file names and columns: unique, and [A-Za-z0-9._+] only
 * where they name a run directory. */
static int check_names(study *s)
{
    int errors = 0;
    int spacing_axes = 0, thread_axes = 0, convergence_axes = 0;
    const study_axis *second_convergence = NULL;
    for (size_t i = 0; i < s->axis_count; i++) {
        study_axis *a = &s->axes[i];
        if (!a->name)
            continue;
        if (a->convergence && convergence_axes++)
            second_convergence = a;
        spacing_axes += a->kind == AXIS_SPACING;
        thread_axes += a->kind == AXIS_THREADS;
        for (size_t j = 0; j < i; j++)
            if (s->axes[j].name && strcmp(s->axes[j].name, a->name) == 0) {
                study_error(s, a->at, "two axes are named '%s'", a->name);
                errors++;
            }
        for (size_t v = 0; v < a->count; v++) {
            for (const char *c = a->values[v].label; *c; c++)
                if (!(isalnum((unsigned char)*c) || *c == '.' || *c == '_' || *c == '+' ||
                      *c == '-')) {
                    study_error(s, a->values[v].at,
                                "axis '%s': the label '%s' names run directories: letters, "
                                "digits, '.', '_', '+' and '-' only",
                                a->name, a->values[v].label);
                    errors++;
                    break;
                }
            for (size_t w = 0; w < v; w++)
                if (strcmp(a->values[w].label, a->values[v].label) == 0) {
                    study_error(s, a->values[v].at, "axis '%s' has the value '%s' twice", a->name,
                                a->values[v].label);
                    errors++;
                }
        }
    }
    if (spacing_axes > 1 || thread_axes > 1) {
        study_error(s, s->root, "a study has at most one spacing axis and one threads axis");
        errors++;
    } else if (second_convergence) {
        study_error(s, second_convergence->at,
                    "axis '%s': a study has one axis of the observed orders (the spacing axis, "
                    "or one parameter axis with convergence: true)",
                    second_convergence->name);
        errors++;
    }
    for (size_t i = 0; i < s->measure_count; i++)
        for (size_t j = 0; j < i; j++)
            if (s->measures[i].name && s->measures[j].name &&
                strcmp(s->measures[i].name, s->measures[j].name) == 0) {
                study_error(s, s->measures[i].at, "two measures are named '%s'",
                            s->measures[i].name);
                errors++;
            }
    for (size_t i = 0; i < s->measure_count; i++) {
        study_measure *m = &s->measures[i];
        if (!m->reference_measure)
            continue;
        size_t j = 0;
        while (j < s->measure_count &&
               (!s->measures[j].name || strcmp(s->measures[j].name, m->reference_measure) != 0))
            j++;
        if (j == s->measure_count || j == i) {
            study_error(s, m->reference_measure_at,
                        "measure '%s': reference_measure '%s' %s", m->name,
                        m->reference_measure,
                        j == i ? "is the measure itself" : "is not a measure of the study");
            errors++;
        }
        m->reference_index = j;
    }
    return errors;
}

/* ------------------------------------------------------------ profiles -- */

static void free_values(study_axis *a)
{
    for (size_t v = 0; v < a->count; v++) {
        for (size_t e = 0; e < a->values[v].edits.count; e++)
            free(a->values[v].edits.items[e].text);
        free(a->values[v].edits.items);
        free(a->values[v].edits.scene);
        free(a->values[v].edits.external);
        free(a->values[v].edits.requires);
        free(a->values[v].label);
    }
    free(a->values);
    a->values = NULL;
    a->count = 0;
}

/* A profile's `axes: {NAME: [...]}`: the labels kept of an axis of edits (in
 * the order given), or the new values of a list axis. */
static int apply_profile_axes(study *s, const sluice_node *axes, const char *profile)
{
    if (!axes)
        return 0;
    if (axes->kind != SLUICE_NODE_MAPPING) {
        study_error(s, axes, "profiles.%s.axes must map axis names to lists of values", profile);
        return 1;
    }
    int errors = 0;
    for (size_t i = 0; i < axes->count; i++) {
        const char *name = axes->keys[i]->value;
        const sluice_node *list = axes->items[i];
        study_axis *a = NULL;
        for (size_t k = 0; k < s->axis_count; k++)
            if (strcmp(s->axes[k].name, name) == 0)
                a = &s->axes[k];
        if (!a) {
            study_error(s, axes->keys[i], "profiles.%s.axes: the study has no axis '%s'", profile,
                        name);
            errors++;
            continue;
        }
        if (list->kind != SLUICE_NODE_SEQUENCE || list->count == 0) {
            study_error(s, list, "profiles.%s.axes.%s must be a non-empty list", profile, name);
            errors++;
            continue;
        }
        if (a->kind != AXIS_EDITS) {
            /* the parameter's path is in the first value's edit: PATH=VALUE */
            char *path = NULL;
            if (a->kind == AXIS_PARAMETER) {
                const char *text = a->values[0].edits.items[0].text;
                path = strndup(text, strcspn(text, "="));
            }
            free_values(a);
            errors +=
                read_list_values(s, a, list, a->kind == AXIS_SPACING ? "particles.spacing" : path);
            free(path);
            continue;
        }
        study_value *kept = calloc(list->count, sizeof *kept);
        if (!kept)
            exit(4);
        size_t count = 0;
        for (size_t j = 0; j < list->count; j++) {
            size_t v = 0;
            while (v < a->count &&
                   (!a->values[v].label || list->items[j]->kind != SLUICE_NODE_SCALAR ||
                    strcmp(a->values[v].label, list->items[j]->value) != 0))
                v++;
            if (v == a->count) {
                study_error(s, list->items[j], "profiles.%s.axes.%s: the axis has no value '%s'",
                            profile, name,
                            list->items[j]->kind == SLUICE_NODE_SCALAR ? list->items[j]->value
                                                                       : "(a collection)");
                errors++;
                continue;
            }
            kept[count++] = a->values[v];
            a->values[v] = (study_value){.number = NAN}; /* moved */
        }
        free_values(a);
        a->values = kept;
        a->count = count;
    }
    return errors;
}

/* `profiles: {NAME: {description, remove, swap, set, axes}}`: the one chosen
 * by --profile adds its edits after the study's and narrows or replaces
 * axes' values; every profile's form is checked. */
static int read_profiles(study *s)
{
    static const char *const keys[] = {"description", "remove", "swap", "set", "axes"};
    const sluice_node *profiles = sluice_node_get(s->root, "profiles");
    if (profiles && profiles->kind != SLUICE_NODE_MAPPING) {
        study_error(s, profiles,
                    "'profiles' must map profile names to their changes "
                    "(description, remove, swap, set, axes)");
        return 1;
    }
    int errors = 0;
    const sluice_node *chosen = NULL;
    for (size_t i = 0; profiles && i < profiles->count; i++) {
        const sluice_node *p = profiles->items[i];
        char *where = study_printf("profiles.%s", profiles->keys[i]->value);
        if (p->kind != SLUICE_NODE_MAPPING) {
            study_error(s, p, "%s must be a mapping (description, remove, swap, set, axes)", where);
            errors++;
        } else
            errors += check_keys(s, p, where, keys, 5);
        free(where);
        if (s->profile && strcmp(profiles->keys[i]->value, s->profile) == 0)
            chosen = p;
    }
    if (errors || !s->profile)
        return errors;
    if (!chosen) {
        const char *names[64];
        size_t count = 0;
        for (size_t i = 0; profiles && i < profiles->count && count < 64; i++)
            names[count++] = profiles->keys[i]->value;
        const char *close = sluice_closest(s->profile, names, count);
        study_error(s, profiles ? profiles : s->root, "--profile '%s': the study defines %s%s%s%s",
                    s->profile,
                    profiles ? "no such profile" : "no profiles (a top-level 'profiles' mapping)",
                    close ? "; did you mean '" : "", close ? close : "", close ? "'?" : "");
        return 1;
    }
    char *where = study_printf("profiles.%s", s->profile);
    errors += read_edits(s, chosen, where, &s->base);
    errors += apply_profile_axes(s, sluice_node_get(chosen, "axes"), s->profile);
    free(where);
    return errors;
}

static int read_top(study *s)
{
    static const char *const keys[] = {"title",  "description", "scene",    "variant",
                                       "remove", "swap",        "set",      "threads",
                                       "jobs",   "axes",        "measures", "profiles"};
    int errors = check_keys(s, s->root, "the study", keys, SLUICE_COUNT(keys));
    const sluice_node *title = sluice_node_get(s->root, "title");
    const sluice_node *description = sluice_node_get(s->root, "description");
    s->title = study_strdup(is_string(title) ? title->value : "");
    s->description = study_strdup(is_string(description) ? description->value : "");
    const sluice_node *scene = sluice_node_get(s->root, "scene");
    if (!is_string(scene)) {
        study_error(s, scene ? scene : s->root,
                    "a study needs 'scene': the path of its base scene (relative to the study "
                    "file)");
        errors++;
    } else {
        s->scene = scene->value[0] == '/' ? study_strdup(scene->value)
                                          : study_printf("%s/%s", s->directory, scene->value);
        struct stat st;
        if (stat(s->scene, &st) != 0 || !S_ISREG(st.st_mode)) {
            study_error(s, scene, "the scene '%s' cannot be read (%s)", scene->value,
                        errno ? strerror(errno) : "not a file");
            errors++;
        }
    }
    errors += read_edits(s, s->root, "the study", &s->base);
    const char *counts[] = {"threads", "jobs"};
    int *targets[] = {&s->threads, &s->jobs};
    for (int c = 0; c < 2; c++) {
        const sluice_node *n = sluice_node_get(s->root, counts[c]);
        double v = 1;
        if (n && (number_of(n, &v) != 0 || v < 1 || v > 4096 || v != floor(v))) {
            study_error(s, n, "%s is a whole number from 1 to 4096", counts[c]);
            errors++;
        }
        *targets[c] = (int)v;
    }
    errors += read_list(s, "axes", 1);
    errors += read_list(s, "measures", 0);
    if (!errors)
        errors += read_profiles(s);
    if (!errors)
        errors += check_names(s);
    return errors;
}

int study_load(study *s, const char *path)
{
    s->path = study_strdup(path);
    char *copy = study_strdup(path);
    char *slash = strrchr(copy, '/');
    s->directory = study_strdup(slash ? (slash == copy ? "/" : (*slash = '\0', copy)) : ".");
    free(copy);
    s->root = sluice_yaml_parse_file(path, s->diag);
    if (!s->root)
        return 1;
    if (s->root->kind != SLUICE_NODE_MAPPING) {
        study_error(s, s->root, "a study file is a mapping: scene, axes, measures, ...");
        return 1;
    }
    return read_top(s);
}

/* ------------------------------------------------------------- the runs -- */

static void push_arg(study_run *r, const char *text, const sluice_node *origin)
{
    char **argv = realloc(r->argv, (r->argc + 2) * sizeof *argv);
    const sluice_node **origins = realloc(r->origin, (r->argc + 2) * sizeof *origins);
    if (!argv || !origins) {
        fprintf(stderr, "sluice-study: error: out of memory\n");
        exit(4);
    }
    r->argv = argv;
    r->origin = origins;
    r->argv[r->argc] = study_strdup(text);
    r->origin[r->argc++] = origin;
    r->argv[r->argc] = NULL;
}

static const char *const edit_options[] = {"--remove", "--swap", "--set"};

/* The external command of a run with its placeholders filled in (malloc'd). */
static char *expand_external(const study *s, const study_run *r, const char *command)
{
    char spacing[32], threads[32];
    snprintf(spacing, sizeof spacing, "%.10g", r->spacing);
    snprintf(threads, sizeof threads, "%d", r->threads);
    char *run_dir = study_printf("%s/runs/%s", s->out, r->name);
    const char *values[] = {run_dir, spacing, threads, s->directory};
    size_t length = 1, n = sizeof external_placeholders / sizeof *external_placeholders;
    for (const char *p = command; *p; p++) {
        length++;
        for (size_t k = 0; k < n; k++)
            if (strncmp(p, external_placeholders[k], strlen(external_placeholders[k])) == 0)
                length += strlen(values[k]);
    }
    char *out = calloc(length, 1), *o = out;
    if (!out)
        exit(4);
    for (const char *p = command; *p;) {
        size_t k = 0;
        while (k < n && strncmp(p, external_placeholders[k], strlen(external_placeholders[k])))
            k++;
        if (k < n) {
            o = stpcpy(o, values[k]);
            p += strlen(external_placeholders[k]);
        } else
            *o++ = *p++;
    }
    free(run_dir);
    return out;
}

/* A run of an external value: `/bin/sh -c COMMAND`; the other axes' values
 * may set the spacing and the threads, not edit a scene. */
static int build_external(study *s, study_run *r, const study_edits *const *sources, size_t count)
{
    int errors = 0;
    for (size_t i = 1; i < count; i++) {
        const study_edits *e = sources[i];
        if (e == r->external || s->axes[i - 1].kind == AXIS_SPACING)
            continue; /* the spacing reaches the program as {spacing} */
        if (e->external) {
            study_error(s, e->external_at,
                        "run '%s' would run two external programs; one axis may choose one",
                        r->name);
            errors++;
        } else if (e->count || e->variant || e->scene) {
            const sluice_node *at = e->count ? e->items[0].at : e->variant ? e->variant_at
                                                                            : e->scene_at;
            study_error(s, at,
                        "run '%s' combines an external program with a scene edit; give the "
                        "external value its own axis, or a profile without this combination",
                        r->name);
            errors++;
        }
    }
    if (strstr(r->external->external, "{spacing}") && isnan(r->spacing)) {
        study_error(s, r->external->external_at,
                    "run '%s': the external command uses {spacing} and no axis sets it",
                    r->name);
        errors++;
    }
    r->scene = s->scene;
    push_arg(r, "/bin/sh", NULL);
    push_arg(r, "-c", NULL);
    char *command = expand_external(s, r, r->external->external);
    push_arg(r, command, r->external->external_at);
    r->command = study_printf("external: %s", command);
    free(command);
    return errors;
}

/* `sluice run SCENE --out DIR [--variant V] --remove.. --swap.. --set..`:
 * each option once per edit, the base study's first. */
static int build_command(study *s, study_run *r)
{
    const study_edits *sources[64];
    size_t count = 0;
    sources[count++] = &s->base;
    for (size_t a = 0; a < s->axis_count && count < 64; a++)
        sources[count++] = &s->axes[a].values[r->choice[a]].edits;
    for (size_t i = 1; i < count && !r->external; i++)
        if (sources[i]->external)
            r->external = sources[i];
    if (r->external)
        return build_external(s, r, sources, count);
    int errors = 0;
    const study_edits *own = NULL;
    for (size_t i = 0; i < count; i++)
        if (sources[i]->scene) {
            if (own) {
                study_error(s, sources[i]->scene_at,
                            "run '%s' would have two scenes ('%s' and '%s'); one axis may "
                            "choose the scene",
                            r->name, own->scene, sources[i]->scene);
                errors++;
            }
            own = sources[i];
        }
    r->scene = own ? own->scene : s->scene;
    push_arg(r, s->sluice, NULL);
    push_arg(r, "run", NULL);
    push_arg(r, r->scene, own ? own->scene_at : NULL);
    push_arg(r, "--out", NULL);
    char *dir = study_printf("%s/runs/%s", s->out, r->name);
    push_arg(r, dir, NULL);
    free(dir);
    const study_edits *variant = NULL;
    for (size_t i = 0; i < count; i++)
        if (sources[i]->variant) {
            if (variant) {
                study_error(s, sources[i]->variant_at,
                            "run '%s' would apply two variants ('%s' and '%s'); a run applies "
                            "at most one",
                            r->name, variant->variant, sources[i]->variant);
                errors++;
            }
            variant = sources[i];
        }
    if (variant) {
        push_arg(r, "--variant", variant->variant_at);
        push_arg(r, variant->variant, variant->variant_at);
    }
    for (int kind = EDIT_REMOVE; kind <= EDIT_SET; kind++)
        for (size_t i = 0; i < count; i++)
            for (size_t e = 0; e < sources[i]->count; e++)
                if ((int)sources[i]->items[e].kind == kind) {
                    push_arg(r, edit_options[kind], sources[i]->items[e].at);
                    push_arg(r, sources[i]->items[e].text, sources[i]->items[e].at);
                }
    char threads[32];
    snprintf(threads, sizeof threads, "%d", r->threads);
    push_arg(r, "--threads", NULL);
    push_arg(r, threads, NULL);
    push_arg(r, "--progress", NULL);
    /* the record: the command without the program's own path */
    size_t length = 1;
    for (size_t i = 1; i < r->argc; i++)
        length += strlen(r->argv[i]) + 1;
    r->command = calloc(length, 1);
    if (!r->command)
        exit(4);
    for (size_t i = 1; i < r->argc; i++) {
        strcat(r->command, r->argv[i]);
        if (i + 1 < r->argc)
            strcat(r->command, " ");
    }
    return errors;
}

int study_expand(study *s)
{
    size_t total = 1;
    for (size_t a = 0; a < s->axis_count; a++) {
        total *= s->axes[a].count;
        if (total > 100000) {
            study_error(s, s->axes[a].at, "the axes make more than 100000 runs");
            return -1;
        }
    }
    s->runs = calloc(total, sizeof *s->runs);
    if (!s->runs)
        return -1;
    int errors = 0;
    for (size_t k = 0; k < total; k++) {
        study_run *r = &s->runs[s->run_count++];
        r->choice = calloc(s->axis_count + 1, sizeof *r->choice);
        if (!r->choice)
            return -1;
        r->threads = s->threads;
        r->spacing = NAN;
        r->resolution = NAN;
        char *name = study_strdup("");
        /* the last axis varies fastest */
        size_t rest = k;
        for (size_t a = s->axis_count; a-- > 0;) {
            r->choice[a] = rest % s->axes[a].count;
            rest /= s->axes[a].count;
        }
        for (size_t a = 0; a < s->axis_count; a++) {
            const study_value *v = &s->axes[a].values[r->choice[a]];
            if (s->axes[a].kind == AXIS_SPACING)
                r->spacing = v->number;
            if (s->axes[a].kind == AXIS_THREADS)
                r->threads = (int)v->number;
            if (s->axes[a].convergence)
                r->resolution = v->number;
            char *longer = study_printf("%s%s%s", name, a ? "_" : "", v->label);
            free(name);
            name = longer;
        }
        r->name = name;
        errors += build_command(s, r);
    }
    return errors ? -1 : 0;
}

void study_free(study *s)
{
    for (size_t i = 0; i < s->run_count; i++) {
        study_run *r = &s->runs[i];
        for (size_t a = 0; a < r->argc; a++)
            free(r->argv[a]);
        free(r->argv);
        free(r->origin);
        free(r->choice);
        free(r->name);
        free(r->command);
        free(r->restart);
        free(r->skipped);
        free(r->values);
        free(r->errors);
    }
    free(s->runs);
    for (size_t a = 0; a < s->axis_count; a++) {
        for (size_t v = 0; v < s->axes[a].count; v++) {
            for (size_t e = 0; e < s->axes[a].values[v].edits.count; e++)
                free(s->axes[a].values[v].edits.items[e].text);
            free(s->axes[a].values[v].edits.items);
            free(s->axes[a].values[v].edits.scene);
            free(s->axes[a].values[v].edits.external);
            free(s->axes[a].values[v].edits.requires);
            free(s->axes[a].values[v].label);
        }
        free(s->axes[a].values);
        free(s->axes[a].name);
    }
    free(s->axes);
    for (size_t m = 0; m < s->measure_count; m++) {
        study_measure *me = &s->measures[m];
        free(me->name);
        free(me->unit);
        free(me->file);
        free(me->column);
        free(me->key);
        free(me->reference_measure);
        for (size_t i = 0; i < me->argument_count; i++)
            free(me->arguments[i]);
        free(me->arguments);
    }
    free(s->measures);
    for (size_t e = 0; e < s->base.count; e++)
        free(s->base.items[e].text);
    free(s->base.items);
    sluice_node_free(s->root);
    free(s->path);
    free(s->directory);
    free(s->title);
    free(s->description);
    free(s->scene);
    free(s->out);
}
