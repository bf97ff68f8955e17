/* sluice study (tools/study, docs/studies.md): a two-axis study on a tiny
 * still tank runs, writes its table, orders and plots, and resumes without
 * redoing a run; an unstable run is recorded, not fatal; bad study files are
 * refused with file:line:column before anything runs. */
#include <check.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "test_util.h"

/* Runs `sluice study ARGS` with stderr and stdout in *output. */
static int study(const char *args, char **output)
{
    return test_sluice(args, output);
}

/* The field of the row whose first field is `run`, in the column `column`. */
static char *csv_field(const char *csv, const char *run, const char *column)
{
    char *copy = strdup(csv);
    char *save = NULL, *line = strtok_r(copy, "\n", &save);
    int index = -1, i = 0;
    char *header = strdup(line);
    for (char *s2 = NULL, *f = strtok_r(header, ",", &s2); f; f = strtok_r(NULL, ",", &s2), i++)
        if (strcmp(f, column) == 0)
            index = i;
    free(header);
    char *result = NULL;
    while (index >= 0 && (line = strtok_r(NULL, "\n", &save))) {
        char *fields[256];
        int n = 0;
        char *row = strdup(line);
        for (char *s3 = NULL, *f = strtok_r(row, ",", &s3); f && n < 256;
             f = strtok_r(NULL, ",", &s3))
            fields[n++] = f;
        if (n > index && strcmp(fields[0], run) == 0)
            result = strdup(fields[index]);
        free(row);
        if (result)
            break;
    }
    free(copy);
    return result;
}

static double csv_number(const char *csv, const char *run, const char *column)
{
    char *field = csv_field(csv, run, column);
    double v = field ? strtod(field, NULL) : NAN;
    free(field);
    return v;
}

/* The mean of a column of a gauge CSV over t in [from, to], computed here
 * independently of the study tool. */
static double column_mean(const char *path, const char *column, double from, double to)
{
    FILE *f = fopen(path, "r");
    ck_assert_ptr_nonnull(f);
    char line[8192];
    ck_assert_ptr_nonnull(fgets(line, sizeof line, f));
    int index = -1, i = 0;
    for (char *s = NULL, *c = strtok_r(line, ",\n", &s); c; c = strtok_r(NULL, ",\n", &s), i++)
        if (strcmp(c, column) == 0)
            index = i;
    ck_assert_int_ge(index, 1);
    double sum = 0;
    int count = 0;
    while (fgets(line, sizeof line, f)) {
        double t = strtod(line, NULL), v = NAN;
        char *p = line;
        for (int k = 0; k < index && p; k++)
            p = strchr(p, ',') ? strchr(p, ',') + 1 : NULL;
        if (p)
            v = strtod(p, NULL);
        if (t >= from && t <= to && isfinite(v)) {
            sum += v;
            count++;
        }
    }
    fclose(f);
    ck_assert_int_gt(count, 0);
    return sum / count;
}

static long long mtime_ns(const char *path)
{
    struct stat st;
    ck_assert_int_eq(stat(path, &st), 0);
    return (long long)st.st_mtim.tv_sec * 1000000000LL + st.st_mtim.tv_nsec;
}

static int is_png(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    unsigned char magic[8] = {0};
    size_t n = fread(magic, 1, 8, f);
    fclose(f);
    return n == 8 && memcmp(magic, "\x89PNG\r\n\x1a\n", 8) == 0;
}

/* Writes DIR/NAME from `format` with the still tank's scene path for its %s;
 * returns the file's path. */
static char *write_study(const char *dir, const char *name, const char *format)
{
    char *scene = test_config("still_water_2d.yaml");
    char *text = NULL;
    ck_assert_int_ge(asprintf(&text, format, scene), 0);
    char *file = test_write_file(dir, name, text);
    free(text);
    free(scene);
    return file;
}

/* The still tank (H = 0.5 m) briefly, with a floor sensor; wall schemes by
 * swap, three spacings. */
static const char *two_axis_study =
    "title: tiny still tank\n"
    "scene: %s\n"
    "set:\n"
    "  time.end: 0.04\n"
    "  plugins.hdf5.interval: 0.04\n"
    "  plugins.floor: {plugin: wall_pressure, positions: [[0.5, 0]], names: p, "
    "size: [0.4], "
    "interval: 0.005}\n"
    "jobs: 2\n"
    "axes:\n"
    "  - name: wall\n"
    "    values:\n"
    "      dbc: {}\n"
    "      mdbc: {swap: {dbc: mdbc}}\n"
    "  - name: dx\n"
    "    spacing: [0.05, 0.025, 0.0125]\n"
    "measures:\n"
    "  - {name: kept, run: particles_final}\n"
    "  - {name: h, unit: m, run: smoothing_length, reference: 0}\n"
    "  - {name: p_floor, unit: Pa, gauge: wall_pressure.csv, column: p_Pa, "
    "from: 0.02, "
    "reference: 4905}\n";

