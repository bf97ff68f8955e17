/* Validation of a parameter mapping against a sluice_param_spec table. */
#include "schema.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------- scalars -- */

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

int sluice_parse_real(const char *text, double *out)
{
    if (!text || !*text || is_space(text[0]))
        return -1;
    for (const char *c = text; *c; c++)
        if (*c == 'x' || *c == 'X') /* no hexadecimal floats */
            return -1;
    char *end = NULL;
    double value = strtod(text, &end);
    if (end == text || *end != '\0' || !isfinite(value))
        return -1;
    *out = value;
    return 0;
}

int sluice_parse_int(const char *text, long long *out)
{
    if (!text || !*text || is_space(text[0]))
        return -1;
    char *end = NULL;
    errno = 0;
    long long value = strtoll(text, &end, 10);
    if (end != text && *end == '\0') {
        if (errno == ERANGE)
            return -1;
        *out = value;
        return 0;
    }
    /* "1e3" or "2.0": a number with an integral value */
    double real;
    if (sluice_parse_real(text, &real) != 0 || real != floor(real) ||
        real < -9223372036854775808.0 || real >= 9223372036854775808.0)
        return -1;
    *out = (long long)real;
    return 0;
}

static int same_word(const char *text, const char *word)
{
    for (; *text && *word; text++, word++) {
        char c = *text >= 'A' && *text <= 'Z' ? (char)(*text - 'A' + 'a') : *text;
        if (c != *word)
            return 0;
    }
    return !*text && !*word;
}

int sluice_parse_bool(const char *text, int *out)
{
    static const char *const yes[] = {"true", "yes", "on"};
    static const char *const no[] = {"false", "no", "off"};
    if (!text)
        return -1;
    for (size_t i = 0; i < 3; i++) {
        if (same_word(text, yes[i])) {
            *out = 1;
            return 0;
        }
        if (same_word(text, no[i])) {
            *out = 0;
            return 0;
        }
    }
    return -1;
}

/* ---------------------------------------------------------- describing -- */

/* Shortest "%g" text that reads back as the same double. */
static const char *format_number(double value, char *buffer, size_t size)
{
    snprintf(buffer, size, "%.15g", value);
    if (strtod(buffer, NULL) != value)
        snprintf(buffer, size, "%.17g", value);
    return buffer;
}

static int has_unit(const char *unit)
{
    return unit && *unit && strcmp(unit, "1") != 0;
}

/* " > 0", " >= 1", " in [1, 10]", " in (0, 10]"; "" without bounds. */
static const char *range_text(const sluice_param_spec *s, char *buffer, size_t size)
{
    char lo[40], hi[40];
    int has_min = (s->flags & SLUICE_PARAM_HAS_MIN) != 0;
    int has_max = (s->flags & SLUICE_PARAM_HAS_MAX) != 0;
    int min_open = (s->flags & SLUICE_PARAM_MIN_EXCLUSIVE) != 0;
    int max_open = (s->flags & SLUICE_PARAM_MAX_EXCLUSIVE) != 0;
    format_number(s->min, lo, sizeof lo);
    format_number(s->max, hi, sizeof hi);
    if (has_min && has_max)
        snprintf(buffer, size, " in %c%s, %s%c", min_open ? '(' : '[', lo, hi,
                 max_open ? ')' : ']');
    else if (has_min)
        snprintf(buffer, size, " %s %s", min_open ? ">" : ">=", lo);
    else if (has_max)
        snprintf(buffer, size, " %s %s", max_open ? "<" : "<=", hi);
    else if (size)
        buffer[0] = '\0';
    return buffer;
}

