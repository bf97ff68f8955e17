/* YAML documents as trees of positioned nodes, loaded with libyaml's event
 * API; command-line overrides; emission back to YAML text; edit distance for
 * suggestions.
 *
 * Ownership: every node is one allocation holding the node and a private copy
 * of its file name (node->file points into it), plus its value string and its
 * item/key arrays. sluice_node_free() therefore frees everything exactly once,
 * and a node's file name stays valid as long as the node lives, wherever the
 * node is moved. */
#include "yaml_tree.h"

#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <yaml.h>

/* Deepest nesting of collections accepted (the loader, clone, free and emit
 * recurse once per level). */
#define MAX_DEPTH 1000
/* Most nodes that aliases may expand to in one document ("billion laughs"). */
#define MAX_ALIAS_NODES 100000

/* ------------------------------------------------------------- strings -- */

static char *copy_text(const char *text, size_t length)
{
    char *s = malloc(length + 1);
    if (!s)
        return NULL;
    if (length)
        memcpy(s, text, length);
    s[length] = '\0';
    return s;
}

static int clamp_int(size_t value)
{
    return value > (size_t)INT_MAX ? INT_MAX : (int)value;
}

/* --------------------------------------------------------------- nodes -- */

static sluice_node *node_alloc(sluice_node_kind kind, const char *file, int line, int column)
{
    size_t n = file ? strlen(file) + 1 : 0;
    sluice_node *node = calloc(1, sizeof *node + n);
    if (!node)
        return NULL;
    node->kind = kind;
    if (file) {
        char *copy = (char *)(node + 1);
        memcpy(copy, file, n);
        node->file = copy;
    }
    node->line = line;
    node->column = column;
    return node;
}

sluice_node *sluice_node_new_scalar(const char *value, int plain, const char *file, int line,
                                    int column)
{
    sluice_node *node = node_alloc(SLUICE_NODE_SCALAR, file, line, column);
    if (!node)
        return NULL;
    const char *text = value ? value : "";
    node->value = copy_text(text, strlen(text));
    if (!node->value) {
        free(node);
        return NULL;
    }
    node->plain = plain ? 1 : 0;
    return node;
}

sluice_node *sluice_node_new_mapping(const char *file, int line, int column)
{
    return node_alloc(SLUICE_NODE_MAPPING, file, line, column);
}

sluice_node *sluice_node_new_sequence(const char *file, int line, int column)
{
    return node_alloc(SLUICE_NODE_SEQUENCE, file, line, column);
}

void sluice_node_free(sluice_node *node)
{
    if (!node)
        return;
    for (size_t i = 0; i < node->count; i++) {
        if (node->items)
            sluice_node_free(node->items[i]);
        if (node->keys)
            sluice_node_free(node->keys[i]);
    }
    free(node->items);
    free(node->keys);
    free(node->value);
    free(node);
}

int sluice_node_append(sluice_node *sequence, sluice_node *value)
{
    if (!sequence || !value || sequence->kind != SLUICE_NODE_SEQUENCE ||
        sequence->count >= SIZE_MAX / sizeof(sluice_node *) - 1) {
        sluice_node_free(value);
        return -1;
    }
    sluice_node **items = realloc(sequence->items, (sequence->count + 1) * sizeof *items);
    if (!items) {
        sluice_node_free(value);
        return -1;
    }
    sequence->items = items;
    items[sequence->count++] = value;
    return 0;
}

/* Appends a key/value pair (both owned) to a mapping; frees both on failure. */
static int mapping_add(sluice_node *mapping, sluice_node *key, sluice_node *value)
{
    if (!key || !value || mapping->count >= SIZE_MAX / sizeof(sluice_node *) - 1) {
        sluice_node_free(key);
        sluice_node_free(value);
        return -1;
    }
    size_t size = (mapping->count + 1) * sizeof(sluice_node *);
    sluice_node **keys = realloc(mapping->keys, size);
    if (!keys) {
        sluice_node_free(key);
        sluice_node_free(value);
        return -1;
    }
    mapping->keys = keys;
    sluice_node **items = realloc(mapping->items, size);
    if (!items) {
        sluice_node_free(key);
        sluice_node_free(value);
        return -1;
    }
    mapping->items = items;
    keys[mapping->count] = key;
    items[mapping->count] = value;
    mapping->count++;
    return 0;
}

static long find_key(const sluice_node *mapping, const char *key)
{
    if (!mapping || !key || mapping->kind != SLUICE_NODE_MAPPING || !mapping->keys)
        return -1;
    for (size_t i = 0; i < mapping->count; i++) {
        const sluice_node *k = mapping->keys[i];
        if (k && k->kind == SLUICE_NODE_SCALAR && k->value && strcmp(k->value, key) == 0)
            return (long)i;
    }
    return -1;
}

int sluice_node_set(sluice_node *mapping, const char *key, sluice_node *value)
{
    if (!mapping || !key || !value || mapping->kind != SLUICE_NODE_MAPPING) {
        sluice_node_free(value);
        return -1;
    }
    long i = find_key(mapping, key);
    if (i >= 0) {
        if (mapping->items[i] != value)
            sluice_node_free(mapping->items[i]);
        mapping->items[i] = value;
        return 0;
    }
    sluice_node *k = sluice_node_new_scalar(key, 1, value->file, value->line, value->column);
    return mapping_add(mapping, k, value);
}

sluice_node *sluice_node_get(const sluice_node *mapping, const char *key)
{
    long i = find_key(mapping, key);
    return i >= 0 ? mapping->items[i] : NULL;
}

sluice_node *sluice_node_get_key(const sluice_node *mapping, const char *key)
{
    long i = find_key(mapping, key);
    return i >= 0 ? mapping->keys[i] : NULL;
}

/* Deep copy; *budget counts down the nodes that may still be made (the copy
 * fails when it runs out). */
static sluice_node *clone_limited(const sluice_node *node, size_t *budget)
{
    if (!node || *budget == 0)
        return NULL;
    (*budget)--;
    sluice_node *copy = node_alloc(node->kind, node->file, node->line, node->column);
    if (!copy)
        return NULL;
    copy->plain = node->plain;
    copy->used = node->used;
    if (node->value) {
        copy->value = copy_text(node->value, strlen(node->value));
        if (!copy->value)
            goto fail;
    }
    if (node->count && node->items) {
        copy->items = calloc(node->count, sizeof *copy->items);
        if (!copy->items)
            goto fail;
        if (node->keys) {
            copy->keys = calloc(node->count, sizeof *copy->keys);
            if (!copy->keys)
                goto fail;
        }
        for (size_t i = 0; i < node->count; i++) {
            /* count grows with each complete entry so that a failure frees
             * exactly what was made */
            copy->items[i] = clone_limited(node->items[i], budget);
            if (copy->keys && copy->items[i])
                copy->keys[i] = clone_limited(node->keys[i], budget);
            if (!copy->items[i] || (copy->keys && !copy->keys[i])) {
                sluice_node_free(copy->items[i]);
                goto fail;
            }
            copy->count = i + 1;
        }
    }
    return copy;
fail:
    sluice_node_free(copy);
    return NULL;
}

