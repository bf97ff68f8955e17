/* libFuzzer target: the scene loader and everything behind `sluice check`
 * (YAML parsing, the core's schema, plugin lookup and parameter validation,
 * plugin creation, geometry and the initial state), then two time steps
 * when the scene is valid. Any input must end in either a loaded scene or
 * diagnostics naming file:line:column; a crash, a sanitizer report, a leak
 * or a hang is a bug. Built by `tools/fuzz.sh` (clang, -fsanitize=fuzzer,
 * address, undefined); docs/reliability.md. */
#define _GNU_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "diag.h"
#include "fuzz_plugins.h"
#include "sim.h"

/* Scenes past this many particles are refused by the core before any
 * allocation (sluice_load_options.max_particles): the fuzzer looks for
 * wrong answers to bad input, not for large scenes. */
#define FUZZ_MAX_PARTICLES 4000.0

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

/* The plugins are instrumented too and must stay mapped (fuzz_plugins.h). */
int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_keep_plugins_mapped("fuzz_scene");
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[64];
    snprintf(path, sizeof path, "/tmp/sluice-fuzz-%ld.yaml", (long)getpid());
    FILE *f = fopen(path, "wb");
    if (!f)
        return 0;
    if (size && fwrite(data, 1, size, f) != size) {
        fclose(f);
        return 0;
    }
    fclose(f);
    sluice_diag *diag = sluice_diag_create();
    if (!diag)
        return 0;
    sluice_load_options options = {.threads = 1, .max_particles = FUZZ_MAX_PARTICLES};
    sluice_sim *sim = sluice_sim_load(path, &options, diag);
    if (sim) {
        /* a valid scene: a couple of steps through every loaded term, with
         * no output directory */
        if (sluice_sim_begin(sim, NULL) == 0) {
            int status = 0;
            for (int step = 0; step < 2 && status == 0; step++)
                status = sluice_sim_step(sim);
            sluice_sim_end(sim, status);
        }
        sluice_sim_free(sim);
    } else {
        /* every refusal says something, with a place */
        if (sluice_diag_error_count(diag) == 0)
            abort();
        for (size_t i = 0; i < sluice_diag_count(diag); i++)
            if (!sluice_diag_message(diag, i) || !*sluice_diag_message(diag, i))
                abort();
    }
    sluice_diag_destroy(diag);
    return 0;
}
