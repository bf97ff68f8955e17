/* Periodic Shepard smoothing of the non-hydrostatic pressure (seed 004, De
 * Padova et al. 2017, section 3, after De Padova et al. 2013 and 2016): every
 * `every` steps, for every fluid particle,
 *
 *   p~_i = p^h_i + sum_j V_j (p_j - p^h_j) W_ij / sum_j V_j W_ij,   V_j = m_j / rho_j,
 *
 * both sums over the fluid particles of the support including i itself
 * (W_ii = W(0)), with the hydrostatic pressure
 *
 *   p^h_i = rho0 |g| (eta(x_i) - z_i),
 *
 * z the elevation along -g and eta the local free-surface level above the
 * particle. Filtering only the departure from hydrostatics removes the
 * acoustic noise of weakly-compressible SPH without smearing the hydrostatic
 * gradient (a Shepard filter of p itself would, near the free surface and
 * the bed, where the support is one-sided).
 *
 * eta: the fluid particles are binned in columns of width h across gravity;
 * a column's level is its highest fluid particle + dx/2 (the lattice
 * particle's half spacing: the level the core's hydrostatic start uses for a
 * region filled to its top), and eta(x) is the bilinear (2D: linear)
 * interpolation between column centres, an empty neighbour column counting
 * as the particle's own. The estimate need not be exact: p^h is subtracted
 * and added back, and the Shepard filter reproduces constants, so an error of
 * eta that is uniform over a support cancels exactly; only its variation
 * within a support enters p~ (an overhang, or a drop thrown above the
 * surface, raises eta of its column). Without gravity p^h = 0 (a plain
 * Shepard filter of the pressure).
 *
 * The result persists through the density: the equation of state recomputes
 * the pressure from the density at every evaluation, so the density is set
 * to EOS^-1(p~) (api->evaluation->density_from_pressure, ABI 1.2). Particle masses are not
 * touched. Before filtering, the hook runs one evaluation (api->evaluation->evaluate) so
 * that the pressure filtered is that of the current density, not the one of
 * the integrator's last (mid-step) evaluation: one more evaluation every
 * `every` steps. The pair callback is on demand (api->evaluation->pair_pass), fluid
 * targets, fluid neighbours. */
#include <math.h>

#include <sluice/plugin_util.h>

typedef struct ps_config {
    int64_t every;
} ps_config;

typedef struct ps_state {
    const sluice_api *api;
    uint32_t dims;
    int64_t every;
    sluice_real rho0, gravity_magnitude, up[3], across[2][3], bin_width, half_spacing;
    sluice_field density, mass, pressure, hydrostatic, smoothed;
    /* work arrays of the hook, grown as needed */
    double *levels; /* double: combined over MPI ranks with api->ranks->reduce */
    size_t level_capacity;
    sluice_index *fluid;
    sluice_real *buffer; /* 2 per fluid particle: pressure, density */
    sluice_index fluid_capacity;
} ps_state;

static const sluice_param_spec params[] = {
    {"every", SLUICE_PARAM_INT, offsetof(ps_config, every), "20", 1, 0, SLUICE_PARAM_HAS_MIN,
     "1", "smooth every this many steps (seed 004 does not state the period; periodic density "
          "filters in WCSPH are applied every 20 to 40 steps)",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_PRESSURE(SLUICE_READ | SLUICE_READ_NEIGHBOUR | SLUICE_WRITE),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR | SLUICE_WRITE),
    SLUICE_SPEC_MASS(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    {"hydrostatic_pressure", SLUICE_TYPE_REAL, 1, "Pa",
     SLUICE_READ | SLUICE_READ_NEIGHBOUR | SLUICE_WRITE, 0, NULL, 0,
     "rho0 |g| (eta - z) below the local free surface eta (pressure smoothing)"},
    {"smoothed_pressure", SLUICE_TYPE_REAL, 1, "Pa", SLUICE_READ | SLUICE_WRITE, 0, NULL, 0,
     "Shepard-filtered pressure of the last smoothing"},
};

static int ps_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const ps_config *c = config;
    ps_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->every = c->every;
    sluice_real dims, h, dx;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "rest_density", &s->rho0) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &h) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &dx) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->bin_width = h;
    s->half_spacing = (sluice_real)0.5 * dx;
    *state = s;
    return SLUICE_OK;
}