sluice_node *sluice_node_clone(const sluice_node *node)
{
    size_t budget = SIZE_MAX;
    return clone_limited(node, &budget);
}

void sluice_node_mark_used(sluice_node *node, int used)
{
    if (!node)
        return;
    node->used = used;
    for (size_t i = 0; i < node->count; i++) {
        if (node->items)
            sluice_node_mark_used(node->items[i], used);
        if (node->keys)
            sluice_node_mark_used(node->keys[i], used);
    }
}

/* -------------------------------------------------------------- loading -- */

/* The dotted path of the node being loaded, as a chain on the stack. */
typedef struct path_seg {
    const struct path_seg *parent;
    const char *key; /* NULL for a sequence index */
    size_t index;
} path_seg;

static size_t path_append(const path_seg *seg, char *buffer, size_t size, size_t pos)
{
    if (!seg)
        return pos;
    pos = path_append(seg->parent, buffer, size, pos);
    if (seg->key && !*seg->key)
        return pos; /* the top level */
    int n;
    if (seg->key)
        n = snprintf(buffer + pos, size - pos, "%s%s", pos ? "." : "", seg->key);
    else
        n = snprintf(buffer + pos, size - pos, "%s%zu", pos ? "." : "", seg->index);
    if (n > 0)
        pos += (size_t)n;
    return pos < size ? pos : size - 1;
}

/* "in a.b" or "at the top level". */
static const char *path_where(const path_seg *seg, char *buffer, size_t size)
{
    char path[512];
    path[0] = '\0';
    path_append(seg, path, sizeof path, 0);
    if (path[0])
        snprintf(buffer, size, "in %s", path);
    else
        snprintf(buffer, size, "at the top level");
    return buffer;
}

typedef struct anchor {
    char *name;
    sluice_node *node; /* NULL while the anchored node is being loaded */
} anchor;

typedef struct loader {
    yaml_parser_t parser;
    const char *name; /* file name of nodes and messages */
    const unsigned char *text;
    size_t length;
    sluice_diag *diag;
    /* Positions: a file has lines; an override value is one line inside the
     * command-line argument, starting at character `base` (0-based). */
    int flat;
    size_t base;
    int flow_only;         /* reject a block collection at the top */
    const char *root_path; /* path of the document's root in messages */
    anchor *anchors;
    size_t anchor_count, anchor_capacity;
    size_t alias_budget;
    int errors; /* problems after which loading goes on, to report them all */
    int fatal;  /* loading stopped */
} loader;

static void position(const loader *L, yaml_mark_t mark, int *line, int *column)
{
    if (L->flat) {
        *line = 1;
        *column = clamp_int(L->base + mark.index + 1);
    } else {
        *line = clamp_int(mark.line + 1);
        *column = clamp_int(mark.column + 1);
    }
}

static void report(loader *L, int line, int column, const char *format, ...) SLUICE_PRINTF(4, 5);
static void report(loader *L, int line, int column, const char *format, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    sluice_diag_add(L->diag, SLUICE_SEVERITY_ERROR, L->name, line, column, "%s", text);
}

static void report_oom(loader *L)
{
    if (!L->fatal)
        sluice_diag_add(L->diag, SLUICE_SEVERITY_ERROR, L->name, 0, 0,
                        "out of memory while loading YAML");
    L->fatal = 1;
}

static void report_syntax_error(loader *L)
{
    const yaml_parser_t *p = &L->parser;
    const char *problem = p->problem ? p->problem : "unknown problem";
    int line, column;
    L->fatal = 1;
    if (p->error == YAML_MEMORY_ERROR) {
        sluice_diag_add(L->diag, SLUICE_SEVERITY_ERROR, L->name, 0, 0,
                        "out of memory while loading YAML");
        return;
    }
    if (p->error == YAML_READER_ERROR) {
        /* only a byte offset is known: count lines up to it */
        size_t offset = p->problem_offset < L->length ? p->problem_offset : L->length;
        if (L->flat) {
            line = 1;
            column = clamp_int(L->base + offset + 1);
        } else {
            size_t l = 1, start = 0;
            for (size_t i = 0; i < offset; i++)
                if (L->text[i] == '\n') {
                    l++;
                    start = i + 1;
                }
            line = clamp_int(l);
            column = clamp_int(offset - start + 1);
        }
        if (p->problem_value >= 0)
            report(L, line, column, "YAML syntax error: %s (byte 0x%02x)", problem,
                   (unsigned)p->problem_value);
        else
            report(L, line, column, "YAML syntax error: %s", problem);
        return;
    }
    position(L, p->problem_mark, &line, &column);
    if (p->context) {
        int cl, cc;
        position(L, p->context_mark, &cl, &cc);
        if (L->flat)
            report(L, line, column, "YAML syntax error: %s (%s that started at column %d)",
                   problem, p->context, cc);
        else
            report(L, line, column,
                   "YAML syntax error: %s (%s that started at line %d, column %d)", problem,
                   p->context, cl, cc);
    } else {
        report(L, line, column, "YAML syntax error: %s", problem);
    }
}

static int next_event(loader *L, yaml_event_t *event)
{
    if (!yaml_parser_parse(&L->parser, event)) {
        report_syntax_error(L);
        return 0;
    }
    return 1;
}

/* Starts an anchor (returns its slot) when `name` is not NULL. */
static int anchor_begin(loader *L, const yaml_char_t *name, size_t *slot)
{
    *slot = SIZE_MAX;
    if (!name)
        return 0;
    if (L->anchor_count == L->anchor_capacity) {
        size_t cap = L->anchor_capacity ? 2 * L->anchor_capacity : 8;
        anchor *a = realloc(L->anchors, cap * sizeof *a);
        if (!a)
            return -1;
        L->anchors = a;
        L->anchor_capacity = cap;
    }
    const char *text = (const char *)name;
    char *copy = copy_text(text, strlen(text));
    if (!copy)
        return -1;
    L->anchors[L->anchor_count].name = copy;
    L->anchors[L->anchor_count].node = NULL;
    *slot = L->anchor_count++;
    return 0;
}

static void anchor_end(loader *L, size_t slot, sluice_node *node)
{
    if (slot != SIZE_MAX)
        L->anchors[slot].node = node;
}

static sluice_node *load_node(loader *L, yaml_event_t *event, const path_seg *path, int depth);

