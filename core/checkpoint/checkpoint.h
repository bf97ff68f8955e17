/* Checkpoints and restart (docs/reliability.md): the only part of the core
 * that links HDF5. It reads and writes the engine's state; the engine reaches
 * it only through the services core/sim/ lends it. */
#ifndef SLUICE_CHECKPOINT_H
#define SLUICE_CHECKPOINT_H

#include <stddef.h>

typedef struct sluice_sim sluice_sim;

/* Checkpoints and restart (docs/reliability.md). sluice_sim_checkpoint
 * writes the complete state after the last whole step to `path` (HDF5,
 * atomically); with path NULL to DIR/checkpoint_<step>.h5 of the output
 * directory (and deletes the oldest beyond checkpoint.keep). Returns
 * SLUICE_OK or SLUICE_ERROR with the reason in sluice_sim_failure().
 * sluice_sim_restart replaces the freshly loaded state of `sim` (before
 * sluice_sim_begin/run) with the checkpoint's; it refuses a missing,
 * truncated or malformed file and one that does not match the scene
 * (dimensions, plugins, field layout) with one message naming the file in
 * `error`, and leaves `sim` unusable then. */
int sluice_sim_checkpoint(sluice_sim *sim, const char *path);
int sluice_sim_restart(sluice_sim *sim, const char *checkpoint, char *error, size_t error_size);

#endif
