/* sluice-analyze: hydraulic-jump measurements from Sluice's gauge output, the
 * way hydraulic engineers take them (docs/analysis.md).
 *
 *   sluice-analyze belanger --d1 D (--v1 V | --fr F)
 *   sluice-analyze conjugate RUN --d1 D --v1 V --x X [--from T0 --to T1]
 *   sluice-analyze toe       RUN --d1 D --v1 V [--fraction F]
 *   sluice-analyze roller    RUN --d1 D --v1 V [--x1 X1]
 *   sluice-analyze vmax      RUN --d1 D --v1 V [--x1 X1]
 *   sluice-analyze surface   RUN --d1 D --v1 V [--x1 X1]
 *   sluice-analyze spectrum  RUN --column NAME [--d1 D --v1 V]
 *   sluice-analyze correlate A.csv:COL B.csv:COL
 *   sluice-analyze l2        RUN --reference REF.csv [--time T ...]
 *   sluice-analyze front     RUN --reference REF.csv [--shift DT] [--width A]
 *   sluice-analyze classify  --y1 Y1 --yt YT --v1 V --drop S
 *   sluice-analyze drop-type RUN [--drop-x X] [--drop S]
 *   sluice-analyze step-profiles RUN|POINTS.csv --per-line N --edges x,y;.. --theta DEG
 *                                --dc DC --uc UC
 *   sluice-analyze dissolved-oxygen POINTS.csv --per-line N --cs CS --cu CU
 *                                [--calibrate STATION --target C]
 *
 * Each prints its headline figures as `name = value [unit]` lines, writes a
 * CSV and (gnuplot permitting) a PNG into --out (default RUN/analysis);
 * step-profiles given a CSV file and dissolved-oxygen print their CSV on
 * stdout instead.
 * Exit status: 0 measured, 1 the feature is absent from the data, 2 bad
 * input (one message on stderr). The numbers come from hydraulics.c. */
#define _GNU_SOURCE
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "hydraulics.h"
#include "io.h"

#define MAX_TIMES 64
#define MAX_POSITIONAL 4

typedef struct options {
    const char *command;
    const char *positional[MAX_POSITIONAL];
    size_t positional_count;
    double d1, v1, fr, g, x, from, to, fraction, x1, bed, drop, y1, yt, min_wet, fmin, fmax,
        tolerance, drop_x, wave_min, per_line, theta, dc, uc, threshold, h, first_step, cs, cu,
        calibrate, target, width, shift, series, arrival, duration, scale, time_scale, force,
        viscosity;
    const char *column, *reference, *out, *positions, *points, *field, *edges, *time_column;
    double times[MAX_TIMES];
    size_t time_count;
    int no_plot;
} options;

enum { OPT_NUMBER, OPT_STRING, OPT_TIMES, OPT_FLAG };

static const struct option_spec {
    const char *name;
    int kind;
    size_t offset;
} option_specs[] = {
    {"d1", OPT_NUMBER, offsetof(options, d1)},
    {"v1", OPT_NUMBER, offsetof(options, v1)},
    {"fr", OPT_NUMBER, offsetof(options, fr)},
    {"g", OPT_NUMBER, offsetof(options, g)},
    {"x", OPT_NUMBER, offsetof(options, x)},
    {"from", OPT_NUMBER, offsetof(options, from)},
    {"to", OPT_NUMBER, offsetof(options, to)},
    {"fraction", OPT_NUMBER, offsetof(options, fraction)},
    {"x1", OPT_NUMBER, offsetof(options, x1)},
    {"bed", OPT_NUMBER, offsetof(options, bed)},
    {"drop", OPT_NUMBER, offsetof(options, drop)},
    {"y1", OPT_NUMBER, offsetof(options, y1)},
    {"yt", OPT_NUMBER, offsetof(options, yt)},
    {"min-wet", OPT_NUMBER, offsetof(options, min_wet)},
    {"fmin", OPT_NUMBER, offsetof(options, fmin)},
    {"fmax", OPT_NUMBER, offsetof(options, fmax)},
    {"tolerance", OPT_NUMBER, offsetof(options, tolerance)},
    {"drop-x", OPT_NUMBER, offsetof(options, drop_x)},
    {"wave-min", OPT_NUMBER, offsetof(options, wave_min)},
    {"per-line", OPT_NUMBER, offsetof(options, per_line)},
    {"theta", OPT_NUMBER, offsetof(options, theta)},
    {"dc", OPT_NUMBER, offsetof(options, dc)},
    {"uc", OPT_NUMBER, offsetof(options, uc)},
    {"threshold", OPT_NUMBER, offsetof(options, threshold)},
    {"h", OPT_NUMBER, offsetof(options, h)},
    {"first-step", OPT_NUMBER, offsetof(options, first_step)},
    {"cs", OPT_NUMBER, offsetof(options, cs)},
    {"cu", OPT_NUMBER, offsetof(options, cu)},
    {"calibrate", OPT_NUMBER, offsetof(options, calibrate)},
    {"width", OPT_NUMBER, offsetof(options, width)},
    {"shift", OPT_NUMBER, offsetof(options, shift)},
    {"series", OPT_NUMBER, offsetof(options, series)},
    {"target", OPT_NUMBER, offsetof(options, target)},
    {"arrival", OPT_NUMBER, offsetof(options, arrival)},
    {"force", OPT_NUMBER, offsetof(options, force)},
    {"viscosity", OPT_NUMBER, offsetof(options, viscosity)},
    {"duration", OPT_NUMBER, offsetof(options, duration)},
    {"scale", OPT_NUMBER, offsetof(options, scale)},
    {"time-scale", OPT_NUMBER, offsetof(options, time_scale)},
    {"time-column", OPT_STRING, offsetof(options, time_column)},
    {"edges", OPT_STRING, offsetof(options, edges)},
    {"column", OPT_STRING, offsetof(options, column)},
    {"reference", OPT_STRING, offsetof(options, reference)},
    {"out", OPT_STRING, offsetof(options, out)},
    {"positions", OPT_STRING, offsetof(options, positions)},
    {"points", OPT_STRING, offsetof(options, points)},
    {"field", OPT_STRING, offsetof(options, field)},
    {"time", OPT_TIMES, 0},
    {"no-plot", OPT_FLAG, offsetof(options, no_plot)},
};

static const char usage[] =
    "usage: sluice-analyze COMMAND [ARGS] [OPTIONS]\n"
    "       sluice-analyze COMMAND --help, or help COMMAND: the options COMMAND reads\n"
    "  belanger  --d1 D (--v1 V | --fr F)          Belanger's conjugate depth\n"
    "  conjugate RUN --d1 --v1 --x X               d2(t) at x, seed 000's A and P\n"
    "  toe       RUN --d1 --v1 [--fraction 0.5]   jump toe x1(t) from the free surface\n"
    "  roller    RUN --d1 --v1 [--x1]             roller length vs Hager et al. (1990)\n"
    "  vmax      RUN --d1 --v1 [--x1]             Vmax/V1 decay vs Chanson (2010)\n"
    "  surface   RUN --d1 --v1 [--x1]             free-surface mean/std vs Murzyn & Chanson\n"
    "  spectrum  RUN --column [FILE:]NAME          amplitude spectrum, Strouhal number\n"
    "  correlate A.csv:COL B.csv:COL               Pearson r (seed 004)\n"
    "  profile   RUN [--column FILE:SUFFIX] [--force F --viscosity NU --width L]\n"
    "                                              a point_gauge line's time-mean profile:\n"
    "                                              wall slip, error against Poiseuille\n"
    "  impact    RUN --column [FILE:]NAME --arrival P [--duration D] [--scale P0]\n"
    "            [--time-scale T0] [--time-column t]\n"
    "                                              an impact on a pressure sensor: arrival,\n"
    "                                              peak, rise time, impulse\n"
    "  l2        RUN --reference REF.csv [--time]  free-surface L2 error, RMSE (seed 002)\n"
    "  front     RUN --reference REF.csv [--shift DT] [--width A] [--series A_IN]\n"
    "                                              dam-break front vs Martin & Moyce: raw,\n"
    "                                              shifted and best-fit time origin\n"
    "  classify  --y1 --yt --v1 --drop S           jump at an abrupt drop (momentum limits)\n"
    "  drop-type RUN [--drop-x X] [--drop S] [--wave-min 0.1]\n"
    "                                              jump type at an abrupt drop from a run\n"
    "  momentum  RUN                               mean momentum function M + P per section\n"
    "                                              (section_gauge with forces: true)\n"
    "  step-profiles RUN|POINTS.csv --per-line N --edges x,y;x,y.. --theta DEG --dc DC --uc UC\n"
    "            [--first-step 1] [--threshold 0.05] [--h H] [--points x,y;..]\n"
    "                                              U/Uc, air concentration, Y90, surface,\n"
    "                                              inception on a stepped chute (CSV on\n"
    "                                              stdout given POINTS.csv)\n"
    "  dissolved-oxygen POINTS.csv --per-line N --cs CS --cu CU [--calibrate S --target C]\n"
    "            [--field dissolved_oxygen]        DO per station of N points, the\n"
    "                                              reaeration rate, the source's scale\n"
    "                                              calibrated on one station (CSV on stdout)\n"
    "options: --from T0 --to T1 (window, s), --out DIR (default RUN/analysis), --g 9.81,\n"
    "  --bed B (bed elevation, m), --positions a,b,.. --points x,y;x,y.. (instead of\n"
    "  RUN/scene.resolved.yaml), --field velocity, --min-wet 0.5, --fmin, --fmax,\n"
    "  --tolerance 1e-6 (m, position matching), --no-plot. Details: docs/analysis.md\n";

/* ----------------------------------------------------------- utilities -- */

static void headline(const char *name, double value, const char *unit)
{
    printf("%s = %.6g%s%s\n", name, value, unit ? " " : "", unit ? unit : "");
}

/* 1 when the command's usage names --NAME (the options it reads). */
static int reads_option(const char *help, const char *name)
{
    const size_t len = strlen(name);
    for (const char *p = strstr(help, "--"); p; p = strstr(p + 2, "--")) {
        const char end = p[2 + len];
        if (strncmp(p + 2, name, len) == 0 &&
            !((end >= 'a' && end <= 'z') || (end >= '0' && end <= '9') || end == '-' ||
              end == '_'))
            return 1;
    }
    return 0;
}

/* Options of option_specs. One the command's usage `help` does not name has
 * no effect: a warning says so (sluice study passes --from, --to and --out
 * to every measure, read or not, and discards the warning). */
static int parse_options(analyze_ctx *cx, int argc, char **argv, options *o, const char *help)
{
    for (int i = 2; i < argc; i++) {
        const char *arg = argv[i];
        if (strncmp(arg, "--", 2) != 0) {
            if (o->positional_count == MAX_POSITIONAL)
                return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "too many arguments ('%s')",
                                    arg);
            o->positional[o->positional_count++] = arg;
            continue;
        }
        const char *name = arg + 2, *eq = strchr(name, '=');
        size_t len = eq ? (size_t)(eq - name) : strlen(name);
        const struct option_spec *spec = NULL;
        for (size_t k = 0; k < sizeof option_specs / sizeof *option_specs; k++)
            if (strlen(option_specs[k].name) == len &&
                strncmp(option_specs[k].name, name, len) == 0)
                spec = &option_specs[k];
        if (!spec)
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "unknown option %.*s (sluice-analyze --help lists them)",
                                (int)len + 2, arg);
        if (!reads_option(help, spec->name))
            fprintf(stderr,
                    "sluice-analyze: warning: '%s' does not read --%s: it has no effect "
                    "(sluice-analyze %s --help lists what it reads)\n",
                    o->command, spec->name, o->command);
        if (spec->kind == OPT_FLAG) {
            if (eq)
                return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--%s takes no value",
                                    spec->name);
            *(int *)((char *)o + spec->offset) = 1;
            continue;
        }
        const char *value = eq ? eq + 1 : (i + 1 < argc ? argv[++i] : NULL);
        if (!value)
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--%s needs a value", spec->name);
        if (spec->kind == OPT_STRING) {
            *(const char **)((char *)o + spec->offset) = value;
            continue;
        }
        char *end;
        double v = strtod(value, &end);
        if (end == value || *end != '\0' || !isfinite(v))
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--%s expects a number, got '%s'",
                                spec->name, value);
        if (spec->kind == OPT_TIMES) {
            if (o->time_count == MAX_TIMES)
                return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "at most %d --time options",
                                    MAX_TIMES);
            o->times[o->time_count++] = v;
        } else {
            *(double *)((char *)o + spec->offset) = v;
        }
    }
    return 0;
}

static int need(analyze_ctx *cx, const options *o, double value, const char *name,
                int positive)
{
    if (isnan(value))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s needs --%s", o->command, name);
    if (positive && !(value > 0.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--%s must be positive", name);
    return 0;
}

/* Fr1 and V1 from --d1 and --v1 or --fr. */
static int inflow(analyze_ctx *cx, const options *o, double *fr1, double *v1)
{
    if (need(cx, o, o->d1, "d1", 1) != 0)
        return -1;
    if (!(o->g > 0.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--g must be positive");
    if (!isnan(o->v1)) {
        if (!(o->v1 > 0.0))
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--v1 must be positive");
        *v1 = o->v1;
        *fr1 = sluice_hyd_froude(o->v1, o->d1, o->g);
        if (!isnan(o->fr) && fabs(o->fr - *fr1) > 1e-3 * *fr1)
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "--fr %g contradicts --v1/--d1 (Fr1 = %g): give one", o->fr,
                                *fr1);
        return 0;
    }
    if (isnan(o->fr))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s needs --v1 (or --fr)", o->command);
    if (!(o->fr > 1.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "--fr must exceed 1 (supercritical inflow)");
    *fr1 = o->fr;
    *v1 = o->fr * sqrt(o->g * o->d1);
    return 0;
}

static const char *run_dir(analyze_ctx *cx, const options *o)
{
    if (o->positional_count != 1) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s needs one run directory, RUN",
                     o->command);
        return NULL;
    }
    return o->positional[0];
}

/* The output directory: --out, else RUN/analysis (created). */
static char *out_dir(analyze_ctx *cx, const options *o, const char *run)
{
    char *dir = o->out ? analyze_format(cx, "%s", o->out)
                       : analyze_format(cx, "%s/analysis", run);
    if (dir && analyze_mkdir(cx, dir) != 0) {
        free(dir);
        return NULL;
    }
    return dir;
}

static FILE *open_csv(analyze_ctx *cx, const char *dir, const char *name, char **path)
{
    *path = analyze_format(cx, "%s/%s", dir, name);
    if (!*path)
        return NULL;
    FILE *f = fopen(*path, "w");
    if (!f)
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "cannot write %s", *path);
    return f;
}

static int close_csv(analyze_ctx *cx, FILE *f, char *path)
{
    int bad = ferror(f);
    bad |= fclose(f) != 0;
    if (bad)
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "cannot write %s", path);
    else
        printf("wrote %s\n", path);
    free(path);
    return bad ? -1 : 0;
}

static void plot(analyze_ctx *cx, const options *o, const char *dir, const char *name,
                 const char *body)
{
    if (!o->no_plot && body)
        analyze_plot(cx, dir, name, body);
}

/* ------------------------------------------------------- run contents -- */

typedef struct run_data {
    const char *run;
    analyze_scene *scene; /* NULL when RUN has no scene.resolved.yaml */
} run_data;

static int run_open(analyze_ctx *cx, const char *run, run_data *r)
{
    r->run = run;
    r->scene = NULL;
    struct stat st;
    if (stat(run, &st) != 0 || !S_ISDIR(st.st_mode))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "run directory %s does not exist", run);
    char *path = analyze_format(cx, "%s/scene.resolved.yaml", run);
    if (!path)
        return -1;
    int status = 0;
    if (analyze_file_exists(path))
        status = analyze_scene_load(cx, path, &r->scene);
    free(path);
    return status;
}

/* RUN/<the gauge's file> (plugins.<gauge>.file, else the default name). */
static char *gauge_path(analyze_ctx *cx, const run_data *r, const char *gauge,
                        const char *default_file)
{
    const char *file = analyze_scene_string(r->scene, gauge, "file");
    return analyze_format(cx, "%s/%s", r->run, file ? file : default_file);
}

/* Gauge positions: --positions, else plugins.<gauge>.positions. */
static long gauge_positions(analyze_ctx *cx, const options *o, const run_data *r,
                            const char *gauge, double **xs)
{
    if (o->positions)
        return analyze_parse_list(cx, "--positions", o->positions, xs);
    if (!r->scene)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%s/scene.resolved.yaml not found: give the %s positions with "
                            "--positions",
                            r->run, gauge);
    long n = analyze_scene_numbers(cx, r->scene, gauge, "positions", xs);
    if (n == 0)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%s/scene.resolved.yaml has no plugins.%s.positions", r->run, gauge);
    return n;
}

