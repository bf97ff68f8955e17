/* libFuzzer target: the checkpoint reader (sluice_sim_restart, the plugins'
 * load_state) behind the checksum.
 *
 * At start-up the target runs the scene checkpoint_scene.yaml (a channel of
 * about 300 particles with open boundaries, gauges and the HDF5 writer) to
 * t = 0.01 s and writes one valid checkpoint of it. Each input is a list of
 * up to eight edits of a copy of that checkpoint without its checksum
 * trailer, made through the HDF5 API on an object picked by index from the
 * file's own listing (every link, every attribute):
 *  - delete it;
 *  - give it another element type (integers, reals, big-endian ones,
 *    strings, a compound, an array, a bitfield, opaque bytes), with values
 *    from the input;
 *  - change values: special ones (0, -1, huge, NaN, infinities, 2^32, the
 *    old value plus or minus a little), raw bytes, one element or all of
 *    them; strings cut, emptied, replaced, a line removed or doubled;
 *  - give it another shape: another rank or length, an empty or null
 *    dataspace, or a huge extent declared without data (2^31 to 2^40);
 *  - make its name a hard link to another object, a soft link (dangling,
 *    to itself), an external link, an empty group or a named datatype; an
 *    attribute takes another attribute's type and value;
 *  - cut the file short.
 * The file then gets a valid trailer again (sluice_checksum_append), so the
 * restart's own checks of types, shapes, counts and values are what is
 * tested, not the checksum. A freshly loaded sim of the scene restarts from
 * it and, when that succeeds, takes two steps: into a copy of the run's
 * output directory (its tables cut or continued) when the input's first byte
 * is odd, with no output directory when it is even. Any input must end in a
 * restart or in one message (one line) naming the file; a crash, a sanitizer
 * report, a leak or a hang is a finding. SLUICE_FUZZ_VERBOSE=1 prints each
 * edit and the restart's answer.
 *
 * SLUICE_FUZZ_RAW_BYTES=1 adds a seventh kind of edit: flipping raw bytes of
 * the HDF5 file behind the valid checksum. That tests the HDF5 library's own
 * parser (1.10, not instrumented, with known CVEs), from which the checksum
 * shields users: a checkpoint changed after it was written never reaches it.
 * The default campaign leaves it out, to test Sluice's reader.
 *
 * Everything per input lives in /tmp/sluice-fuzz-checkpoint-<pid>/, removed
 * at exit (after a crash, at the next start). Built by `tools/fuzz.sh SECONDS WORKERS checkpoint` (clang,
 * -fsanitize=fuzzer, address, undefined); docs/reliability.md. */
#define _GNU_SOURCE
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <ftw.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "diag.h"
#include "file_checksum.h"
#include "fuzz_plugins.h"
#include "sim.h"

#ifndef FUZZ_CHECKPOINT_SCENE
#define FUZZ_CHECKPOINT_SCENE "tests/core/fuzz/checkpoint_scene.yaml"
#endif
#define CHECKPOINT_TIME 0.01  /* s, the checkpoint's time (an output time of the scene) */
#define MAX_EDITS 8
#define MAX_ENTRIES 512
#define MAX_DATA_POINTS 65536 /* elements of a new dataset that get data */
#define MAX_EDIT_POINTS 1048576

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

/* A file of the run's output directory at the checkpoint. */
typedef struct output_file {
    char name[256];
    unsigned char *bytes;
    size_t size;
} output_file;

static struct {
    char base[64];   /* the private directory */
    const char *scene;
    unsigned char *pristine; /* the checkpoint without its trailer */
    size_t pristine_size;
    output_file *outputs;
    size_t output_count;
    int raw;     /* SLUICE_FUZZ_RAW_BYTES=1: raw byte flips too */
    int verbose; /* SLUICE_FUZZ_VERBOSE=1: each edit and the restart's answer on stderr */
} fz;

/* ------------------------------------------------------------ the input -- */

typedef struct input {
    const uint8_t *data;
    size_t size, at;
} input;

static unsigned take(input *in)
{
    return in->at < in->size ? in->data[in->at++] : 0;
}

static uint64_t take_bytes(input *in, int count)
{
    uint64_t value = 0;
    for (int i = 0; i < count; i++)
        value = value << 8 | take(in);
    return value;
}

/* ---------------------------------------------------------------- files -- */

static int write_bytes(const char *path, const void *bytes, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    int ok = (size == 0 || fwrite(bytes, 1, size, f) == size);
    return fclose(f) == 0 && ok ? 0 : -1;
}

