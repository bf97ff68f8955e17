/* Core services of the plugin ABI, through the fixture plugins in
 * tests/sdk/fixtures/api_probe.c and short_component_plugin.c:
 *  - prepare() runs at every evaluation after the neighbour update and
 *    before the passes;
 *  - api->evaluation->point_pass finds exactly the particles within the support of
 *    arbitrary points (brute force), of the kinds asked, across periodic
 *    sides, with the kernel values of the scene's kernel;
 *  - api->walls->wall_nearest returns the signed distance, nearest point and
 *    normal of the nearest wall;
 *  - a descriptor whose components are shorter than ABI 2.0's is refused. */
#include <math.h>

#include "api_probe.h"
#include "sim_util.h"
/* Internal: the engine's own state: instances, passes, the grid, fields (not in sim.h) */
#include "sim_internal.h"

static const char *fixture_dir(void)
{
    const char *d = getenv("SLUICE_FIXTURE_DIR");
    return d ? d : ".";
}

static sluice_instance *instance_named(sluice_sim *sim, const char *name)
{
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if (strcmp(sim->instances[k].name, name) == 0)
            return &sim->instances[k];
    ck_abort_msg("no instance '%s'", name);
    return NULL;
}

START_TEST(prepare_runs_before_the_passes)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "plugin_path: %s\n"
             "particles: {spacing: 0.1}\n"
             "time: {end: 1, max_step: 0.01}\n"
             "domain: {min: [0, 0], max: [1, 1]}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]}\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, prepare_probe: {}, prepare_reader: {}, symplectic: {}}\n",
             fixture_dir());
    sluice_sim *sim = test_load("prepare", yaml, NULL, 0);
    for (int e = 1; e <= 3; e++) {
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *prepared = test_column(sim, "prepared_value", 0);
        const sluice_real *reader = test_column(sim, "reader_value", 0);
        for (sluice_index i = 0; i < v->count; i++) {
            ck_assert_msg(prepared[i] == (sluice_real)e + v->position[0][i],
                          "evaluation %d: prepared %g", e, prepared[i]);
            ck_assert_msg(reader[i] == prepared[i], "evaluation %d: the pass read %g, not %g", e,
                          reader[i], prepared[i]);
        }
    }
    sluice_sim_free(sim);
}
END_TEST

/* W of the scene's kernel at distance r. */
static double kernel_w(sluice_sim *sim, double r)
{
    const sluice_instance *k = &sim->instances[sim->kernel];
    sluice_real rr = (sluice_real)(r * r), distance = 0, w = 0, f = 0;
    k->component->kernel(k->state, 1, &rr, &distance, &w, &f);
    return (double)w;
}