START_TEST(two_axis_study_runs_resumes_and_reports)
{
    char *dir = test_scratch("study");
    char *file = write_study(dir, "tiny.yaml", two_axis_study);
    char *args = NULL, *out = NULL;
    ck_assert_int_ge(asprintf(&args, "study %s --out %s/out", file, dir), 0);
    char *output = NULL;
    int status = study(args, &output);
    fprintf(stderr, "%s", output);
    ck_assert_int_eq(status, 0);
    /* progress for the whole study */
    ck_assert_ptr_nonnull(
        strstr(output, "study: 6/6 runs done (0 failed, 0 running, 0 from before)"));
    free(output);

    ck_assert_int_ge(asprintf(&out, "%s/out/study.csv", dir), 0);
    char *csv = test_read_file(out);
    ck_assert_ptr_nonnull(csv);
    ck_assert_int_eq(test_count_lines(csv, ",complete,"), 6);
    static const char *const runs[] = {"dbc_0.05",  "dbc_0.025",  "dbc_0.0125",
                                       "mdbc_0.05", "mdbc_0.025", "mdbc_0.0125"};
    static const double spacings[] = {0.05, 0.025, 0.0125};
    for (int i = 0; i < 6; i++) {
        /* a still tank loses no particle */
        char *json_path = NULL;
        ck_assert_int_ge(asprintf(&json_path, "%s/out/runs/%s/run.json", dir, runs[i]), 0);
        char *json = test_read_file(json_path);
        ck_assert_ptr_nonnull(json);
        ck_assert_double_eq(csv_number(csv, runs[i], "kept"),
                            test_json_number(json, "particles_initial"));
        /* h = 1.5 dx exactly, its error against 0 absolute */
        ck_assert_double_eq_tol(csv_number(csv, runs[i], "h"), 1.5 * spacings[i % 3], 1e-12);
        ck_assert_double_eq_tol(csv_number(csv, runs[i], "h_error"), 1.5 * spacings[i % 3], 1e-12);
        /* the reduction is the mean of the gauge column over the window */
        char *gauge = NULL;
        ck_assert_int_ge(asprintf(&gauge, "%s/out/runs/%s/wall_pressure.csv", dir, runs[i]), 0);
        double mean = column_mean(gauge, "p_Pa", 0.02, INFINITY);
        ck_assert_double_eq_tol(csv_number(csv, runs[i], "p_floor"), mean, 1e-6 * fabs(mean));
        ck_assert_double_eq_tol(csv_number(csv, runs[i], "p_floor_error"), mean / 4905 - 1, 1e-8);
        /* CPU time and the rate are measured */
        ck_assert(csv_number(csv, runs[i], "cpu_s") > 0);
        ck_assert(csv_number(csv, runs[i], "particle_steps_per_cpu_s") > 0);
        free(gauge);
        free(json);
        free(json_path);
    }
    /* orders: h = 1.5 dx converges to 0 at exactly first order */
    free(out);
    ck_assert_int_ge(asprintf(&out, "%s/out/orders.csv", dir), 0);
    char *orders = test_read_file(out);
    ck_assert_ptr_nonnull(orders);
    ck_assert_ptr_nonnull(strstr(orders, "dbc,h,0.05;0.025;0.0125,0.075;0.0375;0.01875,"
                                         "0.075;0.0375;0.01875,1.00;1.00,1,0\n"));
    ck_assert_ptr_nonnull(strstr(orders, "mdbc,h,"));
    free(orders);
    free(out);
    ck_assert_int_ge(asprintf(&out, "%s/out/study.md", dir), 0);
    char *md = test_read_file(out);
    ck_assert_ptr_nonnull(md);
    ck_assert_ptr_nonnull(strstr(md, "| dbc_0.0125 | dbc | 0.0125 | complete |"));
    ck_assert_ptr_nonnull(strstr(md, "## Observed orders of convergence"));
    free(md);
    static const char *const plots[] = {"p_floor_cost.png", "p_floor_spacing.png", "h_cost.png",
                                        "h_spacing.png"};
    for (int i = 0; i < 4; i++) {
        free(out);
        ck_assert_int_ge(asprintf(&out, "%s/out/plots/%s", dir, plots[i]), 0);
        ck_assert_msg(is_png(out), "%s is not a PNG (is gnuplot installed?)", out);
    }

    /* the same command again: nothing is redone */
    free(out);
    ck_assert_int_ge(asprintf(&out, "%s/out/runs/mdbc_0.0125/run.json", dir), 0);
    long long before = mtime_ns(out);
    status = study(args, &output);
    ck_assert_int_eq(status, 0);
    ck_assert_ptr_nonnull(strstr(output, "6/6 runs done (0 failed, 0 running, 6 from before)"));
    ck_assert_int_eq(mtime_ns(out), before);
    free(output);
    /* a run whose record is gone is run again, the others not */
    char *record = NULL;
    ck_assert_int_ge(asprintf(&record, "%s/out/records/dbc_0.05.txt", dir), 0);
    ck_assert_int_eq(unlink(record), 0);
    status = study(args, &output);
    ck_assert_int_eq(status, 0);
    ck_assert_ptr_nonnull(strstr(output, "6/6 runs done (0 failed, 0 running, 5 from before)"));
    ck_assert_int_eq(mtime_ns(out), before);
    char *again = test_read_file(record);
    ck_assert_ptr_nonnull(again);
    ck_assert_ptr_nonnull(strstr(again, "exit: 0\n"));
    free(again);
    free(record);
    free(output);
    free(csv);
    free(out);
    free(args);
    free(file);
    free(dir);
}
END_TEST

