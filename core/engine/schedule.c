/* The evaluation schedule: components ordered by declared reads and
 * writes into particle passes and fused pair passes; the integrated rates;
 * the order of initialise() calls. */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "geometry.h"
#include "schema.h"
#include "decomposition.h"
#include "sim_internal.h"
#include "yaml_tree.h"

/* a pair term of every evaluation (an on-demand pair callback runs only
 * when its component asks, from a hook) */
int sluice_sim_evaluation_pair(const sluice_component *c)
{
    return c->pair && !(c->flags & SLUICE_COMPONENT_ON_DEMAND);
}

static int is_evaluation(const sluice_component *c)
{
    return c->particle || sluice_sim_evaluation_pair(c);
}

/* Describes a pair pass made of the given components: the terms, the
 * neighbour kinds per target kind, and the columns to gather at neighbours
 * per target kind. 0, or -1 on OOM (the pass is then freed by the caller). */
static int fill_pair_pass(sluice_sim *sim, sluice_pair_pass *p, const uint32_t *members,
                          uint32_t count)
{
    p->select_column = -1;
    p->terms = calloc(count ? count : 1, sizeof *p->terms);
    if (!p->terms)
        return -1;
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++) {
        p->gathered_columns[k] = calloc(sim->column_count + 1, sizeof *p->gathered_columns[k]);
        if (!p->gathered_columns[k])
            return -1;
    }
    const size_t stride = sim->column_count + 1;
    uint8_t *gather = calloc((size_t)SLUICE_KIND_COUNT * stride, 1);
    if (!gather)
        return -1;
    for (uint32_t m = 0; m < count; m++) {
        const uint32_t v = members[m];
        const sluice_component *c = sim->instances[v].component;
        sluice_pair_term *t = &p->terms[p->term_count++];
        t->component = c;
        t->state = sim->instances[v].state;
        t->target_kinds = c->target_kinds;
        for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++) {
            if (!(c->target_kinds & SLUICE_KIND_MASK(k)))
                continue;
            p->neighbour_mask[k] |= sluice_neighbour_kinds(sluice_declared_neighbour_kinds(c, k));
            if (c->flags & SLUICE_COMPONENT_NEEDS_KERNEL)
                p->needs_kernel[k] = 1;
            for (uint32_t f = 0; f < sim->field_count; f++) {
                const sluice_field_entry *field = &sim->fields[f];
                for (uint32_t d = 0; d < field->declarer_count; d++)
                    if (field->declarers[d].instance == v &&
                        (field->declarers[d].access & SLUICE_READ_NEIGHBOUR) &&
                        field->type == SLUICE_TYPE_REAL)
                        for (uint32_t comp = 0; comp < field->components; comp++)
                            gather[(size_t)k * stride + (size_t)(field->column + (int32_t)comp)] = 1;
            }
        }
    }
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++) {
        for (uint32_t c = 0; c < sim->column_count; c++)
            if (gather[(size_t)k * stride + c])
                p->gathered_columns[k][p->gathered_count[k]++] = c;
        if (p->gathered_count[k] > p->gathered_max)
            p->gathered_max = p->gathered_count[k];
    }
    free(gather);
    return 0;
}

void sluice_sim_free_pair_pass(sluice_pair_pass *p)
{
    if (!p)
        return;
    free(p->terms);
    for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++)
        free(p->gathered_columns[k]);
    sluice_reach_list_free(p->reach_list);
    memset(p, 0, sizeof *p);
}

/* The order of the initialise calls: a component that writes a field
 * initialises before the components that only read it (two_phase sets each
 * particle's phase before the components that act on one phase look at
 * it), scene order otherwise; a cycle falls back to scene order. Returns a
 * malloc'd permutation of the instances, NULL when out of memory. */
