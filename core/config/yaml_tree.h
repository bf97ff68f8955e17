/* A YAML document as a tree of nodes that remember where they came from, so
 * every error can name file, line and column. Loaded with libyaml. */
#ifndef SLUICE_YAML_TREE_H
#define SLUICE_YAML_TREE_H

#include <stddef.h>

#include "diag.h"

typedef enum sluice_node_kind {
    SLUICE_NODE_SCALAR = 0,
    SLUICE_NODE_SEQUENCE = 1,
    SLUICE_NODE_MAPPING = 2
} sluice_node_kind;

typedef struct sluice_node sluice_node;
struct sluice_node {
    sluice_node_kind kind;
    const char *file; /* source file name (or "--set #k" / "default"); owned by the node */
    int line, column; /* 1-based; 0 for nodes created by the program (defaults) */
    char *value;      /* SCALAR: the text */
    int plain;        /* SCALAR: 1 when written without quotes */
    size_t count;     /* SEQUENCE: items; MAPPING: key/value pairs */
    sluice_node **items; /* SEQUENCE items, or MAPPING values */
    sluice_node **keys;  /* MAPPING keys (scalar nodes) */
    int used;         /* set by consumers; unused keys are reported as unknown */
};

/* Parses a file / a string holding exactly one YAML document. On error adds
 * messages to diag (YAML syntax errors with their position, duplicate keys,
 * non-scalar keys, more than one document, empty document) and returns NULL.
 * `name` is the file name used in messages. The tree owns a copy of name. */
sluice_node *sluice_yaml_parse_file(const char *path, sluice_diag *diag);
sluice_node *sluice_yaml_parse_string(const char *text, size_t length, const char *name,
                                      sluice_diag *diag);
void sluice_node_free(sluice_node *node);

/* Mapping lookup (NULL if absent or node is not a mapping). */
sluice_node *sluice_node_get(const sluice_node *mapping, const char *key);
/* Key node of a mapping entry (for its position), or NULL. */
sluice_node *sluice_node_get_key(const sluice_node *mapping, const char *key);

/* Node construction (for defaults and --set): nodes made here have line 0
 * unless the caller sets them. Return NULL when out of memory. */
sluice_node *sluice_node_new_scalar(const char *value, int plain, const char *file, int line,
                                    int column);
sluice_node *sluice_node_new_mapping(const char *file, int line, int column);
sluice_node *sluice_node_new_sequence(const char *file, int line, int column);
/* Appends an item to a sequence / sets key in a mapping (replacing and
 * freeing an old value). Take ownership of value, also on failure (then it is
 * freed). 0 on success, -1 on OOM. */
int sluice_node_append(sluice_node *sequence, sluice_node *value);
int sluice_node_set(sluice_node *mapping, const char *key, sluice_node *value);
sluice_node *sluice_node_clone(const sluice_node *node);

/* Applies a command-line override "dotted.key=value" to the tree: the value is
 * parsed as YAML (a scalar or a flow sequence/mapping such as [0, -9.81]);
 * missing intermediate mappings are created; in a sequence a segment
 * addresses an existing item by its 0-based index or by the value of its
 * `name` key; a path through a scalar is an error. Nodes created
 * from it carry file = origin and column = position in the argument. `origin` names the argument in messages, e.g.
 * "--set #2". Returns 0 or -1 (message in diag). */
int sluice_yaml_override(sluice_node *root, const char *assignment, const char *origin,
                         sluice_diag *diag);

/* Edits by dotted path (scene variants, docs/scene-format.md). A segment
 * addresses a mapping key, or an item of a list by its 0-based index or by
 * the value of the item's `name` key (as in sluice_yaml_override). Messages
 * are positioned at the node naming the path and start with `context`
 * (e.g. "variant 'no_air'").
 *
 * sluice_yaml_remove deletes the node each scalar of the sequence `paths`
 * addresses. Every path must exist; all are found in the tree as it is before
 * any is removed (list indices do not shift between entries), and nothing is
 * removed when one is missing. Returns the number of errors.
 *
 * sluice_yaml_set puts `value` (owned, also on failure) at `path`, replacing
 * what is there and creating missing mapping keys (positioned at `at`); a
 * list item must exist. Returns 0 or -1. */
int sluice_yaml_remove(sluice_node *root, const sluice_node *paths, const char *context,
                       sluice_diag *diag);
int sluice_yaml_set(sluice_node *root, const char *path, sluice_node *value,
                    const sluice_node *at, const char *context, sluice_diag *diag);

/* Block-style YAML text of a tree, re-parsable, keys in tree order, scalars
 * quoted when needed. malloc'd; NULL on OOM. */
char *sluice_yaml_emit(const sluice_node *root);

/* Marks node and all its descendants used / unused. */
void sluice_node_mark_used(sluice_node *node, int used);

/* Classic edit distance, used for "did you mean" suggestions. */
size_t sluice_edit_distance(const char *a, const char *b);
/* The candidate closest to word, if it is close enough to be a plausible typo
 * (distance <= max(2, strlen(word) / 3)); NULL otherwise. */
const char *sluice_closest(const char *word, const char *const *candidates, size_t count);

#endif
