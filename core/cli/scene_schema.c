/* sluice inspect --schema: a JSON Schema (draft-07) of scene files.
 *
 * Everything comes from the tables the loader validates against: the core's
 * sections, geometry shapes and profile pieces (sluice_scene_format_tables)
 * and the parameter tables of the plugins on the plugin path. A table
 * becomes an object with its keys as properties (type, range, enumeration,
 * default, and the type, unit and description as "description"), its
 * required keys, and additionalProperties false (the loader refuses unknown
 * keys everywhere). Geometry items are told apart by `shape`, pieces by
 * `piece` and plugin instances by `plugin`, each with if/then. What depends
 * on `dimensions` (vector lengths, the shapes and plugins of one dimension
 * only) is checked by a branch on it at the top level. */
#define _GNU_SOURCE
#include "scene_schema.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "build_config.h"
#include "registry.h"
#include "scene.h"
#include "schema.h"
#include "yaml_tree.h"

/* ----------------------------------------------------------- the writer -- */

#define JSON_DEPTH 64

typedef struct json {
    FILE *out;
    int depth;
    int after_key;
    unsigned count[JSON_DEPTH];
    char problem[512]; /* "" while all is well */
} json;

static void fail(json *j, const char *format, ...) SLUICE_PRINTF(2, 3);
static void fail(json *j, const char *format, ...)
{
    if (j->problem[0])
        return;
    va_list ap;
    va_start(ap, format);
    vsnprintf(j->problem, sizeof j->problem, format, ap);
    va_end(ap);
}

static void new_line(json *j)
{
    fputc('\n', j->out);
    for (int i = 0; i < j->depth; i++)
        fputs("  ", j->out);
}

static void begin_value(json *j)
{
    if (j->after_key) {
        j->after_key = 0;
        return;
    }
    if (j->depth > 0) {
        if (j->count[j->depth]++)
            fputc(',', j->out);
        new_line(j);
    }
}

static void put_string(FILE *out, const char *text)
{
    fputc('"', out);
    for (const unsigned char *c = (const unsigned char *)(text ? text : ""); *c; c++) {
        if (*c == '"' || *c == '\\')
            fprintf(out, "\\%c", *c);
        else if (*c == '\n')
            fputs("\\n", out);
        else if (*c < 0x20)
            fprintf(out, "\\u%04x", *c);
        else
            fputc(*c, out);
    }
    fputc('"', out);
}

static void j_key(json *j, const char *key)
{
    begin_value(j);
    put_string(j->out, key);
    fputs(": ", j->out);
    j->after_key = 1;
}

static void j_open(json *j, char bracket)
{
    begin_value(j);
    fputc(bracket, j->out);
    if (j->depth + 1 >= JSON_DEPTH) {
        fail(j, "the schema nests more than %d deep", JSON_DEPTH);
        return;
    }
    j->count[++j->depth] = 0;
}

static void j_close(json *j, char bracket)
{
    int had_items = j->count[j->depth] != 0;
    if (j->depth > 0)
        j->depth--;
    if (had_items)
        new_line(j);
    fputc(bracket, j->out);
}

static void j_string(json *j, const char *text)
{
    begin_value(j);
    put_string(j->out, text);
}

static void j_number(json *j, double value)
{
    char text[40];
    snprintf(text, sizeof text, "%.15g", value);
    if (strtod(text, NULL) != value)
        snprintf(text, sizeof text, "%.17g", value);
    begin_value(j);
    fputs(text, j->out);
}

static void j_raw(json *j, const char *text)
{
    begin_value(j);
    fputs(text, j->out);
}

static void j_kstring(json *j, const char *key, const char *text)
{
    j_key(j, key);
    j_string(j, text);
}

static void j_knumber(json *j, const char *key, double value)
{
    j_key(j, key);
    j_number(j, value);
}

static void j_kraw(json *j, const char *key, const char *text)
{
    j_key(j, key);
    j_raw(j, text);
}

static void j_kopen(json *j, const char *key, char bracket)
{
    j_key(j, key);
    j_open(j, bracket);
}

static void j_ref(json *j, const char *definition)
{
    char ref[256];
    snprintf(ref, sizeof ref, "#/definitions/%s", definition);
    j_open(j, '{');
    j_kstring(j, "$ref", ref);
    j_close(j, '}');
}

/* A YAML scalar the loader reads as a string: any scalar. */
#define SCALAR_TYPES "[\"string\", \"number\", \"boolean\"]"

/* ------------------------------------------------------------ one key -- */

/* The spec's default for dims (2, 3; 0: either) into buffer, trimmed: 1, or
 * 0 when it has none or it depends on the dimensions and dims is 0. */
