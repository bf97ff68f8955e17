/* Checkpoints: the complete state of a run after a whole step, in one HDF5
 * file, and the restart from one (docs/reliability.md, "Checkpoints and
 * restart").
 *
 * Layout (format "sluice checkpoint", version 1):
 *  - root attributes: format, format_version, sluice_version, abi_major,
 *    abi_minor, real_size, dimensions, time, dt, dt_limit, step, next_id,
 *    removed, particles_initial, particle_count, particle_steps,
 *    max_density_deviation, neighbour_list_rebuilds, grid_valid, scene (the
 *    resolved scene), plugins (component names in scene order, one a line),
 *    fields (one line per field: name, type, components, in declaration
 *    order);
 *  - /particles/<field>: every field (not only those flagged
 *    SLUICE_FIELD_RESTART: derived fields a hook reads before the first
 *    evaluation of the continued run must be the ones of the checkpointed
 *    step for the continuation to be bit-identical), [components][N] in the
 *    core's own types, particles in the current (sorted) order;
 *  - /core/requests: the requested output times still ahead;
 *    /core/grid_built: [dims][N] positions at the last neighbour-list build
 *    (when the list is valid): the restart rebuilds the same Verlet list
 *    from them, so the continuation rebuilds it exactly when the
 *    uninterrupted run does, and a checkpoint never perturbs the run;
 *    /core/table_bytes with attribute table_names: the length of every table
 *    (CSV) at the checkpoint; /core/table_hashes: the FNV-1a hash of those
 *    bytes (a restart continues a table only if the file there starts with
 *    them: another run's table in the directory is started anew);
 *  - /plugins/<component>/: the arrays a component stored with
 *    api->state->state_write in its save_state callback.
 *
 * HDF5 writes the file straight from the particle store into a temporary
 * file in a child process (sluice_write_file_with: no copy of the file in
 * memory), which is renamed once whole: a killed run never leaves a
 * half-written checkpoint. Across MPI ranks (with a parallel HDF5) every rank writes its
 * particles into <path>.partial, which rank 0 renames once whole
 * (checkpoint_shared). */
#define _GNU_SOURCE
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "build_config.h"
#include "ranks.h"
#include "schema.h"
#include "decomposition.h"
#include "file_checksum.h"
#include "sim_internal.h"
#include "yaml_tree.h"

#define CHECKPOINT_FORMAT "sluice checkpoint"
#define CHECKPOINT_VERSION 1

/* Across MPI ranks with a parallel HDF5, every rank writes its particles
 * into one file (parallel HDF5) instead of gathering them on rank 0. */
#if defined(SLUICE_MPI) && defined(H5_HAVE_PARALLEL)
#define CK_PARALLEL 1
#else
#define CK_PARALLEL 0
#endif

typedef struct ck_error {
    char text[1024];
    /* a checkpoint every rank writes (CK_PARALLEL): the calls are
     * collective; rank 0 (`writer`) alone writes the data that are not
     * particles, the particles go to [offset, offset + count) of `total`
     * rows, with the collective transfer list `transfer` */
    int shared, writer;
    hid_t transfer;
    hsize_t offset, total;
#if CK_PARALLEL
    MPI_Comm comm;
#endif
} ck_error;

/* api->state_* while a component saves or loads its state: the store lent
 * to the engine around each save_state or load_state call (end of file). */
static int state_write(sluice_host *host, const char *name, sluice_state_type state_type,
                       uint64_t count, const void *data);
static int state_read(sluice_host *host, const char *name, sluice_state_type state_type,
                      uint64_t count, void *data);
static int64_t state_length(sluice_host *host, const char *name);
static const sluice_state_store checkpoint_store = {state_write, state_read, state_length};

static ck_error ck_clear(void)
{
    ck_error e;
    memset(&e, 0, sizeof e);
    e.transfer = H5P_DEFAULT;
    return e;
}

static herr_t innermost_error(unsigned n, const H5E_error2_t *e, void *data)
{
    ck_error *f = data;
    if (n == 0 && e && e->desc && e->desc[0]) {
        size_t used = strlen(f->text);
        /* a failed system call: the system's message, not HDF5's record of
         * the time, descriptor and buffer */
        const char *system = strstr(e->desc, "error message = '");
        const char *end = system ? strchr(system + 17, '\'') : NULL;
        if (system && end) {
            snprintf(f->text + used, sizeof f->text - used, ": %.*s", (int)(end - system - 17),
                     system + 17);
            return 0;
        }
        snprintf(f->text + used, sizeof f->text - used, " (HDF5: %s)", e->desc);
        for (char *p = f->text + used; *p; p++)
            if (*p == '\n' || *p == '\r' || *p == '\t')
                *p = ' ';
    }
    return 0;
}

static void fail(ck_error *e, const char *format, ...) SLUICE_PRINTF(2, 3);
static void fail(ck_error *e, const char *format, ...)
{
    if (e->text[0])
        return; /* keep the first cause */
    va_list ap;
    va_start(ap, format);
    vsnprintf(e->text, sizeof e->text, format, ap);
    va_end(ap);
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost_error, e);
    H5Eclear2(H5E_DEFAULT);
}

static void close_id(hid_t *id, herr_t (*closer)(hid_t))
{
    if (*id >= 0)
        closer(*id);
    *id = -1;
}

/* HDF5 prints nothing: errors are reported once, by us. */
typedef struct quiet_hdf5 {
    H5E_auto2_t func;
    void *data;
} quiet_hdf5;

