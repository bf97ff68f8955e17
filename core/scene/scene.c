#define _GNU_SOURCE
#include "scene.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "mesh_file.h"
#include "schema.h"

#define OFF(type, member) offsetof(type, member)

/* ------------------------------------------------------------ sections -- */

typedef struct {
    sluice_real spacing, smoothing_length_ratio, rest_density;
    sluice_real lattice_origin[3];
} particles_config;

static const sluice_param_spec particles_specs[] = {
    {"spacing", SLUICE_PARAM_REAL, OFF(particles_config, spacing), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m",
     "initial particle spacing dx of the lattice every region is filled on", NULL, 0},
    {"smoothing_length_ratio", SLUICE_PARAM_REAL, OFF(particles_config, smoothing_length_ratio),
     "1.3", 0.5, 4.0, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "smoothing length h as a multiple of the spacing (kernel support is 2h)", NULL, 0},
    {"rest_density", SLUICE_PARAM_REAL, OFF(particles_config, rest_density), "1000", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "kg m^-3",
     "reference density rho0 of the fluid; particle mass is rho0 dx^d", NULL, 0},
    {"lattice_origin", SLUICE_PARAM_VECTOR, OFF(particles_config, lattice_origin),
     "[0, 0] | [0, 0, 0]", 0, 0, 0, "m",
     "origin of the lattice: particles sit at origin + (k + 1/2) dx", NULL, SLUICE_LENGTH_DIM},
};

typedef struct {
    sluice_real end, max_step;
} time_config;

static const sluice_param_spec time_specs[] = {
    /* at least 1e-6 s, as every output interval: below 1e-12 s the time loop
     * counts the end as reached before the first step */
    {"end", SLUICE_PARAM_REAL, OFF(time_config, end), NULL, 1e-6, 0, SLUICE_PARAM_HAS_MIN, "s",
     "simulated time at which the run ends", NULL, 0},
    {"max_step", SLUICE_PARAM_REAL, OFF(time_config, max_step), "0", 0, 0, SLUICE_PARAM_HAS_MIN,
     "s", "upper limit of the time step (0: no limit beyond the stability conditions)", NULL, 0},
};

typedef struct {
    sluice_real min[3], max[3];
    const char *periodic;
} domain_config;

static const sluice_param_spec domain_specs[] = {
    {"min", SLUICE_PARAM_VECTOR, OFF(domain_config, min), NULL, 0, 0, 0, "m",
     "lower corner of the computational domain", NULL, SLUICE_LENGTH_DIM},
    {"max", SLUICE_PARAM_VECTOR, OFF(domain_config, max), NULL, 0, 0, 0, "m",
     "upper corner of the computational domain; a particle leaving a non-periodic side stops "
     "the run",
     NULL, SLUICE_LENGTH_DIM},
    {"periodic", SLUICE_PARAM_STRING, OFF(domain_config, periodic), "none", 0, 0, 0, NULL,
     "periodic directions: none, or the axes, e.g. x, xy, xyz", NULL, 0},
};

typedef struct {
    int density;
} initial_config;

static const sluice_param_spec initial_specs[] = {
    {"density", SLUICE_PARAM_ENUM, OFF(initial_config, density), "hydrostatic", 0, 0, 0, NULL,
     "initial fluid density: hydrostatic (from the equation of state and gravity, below each "
     "region's free surface) or rest (rho0 everywhere)",
     "hydrostatic|rest", 0},
};

typedef struct {
    sluice_real skin;
    int64_t batch_pairs;
} neighbour_config;

static const sluice_param_spec neighbour_specs[] = {
    {"skin", SLUICE_PARAM_REAL, OFF(neighbour_config, skin), "0.1", 0, 2,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "extra radius of the neighbour list as a fraction of the kernel support; the list is rebuilt "
     "when a particle has moved half of it",
     NULL, 0},
    {"batch_pairs", SLUICE_PARAM_INT, OFF(neighbour_config, batch_pairs), "1024", 64, 1 << 20,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "pairs per batch handed to the pair terms", NULL, 0},
};

typedef struct {
    sluice_real density_band, min_time_step, wall_penetration;
    int64_t every;
} watchdog_config;

static const sluice_param_spec watchdog_specs[] = {
    {"density_band", SLUICE_PARAM_REAL, OFF(watchdog_config, density_band), "0.5", 0, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "a density outside rho0 (1 +/- band) stops the run", NULL, 0},
    {"min_time_step", SLUICE_PARAM_REAL, OFF(watchdog_config, min_time_step), "1e-9", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "s",
     "a time step below this stops the run", NULL, 0},
    {"every", SLUICE_PARAM_INT, OFF(watchdog_config, every), "1", 1, 1000000,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1", "check the state every this many steps",
     NULL, 0},
    {"wall_penetration", SLUICE_PARAM_REAL, OFF(watchdog_config, wall_penetration), "0.5", 0,
     1000, SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "spacings",
     "a fluid particle deeper than this behind a wall surface (in particle spacings) has gone "
     "through the wall and stops the run",
     NULL, 0},
};

typedef struct {
    sluice_real interval;
    int64_t keep;
} checkpoint_config;

static const sluice_param_spec checkpoint_specs[] = {
    {"interval", SLUICE_PARAM_REAL, OFF(checkpoint_config, interval), "0", 0, 0,
     SLUICE_PARAM_HAS_MIN, "s",
     "simulated time between checkpoints (DIR/checkpoint_<step>.h5, at t = interval, 2 interval, "
     "...; steps end exactly on them); 0: none (a run stopped by SIGINT or SIGTERM still writes "
     "one)",
     NULL, 0},
    {"keep", SLUICE_PARAM_INT, OFF(checkpoint_config, keep), "2", 0, 1000000,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "checkpoints of this run kept on disk, the newest (older ones are deleted); 0: keep all",
     NULL, 0},
};

typedef struct {
    int split;
    int balance;
    int64_t every;
    sluice_real tolerance;
} ranks_config;

/* ranks.split's choices, as masks of axes (bit d: axis d) */
static const int split_axes[] = {1, 2, 4, 3, 5, 6, 7};

static const sluice_param_spec ranks_specs[] = {
    {"split", SLUICE_PARAM_ENUM, OFF(ranks_config, split), "x", 0, 0, 0, NULL,
     "in a run across MPI ranks (docs/scaling.md), the axes along which the domain is cut into "
     "one box per rank: x (slabs along the flow), or several (xy, xyz, ...), the number of cuts "
     "along each chosen so that the boxes have the least surface for the particles' extent",
     "x|y|z|xy|xz|yz|xyz", 0},
    {"balance", SLUICE_PARAM_ENUM, OFF(ranks_config, balance), "time", 0, 0, 0, "1",
     "in a run across MPI ranks (docs/scaling.md), what the cuts between the ranks' boxes are "
     "moved to equalise during the run: the ranks' measured time in the passes, their particle counts "
     "(reproducible from run to run), or nothing (the slabs of the start)",
     "time|count|none", 0},
    {"every", SLUICE_PARAM_INT, OFF(ranks_config, every), "50", 1, 1000000000,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "steps between two looks at the balance (a move rebuilds the neighbour lists)", NULL,
     0},
    {"tolerance", SLUICE_PARAM_REAL, OFF(ranks_config, tolerance), "0.05", 0, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_HAS_MAX, "1",
     "the cuts move when the largest rank's share exceeds the mean by this fraction",
     NULL, 0},
};

/* ------------------------------------------------------------ geometry -- */

typedef struct {
    int shape;
    sluice_real min[3], max[3];
    sluice_real_list points;
    sluice_real start[3], heading, max_segment; /* profile */
    sluice_real velocity[3];
    sluice_real surface;
    sluice_real lattice_origin[3];
    const char *name;
} fluid_config;

#define FLUID_SHAPES "box|polygon|profile"
#define FLUID_COMMON                                                                            \
    {"velocity", SLUICE_PARAM_VECTOR, OFF(fluid_config, velocity), "[0, 0] | [0, 0, 0]", 0, 0, \
     0, "m s^-1", "initial velocity of the region's particles", NULL, SLUICE_LENGTH_DIM},      \
    {                                                                                           \
        "surface", SLUICE_PARAM_REAL, OFF(fluid_config, surface), NULL, 0, 0,                   \
            SLUICE_PARAM_OPTIONAL, "m",                                                         \
            "free-surface level (vertical coordinate) for the hydrostatic initial density; "    \
            "default: the top of the region",                                                  \
            NULL, 0                                                                             \
    },                                                                                          \
    {                                                                                           \
        "lattice_origin", SLUICE_PARAM_VECTOR, OFF(fluid_config, lattice_origin), NULL, 0, 0,   \
            SLUICE_PARAM_OPTIONAL, "m",                                                         \
            "this region's lattice: points at lattice_origin + (k + 1/2) dx (default: "         \
            "particles.lattice_origin); align a region with its own bed",                      \
            NULL, SLUICE_LENGTH_DIM                                                             \
    },                                                                                          \
    {                                                                                           \
        "name", SLUICE_PARAM_STRING, OFF(fluid_config, name), NULL, 0, 0,                       \
            SLUICE_PARAM_OPTIONAL, NULL,                                                        \
            "label of the region (a path in --set or a variant may address it by name)", NULL,  \
            0                                                                                   \
    }

static const sluice_param_spec fluid_box_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(fluid_config, shape), NULL, 0, 0, 0, NULL,
     "shape of the region", FLUID_SHAPES, 0},
    {"min", SLUICE_PARAM_VECTOR, OFF(fluid_config, min), NULL, 0, 0, 0, "m", "lower corner", NULL,
     SLUICE_LENGTH_DIM},
    {"max", SLUICE_PARAM_VECTOR, OFF(fluid_config, max), NULL, 0, 0, 0, "m", "upper corner", NULL,
     SLUICE_LENGTH_DIM},
    FLUID_COMMON,
};

static const sluice_param_spec fluid_polygon_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(fluid_config, shape), NULL, 0, 0, 0, NULL,
     "shape of the region", FLUID_SHAPES, 0},
    {"points", SLUICE_PARAM_POINT_LIST, OFF(fluid_config, points), NULL, 0, 0, 0, "m",
     "vertices of the polygon (2D)", NULL, 0},
    FLUID_COMMON,
};

/* The keys of a profile. `pieces` is read by load_profile and taken out of
 * the mapping while the binder reads the rest: its entry here is never
 * bound, it names the key for the binder's suggestions and key lists. */
#define PROFILE_KEYS(type)                                                                      \
    {"pieces", SLUICE_PARAM_POINT_LIST, OFF(type, points), NULL, 0, 0, SLUICE_PARAM_OPTIONAL,    \
     NULL, "the pieces (line, arc, crest, steps), in order from the start", NULL, 0},           \
    {"start", SLUICE_PARAM_VECTOR, OFF(type, start), NULL, 0, 0, 0, "m",                        \
     "first vertex of the profile (2D)", NULL, 2},                                              \
    {"heading", SLUICE_PARAM_REAL, OFF(type, heading), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "deg", \
     "direction of travel before the first piece, in degrees counter-clockwise from +x "       \
     "(needed when the first piece continues a direction: an arc, a line by length)",          \
     NULL, 0},                                                                                  \
    {                                                                                           \
        "max_segment", SLUICE_PARAM_REAL, OFF(type, max_segment), NULL, 0, 0,                   \
            SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_OPTIONAL, "m",     \
            "longest segment of a curved piece (arc, crest); default particles.spacing / 2",    \
            NULL, 0                                                                             \
    }

static const sluice_param_spec fluid_profile_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(fluid_config, shape), NULL, 0, 0, 0, NULL,
     "profile: the region inside a profile closed back to its start (2D)", FLUID_SHAPES, 0},
    PROFILE_KEYS(fluid_config),
    FLUID_COMMON,
};

typedef struct {
    int shape;
    sluice_real min[3], max[3];
    sluice_real_list points;
    sluice_real start[3], heading, max_segment; /* profile */
    int closed;
    const char *scheme, *name;
    sluice_real lattice_origin[3];
    sluice_real across[3]; /* 3D outlines: extruded over y in [across[0], across[1]] */
    const char *file;      /* mesh */
    int fluid;             /* mesh: MESH_FLUID_SIDES */
    sluice_real scale, rotate_axis[3], rotate_angle, translate[3];
} wall_config;