static int default_text(const sluice_param_spec *s, int dims, char *buffer, size_t size)
{
    const char *text = s->default_value;
    if (!text)
        return 0;
    size_t length = strlen(text);
    const char *bar = strstr(text, " | ");
    if (bar && dims == 0)
        return 0;
    if (bar && dims == 2)
        length = (size_t)(bar - text);
    else if (bar) {
        text = bar + 3;
        length = strlen(text);
    }
    while (length && (*text == ' ' || *text == '\t'))
        text++, length--;
    while (length && (text[length - 1] == ' ' || text[length - 1] == '\t'))
        length--;
    snprintf(buffer, size, "%.*s", (int)length, text);
    return 1;
}

/* The default's node as JSON for the spec's type; -1 (nothing written when
 * dry) where it does not convert. */
static int default_value(json *j, const sluice_param_spec *s, const sluice_node *node, int dry)
{
    if (node->kind == SLUICE_NODE_MAPPING)
        return -1;
    if (node->kind == SLUICE_NODE_SEQUENCE) {
        if (!dry)
            j_open(j, '[');
        for (size_t i = 0; i < node->count; i++)
            if (default_value(j, s, node->items[i], dry) != 0)
                return -1;
        if (!dry)
            j_close(j, ']');
        return 0;
    }
    double real;
    long long integer;
    int flag;
    switch (s->type) {
    case SLUICE_PARAM_INT:
        if (sluice_parse_int(node->value, &integer) != 0)
            return -1;
        if (!dry)
            j_number(j, (double)integer);
        return 0;
    case SLUICE_PARAM_BOOL:
        if (sluice_parse_bool(node->value, &flag) != 0)
            return -1;
        if (!dry)
            j_raw(j, flag ? "true" : "false");
        return 0;
    case SLUICE_PARAM_STRING:
    case SLUICE_PARAM_ENUM:
        if (!dry)
            j_string(j, node->value);
        return 0;
    default:
        if (sluice_parse_real(node->value, &real) != 0)
            return -1;
        if (!dry)
            j_number(j, real);
        return 0;
    }
}

static void emit_default(json *j, const sluice_param_spec *s, int dims)
{
    char text[512];
    if (!default_text(s, dims, text, sizeof text))
        return;
    if (!text[0]) {
        if (s->type == SLUICE_PARAM_STRING)
            j_kstring(j, "default", "");
        return;
    }
    sluice_diag *diag = sluice_diag_create();
    sluice_node *node = diag ? sluice_yaml_parse_string(text, strlen(text), "default", diag) : NULL;
    if (!diag)
        fail(j, "out of memory");
    else if (!node)
        fail(j, "the default '%s' of parameter '%s' is not YAML", text, s->name);
    else if (default_value(j, s, node, 1) != 0)
        fail(j, "the default '%s' of parameter '%s' does not match its type", text, s->name);
    else {
        j_key(j, "default");
        default_value(j, s, node, 0);
    }
    sluice_node_free(node);
    sluice_diag_destroy(diag);
}

/* "number > 0 (m): initial particle spacing ..." */
static void spec_description(const sluice_param_spec *s, int dims, char *buffer, size_t size)
{
    char type[600];
    sluice_schema_describe(s, type, sizeof type);
    const char *doc = s->doc && *s->doc ? s->doc : NULL;
    int w = snprintf(buffer, size, "%s%s%s", type, doc ? ": " : "", doc ? doc : "");
    if (w < 0 || (size_t)w >= size)
        return;
    if (dims == 0 && s->default_value && strstr(s->default_value, " | "))
        snprintf(buffer + w, size - (size_t)w, " (default, 2D | 3D: %s)", s->default_value);
    else if (!s->default_value && (s->flags & SLUICE_PARAM_OPTIONAL))
        snprintf(buffer + w, size - (size_t)w, " (optional)");
}

static void number_bounds(json *j, const sluice_param_spec *s)
{
    if (s->flags & SLUICE_PARAM_HAS_MIN)
        j_knumber(j, (s->flags & SLUICE_PARAM_MIN_EXCLUSIVE) ? "exclusiveMinimum" : "minimum",
                  s->min);
    if (s->flags & SLUICE_PARAM_HAS_MAX)
        j_knumber(j, (s->flags & SLUICE_PARAM_MAX_EXCLUSIVE) ? "exclusiveMaximum" : "maximum",
                  s->max);
}

static void number_items(json *j, const sluice_param_spec *s)
{
    j_kopen(j, "items", '{');
    j_kstring(j, "type", "number");
    number_bounds(j, s);
    j_close(j, '}');
}

/* n items, or 2 to 3 (one per dimension) when n is 0 */
static void item_count(json *j, uint32_t n)
{
    j_knumber(j, "minItems", n ? n : 2);
    j_knumber(j, "maxItems", n ? n : 3);
}

static void enum_choices(json *j, const char *choices)
{
    j_kopen(j, "enum", '[');
    const char *c = choices ? choices : "";
    while (1) {
        const char *bar = strchr(c, '|');
        size_t length = bar ? (size_t)(bar - c) : strlen(c);
        char name[128];
        snprintf(name, sizeof name, "%.*s", (int)length, c);
        j_string(j, name);
        if (!bar)
            break;
        c = bar + 1;
    }
    j_close(j, ']');
}