static void quiet_begin(quiet_hdf5 *q)
{
    H5Eget_auto2(H5E_DEFAULT, &q->func, &q->data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

static void quiet_end(const quiet_hdf5 *q)
{
    H5Eclear2(H5E_DEFAULT);
    H5Eset_auto2(H5E_DEFAULT, q->func, q->data);
}

/* Element types of the datasets: the field types (sluice_type) and, above
 * them, those of plugin state arrays (sluice_state_type). */
enum { CK_DOUBLE = 101, CK_INT64 = 102, CK_UINT64 = 103 };

static int state_kind(sluice_state_type t)
{
    switch (t) {
    case SLUICE_STATE_DOUBLE: return CK_DOUBLE;
    case SLUICE_STATE_INT64: return CK_INT64;
    case SLUICE_STATE_UINT64: return CK_UINT64;
    }
    return -1;
}

static const char *type_label(int t)
{
    switch (t) {
    case SLUICE_TYPE_REAL: return "real";
    case SLUICE_TYPE_INT32: return "int32";
    case SLUICE_TYPE_UINT8: return "uint8";
    case SLUICE_TYPE_ID: return "id";
    case CK_DOUBLE: return "double";
    case CK_INT64: return "int64";
    case CK_UINT64: return "uint64";
    }
    return "unknown";
}

static hid_t native_type(int t)
{
    switch (t) {
    case SLUICE_TYPE_REAL:
        return sizeof(sluice_real) == sizeof(float) ? H5T_NATIVE_FLOAT : H5T_NATIVE_DOUBLE;
    case SLUICE_TYPE_INT32: return H5T_NATIVE_INT32;
    case SLUICE_TYPE_UINT8: return H5T_NATIVE_UINT8;
    case SLUICE_TYPE_ID:
    case CK_UINT64: return H5T_NATIVE_UINT64;
    case CK_DOUBLE: return H5T_NATIVE_DOUBLE;
    case CK_INT64: return H5T_NATIVE_INT64;
    }
    return -1;
}

/* 1 when the stored type is the memory type (same class, size and sign). */
static int same_type(hid_t stored, hid_t memory)
{
    H5T_class_t c = H5Tget_class(stored);
    if (c != H5Tget_class(memory) || H5Tget_size(stored) != H5Tget_size(memory))
        return 0;
    return c != H5T_INTEGER || H5Tget_sign(stored) == H5Tget_sign(memory);
}

/* ------------------------------------------------------------- writing -- */

static void put_attr(hid_t object, const char *name, hid_t type, const void *value, ck_error *e)
{
    if (e->text[0])
        return;
    hid_t space = H5Screate(H5S_SCALAR), attr = -1;
    if (space < 0 || (attr = H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT)) < 0 ||
        H5Awrite(attr, type, value) < 0)
        fail(e, "writing attribute '%s' failed", name);
    close_id(&attr, H5Aclose);
    close_id(&space, H5Sclose);
}

static void put_string(hid_t object, const char *name, const char *value, ck_error *e)
{
    if (e->text[0])
        return;
    hid_t type = H5Tcopy(H5T_C_S1);
    if (type < 0 || H5Tset_size(type, H5T_VARIABLE) < 0 || H5Tset_cset(type, H5T_CSET_UTF8) < 0) {
        fail(e, "making the string type of attribute '%s' failed", name);
    } else {
        const char *text = value ? value : "";
        put_attr(object, name, type, &text, e);
    }
    close_id(&type, H5Tclose);
}

/* A dataset of `rank` 1 (length elements at rows[0]) or 2 (`rows` rows of
 * `length` elements, row r at data[r]). */
static void put_rows(hid_t loc, const char *name, int type, int rank, hsize_t rows,
                     hsize_t length, const void *const *data, ck_error *e)
{
    if (e->text[0])
        return;
#if CK_PARALLEL
    if (e->shared) { /* rank 0's shape on every rank (the calls are collective) */
        unsigned long long shape[2] = {rows, length};
        MPI_Bcast(shape, 2, MPI_UNSIGNED_LONG_LONG, 0, e->comm);
        rows = shape[0];
        length = shape[1];
    }
#endif
    const int skip = e->shared && !e->writer; /* takes part, writes nothing */
    const char dummy = 0;
    hsize_t dims[2] = {rank == 2 ? rows : length, length};
    hid_t t = native_type(type);
    hid_t space = H5Screate_simple(rank, dims, NULL), set = -1, memory = -1;
    if (space < 0 ||
        (set = H5Dcreate2(loc, name, t, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)) < 0) {
        fail(e, "creating dataset '%s' failed", name);
    } else if (length > 0) {
        hsize_t one[1] = {length};
        memory = H5Screate_simple(1, one, NULL);
        for (hsize_t r = 0; r < (rank == 2 ? rows : 1) && !e->text[0]; r++) {
            hsize_t start[2] = {r, 0}, count[2] = {1, length};
            if (rank == 2 &&
                H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL) < 0) {
                fail(e, "selecting row %llu of dataset '%s' failed", (unsigned long long)r,
                     name);
                break;
            }
            if (skip && (H5Sselect_none(space) < 0 || (memory >= 0 && H5Sselect_none(memory) < 0)))
                fail(e, "selecting nothing of dataset '%s' failed", name);
            if (memory < 0 || e->text[0] ||
                H5Dwrite(set, t, rank == 2 || skip ? memory : H5S_ALL,
                         rank == 2 || skip ? space : H5S_ALL, e->shared ? e->transfer : H5P_DEFAULT,
                         skip ? (const void *)&dummy : data[r]) < 0)
                fail(e, "writing dataset '%s' failed", name);
        }
    }
    close_id(&memory, H5Sclose);
    close_id(&set, H5Dclose);
    close_id(&space, H5Sclose);
}

/* The particles' rows of a field, [rows][count] of this process, at the
 * columns [e->offset, e->offset + count) of a dataset [rows][e->total] (a
 * shared checkpoint), or the whole dataset. */
static void put_particles(hid_t loc, const char *name, int type, hsize_t rows, hsize_t count,
                          const void *const *data, ck_error *e)
{
    if (!e->shared) {
        put_rows(loc, name, type, 2, rows, count, data, e);
        return;
    }
    if (e->text[0])
        return;
    const char dummy = 0;
    hsize_t dims[2] = {rows, e->total}, own[1] = {count > 0 ? count : 1};
    hid_t t = native_type(type);
    hid_t space = H5Screate_simple(2, dims, NULL), set = -1;
    hid_t memory = H5Screate_simple(1, own, NULL);
    if (space < 0 || memory < 0 ||
        (set = H5Dcreate2(loc, name, t, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)) < 0)
        fail(e, "creating dataset '%s' failed", name);
    for (hsize_t r = 0; r < rows && e->total > 0 && !e->text[0]; r++) {
        hsize_t start[2] = {r, e->offset}, size[2] = {1, count};
        if (count > 0 ? H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, size, NULL) < 0
                      : H5Sselect_none(space) < 0 || H5Sselect_none(memory) < 0) {
            fail(e, "selecting this rank's part of dataset '%s' failed", name);
            break;
        }
        if (H5Dwrite(set, t, memory, space, e->transfer,
                     count > 0 ? data[r] : (const void *)&dummy) < 0)
            fail(e, "writing dataset '%s' failed", name);
    }
    close_id(&memory, H5Sclose);
    close_id(&set, H5Dclose);
    close_id(&space, H5Sclose);
}

/* The layout lines the restart compares: plugins and fields. */
static char *plugin_lines(const sluice_sim *sim)
{
    size_t size = 1;
    for (uint32_t k = 0; k < sim->instance_count; k++)
        size += strlen(sim->instances[k].name) + 1;
    char *text = malloc(size), *p = text;
    if (!text)
        return NULL;
    for (uint32_t k = 0; k < sim->instance_count; k++)
        p += sprintf(p, "%s\n", sim->instances[k].name);
    *p = '\0';
    return text;
}

static char *field_lines(const sluice_sim *sim)
{
    size_t size = 1;
    for (uint32_t f = 0; f < sim->field_count; f++)
        size += strlen(sim->fields[f].name) + 32;
    char *text = malloc(size), *p = text;
    if (!text)
        return NULL;
    for (uint32_t f = 0; f < sim->field_count; f++)
        p += sprintf(p, "%s %s %u\n", sim->fields[f].name, type_label(sim->fields[f].type),
                     sim->fields[f].components);
    *p = '\0';
    return text;
}

