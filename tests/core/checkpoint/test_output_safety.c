/* No data lost: a run killed with SIGKILL at any moment leaves every output
 * it had written readable (snapshots open and read with the HDF5 library,
 * tables hold whole rows, the XDMF index names only snapshots that exist),
 * and a write that fails (a full disk, simulated with the file-size limit;
 * an output directory that cannot be created) is reported at once with the
 * path, a non-zero exit and run.json saying why. */
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>

#include <hdf5.h>

#include "test_util.h"

extern char **environ;

/* ------------------------------------------------------------- checking -- */

typedef struct h5_check {
    int datasets;
    int failures;
} h5_check;

static herr_t read_object(hid_t group, const char *name, const H5L_info_t *info, void *data);

/* Opens every dataset under `group` (recursively) and reads it whole. */
static herr_t read_object(hid_t group, const char *name, const H5L_info_t *info, void *data)
{
    (void)info;
    h5_check *check = data;
    hid_t dataset = H5Dopen2(group, name, H5P_DEFAULT);
    if (dataset < 0) {
        hid_t sub = H5Gopen2(group, name, H5P_DEFAULT);
        if (sub < 0) {
            check->failures++;
            return 0;
        }
        if (H5Literate(sub, H5_INDEX_NAME, H5_ITER_NATIVE, NULL, read_object, check) < 0)
            check->failures++;
        H5Gclose(sub);
        return 0;
    }
    hid_t file_type = H5Dget_type(dataset);
    hid_t memory_type = H5Tget_native_type(file_type, H5T_DIR_DEFAULT);
    hid_t space = H5Dget_space(dataset);
    hssize_t points = H5Sget_simple_extent_npoints(space);
    size_t size = H5Tget_size(memory_type);
    void *buffer = malloc((size_t)(points > 0 ? points : 1) * (size ? size : 1));
    if (!buffer || points < 0 ||
        H5Dread(dataset, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer) < 0)
        check->failures++;
    else {
        check->datasets++;
        /* variable-length data (the walls file's names) is HDF5's to free */
        if (H5Tdetect_class(memory_type, H5T_VLEN) > 0 || H5Tis_variable_str(memory_type) > 0)
            H5Dvlen_reclaim(memory_type, space, H5P_DEFAULT, buffer);
    }
    free(buffer);
    H5Sclose(space);
    H5Tclose(memory_type);
    H5Tclose(file_type);
    H5Dclose(dataset);
    return 0;
}

/* Returns the number of datasets read, or -1 when the file does not open or
 * a dataset does not read. */
static int read_hdf5(const char *path)
{
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file < 0)
        return -1;
    h5_check check = {0, 0};
    if (H5Literate(file, H5_INDEX_NAME, H5_ITER_NATIVE, NULL, read_object, &check) < 0)
        check.failures++;
    H5Fclose(file);
    return check.failures ? -1 : check.datasets;
}

static int count_char(const char *begin, const char *end, char c)
{
    int n = 0;
    for (const char *p = begin; p < end; p++)
        n += *p == c;
    return n;
}

/* A table: ends with a newline, every row has the header's column count. */
static int table_whole(const char *path, char *why, size_t why_size)
{
    char *text = test_read_file(path);
    if (!text) {
        snprintf(why, why_size, "cannot read");
        return 0;
    }
    size_t length = strlen(text);
    int ok = 1;
    if (length > 0 && text[length - 1] != '\n') {
        snprintf(why, why_size, "does not end with a whole line");
        ok = 0;
    }
    const char *line = text;
    int header_commas = -1, row = 0;
    while (ok && *line) {
        const char *end = strchr(line, '\n');
        if (!end)
            end = line + strlen(line);
        int commas = count_char(line, end, ',');
        if (header_commas < 0)
            header_commas = commas;
        else if (commas != header_commas) {
            snprintf(why, why_size, "row %d has %d columns, the header %d", row, commas + 1,
                     header_commas + 1);
            ok = 0;
        }
        row++;
        line = *end ? end + 1 : end;
    }
    free(text);
    return ok;
}

