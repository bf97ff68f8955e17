/* Bad input through the sluice program: every case must give one clear
 * message naming file:line:column, exit with status 2, never crash, and
 * leave no output directory behind. */
#include "sluice/plugin.h"
#include "test_util.h"

/* A valid small scene; cases edit one line of it. Line numbers matter. */
static const char *base_lines[] = {
    "dimensions: 2",                                   /* 1 */
    "particles:",                                      /* 2 */
    "  spacing: 0.05",                                 /* 3 */
    "time:",                                           /* 4 */
    "  end: 0.01",                                     /* 5 */
    "domain:",                                         /* 6 */
    "  min: [-0.2, -0.2]",                             /* 7 */
    "  max: [1.2, 1.2]",                               /* 8 */
    "geometry:",                                       /* 9 */
    "  fluid:",                                        /* 10 */
    "    - {shape: box, min: [0, 0], max: [0.5, 0.5]}", /* 11 */
    "  walls:",                                        /* 12 */
    "    - {shape: tank, min: [0, 0], max: [1, 1]}",   /* 13 */
    "plugins:",                                        /* 14 */
    "  wendland_c2: {}",                               /* 15 */
    "  tait:",                                         /* 16 */
    "    speed_of_sound: 20",                          /* 17 */
    "  continuity: {}",                                /* 18 */
    "  pressure_gradient: {}",                         /* 19 */
    "  artificial_viscosity: {alpha: 0.1}",            /* 20 */
    "  gravity: {}",                                   /* 21 */
    "  dbc: {}",                                       /* 22 */
    "  time_step: {}",                                 /* 23 */
    "  symplectic: {}",                                /* 24 */
};
#define BASE_COUNT (sizeof base_lines / sizeof base_lines[0])

/* The base scene with line `line` (1-based; 0 for none) replaced by
 * `replacement` and `extra` appended. */
static char *scene_text(int line, const char *replacement, const char *extra)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    for (size_t i = 0; i < BASE_COUNT; i++)
        fprintf(f, "%s\n", (int)i + 1 == line ? replacement : base_lines[i]);
    if (extra)
        fputs(extra, f);
    fclose(f);
    return text;
}

/* The base scene without lines first..last (1-based), `extra` appended. */
static char *scene_without(int first, int last, const char *extra)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    for (size_t i = 0; i < BASE_COUNT; i++)
        if ((int)i + 1 < first || (int)i + 1 > last)
            fprintf(f, "%s\n", base_lines[i]);
    if (extra)
        fputs(extra, f);
    fclose(f);
    return text;
}

typedef struct outcome {
    int status;
    char *output;
    char *dir;
    char *scene;
} outcome;

static outcome run_case(const char *text, const char *extra_args)
{
    outcome o;
    o.dir = test_scratch("input");
    ck_assert_ptr_nonnull(o.dir);
    o.scene = test_write_file(o.dir, "scene.yaml", text);
    char *args = NULL;
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/out --no-progress %s", o.scene, o.dir,
                              extra_args ? extra_args : ""),
                     0);
    o.status = test_sluice(args, &o.output);
    free(args);
    return o;
}

static void expect_error_status(outcome *o, int status, int line, int column,
                                const char *needle)
{
    ck_assert_msg(o->status == status, "exit status %d (expected %d); output:\n%s", o->status,
                  status, o->output);
    ck_assert_msg(test_count_lines(o->output, "error:") == 1,
                  "expected exactly one error message, got:\n%s", o->output);
    char *where = NULL;
    ck_assert_int_ge(asprintf(&where, "%s:%d:%d: error: ", o->scene, line, column), 0);
    ck_assert_msg(strstr(o->output, where), "expected '%s' in:\n%s", where, o->output);
    ck_assert_msg(strstr(o->output, needle), "expected '%s' in:\n%s", needle, o->output);
    char *out = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", o->dir), 0);
    ck_assert_msg(!test_exists(out), "bad input must not create the output directory");
    ck_assert_msg(!strstr(o->output, "Sanitizer") && !strstr(o->output, "runtime error"),
                  "sanitizer report:\n%s", o->output);
    free(out);
    free(where);
}

