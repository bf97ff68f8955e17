/* Neighbour search: the pairs the core hands to pair terms must be exactly
 * the pairs within the kernel support found by brute force, in 2D and 3D,
 * with and without periodic directions, with kind masks, and still after
 * particles move within the skin (no rebuild) or beyond it (rebuild). */
#include <math.h>

#include "neighbours.h"
#include "pairs.h"
#include "test_util.h"

enum { COL_X = 0, COL_Y, COL_Z, COL_KIND, COL_ID, COL_COUNT, COL_HASH, COL_OFFSET_ERROR, NCOL };

typedef struct world {
    uint32_t dims;
    sluice_particles particles;
    sluice_grid grid;
    sluice_pair_engine engine;
    sluice_view view;
    double lo[3], hi[3];
    int periodic[3];
    double support;
} world;

static uint64_t rng_state;
static double uniform(void)
{
    rng_state = rng_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static void test_kernel(void *state, sluice_index n, const sluice_real *r2, sluice_real *r,
                        sluice_real *w, sluice_real *f)
{
    (void)state;
    for (sluice_index k = 0; k < n; k++) {
        r[k] = sqrt(r2[k]);
        if (w)
            w[k] = 1 - r[k];
        f[k] = -1;
    }
}

static const sluice_component kernel_component = {.name = "test_kernel", .kernel = test_kernel};

static void refresh(world *w)
{
    sluice_view *v = &w->view;
    v->count = w->particles.count;
    v->dimensions = w->dims;
    v->columns = w->particles.columns;
    v->position[0] = w->particles.columns[COL_X];
    v->position[1] = w->particles.columns[COL_Y];
    v->position[2] = w->dims == 3 ? w->particles.columns[COL_Z] : NULL;
    v->kind = w->particles.columns[COL_KIND];
    v->id = w->particles.columns[COL_ID];
}

/* The term: per target, count of neighbours and an order-independent hash of
 * their ids; checks r_ij and |r_ij| against the positions. */
static void record(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const world *w = state;
    sluice_real *count = v->columns[COL_COUNT];
    sluice_real *hash = v->columns[COL_HASH];
    sluice_real *error = v->columns[COL_OFFSET_ERROR];
    for (sluice_index t = 0; t < b->target_count; t++) {
        sluice_index i = b->target[t];
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            sluice_index j = b->neighbour[k];
            double idj = (double)v->id[j];
            count[i] += 1;
            hash[i] += (idj + 1) * (idj + 7) * 1e-6;
            double r2 = 0;
            for (uint32_t d = 0; d < v->dimensions; d++) {
                double dx = (double)v->position[d][i] - (double)v->position[d][j];
                if (w->periodic[d]) {
                    double L = w->hi[d] - w->lo[d];
                    dx -= L * nearbyint(dx / L);
                }
                double e = fabs(dx - (double)b->offset[d][k]);
                if (e > error[i])
                    error[i] = e;
                r2 += dx * dx;
            }
            double e = fabs(sqrt(r2) - (double)b->distance[k]);
            if (e > error[i])
                error[i] = e;
            if (b->neighbour_kind[k] != v->kind[j])
                error[i] = 1e9;
            if (j == i)
                error[i] = 1e9;
        }
    }
}

static sluice_component record_component = {.name = "record", .pair = record};

static void make_world(world *w, uint32_t dims, sluice_index n, const int periodic[3],
                       double support, int two_kinds)
{
    memset(w, 0, sizeof *w);
    w->dims = dims;
    w->support = support;
    uint8_t sizes[NCOL] = {8, 8, 8, 1, 8, 8, 8, 8};
    ck_assert_int_eq(sluice_particles_init(&w->particles, NCOL, sizes), 0);
    sluice_index first;
    ck_assert_int_eq(sluice_particles_append(&w->particles, n, &first), 0);
    for (int d = 0; d < 3; d++) {
        w->lo[d] = 0;
        w->hi[d] = d == 0 ? 1.0 : 0.7;
        w->periodic[d] = periodic[d];
    }
    for (sluice_index i = 0; i < n; i++) {
        for (uint32_t d = 0; d < dims; d++)
            ((double *)w->particles.columns[COL_X + d])[i] =
                w->lo[d] + (w->hi[d] - w->lo[d]) * uniform() * 0.999999;
        ((uint8_t *)w->particles.columns[COL_KIND])[i] = two_kinds ? (uint8_t)(i % 3 == 0) : 0;
        ((uint64_t *)w->particles.columns[COL_ID])[i] = i;
    }
    const char *reason = NULL;
    ck_assert_msg(sluice_grid_init(&w->grid, dims, w->lo, w->hi, periodic, (sluice_real)support,
                                   (sluice_real)(0.1 * support), &reason) == 0,
                  "grid init: %s", reason ? reason : "");
    ck_assert_int_eq(sluice_pair_engine_init(&w->engine, 2, 256, NCOL), 0);
    w->engine.kernel = &kernel_component;
    refresh(w);
}

