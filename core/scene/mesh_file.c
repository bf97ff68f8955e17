/* STL (ASCII, binary) and OBJ readers and surface checks (mesh_file.h). */
#include "mesh_file.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Largest mesh file read (bytes). */
#define MESH_MAX_BYTES ((size_t)1 << 31)

static int fail(sluice_mesh_problem *problem, int line, int column, uint32_t triangle,
                const char *format, ...) __attribute__((format(printf, 5, 6)));
static int fail(sluice_mesh_problem *problem, int line, int column, uint32_t triangle,
                const char *format, ...)
{
    problem->line = line;
    problem->column = column;
    problem->triangle = triangle;
    va_list ap;
    va_start(ap, format);
    vsnprintf(problem->message, sizeof problem->message, format, ap);
    va_end(ap);
    return -1;
}

void sluice_mesh_free(sluice_mesh *mesh)
{
    if (!mesh)
        return;
    free(mesh->vertices);
    free(mesh->faces);
    free(mesh->face_line);
    memset(mesh, 0, sizeof *mesh);
}

const char *sluice_mesh_format_name(sluice_mesh_format format)
{
    return format == SLUICE_MESH_STL_ASCII    ? "ASCII STL"
           : format == SLUICE_MESH_STL_BINARY ? "binary STL"
                                              : "OBJ";
}

/* ------------------------------------------------------------ building -- */

/* Growable vertex and triangle lists while a file is read. */
typedef struct builder {
    double *vertices;
    size_t vertex_count, vertex_capacity;
    uint32_t *faces, *lines;
    size_t face_count, face_capacity, line_capacity;
} builder;

static int grow(void **data, size_t *capacity, size_t need, size_t item)
{
    if (need <= *capacity)
        return 0;
    size_t fresh = *capacity ? 2 * *capacity : 64;
    while (fresh < need)
        fresh *= 2;
    void *p = realloc(*data, fresh * item);
    if (!p)
        return -1;
    *data = p;
    *capacity = fresh;
    return 0;
}

static int add_vertex(builder *b, const double v[3])
{
    if (b->vertex_count >= UINT32_MAX)
        return -1;
    if (grow((void **)&b->vertices, &b->vertex_capacity, b->vertex_count + 1, 3 * sizeof(double)))
        return -1;
    memcpy(b->vertices + 3 * b->vertex_count++, v, 3 * sizeof(double));
    return 0;
}

static int add_face(builder *b, uint32_t i, uint32_t j, uint32_t k, uint32_t line)
{
    if (b->face_count >= UINT32_MAX / 3)
        return -1;
    if (grow((void **)&b->faces, &b->face_capacity, b->face_count + 1, 3 * sizeof(uint32_t)))
        return -1;
    if (grow((void **)&b->lines, &b->line_capacity, b->face_count + 1, sizeof(uint32_t)))
        return -1;
    uint32_t *f = b->faces + 3 * b->face_count;
    f[0] = i, f[1] = j, f[2] = k;
    b->lines[b->face_count++] = line;
    return 0;
}

static void builder_free(builder *b)
{
    free(b->vertices);
    free(b->faces);
    free(b->lines);
}

/* ------------------------------------------------------------ the file -- */

static int read_whole(const char *path, unsigned char **data, size_t *size,
                      sluice_mesh_problem *problem)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return fail(problem, 0, 0, UINT32_MAX, "cannot open the mesh file: %s", strerror(errno));
    unsigned char *buffer = NULL;
    size_t count = 0, capacity = 0;
    for (;;) {
        if (grow((void **)&buffer, &capacity, count + 65536 + 1, 1)) {
            free(buffer);
            fclose(f);
            return fail(problem, 0, 0, UINT32_MAX, "out of memory reading the mesh file");
        }
        size_t n = fread(buffer + count, 1, 65536, f);
        count += n;
        if (n < 65536)
            break;
        if (count > MESH_MAX_BYTES) {
            free(buffer);
            fclose(f);
            return fail(problem, 0, 0, UINT32_MAX, "the mesh file is larger than %zu bytes",
                        MESH_MAX_BYTES);
        }
    }
    int error = ferror(f);
    fclose(f);
    if (error) {
        free(buffer);
        return fail(problem, 0, 0, UINT32_MAX, "cannot read the mesh file (is it a directory?)");
    }
    buffer[count] = '\0';
    *data = buffer;
    *size = count;
    return 0;
}

