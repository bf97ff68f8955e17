#!/bin/sh
# PySPH 1.0 (Debian 12 python3-pysph) on its own 2D dam break
# (pysph.examples.dam_break_2d: WCSPH, Wendland quintic, h = 1.3 dx, PEC
# integrator, c0 = 62.64 m/s, a 1 m x 2 m column in a 4 m tank), serial and
# OpenMP on 2 threads, as the peer of tools/benchmark.sh.
#
#   tools/peer-pysph.sh OUT_DIR [DX (default 0.03)] [END_S (default 0.75)]
#
# Writes OUT_DIR/dx<DX>_<mode>.txt ("particles steps wall_s particle_steps_per_s")
# for mode serial and openmp, and OUT_DIR/dx<DX>_front.csv (time,x_front from
# the serial run's outputs). Installs python3-pysph with apt when missing
# (root). Notes from running it on this machine kind (../shared/peers/pysph):
# the stock example goes unstable after the wall impact (t ~ 1 s) and at
# dx = 0.015 near 0.48 s, so keep END_S <= 0.75 (<= 0.45 at dx = 0.015); its
# --dx option leaves h and the particle mass at dx = 0.03 (module globals):
# this script sets them from DX.
set -eu
out=$1
dx=${2:-0.03}
end=${3:-0.75}
py=/usr/bin/python3
if ! "$py" -c 'import pysph' >/dev/null 2>&1; then
    echo "peer-pysph: installing python3-pysph (apt)" >&2
    DEBIAN_FRONTEND=noninteractive apt-get install -y python3-pysph >&2
fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
run='import sys, pysph.examples.dam_break_2d as m
m.dx = float(sys.argv[sys.argv.index("--dx") + 1]); m.h = m.hdx * m.dx; m.m = m.dx ** 2 * m.ro
a = m.DamBreak2D(); a.run()'
for mode in serial openmp; do
    d=$out/dx${dx}_$mode
    rm -rf "$d"
    x=""
    threads=1
    [ "$mode" = openmp ] && x=--openmp && threads=2
    echo "peer-pysph: dx = $dx m, $mode, to $end s" >&2
    # a first, very short run compiles PySPH's kernels for this mode (Cython,
    # cached in ~/.pysph), so that the timed run does not count compiling
    (cd "$out" && OMP_NUM_THREADS=$threads "$py" -c "$run" --dx "$dx" --tf 1e-3 $x -o db \
        -d "$d-warmup" >"$d-warmup.log" 2>&1) || true
    rm -rf "$d-warmup"
    (cd "$out" && OMP_NUM_THREADS=$threads "$py" -c "$run" --dx "$dx" --tf "$end" $x -o db -d "$d" \
        >"$d.log" 2>&1) || { echo "peer-pysph: PySPH failed, see $d.log" >&2; tail -n 5 "$d.log" >&2; exit 1; }
done
OUT="$out" DX="$dx" "$py" - <<'PYEOF'
import glob, json, os
from pysph.solver.utils import iter_output, load
out, dx = os.environ['OUT'], os.environ['DX']
for mode in ('serial', 'openmp'):
    d = '%s/dx%s_%s' % (out, dx, mode)
    files = sorted(glob.glob(d + '/db_*.hdf5'), key=lambda f: int(f.rsplit('_', 1)[1].split('.')[0]))
    last = load(files[-1])
    n = sum(a.get_number_of_particles() for a in last['arrays'].values())
    steps = last['solver_data']['count']
    wall = json.load(open(glob.glob(d + '/*.info')[0]))['cpu_time']
    with open('%s/dx%s_%s.txt' % (out, dx, mode), 'w') as f:
        f.write('%d %d %.3f %.4g\n' % (n, steps, wall, n * steps / wall))
    if mode == 'serial':
        with open('%s/dx%s_front.csv' % (out, dx), 'w') as f:
            f.write('time,x_front\n')
            for sd, fl in iter_output(files, 'fluid'):
                f.write('%.6f,%.6f\n' % (sd['t'], fl.get('x').max()))
PYEOF
cat "$out"/dx${dx}_serial.txt "$out"/dx${dx}_openmp.txt >&2
