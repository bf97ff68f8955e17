/* sluice probe (docs/probe.md): fields of a finished run interpolated from
 * its saved snapshots at points, along lines and over planes, to CSV.
 *
 * The run's resolved scene is loaded (its plugins, its kernel and h), each
 * chosen snapshot's particles replace the scene's, and the core's point pass
 * (the one point gauges use) sums over the fluid particles around each point:
 *   S(x) = sum_j V_j W(x - x_j),  V_j = m_j / rho_j,
 *   f(x) = sum_j V_j f_j W(x - x_j) / S(x)      (--correction shepard, default)
 *   f(x) = sum_j V_j f_j W(x - x_j)             (--correction none)
 * Points where S is below --min-support (default 0.5, as point_gauge's
 * min_kernel_sum) lie outside the fluid: their values are nan. */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <hdf5.h>

#include "diag.h"
#include "sim.h"

#define PROBE_MAX_FIELDS 32

static const char usage_text[] =
    "usage: sluice probe RUN --fields NAME[,NAME...]\n"
    "                    (--points \"x,y[,z];x,y[,z];...\"\n"
    "                     | --line \"x0,y0[,z0];x1,y1[,z1]\" --count N\n"
    "                     | --plane \"origin;corner_u;corner_v\" --count NU,NV)\n"
    "                    [--times all|last|T1,T2,...] [--snapshot FILE.h5 ...]\n"
    "                    [--prefix particles] [--correction shepard|none]\n"
    "                    [--min-support S] [--threads N] [--out FILE.csv]\n"
    "\n"
    "Interpolates fields of the run in directory RUN (written by `sluice run`) from\n"
    "its HDF5 snapshots (RUN/<prefix>_NNNNNN.h5) with the run's own kernel and\n"
    "smoothing length, over the fluid particles, at points, at N points along a\n"
    "line (both ends included) or at NU x NV points of the parallelogram spanned by\n"
    "origin, corner_u and corner_v (u fastest). Any real field the snapshots hold\n"
    "can be probed (`h5ls RUN/particles_000000.h5` lists them).\n"
    "\n"
    "  --times       all (default), last, or snapshot times in s (each must match a\n"
    "                snapshot's time to 1e-6 s)\n"
    "  --snapshot    probe these snapshot files instead (repeatable)\n"
    "  --correction  shepard (default): sum_j V_j f_j W / sum_j V_j W, exact for a\n"
    "                constant field; none: the plain sum sum_j V_j f_j W\n"
    "  --min-support points where sum_j V_j W is below S (default 0.5) are outside\n"
    "                the fluid: nan\n"
    "  --out         write the CSV there (atomically); default standard output\n"
    "  -h, --help    this text\n"
    "\n"
    "CSV columns: time (s), point (index), x, y[, z] (m), each field (vectors as\n"
    "NAME_x, NAME_y[, NAME_z]; other multi-component fields NAME_0, NAME_1, ...) in\n"
    "the units of the snapshot's dataset, and support (sum_j V_j W, 1 inside the\n"
    "fluid, 0 outside). Exit status: 0, 2 bad input, 4 other failure.\n";

typedef struct probe_request {
    const char *run, *out, *prefix, *times, *fields;
    const char *points, *line, *plane, *count;
    const char *snapshots[256];
    size_t snapshot_count;
    int shepard;
    double min_support;
    int threads;
} probe_request;

/* One snapshot file and its time. */
typedef struct probe_snapshot {
    char *path;
    double time;
} probe_snapshot;

/* A requested field: its handle and where its sums start. */
typedef struct probe_field {
    char name[128];
    sluice_field field;
    uint32_t slot;
} probe_field;

typedef struct probe_sums {
    probe_field fields[PROBE_MAX_FIELDS];
    uint32_t field_count, stride; /* stride: 1 (the support) + every component */
    sluice_field mass, density;
    double *sums; /* stride per point */
} probe_sums;

static void error(const char *format, ...) __attribute__((format(printf, 1, 2)));
static void error(const char *format, ...)
{
    va_list ap;
    va_start(ap, format);
    fputs("sluice probe: error: ", stderr);
    vfprintf(stderr, format, ap);
    fputc('\n', stderr);
    va_end(ap);
}

/* ------------------------------------------------------------ arguments -- */

