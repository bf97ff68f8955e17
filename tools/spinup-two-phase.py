#!/usr/bin/python3
# Research helper (docs/validation.md, "What fills the cavities"): a two-phase
# checkpoint of the stepped chute whose water is a single-phase run's state
# and whose air fills the rest of the initial air lattice. Needs Debian's
# python3-h5py (not a build dependency). Written for seed 001's two-phase
# Chanson scene (Tait B of c0 = 28 m/s, p_b = 5000 Pa, air 1.09 kg/m^3,
# c0_a = 379.28 m/s); other scenes need those constants changed below.
#
#   tools/spinup-two-phase.py TEMPLATE SINGLE AIR0 OUT DX
#     TEMPLATE  a checkpoint of the two-phase scene at time t (its walls,
#               open particles, plugin states and layout are kept)
#     SINGLE    a snapshot (particles_*.h5) of the single_phase variant at t
#     AIR0      the two-phase run's first snapshot (its air lattice)
#     OUT       the checkpoint written; continue it with
#               sluice run SCENE --set particles.spacing=DX --restart OUT --out DIR
#
# Air sites closer than 0.75 dx to any water particle are left out. The
# neighbour list is rebuilt at the restart (grid_valid = 0).
import sys, shutil, h5py, numpy as np
tpl, single, air0, out, dx = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], float(sys.argv[5])
shutil.copy(tpl, out)
f = h5py.File(out, 'r+'); P = f['particles']
fields = list(P.keys())
N0 = P['kind'].shape[1]
keep = np.array(P['kind'][0]) != 0            # walls and open particles of the template
s = h5py.File(single); sk = np.array(s['kind']).ravel(); sw = sk == 0
wp = np.array(s['position'])[sw]; wv = np.array(s['velocity'])[sw]; wr = np.array(s['density']).ravel()[sw]
a = h5py.File(air0); ak = np.array(a['kind']).ravel(); aph = np.array(a['phase']).ravel()
ap = np.array(a['position'])[(ak == 0) & (aph == 1)]
# air sites clear of the water (cell hashing)
cell = 0.75 * dx
from collections import defaultdict
grid = defaultdict(list)
for i, (x, y) in enumerate(wp):
    grid[(int(np.floor(x / cell)), int(np.floor(y / cell)))].append(i)
clear = np.ones(len(ap), bool)
for n, (x, y) in enumerate(ap):
    cx, cy = int(np.floor(x / cell)), int(np.floor(y / cell))
    for ix in (cx - 1, cx, cx + 1):
        for iy in (cy - 1, cy, cy + 1):
            for i in grid.get((ix, iy), ()):
                if (wp[i, 0] - x) ** 2 + (wp[i, 1] - y) ** 2 < cell * cell:
                    clear[n] = False
ap = ap[clear]
nw, na = len(wp), len(ap)
old = {k: np.array(P[k]) for k in fields}
mass_w = old['mass'][0][(old['kind'][0] == 0) & (old['phase'][0] == 0)][0]
mass_a = old['mass'][0][(old['kind'][0] == 0) & (old['phase'][0] == 1)][0]
B = 1000 * 28 ** 2 / 7  # Tait B of c0 = 28 m/s, gamma 7
pb = 5000.0  # two_phase.background_pressure
next_id = int(f.attrs['next_id'])
new = {}
for k in fields:
    arr = old[k][:, keep]
    comp = arr.shape[0]
    add = np.zeros((comp, nw + na), dtype=arr.dtype)
    new[k] = (arr, add)
def put(k, values):
    arr, add = new[k]
    add[...] = values
put('position', np.concatenate([wp, ap]).T)
put('kind', np.zeros((1, nw + na)))
put('phase', np.concatenate([np.zeros(nw), np.ones(na)])[None])
ids = np.arange(next_id, next_id + nw + na)
put('id', ids[None])
rho = np.concatenate([wr, np.full(na, 1.09)])
put('density', rho[None]); put('density_previous', rho[None])
put('mass', np.concatenate([np.full(nw, mass_w), np.full(na, mass_a)])[None])
put('pressure', np.concatenate([B * ((wr / 1000) ** 7 - 1) + pb, np.full(na, pb)])[None])
put('sound_speed', np.concatenate([28 * (wr / 1000) ** 3, np.full(na, 379.28)])[None])
vel = np.concatenate([wv, np.zeros((na, 2))]).T
put('velocity', vel); put('velocity_previous', vel)
for k in fields:
    arr, add = new[k]
    data = np.concatenate([arr, add], axis=1)
    del P[k]; P.create_dataset(k, data=data)
f.attrs.modify('particle_count', np.uint64(data.shape[1]))
f.attrs.modify('next_id', np.uint64(next_id + nw + na))
f.attrs.modify('grid_valid', np.int32(0))
f.close()
print('water %d, air %d (of %d sites), walls/open %d' % (nw, na, len(clear), keep.sum()))