/* The XDMF index: complete, and every snapshot it names exists. */
static int index_whole(const char *dir, const char *path, char *why, size_t why_size)
{
    char *text = test_read_file(path);
    if (!text) {
        snprintf(why, why_size, "cannot read");
        return 0;
    }
    int ok = strstr(text, "</Xdmf>") != NULL;
    if (!ok)
        snprintf(why, why_size, "is not a complete XDMF document");
    for (const char *p = text; ok && (p = strstr(p, "particles_")) != NULL;) {
        const char *end = strstr(p, ".h5");
        if (!end)
            break;
        char name[256];
        size_t n = (size_t)(end - p) + 3;
        if (n >= sizeof name)
            break;
        memcpy(name, p, n);
        name[n] = '\0';
        char *full = NULL;
        ck_assert_int_ge(asprintf(&full, "%s/%s", dir, name), 0);
        if (!test_exists(full)) {
            snprintf(why, why_size, "names '%s', which does not exist", name);
            ok = 0;
        }
        free(full);
        p = end;
    }
    free(text);
    return ok;
}

typedef struct scan {
    int snapshots, datasets, tables, rows_checked, indexes, temporaries, others;
} scan;

/* Every output file in `dir` must be readable and whole; temporary files
 * (name.tmp.PID, never an output) are counted. */
static void check_outputs(const char *dir, scan *totals, const char *context)
{
    DIR *d = opendir(dir);
    if (!d)
        return; /* killed before the directory was made: nothing to lose */
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        const char *name = e->d_name;
        if (name[0] == '.')
            continue;
        char *full = NULL;
        ck_assert_int_ge(asprintf(&full, "%s/%s", dir, name), 0);
        char why[512] = "";
        size_t len = strlen(name);
        if (strstr(name, ".tmp.")) {
            totals->temporaries++;
        } else if (len > 3 && strcmp(name + len - 3, ".h5") == 0) {
            int n = read_hdf5(full);
            ck_assert_msg(n > 0, "%s: %s does not open or read with the HDF5 library", context,
                          full);
            totals->snapshots++;
            totals->datasets += n;
        } else if (len > 4 && strcmp(name + len - 4, ".csv") == 0) {
            ck_assert_msg(table_whole(full, why, sizeof why), "%s: %s %s", context, full, why);
            totals->tables++;
        } else if (len > 5 && strcmp(name + len - 5, ".xdmf") == 0) {
            ck_assert_msg(index_whole(dir, full, why, sizeof why), "%s: %s %s", context, full,
                          why);
            totals->indexes++;
        } else if (strcmp(name, "run.json") == 0 || strcmp(name, "tables.json") == 0) {
            char *text = test_read_file(full);
            ck_assert_ptr_nonnull(text);
            size_t n = strlen(text);
            ck_assert_msg(n > 2 && strcmp(text + n - 2, "}\n") == 0, "%s: %s is not whole",
                          context, full);
            free(text);
            totals->others++;
        } else {
            totals->others++;
        }
        free(full);
    }
    closedir(d);
}

/* ------------------------------------------------------------ the tests -- */

/* Starts the dam break with frequent outputs into `out`, kills it with
 * SIGKILL after delay_ms of wall time and checks every file it left.
 * Returns 1 when the run had ended before the kill. */