static long gauge_points(analyze_ctx *cx, const options *o, const run_data *r, double **xs,
                         double **ys)
{
    if (o->points)
        return analyze_parse_points(cx, "--points", o->points, xs, ys);
    if (!r->scene)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%s/scene.resolved.yaml not found: give the point_gauge points "
                            "with --points",
                            r->run);
    long n = analyze_scene_points(cx, r->scene, "point_gauge", "points", xs, ys);
    if (n == 0)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%s/scene.resolved.yaml has no plugins.point_gauge.points", r->run);
    return n;
}

/* A gauge table with its time column and the rows in [from, to]. */
typedef struct gauge_table {
    analyze_table table;
    double *time;
    size_t first, last; /* window rows first .. last-1 */
} gauge_table;

static int gauge_table_load(analyze_ctx *cx, const options *o, const char *path, gauge_table *g)
{
    memset(g, 0, sizeof *g);
    if (analyze_table_load(cx, path, &g->table) != 0)
        return -1;
    long tc = analyze_table_column(cx, &g->table, o->time_column ? o->time_column : "time");
    if (tc < 0)
        return -1;
    if (g->table.rows == 0)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s has no data rows", path);
    g->time = analyze_alloc(cx, g->table.rows, sizeof *g->time);
    if (!g->time)
        return -1;
    analyze_table_copy(&g->table, (size_t)tc, g->time);
    for (size_t r = 1; r < g->table.rows; r++)
        if (!(g->time[r] > g->time[r - 1]))
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "%s: time is not increasing at data row %zu", path, r + 1);
    g->first = g->table.rows;
    g->last = 0;
    for (size_t r = 0; r < g->table.rows; r++)
        if (g->time[r] >= o->from && g->time[r] <= o->to) {
            if (g->first == g->table.rows)
                g->first = r;
            g->last = r + 1;
        }
    if (g->first >= g->last)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%s has no rows in the window [%g, %g] s (data: %g to %g s)", path,
                            o->from, o->to, g->time[0], g->time[g->table.rows - 1]);
    return 0;
}

static void gauge_table_free(gauge_table *g)
{
    analyze_table_free(&g->table);
    free(g->time);
}

static double cell(const gauge_table *g, size_t row, size_t col)
{
    return g->table.data[row * g->table.cols + col];
}

static void print_window(const gauge_table *g)
{
    printf("window = [%.6g, %.6g] s\n", g->time[g->first], g->time[g->last - 1]);
    printf("samples = %zu\n", g->last - g->first);
}

/* Columns PREFIX<k> for k = 0..n-1 (e.g. eta_x0, eta_x1, ...). */
static int gauge_columns(analyze_ctx *cx, const gauge_table *g, const char *prefix, size_t n,
                         size_t *cols)
{
    for (size_t k = 0; k < n; k++) {
        char name[64];
        snprintf(name, sizeof name, "%s%zu", prefix, k);
        long c = analyze_table_column(cx, &g->table, name);
        if (c < 0)
            return -1;
        cols[k] = (size_t)c;
    }
    return 0;
}

/* Index k of the position equal to x within the tolerance, or -1. */
static long position_index(const double *xs, size_t n, double x, double tolerance)
{
    for (size_t k = 0; k < n; k++)
        if (fabs(xs[k] - x) <= tolerance)
            return (long)k;
    return -1;
}

/* ---------------------------------------------------- the free surface -- */

/* The free-surface gauges sorted upstream to downstream: positions x[j] and
 * their columns. */
typedef struct surface_gauges {
    gauge_table g;
    size_t n;
    double *x;
    size_t *col;
} surface_gauges;

static void surface_free(surface_gauges *s)
{
    gauge_table_free(&s->g);
    free(s->x);
    free(s->col);
}

static int surface_load(analyze_ctx *cx, const options *o, const run_data *r, surface_gauges *s)
{
    memset(s, 0, sizeof *s);
    double *xs = NULL;
    long n = gauge_positions(cx, o, r, "free_surface_gauge", &xs);
    if (n < 0)
        return -1;
    char *path = gauge_path(cx, r, "free_surface_gauge", "free_surface.csv");
    int status = path ? gauge_table_load(cx, o, path, &s->g) : -1;
    free(path);
    size_t *cols = status == 0 ? analyze_alloc(cx, (size_t)n, sizeof *cols) : NULL;
    if (!cols || gauge_columns(cx, &s->g, "eta_x", (size_t)n, cols) != 0) {
        free(xs);
        free(cols);
        return -1;
    }
    s->n = (size_t)n;
    s->x = analyze_alloc(cx, s->n, sizeof *s->x);
    s->col = analyze_alloc(cx, s->n, sizeof *s->col);
    if (!s->x || !s->col) {
        free(xs);
        free(cols);
        return -1;
    }
    /* insertion sort by x (tens of gauges) */
    for (size_t k = 0; k < s->n; k++) {
        size_t j = k;
        while (j > 0 && s->x[j - 1] > xs[k]) {
            s->x[j] = s->x[j - 1];
            s->col[j] = s->col[j - 1];
            j--;
        }
        s->x[j] = xs[k];
        s->col[j] = cols[k];
    }
    free(xs);
    free(cols);
    for (size_t k = 1; k < s->n; k++)
        if (!(s->x[k] > s->x[k - 1]))
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "two free-surface gauges at x = %g", s->x[k]);
    return 0;
}

/* x1(t) for every row of the free-surface table (NaN: no toe in the row). */
static int toe_series(analyze_ctx *cx, const options *o, const surface_gauges *s, double fr1,
                      double *threshold, double *x1)
{
    if (!(o->fraction > 0.0 && o->fraction < 1.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--fraction must be in (0, 1)");
    double d2 = sluice_hyd_belanger_depth(o->d1, fr1);
    *threshold = o->d1 + o->fraction * (d2 - o->d1);
    double *depth = analyze_alloc(cx, s->n, sizeof *depth);
    if (!depth)
        return -1;
    for (size_t r = 0; r < s->g.table.rows; r++) {
        for (size_t k = 0; k < s->n; k++)
            depth[k] = cell(&s->g, r, s->col[k]) - o->bed;
        x1[r] = sluice_hyd_toe_position(s->x, depth, s->n, *threshold);
    }
    free(depth);
    return 0;
}

/* x1 for roller, vmax and surface: --x1, else the mean toe over the window. */
static int resolve_x1(analyze_ctx *cx, const options *o, const run_data *r, double fr1,
                      double *x1)
{
    if (!isnan(o->x1)) {
        *x1 = o->x1;
        printf("x1 = %.6g m (given)\n", *x1);
        return 0;
    }
    surface_gauges s;
    if (surface_load(cx, o, r, &s) != 0) {
        surface_free(&s);
        return -1;
    }
    double *series = analyze_alloc(cx, s.g.table.rows, sizeof *series), threshold;
    int status = series ? toe_series(cx, o, &s, fr1, &threshold, series) : -1;
    double mean = NAN, std;
    size_t used = 0;
    if (status == 0 &&
        sluice_hyd_mean_std(series + s.g.first, s.g.last - s.g.first, &mean, &std, &used) != 0)
        status = analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                              "no jump toe in the free surface over the window (threshold "
                              "depth %g m): give --x1",
                              threshold);
    if (status == 0) {
        *x1 = mean;
        printf("x1 = %.6g m (mean toe over %zu of %zu rows)\n", mean, used,
               s.g.last - s.g.first);
    }
    free(series);
    surface_free(&s);
    return status;
}

/* -------------------------------------------------------- the commands -- */

static int cmd_belanger(analyze_ctx *cx, const options *o)
{
    double fr1, v1;
    if (inflow(cx, o, &fr1, &v1) != 0)
        return -1;
    double d2 = sluice_hyd_belanger_depth(o->d1, fr1);
    headline("Fr1", fr1, NULL);
    headline("V1", v1, "m/s");
    headline("d1", o->d1, "m");
    headline("d2", d2, "m");
    headline("d2/d1", d2 / o->d1, NULL);
    if (!o->out)
        return 0;
    if (analyze_mkdir(cx, o->out) != 0)
        return -1;
    char *path;
    FILE *f = open_csv(cx, o->out, "belanger.csv", &path);
    if (!f) {
        free(path);
        return -1;
    }
    fprintf(f, "d1,V1,Fr1,d2,d2_over_d1\n%.10g,%.10g,%.10g,%.10g,%.10g\n", o->d1, v1, fr1, d2,
            d2 / o->d1);
    if (close_csv(cx, f, path) != 0)
        return -1;
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel 'Fr1'\nset ylabel 'd2/d1'\nset key top left\n"
             "plot [1:%g] (sqrt(1+8*x**2)-1)/2 title 'Belanger (seed 000 eq. 1)', "
             "'belanger.csv' using 3:5 skip 1 with points pt 7 ps 1.5 title 'this jump'\n",
             fmax(10.0, 1.5 * fr1));
    plot(cx, o, o->out, "belanger", body);
    return 0;
}

static int cmd_conjugate(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    double fr1, v1;
    if (!run || inflow(cx, o, &fr1, &v1) != 0 || need(cx, o, o->x, "x", 0) != 0)
        return -1;
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    gauge_table g = {0};
    double *xs = NULL, *d2 = NULL;
    char *dir = NULL, *path = NULL, *source = NULL;
    long k = -1, n = 0;
    int from_sections = 0;

    path = gauge_path(cx, &r, "section_gauge", "sections.csv");
    if (!path)
        goto done;
    if (analyze_file_exists(path) &&
        (o->positions || analyze_scene_has(r.scene, "section_gauge"))) {
        n = gauge_positions(cx, o, &r, "section_gauge", &xs);
        if (n < 0)
            goto done;
        k = position_index(xs, (size_t)n, o->x, o->tolerance);
        from_sections = k >= 0;
    }
    if (!from_sections) {
        free(xs);
        xs = NULL;
        free(path);
        path = gauge_path(cx, &r, "free_surface_gauge", "free_surface.csv");
        if (!path)
            goto done;
        if (!o->positions && !analyze_scene_has(r.scene, "free_surface_gauge") &&
            !analyze_file_exists(path)) {
            analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                         "%s has neither a section gauge nor a free-surface gauge at x = %g "
                         "(no sections.csv or free_surface.csv)",
                         run, o->x);
            goto done;
        }
        n = gauge_positions(cx, o, &r, "free_surface_gauge", &xs);
        if (n < 0)
            goto done;
        k = position_index(xs, (size_t)n, o->x, o->tolerance);
        if (k < 0) {
            analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                         "no section or free-surface gauge at x = %g m in %s (within %g m)",
                         o->x, run, o->tolerance);
            goto done;
        }
    }
    if (gauge_table_load(cx, o, path, &g) != 0)
        goto done;
    char name[64];
    snprintf(name, sizeof name, from_sections ? "d_x%ld" : "eta_x%ld", k);
    long c = analyze_table_column(cx, &g.table, name);
    d2 = c >= 0 ? analyze_alloc(cx, g.table.rows, sizeof *d2) : NULL;
    if (!d2)
        goto done;
    analyze_table_copy(&g.table, (size_t)c, d2);
    if (!from_sections)
        for (size_t i = 0; i < g.table.rows; i++)
            d2[i] -= o->bed;
    double d2b = sluice_hyd_belanger_depth(o->d1, fr1), A, P, mean, std;
    size_t used;
    if (sluice_hyd_conjugate_statistics(d2 + g.first, g.last - g.first, d2b, &A, &P, &used) !=
            0 ||
        sluice_hyd_mean_std(d2 + g.first, g.last - g.first, &mean, &std, &used) != 0) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND, "%s: %s is nan over the whole window", path,
                     name);
        goto done;
    }
    source = analyze_format(cx, "%s %s (x = %g m)", path, name, xs[k]);
    if (!source)
        goto done;
    printf("source = %s\n", source);
    headline("d1", o->d1, "m");
    headline("V1", v1, "m/s");
    headline("Fr1", fr1, NULL);
    headline("d2_Belanger", d2b, "m");
    print_window(&g);
    printf("used = %zu\n", used);
    headline("d2_mean", mean, "m");
    headline("d2_std", std, "m");
    headline("d2_mean/d2_Belanger", mean / d2b, NULL);
    headline("A", A, NULL);
    headline("P", P, NULL);

    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    char *csv;
    FILE *f = open_csv(cx, dir, "conjugate.csv", &csv);
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "time,d2,d2_over_d2B\n");
    for (size_t i = 0; i < g.table.rows; i++)
        fprintf(f, "%.10g,%.10g,%.10g\n", g.time[i], d2[i], d2[i] / d2b);
    if (close_csv(cx, f, csv) != 0)
        goto done;
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel 'time (s)'\nset ylabel 'd2 / d2_Belanger'\n"
             "set arrow from %g, graph 0 to %g, graph 1 nohead dt 2\n"
             "set arrow from %g, graph 0 to %g, graph 1 nohead dt 2\n"
             "set title 'x = %g m: A = %.3f, P = %.3f over [%g, %g] s'\n"
             "plot 'conjugate.csv' using 1:3 skip 1 with lines title 'Sluice', "
             "1 with lines dt 3 title 'Belanger'\n",
             g.time[g.first], g.time[g.first], g.time[g.last - 1], g.time[g.last - 1], xs[k], A,
             P, g.time[g.first], g.time[g.last - 1]);
    plot(cx, o, dir, "conjugate", body);
    status = 0;
done:
    gauge_table_free(&g);
    analyze_scene_free(r.scene);
    free(xs);
    free(d2);
    free(dir);
    free(path);
    free(source);
    return status;
}

static int cmd_toe(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    double fr1, v1;
    if (!run || inflow(cx, o, &fr1, &v1) != 0)
        return -1;
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    surface_gauges s;
    double *x1 = NULL;
    char *dir = NULL;
    if (surface_load(cx, o, &r, &s) != 0)
        goto done;
    double threshold;
    x1 = analyze_alloc(cx, s.g.table.rows, sizeof *x1);
    if (!x1 || toe_series(cx, o, &s, fr1, &threshold, x1) != 0)
        goto done;
    size_t rows = s.g.last - s.g.first, used = 0;
    double mean = NAN, std = NAN;
    sluice_hyd_mean_std(x1 + s.g.first, rows, &mean, &std, &used);
    double speed = sluice_hyd_slope(s.g.time + s.g.first, x1 + s.g.first, rows);
    headline("Fr1", fr1, NULL);
    headline("d2_Belanger", sluice_hyd_belanger_depth(o->d1, fr1), "m");
    headline("threshold_depth", threshold, "m");
    print_window(&s.g);
    printf("detected = %zu\n", used);
    headline("x1_mean", mean, "m");
    headline("x1_std", std, "m");
    headline("x1_speed", speed, "m/s");

    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    char *csv;
    FILE *f = open_csv(cx, dir, "toe.csv", &csv);
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "time,x1\n");
    for (size_t i = 0; i < s.g.table.rows; i++)
        fprintf(f, "%.10g,%.10g\n", s.g.time[i], x1[i]);
    if (close_csv(cx, f, csv) != 0)
        goto done;
    if (used == 0) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "no jump toe detected in the window: the depth never rises through %g m "
                     "downstream of a gauge below it",
                     threshold);
        goto done;
    }
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel 'time (s)'\nset ylabel 'toe x1 (m)'\n"
             "set title 'toe: depth crosses %.4g m; mean %.4g m, std %.3g m over [%g, %g] s'\n"
             "plot 'toe.csv' using 1:2 skip 1 with lines title 'x1(t)', "
             "%g with lines dt 3 title 'mean'\n",
             threshold, mean, std, s.g.time[s.g.first], s.g.time[s.g.last - 1], mean);
    plot(cx, o, dir, "toe", body);
    status = 0;
done:
    surface_free(&s);
    analyze_scene_free(r.scene);
    free(x1);
    free(dir);
    return status;
}

/* Time-mean horizontal velocity at each point over the window; NaN where the
 * point is wet (finite) in fewer than --min-wet of the rows. */
typedef struct point_means {
    size_t n;
    double *x, *y, *u;
    size_t sections;
    size_t *section_of;
    double *section_x;
} point_means;

static void point_means_free(point_means *p)
{
    free(p->x);
    free(p->y);
    free(p->u);
    free(p->section_of);
    free(p->section_x);
}

static int point_means_load(analyze_ctx *cx, const options *o, const run_data *r, point_means *p)
{
    memset(p, 0, sizeof *p);
    long n = gauge_points(cx, o, r, &p->x, &p->y);
    if (n < 0)
        return -1;
    p->n = (size_t)n;
    char *path = gauge_path(cx, r, "point_gauge", "points.csv");
    gauge_table g;
    memset(&g, 0, sizeof g);
    int status = path ? gauge_table_load(cx, o, path, &g) : -1;
    free(path);
    if (status != 0) {
        gauge_table_free(&g);
        return -1;
    }
    p->u = analyze_alloc(cx, p->n, sizeof *p->u);
    double *series = analyze_alloc(cx, g.table.rows, sizeof *series);
    p->section_of = analyze_alloc(cx, p->n, sizeof *p->section_of);
    p->section_x = analyze_alloc(cx, p->n, sizeof *p->section_x);
    if (!p->u || !series || !p->section_of || !p->section_x)
        status = -1;
    for (size_t k = 0; status == 0 && k < p->n; k++) {
        char name[96];
        snprintf(name, sizeof name, "p%zu_%s_x", k, o->field);
        long c = analyze_table_column(cx, &g.table, name);
        if (c < 0) {
            status = -1;
            break;
        }
        analyze_table_copy(&g.table, (size_t)c, series);
        p->u[k] = sluice_hyd_wet_mean(series + g.first, g.last - g.first, o->min_wet);
    }
    if (status == 0) {
        print_window(&g);
        p->sections = sluice_hyd_group_sections(p->x, p->n, o->tolerance, p->section_of,
                                                p->section_x);
    }
    free(series);
    gauge_table_free(&g);
    return status;
}

