/* The scene's walls in the hdf5 writer's output, for every wall scheme:
 *  - <prefix>_walls.h5 holds every wall's segments (2D) or triangles (3D)
 *    as the scene gives them: end points to round-off, counts, the wall of
 *    each element, normals into the fluid, names and schemes, for
 *    geometric walls (penalty_contact, no wall particles), for particle
 *    walls (dbc) and in 3D (a tank: ten triangles covering its five faces);
 *  - a moving wall (dbc's prescribed motion) is in every snapshot at the
 *    position of its law x_rest + U tau + A (sin(2 pi f tau + phi) - sin phi)
 *    at the snapshot's time;
 *  - the XDMF index is well-formed XML, and every HDF dataset it names
 *    exists with the dimensions it states (HyperSlabs within them), the
 *    element counts of its topologies matching. */
#include <hdf5.h>

#include "sim_util.h"

/* ------------------------------------------------------------ running -- */

/* Runs `yaml` to its end with its outputs in a fresh directory (returned). */
static char *run_scene(const char *tag, const char *yaml)
{
    sluice_sim *sim = test_load(tag, yaml, NULL, 0);
    char *scratch = test_scratch(tag), *out = NULL;
    ck_assert_ptr_nonnull(scratch);
    ck_assert_int_ge(asprintf(&out, "%s/out", scratch), 0);
    ck_assert_int_eq(sluice_sim_begin(sim, out), SLUICE_RUN_COMPLETE);
    const double end = sluice_sim_end_time(sim);
    while (sluice_sim_time(sim) < end - 1e-12) {
        int status = sluice_sim_step(sim);
        ck_assert_msg(status == SLUICE_RUN_COMPLETE, "%s: step failed: %s", tag,
                      sluice_sim_failure(sim));
    }
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    free(scratch);
    return out;
}

/* A 2D tank [0, 2] x [0, 1] with a baffle, the fluid in the middle; `scheme`
 * is the plugins entry of the wall scheme, `walls` extra wall lines. */
static char *scene_2d(const char *scheme, const char *walls)
{
    char *yaml = NULL;
    ck_assert_int_ge(asprintf(&yaml,
                              "dimensions: 2\n"
                              "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
                              "time: {end: 0.1}\n"
                              "domain: {min: [-0.3, -0.3], max: [2.3, 1.5]}\n"
                              "geometry:\n"
                              "  fluid: [{shape: box, min: [0.6, 0], max: [1.4, 0.3]}]\n"
                              "  walls:\n"
                              "    - {shape: tank, min: [0, 0], max: [2, 1], name: tank}\n"
                              "%s"
                              "plugins:\n"
                              "  wendland_c2: {}\n"
                              "  tait: {speed_of_sound: 20}\n"
                              "  continuity: {}\n"
                              "  pressure_gradient: {}\n"
                              "  artificial_viscosity: {alpha: 0.1}\n"
                              "  gravity: {}\n"
                              "  %s\n"
                              "  time_step: {}\n"
                              "  symplectic: {}\n"
                              "  hdf5: {interval: 0.05}\n",
                              walls, scheme),
                     0);
    return yaml;
}

/* ------------------------------------------------------------ reading -- */

/* A dataset read whole as doubles (any numeric type); dims[1] is 1 for a
 * one-dimensional dataset. */
static double *read_doubles(hid_t file, const char *name, hsize_t dims[2])
{
    hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
    ck_assert_msg(set >= 0, "no dataset '%s'", name);
    hid_t space = H5Dget_space(set);
    int rank = H5Sget_simple_extent_ndims(space);
    ck_assert_msg(rank == 1 || rank == 2, "dataset '%s' has rank %d", name, rank);
    dims[1] = 1;
    H5Sget_simple_extent_dims(space, dims, NULL);
    double *values = malloc((size_t)(dims[0] * dims[1] + 1) * sizeof *values);
    ck_assert_ptr_nonnull(values);
    if (dims[0] * dims[1] > 0)
        ck_assert_int_ge(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), 0);
    H5Sclose(space);
    H5Dclose(set);
    return values;
}

