/* Energy gauge: the mechanical energy budget of the fluid particles (kind
 * fluid; wall and open-boundary particles are left out), written every
 * `interval` to a CSV table `time,kinetic,potential,elastic,total,drift,
 * fluid_mass`, for judging whether a run stays stable and how much energy its
 * dissipative terms (artificial viscosity, density diffusion, the walls)
 * remove. Energies are per metre of span in 2D (J m^-1: the particle mass
 * rho0 dx^2 is per metre) and in J in 3D; fluid_mass in kg m^-1 (2D) or kg.
 *
 *   kinetic   K = sum_i 1/2 m_i |v_i|^2
 *   potential P = sum_i m_i (-g . x_i) - P_0, with g the constant `gravity`
 *             (zero when no plugin publishes it) and P_0 the same sum on the
 *             initial state (the first sample, t = 0): relative to the start.
 *             With inflow and outflow the sum runs over the particles of the
 *             moment, so P then also counts the potential energy carried in
 *             and out (as K does).
 *   elastic   U = sum_i m_i e(rho_i), e the specific internal (compression)
 *             energy of the barotropic equation of state,
 *                 de = p / rho^2 drho,   e(rho0) = 0.
 *             The gauge does not know the form p(rho) of the scene's equation
 *             of state, only its inverse R(p) = rho (api->evaluation->density_from_pressure,
 *             which every equation of state provides for the hydrostatic
 *             start). Integrating by parts with rho = R(q):
 *                 e(rho) = int_{p_ref}^{p} (1/R(q) - 1/rho) dq
 *                          + p_ref (1/rho0 - 1/rho),
 *             p = p(rho) the particle's pressure, p_ref = p(rho0) (the
 *             constant `reference_pressure`, 0 when unpublished). The
 *             integral is a 5-point Gauss-Legendre rule (exact for degree 9;
 *             1/R is smooth and varies by a few per cent over the range);
 *             p(rho) is found from the current density by the secant
 *             iteration on R(p) = rho started from the `pressure` field (the
 *             last evaluation's; zero before the first) and a point 1e-4
 *             (|p| + |p_ref| + rho0 x 1 m^2 s^-2) beside it, to
 *             |R(p) - rho| <= 1e-14 rho0 (a few iterations). The
 *             result is a function of the current density alone: no history,
 *             so nothing per particle to checkpoint, and exact for any
 *             barotropic equation of state (Tait, linear, polynomial). A
 *             scene without a `density` field (point masses) has U = 0.
 *   total     E = K + P + U (zero at the start up to U(0) and K(0)).
 *   drift     (E - E_0) / S, E_0 the initial total and
 *                 S = sum_i m_i (-g . x_i) - (sum_i m_i) min_i (-g . x_i)
 *             on the initial fluid: its potential energy above its lowest
 *             particle, the energy a collapsing column can release (for the
 *             dam break S = M g (H - dx) / 2). nan when S = 0 (a single
 *             particle, no gravity).
 *
 * At the end of a run, finish() adds a row for the state the run ended or
 * stopped at (watchdog, failure, signal) when it lies after the last row, so
 * the table's last row is the energy at the end or at the stop. Checkpoints store the rows written and E_0, P_0, S.
 *
 * Across MPI ranks (ABI 1.8, SLUICE_COMPONENT_ACROSS_RANKS): each rank sums
 * K, P, U and the fluid mass over its own particles and finds its lowest
 * -g . x_i (+inf without fluid); the gauge adds the sums and takes the
 * minimum over the ranks (two api->ranks->reduce calls) before it forms E, the
 * drift and the initial E_0, P_0, S, so these and the checkpointed state are
 * the same on every rank; rank 0 writes the row. Whether a row is written
 * (here and in finish()) depends only on the time, so every rank reduces at
 * the same points. The rows are the one-rank rows up to the order of the
 * sums. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct energy_config {
    sluice_real interval;
    const char *file;
} energy_config;

typedef struct energy_state {
    const sluice_api *api;
    uint32_t dims;
    sluice_real rho0, p_ref;
    sluice_real g[3];
    const char *file;
    sluice_table *table;
    int elastic; /* the scene has a density field (and an equation of state) */
    int has_pressure;
    sluice_field mass, velocity, density, pressure;
    sluice_schedule rows; /* the next row is due at rows.count x rows.interval */
    double last_row_time;
    int have_initial;
    double potential0, total0, scale;
    /* scratch, one entry per fluid particle */
    sluice_real *rho, *p, *r, *pp, *rp;
    sluice_index capacity;
} energy_state;