#define WALL_SHAPES "tank|box|polyline|polygon|profile|channel|mesh"
#define MESH_FLUID_SIDES "outside|inside|front|back"
enum { MESH_FLUID_OUTSIDE = 0, MESH_FLUID_INSIDE = 1, MESH_FLUID_FRONT = 2, MESH_FLUID_BACK = 3 };
#define WALL_COMMON                                                                             \
    {"scheme", SLUICE_PARAM_STRING, OFF(wall_config, scheme), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, \
     NULL, "wall scheme plugin for this wall (default: the only one loaded)", NULL, 0},        \
    {                                                                                           \
        "name", SLUICE_PARAM_STRING, OFF(wall_config, name), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, \
            NULL, "name of the wall in reports", NULL, 0                                        \
    },                                                                                          \
    {                                                                                           \
        "lattice_origin", SLUICE_PARAM_VECTOR, OFF(wall_config, lattice_origin), NULL, 0, 0,    \
            SLUICE_PARAM_OPTIONAL, "m",                                                         \
            "lattice of this wall's particle layers (default: particles.lattice_origin)",       \
            NULL, SLUICE_LENGTH_DIM                                                             \
    }

static const sluice_param_spec wall_box_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(wall_config, shape), NULL, 0, 0, 0, NULL,
     "tank: open-top container with the fluid inside; box: solid block with the fluid "
     "outside; channel: a tank without its ends across x (the bed and, in 3D, the sides)",
     WALL_SHAPES, 0},
    {"min", SLUICE_PARAM_VECTOR, OFF(wall_config, min), NULL, 0, 0, 0, "m", "lower corner", NULL,
     SLUICE_LENGTH_DIM},
    {"max", SLUICE_PARAM_VECTOR, OFF(wall_config, max), NULL, 0, 0, 0, "m", "upper corner", NULL,
     SLUICE_LENGTH_DIM},
    WALL_COMMON,
};

static const sluice_param_spec wall_line_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(wall_config, shape), NULL, 0, 0, 0, NULL,
     "polyline: open line with the fluid on its left; polygon: closed solid with the fluid "
     "outside",
     WALL_SHAPES, 0},
    {"points", SLUICE_PARAM_POINT_LIST, OFF(wall_config, points), NULL, 0, 0, 0, "m",
     "vertices (2D)", NULL, 0},
    WALL_COMMON,
};

/* In 3D a polyline, polygon or profile is an outline in the (x, z) plane
 * extruded across y. */
#define WALL_ACROSS                                                                             \
    {"across", SLUICE_PARAM_VECTOR, OFF(wall_config, across), NULL, 0, 0, 0, "m",              \
     "3D: the outline (x, z) is extruded across y from across[0] to across[1] (open at both "   \
     "ends: place it between side walls)",                                                      \
     NULL, 2}

static const sluice_param_spec wall_line_specs_3d[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(wall_config, shape), NULL, 0, 0, 0, NULL,
     "polyline: open line with the fluid on its left (in x-z, seen from -y); polygon: closed "
     "solid with the fluid outside",
     WALL_SHAPES, 0},
    {"points", SLUICE_PARAM_POINT_LIST, OFF(wall_config, points), NULL, 0, 0, 0, "m",
     "vertices (x, z) of the outline", NULL, 2},
    WALL_ACROSS,
    WALL_COMMON,
};

static const sluice_param_spec wall_profile_specs_3d[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(wall_config, shape), NULL, 0, 0, 0, NULL,
     "profile: a wall built from pieces (lines, arcs, crests, steps) in the (x, z) plane, the "
     "fluid on its left, extruded across y",
     WALL_SHAPES, 0},
    PROFILE_KEYS(wall_config),
    {"closed", SLUICE_PARAM_BOOL, OFF(wall_config, closed), "false", 0, 0, 0, NULL,
     "join the end back to the start", NULL, 0},
    WALL_ACROSS,
    WALL_COMMON,
};

static const sluice_param_spec wall_profile_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(wall_config, shape), NULL, 0, 0, 0, NULL,
     "profile: a 2D wall built from pieces (lines, arcs, crests, steps), the fluid on its left",
     WALL_SHAPES, 0},
    PROFILE_KEYS(wall_config),
    {"closed", SLUICE_PARAM_BOOL, OFF(wall_config, closed), "false", 0, 0, 0, NULL,
     "join the end back to the start (the fluid is still on the left: inside a "
     "counter-clockwise profile, outside a clockwise one)",
     NULL, 0},
    WALL_COMMON,
};

/* A surface read from a mesh file (3D): docs/scene-format.md, "Walls from
 * mesh files". */
static const sluice_param_spec wall_mesh_specs[] = {
    {"shape", SLUICE_PARAM_ENUM, OFF(wall_config, shape), NULL, 0, 0, 0, NULL,
     "mesh: a triangulated surface read from an STL (ASCII or binary) or OBJ file (3D)",
     WALL_SHAPES, 0},
    {"file", SLUICE_PARAM_STRING, OFF(wall_config, file), NULL, 0, 0, 0, NULL,
     "the surface: a .stl or .obj file, relative to the scene file's directory", NULL, 0},
    {"fluid", SLUICE_PARAM_ENUM, OFF(wall_config, fluid), NULL, 0, 0, 0, NULL,
     "side of the fluid: outside or inside a closed surface (whatever its winding), or in "
     "front of every triangle (the side from which its corners turn counter-clockwise) or "
     "behind it (open or closed surfaces)",
     MESH_FLUID_SIDES, 0},
    {"scale", SLUICE_PARAM_REAL, OFF(wall_config, scale), "1", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m",
     "length of one unit of the file in metres (0.001 for a file in mm); applied first", NULL,
     0},
    {"rotate_axis", SLUICE_PARAM_VECTOR, OFF(wall_config, rotate_axis), "[0, 0, 1]", 0, 0, 0,
     "1", "axis of the rotation, through the origin; applied after the scale", NULL, 3},
    {"rotate_angle", SLUICE_PARAM_REAL, OFF(wall_config, rotate_angle), "0", 0, 0, 0, "deg",
     "angle of the rotation about rotate_axis (right-hand rule)", NULL, 0},
    {"translate", SLUICE_PARAM_VECTOR, OFF(wall_config, translate), "[0, 0, 0]", 0, 0, 0, "m",
     "translation; applied last", NULL, 3},
    WALL_COMMON,
};

/* ------------------------------------------------------------- pieces -- */

typedef struct {
    int piece;
    sluice_real to[3], to_x, to_y, dx, dy, length, heading, slope; /* line; length: steps too */
    sluice_real radius, turn;                          /* arc */
    sluice_real coefficient, exponent, unit, end_slope, end_x; /* crest */
    int64_t count;                                     /* steps */
    sluice_real height;
    int first;
} piece_config;

#define PIECE_KINDS "line|arc|crest|steps"
#define PIECE_KEY                                                                               \
    {"piece", SLUICE_PARAM_ENUM, OFF(piece_config, piece), NULL, 0, 0, 0, NULL,                 \
     "kind of piece", PIECE_KINDS, 0}

static const sluice_param_spec piece_line_specs[] = {
    PIECE_KEY,
    {"to", SLUICE_PARAM_VECTOR, OFF(piece_config, to), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "m",
     "end point", NULL, 2},
    {"to_x", SLUICE_PARAM_REAL, OFF(piece_config, to_x), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "m",
     "or: the line runs along its direction up to x = to_x", NULL, 0},
    {"to_y", SLUICE_PARAM_REAL, OFF(piece_config, to_y), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "m",
     "or: the line runs along its direction up to y = to_y", NULL, 0},
    {"dx", SLUICE_PARAM_REAL, OFF(piece_config, dx), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "m",
     "extent along x (with dy: the end is start + (dx, dy))", NULL, 0},
    {"dy", SLUICE_PARAM_REAL, OFF(piece_config, dy), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "m",
     "extent along y", NULL, 0},
    {"length", SLUICE_PARAM_REAL, OFF(piece_config, length), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_OPTIONAL, "m",
     "length along the direction (heading, slope, or the previous piece's)", NULL, 0},
    {"heading", SLUICE_PARAM_REAL, OFF(piece_config, heading), NULL, 0, 0, SLUICE_PARAM_OPTIONAL,
     "deg", "direction, in degrees counter-clockwise from +x (default: the previous piece's)",
     NULL, 0},
    {"slope", SLUICE_PARAM_REAL, OFF(piece_config, slope), NULL, 0, 0, SLUICE_PARAM_OPTIONAL, "1",
     "direction as the gradient dy/dx, not an angle (with length: towards +x); -1.333 for a "
     "1:0.75 chute",
     NULL, 0},
};

static const sluice_param_spec piece_arc_specs[] = {
    PIECE_KEY,
    {"radius", SLUICE_PARAM_REAL, OFF(piece_config, radius), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m", "radius of the arc", NULL, 0},
    {"turn", SLUICE_PARAM_REAL, OFF(piece_config, turn), NULL, -360, 360,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "deg",
     "change of direction along the arc, in degrees: > 0 counter-clockwise (towards the fluid "
     "side), < 0 clockwise",
     NULL, 0},
};

static const sluice_param_spec piece_crest_specs[] = {
    PIECE_KEY,
    {"coefficient", SLUICE_PARAM_REAL, OFF(piece_config, coefficient), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "1",
     "a of the crest y = a x^n (y below the apex, x downstream of it, both in units)", NULL, 0},
    {"exponent", SLUICE_PARAM_REAL, OFF(piece_config, exponent), NULL, 1, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "1", "n of the crest y = a x^n (1.85 for "
     "the WES standard crest)", NULL, 0},
    {"unit", SLUICE_PARAM_REAL, OFF(piece_config, unit), "1", 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m",
     "length of one unit of x and y in the crest's equation (0.01: centimetres)", NULL, 0},
    {"end_slope", SLUICE_PARAM_REAL, OFF(piece_config, end_slope), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_OPTIONAL, "1",
     "the crest ends where its slope, the gradient dy/dx (not an angle), reaches this (1.3333 "
     "for 1:0.75), the tangent point",
     NULL, 0},
    {"end_x", SLUICE_PARAM_REAL, OFF(piece_config, end_x), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE | SLUICE_PARAM_OPTIONAL, "units",
     "or: the crest ends at this x from the apex (in units)", NULL, 0},
};

static const sluice_param_spec piece_steps_specs[] = {
    PIECE_KEY,
    {"count", SLUICE_PARAM_INT, OFF(piece_config, count), NULL, 1, 1000000,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1", "number of steps", NULL, 0},
    {"height", SLUICE_PARAM_REAL, OFF(piece_config, height), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m", "rise of each step (riser)", NULL,
     0},
    {"length", SLUICE_PARAM_REAL, OFF(piece_config, length), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m",
     "horizontal length of each step (tread)", NULL, 0},
    {"first", SLUICE_PARAM_ENUM, OFF(piece_config, first), "riser", 0, 0, 0, NULL,
     "each step is a riser down then a tread towards +x, or the tread first", "riser|tread", 0},
};

/* ------------------------------------------------------------- helpers -- */

static const char *const top_level_keys[] = {
    "title",    "description", "dimensions", "particles", "time",       "domain",
    "geometry", "initial",     "neighbour_search", "watchdog", "plugins", "plugin_path",
    "checkpoint", "ranks", "variants", "variant",
};

static const char *const variant_keys[] = {"description", "remove", "swap", "set"};

#define TABLE(name, specs, dims) {name, specs, SLUICE_COUNT(specs), NULL, 0, dims}
#define TABLE_3D(name, specs, specs_3d)                                                         \
    {name, specs, SLUICE_COUNT(specs), specs_3d, SLUICE_COUNT(specs_3d), SLUICE_DIMS_ALL}

static const sluice_scene_table section_tables[] = {
    TABLE("particles", particles_specs, SLUICE_DIMS_ALL),
    TABLE("time", time_specs, SLUICE_DIMS_ALL),
    TABLE("domain", domain_specs, SLUICE_DIMS_ALL),
    TABLE("initial", initial_specs, SLUICE_DIMS_ALL),
    TABLE("neighbour_search", neighbour_specs, SLUICE_DIMS_ALL),
    TABLE("watchdog", watchdog_specs, SLUICE_DIMS_ALL),
    TABLE("checkpoint", checkpoint_specs, SLUICE_DIMS_ALL),
    TABLE("ranks", ranks_specs, SLUICE_DIMS_ALL),
};

/* in the order of FLUID_SHAPES */
static const sluice_scene_table fluid_tables[] = {
    TABLE("box", fluid_box_specs, SLUICE_DIMS_ALL),
    TABLE("polygon", fluid_polygon_specs, SLUICE_DIMS_2),
    TABLE("profile", fluid_profile_specs, SLUICE_DIMS_2),
};

/* in the order of WALL_SHAPES */
static const sluice_scene_table wall_tables[] = {
    TABLE("tank", wall_box_specs, SLUICE_DIMS_ALL),
    TABLE("box", wall_box_specs, SLUICE_DIMS_ALL),
    TABLE_3D("polyline", wall_line_specs, wall_line_specs_3d),
    TABLE_3D("polygon", wall_line_specs, wall_line_specs_3d),
    TABLE_3D("profile", wall_profile_specs, wall_profile_specs_3d),
    TABLE("channel", wall_box_specs, SLUICE_DIMS_ALL),
    TABLE("mesh", wall_mesh_specs, SLUICE_DIMS_3),
};

/* in the order of PIECE_KINDS */
static const sluice_scene_table piece_tables[] = {
    TABLE("line", piece_line_specs, SLUICE_DIMS_ALL),
    TABLE("arc", piece_arc_specs, SLUICE_DIMS_ALL),
    TABLE("crest", piece_crest_specs, SLUICE_DIMS_ALL),
    TABLE("steps", piece_steps_specs, SLUICE_DIMS_ALL),
};

const sluice_scene_format *sluice_scene_format_tables(void)
{
    static const sluice_scene_format format = {
        top_level_keys, SLUICE_COUNT(top_level_keys), section_tables,
        SLUICE_COUNT(section_tables), fluid_tables, SLUICE_COUNT(fluid_tables),
        wall_tables, SLUICE_COUNT(wall_tables), piece_tables,
        SLUICE_COUNT(piece_tables), variant_keys, SLUICE_COUNT(variant_keys),
    };
    return &format;
}

const char *sluice_node_file(const sluice_node *node, const sluice_scene *scene)
{
    return node && node->file ? node->file : scene->path;
}

static void error_at(sluice_diag *diag, const sluice_scene *scene, const sluice_node *node,
                     const char *format, ...) SLUICE_PRINTF(4, 5);
#include <stdarg.h>
static void error_at(sluice_diag *diag, const sluice_scene *scene, const sluice_node *node,
                     const char *format, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    int line = node ? node->line : 1, column = node ? node->column : 1;
    if (line <= 0) {
        line = 1;
        column = 1;
    }
    sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, sluice_node_file(node, scene), line, column, "%s",
                    text);
}

/* Slot of `key` in a mapping, creating an empty mapping entry when absent. */
static sluice_node **section_slot(sluice_node *mapping, const char *key, int create)
{
    for (size_t i = 0; i < mapping->count; i++)
        if (strcmp(mapping->keys[i]->value, key) == 0)
            return &mapping->items[i];
    if (!create)
        return NULL;
    sluice_node *fresh = sluice_node_new_mapping("default", 0, 0);
    if (!fresh || sluice_node_set(mapping, key, fresh) != 0)
        return NULL;
    for (size_t i = 0; i < mapping->count; i++)
        if (strcmp(mapping->keys[i]->value, key) == 0)
            return &mapping->items[i];
    return NULL;
}

static int bind_section(sluice_scene *scene, const char *key, const sluice_param_spec *specs,
                        uint32_t count, void *config, sluice_diag *diag)
{
    sluice_node **slot = section_slot(scene->root, key, 1);
    if (!slot) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 0, 0, "out of memory");
        return 1;
    }
    return sluice_schema_bind(specs, count, slot, scene->root, key, scene->dimensions, config,
                              scene->arena, diag);
}