static int parse_arguments(int argc, char **argv, probe_request *r)
{
    *r = (probe_request){.prefix = "particles", .times = "all", .shepard = 1, .min_support = 0.5};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            fputs(usage_text, stdout);
            exit(0);
        }
        if (a[0] != '-') {
            if (r->run) {
                error("one run directory only ('%s' and '%s')", r->run, a);
                return -1;
            }
            r->run = a;
            continue;
        }
        static const char *const known[] = {
            "--fields", "--points", "--line",     "--plane",      "--count",       "--times",
            "--prefix", "--out",    "--snapshot", "--correction", "--min-support", "--threads"};
        size_t k = 0;
        while (k < sizeof known / sizeof *known && strcmp(a, known[k]) != 0)
            k++;
        if (k == sizeof known / sizeof *known) {
            error("unknown option '%s' (sluice probe --help)", a);
            return -1;
        }
        if (i + 1 >= argc) {
            error("%s needs a value", a);
            return -1;
        }
        const char *v = argv[++i];
        if (strcmp(a, "--fields") == 0)
            r->fields = v;
        else if (strcmp(a, "--points") == 0)
            r->points = v;
        else if (strcmp(a, "--line") == 0)
            r->line = v;
        else if (strcmp(a, "--plane") == 0)
            r->plane = v;
        else if (strcmp(a, "--count") == 0)
            r->count = v;
        else if (strcmp(a, "--times") == 0)
            r->times = v;
        else if (strcmp(a, "--prefix") == 0)
            r->prefix = v;
        else if (strcmp(a, "--out") == 0)
            r->out = v;
        else if (strcmp(a, "--snapshot") == 0 && r->snapshot_count < 256)
            r->snapshots[r->snapshot_count++] = v;
        else if (strcmp(a, "--correction") == 0 && (!strcmp(v, "shepard") || !strcmp(v, "none")))
            r->shepard = strcmp(v, "shepard") == 0;
        else if (strcmp(a, "--min-support") == 0) {
            char *end;
            r->min_support = strtod(v, &end);
            if (*end || !(r->min_support >= 0)) {
                error("--min-support '%s' is not a number >= 0", v);
                return -1;
            }
        } else if (strcmp(a, "--threads") == 0) {
            char *end;
            long n = strtol(v, &end, 10);
            if (*end || n < 1 || n > 1024) {
                error("--threads '%s' is not a count from 1 to 1024", v);
                return -1;
            }
            r->threads = (int)n;
        } else {
            error("unknown option or value '%s %s' (sluice probe --help)", a, v);
            return -1;
        }
    }
    if (!r->run || !r->fields) {
        error("give a run directory and --fields (sluice probe --help)");
        return -1;
    }
    if (!!r->points + !!r->line + !!r->plane != 1) {
        error("give one of --points, --line and --plane");
        return -1;
    }
    if (!r->points == !r->count) {
        /* a line and a plane need --count; points must not have one */
        if (r->points)
            error("--count applies to --line and --plane only");
        else
            error("--%s needs --count", r->line ? "line" : "plane");
        return -1;
    }
    return 0;
}

/* Reads `dims` numbers separated by commas from text[0 .. length). */
static int parse_point(const char *text, size_t length, uint32_t dims, double *point)
{
    char buffer[256];
    if (length >= sizeof buffer)
        return -1;
    memcpy(buffer, text, length);
    buffer[length] = '\0';
    char *s = buffer;
    for (uint32_t d = 0; d < dims; d++) {
        char *end;
        point[d] = strtod(s, &end);
        if (end == s || !isfinite(point[d]))
            return -1;
        while (*end == ' ')
            end++;
        if (d + 1 < dims ? *end != ',' : *end != '\0')
            return -1;
        s = end + 1;
    }
    return 0;
}

/* The points of "p;p;..." (3 reals each, z = 0 in 2D); NULL with a message. */
static double *parse_points(const char *option, const char *text, uint32_t dims, size_t *count)
{
    size_t n = 1;
    for (const char *c = text; *c; c++)
        n += *c == ';';
    double *points = calloc(3 * n, sizeof *points);
    if (!points) {
        error("out of memory");
        return NULL;
    }
    const char *start = text;
    for (size_t k = 0; k < n; k++) {
        const char *end = strchr(start, ';');
        size_t length = end ? (size_t)(end - start) : strlen(start);
        if (parse_point(start, length, dims, points + 3 * k) != 0) {
            error("%s: point %zu '%.*s' is not %u numbers separated by commas (the run is %uD)",
                  option, k + 1, (int)length, start, dims, dims);
            free(points);
            return NULL;
        }
        start = end ? end + 1 : start + length;
    }
    *count = n;
    return points;
}

