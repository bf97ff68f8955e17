/* Contacts between fluid particles and the wall surface, shared by the
 * force-based wall schemes penalty_contact and repulsive_force (header only:
 * plugins never link against each other).
 *
 * The walls of one scheme (those whose `scheme` is the component's name) are
 * copied at bind: segments (2D) or triangles (3D) with their unit normals into
 * the fluid, and bounding boxes per wall and per element so that a particle
 * far from every wall costs a few comparisons.
 *
 * Definition of the contacts of a point p with one wall, within a range R
 * (the contact distance d0 of penalty_contact, the cutoff r0 of
 * repulsive_force):
 *
 *  - Behind the wall. When the wall's signed distance d is negative and p is
 *    not past an open end (the crossing test of the core: the side is given
 *    by the normal of the nearest element at an interior point, by the
 *    core's pseudo-normal from api->walls->wall_nearest at a vertex or an edge), p
 *    has crossed the wall: one contact, gap d < 0, along that normal,
 *    whatever the other faces near it. Pushing along every face p is behind
 *    would push a particle inside a thin solid out through its far face.
 *    Only particles within `reach` of the wall are looked at (the callers
 *    use R + 2h: a step never moves a particle a kernel support).
 *  - In front of the wall (or past an open end). A contact is a local
 *    minimum of the distance |p - x| over the wall surface closer than R:
 *    for every element e, the closest point c_e of e to p (a segment or a
 *    triangle is convex, so c_e is its only local minimum on e) is a contact
 *    when no element that contains c_e is closer to p, and it is counted once:
 *    an element that has c_e as an interior point at the same distance wins
 *    (a face contact), else the lowest-indexed element that has it. Then:
 *      * c_e inside an element (its own closest feature is its interior): gap
 *        = (p - a_e) . n_e, along the element normal n_e, counted only when
 *        gap >= 0 (the far face of a solid is not in contact from outside).
 *        An interior point belongs to no other element, so no test is needed.
 *      * c_e on a vertex (2D, 3D) or an edge (3D): gap = |p - c_e|, along
 *        (p - c_e) / gap (the pseudo-normal when p is on it). A convex vertex
 *        or edge is the closest point of every element that shares it, so it
 *        is one contact, along p - vertex, not one per element. At a concave
 *        vertex or edge the shared point is never a local minimum from the
 *        fluid side (p projects into the interior of at least one of the
 *        faces, which is closer), so a particle in a concave corner gets one
 *        contact from each face it is within R of. A vertex or edge shared
 *        only by coplanar triangles (the diagonal of a rectangle) is never a
 *        local minimum either.
 *    Contacts of one point are at most CONTACT_MAX (distinct local minima
 *    closer than R; more cannot occur on a wall meshed coarser than R).
 *
 * The "contains" and "tie" tests use a tolerance of 1e-9 times the wall's
 * size and position (bounding box), far above the rounding of the closest
 * points and far below any spacing.
 *
 * Walls of other schemes are ignored; each scheme handles only its own. */
#ifndef SLUICE_WALL_CONTACT_H
#define SLUICE_WALL_CONTACT_H

#include <math.h>
#include <string.h>

/* relative to this file, so that tests can include this header too */
#include <sluice/plugin_util.h>

#define CONTACT_MAX 32

typedef struct contact_wall {
    uint32_t index;         /* api->walls->wall index */
    uint32_t element_count; /* segments (2D) or triangles (3D) */
    sluice_real *points;    /* 2 (2D) or 3 (3D) points of 3 reals per element */
    sluice_real *normals;   /* unit normal into the fluid, 3 reals per element */
    sluice_real *bounds;    /* per element: min xyz, max xyz */
    sluice_real box[6];     /* the whole wall: min xyz, max xyz */
    sluice_real tolerance;  /* m: same point / same distance */
} contact_wall;

typedef struct contact_walls {
    uint32_t dims;
    uint32_t count;
    contact_wall *walls;
} contact_walls;

/* One contact: gap (m; < 0 behind the wall) and the unit direction from the
 * wall to the particle (the direction of the repulsion). */
typedef struct contact {
    sluice_real gap;
    sluice_real direction[3];
} contact;

static inline void contact_walls_free(contact_walls *cw)
{
    for (uint32_t w = 0; w < cw->count; w++) {
        free(cw->walls[w].points);
        free(cw->walls[w].normals);
        free(cw->walls[w].bounds);
    }
    free(cw->walls);
    cw->walls = NULL;
    cw->count = 0;
}