static double read_attribute(hid_t file, const char *name)
{
    double value = -1;
    hid_t attribute = H5Aopen(file, name, H5P_DEFAULT);
    ck_assert_msg(attribute >= 0, "no attribute '%s'", name);
    ck_assert_int_ge(H5Aread(attribute, H5T_NATIVE_DOUBLE, &value), 0);
    H5Aclose(attribute);
    return value;
}

/* Entry k of a one-dimensional dataset of variable-length strings. */
static char *read_string(hid_t file, const char *name, hsize_t k)
{
    hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
    ck_assert_msg(set >= 0, "no dataset '%s'", name);
    hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    hid_t space = H5Dget_space(set);
    hsize_t n = 0;
    H5Sget_simple_extent_dims(space, &n, NULL);
    ck_assert_uint_lt(k, n);
    char **all = calloc((size_t)n, sizeof *all);
    ck_assert_ptr_nonnull(all);
    ck_assert_int_ge(H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, all), 0);
    char *copy = strdup(all[k]);
    H5Dvlen_reclaim(type, space, H5P_DEFAULT, all);
    free(all);
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(set);
    return copy;
}

static hid_t open_output(const char *dir, const char *name)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", dir, name), 0);
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_msg(file >= 0, "cannot open %s", path);
    free(path);
    return file;
}

/* ------------------------------------------------------- the geometry -- */

typedef struct segment {
    double a[2], b[2];
    int wall;
} segment;

/* The walls file of a 2D run holds exactly `expected` (in this order), the
 * normal of each the unit left normal (-(by - ay), bx - ax) / length, and
 * the walls' names and schemes. */
static void check_segments(const char *dir, const segment *expected, size_t count,
                           const char *const *names, const char *const *schemes, size_t walls)
{
    hid_t file = open_output(dir, "particles_walls.h5");
    hsize_t dims[2], cdims[2], wdims[2], ndims[2];
    double *points = read_doubles(file, "points", dims);
    double *connectivity = read_doubles(file, "connectivity", cdims);
    double *wall = read_doubles(file, "wall", wdims);
    double *normal = read_doubles(file, "normal", ndims);
    ck_assert_uint_eq(dims[0], 2 * count);
    ck_assert_uint_eq(dims[1], 3);
    ck_assert_uint_eq(cdims[0], count);
    ck_assert_uint_eq(cdims[1], 2);
    ck_assert_uint_eq(wdims[0], count);
    ck_assert_uint_eq(ndims[0], count);
    ck_assert_uint_eq(ndims[1], 3);
    ck_assert_double_eq(read_attribute(file, "dimensions"), 2);
    ck_assert_double_eq(read_attribute(file, "nodes_per_element"), 2);
    /* the run's provenance, as in every file of the run */
    static const char *const provenance[] = {"sluice_version", "git_revision", "build",
                                             "command_line", "date", "host"};
    for (size_t k = 0; k < sizeof provenance / sizeof *provenance; k++)
        ck_assert_msg(H5Aexists(file, provenance[k]) > 0, "no attribute '%s'", provenance[k]);
    ck_assert_double_eq(read_attribute(file, "fixed_elements") +
                            read_attribute(file, "moving_elements"),
                        (double)count);
    for (size_t e = 0; e < count; e++) {
        const segment *s = &expected[e];
        const double *a = points + 6 * e, *b = a + 3;
        /* the scene's numbers, parsed and stored as doubles: round-off */
        for (int d = 0; d < 2; d++) {
            ck_assert_double_eq_tol(a[d], s->a[d], 1e-15);
            ck_assert_double_eq_tol(b[d], s->b[d], 1e-15);
        }
        ck_assert_double_eq(a[2], 0);
        ck_assert_double_eq(b[2], 0);
        ck_assert_double_eq(connectivity[2 * e], (double)(2 * e));
        ck_assert_double_eq(connectivity[2 * e + 1], (double)(2 * e + 1));
        ck_assert_double_eq(wall[e], s->wall);
        const double length = hypot(s->b[0] - s->a[0], s->b[1] - s->a[1]);
        ck_assert_double_eq_tol(normal[3 * e], -(s->b[1] - s->a[1]) / length, 1e-15);
        ck_assert_double_eq_tol(normal[3 * e + 1], (s->b[0] - s->a[0]) / length, 1e-15);
    }
    for (size_t k = 0; k < walls; k++) {
        char *name = read_string(file, "name", k), *scheme = read_string(file, "scheme", k);
        ck_assert_str_eq(name, names[k]);
        ck_assert_str_eq(scheme, schemes[k]);
        free(name);
        free(scheme);
    }
    free(points);
    free(connectivity);
    free(wall);
    free(normal);
    H5Fclose(file);
}

