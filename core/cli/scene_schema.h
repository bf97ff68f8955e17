/* sluice inspect --schema: a JSON Schema (draft-07) of scene files, made from
 * the core's key tables (core/scene) and the parameter tables of the plugins
 * on the plugin path (docs/scene-format.md, "Schema for editors"). */
#ifndef SLUICE_SCENE_SCHEMA_H
#define SLUICE_SCENE_SCHEMA_H

#include <stdio.h>

/* Writes the schema to out, whole or not at all. 0 on success; -1 after a
 * message on stderr (out of memory, a scene key the generator cannot
 * describe, a parameter table it cannot read). */
int sluice_scene_schema(FILE *out);

#endif