static int cmd_roller(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    double fr1, v1;
    if (!run || inflow(cx, o, &fr1, &v1) != 0)
        return -1;
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    point_means p = {0};
    double *us = NULL, *ys = NULL, x1;
    char *dir = NULL;
    if (resolve_x1(cx, o, &r, fr1, &x1) != 0 || point_means_load(cx, o, &r, &p) != 0)
        goto done;
    /* near-surface velocity of a section: its highest point wet in the mean */
    us = analyze_alloc(cx, p.sections, sizeof *us);
    ys = analyze_alloc(cx, p.sections, sizeof *ys);
    if (!us || !ys)
        goto done;
    sluice_hyd_section_top(p.section_of, p.y, p.u, p.n, p.sections, us, ys);
    double x_section = NAN, x_crossing = NAN;
    int found = sluice_hyd_roller_end(p.section_x, us, p.sections, x1, &x_section,
                                      &x_crossing) == 0;
    double hager = sluice_hyd_hager_roller_length(o->d1, fr1);
    headline("Fr1", fr1, NULL);
    printf("sections = %zu\n", p.sections);
    headline("x_roller_end", x_section, "m");
    headline("L_r", x_section - x1, "m");
    headline("L_r_crossing", x_crossing - x1, "m");
    headline("L_r_Hager", hager, "m");
    headline("L_r/L_r_Hager", (x_section - x1) / hager, NULL);

    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    char *csv;
    FILE *f = open_csv(cx, dir, "roller.csv", &csv);
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "x,xi,y_near_surface,u_mean\n");
    for (size_t s = 0; s < p.sections; s++)
        fprintf(f, "%.10g,%.10g,%.10g,%.10g\n", p.section_x[s], (p.section_x[s] - x1) / o->d1,
                ys[s], us[s]);
    if (close_csv(cx, f, csv) != 0)
        goto done;
    if (!found) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "no roller end: no section downstream of x1 = %g m has a negative mean "
                     "near-surface velocity followed by a non-negative one",
                     x1);
        goto done;
    }
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel 'x (m)'\nset ylabel 'mean near-surface u (m/s)'\n"
             "set arrow from %g, graph 0 to %g, graph 1 nohead dt 2\n"
             "set arrow from %g, graph 0 to %g, graph 1 nohead lc rgb 'red'\n"
             "set arrow from %g, graph 0 to %g, graph 1 nohead dt 3 lc rgb 'blue'\n"
             "set title 'L_r = %.4g m (toe %.4g m, dashed; end red), Hager et al. %.4g m "
             "(blue)'\n"
             "plot 'roller.csv' using 1:4 skip 1 with linespoints title 'Sluice', 0 notitle\n",
             x1, x1, x_section, x_section, x1 + hager, x1 + hager, x_section - x1, x1, hager);
    plot(cx, o, dir, "roller", body);
    status = 0;
done:
    point_means_free(&p);
    analyze_scene_free(r.scene);
    free(us);
    free(ys);
    free(dir);
    return status;
}

static int cmd_vmax(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    double fr1, v1;
    if (!run || inflow(cx, o, &fr1, &v1) != 0)
        return -1;
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    point_means p = {0};
    double *vmax = NULL, *xi = NULL, *ratio = NULL, x1;
    char *dir = NULL;
    if (resolve_x1(cx, o, &r, fr1, &x1) != 0 || point_means_load(cx, o, &r, &p) != 0)
        goto done;
    vmax = analyze_alloc(cx, p.sections, sizeof *vmax);
    xi = analyze_alloc(cx, p.sections, sizeof *xi);
    ratio = analyze_alloc(cx, p.sections, sizeof *ratio);
    if (!vmax || !xi || !ratio)
        goto done;
    size_t downstream = 0;
    double dev2 = 0.0;
    sluice_hyd_section_max(p.section_of, p.u, p.n, p.sections, vmax);
    for (size_t s = 0; s < p.sections; s++) {
        xi[s] = (p.section_x[s] - x1) / o->d1;
        ratio[s] = xi[s] >= 0.0 ? vmax[s] / v1 : NAN;
        if (isfinite(ratio[s])) {
            double e = ratio[s] - sluice_hyd_chanson_vmax_ratio(xi[s]);
            dev2 += e * e;
            downstream++;
        }
    }
    double k_fit = sluice_hyd_decay_rate(xi, ratio, p.sections);
    headline("V1", v1, "m/s");
    printf("sections_downstream = %zu\n", downstream);
    headline("decay_rate", k_fit, NULL);
    headline("decay_rate_Chanson", 0.028, NULL);
    headline("rms_deviation_from_Chanson", downstream ? sqrt(dev2 / (double)downstream) : NAN,
             NULL);

    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    char *csv;
    FILE *f = open_csv(cx, dir, "vmax.csv", &csv);
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "x,xi,Vmax,Vmax_over_V1,Chanson\n");
    for (size_t s = 0; s < p.sections; s++)
        fprintf(f, "%.10g,%.10g,%.10g,%.10g,%.10g\n", p.section_x[s], xi[s], vmax[s], ratio[s],
                sluice_hyd_chanson_vmax_ratio(xi[s]));
    if (close_csv(cx, f, csv) != 0)
        goto done;
    if (downstream == 0) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "no wet point gauge downstream of the toe x1 = %g m", x1);
        goto done;
    }
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel '(x - x1)/d1'\nset ylabel 'Vmax / V1'\n"
             "set title 'fitted decay exp(-%.4g xi); Chanson exp(-0.028 xi)'\n"
             "plot 'vmax.csv' using 2:4 skip 1 with points pt 7 title 'Sluice', "
             "'vmax.csv' using 2:5 skip 1 with lines title 'Chanson (2010)'\n",
             k_fit);
    plot(cx, o, dir, "vmax", body);
    status = 0;
done:
    point_means_free(&p);
    analyze_scene_free(r.scene);
    free(vmax);
    free(xi);
    free(ratio);
    free(dir);
    return status;
}

static int cmd_surface(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    double fr1, v1;
    if (!run || inflow(cx, o, &fr1, &v1) != 0)
        return -1;
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    surface_gauges s;
    memset(&s, 0, sizeof s);
    double *series = NULL, *mean = NULL, *std = NULL, *wet = NULL, x1;
    char *dir = NULL;
    if (resolve_x1(cx, o, &r, fr1, &x1) != 0 || surface_load(cx, o, &r, &s) != 0)
        goto done;
    size_t rows = s.g.last - s.g.first;
    series = analyze_alloc(cx, s.g.table.rows, sizeof *series);
    mean = analyze_alloc(cx, s.n, sizeof *mean);
    std = analyze_alloc(cx, s.n, sizeof *std);
    wet = analyze_alloc(cx, s.n, sizeof *wet);
    if (!series || !mean || !std || !wet)
        goto done;
    size_t peak = s.n;
    for (size_t k = 0; k < s.n; k++) {
        analyze_table_copy(&s.g.table, s.col[k], series);
        size_t used = 0;
        mean[k] = std[k] = NAN;
        if (sluice_hyd_mean_std(series + s.g.first, rows, &mean[k], &std[k], &used) == 0)
            mean[k] -= o->bed;
        wet[k] = (double)used / (double)rows;
        if (wet[k] < o->min_wet)
            mean[k] = std[k] = NAN;
        if (s.x[k] >= x1 && isfinite(std[k]) && (peak == s.n || std[k] > std[peak]))
            peak = k;
    }
    double murzyn = sluice_hyd_murzyn_chanson_eta_std(fr1);
    headline("Fr1", fr1, NULL);
    print_window(&s.g);
    if (peak < s.n) {
        headline("eta_std_max/d1", std[peak] / o->d1, NULL);
        headline("x_of_max", s.x[peak], "m");
        headline("xi_of_max", (s.x[peak] - x1) / o->d1, NULL);
    }
    headline("eta_std_max/d1_Murzyn_Chanson", murzyn, NULL);
    if (peak < s.n)
        headline("ratio_to_Murzyn_Chanson", std[peak] / o->d1 / murzyn, NULL);

    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    char *csv;
    FILE *f = open_csv(cx, dir, "surface.csv", &csv);
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "x,xi,depth_mean,eta_std,depth_mean_over_d1,eta_std_over_d1,wet_fraction\n");
    for (size_t k = 0; k < s.n; k++)
        fprintf(f, "%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g\n", s.x[k], (s.x[k] - x1) / o->d1,
                mean[k], std[k], mean[k] / o->d1, std[k] / o->d1, wet[k]);
    if (close_csv(cx, f, csv) != 0)
        goto done;
    if (peak == s.n) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "no wet free-surface gauge downstream of the toe x1 = %g m", x1);
        goto done;
    }
    char body[1200];
    snprintf(body, sizeof body,
             "set xlabel '(x - x1)/d1'\nset ylabel 'depth/d1, eta std/d1'\nset y2tics\n"
             "set key center right\n"
             "set title 'max eta std/d1 = %.3g; Murzyn & Chanson 0.116 (Fr1-1)^1.235 = %.3g'\n"
             "plot 'surface.csv' using 2:5 skip 1 with linespoints title 'mean depth / d1', "
             "'surface.csv' using 2:6 skip 1 with linespoints axes x1y2 title 'std / d1 "
             "(right)', %g axes x1y2 with lines dt 3 title 'Murzyn & Chanson (right)'\n",
             std[peak] / o->d1, murzyn, murzyn);
    plot(cx, o, dir, "surface", body);
    status = 0;
done:
    surface_free(&s);
    analyze_scene_free(r.scene);
    free(series);
    free(mean);
    free(std);
    free(wet);
    free(dir);
    return status;
}

/* FILE:NAME or NAME searched in the run's gauge files. */
static int find_column(analyze_ctx *cx, const options *o, const run_data *r, char **path,
                       char **name)
{
    const char *colon = strrchr(o->column, ':');
    *path = *name = NULL;
    if (colon) {
        *name = analyze_format(cx, "%s", colon + 1);
        *path = o->column[0] == '/'
                    ? analyze_format(cx, "%.*s", (int)(colon - o->column), o->column)
                    : analyze_format(cx, "%s/%.*s", r->run, (int)(colon - o->column), o->column);
        return *name && *path ? 0 : -1;
    }
    static const char *const gauges[][2] = {{"free_surface_gauge", "free_surface.csv"},
                                            {"section_gauge", "sections.csv"},
                                            {"point_gauge", "points.csv"},
                                            {"inlet", "inlet.csv"},
                                            {"outlet", "outlet.csv"},
                                            {"wall_pressure", "wall_pressure.csv"}};
    char searched[512] = "";
    size_t used = 0;
    for (size_t k = 0; k < sizeof gauges / sizeof *gauges; k++) {
        char *candidate = gauge_path(cx, r, gauges[k][0], gauges[k][1]);
        if (!candidate)
            return -1;
        if (analyze_file_exists(candidate)) {
            analyze_table t;
            if (analyze_table_load(cx, candidate, &t) != 0) {
                analyze_table_free(&t);
                free(candidate);
                return -1;
            }
            int has = analyze_table_find(&t, o->column) >= 0;
            analyze_table_free(&t);
            if (has) {
                *path = candidate;
                *name = analyze_format(cx, "%s", o->column);
                return *name ? 0 : -1;
            }
            int w = snprintf(searched + used, sizeof searched - used, "%s%s", used ? ", " : "",
                             candidate);
            if (w > 0 && (size_t)w < sizeof searched - used)
                used += (size_t)w;
        }
        free(candidate);
    }
    return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                        "no gauge file of %s has a column '%s' (searched: %s)", r->run,
                        o->column, used ? searched : "no gauge file found");
}

/* An impact on a pressure sensor (a wall_pressure column, or any column of
 * a table with a time column): in the window, the arrival t_a (the first
 * sample above --arrival); over the impact [t_a, t_a + --duration] (to the
 * window's end without --duration) the peak, its time, the rise time and
 * the impulse, the integral of p (trapezoidal, the window's end cutting it
 * short); with
 * --scale P0 and --time-scale T0 the same divided by P0, T0 and P0 T0
 * (dimensionless, e.g. rho g H and (H/g)^(1/2) of a dam break). */
static int cmd_impact(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    if (!run)
        return -1;
    if (!o->column)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "impact needs --column [FILE:]NAME (e.g. wall_pressure.csv:p_Pa)");
    if (!isfinite(o->arrival))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "impact needs --arrival P: the pressure whose first crossing in the "
                            "window marks the impact's arrival (in the column's unit)");
    if (!isnan(o->duration) && !(o->duration > 0.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--duration must be positive");
    if ((!isnan(o->scale) && !(o->scale > 0.0)) ||
        (!isnan(o->time_scale) && !(o->time_scale > 0.0)))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "--scale and --time-scale must be positive");
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    char *path = NULL, *name = NULL;
    gauge_table g = {0};
    double *p = NULL;
    if (find_column(cx, o, &r, &path, &name) != 0 || gauge_table_load(cx, o, path, &g) != 0)
        goto done;
    long c = analyze_table_column(cx, &g.table, name);
    p = c >= 0 ? analyze_alloc(cx, g.table.rows, sizeof *p) : NULL;
    if (!p)
        goto done;
    analyze_table_copy(&g.table, (size_t)c, p);
    size_t a = g.first;
    while (a < g.last && !(p[a] > o->arrival))
        a++;
    if (a == g.last) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "%s: %s never exceeds --arrival %g in the window [%g, %g]", path, name,
                     o->arrival, g.time[g.first], g.time[g.last - 1]);
        goto done;
    }
    const double end = isnan(o->duration) ? g.time[g.last - 1] : g.time[a] + o->duration;
    size_t peak = a;
    for (size_t i = a; i < g.last && g.time[i] <= end; i++)
        if (p[i] > p[peak])
            peak = i;
    /* the trapezoid rule on the samples from t_a to the impact's end */
    const double impulse = sluice_hyd_profile_integral(g.time + a, p + a, g.last - a, g.time[a],
                                                       fmin(end, g.time[g.last - 1]));
    const double ps = isnan(o->scale) ? 1.0 : o->scale;
    const double ts = isnan(o->time_scale) ? 1.0 : o->time_scale;
    printf("source = %s %s\n", path, name);
    print_window(&g);
    headline("t_arrival", g.time[a], NULL);
    headline("peak", p[peak], NULL);
    headline("t_peak", g.time[peak], NULL);
    headline("rise_time", g.time[peak] - g.time[a], NULL);
    headline("impulse", impulse, NULL);
    headline("impulse_duration", fmin(end, g.time[g.last - 1]) - g.time[a], NULL);
    if (!isnan(o->scale) || !isnan(o->time_scale)) {
        headline("t_arrival_scaled", g.time[a] / ts, NULL);
        headline("peak_scaled", p[peak] / ps, NULL);
        headline("t_peak_scaled", g.time[peak] / ts, NULL);
        headline("impulse_scaled", impulse / (ps * ts), NULL);
    }
    status = 0;
done:
    free(p);
    free(path);
    free(name);
    gauge_table_free(&g);
    analyze_scene_free(r.scene);
    return status;
}

