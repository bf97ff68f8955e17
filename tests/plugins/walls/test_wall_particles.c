/* Wall-particle schemes that take their values from the fluid
 * (plugins/walls/mirror_walls.c: ghost_particles, mdbc) and dbc's prescribed
 * wall motion (plugins/walls/dbc.c):
 *  - mirror values: on a hand-made state (uniform velocity, linear density
 *    field, stale pressure column) every ghost wall particle carries the
 *    mirrored velocity exactly and the pressure EOS(rho(x_m)) + rho(x_m)
 *    g . (x_b - x_m) to round-off (the first-order corrected interpolation is
 *    exact for linear fields); every mdbc wall particle the linearly
 *    extrapolated density rho(x_b), also exact for a linear field;
 *  - still water (configs/still_water_2d.yaml with the scheme substituted):
 *    no fluid particle behind a wall, bottom pressure within 3 % of rho g H,
 *    kinetic energy decays to rest; the fluid next to mirror walls settles
 *    at dx/2 from the wall line, closer to it with mdbc than with dbc;
 *  - dam break (configs/dam_break_2d.yaml, dx = 0.1 m) until 0.85 s, after
 *    the impact on the far wall (0.70-0.76 s): no particle crosses a wall,
 *    count conserved. Later, particles in tension in the film on the left
 *    wall drift through ghost no-slip and mdbc walls (see mirror_walls.c);
 *    SLUICE_DAM_BREAK_DX and SLUICE_DAM_BREAK_END rerun the case longer or
 *    finer, SLUICE_STILL_WATER_DX the tanks at another spacing, and
 *    SLUICE_WALL_TEST_VERBOSE lists every crossing;
 *  - dbc motion: a piston at constant speed and an oscillating one follow the
 *    prescribed law exactly, the other walls do not move. */
#include <math.h>

#include "geometry.h"
#include "sim_util.h"
/* Internal: signed distances to the scene's walls (geometry.h) (not in sim.h) */
#include "sim_internal.h"

#define G 9.81
#define RHO0 1000.0

/* ------------------------------------------------------------- helpers -- */

/* `text` with the first occurrence of `from` replaced by `to` (asserts it
 * occurs). */
static char *substitute(const char *text, const char *from, const char *to)
{
    const char *at = strstr(text, from);
    ck_assert_msg(at != NULL, "'%s' not found in the scene", from);
    size_t head = (size_t)(at - text), n = strlen(text) - strlen(from) + strlen(to) + 1;
    char *out = malloc(n);
    ck_assert_ptr_nonnull(out);
    memcpy(out, text, head);
    strcpy(out + head, to);
    strcat(out, at + strlen(from));
    return out;
}

/* A configs/ scene with its `  dbc: {}` line replaced by `walls` (the one
 * line that switches the wall scheme). */
static char *scene_with_walls(const char *config, const char *walls)
{
    char *path = test_config(config);
    ck_assert_ptr_nonnull(path);
    char *text = test_read_file(path);
    ck_assert_msg(text != NULL, "cannot read %s", path);
    char *line = NULL;
    ck_assert_int_ge(asprintf(&line, "  %s\n", walls), 0);
    char *out = substitute(text, "  dbc: {}\n", line);
    free(line);
    free(text);
    free(path);
    return out;
}

/* Fluid particles behind a wall (signed distance < 0, not past an open end)
 * and the smallest signed distance of any fluid particle to any wall. */
static int crossings(sluice_sim *sim, double *smallest)
{
    const sluice_view *v = sluice_sim_view(sim);
    int crossed = 0;
    double least = INFINITY;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        sluice_real p[3] = {v->position[0][i], v->position[1][i],
                            v->dimensions == 3 ? v->position[2][i] : 0};
        for (size_t w = 0; w < sim->scene.wall_count; w++) {
            int beyond = 0;
            double d = (double)sluice_wall_signed_distance(&sim->scene.walls[w].geometry, p,
                                                           &beyond, NULL);
            if (beyond)
                continue;
            if (d < 0) {
                crossed++;
                if (getenv("SLUICE_WALL_TEST_VERBOSE"))
                    fprintf(stderr,
                            "  t = %.4f s: fluid particle id %llu at (%g, %g) is %.3g m "
                            "behind wall %zu (pressure %g Pa)\n",
                            sluice_sim_time(sim), (unsigned long long)v->id[i], p[0], p[1], -d, w,
                            test_column(sim, "pressure", 0)[i]);
            }
            if (d < least)
                least = d;
        }
    }
    if (smallest)
        *smallest = least;
    return crossed;
}

static double kinetic_energy(sluice_sim *sim)
{
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *m = test_column(sim, "mass", 0);
    const sluice_real *u = test_column(sim, "velocity", 0), *w = test_column(sim, "velocity", 1);
    double e = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            e += 0.5 * m[i] * (u[i] * u[i] + w[i] * w[i]);
    return e;
}

/* ------------------------------------------------------- mirror values -- */

/* Closest point of the tank [0, 1] x [0, 0.8] (left, bottom, right sides)
 * to p, by brute force over the three segments. */
static void tank_closest(const double p[2], double c[2])
{
    const double seg[3][4] = {{0, 0.8, 0, 0}, {0, 0, 1, 0}, {1, 0, 1, 0.8}};
    double best = INFINITY;
    for (int s = 0; s < 3; s++) {
        double ax = seg[s][0], ay = seg[s][1], bx = seg[s][2], by = seg[s][3];
        double dx = bx - ax, dy = by - ay;
        double t = ((p[0] - ax) * dx + (p[1] - ay) * dy) / (dx * dx + dy * dy);
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        double qx = ax + t * dx, qy = ay + t * dy;
        double d = hypot(p[0] - qx, p[1] - qy);
        if (d < best - 1e-12) {
            best = d;
            c[0] = qx;
            c[1] = qy;
        }
    }
}

/* Tait with gamma = 7, c0 = 20 m/s, as in mirror_scene */
static double tait(double rho)
{
    const double B = 20.0 * 20.0 * RHO0 / 7;
    return B * (pow(rho / RHO0, 7) - 1);
}

/* the hand-made density field: linear, 1.6 % over the fluid box; `base` is
 * its value / rho0 at (0, 0.8) (above 1: positive pressure everywhere) */
static double density_field(double base, double x, double y)
{
    return RHO0 * (base + 0.004 * x - 0.012 * (y - 0.8));
}

static sluice_sim *mirror_scene_with(const char *walls, double fluid_top,
                                     const char *const *sets, size_t set_count);

static sluice_sim *mirror_scene(const char *walls, double fluid_top)
{
    return mirror_scene_with(walls, fluid_top, NULL, 0);
}