/* ----------------------------------------------------------- ASCII text -- */

/* A cursor over text with its line and column. */
typedef struct cursor {
    const char *text, *end;
    const char *at;
    int line;
    const char *line_start;
} cursor;

/* Skips blanks; stops at a newline when !newlines. */
static void skip_blanks(cursor *c, int newlines)
{
    while (c->at < c->end && isspace((unsigned char)*c->at)) {
        if (*c->at == '\n') {
            if (!newlines)
                return;
            c->line++;
            c->line_start = c->at + 1;
        }
        c->at++;
    }
}

/* The next whitespace-separated token (across lines): *length 0 at the end. */
static const char *next_token(cursor *c, size_t *length, int *line, int *column)
{
    skip_blanks(c, 1);
    const char *start = c->at;
    while (c->at < c->end && !isspace((unsigned char)*c->at) && *c->at != '\0')
        c->at++;
    *length = (size_t)(c->at - start);
    *line = c->line;
    *column = (int)(start - c->line_start) + 1;
    return start;
}

/* A real from a token of `length` bytes, finite unless any_value; 0 or -1. */
static int parse_real(const char *token, size_t length, double *value, int any_value)
{
    char buffer[64];
    if (length == 0 || length >= sizeof buffer)
        return -1;
    memcpy(buffer, token, length);
    buffer[length] = '\0';
    char *end = NULL;
    errno = 0;
    double v = strtod(buffer, &end);
    if (end != buffer + length || (!any_value && !isfinite(v)))
        return -1;
    *value = v;
    return 0;
}

/* A token as a message shows it: at most 40 bytes, a byte that is not
 * printable ASCII as '?'. */
static const char *shown(const char *token, size_t length, char *out, size_t size)
{
    size_t n = length < 40 ? length : 40;
    if (n >= size)
        n = size - 1;
    for (size_t k = 0; k < n; k++) {
        unsigned char b = (unsigned char)token[k];
        out[k] = b >= 32 && b < 127 ? (char)b : '?';
    }
    out[n] = '\0';
    return out;
}

static int token_is(const char *token, size_t length, const char *word)
{
    return length == strlen(word) && strncasecmp(token, word, length) == 0;
}

/* The coordinates after `vertex` or `normal`, or an OBJ `v` (on_one_line:
 * within its line). */
static int read_coordinates(cursor *c, double v[3], const char *what, uint32_t triangle,
                            int on_one_line, sluice_mesh_problem *problem)
{
    char text[48];
    for (int d = 0; d < 3; d++) {
        size_t n;
        int line, column;
        if (on_one_line) {
            skip_blanks(c, 0);
            if (c->at >= c->end || *c->at == '\n' || *c->at == '#')
                return fail(problem, c->line, (int)(c->at - c->line_start) + 1, triangle,
                            "the line ends where %s coordinate %c was expected", what, "xyz"[d]);
        }
        const char *t = next_token(c, &n, &line, &column);
        if (n == 0)
            return fail(problem, line, column, triangle,
                        "the file ends inside a %s (truncated?): %c is missing", what, "xyz"[d]);
        if (parse_real(t, n, &v[d], strcmp(what, "normal") == 0) != 0)
            return fail(problem, line, column, triangle, "%s coordinate %c is '%s', not a %snumber",
                        what, "xyz"[d], shown(t, n, text, sizeof text),
                        strcmp(what, "normal") == 0 ? "" : "finite ");
    }
    return 0;
}

/* Expects the keyword `word` next. */
static int expect(cursor *c, const char *word, uint32_t triangle, sluice_mesh_problem *problem)
{
    char text[48];
    size_t n;
    int line, column;
    const char *t = next_token(c, &n, &line, &column);
    if (n == 0)
        return fail(problem, line, column, triangle,
                    "the file ends where '%s' was expected (truncated?)", word);
    if (!token_is(t, n, word))
        return fail(problem, line, column, triangle, "expected '%s', found '%s'", word,
                    shown(t, n, text, sizeof text));
    return 0;
}