/* The type without its unit, e.g. "number > 0". */
static void describe_type(const sluice_param_spec *s, char *buffer, size_t size)
{
    char range[100];
    range_text(s, range, sizeof range);
    switch (s->type) {
    case SLUICE_PARAM_REAL: snprintf(buffer, size, "number%s", range); break;
    case SLUICE_PARAM_INT: snprintf(buffer, size, "integer%s", range); break;
    case SLUICE_PARAM_BOOL: snprintf(buffer, size, "boolean"); break;
    case SLUICE_PARAM_STRING: snprintf(buffer, size, "string"); break;
    case SLUICE_PARAM_ENUM: {
        size_t pos = (size_t)snprintf(buffer, size, "one of: ");
        for (const char *c = s->choices ? s->choices : ""; *c && pos + 3 < size; c++) {
            if (*c == '|') {
                buffer[pos++] = ',';
                buffer[pos++] = ' ';
            } else {
                buffer[pos++] = *c;
            }
        }
        if (pos < size)
            buffer[pos] = '\0';
        break;
    }
    case SLUICE_PARAM_VECTOR:
        if (s->length == SLUICE_LENGTH_DIM)
            snprintf(buffer, size, "vector of D numbers%s", range);
        else
            snprintf(buffer, size, "vector of %u number%s%s", (unsigned)s->length,
                     s->length == 1 ? "" : "s", range);
        break;
    case SLUICE_PARAM_REAL_LIST: snprintf(buffer, size, "list of numbers%s", range); break;
    case SLUICE_PARAM_POINT_LIST:
        snprintf(buffer, size, "list of points%s%s", range[0] ? ", coordinates" : "", range);
        break;
    default: snprintf(buffer, size, "parameter of unknown type %d", (int)s->type); break;
    }
}

const char *sluice_schema_describe(const sluice_param_spec *spec, char *buffer, size_t size)
{
    if (!buffer || size == 0)
        return buffer;
    char type[400];
    describe_type(spec, type, sizeof type);
    if (has_unit(spec->unit))
        snprintf(buffer, size, "%s (%s)", type, spec->unit);
    else
        snprintf(buffer, size, "%s", type);
    return buffer;
}

/* ---------------------------------------------------------- converting -- */

/* One conversion of a node to a parameter value; on failure `where` and
 * `text` hold the message. */
typedef struct conversion {
    const sluice_param_spec *spec;
    uint32_t dimensions;
    sluice_arena *arena;
    const sluice_node *where;
    char text[1024];
} conversion;

typedef union param_value {
    sluice_real real;
    int64_t integer;
    int flag; /* BOOL, ENUM */
    const char *string;
    sluice_real vector[3];
    sluice_real_list list;
} param_value;

static int fail(conversion *c, const sluice_node *node, const char *format, ...)
    SLUICE_PRINTF(3, 4);
static int fail(conversion *c, const sluice_node *node, const char *format, ...)
{
    va_list ap;
    va_start(ap, format);
    vsnprintf(c->text, sizeof c->text, format, ap);
    va_end(ap);
    c->where = node;
    return -1;
}

/* What a node is, for "got ..." */
static const char *node_text(const sluice_node *node, char *buffer, size_t size)
{
    if (node->kind == SLUICE_NODE_SEQUENCE)
        return "a list";
    if (node->kind == SLUICE_NODE_MAPPING)
        return "a mapping";
    const char *v = node->value ? node->value : "";
    int long_text = strlen(v) > 60;
    if (node->plain && !*v)
        return "an empty value";
    if (node->plain)
        snprintf(buffer, size, "'%.60s%s'", v, long_text ? "..." : "");
    else
        snprintf(buffer, size, "the string \"%.60s%s\"", v, long_text ? "..." : "");
    return buffer;
}

static int wrong_type(conversion *c, const sluice_node *node, const char *path,
                      const char *expected)
{
    char got[100];
    return fail(c, node, "wrong type for %s: expected %s, got %s", path, expected,
                node_text(node, got, sizeof got));
}

static const char *unit_suffix(const sluice_param_spec *s, char *buffer, size_t size)
{
    if (has_unit(s->unit))
        snprintf(buffer, size, " %s", s->unit);
    else if (size)
        buffer[0] = '\0';
    return buffer;
}

