/* LS-DYNA linear polynomial equation of state (seed 000, Jonsson et al. 2016,
 * eq. 14; LS-DYNA *EOS_LINEAR_POLYNOMIAL, whose coefficients are numbered
 * C0..C6 there and C1..C7 in the seed):
 *   p = C1 + C2 mu + C3 mu^2 + C4 mu^3 + (C5 + C6 mu + C7 mu^2) E,
 *   mu = rho / rho0 - 1,
 * E the internal energy per unit reference volume (constant here: no energy
 * equation is solved, as in the seed's NULL material with mu = 0). As in
 * LS-DYNA, the mu^2 terms (C3, C7) are dropped in expansion (mu < 0) unless
 * `tension_cutoff` is false. Sound speed c = sqrt(dp/drho),
 *   dp/drho = (C2 + 2 C3 mu + 3 C4 mu^2 + (C6 + 2 C7 mu) E) / rho0,
 * (the mu^2 terms again dropped for mu < 0), floored at zero.
 * Seed 000 sets C2 = c0^2 rho0 and every other coefficient to zero, which is
 * p = c0^2 (rho - rho0) (its eq. 13): give `speed_of_sound` for that, or C2
 * directly, not both. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct polynomial_config {
    sluice_real c1, c2, c3, c4, c5, c6, c7;
    sluice_real speed_of_sound, internal_energy;
    int tension_cutoff;
} polynomial_config;

typedef struct polynomial_state {
    const sluice_api *api;
    /* p = a0 + a1 mu + a2 mu^2 + a3 mu^3 with the energy terms folded in */
    sluice_real a0, a1, a2, a3, rho0, inverse_rho0;
    int cutoff;
    sluice_field density, pressure, sound_speed;
} polynomial_state;

#define COEFFICIENT(n, what)                                                                     \
    {"c" #n, SLUICE_PARAM_REAL, offsetof(polynomial_config, c##n), "0", 0, 0, 0, "Pa", what,    \
     NULL, 0}

static const sluice_param_spec params[] = {
    COEFFICIENT(1, "C1: constant pressure term"),
    {"c2", SLUICE_PARAM_REAL, offsetof(polynomial_config, c2), NULL, 0, 0,
     SLUICE_PARAM_OPTIONAL | SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "Pa",
     "C2: bulk modulus, the coefficient of mu (seed 000: c0^2 rho0); give this or "
     "speed_of_sound",
     NULL, 0},
    COEFFICIENT(3, "C3: coefficient of mu^2 (dropped for mu < 0 with tension_cutoff)"),
    COEFFICIENT(4, "C4: coefficient of mu^3"),
    {"c5", SLUICE_PARAM_REAL, offsetof(polynomial_config, c5), "0", 0, 0, 0, "1",
     "C5: coefficient of E", NULL, 0},
    {"c6", SLUICE_PARAM_REAL, offsetof(polynomial_config, c6), "0", 0, 0, 0, "1",
     "C6: coefficient of mu E", NULL, 0},
    {"c7", SLUICE_PARAM_REAL, offsetof(polynomial_config, c7), "0", 0, 0, 0, "1",
     "C7: coefficient of mu^2 E (dropped for mu < 0 with tension_cutoff)", NULL, 0},
    {"speed_of_sound", SLUICE_PARAM_REAL, offsetof(polynomial_config, speed_of_sound), NULL, 0,
     0, SLUICE_PARAM_OPTIONAL | SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "m s^-1",
     "c0: sets C2 = c0^2 rho0 (seed 000 used the adiabatic 1484 m/s); give this or c2", NULL,
     0},
    {"internal_energy", SLUICE_PARAM_REAL, offsetof(polynomial_config, internal_energy), "0", 0,
     0, 0, "J m^-3", "E: internal energy per unit reference volume (constant)", NULL, 0},
    {"tension_cutoff", SLUICE_PARAM_BOOL, offsetof(polynomial_config, tension_cutoff), "true", 0,
     0, 0, NULL, "drop the mu^2 terms in expansion (mu < 0), as LS-DYNA does", NULL, 0},
};

static const sluice_field_spec fields[] = {SLUICE_SPECS_EQUATION_OF_STATE};

