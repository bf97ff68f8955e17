/* Shared by the fuzz targets (fuzz_scene.c, fuzz_checkpoint.c). */
#ifndef SLUICE_FUZZ_PLUGINS_H
#define SLUICE_FUZZ_PLUGINS_H

/* The plugins are instrumented too; libFuzzer reads their coverage counters
 * after every input, so they must stay mapped when the core closes them.
 * Opens every plugin of SLUICE_PLUGIN_PATH once with RTLD_NODELETE (the
 * core's dlopen of the same file then only counts a reference); exits with
 * status 2 when the variable is not set. `target` names the caller in
 * messages. */
void fuzz_keep_plugins_mapped(const char *target);

#endif
