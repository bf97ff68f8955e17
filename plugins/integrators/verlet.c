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
 * Accuracy and energy (measured in tests/plugins/integrators/test_integrators.c): second order in
 * dt for an even euler_every (the default 40), first order for an odd one.
 * An Euler step leaves an O(dt^2) defect in the value it computes, which the
 * leapfrog then carries in one of the two interleaved sequences only. With an
 * even euler_every the next Euler step restarts from the other, clean
 * sequence and the defect is dropped; with an odd one it restarts from the
 * defective value, so the T/(K dt) defects add up to O(dt). The scheme is not
 * symplectic: on an undamped oscillator its energy grows secularly, at the
 * rate given by the spectral radius of its per-cycle amplification matrix
 * (x1.0068 per period at omega dt = 2 pi / 64 with euler_every 40). */
#include <sluice/integrator_util.h>

typedef struct verlet_config {
    int64_t euler_every;
} verlet_config;

typedef struct verlet_state {
    const sluice_api *api;
    int64_t euler_every;
    sluice_integrand in;       /* stored: q^{n-1} of every rate */
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
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_WRITE),
};

static int verlet_integrand(void *state, sluice_host *host);
static void verlet_destroy(void *state);

static int verlet_create(const sluice_api *api, sluice_host *host, const void *config,
                         void **state)
{
    const verlet_config *c = config;
    verlet_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->euler_every = c->euler_every;
    /* integrators are created after every other component: the integrated
     * fields are known, and the stored copies are declared here */
    if (verlet_integrand(s, host) != SLUICE_OK) {
        verlet_destroy(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int verlet_integrand(void *state, sluice_host *host)
{
    verlet_state *s = state;
    return sluice_integrand_bind(&s->in, s->api, host, "value one step back (Verlet integrator)");
}

static void verlet_destroy(void *state)
{
    verlet_state *s = state;
    if (!s)
        return;
    sluice_integrand_free(&s->in);
    free(s);
}

/* x += dt (v^n + dv^n) + dt^2/2 a^n for fluid particles (before v changes) */
static void move(const verlet_state *s, const sluice_view *v, sluice_index begin,
                 sluice_index end)
{
    sluice_integrand_move(&s->in, v, begin, end, (sluice_real)s->dt, s->in.position);
    if (!s->in.has_acceleration)
        return;
    const sluice_real half_dt2 = (sluice_real)(0.5 * s->dt * s->dt);
    const uint8_t *restrict kind = v->kind;
    for (uint32_t d = 0; d < s->in.dims; d++) {
        sluice_real *restrict x = sluice_real_column(v, s->in.position, d);
        const sluice_real *restrict a = sluice_real_column(v, s->in.acceleration, d);
        for (sluice_index i = begin; i < end; i++)
            x[i] += kind[i] == SLUICE_KIND_FLUID ? half_dt2 * a[i] : 0;
    }
}

static void step(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const verlet_state *s = context;
    const uint8_t *restrict kind = v->kind;
    move(s, v, begin, end);
    for (uint32_t r = 0; r < s->in.rate_count; r++) {
        const sluice_rate *rate = &s->in.rates[r];
        const uint32_t kinds = rate->kinds;
        for (uint32_t c = 0; c < rate->state.components; c++) {
            sluice_real *restrict q = sluice_real_column(v, rate->state, c);
            sluice_real *restrict q1 = sluice_real_column(v, s->in.stored[r], c);
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
    if (api->evaluation->evaluate(host, api->particles->view(host)->time, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    s->dt = api->evaluation->time_step(host);
    if (!(s->dt > 0))
        return SLUICE_OK; /* the core reports the collapsed step */
    s->euler = s->steps % s->euler_every == 0;
    const sluice_view *v = api->particles->view(host);
    api->particles->parallel_for(host, v->count, step, s);
    s->dt_previous = s->dt;
    s->steps++;
    return SLUICE_OK;
}

/* Checkpoints: the steps taken (the Euler-step cycle) and the previous step size; q^{n-1} is a particle field. */
static int verlet_save(void *state, sluice_host *host)
{
    const verlet_state *s = state;
    if (sluice_util_save_int(s->api, host, "steps", s->steps) != SLUICE_OK ||
        sluice_util_save_double(s->api, host, "dt_previous", s->dt_previous) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static int verlet_load(void *state, sluice_host *host)
{
    verlet_state *s = state;
    if (sluice_util_load_int(s->api, host, "steps", &s->steps) != SLUICE_OK ||
        sluice_util_load_double(s->api, host, "dt_previous", &s->dt_previous) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->steps < 0 || s->steps > INT64_MAX / 2) { /* a damaged checkpoint: steps++ overflows */
        s->api->messages->error(host, "state array 'steps' holds %lld steps taken",
                                (long long)s->steps);
        return SLUICE_ERROR;
    }
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
    .advance = verlet_advance,
    .save_state = verlet_save,
    .load_state = verlet_load,
}};

SLUICE_DEFINE_LIBRARY("verlet", "1.0.0", "Verlet integrator (Monaghan 1989, DualSPHysics)",
                      SLUICE_DIMS_ALL, components)
