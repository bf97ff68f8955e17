/* Symplectic position-Verlet integrator (Leimkuhler et al. 1996; seed 002 via
 * DualSPHysics), second order, time reversible:
 *   predictor: r^{n+1/2} = r^n + dt/2 v^n,   q^{n+1/2} = q^n + dt/2 (dq/dt)^n
 *   corrector: q^{n+1} = q^n + dt (dq/dt)^{n+1/2},  r^{n+1} = r^{n+1/2} + dt/2 v^{n+1}
 * for every integrated field q (velocity, density, ...: each field declared as
 * the rate of another), over the kinds its rate declares. Positions of fluid
 * particles move with the velocity plus, when a plugin (XSPH) declares it, the
 * field transport_velocity_correction; walls move only when a wall plugin
 * moves them. The step size comes from the rates at t^n (first evaluation). */
#include <sluice/integrator_util.h>

typedef struct symplectic_state {
    const sluice_api *api;
    sluice_integrand in; /* stored: the value at the start of the step */
    double dt;
} symplectic_state;

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_WRITE),
};

static int symplectic_integrand(void *state, sluice_host *host);
static void symplectic_destroy(void *state);

static int symplectic_create(const sluice_api *api, sluice_host *host, const void *config,
                             void **state)
{
    (void)config;
    symplectic_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    /* integrators are created after every other component: the integrated
     * fields are known, and the stored copies are declared here */
    if (symplectic_integrand(s, host) != SLUICE_OK) {
        symplectic_destroy(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int symplectic_integrand(void *state, sluice_host *host)
{
    symplectic_state *s = state;
    return sluice_integrand_bind(&s->in, s->api, host,
                                 "value at the start of the step (symplectic integrator)");
}

static void symplectic_destroy(void *state)
{
    symplectic_state *s = state;
    if (!s)
        return;
    sluice_integrand_free(&s->in);
    free(s);
}

static void predictor(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const symplectic_state *s = context;
    const sluice_real half = (sluice_real)(0.5 * s->dt);
    const uint8_t *restrict kind = v->kind;
    /* positions first: they use v^n */
    sluice_integrand_move(&s->in, v, begin, end, half, s->in.position);
    for (uint32_t r = 0; r < s->in.rate_count; r++) {
        const sluice_rate *rate = &s->in.rates[r];
        const uint32_t kinds = rate->kinds;
        for (uint32_t c = 0; c < rate->state.components; c++) {
            sluice_real *restrict q = sluice_real_column(v, rate->state, c);
            sluice_real *restrict q0 = sluice_real_column(v, s->in.stored[r], c);
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
    for (uint32_t r = 0; r < s->in.rate_count; r++) {
        const sluice_rate *rate = &s->in.rates[r];
        const uint32_t kinds = rate->kinds;
        for (uint32_t c = 0; c < rate->state.components; c++) {
            sluice_real *restrict q = sluice_real_column(v, rate->state, c);
            const sluice_real *restrict q0 = sluice_real_column(v, s->in.stored[r], c);
            const sluice_real *restrict dq = sluice_real_column(v, rate->rate, c);
#pragma omp simd
            for (sluice_index i = begin; i < end; i++)
                q[i] = ((kinds >> kind[i]) & 1u) ? q0[i] + dt * dq[i] : q[i];
        }
    }
    /* positions last: they use v^{n+1} */
    sluice_integrand_move(&s->in, v, begin, end, half, s->in.position);
}

static int symplectic_advance(void *state, sluice_host *host)
{
    symplectic_state *s = state;
    const sluice_api *api = s->api;
    const double t = api->particles->view(host)->time;
    if (api->evaluation->evaluate(host, t, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    s->dt = api->evaluation->time_step(host);
    if (!(s->dt > 0))
        return SLUICE_OK; /* the core reports the collapsed step */
    const sluice_view *v = api->particles->view(host);
    api->particles->parallel_for(host, v->count, predictor, s);
    if (api->evaluation->evaluate(host, t + 0.5 * s->dt, 1) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host);
    api->particles->parallel_for(host, v->count, corrector, s);
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
    .advance = symplectic_advance,
}};

SLUICE_DEFINE_LIBRARY("symplectic", "1.0.0", "symplectic position-Verlet integrator",
                      SLUICE_DIMS_ALL, components)