static int cmd_spectrum(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    if (!run)
        return -1;
    if (!o->column)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "spectrum needs --column [FILE:]NAME");
    double fr1 = NAN, v1 = NAN;
    int strouhal = !isnan(o->d1);
    if (strouhal && inflow(cx, o, &fr1, &v1) != 0)
        return -1;
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    char *path = NULL, *name = NULL, *dir = NULL, *file = NULL;
    gauge_table g = {0};
    double *y = NULL, *u = NULL, *re = NULL, *im = NULL, *amp = NULL;
    if (find_column(cx, o, &r, &path, &name) != 0 || gauge_table_load(cx, o, path, &g) != 0)
        goto done;
    long c = analyze_table_column(cx, &g.table, name);
    if (c < 0)
        goto done;
    size_t n = g.last - g.first;
    if (n < 4) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s: only %zu samples in the window", path,
                     n);
        goto done;
    }
    size_t m = sluice_hyd_next_pow2(n);
    y = analyze_alloc(cx, g.table.rows, sizeof *y);
    u = analyze_alloc(cx, n, sizeof *u);
    re = analyze_alloc(cx, m, sizeof *re);
    im = analyze_alloc(cx, m, sizeof *im);
    amp = analyze_alloc(cx, m / 2 + 1, sizeof *amp);
    if (!y || !u || !re || !im || !amp)
        goto done;
    analyze_table_copy(&g.table, (size_t)c, y);
    size_t finite = 0;
    for (size_t i = g.first; i < g.last; i++)
        finite += isfinite(y[i]) != 0;
    double t0 = g.time[g.first], t1 = g.time[g.last - 1], dt = (t1 - t0) / (double)(n - 1), df;
    if (sluice_hyd_resample(g.time + g.first, y + g.first, n, t0, t1, n, u) != 0) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "%s: %s has fewer than two finite samples in the window", path, name);
        goto done;
    }
    sluice_hyd_amplitude_spectrum(u, n, dt, re, im, amp, &df);
    size_t peak = sluice_hyd_spectrum_peak(amp, m / 2 + 1, df, isnan(o->fmin) ? 0.0 : o->fmin,
                                           isnan(o->fmax) ? 0.0 : o->fmax);
    printf("source = %s %s\n", path, name);
    print_window(&g);
    printf("finite = %zu\n", finite);
    headline("dt", dt, "s");
    printf("fft_length = %zu\n", m);
    headline("df", df, "Hz");
    headline("f_peak", (double)peak * df, "Hz");
    headline("amplitude_peak", peak ? amp[peak] : NAN, NULL);
    if (strouhal) {
        double st = (double)peak * df * o->d1 / v1;
        double cc = sluice_hyd_chachereau_chanson_strouhal(fr1);
        headline("Fr1", fr1, NULL);
        headline("St", st, NULL);
        headline("St_Chachereau_Chanson", cc, NULL);
        headline("St/St_Chachereau_Chanson", st / cc, NULL);
    }
    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    file = analyze_format(cx, "spectrum_%s", name);
    if (!file)
        goto done;
    for (char *q = file; *q; q++)
        if (!(*q == '_' || *q == '-' || *q == '.' || (*q >= '0' && *q <= '9') ||
              (*q >= 'a' && *q <= 'z') || (*q >= 'A' && *q <= 'Z')))
            *q = '_';
    char csvname[300];
    snprintf(csvname, sizeof csvname, "%s.csv", file);
    char *csv;
    FILE *f = open_csv(cx, dir, csvname, &csv);
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "frequency,amplitude\n");
    for (size_t j = 0; j <= m / 2; j++)
        fprintf(f, "%.10g,%.10g\n", (double)j * df, amp[j]);
    if (close_csv(cx, f, csv) != 0)
        goto done;
    if (peak == 0) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND, "no spectral bin in [--fmin, --fmax]");
        goto done;
    }
    if (!(amp[peak] > 0.0)) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "%s is a straight line in the window: its spectrum is zero", name);
        goto done;
    }
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel 'frequency (Hz)'\nset ylabel 'amplitude'\n"
             "set title '%s: peak %.4g Hz (df = %.3g Hz, Hann window, detrended)'\n"
             "plot '%s' using 1:2 skip 1 with lines title '%s'\n",
             name, (double)peak * df, df, csvname, name);
    plot(cx, o, dir, file, body);
    status = 0;
done:
    gauge_table_free(&g);
    analyze_scene_free(r.scene);
    free(path);
    free(name);
    free(dir);
    free(file);
    free(y);
    free(u);
    free(re);
    free(im);
    free(amp);
    return status;
}

/* A.csv:COL -> table, column values, times. */
static int load_series(analyze_ctx *cx, const options *o, const char *spec, gauge_table *g,
                       double **values, char **name)
{
    const char *colon = strrchr(spec, ':');
    *values = NULL;
    *name = NULL;
    if (!colon || colon == spec || !colon[1])
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "correlate expects FILE.csv:COLUMN, got '%s'", spec);
    char *path = analyze_format(cx, "%.*s", (int)(colon - spec), spec);
    if (!path)
        return -1;
    options all = *o; /* the whole file: the window is applied to the common times */
    all.from = -INFINITY;
    all.to = INFINITY;
    int status = gauge_table_load(cx, &all, path, g);
    free(path);
    if (status != 0)
        return -1;
    long c = analyze_table_column(cx, &g->table, colon + 1);
    if (c < 0)
        return -1;
    *values = analyze_alloc(cx, g->table.rows, sizeof **values);
    *name = analyze_format(cx, "%s", colon + 1);
    if (!*values || !*name)
        return -1;
    analyze_table_copy(&g->table, (size_t)c, *values);
    return 0;
}

static int cmd_correlate(analyze_ctx *cx, const options *o)
{
    if (o->positional_count != 2)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "correlate needs two series, A.csv:COLUMN B.csv:COLUMN");
    int status = -1;
    gauge_table a = {0}, b = {0};
    double *va = NULL, *vb = NULL, *bi = NULL;
    char *na = NULL, *nb = NULL, *dir = NULL;
    if (load_series(cx, o, o->positional[0], &a, &va, &na) != 0 ||
        load_series(cx, o, o->positional[1], &b, &vb, &nb) != 0)
        goto done;
    double lo = fmax(fmax(a.time[0], b.time[0]), o->from);
    double hi = fmin(fmin(a.time[a.table.rows - 1], b.time[b.table.rows - 1]), o->to);
    bi = analyze_alloc(cx, a.table.rows, sizeof *bi);
    if (!bi)
        goto done;
    size_t first = a.table.rows, last = 0;
    for (size_t i = 0; i < a.table.rows; i++)
        if (a.time[i] >= lo && a.time[i] <= hi) {
            if (first == a.table.rows)
                first = i;
            last = i + 1;
            bi[i] = sluice_hyd_interpolate(b.time, vb, b.table.rows, a.time[i]);
        }
    if (first >= last) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "%s and %s have no common times in the window", o->positional[0],
                     o->positional[1]);
        goto done;
    }
    size_t used;
    double r = sluice_hyd_pearson(va + first, bi + first, last - first, &used);
    printf("common_window = [%.6g, %.6g] s\n", a.time[first], a.time[last - 1]);
    printf("pairs = %zu\n", used);
    headline("r", r, NULL);
    if (o->out)
        dir = analyze_format(cx, "%s", o->out);
    else {
        const char *slash = strrchr(o->positional[0], '/');
        dir = slash ? analyze_format(cx, "%.*s/analysis", (int)(slash - o->positional[0]),
                                     o->positional[0])
                    : analyze_format(cx, "analysis");
    }
    if (!dir || analyze_mkdir(cx, dir) != 0)
        goto done;
    char *csv;
    FILE *f = open_csv(cx, dir, "correlate.csv", &csv);
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "time,a,b\n");
    for (size_t i = first; i < last; i++)
        fprintf(f, "%.10g,%.10g,%.10g\n", a.time[i], va[i], bi[i]);
    if (close_csv(cx, f, csv) != 0)
        goto done;
    if (!isfinite(r)) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "r undefined: fewer than two common finite pairs or a constant series");
        goto done;
    }
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel '%s (A)'\nset ylabel '%s (B)'\nset title 'r = %.4f (%zu pairs)'\n"
             "plot 'correlate.csv' using 2:3 skip 1 with points pt 7 ps 0.5 notitle\n",
             na, nb, r, used);
    plot(cx, o, dir, "correlate", body);
    status = 0;
done:
    gauge_table_free(&a);
    gauge_table_free(&b);
    free(va);
    free(vb);
    free(bi);
    free(na);
    free(nb);
    free(dir);
    return status;
}

/* ---------------------------------------------------------------- front -- */

/* The run's front Z = x/a at dimensionless time T = t sqrt(2 g / a),
 * interpolated in the front table (NaN outside it). */
static double front_at(const double *t, const double *x, size_t n, double a, double g, double T)
{
    double time = T / sqrt(2 * g / a);
    if (n == 0 || time < t[0] || time > t[n - 1])
        return NAN;
    return sluice_hyd_interpolate(t, x, n, time) / a;
}

/* Relative errors of the run's front against the experiment's points with
 * the experiment's time taken `shift` earlier: max (signed), mean |e|, rms. */
static size_t front_errors(const double *t, const double *x, size_t n, const double *te,
                           const double *ze, size_t m, double a, double g, double shift,
                           double *worst, double *mean, double *rms)
{
    size_t used = 0;
    double sum = 0, sum2 = 0;
    *worst = 0;
    for (size_t i = 0; i < m; i++) {
        double z = front_at(t, x, n, a, g, te[i] - shift);
        if (!isfinite(z) || te[i] - shift < 0)
            continue;
        double e = z / ze[i] - 1;
        if (fabs(e) > fabs(*worst))
            *worst = e;
        sum += fabs(e);
        sum2 += e * e;
        used++;
    }
    *mean = used ? sum / (double)used : NAN;
    *rms = used ? sqrt(sum2 / (double)used) : NAN;
    if (!used)
        *worst = NAN;
    return used;
}

/* The surge front of a collapsing column against an experiment (Martin &
 * Moyce 1952: rows a_in,T,Z): raw, with --shift (the experiment's time
 * origin taken ShIFT later, dimensionless), and the shift that fits best. */
static int cmd_front(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    if (!run)
        return -1;
    if (!o->reference)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "front needs --reference REF.csv (columns T and Z, optionally a_in)");
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    analyze_table ref = {0}, front = {0};
    double *t = NULL, *x = NULL, *te = NULL, *ze = NULL, *series = NULL;
    char *path = analyze_format(cx, "%s/front.csv", run), *dir = NULL, *csv = NULL;
    if (!path || analyze_table_load(cx, path, &front) != 0 ||
        analyze_table_load(cx, o->reference, &ref) != 0)
        goto done;
    long ct = analyze_table_column(cx, &front, "time"), cxf = analyze_table_column(cx, &front, "x_front");
    long cT = analyze_table_column(cx, &ref, "T"), cZ = analyze_table_column(cx, &ref, "Z");
    long ca = analyze_table_find(&ref, "a_in");
    if (ct < 0 || cxf < 0 || cT < 0 || cZ < 0)
        goto done;
    double a = o->width;
    double fluid_min[3], fluid_max[3];
    if (!(a > 0) && r.scene && analyze_scene_region(r.scene, "fluid", 0, fluid_min, fluid_max) == 0)
        a = fluid_max[0] - fluid_min[0];
    if (!(a > 0)) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "the column width is unknown: give --width A (m) or a run with its "
                     "scene.resolved.yaml");
        goto done;
    }
    t = analyze_alloc(cx, front.rows + 1, sizeof *t);
    x = analyze_alloc(cx, front.rows + 1, sizeof *x);
    te = analyze_alloc(cx, ref.rows + 1, sizeof *te);
    ze = analyze_alloc(cx, ref.rows + 1, sizeof *ze);
    series = analyze_alloc(cx, ref.rows + 1, sizeof *series);
    if (!t || !x || !te || !ze || !series)
        goto done;
    analyze_table_copy(&front, (size_t)ct, t);
    analyze_table_copy(&front, (size_t)cxf, x);
    if (ca >= 0)
        analyze_table_copy(&ref, (size_t)ca, series);
    double chosen = o->series > 0 ? o->series : ca >= 0 && ref.rows ? series[0] : 0;
    size_t m = 0;
    for (size_t i = 0; i < ref.rows; i++)
        if (ca < 0 || series[i] == chosen) {
            te[m] = ref.data[i * ref.cols + (size_t)cT];
            ze[m] = ref.data[i * ref.cols + (size_t)cZ];
            double time = te[m] / sqrt(2 * o->g / a); /* the window is in seconds */
            if (te[m] >= 0 && ze[m] > 0 && time >= o->from && time <= o->to)
                m++;
        }
    double worst, mean, rms;
    size_t used = front_errors(t, x, front.rows, te, ze, m, a, o->g, 0, &worst, &mean, &rms);
    if (used == 0) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "no experimental point lies within the run's front table (T up to %.3g)",
                     front.rows ? t[front.rows - 1] * sqrt(2 * o->g / a) : 0);
        goto done;
    }
    printf("source = %s\n", path);
    headline("a", a, "m");
    if (ca >= 0)
        headline("series_a_in", chosen, NULL);
    printf("points = %zu\n", used);
    headline("front_error_max", worst, NULL);
    headline("front_error_mean", mean, NULL);
    headline("front_error_rms", rms, NULL);
    if (o->shift != 0) {
        double w2, m2, r2;
        size_t u2 = front_errors(t, x, front.rows, te, ze, m, a, o->g, o->shift, &w2, &m2, &r2);
        headline("shift", o->shift, NULL);
        printf("points_shifted = %zu\n", u2);
        headline("front_error_max_shifted", w2, NULL);
        headline("front_error_mean_shifted", m2, NULL);
        headline("front_error_rms_shifted", r2, NULL);
    }
    /* the experiment's time origin that fits the run best (rms over the points
     * both cover), searched over T in [-1, 1] by 0.001 */
    double best = NAN, best_rms = INFINITY;
    for (int k = -1000; k <= 1000; k++) {
        double w3, m3, r3;
        size_t u3 = front_errors(t, x, front.rows, te, ze, m, a, o->g, 0.001 * k, &w3, &m3, &r3);
        if (u3 * 2 >= used && r3 < best_rms) {
            best_rms = r3;
            best = 0.001 * k;
        }
    }
    headline("shift_fitted", best, NULL);
    headline("front_error_rms_fitted", best_rms, NULL);
    dir = out_dir(cx, o, run);
    FILE *f = dir ? open_csv(cx, dir, "front.csv", &csv) : NULL;
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "T,Z_experiment,Z_run,error,Z_run_shifted,error_shifted\n");
    for (size_t i = 0; i < m; i++) {
        double z = front_at(t, x, front.rows, a, o->g, te[i]);
        double zs = front_at(t, x, front.rows, a, o->g, te[i] - o->shift);
        fprintf(f, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", te[i], ze[i], z, z / ze[i] - 1, zs,
                zs / ze[i] - 1);
    }
    if (close_csv(cx, f, csv) != 0)
        goto done;
    status = 0;
done:
    free(t);
    free(x);
    free(te);
    free(ze);
    free(series);
    free(path);
    free(dir);
    analyze_table_free(&ref);
    analyze_table_free(&front);
    analyze_scene_free(r.scene);
    return status;
}

static int cmd_l2(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    if (!run)
        return -1;
    if (!o->reference)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "l2 needs --reference REF.csv");
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    surface_gauges s;
    memset(&s, 0, sizeof s);
    analyze_table ref = {0};
    double *xr = NULL, *hr = NULL, *tr = NULL, *profile = NULL, *hn = NULL, *href = NULL;
    double times[MAX_TIMES];
    size_t ntimes = 0;
    char *dir = NULL;
    FILE *f = NULL, *fp = NULL;
    char *csv = NULL, *csvp = NULL;
    options all = *o;
    all.from = -INFINITY;
    all.to = INFINITY;
    if (analyze_table_load(cx, o->reference, &ref) != 0 || surface_load(cx, &all, &r, &s) != 0)
        goto done;
    long cx_ = analyze_table_column(cx, &ref, "x");
    long ch = analyze_table_find(&ref, "eta");
    if (ch < 0)
        ch = analyze_table_find(&ref, "h");
    if (cx_ < 0)
        goto done;
    if (ch < 0) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "%s has no column 'eta' (or 'h'): the measured level", o->reference);
        goto done;
    }
    long ct = analyze_table_find(&ref, "time");
    xr = analyze_alloc(cx, ref.rows, sizeof *xr);
    hr = analyze_alloc(cx, ref.rows, sizeof *hr);
    tr = analyze_alloc(cx, ref.rows, sizeof *tr);
    profile = analyze_alloc(cx, s.n, sizeof *profile);
    hn = analyze_alloc(cx, ref.rows, sizeof *hn);
    href = analyze_alloc(cx, ref.rows, sizeof *href);
    if (!xr || !hr || !tr || !profile || !hn || !href)
        goto done;
    analyze_table_copy(&ref, (size_t)cx_, xr);
    analyze_table_copy(&ref, (size_t)ch, hr);
    if (ct >= 0) {
        analyze_table_copy(&ref, (size_t)ct, tr);
        for (size_t i = 0; i < ref.rows; i++) {
            size_t k = 0;
            while (k < ntimes && times[k] != tr[i])
                k++;
            if (k == ntimes) {
                if (ntimes == MAX_TIMES) {
                    analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s: more than %d profile times",
                                 o->reference, MAX_TIMES);
                    goto done;
                }
                times[ntimes++] = tr[i];
            }
        }
        if (o->time_count) {
            analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                         "%s has a time column: --time is not needed", o->reference);
            goto done;
        }
    } else {
        if (o->time_count != 1) {
            analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                         "%s has no time column: give the profile's time with one --time",
                         o->reference);
            goto done;
        }
        times[ntimes++] = o->times[0];
        for (size_t i = 0; i < ref.rows; i++)
            tr[i] = o->times[0];
    }
    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    f = open_csv(cx, dir, "l2.csv", &csv);
    fp = f ? open_csv(cx, dir, "l2_profiles.csv", &csvp) : NULL;
    if (!f || !fp)
        goto done;
    fprintf(f, "time,time_simulated,L2,RMSE,points\n");
    fprintf(fp, "time,x,h_num,h_ref\n");
    for (size_t k = 0; k < ntimes; k++) {
        size_t best = 0;
        for (size_t i = 1; i < s.g.table.rows; i++)
            if (fabs(s.g.time[i] - times[k]) < fabs(s.g.time[best] - times[k]))
                best = i;
        for (size_t j = 0; j < s.n; j++)
            profile[j] = cell(&s.g, best, s.col[j]);
        size_t count = 0;
        for (size_t i = 0; i < ref.rows; i++)
            if (tr[i] == times[k]) {
                hn[count] = sluice_hyd_interpolate(s.x, profile, s.n, xr[i]);
                href[count] = hr[i];
                fprintf(fp, "%.10g,%.10g,%.10g,%.10g\n", times[k], xr[i], hn[count], hr[i]);
                count++;
            }
        double l2 = NAN, rmse = NAN;
        size_t used = 0;
        if (sluice_hyd_profile_errors(hn, href, count, &l2, &rmse, &used) != 0) {
            analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                         "%s at t = %g: no reference point inside the gauges' range, or a "
                         "reference level of 0 (L2 divides by it)",
                         o->reference, times[k]);
            goto done;
        }
        fprintf(f, "%.10g,%.10g,%.10g,%.10g,%zu\n", times[k], s.g.time[best], l2, rmse, used);
        printf("time = %g s (simulated %g s): L2 = %.6g, RMSE = %.6g m, points = %zu\n",
               times[k], s.g.time[best], l2, rmse, used);
    }
    status = 0;
