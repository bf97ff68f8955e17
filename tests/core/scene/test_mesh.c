/* Walls from mesh files (core/scene/mesh_file.c, shape `mesh`): the STL
 * (ASCII, binary) and OBJ readers on a unit cube written by the test (12
 * triangles, area 6, volume 1 by the divergence theorem, the same triangles
 * through the three formats), the transforms against their closed forms,
 * the side of the fluid, every malformed file refused by `sluice check`
 * with one message naming the file and its line or triangle, and short runs
 * of a tank read from an STL file against the same `shape: tank`, with the
 * particle wall schemes dbc and mdbc and the force schemes penalty_contact
 * and repulsive_force. */
#include "test_util.h"

#include <float.h>
#include <math.h>
#include <stdint.h>

#include "mesh_file.h"
#include "scene.h"
#include "sim_util.h"

/* The unit cube's corners (i = x + 2y + 4z) and its faces as quadrilaterals
 * wound counter-clockwise seen from outside (normals out). */
static const double corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                                    {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
static const int quad[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                               {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

/* Triangle t of the cube: quad t / 2 split along its first diagonal (the
 * fan an OBJ reader makes of the quad). */
static void cube_triangle(int t, int out[3])
{
    const int *q = quad[t / 2];
    out[0] = q[0];
    out[1] = t % 2 == 0 ? q[1] : q[2];
    out[2] = t % 2 == 0 ? q[2] : q[3];
}

/* The cube as ASCII STL; `flip` reverses triangle `flip - 1`'s winding,
 * `extra` is appended before endsolid. */
static char *cube_stl_text(int flip, const char *extra)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    fprintf(f, "solid cube\n");
    for (int t = 0; t < 12; t++) {
        int c[3];
        cube_triangle(t, c);
        if (flip == t + 1) {
            int swap = c[1];
            c[1] = c[2];
            c[2] = swap;
        }
        fprintf(f, "  facet normal 0 0 0\n    outer loop\n");
        for (int k = 0; k < 3; k++)
            fprintf(f, "      vertex %g %g %g\n", corner[c[k]][0], corner[c[k]][1],
                    corner[c[k]][2]);
        fprintf(f, "    endloop\n  endfacet\n");
    }
    if (extra)
        fputs(extra, f);
    fprintf(f, "endsolid cube\n");
    fclose(f);
    return text;
}

/* The line of the `facet` of triangle t (0-based) in cube_stl_text. */
static int cube_stl_line(int t) { return 2 + 7 * t; }

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int k = 0; k < 4; k++)
        p[k] = (unsigned char)(v >> (8 * k));
}

static void put_float(unsigned char *p, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    put_u32(p, bits);
}

/* The cube as binary STL (its header starts with "solid", as some
 * exporters write it); `count` is written as the triangle count,
 * `records` triangles are written, `bad` (1-based) gets a NaN coordinate. */
static char *write_cube_binary(const char *dir, const char *name, uint32_t count, int records,
                               int bad)
{
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/%s", dir, name), 0);
    FILE *f = fopen(path, "wb");
    ck_assert_ptr_nonnull(f);
    unsigned char header[84] = {0};
    memcpy(header, "solid cube written as binary STL", 32);
    put_u32(header + 80, count);
    fwrite(header, 1, sizeof header, f);
    for (int t = 0; t < records; t++) {
        unsigned char r[50] = {0};
        int c[3];
        cube_triangle(t % 12, c);
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++)
                put_float(r + 12 + 12 * k + 4 * d, (float)corner[c[k]][d]);
        if (bad == t + 1)
            put_float(r + 12 + 4, NAN);
        fwrite(r, 1, sizeof r, f);
    }
    fclose(f);
    return path;
}

/* The cube as OBJ: quads, every reference form (i, i/t, i//n, i/t/n) and
 * negative indices. */
static const char *cube_obj_text = "# unit cube\n"
                                   "o cube\n"
                                   "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
                                   "v 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n"
                                   "vt 0 0\nvn 0 0 1\n"
                                   "f 1 3 4 2\n"
                                   "f 5/1 6/1 8/1 7/1\n"
                                   "f 1//1 2//1 6//1 5//1\n"
                                   "f 3/1/1 7/1/1 8/1/1 4/1/1\n"
                                   "f -8 -4 -2 -6 # x = 0\n"
                                   "s off\n"
                                   "f 2 4 8 6\n";

