/* Vorticity omega = curl v of the fluid particles, for output (field
 * `vorticity`: 1 component omega_z = dv/dx - du/dy in 2D, 3 in 3D, s^-1).
 *
 * SPH curl with the difference form (exact for a constant velocity field,
 * zero to round-off for a uniform flow):
 *
 *   omega_i = sum_j V_j grad^_i W_ij x (v_j - v_i),   V_j = m_j / rho_j,
 *
 * over fluid and wall neighbours (wall particles carry their own velocity:
 * zero for fixed dynamic-boundary walls, the no-slip shear at the bed),
 * i.e. (curl v)_a = eps_abc d v_c / d x_b with d v_c / d x_b =
 * sum_j V_j (v_j - v_i)_c (grad^_i W_ij)_b, the velocity gradient of
 * velocity_gradient.c.
 *  - renormalise false: grad^_i W_ij = r_ij F_ij. For a linear field v = A x,
 *    d v_c / d x_b = (A M_i)_cb with M_i = -sum_j V_j F_ij r_ij (x) r_ij, the
 *    kernel's second moment over the actual neighbours: inside a regular
 *    lattice M = m I (cubic symmetry), m = 1 up to the lattice-sum error of
 *    the kernel (an h/dx property), so a rigid rotation v = Omega x r gives
 *    omega = 2 m Omega; near a free surface M loses its outer half and omega
 *    is biased low there.
 *  - renormalise true: (grad^_i W_ij)_b = sum_c L_i,bc (r_ij F_ij)_c with L_i
 *    = M_i^-1 from the field kernel_correction (plugin kernel_correction):
 *    exact for every linear velocity field wherever L_i = M_i^-1 (also at the
 *    free surface); one evaluation (api->evaluation->evaluate) before each computation
 *    brings L to the current positions.
 *
 * Cost: nothing per step. The pair callback is on demand
 * (SLUICE_COMPONENT_ON_DEMAND): the after-step hook runs it (api->evaluation->pair_pass)
 * at t = 0, interval, 2 interval, ... (the core ends steps on these times),
 * and in finish() on the final state when that was not computed yet (in a
 * failed run, when the final state has no valid neighbour list the
 * vorticity is set to nan rather than left stale).
 *
 * Order with the writers: hooks run in scene order, so a writer's after-step
 * hook listed before this plugin would write the vorticity of the previous
 * output time. bind() therefore refuses a scene that lists the `hdf5` writer
 * before `vorticity`; with `interval` equal to (or dividing) the writer's
 * interval every snapshot then holds the vorticity of its own state. Gauges
 * that interpolate the field (point_gauge fields: vorticity) likewise go after
 * this plugin. Wall particles keep zero. */
#include <math.h>
#include <string.h>

#include <sluice/plugin_util.h>

typedef struct vort_config {
    sluice_real interval;
    int renormalise;
} vort_config;

typedef struct vort_state {
    const sluice_api *api;
    uint32_t dims, components;
    int renormalise;
    sluice_schedule schedule; /* the next computation */
    int computed;          /* the vorticity of (computed_step, computed_time) is current */
    int64_t computed_step;
    double computed_time;
    sluice_field velocity, mass, density, vorticity, correction;
} vort_state;

static const sluice_param_spec params[] = {
    {"interval", SLUICE_PARAM_REAL, offsetof(vort_config, interval), "0.05", 1e-6, 0,
     SLUICE_PARAM_HAS_MIN, "s",
     "time between computations: the hdf5 writer's interval (the default is its default) or a "
     "divisor of it",
     NULL, 0},
    {"renormalise", SLUICE_PARAM_BOOL, offsetof(vort_config, renormalise), "false", 0, 0, 0,
     NULL,
     "use the renormalised kernel gradient L_i grad_i W_ij (reads kernel_correction, written by "
     "the kernel_correction plugin; one evaluation per computation): exact for linear velocity "
     "fields, also at free surfaces",
     NULL, 0},
};