static int check_range(conversion *c, const sluice_node *node, const char *path, double value)
{
    const sluice_param_spec *s = c->spec;
    int below = 0, above = 0;
    if (s->flags & SLUICE_PARAM_HAS_MIN)
        below = (s->flags & SLUICE_PARAM_MIN_EXCLUSIVE) ? !(value > s->min) : !(value >= s->min);
    if (s->flags & SLUICE_PARAM_HAS_MAX)
        above = (s->flags & SLUICE_PARAM_MAX_EXCLUSIVE) ? !(value < s->max) : !(value <= s->max);
    if (!below && !above)
        return 0;
    char range[100], unit[64];
    range_text(s, range, sizeof range);
    unit_suffix(s, unit, sizeof unit);
    return fail(c, node, "%s = %s%s is out of range: it must be%s%s", path, node->value, unit,
                range, unit);
}

static int read_real(conversion *c, const sluice_node *node, const char *path, sluice_real *out)
{
    double value;
    if (node->kind != SLUICE_NODE_SCALAR || !node->plain ||
        sluice_parse_real(node->value, &value) != 0)
        return wrong_type(c, node, path, "a number");
    if (check_range(c, node, path, value) != 0)
        return -1;
    *out = (sluice_real)value;
    return 0;
}

/* Splits "a|b|c" into a malloc'd array of names (in one block). */
static const char **split_choices(const char *choices, size_t *count)
{
    const char *text = choices ? choices : "";
    size_t n = 1, length = strlen(text);
    for (const char *p = text; *p; p++)
        n += *p == '|';
    const char **names = malloc(n * sizeof *names + length + 1);
    if (!names)
        return NULL;
    char *copy = (char *)(names + n);
    memcpy(copy, text, length + 1);
    n = 0;
    names[n++] = copy;
    for (char *p = copy; *p; p++)
        if (*p == '|') {
            *p = '\0';
            names[n++] = p + 1;
        }
    *count = n;
    return names;
}

static int read_enum(conversion *c, const sluice_node *node, const char *path, int *out)
{
    char expected[400];
    describe_type(c->spec, expected, sizeof expected);
    if (node->kind != SLUICE_NODE_SCALAR)
        return wrong_type(c, node, path, expected);
    size_t count = 0;
    const char **names = split_choices(c->spec->choices, &count);
    if (!names)
        return fail(c, node, "out of memory while checking %s", path);
    for (size_t i = 0; i < count; i++)
        if (strcmp(node->value, names[i]) == 0) {
            free(names);
            *out = (int)i;
            return 0;
        }
    const char *close = sluice_closest(node->value, names, count);
    if (close)
        fail(c, node, "invalid value '%.60s' for %s; did you mean '%s'?", node->value, path,
             close);
    else
        fail(c, node, "invalid value '%.60s' for %s: expected %s", node->value, path, expected);
    free(names);
    return -1;
}

static int read_vector(conversion *c, const sluice_node *node, const char *path,
                       sluice_real out[3])
{
    const sluice_param_spec *s = c->spec;
    uint32_t n = s->length == SLUICE_LENGTH_DIM ? c->dimensions : s->length;
    if (n < 1 || n > 3)
        return fail(c, node, "%s is declared as a vector of %u numbers; vectors have 1 to 3",
                    path, (unsigned)n);
    char expected[64];
    snprintf(expected, sizeof expected, "a list of %u number%s", (unsigned)n, n == 1 ? "" : "s");
    if (node->kind != SLUICE_NODE_SEQUENCE)
        return wrong_type(c, node, path, expected);
    if (node->count != n)
        return fail(c, node, "wrong length for %s: expected %u number%s%s, got %zu", path,
                    (unsigned)n, n == 1 ? "" : "s",
                    s->length == SLUICE_LENGTH_DIM
                        ? (c->dimensions == 2 ? " (one per dimension of the 2D scene)"
                                              : " (one per dimension of the 3D scene)")
                        : "",
                    node->count);
    out[0] = out[1] = out[2] = 0;
    for (uint32_t i = 0; i < n; i++) {
        char item[600];
        snprintf(item, sizeof item, "%s.%u", path, (unsigned)i);
        if (read_real(c, node->items[i], item, &out[i]) != 0)
            return -1;
    }
    return 0;
}

static sluice_real *list_alloc(conversion *c, size_t count)
{
    if (count > SIZE_MAX / sizeof(sluice_real) || count > UINT32_MAX)
        return NULL;
    return sluice_arena_alloc(c->arena, count * sizeof(sluice_real));
}

