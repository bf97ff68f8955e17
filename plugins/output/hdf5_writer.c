/* HDF5 particle snapshots with an XDMF 3 index for ParaView / VisIt.
 *
 * Every `interval` seconds of simulated time (t = 0, interval, 2 interval, ...,
 * the core ends steps exactly on these times) and once more at the end of the
 * run, the particles are written to DIR/<prefix>_<index>.h5 (index with at
 * least six digits). HDF5 writes it from the particle store, field by field
 * in chunks, under a temporary name in the same directory, and the core
 * renames it once whole (api->output->write_file_with, in a child
 * process), so a reader never sees a half-written snapshot. When the run fails (the watchdog stopped
 * an unstable run, or another failure) the final snapshot is still written:
 * it holds the state that made the run stop, and its root attribute `status`
 * is "failed" (every other snapshot has "ok").
 *
 * Layout of a snapshot, all at the root group:
 *  - one dataset per field, named as the field: scalars [N], vectors and other
 *    multi-component fields [N, components] (particle-major); REAL as native
 *    double, UINT8 as uint8, INT32 as int32, ID as uint64; string attributes
 *    `units` and `description`;
 *  - attributes time (double, s), step (int64), dimensions (int),
 *    particle_count (uint64), smoothing_length and spacing (double, m),
 *    kernel (the scene's kernel component, e.g. "cubic_spline") and
 *    kernel_support (its support radius over h), scene (the fully resolved
 *    scene, YAML text), plugins (one line per loaded plugin: "component
 *    library version path"), provenance (sluice_version, git_revision,
 *    build, command_line, date, host: api->output->describe_run), status
 *    ("ok" or "failed"). Strings are variable-length UTF-8.
 *
 * The scene's walls (1.3.0; api->walls, every wall whatever its scheme:
 * wall particles or geometric walls alike) are written once, at the first
 * snapshot, to DIR/<prefix>_walls.h5: the elements of the fixed walls first,
 * then those of the moving walls (each group in wall order), at the scene's
 * geometry:
 *  - points [P, 3] (double, m; z = 0 in 2D): 2 per segment (2D) or 3 per
 *    triangle (3D), element after element;
 *  - connectivity [E, 2 or 3] (int64): 0, 1, 2, ... (every grid of the
 *    index takes its first rows);
 *  - wall [E] (int32): the wall of each element (its index in the scene's
 *    geometry.walls); normal [E, 3] (double): the unit normal into the fluid;
 *  - per wall: name and scheme (variable-length UTF-8 strings), moves (uint8);
 *  - attributes dimensions, nodes_per_element, fixed_elements, moving_elements;
 *  - when a wall moves, groups fixed and moving with the points,
 *    connectivity, wall and normal of the fixed and of the moving elements
 *    (the index's grids name whole datasets: ParaView 5.11's XDMF 3 readers
 *    read no HyperSlab of a geometry or an attribute).
 * A wall that moves (its scheme reports a displacement,
 * api->walls->wall_displacement: dbc's moving_wall) is also in every
 * snapshot: /walls/points [moving elements x nodes, 3] at the snapshot's time
 * and /walls/displacement [walls, 3] (zero for a fixed wall).
 *
 * Every file of the writer (snapshots, the walls file, the vertex file)
 * carries the run's provenance as string attributes of its root:
 * sluice_version, git_revision, build, command_line, date, host.
 *
 * DIR/<prefix>.xdmf is rewritten atomically after every snapshot: a temporal
 * collection of every snapshot so far. Without walls each is a Uniform grid
 * with Polyvertex topology, Geometry XY / XYZ from /position and one
 * Attribute per written field; with walls each is a spatial collection of
 * that grid (named "particles"), a grid "walls" (the fixed walls: Polyline
 * cells with NodesPerElement 2 in 2D, Triangle cells in 3D, from
 * <prefix>_walls.h5) and a grid "moving_walls" (their points from the
 * snapshot, the rest from the walls file's group moving), both with the
 * cell attributes wall and normal. The Polyvertex
 * connectivity is the first N entries (a HyperSlab) of
 * /index = 0, 1, 2, ... in DIR/<prefix>_vertices.h5, shared by all snapshots
 * and grown when the particle count does: without connectivity ParaView's
 * XDMF 3 readers make no cells and the particles only show as Point Gaussian.
 * Ids are declared Int (ParaView reads UInt of precision 8 as 32-bit). File
 * names in it are relative, so the run directory can be moved.
 * tools/paraview/open_run.py shows a run with its walls (docs/paraview.md).
 *
 * Across MPI ranks (1.1.0, parallel HDF5): the same files. Every rank
 * writes its particles at its offset (the ranks' particles in rank order)
 * into one snapshot, opened collectively as <name>.partial and renamed by
 * rank 0 once complete; rank 0 writes the XDMF index, the vertex file and
 * the walls file, and the moving walls' points in the snapshot.
 *
 * Fields written: `fields: ""` (the default) writes every field flagged
 * SLUICE_FIELD_OUTPUT; otherwise `fields` is a comma-separated list of field
 * names, and position, kind and id are always written in addition. Mass and
 * density are always written when the scene declares them: with the kernel
 * and h they are what a reader needs to interpolate (V = m / rho; `sluice
 * probe`). */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <hdf5.h>

#include <sluice/plugin_util.h>

#define H5W_NONE ((hid_t)-1)
#define H5W_PATH_MAX 4096
#define H5W_PREFIX_MAX 200
/* rows per chunk are chosen for about this many bytes per chunk */
#define H5W_CHUNK_BYTES ((size_t)1 << 20)

typedef struct h5w_config {
    sluice_real interval;
    const char *prefix;
    const char *fields;
    int64_t compression;
} h5w_config;

/* A field chosen for output, copied from the core's field table. */
typedef struct h5w_field {
    char *name, *units, *doc;
    sluice_type type;
    uint32_t components;
    int32_t column;
} h5w_field;

/* One snapshot in the XDMF index. */
typedef struct h5w_record {
    char stem[H5W_PREFIX_MAX + 32];
    double time;
    uint64_t count;
    uint32_t dimensions;
} h5w_record;

/* A growable text buffer. */
typedef struct h5w_text {
    char *data;
    size_t length, capacity;
    int failed; /* out of memory: the text is incomplete */
} h5w_text;

/* The scene's walls as the snapshots show them (api->walls, every scheme),
 * gathered at the first snapshot (every wall scheme has initialised and
 * said which walls move): the elements of fixed walls first, then those of
 * moving walls, each in wall order. */
typedef struct h5w_walls {
    int ready;              /* gathered */
    int written;            /* <prefix>_walls.h5 written by this process */
    uint32_t dimensions;
    uint32_t count;         /* walls */
    uint32_t nodes;         /* points per element: 2 (segments) or 3 (triangles) */
    uint64_t fixed, moving; /* elements of fixed walls, of moving walls */
    double *points;         /* 3 per point, nodes per element: the scene's geometry */
    double *normals;        /* 3 per element, into the fluid */
    int32_t *wall;          /* per element: the wall's index (api->walls->wall) */
    uint8_t *moves;         /* per wall */
    const char **names, **schemes; /* per wall, the core's strings */
    /* at the snapshot being written: every wall's displacement (3 each) and
     * the moving walls' points (3 per point) */
    double *displacement;
    double *moving_points;
    const char *const *provenance; /* the state's, for the file's attributes */
} h5w_walls;

/* The run's provenance, written into every file (api->output->describe_run):
 * attribute names and the describe_run names they come from. */
#define H5W_PROVENANCE 6
static const char *const provenance_attribute[H5W_PROVENANCE] = {
    "sluice_version", "git_revision", "build", "command_line", "date", "host"};
static const char *const provenance_name[H5W_PROVENANCE] = {
    "version", "git_revision", "build", "command_line", "date", "host"};

typedef struct h5w_state {
    const sluice_api *api;
    int compression;
    char *prefix;
    /* explicit `fields` list (empty: every output field) */
    char **names;
    uint32_t name_count;
    /* resolved in initialise() */
    h5w_field *fields;
    uint32_t field_count;
    char *plugins; /* the `plugins` attribute text */
    sluice_host *host;     /* for api->output->describe_run */
    double kernel_support; /* the kernel's support radius over h */
    const char *kernel;    /* the scene's kernel component */
    const char *provenance[H5W_PROVENANCE];
    sluice_schedule schedule; /* the next regular snapshot */
    uint64_t snapshots; /* files written; the next file's index */
    int have_last;
    int64_t last_step;
    double last_time;
    int disabled; /* no output directory (sluice check, library use): write nothing */
    int broken;   /* a write failed and was reported: do not try again in finish() */
    /* interleaving buffer for multi-component fields */
    unsigned char *scratch;
    size_t scratch_size;
    /* XDMF document, regenerated from the records after every snapshot */
    h5w_text xdmf;
    h5w_record *records;
    size_t record_count, record_capacity;
    /* <prefix>_vertices.h5 holds /index = 0 .. vertex_capacity - 1: the
     * Polyvertex connectivity every grid takes its first n entries of, so
     * that ParaView makes one cell per particle */
    uint64_t vertex_capacity;
    /* restarted: the records are those of the checkpointed run; the first
     * XDMF rewrite keeps those whose files are in this output directory */
    int prune_records;
    h5w_walls walls;
} h5w_state;