/* The probe points of --points, --line or --plane (3 reals each). */
static double *probe_points(const probe_request *r, uint32_t dims, size_t *count)
{
    if (r->points)
        return parse_points("--points", r->points, dims, count);
    size_t corners = 0;
    double *c = parse_points(r->line ? "--line" : "--plane", r->line ? r->line : r->plane, dims,
                             &corners);
    if (!c)
        return NULL;
    const size_t want = r->line ? 2 : 3;
    long nu = 0, nv = 1;
    char tail[8] = "";
    int read = r->line ? sscanf(r->count, "%ld%1s", &nu, tail)
                       : sscanf(r->count, "%ld,%ld%1s", &nu, &nv, tail);
    if (corners != want || read != (r->line ? 1 : 2) || nu < (r->line ? 2 : 1) || nv < 1 ||
        nu > 10000000 || nv > 10000000 || (double)nu * (double)nv > 1e8) {
        error("%s takes %zu points and --count %s (each at least %d, at most 1e8 in all)",
              r->line ? "--line" : "--plane", want, r->line ? "N" : "NU,NV", r->line ? 2 : 1);
        free(c);
        return NULL;
    }
    double *points = malloc(3 * (size_t)nu * (size_t)nv * sizeof *points);
    if (!points) {
        error("out of memory");
        free(c);
        return NULL;
    }
    for (long j = 0; j < nv; j++)
        for (long i = 0; i < nu; i++) {
            const double u = nu > 1 ? (double)i / (double)(nu - 1) : 0;
            const double v = nv > 1 ? (double)j / (double)(nv - 1) : 0;
            double *p = points + 3 * ((size_t)j * (size_t)nu + (size_t)i);
            for (int d = 0; d < 3; d++)
                p[d] = c[d] + u * (c[3 + d] - c[d]) + (r->line ? 0 : v * (c[6 + d] - c[d]));
        }
    free(c);
    *count = (size_t)nu * (size_t)nv;
    return points;
}

/* ------------------------------------------------------------ snapshots -- */

/* Reads a scalar attribute of the file's root; -1 when absent or unreadable. */
static int root_attribute(hid_t file, const char *name, hid_t type, void *value)
{
    if (H5Aexists(file, name) <= 0)
        return -1;
    hid_t a = H5Aopen(file, name, H5P_DEFAULT);
    if (a < 0)
        return -1;
    const int rc = H5Aread(a, type, value) < 0 ? -1 : 0;
    H5Aclose(a);
    return rc;
}

static int by_time(const void *a, const void *b)
{
    const double ta = ((const probe_snapshot *)a)->time, tb = ((const probe_snapshot *)b)->time;
    return ta < tb ? -1 : ta > tb;
}

/* 1 when `name` is <prefix>_<digits>.h5. */
static int is_snapshot_name(const char *name, const char *prefix)
{
    const size_t p = strlen(prefix), n = strlen(name);
    if (n < p + 5 || strncmp(name, prefix, p) != 0 || name[p] != '_' ||
        strcmp(name + n - 3, ".h5") != 0)
        return 0;
    for (size_t k = p + 1; k < n - 3; k++)
        if (name[k] < '0' || name[k] > '9')
            return 0;
    return 1;
}

/* The time of a snapshot file; -1 with a message when it is not one. */
static int snapshot_time(const char *path, double *time)
{
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file < 0) {
        error("cannot open '%s' as an HDF5 file (%s)", path,
              access(path, R_OK) != 0 ? strerror(errno) : "corrupt or not HDF5");
        return -1;
    }
    const int rc = root_attribute(file, "time", H5T_NATIVE_DOUBLE, time);
    H5Fclose(file);
    if (rc != 0)
        error("'%s' has no attribute 'time': not a snapshot of the hdf5 writer", path);
    return rc;
}

