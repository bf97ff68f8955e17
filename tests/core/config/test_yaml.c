/* The YAML tree: loading with positions, error messages, overrides,
 * emission and round trips, suggestions. */
#define _POSIX_C_SOURCE 200809L
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene.h"
#include "test_util.h"
#include "yaml_tree.h"

/* ------------------------------------------------------------- helpers -- */

static sluice_node *parse(const char *text, sluice_diag *diag)
{
    return sluice_yaml_parse_string(text, strlen(text), "scene.yaml", diag);
}

/* Parses text that must be valid. */
static sluice_node *parse_ok(const char *text)
{
    sluice_diag *diag = sluice_diag_create();
    ck_assert_ptr_nonnull(diag);
    sluice_node *root = parse(text, diag);
    ck_assert_msg(root && sluice_diag_count(diag) == 0, "unexpected failure for:\n%s\n%s", text,
                  sluice_diag_count(diag) ? sluice_diag_message(diag, 0) : "(no message)");
    sluice_diag_destroy(diag);
    return root;
}

/* Parses text that must fail with exactly one message, equal to `expected`. */
static void expect_parse_error(const char *text, const char *expected)
{
    sluice_diag *diag = sluice_diag_create();
    sluice_node *root = parse(text, diag);
    ck_assert_ptr_null(root);
    ck_assert_msg(sluice_diag_count(diag) == 1, "expected one message for:\n%s\ngot %zu", text,
                  sluice_diag_count(diag));
    ck_assert_str_eq(sluice_diag_message(diag, 0), expected);
    ck_assert_uint_eq(sluice_diag_error_count(diag), 1);
    sluice_diag_destroy(diag);
}

static int trees_equal(const sluice_node *a, const sluice_node *b)
{
    if (a->kind != b->kind || a->count != b->count)
        return 0;
    if (a->kind == SLUICE_NODE_SCALAR)
        return strcmp(a->value, b->value) == 0 && a->plain == b->plain;
    for (size_t i = 0; i < a->count; i++) {
        if (a->kind == SLUICE_NODE_MAPPING && !trees_equal(a->keys[i], b->keys[i]))
            return 0;
        if (!trees_equal(a->items[i], b->items[i]))
            return 0;
    }
    return 1;
}

/* parse -> emit -> parse must give an equal tree. Returns the emitted text. */
static char *round_trip(const char *text)
{
    sluice_node *first = parse_ok(text);
    char *emitted = sluice_yaml_emit(first);
    ck_assert_ptr_nonnull(emitted);
    sluice_node *second = parse_ok(emitted);
    ck_assert_msg(trees_equal(first, second), "round trip changed the tree:\n%s\n--- emitted:\n%s",
                  text, emitted);
    sluice_node_free(first);
    sluice_node_free(second);
    return emitted;
}

static void expect_position(const sluice_node *node, int line, int column)
{
    ck_assert_ptr_nonnull(node);
    ck_assert_msg(node->line == line && node->column == column, "position %d:%d, expected %d:%d",
                  node->line, node->column, line, column);
}

/* ------------------------------------------------------------- loading -- */

START_TEST(positions_kinds_and_plain_flags)
{
    sluice_node *root = parse_ok("dimensions: 2\n"
                                 "plugins:\n"
                                 "  tait:\n"
                                 "    speed_of_sound: 20\n"
                                 "  gravity: {g: [0, -9.81]}\n"
                                 "  empty:\n"
                                 "title: 'a \"title\"'\n"
                                 "list:\n"
                                 "  - a\n"
                                 "  - \"1.0\"\n");
    ck_assert_int_eq(root->kind, SLUICE_NODE_MAPPING);
    ck_assert_uint_eq(root->count, 4);
    ck_assert_str_eq(root->file, "scene.yaml");
    expect_position(sluice_node_get_key(root, "dimensions"), 1, 1);
    expect_position(sluice_node_get(root, "dimensions"), 1, 13);

    sluice_node *plugins = sluice_node_get(root, "plugins");
    expect_position(sluice_node_get_key(plugins, "gravity"), 5, 3);
    sluice_node *tait = sluice_node_get(plugins, "tait");
    ck_assert_int_eq(tait->kind, SLUICE_NODE_MAPPING);
    expect_position(tait, 4, 5);
    expect_position(sluice_node_get_key(tait, "speed_of_sound"), 4, 5);
    sluice_node *c0 = sluice_node_get(tait, "speed_of_sound");
    expect_position(c0, 4, 21);
    ck_assert_str_eq(c0->value, "20");
    ck_assert_int_eq(c0->plain, 1);

    sluice_node *g = sluice_node_get(sluice_node_get(plugins, "gravity"), "g");
    ck_assert_int_eq(g->kind, SLUICE_NODE_SEQUENCE);
    expect_position(g, 5, 16);
    expect_position(g->items[1], 5, 20);
    ck_assert_str_eq(g->items[1]->value, "-9.81");

    /* `empty:` with nothing is a plain empty scalar */
    sluice_node *empty = sluice_node_get(plugins, "empty");
    ck_assert_int_eq(empty->kind, SLUICE_NODE_SCALAR);
    ck_assert_str_eq(empty->value, "");
    ck_assert_int_eq(empty->plain, 1);

    sluice_node *title = sluice_node_get(root, "title");
    ck_assert_str_eq(title->value, "a \"title\"");
    ck_assert_int_eq(title->plain, 0);
    sluice_node *list = sluice_node_get(root, "list");
    expect_position(list, 9, 3);
    ck_assert_int_eq(list->items[1]->plain, 0);
    ck_assert_str_eq(list->items[1]->value, "1.0");

    ck_assert_ptr_null(sluice_node_get(root, "missing"));
    ck_assert_ptr_null(sluice_node_get_key(root, "missing"));
    ck_assert_ptr_null(sluice_node_get(c0, "x")); /* not a mapping */
    sluice_node_free(root);
}
END_TEST

START_TEST(explicit_string_tag_is_not_plain)
{
    sluice_node *root = parse_ok("a: !!str 5\nb: 5\n");
    ck_assert_int_eq(sluice_node_get(root, "a")->plain, 0);
    ck_assert_int_eq(sluice_node_get(root, "b")->plain, 1);
    sluice_node_free(root);
}
END_TEST

START_TEST(syntax_errors_have_libyaml_position_and_text)
{
    expect_parse_error("time:\n"
                       "  end: 1\n"
                       "particles:\n"
                       "  spacing: 0.05: 2\n",
                       "scene.yaml:4:16: error: YAML syntax error: mapping values are not "
                       "allowed in this context");
    /* with libyaml's context */
    expect_parse_error("a: [1, 2\n"
                       "b: 3\n",
                       "scene.yaml:2:2: error: YAML syntax error: did not find expected ',' or "
                       "']' (while parsing a flow sequence that started at line 1, column 4)");
    /* reader errors only know a byte offset */
    expect_parse_error("a: 1\nb: \xff\n",
                       "scene.yaml:2:4: error: YAML syntax error: invalid leading UTF-8 octet "
                       "(byte 0xff)");
}
END_TEST

START_TEST(duplicate_keys)
{
    expect_parse_error("a: 1\n"
                       "b: 2\n"
                       "a: 3\n",
                       "scene.yaml:3:1: error: duplicate key 'a' at the top level (first at line 1)");
    expect_parse_error("plugins:\n"
                       "  tait:\n"
                       "    gamma: 7\n"
                       "    gamma: 8\n",
                       "scene.yaml:4:5: error: duplicate key 'gamma' in plugins.tait (first at "
                       "line 3)");
    expect_parse_error("walls:\n"
                       "  - {shape: box, shape: tank}\n",
                       "scene.yaml:2:18: error: duplicate key 'shape' in walls.0 (first at line "
                       "2)");
    /* every duplicate is reported */
    sluice_diag *diag = sluice_diag_create();
    ck_assert_ptr_null(parse("a: 1\na: 2\nb: 1\nb: 2\n", diag));
    ck_assert_uint_eq(sluice_diag_count(diag), 2);
    sluice_diag_destroy(diag);
}
END_TEST

START_TEST(non_scalar_keys)
{
    expect_parse_error("plugins:\n"
                       "  ? [a, b]\n"
                       "  : 1\n",
                       "scene.yaml:2:5: error: a key in plugins is a list; keys must be scalars");
    expect_parse_error("{a: 1}: 2\n",
                       "scene.yaml:1:1: error: a key at the top level is a mapping; keys must be "
                       "scalars");
}
END_TEST