static int parse_periodic(const char *text, uint32_t dims, int periodic[3])
{
    periodic[0] = periodic[1] = periodic[2] = 0;
    if (strcmp(text, "none") == 0)
        return 0;
    if (!*text)
        return -1;
    for (const char *c = text; *c; c++) {
        int axis = *c == 'x' ? 0 : *c == 'y' ? 1 : *c == 'z' ? 2 : -1;
        if (axis < 0 || (uint32_t)axis >= dims || periodic[axis])
            return -1;
        periodic[axis] = 1;
    }
    return 0;
}

/* Splits "a|b|c" into names (pointers into buffer); returns the count. */
static size_t split_choices(const char *choices, char *buffer, size_t size, const char **names,
                            size_t max_names)
{
    snprintf(buffer, size, "%s", choices);
    size_t n = 0;
    char *save = NULL;
    for (char *tok = strtok_r(buffer, "|", &save); tok && n < max_names;
         tok = strtok_r(NULL, "|", &save))
        names[n++] = tok;
    return n;
}

/* Reads `shape` of a geometry item; returns its index in choices or -1 after
 * reporting the error. */
static int item_shape(sluice_scene *scene, const sluice_node *item, const char *list,
                      const char *choices, sluice_diag *diag)
{
    if (!item || item->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, item, "each entry of geometry.%s must be a mapping with a 'shape'",
                 list);
        return -1;
    }
    const sluice_node *shape = sluice_node_get(item, "shape");
    char buffer[128];
    const char *names[8];
    size_t count = split_choices(choices, buffer, sizeof buffer, names, 8);
    if (!shape) {
        error_at(diag, scene, item, "this entry of geometry.%s has no 'shape' (one of: %s)", list,
                 choices);
        return -1;
    }
    if (shape->kind == SLUICE_NODE_SCALAR)
        for (size_t i = 0; i < count; i++)
            if (strcmp(shape->value, names[i]) == 0)
                return (int)i;
    const char *close =
        shape->kind == SLUICE_NODE_SCALAR ? sluice_closest(shape->value, names, count) : NULL;
    if (close)
        error_at(diag, scene, shape, "unknown shape '%s' in geometry.%s; did you mean '%s'?",
                 shape->value, list, close);
    else
        error_at(diag, scene, shape, "unknown shape in geometry.%s (one of: %s)", list, choices);
    return -1;
}

static sluice_real *polygon_xy(sluice_arena *arena, const sluice_real_list *points, int reverse)
{
    sluice_real *xy = sluice_arena_alloc(arena, (size_t)points->count * 2 * sizeof *xy);
    if (!xy)
        return NULL;
    for (uint32_t k = 0; k < points->count; k++) {
        uint32_t src = reverse ? points->count - 1 - k : k;
        xy[2 * k] = points->values[3 * src];
        xy[2 * k + 1] = points->values[3 * src + 1];
    }
    return xy;
}

/* A 2D outline (x, z) of n vertices extruded across y from across[0] to
 * across[1]: two triangles per segment, the fluid on the left of each
 * segment a -> b seen with x to the right and z up (the 2D polyline's rule),
 * open at both ends across y. */
static int build_extruded(sluice_wall_geometry *wall, const sluice_real *xz, uint32_t n,
                          int closed, const sluice_real *across, const char **reason)
{
    const uint32_t segments = closed ? n : n - 1;
    sluice_real *vertices = malloc(((size_t)n * 6 + 1) * sizeof *vertices);
    uint32_t *faces = malloc(((size_t)segments * 6 + 1) * sizeof *faces);
    if (!vertices || !faces) {
        free(vertices);
        free(faces);
        *reason = "out of memory";
        return -1;
    }
    for (uint32_t k = 0; k < n; k++)
        for (int side = 0; side < 2; side++) {
            sluice_real *v = vertices + 3 * (2 * (size_t)k + (size_t)side);
            v[0] = xz[2 * k];
            v[1] = across[side];
            v[2] = xz[2 * k + 1];
        }
    uint32_t count = 0;
    for (uint32_t k = 0; k < segments; k++) {
        const uint32_t a = k, b = (k + 1) % n;
        if (xz[2 * a] == xz[2 * b] && xz[2 * a + 1] == xz[2 * b + 1])
            continue; /* a repeated vertex */
        const uint32_t a0 = 2 * a, a1 = 2 * a + 1, b0 = 2 * b, b1 = 2 * b + 1;
        /* (b0 - a0) x (b1 - a0) = width (-(bz - az), 0, bx - ax): the left */
        uint32_t *f = faces + 6 * (size_t)count++;
        f[0] = a0, f[1] = b0, f[2] = b1;
        f[3] = a0, f[4] = b1, f[5] = a1;
    }
    int rc = sluice_wall_build_triangles(wall, vertices, 2 * n, faces, 2 * count, reason);
    free(vertices);
    free(faces);
    return rc;
}

static double signed_area(const sluice_real_list *points)
{
    double a = 0;
    for (uint32_t k = 0; k < points->count; k++) {
        uint32_t m = (k + 1) % points->count;
        a += (double)points->values[3 * k] * (double)points->values[3 * m + 1] -
             (double)points->values[3 * m] * (double)points->values[3 * k + 1];
    }
    return 0.5 * a;
}

static int check_box(sluice_scene *scene, const sluice_node *item, const sluice_real *min,
                     const sluice_real *max, const char *what, sluice_diag *diag)
{
    for (uint32_t d = 0; d < scene->dimensions; d++)
        if (!(max[d] > min[d])) {
            error_at(diag, scene, sluice_node_get(item, "max"),
                     "%s: max must be greater than min along every axis (axis %c: %g <= %g)", what,
                     "xyz"[d], (double)max[d], (double)min[d]);
            return 1;
        }
    return 0;
}

/* The list geometry.<key>: NULL when absent or empty, after reporting an
 * error (*errors = 1) when it is not a list. */
static sluice_node *geometry_list(sluice_scene *scene, sluice_node *geometry, const char *key,
                                  const char *what, int *errors, sluice_diag *diag)
{
    *errors = 0;
    sluice_node **slot = section_slot(geometry, key, 0);
    if (!slot)
        return NULL;
    sluice_node *list = *slot;
    if (list->kind == SLUICE_NODE_SCALAR && list->plain && !*list->value)
        return NULL;
    if (list->kind != SLUICE_NODE_SEQUENCE) {
        error_at(diag, scene, list, "geometry.%s must be a list of %s", key, what);
        *errors = 1;
        return NULL;
    }
    return list;
}

/* ------------------------------------------------------------ profiles -- */

/* A key taken out of a mapping while a schema binder reads the rest (the
 * binder would report it as unknown); reattach() puts it back in place. */
typedef struct detached_key {
    size_t index;
    sluice_node *key, *value; /* NULL: the key was absent */
} detached_key;

static detached_key detach(sluice_node *mapping, const char *name)
{
    detached_key d = {0, NULL, NULL};
    if (!mapping || mapping->kind != SLUICE_NODE_MAPPING)
        return d;
    for (size_t i = 0; i < mapping->count; i++)
        if (strcmp(mapping->keys[i]->value, name) == 0) {
            d.index = i;
            d.key = mapping->keys[i];
            d.value = mapping->items[i];
            memmove(mapping->keys + i, mapping->keys + i + 1,
                    (mapping->count - i - 1) * sizeof *mapping->keys);
            memmove(mapping->items + i, mapping->items + i + 1,
                    (mapping->count - i - 1) * sizeof *mapping->items);
            mapping->count--;
            break;
        }
    return d;
}

/* 0, or -1 on OOM (the detached nodes are then freed). */
static int reattach(sluice_node *mapping, detached_key d)
{
    if (!d.key)
        return 0;
    size_t count = mapping->count + 1;
    sluice_node **keys = realloc(mapping->keys, count * sizeof *keys);
    if (keys)
        mapping->keys = keys;
    sluice_node **items = keys ? realloc(mapping->items, count * sizeof *items) : NULL;
    if (!items) {
        sluice_node_free(d.key);
        sluice_node_free(d.value);
        return -1;
    }
    mapping->items = items;
    size_t at = d.index <= mapping->count ? d.index : mapping->count;
    memmove(mapping->keys + at + 1, mapping->keys + at,
            (mapping->count - at) * sizeof *mapping->keys);
    memmove(mapping->items + at + 1, mapping->items + at,
            (mapping->count - at) * sizeof *mapping->items);
    mapping->keys[at] = d.key;
    mapping->items[at] = d.value;
    mapping->count = count;
    return 0;
}

/* The pieces of a profile, flattened: an entry of `pieces` that is itself a
 * list (a YAML alias *name of pieces written elsewhere) is spliced in place.
 * slot[k] is the tree slot of piece k, path[k] its dotted path. */
