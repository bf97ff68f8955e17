/* sluice-bench: speed and memory figures of the core (docs/performance.md).
 *
 *   sluice-bench ratio SCENE [--steps N] [--repeat N] [--warmup-time T] [--set k=v ...]
 *       Compares the plugin path (pair batches handed to each plugin) with a
 *       hand-fused loop of the same physics compiled here (Wendland C2, Tait
 *       gamma 7, continuity, delta-SPH, symmetric pressure gradient, Monaghan
 *       viscosity, gravity, DBC clamp, symplectic), on the same particle
 *       store and neighbour list. First both run 50 steps from t = 0 and
 *       their positions are compared (they must agree to round-off). Then the
 *       scene runs to T (default 0.1 s, a representative state of the flow:
 *       the cost of the viscosity depends on how many pairs approach) and
 *       blocks of N plugin-path steps and N fused steps alternate on the
 *       same evolving state, R times. Prints one CSV line with the medians.
 *   sluice-bench memory SCENE [--steps N] [--set k=v ...]
 *       Loads the scene, runs N steps, prints particles, peak RSS and bytes
 *       per particle (peak RSS / particles).
 *
 * The hand-fused loop supports exactly the dam-break physics; the ratio mode
 * refuses scenes with other plugins. */
#define _GNU_SOURCE
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "diag.h"
#include "sim.h"
#include "sim_internal.h"

typedef struct options {
    const char *mode, *scene;
    const char **sets;
    size_t set_count;
    int steps, warmup, repeat;
    double warmup_time;
} options;

static sluice_sim *load(const options *o)
{
    sluice_diag *diag = sluice_diag_create();
    sluice_load_options lo = {.overrides = o->sets, .override_count = o->set_count};
    sluice_sim *sim = sluice_sim_load(o->scene, &lo, diag);
    sluice_diag_print(diag, stderr);
    sluice_diag_destroy(diag);
    return sim;
}

/* ------------------------------------------------------ fused physics -- */

static inline int64_t sluice_bits(sluice_real non_negative)
{
    int64_t b;
    memcpy(&b, &non_negative, sizeof b);
    return b;
}

static inline sluice_real sluice_from_bits(int64_t b)
{
    sluice_real x;
    memcpy(&x, &b, sizeof x);
    return x;
}

typedef struct fused {
    sluice_sim *sim;
    sluice_real *x, *y, *vx, *vy, *rho, *mass, *p, *c, *ax, *ay, *drho, *mu;
    sluice_real *vx0, *vy0, *rho0s;
    sluice_real h, c0, rho0, B, alpha, g[2], courant, eta2, wendland_a, wendland_b;
    sluice_real delta_coefficient, hydro[2]; /* delta-SPH (0: not loaded) */
    int32_t col_vx, col_vy, col_m, col_rho, col_p, col_c; /* column numbers */
    int variant; /* 0 scalar, 1 flat vectorised, 2 batched */
    double time;
} fused;

static sluice_real *column(sluice_sim *sim, const char *name, uint32_t component)
{
    sluice_field f;
    if (sluice_sim_field(sim, name, &f) != SLUICE_OK) {
        fprintf(stderr, "sluice-bench: the scene has no field '%s'\n", name);
        exit(2);
    }
    return sim->particles.columns[f.column + (int32_t)component];
}

static int32_t column_number(sluice_sim *sim, const char *name, uint32_t component)
{
    sluice_field field;
    sluice_sim_field(sim, name, &field);
    return field.column + (int32_t)component;
}

static void fused_bind(fused *f)
{
    sluice_sim *s = f->sim;
    f->col_vx = column_number(s, "velocity", 0);
    f->col_vy = column_number(s, "velocity", 1);
    f->col_m = column_number(s, "mass", 0);
    f->col_rho = column_number(s, "density", 0);
    f->col_p = column_number(s, "pressure", 0);
    f->col_c = column_number(s, "sound_speed", 0);
    f->x = column(s, "position", 0);
    f->y = column(s, "position", 1);
    f->vx = column(s, "velocity", 0);
    f->vy = column(s, "velocity", 1);
    f->rho = column(s, "density", 0);
    f->mass = column(s, "mass", 0);
    f->p = column(s, "pressure", 0);
    f->c = column(s, "sound_speed", 0);
    f->ax = column(s, "acceleration", 0);
    f->ay = column(s, "acceleration", 1);
    f->drho = column(s, "density_rate", 0);
    f->mu = column(s, "viscous_mu_max", 0);
    f->vx0 = column(s, "velocity_previous", 0);
    f->vy0 = column(s, "velocity_previous", 1);
    f->rho0s = column(s, "density_previous", 0);
}