START_TEST(aliases_are_cloned)
{
    sluice_node *root = parse_ok("base: &b {x: 1, y: [1, 2]}\n"
                                 "copy: *b\n"
                                 "scalar: &s hello\n"
                                 "again: *s\n");
    sluice_node *base = sluice_node_get(root, "base"), *copy = sluice_node_get(root, "copy");
    ck_assert_ptr_ne(base, copy);
    ck_assert(trees_equal(base, copy));
    ck_assert_ptr_ne(base->items[1], copy->items[1]);
    expect_position(copy, 2, 7); /* the copy sits where the alias is */
    expect_position(sluice_node_get(root, "again"), 4, 8);
    ck_assert_str_eq(sluice_node_get(root, "again")->value, "hello");
    /* changing the copy leaves the original alone (a tree, not a DAG) */
    ck_assert_int_eq(sluice_node_set(copy, "x", sluice_node_new_scalar("2", 1, NULL, 0, 0)), 0);
    ck_assert_str_eq(sluice_node_get(base, "x")->value, "1");
    sluice_node_free(root);

    expect_parse_error("a: *nope\n",
                       "scene.yaml:1:4: error: undefined alias '*nope' in a");
    expect_parse_error("a: &r [1, *r]\n",
                       "scene.yaml:1:11: error: alias '*r' in a.1 refers to a node that contains "
                       "it; recursive aliases are not allowed");
}
END_TEST

START_TEST(alias_expansion_is_bounded)
{
    const char *bomb = "a: &a [x, x, x, x, x, x, x, x, x, x]\n"
                       "b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]\n"
                       "c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b]\n"
                       "d: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c, *c]\n"
                       "e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d, *d]\n"
                       "f: &f [*e, *e, *e, *e, *e, *e, *e, *e, *e, *e]\n";
    sluice_diag *diag = sluice_diag_create();
    ck_assert_ptr_null(parse(bomb, diag));
    ck_assert_uint_eq(sluice_diag_count(diag), 1);
    ck_assert_msg(strstr(sluice_diag_message(diag, 0), "aliases expand to more than 100000 nodes"),
                  "%s", sluice_diag_message(diag, 0));
    sluice_diag_destroy(diag);
}
END_TEST

START_TEST(nesting_depth_is_bounded)
{
    char text[2100];
    memset(text, '[', 1001);
    memset(text + 1001, ']', 1001);
    text[2002] = '\0';
    sluice_diag *diag = sluice_diag_create();
    ck_assert_ptr_null(parse(text, diag));
    ck_assert_uint_eq(sluice_diag_count(diag), 1);
    ck_assert_msg(strstr(sluice_diag_message(diag, 0),
                         "scene.yaml:1:1001: error: collections are nested more than 1000 levels"),
                  "%s", sluice_diag_message(diag, 0));
    sluice_diag_destroy(diag);
}
END_TEST

START_TEST(one_document_only)
{
    expect_parse_error("a: 1\n"
                       "---\n"
                       "b: 2\n",
                       "scene.yaml:2:1: error: a second YAML document starts here; the input must "
                       "hold exactly one");
    expect_parse_error("", "scene.yaml:1:1: error: the file is empty");
    expect_parse_error("# just a comment\n\n   # another\n",
                       "scene.yaml:1:1: error: the file is empty");
    sluice_node *root = parse_ok("---\na: 1\n...\n");
    ck_assert_str_eq(sluice_node_get(root, "a")->value, "1");
    sluice_node_free(root);
}
END_TEST

START_TEST(files)
{
    char dir[] = "/tmp/sluice-test-yaml-XXXXXX";
    ck_assert_ptr_nonnull(mkdtemp(dir));
    char *path = malloc(strlen(dir) + 16);
    ck_assert_ptr_nonnull(path);
    sprintf(path, "%s/scene.yaml", dir);
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs("a:\n  b: [1, 2]\n", f);
    fclose(f);

    sluice_diag *diag = sluice_diag_create();
    sluice_node *root = sluice_yaml_parse_file(path, diag);
    ck_assert_ptr_nonnull(root);
    char expected_file[256];
    snprintf(expected_file, sizeof expected_file, "%s", path);
    unlink(path);
    /* the tree keeps its own copy of the name */
    memset(path, 'x', strlen(path));
    free(path);
    sluice_node *b = sluice_node_get(sluice_node_get(root, "a"), "b");
    ck_assert_str_eq(b->file, expected_file);
    ck_assert_str_eq(b->items[0]->file, expected_file);
    expect_position(b->items[1], 2, 10);
    sluice_node_free(root);

    /* a missing file and a directory */
    char missing[300], expected[400];
    snprintf(missing, sizeof missing, "%s/nope.yaml", dir);
    ck_assert_ptr_null(sluice_yaml_parse_file(missing, diag));
    snprintf(expected, sizeof expected, "%s:1:1: error: cannot read file: No such file or directory",
             missing);
    ck_assert_str_eq(sluice_diag_message(diag, 0), expected);
    ck_assert_ptr_null(sluice_yaml_parse_file(dir, diag));
    snprintf(expected, sizeof expected, "%s:1:1: error: cannot read file: Is a directory", dir);
    ck_assert_str_eq(sluice_diag_message(diag, 1), expected);
    ck_assert_uint_eq(sluice_diag_count(diag), 2);
    sluice_diag_destroy(diag);
    rmdir(dir);
}
END_TEST

/* ---------------------------------------------------------- node API -- */

START_TEST(node_construction)
{
    sluice_node *root = sluice_node_new_mapping("default", 0, 0);
    sluice_node *list = sluice_node_new_sequence("default", 0, 0);
    ck_assert_ptr_nonnull(root);
    ck_assert_ptr_nonnull(list);
    ck_assert_int_eq(sluice_node_append(list, sluice_node_new_scalar("1", 1, "default", 0, 0)), 0);
    ck_assert_int_eq(sluice_node_append(list, sluice_node_new_scalar("x y", 0, "default", 0, 0)),
                     0);
    ck_assert_int_eq(sluice_node_set(root, "list", list), 0);
    ck_assert_int_eq(sluice_node_set(root, "n", sluice_node_new_scalar("3", 1, "default", 0, 0)),
                     0);
    /* replacing frees the old value (ASan checks) */
    ck_assert_int_eq(sluice_node_set(root, "n", sluice_node_new_scalar("4", 1, "default", 0, 0)),
                     0);
    ck_assert_uint_eq(root->count, 2);
    ck_assert_str_eq(sluice_node_get(root, "n")->value, "4");
    ck_assert_int_eq(sluice_node_get(root, "n")->line, 0);
    /* wrong kinds are refused (and the value is released) */
    ck_assert_int_eq(sluice_node_append(root, sluice_node_new_scalar("z", 1, NULL, 0, 0)), -1);
    ck_assert_int_eq(sluice_node_set(list, "k", sluice_node_new_scalar("z", 1, NULL, 0, 0)), -1);
    ck_assert_int_eq(sluice_node_set(root, "k", NULL), -1);

    sluice_node *copy = sluice_node_clone(root);
    ck_assert(trees_equal(root, copy));
    ck_assert_ptr_ne(copy->items[0], root->items[0]);
    ck_assert_str_eq(copy->file, "default");
    /* appending to a clone works (arrays are sized exactly) */
    ck_assert_int_eq(sluice_node_append(sluice_node_get(copy, "list"),
                                        sluice_node_new_scalar("5", 1, NULL, 0, 0)),
                     0);
    ck_assert_uint_eq(sluice_node_get(copy, "list")->count, 3);
    ck_assert_uint_eq(list->count, 2);

    sluice_node_mark_used(root, 1);
    ck_assert_int_eq(list->items[1]->used, 1);
    ck_assert_int_eq(sluice_node_get_key(root, "n")->used, 1);
    ck_assert_int_eq(copy->used, 0);
    sluice_node_mark_used(root, 0);
    ck_assert_int_eq(list->used, 0);

    char *text = sluice_yaml_emit(root);
    ck_assert_str_eq(text, "list: [1, \"x y\"]\nn: 4\n");
    free(text);
    sluice_node_free(root);
    sluice_node_free(copy);
    sluice_node_free(NULL);
}
END_TEST

/* ------------------------------------------------------------ emitting -- */

START_TEST(emit_block_style)
{
    sluice_node *root = parse_ok("dimensions: 2\n"
                                 "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
                                 "geometry:\n"
                                 "  fluid:\n"
                                 "    - {shape: polygon, points: [[0, 0], [1, 0], [0, 1]]}\n"
                                 "  walls: []\n"
                                 "plugins:\n"
                                 "  wendland_c2: {}\n"
                                 "  tait:\n"
                                 "    speed_of_sound: 20\n"
                                 "  dbc:\n"
                                 "title: \"1.0\"\n"
                                 "nested:\n"
                                 "  - - a\n"
                                 "    - - b\n"
                                 "      - {c: d}\n");
    char *text = sluice_yaml_emit(root);
    ck_assert_str_eq(text, "dimensions: 2\n"
                           "domain:\n"
                           "  min: [-0.2, -0.2]\n"
                           "  max: [1.2, 1.2]\n"
                           "geometry:\n"
                           "  fluid:\n"
                           "    - shape: polygon\n"
                           "      points:\n"
                           "        - [0, 0]\n"
                           "        - [1, 0]\n"
                           "        - [0, 1]\n"
                           "  walls: []\n"
                           "plugins:\n"
                           "  wendland_c2: {}\n"
                           "  tait:\n"
                           "    speed_of_sound: 20\n"
                           "  dbc:\n"
                           "title: \"1.0\"\n"
                           "nested:\n"
                           "  - - a\n"
                           "    - - b\n"
                           "      - c: d\n");
    free(text);
    sluice_node_free(root);
}
END_TEST