static sluice_node *load_alias(loader *L, yaml_event_t *event, const path_seg *path, int line,
                               int column)
{
    const char *name = (const char *)event->data.alias.anchor;
    const anchor *found = NULL;
    for (size_t i = L->anchor_count; i-- > 0;)
        if (strcmp(L->anchors[i].name, name) == 0) {
            found = &L->anchors[i];
            break;
        }
    char where[600];
    if (!found || !found->node) {
        if (!found)
            report(L, line, column, "undefined alias '*%s' %s", name,
                   path_where(path, where, sizeof where));
        else
            report(L, line, column,
                   "alias '*%s' %s refers to a node that contains it; recursive aliases are "
                   "not allowed",
                   name, path_where(path, where, sizeof where));
        L->errors++;
        sluice_node *placeholder = sluice_node_new_scalar("", 1, L->name, line, column);
        if (!placeholder)
            report_oom(L);
        return placeholder;
    }
    sluice_node *copy = clone_limited(found->node, &L->alias_budget);
    if (!copy) {
        if (L->alias_budget == 0) {
            report(L, line, column,
                   "aliases expand to more than %d nodes; the document is too large",
                   MAX_ALIAS_NODES);
            L->fatal = 1;
        } else {
            report_oom(L);
        }
        return NULL;
    }
    copy->line = line; /* the copy is where the alias is */
    copy->column = column;
    return copy;
}

static sluice_node *load_scalar(loader *L, yaml_event_t *event, int line, int column)
{
    size_t slot;
    if (anchor_begin(L, event->data.scalar.anchor, &slot) != 0) {
        report_oom(L);
        return NULL;
    }
    const char *tag = (const char *)event->data.scalar.tag;
    /* an explicit string tag (!!str, !) makes a plain scalar a string */
    int plain = event->data.scalar.style == YAML_PLAIN_SCALAR_STYLE &&
                !(tag && (strcmp(tag, "!") == 0 || strcmp(tag, YAML_STR_TAG) == 0));
    sluice_node *node = node_alloc(SLUICE_NODE_SCALAR, L->name, line, column);
    if (node)
        node->value = copy_text((const char *)event->data.scalar.value, event->data.scalar.length);
    if (!node || !node->value) {
        free(node);
        report_oom(L);
        return NULL;
    }
    node->plain = plain;
    anchor_end(L, slot, node);
    return node;
}

/* A growable array of node pointers used while loading a collection. */
typedef struct node_vector {
    sluice_node **data;
    size_t count, capacity;
} node_vector;

static int vector_push(node_vector *v, sluice_node *node)
{
    if (v->count == v->capacity) {
        size_t cap = v->capacity ? 2 * v->capacity : 4;
        if (cap > SIZE_MAX / sizeof(sluice_node *))
            return -1;
        sluice_node **d = realloc(v->data, cap * sizeof *d);
        if (!d)
            return -1;
        v->data = d;
        v->capacity = cap;
    }
    v->data[v->count++] = node;
    return 0;
}

static void vector_free_all(node_vector *v)
{
    for (size_t i = 0; i < v->count; i++)
        sluice_node_free(v->data[i]);
    free(v->data);
    v->data = NULL;
    v->count = v->capacity = 0;
}

static const char *kind_name(sluice_node_kind kind)
{
    return kind == SLUICE_NODE_MAPPING ? "mapping" : kind == SLUICE_NODE_SEQUENCE ? "list" : "scalar";
}

static sluice_node *load_sequence(loader *L, yaml_event_t *event, const path_seg *path,
                                  int depth, int line, int column)
{
    size_t slot;
    if (anchor_begin(L, event->data.sequence_start.anchor, &slot) != 0) {
        report_oom(L);
        return NULL;
    }
    node_vector items = {NULL, 0, 0};
    for (;;) {
        yaml_event_t child;
        if (!next_event(L, &child))
            goto fail;
        if (child.type == YAML_SEQUENCE_END_EVENT) {
            yaml_event_delete(&child);
            break;
        }
        path_seg seg = {path, NULL, items.count};
        sluice_node *item = load_node(L, &child, &seg, depth + 1);
        if (!item)
            goto fail;
        if (vector_push(&items, item) != 0) {
            sluice_node_free(item);
            report_oom(L);
            goto fail;
        }
    }
    sluice_node *node = node_alloc(SLUICE_NODE_SEQUENCE, L->name, line, column);
    if (!node) {
        report_oom(L);
        goto fail;
    }
    node->items = items.data;
    node->count = items.count;
    anchor_end(L, slot, node);
    return node;
fail:
    vector_free_all(&items);
    return NULL;
}

static sluice_node *load_mapping(loader *L, yaml_event_t *event, const path_seg *path,
                                 int depth, int line, int column)
{
    size_t slot;
    if (anchor_begin(L, event->data.mapping_start.anchor, &slot) != 0) {
        report_oom(L);
        return NULL;
    }
    node_vector keys = {NULL, 0, 0}, values = {NULL, 0, 0};
    char where[600];
    for (;;) {
        yaml_event_t child;
        if (!next_event(L, &child))
            goto fail;
        if (child.type == YAML_MAPPING_END_EVENT) {
            yaml_event_delete(&child);
            break;
        }
        sluice_node *key = load_node(L, &child, path, depth + 1);
        if (!key)
            goto fail;
        if (vector_push(&keys, key) != 0) {
            sluice_node_free(key);
            report_oom(L);
            goto fail;
        }
        if (key->kind != SLUICE_NODE_SCALAR) {
            /* kept in the tree (anchors may point into it); the load fails */
            report(L, key->line, key->column, "a key %s is a %s; keys must be scalars",
                   path_where(path, where, sizeof where), kind_name(key->kind));
            L->errors++;
        } else {
            for (size_t i = 0; i + 1 < keys.count; i++) {
                const sluice_node *k = keys.data[i];
                if (k->kind == SLUICE_NODE_SCALAR && strcmp(k->value, key->value) == 0) {
                    if (L->flat)
                        report(L, key->line, key->column,
                               "duplicate key '%s' %s (first at column %d)", key->value,
                               path_where(path, where, sizeof where), k->column);
                    else
                        report(L, key->line, key->column,
                               "duplicate key '%s' %s (first at line %d)", key->value,
                               path_where(path, where, sizeof where), k->line);
                    L->errors++;
                    break;
                }
            }
        }
        if (!next_event(L, &child))
            goto fail;
        path_seg seg = {path, key->kind == SLUICE_NODE_SCALAR ? key->value : "?", 0};
        sluice_node *value = load_node(L, &child, &seg, depth + 1);
        if (!value)
            goto fail;
        if (vector_push(&values, value) != 0) {
            sluice_node_free(value);
            report_oom(L);
            goto fail;
        }
    }
    sluice_node *node = node_alloc(SLUICE_NODE_MAPPING, L->name, line, column);
    if (!node) {
        report_oom(L);
        goto fail;
    }
    node->keys = keys.data;
    node->items = values.data;
    node->count = keys.count;
    anchor_end(L, slot, node);
    return node;
fail:
    vector_free_all(&keys);
    vector_free_all(&values);
    return NULL;
}

