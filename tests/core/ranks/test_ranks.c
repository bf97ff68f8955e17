/* A run across MPI ranks (docs/scaling.md), run by meson under mpiexec with
 * 1, 2 and 4 ranks: the 2D dam break split into slabs along x gives, after
 * 200 steps, the particles and fields of the same scene on one rank, by id,
 * to round-off, and after 1000 steps, when particles have crossed from one
 * rank to another (they keep their id and state: they are among those
 * compared), none lost or doubled.
 * Built only with -Dmpi=enabled. Check runs without fork (MPI). */
#include <hdf5.h>
#include <math.h>
#include <mpi.h>

#include "sim_util.h"
/* Internal: each rank's halo lists, particles and grid (not in sim.h) */
#include "sim_internal.h"


/* configs/dam_break_2d.yaml at dx = 0.04 m without its gauge and writer
 * (outputs across ranks come later) */
static const char *scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.04, smoothing_length_ratio: 1.5, rest_density: 1000}\n"
    "time: {end: 1.0}\n"
    "domain: {min: [-0.2, -0.2], max: [4.2, 8.0]}\n"
    "geometry:\n"
    "  fluid:\n"
    "    - {shape: box, min: [0, 0], max: [1.0, 2.0]}\n"
    "  walls:\n"
    "    - {shape: tank, min: [0, 0], max: [4.0, 3.0], name: tank}\n"
    "initial: {density: hydrostatic}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 62.6, gamma: 7}\n"
    "  continuity: {}\n"
    "  delta_sph: {delta: 0.1, form: fourtakas}\n"
    "  pressure_gradient: {}\n"
    "  artificial_viscosity: {alpha: 0.1}\n"
    "  gravity: {acceleration: [0, -9.81]}\n"
    "  dbc: {}\n"
    "  time_step: {courant: 0.2}\n"
    "  symplectic: {}\n";

static sluice_sim *load_text(const char *text, const MPI_Comm *comm, const char *needle)
{
    char *dir = test_scratch("ranks");
    char *path = test_write_file(dir, "scene.yaml", text);
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {.threads = 1, .communicator = comm};
    sluice_sim *sim = sluice_sim_load(path, &options, diag);
    int found = 0;
    for (size_t i = 0; i < sluice_diag_count(diag); i++) {
        if (!sim)
            fprintf(stderr, "%s\n", sluice_diag_message(diag, i));
        found |= needle && strstr(sluice_diag_message(diag, i), needle) != NULL;
    }
    if (needle)
        ck_assert_msg(!sim && found, "expected a refusal with '%s'", needle);
    sluice_diag_destroy(diag);
    free(path);
    free(dir);
    return sim;
}

/* the compared fields, 8 per particle: x, y, u, v, density, pressure, mass
 * and a field of the case's plugins (0 when it has none) */
#define VALUES 8
static const char *const names[VALUES] = {"x", "y", "u", "v", "density", "pressure", "mass",
                                          "-"};

static void values_of(sluice_sim *sim, const char *extra, sluice_index i, double *out)
{
    const sluice_view *v = sluice_sim_view(sim);
    out[0] = (double)v->position[0][i];
    out[1] = (double)v->position[1][i];
    out[2] = (double)test_column(sim, "velocity", 0)[i];
    out[3] = (double)test_column(sim, "velocity", 1)[i];
    out[4] = (double)test_column(sim, "density", 0)[i];
    out[5] = (double)test_column(sim, "pressure", 0)[i];
    out[6] = (double)test_column(sim, "mass", 0)[i];
    out[7] = extra ? (double)test_column(sim, extra, 0)[i] : 0.0;
}

/* An index by id, 0 .. top, every entry -1 (no particle yet). */
static long *id_index(unsigned long long top)
{
    long *where = malloc(((size_t)top + 1) * sizeof *where);
    ck_assert_ptr_nonnull(where);
    for (size_t k = 0; k <= (size_t)top; k++)
        where[k] = -1;
    return where;
}

/* The largest id of a view. */
static sluice_id top_id(const sluice_view *w)
{
    sluice_id top = 0;
    for (sluice_index i = 0; i < w->count; i++)
        top = w->id[i] > top ? w->id[i] : top;
    return top;
}

/* The third run moves the slab boundaries during the run to balance the
 * ranks' particle counts (reproducible, unlike a balance by measured time),
 * every 20 steps at 1 % imbalance: as the surge carries particles
 * downstream, the boundaries follow, and the particles still equal the
 * one-rank run's. */
#define balanced_ranks_text "ranks: {balance: count, every: 20, tolerance: 0.01}\n"

/* A two-phase dam break in a closed 1.6 m x 0.4 m tank (dx = 0.02 m): water
 * in [0, 0.8] x [0, 0.25], air elsewhere, with the plugins that reach other
 * particles outside the evaluation's pair passes: the air's held cohesion (a
 * reach of 2H = 4h beyond the support, on demand every 4 steps) and the
 * dissolved oxygen (new particles found by id; reaeration next to the air).
 * The air's speed of sound (271 m/s) sets the step: 3000 steps are 0.057 s.
 * The cuts stay where the equal counts put them (x = 0.8 m on 2 and on 4
 * ranks, between the water's front column and the air's first), so every
 * particle that changes rank is carried there by the flow: the front's
 * foot crosses from step 1677 on, air over the column crosses back (12
 * crossings on 2 ranks), the same in every run. (Under the default balance
 * by measured time the cuts move by however the ranks were timed, and
 * whether they swept over a particle in 1000 steps was up to the machine's
 * load.) */
#define fixed_cuts_text "ranks: {balance: none}\n"
static const char *two_phase_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.3, rest_density: 1000}\n"
    "time: {end: 1.0}\n"
    "domain: {min: [-0.1, -0.1], max: [1.7, 0.5]}\n"
    "geometry:\n"
    "  fluid:\n"
    "    - {shape: box, min: [0, 0], max: [1.6, 0.4]}\n"
    "  walls:\n"
    "    - {shape: tank, min: [0, 0], max: [1.6, 0.4], name: tank}\n"
    "    - {shape: polyline, points: [[1.6, 0.4], [0, 0.4]], name: lid}\n"
    "initial: {density: hydrostatic}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  two_phase: {speed_of_sound: 20, background_pressure: 300, air_box_min: [[0.8, 0], [0, "
    "0.25]], air_box_max: [[1.6, 0.4], [0.8, 0.4]]}\n"
    "  continuity: {form: volume}\n"
    "  pressure_gradient: {form: density_product}\n"
    "  artificial_viscosity: {alpha: 0.1}\n"
    "  air_cohesion_held: {coefficient: 150, smoothing_length_ratio: 2, update_every: 4}\n"
    "  dissolved_oxygen: {initial_concentration: 1.29, saturation_concentration: 10.48, "
    "two_phase: yes, transfer_velocity: 0.01}\n"
    "  gravity: {acceleration: [0, -9.81]}\n"
    "  dbc: {}\n"
    "  time_step: {courant: 0.2}\n"
    "  symplectic: {}\n";