static unsigned char *read_bytes(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    unsigned char *bytes = NULL;
    long n = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (n >= 0 && fseek(f, 0, SEEK_SET) == 0 && (bytes = malloc((size_t)n + 1)) != NULL &&
        fread(bytes, 1, (size_t)n, f) != (size_t)n) {
        free(bytes);
        bytes = NULL;
    }
    fclose(f);
    *size = n > 0 ? (size_t)n : 0;
    return bytes;
}

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    (void)ftw;
    remove(path);
    return 0;
}

static void remove_tree(const char *path)
{
    nftw(path, remove_one, 16, FTW_DEPTH | FTW_PHYS);
}

static void remove_base(void)
{
    if (fz.base[0])
        remove_tree(fz.base);
}

/* The directories of this target's processes that are gone (a crash skips
 * atexit and leaves the checkpoint that crashed: kept until the next
 * start). */
static void remove_stale(void)
{
    DIR *d = opendir("/tmp");
    if (!d)
        return;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        long pid = 0;
        char rest = 0, path[300];
        if (sscanf(e->d_name, "sluice-fuzz-checkpoint-%ld%c", &pid, &rest) != 1 || pid <= 0 ||
            pid == (long)getpid() || kill((pid_t)pid, 0) == 0 || errno != ESRCH)
            continue;
        snprintf(path, sizeof path, "/tmp/%s", e->d_name);
        remove_tree(path);
    }
    closedir(d);
}

static void give_up(const char *what, const char *path)
{
    fprintf(stderr, "fuzz_checkpoint: %s '%s': %s\n", what, path, strerror(errno));
    abort();
}

/* ------------------------------------------------- the file's listing -- */

typedef struct entry {
    char path[240]; /* "/" or "/core/requests" */
    char attr[80];  /* an attribute of that object; "" for the link itself */
} entry;

typedef struct listing {
    entry items[MAX_ENTRIES];
    size_t count;
    hid_t file;
    const char *current; /* the object whose attributes are being listed */
} listing;

static herr_t add_attribute(hid_t object, const char *name, const H5A_info_t *info, void *data)
{
    (void)object;
    (void)info;
    listing *l = data;
    if (l->count < MAX_ENTRIES && strlen(l->current) < sizeof l->items[0].path &&
        strlen(name) < sizeof l->items[0].attr) {
        strcpy(l->items[l->count].path, l->current);
        strcpy(l->items[l->count].attr, name);
        l->count++;
    }
    return 0;
}

static void add_object(listing *l, const char *path, int hard)
{
    if (l->count >= MAX_ENTRIES || strlen(path) >= sizeof l->items[0].path)
        return;
    strcpy(l->items[l->count].path, path);
    l->items[l->count].attr[0] = '\0';
    l->count++;
    if (!hard)
        return;
    l->current = path;
    hsize_t at = 0;
    H5Aiterate_by_name(l->file, path, H5_INDEX_NAME, H5_ITER_INC, &at, add_attribute, l,
                       H5P_DEFAULT);
}

static herr_t add_link(hid_t group, const char *name, const H5L_info_t *info, void *data)
{
    (void)group;
    char path[sizeof ((entry *)0)->path];
    if (snprintf(path, sizeof path, "/%s", name) < (int)sizeof path)
        add_object(data, path, info->type == H5L_TYPE_HARD);
    return 0;
}

/* Every link and attribute of the file, in a fixed order (by name). */
static listing *list_file(hid_t file)
{
    listing *l = malloc(sizeof *l);
    if (!l)
        return NULL;
    l->count = 0;
    l->file = file;
    add_object(l, "/", 1);
    H5Lvisit(file, H5_INDEX_NAME, H5_ITER_INC, add_link, l);
    return l;
}

/* ----------------------------------------------------------- elements -- */

/* An entry's attribute or dataset with its stored type and dataspace. */
typedef struct opened {
    hid_t id, type, space;
    int is_attr;
    hssize_t points;
} opened;

static void close_opened(opened *o)
{
    if (o->space >= 0)
        H5Sclose(o->space);
    if (o->type >= 0)
        H5Tclose(o->type);
    if (o->id >= 0)
        (o->is_attr ? H5Aclose : H5Dclose)(o->id);
    o->id = o->type = o->space = -1;
}

static int open_entry(hid_t file, const entry *e, opened *o)
{
    o->is_attr = e->attr[0] != '\0';
    o->type = o->space = -1;
    if (o->is_attr) {
        o->id = H5Aopen_by_name(file, e->path, e->attr, H5P_DEFAULT, H5P_DEFAULT);
    } else {
        H5O_info_t info;
        o->id = -1;
        if (H5Oget_info_by_name2(file, e->path, &info, H5O_INFO_BASIC, H5P_DEFAULT) >= 0 &&
            info.type == H5O_TYPE_DATASET)
            o->id = H5Dopen2(file, e->path, H5P_DEFAULT);
    }
    if (o->id >= 0) {
        o->type = o->is_attr ? H5Aget_type(o->id) : H5Dget_type(o->id);
        o->space = o->is_attr ? H5Aget_space(o->id) : H5Dget_space(o->id);
    }
    if (o->id < 0 || o->type < 0 || o->space < 0) {
        close_opened(o);
        return -1;
    }
    o->points = H5Sget_simple_extent_npoints(o->space);
    return 0;
}

