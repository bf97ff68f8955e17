/* The simulation as programs embed it (the sluice program, the tests, the
 * benchmarks): the engine with the services of the libraries above it
 * attached. This is the one place that knows both; the engine knows none of
 * them (docs/plugin-abi.md, "The core's layout"). */
#include "checkpoint.h"
#include "sim_internal.h"

static const sluice_sim_services services = {
    .checkpoint = sluice_sim_checkpoint,
};

sluice_sim *sluice_sim_load(const char *scene_path, const sluice_load_options *options,
                            sluice_diag *diag)
{
    return sluice_engine_load(scene_path, NULL, options, &services, diag);
}

sluice_sim *sluice_sim_load_variant(const char *scene_path, const char *variant,
                                    const sluice_load_options *options, sluice_diag *diag)
{
    return sluice_engine_load(scene_path, variant, options, &services, diag);
}
