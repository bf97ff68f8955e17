/* Kernel sums shared by pair terms (part of the plugin SDK,
 * sluice/plugin_util.h).
 *
 * Called from a pair callback, per target t of a batch, with the fields'
 * handles; the fields must be declared SLUICE_READ_NEIGHBOUR (their values
 * at j are read from b->gathered) and the batch built with the kernel
 * gradient F (grad_i W_ij = r_ij F_ij, r_ij = r_i - r_j). `dims` is best a
 * constant at the call (one specialised loop per dimension count). */
#ifndef SLUICE_KERNEL_SUMS_H
#define SLUICE_KERNEL_SUMS_H

#include "sluice/plugin.h"

#if defined(__GNUC__)
#define SLUICE_ALWAYS_INLINE __attribute__((always_inline))
#else
#define SLUICE_ALWAYS_INLINE
#endif

/* The SPH estimate of the velocity gradient at target t, without
 * renormalisation: g[3 a + b] = sum_j V_j (v_j - v_i)_a (r_ij F_ij)_b
 * = d v_a / d x_b, V_j = m_j / rho_j, for a, b < dims (entries of a third
 * axis are 0 in 2D). vi: the target's velocity. With a kernel correction L
 * the renormalised gradient is sum_e g[3 a + e] L_be. */
static inline SLUICE_ALWAYS_INLINE void
sluice_velocity_gradient_sum(const sluice_pair_batch *b, sluice_index t, uint32_t dims,
                             sluice_field velocity, sluice_field mass, sluice_field density,
                             const sluice_real vi[3], sluice_real g[9])
{
    const sluice_real *restrict vxj = b->gathered[velocity.column];
    const sluice_real *restrict vyj = b->gathered[velocity.column + 1];
    const sluice_real *restrict vzj = b->gathered[velocity.column + (dims == 3 ? 2 : 1)];
    const sluice_real *restrict mj = b->gathered[mass.column];
    const sluice_real *restrict rhoj = b->gathered[density.column];
    const sluice_real *restrict F = b->kernel_gradient;
    const sluice_real *restrict rx = b->offset[0], *restrict ry = b->offset[1];
    const sluice_real *restrict rz = dims == 3 ? b->offset[2] : b->offset[1];
    const sluice_real vxi = vi[0], vyi = vi[1], vzi = vi[2];
    sluice_real gxx = 0, gxy = 0, gxz = 0, gyx = 0, gyy = 0, gyz = 0, gzx = 0, gzy = 0, gzz = 0;
    for (sluice_index k = b->pair_begin[t]; k < b->pair_begin[t + 1]; k++) {
        const sluice_real w = mj[k] / rhoj[k] * F[k];
        const sluice_real du = (vxj[k] - vxi) * w, dv = (vyj[k] - vyi) * w;
        gxx += du * rx[k];
        gxy += du * ry[k];
        gyx += dv * rx[k];
        gyy += dv * ry[k];
        if (dims == 3) {
            const sluice_real dw = (vzj[k] - vzi) * w;
            gxz += du * rz[k];
            gyz += dv * rz[k];
            gzx += dw * rx[k];
            gzy += dw * ry[k];
            gzz += dw * rz[k];
        }
    }
    g[0] = gxx, g[1] = gxy, g[2] = gxz;
    g[3] = gyx, g[4] = gyy, g[5] = gyz;
    g[6] = gzx, g[7] = gzy, g[8] = gzz;
}

#endif