static int read_real_list(conversion *c, const sluice_node *node, const char *path,
                          sluice_real_list *out)
{
    if (node->kind != SLUICE_NODE_SEQUENCE)
        return wrong_type(c, node, path, "a list of numbers");
    sluice_real *values = NULL;
    if (node->count) {
        values = list_alloc(c, node->count);
        if (!values)
            return fail(c, node, "out of memory reading %s", path);
    }
    for (size_t i = 0; i < node->count; i++) {
        char item[600];
        snprintf(item, sizeof item, "%s.%zu", path, i);
        if (read_real(c, node->items[i], item, &values[i]) != 0)
            return -1;
    }
    out->values = values;
    out->count = (uint32_t)node->count;
    return 0;
}

static int read_point_list(conversion *c, const sluice_node *node, const char *path,
                           sluice_real_list *out)
{
    /* points of the scene's dimensions, or of the spec's length (a 2D
     * outline in a 3D scene) */
    uint32_t d = c->spec->length ? c->spec->length : c->dimensions;
    char expected[100];
    snprintf(expected, sizeof expected, "a list of points, each a list of %u numbers",
             (unsigned)d);
    if (node->kind != SLUICE_NODE_SEQUENCE)
        return wrong_type(c, node, path, expected);
    if (d < 1 || d > 3)
        return fail(c, node, "%s needs the scene dimensions (2 or 3), got %u", path, (unsigned)d);
    sluice_real *values = NULL;
    if (node->count) {
        values = node->count <= SIZE_MAX / 3 ? list_alloc(c, 3 * node->count) : NULL;
        if (!values)
            return fail(c, node, "out of memory reading %s", path);
    }
    for (size_t i = 0; i < node->count; i++) {
        const sluice_node *point = node->items[i];
        char item[600];
        snprintf(item, sizeof item, "%s.%zu", path, i);
        snprintf(expected, sizeof expected, "a point (a list of %u numbers)", (unsigned)d);
        if (point->kind != SLUICE_NODE_SEQUENCE)
            return wrong_type(c, point, item, expected);
        if (point->count != d)
            return fail(c, point,
                        "wrong length for %s: expected a point of %u numbers (the scene is "
                        "%uD), got %zu",
                        item, (unsigned)d, (unsigned)d, point->count);
        for (uint32_t k = 0; k < d; k++) {
            char coordinate[620];
            snprintf(coordinate, sizeof coordinate, "%s.%u", item, (unsigned)k);
            if (read_real(c, point->items[k], coordinate, &values[3 * i + k]) != 0)
                return -1;
        }
    }
    out->values = values;
    out->count = (uint32_t)node->count;
    return 0;
}

/* Converts node to the spec's value. 0 or -1 (message in c). */
static int convert(conversion *c, const sluice_node *node, const char *path, param_value *out)
{
    const sluice_param_spec *s = c->spec;
    memset(out, 0, sizeof *out);
    switch (s->type) {
    case SLUICE_PARAM_REAL:
        return read_real(c, node, path, &out->real);
    case SLUICE_PARAM_INT: {
        long long value;
        if (node->kind != SLUICE_NODE_SCALAR || !node->plain ||
            sluice_parse_int(node->value, &value) != 0)
            return wrong_type(c, node, path, "an integer");
        if (check_range(c, node, path, (double)value) != 0)
            return -1;
        out->integer = (int64_t)value;
        return 0;
    }
    case SLUICE_PARAM_BOOL:
        if (node->kind != SLUICE_NODE_SCALAR || !node->plain ||
            sluice_parse_bool(node->value, &out->flag) != 0)
            return wrong_type(c, node, path, "a boolean (true or false)");
        return 0;
    case SLUICE_PARAM_STRING:
        if (node->kind != SLUICE_NODE_SCALAR)
            return wrong_type(c, node, path, "a string");
        out->string = sluice_arena_strdup(c->arena, node->value ? node->value : "");
        return out->string ? 0 : fail(c, node, "out of memory reading %s", path);
    case SLUICE_PARAM_ENUM:
        return read_enum(c, node, path, &out->flag);
    case SLUICE_PARAM_VECTOR:
        return read_vector(c, node, path, out->vector);
    case SLUICE_PARAM_REAL_LIST:
        return read_real_list(c, node, path, &out->list);
    case SLUICE_PARAM_POINT_LIST:
        return read_point_list(c, node, path, &out->list);
    }
    return fail(c, node, "%s has an unknown parameter type %d", path, (int)s->type);
}