/* Common start of every fused evaluation: rebuild the neighbour list when
 * needed (rebinding the columns after the reordering), then the equation of
 * state. */
static void fused_prepare(fused *f)
{
    sluice_sim *s = f->sim;
    sluice_sim_refresh_view(s);
    if (sluice_grid_needs_rebuild(&s->grid, &s->view)) {
        sluice_index bad;
        if (sluice_grid_build(&s->grid, &s->particles, (uint32_t)s->position.column, &bad) != 0) {
            fprintf(stderr, "sluice-bench: neighbour build failed\n");
            exit(4);
        }
        fused_bind(f);
        sluice_sim_refresh_view(s);
    }
    const sluice_index n = s->particles.count;
    const sluice_real i0 = 1 / f->rho0, B = f->B, c0 = f->c0;
    sluice_real *restrict rho = f->rho, *restrict p = f->p, *restrict c = f->c;
#pragma omp parallel for schedule(static)
    for (sluice_index i = 0; i < n; i++) {
        sluice_real q = rho[i] * i0, q2 = q * q, q3 = q2 * q;
        p[i] = B * (q3 * q3 * q - 1);
        c[i] = c0 * q3;
    }
}

static void fused_evaluate_scalar(fused *f)
{
    fused_prepare(f);
    sluice_sim *s = f->sim;
    const sluice_index n = s->particles.count;
    const uint8_t *kind = s->view.kind;
    sluice_real *restrict rho = f->rho, *restrict p = f->p, *restrict c = f->c;
    const sluice_index *list = s->grid.list, *begin = s->grid.list_begin;
    const sluice_real *restrict x = f->x, *restrict y = f->y, *restrict vx = f->vx,
                                *restrict vy = f->vy, *restrict m = f->mass;
    sluice_real *restrict ax = f->ax, *restrict ay = f->ay, *restrict drho = f->drho,
                          *restrict mu_max = f->mu;
    const sluice_real support2 = s->support * s->support, ih = 1 / f->h, h = f->h;
    const sluice_real wb = f->wendland_b, eta2 = f->eta2, alpha = f->alpha;
    const sluice_real gx = f->g[0], gy = f->g[1];
    const sluice_real dc = f->delta_coefficient, hx = f->hydro[0], hy = f->hydro[1];
#pragma omp parallel for schedule(dynamic, 128)
    for (sluice_index i = 0; i < n; i++) {
        const int fluid = kind[i] == SLUICE_KIND_FLUID;
        const sluice_real xi = x[i], yi = y[i], vxi = vx[i], vyi = vy[i];
        const sluice_real pi = p[i] / (rho[i] * rho[i]), ci = c[i], rhoi = rho[i];
        sluice_real sx = 0, sy = 0, sr = 0, sd = 0, worst = 0;
        for (sluice_index k = begin[i]; k < begin[i + 1]; k++) {
            const sluice_index j = list[k];
            const sluice_real dx = xi - x[j], dy = yi - y[j];
            const sluice_real r2 = dx * dx + dy * dy;
            if (r2 >= support2)
                continue;
            const sluice_real r = sqrt(r2);
            sluice_real t = 1 - (sluice_real)0.5 * r * ih;
            const sluice_real F = wb * t * t * t;
            const sluice_real dvx = vxi - vx[j], dvy = vyi - vy[j];
            const sluice_real dot = dvx * dx + dvy * dy;
            sr += m[j] * dot * F;
            if (!fluid)
                continue;
            if (kind[j] == SLUICE_KIND_FLUID) /* delta-SPH, fluid pairs */
                sd += (rho[j] - rhoi - (hx * dx + hy * dy)) * r2 * F / (r2 + eta2) * m[j] / rho[j];
            const sluice_real mu = h * dot / (r2 + eta2);
            const sluice_real amu = mu < 0 ? -mu : mu;
            worst = amu > worst ? amu : worst;
            const sluice_real visc =
                dot < 0 ? -alpha * (sluice_real)0.5 * (ci + c[j]) * mu /
                              ((sluice_real)0.5 * (rhoi + rho[j]))
                        : 0;
            const sluice_real coef = m[j] * (pi + p[j] / (rho[j] * rho[j]) + visc) * F;
            sx += coef * dx;
            sy += coef * dy;
        }
        drho[i] = sr - dc * sd;
        ax[i] = fluid ? gx - sx : 0;
        ay[i] = fluid ? gy - sy : 0;
        mu_max[i] = fluid ? worst : 0;
    }
}



