/* Standard k-epsilon turbulence model (Launder & Spalding 1974; seed 004,
 * section 3, model (2), after Violeau & Issa 2007):
 *   dk_i/dt   = P_i - eps_i + D_i[k, sigma_k]
 *   deps_i/dt = C1 (eps_i / k_i) P_i - C2 eps_i^2 / k_i + D_i[eps, sigma_eps]
 *   nu_T,i = c_mu k_i^2 / eps_i,   P_i = 2 nu_T,i S^d_i : S^d_i
 * (S^d the deviatoric strain rate from the field velocity_gradient: P is the
 * energy the stress 2 rho nu_T S^d of turbulent_stress takes from the mean
 * flow), with the SPH diffusion of seed 004
 *   D_i[f, sigma] = sum_j m_j 2 (nu_i + nu_j) / (rho_i + rho_j) (f_i - f_j)
 *                   (r_ij . grad_i W_ij) / (r^2 + eta^2),   nu = nu_T / sigma + nu_lam,
 * over fluid neighbours. Seed 004's printed form is garbled: its operands are
 * f_i - f_j (not a sum), and the factor 2 is restored so that D equals
 * div(nu grad f) (Brookshaw's Laplacian 2 sum_j V_j f_ij r.gradW / r^2, the
 * arithmetic pair mean of Lo & Shao 2002); the pair term is antisymmetric, so
 * sum_i m_i k_i changes only through P and eps. nu_lam is the constant
 * kinematic_viscosity when laminar_viscosity publishes it, else 0. Seed 004
 * also prints the destruction of eps with an SPH interpolant of eps; here it
 * is the standard pointwise C2 eps_i^2 / k_i.
 *
 * Walls (standard wall functions, Launder & Spalding 1974): no flux of k or
 * eps through a wall (wall particles are not neighbours of the diffusion). In
 * the wall layer, fluid particles closer than wall_layer to a wall (distance y
 * from api->walls->wall_distance), eps is not integrated but set to its log-layer
 * equilibrium value eps = c_mu^(3/4) k^(3/2) / (kappa y), used in the rates at
 * every evaluation and stored after every step; k there keeps its equation
 * with the SPH production. In a log layer (k = u*^2 / sqrt(c_mu)) this is
 * u*^3 / (kappa y), the dissipation that balances the production.
 *
 * Floors: k >= minimum_k, eps >= minimum_epsilon, applied after every step and
 * wherever k, eps enter a rate. Time-step limits: 0.125 h^2 / max(nu) for the
 * diffusion and C k/eps (C the Courant number) for the source terms.
 * Initial values (fluid particles, at initialise): k = initial_k, or
 * 1.5 (I |v|)^2 from the turbulence intensity I and each particle's initial
 * speed; eps = initial_epsilon, or c_mu^(3/4) k^(3/2) / length_scale (seed 004's
 * inflow: I = 10 %, length scale 0.5 y1). */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct ke_config {
    sluice_real c_mu, sigma_k, sigma_epsilon, c1, c2, kappa;
    sluice_real initial_k, initial_epsilon, intensity, length_scale;
    sluice_real minimum_k, minimum_epsilon;
    int wall_function;
    sluice_real wall_layer;
} ke_config;

typedef struct ke_state {
    const sluice_api *api;
    sluice_host *host;
    uint32_t dims;
    ke_config c;
    sluice_real h, eta2, nu_lam, courant, c_mu34, wall_layer;
    sluice_field velocity, mass, density, gradient, k, eps, k_rate, eps_rate, eddy_viscosity;
} ke_state;

#define POSITIVE (SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE)

