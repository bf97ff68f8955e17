/* Geometry: point in polygon, lattice fills of boxes/polygons/prisms, closest
 * points on segments and triangles, wall construction (normals, pseudo-normals,
 * open ends, refusals), signed distance around 2D/3D tanks and boxes (checked
 * against closed-form distances at many random points), wall layer points
 * checked against analytic counts and independent per-point conditions, and
 * profiles (lines, arcs, WES crests, flights of steps: seed 001's
 * structures) against their nominal dimensions, with the scene errors they
 * give. */
#include "test_util.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <time.h>

#include "geometry.h"
#include "scene.h"
#include "wall_distance.h"
#include "wall_watch.h"

#define EPS 1e-12

/* ------------------------------------------------------------- helpers -- */

static double uniform(uint64_t *state, double lo, double hi)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return lo + (hi - lo) * ((double)(*state >> 11) * (1.0 / 9007199254740992.0));
}

static double seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct key3 {
    int64_t k[3];
} key3;

static int key3_compare(const void *pa, const void *pb)
{
    const key3 *a = pa, *b = pb;
    for (int d = 2; d >= 0; d--)
        if (a->k[d] != b->k[d])
            return a->k[d] < b->k[d] ? -1 : 1;
    return 0;
}

/* Lattice keys of the points; checks that every point is a lattice point
 * (z = 0 in 2D) and returns the number of duplicates. keys may be NULL. */
static size_t lattice_keys(const sluice_points *pts, uint32_t dims, double dx,
                           const double origin[3], key3 **keys_out)
{
    key3 *keys = calloc(pts->count ? pts->count : 1, sizeof *keys);
    ck_assert_ptr_nonnull(keys);
    for (size_t i = 0; i < pts->count; i++) {
        for (uint32_t d = 0; d < 3; d++) {
            double x = pts->xyz[3 * i + d];
            if (d >= dims) {
                ck_assert_double_eq(x, 0.0);
                continue;
            }
            double u = (x - origin[d]) / dx - 0.5;
            keys[i].k[d] = llround(u);
            ck_assert_msg(fabs(u - (double)keys[i].k[d]) < 1e-6, "point %zu off the lattice", i);
        }
    }
    qsort(keys, pts->count, sizeof *keys, key3_compare);
    size_t duplicates = 0;
    for (size_t i = 1; i < pts->count; i++)
        duplicates += key3_compare(&keys[i - 1], &keys[i]) == 0;
    if (keys_out)
        *keys_out = keys;
    else
        free(keys);
    return duplicates;
}

/* Number of (i, j) (and k) in [0, L)^2 (^3) with sum (i + 1/2)^2 <= L^2: the
 * lattice points of a quarter disc (octant of a ball) of radius L spacings. */
static long quarter_disc(int L)
{
    long n = 0;
    for (int i = 0; i < L; i++)
        for (int j = 0; j < L; j++)
            n += (i + 0.5) * (i + 0.5) + (j + 0.5) * (j + 0.5) <= (double)L * L;
    return n;
}

static long ball_octant(int L)
{
    long n = 0;
    for (int i = 0; i < L; i++)
        for (int j = 0; j < L; j++)
            for (int k = 0; k < L; k++)
                n += (i + 0.5) * (i + 0.5) + (j + 0.5) * (j + 0.5) + (k + 0.5) * (k + 0.5) <=
                     (double)L * L;
    return n;
}

/* Distance from p to the axis-aligned box [lo, hi] (its surface, from either
 * side) and whether p is strictly inside. */
static double box_surface_distance(const double p[3], const double lo[3], const double hi[3],
                                   uint32_t dims, int *inside)
{
    double outside2 = 0, inner = HUGE_VAL;
    int in = 1;
    for (uint32_t d = 0; d < dims; d++) {
        double below = lo[d] - p[d], above = p[d] - hi[d];
        if (below > 0)
            outside2 += below * below, in = 0;
        if (above > 0)
            outside2 += above * above, in = 0;
        inner = fmin(inner, fmin(p[d] - lo[d], hi[d] - p[d]));
    }
    *inside = in;
    return in ? inner : sqrt(outside2);
}

static double signed_distance(const sluice_wall_geometry *w, double x, double y, double z,
                              int *beyond, uint32_t *element)
{
    sluice_real p[3] = {x, y, z};
    int b = -1;
    double d = sluice_wall_signed_distance(w, p, &b, element);
    ck_assert(b == 0 || b == 1);
    if (beyond)
        *beyond = b;
    return d;
}

static void assert_sd(const sluice_wall_geometry *w, double x, double y, double z, double expect,
                      int expect_beyond)
{
    int beyond;
    double d = signed_distance(w, x, y, z, &beyond, NULL);
    ck_assert_msg(fabs(d - expect) < 1e-12 && beyond == expect_beyond,
                  "signed distance at (%g, %g, %g): %.15g beyond %d, expected %.15g beyond %d", x,
                  y, z, d, beyond, expect, expect_beyond);
}

static void assert_beyond(const sluice_wall_geometry *w, double x, double y, double z)
{
    int beyond;
    signed_distance(w, x, y, z, &beyond, NULL);
    ck_assert_msg(beyond == 1, "(%g, %g, %g) should be beyond an open end", x, y, z);
}

/* --------------------------------------------------------- point in polygon -- */

START_TEST(point_in_polygon_convex)
{
    const sluice_real square[] = {0, 0, 1, 0, 1, 1, 0, 1};
    ck_assert(sluice_point_in_polygon(square, 4, 0.5, 0.5));
    ck_assert(!sluice_point_in_polygon(square, 4, 1.5, 0.5));
    ck_assert(!sluice_point_in_polygon(square, 4, -0.1, 0.5));
    ck_assert(!sluice_point_in_polygon(square, 4, 0.5, 1.2));
    ck_assert(!sluice_point_in_polygon(square, 4, 0.5, -1e-9));
    /* axis-aligned edges follow the half-open rule min <= x < max */
    ck_assert(sluice_point_in_polygon(square, 4, 0.0, 0.5));
    ck_assert(!sluice_point_in_polygon(square, 4, 1.0, 0.5));
    ck_assert(sluice_point_in_polygon(square, 4, 0.5, 0.0));
    ck_assert(!sluice_point_in_polygon(square, 4, 0.5, 1.0));
    /* a clockwise regular hexagon of radius 1 */
    sluice_real hexagon[12];
    for (int k = 0; k < 6; k++) {
        hexagon[2 * k] = cos(-k * M_PI / 3);
        hexagon[2 * k + 1] = sin(-k * M_PI / 3);
    }
    ck_assert(sluice_point_in_polygon(hexagon, 6, 0, 0));
    ck_assert(sluice_point_in_polygon(hexagon, 6, 0.95, 0));
    ck_assert(sluice_point_in_polygon(hexagon, 6, 0, 0.85));
    ck_assert(!sluice_point_in_polygon(hexagon, 6, 0, 0.88));
    ck_assert(!sluice_point_in_polygon(hexagon, 6, 0.9, 0.5));
    ck_assert(!sluice_point_in_polygon(hexagon, 6, 1.01, 0));
    /* fewer than three vertices: nothing is inside */
    ck_assert(!sluice_point_in_polygon(square, 2, 0.5, 0.0));
}
END_TEST

START_TEST(point_in_polygon_concave)
{
    const sluice_real L[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
    ck_assert(sluice_point_in_polygon(L, 6, 0.5, 0.5));
    ck_assert(sluice_point_in_polygon(L, 6, 1.5, 0.5));
    ck_assert(sluice_point_in_polygon(L, 6, 0.5, 1.5));
    ck_assert(!sluice_point_in_polygon(L, 6, 1.5, 1.5)); /* the notch */
    ck_assert(!sluice_point_in_polygon(L, 6, 1.01, 1.01));
    ck_assert(sluice_point_in_polygon(L, 6, 0.99, 1.01));
    ck_assert(!sluice_point_in_polygon(L, 6, 2.5, 0.5));
    /* a dart, concave at (1, 1) */
    const sluice_real dart[] = {0, 0, 2, 1, 0, 2, 1, 1};
    ck_assert(sluice_point_in_polygon(dart, 4, 1.5, 1.0));
    ck_assert(sluice_point_in_polygon(dart, 4, 0.2, 0.15));
    ck_assert(sluice_point_in_polygon(dart, 4, 0.2, 1.85));
    ck_assert(!sluice_point_in_polygon(dart, 4, 0.5, 1.0)); /* the notch */
    ck_assert(!sluice_point_in_polygon(dart, 4, 0.2, 0.3));
    ck_assert(!sluice_point_in_polygon(dart, 4, 2.1, 1.0));
}
END_TEST

/* ----------------------------------------------------------------- fills -- */

static size_t fill_count(const sluice_region *r, uint32_t dims, double dx, const double o[3])
{
    sluice_points pts = {0};
    sluice_real origin[3] = {o[0], o[1], o[2]};
    ck_assert_int_eq(sluice_region_fill(r, dims, dx, origin, &pts), 0);
    size_t n = pts.count;
    ck_assert_uint_eq(lattice_keys(&pts, dims, dx, o, NULL), 0);
    sluice_points_free(&pts);
    return n;
}

START_TEST(box_fill_2d)
{
    const double zero[3] = {0, 0, 0};
    sluice_region box = {.shape = SLUICE_REGION_BOX, .min = {0, 0, 0}, .max = {1, 2, 0}};
    sluice_points pts = {0};
    ck_assert_int_eq(sluice_region_fill(&box, 2, 0.02, (sluice_real[3]){0, 0, 0}, &pts), 0);
    ck_assert_uint_eq(pts.count, 5000);
    ck_assert_double_eq_tol(pts.xyz[0], 0.01, EPS);
    ck_assert_double_eq_tol(pts.xyz[1], 0.01, EPS);
    for (size_t i = 0; i < pts.count; i++) {
        ck_assert(sluice_region_contains(&box, 2, pts.xyz + 3 * i));
        ck_assert_double_eq(pts.xyz[3 * i + 2], 0.0);
    }
    ck_assert_uint_eq(lattice_keys(&pts, 2, 0.02, zero, NULL), 0);
    sluice_points_free(&pts);
    ck_assert_ptr_null(pts.xyz);

    /* boundaries on lattice points: min included, max excluded */
    sluice_region aligned = {.shape = SLUICE_REGION_BOX, .min = {0.01, 0.01, 0},
                             .max = {0.99, 0.05, 0}};
    ck_assert_uint_eq(fill_count(&aligned, 2, 0.02, zero), 49 * 2);
    sluice_region tenths = {.shape = SLUICE_REGION_BOX, .min = {0.05, 0, 0}, .max = {0.35, 0.3, 0}};
    ck_assert_uint_eq(fill_count(&tenths, 2, 0.1, zero), 3 * 3);
    /* ... also where (bound - origin) / dx - 1/2 rounds just above the integer:
     * 0.07 / 0.02 - 0.5 = 3.0000000000000004, 2.49 / 0.02 - 0.5 = 124.00000000000001 */
    sluice_region rounding = {.shape = SLUICE_REGION_BOX, .min = {0.07, 0.07, 0},
                              .max = {2.49, 1.11, 0}};
    ck_assert_int_eq(sluice_region_fill(&rounding, 2, 0.02, NULL, &pts), 0);
    ck_assert_uint_eq(pts.count, 121 * 52);
    double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
    for (size_t i = 0; i < pts.count; i++)
        for (int d = 0; d < 2; d++) {
            lo[d] = fmin(lo[d], pts.xyz[3 * i + d]);
            hi[d] = fmax(hi[d], pts.xyz[3 * i + d]);
        }
    ck_assert_double_eq_tol(lo[0], 0.07, 1e-12);
    ck_assert_double_eq_tol(lo[1], 0.07, 1e-12);
    ck_assert_double_eq_tol(hi[0], 2.47, 1e-12);
    ck_assert_double_eq_tol(hi[1], 1.09, 1e-12);
    sluice_points_free(&pts);
    /* sluice_region_contains is half-open too */
    ck_assert(sluice_region_contains(&box, 2, (sluice_real[3]){0, 0, 0}));
    ck_assert(!sluice_region_contains(&box, 2, (sluice_real[3]){1, 0.5, 0}));
    ck_assert(!sluice_region_contains(&box, 2, (sluice_real[3]){0.5, 2, 0}));
    ck_assert(!sluice_region_contains(&box, 2, (sluice_real[3]){-1e-12, 0.5, 0}));
    ck_assert(sluice_region_contains(&box, 2, (sluice_real[3]){0.5, 0.5, 7})); /* z unused */
    /* negative lattice indices and an offset origin */
    sluice_region negative = {.shape = SLUICE_REGION_BOX, .min = {-1, -1, 0}, .max = {0, 0, 0}};
    ck_assert_uint_eq(fill_count(&negative, 2, 0.1, (double[3]){0.3, 0.7, 0}), 100);
    /* empty and invalid */
    sluice_region empty = {.shape = SLUICE_REGION_BOX, .min = {0, 0, 0}, .max = {0.005, 1, 0}};
    ck_assert_uint_eq(fill_count(&empty, 2, 0.02, zero), 0);
    ck_assert_int_eq(sluice_region_fill(&box, 2, 0, NULL, &pts), -1);
    ck_assert_int_eq(sluice_region_fill(&box, 4, 0.1, NULL, &pts), -1);
    sluice_points_free(&pts);
}
END_TEST

START_TEST(box_fill_3d)
{
    const double zero[3] = {0, 0, 0};
    sluice_region box = {.shape = SLUICE_REGION_BOX, .min = {0, 0, 0}, .max = {1, 2, 0.5}};
    ck_assert_uint_eq(fill_count(&box, 3, 0.05, zero), 8000);
    sluice_points pts = {0};
    ck_assert_int_eq(sluice_region_fill(&box, 3, 0.05, (sluice_real[3]){0, 0, 0}, &pts), 0);
    for (size_t i = 0; i < pts.count; i++)
        ck_assert(sluice_region_contains(&box, 3, pts.xyz + 3 * i));
    ck_assert_double_eq_tol(pts.xyz[2], 0.025, EPS);
    sluice_points_free(&pts);
    /* appending to a non-empty list keeps what is there */
    sluice_region small = {.shape = SLUICE_REGION_BOX, .min = {0, 0, 0}, .max = {0.1, 0.1, 0.1}};
    ck_assert_int_eq(sluice_region_fill(&small, 3, 0.05, NULL, &pts), 0);
    ck_assert_int_eq(sluice_region_fill(&small, 3, 0.05, NULL, &pts), 0);
    ck_assert_uint_eq(pts.count, 16);
    sluice_points_free(&pts);
}
END_TEST

/* Fills the polygon and checks: every point inside, every lattice point of
 * the bounding box that is inside was filled, and count dx^2 is within one
 * boundary layer (perimeter dx) of the exact area. */
static size_t check_polygon_fill(const sluice_real *poly, uint32_t n, double dx, const double o[3],
                                 double area)
{
    sluice_region r = {.shape = SLUICE_REGION_POLYGON, .polygon = poly, .vertex_count = n};
    sluice_points pts = {0};
    sluice_real origin[3] = {o[0], o[1], o[2]};
    ck_assert_int_eq(sluice_region_fill(&r, 2, dx, origin, &pts), 0);
    for (size_t i = 0; i < pts.count; i++) {
        ck_assert(sluice_region_contains(&r, 2, pts.xyz + 3 * i));
        ck_assert(sluice_point_in_polygon(poly, n, pts.xyz[3 * i], pts.xyz[3 * i + 1]));
    }
    ck_assert_uint_eq(lattice_keys(&pts, 2, dx, o, NULL), 0);
    /* completeness, by brute force over the bounding box */
    sluice_real lo[3], hi[3];
    sluice_region_bounds(&r, 2, lo, hi);
    size_t brute = 0;
    for (long j = (long)floor((lo[1] - o[1]) / dx) - 2; j <= (long)ceil((hi[1] - o[1]) / dx) + 2;
         j++)
        for (long i = (long)floor((lo[0] - o[0]) / dx) - 2;
             i <= (long)ceil((hi[0] - o[0]) / dx) + 2; i++)
            brute += sluice_point_in_polygon(poly, n, o[0] + (i + 0.5) * dx,
                                             o[1] + (j + 0.5) * dx);
    ck_assert_uint_eq(pts.count, brute);
    double perimeter = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t m = (k + 1) % n;
        perimeter += hypot(poly[2 * m] - poly[2 * k], poly[2 * m + 1] - poly[2 * k + 1]);
    }
    double filled = (double)pts.count * dx * dx;
    ck_assert_msg(fabs(filled - area) <= perimeter * dx,
                  "filled area %g, exact %g, allowed error %g", filled, area, perimeter * dx);
    size_t count = pts.count;
    sluice_points_free(&pts);
    return count;
}

START_TEST(polygon_fill_triangle)
{
    const double zero[3] = {0, 0, 0};
    const sluice_real tri[] = {0, 0, 1, 0, 0, 0.7};
    size_t n = check_polygon_fill(tri, 3, 0.01, zero, 0.35);
    ck_assert_uint_gt(n, 3000);
    const sluice_real tri_cw[] = {0, 0, 0, 0.7, 1, 0};
    ck_assert_uint_eq(check_polygon_fill(tri_cw, 3, 0.01, zero, 0.35), n);
    /* a right triangle whose hypotenuse runs through lattice points */
    const sluice_real aligned[] = {0, 0, 1, 0, 0, 1};
    check_polygon_fill(aligned, 3, 0.02, zero, 0.5);
    check_polygon_fill(tri, 3, 0.013, (double[3]){0.004, -0.002, 0}, 0.35);
}
END_TEST