/* mirror_scene with `--set` overrides */
static sluice_sim *mirror_scene_with(const char *walls, double fluid_top,
                                     const char *const *sets, size_t set_count)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
             "time: {end: 1}\n"
             "domain: {min: [-0.3, -0.3], max: [1.3, 1.3]}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [1, %g]}]\n"
             "  walls: [{shape: tank, min: [0, 0], max: [1, 0.8]}]\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  gravity: {}\n"
             "  %s\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             fluid_top, walls);
    return test_load("mirror-values", yaml, sets, set_count);
}

/* Sets the hand-made state: uniform velocity U, the linear density field and
 * a pressure column that is deliberately wrong (what prepare() finds there is
 * the previous evaluation's pressure, never the current one). */
static void hand_made_state(sluice_sim *sim, const double U[2], double base)
{
    const sluice_view *v = sluice_sim_view(sim);
    sluice_real *rho = test_column(sim, "density", 0), *p = test_column(sim, "pressure", 0);
    sluice_real *u = test_column(sim, "velocity", 0), *w = test_column(sim, "velocity", 1);
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        rho[i] = (sluice_real)density_field(base, v->position[0][i], v->position[1][i]);
        p[i] = (sluice_real)(0.9 * tait(rho[i]) + 100);
        u[i] = (sluice_real)U[0];
        w[i] = (sluice_real)U[1];
    }
}

/* base < 1 puts the upper part of the field in tension: with clamp_pressure
 * the wall pressure is then max(p_m + rho_m g . (x_b - x_m), 0) (Tait's
 * reference pressure is 0), without it the mirrored tension itself. */
static void check_ghost_mirror(const char *slip, int clamp, double base)
{
    char walls[128];
    snprintf(walls, sizeof walls, "ghost_particles: {slip: %s, clamp_pressure: %s}", slip,
             clamp ? "true" : "false");
    sluice_sim *sim = mirror_scene(walls, 1.0);
    const double U[2] = {0.3, -0.2};
    hand_made_state(sim, U, base);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *p = test_column(sim, "pressure", 0);
    const sluice_real *u = test_column(sim, "velocity", 0), *w = test_column(sim, "velocity", 1);
    const int free_slip = strcmp(slip, "free_slip") == 0;
    double worst_p = 0, worst_u = 0, scale = 0;
    int walls_seen = 0, tension = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_WALL)
            continue;
        walls_seen++;
        const double xb[2] = {v->position[0][i], v->position[1][i]};
        double c[2] = {0, 0};
        tank_closest(xb, c);
        const double xm[2] = {2 * c[0] - xb[0], 2 * c[1] - xb[1]};
        const double rho_m = density_field(base, xm[0], xm[1]);
        /* p_b = p_m + rho_m g . (x_b - x_m), g = (0, -G) */
        double expected = tait(rho_m) + rho_m * (-G) * (xb[1] - xm[1]);
        if (expected < 0) {
            tension++;
            if (clamp)
                expected = 0;
        }
        worst_p = fmax(worst_p, fabs((double)p[i] - expected));
        scale = fmax(scale, fabs(expected));
        double eu[2];
        if (free_slip) {
            double n[2] = {xm[0] - xb[0], xm[1] - xb[1]}, len = hypot(n[0], n[1]);
            n[0] /= len;
            n[1] /= len;
            double un = U[0] * n[0] + U[1] * n[1];
            eu[0] = U[0] - 2 * un * n[0];
            eu[1] = U[1] - 2 * un * n[1];
        } else {
            eu[0] = -U[0];
            eu[1] = -U[1];
        }
        worst_u = fmax(worst_u, fmax(fabs(u[i] - eu[0]), fabs(w[i] - eu[1])));
    }
    fprintf(stderr,
            "ghost_particles %s, clamp_pressure %d, hand-made state: %d wall particles (%d with "
            "mirrored tension); largest pressure error %.2e Pa (of %.0f Pa), largest velocity "
            "error %.2e m/s\n",
            slip, clamp, walls_seen, tension, worst_p, scale, worst_u);
    ck_assert_int_gt(walls_seen, 100);
    ck_assert_int_eq(tension > 0, base < 1);
    /* linear fields are reproduced exactly by the corrected interpolation:
     * what remains is the EOS inversion (the secant iteration stops within
     * 1e-13 rho0 = 1e-10 kg/m^3 of the density, c^2 x that = 4e-8 Pa at
     * c = 20 m/s) and round-off (sums of ~30 terms; Tait's x^7 - 1) */
    ck_assert_msg(worst_p <= 1e-7, "pressure off by %g Pa", worst_p);
    ck_assert_msg(worst_u <= 1e-12, "velocity off by %g m/s", worst_u);
    sluice_sim_free(sim);
}

START_TEST(ghost_mirror_values_no_slip)
{
    check_ghost_mirror("no_slip", 1, 1.004);
}
END_TEST
START_TEST(ghost_mirror_values_free_slip)
{
    check_ghost_mirror("free_slip", 1, 1.004);
}
END_TEST
START_TEST(ghost_mirror_values_tension)
{
    check_ghost_mirror("no_slip", 0, 0.998);
    check_ghost_mirror("free_slip", 1, 0.998);
}
END_TEST

/* continuity's wall_velocity (1.2.0). A uniform flow U = (0.1, -0.2) in the
 * tank on no-slip ghost walls: the wall particles carry v_b = -U (the
 * mirrored velocity; the corrected interpolation reproduces a uniform field
 * exactly), and the fluid-fluid terms of sum_j m_j (v_i - v_j) . grad W
 * vanish. With wall_velocity: particle the wall pairs count v_i - v_b = 2U,
 * with rest (the fixed wall's own velocity, zero) U: the fluid's density
 * rate with `particle` is twice the one with `rest`, particle by particle,
 * to round-off. */
START_TEST(continuity_wall_velocity_rest)
{
    sluice_real *rates[2] = {NULL, NULL};
    sluice_index count = 0;
    const char *modes[2] = {"particle", "rest"};
    sluice_sim *sims[2];
    for (int m = 0; m < 2; m++) {
        char set[64];
        snprintf(set, sizeof set, "plugins.continuity.wall_velocity=%s", modes[m]);
        const char *const sets[1] = {set};
        sims[m] = mirror_scene_with("ghost_particles: {slip: no_slip}", 1.0, sets, 1);
        const double U[2] = {0.1, -0.2};
        hand_made_state(sims[m], U, 1.01);
        ck_assert_int_eq(sluice_sim_evaluate(sims[m]), SLUICE_OK);
        rates[m] = test_column(sims[m], "density_rate", 0);
        count = sluice_sim_view(sims[m])->count;
    }
    const sluice_view *v = sluice_sim_view(sims[1]);
    double largest = 0;
    for (sluice_index i = 0; i < count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID)
            largest = fmax(largest, fabs((double)rates[1][i]));
    double worst = 0;
    int near_wall = 0;
    for (sluice_index i = 0; i < count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        if (fabs((double)rates[1][i]) > 1e-6 * largest)
            near_wall++;
        worst = fmax(worst, fabs((double)rates[0][i] - 2 * (double)rates[1][i]));
    }
    fprintf(stderr,
            "continuity wall_velocity: %d fluid particles with a wall term, largest rate %.3g "
            "kg m^-3 s^-1 (rest); |rate(particle) - 2 rate(rest)| at most %.2e\n",
            near_wall, largest, worst);
    ck_assert_double_gt(largest, 1);
    ck_assert_int_gt(near_wall, 20);
    ck_assert_msg(worst <= 1e-9 * largest, "rates off by %g", worst);
    sluice_sim_free(sims[0]);
    sluice_sim_free(sims[1]);
}
END_TEST

