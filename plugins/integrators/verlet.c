/* Verlet integrator of Monaghan (1989) as used by DualSPHysics (Crespo et al.
 * 2015) and by seed 001 (Wan et al. 2017), one evaluation per step:
 *
 *   leapfrog step:  q^{n+1} = q^{n-1} + (dt_{n-1} + dt_n) (dq/dt)^n
 *                   x^{n+1} = x^n + dt_n (v^n + dv^n) + dt_n^2 / 2 a^n
 *   Euler step:     q^{n+1} = q^n + dt_n (dq/dt)^n
 *                   x^{n+1} = x^n + dt_n (v^n + dv^n) + dt_n^2 / 2 a^n
 *
 * for every integrated field q (velocity, density, ...: each field declared
 * as the rate of another) over the kinds its rate declares; a = dv/dt is the
 * rate of the velocity and dv the XSPH transport-velocity correction when a
 * plugin declares transport_velocity_correction. Wall particles do not move.
 * The leapfrog form couples every other step only: the odd and even
 * sequences drift apart, so every `euler_every` steps an Euler step (which
 * uses q^n instead of q^{n-1}) ties them together again (DualSPHysics'
 * VerletSteps, default 40). The first step is always an Euler step (there is
 * no q^{-1}); DualSPHysics instead starts with q^{-1} = q^0, which doubles
 * the first increment.
 *
 * Variable time step. At a constant step the leapfrog increment is
 * 2 dt (dq/dt)^n. DualSPHysics keeps 2 dt_n when dt varies, which is wrong by
 * (dt_n - dt_{n-1}) dq/dt at every change: the scheme then loses an order (and
 * much more at the short steps the core inserts before output times). Sluice
 * uses dt_{n-1} + dt_n, the length of the interval [t^{n-1}, t^{n+1}] the
 * increment spans: identical at constant dt, exact for a constant rate, and
 * second order while dt varies smoothly.
 *
 * Accuracy and energy (measured in tests/test_integrators.c): second order in
 * dt for an even euler_every (the default 40), first order for an odd one.
 * An Euler step leaves an O(dt^2) defect in the value it computes, which the
 * leapfrog then carries in one of the two interleaved sequences only. With an
 * even euler_every the next Euler step restarts from the other, clean
 * sequence and the defect is dropped; with an odd one it restarts from the
 * defective value, so the T/(K dt) defects add up to O(dt). The scheme is not
 * symplectic: on an undamped oscillator its energy grows secularly, at the
 * rate given by the spectral radius of its per-cycle amplification matrix
 * (x1.0068 per period at omega dt = 2 pi / 64 with euler_every 40). */
#include <stdio.h>
#include <string.h>

#include "plugin_util.h"

typedef struct verlet_config {
    int64_t euler_every;
} verlet_config;

typedef struct verlet_state {
    const sluice_api *api;
    uint32_t dims;
    int64_t euler_every;
    sluice_field position, velocity;
    int has_transport;
    sluice_field transport;    /* transport_velocity_correction (XSPH), if declared */
    int has_acceleration;
    sluice_field acceleration; /* the rate of the velocity */
    uint32_t rate_count;
    sluice_rate *rates;
    sluice_field *previous;    /* q^{n-1} of every rate */
    int64_t steps;             /* steps taken */
    double dt, dt_previous;
    int euler;                 /* this step is an Euler step */
} verlet_state;