/* Loads the node that starts with `event` (a scalar, alias or collection
 * start), consuming the event. NULL when loading must stop. */
static sluice_node *load_node(loader *L, yaml_event_t *event, const path_seg *path, int depth)
{
    int line, column;
    position(L, event->start_mark, &line, &column);
    sluice_node *node = NULL;
    char where[600];
    int collection =
        event->type == YAML_SEQUENCE_START_EVENT || event->type == YAML_MAPPING_START_EVENT;
    if (collection && depth >= MAX_DEPTH) {
        report(L, line, column, "collections are nested more than %d levels deep %s", MAX_DEPTH,
               path_where(path, where, sizeof where));
        L->fatal = 1;
        yaml_event_delete(event);
        return NULL;
    }
    if (collection && depth == 0 && L->flow_only &&
        (event->type == YAML_SEQUENCE_START_EVENT
             ? event->data.sequence_start.style != YAML_FLOW_SEQUENCE_STYLE
             : event->data.mapping_start.style != YAML_FLOW_MAPPING_STYLE)) {
        report(L, line, column,
               "the value for %s must be a scalar or a flow collection such as [1, 2] or "
               "{a: 1}; quote text that contains ': ' or starts with '- '",
               L->root_path);
        L->fatal = 1;
        yaml_event_delete(event);
        return NULL;
    }
    switch (event->type) {
    case YAML_ALIAS_EVENT:
        node = load_alias(L, event, path, line, column);
        break;
    case YAML_SCALAR_EVENT:
        node = load_scalar(L, event, line, column);
        break;
    case YAML_SEQUENCE_START_EVENT:
        node = load_sequence(L, event, path, depth, line, column);
        break;
    case YAML_MAPPING_START_EVENT:
        node = load_mapping(L, event, path, depth, line, column);
        break;
    default:
        report(L, line, column, "unexpected YAML event %d", (int)event->type);
        L->fatal = 1;
        break;
    }
    yaml_event_delete(event);
    return node;
}

/* Loads the single document of the input. Returns the root, or NULL with
 * *empty set when the input holds no document (nothing reported), or NULL
 * after reporting an error. */
static sluice_node *load_document(loader *L, int *empty)
{
    *empty = 0;
    yaml_event_t event;
    if (!next_event(L, &event)) /* stream start */
        return NULL;
    yaml_event_delete(&event);
    if (!next_event(L, &event))
        return NULL;
    if (event.type == YAML_STREAM_END_EVENT) {
        yaml_event_delete(&event);
        *empty = 1;
        return NULL;
    }
    yaml_event_delete(&event); /* document start */
    if (!next_event(L, &event))
        return NULL;
    path_seg root = {NULL, L->root_path, 0};
    sluice_node *node = load_node(L, &event, &root, 0);
    if (!node)
        return NULL;
    if (!next_event(L, &event)) { /* document end */
        sluice_node_free(node);
        return NULL;
    }
    yaml_event_delete(&event);
    if (!next_event(L, &event)) {
        sluice_node_free(node);
        return NULL;
    }
    if (event.type == YAML_DOCUMENT_START_EVENT) {
        int line, column;
        position(L, event.start_mark, &line, &column);
        report(L, line, column,
               "a second YAML document starts here; the input must hold exactly one");
        L->errors++;
    }
    yaml_event_delete(&event);
    if (L->errors) {
        sluice_node_free(node);
        return NULL;
    }
    return node;
}

static void loader_init(loader *L, const char *text, size_t length, const char *name,
                        sluice_diag *diag)
{
    memset(L, 0, sizeof *L);
    L->name = name;
    L->text = (const unsigned char *)text;
    L->length = length;
    L->diag = diag;
    L->root_path = "";
    L->alias_budget = MAX_ALIAS_NODES;
}

/* Runs the loader over its text; *empty as for load_document. */
static sluice_node *loader_run(loader *L, int *empty)
{
    *empty = 0;
    if (!yaml_parser_initialize(&L->parser)) {
        sluice_diag_add(L->diag, SLUICE_SEVERITY_ERROR, L->name, 0, 0,
                        "out of memory while loading YAML");
        return NULL;
    }
    yaml_parser_set_input_string(&L->parser, L->text, L->length);
    sluice_node *root = load_document(L, empty);
    yaml_parser_delete(&L->parser);
    for (size_t i = 0; i < L->anchor_count; i++)
        free(L->anchors[i].name);
    free(L->anchors);
    L->anchors = NULL;
    L->anchor_count = L->anchor_capacity = 0;
    return root;
}

sluice_node *sluice_yaml_parse_string(const char *text, size_t length, const char *name,
                                      sluice_diag *diag)
{
    loader L;
    loader_init(&L, text ? text : "", text ? length : 0, name, diag);
    int empty;
    sluice_node *root = loader_run(&L, &empty);
    if (!root && empty)
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, name, 1, 1, "the file is empty");
    return root;
}

/* The largest YAML file read (scenes and studies are text of kilobytes;
 * the largest shipped, a scene with 240 gauge points, is 16 KiB). */
#define SLUICE_YAML_MAX_BYTES (64 << 20)

sluice_node *sluice_yaml_parse_file(const char *path, sluice_diag *diag)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, path, 1, 1, "cannot read file: %s",
                        strerror(errno));
        return NULL;
    }
    char *text = NULL;
    size_t length = 0, capacity = 0;
    int failed = 0;
    for (;;) {
        if (capacity - length < 4096) {
            size_t cap = capacity ? 2 * capacity : 65536;
            char *t = cap > capacity ? realloc(text, cap) : NULL;
            if (!t) {
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, path, 1, 1,
                                "cannot read file: out of memory");
                failed = 1;
                break;
            }
            text = t;
            capacity = cap;
        }
        errno = 0;
        size_t n = fread(text + length, 1, capacity - length, f);
        length += n;
        if (length > SLUICE_YAML_MAX_BYTES) {
            /* /dev/zero, a device, a binary file given by mistake */
            sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, path, 1, 1,
                            "cannot read file: it is longer than %d MiB, the most a YAML file "
                            "may hold (is it the right file?)",
                            SLUICE_YAML_MAX_BYTES >> 20);
            failed = 1;
            break;
        }
        if (n == 0) {
            if (ferror(f)) {
                int e = errno ? errno : EIO;
                sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, path, 1, 1, "cannot read file: %s",
                                strerror(e));
                failed = 1;
            }
            break;
        }
    }
    fclose(f);
    sluice_node *root = failed ? NULL : sluice_yaml_parse_string(text, length, path, diag);
    free(text);
    return root;
}