/* The schema of one parameter for the scene's dimensions (0: either). */
static void param_schema(json *j, const sluice_param_spec *s, int dims)
{
    char description[4096];
    spec_description(s, dims, description, sizeof description);
    j_open(j, '{');
    j_kstring(j, "description", description);
    switch (s->type) {
    case SLUICE_PARAM_REAL:
    case SLUICE_PARAM_INT:
        j_kstring(j, "type", s->type == SLUICE_PARAM_REAL ? "number" : "integer");
        number_bounds(j, s);
        break;
    case SLUICE_PARAM_BOOL: j_kstring(j, "type", "boolean"); break;
    case SLUICE_PARAM_STRING: j_kraw(j, "type", SCALAR_TYPES); break;
    case SLUICE_PARAM_ENUM: enum_choices(j, s->choices); break;
    case SLUICE_PARAM_VECTOR:
        j_kstring(j, "type", "array");
        number_items(j, s);
        item_count(j, s->length == SLUICE_LENGTH_DIM ? (uint32_t)dims : s->length);
        break;
    case SLUICE_PARAM_REAL_LIST:
        j_kstring(j, "type", "array");
        number_items(j, s);
        break;
    case SLUICE_PARAM_POINT_LIST:
        j_kstring(j, "type", "array");
        j_kopen(j, "items", '{');
        j_kstring(j, "type", "array");
        number_items(j, s);
        item_count(j, s->length ? s->length : (uint32_t)dims);
        j_close(j, '}');
        break;
    default: fail(j, "parameter '%s' has an unknown type %d", s->name, (int)s->type); break;
    }
    emit_default(j, s, dims);
    j_close(j, '}');
}

static int depends_on_dimensions(const sluice_param_spec *s)
{
    return (s->type == SLUICE_PARAM_VECTOR && s->length == SLUICE_LENGTH_DIM) ||
           (s->type == SLUICE_PARAM_POINT_LIST && s->length == 0);
}

/* "properties" holding, for the keys whose form depends on the dimensions,
 * their lengths in a scene of dims (2 or 3); nothing when none does. */
static void dimension_properties(json *j, const sluice_param_spec *specs, uint32_t count,
                                 int dims)
{
    int any = 0;
    for (uint32_t i = 0; i < count; i++)
        any |= depends_on_dimensions(&specs[i]);
    if (!any)
        return;
    j_kopen(j, "properties", '{');
    for (uint32_t i = 0; i < count; i++) {
        const sluice_param_spec *s = &specs[i];
        if (!depends_on_dimensions(s))
            continue;
        j_kopen(j, s->name, '{');
        if (s->type == SLUICE_PARAM_POINT_LIST)
            j_kopen(j, "items", '{');
        item_count(j, (uint32_t)dims);
        if (s->type == SLUICE_PARAM_POINT_LIST)
            j_close(j, '}');
        j_close(j, '}');
    }
    j_close(j, '}');
}

/* ---------------------------------------------------------- one table -- */

#define KEYS_MAX 96

/* The keys of a table in a scene of dims (0: either; then a key is required
 * when both dimensions' tables require it). */
typedef struct key_list {
    const sluice_param_spec *spec[KEYS_MAX];
    int required[KEYS_MAX];
    size_t count;
} key_list;

static int is_required(const sluice_param_spec *s)
{
    return s->name && !s->default_value && !(s->flags & SLUICE_PARAM_OPTIONAL);
}

static const sluice_param_spec *find_spec(const sluice_param_spec *specs, uint32_t count,
                                          const char *name)
{
    for (uint32_t i = 0; i < count; i++)
        if (specs[i].name && strcmp(specs[i].name, name) == 0)
            return &specs[i];
    return NULL;
}

static int add_keys(key_list *keys, const sluice_param_spec *specs, uint32_t count,
                    const sluice_param_spec *other, uint32_t other_count)
{
    for (uint32_t i = 0; i < count; i++) {
        const sluice_param_spec *s = &specs[i];
        if (!s->name)
            continue;
        int known = 0;
        for (size_t k = 0; k < keys->count; k++)
            known |= strcmp(keys->spec[k]->name, s->name) == 0;
        if (known)
            continue;
        if (keys->count == KEYS_MAX)
            return -1;
        const sluice_param_spec *twin = other ? find_spec(other, other_count, s->name) : NULL;
        keys->spec[keys->count] = s;
        keys->required[keys->count] = is_required(s) && (!other || (twin && is_required(twin)));
        keys->count++;
    }
    return 0;
}

static int table_keys(const sluice_scene_table *t, int dims, key_list *keys)
{
    keys->count = 0;
    if (!t->specs_3d || dims == 2)
        return add_keys(keys, t->specs, t->count, NULL, 0);
    if (dims == 3)
        return add_keys(keys, t->specs_3d, t->count_3d, NULL, 0);
    if (add_keys(keys, t->specs, t->count, t->specs_3d, t->count_3d) != 0)
        return -1;
    return add_keys(keys, t->specs_3d, t->count_3d, t->specs, t->count);
}