static const sluice_param_spec params[] = {
    {"interval", SLUICE_PARAM_REAL, offsetof(h5w_config, interval), "0.05", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s",
     "simulated time between snapshots (the first is at t = 0; a final one is written at the "
     "end of the run)",
     NULL, 0},
    {"prefix", SLUICE_PARAM_STRING, offsetof(h5w_config, prefix), "particles", 0, 0, 0, NULL,
     "file name prefix in the output directory: <prefix>_000000.h5, ... and <prefix>.xdmf", NULL,
     0},
    {"fields", SLUICE_PARAM_STRING, offsetof(h5w_config, fields), "", 0, 0, 0, NULL,
     "comma-separated field names to write (position, kind and id are always written); empty: "
     "every field flagged for output",
     NULL, 0},
    {"compression", SLUICE_PARAM_INT, offsetof(h5w_config, compression), "0", 0, 9,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "deflate level of the datasets (with byte shuffling); 0: uncompressed. Every dataset is "
     "chunked with a Fletcher-32 checksum per chunk that HDF5 readers verify (not in MPI-IO "
     "snapshots)",
     NULL, 0},
};

/* ------------------------------------------------------------- helpers -- */

static char *copy_string(const char *s)
{
    size_t n = strlen(s ? s : "") + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s ? s : "", n);
    return d;
}

static void text_reserve(h5w_text *t, size_t extra)
{
    if (t->failed)
        return;
    if (t->length + extra + 1 <= t->capacity)
        return;
    size_t cap = t->capacity ? t->capacity : 4096;
    while (cap < t->length + extra + 1) {
        if (cap > ((size_t)-1) / 2) {
            t->failed = 1;
            return;
        }
        cap *= 2;
    }
    char *grown = realloc(t->data, cap);
    if (!grown) {
        t->failed = 1;
        return;
    }
    t->data = grown;
    t->capacity = cap;
}

static void text_append(h5w_text *t, const char *s, size_t n)
{
    text_reserve(t, n);
    if (t->failed)
        return;
    memcpy(t->data + t->length, s, n);
    t->length += n;
    t->data[t->length] = '\0';
}

static void text_printf(h5w_text *t, const char *format, ...) SLUICE_PRINTF(2, 3);
static void text_printf(h5w_text *t, const char *format, ...)
{
    if (t->failed)
        return;
    va_list ap;
    va_start(ap, format);
    int n = vsnprintf(NULL, 0, format, ap);
    va_end(ap);
    if (n < 0) {
        t->failed = 1;
        return;
    }
    text_reserve(t, (size_t)n);
    if (t->failed)
        return;
    va_start(ap, format);
    vsnprintf(t->data + t->length, (size_t)n + 1, format, ap);
    va_end(ap);
    t->length += (size_t)n;
}

/* Appends s with the five XML special characters escaped. */
static void text_xml(h5w_text *t, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': text_append(t, "&amp;", 5); break;
        case '<': text_append(t, "&lt;", 4); break;
        case '>': text_append(t, "&gt;", 4); break;
        case '"': text_append(t, "&quot;", 6); break;
        case '\'': text_append(t, "&apos;", 6); break;
        default: text_append(t, s, 1); break;
        }
    }
}

/* Edit distance of two short names (for "did you mean"); large when long. */
static size_t edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la > 63 || lb > 63)
        return (size_t)-1;
    size_t row[64];
    for (size_t j = 0; j <= lb; j++)
        row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diagonal = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t above = row[j];
            size_t best = diagonal + (a[i - 1] != b[j - 1]);
            if (above + 1 < best)
                best = above + 1;
            if (row[j - 1] + 1 < best)
                best = row[j - 1] + 1;
            row[j] = best;
            diagonal = above;
        }
    }
    return row[lb];
}

/* Index of field `name` in the core's field table, or -1. */
static int64_t find_field(const sluice_api *api, sluice_host *host, const char *name)
{
    uint32_t count = api->fields->field_count(host);
    for (uint32_t f = 0; f < count; f++) {
        sluice_field_spec spec;
        if (api->fields->field_info(host, f, &spec, NULL) == SLUICE_OK && spec.name &&
            strcmp(spec.name, name) == 0)
            return (int64_t)f;
    }
    return -1;
}

/* ----------------------------------------------------------- lifecycle -- */

static void h5w_destroy(void *state)
{
    h5w_state *s = state;
    if (!s)
        return;
    for (uint32_t i = 0; i < s->name_count; i++)
        free(s->names[i]);
    free(s->names);
    for (uint32_t i = 0; i < s->field_count; i++) {
        free(s->fields[i].name);
        free(s->fields[i].units);
        free(s->fields[i].doc);
    }
    free(s->fields);
    free(s->prefix);
    free(s->plugins);
    free(s->scratch);
    free(s->xdmf.data);
    free(s->records);
    free(s->walls.points);
    free(s->walls.normals);
    free(s->walls.wall);
    free(s->walls.moves);
    free(s->walls.names);
    free(s->walls.schemes);
    free(s->walls.displacement);
    free(s->walls.moving_points);
    free(s);
}

/* Splits the `fields` text into names (trimmed, empty entries ignored,
 * duplicates dropped). */
static int parse_names(h5w_state *s, const char *text)
{
    const char *p = text ? text : "";
    while (*p) {
        const char *end = strchr(p, ',');
        if (!end)
            end = p + strlen(p);
        const char *a = p, *b = end;
        while (a < b && (*a == ' ' || *a == '\t' || *a == '\n' || *a == '\r'))
            a++;
        while (b > a && (b[-1] == ' ' || b[-1] == '\t' || b[-1] == '\n' || b[-1] == '\r'))
            b--;
        if (b > a) {
            size_t n = (size_t)(b - a);
            int duplicate = 0;
            for (uint32_t i = 0; i < s->name_count; i++)
                if (strlen(s->names[i]) == n && memcmp(s->names[i], a, n) == 0)
                    duplicate = 1;
            if (!duplicate) {
                char **grown = realloc(s->names, (s->name_count + 1) * sizeof *grown);
                if (!grown)
                    return SLUICE_ERROR;
                s->names = grown;
                char *name = malloc(n + 1);
                if (!name)
                    return SLUICE_ERROR;
                memcpy(name, a, n);
                name[n] = '\0';
                s->names[s->name_count++] = name;
            }
        }
        p = *end ? end + 1 : end;
    }
    return SLUICE_OK;
}

static int h5w_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const h5w_config *c = config;
    h5w_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->schedule = sluice_schedule_every(c->interval);
    s->compression = (int)c->compression;
    const char *prefix = c->prefix ? c->prefix : "";
    if (!*prefix || strchr(prefix, '/') || strcmp(prefix, ".") == 0 ||
        strcmp(prefix, "..") == 0) {
        api->messages->error(host,
                   "prefix '%s' is not a file name: give a non-empty name without '/' (files "
                   "are written into the run's output directory)",
                   prefix);
        h5w_destroy(s);
        return SLUICE_ERROR;
    }
    if (strlen(prefix) > H5W_PREFIX_MAX) {
        api->messages->error(host, "prefix is longer than %d bytes", H5W_PREFIX_MAX);
        h5w_destroy(s);
        return SLUICE_ERROR;
    }
    for (const char *p = prefix; *p; p++)
        if ((unsigned char)*p < 0x20) {
            api->messages->error(host, "prefix contains a control character; give a plain file name");
            h5w_destroy(s);
            return SLUICE_ERROR;
        }
    s->prefix = copy_string(prefix);
    if (!s->prefix || parse_names(s, c->fields) != SLUICE_OK) {
        api->messages->error(host, "out of memory");
        h5w_destroy(s);
        return SLUICE_ERROR;
    }
    if (s->compression > 0) {
        H5E_auto2_t old_func = NULL;
        void *old_data = NULL;
        H5Eget_auto2(H5E_DEFAULT, &old_func, &old_data);
        H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
        unsigned int info = 0;
        int ok = H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0 &&
                 H5Zget_filter_info(H5Z_FILTER_DEFLATE, &info) >= 0 &&
                 (info & H5Z_FILTER_CONFIG_ENCODE_ENABLED);
        H5Eclear2(H5E_DEFAULT);
        H5Eset_auto2(H5E_DEFAULT, old_func, old_data);
        if (!ok) {
            api->messages->error(host, "compression = %d needs HDF5's deflate filter, which this HDF5 "
                             "library does not provide; use compression: 0",
                       s->compression);
            h5w_destroy(s);
            return SLUICE_ERROR;
        }
    }
    *state = s;
    return SLUICE_OK;
}

/* Reports every name of the `fields` list that no plugin declares. */
static int h5w_bind(void *state, sluice_host *host)
{
    h5w_state *s = state;
    const sluice_api *api = s->api;
    int errors = 0;
    for (uint32_t i = 0; i < s->name_count; i++) {
        const char *name = s->names[i];
        if (find_field(api, host, name) >= 0)
            continue;
        h5w_text available = {0};
        const char *closest = NULL;
        size_t best = (size_t)-1;
        uint32_t count = api->fields->field_count(host);
        for (uint32_t f = 0; f < count; f++) {
            sluice_field_spec spec;
            if (api->fields->field_info(host, f, &spec, NULL) != SLUICE_OK || !spec.name)
                continue;
            text_printf(&available, "%s%s", available.length ? ", " : "", spec.name);
            size_t d = edit_distance(name, spec.name);
            if (d < best) {
                best = d;
                closest = spec.name;
            }
        }
        char hint[160] = "";
        if (closest && best <= 2)
            snprintf(hint, sizeof hint, " (did you mean '%s'?)", closest);
        api->messages->error(host, "fields: unknown field '%s'%s; the available fields are: %s", name, hint,
                   available.failed || !available.data ? "(out of memory)" : available.data);
        free(available.data);
        errors++;
    }
    return errors ? SLUICE_ERROR : SLUICE_OK;
}