START_TEST(unstable_run_is_recorded_not_fatal)
{
    /* c0 = 1 m/s in a 0.5 m deep tank: the density leaves the watchdog's band in
     * the first step (rho g H / c0^2 = 4.9 rho0) */
    char *dir = test_scratch("study-unstable");
    char *file = write_study(dir, "c0.yaml",
                             "scene: %s\n"
                             "set: {time.end: 0.02, particles.spacing: 0.05}\n"
                             "axes:\n"
                             "  - {name: c0, parameter: plugins.tait.speed_of_sound, values: "
                             "[22.1, 1]}\n"
                             "  - {name: walls, values: {dbc: {}}}\n"
                             "measures:\n"
                             "  - {name: steps, run: steps}\n");
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "study %s --out %s/out", file, dir), 0);
    ck_assert_int_eq(study(args, &output), 0);
    ck_assert_ptr_nonnull(strstr(output, "run 1_dbc failed (exit 3: step 1"));
    free(output);
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/out/study.csv", dir), 0);
    char *csv = test_read_file(path);
    ck_assert_ptr_nonnull(csv);
    char *state = csv_field(csv, "1_dbc", "status");
    ck_assert_str_eq(state, "unstable");
    free(state);
    state = csv_field(csv, "22.1_dbc", "status");
    ck_assert_str_eq(state, "complete");
    free(state);
    ck_assert(csv_number(csv, "22.1_dbc", "steps") > 0);
    ck_assert(isnan(csv_number(csv, "1_dbc", "steps"))); /* no measure of a failed run */
    /* the status map: the first axis against the second, the unstable run
     * with the time it stopped at (after its first step, before the end) */
    char *md_path = NULL;
    ck_assert_int_ge(asprintf(&md_path, "%s/out/study.md", dir), 0);
    char *md = test_read_file(md_path);
    ck_assert_ptr_nonnull(md);
    ck_assert_msg(strstr(md, "| c0 \\ walls | dbc |\n|---|---|\n| 22.1 | complete, "), "%s", md);
    const char *stopped = strstr(md, "\n| 1 | unstable at ");
    ck_assert_msg(stopped, "%s", md);
    double t_stop = strtod(stopped + strlen("\n| 1 | unstable at "), NULL);
    ck_assert_msg(t_stop > 0 && t_stop < 0.02, "%g", t_stop);
    free(md);
    free(md_path);
    /* the plot leaves out the run without a value, title and all (a block
     * without data would shift gnuplot's index against the titles) */
    char *gp_path = NULL;
    ck_assert_int_ge(asprintf(&gp_path, "%s/out/plots/steps.gp", dir), 0);
    char *gp = test_read_file(gp_path);
    ck_assert_ptr_nonnull(gp);
    ck_assert_msg(strstr(gp, "\ntitles = '22.1/dbc'\n"), "%s", gp);
    free(gp);
    free(gp_path);
    /* a failed run is kept as failed; --retry-failed runs it again */
    ck_assert_int_eq(study(args, &output), 0);
    ck_assert_ptr_nonnull(strstr(output, "2/2 runs done (1 failed, 0 running, 2 from before)"));
    free(output);
    free(csv);
    free(path);
    free(args);
    free(file);
    free(dir);
}
END_TEST

/* SIGINT to the study: the running run stops after a whole step with a
 * checkpoint, the study exits 5; the same command continues that run from
 * its checkpoint (run.json: restarted_at_step > 0) and completes it. */
