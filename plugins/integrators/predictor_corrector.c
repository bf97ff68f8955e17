/* Two-stage XSPH predictor-corrector of Monaghan (1989, 1992), the "2nd order
 * two-stage XSPH explicit algorithm" of seed 004 (De Padova et al. 2017) and
 * of SPHysics, two evaluations per step. With V = v + dv the velocity that
 * moves fluid particles (dv: XSPH transport-velocity correction, when a plugin
 * declares transport_velocity_correction):
 *
 *   predictor:  q^{n+1/2} = q^n + dt/2 (dq/dt)^n,   x^{n+1/2} = x^n + dt/2 V^n
 *   evaluate at t^{n+1/2}
 *   corrector:  q^{n+1/2} = q^n + dt/2 (dq/dt)^{n+1/2},
 *               x^{n+1/2} = x^n + dt/2 V^{n+1/2}
 *   final:      q^{n+1} = 2 q^{n+1/2} - q^n,   x^{n+1} = 2 x^{n+1/2} - x^n
 *
 * for every integrated field q (velocity, density, ...: each field declared
 * as the rate of another) over the kinds its rate declares. The corrected
 * half-step value and the extrapolation are applied in one operation,
 * q^{n+1} = q^n + dt (dq/dt)^{n+1/2} (algebraically identical, one rounding
 * less). V^{n+1/2} is the velocity of the state the second evaluation saw
 * (the predicted one) plus its XSPH correction: every variable, position
 * included, advances with its rate at the half step, which makes the scheme
 * the explicit midpoint rule (second-order Runge-Kutta). Wall particles do
 * not move. The step size comes from the rates at t^n.
 *
 * Energy: not symplectic. On an undamped oscillator every step multiplies the
 * energy by exactly 1 + (omega dt)^4 / 4, a slow secular growth; dissipation
 * (viscosity) in a real flow outweighs it. */
#include "integrator_util.h"

typedef struct pc_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_field position_start; /* x^n */
    sluice_integrand in;         /* stored: q^n of every rate */
    double dt;
} pc_state;

static const sluice_field_spec fields[] = {
    {"velocity", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m s^-1", SLUICE_READ | SLUICE_WRITE,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "velocity"},
    {"position_previous", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m",
     SLUICE_READ | SLUICE_WRITE, SLUICE_FIELD_RESTART, NULL, 0,
     "position at the start of the step (predictor-corrector integrator)"},
};

static int pc_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    (void)config;
    pc_state *s = sluice_util_state(api, host, sizeof *s);
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

static int pc_bind(void *state, sluice_host *host)
{
    pc_state *s = state;
    if (s->api->field(host, "position_previous", &s->position_start) != SLUICE_OK)
        return SLUICE_ERROR;
    return sluice_integrand_bind(&s->in, s->api, host, s->dims,
                                 "value at the start of the step (predictor-corrector)");
}

static void pc_destroy(void *state)
{
    pc_state *s = state;
    if (!s)
        return;
    sluice_integrand_free(&s->in);
    free(s);
}

/* x = x0 + step V for fluid particles, V = v (+ dv), x0 = x^n */
static void move(const pc_state *s, const sluice_view *v, sluice_index begin, sluice_index end,
                 sluice_real step)
{
    sluice_integrand_move(&s->in, v, begin, end, step, s->position_start);
}

/* q = q0 + step dq/dt over the kinds of each rate, q0 = q^n */
static void update(const pc_state *s, const sluice_view *v, sluice_index begin, sluice_index end,
                   sluice_real step)
{
    const uint8_t *restrict kind = v->kind;
    for (uint32_t r = 0; r < s->in.rate_count; r++) {
        const sluice_rate *rate = &s->in.rates[r];
        const uint32_t kinds = rate->kinds;
        for (uint32_t c = 0; c < rate->state.components; c++) {
            sluice_real *restrict q = sluice_real_column(v, rate->state, c);
            const sluice_real *restrict q0 = sluice_real_column(v, s->in.stored[r], c);
            const sluice_real *restrict dq = sluice_real_column(v, rate->rate, c);
#pragma omp simd
            for (sluice_index i = begin; i < end; i++)
                q[i] = ((kinds >> kind[i]) & 1u) ? q0[i] + step * dq[i] : q[i];
        }
    }
}

static void predictor(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const pc_state *s = context;
    const sluice_real half = (sluice_real)(0.5 * s->dt);
    /* keep x^n and q^n */
    for (uint32_t d = 0; d < s->dims; d++)
        memcpy(sluice_real_column(v, s->position_start, d) + begin,
               sluice_real_column(v, s->in.position, d) + begin,
               (size_t)(end - begin) * sizeof(sluice_real));
    for (uint32_t r = 0; r < s->in.rate_count; r++)
        for (uint32_t c = 0; c < s->in.rates[r].state.components; c++)
            memcpy(sluice_real_column(v, s->in.stored[r], c) + begin,
                   sluice_real_column(v, s->in.rates[r].state, c) + begin,
                   (size_t)(end - begin) * sizeof(sluice_real));
    move(s, v, begin, end, half); /* with V^n, before v changes */
    update(s, v, begin, end, half);
}

static void corrector(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const pc_state *s = context;
    const sluice_real dt = (sluice_real)s->dt;
    move(s, v, begin, end, dt); /* with V^{n+1/2}, the velocity the evaluation saw */
    update(s, v, begin, end, dt);
}

static int pc_advance(void *state, sluice_host *host)
{
    pc_state *s = state;
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
    .name = "predictor_corrector",
    .summary = "two-stage XSPH predictor-corrector (explicit midpoint), second order, two "
               "evaluations per step",
    .reference = "Monaghan (1989) J. Comput. Phys. 82:1; Monaghan (1992) J. Comput. Phys. "
                 "110:399; seed 004 (De Padova et al. 2017)",
    .dimensions = SLUICE_DIMS_ALL,
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = pc_create,
    .destroy = pc_destroy,
    .bind = pc_bind,
    .advance = pc_advance,
}};

SLUICE_DEFINE_LIBRARY("predictor_corrector", "1.0.0",
                      "two-stage XSPH predictor-corrector (Monaghan 1989)", SLUICE_DIMS_ALL,
                      components)