/* up = -g / |g| and an orthonormal basis of the plane across it. */
static void ps_axes(ps_state *s, const sluice_real *g)
{
    const uint32_t dims = s->dims;
    double norm = 0;
    for (uint32_t d = 0; d < dims; d++)
        norm += (double)g[d] * (double)g[d];
    norm = sqrt(norm);
    s->gravity_magnitude = (sluice_real)norm;
    for (uint32_t d = 0; d < 3; d++)
        s->up[d] = d < dims && norm > 0 ? (sluice_real)(-(double)g[d] / norm) : 0;
    if (!(norm > 0))
        return;
    const sluice_real *u = s->up;
    if (dims == 2) {
        s->across[0][0] = u[1];
        s->across[0][1] = -u[0];
        s->across[0][2] = 0;
        return;
    }
    /* the axis least aligned with up, crossed with up */
    int axis = 0;
    for (int d = 1; d < 3; d++)
        if (fabs((double)u[d]) < fabs((double)u[axis]))
            axis = d;
    sluice_real a[3] = {0, 0, 0};
    a[axis] = 1;
    sluice_real t[3] = {u[1] * a[2] - u[2] * a[1], u[2] * a[0] - u[0] * a[2],
                        u[0] * a[1] - u[1] * a[0]};
    double tn = sqrt((double)(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]));
    for (int d = 0; d < 3; d++)
        s->across[0][d] = (sluice_real)((double)t[d] / tn);
    const sluice_real *t1 = s->across[0];
    s->across[1][0] = u[1] * t1[2] - u[2] * t1[1];
    s->across[1][1] = u[2] * t1[0] - u[0] * t1[2];
    s->across[1][2] = u[0] * t1[1] - u[1] * t1[0];
}

static int ps_bind(void *state, sluice_host *host)
{
    ps_state *s = state;
    const sluice_api *api = s->api;
    const sluice_field_binding fields[] = {
        {"density", &s->density}, {"mass", &s->mass}, {"pressure", &s->pressure},
        {"hydrostatic_pressure", &s->hydrostatic}, {"smoothed_pressure", &s->smoothed}};
    if (sluice_util_bind(api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    /* the smoothed pressure persists through the equation of state's inverse */
    if (api->evaluation->density_from_pressure(host, 0, NULL, NULL) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real g[3] = {0, 0, 0};
    api->fields->constant(host, "gravity", g, 3); /* absent: no hydrostatic part */
    ps_axes(s, g);
    return SLUICE_OK;
}

static void ps_destroy(void *state)
{
    ps_state *s = state;
    if (!s)
        return;
    free(s->levels);
    free(s->fluid);
    free(s->buffer);
    free(s);
}

/* --------------------------------------------------------- pair callback -- */

static inline void ps_pairs(const ps_state *s, const sluice_view *v, const sluice_pair_batch *b,
                            const int masked)
{
    const sluice_real *restrict p = sluice_real_column(v, s->pressure, 0);
    const sluice_real *restrict ph = sluice_real_column(v, s->hydrostatic, 0);
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict mass = sluice_real_column(v, s->mass, 0);
    const sluice_real *restrict pj = b->gathered[s->pressure.column];
    const sluice_real *restrict phj = b->gathered[s->hydrostatic.column];
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict W = b->kernel;
    const uint8_t *restrict kj = b->neighbour_kind;
    sluice_real *restrict out = sluice_real_column(v, s->smoothed, 0);
    const sluice_real w0 = b->kernel_self;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real self = mass[i] / rho[i] * w0;
        sluice_real weights = self, sum = self * (p[i] - ph[i]);
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            sluice_real weight = mj[k] / rhoj[k] * W[k];
            if (masked)
                weight = kj[k] != SLUICE_KIND_WALL ? weight : 0;
            weights += weight;
            sum += weight * (pj[k] - phj[k]);
        }
        out[i] = ph[i] + sum / weights;
    }
}

static void ps_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    if (b->neighbour_kinds != SLUICE_KIND_MASK(SLUICE_KIND_FLUID))
        ps_pairs(state, v, b, 1);
    else
        ps_pairs(state, v, b, 0);
}

/* -------------------------------------------------------- the hook -- */

/* Horizontal (across-gravity) coordinate c of particle i. */
static inline sluice_real across(const ps_state *s, const sluice_view *v, sluice_index i, int c)
{
    sluice_real x = 0;
    for (uint32_t d = 0; d < v->dimensions; d++)
        x += s->across[c][d] * v->position[d][i];
    return x;
}

static inline sluice_real elevation(const ps_state *s, const sluice_view *v, sluice_index i)
{
    sluice_real z = 0;
    for (uint32_t d = 0; d < v->dimensions; d++)
        z += s->up[d] * v->position[d][i];
    return z;
}

