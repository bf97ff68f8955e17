/* Binding parameter mappings to sluice_param_spec tables: values, defaults,
 * and every kind of error with its exact position and text. */
#include <check.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "schema.h"

/* ---------------------------------------------------------- the table -- */

typedef struct config {
    sluice_real speed_of_sound, gamma;
    int64_t steps;
    int verbose;
    const char *label;
    int kernel;
    sluice_real gravity[3];
    sluice_real pair[3];
    sluice_real_list levels;
    sluice_real_list outline;
    sluice_real surface;
} config;

#define OFF(member) offsetof(config, member)
#define SPEED_DOC "speed of sound c0 of the weakly compressible fluid"

static const sluice_param_spec specs[] = {
    {"speed_of_sound", SLUICE_PARAM_REAL, OFF(speed_of_sound), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m s^-1", SPEED_DOC, NULL, 0},
    {"gamma", SLUICE_PARAM_REAL, OFF(gamma), "7", 1, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1", "exponent of the Tait equation", NULL, 0},
    {"steps", SLUICE_PARAM_INT, OFF(steps), "10", 1, 0, SLUICE_PARAM_HAS_MIN, NULL,
     "steps between reports", NULL, 0},
    {"verbose", SLUICE_PARAM_BOOL, OFF(verbose), "false", 0, 0, 0, NULL, "talk more", NULL, 0},
    {"label", SLUICE_PARAM_STRING, OFF(label), "'water'", 0, 0, 0, NULL, "name in reports", NULL,
     0},
    {"kernel", SLUICE_PARAM_ENUM, OFF(kernel), "wendland_c2", 0, 0, 0, NULL, "kernel function",
     "wendland_c2|cubic_spline|gaussian", 0},
    {"gravity", SLUICE_PARAM_VECTOR, OFF(gravity), "[0, -9.81] | [0, 0, -9.81]", 0, 0, 0,
     "m s^-2", "gravitational acceleration", NULL, SLUICE_LENGTH_DIM},
    {"pair", SLUICE_PARAM_VECTOR, OFF(pair), "[1, 2]", 0, 5,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX | SLUICE_PARAM_MAX_EXCLUSIVE, "m", "two lengths",
     NULL, 2},
    {"levels", SLUICE_PARAM_REAL_LIST, OFF(levels), "[]", 0, 1,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "fill levels", NULL, 0},
    {"outline", SLUICE_PARAM_POINT_LIST, OFF(outline), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "m",
     "outline of the region", NULL, 0},
    {"surface", SLUICE_PARAM_REAL, OFF(surface), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "m",
     "free-surface level", NULL, 0},
};
#define SPEC_COUNT SLUICE_COUNT(specs)

/* ------------------------------------------------------------- helpers -- */

/* A scene parsed, with plugins.tait bound to `specs`. */
typedef struct bound {
    sluice_node *root;
    sluice_diag *diag;
    sluice_arena *arena;
    config cfg;
    int errors;
} bound;

static sluice_node *parse_ok(const char *text, sluice_diag *diag)
{
    sluice_node *root = sluice_yaml_parse_string(text, strlen(text), "scene.yaml", diag);
    ck_assert_msg(root != NULL, "cannot parse:\n%s\n%s", text,
                  sluice_diag_count(diag) ? sluice_diag_message(diag, 0) : "");
    return root;
}

/* Binds plugins.tait of `text` (the key "tait" is the owner). */
static bound bind_tait(const char *text, uint32_t dimensions, const sluice_param_spec *table,
                       uint32_t count)
{
    bound b;
    memset(&b, 0, sizeof b);
    b.diag = sluice_diag_create();
    b.arena = sluice_arena_create();
    ck_assert_ptr_nonnull(b.diag);
    ck_assert_ptr_nonnull(b.arena);
    b.root = parse_ok(text, b.diag);
    sluice_node *plugins = sluice_node_get(b.root, "plugins");
    ck_assert_ptr_nonnull(plugins);
    size_t i = 0;
    while (i < plugins->count && strcmp(plugins->keys[i]->value, "tait") != 0)
        i++;
    ck_assert_uint_lt(i, plugins->count);
    b.errors = sluice_schema_bind(table, count, &plugins->items[i], plugins->keys[i],
                                  "plugins.tait", dimensions, &b.cfg, b.arena, b.diag);
    ck_assert_int_eq((int)sluice_diag_error_count(b.diag), b.errors);
    return b;
}

static void release(bound *b)
{
    sluice_node_free(b->root);
    sluice_diag_destroy(b->diag);
    sluice_arena_destroy(b->arena);
}

static sluice_node *tait_section(const bound *b)
{
    return sluice_node_get(sluice_node_get(b->root, "plugins"), "tait");
}

/* plugins.tait holding `line` (line 3) and, unless `line` sets it,
 * speed_of_sound: 20 on line 4. Must give exactly one error, `expected`. */
static void expect_one_error(const char *line, uint32_t dimensions, const char *expected)
{
    char text[512];
    snprintf(text, sizeof text, "plugins:\n  tait:\n    %s\n%s", line,
             strncmp(line, "speed_of_sound", 14) == 0 ? "" : "    speed_of_sound: 20\n");
    bound b = bind_tait(text, dimensions, specs, SPEC_COUNT);
    ck_assert_msg(b.errors == 1, "%d errors for '%s'%s%s", b.errors, line,
                  b.errors ? ", first: " : "", b.errors ? sluice_diag_message(b.diag, 0) : "");
    ck_assert_str_eq(sluice_diag_message(b.diag, 0), expected);
    release(&b);
}

/* The same, for a value that must be accepted. */
static config expect_ok(const char *line, uint32_t dimensions)
{
    char text[512];
    snprintf(text, sizeof text, "plugins:\n  tait:\n    %s\n%s", line,
             strncmp(line, "speed_of_sound", 14) == 0 ? "" : "    speed_of_sound: 20\n");
    bound b = bind_tait(text, dimensions, specs, SPEC_COUNT);
    ck_assert_msg(b.errors == 0, "'%s': %s", line, b.errors ? sluice_diag_message(b.diag, 0) : "");
    config c = b.cfg;
    c.label = NULL; /* lives in the arena */
    c.levels.values = c.outline.values = NULL;
    release(&b);
    return c;
}

/* -------------------------------------------------------------- values -- */

START_TEST(every_type_is_converted)
{
    bound b = bind_tait("plugins:\n"
                        "  tait:\n"
                        "    speed_of_sound: 20\n"
                        "    gamma: 7.5\n"
                        "    steps: 1e3\n"
                        "    verbose: Yes\n"
                        "    label: \"salt water\"\n"
                        "    kernel: cubic_spline\n"
                        "    gravity: [0, -9.81]\n"
                        "    pair: [0, 4.5]\n"
                        "    levels: [0.25, 1]\n"
                        "    outline: [[0, 0], [1, 0], [0, 1.5]]\n"
                        "    surface: -0.5\n",
                        2, specs, SPEC_COUNT);
    ck_assert_int_eq(b.errors, 0);
    const config *c = &b.cfg;
    ck_assert(c->speed_of_sound == 20.0);
    ck_assert(c->gamma == 7.5);
    ck_assert_int_eq(c->steps, 1000);
    ck_assert_int_eq(c->verbose, 1);
    ck_assert_str_eq(c->label, "salt water");
    ck_assert_int_eq(c->kernel, 1);
    ck_assert(c->gravity[0] == 0 && c->gravity[1] == -9.81 && c->gravity[2] == 0);
    ck_assert(c->pair[0] == 0 && c->pair[1] == 4.5 && c->pair[2] == 0);
    ck_assert_uint_eq(c->levels.count, 2);
    ck_assert(c->levels.values[0] == 0.25 && c->levels.values[1] == 1.0);
    ck_assert_uint_eq(c->outline.count, 3);
    static const sluice_real points[9] = {0, 0, 0, 1, 0, 0, 0, 1.5, 0};
    for (int i = 0; i < 9; i++)
        ck_assert(c->outline.values[i] == points[i]);
    ck_assert(c->surface == -0.5);

    /* strings are copied into the arena */
    sluice_node *tait = tait_section(&b);
    ck_assert_ptr_ne(c->label, sluice_node_get(tait, "label")->value);
    /* every key and value is marked used; nothing was inserted */
    ck_assert_int_eq(tait->used, 1);
    ck_assert_uint_eq(tait->count, SPEC_COUNT);
    for (size_t i = 0; i < tait->count; i++) {
        ck_assert_int_eq(tait->keys[i]->used, 1);
        ck_assert_int_eq(tait->items[i]->used, 1);
    }
    ck_assert_int_eq(sluice_node_get(tait, "outline")->items[2]->items[1]->used, 1);
    release(&b);

    /* points in 3D */
    bound d = bind_tait("plugins:\n"
                        "  tait:\n"
                        "    speed_of_sound: 20\n"
                        "    outline: [[1, 2, 3], [4, 5, 6]]\n",
                        3, specs, SPEC_COUNT);
    ck_assert_int_eq(d.errors, 0);
    ck_assert_uint_eq(d.cfg.outline.count, 2);
    ck_assert(d.cfg.outline.values[2] == 3 && d.cfg.outline.values[5] == 6);
    ck_assert(d.cfg.gravity[2] == (sluice_real)-9.81);
    release(&d);

    ck_assert_int_eq(expect_ok("kernel: 'gaussian'", 2).kernel, 2);
    ck_assert_int_eq(expect_ok("verbose: off", 2).verbose, 0);
    ck_assert_int_eq(expect_ok("steps: 4", 2).steps, 4);
    ck_assert_int_eq(expect_ok("steps: 9223372036854775807", 2).steps, INT64_MAX);
}
END_TEST

/* ------------------------------------------------------------ defaults -- */

static const char *resolved_2d = "plugins:\n"
                                 "  tait:\n"
                                 "    speed_of_sound: 20\n"
                                 "    gamma: 7\n"
                                 "    steps: 10\n"
                                 "    verbose: false\n"
                                 "    label: \"water\"\n"
                                 "    kernel: wendland_c2\n"
                                 "    gravity: [0, -9.81]\n"
                                 "    pair: [1, 2]\n"
                                 "    levels: []\n";

START_TEST(defaults_are_inserted_and_round_trip)
{
    bound b = bind_tait("plugins:\n  tait:\n    speed_of_sound: 20\n", 2, specs, SPEC_COUNT);
    ck_assert_int_eq(b.errors, 0);
    ck_assert(b.cfg.gamma == 7);
    ck_assert_int_eq(b.cfg.steps, 10);
    ck_assert_int_eq(b.cfg.verbose, 0);
    ck_assert_str_eq(b.cfg.label, "water");
    ck_assert_int_eq(b.cfg.kernel, 0);
    ck_assert(b.cfg.gravity[1] == -9.81 && b.cfg.gravity[2] == 0);
    ck_assert(b.cfg.pair[0] == 1 && b.cfg.pair[1] == 2);
    ck_assert_uint_eq(b.cfg.levels.count, 0);
    /* optional parameters stay zero and absent */
    ck_assert_uint_eq(b.cfg.outline.count, 0);
    ck_assert_ptr_null(b.cfg.outline.values);
    ck_assert(b.cfg.surface == 0);
    sluice_node *tait = tait_section(&b);
    ck_assert_ptr_null(sluice_node_get(tait, "outline"));
    ck_assert_ptr_null(sluice_node_get(tait, "surface"));
    /* inserted defaults are program-made: file "default", no line */
    sluice_node *gamma = sluice_node_get(tait, "gamma");
    ck_assert_str_eq(gamma->file, "default");
    ck_assert_int_eq(gamma->line, 0);
    ck_assert_int_eq(gamma->used, 1);
    ck_assert_int_eq(sluice_node_get(tait, "gravity")->items[1]->line, 0);

    char *text = sluice_yaml_emit(b.root);
    ck_assert_str_eq(text, resolved_2d);
    /* the resolved scene binds to the same values and resolves to itself */
    bound again = bind_tait(text, 2, specs, SPEC_COUNT);
    ck_assert_int_eq(again.errors, 0);
    ck_assert(again.cfg.gamma == b.cfg.gamma && again.cfg.steps == b.cfg.steps);
    ck_assert_str_eq(again.cfg.label, b.cfg.label);
    ck_assert(memcmp(again.cfg.gravity, b.cfg.gravity, sizeof b.cfg.gravity) == 0);
    char *text_again = sluice_yaml_emit(again.root);
    ck_assert_str_eq(text_again, text);
    free(text_again);
    free(text);
    release(&again);
    release(&b);
}
END_TEST

START_TEST(defaults_split_by_dimension)
{
    bound b = bind_tait("plugins:\n  tait:\n    speed_of_sound: 20\n", 3, specs, SPEC_COUNT);
    ck_assert_int_eq(b.errors, 0);
    ck_assert(b.cfg.gravity[0] == 0 && b.cfg.gravity[1] == 0 && b.cfg.gravity[2] == -9.81);
    char *text = sluice_yaml_emit(b.root);
    ck_assert_ptr_nonnull(strstr(text, "\n    gravity: [0, 0, -9.81]\n"));
    free(text);
    release(&b);
}
END_TEST

START_TEST(absent_or_empty_sections)
{
    /* `tait:` with nothing: an empty mapping, replaced by the mapping of
     * defaults at the same position */
    bound b = bind_tait("plugins:\n  tait:\n  other: 1\n", 2, specs, SPEC_COUNT);
    ck_assert_int_eq(b.errors, 1);
    ck_assert_str_eq(sluice_diag_message(b.diag, 0),
                     "scene.yaml:2:3: error: missing required parameter 'speed_of_sound' in "
                     "plugins.tait (number > 0, m s^-1): " SPEED_DOC);
    sluice_node *tait = tait_section(&b);
    ck_assert_int_eq(tait->kind, SLUICE_NODE_MAPPING);
    ck_assert_str_eq(tait->file, "scene.yaml");
    ck_assert_int_eq(tait->line, 2);
    ck_assert_int_eq(tait->column, 8);
    ck_assert_uint_eq(tait->count, SPEC_COUNT - 3);
    ck_assert(b.cfg.gamma == 7);
    release(&b);

    /* no section at all: it is created; the message goes to the owner */
    sluice_diag *diag = sluice_diag_create();
    sluice_arena *arena = sluice_arena_create();
    sluice_node *owner = sluice_node_new_scalar("tait", 1, "owner.yaml", 5, 7);
    sluice_node *section = NULL;
    config cfg;
    memset(&cfg, 0, sizeof cfg);
    ck_assert_int_eq(sluice_schema_bind(specs, SPEC_COUNT, &section, owner, "plugins.tait", 2,
                                        &cfg, arena, diag),
                     1);
    ck_assert_str_eq(sluice_diag_message(diag, 0),
                     "owner.yaml:5:7: error: missing required parameter 'speed_of_sound' in "
                     "plugins.tait (number > 0, m s^-1): " SPEED_DOC);
    ck_assert_ptr_nonnull(section);
    ck_assert_int_eq(section->kind, SLUICE_NODE_MAPPING);
    ck_assert_str_eq(sluice_node_get(section, "kernel")->value, "wendland_c2");
    ck_assert(cfg.gamma == 7);
    sluice_node_free(section);

    /* without an owner there is no position */
    section = NULL;
    ck_assert_int_eq(
        sluice_schema_bind(specs, 1, &section, NULL, "time", 2, &cfg, arena, diag), 1);
    ck_assert_str_eq(sluice_diag_message(diag, 1),
                     "error: missing required parameter 'speed_of_sound' in time (number > 0, "
                     "m s^-1): " SPEED_DOC);
    ck_assert_ptr_null(section); /* nothing to insert */

    /* an owner without a line still names its file */
    sluice_node *made = sluice_node_new_mapping("default", 0, 0);
    ck_assert_int_eq(sluice_schema_bind(specs, 1, &section, made, "time", 2, &cfg, arena, diag),
                     1);
    ck_assert_str_eq(sluice_diag_message(diag, 2),
                     "default: error: missing required parameter 'speed_of_sound' in time "
                     "(number > 0, m s^-1): " SPEED_DOC);
    sluice_node_free(made);
    sluice_node_free(owner);
    sluice_arena_destroy(arena);
    sluice_diag_destroy(diag);
}
END_TEST

START_TEST(section_must_be_a_mapping)
{
    bound b = bind_tait("plugins:\n  tait: [1, 2]\n", 2, specs, SPEC_COUNT);
    ck_assert_int_eq(b.errors, 1);
    ck_assert_str_eq(sluice_diag_message(b.diag, 0),
                     "scene.yaml:2:9: error: plugins.tait must be a mapping of parameters");
    release(&b);
    bound q = bind_tait("plugins:\n  tait: ''\n", 2, specs, SPEC_COUNT);
    ck_assert_int_eq(q.errors, 1);
    ck_assert_str_eq(sluice_diag_message(q.diag, 0),
                     "scene.yaml:2:9: error: plugins.tait must be a mapping of parameters");
    release(&q);
}
END_TEST

START_TEST(invalid_defaults_are_reported)
{
    static const sluice_param_spec bad[] = {
        {"positive", SLUICE_PARAM_REAL, 0, "0", 0, 0,
         SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, NULL, "", NULL, 0},
        {"broken", SLUICE_PARAM_REAL_LIST, 0, "[1,", 0, 0, 0, NULL, "", NULL, 0},
    };
    bound b = bind_tait("plugins:\n  tait: {}\n", 2, bad, 2);
    ck_assert_int_eq(b.errors, 2);
    ck_assert_str_eq(sluice_diag_message(b.diag, 0),
                     "scene.yaml:2:3: error: invalid default '0' for plugins.tait.positive in the "
                     "parameter table: plugins.tait.positive = 0 is out of range: it must be > 0");
    ck_assert_str_eq(sluice_diag_message(b.diag, 1),
                     "scene.yaml:2:3: error: invalid default '[1,' for plugins.tait.broken in the "
                     "parameter table: YAML syntax error: did not find expected node content "
                     "(while parsing a flow node that started at line 2, column 1)");
    ck_assert_uint_eq(tait_section(&b)->count, 0); /* nothing inserted */
    release(&b);
}
END_TEST

/* -------------------------------------------------------------- errors -- */

START_TEST(unknown_keys)
{
    bound b = bind_tait("plugins:\n"
                        "  tait:\n"
                        "    speed_of_sond: 20\n"
                        "    zzzzzzzz: 1\n",
                        2, specs, SPEC_COUNT);
    /* both unknown keys are reported; speed_of_sound is not reported missing
     * as well, since the first message already points at it */
    ck_assert_int_eq(b.errors, 2);
    ck_assert_str_eq(sluice_diag_message(b.diag, 0),
                     "scene.yaml:3:5: error: unknown key 'speed_of_sond' in plugins.tait; did you "
                     "mean 'speed_of_sound'?");
    ck_assert_str_eq(sluice_diag_message(b.diag, 1),
                     "scene.yaml:4:5: error: unknown key 'zzzzzzzz' in plugins.tait (valid keys: "
                     "speed_of_sound, gamma, steps, verbose, label, kernel, gravity, pair, "
                     "levels, outline, surface)");
    ck_assert_ptr_null(sluice_diag_message(b.diag, 2));
    /* unknown keys are marked used too (they have been reported) */
    ck_assert_int_eq(sluice_node_get_key(tait_section(&b), "zzzzzzzz")->used, 1);
    release(&b);

    /* without a typo pointing at it, the missing parameter is reported */
    bound m = bind_tait("plugins:\n  tait:\n    zzzzzzzz: 1\n", 2, specs, SPEC_COUNT);
    ck_assert_int_eq(m.errors, 2);
    ck_assert_str_eq(sluice_diag_message(m.diag, 1),
                     "scene.yaml:2:3: error: missing required parameter 'speed_of_sound' in "
                     "plugins.tait (number > 0, m s^-1): " SPEED_DOC);
    release(&m);

    /* a plugin without parameters */
    bound none = bind_tait("plugins:\n  tait: {alpha: 1}\n", 2, specs, 0);
    ck_assert_int_eq(none.errors, 1);
    ck_assert_str_eq(sluice_diag_message(none.diag, 0),
                     "scene.yaml:2:10: error: unknown key 'alpha' in plugins.tait, which takes no "
                     "parameters");
    release(&none);

    /* the top level */
    sluice_diag *diag = sluice_diag_create();
    sluice_arena *arena = sluice_arena_create();
    sluice_node *root = parse_ok("gama: 3\n", diag);
    config cfg;
    memset(&cfg, 0, sizeof cfg);
    ck_assert_int_eq(
        sluice_schema_bind(specs, SPEC_COUNT, &root, root, "", 2, &cfg, arena, diag), 2);
    ck_assert_str_eq(sluice_diag_message(diag, 0),
                     "scene.yaml:1:1: error: unknown key 'gama' at the top level; did you mean "
                     "'gamma'?");
    ck_assert_str_eq(sluice_diag_message(diag, 1),
                     "scene.yaml:1:1: error: missing required parameter 'speed_of_sound' at the "
                     "top level (number > 0, m s^-1): " SPEED_DOC);
    sluice_node_free(root);
    sluice_arena_destroy(arena);
    sluice_diag_destroy(diag);
}
END_TEST

/* A key renamed with its unit as a suffix (dbc's phase, in radians, became
 * phase_deg): the old name is refused with the new one suggested, unless two
 * keys extend it. */
START_TEST(renamed_keys_are_suggested)
{
    typedef struct {
        sluice_real phase_deg, turn_deg, turn_rad;
    } angles;
    static const sluice_param_spec angle_specs[] = {
        {"phase_deg", SLUICE_PARAM_REAL, offsetof(angles, phase_deg), "0", 0, 0, 0, "deg",
         "phase", NULL, 0},
        {"turn_deg", SLUICE_PARAM_REAL, offsetof(angles, turn_deg), "0", 0, 0, 0, "deg", "turn",
         NULL, 0},
        {"turn_rad", SLUICE_PARAM_REAL, offsetof(angles, turn_rad), "0", 0, 0, 0, "rad", "turn",
         NULL, 0},
    };
    sluice_diag *diag = sluice_diag_create();
    sluice_arena *arena = sluice_arena_create();
    sluice_node *root = parse_ok("phase: 0.3\nturn: 1\n", diag);
    angles a;
    memset(&a, 0, sizeof a);
    ck_assert_int_eq(sluice_schema_bind(angle_specs, 3, &root, root, "plugins.dbc", 2, &a, arena,
                                        diag),
                     2);
    ck_assert_str_eq(sluice_diag_message(diag, 0),
                     "scene.yaml:1:1: error: unknown key 'phase' in plugins.dbc; did you mean "
                     "'phase_deg'?");
    ck_assert_str_eq(sluice_diag_message(diag, 1),
                     "scene.yaml:2:1: error: unknown key 'turn' in plugins.dbc (valid keys: "
                     "phase_deg, turn_deg, turn_rad)");
    sluice_node_free(root);
    sluice_arena_destroy(arena);
    sluice_diag_destroy(diag);
}
END_TEST

START_TEST(wrong_types)
{
    static const struct {
        const char *line, *expected;
    } cases[] = {
        {"gamma: fast",
         "scene.yaml:3:12: error: wrong type for plugins.tait.gamma: expected a number, got "
         "'fast'"},
        {"gamma: \"1.0\"",
         "scene.yaml:3:12: error: wrong type for plugins.tait.gamma: expected a number, got the "
         "string \"1.0\""},
        {"gamma: [1]",
         "scene.yaml:3:12: error: wrong type for plugins.tait.gamma: expected a number, got a "
         "list"},
        {"gamma:",
         "scene.yaml:3:11: error: wrong type for plugins.tait.gamma: expected a number, got an "
         "empty value"},
        {"gamma: .inf",
         "scene.yaml:3:12: error: wrong type for plugins.tait.gamma: expected a number, got "
         "'.inf'"},
        {"steps: 1.5",
         "scene.yaml:3:12: error: wrong type for plugins.tait.steps: expected an integer, got "
         "'1.5'"},
        {"steps: 1e-3",
         "scene.yaml:3:12: error: wrong type for plugins.tait.steps: expected an integer, got "
         "'1e-3'"},
        {"verbose: maybe",
         "scene.yaml:3:14: error: wrong type for plugins.tait.verbose: expected a boolean (true "
         "or false), got 'maybe'"},
        {"verbose: 'true'",
         "scene.yaml:3:14: error: wrong type for plugins.tait.verbose: expected a boolean (true "
         "or false), got the string \"true\""},
        {"label: [a]",
         "scene.yaml:3:12: error: wrong type for plugins.tait.label: expected a string, got a "
         "list"},
        {"kernel: {a: 1}",
         "scene.yaml:3:13: error: wrong type for plugins.tait.kernel: expected one of: "
         "wendland_c2, cubic_spline, gaussian, got a mapping"},
        {"gravity: 9.81",
         "scene.yaml:3:14: error: wrong type for plugins.tait.gravity: expected a list of 2 "
         "numbers, got '9.81'"},
        {"gravity: [0, x]",
         "scene.yaml:3:18: error: wrong type for plugins.tait.gravity.1: expected a number, got "
         "'x'"},
        {"levels: 0.5",
         "scene.yaml:3:13: error: wrong type for plugins.tait.levels: expected a list of "
         "numbers, got '0.5'"},
        {"outline: {}",
         "scene.yaml:3:14: error: wrong type for plugins.tait.outline: expected a list of "
         "points, each a list of 2 numbers, got a mapping"},
        {"outline: [[0, 0], 5]",
         "scene.yaml:3:23: error: wrong type for plugins.tait.outline.1: expected a point (a "
         "list of 2 numbers), got '5'"},
        {"outline: [[0, 0], [1, '2']]",
         "scene.yaml:3:27: error: wrong type for plugins.tait.outline.1.1: expected a number, "
         "got the string \"2\""},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        expect_one_error(cases[i].line, 2, cases[i].expected);
}
END_TEST

START_TEST(out_of_range)
{
    /* inclusive bounds */
    expect_one_error("gamma: 0.5", 2,
                     "scene.yaml:3:12: error: plugins.tait.gamma = 0.5 is out of range: it must "
                     "be in [1, 10]");
    expect_one_error("gamma: 10.5", 2,
                     "scene.yaml:3:12: error: plugins.tait.gamma = 10.5 is out of range: it must "
                     "be in [1, 10]");
    ck_assert(expect_ok("gamma: 1", 2).gamma == 1);
    ck_assert(expect_ok("gamma: 10", 2).gamma == 10);
    expect_one_error("steps: 0", 2,
                     "scene.yaml:3:12: error: plugins.tait.steps = 0 is out of range: it must be "
                     ">= 1");
    ck_assert_int_eq(expect_ok("steps: 1", 2).steps, 1);
    /* exclusive bounds, with the unit */
    expect_one_error("speed_of_sound: -3", 2,
                     "scene.yaml:3:21: error: plugins.tait.speed_of_sound = -3 m s^-1 is out of "
                     "range: it must be > 0 m s^-1");
    expect_one_error("speed_of_sound: 0", 2,
                     "scene.yaml:3:21: error: plugins.tait.speed_of_sound = 0 m s^-1 is out of "
                     "range: it must be > 0 m s^-1");
    ck_assert(expect_ok("speed_of_sound: 1e-6", 2).speed_of_sound == 1e-6);
    /* every component of vectors and lists */
    expect_one_error("pair: [1, 5]", 2,
                     "scene.yaml:3:15: error: plugins.tait.pair.1 = 5 m is out of range: it must "
                     "be in [0, 5) m");
    expect_one_error("pair: [-1, 1]", 2,
                     "scene.yaml:3:12: error: plugins.tait.pair.0 = -1 m is out of range: it must "
                     "be in [0, 5) m");
    ck_assert(expect_ok("pair: [0, 4.999]", 2).pair[1] == 4.999);
    expect_one_error("levels: [0.5, 0]", 2,
                     "scene.yaml:3:19: error: plugins.tait.levels.1 = 0 is out of range: it must "
                     "be in (0, 1]");
    ck_assert_uint_eq(expect_ok("levels: [1, 0.001]", 2).levels.count, 2);

    /* points: each coordinate */
    static const sluice_param_spec positive_points[] = {
        {"points", SLUICE_PARAM_POINT_LIST, offsetof(config, outline), NULL, 0, 0,
         SLUICE_PARAM_HAS_MIN, "m", "", NULL, 0},
    };
    bound b = bind_tait("plugins:\n  tait:\n    points: [[0, 1], [2, -3]]\n", 2,
                        positive_points, 1);
    ck_assert_int_eq(b.errors, 1);
    ck_assert_str_eq(sluice_diag_message(b.diag, 0),
                     "scene.yaml:3:26: error: plugins.tait.points.1.1 = -3 m is out of range: it "
                     "must be >= 0 m");
    release(&b);
}
END_TEST

START_TEST(vector_lengths)
{
    expect_one_error("gravity: [0, 0, -9.81]", 2,
                     "scene.yaml:3:14: error: wrong length for plugins.tait.gravity: expected 2 "
                     "numbers (one per dimension of the 2D scene), got 3");
    expect_one_error("gravity: [0, -9.81]", 3,
                     "scene.yaml:3:14: error: wrong length for plugins.tait.gravity: expected 3 "
                     "numbers (one per dimension of the 3D scene), got 2");
    expect_one_error("pair: [1]", 3,
                     "scene.yaml:3:11: error: wrong length for plugins.tait.pair: expected 2 "
                     "numbers, got 1");
    expect_one_error("outline: [[0, 0], [1, 0, 0]]", 2,
                     "scene.yaml:3:23: error: wrong length for plugins.tait.outline.1: expected a "
                     "point of 2 numbers (the scene is 2D), got 3");
    expect_one_error("outline: [[0, 0, 0], [1, 0]]", 3,
                     "scene.yaml:3:26: error: wrong length for plugins.tait.outline.1: expected a "
                     "point of 3 numbers (the scene is 3D), got 2");
}
END_TEST

START_TEST(enum_choices)
{
    expect_one_error("kernel: wendland_c3", 2,
                     "scene.yaml:3:13: error: invalid value 'wendland_c3' for plugins.tait.kernel; "
                     "did you mean 'wendland_c2'?");
    /* 3 edits from 'wendland_c2' is too far for an 8-letter word */
    expect_one_error("kernel: wendland", 2,
                     "scene.yaml:3:13: error: invalid value 'wendland' for plugins.tait.kernel: "
                     "expected one of: wendland_c2, cubic_spline, gaussian");
    expect_one_error("kernel: spline_of_doom", 2,
                     "scene.yaml:3:13: error: invalid value 'spline_of_doom' for "
                     "plugins.tait.kernel: expected one of: wendland_c2, cubic_spline, gaussian");
    expect_one_error("kernel: 'Gaussian'", 2,
                     "scene.yaml:3:13: error: invalid value 'Gaussian' for "
                     "plugins.tait.kernel; did you mean 'gaussian'?");
}
END_TEST

START_TEST(errors_accumulate)
{
    bound b = bind_tait("plugins:\n"
                        "  tait:\n"
                        "    speed_of_sound: fast\n"
                        "    gamma: 0\n"
                        "    stpes: 3\n"
                        "    kernel: nope\n"
                        "    gravity: [1]\n"
                        "    levels: [2]\n",
                        2, specs, SPEC_COUNT);
    ck_assert_int_eq(b.errors, 6);
    ck_assert_uint_eq(sluice_diag_count(b.diag), 6);
    /* unknown keys first, then the parameters in table order */
    ck_assert_ptr_nonnull(strstr(sluice_diag_message(b.diag, 0), ":5:5: error: unknown key 'stpes'"));
    ck_assert_ptr_nonnull(strstr(sluice_diag_message(b.diag, 1), ":3:21: error: wrong type"));
    ck_assert_ptr_nonnull(strstr(sluice_diag_message(b.diag, 2), ":4:12: error: plugins.tait.gamma"));
    ck_assert_ptr_nonnull(strstr(sluice_diag_message(b.diag, 3), ":6:13: error: invalid value"));
    ck_assert_ptr_nonnull(strstr(sluice_diag_message(b.diag, 4), ":7:14: error: wrong length"));
    ck_assert_ptr_nonnull(strstr(sluice_diag_message(b.diag, 5), ":8:14: error: plugins.tait.levels.0"));
    /* "steps" was misspelled, so its default was inserted next to it */
    ck_assert_ptr_nonnull(sluice_node_get(tait_section(&b), "steps"));
    release(&b);
}
END_TEST

START_TEST(overrides_are_positioned_in_the_argument)
{
    sluice_diag *diag = sluice_diag_create();
    sluice_arena *arena = sluice_arena_create();
    sluice_node *root = parse_ok("plugins:\n  tait:\n    speed_of_sound: 20\n", diag);
    ck_assert_int_eq(sluice_yaml_override(root, "plugins.tait.gamma=0.5", "--set #1", diag), 0);
    ck_assert_int_eq(sluice_yaml_override(root, "plugins.tait.gammma=8", "--set #2", diag), 0);
    sluice_node *plugins = sluice_node_get(root, "plugins");
    config cfg;
    memset(&cfg, 0, sizeof cfg);
    ck_assert_int_eq(sluice_schema_bind(specs, SPEC_COUNT, &plugins->items[0], plugins->keys[0],
                                        "plugins.tait", 2, &cfg, arena, diag),
                     2);
    ck_assert_str_eq(sluice_diag_message(diag, 0),
                     "--set #2:1:14: error: unknown key 'gammma' in plugins.tait; did you mean "
                     "'gamma'?");
    ck_assert_str_eq(sluice_diag_message(diag, 1),
                     "--set #1:1:20: error: plugins.tait.gamma = 0.5 is out of range: it must be "
                     "in [1, 10]");
    sluice_node_free(root);
    sluice_arena_destroy(arena);
    sluice_diag_destroy(diag);
}
END_TEST

/* ------------------------------------------------ scalars, descriptions -- */

START_TEST(scalar_parsers)
{
    double r = 0;
    ck_assert_int_eq(sluice_parse_real("1", &r), 0);
    ck_assert(r == 1);
    ck_assert_int_eq(sluice_parse_real("-9.81", &r), 0);
    ck_assert(r == -9.81);
    ck_assert_int_eq(sluice_parse_real("+2.5e-3", &r), 0);
    ck_assert(r == 2.5e-3);
    static const char *bad_reals[] = {"", " 1", "1 ", "1.0x", "0x10", "nan", "inf", "-inf",
                                      "1e999", ".inf", "1,5", "one", "1_000"};
    for (size_t i = 0; i < sizeof bad_reals / sizeof bad_reals[0]; i++)
        ck_assert_msg(sluice_parse_real(bad_reals[i], &r) != 0, "'%s' accepted", bad_reals[i]);

    long long n = 0;
    ck_assert_int_eq(sluice_parse_int("42", &n), 0);
    ck_assert_int_eq(n, 42);
    ck_assert_int_eq(sluice_parse_int("-7", &n), 0);
    ck_assert_int_eq(n, -7);
    ck_assert_int_eq(sluice_parse_int("1e3", &n), 0);
    ck_assert_int_eq(n, 1000);
    ck_assert_int_eq(sluice_parse_int("2.0", &n), 0);
    ck_assert_int_eq(n, 2);
    ck_assert_int_eq(sluice_parse_int("9223372036854775807", &n), 0);
    ck_assert_int_eq(n, INT64_MAX);
    static const char *bad_ints[] = {"", "1.5", "1e-3", "12a", " 3", "9223372036854775808",
                                     "1e19", "0x10", "nan"};
    for (size_t i = 0; i < sizeof bad_ints / sizeof bad_ints[0]; i++)
        ck_assert_msg(sluice_parse_int(bad_ints[i], &n) != 0, "'%s' accepted", bad_ints[i]);

    int flag = -1;
    static const struct {
        const char *text;
        int value;
    } bools[] = {{"true", 1}, {"TRUE", 1}, {"Yes", 1}, {"on", 1},
                 {"false", 0}, {"No", 0}, {"OFF", 0}};
    for (size_t i = 0; i < sizeof bools / sizeof bools[0]; i++) {
        ck_assert_int_eq(sluice_parse_bool(bools[i].text, &flag), 0);
        ck_assert_int_eq(flag, bools[i].value);
    }
    static const char *bad_bools[] = {"", "y", "1", "0", "truee", "of"};
    for (size_t i = 0; i < sizeof bad_bools / sizeof bad_bools[0]; i++)
        ck_assert_msg(sluice_parse_bool(bad_bools[i], &flag) != 0, "'%s' accepted", bad_bools[i]);
}
END_TEST

START_TEST(descriptions)
{
    static const char *expected[] = {
        "number > 0 (m s^-1)",
        "number in [1, 10]",
        "integer >= 1",
        "boolean",
        "string",
        "one of: wendland_c2, cubic_spline, gaussian",
        "vector of D numbers (m s^-2)",
        "vector of 2 numbers in [0, 5) (m)",
        "list of numbers in (0, 1]",
        "list of points (m)",
        "number (m)",
    };
    char buffer[128];
    for (uint32_t i = 0; i < SPEC_COUNT; i++)
        ck_assert_str_eq(sluice_schema_describe(&specs[i], buffer, sizeof buffer), expected[i]);
    sluice_param_spec below = specs[0];
    below.flags = SLUICE_PARAM_HAS_MAX | SLUICE_PARAM_MAX_EXCLUSIVE;
    below.max = 0.1;
    below.unit = "";
    ck_assert_str_eq(sluice_schema_describe(&below, buffer, sizeof buffer), "number < 0.1");
    below.flags = SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX | SLUICE_PARAM_MIN_EXCLUSIVE;
    below.min = 1e-9;
    ck_assert_str_eq(sluice_schema_describe(&below, buffer, sizeof buffer),
                     "number in (1e-09, 0.1]");
    sluice_param_spec vector3 = specs[7];
    vector3.length = 3;
    vector3.flags = 0;
    ck_assert_str_eq(sluice_schema_describe(&vector3, buffer, sizeof buffer),
                     "vector of 3 numbers (m)");
    /* a small buffer truncates safely */
    char small[8];
    ck_assert_str_eq(sluice_schema_describe(&specs[0], small, sizeof small), "number ");
}
END_TEST

int main(void)
{
    Suite *s = suite_create("schema");
    TCase *values = tcase_create("values");
    tcase_add_test(values, every_type_is_converted);
    tcase_add_test(values, defaults_are_inserted_and_round_trip);
    tcase_add_test(values, defaults_split_by_dimension);
    tcase_add_test(values, absent_or_empty_sections);
    tcase_add_test(values, section_must_be_a_mapping);
    tcase_add_test(values, invalid_defaults_are_reported);
    suite_add_tcase(s, values);
    TCase *errors = tcase_create("errors");
    tcase_add_test(errors, unknown_keys);
    tcase_add_test(errors, renamed_keys_are_suggested);
    tcase_add_test(errors, wrong_types);
    tcase_add_test(errors, out_of_range);
    tcase_add_test(errors, vector_lengths);
    tcase_add_test(errors, enum_choices);
    tcase_add_test(errors, errors_accumulate);
    tcase_add_test(errors, overrides_are_positioned_in_the_argument);
    suite_add_tcase(s, errors);
    TCase *helpers = tcase_create("helpers");
    tcase_add_test(helpers, scalar_parsers);
    tcase_add_test(helpers, descriptions);
    suite_add_tcase(s, helpers);

    SRunner *runner = srunner_create(s);
    srunner_run_all(runner, CK_NORMAL);
    int failed = srunner_ntests_failed(runner);
    srunner_free(runner);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