/* How one table becomes an object. */
typedef struct object_form {
    const char *description;
    const char *discriminator; /* `shape` or `piece`: its value is `kind` */
    const char *kind;
    const char *plugin; /* plugin tables: the instance key `plugin` names this */
    int nullable;       /* an empty value stands for {} */
    int pieces;         /* geometry: `pieces` is the list of profile pieces */
} object_form;

static void special_property(json *j, const sluice_param_spec *s, const object_form *form)
{
    if (form->pieces && strcmp(s->name, "pieces") == 0) {
        j_ref(j, "pieces");
        return;
    }
    j_open(j, '{');
    j_kstring(j, "const", form->kind);
    if (s->doc)
        j_kstring(j, "description", s->doc);
    j_close(j, '}');
}

static void object_schema(json *j, const key_list *keys, int dims, const object_form *form)
{
    j_open(j, '{');
    if (form->description)
        j_kstring(j, "description", form->description);
    j_kraw(j, "type", form->nullable ? "[\"object\", \"null\"]" : "\"object\"");
    j_kopen(j, "properties", '{');
    if (form->plugin) {
        char text[256];
        snprintf(text, sizeof text,
                 "the plugin this instance loads (an instance of %s under a name of its own)",
                 form->plugin);
        j_kopen(j, "plugin", '{');
        j_kstring(j, "const", form->plugin);
        j_kstring(j, "description", text);
        j_close(j, '}');
    }
    for (size_t i = 0; i < keys->count; i++) {
        const sluice_param_spec *s = keys->spec[i];
        j_key(j, s->name);
        int special = (form->discriminator && strcmp(s->name, form->discriminator) == 0) ||
                      (form->pieces && strcmp(s->name, "pieces") == 0);
        if (special)
            special_property(j, s, form);
        else
            param_schema(j, s, dims);
    }
    j_close(j, '}');
    int any = 0;
    for (size_t i = 0; i < keys->count; i++)
        any |= keys->required[i] || (form->pieces && strcmp(keys->spec[i]->name, "pieces") == 0);
    if (any) {
        j_kopen(j, "required", '[');
        for (size_t i = 0; i < keys->count; i++)
            if (keys->required[i] || (form->pieces && strcmp(keys->spec[i]->name, "pieces") == 0))
                j_string(j, keys->spec[i]->name);
        j_close(j, ']');
    }
    j_kraw(j, "additionalProperties", "false");
    j_close(j, '}');
}

/* -------------------------------------------------- geometry and pieces -- */

static const char *dims_suffix(int dims)
{
    return dims == 2 ? "_2d" : dims == 3 ? "_3d" : "";
}

static int available(const sluice_scene_table *t, int dims)
{
    return dims == 0 || (t->dimensions & (dims == 2 ? SLUICE_DIMS_2 : SLUICE_DIMS_3));
}

/* The doc of the table's discriminator key (its `shape` or `piece`). */
static const char *kind_doc(const sluice_scene_table *t, const char *key)
{
    const sluice_param_spec *s = find_spec(t->specs, t->count, key);
    return s && s->doc ? s->doc : NULL;
}

/* Definitions `base` (an item told apart by `key`) and `base.kind` for each
 * table available in dims. */
static void item_definitions(json *j, const char *base, const char *description,
                             const sluice_scene_table *tables, size_t count, const char *key,
                             int dims)
{
    char name[128], ref[160];
    snprintf(name, sizeof name, "%s%s", base, dims_suffix(dims));
    j_kopen(j, name, '{');
    j_kstring(j, "description", description);
    j_kstring(j, "type", "object");
    j_kopen(j, "required", '[');
    j_string(j, key);
    j_close(j, ']');
    j_kopen(j, "properties", '{');
    j_kopen(j, key, '{');
    j_kopen(j, "enum", '[');
    for (size_t i = 0; i < count; i++)
        if (available(&tables[i], dims))
            j_string(j, tables[i].name);
    j_close(j, ']');
    j_close(j, '}');
    j_close(j, '}');
    j_kopen(j, "allOf", '[');
    for (size_t i = 0; i < count; i++) {
        if (!available(&tables[i], dims))
            continue;
        j_open(j, '{');
        j_kopen(j, "if", '{');
        j_kopen(j, "properties", '{');
        j_kopen(j, key, '{');
        j_kstring(j, "const", tables[i].name);
        j_close(j, '}');
        j_close(j, '}');
        char required[64];
        snprintf(required, sizeof required, "[\"%s\"]", key);
        j_kraw(j, "required", required);
        j_close(j, '}');
        snprintf(ref, sizeof ref, "%s.%s", name, tables[i].name);
        j_key(j, "then");
        j_ref(j, ref);
        j_close(j, '}');
    }
    j_close(j, ']');
    j_close(j, '}');
    for (size_t i = 0; i < count; i++) {
        if (!available(&tables[i], dims))
            continue;
        key_list keys;
        if (table_keys(&tables[i], dims, &keys) != 0) {
            fail(j, "the table of %s '%s' has more than %d keys", key, tables[i].name, KEYS_MAX);
            return;
        }
        char text[1024];
        const char *doc = kind_doc(&tables[i], key);
        snprintf(text, sizeof text, "%s%s", doc ? doc : tables[i].name,
                 dims == 0 && tables[i].dimensions == SLUICE_DIMS_2 ? " (2D only)" : "");
        object_form form = {text, key, tables[i].name, NULL, 0, 1};
        snprintf(ref, sizeof ref, "%s.%s", name, tables[i].name);
        j_key(j, ref);
        object_schema(j, &keys, dims, &form);
    }
}