done:
    if (f && close_csv(cx, f, csv) != 0)
        status = -1;
    if (fp && close_csv(cx, fp, csvp) != 0)
        status = -1;
    if (status == 0) {
        char body[1024];
        snprintf(body, sizeof body,
                 "set xlabel 'x (m)'\nset ylabel 'level (m)'\n"
                 "plot 'l2_profiles.csv' using 2:3 skip 1 with points pt 7 ps 0.6 title "
                 "'Sluice', 'l2_profiles.csv' using 2:4 skip 1 with points pt 6 title "
                 "'reference'\n");
        plot(cx, o, dir, "l2", body);
    }
    surface_free(&s);
    analyze_table_free(&ref);
    analyze_scene_free(r.scene);
    free(xr);
    free(hr);
    free(tr);
    free(profile);
    free(hn);
    free(href);
    free(dir);
    return status;
}

static int cmd_classify(analyze_ctx *cx, const options *o)
{
    if (need(cx, o, o->y1, "y1", 1) != 0 || need(cx, o, o->yt, "yt", 1) != 0 ||
        need(cx, o, o->drop, "drop", 0) != 0)
        return -1;
    if (!(o->drop >= 0.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--drop must be >= 0");
    options with_d1 = *o;
    with_d1.d1 = o->y1;
    double fr1, v1;
    if (inflow(cx, &with_d1, &fr1, &v1) != 0)
        return -1;
    double Y = o->yt / o->y1, S = o->drop / o->y1, fa, fb, t;
    sluice_hyd_drop_regime regime;
    if (sluice_hyd_drop_regime_of(fr1, Y, S, &regime, &t) != 0 ||
        sluice_hyd_drop_limits(Y, S, &fa, &fb) != 0)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "the tailwater must stand above the step: yt/y1 = %g <= 1 + s/y1 = %g",
                            Y, 1 + S);
    static const char *const names[] = {"A-jump", "wave-jump region", "B-jump"};
    headline("F1", fr1, NULL);
    headline("yt/y1", Y, NULL);
    headline("s/y1", S, NULL);
    headline("F_A", fa, NULL);
    headline("F_B", fb, NULL);
    headline("t", t, NULL);
    printf("regime = %s\n", names[regime]);
    double face_ratio;
    if (sluice_hyd_drop_face_ratio(fr1, Y, S, &face_ratio) == 0) {
        /* the face's force the balance needs, and the hydrostatic one under
         * the tailwater level, per metre of width with rho = 1000 kg/m^3 */
        const double unit = 1000.0 * o->g * o->y1 * o->y1 / 2.0;
        const double hydrostatic = unit * (Y * Y - (Y - S) * (Y - S));
        headline("face_force_needed", face_ratio * hydrostatic, "N/m");
        headline("face_force_hydrostatic", hydrostatic, "N/m");
        headline("face_ratio", face_ratio, NULL);
    }
    if (!o->out)
        return 0;
    if (analyze_mkdir(cx, o->out) != 0)
        return -1;
    char *path;
    FILE *f = open_csv(cx, o->out, "classify.csv", &path);
    if (!f) {
        free(path);
        return -1;
    }
    fprintf(f, "F1,Y,S,F_A,F_B,t,regime\n%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%d\n", fr1, Y, S, fa,
            fb, t, (int)regime);
    if (close_csv(cx, f, path) != 0)
        return -1;
    char body[1400];
    snprintf(body, sizeof body,
             "S = %.10g\nfa(y) = sqrt(y*((y-S)**2-1)/(2*(y-1)))\n"
             "fb(y) = sqrt(y*(y**2-(1+S)**2)/(2*(y-1)))\n"
             "set xlabel 'yt/y1'\nset ylabel 'F1'\nset key top left\n"
             "set title 'abrupt drop s/y1 = %.3g: A-jump below F_A, B-jump above F_B'\n"
             "plot [%g:%g] fa(x) title 'F_A (A-jump limit)', fb(x) title 'F_B (B-jump limit)', "
             "'classify.csv' using 2:1 skip 1 with points pt 7 ps 1.5 title 'this flow'\n",
             S, S, 1.0 + S + 1e-3, fmax(2.0 * Y, Y + 3.0));
    plot(cx, o, o->out, "classify", body);
    return 0;
}

/* The jump type at an abrupt drop from a run's free surface
 * (sluice_hyd_drop_state_of / sluice_hyd_drop_type; docs/analysis.md). */
static int cmd_drop_type(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    double fr1, v1;
    if (!run || inflow(cx, o, &fr1, &v1) != 0)
        return -1;
    if (!(o->fraction > 0.0 && o->fraction < 1.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--fraction must be in (0, 1)");
    if (!(o->wave_min > 0.0 && o->wave_min < 0.5))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--wave-min must be in (0, 0.5)");
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    surface_gauges s;
    memset(&s, 0, sizeof s);
    double *depth = NULL, *x1 = NULL;
    sluice_hyd_drop_state *state = NULL;
    char *dir = NULL;
    /* the step height: --drop, else the inlet's bed elevation (the upper bed) */
    double drop = o->drop;
    if (isnan(drop))
        analyze_scene_number(r.scene, "inlet", "bed", &drop);
    if (!(drop > 0.0)) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "drop-type needs --drop S > 0 (the upper bed's elevation above the lower "
                     "bed; the run's inlet has no bed above 0)");
        goto done;
    }
    /* the edge: --drop-x, else the downstream end of the scene's fluid
     * region that lies on the upper bed (the upper stream) */
    double drop_x = o->drop_x, lo[3], hi[3];
    for (size_t k = 0; isnan(drop_x) && analyze_scene_region(r.scene, "fluid", k, lo, hi) == 0;
         k++)
        if (fabs(lo[1] - drop) <= 1e-9 * (1 + drop))
            drop_x = hi[0];
    if (!(drop_x > -INFINITY && drop_x < INFINITY)) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "drop-type needs --drop-x X (the edge of the drop; the run's scene has no "
                     "fluid region on the upper bed at %g m to take it from)",
                     drop);
        goto done;
    }
    if (surface_load(cx, o, &r, &s) != 0)
        goto done;
    size_t upper = 0;
    while (upper < s.n && s.x[upper] < drop_x)
        upper++;
    if (upper < 2) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "drop-type needs at least two free-surface gauges upstream of the drop "
                     "(x < %g m); %s has %zu",
                     drop_x, run, upper);
        goto done;
    }
    const double d2 = sluice_hyd_belanger_depth(o->d1, fr1);
    const double threshold = o->d1 + o->fraction * (d2 - o->d1);
    const double roller = sluice_hyd_hager_roller_length(o->d1, fr1);
    depth = analyze_alloc(cx, upper, sizeof *depth);
    x1 = analyze_alloc(cx, s.g.table.rows, sizeof *x1);
    state = analyze_alloc(cx, s.g.table.rows, sizeof *state);
    if (!depth || !x1 || !state)
        goto done;
    for (size_t i = 0; i < s.g.table.rows; i++) {
        for (size_t k = 0; k < upper; k++)
            depth[k] = cell(&s.g, i, s.col[k]) - drop;
        state[i] =
            sluice_hyd_drop_state_of(s.x, depth, upper, threshold, drop_x, roller, &x1[i]);
    }
    double fa, fb, fw;
    size_t episodes;
    const char *type = sluice_hyd_drop_type(state + s.g.first, s.g.last - s.g.first, o->wave_min,
                                            &fa, &fb, &fw, &episodes);
    const double span = s.g.time[s.g.last - 1] - s.g.time[s.g.first];
    headline("F1", fr1, NULL);
    headline("y1", o->d1, "m");
    headline("drop", drop, "m");
    headline("drop_x", drop_x, "m");
    headline("threshold_depth", threshold, "m");
    headline("L_r_Hager", roller, "m");
    print_window(&s.g);
    printf("upper_gauges = %zu\n", upper);
    headline("fraction_A", fa, NULL);
    headline("fraction_B", fb, NULL);
    headline("fraction_wave", fw, NULL);
    printf("wave_episodes = %zu\n", episodes);
    headline("wave_episode_rate", span > 0 ? (double)episodes / span : NAN, "Hz");
    printf("type = %s\n", type ? type : "none");

    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    char *csv;
    FILE *f = open_csv(cx, dir, "drop_type.csv", &csv);
    if (!f) {
        free(csv);
        goto done;
    }
    fprintf(f, "time,x1,state\n");
    for (size_t i = 0; i < s.g.table.rows; i++)
        fprintf(f, "%.10g,%.10g,%d\n", s.g.time[i], x1[i], (int)state[i]);
    if (close_csv(cx, f, csv) != 0)
        goto done;
    if (!type) {
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "every free-surface gauge upstream of the drop is dry in the window");
        goto done;
    }
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel 'time (s)'\nset ylabel 'state (0 A, 1 B, 2 wave)'\nset yrange [-0.5:2.5]\n"
             "set title '%s: A %.2f, B %.2f, wave %.2f over [%g, %g] s'\n"
             "plot 'drop_type.csv' using 1:3 skip 1 with steps title 'state'\n",
             type, fa, fb, fw, s.g.time[s.g.first], s.g.time[s.g.last - 1]);
    plot(cx, o, dir, "drop_type", body);
    status = 0;
done:
    surface_free(&s);
    analyze_scene_free(r.scene);
    free(depth);
    free(x1);
    free(state);
    free(dir);
    return status;
}

/* ------------------------------------------ stepped chute (seed 001) -- */

/* The smallest Y90 (in units of h) for which the band 0.2 Y90 <= y <= 0.5 Y90
 * lies more than the kernel support 2h below a sharp, unaerated interface:
 * C(y) of a flat interface smeared by the Wendland C2 kernel (2D) reaches 0.9
 * at delta90 = 0.69 h above it, so the interface is at Y90 - 0.69 h and the
 * band's top 0.5 Y90 is 2h below it when Y90 >= 2 (2 + 0.69) h = 5.4 h
 * (docs/analysis.md). */
#define STEP_MIN_Y90_OVER_H 5.4

/* The points' coordinates for step-profiles: --points, else
 * plugins.point_gauge.points of the scene.resolved.yaml beside FILE (whose
 * plugins.point_gauge.file must name FILE). */
static long step_points(analyze_ctx *cx, const options *o, const char *file, double **xs,
                        double **ys, double *h)
{
    *h = o->h;
    char *dir = analyze_format(cx, "%s", file);
    if (!dir)
        return -1;
    char *slash = strrchr(dir, '/');
    const char *base = slash ? slash + 1 : file;
    if (slash)
        *slash = '\0';
    char *scene_path = analyze_format(cx, "%s/scene.resolved.yaml", slash ? dir : ".");
    long n = -1;
    analyze_scene *scene = NULL;
    if (!scene_path)
        goto done;
    if (analyze_file_exists(scene_path) && analyze_scene_load(cx, scene_path, &scene) != 0)
        goto done;
    if (isnan(*h)) {
        double spacing, ratio;
        if (analyze_scene_setting(scene, "particles", "spacing", &spacing) == 0 &&
            analyze_scene_setting(scene, "particles", "smoothing_length_ratio", &ratio) == 0)
            *h = spacing * ratio;
    }
    if (o->points) {
        n = analyze_parse_points(cx, "--points", o->points, xs, ys);
        goto done;
    }
    if (!scene) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "%s not found: give the points of %s with --points", scene_path, file);
        goto done;
    }
    const char *gauge_file = analyze_scene_string(scene, "point_gauge", "file");
    if (gauge_file && strcmp(gauge_file, base) != 0) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "%s: plugins.point_gauge.file is '%s', not '%s': give the points of %s "
                     "with --points",
                     scene_path, gauge_file, base, file);
        goto done;
    }
    n = analyze_scene_points(cx, scene, "point_gauge", "points", xs, ys);
    if (n == 0)
        n = analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                         "%s has no plugins.point_gauge.points: give them with --points",
                         scene_path);
done:
    analyze_scene_free(scene);
    free(scene_path);
    free(dir);
    return n;
}

/* Number of consecutive points k = 0, 1, ... with a column p<k>_<suffix>. */
static size_t count_point_columns(const analyze_table *t, const char *suffix)
{
    size_t k = 0;
    for (;; k++) {
        char name[128];
        snprintf(name, sizeof name, "p%zu_%s", k, suffix);
        if (analyze_table_find(t, name) < 0)
            return k;
    }
}

static long point_column(analyze_ctx *cx, const gauge_table *g, size_t k, const char *suffix)
{
    char name[128];
    snprintf(name, sizeof name, "p%zu_%s", k, suffix);
    return analyze_table_column(cx, &g->table, name);
}

static int whole_number(double x)
{
    return isfinite(x) && x == floor(x) && fabs(x) < 1e9;
}

/* Velocity profiles U/Uc against y/dc at step edges, the air concentration,
 * Y90, the clear-water depth, C_mean, the time-mean surface and the inception
 * step (docs/analysis.md, seed 001 Figure 6 and Chanson 2002). */
typedef struct step_profiles {
    size_t K, per_line, rows;
    long lines;
    int has_air;
    double h;
    double *ex, *ey;           /* the step edges (m), one per line */
    double *px, *py;           /* the points (m) */
    double *y, *u, *c;         /* per point: y (m), time-mean U/Uc and C */
    size_t *order;             /* per line, the points in the order of y */
    size_t *u_count, *c_count; /* per point: wet samples, air samples */
    double *y90, *depth, *c_mean, *u_max, *c_core, *surface; /* per line */
    long inception; /* index of the first line above the threshold, -1 none */
} step_profiles;

static void step_profiles_free(step_profiles *sp)
{
    free(sp->ex);
    free(sp->ey);
    free(sp->px);
    free(sp->py);
    free(sp->y);
    free(sp->u);
    free(sp->c);
    free(sp->order);
    free(sp->u_count);
    free(sp->c_count);
    free(sp->y90);
    free(sp->depth);
    free(sp->c_mean);
    free(sp->u_max);
    free(sp->c_core);
    free(sp->surface);
}