#define PIECE_NESTING 8
#define PIECE_PATH 128

typedef struct piece_refs {
    sluice_node ***slot;
    char (*path)[PIECE_PATH];
    size_t count, capacity;
} piece_refs;

static int collect_pieces(sluice_scene *scene, sluice_node *sequence, const char *path, int depth,
                          piece_refs *refs, sluice_diag *diag)
{
    sequence->used = 1;
    for (size_t i = 0; i < sequence->count; i++) {
        sluice_node *item = sequence->items[i];
        char here[PIECE_PATH];
        if (snprintf(here, sizeof here, "%s.%zu", path, i) >= (int)sizeof here) {
            error_at(diag, scene, item, "%s: pieces nest too deep", path);
            return 1;
        }
        if (item->kind == SLUICE_NODE_SEQUENCE) {
            if (depth >= PIECE_NESTING) {
                error_at(diag, scene, item, "%s: lists of pieces nest more than %d deep", here,
                         PIECE_NESTING);
                return 1;
            }
            int e = collect_pieces(scene, item, here, depth + 1, refs, diag);
            if (e)
                return e;
            continue;
        }
        if (refs->count == refs->capacity) {
            size_t cap = refs->capacity ? 2 * refs->capacity : 16;
            sluice_node ***slots = sluice_arena_alloc(scene->arena, cap * sizeof *slots);
            char(*paths)[PIECE_PATH] = sluice_arena_alloc(scene->arena, cap * sizeof *paths);
            if (!slots || !paths) {
                error_at(diag, scene, item, "out of memory");
                return 1;
            }
            if (refs->count) {
                memcpy(slots, refs->slot, refs->count * sizeof *slots);
                memcpy(paths, refs->path, refs->count * sizeof *paths);
            }
            refs->slot = slots;
            refs->path = paths;
            refs->capacity = cap;
        }
        refs->slot[refs->count] = &sequence->items[i];
        memcpy(refs->path[refs->count], here, sizeof here);
        refs->count++;
    }
    return 0;
}

/* Reads one piece into *out; returns the number of errors reported. */
static int load_piece(sluice_scene *scene, sluice_node **slot, const char *path,
                      sluice_profile_piece *out, sluice_diag *diag)
{
    sluice_node *item = *slot;
    if (item->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, item,
                 "%s must be a mapping with a 'piece' (one of: line, arc, crest, steps)", path);
        return 1;
    }
    const sluice_node *kind = sluice_node_get(item, "piece");
    static const char *const kinds[] = {"line", "arc", "crest", "steps"};
    int k = -1;
    if (kind && kind->kind == SLUICE_NODE_SCALAR)
        for (int i = 0; i < 4; i++)
            if (strcmp(kind->value, kinds[i]) == 0)
                k = i;
    if (k < 0) {
        if (!kind) {
            error_at(diag, scene, item, "%s has no 'piece' (one of: line, arc, crest, steps)",
                     path);
            return 1;
        }
        const char *close =
            kind->kind == SLUICE_NODE_SCALAR ? sluice_closest(kind->value, kinds, 4) : NULL;
        if (close)
            error_at(diag, scene, kind, "unknown piece '%s' in %s; did you mean '%s'?",
                     kind->value, path, close);
        else
            error_at(diag, scene, kind, "unknown piece in %s (one of: line, arc, crest, steps)",
                     path);
        return 1;
    }
    static const sluice_param_spec *const specs[] = {piece_line_specs, piece_arc_specs,
                                                     piece_crest_specs, piece_steps_specs};
    static const uint32_t counts[] = {SLUICE_COUNT(piece_line_specs),
                                      SLUICE_COUNT(piece_arc_specs),
                                      SLUICE_COUNT(piece_crest_specs),
                                      SLUICE_COUNT(piece_steps_specs)};
    piece_config c;
    memset(&c, 0, sizeof c);
    int e = sluice_schema_bind(specs[k], counts[k], slot, item, path, scene->dimensions, &c,
                               scene->arena, diag);
    if (e)
        return e;
    item = *slot;
    memset(out, 0, sizeof *out);
    out->kind = (sluice_piece_kind)k;
    switch (out->kind) {
    case SLUICE_PIECE_LINE: {
        static const char *const names[] = {"to",      "dx",    "dy",   "length",
                                            "heading", "slope", "to_x", "to_y"};
        for (unsigned i = 0; i < 8; i++)
            if (sluice_node_get(item, names[i]))
                out->keys |= 1u << i;
        out->to[0] = c.to[0];
        out->to[1] = c.to[1];
        out->to_x = c.to_x;
        out->to_y = c.to_y;
        out->dx = c.dx;
        out->dy = c.dy;
        out->length = c.length;
        out->heading = c.heading;
        out->slope = c.slope;
        break;
    }
    case SLUICE_PIECE_ARC:
        out->radius = c.radius;
        out->turn = c.turn;
        break;
    case SLUICE_PIECE_CREST: {
        const sluice_node *slope = sluice_node_get(item, "end_slope");
        const sluice_node *x = sluice_node_get(item, "end_x");
        if (slope && x) {
            error_at(diag, scene, x,
                     "%s (crest): give the crest's end once: 'end_slope' (the tangent point) or "
                     "'end_x'",
                     path);
            return 1;
        }
        if (!slope && !x) {
            error_at(diag, scene, item,
                     "%s (crest): a crest needs its end: 'end_slope' (the slope dy/dx of the "
                     "tangent point, 1.3333 for 1:0.75) or 'end_x' (in units)",
                     path);
            return 1;
        }
        out->coefficient = c.coefficient;
        out->exponent = c.exponent;
        out->unit = c.unit;
        out->end_slope = c.end_slope;
        out->end_x = c.end_x;
        out->end_at_x = x != NULL;
        break;
    }
    case SLUICE_PIECE_STEPS:
        out->count = (uint32_t)c.count;
        out->height = c.height;
        out->step_length = c.length;
        out->tread_first = c.first == 1;
        break;
    }
    return 0;
}

/* A fluid outline that crosses itself is refused at `at`: the fill would
 * leave out the loops that turn the other way (fewer particles than its
 * area). */
static int refuse_crossing(sluice_scene *scene, sluice_node *item, sluice_node *at,
                           const char *path, const sluice_region *region, sluice_diag *diag)
{
    uint32_t a = 0, b = 0;
    if (!sluice_polygon_crossing(region->polygon, region->vertex_count, &a, &b))
        return 0;
    const sluice_real *p = region->polygon;
    const uint32_t n = region->vertex_count;
    error_at(diag, scene, at ? at : item,
             "%s crosses itself: its edge from (%g, %g) to (%g, %g) crosses the edge from "
             "(%g, %g) to (%g, %g); a fluid region is a simple outline (one loop without "
             "crossings)",
             path, (double)p[2 * a], (double)p[2 * a + 1], (double)p[2 * ((a + 1) % n)],
             (double)p[2 * ((a + 1) % n) + 1], (double)p[2 * b], (double)p[2 * b + 1],
             (double)p[2 * ((b + 1) % n)], (double)p[2 * ((b + 1) % n) + 1]);
    return 1;
}

/* Reads and builds the profile of item (a wall or fluid region already bound
 * to its own keys, `pieces` excepted): pieces, then the vertices into *out.
 * Returns the number of errors reported. */
static int load_profile(sluice_scene *scene, const sluice_node *item, sluice_node *pieces,
                        const char *path, const sluice_real start[3], int has_heading,
                        sluice_real heading, sluice_real max_segment, int closed,
                        sluice_profile_path *out, sluice_diag *diag)
{
    char where[PIECE_PATH];
    snprintf(where, sizeof where, "%.100s.pieces", path);
    if (!pieces || pieces->kind != SLUICE_NODE_SEQUENCE || pieces->count == 0) {
        error_at(diag, scene, pieces ? pieces : item,
                 "%s needs 'pieces': a list of pieces (line, arc, crest, steps) appended in "
                 "order from 'start'",
                 path);
        return 1;
    }
    piece_refs refs = {NULL, NULL, 0, 0};
    int errors = collect_pieces(scene, pieces, where, 0, &refs, diag);
    if (errors)
        return errors;
    size_t count = refs.count;
    if (count == 0) {
        error_at(diag, scene, pieces, "%s lists no piece", where);
        return 1;
    }
    if (count > UINT32_MAX / 2) {
        error_at(diag, scene, pieces, "%s lists too many pieces", where);
        return 1;
    }
    sluice_profile_piece *list = sluice_arena_alloc(scene->arena, count * sizeof *list);
    if (!list) {
        error_at(diag, scene, pieces, "out of memory");
        return 1;
    }
    for (size_t i = 0; i < count; i++)
        errors += load_piece(scene, refs.slot[i], refs.path[i], &list[i], diag);
    if (errors)
        return errors;
    if (!(scene->particles.spacing > 0))
        return 0; /* reported with the particles section; nothing to discretise with */
    sluice_profile profile;
    memset(&profile, 0, sizeof profile);
    profile.start[0] = start[0];
    profile.start[1] = start[1];
    profile.has_heading = has_heading;
    profile.heading = heading;
    profile.pieces = list;
    profile.piece_count = (uint32_t)count;
    profile.closed = closed;
    profile.max_segment = max_segment > 0 ? max_segment : 0.5 * scene->particles.spacing;
    sluice_profile_problem problem;
    if (sluice_profile_build(&profile, out, &problem) == 0)
        return 0;
    if (problem.piece == UINT32_MAX) {
        const sluice_node *at = problem.key ? sluice_node_get(item, problem.key) : NULL;
        error_at(diag, scene, at ? at : item, "%s: %s", path, problem.message);
        return 1;
    }
    const sluice_node *piece = *refs.slot[problem.piece];
    const sluice_node *at = problem.key ? sluice_node_get(piece, problem.key) : NULL;
    char other[160] = "";
    if (problem.closing)
        snprintf(other, sizeof other, " (with the closing segment back to the start)");
    else if (problem.other != UINT32_MAX && problem.other != problem.piece)
        snprintf(other, sizeof other, " (with %s, %s)", refs.path[problem.other],
                 sluice_piece_name(list[problem.other].kind));
    error_at(diag, scene, at ? at : piece, "%s (%s): %s%s", refs.path[problem.piece],
             sluice_piece_name(list[problem.piece].kind), problem.message, other);
    return 1;
}