/* The runs compared with one rank: the dam break for 200 steps (the issue's
 * check; t = 0.038 s, no particle has moved far enough to change rank yet)
 * and 1000 (t = 0.18 s: the column has slumped and its surge set off, and
 * hundreds of particles cross the slab boundaries), then with the slab boundaries balanced during the run; on
 * mdbc walls; on ghost particles with the pressure filter and the vorticity
 * (on-demand pair passes between steps); the two-phase scene above, and
 * with a lone air particle and a pocket of two in its water under
 * unresolved_bubbles (the lone one leaves at t = 0.0101 s on every rank
 * count: its air neighbours are searched among the halo too). */
/* A periodic channel 1.2 m long (x periodic), water 0.6 m deep on a DBC
 * bed, driven along x by a tilted gravity (1 m/s^2): particles cross the
 * periodic side, which a cut along x puts between two ranks (on 2 ranks
 * each is the other's neighbour on both sides). */
static const char *periodic_scene =
    "dimensions: 2\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.5, rest_density: 1000}\n"
    "time: {end: 1.0}\n"
    "domain: {min: [0, -0.1], max: [1.2, 0.8], periodic: x}\n"
    "geometry:\n"
    "  fluid:\n"
    "    - {shape: box, min: [0, 0], max: [1.2, 0.6], velocity: [0.3, 0]}\n"
    "  walls:\n"
    "    - {shape: polyline, points: [[0, 0], [1.2, 0]], name: bed}\n"
    "initial: {density: hydrostatic}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 30}\n"
    "  continuity: {}\n"
    "  delta_sph: {delta: 0.1, form: fourtakas}\n"
    "  pressure_gradient: {}\n"
    "  artificial_viscosity: {alpha: 0.05}\n"
    "  gravity: {acceleration: [1.0, -9.81]}\n"
    "  dbc: {}\n"
    "  time_step: {courant: 0.2}\n"
    "  symplectic: {}\n";

/* A 3D dam break (dx = 0.05 m, 10,228 particles) cut along x, y and z:
 * 2 x 1 x 2 boxes on 4 ranks (the least surface for its extent), so halos
 * cross faces, edges and corners of boxes in 3D. */
static const char *scene_3d =
    "dimensions: 3\n"
    "particles: {spacing: 0.05, smoothing_length_ratio: 1.5, rest_density: 1000}\n"
    "time: {end: 1.0}\n"
    "domain: {min: [-0.2, -0.2, -0.2], max: [1.8, 0.8, 1.5]}\n"
    "geometry:\n"
    "  fluid:\n"
    "    - {shape: box, min: [0, 0, 0], max: [0.5, 0.6, 0.5]}\n"
    "  walls:\n"
    "    - {shape: tank, min: [0, 0, 0], max: [1.6, 0.6, 1.2], name: tank}\n"
    "initial: {density: hydrostatic}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 25, gamma: 7}\n"
    "  continuity: {}\n"
    "  delta_sph: {delta: 0.1, form: fourtakas}\n"
    "  pressure_gradient: {}\n"
    "  artificial_viscosity: {alpha: 0.1}\n"
    "  gravity: {acceleration: [0, 0, -9.81]}\n"
    "  dbc: {}\n"
    "  time_step: {courant: 0.2}\n"
    "  symplectic: {}\n";

typedef struct ranks_case {
    const char *what;
    const char *const *base; /* the scene */
    const char *from, *to;   /* a line of it replaced (NULL: none) */
    const char *ranks;       /* its ranks section (NULL: the defaults) */
    int balanced, steps;     /* balanced: the cuts must have moved */
    const char *extra_field; /* also compared, when not NULL */
} ranks_case;


static const ranks_case cases[] = {
    {"dam break", &scene, NULL, NULL, NULL, 0, 200, NULL},
    {"dam break", &scene, NULL, NULL, NULL, 0, 1000, NULL},
    {"dam break, balanced", &scene, NULL, NULL, balanced_ranks_text, 1, 1000, NULL},
    {"dam break on mdbc walls", &scene, "  dbc: {}\n", "  mdbc: {velocity: no_slip}\n",
     balanced_ranks_text, 1, 1000, NULL},
    {"dam break on ghost particles, pressure filter, vorticity", &scene, "  dbc: {}\n",
     "  ghost_particles: {slip: free_slip}\n  pressure_smoothing: {every: 10}\n"
     "  vorticity: {interval: 0.01}\n",
     balanced_ranks_text, 1, 1000, "vorticity"},
    {"two-phase dam break: held cohesion, dissolved oxygen", &two_phase_scene, NULL, NULL,
     fixed_cuts_text, 0, 3000, "dissolved_oxygen"},
    {"two-phase dam break: unresolved bubbles (a lone air particle in the water, a pocket of two)",
     &two_phase_scene, "0.25]], air_box_max: [[1.6, 0.4], [0.8, 0.4]]}\n",
     "0.25], [0.4, 0.04], [0.68, 0.04]], air_box_max: [[1.6, 0.4], [0.8, 0.4], [0.42, 0.06], "
     "[0.72, 0.06]]}\n  unresolved_bubbles: {lifetime: 0.01, check_every: 10}\n",
     fixed_cuts_text, 0, 3000, "isolation_time"},
    {"dam break cut along x and y (2 x 2 on 4 ranks), balanced", &scene, NULL, NULL,
     "ranks: {split: xy, balance: count, every: 20, tolerance: 0.01}\n", 1, 1000, NULL},
    {"dam break cut along y, balanced", &scene, NULL, NULL,
     "ranks: {split: y, balance: count, every: 20, tolerance: 0.01}\n", 1, 1000, NULL},
    {"periodic channel cut along x and y (2 x 2 on 4 ranks)", &periodic_scene, NULL, NULL,
     "ranks: {split: xy, balance: count, every: 20, tolerance: 0.01}\n", 0, 1000, NULL},
    {"3D dam break cut along x, y and z (2 x 1 x 2 on 4 ranks), balanced", &scene_3d, NULL, NULL,
     "ranks: {split: xyz, balance: count, every: 20, tolerance: 0.01}\n", 1, 1000, NULL},
};
#define CASES ((int)(sizeof cases / sizeof cases[0]))