/* ----------------------------------------------------------- path walk -- */

static int all_digits(const char *s)
{
    if (!*s)
        return 0;
    for (; *s; s++)
        if (*s < '0' || *s > '9')
            return 0;
    return 1;
}

static int empty_plain(const sluice_node *node)
{
    return node && node->kind == SLUICE_NODE_SCALAR && node->plain && node->value &&
           !node->value[0];
}

/* The item of a list that a path segment addresses: by its 0-based index
 * (all digits) or by the value of its `name` key. Returns the index, or -1
 * with the reason in why[]. The list's own dotted path is the first
 * list_length characters of list_path. */
static long list_item(const sluice_node *list, const char *segment, const char *list_path,
                      int list_length, char *why, size_t size)
{
    size_t n = list->count;
    const char *plural = n == 1 ? "" : "s";
    if (all_digits(segment)) {
        errno = 0;
        unsigned long long index = strtoull(segment, NULL, 10);
        if (errno != ERANGE && index < n)
            return (long)index;
        snprintf(why, size, "index %s is out of range, %.*s has %zu item%s", segment,
                 list_length, list_path, n, plural);
        return -1;
    }
    long found = -1, second = -1;
    size_t named = 0;
    for (size_t i = 0; i < n; i++) {
        const sluice_node *name = sluice_node_get(list->items[i], "name");
        if (!name || name->kind != SLUICE_NODE_SCALAR)
            continue;
        named++;
        if (strcmp(name->value, segment) != 0)
            continue;
        if (found < 0)
            found = (long)i;
        else if (second < 0)
            second = (long)i;
    }
    if (found >= 0 && second < 0)
        return found;
    if (found >= 0) {
        snprintf(why, size, "items %ld and %ld of %.*s are both named '%s'; address one by its "
                 "index", found, second, list_length, list_path, segment);
        return -1;
    }
    if (named == 0) {
        snprintf(why, size, "%.*s is a list, so '%s' must be a numeric index or the name of "
                 "an item (it has %zu item%s, none named)", list_length, list_path, segment, n,
                 plural);
        return -1;
    }
    size_t used = (size_t)snprintf(why, size, "%.*s has no item named '%s' (names:",
                                   list_length, list_path, segment);
    const char *separator = " ";
    for (size_t i = 0; i < n && used < size; i++) {
        const sluice_node *name = sluice_node_get(list->items[i], "name");
        if (!name || name->kind != SLUICE_NODE_SCALAR)
            continue;
        used += (size_t)snprintf(why + used, size - used, "%s'%s'", separator, name->value);
        separator = ", ";
    }
    if (used < size)
        snprintf(why + used, size - used, "; or an index below %zu)", n);
    return -1;
}

/* Why a mapping has no child `segment` (with the closest key as a
 * suggestion). The mapping's dotted path is the first length characters of
 * path (none: the top level). */
static void missing_key(const sluice_node *mapping, const char *segment, const char *path,
                        int length, char *why, size_t size)
{
    const char *close = NULL;
    const char **names = mapping->count ? malloc(mapping->count * sizeof *names) : NULL;
    if (names) {
        for (size_t i = 0; i < mapping->count; i++)
            names[i] = mapping->keys[i]->value;
        close = sluice_closest(segment, names, mapping->count);
    }
    int used = length ? snprintf(why, size, "%.*s has no key '%s'", length, path, segment)
                      : snprintf(why, size, "the top level has no key '%s'", segment);
    if (close && used >= 0 && (size_t)used < size)
        snprintf(why + used, size - (size_t)used, "; did you mean '%s'?", close);
    free(names);
}

/* One walk down a dotted path, shared by --set (sluice_yaml_override) and a
 * variant's `set` and `remove` (sluice_yaml_set, sluice_yaml_remove). */
typedef struct path_walk {
    const char *path;
    /* What to put at the path (owned, freed on failure). NULL: only find the
     * node the path addresses, which must exist: parent->items[index]. */
    sluice_node *value;
    /* Where the keys and mappings the walk creates are positioned. A variant's
     * setting: file, line, column of its YAML key. --set (argument nonzero):
     * file names the argument, line 1, column of the segment in it. */
    const char *file;
    int line, column;
    int argument;
    sluice_node *parent;
    size_t index;
    size_t failed; /* on failure: offset in path of the segment at fault */
    char why[768]; /* on failure: the reason, to end the caller's message */
} path_walk;

enum { WALK_FAILED = -1, WALK_OUT_OF_MEMORY = -2 };

/* Walks w->path from root (a mapping), segment by segment: a segment is a
 * key of a mapping or an item of a list, by its index or by its `name`
 * (list_item). With a value, puts it at the path, replacing what is there:
 * missing keys are created (intermediate ones as empty mappings), an empty
 * `key:` on the way becomes a mapping, list items must exist. Without, finds
 * the node. Returns 0, WALK_FAILED or WALK_OUT_OF_MEMORY, with the reason in
 * w->why. A failure changes nothing, except when an empty segment or an
 * allocation failure comes after keys were created. */