static int load_fluids(sluice_scene *scene, sluice_node *geometry, sluice_diag *diag)
{
    int errors;
    sluice_node *list = geometry_list(scene, geometry, "fluid", "regions", &errors, diag);
    if (!list)
        return errors;
    scene->fluids = sluice_arena_alloc(scene->arena, (list->count ? list->count : 1) *
                                                         sizeof *scene->fluids);
    if (!scene->fluids)
        return 1;
    for (size_t i = 0; i < list->count; i++) {
        sluice_node *item = list->items[i];
        int shape = item_shape(scene, item, "fluid", FLUID_SHAPES, diag);
        if (shape < 0) {
            errors++;
            continue;
        }
        char path[64];
        snprintf(path, sizeof path, "geometry.fluid.%zu", i);
        fluid_config c;
        memset(&c, 0, sizeof c);
        detached_key pieces = shape == 2 ? detach(item, "pieces") : (detached_key){0, NULL, NULL};
        int e = shape == 0   ? sluice_schema_bind(fluid_box_specs, SLUICE_COUNT(fluid_box_specs),
                                                  &list->items[i], item, path, scene->dimensions,
                                                  &c, scene->arena, diag)
                : shape == 1 ? sluice_schema_bind(fluid_polygon_specs,
                                                  SLUICE_COUNT(fluid_polygon_specs),
                                                  &list->items[i], item, path, scene->dimensions,
                                                  &c, scene->arena, diag)
                             : sluice_schema_bind(fluid_profile_specs,
                                                  SLUICE_COUNT(fluid_profile_specs),
                                                  &list->items[i], item, path, scene->dimensions,
                                                  &c, scene->arena, diag);
        item = list->items[i];
        if (reattach(item, pieces) != 0) {
            error_at(diag, scene, item, "out of memory");
            return errors + 1;
        }
        if (e) {
            errors += e;
            continue;
        }
        sluice_scene_fluid *f = &scene->fluids[scene->fluid_count];
        memset(f, 0, sizeof *f);
        f->node = item;
        memcpy(f->velocity, c.velocity, sizeof f->velocity);
        f->has_surface = sluice_node_get(item, "surface") != NULL;
        f->surface = c.surface;
        f->name = c.name ? c.name : "";
        f->has_lattice_origin = sluice_node_get(item, "lattice_origin") != NULL;
        memcpy(f->lattice_origin,
               f->has_lattice_origin ? c.lattice_origin : scene->particles.lattice_origin,
               sizeof f->lattice_origin);
        if (shape == 0) {
            if (check_box(scene, item, c.min, c.max, path, diag)) {
                errors++;
                continue;
            }
            f->region.shape = SLUICE_REGION_BOX;
            memcpy(f->region.min, c.min, sizeof c.min);
            memcpy(f->region.max, c.max, sizeof c.max);
        } else {
            if (scene->dimensions != 2) {
                error_at(diag, scene, sluice_node_get(item, "shape"),
                         "shape '%s' in %s is only available in 2D",
                         shape == 1 ? "polygon" : "profile", path);
                errors++;
                continue;
            }
            if (shape == 2) {
                /* the region inside the profile closed back to its start */
                sluice_profile_path outline = {0};
                int pe = load_profile(scene, item, sluice_node_get(item, "pieces"), path, c.start,
                                      sluice_node_get(item, "heading") != NULL, c.heading,
                                      c.max_segment, 1, &outline, diag);
                if (pe || !outline.xy) {
                    errors += pe;
                    sluice_profile_path_free(&outline);
                    continue;
                }
                sluice_real *xy = sluice_arena_alloc(scene->arena, (size_t)outline.vertex_count *
                                                                       2 * sizeof *xy);
                if (!xy) {
                    sluice_profile_path_free(&outline);
                    return errors + 1;
                }
                memcpy(xy, outline.xy, (size_t)outline.vertex_count * 2 * sizeof *xy);
                f->region.shape = SLUICE_REGION_POLYGON;
                f->region.polygon = xy;
                f->region.vertex_count = outline.vertex_count;
                sluice_profile_path_free(&outline);
                if (refuse_crossing(scene, item, sluice_node_get(item, "pieces"), path,
                                    &f->region, diag)) {
                    errors++;
                    continue;
                }
                scene->fluid_count++;
                continue;
            }
            if (c.points.count < 3) {
                error_at(diag, scene, sluice_node_get(item, "points"),
                         "%s.points needs at least 3 vertices", path);
                errors++;
                continue;
            }
            f->region.shape = SLUICE_REGION_POLYGON;
            f->region.polygon = polygon_xy(scene->arena, &c.points, 0);
            f->region.vertex_count = c.points.count;
            if (!f->region.polygon)
                return errors + 1;
            if (refuse_crossing(scene, item, sluice_node_get(item, "points"), path, &f->region,
                                diag)) {
                errors++;
                continue;
            }
        }
        scene->fluid_count++;
    }
    return errors;
}

/* ---------------------------------------------------------- mesh walls -- */

/* Where a mesh wall's messages point: the mesh file's line when the problem
 * has one, else the wall's `file` key with the mesh file named. */
typedef struct mesh_site {
    sluice_scene *scene;
    sluice_diag *diag;
    const sluice_node *file_node;
    const char *wall_path; /* geometry.walls.N */
    const char *mesh_path; /* the file, resolved */
    const sluice_mesh *mesh;
} mesh_site;

static void mesh_report(const mesh_site *site, sluice_severity severity, int line, int column,
                        const char *format, ...) SLUICE_PRINTF(5, 6);
static void mesh_report(const mesh_site *site, sluice_severity severity, int line, int column,
                        const char *format, ...)
{
    char text[900];
    va_list ap;
    va_start(ap, format);
    vsnprintf(text, sizeof text, format, ap);
    va_end(ap);
    if (line > 0) {
        sluice_diag_add(site->diag, severity, site->mesh_path, line, column, "%s: %s",
                        site->wall_path, text);
        return;
    }
    const sluice_node *at = site->file_node;
    sluice_diag_add(site->diag, severity, sluice_node_file(at, site->scene),
                    at && at->line > 0 ? at->line : 1, at && at->line > 0 ? at->column : 1,
                    "%s: mesh file '%s': %s", site->wall_path, site->mesh_path, text);
}

/* The line of triangle t in the mesh file (0 for binary STL). */
static int mesh_line(const sluice_mesh *mesh, uint32_t t)
{
    return mesh->face_line && t < mesh->face_count ? (int)mesh->face_line[t] : 0;
}

/* "(x, y, z) to (x, y, z)", the corners of an edge. */
static void edge_text(const sluice_mesh *mesh, const uint32_t edge[2], char *out, size_t size)
{
    const double *a = mesh->vertices + 3 * (size_t)edge[0],
                 *b = mesh->vertices + 3 * (size_t)edge[1];
    /* + 0.0: a negative zero prints as 0 */
    snprintf(out, size, "(%g, %g, %g) to (%g, %g, %g)", a[0] + 0.0, a[1] + 0.0, a[2] + 0.0,
             b[0] + 0.0, b[1] + 0.0, b[2] + 0.0);
}

/* The surface checks: non-manifold and misoriented edges are refused; open
 * edges are refused when the fluid is inside or outside (a closed surface),
 * else reported as a warning. Returns the number of errors. */
static int check_mesh_surface(const mesh_site *site, int closed, const char *side)
{
    const sluice_mesh *mesh = site->mesh;
    sluice_mesh_edges edges;
    if (sluice_mesh_check_edges(mesh, &edges) != 0) {
        mesh_report(site, SLUICE_SEVERITY_ERROR, 0, 0, "out of memory");
        return 1;
    }
    char where[200];
    if (edges.nonmanifold) {
        uint32_t t = edges.nonmanifold_triangle;
        edge_text(mesh, edges.nonmanifold_edge, where, sizeof where);
        mesh_report(site, SLUICE_SEVERITY_ERROR, mesh_line(mesh, t), 1,
                    "non-manifold surface: the edge %s of triangle %u is shared by %u triangles "
                    "(an edge of a surface joins two at most; %llu such edges)",
                    where, t + 1, edges.nonmanifold_uses, (unsigned long long)edges.nonmanifold);
        return 1;
    }
    if (edges.misoriented) {
        uint32_t t = edges.misoriented_triangle;
        edge_text(mesh, edges.misoriented_edge, where, sizeof where);
        mesh_report(site, SLUICE_SEVERITY_ERROR, mesh_line(mesh, t), 1,
                    "triangles %u and %u run along their shared edge %s in the same direction: "
                    "their windings disagree (%llu such edges); the file's triangles must be "
                    "wound consistently",
                    t + 1, edges.misoriented_other + 1, where,
                    (unsigned long long)edges.misoriented);
        return 1;
    }
    if (edges.open) {
        uint32_t t = edges.open_triangle;
        edge_text(mesh, edges.open_edge, where, sizeof where);
        if (closed) {
            mesh_report(site, SLUICE_SEVERITY_ERROR, mesh_line(mesh, t), 1,
                        "open surface: the edge %s of triangle %u belongs to no other triangle "
                        "(%llu open edges); 'fluid: %s' needs a closed surface (an open one "
                        "takes 'fluid: front' or 'fluid: back')",
                        where, t + 1, (unsigned long long)edges.open, side);
            return 1;
        }
        mesh_report(site, SLUICE_SEVERITY_WARNING, mesh_line(mesh, t), 1,
                    "open surface (%llu edges belong to one triangle only, the first %s of "
                    "triangle %u): the fluid is on the %s side of every triangle, and a point "
                    "beyond the rim is not behind the wall",
                    (unsigned long long)edges.open, where, t + 1, side);
    }
    return 0;
}

/* The mesh's triangles as the wall, after the transform and with the
 * winding turned so that every normal points into the fluid. */
static int build_mesh_geometry(const mesh_site *site, sluice_mesh *mesh, const wall_config *c,
                               const sluice_node *item, sluice_wall_geometry *wall)
{
    const double axis[3] = {c->rotate_axis[0], c->rotate_axis[1], c->rotate_axis[2]};
    const double shift[3] = {c->translate[0], c->translate[1], c->translate[2]};
    if (sluice_mesh_transform(mesh, c->scale, axis, c->rotate_angle, shift) != 0) {
        error_at(site->diag, site->scene, sluice_node_get(item, "rotate_axis"),
                 "%s.rotate_axis must not be zero when rotate_angle is not", site->wall_path);
        return 1;
    }
    if (c->fluid == MESH_FLUID_INSIDE || c->fluid == MESH_FLUID_OUTSIDE) {
        /* closed: the signed volume tells whether the normals point out */
        double volume = sluice_mesh_volume(mesh);
        if (!(fabs(volume) > 0)) {
            mesh_report(site, SLUICE_SEVERITY_ERROR, 0, 0, "the closed surface encloses no volume");
            return 1;
        }
        if ((volume > 0) != (c->fluid == MESH_FLUID_OUTSIDE))
            sluice_mesh_reverse(mesh);
    } else if (c->fluid == MESH_FLUID_BACK) {
        sluice_mesh_reverse(mesh);
    }
    sluice_real *vertices = malloc(((size_t)mesh->vertex_count * 3 + 1) * sizeof *vertices);
    if (!vertices) {
        mesh_report(site, SLUICE_SEVERITY_ERROR, 0, 0, "out of memory");
        return 1;
    }
    for (size_t k = 0; k < 3 * (size_t)mesh->vertex_count; k++)
        vertices[k] = (sluice_real)mesh->vertices[k];
    const char *reason = NULL;
    int rc = sluice_wall_build_triangles(wall, vertices, mesh->vertex_count, mesh->faces,
                                         mesh->face_count, &reason);
    free(vertices);
    if (rc != 0) {
        mesh_report(site, SLUICE_SEVERITY_ERROR, 0, 0, "%s",
                    reason ? reason : "out of memory");
        sluice_wall_geometry_free(wall);
        return 1;
    }
    return 0;
}

/* A wall read from a mesh file: geometry.walls[i] with shape mesh. Returns
 * the number of errors; on success scene->wall_count grows by one. */
static int load_mesh_wall(sluice_scene *scene, sluice_node *list, size_t i, const char *path,
                          sluice_diag *diag)
{
    if (scene->dimensions != 3) {
        error_at(diag, scene, sluice_node_get(list->items[i], "shape"),
                 "shape 'mesh' in %s is only available in 3D", path);
        return 1;
    }
    wall_config c;
    memset(&c, 0, sizeof c);
    int e = sluice_schema_bind(wall_mesh_specs, SLUICE_COUNT(wall_mesh_specs), &list->items[i],
                               list->items[i], path, scene->dimensions, &c, scene->arena, diag);
    if (e)
        return e;
    const sluice_node *item = list->items[i];
    char *mesh_path = NULL;
    if (c.file[0] == '/')
        mesh_path = strdup(c.file);
    else if (asprintf(&mesh_path, "%s/%s", scene->directory, c.file) < 0)
        mesh_path = NULL;
    if (!mesh_path) {
        error_at(diag, scene, item, "out of memory");
        return 1;
    }
    if (c.file[0] != '/') {
        /* the resolved scene names the file by its absolute path, so that
         * it runs from the output directory too */
        const sluice_node *given = sluice_node_get(item, "file");
        sluice_node *absolute =
            sluice_node_new_scalar(mesh_path, 0, given ? given->file : NULL,
                                   given ? given->line : 0, given ? given->column : 0);
        if (!absolute || sluice_node_set(list->items[i], "file", absolute) != 0) {
            error_at(diag, scene, item, "out of memory");
            free(mesh_path);
            return 1;
        }
        sluice_node_mark_used(absolute, 1);
    }
    sluice_mesh mesh;
    sluice_mesh_problem problem;
    mesh_site site = {scene, diag, sluice_node_get(item, "file"), path, mesh_path, &mesh};
    int errors = 0;
    if (sluice_mesh_read(mesh_path, &mesh, &problem) != 0) {
        mesh_report(&site, SLUICE_SEVERITY_ERROR, problem.line, problem.column, "%s",
                    problem.message);
        errors = 1;
    }
    const char *side = MESH_FLUID_SIDES; /* the name of c.fluid */
    char sides[64];
    const char *names[4];
    if (split_choices(side, sides, sizeof sides, names, 4) == 4)
        side = names[c.fluid];
    int closed = c.fluid == MESH_FLUID_INSIDE || c.fluid == MESH_FLUID_OUTSIDE;
    sluice_scene_wall *w = &scene->walls[scene->wall_count];
    memset(w, 0, sizeof *w);
    if (!errors)
        errors = check_mesh_surface(&site, closed, side);
    if (!errors)
        errors = build_mesh_geometry(&site, &mesh, &c, item, &w->geometry);
    sluice_mesh_free(&mesh);
    free(mesh_path);
    if (errors)
        return errors;
    w->node = item;
    memcpy(w->lattice_origin,
           sluice_node_get(item, "lattice_origin") ? c.lattice_origin
                                                   : scene->particles.lattice_origin,
           sizeof w->lattice_origin);
    w->scheme = c.scheme;
    w->name = c.name ? c.name : "";
    scene->wall_count++;
    return 0;
}