static herr_t read_all(const opened *o, hid_t memory, void *buffer)
{
    return o->is_attr ? H5Aread(o->id, memory, buffer)
                      : H5Dread(o->id, memory, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer);
}

static herr_t write_all(const opened *o, hid_t memory, const void *buffer)
{
    return o->is_attr ? H5Awrite(o->id, memory, buffer)
                      : H5Dwrite(o->id, memory, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer);
}

static const double special_reals[] = {
    0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, 1e300, -1e300, 1e10, -1e10, NAN, INFINITY, -INFINITY,
    DBL_MAX, 4.9e-324, 1e-9, 10.0, CHECKPOINT_TIME,
};
static const int64_t special_integers[] = {
    0, 1, -1, 2, 7, 255, 256, 65535, INT32_MAX, INT32_MIN, UINT32_MAX, (int64_t)UINT32_MAX + 1,
    INT64_MAX, INT64_MIN, 1ll << 40, 3, 300, 320,
};
#define SPECIALS (sizeof special_reals / sizeof special_reals[0])
_Static_assert(SPECIALS == sizeof special_integers / sizeof special_integers[0],
               "as many special integers as reals");

/* One element of stored type `type` at `element` (size bytes, holding the
 * old value): a special value, the old one plus or minus a little, or raw
 * bytes, from the input. */
static void make_element(input *in, hid_t type, unsigned char *element, size_t size)
{
    const H5T_class_t c = H5Tget_class(type);
    const unsigned mode = take(in) % 24;
    unsigned char buffer[64];
    if ((c != H5T_INTEGER && c != H5T_FLOAT) || mode >= 20 || size > 16) {
        for (size_t i = 0; i < size; i++)
            element[i] = (unsigned char)take(in);
        return;
    }
    const int is_unsigned = c == H5T_INTEGER && H5Tget_sign(type) == H5T_SGN_NONE;
    const hid_t native = c == H5T_FLOAT ? H5T_NATIVE_DOUBLE
                         : is_unsigned  ? H5T_NATIVE_UINT64
                                        : H5T_NATIVE_INT64;
    memset(buffer, 0, sizeof buffer);
    if (mode < SPECIALS) {
        if (c == H5T_FLOAT)
            memcpy(buffer, &special_reals[mode], sizeof(double));
        else
            memcpy(buffer, &special_integers[mode], sizeof(int64_t)); /* -1: all ones */
    } else { /* the old value plus or minus a little */
        memcpy(buffer, element, size);
        const int delta = (int)(take(in) % 7) - 3;
        if (H5Tconvert(type, native, 1, buffer, NULL, H5P_DEFAULT) < 0)
            return;
        if (c == H5T_FLOAT) {
            double v;
            memcpy(&v, buffer, sizeof v);
            v = delta == 0 ? v * 2 : v + delta * 1e-3 * fabs(v) + delta;
            memcpy(buffer, &v, sizeof v);
        } else {
            uint64_t v;
            memcpy(&v, buffer, sizeof v);
            v += (uint64_t)(int64_t)delta;
            memcpy(buffer, &v, sizeof v);
        }
    }
    if (H5Tconvert(native, type, 1, buffer, NULL, H5P_DEFAULT) >= 0)
        memcpy(element, buffer, size);
}

/* A string from an old one (NULL for a null string): emptied, cut, replaced
 * by input bytes, one line removed or doubled, input bytes inserted. */
static char *edited_text(input *in, const char *old, int *null)
{
    const char *text = old ? old : "";
    const size_t length = strlen(text), at = (size_t)take_bytes(in, 2) % (length + 1);
    char piece[65];
    const size_t n = take(in) % sizeof piece;
    for (size_t i = 0; i < n; i++)
        piece[i] = (char)(take(in) | 1); /* never a NUL */
    piece[n] = '\0';
    const unsigned mode = take(in) % 6;
    *null = mode == 1;
    char *edited = malloc(length + sizeof piece + length + 2);
    if (!edited)
        return NULL;
    const char *line = text;
    for (size_t k = at % 16; k > 0 && strchr(line, '\n'); k--)
        line = strchr(line, '\n') + 1;
    const size_t before = (size_t)(line - text), line_length = strcspn(line, "\n") + 1;
    switch (mode) {
    case 0:
    case 1: edited[0] = '\0'; break;
    case 2: strcpy(edited, piece); break;
    case 3: snprintf(edited, length + 1, "%.*s", (int)at, text); break;
    case 4: /* line removed */
        snprintf(edited, length + 1, "%.*s%s", (int)before, text,
                 line[line_length - 1] ? line + line_length : "");
        break;
    default: /* a line doubled, the piece inserted */
        sprintf(edited, "%.*s%.*s%s%s", (int)before, text, (int)line_length, line, piece, line);
        break;
    }
    return edited;
}