static int walk_path(sluice_node *root, path_walk *w)
{
    const char *path = w->path;
    const int edit = w->value != NULL;
    size_t n = strlen(path);
    char *segment = malloc(n + 1);
    if (!segment) {
        snprintf(w->why, sizeof w->why, "out of memory");
        sluice_node_free(w->value);
        w->value = NULL;
        return WALK_OUT_OF_MEMORY;
    }
    sluice_node *current = root;
    sluice_node **slot = NULL;
    size_t start = 0;
    int rc = WALK_FAILED;
    for (;;) {
        size_t end = start;
        while (end < n && path[end] != '.')
            end++;
        w->failed = start;
        /* only a variant's paths get here with an empty key: --set rejects
         * them, with its own message, before it parses its value */
        if (end == start) {
            snprintf(w->why, sizeof w->why, "the path has an empty key");
            break;
        }
        memcpy(segment, path + start, end - start);
        segment[end - start] = '\0';
        int last = end == n, length = (int)(start ? start - 1 : 0);
        if (edit && slot && empty_plain(current)) {
            /* `key:` with nothing is an empty mapping */
            sluice_node *mapping =
                sluice_node_new_mapping(current->file, current->line, current->column);
            if (!mapping) {
                rc = WALK_OUT_OF_MEMORY;
                break;
            }
            sluice_node_free(current);
            *slot = current = mapping;
        }
        long i = -1;
        if (current->kind == SLUICE_NODE_MAPPING) {
            i = find_key(current, segment);
            if (i < 0 && !edit) {
                missing_key(current, segment, path, length, w->why, sizeof w->why);
            } else if (i < 0) {
                const char *file = w->file;
                int line = w->argument ? 1 : w->line;
                int column = w->argument ? clamp_int(start + 1) : w->column;
                sluice_node *key = sluice_node_new_scalar(segment, 1, file, line, column);
                sluice_node *child = last ? w->value : sluice_node_new_mapping(file, line, column);
                if (last)
                    w->value = NULL;
                if (mapping_add(current, key, child) != 0) {
                    rc = WALK_OUT_OF_MEMORY;
                    break;
                }
                if (last) {
                    rc = 0;
                    break;
                }
                i = (long)current->count - 1;
            }
        } else if (current->kind == SLUICE_NODE_SEQUENCE) {
            i = list_item(current, segment, path, length, w->why, sizeof w->why);
        } else {
            /* only removal meets an empty `key:` here (an edit made it a
             * mapping); --set's message has always named mappings only */
            snprintf(w->why, sizeof w->why, "%.*s is %s, not %s", length, path,
                     empty_plain(current) ? "empty" : "a scalar",
                     w->argument ? "a mapping" : "a mapping or a list");
        }
        if (i < 0)
            break;
        if (last) {
            if (edit) {
                sluice_node_free(current->items[i]);
                current->items[i] = w->value;
                w->value = NULL;
            } else {
                w->parent = current;
                w->index = (size_t)i;
            }
            rc = 0;
            break;
        }
        slot = &current->items[i];
        current = *slot;
        start = end + 1;
    }
    if (rc == WALK_OUT_OF_MEMORY)
        snprintf(w->why, sizeof w->why, "out of memory");
    sluice_node_free(w->value);
    w->value = NULL;
    free(segment);
    return rc;
}

/* ------------------------------------------------------------ overrides -- */

static void override_error(sluice_diag *diag, const char *origin, size_t column,
                           const char *format, ...) SLUICE_PRINTF(4, 5);
static void override_error(sluice_diag *diag, const char *origin, size_t column,
                           const char *format, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, origin, 1, clamp_int(column), "%s", text);
}

/* Parses the value of an override: one scalar or flow collection. */
static sluice_node *override_value(const char *text, size_t base, const char *path,
                                   const char *origin, sluice_diag *diag)
{
    loader L;
    loader_init(&L, text, strlen(text), origin, diag);
    L.flat = 1;
    L.base = base;
    L.flow_only = 1;
    L.root_path = path;
    int empty;
    sluice_node *value = loader_run(&L, &empty);
    if (!value && empty) {
        value = sluice_node_new_scalar("", 1, origin, 1, clamp_int(base + 1));
        if (!value)
            sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, origin, 0, 0,
                            "out of memory while applying an override");
    }
    return value;
}

int sluice_yaml_override(sluice_node *root, const char *assignment, const char *origin,
                         sluice_diag *diag)
{
    const char *eq = strchr(assignment, '=');
    if (!eq) {
        override_error(diag, origin, 1, "the override '%s' has no '=': write key.path=value",
                       assignment);
        return -1;
    }
    size_t path_length = (size_t)(eq - assignment);
    if (path_length == 0) {
        override_error(diag, origin, 1,
                       "the override '%s' names no key before '=': write key.path=value",
                       assignment);
        return -1;
    }
    for (size_t i = 0; i <= path_length; i++)
        if ((i == path_length || assignment[i] == '.') &&
            (i == 0 || assignment[i - 1] == '.')) {
            override_error(diag, origin, i + 1, "empty key in the path '%.*s' of the override",
                           (int)path_length, assignment);
            return -1;
        }
    if (!root || root->kind != SLUICE_NODE_MAPPING) {
        override_error(diag, origin, 1,
                       "cannot apply the override '%s': the document is not a mapping",
                       assignment);
        return -1;
    }
    char *path = copy_text(assignment, path_length);
    if (!path) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, origin, 0, 0,
                        "out of memory while applying an override");
        return -1;
    }
    sluice_node *value = override_value(eq + 1, path_length + 1, path, origin, diag);
    if (!value) {
        free(path);
        return -1;
    }
    path_walk w = {.path = path, .value = value, .file = origin, .argument = 1};
    int rc = walk_path(root, &w);
    /* errors sit on line 1 of the argument, at the column of the segment */
    if (rc == WALK_FAILED)
        override_error(diag, origin, w.failed + 1, "cannot set '%s': %s", path, w.why);
    else if (rc == WALK_OUT_OF_MEMORY)
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, origin, 0, 0,
                        "out of memory while applying an override");
    free(path);
    return rc == 0 ? 0 : -1;
}

/* ----------------------------------------------------------- path edits -- */

static void path_error(sluice_diag *diag, const sluice_node *at, const char *format, ...)
    SLUICE_PRINTF(3, 4);
static void path_error(sluice_diag *diag, const sluice_node *at, const char *format, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    int line = at && at->line > 0 ? at->line : 1;
    int column = at && at->line > 0 ? at->column : 1;
    sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, at ? at->file : NULL, line, column, "%s", text);
}

/* Drops the entries of a collection whose value is NULL. */
static void drop_empty_slots(sluice_node *node)
{
    size_t kept = 0;
    for (size_t i = 0; i < node->count; i++) {
        if (!node->items[i]) {
            if (node->keys)
                sluice_node_free(node->keys[i]);
            continue;
        }
        if (node->keys)
            node->keys[kept] = node->keys[i];
        node->items[kept++] = node->items[i];
    }
    node->count = kept;
}

int sluice_yaml_remove(sluice_node *root, const sluice_node *paths, const char *context,
                       sluice_diag *diag)
{
    if (!paths || paths->kind != SLUICE_NODE_SEQUENCE || paths->count == 0)
        return 0;
    size_t n = paths->count;
    sluice_node **parents = calloc(n, sizeof *parents);
    size_t *indices = calloc(n, sizeof *indices);
    sluice_node **removed = calloc(n, sizeof *removed);
    int errors = 0;
    if (!parents || !indices || !removed) {
        path_error(diag, paths, "%s: out of memory", context);
        errors = 1;
        goto done;
    }
    /* every path addresses the tree as it is: all are found before any is
     * removed, so indices do not shift under later entries */
    for (size_t i = 0; i < n; i++) {
        const sluice_node *path = paths->items[i];
        path_walk w = {.path = path->value};
        if (path->kind != SLUICE_NODE_SCALAR) {
            path_error(diag, path, "%s: each entry of 'remove' must be a dotted path such as "
                       "plugins.two_phase", context);
            errors++;
        } else if (!root || root->kind != SLUICE_NODE_MAPPING) {
            path_error(diag, path, "%s: cannot remove '%s': the document is not a mapping",
                       context, path->value);
            errors++;
        } else if (walk_path(root, &w) != 0) {
            /* errors sit on the path's own node (an allocation failure too) */
            path_error(diag, path, "%s: cannot remove '%s': %s", context, path->value, w.why);
            errors++;
        } else {
            parents[i] = w.parent;
            indices[i] = w.index;
        }
    }
    if (errors)
        goto done;
    /* detach every node before any is freed: one may lie inside another
     * (then its parent is compacted before being freed with it) */
    for (size_t i = 0; i < n; i++) {
        removed[i] = parents[i]->items[indices[i]];
        parents[i]->items[indices[i]] = NULL;
    }
    for (size_t i = 0; i < n; i++)
        drop_empty_slots(parents[i]);
    for (size_t i = 0; i < n; i++)
        sluice_node_free(removed[i]);
done:
    free(parents);
    free(indices);
    free(removed);
    return errors;
}