static char *case_scene(int k)
{
    const ranks_case *c = &cases[k];
    char *text = NULL;
    const char *base = *c->base;
    const char *at = c->from ? strstr(base, c->from) : NULL;
    ck_assert(!c->from || at);
    if (at)
        ck_assert_int_ge(asprintf(&text, "%.*s%s%s%s", (int)(at - base), base, c->to,
                                  at + strlen(c->from), c->ranks ? c->ranks : ""),
                         0);
    else
        ck_assert_int_ge(asprintf(&text, "%s%s", base, c->ranks ? c->ranks : ""), 0);
    return text;
}

START_TEST(same_particles_as_one_rank)
{
    const ranks_case *c = &cases[_i];
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    /* on one rank nothing crosses a rank boundary and no boundary moves:
     * the longer runs that check migration and balance (1000 steps) are
     * checked across 2 and 4 ranks; one rank runs each scene for 200 steps,
     * its communicator's code path against the plain one */
    const int STEPS = size == 1 && c->steps > 200 ? 200 : c->steps;
    MPI_Comm world = MPI_COMM_WORLD;
    char *text = case_scene(_i);
    sluice_sim *sim = load_text(text, &world, NULL);
    int loaded = sim != NULL, all_loaded = 0;
    MPI_Allreduce(&loaded, &all_loaded, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
    ck_assert_msg(all_loaded, "rank %d: the scene did not load on every rank", rank);
    ck_assert_int_eq(sluice_sim_rank_count(sim), size);
    ck_assert_int_eq(sluice_sim_begin(sim, NULL), SLUICE_RUN_COMPLETE);
    for (int s = 0; s < STEPS; s++)
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);

    /* gather (id, values) on rank 0 */
    const sluice_view *v = sluice_sim_view(sim);
    int n = (int)v->count;
    unsigned long long *ids = malloc(((size_t)n + 1) * sizeof *ids);
    double *vals = malloc(((size_t)n * VALUES + 1) * sizeof *vals);
    ck_assert(ids && vals);
    for (int i = 0; i < n; i++) {
        ids[i] = (unsigned long long)v->id[i];
        values_of(sim, c->extra_field, (sluice_index)i, vals + (size_t)i * VALUES);
    }
    int *counts = malloc((size_t)size * sizeof *counts), *offsets = malloc((size_t)size * sizeof *offsets);
    int *vcounts = malloc((size_t)size * sizeof *vcounts), *voffsets = malloc((size_t)size * sizeof *voffsets);
    ck_assert(counts && offsets && vcounts && voffsets);
    MPI_Gather(&n, 1, MPI_INT, counts, 1, MPI_INT, 0, MPI_COMM_WORLD);
    int total = 0;
    if (rank == 0)
        for (int r = 0; r < size; r++) {
            offsets[r] = total;
            vcounts[r] = counts[r] * VALUES;
            voffsets[r] = total * VALUES;
            total += counts[r];
        }
    unsigned long long *all_ids = malloc(((size_t)total + 1) * sizeof *all_ids);
    double *all_vals = malloc(((size_t)total * VALUES + 1) * sizeof *all_vals);
    ck_assert(all_ids && all_vals);
    MPI_Gatherv(ids, n, MPI_UNSIGNED_LONG_LONG, all_ids, counts, offsets, MPI_UNSIGNED_LONG_LONG,
                0, MPI_COMM_WORLD);
    MPI_Gatherv(vals, n * VALUES, MPI_DOUBLE, all_vals, vcounts, voffsets, MPI_DOUBLE, 0,
                MPI_COMM_WORLD);
    const unsigned long long balances = sim->halo.balances;
    unsigned long long arrived = sim->halo.arrived, arrived_total = 0;
    MPI_Reduce(&arrived, &arrived_total, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
    /* the halo of each rank at the end, and the bytes of one particle's row
     * (the communication model of docs/scaling.md) */
    unsigned long long halo = sim->grid.halo_count, halo_total = 0;
    MPI_Reduce(&halo, &halo_total, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
    size_t row = 0, refreshed = 0;
    for (uint32_t c = 0; c < sim->particles.column_count; c++)
        row += sim->particles.element_size[c];
    for (uint32_t k = 0; k < sim->halo.column_count; k++)
        refreshed += sim->particles.element_size[sim->halo.columns[k]];
    long long steps = sluice_sim_steps(sim), steps_min = 0, steps_max = 0;
    MPI_Reduce(&steps, &steps_min, 1, MPI_LONG_LONG, MPI_MIN, 0, MPI_COMM_WORLD);
    MPI_Reduce(&steps, &steps_max, 1, MPI_LONG_LONG, MPI_MAX, 0, MPI_COMM_WORLD);
    double t = sluice_sim_time(sim), t_min = 0, t_max = 0;
    MPI_Reduce(&t, &t_min, 1, MPI_DOUBLE, MPI_MIN, 0, MPI_COMM_WORLD);
    MPI_Reduce(&t, &t_max, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);

    if (rank == 0) {
        /* the same scene on this rank alone */
        sluice_sim *one = load_text(text, NULL, NULL);
        ck_assert_ptr_nonnull(one);
        ck_assert_int_eq(sluice_sim_rank_count(one), 1);
        ck_assert_int_eq(sluice_sim_begin(one, NULL), SLUICE_RUN_COMPLETE);
        for (int s = 0; s < STEPS; s++)
            ck_assert_int_eq(sluice_sim_step(one), SLUICE_RUN_COMPLETE);
        const sluice_view *w = sluice_sim_view(one);
        ck_assert_int_eq(steps_min, STEPS);
        ck_assert_int_eq(steps_max, STEPS);
        ck_assert_msg(t_min == t_max && fabs(t_max - sluice_sim_time(one)) <= 1e-15,
                      "time %.17g..%.17g s across ranks, %.17g s on one", t_min, t_max,
                      sluice_sim_time(one));
        ck_assert_int_eq(total, (int)w->count);
        /* by id: every particle exactly once */
        const sluice_id top = top_id(w);
        long *where = id_index(top);
        for (int k = 0; k < total; k++) {
            ck_assert_msg(all_ids[k] <= (unsigned long long)top, "unknown id %llu", all_ids[k]);
            ck_assert_msg(where[all_ids[k]] < 0, "id %llu on two ranks", all_ids[k]);
            where[all_ids[k]] = k;
        }
        double worst[VALUES] = {0}, scale[VALUES] = {0};
        for (sluice_index i = 0; i < w->count; i++) {
            long k = where[w->id[i]];
            ck_assert_msg(k >= 0, "id %llu lost", (unsigned long long)w->id[i]);
            double mine[VALUES];
            values_of(one, c->extra_field, i, mine);
            for (int c = 0; c < VALUES; c++) {
                worst[c] = fmax(worst[c], fabs(all_vals[(size_t)k * VALUES + c] - mine[c]));
                scale[c] = fmax(scale[c], fabs(mine[c]));
            }
        }
        if (size > 1)
            fprintf(stderr, "ranks: boxes %d x %d x %d; ", sim->halo.split[0],
                    sim->halo.split[1], sim->halo.split[2]);
        fprintf(stderr,
                "ranks: %s: %d ranks, %d particles, %d steps to t = %.6g s, %llu particles moved "
                "between ranks, %llu halo particles over all ranks (%zu bytes each, %zu "
                "refreshed);",
                c->what, size, total, STEPS, t_max, arrived_total, halo_total, row, refreshed);
        for (int k = 0; k < VALUES; k++)
            fprintf(stderr, " %s %.2e (of %.3g)", k == VALUES - 1 && c->extra_field
                                                       ? c->extra_field : names[k],
                    worst[k], scale[k]);
        fputc('\n', stderr);
        /* round-off: the sums over neighbours run in another order across a
         * slab boundary (relative 1e-16 per operation). Before the surge
         * reaches the far wall (t < 0.7 s) the flow does not amplify such
         * differences by more than a few orders in 1000 steps; 1e-10 of each
         * field's scale bounds that with a margin, and is far below any
         * error of the decomposition itself (a missed neighbour changes a
         * particle's density by 1e-3 of its value or more) */
        for (int k = 0; k < VALUES; k++)
            ck_assert_msg(worst[k] <= 1e-10 * scale[k], "%s: %s differs by %g (scale %g)",
                          c->what, k == VALUES - 1 && c->extra_field ? c->extra_field : names[k],
                          worst[k], scale[k]);
        if (size > 1 && STEPS >= 1000)
            ck_assert_msg(arrived_total > 0, "no particle moved between ranks: the test does "
                                             "not check migration");
        if (size > 1 && c->balanced) {
            fprintf(stderr, "ranks: balanced by particle count: the slab boundaries moved %llu "
                            "times\n", balances);
            ck_assert_msg(balances > 0, "the slab boundaries never moved: the test does not "
                                        "check the balance");
        }
        free(where);
        sluice_sim_free(one);
    }
    free(all_ids);
    free(all_vals);
    free(ids);
    free(vals);
    free(counts);
    free(offsets);
    free(vcounts);
    free(voffsets);
    free(text);
    sluice_sim_free(sim);
}
END_TEST

/* ------------------------------------------------- output across ranks -- */

/* The dam break with what a user writes: snapshots (parallel HDF5 across
 * ranks), a front gauge, a point gauge, a section gauge with its forces,
 * the tank's wall force and wall pressure sensors with their filter
 * (tables written by rank 0 from reduced sums and minima), and a
 * checkpoint at t = 0.05 s (gathered on rank 0). */
static const char *output_plugins =
    "  front_gauge: {interval: 0.01, origin: 0.0}\n"
    "  point_gauge: {interval: 0.01, points: [[1.0, 0.1], [0.5, 0.5], [2.0, 0.05]], fields: "
    "\"pressure,velocity\"}\n"
    "  section_gauge: {interval: 0.01, positions: [0.5, 1.5], forces: true}\n"
    "  wall_force: {interval: 0.01, walls: tank}\n"
    "  wall_pressure: {interval: 0.01, time_constant: 0.02, positions: [[4.0, 0.05], [0, 0.5], "
    "[2.0, 0]], size: [0.04]}\n"
    "  hdf5: {interval: 0.05}\n";

static char *output_scene(void)
{
    char *text = NULL;
    const char *end = strstr(scene, "time: {end: 1.0}\n");
    ck_assert_ptr_nonnull(end);
    ck_assert_int_ge(asprintf(&text, "%.*stime: {end: 0.12}\ncheckpoint: {interval: 0.05}\n%s%s",
                              (int)(end - scene), scene, end + strlen("time: {end: 1.0}\n"),
                              output_plugins),
                     0);
    return text;
}

/* The same scratch directory on every rank (rank 0 makes it). */
static char *shared_scratch(const char *tag, MPI_Comm comm)
{
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    char path[256] = "";
    if (rank == 0) {
        char *dir = test_scratch(tag);
        ck_assert_ptr_nonnull(dir);
        snprintf(path, sizeof path, "%s", dir);
        free(dir);
    }
    MPI_Bcast(path, sizeof path, MPI_CHAR, 0, comm);
    return strdup(path);
}

static int run_scene(const char *text, const MPI_Comm *comm, const char *dir, const char *restart)
{
    sluice_sim *sim = load_text(text, comm, NULL);
    ck_assert_ptr_nonnull(sim);
    if (restart) {
        char error[1024];
        ck_assert_msg(sluice_sim_restart(sim, restart, error, sizeof error) == SLUICE_OK, "%s",
                      error);
    }
    sluice_run_options options = {dir, 0, 1, 0};
    int status = sluice_sim_run(sim, &options);
    sluice_sim_free(sim);
    return status;
}

/* A snapshot's particles: id and 6 values (x, y, u, v, density, pressure). */
typedef struct snapshot {
    size_t count;
    unsigned long long *id;
    double *value; /* 6 per particle, in the file's order */
    double time;
} snapshot;

static void read_dataset(hid_t file, const char *name, hid_t type, void *out)
{
    hid_t set = H5Dopen2(file, name, H5P_DEFAULT);
    ck_assert_msg(set >= 0, "no dataset '%s'", name);
    ck_assert(H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) >= 0);
    H5Dclose(set);
}

static int read_snapshot(const char *dir, int index, snapshot *s)
{
    char path[512];
    snprintf(path, sizeof path, "%s/particles_%06d.h5", dir, index);
    if (access(path, R_OK) != 0)
        return 0;
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_msg(file >= 0, "cannot open %s", path);
    unsigned long long count = 0;
    hid_t attr = H5Aopen(file, "particle_count", H5P_DEFAULT);
    ck_assert(H5Aread(attr, H5T_NATIVE_ULLONG, &count) >= 0);
    H5Aclose(attr);
    attr = H5Aopen(file, "time", H5P_DEFAULT);
    ck_assert(H5Aread(attr, H5T_NATIVE_DOUBLE, &s->time) >= 0);
    H5Aclose(attr);
    s->count = count;
    s->id = malloc((count + 1) * sizeof *s->id);
    s->value = malloc((count * 6 + 1) * sizeof *s->value);
    double *xy = malloc((count * 2 + 1) * sizeof *xy), *uv = malloc((count * 2 + 1) * sizeof *uv);
    double *rho = malloc((count + 1) * sizeof *rho), *p = malloc((count + 1) * sizeof *p);
    ck_assert(s->id && s->value && xy && uv && rho && p);
    read_dataset(file, "id", H5T_NATIVE_ULLONG, s->id);
    read_dataset(file, "position", H5T_NATIVE_DOUBLE, xy);
    read_dataset(file, "velocity", H5T_NATIVE_DOUBLE, uv);
    read_dataset(file, "density", H5T_NATIVE_DOUBLE, rho);
    read_dataset(file, "pressure", H5T_NATIVE_DOUBLE, p);
    for (size_t i = 0; i < count; i++) {
        double *v = s->value + 6 * i;
        v[0] = xy[2 * i], v[1] = xy[2 * i + 1], v[2] = uv[2 * i], v[3] = uv[2 * i + 1];
        v[4] = rho[i], v[5] = p[i];
    }
    free(xy), free(uv), free(rho), free(p);
    H5Fclose(file);
    return 1;
}

/* The snapshots of `dir` against those of the one-rank run in `one`, by id
 * (every particle once), to 1e-10 of each field's scale (round-off, as in
 * same_particles_as_one_rank); from snapshot `first` on. Returns how many
 * were compared. */
static int compare_snapshots(const char *one, const char *dir, int first)
{
    int compared = 0;
    for (int k = first;; k++) {
        snapshot a = {0}, b = {0};
        if (!read_snapshot(one, k, &a))
            break;
        ck_assert_msg(read_snapshot(dir, k, &b), "%s: snapshot %d is missing", dir, k);
        ck_assert_int_eq(a.count, b.count);
        ck_assert_msg(a.time == b.time, "snapshot %d at %.17g s and %.17g s", k, a.time, b.time);
        unsigned long long top = 0;
        for (size_t i = 0; i < a.count; i++)
            top = a.id[i] > top ? a.id[i] : top;
        long *where = id_index(top);
        for (size_t i = 0; i < b.count; i++) {
            ck_assert_msg(b.id[i] <= top && where[b.id[i]] < 0, "id %llu unknown or twice",
                          b.id[i]);
            where[b.id[i]] = (long)i;
        }
        double worst[6] = {0}, scale[6] = {0};
        for (size_t i = 0; i < a.count; i++) {
            long j = where[a.id[i]];
            ck_assert_msg(j >= 0, "id %llu lost", a.id[i]);
            for (int c = 0; c < 6; c++) {
                worst[c] = fmax(worst[c], fabs(a.value[6 * i + c] - b.value[6 * (size_t)j + c]));
                scale[c] = fmax(scale[c], fabs(a.value[6 * i + c]));
            }
        }
        for (int c = 0; c < 6; c++)
            ck_assert_msg(worst[c] <= 1e-10 * scale[c], "%s snapshot %d: value %d differs by %g "
                          "(scale %g)", dir, k, c, worst[c], scale[c]);
        free(where), free(a.id), free(a.value), free(b.id), free(b.value);
        compared++;
    }
    return compared;
}

/* A table of `dir` against the one-rank run's, row by row: the same times,
 * and values to 1e-9 of each column's scale (they are printed with 10
 * significant digits, and differ by round-off before that). */
static void compare_table(const char *one, const char *dir, const char *name, int *rows)
{
    char a_path[512], b_path[512];
    snprintf(a_path, sizeof a_path, "%s/%s", one, name);
    snprintf(b_path, sizeof b_path, "%s/%s", dir, name);
    char *a = test_read_file(a_path), *b = test_read_file(b_path);
    ck_assert_msg(a && b, "%s or %s is missing", a_path, b_path);
    char *sa = NULL, *sb = NULL;
    char *la = strtok_r(a, "\n", &sa), *lb = strtok_r(b, "\n", &sb);
    ck_assert_msg(la && lb && strcmp(la, lb) == 0, "%s: the headers differ", name);
    double scale[64] = {0}, worst[64] = {0};
    int columns = 0;
    *rows = 0;
    for (;;) {
        la = strtok_r(NULL, "\n", &sa);
        lb = strtok_r(NULL, "\n", &sb);
        ck_assert_msg((la == NULL) == (lb == NULL), "%s: the row counts differ", name);
        if (!la)
            break;
        char *pa = la, *pb = lb;
        int c = 0;
        while (*pa && *pb && c < 64) {
            double x = strtod(pa, &pa), y = strtod(pb, &pb);
            worst[c] = fmax(worst[c], fabs(x - y));
            scale[c] = fmax(scale[c], fabs(x));
            c++;
            pa += *pa == ',';
            pb += *pb == ',';
        }
        columns = c > columns ? c : columns;
        (*rows)++;
    }
    ck_assert_msg(worst[0] == 0, "%s: the times differ", name);
    for (int c = 0; c < columns; c++)
        ck_assert_msg(worst[c] <= 1e-9 * scale[c] + 1e-300, "%s column %d differs by %g (scale %g)",
                      name, c, worst[c], scale[c]);
    free(a), free(b);
}

/* The walls file's `points` of the run in `dir` (every wall's segments). */
static double *read_wall_points(const char *dir, hsize_t *rows)
{
    char path[600];
    snprintf(path, sizeof path, "%s/particles_walls.h5", dir);
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    ck_assert_msg(file >= 0, "cannot open %s", path);
    hid_t set = H5Dopen2(file, "points", H5P_DEFAULT);
    ck_assert_int_ge(set, 0);
    hid_t space = H5Dget_space(set);
    hsize_t dims[2] = {0, 0};
    H5Sget_simple_extent_dims(space, dims, NULL);
    double *points = malloc((size_t)(dims[0] * 3 + 1) * sizeof *points);
    ck_assert_ptr_nonnull(points);
    ck_assert_int_ge(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, points), 0);
    H5Sclose(space);
    H5Dclose(set);
    H5Fclose(file);
    *rows = dims[0];
    return points;
}

