/* The memory a scene needs, estimated before its particles are allocated,
 * and the memory this process may still take (docs/reliability.md,
 * "Memory"). */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include <omp.h>

#include "geometry.h"
#include "wall_watch.h"
#include "sim_internal.h"

/* ------------------------------------------------------------ counting -- */

/* A wall element's length (2D) or area (3D) in spacings (dx, dx^2). */
static double element_measure(const sluice_real *p, uint32_t dims, double dx)
{
    if (dims == 2)
        return hypot((double)(p[3] - p[0]), (double)(p[4] - p[1])) / dx;
    double a[3], b[3];
    for (int d = 0; d < 3; d++) {
        a[d] = (double)(p[3 + d] - p[d]);
        b[d] = (double)(p[6 + d] - p[d]);
    }
    const double c0 = a[1] * b[2] - a[2] * b[1], c1 = a[2] * b[0] - a[0] * b[2],
                 c2 = a[0] * b[1] - a[1] * b[0];
    return 0.5 * sqrt(c0 * c0 + c1 * c1 + c2 * c2) / (dx * dx);
}

void sluice_sim_count_particles(const sluice_sim *sim, double wall_layers, double *fluid,
                                double *wall)
{
    const sluice_scene *scene = &sim->scene;
    const uint32_t dims = scene->dimensions;
    const double dx = (double)scene->particles.spacing;
    *fluid = 0;
    *wall = 0;
    for (size_t r = 0; r < scene->fluid_count; r++) {
        sluice_real lo[3], hi[3];
        sluice_region_bounds(&scene->fluids[r].region, dims, lo, hi);
        double points = 1;
        for (uint32_t d = 0; d < dims; d++)
            points *= floor(((double)hi[d] - (double)lo[d]) / dx) + 1;
        *fluid += points;
    }
    for (size_t w = 0; w < scene->wall_count; w++) {
        const sluice_wall_geometry *g = &scene->walls[w].geometry;
        for (uint32_t e = 0; e < g->element_count; e++) {
            const sluice_real *p = g->points + (size_t)e * dims * 3;
            const double measure = element_measure(p, dims, dx);
            *wall += wall_layers * measure;
        }
    }
}

/* The lattice points (spacing 1) within `radius` of a lattice point, itself
 * excluded: the neighbour-list length of a particle inside the fluid. */
static double lattice_neighbours(uint32_t dims, double radius)
{
    const int64_t reach = (int64_t)floor(radius);
    const double r2 = radius * radius;
    double count = 0;
    const int64_t zreach = dims == 3 ? reach : 0;
    for (int64_t i = -reach; i <= reach; i++)
        for (int64_t j = -reach; j <= reach; j++)
            for (int64_t k = -zreach; k <= zreach; k++)
                if ((double)(i * i + j * j + k * k) < r2)
                    count++;
    return count - 1;
}

/* 1 when a fluid region holds p. */
static int in_fluid(const sluice_sim *sim, const double p[3])
{
    const sluice_real q[3] = {(sluice_real)p[0], (sluice_real)p[1], (sluice_real)p[2]};
    for (size_t r = 0; r < sim->scene.fluid_count; r++)
        if (sluice_region_contains(&sim->scene.fluids[r].region, sim->scene.dimensions, q))
            return 1;
    return 0;
}

/* The share of a wall element with fluid on one side or the other (one
 * spacing away), sampled on a grid of points over it. */