int sluice_yaml_set(sluice_node *root, const char *path, sluice_node *value,
                    const sluice_node *at, const char *context, sluice_diag *diag)
{
    if (!value) {
        path_error(diag, at, "%s: out of memory", context);
        return -1;
    }
    if (!root || root->kind != SLUICE_NODE_MAPPING) {
        path_error(diag, at, "%s: cannot set '%s': the document is not a mapping", context,
                   path);
        sluice_node_free(value);
        return -1;
    }
    /* created keys, and every error, sit at the setting's YAML key `at` */
    path_walk w = {.path = path,
                   .value = value,
                   .file = at ? at->file : NULL,
                   .line = at ? at->line : 0,
                   .column = at ? at->column : 0};
    int rc = walk_path(root, &w);
    if (rc == WALK_FAILED)
        path_error(diag, at, "%s: cannot set '%s': %s", context, path, w.why);
    else if (rc == WALK_OUT_OF_MEMORY)
        path_error(diag, at, "%s: out of memory", context);
    return rc == 0 ? 0 : -1;
}

/* ------------------------------------------------------------- emitting -- */

typedef struct buffer {
    char *data;
    size_t length, capacity;
    int failed;
} buffer;

static void put(buffer *b, const char *text, size_t n)
{
    if (b->failed)
        return;
    if (b->capacity - b->length <= n) {
        size_t cap = b->capacity ? b->capacity : 256;
        while (cap - b->length <= n) {
            if (cap > SIZE_MAX / 2) {
                b->failed = 1;
                return;
            }
            cap *= 2;
        }
        char *d = realloc(b->data, cap);
        if (!d) {
            b->failed = 1;
            return;
        }
        b->data = d;
        b->capacity = cap;
    }
    memcpy(b->data + b->length, text, n);
    b->length += n;
    b->data[b->length] = '\0';
}

static void put_string(buffer *b, const char *text)
{
    put(b, text, strlen(text));
}

static void put_indent(buffer *b, size_t indent)
{
    static const char spaces[] = "                                ";
    while (indent > 0) {
        size_t n = indent < sizeof spaces - 1 ? indent : sizeof spaces - 1;
        put(b, spaces, n);
        indent -= n;
    }
}

/* Decodes one UTF-8 character; returns its length (1 for an invalid byte,
 * with *code = 0xFFFFFFFF). */
static size_t utf8_decode(const unsigned char *s, uint32_t *code)
{
    if (s[0] < 0x80) {
        *code = s[0];
        return 1;
    }
    size_t n = (s[0] & 0xE0) == 0xC0 ? 2 : (s[0] & 0xF0) == 0xE0 ? 3 : (s[0] & 0xF8) == 0xF0 ? 4 : 0;
    uint32_t c = n == 2 ? s[0] & 0x1Fu : n == 3 ? s[0] & 0x0Fu : s[0] & 0x07u;
    for (size_t i = 1; i < n; i++) {
        if ((s[i] & 0xC0) != 0x80) {
            n = 0;
            break;
        }
        c = (c << 6) | (s[i] & 0x3Fu);
    }
    if (n == 0) {
        *code = 0xFFFFFFFFu;
        return 1;
    }
    *code = c;
    return n;
}

/* Characters that must be escaped inside double quotes (line breaks and
 * characters YAML does not allow in a stream). */
static int needs_escape(uint32_t c)
{
    if (c == 0xFFFFFFFFu)
        return 0; /* invalid byte: copied as it is */
    return c < 0x20 || c == '"' || c == '\\' || (c >= 0x7F && c <= 0x9F) || c == 0x2028 ||
           c == 0x2029 || c == 0xFEFF || c == 0xFFFE || c == 0xFFFF || (c >= 0xD800 && c <= 0xDFFF);
}

static void put_quoted(buffer *b, const char *text)
{
    const unsigned char *s = (const unsigned char *)text;
    put(b, "\"", 1);
    while (*s) {
        uint32_t c;
        size_t n = utf8_decode(s, &c);
        if (!needs_escape(c)) {
            put(b, (const char *)s, n);
        } else {
            char escape[16];
            switch (c) {
            case '"': snprintf(escape, sizeof escape, "\\\""); break;
            case '\\': snprintf(escape, sizeof escape, "\\\\"); break;
            case '\n': snprintf(escape, sizeof escape, "\\n"); break;
            case '\t': snprintf(escape, sizeof escape, "\\t"); break;
            case '\r': snprintf(escape, sizeof escape, "\\r"); break;
            case 0x85: snprintf(escape, sizeof escape, "\\N"); break;
            case 0x2028: snprintf(escape, sizeof escape, "\\L"); break;
            case 0x2029: snprintf(escape, sizeof escape, "\\P"); break;
            default:
                if (c <= 0xFF)
                    snprintf(escape, sizeof escape, "\\x%02X", (unsigned)c);
                else
                    snprintf(escape, sizeof escape, "\\u%04X", (unsigned)c);
            }
            put_string(b, escape);
        }
        s += n;
    }
    put(b, "\"", 1);
}

static int flow_indicator(char c)
{
    return c == ',' || c == '[' || c == ']' || c == '{' || c == '}';
}

/* Whether text written plain reads back as the same plain scalar, in block
 * context or (flow) inside a flow sequence. */
