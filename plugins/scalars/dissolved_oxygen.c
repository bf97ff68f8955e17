/* Dissolved oxygen: a concentration C (mg L^-1 = g m^-3) carried by the water
 * particles, with turbulent diffusion and reaeration from air particles
 * (seed 001, Wan et al. 2017, Water 9:565, eqs. 13-20; its equations were lost
 * from the text, so the forms below are restated from the papers it cites):
 *
 *   dC_i/dt = sum_j (m_j / (rho_i rho_j)) (rho_i + rho_j) D_ij (C_i - C_j)
 *                   (r_ij . grad_i W_ij) / (r_ij^2 + eta^2)   +   S_i
 *
 * Diffusion (seed 001 eq. 15 after Cleary & Monaghan 1999, J. Comput. Phys.
 * 148:227, and Aristodemo et al. 2010, Environ. Fluid Mech. 10:451):
 * D = D_m + nu_t / Sc_t per particle, D_m the molecular diffusivity, nu_t the
 * field eddy_viscosity when a turbulence plugin declares it (else D = D_m),
 * Sc_t the turbulent Schmidt number (1.0 in seed 001), and the harmonic pair
 * mean D_ij = 2 D_i D_j / (D_i + D_j) (Cleary & Monaghan's conductivity
 * mean). eta^2 = 0.01 h^2. Since r_ij . grad_i W_ij = r^2 F_ij = r dW/dr < 0,
 * a particle richer than its neighbours loses oxygen: it is diffusion (a bump
 * decays). With equal densities the weight is 2 V_j D_ij r^2 F / (r^2 + eta^2),
 * Brookshaw's (1985) Laplacian, which equals div(D grad C) in the continuum
 * limit. Only water-water pairs diffuse (air carries no oxygen), over fluid
 * neighbours (wall particles take no part: no flux through walls).
 *
 * Conservation: m_i times the pair term of i is
 * m_i m_j (1/rho_i + 1/rho_j) D_ij r^2 F / (r^2 + eta^2) (C_i - C_j): a weight
 * symmetric in i and j times an antisymmetric difference. The exactly
 * conserved quantity is therefore sum_i m_i C_i, i.e. the total solute
 * sum_i (m_i / rho_0) C_i with each particle's volume taken at the rest
 * density (C is carried with the particle, unchanged by the small
 * compressions of weakly compressible SPH). The volume-weighted
 * sum_i (m_i / rho_i) C_i differs from it by at most max |rho_0/rho_i - 1|
 * sum_i (m_i / rho_0) |C_i|, the compressibility of the water, not a flux
 * imbalance (test dissolved_oxygen/conservation).
 *
 * Reaeration source (seed 001 eqs. 17-19): for a water particle with N_air > 0
 * air particles within the search radius R,
 *   S_i = K a_i (C_s - C_i),   a_i = N_air A_b / V_w,
 * with A_b the surface of one bubble of diameter d_b (2D: its perimeter
 * pi d_b; 3D: pi d_b^2) and V_w the water volume within R, taken as the rest
 * volume of the water particles there, i included: V_w = (N_water + 1) dx^d
 * (seed 001 eq. 19 counts particles; the kernel-weighted volume would be a
 * second choice). S_i = 0 where no air particle is within R. K is either the
 * constant transfer_velocity, or a power law of an effective Reynolds number
 * (seed 001 eq. 20, "after Banerjee et al.", with one constant "recommended as
 * 0.2" and another "a constant value", Re "after Price"; the equation itself
 * was lost): reconstructed here as the small-eddy / surface-renewal law
 *   K Sc^(1/2) / U = c_1 Re^(c_2),   Re = U d_b / nu,   Sc = nu / D_m,
 * i.e. K = c_1 sqrt(D_m nu) / d_b Re^(1 + c_2), with U the slip speed
 * |v_i - mean of v over the air particles within R|. Defaults c_1 = 0.2 (the
 * seed's recommended value) and c_2 = -1/4 (the turbulent surface-renewal
 * exponent, K ~ Sc^(-1/2) (eps nu)^(1/4) with eps ~ U^3 / d_b; Banerjee, Rhodes
 * & Scott 1968, Lamont & Scott 1970). c_2 = -1/2, c_1 = 2/sqrt(pi) gives
 * Higbie's penetration law K = 1.13 sqrt(D_m U / d_b).
 *
 * Phase: the field `phase` (uint8, 0 water, 1 air) of the two-phase plugin.
 * two_phase: auto uses it when some plugin declares it (by the end of
 * create()); yes requires it; no ignores it. Without it every fluid particle
 * is water and the source is zero everywhere (a warning at bind).
 *
 * Initial value: every fluid particle initial_concentration, air particles 0
 * (set at the first evaluation, once the phase is known); particles created
 * during the run (inlets) start at initial_concentration too (set in this
 * plugin's after_step, and in any case before the next evaluation). A
 * particle is new when its id is at least the first id not seen yet; across
 * MPI ranks every scan looks at every particle of the rank (a particle that
 * came from another rank changes no count) and the ranks agree on the first
 * id not seen (api->ranks->reduce, maximum), so a particle initialised on one rank
 * keeps its concentration when it moves to another.
 *
 * Time step: the explicit diffusion limit 0.125 h^2 / max(D) (as
 * laminar_viscosity, Morris et al. 1997; not multiplied by the Courant
 * number), and C / max(K a) for the source (C the constant courant_number),
 * whose relaxation time is 1 / (K a). */