static int step_check_options(analyze_ctx *cx, const options *o)
{
    if (need(cx, o, o->per_line, "per-line", 1) != 0 || need(cx, o, o->theta, "theta", 0) != 0 ||
        need(cx, o, o->dc, "dc", 1) != 0 || need(cx, o, o->uc, "uc", 1) != 0)
        return -1;
    if (!o->edges)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "step-profiles needs --edges x,y;x,y;... (the step edges, one per "
                            "line of points)");
    if (!whole_number(o->per_line))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--per-line must be a whole number");
    if (!(o->theta >= 0.0 && o->theta < 90.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "--theta must be in [0, 90) degrees (the chute's slope)");
    if (!(o->threshold > 0.0 && o->threshold < 1.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--threshold must be in (0, 1)");
    if (!isnan(o->h) && !(o->h > 0.0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--h must be positive");
    if (!whole_number(o->first_step))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--first-step must be a whole number");
    return 0;
}

/* The point_gauge CSV of step-profiles: the file given, or for a run
 * directory RUN/<plugins.point_gauge.file> (default points.csv). */
static char *step_points_file(analyze_ctx *cx, const char *given, int *is_run)
{
    struct stat st;
    *is_run = stat(given, &st) == 0 && S_ISDIR(st.st_mode);
    if (!*is_run)
        return analyze_format(cx, "%s", given);
    run_data r;
    if (run_open(cx, given, &r) != 0)
        return NULL;
    char *file = gauge_path(cx, &r, "point_gauge", "points.csv");
    analyze_scene_free(r.scene);
    return file;
}

/* Time means over the window of every point: U/Uc over the samples where
 * the point is wet (both components finite), C over its finite samples. */
static int step_point_means(analyze_ctx *cx, const options *o, const char *file,
                            const gauge_table *g, step_profiles *sp)
{
    const double theta = o->theta * M_PI / 180.0;
    char suffix_u[96], suffix_v[96];
    snprintf(suffix_u, sizeof suffix_u, "%s_x", o->field);
    snprintf(suffix_v, sizeof suffix_v, "%s_y", o->field);
    {
        char z[96];
        snprintf(z, sizeof z, "p0_%s_z", o->field);
        if (analyze_table_find(&g->table, z) >= 0)
            snprintf(suffix_v, sizeof suffix_v, "%s_z", o->field);
    }
    sp->K = count_point_columns(&g->table, suffix_u);
    if (sp->K == 0)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%s has no column p0_%s (a point_gauge output with the field '%s')",
                            file, suffix_u, o->field);
    if (sp->K != sp->per_line * (size_t)sp->lines)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%s has %zu points (p0 .. p%zu) but --per-line %zu x %ld edges = "
                            "%zu: each edge needs its line of --per-line points, in the gauge's "
                            "order",
                            file, sp->K, sp->K - 1, sp->per_line, sp->lines,
                            sp->per_line * (size_t)sp->lines);
    const size_t air_points = count_point_columns(&g->table, "air_fraction");
    if (air_points != 0 && air_points != sp->K)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%s has p<k>_air_fraction for %zu of its %zu points", file, air_points,
                            sp->K);
    sp->has_air = air_points == sp->K;
    long point_count = step_points(cx, o, file, &sp->px, &sp->py, &sp->h);
    if (point_count < 0)
        return -1;
    if ((size_t)point_count != sp->K)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "%zu point coordinates (%s) for the "
                            "%zu points of %s",
                            (size_t)point_count, o->points ? "--points" : "scene.resolved.yaml",
                            sp->K, file);
    const size_t K = sp->K, rows = g->last - g->first;
    sp->rows = rows;
    sp->y = analyze_alloc(cx, K, sizeof *sp->y);
    sp->u = analyze_alloc(cx, K, sizeof *sp->u);
    sp->c = analyze_alloc(cx, K, sizeof *sp->c);
    sp->order = analyze_alloc(cx, K, sizeof *sp->order);
    sp->u_count = analyze_alloc(cx, K, sizeof *sp->u_count);
    sp->c_count = analyze_alloc(cx, K, sizeof *sp->c_count);
    double *series = analyze_alloc(cx, rows, sizeof *series);
    int status = -1;
    if (!sp->y || !sp->u || !sp->c || !sp->order || !sp->u_count || !sp->c_count || !series)
        goto done;
    for (size_t k = 0; k < K; k++) {
        long cu = point_column(cx, g, k, suffix_u), cv = point_column(cx, g, k, suffix_v);
        if (cu < 0 || cv < 0)
            goto done;
        for (size_t r = 0; r < rows; r++) {
            const double uu = cell(g, g->first + r, (size_t)cu);
            const double vv = cell(g, g->first + r, (size_t)cv);
            series[r] = isfinite(uu) && isfinite(vv)
                            ? sluice_hyd_chute_velocity(uu, vv, theta) / o->uc
                            : NAN;
        }
        double mean, std;
        sp->u[k] =
            sluice_hyd_mean_std(series, rows, &mean, &std, &sp->u_count[k]) == 0 ? mean : NAN;
        sp->c[k] = NAN;
        sp->c_count[k] = 0;
        if (sp->has_air) {
            long cc = point_column(cx, g, k, "air_fraction");
            if (cc < 0)
                goto done;
            for (size_t r = 0; r < rows; r++)
                series[r] = cell(g, g->first + r, (size_t)cc);
            sp->c[k] =
                sluice_hyd_mean_std(series, rows, &mean, &std, &sp->c_count[k]) == 0 ? mean : NAN;
        }
    }
    status = 0;
done:
    free(series);
    return status;
}

/* Each line: y along the normal to the pseudo-bottom, the points sorted by
 * it; a point off its normal or two at one y is bad input. */
static int step_sort_lines(analyze_ctx *cx, const options *o, step_profiles *sp)
{
    const double theta = o->theta * M_PI / 180.0;
    const size_t per_line = sp->per_line;
    for (long l = 0; l < sp->lines; l++) {
        const size_t base = (size_t)l * per_line;
        double extent = 0.0, worst = 0.0;
        size_t worst_k = base;
        for (size_t j = 0; j < per_line; j++) {
            const size_t k = base + j;
            double offset;
            sp->y[k] = sluice_hyd_normal_distance(sp->px[k], sp->py[k], sp->ex[l], sp->ey[l], theta,
                                                  &offset);
            extent = fmax(extent, fabs(sp->y[k]));
            if (fabs(offset) > worst) {
                worst = fabs(offset);
                worst_k = k;
            }
            sp->order[k] = k;
        }
        const double allowed = fmax(o->tolerance, 1e-3 * extent);
        if (worst > allowed)
            return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                "point %zu (%g, %g) is %g m off the normal to the pseudo-bottom "
                                "at edge %ld (%g, %g) with --theta %g (allowed %g m): check "
                                "--edges, --theta and --per-line",
                                worst_k, sp->px[worst_k], sp->py[worst_k], worst, l + 1, sp->ex[l],
                                sp->ey[l], o->theta, allowed);
        size_t *order = sp->order;
        for (size_t j = 1; j < per_line; j++) /* insertion sort by y */
            for (size_t i = base + j; i > base && sp->y[order[i - 1]] > sp->y[order[i]]; i--) {
                size_t t = order[i];
                order[i] = order[i - 1];
                order[i - 1] = t;
            }
        for (size_t j = 1; j < per_line; j++)
            if (!(sp->y[order[base + j]] > sp->y[order[base + j - 1]]))
                return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                                    "points %zu and %zu of edge %ld lie at the same distance y = "
                                    "%g m from it",
                                    order[base + j - 1], order[base + j], l + 1,
                                    sp->y[order[base + j]]);
    }
    return 0;
}

/* The time-mean free surface of a line: the y at which the wet fraction of
 * the samples (a point is wet where the gauge reads a velocity) falls
 * through 1/2 going up, linear between points; NaN when the lowest point
 * is wet less than half of the time or no point above it is. */
static double step_surface(const step_profiles *sp, size_t base)
{
    if (sp->rows == 0)
        return NAN;
    double below_y = NAN, below_w = NAN;
    for (size_t j = 0; j < sp->per_line; j++) {
        const size_t k = sp->order[base + j];
        const double w = (double)sp->u_count[k] / (double)sp->rows;
        if (w < 0.5)
            return j == 0 ? NAN : below_y + (below_w - 0.5) / (below_w - w) * (sp->y[k] - below_y);
        below_y = sp->y[k];
        below_w = w;
    }
    return NAN;
}

/* Each line's profile in the order of y: U/Uc max, the surface, and with
 * air Y90, d, C_mean and C_core; then the inception line. */
static int step_line_summaries(analyze_ctx *cx, const options *o, step_profiles *sp)
{
    const size_t n = (size_t)sp->lines, per_line = sp->per_line;
    sp->y90 = analyze_alloc(cx, n, sizeof *sp->y90);
    sp->depth = analyze_alloc(cx, n, sizeof *sp->depth);
    sp->c_mean = analyze_alloc(cx, n, sizeof *sp->c_mean);
    sp->u_max = analyze_alloc(cx, n, sizeof *sp->u_max);
    sp->c_core = analyze_alloc(cx, n, sizeof *sp->c_core);
    sp->surface = analyze_alloc(cx, n, sizeof *sp->surface);
    double *ys = analyze_alloc(cx, per_line, sizeof *ys);
    double *cs = analyze_alloc(cx, per_line, sizeof *cs);
    int status = -1;
    if (!sp->y90 || !sp->depth || !sp->c_mean || !sp->u_max || !sp->c_core || !sp->surface || !ys ||
        !cs)
        goto done;
    for (size_t l = 0; l < n; l++) {
        const size_t base = l * per_line;
        sp->u_max[l] = NAN;
        for (size_t j = 0; j < per_line; j++) {
            const size_t k = sp->order[base + j];
            ys[j] = sp->y[k];
            cs[j] = sp->c[k];
            if (isfinite(sp->u[k]) && !(sp->u[k] <= sp->u_max[l]))
                sp->u_max[l] = sp->u[k];
        }
        sp->surface[l] = step_surface(sp, base);
        sp->y90[l] = sp->depth[l] = sp->c_mean[l] = sp->c_core[l] = NAN;
        if (sp->has_air && sluice_hyd_aerated_depths(ys, cs, per_line, 0.9, &sp->y90[l],
                                                     &sp->depth[l], &sp->c_mean[l]) == 0)
            sp->c_core[l] =
                sluice_hyd_band_mean(ys, cs, per_line, 0.2 * sp->y90[l], 0.5 * sp->y90[l]);
    }
    sp->inception = sp->has_air ? sluice_hyd_first_above(sp->c_core, n, o->threshold) : -1;
    status = 0;
done:
    free(ys);
    free(cs);
    return status;
}

/* The profiles as CSV: a heading, one section per edge, the per-edge
 * summary and the inception (docs/analysis.md). */
static void step_write_csv(FILE *f, const options *o, const char *file, const gauge_table *g,
                           const step_profiles *sp)
{
    const long first = (long)o->first_step;
    fprintf(f,
            "# step-profiles %s: window [%.10g, %.10g] s, %zu samples; theta = %.10g deg, "
            "dc = %.10g m, Uc = %.10g m/s (sqrt(g dc) = q/dc = %.6g m/s); %ld edges of %zu "
            "points; h = %.6g m\n",
            file, g->time[g->first], g->time[g->last - 1], sp->rows, o->theta, o->dc, o->uc,
            sqrt(o->g * o->dc), sp->lines, sp->per_line, sp->h);
    for (long l = 0; l < sp->lines; l++) {
        fprintf(f, "\n# step %ld: edge (%.10g, %.10g) m\n", first + l, sp->ex[l], sp->ey[l]);
        fprintf(f, "step,point,y,y_dc,U_Uc,U_samples,C,C_samples\n");
        for (size_t j = 0; j < sp->per_line; j++) {
            const size_t k = sp->order[(size_t)l * sp->per_line + j];
            fprintf(f, "%ld,%zu,%.10g,%.10g,%.10g,%zu,%.10g,%zu\n", first + l, k, sp->y[k],
                    sp->y[k] / o->dc, sp->u[k], sp->u_count[k], sp->c[k], sp->c_count[k]);
        }
    }
    fprintf(f, "\n# per edge: Y90 (C = 0.9), d = integral_0^Y90 (1 - C) dy, C_mean = 1 - "
               "d/Y90, max U/Uc, C_core = mean C over 0.2-0.5 Y90, surface = y wet half of the "
               "time\n");
    fprintf(f, "step,edge_x,edge_y,Y90,Y90_dc,d,d_dc,C_mean,U_Uc_max,C_core,surface,"
               "surface_dc\n");
    for (long l = 0; l < sp->lines; l++)
        fprintf(f, "%ld,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g\n",
                first + l, sp->ex[l], sp->ey[l], sp->y90[l], sp->y90[l] / o->dc, sp->depth[l],
                sp->depth[l] / o->dc, sp->c_mean[l], sp->u_max[l], sp->c_core[l], sp->surface[l],
                sp->surface[l] / o->dc);
    fprintf(f, "\n# inception of free-surface aeration: the first edge whose C_core exceeds the "
               "threshold\n");
    fprintf(f, "inception_step,edge_x,edge_y,C_core,threshold\n");
    const long i = sp->inception;
    if (i >= 0)
        fprintf(f, "%ld,%.10g,%.10g,%.10g,%.10g\n", first + i, sp->ex[i], sp->ey[i], sp->c_core[i],
                o->threshold);
    else
        fprintf(f, "nan,nan,nan,nan,%.10g\n", o->threshold);
}

/* For a run directory: the headline figures as `name = value` lines, one
 * per edge and quantity (named by the step), and the inception step. */
static void step_print_figures(const options *o, const step_profiles *sp)
{
    const long first = (long)o->first_step;
    for (long l = 0; l < sp->lines; l++) {
        const long s = first + l;
        printf("U_Uc_max_step%ld = %.10g\n", s, sp->u_max[l]);
        printf("surface_dc_step%ld = %.10g\n", s, sp->surface[l] / o->dc);
        if (sp->has_air) {
            printf("Y90_dc_step%ld = %.10g\n", s, sp->y90[l] / o->dc);
            printf("d_dc_step%ld = %.10g\n", s, sp->depth[l] / o->dc);
            printf("C_mean_step%ld = %.10g\n", s, sp->c_mean[l]);
            printf("C_core_step%ld = %.10g\n", s, sp->c_core[l]);
        }
    }
    if (sp->has_air) {
        if (sp->inception >= 0)
            printf("inception_step = %ld\n", first + sp->inception);
        else
            printf("inception_step = nan\n");
    }
}

static void step_warnings(const options *o, const char *file, const step_profiles *sp)
{
    const long first = (long)o->first_step;
    if (sp->has_air && isfinite(sp->h))
        for (long l = 0; l < sp->lines; l++)
            if (sp->y90[l] < STEP_MIN_Y90_OVER_H * sp->h)
                fprintf(stderr,
                        "sluice-analyze: warning: step %ld: Y90 = %.4g m < %.1f h = %.4g m: the "
                        "band 0.2-0.5 Y90 reaches the kernel smear of the free surface, so "
                        "C_core there is not entrainment alone\n",
                        first + l, sp->y90[l], STEP_MIN_Y90_OVER_H, STEP_MIN_Y90_OVER_H * sp->h);
    if (sp->has_air && !isfinite(sp->h))
        fprintf(stderr,
                "sluice-analyze: note: h unknown (no --h, no scene.resolved.yaml): the "
                "Y90 >= %.1f h check of the inception band is skipped\n",
                STEP_MIN_Y90_OVER_H);
    if (!sp->has_air)
        fprintf(stderr,
                "sluice-analyze: note: %s has no p<k>_air_fraction columns (point_gauge "
                "fields: velocity, air_fraction in a two_phase scene): no Y90, C_mean "
                "or inception\n",
                file);
}

/* Given a point_gauge CSV, the CSV on stdout and exit 1 when no edge
 * reaches the threshold; given a run directory, step_profiles.csv in --out
 * and the figures on stdout, no inception being a figure (nan), not a
 * failure. */
static int cmd_step_profiles(analyze_ctx *cx, const options *o)
{
    if (o->positional_count != 1)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "step-profiles needs a run directory or its point_gauge CSV file");
    if (step_check_options(cx, o) != 0)
        return -1;
    int is_run = 0, status = -1;
    step_profiles sp;
    memset(&sp, 0, sizeof sp);
    sp.per_line = (size_t)o->per_line;
    gauge_table g;
    memset(&g, 0, sizeof g);
    char *out = NULL;
    char *file = step_points_file(cx, o->positional[0], &is_run);
    if (!file)
        goto done;
    sp.lines = analyze_parse_points(cx, "--edges", o->edges, &sp.ex, &sp.ey);
    if (sp.lines < 0 || gauge_table_load(cx, o, file, &g) != 0 ||
        step_point_means(cx, o, file, &g, &sp) != 0 || step_sort_lines(cx, o, &sp) != 0 ||
        step_line_summaries(cx, o, &sp) != 0)
        goto done;
    if (is_run) {
        char *path;
        out = out_dir(cx, o, o->positional[0]);
        FILE *f = out ? open_csv(cx, out, "step_profiles.csv", &path) : NULL;
        if (!f)
            goto done;
        printf("source = %s\n", file);
        step_write_csv(f, o, file, &g, &sp);
        if (close_csv(cx, f, path) != 0)
            goto done;
        step_print_figures(o, &sp);
    } else {
        step_write_csv(stdout, o, file, &g, &sp);
    }
    fflush(stdout);
    step_warnings(o, file, &sp);
    if (sp.has_air && sp.inception < 0 && !is_run)
        analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                     "no step edge has a mean air concentration above %g over 0.2-0.5 Y90 (no "
                     "inception of free-surface aeration among these edges)",
                     o->threshold);
    else
        status = 0;
done:
    gauge_table_free(&g);
    step_profiles_free(&sp);
    free(file);
    free(out);
    return status;
}

/* A run made with an `inlet` knows its inflow: when --d1, --v1 and --fr are
 * not given, take d1 and v1 from the inlet's depth and velocity (or
 * discharge / depth) in RUN/scene.resolved.yaml. Options given on the
 * command line win. */
static int inflow_from_run(analyze_ctx *cx, options *o)
{
    if (o->positional_count != 1 || (!isnan(o->d1) && (!isnan(o->v1) || !isnan(o->fr))))
        return 0;
    struct stat st;
    if (stat(o->positional[0], &st) != 0 || !S_ISDIR(st.st_mode))
        return 0; /* the command reports a missing run itself */
    run_data r;
    if (run_open(cx, o->positional[0], &r) != 0)
        return -1;
    double depth = NAN, velocity = NAN, discharge = NAN;
    analyze_scene_number(r.scene, "inlet", "depth", &depth);
    analyze_scene_number(r.scene, "inlet", "velocity", &velocity);
    analyze_scene_number(r.scene, "inlet", "discharge", &discharge);
    if (isnan(o->d1) && depth > 0)
        o->d1 = depth;
    if (isnan(o->v1) && isnan(o->fr)) {
        if (velocity > 0)
            o->v1 = velocity;
        else if (discharge > 0 && o->d1 > 0)
            o->v1 = discharge / o->d1;
    }
    analyze_scene_free(r.scene);
    return 0;
}

