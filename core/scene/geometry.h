/* Scene geometry: fluid regions filled on a lattice, and walls described once
 * (segments in 2D, triangles in 3D) for every wall scheme. Pure functions, no
 * global state. Points are always 3 reals (z = 0 in 2D). */
#ifndef SLUICE_GEOMETRY_H
#define SLUICE_GEOMETRY_H

#include <stddef.h>
#include <stdint.h>

#include "sluice/plugin.h"

/* A growable list of points (3 reals each). */
typedef struct sluice_points {
    sluice_real *xyz;
    size_t count, capacity;
} sluice_points;

int sluice_points_push(sluice_points *points, const sluice_real p[3]); /* 0 or -1 on OOM */
void sluice_points_free(sluice_points *points);

/* -------------------------------------------------------------- regions -- */

typedef enum sluice_region_shape {
    SLUICE_REGION_BOX = 0,     /* 2D/3D: min <= x < max */
    SLUICE_REGION_POLYGON = 1, /* 2D: closed polygon (either orientation) */
    SLUICE_REGION_PRISM = 2    /* 3D: polygon in x-y extruded over z in [zmin, zmax) */
} sluice_region_shape;

typedef struct sluice_region {
    sluice_region_shape shape;
    sluice_real min[3], max[3]; /* BOX; PRISM uses min[2], max[2] for z */
    const sluice_real *polygon; /* POLYGON/PRISM: vertex_count vertices, 2 reals each (x, y) */
    uint32_t vertex_count;
} sluice_region;

/* Axis-aligned bounding box of a region (3D box; z = 0 in 2D). */
void sluice_region_bounds(const sluice_region *region, uint32_t dimensions, sluice_real min[3],
                          sluice_real max[3]);
int sluice_region_contains(const sluice_region *region, uint32_t dimensions, const sluice_real p[3]);

/* Appends the lattice points lattice_origin + (k + 1/2) dx (per axis) that lie
 * inside the region. Returns 0 or -1 on OOM. */
int sluice_region_fill(const sluice_region *region, uint32_t dimensions, sluice_real spacing,
                       const sluice_real lattice_origin[3], sluice_points *out);

/* 2D point in polygon (even-odd rule); polygon is n vertices (x, y). */
int sluice_point_in_polygon(const sluice_real *polygon, uint32_t n, sluice_real x, sluice_real y);

/* Whether two edges of the closed polygon cross (a proper crossing: each
 * edge's ends strictly on both sides of the other), edge k running from
 * vertex k to vertex k + 1 (mod n); the first such pair in *edge_a <
 * *edge_b. A self-crossing outline has loops of opposite turn, which the
 * crossing-number fill counts as outside. */
int sluice_polygon_crossing(const sluice_real *polygon, uint32_t n, uint32_t *edge_a,
                            uint32_t *edge_b);

/* ---------------------------------------------------------------- walls -- */

/* Internal wall: the same layout as the public sluice_wall (points, normals)
 * plus pseudo-normals for a correct inside/outside sign at shared vertices
 * and edges. Build with sluice_wall_build_*(). */
typedef struct sluice_wall_geometry {
    uint32_t dimensions;
    uint32_t element_count;
    sluice_real *points;  /* 2D: 2 points per segment; 3D: 3 per triangle (3 reals per point) */
    sluice_real *normals; /* unit normal into the fluid, per element */
    /* Per element end/vertex: pseudo-normal (3 reals) and whether the vertex is
     * an open end (belongs to one element only, 2D). 2D: 2 per element;
     * 3D: 3 vertex pseudo-normals then 3 edge pseudo-normals per element. */
    sluice_real *vertex_normals;
    uint8_t *open_vertex;
    sluice_real *edge_normals; /* 3D only */
    uint8_t *open_edge;        /* 3D only: edge used by one triangle only */
} sluice_wall_geometry;

/* 2D polyline through n vertices (x, y); the fluid is on the left of each
 * segment a->b (normal = (-(by - ay), bx - ax) / length). closed != 0 joins
 * the last vertex to the first. Returns 0, or -1 (OOM or fewer than 2 distinct
 * vertices / zero-length segments: *reason is set). */
int sluice_wall_build_polyline(sluice_wall_geometry *wall, const sluice_real *xy, uint32_t n,
                               int closed, const char **reason);
/* 3D triangles: vertices (3 reals each) and faces (3 indices each), fluid on
 * the side of (b - a) x (c - a). */
int sluice_wall_build_triangles(sluice_wall_geometry *wall, const sluice_real *vertices,
                                uint32_t vertex_count, const uint32_t *faces,
                                uint32_t face_count, const char **reason);
