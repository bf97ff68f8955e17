/* Scene geometry: lattice fills of fluid regions, walls with pseudo-normals,
 * signed distance to walls and the lattice points of wall layers. The
 * contract is in geometry.h; the choices it leaves open are documented here.
 *
 * Conventions
 *  - Lattice points are origin + (k + 1/2) dx per axis, k any integer; in 2D
 *    only x and y are lattice coordinates and z is 0. Every function computes
 *    a lattice coordinate with the same expression (lattice_coordinate), so
 *    fluid points and wall points generated separately line up bit for bit.
 *  - Internal arithmetic is in double whatever sluice_real is.
 *
 * Wall storage (sluice_wall_geometry), per element e:
 *  2D  points         + 6e: a, b
 *      normals        + 3e
 *      vertex_normals + 6e: pseudo-normal at a, then at b
 *      open_vertex    + 2e: a open, b open
 *  3D  points         + 9e: a, b, c
 *      normals        + 3e
 *      vertex_normals + 9e: pseudo-normals at a, b, c
 *      open_vertex    + 3e: a, b, c lies on an open edge (of any triangle)
 *      edge_normals   + 9e: pseudo-normals of the edges ab, bc, ca
 *      open_edge      + 3e: ab, bc, ca belongs to this triangle only
 *  The feature numbers of sluice_segment_closest/sluice_triangle_closest index
 *  these directly (triangle feature 1..3 -> vertex f - 1, 4..6 -> edge f - 4).
 */
#include "geometry.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Relative tolerance (in lattice units) for boundaries that fall on lattice
 * points, and for "beyond an open end" decisions (in units of edge length). */
#define LATTICE_TOLERANCE 1e-9
#define BEYOND_TOLERANCE 1e-9
/* Lattice indices beyond this magnitude are refused (doubles stay exact). */
#define INDEX_LIMIT 4503599627370496.0 /* 2^52 */

/* --------------------------------------------------------- small vectors -- */

static void load3(double v[3], const sluice_real p[3])
{
    v[0] = (double)p[0];
    v[1] = (double)p[1];
    v[2] = (double)p[2];
}

static void store3(sluice_real out[3], const double v[3])
{
    out[0] = (sluice_real)v[0];
    out[1] = (sluice_real)v[1];
    out[2] = (sluice_real)v[2];
}