uint32_t *sluice_sim_initialise_order(const sluice_sim *sim)
{
    const uint32_t n = sim->instance_count;
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    uint8_t *placed = calloc(n ? n : 1, 1);
    if (!order || !placed) {
        free(order);
        free(placed);
        return NULL;
    }
    for (uint32_t o = 0; o < n; o++) {
        /* the first instance in scene order that waits for no writer */
        uint32_t chosen = n;
        for (uint32_t k = 0; k < n && chosen == n; k++) {
            if (placed[k])
                continue;
            int waits = 0;
            for (uint32_t f = 0; f < sim->field_count && !waits; f++) {
                const sluice_field_entry *field = &sim->fields[f];
                int reads = 0;
                for (uint32_t d = 0; d < field->declarer_count; d++)
                    if (field->declarers[d].instance == k) {
                        const uint32_t access = field->declarers[d].access;
                        reads = (access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR)) &&
                                !(access & SLUICE_WRITE);
                    }
                for (uint32_t d = 0; d < field->declarer_count && reads; d++) {
                    const sluice_declarer *dec = &field->declarers[d];
                    if (dec->instance != SLUICE_CORE_INSTANCE && dec->instance != k &&
                        (dec->access & SLUICE_WRITE) && !placed[dec->instance])
                        waits = 1;
                }
            }
            if (!waits)
                chosen = k;
        }
        if (chosen == n) /* a cycle: scene order */
            for (uint32_t k = 0; k < n && chosen == n; k++)
                if (!placed[k])
                    chosen = k;
        placed[chosen] = 1;
        order[o] = chosen;
    }
    free(placed);
    return order;
}

/* The reach pass's selection (api->evaluation->restrict_reach): a uint8 field of one
 * component that the instance declared it reads. 0, or 1 with the error
 * reported. */
static int reach_selection(sluice_sim *sim, uint32_t v, sluice_pair_pass *pass)
{
    const sluice_instance *in = &sim->instances[v];
    if (!in->reach_field[0])
        return 0;
    const sluice_field_entry *field = sluice_sim_find_field(sim, in->reach_field);
    int reads = 0;
    for (uint32_t d = 0; field && d < field->declarer_count; d++)
        reads |= field->declarers[d].instance == v &&
                 (field->declarers[d].access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR));
    if (!field || field->type != SLUICE_TYPE_UINT8 || field->components != 1 || !reads) {
        sluice_sim_report(sim, v,
               "plugin '%s' restricts its reach to the field '%s', which must be a uint8 field "
               "of one component that it declares it reads",
               in->name, in->reach_field);
        return 1;
    }
    pass->select_column = field->column;
    pass->select_value = (uint8_t)in->reach_value;
    return 0;
}

/* Checks the declarations and orders the evaluation components into passes. */
/* Every field read has a provider; one writer per field, or accumulators;
 * a rate's state exists. Returns the number of errors reported. */
static int check_field_providers(sluice_sim *sim)
{
    int errors = 0;
    char missing[1024] = "";
    size_t missing_used = 0;
    uint32_t missing_count = 0, missing_reader = SLUICE_CORE_INSTANCE;
    /* conflicts and missing providers */
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        int64_t writer = -1, accumulator = -1;
        int provided = strcmp(field->name, "position") == 0 || strcmp(field->name, "kind") == 0 ||
                       strcmp(field->name, "id") == 0 || strcmp(field->name, "mass") == 0 ||
                       strcmp(field->name, "velocity") == 0 || strcmp(field->name, "density") == 0;
        for (uint32_t d = 0; d < field->declarer_count; d++) {
            const sluice_declarer *dec = &field->declarers[d];
            if (dec->access & (SLUICE_WRITE | SLUICE_ACCUMULATE))
                provided = 1;
            if (dec->instance == SLUICE_CORE_INSTANCE ||
                !is_evaluation(sim->instances[dec->instance].component))
                continue;
            if (dec->access & SLUICE_WRITE) {
                if (writer >= 0 && (uint32_t)writer != dec->instance) {
                    sluice_sim_report(sim, dec->instance,
                           "plugins '%s' and '%s' both write field '%s' during the evaluation; "
                           "load only one of them",
                           sim->instances[writer].name, sim->instances[dec->instance].name,
                           field->name);
                    errors++;
                }
                writer = dec->instance;
            }
            if (dec->access & SLUICE_ACCUMULATE)
                accumulator = dec->instance;
        }
        if (writer >= 0 && accumulator >= 0 && writer != accumulator) {
            sluice_sim_report(sim, (uint32_t)writer,
                   "plugin '%s' writes field '%s' while '%s' accumulates into it; a field is "
                   "either written by one plugin or accumulated",
                   sim->instances[writer].name, field->name, sim->instances[accumulator].name);
            errors++;
        }
        if (!provided) {
            /* gathered into one message below: one missing plugin (an
             * equation of state, a turbulence model) often leaves several
             * fields without a provider */
            for (uint32_t d = 0; d < field->declarer_count; d++) {
                const sluice_declarer *dec = &field->declarers[d];
                if (dec->access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR)) {
                    if (missing_count == 0)
                        missing_reader = dec->instance;
                    int w = snprintf(missing + missing_used, sizeof missing - missing_used,
                                     "%s'%s' (read by '%s')", missing_count ? ", " : "",
                                     field->name, sluice_sim_instance_name(sim, dec->instance));
                    if (w > 0 && (size_t)w < sizeof missing - missing_used)
                        missing_used += (size_t)w;
                    missing_count++;
                    break;
                }
            }
        }
        if (field->rate_of && !sluice_sim_find_field(sim, field->rate_of)) {
            sluice_sim_report(sim, field->declarers[0].instance,
                   "field '%s' is declared the rate of '%s', which no loaded plugin declares",
                   field->name, field->rate_of);
            errors++;
        }
    }
    if (missing_count == 1) {
        sluice_sim_report(sim, missing_reader,
               "field %s is computed by no loaded plugin; load the plugin that provides it",
               missing);
        errors++;
    } else if (missing_count > 1) {
        sluice_sim_report(sim, missing_reader,
               "fields %s are computed by no loaded plugin; load the plugins that provide them",
               missing);
        errors++;
    }
    return errors;
}