static void free_world(world *w)
{
    sluice_pair_engine_free(&w->engine);
    sluice_grid_free(&w->grid);
    sluice_particles_free(&w->particles);
}

/* Runs a pass and compares with brute force: fluid targets (kind 0) see the
 * kinds of fluid_neighbours, wall targets (kind 1) those of wall_neighbours
 * (0: walls are no targets). */
static void check_kinds_against_brute_force(world *w, uint32_t fluid_neighbours,
                                            uint32_t wall_neighbours)
{
    if (sluice_grid_needs_rebuild(&w->grid, &w->view)) {
        sluice_index bad = 0;
        ck_assert_int_eq(sluice_grid_build(&w->grid, &w->particles, COL_X, &bad), 0);
    }
    refresh(w);
    const sluice_index n = w->view.count;
    for (int c = COL_COUNT; c < NCOL; c++)
        memset(w->particles.columns[c], 0, n * sizeof(double));
    sluice_pair_term term = {&record_component, w, SLUICE_KINDS_ALL};
    sluice_pair_pass pass;
    memset(&pass, 0, sizeof pass);
    pass.term_count = 1;
    pass.terms = &term;
    pass.neighbour_mask[0] = fluid_neighbours;
    pass.neighbour_mask[1] = wall_neighbours;
    ck_assert_int_eq(sluice_pair_pass_run(&w->engine, &pass, &w->grid, &w->view), 0);

    const double *count = w->particles.columns[COL_COUNT];
    const double *hash = w->particles.columns[COL_HASH];
    const double *error = w->particles.columns[COL_OFFSET_ERROR];
    const uint8_t *kind = w->view.kind;
    const double s2 = w->support * w->support;
    long total = 0;
    for (sluice_index i = 0; i < n; i++) {
        uint32_t mask = kind[i] == 0 ? fluid_neighbours : wall_neighbours;
        double c = 0, h = 0;
        for (sluice_index j = 0; j < n && mask; j++) {
            if (j == i || !((mask >> kind[j]) & 1u))
                continue;
            double r2 = 0;
            for (uint32_t d = 0; d < w->dims; d++) {
                double dx = (double)w->view.position[d][i] - (double)w->view.position[d][j];
                if (w->periodic[d]) {
                    double L = w->hi[d] - w->lo[d];
                    dx -= L * nearbyint(dx / L);
                }
                r2 += dx * dx;
            }
            if (r2 < s2) {
                double idj = (double)w->view.id[j];
                c += 1;
                h += (idj + 1) * (idj + 7) * 1e-6;
            }
        }
        ck_assert_msg(count[i] == c, "particle %u: %g pairs, brute force %g", i, count[i], c);
        ck_assert_msg(fabs(hash[i] - h) <= 1e-9 * (1 + fabs(h)),
                      "particle %u: neighbour set differs from brute force", i);
        ck_assert_msg(error[i] < 1e-12, "particle %u: offset/distance error %g", i, error[i]);
        total += (long)c;
    }
    ck_assert_msg(total > 10 * (long)n, "too few pairs (%ld) for a meaningful test", total);
}

static void check_against_brute_force(world *w, uint32_t fluid_neighbours, int two_kinds)
{
    check_kinds_against_brute_force(w, fluid_neighbours, two_kinds ? SLUICE_KINDS_ALL : 0);
}

static void move(world *w, double amplitude)
{
    for (sluice_index i = 0; i < w->view.count; i++)
        for (uint32_t d = 0; d < w->dims; d++) {
            double *x = w->particles.columns[COL_X + d];
            double v = x[i] + amplitude * (2 * uniform() - 1) / sqrt((double)w->dims);
            if (w->periodic[d]) {
                double L = w->hi[d] - w->lo[d];
                v -= L * floor((v - w->lo[d]) / L);
            } else {
                v = v < w->lo[d] ? w->lo[d] : v >= w->hi[d] ? w->hi[d] - 1e-9 : v;
            }
            x[i] = v;
        }
    refresh(w);
}