/* Column bins of the free-surface level; bin (a, b) at levels[a + na * b]. */
typedef struct ps_bins {
    sluice_real origin[2];
    int64_t count[2];
} ps_bins;

static inline int64_t bin_index(sluice_real x, sluice_real origin, sluice_real width, int64_t n)
{
    int64_t k = (int64_t)floor((double)((x - origin) / width));
    return k < 0 ? 0 : k >= n ? n - 1 : k;
}

/* eta at particle i: (bi)linear interpolation between column centres. */
static sluice_real surface_level(const ps_state *s, const ps_bins *bins, const sluice_real *c)
{
    const int axes = s->dims == 3 ? 2 : 1;
    int64_t lo[2] = {0, 0}, own[2] = {0, 0};
    sluice_real frac[2] = {0, 0};
    for (int a = 0; a < axes; a++) {
        const sluice_real u = (c[a] - bins->origin[a]) / s->bin_width - (sluice_real)0.5;
        const sluice_real f = (sluice_real)floor((double)u);
        own[a] = bin_index(c[a], bins->origin[a], s->bin_width, bins->count[a]);
        lo[a] = (int64_t)f;
        frac[a] = u - f;
    }
    const int64_t na = bins->count[0];
    const sluice_real own_level = (sluice_real)s->levels[own[0] + na * own[1]];
    sluice_real eta = 0;
    for (int corner = 0; corner < (1 << axes); corner++) {
        sluice_real weight = 1;
        int64_t k[2] = {0, 0};
        int inside = 1;
        for (int a = 0; a < axes; a++) {
            const int upper = (corner >> a) & 1;
            k[a] = lo[a] + upper;
            weight *= upper ? frac[a] : 1 - frac[a];
            inside &= k[a] >= 0 && k[a] < bins->count[a];
        }
        sluice_real level = inside ? (sluice_real)s->levels[k[0] + na * k[1]] : own_level;
        if (!(level > -INFINITY))
            level = own_level; /* empty column */
        eta += weight * level;
    }
    return eta;
}

/* p^h for every particle (0 for walls). */
static int ps_hydrostatic(ps_state *s, sluice_host *host, const sluice_view *v)
{
    const sluice_api *api = s->api;
    sluice_real *restrict ph = sluice_real_column(v, s->hydrostatic, 0);
    const uint8_t *kind = v->kind;
    const sluice_index n = v->count;
    for (sluice_index i = 0; i < n; i++)
        ph[i] = 0;
    if (!(s->gravity_magnitude > 0))
        return SLUICE_OK;
    const int axes = s->dims == 3 ? 2 : 1;
    ps_bins bins = {{0, 0}, {1, 1}};
    sluice_real lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    sluice_index fluid = 0;
    for (sluice_index i = 0; i < n; i++) {
        if (kind[i] != SLUICE_KIND_FLUID)
            continue;
        fluid++;
        for (int a = 0; a < axes; a++) {
            const sluice_real c = across(s, v, i, a);
            lo[a] = c < lo[a] ? c : lo[a];
            hi[a] = c > hi[a] ? c : hi[a];
        }
    }
    /* across MPI ranks: the columns span every rank's fluid (the one-rank
     * columns); the identity on one rank */
    double extent[5] = {-(double)lo[0], -(double)lo[1], (double)hi[0], (double)hi[1],
                        fluid > 0 ? 1.0 : 0.0};
    if (api->ranks->reduce(host, extent, 5, SLUICE_REDUCE_MAX) != SLUICE_OK)
        return SLUICE_ERROR;
    if (extent[4] == 0)
        return SLUICE_OK;
    for (int a = 0; a < axes; a++) {
        lo[a] = (sluice_real)-extent[a];
        hi[a] = (sluice_real)extent[2 + a];
    }
    size_t total = 1;
    for (int a = 0; a < axes; a++) {
        const double span = floor((double)((hi[a] - lo[a]) / s->bin_width)) + 1;
        if (!(span >= 1 && span < 1e8)) {
            api->messages->error(host, "the fluid spans %g m across gravity: too many free-surface columns "
                             "of width h = %g m (or a non-finite position)",
                       (double)(hi[a] - lo[a]), (double)s->bin_width);
            return SLUICE_ERROR;
        }
        bins.origin[a] = lo[a];
        bins.count[a] = (int64_t)span;
        total *= (size_t)span;
    }
    if (total > s->level_capacity) {
        double *grown = realloc(s->levels, total * sizeof *grown);
        if (!grown) {
            api->messages->error(host, "out of memory (%zu free-surface columns)", total);
            return SLUICE_ERROR;
        }
        s->levels = grown;
        s->level_capacity = total;
    }
    for (size_t k = 0; k < total; k++)
        s->levels[k] = -INFINITY;
    const int64_t na = bins.count[0];
    for (sluice_index i = 0; i < n; i++) {
        if (kind[i] != SLUICE_KIND_FLUID)
            continue;
        int64_t k[2] = {0, 0};
        for (int a = 0; a < axes; a++)
            k[a] = bin_index(across(s, v, i, a), bins.origin[a], s->bin_width, bins.count[a]);
        const double top = (double)(elevation(s, v, i) + s->half_spacing);
        double *level = &s->levels[k[0] + na * k[1]];
        *level = top > *level ? top : *level;
    }
    /* each column's highest particle over the ranks (collective) */
    if (total > UINT32_MAX ||
        api->ranks->reduce(host, s->levels, (uint32_t)total, SLUICE_REDUCE_MAX) != SLUICE_OK)
        return SLUICE_ERROR;
    const sluice_real weight = s->rho0 * s->gravity_magnitude;
    for (sluice_index i = 0; i < n; i++) {
        if (kind[i] != SLUICE_KIND_FLUID)
            continue;
        sluice_real c[2] = {0, 0};
        for (int a = 0; a < axes; a++)
            c[a] = across(s, v, i, a);
        ph[i] = weight * (surface_level(s, &bins, c) - elevation(s, v, i));
    }
    return SLUICE_OK;
}