static void sub3(double out[3], const double a[3], const double b[3])
{
    out[0] = a[0] - b[0];
    out[1] = a[1] - b[1];
    out[2] = a[2] - b[2];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(double out[3], const double a[3], const double b[3])
{
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

static double norm3(const double a[3])
{
    return sqrt(dot3(a, a));
}

/* Normalises v in place; returns its former length (v unchanged if 0). */
static double normalise3(double v[3])
{
    double n = norm3(v);
    if (n > 0) {
        v[0] /= n;
        v[1] /= n;
        v[2] /= n;
    }
    return n;
}

static double distance3(const double a[3], const double b[3])
{
    double d[3];
    sub3(d, a, b);
    return norm3(d);
}

static int finite3(const sluice_real p[3])
{
    return isfinite((double)p[0]) && isfinite((double)p[1]) && isfinite((double)p[2]);
}

/* --------------------------------------------------------------- points -- */

static int points_reserve(sluice_points *points, size_t extra)
{
    if (points->capacity >= points->count && extra <= points->capacity - points->count)
        return 0;
    const size_t limit = SIZE_MAX / (3 * sizeof(sluice_real));
    if (extra > limit - points->count)
        return -1;
    size_t need = points->count + extra;
    size_t capacity = points->capacity ? points->capacity : 64;
    while (capacity < need)
        capacity = capacity > limit / 2 ? limit : 2 * capacity;
    sluice_real *grown = realloc(points->xyz, capacity * 3 * sizeof *grown);
    if (!grown)
        return -1;
    points->xyz = grown;
    points->capacity = capacity;
    return 0;
}

int sluice_points_push(sluice_points *points, const sluice_real p[3])
{
    if (points_reserve(points, 1) != 0)
        return -1;
    memcpy(points->xyz + 3 * points->count, p, 3 * sizeof *p);
    points->count++;
    return 0;
}

void sluice_points_free(sluice_points *points)
{
    if (!points)
        return;
    free(points->xyz);
    points->xyz = NULL;
    points->count = points->capacity = 0;
}

/* -------------------------------------------------------------- lattice -- */

static double lattice_coordinate(double origin, int64_t k, double spacing)
{
    return origin + ((double)k + 0.5) * spacing;
}

/* Lattice units of x: the k for which x is the lattice coordinate. */
static double lattice_units(double x, double origin, double spacing)
{
    return (x - origin) / spacing - 0.5;
}

static double lattice_tolerance(double u)
{
    return LATTICE_TOLERANCE * fmax(1.0, fabs(u));
}

static int index_ok(double k)
{
    return isfinite(k) && fabs(k) <= INDEX_LIMIT;
}

/* [*first, *last] (inclusive; empty when last < first): the k with
 * lo <= x_k < hi, where a bound within the relative tolerance of a lattice
 * point counts as exactly on it. Returns -1 for unusable bounds. */
static int lattice_range_half_open(double lo, double hi, double origin, double spacing,
                                   int64_t *first, int64_t *last)
{
    double a = lattice_units(lo, origin, spacing), b = lattice_units(hi, origin, spacing);
    double ka = ceil(a - lattice_tolerance(a));
    double kb = ceil(b - lattice_tolerance(b)) - 1.0;
    if (!index_ok(ka) || !index_ok(kb))
        return -1;
    *first = (int64_t)ka;
    *last = (int64_t)kb;
    return 0;
}

/* [*first, *last]: every k with lo <= x_k <= hi, widened by the tolerance
 * (a superset for candidate searches). */
static int lattice_range_closed(double lo, double hi, double origin, double spacing,
                                int64_t *first, int64_t *last)
{
    double a = lattice_units(lo, origin, spacing), b = lattice_units(hi, origin, spacing);
    double ka = ceil(a - lattice_tolerance(a));
    double kb = floor(b + lattice_tolerance(b));
    if (!index_ok(ka) || !index_ok(kb))
        return -1;
    *first = (int64_t)ka;
    *last = (int64_t)kb;
    return 0;
}

/* -------------------------------------------------------------- regions -- */

static int region_polygonal(const sluice_region *region)
{
    return region->shape == SLUICE_REGION_POLYGON || region->shape == SLUICE_REGION_PRISM;
}

/* A polygon usable for filling: at least three vertices. */
static int region_polygon_ok(const sluice_region *region)
{
    return region->polygon && region->vertex_count >= 3;
}

/* POLYGON and PRISM are the same shape: a polygon in x-y, extruded over
 * [min[2], max[2]) in 3D (a POLYGON in 3D is read as a prism, a PRISM in 2D as
 * its polygon). Anything else than BOX/POLYGON/PRISM is an empty region. */
void sluice_region_bounds(const sluice_region *region, uint32_t dimensions, sluice_real min[3],
                          sluice_real max[3])
{
    for (int d = 0; d < 3; d++)
        min[d] = max[d] = 0;
    if (!region || (dimensions != 2 && dimensions != 3))
        return;
    if (region->shape == SLUICE_REGION_BOX) {
        for (uint32_t d = 0; d < dimensions; d++) {
            min[d] = region->min[d];
            max[d] = region->max[d];
        }
    } else if (region_polygonal(region)) {
        if (region->polygon && region->vertex_count > 0) {
            min[0] = max[0] = region->polygon[0];
            min[1] = max[1] = region->polygon[1];
            for (uint32_t v = 1; v < region->vertex_count; v++)
                for (int d = 0; d < 2; d++) {
                    sluice_real c = region->polygon[2 * v + (uint32_t)d];
                    if (c < min[d])
                        min[d] = c;
                    if (c > max[d])
                        max[d] = c;
                }
        }
        if (dimensions == 3) {
            min[2] = region->min[2];
            max[2] = region->max[2];
        }
    }
}

int sluice_region_contains(const sluice_region *region, uint32_t dimensions, const sluice_real p[3])
{
    if (!region || !p || (dimensions != 2 && dimensions != 3))
        return 0;
    if (region->shape == SLUICE_REGION_BOX) {
        for (uint32_t d = 0; d < dimensions; d++)
            if (!(region->min[d] <= p[d] && p[d] < region->max[d]))
                return 0;
        return 1;
    }
    if (!region_polygonal(region))
        return 0;
    if (dimensions == 3 && !(region->min[2] <= p[2] && p[2] < region->max[2]))
        return 0;
    return sluice_point_in_polygon(region->polygon, region->vertex_count, p[0], p[1]);
}

/* Crossing-number test with a ray towards +x (W. R. Franklin's PNPOLY).
 * For an axis-aligned rectangle it is exactly the half-open rule
 * min <= x < max, min <= y < max. */
int sluice_point_in_polygon(const sluice_real *polygon, uint32_t n, sluice_real x, sluice_real y)
{
    if (!polygon || n < 3)
        return 0;
    int inside = 0;
    double px = (double)x, py = (double)y;
    for (uint32_t i = 0, j = n - 1; i < n; j = i++) {
        double xi = (double)polygon[2 * i], yi = (double)polygon[2 * i + 1];
        double xj = (double)polygon[2 * j], yj = (double)polygon[2 * j + 1];
        if ((yi > py) != (yj > py)) {
            double crossing = xi + (xj - xi) * (py - yi) / (yj - yi);
            if (px < crossing)
                inside = !inside;
        }
    }
    return inside;
}

/* Orientation of c against the line a -> b: +1 left, -1 right, 0 on it. */
static int orientation(const sluice_real *a, const sluice_real *b, const sluice_real *c)
{
    double v = ((double)b[0] - (double)a[0]) * ((double)c[1] - (double)a[1]) -
               ((double)b[1] - (double)a[1]) * ((double)c[0] - (double)a[0]);
    return (v > 0) - (v < 0);
}

int sluice_polygon_crossing(const sluice_real *polygon, uint32_t n, uint32_t *edge_a,
                            uint32_t *edge_b)
{
    if (!polygon || n < 4)
        return 0;
    for (uint32_t i = 0; i < n; i++) {
        const sluice_real *p1 = polygon + 2 * i, *p2 = polygon + 2 * ((i + 1) % n);
        for (uint32_t j = i + 2; j < n; j++) {
            if (i == 0 && j == n - 1)
                continue; /* the closing edge meets the first at vertex 0 */
            const sluice_real *q1 = polygon + 2 * j, *q2 = polygon + 2 * ((j + 1) % n);
            const int o1 = orientation(p1, p2, q1), o2 = orientation(p1, p2, q2);
            const int o3 = orientation(q1, q2, p1), o4 = orientation(q1, q2, p2);
            if (o1 * o2 < 0 && o3 * o4 < 0) {
                *edge_a = i;
                *edge_b = j;
                return 1;
            }
        }
    }
    return 0;
}

/* Boxes take the lattice index range directly (half-open with the lattice
 * tolerance, so boundaries on lattice points behave exactly). Polygons and
 * prisms test every candidate of the bounding box with
 * sluice_point_in_polygon on the very coordinates that are appended, so every
 * filled point satisfies sluice_region_contains (the prism's z range uses the
 * box rule). Points are appended z-major, then y, then x. */
int sluice_region_fill(const sluice_region *region, uint32_t dimensions, sluice_real spacing,
                       const sluice_real lattice_origin[3], sluice_points *out)
{
    if (!region || !out || (dimensions != 2 && dimensions != 3))
        return -1;
    double dx = (double)spacing;
    if (!(dx > 0) || !isfinite(dx))
        return -1;
    double origin[3] = {0, 0, 0};
    if (lattice_origin)
        load3(origin, lattice_origin);
    int64_t first[3] = {0, 0, 0}, last[3] = {0, 0, 0};
    int polygonal = region_polygonal(region);
    if (region->shape == SLUICE_REGION_BOX) {
        for (uint32_t d = 0; d < dimensions; d++)
            if (lattice_range_half_open((double)region->min[d], (double)region->max[d], origin[d],
                                        dx, &first[d], &last[d]) != 0)
                return -1;
    } else if (polygonal) {
        if (!region_polygon_ok(region))
            return 0;
        sluice_real lo[3], hi[3];
        sluice_region_bounds(region, dimensions, lo, hi);
        for (int d = 0; d < 2; d++) {
            if (lattice_range_closed((double)lo[d], (double)hi[d], origin[d], dx, &first[d],
                                     &last[d]) != 0)
                return -1;
            first[d]--; /* PNPOLY decides at the boundary itself */
            last[d]++;
        }
        if (dimensions == 3 && lattice_range_half_open((double)region->min[2],
                                                       (double)region->max[2], origin[2], dx,
                                                       &first[2], &last[2]) != 0)
            return -1;
    } else {
        return 0;
    }
    double candidates = 1;
    for (uint32_t d = 0; d < dimensions; d++) {
        if (last[d] < first[d])
            return 0;
        candidates *= (double)(last[d] - first[d]) + 1.0;
    }
    if (!(candidates < (double)(SIZE_MAX / (3 * sizeof(sluice_real)))))
        return -1;
    if (!polygonal && points_reserve(out, (size_t)candidates) != 0)
        return -1;
    for (int64_t k2 = first[2]; k2 <= last[2]; k2++) {
        for (int64_t k1 = first[1]; k1 <= last[1]; k1++) {
            for (int64_t k0 = first[0]; k0 <= last[0]; k0++) {
                sluice_real p[3];
                p[0] = (sluice_real)lattice_coordinate(origin[0], k0, dx);
                p[1] = (sluice_real)lattice_coordinate(origin[1], k1, dx);
                p[2] = dimensions == 3 ? (sluice_real)lattice_coordinate(origin[2], k2, dx) : 0;
                if (polygonal &&
                    !sluice_point_in_polygon(region->polygon, region->vertex_count, p[0], p[1]))
                    continue;
                if (sluice_points_push(out, p) != 0)
                    return -1;
            }
        }
    }
    return 0;
}

/* ---------------------------------------------------------------- walls -- */

static void wall_reset(sluice_wall_geometry *wall)
{
    *wall = (sluice_wall_geometry){0};
}

void sluice_wall_geometry_free(sluice_wall_geometry *wall)
{
    if (!wall)
        return;
    free(wall->points);
    free(wall->normals);
    free(wall->vertex_normals);
    free(wall->open_vertex);
    free(wall->edge_normals);
    free(wall->open_edge);
    wall_reset(wall);
}

/* Zeroed arrays for `count` elements; -1 (wall reset) on OOM. */
static int wall_allocate(sluice_wall_geometry *wall, uint32_t dimensions, uint32_t count)
{
    size_t corners = dimensions == 2 ? 2 : 3;
    wall_reset(wall);
    wall->points = calloc((size_t)count * corners * 3, sizeof(sluice_real));
    wall->normals = calloc((size_t)count * 3, sizeof(sluice_real));
    wall->vertex_normals = calloc((size_t)count * corners * 3, sizeof(sluice_real));
    wall->open_vertex = calloc((size_t)count * corners, 1);
    int ok = wall->points && wall->normals && wall->vertex_normals && wall->open_vertex;
    if (dimensions == 3) {
        wall->edge_normals = calloc((size_t)count * 9, sizeof(sluice_real));
        wall->open_edge = calloc((size_t)count * 3, 1);
        ok = ok && wall->edge_normals && wall->open_edge;
    }
    if (!ok) {
        sluice_wall_geometry_free(wall);
        return -1;
    }
    wall->dimensions = dimensions;
    wall->element_count = count;
    return 0;
}

static int wall_fail(sluice_wall_geometry *wall, const char **reason, const char *why)
{
    sluice_wall_geometry_free(wall);
    *reason = why;
    return -1;
}

/* Pseudo-normal at a vertex shared by two segments with unit normals n0, n1:
 * their normalised sum. When the two cancel (the polyline folds back on
 * itself), the direction out of the tip, `tip`, is used. */
static void segment_vertex_normal(double out[3], const double n0[3], const double n1[3],
                                  const double tip[3])
{
    double s[3] = {n0[0] + n1[0], n0[1] + n1[1], n0[2] + n1[2]};
    if (normalise3(s) > 1e-12) {
        memcpy(out, s, sizeof s);
    } else {
        memcpy(out, tip, 3 * sizeof *out);
    }
}

int sluice_wall_build_polyline(sluice_wall_geometry *wall, const sluice_real *xy, uint32_t n,
                               int closed, const char **reason)
{
    const char *ignored;
    if (!reason)
        reason = &ignored;
    *reason = NULL;
    if (!wall) {
        *reason = "no wall to build";
        return -1;
    }
    wall_reset(wall);
    if (!xy || n < 2)
        return wall_fail(wall, reason, "a wall polyline needs at least 2 vertices");
    if (closed && n < 3)
        return wall_fail(wall, reason, "a closed wall polyline needs at least 3 vertices");
    for (uint32_t v = 0; v < 2 * n; v++)
        if (!isfinite((double)xy[v]))
            return wall_fail(wall, reason, "a wall vertex has a non-finite coordinate");
    uint32_t segments = closed ? n : n - 1;
    for (uint32_t s = 0; s < segments; s++) {
        uint32_t a = s, b = (s + 1) % n;
        double length = hypot((double)xy[2 * b] - (double)xy[2 * a],
                              (double)xy[2 * b + 1] - (double)xy[2 * a + 1]);
        if (!(length > 0))
            return wall_fail(wall, reason,
                             "zero-length wall segment (two consecutive vertices coincide)");
        if (!isfinite(length))
            return wall_fail(wall, reason, "a wall segment is too long to represent");
    }
    if (wall_allocate(wall, 2, segments) != 0)
        return wall_fail(wall, reason, "out of memory");
    /* points, normals, and unit tangents (a -> b) */
    for (uint32_t s = 0; s < segments; s++) {
        uint32_t a = s, b = (s + 1) % n;
        sluice_real *pa = wall->points + 6 * s, *pb = pa + 3;
        pa[0] = xy[2 * a];
        pa[1] = xy[2 * a + 1];
        pa[2] = 0;
        pb[0] = xy[2 * b];
        pb[1] = xy[2 * b + 1];
        pb[2] = 0;
        double tx = (double)pb[0] - (double)pa[0], ty = (double)pb[1] - (double)pa[1];
        double length = hypot(tx, ty);
        double normal[3] = {-ty / length, tx / length, 0};
        store3(wall->normals + 3 * s, normal);
    }
    for (uint32_t s = 0; s < segments; s++) {
        double own[3], tip[3], other[3], pseudo[3];
        load3(own, wall->normals + 3 * s);
        double pa[3], pb[3];
        load3(pa, wall->points + 6 * s);
        load3(pb, wall->points + 6 * s + 3);
        for (int end = 0; end < 2; end++) {
            /* the neighbouring segment at this end, if any */
            int has_other = end == 0 ? (s > 0 || closed) : (s + 1 < segments || closed);
            size_t slot = 2 * (size_t)s + (size_t)end;
            if (!has_other) {
                store3(wall->vertex_normals + 3 * slot, own);
                wall->open_vertex[slot] = 1;
                continue;
            }
            uint32_t o = end == 0 ? (s + segments - 1) % segments : (s + 1) % segments;
            load3(other, wall->normals + 3 * o);
            if (end == 0)
                sub3(tip, pa, pb);
            else
                sub3(tip, pb, pa);
            normalise3(tip);
            segment_vertex_normal(pseudo, own, other, tip);
            store3(wall->vertex_normals + 3 * slot, pseudo);
        }
    }
    return 0;
}

/* One directed edge of a triangle, for finding the triangles sharing it. */
typedef struct edge_ref {
    uint32_t lo, hi; /* vertex indices, lo < hi */
    uint32_t face;
    uint8_t local;   /* 0 ab, 1 bc, 2 ca */
    uint8_t forward; /* the face runs lo -> hi */
} edge_ref;

static int edge_ref_compare(const void *pa, const void *pb)
{
    const edge_ref *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    if (a->face != b->face)
        return a->face < b->face ? -1 : 1;
    return (a->local > b->local) - (a->local < b->local);
}

/* Pseudo-normals after J. A. Baerentzen and H. Aanaes, "Signed distance
 * computation using the angle weighted pseudonormal", IEEE TVCG 11 (2005):
 * vertex = angle-weighted sum of the incident face normals, edge = sum of the
 * two adjacent face normals, both normalised. Vertices and edges are shared
 * by index. An edge of one triangle only is open (its pseudo-normal is the face
 * normal); its vertices are open ends. Edges of more than two triangles, or two
 * triangles running along a shared edge in the same direction (inconsistent
 * orientation), are refused: the sign of the distance would be meaningless. */
int sluice_wall_build_triangles(sluice_wall_geometry *wall, const sluice_real *vertices,
                                uint32_t vertex_count, const uint32_t *faces,
                                uint32_t face_count, const char **reason)
{
    const char *ignored;
    if (!reason)
        reason = &ignored;
    *reason = NULL;
    if (!wall) {
        *reason = "no wall to build";
        return -1;
    }
    wall_reset(wall);
    if (!vertices || !faces || face_count == 0)
        return wall_fail(wall, reason, "a triangulated wall needs at least one triangle");
    if (face_count > UINT32_MAX / 3)
        return wall_fail(wall, reason, "too many triangles");
    for (uint32_t f = 0; f < face_count; f++) {
        const uint32_t *t = faces + 3 * (size_t)f;
        for (int j = 0; j < 3; j++) {
            if (t[j] >= vertex_count)
                return wall_fail(wall, reason, "a triangle refers to a vertex index out of range");
            if (!finite3(vertices + 3 * (size_t)t[j]))
                return wall_fail(wall, reason, "a wall vertex has a non-finite coordinate");
        }
        if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
            return wall_fail(wall, reason, "degenerate triangle (a vertex index is repeated)");
        double a[3], b[3], c[3], ab[3], ac[3], n[3];
        load3(a, vertices + 3 * (size_t)t[0]);
        load3(b, vertices + 3 * (size_t)t[1]);
        load3(c, vertices + 3 * (size_t)t[2]);
        sub3(ab, b, a);
        sub3(ac, c, a);
        cross3(n, ab, ac);
        double area2 = norm3(n);
        if (!(area2 > 1e-12 * norm3(ab) * norm3(ac)) || !isfinite(area2))
            return wall_fail(wall, reason, "degenerate triangle (zero area)");
    }
    if (wall_allocate(wall, 3, face_count) != 0)
        return wall_fail(wall, reason, "out of memory");
    double *accumulated = calloc((size_t)vertex_count * 3, sizeof *accumulated);
    uint8_t *vertex_open = calloc(vertex_count ? vertex_count : 1, 1);
    edge_ref *edges = malloc((size_t)face_count * 3 * sizeof *edges);
    if (!accumulated || !vertex_open || !edges) {
        free(accumulated);
        free(vertex_open);
        free(edges);
        return wall_fail(wall, reason, "out of memory");
    }
    /* points, face normals, angle-weighted vertex sums, edge list */
    for (uint32_t f = 0; f < face_count; f++) {
        const uint32_t *t = faces + 3 * (size_t)f;
        double v[3][3], n[3];
        for (int j = 0; j < 3; j++) {
            load3(v[j], vertices + 3 * (size_t)t[j]);
            memcpy(wall->points + 9 * (size_t)f + 3 * (size_t)j, vertices + 3 * (size_t)t[j],
                   3 * sizeof(sluice_real));
        }
        double ab[3], ac[3];
        sub3(ab, v[1], v[0]);
        sub3(ac, v[2], v[0]);
        cross3(n, ab, ac);
        normalise3(n);
        store3(wall->normals + 3 * (size_t)f, n);
        for (int j = 0; j < 3; j++) {
            double e1[3], e2[3], c[3];
            sub3(e1, v[(j + 1) % 3], v[j]);
            sub3(e2, v[(j + 2) % 3], v[j]);
            cross3(c, e1, e2);
            double angle = atan2(norm3(c), dot3(e1, e2));
            double *acc = accumulated + 3 * (size_t)t[j];
            for (int d = 0; d < 3; d++)
                acc[d] += angle * n[d];
            uint32_t p = t[j], q = t[(j + 1) % 3];
            edge_ref *e = &edges[3 * (size_t)f + (size_t)j];
            e->lo = p < q ? p : q;
            e->hi = p < q ? q : p;
            e->face = f;
            e->local = (uint8_t)j;
            e->forward = p < q;
        }
    }
    size_t edge_count = 3 * (size_t)face_count;
    qsort(edges, edge_count, sizeof *edges, edge_ref_compare);
    const char *problem = NULL;
    for (size_t i = 0; i < edge_count && !problem;) {
        size_t j = i + 1;
        while (j < edge_count && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi)
            j++;
        const edge_ref *e0 = &edges[i];
        size_t slot0 = 3 * (size_t)e0->face + e0->local;
        if (j - i == 1) {
            memcpy(wall->edge_normals + 3 * slot0, wall->normals + 3 * (size_t)e0->face,
                   3 * sizeof(sluice_real));
            wall->open_edge[slot0] = 1;
            vertex_open[e0->lo] = vertex_open[e0->hi] = 1;
        } else if (j - i == 2) {
            const edge_ref *e1 = &edges[i + 1];
            if (e0->forward == e1->forward) {
                problem = "two triangles sharing an edge have opposite orientations";
                break;
            }
            size_t slot1 = 3 * (size_t)e1->face + e1->local;
            double n0[3], n1[3], s[3];
            load3(n0, wall->normals + 3 * (size_t)e0->face);
            load3(n1, wall->normals + 3 * (size_t)e1->face);
            for (int d = 0; d < 3; d++)
                s[d] = n0[d] + n1[d];
            if (normalise3(s) > 1e-12) {
                store3(wall->edge_normals + 3 * slot0, s);
                store3(wall->edge_normals + 3 * slot1, s);
            } else { /* a zero-thickness fin: each side keeps its own normal */
                store3(wall->edge_normals + 3 * slot0, n0);
                store3(wall->edge_normals + 3 * slot1, n1);
            }
        } else {
            problem = "an edge is shared by more than two triangles";
        }
        i = j;
    }
    if (!problem) {
        for (uint32_t f = 0; f < face_count; f++) {
            const uint32_t *t = faces + 3 * (size_t)f;
            for (int j = 0; j < 3; j++) {
                double s[3];
                memcpy(s, accumulated + 3 * (size_t)t[j], sizeof s);
                size_t slot = 3 * (size_t)f + (size_t)j;
                if (normalise3(s) > 1e-12)
                    store3(wall->vertex_normals + 3 * slot, s);
                else
                    memcpy(wall->vertex_normals + 3 * slot, wall->normals + 3 * (size_t)f,
                           3 * sizeof(sluice_real));
                wall->open_vertex[slot] = vertex_open[t[j]];
            }
        }
    }
    free(accumulated);
    free(vertex_open);
    free(edges);
    if (problem)
        return wall_fail(wall, reason, problem);
    return 0;
}

static int box_check(uint32_t dimensions, const sluice_real min[3], const sluice_real max[3],
                     const char **reason)
{
    if (dimensions != 2 && dimensions != 3) {
        *reason = "dimensions must be 2 or 3";
        return -1;
    }
    if (!min || !max) {
        *reason = "the box has no bounds";
        return -1;
    }
    for (uint32_t d = 0; d < dimensions; d++) {
        if (!isfinite((double)min[d]) || !isfinite((double)max[d])) {
            *reason = "the box has a non-finite bound";
            return -1;
        }
        if (!(max[d] > min[d])) {
            *reason = "the box needs max > min along every axis";
            return -1;
        }
    }
    return 0;
}

/* The faces of the box with corners i = x + 2 y + 4 z (bit set: max side),
 * each as a cycle of four corners. The first is the top (z = max). */
static const uint32_t box_quads[6][4] = {
    {4, 5, 7, 6}, /* z max */
    {0, 1, 3, 2}, /* z min */
    {0, 1, 5, 4}, /* y min */
    {2, 3, 7, 6}, /* y max */
    {0, 2, 6, 4}, /* x min */
    {1, 3, 7, 5}, /* x max */
};

/* 3D box faces as triangles sharing the 8 corner indices; normals point into
 * the box when `inward`, out of it otherwise. The top face is left out for an
 * open tank. */
static int build_box_3d(sluice_wall_geometry *wall, const sluice_real min[3],
                        const sluice_real max[3], int inward, int with_top, int with_ends,
                        const char **reason)
{
    sluice_real corners[8 * 3];
    double centre[3];
    for (int d = 0; d < 3; d++)
        centre[d] = 0.5 * ((double)min[d] + (double)max[d]);
    for (uint32_t i = 0; i < 8; i++)
        for (uint32_t d = 0; d < 3; d++)
            corners[3 * i + d] = (i >> d) & 1u ? max[d] : min[d];
    uint32_t faces[12 * 3];
    uint32_t count = 0;
    for (int q = with_top ? 0 : 1; q < 6; q++) {
        uint32_t c[4];
        memcpy(c, box_quads[q], sizeof c);
        /* the ends across x: the four corners share their x (bit 0) */
        const uint32_t x_bits = (c[0] & 1u) + (c[1] & 1u) + (c[2] & 1u) + (c[3] & 1u);
        if (!with_ends && (x_bits == 0 || x_bits == 4))
            continue;
        double v0[3], v1[3], v2[3], e1[3], e2[3], n[3], to_centre[3];
        load3(v0, corners + 3 * c[0]);
        load3(v1, corners + 3 * c[1]);
        load3(v2, corners + 3 * c[2]);
        sub3(e1, v1, v0);
        sub3(e2, v2, v0);
        cross3(n, e1, e2);
        sub3(to_centre, centre, v0);
        int points_in = dot3(n, to_centre) > 0;
        if (points_in != inward) { /* reverse the cycle */
            uint32_t swap = c[1];
            c[1] = c[3];
            c[3] = swap;
        }
        uint32_t *t = faces + 3 * count;
        t[0] = c[0], t[1] = c[1], t[2] = c[2];
        t[3] = c[0], t[4] = c[2], t[5] = c[3];
        count += 2;
    }
    return sluice_wall_build_triangles(wall, corners, 8, faces, count, reason);
}

/* Common start of the box-shaped builders: resets the wall and checks the box.
 * Returns 0 when building may go on. */
static int begin_box_wall(sluice_wall_geometry *wall, uint32_t dimensions,
                          const sluice_real min[3], const sluice_real max[3], const char **reason)
{
    *reason = NULL;
    if (!wall) {
        *reason = "no wall to build";
        return -1;
    }
    wall_reset(wall);
    return box_check(dimensions, min, max, reason);
}

int sluice_wall_build_tank(sluice_wall_geometry *wall, uint32_t dimensions,
                           const sluice_real min[3], const sluice_real max[3],
                           const char **reason)
{
    const char *ignored;
    if (!reason)
        reason = &ignored;
    if (begin_box_wall(wall, dimensions, min, max, reason) != 0)
        return -1;
    if (dimensions == 2) {
        /* down the left side, along the bottom, up the right side: the fluid
         * (inside) is on the left of every segment */
        const sluice_real xy[8] = {min[0], max[1], min[0], min[1],
                                   max[0], min[1], max[0], max[1]};
        return sluice_wall_build_polyline(wall, xy, 4, 0, reason);
    }
    return build_box_3d(wall, min, max, 1, 0, 1, reason);
}

int sluice_wall_build_channel(sluice_wall_geometry *wall, uint32_t dimensions,
                              const sluice_real min[3], const sluice_real max[3],
                              const char **reason)
{
    const char *ignored;
    if (!reason)
        reason = &ignored;
    if (begin_box_wall(wall, dimensions, min, max, reason) != 0)
        return -1;
    if (dimensions == 2) { /* the bed, the fluid above it */
        const sluice_real xy[4] = {min[0], min[1], max[0], min[1]};
        return sluice_wall_build_polyline(wall, xy, 2, 0, reason);
    }
    return build_box_3d(wall, min, max, 1, 0, 0, reason);
}

int sluice_wall_build_box(sluice_wall_geometry *wall, uint32_t dimensions,
                          const sluice_real min[3], const sluice_real max[3],
                          const char **reason)
{
    const char *ignored;
    if (!reason)
        reason = &ignored;
    if (begin_box_wall(wall, dimensions, min, max, reason) != 0)
        return -1;
    if (dimensions == 2) {
        /* clockwise: the fluid (outside) is on the left of every segment */
        const sluice_real xy[8] = {min[0], min[1], min[0], max[1],
                                   max[0], max[1], max[0], min[1]};
        return sluice_wall_build_polyline(wall, xy, 4, 1, reason);
    }
    return build_box_3d(wall, min, max, 0, 1, 1, reason);
}

/* ------------------------------------------------------ closest points -- */

sluice_real sluice_segment_closest(const sluice_real p[3], const sluice_real a[3],
                                   const sluice_real b[3], sluice_real closest[3], int *feature)
{
    double P[3], A[3], B[3], ab[3], ap[3], c[3];
    load3(P, p);
    load3(A, a);
    load3(B, b);
    sub3(ab, B, A);
    sub3(ap, P, A);
    double length2 = dot3(ab, ab);
    double t = length2 > 0 ? dot3(ap, ab) / length2 : 0;
    int f;
    if (t <= 0) {
        memcpy(c, A, sizeof c);
        f = 1;
    } else if (t >= 1) {
        memcpy(c, B, sizeof c);
        f = 2;
    } else {
        for (int d = 0; d < 3; d++)
            c[d] = A[d] + t * ab[d];
        f = 0;
    }
    if (closest)
        store3(closest, c);
    if (feature)
        *feature = f;
    return (sluice_real)distance3(P, c);
}

/* A degenerate (zero-area) triangle: the closest of its three edges. */
static sluice_real degenerate_triangle_closest(const sluice_real p[3], const sluice_real *v[3],
                                               sluice_real closest[3], int *feature)
{
    /* segment features 0 interior, 1 start, 2 end -> triangle features */
    static const int map[3][3] = {{4, 1, 2}, {5, 2, 3}, {6, 3, 1}};
    sluice_real best = 0, c[3];
    int best_feature = 0;
    for (int e = 0; e < 3; e++) {
        int f;
        sluice_real d = sluice_segment_closest(p, v[e], v[(e + 1) % 3], c, &f);
        if (e == 0 || d < best) {
            best = d;
            best_feature = map[e][f];
            memcpy(closest, c, sizeof c);
        }
    }
    *feature = best_feature;
    return best;
}

/* C. Ericson, Real-Time Collision Detection (2005), 5.1.5: finds the Voronoi
 * region of p among the vertices, edges and face of a non-degenerate triangle;
 * writes the closest point and returns the feature. */
static int triangle_region(const double P[3], const double A[3], const double B[3],
                           const double C[3], double out[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3];
    sub3(ab, B, A);
    sub3(ac, C, A);
    sub3(ap, P, A);
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) {
        memcpy(out, A, 3 * sizeof *out);
        return 1;
    }
    sub3(bp, P, B);
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) {
        memcpy(out, B, 3 * sizeof *out);
        return 2;
    }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        for (int d = 0; d < 3; d++)
            out[d] = A[d] + v * ab[d];
        return 4;
    }
    sub3(cp, P, C);
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6) {
        memcpy(out, C, 3 * sizeof *out);
        return 3;
    }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        for (int d = 0; d < 3; d++)
            out[d] = A[d] + w * ac[d];
        return 6;
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int d = 0; d < 3; d++)
            out[d] = B[d] + w * (C[d] - B[d]);
        return 5;
    }
    double denominator = 1.0 / (va + vb + vc);
    double v = vb * denominator, w = vc * denominator;
    for (int d = 0; d < 3; d++)
        out[d] = A[d] + ab[d] * v + ac[d] * w;
    return 0;
}

