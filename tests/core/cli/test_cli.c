/* The sluice program's reports on stderr (docs/reliability.md, "Progress and
 * logs"): in a batch log (stderr not a terminal) timestamped plain lines at
 * the start, every --log-every s and at the end, never a carriage return;
 * --progress forces the terminal's line; --quiet prints nothing for a run
 * that succeeds (not even the plugins' notes while loading); --verbose adds
 * the provenance and the plugins; contradictory or bad options exit 2. */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

static const char scene_text[] = "dimensions: 2\n"
                                 "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
                                 "time: {end: 0.2}\n"
                                 "domain: {min: [-0.2, -0.2], max: [1.2, 1.2]}\n"
                                 "geometry:\n"
                                 "  fluid: [{shape: box, min: [0, 0], max: [1.0, 0.5]}]\n"
                                 "  walls: [{shape: tank, min: [0, 0], max: [1.0, 1.0]}]\n"
                                 "plugins:\n"
                                 "  wendland_c2: {}\n"
                                 "  tait: {speed_of_sound: 22.1}\n"
                                 "  continuity: {}\n"
                                 "  pressure_gradient: {}\n"
                                 "  gravity: {acceleration: [0, -9.81]}\n"
                                 "  penalty_contact: {}\n"
                                 "  time_step: {}\n"
                                 "  symplectic: {}\n";

/* Runs the scene with `options`, stderr (and stdout) captured through a
 * pipe: not a terminal. */
static int run(const char *options, char **output)
{
    char *dir = test_scratch("cli");
    ck_assert_ptr_nonnull(dir);
    char *scene = test_write_file(dir, "scene.yaml", scene_text);
    char *args = NULL;
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/run --threads 1 %s", scene, dir, options),
                     0);
    const int status = test_sluice(args, output);
    free(args);
    free(scene);
    free(dir);
    return status;
}

/* 1 when the line begins with YYYY-MM-DDTHH:MM:SSZ and a space. */
static int stamped(const char *line)
{
    int y, mo, d, h, mi, s;
    char z = 0, space = 0;
    return sscanf(line, "%4d-%2d-%2dT%2d:%2d:%2d%c%c", &y, &mo, &d, &h, &mi, &s, &z, &space) ==
               8 &&
           z == 'Z' && space == ' ' && y >= 2026 && mo >= 1 && mo <= 12;
}

START_TEST(batch_log)
{
    char *out = NULL;
    ck_assert_int_eq(run("--log-every 0.01", &out), 0);
    ck_assert_msg(!strchr(out, '\r'), "a carriage return in a batch log");
    int lines = 0, progress = 0, notes = 0;
    for (char *save = NULL, *line = strtok_r(out, "\n", &save); line;
         line = strtok_r(NULL, "\n", &save)) {
        /* every line, the plugins' notes while the scene loads included */
        ck_assert_msg(stamped(line), "line without a timestamp: %s", line);
        notes += strstr(line, "sluice: penalty_contact: k =") != NULL;
        lines++;
        progress += strstr(line, "steps/s") && strstr(line, "ETA") && strstr(line, " t ");
    }
    free(out);
    /* the start, the first step, the last step and the end at least */
    ck_assert_int_ge(lines, 4);
    ck_assert_int_ge(progress, 2);
    ck_assert_int_eq(notes, 1);
}
END_TEST

START_TEST(terminal_line_on_request)
{
    char *out = NULL;
    ck_assert_int_eq(run("--progress", &out), 0);
    ck_assert_msg(strchr(out, '\r'), "--progress wrote no terminal line: %s", out);
    free(out);
}
END_TEST

START_TEST(quiet_and_verbose)
{
    char *out = NULL;
    ck_assert_int_eq(run("--quiet", &out), 0);
    ck_assert_msg(out[0] == '\0', "--quiet printed: %s", out);
    free(out);
    ck_assert_int_eq(run("--verbose --no-progress", &out), 0);
    ck_assert_msg(strstr(out, "sluice: git_revision: ") && strstr(out, "sluice: plugin tait") &&
                      strstr(out, "sluice: kernel: wendland_c2") && strstr(out, "sluice: completed"),
                  "%s", out);
    free(out);
    static const char *const bad[] = {"-q -v", "--log-every 0", "--log-every x"};
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        ck_assert_int_eq(run(bad[k], &out), 2);
        ck_assert_int_eq(test_count_lines(out, "error"), 1);
        free(out);
    }
}
END_TEST

int main(void)
{
    Suite *s = suite_create("cli");
    TCase *tc = tcase_create("cli");
    tcase_set_timeout(tc, 200);
    tcase_add_test(tc, batch_log);
    tcase_add_test(tc, terminal_line_on_request);
    tcase_add_test(tc, quiet_and_verbose);
    suite_add_tcase(s, tc);
    return test_run_suite(s);
}
