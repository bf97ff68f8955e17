/* A third-party plugin built outside the tree: install Sluice into a staging
 * directory, build tools/plugin-template against the installed headers via
 * pkg-config, load it in a scene, and check its effect: in a uniform periodic
 * box every fluid particle accelerates at exactly the configured rate. */
#include <math.h>

#include "sim_util.h"

START_TEST(template_plugin_builds_loads_and_acts)
{
    char *dir = test_scratch("outoftree");
    char *command = NULL, *output = NULL;
    /* 1. install into a staging directory */
    ck_assert_int_ge(asprintf(&command,
                              "meson install -C %s --no-rebuild --quiet --destdir %s/stage "
                              ">%s/install.log 2>&1",
                              test_build_dir(), dir, dir),
                     0);
    ck_assert_msg(system(command) == 0, "meson install failed: see %s/install.log", dir);
    free(command);
    /* 2. build the template with pkg-config pointing at the staged .pc */
    ck_assert_int_ge(asprintf(&command,
                              "pc=$(dirname $(find %s/stage -name sluice.pc | head -n 1)) && "
                              "PKG_CONFIG_PATH=$pc make -s -C %s/tools/plugin-template OUT=%s "
                              ">%s/make.log 2>&1",
                              dir, test_source_dir(), dir, dir),
                     0);
    ck_assert_msg(system(command) == 0, "building the template failed: see %s/make.log", dir);
    free(command);
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
    /* run.json's plugins: {"component": ..., "library": ..., "version": ...,
     * "path": ...}, one object each */
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

int main(void)
{
    Suite *s = suite_create("out of tree");
    TCase *tc = tcase_create("template");
    tcase_set_timeout(tc, 300);
    tcase_add_test(tc, template_plugin_builds_loads_and_acts);
    suite_add_tcase(s, tc);
    return test_run_suite(s);
}