static void fused_evaluate_flat(fused *f)
{
    fused_prepare(f);
    sluice_sim *s = f->sim;
    const sluice_index n = s->particles.count;
    const uint8_t *kind = s->view.kind;
    sluice_real *restrict rho = f->rho, *restrict p = f->p, *restrict c = f->c;
    const sluice_index *list = s->grid.list, *begin = s->grid.list_begin;
    const sluice_real *restrict x = f->x, *restrict y = f->y, *restrict vx = f->vx,
                                *restrict vy = f->vy, *restrict m = f->mass;
    sluice_real *restrict ax = f->ax, *restrict ay = f->ay, *restrict drho = f->drho,
                          *restrict mu_max = f->mu;
    const sluice_real support2 = s->support * s->support, ih = 1 / f->h, h = f->h;
    const sluice_real wb = f->wendland_b, eta2 = f->eta2, alpha = f->alpha;
    const sluice_real gx = f->g[0], gy = f->g[1];
    const sluice_real dc = f->delta_coefficient, hx = f->hydro[0], hy = f->hydro[1];
#pragma omp parallel for schedule(dynamic, 128)
    for (sluice_index i = 0; i < n; i++) {
        const int fluid = kind[i] == SLUICE_KIND_FLUID;
        const sluice_real xi = x[i], yi = y[i], vxi = vx[i], vyi = vy[i];
        const sluice_real pi = p[i] / (rho[i] * rho[i]), ci = c[i], rhoi = rho[i];
        const sluice_real on = fluid ? 1 : 0; /* momentum and diffusion act on fluid only */
        sluice_real sx = 0, sy = 0, sr = 0, sd = 0;
        int64_t worst = 0;
        /* branch-free so that the compiler vectorises it over the list (gathers) */
        for (sluice_index k = begin[i]; k < begin[i + 1]; k++) {
            const sluice_index j = list[k];
            const sluice_real dx = xi - x[j], dy = yi - y[j];
            const sluice_real r2 = dx * dx + dy * dy;
            const sluice_real inside = r2 < support2 ? 1 : 0;
            const sluice_real r = sqrt(r2);
            sluice_real t = 1 - (sluice_real)0.5 * r * ih;
            t = t > 0 ? t : 0;
            const sluice_real F = inside * wb * t * t * t;
            const sluice_real dvx = vxi - vx[j], dvy = vyi - vy[j];
            const sluice_real dot = dvx * dx + dvy * dy;
            sr += m[j] * dot * F;
            const sluice_real rhoj = rho[j];
            const sluice_real inv = 1 / (r2 + eta2);
            const sluice_real fluid_j = kind[j] == SLUICE_KIND_FLUID ? 1 : 0;
            sd += fluid_j * (rhoj - rhoi - (hx * dx + hy * dy)) * r2 * F * inv * m[j] / rhoj;
            const sluice_real mu = h * dot * inv;
            const sluice_real amu = mu < 0 ? -mu : mu;
            const int64_t bits = inside > 0 ? sluice_bits(amu) : 0;
            worst = bits > worst ? bits : worst;
            const sluice_real visc =
                dot < 0 ? -alpha * (ci + c[j]) * mu / (rhoi + rhoj) : 0; /* cbar/rhobar */
            const sluice_real coef = m[j] * (pi + p[j] / (rhoj * rhoj) + visc) * F;
            sx += coef * dx;
            sy += coef * dy;
        }
        drho[i] = sr - on * dc * sd;
        ax[i] = fluid ? gx - sx : 0;
        ay[i] = fluid ? gy - sy : 0;
        mu_max[i] = fluid ? sluice_from_bits(worst) : 0;
    }
}

