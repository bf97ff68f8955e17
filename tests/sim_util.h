/* Loading simulations from scene text in tests. */
#ifndef SLUICE_TEST_SIM_UTIL_H
#define SLUICE_TEST_SIM_UTIL_H

#include "sim.h"
#include "sim_internal.h"
#include "test_util.h"

/* Writes `yaml` to a scratch file and loads it; fails the test with the
 * diagnostics when loading fails. */
static inline sluice_sim *test_load(const char *tag, const char *yaml, const char *const *sets,
                                    size_t set_count)
{
    char *dir = test_scratch(tag);
    ck_assert_ptr_nonnull(dir);
    char *path = test_write_file(dir, "scene.yaml", yaml);
    ck_assert_ptr_nonnull(path);
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {sets, set_count, 0, 0, 0};
    sluice_sim *sim = sluice_sim_load(path, &options, diag);
    if (!sim) {
        for (size_t i = 0; i < sluice_diag_count(diag); i++)
            fprintf(stderr, "%s\n", sluice_diag_message(diag, i));
    }
    ck_assert_msg(sim != NULL, "scene '%s' failed to load", tag);
    sluice_diag_destroy(diag);
    free(path);
    free(dir);
    return sim;
}

static inline sluice_real *test_column(sluice_sim *sim, const char *field, uint32_t component)
{
    sluice_field f;
    ck_assert_msg(sluice_sim_field(sim, field, &f) == SLUICE_OK, "no field '%s'", field);
    const sluice_view *v = sluice_sim_view(sim);
    return sluice_real_column(v, f, component);
}

#endif