static uint64_t rng = 5;
static double uniform(void)
{
    rng = rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

static void check_points(int periodic)
{
    /* fluid in a tank, particles jittered, a density field; points
     * anywhere, including outside the fluid, near walls and (periodic)
     * across the x sides */
    enum { POINTS = 40 };
    double pts[POINTS][2];
    for (int q = 0; q < POINTS; q++) {
        pts[q][0] = -0.05 + 1.1 * uniform();
        pts[q][1] = -0.05 + 0.7 * uniform();
    }
    pts[0][0] = 0.001; /* near a periodic side */
    pts[0][1] = 0.3;
    pts[1][0] = 0.999;
    pts[1][1] = 0.3;
    char list[4096];
    size_t used = 0;
    for (int q = 0; q < POINTS; q++)
        used += (size_t)snprintf(list + used, sizeof list - used, "%s[%.17g, %.17g]",
                                 q ? ", " : "", pts[q][0], pts[q][1]);
    for (int kinds = 1; kinds <= 3; kinds++) {
        char yaml[8192];
        snprintf(yaml, sizeof yaml,
                 "dimensions: 2\n"
                 "plugin_path: %s\n"
                 "particles: {spacing: 0.05, smoothing_length_ratio: 1.5}\n"
                 "time: {end: 1, max_step: 0.01}\n"
                 "domain: {min: [0, -0.2], max: [1, 1]%s}\n"
                 "geometry:\n"
                 "  fluid: [{shape: box, min: [0, 0], max: [1, 0.5]}]\n"
                 "  walls: [{shape: polyline, points: [[0, 0], [1, 0]]}]\n"
                 "initial: {density: rest}\n"
                 "plugins: {wendland_c2: {}, dbc: {}, point_probe: {points: [%s], kinds: %d}, "
                 "tait: {speed_of_sound: 10}, symplectic: {}}\n",
                 fixture_dir(), periodic ? ", periodic: x" : "", list, kinds);
        sluice_sim *sim = test_load("points", yaml, NULL, 0);
        const sluice_view *v = sluice_sim_view(sim);
        sluice_real *rho = test_column(sim, "density", 0);
        for (sluice_index i = 0; i < v->count; i++)
            rho[i] = (sluice_real)(1000 + 10 * v->position[0][i] + 5 * v->position[1][i] +
                                   uniform());
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        v = sluice_sim_view(sim);
        rho = test_column(sim, "density", 0);
        const sluice_real *m = test_column(sim, "mass", 0);
        const api_probe_state *s = instance_named(sim, "point_probe")->state;
        ck_assert_int_eq(s->count, POINTS);
        const double support = 2 * (double)sim->smoothing_length;
        int with_neighbours = 0, across = 0;
        for (int q = 0; q < POINTS; q++) {
            double sum = 0, weighted = 0;
            sluice_index n = 0;
            for (sluice_index j = 0; j < v->count; j++) {
                if (!((kinds >> v->kind[j]) & 1))
                    continue;
                double dx = pts[q][0] - v->position[0][j], dy = pts[q][1] - v->position[1][j];
                if (periodic)
                    dx -= nearbyint(dx);
                double r = sqrt(dx * dx + dy * dy);
                if (r >= support)
                    continue;
                n++;
                across += periodic && fabs(pts[q][0] - v->position[0][j]) > 0.5;
                double w = (double)m[j] / (double)rho[j] * kernel_w(sim, r);
                sum += w;
                weighted += w * (double)rho[j];
            }
            ck_assert_msg(s->neighbours[q] == n, "point %d (%g, %g), kinds %d: %u neighbours, "
                                                 "brute force %u",
                          q, pts[q][0], pts[q][1], kinds, s->neighbours[q], n);
            ck_assert_msg(fabs(s->shepard[q] - sum) <= 1e-12 * (1 + sum), "point %d: %g vs %g", q,
                          s->shepard[q], sum);
            if (sum > 0) {
                ck_assert_msg(fabs(s->density[q] - weighted / sum) <= 1e-9, "point %d: %g vs %g",
                              q, s->density[q], weighted / sum);
                with_neighbours++;
            }
        }
        /* most points lie in the fluid; walls are seen only near the bed */
        ck_assert_int_gt(with_neighbours, kinds & 1 ? POINTS / 2 : 3);
        if (periodic)
            ck_assert_int_gt(across, 0);
        fprintf(stderr, "point pass (%s, kinds %d): %d of %d points have neighbours, all equal "
                        "to brute force%s\n",
                periodic ? "periodic x" : "open", kinds, with_neighbours, POINTS,
                periodic ? ", some across the periodic side" : "");
        sluice_sim_free(sim);
    }
}

START_TEST(point_pass_matches_brute_force) { check_points(0); }
END_TEST
START_TEST(point_pass_periodic) { check_points(1); }
END_TEST

START_TEST(wall_nearest_in_a_tank)
{
    const double pts[][2] = {{0.5, 0.3}, {0.1, 0.05}, {0.03, 0.02}, {0.5, -0.1}, {1.1, 0.5}};
    char list[1024];
    size_t used = 0;
    for (size_t q = 0; q < sizeof pts / sizeof pts[0]; q++)
        used += (size_t)snprintf(list + used, sizeof list - used, "%s[%g, %g]", q ? ", " : "",
                                 pts[q][0], pts[q][1]);
    char yaml[4096];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "plugin_path: %s\n"
             "particles: {spacing: 0.05}\n"
             "time: {end: 1, max_step: 0.01}\n"
             "domain: {min: [-0.5, -0.5], max: [1.5, 1.5]}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]\n"
             "  walls: [{shape: tank, min: [0, 0], max: [1, 1]}]\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, dbc: {}, point_probe: {points: [%s]}, tait: "
             "{speed_of_sound: 10}, symplectic: {}}\n",
             fixture_dir(), list);
    sluice_sim *sim = test_load("nearest", yaml, NULL, 0);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const api_probe_state *s = instance_named(sim, "point_probe")->state;
    const sluice_wall_point *w = s->nearest;
    for (int q = 0; q < 5; q++)
        ck_assert_int_eq(s->nearest_status[q], SLUICE_OK);
    /* inside, nearest the floor */
    ck_assert(fabs(w[0].distance - 0.3) < 1e-12 && w[0].feature == 0);
    ck_assert(fabs(w[0].normal[0]) < 1e-12 && fabs(w[0].normal[1] - 1) < 1e-12);
    ck_assert(fabs(w[0].closest[0] - 0.5) < 1e-12 && fabs(w[0].closest[1]) < 1e-12);
    /* inside, nearest the floor at 0.05 (the left wall is at 0.1) */
    ck_assert(fabs(w[1].distance - 0.05) < 1e-12);
    /* near the concave corner: distance 0.02 to the floor */
    ck_assert(fabs(w[2].distance - 0.02) < 1e-12 && w[2].normal[1] > 0.99);
    /* behind the floor: negative, same normal */
    ck_assert(fabs(w[3].distance + 0.1) < 1e-12 && w[3].normal[1] > 0.99);
    /* behind the right wall, outside the tank: negative, normal -x */
    ck_assert_msg(fabs(w[4].distance + 0.1) < 1e-12 && w[4].normal[0] < -0.99,
                  "d = %g, n = (%g, %g)", w[4].distance, w[4].normal[0], w[4].normal[1]);
    sluice_sim_free(sim);
}
END_TEST

/* What each kind of component must provide, and when fields may be
 * declared (docs/plugin-abi.md): each broken component of
 * tests/sdk/fixtures/abi2_rules.c is refused with a message that says why. */
static void rules_scene(const char *tag, const char *plugins, const char *needle)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "plugin_path: %s\n"
             "particles: {spacing: 0.1}\n"
             "time: {end: 1, max_step: 0.01}\n"
             "domain: {min: [0, 0], max: [1, 1]}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]}\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, %s}\n",
             fixture_dir(), plugins);
    test_load_refused(tag, yaml, needle);
}

START_TEST(abi2_rules_refused)
{
    rules_scene("silent-eos", "silent_eos: {}, symplectic: {}",
                "did not publish the constant 'speed_of_sound'");
    rules_scene("late-rate", "continuity: {}, late_rate: {}, symplectic: {}",
                "declares field 'late_rate' after create()");
    rules_scene("busy-integrator", "busy_integrator: {}", "also has a particle callback");
    rules_scene("stray-neighbours", "stray_neighbours: {}, symplectic: {}",
                "declares neighbour kinds for wall targets, which it does not act on");
}
END_TEST

/* A descriptor whose components are shorter than ABI 2.0's (not made by
 * SLUICE_DEFINE_LIBRARY) is refused with the plugin's file named: the core
 * never reads a component past its end. */
START_TEST(plugin_with_short_components_refused)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "plugin_path: %s\n"
             "particles: {spacing: 0.1}\n"
             "time: {end: 1, max_step: 0.01}\n"
             "domain: {min: [0, 0], max: [1, 1]}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.5, 0.5]}]}\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, short_component_plugin: {}, symplectic: {}}\n",
             fixture_dir());
    test_load_refused("short-component", yaml, "component size");
}
END_TEST