START_TEST(emit_quotes_only_when_needed)
{
    static const struct {
        const char *value;
        int plain;
        const char *written;
    } cases[] = {
        {"plain text", 1, "plain text"},
        {"-9.81", 1, "-9.81"},
        {"yes", 1, "yes"},            /* plain stays plain: it reads back the same */
        {"a:b", 1, "a:b"},
        {"a#b", 1, "a#b"},
        {"1.0", 0, "\"1.0\""},        /* quoted number stays quoted */
        {"true", 0, "\"true\""},
        {"water", 0, "\"water\""},     /* quoted in the source: stays quoted */
        {"", 0, "\"\""},
        {" lead", 1, "\" lead\""},
        {"trail ", 1, "\"trail \""},
        {"a: b", 1, "\"a: b\""},
        {"a #b", 1, "\"a #b\""},
        {"ends:", 1, "\"ends:\""},
        {"- x", 1, "\"- x\""},
        {"-", 1, "\"-\""},
        {"#x", 1, "\"#x\""},
        {"{x", 1, "\"{x\""},
        {"[x", 1, "\"[x\""},
        {",x", 1, "\",x\""},
        {"&x", 1, "\"&x\""},
        {"*x", 1, "\"*x\""},
        {"!x", 1, "\"!x\""},
        {"|x", 1, "\"|x\""},
        {">x", 1, "\">x\""},
        {"'x", 1, "\"'x\""},
        {"\"x", 1, "\"\\\"x\""},
        {"%x", 1, "\"%x\""},
        {"@x", 1, "\"@x\""},
        {"`x", 1, "\"`x\""},
        {"---", 1, "\"---\""},
        {"two\nlines", 1, "\"two\\nlines\""},
        {"tab\there", 0, "\"tab\\there\""},
        {"back\\slash", 0, "\"back\\\\slash\""},
        {"caf\xc3\xa9", 1, "caf\xc3\xa9"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        sluice_node *root = sluice_node_new_mapping(NULL, 0, 0);
        ck_assert_int_eq(
            sluice_node_set(root, "k", sluice_node_new_scalar(cases[i].value, cases[i].plain,
                                                              NULL, 0, 0)),
            0);
        char *text = sluice_yaml_emit(root);
        char expected[128];
        snprintf(expected, sizeof expected, "k: %s\n", cases[i].written);
        ck_assert_str_eq(text, expected);
        /* and it reads back as the same value */
        sluice_node *again = parse_ok(text);
        ck_assert_str_eq(sluice_node_get(again, "k")->value, cases[i].value);
        ck_assert_int_eq(sluice_node_get(again, "k")->plain, strcmp(cases[i].written,
                                                                    cases[i].value) == 0);
        sluice_node_free(again);
        free(text);
        sluice_node_free(root);
    }
}
END_TEST

START_TEST(emit_round_trips)
{
    static const char *documents[] = {
        "a: 1\nb: [0, -9.81]\nc: {}\nd: []\ne:\n",
        "geometry:\n"
        "  fluid:\n"
        "    - shape: box\n"
        "      min: [0, 0]\n"
        "      max: [0.5, 0.5]\n"
        "    - {shape: polygon, points: [[0, 0], [1, 0], [0.5, 1]]}\n"
        "  walls:\n"
        "    - shape: tank\n"
        "      name: 'left: tank'\n"
        "      tags: [a, 'b, c', \"\", '1']\n",
        "- - - deep\n    - [x]\n  - {}\n- \n- k: v\n  l:\n    - m: [1, {n: 2}]\n",
        "quoted: ['1.0', \"true\", '', ' x ', 'a: b', 'it''s', \"\\t\\u00e9\\n\"]\n"
        "plain: [1.0, true, null, ~, x]\n"
        "'key with: colon': 1\n"
        "\"#hash\": 2\n"
        "'': empty key\n",
        "- [a, 'b,c']\n- [':x', '-']\n- - ''\n  -\n",
        "- ?x\n- y\n- a,b\n", /* plain here, but not inside [...] */
        "scalar at the root\n",
        "[1, 2, 3]\n",
        "{}\n",
    };
    for (size_t i = 0; i < sizeof documents / sizeof documents[0]; i++)
        free(round_trip(documents[i]));
    char *text = round_trip("- [a, 'b,c']\n- [x, y]\n- - \n  - z\n");
    /* items that flow style cannot keep exactly force block style */
    ck_assert_str_eq(text, "- [a, \"b,c\"]\n- [x, y]\n- -\n  - z\n");
    free(text);
}
END_TEST

/* ------------------------------------------------------------ overrides -- */

static const char *scene_text = "time:\n"
                                "  end: 1\n"
                                "plugins:\n"
                                "  tait:\n"
                                "  gravity: {g: [0, -9.81]}\n"
                                "geometry:\n"
                                "  fluid:\n"
                                "    - {shape: box, min: [0, 0]}\n";

START_TEST(override_creates_and_replaces)
{
    sluice_node *root = parse_ok(scene_text);
    sluice_diag *diag = sluice_diag_create();
    char origin[16];
    snprintf(origin, sizeof origin, "--set #1");
    ck_assert_int_eq(sluice_yaml_override(root, "time.end=0.2", origin, diag), 0);
    snprintf(origin, sizeof origin, "--set #2");
    ck_assert_int_eq(sluice_yaml_override(root, "plugins.tait.speed_of_sound=20", origin, diag), 0);
    snprintf(origin, sizeof origin, "--set #3");
    ck_assert_int_eq(sluice_yaml_override(root, "output.every.steps=[0, -9.81]", origin, diag), 0);
    snprintf(origin, sizeof origin, "--set #4");
    ck_assert_int_eq(sluice_yaml_override(root, "geometry.fluid.0.min.1=0.25", origin, diag), 0);
    snprintf(origin, sizeof origin, "--set #5");
    ck_assert_int_eq(sluice_yaml_override(root, "title='quoted'", origin, diag), 0);
    snprintf(origin, sizeof origin, "--set #6");
    ck_assert_int_eq(sluice_yaml_override(root, "plugins.gravity={g: [1, 2]}", origin, diag), 0);
    snprintf(origin, sizeof origin, "--set #7");
    ck_assert_int_eq(sluice_yaml_override(root, "description=", origin, diag), 0);
    ck_assert_uint_eq(sluice_diag_count(diag), 0);
    memset(origin, 0, sizeof origin); /* nodes keep their own copy */

    sluice_node *end = sluice_node_get(sluice_node_get(root, "time"), "end");
    ck_assert_str_eq(end->value, "0.2");
    ck_assert_str_eq(end->file, "--set #1");
    expect_position(end, 1, 10);
    /* the key that was in the file stays where it was */
    expect_position(sluice_node_get_key(sluice_node_get(root, "time"), "end"), 2, 3);

    /* `tait:` (empty) became a mapping that keeps its position */
    sluice_node *tait = sluice_node_get(sluice_node_get(root, "plugins"), "tait");
    ck_assert_int_eq(tait->kind, SLUICE_NODE_MAPPING);
    ck_assert_str_eq(tait->file, "scene.yaml");
    sluice_node *c0 = sluice_node_get(tait, "speed_of_sound");
    ck_assert_str_eq(c0->file, "--set #2");
    expect_position(c0, 1, 29);
    sluice_node *c0_key = sluice_node_get_key(tait, "speed_of_sound");
    ck_assert_str_eq(c0_key->file, "--set #2");
    expect_position(c0_key, 1, 14);

    /* missing mappings are created, each positioned at its segment */
    sluice_node *output = sluice_node_get(root, "output");
    ck_assert_int_eq(output->kind, SLUICE_NODE_MAPPING);
    expect_position(output, 1, 1);
    sluice_node *every = sluice_node_get(output, "every");
    expect_position(every, 1, 8);
    expect_position(sluice_node_get_key(every, "steps"), 1, 14);
    sluice_node *steps = sluice_node_get(every, "steps");
    ck_assert_int_eq(steps->kind, SLUICE_NODE_SEQUENCE);
    expect_position(steps, 1, 20);
    expect_position(steps->items[1], 1, 24);
    ck_assert_str_eq(steps->items[1]->value, "-9.81");

    /* numeric index into an existing sequence */
    sluice_node *fluid0 = sluice_node_get(sluice_node_get(root, "geometry"), "fluid")->items[0];
    sluice_node *min = sluice_node_get(fluid0, "min");
    ck_assert_str_eq(min->items[0]->file, "scene.yaml");
    ck_assert_str_eq(min->items[1]->value, "0.25");
    ck_assert_str_eq(min->items[1]->file, "--set #4");
    expect_position(min->items[1], 1, 24);

    ck_assert_int_eq(sluice_node_get(root, "title")->plain, 0);
    sluice_node *g = sluice_node_get(sluice_node_get(sluice_node_get(root, "plugins"), "gravity"),
                                     "g");
    ck_assert_str_eq(g->items[0]->value, "1");
    expect_position(g->items[0], 1, 22);
    sluice_node *description = sluice_node_get(root, "description");
    ck_assert_str_eq(description->value, "");
    ck_assert_int_eq(description->plain, 1);
    expect_position(description, 1, 13);

    char *text = sluice_yaml_emit(root);
    ck_assert_str_eq(text, "time:\n"
                           "  end: 0.2\n"
                           "plugins:\n"
                           "  tait:\n"
                           "    speed_of_sound: 20\n"
                           "  gravity:\n"
                           "    g: [1, 2]\n"
                           "geometry:\n"
                           "  fluid:\n"
                           "    - shape: box\n"
                           "      min: [0, 0.25]\n"
                           "output:\n"
                           "  every:\n"
                           "    steps: [0, -9.81]\n"
                           "title: \"quoted\"\n"
                           "description:\n");
    free(text);
    sluice_diag_destroy(diag);
    sluice_node_free(root);
}
END_TEST

/* Applies one override that must fail with exactly `expected`. */
static void expect_override_error(const char *assignment, const char *expected)
{
    sluice_node *root = parse_ok(scene_text);
    sluice_diag *diag = sluice_diag_create();
    ck_assert_int_eq(sluice_yaml_override(root, assignment, "--set #2", diag), -1);
    ck_assert_msg(sluice_diag_count(diag) == 1, "%s: %zu messages", assignment,
                  sluice_diag_count(diag));
    ck_assert_str_eq(sluice_diag_message(diag, 0), expected);
    /* the tree is unchanged */
    char *text = sluice_yaml_emit(root);
    sluice_node *original = parse_ok(scene_text);
    char *original_text = sluice_yaml_emit(original);
    ck_assert_str_eq(text, original_text);
    free(text);
    free(original_text);
    sluice_node_free(original);
    sluice_diag_destroy(diag);
    sluice_node_free(root);
}

START_TEST(override_errors)
{
    expect_override_error("time.end", "--set #2:1:1: error: the override 'time.end' has no '=': "
                                      "write key.path=value");
    expect_override_error("=3", "--set #2:1:1: error: the override '=3' names no key before '=': "
                                "write key.path=value");
    expect_override_error("time..end=3",
                          "--set #2:1:6: error: empty key in the path 'time..end' of the override");
    expect_override_error("time.end.x=3", "--set #2:1:10: error: cannot set 'time.end.x': "
                                          "time.end is a scalar, not a mapping");
    expect_override_error("geometry.fluid.3.min=[1, 1]",
                          "--set #2:1:16: error: cannot set 'geometry.fluid.3.min': index 3 is out "
                          "of range, geometry.fluid has 1 item");
    expect_override_error("geometry.fluid.first=1",
                          "--set #2:1:16: error: cannot set 'geometry.fluid.first': geometry.fluid "
                          "is a list, so 'first' must be a numeric index or the name of an item "
                          "(it has 1 item, none named)");
    /* value syntax errors: column inside the whole argument */
    expect_override_error("time.end=[1, 2", "--set #2:1:15: error: YAML syntax error: did not find "
                                            "expected ',' or ']' (while parsing a flow sequence "
                                            "that started at column 10)");
    expect_override_error("time.end={a: 1, a: 2}",
                          "--set #2:1:17: error: duplicate key 'a' in time.end (first at column "
                          "11)");
    expect_override_error("time.end=a: b",
                          "--set #2:1:10: error: the value for time.end must be a scalar or a flow "
                          "collection such as [1, 2] or {a: 1}; quote text that contains ': ' or "
                          "starts with '- '");
}
END_TEST

/* A tree with named and unnamed list items, for paths by name and index. */
static const char *named_text = "geometry:\n"                                       /* 1 */
                                "  fluid:\n"                                        /* 2 */
                                "    - {shape: box, name: water}\n"                 /* 3 */
                                "    - {shape: box, name: air}\n"                   /* 4 */
                                "    - {shape: polygon}\n"                          /* 5 */
                                "  walls:\n"                                        /* 6 */
                                "    - {shape: tank, name: left}\n"                 /* 7 */
                                "    - {shape: box, name: left}\n"                  /* 8 */
                                "plugins:\n"                                        /* 9 */
                                "  tait: {speed_of_sound: 20}\n"                    /* 10 */
                                "  two_phase: {air_density: 1.2}\n"                 /* 11 */
                                "  empty:\n"                                        /* 12 */
                                "edits:\n"                                          /* 13 */
                                "  remove: [plugins.two_phase, geometry.fluid.air,\n" /* 14 */
                                "           geometry.fluid.2, geometry.fluid.air.shape,\n" /* 15 */
                                "           plugins.two_phase]\n"                   /* 16 */
                                "  set:\n"                                          /* 17 */
                                "    plugins.tait.speed_of_sound: 28\n"             /* 18 */
                                "    plugins.empty.a.b: [1, 2]\n"                   /* 19 */
                                "    geometry.fluid.water: {shape: box, name: w2}\n" /* 20 */
                                "    geometry.walls.1.min: [0, 0]\n";               /* 21 */

START_TEST(path_edits_by_name_and_index)
{
    sluice_node *root = parse_ok(named_text);
    sluice_node *edits = sluice_node_get(root, "edits");
    sluice_diag *diag = sluice_diag_create();
    /* every remove path addresses the tree as it was: geometry.fluid.2 is the
     * polygon even though 'air' (item 1) goes too; a path inside a removed
     * node and a repeated path are harmless */
    ck_assert_int_eq(sluice_yaml_remove(root, sluice_node_get(edits, "remove"), "edits", diag), 0);
    const sluice_node *set = sluice_node_get(edits, "set");
    for (size_t i = 0; i < set->count; i++)
        ck_assert_int_eq(sluice_yaml_set(root, set->keys[i]->value,
                                         sluice_node_clone(set->items[i]), set->keys[i], "edits",
                                         diag),
                         0);
    ck_assert_uint_eq(sluice_diag_count(diag), 0);
    char *text = sluice_yaml_emit(root);
    ck_assert_str_eq(text, "geometry:\n"
                           "  fluid:\n"
                           "    - shape: box\n"
                           "      name: w2\n"
                           "  walls:\n"
                           "    - shape: tank\n"
                           "      name: left\n"
                           "    - shape: box\n"
                           "      name: left\n"
                           "      min: [0, 0]\n"
                           "plugins:\n"
                           "  tait:\n"
                           "    speed_of_sound: 28\n"
                           "  empty:\n"
                           "    a:\n"
                           "      b: [1, 2]\n"
                           "edits:\n"
                           "  remove: [plugins.two_phase, geometry.fluid.air, geometry.fluid.2, "
                           "geometry.fluid.air.shape, plugins.two_phase]\n"
                           "  set:\n"
                           "    plugins.tait.speed_of_sound: 28\n"
                           "    plugins.empty.a.b: [1, 2]\n"
                           "    geometry.fluid.water:\n"
                           "      shape: box\n"
                           "      name: w2\n"
                           "    geometry.walls.1.min: [0, 0]\n");
    free(text);
    /* a value keeps its own position; keys made on the way are at the entry */
    sluice_node *plugins = sluice_node_get(root, "plugins");
    expect_position(sluice_node_get(sluice_node_get(plugins, "tait"), "speed_of_sound"), 18, 34);
    sluice_node *empty = sluice_node_get(plugins, "empty");
    expect_position(empty, 12, 9); /* `empty:` became a mapping where it was */
    expect_position(sluice_node_get_key(empty, "a"), 19, 5);
    expect_position(sluice_node_get(empty, "a"), 19, 5);
    expect_position(sluice_node_get_key(sluice_node_get(empty, "a"), "b"), 19, 5);
    expect_position(sluice_node_get(sluice_node_get(empty, "a"), "b"), 19, 24);
    sluice_diag_destroy(diag);
    sluice_node_free(root);
}
END_TEST

/* Removes the paths of a one-line YAML list (parsed as file "v.yaml") from
 * named_text; expects exactly the messages given (NULL-terminated) and the
 * tree unchanged. */
static void expect_remove_errors(const char *list, const char *const *expected)
{
    sluice_node *root = parse_ok(named_text);
    char *before = sluice_yaml_emit(root);
    sluice_diag *diag = sluice_diag_create();
    sluice_node *paths = sluice_yaml_parse_string(list, strlen(list), "v.yaml", diag);
    ck_assert_ptr_nonnull(paths);
    size_t count = 0;
    while (expected[count])
        count++;
    ck_assert_int_eq(sluice_yaml_remove(root, paths, "variant 'v'", diag), (int)count);
    ck_assert_uint_eq(sluice_diag_count(diag), count);
    for (size_t i = 0; i < count; i++)
        ck_assert_str_eq(sluice_diag_message(diag, i), expected[i]);
    char *after = sluice_yaml_emit(root);
    ck_assert_str_eq(after, before); /* nothing removed when one path is wrong */
    free(before);
    free(after);
    sluice_node_free(paths);
    sluice_diag_destroy(diag);
    sluice_node_free(root);
}

START_TEST(path_edit_errors)
{
    static const char *const missing[] = {
        "v.yaml:1:21: error: variant 'v': cannot remove 'plugins.tiat': plugins has no key "
        "'tiat'; did you mean 'tait'?",
        "v.yaml:1:35: error: variant 'v': cannot remove 'physics': the top level has no key "
        "'physics'",
        NULL};
    expect_remove_errors("[plugins.two_phase, plugins.tiat, physics]", missing);
    static const char *const lists[] = {
        "v.yaml:1:2: error: variant 'v': cannot remove 'geometry.fluid.3': index 3 is out of "
        "range, geometry.fluid has 3 items",
        "v.yaml:1:20: error: variant 'v': cannot remove 'geometry.fluid.oil': geometry.fluid has "
        "no item named 'oil' (names: 'water', 'air'; or an index below 3)",
        "v.yaml:1:40: error: variant 'v': cannot remove 'geometry.walls.left': items 0 and 1 of "
        "geometry.walls are both named 'left'; address one by its index",
        NULL};
    expect_remove_errors("[geometry.fluid.3, geometry.fluid.oil, geometry.walls.left]", lists);
    static const char *const scalars[] = {
        "v.yaml:1:2: error: variant 'v': cannot remove 'plugins.tait.speed_of_sound.x': "
        "plugins.tait.speed_of_sound is a scalar, not a mapping or a list",
        "v.yaml:1:33: error: variant 'v': cannot remove 'plugins.empty.x': plugins.empty is "
        "empty, not a mapping or a list",
        "v.yaml:1:50: error: variant 'v': cannot remove 'plugins..tait': the path has an empty "
        "key",
        "v.yaml:1:65: error: variant 'v': each entry of 'remove' must be a dotted path such as "
        "plugins.two_phase",
        NULL};
    expect_remove_errors(
        "[plugins.tait.speed_of_sound.x, plugins.empty.x, plugins..tait, {a: 1}]", scalars);

    /* settings: a list item must exist; nothing is changed by a failure */
    sluice_node *root = parse_ok(named_text);
    char *before = sluice_yaml_emit(root);
    sluice_diag *diag = sluice_diag_create();
    sluice_node *at = sluice_node_new_scalar("x", 1, "v.yaml", 7, 9);
    static const char *const paths[] = {"geometry.fluid.oil.shape", "geometry.walls.5",
                                        "plugins.tait.speed_of_sound.x", "geometry.fluid.air."};
    static const char *const messages[] = {
        "v.yaml:7:9: error: variant 'v': cannot set 'geometry.fluid.oil.shape': geometry.fluid "
        "has no item named 'oil' (names: 'water', 'air'; or an index below 3)",
        "v.yaml:7:9: error: variant 'v': cannot set 'geometry.walls.5': index 5 is out of range, "
        "geometry.walls has 2 items",
        "v.yaml:7:9: error: variant 'v': cannot set 'plugins.tait.speed_of_sound.x': "
        "plugins.tait.speed_of_sound is a scalar, not a mapping or a list",
        "v.yaml:7:9: error: variant 'v': cannot set 'geometry.fluid.air.': the path has an empty "
        "key"};
    for (size_t i = 0; i < 4; i++) {
        sluice_node *value = sluice_node_new_scalar("1", 1, "v.yaml", 7, 12);
        ck_assert_int_eq(sluice_yaml_set(root, paths[i], value, at, "variant 'v'", diag), -1);
        ck_assert_uint_eq(sluice_diag_count(diag), i + 1);
        ck_assert_str_eq(sluice_diag_message(diag, i), messages[i]);
    }
    char *after = sluice_yaml_emit(root);
    ck_assert_str_eq(after, before);
    free(before);
    free(after);
    sluice_node_free(at);
    sluice_diag_destroy(diag);
    sluice_node_free(root);
}
END_TEST

START_TEST(override_addresses_items_by_name)
{
    sluice_node *root = parse_ok(named_text);
    sluice_diag *diag = sluice_diag_create();
    ck_assert_int_eq(sluice_yaml_override(root, "geometry.fluid.air.shape=polygon", "--set #1",
                                          diag),
                     0);
    ck_assert_uint_eq(sluice_diag_count(diag), 0);
    sluice_node *fluid = sluice_node_get(sluice_node_get(root, "geometry"), "fluid");
    sluice_node *shape = sluice_node_get(fluid->items[1], "shape");
    ck_assert_str_eq(shape->value, "polygon");
    ck_assert_str_eq(shape->file, "--set #1");
    expect_position(shape, 1, 26);
    ck_assert_str_eq(sluice_node_get(fluid->items[0], "shape")->value, "box");
    /* the same names, the same messages as a variant's paths */
    ck_assert_int_eq(sluice_yaml_override(root, "geometry.walls.left.min=0", "--set #2", diag),
                     -1);
    ck_assert_int_eq(sluice_yaml_override(root, "geometry.fluid.oil.min=0", "--set #3", diag), -1);
    ck_assert_uint_eq(sluice_diag_count(diag), 2);
    ck_assert_str_eq(sluice_diag_message(diag, 0),
                     "--set #2:1:16: error: cannot set 'geometry.walls.left.min': items 0 and 1 "
                     "of geometry.walls are both named 'left'; address one by its index");
    ck_assert_str_eq(sluice_diag_message(diag, 1),
                     "--set #3:1:16: error: cannot set 'geometry.fluid.oil.min': geometry.fluid "
                     "has no item named 'oil' (names: 'water', 'air'; or an index below 3)");
    sluice_diag_destroy(diag);
    sluice_node_free(root);
}
END_TEST

/* ------------------------------------------------------------- variants -- */

/* A scene with variants (only the core's sections are validated here: the
 * plugins are not loaded). Line numbers matter. */
#define VARIANT_HEAD                                                                   \
    "dimensions: 2\n"                                                    /* 1 */      \
    "particles: {spacing: 0.05}\n"                                       /* 2 */      \
    "time: {end: 1}\n"                                                   /* 3 */      \
    "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"                     /* 4 */      \
    "geometry:\n"                                                        /* 5 */      \
    "  fluid:\n"                                                         /* 6 */      \
    "    - {shape: box, min: [0, 0], max: [0.5, 0.5], name: water}\n"    /* 7 */      \
    "    - {shape: box, min: [0.5, 0.6], max: [0.9, 0.9], name: air}\n"  /* 8 */      \
    "  walls:\n"                                                         /* 9 */      \
    "    - {shape: tank, min: [0, 0], max: [1, 1]}\n"                    /* 10 */     \
    "    - {shape: box, min: [0.6, 0], max: [0.7, 0.2], name: sill}\n"   /* 11 */     \
    "plugins:\n"                                                         /* 12 */     \
    "  tait: {speed_of_sound: 20}\n"                                     /* 13 */     \
    "  two_phase: {air_density: 1.2}\n"                                  /* 14 */     \
    "  gravity: {}\n"                                                    /* 15 */
#define VARIANT_TAIL "initial: {density: rest}\n"

static const char *variant_scene = VARIANT_HEAD
    "variants:\n"                                                        /* 16 */
    "  single_phase:\n"                                                  /* 17 */
    "    description: water only, no air\n"                              /* 18 */
    "    remove: [plugins.two_phase, geometry.fluid.air]\n"              /* 19 */
    "  no_sill:\n"                                                       /* 20 */
    "    remove: [geometry.walls.1]\n"                                   /* 21 */
    "    set:\n"                                                         /* 22 */
    "      plugins.tait: {speed_of_sound: 28}\n"                         /* 23 */
    "      plugins.xsph.epsilon: 0.5\n"                                  /* 24 */
    "      geometry.fluid.water.max: [0.5, 0.4]\n"                       /* 25 */
    "      geometry.walls.0.name: tank\n"                                /* 26 */
    "  unchanged:\n"                                                     /* 27 */
    VARIANT_TAIL;                                                        /* 28 */

/* Writes text as scene.yaml in a scratch directory; returns its path. */
static char *write_scene(const char *tag, const char *text)
{
    char *dir = test_scratch(tag);
    ck_assert_ptr_nonnull(dir);
    char *path = test_write_file(dir, "scene.yaml", text);
    ck_assert_ptr_nonnull(path);
    free(dir);
    return path;
}

/* Deletes a scene written by write_scene, and its directory. */
static void remove_scene(char *path)
{
    unlink(path);
    char *slash = strrchr(path, '/');
    if (slash) {
        *slash = '\0';
        rmdir(path);
    }
    free(path);
}

/* Loads text with a variant and overrides; the load must succeed. */
static void load_scene(sluice_scene *scene, const char *text, const char *variant,
                       const char *const *sets, size_t set_count)
{
    char *path = write_scene("variant", text);
    sluice_diag *diag = sluice_diag_create();
    int errors = sluice_scene_load_variant(scene, path, variant, sets, set_count, diag);
    for (size_t i = 0; i < sluice_diag_count(diag); i++)
        fprintf(stderr, "%s\n", sluice_diag_message(diag, i));
    ck_assert_int_eq(errors, 0);
    ck_assert_uint_eq(sluice_diag_error_count(diag), 0);
    sluice_diag_destroy(diag);
    remove_scene(path);
}

/* The resolved tree of text loaded with a variant equals that of `expected`
 * (the same scene edited by hand) loaded as it is. */
static void expect_variant_tree(const char *variant, const char *expected)
{
    sluice_scene a, b;
    load_scene(&a, variant_scene, variant, NULL, 0);
    load_scene(&b, expected, NULL, NULL, 0);
    char *ta = sluice_yaml_emit(a.root), *tb = sluice_yaml_emit(b.root);
    ck_assert_msg(strcmp(ta, tb) == 0, "variant %s gives:\n%s\nexpected:\n%s",
                  variant ? variant : "(none)", ta, tb);
    free(ta);
    free(tb);
    sluice_scene_free(&a);
    sluice_scene_free(&b);
}

START_TEST(variants_change_exactly_the_named_keys)
{
    /* without --variant: the base scene, `variants` taken out */
    expect_variant_tree(NULL, VARIANT_HEAD VARIANT_TAIL);
    expect_variant_tree("single_phase",
                        "dimensions: 2\n"
                        "particles: {spacing: 0.05}\n"
                        "time: {end: 1}\n"
                        "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
                        "geometry:\n"
                        "  fluid:\n"
                        "    - {shape: box, min: [0, 0], max: [0.5, 0.5], name: water}\n"
                        "  walls:\n"
                        "    - {shape: tank, min: [0, 0], max: [1, 1]}\n"
                        "    - {shape: box, min: [0.6, 0], max: [0.7, 0.2], name: sill}\n"
                        "plugins:\n"
                        "  tait: {speed_of_sound: 20}\n"
                        "  gravity: {}\n"
                        "variant: single_phase\n" VARIANT_TAIL);
    expect_variant_tree("no_sill",
                        "dimensions: 2\n"
                        "particles: {spacing: 0.05}\n"
                        "time: {end: 1}\n"
                        "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
                        "geometry:\n"
                        "  fluid:\n"
                        "    - {shape: box, min: [0, 0], max: [0.5, 0.4], name: water}\n"
                        "    - {shape: box, min: [0.5, 0.6], max: [0.9, 0.9], name: air}\n"
                        "  walls:\n"
                        "    - {shape: tank, min: [0, 0], max: [1, 1], name: tank}\n"
                        "plugins:\n"
                        "  tait: {speed_of_sound: 28}\n"
                        "  two_phase: {air_density: 1.2}\n"
                        "  gravity: {}\n"
                        "  xsph: {epsilon: 0.5}\n"
                        "variant: no_sill\n" VARIANT_TAIL);
    expect_variant_tree("unchanged", VARIANT_HEAD "variant: unchanged\n" VARIANT_TAIL);

    /* what the loaded scene records */
    sluice_scene scene;
    load_scene(&scene, variant_scene, "no_sill", NULL, 0);
    ck_assert_str_eq(scene.variant, "no_sill");
    ck_assert_uint_eq(scene.variant_count, 3);
    ck_assert_str_eq(scene.variants[0].name, "single_phase");
    ck_assert_str_eq(scene.variants[0].description, "water only, no air");
    ck_assert_str_eq(scene.variants[1].name, "no_sill");
    ck_assert_str_eq(scene.variants[1].description, "");
    ck_assert_str_eq(scene.variants[2].name, "unchanged");
    ck_assert_uint_eq(scene.fluid_count, 2);
    ck_assert_uint_eq(scene.wall_count, 1);
    ck_assert_str_eq(scene.fluids[0].name, "water");
    ck_assert_str_eq(scene.fluids[1].name, "air");
    ck_assert_str_eq(scene.walls[0].name, "tank");
    ck_assert_double_eq(scene.fluids[0].region.max[1], (sluice_real)0.4);
    /* values set by the variant keep their place in the file for messages */
    sluice_node *plugins = sluice_node_get(scene.root, "plugins");
    expect_position(sluice_node_get_key(plugins, "xsph"), 24, 7);
    expect_position(sluice_node_get(sluice_node_get(plugins, "xsph"), "epsilon"), 24, 29);
    expect_position(sluice_node_get(plugins, "tait"), 23, 21);
    expect_position(sluice_node_get_key(scene.root, "variant"), 16, 1);
    sluice_scene_free(&scene);

    load_scene(&scene, variant_scene, NULL, NULL, 0);
    ck_assert_ptr_null(scene.variant);
    ck_assert_uint_eq(scene.variant_count, 3);
    ck_assert_uint_eq(scene.fluid_count, 2);
    ck_assert_uint_eq(scene.wall_count, 2);
    ck_assert_ptr_null(sluice_node_get(scene.root, "variant"));
    ck_assert_ptr_null(sluice_node_get(scene.root, "variants"));
    sluice_scene_free(&scene);
}
END_TEST

START_TEST(variant_then_overrides)
{
    /* --set applies after the variant: it can change what the variant set or
     * created, and the variant sees the file as written */
    static const char *const sets[] = {"geometry.fluid.water.max=[0.5, 0.45]",
                                       "plugins.xsph.epsilon=0.25",
                                       "geometry.walls.tank.scheme=dbc"};
    sluice_scene scene;
    load_scene(&scene, variant_scene, "no_sill", sets, 3);
    ck_assert_double_eq(scene.fluids[0].region.max[1], (sluice_real)0.45);
    const sluice_node *epsilon = sluice_node_get(
        sluice_node_get(sluice_node_get(scene.root, "plugins"), "xsph"), "epsilon");
    ck_assert_str_eq(epsilon->value, "0.25");
    ck_assert_str_eq(epsilon->file, "--set #2");
    ck_assert_str_eq(scene.walls[0].scheme, "dbc"); /* the name the variant gave */
    sluice_scene_free(&scene);
}
END_TEST

/* Loads text with a variant and overrides; expects exactly one error,
 * "<path or origin>:line:column: error: message". `origin` NULL: the scene. */
static void expect_variant_error(const char *text, const char *variant, const char *set,
                                 const char *origin, int line, int column, const char *message)
{
    char *path = write_scene("variant-error", text);
    sluice_diag *diag = sluice_diag_create();
    sluice_scene scene;
    int errors = sluice_scene_load_variant(&scene, path, variant, &set, set ? 1 : 0, diag);
    for (size_t i = 0; i < sluice_diag_count(diag); i++)
        fprintf(stderr, "%s\n", sluice_diag_message(diag, i));
    ck_assert_int_eq(errors, 1);
    ck_assert_uint_eq(sluice_diag_count(diag), 1);
    char *expected = NULL;
    ck_assert_int_ge(asprintf(&expected, "%s:%d:%d: error: %s", origin ? origin : path, line,
                              column, message),
                     0);
    ck_assert_str_eq(sluice_diag_message(diag, 0), expected);
    free(expected);
    sluice_scene_free(&scene);
    sluice_diag_destroy(diag);
    remove_scene(path);
}

START_TEST(variant_errors)
{
    expect_variant_error(variant_scene, "singel_phase", NULL, NULL, 16, 1,
                         "unknown variant 'singel_phase'; did you mean 'single_phase'? (the "
                         "scene defines: single_phase, no_sill, unchanged)");
    expect_variant_error(variant_scene, "coarse", NULL, NULL, 16, 1,
                         "unknown variant 'coarse' (the scene defines: single_phase, no_sill, "
                         "unchanged)");
    expect_variant_error(VARIANT_HEAD VARIANT_TAIL, "coarse", NULL, NULL, 1, 1,
                         "--variant 'coarse': the scene defines no variants (a top-level "
                         "'variants' mapping)");
    expect_variant_error(VARIANT_HEAD "variants: {}\n", "coarse", NULL, NULL, 16, 1,
                         "--variant 'coarse': the scene defines no variants (a top-level "
                         "'variants' mapping)");
    /* a path to remove that does not exist: at its entry */
    expect_variant_error(VARIANT_HEAD "variants:\n"
                                      "  v:\n"
                                      "    remove:\n"
                                      "      - plugins.two_phase\n"
                                      "      - geometry.fluid.oil\n",
                         "v", NULL, NULL, 20, 9,
                         "variant 'v': cannot remove 'geometry.fluid.oil': geometry.fluid has no "
                         "item named 'oil' (names: 'water', 'air'; or an index below 2)");
    expect_variant_error(VARIANT_HEAD "variants:\n"
                                      "  v: {remove: [plugins.tiat]}\n",
                         "v", NULL, NULL, 17, 16,
                         "variant 'v': cannot remove 'plugins.tiat': plugins has no key 'tiat'; "
                         "did you mean 'tait'?");
    expect_variant_error(VARIANT_HEAD "variants:\n"
                                      "  v:\n"
                                      "    set: {geometry.walls.2.name: x}\n",
                         "v", NULL, NULL, 18, 11,
                         "variant 'v': cannot set 'geometry.walls.2.name': index 2 is out of "
                         "range, geometry.walls has 2 items");

    /* malformed entries: refused on every load, with or without --variant */
    const char *variants[] = {NULL, "v"};
    for (int k = 0; k < 2; k++) {
        const char *v = variants[k];
        expect_variant_error(VARIANT_HEAD "variants:\n"
                                          "  v:\n"
                                          "    remvoe: [plugins.two_phase]\n",
                             v, NULL, NULL, 18, 5,
                             "unknown key 'remvoe' in variants.v; did you mean 'remove'?");
        expect_variant_error(VARIANT_HEAD "variants:\n"
                                          "  v: {drop: [plugins.two_phase]}\n",
                             v, NULL, NULL, 17, 7,
                             "unknown key 'drop' in variants.v (valid keys: description, remove, "
                             "swap, set)");
        expect_variant_error(VARIANT_HEAD "variants:\n"
                                          "  v: {description: [a, b]}\n",
                             v, NULL, NULL, 17, 20, "variants.v.description must be a string");
        expect_variant_error(VARIANT_HEAD "variants:\n"
                                          "  v: {remove: plugins.two_phase}\n",
                             v, NULL, NULL, 17, 15,
                             "variants.v.remove must be a list of dotted paths, e.g. "
                             "[plugins.two_phase, geometry.fluid.air]");
        expect_variant_error(VARIANT_HEAD "variants:\n"
                                          "  v: {remove: [{plugins: two_phase}]}\n",
                             v, NULL, NULL, 17, 16,
                             "each entry of variants.v.remove must be a dotted path such as "
                             "plugins.two_phase");
        expect_variant_error(VARIANT_HEAD "variants:\n"
                                          "  v: {set: [plugins.tait.speed_of_sound, 28]}\n",
                             v, NULL, NULL, 17, 12,
                             "variants.v.set must be a mapping from dotted paths to values, e.g. "
                             "{plugins.tait.speed_of_sound: 28}");
        expect_variant_error(VARIANT_HEAD "variants:\n"
                                          "  v: [plugins.two_phase]\n",
                             v, NULL, NULL, 17, 6,
                             "variants.v must be a mapping with the optional keys description, "
                             "remove, swap and set");
        expect_variant_error(VARIANT_HEAD "variants: [v]\n", v, NULL, NULL, 16, 11,
                             "'variants' must be a mapping from variant names to their changes "
                             "(description, remove, swap, set)");
        /* a record of a resolved scene beside variants */
        expect_variant_error(VARIANT_HEAD "variants: {v: {}}\nvariant: v\n", v, NULL, NULL, 17, 1,
                             "'variant' records the variant a resolved scene was made from and "
                             "cannot stand beside 'variants': choose a variant with --variant "
                             "NAME");
    }
    /* variants cannot come from an override */
    expect_variant_error(variant_scene, NULL, "variants.v.remove=[plugins.tait]", "--set #1", 1,
                         1,
                         "'variants' can only be written in the scene file: it is taken out "
                         "before a variant and the --remove, --swap and --set edits are "
                         "applied");
    /* a resolved scene's record is a string */
    expect_variant_error(VARIANT_HEAD "variant: [a]\n", NULL, NULL, NULL, 16, 10,
                         "variant must be a string (it records the variant a resolved scene was "
                         "made from)");
}
END_TEST

/* ---------------------------------------------------------------- swaps -- */

#define SWAP_HEAD                                                                      \
    "dimensions: 2\n"                                                    /* 1 */      \
    "particles: {spacing: 0.05}\n"                                       /* 2 */      \
    "time: {end: 1}\n"                                                   /* 3 */      \
    "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"                     /* 4 */      \
    "geometry:\n"                                                        /* 5 */      \
    "  fluid:\n"                                                         /* 6 */      \
    "    - {shape: box, min: [0, 0], max: [0.5, 0.5]}\n"                 /* 7 */      \
    "  walls:\n"                                                         /* 8 */      \
    "    - {shape: tank, min: [0, 0], max: [1, 1], scheme: dbc}\n"       /* 9 */      \
    "    - {shape: box, min: [0.6, 0], max: [0.7, 0.2], name: sill, scheme: plate}\n" \
    "plugins:\n"                                                         /* 11 */     \
    "  tait: {speed_of_sound: 20}\n"                                     /* 12 */     \
    "  dbc: {}\n"                                                        /* 13 */     \
    "  plate: {plugin: penalty_contact, stiffness: 2}\n"                 /* 14 */     \
    "  gravity: {}\n"                                                    /* 15 */

/* The scene with `replacement` in the place of `plugins` entry `entry`
 * (line 13 or 14) and the walls' schemes given. */
static char *swapped_scene(const char *dbc_line, const char *plate_line, const char *tank_scheme,
                           const char *sill_scheme, const char *gravity_line)
{
    char *text = NULL;
    ck_assert_int_ge(
        asprintf(&text,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.05}\n"
                 "time: {end: 1}\n"
                 "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [0.5, 0.5]}\n"
                 "  walls:\n"
                 "    - {shape: tank, min: [0, 0], max: [1, 1], scheme: %s}\n"
                 "    - {shape: box, min: [0.6, 0], max: [0.7, 0.2], name: sill, scheme: %s}\n"
                 "plugins:\n"
                 "  tait: {speed_of_sound: 20}\n"
                 "  %s\n"
                 "  %s\n"
                 "%s",
                 tank_scheme, sill_scheme, dbc_line, plate_line, gravity_line),
        0);
    return text;
}