START_TEST(interrupted_study_continues_from_the_checkpoint)
{
    char *dir = test_scratch("study-interrupt");
    char *file = write_study(dir, "i.yaml",
                             "scene: %s\n"
                             "set: {time.end: 1.5, plugins.hdf5.interval: 0.5}\n"
                             "axes:\n"
                             "  - {name: dx, spacing: [0.025]}\n"
                             "measures:\n"
                             "  - {name: kept, run: particles_final}\n");
    char *out = NULL, *log = NULL, *program = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", dir), 0);
    ck_assert_int_ge(asprintf(&log, "%s/out/logs/0.025.log", dir), 0);
    ck_assert_int_ge(asprintf(&program, "%s/sluice", test_build_dir()), 0);
    pid_t pid = fork();
    ck_assert_int_ge(pid, 0);
    if (pid == 0) {
        int null = open("/dev/null", O_WRONLY);
        dup2(null, STDERR_FILENO);
        execl(program, program, "study", file, "--out", out, (char *)NULL);
        _exit(127);
    }
    /* wait until the run has taken steps (its progress line), then interrupt */
    double t = 0;
    for (int k = 0; k < 600 && t < 0.05; k++) {
        usleep(100000);
        char *text_log = test_read_file(log);
        for (char *p = text_log; p && (p = strstr(p, "  t ")); p += 4)
            sscanf(p, "  t %lf", &t);
        free(text_log);
    }
    ck_assert_double_gt(t, 0.0);
    kill(pid, SIGINT);
    int status = 0;
    ck_assert_int_eq(waitpid(pid, &status, 0), pid);
    ck_assert(WIFEXITED(status));
    ck_assert_int_eq(WEXITSTATUS(status), 5);
    char *record_path = NULL;
    ck_assert_int_ge(asprintf(&record_path, "%s/records/0.025.txt", out), 0);
    char *record = test_read_file(record_path);
    ck_assert_ptr_nonnull(record);
    ck_assert_ptr_nonnull(strstr(record, "exit: 5\n"));
    free(record);
    /* the same command: continued, completed */
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "study %s --out %s", file, out), 0);
    ck_assert_int_eq(study(args, &output), 0);
    ck_assert_ptr_nonnull(strstr(output, "1/1 runs done (0 failed, 0 running, 0 from before)"));
    free(output);
    char *json_path = NULL;
    ck_assert_int_ge(asprintf(&json_path, "%s/runs/0.025/run.json", out), 0);
    char *json = test_read_file(json_path);
    ck_assert_ptr_nonnull(json);
    ck_assert_ptr_nonnull(strstr(json, "\"status\": \"complete\""));
    ck_assert_double_gt(test_json_number(json, "restarted_at_step"), 0);
    ck_assert_double_eq(test_json_number(json, "particles_final"),
                        test_json_number(json, "particles_initial"));
    record = test_read_file(record_path);
    ck_assert_ptr_nonnull(strstr(record, "exit: 0\n"));
    free(record);
    free(json);
    free(json_path);
    free(args);
    free(record_path);
    free(program);
    free(log);
    free(out);
    free(file);
    free(dir);
}
END_TEST

/* A profile narrows an axis of edits and replaces a spacing list, adds its
 * edits after the study's; --dry-run lists the runs and their commands and
 * runs nothing; an unknown profile is refused. */
START_TEST(profiles_and_dry_run)
{
    char *dir = test_scratch("study-profile");
    char *file = write_study(dir, "p.yaml",
                             "scene: %s\n"
                             "set: {time.end: 2}\n"
                             "axes:\n"
                             "  - {name: wall, values: {dbc: {}, mdbc: {swap: {dbc: mdbc}}, "
                             "ghost: {swap: {dbc: ghost_particles}}}}\n"
                             "  - {name: dx, spacing: [0.02, 0.01]}\n"
                             "profiles:\n"
                             "  quick:\n"
                             "    set: {time.end: 0.1}\n"
                             "    axes: {wall: [ghost, dbc], dx: [0.05]}\n");
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "study %s --out %s/out --profile quick --dry-run", file, dir),
                     0);
    ck_assert_int_eq(study(args, &output), 0);
    ck_assert_ptr_nonnull(strstr(output, ": 2 runs into "));
    const char *ghost = strstr(output, "  ghost_0.05 ");
    const char *dbc = strstr(output, "  dbc_0.05 ");
    ck_assert(ghost && dbc && ghost < dbc); /* the profile's order */
    ck_assert_ptr_null(strstr(output, "mdbc_"));
    /* the study's edits, then the profile's, then the axes' */
    ck_assert_ptr_nonnull(strstr(output, "--swap dbc=ghost_particles --set time.end=2 --set "
                                         "time.end=0.1 --set particles.spacing=0.05"));
    char *out = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", dir), 0);
    ck_assert(!test_exists(out)); /* nothing run, nothing written */
    free(output);
    free(args);
    ck_assert_int_ge(asprintf(&args, "study %s --out %s/out --profile quik", file, dir), 0);
    ck_assert_int_eq(study(args, &output), 2);
    ck_assert_ptr_nonnull(strstr(output, "error: --profile 'quik': the study defines no such "
                                         "profile; did you mean 'quick'?"));
    free(output);
    free(args);
    free(out);
    free(file);
    free(dir);
}
END_TEST