static void read_ok(const char *path, sluice_mesh *mesh)
{
    sluice_mesh_problem problem;
    int rc = sluice_mesh_read(path, mesh, &problem);
    ck_assert_msg(rc == 0, "%s refused: line %d: %s", path, problem.line, problem.message);
}

/* 12 triangles on 8 shared vertices, closed and consistently wound, area
 * 6, volume +1 (normals out) to round-off. */
static void check_cube(const sluice_mesh *mesh, double scale)
{
    ck_assert_uint_eq(mesh->face_count, 12);
    ck_assert_uint_eq(mesh->vertex_count, 8);
    sluice_mesh_edges edges;
    ck_assert_int_eq(sluice_mesh_check_edges(mesh, &edges), 0);
    ck_assert_uint_eq(edges.open, 0);
    ck_assert_uint_eq(edges.nonmanifold, 0);
    ck_assert_uint_eq(edges.misoriented, 0);
    ck_assert_double_eq_tol(sluice_mesh_area(mesh), 6 * scale * scale, 1e-13 * scale * scale);
    ck_assert_double_eq_tol(sluice_mesh_volume(mesh), scale * scale * scale,
                            1e-13 * scale * scale * scale);
}

START_TEST(cube_three_formats)
{
    char *dir = test_scratch("mesh-cube");
    char *stl_text = cube_stl_text(0, NULL);
    char *ascii = test_write_file(dir, "cube.stl", stl_text);
    char *binary = write_cube_binary(dir, "cube_binary.STL", 12, 12, 0);
    char *obj = test_write_file(dir, "cube.obj", cube_obj_text);
    sluice_mesh m[3];
    read_ok(ascii, &m[0]);
    read_ok(binary, &m[1]);
    read_ok(obj, &m[2]);
    ck_assert_int_eq(m[0].format, SLUICE_MESH_STL_ASCII);
    ck_assert_int_eq(m[1].format, SLUICE_MESH_STL_BINARY);
    ck_assert_int_eq(m[2].format, SLUICE_MESH_OBJ);
    ck_assert_ptr_null(m[1].face_line);
    for (int k = 0; k < 3; k++)
        check_cube(&m[k], 1);
    /* the same triangles, corner by corner, in the same order: the cube's */
    for (int t = 0; t < 12; t++) {
        int c[3];
        cube_triangle(t, c);
        for (int k = 0; k < 3; k++)
            for (int f = 0; f < 3; f++) {
                const double *p = m[f].vertices + 3 * (size_t)m[f].faces[3 * t + k];
                for (int d = 0; d < 3; d++)
                    ck_assert_msg(p[d] == corner[c[k]][d],
                                  "format %d, triangle %d, corner %d differs", f, t, k);
            }
        ck_assert_uint_eq(m[0].face_line[t], (uint32_t)cube_stl_line(t));
        ck_assert_uint_eq(m[2].face_line[t], (uint32_t)(13 + t / 2 + (t >= 10)));
    }
    for (int k = 0; k < 3; k++)
        sluice_mesh_free(&m[k]);
    free(stl_text);
    free(ascii);
    free(binary);
    free(obj);
    free(dir);
}
END_TEST

/* What files do that the readers accept: an ASCII STL of two solids, with
 * upper-case keywords and a NaN stored normal (normals are not read); an
 * OBJ whose faces each have their own four vertices (merged by
 * coordinates, as an STL's corners are). Both read as the cube. */
START_TEST(tolerated_variants)
{
    char *dir = test_scratch("mesh-variants");
    char *text = cube_stl_text(0, NULL);
    char *split = NULL;
    char *seventh = text;
    for (int t = 0; t < 6; t++)
        seventh = strstr(seventh, "endfacet\n") + strlen("endfacet\n");
    ck_assert_int_ge(asprintf(&split, "%.*sendsolid first\nSOLID second\n%s", (int)(seventh - text),
                              text, seventh),
                     0);
    char *normal = strstr(split, "facet normal 0 0 0\n"), *edited = NULL;
    ck_assert_int_ge(asprintf(&edited, "%.*sFACET NORMAL nan inf 0%s", (int)(normal - split), split,
                              normal + strlen("facet normal 0 0 0")),
                     0);
    char *stl = test_write_file(dir, "two_solids.stl", edited);
    free(edited);
    char *obj_text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&obj_text, &size);
    for (int q = 0; q < 6; q++) {
        for (int k = 0; k < 4; k++)
            fprintf(f, "v %g %g %g\n", corner[quad[q][k]][0], corner[quad[q][k]][1],
                    corner[quad[q][k]][2]);
        fprintf(f, "f -4 -3 -2 -1\n");
    }
    fclose(f);
    char *obj = test_write_file(dir, "apart.obj", obj_text);
    sluice_mesh mesh;
    read_ok(stl, &mesh);
    check_cube(&mesh, 1);
    sluice_mesh_free(&mesh);
    read_ok(obj, &mesh);
    check_cube(&mesh, 1);
    sluice_mesh_free(&mesh);
    free(obj);
    free(obj_text);
    free(stl);
    free(split);
    free(text);
    free(dir);
}
END_TEST