static void write_state(sluice_sim *sim, hid_t file, ck_error *e)
{
    const sluice_index n = sim->particles.count;
    const uint32_t dims = sim->scene.dimensions;
    char *plugins = plugin_lines(sim), *fields = field_lines(sim);
    if (!plugins || !fields)
        fail(e, "out of memory");
    int version = CHECKPOINT_VERSION, major = SLUICE_ABI_MAJOR, minor = SLUICE_ABI_MINOR;
    int real_size = (int)sizeof(sluice_real), dimensions = (int)dims;
    /* across ranks the particles are the gathered ones and the grids are
     * the ranks' own: the restart rebuilds the neighbour lists */
    int grid_valid = sim->comm.size == 1 && sim->grid.valid && sim->grid.count == n;
    uint64_t count = e->shared ? (uint64_t)e->total : n, next_id = sim->next_id, removed = sim->removed,
             initial = sim->particles_initial, steps = sim->particle_steps,
             rebuilds = sim->grid.rebuilds;
    int64_t step = sim->step;
    put_string(file, "format", CHECKPOINT_FORMAT, e);
    put_attr(file, "format_version", H5T_NATIVE_INT, &version, e);
    put_string(file, "sluice_version", SLUICE_VERSION, e);
    /* provenance, as in run.json and the snapshots */
    static const char *const provenance[] = {"git_revision", "build", "command_line", "date",
                                             "host"};
    for (size_t k = 0; k < sizeof provenance / sizeof *provenance; k++)
        put_string(file, provenance[k], sluice_sim_describe(sim, provenance[k]), e);
    put_attr(file, "abi_major", H5T_NATIVE_INT, &major, e);
    put_attr(file, "abi_minor", H5T_NATIVE_INT, &minor, e);
    put_attr(file, "real_size", H5T_NATIVE_INT, &real_size, e);
    put_attr(file, "dimensions", H5T_NATIVE_INT, &dimensions, e);
    put_attr(file, "time", H5T_NATIVE_DOUBLE, &sim->time, e);
    put_attr(file, "dt", H5T_NATIVE_DOUBLE, &sim->dt, e);
    put_attr(file, "dt_limit", H5T_NATIVE_DOUBLE, &sim->dt_limit, e);
    put_attr(file, "step", H5T_NATIVE_INT64, &step, e);
    put_attr(file, "next_id", H5T_NATIVE_UINT64, &next_id, e);
    put_attr(file, "removed", H5T_NATIVE_UINT64, &removed, e);
    put_attr(file, "particles_initial", H5T_NATIVE_UINT64, &initial, e);
    put_attr(file, "particle_count", H5T_NATIVE_UINT64, &count, e);
    put_attr(file, "particle_steps", H5T_NATIVE_UINT64, &steps, e);
    put_attr(file, "max_density_deviation", H5T_NATIVE_DOUBLE, &sim->max_density_deviation, e);
    put_attr(file, "neighbour_list_rebuilds", H5T_NATIVE_UINT64, &rebuilds, e);
    put_attr(file, "grid_valid", H5T_NATIVE_INT, &grid_valid, e);
    put_string(file, "scene", sim->resolved_scene, e);
    put_string(file, "plugins", plugins, e);
    put_string(file, "fields", fields, e);
    free(plugins);
    free(fields);

    hid_t group = e->text[0] ? -1 : H5Gcreate2(file, "particles", H5P_DEFAULT, H5P_DEFAULT,
                                                H5P_DEFAULT);
    if (group < 0)
        fail(e, "creating group 'particles' failed");
    for (uint32_t f = 0; f < sim->field_count && !e->text[0]; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        const void *rows[16];
        for (uint32_t c = 0; c < field->components; c++)
            rows[c] = sim->particles.columns[field->column + (int32_t)c];
        put_particles(group, field->name, field->type, field->components, n, rows, e);
    }
    close_id(&group, H5Gclose);

    group = e->text[0] ? -1 : H5Gcreate2(file, "core", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (group < 0)
        fail(e, "creating group 'core' failed");
    /* requests still ahead */
    double *ahead = malloc((sim->request_count + 1) * sizeof *ahead);
    uint64_t *bytes = malloc((2 * sim->table_count + 1) * sizeof *bytes);
    size_t names_size = 1;
    for (size_t t = 0; t < sim->table_count; t++)
        names_size += strlen(sim->tables[t]->path) + 1;
    char *names = malloc(names_size);
    if (!ahead || !bytes || !names) {
        fail(e, "out of memory");
    } else {
        size_t m = 0;
        for (size_t i = 0; i < sim->request_count; i++)
            if (sim->requests[i] > sim->time)
                ahead[m++] = sim->requests[i];
        const void *row[1] = {ahead};
        put_rows(group, "requests", CK_DOUBLE, 1, 1, m, row, e);
        char *p = names;
        *p = '\0';
        for (size_t t = 0; t < sim->table_count; t++) {
            const char *path = sim->tables[t]->path, *slash = strrchr(path, '/');
            p += sprintf(p, "%s\n", slash ? slash + 1 : path);
            bytes[t] = sim->tables[t]->bytes;
            bytes[sim->table_count + t] = sim->tables[t]->hash;
        }
        row[0] = bytes;
        put_rows(group, "table_bytes", CK_UINT64, 1, 1, sim->table_count, row, e);
        row[0] = bytes + sim->table_count;
        put_rows(group, "table_hashes", CK_UINT64, 1, 1, sim->table_count, row, e);
        put_string(group, "table_names", names, e);
    }
    free(ahead);
    free(bytes);
    free(names);
    if (grid_valid && !e->text[0]) {
        const void *rows[3] = {sim->grid.built[0], sim->grid.built[1], sim->grid.built[2]};
        put_rows(group, "grid_built", SLUICE_TYPE_REAL, 2, dims, n, rows, e);
    }
    close_id(&group, H5Gclose);

    group = e->text[0] ? -1 : H5Gcreate2(file, "plugins", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (group < 0)
        fail(e, "creating group 'plugins' failed");
    for (uint32_t k = 0; k < sim->instance_count && !e->text[0]; k++) {
        sluice_instance *in = &sim->instances[k];
        if (!in->component->save_state)
            continue;
        hid_t own = H5Gcreate2(group, in->name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (own < 0) {
            fail(e, "creating group 'plugins/%s' failed", in->name);
            break;
        }
        sim->state_group = own;
        sim->state_instance = k;
        sim->state_writing = 1;
        sim->state_context = e;
        sim->state_store = &checkpoint_store;
        int rc = in->component->save_state(in->state, &in->host);
        sim->state_store = NULL;
        sim->state_group = -1;
        sim->state_writing = 0;
        sim->state_context = NULL;
        H5Gclose(own);
        if (rc != SLUICE_OK || sim->failure[0])
            fail(e, "plugin '%s' failed to save its state%s%s", in->name,
                 sim->failure[0] ? ": " : "", sim->failure);
    }
    close_id(&group, H5Gclose);
}

/* The checkpoint file of the current state, written by HDF5 straight to
 * `temporary` (sluice_write_file_with runs this in a child process: a full
 * disk cannot leave HDF5 half-closed in the run), then its checksum
 * trailer. */
static int write_checkpoint_file(void *context, const char *temporary, char *error,
                                 size_t error_size)
{
    sluice_sim *sim = context;
    quiet_hdf5 q;
    quiet_begin(&q);
    ck_error e = ck_clear();
    errno = 0;
    hid_t file = H5Fcreate(temporary, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file < 0)
        fail(&e, "cannot create it: %s", errno ? strerror(errno) : "H5Fcreate failed");
    else
        write_state(sim, file, &e);
    if (file >= 0 && H5Fclose(file) < 0 && !e.text[0])
        fail(&e, "%s", errno ? strerror(errno) : "H5Fclose failed");
    quiet_end(&q);
    char sum_error[600];
    if (!e.text[0] && sluice_checksum_append(temporary, sum_error, sizeof sum_error) != 0)
        fail(&e, "%s", sum_error);
    if (e.text[0]) {
        snprintf(error, error_size, "%s", e.text);
        return -1;
    }
    return 0;
}

/* After a checkpoint is on disk: the message, and the newest kept. */
static int checkpoint_written(sluice_sim *sim, const char *path, const char *full,
                              double started, size_t size)
{
    sim->checkpoint_step = sim->step;
    if (!sim->quiet && sim->comm.rank == 0)
        fprintf(stderr, "%ssluice: checkpoint %s: step %lld, t = %.9g s, %zu bytes, %.3f s\n",
                sim->progress ? "\n" : "", path, (long long)sim->step, sim->time, size,
                sluice_wall_clock() - started);
    if (path != full || sim->comm.rank != 0)
        return SLUICE_OK;
    /* this run's checkpoints in the output directory: keep the newest */
    char **grown = realloc(sim->checkpoint_files,
                           (sim->checkpoint_file_count + 1) * sizeof *grown);
    char *copy = strdup(full);
    if (grown)
        sim->checkpoint_files = grown;
    if (!grown || !copy) {
        free(copy);
        sluice_sim_fail(sim, "out of memory");
        return SLUICE_ERROR;
    }
    size_t same = sim->checkpoint_file_count;
    for (size_t c = 0; c < sim->checkpoint_file_count; c++)
        if (strcmp(sim->checkpoint_files[c], copy) == 0)
            same = c;
    if (same < sim->checkpoint_file_count) { /* rewritten: it is the newest now */
        free(sim->checkpoint_files[same]);
        memmove(sim->checkpoint_files + same, sim->checkpoint_files + same + 1,
                (sim->checkpoint_file_count - same - 1) * sizeof *sim->checkpoint_files);
        sim->checkpoint_file_count--;
    }
    sim->checkpoint_files[sim->checkpoint_file_count++] = copy;
    const size_t keep = (size_t)sim->scene.checkpoint.keep;
    while (keep > 0 && sim->checkpoint_file_count > keep) {
        if (unlink(sim->checkpoint_files[0]) != 0 && errno != ENOENT)
            fprintf(stderr, "sluice: warning: cannot delete old checkpoint '%s': %s\n",
                    sim->checkpoint_files[0], strerror(errno));
        free(sim->checkpoint_files[0]);
        memmove(sim->checkpoint_files, sim->checkpoint_files + 1,
                (sim->checkpoint_file_count - 1) * sizeof *sim->checkpoint_files);
        sim->checkpoint_file_count--;
    }
    return SLUICE_OK;
}

#if CK_PARALLEL
/* Across ranks: every rank writes its particles into one file of the
 * one-process layout with parallel HDF5 (as the hdf5 writer's snapshots),
 * opened collectively as <path>.partial and renamed by rank 0 once every
 * rank has closed it; rank 0 writes what is not particles (its plugins'
 * state, which a plugin keeps alike on every rank). The run's counters are
 * summed over the ranks for the file. Collective. Returns the file's size,
 * or 0 with `why` set. */
static size_t checkpoint_shared(sluice_sim *sim, const char *path, char *why, size_t why_size)
{
    const sluice_comm *c = &sim->comm;
    ck_error e = ck_clear();
    e.shared = 1;
    e.writer = c->rank == 0;
    e.comm = c->comm;
    uint64_t offset = 0, total = 0;
    double sums[2] = {(double)sim->removed, (double)sim->particle_steps};
    double largest[3] = {(double)sim->next_id, sim->max_density_deviation,
                         (double)sim->grid.rebuilds};
    if (sluice_comm_offset(c, sim->particles.count, &offset, &total) != 0 ||
        sluice_comm_reduce(c, sums, 2, SLUICE_REDUCE_SUM) != 0 ||
        sluice_comm_reduce(c, largest, 3, SLUICE_REDUCE_MAX) != 0) {
        snprintf(why, why_size, "MPI failed");
        return 0;
    }
    e.offset = offset;
    e.total = total;
    const uint64_t own_removed = sim->removed, own_steps = sim->particle_steps,
                   own_next_id = sim->next_id, own_rebuilds = sim->grid.rebuilds;
    const double own_deviation = sim->max_density_deviation;
    sim->removed = (uint64_t)sums[0];
    sim->particle_steps = (uint64_t)sums[1];
    sim->next_id = (uint64_t)largest[0];
    sim->max_density_deviation = largest[1];
    sim->grid.rebuilds = (uint64_t)largest[2];
    char partial[4200];
    snprintf(partial, sizeof partial, "%s.partial", path);
    quiet_hdf5 q;
    quiet_begin(&q);
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS), file = -1;
    e.transfer = H5Pcreate(H5P_DATASET_XFER);
    if (fapl < 0 || e.transfer < 0 || H5Pset_fapl_mpio(fapl, c->comm, MPI_INFO_NULL) < 0 ||
        H5Pset_dxpl_mpio(e.transfer, H5FD_MPIO_COLLECTIVE) < 0)
        fail(&e, "setting up parallel HDF5 failed");
    else if ((file = H5Fcreate(partial, H5F_ACC_TRUNC, H5P_DEFAULT, fapl)) < 0)
        fail(&e, "cannot create '%s'", partial);
    if (!e.text[0])
        write_state(sim, file, &e);
    if (file >= 0 && H5Fclose(file) < 0)
        fail(&e, "H5Fclose failed");
    close_id(&fapl, H5Pclose);
    close_id(&e.transfer, H5Pclose);
    quiet_end(&q);
    sim->removed = own_removed;
    sim->particle_steps = own_steps;
    sim->next_id = own_next_id;
    sim->max_density_deviation = own_deviation;
    sim->grid.rebuilds = own_rebuilds;
    /* whole once every rank has closed it */
    if (sluice_comm_any(c, e.text[0] != 0) && !e.text[0])
        fail(&e, "another rank failed to write its part");
    size_t size = 0;
    if (c->rank == 0) {
        struct stat st;
        char sum_error[600];
        if (e.text[0])
            unlink(partial);
        else if (sluice_checksum_append(partial, sum_error, sizeof sum_error) != 0)
            fail(&e, "%s", sum_error);
        else if (stat(partial, &st) != 0 || rename(partial, path) != 0)
            fail(&e, "cannot rename '%s' to '%s': %s", partial, path, strerror(errno));
        else
            size = (size_t)st.st_size;
    }
    if (sluice_comm_any(c, e.text[0] != 0)) {
        snprintf(why, why_size, "%s", e.text[0] ? e.text : "rank 0 failed to rename it");
        return 0;
    }
    return size > 0 ? size : 1;
}
#endif

int sluice_sim_checkpoint(sluice_sim *sim, const char *path)
{
    char name[64], full[4096];
    if (!path) {
        if (!sim->output_directory) {
            sluice_sim_fail(sim, "a checkpoint needs an output directory");
            return SLUICE_ERROR;
        }
        snprintf(name, sizeof name, "checkpoint_%09lld.h5", (long long)sim->step);
        if (snprintf(full, sizeof full, "%s/%s", sim->output_directory, name) >= (int)sizeof full) {
            sluice_sim_fail(sim, "the checkpoint path in '%s' is too long", sim->output_directory);
            return SLUICE_ERROR;
        }
        path = full;
    }
    sim->state_file = path;
    const double started = sluice_wall_clock();
    size_t size = 0;
    char why[1400] = "";
    int rc = 0;
#if CK_PARALLEL
    if (sim->comm.size > 1) {
        size = checkpoint_shared(sim, path, why, sizeof why);
        sim->state_file = NULL;
        if (size == 0) {
            sluice_sim_fail(sim, "cannot write checkpoint '%s' (step %lld, t = %.9g s): %s",
                            path, (long long)sim->step, sim->time, why);
            return SLUICE_ERROR;
        }
        return checkpoint_written(sim, path, full, started, size);
    }
#endif
#ifdef SLUICE_MPI
    /* Across ranks rank 0 writes the one-process checkpoint of every rank's
     * particles (gathered in rank order) and of its plugins' state, which a
     * plugin keeps alike on every rank; a restart on any number of ranks
     * reads it (docs/scaling.md). */
    sluice_particles all, own;
    uint64_t own_removed = sim->removed, own_steps = sim->particle_steps,
             own_next_id = sim->next_id;
    if (sim->comm.size > 1) {
        double sums[2] = {(double)sim->removed, (double)sim->particle_steps};
        /* the ids of every rank are below the largest next id */
        double next_id = (double)sim->next_id;
        if (sluice_ranks_gather(&sim->ranks_run, &all) != 0 ||
            sluice_comm_reduce(&sim->comm, sums, 2, SLUICE_REDUCE_SUM) != 0 ||
            sluice_comm_reduce(&sim->comm, &next_id, 1, SLUICE_REDUCE_MAX) != 0) {
            sim->state_file = NULL;
            sluice_sim_fail(sim, "cannot write checkpoint '%s' (step %lld, t = %.9g s): out of "
                                 "memory or MPI failed gathering the particles on rank 0",
                            path, (long long)sim->step, sim->time);
            return SLUICE_ERROR;
        }
        if (sim->comm.rank == 0) {
            own = sim->particles;
            sim->particles = all;
            sim->removed = (uint64_t)sums[0];
            sim->particle_steps = (uint64_t)sums[1];
            sim->next_id = (uint64_t)next_id;
        }
    }
    if (sim->comm.rank == 0)
        rc = sluice_write_file_with(path, write_checkpoint_file, sim, why, sizeof why);
    if (sim->comm.size > 1 && sim->comm.rank == 0) {
        sim->particles = own;
        sluice_particles_free(&all);
        sim->removed = own_removed;
        sim->particle_steps = own_steps;
        sim->next_id = own_next_id;
    }
#else
    rc = sluice_write_file_with(path, write_checkpoint_file, sim, why, sizeof why);
#endif
    sim->state_file = NULL;
    struct stat st;
    if (rc == 0 && sim->comm.rank == 0 && stat(path, &st) == 0)
        size = (size_t)st.st_size;
    if (sluice_comm_any(&sim->comm, rc != 0)) {
        if (why[0]) /* names the file */
            sluice_sim_fail(sim, "%s (the checkpoint of step %lld, t = %.9g s)", why,
                            (long long)sim->step, sim->time);
        else
            sluice_sim_fail(sim, "cannot write checkpoint '%s' (step %lld, t = %.9g s): rank 0 "
                                 "failed",
                            path, (long long)sim->step, sim->time);
        return SLUICE_ERROR;
    }
    return checkpoint_written(sim, path, full, started, size);
}

/* ------------------------------------------------------------- reading -- */

static int get_attr(hid_t object, const char *name, hid_t memory, void *value, ck_error *e)
{
    if (e->text[0])
        return -1;
    if (H5Aexists(object, name) <= 0) {
        fail(e, "attribute '%s' is missing", name);
        return -1;
    }
    hid_t attr = H5Aopen(object, name, H5P_DEFAULT), type = -1, space = -1;
    if (attr < 0 || (type = H5Aget_type(attr)) < 0 || (space = H5Aget_space(attr)) < 0)
        fail(e, "attribute '%s' cannot be read", name);
    else if (!same_type(type, memory) || H5Sget_simple_extent_npoints(space) != 1)
        fail(e, "attribute '%s' has the wrong type", name);
    else if (H5Aread(attr, memory, value) < 0)
        fail(e, "attribute '%s' cannot be read", name);
    close_id(&space, H5Sclose);
    close_id(&type, H5Tclose);
    close_id(&attr, H5Aclose);
    return e->text[0] ? -1 : 0;
}

/* A variable-length string attribute, copied (malloc'd). */
static char *get_string(hid_t object, const char *name, ck_error *e)
{
    if (e->text[0])
        return NULL;
    if (H5Aexists(object, name) <= 0) {
        fail(e, "attribute '%s' is missing", name);
        return NULL;
    }
    char *copy = NULL;
    hid_t attr = H5Aopen(object, name, H5P_DEFAULT), type = -1, memory = -1, space = -1;
    if (attr < 0 || (type = H5Aget_type(attr)) < 0 || (space = H5Aget_space(attr)) < 0) {
        fail(e, "attribute '%s' cannot be read", name);
    } else if (H5Tget_class(type) != H5T_STRING || H5Tis_variable_str(type) <= 0 ||
               H5Sget_simple_extent_npoints(space) != 1) {
        fail(e, "attribute '%s' is not a string", name);
    } else if ((memory = H5Tget_native_type(type, H5T_DIR_ASCEND)) < 0) {
        fail(e, "attribute '%s' cannot be read", name);
    } else {
        char *text = NULL;
        if (H5Aread(attr, memory, &text) < 0 || !text) {
            fail(e, "attribute '%s' cannot be read", name);
        } else {
            copy = strdup(text);
            if (!copy)
                fail(e, "out of memory");
        }
        if (text)
            H5Dvlen_reclaim(memory, space, H5P_DEFAULT, &text);
    }
    close_id(&memory, H5Tclose);
    close_id(&space, H5Sclose);
    close_id(&type, H5Tclose);
    close_id(&attr, H5Aclose);
    return copy;
}

/* rows_length of a dataset whose extent the file does not hold: declared
 * without its data (never written, or chunks missing), which a restart
 * must not allocate for. */
#define CK_UNSTORED (-2)

/* Length of the last dimension of dataset `name` of the given rank (its
 * first dimension `rows` for rank 2), -1 when absent or of another shape,
 * CK_UNSTORED when the file holds fewer bytes than its extent needs. */
static int64_t rows_length(hid_t loc, const char *name, int rank, hsize_t rows)
{
    if (H5Lexists(loc, name, H5P_DEFAULT) <= 0)
        return -1;
    hid_t set = H5Dopen2(loc, name, H5P_DEFAULT), space = -1, type = -1;
    int64_t length = -1;
    hsize_t dims[2] = {0, 0};
    if (set >= 0 && (space = H5Dget_space(set)) >= 0 && (type = H5Dget_type(set)) >= 0 &&
        H5Sget_simple_extent_ndims(space) == rank && H5Sget_simple_extent_dims(space, dims, NULL) == rank &&
        (rank == 1 || dims[0] == rows) && dims[rank - 1] <= (hsize_t)INT64_MAX) {
        /* the checkpoint's datasets are contiguous and unfiltered: their
         * storage is every value's bytes */
        const hsize_t n = dims[rank - 1], width = rank == 2 ? dims[0] : 1;
        const hsize_t size = H5Tget_size(type);
        length = (int64_t)n;
        if (size == 0)
            length = -1;
        else if (n > 0 && width > 0 &&
                 (n > UINT64_MAX / width / size || H5Dget_storage_size(set) < n * width * size))
            length = CK_UNSTORED;
    }
    close_id(&type, H5Tclose);
    close_id(&space, H5Sclose);
    close_id(&set, H5Dclose);
    return length;
}

/* Dataset `name` has the shape get_rows reads (and its values are in the
 * file); otherwise a message. */
static int check_rows(hid_t loc, const char *name, int rank, hsize_t rows, hsize_t length,
                      ck_error *e)
{
    if (e->text[0])
        return -1;
    const int64_t have = rows_length(loc, name, rank, rows);
    if (have == (int64_t)length)
        return 0;
    if (have == CK_UNSTORED)
        fail(e, "dataset '%s' declares more values than the file holds", name);
    else if (rank == 2)
        fail(e, "dataset '%s' is missing or is not %llu x %llu", name, (unsigned long long)rows,
             (unsigned long long)length);
    else
        fail(e, "dataset '%s' is missing or does not hold %llu values", name,
             (unsigned long long)length);
    return -1;
}

/* Reads a dataset written by put_rows, checking its type and shape. */
static int get_rows(hid_t loc, const char *name, int type, int rank, hsize_t rows,
                    hsize_t length, void *const *data, ck_error *e)
{
    if (check_rows(loc, name, rank, rows, length, e) != 0)
        return -1;
    hid_t t = native_type(type);
    hid_t set = H5Dopen2(loc, name, H5P_DEFAULT), stored = -1, space = -1, memory = -1;
    if (set < 0 || (stored = H5Dget_type(set)) < 0 || (space = H5Dget_space(set)) < 0) {
        fail(e, "dataset '%s' cannot be read", name);
    } else if (!same_type(stored, t)) {
        fail(e, "dataset '%s' is not of type %s", name, type_label(type));
    } else if (length > 0) {
        hsize_t one[1] = {length};
        memory = H5Screate_simple(1, one, NULL);
        for (hsize_t r = 0; r < (rank == 2 ? rows : 1) && !e->text[0]; r++) {
            if (rank == 2) {
                hsize_t start[2] = {r, 0}, count[2] = {1, length};
                if (H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL) < 0) {
                    fail(e, "dataset '%s' cannot be read", name);
                    break;
                }
            }
            if (memory < 0 || H5Dread(set, t, rank == 2 ? memory : H5S_ALL,
                                      rank == 2 ? space : H5S_ALL, H5P_DEFAULT, data[r]) < 0)
                fail(e, "dataset '%s' cannot be read (is the file truncated?)", name);
        }
    }
    close_id(&memory, H5Sclose);
    close_id(&space, H5Sclose);
    close_id(&stored, H5Tclose);
    close_id(&set, H5Dclose);
    return e->text[0] ? -1 : 0;
}

/* Text of the file in a message: the first `length` bytes (at most 64) of
 * it, each control character a '?', so that the message stays one line and
 * prints no terminal escapes. */
static const char *shown(const char *text, size_t length, char *out, size_t size)
{
    size_t n = 0, i = 0;
    for (; i < length && text[i] && i < 64 && n + 4 < size; i++)
        out[n++] = (unsigned char)text[i] < 0x20 || text[i] == 0x7f ? '?' : text[i];
    if (i < length && text[i] && n + 4 <= size)
        for (int k = 0; k < 3; k++)
            out[n++] = '.';
    out[n] = '\0';
    return out;
}

/* The first line in which two layouts differ, for the mismatch message. */
static void first_difference(const char *have, const char *want, char *out, size_t size)
{
    char line[80];
    while (*have && *want) {
        size_t a = strcspn(have, "\n"), b = strcspn(want, "\n");
        if (a != b || memcmp(have, want, a) != 0) {
            snprintf(out, size, "'%s' in the checkpoint, '%.*s' in the scene",
                     shown(have, a, line, sizeof line), (int)b, want);
            return;
        }
        have += a + (have[a] == '\n');
        want += b + (want[b] == '\n');
    }
    if (*have)
        snprintf(out, size, "'%s' only in the checkpoint",
                 shown(have, strcspn(have, "\n"), line, sizeof line));
    else
        snprintf(out, size, "'%.*s' only in the scene", (int)strcspn(want, "\n"), want);
}

/* Rebuilds the neighbour list from the positions of its last build (the
 * particles are still in the order of that build: the stable counting sort
 * leaves them in place), then puts the current positions back. */
static int restore_grid(sluice_sim *sim, sluice_real *const *built, ck_error *e)
{
    const sluice_index n = sim->particles.count;
    const uint32_t dims = sim->scene.dimensions;
    sluice_real *current = malloc((size_t)dims * n * sizeof *current + 1);
    if (!current) {
        fail(e, "out of memory");
        return -1;
    }
    for (uint32_t d = 0; d < dims; d++) {
        sluice_real *x = sim->particles.columns[sim->position.column + (int32_t)d];
        memcpy(current + (size_t)d * n, x, (size_t)n * sizeof *x);
        memcpy(x, built[d], (size_t)n * sizeof *x);
    }
    sluice_index bad = 0;
    sim->grid.valid = 0;
    int rc = sluice_grid_build(&sim->grid, &sim->particles, (uint32_t)sim->position.column, &bad);
    int identity = rc == 0;
    for (sluice_index i = 0; identity && i < n; i++)
        identity = sim->grid.order[i] == i;
    /* the build gathered every column through grid.order (particle k is
     * the old order[k]): the current positions follow the same way */
    for (uint32_t d = 0; d < dims; d++) {
        sluice_real *x = sim->particles.columns[sim->position.column + (int32_t)d];
        const sluice_real *saved = current + (size_t)d * n;
        if (identity || rc != 0)
            memcpy(x, saved, (size_t)n * sizeof *x);
        else
            for (sluice_index k = 0; k < n; k++)
                x[k] = saved[sim->grid.order[k]];
    }
    free(current);
    if (rc == -1) {
        sim->grid.valid = 0;
        fail(e, "out of memory rebuilding the neighbour list");
        return -1;
    }
    if (!identity) {
        /* the scene's cells differ from the run's (another smoothing length,
         * kernel or neighbour-search skin): the first step builds the list
         * afresh from the current positions, a correct state that an
         * uninterrupted run would not have reached bit for bit */
        sim->grid.valid = 0;
        fprintf(stderr, "sluice: warning: the scene's neighbour cells differ from the "
                        "checkpoint's (smoothing length, kernel or neighbour_search changed): "
                        "the neighbour list is built afresh, and the run does not continue bit "
                        "for bit\n");
    }
    return 0;
}

/* The particle spacing the checkpoint's run was set up with, from its
 * resolved scene: 0 when it cannot be read (an older or edited file). */
static double checkpoint_spacing(const char *scene_text)
{
    if (!scene_text)
        return 0;
    sluice_diag *diag = sluice_diag_create();
    if (!diag)
        return 0;
    sluice_node *root = sluice_yaml_parse_string(scene_text, strlen(scene_text), "checkpoint", diag);
    double spacing = 0;
    const sluice_node *particles = root ? sluice_node_get(root, "particles") : NULL;
    const sluice_node *node = particles ? sluice_node_get(particles, "spacing") : NULL;
    if (!node || node->kind != SLUICE_NODE_SCALAR || sluice_parse_real(node->value, &spacing) != 0)
        spacing = 0;
    sluice_node_free(root);
    sluice_diag_destroy(diag);
    return spacing;
}

/* The checkpoint's figures a restart needs past reading the particles. */
typedef struct restored_run {
    uint64_t count;    /* particles in the checkpoint */
    uint64_t rebuilds; /* neighbour-list rebuilds so far */
    int grid_valid;    /* the neighbour list was valid (its build positions are stored) */
} restored_run;

/* The format, its version, the reals' size, the dimensions, the plugins,
 * the field layout and the spacing match the scene's. */
static void check_matches_scene(sluice_sim *sim, hid_t file, ck_error *e)
{
    char *format = get_string(file, "format", e), text[80];
    if (format && strcmp(format, CHECKPOINT_FORMAT) != 0)
        fail(e, "it is not a Sluice checkpoint (format '%s')",
             shown(format, strlen(format), text, sizeof text));
    free(format);
    int version = 0, real_size = 0, dimensions = 0;
    get_attr(file, "format_version", H5T_NATIVE_INT, &version, e);
    if (!e->text[0] && version != CHECKPOINT_VERSION)
        fail(e, "it has checkpoint format version %d; this sluice reads version %d", version,
             CHECKPOINT_VERSION);
    get_attr(file, "real_size", H5T_NATIVE_INT, &real_size, e);
    if (!e->text[0] && real_size != (int)sizeof(sluice_real))
        fail(e, "it was written by a sluice with %d-byte reals; this one has %d-byte reals",
             real_size, (int)sizeof(sluice_real));
    get_attr(file, "dimensions", H5T_NATIVE_INT, &dimensions, e);
    if (!e->text[0] && dimensions != (int)sim->scene.dimensions)
        fail(e, "it holds a %dD run and the scene is %uD: it does not match the scene",
             dimensions, sim->scene.dimensions);
    char *plugins = get_string(file, "plugins", e), *fields = get_string(file, "fields", e);
    char *want_plugins = plugin_lines(sim), *want_fields = field_lines(sim);
    char difference[512];
    if (!e->text[0] && (!want_plugins || !want_fields))
        fail(e, "out of memory");
    if (!e->text[0] && strcmp(plugins, want_plugins) != 0) {
        first_difference(plugins, want_plugins, difference, sizeof difference);
        fail(e, "its plugins do not match the scene's (%s)", difference);
    }
    if (!e->text[0] && strcmp(fields, want_fields) != 0) {
        first_difference(fields, want_fields, difference, sizeof difference);
        fail(e, "its field layout (name type components) does not match the scene's (%s)",
             difference);
    }
    free(plugins);
    free(fields);
    free(want_plugins);
    free(want_fields);
    /* the particles are the run's: their mass and lattice belong to its
     * spacing, which a restart cannot change (any other parameter it can) */
    if (!e->text[0]) {
        char *scene_text = get_string(file, "scene", e);
        const double spacing = checkpoint_spacing(scene_text);
        free(scene_text);
        if (!e->text[0] && spacing > 0 &&
            fabs(spacing - (double)sim->spacing) > 1e-12 * spacing)
            fail(e, "it holds a run at particles.spacing = %.9g m and the scene asks for %.9g "
                    "m; a restart continues the same particles (--set particles.spacing=%.9g, "
                    "or start a new run)",
                 spacing, (double)sim->spacing, spacing);
    }
}

/* The run's counters and every particle field; across ranks, the split of
 * the particles into the ranks' boxes. */
static void read_particles(sluice_sim *sim, hid_t file, ck_error *e, restored_run *run)
{
    uint64_t count = 0, next_id = 0, removed = 0, initial = 0, steps = 0, rebuilds = 0;
    int grid_valid = 0;
    int64_t step = 0;
    double time = 0, dt = 0, dt_limit = 0, deviation = 0;
    get_attr(file, "particle_count", H5T_NATIVE_UINT64, &count, e);
    get_attr(file, "time", H5T_NATIVE_DOUBLE, &time, e);
    get_attr(file, "dt", H5T_NATIVE_DOUBLE, &dt, e);
    get_attr(file, "dt_limit", H5T_NATIVE_DOUBLE, &dt_limit, e);
    get_attr(file, "step", H5T_NATIVE_INT64, &step, e);
    get_attr(file, "next_id", H5T_NATIVE_UINT64, &next_id, e);
    get_attr(file, "removed", H5T_NATIVE_UINT64, &removed, e);
    get_attr(file, "particles_initial", H5T_NATIVE_UINT64, &initial, e);
    get_attr(file, "particle_steps", H5T_NATIVE_UINT64, &steps, e);
    get_attr(file, "max_density_deviation", H5T_NATIVE_DOUBLE, &deviation, e);
    get_attr(file, "neighbour_list_rebuilds", H5T_NATIVE_UINT64, &rebuilds, e);
    get_attr(file, "grid_valid", H5T_NATIVE_INT, &grid_valid, e);
    *run = (restored_run){count, rebuilds, grid_valid};
    if (e->text[0])
        return;
    /* (a step count no run reaches, with room to count on) */
    if (count == 0 || count > UINT32_MAX - 1 || !isfinite(time) || step < 0 ||
        step > INT64_MAX / 2 || next_id < count) {
        fail(e, "its run state is inconsistent (%llu particles, step %lld, t = %g s)",
             (unsigned long long)count, (long long)step, time);
        return;
    }
    if (!(time < sim->end)) {
        fail(e, "it holds t = %.9g s, not before the scene's end time %.9g s (raise time.end "
                "with --set time.end=...)",
             time, sim->end);
        return;
    }

    /* particles: every field, in the checkpoint's order; each dataset's
     * shape (and data in the file) checked before the store grows to
     * `count` particles */
    hid_t group = H5Gopen2(file, "particles", H5P_DEFAULT);
    if (group < 0)
        fail(e, "group 'particles' is missing");
    for (uint32_t f = 0; f < sim->field_count && !e->text[0]; f++)
        check_rows(group, sim->fields[f].name, 2, sim->fields[f].components, count, e);
    sim->particles.count = 0;
    if (!e->text[0] && sluice_particles_append(&sim->particles, (sluice_index)count, NULL) != 0)
        fail(e, "out of memory for %llu particles", (unsigned long long)count);
    for (uint32_t f = 0; f < sim->field_count && !e->text[0]; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        void *rows[16];
        for (uint32_t c = 0; c < field->components; c++)
            rows[c] = sim->particles.columns[field->column + (int32_t)c];
        get_rows(group, field->name, field->type, 2, field->components, count, rows, e);
    }
    close_id(&group, H5Gclose);
    if (e->text[0])
        return;
    const uint8_t *kind = sim->particles.columns[sim->kind.column];
    for (sluice_index i = 0; i < (sluice_index)count; i++)
        if (kind[i] >= SLUICE_KIND_COUNT) {
            fail(e, "particle %u has the unknown kind %u", i, kind[i]);
            return;
        }

    sim->time = time;
    sim->dt = dt;
    sim->dt_limit = dt_limit;
    sim->step = step;
    sim->next_id = next_id;
    sim->removed = removed;
    sim->particles_initial = (sluice_index)initial;
    sim->particle_steps = steps;
    sim->max_density_deviation = deviation;
#ifdef SLUICE_MPI
    /* Across ranks every rank read every particle (the checkpoint may come
     * from another rank count): split them into slabs anew, before the
     * plugins load their state. The run's sums are rank 0's to carry on. */
    if (sim->comm.size > 1) {
        run->grid_valid = 0;
        if (sim->comm.rank != 0) {
            sim->removed = 0;
            sim->particle_steps = 0;
        }
        if (sluice_sim_split_ranks(sim) != 0) {
            fail(e, "%s", sim->failure);
            return;
        }
    }
#endif
}

/* The core's group: requested times, the tables' lengths and hashes, the
 * neighbour list's build positions. */
static void read_core_group(sluice_sim *sim, hid_t file, ck_error *e, const restored_run *run)
{
    /* core: requests, tables, neighbour list */
    hid_t group = H5Gopen2(file, "core", H5P_DEFAULT);
    if (group < 0) {
        fail(e, "group 'core' is missing");
        return;
    }
    int64_t requests = rows_length(group, "requests", 1, 1);
    int64_t tables = rows_length(group, "table_bytes", 1, 1);
    if (requests == CK_UNSTORED || tables == CK_UNSTORED)
        fail(e, "dataset '%s' declares more values than the file holds",
             requests == CK_UNSTORED ? "requests" : "table_bytes");
    else if (requests < 0 || tables < 0)
        fail(e, "the requested times or the table lengths are missing");
    double *times = malloc(((size_t)(requests > 0 ? requests : 0) + 1) * sizeof *times);
    /* table_hashes (since the session-19 checkpoints) must match table_bytes */
    int hashed = tables >= 0 && rows_length(group, "table_hashes", 1, 1) == tables;
    uint64_t *bytes = malloc((2 * (size_t)(tables > 0 ? tables : 0) + 1) * sizeof *bytes);
    if (!e->text[0] && (!times || !bytes))
        fail(e, "out of memory");
    void *row[1] = {times};
    get_rows(group, "requests", CK_DOUBLE, 1, 1, (hsize_t)requests, row, e);
    row[0] = bytes;
    get_rows(group, "table_bytes", CK_UINT64, 1, 1, (hsize_t)tables, row, e);
    if (hashed) {
        row[0] = bytes + tables;
        get_rows(group, "table_hashes", CK_UINT64, 1, 1, (hsize_t)tables, row, e);
    }
    char *names = get_string(group, "table_names", e);
    if (!e->text[0]) {
        sim->request_count = 0;
        for (int64_t i = 0; i < requests; i++)
            sluice_sim_request_time(sim, times[i]);
        /* each table of the scene continues from its length at the checkpoint */
        const char *p = names;
        for (int64_t t = 0; t < tables && *p; t++) {
            size_t len = strcspn(p, "\n");
            for (size_t k = 0; k < sim->table_count; k++) {
                sluice_table *table = sim->tables[k];
                if (table->fd < 0 && strlen(table->path) == len &&
                    memcmp(table->path, p, len) == 0) {
                    table->resume = 1;
                    table->resume_bytes = bytes[t];
                    table->resume_hashed = hashed;
                    table->resume_hash = hashed ? bytes[tables + t] : 0;
                }
            }
            p += len + (p[len] == '\n');
        }
    }
    free(names);
    free(times);
    free(bytes);
    if (!e->text[0] && run->grid_valid) {
        const uint32_t dims = sim->scene.dimensions;
        const uint64_t count = run->count;
        sluice_real *built = malloc((size_t)dims * count * sizeof *built + 1);
        void *rows[3] = {NULL, NULL, NULL};
        sluice_real *columns[3] = {NULL, NULL, NULL};
        for (uint32_t d = 0; built && d < dims; d++)
            rows[d] = columns[d] = built + (size_t)d * count;
        if (!built)
            fail(e, "out of memory");
        else if (get_rows(group, "grid_built", SLUICE_TYPE_REAL, 2, dims, count, rows, e) == 0)
            restore_grid(sim, columns, e);
        free(built);
    } else {
        sim->grid.valid = 0;
    }
    sim->grid.rebuilds = run->rebuilds;
    close_id(&group, H5Gclose);
    if (e->text[0])
        return;
}

/* Every plugin's saved state, through its load_state. */
static void read_plugin_states(sluice_sim *sim, hid_t file, ck_error *e)
{
    /* plugins */
    hid_t group = H5Gopen2(file, "plugins", H5P_DEFAULT);
    if (group < 0) {
        fail(e, "group 'plugins' is missing");
        return;
    }
    for (uint32_t k = 0; k < sim->instance_count && !e->text[0]; k++) {
        sluice_instance *in = &sim->instances[k];
        if (!in->component->load_state)
            continue;
        /* A checkpoint of a plugin version without state has no group: its
         * load_state still runs, sees every array missing (state_length -1)
         * and decides; state_read fails with the message below. */
        const int absent = H5Lexists(group, in->name, H5P_DEFAULT) <= 0;
        hid_t own = absent ? -1 : H5Gopen2(group, in->name, H5P_DEFAULT);
        if (!absent && own < 0) {
            fail(e, "the state of plugin '%s' cannot be read", in->name);
            break;
        }
        sim->state_group = own;
        sim->state_absent = absent;
        sim->state_instance = k;
        sim->state_writing = 0;
        sluice_sim_refresh_view(sim);
        sim->state_store = &checkpoint_store;
        int rc = in->component->load_state(in->state, &in->host);
        sim->state_store = NULL;
        sim->state_group = -1;
        sim->state_absent = 0;
        if (own >= 0)
            H5Gclose(own);
        if (rc != SLUICE_OK || sim->failure[0])
            fail(e, "plugin '%s' could not load its state%s%s", in->name,
                 sim->failure[0] ? ": " : "", sim->failure);
    }
    close_id(&group, H5Gclose);
}

static void read_state(sluice_sim *sim, hid_t file, ck_error *e)
{
    restored_run run = {0, 0, 0};
    check_matches_scene(sim, file, e);
    if (!e->text[0])
        read_particles(sim, file, e, &run);
    if (!e->text[0])
        read_core_group(sim, file, e, &run);
    if (!e->text[0])
        read_plugin_states(sim, file, e);
}

int sluice_sim_restart(sluice_sim *sim, const char *path, char *error, size_t error_size)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        snprintf(error, error_size, "cannot read checkpoint '%s': %s", path, strerror(errno));
        return SLUICE_ERROR;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(error, error_size, "checkpoint '%s' is not a regular file", path);
        return SLUICE_ERROR;
    }
    /* every byte as written before HDF5 reads one */
    char why[600];
    if (sluice_checksum_verify(path, why, sizeof why) != 0) {
        snprintf(error, error_size, "cannot restart from checkpoint '%s': %s", path, why);
        return SLUICE_ERROR;
    }
    quiet_hdf5 q;
    quiet_begin(&q);
    ck_error e = ck_clear();
    hid_t file = -1;
    htri_t is_hdf5 = H5Fis_hdf5(path);
    if (is_hdf5 <= 0)
        fail(&e, "it is not an HDF5 file");
    else if ((file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT)) < 0)
        fail(&e, "it cannot be opened: the file is truncated or damaged");
    sim->state_file = path;
    if (!e.text[0])
        read_state(sim, file, &e);
    sim->state_file = NULL;
    if (file >= 0 && H5Fclose(file) < 0)
        fail(&e, "closing it failed");
    quiet_end(&q);
    if (e.text[0]) {
        snprintf(error, error_size, "cannot restart from checkpoint '%s': %s", path, e.text);
        return SLUICE_ERROR;
    }
    sim->restarted = 1;
    sim->checkpoint_step = sim->step; /* this state is on disk already */
    sluice_sim_refresh_view(sim);
    return SLUICE_OK;
}

