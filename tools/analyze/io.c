/* I/O of sluice-analyze (see io.h). */
#define _GNU_SOURCE
#include "io.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <yaml.h>

int analyze_fail(analyze_ctx *cx, int status, const char *format, ...)
{
    if (cx->status == SLUICE_ANALYZE_OK) {
        va_list ap;
        va_start(ap, format);
        vsnprintf(cx->message, sizeof cx->message, format, ap);
        va_end(ap);
        cx->status = status;
    }
    return -1;
}

void *analyze_alloc(analyze_ctx *cx, size_t count, size_t size)
{
    void *p = calloc(count ? count : 1, size ? size : 1);
    if (!p)
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
    return p;
}

char *analyze_format(analyze_ctx *cx, const char *format, ...)
{
    char *text = NULL;
    va_list ap;
    va_start(ap, format);
    int n = vasprintf(&text, format, ap);
    va_end(ap);
    if (n < 0) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
        return NULL;
    }
    return text;
}

int analyze_file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* ------------------------------------------------------------------ CSV -- */

static char *read_all(analyze_ctx *cx, const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "cannot read %s: %s", path, strerror(errno));
        return NULL;
    }
    size_t cap = 1 << 16, used = 0;
    char *text = malloc(cap);
    if (!text) {
        fclose(f);
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
        return NULL;
    }
    size_t n;
    while ((n = fread(text + used, 1, cap - used - 1, f)) > 0) {
        used += n;
        if (cap - used - 1 == 0) {
            char *bigger = realloc(text, cap * 2);
            if (!bigger) {
                free(text);
                fclose(f);
                analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
                return NULL;
            }
            text = bigger;
            cap *= 2;
        }
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(text);
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "cannot read %s", path);
        return NULL;
    }
    text[used] = '\0';
    *size = used;
    return text;
}

static char *trim(char *s)
{
    while (*s && isspace((unsigned char)*s))
        s++;
    char *end = s + strlen(s);
    while (end > s && isspace((unsigned char)end[-1]))
        *--end = '\0';
    return s;
}

/* Next non-blank, non-comment line of text (modified in place), or NULL. */
static char *next_line(char **cursor, size_t *line_number)
{
    while (*cursor && **cursor) {
        char *line = *cursor;
        char *end = strchr(line, '\n');
        if (end) {
            *end = '\0';
            *cursor = end + 1;
        } else {
            *cursor = line + strlen(line);
        }
        (*line_number)++;
        char *t = trim(line);
        if (*t && *t != '#')
            return t;
    }
    return NULL;
}

int analyze_table_load(analyze_ctx *cx, const char *path, analyze_table *table)
{
    memset(table, 0, sizeof *table);
    size_t size;
    char *text = read_all(cx, path, &size);
    if (!text)
        return -1;
    table->path = strdup(path);
    if (!table->path) {
        free(text);
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
    }
    char *cursor = text;
    size_t line_number = 0;
    char *header = next_line(&cursor, &line_number);
    if (!header) {
        free(text);
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s is empty (no header line)", path);
    }
    size_t cols = 1;
    for (const char *p = header; *p; p++)
        cols += *p == ',';
    table->names = analyze_alloc(cx, cols, sizeof *table->names);
    if (!table->names) {
        free(text);
        return -1;
    }
    table->cols = cols;
    char *field = header;
    for (size_t c = 0; c < cols; c++) {
        char *comma = strchr(field, ',');
        if (comma)
            *comma = '\0';
        table->names[c] = strdup(trim(field));
        if (!table->names[c]) {
            free(text);
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
        }
        field = comma ? comma + 1 : field + strlen(field);
    }
    size_t cap = 1024;
    table->data = malloc(cap * cols * sizeof *table->data);
    if (!table->data) {
        free(text);
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
    }
    char *line;
    while ((line = next_line(&cursor, &line_number))) {
        if (table->rows == cap) {
            double *bigger = realloc(table->data, 2 * cap * cols * sizeof *bigger);
            if (!bigger) {
                free(text);
                return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
            }
            table->data = bigger;
            cap *= 2;
        }
        size_t fields = 1;
        for (const char *q = line; *q; q++)
            fields += *q == ',';
        if (fields != cols) {
            free(text);
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "%s:%zu: %zu fields, the header has %zu", path, line_number,
                                fields, cols);
        }
        double *row = table->data + table->rows * cols;
        char *p = line;
        for (size_t c = 0; c < cols; c++) {
            char *end;
            errno = 0;
            double v = strtod(p, &end);
            while (*end == ' ' || *end == '\t' || *end == '\r')
                end++;
            if (end == p || (*end != ',' && *end != '\0')) {
                free(text);
                return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                    "%s:%zu: field %zu (%s) is not a number", path,
                                    line_number, c + 1, table->names[c]);
            }
            row[c] = v;
            p = *end == ',' ? end + 1 : end;
        }
        table->rows++;
    }
    free(text);
    return 0;
}