/* Dissolved oxygen at stations of --per-line points (a point_gauge with the
 * field dissolved_oxygen, phase water): per station the mean over the window
 * of each sample's mean over its wet points; the reaeration rate
 * r = (Cs - Cu) / (Cs - C_last) at the last station; with --calibrate S
 * --target C, the scale f of the source's K that brings station S to C
 * (sluice_hyd_do_calibrate: exact where oxygen changes by the source only)
 * and every station under it, the others being predictions. */
static int cmd_dissolved_oxygen(analyze_ctx *cx, const options *o)
{
    if (o->positional_count != 1)
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "dissolved-oxygen needs one point_gauge CSV file, POINTS.csv");
    const char *file = o->positional[0];
    if (need(cx, o, o->per_line, "per-line", 1) != 0 || need(cx, o, o->cs, "cs", 1) != 0 ||
        need(cx, o, o->cu, "cu", 0) != 0)
        return -1;
    if (!whole_number(o->per_line))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--per-line must be a whole number");
    if (!(o->cu >= 0.0 && o->cu < o->cs))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "--cu must be in [0, --cs): the inflow's DO below saturation");
    const int calibrating = !isnan(o->calibrate) || !isnan(o->target);
    if (calibrating && (isnan(o->calibrate) || isnan(o->target)))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "--calibrate STATION and --target C go together");
    if (calibrating && !(o->target > o->cu && o->target < o->cs))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "--target must lie between --cu and --cs");
    const size_t per = (size_t)o->per_line;
    const char *field = strcmp(o->field, "velocity") == 0 ? "dissolved_oxygen" : o->field;
    int status = -1;
    gauge_table g;
    double *readings = NULL, *station_mean = NULL, *calibrated = NULL;
    size_t *used = NULL;
    long *column = NULL;
    if (gauge_table_load(cx, o, file, &g) != 0)
        goto done;
    /* the columns p<k>_<field>, k = 0, 1, ... */
    size_t points = 0;
    for (;;) {
        char name[128];
        snprintf(name, sizeof name, "p%zu_%s", points, field);
        if (analyze_table_find(&g.table, name) < 0)
            break;
        points++;
    }
    if (points == 0 || points % per != 0) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                     "%s has %zu columns p<k>_%s, not a whole number of stations of %zu points",
                     file, points, field, per);
        goto done;
    }
    const size_t stations = points / per, samples = g.last - g.first;
    if (calibrating && !(whole_number(o->calibrate) && o->calibrate >= 1 &&
                         o->calibrate <= (double)stations)) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "--calibrate must be a station from 1 to %zu",
                     stations);
        goto done;
    }
    column = analyze_alloc(cx, points, sizeof *column);
    readings = analyze_alloc(cx, samples * per, sizeof *readings);
    station_mean = analyze_alloc(cx, stations, sizeof *station_mean);
    calibrated = analyze_alloc(cx, stations, sizeof *calibrated);
    used = analyze_alloc(cx, stations, sizeof *used);
    if (!column || !readings || !station_mean || !calibrated || !used)
        goto done;
    for (size_t k = 0; k < points; k++) {
        char name[128];
        snprintf(name, sizeof name, "p%zu_%s", k, field);
        column[k] = analyze_table_find(&g.table, name);
    }
    double scale = 1.0;
    for (int round = 0; round < 2; round++) {
        for (size_t s = 0; s < stations; s++) {
            for (size_t r = 0; r < samples; r++)
                for (size_t k = 0; k < per; k++)
                    readings[r * per + k] =
                        g.table.data[(g.first + r) * g.table.cols + (size_t)column[s * per + k]];
            if (round == 0) {
                station_mean[s] =
                    sluice_hyd_do_station_mean(readings, samples, per, o->cs, o->cu, 1.0, &used[s]);
                if (calibrating && s + 1 == (size_t)o->calibrate &&
                    sluice_hyd_do_calibrate(readings, samples, per, o->cs, o->cu, o->target,
                                            &scale) != 0) {
                    analyze_fail(cx, SLUICE_ANALYZE_NOT_FOUND,
                                 "station %zu (mean %g mg/L over %zu samples) cannot be brought to "
                                 "%g mg/L by scaling the source",
                                 s + 1, station_mean[s], used[s], o->target);
                    goto done;
                }
            } else {
                calibrated[s] =
                    sluice_hyd_do_station_mean(readings, samples, per, o->cs, o->cu, scale, NULL);
            }
        }
        if (!calibrating)
            break;
    }
    printf("# dissolved-oxygen %s: window [%.10g, %.10g] s, %zu samples, %zu stations of %zu "
           "points; Cs = %.10g, Cu = %.10g mg/L\n",
           file, g.time[g.first], g.time[g.last - 1], samples, stations, per, o->cs, o->cu);
    if (calibrating)
        printf("# calibrated on station %.0f (target %.10g mg/L): the source's K scaled by f = "
               "%.6g; the other stations are predictions\n",
               o->calibrate, o->target, scale);
    printf("station,mean_mg_L,samples%s\n", calibrating ? ",calibrated_mg_L" : "");
    for (size_t s = 0; s < stations; s++) {
        printf("%zu,%.6g,%zu", s + 1, station_mean[s], used[s]);
        if (calibrating)
            printf(",%.6g", calibrated[s]);
        printf("\n");
    }
    const double last = station_mean[stations - 1];
    if (!isnan(last)) {
        printf("# reaeration rate r = (Cs - Cu)/(Cs - C) at station %zu: %.6g", stations,
               (o->cs - o->cu) / (o->cs - last));
        if (calibrating)
            printf(" (calibrated: %.6g)", (o->cs - o->cu) / (o->cs - calibrated[stations - 1]));
        printf("\n");
    }
    status = 0;
done:
    analyze_table_free(&g.table);
    free(g.time);
    free(column);
    free(readings);
    free(station_mean);
    free(calibrated);
    free(used);
    return status;
}

/* The momentum function per section: the means over the window of d, q,
 * the momentum flux M, the pressure force P and S = M + P from the columns
 * of section_gauge with `forces: true` (N per metre of width), and, for a
 * column not wet to its top, the hydrostatic force rho0 g d^2 / 2 of its
 * mean depth (rho0 from particles.rest_density, default 1000; --g). A column
 * wet to its top (a face) has none: its surface is not in it. */
/* A profile across a flow from a point_gauge line (RUN/points.csv, or the
 * FILE of --column FILE:SUFFIX): each point's time mean of p<k>_SUFFIX over
 * the window, with the points' coordinates from the scene; the first
 * point's value over the largest (the slip at a wall when point 0 is the
 * one next to it); with --force F --viscosity NU --width L the L2 error
 * against the steady plane Poiseuille profile F / (2 NU) y (L - y) between
 * walls at y = 0 and y = L. */
static int cmd_profile(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    if (!run)
        return -1;
    const int poiseuille = !isnan(o->force) || !isnan(o->viscosity) || o->width > 0;
    if (poiseuille && !(o->force > 0 && o->viscosity > 0 && o->width > 0))
        return analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                            "the Poiseuille profile needs --force F (m s^-2), --viscosity NU "
                            "(m^2 s^-1) and --width L (m), each positive");
    const char *spec = o->column ? o->column : "velocity_x";
    const char *colon = strrchr(spec, ':');
    char *file = colon ? analyze_format(cx, "%s/%.*s", run, (int)(colon - spec), spec)
                       : analyze_format(cx, "%s/points.csv", run);
    const char *suffix = colon ? colon + 1 : spec;
    int status = -1;
    gauge_table g = {0};
    double *px = NULL, *py = NULL, *mean = NULL, *series = NULL, h;
    if (!file || gauge_table_load(cx, o, file, &g) != 0)
        goto done;
    const size_t n = count_point_columns(&g.table, suffix);
    if (n == 0) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%s has no column p0_%s", file, suffix);
        goto done;
    }
    long count = step_points(cx, o, file, &px, &py, &h);
    if (count < 0)
        goto done;
    if ((size_t)count != n) {
        analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT, "%ld point coordinates for the %zu points of %s",
                     count, n, file);
        goto done;
    }
    const size_t rows = g.last - g.first;
    mean = analyze_alloc(cx, n, sizeof *mean);
    series = analyze_alloc(cx, rows, sizeof *series);
    if (!mean || !series)
        goto done;
    double largest = -INFINITY, error = 0.0, norm = 0.0;
    for (size_t k = 0; k < n; k++) {
        long c = point_column(cx, &g, k, suffix);
        if (c < 0)
            goto done;
        for (size_t r = 0; r < rows; r++)
            series[r] = cell(&g, g.first + r, (size_t)c);
        double std;
        size_t used;
        if (sluice_hyd_mean_std(series, rows, &mean[k], &std, &used) != 0)
            mean[k] = NAN;
        if (mean[k] > largest)
            largest = mean[k];
        if (poiseuille) {
            const double exact = o->force / (2 * o->viscosity) * py[k] * (o->width - py[k]);
            error += (mean[k] - exact) * (mean[k] - exact);
            norm += exact * exact;
        }
    }
    printf("source = %s p<k>_%s\n", file, suffix);
    print_window(&g);
    printf("points = %zu\n", n);
    headline("first", mean[0], NULL);
    headline("max", largest, NULL);
    headline("first_over_max", mean[0] / largest, NULL);
    if (poiseuille) {
        headline("u_max_poiseuille", o->force * o->width * o->width / (8 * o->viscosity), "m/s");
        headline("l2_poiseuille", norm > 0 ? sqrt(error / norm) : NAN, NULL);
    }
    status = 0;
done:
    free(file);
    free(px);
    free(py);
    free(mean);
    free(series);
    gauge_table_free(&g);
    return status;
}

static int cmd_momentum(analyze_ctx *cx, const options *o)
{
    const char *run = run_dir(cx, o);
    if (!run)
        return -1;
    run_data r;
    if (run_open(cx, run, &r) != 0)
        return -1;
    int status = -1;
    gauge_table g = {0};
    double *xs = NULL, *beds = NULL, *tops = NULL, *column = NULL, *means = NULL;
    char *dir = NULL, *path = NULL, *csv = NULL;
    long nb = 0, nt = 0;
    long n = gauge_positions(cx, o, &r, "section_gauge", &xs);
    if (n < 0)
        goto done;
    if (r.scene) {
        nb = analyze_scene_numbers(cx, r.scene, "section_gauge", "bed_elevation", &beds);
        nt = analyze_scene_numbers(cx, r.scene, "section_gauge", "top", &tops);
        if (nb < 0 || nt < 0)
            goto done;
    }
    double rho0 = 1000;
    if (r.scene)
        analyze_scene_setting(r.scene, "particles", "rest_density", &rho0);
    path = gauge_path(cx, &r, "section_gauge", "sections.csv");
    if (!path || gauge_table_load(cx, o, path, &g) != 0)
        goto done;
    static const char *const names[5] = {"d", "q", "M", "P", "S"};
    column = analyze_alloc(cx, g.table.rows, sizeof *column);
    means = analyze_alloc(cx, 5 * (size_t)n, sizeof *means);
    if (!column || !means)
        goto done;
    for (long k = 0; k < n; k++) {
        long c[4];
        for (int q = 0; q < 4; q++) {
            char name[64];
            snprintf(name, sizeof name, "%s_x%ld", names[q], k);
            if (q >= 2 && analyze_table_find(&g.table, name) < 0) {
                analyze_fail(cx, SLUICE_ANALYZE_BAD_INPUT,
                             "%s has no column %s: run with plugins.section_gauge.forces: true",
                             path, name);
                goto done;
            }
            c[q] = analyze_table_column(cx, &g.table, name);
            if (c[q] < 0)
                goto done;
        }
        for (int q = 0; q < 5; q++) {
            if (q < 4)
                analyze_table_copy(&g.table, (size_t)c[q], column);
            else
                for (size_t i = 0; i < g.table.rows; i++)
                    column[i] = g.table.data[i * g.table.cols + (size_t)c[2]] +
                                g.table.data[i * g.table.cols + (size_t)c[3]];
            double mean, std;
            size_t used;
            if (sluice_hyd_mean_std(column + g.first, g.last - g.first, &mean, &std, &used) != 0)
                mean = NAN;
            means[5 * k + q] = mean;
        }
    }
    printf("source = %s\n", path);
    print_window(&g);
    headline("rest_density", rho0, "kg/m^3");
    printf("# x (m), bed (m), d (m), q (m^2/s), M (N/m), P (N/m), S = M + P (N/m), "
           "rho0 g d^2/2 (N/m)\n");
    dir = out_dir(cx, o, run);
    if (!dir)
        goto done;
    FILE *f = open_csv(cx, dir, "momentum.csv", &csv);
    if (!f)
        goto done;
    fprintf(f, "x,bed,d,q,M,P,S,P_hydrostatic,face\n");
    long first_full = -1, last_full = -1; /* sections not wet to their top */
    for (long k = 0; k < n; k++) {
        const double bed = nb > 0 ? beds[nb == 1 ? 0 : k] : 0;
        const double top = nt > 0 ? tops[nt == 1 ? 0 : k] : INFINITY;
        const double *m = means + 5 * k;
        /* a column wet to its top reads d = top - bed in every row */
        const int to_top = fabs(m[0] - (top - bed)) <= 1e-9 * (1 + fabs(top));
        const double hydrostatic = to_top ? NAN : rho0 * o->g * m[0] * m[0] / 2;
        if (!to_top && !isnan(m[4])) {
            if (first_full < 0)
                first_full = k;
            last_full = k;
        }
        printf("%g, %g, %.6g, %.6g, %.6g, %.6g, %.6g, %.6g%s\n", xs[k], bed, m[0], m[1], m[2],
               m[3], m[4], hydrostatic, to_top ? " (wet to its top: a face's force)" : "");
        fprintf(f, "%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%.10g,%d\n", xs[k], bed, m[0],
                m[1], m[2], m[3], m[4], hydrostatic, to_top);
    }
    for (long k = 0; k < n; k++) {
        char name[64];
        snprintf(name, sizeof name, "S_x%ld", k);
        headline(name, means[5 * k + 4], "N/m");
    }
    /* the walls' forces over the same window, when the run has wall_force */
    double walls_fx = 0;
    int walls_measured = 0;
    if (r.scene && analyze_scene_has(r.scene, "wall_force")) {
        char *walls_path = gauge_path(cx, &r, "wall_force", "wall_forces.csv");
        gauge_table w = {0};
        if (!walls_path || gauge_table_load(cx, o, walls_path, &w) != 0) {
            free(walls_path);
            goto done;
        }
        double *values = analyze_alloc(cx, w.table.rows, sizeof *values);
        if (!values) {
            gauge_table_free(&w);
            free(walls_path);
            goto done;
        }
        printf("# wall forces (%s), means over the window\n", walls_path);
        for (size_t c = 0; c < w.table.cols; c++) {
            const char *name = w.table.names[c];
            if (strncmp(name, "Fx_", 3) != 0 && strncmp(name, "Fy_", 3) != 0)
                continue;
            analyze_table_copy(&w.table, c, values);
            double mean, std;
            size_t used;
            if (sluice_hyd_mean_std(values + w.first, w.last - w.first, &mean, &std, &used) != 0)
                mean = NAN;
            headline(name, mean, "N/m");
            if (name[1] == 'x') {
                walls_fx += mean;
                walls_measured++;
            }
        }
        free(values);
        gauge_table_free(&w);
        free(walls_path);
    }
    /* the budget between the first and the last section that is not a
     * face column: S in - S out + the measured walls' x-force on the fluid
     * (-Fx), zero for a steady flow that no other force acts on */
    if (first_full >= 0 && last_full > first_full) {
        printf("# balance = S(x = %g) - S(x = %g) - sum of the measured walls' Fx (%d wall%s): "
               "0 for a steady flow without friction or other forces\n",
               xs[first_full], xs[last_full], walls_measured, walls_measured == 1 ? "" : "s");
        headline("balance", means[5 * first_full + 4] - means[5 * last_full + 4] - walls_fx,
                 "N/m");
    }
    if (close_csv(cx, f, csv) != 0)
        goto done;
    csv = NULL;
    char body[1024];
    snprintf(body, sizeof body,
             "set xlabel 'x (m)'\nset ylabel 'N per m of width'\nset key left top\n"
             "set title 'momentum function over [%g, %g] s'\n"
             "set datafile separator ','\n"
             "plot 'momentum.csv' using 1:($9 == 0 ? $7 : 1/0) skip 1 with linespoints "
             "title 'S = M + P', "
             "'' using 1:($9 == 0 ? $5 : 1/0) skip 1 with linespoints title 'M', "
             "'' using 1:($9 == 0 ? $6 : 1/0) skip 1 with linespoints title 'P', "
             "'' using 1:8 skip 1 with points title 'rho0 g d^2/2', "
             "'' using 1:($9 == 1 ? $6 : 1/0) skip 1 with points pt 7 ps 1.5 "
             "title 'P of a face column'\n",
             g.time[g.first], g.time[g.last - 1]);
    plot(cx, o, dir, "momentum", body);
    status = 0;
done:
    gauge_table_free(&g);
    analyze_scene_free(r.scene);
    free(xs);
    free(beds);
    free(tops);
    free(column);
    free(means);
    free(dir);
    free(path);
    free(csv);
    return status;
}

