/* The output directory of `sluice run` (docs/reliability.md, "Output
 * directories"). */
#ifndef SLUICE_OUTPUT_DIR_H
#define SLUICE_OUTPUT_DIR_H

#include <stddef.h>

enum {
    SLUICE_OUTPUT_OK = 0,
    SLUICE_OUTPUT_REFUSED = 1, /* another live run, or an earlier run's outputs */
    SLUICE_OUTPUT_FAILED = 2   /* the directory cannot be made, read or cleared */
};

/* Makes dir, takes its lock (DIR/.sluice.lock, held until *lock_fd is
 * closed or the process ends) and, unless the run continues from a
 * checkpoint (restart), refuses a directory that holds another run's
 * outputs or, with overwrite, removes them first (run.json,
 * scene.resolved.yaml, *.h5, *.xmf, *.csv and analysis/; nothing else).
 * On failure writes one message to error. */
int sluice_output_dir_claim(const char *dir, int restart, int overwrite, int *lock_fd,
                            char *error, size_t size);

#endif