static double wetted_share(const sluice_sim *sim, const sluice_real *p, double dx)
{
    const uint32_t dims = sim->scene.dimensions;
    enum { SAMPLES = 8 };
    double a[3] = {0, 0, 0}, b[3] = {0, 0, 0}, normal[3] = {0, 0, 0};
    for (uint32_t d = 0; d < dims; d++) {
        a[d] = (double)(p[3 + d] - p[d]);
        b[d] = dims == 3 ? (double)(p[6 + d] - p[d]) : 0;
    }
    if (dims == 2) {
        normal[0] = -a[1];
        normal[1] = a[0];
    } else {
        normal[0] = a[1] * b[2] - a[2] * b[1];
        normal[1] = a[2] * b[0] - a[0] * b[2];
        normal[2] = a[0] * b[1] - a[1] * b[0];
    }
    const double length = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(length > 0))
        return 0;
    double wet = 0, points = 0;
    for (int i = 0; i < SAMPLES; i++)
        for (int j = 0; j < (dims == 3 ? SAMPLES - i : 1); j++) {
            /* 2D: along the segment; 3D: barycentric points inside the triangle */
            const double u = dims == 3 ? (i + 1.0 / 3.0) / SAMPLES : (i + 0.5) / SAMPLES;
            const double v = dims == 3 ? (j + 1.0 / 3.0) / SAMPLES : 0;
            double front[3], back[3];
            for (int d = 0; d < 3; d++) {
                const double x = (d < (int)dims ? (double)p[d] : 0) + u * a[d] + v * b[d];
                front[d] = x + dx * normal[d] / length;
                back[d] = x - dx * normal[d] / length;
            }
            wet += in_fluid(sim, front) || in_fluid(sim, back);
            points++;
        }
    return points > 0 ? wet / points : 0;
}

/* The neighbour-list entries missing at the free faces of the particles:
 * behind every wall's layers, and in front of a wall where no fluid lies.
 * Per spacing of a free face (dx^(d-1)) the particles within the cutoff q
 * (in spacings) of it miss the part of their ball beyond it: (2/3) q^3
 * entries in 2D, (pi/4) q^4 in 3D. */
static double free_face_deficit(const sluice_sim *sim, double q)
{
    const uint32_t dims = sim->scene.dimensions;
    const double dx = (double)sim->spacing;
    const double per_face = dims == 2 ? 2.0 / 3.0 * q * q * q : M_PI / 4.0 * q * q * q * q;
    double deficit = 0;
    for (size_t w = 0; w < sim->scene.wall_count; w++) {
        const sluice_wall_geometry *g = &sim->scene.walls[w].geometry;
        for (uint32_t e = 0; e < g->element_count; e++) {
            const sluice_real *p = g->points + (size_t)e * dims * 3;
            const double measure = element_measure(p, dims, dx);
            deficit += measure * per_face * (2.0 - wetted_share(sim, p, dx));
        }
    }
    return deficit;
}

void sluice_sim_estimate_memory(const sluice_sim *sim, double particles,
                                sluice_memory_estimate *out)
{
    memset(out, 0, sizeof *out);
    const uint32_t dims = sim->scene.dimensions;
    out->particles = particles;
    /* the particle store: every column of every declared field; the
     * reordering by cell swaps each column with a scratch column of its
     * element size (one per size in use) */
    int size_in_use[9] = {0};
    for (uint32_t f = 0; f < sim->field_count; f++) {
        const uint8_t size = sluice_sim_type_size(sim->fields[f].type);
        out->store += (double)size * sim->fields[f].components;
        size_in_use[size < 9 ? size : 8] = 1;
    }
    for (int s = 1; s < 9; s++)
        out->scratch += size_in_use[s] ? s : 0;
    /* the cell grid: order, cell, list start and the positions at the
     * list's build */
    out->grid = 3.0 * sizeof(sluice_index) + (double)dims * sizeof(sluice_real);
    /* the Verlet list: every neighbour within the support plus the skin,
     * counted on the lattice, less those missing at the free faces of the
     * wall layers (the fluid's own free surface is not counted: a small
     * overestimate) */
    const double cutoff = (double)sim->support * (1.0 + (double)sim->scene.neighbour_search.skin);
    const double q = cutoff / (double)sim->spacing;
    out->neighbours = lattice_neighbours(dims, q);
    if (particles > 0) {
        const double entries = out->neighbours * particles - free_face_deficit(sim, q);
        out->neighbours = entries > 0 ? entries / particles : 0;
    }
    out->list = out->neighbours * sizeof(sluice_index);
    out->per_particle = out->store + out->scratch + out->grid + out->list;
    /* what the process holds now (program, libraries, the scene, the
     * plugins' state), the cell grid's cell starts, and the pair engine's
     * batch buffers of every thread */
    out->resident = sluice_memory_resident();
    double cells = 1;
    for (uint32_t d = 0; d < dims; d++)
        cells *= ceil(((double)sim->scene.domain.max[d] - (double)sim->scene.domain.min[d]) /
                      cutoff);
    const double batch = (double)(sim->scene.neighbour_search.batch_pairs
                                      ? sim->scene.neighbour_search.batch_pairs
                                      : 1024);
    out->fixed = out->resident + (cells + 1) * sizeof(sluice_index) +
                 (double)omp_get_max_threads() * batch *
                     (2.0 * sizeof(sluice_index) + 1 + (7.0 + sim->column_count) * sizeof(sluice_real));
    /* the watchdog's wall cells (built when the run starts, run.c) */
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (uint32_t d = 0; d < dims; d++) {
        lo[d] = (double)sim->scene.domain.min[d];
        hi[d] = (double)sim->scene.domain.max[d];
    }
    out->fixed += sluice_wall_watch_bytes(dims, sim->wall_geometries, sim->scene.wall_count, lo,
                                          hi, (double)sim->support);
    /* when the run starts: the OpenMP threads' stacks and heaps and the
     * HDF5 library's state (measured: 2.0 MB and 0.4 MB a thread, Debian 12) */
    out->fixed += 2.0e6 + 0.4e6 * omp_get_max_threads();
    out->total = out->fixed + particles * out->per_particle;
    out->available = sluice_memory_available(&out->available_from);
}

