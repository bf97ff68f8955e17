/* First-order Euler integrator (seed 000, Jonsson et al. 2016: the "first
 * order time integration" of LS-DYNA's SPH solver), one evaluation per step:
 *
 *   form semi_implicit (symplectic Euler, the default):
 *     q^{n+1} = q^n + dt (dq/dt)^n           every integrated field q
 *     x^{n+1} = x^n + dt (v^{n+1} + dv^n)    fluid positions, with the new velocity
 *   form explicit (forward Euler):
 *     x^{n+1} = x^n + dt (v^n + dv^n)
 *     q^{n+1} = q^n + dt (dq/dt)^n
 *
 * q is every field declared as the rate of another (velocity, density, ...),
 * over the particle kinds its rate declares; dv is the XSPH transport-velocity
 * correction when some plugin declares transport_velocity_correction. Wall
 * particles do not move.
 *
 * Both forms are first order in dt. The semi-implicit form is symplectic: on
 * an undamped oscillator d2x/dt2 = -omega^2 x it keeps a modified energy
 * exactly and its energy error stays bounded, of order omega dt. The explicit
 * form is unconditionally unstable for undamped oscillators: every step
 * multiplies the oscillator's energy by exactly 1 + (omega dt)^2, so it only
 * runs where dissipation (viscosity) outweighs that growth; it is offered for
 * comparison with seed 000, not for production. */
#include <sluice/integrator_util.h>

enum { FORM_SEMI_IMPLICIT = 0, FORM_EXPLICIT = 1 };

typedef struct euler_config {
    int form;
} euler_config;

typedef struct euler_state {
    const sluice_api *api;
    int form;
    sluice_integrand in;
    double dt;
} euler_state;

static const sluice_param_spec params[] = {
    {"form", SLUICE_PARAM_ENUM, offsetof(euler_config, form), "semi_implicit", 0, 0, 0, NULL,
     "semi_implicit: positions move with the updated velocity (symplectic Euler, energy error "
     "bounded); explicit: forward Euler, positions move with the old velocity (the energy of an "
     "undamped oscillator grows by 1 + (omega dt)^2 per step)",
     "semi_implicit|explicit", 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_WRITE),
};

static int euler_integrand(void *state, sluice_host *host);
static void euler_destroy(void *state);

static int euler_create(const sluice_api *api, sluice_host *host, const void *config,
                        void **state)
{
    const euler_config *c = config;
    euler_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->form = c->form;
    /* integrators are created after every other component: the integrated
     * fields are known, and the stored copies are declared here */
    if (euler_integrand(s, host) != SLUICE_OK) {
        euler_destroy(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int euler_integrand(void *state, sluice_host *host)
{
    euler_state *s = state;
    return sluice_integrand_bind(&s->in, s->api, host, NULL);
}

static void euler_destroy(void *state)
{
    euler_state *s = state;
    if (!s)
        return;
    sluice_integrand_free(&s->in);
    free(s);
}

/* x += dt (v + transport correction) for fluid particles */
static void move(const euler_state *s, const sluice_view *v, sluice_index begin, sluice_index end)
{
    sluice_integrand_move(&s->in, v, begin, end, (sluice_real)s->dt, s->in.position);
}

/* q += dt dq/dt for every integrated field, over the kinds of its rate */
static void update(const euler_state *s, const sluice_view *v, sluice_index begin,
                   sluice_index end)
{
    const sluice_real dt = (sluice_real)s->dt;
    const uint8_t *restrict kind = v->kind;
    for (uint32_t r = 0; r < s->in.rate_count; r++) {
        const sluice_rate *rate = &s->in.rates[r];
        const uint32_t kinds = rate->kinds;
        for (uint32_t c = 0; c < rate->state.components; c++) {
            sluice_real *restrict q = sluice_real_column(v, rate->state, c);
            const sluice_real *restrict dq = sluice_real_column(v, rate->rate, c);
#pragma omp simd
            for (sluice_index i = begin; i < end; i++)
                q[i] += ((kinds >> kind[i]) & 1u) ? dt * dq[i] : 0;
        }
    }
}

static void step_semi_implicit(void *context, const sluice_view *v, sluice_index begin,
                               sluice_index end)
{
    const euler_state *s = context;
    update(s, v, begin, end); /* v^{n+1} first ... */
    move(s, v, begin, end);   /* ... then positions with it */
}

static void step_explicit(void *context, const sluice_view *v, sluice_index begin,
                          sluice_index end)
{
    const euler_state *s = context;
    move(s, v, begin, end); /* positions with v^n ... */
    update(s, v, begin, end);
}

static int euler_advance(void *state, sluice_host *host)
{
    euler_state *s = state;
    const sluice_api *api = s->api;
    if (api->evaluation->evaluate(host, api->particles->view(host)->time, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    s->dt = api->evaluation->time_step(host);
    if (!(s->dt > 0))
        return SLUICE_OK; /* the core reports the collapsed step */
    const sluice_view *v = api->particles->view(host);
    api->particles->parallel_for(host, v->count,
                      s->form == FORM_EXPLICIT ? step_explicit : step_semi_implicit, s);
    return SLUICE_OK;
}

static const sluice_component components[] = {{
    .name = "euler",
    .summary = "first-order Euler, semi-implicit (symplectic) or explicit, one evaluation per "
               "step",
    .reference = "seed 000 (Jonsson et al. 2016, LS-DYNA first-order scheme); Hairer, Lubich & "
                 "Wanner (2006) Geometric Numerical Integration, sec. I.1",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(euler_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = euler_create,
    .destroy = euler_destroy,
    .advance = euler_advance,
}};

SLUICE_DEFINE_LIBRARY("euler", "1.0.0", "first-order Euler integrator", SLUICE_DIMS_ALL,
                      components)