static void store(const sluice_param_spec *s, void *config, const param_value *v)
{
    unsigned char *at = (unsigned char *)config + s->offset;
    switch (s->type) {
    case SLUICE_PARAM_REAL: memcpy(at, &v->real, sizeof v->real); break;
    case SLUICE_PARAM_INT: memcpy(at, &v->integer, sizeof v->integer); break;
    case SLUICE_PARAM_BOOL:
    case SLUICE_PARAM_ENUM: memcpy(at, &v->flag, sizeof v->flag); break;
    case SLUICE_PARAM_STRING: memcpy(at, &v->string, sizeof v->string); break;
    case SLUICE_PARAM_VECTOR: memcpy(at, v->vector, sizeof v->vector); break;
    case SLUICE_PARAM_REAL_LIST:
    case SLUICE_PARAM_POINT_LIST: memcpy(at, &v->list, sizeof v->list); break;
    }
}

/* -------------------------------------------------------------- binding -- */

typedef struct binder {
    const sluice_param_spec *specs;
    uint32_t count;
    const sluice_node *owner;
    const char *path; /* "" at the top level */
    uint32_t dimensions;
    sluice_arena *arena;
    sluice_diag *diag;
    int errors;
    const char *reserved; /* a key the caller reads itself (NULL: none) */
} binder;

static void error_at(binder *b, const sluice_node *node, const char *format, ...)
    SLUICE_PRINTF(3, 4);
static void error_at(binder *b, const sluice_node *node, const char *format, ...)
{
    char text[2048];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    sluice_diag_add(b->diag, SLUICE_SEVERITY_ERROR, node ? node->file : NULL,
                    node ? node->line : 0, node ? node->column : 0, "%s", text);
    b->errors++;
}

/* "in plugins.tait" or "at the top level" */
static const char *where_text(const binder *b, char *buffer, size_t size)
{
    if (b->path[0])
        snprintf(buffer, size, "in %s", b->path);
    else
        snprintf(buffer, size, "at the top level");
    return buffer;
}

static void parameter_path(const binder *b, const char *name, char *buffer, size_t size)
{
    snprintf(buffer, size, "%s%s%s", b->path, b->path[0] ? "." : "", name);
}

static int is_empty_plain(const sluice_node *node)
{
    return node->kind == SLUICE_NODE_SCALAR && node->plain && node->value && !node->value[0];
}

static int known_key(const binder *b, const char *key)
{
    if (b->reserved && strcmp(b->reserved, key) == 0)
        return 1;
    for (uint32_t i = 0; i < b->count; i++)
        if (b->specs[i].name && strcmp(b->specs[i].name, key) == 0)
            return 1;
    return 0;
}

/* The spec names (NULL names skipped); NULL when out of memory. */
static const char **spec_names(const binder *b, size_t *count)
{
    const char **names = malloc((b->count ? b->count : 1) * sizeof *names);
    size_t n = 0;
    for (uint32_t i = 0; names && i < b->count; i++)
        if (b->specs[i].name)
            names[n++] = b->specs[i].name;
    *count = n;
    return names;
}

/* The valid name an unknown key is a plausible typo of, or else the one
 * valid name that is the key with a suffix `_...` (a key renamed with its
 * unit, as dbc's `phase` became `phase_deg`), or NULL. */
static const char *suggestion(const binder *b, const sluice_node *key)
{
    size_t n;
    const char **names = spec_names(b, &n);
    const char *close = names ? sluice_closest(key->value, names, n) : NULL;
    size_t length = strlen(key->value), extended = 0;
    const char *longer = NULL;
    for (size_t i = 0; names && !close && i < n; i++)
        if (strncmp(names[i], key->value, length) == 0 && names[i][length] == '_') {
            longer = names[i];
            extended++;
        }
    if (!close && extended == 1)
        close = longer;
    free(names);
    return close;
}

