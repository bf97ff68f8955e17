/* The log-law wall function (plugins/walls/wall_friction.c): a layer of
 * water sliding at U over a floor (periodic in x, no other force):
 *  - every particle closer to the wall than one spacing is decelerated by
 *    u*^2 / dx along its tangential velocity, with u* solving the smooth log
 *    law (or, in its viscous sublayer, u* = (U nu / y)^(1/2)) or the rough
 *    law at its distance, to round-off; the particles further up feel
 *    nothing; the field friction_velocity holds u*;
 *  - a velocity normal to the wall is not resisted;
 *  - law rough without a roughness is refused. */
#include <math.h>

#include "sim_util.h"

static sluice_sim *sliding_layer(const char *friction, double U, double V)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "particles: {spacing: 0.01, smoothing_length_ratio: 1.5}\n"
             "time: {end: 1}\n"
             "domain: {min: [0, -0.1], max: [0.5, 0.3], periodic: x}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [0.5, 0.1]}]\n"
             "  walls: [{shape: polyline, points: [[0, 0], [0.5, 0]]}]\n"
             "initial: {density: rest}\n"
             "plugins:\n"
             "  wendland_c2: {}\n"
             "  tait: {speed_of_sound: 20}\n"
             "  continuity: {}\n"
             "  dbc: {}\n"
             "  wall_friction: {%s}\n"
             "  time_step: {}\n"
             "  symplectic: {}\n",
             friction);
    sluice_sim *sim = test_load("wall-friction", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            test_column(sim, "velocity", 0)[i] = (sluice_real)U;
            test_column(sim, "velocity", 1)[i] = (sluice_real)V;
        }
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    return sim;
}

/* residual of the law at (u*, y) for the speed U, relative */
static double law_residual(int rough, double us, double U, double y, double ks, double nu)
{
    const double kappa = 0.41;
    if (rough)
        return fabs(us - kappa * U / fmax(log(30 * y / ks), 1.0)) / us;
    if (us * y / nu < 11.2) /* viscous sublayer */
        return fabs(us * us * y / nu - U) / U;
    return fabs(U / us - log(9.8 * y * us / nu) / kappa) / (U / us);
}

static void check_layer(int rough)
{
    const double U = 2.0, dx = 0.01, ks = 0.002, nu = 1e-6;
    sluice_sim *sim =
        sliding_layer(rough ? "law: rough, roughness: 0.002" : "law: smooth", U, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *ax = test_column(sim, "acceleration", 0);
    const sluice_real *ay = test_column(sim, "acceleration", 1);
    const sluice_real *ustar = test_column(sim, "friction_velocity", 0);
    double worst_law = 0, worst_a = 0, us_mean = 0;
    int layer = 0, above = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const double y = v->position[1][i];
        if (y < dx) {
            const double us = ustar[i];
            ck_assert_msg(us > 0, "no u* at y = %g", y);
            worst_law = fmax(worst_law, law_residual(rough, us, U, y, ks, nu));
            worst_a = fmax(worst_a, fabs(ax[i] + us * us / dx) / (us * us / dx));
            ck_assert(ay[i] == 0);
            us_mean += us;
            layer++;
        } else {
            ck_assert(ax[i] == 0 && ay[i] == 0 && ustar[i] == 0);
            above++;
        }
    }
    us_mean /= layer;
    fprintf(stderr,
            "wall_friction %s: %d particles in the wall layer (u* = %.4f m/s, tau_w / (rho U^2) = "
            "%.2e), %d above; log law solved to %.1e, acceleration -u*^2/dx to %.1e\n",
            rough ? "rough, k_s = 2 mm" : "smooth", layer, us_mean, us_mean * us_mean / (U * U),
            above, worst_law, worst_a);
    ck_assert_int_gt(layer, 40);
    ck_assert_msg(worst_law < 1e-9, "the law is solved to %g only", worst_law);
    ck_assert_msg(worst_a < 1e-12, "acceleration off by %g", worst_a);
    sluice_sim_free(sim);
}

START_TEST(smooth_layer) { check_layer(0); }
END_TEST
START_TEST(rough_layer) { check_layer(1); }
END_TEST

/* a flow towards the wall has no tangential part: no friction */
START_TEST(normal_flow)
{
    sluice_sim *sim = sliding_layer("law: smooth", 0, -0.5);
    const sluice_view *v = sluice_sim_view(sim);
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            ck_assert(test_column(sim, "acceleration", 0)[i] == 0);
            ck_assert(test_column(sim, "acceleration", 1)[i] == 0);
        }
    sluice_sim_free(sim);
}
END_TEST

START_TEST(rough_needs_roughness)
{
    test_load_refused("wall-friction-rough",
                      "dimensions: 2\n"
                      "particles: {spacing: 0.01}\n"
                      "time: {end: 1}\n"
                      "domain: {min: [0, -0.1], max: [0.5, 0.3], periodic: x}\n"
                      "geometry:\n"
                      "  fluid: [{shape: box, min: [0, 0], max: [0.5, 0.1]}]\n"
                      "  walls: [{shape: polyline, points: [[0, 0], [0.5, 0]]}]\n"
                      "plugins:\n"
                      "  wendland_c2: {}\n"
                      "  tait: {speed_of_sound: 20}\n"
                      "  continuity: {}\n"
                      "  dbc: {}\n"
                      "  wall_friction: {law: rough}\n"
                      "  time_step: {}\n"
                      "  symplectic: {}\n",
                      "roughness");
}
END_TEST

int main(void)
{
    Suite *s = suite_create("wall_friction");
    TCase *t = tcase_create("wall_friction");
    tcase_add_test(t, smooth_layer);
    tcase_add_test(t, rough_layer);
    tcase_add_test(t, normal_flow);
    tcase_add_test(t, rough_needs_roughness);
    suite_add_tcase(s, t);
    return test_run_suite(s);
}