static void geometry_definitions(json *j, const sluice_scene_format *f, int dims)
{
    char name[64], fluid[64], walls[64];
    snprintf(name, sizeof name, "geometry%s", dims_suffix(dims));
    snprintf(fluid, sizeof fluid, "fluid%s", dims_suffix(dims));
    snprintf(walls, sizeof walls, "wall%s", dims_suffix(dims));
    j_kopen(j, name, '{');
    j_kstring(j, "description", "the fluid regions and the walls");
    j_kstring(j, "type", "object");
    j_kopen(j, "properties", '{');
    j_kopen(j, "fluid", '{');
    j_kstring(j, "description", "fluid regions, each a mapping with a 'shape'");
    j_kraw(j, "type", "[\"array\", \"null\"]");
    j_key(j, "items");
    j_ref(j, fluid);
    j_close(j, '}');
    j_kopen(j, "walls", '{');
    j_kstring(j, "description", "walls, each a mapping with a 'shape'; one description serves "
                                "every wall scheme");
    j_kraw(j, "type", "[\"array\", \"null\"]");
    j_key(j, "items");
    j_ref(j, walls);
    j_close(j, '}');
    j_close(j, '}');
    j_kraw(j, "additionalProperties", "false");
    j_close(j, '}');
    item_definitions(j, "fluid", "a fluid region", f->fluid_shapes, f->fluid_shape_count, "shape",
                     dims);
    item_definitions(j, "wall", "a wall", f->wall_shapes, f->wall_shape_count, "shape", dims);
}

static void piece_definitions(json *j, const sluice_scene_format *f)
{
    j_kopen(j, "pieces", '{');
    j_kstring(j, "description",
              "the pieces of a profile (line, arc, crest, steps), appended in order from "
              "'start'; an entry may itself be a list of pieces (a YAML alias of pieces written "
              "once), spliced in place");
    j_kstring(j, "type", "array");
    j_knumber(j, "minItems", 1);
    j_key(j, "items");
    j_ref(j, "piece_or_list");
    j_close(j, '}');
    j_kopen(j, "piece_or_list", '{');
    j_kraw(j, "if", "{\"type\": \"array\"}");
    j_kopen(j, "then", '{');
    j_key(j, "items");
    j_ref(j, "piece_or_list");
    j_close(j, '}');
    j_key(j, "else");
    j_ref(j, "piece");
    j_close(j, '}');
    item_definitions(j, "piece", "a piece of a profile", f->pieces, f->piece_count, "piece", 0);
}

/* ------------------------------------------------------------- plugins -- */

typedef struct plugin_set {
    const sluice_component **component;
    size_t count;
} plugin_set;

static int by_name(const void *a, const void *b)
{
    const sluice_component *const *x = a, *const *y = b;
    return strcmp((*x)->name, (*y)->name);
}

static int plugin_set_open(plugin_set *set, const sluice_registry *registry)
{
    set->count = 0;
    set->component = malloc((registry->component_count + 1) * sizeof *set->component);
    if (!set->component)
        return -1;
    for (size_t i = 0; i < registry->component_count; i++)
        if (!registry->components[i].shadowed && registry->components[i].component->name)
            set->component[set->count++] = registry->components[i].component;
    qsort(set->component, set->count, sizeof *set->component, by_name);
    return 0;
}

static int dims_of(const sluice_component *c, int dims)
{
    return dims == 0 || (c->dimensions & (dims == 2 ? SLUICE_DIMS_2 : SLUICE_DIMS_3));
}