static int load_walls(sluice_scene *scene, sluice_node *geometry, sluice_diag *diag)
{
    int errors;
    sluice_node *list = geometry_list(scene, geometry, "walls", "walls", &errors, diag);
    if (!list)
        return errors;
    scene->walls =
        sluice_arena_alloc(scene->arena, (list->count ? list->count : 1) * sizeof *scene->walls);
    if (!scene->walls)
        return 1;
    for (size_t i = 0; i < list->count; i++) {
        sluice_node *item = list->items[i];
        int shape = item_shape(scene, item, "walls", WALL_SHAPES, diag);
        if (shape < 0) {
            errors++;
            continue;
        }
        char path[64];
        snprintf(path, sizeof path, "geometry.walls.%zu", i);
        if (shape == 6) {
            errors += load_mesh_wall(scene, list, i, path, diag);
            continue;
        }
        wall_config c;
        memset(&c, 0, sizeof c);
        int boxlike = shape <= 1 || shape == 5, profile = shape == 4,
            three = scene->dimensions == 3;
        detached_key pieces = profile ? detach(item, "pieces") : (detached_key){0, NULL, NULL};
        int e = boxlike   ? sluice_schema_bind(wall_box_specs, SLUICE_COUNT(wall_box_specs),
                                               &list->items[i], item, path, scene->dimensions, &c,
                                               scene->arena, diag)
                : profile && three
                    ? sluice_schema_bind(wall_profile_specs_3d, SLUICE_COUNT(wall_profile_specs_3d),
                                         &list->items[i], item, path, scene->dimensions, &c,
                                         scene->arena, diag)
                : profile ? sluice_schema_bind(wall_profile_specs, SLUICE_COUNT(wall_profile_specs),
                                               &list->items[i], item, path, scene->dimensions, &c,
                                               scene->arena, diag)
                : three   ? sluice_schema_bind(wall_line_specs_3d, SLUICE_COUNT(wall_line_specs_3d),
                                               &list->items[i], item, path, scene->dimensions, &c,
                                               scene->arena, diag)
                          : sluice_schema_bind(wall_line_specs, SLUICE_COUNT(wall_line_specs),
                                               &list->items[i], item, path, scene->dimensions, &c,
                                               scene->arena, diag);
        item = list->items[i];
        if (reattach(item, pieces) != 0) {
            error_at(diag, scene, item, "out of memory");
            return errors + 1;
        }
        if (e) {
            errors += e;
            continue;
        }
        sluice_scene_wall *w = &scene->walls[scene->wall_count];
        memset(w, 0, sizeof *w);
        w->node = item;
        memcpy(w->lattice_origin,
               sluice_node_get(item, "lattice_origin") ? c.lattice_origin
                                                       : scene->particles.lattice_origin,
               sizeof w->lattice_origin);
        w->scheme = c.scheme;
        w->name = c.name ? c.name : "";
        const char *reason = NULL;
        int rc;
        if (boxlike) {
            if (check_box(scene, item, c.min, c.max, path, diag)) {
                errors++;
                continue;
            }
            rc = shape == 0   ? sluice_wall_build_tank(&w->geometry, scene->dimensions, c.min,
                                                       c.max, &reason)
                 : shape == 5 ? sluice_wall_build_channel(&w->geometry, scene->dimensions, c.min,
                                                          c.max, &reason)
                              : sluice_wall_build_box(&w->geometry, scene->dimensions, c.min,
                                                      c.max, &reason);
        } else {
            if (three && !(c.across[1] > c.across[0])) {
                error_at(diag, scene, sluice_node_get(item, "across"),
                         "%s.across must run from a smaller to a larger y (got [%g, %g])", path,
                         (double)c.across[0], (double)c.across[1]);
                errors++;
                continue;
            }
            if (profile) {
                sluice_profile_path outline = {0};
                int pe = load_profile(scene, item, sluice_node_get(item, "pieces"), path, c.start,
                                      sluice_node_get(item, "heading") != NULL, c.heading,
                                      c.max_segment, c.closed, &outline, diag);
                if (pe || !outline.xy) {
                    errors += pe;
                    sluice_profile_path_free(&outline);
                    continue;
                }
                rc = three ? build_extruded(&w->geometry, outline.xy, outline.vertex_count,
                                            c.closed, c.across, &reason)
                           : sluice_wall_build_polyline(&w->geometry, outline.xy,
                                                        outline.vertex_count, c.closed, &reason);
                sluice_profile_path_free(&outline);
                if (rc != 0) {
                    error_at(diag, scene, item, "%s: %s", path, reason ? reason : "out of memory");
                    sluice_wall_geometry_free(&w->geometry);
                    errors++;
                    continue;
                }
                scene->wall_count++;
                continue;
            }
            int closed = shape == 3;
            if (c.points.count < (closed ? 3u : 2u)) {
                error_at(diag, scene, sluice_node_get(item, "points"),
                         "%s.points needs at least %d vertices", path, closed ? 3 : 2);
                errors++;
                continue;
            }
            /* a closed polygon is a solid: the fluid is outside, i.e. on the left of a
             * clockwise boundary */
            int reverse = closed && signed_area(&c.points) > 0;
            sluice_real *xy = polygon_xy(scene->arena, &c.points, reverse);
            if (!xy)
                return errors + 1;
            rc = three ? build_extruded(&w->geometry, xy, c.points.count, closed, c.across, &reason)
                       : sluice_wall_build_polyline(&w->geometry, xy, c.points.count, closed,
                                                    &reason);
        }
        if (rc != 0) {
            error_at(diag, scene, item, "%s: %s", path, reason ? reason : "out of memory");
            sluice_wall_geometry_free(&w->geometry);
            errors++;
            continue;
        }
        scene->wall_count++;
    }
    return errors;
}

/* A name in `plugins`: letters, digits, '_' and '-' (it is a segment of
 * dotted paths, a checkpoint group and part of messages). */
static int valid_instance_name(const char *name)
{
    if (!name || !*name)
        return 0;
    for (const char *c = name; *c; c++)
        if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
              *c == '_' || *c == '-'))
            return 0;
    return 1;
}

/* One entry of `plugins`: its key names the instance; an optional `plugin`
 * key in its parameters names the component it loads (a plugin loaded
 * several times under instance names), else the key does. */
static int plugin_instance(sluice_scene *scene, sluice_scene_plugin *sp, sluice_diag *diag)
{
    if (!valid_instance_name(sp->name)) {
        error_at(diag, scene, sp->key,
                 "'%s' is not a valid name in 'plugins': use letters, digits, '_' and '-'",
                 sp->name ? sp->name : "");
        return 1;
    }
    const sluice_node *section = *sp->section;
    if (!section || section->kind != SLUICE_NODE_MAPPING)
        return 0;
    const sluice_node *component = sluice_node_get(section, "plugin");
    if (!component)
        return 0;
    if (component->kind != SLUICE_NODE_SCALAR || !valid_instance_name(component->value)) {
        error_at(diag, scene, component,
                 "plugins.%s.plugin must name the plugin this instance loads (e.g. "
                 "wall_pressure)",
                 sp->name);
        return 1;
    }
    sp->component = component->value;
    sp->component_node = component;
    return 0;
}

static int load_plugins(sluice_scene *scene, sluice_diag *diag)
{
    sluice_node **slot = section_slot(scene->root, "plugins", 0);
    if (!slot || ((*slot)->kind == SLUICE_NODE_SCALAR && !*(*slot)->value)) {
        error_at(diag, scene, slot ? *slot : scene->root,
                 "the scene loads no plugins: 'plugins' must list at least a kernel, the "
                 "physics terms and an integrator");
        return 1;
    }
    sluice_node *map = *slot;
    if (map->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, map,
                 "'plugins' must be a mapping from plugin names to their parameters");
        return 1;
    }
    map->used = 1;
    scene->plugins = sluice_arena_alloc(scene->arena, (map->count ? map->count : 1) *
                                                          sizeof *scene->plugins);
    if (!scene->plugins)
        return 1;
    int errors = 0;
    for (size_t i = 0; i < map->count; i++) {
        sluice_scene_plugin *sp = &scene->plugins[i];
        sp->name = map->keys[i]->value;
        sp->key = map->keys[i];
        sp->section = &map->items[i];
        sp->component = sp->name;
        sp->component_node = sp->key;
        errors += plugin_instance(scene, sp, diag);
    }
    scene->plugin_count = map->count;
    if (errors)
        return errors;
    if (map->count == 0) {
        error_at(diag, scene, map, "the scene loads no plugins");
        return 1;
    }
    return 0;
}

static int load_plugin_path(sluice_scene *scene, sluice_diag *diag)
{
    sluice_node *node = sluice_node_get(scene->root, "plugin_path");
    if (!node)
        return 0;
    node->used = 1;
    if (node->kind != SLUICE_NODE_SCALAR) {
        error_at(diag, scene, node,
                 "plugin_path must be a string of directories separated by ':'");
        return 1;
    }
    char *copy = sluice_arena_strdup(scene->arena, node->value);
    if (!copy)
        return 1;
    size_t count = 1;
    for (const char *c = copy; *c; c++)
        count += *c == ':';
    scene->plugin_path = sluice_arena_alloc(scene->arena, count * sizeof(char *));
    if (!scene->plugin_path)
        return 1;
    char *save = NULL;
    for (char *tok = strtok_r(copy, ":", &save); tok; tok = strtok_r(NULL, ":", &save)) {
        if (!*tok)
            continue;
        size_t len = strlen(scene->directory) + strlen(tok) + 2;
        char *full = sluice_arena_alloc(scene->arena, len);
        if (!full)
            return 1;
        if (tok[0] == '/')
            snprintf(full, len, "%s", tok);
        else
            snprintf(full, len, "%s/%s", scene->directory, tok);
        struct stat st;
        const int missing = stat(full, &st) != 0;
        if (missing || !S_ISDIR(st.st_mode)) {
            error_at(diag, scene, node, "plugin_path: '%s' is not a directory (%s)", full,
                     missing ? strerror(errno) : "a file");
            return 1;
        }
        scene->plugin_path[scene->plugin_path_count++] = full;
    }
    return 0;
}

/* ------------------------------------------------------------ variants -- */

static int empty_value(const sluice_node *node)
{
    return node->kind == SLUICE_NODE_SCALAR && node->plain && !*node->value;
}

/* Checks the form of every variant (the paths of the one applied are checked
 * as it is applied) and records their names and descriptions. */