/* A peer code as an axis value: an external program (here a shell script
 * standing in for one) writes its run directory; its run.json's figures and
 * files are measured like a Sluice run's, its own CPU figure replaces the
 * measured one, it is not redone on resuming; a program that is not
 * installed (`requires` fails) is skipped with a note, not fatal. */
START_TEST(external_programs_as_axis_values)
{
    char *dir = test_scratch("study-external");
    /* the peer: particles 100 / spacing, 10 steps, x = 3 * spacing */
    free(test_write_file(dir, "peer.sh",
                         "set -e\n"
                         "mkdir -p \"$1\"\n"
                         "echo run >>\"$1/../../../count\"\n"
                         "awk -v dx=\"$2\" 'BEGIN { n = 100 / dx; printf \"{\\n  \\\"status\\\": "
                         "\\\"complete\\\",\\n  \\\"steps\\\": 10,\\n  \\\"particle_steps\\\": "
                         "%.0f,\\n  \\\"cpu_seconds\\\": 2.5\\n}\\n\", 10 * n }' "
                         ">\"$1/run.json\"\n"
                         "printf 'time,x\\n0,0\\n1,%s\\n' \"$(awk -v dx=\"$2\" 'BEGIN "
                         "{ print 3 * dx }')\" >\"$1/peer.csv\"\n"));
    char *file = write_study(dir, "e.yaml",
                             "scene: %s\n"
                             "set: {time.end: 0.01, plugins.hdf5.interval: 0.01}\n"
                             "axes:\n"
                             "  - name: code\n"
                             "    values:\n"
                             "      sluice: {}\n"
                             "      peer: {external: \"sh {study_dir}/peer.sh {run_dir} "
                             "{spacing}\"}\n"
                             "      absent:\n"
                             "        external: \"sh {study_dir}/peer.sh {run_dir} {spacing}\"\n"
                             "        requires: \"echo no such program >&2; exit 3\"\n"
                             "  - {name: dx, spacing: [0.05, 0.025]}\n"
                             "measures:\n"
                             "  - {name: steps, run: steps}\n"
                             "  - {name: x, unit: m, gauge: peer.csv, column: x, reduce: max}\n");
    char *args = NULL, *output = NULL, *path = NULL;
    ck_assert_int_ge(asprintf(&args, "study %s --out %s/out", file, dir), 0);
    int status = study(args, &output);
    fprintf(stderr, "%s", output);
    ck_assert_int_eq(status, 0);
    free(output);
    ck_assert_int_ge(asprintf(&path, "%s/out/study.csv", dir), 0);
    char *csv = test_read_file(path);
    ck_assert_ptr_nonnull(csv);
    static const double spacings[] = {0.05, 0.025};
    static const char *const peers[] = {"peer_0.05", "peer_0.025"};
    static const char *const absent[] = {"absent_0.05", "absent_0.025"};
    for (int i = 0; i < 2; i++) {
        char *state = csv_field(csv, peers[i], "status");
        ck_assert_str_eq(state, "complete");
        free(state);
        ck_assert_double_eq_tol(csv_number(csv, peers[i], "steps"), 10, 1e-12);
        ck_assert_double_eq_tol(csv_number(csv, peers[i], "particles"), 100 / spacings[i], 0.5);
        ck_assert_double_eq_tol(csv_number(csv, peers[i], "cpu_s"), 2.5, 1e-9);
        ck_assert_double_eq_tol(csv_number(csv, peers[i], "x"), 3 * spacings[i], 1e-12);
        state = csv_field(csv, absent[i], "status");
        ck_assert_str_eq(state, "skipped");
        free(state);
    }
    /* Sluice's own runs beside them, without the peer's file */
    ck_assert_double_gt(csv_number(csv, "sluice_0.025", "steps"), 0);
    ck_assert(isnan(csv_number(csv, "sluice_0.025", "x")));
    free(csv);
    free(path);
    ck_assert_int_ge(asprintf(&path, "%s/out/study.md", dir), 0);
    char *md = test_read_file(path);
    ck_assert_ptr_nonnull(md);
    ck_assert_ptr_nonnull(strstr(md, "- absent_0.05: skipped, not installed here: `echo no such "
                                     "program >&2; exit 3` gave exit 3: no such program\n"));
    free(md);
    free(path);
    /* resumed: nothing is run again */
    ck_assert_int_eq(study(args, &output), 0);
    ck_assert_ptr_nonnull(strstr(output, "from before, some skipped)"));
    free(output);
    ck_assert_int_ge(asprintf(&path, "%s/count", dir), 0);
    char *count = test_read_file(path);
    ck_assert_int_eq(test_count_lines(count, "run"), 2);
    free(count);
    free(path);
    free(args);
    free(file);
    free(dir);
}
END_TEST

