/* libFuzzer target: the scene loader and everything behind `sluice check`
 * (YAML parsing, the core's schema, plugin lookup and parameter validation,
 * plugin creation, geometry and the initial state), then two time steps
 * when the scene is valid. Any input must end in either a loaded scene or
 * diagnostics naming file:line:column; a crash, a sanitizer report, a leak
 * or a hang is a bug. Built by `tools/fuzz.sh` (clang, -fsanitize=fuzzer,
 * address, undefined); docs/reliability.md. */
#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "diag.h"
#include "sim.h"

/* Scenes past this many particles are refused by the core before any
 * allocation (sluice_load_options.max_particles): the fuzzer looks for
 * wrong answers to bad input, not for large scenes. */
#define FUZZ_MAX_PARTICLES 4000.0

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

/* The plugins are instrumented too; libFuzzer reads their coverage counters
 * after every input, so they must stay mapped when the core closes them.
 * Opening each once here with RTLD_NODELETE keeps them loaded (the core's
 * dlopen of the same file then only counts a reference). */
int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    const char *directory = getenv("SLUICE_PLUGIN_PATH");
    DIR *d = directory ? opendir(directory) : NULL;
    if (!d) {
        fprintf(stderr, "fuzz_scene: set SLUICE_PLUGIN_PATH to the build's plugin directory\n");
        exit(2);
    }
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 4 || strcmp(e->d_name + n - 3, ".so") != 0)
            continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", directory, e->d_name);
        if (!dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE))
            fprintf(stderr, "fuzz_scene: %s\n", dlerror());
    }
    closedir(d);
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