/* x -> R (s x) + t, against the closed forms of two rotations: 90 degrees
 * about z, (x, y, z) -> (-y, x, z); 120 degrees about (1, 1, 1), a cyclic
 * permutation (x, y, z) -> (z, x, y). */
START_TEST(transforms_in_order)
{
    char *dir = test_scratch("mesh-transform");
    char *obj = test_write_file(dir, "cube.obj", cube_obj_text);
    const double t[3] = {1, 2, 3};
    struct {
        double axis[3], angle;
    } rotation[2] = {{{0, 0, 2}, 90}, {{1, 1, 1}, 120}};
    for (int r = 0; r < 2; r++) {
        sluice_mesh mesh;
        read_ok(obj, &mesh);
        const double s = 2.5;
        ck_assert_int_eq(sluice_mesh_transform(&mesh, s, rotation[r].axis, rotation[r].angle, t),
                         0);
        check_cube(&mesh, s);
        for (uint32_t v = 0; v < 8; v++) {
            const double *x = corner[v], *y = mesh.vertices + 3 * v;
            double expected[3];
            if (r == 0) {
                expected[0] = -s * x[1] + t[0];
                expected[1] = s * x[0] + t[1];
                expected[2] = s * x[2] + t[2];
            } else {
                expected[0] = s * x[2] + t[0];
                expected[1] = s * x[0] + t[1];
                expected[2] = s * x[1] + t[2];
            }
            for (int d = 0; d < 3; d++)
                ck_assert_double_eq_tol(y[d], expected[d], 1e-14 * 8);
        }
        sluice_mesh_free(&mesh);
    }
    /* refused: a zero axis with an angle, a scale that is not positive */
    sluice_mesh mesh;
    read_ok(obj, &mesh);
    const double zero[3] = {0, 0, 0};
    ck_assert_int_eq(sluice_mesh_transform(&mesh, 1, zero, 10, t), -1);
    ck_assert_int_eq(sluice_mesh_transform(&mesh, 0, rotation[0].axis, 10, t), -1);
    ck_assert_double_eq(mesh.vertices[3 * 7], 1); /* unchanged */
    sluice_mesh_free(&mesh);
    free(obj);
    free(dir);
}
END_TEST

/* A 3D scene text with one mesh wall; `wall` is the rest of its mapping. */
static char *mesh_scene(const char *wall)
{
    char *text = NULL;
    ck_assert_int_ge(asprintf(&text,
                              "dimensions: 3\n"                               /* 1 */
                              "particles: {spacing: 0.1}\n"                   /* 2 */
                              "time: {end: 0.01}\n"                           /* 3 */
                              "domain: {min: [-1, -1, -1], max: [3, 3, 3]}\n" /* 4 */
                              "geometry:\n"                                   /* 5 */
                              "  fluid:\n"                                    /* 6 */
                              "    - {shape: box, min: [1.5, 0, 0], max: [2, 0.5, 0.5]}\n"
                              "  walls:\n"                /* 8 */
                              "    - {shape: mesh, %s}\n" /* 9 */
                              "plugins:\n"
                              "  wendland_c2: {}\n"
                              "  tait: {speed_of_sound: 20}\n"
                              "  continuity: {}\n"
                              "  pressure_gradient: {}\n"
                              "  gravity: {}\n"
                              "  dbc: {}\n"
                              "  time_step: {}\n"
                              "  symplectic: {}\n",
                              wall),
                     0);
    return text;
}

/* The fluid side of a closed cube, whatever the file's winding: outside
 * (inside) makes a point at the centre behind (in front of) the wall. */