static void expect_same_tree(sluice_scene *a, const char *expected)
{
    sluice_scene b;
    load_scene(&b, expected, NULL, NULL, 0);
    char *ta = sluice_yaml_emit(a->root), *tb = sluice_yaml_emit(b.root);
    ck_assert_msg(strcmp(ta, tb) == 0, "the edited scene is:\n%s\nexpected:\n%s", ta, tb);
    free(ta);
    free(tb);
    sluice_scene_free(&b);
}

START_TEST(swaps_replace_plugins_and_walls_follow)
{
    /* a variant's swap: the instance 'plate' becomes mdbc with mdbc's defaults in its
     * place; the sill it handled follows; then the variant's settings apply to it */
    sluice_scene scene;
    load_scene(&scene,
               SWAP_HEAD "variants:\n"
                         "  v: {swap: {plate: mdbc}, set: {plugins.mdbc.reference: wall}}\n",
               "v", NULL, 0);
    char *expected = swapped_scene("dbc: {}", "mdbc: {reference: wall}", "dbc", "mdbc",
                                   "  gravity: {}\n");
    char *with_record = NULL;
    ck_assert_int_ge(asprintf(&with_record, "%svariant: v\n", expected), 0);
    expect_same_tree(&scene, with_record);
    ck_assert_str_eq(scene.walls[1].scheme, "mdbc");
    ck_assert_str_eq(scene.walls[0].scheme, "dbc");
    sluice_scene_free(&scene);
    free(expected);
    free(with_record);

    /* the command line's: removals first, then swaps in order, then the settings */
    char *path = write_scene("swap", SWAP_HEAD);
    static const char *const removals[] = {"plugins.gravity"};
    static const char *const swaps[] = {"dbc=ghost_particles", "plate=repulsive_force"};
    static const char *const sets[] = {"plugins.ghost_particles.slip=free_slip"};
    sluice_scene_edits edits = {removals, 1, swaps, 2, sets, 1};
    sluice_diag *diag = sluice_diag_create();
    ck_assert_int_eq(sluice_scene_load_edited(&scene, path, NULL, &edits, diag), 0);
    sluice_diag_destroy(diag);
    remove_scene(path);
    expected = swapped_scene("ghost_particles: {slip: free_slip}", "repulsive_force: {}",
                             "ghost_particles", "repulsive_force", "");
    expect_same_tree(&scene, expected);
    /* the new entry sits where the swap was written */
    const sluice_node *key = sluice_node_get_key(sluice_node_get(scene.root, "plugins"),
                                                 "repulsive_force");
    ck_assert_str_eq(key->file, "--swap #2");
    sluice_scene_free(&scene);
    free(expected);

    /* into a plugin the scene loads already: the instance goes, the sill joins dbc
     * (with dbc's parameters) */
    path = write_scene("swap-merge", SWAP_HEAD);
    static const char *const merge[] = {"plate=dbc"};
    edits = (sluice_scene_edits){.swaps = merge, .swap_count = 1};
    diag = sluice_diag_create();
    ck_assert_int_eq(sluice_scene_load_edited(&scene, path, NULL, &edits, diag), 0);
    sluice_diag_destroy(diag);
    remove_scene(path);
    ck_assert_ptr_null(sluice_node_get(sluice_node_get(scene.root, "plugins"), "plate"));
    ck_assert_uint_eq(sluice_node_get(scene.root, "plugins")->count, 3);
    ck_assert_str_eq(scene.walls[1].scheme, "dbc");
    sluice_scene_free(&scene);
}
END_TEST