sluice_real sluice_triangle_closest(const sluice_real p[3], const sluice_real a[3],
                                    const sluice_real b[3], const sluice_real c[3],
                                    sluice_real closest[3], int *feature)
{
    sluice_real closest_buffer[3];
    int feature_buffer;
    if (!closest)
        closest = closest_buffer;
    if (!feature)
        feature = &feature_buffer;
    double P[3], A[3], B[3], C[3], ab[3], ac[3], n[3], out[3];
    load3(P, p);
    load3(A, a);
    load3(B, b);
    load3(C, c);
    sub3(ab, B, A);
    sub3(ac, C, A);
    cross3(n, ab, ac);
    if (!(dot3(n, n) > 1e-24 * dot3(ab, ab) * dot3(ac, ac))) {
        const sluice_real *v[3] = {a, b, c};
        return degenerate_triangle_closest(p, v, closest, feature);
    }
    *feature = triangle_region(P, A, B, C, out);
    store3(closest, out);
    return (sluice_real)distance3(P, out);
}

/* ------------------------------------------------------ signed distance -- */

static size_t wall_corners(const sluice_wall_geometry *wall)
{
    return wall->dimensions == 2 ? 2 : 3;
}

static double element_closest(const sluice_wall_geometry *wall, uint32_t e, const sluice_real p[3],
                              sluice_real closest[3], int *feature)
{
    const sluice_real *a = wall->points + 3 * wall_corners(wall) * (size_t)e;
    if (wall->dimensions == 2)
        return (double)sluice_segment_closest(p, a, a + 3, closest, feature);
    return (double)sluice_triangle_closest(p, a, a + 3, a + 6, closest, feature);
}

