/* Files that are never left half-written: whole files replaced atomically,
 * CSV tables appended row by row and continued after a restart only when
 * they start with the checkpointed bytes; the output directory. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <omp.h>

#include "build_config.h"
#include "sim_internal.h"

/* ------------------------------------------------------------------ I/O -- */

int sluice_write_file_atomic(const char *path, const void *data, size_t size, char *error,
                             size_t error_size)
{
    size_t n = strlen(path) + 32;
    char *tmp = malloc(n);
    if (!tmp) {
        snprintf(error, error_size, "out of memory writing '%s'", path);
        return -1;
    }
    snprintf(tmp, n, "%s.tmp.%ld", path, (long)getpid());
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
        free(tmp);
        return -1;
    }
    const char *p = data;
    size_t left = size;
    while (left > 0) {
        ssize_t w = write(fd, p, left);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
            close(fd);
            unlink(tmp);
            free(tmp);
            return -1;
        }
        p += w;
        left -= (size_t)w;
    }
    if (close(fd) != 0) {
        snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
        unlink(tmp);
        free(tmp);
        return -1;
    }
    if (rename(tmp, path) != 0) {
        snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
        unlink(tmp);
        free(tmp);
        return -1;
    }
    free(tmp);
    return 0;
}

/* The child's side of sluice_write_file_with: the writer's message, if
 * any, goes back through the pipe. OpenMP runs on one thread here: GNU
 * libgomp's thread pool does not survive fork, and a parallel region of
 * more threads would wait for it for ever. */
static void write_file_child(const char *temporary, sluice_file_writer write_file, void *context,
                             int pipe_out)
{
    omp_set_num_threads(1);
    char message[1024] = "";
    int rc = write_file(context, temporary, message, sizeof message);
    if (rc != 0) {
        if (!message[0])
            snprintf(message, sizeof message, "the writer failed");
        size_t left = strlen(message);
        const char *p = message;
        while (left > 0) {
            ssize_t w = write(pipe_out, p, left);
            if (w < 0 && errno == EINTR)
                continue;
            if (w <= 0)
                break;
            p += w;
            left -= (size_t)w;
        }
    }
    _exit(rc == 0 ? 0 : 1);
}

/* Waits for the writing child; 0 when it wrote the file. */
static int write_file_wait(pid_t child, int pipe_in, const char *path, char *error,
                           size_t error_size)
{
    size_t used = 0;
    char message[1024];
    for (;;) {
        ssize_t got = read(pipe_in, message + used, sizeof message - 1 - used);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            break;
        used += (size_t)got;
        if (used == sizeof message - 1)
            break;
    }
    message[used] = '\0';
    int status = 0;
    while (waitpid(child, &status, 0) < 0)
        if (errno != EINTR) {
            snprintf(error, error_size, "cannot write '%s': waiting for the writer: %s", path,
                     strerror(errno));
            return -1;
        }
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0)
        return 0;
    if (WIFSIGNALED(status))
        snprintf(error, error_size, "cannot write '%s': the writing process died of signal %d (%s)",
                 path, WTERMSIG(status), strsignal(WTERMSIG(status)));
    else
        snprintf(error, error_size, "cannot write '%s': %s", path,
                 message[0] ? message : "the writer failed");
    return -1;
}

int sluice_write_file_with(const char *path, sluice_file_writer write_file, void *context,
                           char *error, size_t error_size)
{
    size_t n = strlen(path) + 32;
    char *temporary = malloc(n);
    if (!temporary) {
        snprintf(error, error_size, "out of memory writing '%s'", path);
        return -1;
    }
    snprintf(temporary, n, "%s.tmp.%ld", path, (long)getpid());
    int pipe_ends[2] = {-1, -1};
    const pid_t run = getpid();
    pid_t child = pipe2(pipe_ends, O_CLOEXEC) == 0 ? fork() : -1;
    int rc;
    if (child == 0) {
        /* the writer dies with the run (a killed run leaves no process
         * behind that would rename a file into its directory later) */
        if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != run)
            _exit(1);
        close(pipe_ends[0]);
        write_file_child(temporary, write_file, context, pipe_ends[1]);
    }
    if (child > 0) {
        close(pipe_ends[1]);
        rc = write_file_wait(child, pipe_ends[0], path, error, error_size);
        close(pipe_ends[0]);
    } else {
        /* no second process (out of processes or memory): written here */
        if (pipe_ends[0] >= 0) {
            close(pipe_ends[0]);
            close(pipe_ends[1]);
        }
        char message[1024] = "";
        rc = write_file(context, temporary, message, sizeof message) == 0 ? 0 : -1;
        if (rc != 0)
            snprintf(error, error_size, "cannot write '%s': %s", path,
                     message[0] ? message : "the writer failed");
    }
    if (rc == 0 && rename(temporary, path) != 0) {
        snprintf(error, error_size, "cannot write '%s': %s", path, strerror(errno));
        rc = -1;
    }
    if (rc != 0)
        unlink(temporary);
    free(temporary);
    return rc;
}