/* One facet after its `facet` keyword (at line `line`). */
static int read_facet(cursor *c, builder *b, uint32_t line, sluice_mesh_problem *problem)
{
    const uint32_t triangle = (uint32_t)b->face_count;
    double normal[3], v[3];
    if (expect(c, "normal", triangle, problem) != 0 ||
        read_coordinates(c, normal, "normal", triangle, 0, problem) != 0 ||
        expect(c, "outer", triangle, problem) != 0 || expect(c, "loop", triangle, problem) != 0)
        return -1;
    uint32_t first = (uint32_t)b->vertex_count;
    for (int k = 0; k < 3; k++) {
        if (expect(c, "vertex", triangle, problem) != 0 ||
            read_coordinates(c, v, "vertex", triangle, 0, problem) != 0)
            return -1;
        if (add_vertex(b, v) != 0)
            return fail(problem, 0, 0, UINT32_MAX, "out of memory reading the mesh file");
    }
    if (expect(c, "endloop", triangle, problem) != 0 ||
        expect(c, "endfacet", triangle, problem) != 0)
        return -1;
    if (add_face(b, first, first + 1, first + 2, line) != 0)
        return fail(problem, 0, 0, UINT32_MAX, "out of memory reading the mesh file");
    return 0;
}

static int read_stl_ascii(const unsigned char *data, size_t size, builder *b,
                          sluice_mesh_problem *problem)
{
    char text[48];
    cursor c = {(const char *)data, (const char *)data + size, (const char *)data, 1,
                (const char *)data};
    size_t n;
    int line, column;
    next_token(&c, &n, &line, &column);   /* `solid`, checked by the caller */
    while (c.at < c.end && *c.at != '\n') /* the solid's name */
        c.at++;
    for (;;) {
        const char *t = next_token(&c, &n, &line, &column);
        if (n == 0)
            return fail(problem, line, column, UINT32_MAX,
                        "the file ends without 'endsolid' (truncated?)");
        if (token_is(t, n, "endsolid")) {
            while (c.at < c.end && *c.at != '\n') /* the solid's name */
                c.at++;
            t = next_token(&c, &n, &line, &column);
            if (n == 0)
                break;
            if (!token_is(t, n, "solid")) /* files that join several solids */
                return fail(problem, line, column, UINT32_MAX,
                            "expected 'solid' or the end of the file after 'endsolid', found "
                            "'%s'",
                            shown(t, n, text, sizeof text));
            while (c.at < c.end && *c.at != '\n')
                c.at++;
            continue;
        }
        if (!token_is(t, n, "facet"))
            return fail(problem, line, column, UINT32_MAX,
                        "expected 'facet' or 'endsolid', found '%s'",
                        shown(t, n, text, sizeof text));
        if (read_facet(&c, b, (uint32_t)line, problem) != 0)
            return -1;
    }
    return 0;
}

/* ----------------------------------------------------------- binary STL -- */

static uint32_t little_u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static double little_float(const unsigned char *p)
{
    uint32_t bits = little_u32(p);
    float f;
    memcpy(&f, &bits, sizeof f);
    return (double)f;
}

static int read_stl_binary(const unsigned char *data, size_t size, builder *b,
                           sluice_mesh_problem *problem)
{
    const uint32_t count = little_u32(data + 80);
    (void)size;
    for (uint32_t t = 0; t < count; t++) {
        const unsigned char *record = data + 84 + 50 * (size_t)t;
        uint32_t first = (uint32_t)b->vertex_count;
        for (int k = 1; k < 4; k++) { /* the stored normal (k = 0) is not read */
            double v[3];
            for (int d = 0; d < 3; d++) {
                v[d] = little_float(record + 12 * k + 4 * d);
                if (!isfinite(v[d]))
                    return fail(problem, 0, 0, t,
                                "triangle %u (bytes %zu-%zu): %s coordinate %c is not finite "
                                "(NaN or infinite)",
                                t + 1, 84 + 50 * (size_t)t, 84 + 50 * (size_t)t + 49, "vertex",
                                "xyz"[d]);
            }
            if (add_vertex(b, v) != 0)
                return fail(problem, 0, 0, UINT32_MAX, "out of memory reading the mesh file");
        }
        if (add_face(b, first, first + 1, first + 2, 0) != 0)
            return fail(problem, 0, 0, UINT32_MAX, "out of memory reading the mesh file");
    }
    return 0;
}

/* ------------------------------------------------------------------ OBJ -- */

/* One vertex reference of a face: "i", "i/t", "i//n" or "i/t/n"; the
 * vertex index i (1-based, or negative: from the end of the vertices read so
 * far). *index is 0-based, or (positive references) checked at the end. */