static void expect_error(outcome *o, int line, int column, const char *needle)
{
    expect_error_status(o, 2, line, column, needle);
}

static void done(outcome *o)
{
    free(o->output);
    free(o->dir);
    free(o->scene);
}

START_TEST(valid_base_scene_runs)
{
    char *text = scene_text(0, NULL, NULL);
    outcome o = run_case(text, "--quiet");
    ck_assert_msg(o.status == 0, "the base scene must run (status %d):\n%s", o.status, o.output);
    char *json = NULL;
    ck_assert_int_ge(asprintf(&json, "%s/out/run.json", o.dir), 0);
    ck_assert(test_exists(json));
    free(json);
    done(&o);
    free(text);
}
END_TEST

START_TEST(yaml_syntax_error)
{
    char *text = scene_text(5, "  end: 0.01: 2", NULL);
    outcome o = run_case(text, NULL);
    expect_error(&o, 5, 12, "YAML syntax error");
    done(&o);
    free(text);
}
END_TEST

START_TEST(unknown_plugin_parameter_suggests)
{
    char *text = scene_text(17, "    speed_of_sond: 20", NULL);
    outcome o = run_case(text, NULL);
    expect_error(&o, 17, 5, "did you mean 'speed_of_sound'?");
    done(&o);
    free(text);
}
END_TEST

START_TEST(unknown_top_level_key_suggests)
{
    char *text = scene_text(4, "tmie:", NULL);
    outcome o = run_case(text, NULL);
    ck_assert_int_eq(o.status, 2);
    ck_assert_msg(strstr(o.output, "4:1: error: unknown key 'tmie' at the top level; did you "
                                   "mean 'time'?"),
                  "%s", o.output);
    done(&o);
    free(text);
}
END_TEST

START_TEST(wrong_type)
{
    char *text = scene_text(17, "    speed_of_sound: fast", NULL);
    outcome o = run_case(text, NULL);
    expect_error(&o, 17, 21, "plugins.tait.speed_of_sound");
    ck_assert(strstr(o.output, "number"));
    done(&o);
    free(text);
}
END_TEST

START_TEST(out_of_range)
{
    char *text = scene_text(20, "  artificial_viscosity: {alpha: -1}", NULL);
    outcome o = run_case(text, NULL);
    expect_error(&o, 20, 33, "plugins.artificial_viscosity.alpha");
    ck_assert(strstr(o.output, "range"));
    done(&o);
    free(text);
}
END_TEST

/* An output interval of 1e-300 s (found by the fuzzer: the gauge's schedule
 * then counted 1e296 sample times after the first step) is refused at load:
 * every interval is at least 1e-6 s, and a step ends on each sample time. */
START_TEST(interval_too_small)
{
    char *text = scene_text(20, "  artificial_viscosity: {alpha: 0.1}\n  wall_monitor: {interval: 1e-300}",
                            NULL);
    outcome o = run_case(text, NULL);
    expect_error(&o, 21, 28, "plugins.wall_monitor.interval");
    ck_assert(strstr(o.output, "range"));
    done(&o);
    free(text);
}
END_TEST

/* Accepted silently before: an end time the time loop counts as reached
 * before the first step ("completed 0 steps"), a plugin directory that does
 * not exist, a thread count that crashed libgomp. */
START_TEST(silent_acceptances_refused)
{
    char *text = scene_text(5, "  end: 1e-300", NULL);
    outcome o = run_case(text, NULL);
    expect_error(&o, 5, 8, "time.end");
    ck_assert(strstr(o.output, "range"));
    done(&o);
    free(text);

    text = scene_text(0, NULL, "plugin_path: /nonexistent/sluice-plugins\n");
    o = run_case(text, NULL);
    expect_error(&o, 25, 14, "plugin_path: '/nonexistent/sluice-plugins' is not a directory "
                             "(No such file or directory)");
    done(&o);
    free(text);

    text = scene_text(0, NULL, NULL);
    o = run_case(text, "--threads 100000");
    ck_assert_int_eq(o.status, 2);
    ck_assert_msg(strstr(o.output, "sluice: error: --threads 100000: at most ") &&
                      test_count_lines(o.output, "error:") == 1,
                  "%s", o.output);
    done(&o);
    free(text);
}
END_TEST