/* The same physics as one hand-fused pair term fed by the core's own batch
 * pipeline (Verlet list filter, kernel, gathered neighbour values): what the
 * plugin path would be if its four pair terms were written as one. */
static void fused_term(void *state, const sluice_view *v, const sluice_pair_batch *b)
{
    const fused *f = state;
    if (b->target_count == 0)
        return;
    const int fluid = v->kind[b->target[0]] == SLUICE_KIND_FLUID; /* batches hold one kind */
    const sluice_real *restrict vxj = b->gathered[f->col_vx], *restrict vyj = b->gathered[f->col_vy];
    const sluice_real *restrict mj = b->gathered[f->col_m];
    const sluice_real *restrict F = b->kernel_gradient, *restrict r = b->distance;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const uint8_t *restrict kj = b->neighbour_kind;
    const sluice_real h = f->h, eta2 = f->eta2, alpha = f->alpha, dc = f->delta_coefficient;
    const sluice_real hx = f->hydro[0], hy = f->hydro[1];
    for (sluice_index t = 0; t < b->target_count; t++) {
        const sluice_index i = b->target[t];
        const sluice_real vxi = f->vx[i], vyi = f->vy[i];
        sluice_real sr = 0;
        if (!fluid) {
            for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++)
                sr += mj[k] * ((vxi - vxj[k]) * rx[k] + (vyi - vyj[k]) * ry[k]) * F[k];
            f->drho[i] = sr;
            f->ax[i] = f->ay[i] = 0;
            f->mu[i] = 0;
            continue;
        }
        const sluice_real *restrict rhoj = b->gathered[f->col_rho];
        const sluice_real *restrict pj = b->gathered[f->col_p], *restrict cj = b->gathered[f->col_c];
        const sluice_real rhoi = f->rho[i], pi = f->p[i] / (rhoi * rhoi), ci = f->c[i];
        sluice_real sx = 0, sy = 0, sd = 0;
        int64_t worst = 0;
        for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
            const sluice_real dot = (vxi - vxj[k]) * rx[k] + (vyi - vyj[k]) * ry[k];
            const sluice_real r2 = r[k] * r[k], inv = 1 / (r2 + eta2);
            sr += mj[k] * dot * F[k];
            const sluice_real diffusion =
                (rhoj[k] - rhoi - (hx * rx[k] + hy * ry[k])) * r2 * F[k] * inv * mj[k] / rhoj[k];
            sd += kj[k] == SLUICE_KIND_FLUID ? diffusion : 0;
            const sluice_real mu = h * dot * inv;
            const int64_t bits = sluice_bits(mu < 0 ? -mu : mu);
            worst = bits > worst ? bits : worst;
            const sluice_real visc = dot < 0 ? -alpha * (ci + cj[k]) * mu / (rhoi + rhoj[k]) : 0;
            const sluice_real coef = mj[k] * (pi + pj[k] / (rhoj[k] * rhoj[k]) + visc) * F[k];
            sx += coef * rx[k];
            sy += coef * ry[k];
        }
        f->drho[i] = sr - dc * sd;
        f->ax[i] = f->g[0] - sx;
        f->ay[i] = f->g[1] - sy;
        f->mu[i] = sluice_from_bits(worst);
    }
}