void analyze_table_free(analyze_table *table)
{
    if (table->names)
        for (size_t c = 0; c < table->cols; c++)
            free(table->names[c]);
    free(table->names);
    free(table->data);
    free(table->path);
    memset(table, 0, sizeof *table);
}

long analyze_table_find(const analyze_table *table, const char *name)
{
    for (size_t c = 0; c < table->cols; c++)
        if (strcmp(table->names[c], name) == 0)
            return (long)c;
    return -1;
}

long analyze_table_column(analyze_ctx *cx, const analyze_table *table, const char *name)
{
    long c = analyze_table_find(table, name);
    if (c < 0) {
        char list[256] = "";
        size_t used = 0;
        for (size_t k = 0; k < table->cols && used + 1 < sizeof list; k++) {
            int w = snprintf(list + used, sizeof list - used, "%s%s", k ? ", " : "",
                             table->names[k]);
            if (w < 0)
                break;
            used += (size_t)w;
        }
        if (used + 1 >= sizeof list)
            strcpy(list + sizeof list - 5, "...");
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s has no column '%s' (columns: %s)",
                     table->path, name, list);
    }
    return c;
}

void analyze_table_copy(const analyze_table *table, size_t c, double *out)
{
    for (size_t r = 0; r < table->rows; r++)
        out[r] = table->data[r * table->cols + c];
}

/* ---------------------------------------------------------------- scene -- */

struct analyze_scene {
    char *path;
    yaml_document_t document;
};

int analyze_scene_load(analyze_ctx *cx, const char *path, analyze_scene **scene)
{
    *scene = NULL;
    FILE *f = fopen(path, "rb");
    if (!f)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "cannot read %s: %s", path,
                            strerror(errno));
    analyze_scene *s = analyze_alloc(cx, 1, sizeof *s);
    if (!s) {
        fclose(f);
        return -1;
    }
    s->path = strdup(path);
    yaml_parser_t parser;
    if (!s->path || !yaml_parser_initialize(&parser)) {
        free(s->path);
        free(s);
        fclose(f);
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
    }
    yaml_parser_set_input_file(&parser, f);
    int ok = yaml_parser_load(&parser, &s->document);
    if (!ok)
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s:%zu: %s", path,
                     parser.problem_mark.line + 1,
                     parser.problem ? parser.problem : "YAML error");
    yaml_parser_delete(&parser);
    fclose(f);
    if (!ok) {
        free(s->path);
        free(s);
        return -1;
    }
    *scene = s;
    return 0;
}

void analyze_scene_free(analyze_scene *scene)
{
    if (!scene)
        return;
    yaml_document_delete(&scene->document);
    free(scene->path);
    free(scene);
}

static yaml_node_t *map_get(yaml_document_t *d, yaml_node_t *map, const char *key)
{
    if (!map || map->type != YAML_MAPPING_NODE)
        return NULL;
    for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top;
         p++) {
        yaml_node_t *k = yaml_document_get_node(d, p->key);
        if (k && k->type == YAML_SCALAR_NODE &&
            strcmp((const char *)k->data.scalar.value, key) == 0)
            return yaml_document_get_node(d, p->value);
    }
    return NULL;
}

static yaml_node_t *plugin_key(const analyze_scene *scene, const char *plugin, const char *key)
{
    if (!scene)
        return NULL;
    yaml_document_t *d = (yaml_document_t *)&scene->document;
    yaml_node_t *root = yaml_document_get_root_node(d);
    yaml_node_t *node = map_get(d, map_get(d, root, "plugins"), plugin);
    return key ? map_get(d, node, key) : node;
}

int analyze_scene_has(const analyze_scene *scene, const char *plugin)
{
    return plugin_key(scene, plugin, NULL) != NULL;
}

const char *analyze_scene_string(const analyze_scene *scene, const char *plugin, const char *key)
{
    yaml_node_t *n = plugin_key(scene, plugin, key);
    if (!n || n->type != YAML_SCALAR_NODE || n->data.scalar.length == 0)
        return NULL;
    return (const char *)n->data.scalar.value;
}

static int scalar_number(yaml_node_t *n, double *value)
{
    if (!n || n->type != YAML_SCALAR_NODE)
        return -1;
    const char *text = (const char *)n->data.scalar.value;
    char *end;
    *value = strtod(text, &end);
    return end != text && *end == '\0' ? 0 : -1;
}