/* ------------------------------------------------------ the XDMF index -- */

/* A minimal XML reader for the index: tags nest and close, attributes are
 * quoted, and every DataItem of Format="HDF" names a dataset that exists
 * with the dimensions the item states; the XML item of a HyperSlab (start,
 * stride, count per dimension) stays within the HDF item, its count being
 * the HyperSlab's dimensions. Returns the number of HDF items checked. */
typedef struct xml_frame {
    char name[32];
    char attributes[512];
    const char *content;           /* text after the start tag */
    unsigned long long slab[3][2]; /* a HyperSlab's start, stride, count */
    int slab_rank, has_slab;
    unsigned long long source[2]; /* its HDF item's dimensions */
    int source_rank;
} xml_frame;

static int attribute(const char *attributes, const char *key, char *value, size_t size)
{
    char needle[64];
    snprintf(needle, sizeof needle, " %s=\"", key);
    const char *p = strstr(attributes, needle);
    if (!p)
        return 0;
    p += strlen(needle);
    const char *end = strchr(p, '"');
    ck_assert_ptr_nonnull(end);
    snprintf(value, size, "%.*s", (int)(end - p), p);
    return 1;
}

static int parse_numbers(const char *text, unsigned long long *out, int max)
{
    int n = 0;
    char *end;
    for (const char *p = text; n < max;) {
        unsigned long long v = strtoull(p, &end, 10);
        if (end == p)
            break;
        out[n++] = v;
        p = end;
    }
    return n;
}

/* Checks one HDF item: "file:/dataset" relative to dir, its dimensions. */
static void check_hdf_item(const char *dir, const char *dims_text, const char *content,
                           size_t length, unsigned long long dims[2], int *rank)
{
    char reference[512];
    ck_assert_uint_lt(length, sizeof reference);
    memcpy(reference, content, length);
    reference[length] = '\0';
    char *colon = strstr(reference, ":/");
    ck_assert_msg(colon != NULL, "HDF item '%s' names no dataset", reference);
    *colon = '\0';
    hid_t file = open_output(dir, reference);
    hid_t set = H5Dopen2(file, colon + 1, H5P_DEFAULT);
    ck_assert_msg(set >= 0, "%s has no dataset %s", reference, colon + 1);
    hid_t space = H5Dget_space(set);
    hsize_t actual[2] = {0, 0};
    int actual_rank = H5Sget_simple_extent_ndims(space);
    H5Sget_simple_extent_dims(space, actual, NULL);
    *rank = parse_numbers(dims_text, dims, 2);
    ck_assert_msg(*rank == actual_rank && dims[0] == actual[0] &&
                      (*rank < 2 || dims[1] == actual[1]),
                  "%s:%s: the index says %s", reference, colon + 1, dims_text);
    H5Sclose(space);
    H5Dclose(set);
    H5Fclose(file);
}