START_TEST(missing_plugin_suggests)
{
    char *text = scene_text(16, "  taitt:", NULL);
    outcome o = run_case(text, NULL);
    expect_error(&o, 16, 3, "did you mean 'tait'?");
    done(&o);
    free(text);
}
END_TEST

static char *fixture_scene(const char *plugin)
{
    char *extra = NULL;
    ck_assert_int_ge(asprintf(&extra, "  %s: {}\nplugin_path: %s\n", plugin,
                              getenv("SLUICE_FIXTURE_DIR")),
                     0);
    char *text = scene_text(0, NULL, extra);
    free(extra);
    return text;
}

START_TEST(plugin_wrong_abi_major)
{
    char *text = fixture_scene("abi_major_plugin");
    outcome o = run_case(text, NULL);
    expect_error(&o, 25, 3, "abi_major_plugin.so");
    char *versions = NULL;
    ck_assert_int_ge(asprintf(&versions, "ABI %d.0, but this sluice provides ABI %d.%d",
                              SLUICE_ABI_MAJOR + 1, SLUICE_ABI_MAJOR, SLUICE_ABI_MINOR),
                     0);
    ck_assert_msg(strstr(o.output, versions), "expected '%s' in:\n%s", versions, o.output);
    free(versions);
    done(&o);
    free(text);
}
END_TEST

START_TEST(plugin_newer_abi_minor)
{
    char *text = fixture_scene("abi_minor_plugin");
    outcome o = run_case(text, NULL);
    expect_error(&o, 25, 3, "abi_minor_plugin.so");
    ck_assert(strstr(o.output, "needs a newer sluice"));
    done(&o);
    free(text);
}
END_TEST

START_TEST(plugin_wrong_real_type)
{
    char *text = fixture_scene("float_plugin");
    outcome o = run_case(text, NULL);
    expect_error(&o, 25, 3, "4-byte real type");
    done(&o);
    free(text);
}
END_TEST

START_TEST(plugin_without_entry_point)
{
    char *text = fixture_scene("no_entry_plugin");
    outcome o = run_case(text, NULL);
    expect_error(&o, 25, 3, "no entry point 'sluice_plugin_entry'");
    done(&o);
    free(text);
}
END_TEST

START_TEST(plugin_failing_init)
{
    char *text = fixture_scene("failing_init_plugin");
    outcome o = run_case(text, NULL);
    expect_error(&o, 25, 3, "cannot open its lookup table 'missing.dat'");
    ck_assert_msg(strstr(o.output, "library 'failing_init_plugin' 1.2.3, plugin ABI") &&
                      strstr(o.output, "failing_init_plugin.so") &&
                      strstr(o.output, "failed to initialise"),
                  "the message must name the plugin, its version, ABI and path:\n%s", o.output);
    done(&o);
    free(text);
}
END_TEST

START_TEST(not_a_shared_object)
{
    char *dir = test_scratch("garbage");
    char *so = test_write_file(dir, "garbage_plugin.so", "this is not an ELF file\n");
    char *extra = NULL;
    ck_assert_int_ge(asprintf(&extra, "  garbage_plugin: {}\nplugin_path: %s\n", dir), 0);
    char *text = scene_text(0, NULL, extra);
    outcome o = run_case(text, NULL);
    expect_error(&o, 25, 3, "cannot be loaded");
    done(&o);
    free(text);
    free(extra);
    free(so);
    free(dir);
}
END_TEST

