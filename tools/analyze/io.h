/* I/O of sluice-analyze: CSV tables, the resolved scene (libyaml), output
 * directories, gnuplot. The numerical functions are in hydraulics.h. */
#ifndef SLUICE_ANALYZE_IO_H
#define SLUICE_ANALYZE_IO_H

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

/* Exit statuses: 0 measured, 1 the data do not contain the feature (e.g. no
 * jump toe in the window), 2 bad input (usage, missing file or column). */
enum { SLUICE_ANALYZE_OK = 0, SLUICE_ANALYZE_NOT_FOUND = 1, SLUICE_ANALYZE_BAD_INPUT = 2 };

/* Error state of one invocation: the first message wins. */
typedef struct analyze_ctx {
    char message[1024];
    int status;
} analyze_ctx;

/* Records the error (if none yet) with its exit status; returns -1. */
int analyze_fail(analyze_ctx *cx, int status, const char *format, ...)
    __attribute__((format(printf, 3, 4)));

/* calloc that records "out of memory" on failure. */
void *analyze_alloc(analyze_ctx *cx, size_t count, size_t size);

/* A numeric CSV file: header names, rows x cols values (row-major). Lines
 * starting with '#' and blank lines are skipped; "nan" parses as NaN. */
typedef struct analyze_table {
    char *path;
    size_t cols, rows;
    char **names;
    double *data;
} analyze_table;

int analyze_table_load(analyze_ctx *cx, const char *path, analyze_table *table);
void analyze_table_free(analyze_table *table);
/* Index of a column, or -1 (no error recorded). */
long analyze_table_find(const analyze_table *table, const char *name);
/* Index of a column; records "PATH has no column 'NAME'" when absent. */
long analyze_table_column(analyze_ctx *cx, const analyze_table *table, const char *name);
/* Copies column c into out[0..rows). */
void analyze_table_copy(const analyze_table *table, size_t c, double *out);

/* The resolved scene: plugins.<plugin>.<key> as a list of numbers (a flat
 * sequence) or of points (a sequence of sequences, `dims` numbers each).
 * Returns the count (0 when absent), -1 on a parse error (recorded). */
typedef struct analyze_scene analyze_scene;
int analyze_scene_load(analyze_ctx *cx, const char *path, analyze_scene **scene);
void analyze_scene_free(analyze_scene *scene);
/* geometry.<kind>[index]'s corners (kind "fluid" or "walls"; a region with
 * min and max): 0, or -1 when absent. */
int analyze_scene_region(const analyze_scene *scene, const char *kind, size_t index,
                         double min[3], double max[3]);
long analyze_scene_numbers(analyze_ctx *cx, const analyze_scene *scene, const char *plugin,
                           const char *key, double **values);
long analyze_scene_points(analyze_ctx *cx, const analyze_scene *scene, const char *plugin,
                          const char *key, double **xs, double **ys);
/* plugins.<plugin>.<key> as a string, or NULL. */
const char *analyze_scene_string(const analyze_scene *scene, const char *plugin, const char *key);
/* plugins.PLUGIN.KEY as a number: 0 with *value set, -1 when absent or not a
 * number. */
int analyze_scene_number(const analyze_scene *scene, const char *plugin, const char *key,
                         double *value);
/* A top-level setting SECTION.KEY (e.g. particles.spacing) as a number: 0
 * with *value set, -1 when absent or not a number. */
int analyze_scene_setting(const analyze_scene *scene, const char *section, const char *key,
                          double *value);
/* Whether plugins.<plugin> exists. */
int analyze_scene_has(const analyze_scene *scene, const char *plugin);

/* Parses "a,b,c" into numbers; -1 with an error recorded when malformed. */
long analyze_parse_list(analyze_ctx *cx, const char *option, const char *text, double **values);
/* Parses "x,y;x,y;..." into points. */
long analyze_parse_points(analyze_ctx *cx, const char *option, const char *text, double **xs,
                          double **ys);

/* Creates a directory and its parents. */
int analyze_mkdir(analyze_ctx *cx, const char *path);
int analyze_file_exists(const char *path);
/* asprintf that records "out of memory" on failure. */
char *analyze_format(analyze_ctx *cx, const char *format, ...)
    __attribute__((format(printf, 2, 3)));

/* Writes a gnuplot script NAME.gp into dir and runs it with gnuplot (popen),
 * producing NAME.png there; the body runs with dir as the working directory
 * and the CSV separator set to ','. When gnuplot is not installed, prints a
 * note to stderr and returns 0. Returns 0 unless the script cannot be
 * written (gnuplot's own failures are reported on stderr, not fatal). */
int analyze_plot(analyze_ctx *cx, const char *dir, const char *name, const char *body);

#endif