/* A parameter axis marked convergence: true is the axis of the observed
 * orders: h = ratio x dx against a reference of 0 falls at exactly first
 * order in the ratio, and Richardson's order of h is 1 (extrapolated 0).
 * A measure's scale multiplies its value (h in mm); a reference taken from
 * another measure of the same run (h in m against 0.001 x h in mm) gives
 * the error 0, and 2 x h against 1 x h gives +100 %. */
START_TEST(orders_along_a_parameter_axis)
{
    char *dir = test_scratch("study-convergence");
    char *file = write_study(dir, "c.yaml",
                             "scene: %s\n"
                             "set: {time.end: 0.01, plugins.hdf5.interval: 0.01, "
                             "particles.spacing: 0.05}\n"
                             "axes:\n"
                             "  - {name: ratio, parameter: particles.smoothing_length_ratio, "
                             "values: [2, 1.5, 1.125], convergence: true}\n"
                             "measures:\n"
                             "  - {name: h, unit: m, run: smoothing_length, reference: 0}\n"
                             "  - {name: h_mm, unit: mm, run: smoothing_length, scale: 1000}\n"
                             "  - {name: h_again, unit: m, run: smoothing_length, "
                             "reference_measure: h_mm, reference_factor: 0.001}\n"
                             "  - {name: twice_h, unit: m, run: smoothing_length, scale: 2, "
                             "reference_measure: h}\n");
    char *args = NULL, *output = NULL, *path = NULL;
    ck_assert_int_ge(asprintf(&args, "study %s --out %s/out", file, dir), 0);
    ck_assert_int_eq(study(args, &output), 0);
    free(output);
    ck_assert_int_ge(asprintf(&path, "%s/out/study.csv", dir), 0);
    char *csv = test_read_file(path);
    ck_assert_ptr_nonnull(csv);
    ck_assert_double_eq_tol(csv_number(csv, "1.5", "h_mm"), 75, 1e-9);
    ck_assert_double_eq_tol(csv_number(csv, "1.5", "h_again_error"), 0, 1e-12);
    ck_assert_double_eq_tol(csv_number(csv, "1.125", "twice_h_error"), 1, 1e-12);
    free(csv);
    free(path);
    ck_assert_int_ge(asprintf(&path, "%s/out/orders.csv", dir), 0);
    char *orders = test_read_file(path);
    ck_assert_ptr_nonnull(orders);
    static const char row[] = "all,h,2;1.5;1.125,0.1;0.075;0.05625,0.1;0.075;0.05625,"
                              "1.00;1.00,1,";
    const char *at = strstr(orders, row);
    ck_assert_msg(at, "%s", orders);
    ck_assert_double_eq_tol(strtod(at + strlen(row), NULL), 0, 1e-12); /* extrapolated h */
    free(orders);
    free(path);
    ck_assert_int_ge(asprintf(&path, "%s/out/plots/h_convergence.png", dir), 0);
    ck_assert(is_png(path));
    free(path);
    free(args);
    free(file);
    free(dir);
}
END_TEST

/* Targets: h = ratio x dx against 0.05 m within 30 % (0.035-0.065 m), h in
 * mm at most 40 and h at least 1 mm. Ratio 1.2 (h 0.06, 0.03 m) meets the
 * first at dx 0.05 only and the second at 0.025 only; ratio 1.5 (0.075,
 * 0.0375 m) meets both at 0.025: no group meets two targets at every
 * spacing, and 1.5 is best by the finest spacing (3 of 3 against 2). */
START_TEST(targets_name_the_best_group)
{
    char *dir = test_scratch("study-targets");
    char *file = write_study(dir, "t.yaml",
                             "scene: %s\n"
                             "set: {time.end: 0.01, plugins.hdf5.interval: 0.01}\n"
                             "jobs: 2\n"
                             "axes:\n"
                             "  - {name: ratio, parameter: particles.smoothing_length_ratio, "
                             "values: [1.2, 1.5]}\n"
                             "  - {name: dx, spacing: [0.05, 0.025]}\n"
                             "measures:\n"
                             "  - {name: h, unit: m, run: smoothing_length, reference: 0.05, "
                             "within: 0.3}\n"
                             "  - {name: h_mm, unit: mm, run: smoothing_length, scale: 1000, "
                             "below: 40}\n"
                             "  - {name: h_m, unit: m, run: smoothing_length, above: 0.001}\n");
    char *args = NULL, *output = NULL, *path = NULL;
    ck_assert_int_ge(asprintf(&args, "study %s --out %s/out", file, dir), 0);
    ck_assert_int_eq(study(args, &output), 0);
    free(output);
    ck_assert_int_ge(asprintf(&path, "%s/out/study.md", dir), 0);
    char *md = test_read_file(path);
    ck_assert_ptr_nonnull(md);
    ck_assert_msg(strstr(md, "| 1.2 | yes no | no yes | yes yes | 1 of 3 | 2 of 3 |"), "%s", md);
    ck_assert_msg(strstr(md, "| 1.5 | no yes | no yes | yes yes | 1 of 3 | 3 of 3 |"), "%s", md);
    ck_assert_msg(strstr(md, "**Best against the targets: 1.5**, meeting 1 of the 3 targets at "
                             "every spacing and 3 at the finest; no group meets every target"),
                  "%s", md);
    free(md);
    free(path);
    free(args);
    free(file);
    free(dir);
}
END_TEST

