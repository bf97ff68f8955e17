/* Loading simulations from scene text in tests, through the embedding API
 * (sim.h) alone. A suite that reads the core's internals includes
 * sim_internal.h itself and says why. */
#ifndef SLUICE_TEST_SIM_UTIL_H
#define SLUICE_TEST_SIM_UTIL_H

#include "sim.h"
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
    sluice_load_options options = {.overrides = sets, .override_count = set_count};
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

/* Loads `yaml` expecting a refusal: fails the test when the scene loads or
 * when no error message contains `needle`. Prints the messages. */
static inline void test_load_refused(const char *tag, const char *yaml, const char *needle)
{
    char *dir = test_scratch(tag);
    ck_assert_ptr_nonnull(dir);
    char *path = test_write_file(dir, "scene.yaml", yaml);
    ck_assert_ptr_nonnull(path);
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options options = {0};
    sluice_sim *sim = sluice_sim_load(path, &options, diag);
    int found = 0;
    for (size_t i = 0; i < sluice_diag_count(diag); i++) {
        const char *message = sluice_diag_message(diag, i);
        fprintf(stderr, "%s: %s\n", tag, message);
        found |= strstr(message, needle) != NULL && strstr(message, "error") != NULL;
    }
    ck_assert_msg(sim == NULL, "%s: the scene loaded, expected an error with '%s'", tag, needle);
    ck_assert_msg(found, "%s: no error message contains '%s'", tag, needle);
    sluice_diag_destroy(diag);
    free(path);
    free(dir);
}

static inline sluice_real *test_column(sluice_sim *sim, const char *field, uint32_t component)
{
    sluice_field f;
    ck_assert_msg(sluice_sim_field(sim, field, &f) == SLUICE_OK, "no field '%s'", field);
    const sluice_view *v = sluice_sim_view(sim);
    return sluice_real_column(v, f, component);
}

#endif