static int parse_reference(const char *token, size_t length, size_t vertices_so_far, int64_t *index)
{
    char buffer[64];
    if (length == 0 || length >= sizeof buffer)
        return -1;
    memcpy(buffer, token, length);
    buffer[length] = '\0';
    char *end = NULL;
    errno = 0;
    long long i = strtoll(buffer, &end, 10);
    if (end == buffer || errno != 0 || (*end != '\0' && *end != '/') || i == 0)
        return -1;
    *index = i > 0 ? (int64_t)i - 1 : (int64_t)vertices_so_far + (int64_t)i;
    return 0;
}

/* A face line after its `f` (at line `line`): fan-triangulated from its
 * first vertex. */
static int read_obj_face(cursor *c, builder *b, int line, sluice_mesh_problem *problem)
{
    char text[48];
    int64_t first = 0, previous = 0;
    int count = 0;
    for (;;) {
        skip_blanks(c, 0);
        if (c->at >= c->end || *c->at == '\n' || *c->at == '#')
            break;
        size_t n;
        int l, column;
        const char *t = next_token(c, &n, &l, &column);
        int64_t index;
        if (parse_reference(t, n, b->vertex_count, &index) != 0)
            return fail(problem, l, column, UINT32_MAX,
                        "'%s' is not a vertex reference (a non-zero index, optionally "
                        "followed by /texture/normal)",
                        shown(t, n, text, sizeof text));
        if (index < 0 || index >= (int64_t)UINT32_MAX)
            return fail(problem, l, column, UINT32_MAX,
                        "the face refers to vertex %s, which does not exist (%zu vertices "
                        "before this line)",
                        shown(t, n, text, sizeof text), b->vertex_count);
        if (count == 0)
            first = index;
        else if (count >= 2 && add_face(b, (uint32_t)first, (uint32_t)previous, (uint32_t)index,
                                        (uint32_t)line) != 0)
            return fail(problem, 0, 0, UINT32_MAX, "out of memory reading the mesh file");
        previous = index;
        count++;
    }
    if (count < 3)
        return fail(problem, line, 1, UINT32_MAX,
                    "a face needs at least 3 vertices, this one has %d", count);
    return 0;
}

static int read_obj(const unsigned char *data, size_t size, builder *b,
                    sluice_mesh_problem *problem)
{
    cursor c = {(const char *)data, (const char *)data + size, (const char *)data, 1,
                (const char *)data};
    while (c.at < c.end) {
        skip_blanks(&c, 1);
        if (c.at >= c.end)
            break;
        size_t n;
        int line, column;
        const char *t = next_token(&c, &n, &line, &column);
        if (t[0] == '#') {
            /* a comment: the rest of the line */
        } else if (token_is(t, n, "v")) {
            double v[3];
            if (read_coordinates(&c, v, "vertex", UINT32_MAX, 1, problem) != 0)
                return -1;
            if (add_vertex(b, v) != 0)
                return fail(problem, 0, 0, UINT32_MAX, "out of memory reading the mesh file");
        } else if (token_is(t, n, "f")) {
            if (read_obj_face(&c, b, line, problem) != 0)
                return -1;
        }
        /* anything else (vt, vn, g, o, s, usemtl, mtllib, l, ...) is not
         * geometry: the rest of its line is skipped */
        while (c.at < c.end && *c.at != '\n')
            c.at++;
    }
    for (size_t f = 0; f < 3 * b->face_count; f++)
        if (b->faces[f] >= b->vertex_count)
            return fail(problem, (int)b->lines[f / 3], 1, (uint32_t)(f / 3),
                        "the face refers to vertex %u, but the file defines %zu vertices",
                        b->faces[f] + 1, b->vertex_count);
    return 0;
}

/* ------------------------------------------------------------- welding -- */

typedef struct keyed_point {
    double xyz[3];
    uint32_t index;
} keyed_point;

static int compare_keyed(const void *x, const void *y)
{
    const keyed_point *a = x, *b = y;
    for (int d = 0; d < 3; d++) {
        if (a->xyz[d] < b->xyz[d])
            return -1;
        if (a->xyz[d] > b->xyz[d])
            return 1;
    }
    return (a->index > b->index) - (a->index < b->index);
}

/* Merges the vertices with equal coordinates (STL stores each triangle's
 * corners apart; OBJ exporters repeat a vertex where its texture or normal
 * changes), keeping them in the order of the file. */