/* The run's snapshots (or the --snapshot files), sorted by time. */
static probe_snapshot *list_snapshots(const probe_request *r, size_t *count)
{
    size_t n = 0, capacity = 16;
    int failed = 0;
    probe_snapshot *list = malloc(capacity * sizeof *list);
    DIR *dir = r->snapshot_count ? NULL : opendir(r->run);
    if (!list || (!r->snapshot_count && !dir)) {
        error(list ? "cannot read the run directory '%s': %s" : "out of memory", r->run,
              strerror(errno));
        free(list);
        return NULL;
    }
    for (size_t k = 0;; k++) {
        const char *name = NULL;
        if (dir) {
            struct dirent *e = readdir(dir);
            if (!e)
                break;
            if (!is_snapshot_name(e->d_name, r->prefix))
                continue;
            name = e->d_name;
        } else if (k < r->snapshot_count)
            name = r->snapshots[k];
        else
            break;
        if (n == capacity) {
            probe_snapshot *grown = realloc(list, 2 * capacity * sizeof *list);
            if (!grown) {
                error("out of memory");
                failed = 1;
                break;
            }
            list = grown;
            capacity *= 2;
        }
        char *path = NULL;
        if (dir ? asprintf(&path, "%s/%s", r->run, name) < 0 : !(path = strdup(name))) {
            error("out of memory");
            failed = 1;
            break;
        }
        list[n] = (probe_snapshot){path, 0};
        if (snapshot_time(path, &list[n].time) != 0) {
            free(path);
            failed = 1;
            break;
        }
        n++;
    }
    if (dir)
        closedir(dir);
    if (failed || n == 0) {
        if (!failed)
            error("no snapshots %s_NNNNNN.h5 in '%s' (the scene's hdf5 writer writes them; "
                  "another prefix: --prefix)",
                  r->prefix, r->run);
        for (size_t k = 0; k < n; k++)
            free(list[k].path);
        free(list);
        return NULL;
    }
    qsort(list, n, sizeof *list, by_time);
    *count = n;
    return list;
}

/* Keeps the snapshots --times asks for (in the order asked); 0 or -1. */
static int choose_times(const char *times, probe_snapshot *list, size_t *count)
{
    if (strcmp(times, "all") == 0)
        return 0;
    if (strcmp(times, "last") == 0) {
        for (size_t k = 0; k + 1 < *count; k++)
            free(list[k].path);
        list[0] = list[*count - 1];
        *count = 1;
        return 0;
    }
    probe_snapshot chosen[4096];
    size_t n = 0;
    for (const char *s = times; *s;) {
        if (n == *count || n == 4096) {
            error("--times lists more times than the run has snapshots (%zu)", *count);
            goto fail;
        }
        char *end;
        const double t = strtod(s, &end);
        if (end == s || (*end && *end != ',')) {
            error("--times '%s' is not all, last or times in s separated by commas", times);
            goto fail;
        }
        size_t best = 0;
        for (size_t k = 1; k < *count; k++)
            if (fabs(list[k].time - t) < fabs(list[best].time - t))
                best = k;
        if (!(fabs(list[best].time - t) <= 1e-6 + 1e-9 * fabs(t))) {
            error("no snapshot at t = %g s: the nearest is at %.9g s (snapshots from %.9g to "
                  "%.9g s)",
                  t, list[best].time, list[0].time, list[*count - 1].time);
            goto fail;
        }
        chosen[n] = list[best];
        if (!(chosen[n].path = strdup(list[best].path))) {
            error("out of memory");
            goto fail;
        }
        n++;
        s = *end ? end + 1 : end;
    }
    for (size_t k = 0; k < *count; k++)
        free(list[k].path);
    memcpy(list, chosen, n * sizeof *list);
    *count = n;
    return 0;
fail:
    for (size_t k = 0; k < n; k++)
        free(chosen[k].path);
    return -1;
}

/* ------------------------------------------------------------ particles -- */

static hid_t memory_type(sluice_type type)
{
    switch (type) {
    case SLUICE_TYPE_REAL:
        return sizeof(sluice_real) == sizeof(double) ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT;
    case SLUICE_TYPE_INT32:
        return H5T_NATIVE_INT32;
    case SLUICE_TYPE_UINT8:
        return H5T_NATIVE_UINT8;
    default:
        return H5T_NATIVE_UINT64;
    }
}

static size_t type_size(sluice_type type)
{
    return type == SLUICE_TYPE_REAL    ? sizeof(sluice_real)
           : type == SLUICE_TYPE_INT32 ? 4
           : type == SLUICE_TYPE_UINT8 ? 1
                                       : sizeof(sluice_id);
}

/* Reads dataset `name` ([count] or [count, components]) into the field's
 * columns: 1 read, 0 absent, -1 with a message (wrong shape, read error). */
