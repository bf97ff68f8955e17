/* Third-party plugins built outside the tree: install Sluice into a staging
 * directory, build tools/plugin-template and the plugins of
 * tests/sdk/out_of_tree against the installed headers with pkg-config alone,
 * load them in scenes and check their effect:
 *  - the template: in a uniform periodic box every fluid particle
 *    accelerates at exactly the configured rate;
 *  - background_eos (an equation of state with a background pressure,
 *    56 lines of code): the hydrostatic start inverts it and its pressures
 *    are p_b + rho0 g depth;
 *  - oscillating_force (a body force a sin(2 pi t / T) read at the stage
 *    time): the velocity it drives converges to the exact one at second
 *    order under the symplectic integrator, which evaluates the force at
 *    mid-step; read at the step's start it would be first order. */
#include <math.h>

#include "build_config.h"
#include "sim_util.h"

/* Installs Sluice into DIR/stage, DIR a new scratch directory. */
static char *stage(const char *tag)
{
    char *dir = test_scratch(tag), *command = NULL;
    ck_assert_ptr_nonnull(dir);
    ck_assert_int_ge(asprintf(&command,
                              "meson install -C %s --no-rebuild --quiet --destdir %s/stage "
                              ">%s/install.log 2>&1",
                              test_build_dir(), dir, dir),
                     0);
    ck_assert_msg(system(command) == 0, "meson install failed: see %s/install.log", dir);
    free(command);
    return dir;
}

/* Installs Sluice into DIR/stage (DIR a new scratch directory) and builds the
 * plugins of `source` (a directory of the source tree with a Makefile) into
 * DIR with pkg-config sluice from the stage alone. */
static char *stage_and_build(const char *tag, const char *source)
{
    char *dir = stage(tag), *command = NULL;
    ck_assert_int_ge(asprintf(&command,
                              "pc=$(dirname $(find %s/stage -name sluice.pc | head -n 1)) && "
                              "PKG_CONFIG_PATH=$pc make -s -C %s/%s OUT=%s >%s/make.log 2>&1",
                              dir, test_source_dir(), source, dir, dir),
                     0);
    ck_assert_msg(system(command) == 0, "building %s failed: see %s/make.log", source, dir);
    free(command);
    return dir;
}

START_TEST(template_plugin_builds_loads_and_acts)
{
    /* 1-2. install into a staging directory, build the template with
     * pkg-config pointing at the staged .pc */
    char *dir = stage_and_build("outoftree", "tools/plugin-template");
    char *command = NULL, *output = NULL;
    /* the build must not have used the source tree's headers: check the flags */
    ck_assert_int_ge(asprintf(&command,
                              "pc=$(dirname $(find %s/stage -name sluice.pc | head -n 1)) && "
                              "PKG_CONFIG_PATH=$pc pkg-config --cflags sluice | grep -q %s/stage",
                              dir, dir),
                     0);
    ck_assert_msg(system(command) == 0, "pkg-config does not point into the installed tree");
    free(command);
    /* out-of-tree plugins get the in-tree plugins' flags and libm */
    ck_assert_int_ge(asprintf(&command,
                              "pc=$(dirname $(find %s/stage -name sluice.pc | head -n 1)) && "
                              "PKG_CONFIG_PATH=$pc pkg-config --cflags sluice | "
                              "grep -q -e '-fopenmp-simd.*-fno-trapping-math' && "
                              "PKG_CONFIG_PATH=$pc pkg-config --libs sluice | grep -q -e '-lm'",
                              dir),
                     0);
    ck_assert_msg(system(command) == 0, "pkg-config sluice lacks the plugin flags or -lm");
    free(command);
    /* every installed SDK header compiles on its own with the package's flags */
    ck_assert_int_ge(asprintf(&command,
                              "pc=$(dirname $(find %s/stage -name sluice.pc | head -n 1)) && "
                              "inc=$(dirname $(find %s/stage -name plugin_util.h | head -n 1)) && "
                              "for h in $inc/*.h; do echo \"#include <sluice/${h##*/}>\" | "
                              "${CC:-cc} $(PKG_CONFIG_PATH=$pc pkg-config --cflags sluice) "
                              "-Wall -Wextra -Werror -x c -c -o /dev/null - || exit 1; "
                              "done >%s/headers.log 2>&1",
                              dir, dir, dir),
                     0);
    ck_assert_msg(system(command) == 0,
                  "an installed header does not compile alone: see %s/headers.log", dir);
    free(command);
    /* 3. a scene that loads it */
    char *yaml = NULL;
    ck_assert_int_ge(asprintf(&yaml,
                              "dimensions: 2\n"
                              "particles: {spacing: 0.05}\n"
                              "time: {end: 0.2}\n"
                              "domain: {min: [0, 0], max: [1, 1], periodic: xy}\n"
                              "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 1]}]}\n"
                              "plugin_path: %s\n"
                              "plugins:\n"
                              "  wendland_c2: {}\n"
                              "  tait: {speed_of_sound: 10}\n"
                              "  continuity: {}\n"
                              "  pressure_gradient: {}\n"
                              "  uniform_acceleration: {acceleration: [0.5, -0.25]}\n"
                              "  time_step: {}\n"
                              "  symplectic: {}\n",
                              dir),
                     0);
    sluice_sim *sim = test_load("outoftree-scene", yaml, NULL, 0);
    /* an output directory for run.json, which names each plugin's file */
    char *run = NULL;
    ck_assert_int_ge(asprintf(&run, "%s/run", dir), 0);
    ck_assert_int_eq(sluice_sim_begin(sim, run), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < 0.2 - 1e-12)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *u = test_column(sim, "velocity", 0);
    const sluice_real *w = test_column(sim, "velocity", 1);
    double t = sluice_sim_time(sim);
    for (sluice_index i = 0; i < v->count; i++) {
        ck_assert_msg(fabs(u[i] - 0.5 * t) < 1e-9 && fabs(w[i] + 0.25 * t) < 1e-9,
                      "particle %u: velocity (%g, %g), expected (%g, %g)", i, u[i], w[i], 0.5 * t,
                      -0.25 * t);
    }
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    /* run.json's plugins: {"component": ..., "instance": ..., "library": ...,
     * "version": ..., "path": ...}, one object each */
    char *json_path = NULL;
    ck_assert_int_ge(asprintf(&json_path, "%s/run.json", run), 0);
    char *json = test_read_file(json_path);
    ck_assert_msg(json != NULL, "no %s", json_path);
    const char *entry = strstr(json, "{\"component\": \"uniform_acceleration\"");
    ck_assert_msg(entry != NULL, "run.json lists no uniform_acceleration");
    char *object = strndup(entry, strcspn(entry, "}"));
    const char *path = strstr(object, "\"path\": ");
    ck_assert_msg(path != NULL && strstr(path, dir) != NULL,
                  "the plugin must come from the out-of-tree build: %s", object);
    free(object);
    free(json);
    free(json_path);
    free(run);
    free(yaml);
    free(output);
    free(dir);
}
END_TEST