START_TEST(polygon_fill_l_shape)
{
    const double zero[3] = {0, 0, 0};
    const sluice_real L[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
    /* boundaries on lattice lines: exactly area / dx^2 */
    ck_assert_uint_eq(check_polygon_fill(L, 6, 0.02, zero, 3.0), 7500);
    const sluice_real L_cw[] = {0, 0, 0, 2, 1, 2, 1, 1, 2, 1, 2, 0};
    ck_assert_uint_eq(check_polygon_fill(L_cw, 6, 0.02, zero, 3.0), 7500);
    check_polygon_fill(L, 6, 0.017, (double[3]){0.003, 0.011, 0}, 3.0);
    /* a polygon with the box's boundary gives the box's points */
    const sluice_real rect[] = {0, 0, 1, 0, 1, 2, 0, 2};
    ck_assert_uint_eq(check_polygon_fill(rect, 4, 0.02, zero, 2.0), 5000);
    /* degenerate polygons fill nothing */
    sluice_region line = {.shape = SLUICE_REGION_POLYGON, .polygon = rect, .vertex_count = 2};
    ck_assert_uint_eq(fill_count(&line, 2, 0.02, zero), 0);
}
END_TEST

START_TEST(prism_fill)
{
    const sluice_real L[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
    sluice_region prism = {.shape = SLUICE_REGION_PRISM, .min = {0, 0, -0.25}, .max = {0, 0, 0.25},
                           .polygon = L, .vertex_count = 6};
    sluice_points pts = {0};
    ck_assert_int_eq(sluice_region_fill(&prism, 3, 0.05, NULL, &pts), 0);
    ck_assert_uint_eq(pts.count, 1200 * 10);
    for (size_t i = 0; i < pts.count; i++)
        ck_assert(sluice_region_contains(&prism, 3, pts.xyz + 3 * i));
    ck_assert_uint_eq(lattice_keys(&pts, 3, 0.05, (double[3]){0, 0, 0}, NULL), 0);
    sluice_real lo[3], hi[3];
    sluice_region_bounds(&prism, 3, lo, hi);
    ck_assert_double_eq(lo[0], 0);
    ck_assert_double_eq(hi[1], 2);
    ck_assert_double_eq(lo[2], -0.25);
    ck_assert_double_eq(hi[2], 0.25);
    ck_assert(!sluice_region_contains(&prism, 3, (sluice_real[3]){0.5, 0.5, 0.25}));
    ck_assert(sluice_region_contains(&prism, 3, (sluice_real[3]){0.5, 0.5, -0.25}));
    ck_assert(!sluice_region_contains(&prism, 3, (sluice_real[3]){1.5, 1.5, 0}));
    sluice_points_free(&pts);
}
END_TEST

/* ------------------------------------------------------- closest points -- */

static void assert_point(const sluice_real got[3], double x, double y, double z)
{
    ck_assert_msg(got[0] == x && got[1] == y && got[2] == z,
                  "closest point (%.17g, %.17g, %.17g), expected (%g, %g, %g)", got[0], got[1],
                  got[2], x, y, z);
}

START_TEST(segment_closest)
{
    const sluice_real a[3] = {0, 0, 0}, b[3] = {2, 0, 0};
    sluice_real c[3];
    int f = -1;
    ck_assert_double_eq(sluice_segment_closest((sluice_real[3]){1, 1, 0}, a, b, c, &f), 1.0);
    ck_assert_int_eq(f, 0);
    assert_point(c, 1, 0, 0);
    ck_assert_double_eq_tol(sluice_segment_closest((sluice_real[3]){-1, 1, 0}, a, b, c, &f),
                            sqrt(2.0), EPS);
    ck_assert_int_eq(f, 1);
    assert_point(c, 0, 0, 0);
    ck_assert_double_eq_tol(sluice_segment_closest((sluice_real[3]){3, -1, 0}, a, b, c, &f),
                            sqrt(2.0), EPS);
    ck_assert_int_eq(f, 2);
    assert_point(c, 2, 0, 0);
    /* on the segment, and in 3D */
    ck_assert_double_eq(sluice_segment_closest((sluice_real[3]){0.5, 0, 0}, a, b, c, &f), 0.0);
    ck_assert_int_eq(f, 0);
    const sluice_real a3[3] = {1, 1, 1}, b3[3] = {1, 1, 3};
    ck_assert_double_eq(sluice_segment_closest((sluice_real[3]){1, 4, 2.5}, a3, b3, c, &f), 3.0);
    ck_assert_int_eq(f, 0);
    assert_point(c, 1, 1, 2.5);
}
END_TEST

START_TEST(triangle_closest_regions)
{
    const sluice_real a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
    struct {
        sluice_real p[3];
        int feature;
        double q[3];
    } cases[] = {
        {{0.25, 0.25, 2}, 0, {0.25, 0.25, 0}},   /* face */
        {{-1, -1, 1}, 1, {0, 0, 0}},             /* vertex a */
        {{2, -0.5, 0.25}, 2, {1, 0, 0}},         /* vertex b */
        {{-0.5, 2, -1}, 3, {0, 1, 0}},           /* vertex c */
        {{0.5, -1, 0.5}, 4, {0.5, 0, 0}},        /* edge ab */
        {{1, 1, 0}, 5, {0.5, 0.5, 0}},           /* edge bc */
        {{-1, 0.5, -0.25}, 6, {0, 0.5, 0}},      /* edge ca */
        {{0.25, 0.5, -3}, 0, {0.25, 0.5, 0}},    /* face, from behind */
        {{0.75, 0.75, 0.5}, 5, {0.5, 0.5, 0}},   /* edge bc, off the plane */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        sluice_real q[3];
        int f = -1;
        double d = sluice_triangle_closest(cases[i].p, a, b, c, q, &f);
        ck_assert_msg(f == cases[i].feature, "case %zu: feature %d, expected %d", i, f,
                      cases[i].feature);
        assert_point(q, cases[i].q[0], cases[i].q[1], cases[i].q[2]);
        double e[3] = {cases[i].p[0] - cases[i].q[0], cases[i].p[1] - cases[i].q[1],
                       cases[i].p[2] - cases[i].q[2]};
        ck_assert_double_eq_tol(d, sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]), EPS);
    }
    /* a degenerate (collinear) triangle falls back to its edges */
    const sluice_real d0[3] = {0, 0, 0}, d1[3] = {1, 0, 0}, d2[3] = {2, 0, 0};
    sluice_real q[3];
    int f = -1;
    ck_assert_double_eq(sluice_triangle_closest((sluice_real[3]){0.5, 1, 0}, d0, d1, d2, q, &f),
                        1.0);
    assert_point(q, 0.5, 0, 0);
    ck_assert_int_eq(f, 4);
}
END_TEST

/* A general triangle against brute force over a fine barycentric sampling. */
START_TEST(triangle_closest_random)
{
    uint64_t rng = 12345;
    const sluice_real a[3] = {0.3, -0.2, 0.1}, b[3] = {1.4, 0.5, -0.3}, c[3] = {-0.1, 0.9, 0.8};
    const int N = 200;
    for (int trial = 0; trial < 300; trial++) {
        sluice_real p[3] = {uniform(&rng, -1, 2), uniform(&rng, -1, 2), uniform(&rng, -1, 2)};
        sluice_real q[3];
        int f;
        double d = sluice_triangle_closest(p, a, b, c, q, &f);
        double best = HUGE_VAL;
        for (int i = 0; i <= N; i++)
            for (int j = 0; i + j <= N; j++) {
                double u = (double)i / N, v = (double)j / N, w = 1 - u - v, s = 0;
                for (int k = 0; k < 3; k++) {
                    double x = w * a[k] + u * b[k] + v * c[k] - p[k];
                    s += x * x;
                }
                best = fmin(best, sqrt(s));
            }
        ck_assert(d <= best + 1e-12);
        ck_assert(d >= best - 0.02);
        double e = 0;
        for (int k = 0; k < 3; k++)
            e += (p[k] - q[k]) * (p[k] - q[k]);
        ck_assert_double_eq_tol(sqrt(e), d, 1e-12);
        ck_assert(f >= 0 && f <= 6);
    }
}
END_TEST

/* ----------------------------------------------------------- wall build -- */