/* --------------------------------------------------- api->state_* (1.5) -- */

static int state_access(sluice_host *host, const char *name, int type, int writing)
{
    sluice_sim *sim = host->sim;
    const char *who = sim->instances[host->instance].name;
    if ((sim->state_group < 0 && !(sim->state_absent && !writing)) ||
        sim->state_instance != host->instance || sim->state_writing != writing) {
        sluice_sim_fail(sim, "plugin '%s': api->state->state_%s outside its own %s callback", who,
                        writing ? "write" : "read", writing ? "save_state" : "load_state");
        return SLUICE_ERROR;
    }
    if (!name || !*name || strchr(name, '/') || strcmp(name, ".") == 0) {
        sluice_sim_fail(sim, "plugin '%s': state array name '%s' is not a plain name", who,
                        name ? name : "");
        return SLUICE_ERROR;
    }
    if (type < 0) {
        sluice_sim_fail(sim, "plugin '%s': state array '%s' has the unknown type %d", who, name,
                        (int)type);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int state_write(sluice_host *host, const char *name, sluice_state_type state_type,
                           uint64_t count, const void *data)
{
    sluice_sim *sim = host->sim;
    const int type = state_kind(state_type);
    if (state_access(host, name, type, 1) != SLUICE_OK)
        return SLUICE_ERROR;
    if (count > 0 && !data) {
        sluice_sim_fail(sim, "plugin '%s': api->state->state_write('%s') without data",
                        sim->instances[host->instance].name, name);
        return SLUICE_ERROR;
    }
    ck_error e = ck_clear();
    if (sim->state_context) { /* a shared checkpoint: collective, rank 0 writes */
        e = *(const ck_error *)sim->state_context;
        e.text[0] = '\0';
    }
    const void *row[1] = {data};
    if (H5Lexists((hid_t)sim->state_group, name, H5P_DEFAULT) > 0)
        fail(&e, "it is written twice");
    put_rows((hid_t)sim->state_group, name, type, 1, 1, count, row, &e);
    if (e.text[0]) {
        /* only inside load_state, whose failure the restart reports with
         * the plugin's name and the checkpoint's */
        sluice_sim_fail(sim, "state array '%s': %s", name, e.text);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int state_read(sluice_host *host, const char *name, sluice_state_type state_type,
                          uint64_t count, void *data)
{
    sluice_sim *sim = host->sim;
    const int type = state_kind(state_type);
    if (state_access(host, name, type, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    ck_error e = ck_clear();
    void *row[1] = {data};
    if (sim->state_absent)
        fail(&e, "the checkpoint holds no state of this plugin (was it written by an older "
                 "version of the plugin?)");
    else if (count > 0 && !data)
        fail(&e, "no buffer given");
    else
        get_rows((hid_t)sim->state_group, name, type, 1, 1, count, row, &e);
    if (e.text[0]) {
        /* only inside load_state, whose failure the restart reports with
         * the plugin's name and the checkpoint's */
        sluice_sim_fail(sim, "state array '%s': %s", name, e.text);
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int64_t state_length(sluice_host *host, const char *name)
{
    sluice_sim *sim = host->sim;
    if (state_access(host, name, CK_DOUBLE, 0) != SLUICE_OK || sim->state_absent)
        return -1;
    const int64_t length = rows_length((hid_t)sim->state_group, name, 1, 1);
    if (length == CK_UNSTORED) { /* the restart fails, whatever load_state decides */
        sluice_sim_fail(sim, "state array '%s': it declares more values than the file holds",
                        name);
        return -1;
    }
    return length;
}