static int ps_after_step(void *state, sluice_host *host)
{
    ps_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (v->step <= 0 || v->step % s->every != 0)
        return SLUICE_OK;
    /* the pressure of the current density (the last evaluation was mid-step) */
    if (api->evaluation->evaluate(host, api->particles->view(host)->time, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host);
    if (ps_hydrostatic(s, host, v) != SLUICE_OK)
        return SLUICE_ERROR;
    if (api->evaluation->pair_pass(host) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host); /* fields move with the particles if the pass re-sorted them */
    const sluice_index n = v->count;
    if (n > s->fluid_capacity) {
        sluice_index *fluid = realloc(s->fluid, (size_t)n * sizeof *fluid);
        if (fluid)
            s->fluid = fluid;
        sluice_real *buffer = realloc(s->buffer, 2 * (size_t)n * sizeof *buffer);
        if (buffer)
            s->buffer = buffer;
        if (!fluid || !buffer) {
            api->messages->error(host, "out of memory (%u particles)", n);
            return SLUICE_ERROR;
        }
        s->fluid_capacity = n;
    }
    const uint8_t *kind = v->kind;
    const sluice_real *smoothed = sluice_real_column(v, s->smoothed, 0);
    sluice_index count = 0;
    for (sluice_index i = 0; i < n; i++)
        if (kind[i] == SLUICE_KIND_FLUID) {
            s->buffer[count] = smoothed[i];
            s->fluid[count++] = i;
        }
    sluice_real *density_new = s->buffer + n;
    if (api->evaluation->density_from_pressure(host, count, s->buffer, density_new) != SLUICE_OK)
        return SLUICE_ERROR;
    sluice_real *density = sluice_real_column(v, s->density, 0);
    sluice_real *pressure = sluice_real_column(v, s->pressure, 0);
    for (sluice_index k = 0; k < count; k++) {
        density[s->fluid[k]] = density_new[k];
        pressure[s->fluid[k]] = s->buffer[k];
    }
    return SLUICE_OK;
}

static const sluice_component components[] = {{
    .name = "pressure_smoothing",
    .summary = "Shepard filter of the non-hydrostatic pressure every N steps (kept through the "
               "density)",
    .reference = "De Padova et al. (2017, seed 004, after De Padova et al. 2013 and 2016); "
                 "Shepard (1968) normalisation",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_NEEDS_KERNEL | SLUICE_COMPONENT_ON_DEMAND,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(ps_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = ps_create,
    .destroy = ps_destroy,
    .bind = ps_bind,
    .pair = ps_pair,
    .after_step = ps_after_step,
}};

SLUICE_DEFINE_LIBRARY("pressure_smoothing", "1.1.0",
                      "Shepard smoothing of the non-hydrostatic pressure", SLUICE_DIMS_ALL,
                      components)
