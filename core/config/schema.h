/* Validation of a YAML mapping against a parameter table (sluice_param_spec),
 * used for every plugin's parameters and for the core's own scene sections. */
#ifndef SLUICE_SCHEMA_H
#define SLUICE_SCHEMA_H

#include "arena.h"
#include "diag.h"
#include "sluice/plugin.h"
#include "yaml_tree.h"

/* Validates *section (a mapping, or NULL when absent) against specs and fills
 * `config` (a zeroed struct laid out as the specs' offsets say).
 *  - unknown keys: error at the key, with the closest valid name suggested;
 *  - wrong type, out of range, wrong vector length, bad enum choice: error at
 *    the value, naming `path`.key, the expected type/range and the unit;
 *  - missing required parameter: error at `owner` (the node that should have
 *    contained it; may be NULL);
 *  - absent parameters with defaults: the default is parsed and also inserted
 *    into the tree (creating *section when it was NULL) so that the resolved
 *    scene shows it.
 * `dimensions` resolves SLUICE_LENGTH_DIM. Strings and lists are allocated in
 * `arena`. Every key of the section is marked used. Returns the number of
 * errors added to diag (0 on success). */
int sluice_schema_bind(const sluice_param_spec *specs, uint32_t spec_count, sluice_node **section,
                       const sluice_node *owner, const char *path, uint32_t dimensions,
                       void *config, sluice_arena *arena, sluice_diag *diag);
/* As sluice_schema_bind, with one key of the section (`reserved`, e.g. the
 * `plugin` of a plugin instance) left to the caller: not reported unknown. */
int sluice_schema_bind_except(const sluice_param_spec *specs, uint32_t spec_count,
                              sluice_node **section, const sluice_node *owner, const char *path,
                              uint32_t dimensions, void *config, sluice_arena *arena,
                              sluice_diag *diag, const char *reserved);

/* Scalar conversions with the same rules as the binder (strict: the whole
 * text must be a finite number / integer / boolean). 0 on success. */
int sluice_parse_real(const char *text, double *out);
int sluice_parse_int(const char *text, long long *out);
int sluice_parse_bool(const char *text, int *out);

/* Human-readable type of a spec, e.g. "number in [1, 10] (1)", for messages and
 * for `sluice inspect`. Writes into buffer; returns buffer. */
const char *sluice_schema_describe(const sluice_param_spec *spec, char *buffer, size_t size);

#endif