static int check_variants(sluice_scene *scene, const sluice_node *variants, sluice_diag *diag)
{
    if (empty_value(variants))
        return 0;
    if (variants->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, variants,
                 "'variants' must be a mapping from variant names to their changes "
                 "(description, remove, swap, set)");
        return 1;
    }
    scene->variants = sluice_arena_alloc(scene->arena, (variants->count ? variants->count : 1) *
                                                           sizeof *scene->variants);
    if (!scene->variants) {
        error_at(diag, scene, variants, "out of memory");
        return 1;
    }
    const char *const *keys = variant_keys;
    int errors = 0;
    for (size_t i = 0; i < variants->count; i++) {
        const char *name = variants->keys[i]->value;
        const sluice_node *variant = variants->items[i];
        sluice_scene_variant *record = &scene->variants[scene->variant_count++];
        record->name = sluice_arena_strdup(scene->arena, name);
        record->description = "";
        if (!record->name) {
            error_at(diag, scene, variant, "out of memory");
            return errors + 1;
        }
        if (!*name) {
            error_at(diag, scene, variants->keys[i], "a variant needs a name");
            errors++;
            continue;
        }
        if (empty_value(variant))
            continue;
        if (variant->kind != SLUICE_NODE_MAPPING) {
            error_at(diag, scene, variant,
                     "variants.%s must be a mapping with the optional keys description, remove, "
                     "swap and set",
                     name);
            errors++;
            continue;
        }
        for (size_t k = 0; k < variant->count; k++) {
            const char *key = variant->keys[k]->value;
            const sluice_node *value = variant->items[k];
            if (strcmp(key, "description") == 0) {
                if (value->kind != SLUICE_NODE_SCALAR) {
                    error_at(diag, scene, value, "variants.%s.description must be a string",
                             name);
                    errors++;
                } else if (!(record->description =
                                 sluice_arena_strdup(scene->arena, value->value))) {
                    error_at(diag, scene, value, "out of memory");
                    return errors + 1;
                }
            } else if (strcmp(key, "remove") == 0) {
                if (empty_value(value))
                    continue;
                if (value->kind != SLUICE_NODE_SEQUENCE) {
                    error_at(diag, scene, value,
                             "variants.%s.remove must be a list of dotted paths, e.g. "
                             "[plugins.two_phase, geometry.fluid.air]",
                             name);
                    errors++;
                    continue;
                }
                for (size_t j = 0; j < value->count; j++) {
                    const sluice_node *path = value->items[j];
                    if (path->kind != SLUICE_NODE_SCALAR || !*path->value) {
                        error_at(diag, scene, path,
                                 "each entry of variants.%s.remove must be a dotted path such "
                                 "as plugins.two_phase",
                                 name);
                        errors++;
                    }
                }
            } else if (strcmp(key, "swap") == 0) {
                if (empty_value(value))
                    continue;
                int form = value->kind == SLUICE_NODE_MAPPING;
                for (size_t j = 0; form && j < value->count; j++)
                    form = value->items[j]->kind == SLUICE_NODE_SCALAR;
                if (!form) {
                    error_at(diag, scene, value,
                             "variants.%s.swap must be a mapping from loaded plugins to the "
                             "plugins that replace them, e.g. {dbc: mdbc}",
                             name);
                    errors++;
                }
            } else if (strcmp(key, "set") == 0) {
                if (!empty_value(value) && value->kind != SLUICE_NODE_MAPPING) {
                    error_at(diag, scene, value,
                             "variants.%s.set must be a mapping from dotted paths to values, "
                             "e.g. {plugins.tait.speed_of_sound: 28}",
                             name);
                    errors++;
                }
            } else {
                const char *close = sluice_closest(key, keys, SLUICE_COUNT(variant_keys));
                if (close)
                    error_at(diag, scene, variant->keys[k],
                             "unknown key '%s' in variants.%s; did you mean '%s'?", key, name,
                             close);
                else
                    error_at(diag, scene, variant->keys[k],
                             "unknown key '%s' in variants.%s (valid keys: description, remove, "
                             "swap, set)",
                             key, name);
                errors++;
            }
        }
    }
    return errors;
}

/* --------------------------------------------------------------- swaps -- */

/* Replaces the entry `old` of the scene's `plugins` (a plugin or an
 * instance name) by `replacement: {}`, the other plugin with its own
 * defaults, in the same place (when the scene loads `replacement` already,
 * `old` is only taken out), and points every wall whose `scheme` is `old`
 * to it (docs/scene-format.md, Variants). New nodes sit at `at`. */
static int swap_plugin(sluice_scene *scene, const char *old, const char *replacement,
                       const sluice_node *at, const char *context, sluice_diag *diag)
{
    sluice_node *plugins = sluice_node_get(scene->root, "plugins");
    if (!plugins || plugins->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, at, "%s: cannot swap '%s': the scene has no 'plugins' mapping",
                 context, old);
        return 1;
    }
    if (!valid_instance_name(replacement)) {
        error_at(diag, scene, at,
                 "%s: '%s' is not a plugin name (letters, digits, '_' and '-'); write "
                 "OLD=NEW, e.g. dbc=mdbc",
                 context, replacement);
        return 1;
    }
    size_t index = 0;
    while (index < plugins->count && strcmp(plugins->keys[index]->value, old) != 0)
        index++;
    if (index == plugins->count) {
        const char **names = sluice_arena_alloc(scene->arena, (plugins->count + 1) * sizeof *names);
        for (size_t i = 0; names && i < plugins->count; i++)
            names[i] = plugins->keys[i]->value;
        const char *close = names ? sluice_closest(old, names, plugins->count) : NULL;
        if (close)
            error_at(diag, scene, at,
                     "%s: cannot swap '%s': the scene loads no plugin of that name; did you "
                     "mean '%s'?",
                     context, old, close);
        else
            error_at(diag, scene, at, "%s: cannot swap '%s': the scene loads no plugin of that name",
                     context, old);
        return 1;
    }
    if (strcmp(old, replacement) == 0)
        return 0;
    if (sluice_node_get(plugins, replacement)) {
        /* NEW is loaded already: OLD goes, its walls join NEW (as configured) */
        detached_key d = detach(plugins, old);
        sluice_node_free(d.key);
        sluice_node_free(d.value);
    } else {
        sluice_node *key = sluice_node_new_scalar(replacement, 1, at->file, at->line, at->column);
        sluice_node *value = sluice_node_new_mapping(at->file, at->line, at->column);
        if (!key || !value) {
            sluice_node_free(key);
            sluice_node_free(value);
            error_at(diag, scene, at, "out of memory");
            return 1;
        }
        sluice_node_free(plugins->keys[index]);
        sluice_node_free(plugins->items[index]);
        plugins->keys[index] = key;
        plugins->items[index] = value;
    }
    /* the walls it handled follow it */
    sluice_node *geometry = sluice_node_get(scene->root, "geometry");
    sluice_node *walls = geometry ? sluice_node_get(geometry, "walls") : NULL;
    for (size_t i = 0; walls && walls->kind == SLUICE_NODE_SEQUENCE && i < walls->count; i++) {
        sluice_node *wall = walls->items[i];
        sluice_node *scheme = sluice_node_get(wall, "scheme");
        if (!scheme || scheme->kind != SLUICE_NODE_SCALAR || strcmp(scheme->value, old) != 0)
            continue;
        sluice_node *name = sluice_node_new_scalar(replacement, 1, at->file, at->line, at->column);
        if (!name || sluice_node_set(wall, "scheme", name) != 0) {
            error_at(diag, scene, at, "out of memory");
            return 1;
        }
    }
    return 0;
}

/* The swaps of a variant (a mapping OLD: NEW), in order. */
static int apply_swaps(sluice_scene *scene, const sluice_node *swaps, const char *context,
                       sluice_diag *diag)
{
    int errors = 0;
    for (size_t i = 0; swaps && swaps->kind == SLUICE_NODE_MAPPING && i < swaps->count; i++)
        errors += swap_plugin(scene, swaps->keys[i]->value, swaps->items[i]->value,
                              swaps->items[i], context, diag);
    return errors;
}

/* Takes `variants` out of the tree, checks it and applies the variant `name`
 * (NULL: none): its removals, then its settings in order. The applied
 * variant is recorded as `variant: NAME` where `variants` was. */
static int apply_variant(sluice_scene *scene, const char *name, sluice_diag *diag)
{
    sluice_node *root = scene->root;
    const sluice_node *record = sluice_node_get_key(root, "variant");
    detached_key d = detach(root, "variants");
    int errors = 0;
    if (d.key && record) {
        error_at(diag, scene, record,
                 "'variant' records the variant a resolved scene was made from and cannot "
                 "stand beside 'variants': choose a variant with --variant NAME");
        errors++;
    }
    if (d.key)
        errors += check_variants(scene, d.value, diag);
    if (errors || !name)
        goto done;
    if (scene->variant_count == 0) {
        error_at(diag, scene, d.key,
                 "--variant '%s': the scene defines no variants (a top-level 'variants' "
                 "mapping)",
                 name);
        errors++;
        goto done;
    }
    size_t chosen = 0;
    while (chosen < d.value->count && strcmp(d.value->keys[chosen]->value, name) != 0)
        chosen++;
    if (chosen == d.value->count) {
        char defined[512] = "";
        size_t used = 0;
        for (size_t i = 0; i < scene->variant_count && used < sizeof defined; i++)
            used += (size_t)snprintf(defined + used, sizeof defined - used, "%s%s",
                                     i ? ", " : "", scene->variants[i].name);
        const char **names =
            sluice_arena_alloc(scene->arena, scene->variant_count * sizeof *names);
        for (size_t i = 0; names && i < scene->variant_count; i++)
            names[i] = scene->variants[i].name;
        const char *close = names ? sluice_closest(name, names, scene->variant_count) : NULL;
        if (close)
            error_at(diag, scene, d.key,
                     "unknown variant '%s'; did you mean '%s'? (the scene defines: %s)", name,
                     close, defined);
        else
            error_at(diag, scene, d.key, "unknown variant '%s' (the scene defines: %s)", name,
                     defined);
        errors++;
        goto done;
    }
    const sluice_node *variant = d.value->items[chosen];
    if (variant->kind == SLUICE_NODE_MAPPING) {
        char context[256];
        snprintf(context, sizeof context, "variant '%.200s'", name);
        errors += sluice_yaml_remove(root, sluice_node_get(variant, "remove"), context, diag);
        if (!errors)
            errors += apply_swaps(scene, sluice_node_get(variant, "swap"), context, diag);
        /* then the settings, in order, on the scene without the removed keys; a setting
         * that fails changes nothing, so the later ones are still checked */
        const sluice_node *set = errors ? NULL : sluice_node_get(variant, "set");
        for (size_t i = 0; set && set->kind == SLUICE_NODE_MAPPING && i < set->count; i++)
            if (sluice_yaml_set(root, set->keys[i]->value, sluice_node_clone(set->items[i]),
                                set->keys[i], context, diag) != 0)
                errors++;
    }
    if (errors)
        goto done;
    const sluice_node *at = d.value->keys[chosen];
    sluice_node *key = sluice_node_new_scalar("variant", 1, d.key->file, d.key->line,
                                              d.key->column);
    sluice_node *value = sluice_node_new_scalar(name, 1, at->file, at->line, at->column);
    scene->variant = sluice_arena_strdup(scene->arena, name);
    if (!key || !value || !scene->variant) {
        sluice_node_free(key);
        sluice_node_free(value);
        error_at(diag, scene, d.key, "out of memory");
        errors++;
    } else if (reattach(root, (detached_key){d.index, key, value}) != 0) { /* frees both */
        error_at(diag, scene, d.key, "out of memory");
        errors++;
    }
done:
    sluice_node_free(d.key);
    sluice_node_free(d.value);
    return errors;
}

/* ---------------------------------------------------------------- load -- */

int sluice_scene_load(sluice_scene *scene, const char *path, const char *const *overrides,
                      size_t override_count, sluice_diag *diag)
{
    return sluice_scene_load_variant(scene, path, NULL, overrides, override_count, diag);
}

/* Top-level keys the scene format knows (with a suggestion for a near
 * miss), and the title, description and recorded variant as strings. */
static int check_top_level(sluice_scene *scene, sluice_diag *diag)
{
    int errors = 0;
    /* unknown top-level sections */
    for (size_t i = 0; i < scene->root->count; i++) {
        const char *key = scene->root->keys[i]->value;
        int known = 0;
        for (size_t k = 0; k < SLUICE_COUNT(top_level_keys); k++)
            known |= strcmp(key, top_level_keys[k]) == 0;
        if (known)
            continue;
        const char *close = sluice_closest(key, top_level_keys, SLUICE_COUNT(top_level_keys));
        if (close)
            error_at(diag, scene, scene->root->keys[i],
                     "unknown key '%s' at the top level; did you mean '%s'?", key, close);
        else
            error_at(diag, scene, scene->root->keys[i],
                     "unknown key '%s' at the top level (valid keys: title, description, "
                     "dimensions, particles, time, domain, geometry, initial, neighbour_search, "
                     "watchdog, checkpoint, ranks, plugins, plugin_path, variants, variant)",
                     key);
        errors++;
    }

    sluice_node *title = sluice_node_get(scene->root, "title");
    if (title) {
        if (title->kind != SLUICE_NODE_SCALAR) {
            error_at(diag, scene, title, "title must be a string");
            errors++;
        } else {
            scene->title = title->value;
        }
    }
    sluice_node *description = sluice_node_get(scene->root, "description");
    if (description && description->kind != SLUICE_NODE_SCALAR) {
        error_at(diag, scene, description, "description must be a string");
        errors++;
    }
    sluice_node *record = sluice_node_get(scene->root, "variant");
    if (record && record->kind != SLUICE_NODE_SCALAR) {
        error_at(diag, scene, record,
                 "variant must be a string (it records the variant a resolved scene was made "
                 "from)");
        errors++;
    }
    return errors;
}