START_TEST(fluid_side_of_closed_surface)
{
    char *dir = test_scratch("mesh-side");
    char *stl_text = cube_stl_text(0, NULL);
    char *out = test_write_file(dir, "cube.stl", stl_text);
    /* the same cube wound inwards: every triangle reversed */
    sluice_mesh mesh;
    read_ok(out, &mesh);
    sluice_mesh_reverse(&mesh);
    ck_assert_double_eq_tol(sluice_mesh_volume(&mesh), -1, 1e-13);
    sluice_mesh_free(&mesh);
    char *in_text = strdup(stl_text);
    for (int t = 12; t-- > 0;) { /* swap the 2nd and 3rd vertex lines of each facet */
        char *p = in_text;
        for (int line = 1; line < cube_stl_line(t) + 3; line++)
            p = strchr(p, '\n') + 1;
        char *second = p, *third = strchr(second, '\n') + 1, *end = strchr(third, '\n') + 1;
        size_t a = (size_t)(third - second), b = (size_t)(end - third);
        char buffer[128];
        memcpy(buffer, second, a);
        memmove(second, third, b);
        memcpy(second + b, buffer, a);
    }
    char *in = test_write_file(dir, "cube_inward.stl", in_text);
    const char *files[2] = {"cube.stl", "cube_inward.stl"};
    const char *sides[4] = {"outside", "inside", "front", "back"};
    /* the centre's signed distance: outside -0.5, inside +0.5; front and
     * back follow the winding (+ when the normals point in) */
    for (int f = 0; f < 2; f++)
        for (int s = 0; s < 4; s++) {
            char *wall = NULL, *tag = NULL;
            ck_assert_int_ge(
                asprintf(&wall, "file: %s, fluid: %s, translate: [0.1, 0, 0]", files[f], sides[s]),
                0);
            char *text = mesh_scene(wall);
            char *scene_path = test_write_file(dir, "scene.yaml", text);
            sluice_scene scene;
            memset(&scene, 0, sizeof scene);
            sluice_diag *diag = sluice_diag_create();
            int errors = sluice_scene_load(&scene, scene_path, NULL, 0, diag);
            for (size_t k = 0; k < sluice_diag_count(diag); k++)
                fprintf(stderr, "%s\n", sluice_diag_message(diag, k));
            ck_assert_int_eq(errors, 0);
            ck_assert_uint_eq(scene.wall_count, 1);
            /* the resolved scene names the file by its absolute path */
            char *absolute = NULL, *real = realpath(dir, NULL);
            ck_assert_int_ge(asprintf(&absolute, "%s/%s", real, files[f]), 0);
            ck_assert_str_eq(sluice_node_get(scene.walls[0].node, "file")->value, absolute);
            free(absolute);
            free(real);
            const sluice_real centre[3] = {0.6, 0.5, 0.5}, far[3] = {2.6, 0.5, 0.5};
            int beyond;
            double d = sluice_wall_signed_distance(&scene.walls[0].geometry, centre, &beyond, NULL);
            double d_far =
                sluice_wall_signed_distance(&scene.walls[0].geometry, far, &beyond, NULL);
            int normals_in = s == 1 || (s == 2 && f == 1) || (s == 3 && f == 0);
            ck_assert_double_eq_tol(d, normals_in ? 0.5 : -0.5, 1e-12);
            ck_assert_double_eq_tol(d_far, normals_in ? -1.5 : 1.5, 1e-12);
            sluice_scene_free(&scene);
            sluice_diag_destroy(diag);
            free(scene_path);
            free(text);
            free(wall);
            free(tag);
        }
    free(in);
    free(in_text);
    free(out);
    free(stl_text);
    free(dir);
}
END_TEST

/* `sluice check` on a scene whose mesh wall is `wall`: exit 2 and exactly
 * one error, at `where` (a prefix "file:line:" or the scene's position),
 * containing `needle`. */