/* The walls in the output across ranks (rank 0 writes them): the walls
 * file's points and the XDMF index, wall grids included, as on one rank. */
static void compare_walls(const char *one, const char *dir)
{
    hsize_t rows_one = 0, rows = 0;
    double *a = read_wall_points(one, &rows_one), *b = read_wall_points(dir, &rows);
    ck_assert_uint_eq(rows, rows_one);
    ck_assert_uint_eq(rows, 6); /* the tank's three segments */
    for (hsize_t i = 0; i < 3 * rows; i++)
        ck_assert_double_eq(a[i], b[i]);
    char a_path[600], b_path[600];
    snprintf(a_path, sizeof a_path, "%s/particles.xdmf", one);
    snprintf(b_path, sizeof b_path, "%s/particles.xdmf", dir);
    char *x = test_read_file(a_path), *y = test_read_file(b_path);
    ck_assert_msg(x && y && strcmp(x, y) == 0, "%s differs from the one-rank index", b_path);
    ck_assert_ptr_nonnull(strstr(x, "<Grid Name=\"walls\""));
    free(a), free(b), free(x), free(y);
}

START_TEST(output_as_one_rank)
{
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    MPI_Comm world = MPI_COMM_WORLD;
    char *text = output_scene();
    char *across = shared_scratch("ranks-out", world);
    char *again = shared_scratch("ranks-restart", world);
    ck_assert_int_eq(run_scene(text, &world, across, NULL), SLUICE_RUN_COMPLETE);
    char checkpoint[600];
    snprintf(checkpoint, sizeof checkpoint, "%s/checkpoint_%09d.h5", across, 0);
    /* the checkpoint at t = 0.05 s: its step number is in its name */
    if (rank == 0) {
        char command[800];
        snprintf(command, sizeof command, "ls %s/checkpoint_*.h5 | head -n 1", across);
        FILE *ls = popen(command, "r");
        ck_assert_ptr_nonnull(ls);
        ck_assert_ptr_nonnull(fgets(checkpoint, sizeof checkpoint, ls));
        checkpoint[strcspn(checkpoint, "\n")] = '\0';
        pclose(ls);
    }
    MPI_Bcast(checkpoint, sizeof checkpoint, MPI_CHAR, 0, world);
    /* the same ranks continue from it, in a copy of the run's directory
     * (so that the tables go on from their rows at the checkpoint) */
    char command[1400];
    snprintf(command, sizeof command, "cp -r %s/. %s", across, again);
    if (rank == 0)
        ck_assert_int_eq(system(command), 0);
    MPI_Barrier(world);
    ck_assert_int_eq(run_scene(text, &world, again, checkpoint), SLUICE_RUN_COMPLETE);
    if (rank == 0) {
        /* the scene on this rank alone, and a restart of the across-ranks
         * checkpoint on one rank (another rank count) */
        char *one = test_scratch("ranks-one"), *alone = test_scratch("ranks-alone");
        ck_assert_int_eq(run_scene(text, NULL, one, NULL), SLUICE_RUN_COMPLETE);
        snprintf(command, sizeof command, "cp -r %s/. %s", across, alone);
        ck_assert_int_eq(system(command), 0);
        ck_assert_int_eq(run_scene(text, NULL, alone, checkpoint), SLUICE_RUN_COMPLETE);
        int snapshots = compare_snapshots(one, across, 0);
        ck_assert_int_eq(snapshots, 4); /* t = 0, 0.05, 0.1 and the end, 0.12 s */
        /* the restarts rewrite from the checkpoint's time on: t = 0.1 s and the end */
        ck_assert_int_eq(compare_snapshots(one, again, 0), 4);
        ck_assert_int_eq(compare_snapshots(one, alone, 0), 4);
        compare_walls(one, across);
        int front_rows = 0, point_rows = 0, other_rows = 0;
        compare_table(one, across, "front.csv", &front_rows);
        compare_table(one, across, "points.csv", &point_rows);
        ck_assert_int_eq(front_rows, 13); /* t = 0, 0.01, ..., 0.12 s */
        ck_assert_int_eq(point_rows, 13);
        compare_table(one, across, "sections.csv", &other_rows);
        ck_assert_int_eq(other_rows, 13);
        compare_table(one, across, "wall_forces.csv", &other_rows);
        ck_assert_int_eq(other_rows, 13);
        compare_table(one, across, "wall_pressure.csv", &other_rows);
        ck_assert_int_eq(other_rows, 13);
        for (int k = 0; k < 2; k++) {
            const char *restarted = k == 0 ? again : alone;
            compare_table(one, restarted, "front.csv", &front_rows);
            compare_table(one, restarted, "points.csv", &point_rows);
            ck_assert_int_eq(front_rows, 13);
            ck_assert_int_eq(point_rows, 13);
            compare_table(one, restarted, "sections.csv", &other_rows);
            ck_assert_int_eq(other_rows, 13);
            compare_table(one, restarted, "wall_forces.csv", &other_rows);
            ck_assert_int_eq(other_rows, 13);
            compare_table(one, restarted, "wall_pressure.csv", &other_rows);
            ck_assert_int_eq(other_rows, 13);
        }
        /* run.json: the counts of every rank */
        char path[600];
        snprintf(path, sizeof path, "%s/run.json", across);
        char *json = test_read_file(path);
        ck_assert_ptr_nonnull(json);
        ck_assert_msg(strstr(json, "\"particles_final\": 2016,") &&
                          strstr(json, "\"particles_initial\": 2016,"),
                      "%s", json);
        char ranks_line[64];
        snprintf(ranks_line, sizeof ranks_line, "\"ranks\": %d,", size);
        ck_assert_msg(strstr(json, ranks_line) != NULL, "%s", json);
        fprintf(stderr, "ranks: %d ranks: %d snapshots, %d + %d table rows and the restarts on "
                        "%d and on 1 rank(s) equal the one-rank run\n",
                size, snapshots, front_rows, point_rows, size);
        free(json), free(one), free(alone);
    }
    free(text), free(across), free(again);
}
END_TEST