static int check_xdmf(const char *dir)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/particles.xdmf", dir), 0);
    char *text = test_read_file(path);
    ck_assert_ptr_nonnull(text);
    xml_frame stack[16];
    int depth = 0, items = 0, roots = 0;
    const char *p = text;
    while ((p = strchr(p, '<')) != NULL) {
        if (p[1] == '?') {
            p = strstr(p, "?>");
            ck_assert_ptr_nonnull(p);
            continue;
        }
        const char *end = strchr(p, '>');
        ck_assert_msg(end != NULL, "an unclosed tag");
        if (p[1] == '/') { /* an end tag */
            ck_assert_msg(depth > 0, "an end tag without a start");
            xml_frame *f = &stack[--depth];
            size_t n = strlen(f->name);
            ck_assert_msg(strncmp(p + 2, f->name, n) == 0 && p[2 + n] == '>', "<%s> closed by %.*s",
                          f->name, (int)(end - p + 1), p);
            char value[128];
            if (strcmp(f->name, "DataItem") == 0) {
                xml_frame *parent = depth > 0 ? &stack[depth - 1] : NULL;
                const int slab_child =
                    parent && attribute(parent->attributes, "ItemType", value, sizeof value) &&
                    strcmp(value, "HyperSlab") == 0;
                char format[16] = "", dims[64] = "";
                attribute(f->attributes, "Format", format, sizeof format);
                ck_assert(attribute(f->attributes, "Dimensions", dims, sizeof dims));
                if (strcmp(format, "HDF") == 0) {
                    unsigned long long d[2] = {0, 0};
                    int rank = 0;
                    check_hdf_item(dir, dims, f->content, (size_t)(p - f->content), d, &rank);
                    items++;
                    if (slab_child) {
                        parent->source[0] = d[0];
                        parent->source[1] = rank > 1 ? d[1] : 1;
                        parent->source_rank = rank;
                    }
                } else if (strcmp(format, "XML") == 0 && slab_child) {
                    unsigned long long v[6];
                    int n = parse_numbers(f->content, v, 6);
                    ck_assert(n == 3 || n == 6);
                    parent->slab_rank = n / 3;
                    for (int k = 0; k < 3; k++)
                        for (int r = 0; r < parent->slab_rank; r++)
                            parent->slab[k][r] = v[k * parent->slab_rank + r];
                    parent->has_slab = 1;
                } else if (attribute(f->attributes, "ItemType", value, sizeof value) &&
                           strcmp(value, "HyperSlab") == 0) {
                    ck_assert_msg(f->has_slab && f->source_rank == f->slab_rank,
                                  "a HyperSlab without its selection or source");
                    unsigned long long d[2] = {0, 0};
                    ck_assert_int_eq(parse_numbers(dims, d, 2), f->slab_rank);
                    for (int r = 0; r < f->slab_rank; r++) {
                        const unsigned long long start = f->slab[0][r], stride = f->slab[1][r],
                                                 count = f->slab[2][r];
                        ck_assert_uint_eq(count, d[r]);
                        ck_assert_uint_ge(stride, 1);
                        ck_assert_uint_le(start + (count - 1) * stride + 1, f->source[r]);
                    }
                }
            }
            p = end + 1;
            continue;
        }
        /* a start tag, perhaps empty */
        ck_assert_msg(depth < 16, "nested too deeply");
        xml_frame *f = &stack[depth];
        memset(f, 0, sizeof *f);
        const char *name_end = p + 1;
        while (*name_end && *name_end != ' ' && *name_end != '>' && *name_end != '/')
            name_end++;
        snprintf(f->name, sizeof f->name, "%.*s", (int)(name_end - p - 1), p + 1);
        ck_assert_msg(f->name[0], "a tag without a name");
        ck_assert_uint_lt((size_t)(end - name_end), sizeof f->attributes);
        snprintf(f->attributes, sizeof f->attributes, "%.*s", (int)(end - name_end), name_end);
        int quotes = 0;
        for (const char *q = f->attributes; *q; q++)
            quotes += *q == '"';
        ck_assert_msg(quotes % 2 == 0, "<%s%s>: an unquoted attribute", f->name, f->attributes);
        const int empty = end[-1] == '/';
        if (!empty) {
            f->content = end + 1;
            if (depth == 0)
                roots++;
            depth++;
        }
        p = end + 1;
    }
    ck_assert_int_eq(depth, 0);
    ck_assert_int_eq(roots, 1);
    free(text);
    free(path);
    return items;
}