/* ------------------------------------------------------------ commands -- */

/* The commands, each with its usage (`sluice-analyze COMMAND --help`,
 * `sluice-analyze help COMMAND`): the options it reads (any other is
 * accepted with a warning that it has no effect: parse_options). */
#define WINDOW_HELP "  --from T0 --to T1     the time window (s; default the whole series)\n"
#define TIME_COLUMN_HELP "  --time-column NAME    the tables' time column (default time)\n"
#define OUT_HELP                                                                              \
    "  --out DIR             where the CSV and PNG go (default RUN/analysis)\n"               \
    "  --no-plot             no PNG (else drawn with gnuplot when installed)\n"
#define INFLOW_HELP                                                                           \
    "  --d1 D --v1 V         the inflow depth (m) and velocity (m/s), or --fr F instead of\n" \
    "                        --v1; without them, the run's inlet; --g 9.81 (m/s^2)\n"
#define SURFACE_HELP                                                                          \
    "  --positions a,b,..    the free-surface gauge's positions instead of\n"                 \
    "                        RUN/scene.resolved.yaml\n"
#define POINTS_HELP                                                                           \
    "  --points x,y;x,y..    the point gauge's points instead of RUN/scene.resolved.yaml\n"   \
    "  --field velocity      the point gauge's field\n"                                      \
    "  --min-wet 0.5         the least fraction of wet rows a point needs for a mean\n"       \
    "  --tolerance 1e-6      position matching (m)\n"
#define X1_HELP                                                                               \
    "  --x1 X1               the toe (m); default the mean toe as 'toe' finds it, with\n"     \
    "                        --fraction 0.5 and --bed B (m, default 0)\n"

static const struct command {
    const char *name;
    int (*run)(analyze_ctx *, const options *);
    const char *help;
} commands[] = {
    {"belanger", cmd_belanger,
     "usage: sluice-analyze belanger --d1 D (--v1 V | --fr F) [--g 9.81] [--out DIR]\n"
     "Belanger's conjugate depth d2 of a jump in a horizontal rectangular channel.\n"
     "  --d1 D                the inflow depth (m)\n"
     "  --v1 V | --fr F       the inflow velocity (m/s) or Froude number\n"
     "  --g 9.81              gravity (m/s^2)\n"
     "  --out DIR             also write belanger.csv and belanger.png into DIR\n"
     "  --no-plot             no PNG\n"},
    {"conjugate", cmd_conjugate,
     "usage: sluice-analyze conjugate RUN --x X [--d1 D --v1 V] [--from T0 --to T1]\n"
     "The sequent depth d2(t) at x = X (a section gauge there, else the free surface\n"
     "minus --bed) against Belanger's; seed 000's statistics A and P.\n"
     "  --x X                 the position (m)\n" INFLOW_HELP WINDOW_HELP
     "  --bed B               the bed elevation under the free-surface gauge (m, default 0)\n"
     "  --positions a,b,..    the section (or free-surface) gauge's positions instead of\n"
     "                        RUN/scene.resolved.yaml\n"
     "  --tolerance 1e-6      position matching (m)\n" TIME_COLUMN_HELP OUT_HELP},
    {"toe", cmd_toe,
     "usage: sluice-analyze toe RUN [--d1 D --v1 V] [--fraction 0.5] [--from T0 --to T1]\n"
     "The jump toe x1(t) from the free-surface profiles: the first position where the\n"
     "depth rises through d1 + fraction (d2_Belanger - d1).\n"
     "  --fraction 0.5        the threshold between d1 and d2\n"
     "  --bed B               the bed elevation (m, default 0)\n" INFLOW_HELP WINDOW_HELP
     SURFACE_HELP TIME_COLUMN_HELP OUT_HELP},
    {"roller", cmd_roller,
     "usage: sluice-analyze roller RUN [--d1 D --v1 V] [--x1 X1] [--from T0 --to T1]\n"
     "The roller length: the first position downstream of the toe with a non-negative\n"
     "time-mean horizontal velocity, against Hager et al. (1990).\n" X1_HELP
     INFLOW_HELP WINDOW_HELP POINTS_HELP SURFACE_HELP TIME_COLUMN_HELP OUT_HELP},
    {"vmax", cmd_vmax,
     "usage: sluice-analyze vmax RUN [--d1 D --v1 V] [--x1 X1] [--from T0 --to T1]\n"
     "The decay of each section's largest time-mean velocity, Vmax/V1, against Chanson\n"
     "(2010).\n" X1_HELP INFLOW_HELP WINDOW_HELP POINTS_HELP SURFACE_HELP TIME_COLUMN_HELP
     OUT_HELP},
    {"surface", cmd_surface,
     "usage: sluice-analyze surface RUN [--d1 D --v1 V] [--x1 X1] [--from T0 --to T1]\n"
     "The free surface's mean and standard deviation at each gauge, against Murzyn &\n"
     "Chanson (2009).\n" X1_HELP
     "  --min-wet 0.5         the least fraction of wet rows a gauge needs\n" INFLOW_HELP
     WINDOW_HELP SURFACE_HELP TIME_COLUMN_HELP OUT_HELP},
    {"spectrum", cmd_spectrum,
     "usage: sluice-analyze spectrum RUN --column [FILE:]NAME [--fmin F --fmax F]\n"
     "                      [--d1 D --v1 V] [--from T0 --to T1]\n"
     "The amplitude spectrum of one column, its dominant frequency and (given the\n"
     "inflow) the Strouhal number f d1 / V1.\n"
     "  --column [FILE:]NAME  the column (searched in the run's gauge files, or in FILE\n"
     "                        relative to RUN)\n"
     "  --fmin F --fmax F     the band searched for the peak (Hz)\n" INFLOW_HELP WINDOW_HELP
     TIME_COLUMN_HELP OUT_HELP},
    {"correlate", cmd_correlate,
     "usage: sluice-analyze correlate A.csv:COL B.csv:COL [--from T0 --to T1] [--out DIR]\n"
     "Pearson's correlation coefficient r of two series (seed 004), B interpolated onto\n"
     "A's times.\n" WINDOW_HELP TIME_COLUMN_HELP
     "  --out DIR             where the CSV and PNG go (default A.csv's directory/analysis)\n"
     "  --no-plot             no PNG\n"},
    {"profile", cmd_profile,
     "usage: sluice-analyze profile RUN [--column FILE:SUFFIX] [--force F --viscosity NU\n"
     "                     --width L] [--from T0 --to T1]\n"
     "A point_gauge line's time-mean profile: the slip at the wall and, given the\n"
     "Poiseuille flow's data, the error against it.\n"
     "  --column FILE:SUFFIX  the columns pK_SUFFIX of FILE (default points.csv:velocity_x)\n"
     "  --force F             the driving acceleration (m/s^2)\n"
     "  --viscosity NU        the kinematic viscosity (m^2/s)\n"
     "  --width L             the channel's width (m)\n"
     "  --points x,y;x,y..    the points instead of RUN/scene.resolved.yaml\n" WINDOW_HELP
     TIME_COLUMN_HELP},
    {"impact", cmd_impact,
     "usage: sluice-analyze impact RUN --column [FILE:]NAME --arrival P [--duration D]\n"
     "                    [--scale P0] [--time-scale T0] [--time-column t] [--from T0 --to T1]\n"
     "An impact on a pressure sensor: arrival, peak, rise time and impulse.\n"
     "  --column [FILE:]NAME  the sensor's column\n"
     "  --arrival P           the pressure that marks the arrival (the column's unit)\n"
     "  --duration D          the impact's duration after the arrival (s; default to the\n"
     "                        window's end)\n"
     "  --scale P0            divides the pressures (e.g. rho g H)\n"
     "  --time-scale T0       divides the times (e.g. sqrt(H/g))\n" WINDOW_HELP
     TIME_COLUMN_HELP},
    {"l2", cmd_l2,
     "usage: sluice-analyze l2 RUN --reference REF.csv [--time T]\n"
     "The free surface's L2 error and RMSE against measured levels (seed 002).\n"
     "  --reference REF.csv   the measured levels\n"
     "  --time T              the time of the measured profile when REF.csv has no time\n"
     "                        column\n" SURFACE_HELP WINDOW_HELP TIME_COLUMN_HELP OUT_HELP},
    {"front", cmd_front,
     "usage: sluice-analyze front RUN --reference REF.csv [--shift DT] [--width A]\n"
     "                   [--series A_IN] [--from T0 --to T1]\n"
     "A dam break's surge front against Martin & Moyce (1952): raw, shifted and\n"
     "best-fit time origin.\n"
     "  --reference REF.csv   the experiment's points (columns T, Z, optionally a_in)\n"
     "  --shift DT            a time shift (s) for the shifted comparison\n"
     "  --width A             the column's width (m; default from the scene)\n"
     "  --series A_IN         the reference series (a_in; default the first)\n"
     "  --g 9.81              gravity (m/s^2)\n"
     "  --out DIR             where the CSV goes (default RUN/analysis)\n" WINDOW_HELP},
    {"classify", cmd_classify,
     "usage: sluice-analyze classify --y1 Y1 --yt YT --v1 V --drop S [--out DIR]\n"
     "The jump at an abrupt drop (momentum limits): A-jump, wave-jump region or B-jump.\n"
     "  --y1 Y1               the inflow depth on the upper bed (m)\n"
     "  --yt YT               the tailwater depth above the lower bed (m)\n"
     "  --v1 V | --fr F       the inflow velocity (m/s) or Froude number\n"
     "  --drop S              the step height (m)\n"
     "  --g 9.81              gravity (m/s^2)\n"
     "  --out DIR             also write classify.csv and classify.png into DIR\n"
     "  --no-plot             no PNG\n"},
    {"drop-type", cmd_drop_type,
     "usage: sluice-analyze drop-type RUN [--drop-x X] [--drop S] [--d1 D --v1 V]\n"
     "                       [--fraction 0.5] [--wave-min 0.1] [--from T0 --to T1]\n"
     "The jump type at an abrupt drop from a run's free surface.\n"
     "  --drop-x X            the step edge's position (m; default from the scene)\n"
     "  --drop S              the step height (m; default the inlet's bed)\n"
     "  --fraction 0.5        the toe's threshold between d1 and d2\n"
     "  --wave-min 0.1        the share of wave samples below which the type is an A- or\n"
     "                        B-jump (above 1 - it, a wave jump)\n"
     INFLOW_HELP WINDOW_HELP SURFACE_HELP TIME_COLUMN_HELP OUT_HELP},
    {"momentum", cmd_momentum,
     "usage: sluice-analyze momentum RUN [--from T0 --to T1] [--g 9.81]\n"
     "The mean momentum function S = M + P per section (section_gauge with forces:\n"
     "true) and the hydrostatic force of the mean depth.\n"
     "  --g 9.81              gravity (m/s^2)\n"
     "  --positions a,b,..    the section gauge's positions instead of\n"
     "                        RUN/scene.resolved.yaml\n" WINDOW_HELP TIME_COLUMN_HELP OUT_HELP},
    {"step-profiles", cmd_step_profiles,
     "usage: sluice-analyze step-profiles RUN|POINTS.csv --per-line N --edges x,y;x,y..\n"
     "                           --theta DEG --dc DC --uc UC [--first-step 1]\n"
     "                           [--threshold 0.05] [--h H] [--points x,y;..]\n"
     "Velocity and air-concentration profiles at the step edges of a stepped chute:\n"
     "U/Uc, C, Y90, the free surface and the inception of aeration (CSV on stdout given\n"
     "POINTS.csv).\n"
     "  --per-line N          points per step edge\n"
     "  --edges x,y;x,y..     the step edges (m)\n"
     "  --theta DEG           the chute's slope (degrees)\n"
     "  --dc DC --uc UC       the critical depth (m) and velocity (m/s)\n"
     "  --first-step 1        the number of the first edge\n"
     "  --threshold 0.05      the air concentration of the aerated flow's edge\n"
     "  --h H                 the smoothing length (m; default from the scene)\n"
     "  --points x,y;x,y..    the points instead of the scene.resolved.yaml beside them\n"
     "  --field velocity      the point gauge's field\n"
     "  --tolerance 1e-6      position matching (m)\n"
     "  --g 9.81              gravity (m/s^2)\n" WINDOW_HELP TIME_COLUMN_HELP
     "  --out DIR             where the CSV goes (default RUN/analysis)\n"},
    {"dissolved-oxygen", cmd_dissolved_oxygen,
     "usage: sluice-analyze dissolved-oxygen POINTS.csv --per-line N --cs CS --cu CU\n"
     "                              [--calibrate S --target C] [--field dissolved_oxygen]\n"
     "Dissolved oxygen per station of N points, the reaeration rate, and the source's\n"
     "scale calibrated on one station (CSV on stdout).\n"
     "  --per-line N          points per station\n"
     "  --cs CS               the saturation concentration\n"
     "  --cu CU               the inflow's concentration\n"
     "  --calibrate S         the station (1..) to calibrate on, with --target C\n"
     "  --target C            the concentration measured at that station\n"
     "  --field NAME          the point gauge's field (default dissolved_oxygen)\n" WINDOW_HELP
     TIME_COLUMN_HELP},
};

static const struct command *find_command(const char *name)
{
    for (size_t k = 0; k < sizeof commands / sizeof *commands; k++)
        if (strcmp(commands[k].name, name) == 0)
            return &commands[k];
    return NULL;
}

/* `sluice-analyze COMMAND ... --help`: -h or --help among the arguments. */
static int asks_for_help(int argc, char **argv)
{
    for (int i = 2; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0)
            return 1;
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fputs(usage, stderr);
        return SLUICE_ANALYZE_BAD_INPUT;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 ||
        strcmp(argv[1], "help") == 0) {
        /* `sluice-analyze help [COMMAND]` */
        const struct command *topic = argc > 2 && strcmp(argv[1], "help") == 0
                                          ? find_command(argv[2])
                                          : NULL;
        if (argc > 2 && strcmp(argv[1], "help") == 0 && !topic) {
            fprintf(stderr,
                    "sluice-analyze: error: unknown command '%s' (sluice-analyze --help lists "
                    "them)\n",
                    argv[2]);
            return SLUICE_ANALYZE_BAD_INPUT;
        }
        fputs(topic ? topic->help : usage, stdout);
        return SLUICE_ANALYZE_OK;
    }
    analyze_ctx cx = {{0}, SLUICE_ANALYZE_OK};
    options o = {0};
    o.command = argv[1];
    o.d1 = o.v1 = o.fr = o.x = o.x1 = o.drop = o.y1 = o.yt = o.fmin = o.fmax = o.drop_x = NAN;
    o.per_line = o.theta = o.dc = o.uc = o.h = NAN;
    o.cs = o.cu = o.calibrate = o.target = o.arrival = o.duration = o.scale = o.time_scale = NAN;
    o.force = o.viscosity = NAN;
    o.threshold = 0.05;
    o.first_step = 1;
    o.wave_min = 0.1;
    o.g = 9.81;
    o.from = -INFINITY;
    o.to = INFINITY;
    o.fraction = 0.5;
    o.bed = 0.0;
    o.min_wet = 0.5;
    o.tolerance = 1e-6;
    o.field = "velocity";
    const struct command *command = find_command(argv[1]);
    if (command && asks_for_help(argc, argv)) {
        fputs(command->help, stdout);
        return SLUICE_ANALYZE_OK;
    }
    if (!command)
        analyze_fail(&cx, SLUICE_ANALYZE_BAD_INPUT,
                     "unknown command '%s' (sluice-analyze --help lists them)", argv[1]);
    else if (parse_options(&cx, argc, argv, &o, command->help) == 0) {
        if (!(o.from <= o.to))
            analyze_fail(&cx, SLUICE_ANALYZE_BAD_INPUT, "--from must not exceed --to");
        else if (!(o.min_wet >= 0.0 && o.min_wet <= 1.0))
            analyze_fail(&cx, SLUICE_ANALYZE_BAD_INPUT, "--min-wet must be in [0, 1]");
        else if (!(o.tolerance >= 0.0))
            analyze_fail(&cx, SLUICE_ANALYZE_BAD_INPUT, "--tolerance must be >= 0");
        else if (inflow_from_run(&cx, &o) == 0)
            command->run(&cx, &o);
    }
    fflush(stdout);
    if (cx.status != SLUICE_ANALYZE_OK)
        fprintf(stderr, "sluice-analyze: %s: %s\n",
                cx.status == SLUICE_ANALYZE_NOT_FOUND ? "not found" : "error", cx.message);
    return cx.status;
}