START_TEST(unreadable_scene_files)
{
    char *dir = test_scratch("unreadable");
    char *args = NULL, *output = NULL;
    /* a path that does not exist */
    ck_assert_int_ge(asprintf(&args, "run %s/nope.yaml --out %s/out", dir, dir), 0);
    int status = test_sluice(args, &output);
    ck_assert_int_eq(status, 2);
    ck_assert_msg(strstr(output, "nope.yaml:1:1: error: cannot read file"), "%s", output);
    ck_assert_int_eq(test_count_lines(output, "error:"), 1);
    free(args);
    free(output);
    /* a directory given as the scene */
    ck_assert_int_ge(asprintf(&args, "check %s", dir), 0);
    status = test_sluice(args, &output);
    ck_assert_int_eq(status, 2);
    ck_assert_msg(strstr(output, ":1:1: error: cannot read file"), "%s", output);
    free(args);
    free(output);
    /* an endless file: read up to the 64 MiB limit, then refused */
    ck_assert_int_ge(asprintf(&args, "run /dev/zero --out %s/out", dir), 0);
    status = test_sluice(args, &output);
    ck_assert_int_eq(status, 2);
    ck_assert_msg(strstr(output, "/dev/zero:1:1: error: cannot read file: it is longer than 64 "
                                 "MiB") &&
                      test_count_lines(output, "error:") == 1,
                  "%s", output);
    free(args);
    free(output);
    char *out = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", dir), 0);
    ck_assert(!test_exists(out));
    free(out);
    free(dir);
}
END_TEST

START_TEST(bad_command_line_override)
{
    char *text = scene_text(0, NULL, NULL);
    outcome o = run_case(text, "--set time.edn=1");
    ck_assert_int_eq(o.status, 2);
    ck_assert_msg(strstr(o.output, "--set #1:1:") && strstr(o.output, "did you mean 'end'?"),
                  "%s", o.output);
    done(&o);
    outcome p = run_case(text, "--set particles.spacing=-1");
    ck_assert_int_eq(p.status, 2);
    ck_assert_msg(strstr(p.output, "particles.spacing") && strstr(p.output, "range"), "%s",
                  p.output);
    done(&p);
    free(text);
}
END_TEST

START_TEST(geometry_errors)
{
    char *text = scene_text(11, "    - {shape: bx, min: [0, 0], max: [0.5, 0.5]}", NULL);
    outcome o = run_case(text, NULL);
    expect_error(&o, 11, 15, "did you mean 'box'?");
    done(&o);
    free(text);
    text = scene_text(8, "  max: [0.4, 1.2]", NULL); /* tank wall outside the domain */
    o = run_case(text, NULL);
    ck_assert_int_eq(o.status, 2);
    ck_assert_msg(strstr(o.output, "outside the domain"), "%s", o.output);
    done(&o);
    free(text);
    /* a bow tie: its two loops turn opposite ways, and the fill left one
     * out (fewer particles than its area, accepted silently before) */
    text = scene_text(11,
                      "    - {shape: polygon, points: [[0, 0], [0.5, 0.5], [0.5, 0], [0, 0.5]]}",
                      NULL);
    o = run_case(text, NULL);
    expect_error(&o, 11, 32,
                 "geometry.fluid.0 crosses itself: its edge from (0, 0) to (0.5, 0.5) crosses "
                 "the edge from (0.5, 0) to (0, 0.5)");
    done(&o);
    free(text);
}
END_TEST

/* ------------------------------------------------------------ variants -- */

static const char *variants_block =
    "variants:\n"                                                                 /* 25 */
    "  inviscid:\n"                                                               /* 26 */
    "    description: without artificial viscosity\n"                             /* 27 */
    "    remove: [plugins.artificial_viscosity]\n"                                /* 28 */
    "  stiffer:\n"                                                                /* 29 */
    "    set: {plugins.tait.speed_of_sound: 40, geometry.fluid.0.max: [0.5, 0.4]}\n"; /* 30 */

/* Runs `sluice run` on the scene with the variants block and returns the
 * text of DIR/out/scene.resolved.yaml. */
static char *run_variant(const char *args)
{
    char *text = scene_text(0, NULL, variants_block);
    outcome o = run_case(text, args);
    ck_assert_msg(o.status == 0, "%s: status %d:\n%s", args, o.status, o.output);
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/out/scene.resolved.yaml", o.dir), 0);
    char *resolved = test_read_file(path);
    ck_assert_ptr_nonnull(resolved);
    free(path);
    done(&o);
    free(text);
    return resolved;
}