/* Per-region and per-wall lattice origins: an upper reach whose bed lies
 * 0.032 m up (3.2 dx at dx = 0.01 m) is filled on its own lattice, rows at
 * 0.032 + (k + 1/2) dx, and its bed's dbc layers at 0.032 - (k + 1/2) dx,
 * while the lower region keeps the global lattice. */
START_TEST(region_and_wall_lattice_origin)
{
    const char *yaml = "dimensions: 2\n"
                       "particles: {spacing: 0.01, smoothing_length_ratio: 1.5}\n"
                       "time: {end: 0.01}\n"
                       "domain: {min: [-0.2, -0.2], max: [1.2, 0.5]}\n"
                       "geometry:\n"
                       "  fluid:\n"
                       "    - {shape: box, min: [0, 0.032], max: [0.5, 0.072], lattice_origin: [0, 0.032]}\n"
                       "    - {shape: box, min: [0.5, 0], max: [1.0, 0.05]}\n"
                       "  walls:\n"
                       "    - {shape: polyline, points: [[-0.1, 0.032], [0.5, 0.032]], name: upper,\n"
                       "       lattice_origin: [0, 0.032]}\n"
                       "    - {shape: polyline, points: [[0.5, 0], [1.1, 0]], name: lower}\n"
                       "plugins:\n"
                       "  wendland_c2: {}\n"
                       "  tait: {speed_of_sound: 10}\n"
                       "  continuity: {}\n"
                       "  pressure_gradient: {}\n"
                       "  gravity: {}\n"
                       "  dbc: {}\n"
                       "  time_step: {}\n"
                       "  symplectic: {}\n";
    sluice_sim *sim = test_load("lattice-origin", yaml, NULL, 0);
    const sluice_view *v = sluice_sim_view(sim);
    const double dx = 0.01;
    int upper_fluid = 0, lower_fluid = 0, upper_wall = 0;
    double worst = 0;
    for (sluice_index i = 0; i < v->count; i++) {
        const double x = v->position[0][i], y = v->position[1][i];
        double k;
        if (v->kind[i] == SLUICE_KIND_FLUID && x < 0.5) {
            k = (y - 0.032) / dx - 0.5; /* rows above the upper bed */
            upper_fluid++;
        } else if (v->kind[i] == SLUICE_KIND_FLUID) {
            k = y / dx - 0.5; /* the global lattice */
            lower_fluid++;
        } else if (y > 0.0) {
            k = (0.032 - y) / dx - 0.5; /* layers under the upper bed */
            upper_wall++;
        } else {
            k = -y / dx - 0.5;
        }
        worst = fmax(worst, fabs(k - nearbyint(k)));
        worst = fmax(worst, fabs(x / dx - 0.5 - nearbyint(x / dx - 0.5)));
    }
    fprintf(stderr, "lattice origins: %d upper fluid, %d lower fluid, %d upper-bed wall "
                    "particles; largest distance from their lattices %.2e dx\n",
            upper_fluid, lower_fluid, upper_wall, worst);
    ck_assert_int_eq(upper_fluid, 50 * 4);
    ck_assert_int_eq(lower_fluid, 50 * 5);
    ck_assert_int_gt(upper_wall, 0);
    ck_assert_msg(worst < 1e-9, "a particle is %g dx off its lattice", worst);
    sluice_sim_free(sim);
}
END_TEST

/* Pass index of each evaluation instance (-1: in no pass). */
static void pass_of_instances(sluice_sim *sim, int *pass_of)
{
    for (uint32_t v = 0; v < sim->instance_count; v++)
        pass_of[v] = -1;
    for (uint32_t p = 0; p < sim->pass_count; p++) {
        const sluice_pass *pass = &sim->passes[p];
        if (!pass->is_pair) {
            pass_of[pass->instance] = (int)p;
            continue;
        }
        for (uint32_t t = 0; t < pass->pair.term_count; t++)
            for (uint32_t v = 0; v < sim->instance_count; v++)
                if (sim->instances[v].state == pass->pair.terms[t].state &&
                    sim->instances[v].component == pass->pair.terms[t].component)
                    pass_of[v] = (int)p;
    }
}

/* The schedule as sluice check --schedule and run.json write it says what
 * the core runs: as many passes as it has, of the same kinds, and each
 * evaluation component named once, in its pass. */
static void check_written_schedule(const sluice_sim *sim, const int *pass_of, const char *scene)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    ck_assert_ptr_nonnull(f);
    sluice_sim_write_schedule(sim, f, 1);
    ck_assert_int_eq(fclose(f), 0);
    uint32_t particle = 0, pair = 0;
    for (const char *p = text; (p = strstr(p, "\"kind\": \"")); p++) {
        particle += strncmp(p + 9, "particle", 8) == 0;
        pair += strncmp(p + 9, "pair", 4) == 0;
    }
    uint32_t want_pair = 0;
    for (uint32_t p = 0; p < sim->pass_count; p++)
        want_pair += sim->passes[p].is_pair != 0;
    ck_assert_msg(pair == want_pair && particle + pair == sim->pass_count,
                  "%s: the written schedule has %u particle and %u pair passes, the core %u "
                  "passes (%u pair): %s", scene, particle, pair, sim->pass_count, want_pair, text);
    /* each component in its pass: the k-th {"kind" ...} object names it */
    for (uint32_t v = 0; v < sim->instance_count; v++) {
        if (pass_of[v] < 0)
            continue;
        const char *p = strstr(text, "\"passes\": [");
        ck_assert_ptr_nonnull(p);
        for (int k = 0; k <= pass_of[v]; k++)
            p = strstr(p + 1, "{\"kind\"");
        const char *end = strchr(p, '}');
        char quoted[256];
        snprintf(quoted, sizeof quoted, "\"%s\"", sim->instances[v].name);
        const char *at = strstr(p, quoted);
        ck_assert_msg(at && at < end, "%s: '%s' is not written in pass %d: %s", scene,
                      sim->instances[v].name, pass_of[v] + 1, text);
    }
    fprintf(stderr, "%s: schedule as written: %s\n", scene, text);
    free(text);
}