/* --------------------------------------------------------------- edits -- */

/* A string attribute or dataset: one element's text edited. */
static void edit_strings(const opened *o, input *in)
{
    hid_t memory = H5Tget_native_type(o->type, H5T_DIR_ASCEND);
    char **texts = calloc((size_t)o->points, sizeof *texts);
    if (memory >= 0 && texts && read_all(o, memory, texts) >= 0) {
        const size_t k = (size_t)take_bytes(in, 2) % (size_t)o->points;
        int null = 0;
        char *old = texts[k], *edited = edited_text(in, old, &null);
        if (edited) {
            texts[k] = null ? NULL : edited;
            write_all(o, memory, texts);
        }
        texts[k] = old;
        free(edited);
        H5Dvlen_reclaim(memory, o->space, H5P_DEFAULT, texts);
    }
    free(texts);
    if (memory >= 0)
        H5Tclose(memory);
}

/* New values of some elements (or all) of an attribute or dataset. */
static void edit_values(hid_t file, const entry *e, input *in)
{
    opened o;
    if (open_entry(file, e, &o) != 0)
        return;
    if (o.points > 0 && o.points <= MAX_EDIT_POINTS) {
        const size_t size = H5Tget_size(o.type), points = (size_t)o.points;
        unsigned char *values = size > 0 && size <= 64 ? malloc(points * size) : NULL;
        if (H5Tis_variable_str(o.type) > 0) {
            edit_strings(&o, in);
        } else if (H5Tdetect_class(o.type, H5T_VLEN) <= 0 && values &&
                   read_all(&o, o.type, values) >= 0) {
            const unsigned how = take(in);
            if (how & 0x80) { /* every element the same value */
                make_element(in, o.type, values, size);
                for (size_t i = 1; i < points; i++)
                    memcpy(values + i * size, values, size);
            } else {
                for (unsigned k = 0; k <= how % 4; k++) {
                    const size_t i = (size_t)take_bytes(in, 3) % points;
                    make_element(in, o.type, values + i * size, size);
                }
            }
            write_all(&o, o.type, values);
        }
        free(values);
    }
    close_opened(&o);
}

/* An element type for a replacement (a new type the caller closes). */
static hid_t pick_type(input *in)
{
    const hid_t atomic[] = {
        H5T_NATIVE_INT8,  H5T_NATIVE_UINT8,  H5T_NATIVE_INT32, H5T_NATIVE_UINT32,
        H5T_NATIVE_INT64, H5T_NATIVE_UINT64, H5T_NATIVE_FLOAT, H5T_NATIVE_DOUBLE,
        H5T_STD_I64BE,    H5T_IEEE_F64BE,    H5T_STD_U64BE,    H5T_NATIVE_B8,
    };
    const size_t n = sizeof atomic / sizeof atomic[0], k = take(in) % (n + 5);
    if (k < n)
        return H5Tcopy(atomic[k]);
    hid_t t = -1;
    if (k == n || k == n + 1) { /* fixed-size or variable-length string */
        t = H5Tcopy(H5T_C_S1);
        if (t >= 0)
            H5Tset_size(t, k == n ? 8 : H5T_VARIABLE);
    } else if (k == n + 2) { /* a compound of one double */
        t = H5Tcreate(H5T_COMPOUND, sizeof(double));
        if (t >= 0)
            H5Tinsert(t, "value", 0, H5T_NATIVE_DOUBLE);
    } else if (k == n + 3) { /* an array of two doubles */
        hsize_t two[1] = {2};
        t = H5Tarray_create2(H5T_NATIVE_DOUBLE, 1, two);
    } else {
        t = H5Tcreate(H5T_OPAQUE, 8);
    }
    return t;
}

/* A dataspace: another rank, lengths near the old ones, empty or null, or a
 * huge extent (*declared: no data to write). */
