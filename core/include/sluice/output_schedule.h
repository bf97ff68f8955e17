/* Regular output times of a gauge or writer (part of the plugin SDK,
 * sluice/plugin_util.h).
 *
 * Something written every `interval` seconds of simulated time, first at
 * t = 0: rows of a gauge's table, snapshots, a field computed on demand. The
 * schedule counts the outputs made; the next one is due at
 * count x interval (never accumulated, so no rounding drifts in). Times
 * within 1e-9 interval of a due time count as that time. After an output,
 * sluice_schedule_advance asks the core (api->evaluation->request_time) to end a step
 * exactly on the next due time.
 *
 *     if (!sluice_schedule_due(&s->schedule, v->time))      in after_step
 *         return SLUICE_OK;
 *     ... write the row ...
 *     sluice_schedule_advance(&s->schedule, s->api, host, v->time);
 *
 * after_step is also called once before the first step, so the row at t = 0
 * is written like the others. The count is the schedule's whole state: save
 * it in save_state and read it back in load_state (sluice_schedule_save /
 * sluice_schedule_load, under a name of the component's choosing), and a
 * restarted run writes the same rows at the same times. */
#ifndef SLUICE_OUTPUT_SCHEDULE_H
#define SLUICE_OUTPUT_SCHEDULE_H

#include <stdint.h>

#include "sluice/plugin.h"

typedef struct sluice_schedule {
    double interval; /* s, > 0 */
    int64_t count;   /* outputs made: the next is due at count x interval */
} sluice_schedule;

/* A schedule whose first output is due at t = 0. */
static inline sluice_schedule sluice_schedule_every(double interval)
{
    sluice_schedule s = {interval, 0};
    return s;
}

/* The slack within which a time counts as a due time (s). */
static inline double sluice_schedule_tolerance(const sluice_schedule *s)
{
    return 1e-9 * s->interval;
}

/* The time the next output is due at (s). */
static inline double sluice_schedule_next(const sluice_schedule *s)
{
    return (double)s->count * s->interval;
}

/* 1 when an output is due at `time` (on or past the next due time). */
static inline int sluice_schedule_due(const sluice_schedule *s, double time)
{
    return !(time + sluice_schedule_tolerance(s) < sluice_schedule_next(s));
}

/* After an output at `time`: counts every due time up to it as done (a long
 * step may have passed several) and asks the core to stop on the next one. */
static inline void sluice_schedule_advance(sluice_schedule *s, const sluice_api *api,
                                           sluice_host *host, double time)
{
    const double tolerance = sluice_schedule_tolerance(s);
    while (sluice_schedule_next(s) <= time + tolerance)
        s->count++;
    api->evaluation->request_time(host, sluice_schedule_next(s));
}

/* Checkpoints (save_state / load_state): the count, as an int64 named
 * `name` (the gauges of Sluice use "rows_written"); load refuses a negative
 * count, and so does restore, for a count stored with other values. */
static inline int sluice_schedule_save(const sluice_schedule *s, const sluice_api *api,
                                       sluice_host *host, const char *name)
{
    return api->state->state_write(host, name, SLUICE_STATE_INT64, 1, &s->count);
}

/* The count read back with other state (in the array `name`): refused when
 * negative (a damaged checkpoint: sluice_schedule_advance would count up to
 * the current time one by one, 2^63 times). */
static inline int sluice_schedule_restore(sluice_schedule *s, const sluice_api *api,
                                          sluice_host *host, const char *name, int64_t count)
{
    if (count < 0) {
        api->messages->error(host, "state array '%s' holds %lld outputs made", name,
                             (long long)count);
        return SLUICE_ERROR;
    }
    s->count = count;
    return SLUICE_OK;
}

static inline int sluice_schedule_load(sluice_schedule *s, const sluice_api *api,
                                       sluice_host *host, const char *name)
{
    int64_t count = 0;
    if (api->state->state_read(host, name, SLUICE_STATE_INT64, 1, &count) != SLUICE_OK)
        return SLUICE_ERROR;
    return sluice_schedule_restore(s, api, host, name, count);
}

/* Defines the save_state and load_state callbacks (named save_fn, load_fn)
 * of a component whose only state across steps is one schedule: the member
 * `member` of its state type `state_type`, which also holds `api` (the
 * sluice_api), saved under `name`:
 *
 *     SLUICE_DEFINE_SCHEDULE_STATE(gauge_save, gauge_load, gauge_state, rows, "rows_written")
 *     ... .save_state = gauge_save, .load_state = gauge_load, ...
 */
#define SLUICE_DEFINE_SCHEDULE_STATE(save_fn, load_fn, state_type, member, name)                 \
    static int save_fn(void *state, sluice_host *host)                                         \
    {                                                                                          \
        const state_type *s_ = state;                                                          \
        return sluice_schedule_save(&s_->member, s_->api, host, name);                         \
    }                                                                                          \
    static int load_fn(void *state, sluice_host *host)                                         \
    {                                                                                          \
        state_type *s_ = state;                                                                \
        return sluice_schedule_load(&s_->member, s_->api, host, name);                         \
    }

#endif