/* Loads a scene file and checks its evaluation schedule against the plugins'
 * declarations: every reader of a field runs in a later pass than each of the
 * field's writers and accumulators, and there are as few pair passes as the
 * longest chain of pair terms that feed each other (computed here from the
 * declarations, by dynamic programming over the writer -> reader graph). */
static void check_schedule(const char *scene, uint32_t expected_pair_passes)
{
    char path[4096];
    const char *root = getenv("SLUICE_SOURCE_DIR");
    snprintf(path, sizeof path, "%s/configs/%s", root ? root : "..", scene);
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {0};
    sluice_sim *sim = sluice_sim_load(path, &options, diag);
    ck_assert_msg(sim != NULL, "%s failed to load", path);
    sluice_diag_destroy(diag);
    const uint32_t n = sim->instance_count;
    int *pass_of = malloc(n * sizeof *pass_of);
    uint8_t *edge = calloc((size_t)n * n, 1);
    int *chain = malloc(n * sizeof *chain);
    ck_assert(pass_of && edge && chain);
    pass_of_instances(sim, pass_of);
    uint32_t pair_passes = 0;
    for (uint32_t p = 0; p < sim->pass_count; p++)
        pair_passes += sim->passes[p].is_pair != 0;
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        for (uint32_t a = 0; a < field->declarer_count; a++) {
            const sluice_declarer *w = &field->declarers[a];
            if (w->instance == SLUICE_CORE_INSTANCE || pass_of[w->instance] < 0 ||
                !(w->access & (SLUICE_WRITE | SLUICE_ACCUMULATE)))
                continue;
            for (uint32_t b = 0; b < field->declarer_count; b++) {
                const sluice_declarer *r = &field->declarers[b];
                if (r->instance == SLUICE_CORE_INSTANCE || r->instance == w->instance ||
                    pass_of[r->instance] < 0 || !(r->access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR)))
                    continue;
                ck_assert_msg(pass_of[w->instance] < pass_of[r->instance],
                              "%s: '%s' reads '%s' in pass %d, but '%s' writes it in pass %d",
                              scene, sim->instances[r->instance].name, field->name,
                              pass_of[r->instance], sim->instances[w->instance].name,
                              pass_of[w->instance]);
                edge[(size_t)w->instance * n + r->instance] = 1;
            }
        }
    }
    /* longest chain of pair terms ending at each instance (the edges are acyclic) */
    uint32_t longest = 0;
    for (uint32_t v = 0; v < n; v++)
        chain[v] = -1;
    for (uint32_t round = 0; round < n; round++)
        for (uint32_t v = 0; v < n; v++) {
            if (pass_of[v] < 0 || chain[v] >= 0)
                continue;
            int ready = 1, best = 0;
            for (uint32_t u = 0; u < n; u++)
                if (edge[(size_t)u * n + v]) {
                    if (chain[u] < 0)
                        ready = 0;
                    else if (chain[u] > best)
                        best = chain[u];
                }
            if (!ready)
                continue;
            chain[v] = best + (sim->instances[v].component->pair != NULL);
            if ((uint32_t)chain[v] > longest)
                longest = (uint32_t)chain[v];
        }
    fprintf(stderr, "%s: %u passes, %u of them pair passes; longest chain of pair terms %u:", scene,
            sim->pass_count, pair_passes, longest);
    for (uint32_t p = 0; p < sim->pass_count; p++) {
        fprintf(stderr, " [");
        for (uint32_t v = 0; v < n; v++)
            if (pass_of[v] == (int)p)
                fprintf(stderr, " %s", sim->instances[v].name);
        fprintf(stderr, " ]");
    }
    fprintf(stderr, "\n");
    ck_assert_uint_eq(longest, expected_pair_passes);
    ck_assert_uint_eq(pair_passes, longest);
    check_written_schedule(sim, pass_of, scene);
    free(pass_of);
    free(edge);
    free(chain);
    sluice_sim_free(sim);
}

/* The dam break's density and force terms share one neighbour traversal
 * (the dbc clamp, a particle term that writes density, once split them);
 * the abrupt drop's kernel correction -> velocity gradient -> mixing length
 * (a pair term: its Shepard sum damps the length at the free surface) -> turbulent stress chain needs
 * four. */
START_TEST(schedule_has_fewest_pair_passes)
{
    check_schedule("dam_break_2d.yaml", 1);
    check_schedule("abrupt_drop_T1.yaml", 4);
    check_schedule("hydraulic_jump_jonsson2016.yaml", 1);
}
END_TEST

/* api->evaluation->request_reach (ABI 1.6): the fixture reach_probe asks for every fluid
 * pair within twice the kernel support (a kernel of smoothing length 2h, as
 * the air's cohesion). Its counts, summed distances and x offsets must equal
 * brute force over all fluid pairs, at the start and after the particles
 * moved by up to 0.45 of the skin without a list rebuild (the cells it scans
 * must cover the motion); its batches carry no kernel values; the terms
 * within the support keep their single pass. Closed and periodic domains. */