static void report_unknown_key(binder *b, const sluice_node *key)
{
    char where[600];
    where_text(b, where, sizeof where);
    const char *close = suggestion(b, key);
    size_t n = 0;
    const char **names = close ? NULL : spec_names(b, &n);
    if (close) {
        error_at(b, key, "unknown key '%s' %s; did you mean '%s'?", key->value, where, close);
    } else if (!names) {
        error_at(b, key, "unknown key '%s' %s", key->value, where);
    } else if (n == 0) {
        error_at(b, key, "unknown key '%s' %s, which takes no parameters", key->value, where);
    } else {
        char valid[1024];
        size_t pos = 0;
        valid[0] = '\0';
        for (size_t i = 0; i < n && pos < sizeof valid; i++) {
            int w = snprintf(valid + pos, sizeof valid - pos, "%s%s", i ? ", " : "", names[i]);
            if (w < 0)
                break;
            pos += (size_t)w;
        }
        error_at(b, key, "unknown key '%s' %s (valid keys: %s)", key->value, where, valid);
    }
    free(names);
}

/* Whether an unknown key of the section was reported as a typo of `name`
 * (then "missing" would only repeat that message). */
static int suggested_for(const binder *b, const sluice_node *section, const char *name)
{
    if (!section || section->kind != SLUICE_NODE_MAPPING)
        return 0;
    for (size_t i = 0; i < section->count; i++) {
        const sluice_node *key = section->keys[i];
        if (key->kind == SLUICE_NODE_SCALAR && !known_key(b, key->value)) {
            const char *close = suggestion(b, key);
            if (close && strcmp(close, name) == 0)
                return 1;
        }
    }
    return 0;
}

static void report_missing(binder *b, const sluice_param_spec *s)
{
    char where[600], type[400];
    where_text(b, where, sizeof where);
    describe_type(s, type, sizeof type);
    const char *unit = has_unit(s->unit) ? s->unit : NULL;
    const char *doc = s->doc && *s->doc ? s->doc : NULL;
    error_at(b, b->owner, "missing required parameter '%s' %s (%s%s%s)%s%s", s->name, where, type,
             unit ? ", " : "", unit ? unit : "", doc ? ": " : "", doc ? doc : "");
}

static void zero_positions(sluice_node *node)
{
    node->line = node->column = 0;
    for (size_t i = 0; i < node->count; i++) {
        zero_positions(node->items[i]);
        if (node->keys)
            zero_positions(node->keys[i]);
    }
}

/* Parses the spec's default for the scene's dimensions: "2D | 3D" or one
 * text for both. NULL after reporting. */
static sluice_node *parse_default(binder *b, const sluice_param_spec *s, const char *full)
{
    const char *text = s->default_value;
    size_t length = strlen(text);
    const char *bar = strstr(text, " | ");
    if (bar) {
        if (b->dimensions == 2) {
            length = (size_t)(bar - text);
        } else {
            text = bar + 3;
            length = strlen(text);
        }
    }
    while (length && is_space(*text)) {
        text++;
        length--;
    }
    while (length && is_space(text[length - 1]))
        length--;
    sluice_node *node;
    if (length == 0) {
        node = sluice_node_new_scalar("", 1, "default", 0, 0);
        if (!node)
            error_at(b, b->owner, "out of memory reading the default of %s", full);
        return node;
    }
    sluice_diag *inner = sluice_diag_create();
    if (!inner) {
        error_at(b, b->owner, "out of memory reading the default of %s", full);
        return NULL;
    }
    node = sluice_yaml_parse_string(text, length, "default", inner);
    if (!node) {
        /* the reason without its "default:1:4: error: " prefix */
        const char *why = sluice_diag_count(inner) ? sluice_diag_message(inner, 0) : NULL;
        const char *text_start = why ? strstr(why, "error: ") : NULL;
        why = text_start ? text_start + strlen("error: ") : why ? why : "unknown problem";
        error_at(b, b->owner, "invalid default '%.*s' for %s in the parameter table: %s",
                 (int)length, text, full, why);
    } else {
        zero_positions(node);
    }
    sluice_diag_destroy(inner);
    return node;
}