static const sluice_field_spec fields[] = {
    SLUICE_SPEC_VELOCITY(SLUICE_READ | SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_MASS(SLUICE_READ_NEIGHBOUR),
    SLUICE_SPEC_DENSITY(SLUICE_READ_NEIGHBOUR),
};

static int vort_create(const sluice_api *api, sluice_host *host, const void *config, void **state)
{
    const vort_config *c = config;
    vort_state *s = sluice_util_state(api, host, sizeof *s);
    if (!s)
        return SLUICE_ERROR;
    s->api = api;
    s->schedule = sluice_schedule_every(c->interval);
    s->renormalise = c->renormalise;
    if (sluice_util_dimensions(api, host, &s->dims) != SLUICE_OK) {
        free(s);
        return SLUICE_ERROR;
    }
    s->components = s->dims == 3 ? 3 : 1;
    const sluice_field_spec vorticity = {
        "vorticity", SLUICE_TYPE_REAL, s->components, "s^-1", SLUICE_WRITE, SLUICE_FIELD_OUTPUT,
        NULL, 0,
        s->dims == 3 ? "vorticity curl v (x, y, z) of fluid particles at the last computation"
                     : "vorticity dv/dx - du/dy of fluid particles at the last computation"};
    const sluice_field_spec correction = SLUICE_SPEC_KERNEL_CORRECTION(s->dims, SLUICE_READ);
    if (api->fields->declare_field(host, &vorticity) != SLUICE_OK ||
        (s->renormalise && api->fields->declare_field(host, &correction) != SLUICE_OK)) {
        free(s);
        return SLUICE_ERROR;
    }
    *state = s;
    return SLUICE_OK;
}

static int vort_bind(void *state, sluice_host *host)
{
    vort_state *s = state;
    const sluice_api *api = s->api;
    const sluice_field_binding fields[] = {
        {"velocity", &s->velocity}, {"mass", &s->mass}, {"density", &s->density},
        {"vorticity", &s->vorticity}};
    if (sluice_util_bind(api, host, fields, SLUICE_COUNT(fields)) != SLUICE_OK)
        return SLUICE_ERROR;
    if (s->renormalise && api->fields->field(host, "kernel_correction", &s->correction) != SLUICE_OK)
        return SLUICE_ERROR;
    /* hooks run in scene order: the writer must come after this plugin */
    const uint32_t count = api->output->plugin_count(host);
    int64_t writer = -1;
    for (uint32_t k = 0; k < count; k++) {
        sluice_plugin_info info;
        if (api->output->plugin(host, k, &info) != SLUICE_OK || !info.component)
            continue;
        if (strcmp(info.component, "hdf5") == 0 && writer < 0)
            writer = k;
        if (strcmp(info.component, "vorticity") == 0) {
            if (writer >= 0) {
                api->messages->error(host, "is listed after the writer 'hdf5' in the scene's plugins; "
                                 "after-step hooks run in scene order, so 'hdf5' would write "
                                 "the vorticity of the previous output time: list 'vorticity' "
                                 "before 'hdf5'");
                return SLUICE_ERROR;
            }
            break;
        }
    }
    return SLUICE_OK;
}

static void vort_destroy(void *state)
{
    free(state);
}

/* --------------------------------------------------------- pair callback -- */

/* One loop per (dims, renormalise): no test of either inside. */
static inline void vort_pairs(const vort_state *s, const sluice_view *v,
                              const sluice_pair_batch *b, const uint32_t dims,
                              const int renormalise)
{
    const sluice_real *vel[3], *vj[3];
    for (uint32_t d = 0; d < dims; d++) {
        vel[d] = sluice_real_column(v, s->velocity, d);
        vj[d] = b->gathered[s->velocity.column + (int32_t)d];
    }
    const sluice_real *restrict vxj = vj[0], *restrict vyj = vj[1];
    const sluice_real *restrict vzj = dims == 3 ? vj[2] : vj[1];
    const sluice_real *restrict mj = b->gathered[s->mass.column];
    const sluice_real *restrict rhoj = b->gathered[s->density.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    sluice_real *out[3];
    for (uint32_t c = 0; c < s->components; c++)
        out[c] = sluice_real_column(v, s->vorticity, c);
    const sluice_real *L[9];
    for (uint32_t c = 0; c < dims * dims; c++)
        L[c] = renormalise ? sluice_real_column(v, s->correction, c) : NULL;
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vxi = vel[0][i], vyi = vel[1][i], vzi = dims == 3 ? vel[2][i] : 0;
        if (!renormalise) {
            /* omega = sum_j V_j F_ij r_ij x (v_j - v_i) */
            sluice_real ox = 0, oy = 0, oz = 0;
            for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
                const sluice_real w = mj[k] / rhoj[k] * F[k];
                const sluice_real du = vxj[k] - vxi, dv = vyj[k] - vyi;
                oz += w * (rx[k] * dv - ry[k] * du);
                if (dims == 3) {
                    const sluice_real dw = vzj[k] - vzi;
                    ox += w * (ry[k] * dw - rz[k] * dv);
                    oy += w * (rz[k] * du - rx[k] * dw);
                }
            }
            if (dims == 3) {
                out[0][i] = ox;
                out[1][i] = oy;
                out[2][i] = oz;
            } else {
                out[0][i] = oz;
            }
            continue;
        }
        /* g_cb = sum_j V_j (v_j - v_i)_c (r_ij F_ij)_b, then
         * d v_c / d x_b = sum_e L_be g_ce */
        const sluice_real vi[3] = {vxi, vyi, vzi};
        sluice_real g[9];
        sluice_velocity_gradient_sum(b, t, dims, s->velocity, s->mass, s->density, vi, g);
        sluice_real G[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}; /* G[c][b] = d v_c / d x_b */
        for (uint32_t c = 0; c < dims; c++)
            for (uint32_t bb = 0; bb < dims; bb++) {
                sluice_real value = 0;
                for (uint32_t e = 0; e < dims; e++)
                    value += L[bb * dims + e][i] * g[3 * c + e];
                G[c][bb] = value;
            }
        if (dims == 3) {
            out[0][i] = G[2][1] - G[1][2];
            out[1][i] = G[0][2] - G[2][0];
            out[2][i] = G[1][0] - G[0][1];
        } else {
            out[0][i] = G[1][0] - G[0][1];
        }
    }
}