static void plugin_definitions(json *j, const plugin_set *set)
{
    for (size_t i = 0; i < set->count; i++) {
        const sluice_component *c = set->component[i];
        key_list keys = {.count = 0};
        if (add_keys(&keys, c->params, c->param_count, NULL, 0) != 0) {
            fail(j, "plugin '%s' has more than %d parameters", c->name, KEYS_MAX);
            return;
        }
        char description[1024], name[160];
        snprintf(description, sizeof description, "%s%s", c->summary ? c->summary : c->name,
                 (c->dimensions & SLUICE_DIMS_ALL) == SLUICE_DIMS_2   ? " (2D only)"
                 : (c->dimensions & SLUICE_DIMS_ALL) == SLUICE_DIMS_3 ? " (3D only)"
                                                                      : "");
        object_form form = {description, NULL, NULL, c->name, 1, 0};
        snprintf(name, sizeof name, "plugin.%s", c->name);
        j_key(j, name);
        object_schema(j, &keys, 0, &form);
    }
    j_kopen(j, "instance", '{');
    j_kstring(j, "description",
              "an instance of a plugin under a name of its own: 'plugin' names the plugin, the "
              "other keys are its parameters");
    j_kstring(j, "type", "object");
    j_kraw(j, "required", "[\"plugin\"]");
    j_kopen(j, "properties", '{');
    j_kopen(j, "plugin", '{');
    j_kstring(j, "description", "the plugin this instance loads");
    j_kopen(j, "enum", '[');
    for (size_t i = 0; i < set->count; i++)
        j_string(j, set->component[i]->name);
    j_close(j, ']');
    j_close(j, '}');
    j_close(j, '}');
    j_kopen(j, "allOf", '[');
    for (size_t i = 0; i < set->count; i++) {
        char if_text[300], ref[160];
        snprintf(if_text, sizeof if_text, "{\"properties\": {\"plugin\": {\"const\": \"%s\"}}}",
                 set->component[i]->name);
        snprintf(ref, sizeof ref, "plugin.%s", set->component[i]->name);
        j_open(j, '{');
        j_kraw(j, "if", if_text);
        j_key(j, "then");
        j_ref(j, ref);
        j_close(j, '}');
    }
    j_close(j, ']');
    j_close(j, '}');
}

/* The names in `plugins` that are not plugins: instances, which need
 * `plugin`. Names are letters, digits, '_' and '-'. */
static char *instance_pattern(const plugin_set *set)
{
    size_t size = 64;
    for (size_t i = 0; i < set->count; i++)
        size += 2 * strlen(set->component[i]->name) + 1;
    char *pattern = malloc(size);
    if (!pattern)
        return NULL;
    size_t n = (size_t)snprintf(pattern, size, "^(?!(?:");
    for (size_t i = 0; i < set->count; i++) {
        if (i)
            pattern[n++] = '|';
        for (const char *c = set->component[i]->name; *c; c++) {
            int plain = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') ||
                        (*c >= '0' && *c <= '9') || *c == '_' || *c == '-';
            if (!plain)
                pattern[n++] = '\\';
            pattern[n++] = *c;
        }
    }
    snprintf(pattern + n, size - n, ")$)[A-Za-z0-9_-]+$");
    return pattern;
}

/* The `plugins` mapping; dims 2 or 3: only what depends on the dimensions
 * (plugins of the other dimension refused, vector lengths). */
static void plugins_schema(json *j, const plugin_set *set, const char *pattern, int dims)
{
    j_open(j, '{');
    if (!dims) {
        j_kstring(j, "description",
                  "plugin (component) name -> its parameters (sluice inspect NAME); a name of "
                  "its own with 'plugin: NAME' loads plugin NAME as one more instance");
        j_kstring(j, "type", "object");
        j_knumber(j, "minProperties", 1);
    }
    j_kopen(j, "properties", '{');
    for (size_t i = 0; i < set->count; i++) {
        const sluice_component *c = set->component[i];
        char ref[160];
        snprintf(ref, sizeof ref, "plugin.%s", c->name);
        if (!dims) {
            j_key(j, c->name);
            j_ref(j, ref);
        } else if (!dims_of(c, dims)) {
            j_kraw(j, c->name, "false");
        } else {
            j_kopen(j, c->name, '{');
            dimension_properties(j, c->params, c->param_count, dims);
            j_close(j, '}');
        }
    }
    j_close(j, '}');
    j_kopen(j, "patternProperties", '{');
    j_key(j, pattern);
    if (!dims) {
        j_ref(j, "instance");
    } else {
        j_open(j, '{');
        j_kopen(j, "allOf", '[');
        for (size_t i = 0; i < set->count; i++) {
            const sluice_component *c = set->component[i];
            char if_text[300];
            snprintf(if_text, sizeof if_text,
                     "{\"properties\": {\"plugin\": {\"const\": \"%s\"}}, \"required\": "
                     "[\"plugin\"]}",
                     c->name);
            j_open(j, '{');
            j_kraw(j, "if", if_text);
            if (!dims_of(c, dims)) {
                j_kraw(j, "then", "false");
            } else {
                j_kopen(j, "then", '{');
                dimension_properties(j, c->params, c->param_count, dims);
                j_close(j, '}');
            }
            j_close(j, '}');
        }
        j_close(j, ']');
        j_close(j, '}');
    }
    j_close(j, '}');
    if (!dims)
        j_kraw(j, "additionalProperties", "false");
    j_close(j, '}');
}

/* ----------------------------------------------------------- top level -- */