static const sluice_param_spec params[] = {
    {"c_mu", SLUICE_PARAM_REAL, offsetof(ke_config, c_mu), "0.09", 0, 0, POSITIVE, "1",
     "nu_T = c_mu k^2 / eps (Launder & Spalding 1974)", NULL, 0},
    {"sigma_k", SLUICE_PARAM_REAL, offsetof(ke_config, sigma_k), "1.0", 0, 0, POSITIVE, "1",
     "turbulent Prandtl number of k", NULL, 0},
    {"sigma_epsilon", SLUICE_PARAM_REAL, offsetof(ke_config, sigma_epsilon), "1.3", 0, 0, POSITIVE,
     "1", "turbulent Prandtl number of eps", NULL, 0},
    {"c_epsilon_1", SLUICE_PARAM_REAL, offsetof(ke_config, c1), "1.44", 0, 0, POSITIVE, "1",
     "production coefficient C1 of the eps equation", NULL, 0},
    {"c_epsilon_2", SLUICE_PARAM_REAL, offsetof(ke_config, c2), "1.92", 0, 0, POSITIVE, "1",
     "destruction coefficient C2 of the eps equation", NULL, 0},
    {"kappa", SLUICE_PARAM_REAL, offsetof(ke_config, kappa), "0.41", 0, 0, POSITIVE, "1",
     "von Karman constant (wall functions)", NULL, 0},
    {"initial_k", SLUICE_PARAM_REAL, offsetof(ke_config, initial_k), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m^2 s^-2",
     "initial k of every fluid particle (default: 1.5 (I |v|)^2 from turbulence_intensity)", NULL,
     0},
    {"initial_epsilon", SLUICE_PARAM_REAL, offsetof(ke_config, initial_epsilon), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m^2 s^-3",
     "initial eps of every fluid particle (default: c_mu^(3/4) k^(3/2) / length_scale)", NULL, 0},
    {"turbulence_intensity", SLUICE_PARAM_REAL, offsetof(ke_config, intensity), "0.1", 0, 10,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_HAS_MAX, "1",
     "initial k = 1.5 (I |v|)^2 when initial_k is absent (seed 004 inflow: 0.1)", NULL, 0},
    {"length_scale", SLUICE_PARAM_REAL, offsetof(ke_config, length_scale), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m",
     "turbulence length scale for the initial eps when initial_epsilon is absent (seed 004 "
     "inflow: 0.5 y1)",
     NULL, 0},
    {"minimum_k", SLUICE_PARAM_REAL, offsetof(ke_config, minimum_k), "1e-10", 0, 0, POSITIVE,
     "m^2 s^-2", "floor of k", NULL, 0},
    {"minimum_epsilon", SLUICE_PARAM_REAL, offsetof(ke_config, minimum_epsilon), "1e-10", 0, 0,
     POSITIVE, "m^2 s^-3", "floor of eps", NULL, 0},
    {"wall_function", SLUICE_PARAM_BOOL, offsetof(ke_config, wall_function), "true", 0, 0, 0,
     NULL, "set eps = c_mu^(3/4) k^(3/2) / (kappa y) in the wall layer (log-layer equilibrium)",
     NULL, 0},
    {"wall_layer", SLUICE_PARAM_REAL, offsetof(ke_config, wall_layer), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m",
     "thickness of the wall layer of the wall function (default: the particle spacing, i.e. the "
     "first layer of fluid particles)",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    {"turbulent_kinetic_energy", SLUICE_TYPE_REAL, 1, "m^2 s^-2",
     SLUICE_READ | SLUICE_READ_NEIGHBOUR | SLUICE_WRITE,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0, "turbulent kinetic energy k"},
    {"turbulent_dissipation_rate", SLUICE_TYPE_REAL, 1, "m^2 s^-3",
     SLUICE_READ | SLUICE_READ_NEIGHBOUR | SLUICE_WRITE,
     SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART, NULL, 0,
     "dissipation rate eps of turbulent kinetic energy"},
    {"turbulent_kinetic_energy_rate", SLUICE_TYPE_REAL, 1, "m^2 s^-3", SLUICE_ACCUMULATE, 0,
     "turbulent_kinetic_energy", SLUICE_KIND_MASK(SLUICE_KIND_FLUID), "dk/dt"},
    {"turbulent_dissipation_rate_rate", SLUICE_TYPE_REAL, 1, "m^2 s^-4", SLUICE_ACCUMULATE, 0,
     "turbulent_dissipation_rate", SLUICE_KIND_MASK(SLUICE_KIND_FLUID), "d eps/dt"},
    SLUICE_SPEC_EDDY_VISCOSITY(SLUICE_WRITE),
};

static int ke_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const ke_config *c = config;
    ke_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->c = *c;
    sluice_real dims, dx;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &dx) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->eta2 = (sluice_real)0.01 * s->h * s->h;
    s->c_mu34 = pow(c->c_mu, 0.75);
    s->wall_layer = c->wall_layer > 0 ? c->wall_layer : dx;
    if (!(c->initial_epsilon > 0) && !(c->length_scale > 0)) {
        api->messages->error(host, "the initial eps needs initial_epsilon or length_scale (eps = "
                         "c_mu^(3/4) k^(3/2) / length_scale)");
        free(s);
        return SLUICE_ERROR;
    }
    const sluice_field_spec gradient = SLUICE_SPEC_VELOCITY_GRADIENT(s->dims, SLUICE_READ);
    if (api->fields->declare_field(host, &gradient) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int ke_bind(void *state, sluice_host *host)
{
    ke_state *s = state;
    const sluice_api *api = s->api;
    s->host = host;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity}, {"mass", &s->mass}, {"density", &s->density},
        {"velocity_gradient", &s->gradient}, {"turbulent_kinetic_energy", &s->k},
        {"turbulent_dissipation_rate", &s->eps}, {"turbulent_kinetic_energy_rate", &s->k_rate},
        {"turbulent_dissipation_rate_rate", &s->eps_rate}, {"eddy_viscosity", &s->eddy_viscosity}};
    if (sluice_util_bind(api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    s->nu_lam = 0;
    api->fields->constant(host, "kinematic_viscosity", &s->nu_lam, 1);
    if (sluice_util_constant(api, host, "courant_number", &s->courant) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static void ke_destroy(void *state)
{
    free(state);
}

/* Distance of particle i to the nearest wall (thread-safe query). */
static inline sluice_real ke_wall_distance(const ke_state *s, const sluice_view *v, sluice_index i)
{
    const sluice_real point[3] = {v->position[0][i], v->position[1][i],
                                  v->dimensions == 3 ? v->position[2][i] : 0};
    return s->api->walls->wall_distance(s->host, point);
}

/* walls: the batch holds wall neighbours (another term of the pass reads
 * them); the diffusion of k and epsilon is between fluid particles only, so
 * they are masked out. */
static inline void ke_pairs(const ke_state *s, const sluice_view *v, const sluice_pair_batch *b,
                            const uint32_t dims, const int wall_function, const int walls)
{
    const uint8_t *restrict nk = b->neighbour_kind;
    const sluice_real *G[9];
    for (uint32_t c = 0; c < dims * dims; c++)
        G[c] = sluice_real_column(v, s->gradient, c);
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict kk = sluice_real_column(v, s->k, 0);
    const sluice_real *restrict ee = sluice_real_column(v, s->eps, 0);
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict kj = b->gathered[s->k.column];
    const sluice_real *restrict ej = b->gathered[s->eps.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict r = b->distance;
    sluice_real *restrict k_rate = sluice_real_column(v, s->k_rate, 0);
    sluice_real *restrict e_rate = sluice_real_column(v, s->eps_rate, 0);
    sluice_real *restrict nu_out = sluice_real_column(v, s->eddy_viscosity, 0);
    const sluice_real c_mu = s->c.c_mu, k_min = s->c.minimum_k, e_min = s->c.minimum_epsilon;
    const sluice_real inv_sk = 1 / s->c.sigma_k, inv_se = 1 / s->c.sigma_epsilon;
    const sluice_real c1 = s->c.c1, c2 = s->c.c2, nu_lam = s->nu_lam, eta2 = s->eta2;
    const sluice_real third = (sluice_real)1 / (sluice_real)dims;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real ki = kk[i] > k_min ? kk[i] : k_min;
        sluice_real ei = ee[i] > e_min ? ee[i] : e_min;
        int in_layer = 0;
        if (wall_function) {
            const sluice_real y = ke_wall_distance(s, v, i);
            if (y < s->wall_layer) {
                in_layer = 1;
                const sluice_real e_wall = s->c_mu34 * ki * sqrt(ki) / (s->c.kappa * y);
                ei = e_wall > e_min ? e_wall : e_min;
            }
        }
        const sluice_real nui = c_mu * ki * ki / ei;
        /* production 2 nu_T S^d : S^d */
        sluice_real tr = 0;
        for (uint32_t a = 0; a < dims; a++)
            tr += G[a * dims + a][i];
        tr *= third;
        sluice_real ss = 0;
        for (uint32_t a = 0; a < dims; a++) {
            const sluice_real d = G[a * dims + a][i] - tr;
            ss += d * d;
            for (uint32_t c = a + 1; c < dims; c++) {
                const sluice_real o = (sluice_real)0.5 * (G[a * dims + c][i] + G[c * dims + a][i]);
                ss += 2 * o * o;
            }
        }
        const sluice_real production = 2 * nui * ss;
        /* diffusion */
        const sluice_real ai = nui * inv_sk + nu_lam, bi = nui * inv_se + nu_lam;
        sluice_real dk = 0, de = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_real kjk = kj[k] > k_min ? kj[k] : k_min;
            const sluice_real ejk = ej[k] > e_min ? ej[k] : e_min;
            const sluice_real nuj = c_mu * kjk * kjk / ejk;
            const sluice_real r2 = r[k] * r[k];
            sluice_real w = 2 * mj[k] * r2 * F[k] / ((rho[i] + rhoj[k]) * (r2 + eta2));
            if (walls)
                w = nk[k] == SLUICE_KIND_WALL ? 0 : w;
            dk += w * (ai + nuj * inv_sk + nu_lam) * (ki - kjk);
            de += w * (bi + nuj * inv_se + nu_lam) * (ei - ejk);
        }
        k_rate[i] += production - ei + dk;
        e_rate[i] += in_layer ? 0 : (c1 * production - c2 * ei) * ei / ki + de;
        nu_out[i] = nui;
    }
}

static void ke_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const ke_state *s = state;
    const int walls = (b->neighbour_kinds & SLUICE_KIND_MASK(SLUICE_KIND_WALL)) != 0;
    const int three = v->dimensions == 3;
    if (s->c.wall_function) {
        if (walls)
            three ? ke_pairs(s, v, b, 3, 1, 1) : ke_pairs(s, v, b, 2, 1, 1);
        else
            three ? ke_pairs(s, v, b, 3, 1, 0) : ke_pairs(s, v, b, 2, 1, 0);
    } else {
        if (walls)
            three ? ke_pairs(s, v, b, 3, 0, 1) : ke_pairs(s, v, b, 2, 0, 1);
        else
            three ? ke_pairs(s, v, b, 3, 0, 0) : ke_pairs(s, v, b, 2, 0, 0);
    }
}

/* Floors, and eps of the wall layer (after every step and at the start). */
static void ke_clamp(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const ke_state *s = context;
    sluice_real *restrict k = sluice_real_column(v, s->k, 0);
    sluice_real *restrict e = sluice_real_column(v, s->eps, 0);
    const sluice_real k_min = s->c.minimum_k, e_min = s->c.minimum_epsilon;
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        if (!(k[i] >= k_min))
            k[i] = k[i] != k[i] ? k[i] : k_min; /* a NaN stays for the watchdog */
        if (!(e[i] >= e_min))
            e[i] = e[i] != e[i] ? e[i] : e_min;
        if (s->c.wall_function) {
            const sluice_real y = ke_wall_distance(s, v, i);
            if (y < s->wall_layer) {
                const sluice_real e_wall = s->c_mu34 * k[i] * sqrt(k[i]) / (s->c.kappa * y);
                e[i] = e_wall > e_min ? e_wall : e_min;
            }
        }
    }
}