static int polynomial_create(const sluice_api *api, sluice_host *host, const void *config,
                             void **state)
{
    const polynomial_config *c = config;
    polynomial_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    if (sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->inverse_rho0 = 1 / s->rho0;
    sluice_real c2 = c->c2;
    if (c->c2 > 0 && c->speed_of_sound > 0) {
        api->messages->error(host, "give either c2 or speed_of_sound (which sets c2 = c0^2 rho0), not both");
        free(s);
        return SLUICE_ERROR;
    }
    if (c->speed_of_sound > 0)
        c2 = c->speed_of_sound * c->speed_of_sound * s->rho0;
    if (!(c2 > 0)) {
        api->messages->error(host, "needs c2 > 0 or speed_of_sound: the bulk modulus sets the speed of "
                         "sound and the time step");
        free(s);
        return SLUICE_ERROR;
    }
    const sluice_real E = c->internal_energy;
    s->a0 = c->c1 + c->c5 * E;
    s->a1 = c2 + c->c6 * E;
    s->a2 = c->c3 + c->c7 * E;
    s->a3 = c->c4;
    s->cutoff = c->tension_cutoff;
    if (!(s->a1 > 0)) {
        api->messages->error(host, "dp/drho at the rest density, (C2 + C6 E) / rho0, must be positive "
                         "(it is %g m^2 s^-2)",
                   (double)(s->a1 / s->rho0));
        free(s);
        return SLUICE_ERROR;
    }
    const sluice_real c0 = sqrt(s->a1 / s->rho0);
    if (sluice_util_publish_eos(api, host, c0, s->a0) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int polynomial_bind(void *state, sluice_host *host)
{
    polynomial_state *s = state;
    const sluice_field_binding fields[] = {
        {"density", &s->density}, {"pressure", &s->pressure}, {"sound_speed", &s->sound_speed}};
    return sluice_util_bind(s->api, host, fields, SLUICE_COUNT(fields));
}

static void polynomial_destroy(void *state)
{
    free(state);
}

static void polynomial_particle(void *state, const sluice_view *v, sluice_index begin,
                                sluice_index end)
{
    const polynomial_state *s = state;
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    sluice_real *restrict p = sluice_real_column(v, s->pressure, 0);
    sluice_real *restrict c = sluice_real_column(v, s->sound_speed, 0);
    const sluice_real a0 = s->a0, a1 = s->a1, a2 = s->a2, a3 = s->a3, i0 = s->inverse_rho0;
    const int cutoff = s->cutoff;
#pragma omp simd
    for (sluice_index i = begin; i < end; i++) {
        const sluice_real mu = rho[i] * i0 - 1;
        const sluice_real b2 = cutoff && mu < 0 ? 0 : a2;
        p[i] = a0 + mu * (a1 + mu * (b2 + mu * a3));
        const sluice_real slope = (a1 + mu * (2 * b2 + 3 * a3 * mu)) * i0;
        c[i] = sqrt(slope > 0 ? slope : 0);
    }
}

/* Inverts p(mu) by Newton's method from the linear estimate: p is monotonic
 * near the rest state for any sensible coefficients (a1 > 0). */
static void polynomial_density_from_pressure(void *state, sluice_index n,
                                             const sluice_real *pressure, sluice_real *density)
{
    const polynomial_state *s = state;
    for (sluice_index i = 0; i < n; i++) {
        const sluice_real target = pressure[i] - s->a0;
        sluice_real mu = target / s->a1;
        for (int iteration = 0; iteration < 50; iteration++) {
            const sluice_real b2 = s->cutoff && mu < 0 ? 0 : s->a2;
            const sluice_real f = mu * (s->a1 + mu * (b2 + mu * s->a3)) - target;
            const sluice_real df = s->a1 + mu * (2 * b2 + 3 * s->a3 * mu);
            if (!(df > 0))
                break;
            const sluice_real step = f / df;
            mu -= step;
            if (fabs(step) <= 1e-15 * (1 + fabs(mu)))
                break;
        }
        density[i] = s->rho0 * (1 + mu);
    }
}

static const sluice_component components[] = {{
    .name = "linear_polynomial",
    .summary = "LS-DYNA linear polynomial equation of state (C1..C7, mu = rho/rho0 - 1)",
    .reference = "Jonsson et al. (2016), seed 000 eq. 14; LS-DYNA keyword manual, "
                 "*EOS_LINEAR_POLYNOMIAL",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(polynomial_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .particle_kinds = SLUICE_KINDS_ALL,
    .create = polynomial_create,
    .destroy = polynomial_destroy,
    .bind = polynomial_bind,
    .particle = polynomial_particle,
    .density_from_pressure = polynomial_density_from_pressure,
}};

SLUICE_DEFINE_LIBRARY("linear_polynomial", "1.0.0", "LS-DYNA linear polynomial equation of state",
                      SLUICE_DIMS_ALL, components)
