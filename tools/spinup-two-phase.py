#!/usr/bin/python3
# Research helper (docs/validation.md: "What fills the cavities" and "Cheng at
# the seed's spacing from a single-phase spin-up"): a two-phase checkpoint whose water
# is a single-phase run's state and whose air fills the rest of the scene's
# initial fluid lattice. Needs Debian's python3-h5py and python3-yaml (not
# build dependencies).
#
#   tools/spinup-two-phase.py TEMPLATE SINGLE AIR0 OUT DX
#     TEMPLATE  a checkpoint of the two-phase scene (its walls, open
#               particles, plugin states and layout are kept; the restarted
#               run's clock starts at its time)
#     SINGLE    a snapshot (particles_*.h5) of the scene's single_phase variant
#     AIR0      the two-phase run's first snapshot (its initial fluid lattice)
#     OUT       the checkpoint written; continue it with
#               sluice run SCENE [--variant V] --set particles.spacing=DX --restart OUT --out DIR
#     DX        the particle spacing of all three (m)
#   tools/spinup-two-phase.py ... DX --water-below X0 Y0 X1 Y1
#               also turns the lattice sites under the segment (X0, Y0)-(X1, Y1)
#               with X0 < X1 (and X0 < x <= X1) that no water particle is
#               within 0.75 dx of into water at rest at its rest density: for
#               a stepped chute the segment through the first and last step
#               edges (the pseudo-bottom) fills the step cavities, which the
#               two-phase model fills with water within 1-2 s of the flow's
#               arrival (docs/validation.md), where a single-phase run's
#               nappes leave them empty
#
# The constants of the two phases (c0 of the water, gamma, the air's gamma and
# rest density, the background pressure) and the kernel's smoothing length
# are read from the template's resolved scene. A site of the initial lattice
# (water or air at t = 0) becomes air where it lies outside the water (the
# water's kernel sum sum_j W_ij dx^d there is under 0.5: the free surface
# reads about 0.5, the inside 1; and no water particle is within 0.75 dx)
# and joins the open air (below: enclosed pockets stay empty). Air
# starts at rest at its rest density (pressure p_b), the water keeps the
# single-phase run's position, velocity and density (its pressure and sound
# speed follow from the two-phase equation of state; the single-phase Tait
# has the same c0 and gamma, so the same density is the same pressure less
# p_b). Water within 0.5 dx of one of the template's open-boundary particles
# is left out (the inlet's buffer columns are the template's). Every other
# per-particle field starts at zero, but dissolved_oxygen, which starts at the
# water's value in SINGLE and 0 in the air. The neighbour list is rebuilt at
# the restart (grid_valid = 0). 2D only.
import sys, shutil, math
from collections import defaultdict
import h5py, numpy as np, yaml

USAGE = 'usage: spinup-two-phase.py TEMPLATE SINGLE AIR0 OUT DX [--water-below X0 Y0 X1 Y1] (see its header)'
if len(sys.argv) == 11 and sys.argv[6] == '--water-below':
    below = [float(a) for a in sys.argv[7:11]]
    if not below[0] < below[2]:
        sys.exit(USAGE)
elif len(sys.argv) == 6:
    below = None
else:
    sys.exit(USAGE)
tpl, single, air0, out, dx = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], float(sys.argv[5])

with h5py.File(tpl, 'r') as f:
    scene = yaml.safe_load(f.attrs['scene'])
    if int(f.attrs['dimensions']) != 2:
        sys.exit('spinup-two-phase.py: 2D scenes only')
tp = scene['plugins']['two_phase']
rho0 = float(scene['particles']['rest_density'])
c0 = float(tp['speed_of_sound'])
gamma = float(tp.get('gamma', 7))
air_gamma = float(tp.get('air_gamma', 1.4))
rho0_a = float(tp.get('air_rest_density', 1.09))
pb = float(tp['background_pressure'])
B = rho0 * c0 * c0 / gamma
c0_a = math.sqrt(air_gamma * B / rho0_a)
h = float(scene['particles']['smoothing_length_ratio']) * dx
if abs(float(scene['particles']['spacing']) - dx) > 1e-12:
    sys.exit('spinup-two-phase.py: the template was run at dx = %g, not %g'
             % (float(scene['particles']['spacing']), dx))