static void check_reach(int periodic, int checkerboard)
{
    char yaml[2048];
    const double dx = 0.02, radius = 4 * 1.3 * dx; /* 2 x the support 2h, h = 1.3 dx */
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "plugin_path: %s\n"
             "particles: {spacing: %g, smoothing_length_ratio: 1.3}\n"
             "time: {end: 1, max_step: 1e-4}\n"
             "domain: {min: [0, -0.1], max: [0.6, 0.5]%s}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [%g, 0], max: [%g, 0.3]}]\n"
             "  walls: [{shape: polyline, points: [[0, 0], [0.6, 0]]}]\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, tait: {speed_of_sound: 10}, continuity: {}, "
             "pressure_gradient: {}, dbc: {}, reach_probe: {radius: %.17g, checkerboard: %s}, "
             "symplectic: {}}\n",
             fixture_dir(), dx, periodic ? ", periodic: x" : "", periodic ? 0.0 : 0.1,
             periodic ? 0.6 : 0.5, radius, checkerboard ? "true" : "false");
    sluice_sim *sim = test_load(periodic ? "reach-periodic" : "reach", yaml, NULL, 0);
    sluice_field group_field;
    ck_assert_int_eq(sluice_sim_field(sim, "reach_group", &group_field), SLUICE_OK);
    uint32_t pair_passes = 0, reach_passes = 0;
    for (uint32_t p = 0; p < sim->pass_count; p++)
        if (sim->passes[p].is_pair) {
            pair_passes++;
            reach_passes += sim->passes[p].pair.reach > 0;
        }
    ck_assert_uint_eq(pair_passes, 2);
    ck_assert_uint_eq(reach_passes, 1);
    const double skin = sim->grid.skin, length = 0.6;
    for (int round = 0; round < 2; round++) {
        const sluice_index rebuilds = (sluice_index)sim->grid.rebuilds;
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        if (round == 1)
            ck_assert_msg(sim->grid.rebuilds == rebuilds, "the list was rebuilt");
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *count = test_column(sim, "reach_count", 0);
        const sluice_real *distance = test_column(sim, "reach_distance", 0);
        const sluice_real *offset = test_column(sim, "reach_offset_x", 0);
        const sluice_real *null = test_column(sim, "reach_kernel_null", 0);
        const uint8_t *group = v->columns[group_field.column];
        double worst = 0, pairs = 0;
        int targets = 0, left_out = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_FLUID)
                continue;
            if (group[i] != 1) { /* left out of the pass: never written */
                ck_assert_msg(count[i] == 0, "particle %u of group 0 has %g pairs", (unsigned)i,
                              count[i]);
                left_out++;
                continue;
            }
            double n = 0, r = 0, x = 0;
            for (sluice_index j = 0; j < v->count; j++) {
                if (j == i || v->kind[j] != SLUICE_KIND_FLUID || group[j] != 1)
                    continue;
                double ex = v->position[0][i] - v->position[0][j];
                double ey = v->position[1][i] - v->position[1][j];
                if (periodic)
                    ex -= length * nearbyint(ex / length);
                double e = sqrt(ex * ex + ey * ey);
                if (e < radius) {
                    n += 1;
                    r += e;
                    x += ex;
                }
            }
            ck_assert_msg(count[i] == n, "round %d, particle %u: %g pairs, brute force %g", round,
                          (unsigned)i, count[i], n);
            worst = fmax(worst, fabs(distance[i] - r) + fabs(offset[i] - x));
            ck_assert(null[i] == 1);
            pairs += n;
            targets++;
        }
        fprintf(stderr, "reach %g m (%s%s, round %d): %d targets (%d left out), %.0f pairs (%.1f "
                        "each) as brute force; largest difference of the summed distances and "
                        "offsets %.2e m\n",
                radius, periodic ? "periodic" : "closed", checkerboard ? ", checkerboard" : "",
                round, targets, left_out, pairs, pairs / targets, worst);
        if (checkerboard)
            ck_assert_msg(left_out > targets / 2 && targets > left_out / 2,
                          "the checkerboard should split the fluid about evenly: %d and %d",
                          targets, left_out);
        ck_assert_msg(worst < 1e-12, "summed distances and offsets differ by %g m", worst);
        /* move every fluid particle by up to 0.45 skin (no rebuild: < skin / 2) */
        sluice_real *px = (sluice_real *)v->position[0], *py = (sluice_real *)v->position[1];
        for (sluice_index i = 0; i < v->count; i++)
            if (v->kind[i] == SLUICE_KIND_FLUID) {
                double a = 2 * M_PI * uniform(), m = 0.45 * skin * uniform();
                px[i] += (sluice_real)(m * cos(a));
                py[i] += (sluice_real)(m * sin(a));
                if (periodic)
                    px[i] -= (sluice_real)(length * floor(px[i] / length));
            }
    }
    sluice_sim_free(sim);
}

START_TEST(reach_matches_brute_force) { check_reach(0, 0); }
END_TEST

START_TEST(reach_matches_brute_force_periodic) { check_reach(1, 0); }
END_TEST

/* api->evaluation->restrict_reach (ABI 1.7): the fixture restricted to a checkerboard
 * of particles (reach_group = 1) gets exactly the pairs among them, and
 * the others are never targets. */
START_TEST(restricted_reach_matches_brute_force) { check_reach(0, 1); }
END_TEST

START_TEST(restricted_reach_matches_brute_force_periodic) { check_reach(1, 1); }
END_TEST

/* The same in 3D (closed, then periodic in x), restricted to the
 * checkerboard (columns of cells in x and y): every count and summed
 * distance of the fluid's particles against brute force, before and after
 * a motion of 0.45 skin without a list rebuild. */