static hid_t pick_space(input *in, const opened *old, int *declared)
{
    hsize_t was[H5S_MAX_RANK] = {0}, dims[3] = {1, 1, 1};
    int was_rank = old ? H5Sget_simple_extent_dims(old->space, was, NULL) : 0;
    if (was_rank < 0 || was_rank > 3)
        was_rank = 0;
    const unsigned mode = take(in) % 8;
    if (mode == 0)
        return H5Screate(H5S_SCALAR);
    if (mode == 1)
        return H5Screate(H5S_NULL);
    const int rank = mode <= 4 ? (was_rank > 0 ? was_rank : 1) : (int)mode - 4;
    static const hsize_t huge[] = {1ull << 31, 1ull << 32, 1ull << 36, 1ull << 40};
    double points = 1;
    *declared = 0;
    for (int d = 0; d < rank; d++) {
        const hsize_t w = d < was_rank ? was[d] : 1;
        const unsigned how = take(in) % 8;
        switch (how) {
        case 0: dims[d] = w; break;
        case 1: dims[d] = w + 1; break;
        case 2: dims[d] = w > 0 ? w - 1 : 0; break;
        case 3: dims[d] = 0; break;
        case 4: dims[d] = 1; break;
        case 5: dims[d] = take(in); break;
        case 6: dims[d] = w + take(in); break;
        default: dims[d] = huge[take(in) % 4]; break;
        }
        points *= (double)dims[d];
    }
    *declared = points > MAX_DATA_POINTS;
    return H5Screate_simple(rank, dims, NULL);
}

/* Data for `points` elements of `type`: zeros, input bytes, the old
 * object's bytes (same type), or one value everywhere. */
static void *make_data(input *in, hid_t type, size_t points, const opened *old, int same_type)
{
    const size_t size = H5Tget_size(type);
    const int strings = H5Tis_variable_str(type) > 0;
    if (size == 0 || size > 64 || (H5Tdetect_class(type, H5T_VLEN) > 0 && !strings))
        return NULL;
    unsigned char *data = calloc(points + 1, size);
    if (!data || strings)
        return data; /* null strings; the caller may set them */
    const unsigned mode = take(in) % 4;
    if (mode == 1) {
        for (size_t i = 0; i < points * size; i++)
            data[i] = (unsigned char)take(in);
    } else if (mode == 2 && old && same_type && old->points > 0 &&
               old->points <= MAX_EDIT_POINTS) {
        unsigned char *was = malloc((size_t)old->points * size);
        if (was && read_all(old, old->type, was) >= 0)
            memcpy(data, was, size * (points < (size_t)old->points ? points : (size_t)old->points));
        free(was);
    } else if (mode == 3) {
        make_element(in, type, data, size);
        for (size_t i = 1; i < points; i++)
            memcpy(data + i * size, data, size);
    }
    return data;
}

/* The entry replaced by an attribute or dataset of another type
 * (`new_type`) or another shape (`new_shape`), or both. */