static int kill_one(const char *program, const char *scene, const char *out, long delay_ms,
                    scan *totals)
{
    char *argv[] = {(char *)program, "run", (char *)scene, "--out", (char *)out, "--quiet",
                    "--no-progress", "--threads", "1", "--set", "plugins.hdf5.interval=0.002",
                    "--set", "plugins.front_gauge.interval=0.0005",
                    "--set", "checkpoint.interval=0.004", NULL};
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    pid_t pid;
    ck_assert_int_eq(posix_spawn(&pid, program, &actions, NULL, argv, environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    struct timespec pause = {delay_ms / 1000, (delay_ms % 1000) * 1000000L};
    nanosleep(&pause, NULL);
    kill(pid, SIGKILL);
    int status = 0;
    ck_assert_int_eq(waitpid(pid, &status, 0), pid);
    /* a snapshot's writing process dies with the run (it may take a
     * moment to notice): wait for it, so that nothing changes the
     * directory while it is checked */
    struct timespec settle = {0, 50000000L};
    nanosleep(&settle, NULL);
    char context[64];
    snprintf(context, sizeof context, "run killed after %ld ms", delay_ms);
    check_outputs(out, totals, context);
    return !WIFSIGNALED(status);
}

START_TEST(killed_runs_leave_readable_outputs)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    char *scratch = test_scratch("kill");
    ck_assert_ptr_nonnull(scratch);
    char *program = NULL, *scene = test_config("dam_break_2d.yaml");
    ck_assert_int_ge(asprintf(&program, "%s/sluice", test_build_dir()), 0);
    /* A snapshot every 2 ms of simulated time (every few steps), a
     * checkpoint every 4 ms and the front gauge every step or so: kills
     * land in writes often. The kill times are spread over 20-900 ms of
     * wall time, from before the output directory exists to well into the
     * run. On a slow machine (a sanitizer build, other work) fewer outputs
     * are written before the kills: more runs follow, killed later each
     * time, until the campaign has checked more snapshots than it killed
     * runs and tables in half as many (at most as many runs again). */
    const char *requested = getenv("SLUICE_KILL_COUNT"); /* a longer campaign: docs/reliability.md */
    const int kills = requested && atoi(requested) > 0 ? atoi(requested) : 24;
    scan totals = {0};
    int finished_before_kill = 0, runs = 0;
    for (int k = 0; k < 2 * kills &&
                    (k < kills || totals.snapshots <= kills || totals.tables <= kills / 2);
         k++) {
        char *out = NULL;
        ck_assert_int_ge(asprintf(&out, "%s/run%02d", scratch, k), 0);
        const long delay_ms =
            k < kills ? 20 + (k * 379L + (k / 880) * 7) % 880 : 900L * (k - kills + 2);
        finished_before_kill += kill_one(program, scene, out, delay_ms, &totals);
        runs++;
        free(out);
    }
    fprintf(stderr,
            "output_safety: %d runs killed with SIGKILL (%d had ended first): %d snapshots "
            "and checkpoints (%d datasets) opened and read, %d tables and %d indexes whole, %d temporary "
            "files left (never outputs), %d other files\n",
            runs, finished_before_kill, totals.snapshots, totals.datasets, totals.tables,
            totals.indexes, totals.temporaries, totals.others);
    /* the test must have seen outputs to check, or it proves nothing */
    ck_assert_int_gt(totals.snapshots, kills);
    ck_assert_int_gt(totals.tables, kills / 2);
    ck_assert_int_eq(finished_before_kill, 0);
    free(program);
    free(scene);
    free(scratch);
}
END_TEST

/* Output directories: a second run into a directory that holds a run is
 * refused and leaves it as it was; --overwrite replaces the run's outputs
 * and nothing else; a run that another live run writes to is refused
 * (DIR/.sluice.lock), and the lock goes with its process, even killed. */
START_TEST(output_directories_are_protected)
{
    char *scratch = test_scratch("outdir");
    char *scene = test_config("still_water_2d.yaml");
    char *args = NULL, *output = NULL, *path = NULL;
    const char *fast = "--quiet --no-progress --threads 1 --set time.end=0.01 "
                       "--set particles.spacing=0.05";
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/a %s --set "
                                     "plugins.energy_gauge.file=only_first.csv",
                              scene, scratch, fast), 0);
    ck_assert_int_eq(test_sluice(args, &output), 0);
    free(args);
    free(output);
    ck_assert_int_ge(asprintf(&path, "%s/a/run.json", scratch), 0);
    char *first = test_read_file(path);
    ck_assert_ptr_nonnull(first);
    char *notes = test_write_file(scratch, "a/notes.txt", "a user's file\n");
    char *analysis = NULL;
    ck_assert_int_ge(asprintf(&analysis, "%s/a/analysis", scratch), 0);
    ck_assert_int_eq(mkdir(analysis, 0755), 0);
    free(test_write_file(analysis, "conjugate.csv", "time,d2\n0,0.08\n"));
    /* the same --out again: refused, the run left as it was */
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/a %s", scene, scratch, fast), 0);
    ck_assert_int_eq(test_sluice(args, &output), 2);
    ck_assert_msg(strstr(output, "holds another run (run.json): --overwrite replaces it") &&
                      test_count_lines(output, "error:") == 1,
                  "%s", output);
    free(output);
    char *again = test_read_file(path);
    ck_assert_str_eq(again, first);
    free(again);
    free(args);
    /* --overwrite: the earlier run's outputs go, other files stay */
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/a %s --overwrite", scene, scratch, fast),
                     0);
    ck_assert_int_eq(test_sluice(args, &output), 0);
    free(output);
    free(args);
    char *gone = NULL;
    ck_assert_int_ge(asprintf(&gone, "%s/a/only_first.csv", scratch), 0);
    ck_assert(!test_exists(gone));
    ck_assert(!test_exists(analysis)); /* sluice-analyze's outputs of the first run */
    ck_assert(test_exists(notes));
    free(gone);
    free(analysis);
    /* --overwrite and --restart contradict each other */
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/a %s --overwrite --restart %s/x.h5", scene,
                              scratch, fast, scratch), 0);
    ck_assert_int_eq(test_sluice(args, &output), 2);
    ck_assert_ptr_nonnull(strstr(output, "give either --overwrite"));
    free(output);
    free(args);
    /* a live run holds its directory */
    char *program = NULL, *out_b = NULL, *lock = NULL;
    ck_assert_int_ge(asprintf(&program, "%s/sluice", test_build_dir()), 0);
    ck_assert_int_ge(asprintf(&out_b, "%s/b", scratch), 0);
    ck_assert_int_ge(asprintf(&lock, "%s/b/.sluice.lock", scratch), 0);
    char *argv[] = {program, "run", scene, "--out", out_b, "--quiet", "--no-progress",
                    "--threads", "1", "--set", "time.end=100", NULL};
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    pid_t pid;
    ck_assert_int_eq(posix_spawn(&pid, program, &actions, NULL, argv, environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    char *held = NULL;
    for (int i = 0; i < 600 && !(held && *held); i++) { /* up to 60 s on a busy machine */
        struct timespec pause = {0, 100000000L};
        nanosleep(&pause, NULL);
        free(held);
        held = test_exists(lock) ? test_read_file(lock) : NULL;
    }
    ck_assert_msg(held && atol(held) == (long)pid, "lock file: %s", held ? held : "(none)");
    free(held);
    ck_assert_int_ge(asprintf(&args, "run %s --out %s %s --overwrite", scene, out_b, fast), 0);
    ck_assert_int_eq(test_sluice(args, &output), 2);
    char *expected = NULL;
    ck_assert_int_ge(asprintf(&expected, "another sluice run (pid %ld) is writing to '%s'",
                              (long)pid, out_b), 0);
    ck_assert_msg(strstr(output, expected), "%s", output);
    free(expected);
    free(output);
    kill(pid, SIGKILL);
    int status = 0;
    ck_assert_int_eq(waitpid(pid, &status, 0), pid);
    /* killed: the lock went with it; its outputs are replaced on request */
    ck_assert_int_eq(test_sluice(args, &output), 0);
    free(output);
    free(args);
    free(lock);
    free(out_b);
    free(program);
    free(notes);
    free(first);
    free(path);
    free(scene);
    free(scratch);
}
END_TEST

/* A snapshot's datasets carry Fletcher-32 checksums: one bit changed in a
 * chunk of positions makes the HDF5 read fail instead of returning a
 * wrong number. */
START_TEST(snapshot_chunks_are_checksummed)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    char *dir = test_scratch("snapshot-sum");
    char *scene = test_config("still_water_2d.yaml"), *args = NULL, *path = NULL;
    ck_assert_int_ge(asprintf(&args, "run %s --out %s/out --quiet --no-progress --threads 1 "
                                     "--set time.end=0.01 --set particles.spacing=0.05",
                              scene, dir), 0);
    ck_assert_int_eq(test_sluice(args, NULL), 0);
    ck_assert_int_ge(asprintf(&path, "%s/out/particles_000000.h5", dir), 0);
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_int_ge(file, 0);
    hid_t set = H5Dopen2(file, "position", H5P_DEFAULT), dcpl = H5Dget_create_plist(set);
    ck_assert_int_eq(H5Pget_layout(dcpl), H5D_CHUNKED);
    int fletcher = 0;
    for (int k = 0; k < H5Pget_nfilters(dcpl); k++) {
        unsigned flags = 0;
        size_t count = 0;
        fletcher |= H5Pget_filter2(dcpl, (unsigned)k, &flags, &count, NULL, 0, NULL, NULL) ==
                    H5Z_FILTER_FLETCHER32;
    }
    ck_assert(fletcher);
    haddr_t offset = 0;
    hsize_t chunk_size = 0;
    unsigned mask = 0;
    hsize_t origin[2] = {0, 0};
    ck_assert_int_ge(H5Dget_chunk_info_by_coord(set, origin, &mask, &offset, &chunk_size), 0);
    hid_t space = H5Dget_space(set);
    hssize_t points = H5Sget_simple_extent_npoints(space);
    double *xy = malloc((size_t)points * sizeof *xy);
    ck_assert_int_ge(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, xy), 0);
    H5Sclose(space);
    H5Pclose(dcpl);
    H5Dclose(set);
    H5Fclose(file);
    /* one bit of the chunk's data changed */
    FILE *f = fopen(path, "r+b");
    ck_assert_ptr_nonnull(f);
    ck_assert_int_eq(fseek(f, (long)offset + (long)chunk_size / 2, SEEK_SET), 0);
    int byte = fgetc(f);
    ck_assert_int_ge(byte, 0);
    ck_assert_int_eq(fseek(f, (long)offset + (long)chunk_size / 2, SEEK_SET), 0);
    fputc(byte ^ 0x08, f);
    fclose(f);
    file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_int_ge(file, 0);
    set = H5Dopen2(file, "position", H5P_DEFAULT);
    ck_assert_msg(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, xy) < 0,
                  "a changed chunk was read without an error");
    H5Dclose(set);
    H5Fclose(file);
    free(xy);
    free(path);
    free(args);
    free(scene);
    free(dir);
}
END_TEST