/* Inserts the default node into the section, creating the mapping when the
 * section is absent or an empty plain scalar. Takes ownership of node. */
static void insert_default(binder *b, sluice_node **section, const char *name, sluice_node *node,
                           const char *full)
{
    if (!section) {
        sluice_node_free(node);
        return;
    }
    sluice_node *old = *section;
    if (!old || is_empty_plain(old)) {
        sluice_node *mapping = old ? sluice_node_new_mapping(old->file, old->line, old->column)
                                   : sluice_node_new_mapping("default", 0, 0);
        if (!mapping) {
            sluice_node_free(node);
            error_at(b, b->owner, "out of memory inserting the default of %s", full);
            return;
        }
        mapping->used = 1;
        sluice_node_free(old);
        *section = mapping;
    }
    sluice_node_mark_used(node, 1);
    if (sluice_node_set(*section, name, node) != 0) {
        error_at(b, b->owner, "out of memory inserting the default of %s", full);
        return;
    }
    sluice_node *key = sluice_node_get_key(*section, name);
    if (key)
        key->used = 1;
}

int sluice_schema_bind(const sluice_param_spec *specs, uint32_t spec_count, sluice_node **section,
                       const sluice_node *owner, const char *path, uint32_t dimensions,
                       void *config, sluice_arena *arena, sluice_diag *diag)
{
    return sluice_schema_bind_except(specs, spec_count, section, owner, path, dimensions, config,
                                     arena, diag, NULL);
}

int sluice_schema_bind_except(const sluice_param_spec *specs, uint32_t spec_count,
                              sluice_node **section, const sluice_node *owner, const char *path,
                              uint32_t dimensions, void *config, sluice_arena *arena,
                              sluice_diag *diag, const char *reserved)
{
    binder b = {specs, spec_count, owner, path ? path : "", dimensions, arena, diag, 0, reserved};
    sluice_node *sec = section ? *section : NULL;
    if (sec && sec->kind != SLUICE_NODE_MAPPING && !is_empty_plain(sec)) {
        if (b.path[0])
            error_at(&b, sec, "%s must be a mapping of parameters", b.path);
        else
            error_at(&b, sec, "the document must be a mapping of parameters");
        return b.errors;
    }
    if (sec) {
        sec->used = 1;
        if (sec->kind == SLUICE_NODE_MAPPING)
            for (size_t i = 0; i < sec->count; i++) {
                sluice_node_mark_used(sec->keys[i], 1);
                sluice_node_mark_used(sec->items[i], 1);
                if (sec->keys[i]->kind == SLUICE_NODE_SCALAR &&
                    !known_key(&b, sec->keys[i]->value))
                    report_unknown_key(&b, sec->keys[i]);
            }
    }
    for (uint32_t i = 0; i < spec_count; i++) {
        const sluice_param_spec *s = &specs[i];
        if (!s->name)
            continue;
        char full[600];
        parameter_path(&b, s->name, full, sizeof full);
        conversion c;
        c.spec = s;
        c.dimensions = dimensions;
        c.arena = arena;
        c.where = NULL;
        c.text[0] = '\0';
        param_value value;
        const sluice_node *node = sec ? sluice_node_get(sec, s->name) : NULL;
        if (node) {
            if (convert(&c, node, full, &value) != 0)
                error_at(&b, c.where, "%s", c.text);
            else
                store(s, config, &value);
        } else if (s->default_value) {
            sluice_node *fallback = parse_default(&b, s, full);
            if (!fallback)
                continue;
            if (convert(&c, fallback, full, &value) != 0) {
                error_at(&b, b.owner, "invalid default '%s' for %s in the parameter table: %s",
                         s->default_value, full, c.text);
                sluice_node_free(fallback);
                continue;
            }
            store(s, config, &value);
            insert_default(&b, section, s->name, fallback, full);
            sec = section ? *section : NULL;
        } else if (!(s->flags & SLUICE_PARAM_OPTIONAL) && !suggested_for(&b, sec, s->name)) {
            report_missing(&b, s);
        }
    }
    return b.errors;
}
