/* Triangulated surfaces from files: STL (ASCII and binary) and Wavefront
 * OBJ, read into shared vertices and triangles, with the checks a wall or a
 * closed volume needs (open and non-manifold edges, winding). Pure
 * functions, no global state. docs/scene-format.md, "Walls from mesh
 * files". */
#ifndef SLUICE_MESH_FILE_H
#define SLUICE_MESH_FILE_H

#include <stdint.h>

typedef enum sluice_mesh_format {
    SLUICE_MESH_STL_ASCII = 0,
    SLUICE_MESH_STL_BINARY = 1,
    SLUICE_MESH_OBJ = 2
} sluice_mesh_format;

/* A triangulated surface. Vertices with equal coordinates are merged into
 * one (STL stores every triangle's three corners apart), which is how the
 * triangles' shared edges are found. The winding of each triangle is the
 * file's: its normal is (b - a) x (c - a); the normals an STL file stores
 * are not read. */
typedef struct sluice_mesh {
    sluice_mesh_format format;
    double *vertices; /* 3 per vertex */
    uint32_t vertex_count;
    uint32_t *faces; /* 3 vertex indices per triangle, in file order */
    uint32_t face_count;
    uint32_t *face_line; /* ASCII formats: the line of each triangle; NULL for binary STL */
} sluice_mesh;

/* Why a file was refused. line (and column) are 1-based, 0 when the
 * format has no lines (binary STL) or the problem is the file as a whole;
 * triangle is 0-based, UINT32_MAX when no triangle is at fault. */
typedef struct sluice_mesh_problem {
    int line, column;
    uint32_t triangle;
    char message[512];
} sluice_mesh_problem;

/* Reads `path`: the format from the extension (.stl or .obj, any case); an
 * STL file is binary when its size is 84 + 50 n bytes, n being the
 * triangle count at bytes 80-83 (little-endian), whatever its first bytes
 * say, else ASCII when it starts with `solid`. Refuses (returns -1 with
 * *problem filled) an unreadable or empty file, a truncated binary file or
 * one whose size disagrees with its count, a malformed ASCII line, a
 * non-numeric, NaN or infinite coordinate, a face index that is 0 or names
 * no vertex, a file without triangles and a degenerate (zero-area)
 * triangle. Returns 0 on success; the mesh is then freed with
 * sluice_mesh_free (it is left empty on failure). */
int sluice_mesh_read(const char *path, sluice_mesh *mesh, sluice_mesh_problem *problem);
void sluice_mesh_free(sluice_mesh *mesh);
const char *sluice_mesh_format_name(sluice_mesh_format format);

/* The edges of the surface, by how many triangles use them: an open edge
 * (one triangle: a boundary of an open surface), a non-manifold edge (three
 * or more), and a misoriented one (two triangles that run along it in the
 * same direction: their windings disagree). Counts and, for each kind, the
 * first triangle at fault (UINT32_MAX: none) and the edge's two vertices. */
typedef struct sluice_mesh_edges {
    uint64_t open, nonmanifold, misoriented;
    uint32_t open_triangle, nonmanifold_triangle, misoriented_triangle;
    uint32_t misoriented_other; /* the second triangle of the first misoriented edge */
    uint32_t nonmanifold_uses;  /* triangles on the first non-manifold edge */
    uint32_t open_edge[2], nonmanifold_edge[2], misoriented_edge[2];
} sluice_mesh_edges;

/* Returns 0, or -1 when out of memory. */
int sluice_mesh_check_edges(const sluice_mesh *mesh, sluice_mesh_edges *edges);

/* Total area, and the signed volume enclosed (divergence theorem, the sum
 * of a . (b x c) / 6 over the triangles): positive when a closed surface's
 * windings make its normals point out of it. */
double sluice_mesh_area(const sluice_mesh *mesh);
double sluice_mesh_volume(const sluice_mesh *mesh);

/* x -> R (scale x) + translate: first the scale, then the rotation by
 * angle_deg degrees about `axis` through the origin (right-hand rule), then
 * the translation. Returns -1 (mesh unchanged) when the scale is not
 * positive and finite or the axis is zero while the angle is not. */
int sluice_mesh_transform(sluice_mesh *mesh, double scale, const double axis[3], double angle_deg,
                          const double translate[3]);

/* Reverses every triangle's winding (a, b, c) -> (a, c, b). */
void sluice_mesh_reverse(sluice_mesh *mesh);

#endif