/* The evaluation components' slots: writers before readers (longest paths
 * over writer -> reader edges), particle terms on even slots, pair terms on
 * odd ones, each pair term as late as its readers allow. Returns 0, 1 after
 * reporting a cycle, -1 out of memory. */
static int order_slots(sluice_sim *sim, int *slot, int *max_slot_out)
{
    const uint32_t n = sim->instance_count;
    uint8_t *edge = calloc((size_t)n * n + 1, 1);
    int *done = calloc(n + 1, sizeof *done);
    if (!edge || !done) {
        free(edge);
        free(done);
        return -1;
    }
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        for (uint32_t a = 0; a < field->declarer_count; a++) {
            const sluice_declarer *w = &field->declarers[a];
            if (w->instance == SLUICE_CORE_INSTANCE || !(w->access & (SLUICE_WRITE | SLUICE_ACCUMULATE)))
                continue;
            if (!is_evaluation(sim->instances[w->instance].component))
                continue;
            for (uint32_t b = 0; b < field->declarer_count; b++) {
                const sluice_declarer *r = &field->declarers[b];
                if (r->instance == SLUICE_CORE_INSTANCE || r->instance == w->instance ||
                    !(r->access & (SLUICE_READ | SLUICE_READ_NEIGHBOUR)))
                    continue;
                if (!is_evaluation(sim->instances[r->instance].component))
                    continue;
                edge[(size_t)w->instance * n + r->instance] = 1;
            }
        }
    }
    /* longest-path slots: particle terms on even slots, pair passes on odd */
    int max_slot = -1;
    for (uint32_t round = 0; round < n; round++) {
        int progress = 0;
        for (uint32_t v = 0; v < n; v++) {
            if (done[v] || !is_evaluation(sim->instances[v].component))
                continue;
            int ready = 1, lower = 0;
            for (uint32_t u = 0; u < n; u++) {
                if (!edge[(size_t)u * n + v])
                    continue;
                if (!done[u]) {
                    ready = 0;
                    break;
                }
                if (slot[u] + 1 > lower)
                    lower = slot[u] + 1;
            }
            if (!ready)
                continue;
            int pair = sluice_sim_evaluation_pair(sim->instances[v].component);
            if ((lower % 2 == 1) != pair)
                lower++;
            slot[v] = lower;
            done[v] = 1;
            progress = 1;
            if (lower > max_slot)
                max_slot = lower;
        }
        if (!progress)
            break;
    }
    for (uint32_t v = 0; v < n; v++)
        if (is_evaluation(sim->instances[v].component) && !done[v]) {
            char cycle[1024];
            size_t used = 0;
            for (uint32_t u = 0; u < n; u++)
                if (is_evaluation(sim->instances[u].component) && !done[u]) {
                    int w = snprintf(cycle + used, sizeof cycle - used, "%s%s", used ? ", " : "",
                                     sim->instances[u].name);
                    if (w > 0 && (size_t)w < sizeof cycle - used)
                        used += (size_t)w;
                }
            sluice_sim_report(sim, v,
                   "the plugins %s depend on each other's fields in a cycle; no evaluation order "
                   "exists",
                   cycle);
            free(edge);
            free(done);
            return 1;
        }

    /* Pair terms as late as their readers allow: a pair term whose results
     * nothing in the evaluation reads (rates, accelerations) joins the last
     * pair pass, and any other moves up to just before its first reader.
     * Every reader still comes after its writers, and terms that could share a
     * traversal do (the dbc clamp, a particle term, would otherwise split the
     * density terms from the forces into two neighbour traversals). Visited in
     * decreasing slot order, so that readers are placed before their writers. */
    int last_pair_slot = max_slot % 2 == 1 ? max_slot : max_slot - 1;
    for (int s = max_slot; s >= 0; s--)
        for (uint32_t v = 0; v < n; v++) {
            if (!is_evaluation(sim->instances[v].component) || slot[v] != s ||
                !sluice_sim_evaluation_pair(sim->instances[v].component))
                continue;
            int latest = last_pair_slot;
            for (uint32_t u = 0; u < n; u++)
                if (edge[(size_t)v * n + u] && slot[u] - 1 < latest)
                    latest = slot[u] - 1;
            if (latest % 2 == 0)
                latest--;
            if (latest > slot[v])
                slot[v] = latest;
        }
    free(edge);
    free(done);
    *max_slot_out = max_slot;
    return 0;
}