/* Every time step of the index: a spatial collection of the particles and
 * the walls ("walls" with `fixed` elements, "moving_walls" with `moving`). */
static void check_index_walls(const char *dir, int snapshots, uint64_t fixed, uint64_t moving,
                              int triangles)
{
    ck_assert_int_gt(check_xdmf(dir), 0);
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/particles.xdmf", dir), 0);
    char *text = test_read_file(path);
    ck_assert_int_eq(test_count_lines(text, "CollectionType=\"Spatial\""), snapshots);
    ck_assert_int_eq(test_count_lines(text, "<Grid Name=\"walls\""), fixed ? snapshots : 0);
    ck_assert_int_eq(test_count_lines(text, "<Grid Name=\"moving_walls\""), moving ? snapshots : 0);
    /* the walls' items name whole datasets: ParaView 5.11's XDMF 3 readers
     * read no HyperSlab of a geometry or a cell attribute (they made walls
     * without points); the one HyperSlab per time is the particles' vertex
     * index */
    ck_assert_int_eq(test_count_lines(text, "ItemType=\"HyperSlab\""), snapshots);
    char topology[160];
    snprintf(topology, sizeof topology, "TopologyType=\"%s\" NumberOfElements=\"%llu\"",
             triangles ? "Triangle" : "Polyline", (unsigned long long)fixed);
    if (fixed)
        ck_assert_int_eq(test_count_lines(text, topology), snapshots);
    snprintf(topology, sizeof topology, "TopologyType=\"%s\" NumberOfElements=\"%llu\"",
             triangles ? "Triangle" : "Polyline", (unsigned long long)moving);
    if (moving)
        ck_assert_int_eq(test_count_lines(text, topology), snapshots);
    free(text);
    free(path);
}

/* ------------------------------------------------------------ the tests -- */

/* the tank's three segments (down, along, up) and the baffle's two */
static const segment tank_and_baffle[] = {
    {{0, 1}, {0, 0}, 0},          {{0, 0}, {2, 0}, 0},           {{2, 0}, {2, 1}, 0},
    {{0.5, 0.8}, {0.5, 0.35}, 1}, {{0.5, 0.35}, {0.3, 0.15}, 1},
};
static const char *const baffle =
    "    - {shape: polyline, points: [[0.5, 0.8], [0.5, 0.35], [0.3, 0.15]], name: baffle}\n";

/* penalty_contact keeps its walls as segments: no wall particle, and the
 * walls are in the output all the same */
START_TEST(geometric_walls_2d)
{
    char *yaml = scene_2d("penalty_contact: {}", baffle);
    char *out = run_scene("walls-penalty", yaml);
    const char *names[] = {"tank", "baffle"}, *schemes[] = {"penalty_contact", "penalty_contact"};
    check_segments(out, tank_and_baffle, 5, names, schemes, 2);
    hid_t file = open_output(out, "particles_000000.h5");
    hsize_t dims[2];
    double *kind = read_doubles(file, "kind", dims);
    for (hsize_t i = 0; i < dims[0]; i++)
        ck_assert_double_eq(kind[i], SLUICE_KIND_FLUID);
    ck_assert_int_lt(H5Lexists(file, "walls", H5P_DEFAULT), 1); /* no moving wall */
    free(kind);
    H5Fclose(file);
    check_index_walls(out, 3, 5, 0, 0);
    free(out);
    free(yaml);
}
END_TEST

/* dbc's walls are layers of wall particles; the output holds both, and a
 * scene mixing schemes names each wall's */