/* Loads SWAP_HEAD + tail with the command-line swap `swap` (NULL: none) and
 * variant v when the tail has one; expects exactly one error. */
static void expect_swap_error(const char *tail, const char *swap, const char *origin, int line,
                              int column, const char *message)
{
    char *text = NULL;
    ck_assert_int_ge(asprintf(&text, "%s%s", SWAP_HEAD, tail), 0);
    char *path = write_scene("swap-error", text);
    sluice_scene_edits edits = {.swaps = &swap, .swap_count = swap ? 1 : 0};
    sluice_diag *diag = sluice_diag_create();
    sluice_scene scene;
    int errors = sluice_scene_load_edited(&scene, path, *tail ? "v" : NULL, &edits, diag);
    for (size_t i = 0; i < sluice_diag_count(diag); i++)
        fprintf(stderr, "%s\n", sluice_diag_message(diag, i));
    ck_assert_int_eq(errors, 1);
    ck_assert_uint_eq(sluice_diag_count(diag), 1);
    char *expected = NULL;
    ck_assert_int_ge(asprintf(&expected, "%s:%d:%d: error: %s", origin ? origin : path, line,
                              column, message),
                     0);
    ck_assert_str_eq(sluice_diag_message(diag, 0), expected);
    free(expected);
    free(text);
    sluice_scene_free(&scene);
    sluice_diag_destroy(diag);
    remove_scene(path);
}