START_TEST(background_eos_hydrostatic)
{
    char *dir = stage_and_build("outoftree-eos", "tests/sdk/out_of_tree");
    const double rho0 = 1000, c0 = 30, pb = 5000, g = 9.81, H = 1.0;
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.05}\n"
             "time: {end: 1.0, max_step: 0.001}\n"
             "domain: {min: [-1, -1], max: [2, 2]}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 1]}]}\n"
             "initial: {density: hydrostatic}\n"
             "plugin_path: %s\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  background_eos: {speed_of_sound: %g, background_pressure: %g}\n"
             "  gravity: {acceleration: [0, %g]}\n"
             "  symplectic: {}\n",
             dir, c0, pb, -g);
    sluice_sim *sim = test_load("outoftree-eos-scene", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    /* the hydrostatic start went through the plugin's inverse */
    const sluice_real *rho = test_column(sim, "density", 0);
    for (sluice_index i = 0; i < v->count; i++) {
        const double expected = rho0 + rho0 * g * (H - v->position[1][i]) / (c0 * c0);
        ck_assert_msg(fabs(rho[i] - expected) <= 1e-12 * rho0, "rho(y = %g) = %.15g, expected %.15g",
                      v->position[1][i], rho[i], expected);
    }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    v = sluice_sim_view(sim);
    const sluice_real *p = test_column(sim, "pressure", 0);
    for (sluice_index i = 0; i < v->count; i++) {
        const double expected = pb + rho0 * g * (H - v->position[1][i]);
        ck_assert_msg(fabs(p[i] - expected) <= 1e-9 * rho0 * g * H, "p(y = %g) = %.12g, expected %.12g",
                      v->position[1][i], p[i], expected);
    }
    sluice_sim_free(sim);
    free(dir);
}
END_TEST