/* The components that prepare every evaluation, and the passes in slot
 * order: particle terms one pass each, the pair terms of a slot within the
 * support one shared pass, each term that reaches beyond it a pass of its
 * own. Returns 0 or -1 out of memory; a reach's selection errors add to
 * *errors. */
static int build_passes(sluice_sim *sim, const int *slot, int max_slot, int *errors)
{
    const uint32_t n = sim->instance_count;
    /* components that prepare every evaluation, in scene order */
    sim->prepare = calloc((size_t)n + 1, sizeof *sim->prepare);
    if (!sim->prepare)
        return -1;
    for (uint32_t v = 0; v < n; v++)
        if (sim->instances[v].component->prepare)
            sim->prepare[sim->prepare_count++] = v;

    /* passes in slot order */
    sim->passes = calloc((size_t)n + 1, sizeof *sim->passes);
    if (!sim->passes)
        return -1;
    for (int s = 0; s <= max_slot; s++) {
        if (s % 2 == 0) {
            for (uint32_t v = 0; v < n; v++)
                if (is_evaluation(sim->instances[v].component) && slot[v] == s) {
                    sluice_pass *p = &sim->passes[sim->pass_count++];
                    p->is_pair = 0;
                    p->instance = v;
                }
            continue;
        }
        /* the terms within the support share one pass; a term that reaches
         * beyond it (api->evaluation->request_reach) gets a pass of its own, after */
        uint32_t terms = 0;
        for (uint32_t v = 0; v < n; v++)
            terms += is_evaluation(sim->instances[v].component) && slot[v] == s &&
                     !(sim->instances[v].reach > sim->support);
        if (terms) {
            sluice_pass *p = &sim->passes[sim->pass_count++];
            p->is_pair = 1;
            uint32_t *members = calloc(terms, sizeof *members);
            if (!members)
                return -1;
            uint32_t m = 0;
            for (uint32_t v = 0; v < n; v++)
                if (is_evaluation(sim->instances[v].component) && slot[v] == s &&
                    !(sim->instances[v].reach > sim->support))
                    members[m++] = v;
            int rc = fill_pair_pass(sim, &p->pair, members, m);
            free(members);
            if (rc != 0)
                return -1;
        }
        for (uint32_t v = 0; v < n; v++) {
            if (!is_evaluation(sim->instances[v].component) || slot[v] != s ||
                !(sim->instances[v].reach > sim->support))
                continue;
            sluice_pass *p = &sim->passes[sim->pass_count++];
            p->is_pair = 1;
            if (fill_pair_pass(sim, &p->pair, &v, 1) != 0)
                return -1;
            p->pair.reach = sim->instances[v].reach;
            p->pair.reach_list = calloc(1, sizeof *p->pair.reach_list);
            if (!p->pair.reach_list)
                return -1;
            if (reach_selection(sim, v, &p->pair) != 0)
                (*errors)++;
        }
    }
    return 0;
}