START_TEST(particle_walls_2d)
{
    char *walls = NULL;
    ck_assert_int_ge(
        asprintf(&walls, "%.*s, scheme: repulsive_force}\n", (int)(strlen(baffle) - 2), baffle), 0);
    char *yaml = scene_2d("dbc: {}\n  repulsive_force: {}", walls);
    /* the tank names no scheme: name dbc */
    char *edited = NULL;
    ck_assert_int_ge(asprintf(&edited, "%s", yaml), 0);
    char *at = strstr(edited, "name: tank}");
    ck_assert_ptr_nonnull(at);
    char *with = NULL;
    ck_assert_int_ge(asprintf(&with, "%.*sname: tank, scheme: dbc}%s", (int)(at - edited), edited,
                              at + strlen("name: tank}")),
                     0);
    char *out = run_scene("walls-dbc", with);
    const char *names[] = {"tank", "baffle"}, *schemes[] = {"dbc", "repulsive_force"};
    check_segments(out, tank_and_baffle, 5, names, schemes, 2);
    hid_t file = open_output(out, "particles_000002.h5");
    hsize_t dims[2];
    double *kind = read_doubles(file, "kind", dims);
    hsize_t wall_particles = 0;
    for (hsize_t i = 0; i < dims[0]; i++)
        wall_particles += kind[i] == SLUICE_KIND_WALL;
    ck_assert_uint_gt(wall_particles, 100);
    free(kind);
    H5Fclose(file);
    check_index_walls(out, 3, 5, 0, 0);
    free(out);
    free(with);
    free(edited);
    free(yaml);
    free(walls);
}
END_TEST

/* 3D: a tank [0, 1] x [0, 0.5] x [0, 0.6] as triangles: ten, each with its
 * vertices on one of the five faces, covering them (the areas add up to the
 * faces'), the normal of each the unit normal of (b - a) x (c - a), pointing
 * into the tank */
START_TEST(geometric_walls_3d)
{
    const char *yaml = "dimensions: 3\n"
                       "particles: {spacing: 0.1, smoothing_length_ratio: 1.3}\n"
                       "time: {end: 0.02}\n"
                       "domain: {min: [-0.3, -0.3, -0.3], max: [1.3, 0.8, 0.9]}\n"
                       "geometry:\n"
                       "  fluid: [{shape: box, min: [0, 0, 0], max: [0.4, 0.5, 0.2]}]\n"
                       "  walls: [{shape: tank, min: [0, 0, 0], max: [1, 0.5, 0.6], name: tank}]\n"
                       "plugins:\n"
                       "  wendland_c2: {}\n"
                       "  tait: {speed_of_sound: 20}\n"
                       "  continuity: {}\n"
                       "  pressure_gradient: {}\n"
                       "  artificial_viscosity: {alpha: 0.1}\n"
                       "  gravity: {}\n"
                       "  penalty_contact: {}\n"
                       "  time_step: {}\n"
                       "  symplectic: {}\n"
                       "  hdf5: {interval: 0.01}\n";
    char *out = run_scene("walls-3d", yaml);
    hid_t file = open_output(out, "particles_walls.h5");
    hsize_t dims[2], ndims[2], cdims[2];
    double *points = read_doubles(file, "points", dims);
    double *normal = read_doubles(file, "normal", ndims);
    double *connectivity = read_doubles(file, "connectivity", cdims);
    ck_assert_uint_eq(dims[0], 30);
    ck_assert_uint_eq(cdims[0], 10);
    ck_assert_uint_eq(cdims[1], 3);
    ck_assert_double_eq(read_attribute(file, "nodes_per_element"), 3);
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 0.5, 0.6}, centre[3] = {0.5, 0.25, 0.3};
    double area = 0;
    for (int e = 0; e < 10; e++) {
        const double *a = points + 9 * e, *b = a + 3, *c = a + 6;
        /* one face: a coordinate all three share, at a side of the tank */
        int on_face = 0;
        for (int d = 0; d < 3; d++)
            for (int side = 0; side < 2; side++) {
                const double x = side ? hi[d] : lo[d];
                on_face |= a[d] == x && b[d] == x && c[d] == x && !(d == 2 && side == 1);
            }
        ck_assert_msg(on_face, "triangle %d is on no face of the tank", e);
        double u[3], v[3], n[3];
        for (int d = 0; d < 3; d++)
            u[d] = b[d] - a[d], v[d] = c[d] - a[d];
        n[0] = u[1] * v[2] - u[2] * v[1];
        n[1] = u[2] * v[0] - u[0] * v[2];
        n[2] = u[0] * v[1] - u[1] * v[0];
        const double length = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        area += 0.5 * length;
        double inward = 0;
        for (int d = 0; d < 3; d++) {
            ck_assert_double_eq_tol(normal[3 * e + d], n[d] / length, 1e-15);
            inward += normal[3 * e + d] * (centre[d] - a[d]);
        }
        ck_assert_msg(inward > 0, "the normal of triangle %d points out of the tank", e);
        for (int k = 0; k < 3; k++)
            ck_assert_double_eq(connectivity[3 * e + k], 3 * e + k);
    }
    /* bottom 1 x 0.5, two sides 1 x 0.6, two ends 0.5 x 0.6 */
    ck_assert_double_eq_tol(area, 0.5 + 2 * 0.6 + 2 * 0.3, 1e-14);
    free(points);
    free(normal);
    free(connectivity);
    H5Fclose(file);
    check_index_walls(out, 3, 10, 0, 1);
    free(out);
}
END_TEST