/* The pseudo-normal of feature f of element e. */
static const sluice_real *feature_normal(const sluice_wall_geometry *wall, uint32_t e, int f)
{
    size_t corners = wall_corners(wall);
    if (f == 0)
        return wall->normals + 3 * (size_t)e;
    if (f <= (int)corners)
        return wall->vertex_normals + 3 * (corners * (size_t)e + (size_t)(f - 1));
    return wall->edge_normals + 3 * (3 * (size_t)e + (size_t)(f - 4));
}

/* Is p (closest point c on edge `edge` of triangle e) past that edge, i.e.
 * does p project onto the triangle's plane strictly outside the triangle
 * across the edge? With m the unit in-plane direction perpendicular to the
 * edge and pointing away from the triangle: (p - c) . m > tol |edge|. */
static int past_triangle_edge(const sluice_wall_geometry *wall, uint32_t e, int edge,
                              const double p[3], const double c[3])
{
    const sluice_real *v = wall->points + 9 * (size_t)e;
    double P[3], Q[3], R[3], u[3], m[3], pc[3];
    load3(P, v + 3 * edge);
    load3(Q, v + 3 * ((edge + 1) % 3));
    load3(R, v + 3 * ((edge + 2) % 3));
    sub3(u, Q, P);
    double length = normalise3(u);
    sub3(m, P, R);
    double along = dot3(m, u);
    for (int d = 0; d < 3; d++)
        m[d] -= along * u[d];
    normalise3(m);
    sub3(pc, p, c);
    return dot3(pc, m) > BEYOND_TOLERANCE * length;
}

/* beyond_end for one element whose closest point to p is c (feature f).
 *  2D: the closest feature is an open vertex and p's projection parameter t
 *      on the segment is outside [0, 1] by more than the tolerance (1e-9):
 *      (p - c) . (a - b) / |a - b| > 1e-9 |a - b| at an open a, likewise at b.
 *  3D: the closest feature is an open edge, or a vertex on an open edge of
 *      this triangle, and p is past that edge (past_triangle_edge): the 3D
 *      form of the 2D rule. A vertex can be on open edges of other
 *      triangles; wall_query asks every triangle at the same closest point. */
static int element_beyond(const sluice_wall_geometry *wall, uint32_t e, int f, const double p[3],
                          const double c[3])
{
    if (f == 0)
        return 0;
    if (wall->dimensions == 2) {
        size_t slot = 2 * (size_t)e + (size_t)(f - 1);
        if (!wall->open_vertex[slot])
            return 0;
        const sluice_real *v = wall->points + 6 * (size_t)e;
        double end[3], other[3], out[3], pc[3];
        load3(end, v + 3 * (f - 1));
        load3(other, v + 3 * (2 - f));
        sub3(out, end, other);
        double length = normalise3(out);
        sub3(pc, p, c);
        return dot3(pc, out) > BEYOND_TOLERANCE * length;
    }
    if (f >= 4) {
        int edge = f - 4;
        return wall->open_edge[3 * (size_t)e + (size_t)edge] &&
               past_triangle_edge(wall, e, edge, p, c);
    }
    int vertex = f - 1;
    if (!wall->open_vertex[3 * (size_t)e + (size_t)vertex])
        return 0;
    /* the two edges of this triangle at the vertex: vertex -> vertex + 1, and
     * vertex + 2 -> vertex */
    int edges[2] = {vertex, (vertex + 2) % 3};
    for (int k = 0; k < 2; k++)
        if (wall->open_edge[3 * (size_t)e + (size_t)edges[k]] &&
            past_triangle_edge(wall, e, edges[k], p, c))
            return 1;
    return 0;
}

/* Does element e's bounding box come within tol of c? */
static int element_near(const sluice_wall_geometry *wall, uint32_t e, const double c[3], double tol)
{
    size_t corners = wall_corners(wall);
    const sluice_real *v = wall->points + 3 * corners * (size_t)e;
    for (int d = 0; d < 3; d++) {
        double lo = (double)v[d], hi = lo;
        for (size_t j = 1; j < corners; j++) {
            double x = (double)v[3 * j + (size_t)d];
            lo = fmin(lo, x);
            hi = fmax(hi, x);
        }
        if (c[d] < lo - tol || c[d] > hi + tol)
            return 0;
    }
    return 1;
}

/* Signed distance over the elements `subset` (n of them; all elements when
 * subset is NULL). The closest element is the first one at the smallest
 * distance. Sign: (p - c) . n_f >= 0 -> positive (a point exactly on the
 * wall gets 0). beyond_end: any element whose own closest point is c (within a
 * rounding tolerance) finds p beyond an open end (element_beyond); this
 * covers every triangle at an open vertex, whichever reported the minimum. */
static double wall_query(const sluice_wall_geometry *wall, const sluice_real p[3],
                         const uint32_t *subset, size_t n, int *beyond_end, uint32_t *element,
                         sluice_real closest_out[3], int *feature_out)
{
    double best = HUGE_VAL;
    uint32_t best_element = UINT32_MAX;
    int best_feature = 0;
    sluice_real best_closest[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        uint32_t e = subset ? subset[i] : (uint32_t)i;
        sluice_real c[3];
        int f;
        double d = element_closest(wall, e, p, c, &f);
        if (d < best) {
            best = d;
            best_element = e;
            best_feature = f;
            memcpy(best_closest, c, sizeof c);
        }
    }
    if (beyond_end)
        *beyond_end = 0;
    if (element)
        *element = best_element;
    if (closest_out)
        memcpy(closest_out, best_closest, sizeof best_closest);
    if (feature_out)
        *feature_out = best_feature;
    if (best_element == UINT32_MAX)
        return HUGE_VAL;
    double P[3], C[3], pc[3], nf[3];
    load3(P, p);
    load3(C, best_closest);
    sub3(pc, P, C);
    load3(nf, feature_normal(wall, best_element, best_feature));
    double sign = dot3(pc, nf) >= 0 ? 1.0 : -1.0;
    if (beyond_end && best_feature != 0) {
        const sluice_real *v = wall->points + 3 * wall_corners(wall) * (size_t)best_element;
        double v0[3], v1[3];
        load3(v0, v);
        load3(v1, v + 3);
        double scale = fabs(P[0]) + fabs(P[1]) + fabs(P[2]) + best + distance3(v0, v1);
        double tol = 1e-9 * scale;
        for (size_t i = 0; i < n && !*beyond_end; i++) {
            uint32_t e = subset ? subset[i] : (uint32_t)i;
            if (!element_near(wall, e, C, tol))
                continue;
            sluice_real c[3];
            int f;
            element_closest(wall, e, p, c, &f);
            double ce[3];
            load3(ce, c);
            if (distance3(ce, C) <= tol && element_beyond(wall, e, f, P, ce))
                *beyond_end = 1;
        }
    }
    return best > 0 ? sign * best : 0.0;
}