/* The accumulated columns, zeroed before every evaluation, and the passes of
 * the on-demand pair terms (run through api->evaluation->pair_pass). Returns 0 or -1 out
 * of memory. */
static int build_accumulators_and_on_demand(sluice_sim *sim, int *errors)
{
    const uint32_t n = sim->instance_count;
    /* accumulated columns, zeroed before every evaluation */
    sim->accumulate_columns = calloc(sim->column_count + 1, sizeof *sim->accumulate_columns);
    if (!sim->accumulate_columns)
        return -1;
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *field = &sim->fields[f];
        int acc = 0;
        for (uint32_t d = 0; d < field->declarer_count; d++)
            acc |= (field->declarers[d].access & SLUICE_ACCUMULATE) != 0;
        if (acc)
            for (uint32_t comp = 0; comp < field->components; comp++)
                sim->accumulate_columns[sim->accumulate_count++] =
                    (uint32_t)field->column + comp;
    }
    /* on-demand pair terms: a pass of their own, run through api->evaluation->pair_pass */
    for (uint32_t v = 0; v < n; v++) {
        sluice_instance *in = &sim->instances[v];
        if (!(in->component->flags & SLUICE_COMPONENT_ON_DEMAND))
            continue;
        in->on_demand = calloc(1, sizeof *in->on_demand);
        if (!in->on_demand || fill_pair_pass(sim, in->on_demand, &v, 1) != 0)
            return -1;
        if (in->reach > sim->support) {
            in->on_demand->reach = in->reach;
            in->on_demand->reach_list = calloc(1, sizeof *in->on_demand->reach_list);
            if (!in->on_demand->reach_list)
                return -1;
            if (reach_selection(sim, v, in->on_demand) != 0)
                (*errors)++;
        }
    }
    return 0;
}

int sluice_sim_build_schedule(sluice_sim *sim)
{
    int errors = check_field_providers(sim);
    if (errors)
        return errors;
    int *slot = malloc(((size_t)sim->instance_count + 1) * sizeof *slot);
    if (!slot)
        return 1;
    int max_slot = -1;
    int rc = order_slots(sim, slot, &max_slot);
    if (rc == 0)
        rc = build_passes(sim, slot, max_slot, &errors);
    free(slot);
    if (rc == 1)
        return 1; /* a cycle, reported */
    if (rc == 0)
        rc = build_accumulators_and_on_demand(sim, &errors);
    if (rc != 0) {
        sluice_sim_report(sim, SLUICE_CORE_INSTANCE,
                          "out of memory building the evaluation schedule");
        return 1;
    }
    return errors;
}

void sluice_sim_set_list_kinds(sluice_sim *sim)
{
    uint32_t kinds[SLUICE_KIND_COUNT] = {0};
    for (uint32_t p = 0; p < sim->pass_count; p++)
        if (sim->passes[p].is_pair && !(sim->passes[p].pair.reach > 0))
            for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++)
                kinds[k] |= sim->passes[p].pair.neighbour_mask[k];
    for (uint32_t v = 0; v < sim->instance_count; v++) {
        const sluice_pair_pass *p = sim->instances[v].on_demand;
        if (p && !(p->reach > 0))
            for (uint32_t k = 0; k < SLUICE_KIND_COUNT; k++)
                kinds[k] |= p->neighbour_mask[k];
    }
    sim->grid.kind_column = sim->kind.column;
    memcpy(sim->grid.list_kinds, kinds, sizeof kinds);
    sim->grid.valid = 0;
}

int sluice_sim_build_rates(sluice_sim *sim)
{
    uint32_t count = 0;
    for (uint32_t f = 0; f < sim->field_count; f++)
        count += sim->fields[f].rate_of != NULL;
    sim->rates = calloc(count + 1, sizeof *sim->rates);
    if (!sim->rates)
        return -1;
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const sluice_field_entry *rate = &sim->fields[f];
        if (!rate->rate_of)
            continue;
        const sluice_field_entry *state = sluice_sim_find_field(sim, rate->rate_of);
        if (!state)
            continue; /* reported by build_schedule */
        sluice_rate *r = &sim->rates[sim->rate_count++];
        sluice_sim_handle_of(sim, state->name, &r->state);
        sluice_sim_handle_of(sim, rate->name, &r->rate);
        r->kinds = rate->kinds;
        r->state_name = state->name;
        r->rate_name = rate->name;
        if (state->components != rate->components || state->type != SLUICE_TYPE_REAL ||
            rate->type != SLUICE_TYPE_REAL) {
            sluice_sim_report(sim, rate->declarers[0].instance,
                   "field '%s' (%u components) cannot be the rate of '%s' (%u components)",
                   rate->name, rate->components, state->name, state->components);
            return 1;
        }
    }
    return 0;
}