/* The sections bound through their schemas: particles, time, domain,
 * initial, neighbour_search, watchdog, checkpoint, ranks. */
static int bind_sections(sluice_scene *scene, sluice_diag *diag)
{
    int errors = 0;
    particles_config pc;
    memset(&pc, 0, sizeof pc);
    errors += bind_section(scene, "particles", particles_specs, SLUICE_COUNT(particles_specs), &pc,
                           diag);
    scene->particles.spacing = pc.spacing;
    scene->particles.smoothing_length_ratio = pc.smoothing_length_ratio;
    scene->particles.rest_density = pc.rest_density;
    memcpy(scene->particles.lattice_origin, pc.lattice_origin, sizeof pc.lattice_origin);

    time_config tc;
    memset(&tc, 0, sizeof tc);
    errors += bind_section(scene, "time", time_specs, SLUICE_COUNT(time_specs), &tc, diag);
    scene->time.end = tc.end;
    scene->time.max_step = tc.max_step;

    domain_config dc;
    memset(&dc, 0, sizeof dc);
    int domain_errors =
        bind_section(scene, "domain", domain_specs, SLUICE_COUNT(domain_specs), &dc, diag);
    errors += domain_errors;
    if (!domain_errors) {
        memcpy(scene->domain.min, dc.min, sizeof dc.min);
        memcpy(scene->domain.max, dc.max, sizeof dc.max);
        sluice_node *domain = sluice_node_get(scene->root, "domain");
        if (parse_periodic(dc.periodic, scene->dimensions, scene->domain.periodic) != 0) {
            error_at(diag, scene, sluice_node_get(domain, "periodic"),
                     "domain.periodic must be 'none' or axes among %s, each once (got '%s')",
                     scene->dimensions == 2 ? "x, y" : "x, y, z", dc.periodic);
            errors++;
        }
        errors += check_box(scene, domain, dc.min, dc.max, "domain", diag);
    }

    initial_config ic;
    memset(&ic, 0, sizeof ic);
    errors += bind_section(scene, "initial", initial_specs, SLUICE_COUNT(initial_specs), &ic, diag);
    scene->initial_density = ic.density == 0 ? SLUICE_INITIAL_HYDROSTATIC : SLUICE_INITIAL_REST;

    neighbour_config nc;
    memset(&nc, 0, sizeof nc);
    errors += bind_section(scene, "neighbour_search", neighbour_specs,
                           SLUICE_COUNT(neighbour_specs), &nc, diag);
    scene->neighbour_search.skin = nc.skin;
    scene->neighbour_search.batch_pairs = nc.batch_pairs;

    watchdog_config wc;
    memset(&wc, 0, sizeof wc);
    errors +=
        bind_section(scene, "watchdog", watchdog_specs, SLUICE_COUNT(watchdog_specs), &wc, diag);
    scene->watchdog.density_band = wc.density_band;
    scene->watchdog.min_time_step = wc.min_time_step;
    scene->watchdog.every = wc.every;
    scene->watchdog.wall_penetration = wc.wall_penetration;

    checkpoint_config kc;
    memset(&kc, 0, sizeof kc);
    errors += bind_section(scene, "checkpoint", checkpoint_specs, SLUICE_COUNT(checkpoint_specs),
                           &kc, diag);
    scene->checkpoint.interval = kc.interval;
    scene->checkpoint.keep = kc.keep;

    ranks_config rc;
    memset(&rc, 0, sizeof rc);
    errors += bind_section(scene, "ranks", ranks_specs, SLUICE_COUNT(ranks_specs), &rc, diag);
    scene->ranks.split = split_axes[rc.split];
    if (scene->dimensions == 2 && (scene->ranks.split & 4)) {
        sluice_node **ranks_slot = section_slot(scene->root, "ranks", 0);
        sluice_node **split_slot =
            ranks_slot && (*ranks_slot)->kind == SLUICE_NODE_MAPPING
                ? section_slot(*ranks_slot, "split", 0)
                : NULL;
        error_at(diag, scene, split_slot ? *split_slot : scene->root,
                 "ranks.split names the axis z in a 2D scene (use x, y or xy)");
        errors++;
    }
    scene->ranks.balance = rc.balance;
    scene->ranks.every = rc.every;
    scene->ranks.tolerance = rc.tolerance;
    return errors;
}

/* The geometry section: its fluid regions and walls. */
static int load_geometry(sluice_scene *scene, sluice_diag *diag)
{
    int errors = 0;
    sluice_node **geometry_slot = section_slot(scene->root, "geometry", 0);
    if (geometry_slot) {
        sluice_node *geometry = *geometry_slot;
        geometry->used = 1;
        if (geometry->kind != SLUICE_NODE_MAPPING) {
            error_at(diag, scene, geometry, "geometry must be a mapping with 'fluid' and 'walls'");
            errors++;
        } else {
            for (size_t i = 0; i < geometry->count; i++) {
                const char *key = geometry->keys[i]->value;
                if (strcmp(key, "fluid") != 0 && strcmp(key, "walls") != 0) {
                    static const char *const keys[] = {"fluid", "walls"};
                    const char *close = sluice_closest(key, keys, 2);
                    if (close)
                        error_at(diag, scene, geometry->keys[i],
                                 "unknown key '%s' in geometry; did you mean '%s'?", key, close);
                    else
                        error_at(diag, scene, geometry->keys[i],
                                 "unknown key '%s' in geometry (valid keys: fluid, walls)", key);
                    errors++;
                }
            }
            errors += load_fluids(scene, geometry, diag);
            errors += load_walls(scene, geometry, diag);
        }
    }
    return errors;
}

/* The command line's edits: --remove (all found before any is removed, as
 * a variant's), --swap in order, then --set in order. */
static int apply_edits(sluice_scene *scene, const sluice_scene_edits *edits, sluice_diag *diag)
{
    int errors = 0;
    if (edits->removal_count) {
        sluice_node *paths = sluice_node_new_sequence("--remove", 1, 1);
        for (size_t i = 0; paths && i < edits->removal_count; i++) {
            char origin[32];
            snprintf(origin, sizeof origin, "--remove #%zu", i + 1);
            sluice_node *item = sluice_node_new_scalar(edits->removals[i], 1, origin, 1, 1);
            if (!item || sluice_node_append(paths, item) != 0) { /* append frees item */
                sluice_node_free(paths);
                paths = NULL;
            }
        }
        if (!paths) {
            sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, scene->path, 0, 0, "out of memory");
            return 1;
        }
        errors += sluice_yaml_remove(scene->root, paths, "--remove", diag);
        sluice_node_free(paths);
    }
    for (size_t i = 0; !errors && i < edits->swap_count; i++) {
        char origin[32];
        snprintf(origin, sizeof origin, "--swap #%zu", i + 1);
        const char *text = edits->swaps[i];
        const char *eq = strchr(text, '=');
        sluice_node *at = sluice_node_new_scalar(text, 1, origin, 1, 1);
        char *old = eq ? strndup(text, (size_t)(eq - text)) : NULL;
        if (!at || (eq && !old)) {
            sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, origin, 0, 0, "out of memory");
            errors++;
        } else if (!eq || eq == text || !eq[1]) {
            error_at(diag, scene, at,
                     "--swap '%s': write OLD=NEW, a plugin the scene loads and the plugin "
                     "that replaces it (e.g. --swap dbc=mdbc)",
                     text);
            errors++;
        } else {
            errors += swap_plugin(scene, old, eq + 1, at, "--swap", diag);
        }
        free(old);
        sluice_node_free(at);
    }
    for (size_t i = 0; !errors && i < edits->override_count; i++) {
        char origin[32];
        snprintf(origin, sizeof origin, "--set #%zu", i + 1);
        const char *text = edits->overrides[i];
        if (strncmp(text, "variant", 7) == 0 && (text[7] == '=' || text[7] == '.')) {
            /* setting it would only write the record of a resolved scene and
             * apply nothing */
            sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, origin, 1, 1,
                            "--set '%s': a variant is applied with --variant NAME (in a study, "
                            "the key 'variant' beside 'set'); the scene key 'variant' only "
                            "records the variant a resolved scene was made from",
                            text);
            errors++;
        } else if (sluice_yaml_override(scene->root, text, origin, diag) != 0) {
            errors++;
        }
    }
    return errors;
}

int sluice_scene_load_variant(sluice_scene *scene, const char *path, const char *variant,
                              const char *const *overrides, size_t override_count,
                              sluice_diag *diag)
{
    sluice_scene_edits edits = {.overrides = overrides, .override_count = override_count};
    return sluice_scene_load_edited(scene, path, variant, &edits, diag);
}

int sluice_scene_load_edited(sluice_scene *scene, const char *path, const char *variant,
                             const sluice_scene_edits *edits, sluice_diag *diag)
{
    memset(scene, 0, sizeof *scene);
    scene->arena = sluice_arena_create();
    scene->path = strdup(path);
    if (!scene->arena || !scene->path) {
        sluice_diag_add(diag, SLUICE_SEVERITY_ERROR, path, 0, 0, "out of memory");
        return 1;
    }
    char resolved[PATH_MAX];
    char *dir = strdup(path);
    if (!dir)
        return 1;
    char *slash = strrchr(dir, '/');
    const char *d = slash ? (slash == dir ? "/" : (*slash = '\0', dir)) : ".";
    scene->directory = strdup(realpath(d, resolved) ? resolved : d);
    free(dir);
    if (!scene->directory)
        return 1;

    scene->root = sluice_yaml_parse_file(path, diag);
    if (!scene->root)
        return (int)(sluice_diag_error_count(diag) ? sluice_diag_error_count(diag) : 1);
    if (scene->root->kind != SLUICE_NODE_MAPPING) {
        error_at(diag, scene, scene->root, "a scene must be a mapping of sections");
        return 1;
    }
    /* the variant first, then the command line's edits */
    int errors = apply_variant(scene, variant, diag);
    if (errors)
        return errors;
    if (edits)
        errors = apply_edits(scene, edits, diag);
    if (errors)
        return errors;
    const sluice_node *late = sluice_node_get_key(scene->root, "variants");
    if (late) {
        error_at(diag, scene, late,
                 "'variants' can only be written in the scene file: it is taken out before a "
                 "variant and the --remove, --swap and --set edits are applied");
        return 1;
    }

    errors += check_top_level(scene, diag);

    /* dimensions first: vectors depend on it */
    sluice_node *dims = sluice_node_get(scene->root, "dimensions");
    long long dimensions = 0;
    if (!dims) {
        error_at(diag, scene, scene->root, "missing required key 'dimensions' (2 or 3)");
        return errors + 1;
    }
    if (dims->kind != SLUICE_NODE_SCALAR || !dims->plain ||
        sluice_parse_int(dims->value, &dimensions) != 0 || (dimensions != 2 && dimensions != 3)) {
        error_at(diag, scene, dims, "dimensions must be 2 or 3, got '%s'",
                 dims->kind == SLUICE_NODE_SCALAR ? dims->value : "a collection");
        return errors + 1;
    }
    scene->dimensions = (uint32_t)dimensions;

    errors += bind_sections(scene, diag);
    errors += load_geometry(scene, diag);
    if (!errors && scene->fluid_count == 0)
        sluice_diag_add(diag, SLUICE_SEVERITY_WARNING, scene->path, 0, 0,
                        "the scene has no fluid regions");

    errors += load_plugin_path(scene, diag);
    errors += load_plugins(scene, diag);
    return errors;
}

void sluice_scene_free(sluice_scene *scene)
{
    for (size_t i = 0; i < scene->wall_count; i++)
        sluice_wall_geometry_free(&scene->walls[i].geometry);
    sluice_node_free(scene->root);
    sluice_arena_destroy(scene->arena);
    free(scene->path);
    free(scene->directory);
    memset(scene, 0, sizeof *scene);
}