START_TEST(failed_write_is_reported_with_its_path)
{
    /* A full disk, as the file-size limit: 100 blocks hold the tables but
     * not the first snapshot. SIGXFSZ ignored, so the write fails with
     * EFBIG as it would with ENOSPC. */
    char *scratch = test_scratch("full");
    ck_assert_ptr_nonnull(scratch);
    char *scene = test_config("dam_break_2d.yaml"), *command = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&command,
                              "trap '' XFSZ; ulimit -f 100; exec %s/sluice run %s --out %s/out "
                              "--no-progress --threads 1 --set time.end=0.05 2>&1",
                              test_build_dir(), scene, scratch),
                     0);
    int status = test_popen(command, &output);
    fprintf(stderr, "output_safety: full disk: status %d: %s", status, output);
    ck_assert_msg(status == 4, "exit status %d (expected 4):\n%s", status, output);
    ck_assert_msg(test_count_lines(output, "error:") == 1, "one message expected:\n%s", output);
    char *where = NULL;
    ck_assert_int_ge(asprintf(&where, "cannot write '%s/out/particles_000000.h5'", scratch), 0);
    ck_assert_msg(strstr(output, where), "expected \"%s\" in:\n%s", where, output);
    /* what was written before is whole, run.json says why, no temporary
     * file is left behind */
    char *out = NULL, *json_path = NULL;
    ck_assert_int_ge(asprintf(&out, "%s/out", scratch), 0);
    ck_assert_int_ge(asprintf(&json_path, "%s/run.json", out), 0);
    char *json = test_read_file(json_path);
    ck_assert_ptr_nonnull(json);
    ck_assert_msg(strstr(json, "\"status\": \"failed\"") && strstr(json, where), "%s", json);
    scan totals = {0};
    check_outputs(out, &totals, "full disk");
    ck_assert_int_eq(totals.temporaries, 0);
    ck_assert_int_eq(totals.snapshots, 0);
    free(json);
    free(json_path);
    free(out);
    free(where);
    free(output);
    free(command);

    /* an output directory that cannot be made (its parent is a file) */
    char *file = test_write_file(scratch, "a-file", "x\n");
    ck_assert_ptr_nonnull(file);
    ck_assert_int_ge(asprintf(&command, "%s/sluice run %s --out %s/out --no-progress 2>&1",
                              test_build_dir(), scene, file),
                     0);
    status = test_popen(command, &output);
    ck_assert_msg(status == 4, "exit status %d (expected 4):\n%s", status, output);
    ck_assert_msg(test_count_lines(output, "error:") == 1, "%s", output);
    ck_assert_msg(strstr(output, "cannot create output directory") && strstr(output, file), "%s",
                  output);
    free(output);
    free(command);
    free(file);
    free(scene);
    free(scratch);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("output safety");
    TCase *tc = tcase_create("outputs");
    tcase_set_timeout(tc, 300);
    tcase_add_test(tc, killed_runs_leave_readable_outputs);
    tcase_add_test(tc, failed_write_is_reported_with_its_path);
    tcase_add_test(tc, output_directories_are_protected);
    tcase_add_test(tc, snapshot_chunks_are_checksummed);
    suite_add_tcase(s, tc);
    return test_run_suite(s);
}
