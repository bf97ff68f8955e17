/* Two-stage XSPH predictor-corrector of Monaghan (1989, 1992), the "2nd order
 * two-stage XSPH explicit algorithm" of seed 004 (De Padova et al. 2017) and
 * of SPHysics. Two modes:
 *
 *  - epec (default): evaluate at t^n, predict, evaluate, correct; two
 *    evaluations per step (SPHysics; PySPH's EPECIntegrator);
 *  - pec: predict with the rates of the previous step's evaluation (the one
 *    at t^{n-1/2}), evaluate, correct; one evaluation per step (PySPH's
 *    PECIntegrator, the integrator of its dam break). Still second order:
 *    the lagged rates differ from those at t^n by O(dt), which moves the
 *    predicted state by O(dt^2) and the corrected one by O(dt^3) per step.
 *    The first step of a run evaluates at t^0 first. The rates survive
 *    between steps in their fields, and checkpoints hold every field, so a
 *    restart continues exactly; particles that enter during a run start
 *    with zero lagged rates (their first predicted state only).
 *
 * With V = v + dv the velocity that
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
 * In pec mode the predictor reads the lagged rates (dq/dt)^{n-1/2} and the
 * lagged transport correction dv^{n-1/2} in place of those at t^n.
 *
 * Energy: not symplectic. On an undamped oscillator every step multiplies the
 * energy by exactly 1 + (omega dt)^4 / 4, a slow secular growth; dissipation
 * (viscosity) in a real flow outweighs it. In pec mode the energy is not
 * multiplied by a fixed factor every step, but grows as the spectral radius
 * of its step squared, 1 + (omega dt)^4 / 2 + O((omega dt)^6) per step
 * (test_integrators, energy_pec): twice the epec rate. */
#include <sluice/integrator_util.h>

enum { MODE_EPEC = 0, MODE_PEC = 1 };

typedef struct pc_config {
    int mode;
} pc_config;

static const sluice_param_spec params[] = {
    {"mode", SLUICE_PARAM_ENUM, offsetof(pc_config, mode), "epec", 0, 0, 0, NULL,
     "epec: evaluate at t^n, predict, evaluate, correct (two evaluations per step; SPHysics, "
     "seed 004); pec: predict with the rates of the previous step's evaluation, evaluate, "
     "correct (one evaluation per step; PySPH's PECIntegrator)",
     "epec|pec", 0},
};

typedef struct pc_state {
    const sluice_api *api;
    int mode;
    int64_t rates_ready; /* the rate fields hold the last step's evaluation */
    sluice_field position_start; /* x^n */
    sluice_integrand in;         /* stored: q^n of every rate */
    double dt;
} pc_state;

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_WRITE),
    {"position_previous", SLUICE_TYPE_REAL, SLUICE_COMPONENTS_DIM, "m",
     SLUICE_READ | SLUICE_WRITE, SLUICE_FIELD_RESTART, NULL, 0,
     "position at the start of the step (predictor-corrector integrator)"},
};

static int pc_integrand(void *state, sluice_host *host);
static void pc_destroy(void *state);

static int pc_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const pc_config *c = config;
    pc_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->mode = c->mode;
    /* integrators are created after every other component: the integrated
     * fields are known, and the stored copies are declared here */
    if (pc_integrand(s, host) != SLUICE_OK) {
        pc_destroy(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int pc_integrand(void *state, sluice_host *host)
{
    pc_state *s = state;
    if (s->api->fields->field(host, "position_previous", &s->position_start) != SLUICE_OK)
        return SLUICE_ERROR;
    return sluice_integrand_bind(&s->in, s->api, host,
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
    for (uint32_t d = 0; d < s->in.dims; d++)
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
    const double t = api->particles->view(host)->time;
    /* pec reuses the rates of the previous step's (mid-step) evaluation */
    if ((s->mode == MODE_EPEC || !s->rates_ready) && api->evaluation->evaluate(host, t, 0) != SLUICE_OK)
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
    s->rates_ready = 1;
    return SLUICE_OK;
}

/* Both modes record whether the rate fields hold a step's evaluation, so that
 * a pec restart from either mode's checkpoint continues without evaluating
 * at t^n (which would change the result). */
static int pc_save(void *state, sluice_host *host)
{
    const pc_state *s = state;
    return sluice_util_save_int(s->api, host, "rates_ready", s->rates_ready);
}

static int pc_load(void *state, sluice_host *host)
{
    pc_state *s = state;
    if (s->api->state->state_length(host, "rates_ready") < 0) {
        s->rates_ready = 0; /* a checkpoint of predictor_corrector 1.0: evaluate first */
        return SLUICE_OK;
    }
    return sluice_util_load_int(s->api, host, "rates_ready", &s->rates_ready);
}

static const sluice_component components[] = {{
    .name = "predictor_corrector",
    .summary = "two-stage XSPH predictor-corrector (explicit midpoint), second order, two "
               "evaluations per step (epec) or one (pec, lagged predictor)",
    .reference = "Monaghan (1989) J. Comput. Phys. 82:1; Monaghan (1992) J. Comput. Phys. "
                 "110:399; seed 004 (De Padova et al. 2017)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(pc_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = pc_create,
    .destroy = pc_destroy,
    .advance = pc_advance,
    .save_state = pc_save,
    .load_state = pc_load,
}};

SLUICE_DEFINE_LIBRARY("predictor_corrector", "1.1.0",
                      "two-stage XSPH predictor-corrector (Monaghan 1989)", SLUICE_DIMS_ALL,
                      components)