/* Copies the walls whose scheme is `scheme` (with `exclude`, those whose
 * scheme is not). Returns SLUICE_OK, or SLUICE_ERROR after api->messages->error (out
 * of memory). */
static inline int contact_walls_select(contact_walls *cw, const sluice_api *api,
                                       sluice_host *host, const char *scheme, int exclude,
                                       uint32_t dims)
{
    memset(cw, 0, sizeof *cw);
    cw->dims = dims;
    const uint32_t total = api->walls->wall_count(host);
    cw->walls = calloc((size_t)total + 1, sizeof *cw->walls);
    if (!cw->walls) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    const size_t corners = dims == 2 ? 2 : 3;
    for (uint32_t w = 0; w < total; w++) {
        const sluice_wall *wall = api->walls->wall(host, w);
        if (!wall || !wall->scheme || (strcmp(wall->scheme, scheme) != 0) != (exclude != 0) ||
            wall->element_count == 0)
            continue;
        contact_wall *c = &cw->walls[cw->count];
        const size_t n = wall->element_count;
        c->index = w;
        c->element_count = wall->element_count;
        c->points = malloc(n * corners * 3 * sizeof *c->points);
        c->normals = malloc(n * 3 * sizeof *c->normals);
        c->bounds = malloc(n * 6 * sizeof *c->bounds);
        cw->count++; /* so that contact_walls_free releases a partial wall */
        if (!c->points || !c->normals || !c->bounds) {
            contact_walls_free(cw);
            api->messages->error(host, "out of memory");
            return SLUICE_ERROR;
        }
        memcpy(c->points, wall->points, n * corners * 3 * sizeof *c->points);
        memcpy(c->normals, wall->normals, n * 3 * sizeof *c->normals);
        for (int d = 0; d < 3; d++) {
            c->box[d] = (sluice_real)INFINITY;
            c->box[3 + d] = -(sluice_real)INFINITY;
        }
        for (size_t e = 0; e < n; e++) {
            sluice_real *b = c->bounds + 6 * e;
            const sluice_real *v = c->points + corners * 3 * e;
            for (int d = 0; d < 3; d++) {
                b[d] = b[3 + d] = v[d];
                for (size_t j = 1; j < corners; j++) {
                    sluice_real x = v[3 * j + (size_t)d];
                    b[d] = x < b[d] ? x : b[d];
                    b[3 + d] = x > b[3 + d] ? x : b[3 + d];
                }
                c->box[d] = b[d] < c->box[d] ? b[d] : c->box[d];
                c->box[3 + d] = b[3 + d] > c->box[3 + d] ? b[3 + d] : c->box[3 + d];
            }
        }
        sluice_real scale = 0;
        for (int d = 0; d < 6; d++)
            scale += fabs(c->box[d]);
        c->tolerance = (sluice_real)1e-9 * scale;
    }
    return SLUICE_OK;
}

/* The walls whose scheme is `scheme`. */
static inline int contact_walls_build(contact_walls *cw, const sluice_api *api, sluice_host *host,
                                      const char *scheme, uint32_t dims)
{
    return contact_walls_select(cw, api, host, scheme, 0, dims);
}

/* Is p within `margin` of the box (min xyz, max xyz)? */
static inline int contact_box_near(const sluice_real *box, const sluice_real p[3],
                                   sluice_real margin, uint32_t dims)
{
    for (uint32_t d = 0; d < dims; d++)
        if (p[d] < box[d] - margin || p[d] > box[3 + d] + margin)
            return 0;
    return 1;
}