static int section_required(const sluice_scene_table *t)
{
    for (uint32_t i = 0; i < t->count; i++)
        if (is_required(&t->specs[i]))
            return 1;
    return 0;
}

static const sluice_scene_table *find_section(const sluice_scene_format *f, const char *key)
{
    for (size_t i = 0; i < f->section_count; i++)
        if (strcmp(f->sections[i].name, key) == 0)
            return &f->sections[i];
    return NULL;
}

static void scalar_property(json *j, const char *key, const char *description)
{
    j_kopen(j, key, '{');
    j_kstring(j, "description", description);
    j_kraw(j, "type", SCALAR_TYPES);
    j_close(j, '}');
}

static void variants_property(json *j, const sluice_scene_format *f)
{
    j_kopen(j, "variants", '{');
    j_kstring(j, "description",
              "named variants of the scene, applied by --variant NAME: keys removed, plugins "
              "swapped, keys set (docs/scene-format.md, Variants)");
    j_kraw(j, "type", "[\"object\", \"null\"]");
    j_kraw(j, "propertyNames", "{\"minLength\": 1}");
    j_kopen(j, "additionalProperties", '{');
    j_kraw(j, "type", "[\"object\", \"null\"]");
    j_kopen(j, "properties", '{');
    for (size_t i = 0; i < f->variant_key_count; i++) {
        const char *key = f->variant_keys[i];
        if (strcmp(key, "description") == 0)
            scalar_property(j, key, "shown by sluice check and in the message for an unknown "
                                    "variant");
        else if (strcmp(key, "remove") == 0)
            j_kraw(j, key,
                   "{\"description\": \"dotted paths of keys to remove, e.g. "
                   "[plugins.two_phase, geometry.fluid.air]\", \"type\": [\"array\", \"null\"], "
                   "\"items\": {\"type\": \"string\", \"minLength\": 1}}");
        else if (strcmp(key, "swap") == 0)
            j_kraw(j, key,
                   "{\"description\": \"loaded plugin -> the plugin that replaces it with its "
                   "own defaults (its walls follow), e.g. {dbc: mdbc}\", \"type\": "
                   "[\"object\", \"null\"], \"additionalProperties\": {\"type\": \"string\"}}");
        else if (strcmp(key, "set") == 0)
            j_kraw(j, key,
                   "{\"description\": \"dotted path -> value, applied in order after the "
                   "removals and swaps, e.g. {plugins.tait.speed_of_sound: 28}\", \"type\": "
                   "[\"object\", \"null\"]}");
        else
            fail(j, "the variant key '%s' has no description in the schema generator", key);
    }
    j_close(j, '}');
    j_kraw(j, "additionalProperties", "false");
    j_close(j, '}');
    j_close(j, '}');
}

static void top_level_property(json *j, const char *key, const sluice_scene_format *f,
                               const plugin_set *set, const char *pattern)
{
    const sluice_scene_table *section = find_section(f, key);
    if (section) {
        key_list keys;
        if (table_keys(section, 0, &keys) != 0) {
            fail(j, "section '%s' has more than %d keys", key, KEYS_MAX);
            return;
        }
        object_form form = {NULL, NULL, NULL, NULL, !section_required(section), 0};
        j_key(j, key);
        object_schema(j, &keys, 0, &form);
    } else if (strcmp(key, "title") == 0) {
        scalar_property(j, key, "free text: the scene's title");
    } else if (strcmp(key, "description") == 0) {
        scalar_property(j, key, "free text");
    } else if (strcmp(key, "variant") == 0) {
        scalar_property(j, key, "written into scene.resolved.yaml: the variant it was made from "
                                "(no effect; not beside 'variants')");
    } else if (strcmp(key, "dimensions") == 0) {
        j_kraw(j, key, "{\"description\": \"spatial dimensions: 2 or 3\", \"enum\": [2, 3]}");
    } else if (strcmp(key, "plugin_path") == 0) {
        j_kraw(j, key,
               "{\"description\": \"extra plugin directories, ':'-separated, relative to the "
               "scene file; each must exist (their plugins are in this schema only when it was "
               "generated with them on SLUICE_PLUGIN_PATH)\", \"type\": \"string\"}");
    } else if (strcmp(key, "geometry") == 0) {
        j_key(j, key);
        j_ref(j, "geometry");
    } else if (strcmp(key, "plugins") == 0) {
        j_key(j, key);
        plugins_schema(j, set, pattern, 0);
    } else if (strcmp(key, "variants") == 0) {
        variants_property(j, f);
    } else {
        fail(j, "the top-level key '%s' has no description in the schema generator", key);
    }
}

/* if dimensions is dims then: the geometry of dims, the lengths of vectors
 * in the sections and plugins, the plugins of the other dimension refused */