static int weld(builder *b)
{
    const size_t n = b->vertex_count;
    if (n == 0)
        return 0;
    keyed_point *keyed = malloc(n * sizeof *keyed);
    uint32_t *remap = malloc(n * sizeof *remap);
    if (!keyed || !remap) {
        free(keyed);
        free(remap);
        return -1;
    }
    for (size_t i = 0; i < n; i++) {
        memcpy(keyed[i].xyz, b->vertices + 3 * i, sizeof keyed[i].xyz);
        keyed[i].index = (uint32_t)i;
    }
    qsort(keyed, n, sizeof *keyed, compare_keyed);
    /* every vertex points at the first (lowest index) of its equals */
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && keyed[j].xyz[0] == keyed[i].xyz[0] && keyed[j].xyz[1] == keyed[i].xyz[1] &&
               keyed[j].xyz[2] == keyed[i].xyz[2])
            j++;
        for (size_t k = i; k < j; k++)
            remap[keyed[k].index] = keyed[i].index;
        i = j;
    }
    /* compact: the kept vertices renumbered in order */
    size_t kept = 0;
    for (size_t i = 0; i < n; i++) {
        if (remap[i] == i) {
            memmove(b->vertices + 3 * kept, b->vertices + 3 * i, 3 * sizeof(double));
            remap[i] = (uint32_t)kept++;
        } else {
            remap[i] = remap[remap[i]];
        }
    }
    for (size_t f = 0; f < 3 * b->face_count; f++)
        b->faces[f] = remap[b->faces[f]];
    b->vertex_count = kept;
    free(keyed);
    free(remap);
    return 0;
}

/* ---------------------------------------------------------- the reader -- */

static void sub(double out[3], const double a[3], const double b[3])
{
    for (int d = 0; d < 3; d++)
        out[d] = a[d] - b[d];
}