static void fused_evaluate_batched(fused *f)
{
    fused_prepare(f);
    sluice_sim *s = f->sim;
    static const sluice_component term = {.name = "fused", .pair = fused_term};
    sluice_pair_term t = {&term, f, SLUICE_KINDS_ALL};
    uint32_t fluid_columns[6] = {(uint32_t)f->col_vx, (uint32_t)f->col_vy, (uint32_t)f->col_m,
                                 (uint32_t)f->col_rho, (uint32_t)f->col_p, (uint32_t)f->col_c};
    uint32_t wall_columns[3] = {(uint32_t)f->col_vx, (uint32_t)f->col_vy, (uint32_t)f->col_m};
    sluice_pair_pass pass;
    memset(&pass, 0, sizeof pass);
    pass.term_count = 1;
    pass.terms = &t;
    pass.neighbour_mask[SLUICE_KIND_FLUID] = pass.neighbour_mask[SLUICE_KIND_WALL] =
        SLUICE_KINDS_ALL;
    pass.gathered_count[SLUICE_KIND_FLUID] = 6;
    pass.gathered_columns[SLUICE_KIND_FLUID] = fluid_columns;
    pass.gathered_count[SLUICE_KIND_WALL] = 3;
    pass.gathered_columns[SLUICE_KIND_WALL] = wall_columns;
    pass.gathered_max = 6;
    if (sluice_pair_pass_run(&s->engine, &pass, &s->grid, &s->view) != 0) {
        fprintf(stderr, "sluice-bench: out of memory\n");
        exit(4);
    }
}

static void fused_evaluate(fused *f)
{
    switch (f->variant) {
    case 0: fused_evaluate_scalar(f); break;
    case 1: fused_evaluate_flat(f); break;
    default: fused_evaluate_batched(f); break;
    }
}

static double fused_time_step(fused *f)
{
    sluice_sim *s = f->sim;
    const sluice_index n = s->particles.count;
    const uint8_t *kind = s->view.kind;
    double a2max = 0, speed = 0, visc = 0;
#pragma omp parallel for schedule(static) reduction(max : a2max, speed, visc)
    for (sluice_index i = 0; i < n; i++) {
        if (kind[i] != SLUICE_KIND_FLUID)
            continue;
        double a2 = f->ax[i] * f->ax[i] + f->ay[i] * f->ay[i];
        double v = f->c[i] + sqrt(f->vx[i] * f->vx[i] + f->vy[i] * f->vy[i]);
        double cv = f->c[i] + f->mu[i];
        a2max = a2 > a2max ? a2 : a2max;
        speed = v > speed ? v : speed;
        visc = cv > visc ? cv : visc;
    }
    double dt = INFINITY;
    if (a2max > 0)
        dt = f->courant * sqrt(f->h / sqrt(a2max));
    if (speed > 0 && f->courant * f->h / speed < dt)
        dt = f->courant * f->h / speed;
    if (visc > 0 && f->courant * f->h / visc < dt)
        dt = f->courant * f->h / visc;
    return dt;
}

static void fused_step(fused *f)
{
    sluice_sim *s = f->sim;
    fused_evaluate(f);
    const double dt = fused_time_step(f);
    const sluice_real half = (sluice_real)(0.5 * dt), full = (sluice_real)dt;
    const sluice_real rho0 = f->rho0;
    sluice_index n = s->particles.count;
    const uint8_t *kind = s->view.kind;
#pragma omp parallel for schedule(static)
    for (sluice_index i = 0; i < n; i++) {
        const int fluid = kind[i] == SLUICE_KIND_FLUID;
        if (fluid) {
            f->x[i] += half * f->vx[i];
            f->y[i] += half * f->vy[i];
        }
        f->vx0[i] = f->vx[i];
        f->vy0[i] = f->vy[i];
        f->rho0s[i] = f->rho[i];
        if (fluid) {
            f->vx[i] += half * f->ax[i];
            f->vy[i] += half * f->ay[i];
        }
        f->rho[i] += half * f->drho[i];
        if (!fluid && f->rho[i] < rho0)
            f->rho[i] = rho0; /* DBC clamp of the mid-step state */
    }
    fused_evaluate(f);
    n = s->particles.count;
    kind = s->view.kind;
#pragma omp parallel for schedule(static)
    for (sluice_index i = 0; i < n; i++) {
        const int fluid = kind[i] == SLUICE_KIND_FLUID;
        if (fluid) {
            f->vx[i] = f->vx0[i] + full * f->ax[i];
            f->vy[i] = f->vy0[i] + full * f->ay[i];
        }
        f->rho[i] = f->rho0s[i] + full * f->drho[i];
        if (fluid) {
            f->x[i] += half * f->vx[i];
            f->y[i] += half * f->vy[i];
        } else if (f->rho[i] < rho0) {
            f->rho[i] = rho0; /* DBC clamp */
        }
    }
    f->time += dt;
    s->time = f->time;
    s->step++;
}