static void scenario(uint32_t dims, sluice_index n, int px, int py, int pz, double support)
{
    int periodic[3] = {px, py, pz};
    world w;
    rng_state = 12345 + dims * 7 + (uint64_t)px * 3 + (uint64_t)py * 5;
    make_world(&w, dims, n, periodic, support, 0);
    check_against_brute_force(&w, SLUICE_KINDS_ALL, 0);
    uint64_t builds = w.grid.rebuilds;
    /* within half the skin: the list is reused and still exact */
    move(&w, 0.4 * 0.5 * 0.1 * support);
    ck_assert_int_eq(sluice_grid_needs_rebuild(&w.grid, &w.view), 0);
    check_against_brute_force(&w, SLUICE_KINDS_ALL, 0);
    ck_assert_uint_eq(w.grid.rebuilds, builds);
    /* beyond it: rebuilt */
    move(&w, 0.5 * support);
    ck_assert_int_eq(sluice_grid_needs_rebuild(&w.grid, &w.view), 1);
    check_against_brute_force(&w, SLUICE_KINDS_ALL, 0);
    ck_assert_uint_eq(w.grid.rebuilds, builds + 1);
    free_world(&w);
}

START_TEST(random_2d) { scenario(2, 3000, 0, 0, 0, 0.05); }
END_TEST
START_TEST(random_2d_periodic) { scenario(2, 3000, 1, 1, 0, 0.05); }
END_TEST
START_TEST(random_2d_periodic_x) { scenario(2, 3000, 1, 0, 0, 0.05); }
END_TEST
START_TEST(random_3d) { scenario(3, 4000, 0, 0, 0, 0.12); }
END_TEST
START_TEST(random_3d_periodic) { scenario(3, 4000, 1, 1, 1, 0.12); }
END_TEST

START_TEST(kind_masks)
{
    int periodic[3] = {0, 0, 0};
    world w;
    rng_state = 99;
    make_world(&w, 2, 2500, periodic, 0.05, 1);
    /* fluid targets see only fluid; wall targets see everything */
    check_against_brute_force(&w, SLUICE_KIND_MASK(SLUICE_KIND_FLUID), 1);
    free_world(&w);
}
END_TEST

/* Lists of kinds (grid->list_kinds): a wall particle that pairs with fluid
 * alone lists fluid neighbours alone, one whose kind no pass targets lists
 * nothing, and the passes still get exactly the brute-force pairs; the
 * lists shrink accordingly, also across a rebuild. */
static void kind_lists_scenario(int periodic_x)
{
    int periodic[3] = {periodic_x, 0, 0};
    world w;
    rng_state = 4242 + (uint64_t)periodic_x;
    make_world(&w, 3, 4000, periodic, 0.12, 1);
    /* a dry corner: the particles of x > 0.75 are walls, so that whole
     * cells hold no fluid and the build skips them */
    for (sluice_index i = 0; i < w.particles.count; i++)
        if (((double *)w.particles.columns[COL_X])[i] > 0.75)
            ((uint8_t *)w.particles.columns[COL_KIND])[i] = SLUICE_KIND_WALL;
    const uint32_t fluid = SLUICE_KIND_MASK(SLUICE_KIND_FLUID);
    check_kinds_against_brute_force(&w, SLUICE_KINDS_ALL, SLUICE_KINDS_ALL);
    const size_t all_entries = w.grid.list_begin[w.grid.count];

    w.grid.kind_column = COL_KIND;
    w.grid.list_kinds[SLUICE_KIND_FLUID] = SLUICE_KINDS_ALL;
    w.grid.list_kinds[SLUICE_KIND_WALL] = fluid;
    w.grid.valid = 0;
    check_kinds_against_brute_force(&w, SLUICE_KINDS_ALL, fluid);
    const uint8_t *kind = w.particles.columns[COL_KIND];
    size_t wall_entries = 0, fluid_entries = 0;
    for (sluice_index i = 0; i < w.grid.count; i++)
        for (sluice_index m = w.grid.list_begin[i]; m < w.grid.list_begin[i + 1]; m++) {
            if (kind[i] == SLUICE_KIND_WALL)
                ck_assert_msg(kind[w.grid.list[m]] == SLUICE_KIND_FLUID,
                              "wall particle %u lists wall particle %u", i, w.grid.list[m]);
            *(kind[i] == SLUICE_KIND_WALL ? &wall_entries : &fluid_entries) += 1;
        }
    /* the walls' lists lost their wall entries: every list together holds
     * the fluid's lists and the walls' fluid neighbours */
    const size_t mixed_entries = w.grid.list_begin[w.grid.count];
    ck_assert_uint_eq(mixed_entries, wall_entries + fluid_entries);
    ck_assert_msg(wall_entries < all_entries - fluid_entries, "wall lists hold %zu of %zu entries",
                  wall_entries, all_entries - fluid_entries);

    /* walls no pass targets: empty lists, across a rebuild too */
    w.grid.list_kinds[SLUICE_KIND_WALL] = 0;
    w.grid.valid = 0;
    check_kinds_against_brute_force(&w, fluid, 0);
    move(&w, 0.5 * w.support);
    check_kinds_against_brute_force(&w, fluid, 0);
    kind = w.particles.columns[COL_KIND]; /* the rebuild sorted the store */
    for (sluice_index i = 0; i < w.grid.count; i++)
        if (kind[i] == SLUICE_KIND_WALL)
            ck_assert_uint_eq(w.grid.list_begin[i + 1], w.grid.list_begin[i]);
    free_world(&w);
}