int analyze_scene_number(const analyze_scene *scene, const char *plugin, const char *key,
                         double *value)
{
    return scene ? scalar_number(plugin_key(scene, plugin, key), value) : -1;
}

int analyze_scene_setting(const analyze_scene *scene, const char *section, const char *key,
                          double *value)
{
    if (!scene)
        return -1;
    yaml_document_t *d = (yaml_document_t *)&scene->document;
    yaml_node_t *root = yaml_document_get_root_node(d);
    return scalar_number(map_get(d, map_get(d, root, section), key), value);
}

int analyze_scene_region(const analyze_scene *scene, const char *kind, size_t index,
                         double min[3], double max[3])
{
    if (!scene)
        return -1;
    yaml_document_t *d = (yaml_document_t *)&scene->document;
    yaml_node_t *root = yaml_document_get_root_node(d);
    yaml_node_t *list = map_get(d, map_get(d, root, "geometry"), kind);
    if (!list || list->type != YAML_SEQUENCE_NODE ||
        index >= (size_t)(list->data.sequence.items.top - list->data.sequence.items.start))
        return -1;
    yaml_node_t *region = yaml_document_get_node(d, list->data.sequence.items.start[index]);
    yaml_node_t *corners[2] = {map_get(d, region, "min"), map_get(d, region, "max")};
    double *out[2] = {min, max};
    for (int c = 0; c < 2; c++) {
        if (!corners[c] || corners[c]->type != YAML_SEQUENCE_NODE)
            return -1;
        size_t n = (size_t)(corners[c]->data.sequence.items.top -
                            corners[c]->data.sequence.items.start);
        for (size_t k = 0; k < 3; k++)
            out[c][k] = 0;
        for (size_t k = 0; k < n && k < 3; k++)
            if (scalar_number(yaml_document_get_node(d, corners[c]->data.sequence.items.start[k]),
                              &out[c][k]) != 0)
                return -1;
    }
    return 0;
}

long analyze_scene_numbers(analyze_ctx *cx, const analyze_scene *scene, const char *plugin,
                           const char *key, double **values)
{
    *values = NULL;
    yaml_node_t *n = plugin_key(scene, plugin, key);
    if (!n)
        return 0;
    yaml_document_t *d = (yaml_document_t *)&scene->document;
    if (n->type != YAML_SEQUENCE_NODE)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s: plugins.%s.%s is not a list",
                            scene->path, plugin, key);
    size_t count = (size_t)(n->data.sequence.items.top - n->data.sequence.items.start);
    double *v = analyze_alloc(cx, count, sizeof *v);
    if (!v)
        return -1;
    for (size_t i = 0; i < count; i++)
        if (scalar_number(yaml_document_get_node(d, n->data.sequence.items.start[i]), &v[i]) !=
            0) {
            free(v);
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "%s: item %zu of plugins.%s.%s is not a number", scene->path,
                                i + 1, plugin, key);
        }
    *values = v;
    return (long)count;
}

long analyze_scene_points(analyze_ctx *cx, const analyze_scene *scene, const char *plugin,
                          const char *key, double **xs, double **ys)
{
    *xs = *ys = NULL;
    yaml_node_t *n = plugin_key(scene, plugin, key);
    if (!n)
        return 0;
    yaml_document_t *d = (yaml_document_t *)&scene->document;
    if (n->type != YAML_SEQUENCE_NODE)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s: plugins.%s.%s is not a list",
                            scene->path, plugin, key);
    size_t count = (size_t)(n->data.sequence.items.top - n->data.sequence.items.start);
    double *x = analyze_alloc(cx, count, sizeof *x), *y = analyze_alloc(cx, count, sizeof *y);
    if (!x || !y) {
        free(x);
        free(y);
        return -1;
    }
    for (size_t i = 0; i < count; i++) {
        yaml_node_t *p = yaml_document_get_node(d, n->data.sequence.items.start[i]);
        size_t dims = p && p->type == YAML_SEQUENCE_NODE
                          ? (size_t)(p->data.sequence.items.top - p->data.sequence.items.start)
                          : 0;
        /* (x, y) in 2D; (x, y, z) in 3D: the vertical is the last axis */
        if (dims < 2 || dims > 3 ||
            scalar_number(yaml_document_get_node(d, p->data.sequence.items.start[0]), &x[i]) !=
                0 ||
            scalar_number(yaml_document_get_node(d, p->data.sequence.items.start[dims - 1]),
                          &y[i]) != 0) {
            free(x);
            free(y);
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "%s: item %zu of plugins.%s.%s is not a point [x, y]",
                                scene->path, i + 1, plugin, key);
        }
    }
    *xs = x;
    *ys = y;
    return (long)count;
}