static void dimension_branch(json *j, const sluice_scene_format *f, const plugin_set *set,
                             const char *pattern, int dims)
{
    char text[160], ref[64];
    j_open(j, '{');
    snprintf(text, sizeof text,
             "{\"properties\": {\"dimensions\": {\"const\": %d}}, \"required\": "
             "[\"dimensions\"]}",
             dims);
    j_kraw(j, "if", text);
    j_kopen(j, "then", '{');
    j_kopen(j, "properties", '{');
    snprintf(ref, sizeof ref, "geometry%s", dims_suffix(dims));
    j_key(j, "geometry");
    j_ref(j, ref);
    for (size_t i = 0; i < f->section_count; i++) {
        const sluice_scene_table *t = &f->sections[i];
        int any = 0;
        for (uint32_t k = 0; k < t->count; k++)
            any |= depends_on_dimensions(&t->specs[k]);
        if (!any)
            continue;
        j_kopen(j, t->name, '{');
        dimension_properties(j, t->specs, t->count, dims);
        j_close(j, '}');
    }
    j_key(j, "plugins");
    plugins_schema(j, set, pattern, dims);
    j_close(j, '}');
    j_close(j, '}');
    j_close(j, '}');
}

static void scene_schema(json *j, const sluice_scene_format *f, const plugin_set *set,
                         const char *pattern)
{
    char text[1024];
    j_open(j, '{');
    j_kstring(j, "$schema", "http://json-schema.org/draft-07/schema#");
    j_kstring(j, "title", "Sluice scene");
    snprintf(text, sizeof text,
             "A Sluice scene file (sluice %s, plugin ABI %d.%d; docs/scene-format.md), "
             "generated by 'sluice inspect --schema' from the core's key tables and the "
             "parameter tables of the %zu plugins on the plugin path. SI units; angles in "
             "degrees.",
             SLUICE_VERSION, SLUICE_ABI_MAJOR, SLUICE_ABI_MINOR, set->count);
    j_kstring(j, "description", text);
    j_kstring(j, "type", "object");
    j_kopen(j, "required", '[');
    j_string(j, "dimensions");
    for (size_t i = 0; i < f->section_count; i++)
        if (section_required(&f->sections[i]))
            j_string(j, f->sections[i].name);
    j_string(j, "plugins");
    j_close(j, ']');
    j_kopen(j, "properties", '{');
    for (size_t i = 0; i < f->top_level_count; i++)
        top_level_property(j, f->top_level_keys[i], f, set, pattern);
    j_close(j, '}');
    j_kraw(j, "additionalProperties", "false");
    j_kraw(j, "not", "{\"required\": [\"variant\", \"variants\"]}");
    j_kopen(j, "allOf", '[');
    dimension_branch(j, f, set, pattern, 2);
    dimension_branch(j, f, set, pattern, 3);
    j_close(j, ']');
    j_kopen(j, "definitions", '{');
    for (int dims = 0; dims <= 3; dims += dims ? 1 : 2)
        geometry_definitions(j, f, dims);
    piece_definitions(j, f);
    plugin_definitions(j, set);
    j_close(j, '}');
    j_close(j, '}');
    fputc('\n', j->out);
}

/* The schema into a memory buffer first: written whole or not at all. */
static int write_schema(FILE *out, const plugin_set *set)
{
    char *pattern = instance_pattern(set);
    char *text = NULL;
    size_t size = 0;
    FILE *memory = pattern ? open_memstream(&text, &size) : NULL;
    if (!memory) {
        free(pattern);
        fprintf(stderr, "sluice: error: out of memory writing the scene schema\n");
        return -1;
    }
    json j = {.out = memory};
    scene_schema(&j, sluice_scene_format_tables(), set, pattern);
    int failed = fclose(memory) != 0 || !text;
    free(pattern);
    if (j.problem[0] || failed) {
        fprintf(stderr, "sluice: error: cannot write the scene schema: %s\n",
                j.problem[0] ? j.problem : "out of memory");
        free(text);
        return -1;
    }
    int status = fwrite(text, 1, size, out) == size && fflush(out) == 0 ? 0 : -1;
    if (status)
        fprintf(stderr, "sluice: error: cannot write the scene schema to the output\n");
    free(text);
    return status;
}

int sluice_scene_schema(FILE *out)
{
    char **dirs = NULL;
    size_t count = 0;
    sluice_registry registry;
    if (sluice_registry_default_path(&dirs, &count, NULL, 0) != 0 ||
        sluice_registry_open(&registry, dirs, count) != 0) {
        fprintf(stderr, "sluice: error: out of memory scanning the plugin path\n");
        return -1;
    }
    for (size_t i = 0; i < registry.library_count; i++)
        if (registry.libraries[i].refusal)
            fprintf(stderr, "sluice: warning: %s %s; its plugins are not in the schema\n",
                    registry.libraries[i].path, registry.libraries[i].refusal);
    plugin_set set;
    int status = -1;
    if (plugin_set_open(&set, &registry) != 0)
        fprintf(stderr, "sluice: error: out of memory listing the plugins\n");
    else
        status = write_schema(out, &set);
    free(set.component);
    sluice_registry_close(&registry);
    return status;
}