#include <float.h>
#include <math.h>

#include <sluice/plugin_util.h>

enum { TWO_PHASE_AUTO = 0, TWO_PHASE_YES = 1, TWO_PHASE_NO = 2 };

typedef struct do_config {
    sluice_real initial, saturation, diffusivity, schmidt;
    int two_phase;
    sluice_real radius, bubble, transfer_velocity, c1, c2, nu;
} do_config;

typedef struct do_state {
    const sluice_api *api;
    do_config c;
    uint32_t dims;
    sluice_real h, dx, eta2, support;
    int two_phase;  /* the phase field is read and the source is on */
    int eddy;       /* eddy_viscosity is read */
    int power_law;  /* K from the Reynolds-number law (else transfer_velocity) */
    sluice_real radius, bubble, bubble_area, rest_volume, courant;
    sluice_real law; /* c_1 sqrt(D_m nu) / d_b */
    sluice_real inv_schmidt;
    sluice_field mass, density, velocity, concentration, rate, eddy_viscosity, phase, ka;
    int started;          /* air particles zeroed (first evaluation) */
    sluice_id next_id;    /* particles with an id from here on are new */
    uint64_t seen;        /* count + removed at the last scan for new particles */
    int32_t ranks;        /* ranks of the run (api->ranks->ranks) */
} do_state;

#define POSITIVE (SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE)