static int ke_after_step(void *state, sluice_host *host)
{
    ke_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    s->api->particles->parallel_for(host, v->count, ke_clamp, s);
    return SLUICE_OK;
}

static void ke_start(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const ke_state *s = context;
    sluice_real *restrict k = sluice_real_column(v, s->k, 0);
    sluice_real *restrict e = sluice_real_column(v, s->eps, 0);
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        sluice_real ki = s->c.initial_k;
        if (!(ki > 0)) {
            sluice_real speed2 = 0;
            for (uint32_t d = 0; d < v->dimensions; d++) {
                const sluice_real u = sluice_real_column(v, s->velocity, d)[i];
                speed2 += u * u;
            }
            ki = (sluice_real)1.5 * s->c.intensity * s->c.intensity * speed2;
        }
        if (ki < s->c.minimum_k)
            ki = s->c.minimum_k;
        sluice_real ei = s->c.initial_epsilon;
        if (!(ei > 0))
            ei = s->c_mu34 * ki * sqrt(ki) / s->c.length_scale;
        k[i] = ki;
        e[i] = ei;
    }
    ke_clamp(context, v, begin, end);
}

static int ke_initialise(void *state, sluice_host *host)
{
    ke_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    s->api->particles->parallel_for(host, v->count, ke_start, s);
    return SLUICE_OK;
}