/* --------------------------------------------------------- the machine -- */

double sluice_memory_resident(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    unsigned long long size = 0, resident = 0;
    int got = f ? fscanf(f, "%llu %llu", &size, &resident) : 0;
    if (f)
        fclose(f);
    const long page = sysconf(_SC_PAGESIZE);
    return got == 2 && page > 0 ? (double)resident * (double)page : 0;
}

/* A number from a one-line file (cgroup), or -1 ("max", missing). */
static double read_number(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char text[64] = "";
    double value = -1;
    if (fgets(text, sizeof text, f) && strncmp(text, "max", 3) != 0) {
        char *end = NULL;
        double v = strtod(text, &end);
        if (end != text && v >= 0)
            value = v;
    }
    fclose(f);
    return value;
}

/* MemAvailable of /proc/meminfo in bytes, or -1. */
static double meminfo_available(void)
{
    FILE *f = fopen("/proc/meminfo", "r");
    if (!f)
        return -1;
    char line[256];
    double value = -1;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, "MemAvailable:", 13) == 0) {
            unsigned long long kib = 0;
            if (sscanf(line + 13, "%llu", &kib) == 1)
                value = (double)kib * 1024.0;
            break;
        }
    fclose(f);
    return value;
}

double sluice_memory_available(const char **source)
{
    /* the memory this process may grow by: the least of what the kernel
     * can give without swapping, what the control group allows and the
     * address-space limit */
    double available = meminfo_available();
    const char *from = available >= 0 ? "MemAvailable in /proc/meminfo" : NULL;
    const double limit = read_number("/sys/fs/cgroup/memory.max"),
                 used = read_number("/sys/fs/cgroup/memory.current");
    if (limit >= 0 && used >= 0 && (available < 0 || limit - used < available)) {
        available = limit > used ? limit - used : 0;
        from = "the control group's memory.max";
    }
    struct rlimit r;
    FILE *f = fopen("/proc/self/statm", "r");
    unsigned long long size = 0;
    const long page = sysconf(_SC_PAGESIZE);
    if (f && fscanf(f, "%llu", &size) == 1 && getrlimit(RLIMIT_AS, &r) == 0 &&
        r.rlim_cur != RLIM_INFINITY && page > 0) {
        const double virtual_size = (double)size * (double)page;
        const double room = (double)r.rlim_cur > virtual_size ? (double)r.rlim_cur - virtual_size : 0;
        if (available < 0 || room < available) {
            available = room;
            from = "the address-space limit (ulimit -v)";
        }
    }
    if (f)
        fclose(f);
    if (source)
        *source = from;
    return available;
}
