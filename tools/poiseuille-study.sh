#!/bin/sh
# Poiseuille flow between DBC plates (configs/poiseuille_2d.yaml, Morris et
# al. 1997) at several resolutions, both forms of the laminar viscosity, to
# t = 1.5 s (docs/validation.md). It runs the `study` case of the viscosity
# test program, which loads the scene at each resolution and measures:
#   - the L2 relative error against the series solution at t = 0.1 s and
#     against the steady parabola at t = 1.5 s (walls at y = 0 and y = L);
#   - the L2 error of the discrete steady state of the same SPH equations
#     (solved directly) and the simulation's difference from it;
#   - where the near-wall profile extrapolates to zero, in dx from the wall.
#
#   tools/poiseuille-study.sh [BUILD_DIR] [ACROSS ...]   (default: build 10 20 40 80)
#   H_RATIO=1.3 tools/poiseuille-study.sh ...            (h/dx; default 1.5)
#   SCHEME=ghost_particles tools/poiseuille-study.sh ... (walls; default dbc)
#
# SCHEME switches the walls' line of the scene: dbc (the scene's), or the
# no-slip form of a mirror scheme: ghost_particles (slip: no_slip) or mdbc
# (velocity: no_slip). With a mirror scheme the "discrete steady state" is
# that of ideal mirrored walls (wall row k: u = -u of fluid row k).
#
# Writes runs/poiseuille-study/summary.csv (runs/poiseuille-study-SCHEME/ for
# another SCHEME; one line per form and resolution, with the observed order
# against the previous resolution) and prints it.
set -eu
cd "$(dirname "$0")/.."
build=${1:-build}
[ $# -gt 0 ] && shift
across=${*:-10 20 40 80}
scheme=${SCHEME:-dbc}
out=${OUT:-runs/poiseuille-study-$scheme}
case $scheme in
dbc) walls= ; out=${OUT:-runs/poiseuille-study} ;;
ghost_particles) walls="ghost_particles: {slip: no_slip}" ;;
mdbc) walls="mdbc: {velocity: no_slip}" ;;
*) echo "SCHEME must be dbc, ghost_particles or mdbc" >&2; exit 2 ;;
esac
mkdir -p "$out"
if [ -n "$walls" ]; then
    SLUICE_POISEUILLE_WALLS=$walls
    export SLUICE_POISEUILLE_WALLS
fi
SLUICE_POISEUILLE_STUDY="$across" SLUICE_POISEUILLE_H_RATIO="${H_RATIO:-1.5}" \
    SLUICE_PLUGIN_PATH="$PWD/$build/plugins" SLUICE_BUILD_DIR="$PWD/$build" \
    SLUICE_SOURCE_DIR="$PWD" CK_RUN_CASE=study \
    OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}" \
    "$build/tests/test_viscosity" >"$out/raw.txt" 2>"$out/log.txt" || {
    cat "$out/raw.txt" "$out/log.txt" >&2
    exit 1
}
{
    echo "form,h_over_dx,across,particles,steps,wall_s,l2_transient_t0.1,l2_steady,l2_discrete_steady,sim_minus_discrete,order_steady,order_transient,wall_zero_dx"
    awk -F, '$1 == "study" {
        order = ""; order_t = ""
        if ($2 == form && prev > 0) {
            order = sprintf("%.3f", log(prev / $9) / log($4 / prev_n))
            order_t = sprintf("%.3f", log(prev_t / $8) / log($4 / prev_n))
        }
        printf "%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s\n", $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, order, order_t, $12
        form = $2; prev = $9; prev_t = $8; prev_n = $4
    }' "$out/raw.txt"
} >"$out/summary.csv"
cat "$out/summary.csv"