sluice_real sluice_wall_signed_distance(const sluice_wall_geometry *wall, const sluice_real p[3],
                                        int *beyond_end, uint32_t *element)
{
    if (!wall || !p || (wall->dimensions != 2 && wall->dimensions != 3)) {
        if (beyond_end)
            *beyond_end = 0;
        if (element)
            *element = UINT32_MAX;
        return (sluice_real)HUGE_VAL;
    }
    return (sluice_real)wall_query(wall, p, NULL, wall->element_count, beyond_end, element, NULL,
                                   NULL);
}

sluice_real sluice_wall_signed_distance_among(const sluice_wall_geometry *wall,
                                              const sluice_real p[3], const uint32_t *subset,
                                              size_t n, int *beyond_end, uint32_t *element)
{
    if (!wall || !p || !subset || (wall->dimensions != 2 && wall->dimensions != 3)) {
        if (beyond_end)
            *beyond_end = 0;
        if (element)
            *element = UINT32_MAX;
        return (sluice_real)HUGE_VAL;
    }
    return (sluice_real)wall_query(wall, p, subset, n, beyond_end, element, NULL, NULL);
}

sluice_real sluice_wall_element_distance(const sluice_wall_geometry *wall, uint32_t e,
                                         const sluice_real p[3])
{
    if (!wall || !p || e >= wall->element_count)
        return (sluice_real)HUGE_VAL;
    sluice_real c[3];
    int f;
    return (sluice_real)element_closest(wall, e, p, c, &f);
}

double sluice_walls_nearest_distance(const sluice_wall_geometry *const *walls, size_t wall_count,
                                     const sluice_real p[3])
{
    double best = HUGE_VAL;
    for (size_t w = 0; w < wall_count; w++)
        for (uint32_t e = 0; e < walls[w]->element_count; e++) {
            const double d = (double)sluice_wall_element_distance(walls[w], e, p);
            if (d < best)
                best = d;
        }
    return best;
}

uint32_t sluice_walls_elements_within(const sluice_wall_geometry *const *walls, size_t wall_count,
                                      const sluice_real p[3], double limit, uint32_t *wall_out,
                                      uint32_t *element_out)
{
    uint32_t count = 0;
    for (size_t w = 0; w < wall_count; w++)
        for (uint32_t e = 0; e < walls[w]->element_count; e++)
            if ((double)sluice_wall_element_distance(walls[w], e, p) <= limit) {
                if (wall_out) {
                    wall_out[count] = (uint32_t)w;
                    element_out[count] = e;
                }
                count++;
            }
    return count;
}

void sluice_wall_nearest(const sluice_wall_geometry *wall, const sluice_real p[3],
                         sluice_wall_point *out)
{
    memset(out, 0, sizeof *out);
    out->element = UINT32_MAX;
    out->distance = (sluice_real)HUGE_VAL;
    if (!wall || !p || (wall->dimensions != 2 && wall->dimensions != 3) ||
        wall->element_count == 0)
        return;
    int beyond = 0, feature = 0;
    uint32_t element = UINT32_MAX;
    sluice_real closest[3];
    double d = wall_query(wall, p, NULL, wall->element_count, &beyond, &element, closest, &feature);
    out->distance = (sluice_real)d;
    memcpy(out->closest, closest, sizeof closest);
    memcpy(out->normal, feature_normal(wall, element, feature), sizeof out->normal);
    out->element = element;
    out->feature = feature;
    out->beyond_end = beyond;
}

/* ----------------------------------------------------------- wall layers -- */

/* A lattice point near an element: its lattice index relative to the wall's
 * base index, packed into one key (x in the low bits, z in the high bits, so
 * that key order is z-major). */
typedef struct layer_record {
    uint64_t key;
    uint32_t element;
} layer_record;

typedef struct layer_records {
    layer_record *items;
    size_t count, capacity;
} layer_records;

static int layer_records_push(layer_records *r, uint64_t key, uint32_t element)
{
    if (r->count == r->capacity) {
        size_t limit = SIZE_MAX / sizeof *r->items;
        if (r->capacity >= limit)
            return -1;
        size_t capacity = r->capacity ? (r->capacity > limit / 2 ? limit : 2 * r->capacity) : 1024;
        layer_record *grown = realloc(r->items, capacity * sizeof *grown);
        if (!grown)
            return -1;
        r->items = grown;
        r->capacity = capacity;
    }
    r->items[r->count].key = key;
    r->items[r->count].element = element;
    r->count++;
    return 0;
}

/* Stable LSD radix sort of the records by the low `bits` bits of their keys,
 * 16 bits per pass. Stability keeps the records of one key in the order they
 * were pushed (ascending element). Returns -1 on OOM (records unchanged). */
static int layer_records_sort(layer_records *r, unsigned bits)
{
    if (r->count < 2 || bits == 0)
        return 0;
    enum { DIGITS = 1 << 16 };
    layer_record *spare = malloc(r->count * sizeof *spare);
    size_t *start = malloc((DIGITS + 1) * sizeof *start);
    if (!spare || !start) {
        free(spare);
        free(start);
        return -1;
    }
    layer_record *from = r->items, *to = spare;
    for (unsigned shift = 0; shift < bits; shift += 16) {
        memset(start, 0, (DIGITS + 1) * sizeof *start);
        for (size_t i = 0; i < r->count; i++)
            start[((from[i].key >> shift) & (DIGITS - 1)) + 1]++;
        for (size_t d = 1; d <= DIGITS; d++)
            start[d] += start[d - 1];
        for (size_t i = 0; i < r->count; i++)
            to[start[(from[i].key >> shift) & (DIGITS - 1)]++] = from[i];
        layer_record *swap = from;
        from = to;
        to = swap;
    }
    free(start);
    free(to); /* the buffer not holding the result */
    r->items = from;
    return 0;
}

/* Number of bits needed for the values 0..v. */
static unsigned bits_for(uint64_t v)
{
    unsigned bits = 0;
    while (v) {
        bits++;
        v >>= 1;
    }
    return bits;
}

/* Bounds of element e's corners. */
static void element_bounds(const sluice_wall_geometry *wall, uint32_t e, double lo[3], double hi[3])
{
    size_t corners = wall_corners(wall);
    const sluice_real *v = wall->points + 3 * corners * (size_t)e;
    for (int d = 0; d < 3; d++) {
        lo[d] = hi[d] = (double)v[d];
        for (size_t j = 1; j < corners; j++) {
            lo[d] = fmin(lo[d], (double)v[3 * j + (size_t)d]);
            hi[d] = fmax(hi[d], (double)v[3 * j + (size_t)d]);
        }
    }
}

/* Candidates: for every element, the lattice points of its bounding box
 * widened by the thickness that lie within the thickness (plus a margin) of
 * the element, recorded with the element. Sorting the records by lattice
 * index brings every point's records together (deduplication), and lists for
 * each point every element within reach of it. (A wall whose widened lattice
 * bounding box needs more than 64 bits of index, some 2^21 points per axis in
 * 3D, is refused with -1.) A point of the layer has
 * |signed distance| <= thickness, so its closest element, and any element
 * tied with it, is in that list: the signed distance over the list is the one
 * over the whole wall. The accepted points are those with
 * -thickness - tol <= signed distance <= tol (tol = 1e-9 spacing) and not
 * beyond an open end; they come out sorted z-major, then y, then x. The
 * distance is Euclidean, so a corner that is convex seen from behind the wall
 * (the outside of a tank's bottom corner) gets a rounded layer: a lattice
 * point diagonally off the corner is kept only when its distance to the
 * corner is within the thickness. */
int sluice_wall_layer_points(const sluice_wall_geometry *wall, sluice_real spacing,
                             const sluice_real lattice_origin[3], sluice_real thickness,
                             sluice_points *out)
{
    if (!wall || !out || (wall->dimensions != 2 && wall->dimensions != 3))
        return -1;
    double dx = (double)spacing, T = (double)thickness;
    if (!(dx > 0) || !isfinite(dx))
        return -1;
    if (wall->element_count == 0 || !(T >= 0) || !isfinite(T))
        return 0;
    uint32_t dims = wall->dimensions;
    double origin[3] = {0, 0, 0};
    if (lattice_origin)
        load3(origin, lattice_origin);
    double tol = 1e-9 * dx;
    double reach = T * (1 + 1e-6) + 4 * tol; /* records: a superset of the layer */

    /* base lattice index of the whole wall, widened by the reach */
    int64_t base[3] = {0, 0, 0}, top[3] = {0, 0, 0};
    double wlo[3], whi[3];
    element_bounds(wall, 0, wlo, whi);
    for (uint32_t e = 1; e < wall->element_count; e++) {
        double lo[3], hi[3];
        element_bounds(wall, e, lo, hi);
        for (int d = 0; d < 3; d++) {
            wlo[d] = fmin(wlo[d], lo[d]);
            whi[d] = fmax(whi[d], hi[d]);
        }
    }
    unsigned shift[3] = {0, 0, 0}, key_bits = 0;
    for (uint32_t d = 0; d < dims; d++) {
        if (lattice_range_closed(wlo[d] - reach, whi[d] + reach, origin[d], dx, &base[d],
                                 &top[d]) != 0)
            return -1;
        shift[d] = key_bits;
        key_bits += top[d] > base[d] ? bits_for((uint64_t)(top[d] - base[d])) : 0;
        if (key_bits > 64)
            return -1;
    }

    layer_records records = {0};
    for (uint32_t e = 0; e < wall->element_count; e++) {
        double lo[3], hi[3];
        element_bounds(wall, e, lo, hi);
        int64_t first[3] = {0, 0, 0}, last[3] = {0, 0, 0};
        int empty = 0;
        for (uint32_t d = 0; d < dims; d++) {
            if (lattice_range_closed(lo[d] - reach, hi[d] + reach, origin[d], dx, &first[d],
                                     &last[d]) != 0) {
                free(records.items);
                return -1;
            }
            empty |= last[d] < first[d];
        }
        if (empty)
            continue;
        double a[3], n[3];
        load3(a, wall->points + 3 * wall_corners(wall) * (size_t)e);
        load3(n, wall->normals + 3 * (size_t)e);
        for (int64_t k2 = first[2]; k2 <= last[2]; k2++) {
            for (int64_t k1 = first[1]; k1 <= last[1]; k1++) {
                for (int64_t k0 = first[0]; k0 <= last[0]; k0++) {
                    sluice_real p[3];
                    p[0] = (sluice_real)lattice_coordinate(origin[0], k0, dx);
                    p[1] = (sluice_real)lattice_coordinate(origin[1], k1, dx);
                    p[2] = dims == 3 ? (sluice_real)lattice_coordinate(origin[2], k2, dx) : 0;
                    if (dims == 3) { /* cheap rejection by the distance to the plane */
                        double P[3], ap[3];
                        load3(P, p);
                        sub3(ap, P, a);
                        if (fabs(dot3(ap, n)) > reach)
                            continue;
                    }
                    sluice_real c[3];
                    int f;
                    if (element_closest(wall, e, p, c, &f) > reach)
                        continue;
                    const int64_t k[3] = {k0, k1, k2};
                    uint64_t key = 0;
                    for (uint32_t d = 0; d < dims; d++)
                        if (shift[d] < 64) /* else the axis has one index: 0 */
                            key |= (uint64_t)(k[d] - base[d]) << shift[d];
                    if (layer_records_push(&records, key, e) != 0) {
                        free(records.items);
                        return -1;
                    }
                }
            }
        }
    }
    if (layer_records_sort(&records, key_bits) != 0) {
        free(records.items);
        return -1;
    }

    uint32_t *near = NULL;
    size_t near_capacity = 0;
    int rc = 0;
    for (size_t i = 0; i < records.count && rc == 0;) {
        size_t j = i + 1;
        uint64_t key = records.items[i].key;
        while (j < records.count && records.items[j].key == key)
            j++;
        if (j - i > near_capacity) {
            uint32_t *grown = realloc(near, (j - i) * sizeof *grown);
            if (!grown) {
                rc = -1;
                break;
            }
            near = grown;
            near_capacity = j - i;
        }
        for (size_t m = i; m < j; m++)
            near[m - i] = records.items[m].element;
        int64_t k[3];
        for (uint32_t d = 0; d < 3; d++) {
            k[d] = 0;
            if (d >= dims)
                continue;
            unsigned width = (d + 1 < dims ? shift[d + 1] : key_bits) - shift[d];
            uint64_t mask = width >= 64 ? UINT64_MAX : ((uint64_t)1 << width) - 1;
            k[d] = base[d] + (width ? (int64_t)((key >> shift[d]) & mask) : 0);
        }
        sluice_real p[3];
        p[0] = (sluice_real)lattice_coordinate(origin[0], k[0], dx);
        p[1] = (sluice_real)lattice_coordinate(origin[1], k[1], dx);
        p[2] = dims == 3 ? (sluice_real)lattice_coordinate(origin[2], k[2], dx) : 0;
        int beyond = 0;
        double sd = wall_query(wall, p, near, j - i, &beyond, NULL, NULL, NULL);
        if (!beyond && sd >= -T - tol && sd <= tol && sluice_points_push(out, p) != 0)
            rc = -1;
        i = j;
    }
    free(near);
    free(records.items);
    return rc;
}