/* An open-top tank with the fluid inside: 2D three segments (left, bottom,
 * right), 3D five rectangles (bottom and four sides) as triangles. */
int sluice_wall_build_tank(sluice_wall_geometry *wall, uint32_t dimensions,
                           const sluice_real min[3], const sluice_real max[3],
                           const char **reason);
/* An open channel: a tank without its ends across x (the fluid enters and
 * leaves there): 2D the bed, 3D the bed and the two sides. */
int sluice_wall_build_channel(sluice_wall_geometry *wall, uint32_t dimensions,
                              const sluice_real min[3], const sluice_real max[3],
                              const char **reason);
/* A solid box with the fluid outside (2D closed rectangle, 3D six faces). */
int sluice_wall_build_box(sluice_wall_geometry *wall, uint32_t dimensions,
                          const sluice_real min[3], const sluice_real max[3],
                          const char **reason);
void sluice_wall_geometry_free(sluice_wall_geometry *wall);

/* Closest point on a segment / triangle to p (3D arithmetic; 2D uses z = 0).
 * Return the distance; *feature tells which feature is closest:
 * segment: 0 interior, 1 vertex a, 2 vertex b;
 * triangle: 0 face, 1..3 vertex a/b/c, 4..6 edge ab/bc/ca. */
sluice_real sluice_segment_closest(const sluice_real p[3], const sluice_real a[3],
                                   const sluice_real b[3], sluice_real closest[3], int *feature);
sluice_real sluice_triangle_closest(const sluice_real p[3], const sluice_real a[3],
                                    const sluice_real b[3], const sluice_real c[3],
                                    sluice_real closest[3], int *feature);

/* Signed distance from p to the wall: > 0 on the fluid side, < 0 behind it,
 * using the pseudo-normal of the closest feature. *beyond_end is set to 1
 * when the closest feature is an open end (2D vertex used by one segment, 3D
 * boundary edge or its vertices) and p lies outside the wall's extent there,
 * so "behind" has no meaning; 0 otherwise. element (may be NULL) receives the
 * index of the closest element. */
sluice_real sluice_wall_signed_distance(const sluice_wall_geometry *wall, const sluice_real p[3],
                                        int *beyond_end, uint32_t *element);

/* As sluice_wall_signed_distance, over the elements subset[0..n) only (in
 * increasing order): the same result as the full query whenever the subset
 * holds every element that can be nearest to p (see wall_watch.c). */
sluice_real sluice_wall_signed_distance_among(const sluice_wall_geometry *wall,
                                              const sluice_real p[3], const uint32_t *subset,
                                              size_t n, int *beyond_end, uint32_t *element);

/* Over several walls: the unsigned distance from p to the nearest element
 * (HUGE_VAL without elements), and the elements within `limit` of p (their
 * count; when wall_out is not NULL also the elements, by wall then element).
 * The watchdog's cells (wall_watch.c) and api->walls->wall_distance's
 * (wall_distance.c) build their candidate lists with them. */
double sluice_walls_nearest_distance(const sluice_wall_geometry *const *walls, size_t wall_count,
                                     const sluice_real p[3]);
uint32_t sluice_walls_elements_within(const sluice_wall_geometry *const *walls, size_t wall_count,
                                      const sluice_real p[3], double limit, uint32_t *wall_out,
                                      uint32_t *element_out);

/* Unsigned distance from p to element e of the wall. */
sluice_real sluice_wall_element_distance(const sluice_wall_geometry *wall, uint32_t e,
                                         const sluice_real p[3]);

/* The nearest point of the wall to p: signed distance (as above), closest
 * point, the normal of the closest feature (pseudo-normal at vertices and
 * edges), element, feature and beyond_end; out->wall is left 0. */
void sluice_wall_nearest(const sluice_wall_geometry *wall, const sluice_real p[3],
                         sluice_wall_point *out);

/* Appends the lattice points (origin + (k + 1/2) dx) with
 * -thickness <= signed distance <= 0 and not beyond an open end. */
int sluice_wall_layer_points(const sluice_wall_geometry *wall, sluice_real spacing,
                             const sluice_real lattice_origin[3], sluice_real thickness,
                             sluice_points *out);

/* ------------------------------------------------------------- profiles -- */

/* A 2D profile: a polyline written as an engineer describes a structure, a
 * start point followed by pieces appended in order, each starting where the
 * previous one ended. Curved pieces are split into equal segments no longer
 * than max_segment. The fluid is on the left of the direction of travel, as
 * for every 2D wall polyline. Angles are in degrees, counter-clockwise from +x;
 * a heading is the direction of travel. */