/* |u - u_exact| at t = T/4 with steps of dt, in a uniform periodic box. */
static double oscillation_error(const char *dir, double dt)
{
    const double amplitude = 1.0, period = 0.2, end = period / 4;
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.1}\n"
             "time: {end: %.17g, max_step: %.17g}\n"
             "domain: {min: [0, 0], max: [1, 1], periodic: xy}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 1]}]}\n"
             "plugin_path: %s\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  background_eos: {speed_of_sound: 10}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  oscillating_force: {amplitude: [%g, 0], period: %g}\n"
             "  symplectic: {}\n",
             end, dt, dir, amplitude, period);
    sluice_sim *sim = test_load("outoftree-force-scene", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < end - 1e-12)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
    /* u(t) = A T / (2 pi) (1 - cos(2 pi t / T)): at T/4, A T / (2 pi) */
    const double exact = amplitude * period / (2 * 3.14159265358979323846);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *u = test_column(sim, "velocity", 0);
    double error = 0;
    for (sluice_index i = 0; i < v->count; i++)
        error = fmax(error, fabs((double)u[i] - exact));
    sluice_sim_free(sim);
    return error;
}

START_TEST(body_force_reads_the_stage_time)
{
    char *dir = stage_and_build("outoftree-force", "tests/sdk/out_of_tree");
    const double dt[3] = {0.01, 0.005, 0.0025};
    double error[3];
    for (int k = 0; k < 3; k++)
        error[k] = oscillation_error(dir, dt[k]);
    /* the midpoint rule of the symplectic integrator: error ~ dt^2 */
    for (int k = 0; k < 2; k++) {
        const double order = log2(error[k] / error[k + 1]);
        fprintf(stderr, "oscillating force: dt %g -> %g, error %.3e -> %.3e, order %.3f\n", dt[k],
                dt[k + 1], error[k], error[k + 1], order);
        ck_assert_msg(order > 1.8 && order < 2.2,
                      "observed order %.3f between dt = %g and %g (errors %.3e, %.3e): the "
                      "force is not evaluated at the stage time",
                      order, dt[k], dt[k + 1], error[k], error[k + 1]);
    }
    free(dir);
}
END_TEST

/* The installed tree on its own (docs/install.md): everything installed, then
 * with an environment that names nothing but the installed programs (no
 * SLUICE_PLUGIN_PATH, no build directory, run outside the source tree):
 * check every installed scene, run the default one briefly, probe and
 * measure it, load it with the installed Python package (when Debian's
 * numpy, h5py and PyYAML are there, as the README installs them), inspect,
 * the help of sluice-analyze, two studies' dry runs, pkg-config sluice. The run's plugins must come from the installed tree. */