/* A paddle at x = 0.5 (dbc's moving wall) moves by the law; each snapshot
 * holds its segment where the law puts it at the snapshot's time, and its
 * displacement; the tank stays in the walls file alone */
START_TEST(moving_wall)
{
    const double U[2] = {0.2, 0}, A[2] = {0.02, 0.01}, f = 5, phase_deg = 30, start = 0.02;
    const double phase = phase_deg * M_PI / 180;
    char *yaml = NULL;
    ck_assert_int_ge(asprintf(&yaml,
                              "dimensions: 2\n"
                              "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
                              "time: {end: 0.1}\n"
                              "domain: {min: [-0.3, -0.3], max: [2.3, 1.5]}\n"
                              "geometry:\n"
                              "  fluid: [{shape: box, min: [0.6, 0], max: [1.4, 0.3]}]\n"
                              "  walls:\n"
                              "    - {shape: tank, min: [0, 0], max: [2, 1], name: tank}\n"
                              "    - {shape: polyline, points: [[0.5, 0.8], [0.5, 0.05]], "
                              "name: paddle}\n"
                              "plugins:\n"
                              "  wendland_c2: {}\n"
                              "  tait: {speed_of_sound: 20}\n"
                              "  continuity: {}\n"
                              "  pressure_gradient: {}\n"
                              "  artificial_viscosity: {alpha: 0.1}\n"
                              "  gravity: {}\n"
                              "  dbc: {moving_wall: paddle, velocity: [%g, %g], amplitude: [%g, "
                              "%g], frequency: %g, phase_deg: %g, start: %g}\n"
                              "  time_step: {}\n"
                              "  symplectic: {}\n"
                              "  hdf5: {interval: 0.05}\n",
                              U[0], U[1], A[0], A[1], f, phase_deg, start),
                     0);
    char *out = run_scene("walls-moving", yaml);
    /* the walls file: the tank (fixed) first, then the paddle at rest */
    const segment rest[] = {{{0, 1}, {0, 0}, 0},
                            {{0, 0}, {2, 0}, 0},
                            {{2, 0}, {2, 1}, 0},
                            {{0.5, 0.8}, {0.5, 0.05}, 1}};
    const char *names[] = {"tank", "paddle"}, *schemes[] = {"dbc", "dbc"};
    check_segments(out, rest, 4, names, schemes, 2);
    hid_t walls = open_output(out, "particles_walls.h5");
    ck_assert_double_eq(read_attribute(walls, "fixed_elements"), 3);
    ck_assert_double_eq(read_attribute(walls, "moving_elements"), 1);
    /* the index's grids: the groups fixed (the tank) and moving (the paddle) */
    hsize_t gdims[2];
    double *fixed = read_doubles(walls, "fixed/points", gdims);
    ck_assert_uint_eq(gdims[0], 6);
    for (int e = 0; e < 3; e++)
        for (int d = 0; d < 2; d++) {
            ck_assert_double_eq_tol(fixed[6 * e + d], rest[e].a[d], 1e-15);
            ck_assert_double_eq_tol(fixed[6 * e + 3 + d], rest[e].b[d], 1e-15);
        }
    double *moving_wall = read_doubles(walls, "moving/wall", gdims);
    ck_assert_uint_eq(gdims[0], 1);
    ck_assert_double_eq(moving_wall[0], 1);
    double *moving_cells = read_doubles(walls, "moving/connectivity", gdims);
    ck_assert_uint_eq(gdims[0], 1);
    ck_assert_uint_eq(gdims[1], 2);
    ck_assert_double_eq(moving_cells[0], 0);
    ck_assert_double_eq(moving_cells[1], 1);
    free(fixed);
    free(moving_wall);
    free(moving_cells);
    H5Fclose(walls);
    int moved = 0;
    for (int k = 0; k < 3; k++) {
        char name[64];
        snprintf(name, sizeof name, "particles_%06d.h5", k);
        hid_t file = open_output(out, name);
        const double t = read_attribute(file, "time");
        ck_assert_double_eq_tol(t, 0.05 * k, 1e-12);
        const double tau = t - start;
        double law[2] = {0, 0};
        for (int d = 0; d < 2 && tau >= 0; d++)
            law[d] = U[d] * tau + A[d] * (sin(2 * M_PI * f * tau + phase) - sin(phase));
        hsize_t dims[2], ddims[2];
        double *points = read_doubles(file, "walls/points", dims);
        double *displacement = read_doubles(file, "walls/displacement", ddims);
        ck_assert_uint_eq(dims[0], 2);
        ck_assert_uint_eq(dims[1], 3);
        ck_assert_uint_eq(ddims[0], 2);
        for (int d = 0; d < 2; d++) {
            ck_assert_double_eq_tol(points[d], rest[3].a[d] + law[d], 1e-12);
            ck_assert_double_eq_tol(points[3 + d], rest[3].b[d] + law[d], 1e-12);
            ck_assert_double_eq_tol(displacement[3 + d], law[d], 1e-12);
            ck_assert_double_eq(displacement[d], 0); /* the tank */
        }
        moved += fabs(law[0]) > 0.005;
        fprintf(stderr, "moving wall: t = %g s, paddle displaced by (%.6f, %.6f) m as the law\n", t,
                points[0] - rest[3].a[0], points[1] - rest[3].a[1]);
        free(points);
        free(displacement);
        H5Fclose(file);
    }
    ck_assert_int_eq(moved, 2); /* it did move between the snapshots */
    check_index_walls(out, 3, 3, 1, 0);
    free(out);
    free(yaml);
}
END_TEST

/* Only the wall scheme that handles a wall moves it, and it says so before
 * the run: the core refuses the others */
START_TEST(only_its_scheme_moves_a_wall)
{
    char *scene = scene_2d("penalty_contact: {}\n  wall_mover: {}", ""), *yaml = NULL;
    const char *fixtures = getenv("SLUICE_FIXTURE_DIR");
    ck_assert_int_ge(asprintf(&yaml, "plugin_path: %s\n%s", fixtures ? fixtures : ".", scene), 0);
    test_load_refused("walls-probe", yaml, "only its wall scheme moves it");
    free(yaml);
    free(scene);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("wall_output");
    TCase *c = tcase_create("walls");
    tcase_add_test(c, geometric_walls_2d);
    tcase_add_test(c, particle_walls_2d);
    tcase_add_test(c, geometric_walls_3d);
    tcase_add_test(c, moving_wall);
    tcase_add_test(c, only_its_scheme_moves_a_wall);
    suite_add_tcase(s, c);
    return test_run_suite(s);
}