/* A drop between two walls that meet without sharing a vertex, as in the
 * abrupt-drop scenes: an upper bed and the drop's face (one polyline,
 * (-0.5, 0.2) -> (0.5, 0.2) -> (0.5, 0)) and a lower bed that starts inside
 * the step (0.3, 0) -> (1.5, 0), so that its layers fill the block behind
 * the concave corner at (0.5, 0). A wall particle in that block just left
 * of x = 0.5 is nearest the lower bed, whose mirror lands inside the step,
 * behind the face, where no fluid is; its mirror must be the next nearest
 * wall point's (the corner vertex: the point reflection, in the fluid). The
 * expected mirror of every wall particle is computed here from the two
 * walls' geometry: of the walls' nearest points, the nearest whose mirror
 * lies in the fluid (above the upper bed or right of the face, above the
 * lower bed). With the hand-made linear density field, the wall pressure
 * is then tait(rho(x_m)) + rho(x_m) (-g) (y_b - y_m) exactly. */
static double segment_closest(const double p[2], const double a[2], const double b[2],
                              double c[2])
{
    const double dx = b[0] - a[0], dy = b[1] - a[1];
    double t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    c[0] = a[0] + t * dx;
    c[1] = a[1] + t * dy;
    return hypot(p[0] - c[0], p[1] - c[1]);
}

START_TEST(ghost_mirror_at_a_drop)
{
    const char *yaml =
        "dimensions: 2\n"
        "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
        "time: {end: 1}\n"
        "domain: {min: [-0.8, -0.3], max: [1.8, 1.0]}\n"
        "geometry:\n"
        "  fluid:\n"
        "    - {shape: box, min: [-0.5, 0.2], max: [0.5, 0.7]}\n"
        "    - {shape: box, min: [0.5, 0], max: [1.5, 0.7]}\n"
        "  walls:\n"
        "    - {shape: polyline, points: [[-0.5, 0.2], [0.5, 0.2], [0.5, 0]], name: upper}\n"
        "    - {shape: polyline, points: [[0.3, 0], [1.5, 0]], name: lower}\n"
        "initial: {density: rest}\n"
        "plugins:\n"
        "  wendland_c2: {}\n"
        "  tait: {speed_of_sound: 20}\n"
        "  continuity: {}\n"
        "  pressure_gradient: {}\n"
        "  gravity: {}\n"
        "  ghost_particles: {slip: free_slip}\n"
        "  time_step: {}\n"
        "  symplectic: {}\n";
    sluice_sim *sim = test_load("mirror-drop", yaml, NULL, 0);
    const double U[2] = {0.3, -0.2};
    hand_made_state(sim, U, 1.01);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *p = test_column(sim, "pressure", 0);
    const double seg[3][2][2] = {{{-0.5, 0.2}, {0.5, 0.2}}, {{0.5, 0.2}, {0.5, 0}},
                                 {{0.3, 0}, {1.5, 0}}};
    double worst = 0;
    int checked = 0, corner = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_WALL)
            continue;
        const double xb[2] = {v->position[0][i], v->position[1][i]};
        if (xb[0] < -0.2 || xb[0] > 1.2) /* away from the walls' open ends */
            continue;
        /* nearest point of each wall (the polyline: the nearer segment) */
        double c[2][2], d[2], q[2];
        d[0] = segment_closest(xb, seg[0][0], seg[0][1], c[0]);
        const double d1 = segment_closest(xb, seg[1][0], seg[1][1], q);
        if (d1 < d[0]) {
            d[0] = d1;
            c[0][0] = q[0];
            c[0][1] = q[1];
        }
        d[1] = segment_closest(xb, seg[2][0], seg[2][1], c[1]);
        const int order[2] = {d[0] <= d[1] ? 0 : 1, d[0] <= d[1] ? 1 : 0};
        double xm[2] = {0, 0};
        int found = 0;
        for (int k = 0; k < 2 && !found; k++) {
            const double *cc = c[order[k]];
            xm[0] = 2 * cc[0] - xb[0];
            xm[1] = 2 * cc[1] - xb[1];
            const int in_fluid = xm[0] < 0.5 ? xm[1] > 0.2 : xm[1] > 0;
            found = in_fluid;
            if (found && k == 1)
                corner++;
        }
        ck_assert_msg(found, "no mirror in the fluid for the wall particle at (%g, %g)", xb[0],
                      xb[1]);
        const double rho_m = density_field(1.01, xm[0], xm[1]);
        const double expected = tait(rho_m) + rho_m * (-G) * (xb[1] - xm[1]);
        worst = fmax(worst, fabs((double)p[i] - expected));
        checked++;
    }
    fprintf(stderr,
            "ghost_particles at a drop: %d wall particles checked, %d of them in the corner block "
            "mirrored through the corner instead of into the step; largest pressure error "
            "%.2e Pa\n",
            checked, corner, worst);
    ck_assert_int_gt(checked, 50);
    ck_assert_int_gt(corner, 0);
    ck_assert_msg(worst <= 1e-7, "pressure off by %g Pa", worst);
    sluice_sim_free(sim);
}
END_TEST

/* The same in 3D (4 x 4 corrected interpolation; walls of triangles, with
 * edges and corners): an open tank [0, 0.5]^2 x [0, 0.4] whose nearest point
 * to a wall particle is the particle clamped to the box. Ghost particles
 * (no-slip, Tait, gravity along -z) and mdbc on a linear density field. */