static int plain_safe(const char *text, int flow)
{
    size_t n = strlen(text);
    if (n == 0)
        return 0;
    char c0 = text[0];
    if (strchr(",[]{}#&*!|>'\"%@`", c0))
        return 0;
    if ((c0 == '-' || c0 == '?' || c0 == ':') &&
        (n == 1 || text[1] == ' ' || (flow && flow_indicator(text[1]))))
        return 0;
    if (flow && c0 == '?') /* "[?x]" reads as a mapping */
        return 0;
    if (c0 == ' ' || text[n - 1] == ' ')
        return 0;
    if (strncmp(text, "---", 3) == 0 || strncmp(text, "...", 3) == 0)
        return 0;
    for (size_t i = 0; i < n;) {
        char c = text[i];
        if (c == ':' && (flow || i + 1 == n || text[i + 1] == ' '))
            return 0;
        if (c == '#' && i > 0 && text[i - 1] == ' ')
            return 0;
        if (flow && flow_indicator(c))
            return 0;
        uint32_t code;
        size_t len = utf8_decode((const unsigned char *)text + i, &code);
        if (code == 0xFFFFFFFFu || needs_escape(code) || code == '\t')
            return 0;
        i += len;
    }
    return 1;
}

/* A sequence written on one line: every item a scalar that flow style keeps
 * exactly (an empty plain scalar cannot be written in a flow sequence). */
static int flow_sequence(const sluice_node *node)
{
    if (node->kind != SLUICE_NODE_SEQUENCE)
        return 0;
    for (size_t i = 0; i < node->count; i++) {
        const sluice_node *item = node->items[i];
        if (item->kind != SLUICE_NODE_SCALAR)
            return 0;
        if (item->plain && !plain_safe(item->value, 1))
            return 0;
    }
    return 1;
}

static int one_line(const sluice_node *node)
{
    return node->kind == SLUICE_NODE_SCALAR || node->count == 0 || flow_sequence(node);
}

static void put_scalar(buffer *b, const sluice_node *node, int flow)
{
    const char *value = node->value ? node->value : "";
    if (node->plain && plain_safe(value, flow))
        put_string(b, value);
    else
        put_quoted(b, value);
}

/* Writes a one-line node (see one_line) after a space; an empty plain scalar
 * is written as nothing, which reads back as one. */
static void put_one_line(buffer *b, const sluice_node *node)
{
    if (empty_plain(node)) {
        put(b, "\n", 1);
        return;
    }
    put(b, " ", 1);
    if (node->kind == SLUICE_NODE_SCALAR) {
        put_scalar(b, node, 0);
    } else if (node->count == 0) {
        put_string(b, node->kind == SLUICE_NODE_MAPPING ? "{}" : "[]");
    } else {
        put(b, "[", 1);
        for (size_t i = 0; i < node->count; i++) {
            if (i)
                put(b, ", ", 2);
            put_scalar(b, node->items[i], 1);
        }
        put(b, "]", 1);
    }
    put(b, "\n", 1);
}

static void emit_sequence(buffer *b, const sluice_node *node, size_t indent, int inline_first);

/* inline_first: the first entry continues the current line (after "- "). */
static void emit_mapping(buffer *b, const sluice_node *node, size_t indent, int inline_first)
{
    for (size_t i = 0; i < node->count; i++) {
        if (i > 0 || !inline_first)
            put_indent(b, indent);
        const sluice_node *key = node->keys[i], *value = node->items[i];
        if (key->kind == SLUICE_NODE_SCALAR && !empty_plain(key))
            put_scalar(b, key, 0);
        else
            put_quoted(b, key->kind == SLUICE_NODE_SCALAR && key->value ? key->value : "");
        put(b, ":", 1);
        if (one_line(value)) {
            put_one_line(b, value);
        } else {
            put(b, "\n", 1);
            if (value->kind == SLUICE_NODE_MAPPING)
                emit_mapping(b, value, indent + 2, 0);
            else
                emit_sequence(b, value, indent + 2, 0);
        }
    }
}

static void emit_sequence(buffer *b, const sluice_node *node, size_t indent, int inline_first)
{
    for (size_t i = 0; i < node->count; i++) {
        if (i > 0 || !inline_first)
            put_indent(b, indent);
        put(b, "-", 1);
        const sluice_node *item = node->items[i];
        if (one_line(item)) {
            put_one_line(b, item);
        } else {
            put(b, " ", 1);
            if (item->kind == SLUICE_NODE_MAPPING)
                emit_mapping(b, item, indent + 2, 1);
            else
                emit_sequence(b, item, indent + 2, 1);
        }
    }
}

char *sluice_yaml_emit(const sluice_node *root)
{
    buffer b = {NULL, 0, 0, 0};
    put(&b, "", 0); /* an empty tree still gives a string */
    if (root) {
        if (root->kind == SLUICE_NODE_SCALAR && empty_plain(root)) {
            put_string(&b, "\"\"\n");
        } else if (one_line(root)) {
            put_one_line(&b, root);
            /* drop the separating space */
            if (!b.failed && b.length > 0 && b.data[0] == ' ')
                memmove(b.data, b.data + 1, b.length--);
        } else if (root->kind == SLUICE_NODE_MAPPING) {
            emit_mapping(&b, root, 0, 0);
        } else {
            emit_sequence(&b, root, 0, 0);
        }
    }
    if (b.failed) {
        free(b.data);
        return NULL;
    }
    return b.data;
}

/* --------------------------------------------------------- suggestions -- */

size_t sluice_edit_distance(const char *a, const char *b)
{
    size_t n = strlen(a), m = strlen(b);
    if (m > n) { /* keep the row short */
        const char *t = a;
        a = b;
        b = t;
        size_t u = n;
        n = m;
        m = u;
    }
    size_t stack_row[64];
    size_t *row = stack_row;
    if (m + 1 > sizeof stack_row / sizeof stack_row[0]) {
        if (m + 1 > SIZE_MAX / sizeof *row)
            return SIZE_MAX;
        row = malloc((m + 1) * sizeof *row);
        if (!row)
            return SIZE_MAX;
    }
    for (size_t j = 0; j <= m; j++)
        row[j] = j;
    for (size_t i = 1; i <= n; i++) {
        size_t diagonal = row[0];
        row[0] = i;
        for (size_t j = 1; j <= m; j++) {
            size_t above = row[j];
            size_t best = diagonal + (a[i - 1] != b[j - 1]);
            if (above + 1 < best)
                best = above + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diagonal = above;
        }
    }
    size_t result = row[m];
    if (row != stack_row)
        free(row);
    return result;
}

const char *sluice_closest(const char *word, const char *const *candidates, size_t count)
{
    if (!word || !candidates)
        return NULL;
    size_t limit = strlen(word) / 3;
    if (limit < 2)
        limit = 2;
    const char *best = NULL;
    size_t best_distance = SIZE_MAX;
    for (size_t i = 0; i < count; i++) {
        if (!candidates[i])
            continue;
        size_t d = sluice_edit_distance(word, candidates[i]);
        if (d < best_distance) {
            best_distance = d;
            best = candidates[i];
        }
    }
    return best_distance <= limit ? best : NULL;
}