/* ------------------------------------------------------ the schedule, written -- */

static const char *term_name(const sluice_sim *sim, const sluice_pair_term *term)
{
    for (uint32_t v = 0; v < sim->instance_count; v++)
        if (sim->instances[v].state == term->state &&
            sim->instances[v].component == term->component)
            return sim->instances[v].name;
    return "?";
}

static void write_name(FILE *out, const char *name, int json, int first)
{
    if (json)
        fprintf(out, "%s\"%s\"", first ? "" : ", ", name);
    else
        fprintf(out, "%s%s", first ? "" : ", ", name);
}

static void write_pair_pass(const sluice_sim *sim, const sluice_pair_pass *p, FILE *out,
                            int json)
{
    fputs(json ? "{\"kind\": \"pair\", \"components\": [" : "pair pass: ", out);
    for (uint32_t t = 0; t < p->term_count; t++)
        write_name(out, term_name(sim, &p->terms[t]), json, t == 0);
    if (json) {
        fprintf(out, "], \"reach_m\": %.9g}", (double)p->reach);
    } else if (p->reach > 0) {
        fprintf(out, " (reach %.6g m", (double)p->reach);
        if (p->select_column >= 0)
            fprintf(out, ", only particles with %u in column %d", p->select_value,
                    p->select_column);
        fputc(')', out);
    }
}

/* The evaluation schedule as the core runs it: the components that prepare
 * every evaluation, the passes in order (a particle pass per particle term,
 * the pair terms of a pass fused into one traversal, reach passes), the
 * on-demand pair terms and the integrated fields; as text (sluice check
 * --schedule) or as a JSON object (run.json "schedule"). */
void sluice_sim_write_schedule(const sluice_sim *sim, FILE *out, int json)
{
    fputs(json ? "{\"prepare\": [" : "evaluation schedule (docs/plugin-abi.md, \"A step\"):\n  prepare: ", out);
    for (uint32_t k = 0; k < sim->prepare_count; k++)
        write_name(out, sim->instances[sim->prepare[k]].name, json, k == 0);
    if (!json && sim->prepare_count == 0)
        fputs("(none)", out);
    fputs(json ? "], \"passes\": [" : "\n", out);
    for (uint32_t p = 0; p < sim->pass_count; p++) {
        const sluice_pass *pass = &sim->passes[p];
        if (json && p)
            fputs(", ", out);
        if (!json)
            fprintf(out, "  %u. ", p + 1);
        if (pass->is_pair)
            write_pair_pass(sim, &pass->pair, out, json);
        else if (json)
            fprintf(out, "{\"kind\": \"particle\", \"components\": [\"%s\"]}",
                    sim->instances[pass->instance].name);
        else
            fprintf(out, "particle pass: %s", sim->instances[pass->instance].name);
        if (!json)
            fputc('\n', out);
    }
    fputs(json ? "], \"on_demand\": [" : "  on demand (api->evaluation->pair_pass): ", out);
    int first = 1;
    for (uint32_t v = 0; v < sim->instance_count; v++)
        if (sim->instances[v].on_demand) {
            write_name(out, sim->instances[v].name, json, first);
            first = 0;
        }
    if (!json && first)
        fputs("(none)", out);
    fputs(json ? "], \"integrated\": [" : "\n  integrated: ", out);
    for (uint32_t r = 0; r < sim->rate_count; r++) {
        const sluice_rate *rate = &sim->rates[r];
        if (json)
            fprintf(out, "%s{\"state\": \"%s\", \"rate\": \"%s\", \"kinds\": %u}", r ? ", " : "",
                    rate->state_name, rate->rate_name, rate->kinds);
        else
            fprintf(out, "%s%s <- %s", r ? ", " : "", rate->state_name, rate->rate_name);
    }
    if (!json && sim->rate_count == 0)
        fputs("(none)", out);
    fprintf(out, json ? "], \"integrator\": \"%s\"}" : " (integrator '%s')\n",
            sim->instances[sim->integrator].name);
}