START_TEST(variants_run_and_are_listed)
{
    /* sluice check lists the variants with their descriptions */
    char *text = scene_text(0, NULL, variants_block);
    char *dir = test_scratch("variants");
    char *scene = test_write_file(dir, "scene.yaml", text);
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "check %s", scene), 0);
    ck_assert_int_eq(test_sluice(args, &output), 0);
    fprintf(stderr, "%s", output);
    ck_assert_msg(strstr(output, "valid 2D scene, 296 particles (100 fluid, 196 wall)") &&
                      strstr(output, "variants (sluice check|run SCENE --variant NAME):\n"
                                     "  inviscid  without artificial viscosity\n"
                                     "  stiffer\n"),
                  "%s", output);
    free(args);
    free(output);
    /* checking a variant: the fluid box 0.5 m x 0.4 m at dx = 0.05 m holds 80 particles */
    ck_assert_int_ge(asprintf(&args, "check %s --variant stiffer", scene), 0);
    ck_assert_int_eq(test_sluice(args, &output), 0);
    ck_assert_msg(strstr(output, "valid 2D scene (variant 'stiffer'), 276 particles (80 fluid"),
                  "%s", output);
    ck_assert_msg(!strstr(output, "variants ("), "%s", output);
    free(args);
    free(output);
    unlink(scene);
    rmdir(dir);
    free(scene);
    free(dir);
    free(text);

    /* the resolved scene shows the variant: the plugin removed, the record */
    char *resolved = run_variant("--variant inviscid --quiet");
    ck_assert_msg(!strstr(resolved, "artificial_viscosity") && strstr(resolved, "tait:") &&
                      strstr(resolved, "\nvariant: inviscid\n") && !strstr(resolved, "variants"),
                  "%s", resolved);
    free(resolved);
    /* --set after the variant: it wins over the variant's setting */
    resolved = run_variant("--variant=stiffer --set plugins.tait.speed_of_sound=30 --quiet");
    ck_assert_msg(strstr(resolved, "speed_of_sound: 30\n") &&
                      strstr(resolved, "max: [0.5, 0.4]\n") &&
                      strstr(resolved, "\nvariant: stiffer\n"),
                  "%s", resolved);
    free(resolved);
    /* no --variant: the base scene, without `variants` or a record */
    resolved = run_variant("--quiet");
    ck_assert_msg(strstr(resolved, "artificial_viscosity") &&
                      strstr(resolved, "speed_of_sound: 20\n") && !strstr(resolved, "variant"),
                  "%s", resolved);
    free(resolved);
}
END_TEST

START_TEST(variant_errors)
{
    char *text = scene_text(0, NULL, variants_block);
    outcome o = run_case(text, "--variant invscid");
    expect_error(&o, 25, 1, "unknown variant 'invscid'; did you mean 'inviscid'? (the scene "
                            "defines: inviscid, stiffer)");
    done(&o);
    o = run_case(text, "--variant inviscid --variant stiffer");
    ck_assert_int_eq(o.status, 2);
    ck_assert_msg(strstr(o.output, "--variant is given twice"), "%s", o.output);
    done(&o);
    /* setting the record would apply nothing: refused at the --set */
    o = run_case(text, "--set variant=inviscid");
    ck_assert_int_eq(o.status, 2);
    ck_assert_msg(strstr(o.output, "--set #1:1:1: error: --set 'variant=inviscid': a variant is "
                                   "applied with --variant NAME"),
                  "%s", o.output);
    done(&o);
    free(text);

    text = scene_text(0, NULL, NULL);
    o = run_case(text, "--variant inviscid");
    expect_error(&o, 1, 1, "--variant 'inviscid': the scene defines no variants");
    done(&o);
    free(text);

    text = scene_text(0, NULL,
                      "variants:\n"                                       /* 25 */
                      "  no_gravity:\n"                                   /* 26 */
                      "    remove:\n"                                     /* 27 */
                      "      - plugins.gravity\n"                         /* 28 */
                      "      - plugins.gravty\n");                        /* 29 */
    o = run_case(text, "--variant no_gravity");
    expect_error(&o, 29, 9, "variant 'no_gravity': cannot remove 'plugins.gravty': plugins has "
                            "no key 'gravty'; did you mean 'gravity'?");
    done(&o);
    free(text);

    /* a malformed variant stops the base scene too */
    text = scene_text(0, NULL,
                      "variants:\n"                                       /* 25 */
                      "  no_gravity: {remvoe: [plugins.gravity]}\n");     /* 26 */
    o = run_case(text, NULL);
    expect_error(&o, 26, 16, "unknown key 'remvoe' in variants.no_gravity; did you mean "
                             "'remove'?");
    done(&o);
    free(text);
}
END_TEST