START_TEST(mirror_values_3d)
{
    for (int k = 0; k < 2; k++) {
        char yaml[2048];
        snprintf(yaml, sizeof yaml,
                 "dimensions: 3\n"
                 "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
                 "time: {end: 1}\n"
                 "domain: {min: [-0.3, -0.3, -0.3], max: [0.8, 0.8, 0.8]}\n"
                 "geometry:\n"
                 "  fluid: [{shape: box, min: [0, 0, 0], max: [0.5, 0.5, 0.5]}]\n"
                 "  walls: [{shape: tank, min: [0, 0, 0], max: [0.5, 0.5, 0.4]}]\n"
                 "initial: {density: rest}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  tait: {speed_of_sound: 20}\n"
                 "  continuity: {}\n"
                 "  pressure_gradient: {}\n"
                 "  gravity: {}\n"
                 "  %s\n"
                 "  time_step: {}\n"
                 "  symplectic: {}\n",
                 k ? "mdbc: {}" : "ghost_particles: {slip: no_slip}");
        sluice_sim *sim = test_load("mirror-values-3d", yaml, NULL, 0);
        const double U[3] = {0.3, -0.2, 0.1};
        const sluice_view *v = sluice_sim_view(sim);
        sluice_real *rho = test_column(sim, "density", 0), *p = test_column(sim, "pressure", 0);
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_FLUID)
                continue;
            rho[i] = (sluice_real)(RHO0 * (1.004 + 0.004 * v->position[0][i] -
                                           0.002 * v->position[1][i] -
                                           0.012 * (v->position[2][i] - 0.4)));
            p[i] = 0;
            for (int d = 0; d < 3; d++)
                test_column(sim, "velocity", (uint32_t)d)[i] = (sluice_real)U[d];
        }
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        v = sluice_sim_view(sim);
        rho = test_column(sim, "density", 0);
        p = test_column(sim, "pressure", 0);
        double worst = 0, worst_u = 0;
        int walls = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_WALL)
                continue;
            walls++;
            const double lim[3] = {0.5, 0.5, 0.4};
            double xb[3], xm[3], field_m = 0, field_b = 0;
            for (int d = 0; d < 3; d++) {
                xb[d] = v->position[d][i];
                double c = xb[d] < 0 ? 0 : (xb[d] > lim[d] ? lim[d] : xb[d]);
                xm[d] = 2 * c - xb[d];
            }
            field_m = RHO0 * (1.004 + 0.004 * xm[0] - 0.002 * xm[1] - 0.012 * (xm[2] - 0.4));
            field_b = RHO0 * (1.004 + 0.004 * xb[0] - 0.002 * xb[1] - 0.012 * (xb[2] - 0.4));
            if (k) { /* mdbc: the linear field extrapolated to x_b */
                worst = fmax(worst, fabs((double)rho[i] - field_b));
            } else { /* ghost: p_m + rho_m g . (x_b - x_m) */
                double expected = tait(field_m) + field_m * (-G) * (xb[2] - xm[2]);
                worst = fmax(worst, fabs((double)p[i] - expected));
                for (int d = 0; d < 3; d++)
                    worst_u = fmax(worst_u,
                                   fabs(test_column(sim, "velocity", (uint32_t)d)[i] + U[d]));
            }
        }
        fprintf(stderr, "3D %s: %d wall particles; largest %s error %.2e, velocity error %.2e\n",
                k ? "mdbc" : "ghost_particles no_slip", walls, k ? "density" : "pressure", worst,
                worst_u);
        ck_assert_int_gt(walls, 500);
        /* as in 2D: round-off, and for the ghost pressure the EOS inversion
         * (c^2 x 1e-13 rho0 = 4e-8 Pa) */
        ck_assert_msg(worst <= (k ? 1e-9 : 1e-7), "3D: off by %g", worst);
        ck_assert_msg(worst_u <= 1e-12, "3D: velocity off by %g", worst_u);
        sluice_sim_free(sim);
    }
}
END_TEST

/* Wall particles whose mirror point has no fluid within the kernel support
 * (fluid below 0.3 m; side-wall particles above 0.3 m + 2h, whose mirror
 * points are at their own height) get the rest values: v = 0 and the
 * reference pressure (0 for Tait), i.e. rho0; mdbc gives rho0. */
START_TEST(rest_values_without_fluid)
{
    const char *schemes[3] = {"ghost_particles: {slip: no_slip}",
                              "ghost_particles: {slip: free_slip}", "mdbc: {velocity: no_slip}"};
    for (int k = 0; k < 3; k++) {
        sluice_sim *sim = mirror_scene(schemes[k], 0.3);
        const double U[2] = {0.3, -0.2};
        hand_made_state(sim, U, 1.004);
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *rho = test_column(sim, "density", 0);
        const sluice_real *p = test_column(sim, "pressure", 0);
        const sluice_real *u = test_column(sim, "velocity", 0);
        const sluice_real *w = test_column(sim, "velocity", 1);
        const double reach = 0.3 + 2 * 1.5 * 0.05;
        int dry = 0, wet = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_WALL)
                continue;
            if (v->position[1][i] > reach + 1e-9) {
                dry++;
                ck_assert_msg(u[i] == 0 && w[i] == 0 && rho[i] == RHO0 && p[i] == 0,
                              "%s: wall particle at (%g, %g) without fluid has v = (%g, %g), "
                              "rho = %.17g, p = %g",
                              schemes[k], v->position[0][i], v->position[1][i], u[i], w[i], rho[i],
                              p[i]);
            } else if (v->position[1][i] < 0.2) {
                wet++;
                ck_assert_msg(u[i] != 0 && rho[i] > RHO0, "%s: wet wall particle at rest",
                              schemes[k]);
            }
        }
        fprintf(stderr,
                "%s: %d wall particles without fluid at rest, %d below the water "
                "mirrored\n",
                schemes[k], dry, wet);
        ck_assert_int_ge(dry, 2 * 3 * 6); /* both sides, 3 layers, y in (0.45, 0.8) */
        ck_assert_int_gt(wet, 0);
        sluice_sim_free(sim);
    }
}
END_TEST

/* Schemes mixed per wall: dbc for the bed, ghost particles (without the
 * pressure clamp) for the side walls, on a state in tension above y = 0.47 m.
 * Each scheme builds particles only behind its own walls; the ghost
 * particles keep their mirrored values, below rho0 where the fluid is in
 * tension, although dbc's density clamp (a particle term, run after
 * prepare()) is loaded: it acts on dbc's own particles only. */
START_TEST(mixed_schemes)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
             "time: {end: 1}\n"
             "domain: {min: [-0.3, -0.3], max: [1.3, 1.3]}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [1, 1]}]\n"
             "  walls:\n"
             "    - {shape: polyline, points: [[0, 0], [1, 0]], scheme: dbc, name: bed}\n"
             "    - {shape: polyline, points: [[0, 0.8], [0, 0]], scheme: ghost_particles}\n"
             "    - {shape: polyline, points: [[1, 0], [1, 0.8]], scheme: ghost_particles}\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  gravity: {}\n"
             "  dbc: {}\n"
             "  ghost_particles: {slip: free_slip, clamp_pressure: false}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n");
    sluice_sim *sim = test_load("mixed-walls", yaml, NULL, 0);
    const double U[2] = {0.3, -0.2};
    hand_made_state(sim, U, 0.998);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *rho = test_column(sim, "density", 0);
    const sluice_real *u = test_column(sim, "velocity", 0);
    int bed = 0, sides = 0, tension = 0;
    double worst = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_WALL)
            continue;
        const double xb[2] = {v->position[0][i], v->position[1][i]};
        if (xb[1] < 0) { /* dbc: at rest, density clamped to >= rho0 (rho0 initially) */
            bed++;
            ck_assert(xb[0] > 0 && xb[0] < 1);
            ck_assert(rho[i] == RHO0 && u[i] == 0);
            continue;
        }
        sides++;
        ck_assert(xb[0] < 0 || xb[0] > 1);
        const double xm[2] = {xb[0] < 0 ? -xb[0] : 2 - xb[0], xb[1]};
        const double rho_m = density_field(0.998, xm[0], xm[1]);
        /* side walls: g . (x_b - x_m) = 0, so p_b = p_m and rho_b = rho_m */
        worst = fmax(worst, fabs((double)rho[i] - rho_m));
        tension += rho_m < RHO0;
    }
    fprintf(stderr,
            "mixed schemes: %d dbc particles (bed), %d ghost particles (sides, %d in "
            "tension); ghost densities off by %.2e kg/m^3\n",
            bed, sides, tension, worst);
    ck_assert_int_eq(bed, 3 * 20);       /* 3 layers under the 20 columns */
    ck_assert_int_eq(sides, 2 * 3 * 16); /* 3 layers beside 16 rows, each side */
    ck_assert_int_gt(tension, 0);
    ck_assert_msg(worst <= 1e-9, "ghost densities off by %g", worst);
    sluice_sim_free(sim);
}
END_TEST