static const char installed_script[] =
    "set -eu\n"
    "src=$1 stage=$2 version=$3\n"
    "bin=$(dirname \"$(find \"$stage\" -path '*/bin/sluice' -type f)\")\n"
    "prefix=$(dirname \"$bin\")\n"
    "data=$prefix/share/sluice doc=$prefix/share/doc/sluice\n"
    "for p in sluice sluice-analyze sluice-study sluice-probe; do\n"
    "  test -x \"$bin/$p\" || { echo \"not installed: bin/$p\"; exit 1; }; done\n"
    "for h in \"$src\"/core/include/sluice/*.h; do\n"
    "  test -f \"$prefix/include/sluice/${h##*/}\" || { echo \"no header ${h##*/}\"; exit 1; }\n"
    "done\n"
    /* every file of configs/, the reference data, docs/ and the template */
    "same() { (cd \"$1\" && find . -type f | sort) >\"$stage/a\"; "
    "(cd \"$2\" && find . -type f | sort) >\"$stage/b\"; "
    "diff \"$stage/a\" \"$stage/b\" || { echo \"$2 differs from $1\"; exit 1; }; }\n"
    "same \"$src/configs\" \"$data/configs\"\n"
    "same \"$src/tests/scenes/data\" \"$data/tests/scenes/data\"\n"
    "same \"$src/tools/plugin-template\" \"$data/tools/plugin-template\"\n"
    "same \"$src/docs\" \"$doc\"\n"
    "test -x \"$data/tools/peers/pysph-dam-break\" || { echo \"no tools/peers\"; exit 1; }\n"
    /* the man pages, with every command's section */
    "man=$prefix/share/man/man1\n"
    "grep -q '^\\.SH \"sluice run\"' \"$man/sluice.1\" && grep -q '^\\.SH \"sluice study\"' "
    "\"$man/sluice.1\" && grep -q 'analyze conjugate\"' \"$man/sluice-analyze.1\" && "
    "grep -q dry \"$man/sluice-study.1\" && grep -q plane \"$man/sluice-probe.1\" || "
    "{ echo \"man pages missing\"; exit 1; }\n"
    /* every relative reference of the installed studies resolves */
    "cd \"$data/configs/studies\"\n"
    "for r in $(grep -ho '{study_dir}/[^ \"]*' *.yaml | sort -u) "
    "$(grep -ho 'scene: *\\.\\./[^ ,}]*' *.yaml | sed 's/scene: *//' | sort -u); do\n"
    "  test -e \"${r#\\{study_dir\\}/}\" || { echo \"unresolved in studies: $r\"; exit 1; }; done\n"
    /* the installed scenes need no plugin_path of the source tree's */
    "if grep -l '^plugin_path:' \"$data\"/configs/*.yaml; then\n"
    "  echo 'an installed scene sets plugin_path'; exit 1; fi\n"
    "cd \"$stage/..\"\n"
    /* the Python package, and a script of it for the run below */
    "pysite=$(dirname \"$(dirname \"$(find \"$stage\" -path '*/sluice/__init__.py' | head -1)\")\")\n"
    "test -f \"$pysite/sluice/run.py\" || { echo 'the Python package is not installed'; exit 1; }\n"
    "printf 'import sluice\\nr = sluice.load(\"run\")\\nassert r.info[\"status\"] == \"complete\"\\n"
    "print(r.table(\"sections\").names[1], len(r.snapshots))\\n' >check.py\n"
    "pc=$(dirname \"$(find \"$stage\" -name sluice.pc)\")\n"
    "exec env -i PATH=\"$bin:/usr/bin:/bin\" HOME=\"$PWD\" PKG_CONFIG_PATH=\"$pc\" "
    "OMP_NUM_THREADS=2 sh -eu -c '\n"
    "  data=$1 version=$2 stage=$3\n"
    "  for scene in \"$data\"/configs/*.yaml; do sluice check \"$scene\" >/dev/null; done\n"
    "  sluice run \"$data/configs/hydraulic_jump_jonsson2016.yaml\" --set time.end=0.02 "
    "--out run\n"
    "  test -s run/sections.csv && test -s run/run.json\n"
    "  if grep \"\\\"path\\\": \" run/run.json | grep -v \"\\\"$stage/\"; then\n"
    "    echo \"a plugin of the run is not from the installed tree\"; exit 1; fi\n"
    "  sluice inspect >inspect.txt && grep -q section_gauge inspect.txt\n"
    "  sluice-analyze --help >help.txt && grep -q conjugate help.txt\n"
    "  sluice run --help >help.txt && grep -q -e --out help.txt\n"
    "  sluice study --help >help.txt && grep -q -e --dry-run help.txt\n"
    "  sluice probe run --fields pressure --points 0.5,0.01 --times last --out probe.csv\n"
    "  grep -q '^0.02,0,0.5,0.01,' probe.csv\n"
    "  sluice-analyze conjugate run --x 1.0 --no-plot >conjugate.txt\n"
    "  grep -q d2_Belanger conjugate.txt\n"
    "  sluice study \"$data/configs/studies/dam_break_martin_moyce.yaml\" "
    "\"$data/configs/studies/abrupt_drop.yaml\" --dry-run --out study >study.txt\n"
    "  grep -q external study.txt\n"
    "  test \"$(pkg-config --modversion sluice)\" = \"$version\"\n"
    "  test -d \"$(pkg-config --variable=plugindir sluice)\"\n"
    "  test -f \"$(pkg-config --variable=includedir sluice)/sluice/plugin_util.h\"\n"
    "  if /usr/bin/python3 -c \"import numpy, h5py, yaml\" 2>/dev/null; then\n"
    "    PYTHONPATH=\"$4\" /usr/bin/python3 check.py >python.txt && grep -q \"^d_x0 2$\" python.txt\n"
    "  fi\n"
    "' sh \"$data\" \"$version\" \"$stage\" \"$pysite\"\n";

START_TEST(installed_tree_runs_alone)
{
    char *dir = stage("installed"), *command = NULL;
    char *script = test_write_file(dir, "installed.sh", installed_script);
    ck_assert_ptr_nonnull(script);
    ck_assert_int_ge(asprintf(&command, "sh %s %s %s/stage %s >%s/installed.log 2>&1", script,
                              test_source_dir(), dir, SLUICE_VERSION, dir),
                     0);
    ck_assert_msg(system(command) == 0, "the installed tree failed: see %s/installed.log", dir);
    free(command);
    free(script);
    free(dir);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("out of tree");
    TCase *tc = tcase_create("template");
    tcase_set_timeout(tc, 300);
    tcase_add_test(tc, template_plugin_builds_loads_and_acts);
    tcase_add_test(tc, background_eos_hydrostatic);
    tcase_add_test(tc, body_force_reads_the_stage_time);
    suite_add_tcase(s, tc);
    TCase *installed = tcase_create("installed");
    tcase_set_timeout(installed, 300);
    tcase_add_test(installed, installed_tree_runs_alone);
    suite_add_tcase(s, installed);
    return test_run_suite(s);
}
