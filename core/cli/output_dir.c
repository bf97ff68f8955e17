/* The output directory of `sluice run`: one live run at a time (a lock
 * file), and no silent mixing with an earlier run (docs/reliability.md,
 * "Output directories"). */
#define _GNU_SOURCE
#include "output_dir.h"

#include "sim.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <fnmatch.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#define LOCK_NAME ".sluice.lock"

/* What a run writes at the top of its directory: removed by --overwrite,
 * and the marks of an earlier run. */
static const char *const run_outputs[] = {"run.json", "scene.resolved.yaml", "tables.json", "*.h5",
                                          "*.xdmf", "*.xmf", "*.csv", "*.tmp"};
static const char *const run_marks[] = {"run.json", "scene.resolved.yaml", "checkpoint_*.h5",
                                        "particles_*.h5"};

/* 1 + the index of the first pattern name matches, 0 none. */
static size_t matches(const char *name, const char *const *patterns, size_t count)
{
    for (size_t i = 0; i < count; i++)
        if (fnmatch(patterns[i], name, 0) == 0)
            return i + 1;
    return 0;
}

/* The lock: DIR/.sluice.lock held with flock() for the life of the
 * process (closed at exit, also when killed). */
static int take_lock(const char *dir, int *fd_out, char *error, size_t size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, LOCK_NAME);
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
        snprintf(error, size, "cannot create '%s': %s", path, strerror(errno));
        return -1;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
        char pid[32] = "";
        ssize_t n = pread(fd, pid, sizeof pid - 1, 0);
        pid[n > 0 ? n : 0] = '\0';
        pid[strcspn(pid, "\n")] = '\0';
        snprintf(error, size,
                 "another sluice run%s%s%s is writing to '%s' (it holds %s): wait for it to end "
                 "or choose another --out",
                 *pid ? " (pid " : "", pid, *pid ? ")" : "", dir, path);
        close(fd);
        return -1;
    }
    char text[32];
    int length = snprintf(text, sizeof text, "%ld\n", (long)getpid());
    if (ftruncate(fd, 0) != 0 || pwrite(fd, text, (size_t)length, 0) != length) {
        /* the pid is a courtesy for the message above; the lock holds */
    }
    *fd_out = fd;
    return 0;
}

static int remove_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st, (void)flag, (void)ftw;
    return remove(path);
}

/* Removes a directory tree (the analyses of an earlier run), depth first,
 * links not followed. */
static int remove_tree(const char *path)
{
    return nftw(path, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
}

/* The first mark of an earlier run in dir ("" none); with clear, removes
 * every output a run writes instead. */
static int scan_outputs(const char *dir, int clear, char *mark, size_t mark_size, char *error,
                        size_t size)
{
    mark[0] = '\0';
    DIR *d = opendir(dir);
    if (!d) {
        snprintf(error, size, "cannot read output directory '%s': %s", dir, strerror(errno));
        return -1;
    }
    int status = 0;
    size_t best = 0; /* the mark named: the first of run_marks found */
    struct dirent *e;
    while ((e = readdir(d)) && status == 0) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        struct stat st;
        if (lstat(path, &st) != 0)
            continue;
        const int file = S_ISREG(st.st_mode);
        const int analysis = S_ISDIR(st.st_mode) && strcmp(e->d_name, "analysis") == 0;
        if (!clear) {
            size_t m = file ? matches(e->d_name, run_marks, sizeof run_marks / sizeof *run_marks)
                            : 0;
            if (m && (!best || m < best)) {
                best = m;
                snprintf(mark, mark_size, "%s", e->d_name);
            }
            continue;
        }
        if ((file && matches(e->d_name, run_outputs, sizeof run_outputs / sizeof *run_outputs) &&
             unlink(path) != 0) ||
            (analysis && remove_tree(path) != 0)) {
            snprintf(error, size, "--overwrite: cannot remove '%s': %s", path, strerror(errno));
            status = -1;
        }
    }
    closedir(d);
    return status;
}

int sluice_output_dir_claim(const char *dir, int restart, int overwrite, int *lock_fd,
                            char *error, size_t size)
{
    *lock_fd = -1;
    if (sluice_sim_make_directory(dir, error, size) != 0)
        return SLUICE_OUTPUT_FAILED;
    if (take_lock(dir, lock_fd, error, size) != 0)
        return SLUICE_OUTPUT_REFUSED;
    if (restart)
        return SLUICE_OUTPUT_OK; /* continues the run it holds */
    char mark[256];
    if (scan_outputs(dir, 0, mark, sizeof mark, error, size) != 0)
        return SLUICE_OUTPUT_FAILED;
    if (!*mark)
        return SLUICE_OUTPUT_OK;
    if (!overwrite) {
        snprintf(error, size,
                 "output directory '%s' holds another run (%s): --overwrite replaces it, "
                 "--restart %s/checkpoint_<step>.h5 continues it, or choose another --out",
                 dir, mark, dir);
        return SLUICE_OUTPUT_REFUSED;
    }
    if (scan_outputs(dir, 1, mark, sizeof mark, error, size) != 0)
        return SLUICE_OUTPUT_FAILED;
    return SLUICE_OUTPUT_OK;
}