static void expect_refused(const char *dir, const char *wall, const char *where, const char *needle)
{
    char *text = mesh_scene(wall);
    char *scene_path = test_write_file(dir, "scene.yaml", text);
    char *args = NULL, *output = NULL;
    ck_assert_int_ge(asprintf(&args, "check %s", scene_path), 0);
    int status = test_sluice(args, &output);
    ck_assert_msg(status == 2, "%s: exit status %d (expected 2):\n%s", wall, status, output);
    ck_assert_msg(test_count_lines(output, "error:") == 1, "%s: expected one error:\n%s", wall,
                  output);
    ck_assert_msg(strstr(output, where), "%s: expected '%s' in:\n%s", wall, where, output);
    ck_assert_msg(strstr(output, needle), "%s: expected '%s' in:\n%s", wall, needle, output);
    ck_assert_msg(!strstr(output, "Sanitizer") && !strstr(output, "runtime error"), "%s", output);
    free(output);
    free(args);
    free(scene_path);
    free(text);
}

/* The position of a mesh file's line in a message: "DIR/NAME:LINE:". */
static char *at_line(const char *dir, const char *name, int line)
{
    char *where = NULL;
    ck_assert_int_ge(asprintf(&where, "%s/%s:%d:", dir, name, line), 0);
    return where;
}

START_TEST(malformed_files_refused)
{
    char *dir = test_scratch("mesh-bad");
    char *scene_at = NULL; /* the `file` key of the wall, line 9 */
    ck_assert_int_ge(asprintf(&scene_at, "%s/scene.yaml:9:", dir), 0);
    free(test_write_file(dir, "empty.stl", ""));
    expect_refused(dir, "file: empty.stl, fluid: outside", scene_at,
                   "empty.stl': the mesh file is empty");
    expect_refused(dir, "file: missing.stl, fluid: outside", scene_at,
                   "missing.stl': cannot open the mesh file: No such file");
    expect_refused(dir, "file: ., fluid: outside", scene_at, "cannot read the mesh file");
    free(test_write_file(dir, "cube.ply", "ply\n"));
    expect_refused(dir, "file: cube.ply, fluid: outside", scene_at, "must end in .stl or .obj");
    /* binary: a count that disagrees with the size, truncated, short, NaN */
    free(write_cube_binary(dir, "count.stl", 13, 12, 0));
    expect_refused(dir, "file: count.stl, fluid: outside", scene_at,
                   "the count at bytes 80-83 is 13, which needs 84 + 50 x 13 = 734 bytes, the "
                   "file has 684 (truncated?)");
    free(write_cube_binary(dir, "short.stl", 12, 0, 0));
    {
        char *p = NULL;
        ck_assert_int_ge(asprintf(&p, "%s/short.stl", dir), 0);
        ck_assert_int_eq(truncate(p, 60), 0);
        free(p);
    }
    expect_refused(dir, "file: short.stl, fluid: outside", scene_at,
                   "too short for a binary STL (60 bytes");
    free(write_cube_binary(dir, "nan.stl", 12, 12, 3));
    expect_refused(dir, "file: nan.stl, fluid: outside", scene_at,
                   "triangle 3 (bytes 184-233): vertex coordinate y is not finite");
    /* binary: a degenerate triangle (two corners made equal) */
    {
        char *p = write_cube_binary(dir, "flat.stl", 12, 12, 0);
        FILE *f = fopen(p, "r+b");
        unsigned char corner_a[12];
        ck_assert_int_eq(fseek(f, 84 + 50 * 4 + 12, SEEK_SET), 0);
        ck_assert_uint_eq(fread(corner_a, 1, 12, f), 12);
        ck_assert_int_eq(fseek(f, 84 + 50 * 4 + 24, SEEK_SET), 0);
        ck_assert_uint_eq(fwrite(corner_a, 1, 12, f), 12);
        fclose(f);
        free(p);
    }
    expect_refused(dir, "file: flat.stl, fluid: outside", scene_at,
                   "triangle 5 is degenerate (two corners coincide)");
    free(scene_at);
    free(dir);
}
END_TEST