START_TEST(swap_errors)
{
    expect_swap_error("", "dcb=mdbc", "--swap #1", 1, 1,
                      "--swap: cannot swap 'dcb': the scene loads no plugin of that name; did "
                      "you mean 'dbc'?");
    expect_swap_error("", "dbc", "--swap #1", 1, 1,
                      "--swap 'dbc': write OLD=NEW, a plugin the scene loads and the plugin "
                      "that replaces it (e.g. --swap dbc=mdbc)");
    expect_swap_error("", "dbc=", "--swap #1", 1, 1,
                      "--swap 'dbc=': write OLD=NEW, a plugin the scene loads and the plugin "
                      "that replaces it (e.g. --swap dbc=mdbc)");
    expect_swap_error("", "dbc=m dbc", "--swap #1", 1, 1,
                      "--swap: 'm dbc' is not a plugin name (letters, digits, '_' and '-'); "
                      "write OLD=NEW, e.g. dbc=mdbc");
    /* in a variant: at the value */
    expect_swap_error("variants:\n  v: {swap: {gravty: none}}\n", NULL, NULL, 17, 22,
                      "variant 'v': cannot swap 'gravty': the scene loads no plugin of that "
                      "name; did you mean 'gravity'?");
    expect_swap_error("variants:\n  v: {swap: [dbc, mdbc]}\n", NULL, NULL, 17, 13,
                      "variants.v.swap must be a mapping from loaded plugins to the plugins "
                      "that replace them, e.g. {dbc: mdbc}");
}
END_TEST