/* ------------------------------------------------------------- profiles -- */

/* A profile is built piece by piece from the current point P and the
 * current heading h (a unit vector; unknown before the first piece unless
 * the profile has a `heading`). Each piece appends its vertices after P:
 *  - line: the end point E from the keys given (geometry.h), h = (E - P)/|E - P|;
 *  - arc: centre C = P + r s, s the unit normal on the side of the turn (left
 *    for turn > 0); vertex k of m is C + r R(turn k / m) (P - C)/r, R a
 *    rotation; h = R(turn) h. m = ceil(r |turn| / max_segment): every chord
 *    is shorter than its arc, r |turn| / m <= max_segment;
 *  - crest: from the apex P, x = P_x + u X, y = P_y - u a X^n (X in units of
 *    u metres, so that a is the coefficient of the crest's equation as
 *    published); the end X_e = (s_e / (a n))^(1 / (n - 1)) where the slope
 *    a n X^(n-1) reaches s_e, or X_e = end_x. The vertices are equally spaced
 *    in arc length, S(X) = u int_0^X sqrt(1 + (a n t^(n-1))^2) dt, m =
 *    ceil(S(X_e) / max_segment) segments (5-point Gauss-Legendre quadrature
 *    and Newton's method for S(X_k) = k S(X_e) / m); the last vertex is X_e
 *    itself; h = (1, -s_e) / |(1, -s_e)|, the tangent at the end;
 *  - steps: the corners P + (k l, -k h) computed from k directly (no
 *    accumulated round-off): riser then tread for each step, or tread then
 *    riser; h = +x (or -y when the flight ends with a riser).
 * Angles in degrees go through degrees_cos_sin, exact at multiples of 90
 * degrees, so that a vertical face or a quarter turn gives exact axes. */

#define PROFILE_PI 3.14159265358979323846

const char *sluice_piece_name(sluice_piece_kind kind)
{
    switch (kind) {
    case SLUICE_PIECE_LINE: return "line";
    case SLUICE_PIECE_ARC: return "arc";
    case SLUICE_PIECE_CREST: return "crest";
    case SLUICE_PIECE_STEPS: return "steps";
    }
    return "piece";
}

/* cos and sin of an angle in degrees, exact at multiples of 90 degrees. */
static void degrees_cos_sin(double degrees, double *c, double *s)
{
    double r = fmod(degrees, 360.0);
    if (r < 0)
        r += 360.0;
    double q = nearbyint(r / 90.0);
    double rad = (r - 90.0 * q) * (PROFILE_PI / 180.0);
    double cr = cos(rad), sr = sin(rad);
    switch ((int)q & 3) {
    case 0: *c = cr; *s = sr; break;
    case 1: *c = -sr; *s = cr; break;
    case 2: *c = -cr; *s = -sr; break;
    default: *c = sr; *s = -cr; break;
    }
}

static int profile_fail(sluice_profile_problem *problem, uint32_t piece, const char *key,
                        const char *format, ...) SLUICE_PRINTF(4, 5);
static int profile_fail(sluice_profile_problem *problem, uint32_t piece, const char *key,
                        const char *format, ...)
{
    problem->piece = piece;
    problem->other = UINT32_MAX;
    problem->closing = 0;
    problem->key = key;
    va_list ap;
    va_start(ap, format);
    vsnprintf(problem->message, sizeof problem->message, format, ap);
    va_end(ap);
    return -1;
}

typedef struct profile_builder {
    double *xy;
    uint32_t *piece;
    uint32_t count, capacity;
    double max_segment;
    sluice_profile_problem *problem;
} profile_builder;

/* Room for `extra` more vertices, within SLUICE_PROFILE_MAX_VERTICES. */
static int builder_reserve(profile_builder *b, double extra, uint32_t piece)
{
    if (!(extra + (double)b->count <= (double)SLUICE_PROFILE_MAX_VERTICES))
        return profile_fail(b->problem, piece, NULL,
                            "the profile would need %.3g vertices, more than %u (segments of "
                            "curves are at most max_segment = %g m long)",
                            extra + (double)b->count, SLUICE_PROFILE_MAX_VERTICES, b->max_segment);
    uint32_t need = b->count + (uint32_t)extra;
    if (need <= b->capacity)
        return 0;
    uint32_t capacity = b->capacity ? b->capacity : 64;
    while (capacity < need)
        capacity *= 2;
    double *xy = realloc(b->xy, (size_t)capacity * 2 * sizeof *xy);
    if (xy)
        b->xy = xy;
    uint32_t *pieces = xy ? realloc(b->piece, (size_t)capacity * sizeof *pieces) : NULL;
    if (!pieces)
        return profile_fail(b->problem, piece, NULL, "out of memory");
    b->piece = pieces;
    b->capacity = capacity;
    return 0;
}

/* Appends a vertex (room reserved); refuses a zero-length segment and
 * coordinates that are not finite. */
static int builder_push(profile_builder *b, double x, double y, uint32_t piece)
{
    if (!isfinite(x) || !isfinite(y))
        return profile_fail(b->problem, piece, NULL,
                            "the piece reaches a point with a coordinate too large to represent");
    const double *last = b->xy + 2 * (size_t)(b->count - 1);
    if (x == last[0] && y == last[1])
        return profile_fail(b->problem, piece, NULL,
                            "the piece makes a segment of zero length at (%g, %g) m", x, y);
    b->xy[2 * (size_t)b->count] = x;
    b->xy[2 * (size_t)b->count + 1] = y;
    b->piece[b->count] = piece;
    b->count++;
    return 0;
}

/* Name of the first key of `keys` (in the order of enum sluice_line_keys). */
static const char *line_key_name(unsigned keys)
{
    static const char *const names[] = {"to", "dx", "dy", "length", "heading", "slope", "to_x",
                                        "to_y"};
    for (unsigned i = 0; i < 8; i++)
        if (keys & (1u << i))
            return names[i];
    return NULL;
}

static int profile_line(profile_builder *b, const sluice_profile_piece *pc, uint32_t index,
                        double P[2], int *has_heading, double h[2])
{
    sluice_profile_problem *pr = b->problem;
    const unsigned k = pc->keys;
    const unsigned extents = SLUICE_LINE_LENGTH | SLUICE_LINE_DX | SLUICE_LINE_DY |
                             SLUICE_LINE_TO_X | SLUICE_LINE_TO_Y;
    const unsigned directions = SLUICE_LINE_HEADING | SLUICE_LINE_SLOPE;
    double E[2];
    if (!(k & (extents | SLUICE_LINE_TO)))
        return profile_fail(pr, index, NULL,
                            "a line needs its end: 'to', or 'dx' and 'dy', or one of 'length', "
                            "'dx', 'dy', 'to_x', 'to_y' along 'heading', 'slope' or the "
                            "direction of the previous piece");
    if (k & SLUICE_LINE_TO) {
        if (k & ~SLUICE_LINE_TO)
            return profile_fail(pr, index, line_key_name(k & ~SLUICE_LINE_TO),
                                "'to' sets the line's end alone: remove '%s'",
                                line_key_name(k & ~SLUICE_LINE_TO));
        E[0] = pc->to[0];
        E[1] = pc->to[1];
    } else if ((k & SLUICE_LINE_DX) && (k & SLUICE_LINE_DY)) {
        unsigned extra = k & ~(SLUICE_LINE_DX | SLUICE_LINE_DY);
        if (extra)
            return profile_fail(pr, index, line_key_name(extra),
                                "'dx' and 'dy' set the line's end alone: remove '%s'",
                                line_key_name(extra));
        E[0] = P[0] + pc->dx;
        E[1] = P[1] + pc->dy;
    } else {
        unsigned extent = k & extents;
        if (extent & (extent - 1)) /* more than one */
            return profile_fail(pr, index, line_key_name(extent & (extent - 1)),
                                "give the line's extent once: one of 'length', 'dx', 'dy', "
                                "'to_x', 'to_y' (or 'dx' and 'dy' together)");
        if ((k & directions) == directions)
            return profile_fail(pr, index, "slope",
                                "give the line's direction once: 'heading' or 'slope'");
        if ((k & SLUICE_LINE_LENGTH) && !(pc->length > 0))
            return profile_fail(pr, index, "length", "the length must be > 0 (got %g m)",
                                pc->length);
        double d[2];
        char along[80];
        if (k & SLUICE_LINE_HEADING) {
            if (!isfinite(pc->heading))
                return profile_fail(pr, index, "heading", "the heading must be finite");
            degrees_cos_sin(pc->heading, &d[0], &d[1]);
            snprintf(along, sizeof along, "heading %g deg", pc->heading);
        } else if (k & SLUICE_LINE_SLOPE) {
            double norm = hypot(1.0, pc->slope);
            if (!isfinite(norm))
                return profile_fail(pr, index, "slope", "the slope must be finite");
            d[0] = 1.0 / norm;
            d[1] = pc->slope / norm;
            snprintf(along, sizeof along, "slope %g", pc->slope);
        } else if (*has_heading) {
            d[0] = h[0];
            d[1] = h[1];
            snprintf(along, sizeof along, "the previous piece's direction, heading %.6g deg",
                     atan2(h[1], h[0]) * (180.0 / PROFILE_PI));
        } else {
            return profile_fail(pr, index, NULL,
                                "this line runs along the direction of the previous piece, but "
                                "it is the first piece: give it a 'heading' or a 'slope', or "
                                "give the profile a 'heading'");
        }
        if (k & SLUICE_LINE_LENGTH) {
            E[0] = P[0] + pc->length * d[0];
            E[1] = P[1] + pc->length * d[1];
        } else {
            int by_x = (k & (SLUICE_LINE_DX | SLUICE_LINE_TO_X)) != 0;
            const char *key = line_key_name(extent);
            double delta = (k & SLUICE_LINE_DX)     ? pc->dx
                           : (k & SLUICE_LINE_DY)   ? pc->dy
                           : (k & SLUICE_LINE_TO_X) ? pc->to_x - P[0]
                                                    : pc->to_y - P[1];
            if (k & SLUICE_LINE_SLOPE) {
                /* the direction is (1, slope) up to its sign: either delta goes */
                if (by_x) {
                    E[0] = P[0] + delta;
                    E[1] = P[1] + pc->slope * delta;
                } else {
                    if (pc->slope == 0)
                        return profile_fail(pr, index, key,
                                            "a line of slope 0 is horizontal: '%s' cannot set "
                                            "its end (give 'dx', 'to_x' or 'length')",
                                            key);
                    E[0] = P[0] + delta / pc->slope;
                    E[1] = P[1] + delta;
                }
                if (by_x && (k & SLUICE_LINE_TO_X))
                    E[0] = pc->to_x;
                if (!by_x && (k & SLUICE_LINE_TO_Y))
                    E[1] = pc->to_y;
            } else {
                double component = by_x ? d[0] : d[1];
                if (fabs(component) < 1e-12)
                    return profile_fail(pr, index, key,
                                        "a line along %s is %s: '%s' cannot set its end (give "
                                        "'%s' or 'length')",
                                        along, by_x ? "vertical" : "horizontal", key,
                                        by_x ? "dy' or 'to_y" : "dx' or 'to_x");
                double t = delta / component;
                if (!(t > 0))
                    return profile_fail(pr, index, key,
                                        "%s = %g m is not ahead along %s (from (%g, %g) m)", key,
                                        (k & SLUICE_LINE_TO_X)   ? pc->to_x
                                        : (k & SLUICE_LINE_TO_Y) ? pc->to_y
                                                                 : delta,
                                        along, P[0], P[1]);
                /* the given coordinate exactly, the other one along d */
                E[0] = by_x ? ((k & SLUICE_LINE_TO_X) ? pc->to_x : P[0] + delta) : P[0] + t * d[0];
                E[1] = by_x ? P[1] + t * d[1] : ((k & SLUICE_LINE_TO_Y) ? pc->to_y : P[1] + delta);
            }
        }
    }
    double length = hypot(E[0] - P[0], E[1] - P[1]);
    if (!isfinite(length))
        return profile_fail(pr, index, NULL, "the line is too long to represent");
    if (!(length > 0))
        return profile_fail(pr, index, NULL, "the line has zero length: it ends where it starts");
    if (builder_reserve(b, 1, index) != 0 || builder_push(b, E[0], E[1], index) != 0)
        return -1;
    h[0] = (E[0] - P[0]) / length;
    h[1] = (E[1] - P[1]) / length;
    *has_heading = 1;
    P[0] = E[0];
    P[1] = E[1];
    return 0;
}