static int read_field(hid_t file, const char *path, const char *name, sluice_field field,
                      uint64_t count, const sluice_view *v)
{
    if (H5Lexists(file, name, H5P_DEFAULT) <= 0)
        return 0;
    hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
    hid_t space = set >= 0 ? H5Dget_space(set) : -1;
    hsize_t dims[2] = {0, 0};
    const int rank = space >= 0 ? H5Sget_simple_extent_dims(space, dims, NULL) : -1;
    const uint32_t components = rank == 2 ? (uint32_t)dims[1] : 1;
    int rc = 1;
    if (rank < 1 || rank > 2 || dims[0] != count || components != field.components) {
        error("'%s': dataset '%s' holds %llu x %u values where %llu x %u were expected", path,
              name, rank >= 1 ? (unsigned long long)dims[0] : 0ULL, components,
              (unsigned long long)count, field.components);
        rc = -1;
    }
    const size_t size = type_size(field.type);
    unsigned char *buffer = rc == 1 ? malloc((size_t)count * components * size + 1) : NULL;
    if (rc == 1 && !buffer) {
        error("out of memory reading '%s'", name);
        rc = -1;
    }
    if (rc == 1 && H5Dread(set, memory_type(field.type), H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer) < 0) {
        error("'%s': cannot read dataset '%s' (corrupt file?)", path, name);
        rc = -1;
    }
    for (uint32_t c = 0; rc == 1 && c < components; c++) {
        unsigned char *column = v->columns[field.column + (int32_t)c];
        for (uint64_t i = 0; i < count; i++)
            memcpy(column + i * size, buffer + (i * components + c) * size, size);
    }
    free(buffer);
    if (space >= 0)
        H5Sclose(space);
    if (set >= 0)
        H5Dclose(set);
    return rc;
}

/* Puts the snapshot's particles in place of the scene's: every field the
 * snapshot holds; position, kind, mass, density and the probed fields must
 * be there. 0 or -1 with a message. */
static int load_snapshot(sluice_sim *sim, const char *path, const probe_sums *p)
{
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file < 0) {
        error("cannot open '%s' as an HDF5 file", path);
        return -1;
    }
    uint64_t count = 0;
    int dims = 0;
    double h = 0;
    const sluice_view *v = sluice_sim_view(sim);
    int rc = 0;
    if (root_attribute(file, "particle_count", H5T_NATIVE_UINT64, &count) != 0 ||
        root_attribute(file, "dimensions", H5T_NATIVE_INT, &dims) != 0 ||
        root_attribute(file, "smoothing_length", H5T_NATIVE_DOUBLE, &h) != 0) {
        error("'%s' lacks the attributes particle_count, dimensions or smoothing_length: not a "
              "snapshot of the hdf5 writer",
              path);
        rc = -1;
    } else if ((uint32_t)dims != v->dimensions || fabs(h - (double)v->smoothing_length) >
                                                     1e-9 * (double)v->smoothing_length) {
        error("'%s' is a %dD snapshot with h = %g m; the run's scene is %uD with h = %g m: "
              "not a snapshot of this run",
              path, dims, h, v->dimensions, (double)v->smoothing_length);
        rc = -1;
    } else if (count > UINT32_MAX - 1) {
        error("'%s' holds %llu particles, more than Sluice can hold", path,
              (unsigned long long)count);
        rc = -1;
    } else if (sluice_sim_replace_particles(sim, (sluice_index)count) != SLUICE_OK) {
        error("%s", sluice_sim_failure(sim));
        rc = -1;
    }
    v = sluice_sim_view(sim);
    const char *required[] = {"position", "kind", "mass", "density"};
    const uint32_t field_count = sluice_sim_field_count(sim);
    for (uint32_t f = 0; rc == 0 && f < field_count; f++) {
        const char *name = sluice_sim_field_name(sim, f);
        sluice_field field;
        if (!name || sluice_sim_field(sim, name, &field) != SLUICE_OK)
            continue;
        const int read = read_field(file, path, name, field, count, v);
        int needed = 0;
        for (size_t k = 0; k < sizeof required / sizeof *required; k++)
            needed |= strcmp(name, required[k]) == 0;
        for (uint32_t k = 0; k < p->field_count; k++)
            needed |= strcmp(name, p->fields[k].name) == 0;
        if (read < 0)
            rc = -1;
        else if (read == 0 && needed) {
            error("'%s' has no dataset '%s'%s", path, name,
                  strcmp(name, "mass") == 0 || strcmp(name, "density") == 0
                      ? " (snapshots of Sluice before hdf5 writer 1.2.0 lack it: run again)"
                      : " (the writer's `fields` list left it out)");
            rc = -1;
        }
    }
    H5Fclose(file);
    return rc;
}