static const sluice_param_spec params[] = {
    {"interval", SLUICE_PARAM_REAL, offsetof(energy_config, interval), "0.01", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s", "time between samples", NULL, 0},
    {"file", SLUICE_PARAM_STRING, offsetof(energy_config, file), "energy.csv", 0, 0, 0, NULL,
     "output file in the run directory", NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_MASS(0),
    SLUICE_SPEC_VELOCITY(0),
};

static int energy_create(const sluice_api *api, sluice_host *host, const void *config,
                         void **state)
{
    const energy_config *c = config;
    energy_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    sluice_real dims;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->rows = sluice_schedule_every(c->interval);
    s->file = c->file;
    *state = s;
    return SLUICE_OK;
}

static int energy_bind(void *state, sluice_host *host)
{
    energy_state *s = state;
    const sluice_api *api = s->api;
    sluice_real g[3] = {0, 0, 0};
    if (api->fields->constant(host, "gravity", g, 3) > 0)
        for (uint32_t d = 0; d < 3; d++)
            s->g[d] = g[d];
    sluice_real p_ref[3] = {0, 0, 0};
    if (api->fields->constant(host, "reference_pressure", p_ref, 3) > 0)
        s->p_ref = p_ref[0];
    const sluice_field_binding fields[] = {
        {"mass", &s->mass}, {"velocity", &s->velocity}};
    if (sluice_util_bind(api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    s->elastic = sluice_util_optional_field(api, host, "density", &s->density);
    if (s->elastic) {
        /* a density without an equation of state has no elastic energy to
         * speak of: refuse (the call reports it) */
        if (api->evaluation->density_from_pressure(host, 0, NULL, NULL) != SLUICE_OK)
            return SLUICE_ERROR;
        s->has_pressure = sluice_util_optional_field(api, host, "pressure", &s->pressure);
    }
    return SLUICE_OK;
}

static void energy_destroy(void *state)
{
    energy_state *s = state;
    if (!s)
        return;
    free(s->rho);
    free(s->p);
    free(s->r);
    free(s->pp);
    free(s->rp);
    free(s);
}

static int energy_initialise(void *state, sluice_host *host)
{
    energy_state *s = state;
    s->table = s->api->output->table_open(host, s->file,
                                  "time,kinetic,potential,elastic,total,drift,fluid_mass");
    if (!s->table)
        return SLUICE_ERROR;
    /* per metre of span in 2D */
    const char *energy = s->dims == 2 ? "J m^-1" : "J", *mass = s->dims == 2 ? "kg m^-1" : "kg";
    const sluice_column_doc columns[] = {
        {"s", "simulated time"},
        {energy, "kinetic energy of the fluid"},
        {energy, "potential energy of the fluid relative to the start"},
        {energy, "elastic (compression) energy of the fluid"},
        {energy, "total mechanical energy, kinetic + potential + elastic"},
        {"1", "change of the total energy over the releasable potential energy"},
        {mass, "mass of the fluid"},
    };
    return sluice_util_describe_columns(s->api, s->table, 0, columns, SLUICE_COUNT(columns));
}

static int grow(energy_state *s, sluice_host *host, sluice_index n)
{
    if (n <= s->capacity)
        return SLUICE_OK;
    sluice_index capacity = n + n / 4 + 16;
    sluice_real **arrays[5] = {&s->rho, &s->p, &s->r, &s->pp, &s->rp};
    for (int k = 0; k < 5; k++) {
        sluice_real *grown = realloc(*arrays[k], (size_t)capacity * sizeof **arrays[k]);
        if (!grown) {
            s->api->messages->error(host, "out of memory (%u particles)", (unsigned)capacity);
            return SLUICE_ERROR;
        }
        *arrays[k] = grown;
    }
    s->capacity = capacity;
    return SLUICE_OK;
}

/* sum_i m_i e(rho_i) over the fluid particles (see the header). */
static int elastic_energy(energy_state *s, sluice_host *host, const sluice_view *v, double *out)
{
    const sluice_api *api = s->api;
    const sluice_real *mass = sluice_real_column(v, s->mass, 0);
    const sluice_real *density = sluice_real_column(v, s->density, 0);
    const sluice_real *pressure = s->has_pressure ? sluice_real_column(v, s->pressure, 0) : NULL;
    sluice_index n = 0;
    for (sluice_index i = 0; i < v->count; i++)
        n += v->kind[i] == SLUICE_KIND_FLUID;
    *out = 0;
    if (n == 0)
        return SLUICE_OK;
    if (grow(s, host, n) != SLUICE_OK)
        return SLUICE_ERROR;
    /* p(rho): secant iteration on R(p) = rho, from the `pressure` field (the
     * last evaluation's, or zero before the first one) and a point beside it */
    sluice_index k = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            s->rho[k] = density[i];
            s->p[k] = pressure ? pressure[i] : s->p_ref;
            s->pp[k] = s->p[k] + 1e-4 * (fabs((double)s->p[k]) + fabs((double)s->p_ref) +
                                         (double)s->rho0 * 1.0);
            k++;
        }
    if (api->evaluation->density_from_pressure(host, n, s->p, s->r) != SLUICE_OK ||
        api->evaluation->density_from_pressure(host, n, s->pp, s->rp) != SLUICE_OK)
        return SLUICE_ERROR;
    for (int iteration = 0; iteration < 50; iteration++) {
        double worst = 0;
        for (k = 0; k < n; k++) {
            const double residual = (double)s->rho[k] - (double)s->r[k];
            const double denominator = (double)s->rp[k] - (double)s->r[k];
            worst = fmax(worst, fabs(residual));
            if (residual == 0 || denominator == 0 || !isfinite(residual) || !isfinite(denominator))
                continue;
            const double next =
                (double)s->p[k] + residual * ((double)s->pp[k] - (double)s->p[k]) / denominator;
            s->pp[k] = s->p[k];
            s->rp[k] = s->r[k];
            s->p[k] = (sluice_real)next;
        }
        if (!(worst > 1e-14 * (double)s->rho0))
            break;
        if (api->evaluation->density_from_pressure(host, n, s->p, s->r) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    /* int_{p_ref}^{p} (1/R(q) - 1/rho) dq, 5-point Gauss-Legendre */
    static const double node[5] = {0.0, -0.5384693101056831, 0.5384693101056831,
                                   -0.9061798459386640, 0.9061798459386640};
    static const double weight[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665,
                                     0.2369268850561891, 0.2369268850561891};
    const double p_ref = (double)s->p_ref;
    double *integral = NULL;
    integral = calloc((size_t)n, sizeof *integral);
    if (!integral) {
        api->messages->error(host, "out of memory (%u particles)", (unsigned)n);
        return SLUICE_ERROR;
    }
    for (int j = 0; j < 5; j++) {
        for (k = 0; k < n; k++)
            s->pp[k] = (sluice_real)(0.5 * (p_ref + (double)s->p[k]) +
                                    0.5 * ((double)s->p[k] - p_ref) * node[j]);
        if (api->evaluation->density_from_pressure(host, n, s->pp, s->r) != SLUICE_OK) {
            free(integral);
            return SLUICE_ERROR;
        }
        for (k = 0; k < n; k++)
            integral[k] += weight[j] * (1 / (double)s->r[k] - 1 / (double)s->rho[k]);
    }
    double sum = 0;
    k = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->kind[i] == SLUICE_KIND_FLUID) {
            const double rho = (double)s->rho[k];
            const double e = 0.5 * ((double)s->p[k] - p_ref) * integral[k] +
                             p_ref * (1 / (double)s->rho0 - 1 / rho);
            sum += (double)mass[i] * e;
            k++;
        }
    free(integral);
    *out = sum;
    return SLUICE_OK;
}

/* One row for the current state. */
static int energy_row(energy_state *s, sluice_host *host)
{
    const sluice_view *v = s->api->particles->view(host);
    const sluice_real *mass = sluice_real_column(v, s->mass, 0);
    double kinetic = 0, potential = 0, fluid_mass = 0, lowest = INFINITY;
    for (sluice_index i = 0; i < v->count; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        double v2 = 0, height = 0; /* height = -g . x */
        for (uint32_t d = 0; d < v->dimensions; d++) {
            const double u = (double)sluice_real_column(v, s->velocity, d)[i];
            v2 += u * u;
            height -= (double)s->g[d] * (double)v->position[d][i];
        }
        kinetic += 0.5 * (double)mass[i] * v2;
        potential += (double)mass[i] * height;
        fluid_mass += (double)mass[i];
        lowest = fmin(lowest, height);
    }
    double elastic = 0;
    if (s->elastic && elastic_energy(s, host, v, &elastic) != SLUICE_OK)
        return SLUICE_ERROR;
    /* over the ranks (collective; the identity on one rank), before anything
     * is formed from them */
    double sums[4] = {kinetic, potential, elastic, fluid_mass};
    if (s->api->ranks->reduce(host, sums, 4, SLUICE_REDUCE_SUM) != SLUICE_OK ||
        s->api->ranks->reduce(host, &lowest, 1, SLUICE_REDUCE_MIN) != SLUICE_OK)
        return SLUICE_ERROR;
    kinetic = sums[0];
    potential = sums[1];
    elastic = sums[2];
    fluid_mass = sums[3];
    if (!s->have_initial) {
        s->potential0 = potential;
        s->total0 = kinetic + elastic;
        s->scale = fluid_mass > 0 ? potential - fluid_mass * lowest : 0;
        s->have_initial = 1;
    }
    const double relative = potential - s->potential0;
    const double total = kinetic + relative + elastic;
    const double drift = s->scale > 0 ? (total - s->total0) / s->scale : NAN;
    const double row[7] = {v->time, kinetic, relative, elastic, total, drift, fluid_mass};
    if (s->api->output->table_row(s->table, row, 7) != SLUICE_OK)
        return SLUICE_ERROR;
    s->last_row_time = v->time;
    return SLUICE_OK;
}

static int energy_after_step(void *state, sluice_host *host)
{
    energy_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    if (!sluice_schedule_due(&s->rows, v->time))
        return SLUICE_OK;
    if (energy_row(s, host) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_schedule_advance(&s->rows, s->api, host, v->time);
    return SLUICE_OK;
}

/* The state the run ended or stopped at, when that lies after the last row
 * (an end between samples, a failure, a signal). */
static int energy_finish(void *state, sluice_host *host, int status)
{
    energy_state *s = state;
    (void)status;
    if (!s->table || !s->have_initial)
        return SLUICE_OK;
    const sluice_view *v = s->api->particles->view(host);
    if (!(v->time > s->last_row_time + sluice_schedule_tolerance(&s->rows)))
        return SLUICE_OK;
    return energy_row(s, host);
}

/* Checkpoints: the rows written, the initial sums and the last row's time. */
static int energy_save(void *state, sluice_host *host)
{
    const energy_state *s = state;
    const double values[5] = {s->potential0, s->total0, s->scale, s->last_row_time,
                              (double)s->have_initial};
    if (s->api->state->state_write(host, "potential0,total0,scale,last_row_time,have_initial",
                            SLUICE_STATE_DOUBLE, 5, values) != SLUICE_OK)
        return SLUICE_ERROR;
    return sluice_schedule_save(&s->rows, s->api, host, "rows_written");
}

static int energy_load(void *state, sluice_host *host)
{
    energy_state *s = state;
    double values[5];
    if (s->api->state->state_read(host, "potential0,total0,scale,last_row_time,have_initial",
                           SLUICE_STATE_DOUBLE, 5, values) != SLUICE_OK ||
        sluice_schedule_load(&s->rows, s->api, host, "rows_written") != SLUICE_OK)
        return SLUICE_ERROR;
    s->potential0 = values[0];
    s->total0 = values[1];
    s->scale = values[2];
    s->last_row_time = values[3];
    s->have_initial = values[4] != 0;
    return SLUICE_OK;
}

static const sluice_component components[] = {{
    .name = "energy_gauge",
    .summary = "energy budget of the fluid: kinetic, potential, elastic (equation of state), "
               "total and its drift, as time,kinetic,potential,elastic,total,drift,fluid_mass",
    .reference = "elastic energy de = p/rho^2 drho of a barotropic fluid (Monaghan 1992, "
                 "Annu. Rev. Astron. Astrophys. 30, sec. 3)",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_ACROSS_RANKS,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(energy_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .create = energy_create,
    .destroy = energy_destroy,
    .bind = energy_bind,
    .initialise = energy_initialise,
    .after_step = energy_after_step,
    .finish = energy_finish,
    .save_state = energy_save,
    .load_state = energy_load,
}};

SLUICE_DEFINE_LIBRARY("energy_gauge", "1.1.0", "energy budget gauge", SLUICE_DIMS_ALL,
                      components)