static int profile_arc(profile_builder *b, const sluice_profile_piece *pc, uint32_t index,
                       double max_segment, double P[2], int *has_heading, double h[2])
{
    sluice_profile_problem *pr = b->problem;
    const double r = pc->radius, turn = pc->turn;
    if (!(r > 0) || !isfinite(r))
        return profile_fail(pr, index, "radius", "the radius must be > 0 (got %g m)", r);
    if (!(turn != 0) || !(fabs(turn) <= 360))
        return profile_fail(pr, index, "turn",
                            "the turn must be nonzero and at most 360 degrees either way (got %g)",
                            turn);
    if (!*has_heading)
        return profile_fail(pr, index, NULL,
                            "an arc starts tangent to the previous piece, but it is the first "
                            "piece: give the profile a 'heading'");
    double length = r * fabs(turn) * (PROFILE_PI / 180.0);
    double m = ceil(length / max_segment);
    if (m < 1)
        m = 1;
    if (builder_reserve(b, m, index) != 0)
        return -1;
    double side[2] = {turn > 0 ? -h[1] : h[1], turn > 0 ? h[0] : -h[0]};
    double C[2] = {P[0] + r * side[0], P[1] + r * side[1]};
    double e0[2] = {-side[0], -side[1]};
    uint32_t segments = (uint32_t)m;
    for (uint32_t k = 1; k <= segments; k++) {
        double angle = k == segments ? turn : turn * (double)k / (double)segments;
        double c, s;
        degrees_cos_sin(angle, &c, &s);
        double x = C[0] + r * (c * e0[0] - s * e0[1]);
        double y = C[1] + r * (s * e0[0] + c * e0[1]);
        if (builder_push(b, x, y, index) != 0)
            return -1;
    }
    double c, s;
    degrees_cos_sin(turn, &c, &s);
    double hx = c * h[0] - s * h[1], hy = s * h[0] + c * h[1];
    double norm = hypot(hx, hy);
    h[0] = hx / norm;
    h[1] = hy / norm;
    P[0] = b->xy[2 * (size_t)(b->count - 1)];
    P[1] = b->xy[2 * (size_t)(b->count - 1) + 1];
    return 0;
}

/* d(arc length)/dX of the crest Y = a X^n (both in units). */
static double crest_speed(double a, double n, double X)
{
    double slope = a * n * pow(X, n - 1);
    return sqrt(1 + slope * slope);
}

/* int_lo^hi crest_speed by 5-point Gauss-Legendre. */
static double crest_gauss(double a, double n, double lo, double hi)
{
    static const double node[5] = {-0.9061798459386640, -0.5384693101056831, 0.0,
                                   0.5384693101056831, 0.9061798459386640};
    static const double weight[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                                     0.4786286704993665, 0.2369268850561891};
    double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo), sum = 0;
    for (int i = 0; i < 5; i++)
        sum += weight[i] * crest_speed(a, n, mid + half * node[i]);
    return half * sum;
}

static int profile_crest(profile_builder *b, const sluice_profile_piece *pc, uint32_t index,
                         double max_segment, double P[2], int *has_heading, double h[2])
{
    sluice_profile_problem *pr = b->problem;
    const double a = pc->coefficient, n = pc->exponent, u = pc->unit;
    if (!(a > 0) || !isfinite(a))
        return profile_fail(pr, index, "coefficient", "the coefficient must be > 0 (got %g)", a);
    if (!(n > 1) || !isfinite(n))
        return profile_fail(pr, index, "exponent",
                            "the exponent must be > 1 (got %g): the crest's slope a n x^(n-1) "
                            "must start at 0 at the apex and grow downstream",
                            n);
    if (!(u > 0) || !isfinite(u))
        return profile_fail(pr, index, "unit", "the unit must be > 0 (got %g m)", u);
    double X_end, s_end;
    if (pc->end_at_x) {
        X_end = pc->end_x;
        if (!(X_end > 0) || !isfinite(X_end))
            return profile_fail(pr, index, "end_x", "end_x must be > 0 (got %g units)", X_end);
        s_end = a * n * pow(X_end, n - 1);
    } else {
        s_end = pc->end_slope;
        if (!(s_end > 0) || !isfinite(s_end))
            return profile_fail(pr, index, "end_slope",
                                "end_slope must be > 0 (got %g): the crest's slope is 0 at the "
                                "apex and only grows",
                                s_end);
        X_end = pow(s_end / (a * n), 1 / (n - 1));
    }
    double x_extent = u * X_end, y_extent = u * a * pow(X_end, n);
    if (!isfinite(s_end) || !isfinite(x_extent) || !isfinite(y_extent) || !(x_extent > 0))
        return profile_fail(pr, index, pc->end_at_x ? "end_x" : "end_slope",
                            "the crest y = %g x^%g reaches the slope %g only at x = %g units of "
                            "%g m: never at a size that can be represented",
                            a, n, s_end, X_end, u);
    /* arc length in units: graded panels X_end (j / J)^2 resolve the
     * non-smooth speed at the apex (X^(n-1), n < 2) */
    const int J = 256;
    double total = 0;
    for (int j = 0; j < J; j++) {
        double lo = X_end * ((double)j / J) * ((double)j / J);
        double hi = X_end * ((double)(j + 1) / J) * ((double)(j + 1) / J);
        total += crest_gauss(a, n, lo, hi);
    }
    double m = ceil(u * total / max_segment);
    if (m < 1)
        m = 1;
    if (builder_reserve(b, m, index) != 0)
        return -1;
    uint32_t segments = (uint32_t)m;
    double X = 0, S = 0;
    for (uint32_t k = 1; k <= segments; k++) {
        double next = X_end;
        if (k < segments) {
            double target = total * (double)k / (double)segments;
            double lo = X, hi = X_end;
            next = fmin(X + (target - S) / crest_speed(a, n, X), X_end);
            for (int it = 0; it < 100; it++) {
                double g = S + crest_gauss(a, n, X, next) - target;
                if (g > 0)
                    hi = next;
                else
                    lo = next;
                double step = g / crest_speed(a, n, next);
                double moved = next - step;
                if (!(moved > lo && moved < hi))
                    moved = 0.5 * (lo + hi);
                double change = fabs(moved - next);
                next = moved;
                if (change <= 1e-15 * X_end)
                    break;
            }
            S += crest_gauss(a, n, X, next);
        }
        X = next;
        if (builder_push(b, P[0] + u * X, P[1] - u * a * pow(X, n), index) != 0)
            return -1;
    }
    double norm = hypot(1.0, s_end);
    h[0] = 1.0 / norm;
    h[1] = -s_end / norm;
    *has_heading = 1;
    P[0] = b->xy[2 * (size_t)(b->count - 1)];
    P[1] = b->xy[2 * (size_t)(b->count - 1) + 1];
    return 0;
}

static int profile_steps(profile_builder *b, const sluice_profile_piece *pc, uint32_t index,
                         double P[2], int *has_heading, double h[2])
{
    sluice_profile_problem *pr = b->problem;
    const double rise = pc->height, tread = pc->step_length;
    if (pc->count < 1)
        return profile_fail(pr, index, "count", "a flight needs at least one step (got %u)",
                            pc->count);
    if (!(rise > 0) || !isfinite(rise))
        return profile_fail(pr, index, "height", "the step height must be > 0 (got %g m)", rise);
    if (!(tread > 0) || !isfinite(tread))
        return profile_fail(pr, index, "length", "the step length must be > 0 (got %g m)",
                            tread);
    if (builder_reserve(b, 2.0 * pc->count, index) != 0)
        return -1;
    const double x0 = P[0], y0 = P[1];
    for (uint32_t i = 0; i < pc->count; i++) {
        double k = (double)i, k1 = (double)i + 1;
        int rc = pc->tread_first
                     ? builder_push(b, x0 + k1 * tread, y0 - k * rise, index) ||
                           builder_push(b, x0 + k1 * tread, y0 - k1 * rise, index)
                     : builder_push(b, x0 + k * tread, y0 - k1 * rise, index) ||
                           builder_push(b, x0 + k1 * tread, y0 - k1 * rise, index);
        if (rc)
            return -1;
    }
    h[0] = pc->tread_first ? 0 : 1;
    h[1] = pc->tread_first ? -1 : 0;
    *has_heading = 1;
    P[0] = b->xy[2 * (size_t)(b->count - 1)];
    P[1] = b->xy[2 * (size_t)(b->count - 1) + 1];
    return 0;
}

