/* The measures of a study's runs, their observed orders of convergence over
 * the spacing axis, and the reports: OUT/study.csv, OUT/orders.csv,
 * OUT/study.md and (gnuplot permitting) PNG plots in OUT/plots. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "study.h"

/* ------------------------------------------------------------ measures -- */

/* The measure's time window in the run: from/to, or the run's last seconds
 * or share. */
static void study_window(const study_measure *m, const study_run *r, double *from, double *to)
{
    *from = m->from;
    *to = m->to;
    if (m->last > 0 || m->last_share > 0) {
        *from = r->end_time - (m->last > 0 ? m->last : m->last_share * r->end_time);
        *to = r->end_time;
    }
}

/* Splits a CSV line in place; returns the number of fields. */
static size_t split(char *line, char **fields, size_t max)
{
    size_t n = 0;
    line[strcspn(line, "\r\n")] = '\0';
    for (char *p = line; n < max;) {
        while (*p == ' ')
            p++;
        fields[n++] = p;
        char *comma = strchr(p, ',');
        if (!comma)
            break;
        *comma = '\0';
        p = comma + 1;
    }
    return n;
}

/* A gauge column of the run reduced over the measure's window. */
static double gauge_value(const study *s, const study_run *r, const study_measure *m)
{
    char *path = study_printf("%s/runs/%s/%s", s->out, r->name, m->file);
    FILE *f = fopen(path, "r");
    free(path);
    if (!f)
        return NAN;
    double from, to;
    study_window(m, r, &from, &to);
    enum { MAX_FIELDS = 4096 };
    char **fields = malloc(MAX_FIELDS * sizeof *fields);
    size_t size = 1 << 16;
    char *line = malloc(size);
    double result = NAN;
    long time_col = -1, col = -1;
    double sum = 0, sum2 = 0, count = 0, integral = 0, extreme = NAN, at = NAN, first = NAN,
           last = NAN, previous_t = NAN, previous_v = NAN;
    while (fields && line && getline(&line, &size, f) > 0) {
        if (line[0] == '#' || line[0] == '\n')
            continue;
        size_t n = split(line, fields, MAX_FIELDS);
        if (col < 0) { /* the header */
            for (size_t i = 0; i < n; i++) {
                if (strcmp(fields[i], m->column) == 0)
                    col = (long)i;
                if (strcmp(fields[i], "time") == 0 || strcmp(fields[i], "time_s") == 0 ||
                    strcmp(fields[i], "t") == 0)
                    time_col = (long)i;
            }
            if (col < 0)
                break;
            if (time_col < 0)
                time_col = 0;
            continue;
        }
        if ((size_t)col >= n || (size_t)time_col >= n)
            continue;
        double t = strtod(fields[time_col], NULL), v = strtod(fields[col], NULL);
        if (!(t >= from && t <= to) || !isfinite(v))
            continue;
        if (count == 0)
            first = v;
        last = v;
        sum += v;
        sum2 += v * v;
        count++;
        if (isfinite(previous_t))
            integral += 0.5 * (v + previous_v) * (t - previous_t);
        previous_t = t;
        previous_v = v;
        int take_max = m->reduce == REDUCE_MAX || m->reduce == REDUCE_TIME_OF_MAX;
        if (isnan(extreme) || (take_max ? v > extreme : v < extreme)) {
            extreme = v;
            at = t;
        }
    }
    fclose(f);
    free(fields);
    free(line);
    if (count == 0)
        return NAN;
    double mean = sum / count;
    switch (m->reduce) {
    case REDUCE_MEAN:
        result = mean;
        break;
    case REDUCE_MAX:
    case REDUCE_MIN:
        result = extreme;
        break;
    case REDUCE_FIRST:
        result = first;
        break;
    case REDUCE_LAST:
        result = last;
        break;
    case REDUCE_STD:
        result = sqrt(fmax(0, sum2 / count - mean * mean));
        break;
    case REDUCE_RMS:
        result = sqrt(sum2 / count);
        break;
    case REDUCE_INTEGRAL:
        result = integral;
        break;
    case REDUCE_TIME_OF_MAX:
    case REDUCE_TIME_OF_MIN:
        result = at;
        break;
    default:
        break;
    }
    return result;
}