/* Appends field table entry `index` to the output list. */
static int add_field(h5w_state *s, sluice_host *host, uint32_t index, int explicit_choice)
{
    const sluice_api *api = s->api;
    sluice_field_spec spec;
    sluice_field field;
    if (api->fields->field_info(host, index, &spec, &field) != SLUICE_OK || !spec.name) {
        api->messages->error(host, "cannot read entry %u of the field table", index);
        return SLUICE_ERROR;
    }
    for (uint32_t i = 0; i < s->field_count; i++)
        if (strcmp(s->fields[i].name, spec.name) == 0)
            return SLUICE_OK;
    if (!spec.name[0] || strchr(spec.name, '/') || strcmp(spec.name, ".") == 0) {
        if (explicit_choice) {
            api->messages->error(host, "field '%s' cannot be written: its name is not a valid HDF5 "
                             "dataset name",
                       spec.name);
            return SLUICE_ERROR;
        }
        api->messages->warning(host, "field '%s' is not written: its name is not a valid HDF5 dataset name",
                     spec.name);
        return SLUICE_OK;
    }
    if (field.components == 0 || field.column < 0) {
        api->messages->error(host, "field '%s' has no storage (%u components, column %d)", spec.name,
                   field.components, field.column);
        return SLUICE_ERROR;
    }
    h5w_field *grown = realloc(s->fields, (s->field_count + 1) * sizeof *grown);
    if (!grown) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    s->fields = grown;
    h5w_field *f = &grown[s->field_count];
    memset(f, 0, sizeof *f);
    f->name = copy_string(spec.name);
    f->units = copy_string(spec.units);
    f->doc = copy_string(spec.doc);
    f->type = field.type;
    f->components = field.components;
    f->column = field.column;
    s->field_count++; /* counted now so that destroy frees the strings */
    if (!f->name || !f->units || !f->doc) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

/* Fixes the output list (every declaration is known now) and the plugin list. */
static int h5w_initialise(void *state, sluice_host *host)
{
    h5w_state *s = state;
    const sluice_api *api = s->api;
    s->host = host;
    sluice_real support = 0;
    if (sluice_util_constant(api, host, "kernel_support", &support) != SLUICE_OK)
        return SLUICE_ERROR;
    s->kernel_support = (double)support;
    const char *kernel = api->output->describe_run(host, "kernel");
    s->kernel = kernel ? kernel : "";
    for (int k = 0; k < H5W_PROVENANCE; k++) {
        const char *value = api->output->describe_run(host, provenance_name[k]);
        s->provenance[k] = value ? value : "";
    }
    s->walls.provenance = s->provenance;
    uint32_t count = api->fields->field_count(host);
    if (s->name_count == 0) {
        for (uint32_t f = 0; f < count; f++) {
            sluice_field_spec spec;
            if (api->fields->field_info(host, f, &spec, NULL) != SLUICE_OK)
                continue;
            if ((spec.flags & SLUICE_FIELD_OUTPUT) && add_field(s, host, f, 0) != SLUICE_OK)
                return SLUICE_ERROR;
        }
    }
    /* always: what a reader needs to interpolate (the volume m / rho of each
     * particle; mass and density when the scene declares them) */
    static const char *const always[] = {"position", "kind", "id", "mass", "density"};
    for (uint32_t k = 0; k < SLUICE_COUNT(always) + s->name_count; k++) {
        const char *name = k < SLUICE_COUNT(always) ? always[k] : s->names[k - SLUICE_COUNT(always)];
        int64_t index = find_field(api, host, name);
        if (index < 0 && k >= 3 && k < SLUICE_COUNT(always))
            continue;
        if (index < 0) {
            api->messages->error(host, "fields: unknown field '%s'", name);
            return SLUICE_ERROR;
        }
        if (add_field(s, host, (uint32_t)index, 1) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    for (uint32_t i = 0; i < s->field_count; i++)
        if (strcmp(s->fields[i].name, "position") == 0 && s->fields[i].type != SLUICE_TYPE_REAL) {
            api->messages->error(host, "field 'position' is not of type real");
            return SLUICE_ERROR;
        }

    h5w_text plugins = {0};
    uint32_t n = api->output->plugin_count(host);
    for (uint32_t k = 0; k < n; k++) {
        sluice_plugin_info info;
        if (api->output->plugin(host, k, &info) != SLUICE_OK)
            continue;
        text_printf(&plugins, "%s %s %s %s\n", info.component ? info.component : "?",
                    info.library ? info.library : "?", info.version ? info.version : "?",
                    info.path ? info.path : "?");
    }
    if (!plugins.failed && !plugins.data)
        text_append(&plugins, "", 0);
    if (plugins.failed) {
        free(plugins.data);
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    s->plugins = plugins.data;
    return SLUICE_OK;
}

/* ---------------------------------------------------------------- HDF5 -- */

/* Where a write failed: the call and HDF5's innermost error message. */
typedef struct h5w_failure {
    char text[1024];
} h5w_failure;

static herr_t innermost_error(unsigned n, const H5E_error2_t *e, void *data)
{
    h5w_failure *f = data;
    if (n == 0 && e && e->desc && e->desc[0]) {
        size_t used = strlen(f->text);
        /* a failed system call: HDF5's description holds the time, the
         * descriptor and the buffer address; the system's message is the
         * news ("file write failed: ..., error message = 'No space left on
         * device', ...") */
        const char *system = strstr(e->desc, "error message = '");
        const char *end = system ? strchr(system + 17, '\'') : NULL;
        if (system && end) {
            snprintf(f->text + used, sizeof f->text - used, ": %.*s", (int)(end - system - 17),
                     system + 17);
            return 0;
        }
        snprintf(f->text + used, sizeof f->text - used, ": %s", e->desc);
        for (char *p = f->text + used; *p; p++)
            if (*p == '\n' || *p == '\r' || *p == '\t')
                *p = ' ';
    }
    return 0;
}

static void fail(h5w_failure *f, const char *format, ...) SLUICE_PRINTF(2, 3);
static void fail(h5w_failure *f, const char *format, ...)
{
    if (f->text[0])
        return; /* keep the first cause */
    va_list ap;
    va_start(ap, format);
    vsnprintf(f->text, sizeof f->text, format, ap);
    va_end(ap);
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost_error, f);
    H5Eclear2(H5E_DEFAULT);
}

static void close_id(hid_t *id, herr_t (*closer)(hid_t), h5w_failure *f, const char *what)
{
    if (*id < 0)
        return;
    if (closer(*id) < 0)
        fail(f, "%s failed", what);
    *id = H5W_NONE;
}

static int attr_scalar(hid_t object, const char *name, hid_t stored_type, hid_t given_type,
                       const void *value, h5w_failure *f)
{
    hid_t space = H5W_NONE, attr = H5W_NONE;
    int ok = 0;
    if ((space = H5Screate(H5S_SCALAR)) < 0)
        fail(f, "H5Screate for attribute '%s' failed", name);
    else if ((attr = H5Acreate2(object, name, stored_type, space, H5P_DEFAULT, H5P_DEFAULT)) < 0)
        fail(f, "creating attribute '%s' failed", name);
    else if (H5Awrite(attr, given_type, value) < 0)
        fail(f, "writing attribute '%s' failed", name);
    else
        ok = 1;
    close_id(&attr, H5Aclose, f, "H5Aclose");
    close_id(&space, H5Sclose, f, "H5Sclose");
    return ok && !f->text[0] ? 0 : -1;
}

/* A variable-length UTF-8 string attribute (no size limit on the text). */
static int attr_string(hid_t object, const char *name, const char *value, h5w_failure *f)
{
    hid_t type = H5Tcopy(H5T_C_S1);
    if (type < 0) {
        fail(f, "H5Tcopy for attribute '%s' failed", name);
        return -1;
    }
    int rc = -1;
    if (H5Tset_size(type, H5T_VARIABLE) < 0 || H5Tset_cset(type, H5T_CSET_UTF8) < 0)
        fail(f, "making the string type of attribute '%s' failed", name);
    else {
        const char *text = value ? value : "";
        rc = attr_scalar(object, name, type, type, &text, f);
    }
    close_id(&type, H5Tclose, f, "H5Tclose");
    return rc == 0 && !f->text[0] ? 0 : -1;
}

static hid_t memory_type(sluice_type type)
{
    switch (type) {
    case SLUICE_TYPE_REAL: return sizeof(sluice_real) == sizeof(float) ? H5T_NATIVE_FLOAT
                                                                          : H5T_NATIVE_DOUBLE;
    case SLUICE_TYPE_INT32: return H5T_NATIVE_INT32;
    case SLUICE_TYPE_UINT8: return H5T_NATIVE_UINT8;
    case SLUICE_TYPE_ID: return H5T_NATIVE_UINT64;
    }
    return H5W_NONE;
}

static hid_t file_type(sluice_type type)
{
    switch (type) {
    case SLUICE_TYPE_REAL: return H5T_NATIVE_DOUBLE;
    case SLUICE_TYPE_INT32: return H5T_NATIVE_INT32;
    case SLUICE_TYPE_UINT8: return H5T_NATIVE_UINT8;
    case SLUICE_TYPE_ID: return H5T_NATIVE_UINT64;
    }
    return H5W_NONE;
}

static size_t element_size(sluice_type type)
{
    switch (type) {
    case SLUICE_TYPE_REAL: return sizeof(sluice_real);
    case SLUICE_TYPE_INT32: return sizeof(int32_t);
    case SLUICE_TYPE_UINT8: return sizeof(uint8_t);
    case SLUICE_TYPE_ID: return sizeof(sluice_id);
    }
    return 0;
}

/* Structure of arrays (one column per component) to particle-major rows. */
#define H5W_INTERLEAVE(SIZE)                                                                 \
    for (uint32_t c = 0; c < components; c++) {                                              \
        const unsigned char *src = columns[column + (int32_t)c];                              \
        for (size_t i = 0; i < n; i++)                                                       \
            memcpy(out + (i * components + c) * (SIZE), src + i * (SIZE), (SIZE));           \
    }

static void interleave(unsigned char *out, void *const *columns, int32_t column,
                       uint32_t components, size_t n, size_t size)
{
    switch (size) {
    case 1: H5W_INTERLEAVE(1) break;
    case 2: H5W_INTERLEAVE(2) break;
    case 4: H5W_INTERLEAVE(4) break;
    case 8: H5W_INTERLEAVE(8) break;
    default: H5W_INTERLEAVE(size) break;
    }
}

/* The rows this process writes: its n particles at `offset` of `total`
 * (across ranks; on one rank offset 0 and total n), with the transfer
 * property list for them (collective across ranks). */
typedef struct h5w_part {
    uint64_t offset, total;
    hid_t transfer;
    int parallel; /* written collectively (MPI-IO): no checksum filter */
} h5w_part;

static int write_field(h5w_state *s, hid_t file, const h5w_field *field, const sluice_view *v,
                       const h5w_part *part, h5w_failure *f)
{
    const size_t n = v->count;
    const uint32_t components = field->components;
    const int rank = components == 1 ? 1 : 2;
    hsize_t dims[2] = {(hsize_t)part->total, (hsize_t)components};
    const int shared = part->total != (uint64_t)n || part->offset != 0;
    hid_t memory = H5W_NONE;
    const size_t size = element_size(field->type);
    hid_t space = H5W_NONE, dcpl = H5W_NONE, dset = H5W_NONE;
    const void *data = NULL;

    if (n > 0 && components == 1) {
        data = v->columns[field->column];
    } else if (n > 0) {
        if (n > ((size_t)-1) / components / size) {
            fail(f, "field '%s' is too large to buffer", field->name);
            return -1;
        }
        size_t bytes = n * components * size;
        if (bytes > s->scratch_size) {
            unsigned char *grown = realloc(s->scratch, bytes);
            if (!grown) {
                fail(f, "out of memory interleaving field '%s' (%zu bytes)", field->name, bytes);
                return -1;
            }
            s->scratch = grown;
            s->scratch_size = bytes;
        }
        interleave(s->scratch, v->columns, field->column, components, n, size);
        data = s->scratch;
    }

    if ((space = H5Screate_simple(rank, dims, NULL)) < 0) {
        fail(f, "H5Screate_simple for field '%s' failed", field->name);
        goto done;
    }
    if ((dcpl = H5Pcreate(H5P_DATASET_CREATE)) < 0) {
        fail(f, "H5Pcreate for field '%s' failed", field->name);
        goto done;
    }
    /* chunked with a Fletcher-32 checksum per chunk, which every HDF5 reader
     * (h5py, ParaView) verifies: a changed byte of data is an error there,
     * not a wrong number; compressed too with `compression` */
    const int checksummed = !part->parallel;
    if ((s->compression > 0 || checksummed) && part->total > 0) {
        size_t row_bytes = (size_t)components * 8;
        size_t rows = H5W_CHUNK_BYTES / row_bytes;
        if (rows < 1)
            rows = 1;
        hsize_t chunk[2] = {(hsize_t)(rows < part->total ? rows : part->total),
                            (hsize_t)components};
        if (H5Pset_chunk(dcpl, rank, chunk) < 0 ||
            (s->compression > 0 &&
             (H5Pset_shuffle(dcpl) < 0 || H5Pset_deflate(dcpl, (unsigned)s->compression) < 0)) ||
            (checksummed && H5Pset_fletcher32(dcpl) < 0)) {
            fail(f, "setting up the chunks of field '%s' failed", field->name);
            goto done;
        }
    }
    if ((dset = H5Dcreate2(file, field->name, file_type(field->type), space, H5P_DEFAULT, dcpl,
                           H5P_DEFAULT)) < 0) {
        fail(f, "creating dataset '%s' failed", field->name);
        goto done;
    }
    if (shared) {
        /* this rank's rows [offset, offset + n); a rank without particles
         * still takes part in the collective write, with an empty selection */
        hsize_t start[2] = {(hsize_t)part->offset, 0}, rows[2] = {(hsize_t)n, (hsize_t)components};
        memory = H5Screate_simple(rank, rows, NULL);
        herr_t selected = memory < 0 ? -1
                          : n > 0    ? H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL,
                                                           rows, NULL)
                                     : H5Sselect_none(space);
        if (selected >= 0 && n == 0)
            selected = H5Sselect_none(memory);
        if (selected < 0) {
            fail(f, "selecting the rows of field '%s' failed", field->name);
            goto done;
        }
        if (H5Dwrite(dset, memory_type(field->type), memory, space, part->transfer,
                     n > 0 ? data : s) < 0) {
            fail(f, "writing dataset '%s' failed", field->name);
            goto done;
        }
    } else if (n > 0 &&
               H5Dwrite(dset, memory_type(field->type), H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
        fail(f, "writing dataset '%s' failed", field->name);
        goto done;
    }
    if (attr_string(dset, "units", field->units, f) == 0)
        attr_string(dset, "description", field->doc, f);
done:
    close_id(&dset, H5Dclose, f, "H5Dclose");
    close_id(&dcpl, H5Pclose, f, "H5Pclose");
    close_id(&space, H5Sclose, f, "H5Sclose");
    if (memory >= 0)
        close_id(&memory, H5Sclose, f, "H5Sclose");
    return f->text[0] ? -1 : 0;
}

/* The run's provenance as root attributes of `file`. */
static int write_provenance(hid_t file, const char *const *provenance, h5w_failure *f)
{
    int rc = 0;
    for (int k = 0; k < H5W_PROVENANCE && rc == 0; k++)
        rc = attr_string(file, provenance_attribute[k], provenance[k], f);
    return rc;
}

/* The root attributes of a snapshot (the same on every rank). */
static void write_attributes(h5w_state *s, hid_t file, const sluice_view *v, uint64_t count,
                             const char *scene, const char *status, h5w_failure *f)
{
    double time = v->time, h = (double)v->smoothing_length, dx = (double)v->spacing;
    int64_t step = v->step;
    int dimensions = (int)v->dimensions;
    int rc = attr_scalar(file, "time", H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE, &time, f);
    if (rc == 0)
        rc = attr_scalar(file, "step", H5T_NATIVE_INT64, H5T_NATIVE_INT64, &step, f);
    if (rc == 0)
        rc = attr_scalar(file, "dimensions", H5T_NATIVE_INT, H5T_NATIVE_INT, &dimensions, f);
    if (rc == 0)
        rc = attr_scalar(file, "particle_count", H5T_NATIVE_UINT64, H5T_NATIVE_UINT64, &count, f);
    if (rc == 0)
        rc = attr_scalar(file, "smoothing_length", H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE, &h, f);
    if (rc == 0)
        rc = attr_scalar(file, "spacing", H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE, &dx, f);
    if (rc == 0)
        rc = attr_string(file, "scene", scene, f);
    if (rc == 0)
        rc = attr_string(file, "plugins", s->plugins, f);
    if (rc == 0)
        rc = attr_scalar(file, "kernel_support", H5T_NATIVE_DOUBLE, H5T_NATIVE_DOUBLE,
                         &s->kernel_support, f);
    if (rc == 0)
        rc = attr_string(file, "kernel", s->kernel, f);
    if (rc == 0)
        rc = write_provenance(file, s->provenance, f);
    if (rc == 0)
        attr_string(file, "status", status, f);
}

/* --------------------------------------------------------------- walls -- */

/* Gathers the scene's walls (api->walls->wall, of every scheme), fixed
 * walls' elements first, then moving walls' (those whose scheme set a
 * displacement: api->walls->wall_displacement). */
static int gather_walls(h5w_state *s, sluice_host *host)
{
    const sluice_api *api = s->api;
    h5w_walls *w = &s->walls;
    w->ready = 1;
    w->dimensions = api->particles->view(host)->dimensions;
    w->nodes = w->dimensions == 3 ? 3 : 2;
    w->count = api->walls->wall_count(host);
    if (w->count == 0)
        return SLUICE_OK;
    w->moves = calloc(w->count, 1);
    w->names = calloc(w->count, sizeof *w->names);
    w->schemes = calloc(w->count, sizeof *w->schemes);
    w->displacement = calloc(3 * (size_t)w->count, sizeof *w->displacement);
    if (!w->moves || !w->names || !w->schemes || !w->displacement) {
        api->messages->error(host, "out of memory gathering the walls");
        return SLUICE_ERROR;
    }
    for (uint32_t k = 0; k < w->count; k++) {
        const sluice_wall *wall = api->walls->wall(host, k);
        if (!wall) {
            api->messages->error(host, "cannot read wall %u of %u", k, w->count);
            return SLUICE_ERROR;
        }
        sluice_real d[3];
        w->moves[k] = api->walls->wall_displacement(host, k, d) != 0;
        w->names[k] = wall->name ? wall->name : "";
        w->schemes[k] = wall->scheme ? wall->scheme : "";
        if (w->moves[k])
            w->moving += wall->element_count;
        else
            w->fixed += wall->element_count;
    }
    const size_t elements = (size_t)(w->fixed + w->moving);
    w->points = malloc((elements * w->nodes * 3 + 1) * sizeof *w->points);
    w->normals = malloc((elements * 3 + 1) * sizeof *w->normals);
    w->wall = malloc((elements + 1) * sizeof *w->wall);
    w->moving_points = malloc(((size_t)w->moving * w->nodes * 3 + 1) * sizeof *w->moving_points);
    if (!w->points || !w->normals || !w->wall || !w->moving_points) {
        api->messages->error(host, "out of memory gathering the walls");
        return SLUICE_ERROR;
    }
    size_t e = 0;
    for (int moving = 0; moving < 2; moving++)
        for (uint32_t k = 0; k < w->count; k++) {
            const sluice_wall *wall = api->walls->wall(host, k);
            if (w->moves[k] != moving)
                continue;
            for (uint32_t q = 0; q < wall->element_count; q++, e++) {
                for (size_t c = 0; c < 3 * (size_t)w->nodes; c++)
                    w->points[3 * w->nodes * e + c] =
                        (double)wall->points[3 * w->nodes * (size_t)q + c];
                for (size_t c = 0; c < 3; c++)
                    w->normals[3 * e + c] = (double)wall->normals[3 * (size_t)q + c];
                w->wall[e] = (int32_t)k;
            }
        }
    return SLUICE_OK;
}

/* The moving walls' displacements and points now. */
static void move_walls(h5w_state *s, sluice_host *host)
{
    h5w_walls *w = &s->walls;
    for (uint32_t k = 0; k < w->count; k++) {
        sluice_real d[3] = {0, 0, 0};
        if (w->moves[k])
            s->api->walls->wall_displacement(host, k, d);
        for (int c = 0; c < 3; c++)
            w->displacement[3 * k + c] = (double)d[c];
    }
    const size_t first = (size_t)w->fixed * w->nodes;
    for (size_t p = 0; p < (size_t)w->moving * w->nodes; p++) {
        const int32_t k = w->wall[(first + p) / w->nodes];
        for (int c = 0; c < 3; c++)
            w->moving_points[3 * p + c] =
                w->points[3 * (first + p) + c] + w->displacement[3 * k + c];
    }
}

/* A small dataset written whole. Across ranks every rank takes part in the
 * collective calls and the one with `writes` set writes the values; outside
 * MPI-IO it is one chunk with a Fletcher-32 checksum when `checksum`. */
static void write_array(hid_t where, const char *name, hid_t type, int rank, const hsize_t *dims,
                        const void *data, const h5w_part *part, int writes, int checksum,
                        h5w_failure *f)
{
    if (f->text[0])
        return;
    hsize_t elements = 1;
    for (int r = 0; r < rank; r++)
        elements *= dims[r];
    hid_t space = H5W_NONE, dcpl = H5W_NONE, set = H5W_NONE, none = H5W_NONE;
    if ((space = H5Screate_simple(rank, dims, NULL)) < 0 ||
        (dcpl = H5Pcreate(H5P_DATASET_CREATE)) < 0)
        fail(f, "creating dataset '%s' failed", name);
    else if (checksum && !part->parallel && elements > 0 &&
             (H5Pset_chunk(dcpl, rank, dims) < 0 || H5Pset_fletcher32(dcpl) < 0))
        fail(f, "setting up the chunk of dataset '%s' failed", name);
    else if ((set = H5Dcreate2(where, name, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT)) < 0)
        fail(f, "creating dataset '%s' failed", name);
    else if (elements > 0) {
        hid_t memory = H5S_ALL, selection = H5S_ALL;
        if (!writes) {
            if ((none = H5Screate_simple(rank, dims, NULL)) < 0 || H5Sselect_none(none) < 0 ||
                H5Sselect_none(space) < 0)
                fail(f, "selecting nothing of dataset '%s' failed", name);
            memory = none;
            selection = space;
        }
        if (!f->text[0] && H5Dwrite(set, type, memory, selection, part->transfer, data) < 0)
            fail(f, "writing dataset '%s' failed", name);
    }
    close_id(&none, H5Sclose, f, "H5Sclose");
    close_id(&set, H5Dclose, f, "H5Dclose");
    close_id(&dcpl, H5Pclose, f, "H5Pclose");
    close_id(&space, H5Sclose, f, "H5Sclose");
}

/* The moving walls in a snapshot: /walls/points (their points at the
 * snapshot's time, in the walls file's order) and /walls/displacement
 * (every wall's, zero for fixed ones). Nothing when no wall moves. */
static void write_snapshot_walls(const h5w_state *s, hid_t file, const h5w_part *part, int writes,
                                 h5w_failure *f)
{
    const h5w_walls *w = &s->walls;
    if (f->text[0] || w->moving == 0)
        return;
    hid_t group = H5Gcreate2(file, "walls", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (group < 0) {
        fail(f, "creating group 'walls' failed");
        return;
    }
    const hsize_t points[2] = {(hsize_t)w->moving * w->nodes, 3}, displacement[2] = {w->count, 3};
    write_array(group, "points", H5T_NATIVE_DOUBLE, 2, points, w->moving_points, part, writes, 1,
                f);
    write_array(group, "displacement", H5T_NATIVE_DOUBLE, 2, displacement, w->displacement, part,
                writes, 1, f);
    if (!f->text[0])
        attr_string(group, "units", "m", f);
    close_id(&group, H5Gclose, f, "H5Gclose");
}

/* Elements [first, first + count) of the walls as group `name` (points,
 * connectivity 0, 1, 2, ..., wall, normal): the grids of the XDMF index
 * when a wall moves (ParaView's XDMF 3 readers read no HyperSlab of a
 * geometry or an attribute). */
static void write_wall_group(hid_t file, const char *name, const h5w_walls *w, uint64_t first,
                             uint64_t count, const int64_t *connectivity, h5w_failure *f)
{
    if (f->text[0] || count == 0)
        return;
    hid_t group = H5Gcreate2(file, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (group < 0) {
        fail(f, "creating group '%s' failed", name);
        return;
    }
    const h5w_part whole = {0, 0, H5P_DEFAULT, 0};
    const hsize_t points[2] = {count * w->nodes, 3}, cells[2] = {count, w->nodes},
                  normals[2] = {count, 3}, per_element[1] = {count};
    write_array(group, "points", H5T_NATIVE_DOUBLE, 2, points, w->points + 3 * w->nodes * first,
                &whole, 1, 1, f);
    write_array(group, "connectivity", H5T_NATIVE_INT64, 2, cells, connectivity, &whole, 1, 1, f);
    write_array(group, "wall", H5T_NATIVE_INT32, 1, per_element, w->wall + first, &whole, 1, 1, f);
    write_array(group, "normal", H5T_NATIVE_DOUBLE, 2, normals, w->normals + 3 * first, &whole, 1,
                1, f);
    close_id(&group, H5Gclose, f, "H5Gclose");
}

/* <prefix>_walls.h5's writer (write_file_with): every wall at the scene's
 * geometry, fixed walls' elements first (docs: the header comment). */
static int write_walls_file(void *context, const char *temporary, char *error, size_t error_size)
{
    const h5w_walls *w = context;
    const uint64_t elements = w->fixed + w->moving, point_count = elements * w->nodes;
    h5w_failure failure = {{0}}, *f = &failure;
    const h5w_part whole = {0, 0, H5P_DEFAULT, 0};
    int64_t *connectivity = malloc((size_t)(point_count + 1) * sizeof *connectivity);
    hid_t file = H5W_NONE, text = H5W_NONE;
    errno = 0;
    if (!connectivity)
        fail(f, "out of memory");
    else if ((file = H5Fcreate(temporary, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT)) < 0)
        fail(f, "cannot create it: %s", errno ? strerror(errno) : "H5Fcreate failed");
    else if ((text = H5Tcopy(H5T_C_S1)) < 0 || H5Tset_size(text, H5T_VARIABLE) < 0 ||
             H5Tset_cset(text, H5T_CSET_UTF8) < 0)
        fail(f, "making a string type failed");
    for (uint64_t p = 0; connectivity && p < point_count; p++)
        connectivity[p] = (int64_t)p;
    const hsize_t points[2] = {point_count, 3}, cells[2] = {elements, w->nodes},
                  normals[2] = {elements, 3}, per_element[1] = {elements}, per_wall[1] = {w->count};
    write_array(file, "points", H5T_NATIVE_DOUBLE, 2, points, w->points, &whole, 1, 1, f);
    write_array(file, "connectivity", H5T_NATIVE_INT64, 2, cells, connectivity, &whole, 1, 1, f);
    write_array(file, "wall", H5T_NATIVE_INT32, 1, per_element, w->wall, &whole, 1, 1, f);
    write_array(file, "normal", H5T_NATIVE_DOUBLE, 2, normals, w->normals, &whole, 1, 1, f);
    write_array(file, "moves", H5T_NATIVE_UINT8, 1, per_wall, w->moves, &whole, 1, 1, f);
    write_array(file, "name", text, 1, per_wall, w->names, &whole, 1, 0, f);
    write_array(file, "scheme", text, 1, per_wall, w->schemes, &whole, 1, 0, f);
    if (w->moving > 0) {
        write_wall_group(file, "fixed", w, 0, w->fixed, connectivity, f);
        write_wall_group(file, "moving", w, w->fixed, w->moving, connectivity, f);
    }
    const int dimensions = (int)w->dimensions, nodes = (int)w->nodes;
    if (!f->text[0] &&
        (attr_scalar(file, "dimensions", H5T_NATIVE_INT, H5T_NATIVE_INT, &dimensions, f) != 0 ||
         attr_scalar(file, "nodes_per_element", H5T_NATIVE_INT, H5T_NATIVE_INT, &nodes, f) != 0 ||
         attr_scalar(file, "fixed_elements", H5T_NATIVE_UINT64, H5T_NATIVE_UINT64, &w->fixed,
                     f) != 0 ||
         attr_scalar(file, "moving_elements", H5T_NATIVE_UINT64, H5T_NATIVE_UINT64, &w->moving,
                     f) != 0 ||
         write_provenance(file, w->provenance, f) != 0))
        fail(f, "writing the attributes failed");
    close_id(&text, H5Tclose, f, "H5Tclose");
    if (file >= 0 && H5Fclose(file) < 0 && !f->text[0])
        fail(f, "%s", errno ? strerror(errno) : "H5Fclose failed");
    free(connectivity);
    if (f->text[0]) {
        snprintf(error, error_size, "%s", f->text);
        return -1;
    }
    return 0;
}

/* Writes <prefix>_<suffix>.h5 through `writer` (api->output->write_file_with),
 * HDF5's own error printing muted: the writer's message says what failed. */
static int write_side_file(h5w_state *s, sluice_host *host, const char *suffix,
                           sluice_file_writer writer, void *context)
{
    const sluice_api *api = s->api;
    char name[H5W_PREFIX_MAX + 32], path[H5W_PATH_MAX];
    snprintf(name, sizeof name, "%s_%s.h5", s->prefix, suffix);
    if (api->output->output_path(host, name, path, sizeof path) != SLUICE_OK) {
        api->messages->error(host, "the path of '%s' in the output directory is too long", name);
        return SLUICE_ERROR;
    }
    H5E_auto2_t old_func = NULL;
    void *old_data = NULL;
    H5Eget_auto2(H5E_DEFAULT, &old_func, &old_data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    int rc = api->output->write_file_with(host, path, writer, context);
    H5Eclear2(H5E_DEFAULT);
    H5Eset_auto2(H5E_DEFAULT, old_func, old_data);
    return rc;
}

/* Writes <prefix>_walls.h5 once per process (a restart into another
 * directory writes it there too). */
static int write_walls_index(h5w_state *s, sluice_host *host)
{
    if (s->walls.written || s->walls.count == 0)
        return SLUICE_OK;
    int rc = write_side_file(s, host, "walls", write_walls_file, &s->walls);
    if (rc == SLUICE_OK)
        s->walls.written = 1;
    return rc;
}

/* What a snapshot's writer needs (write_snapshot_file). */
typedef struct h5w_job {
    h5w_state *s;
    sluice_host *host;
    const sluice_view *v;
    const char *status;
} h5w_job;

/* Writes the complete snapshot to `temporary`, HDF5 streaming each field
 * from the particle store in chunks. It runs through the core's
 * write_file_with (a child process, which renames the file once whole): a
 * full disk makes HDF5 1.10's H5Fclose fail and leaves the library broken,
 * which must not happen in the run itself. */
static int write_snapshot_file(void *context, const char *temporary, char *error,
                               size_t error_size)
{
    const h5w_job *job = context;
    h5w_state *s = job->s;
    const sluice_view *v = job->v;
    const char *scene = s->api->output->resolved_scene(job->host);
    h5w_failure failure = {{0}}, *f = &failure;
    errno = 0;
    hid_t file = H5Fcreate(temporary, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file < 0)
        fail(f, "cannot create it: %s", errno ? strerror(errno) : "H5Fcreate failed");
    const h5w_part whole = {0, v->count, H5P_DEFAULT, 0};
    for (uint32_t i = 0; i < s->field_count && !f->text[0]; i++)
        write_field(s, file, &s->fields[i], v, &whole, f);
    write_snapshot_walls(s, file, &whole, 1, f);
    if (!f->text[0])
        write_attributes(s, file, v, v->count, scene ? scene : "", job->status, f);
    if (file >= 0 && H5Fclose(file) < 0 && !f->text[0])
        fail(f, "%s", errno ? strerror(errno) : "H5Fclose failed");
    if (f->text[0]) {
        snprintf(error, error_size, "%s", f->text);
        return -1;
    }
    return 0;
}

/* Across ranks (parallel HDF5): every rank writes its particles at its
 * offset into one file of the one-process layout, opened collectively
 * under a temporary name in the output directory; rank 0 renames it once
 * every rank has closed it, so a reader never sees a half-written
 * snapshot here either. Every call below is collective. */
static int write_shared(h5w_state *s, sluice_host *host, const sluice_view *v,
                        const sluice_ranks *ranks, const char *path, const char *status,
                        h5w_failure *f)
{
#ifdef H5_HAVE_PARALLEL
    const sluice_api *api = s->api;
    const char *scene = api->output->resolved_scene(host);
    char partial[H5W_PATH_MAX + 16];
    if (snprintf(partial, sizeof partial, "%s.partial", path) >= (int)sizeof partial) {
        fail(f, "the path is too long");
        return -1;
    }
    const MPI_Comm comm = *(const MPI_Comm *)ranks->communicator;
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS), file = H5W_NONE;
    h5w_part part = {ranks->particle_offset, ranks->particle_total, H5Pcreate(H5P_DATASET_XFER),
                     1};
    if (fapl < 0 || part.transfer < 0 || H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL) < 0 ||
        H5Pset_dxpl_mpio(part.transfer, H5FD_MPIO_COLLECTIVE) < 0)
        fail(f, "setting up parallel HDF5 failed");
    else if ((file = H5Fcreate(partial, H5F_ACC_TRUNC, H5P_DEFAULT, fapl)) < 0)
        fail(f, "H5Fcreate of '%s' failed", partial);
    for (uint32_t i = 0; i < s->field_count && !f->text[0]; i++)
        write_field(s, file, &s->fields[i], v, &part, f);
    write_snapshot_walls(s, file, &part, ranks->rank == 0, f);
    if (!f->text[0])
        write_attributes(s, file, v, ranks->particle_total, scene ? scene : "", status, f);
    if (file >= 0 && H5Fclose(file) < 0)
        fail(f, "H5Fclose failed");
    if (fapl >= 0)
        H5Pclose(fapl);
    if (part.transfer >= 0)
        H5Pclose(part.transfer);
    /* the file is whole once every rank has closed it */
    double failed = f->text[0] ? 1 : 0;
    if (api->ranks->reduce(host, &failed, 1, SLUICE_REDUCE_MAX) != SLUICE_OK)
        return -1;
    if (failed > 0 && !f->text[0])
        fail(f, "another rank failed to write its part");
    if (ranks->rank == 0) {
        if (f->text[0])
            unlink(partial);
        else if (rename(partial, path) != 0)
            fail(f, "cannot rename '%s' to '%s': %s", partial, path, strerror(errno));
    }
    return f->text[0] ? -1 : 0;
#else
    (void)s, (void)host, (void)v, (void)ranks, (void)path, (void)status;
    fail(f, "this hdf5 writer was built with a serial HDF5; a run across ranks needs a parallel "
            "HDF5 (Debian: libhdf5-openmpi-dev, meson -Dmpi=enabled)");
    return -1;
#endif
}

/* ---------------------------------------------------------------- XDMF -- */

static const char *xdmf_number_type(sluice_type type, int *precision)
{
    switch (type) {
    case SLUICE_TYPE_REAL: *precision = 8; return "Float";
    case SLUICE_TYPE_INT32: *precision = 4; return "Int";
    case SLUICE_TYPE_UINT8: *precision = 1; return "UChar";
    case SLUICE_TYPE_ID: *precision = 8; return "Int"; /* ParaView reads UInt 8 as 32-bit */
    }
    *precision = 8;
    return "Float";
}

static void xdmf_data_item(h5w_text *t, const h5w_field *field, size_t n, const char *file_name)
{
    int precision;
    const char *number = xdmf_number_type(field->type, &precision);
    if (field->components == 1)
        text_printf(t, "<DataItem Dimensions=\"%zu\"", n);
    else
        text_printf(t, "<DataItem Dimensions=\"%zu %u\"", n, field->components);
    text_printf(t, " NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">", number, precision);
    text_xml(t, file_name);
    text_append(t, ":/", 2);
    text_xml(t, field->name);
    text_append(t, "</DataItem>", 11);
}

/* Rows [first, first + count) of an HDF dataset of `total` rows and
 * `columns` columns (0: one-dimensional) as a DataItem. */
static void xdmf_rows(h5w_text *t, const char *pad, const char *file_name, const char *dataset,
                      const char *number, int precision, uint64_t first, uint64_t count,
                      uint64_t total, uint32_t columns)
{
    char shape[64], whole[64];
    if (columns)
        snprintf(shape, sizeof shape, "%llu %u", (unsigned long long)count, columns),
            snprintf(whole, sizeof whole, "%llu %u", (unsigned long long)total, columns);
    else
        snprintf(shape, sizeof shape, "%llu", (unsigned long long)count),
            snprintf(whole, sizeof whole, "%llu", (unsigned long long)total);
    const int slab = first != 0 || count != total;
    if (slab) {
        text_printf(t, "%s<DataItem ItemType=\"HyperSlab\" Dimensions=\"%s\" Type=\"HyperSlab\">\n",
                    pad, shape);
        if (columns)
            text_printf(t,
                        "%s  <DataItem Dimensions=\"3 2\" Format=\"XML\">%llu 0 1 1 %llu "
                        "%u</DataItem>\n",
                        pad, (unsigned long long)first, (unsigned long long)count, columns);
        else
            text_printf(t,
                        "%s  <DataItem Dimensions=\"3 1\" Format=\"XML\">%llu 1 %llu</DataItem>\n",
                        pad, (unsigned long long)first, (unsigned long long)count);
        text_printf(t, "%s  ", pad);
    } else {
        text_printf(t, "%s", pad);
    }
    text_printf(t, "<DataItem Dimensions=\"%s\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">",
                whole, number, precision);
    text_xml(t, file_name);
    text_append(t, ":/", 2);
    text_xml(t, dataset);
    text_append(t, "</DataItem>\n", 12);
    if (slab)
        text_printf(t, "%s</DataItem>\n", pad);
}

/* One snapshot's particles: a Uniform grid of Polyvertex cells. */
static void xdmf_particles(h5w_text *t, const h5w_state *s, const h5w_record *g,
                           const char *file_name, const char *vertices, const char *name,
                           const char *pad, int with_time)
{
    const size_t n = (size_t)g->count;
    const h5w_field *position = NULL;
    for (uint32_t i = 0; i < s->field_count; i++)
        if (strcmp(s->fields[i].name, "position") == 0)
            position = &s->fields[i];
    text_printf(t, "%s<Grid Name=\"", pad);
    text_xml(t, name);
    text_printf(t, "\" GridType=\"Uniform\">\n");
    if (with_time)
        text_printf(t, "%s  <Time Value=\"%.15g\"/>\n", pad, g->time);
    text_printf(t,
                "%s  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%zu\" "
                "NodesPerElement=\"1\">\n",
                pad, n);
    char inner[32];
    snprintf(inner, sizeof inner, "%s    ", pad);
    xdmf_rows(t, inner, vertices, "index", "Int", 8, 0, n, s->vertex_capacity, 0);
    text_printf(t, "%s  </Topology>\n", pad);
    text_printf(t, "%s  <Geometry GeometryType=\"%s\">\n%s    ", pad,
                g->dimensions == 3 ? "XYZ" : "XY", pad);
    if (position)
        xdmf_data_item(t, position, n, file_name);
    text_printf(t, "\n%s  </Geometry>\n", pad);
    for (uint32_t i = 0; i < s->field_count; i++) {
        const h5w_field *field = &s->fields[i];
        const char *kind = field->components == 1               ? "Scalar"
                           : field->components == g->dimensions ? "Vector"
                                                                : "Matrix";
        text_printf(t, "%s  <Attribute Name=\"", pad);
        text_xml(t, field->name);
        text_printf(t, "\" AttributeType=\"%s\" Center=\"Node\">\n%s    ", kind, pad);
        xdmf_data_item(t, field, n, file_name);
        text_printf(t, "\n%s  </Attribute>\n", pad);
    }
    text_printf(t, "%s</Grid>\n", pad);
}

/* The fixed walls (grid "walls") or the moving ones (grid "moving_walls":
 * their points from the snapshot), as Polyline (2D) or Triangle (3D) cells
 * with the attributes wall (its index) and normal (into the fluid), from
 * <prefix>_walls.h5: its whole arrays when no wall moves, else its groups
 * fixed and moving. Nothing when there are none. */
static void xdmf_walls(h5w_text *t, const h5w_walls *w, const char *walls_file,
                       const char *snapshot_file, int moving)
{
    const uint64_t count = moving ? w->moving : w->fixed;
    if (count == 0)
        return;
    const char *group = w->moving == 0 ? "" : moving ? "moving/" : "fixed/";
    const char *pad = "            ";
    char name[64];
    text_printf(t, "        <Grid Name=\"%s\" GridType=\"Uniform\">\n",
                moving ? "moving_walls" : "walls");
    if (w->nodes == 2)
        text_printf(t,
                    "          <Topology TopologyType=\"Polyline\" NumberOfElements=\"%llu\" "
                    "NodesPerElement=\"2\">\n",
                    (unsigned long long)count);
    else
        text_printf(t, "          <Topology TopologyType=\"Triangle\" NumberOfElements=\"%llu\">\n",
                    (unsigned long long)count);
    snprintf(name, sizeof name, "%sconnectivity", group);
    xdmf_rows(t, pad, walls_file, name, "Int", 8, 0, count, count, w->nodes);
    text_printf(t, "          </Topology>\n          <Geometry GeometryType=\"XYZ\">\n");
    snprintf(name, sizeof name, "%spoints", group);
    xdmf_rows(t, pad, moving ? snapshot_file : walls_file, moving ? "walls/points" : name, "Float",
              8, 0, count * w->nodes, count * w->nodes, 3);
    text_printf(t,
                "          </Geometry>\n"
                "          <Attribute Name=\"wall\" AttributeType=\"Scalar\" Center=\"Cell\">\n");
    snprintf(name, sizeof name, "%swall", group);
    xdmf_rows(t, pad, walls_file, name, "Int", 4, 0, count, count, 0);
    text_printf(t,
                "          </Attribute>\n"
                "          <Attribute Name=\"normal\" AttributeType=\"Vector\" Center=\"Cell\">\n");
    snprintf(name, sizeof name, "%snormal", group);
    xdmf_rows(t, pad, walls_file, name, "Float", 8, 0, count, count, 3);
    text_printf(t, "          </Attribute>\n        </Grid>\n");
}

/* The vertex file's writer (write_file_with): /index = 0 .. capacity - 1
 * (int64), written in blocks. */
/* What the vertex file's writer needs. */
typedef struct h5w_vertex_job {
    uint64_t capacity;
    const char *const *provenance;
} h5w_vertex_job;

static int write_vertex_file(void *context, const char *temporary, char *error,
                             size_t error_size)
{
    const h5w_vertex_job *job = context;
    const uint64_t capacity = job->capacity;
    enum { BLOCK = 65536 };
    int64_t *index = malloc(BLOCK * sizeof *index);
    h5w_failure failure = {{0}}, *f = &failure;
    hid_t file = H5W_NONE, space = H5W_NONE, set = H5W_NONE, block = H5W_NONE;
    hsize_t dims[1] = {capacity};
    errno = 0;
    if (!index)
        fail(f, "out of memory");
    else if ((file = H5Fcreate(temporary, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT)) < 0)
        fail(f, "cannot create it: %s", errno ? strerror(errno) : "H5Fcreate failed");
    else if ((space = H5Screate_simple(1, dims, NULL)) < 0)
        fail(f, "H5Screate_simple failed");
    else if ((set = H5Dcreate2(file, "index", H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT,
                               H5P_DEFAULT)) < 0)
        fail(f, "H5Dcreate2 failed");
    for (uint64_t first = 0; first < capacity && !f->text[0]; first += BLOCK) {
        hsize_t start[1] = {first}, count[1] = {capacity - first < BLOCK ? capacity - first : BLOCK};
        for (hsize_t i = 0; i < count[0]; i++)
            index[i] = (int64_t)(first + i);
        if ((block = H5Screate_simple(1, count, NULL)) < 0 ||
            H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
            H5Dwrite(set, H5T_NATIVE_INT64, block, space, H5P_DEFAULT, index) < 0)
            fail(f, "writing /index failed: %s", errno ? strerror(errno) : "H5Dwrite failed");
        if (block >= 0)
            H5Sclose(block);
        block = H5W_NONE;
    }
    if (set >= 0)
        H5Dclose(set);
    if (space >= 0)
        H5Sclose(space);
    if (file >= 0 && !f->text[0])
        write_provenance(file, job->provenance, f);
    if (file >= 0 && H5Fclose(file) < 0 && !f->text[0])
        fail(f, "%s", errno ? strerror(errno) : "H5Fclose failed");
    free(index);
    if (f->text[0]) {
        snprintf(error, error_size, "%s", f->text);
        return -1;
    }
    return 0;
}

/* Writes <prefix>_vertices.h5 with /index = 0 .. capacity - 1 (int64). */
static int write_vertex_index(h5w_state *s, sluice_host *host, uint64_t capacity)
{
    h5w_vertex_job job = {capacity, s->provenance};
    int rc = write_side_file(s, host, "vertices", write_vertex_file, &job);
    if (rc == SLUICE_OK)
        s->vertex_capacity = capacity;
    return rc;
}

/* Records one snapshot and rewrites the XDMF file from all records. */
static int write_xdmf(h5w_state *s, sluice_host *host, const sluice_view *v, uint64_t count,
                      const char *stem)
{
    const sluice_api *api = s->api;
    if (s->prune_records) {
        size_t kept = 0;
        for (size_t r = 0; r < s->record_count; r++) {
            char name[H5W_PREFIX_MAX + 40], path[H5W_PATH_MAX];
            snprintf(name, sizeof name, "%s.h5", s->records[r].stem);
            if (api->output->output_path(host, name, path, sizeof path) == SLUICE_OK &&
                access(path, F_OK) == 0)
                s->records[kept++] = s->records[r];
        }
        s->record_count = kept;
        s->prune_records = 0;
    }
    if (count > s->vertex_capacity) {
        uint64_t capacity = s->vertex_capacity * 2 > count ? s->vertex_capacity * 2 : count;
        if (capacity < 1024)
            capacity = 1024;
        if (write_vertex_index(s, host, capacity) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    if (s->record_count == s->record_capacity) {
        size_t cap = s->record_capacity ? 2 * s->record_capacity : 64;
        h5w_record *r = realloc(s->records, cap * sizeof *r);
        if (!r) {
            api->messages->error(host, "out of memory building the XDMF index");
            return SLUICE_ERROR;
        }
        s->records = r;
        s->record_capacity = cap;
    }
    h5w_record *rec = &s->records[s->record_count++];
    snprintf(rec->stem, sizeof rec->stem, "%s", stem);
    rec->time = v->time;
    rec->count = count;
    rec->dimensions = v->dimensions;

    h5w_text *t = &s->xdmf;
    t->length = 0;
    if (t->data)
        t->data[0] = '\0';
    text_printf(t, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                   "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
                   "  <Domain>\n"
                   "    <Grid Name=\"");
    text_xml(t, s->prefix);
    text_printf(t, "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
    char vertices[H5W_PREFIX_MAX + 16], walls[H5W_PREFIX_MAX + 16];
    snprintf(vertices, sizeof vertices, "%s_vertices.h5", s->prefix);
    snprintf(walls, sizeof walls, "%s_walls.h5", s->prefix);
    for (size_t r = 0; r < s->record_count; r++) {
        const h5w_record *g = &s->records[r];
        char file_name[H5W_PREFIX_MAX + 40];
        snprintf(file_name, sizeof file_name, "%s.h5", g->stem);
        if (s->walls.count == 0) {
            xdmf_particles(t, s, g, file_name, vertices, g->stem, "      ", 1);
            continue;
        }
        /* with walls: a spatial collection per time, the particles and the walls */
        text_printf(t, "      <Grid Name=\"");
        text_xml(t, g->stem);
        text_printf(t, "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
                       "        <Time Value=\"%.15g\"/>\n",
                    g->time);
        xdmf_particles(t, s, g, file_name, vertices, "particles", "        ", 0);
        xdmf_walls(t, &s->walls, walls, file_name, 0);
        xdmf_walls(t, &s->walls, walls, file_name, 1);
        text_printf(t, "      </Grid>\n");
    }
    text_printf(t, "    </Grid>\n  </Domain>\n</Xdmf>\n");
    if (t->failed) {
        api->messages->error(host, "out of memory building the XDMF index");
        return SLUICE_ERROR;
    }
    char name[H5W_PREFIX_MAX + 8], path[H5W_PATH_MAX];
    snprintf(name, sizeof name, "%s.xdmf", s->prefix);
    if (api->output->output_path(host, name, path, sizeof path) != SLUICE_OK) {
        api->messages->error(host, "the path of '%s' in the output directory is too long", name);
        return SLUICE_ERROR;
    }
    return api->output->write_file_atomic(host, path, t->data, t->length);
}

/* ------------------------------------------------------------ snapshots -- */

static int write_snapshot(h5w_state *s, sluice_host *host, const char *status)
{
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    /* the prefix is at most H5W_PREFIX_MAX bytes (checked in create) */
    char stem[H5W_PREFIX_MAX + 32], name[H5W_PREFIX_MAX + 40], path[H5W_PATH_MAX];
    snprintf(stem, sizeof stem, "%s_%06llu", s->prefix, (unsigned long long)s->snapshots);
    snprintf(name, sizeof name, "%.*s.h5", (int)(sizeof stem), stem);
    if (api->output->output_path(host, name, path, sizeof path) != SLUICE_OK) {
        if (!path[0]) {
            s->disabled = 1; /* no output directory: nothing is written */
            return SLUICE_OK;
        }
        api->messages->error(host, "the path of '%s' in the output directory is too long", name);
        s->broken = 1;
        return SLUICE_ERROR;
    }

    if (!s->walls.ready && gather_walls(s, host) != SLUICE_OK) {
        s->broken = 1;
        return SLUICE_ERROR;
    }
    if (s->walls.count > 0)
        move_walls(s, host);

    /* HDF5 errors are reported once, here, not printed by the library */
    H5E_auto2_t old_func = NULL;
    void *old_data = NULL;
    H5Eget_auto2(H5E_DEFAULT, &old_func, &old_data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    h5w_failure failure = {{0}};
    sluice_ranks ranks = {0, 1, 0, v->count, NULL};
    if (api->ranks->ranks(host, &ranks) != SLUICE_OK) {
        s->broken = 1;
        return SLUICE_ERROR;
    }
    int rc = SLUICE_OK;
    if (ranks.count > 1 && write_shared(s, host, v, &ranks, path, status, &failure) != 0) {
        api->messages->error(host, "cannot write snapshot '%s' (t = %.9g s): %s", path, v->time,
                             failure.text);
        rc = SLUICE_ERROR;
    } else if (ranks.count <= 1) {
        /* a temporary file in the same directory, renamed once complete;
         * the core reports a failure with the path */
        h5w_job job = {s, host, v, status};
        rc = api->output->write_file_with(host, path, write_snapshot_file, &job);
    }
    H5Eclear2(H5E_DEFAULT);
    H5Eset_auto2(H5E_DEFAULT, old_func, old_data);
    if (rc != SLUICE_OK) {
        s->broken = 1;
        return SLUICE_ERROR;
    }
    s->snapshots++;
    s->have_last = 1;
    s->last_step = v->step;
    s->last_time = v->time;
    if (write_walls_index(s, host) != SLUICE_OK ||
        write_xdmf(s, host, v, ranks.particle_total, stem) != SLUICE_OK) {
        s->broken = 1;
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static int h5w_after_step(void *state, sluice_host *host)
{
    h5w_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    if (!sluice_schedule_due(&s->schedule, v->time))
        return SLUICE_OK;
    if (!s->disabled && write_snapshot(s, host, "ok") != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->schedule, s->api, host, v->time);
    return SLUICE_OK;
}

/* The final snapshot: always after a failure (it holds the state that made
 * the run stop), otherwise unless the last regular one is of this state. */
static int h5w_finish(void *state, sluice_host *host, int status)
{
    h5w_state *s = state;
    if (s->disabled || s->broken)
        return SLUICE_OK;
    const sluice_view *v = s->api->particles->view(host);
    if (status != SLUICE_FINISH_FAILED && s->have_last && s->last_step == v->step &&
        s->last_time == v->time)
        return SLUICE_OK;
    return write_snapshot(s, host, status == SLUICE_FINISH_FAILED ? "failed" : "ok");
}

/* Checkpoints: the schedule, the file index, the last snapshot and the
 * XDMF records (time and particle count of every snapshot so far). */
static int h5w_save(void *state, sluice_host *host)
{
    const h5w_state *s = state;
    const sluice_api *api = s->api;
    const size_t n = s->record_count;
    double *times = malloc((n + 1) * sizeof *times);
    uint64_t *counts = malloc((n + 1) * sizeof *counts);
    int rc = SLUICE_ERROR;
    if (!times || !counts) {
        api->messages->error(host, "out of memory");
    } else {
        for (size_t r = 0; r < n; r++) {
            times[r] = s->records[r].time;
            counts[r] = s->records[r].count;
        }
        if (sluice_schedule_save(&s->schedule, api, host, "schedule") == SLUICE_OK &&
            sluice_util_save_int(api, host, "snapshots", (int64_t)s->snapshots) == SLUICE_OK &&
            sluice_util_save_int(api, host, "have_last", s->have_last) == SLUICE_OK &&
            sluice_util_save_int(api, host, "last_step", s->last_step) == SLUICE_OK &&
            sluice_util_save_double(api, host, "last_time", s->last_time) == SLUICE_OK &&
            api->state->state_write(host, "record_times", SLUICE_STATE_DOUBLE, n, times) == SLUICE_OK &&
            api->state->state_write(host, "record_counts", SLUICE_STATE_UINT64, n, counts) == SLUICE_OK)
            rc = SLUICE_OK;
    }
    free(times);
    free(counts);
    return rc;
}

static int h5w_load(void *state, sluice_host *host)
{
    h5w_state *s = state;
    const sluice_api *api = s->api;
    int64_t snapshots = 0, have_last = 0;
    const int64_t n = api->state->state_length(host, "record_times");
    if (sluice_schedule_load(&s->schedule, api, host, "schedule") != SLUICE_OK ||
        sluice_util_load_int(api, host, "snapshots", &snapshots) != SLUICE_OK ||
        sluice_util_load_int(api, host, "have_last", &have_last) != SLUICE_OK ||
        sluice_util_load_int(api, host, "last_step", &s->last_step) != SLUICE_OK ||
        sluice_util_load_double(api, host, "last_time", &s->last_time) != SLUICE_OK || n < 0 ||
        snapshots < 0)
        return SLUICE_ERROR;
    s->snapshots = (uint64_t)snapshots;
    s->have_last = have_last != 0;
    double *times = malloc(((size_t)n + 1) * sizeof *times);
    uint64_t *counts = malloc(((size_t)n + 1) * sizeof *counts);
    h5w_record *records = calloc((size_t)n + 1, sizeof *records);
    int rc = SLUICE_ERROR;
    if (!times || !counts || !records) {
        api->messages->error(host, "out of memory");
    } else if (api->state->state_read(host, "record_times", SLUICE_STATE_DOUBLE, (uint64_t)n, times) ==
                   SLUICE_OK &&
               api->state->state_read(host, "record_counts", SLUICE_STATE_UINT64, (uint64_t)n,
                               counts) == SLUICE_OK) {
        const sluice_view *v = api->particles->view(host);
        /* snapshot r is <prefix>_r; the last n of them are recorded */
        const uint64_t first = s->snapshots >= (uint64_t)n ? s->snapshots - (uint64_t)n : 0;
        for (int64_t r = 0; r < n; r++) {
            snprintf(records[r].stem, sizeof records[r].stem, "%s_%06llu", s->prefix,
                     (unsigned long long)(first + (uint64_t)r));
            records[r].time = times[r];
            records[r].count = counts[r];
            records[r].dimensions = v->dimensions;
        }
        free(s->records);
        s->records = records;
        records = NULL;
        s->record_count = (size_t)n;
        s->record_capacity = (size_t)n + 1;
        s->vertex_capacity = 0; /* rewritten with the next snapshot */
        s->prune_records = 1;
        rc = SLUICE_OK;
    }
    free(times);
    free(counts);
    free(records);
    return rc;
}

static const sluice_component components[] = {{
    .name = "hdf5",
    .summary = "particle snapshots in HDF5 (one file per output time) with the scene's walls "
               "and an XDMF index",
    .reference = "HDF5 (The HDF Group); XDMF 3 (xdmf.org)",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_ACROSS_RANKS,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(h5w_config),
    .create = h5w_create,
    .destroy = h5w_destroy,
    .bind = h5w_bind,
    .initialise = h5w_initialise,
    .after_step = h5w_after_step,
    .finish = h5w_finish,
    .save_state = h5w_save,
    .load_state = h5w_load,
}};

SLUICE_DEFINE_LIBRARY("hdf5_writer", "1.3.0", "HDF5 particle snapshots with an XDMF index",
                      SLUICE_DIMS_ALL, components)
