/* Diagnostics: every problem with the input is collected as one message
 * "file:line:column: error: text" and reported together. */
#ifndef SLUICE_DIAG_H
#define SLUICE_DIAG_H

#include <stddef.h>
#include <stdio.h>

#include "sluice/plugin.h"

typedef enum sluice_severity { SLUICE_SEVERITY_ERROR = 0, SLUICE_SEVERITY_WARNING = 1 } sluice_severity;

typedef struct sluice_diag sluice_diag;

sluice_diag *sluice_diag_create(void);
void sluice_diag_destroy(sluice_diag *diag);

/* Adds one message. file may be NULL (then only the text is printed);
 * line/column are 1-based, 0 when unknown (then omitted). */
void sluice_diag_add(sluice_diag *diag, sluice_severity severity, const char *file, int line,
                     int column, const char *format, ...) SLUICE_PRINTF(6, 7);

size_t sluice_diag_count(const sluice_diag *diag);
size_t sluice_diag_error_count(const sluice_diag *diag);
/* Errors for want of resources rather than bad input: the machine's memory
 * cannot hold the scene (sluice_diag_mark_resources) or an allocation
 * failed (any error whose text says "out of memory"). `sluice run` and
 * `sluice check` then exit 4, not 2. */
void sluice_diag_mark_resources(sluice_diag *diag);
int sluice_diag_resources(const sluice_diag *diag);
/* The i-th formatted message, "file:line:col: error: text". */
const char *sluice_diag_message(const sluice_diag *diag, size_t index);
/* Prints every message, one per line, in the order they were added. */
void sluice_diag_print(const sluice_diag *diag, FILE *stream);
void sluice_diag_clear(sluice_diag *diag);

#endif