/* mdbc: rho_b = rho_g + (x_b - x_g) . grad rho_g is exact for a linear
 * density field wherever the corrected interpolation is used (here below
 * rho0 in the upper part); velocity zero by default, mirrored with
 * velocity: no_slip or free_slip; clamp_density keeps rho_b >= rho0. */
START_TEST(mdbc_extrapolates_linear_density)
{
    const char *modes[3] = {"mdbc: {}", "mdbc: {velocity: no_slip}",
                            "mdbc: {velocity: free_slip, clamp_density: true}"};
    for (int mode = 0; mode < 3; mode++) {
        sluice_sim *sim = mirror_scene(modes[mode], 1.0);
        const double U[2] = {0.3, -0.2};
        hand_made_state(sim, U, 0.998); /* wall densities below rho0 too */
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *rho = test_column(sim, "density", 0);
        const sluice_real *u = test_column(sim, "velocity", 0);
        const sluice_real *w = test_column(sim, "velocity", 1);
        double worst = 0, worst_u = 0;
        int walls = 0, below = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_WALL)
                continue;
            walls++;
            const double xb[2] = {v->position[0][i], v->position[1][i]};
            double expected = density_field(0.998, xb[0], xb[1]);
            below += expected < RHO0;
            if (mode == 2 && expected < RHO0)
                expected = RHO0;
            worst = fmax(worst, fabs((double)rho[i] - expected));
            double eu[2] = {0, 0};
            if (mode == 1) {
                eu[0] = -U[0];
                eu[1] = -U[1];
            } else if (mode == 2) {
                double c[2] = {0, 0};
                tank_closest(xb, c);
                double n[2] = {2 * (c[0] - xb[0]), 2 * (c[1] - xb[1])}, len = hypot(n[0], n[1]);
                double un = (U[0] * n[0] + U[1] * n[1]) / len;
                eu[0] = U[0] - 2 * un * n[0] / len;
                eu[1] = U[1] - 2 * un * n[1] / len;
            }
            worst_u = fmax(worst_u, fmax(fabs(u[i] - eu[0]), fabs(w[i] - eu[1])));
        }
        fprintf(stderr,
                "%s, linear density field: %d wall particles (%d below rho0), largest density "
                "error %.2e kg/m^3, velocity error %.2e m/s\n",
                modes[mode], walls, below, worst, worst_u);
        ck_assert_int_gt(below, 0);
        ck_assert_int_gt(walls, 100);
        /* round-off of the 3x3 solve and of sums of ~30 terms of 1000 */
        ck_assert_msg(worst <= 1e-9, "density off by %g", worst);
        ck_assert_msg(worst_u <= 1e-12, "velocity off by %g", worst_u);
        sluice_sim_free(sim);
    }
}
END_TEST

/* --------------------------------------------------------- still water -- */

/* dx = 0.05 m (10 particles deep) keeps the four 10 s tanks within the
 * suite's time; SLUICE_STILL_WATER_DX overrides it for the report's runs at
 * the scene's own 0.02 m. */
#define TANK_END 10.0
#define TANK_DEPTH 0.5 /* the scene's water depth H, m */

static double tank_dx(void)
{
    const char *text = getenv("SLUICE_STILL_WATER_DX");
    return text ? atof(text) : 0.05;
}

typedef struct tank_result {
    double pressure_error; /* bottom layer vs rho g (H - y), relative */
    double energy_end, energy_first;
    double residual_speed; /* sqrt(2 kinetic energy / fluid mass) at the end, m/s */
    double gap;          /* smallest fluid distance to a wall at the end, m */
    double bottom_layer; /* mean height of the lowest fluid layer (middle 60 %), m */
    double side_column;  /* mean distance of the fluid column next to the left wall
                            (0.2 m < y < 0.4 m), m */
    int crossed;         /* largest number of fluid particles behind a wall at a sample */
    double seconds, steps_per_second;
    int64_t steps;
} tank_result;