typedef enum sluice_piece_kind {
    SLUICE_PIECE_LINE = 0,  /* straight line */
    SLUICE_PIECE_ARC = 1,   /* circular arc, tangent to the previous piece */
    SLUICE_PIECE_CREST = 2, /* power-law (WES) crest y = -a x^n from its apex */
    SLUICE_PIECE_STEPS = 3  /* flight of steps down towards +x */
} sluice_piece_kind;

/* Which keys a line was given. Its end is set by exactly one of: TO; DX and
 * DY together; one extent (LENGTH, DX, DY, TO_X or TO_Y: up to x = to_x or
 * y = to_y) along a direction, HEADING or SLOPE or else the previous piece's
 * direction. */
enum sluice_line_keys {
    SLUICE_LINE_TO = 1u << 0,
    SLUICE_LINE_DX = 1u << 1,
    SLUICE_LINE_DY = 1u << 2,
    SLUICE_LINE_LENGTH = 1u << 3,
    SLUICE_LINE_HEADING = 1u << 4,
    SLUICE_LINE_SLOPE = 1u << 5,
    SLUICE_LINE_TO_X = 1u << 6,
    SLUICE_LINE_TO_Y = 1u << 7
};

typedef struct sluice_profile_piece {
    sluice_piece_kind kind;
    /* LINE: to, to_x, to_y (m, absolute), dx, dy (m), length (m), heading
     * (deg), slope (dy/dx; with length: towards +x) */
    unsigned keys; /* sluice_line_keys given */
    double to[2], to_x, to_y, dx, dy, length, heading, slope;
    /* ARC: radius (m), turn (deg, > 0 counter-clockwise = to the left) */
    double radius, turn;
    /* CREST: y below the apex = unit * coefficient * (x / unit)^exponent, x
     * from the apex towards +x; it ends where the slope dy/dx (downwards)
     * reaches end_slope, or at x = end_x (in units) when end_at_x */
    double coefficient, exponent, unit, end_slope, end_x;
    int end_at_x;
    /* STEPS: count steps of height (rise) and length (tread), each a riser
     * down then a tread towards +x (tread first when tread_first) */
    uint32_t count;
    double height, step_length;
    int tread_first;
} sluice_profile_piece;

typedef struct sluice_profile {
    double start[2];
    int has_heading;
    double heading; /* deg: direction before the first piece */
    const sluice_profile_piece *pieces;
    uint32_t piece_count;
    int closed;         /* join the last vertex to the start */
    double max_segment; /* m: longest segment of a curved piece */
} sluice_profile;

/* The discretised profile: vertex_count vertices (x, y); piece[v] is the
 * piece whose segment ends at vertex v (UINT32_MAX for the start). A closed
 * profile does not repeat the start at the end. */
typedef struct sluice_profile_path {
    sluice_real *xy;
    uint32_t *piece;
    uint32_t vertex_count;
} sluice_profile_path;

/* Why a profile was refused: the piece at fault (UINT32_MAX: the profile as a
 * whole), the other piece of a crossing (UINT32_MAX: none, or the closing
 * segment when `closing`), the key at fault (NULL: the piece itself). */
typedef struct sluice_profile_problem {
    uint32_t piece, other;
    int closing;
    const char *key;
    char message[400];
} sluice_profile_problem;

/* Most vertices of one profile. */
#define SLUICE_PROFILE_MAX_VERTICES (1u << 22)

/* Builds the vertices. Returns 0, or -1 with *problem filled (bad parameters,
 * a line whose end is not determined, a curve needing more than
 * SLUICE_PROFILE_MAX_VERTICES vertices, a profile that crosses, touches or
 * folds back on itself, out of memory). */
int sluice_profile_build(const sluice_profile *profile, sluice_profile_path *out,
                         sluice_profile_problem *problem);
void sluice_profile_path_free(sluice_profile_path *path);
const char *sluice_piece_name(sluice_piece_kind kind);

/* Segment crossing test of a polyline of n vertices (closed: also the
 * segment n-1 -> 0): two segments that are not neighbours crossing or
 * touching, or two neighbours folding back onto each other. Returns 1 and the
 * two segments (*first < *second; the segment s runs from vertex s) and a
 * point of contact, 0 when the polyline is simple, -1 on OOM. */
int sluice_polyline_crossing(const sluice_real *xy, uint32_t n, int closed, uint32_t *first,
                             uint32_t *second, double where[2]);

#endif