static void replace_entry(hid_t file, const entry *e, input *in, int new_type, int new_shape)
{
    if (strcmp(e->path, "/") == 0 && !e->attr[0])
        return;
    opened old;
    const int had = open_entry(file, e, &old) == 0;
    hid_t type = had && !new_type ? H5Tcopy(old.type) : pick_type(in);
    int declared = 0;
    hid_t space = had && !new_shape ? H5Scopy(old.space) : pick_space(in, had ? &old : NULL,
                                                                      &declared);
    const hssize_t points = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
    void *data = NULL;
    char text[] = "x";
    if (type >= 0 && points > 0 && !declared) {
        data = make_data(in, type, (size_t)points, had ? &old : NULL, !new_type);
        if (data && H5Tis_variable_str(type) > 0 && (take(in) & 1))
            for (hssize_t i = 0; i < points; i++)
                ((char **)data)[i] = text;
    }
    close_opened(&old);
    hid_t made = -1, dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (type >= 0 && space >= 0 && dcpl >= 0) {
        if (e->attr[0]) {
            H5Adelete_by_name(file, e->path, e->attr, H5P_DEFAULT);
            made = H5Acreate_by_name(file, e->path, e->attr, type, space, H5P_DEFAULT,
                                     H5P_DEFAULT, H5P_DEFAULT);
            if (made >= 0 && data)
                H5Awrite(made, type, data);
        } else {
            hsize_t dims[H5S_MAX_RANK], chunk[H5S_MAX_RANK];
            const int rank = H5Sget_simple_extent_dims(space, dims, NULL);
            if (declared && rank > 0 && (take(in) & 1)) { /* chunked, no chunk written */
                for (int d = 0; d < rank; d++)
                    chunk[d] = dims[d] < 64 && dims[d] > 0 ? dims[d] : 64;
                H5Pset_chunk(dcpl, rank, chunk);
            }
            H5Ldelete(file, e->path, H5P_DEFAULT);
            made = H5Dcreate2(file, e->path, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
            if (made >= 0 && data)
                H5Dwrite(made, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
        }
    }
    if (made >= 0)
        (e->attr[0] ? H5Aclose : H5Dclose)(made);
    free(data);
    if (dcpl >= 0)
        H5Pclose(dcpl);
    if (space >= 0)
        H5Sclose(space);
    if (type >= 0)
        H5Tclose(type);
}

/* An attribute takes another attribute's type, shape and value. */
static void copy_attribute(hid_t file, const entry *e, const entry *other)
{
    opened from;
    if (!other->attr[0] || open_entry(file, other, &from) != 0)
        return;
    hid_t memory = H5Tget_native_type(from.type, H5T_DIR_ASCEND);
    const size_t size = memory >= 0 ? H5Tget_size(memory) : 0;
    void *value = from.points > 0 && from.points < 4096 && size > 0 && size <= 64
                      ? calloc((size_t)from.points, size)
                      : NULL;
    if (value && read_all(&from, memory, value) >= 0) {
        H5Adelete_by_name(file, e->path, e->attr, H5P_DEFAULT);
        hid_t made = H5Acreate_by_name(file, e->path, e->attr, from.type, from.space,
                                       H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (made >= 0) {
            H5Awrite(made, memory, value);
            H5Aclose(made);
        }
        if (H5Tdetect_class(memory, H5T_VLEN) > 0 || H5Tis_variable_str(memory) > 0)
            H5Dvlen_reclaim(memory, from.space, H5P_DEFAULT, value);
    }
    free(value);
    if (memory >= 0)
        H5Tclose(memory);
    close_opened(&from);
}

/* The entry's name made a hard link to another object, a soft link
 * (elsewhere, nowhere, to itself), an external link, an empty group or a
 * named datatype; an attribute takes another attribute's value. */
static void relink_entry(hid_t file, const entry *e, const listing *l, input *in)
{
    const entry *other = &l->items[take_bytes(in, 2) % l->count];
    if (e->attr[0]) {
        copy_attribute(file, e, other);
        return;
    }
    if (strcmp(e->path, "/") == 0)
        return;
    const unsigned mode = take(in) % 7;
    H5Ldelete(file, e->path, H5P_DEFAULT);
    switch (mode) {
    case 0: H5Lcreate_hard(file, other->path, file, e->path, H5P_DEFAULT, H5P_DEFAULT); break;
    case 1: H5Lcreate_soft(other->path, file, e->path, H5P_DEFAULT, H5P_DEFAULT); break;
    case 2: H5Lcreate_soft("/no/such/object", file, e->path, H5P_DEFAULT, H5P_DEFAULT); break;
    case 3: H5Lcreate_soft(e->path, file, e->path, H5P_DEFAULT, H5P_DEFAULT); break;
    case 4:
        H5Lcreate_external("no_such_file.h5", "/x", file, e->path, H5P_DEFAULT, H5P_DEFAULT);
        break;
    case 5: {
        hid_t group = H5Gcreate2(file, e->path, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (group >= 0)
            H5Gclose(group);
        break;
    }
    default: {
        hid_t type = H5Tcopy(H5T_NATIVE_DOUBLE);
        if (type >= 0) {
            H5Tcommit2(file, e->path, type, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
            H5Tclose(type);
        }
        break;
    }
    }
}

static void delete_entry(hid_t file, const entry *e)
{
    if (e->attr[0])
        H5Adelete_by_name(file, e->path, e->attr, H5P_DEFAULT);
    else if (strcmp(e->path, "/") != 0)
        H5Ldelete(file, e->path, H5P_DEFAULT);
}

enum { EDIT_DELETE, EDIT_TYPE, EDIT_VALUES, EDIT_SHAPE, EDIT_LINK, EDIT_CUT, EDIT_FLIP };
static const char *const edit_names[] = {"delete", "type", "values", "shape", "link", "cut",
                                         "flip"};

/* Edits of the file itself, made once HDF5 has closed it. */
typedef struct byte_edit {
    int kind; /* EDIT_CUT, EDIT_FLIP */
    uint64_t at;
    unsigned char mask;
} byte_edit;

/* The input's edits through HDF5; those of bytes are returned for later. */
static size_t edit_objects(const char *path, input *in, byte_edit *bytes)
{
    size_t byte_count = 0;
    hid_t access = H5Pcreate(H5P_FILE_ACCESS);
    if (access < 0 || H5Pset_fclose_degree(access, H5F_CLOSE_STRONG) < 0)
        abort();
    hid_t file = H5Fopen(path, H5F_ACC_RDWR, access);
    H5Pclose(access);
    if (file < 0) {
        fprintf(stderr, "fuzz_checkpoint: HDF5 cannot open the copy of the checkpoint\n");
        abort();
    }
    for (int k = 0; k < MAX_EDITS && in->at < in->size; k++) {
        const unsigned kind = take(in) % (fz.raw ? EDIT_FLIP + 1 : EDIT_FLIP);
        if (kind == EDIT_CUT || kind == EDIT_FLIP) {
            bytes[byte_count].kind = (int)kind;
            bytes[byte_count].at = take_bytes(in, 3);
            bytes[byte_count].mask = (unsigned char)(take(in) % 255 + 1);
            if (fz.verbose)
                fprintf(stderr, "fuzz_checkpoint: edit %d (%s) at byte %llu (modulo the size)\n",
                        k, edit_names[kind], (unsigned long long)bytes[byte_count].at);
            byte_count++;
            continue;
        }
        listing *l = list_file(file);
        if (!l) {
            fprintf(stderr, "fuzz_checkpoint: out of memory\n");
            abort();
        }
        const entry *e = l->count ? &l->items[take_bytes(in, 2) % l->count] : NULL;
        if (fz.verbose && e)
            fprintf(stderr, "fuzz_checkpoint: edit %d (%s) of %s%s%s\n", k, edit_names[kind],
                    e->path, e->attr[0] ? " attribute " : "", e->attr);
        if (e && kind == EDIT_DELETE)
            delete_entry(file, e);
        else if (e && (kind == EDIT_TYPE || kind == EDIT_SHAPE))
            replace_entry(file, e, in, kind == EDIT_TYPE, kind == EDIT_SHAPE || (take(in) & 1));
        else if (e && kind == EDIT_VALUES)
            edit_values(file, e, in);
        else if (e)
            relink_entry(file, e, l, in);
        free(l);
    }
    H5Fclose(file);
    return byte_count;
}

static void edit_bytes(const char *path, const byte_edit *edits, size_t count)
{
    for (size_t k = 0; k < count; k++) {
        struct stat st;
        if (stat(path, &st) != 0 || st.st_size <= 0)
            return;
        const off_t at = (off_t)(edits[k].at % (uint64_t)st.st_size);
        if (edits[k].kind == EDIT_CUT) {
            if (truncate(path, at) != 0)
                give_up("cannot cut", path);
            continue;
        }
        FILE *f = fopen(path, "r+b");
        if (!f)
            give_up("cannot open", path);
        int c = fseeko(f, at, SEEK_SET) == 0 ? fgetc(f) : EOF;
        if (c != EOF && fseeko(f, at, SEEK_SET) == 0)
            fputc(c ^ edits[k].mask, f);
        fclose(f);
    }
}

/* ------------------------------------------------------------- restart -- */

static sluice_sim *load_scene(sluice_diag *diag)
{
    sluice_load_options options = {.threads = 1};
    sluice_sim *sim = sluice_sim_load(fz.scene, &options, diag);
    if (!sim) {
        fprintf(stderr, "fuzz_checkpoint: the scene %s does not load: %s\n", fz.scene,
                sluice_diag_count(diag) ? sluice_diag_message(diag, 0) : "?");
        abort();
    }
    return sim;
}

/* The restart from `path`, then two steps into `out` (NULL: no output
 * directory); or one message. */
static void restart(const char *path, const char *out)
{
    sluice_diag *diag = sluice_diag_create();
    if (!diag)
        abort();
    sluice_sim *sim = load_scene(diag);
    char error[4096] = "";
    if (sluice_sim_restart(sim, path, error, sizeof error) == SLUICE_OK) {
        int status = sluice_sim_begin(sim, out);
        if (status == SLUICE_RUN_COMPLETE) {
            for (int step = 0; step < 2 && status == SLUICE_RUN_COMPLETE; step++)
                status = sluice_sim_step(sim);
            status = sluice_sim_end(sim, status);
        }
        if (fz.verbose)
            fprintf(stderr, "fuzz_checkpoint: restarted; two steps: status %d %s\n", status,
                    sluice_sim_failure(sim));
    } else {
        const char *why = strstr(error, "': ");
        if (fz.verbose)
            fprintf(stderr, "fuzz_checkpoint: %s\n", error);
        if (!strstr(error, path) || strchr(error, '\n') || !why || !why[3]) {
            /* one line that names the file and says why */
            fprintf(stderr, "fuzz_checkpoint: not one message naming the file: '%s'\n", error);
            abort();
        }
    }
    sluice_sim_free(sim);
    sluice_diag_destroy(diag);
}

/* --------------------------------------------------------------- set-up -- */

/* The run's output directory at the checkpoint, kept in memory. */
static void keep_outputs(const char *directory)
{
    DIR *d = opendir(directory);
    if (!d)
        give_up("cannot list", directory);
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        char path[512];
        struct stat st;
        snprintf(path, sizeof path, "%s/%s", directory, e->d_name);
        if (stat(path, &st) != 0 || !S_ISREG(st.st_mode) || strlen(e->d_name) >= 256)
            continue;
        output_file *grown = realloc(fz.outputs, (fz.output_count + 1) * sizeof *grown);
        if (!grown)
            give_up("out of memory for", path);
        fz.outputs = grown;
        output_file *f = &fz.outputs[fz.output_count];
        strcpy(f->name, e->d_name);
        if (!(f->bytes = read_bytes(path, &f->size)))
            give_up("cannot read", path);
        fz.output_count++;
    }
    closedir(d);
}

/* Runs the scene to CHECKPOINT_TIME and keeps its checkpoint (without the
 * trailer) and its output directory. */
static void make_checkpoint(void)
{
    char run[128], checkpoint[128];
    snprintf(run, sizeof run, "%s/run", fz.base);
    snprintf(checkpoint, sizeof checkpoint, "%s/pristine.h5", fz.base);
    sluice_diag *diag = sluice_diag_create();
    if (!diag)
        abort();
    sluice_sim *sim = load_scene(diag);
    int status = sluice_sim_begin(sim, run);
    while (status == SLUICE_RUN_COMPLETE && sluice_sim_time(sim) < CHECKPOINT_TIME - 1e-12)
        status = sluice_sim_step(sim);
    if (status != SLUICE_RUN_COMPLETE || sluice_sim_checkpoint(sim, checkpoint) != SLUICE_OK) {
        fprintf(stderr, "fuzz_checkpoint: the scene's run or checkpoint failed: %s\n",
                sluice_sim_failure(sim));
        abort();
    }
    sluice_sim_end(sim, SLUICE_RUN_INTERRUPTED); /* as `sluice run` stopped by a signal */
    sluice_sim_free(sim);
    sluice_diag_destroy(diag);
    keep_outputs(run);
    fz.pristine = read_bytes(checkpoint, &fz.pristine_size);
    if (!fz.pristine || fz.pristine_size <= SLUICE_CHECKSUM_BYTES)
        give_up("cannot read", checkpoint);
    fz.pristine_size -= SLUICE_CHECKSUM_BYTES;
    remove_tree(run);
    unlink(checkpoint);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_keep_plugins_mapped("fuzz_checkpoint");
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* the edits' failures are expected */
    const char *raw = getenv("SLUICE_FUZZ_RAW_BYTES");
    fz.raw = raw && strcmp(raw, "1") == 0;
    const char *verbose = getenv("SLUICE_FUZZ_VERBOSE");
    fz.verbose = verbose && strcmp(verbose, "1") == 0;
    fz.scene = getenv("SLUICE_FUZZ_CHECKPOINT_SCENE");
    if (!fz.scene)
        fz.scene = FUZZ_CHECKPOINT_SCENE;
    snprintf(fz.base, sizeof fz.base, "/tmp/sluice-fuzz-checkpoint-%ld", (long)getpid());
    remove_stale();
    remove_tree(fz.base);
    if (mkdir(fz.base, 0700) != 0)
        give_up("cannot make", fz.base);
    atexit(remove_base);
    make_checkpoint();
    fprintf(stderr, "fuzz_checkpoint: a checkpoint of %zu bytes (without its trailer) of %s%s\n",
            fz.pristine_size, fz.scene, fz.raw ? "; raw byte flips on" : "");
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[128], out[128];
    snprintf(path, sizeof path, "%s/checkpoint.h5", fz.base);
    snprintf(out, sizeof out, "%s/out", fz.base);
    if (write_bytes(path, fz.pristine, fz.pristine_size) != 0)
        give_up("cannot write", path);
    input in = {data, size, 0};
    /* the first byte: an odd one continues into a copy of the run's output
     * directory (its tables cut or continued), at the cost of the engine's
     * writer processes (forks of this large process, 0.1 s an input); an
     * even one without an output directory */
    const int with_outputs = take(&in) & 1;
    if (with_outputs && mkdir(out, 0700) != 0)
        give_up("cannot make", out);
    for (size_t k = 0; with_outputs && k < fz.output_count; k++) {
        char copy[512];
        snprintf(copy, sizeof copy, "%s/%s", out, fz.outputs[k].name);
        if (write_bytes(copy, fz.outputs[k].bytes, fz.outputs[k].size) != 0)
            give_up("cannot write", copy);
    }
    byte_edit bytes[MAX_EDITS];
    const size_t byte_count = edit_objects(path, &in, bytes);
    edit_bytes(path, bytes, byte_count);
    char error[600];
    if (sluice_checksum_append(path, error, sizeof error) != 0) {
        fprintf(stderr, "fuzz_checkpoint: %s\n", error);
        abort();
    }
    restart(path, with_outputs ? out : NULL);
    if (with_outputs)
        remove_tree(out);
    unlink(path);
    return 0;
}