/* ------------------------------------------------ invalid combinations -- */
/* Plugins that load one by one but cannot work together: refused at load
 * with one message at the plugin that makes the combination invalid. */

static void expect_combination(const char *text, int line, int column, const char *needle)
{
    outcome o = run_case(text, NULL);
    expect_error(&o, line, column, needle);
    done(&o);
}

START_TEST(field_written_by_two_plugins)
{
    /* two turbulence models: both compute the eddy viscosity */
    char *text = scene_text(0, NULL,
                            "  velocity_gradient: {}\n"        /* 25 */
                            "  mixing_length: {l_max: 0.1}\n"  /* 26 */
                            "  k_epsilon: {length_scale: 0.01}\n"); /* 27 */
    expect_combination(text, 27, 3, "both write field 'eddy_viscosity'");
    free(text);
}
END_TEST

START_TEST(constant_published_by_two_plugins)
{
    /* two equations of state */
    char *text = scene_text(0, NULL, "  linear_eos: {speed_of_sound: 20}\n");
    expect_combination(text, 25, 3, "published by both 'tait' and 'linear_eos'");
    free(text);
}
END_TEST

START_TEST(turbulence_without_its_fields)
{
    /* the Reynolds stress needs an eddy viscosity and the velocity gradient */
    char *text = scene_text(0, NULL, "  turbulent_stress: {}\n");
    expect_combination(text, 25, 3,
                       "fields 'eddy_viscosity' (read by 'turbulent_stress'), 'velocity_gradient' "
                       "(read by 'turbulent_stress') are computed by no loaded plugin");
    free(text);
}
END_TEST

START_TEST(no_equation_of_state)
{
    /* without tait (lines 16-17) nothing computes pressure or sound speed;
     * pressure_gradient moves to line 17 */
    char *text = scene_without(16, 17, NULL);
    expect_combination(text, 17, 3, "'pressure' (read by 'pressure_gradient')");
    free(text);
}
END_TEST

START_TEST(renormalised_without_kernel_correction)
{
    char *text = scene_text(18, "  continuity: {renormalise: true}", NULL);
    expect_combination(text, 18, 3, "field 'kernel_correction' (read by 'continuity')");
    free(text);
}
END_TEST

START_TEST(two_integrators_or_kernels)
{
    char *text = scene_text(0, NULL, "  predictor_corrector: {}\n");
    expect_combination(text, 25, 3, "two integrators are loaded");
    free(text);
    text = scene_text(0, NULL, "  cubic_spline: {}\n");
    expect_combination(text, 25, 3, "two kernels are loaded");
    free(text);
}
END_TEST

START_TEST(no_integrator)
{
    char *text = scene_without(24, 24, NULL);
    expect_combination(text, 1, 1, "no integrator is loaded");
    free(text);
}
END_TEST

START_TEST(spacing_larger_than_geometry)
{
    /* the fluid box is 0.5 m across */
    char *text = scene_text(3, "  spacing: 0.6", NULL);
    expect_combination(text, 11, 7, "less than particles.spacing = 0.6 m");
    free(text);
}
END_TEST