static sluice_real ke_time_step_limit(void *state, const sluice_view *v, sluice_index begin,
                                      sluice_index end)
{
    const ke_state *s = state;
    const sluice_real *nu = sluice_real_column(v, s->eddy_viscosity, 0);
    const sluice_real *k = sluice_real_column(v, s->k, 0);
    const sluice_real *e = sluice_real_column(v, s->eps, 0);
    const sluice_real sigma =
        s->c.sigma_k < s->c.sigma_epsilon ? s->c.sigma_k : s->c.sigma_epsilon;
    sluice_real nu_max = 0, time_min = (sluice_real)INFINITY;
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        const sluice_real n = nu[i] / sigma + s->nu_lam;
        if (n > nu_max || n != n)
            nu_max = n != n ? (sluice_real)INFINITY : n;
        const sluice_real tau = k[i] / e[i];
        if (tau < time_min || tau != tau)
            time_min = tau;
    }
    sluice_real limit = s->courant * time_min;
    if (nu_max > 0) {
        const sluice_real diffusion = (sluice_real)0.125 * s->h * s->h / nu_max;
        if (diffusion < limit)
            limit = diffusion;
    }
    return limit;
}

static const sluice_component components[] = {{
    .name = "k_epsilon",
    .summary = "standard k-epsilon model: transport of k and eps, nu_T = c_mu k^2/eps, wall "
               "functions",
    .reference = "Launder & Spalding (1974); seed 004 (De Padova et al. 2017), model (2); Violeau "
                 "& Issa (2007)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(ke_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = ke_create,
    .destroy = ke_destroy,
    .bind = ke_bind,
    .initialise = ke_initialise,
    .pair = ke_pair,
    .time_step_limit = ke_time_step_limit,
    .after_step = ke_after_step,
}};

SLUICE_DEFINE_LIBRARY("k_epsilon", "1.0.0", "standard k-epsilon turbulence model",
                      SLUICE_DIMS_ALL, components)