/* --------------------------------------------------------- suggestions -- */

START_TEST(edit_distance)
{
    ck_assert_uint_eq(sluice_edit_distance("kitten", "sitting"), 3);
    ck_assert_uint_eq(sluice_edit_distance("sitting", "kitten"), 3);
    ck_assert_uint_eq(sluice_edit_distance("flaw", "lawn"), 2);
    ck_assert_uint_eq(sluice_edit_distance("", "abc"), 3);
    ck_assert_uint_eq(sluice_edit_distance("abc", ""), 3);
    ck_assert_uint_eq(sluice_edit_distance("same", "same"), 0);
    ck_assert_uint_eq(sluice_edit_distance("Tait", "tait"), 1);
    /* long words (heap row) */
    char a[201], b[201];
    memset(a, 'a', 200);
    memset(b, 'a', 200);
    a[200] = b[200] = '\0';
    b[10] = 'b';
    b[150] = 'c';
    ck_assert_uint_eq(sluice_edit_distance(a, b), 2);
    ck_assert_uint_eq(sluice_edit_distance(a, "aaa"), 197);
}
END_TEST

START_TEST(closest_candidate)
{
    static const char *const names[] = {"speed_of_sound", "gamma", "rest_density", "end",
                                        "and"};
    ck_assert_str_eq(sluice_closest("speed_of_sond", names, 5), "speed_of_sound");
    ck_assert_str_eq(sluice_closest("gama", names, 5), "gamma");
    ck_assert_str_eq(sluice_closest("edn", names, 5), "end");
    /* ties go to the first candidate */
    ck_assert_str_eq(sluice_closest("xnd", names, 5), "end");
    /* case-sensitive: "GAMMA" is 5 edits from "gamma" */
    ck_assert_ptr_null(sluice_closest("GAMMA", names, 5));
    ck_assert_ptr_null(sluice_closest("viscosity", names, 5));
    ck_assert_ptr_null(sluice_closest("gamma", names, 0));
    /* the limit is max(2, strlen / 3): 12 letters allow 4 edits, not 5 */
    static const char *const long_name[] = {"abcdefghijkl"};
    ck_assert_str_eq(sluice_closest("abcdefghWXYZ", long_name, 1), "abcdefghijkl");
    ck_assert_ptr_null(sluice_closest("abcdefgVWXYZ", long_name, 1));
}
END_TEST