static inline sluice_real contact_dot(const sluice_real a[3], const sluice_real b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Closest point of segment ab to p: feature 0 interior, 1 a, 2 b. */
static inline sluice_real contact_segment(const sluice_real p[3], const sluice_real a[3],
                                          const sluice_real b[3], sluice_real c[3], int *feature)
{
    const sluice_real ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const sluice_real ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    const sluice_real length2 = contact_dot(ab, ab);
    const sluice_real t = length2 > 0 ? contact_dot(ap, ab) / length2 : 0;
    if (t <= 0) {
        memcpy(c, a, 3 * sizeof *c);
        *feature = 1;
    } else if (t >= 1) {
        memcpy(c, b, 3 * sizeof *c);
        *feature = 2;
    } else {
        for (int d = 0; d < 3; d++)
            c[d] = a[d] + t * ab[d];
        *feature = 0;
    }
    const sluice_real pc[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    return sqrt(contact_dot(pc, pc));
}

/* Closest point of triangle abc to p (C. Ericson, Real-Time Collision
 * Detection, 2005, 5.1.5): feature 0 face, 1..3 vertex a/b/c, 4..6 edge
 * ab/bc/ca. A degenerate triangle falls back to its closest edge. */
static inline sluice_real contact_triangle(const sluice_real p[3], const sluice_real a[3],
                                           const sluice_real b[3], const sluice_real cc[3],
                                           sluice_real c[3], int *feature)
{
    const sluice_real ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const sluice_real ac[3] = {cc[0] - a[0], cc[1] - a[1], cc[2] - a[2]};
    const sluice_real n[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2],
                              ab[0] * ac[1] - ab[1] * ac[0]};
    if (!(contact_dot(n, n) > 1e-24 * contact_dot(ab, ab) * contact_dot(ac, ac))) {
        static const int map[3][3] = {{4, 1, 2}, {5, 2, 3}, {6, 3, 1}};
        const sluice_real *v[3] = {a, b, cc};
        sluice_real best = (sluice_real)INFINITY;
        for (int e = 0; e < 3; e++) {
            sluice_real q[3];
            int f;
            sluice_real r = contact_segment(p, v[e], v[(e + 1) % 3], q, &f);
            if (r < best) {
                best = r;
                *feature = map[e][f];
                memcpy(c, q, sizeof q);
            }
        }
        return best;
    }
    const sluice_real ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    const sluice_real d1 = contact_dot(ab, ap), d2 = contact_dot(ac, ap);
    const sluice_real bp[3] = {p[0] - b[0], p[1] - b[1], p[2] - b[2]};
    const sluice_real d3 = contact_dot(ab, bp), d4 = contact_dot(ac, bp);
    const sluice_real cp[3] = {p[0] - cc[0], p[1] - cc[1], p[2] - cc[2]};
    const sluice_real d5 = contact_dot(ab, cp), d6 = contact_dot(ac, cp);
    const sluice_real vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d1 <= 0 && d2 <= 0) {
        memcpy(c, a, 3 * sizeof *c);
        *feature = 1;
    } else if (d3 >= 0 && d4 <= d3) {
        memcpy(c, b, 3 * sizeof *c);
        *feature = 2;
    } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const sluice_real v = d1 / (d1 - d3);
        for (int d = 0; d < 3; d++)
            c[d] = a[d] + v * ab[d];
        *feature = 4;
    } else if (d6 >= 0 && d5 <= d6) {
        memcpy(c, cc, 3 * sizeof *c);
        *feature = 3;
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const sluice_real w = d2 / (d2 - d6);
        for (int d = 0; d < 3; d++)
            c[d] = a[d] + w * ac[d];
        *feature = 6;
    } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const sluice_real w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int d = 0; d < 3; d++)
            c[d] = b[d] + w * (cc[d] - b[d]);
        *feature = 5;
    } else {
        const sluice_real denominator = 1 / (va + vb + vc);
        const sluice_real v = vb * denominator, w = vc * denominator;
        for (int d = 0; d < 3; d++)
            c[d] = a[d] + ab[d] * v + ac[d] * w;
        *feature = 0;
    }
    const sluice_real pc[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    return sqrt(contact_dot(pc, pc));
}

static inline sluice_real contact_element(const contact_wall *w, uint32_t e, const sluice_real p[3],
                                          uint32_t dims, sluice_real c[3], int *feature)
{
    if (dims == 2) {
        const sluice_real *v = w->points + 6 * (size_t)e;
        return contact_segment(p, v, v + 3, c, feature);
    }
    const sluice_real *v = w->points + 9 * (size_t)e;
    return contact_triangle(p, v, v + 3, v + 6, c, feature);
}

/* Is the vertex or edge point c of element e (closest to p, at distance r)
 * a contact claimed by e: no element containing c is closer to p, and no
 * element containing c has it at the same distance as its interior point (a
 * face contact then) or with a lower index? */