static tank_result still_tank(const char *walls, double dx, double t_end)
{
    char *yaml = scene_with_walls("still_water_2d.yaml", walls);
    char sets[2][128];
    snprintf(sets[0], sizeof sets[0], "particles.spacing=%.17g", dx);
    snprintf(sets[1], sizeof sets[1], "time.end=%.17g", t_end);
    const char *set_list[2] = {sets[0], sets[1]};
    sluice_sim *sim = test_load("still-water", yaml, set_list, 2);
    free(yaml);
    tank_result r;
    memset(&r, 0, sizeof r);
    const double H = TANK_DEPTH, width = 1.0; /* the scene's tank is 1 m wide */
    int first = 0;
    double start = sluice_wall_clock();
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < t_end - 1e-9) {
        int status = sluice_sim_step(sim);
        ck_assert_msg(status == SLUICE_RUN_COMPLETE, "still water (%s) stopped: %s", walls,
                      sluice_sim_failure(sim));
        if (sluice_sim_steps(sim) % 20)
            continue;
        int crossed = crossings(sim, NULL);
        if (crossed > r.crossed)
            r.crossed = crossed;
        if (sluice_sim_time(sim) < 1.0) {
            r.energy_first += kinetic_energy(sim);
            first++;
        }
    }
    r.seconds = sluice_wall_clock() - start;
    r.steps = sluice_sim_steps(sim);
    r.energy_first /= first > 0 ? first : 1;
    r.energy_end = kinetic_energy(sim);
    {
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *m = test_column(sim, "mass", 0);
        double mass = 0;
        for (sluice_index i = 0; i < v->count; i++)
            mass += v->kind[i] == SLUICE_KIND_FLUID ? m[i] : 0;
        r.residual_speed = sqrt(2 * r.energy_end / mass);
    }
    int crossed = crossings(sim, &r.gap);
    if (crossed > r.crossed)
        r.crossed = crossed;
    /* bottom pressure as tests/scenes/test_scenes.c measures it, on the current
     * state through one more evaluation */
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *p = test_column(sim, "pressure", 0);
    double lowest = INFINITY;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && v->position[1][i] < lowest)
            lowest = v->position[1][i];
    double leftmost = INFINITY;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID && v->position[1][i] > 0.2 && v->position[1][i] < 0.4 &&
            v->position[0][i] < leftmost)
            leftmost = v->position[0][i];
    double sum_p = 0, sum_ref = 0, layer = 0, side = 0;
    int bottom = 0, in_layer = 0, in_side = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        double x = v->position[0][i], y = v->position[1][i];
        if (v->kind[i] == SLUICE_KIND_FLUID && y > 0.2 && y < 0.4 && x < leftmost + 0.5 * dx) {
            side += x;
            in_side++;
        }
        if (v->kind[i] != SLUICE_KIND_FLUID || x < 0.2 * width || x > 0.8 * width)
            continue;
        if (y < lowest + 0.5 * dx) {
            layer += y;
            in_layer++;
        }
        if (y > 1.5 * dx)
            continue;
        sum_p += p[i];
        sum_ref += RHO0 * G * (H - y);
        bottom++;
    }
    /* the lowest layer holds 0.6 width / dx particles in the window */
    ck_assert_int_ge(bottom, (int)(0.5 * 0.6 * width / dx));
    r.pressure_error = (sum_p - sum_ref) / sum_ref;
    r.bottom_layer = layer / in_layer;
    r.side_column = side / in_side;
    r.steps_per_second = (double)r.steps / r.seconds;
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    fprintf(stderr,
            "still water %s, dx = %g m, %g s: bottom pressure %+.2f %% from rho g (H - y); "
            "fluid behind a wall: %d; smallest fluid-wall distance %.3f dx, lowest layer at "
            "%.3f dx, column next to the side wall at %.3f dx; kinetic energy %.3g J at the "
            "end (rms speed %.2e sqrt(g H)), %.3g J mean over the first second; %lld steps, "
            "%.1f s, %.0f steps/s\n",
            walls, dx, t_end, 100 * r.pressure_error, r.crossed, r.gap / dx, r.bottom_layer / dx,
            r.side_column / dx, r.energy_end, r.residual_speed / sqrt(G * H), r.energy_first,
            (long long)r.steps, r.seconds, r.steps_per_second);
    return r;
}

/* The still tank after TANK_END: no fluid behind a wall; the bottom pressure
 * within 3 % of rho g (H - y) (issue 4); the kinetic energy decayed: below
 * its mean over the first second, and the fluid at rest, its rms speed below
 * 1e-3 sqrt(g H) (the speed of the sloshing the start excites; the dynamic
 * pressure of that residual flow is 5e-7 rho g H, nothing against the 3 %).
 * tests/scenes/test_scenes.c asks for a tenfold decay from the first second, which
 * dbc's initial drop (0.17 J here) gives; mirror walls start in equilibrium
 * with the hydrostatic fluid (0.006 J in the first second), so their
 * residual, not the decay ratio, is the measure of rest. */
static void check_still_tank(const char *walls, tank_result *out)
{
    tank_result r = still_tank(walls, tank_dx(), TANK_END);
    ck_assert_msg(r.crossed == 0, "%s: %d fluid particles behind a wall", walls, r.crossed);
    ck_assert_msg(fabs(r.pressure_error) <= 0.03, "%s: bottom pressure off by %.2f %%", walls,
                  100 * r.pressure_error);
    ck_assert_msg(r.energy_end < r.energy_first, "%s: kinetic energy did not decay (%g J vs %g J)",
                  walls, r.energy_end, r.energy_first);
    ck_assert_msg(r.residual_speed < 1e-3 * sqrt(G * TANK_DEPTH),
                  "%s: residual rms speed %g m/s after %g s", walls, r.residual_speed, TANK_END);
    if (out)
        *out = r;
}

/* Where the fluid settles next to a wall whose particles mirror it. By the
 * mirror symmetry the wall acts on the fluid next to it as the fluid
 * continued across the wall line would, so the initial lattice, whose first
 * layer is dx/2 from the wall line, is the equilibrium. What can move the
 * settled layer: the hydrostatic compression of the lattice (g H / c0^2 =
 * 1 % at the bed, 0.005 dx on the half spacing) and the sloshing left after
 * 10 s (rms speed below 1e-3 sqrt(g H) = 2.2 mm/s, amplitude below
 * 2.2 mm/s over the sloshing frequency, about 6 rad/s: 0.4 mm = 0.007 dx).
 * LAYER_TOLERANCE allows twice their sum. */
#define LAYER_TOLERANCE 0.025

static void check_layers(const char *walls, const tank_result *r)
{
    ck_assert_msg(fabs(r->bottom_layer / tank_dx() - 0.5) <= LAYER_TOLERANCE,
                  "%s: the lowest layer settled at %.3f dx", walls, r->bottom_layer / tank_dx());
    ck_assert_msg(fabs(r->side_column / tank_dx() - 0.5) <= LAYER_TOLERANCE,
                  "%s: the column next to the side wall settled at %.3f dx", walls,
                  r->side_column / tank_dx());
}

START_TEST(still_water_ghost_no_slip)
{
    const char *walls = "ghost_particles: {slip: no_slip}";
    tank_result r;
    check_still_tank(walls, &r);
    check_layers(walls, &r);
}
END_TEST

START_TEST(still_water_ghost_free_slip)
{
    const char *walls = "ghost_particles: {slip: free_slip}";
    tank_result r;
    check_still_tank(walls, &r);
    check_layers(walls, &r);
}
END_TEST

/* English et al. (2021): mDBC removes the gap DBC leaves between fluid and
 * wall. What that claim implies here: the fluid next to mdbc walls settles at
 * the mirror-symmetric distance dx/2 (check_layers), and closer to it than
 * next to dbc walls, at the bed and at the side wall. Both tanks must pass
 * the still-water checks. */
START_TEST(still_water_mdbc_against_dbc)
{
    tank_result m, d;
    check_still_tank("mdbc: {}", &m);
    check_layers("mdbc: {}", &m);
    check_still_tank("dbc: {}", &d);
    const double bm = fabs(m.bottom_layer / tank_dx() - 0.5),
                 bd = fabs(d.bottom_layer / tank_dx() - 0.5);
    const double sm = fabs(m.side_column / tank_dx() - 0.5),
                 sd = fabs(d.side_column / tank_dx() - 0.5);
    fprintf(stderr,
            "settled distance from the wall line minus dx/2: bed mdbc %+.3f dx, dbc %+.3f dx; "
            "side wall mdbc %+.3f dx, dbc %+.3f dx\n",
            m.bottom_layer / tank_dx() - 0.5, d.bottom_layer / tank_dx() - 0.5,
            m.side_column / tank_dx() - 0.5, d.side_column / tank_dx() - 0.5);
    ck_assert_msg(bm < bd, "bed: mdbc %.3f dx from dx/2, dbc %.3f dx", bm, bd);
    ck_assert_msg(sm < sd, "side wall: mdbc %.3f dx from dx/2, dbc %.3f dx", sm, sd);
}
END_TEST