kernels = [k for k in ('wendland_c2', 'cubic_spline') if k in scene['plugins']]
if kernels != ['wendland_c2']:
    sys.exit('spinup-two-phase.py: written for the Wendland C2 kernel (the spillway scenes)')


def kernel(r):  # Wendland C2, 2D, support 2h
    q = r / h
    return np.where(q < 2, 7.0 / (4 * math.pi * h * h) * (1 - q / 2) ** 4 * (2 * q + 1), 0.0)


def hashed(points, cell):
    grid = defaultdict(list)
    for i, (x, y) in enumerate(points):
        grid[(int(math.floor(x / cell)), int(math.floor(y / cell)))].append(i)
    return {k: np.array(v) for k, v in grid.items()}


def near(grid, cell, x, y):
    cx, cy = int(math.floor(x / cell)), int(math.floor(y / cell))
    parts = [grid[(ix, iy)] for ix in (cx - 1, cx, cx + 1) for iy in (cy - 1, cy, cy + 1)
             if (ix, iy) in grid]
    return np.concatenate(parts) if parts else np.zeros(0, int)


# sluice's checkpoints end in a checksum trailer (core/checkpoint/file_checksum.h):
# 8 bytes of magic and the 64-bit FNV-1a hash of every byte before them
MAGIC = b'SLUICE\x01\x0f'


def strip_trailer(path):
    with open(path, 'r+b') as fh:
        fh.seek(0, 2)
        n = fh.tell()
        if n >= 16:
            fh.seek(n - 16)
            if fh.read(8) == MAGIC:
                fh.truncate(n - 16)


def append_trailer(path):
    h = 0xcbf29ce484222325
    with open(path, 'rb') as fh:
        data = fh.read()
    for b in data:
        h = ((h ^ b) * 0x100000001b3) & 0xffffffffffffffff
    with open(path, 'ab') as fh:
        fh.write(MAGIC + h.to_bytes(8, 'little'))


shutil.copy(tpl, out)
strip_trailer(out)
f = h5py.File(out, 'r+')
P = f['particles']
fields = list(P.keys())
old = {k: np.array(P[k]) for k in fields}
kind = old['kind'][0]
phase_t = old['phase'][0]
keep = kind != 0                                  # walls and open particles of the template
open_pts = old["position"][:, kind == 2].T   # SLUICE_KIND_OPEN (1 is a wall)
fluid_mass_w = old['mass'][0][(kind == 0) & (phase_t == 0)]
fluid_mass_a = old['mass'][0][(kind == 0) & (phase_t == 1)]
mass_w, mass_a = float(fluid_mass_w[0]), float(fluid_mass_a[0])

with h5py.File(single, 'r') as s:
    sk = np.array(s['kind']).ravel()
    sw = sk == 0
    wp = np.array(s['position'])[sw]
    wv = np.array(s['velocity'])[sw]
    wr = np.array(s['density']).ravel()[sw]
    wc = (np.array(s['dissolved_oxygen']).ravel()[sw] if 'dissolved_oxygen' in s else None)
# the inlet's buffer is the template's: leave out water on top of it
og = hashed(open_pts, 0.5 * dx)
drop = np.zeros(len(wp), bool)
for n, (x, y) in enumerate(wp):
    j = near(og, 0.5 * dx, x, y)
    if len(j) and np.min(np.hypot(open_pts[j, 0] - x, open_pts[j, 1] - y)) < 0.5 * dx:
        drop[n] = True
wp, wv, wr = wp[~drop], wv[~drop], wr[~drop]
if wc is not None:
    wc = wc[~drop]

with h5py.File(air0, 'r') as a:
    ak = np.array(a['kind']).ravel()
    sites = np.array(a['position'])[ak == 0]
support = 2 * h
wg = hashed(wp, support)
vol = mass_w / wr
clear = np.zeros(len(sites), bool)
for n, (x, y) in enumerate(sites):
    j = near(wg, support, x, y)
    if len(j) == 0:
        clear[n] = True
        continue
    r = np.hypot(wp[j, 0] - x, wp[j, 1] - y)
    clear[n] = r.min() >= 0.75 * dx and float(np.sum(kernel(r) * vol[j])) < 0.5
