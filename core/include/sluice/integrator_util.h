/* What every integrator plugin binds and does the same way (header only):
 * positions and velocities, the XSPH transport-velocity correction when some
 * plugin declares it, every rate pair the core reports (each field declared as
 * the time derivative of another), optionally one stored copy
 * "<state>_previous" of every integrated field (declared as a restart field so
 * that it is reordered with the particles), and the position update of fluid
 * particles. Wall particles never move here. */
#ifndef SLUICE_INTEGRATOR_UTIL_H
#define SLUICE_INTEGRATOR_UTIL_H

#include <stdio.h>
#include <string.h>

#include "sluice/plugin_util.h"

typedef struct sluice_integrand {
    uint32_t dims;
    sluice_field position, velocity;
    int has_transport;
    sluice_field transport;    /* transport_velocity_correction (XSPH), if declared */
    int has_acceleration;
    sluice_field acceleration; /* the rate of the velocity, if any */
    uint32_t rate_count;
    sluice_rate *rates;
    sluice_field *stored;      /* "<state>_previous" of every rate, when asked for */
} sluice_integrand;

/* Binds everything, in the integrator's create(): the core creates the
 * integrator after every other component, so the integrated fields
 * (api->fields->rate_count / rate) are known there. With stored_doc non-NULL
 * also declares the stored copies (documented by stored_doc, in the units of
 * their field). in->dims is the scene's dimension count. */
static inline int sluice_integrand_bind(sluice_integrand *in, const sluice_api *api,
                                        sluice_host *host, const char *stored_doc)
{
    memset(in, 0, sizeof *in);
    if (sluice_util_dimensions(api, host, &in->dims) != SLUICE_OK ||
        api->fields->field(host, "position", &in->position) != SLUICE_OK ||
        api->fields->field(host, "velocity", &in->velocity) != SLUICE_OK)
        return SLUICE_ERROR;
    in->has_transport =
        sluice_util_optional_field(api, host, "transport_velocity_correction", &in->transport);
    in->rate_count = api->fields->rate_count(host);
    in->rates = calloc(in->rate_count + 1, sizeof *in->rates);
    in->stored = stored_doc ? calloc(in->rate_count + 1, sizeof *in->stored) : NULL;
    if (!in->rates || (stored_doc && !in->stored)) {
        api->messages->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    for (uint32_t r = 0; r < in->rate_count; r++) {
        if (api->fields->rate(host, r, &in->rates[r]) != SLUICE_OK)
            return SLUICE_ERROR;
        if (strcmp(in->rates[r].state_name, "velocity") == 0) {
            in->has_acceleration = 1;
            in->acceleration = in->rates[r].rate;
        }
        if (!stored_doc)
            continue;
        char name[256];
        snprintf(name, sizeof name, "%s_previous", in->rates[r].state_name);
        sluice_field_spec spec = {name, SLUICE_TYPE_REAL, in->rates[r].state.components, "",
                                  SLUICE_READ | SLUICE_WRITE, SLUICE_FIELD_RESTART, NULL, 0,
                                  stored_doc};
        uint32_t count = api->fields->field_count(host);
        for (uint32_t f = 0; f < count; f++) {
            sluice_field_spec info;
            if (api->fields->field_info(host, f, &info, NULL) == SLUICE_OK &&
                strcmp(info.name, in->rates[r].state_name) == 0)
                spec.units = info.units;
        }
        if (api->fields->declare_field(host, &spec) != SLUICE_OK ||
            api->fields->field(host, name, &in->stored[r]) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static inline void sluice_integrand_free(sluice_integrand *in)
{
    free(in->rates);
    free(in->stored);
    in->rates = NULL;
    in->stored = NULL;
}

/* x = from + step (v + dv) for fluid particles over [begin, end), dv the
 * transport correction when declared; from is the position field itself
 * (in-place update) or another position-like field (predictor-corrector's
 * start of step). Other kinds keep their position. */
static inline void sluice_integrand_move(const sluice_integrand *in, const sluice_view *v,
                                         sluice_index begin, sluice_index end, sluice_real step,
                                         sluice_field from)
{
    const uint8_t *restrict kind = v->kind;
    for (uint32_t d = 0; d < in->dims; d++) {
        sluice_real *x = sluice_real_column(v, in->position, d);
        const sluice_real *x0 = sluice_real_column(v, from, d);
        const sluice_real *restrict u = sluice_real_column(v, in->velocity, d);
        if (in->has_transport) {
            const sluice_real *restrict du = sluice_real_column(v, in->transport, d);
            for (sluice_index i = begin; i < end; i++)
                x[i] = kind[i] == SLUICE_KIND_FLUID ? x0[i] + step * (u[i] + du[i]) : x[i];
        } else {
            for (sluice_index i = begin; i < end; i++)
                x[i] = kind[i] == SLUICE_KIND_FLUID ? x0[i] + step * u[i] : x[i];
        }
    }
}

#endif
