/* Helpers shared by the Check tests: scratch directories, running the sluice
 * program, reading CSV outputs. Paths come from the environment meson sets:
 * SLUICE_BUILD_DIR and SLUICE_SOURCE_DIR. */
#ifndef SLUICE_TEST_UTIL_H
#define SLUICE_TEST_UTIL_H

#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif
#include <check.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static inline const char *test_build_dir(void)
{
    const char *d = getenv("SLUICE_BUILD_DIR");
    return d ? d : ".";
}

static inline const char *test_source_dir(void)
{
    const char *d = getenv("SLUICE_SOURCE_DIR");
    return d ? d : "..";
}

/* A fresh scratch directory: under the suite's scratch root when
 * test_run_suite made one (removed when every test passed, kept for
 * inspection otherwise), else under /tmp. */
static inline char *test_scratch(const char *tag)
{
    char *path = NULL;
    const char *root = getenv("SLUICE_TEST_SCRATCH_ROOT");
    if (asprintf(&path, "%s/sluice-test-%s-XXXXXX", root && *root ? root : "/tmp", tag) < 0)
        return NULL;
    if (!mkdtemp(path)) {
        free(path);
        return NULL;
    }
    return path;
}

static inline char *test_write_file(const char *dir, const char *name, const char *text)
{
    char *path = NULL;
    if (asprintf(&path, "%s/%s", dir, name) < 0)
        return NULL;
    FILE *f = fopen(path, "w");
    if (!f) {
        free(path);
        return NULL;
    }
    fputs(text, f);
    fclose(f);
    return path;
}

static inline char *test_read_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    char *text = NULL;
    size_t size = 0;
    FILE *m = open_memstream(&text, &size);
    char buffer[4096];
    size_t n;
    while ((n = fread(buffer, 1, sizeof buffer, f)) > 0)
        fwrite(buffer, 1, n, m);
    fclose(f);
    fclose(m);
    return text;
}

static inline int test_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* Runs a shell command; its standard output into *output (when given).
 * Returns the exit status, or -1. */
static inline int test_popen(const char *command, char **output)
{
    FILE *p = popen(command, "r");
    if (!p)
        return -1;
    char *text = NULL;
    size_t size = 0;
    FILE *m = open_memstream(&text, &size);
    char buffer[4096];
    size_t n;
    while ((n = fread(buffer, 1, sizeof buffer, p)) > 0)
        fwrite(buffer, 1, n, m);
    fclose(m);
    int status = pclose(p);
    if (output)
        *output = text;
    else
        free(text);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/* Runs `<build>/sluice args...` through the shell, capturing stderr and
 * stdout; returns the exit status (or -1). */
static inline int test_sluice(const char *args, char **output)
{
    char *command = NULL;
    if (asprintf(&command, "%s/sluice %s 2>&1", test_build_dir(), args) < 0)
        return -1;
    int status = test_popen(command, output);
    free(command);
    return status;
}

/* Counts the lines of text that contain `needle`. */
static inline int test_count_lines(const char *text, const char *needle)
{
    int count = 0;
    const char *line = text;
    while (line && *line) {
        const char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line) : strlen(line);
        char *copy = strndup(line, len);
        if (copy && strstr(copy, needle))
            count++;
        free(copy);
        line = end ? end + 1 : NULL;
    }
    return count;
}

/* Reads a two-column numeric CSV with a header; returns the row count. */
static inline int test_read_csv2(const char *path, double **a, double **b)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char line[1024];
    int n = 0, cap = 0;
    *a = *b = NULL;
    if (!fgets(line, sizeof line, f)) {
        fclose(f);
        return 0;
    }
    while (fgets(line, sizeof line, f)) {
        double x, y;
        if (sscanf(line, "%lf,%lf", &x, &y) != 2)
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 256;
            *a = realloc(*a, (size_t)cap * sizeof **a);
            *b = realloc(*b, (size_t)cap * sizeof **b);
        }
        (*a)[n] = x;
        (*b)[n] = y;
        n++;
    }
    fclose(f);
    return n;
}

/* A scene path inside the source tree. */
static inline char *test_config(const char *name)
{
    char *path = NULL;
    if (asprintf(&path, "%s/configs/%s", test_source_dir(), name) < 0)
        return NULL;
    return path;
}

/* Runs the suite with its scratch directories (test_scratch) under one
 * root in $TMPDIR or /tmp: removed when every test passed, kept (and named)
 * when one failed, so that a passing suite leaves nothing behind. */
static inline int test_run_suite(Suite *suite)
{
    const char *tmp = getenv("TMPDIR");
    char *root = NULL;
    if (asprintf(&root, "%s/sluice-tests-XXXXXX", tmp && *tmp ? tmp : "/tmp") < 0 ||
        !mkdtemp(root)) {
        free(root);
        root = NULL;
    } else
        setenv("SLUICE_TEST_SCRATCH_ROOT", root, 1);
    SRunner *runner = srunner_create(suite);
    srunner_run_all(runner, CK_NORMAL);
    int failed = srunner_ntests_failed(runner);
    srunner_free(runner);
    if (root) {
        char *command = NULL;
        if (failed)
            fprintf(stderr, "the tests' scratch directories are kept in %s\n", root);
        else if (asprintf(&command, "rm -rf '%s'", root) >= 0 && system(command) != 0)
            fprintf(stderr, "could not remove %s\n", root);
        free(command);
        unsetenv("SLUICE_TEST_SCRATCH_ROOT");
        free(root);
    }
    return failed == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}

/* A uniform deviate in [0, 1) from a 64-bit linear congruential state:
 * reproducible random fields for tests. */
static inline double test_uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

/* The number after "key": in a run.json text; NaN when the key is absent
 * (so that any comparison with it fails). */
static inline double test_json_number(const char *json, const char *key)
{
    char *pattern = NULL;
    if (asprintf(&pattern, "\"%s\": ", key) < 0)
        return NAN;
    const char *p = strstr(json, pattern);
    free(pattern);
    return p ? strtod(p + strlen(key) + 4, NULL) : NAN;
}

#endif