static int write_all(int fd, const char *data, size_t size)
{
    while (size > 0) {
        ssize_t w = write(fd, data, size);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            return -1;
        }
        data += w;
        size -= (size_t)w;
    }
    return 0;
}

/* The FNV-1a hash of the file's first `bytes` bytes; 0 when it cannot be
 * read. */
static int file_hash(int fd, uint64_t bytes, uint64_t *hash)
{
    char buffer[65536];
    uint64_t h = SLUICE_TABLE_HASH_START, offset = 0;
    while (offset < bytes) {
        size_t want = bytes - offset < sizeof buffer ? (size_t)(bytes - offset) : sizeof buffer;
        ssize_t got = pread(fd, buffer, want, (off_t)offset);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            return 0;
        h = sluice_table_hash_bytes(h, buffer, (size_t)got);
        offset += (uint64_t)got;
    }
    *hash = h;
    return 1;
}

/* A restarted run continues a table that is in the output directory (the
 * same directory as the checkpointed run) from its length at the checkpoint:
 * the rows written after the checkpoint (by the run that went on, or by
 * its finish) are cut off. The file must start with the checkpointed bytes
 * (their hash, when the checkpoint has it): another run's table left in the
 * directory is not cut in the middle of a row but started anew, with a
 * note. Returns the open descriptor, or -1 when the file is missing, shorter
 * or different (then a new file with the header is started). */
static int resume_table(sluice_table *table)
{
    int fd = open(table->path, O_RDWR | O_APPEND | O_CLOEXEC);
    if (fd < 0)
        return -1;
    struct stat st;
    uint64_t hash = 0;
    int same = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
               (uint64_t)st.st_size >= table->resume_bytes &&
               file_hash(fd, table->resume_bytes, &hash) &&
               (!table->resume_hashed || hash == table->resume_hash);
    if (!same || ftruncate(fd, (off_t)table->resume_bytes) != 0) {
        if (!same && !table->sim->quiet)
            fprintf(stderr,
                    "sluice: note: '%s' is not the checkpointed run's table (its first %llu "
                    "bytes differ or are missing): it is started anew\n",
                    table->path, (unsigned long long)table->resume_bytes);
        close(fd);
        return -1;
    }
    table->bytes = table->resume_bytes;
    table->hash = hash;
    return fd;
}

/* Appends one complete line (one write call) to a table, creating the file
 * with its header first. */
int sluice_sim_table_flush_row(sluice_table *table, const char *line, size_t length)
{
    if (table->fd < 0) {
        size_t n = strlen(table->sim->output_directory) + strlen(table->path) + 2;
        char *full = malloc(n);
        if (!full) {
            table->failed = 1;
            return SLUICE_ERROR;
        }
        snprintf(full, n, "%s/%s", table->sim->output_directory, table->path);
        free(table->path);
        table->path = full;
        if (table->resume && table->resume_bytes > 0 &&
            (table->fd = resume_table(table)) >= 0) {
            if (write_all(table->fd, line, length) != 0) {
                table->failed = 1;
                sluice_sim_fail(table->sim, "cannot write '%s': %s", table->path,
                                strerror(errno));
                return SLUICE_ERROR;
            }
            table->bytes += length;
            table->hash = sluice_table_hash_bytes(table->hash, line, length);
            return SLUICE_OK;
        }
        table->fd = open(table->path, O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0644);
        if (table->fd < 0) {
            table->failed = 1;
            sluice_sim_fail(table->sim, "cannot write '%s': %s", table->path, strerror(errno));
            return SLUICE_ERROR;
        }
        size_t hl = strlen(table->header);
        char *header = malloc(hl + 2);
        if (!header) {
            table->failed = 1;
            return SLUICE_ERROR;
        }
        memcpy(header, table->header, hl);
        header[hl] = '\n';
        int rc = write_all(table->fd, header, hl + 1);
        table->bytes = hl + 1;
        table->hash = sluice_table_hash_bytes(SLUICE_TABLE_HASH_START, header, hl + 1);
        free(header);
        if (rc != 0) {
            table->failed = 1;
            sluice_sim_fail(table->sim, "cannot write '%s': %s", table->path, strerror(errno));
            return SLUICE_ERROR;
        }
    }
    if (write_all(table->fd, line, length) != 0) {
        table->failed = 1;
        sluice_sim_fail(table->sim, "cannot write '%s': %s", table->path, strerror(errno));
        return SLUICE_ERROR;
    }
    table->bytes += length;
    table->hash = sluice_table_hash_bytes(table->hash, line, length);
    return SLUICE_OK;
}