/* A figure `key = value` printed by sluice-analyze on the run. */
static double analysis_value(const study *s, const study_run *r, const study_measure *m)
{
    char **argv = calloc(m->argument_count + 9, sizeof *argv);
    if (!argv)
        return NAN;
    char *dir = study_printf("%s/runs/%s", s->out, r->name);
    char *out = study_printf("%s/runs/%s/analysis", s->out, r->name);
    char from[64], to[64];
    size_t n = 0;
    argv[n++] = (char *)s->analyze;
    argv[n++] = m->arguments[0];
    argv[n++] = dir;
    for (size_t i = 1; i < m->argument_count; i++)
        argv[n++] = m->arguments[i];
    /* the window: the run's last seconds, or from/to */
    double t0, t1;
    study_window(m, r, &t0, &t1);
    if (isfinite(t0)) {
        snprintf(from, sizeof from, "%.10g", t0);
        argv[n++] = "--from";
        argv[n++] = from;
    }
    if (isfinite(t1)) {
        snprintf(to, sizeof to, "%.10g", t1);
        argv[n++] = "--to";
        argv[n++] = to;
    }
    argv[n++] = "--out";
    argv[n++] = out;
    argv[n] = NULL;
    int pipefd[2];
    double value = NAN;
    if (pipe(pipefd) == 0) {
        pid_t pid = fork();
        if (pid == 0) {
            dup2(pipefd[1], STDOUT_FILENO);
            int null = open("/dev/null", O_WRONLY);
            if (null >= 0)
                dup2(null, STDERR_FILENO);
            close(pipefd[0]);
            execv(argv[0], argv);
            _exit(127);
        }
        close(pipefd[1]);
        FILE *f = fdopen(pipefd[0], "r");
        char line[4096];
        size_t key_length = strlen(m->key);
        while (f && fgets(line, sizeof line, f))
            if (strncmp(line, m->key, key_length) == 0 && strncmp(line + key_length, " = ", 3) == 0)
                value = strtod(line + key_length + 3, NULL);
        if (f)
            fclose(f);
        int status = 0;
        if (pid > 0)
            waitpid(pid, &status, 0);
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
            value = NAN;
    }
    free(dir);
    free(out);
    free(argv);
    return value;
}

/* A top-level number of run.json. */
static double run_value(const study *s, const study_run *r, const char *key)
{
    char text[8192];
    if (study_run_json_head(s, r, text, sizeof text) != 0)
        return NAN;
    char *pattern = study_printf("\"%s\": ", key);
    const char *at = strstr(text, pattern);
    double value = at ? strtod(at + strlen(pattern), NULL) : NAN;
    free(pattern);
    return value;
}

int study_measure_runs(study *s)
{
    for (size_t i = 0; i < s->run_count; i++) {
        study_run *r = &s->runs[i];
        free(r->values);
        free(r->errors);
        r->values = calloc(s->measure_count + 1, sizeof *r->values);
        r->errors = calloc(s->measure_count + 1, sizeof *r->errors);
        if (!r->values || !r->errors)
            return -1;
        for (size_t k = 0; k < s->measure_count; k++) {
            const study_measure *m = &s->measures[k];
            double v = NAN;
            if (r->state == RUN_DONE)
                v = m->source == SOURCE_GAUGE      ? gauge_value(s, r, m)
                    : m->source == SOURCE_ANALYSIS ? analysis_value(s, r, m)
                                                   : run_value(s, r, m->key);
            r->values[k] = v * m->scale;
        }
        /* the errors once every value is known (a reference may be another
         * measure's value) */
        for (size_t k = 0; k < s->measure_count; k++) {
            const study_measure *m = &s->measures[k];
            const double v = r->values[k];
            const double reference = m->reference_measure
                                         ? m->reference_factor * r->values[m->reference_index]
                                         : m->reference;
            r->errors[k] = !m->has_reference ? NAN
                           : m->absolute     ? v - reference
                                             : v / reference - 1;
        }
    }
    return 0;
}

/* -------------------------------------------------------------- orders -- */

/* The axis of the observed orders: the spacing, or a parameter axis with
 * convergence: true (axis_count: none). */
static size_t convergence_axis(const study *s)
{
    for (size_t a = 0; a < s->axis_count; a++)
        if (s->axes[a].convergence)
            return a;
    return s->axis_count;
}

/* Whether runs a and b differ only in the spacing. */
static int same_group(const study *s, const study_run *a, const study_run *b)
{
    size_t sp = convergence_axis(s);
    for (size_t k = 0; k < s->axis_count; k++)
        if (k != sp && a->choice[k] != b->choice[k])
            return 0;
    return 1;
}