static sluice_real constant(sluice_sim *sim, const char *name)
{
    for (uint32_t i = 0; i < sim->constant_count; i++)
        if (strcmp(sim->constants[i].name, name) == 0)
            return sim->constants[i].values[sim->constants[i].count - 1];
    fprintf(stderr, "sluice-bench: constant '%s' missing\n", name);
    exit(2);
}

static void check_fusable(sluice_sim *sim)
{
    static const char *const allowed[] = {"wendland_c2",     "tait",     "continuity", "delta_sph",
                                          "pressure_gradient", "artificial_viscosity", "gravity",
                                          "dbc",             "time_step", "symplectic",
                                          "front_gauge",     "hdf5"};
    for (uint32_t k = 0; k < sim->instance_count; k++) {
        int ok = 0;
        for (size_t a = 0; a < sizeof allowed / sizeof allowed[0]; a++)
            ok |= strcmp(sim->instances[k].name, allowed[a]) == 0;
        if (!ok) {
            fprintf(stderr, "sluice-bench: the fused loop does not implement plugin '%s'\n",
                    sim->instances[k].name);
            exit(2);
        }
    }
    if (sim->scene.dimensions != 2) {
        fprintf(stderr, "sluice-bench: the fused loop is 2D only\n");
        exit(2);
    }
}

static void fused_init(fused *f, sluice_sim *sim)
{
    memset(f, 0, sizeof *f);
    f->sim = sim;
    fused_bind(f);
    f->h = sim->smoothing_length;
    f->c0 = constant(sim, "speed_of_sound");
    f->rho0 = sim->rest_density;
    f->B = f->c0 * f->c0 * f->rho0 / 7;
    f->courant = constant(sim, "courant_number");
    sluice_real g[3] = {0, 0, 0};
    for (uint32_t i = 0; i < sim->constant_count; i++)
        if (strcmp(sim->constants[i].name, "gravity") == 0)
            memcpy(g, sim->constants[i].values, sizeof g);
    f->g[0] = g[0];
    f->g[1] = g[1];
    f->eta2 = (sluice_real)0.01 * f->h * f->h;
    f->wendland_a = (sluice_real)(7.0 / (4.0 * 3.14159265358979323846) / (f->h * f->h));
    f->wendland_b = -5 * f->wendland_a / (f->h * f->h);
    /* delta-SPH: config {delta, form} as in plugins/density_diffusion */
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if (strcmp(sim->instances[k].name, "delta_sph") == 0) {
            const struct {
                sluice_real delta;
                int form;
            } *dc = sim->instances[k].config;
            f->delta_coefficient = 2 * dc->delta * f->h * f->c0;
            if (dc->form == 1) /* fourtakas: rho^H_ji = -(rho0 / c0^2) g . r_ij */
                for (int d = 0; d < 2; d++)
                    f->hydro[d] = -f->rho0 * g[d] / (f->c0 * f->c0);
        }
    /* alpha: read from the artificial_viscosity config (first parameter) */
    for (uint32_t k = 0; k < sim->instance_count; k++)
        if (strcmp(sim->instances[k].name, "artificial_viscosity") == 0)
            f->alpha = *(const sluice_real *)sim->instances[k].config;
}

/* --------------------------------------------------------------- modes -- */

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, compare_doubles);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* Largest distance between the same particles (by id) of two simulations. */
static double position_difference(sluice_sim *a, sluice_sim *b)
{
    const sluice_view *va = sluice_sim_view(a), *vb = sluice_sim_view(b);
    sluice_index n = va->count;
    double *xa = calloc(n, sizeof *xa), *ya = calloc(n, sizeof *ya), difference = 0;
    for (sluice_index i = 0; i < n && xa && ya; i++) {
        xa[va->id[i]] = va->position[0][i];
        ya[va->id[i]] = va->position[1][i];
    }
    for (sluice_index i = 0; i < vb->count && xa && ya; i++) {
        double d = hypot(vb->position[0][i] - xa[vb->id[i]], vb->position[1][i] - ya[vb->id[i]]);
        if (d > difference)
            difference = d;
    }
    free(xa);
    free(ya);
    return difference;
}