START_TEST(malformed_text_and_surfaces_refused)
{
    char *dir = test_scratch("mesh-bad-text");
    char *scene_at = NULL; /* the `file` key of the wall, line 9 */
    ck_assert_int_ge(asprintf(&scene_at, "%s/scene.yaml:9:", dir), 0);
    /* ASCII: bad numbers, truncation, a degenerate triangle */
    char *good = cube_stl_text(0, NULL);
    struct {
        const char *from, *to, *name, *needle;
        int line;
    } edits[] = {
        {"vertex 1 1 0\n", "vertex 1 one 0\n", "word.stl", "vertex coordinate y is 'one'", 6},
        {"vertex 1 1 0\n", "vertex 1 nan 0\n", "nan_ascii.stl", "vertex coordinate y is 'nan'", 6},
        {"vertex 1 1 0\n", "vertex 1 1e999 0\n", "inf.stl", "is '1e999', not a finite", 6},
        {"endsolid cube\n", "", "cut.stl", "ends without 'endsolid'", 86},
        {"    endloop\n  endfacet\n  facet", "    endloop\n  facet", "nofacetend.stl",
         "expected 'endfacet', found 'facet'", 8},
        {"vertex 1 1 0\n", "vertex 0 0 0\n", "zero.stl", "triangle 1 is degenerate", 2},
    };
    for (size_t k = 0; k < sizeof edits / sizeof edits[0]; k++) {
        char *text = strdup(good);
        char *p = strstr(text, edits[k].from);
        ck_assert_ptr_nonnull(p);
        char *edited = NULL;
        ck_assert_int_ge(asprintf(&edited, "%.*s%s%s", (int)(p - text), text, edits[k].to,
                                  p + strlen(edits[k].from)),
                         0);
        free(test_write_file(dir, edits[k].name, edited));
        char *wall = NULL, *where = at_line(dir, edits[k].name, edits[k].line);
        ck_assert_int_ge(asprintf(&wall, "file: %s, fluid: outside", edits[k].name), 0);
        expect_refused(dir, wall, where, edits[k].needle);
        free(wall);
        free(where);
        free(edited);
        free(text);
    }
    /* OBJ: a face naming a vertex that does not exist, index 0, a short face,
     * a missing coordinate */
    struct {
        const char *text, *name, *needle;
        int line;
    } objs[] = {
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "missing.obj",
         "the face refers to vertex 4, but the file defines 3 vertices", 4},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "negative.obj", "vertex -4, which does not exist",
         4},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "zero.obj", "'0' is not a vertex reference", 4},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "short.obj", "at least 3 vertices, this one has 2",
         4},
        {"v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", "coordinate.obj",
         "the line ends where vertex coordinate z was expected", 2},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "nofaces.obj", "holds no triangles", 0},
    };
    for (size_t k = 0; k < sizeof objs / sizeof objs[0]; k++) {
        free(test_write_file(dir, objs[k].name, objs[k].text));
        char *wall = NULL,
             *where = objs[k].line ? at_line(dir, objs[k].name, objs[k].line) : strdup(scene_at);
        ck_assert_int_ge(asprintf(&wall, "file: %s, fluid: front", objs[k].name), 0);
        expect_refused(dir, wall, where, objs[k].needle);
        free(wall);
        free(where);
    }
    /* surfaces: open where closed is asked, non-manifold, misoriented */
    char *open_text = strdup(good);
    *strstr(open_text, "  facet normal 0 0 0\n    outer loop\n      vertex 0 0 1") = '\0';
    char *open = NULL;
    ck_assert_int_ge(asprintf(&open, "%sendsolid cube\n", open_text), 0);
    free(test_write_file(dir, "open.stl", open));
    char *where = at_line(dir, "open.stl", cube_stl_line(0));
    expect_refused(dir, "file: open.stl, fluid: inside", where,
                   "open surface: the edge (0, 0, 0) to (0, 1, 0) of triangle 1 belongs to no "
                   "other triangle (4 open edges); 'fluid: inside' needs a closed surface");
    free(where);
    char *fin = cube_stl_text(0, "  facet normal 0 0 0\n    outer loop\n      vertex 0 0 0\n"
                                 "      vertex 0 1 0\n      vertex -1 0 0\n    endloop\n"
                                 "  endfacet\n");
    free(test_write_file(dir, "fin.stl", fin));
    where = at_line(dir, "fin.stl", cube_stl_line(0));
    expect_refused(dir, "file: fin.stl, fluid: front", where,
                   "non-manifold surface: the edge (0, 0, 0) to (0, 1, 0) of triangle 1 is shared "
                   "by 3 triangles");
    free(where);
    char *flipped = cube_stl_text(4, NULL);
    free(test_write_file(dir, "flipped.stl", flipped));
    where = at_line(dir, "flipped.stl", cube_stl_line(2));
    expect_refused(dir, "file: flipped.stl, fluid: outside", where,
                   "triangles 3 and 4 run along their shared edge");
    free(where);
    /* the scene's keys: a zero rotation axis, a mesh in 2D */
    free(test_write_file(dir, "cube.stl", good));
    expect_refused(dir, "file: cube.stl, fluid: outside, rotate_axis: [0, 0, 0], rotate_angle: 30",
                   "scene.yaml:9:", "rotate_axis must not be zero");
    free(flipped);
    free(fin);
    free(open);
    free(open_text);
    free(good);
    free(scene_at);
    free(dir);
}
END_TEST