filled = 0
if below is not None:
    x0, y0, x1, y1 = below
    ys = y0 + (y1 - y0) * (sites[:, 0] - x0) / (x1 - x0)
    under = clear & (sites[:, 0] > x0) & (sites[:, 0] <= x1) & (sites[:, 1] < ys)
    filled = int(under.sum())
    wp = np.concatenate([wp, sites[under]])
    wv = np.concatenate([wv, np.zeros((filled, 2))])
    wr = np.concatenate([wr, np.full(filled, rho0)])
    if wc is not None:
        wc = np.concatenate([wc, np.full(filled, float(scene['plugins']['dissolved_oxygen']['initial_concentration']))])
    clear &= ~under
# Air only where it joins the open air: a pocket of lattice sites enclosed by
# the single-phase water (a void under a nappe, between a filled cavity and
# the film, in the toe's roller) would be a bubble of many particles that
# the flow squeezes (an air particle at 2.2 rho0_a stopped Cheng's first
# spin-up at 0.16 s). The open air: clear sites joined, through lattice
# neighbours (4-connected), to a site with no water within the kernel's
# support. Enclosed sites stay empty (as in the single-phase run).
wg = hashed(wp, support)   # with the cavities' water
index = {}
for n in np.flatnonzero(clear):
    index[(int(math.floor(sites[n, 0] / dx)), int(math.floor(sites[n, 1] / dx)))] = n
far = np.zeros(len(sites), bool)
for n in np.flatnonzero(clear):
    x, y = sites[n]
    j = near(wg, support, x, y)
    far[n] = len(j) == 0 or np.hypot(wp[j, 0] - x, wp[j, 1] - y).min() >= support
joined = np.zeros(len(sites), bool)
queue = [n for n in np.flatnonzero(far)]
joined[queue] = True
while queue:
    n = queue.pop()
    i, j = int(math.floor(sites[n, 0] / dx)), int(math.floor(sites[n, 1] / dx))
    for key in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
        m = index.get(key)
        if m is not None and not joined[m]:
            joined[m] = True
            queue.append(m)
enclosed = int((clear & ~joined).sum())
clear &= joined

ap = sites[clear]
nw, na = len(wp), len(ap)

next_id = int(f.attrs['next_id'])
values = {
    'position': np.concatenate([wp, ap]).T,
    'kind': np.zeros((1, nw + na)),
    'phase': np.concatenate([np.zeros(nw), np.ones(na)])[None],
    'id': np.arange(next_id, next_id + nw + na)[None],
    'mass': np.concatenate([np.full(nw, mass_w), np.full(na, mass_a)])[None],
}
rho = np.concatenate([wr, np.full(na, rho0_a)])
values['density'] = values['density_previous'] = rho[None]
values['pressure'] = np.concatenate([B * ((wr / rho0) ** gamma - 1) + pb, np.full(na, pb)])[None]
values['sound_speed'] = np.concatenate([c0 * (wr / rho0) ** ((gamma - 1) / 2), np.full(na, c0_a)])[None]
vel = np.concatenate([wv, np.zeros((na, 2))]).T
values['velocity'] = values['velocity_previous'] = vel
if 'dissolved_oxygen' in fields:
    cw = wc if wc is not None else np.full(nw, float(scene['plugins']['dissolved_oxygen']['initial_concentration']))
    cc = np.concatenate([cw, np.zeros(na)])[None]
    values['dissolved_oxygen'] = values['dissolved_oxygen_previous'] = cc
for k in fields:
    arr = old[k][:, keep]
    add = np.zeros((arr.shape[0], nw + na), dtype=arr.dtype)
    if k in values:
        add[...] = values[k]
    data = np.concatenate([arr, add], axis=1)
    del P[k]
    P.create_dataset(k, data=data)
f.attrs.modify('particle_count', np.uint64(data.shape[1]))
f.attrs.modify('next_id', np.uint64(next_id + nw + na))
f.attrs.modify('grid_valid', np.int32(0))
f.close()
append_trailer(out)
print('water %d (%d on the inlet buffer left out, %d added under the segment), air %d (of %d lattice sites; '
      '%d enclosed by water left empty), walls/open %d; '
      'B = %.6g Pa, c0_a = %.6g m/s, p_b = %g Pa' % (nw, int(drop.sum()), filled, na, len(sites), enclosed, keep.sum(), B, c0_a, pb))