START_TEST(wall_refusals)
{
    sluice_wall_geometry w;
    const char *reason = NULL;
    const sluice_real one[] = {0, 0};
    ck_assert_int_eq(sluice_wall_build_polyline(&w, one, 1, 0, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    ck_assert_ptr_null(w.points);
    sluice_wall_geometry_free(&w);
    reason = NULL;
    const sluice_real repeated[] = {0, 0, 1, 0, 1, 0, 2, 1};
    ck_assert_int_eq(sluice_wall_build_polyline(&w, repeated, 4, 0, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    ck_assert_ptr_null(w.points);
    reason = NULL;
    const sluice_real two[] = {0, 0, 1, 0};
    ck_assert_int_eq(sluice_wall_build_polyline(&w, two, 2, 1, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    reason = NULL;
    const sluice_real closing[] = {0, 0, 1, 0, 1, 1, 0, 0}; /* closed, last == first */
    ck_assert_int_eq(sluice_wall_build_polyline(&w, closing, 4, 1, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    reason = NULL;
    const sluice_real nan_point[] = {0, 0, NAN, 1};
    ck_assert_int_eq(sluice_wall_build_polyline(&w, nan_point, 2, 0, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    /* the same vertices open are fine, and NULL reason is allowed */
    ck_assert_int_eq(sluice_wall_build_polyline(&w, closing, 3, 1, NULL), 0);
    ck_assert_uint_eq(w.element_count, 3);
    sluice_wall_geometry_free(&w);
    ck_assert_ptr_null(w.points);
    sluice_wall_geometry_free(&w); /* twice is harmless */

    const sluice_real v[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 2, 0, 0};
    const uint32_t out_of_range[] = {0, 1, 7};
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_triangles(&w, v, 5, out_of_range, 1, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    const uint32_t same_index[] = {0, 1, 1};
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_triangles(&w, v, 5, same_index, 1, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    const uint32_t collinear[] = {0, 1, 4};
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_triangles(&w, v, 5, collinear, 1, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    const uint32_t three_on_an_edge[] = {0, 1, 2, 1, 0, 3, 0, 1, 3};
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_triangles(&w, v, 5, three_on_an_edge, 3, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    ck_assert_ptr_null(w.points);
    const uint32_t inconsistent[] = {0, 1, 2, 0, 1, 3};
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_triangles(&w, v, 5, inconsistent, 2, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_triangles(&w, v, 5, NULL, 0, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    const uint32_t consistent[] = {0, 1, 2, 1, 0, 3};
    ck_assert_int_eq(sluice_wall_build_triangles(&w, v, 5, consistent, 2, &reason), 0);
    ck_assert_uint_eq(w.element_count, 2);
    sluice_wall_geometry_free(&w);

    const sluice_real lo[3] = {0, 0, 0}, flat[3] = {1, 0, 1}, hi[3] = {1, 1, 1};
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_tank(&w, 3, lo, flat, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_box(&w, 2, lo, flat, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    reason = NULL;
    ck_assert_int_eq(sluice_wall_build_box(&w, 4, lo, hi, &reason), -1);
    ck_assert_ptr_nonnull(reason);
    /* in 2D the z bounds are not used */
    ck_assert_int_eq(sluice_wall_build_tank(&w, 2, lo, (sluice_real[3]){1, 1, 0}, &reason), 0);
    sluice_wall_geometry_free(&w);
}
END_TEST

static void assert_vec(const sluice_real *v, double x, double y, double z)
{
    ck_assert_msg(fabs(v[0] - x) < EPS && fabs(v[1] - y) < EPS && fabs(v[2] - z) < EPS,
                  "(%.15g, %.15g, %.15g), expected (%g, %g, %g)", v[0], v[1], v[2], x, y, z);
}

START_TEST(wall_normals_2d)
{
    sluice_wall_geometry w;
    const char *reason = NULL;
    const sluice_real lo[3] = {0, 0, 0}, hi[3] = {4, 2.5, 0};
    ck_assert_int_eq(sluice_wall_build_tank(&w, 2, lo, hi, &reason), 0);
    ck_assert_uint_eq(w.dimensions, 2);
    ck_assert_uint_eq(w.element_count, 3);
    assert_vec(w.points + 0, 0, 2.5, 0);
    assert_vec(w.points + 3, 0, 0, 0);
    assert_vec(w.normals + 0, 1, 0, 0); /* into the tank */
    assert_vec(w.normals + 3, 0, 1, 0);
    assert_vec(w.normals + 6, -1, 0, 0);
    const uint8_t open[6] = {1, 0, 0, 0, 0, 1};
    for (int k = 0; k < 6; k++)
        ck_assert_uint_eq(w.open_vertex[k], open[k]);
    const double s = sqrt(0.5);
    assert_vec(w.vertex_normals + 0, 1, 0, 0);  /* open end: the segment normal */
    assert_vec(w.vertex_normals + 3, s, s, 0);  /* bottom-left, end of segment 0 */
    assert_vec(w.vertex_normals + 6, s, s, 0);  /* bottom-left, start of segment 1 */
    assert_vec(w.vertex_normals + 9, -s, s, 0); /* bottom-right */
    assert_vec(w.vertex_normals + 15, -1, 0, 0);
    sluice_wall_geometry_free(&w);

    ck_assert_int_eq(sluice_wall_build_box(&w, 2, lo, hi, &reason), 0);
    ck_assert_uint_eq(w.element_count, 4);
    for (uint32_t e = 0; e < 4; e++) {
        double mx = 0.5 * (w.points[6 * e] + w.points[6 * e + 3]) - 2;
        double my = 0.5 * (w.points[6 * e + 1] + w.points[6 * e + 4]) - 1.25;
        ck_assert(w.normals[3 * e] * mx + w.normals[3 * e + 1] * my > 0); /* out of the box */
        ck_assert(!w.open_vertex[2 * e] && !w.open_vertex[2 * e + 1]);
        /* vertex pseudo-normals point out of the box, diagonally */
        for (int j = 0; j < 2; j++) {
            const sluice_real *v = w.points + 6 * e + 3 * j, *n = w.vertex_normals + 6 * e + 3 * j;
            ck_assert_double_eq_tol(fabs(n[0]), s, EPS);
            ck_assert(n[0] * (v[0] - 2) > 0 && n[1] * (v[1] - 1.25) > 0);
        }
    }
    sluice_wall_geometry_free(&w);
}
END_TEST

START_TEST(wall_normals_3d)
{
    sluice_wall_geometry w;
    const char *reason = NULL;
    const sluice_real lo[3] = {0, 0, 0}, hi[3] = {1, 0.6, 0.5};
    const double centre[3] = {0.5, 0.3, 0.25};
    for (int tank = 1; tank >= 0; tank--) {
        int rc = tank ? sluice_wall_build_tank(&w, 3, lo, hi, &reason)
                      : sluice_wall_build_box(&w, 3, lo, hi, &reason);
        ck_assert_int_eq(rc, 0);
        ck_assert_uint_eq(w.dimensions, 3);
        ck_assert_uint_eq(w.element_count, tank ? 10 : 12);
        int open_edges = 0, top_faces = 0;
        for (uint32_t e = 0; e < w.element_count; e++) {
            const sluice_real *p = w.points + 9 * e, *n = w.normals + 3 * e;
            double to_centre = 0;
            for (int d = 0; d < 3; d++)
                to_centre += n[d] * (centre[d] - (p[d] + p[3 + d] + p[6 + d]) / 3);
            ck_assert(tank ? to_centre > 0 : to_centre < 0);
            top_faces += p[2] == 0.5 && p[5] == 0.5 && p[8] == 0.5;
            for (int j = 0; j < 3; j++) {
                const sluice_real *v = p + 3 * j, *vn = w.vertex_normals + 9 * e + 3 * j;
                const sluice_real *q = p + 3 * ((j + 1) % 3);
                const sluice_real *en = w.edge_normals + 9 * e + 3 * j;
                open_edges += w.open_edge[3 * e + j];
                /* open edges: the top rim of the tank */
                int rim = tank && v[2] == 0.5 && q[2] == 0.5;
                ck_assert_int_eq(w.open_edge[3 * e + j], rim);
                ck_assert_int_eq(w.open_vertex[3 * e + j], tank && v[2] == 0.5);
                /* corner pseudo-normals: the diagonal of the corner */
                const double r3 = 1 / sqrt(3.0);
                double sx = v[0] == 0 ? 1 : -1, sy = v[1] == 0 ? 1 : -1, sz = v[2] == 0 ? 1 : -1;
                if (tank && v[2] == 0)
                    assert_vec(vn, sx * r3, sy * r3, sz * r3);
                if (tank && v[2] == 0.5)
                    assert_vec(vn, sx * sqrt(0.5), sy * sqrt(0.5), 0);
                if (!tank)
                    assert_vec(vn, -sx * r3, -sy * r3, -sz * r3);
                /* edge pseudo-normals: face normal inside a face, diagonal on
                 * the box's edges */
                int axes = (v[0] != q[0]) + (v[1] != q[1]) + (v[2] != q[2]);
                if (axes == 2 || rim) {
                    assert_vec(en, n[0], n[1], n[2]);
                } else {
                    double ex = v[0] == q[0] ? (v[0] == 0 ? 1 : -1) : 0;
                    double ey = v[1] == q[1] ? (v[1] == 0 ? 1 : -1) : 0;
                    double ez = v[2] == q[2] ? (v[2] == 0 ? 1 : -1) : 0;
                    double f = tank ? sqrt(0.5) : -sqrt(0.5);
                    assert_vec(en, f * ex, f * ey, f * ez);
                }
            }
        }
        ck_assert_int_eq(open_edges, tank ? 4 : 0);
        ck_assert_int_eq(top_faces, tank ? 0 : 2);
        sluice_wall_geometry_free(&w);
    }
}
END_TEST

/* -------------------------------------------------------- signed distance -- */

START_TEST(signed_distance_tank_2d)
{
    sluice_wall_geometry w;
    const char *reason = NULL;
    ck_assert_int_eq(
        sluice_wall_build_tank(&w, 2, (sluice_real[3]){0, 0, 0}, (sluice_real[3]){4, 2.5, 0},
                               &reason),
        0);
    uint32_t element = 99;
    ck_assert_double_eq_tol(signed_distance(&w, 2, 1, 0, NULL, &element), 1.0, EPS);
    ck_assert_uint_eq(element, 1);
    assert_sd(&w, 2, -0.5, 0, -0.5, 0);
    assert_sd(&w, -0.3, 1, 0, -0.3, 0);
    assert_sd(&w, 4.2, 1, 0, -0.2, 0);
    assert_sd(&w, 3.9, 1, 0, 0.1, 0);
    assert_sd(&w, 0, 1, 0, 0, 0); /* on the wall */
    /* bottom-left corner, inside and outside */
    assert_sd(&w, 0.1, 0.2, 0, 0.1, 0);
    assert_sd(&w, 0.2, 0.1, 0, 0.1, 0);
    assert_sd(&w, 0.1, 0.1, 0, 0.1, 0);
    assert_sd(&w, -0.3, -0.4, 0, -0.5, 0);
    assert_sd(&w, -0.1, 0.05, 0, -0.1, 0);
    assert_sd(&w, 0.05, -0.1, 0, -0.1, 0);
    assert_sd(&w, -0.1, -0.1, 0, -sqrt(0.02), 0);
    assert_sd(&w, 4.3, -0.4, 0, -0.5, 0);
    /* next to the open top ends: in front of / behind the wall, or beyond it */
    assert_sd(&w, -0.1, 2.4, 0, -0.1, 0);
    assert_sd(&w, 0.1, 2.4, 0, 0.1, 0);
    assert_beyond(&w, -0.1, 2.6, 0);
    assert_beyond(&w, 0.5, 2.7, 0);
    assert_beyond(&w, 3.9, 2.6, 0);
    assert_beyond(&w, 4.3, 2.6, 0);
    assert_beyond(&w, 2, 3, 0);
    assert_beyond(&w, 0, 2.6, 0);
    /* exactly level with the end is not beyond */
    assert_sd(&w, -0.1, 2.5, 0, -0.1, 0);
    sluice_wall_geometry_free(&w);
}
END_TEST

/* The tank [0,1] x [0,0.6] x [0,0.5] (open top) and the box of the same
 * bounds: fixed points at faces, edges and corners, then random points
 * against the closed-form distance to a box. */
START_TEST(signed_distance_3d)
{
    sluice_wall_geometry tank, box;
    const char *reason = NULL;
    const sluice_real lo[3] = {0, 0, 0}, hi[3] = {1, 0.6, 0.5};
    ck_assert_int_eq(sluice_wall_build_tank(&tank, 3, lo, hi, &reason), 0);
    ck_assert_int_eq(sluice_wall_build_box(&box, 3, lo, hi, &reason), 0);

    /* tank: faces */
    assert_sd(&tank, 0.5, 0.3, 0.25, 0.25, 0);
    assert_sd(&tank, -0.2, 0.3, 0.25, -0.2, 0);
    assert_sd(&tank, 0.5, 0.3, -0.1, -0.1, 0);
    assert_sd(&tank, 0.9, 0.3, 0.3, 0.1, 0);
    assert_sd(&tank, 0.5, 0.7, 0.3, -0.1, 0);
    /* tank: edges (bottom, vertical) inside and outside */
    assert_sd(&tank, 0.5, -0.3, -0.4, -0.5, 0);
    assert_sd(&tank, -0.3, -0.4, 0.25, -0.5, 0);
    assert_sd(&tank, 1.3, 0.3, -0.4, -0.5, 0);
    assert_sd(&tank, 0.5, 0.05, 0.05, 0.05, 0);
    assert_sd(&tank, 0.05, 0.05, 0.3, 0.05, 0);
    /* tank: corners */
    assert_sd(&tank, -0.1, -0.2, -0.2, -0.3, 0);
    assert_sd(&tank, 1.2, 0.7, -0.2, -0.3, 0);
    assert_sd(&tank, 0.1, 0.1, 0.1, 0.1, 0);
    assert_sd(&tank, 0.95, 0.55, 0.05, 0.05, 0);
    /* tank: near the open top */
    assert_sd(&tank, -0.1, 0.3, 0.45, -0.1, 0);
    assert_sd(&tank, 0.1, 0.3, 0.45, 0.1, 0);
    assert_sd(&tank, -0.1, -0.1, 0.45, -sqrt(0.02), 0);
    assert_sd(&tank, -0.1, -0.1, 0.5, -sqrt(0.02), 0); /* level with the rim corner */
    assert_beyond(&tank, 0.5, 0.3, 0.6);
    assert_beyond(&tank, -0.1, 0.3, 0.55);
    assert_beyond(&tank, 0.1, 0.3, 0.55);
    assert_beyond(&tank, -0.1, -0.1, 0.6);
    assert_beyond(&tank, 1.1, 0.7, 0.51);
    assert_beyond(&tank, 0.02, 0.01, 0.5001);

    /* box (fluid outside) */
    assert_sd(&box, 0.5, 0.3, 0.25, -0.25, 0);
    assert_sd(&box, 1.2, 0.3, 0.25, 0.2, 0);
    assert_sd(&box, 0.5, 0.3, 0.6, 0.1, 0);
    assert_sd(&box, 1.3, 0.3, 0.9, 0.5, 0);
    assert_sd(&box, 0.5, -0.3, -0.4, 0.5, 0);
    assert_sd(&box, 1.1, 0.8, 0.7, 0.3, 0);
    assert_sd(&box, -0.1, -0.2, -0.2, 0.3, 0);
    assert_sd(&box, 0.9, 0.55, 0.45, -0.05, 0);
    assert_sd(&box, 0.95, 0.5, 0.3, -0.05, 0);
    assert_sd(&box, 1, 0.3, 0.25, 0, 0);

    uint64_t rng = 7;
    const double blo[3] = {0, 0, 0}, bhi[3] = {1, 0.6, 0.5};
    for (int trial = 0; trial < 20000; trial++) {
        double p[3] = {uniform(&rng, -0.4, 1.4), uniform(&rng, -0.4, 1.0),
                       uniform(&rng, -0.4, 0.9)};
        int inside, beyond;
        double dist = box_surface_distance(p, blo, bhi, 3, &inside);
        double d = signed_distance(&box, p[0], p[1], p[2], &beyond, NULL);
        ck_assert_msg(fabs(d - (inside ? -dist : dist)) < 1e-12 && !beyond,
                      "box at (%g, %g, %g): %g, expected %g", p[0], p[1], p[2], d,
                      inside ? -dist : dist);
        d = signed_distance(&tank, p[0], p[1], p[2], &beyond, NULL);
        if (inside) /* the open top is no wall */
            dist = fmin(fmin(fmin(p[0], 1 - p[0]), fmin(p[1], 0.6 - p[1])), p[2]);
        if (p[2] > 0.5 + 1e-9) {
            ck_assert_msg(beyond, "tank at (%g, %g, %g) should be beyond", p[0], p[1], p[2]);
        } else if (p[2] < 0.5 - 1e-9) {
            ck_assert_msg(fabs(d - (inside ? dist : -dist)) < 1e-12 && !beyond,
                          "tank at (%g, %g, %g): %g beyond %d, expected %g", p[0], p[1], p[2],
                          d, beyond, inside ? dist : -dist);
        }
    }
    sluice_wall_geometry_free(&tank);
    sluice_wall_geometry_free(&box);
}
END_TEST

/* Brute-force distance to the segments of a closed polygon. */
static double polygon_distance(const sluice_real *xy, uint32_t n, const sluice_real p[3])
{
    double best = HUGE_VAL;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t m = (k + 1) % n;
        sluice_real a[3] = {xy[2 * k], xy[2 * k + 1], 0}, b[3] = {xy[2 * m], xy[2 * m + 1], 0};
        best = fmin(best, sluice_segment_closest(p, a, b, NULL, NULL));
    }
    return best;
}

/* Closed polylines as obstacles (fluid outside, clockwise): the sign must be
 * negative exactly inside the polygon, at convex and concave corners. */
START_TEST(signed_distance_obstacles_2d)
{
    const sluice_real L_cw[] = {0, 0, 0, 2, 1, 2, 1, 1, 2, 1, 2, 0};
    const sluice_real dart_cw[] = {0, 0, 1, 1, 0, 2, 2, 1};
    const sluice_real box_cw[] = {0.2, 0.4, 0.2, 1.0, 1.2, 1.0, 1.2, 0.4};
    const sluice_real *shapes[] = {L_cw, dart_cw, box_cw};
    const uint32_t counts[] = {6, 4, 4};
    uint64_t rng = 99;
    for (int s = 0; s < 3; s++) {
        sluice_wall_geometry w;
        const char *reason = NULL;
        ck_assert_int_eq(sluice_wall_build_polyline(&w, shapes[s], counts[s], 1, &reason), 0);
        for (int trial = 0; trial < 20000; trial++) {
            sluice_real p[3] = {uniform(&rng, -0.5, 2.5), uniform(&rng, -0.5, 2.5), 0};
            /* also points on the diagonals through the corners */
            if (trial % 4 == 0) {
                uint32_t v = (uint32_t)trial / 4 % counts[s];
                double t = uniform(&rng, -0.3, 0.3);
                p[0] = shapes[s][2 * v] + t;
                p[1] = shapes[s][2 * v + 1] + (trial % 8 ? t : -t);
            }
            int beyond;
            double d = signed_distance(&w, p[0], p[1], 0, &beyond, NULL);
            double dist = polygon_distance(shapes[s], counts[s], p);
            int inside = sluice_point_in_polygon(shapes[s], counts[s], p[0], p[1]);
            if (dist < 1e-9)
                continue;
            ck_assert_msg(fabs(d - (inside ? -dist : dist)) < 1e-12 && !beyond,
                          "shape %d at (%g, %g): %g, expected %g", s, p[0], p[1], d,
                          inside ? -dist : dist);
        }
        sluice_wall_geometry_free(&w);
    }
    /* the box builder gives the same as the clockwise polyline */
    sluice_wall_geometry a, b;
    ck_assert_int_eq(sluice_wall_build_polyline(&a, box_cw, 4, 1, NULL), 0);
    ck_assert_int_eq(sluice_wall_build_box(&b, 2, (sluice_real[3]){0.2, 0.4, 0},
                                           (sluice_real[3]){1.2, 1.0, 0}, NULL),
                     0);
    for (int trial = 0; trial < 1000; trial++) {
        sluice_real p[3] = {uniform(&rng, -0.5, 2), uniform(&rng, -0.5, 2), 0};
        ck_assert_double_eq(sluice_wall_signed_distance(&a, p, NULL, NULL),
                            sluice_wall_signed_distance(&b, p, NULL, NULL));
    }
    sluice_wall_geometry_free(&a);
    sluice_wall_geometry_free(&b);
}
END_TEST

/* Closed meshes with sharp (55 degree) and reflex edges and corners, as
 * obstacles: the sign must say inside/outside exactly, the magnitude must be
 * the distance to the nearest triangle. */
static int tetra_inside(const double p[3])
{
    return p[0] > 0 && p[1] > 0 && p[2] > 0 && p[0] + p[1] + p[2] < 1;
}

static int l_prism_inside(const double p[3])
{
    const sluice_real L[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
    return p[2] > 0 && p[2] < 0.5 && sluice_point_in_polygon(L, 6, p[0], p[1]);
}

START_TEST(signed_distance_meshes_3d)
{
    const sluice_real tetra_v[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const uint32_t tetra_f[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    /* the L polygon (counter-clockwise) extruded over z in [0, 0.5] */
    const sluice_real L[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
    sluice_real prism_v[12 * 3];
    for (int i = 0; i < 12; i++) {
        prism_v[3 * i] = L[2 * (i % 6)];
        prism_v[3 * i + 1] = L[2 * (i % 6) + 1];
        prism_v[3 * i + 2] = i < 6 ? 0 : 0.5;
    }
    uint32_t prism_f[20 * 3], nf = 0;
    const uint32_t cap[4][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}};
    for (int t = 0; t < 4; t++) {
        uint32_t *bottom = prism_f + 3 * nf++, *top = prism_f + 3 * nf++;
        bottom[0] = cap[t][0], bottom[1] = cap[t][2], bottom[2] = cap[t][1]; /* -z */
        top[0] = 6 + cap[t][0], top[1] = 6 + cap[t][1], top[2] = 6 + cap[t][2];
    }
    for (uint32_t i = 0; i < 6; i++) {
        uint32_t j = (i + 1) % 6;
        uint32_t *a = prism_f + 3 * nf++, *b = prism_f + 3 * nf++;
        a[0] = i, a[1] = j, a[2] = 6 + j;
        b[0] = i, b[1] = 6 + j, b[2] = 6 + i;
    }
    const struct {
        const sluice_real *v;
        const uint32_t *f;
        uint32_t nv, nf;
        int (*inside)(const double p[3]);
        double lo[3], hi[3];
    } meshes[] = {
        {tetra_v, tetra_f, 4, 4, tetra_inside, {-0.5, -0.5, -0.5}, {1.5, 1.5, 1.5}},
        {prism_v, prism_f, 12, 20, l_prism_inside, {-0.5, -0.5, -0.5}, {2.5, 2.5, 1.0}},
    };
    uint64_t rng = 5;
    for (int m = 0; m < 2; m++) {
        sluice_wall_geometry w;
        const char *reason = NULL;
        ck_assert_msg(sluice_wall_build_triangles(&w, meshes[m].v, meshes[m].nv, meshes[m].f,
                                                  meshes[m].nf, &reason) == 0,
                      "%s", reason);
        for (uint32_t e = 0; e < 3 * w.element_count; e++)
            ck_assert(!w.open_edge[e] && !w.open_vertex[e]);
        for (int trial = 0; trial < 40000; trial++) {
            double p[3];
            for (int d = 0; d < 3; d++)
                p[d] = uniform(&rng, meshes[m].lo[d], meshes[m].hi[d]);
            if (trial % 2) { /* near a vertex, where the pseudo-normals matter */
                uint32_t v = (uint32_t)trial / 2 % meshes[m].nv;
                for (int d = 0; d < 3; d++)
                    p[d] = meshes[m].v[3 * v + (uint32_t)d] + uniform(&rng, -0.2, 0.2);
            }
            double dist = HUGE_VAL;
            for (uint32_t t = 0; t < meshes[m].nf; t++) {
                const uint32_t *f = meshes[m].f + 3 * t;
                dist = fmin(dist, sluice_triangle_closest((sluice_real[3]){p[0], p[1], p[2]},
                                                          meshes[m].v + 3 * f[0],
                                                          meshes[m].v + 3 * f[1],
                                                          meshes[m].v + 3 * f[2], NULL, NULL));
            }
            if (dist < 1e-9)
                continue;
            int beyond;
            double d = signed_distance(&w, p[0], p[1], p[2], &beyond, NULL);
            double expect = meshes[m].inside(p) ? -dist : dist;
            ck_assert_msg(fabs(d - expect) < 1e-12 && !beyond,
                          "mesh %d at (%g, %g, %g): %g, expected %g", m, p[0], p[1], p[2], d,
                          expect);
        }
        sluice_wall_geometry_free(&w);
    }
}
END_TEST

/* ------------------------------------------------------------ wall layers -- */

static void layer(const sluice_wall_geometry *w, double dx, double thickness, sluice_points *pts)
{
    *pts = (sluice_points){0};
    ck_assert_int_eq(sluice_wall_layer_points(w, dx, (sluice_real[3]){0, 0, 0}, thickness, pts), 0);
}

/* Every point: a lattice point, once, behind the wall within the thickness,
 * not beyond an end. */
static void check_layer_points(const sluice_wall_geometry *w, const sluice_points *pts, double dx,
                               double thickness)
{
    const double zero[3] = {0, 0, 0};
    ck_assert_uint_eq(lattice_keys(pts, w->dimensions, dx, zero, NULL), 0);
    for (size_t i = 0; i < pts->count; i++) {
        int beyond;
        double d = sluice_wall_signed_distance(w, pts->xyz + 3 * i, &beyond, NULL);
        ck_assert_msg(d >= -thickness - 1e-9 * dx && d < 0 && !beyond,
                      "layer point (%g, %g, %g) at signed distance %g beyond %d", pts->xyz[3 * i],
                      pts->xyz[3 * i + 1], pts->xyz[3 * i + 2], d, beyond);
    }
}

START_TEST(layer_tank_2d)
{
    const double dx = 0.02, T = 3 * dx;
    sluice_wall_geometry w;
    ck_assert_int_eq(sluice_wall_build_tank(&w, 2, (sluice_real[3]){0, 0, 0},
                                            (sluice_real[3]){4, 2.5, 0}, NULL),
                     0);
    sluice_points pts;
    layer(&w, dx, T, &pts);
    check_layer_points(&w, &pts, dx, T);
    /* analytic: 3 rows under the 200 bottom cells, 3 columns beside the 125
     * cells of each side, and at each bottom corner the lattice points of a
     * quarter disc of radius 3 spacings (8 of the 9 corner points: the far
     * corner (-0.05, -0.05) is 0.0707 > 0.06 from the wall) */
    long expected = 3 * 200 + 2 * 3 * 125 + 2 * quarter_disc(3);
    ck_assert_int_eq(quarter_disc(3), 8);
    ck_assert_int_eq((long)pts.count, expected);
    int rows[3] = {0, 0, 0};
    double row_min[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, row_max[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    double min_x = HUGE_VAL, max_x = -HUGE_VAL, max_y = -HUGE_VAL;
    int corner_points = 0;
    for (size_t i = 0; i < pts.count; i++) {
        double x = pts.xyz[3 * i], y = pts.xyz[3 * i + 1];
        max_y = fmax(max_y, y);
        ck_assert(!(x > 0 && x < 4 && y > 0)); /* nothing inside the tank */
        if (y < 0) {
            long r = lround((-y / dx - 0.5));
            ck_assert_msg(r >= 0 && r < 3 && fabs(y + (r + 0.5) * dx) < 1e-12,
                          "a point at y = %g under the bottom", y);
            rows[r]++;
            row_min[r] = fmin(row_min[r], x);
            row_max[r] = fmax(row_max[r], x);
            min_x = fmin(min_x, x);
            max_x = fmax(max_x, x);
            if (x < 0 || x > 4) {
                corner_points++;
                double cx = x < 0 ? x : x - 4;
                ck_assert(cx * cx + y * y <= T * T);
            }
        }
    }
    ck_assert_int_eq(corner_points, 16);
    /* three layers below the bottom spanning x from -0.05 to 4.05 */
    ck_assert_double_eq_tol(min_x, -0.05, 1e-12);
    ck_assert_double_eq_tol(max_x, 4.05, 1e-12);
    ck_assert_int_eq(rows[0], 206);
    ck_assert_int_eq(rows[1], 206);
    ck_assert_int_eq(rows[2], 204);
    ck_assert_double_eq_tol(row_min[0], -0.05, 1e-12);
    ck_assert_double_eq_tol(row_max[1], 4.05, 1e-12);
    ck_assert_double_eq_tol(row_min[2], -0.03, 1e-12);
    ck_assert_double_eq_tol(row_max[2], 4.03, 1e-12);
    /* nothing beside the open top: the highest points are the last row below it */
    ck_assert_double_eq_tol(max_y, 2.49, 1e-12);
    ck_assert(max_y <= 2.5 + dx);
    sluice_points_free(&pts);

    /* a thicker layer only adds points; thickness 0 gives none here */
    layer(&w, dx, 5 * dx, &pts);
    ck_assert_int_eq((long)pts.count, 5 * 200 + 2 * 5 * 125 + 2 * quarter_disc(5));
    sluice_points_free(&pts);
    layer(&w, dx, 0, &pts);
    ck_assert_uint_eq(pts.count, 0);
    sluice_points_free(&pts);
    sluice_wall_geometry_free(&w);
}
END_TEST

START_TEST(layer_tank_3d)
{
    const double dx = 0.05, T = 3 * dx;
    sluice_wall_geometry w;
    ck_assert_int_eq(sluice_wall_build_tank(&w, 3, (sluice_real[3]){0, 0, 0},
                                            (sluice_real[3]){1, 0.6, 0.5}, NULL),
                     0);
    sluice_points pts;
    layer(&w, dx, T, &pts);
    check_layer_points(&w, &pts, dx, T);
    const long nx = 20, ny = 12, nz = 10;
    /* bottom slab, side slabs, vertical edges, bottom edges, bottom corners */
    long expected = 3 * nx * ny + 3 * nz * 2 * (nx + ny) + 4 * nz * quarter_disc(3) +
                    2 * (nx + ny) * quarter_disc(3) + 4 * ball_octant(3);
    ck_assert_int_eq(ball_octant(3), 17);
    ck_assert_int_eq(expected, 3540);
    ck_assert_int_eq((long)pts.count, expected);
    double max_z = -HUGE_VAL;
    int bottom_rows[3] = {0, 0, 0};
    for (size_t i = 0; i < pts.count; i++) {
        const sluice_real *p = pts.xyz + 3 * i;
        max_z = fmax(max_z, p[2]);
        int inside = p[0] > 0 && p[0] < 1 && p[1] > 0 && p[1] < 0.6 && p[2] > 0;
        ck_assert(!inside);
        if (p[0] > 0 && p[0] < 1 && p[1] > 0 && p[1] < 0.6) {
            long r = lround(-p[2] / dx - 0.5);
            ck_assert(r >= 0 && r < 3);
            bottom_rows[r]++;
        }
    }
    for (int r = 0; r < 3; r++)
        ck_assert_int_eq(bottom_rows[r], nx * ny);
    ck_assert_double_eq_tol(max_z, 0.475, 1e-12);
    sluice_points_free(&pts);
    sluice_wall_geometry_free(&w);
}
END_TEST

/* A 30 degree wall: the layer is exactly the lattice points behind it within
 * the thickness whose projection falls on the segment. */
START_TEST(layer_slanted_2d)
{
    const double dx = 0.02, T = 3 * dx;
    const double c30 = cos(M_PI / 6), s30 = sin(M_PI / 6);
    const double a[2] = {0.1, 0.2}, b[2] = {0.1 + 2 * c30, 0.2 + 2 * s30};
    const sluice_real xy[4] = {a[0], a[1], b[0], b[1]};
    sluice_wall_geometry w;
    ck_assert_int_eq(sluice_wall_build_polyline(&w, xy, 2, 0, NULL), 0);
    sluice_points pts;
    layer(&w, dx, T, &pts);
    check_layer_points(&w, &pts, dx, T);
    const double n[2] = {-s30, c30}, u[2] = {c30, s30};
    for (size_t i = 0; i < pts.count; i++) {
        double px = pts.xyz[3 * i] - a[0], py = pts.xyz[3 * i + 1] - a[1];
        double behind = px * n[0] + py * n[1], t = (px * u[0] + py * u[1]) / 2;
        ck_assert(behind < 0 && behind >= -T - 1e-12);
        ck_assert(t >= -1e-9 && t <= 1 + 1e-9);
    }
    long brute = 0;
    for (long j = -10; j < 100; j++)
        for (long i = -10; i < 120; i++) {
            double px = (i + 0.5) * dx - a[0], py = (j + 0.5) * dx - a[1];
            double behind = px * n[0] + py * n[1], t = (px * u[0] + py * u[1]) / 2;
            brute += behind <= 0 && behind >= -T && t >= 0 && t <= 1;
        }
    ck_assert_int_eq((long)pts.count, brute);
    ck_assert_int_gt(brute, 200);
    sluice_points_free(&pts);
    sluice_wall_geometry_free(&w);

    /* a tank with slanted sides: every layer point is outside the tank,
     * within the thickness of the wall */
    const sluice_real trap[] = {0, 2, 0.5, 0, 3.5, 0, 4, 2};
    ck_assert_int_eq(sluice_wall_build_polyline(&w, trap, 4, 0, NULL), 0);
    layer(&w, dx, T, &pts);
    check_layer_points(&w, &pts, dx, T);
    ck_assert_int_gt((long)pts.count, 2.5 * 7.1 / dx);
    for (size_t i = 0; i < pts.count; i++) {
        const sluice_real *p = pts.xyz + 3 * i;
        ck_assert(!sluice_point_in_polygon(trap, 4, p[0], p[1]));
        double dist = HUGE_VAL;
        for (int s = 0; s < 3; s++) {
            sluice_real sa[3] = {trap[2 * s], trap[2 * s + 1], 0};
            sluice_real sb[3] = {trap[2 * s + 2], trap[2 * s + 3], 0};
            dist = fmin(dist, sluice_segment_closest(p, sa, sb, NULL, NULL));
        }
        ck_assert(dist > 0 && dist <= T + 1e-12);
        ck_assert(p[1] < 2);
    }
    sluice_points_free(&pts);
    sluice_wall_geometry_free(&w);
}
END_TEST

START_TEST(layer_box_obstacles)
{
    /* 2D: the box [0.2, 1.2] x [0.4, 1.0], 50 x 30 cells, layer inside */
    const double dx = 0.02, T = 3 * dx;
    sluice_wall_geometry w;
    const sluice_real lo2[3] = {0.2, 0.4, 0}, hi2[3] = {1.2, 1.0, 0};
    ck_assert_int_eq(sluice_wall_build_box(&w, 2, lo2, hi2, NULL), 0);
    sluice_points pts;
    layer(&w, dx, T, &pts);
    check_layer_points(&w, &pts, dx, T);
    ck_assert_int_eq((long)pts.count, 50 * 30 - 44 * 24);
    sluice_region r2 = {.shape = SLUICE_REGION_BOX, .min = {0.2, 0.4, 0}, .max = {1.2, 1.0, 0}};
    for (size_t i = 0; i < pts.count; i++)
        ck_assert(sluice_region_contains(&r2, 2, pts.xyz + 3 * i));
    sluice_points_free(&pts);
    sluice_wall_geometry_free(&w);

    /* 3D: [0,1] x [0,0.6] x [0,0.5] at 0.05, 20 x 12 x 10 cells */
    const double dx3 = 0.05, T3 = 3 * dx3;
    ck_assert_int_eq(sluice_wall_build_box(&w, 3, (sluice_real[3]){0, 0, 0},
                                           (sluice_real[3]){1, 0.6, 0.5}, NULL),
                     0);
    layer(&w, dx3, T3, &pts);
    check_layer_points(&w, &pts, dx3, T3);
    ck_assert_int_eq((long)pts.count, 20 * 12 * 10 - 14 * 6 * 4);
    sluice_region r3 = {.shape = SLUICE_REGION_BOX, .min = {0, 0, 0}, .max = {1, 0.6, 0.5}};
    for (size_t i = 0; i < pts.count; i++)
        ck_assert(sluice_region_contains(&r3, 3, pts.xyz + 3 * i));
    sluice_points_free(&pts);
    /* a box thinner than twice the thickness is filled completely */
    sluice_wall_geometry_free(&w);
    ck_assert_int_eq(sluice_wall_build_box(&w, 3, (sluice_real[3]){0, 0, 0},
                                           (sluice_real[3]){0.2, 0.6, 0.5}, NULL),
                     0);
    layer(&w, dx3, T3, &pts);
    ck_assert_int_eq((long)pts.count, 4 * 12 * 10);
    sluice_points_free(&pts);
    sluice_wall_geometry_free(&w);
}
END_TEST

/* ---------------------------------------------------------------- scale -- */

START_TEST(fill_million)
{
    sluice_region box = {.shape = SLUICE_REGION_BOX, .min = {0, 0, 0}, .max = {1, 1, 0}};
    sluice_points pts = {0};
    double t0 = seconds();
    ck_assert_int_eq(sluice_region_fill(&box, 2, 0.001, NULL, &pts), 0);
    double t1 = seconds();
    ck_assert_uint_eq(pts.count, 1000000);
    sluice_points_free(&pts);
    const sluice_real L[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 2, 0, 2};
    sluice_region poly = {.shape = SLUICE_REGION_POLYGON, .polygon = L, .vertex_count = 6};
    double t2 = seconds();
    ck_assert_int_eq(sluice_region_fill(&poly, 2, 0.002, NULL, &pts), 0);
    double t3 = seconds();
    ck_assert_uint_eq(pts.count, 750000);
    sluice_points_free(&pts);
    printf("fill: 1e6 box points %.3f s, 7.5e5 polygon points %.3f s\n", t1 - t0, t3 - t2);
    ck_assert(t1 - t0 < 10 && t3 - t2 < 10);
}
END_TEST

/* A circle of 10^4 segments, as an obstacle: layer inside the ring. */
START_TEST(layer_many_segments)
{
    const uint32_t n = 10000;
    const double R = 0.5, dx = 0.001, T = 3 * dx;
    sluice_real *xy = malloc(2 * n * sizeof *xy);
    ck_assert_ptr_nonnull(xy);
    for (uint32_t k = 0; k < n; k++) { /* clockwise: fluid outside */
        xy[2 * k] = 0.5 + R * cos(-2 * M_PI * k / n);
        xy[2 * k + 1] = 0.5 + R * sin(-2 * M_PI * k / n);
    }
    sluice_wall_geometry w;
    ck_assert_int_eq(sluice_wall_build_polyline(&w, xy, n, 1, NULL), 0);
    sluice_points pts;
    double t0 = seconds();
    layer(&w, dx, T, &pts);
    double t1 = seconds();
    printf("layer of %u segments: %zu points in %.3f s\n", n, pts.count, t1 - t0);
    ck_assert(t1 - t0 < 10);
    ck_assert_uint_eq(lattice_keys(&pts, 2, dx, (double[3]){0, 0, 0}, NULL), 0);
    const double sagitta = R * (1 - cos(M_PI / n));
    for (size_t i = 0; i < pts.count; i++) {
        double r = hypot(pts.xyz[3 * i] - 0.5, pts.xyz[3 * i + 1] - 0.5);
        ck_assert(r < R && r >= R - T - sagitta - 1e-12);
    }
    long brute = 0;
    for (long j = 0; j < 1000; j++)
        for (long i = 0; i < 1000; i++) {
            double r = hypot((i + 0.5) * dx - 0.5, (j + 0.5) * dx - 0.5);
            brute += r < R - sagitta && r >= R - T;
        }
    /* all points certainly in the layer, and hardly more */
    ck_assert_int_ge((long)pts.count, brute);
    ck_assert_int_le((long)pts.count, brute + 200);
    sluice_points_free(&pts);
    sluice_wall_geometry_free(&w);
    free(xy);
}
END_TEST

/* The unit cube with every face cut into m x m squares (2 m^2 triangles):
 * the same signed distance and the same layer as the 12-triangle box. */
START_TEST(layer_many_triangles)
{
    const uint32_t m = 29; /* 6 * 2 * 29^2 = 10092 triangles */
    const uint32_t side = m + 1;
    uint32_t *index = malloc((size_t)side * side * side * sizeof *index);
    sluice_real *vertices = malloc((size_t)side * side * side * 3 * sizeof *vertices);
    uint32_t *faces = malloc((size_t)6 * 2 * m * m * 3 * sizeof *faces);
    ck_assert(index && vertices && faces);
    uint32_t nv = 0, nf = 0;
    for (uint32_t k = 0; k < side; k++)
        for (uint32_t j = 0; j < side; j++)
            for (uint32_t i = 0; i < side; i++) {
                size_t at = ((size_t)k * side + j) * side + i;
                int surface = i == 0 || j == 0 || k == 0 || i == m || j == m || k == m;
                index[at] = surface ? nv : UINT32_MAX;
                if (surface) {
                    vertices[3 * nv] = (double)i / m;
                    vertices[3 * nv + 1] = (double)j / m;
                    vertices[3 * nv + 2] = (double)k / m;
                    nv++;
                }
            }
    /* each face: axis `a` fixed at 0 or m; (u, v) the other two axes */
    for (int a = 0; a < 3; a++)
        for (int high = 0; high < 2; high++)
            for (uint32_t u = 0; u < m; u++)
                for (uint32_t v = 0; v < m; v++) {
                    uint32_t q[4];
                    const uint32_t du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
                    for (int c = 0; c < 4; c++) {
                        uint32_t g[3];
                        g[a] = high ? m : 0;
                        g[(a + 1) % 3] = u + du[c];
                        g[(a + 2) % 3] = v + dv[c];
                        q[c] = index[((size_t)g[2] * side + g[1]) * side + g[0]];
                    }
                    /* (u, v, a) is right-handed: the cycle's normal is +a;
                     * outward is +a on the high face */
                    if (!high) {
                        uint32_t t = q[1];
                        q[1] = q[3];
                        q[3] = t;
                    }
                    uint32_t *f = faces + 3 * nf;
                    f[0] = q[0], f[1] = q[1], f[2] = q[2];
                    f[3] = q[0], f[4] = q[2], f[5] = q[3];
                    nf += 2;
                }
    ck_assert_uint_eq(nf, 10092);
    sluice_wall_geometry fine, coarse;
    const char *reason = NULL;
    ck_assert_msg(sluice_wall_build_triangles(&fine, vertices, nv, faces, nf, &reason) == 0, "%s",
                  reason);
    ck_assert_int_eq(sluice_wall_build_box(&coarse, 3, (sluice_real[3]){0, 0, 0},
                                           (sluice_real[3]){1, 1, 1}, NULL),
                     0);
    for (uint32_t e = 0; e < fine.element_count * 3; e++)
        ck_assert(!fine.open_edge[e]);
    uint64_t rng = 3;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    for (int trial = 0; trial < 300; trial++) {
        double p[3] = {uniform(&rng, -0.3, 1.3), uniform(&rng, -0.3, 1.3),
                       uniform(&rng, -0.3, 1.3)};
        int inside, beyond;
        double dist = box_surface_distance(p, lo, hi, 3, &inside);
        double d = signed_distance(&fine, p[0], p[1], p[2], &beyond, NULL);
        ck_assert_msg(fabs(d - (inside ? -dist : dist)) < 1e-12 && !beyond,
                      "(%g, %g, %g): %g, expected %g", p[0], p[1], p[2], d, inside ? -dist : dist);
    }
    const double dx = 0.02, T = 3 * dx;
    sluice_points a, b;
    double t0 = seconds();
    layer(&fine, dx, T, &a);
    double t1 = seconds();
    printf("layer of %u triangles: %zu points in %.3f s\n", nf, a.count, t1 - t0);
    ck_assert(t1 - t0 < 10);
    layer(&coarse, dx, T, &b);
    ck_assert_uint_eq(b.count, 50 * 50 * 50 - 44 * 44 * 44);
    ck_assert_uint_eq(a.count, b.count);
    key3 *ka, *kb;
    ck_assert_uint_eq(lattice_keys(&a, 3, dx, lo, &ka), 0);
    ck_assert_uint_eq(lattice_keys(&b, 3, dx, lo, &kb), 0);
    ck_assert_int_eq(memcmp(ka, kb, a.count * sizeof *ka), 0);
    free(ka);
    free(kb);
    sluice_points_free(&a);
    sluice_points_free(&b);
    sluice_wall_geometry_free(&fine);
    sluice_wall_geometry_free(&coarse);
    free(index);
    free(vertices);
    free(faces);
}
END_TEST

/* The watchdog's wall cells (wall_watch.c) give, wherever they compute it, the
 * same signed distance as asking every element (bit for bit), and skip only
 * points that are truly farther than the allowed depth on the fluid side. A
 * 2D scene of several walls (a tank, an open polyline with a step and a
 * jet-like overhang, a closed obstacle) and a 3D tank with a box obstacle. */
static void check_watch(const sluice_wall_watch *watch, const sluice_real p[3], double depth)
{
    int b1, b2;
    uint32_t w1, w2, e1, e2;
    double fast = sluice_wall_watch_distance(watch, p, &b1, &w1, &e1);
    double full = sluice_wall_watch_distance_full(watch, p, &b2, &w2, &e2);
    if (fast == HUGE_VAL && !b1) {
        /* skipped: must be in front, farther than the depth (or past an end) */
        ck_assert_msg(full == HUGE_VAL || full > depth,
                      "(%g, %g, %g) skipped but its distance is %g", p[0], p[1], p[2], full);
        return;
    }
    ck_assert_msg(fast == full && b1 == b2 && w1 == w2 && e1 == e2,
                  "(%g, %g, %g): cells %g (wall %u element %u beyond %d), full %g (wall %u "
                  "element %u beyond %d)",
                  p[0], p[1], p[2], fast, w1, e1, b1, full, w2, e2, b2);
}

START_TEST(wall_watch_matches_full_query)
{
    uint64_t rng = 2026;
    /* 2D */
    const sluice_real bed[] = {-0.5, 0.3, 0.6, 0.3, 0.6, 0.0, 2.0, 0.0, 2.0, 0.1, 3.0, 0.1};
    const sluice_real obstacle[] = {1.2, 0.4, 1.2, 0.6, 1.5, 0.6, 1.5, 0.4};
    sluice_wall_geometry g[3];
    ck_assert_int_eq(sluice_wall_build_tank(&g[0], 2, (sluice_real[3]){-1, -0.2, 0},
                                            (sluice_real[3]){3.5, 1.5, 0}, NULL),
                     0);
    ck_assert_int_eq(sluice_wall_build_polyline(&g[1], bed, 6, 0, NULL), 0);
    ck_assert_int_eq(sluice_wall_build_polyline(&g[2], obstacle, 4, 1, NULL), 0);
    const sluice_wall_geometry *walls[3] = {&g[0], &g[1], &g[2]};
    const double lo[3] = {-1.2, -0.4, 0}, hi[3] = {3.7, 1.8, 0};
    for (int depth_case = 0; depth_case < 2; depth_case++) {
        const double depth = depth_case ? 0.05 : 0.005;
        sluice_wall_watch watch;
        ck_assert_int_eq(sluice_wall_watch_init(&watch, 2, walls, 3, lo, hi, 0.04, depth), 0);
        size_t front = 0, near = 0, behind = 0;
        for (size_t c = 0; c < watch.cells.cell_count; c++) {
            front += watch.state[c] == SLUICE_WALL_CELL_FRONT;
            near += watch.state[c] == SLUICE_WALL_CELL_NEAR;
            behind += watch.state[c] == SLUICE_WALL_CELL_BEHIND;
        }
        /* the cells must save work: most of the box is far from every wall */
        ck_assert_msg(front > near && behind > 0, "front %zu near %zu behind %zu", front, near,
                      behind);
        for (int trial = 0; trial < 200000; trial++) {
            sluice_real p[3] = {uniform(&rng, -1.3, 3.8), uniform(&rng, -0.5, 1.9), 0};
            if (trial % 3 == 0) { /* close to a vertex of the bed or the obstacle */
                const sluice_real *v = trial % 2 ? bed + 2 * (trial / 3 % 6)
                                                 : obstacle + 2 * (trial / 3 % 4);
                p[0] = v[0] + uniform(&rng, -0.1, 0.1);
                p[1] = v[1] + uniform(&rng, -0.1, 0.1);
            }
            check_watch(&watch, p, depth);
        }
        sluice_wall_watch_free(&watch);
    }
    for (int k = 0; k < 3; k++)
        sluice_wall_geometry_free(&g[k]);
    /* 3D */
    sluice_wall_geometry tank, box;
    ck_assert_int_eq(sluice_wall_build_tank(&tank, 3, (sluice_real[3]){0, 0, 0},
                                            (sluice_real[3]){2, 1, 1}, NULL),
                     0);
    ck_assert_int_eq(sluice_wall_build_box(&box, 3, (sluice_real[3]){1.2, 0.3, 0},
                                           (sluice_real[3]){1.5, 0.6, 0.3}, NULL),
                     0);
    const sluice_wall_geometry *walls3[2] = {&tank, &box};
    const double lo3[3] = {-0.2, -0.2, -0.2}, hi3[3] = {2.2, 1.2, 1.5};
    sluice_wall_watch watch;
    ck_assert_int_eq(sluice_wall_watch_init(&watch, 3, walls3, 2, lo3, hi3, 0.05, 0.01), 0);
    for (int trial = 0; trial < 200000; trial++) {
        sluice_real p[3] = {uniform(&rng, -0.3, 2.3), uniform(&rng, -0.3, 1.3),
                            uniform(&rng, -0.3, 1.6)};
        if (trial % 2 == 0) { /* near the obstacle's corners and edges */
            p[0] = (trial % 4 ? 1.2 : 1.5) + uniform(&rng, -0.06, 0.06);
            p[1] = (trial % 8 < 4 ? 0.3 : 0.6) + uniform(&rng, -0.06, 0.06);
            p[2] = uniform(&rng, -0.05, 0.35);
        }
        check_watch(&watch, p, 0.01);
    }
    sluice_wall_watch_free(&watch);
    sluice_wall_geometry_free(&tank);
    sluice_wall_geometry_free(&box);
}
END_TEST

/* The nearest-wall distance of the index (api->walls->wall_distance) against every
 * element of every wall: the same number, bit for bit, for points in the
 * index's box, near the walls' vertices and corners, and far outside the
 * box (where every element is asked), with the cell size of a kernel
 * support and with one so small that the budget enlarges it. */
static void check_wall_distance(const sluice_wall_distance_index *index,
                                const sluice_wall_geometry *const *walls, size_t count,
                                const sluice_real p[3])
{
    double brute = HUGE_VAL;
    for (size_t w = 0; w < count; w++) {
        const double d = fabs((double)sluice_wall_signed_distance(walls[w], p, NULL, NULL));
        brute = d < brute ? d : brute;
    }
    const double fast = sluice_wall_distance(index, p);
    ck_assert_msg(fast == brute, "(%g, %g, %g): index %.17g, every element %.17g", (double)p[0],
                  (double)p[1], (double)p[2], fast, brute);
    ck_assert(sluice_wall_distance_full(index, p) == brute);
}

START_TEST(wall_distance_matches_every_element)
{
    uint64_t rng = 2027;
    /* 2D: a tank, a chute of 40 steps (80 segments) and a closed obstacle */
    sluice_real chute[2 * 81];
    for (int k = 0; k <= 80; k++) {
        const int step = k / 2;
        chute[2 * k] = (sluice_real)(0.1 * (step + (k % 2)));
        chute[2 * k + 1] = (sluice_real)(2.0 - 0.05 * step);
    }
    const sluice_real obstacle[] = {2.2, 0.4, 2.2, 0.6, 2.5, 0.6, 2.5, 0.4};
    sluice_wall_geometry g[3];
    ck_assert_int_eq(sluice_wall_build_tank(&g[0], 2, (sluice_real[3]){-1, -0.2, 0},
                                            (sluice_real[3]){4.5, 2.5, 0}, NULL),
                     0);
    ck_assert_int_eq(sluice_wall_build_polyline(&g[1], chute, 81, 0, NULL), 0);
    ck_assert_int_eq(sluice_wall_build_polyline(&g[2], obstacle, 4, 1, NULL), 0);
    const sluice_wall_geometry *walls[3] = {&g[0], &g[1], &g[2]};
    for (int size_case = 0; size_case < 2; size_case++) {
        sluice_wall_distance_index index;
        const double lo[3] = {-1.5, -0.5, 0}, hi[3] = {5, 3, 0};
        ck_assert_int_eq(
            sluice_wall_distance_init(&index, 2, walls, 3, lo, hi, size_case ? 1e-4 : 0.045), 0);
        /* the cells must save work: a cell's list holds on average at most a
         * tenth of the 87 elements that a query would otherwise ask */
        ck_assert_uint_gt(index.cells.cell_count, 1000);
        ck_assert_double_le((double)index.cells.candidate_count / (double)index.cells.cell_count, 87 / 10.0);
        for (int trial = 0; trial < 100000; trial++) {
            sluice_real p[3] = {uniform(&rng, -3, 6.5), uniform(&rng, -2, 4.5), 0};
            if (trial % 3 == 0) { /* close to a step's corner */
                const sluice_real *v = chute + 2 * (trial / 3 % 81);
                p[0] = v[0] + uniform(&rng, -0.06, 0.06);
                p[1] = v[1] + uniform(&rng, -0.06, 0.06);
            } else if (trial % 3 == 1 && trial % 7 == 0) { /* far outside */
                p[0] = uniform(&rng, -40, 40);
                p[1] = uniform(&rng, -40, 40);
            }
            check_wall_distance(&index, walls, 3, p);
        }
        sluice_wall_distance_free(&index);
    }
    for (int k = 0; k < 3; k++)
        sluice_wall_geometry_free(&g[k]);
    /* no walls: no distance */
    sluice_wall_distance_index none;
    ck_assert_int_eq(sluice_wall_distance_init(&none, 2, NULL, 0, (double[3]){0, 0, 0},
                                               (double[3]){1, 1, 0}, 0.05),
                     0);
    ck_assert(sluice_wall_distance(&none, (sluice_real[3]){0, 0, 0}) == HUGE_VAL);
    sluice_wall_distance_free(&none);
    /* 3D: a tank and a box obstacle on its floor */
    sluice_wall_geometry tank, box;
    ck_assert_int_eq(sluice_wall_build_tank(&tank, 3, (sluice_real[3]){0, 0, 0},
                                            (sluice_real[3]){2, 1, 1}, NULL),
                     0);
    ck_assert_int_eq(sluice_wall_build_box(&box, 3, (sluice_real[3]){1.2, 0.3, 0},
                                           (sluice_real[3]){1.5, 0.6, 0.3}, NULL),
                     0);
    const sluice_wall_geometry *walls3[2] = {&tank, &box};
    sluice_wall_distance_index index;
    ck_assert_int_eq(sluice_wall_distance_init(&index, 3, walls3, 2, (double[3]){-0.2, -0.2, -0.2},
                                               (double[3]){2.2, 1.2, 1.5}, 0.1),
                     0);
    for (int trial = 0; trial < 100000; trial++) {
        sluice_real p[3] = {uniform(&rng, -1, 3), uniform(&rng, -1, 2), uniform(&rng, -1, 2)};
        if (trial % 2 == 0) { /* near the obstacle's corners and edges */
            p[0] = (trial % 4 ? 1.2 : 1.5) + uniform(&rng, -0.06, 0.06);
            p[1] = (trial % 8 < 4 ? 0.3 : 0.6) + uniform(&rng, -0.06, 0.06);
            p[2] = uniform(&rng, -0.05, 0.35);
        }
        check_wall_distance(&index, walls3, 2, p);
    }
    sluice_wall_distance_free(&index);
    sluice_wall_geometry_free(&tank);
    sluice_wall_geometry_free(&box);
}
END_TEST

/* ------------------------------------------------------------- profiles -- */

/* Builds a profile (test helper: refusal is a failure). */
static void build_profile(const sluice_profile_piece *pieces, uint32_t count, double x0, double y0,
                          int has_heading, double heading, int closed, double max_segment,
                          sluice_profile_path *path)
{
    sluice_profile profile = {{x0, y0}, has_heading, heading, pieces, count, closed, max_segment};
    sluice_profile_problem problem;
    int rc = sluice_profile_build(&profile, path, &problem);
    ck_assert_msg(rc == 0, "profile refused: piece %u: %s", problem.piece, problem.message);
}

/* The profile is refused for piece `piece` (key `key`, NULL: none) with a
 * message containing `needle`. */
static void refuse_profile(const sluice_profile_piece *pieces, uint32_t count, int has_heading,
                           double heading, int closed, uint32_t piece, const char *key,
                           const char *needle)
{
    sluice_profile profile = {{0, 0}, has_heading, heading, pieces, count, closed, 0.01};
    sluice_profile_path path;
    sluice_profile_problem problem;
    ck_assert_int_eq(sluice_profile_build(&profile, &path, &problem), -1);
    ck_assert_ptr_null(path.xy);
    ck_assert_msg(problem.piece == piece, "refused at piece %u, expected %u (%s)", problem.piece,
                  piece, problem.message);
    ck_assert_msg((key == NULL && problem.key == NULL) ||
                      (key && problem.key && strcmp(key, problem.key) == 0),
                  "refused for key %s, expected %s (%s)", problem.key ? problem.key : "(none)",
                  key ? key : "(none)", problem.message);
    ck_assert_msg(strstr(problem.message, needle), "'%s' not in '%s'", needle, problem.message);
}

static double vertex_x(const sluice_profile_path *p, uint32_t v)
{
    return (double)p->xy[2 * v];
}

static double vertex_y(const sluice_profile_path *p, uint32_t v)
{
    return (double)p->xy[2 * v + 1];
}

static double chord(const sluice_profile_path *p, uint32_t v)
{
    return hypot(vertex_x(p, v + 1) - vertex_x(p, v), vertex_y(p, v + 1) - vertex_y(p, v));
}

/* Signed turning angle (rad, > 0 counter-clockwise) at vertex v. */
static double turning(const sluice_profile_path *p, uint32_t v)
{
    double ux = vertex_x(p, v) - vertex_x(p, v - 1), uy = vertex_y(p, v) - vertex_y(p, v - 1);
    double wx = vertex_x(p, v + 1) - vertex_x(p, v), wy = vertex_y(p, v + 1) - vertex_y(p, v);
    return atan2(ux * wy - uy * wx, ux * wx + uy * wy);
}

/* |a - b| within a few units of round-off of their magnitude. */
static void assert_exact(double a, double b, const char *what, uint32_t v)
{
    double tol = 4 * DBL_EPSILON * fmax(1.0, fmax(fabs(a), fabs(b)));
    ck_assert_msg(fabs(a - b) <= tol, "%s of vertex %u: %.17g, expected %.17g", what, v, a, b);
}

static sluice_profile_piece line_to(double x, double y)
{
    sluice_profile_piece p = {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_TO};
    p.to[0] = x;
    p.to[1] = y;
    return p;
}

/* Seed 001's Chanson flight: 9 steps, 0.1 m high, 0.25 m long, from the
 * crest's downstream edge. Every corner is exactly where the nominal
 * dimensions put it, and the pseudo-bottom through the step edges slopes at
 * atan(0.1 / 0.25) = 21.80 deg, the seed's 21.8 deg (printed to 0.1 deg). */
START_TEST(profile_steps)
{
    const double x0 = 1.4, y0 = 0.9, h = 0.1, l = 0.25;
    for (int tread_first = 0; tread_first < 2; tread_first++) {
        sluice_profile_piece pieces[2] = {
            {.kind = SLUICE_PIECE_STEPS, .count = 9, .height = h, .step_length = l,
             .tread_first = tread_first},
            {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_LENGTH, .length = 0.5}};
        sluice_profile_path p;
        build_profile(pieces, 2, x0, y0, 0, 0, 0, 0.004, &p);
        ck_assert_uint_eq(p.vertex_count, 1 + 2 * 9 + 1);
        for (uint32_t i = 0; i < 9; i++) {
            double k = i, k1 = i + 1.0;
            double corner_x = tread_first ? x0 + k1 * l : x0 + k * l;
            double corner_y = tread_first ? y0 - k * h : y0 - k1 * h;
            assert_exact(vertex_x(&p, 2 * i + 1), corner_x, "x", 2 * i + 1);
            assert_exact(vertex_y(&p, 2 * i + 1), corner_y, "y", 2 * i + 1);
            assert_exact(vertex_x(&p, 2 * i + 2), x0 + k1 * l, "x", 2 * i + 2);
            assert_exact(vertex_y(&p, 2 * i + 2), y0 - k1 * h, "y", 2 * i + 2);
            ck_assert_uint_eq(p.piece[2 * i + 1], 0);
            ck_assert_uint_eq(p.piece[2 * i + 2], 0);
        }
        ck_assert_uint_eq(p.piece[0], UINT32_MAX);
        ck_assert_uint_eq(p.piece[19], 1);
        /* the line after the flight continues the last segment: the tread
         * (+x), or the riser (-y) when the tread comes first */
        if (tread_first) {
            assert_exact(vertex_x(&p, 19), x0 + 9 * l, "x", 19);
            assert_exact(vertex_y(&p, 19), y0 - 9 * h - 0.5, "y", 19);
        } else {
            assert_exact(vertex_x(&p, 19), x0 + 9 * l + 0.5, "x", 19);
            assert_exact(vertex_y(&p, 19), y0 - 9 * h, "y", 19);
        }
        /* the pseudo-bottom: step edge 1 to step edge 9 (riser first: the
         * ends of the treads, vertices 2, 4, ..., 18) */
        if (!tread_first) {
            double angle = atan2(vertex_y(&p, 2) - vertex_y(&p, 18),
                                 vertex_x(&p, 18) - vertex_x(&p, 2)) * 180 / M_PI;
            fprintf(stderr, "profile_steps: pseudo-bottom %.6f deg (seed 001: 21.8)\n", angle);
            ck_assert_double_eq_tol(angle, atan(h / l) * 180 / M_PI, 1e-12);
            ck_assert(fabs(angle - 21.8) <= 0.05);
        }
        sluice_profile_path_free(&p);
    }
}
END_TEST

/* The broad-crested weir's rounded upstream corner (seed 001, Chanson:
 * r = 0.057 m) between the vertical face and the crest, at max_segment =
 * dx/2 = 0.004 m: every arc vertex on the circle (to round-off), m =
 * ceil(r pi/2 / max_segment) equal chords, each vertex turning by pi/(2m),
 * half of it where the arc meets the straight face and crest (tangent
 * continuity: the chord from the tangent point is pi/(4m) off the tangent),
 * and the chords' total r pi/2 - 2 r m sin(pi/(4m)) short of the arc length,
 * within the chord error bound r theta (theta/m)^2 / 24. */
START_TEST(profile_arc)
{
    const double r = 0.057, max_segment = 0.004;
    sluice_profile_piece pieces[3] = {
        line_to(0.8, 0.843),
        {.kind = SLUICE_PIECE_ARC, .radius = r, .turn = -90},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_LENGTH, .length = 0.543}};
    sluice_profile_path p;
    build_profile(pieces, 3, 0.8, 0, 0, 0, 0, max_segment, &p);
    const uint32_t m = (uint32_t)ceil(r * M_PI / 2 / max_segment);
    ck_assert_uint_eq(m, 23);
    ck_assert_uint_eq(p.vertex_count, 2 + m + 1);
    const double cx = 0.8 + r, cy = 0.843;
    double chords = 0;
    for (uint32_t v = 2; v <= 1 + m; v++) {
        ck_assert_uint_eq(p.piece[v], 1);
        double radius = hypot(vertex_x(&p, v) - cx, vertex_y(&p, v) - cy);
        ck_assert_msg(fabs(radius - r) <= 8 * DBL_EPSILON * (fabs(cx) + fabs(cy) + r),
                      "arc vertex %u at distance %.17g from the centre", v, radius);
    }
    for (uint32_t v = 1; v <= m; v++) {
        ck_assert(chord(&p, v) <= max_segment);
        chords += chord(&p, v);
    }
    assert_exact(vertex_x(&p, 1 + m), 0.857, "x", 1 + m);
    assert_exact(vertex_y(&p, 1 + m), 0.9, "y", 1 + m);
    assert_exact(vertex_x(&p, 2 + m), 1.4, "x", 2 + m);
    assert_exact(vertex_y(&p, 2 + m), 0.9, "y", 2 + m);
    const double step = M_PI / 2 / m;
    ck_assert_double_eq_tol(turning(&p, 1), -step / 2, 1e-9);
    ck_assert_double_eq_tol(turning(&p, 1 + m), -step / 2, 1e-9);
    for (uint32_t v = 2; v <= m; v++)
        ck_assert_double_eq_tol(turning(&p, v), -step, 1e-9);
    const double arc = r * M_PI / 2, bound = arc * step * step / 24;
    fprintf(stderr,
            "profile_arc: %u chords, total %.12f m, arc %.12f m, shortfall %.3g (bound %.3g)\n", m,
            chords, arc, arc - chords, bound);
    ck_assert(arc - chords >= -1e-15);
    ck_assert(arc - chords <= bound);
    ck_assert(arc - chords >= 0.99 * bound); /* the leading term of the bound */
    sluice_profile_path_free(&p);

    /* counter-clockwise: a half turn to the left from heading +x, r = 1,
     * ends 2 r above the start heading -x (a following line goes to -x) */
    sluice_profile_piece left[2] = {
        {.kind = SLUICE_PIECE_ARC, .radius = 1, .turn = 180},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_DX, .dx = -0.5}};
    build_profile(left, 2, 0, 0, 1, 0, 0, 0.1, &p);
    const uint32_t n = (uint32_t)ceil(M_PI / 0.1);
    ck_assert_uint_eq(p.vertex_count, 1 + n + 1);
    for (uint32_t v = 1; v <= n; v++)
        ck_assert_double_eq_tol(hypot(vertex_x(&p, v), vertex_y(&p, v) - 1), 1, 1e-15);
    for (uint32_t v = 1; v < n; v++)
        ck_assert_double_eq_tol(turning(&p, v), M_PI / n, 1e-12);
    assert_exact(vertex_x(&p, n), 0, "x", n);
    assert_exact(vertex_y(&p, n), 2, "y", n);
    assert_exact(vertex_x(&p, n + 1), -0.5, "x", n + 1);
    assert_exact(vertex_y(&p, n + 1), 2, "y", n + 1);
    sluice_profile_path_free(&p);
}
END_TEST

/* Arc length of y = a x^n from 0 to X (units), by Simpson's rule on x =
 * X w^2 (dx = 2 X w dw), which makes the integrand smooth at the apex. */
static double crest_arc_length(double a, double n, double X)
{
    const int N = 20000; /* even */
    double sum = 0;
    for (int i = 0; i <= N; i++) {
        double w = (double)i / N, x = X * w * w;
        double slope = a * n * pow(x, n - 1);
        double f = sqrt(1 + slope * slope) * 2 * X * w;
        sum += f * (i == 0 || i == N ? 1 : i % 2 ? 4 : 2);
    }
    return sum / (3.0 * N);
}

/* Seed 001's Cheng crest: y = 0.0304 x^1.85 with x, y in centimetres below
 * and downstream of the apex, down to the tangent point of the 1:0.75 slope
 * (dy/dx = 4/3), at max_segment = dx/2 = 0.002 m. Every vertex lies on the
 * curve (to round-off); the end is where the slope is 4/3, i.e. the seed's
 * T = (41.45, 29.87) cm within the rounding of its printed 0.4145 and 0.2987
 * m (+-0.005 cm); the last chord's slope lies between the curve's slopes at
 * its ends (mean value theorem), so it is short of 4/3 by at most the
 * slope's change over the last segment; the line after the crest leaves
 * exactly along the tangent (3/5, -4/5). The chords, equal in arc length,
 * fall short of the arc length (Simpson, independent) by at most
 * sum c_k (1 / cos dtheta_k - 1), dtheta_k the tangent's turn over segment k
 * (a chord c of an arc l turning by dtheta has c >= l cos dtheta). */
START_TEST(profile_crest)
{
    const double a = 0.0304, n = 1.85, u = 0.01, x0 = 0.3, y0 = 1.62, max_segment = 0.002;
    sluice_profile_piece pieces[2] = {
        {.kind = SLUICE_PIECE_CREST, .coefficient = a, .exponent = n, .unit = u,
         .end_slope = 1 / 0.75},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_LENGTH, .length = 0.1}};
    sluice_profile_path p;
    build_profile(pieces, 2, x0, y0, 1, 90, 0, max_segment, &p);
    const uint32_t m = p.vertex_count - 2;
    const double X_T = pow(4.0 / 3.0 / (a * n), 1 / (n - 1));
    const double S = u * crest_arc_length(a, n, X_T);
    ck_assert_uint_eq(m, (uint32_t)ceil(S / max_segment));
    double chords = 0, bound = 0;
    for (uint32_t v = 1; v <= m; v++) {
        ck_assert_uint_eq(p.piece[v], 0);
        double X = (vertex_x(&p, v) - x0) / u, Y = (y0 - vertex_y(&p, v)) / u;
        ck_assert_msg(fabs(Y - a * pow(X, n)) <= 1e-11, "vertex %u: y = %.15g cm, a x^n = %.15g",
                      v, Y, a * pow(X, n));
        double X0 = (vertex_x(&p, v - 1) - x0) / u;
        double turn = atan(a * n * pow(X, n - 1)) - atan(a * n * pow(X0, n - 1));
        double c = chord(&p, v - 1);
        ck_assert(c <= max_segment);
        ck_assert_msg(c >= S / m * cos(turn) - 1e-12 && c <= S / m + 1e-12,
                      "chord %u: %.12g m, the equal arc length is %.12g m", v, c, S / m);
        chords += c;
        bound += c * (1 / cos(turn) - 1);
    }
    double X_end = (vertex_x(&p, m) - x0) / u, Y_end = (y0 - vertex_y(&p, m)) / u;
    fprintf(stderr, "profile_crest: T = (%.4f, %.4f) cm (seed 001: (41.45, 29.87)), %u chords, "
            "arc %.9f m, chords %.9f m, shortfall %.3g (bound %.3g)\n",
            X_end, Y_end, m, S, chords, S - chords, bound);
    ck_assert_double_eq_tol(X_end, X_T, 1e-11);
    ck_assert_double_eq_tol(a * n * pow(X_end, n - 1), 4.0 / 3.0, 1e-12);
    ck_assert(fabs(X_end - 41.45) <= 0.005);
    ck_assert(fabs(Y_end - 29.87) <= 0.005);
    double X_before = (vertex_x(&p, m - 1) - x0) / u;
    double last = (vertex_y(&p, m - 1) - vertex_y(&p, m)) / (vertex_x(&p, m) - vertex_x(&p, m - 1));
    ck_assert(last <= 4.0 / 3.0 + 1e-12);
    ck_assert(last >= a * n * pow(X_before, n - 1) - 1e-12);
    double tx = (vertex_x(&p, m + 1) - vertex_x(&p, m)) / 0.1;
    double ty = (vertex_y(&p, m + 1) - vertex_y(&p, m)) / 0.1;
    ck_assert_double_eq_tol(tx, 0.6, 1e-12);
    ck_assert_double_eq_tol(ty, -0.8, 1e-12);
    ck_assert(S - chords >= -1e-12);
    ck_assert(S - chords <= bound + 1e-12);
    /* the first segment leaves the apex horizontally: the tangent there is +x */
    ck_assert(fabs(atan2(vertex_y(&p, 1) - y0, vertex_x(&p, 1) - x0)) < 0.01);
    sluice_profile_path_free(&p);

    /* ending at x instead: end_x = 41.45 cm, where the slope is 4/3 to the
     * seed's rounding */
    sluice_profile_piece at_x = {.kind = SLUICE_PIECE_CREST, .coefficient = a, .exponent = n,
                                 .unit = u, .end_x = 41.45, .end_at_x = 1};
    build_profile(&at_x, 1, x0, y0, 0, 0, 0, max_segment, &p);
    uint32_t e = p.vertex_count - 1;
    assert_exact(vertex_x(&p, e), x0 + u * 41.45, "x", e);
    ck_assert_double_eq_tol(a * n * pow(41.45, n - 1), 4.0 / 3.0, 1e-4);
    sluice_profile_path_free(&p);
}
END_TEST

/* Every way of ending a line, and every refusal of the builder. */
START_TEST(profile_lines)
{
    sluice_profile_piece pieces[8] = {
        line_to(1, 0),
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_DX | SLUICE_LINE_DY, .dx = 0.5, .dy = 0.5},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_LENGTH | SLUICE_LINE_HEADING,
         .length = 1, .heading = 90},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_LENGTH | SLUICE_LINE_SLOPE, .length = 5,
         .slope = -0.75},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_DX, .dx = 0.8},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_TO_Y | SLUICE_LINE_HEADING, .to_y = -3,
         .heading = -90},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_TO_X | SLUICE_LINE_SLOPE, .to_x = 8.3,
         .slope = 0.5},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_DY | SLUICE_LINE_SLOPE, .dy = 1,
         .slope = -2}};
    const double expect[9][2] = {{0, 0},   {1, 0},      {1.5, 0.5}, {1.5, 1.5},  {5.5, -1.5},
                                 {6.3, -2.1}, {6.3, -3}, {8.3, -2},  {7.8, -1}};
    sluice_profile_path p;
    build_profile(pieces, 8, 0, 0, 0, 0, 0, 0.01, &p);
    ck_assert_uint_eq(p.vertex_count, 9);
    for (uint32_t v = 0; v < 9; v++) {
        ck_assert_double_eq_tol(vertex_x(&p, v), expect[v][0], 1e-14);
        ck_assert_double_eq_tol(vertex_y(&p, v), expect[v][1], 1e-14);
    }
    /* exact where the given coordinate sets it */
    ck_assert(vertex_x(&p, 3) == 1.5 && vertex_x(&p, 6) == vertex_x(&p, 5));
    ck_assert(vertex_y(&p, 6) == -3 && vertex_x(&p, 7) == 8.3);
    sluice_profile_path_free(&p);

    sluice_profile_piece bad[2] = {line_to(1, 0), {.kind = SLUICE_PIECE_LINE}};
    refuse_profile(bad, 2, 0, 0, 0, 1, NULL, "a line needs its end");
    bad[1].keys = SLUICE_LINE_TO | SLUICE_LINE_DX;
    refuse_profile(bad, 2, 0, 0, 0, 1, "dx", "'to' sets the line's end alone");
    bad[1] = (sluice_profile_piece){.kind = SLUICE_PIECE_LINE,
                                    .keys = SLUICE_LINE_DX | SLUICE_LINE_DY | SLUICE_LINE_SLOPE,
                                    .dx = 1, .dy = 1};
    refuse_profile(bad, 2, 0, 0, 0, 1, "slope", "'dx' and 'dy' set the line's end alone");
    bad[1] = (sluice_profile_piece){.kind = SLUICE_PIECE_LINE,
                                    .keys = SLUICE_LINE_LENGTH | SLUICE_LINE_TO_X, .length = 1};
    refuse_profile(bad, 2, 0, 0, 0, 1, "to_x", "give the line's extent once");
    bad[1] = (sluice_profile_piece){.kind = SLUICE_PIECE_LINE,
                                    .keys = SLUICE_LINE_LENGTH | SLUICE_LINE_HEADING |
                                            SLUICE_LINE_SLOPE,
                                    .length = 1};
    refuse_profile(bad, 2, 0, 0, 0, 1, "slope", "direction once");
    bad[1] = (sluice_profile_piece){.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_DX, .dx = -1};
    refuse_profile(bad, 2, 0, 0, 0, 1, "dx", "is not ahead");
    bad[1] = (sluice_profile_piece){.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_DY, .dy = 1};
    refuse_profile(bad, 2, 0, 0, 0, 1, "dy", "is horizontal");
    bad[1] = line_to(1, 0);
    refuse_profile(bad, 2, 0, 0, 0, 1, NULL, "zero length");
    sluice_profile_piece first[1] = {{.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_LENGTH,
                                      .length = 1}};
    refuse_profile(first, 1, 0, 0, 0, 0, NULL, "it is the first piece");
    sluice_profile_piece arc[1] = {{.kind = SLUICE_PIECE_ARC, .radius = 1, .turn = 90}};
    refuse_profile(arc, 1, 0, 0, 0, 0, NULL, "give the profile a 'heading'");
    arc[0].turn = 0;
    refuse_profile(arc, 1, 1, 0, 0, 0, "turn", "nonzero");
    arc[0] = (sluice_profile_piece){.kind = SLUICE_PIECE_ARC, .radius = -0.057, .turn = 90};
    refuse_profile(arc, 1, 1, 0, 0, 0, "radius", "must be > 0");
    sluice_profile_piece steps[1] = {{.kind = SLUICE_PIECE_STEPS, .count = 0, .height = 0.1,
                                      .step_length = 0.25}};
    refuse_profile(steps, 1, 0, 0, 0, 0, "count", "at least one step");
    sluice_profile_piece crest[1] = {{.kind = SLUICE_PIECE_CREST, .coefficient = 0.0304,
                                      .exponent = 1, .unit = 0.01, .end_slope = 1}};
    refuse_profile(crest, 1, 0, 0, 0, 0, "exponent", "must be > 1");
    crest[0].exponent = 1.0001; /* slope 10 only at x = (10 / 0.0304)^10000 */
    crest[0].end_slope = 10;
    refuse_profile(crest, 1, 0, 0, 0, 0, "end_slope", "never at a size");
    /* too many vertices for the segment length */
    sluice_profile_piece big[1] = {{.kind = SLUICE_PIECE_ARC, .radius = 1e6, .turn = 90}};
    refuse_profile(big, 1, 1, 0, 0, 0, NULL, "vertices, more than");
}
END_TEST

/* Crossings: a profile meeting itself is refused at the later piece. */
START_TEST(profile_crossings)
{
    uint32_t s0, s1;
    double at[2];
    const sluice_real simple[] = {0, 0, 1, 0, 1, 1, 0, 1};
    ck_assert_int_eq(sluice_polyline_crossing(simple, 4, 0, &s0, &s1, at), 0);
    ck_assert_int_eq(sluice_polyline_crossing(simple, 4, 1, &s0, &s1, at), 0);
    const sluice_real bowtie[] = {0, 0, 1, 1, 1, 0, 0, 1};
    ck_assert_int_eq(sluice_polyline_crossing(bowtie, 4, 0, &s0, &s1, at), 1);
    ck_assert_uint_eq(s0, 0);
    ck_assert_uint_eq(s1, 2);
    ck_assert_double_eq_tol(at[0], 0.5, 1e-15);
    ck_assert_double_eq_tol(at[1], 0.5, 1e-15);
    const sluice_real touch[] = {0, 0, 2, 0, 2, 1, 1, 1, 1, 0}; /* back onto the first segment */
    ck_assert_int_eq(sluice_polyline_crossing(touch, 5, 0, &s0, &s1, at), 1);
    ck_assert_uint_eq(s0, 0);
    ck_assert_uint_eq(s1, 3);
    ck_assert(at[0] == 1 && at[1] == 0);
    const sluice_real fold[] = {0, 0, 1, 0, 0.5, 0};
    ck_assert_int_eq(sluice_polyline_crossing(fold, 3, 0, &s0, &s1, at), 1);
    ck_assert_uint_eq(s0, 0);
    ck_assert_uint_eq(s1, 1);
    /* closed: the closing segment 3 -> 0 crosses segment 1 */
    const sluice_real closing[] = {0, 0, 2, 0, 2, 2, 3, 1};
    ck_assert_int_eq(sluice_polyline_crossing(closing, 4, 1, &s0, &s1, at), 1);
    ck_assert_uint_eq(s0, 1);
    ck_assert_uint_eq(s1, 3);
    ck_assert_int_eq(sluice_polyline_crossing(closing, 4, 0, &s0, &s1, at), 0);

    /* a weir whose downstream line runs back through its face */
    sluice_profile_piece pieces[4] = {line_to(1, 0), line_to(1, 1), line_to(2, 1),
                                      line_to(0.5, 0.5)};
    sluice_profile profile = {{0, 0}, 0, 0, pieces, 4, 0, 0.01};
    sluice_profile_path path;
    sluice_profile_problem problem;
    ck_assert_int_eq(sluice_profile_build(&profile, &path, &problem), -1);
    ck_assert_uint_eq(problem.piece, 3);
    ck_assert_uint_eq(problem.other, 1);
    ck_assert_int_eq(problem.closing, 0);
    ck_assert_ptr_nonnull(strstr(problem.message, "crosses or touches itself at (1, 0.666667) m"));
    /* closed: the closing segment back to the start crosses piece 1 */
    sluice_profile_piece loop[3] = {line_to(2, 0), line_to(2, 2), line_to(3, 1)};
    profile = (sluice_profile){{0, 0}, 0, 0, loop, 3, 1, 0.01};
    ck_assert_int_eq(sluice_profile_build(&profile, &path, &problem), -1);
    ck_assert_uint_eq(problem.piece, 1);
    ck_assert_int_eq(problem.closing, 1);
    /* a full circle closed on itself is simple; left open it touches its start */
    sluice_profile_piece circle[1] = {{.kind = SLUICE_PIECE_ARC, .radius = 1, .turn = 360}};
    profile = (sluice_profile){{0, 0}, 1, 0, circle, 1, 1, 0.1};
    ck_assert_int_eq(sluice_profile_build(&profile, &path, &problem), 0);
    ck_assert_uint_eq(path.vertex_count, (uint32_t)ceil(2 * M_PI / 0.1));
    ck_assert_uint_eq(path.piece[0], 0);
    sluice_profile_path_free(&path);
    profile.closed = 0;
    ck_assert_int_eq(sluice_profile_build(&profile, &path, &problem), -1);
    ck_assert_ptr_nonnull(strstr(problem.message, "touches itself"));
}
END_TEST

/* Lattice keys (x, y) of the points, sorted, for set comparisons. */
static key3 *sorted_keys(const sluice_points *pts, double dx, const double origin[3])
{
    key3 *keys = NULL;
    ck_assert_uint_eq(lattice_keys(pts, 2, dx, origin, &keys), 0);
    return keys;
}

static int has_key(const key3 *keys, size_t n, int64_t i, int64_t j)
{
    key3 k = {{i, j, 0}};
    return bsearch(&k, keys, n, sizeof k, key3_compare) != NULL;
}

/* A fluid region bounded by a profile fills exactly the lattice points on
 * the fluid side: (1) the air over a flight of steps, closed up to a lid,
 * against the exact staircase test and against a brute-force
 * sluice_point_in_polygon over every lattice point; (2) a circle (one
 * closed arc of 360 deg) against the disc: every point deeper than the
 * sagitta R (1 - cos(pi/m)) inside is filled, none outside; filled points are
 * on the wall's fluid side (signed distance > 0 to the same closed profile
 * as a wall, counter-clockwise: fluid inside), and the wall's particle layer
 * (thickness T) is the lattice annulus R < r <= R + T up to the same
 * sagitta: the curve gives the evenly spaced lattice layer a true circle
 * would. */
START_TEST(profile_fill)
{
    const double dx = 0.01, origin[3] = {0.003, 0.002, 0};
    /* (1) start (0, 1), down to the top step, 4 steps 0.1 x 0.25, up to the lid */
    sluice_profile_piece pieces[3] = {
        line_to(0, 0.6),
        {.kind = SLUICE_PIECE_STEPS, .count = 4, .height = 0.1, .step_length = 0.25},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_TO_Y | SLUICE_LINE_HEADING, .to_y = 1,
         .heading = 90}};
    sluice_profile_path p;
    build_profile(pieces, 3, 0, 1, 0, 0, 1, 0.005, &p);
    ck_assert_uint_eq(p.vertex_count, 11);
    sluice_region region = {.shape = SLUICE_REGION_POLYGON, .polygon = p.xy,
                            .vertex_count = p.vertex_count};
    sluice_points pts = {0};
    ck_assert_int_eq(sluice_region_fill(&region, 2, dx, (sluice_real[3]){0.003, 0.002, 0}, &pts),
                     0);
    key3 *keys = sorted_keys(&pts, dx, origin);
    size_t expected = 0;
    for (int64_t j = -10; j < 110; j++)
        for (int64_t i = -10; i < 110; i++) {
            double x = origin[0] + (i + 0.5) * dx, y = origin[1] + (j + 0.5) * dx;
            double tread = 0.6 - 0.1 * (floor(x / 0.25) + 1); /* the step under x */
            int inside = x > 0 && x < 1 && y < 1 && y > tread;
            int pnpoly = sluice_point_in_polygon(p.xy, p.vertex_count, x, y);
            ck_assert_msg(inside == pnpoly, "(%g, %g): staircase %d, polygon %d", x, y, inside,
                          pnpoly);
            ck_assert_msg(has_key(keys, pts.count, i, j) == inside, "(%g, %g) filled %d", x, y,
                          !inside);
            expected += inside;
        }
    ck_assert_uint_eq(pts.count, expected);
    fprintf(stderr, "profile_fill: %zu lattice points over the steps\n", expected);
    free(keys);
    sluice_points_free(&pts);
    sluice_profile_path_free(&p);

    /* (2) a circle of radius R about (0.5, 0.5), counter-clockwise */
    const double R = 0.4, T = 3 * dx, max_segment = dx / 2;
    sluice_profile_piece circle[1] = {{.kind = SLUICE_PIECE_ARC, .radius = R, .turn = 360}};
    build_profile(circle, 1, 0.5, 0.1, 1, 0, 1, max_segment, &p);
    const uint32_t m = p.vertex_count;
    ck_assert_uint_eq(m, (uint32_t)ceil(2 * M_PI * R / max_segment));
    const double sagitta = R * (1 - cos(M_PI / m));
    region = (sluice_region){.shape = SLUICE_REGION_POLYGON, .polygon = p.xy, .vertex_count = m};
    ck_assert_int_eq(sluice_region_fill(&region, 2, dx, (sluice_real[3]){0.003, 0.002, 0}, &pts),
                     0);
    keys = sorted_keys(&pts, dx, origin);
    sluice_wall_geometry wall;
    ck_assert_int_eq(sluice_wall_build_polyline(&wall, p.xy, m, 1, NULL), 0);
    sluice_points layer_pts = {0};
    ck_assert_int_eq(sluice_wall_layer_points(&wall, dx, (sluice_real[3]){0.003, 0.002, 0}, T,
                                              &layer_pts),
                     0);
    key3 *layer_keys = sorted_keys(&layer_pts, dx, origin);
    size_t band = 0, layer_band = 0;
    for (int64_t j = -10; j < 110; j++)
        for (int64_t i = -10; i < 110; i++) {
            double x = origin[0] + (i + 0.5) * dx, y = origin[1] + (j + 0.5) * dx;
            double r = hypot(x - 0.5, y - 0.5);
            int filled = has_key(keys, pts.count, i, j);
            ck_assert_int_eq(filled, sluice_point_in_polygon(p.xy, m, x, y));
            if (r < R - sagitta)
                ck_assert_msg(filled, "(%g, %g) at r = %g not filled", x, y, r);
            else if (r > R)
                ck_assert_msg(!filled, "(%g, %g) at r = %g filled", x, y, r);
            else
                band++;
            double sd = signed_distance(&wall, x, y, 0, NULL, NULL);
            if (fabs(sd) > 1e-12)
                ck_assert_int_eq(filled, sd > 0);
            int layered = has_key(layer_keys, layer_pts.count, i, j);
            if (r > R && r <= R + T - sagitta)
                ck_assert_msg(layered, "(%g, %g) at r = %g not in the layer", x, y, r);
            else if (r < R - sagitta || r > R + T)
                ck_assert_msg(!layered, "(%g, %g) at r = %g in the layer", x, y, r);
            else
                layer_band++;
        }
    fprintf(stderr, "profile_fill: circle of %u segments (sagitta %.2g m): %zu filled, %zu layer "
            "points; %zu and %zu lattice points in the sagitta bands\n",
            m, sagitta, pts.count, layer_pts.count, band, layer_band);
    free(keys);
    free(layer_keys);
    sluice_points_free(&pts);
    sluice_points_free(&layer_pts);
    sluice_wall_geometry_free(&wall);
    sluice_profile_path_free(&p);
}
END_TEST

/* ------------------------------------------------------ profile scenes -- */

/* Loads scene text (written to a scratch file); returns the error count and
 * the diagnostics (caller destroys), *path the file. */
static size_t load_scene_text(const char *text, sluice_scene *scene, sluice_diag **diag,
                              char **path)
{
    char *dir = test_scratch("geometry");
    ck_assert_ptr_nonnull(dir);
    *path = test_write_file(dir, "scene.yaml", text);
    ck_assert_ptr_nonnull(*path);
    free(dir);
    *diag = sluice_diag_create();
    ck_assert_ptr_nonnull(*diag);
    sluice_scene_load(scene, *path, NULL, 0, *diag);
    return sluice_diag_error_count(*diag);
}

/* Removes the scratch scene file and its directory; frees path. */
static void remove_scene_file(char *path)
{
    ck_assert_int_eq(unlink(path), 0);
    char *slash = strrchr(path, '/');
    ck_assert_ptr_nonnull(slash);
    *slash = '\0';
    ck_assert_int_eq(rmdir(path), 0);
    free(path);
}

static const char *scene_head = "dimensions: 2\n"
                                "particles: {spacing: 0.008}\n"
                                "time: {end: 0.1}\n"
                                "domain: {min: [-0.1, -0.1], max: [4.3, 1.2]}\n"
                                "plugins: {wendland_c2: {}}\n"
                                "geometry:\n";

/* An open channel: the tank without its ends across x. 3D: the bed and the
 * two sides (6 triangles); a point past an open end is beyond it (no
 * "behind"), and the layers are the tank's without the end walls' and
 * without points past the ends. 2D: the bed alone. */
START_TEST(channel_walls)
{
    const sluice_real lo[3] = {0, 0, 0}, hi[3] = {2, 0.5, 0.6};
    const double dx = 0.05, T = 3 * dx;
    sluice_wall_geometry channel, tank;
    ck_assert_int_eq(sluice_wall_build_channel(&channel, 3, lo, hi, NULL), 0);
    ck_assert_int_eq(sluice_wall_build_tank(&tank, 3, lo, hi, NULL), 0);
    ck_assert_uint_eq(channel.element_count, 6);
    ck_assert_uint_eq(tank.element_count, 10);
    int beyond = 0;
    const sluice_real inside[3] = {1.0, 0.2, 0.1}, past[3] = {2.3, 0.25, 0.1};
    ck_assert(fabs((double)sluice_wall_signed_distance(&channel, inside, &beyond, NULL) - 0.1) <
              1e-12);
    ck_assert_int_eq(beyond, 0);
    (void)sluice_wall_signed_distance(&channel, past, &beyond, NULL);
    ck_assert_int_eq(beyond, 1);
    sluice_points a, b;
    layer(&channel, dx, T, &a);
    layer(&tank, dx, T, &b);
    check_layer_points(&channel, &a, dx, T);
    /* the channel's layers: the tank's whose x lies within the channel */
    size_t within = 0;
    for (size_t i = 0; i < b.count; i++)
        within += b.xyz[3 * i] > 0 && b.xyz[3 * i] < 2;
    ck_assert_uint_eq(a.count, within);
    for (size_t i = 0; i < a.count; i++)
        ck_assert(a.xyz[3 * i] > 0 && a.xyz[3 * i] < 2);
    sluice_points_free(&a);
    sluice_points_free(&b);
    sluice_wall_geometry_free(&channel);
    sluice_wall_geometry_free(&tank);
    ck_assert_int_eq(sluice_wall_build_channel(&channel, 2, lo, hi, NULL), 0);
    ck_assert_uint_eq(channel.element_count, 1);
    ck_assert(channel.normals[1] > 0.999); /* the fluid above the bed */
    sluice_wall_geometry_free(&channel);
}
END_TEST

/* 3D walls extruded from a 2D outline (x, z) across y: a trapezoidal
 * obstacle (polygon: a solid) on a sloped bed (polyline), in a 3D scene
 * and, as 2D walls, in a 2D one. Exact: for points between the extrusion's
 * ends the 3D signed distance is the 2D one of (x, z) (to round-off), and
 * the 3D wall layers are the 2D layers repeated on every lattice row of y
 * within the ends, no point beyond them. */
static const char *extruded_walls =
    "    - {shape: polygon, points: [[6.18, 0], [6.58, 0.075], [6.78, 0.075], [7.18, 0]]%s}\n"
    "    - {shape: polyline, points: [[5.0, 0.1], [6.0, 0], [8.0, 0]]%s}\n";

START_TEST(extruded_walls_3d)
{
    char *walls2 = NULL, *walls3 = NULL, *text2 = NULL, *text3 = NULL;
    ck_assert_int_ge(asprintf(&walls2, extruded_walls, "", ""), 0);
    ck_assert_int_ge(asprintf(&walls3, extruded_walls, ", across: [0, 0.3]",
                              ", across: [0, 0.3]"),
                     0);
    ck_assert_int_ge(asprintf(&text2,
                              "dimensions: 2\nparticles: {spacing: 0.015}\ntime: {end: 0.1}\n"
                              "domain: {min: [4.5, -0.2], max: [8.5, 0.5]}\n"
                              "plugins: {wendland_c2: {}}\ngeometry:\n  walls:\n%s",
                              walls2),
                     0);
    ck_assert_int_ge(asprintf(&text3,
                              "dimensions: 3\nparticles: {spacing: 0.015}\ntime: {end: 0.1}\n"
                              "domain: {min: [4.5, -0.2, -0.2], max: [8.5, 0.5, 0.5]}\n"
                              "plugins: {wendland_c2: {}}\ngeometry:\n  walls:\n%s",
                              walls3),
                     0);
    sluice_scene s2, s3;
    sluice_diag *d2, *d3;
    char *p2, *p3;
    ck_assert_uint_eq(load_scene_text(text2, &s2, &d2, &p2), 0);
    size_t errors = load_scene_text(text3, &s3, &d3, &p3);
    for (size_t i = 0; i < sluice_diag_count(d3); i++)
        fprintf(stderr, "%s\n", sluice_diag_message(d3, i));
    ck_assert_uint_eq(errors, 0);
    ck_assert_uint_eq(s3.wall_count, 2);
    const double dx = 0.015, T = 3 * dx, width = 0.3;
    uint64_t state = 12345;
    double worst = 0;
    for (int w = 0; w < 2; w++) {
        const sluice_wall_geometry *g2 = &s2.walls[w].geometry, *g3 = &s3.walls[w].geometry;
        ck_assert_uint_eq(g3->element_count, 2 * g2->element_count);
        for (int k = 0; k < 20000; k++) {
            sluice_real p2[3] = {(sluice_real)uniform(&state, 4.8, 8.4),
                                 (sluice_real)uniform(&state, -0.1, 0.3), 0};
            sluice_real p3[3] = {p2[0], (sluice_real)uniform(&state, 0.01, width - 0.01), p2[1]};
            int beyond2 = 0, beyond3 = 0;
            const double a = (double)sluice_wall_signed_distance(g2, p2, &beyond2, NULL);
            const double b = (double)sluice_wall_signed_distance(g3, p3, &beyond3, NULL);
            ck_assert_int_eq(beyond2, beyond3);
            if (!beyond2)
                worst = fmax(worst, fabs(a - b));
        }
        /* layers: every 3D point is a 2D point on one of the 20 rows of y */
        sluice_points q2, q3;
        layer(g2, dx, T, &q2);
        layer(g3, dx, T, &q3);
        check_layer_points(g3, &q3, dx, T);
        const size_t rows = (size_t)llround(width / dx);
        ck_assert_uint_eq(q3.count, rows * q2.count);
        for (size_t i = 0; i < q3.count; i++) {
            const double y = q3.xyz[3 * i + 1];
            ck_assert(y > 0 && y < width);
            int found = 0;
            for (size_t j = 0; j < q2.count && !found; j++)
                found = fabs(q2.xyz[3 * j] - q3.xyz[3 * i]) < 1e-9 &&
                        fabs(q2.xyz[3 * j + 1] - q3.xyz[3 * i + 2]) < 1e-9;
            ck_assert_msg(found, "3D layer point (%g, %g, %g) is no 2D layer point",
                          q3.xyz[3 * i], q3.xyz[3 * i + 1], q3.xyz[3 * i + 2]);
        }
        fprintf(stderr, "extruded wall %d: %zu 2D layer points, %zu in 3D (%zu rows)\n", w,
                q2.count, q3.count, rows);
        sluice_points_free(&q2);
        sluice_points_free(&q3);
    }
    fprintf(stderr, "extruded walls: largest |3D - 2D| signed distance %.2e m\n", worst);
    ck_assert(worst < 1e-12);
    sluice_scene_free(&s2);
    sluice_scene_free(&s3);
    sluice_diag_destroy(d2);
    sluice_diag_destroy(d3);
    remove_scene_file(p2);
    remove_scene_file(p3);

    /* refused: the extrusion's ends reversed, with their line */
    char *bad = NULL;
    ck_assert_int_ge(asprintf(&bad,
                              "dimensions: 3\nparticles: {spacing: 0.015}\ntime: {end: 0.1}\n"
                              "domain: {min: [4.5, -0.2, -0.2], max: [8.5, 0.5, 0.5]}\n"
                              "plugins: {wendland_c2: {}}\ngeometry:\n  walls:\n"
                              "    - {shape: polyline, points: [[5, 0], [6, 0]], across: [0.3, 0]}\n"),
                     0);
    sluice_scene sb;
    sluice_diag *db;
    char *pb;
    ck_assert_uint_eq(load_scene_text(bad, &sb, &db, &pb), 1);
    ck_assert_ptr_nonnull(strstr(sluice_diag_message(db, 0), "across must run from a smaller"));
    ck_assert_ptr_nonnull(strstr(sluice_diag_message(db, 0), ":8:"));
    sluice_scene_free(&sb);
    sluice_diag_destroy(db);
    remove_scene_file(pb);
    free(bad);
    free(walls2), free(walls3), free(text2), free(text3);
}
END_TEST

/* The Chanson chute as docs/scene-format.md writes it (anchors, nested
 * lists of pieces): the wall and the regions are the profiles the builder
 * makes of the same pieces; max_segment defaults to spacing / 2. */
START_TEST(profile_scene)
{
    char *text = NULL;
    ck_assert_int_ge(
        asprintf(&text,
                 "%s"
                 "  walls:\n"
                 "    - shape: profile\n"
                 "      start: [0, 1.1]\n"
                 "      pieces:\n"
                 "        - {piece: line, to: [0, 0]}\n"
                 "        - &weir\n"
                 "          - {piece: line, to: [0.8, 0]}\n"
                 "          - {piece: line, to: [0.8, 0.843]}\n"
                 "          - {piece: arc, radius: 0.057, turn: -90}\n"
                 "          - {piece: line, to_x: 1.4}\n"
                 "        - &chute\n"
                 "          - {piece: steps, count: 9, height: 0.1, length: 0.25}\n"
                 "          - {piece: line, length: 0.5}\n"
                 "  fluid:\n"
                 "    - shape: profile\n"
                 "      start: [0, 1.0]\n"
                 "      pieces: [{piece: line, to: [0, 0]}, *weir, {piece: line, to: [1.4, 1.0]}]\n"
                 "    - shape: profile\n"
                 "      start: [0, 1.1]\n"
                 "      max_segment: 0.001\n"
                 "      pieces:\n"
                 "        - {piece: line, to: [0, 1.0]}\n"
                 "        - {piece: line, to: [1.4, 1.0]}\n"
                 "        - {piece: line, to: [1.4, 0.9]}\n"
                 "        - *chute\n"
                 "        - {piece: line, heading: 90, to_y: 1.1}\n",
                 scene_head),
        0);
    sluice_scene scene;
    sluice_diag *diag;
    char *path;
    size_t errors = load_scene_text(text, &scene, &diag, &path);
    for (size_t i = 0; i < sluice_diag_count(diag); i++)
        fprintf(stderr, "%s\n", sluice_diag_message(diag, i));
    ck_assert_uint_eq(errors, 0);
    ck_assert_uint_eq(scene.wall_count, 1);
    ck_assert_uint_eq(scene.fluid_count, 2);

    sluice_profile_piece weir[4] = {line_to(0.8, 0), line_to(0.8, 0.843),
                                    {.kind = SLUICE_PIECE_ARC, .radius = 0.057, .turn = -90},
                                    {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_TO_X,
                                     .to_x = 1.4}};
    sluice_profile_piece chute[2] = {
        {.kind = SLUICE_PIECE_STEPS, .count = 9, .height = 0.1, .step_length = 0.25},
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_LENGTH, .length = 0.5}};
    sluice_profile_piece wall[7] = {line_to(0, 0), weir[0], weir[1], weir[2], weir[3], chute[0],
                                    chute[1]};
    sluice_profile_path p;
    build_profile(wall, 7, 0, 1.1, 0, 0, 0, 0.004, &p);
    const sluice_wall_geometry *g = &scene.walls[0].geometry;
    ck_assert_uint_eq(g->element_count, p.vertex_count - 1);
    for (uint32_t e = 0; e < g->element_count; e++) {
        ck_assert(g->points[6 * e] == p.xy[2 * e] && g->points[6 * e + 1] == p.xy[2 * e + 1]);
        ck_assert(g->points[6 * e + 3] == p.xy[2 * e + 2] &&
                  g->points[6 * e + 4] == p.xy[2 * e + 3]);
    }
    /* 23 arc segments at 0.004 m: the default max_segment */
    uint32_t arc_segments = 0;
    for (uint32_t v = 0; v < p.vertex_count; v++)
        arc_segments += p.piece[v] == 3;
    ck_assert_uint_eq(arc_segments, 23);
    sluice_profile_path_free(&p);

    sluice_profile_piece water[6] = {line_to(0, 0), weir[0], weir[1], weir[2], weir[3],
                                     line_to(1.4, 1.0)};
    build_profile(water, 6, 0, 1.0, 0, 0, 1, 0.004, &p);
    const sluice_region *r = &scene.fluids[0].region;
    ck_assert_int_eq(r->shape, SLUICE_REGION_POLYGON);
    ck_assert_uint_eq(r->vertex_count, p.vertex_count);
    ck_assert_int_eq(memcmp(r->polygon, p.xy, 2 * p.vertex_count * sizeof *p.xy), 0);
    sluice_profile_path_free(&p);
    sluice_profile_piece air[6] = {
        line_to(0, 1.0), line_to(1.4, 1.0), line_to(1.4, 0.9), chute[0], chute[1],
        {.kind = SLUICE_PIECE_LINE, .keys = SLUICE_LINE_TO_Y | SLUICE_LINE_HEADING, .to_y = 1.1,
         .heading = 90}};
    build_profile(air, 6, 0, 1.1, 0, 0, 1, 0.001, &p);
    r = &scene.fluids[1].region;
    ck_assert_uint_eq(r->vertex_count, p.vertex_count);
    ck_assert_int_eq(memcmp(r->polygon, p.xy, 2 * p.vertex_count * sizeof *p.xy), 0);
    sluice_profile_path_free(&p);

    sluice_scene_free(&scene);
    sluice_diag_destroy(diag);
    remove_scene_file(path);
    free(text);
}
END_TEST

/* One bad parameter in a profile: exactly one error, at the line and column
 * of the offending text (the `at` token on the first line containing
 * `line_marker`), naming it. */
static void expect_profile_error(const char *geometry, int dimensions, const char *line_marker,
                                 const char *at, const char *needle)
{
    char *text = NULL;
    ck_assert_int_ge(asprintf(&text,
                              "dimensions: %d\n"
                              "particles: {spacing: 0.01}\n"
                              "time: {end: 0.1}\n"
                              "domain: {min: %s, max: %s}\n"
                              "plugins: {wendland_c2: {}}\n"
                              "geometry:\n%s",
                              dimensions, dimensions == 2 ? "[-1, -1]" : "[-1, -1, -1]",
                              dimensions == 2 ? "[3, 3]" : "[3, 3, 3]", geometry),
                     0);
    int line = 0, column = 0, n = 1;
    for (const char *c = text; *c; n++) {
        const char *end = strchr(c, '\n');
        size_t len = end ? (size_t)(end - c) : strlen(c);
        char *copy = strndup(c, len);
        if (!line && strstr(copy, line_marker)) {
            const char *hit = strstr(copy, at);
            ck_assert_ptr_nonnull(hit);
            line = n;
            column = (int)(hit - copy) + 1;
        }
        free(copy);
        c = end ? end + 1 : c + len;
    }
    ck_assert_int_gt(line, 0);
    sluice_scene scene;
    sluice_diag *diag;
    char *path;
    size_t errors = load_scene_text(text, &scene, &diag, &path);
    char *where = NULL;
    ck_assert_int_ge(asprintf(&where, "%s:%d:%d: error: ", path, line, column), 0);
    const char *message = sluice_diag_count(diag) ? sluice_diag_message(diag, 0) : "(none)";
    fprintf(stderr, "%s\n", message);
    ck_assert_msg(errors == 1, "expected one error, got %zu (first: %s)", errors, message);
    ck_assert_msg(strstr(message, where), "expected '%s' in '%s'", where, message);
    ck_assert_msg(strstr(message, needle), "expected '%s' in '%s'", needle, message);
    free(where);
    sluice_scene_free(&scene);
    sluice_diag_destroy(diag);
    remove_scene_file(path);
    free(text);
}

#define WALL_PROFILE(pieces)                                                                   \
    "  walls:\n"                                                                               \
    "    - shape: profile\n"                                                                   \
    "      start: [0, 1]\n"                                                                    \
    "      pieces:\n"                                                                          \
    "        - {piece: line, to: [0, 0.5]}\n" pieces

START_TEST(profile_errors)
{
    expect_profile_error(WALL_PROFILE("        - {piece: arc, radius: -0.057, turn: -90}\n"), 2,
                         "radius", "-0.057",
                         "geometry.walls.0.pieces.1.radius = -0.057 m is out of range: it must "
                         "be > 0 m");
    expect_profile_error(WALL_PROFILE("        - {piece: arc, radius: 0.057, turn: 0}\n"), 2,
                         "turn: 0", "0}",
                         "geometry.walls.0.pieces.1 (arc): the turn must be nonzero");
    expect_profile_error(
        WALL_PROFILE("        - {piece: steps, count: 0, height: 0.1, length: 0.25}\n"), 2,
        "count", "0, height", "geometry.walls.0.pieces.1.count = 0 is out of range");
    expect_profile_error(
        WALL_PROFILE("        - {piece: steps, count: 9, height: -0.1, length: 0.25}\n"), 2,
        "count", "-0.1", "geometry.walls.0.pieces.1.height = -0.1 m is out of range");
    expect_profile_error(WALL_PROFILE("        - {piece: crest, coefficient: 0.0304, exponent: "
                                      "1, unit: 0.01, end_slope: 1.333}\n"),
                         2, "crest", "1, unit",
                         "geometry.walls.0.pieces.1.exponent = 1 is out of range: it must be > 1");
    expect_profile_error(WALL_PROFILE("        - {piece: crest, coefficient: 0.0304, exponent: "
                                      "1.0001, end_slope: 10}\n"),
                         2, "crest", "10}",
                         "geometry.walls.0.pieces.1 (crest): the crest y = 0.0304 x^1.0001 "
                         "reaches the slope 10 only at x = inf");
    expect_profile_error(WALL_PROFILE("        - {piece: crest, coefficient: 0.0304, exponent: "
                                      "1.85, end_slope: 1.3, end_x: 41}\n"),
                         2, "crest", "41}", "give the crest's end once");
    expect_profile_error(
        WALL_PROFILE("        - {piece: crest, coefficient: 0.0304, exponent: 1.85}\n"), 2,
        "crest", "{piece", "a crest needs its end");
    expect_profile_error(WALL_PROFILE("        - {piece: arcc, radius: 0.057, turn: -90}\n"), 2,
                         "arcc", "arcc", "unknown piece 'arcc' in geometry.walls.0.pieces.1; "
                                         "did you mean 'arc'?");
    expect_profile_error(WALL_PROFILE("        - {piece: arc, radiuss: 0.057, turn: -90}\n"), 2,
                         "radiuss", "radiuss", "did you mean 'radius'?");
    expect_profile_error(WALL_PROFILE("        - {piece: line, to: [1, 0.5], dx: 1}\n"), 2,
                         "dx: 1", "1}", "'to' sets the line's end alone: remove 'dx'");
    expect_profile_error(WALL_PROFILE("        - {piece: line, to: [1, 0.5]}\n"
                                      "        - {piece: line, to: [1, 1]}\n"
                                      "        - {piece: line, to: [-1, 0.75]}\n"),
                         2, "[-1, 0.75]", "{piece",
                         "geometry.walls.0.pieces.3 (line): the profile crosses or touches itself "
                         "at (0, 0.875) m (with geometry.walls.0.pieces.0, line)");
    expect_profile_error("  walls:\n"
                         "    - shape: profile\n"
                         "      start: [0, 1]\n"
                         "      pieces: [{piece: arc, radius: 0.057, turn: -90}]\n",
                         2, "pieces", "{piece", "give the profile a 'heading'");
    expect_profile_error("  walls:\n"
                         "    - {shape: profile, start: [0, 1], peices: [{piece: line, to: [1, "
                         "1]}]}\n",
                         2, "peices", "peices", "unknown key 'peices' in geometry.walls.0; did "
                                                "you mean 'pieces'?");
    expect_profile_error("  walls:\n"
                         "    - {shape: profile, start: [0, 1]}\n",
                         2, "shape", "{shape", "geometry.walls.0 needs 'pieces'");
    expect_profile_error("  walls:\n"
                         "    - {shape: profile, start: [0, 1], pieces: [{piece: line, to: [0, "
                         "0]}]}\n",
                         3, "shape", "{shape", "missing required parameter 'across' in "
                                               "geometry.walls.0");
    /* a fluid region whose closing segment crosses its outline */
    expect_profile_error("  fluid:\n"
                         "    - shape: profile\n"
                         "      start: [0, 0]\n"
                         "      pieces:\n"
                         "        - {piece: line, to: [2, 0]}\n"
                         "        - {piece: line, to: [2, 2]}\n"
                         "        - {piece: line, to: [3, 1]}\n",
                         2, "[2, 2]", "{piece",
                         "geometry.fluid.0.pieces.1 (line): the profile crosses or touches itself "
                         "at (2, 0.666667) m (with the closing segment back to the start)");
}
END_TEST

int main(void)
{
    Suite *s = suite_create("geometry");
    TCase *basics = tcase_create("basics");
    tcase_set_timeout(basics, 120);
    tcase_add_test(basics, point_in_polygon_convex);
    tcase_add_test(basics, point_in_polygon_concave);
    tcase_add_test(basics, box_fill_2d);
    tcase_add_test(basics, box_fill_3d);
    tcase_add_test(basics, polygon_fill_triangle);
    tcase_add_test(basics, polygon_fill_l_shape);
    tcase_add_test(basics, prism_fill);
    tcase_add_test(basics, segment_closest);
    tcase_add_test(basics, triangle_closest_regions);
    tcase_add_test(basics, triangle_closest_random);
    suite_add_tcase(s, basics);
    TCase *walls = tcase_create("walls");
    tcase_set_timeout(walls, 120);
    tcase_add_test(walls, wall_refusals);
    tcase_add_test(walls, wall_normals_2d);
    tcase_add_test(walls, wall_normals_3d);
    tcase_add_test(walls, signed_distance_tank_2d);
    tcase_add_test(walls, signed_distance_3d);
    tcase_add_test(walls, signed_distance_obstacles_2d);
    tcase_add_test(walls, signed_distance_meshes_3d);
    tcase_add_test(walls, layer_tank_2d);
    tcase_add_test(walls, layer_tank_3d);
    tcase_add_test(walls, extruded_walls_3d);
    tcase_add_test(walls, channel_walls);
    tcase_add_test(walls, layer_slanted_2d);
    tcase_add_test(walls, layer_box_obstacles);
    tcase_add_test(walls, wall_watch_matches_full_query);
    suite_add_tcase(s, walls);
    /* a brute-force comparison over every element at many points (tag
     * `long`: the sanitizer pass of tools/run-tests.sh leaves it, the
     * cases above reach the same code) */
    TCase *every_element = tcase_create("walls_every_element");
    tcase_set_tags(every_element, "long");
    tcase_set_timeout(every_element, 120);
    tcase_add_test(every_element, wall_distance_matches_every_element);
    suite_add_tcase(s, every_element);
    TCase *profiles = tcase_create("profiles");
    tcase_set_timeout(profiles, 120);
    tcase_add_test(profiles, profile_steps);
    tcase_add_test(profiles, profile_arc);
    tcase_add_test(profiles, profile_crest);
    tcase_add_test(profiles, profile_lines);
    tcase_add_test(profiles, profile_crossings);
    tcase_add_test(profiles, profile_fill);
    tcase_add_test(profiles, profile_scene);
    tcase_add_test(profiles, profile_errors);
    suite_add_tcase(s, profiles);
    TCase *scale = tcase_create("scale");
    tcase_set_timeout(scale, 300);
    tcase_add_test(scale, fill_million);
    tcase_add_test(scale, layer_many_segments);
    tcase_add_test(scale, layer_many_triangles);
    suite_add_tcase(s, scale);
    return test_run_suite(s);
}