/* ----------------------------------------------------------- the sums -- */

static void accumulate(void *context, const sluice_view *v, const sluice_pair_batch *b)
{
    probe_sums *p = context;
    const sluice_real *rho = sluice_real_column(v, p->density, 0);
    const sluice_real *m = sluice_real_column(v, p->mass, 0);
    for (sluice_index t = 0; t < b->target_count; t++) {
        double *sum = p->sums + (size_t)b->target[t] * p->stride;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_index j = b->neighbour[k];
            const double w = (double)m[j] / (double)rho[j] * (double)b->kernel[k];
            sum[0] += w;
            for (uint32_t f = 0; f < p->field_count; f++)
                for (uint32_t c = 0; c < p->fields[f].field.components; c++)
                    sum[p->fields[f].slot + c] +=
                        w * (double)sluice_real_column(v, p->fields[f].field, c)[j];
        }
    }
}

/* The probed fields: real fields the scene declares. 0 or -1 with a message. */
static int bind_fields(sluice_sim *sim, const char *list, probe_sums *p)
{
    if (sluice_sim_field(sim, "mass", &p->mass) != SLUICE_OK ||
        sluice_sim_field(sim, "density", &p->density) != SLUICE_OK) {
        error("the run's scene declares no field 'mass' or 'density'");
        return -1;
    }
    p->stride = 1;
    for (const char *s = list; *s;) {
        size_t n = strcspn(s, ",");
        if (n == 0 || n >= sizeof p->fields[0].name || p->field_count == PROBE_MAX_FIELDS) {
            error("--fields '%s' is not a list of up to %d field names separated by commas", list,
                  PROBE_MAX_FIELDS);
            return -1;
        }
        probe_field *f = &p->fields[p->field_count++];
        memcpy(f->name, s, n);
        f->name[n] = '\0';
        if (sluice_sim_field(sim, f->name, &f->field) != SLUICE_OK ||
            f->field.type != SLUICE_TYPE_REAL) {
            error("--fields: the run's scene declares no real field '%s' (`sluice inspect` lists "
                  "each plugin's fields)",
                  f->name);
            return -1;
        }
        f->slot = p->stride;
        p->stride += f->field.components;
        s += n + (s[n] == ',');
    }
    return 0;
}

/* ------------------------------------------------------------- output -- */

static void write_header(FILE *out, const probe_sums *p, uint32_t dims)
{
    static const char axis[] = "xyz";
    fputs("time,point,x,y", out);
    if (dims == 3)
        fputs(",z", out);
    for (uint32_t f = 0; f < p->field_count; f++) {
        const uint32_t n = p->fields[f].field.components;
        for (uint32_t c = 0; c < n; c++) {
            if (n == 1)
                fprintf(out, ",%s", p->fields[f].name);
            else if (n == dims)
                fprintf(out, ",%s_%c", p->fields[f].name, axis[c]);
            else
                fprintf(out, ",%s_%u", p->fields[f].name, c);
        }
    }
    fputs(",support\n", out);
}

/* Probes one snapshot at every point and writes its rows. 0 or -1. */
static int probe_snapshot_rows(sluice_sim *sim, const probe_snapshot *snap, const double *points,
                               size_t count, const probe_request *r, probe_sums *p, FILE *out)
{
    if (load_snapshot(sim, snap->path, p) != 0)
        return -1;
    const uint32_t dims = sluice_sim_dimensions(sim);
    memset(p->sums, 0, count * p->stride * sizeof *p->sums);
    sluice_real *at = malloc(3 * count * sizeof *at);
    if (!at) {
        error("out of memory");
        return -1;
    }
    for (size_t k = 0; k < 3 * count; k++)
        at[k] = (sluice_real)points[k];
    const int rc = sluice_sim_point_pass(sim, at, (sluice_index)count,
                                         SLUICE_KIND_MASK(SLUICE_KIND_FLUID), accumulate, p);
    free(at);
    if (rc != SLUICE_OK) {
        error("'%s': %s", snap->path, sluice_sim_failure(sim));
        return -1;
    }
    for (size_t k = 0; k < count; k++) {
        const double *sum = p->sums + k * p->stride;
        const int inside = sum[0] >= r->min_support && sum[0] > 0;
        fprintf(out, "%.10g,%zu", snap->time, k);
        for (uint32_t d = 0; d < dims; d++)
            fprintf(out, ",%.10g", points[3 * k + d]);
        for (uint32_t c = 1; c < p->stride; c++)
            fprintf(out, ",%.10g", inside ? (r->shepard ? sum[c] / sum[0] : sum[c]) : NAN);
        fprintf(out, ",%.10g\n", sum[0]);
    }
    return 0;
}