static inline int contact_claimed(const contact_wall *w, uint32_t e, const sluice_real p[3],
                                  const sluice_real c[3], sluice_real r, uint32_t dims)
{
    const sluice_real tol = w->tolerance;
    for (uint32_t o = 0; o < w->element_count; o++) {
        if (o == e || !contact_box_near(w->bounds + 6 * (size_t)o, c, tol, dims))
            continue;
        sluice_real q[3];
        int f;
        if (contact_element(w, o, c, dims, q, &f) > tol)
            continue; /* o does not contain c */
        sluice_real ro = contact_element(w, o, p, dims, q, &f);
        if (ro < r - tol || (ro <= r + tol && (o < e || f == 0)))
            return 0;
    }
    return 1;
}

/* The contacts of point p with the walls of `cw` closer than `range`, plus
 * the behind-the-wall contacts of points behind a wall by less than `reach`
 * (>= range). Writes at most CONTACT_MAX and returns their number. Thread-safe
 * (api->walls->wall_nearest is). */
static inline uint32_t contact_find(const contact_walls *cw, const sluice_api *api,
                                    sluice_host *host, const sluice_real p[3], sluice_real range,
                                    sluice_real reach, uint32_t dims, contact *out)
{
    uint32_t n = 0;
    for (uint32_t k = 0; k < cw->count; k++) {
        const contact_wall *w = &cw->walls[k];
        if (!contact_box_near(w->box, p, reach, dims))
            continue;
        /* the nearest element (the first at the smallest distance, as the
         * core's signed distance takes it) */
        sluice_real best = (sluice_real)INFINITY;
        uint32_t best_element = UINT32_MAX;
        int best_feature = 0;
        for (uint32_t e = 0; e < w->element_count; e++) {
            if (!contact_box_near(w->bounds + 6 * (size_t)e, p, reach, dims))
                continue;
            sluice_real c[3];
            int f;
            sluice_real r = contact_element(w, e, p, dims, c, &f);
            if (r < best) {
                best = r;
                best_element = e;
                best_feature = f;
            }
        }
        if (!(best < reach))
            continue;
        /* which side: the element normal at an interior point, the core's
         * pseudo-normal (api->walls->wall_nearest) at a vertex or an edge */
        if (best_feature == 0) {
            const sluice_real *a = w->points + (dims == 2 ? 6 : 9) * (size_t)best_element;
            const sluice_real *normal = w->normals + 3 * (size_t)best_element;
            const sluice_real pa[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
            const sluice_real gap = contact_dot(pa, normal);
            if (gap < 0) {
                if (n < CONTACT_MAX) {
                    out[n].gap = gap;
                    memcpy(out[n].direction, normal, 3 * sizeof *normal);
                    n++;
                }
                continue;
            }
        } else {
            sluice_wall_point q;
            if (api->walls->wall_nearest(host, p, (int32_t)w->index, &q) == SLUICE_OK && q.distance < 0 &&
                !q.beyond_end) {
                if (n < CONTACT_MAX) {
                    out[n].gap = q.distance;
                    memcpy(out[n].direction, q.normal, sizeof q.normal);
                    n++;
                }
                continue;
            }
        }
        if (!(best < range))
            continue;
        /* in front: the local minima of the distance closer than range */
        for (uint32_t e = 0; e < w->element_count && n < CONTACT_MAX; e++) {
            if (!contact_box_near(w->bounds + 6 * (size_t)e, p, range, dims))
                continue;
            sluice_real c[3];
            int f;
            sluice_real r = contact_element(w, e, p, dims, c, &f);
            if (!(r < range))
                continue;
            if (f == 0) {
                const sluice_real *a = w->points + (dims == 2 ? 6 : 9) * (size_t)e;
                const sluice_real *normal = w->normals + 3 * (size_t)e;
                const sluice_real pa[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
                const sluice_real gap = contact_dot(pa, normal);
                if (gap < 0)
                    continue; /* the far face of a solid */
                out[n].gap = gap;
                memcpy(out[n].direction, normal, 3 * sizeof *normal);
                n++;
                continue;
            }
            if (!contact_claimed(w, e, p, c, r, dims))
                continue;
            out[n].gap = r;
            if (r > 0) {
                for (int d = 0; d < 3; d++)
                    out[n].direction[d] = (p[d] - c[d]) / r;
            } else { /* on the vertex or edge itself: its pseudo-normal */
                sluice_wall_point q;
                if (api->walls->wall_nearest(host, p, (int32_t)w->index, &q) != SLUICE_OK)
                    continue;
                memcpy(out[n].direction, q.normal, sizeof q.normal);
            }
            n++;
        }
    }
    return n;
}

#endif
