/* Symplectic position-Verlet integrator (Leimkuhler et al. 1996; seed 002 via
 * DualSPHysics), second order, time reversible:
 *   predictor: r^{n+1/2} = r^n + dt/2 v^n,   q^{n+1/2} = q^n + dt/2 (dq/dt)^n
 *   corrector: q^{n+1} = q^n + dt (dq/dt)^{n+1/2},  r^{n+1} = r^{n+1/2} + dt/2 v^{n+1}
 * for every integrated field q (velocity, density, ...: each field declared as
 * the rate of another), over the kinds its rate declares. Positions of fluid
 * particles move with the velocity plus, when a plugin (XSPH) declares it, the
 * field transport_velocity_correction; walls move only when a wall plugin
 * moves them. The step size comes from the rates at t^n (first evaluation). */
#include <stdio.h>
#include <string.h>

#include "plugin_util.h"

typedef struct symplectic_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_field position, velocity;
    int has_transport;
    sluice_field transport; /* transport_velocity_correction (XSPH), if declared */
    uint32_t rate_count;
    sluice_rate *rates;
    sluice_field *previous;
    double dt;
} symplectic_state;

static const sluice_field_spec fields[] = {
    {"velocity", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1", SLUICE_READ | SLUICE_WRITE,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "velocity"},
};

static int symplectic_create(const sluice_api *api, sluice_host *host, const void *config,
                             void **state)
{
    (void)config;
    symplectic_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    sluice_real dims;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    *state = s;
    return SLUICE_OK;
}

static int symplectic_bind(void *state, sluice_host *host)
{
    symplectic_state *s = state;
    const sluice_api *api = s->api;
    if (api->field(host, "position", &s->position) != SLUICE_OK ||
        api->field(host, "velocity", &s->velocity) != SLUICE_OK)
        return SLUICE_ERROR;
    s->has_transport =
        sluice_util_optional_field(api, host, "transport_velocity_correction", &s->transport);
    s->rate_count = api->rate_count(host);
    s->rates = calloc(s->rate_count + 1, sizeof *s->rates);
    s->previous = calloc(s->rate_count + 1, sizeof *s->previous);
    if (!s->rates || !s->previous) {
        api->error(host, "out of memory");
        return SLUICE_ERROR;
    }
    for (uint32_t r = 0; r < s->rate_count; r++) {
        if (api->rate(host, r, &s->rates[r]) != SLUICE_OK)
            return SLUICE_ERROR;
        /* the value at the start of the step, kept across the two stages */
        char name[256];
        snprintf(name, sizeof name, "%s_previous", s->rates[r].state_name);
        sluice_field_spec spec = {name, SLUICE_TYPE_REAL, s->rates[r].state.components, "",
                                  0, SLUICE_FIELD_RESTART, NULL, 0,
                                  "value at the start of the step (symplectic integrator)"};
        uint32_t count = api->field_count(host);
        for (uint32_t f = 0; f < count; f++) {
            sluice_field_spec info;
            if (api->field_info(host, f, &info, NULL) == SLUICE_OK &&
                strcmp(info.name, s->rates[r].state_name) == 0)
                spec.units = info.units;
        }
        spec.access = SLUICE_READ | SLUICE_WRITE;
        if (api->declare_field(host, &spec) != SLUICE_OK ||
            api->field(host, name, &s->previous[r]) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static void symplectic_destroy(void *state)
{
    symplectic_state *s = state;
    if (!s)
        return;
    free(s->rates);
    free(s->previous);
    free(s);
}

/* x += step (v + transport correction) for fluid particles */
static void move(const symplectic_state *s, const sluice_view *v, sluice_index begin,
                 sluice_index end, sluice_real step)
{
    const uint8_t *restrict kind = v->kind;
    for (uint32_t d = 0; d < s->dims; d++) {
        sluice_real *restrict x = sluice_real_column(v, s->position, d);
        const sluice_real *restrict u = sluice_real_column(v, s->velocity, d);
        if (s->has_transport) {
            const sluice_real *restrict du = sluice_real_column(v, s->transport, d);
            for (sluice_index i = begin; i < end; i++)
                x[i] += kind[i] == SLUICE_KIND_FLUID ? step * (u[i] + du[i]) : 0;
        } else {
            for (sluice_index i = begin; i < end; i++)
                x[i] += kind[i] == SLUICE_KIND_FLUID ? step * u[i] : 0;
        }
    }
}

static void predictor(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const symplectic_state *s = context;
    const sluice_real half = (sluice_real)(0.5 * s->dt);
    const uint8_t *restrict kind = v->kind;
    /* positions first: they use v^n */
    move(s, v, begin, end, half);
    for (uint32_t r = 0; r < s->rate_count; r++) {
        const sluice_rate *rate = &s->rates[r];
        const uint32_t kinds = rate->kinds;
        for (uint32_t c = 0; c < rate->state.components; c++) {
            sluice_real *restrict q = sluice_real_column(v, rate->state, c);
            sluice_real *restrict q0 = sluice_real_column(v, s->previous[r], c);
            const sluice_real *restrict dq = sluice_real_column(v, rate->rate, c);
#pragma omp simd
            for (sluice_index i = begin; i < end; i++) {
                q0[i] = q[i];
                q[i] += ((kinds >> kind[i]) & 1u) ? half * dq[i] : 0;
            }
        }
    }
}

static void corrector(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const symplectic_state *s = context;
    const sluice_real dt = (sluice_real)s->dt, half = (sluice_real)(0.5 * s->dt);
    const uint8_t *restrict kind = v->kind;
    for (uint32_t r = 0; r < s->rate_count; r++) {
        const sluice_rate *rate = &s->rates[r];
        const uint32_t kinds = rate->kinds;
        for (uint32_t c = 0; c < rate->state.components; c++) {
            sluice_real *restrict q = sluice_real_column(v, rate->state, c);
            const sluice_real *restrict q0 = sluice_real_column(v, s->previous[r], c);
            const sluice_real *restrict dq = sluice_real_column(v, rate->rate, c);
#pragma omp simd
            for (sluice_index i = begin; i < end; i++)
                q[i] = ((kinds >> kind[i]) & 1u) ? q0[i] + dt * dq[i] : q[i];
        }
    }
    /* positions last: they use v^{n+1} */
    move(s, v, begin, end, half);
}

static int symplectic_advance(void *state, sluice_host *host)
{
    symplectic_state *s = state;
    const sluice_api *api = s->api;
    if (api->evaluate(host) != SLUICE_OK)
        return SLUICE_ERROR;
    s->dt = api->time_step(host);
    if (!(s->dt > 0))
        return SLUICE_OK; /* the core reports the collapsed step */
    const sluice_view *v = api->view(host);
    api->parallel_for(host, v->count, predictor, s);
    if (api->evaluate(host) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->view(host);
    api->parallel_for(host, v->count, corrector, s);
    return SLUICE_OK;
}

static const sluice_component components[] = {{
    .name = "symplectic",
    .summary = "symplectic position-Verlet, second order, two evaluations per step",
    .reference = "Leimkuhler, Reich & Skeel (1996); Crespo et al. (2015); seed 002",
    .dimensions = SLUICE_DIMS_ALL,
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = symplectic_create,
    .destroy = symplectic_destroy,
    .bind = symplectic_bind,
    .advance = symplectic_advance,
}};

SLUICE_DEFINE_LIBRARY("symplectic", "1.0.0", "symplectic position-Verlet integrator",
                      SLUICE_DIMS_ALL, components)