/* ------------------------------------------ inlets and outlets across ranks -- */

/* A channel 1 m long (tests/plugins/open_boundaries/test_open_boundaries.c's uniform channel): water
 * 0.1 m deep at 0.5 m/s between a buffer inlet at x = 0, on the first
 * rank's slab, and a free outlet at x = 1 m, on the last rank's; 0.5 s, in
 * which the inlet adds 13 columns of 5 particles and the outlet removes
 * about as many. */
static const char *channel =
    "dimensions: 2\n"
    "particles: {spacing: 0.02, smoothing_length_ratio: 1.5}\n"
    "time: {end: 0.5}\n"
    "domain: {min: [-0.7, -0.1], max: [1.5, 0.6]}\n"
    "geometry:\n"
    "  fluid:\n"
    "    - {shape: box, min: [0, 0], max: [1.0, 0.1], velocity: [0.5, 0]}\n"
    "  walls:\n"
    "    - {shape: polyline, points: [[-0.66, 0], [1.4, 0]], name: bed}\n"
    "plugins:\n"
    "  wendland_c2: {}\n"
    "  tait: {speed_of_sound: 20}\n"
    "  continuity: {}\n"
    "  delta_sph: {delta: 0.1, form: fourtakas}\n"
    "  pressure_gradient: {}\n"
    "  artificial_viscosity: {alpha: 0.02}\n"
    "  gravity: {}\n"
    "  penalty_contact: {}\n"
    "  time_step: {courant: 0.25}\n"
    "  symplectic: {}\n"
    "  inlet: {form: buffer, position: 0, depth: 0.1, velocity: 0.5, interval: 0.05}\n"
    "  outlet: {form: free, position: 1.0, interval: 0.05}\n"
    /* the cuts move with the particle counts, reproducibly (a balance by
     * measured time moves them as the machine's load says, and the
     * round-off with them) */
    "ranks: {balance: count}\n";