/* Writes `size` bytes to `path` through a temporary file renamed into place. */
static int write_atomic(const char *path, const char *data, size_t size)
{
    char *temporary = NULL;
    if (asprintf(&temporary, "%s.tmp%ld", path, (long)getpid()) < 0) {
        error("out of memory");
        return -1;
    }
    FILE *f = fopen(temporary, "wb");
    int rc = f && fwrite(data, 1, size, f) == size ? 0 : -1;
    if (f && fclose(f) != 0)
        rc = -1;
    if (rc == 0 && rename(temporary, path) != 0)
        rc = -1;
    if (rc != 0) {
        error("cannot write '%s': %s", path, strerror(errno));
        unlink(temporary);
    }
    free(temporary);
    return rc;
}

/* Loads the run's scene as it ran (its plugins, kernel and h). */
static sluice_sim *load_run(const probe_request *r)
{
    char *scene = NULL;
    if (asprintf(&scene, "%s/scene.resolved.yaml", r->run) < 0) {
        error("out of memory");
        return NULL;
    }
    if (access(scene, R_OK) != 0) {
        error("'%s': %s (a run directory written by `sluice run` holds it)", scene,
              strerror(errno));
        free(scene);
        return NULL;
    }
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {.threads = r->threads, .check_only = 1, .quiet = 1};
    sluice_sim *sim = diag ? sluice_sim_load(scene, &options, diag) : NULL;
    if (diag)
        sluice_diag_print(diag, stderr);
    else
        error("out of memory");
    sluice_diag_destroy(diag);
    free(scene);
    return sim;
}

static int probe(const probe_request *r)
{
    sluice_sim *sim = load_run(r);
    if (!sim)
        return 2;
    const uint32_t dims = sluice_sim_dimensions(sim);
    probe_sums p;
    memset(&p, 0, sizeof p);
    size_t point_count = 0, snapshot_count = 0;
    double *points = NULL;
    probe_snapshot *snapshots = NULL;
    char *text = NULL;
    size_t size = 0;
    FILE *out = NULL;
    int status = 2;
    if (bind_fields(sim, r->fields, &p) != 0 ||
        !(points = probe_points(r, dims, &point_count)) ||
        !(snapshots = list_snapshots(r, &snapshot_count)) ||
        choose_times(r->times, snapshots, &snapshot_count) != 0)
        goto done;
    status = 4;
    p.sums = malloc(point_count * p.stride * sizeof *p.sums);
    out = open_memstream(&text, &size);
    if (!p.sums || !out) {
        error("out of memory");
        goto done;
    }
    write_header(out, &p, dims);
    status = 2;
    for (size_t k = 0; k < snapshot_count; k++)
        if (probe_snapshot_rows(sim, &snapshots[k], points, point_count, r, &p, out) != 0)
            goto done;
    status = 4;
    if (fclose(out) != 0) {
        out = NULL;
        error("out of memory");
        goto done;
    }
    out = NULL;
    if (r->out ? write_atomic(r->out, text, size) != 0
               : fwrite(text, 1, size, stdout) != size || fflush(stdout) != 0)
        goto done;
    status = 0;
done:
    if (out)
        fclose(out);
    free(text);
    for (size_t k = 0; snapshots && k < snapshot_count; k++)
        free(snapshots[k].path);
    free(snapshots);
    free(points);
    free(p.sums);
    sluice_sim_free(sim);
    return status;
}

int main(int argc, char **argv)
{
    probe_request r;
    if (parse_arguments(argc, argv, &r) != 0)
        return 2;
    /* HDF5's own error stack printing is replaced by the messages above */
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    return probe(&r);
}