/* The group's label: the values of the axes other than the spacing. */
static char *group_label(const study *s, const study_run *r)
{
    size_t sp = convergence_axis(s);
    char *label = study_strdup("");
    for (size_t a = 0; a < s->axis_count; a++) {
        if (a == sp)
            continue;
        char *longer =
            study_printf("%s%s%s", label, *label ? "/" : "", s->axes[a].values[r->choice[a]].label);
        free(label);
        label = longer;
    }
    if (!*label) {
        free(label);
        label = study_strdup("all");
    }
    return label;
}

/* The runs of r's group with a value of measure k (k = measure_count:
 * every run of the group), coarse to fine. */
static size_t group_members(const study *s, const study_run *r, size_t k, const study_run **out)
{
    size_t n = 0;
    for (size_t i = 0; i < s->run_count; i++) {
        const study_run *o = &s->runs[i];
        if (same_group(s, r, o) &&
            (k == s->measure_count || (isfinite(o->values[k]) && isfinite(o->resolution))))
            out[n++] = o;
    }
    for (size_t i = 1; i < n; i++) /* insertion sort by spacing, descending */
        for (size_t j = i; j > 0 && out[j]->resolution > out[j - 1]->resolution; j--) {
            const study_run *t = out[j];
            out[j] = out[j - 1];
            out[j - 1] = t;
        }
    return n;
}