/* Every rank's (id, x, y, u, v, density, kind) on rank 0. */
static int gather_particles(sluice_sim *sim, MPI_Comm comm, unsigned long long **ids,
                            double **values)
{
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    const sluice_view *v = sluice_sim_view(sim);
    const int n = (int)v->count;
    unsigned long long *my_ids = malloc(((size_t)n + 1) * sizeof *my_ids);
    double *mine = malloc(((size_t)n * 6 + 1) * sizeof *mine);
    ck_assert(my_ids && mine);
    for (int i = 0; i < n; i++) {
        my_ids[i] = v->id[i];
        double *m = mine + 6 * (size_t)i;
        m[0] = v->position[0][i], m[1] = v->position[1][i];
        m[2] = test_column(sim, "velocity", 0)[i], m[3] = test_column(sim, "velocity", 1)[i];
        m[4] = test_column(sim, "density", 0)[i], m[5] = v->kind[i];
    }
    int *counts = calloc((size_t)size, sizeof *counts), *at = calloc((size_t)size, sizeof *at);
    int *counts6 = calloc((size_t)size, sizeof *counts6), *at6 = calloc((size_t)size, sizeof *at6);
    ck_assert(counts && at && counts6 && at6);
    MPI_Gather(&n, 1, MPI_INT, counts, 1, MPI_INT, 0, comm);
    int total = 0;
    for (int r = 0; r < size; r++) {
        at[r] = total, at6[r] = 6 * total, counts6[r] = 6 * counts[r];
        total += counts[r];
    }
    *ids = malloc(((size_t)total + 1) * sizeof **ids);
    *values = malloc(((size_t)total * 6 + 1) * sizeof **values);
    ck_assert(*ids && *values);
    MPI_Gatherv(my_ids, n, MPI_UNSIGNED_LONG_LONG, *ids, counts, at, MPI_UNSIGNED_LONG_LONG, 0,
                comm);
    MPI_Gatherv(mine, 6 * n, MPI_DOUBLE, *values, counts6, at6, MPI_DOUBLE, 0, comm);
    free(my_ids), free(mine), free(counts), free(at), free(counts6), free(at6);
    return total;
}