/* ---------------------------------------------------------- dam break -- */

static void check_dam_break(const char *walls)
{
    char *yaml = scene_with_walls("dam_break_2d.yaml", walls);
    /* the study hooks reproduce the longer runs of the report */
    const char *dx_text = getenv("SLUICE_DAM_BREAK_DX"), *end_text = getenv("SLUICE_DAM_BREAK_END");
    const double dx = dx_text ? atof(dx_text) : 0.1, t_end = end_text ? atof(end_text) : 0.85;
    char sets[5][96];
    snprintf(sets[0], sizeof sets[0], "particles.spacing=%.17g", dx);
    snprintf(sets[1], sizeof sets[1], "time.end=%.17g", t_end);
    snprintf(sets[2], sizeof sets[2], "plugins.front_gauge.interval=%.17g", 0.05);
    snprintf(sets[3], sizeof sets[3], "domain.min=[%.17g, %.17g]", -4 * dx, -4 * dx);
    snprintf(sets[4], sizeof sets[4], "domain.max=[%.17g, 8]", 4 + 4 * dx);
    const char *set_list[5] = {sets[0], sets[1], sets[2], sets[3], sets[4]};
    sluice_sim *sim = test_load("dam-break", yaml, set_list, 5);
    free(yaml);
    const sluice_index initial = sluice_sim_view(sim)->count;
    int worst = 0;
    double front = 0, impact = -1, deepest = INFINITY, start = sluice_wall_clock();
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    while (sluice_sim_time(sim) < t_end - 1e-9) {
        int status = sluice_sim_step(sim);
        ck_assert_msg(status == SLUICE_RUN_COMPLETE, "dam break (%s) stopped: %s", walls,
                      sluice_sim_failure(sim));
        if (sluice_sim_steps(sim) % 5)
            continue;
        double smallest;
        int crossed = crossings(sim, &smallest);
        if (crossed > worst)
            worst = crossed;
        if (smallest < deepest)
            deepest = smallest;
        const sluice_view *v = sluice_sim_view(sim);
        for (sluice_index i = 0; i < v->count; i++)
            if (v->kind[i] == SLUICE_KIND_FLUID && v->position[0][i] > front)
                front = v->position[0][i];
        if (impact < 0 && front > 4.0 - 1.5 * dx)
            impact = sluice_sim_time(sim);
    }
    double seconds = sluice_wall_clock() - start;
    const sluice_view *v = sluice_sim_view(sim);
    fprintf(stderr,
            "dam break %s, dx = %g m, to %g s: front reached x = %.2f m (far wall at 4 m) at "
            "t = %.3f s; fluid behind a wall: %d at worst; smallest fluid-wall distance "
            "%+.4f dx; particles %u -> %u; %lld steps, %.1f s\n",
            walls, dx, t_end, front, impact, worst, deepest / dx, (unsigned)initial,
            (unsigned)v->count, (long long)sluice_sim_steps(sim), seconds);
    /* the water reached the far wall (the front is within one particle
     * spacing plus the wall gap of x = 4 m) */
    ck_assert_msg(front > 4.0 - 1.5 * dx, "%s: the front (%g m) did not reach the far wall", walls,
                  front);
    ck_assert_msg(worst == 0, "%s: %d fluid particles crossed a wall", walls, worst);
    ck_assert_uint_eq(v->count, initial);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
}

/* The schemes' default walls (ceil(2h/dx) = 3 layers, 3 dx thick: a full
 * kernel support) and walls 2 dx thick (2 layers, a truncated support), the
 * thinnest a particle wall can be at the impact that still holds (a wall
 * thinner than one spacing has no particle layer; the force schemes of
 * test_wall_forces take 0.5 dx plates). */
static const char *const dam_walls[] = {
    "ghost_particles: {slip: no_slip}",
    "ghost_particles: {slip: free_slip}",
    "mdbc: {}",
    "dbc: {layers: 2}",
    "mdbc: {layers: 2}",
    "ghost_particles: {slip: no_slip, layers: 2}",
    "ghost_particles: {slip: free_slip, layers: 2}",
};

START_TEST(dam_break_impact)
{
    check_dam_break(dam_walls[_i]);
}
END_TEST

/* --------------------------------------------------------- dbc motion -- */

/* A tank [0, 2] x [0, 1] with a vertical paddle at x = 0.5 (fluid on its
 * right) named `paddle`, moving by the law in `motion`. */