static void vort_pair(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const vort_state *s = state;
    if (s->renormalise) {
        if (v->dimensions == 3)
            vort_pairs(s, v, b, 3, 1);
        else
            vort_pairs(s, v, b, 2, 1);
    } else {
        if (v->dimensions == 3)
            vort_pairs(s, v, b, 3, 0);
        else
            vort_pairs(s, v, b, 2, 0);
    }
}

/* -------------------------------------------------------------- hooks -- */

static int compute(vort_state *s, sluice_host *host)
{
    const sluice_api *api = s->api;
    /* L_i of the current positions (written during the evaluation) */
    if (s->renormalise && api->evaluation->evaluate(host, api->particles->view(host)->time, 0) != SLUICE_OK)
        return SLUICE_ERROR;
    if (api->evaluation->pair_pass(host) != SLUICE_OK)
        return SLUICE_ERROR;
    const sluice_view *v = api->particles->view(host);
    s->computed = 1;
    s->computed_step = v->step;
    s->computed_time = v->time;
    return SLUICE_OK;
}

static int vort_after_step(void *state, sluice_host *host)
{
    vort_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (!sluice_schedule_due(&s->schedule, v->time))
        return SLUICE_OK;
    if (compute(s, host) != SLUICE_OK)
        return SLUICE_ERROR;
    v = api->particles->view(host);
    sluice_schedule_advance(&s->schedule, api, host, v->time);
    return SLUICE_OK;
}

/* The final state, for the writers' final snapshot (their finish() runs
 * after this one, in scene order). */
static int vort_finish(void *state, sluice_host *host, int status)
{
    vort_state *s = state;
    const sluice_api *api = s->api;
    const sluice_view *v = api->particles->view(host);
    if (s->computed && s->computed_step == v->step && s->computed_time == v->time)
        return SLUICE_OK;
    if (status != SLUICE_FINISH_FAILED)
        return compute(s, host);
    /* a failed run: its state may have no valid neighbour list */
    if (compute(s, host) == SLUICE_OK)
        return SLUICE_OK;
    v = api->particles->view(host);
    for (uint32_t c = 0; c < s->components; c++) {
        sluice_real *omega = sluice_real_column(v, s->vorticity, c);
        for (sluice_index i = 0; i < v->count; i++)
            omega[i] = v->kind[i] == SLUICE_KIND_WALL ? 0 : (sluice_real)NAN;
    }
    api->messages->warning(host, "the final state of the failed run has no vorticity (nan)");
    return SLUICE_OK;
}

/* Checkpoints: the schedule and which state the vorticity field holds. */
static int vort_save(void *state, sluice_host *host)
{
    const vort_state *s = state;
    const sluice_api *api = s->api;
    if (sluice_schedule_save(&s->schedule, api, host, "scheduled") != SLUICE_OK ||
        sluice_util_save_int(api, host, "computed", s->computed) != SLUICE_OK ||
        sluice_util_save_int(api, host, "computed_step", s->computed_step) != SLUICE_OK ||
        sluice_util_save_double(api, host, "computed_time", s->computed_time) != SLUICE_OK)
        return SLUICE_ERROR;
    return SLUICE_OK;
}

static int vort_load(void *state, sluice_host *host)
{
    vort_state *s = state;
    const sluice_api *api = s->api;
    int64_t computed = 0;
    if (sluice_schedule_load(&s->schedule, api, host, "scheduled") != SLUICE_OK ||
        sluice_util_load_int(api, host, "computed", &computed) != SLUICE_OK ||
        sluice_util_load_int(api, host, "computed_step", &s->computed_step) != SLUICE_OK ||
        sluice_util_load_double(api, host, "computed_time", &s->computed_time) != SLUICE_OK)
        return SLUICE_ERROR;
    s->computed = computed != 0;
    return SLUICE_OK;
}

static const sluice_component components[] = {{
    .name = "vorticity",
    .summary = "vorticity curl v of the fluid (SPH curl, optionally renormalised), computed on "
               "demand at an output interval",
    .reference = "SPH difference-form curl (Monaghan 1992, 2005); Bonet & Lok (1999) "
                 "renormalisation",
    .dimensions = SLUICE_DIMS_ALL,
    .flags = SLUICE_COMPONENT_ON_DEMAND,
    .params = params,
    .param_count = SLUICE_COUNT(params),
    .config_size = sizeof(vort_config),
    .fields = fields,
    .field_count = SLUICE_COUNT(fields),
    .target_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID),
    .neighbour_kinds = SLUICE_KIND_MASK(SLUICE_KIND_FLUID) | SLUICE_KIND_MASK(SLUICE_KIND_WALL),
    .create = vort_create,
    .destroy = vort_destroy,
    .bind = vort_bind,
    .pair = vort_pair,
    .after_step = vort_after_step,
    .save_state = vort_save,
    .load_state = vort_load,
    .finish = vort_finish,
}};

SLUICE_DEFINE_LIBRARY("vorticity", "1.0.0", "SPH vorticity for output", SLUICE_DIMS_ALL,
                      components)