/* A study file that is refused: exit 2, the message at file:line:column,
 * nothing written. */
static void expect_refused(const char *body, const char *position, const char *message)
{
    char *dir = test_scratch("study-refused");
    char *file = write_study(dir, "bad.yaml", body);
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "study %s --out %s/out", file, dir), 0);
    int status = study(args, &output);
    char *expected = NULL;
    ck_assert_int_ge(asprintf(&expected, "%s:%s: error: %s", file, position, message), 0);
    ck_assert_msg(status == 2 && strstr(output, expected), "exit %d, output:\n%s\nexpected:\n%s",
                  status, output, expected);
    char *out = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", dir), 0);
    ck_assert(!test_exists(out));
    free(out);
    free(expected);
    free(output);
    free(args);
    free(file);
    free(dir);
}

#define AXIS "axes:\n  - {name: dx, spacing: [0.05]}\n"

START_TEST(bad_study_files_are_refused)
{
    expect_refused("scene: %s\n" AXIS "mesures: []\n", "4:1",
                   "unknown key 'mesures' in the study; did you mean 'measures'?");
    expect_refused("scene: %s/nothing.yaml\n" AXIS, "1:8", "the scene '");
    expect_refused("title: no scene %s\n" AXIS, "1:1",
                   "a study needs 'scene': the path of its base scene (relative "
                   "to the study "
                   "file)");
    expect_refused("scene: %s\n", "1:1", "a study needs 'axes' (a list)");
    expect_refused("scene: %s\naxes:\n  - {name: dx, spacing: [0.1, -1]}\n", "3:31",
                   "axis 'dx': a spacing is a positive number of metres, got '-1'");
    expect_refused("scene: %s\naxes:\n  - {name: t, threads: [1.5]}\n", "3:25",
                   "axis 't': a thread count is a whole number from 1 to 4096, got '1.5'");
    expect_refused("scene: %s\naxes:\n  - {name: x, spacing: [0.1], threads: [1]}\n", "3:5",
                   "axis 'x' needs exactly one of: values (labels and their scene edits), "
                   "parameter with values (a list), spacing (a list), threads (a list)");
    expect_refused("scene: %s\naxes:\n  - {spacing: [0.1]}\n", "3:5",
                   "an axis needs a name (a column of the table)");
    expect_refused("scene: %s\naxes:\n  - {name: c, parameter: plugins.tait.speed_of_sound, "
                   "values: [20, 20]}\n",
                   "3:68", "axis 'c' has the value '20' twice");
    expect_refused("scene: %s\naxes:\n  - {name: w, values: {dbc: {}, m: {swap: {dbx: "
                   "mdbc}}}}\n",
                   "3:49",
                   "cannot swap 'dbx': the scene loads no plugin of that name; did you "
                   "mean 'dbc'?");
    expect_refused("scene: %s\naxes:\n  - {name: c, parameter: plugins.tait.speed_of_sound, "
                   "values: [-3]}\n",
                   "3:64",
                   "plugins.tait.speed_of_sound = -3 m s^-1 is out of range: it must be > 0 "
                   "m s^-1");
    expect_refused("scene: %s\naxes:\n  - {name: w, values: {a: {swap: [dbc]}}}\n", "3:34",
                   "axes.w.values.a.swap must be a mapping from plugins the scene loads to "
                   "the "
                   "plugins that replace them, e.g. {dbc: mdbc}");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, gauge: a.csv, column: p, "
                   "reduce: maen}\n",
                   "5:48",
                   "measure 'p': reduce must be one of mean, max, min, first, "
                   "last, std, rms, "
                   "integral, time_of_max, time_of_min; did you mean 'mean'?");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p}\n", "5:5",
                   "measure 'p' needs exactly one source: gauge (a CSV file of "
                   "the run, with "
                   "column), analysis (sluice-analyze arguments, with key) or "
                   "run (a figure of "
                   "run.json)");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, run: steps}\n  - {name: p, run: "
                   "steps}\n",
                   "6:5", "two measures are named 'p'");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, run: steps, error: absolute}\n",
                   "5:34", "measure 'p': error needs a reference");
    expect_refused("scene: %s\naxes:\n  - {name: w, values: {a/b: {}}}\n", "3:24",
                   "axis 'w': the label 'a/b' names run directories: letters, "
                   "digits, '.', '_', "
                   "'+' and '-' only");
    expect_refused("scene: %s\naxes:\n  - {name: m, values: {a: {scene: nowhere.yaml}}}\n", "3:35",
                   "the scene 'nowhere.yaml' cannot be read (No such file or directory)");
    expect_refused("scene: %s\naxes:\n  - {name: c, values: {p: {external: \"run {out}\"}}}\n",
                   "3:38",
                   "axes.c.values.p.external must name the run directory it writes as "
                   "{run_dir}");
    expect_refused("scene: %s\naxes:\n  - {name: c, values: {p: {external: \"run {run_dir} "
                   "{dx}\"}}}\n",
                   "3:38",
                   "axes.c.values.p.external: unknown placeholder '{dx}' (known: "
                   "{run_dir}, {spacing}, {threads}, {study_dir})");
    expect_refused("scene: %s\naxes:\n  - {name: c, values: {p: {external: \"run {run_dir}\", "
                   "set: {time.end: 1}}}}\n",
                   "3:60",
                   "axes.c.values.p: an external value runs another program and takes "
                   "no scene edits ('set')");
    expect_refused("scene: %s\naxes:\n  - {name: c, values: {p: {requires: \"true\"}}}\n", "3:38",
                   "axes.c.values.p.requires belongs to an external value (give "
                   "'external')");
    expect_refused("scene: %s\naxes:\n  - {name: c, values: {p: {external: \"run {run_dir} "
                   "{spacing}\"}}}\n",
                   "3:38", "run 'p': the external command uses {spacing} and no axis sets it");
    expect_refused("scene: %s\naxes:\n  - {name: c, values: {p: {external: \"run {run_dir}\"}}}\n"
                   "  - {name: w, values: {m: {swap: {dbc: mdbc}}}}\n",
                   "4:40",
                   "run 'p_m' combines an external program with a scene edit; give the "
                   "external value its own axis, or a profile without this combination");
    expect_refused("scene: %s\naxes:\n  - {name: dx, spacing: [0.05], convergence: true}\n", "3:46",
                   "axis 'dx': convergence (true or false) marks a parameter axis of "
                   "positive numbers, such as time.max_step, as the axis of the observed "
                   "orders");
    expect_refused("scene: %s\naxes:\n  - {name: dt, parameter: time.max_step, values: [1e-4, "
                   "fast], convergence: true}\n",
                   "3:57",
                   "axis 'dt': the values of a convergence axis are positive numbers, "
                   "got 'fast'");
    expect_refused("scene: %s\naxes:\n  - {name: dx, spacing: [0.05]}\n  - {name: dt, parameter: "
                   "time.max_step, values: [1e-4], convergence: true}\n",
                   "4:5",
                   "axis 'dt': a study has one axis of the observed orders (the spacing "
                   "axis, or one parameter axis with convergence: true)");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, run: steps, reference_measure: q}\n",
                   "5:46", "measure 'p': reference_measure 'q' is not a measure of the study");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, run: steps, reference_measure: p}\n",
                   "5:46", "measure 'p': reference_measure 'p' is the measure itself");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, run: steps, reference: 1, "
                   "reference_measure: p}\n",
                   "5:60", "measure 'p': give either reference or reference_measure");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, run: steps, scale: 0}\n", "5:34",
                   "measure 'p': scale is a non-zero number the value is multiplied by");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, run: steps, within: 0.1}\n",
                   "5:35", "measure 'p': within needs a reference (or give below/above)");
    expect_refused("scene: %s\n" AXIS
                   "measures:\n  - {name: p, run: steps, reference: 1, within: -0.1}\n",
                   "5:49", "measure 'p': within is the largest error allowed, a positive number");
    expect_refused("scene: %s\n" AXIS "measures:\n  - {name: p, run: steps, below: 1, above: 2}\n",
                   "5:34", "measure 'p': below 1 is not above above 2: no value meets both");
    expect_refused("scene: %s\naxes: [\n", "3:1",
                   "YAML syntax error: did not find expected node content");
}
END_TEST

int main(void)
{
    Suite *s = suite_create("study");
    TCase *runs = tcase_create("runs");
    tcase_set_timeout(runs, 600);
    tcase_add_test(runs, two_axis_study_runs_resumes_and_reports);
    tcase_add_test(runs, unstable_run_is_recorded_not_fatal);
    tcase_add_test(runs, interrupted_study_continues_from_the_checkpoint);
    tcase_add_test(runs, external_programs_as_axis_values);
    tcase_add_test(runs, orders_along_a_parameter_axis);
    tcase_add_test(runs, targets_name_the_best_group);
    suite_add_tcase(s, runs);
    TCase *refusals = tcase_create("refusals");
    tcase_add_test(refusals, bad_study_files_are_refused);
    tcase_add_test(refusals, profiles_and_dry_run);
    suite_add_tcase(s, refusals);
    return test_run_suite(s);
}
