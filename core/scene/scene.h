/* The scene file: the core's own sections (dimensions, particles, time,
 * domain, geometry, initial state, neighbour search, watchdog, plugin list),
 * validated against parameter tables like every plugin's parameters. */
#ifndef SLUICE_SCENE_H
#define SLUICE_SCENE_H

#include "arena.h"
#include "diag.h"
#include "geometry.h"
#include "sluice/plugin.h"
#include "yaml_tree.h"

typedef enum sluice_initial_density {
    SLUICE_INITIAL_HYDROSTATIC = 0,
    SLUICE_INITIAL_REST = 1
} sluice_initial_density;

typedef struct sluice_scene_fluid {
    sluice_region region;
    sluice_real velocity[3];
    int has_surface;
    sluice_real surface; /* free-surface level along the vertical (last) axis */
    int has_lattice_origin;
    sluice_real lattice_origin[3]; /* the region's lattice (particles.lattice_origin unless set) */
    const char *name; /* "" when the region has none */
    const sluice_node *node;
} sluice_scene_fluid;

typedef struct sluice_scene_wall {
    sluice_wall_geometry geometry;
    const char *scheme; /* NULL: the only loaded wall scheme */
    const char *name;
    sluice_real lattice_origin[3]; /* lattice of its particle layers */
    const sluice_node *node;
} sluice_scene_wall;

typedef struct sluice_scene_plugin {
    const char *name;      /* the instance: its key in `plugins` */
    const char *component; /* the component it loads: its `plugin` key, else `name` */
    const sluice_node *component_node; /* where the component is named (messages) */
    sluice_node *key;      /* the key node in `plugins` (position for messages) */
    sluice_node **section; /* slot of its parameter mapping in the tree */
} sluice_scene_plugin;

/* A variant the scene defines (top-level `variants`). */
typedef struct sluice_scene_variant {
    const char *name;
    const char *description; /* "" when none */
} sluice_scene_variant;

typedef struct sluice_scene {
    char *path;      /* as given */
    char *directory; /* absolute directory of the scene file */
    sluice_node *root;
    sluice_arena *arena;

    uint32_t dimensions;
    const char *title;
    struct {
        sluice_real spacing, smoothing_length_ratio, rest_density;
        sluice_real lattice_origin[3];
    } particles;
    struct {
        sluice_real end, max_step;
    } time;
    struct {
        sluice_real min[3], max[3];
        int periodic[3];
    } domain;
    sluice_initial_density initial_density;
    struct {
        sluice_real skin; /* fraction of the kernel support */
        int64_t batch_pairs;
    } neighbour_search;
    struct {
        sluice_real density_band; /* relative to the rest density */
        sluice_real min_time_step;
        sluice_real wall_penetration; /* in particle spacings */
        int64_t every;
    } watchdog;
    struct {
        sluice_real interval; /* s; 0: no periodic checkpoints */
        int64_t keep;         /* newest checkpoints kept; 0: all */
    } checkpoint;
    struct {
        int split;            /* axes cut into the ranks' boxes: bit d for axis d */
        int balance;          /* SLUICE_BALANCE_TIME, _COUNT or _NONE */
        int64_t every;        /* steps between balances */
        sluice_real tolerance; /* largest share over the mean, minus 1 */
    } ranks;
    char **plugin_path; /* absolute directories */
    size_t plugin_path_count;

    sluice_scene_fluid *fluids;
    size_t fluid_count;
    sluice_scene_wall *walls;
    size_t wall_count;
    sluice_scene_plugin *plugins;
    size_t plugin_count;
    const char *variant; /* the variant applied; NULL: the base scene */
    sluice_scene_variant *variants; /* every variant the file defines, in file order */
    size_t variant_count;
} sluice_scene;

/* Parses the file, applies the overrides ("dotted.key=value") and validates
 * the core sections. Returns 0, or the number of errors (messages in diag);
 * on error the scene may be partly filled and must still be freed. */
int sluice_scene_load(sluice_scene *scene, const char *path, const char *const *overrides,
                      size_t override_count, sluice_diag *diag);
/* The same with a variant: `variant` (NULL: the base scene) names an entry of
 * the file's top-level `variants`, applied before the overrides; the
 * `variants` key is taken out of the tree before validation and, when a
 * variant is applied, a top-level `variant: NAME` records it in its place
 * (docs/scene-format.md, Variants). */
int sluice_scene_load_variant(sluice_scene *scene, const char *path, const char *variant,
                              const char *const *overrides, size_t override_count,
                              sluice_diag *diag);
/* The command line's edits of a scene, applied after the variant: the
 * removals (dotted paths), then the swaps ("OLD=NEW": plugins entry OLD
 * replaced by plugin NEW with its defaults, walls handled by OLD handled by
 * NEW), then the overrides ("dotted.key=value"), each in order. */
typedef struct sluice_scene_edits {
    const char *const *removals;
    size_t removal_count;
    const char *const *swaps;
    size_t swap_count;
    const char *const *overrides;
    size_t override_count;
} sluice_scene_edits;
int sluice_scene_load_edited(sluice_scene *scene, const char *path, const char *variant,
                             const sluice_scene_edits *edits, sluice_diag *diag);
void sluice_scene_free(sluice_scene *scene);

/* Position helpers for messages about a node. */
const char *sluice_node_file(const sluice_node *node, const sluice_scene *scene);

/* The scene format's key tables, as the loader validates against them, for
 * describing the format (sluice inspect --schema). An entry is a section,
 * a shape of a fluid region or wall, or a piece of a profile; its specs hold
 * every key the loader accepts there (the `shape` or `piece` key among them,
 * an enumeration of all the list's shapes). A profile's `pieces` appears as
 * a placeholder spec: the loader reads it as a list of pieces. */
typedef struct sluice_scene_table {
    const char *name;
    const sluice_param_spec *specs; /* 2D, and 3D unless specs_3d */
    uint32_t count;
    const sluice_param_spec *specs_3d; /* NULL: as in 2D */
    uint32_t count_3d;
    uint32_t dimensions; /* SLUICE_DIMS_* where the loader accepts it */
} sluice_scene_table;

typedef struct sluice_scene_format {
    const char *const *top_level_keys; /* every key the loader accepts at the top */
    size_t top_level_count;
    const sluice_scene_table *sections; /* particles, time, domain, ... */
    size_t section_count;
    const sluice_scene_table *fluid_shapes;
    size_t fluid_shape_count;
    const sluice_scene_table *wall_shapes;
    size_t wall_shape_count;
    const sluice_scene_table *pieces;
    size_t piece_count;
    const char *const *variant_keys; /* the keys of one variant */
    size_t variant_key_count;
} sluice_scene_format;

const sluice_scene_format *sluice_scene_format_tables(void);

enum { SLUICE_BALANCE_TIME = 0, SLUICE_BALANCE_COUNT = 1, SLUICE_BALANCE_NONE = 2 };

#endif