static const char *const variant_names[3] = {"scalar", "flat", "batched"};

static int mode_ratio(const options *o)
{
    /* 1. same physics: the plugin path and each fused variant from t = 0 */
    sluice_sim *a = load(o);
    if (!a)
        return 2;
    check_fusable(a);
    if (sluice_sim_begin(a, NULL) != SLUICE_RUN_COMPLETE)
        return 4;
    for (int s = 0; s < 50; s++)
        if (sluice_sim_step(a) != SLUICE_RUN_COMPLETE) {
            fprintf(stderr, "sluice-bench: %s\n", sluice_sim_failure(a));
            return 3;
        }
    double difference = 0;
    for (int variant = 0; variant < 3; variant++) {
        sluice_sim *b = load(o);
        if (!b || sluice_sim_begin(b, NULL) != SLUICE_RUN_COMPLETE)
            return 4;
        fused check;
        fused_init(&check, b);
        check.variant = variant;
        for (int s = 0; s < 50; s++)
            fused_step(&check);
        double d = position_difference(a, b);
        if (d > difference)
            difference = d;
        sluice_sim_end(b, SLUICE_RUN_COMPLETE);
        sluice_sim_free(b);
    }

    /* 2. warm up to a representative state of the flow, then alternate
     *    blocks of plugin-path and fused steps on the same evolving state */
    while (sluice_sim_time(a) < o->warmup_time)
        if (sluice_sim_step(a) != SLUICE_RUN_COMPLETE) {
            fprintf(stderr, "sluice-bench: %s\n", sluice_sim_failure(a));
            return 3;
        }
    double plugin_times[64], fused_times[3][64];
    uint64_t pairs = 0;
    int repeat = o->repeat > 64 ? 64 : o->repeat;
    fused f;
    fused_init(&f, a);
    for (int r = 0; r < repeat; r++) {
        uint64_t pairs0 = sluice_sim_pair_count(a);
        double t0 = sluice_wall_clock();
        for (int s = 0; s < o->steps; s++)
            if (sluice_sim_step(a) != SLUICE_RUN_COMPLETE) {
                fprintf(stderr, "sluice-bench: %s\n", sluice_sim_failure(a));
                return 3;
            }
        plugin_times[r] = (sluice_wall_clock() - t0) / o->steps;
        pairs += sluice_sim_pair_count(a) - pairs0;
        for (int variant = 0; variant < 3; variant++) {
            fused_bind(&f); /* earlier steps may have reordered the particles */
            f.variant = variant;
            f.time = sluice_sim_time(a);
            t0 = sluice_wall_clock();
            for (int s = 0; s < o->steps; s++)
                fused_step(&f);
            fused_times[variant][r] = (sluice_wall_clock() - t0) / o->steps;
        }
    }
    sluice_index particles = a->particles.count;
    double simulated = sluice_sim_time(a);
    sluice_sim_end(a, SLUICE_RUN_COMPLETE);
    sluice_sim_free(a);
    double tp = median(plugin_times, repeat), tf[3], best = INFINITY;
    int fastest = 0;
    for (int variant = 0; variant < 3; variant++) {
        tf[variant] = median(fused_times[variant], repeat);
        if (tf[variant] < best) {
            best = tf[variant];
            fastest = variant;
        }
    }
    double pairs_per_step = (double)pairs / ((double)o->steps * repeat);
    printf("particles,threads,steps,warmup_time_s,end_time_s,plugin_s_per_step,"
           "fused_scalar_s_per_step,fused_flat_s_per_step,fused_batched_s_per_step,fastest_fused,"
           "plugin_particle_steps_per_s,fused_particle_steps_per_s,pair_interactions_per_s,"
           "plugin_over_fused,max_position_difference_m\n");
    printf("%u,%d,%d,%.4g,%.4g,%.6e,%.6e,%.6e,%.6e,%s,%.4e,%.4e,%.4e,%.4f,%.3e\n", particles,
           omp_get_max_threads(), o->steps, o->warmup_time, simulated, tp, tf[0], tf[1], tf[2],
           variant_names[fastest], particles / tp, particles / best, pairs_per_step / tp,
           tp / best, difference);
    return 0;
}