/* Out of memory is a want of resources (sluice run and check exit 4), not
 * bad input (2): any error that says so marks the diagnostics, as does an
 * explicit mark (the memory estimate's refusal). */
START_TEST(out_of_memory_marks_resources)
{
    sluice_diag *diag = sluice_diag_create();
    ck_assert_ptr_nonnull(diag);
    sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, "s.yaml", 3, 5, "unknown key 'x'");
    sluice_diag_add(diag, SLUICE_SEVERITY_WARNING, "s.yaml", 4, 1, "out of memory (a warning)");
    ck_assert_int_eq(sluice_diag_resources(diag), 0);
    sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, "s.yaml", 5, 1, "out of memory reading %s", "y");
    ck_assert_int_eq(sluice_diag_resources(diag), 1);
    sluice_diag_destroy(diag);
    diag = sluice_diag_create();
    ck_assert_ptr_nonnull(diag);
    sluice_diag_mark_resources(diag);
    ck_assert_int_eq(sluice_diag_resources(diag), 1);
    sluice_diag_destroy(diag);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("yaml");
    TCase *load = tcase_create("load");
    tcase_add_test(load, positions_kinds_and_plain_flags);
    tcase_add_test(load, out_of_memory_marks_resources);
    tcase_add_test(load, explicit_string_tag_is_not_plain);
    tcase_add_test(load, syntax_errors_have_libyaml_position_and_text);
    tcase_add_test(load, duplicate_keys);
    tcase_add_test(load, non_scalar_keys);
    tcase_add_test(load, aliases_are_cloned);
    tcase_add_test(load, alias_expansion_is_bounded);
    tcase_add_test(load, nesting_depth_is_bounded);
    tcase_add_test(load, one_document_only);
    tcase_add_test(load, files);
    tcase_add_test(load, node_construction);
    suite_add_tcase(s, load);
    TCase *emit = tcase_create("emit");
    tcase_add_test(emit, emit_block_style);
    tcase_add_test(emit, emit_quotes_only_when_needed);
    tcase_add_test(emit, emit_round_trips);
    suite_add_tcase(s, emit);
    TCase *override = tcase_create("override");
    tcase_add_test(override, override_creates_and_replaces);
    tcase_add_test(override, override_errors);
    tcase_add_test(override, path_edits_by_name_and_index);
    tcase_add_test(override, path_edit_errors);
    tcase_add_test(override, override_addresses_items_by_name);
    suite_add_tcase(s, override);
    TCase *variants = tcase_create("variants");
    tcase_add_test(variants, variants_change_exactly_the_named_keys);
    tcase_add_test(variants, variant_then_overrides);
    tcase_add_test(variants, variant_errors);
    tcase_add_test(variants, swaps_replace_plugins_and_walls_follow);
    tcase_add_test(variants, swap_errors);
    suite_add_tcase(s, variants);
    TCase *suggest = tcase_create("suggest");
    tcase_add_test(suggest, edit_distance);
    tcase_add_test(suggest, closest_candidate);
    suite_add_tcase(s, suggest);

    SRunner *runner = srunner_create(s);
    srunner_run_all(runner, CK_NORMAL);
    int failed = srunner_ntests_failed(runner);
    srunner_free(runner);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