START_TEST(inlet_and_outlet_on_other_ranks)
{
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    MPI_Comm world = MPI_COMM_WORLD;
    char *across = shared_scratch("ranks-channel", world);
    sluice_sim *sim = load_text(channel, &world, NULL);
    ck_assert_ptr_nonnull(sim);
    const uint64_t initial = sluice_sim_particle_total(sim);
    /* the scene's ids end below `initial`: the run's new ones are above */
    ck_assert_int_eq(sluice_sim_begin(sim, across), SLUICE_RUN_COMPLETE);
    size_t capacity = 4096, steps = 0;
    unsigned long long *totals = malloc(capacity * sizeof *totals);
    ck_assert_ptr_nonnull(totals);
    while (sluice_sim_time(sim) < 0.5 - 1e-12) {
        ck_assert_int_eq(sluice_sim_step(sim), SLUICE_RUN_COMPLETE);
        ck_assert(steps < capacity);
        totals[steps++] = sluice_sim_particle_total(sim);
    }
    unsigned long long *ids = NULL;
    double *values = NULL;
    const int total = gather_particles(sim, world, &ids, &values);
    ck_assert_int_eq(sluice_sim_end(sim, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    if (rank == 0) {
        char *one_dir = test_scratch("ranks-channel-one");
        sluice_sim *one = load_text(channel, NULL, NULL);
        ck_assert_ptr_nonnull(one);
        ck_assert_int_eq(sluice_sim_begin(one, one_dir), SLUICE_RUN_COMPLETE);
        size_t step = 0;
        uint64_t added_max = 0;
        while (sluice_sim_time(one) < 0.5 - 1e-12) {
            ck_assert_int_eq(sluice_sim_step(one), SLUICE_RUN_COMPLETE);
            ck_assert(step < steps);
            /* the global count of every step is the one-rank count */
            ck_assert_msg(totals[step] == sluice_sim_view(one)->count,
                          "step %zu: %llu particles across %d ranks, %u on one", step + 1,
                          totals[step], size, sluice_sim_view(one)->count);
            step++;
        }
        ck_assert_int_eq(step, steps);
        const sluice_view *w = sluice_sim_view(one);
        ck_assert_int_eq(total, (int)w->count);
        /* ids: the scene's below `initial`, the run's rank r of R at
         * initial + r + R k; here the inlet is on rank 0, so its k-th new
         * particle is initial + R k across ranks and initial + k on one */
        const sluice_id top = top_id(w);
        long *where = id_index(top);
        for (int k = 0; k < total; k++) {
            unsigned long long id = ids[k];
            if (id >= initial) {
                ck_assert_msg((id - initial) % (unsigned long long)size == 0,
                              "id %llu was not added by rank 0", id);
                id = initial + (id - initial) / (unsigned long long)size;
                added_max = id > added_max ? id : added_max;
            }
            ck_assert_msg(id <= top && where[id] < 0, "id %llu unknown or on two ranks", ids[k]);
            where[id] = k;
        }
        double worst[6] = {0}, scale[6] = {0};
        for (sluice_index i = 0; i < w->count; i++) {
            const long k = where[w->id[i]];
            ck_assert_msg(k >= 0, "id %llu lost", (unsigned long long)w->id[i]);
            const double mine[6] = {w->position[0][i], w->position[1][i],
                                    test_column(one, "velocity", 0)[i],
                                    test_column(one, "velocity", 1)[i],
                                    test_column(one, "density", 0)[i], w->kind[i]};
            for (int c = 0; c < 6; c++) {
                worst[c] = fmax(worst[c], fabs(values[6 * (size_t)k + c] - mine[c]));
                scale[c] = fmax(scale[c], fabs(mine[c]));
            }
        }
        /* the velocity's scale is the flow's speed, for both components
         * (the vertical one alone is noise about zero) */
        scale[2] = scale[3] = fmax(scale[2], scale[3]);
        for (int c = 0; c < 6; c++)
            ck_assert_msg(worst[c] <= 1e-10 * scale[c], "value %d differs by %g (scale %g)", c,
                          worst[c], scale[c]);
        ck_assert_int_eq(sluice_sim_end(one, SLUICE_RUN_COMPLETE), SLUICE_RUN_COMPLETE);
        int inlet_rows = 0, outlet_rows = 0;
        compare_table(one_dir, across, "inlet.csv", &inlet_rows);
        compare_table(one_dir, across, "outlet.csv", &outlet_rows);
        ck_assert_int_eq(inlet_rows, 11); /* t = 0, 0.05, ..., 0.5 s */
        ck_assert_int_eq(outlet_rows, 11);
        char path[600];
        snprintf(path, sizeof path, "%s/run.json", across);
        char *json = test_read_file(path);
        ck_assert_ptr_nonnull(json);
        char final[64];
        snprintf(final, sizeof final, "\"particles_final\": %u,", w->count);
        ck_assert_msg(strstr(json, final) != NULL, "%s", json);
        fprintf(stderr, "ranks: channel across %d ranks: %zu steps, %llu -> %d particles "
                        "(%llu added by the inlet), the global count of every step, the fields "
                        "by id and inlet.csv / outlet.csv equal the one-rank run's; largest "
                        "differences x %.1e m, u %.1e m/s, density %.1e kg/m^3\n",
                size, steps, (unsigned long long)initial, total,
                (unsigned long long)(added_max >= initial ? added_max - initial + 1 : 0),
                worst[0], worst[2], worst[4]);
        ck_assert_msg(added_max >= initial, "the inlet added no particle");
        free(json), free(where), free(one_dir);
        sluice_sim_free(one);
    }
    free(ids), free(values), free(totals), free(across);
}
END_TEST

/* A term that reads a field at its neighbours without declaring it
 * (tests/sdk/fixtures/neighbour_reader.c: density_rate, declared SLUICE_READ
 * only) gets NaN from the halo across ranks, where the refresh does not send
 * that field: one evaluation leaves NaN in the acceleration of the particles
 * with neighbours on other ranks (which the watchdog then stops), never a
 * value one rebuild old. On one rank every acceleration is finite. */
START_TEST(undeclared_neighbour_read_is_nan)
{
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    MPI_Comm world = MPI_COMM_WORLD;
    const char *fixtures = getenv("SLUICE_FIXTURE_DIR");
    ck_assert_ptr_nonnull(fixtures);
    char *text = NULL;
    ck_assert_int_ge(asprintf(&text, "plugin_path: %s\n%s  neighbour_reader: {}\n",
                              fixtures, scene),
                     0);
    sluice_sim *sim = load_text(text, &world, NULL);
    free(text);
    ck_assert_ptr_nonnull(sim);
    ck_assert_int_eq(sluice_sim_evaluate(sim), SLUICE_OK);
    const sluice_view *v = sluice_sim_view(sim);
    const sluice_real *ax = test_column(sim, "acceleration", 0);
    double nan_count = 0;
    for (sluice_index i = 0; i < v->count; i++)
        nan_count += v->kind[i] == SLUICE_KIND_FLUID && !isfinite((double)ax[i]);
    double total = 0;
    MPI_Allreduce(&nan_count, &total, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    if (rank == 0)
        fprintf(stderr, "ranks: an undeclared neighbour read on %d rank(s): %.0f fluid particles "
                        "with a NaN acceleration\n",
                size, total);
    if (size == 1)
        ck_assert_msg(total == 0, "NaN on one rank");
    else
        ck_assert_msg(total > 0, "the undeclared read across ranks went unnoticed");
    sluice_sim_free(sim);
}
END_TEST

/* A split the scene cannot have is refused at load, with the line of the
 * key: the axis z in a 2D scene. */
START_TEST(refused_across_ranks)
{
    MPI_Comm world = MPI_COMM_WORLD;
    char *text = NULL;
    ck_assert_int_ge(asprintf(&text, "%sranks: {split: xz}\n", scene), 0);
    load_text(text, &world, "ranks.split names the axis z in a 2D scene");
    free(text);
}
END_TEST

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    Suite *s = suite_create("ranks");
    /* in cases of a minute or two each (tests/meson.build runs each case
     * as a test of its own, CK_RUN_CASE) */
    const int thirds[4] = {0, CASES / 3, 2 * CASES / 3, CASES};
    static const char *const scene_cases[3] = {"scenes_1", "scenes_2", "scenes_3"};
    for (int k = 0; k < 3; k++) {
        TCase *t = tcase_create(scene_cases[k]);
        tcase_set_timeout(t, 600);
        tcase_add_loop_test(t, same_particles_as_one_rank, thirds[k], thirds[k + 1]);
        suite_add_tcase(s, t);
    }
    TCase *t = tcase_create("outputs");
    tcase_set_timeout(t, 600);
    tcase_add_test(t, output_as_one_rank);
    tcase_add_test(t, inlet_and_outlet_on_other_ranks);
    tcase_add_test(t, refused_across_ranks);
    tcase_add_test(t, undeclared_neighbour_read_is_nan);
    suite_add_tcase(s, t);
    SRunner *runner = srunner_create(s);
    srunner_set_fork_status(runner, CK_NOFORK);
    srunner_run_all(runner, CK_NORMAL);
    int failed = srunner_ntests_failed(runner);
    srunner_free(runner);
    int any = 0;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    MPI_Finalize();
    return any == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