int sluice_sim_table_split_header(sluice_table *table)
{
    uint32_t count = 1;
    for (const char *c = table->header; *c; c++)
        count += *c == ',';
    table->columns = calloc(count, sizeof *table->columns);
    if (!table->columns)
        return -1;
    table->column_count = count;
    const char *start = table->header;
    for (uint32_t k = 0; k < count; k++) {
        const char *end = strchr(start, ',');
        size_t length = end ? (size_t)(end - start) : strlen(start);
        table->columns[k].name = strndup(start, length);
        if (!table->columns[k].name)
            return -1;
        start += length + (end ? 1 : 0);
    }
    return 0;
}

void sluice_sim_table_free(sluice_table *table)
{
    if (!table)
        return;
    if (table->fd >= 0)
        close(table->fd);
    for (uint32_t k = 0; table->columns && k < table->column_count; k++) {
        free(table->columns[k].name);
        free(table->columns[k].unit);
        free(table->columns[k].description);
    }
    free(table->columns);
    free(table->name);
    free(table->path);
    free(table->header);
    free(table);
}

static void index_json_string(FILE *f, const char *s)
{
    if (!s) {
        fputs("null", f);
        return;
    }
    fputc('"', f);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(f, "\\%c", c);
        else if (c < 0x20)
            fprintf(f, "\\u%04x", c);
        else
            fputc(c, f);
    }
    fputc('"', f);
}

static void index_table(FILE *f, const sluice_sim *sim, const sluice_table *table)
{
    const sluice_instance *in = &sim->instances[table->instance];
    fprintf(f, "    {\n      \"file\": ");
    index_json_string(f, table->name);
    fprintf(f, ",\n      \"instance\": ");
    index_json_string(f, in->name);
    fprintf(f, ",\n      \"component\": ");
    index_json_string(f, in->component->name);
    fprintf(f, ",\n      \"library\": ");
    index_json_string(f, in->library->name);
    fprintf(f, ",\n      \"columns\": [");
    for (uint32_t k = 0; k < table->column_count; k++) {
        const sluice_table_column_info *c = &table->columns[k];
        fprintf(f, "%s\n        {\"name\": ", k ? "," : "");
        index_json_string(f, c->name);
        fprintf(f, ", \"unit\": ");
        index_json_string(f, c->unit);
        fprintf(f, ", \"description\": ");
        index_json_string(f, c->description);
        if (c->has_position) {
            fprintf(f, ", \"position\": [");
            for (uint32_t d = 0; d < sim->scene.dimensions; d++)
                fprintf(f, "%s%.10g", d ? ", " : "", c->position[d]);
            fprintf(f, "]");
        }
        fprintf(f, "}");
    }
    fprintf(f, "\n      ]\n    }");
}

int sluice_sim_write_table_index(sluice_sim *sim)
{
    if (!sim->output_directory || sim->comm.rank != 0)
        return 0;
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f) {
        fprintf(stderr, "sluice: error: out of memory writing the index of the tables\n");
        return -1;
    }
    fprintf(f, "{\n  \"format\": \"sluice-tables\",\n  \"version\": 1,\n");
    fprintf(f, "  \"dimensions\": %u,\n  \"tables\": [", sim->scene.dimensions);
    for (size_t t = 0; t < sim->table_count; t++) {
        fprintf(f, "%s\n", t ? "," : "");
        index_table(f, sim, sim->tables[t]);
    }
    fprintf(f, "%s]\n}\n", sim->table_count ? "\n  " : "");
    if (fclose(f) != 0) {
        free(text);
        fprintf(stderr, "sluice: error: out of memory writing the index of the tables\n");
        return -1;
    }
    char error[1024];
    size_t n = strlen(sim->output_directory) + sizeof "/tables.json";
    char *path = malloc(n);
    int rc = -1;
    if (!path)
        snprintf(error, sizeof error, "out of memory writing the index of the tables");
    else {
        snprintf(path, n, "%s/tables.json", sim->output_directory);
        rc = sluice_write_file_atomic(path, text, size, error, sizeof error);
    }
    if (rc != 0)
        fprintf(stderr, "sluice: error: %s\n", error);
    free(path);
    free(text);
    return rc;
}

int sluice_sim_make_directory(const char *path, char *error, size_t size)
{
    char *copy = strdup(path);
    if (!copy) {
        snprintf(error, size, "out of memory");
        return -1;
    }
    for (char *p = copy + 1; *p; p++) {
        if (*p != '/')
            continue;
        *p = '\0';
        if (mkdir(copy, 0755) != 0 && errno != EEXIST) {
            snprintf(error, size, "cannot create output directory '%s': %s", copy,
                     strerror(errno));
            free(copy);
            return -1;
        }
        *p = '/';
    }
    if (mkdir(copy, 0755) != 0 && errno != EEXIST) {
        snprintf(error, size, "cannot create output directory '%s': %s", copy, strerror(errno));
        free(copy);
        return -1;
    }
    free(copy);
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) {
        snprintf(error, size, "output path '%s' is not a directory", path);
        return -1;
    }
    if (access(path, W_OK) != 0) {
        snprintf(error, size, "cannot write to output directory '%s': %s", path, strerror(errno));
        return -1;
    }
    return 0;
}