static void check_reach_3d(int periodic)
{
    char yaml[2048];
    const double dx = 0.04, radius = 4 * 1.3 * dx, length = 0.64;
    snprintf(yaml, sizeof yaml,
             "dimensions: 3\n"
             "plugin_path: %s\n"
             "particles: {spacing: %g, smoothing_length_ratio: 1.3}\n"
             "time: {end: 1, max_step: 1e-4}\n"
             "domain: {min: [0, 0, 0], max: [%g, 0.48, 0.48]%s}\n"
             "geometry:\n"
             "  fluid: [{shape: box, min: [0, 0.04, 0.04], max: [%g, 0.44, 0.44]}]\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, tait: {speed_of_sound: 10}, continuity: {}, "
             "pressure_gradient: {}, reach_probe: {radius: %.17g, checkerboard: true}, "
             "symplectic: {}}\n",
             fixture_dir(), dx, length, periodic ? ", periodic: x" : "",
             periodic ? length : 0.6, radius);
    sluice_sim *sim = test_load(periodic ? "reach-3d-periodic" : "reach-3d", yaml, NULL, 0);
    sluice_field group_field;
    ck_assert_int_eq(sluice_sim_field(sim, "reach_group", &group_field), SLUICE_OK);
    const double skin = sim->grid.skin;
    for (int round = 0; round < 2; round++) {
        const uint64_t rebuilds = sim->grid.rebuilds;
        ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
        if (round == 1)
            ck_assert_msg(sim->grid.rebuilds == rebuilds, "the list was rebuilt");
        const sluice_view *v = sluice_sim_view(sim);
        const sluice_real *count = test_column(sim, "reach_count", 0);
        const sluice_real *distance = test_column(sim, "reach_distance", 0);
        const uint8_t *group = v->columns[group_field.column];
        double worst = 0, pairs = 0;
        int targets = 0;
        for (sluice_index i = 0; i < v->count; i++) {
            if (v->kind[i] != SLUICE_KIND_FLUID || group[i] != 1)
                continue;
            double n = 0, r = 0;
            for (sluice_index j = 0; j < v->count; j++) {
                if (j == i || v->kind[j] != SLUICE_KIND_FLUID || group[j] != 1)
                    continue;
                double e[3];
                for (int d = 0; d < 3; d++)
                    e[d] = v->position[d][i] - v->position[d][j];
                if (periodic)
                    e[0] -= length * nearbyint(e[0] / length);
                const double s = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
                if (s < radius) {
                    n += 1;
                    r += s;
                }
            }
            if (count[i] != n)
                ck_abort_msg("3D round %d, particle %u: %g pairs, brute force %g", round,
                             (unsigned)i, count[i], n);
            worst = fmax(worst, fabs(distance[i] - r));
            pairs += n;
            targets++;
        }
        fprintf(stderr, "reach 3D (%s, round %d): %d targets, %.0f pairs as brute force; summed "
                        "distances within %.2e m\n",
                periodic ? "periodic" : "closed", round, targets, pairs, worst);
        ck_assert_int_gt(targets, 100);
        ck_assert_msg(worst < 1e-11, "summed distances differ by %g m", worst);
        sluice_real *p[3] = {(sluice_real *)v->position[0], (sluice_real *)v->position[1],
                             (sluice_real *)v->position[2]};
        for (sluice_index i = 0; i < v->count; i++) {
            double a = 2 * M_PI * uniform(), b = acos(2 * uniform() - 1), m = 0.45 * skin * uniform();
            p[0][i] += (sluice_real)(m * sin(b) * cos(a));
            p[1][i] += (sluice_real)(m * sin(b) * sin(a));
            p[2][i] += (sluice_real)(m * cos(b));
            if (periodic)
                p[0][i] -= (sluice_real)(length * floor(p[0][i] / length));
        }
    }
    sluice_sim_free(sim);
}

START_TEST(restricted_reach_matches_brute_force_3d) { check_reach_3d(0); }
END_TEST

START_TEST(restricted_reach_matches_brute_force_3d_periodic) { check_reach_3d(1); }
END_TEST

/* A reach longer than half a periodic side (plus a cell) is refused at load,
 * naming the plugin. */
START_TEST(reach_longer_than_periodic_side_refused)
{
    char yaml[2048];
    snprintf(yaml, sizeof yaml,
             "dimensions: 2\n"
             "plugin_path: %s\n"
             "particles: {spacing: 0.02, smoothing_length_ratio: 1.3}\n"
             "time: {end: 1, max_step: 1e-4}\n"
             "domain: {min: [0, -0.1], max: [0.3, 0.5], periodic: x}\n"
             "geometry: {fluid: [{shape: box, min: [0, 0], max: [0.3, 0.3]}]}\n"
             "initial: {density: rest}\n"
             "plugins: {wendland_c2: {}, tait: {speed_of_sound: 10}, reach_probe: {radius: 0.2}, "
             "symplectic: {}}\n",
             fixture_dir());
    test_load_refused("reach-refused", yaml,
                      "plugin 'reach_probe' reaches 0.2 m, more than half the length of a "
                      "periodic side");
}
END_TEST

/* --------------------------------------------------- the tables' index -- */

/* The instance that writes `file`, or NULL. */
static const sluice_table *table_of(const sluice_sim *sim, const char *file)
{
    for (size_t t = 0; t < sim->table_count; t++)
        if (strcmp(sim->tables[t]->name, file) == 0)
            return sim->tables[t];
    return NULL;
}

/* Every column of every table has a unit and a description; returns the
 * number of tables and sets bit k of *components for expected[k] when a
 * table of that component is there. */
static size_t check_described(const sluice_sim *sim, const char *const *expected, size_t count,
                              uint32_t *components)
{
    for (size_t t = 0; t < sim->table_count; t++) {
        const sluice_table *table = sim->tables[t];
        const char *component = sim->instances[table->instance].component->name;
        for (size_t k = 0; k < count; k++)
            if (strcmp(component, expected[k]) == 0)
                *components |= 1u << k;
        ck_assert_uint_gt(table->column_count, 1);
        ck_assert_str_eq(table->columns[0].name, "time");
        for (uint32_t c = 0; c < table->column_count; c++) {
            const sluice_table_column_info *info = &table->columns[c];
            ck_assert_msg(info->unit && *info->unit && info->description && *info->description,
                          "%s (%s): column %u '%s' is not described", table->name, component, c,
                          info->name);
        }
        ck_assert_str_eq(table->columns[0].unit, "s");
    }
    return sim->table_count;
}