START_TEST(kind_lists) { kind_lists_scenario(0); }
END_TEST
START_TEST(kind_lists_periodic) { kind_lists_scenario(1); }
END_TEST

START_TEST(outside_domain_reported)
{
    int periodic[3] = {0, 0, 0};
    world w;
    rng_state = 7;
    make_world(&w, 2, 100, periodic, 0.05, 0);
    ((double *)w.particles.columns[COL_Y])[42] = 5.0; /* above the domain */
    sluice_index bad = 0;
    ck_assert_int_eq(sluice_grid_build(&w.grid, &w.particles, COL_X, &bad), -2);
    ck_assert_uint_eq(bad, 42);
    ((double *)w.particles.columns[COL_Y])[42] = NAN;
    ck_assert_int_eq(sluice_grid_build(&w.grid, &w.particles, COL_X, &bad), -2);
    ck_assert_uint_eq(bad, 42);
    free_world(&w);
}
END_TEST

START_TEST(list_growth_limited)
{
    /* counts 3, 0, 5: 8 entries. Past a limit of 7 entries nothing is
     * allocated and the total is reported; at 8 (no margin) it fits */
    sluice_index begin[4] = {0, 3, 0, 5};
    sluice_index *list = NULL;
    size_t capacity = 0, needed = 0;
    ck_assert_int_eq(sluice_list_offsets(begin, 3, &list, &capacity, 7, &needed), -4);
    ck_assert_uint_eq(needed, 8);
    ck_assert_ptr_null(list);
    ck_assert_uint_eq(capacity, 0);
    sluice_index again[4] = {0, 3, 0, 5};
    ck_assert_int_eq(sluice_list_offsets(again, 3, &list, &capacity, 8 + 64, &needed), 0);
    ck_assert_ptr_nonnull(list);
    ck_assert_uint_ge(capacity, 8);
    ck_assert_uint_eq(again[3], 8);
    free(list);
}
END_TEST

START_TEST(short_periodic_refused)
{
    int periodic[3] = {1, 0, 0};
    double lo[3] = {0, 0, 0}, hi[3] = {0.1, 1, 0};
    sluice_grid g;
    const char *reason = NULL;
    ck_assert_int_eq(sluice_grid_init(&g, 2, lo, hi, periodic, 0.05, 0.005, &reason), -1);
    ck_assert_ptr_nonnull(reason);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("neighbours");
    TCase *tc = tcase_create("brute force");
    tcase_set_timeout(tc, 120);
    tcase_add_test(tc, random_2d);
    tcase_add_test(tc, random_2d_periodic);
    tcase_add_test(tc, random_2d_periodic_x);
    tcase_add_test(tc, random_3d);
    tcase_add_test(tc, random_3d_periodic);
    tcase_add_test(tc, kind_masks);
    tcase_add_test(tc, kind_lists);
    tcase_add_test(tc, kind_lists_periodic);
    tcase_add_test(tc, outside_domain_reported);
    tcase_add_test(tc, short_periodic_refused);
    tcase_add_test(tc, list_growth_limited);
    suite_add_tcase(s, tc);
    return test_run_suite(s);
}