static void check_motion(const char *motion, const double U[2], const double A[2], double f,
                         double phase, double start)
{
    char yaml[4096];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
             "time: {end: 0.3}\n"
             "domain: {min: [-0.3, -0.3], max: [2.3, 1.5]}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0.5, 0], max: [1.5, 0.4]}]\n"
             "  walls:\n"
             "    - {shape: tank, min: [0, 0], max: [2, 1], name: tank}\n"
             "    - {shape: polyline, points: [[0.5, 0.8], [0.5, 0.0]], name: paddle}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "  pressure_gradient: {}\n"
             "  artificial_viscosity: {alpha: 0.1}\n"
             "  gravity: {}\n"
             "  dbc: {moving_wall: paddle, %s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             motion);
    sluice_sim *sim = test_load("dbc-motion", yaml, NULL, 0);
    const double dx = 0.05;
    /* rest positions by id; the paddle's particles are the wall particles
     * behind the paddle line: x in (0.5 - 3 dx, 0.5), y > 0 */
    const sluice_view *v = sluice_sim_view(sim);
    sluice_id max_id = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->id[i] > max_id)
            max_id = v->id[i];
    double *rest = calloc(2 * (size_t)(max_id + 1), sizeof *rest);
    uint8_t *paddle = calloc((size_t)max_id + 1, 1);
    ck_assert(rest && paddle);
    int moving = 0;
    sluice_index fluid = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        rest[2 * v->id[i]] = v->position[0][i];
        rest[2 * v->id[i] + 1] = v->position[1][i];
        fluid += v->kind[i] == SLUICE_KIND_FLUID;
        if (v->kind[i] == SLUICE_KIND_WALL && v->position[0][i] < 0.5 &&
            v->position[0][i] > 0.5 - 3 * dx && v->position[1][i] > 0) {
            paddle[v->id[i]] = 1;
            moving++;
        }
    }
    /* 3 layers (h = 1.5 dx) of 16 rows along the 0.8 m paddle */
    ck_assert_int_eq(moving, 3 * 16);
    const double omega = 2 * M_PI * f;
    double worst_x = 0, worst_v = 0, worst_fixed = 0;
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    for (int step = 0; step < 400 && sluice_sim_time(sim) < 0.3 - 1e-9; step++) {
        ck_assert_msg(sluice_sim_step(sim) == SLUICE_RUN_COMPLETE, "paddle run stopped: %s",
                      sluice_sim_failure(sim));
        v = sluice_sim_view(sim);
        const double t = sluice_sim_time(sim), tau = t - start;
        const sluice_real *u = test_column(sim, "velocity", 0);
        const sluice_real *w = test_column(sim, "velocity", 1);
        double disp[2] = {0, 0}, vel[2] = {0, 0};
        if (tau >= 0)
            for (int d = 0; d < 2; d++) {
                disp[d] = U[d] * tau + A[d] * (sin(omega * tau + phase) - sin(phase));
                vel[d] = U[d] + A[d] * omega * cos(omega * tau + phase);
            }
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_WALL)
                continue;
            const sluice_id id = v->id[i];
            const double x = v->position[0][i], y = v->position[1][i];
            if (paddle[id]) {
                worst_x = fmax(worst_x, fmax(fabs(x - (rest[2 * id] + disp[0])),
                                             fabs(y - (rest[2 * id + 1] + disp[1]))));
                worst_v = fmax(worst_v, fmax(fabs(u[i] - vel[0]), fabs(w[i] - vel[1])));
            } else {
                worst_fixed =
                    fmax(worst_fixed, fmax(fabs(x - rest[2 * id]), fabs(y - rest[2 * id + 1])));
                worst_fixed = fmax(worst_fixed, fmax(fabs(u[i]), fabs(w[i])));
            }
        }
    }
    v = sluice_sim_view(sim);
    sluice_index fluid_end = 0;
    for (sluice_index i = 0; i < v->count; i++)
        fluid_end += v->kind[i] == SLUICE_KIND_FLUID;
    fprintf(stderr,
            "dbc moving wall {%s}: %d paddle particles over %lld steps to t = %.3f s: largest "
            "position error %.2e m, velocity error %.2e m/s; other walls moved by %.2e m\n",
            motion, moving, (long long)sluice_sim_steps(sim), sluice_sim_time(sim), worst_x,
            worst_v, worst_fixed);
    /* the same law evaluated in double precision: round-off only */
    ck_assert_msg(worst_x <= 1e-14, "paddle off its law by %g m", worst_x);
    ck_assert_msg(worst_v <= 1e-14, "paddle velocity off its law by %g m/s", worst_v);
    ck_assert_msg(worst_fixed == 0, "fixed walls moved (%g)", worst_fixed);
    ck_assert_uint_eq(fluid_end, fluid);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    free(rest);
    free(paddle);
    sluice_sim_free(sim);
}

START_TEST(dbc_piston_constant_speed)
{
    const double U[2] = {0.2, 0}, A[2] = {0, 0};
    check_motion("velocity: [0.2, 0]", U, A, 0, 0, 0);
}
END_TEST

START_TEST(dbc_paddle_oscillates)
{
    const double U[2] = {0, 0}, A[2] = {0.03, 0.01};
    /* the phase in degrees in the scene, 30 deg = pi/6 rad in the law */
    check_motion("amplitude: [0.03, 0.01], frequency: 2, phase_deg: 30, start: 0.05", U, A, 2,
                 M_PI / 6, 0.05);
}
END_TEST

/* a motion law without a wall to move, and a name no wall has, are refused */
START_TEST(dbc_motion_errors)
{
    /* ... and the key of the phase in radians, renamed phase_deg with its unit: the message
     * names the new key */
    const char *bad[3] = {"velocity: [0.2, 0]", "moving_wall: gate", "phase: 0.3"};
    const char *named_in_message[3] = {"moving_wall", "gate", "did you mean 'phase_deg'?"};
    for (int k = 0; k < 3; k++) {
        char yaml[2048];
        snprintf(yaml, sizeof yaml,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.05}\n"
                 "time: {end: 0.1}\n"
                 "domain: {min: [-0.3, -0.3], max: [1.3, 1.3]}\n"
                 "geometry:\n"
                 "  fluid: [{shape: box, min: [0, 0], max: [1, 0.4]}]\n"
                 "  walls: [{shape: tank, min: [0, 0], max: [1, 1], name: tank}]\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  tait: {speed_of_sound: 20}\n"
                 "  continuity: {}\n"
                 "  pressure_gradient: {}\n"
                 "  dbc: {%s}\n"
                 "  time_step: {}\n"
                 "  symplectic: {}\n",
                 bad[k]);
        char *dir = test_scratch("dbc-bad");
        char *path = test_write_file(dir, "scene.yaml", yaml);
        sluice_diag *diag = sluice_diag_create();
        sluice_load_options options = {0};
        sluice_sim *sim = sluice_sim_load(path, &options, diag);
        ck_assert_ptr_null(sim);
        int named = 0;
        for (size_t i = 0; i < sluice_diag_count(diag); i++) {
            fprintf(stderr, "refused as expected: %s\n", sluice_diag_message(diag, i));
            named |= strstr(sluice_diag_message(diag, i), named_in_message[k]) != NULL;
        }
        ck_assert_msg(named, "the message does not name the problem");
        sluice_diag_destroy(diag);
        free(path);
        free(dir);
    }
}
END_TEST

int main(void)
{
    Suite *s = suite_create("wall_particles");
    TCase *values = tcase_create("mirror values");
    tcase_add_test(values, ghost_mirror_values_no_slip);
    tcase_add_test(values, ghost_mirror_values_free_slip);
    tcase_add_test(values, ghost_mirror_values_tension);
    tcase_add_test(values, ghost_mirror_at_a_drop);
    tcase_add_test(values, continuity_wall_velocity_rest);
    tcase_add_test(values, rest_values_without_fluid);
    tcase_add_test(values, mixed_schemes);
    tcase_add_test(values, mirror_values_3d);
    tcase_add_test(values, mdbc_extrapolates_linear_density);
    suite_add_tcase(s, values);
    TCase *motion = tcase_create("dbc motion");
    tcase_add_test(motion, dbc_piston_constant_speed);
    tcase_add_test(motion, dbc_paddle_oscillates);
    tcase_add_test(motion, dbc_motion_errors);
    suite_add_tcase(s, motion);
    TCase *tank = tcase_create("still water");
    tcase_set_tags(tank, "validation"); /* long: release pass only */
    tcase_set_timeout(tank, 300);
    tcase_add_test(tank, still_water_ghost_no_slip);
    tcase_add_test(tank, still_water_ghost_free_slip);
    tcase_add_test(tank, still_water_mdbc_against_dbc);
    suite_add_tcase(s, tank);
    TCase *dam = tcase_create("dam break");
    tcase_set_timeout(dam, 300);
    tcase_add_loop_test(dam, dam_break_impact, 0, (int)(sizeof dam_walls / sizeof *dam_walls));
    suite_add_tcase(s, dam);
    return test_run_suite(s);
}