/* The hydraulic jump scene's gauges (free surface, sections with forces,
 * 400 velocity points, 21 floor pressure sensors with a filter, the wall
 * monitor, inlet and outlet) with an energy gauge, a front gauge, the force
 * and moment on the walls and a point gauge of pressure added, and a
 * two-phase tank with an inlet, the air vent and unresolved bubbles: every
 * table of every table writer in plugins/ describes each column (ABI 2.2),
 * gauge columns are at their scene positions, and the run's tables.json
 * holds them, with no column left undescribed. */
START_TEST(every_table_described)
{
    static const char *const expected[] = {
        "free_surface_gauge", "section_gauge", "point_gauge", "wall_pressure", "wall_monitor",
        "inlet",          "outlet",        "energy_gauge", "front_gauge",   "wall_force",
        "air_vent",       "unresolved_bubbles"};
    uint32_t found = 0;
    char *path = test_config("hydraulic_jump_jonsson2016.yaml");
    char *config = test_read_file(path);
    ck_assert_ptr_nonnull(config);
    free(path);
    char *yaml = NULL;
    /* the plugins are the scene's last section */
    ck_assert_int_ge(asprintf(&yaml,
                              "%s"
                              "  energy_gauge: {interval: 0.1}\n"
                              "  front_gauge: {interval: 0.1}\n"
                              "  wall_force: {moments: true, moment_about: [1.1, 0], interval: 0.1}\n"
                              "  pressure_points: {plugin: point_gauge, points: [[0.5, 0.01], "
                              "[0.7, 0.015]], fields: \"velocity,pressure\", file: pressure.csv}\n",
                              config),
                     0);
    free(config);
    const char *sets[] = {"plugins.section_gauge.forces=true",
                          "plugins.wall_pressure.time_constant=0.01"};
    sluice_sim *sim = test_load("tables-jump", yaml, sets, 2);
    free(yaml);
    ck_assert_uint_eq(check_described(sim, expected, SLUICE_COUNT(expected), &found), 11);
    /* free-surface columns at their positions (the foot of each vertical
     * line: the domain's bottom), sections' momentum terms in N/m */
    const sluice_table *eta = table_of(sim, "free_surface.csv");
    ck_assert_ptr_nonnull(eta);
    ck_assert_uint_eq(eta->column_count, 44);
    ck_assert_str_eq(eta->columns[1].name, "eta_x0");
    ck_assert_str_eq(eta->columns[1].unit, "m");
    ck_assert(eta->columns[1].has_position && !eta->columns[0].has_position);
    ck_assert_double_eq_tol(eta->columns[1].position[0], 0.025, 1e-12);
    ck_assert_double_eq_tol(eta->columns[43].position[0], 1.075, 1e-12);
    ck_assert_double_eq_tol(eta->columns[43].position[1], -0.1, 1e-12);
    const sluice_table *sections = table_of(sim, "sections.csv");
    ck_assert_uint_eq(sections->column_count, 1 + 11 * 6);
    ck_assert_str_eq(sections->columns[5].name, "M_x0");
    ck_assert_str_eq(sections->columns[5].unit, "N m^-1");
    ck_assert_str_eq(sections->columns[4].unit, "1"); /* Fr_x0 */
    const sluice_table *pressure = table_of(sim, "pressure.csv");
    ck_assert_str_eq(pressure->columns[3].name, "p0_pressure");
    ck_assert_str_eq(pressure->columns[3].unit, "Pa");
    ck_assert_str_eq(pressure->columns[1].unit, "m s^-1");
    ck_assert_double_eq_tol(pressure->columns[6].position[0], 0.7, 1e-12);
    ck_assert_double_eq_tol(pressure->columns[6].position[1], 0.015, 1e-12);
    const sluice_table *floor = table_of(sim, "bed_pressure.csv");
    ck_assert_uint_eq(floor->column_count, 1 + 21 * 3);
    ck_assert_str_eq(floor->columns[2].name, "bed005_filtered_Pa");
    ck_assert_double_eq_tol(floor->columns[2].position[0], 0.05, 1e-9);
    const sluice_table *forces = table_of(sim, "wall_forces.csv");
    ck_assert_str_eq(forces->columns[1].unit, "N m^-1");
    ck_assert_str_eq(forces->columns[4].unit, "N m m^-1"); /* Mz per metre of width */
    /* the index, written when the run begins */
    char *dir = test_scratch("tables-jump-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    char *index_path = NULL;
    ck_assert_int_ge(asprintf(&index_path, "%s/tables.json", dir), 0);
    char *index = test_read_file(index_path);
    ck_assert_ptr_nonnull(index);
    ck_assert_ptr_null(strstr(index, "null"));
    ck_assert_ptr_nonnull(strstr(index, "\"format\": \"sluice-tables\""));
    ck_assert_ptr_nonnull(
        strstr(index, "{\"name\": \"eta_x0\", \"unit\": \"m\", \"description\": \"free-surface "
                      "elevation: the vertical coordinate of the surface on the vertical line "
                      "of samples through the position (its lowest sample)\", \"position\": "
                      "[0.025, -0.1]}"));
    ck_assert_ptr_nonnull(strstr(index, "\"file\": \"wall_forces.csv\",\n      \"instance\": "
                                        "\"wall_force\",\n      \"component\": \"wall_force\""));
    free(index);
    free(index_path);
    free(dir);
    sluice_sim_free(sim);

    yaml = NULL;
    ck_assert_int_ge(
        asprintf(&yaml,
                 "dimensions: 2\n"
                 "particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: 1000}\n"
                 "time: {end: 0.1}\n"
                 "domain: {min: [-0.1, -0.1], max: [0.7, 0.5]}\n"
                 "geometry:\n"
                 "  fluid:\n"
                 "    - {shape: box, min: [0, 0], max: [0.6, 0.2]}\n"
                 "    - {shape: box, min: [0, 0.2], max: [0.6, 0.4]}\n"
                 "  walls:\n"
                 "    - {shape: polyline, name: box, points: [[-0.1, 0], [0.6, 0], [0.6, 0.4], "
                 "[0, 0.4], [0, 0.1]]}\n"
                 "initial: {density: hydrostatic}\n"
                 "plugins:\n"
                 "  wendland_c2: {}\n"
                 "  two_phase: {speed_of_sound: 10, background_pressure: 100, "
                 "air_above: [[0, 0.2]]}\n"
                 "  continuity: {form: volume}\n"
                 "  pressure_gradient: {form: density_product}\n"
                 "  gravity: {}\n"
                 "  dbc: {}\n"
                 "  time_step: {courant: 0.25}\n"
                 "  symplectic: {}\n"
                 "  inlet: {position: 0, depth: 0.1, submergence: 0.1, discharge: 0.04}\n"
                 "  air_vent: {box_min: [0.4, 0.3], box_max: [0.6, 0.4]}\n"
                 "  unresolved_bubbles: {}\n"),
        0);
    sim = test_load("tables-two-phase", yaml, NULL, 0);
    free(yaml);
    ck_assert_uint_eq(check_described(sim, expected, SLUICE_COUNT(expected), &found), 3);
    const sluice_table *vent = table_of(sim, "air_vent.csv");
    ck_assert_str_eq(vent->columns[5].name, "air_pressure_near");
    ck_assert_str_eq(vent->columns[5].unit, "Pa");
    sluice_sim_free(sim);
    for (size_t k = 0; k < SLUICE_COUNT(expected); k++)
        ck_assert_msg(found & (1u << k), "no table of '%s' was checked", expected[k]);
}
END_TEST

/* api->output->table_column refuses a column beyond the header and an
 * empty unit, naming the table and the column; a described column is in
 * tables.json, an undescribed one (a plugin built before ABI 2.2) has null
 * unit and description. */
START_TEST(table_column_refusals)
{
    char yaml[1024];
    const char *scene = "dimensions: 2\n"
                        "plugin_path: %s\n"
                        "particles: {spacing: 0.1}\n"
                        "time: {end: 0.1, max_step: 0.01}\n"
                        "domain: {min: [0, 0], max: [1, 1]}\n"
                        "geometry: {fluid: [{shape: box, min: [0, 0], max: [1, 0.5]}]}\n"
                        "plugins: {wendland_c2: {}, tait: {speed_of_sound: 10}, "
                        "table_probe: {%s}, symplectic: {}}\n";
    snprintf(yaml, sizeof yaml, scene, fixture_dir(), "column: 3");
    test_load_refused("table-column-beyond", yaml,
                      "table 'table_probe.csv': column 3 described, and its header has 3 "
                      "columns (0 to 2)");
    snprintf(yaml, sizeof yaml, scene, fixture_dir(), "unit: ''");
    test_load_refused("table-column-unitless", yaml,
                      "table 'table_probe.csv': column 'a' needs a unit and a description");
    snprintf(yaml, sizeof yaml, scene, fixture_dir(), "column: 2, unit: m s^-1");
    sluice_sim *sim = test_load("table-column", yaml, NULL, 0);
    char *dir = test_scratch("table-column-run");
    ck_assert_int_eq(sluice_sim_begin(sim, dir), SLUICE_RUN_COMPLETE);
    char *path = NULL;
    ck_assert_int_ge(asprintf(&path, "%s/tables.json", dir), 0);
    char *index = test_read_file(path);
    ck_assert_ptr_nonnull(index);
    ck_assert_ptr_nonnull(strstr(index, "{\"name\": \"time\", \"unit\": null, "
                                        "\"description\": null},\n"
                                        "        {\"name\": \"a\", \"unit\": null, "
                                        "\"description\": null},\n"
                                        "        {\"name\": \"b\", \"unit\": \"m s^-1\", "
                                        "\"description\": \"a length\", \"position\": "
                                        "[0.5, 0.25]}"));
    ck_assert_ptr_nonnull(strstr(index, "\"component\": \"table_probe\",\n      "
                                        "\"library\": \"api_probe\""));
    free(index);
    free(path);
    free(dir);
    sluice_sim_free(sim);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("core_api");
    TCase *c = tcase_create("abi_1_3");
    tcase_add_test(c, prepare_runs_before_the_passes);
    tcase_add_test(c, point_pass_matches_brute_force);
    tcase_add_test(c, point_pass_periodic);
    tcase_add_test(c, wall_nearest_in_a_tank);
    tcase_add_test(c, plugin_with_short_components_refused);
    tcase_add_test(c, abi2_rules_refused);
    tcase_add_test(c, region_and_wall_lattice_origin);
    tcase_add_test(c, schedule_has_fewest_pair_passes);
    tcase_add_test(c, reach_matches_brute_force);
    tcase_add_test(c, reach_matches_brute_force_periodic);
    tcase_add_test(c, restricted_reach_matches_brute_force);
    tcase_add_test(c, restricted_reach_matches_brute_force_periodic);
    tcase_add_test(c, restricted_reach_matches_brute_force_3d);
    tcase_add_test(c, restricted_reach_matches_brute_force_3d_periodic);
    tcase_add_test(c, reach_longer_than_periodic_side_refused);
    suite_add_tcase(s, c);
    TCase *tables = tcase_create("table_index");
    tcase_set_timeout(tables, 300);
    tcase_add_test(tables, every_table_described);
    tcase_add_test(tables, table_column_refusals);
    suite_add_tcase(s, tables);
    return test_run_suite(s);
}