/* -------------------------------------------------------------- options -- */

long analyze_parse_list(analyze_ctx *cx, const char *option, const char *text, double **values)
{
    *values = NULL;
    size_t count = 1;
    for (const char *p = text; *p; p++)
        count += *p == ',';
    double *v = analyze_alloc(cx, count, sizeof *v);
    if (!v)
        return -1;
    const char *p = text;
    for (size_t i = 0; i < count; i++) {
        char *end;
        v[i] = strtod(p, &end);
        while (*end == ' ')
            end++;
        if (end == p || (*end != ',' && *end != '\0') || !isfinite(v[i])) {
            free(v);
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "%s expects numbers separated by commas, got '%s'", option, text);
        }
        p = end + (*end == ',');
    }
    *values = v;
    return (long)count;
}

long analyze_parse_points(analyze_ctx *cx, const char *option, const char *text, double **xs,
                          double **ys)
{
    *xs = *ys = NULL;
    size_t count = 1;
    for (const char *p = text; *p; p++)
        count += *p == ';';
    double *x = analyze_alloc(cx, count, sizeof *x), *y = analyze_alloc(cx, count, sizeof *y);
    if (!x || !y) {
        free(x);
        free(y);
        return -1;
    }
    const char *p = text;
    for (size_t i = 0; i < count; i++) {
        char *end1, *end2;
        x[i] = strtod(p, &end1);
        int ok = end1 != p && *end1 == ',';
        if (ok) {
            y[i] = strtod(end1 + 1, &end2);
            ok = end2 != end1 + 1 && (*end2 == ';' || *end2 == '\0');
            p = end2 + (*end2 == ';');
        }
        if (!ok) {
            free(x);
            free(y);
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "%s expects points 'x,y;x,y;...', got '%s'", option, text);
        }
    }
    *xs = x;
    *ys = y;
    return (long)count;
}

/* ------------------------------------------------------------- outputs -- */

int analyze_mkdir(analyze_ctx *cx, const char *path)
{
    char *copy = strdup(path);
    if (!copy)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
    for (char *p = copy + 1; ; p++) {
        if (*p == '/' || *p == '\0') {
            char saved = *p;
            *p = '\0';
            if (mkdir(copy, 0777) != 0 && errno != EEXIST) {
                int e = errno;
                free(copy);
                return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "cannot create %s: %s", path,
                                    strerror(e));
            }
            *p = saved;
            if (saved == '\0')
                break;
        }
    }
    free(copy);
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s is not a directory", path);
    return 0;
}

/* gnuplot single-quoted string: a quote is doubled. */
static void gp_quoted(FILE *f, const char *text)
{
    fputc('\'', f);
    for (const char *p = text; *p; p++) {
        if (*p == '\'')
            fputc('\'', f);
        fputc(*p, f);
    }
    fputc('\'', f);
}

int analyze_plot(analyze_ctx *cx, const char *dir, const char *name, const char *body)
{
    if (system("command -v gnuplot >/dev/null 2>&1") != 0) {
        fprintf(stderr, "sluice-analyze: note: gnuplot is not installed: no %s.png\n", name);
        return 0;
    }
    char *script = NULL;
    size_t size = 0;
    FILE *m = open_memstream(&script, &size);
    if (!m)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
    fputs("if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
          "  set terminal pngcairo size 900,600 noenhanced\n"
          "} else {\n"
          "  set terminal png size 900,600 noenhanced\n"
          "}\n",
          m);
    fputs("cd ", m);
    gp_quoted(m, dir);
    fprintf(m, "\nset output '%s.png'\nset datafile separator ','\nset grid\n", name);
    fputs(body, m);
    fputs("\nunset output\n", m);
    if (fclose(m) != 0 || !script) {
        free(script);
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "out of memory");
    }
    char *gp_path = analyze_format(cx, "%s/%s.gp", dir, name);
    if (!gp_path) {
        free(script);
        return -1;
    }
    FILE *f = fopen(gp_path, "w");
    if (!f || fputs(script, f) < 0 || fclose(f) != 0) {
        free(script);
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "cannot write %s", gp_path);
        free(gp_path);
        return -1;
    }
    free(gp_path);
    fflush(stdout);
    FILE *p = popen("gnuplot", "w");
    if (!p) {
        fprintf(stderr, "sluice-analyze: note: cannot start gnuplot: no %s.png\n", name);
        free(script);
        return 0;
    }
    fputs(script, p);
    int status = pclose(p);
    if (status != 0)
        fprintf(stderr, "sluice-analyze: note: gnuplot failed on %s/%s.gp\n", dir, name);
    free(script);
    return 0;
}