/* Appends to a fixed buffer (truncating). */
static void append(char *buffer, size_t size, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
static void append(char *buffer, size_t size, const char *format, ...)
{
    size_t used = strlen(buffer);
    if (used + 1 >= size)
        return;
    va_list ap;
    va_start(ap, format);
    vsnprintf(buffer + used, size - used, format, ap);
    va_end(ap);
}

/* Writes the observed orders of every group and measure: from the errors
 * against the reference between successive spacings, or (no reference)
 * Richardson's from three successive values with its extrapolated value. */
static void write_orders(study *s, FILE *csv, FILE *md)
{
    size_t sp = convergence_axis(s);
    if (sp == s->axis_count)
        return;
    const study_run **members = calloc(s->run_count + 1, sizeof *members);
    if (!members)
        return;
    fprintf(csv, "group,measure,spacings,values,errors,observed_orders,richardson_order,"
                 "richardson_value\n");
    fprintf(
        md,
        "\n## Observed orders of convergence\n\n"
        "Between successive values of the convergence axis (the spacing dx, or a parameter "
        "such as the time step; coarse to fine): p = ln(|e_coarse| / |e_fine|) / "
        "ln(dx_coarse / dx_fine) for the error e against the reference; without a "
        "reference, Richardson's p = ln(|f1 - f2| / |f2 - f3|) / ln(r) from three values "
        "and the value it extrapolates to (monotone sequences at a constant spacing ratio only: "
        "nan where the values oscillate).\n\n"
        "| group | measure | %s | errors | observed orders | Richardson p | "
        "extrapolated |\n|---|---|---|---|---|---|---|\n",
        s->axes[sp].kind == AXIS_SPACING ? "spacings (m)" : s->axes[sp].name);
    for (size_t i = 0; i < s->run_count; i++) {
        const study_run *r = &s->runs[i];
        int first = 1; /* only the group's first run writes it */
        for (size_t j = 0; j < i; j++)
            if (same_group(s, r, &s->runs[j]))
                first = 0;
        if (!first)
            continue;
        char *label = group_label(s, r);
        for (size_t k = 0; k < s->measure_count; k++) {
            const study_measure *m = &s->measures[k];
            size_t n = group_members(s, r, k, members);
            if (n < 2)
                continue;
            char spacings[512] = "", values[512] = "", errors[512] = "", orders[512] = "";
            for (size_t j = 0; j < n; j++) {
                const char *sep = j ? ";" : "";
                append(spacings, sizeof spacings, "%s%g", sep, members[j]->resolution);
                append(values, sizeof values, "%s%.6g", sep, members[j]->values[k]);
                if (!m->has_reference)
                    continue;
                append(errors, sizeof errors, "%s%.4g", sep, members[j]->errors[k]);
                if (j) {
                    double p = log(fabs(members[j - 1]->errors[k]) / fabs(members[j]->errors[k])) /
                               log(members[j - 1]->resolution / members[j]->resolution);
                    append(orders, sizeof orders, "%s%.2f", j > 1 ? ";" : "", p);
                }
            }
            double richardson = NAN, extrapolated = NAN;
            if (n >= 3) {
                double f1 = members[n - 3]->values[k], f2 = members[n - 2]->values[k],
                       f3 = members[n - 1]->values[k];
                double ratio = members[n - 3]->resolution / members[n - 2]->resolution;
                /* monotone convergence only: an oscillating sequence has no order */
                double ratio2 = members[n - 2]->resolution / members[n - 1]->resolution;
                if ((f1 - f2) * (f2 - f3) > 0 && fabs(ratio / ratio2 - 1) < 0.01)
                    richardson = log(fabs(f1 - f2) / fabs(f2 - f3)) / log(ratio);
                if (isfinite(richardson) && richardson > 0)
                    extrapolated = f3 + (f3 - f2) / (pow(ratio, richardson) - 1);
            }
            fprintf(csv, "%s,%s,%s,%s,%s,%s,%.4g,%.6g\n", label, m->name, spacings, values, errors,
                    orders, richardson, extrapolated);
            fprintf(md, "| %s | %s | %s | %s | %s | %.2f | %.6g |\n", label, m->name, spacings,
                    m->has_reference ? errors : "-", m->has_reference ? orders : "-", richardson,
                    extrapolated);
        }
        free(label);
    }
    free(members);
}

/* ---------------------------------------------------------- status map -- */

static const char *state_name(const study_run *r);

/* The run with values i and j of the first two axes and r's values of the
 * others, or NULL. */
static const study_run *map_run(const study *s, const study_run *r, size_t i, size_t j)
{
    for (size_t n = 0; n < s->run_count; n++) {
        const study_run *o = &s->runs[n];
        int same = o->choice[0] == i && o->choice[1] == j;
        for (size_t a = 2; same && a < s->axis_count; a++)
            same = o->choice[a] == r->choice[a];
        if (same)
            return o;
    }
    return NULL;
}

/* How each run ended, on the grid of the first two axes (one grid per
 * combination of the other axes): complete with its largest density
 * deviation, or the time a run stopped at (a stability map). */
static void write_status_map(const study *s, FILE *md)
{
    if (s->axis_count < 2)
        return;
    const study_axis *rows = &s->axes[0], *columns = &s->axes[1];
    fprintf(md, "\n## Status map\n\nHow each run ended, %s (rows) against %s (columns): "
                "complete with its largest fluid density deviation |rho/rho0 - 1|, or the "
                "simulated time at which it stopped (the reason under *Runs skipped or "
                "failed*).\n",
            rows->name, columns->name);
    for (size_t n = 0; n < s->run_count; n++) {
        const study_run *r = &s->runs[n];
        if (r->choice[0] != 0 || r->choice[1] != 0)
            continue;
        if (s->axis_count > 2) {
            fprintf(md, "\n###");
            for (size_t a = 2; a < s->axis_count; a++)
                fprintf(md, " %s %s", s->axes[a].name, s->axes[a].values[r->choice[a]].label);
            fprintf(md, "\n");
        }
        fprintf(md, "\n| %s \\ %s |", rows->name, columns->name);
        for (size_t j = 0; j < columns->count; j++)
            fprintf(md, " %s |", columns->values[j].label);
        fprintf(md, "\n|---|");
        for (size_t j = 0; j < columns->count; j++)
            fprintf(md, "---|");
        fprintf(md, "\n");
        for (size_t i = 0; i < rows->count; i++) {
            fprintf(md, "| %s |", rows->values[i].label);
            for (size_t j = 0; j < columns->count; j++) {
                const study_run *c = map_run(s, r, i, j);
                if (!c) {
                    fprintf(md, " |");
                    continue;
                }
                const double deviation = run_value(s, c, "max_density_deviation");
                const double reached = run_value(s, c, "simulated_time");
                if (c->state == RUN_DONE)
                    fprintf(md, " complete, %.2g %% |", 100 * deviation);
                else if (c->state == RUN_FAILED && isfinite(reached))
                    fprintf(md, " %s at %.3g s |", state_name(c), reached);
                else
                    fprintf(md, " %s |", state_name(c));
            }
            fprintf(md, "\n");
        }
    }
}

/* ------------------------------------------------------------- targets -- */

/* How far run r misses measure k's target: 0 met, > 0 the miss in units of
 * the target (|error| / within - 1, or the value's distance past a bound
 * over the bound's size); +inf without a value (failed, unstable, not run). */
static double target_miss(const study_measure *m, const study_run *r, size_t k)
{
    if (r->state != RUN_DONE || !r->values || !isfinite(r->values[k]))
        return INFINITY;
    const double v = r->values[k];
    double miss = 0;
    if (isfinite(m->within)) {
        if (!isfinite(r->errors[k]))
            return INFINITY;
        miss = fmax(miss, fabs(r->errors[k]) / m->within - 1);
    }
    if (isfinite(m->below) && v > m->below)
        miss = fmax(miss, (v - m->below) / fmax(fabs(m->below), 1e-300));
    if (isfinite(m->above) && v < m->above)
        miss = fmax(miss, (m->above - v) / fmax(fabs(m->above), 1e-300));
    return miss;
}

static void target_text(const study_measure *m, char *text, size_t size)
{
    text[0] = '\0';
    if (isfinite(m->within)) {
        if (m->absolute)
            append(text, size, "|error| <= %g%s%s", m->within, *m->unit ? " " : "", m->unit);
        else
            append(text, size, "within %g %% of the reference", 100 * m->within);
    }
    if (isfinite(m->above))
        append(text, size, "%sat least %g", *text ? ", " : "", m->above);
    if (isfinite(m->below))
        append(text, size, "%sat most %g", *text ? ", " : "", m->below);
}

/* One row per group: each target's misses at each spacing (coarse to
 * fine), how many targets it meets at every spacing; then the best group:
 * the most targets met at every spacing, then at the finest, then the most
 * (target, spacing) pairs met, then the smallest sum of misses at the
 * finest. */
static void write_targets(const study *s, FILE *md)
{
    size_t targets = 0;
    for (size_t k = 0; k < s->measure_count; k++)
        targets += s->measures[k].has_target != 0;
    const study_run **members = calloc(s->run_count + 1, sizeof *members);
    if (targets == 0 || !members) {
        free(members);
        return;
    }
    fprintf(md, "\n## Against the targets\n\nTargets:");
    for (size_t k = 0, j = 0; k < s->measure_count; k++) {
        char text[256];
        if (!s->measures[k].has_target)
            continue;
        target_text(&s->measures[k], text, sizeof text);
        fprintf(md, "%s %s %s", j++ ? ";" : "", s->measures[k].name, text);
    }
    fprintf(md, ". Each cell: met (yes) or missed (no) at each spacing, coarse to fine "
                "(- : no value: the run failed, went unstable or has not run).\n\n| group |");
    for (size_t k = 0; k < s->measure_count; k++)
        if (s->measures[k].has_target)
            fprintf(md, " %s |", s->measures[k].name);
    fprintf(md, " met at every spacing | met at the finest |\n|---|");
    for (size_t k = 0; k < targets + 2; k++)
        fprintf(md, "---|");
    fprintf(md, "\n");
    char *best = NULL;
    size_t best_every = 0, best_finest = 0, best_cells = 0;
    double best_miss = INFINITY;
    int best_set = 0;
    for (size_t i = 0; i < s->run_count; i++) {
        const study_run *r = &s->runs[i];
        int first = 1;
        for (size_t j = 0; j < i && first; j++)
            first = !same_group(s, r, &s->runs[j]);
        if (!first)
            continue;
        size_t n = group_members(s, r, s->measure_count, members), every = 0, finest = 0,
               cells = 0;
        double miss_sum = 0;
        char *label = group_label(s, r);
        fprintf(md, "| %s |", label);
        for (size_t k = 0; k < s->measure_count; k++) {
            const study_measure *m = &s->measures[k];
            if (!m->has_target)
                continue;
            int all = 1;
            fprintf(md, " ");
            for (size_t j = 0; j < n; j++) {
                double miss = target_miss(m, members[j], k);
                all &= miss == 0;
                cells += miss == 0;
                fprintf(md, "%s%s", j ? " " : "", isinf(miss) ? "-" : miss == 0 ? "yes" : "no");
                if (j == n - 1) {
                    finest += miss == 0;
                    miss_sum += miss;
                }
            }
            every += all && n > 0;
            fprintf(md, " |");
        }
        fprintf(md, " %zu of %zu | %zu of %zu |\n", every, targets, finest, targets);
        /* the most targets met at every spacing, then at the finest, then
         * (target, spacing) cells met, then the smallest misses at the finest */
        const int better =
            every != best_every     ? every > best_every
            : finest != best_finest ? finest > best_finest
            : cells != best_cells   ? cells > best_cells
                                    : miss_sum < best_miss;
        if (!best_set || better) {
            free(best);
            best = study_strdup(label);
            best_every = every;
            best_finest = finest;
            best_cells = cells;
            best_miss = miss_sum;
            best_set = 1;
        }
        free(label);
    }
    if (best)
        fprintf(md,
                "\n**Best against the targets: %s**, meeting %zu of the %zu targets at every "
                "spacing and %zu at the finest%s.\n",
                best, best_every, targets, best_finest,
                best_every == targets ? "" : "; no group meets every target at every spacing");
    free(best);
    free(members);
}

/* ---------------------------------------------------------------- tables -- */

static const char *state_name(const study_run *r)
{
    switch (r->state) {
    case RUN_DONE:
        return "complete";
    case RUN_FAILED:
        return r->exit_code == 3 ? "unstable" : "failed";
    case RUN_INTERRUPTED:
        return "interrupted";
    case RUN_RUNNING:
        return "running";
    case RUN_SKIPPED:
        return "skipped";
    default:
        return "not run";
    }
}

/* Why runs were skipped or failed, one line each. */
static void write_notes(const study *s, FILE *md)
{
    int any = 0;
    for (size_t i = 0; i < s->run_count; i++) {
        const study_run *r = &s->runs[i];
        if (r->state != RUN_SKIPPED && r->state != RUN_FAILED)
            continue;
        if (!any++)
            fprintf(md, "\n## Runs skipped or failed\n\n");
        if (r->state == RUN_SKIPPED)
            fprintf(md, "- %s: skipped, %s\n", r->name, r->skipped);
        else
            fprintf(md, "- %s: %s (exit %d)%s%s; its log: %s/logs/%s.log\n", r->name,
                    state_name(r), r->exit_code, r->failure[0] ? ", " : "", r->failure, s->out,
                    r->name);
    }
}

static void write_table(study *s, FILE *csv, FILE *md)
{
    fprintf(csv, "run");
    fprintf(md, "| run |");
    for (size_t a = 0; a < s->axis_count; a++) {
        fprintf(csv, ",%s", s->axes[a].name);
        fprintf(md, " %s |", s->axes[a].name);
    }
    fprintf(csv, ",status,exit,particles,steps,cpu_s,wall_s,particle_steps_per_cpu_s,"
                 "particle_steps_per_s");
    fprintf(md, " status | particles | CPU s | particle-steps / CPU s | particle-steps / s |");
    for (size_t k = 0; k < s->measure_count; k++) {
        const study_measure *m = &s->measures[k];
        fprintf(csv, ",%s", m->name);
        fprintf(md, " %s%s%s%s |", m->name, *m->unit ? " (" : "", m->unit, *m->unit ? ")" : "");
        if (m->has_reference) {
            fprintf(csv, ",%s_error", m->name);
            fprintf(md, " error%s |", m->absolute ? "" : " (%)");
        }
    }
    fprintf(csv, "\n");
    fprintf(md, "\n|---|");
    for (size_t a = 0; a < s->axis_count; a++)
        fprintf(md, "---|");
    fprintf(md, "---|---:|---:|---:|---:|");
    for (size_t k = 0; k < s->measure_count; k++)
        fprintf(md, s->measures[k].has_reference ? "---:|---:|" : "---:|");
    fprintf(md, "\n");
    for (size_t i = 0; i < s->run_count; i++) {
        const study_run *r = &s->runs[i];
        /* a run not run has no rate (not 0/0 printed as -nan) */
        double rate = r->cpu_seconds > 0 ? r->particle_steps / r->cpu_seconds : NAN;
        double wall_rate = r->wall_seconds > 0 ? r->particle_steps / r->wall_seconds : NAN;
        fprintf(csv, "%s", r->name);
        fprintf(md, "| %s |", r->name);
        for (size_t a = 0; a < s->axis_count; a++) {
            fprintf(csv, ",%s", s->axes[a].values[r->choice[a]].label);
            fprintf(md, " %s |", s->axes[a].values[r->choice[a]].label);
        }
        /* the mean particle count of the run (open boundaries add and remove) */
        double particles = r->steps > 0 ? r->particle_steps / r->steps : r->particles;
        fprintf(csv, ",%s,%d,%.0f,%.0f,%.3f,%.3f,%.4g,%.4g", state_name(r), r->exit_code,
                particles, r->steps, r->cpu_seconds, r->wall_seconds, rate, wall_rate);
        fprintf(md, " %s | %.0f | %.1f | %.3g | %.3g |", state_name(r), particles, r->cpu_seconds,
                rate, wall_rate);
        for (size_t k = 0; k < s->measure_count; k++) {
            fprintf(csv, ",%.10g", r->values[k]);
            fprintf(md, " %.5g |", r->values[k]);
            if (s->measures[k].has_reference) {
                fprintf(csv, ",%.10g", r->errors[k]);
                if (s->measures[k].absolute)
                    fprintf(md, " %.3g |", r->errors[k]);
                else
                    fprintf(md, " %+.2f |", 100 * r->errors[k]);
            }
        }
        fprintf(csv, "\n");
        fprintf(md, "\n");
    }
}

/* ----------------------------------------------------------------- plots -- */

static int have_program(const char *name, char *path, size_t size)
{
    const char *env = getenv("PATH");
    char *copy = study_strdup(env ? env : "/usr/bin:/bin");
    int found = 0;
    for (char *save = NULL, *dir = strtok_r(copy, ":", &save); dir && !found;
         dir = strtok_r(NULL, ":", &save)) {
        snprintf(path, size, "%s/%s", dir, name);
        found = access(path, X_OK) == 0;
    }
    free(copy);
    return found;
}

/* Text for a single-quoted gnuplot string (a quote doubled). */
static char *gnuplot_quoted(const char *text)
{
    char *out = calloc(2 * strlen(text) + 1, 1);
    if (!out)
        exit(4);
    for (char *o = out; *text; text++) {
        *o++ = *text;
        if (*text == '\'')
            *o++ = '\'';
    }
    return out;
}

/* One gnuplot script per measure: against CPU time, and (with a spacing
 * axis) against the spacing, one line per group. Returns the PNGs made. */
static int write_plots(study *s, FILE *md)
{
    char gnuplot[4096];
    if (!have_program("gnuplot", gnuplot, sizeof gnuplot)) {
        fprintf(md, "\n(No plots: gnuplot was not found; `apt-get install gnuplot-nox`.)\n");
        fprintf(stderr, "sluice-study: gnuplot not found: plots skipped (apt-get install "
                        "gnuplot-nox)\n");
        return 0;
    }
    char *dir = study_printf("%s/plots", s->out);
    study_mkdirs(dir);
    int made = 0;
    size_t c = convergence_axis(s);
    int spacing = c < s->axis_count;
    /* the convergence axis: the spacing (<measure>_spacing.png), or a
     * parameter (<measure>_convergence.png) */
    const int of_spacing = spacing && s->axes[c].kind == AXIS_SPACING;
    char *axis_label = !spacing      ? NULL
                       : of_spacing ? study_strdup("particle spacing dx (m)")
                                    : gnuplot_quoted(s->axes[c].name);
    const char *axis_file = of_spacing ? "spacing" : "convergence";
    fprintf(md, "\n## Plots\n\n");
    for (size_t k = 0; k < s->measure_count; k++) {
        const study_measure *m = &s->measures[k];
        char *data = study_printf("%s/%s.dat", dir, m->name);
        FILE *f = fopen(data, "w");
        if (!f) {
            free(data);
            continue;
        }
        /* blocks: one per group, "cpu_s spacing y"; y = |error| (in % when relative) or the value
         */
        size_t blocks = 0, points = 0;
        char *titles = study_strdup("");
        for (size_t i = 0; i < s->run_count; i++) {
            const study_run *r = &s->runs[i];
            int first = 1;
            for (size_t j = 0; j < i; j++)
                if (same_group(s, r, &s->runs[j]))
                    first = 0;
            if (!first)
                continue;
            /* a group without a value has no block (gnuplot's index counts
             * only blocks with data: an empty one would shift the titles) */
            size_t values = 0;
            for (size_t j = 0; j < s->run_count; j++)
                values += same_group(s, r, &s->runs[j]) && isfinite(s->runs[j].values[k]);
            if (values == 0)
                continue;
            char *label = group_label(s, r);
            char *more = study_printf("%s%s%s", titles, blocks ? " " : "", label);
            free(titles);
            titles = more;
            free(label);
            fprintf(f, "%s# group %zu\n", blocks ? "\n\n" : "", blocks);
            blocks++;
            for (size_t j = 0; j < s->run_count; j++) {
                const study_run *o = &s->runs[j];
                if (!same_group(s, r, o) || !isfinite(o->values[k]))
                    continue;
                double y =
                    m->has_reference ? fabs(o->errors[k]) * (m->absolute ? 1 : 100) : o->values[k];
                points += isfinite(y) && (!m->has_reference || y > 0);
                fprintf(f, "%.6g %.6g %.8g\n", o->cpu_seconds,
                        isfinite(o->resolution) ? o->resolution : 0, y);
            }
        }
        fclose(f);
        if (points == 0) {
            fprintf(md, "(%s: no value to plot.)\n", m->name);
            free(titles);
            free(data);
            continue;
        }
        const char *ylabel = m->has_reference ? (m->absolute ? "|error|" : "|error| (%)") : m->name;
        char *title = gnuplot_quoted(s->title[0] ? s->title : "study");
        char *script = study_printf("%s/%s.gp", dir, m->name);
        f = fopen(script, "w");
        if (f) {
            fprintf(f,
                    "set terminal pngcairo size 800,560 noenhanced\nset grid\nset key outside "
                    "right\ntitles = '%s'\nset logscale x\n%s"
                    "set xlabel 'CPU time of the run (s)'\nset ylabel '%s%s%s%s'\n"
                    "set title '%s: %s against cost' font ',10'\nset output '%s/%s_cost.png'\n"
                    "plot for [i=0:%zu] '%s' index i using 1:3 with linespoints title "
                    "word(titles, i+1)\n",
                    titles, m->has_reference ? "set logscale y\n" : "", ylabel,
                    *m->unit && !m->has_reference ? " (" : "", m->has_reference ? "" : m->unit,
                    *m->unit && !m->has_reference ? ")" : "", title, m->name, dir, m->name,
                    blocks - 1, data);
            if (spacing)
                fprintf(f,
                        "set xlabel '%s'\nset title '%s: %s against %s' font ',10'\nset output "
                        "'%s/%s_%s.png'\nplot for [i=0:%zu] '%s' index i using 2:3 with "
                        "linespoints title word(titles, i+1)\n",
                        axis_label, title, m->name, axis_label, dir, m->name, axis_file,
                        blocks - 1, data);
            fclose(f);
            char *argv[] = {gnuplot, script, NULL};
            char *log = study_printf("%s/gnuplot.log", dir);
            pid_t pid = fork();
            if (pid == 0) {
                int fd = open(log, O_WRONLY | O_CREAT | O_APPEND, 0666);
                if (fd >= 0)
                    dup2(fd, STDERR_FILENO);
                execv(argv[0], argv);
                _exit(127);
            }
            free(log);
            int status = 1;
            if (pid > 0)
                waitpid(pid, &status, 0);
            if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
                made += 1 + spacing;
                fprintf(md, "![%s against cost](plots/%s_cost.png)\n", m->name, m->name);
                if (spacing)
                    fprintf(md, "![%s against %s](plots/%s_%s.png)\n", m->name, axis_label,
                            m->name, axis_file);
            } else
                fprintf(stderr,
                        "sluice-study: gnuplot failed on %s (its messages: %s/gnuplot.log)\n",
                        script, dir);
        }
        free(titles);
        free(title);
        free(script);
        free(data);
    }
    free(dir);
    free(axis_label);
    return made;
}