START_TEST(inlet_outside_the_domain)
{
    char *text = scene_text(0, NULL,
                            "  inlet:\n"             /* 25 */
                            "    position: 1.5\n"
                            "    depth: 0.1\n"
                            "    velocity: 1\n");
    expect_combination(text, 25, 3, "the inflow section (x = 1.5 m");
    free(text);
    text = scene_text(0, NULL,
                      "  inlet:\n"
                      "    position: 0\n"
                      "    depth: 2\n" /* water column above domain.max */
                      "    velocity: 1\n");
    expect_combination(text, 25, 3, "lies outside the domain");
    free(text);
}
END_TEST

START_TEST(scene_too_large_for_the_machine)
{
    /* 0.5 m x 0.5 m of fluid at dx = 1 um: 2.5e11 particles, about 75 TB;
     * refused before anything is allocated */
    char *text = scene_text(3, "  spacing: 1e-6", NULL);
    expect_combination(text, 3, 3, "would create about 2.5e+11 particles");
    free(text);
}
END_TEST

START_TEST(scene_needs_more_memory_than_the_machine)
{
    /* 0.5 m x 0.5 m of fluid at dx = 10 um: 2.5e9 particles (an index
     * counts them), of about 300 bytes each: 0.75 TB. Refused once the
     * plugins have declared their fields, before any particle exists, with
     * the figures; for want of resources (exit 4), not bad input */
    char *text = scene_text(3, "  spacing: 1e-5", NULL);
    outcome o = run_case(text, NULL);
    expect_error_status(&o, 4, 3, 3, "the run needs about");
    ck_assert_msg(strstr(o.output, "2.5e+09 particles") && strstr(o.output, "bytes each (fields ") &&
                      strstr(o.output, "neighbour list") && strstr(o.output, "leaves this process"),
                  "%s", o.output);
    done(&o);
    free(text);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("input errors");
    TCase *tc = tcase_create("cli");
    tcase_set_timeout(tc, 300);
    tcase_add_test(tc, valid_base_scene_runs);
    tcase_add_test(tc, yaml_syntax_error);
    tcase_add_test(tc, unknown_plugin_parameter_suggests);
    tcase_add_test(tc, unknown_top_level_key_suggests);
    tcase_add_test(tc, wrong_type);
    tcase_add_test(tc, out_of_range);
    tcase_add_test(tc, interval_too_small);
    tcase_add_test(tc, silent_acceptances_refused);
    tcase_add_test(tc, missing_plugin_suggests);
    tcase_add_test(tc, plugin_wrong_abi_major);
    tcase_add_test(tc, plugin_newer_abi_minor);
    tcase_add_test(tc, plugin_wrong_real_type);
    tcase_add_test(tc, plugin_without_entry_point);
    tcase_add_test(tc, plugin_failing_init);
    tcase_add_test(tc, not_a_shared_object);
    tcase_add_test(tc, unreadable_scene_files);
    tcase_add_test(tc, bad_command_line_override);
    tcase_add_test(tc, geometry_errors);
    tcase_add_test(tc, variants_run_and_are_listed);
    tcase_add_test(tc, variant_errors);
    suite_add_tcase(s, tc);
    TCase *combinations = tcase_create("invalid combinations");
    tcase_set_timeout(combinations, 300);
    tcase_add_test(combinations, field_written_by_two_plugins);
    tcase_add_test(combinations, constant_published_by_two_plugins);
    tcase_add_test(combinations, turbulence_without_its_fields);
    tcase_add_test(combinations, no_equation_of_state);
    tcase_add_test(combinations, renormalised_without_kernel_correction);
    tcase_add_test(combinations, two_integrators_or_kernels);
    tcase_add_test(combinations, no_integrator);
    tcase_add_test(combinations, spacing_larger_than_geometry);
    tcase_add_test(combinations, inlet_outside_the_domain);
    tcase_add_test(combinations, scene_too_large_for_the_machine);
    tcase_add_test(combinations, scene_needs_more_memory_than_the_machine);
    suite_add_tcase(s, combinations);
    return test_run_suite(s);
}