static const sluice_param_spec params[] = {
    {"initial_concentration", SLUICE_PARAM_REAL, offsetof(do_config, initial), NULL, 0, 0,
     SLUICE_PARAM_HAS_MIN, "mg L^-1",
     "concentration of every water particle at the start, and of particles created during the "
     "run (inlets); seed 001, Cheng's spillway: Cu = 1.29 at the crest",
     NULL, 0},
    {"saturation_concentration", SLUICE_PARAM_REAL, offsetof(do_config, saturation), "10.48", 0,
     0, SLUICE_PARAM_HAS_MIN, "mg L^-1",
     "saturation concentration C_s at atmospheric pressure (seed 001, Cheng: 10.48)", NULL, 0},
    {"molecular_diffusivity", SLUICE_PARAM_REAL, offsetof(do_config, diffusivity), "2.1e-9", 0,
     0, SLUICE_PARAM_HAS_MIN, "m^2 s^-1",
     "molecular diffusivity D_m of oxygen in water (2.1e-9 at 25 C, Cussler 2009 table 5.2-1; "
     "about 1.8e-9 at 20 C by the Stokes-Einstein scaling T/mu)",
     NULL, 0},
    {"turbulent_schmidt_number", SLUICE_PARAM_REAL, offsetof(do_config, schmidt), "1.0", 0, 0,
     POSITIVE, "1", "Sc_t in D = D_m + nu_t / Sc_t (seed 001: 1.0)", NULL, 0},
    {"two_phase", SLUICE_PARAM_ENUM, offsetof(do_config, two_phase), "auto", 0, 0, 0, NULL,
     "auto: read the field 'phase' (0 water, 1 air) when a plugin declares it; yes: require it; "
     "no: every fluid particle is water and there is no source",
     "auto|yes|no", 0},
    {"search_radius", SLUICE_PARAM_REAL, offsetof(do_config, radius), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m",
     "radius R within which air particles count for the source; at most the kernel support "
     "(default: the kernel support)",
     NULL, 0},
    {"bubble_diameter", SLUICE_PARAM_REAL, offsetof(do_config, bubble), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m",
     "diameter d_b of the bubble each air particle stands for (default: the particle spacing)",
     NULL, 0},
    {"transfer_velocity", SLUICE_PARAM_REAL, offsetof(do_config, transfer_velocity), NULL, 0, 0,
     POSITIVE | SLUICE_PARAM_OPTIONAL, "m s^-1",
     "constant transfer velocity K (calibration); when absent K follows the Reynolds-number law",
     NULL, 0},
    {"transfer_coefficient", SLUICE_PARAM_REAL, offsetof(do_config, c1), "0.2", 0, 0, POSITIVE,
     "1", "c_1 in K Sc^(1/2) / U = c_1 Re^(c_2) (seed 001: 0.2)", NULL, 0},
    {"reynolds_exponent", SLUICE_PARAM_REAL, offsetof(do_config, c2), "-0.25", -1, 0,
     SLUICE_PARAM_HAS_MIN | SLUICE_PARAM_MIN_EXCLUSIVE, "1",
     "c_2 in K Sc^(1/2) / U = c_1 Re^(c_2), > -1 (default -1/4: surface renewal by small "
     "eddies; -1/2: Higbie's penetration law)",
     NULL, 0},
    {"kinematic_viscosity", SLUICE_PARAM_REAL, offsetof(do_config, nu), "1.0e-6", 0, 0, POSITIVE,
     "m^2 s^-1", "kinematic viscosity nu of water in Re and Sc (20 C: 1.0e-6)", NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    {"dissolved_oxygen", SLUICE_TYPE_REAL, 1, "mg L^-1",
     SLUICE_READ | SLUICE_READ_NEIGHBOUR | SLUICE_WRITE, SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART,
     NULL, 0,
     "dissolved-oxygen concentration C of water particles (0 in air)"},
    {"dissolved_oxygen_rate", SLUICE_TYPE_REAL, 1, "mg L^-1 s^-1", SLUICE_ACCUMULATE, 0,
     "dissolved_oxygen", SLUICE_KIND_MASK(SLUICE_KIND_FLUID), "dC/dt: diffusion and reaeration"},
};

static int do_declare(do_state *s, sluice_host *host, const char *name, uint32_t components,
                      const char *units, uint32_t access, uint32_t flags, const char *doc,
                      sluice_type type)
{
    const sluice_field_spec spec = {name, type, components, units, access, flags, NULL, 0, doc};
    return s->api->fields->declare_field(host, &spec);
}

/* The fields that depend on the scene's other plugins, declared in create()
 * (every component's static fields are declared by then): nu_t when a
 * turbulence model declares it; with a phase (two_phase), the phase, the
 * velocity of the Reynolds-number law and K a. The same conditions decide
 * in bind() what the term computes. */
static int declare_optional(do_state *s, sluice_host *host)
{
    const sluice_api *api = s->api;
    sluice_field found;
    if (sluice_util_optional_field(api, host, "eddy_viscosity", &found) &&
        do_declare(s, host, "eddy_viscosity", 1, "m^2 s^-1", SLUICE_READ | SLUICE_READ_NEIGHBOUR,
                   0, "kinematic eddy viscosity nu_T", SLUICE_TYPE_REAL) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->c.two_phase == TWO_PHASE_NO || !sluice_util_optional_field(api, host, "phase", &found))
        return SLUICE_OK;
    if (s->c.two_phase == TWO_PHASE_AUTO &&
        do_declare(s, host, "phase", 1, "1", SLUICE_READ | SLUICE_READ_NEIGHBOUR, 0,
                   "phase of a fluid particle: 0 water, 1 air", SLUICE_TYPE_UINT8) != SLUICE_OK)
        return SLUICE_ERROR;
    if (!(s->c.transfer_velocity > 0) &&
        do_declare(s, host, "velocity", SLUICE_COMPONENTS_DIM, "m s^-1",
                   SLUICE_READ | SLUICE_READ_NEIGHBOUR, SLUICE_FIELD_OUTPUT | SLUICE_FIELD_RESTART,
                   "velocity", SLUICE_TYPE_REAL) != SLUICE_OK)
        return SLUICE_ERROR;
    return do_declare(s, host, "reaeration_coefficient", 1, "s^-1", SLUICE_WRITE,
                      SLUICE_FIELD_OUTPUT,
                      "K a_i: volumetric oxygen transfer coefficient (0 away from air)",
                      SLUICE_TYPE_REAL);
}

static int do_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const do_config *c = config;
    do_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->c = *c;
    sluice_real dims;
    if (sluice_util_constant(api, host, "dimensions", &dims) != SLUICE_OK ||
        sluice_util_constant(api, host, "smoothing_length", &s->h) != SLUICE_OK ||
        sluice_util_constant(api, host, "spacing", &s->dx) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->dims = (uint32_t)dims;
    s->eta2 = (sluice_real)0.01 * s->h * s->h;
    s->inv_schmidt = 1 / c->schmidt;
    /* two_phase: yes declares the phase now, so that a scene without a
     * provider is refused by the core ("computed by no loaded plugin") */
    if (c->two_phase == TWO_PHASE_YES) {
        const sluice_field_spec phase = SLUICE_SPEC_PHASE_DOC(
            SLUICE_READ | SLUICE_READ_NEIGHBOUR, 0, "phase of a fluid particle: 0 water, 1 air");
        if (api->fields->declare_field(host, &phase) != SLUICE_OK) {
            free(s);
            return SLUICE_ERROR;
        }
    }
    if (declare_optional(s, host) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}


static int do_bind(void *state, sluice_host *host)
{
    do_state *s = state;
    const sluice_api *api = s->api;
    const sluice_field_binding fields[] = {
        {"mass", &s->mass}, {"density", &s->density}, {"dissolved_oxygen", &s->concentration},
        {"dissolved_oxygen_rate", &s->rate}};
    if (sluice_util_bind(api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;

    sluice_real ratio;
    if (sluice_util_constant(api, host, "kernel_support", &ratio) != SLUICE_OK)
        return SLUICE_ERROR;
    s->support = ratio * s->h;
    s->radius = s->c.radius > 0 ? s->c.radius : s->support;
    if (s->radius > s->support * (1 + 1e-12)) {
        api->messages->error(host,
                   "search_radius = %g m is larger than the kernel support %g m (%g h): pairs "
                   "reach only the support; use search_radius <= %g m",
                   (double)s->radius, (double)s->support, (double)ratio, (double)s->support);
        return SLUICE_ERROR;
    }

    /* turbulent diffusion when a turbulence model declares nu_t */
    sluice_field nu_t;
    if (sluice_util_optional_field(api, host, "eddy_viscosity", &nu_t)) {
        s->eddy_viscosity = nu_t;
        s->eddy = 1;
    }

    /* the phase, and with it the source */
    sluice_field phase;
    const int has_phase = sluice_util_optional_field(api, host, "phase", &phase);
    if (s->c.two_phase == TWO_PHASE_NO) {
        if (has_phase)
            api->messages->warning(host, "two_phase: no: the field 'phase' is ignored; every fluid "
                               "particle is water and the reaeration source is zero");
    } else if (!has_phase) {
        /* (two_phase: yes declared it in create(): it is always found here) */
        api->messages->warning(host, "no loaded plugin declares the field 'phase': every fluid particle "
                           "is water and the reaeration source is zero everywhere (diffusion "
                           "and advection only)");
    } else {
        if (phase.type != SLUICE_TYPE_UINT8 || phase.components != 1) {
            api->messages->error(host, "the field 'phase' must be uint8 with one component (0 water, 1 "
                             "air)");
            return SLUICE_ERROR;
        }
        s->two_phase = 1;
    }
    if (!s->two_phase)
        return SLUICE_OK;

    s->phase = phase;
    const sluice_real d_b = s->bubble = s->c.bubble > 0 ? s->c.bubble : s->dx;
    s->bubble_area = (sluice_real)SLUICE_PI * d_b * (s->dims == 3 ? d_b : 1);
    s->rest_volume = s->dims == 3 ? s->dx * s->dx * s->dx : s->dx * s->dx;
    s->power_law = !(s->c.transfer_velocity > 0);
    if (s->power_law) {
        s->law = s->c.c1 * sqrt(s->c.diffusivity * s->c.nu) / d_b;
        if (!(s->c.diffusivity > 0))
            api->messages->warning(host, "molecular_diffusivity = 0 makes the transfer velocity of the "
                               "Reynolds-number law zero (K ~ Sc^(-1/2)): no reaeration");
        if (api->fields->field(host, "velocity", &s->velocity) != SLUICE_OK)
            return SLUICE_ERROR;
    }
    if (api->fields->field(host, "reaeration_coefficient", &s->ka) != SLUICE_OK)
        return SLUICE_ERROR;
    if (api->fields->constant(host, "courant_number", &s->courant, 1) < 1) {
        api->messages->error(host, "the reaeration source needs the constant 'courant_number' for its "
                         "time-step limit C / (K a): load time_step");
        return SLUICE_ERROR;
    }
    return SLUICE_OK;
}

static void do_destroy(void *state)
{
    free(state);
}

/* ---------------------------------------------------------- pair term -- */

/* One target loop per combination of the scene's features (no branch on a
 * feature inside the pair loops): walls (the batch holds wall neighbours,
 * brought by another term of the pass: masked out), eddy (nu_t read),
 * two_phase (phase read, air counted, source), slip_dims (0: constant K; 2 or
 * 3: the Reynolds law with the slip velocity). */
static inline void do_pairs(const do_state *s, const sluice_view *v, const sluice_pair_batch *b,
                            const int walls, const int eddy, const int two_phase,
                            const uint32_t slip_dims)
{
    const sluice_real *restrict rho = sluice_real_column(v, s->density, 0);
    const sluice_real *restrict conc = sluice_real_column(v, s->concentration, 0);
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict cj = b->gathered[s->concentration.column];
    const sluice_real *restrict nut = eddy ? sluice_real_column(v, s->eddy_viscosity, 0) : NULL;
    const sluice_real *restrict nutj = eddy ? b->gathered[s->eddy_viscosity.column] : NULL;
    const uint8_t *restrict phase =
        two_phase ? (const uint8_t *)v->columns[s->phase.column] : NULL;
    const sluice_real *vel[3] = {NULL, NULL, NULL}, *velj[3] = {NULL, NULL, NULL};
    for (uint32_t d = 0; d < slip_dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        velj[d] = b->gathered[s->velocity.column + (int32_t)d];
    }
    const sluice_index *restrict nb = b->neighbour;
    const uint8_t *restrict kj = b->neighbour_kind;
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict r = b->distance;
    sluice_real *restrict rate = sluice_real_column(v, s->rate, 0);
    sluice_real *restrict ka_out = two_phase ? sluice_real_column(v, s->ka, 0) : NULL;
    const sluice_real eta2 = s->eta2, dm = s->c.diffusivity, inv_sc = s->inv_schmidt;
    const sluice_real radius = s->radius, cs = s->c.saturation;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        if (two_phase && phase[i] != 0) {
            ka_out[i] = 0; /* air: no oxygen, no rate */
            continue;
        }
        const sluice_real ci = conc[i], rhoi = rho[i];
        const sluice_real di = eddy ? dm + nut[i] * inv_sc : dm;
        sluice_real sum = 0, n_air = 0, n_water = 0, ua[3] = {0, 0, 0};
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_real r2 = r[k] * r[k];
            /* m_j (1/rho_i + 1/rho_j) r^2 F / (r^2 + eta^2), one division */
            sluice_real w = mj[k] * (rhoi + rhoj[k]) * r2 * F[k] / (rhoi * rhoj[k] * (r2 + eta2));
            if (eddy) {
                const sluice_real dj = dm + nutj[k] * inv_sc;
                w *= 2 * di * dj / (di + dj + DBL_MIN);
            }
            sluice_real fluid = 1;
            if (walls)
                fluid = kj[k] != SLUICE_KIND_WALL ? 1 : 0;
            if (two_phase) {
                /* a wall particle's phase is 0: fluid masks it out */
                const sluice_real air = (sluice_real)phase[nb[k]];
                const sluice_real inside = r[k] < radius ? fluid : 0;
                w *= fluid - air;
                n_air += air * inside;
                n_water += (fluid - air) * inside;
                for (uint32_t d = 0; d < slip_dims; d++)
                    ua[d] += air * inside * velj[d][k];
            } else if (walls) {
                w *= fluid;
            }
            sum += w * (ci - cj[k]);
        }
        sluice_real dc = eddy ? sum : dm * sum;
        if (two_phase) {
            sluice_real ka = 0;
            if (n_air > 0) {
                const sluice_real a = n_air * s->bubble_area / ((n_water + 1) * s->rest_volume);
                sluice_real k_transfer = s->c.transfer_velocity;
                if (slip_dims) {
                    sluice_real u2 = 0;
                    for (uint32_t d = 0; d < slip_dims; d++) {
                        const sluice_real u = vel[d][i] - ua[d] / n_air;
                        u2 += u * u;
                    }
                    const sluice_real re = sqrt(u2) * s->bubble / s->c.nu;
                    k_transfer = s->law * pow(re, 1 + s->c.c2);
                }
                ka = k_transfer * a;
            }
            ka_out[i] = ka;
            dc += ka * (cs - ci);
        }
        rate[i] += dc;
    }
}

#define DO_VARIANT(walls, eddy, two_phase, slip)                                               \
    case ((walls) << 4 | (eddy) << 3 | (two_phase) << 2 | (slip)):                            \
        do_pairs(s, v, b, walls, eddy, two_phase, slip);                                     \
        break;
#define DO_VARIANTS(walls, eddy)                                                               \
    DO_VARIANT(walls, eddy, 0, 0)                                                              \
    DO_VARIANT(walls, eddy, 1, 0)                                                              \
    DO_VARIANT(walls, eddy, 1, 2)                                                              \
    DO_VARIANT(walls, eddy, 1, 3)

static void do_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const do_state *s = state;
    const uint32_t walls = (b->neighbour_kinds & SLUICE_KIND_MASK(SLUICE_KIND_WALL)) != 0;
    const uint32_t slip = s->two_phase && s->power_law ? v->dimensions : 0;
    switch (walls << 4 | (uint32_t)s->eddy << 3 | (uint32_t)s->two_phase << 2 | slip) {
        DO_VARIANTS(0, 0)
        DO_VARIANTS(0, 1)
        DO_VARIANTS(1, 0)
        DO_VARIANTS(1, 1)
    default:
        break;
    }
}

/* ------------------------------------------------------ initial values -- */

static sluice_id do_next_id(const sluice_view *v)
{
    sluice_id next = 0;
    for (sluice_index i = 0; i < v->count; i++)
        if (v->id[i] >= next)
            next = v->id[i] + 1;
    return next;
}

static void do_start(void *context, const sluice_view *v, sluice_index begin, sluice_index end)
{
    const do_state *s = context;
    sluice_real *restrict c = sluice_real_column(v, s->concentration, 0);
    for (sluice_index i = begin; i < end; i++)
        c[i] = v->kind[i] == SLUICE_KIND_WALL ? 0 : s->c.initial;
}

static int do_initialise(void *state, sluice_host *host)
{
    do_state *s = state;
    const sluice_view *v = s->api->particles->view(host);
    s->api->particles->parallel_for(host, v->count, do_start, s);
    s->next_id = do_next_id(v);
    s->seen = (uint64_t)v->count + s->api->particles->removed_count(host);
    sluice_ranks ranks;
    if (s->api->ranks->ranks(host, &ranks) != SLUICE_OK)
        return SLUICE_ERROR;
    s->ranks = ranks.count;
    return SLUICE_OK;
}

/* Particles created since the last scan (inlets, in their after_step hooks)
 * get the initial concentration (air 0), and, at the first call (the phase is
 * written at initialise, possibly after this plugin's), air particles get 0.
 * A particle's rate is zero in air, so it stays 0 there. Called from prepare
 * (before every evaluation: no pass ever reads an unset value) and from
 * after_step (so that writers and gauges later in the scene see the newest
 * inflow particles' value). */
static int do_scan(do_state *s, sluice_host *host)
{
    const sluice_view *v = s->api->particles->view(host);
    const uint64_t total = (uint64_t)v->count + s->api->particles->removed_count(host);
    sluice_real *restrict c = sluice_real_column(v, s->concentration, 0);
    const uint8_t *phase = s->two_phase ? (const uint8_t *)v->columns[s->phase.column] : NULL;
    if (total != s->seen || s->ranks > 1) {
        const sluice_id first = s->next_id;
        for (sluice_index i = 0; i < v->count; i++)
            if (v->id[i] >= first) {
                c[i] = v->kind[i] == SLUICE_KIND_WALL || (phase && phase[i]) ? 0 : s->c.initial;
                if (v->id[i] >= s->next_id)
                    s->next_id = v->id[i] + 1;
            }
        s->seen = total;
    }
    if (s->ranks > 1) { /* collective: every rank scans at the same points */
        double next = (double)s->next_id; /* ids below 2^53: exact */
        if (s->api->ranks->reduce(host, &next, 1, SLUICE_REDUCE_MAX) != SLUICE_OK)
            return SLUICE_ERROR;
        s->next_id = (sluice_id)next;
    }
    if (!s->started) {
        if (phase)
            for (sluice_index i = 0; i < v->count; i++)
                if (phase[i])
                    c[i] = 0;
        s->started = 1;
    }
    return SLUICE_OK;
}

static int do_prepare(void *state, sluice_host *host)
{
    return do_scan(state, host);
}

static int do_after_step(void *state, sluice_host *host)
{
    return do_scan(state, host);
}

/* Checkpoints: the first id not yet given its initial value (a particle
 * removed before a checkpoint may have held the largest id). The count of
 * particles seen is the checkpoint's count + removed; its air particles hold
 * 0 already. */
static int do_save_state(void *state, sluice_host *host)
{
    const do_state *s = state;
    const uint64_t next = s->next_id;
    return s->api->state->state_write(host, "next_id", SLUICE_STATE_UINT64, 1, &next);
}

static int do_load_state(void *state, sluice_host *host)
{
    do_state *s = state;
    uint64_t next;
    if (s->api->state->state_read(host, "next_id", SLUICE_STATE_UINT64, 1, &next) != SLUICE_OK)
        return SLUICE_ERROR;
    s->next_id = (sluice_id)next;
    const sluice_view *v = s->api->particles->view(host);
    s->seen = (uint64_t)v->count + s->api->particles->removed_count(host);
    s->started = 1;
    return SLUICE_OK;
}

/* ----------------------------------------------------------- time step -- */

static sluice_real do_time_step_limit(void *state, const sluice_view *v, sluice_index begin,
                                      sluice_index end)
{
    const do_state *s = state;
    const sluice_real *nut = s->eddy ? sluice_real_column(v, s->eddy_viscosity, 0) : NULL;
    const sluice_real *ka = s->two_phase ? sluice_real_column(v, s->ka, 0) : NULL;
    sluice_real nu_max = 0, ka_max = 0;
    int fluid = 0;
    for (sluice_index i = begin; i < end; i++) {
        if (v->kind[i] != SLUICE_KIND_FLUID)
            continue;
        fluid = 1;
        if (nut && (nut[i] > nu_max || nut[i] != nut[i]))
            nu_max = nut[i] != nut[i] ? (sluice_real)INFINITY : nut[i];
        if (ka && (ka[i] > ka_max || ka[i] != ka[i]))
            ka_max = ka[i] != ka[i] ? (sluice_real)INFINITY : ka[i];
    }
    if (!fluid)
        return (sluice_real)INFINITY;
    sluice_real limit = (sluice_real)INFINITY;
    const sluice_real d_max = s->c.diffusivity + nu_max * s->inv_schmidt;
    if (d_max > 0)
        limit = (sluice_real)0.125 * s->h * s->h / d_max;
    if (ka_max > 0 && s->courant / ka_max < limit)
        limit = s->courant / ka_max;
    return limit;
}

static const sluice_component components[] = {{
    .name = "dissolved_oxygen",
    .summary = "dissolved-oxygen concentration of the water: turbulent diffusion and reaeration "
               "K a (C_s - C) next to air particles",
    .reference = "seed 001 (Wan et al. 2017, Water 9:565), eqs. 13-20; Cleary & Monaghan (1999); "
                 "Aristodemo et al. (2010); Banerjee, Rhodes & Scott (1968)",
    .dimensions = SLUICE_DIMS_ALL,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(do_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .create = do_create,
    .destroy = do_destroy,
    .bind = do_bind,
    .initialise = do_initialise,
    .pair = do_pair,
    .time_step_limit = do_time_step_limit,
    .after_step = do_after_step,
    .prepare = do_prepare,
    .save_state = do_save_state,
    .load_state = do_load_state,
}};

SLUICE_DEFINE_LIBRARY("dissolved_oxygen", "1.1.0",
                      "dissolved oxygen: diffusion and air-water reaeration (seed 001)",
                      SLUICE_DIMS_ALL, components)