int study_write_reports(study *s)
{
    char *paths[3] = {study_printf("%s/study.csv", s->out), study_printf("%s/orders.csv", s->out),
                      study_printf("%s/study.md", s->out)};
    char *temporary[3];
    FILE *files[3];
    int rc = 0;
    for (int i = 0; i < 3; i++) {
        temporary[i] = study_printf("%s.tmp", paths[i]);
        files[i] = fopen(temporary[i], "w");
        if (!files[i])
            rc = -1;
    }
    if (rc == 0) {
        FILE *md = files[2];
        fprintf(md, "# %s\n\n", s->title[0] ? s->title : "Study");
        if (s->description[0])
            fprintf(md, "%s\n\n", s->description);
        fprintf(md,
                "Study file `%s`, base scene `%s`; %zu runs. Reproduce: `sluice study %s%s%s "
                "--out %s`.\n\n",
                s->path, s->scene, s->run_count, s->path, s->profile ? " --profile " : "",
                s->profile ? s->profile : "", s->out);
        write_table(s, files[0], md);
        write_notes(s, md);
        write_status_map(s, md);
        write_targets(s, md);
        write_orders(s, files[1], md);
        write_plots(s, md);
        for (int i = 0; i < 3; i++)
            if (fclose(files[i]) != 0 || rename(temporary[i], paths[i]) != 0)
                rc = -1;
    } else
        for (int i = 0; i < 3; i++)
            if (files[i])
                fclose(files[i]);
    for (int i = 0; i < 3; i++) {
        free(temporary[i]);
        free(paths[i]);
    }
    return rc;
}