void sluice_profile_path_free(sluice_profile_path *path)
{
    if (!path)
        return;
    free(path->xy);
    free(path->piece);
    path->xy = NULL;
    path->piece = NULL;
    path->vertex_count = 0;
}

int sluice_profile_build(const sluice_profile *profile, sluice_profile_path *out,
                         sluice_profile_problem *problem)
{
    sluice_profile_problem ignored;
    if (!problem)
        problem = &ignored;
    memset(problem, 0, sizeof *problem);
    if (out)
        *out = (sluice_profile_path){0};
    if (!profile || !out)
        return profile_fail(problem, UINT32_MAX, NULL, "no profile to build");
    if (profile->piece_count == 0 || !profile->pieces)
        return profile_fail(problem, UINT32_MAX, NULL, "a profile needs at least one piece");
    const double max_segment = profile->max_segment;
    if (!(max_segment > 0) || !isfinite(max_segment))
        return profile_fail(problem, UINT32_MAX, "max_segment",
                            "max_segment must be > 0 (got %g m)", max_segment);
    if (!isfinite(profile->start[0]) || !isfinite(profile->start[1]))
        return profile_fail(problem, UINT32_MAX, "start", "the start must be finite");
    profile_builder b = {0};
    b.problem = problem;
    b.max_segment = max_segment;
    double P[2] = {profile->start[0], profile->start[1]}, h[2] = {1, 0};
    int has_heading = profile->has_heading;
    if (has_heading) {
        if (!isfinite(profile->heading))
            return profile_fail(problem, UINT32_MAX, "heading", "the heading must be finite");
        degrees_cos_sin(profile->heading, &h[0], &h[1]);
    }
    int rc = builder_reserve(&b, 1, UINT32_MAX);
    if (rc == 0) {
        b.xy[0] = P[0];
        b.xy[1] = P[1];
        b.piece[0] = UINT32_MAX;
        b.count = 1;
    }
    for (uint32_t i = 0; i < profile->piece_count && rc == 0; i++) {
        const sluice_profile_piece *pc = &profile->pieces[i];
        switch (pc->kind) {
        case SLUICE_PIECE_LINE: rc = profile_line(&b, pc, i, P, &has_heading, h); break;
        case SLUICE_PIECE_ARC:
            rc = profile_arc(&b, pc, i, max_segment, P, &has_heading, h);
            break;
        case SLUICE_PIECE_CREST:
            rc = profile_crest(&b, pc, i, max_segment, P, &has_heading, h);
            break;
        case SLUICE_PIECE_STEPS: rc = profile_steps(&b, pc, i, P, &has_heading, h); break;
        default: rc = profile_fail(problem, i, NULL, "unknown kind of piece %d", (int)pc->kind);
        }
    }
    if (rc == 0 && profile->closed) {
        /* a last vertex on the start (a full circle) is the start itself */
        double lo[2] = {b.xy[0], b.xy[1]}, hi[2] = {b.xy[0], b.xy[1]};
        for (uint32_t v = 1; v < b.count; v++)
            for (int d = 0; d < 2; d++) {
                lo[d] = fmin(lo[d], b.xy[2 * v + (uint32_t)d]);
                hi[d] = fmax(hi[d], b.xy[2 * v + (uint32_t)d]);
            }
        double size = hypot(hi[0] - lo[0], hi[1] - lo[1]);
        const double *last = b.xy + 2 * (size_t)(b.count - 1);
        if (b.count > 1 && hypot(last[0] - b.xy[0], last[1] - b.xy[1]) <= 1e-12 * size) {
            b.count--;
            if (b.count > 1)
                b.piece[0] = b.piece[b.count];
        }
        if (b.count < 3)
            rc = profile_fail(problem, UINT32_MAX, NULL,
                              "a closed profile needs at least 3 distinct vertices (it has %u)",
                              b.count);
    }
    if (rc == 0) {
        uint32_t first = 0, second = 0;
        double where[2];
        int crossing =
            sluice_polyline_crossing(b.xy, b.count, profile->closed, &first, &second, where);
        if (crossing < 0) {
            rc = profile_fail(problem, UINT32_MAX, NULL, "out of memory");
        } else if (crossing > 0) {
            /* segment s runs from vertex s to vertex s + 1 (to vertex 0 for
             * the last segment of a closed profile) and belongs to the piece
             * of its end; UINT32_MAX: the closing segment */
            uint32_t piece_first = b.piece[(first + 1) % b.count];
            uint32_t piece_second = b.piece[(second + 1) % b.count];
            int fold = second == first + 1 || (profile->closed && first == 0 &&
                                               second == b.count - 1);
            int closing = piece_second == UINT32_MAX;
            rc = profile_fail(problem, closing ? piece_first : piece_second, NULL,
                              "the profile %s itself at (%.6g, %.6g) m",
                              fold ? "folds back onto" : "crosses or touches", where[0],
                              where[1]);
            problem->other = closing ? UINT32_MAX : piece_first;
            problem->closing = closing;
        }
    }
    if (rc != 0) {
        free(b.xy);
        free(b.piece);
        return -1;
    }
    /* hand out sluice_real vertices */
    sluice_real *xy = malloc((size_t)b.count * 2 * sizeof *xy);
    if (!xy) {
        free(b.xy);
        free(b.piece);
        return profile_fail(problem, UINT32_MAX, NULL, "out of memory");
    }
    for (size_t v = 0; v < 2 * (size_t)b.count; v++)
        xy[v] = (sluice_real)b.xy[v];
    free(b.xy);
    out->xy = xy;
    out->piece = b.piece;
    out->vertex_count = b.count;
    return 0;
}

/* -------------------------------------------------- polyline crossings -- */

typedef struct segment_span {
    double lo, hi; /* x extent */
    uint32_t segment;
} segment_span;

static int segment_span_compare(const void *pa, const void *pb)
{
    const segment_span *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    return (a->segment > b->segment) - (a->segment < b->segment);
}

static double orient2(const double a[2], const double b[2], const double c[2])
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* p, collinear with ab, lies within the segment ab. */
static int within_segment(const double a[2], const double b[2], const double p[2])
{
    return fmin(a[0], b[0]) <= p[0] && p[0] <= fmax(a[0], b[0]) && fmin(a[1], b[1]) <= p[1] &&
           p[1] <= fmax(a[1], b[1]);
}

/* Closed segments ab and cd share a point: 1 and one such point. */
static int segments_meet(const double a[2], const double b[2], const double c[2],
                         const double d[2], double where[2])
{
    double o1 = orient2(a, b, c), o2 = orient2(a, b, d);
    double o3 = orient2(c, d, a), o4 = orient2(c, d, b);
    if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) {
        double t = o3 / (o3 - o4);
        where[0] = a[0] + t * (b[0] - a[0]);
        where[1] = a[1] + t * (b[1] - a[1]);
        return 1;
    }
    const double *candidates[4] = {c, d, a, b};
    const double orientation[4] = {o1, o2, o3, o4};
    for (int i = 0; i < 4; i++) {
        const double *s0 = i < 2 ? a : c, *s1 = i < 2 ? b : d;
        if (orientation[i] == 0 && within_segment(s0, s1, candidates[i])) {
            where[0] = candidates[i][0];
            where[1] = candidates[i][1];
            return 1;
        }
    }
    return 0;
}

/* Neighbouring segments ab and bc fold back: antiparallel and collinear. */
static int segments_fold(const double a[2], const double b[2], const double c[2])
{
    double u[2] = {b[0] - a[0], b[1] - a[1]}, v[2] = {c[0] - b[0], c[1] - b[1]};
    double cross = u[0] * v[1] - u[1] * v[0], dot = u[0] * v[0] + u[1] * v[1];
    return dot < 0 && fabs(cross) <= 1e-12 * hypot(u[0], u[1]) * hypot(v[0], v[1]);
}

/* Spans sorted by their lower x; each segment is tested against the ones
 * whose x extent starts before its own ends (and overlaps it in y). Of all
 * the crossings the one with the smallest (second, first) is reported: the
 * first place along the polyline where it meets an earlier part of itself. */
int sluice_polyline_crossing(const sluice_real *xy, uint32_t n, int closed, uint32_t *first,
                             uint32_t *second, double where[2])
{
    if (!xy || n < 2)
        return 0;
    uint32_t segments = closed && n >= 3 ? n : n - 1;
    segment_span *spans = malloc((size_t)segments * sizeof *spans);
    if (!spans)
        return -1;
    for (uint32_t s = 0; s < segments; s++) {
        double x0 = (double)xy[2 * s], x1 = (double)xy[2 * ((s + 1) % n)];
        spans[s].lo = fmin(x0, x1);
        spans[s].hi = fmax(x0, x1);
        spans[s].segment = s;
    }
    qsort(spans, segments, sizeof *spans, segment_span_compare);
    uint32_t best_first = 0, best_second = UINT32_MAX;
    double best_where[2] = {0, 0};
    for (uint32_t i = 0; i < segments; i++) {
        for (uint32_t j = i + 1; j < segments && spans[j].lo <= spans[i].hi; j++) {
            uint32_t s = spans[i].segment, t = spans[j].segment;
            uint32_t lo = s < t ? s : t, hi = s < t ? t : s;
            if (hi > best_second || (hi == best_second && lo >= best_first))
                continue; /* cannot improve on the crossing found */
            double a[2] = {(double)xy[2 * lo], (double)xy[2 * lo + 1]};
            double b[2] = {(double)xy[2 * ((lo + 1) % n)], (double)xy[2 * ((lo + 1) % n) + 1]};
            double c[2] = {(double)xy[2 * hi], (double)xy[2 * hi + 1]};
            double d[2] = {(double)xy[2 * ((hi + 1) % n)], (double)xy[2 * ((hi + 1) % n) + 1]};
            int next = hi == lo + 1, wrap = closed && lo == 0 && hi == segments - 1;
            double at[2];
            int found = 0;
            if (next) {
                found = segments_fold(a, b, d);
                at[0] = b[0];
                at[1] = b[1];
            } else if (wrap) {
                found = segments_fold(c, a, b); /* c -> d = a -> b */
                at[0] = a[0];
                at[1] = a[1];
            } else if (fmax(a[1], b[1]) >= fmin(c[1], d[1]) &&
                       fmax(c[1], d[1]) >= fmin(a[1], b[1])) {
                found = segments_meet(a, b, c, d, at);
            }
            if (found) {
                best_first = lo;
                best_second = hi;
                best_where[0] = at[0];
                best_where[1] = at[1];
            }
        }
    }
    free(spans);
    if (best_second == UINT32_MAX)
        return 0;
    *first = best_first;
    *second = best_second;
    where[0] = best_where[0];
    where[1] = best_where[1];
    return 1;
}