START_TEST(mesh_wall_needs_3d)
{
    test_load_refused("mesh-2d",
                      "dimensions: 2\nparticles: {spacing: 0.1}\ntime: {end: 0.01}\n"
                      "domain: {min: [-1, -1], max: [2, 2]}\ngeometry:\n  fluid:\n"
                      "    - {shape: box, min: [0, 0], max: [0.5, 0.5]}\n  walls:\n"
                      "    - {shape: mesh, file: a.stl, fluid: front}\nplugins:\n"
                      "  wendland_c2: {}\n  tait: {speed_of_sound: 20}\n  continuity: {}\n"
                      "  pressure_gradient: {}\n  dbc: {}\n  time_step: {}\n  symplectic: {}\n",
                      "shape 'mesh' in geometry.walls.0 is only available in 3D");
}
END_TEST

/* ------------------------------------------------------------- runs -- */

/* An open-top tank [0, 0.4] x [0, 0.3] x [0, 0.3] as ASCII STL in mm,
 * rotated -90 degrees about z in the file (x_file = -y, y_file = x), its
 * normals pointing in: the scene turns it back (+90 degrees about z) and
 * scales it to metres. */
static char *write_tank_stl(const char *dir)
{
    const double size[3] = {0.4, 0.3, 0.3};
    /* the tank's five faces as quads of corners i = x + 2y + 4z, each wound
     * counter-clockwise seen from inside */
    static const int faces[5][4] = {
        {0, 1, 3, 2}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
    char *text = NULL;
    size_t length = 0;
    FILE *f = open_memstream(&text, &length);
    fprintf(f, "solid tank\n");
    for (int q = 0; q < 5; q++)
        for (int half = 0; half < 2; half++) {
            const int c[3] = {faces[q][0], faces[q][1 + half], faces[q][2 + half]};
            fprintf(f, "facet normal 0 0 0\nouter loop\n");
            for (int k = 0; k < 3; k++) {
                double x = (c[k] & 1) ? size[0] : 0, y = (c[k] & 2) ? size[1] : 0,
                       z = (c[k] & 4) ? size[2] : 0;
                fprintf(f, "vertex %.17g %.17g %.17g\n", 1000 * y, -1000 * x, 1000 * z);
            }
            fprintf(f, "endloop\nendfacet\n");
        }
    fprintf(f, "endsolid tank\n");
    fclose(f);
    char *path = test_write_file(dir, "tank.stl", text);
    free(text);
    return path;
}

static const char *tank_scene_format = "dimensions: 3\n"
                                       "particles: {spacing: 0.05}\n"
                                       "time: {end: 0.05}\n"
                                       "domain: {min: [-0.3, -0.3, -0.3], max: [0.7, 0.6, 0.6]}\n"
                                       "geometry:\n"
                                       "  fluid:\n"
                                       "    - {shape: box, min: [0, 0, 0], max: [0.4, 0.3, 0.15]}\n"
                                       "  walls:\n"
                                       "    - %s\n"
                                       "plugins:\n"
                                       "  wendland_c2: {}\n"
                                       "  tait: {speed_of_sound: 20}\n"
                                       "  continuity: {}\n"
                                       "  pressure_gradient: {}\n"
                                       "  artificial_viscosity: {alpha: 0.1}\n"
                                       "  gravity: {}\n"
                                       "  %s: {}\n"
                                       "  time_step: {}\n"
                                       "  symplectic: {}\n";

/* Loads the tank scene with `wall` and the wall scheme `scheme`, next to
 * the STL file in dir. */
static sluice_sim *load_tank(const char *wall, const char *scheme)
{
    char *text = NULL;
    ck_assert_int_ge(asprintf(&text, tank_scene_format, wall, scheme), 0);
    sluice_sim *sim = test_load("mesh-tank", text, NULL, 0);
    free(text);
    return sim;
}

/* The tank read from the file and `shape: tank` describe the same surface
 * (up to the triangles' diagonals and round-off of the transform): the same
 * particles, and after 40 steps the same motion to within 1e-9 m; the water
 * stays in the tank at rest to within its start-up sloshing (no particle
 * below the floor by more than a spacing, speeds under sqrt(2 g H)). */
static void compare_tanks(const char *scheme)
{
    char *dir = test_scratch("mesh-run");
    char *stl = write_tank_stl(dir);
    char *mesh_wall = NULL;
    ck_assert_int_ge(asprintf(&mesh_wall,
                              "{shape: mesh, file: '%s', fluid: front, scale: 0.001, "
                              "rotate_axis: [0, 0, 1], rotate_angle: 90, name: tank}",
                              stl),
                     0);
    const char *box_wall = "{shape: tank, min: [0, 0, 0], max: [0.4, 0.3, 0.3], name: tank}";
    sluice_sim *a = load_tank(mesh_wall, scheme);
    sluice_sim *b = load_tank(box_wall, scheme);
    free(mesh_wall);
    ck_assert_int_eq(sluice_sim_begin(a, NULL), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_begin(b, NULL), SLUICE_RUN_COMPLETE);
    ck_assert_int_eq(sluice_sim_view(a)->count, sluice_sim_view(b)->count);
    for (int step = 0; step < 40; step++) {
        ck_assert_int_eq(sluice_sim_step(a), SLUICE_RUN_COMPLETE);
        ck_assert_int_eq(sluice_sim_step(b), SLUICE_RUN_COMPLETE);
    }
    const sluice_view *va = sluice_sim_view(a), *vb = sluice_sim_view(b);
    ck_assert_int_eq(va->count, vb->count);
    const double g = 9.81, H = 0.15, spacing = 0.05, limit = sqrt(2 * g * H);
    sluice_real *ua = test_column(a, "velocity", 0), *wa = test_column(a, "velocity", 2);
    double largest = 0, lowest = HUGE_VAL;
    for (sluice_index i = 0; i < va->count; i++) {
        for (int d = 0; d < 3; d++)
            ck_assert_msg(fabs((double)va->position[d][i] - (double)vb->position[d][i]) < 1e-9,
                          "%s: particle %ld differs along %c: %.17g vs %.17g", scheme, (long)i,
                          "xyz"[d], (double)va -> position[d][i], (double)vb -> position[d][i]);
        largest = fmax(largest, hypot((double)ua[i], (double)wa[i]));
        lowest = fmin(lowest, (double)va->position[2][i]);
    }
    ck_assert_msg(largest < limit, "%s: speed %g above sqrt(2 g H) = %g", scheme, largest, limit);
    ck_assert_msg(lowest > -spacing * 4, "%s: a particle at z = %g", scheme, lowest);
    ck_assert_double_gt(sluice_sim_time(a), 0);
    sluice_sim_free(a);
    sluice_sim_free(b);
    free(stl);
    free(dir);
}

START_TEST(tank_from_stl_dbc) { compare_tanks("dbc"); }
END_TEST

START_TEST(tank_from_stl_penalty_contact) { compare_tanks("penalty_contact"); }
END_TEST

START_TEST(tank_from_stl_mdbc) { compare_tanks("mdbc"); }
END_TEST

START_TEST(tank_from_stl_repulsive_force) { compare_tanks("repulsive_force"); }
END_TEST

int main(void)
{
    Suite *s = suite_create("mesh");
    TCase *readers = tcase_create("readers");
    tcase_add_test(readers, cube_three_formats);
    tcase_add_test(readers, tolerated_variants);
    tcase_add_test(readers, transforms_in_order);
    tcase_add_test(readers, fluid_side_of_closed_surface);
    tcase_add_test(readers, mesh_wall_needs_3d);
    suite_add_tcase(s, readers);
    TCase *refusals = tcase_create("refusals");
    tcase_set_timeout(refusals, 120);
    tcase_add_test(refusals, malformed_files_refused);
    tcase_add_test(refusals, malformed_text_and_surfaces_refused);
    suite_add_tcase(s, refusals);
    TCase *runs = tcase_create("runs");
    tcase_set_timeout(runs, 240);
    tcase_add_test(runs, tank_from_stl_dbc);
    tcase_add_test(runs, tank_from_stl_penalty_contact);
    tcase_add_test(runs, tank_from_stl_mdbc);
    tcase_add_test(runs, tank_from_stl_repulsive_force);
    suite_add_tcase(s, runs);
    return test_run_suite(s);
}