static int mode_memory(const options *o)
{
    sluice_sim *sim = load(o);
    if (!sim)
        return 2;
    if (sluice_sim_begin(sim, NULL) != SLUICE_RUN_COMPLETE)
        return 4;
    double t0 = sluice_wall_clock();
    for (int s = 0; s < o->steps; s++)
        if (sluice_sim_step(sim) != SLUICE_RUN_COMPLETE) {
            fprintf(stderr, "sluice-bench: %s\n", sluice_sim_failure(sim));
            return 3;
        }
    double seconds = (sluice_wall_clock() - t0) / (o->steps ? o->steps : 1);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double peak = (double)ru.ru_maxrss * 1024.0;
    sluice_index n = sluice_sim_view(sim)->count;
    printf("particles,threads,peak_rss_bytes,bytes_per_particle,core_bytes_per_particle,"
           "s_per_step\n");
    printf("%u,%d,%.0f,%.1f,%.1f,%.4e\n", n, omp_get_max_threads(), peak, peak / n,
           (double)sluice_sim_bytes(sim) / n, seconds);
    sluice_sim_end(sim, SLUICE_RUN_COMPLETE);
    sluice_sim_free(sim);
    return 0;
}

/* Run from the build tree (build/tools/sluice-bench): the plugins are in
 * build/plugins unless SLUICE_PLUGIN_PATH says otherwise. */
static void default_plugin_path(void)
{
    if (getenv("SLUICE_PLUGIN_PATH"))
        return;
    char exe[4096];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0)
        return;
    exe[n] = '\0';
    char *slash = strrchr(exe, '/');
    if (!slash)
        return;
    *slash = '\0';
    char path[4200];
    snprintf(path, sizeof path, "%s/../plugins", exe);
    setenv("SLUICE_PLUGIN_PATH", path, 0);
}

int main(int argc, char **argv)
{
    default_plugin_path();
    options o = {0};
    o.steps = 200;
    o.warmup = 20;
    o.repeat = 5;
    o.warmup_time = 0.1;
    o.sets = calloc((size_t)argc + 1, sizeof *o.sets);
    if (!o.sets)
        return 4;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--steps") == 0 && i + 1 < argc)
            o.steps = atoi(argv[++i]);
        else if (strcmp(argv[i], "--warmup") == 0 && i + 1 < argc)
            o.warmup = atoi(argv[++i]);
        else if (strcmp(argv[i], "--warmup-time") == 0 && i + 1 < argc)
            o.warmup_time = atof(argv[++i]);
        else if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc)
            o.repeat = atoi(argv[++i]);
        else if (strcmp(argv[i], "--set") == 0 && i + 1 < argc)
            o.sets[o.set_count++] = argv[++i];
        else if (!o.mode)
            o.mode = argv[i];
        else if (!o.scene)
            o.scene = argv[i];
        else {
            fprintf(stderr, "sluice-bench: unexpected argument '%s'\n", argv[i]);
            return 2;
        }
    }
    if (!o.mode || !o.scene || o.steps < 1 || o.repeat < 1 || o.warmup < 0) {
        fprintf(stderr, "usage: sluice-bench ratio|memory SCENE [--steps N] [--repeat N] "
                        "[--warmup-time T] [--set key=value ...]\n");
        return 2;
    }
    int rc;
    if (strcmp(o.mode, "ratio") == 0)
        rc = mode_ratio(&o);
    else if (strcmp(o.mode, "memory") == 0)
        rc = mode_memory(&o);
    else {
        fprintf(stderr, "sluice-bench: unknown mode '%s'\n", o.mode);
        rc = 2;
    }
    free(o.sets);
    return rc;
}