static const sluice_param_spec params[] = {
    {"euler_every", SLUICE_PARAM_INT, offsetof(verlet_config, euler_every), "40", 1, 0,
     SLUICE_PARAM_HAS_MIN, "1",
     "an Euler step every this many steps ties the odd and even leapfrog sequences together "
     "(DualSPHysics' VerletSteps); keep it even (an odd value makes the scheme first order), 1 "
     "makes every step an Euler step",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    {"velocity", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1", SLUICE_READ | SLUICE_WRITE,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "velocity"},
};

static int verlet_create(const sluice_api *api, sluice_host *host, const void *config,
                         void **state)
{
    const verlet_config *c = config;
    verlet_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->euler_every = c->euler_every;
    sluice_real dims;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    *state = s;
    return SLUICE_OK;
}

static int verlet_bind(void *state, sluice_host *host)
{
    verlet_state *s = state;
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
        if (strcmp(s->rates[r].state_name, "velocity") == 0) {
            s->has_acceleration = 1;
            s->acceleration = s->rates[r].rate;
        }
        /* q^{n-1}, reordered with the particles */
        char name[256];
        snprintf(name, sizeof name, "%s_previous", s->rates[r].state_name);
        sluice_field_spec spec = {name, SLUICE_TYPE_REAL, s->rates[r].state.components, "",
                                  SLUICE_READ | SLUICE_WRITE, SLUICE_FIELD_RESTART, NULL, 0,
                                  "value one step back (Verlet integrator)"};
        uint32_t count = api->field_count(host);
        for (uint32_t f = 0; f < count; f++) {
            sluice_field_spec info;
            if (api->field_info(host, f, &info, NULL) == SLUICE_OK &&
                strcmp(info.name, s->rates[r].state_name) == 0)
                spec.units = info.units;
        }
        if (api->declare_field(host, &spec) != SLUICE_OK ||
            api->field(host, name, &s->previous[r]) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static void verlet_destroy(void *state)
{
    verlet_state *s = state;
    if (!s)
        return;
    free(s->rates);
    free(s->previous);
    free(s);
}

/* x += dt (v^n + dv^n) + dt^2/2 a^n for fluid particles (before v changes) */
static void move(const verlet_state *s, const sluice_view *v, sluice_index begin,
                 sluice_index end)
{
    const sluice_real dt = (sluice_real)s->dt, half_dt2 = (sluice_real)(0.5 * s->dt * s->dt);
    const uint8_t *restrict kind = v->kind;
    for (uint32_t d = 0; d < s->dims; d++) {
        sluice_real *restrict x = sluice_real_column(v, s->position, d);
        const sluice_real *restrict u = sluice_real_column(v, s->velocity, d);
        if (s->has_transport) {
            const sluice_real *restrict du = sluice_real_column(v, s->transport, d);
            for (sluice_index i = begin; i < end; i++)
                x[i] += kind[i] == SLUICE_KIND_FLUID ? dt * (u[i] + du[i]) : 0;
        } else {
            for (sluice_index i = begin; i < end; i++)
                x[i] += kind[i] == SLUICE_KIND_FLUID ? dt * u[i] : 0;
        }
        if (s->has_acceleration) {
            const sluice_real *restrict a = sluice_real_column(v, s->acceleration, d);
            for (sluice_index i = begin; i < end; i++)
                x[i] += kind[i] == SLUICE_KIND_FLUID ? half_dt2 * a[i] : 0;
        }
    }
}

static void step(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const verlet_state *s = context;
    const uint8_t *restrict kind = v->kind;
    move(s, v, begin, end);
    for (uint32_t r = 0; r < s->rate_count; r++) {
        const sluice_rate *rate = &s->rates[r];
        const uint32_t kinds = rate->kinds;
        for (uint32_t c = 0; c < rate->state.components; c++) {
            sluice_real *restrict q = sluice_real_column(v, rate->state, c);
            sluice_real *restrict q1 = sluice_real_column(v, s->previous[r], c);
            const sluice_real *restrict dq = sluice_real_column(v, rate->rate, c);
            if (s->euler) {
                const sluice_real dt = (sluice_real)s->dt;
#pragma omp simd
                for (sluice_index i = begin; i < end; i++) {
                    const sluice_real now = q[i];
                    q[i] = ((kinds >> kind[i]) & 1u) ? now + dt * dq[i] : now;
                    q1[i] = now;
                }
            } else {
                const sluice_real span = (sluice_real)(s->dt_previous + s->dt);
#pragma omp simd
                for (sluice_index i = begin; i < end; i++) {
                    const sluice_real now = q[i];
                    q[i] = ((kinds >> kind[i]) & 1u) ? q1[i] + span * dq[i] : now;
                    q1[i] = now;
                }
            }
        }
    }
}

static int verlet_advance(void *state, sluice_host *host)
{
    verlet_state *s = state;
    const sluice_api *api = s->api;
    if (api->evaluate(host) != SLUICE_OK)
        return SLUICE_ERROR;
    s->dt = api->time_step(host);
    if (!(s->dt > 0))
        return SLUICE_OK; /* the core reports the collapsed step */
    s->euler = s->steps % s->euler_every == 0;
    const sluice_view *v = api->view(host);
    api->parallel_for(host, v->count, step, s);
    s->dt_previous = s->dt;
    s->steps++;
    return SLUICE_OK;
}

static const sluice_component components[] = {{
    .name = "verlet",
    .summary = "Verlet (Monaghan 1989, DualSPHysics) with an Euler step every euler_every "
               "steps, one evaluation per step",
    .reference = "Monaghan (1989) J. Comput. Phys. 82:1; Crespo et al. (2015) Comput. Phys. "
                 "Commun. 187:204; seed 001 (Wan et al. 2017)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(verlet_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = verlet_create,
    .destroy = verlet_destroy,
    .bind = verlet_bind,
    .advance = verlet_advance,
}};

SLUICE_DEFINE_LIBRARY("verlet", "1.0.0", "Verlet integrator (Monaghan 1989, DualSPHysics)",
                      SLUICE_DIMS_ALL, components)