static void cross(double out[3], const double a[3], const double b[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static double norm(const double a[3]) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

/* Refuses the first triangle with a repeated vertex or no area (the rule of
 * sluice_wall_build_triangles: |ab x ac| <= 1e-12 |ab| |ac|). */
static int check_degenerate(const builder *b, int has_lines, sluice_mesh_problem *problem)
{
    for (size_t f = 0; f < b->face_count; f++) {
        const uint32_t *t = b->faces + 3 * f;
        const double *p = b->vertices + 3 * (size_t)t[0], *q = b->vertices + 3 * (size_t)t[1],
                     *r = b->vertices + 3 * (size_t)t[2];
        double ab[3], ac[3], n[3];
        sub(ab, q, p);
        sub(ac, r, p);
        cross(n, ab, ac);
        int repeated = t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
        if (repeated || !(norm(n) > 1e-12 * norm(ab) * norm(ac)))
            return fail(problem, has_lines ? (int)b->lines[f] : 0, has_lines ? 1 : 0, (uint32_t)f,
                        "triangle %zu is degenerate (%s): corners (%g, %g, %g), (%g, %g, %g), "
                        "(%g, %g, %g)",
                        f + 1, repeated ? "two corners coincide" : "zero area", p[0], p[1], p[2],
                        q[0], q[1], q[2], r[0], r[1], r[2]);
    }
    return 0;
}

static int has_extension(const char *path, const char *extension)
{
    size_t n = strlen(path), e = strlen(extension);
    return n > e && strcasecmp(path + n - e, extension) == 0;
}

/* Which kind of STL: binary when the size matches the count at bytes
 * 80-83, ASCII when it starts with `solid` and holds no NUL byte (a binary
 * header may start with `solid` too); -1 after reporting otherwise. */
static int stl_kind(const unsigned char *data, size_t size, sluice_mesh_problem *problem)
{
    const uint64_t count = size >= 84 ? little_u32(data + 80) : 0;
    if (size >= 84 && 84 + 50 * count == size)
        return SLUICE_MESH_STL_BINARY;
    const unsigned char *p = data;
    while (p < data + size && isspace(*p))
        p++;
    int solid = (size_t)(data + size - p) >= 5 && strncasecmp((const char *)p, "solid", 5) == 0 &&
                (p + 5 == data + size || isspace(p[5]));
    if (solid && !memchr(data, '\0', size))
        return SLUICE_MESH_STL_ASCII;
    if (size < 84)
        return fail(problem, 0, 0, UINT32_MAX,
                    "too short for a binary STL (%zu bytes; the header and triangle count alone "
                    "take 84) and not an ASCII one (%s): truncated?",
                    size, solid ? "it holds NUL bytes" : "it does not start with 'solid'");
    return fail(problem, 0, 0, UINT32_MAX,
                "binary STL whose size disagrees with its triangle count: the count at bytes "
                "80-83 is %llu, which needs 84 + 50 x %llu = %llu bytes, the file has %zu%s",
                (unsigned long long)count, (unsigned long long)count,
                (unsigned long long)(84 + 50 * count), size,
                size < 84 + 50 * count ? " (truncated?)" : "");
}

/* Reads data (size bytes, NUL-terminated) into b; the format in *format. */
static int read_any(const char *path, const unsigned char *data, size_t size, builder *b,
                    sluice_mesh_format *format, sluice_mesh_problem *problem)
{
    if (has_extension(path, ".obj")) {
        *format = SLUICE_MESH_OBJ;
        if (memchr(data, '\0', size))
            return fail(problem, 0, 0, UINT32_MAX, "an OBJ file is text, this one holds NUL bytes");
        return read_obj(data, size, b, problem);
    }
    if (!has_extension(path, ".stl"))
        return fail(problem, 0, 0, UINT32_MAX,
                    "unknown mesh format: the file name must end in .stl or .obj");
    int kind = stl_kind(data, size, problem);
    if (kind < 0)
        return -1;
    *format = (sluice_mesh_format)kind;
    if (kind == SLUICE_MESH_STL_BINARY)
        return read_stl_binary(data, size, b, problem);
    return read_stl_ascii(data, size, b, problem);
}

int sluice_mesh_read(const char *path, sluice_mesh *mesh, sluice_mesh_problem *problem)
{
    memset(mesh, 0, sizeof *mesh);
    memset(problem, 0, sizeof *problem);
    problem->triangle = UINT32_MAX;
    unsigned char *data = NULL;
    size_t size = 0;
    if (read_whole(path, &data, &size, problem) != 0)
        return -1;
    if (size == 0) {
        free(data);
        return fail(problem, 0, 0, UINT32_MAX, "the mesh file is empty");
    }
    builder b = {0};
    sluice_mesh_format format = SLUICE_MESH_OBJ;
    int rc = read_any(path, data, size, &b, &format, problem);
    free(data);
    if (rc == 0 && b.face_count == 0)
        rc = fail(problem, 0, 0, UINT32_MAX, "the mesh file holds no triangles");
    if (rc == 0 && weld(&b) != 0)
        rc = fail(problem, 0, 0, UINT32_MAX, "out of memory reading the mesh file");
    if (rc == 0)
        rc = check_degenerate(&b, format != SLUICE_MESH_STL_BINARY, problem);
    if (rc != 0) {
        builder_free(&b);
        return -1;
    }
    mesh->format = format;
    mesh->vertices = b.vertices;
    mesh->vertex_count = (uint32_t)b.vertex_count;
    mesh->faces = b.faces;
    mesh->face_count = (uint32_t)b.face_count;
    if (format == SLUICE_MESH_STL_BINARY) {
        free(b.lines);
        mesh->face_line = NULL;
    } else {
        mesh->face_line = b.lines;
    }
    return 0;
}

/* -------------------------------------------------------------- checks -- */

typedef struct mesh_edge {
    uint32_t lo, hi, face;
    uint8_t forward;
} mesh_edge;

static int compare_edges(const void *x, const void *y)
{
    const mesh_edge *a = x, *b = y;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    return (a->face > b->face) - (a->face < b->face);
}

int sluice_mesh_check_edges(const sluice_mesh *mesh, sluice_mesh_edges *edges)
{
    memset(edges, 0, sizeof *edges);
    edges->open_triangle = edges->nonmanifold_triangle = edges->misoriented_triangle =
        edges->misoriented_other = UINT32_MAX;
    const size_t count = 3 * (size_t)mesh->face_count;
    mesh_edge *list = malloc((count ? count : 1) * sizeof *list);
    if (!list)
        return -1;
    for (uint32_t f = 0; f < mesh->face_count; f++)
        for (int j = 0; j < 3; j++) {
            uint32_t p = mesh->faces[3 * (size_t)f + j],
                     q = mesh->faces[3 * (size_t)f + (j + 1) % 3];
            mesh_edge *e = &list[3 * (size_t)f + j];
            e->lo = p < q ? p : q;
            e->hi = p < q ? q : p;
            e->face = f;
            e->forward = p < q;
        }
    qsort(list, count, sizeof *list, compare_edges);
    for (size_t i = 0; i < count;) {
        size_t j = i + 1;
        while (j < count && list[j].lo == list[i].lo && list[j].hi == list[i].hi)
            j++;
        /* the triangle named is the lowest on the edge (sorted by face) */
        if (j - i == 1) {
            if (edges->open++ == 0 || list[i].face < edges->open_triangle) {
                edges->open_triangle = list[i].face;
                edges->open_edge[0] = list[i].lo, edges->open_edge[1] = list[i].hi;
            }
        } else if (j - i > 2) {
            if (edges->nonmanifold++ == 0 || list[i].face < edges->nonmanifold_triangle) {
                edges->nonmanifold_triangle = list[i].face;
                edges->nonmanifold_uses = (uint32_t)(j - i);
                edges->nonmanifold_edge[0] = list[i].lo, edges->nonmanifold_edge[1] = list[i].hi;
            }
        } else if (list[i].forward == list[i + 1].forward) {
            if (edges->misoriented++ == 0 || list[i].face < edges->misoriented_triangle) {
                edges->misoriented_triangle = list[i].face;
                edges->misoriented_other = list[i + 1].face;
                edges->misoriented_edge[0] = list[i].lo, edges->misoriented_edge[1] = list[i].hi;
            }
        }
        i = j;
    }
    free(list);
    return 0;
}

double sluice_mesh_area(const sluice_mesh *mesh)
{
    double area = 0;
    for (uint32_t f = 0; f < mesh->face_count; f++) {
        const uint32_t *t = mesh->faces + 3 * (size_t)f;
        double ab[3], ac[3], n[3];
        sub(ab, mesh->vertices + 3 * (size_t)t[1], mesh->vertices + 3 * (size_t)t[0]);
        sub(ac, mesh->vertices + 3 * (size_t)t[2], mesh->vertices + 3 * (size_t)t[0]);
        cross(n, ab, ac);
        area += 0.5 * norm(n);
    }
    return area;
}

double sluice_mesh_volume(const sluice_mesh *mesh)
{
    double volume = 0;
    for (uint32_t f = 0; f < mesh->face_count; f++) {
        const uint32_t *t = mesh->faces + 3 * (size_t)f;
        const double *a = mesh->vertices + 3 * (size_t)t[0];
        double bc[3];
        cross(bc, mesh->vertices + 3 * (size_t)t[1], mesh->vertices + 3 * (size_t)t[2]);
        volume += (a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2]) / 6.0;
    }
    return volume;
}

int sluice_mesh_transform(sluice_mesh *mesh, double scale, const double axis[3], double angle_deg,
                          const double translate[3])
{
    if (!(scale > 0) || !isfinite(scale) || !isfinite(angle_deg))
        return -1;
    double u[3] = {0, 0, 1}, length = axis ? norm(axis) : 0;
    if (angle_deg != 0) {
        if (!(length > 0) || !isfinite(length))
            return -1;
        for (int d = 0; d < 3; d++)
            u[d] = axis[d] / length;
    }
    /* Rodrigues: R = cos I + sin [u]x + (1 - cos) u u^T */
    const double theta = angle_deg * M_PI / 180.0, c = cos(theta), s = sin(theta), k = 1 - c;
    const double R[3][3] = {
        {c + k * u[0] * u[0], k * u[0] * u[1] - s * u[2], k * u[0] * u[2] + s * u[1]},
        {k * u[1] * u[0] + s * u[2], c + k * u[1] * u[1], k * u[1] * u[2] - s * u[0]},
        {k * u[2] * u[0] - s * u[1], k * u[2] * u[1] + s * u[0], c + k * u[2] * u[2]},
    };
    for (uint32_t v = 0; v < mesh->vertex_count; v++) {
        double *x = mesh->vertices + 3 * (size_t)v, y[3];
        for (int i = 0; i < 3; i++)
            y[i] = scale * (R[i][0] * x[0] + R[i][1] * x[1] + R[i][2] * x[2]) +
                   (translate ? translate[i] : 0);
        memcpy(x, y, sizeof y);
    }
    return 0;
}

void sluice_mesh_reverse(sluice_mesh *mesh)
{
    for (uint32_t f = 0; f < mesh->face_count; f++) {
        uint32_t *t = mesh->faces + 3 * (size_t)f;
        uint32_t swap = t[1];
        t[1] = t[2];
        t[2] = swap;
    }
}
