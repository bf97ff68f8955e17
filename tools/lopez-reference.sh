#!/bin/sh
# A computable reference free surface for seed 002's 3D hydraulic jumps
# (configs/lopez2010_case{1,2,3}_3d.yaml), for `sluice-analyze l2`.
#
# Seed 002 (Lin et al. 2025, section 3.2, table 1) computes its L2 errors
# against Lopez et al.'s (2010) measured free surfaces, plotted in its
# figures 4-6; those figures were lost in the text extraction and no table of
# them exists here. What can be computed instead is the pair of conjugate
# depths of a hydraulic jump:
#   - upstream of the toe, the supercritical depth d1 (the gate's opening,
#     1 m, in all three cases),
#   - downstream of the roller, Belanger's sequent depth
#     d2 = d1 (sqrt(1 + 8 Fr1^2) - 1) / 2, with the seed's Fr1 (3.8, 5.5, 8.0),
# with the toe where the simulated surface first rises above (d1 + d2) / 2
# downstream of the gate (the reference cannot know where the moving jump
# is: this L2 measures the depths on both sides of the jump, not the toe's
# position), and the roller (toe to toe + Lr, Hager et al.'s
# Lr = d1 (160 tanh(Fr1 / 20) - 12)) left out, as are the reservoir and the
# weir's crest. Points between the gate and the weir's face only.
#
# usage: tools/lopez-reference.sh RUN (--case 1|2|3 | --d1 D1 --fr1 FR1)
#            [--gate X] [--weir X] [--roller LR] [--times "5 10 15 20 25"]
#            > REF.csv
# then:  build/tools/sluice-analyze l2 RUN --reference REF.csv
#
# RUN is a run directory of `sluice run` (free_surface.csv and
# scene.resolved.yaml). --gate: the first gauge used lies beyond this x
# (default 62, past the gate's 3 dx); --weir: the weir's upstream face
# (default 120); --roller: Lr in m (default Hager's; 0 keeps the roller, with
# d2 from the toe on). Writes `time,x,eta` on stdout and, per time, the toe
# and the point counts on stderr. Exit status 2 on bad input.
set -eu

usage() {
    sed -n '/^# usage:/,/^# then:/p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
}

[ $# -ge 1 ] || usage
case $1 in -h | --help | -*) usage ;; esac
run=$1
shift
d1='' fr1='' gate=62 weir=120 roller='' times="5 10 15 20 25"
while [ $# -gt 0 ]; do
    case $1 in
    --case)
        [ $# -ge 2 ] || usage
        case $2 in
        1) d1=1 fr1=3.8 ;;
        2) d1=1 fr1=5.5 ;;
        3) d1=1 fr1=8.0 ;;
        *) echo "lopez-reference: --case must be 1, 2 or 3" >&2; exit 2 ;;
        esac
        shift 2 ;;
    --d1) [ $# -ge 2 ] || usage; d1=$2; shift 2 ;;
    --fr1) [ $# -ge 2 ] || usage; fr1=$2; shift 2 ;;
    --gate) [ $# -ge 2 ] || usage; gate=$2; shift 2 ;;
    --weir) [ $# -ge 2 ] || usage; weir=$2; shift 2 ;;
    --roller) [ $# -ge 2 ] || usage; roller=$2; shift 2 ;;
    --times) [ $# -ge 2 ] || usage; times=$2; shift 2 ;;
    *) usage ;;
    esac
done
if [ -z "$d1" ] || [ -z "$fr1" ]; then
    echo "lopez-reference: give --case or --d1 and --fr1" >&2
    exit 2
fi
for f in "$run/free_surface.csv" "$run/scene.resolved.yaml"; do
    [ -r "$f" ] || { echo "lopez-reference: cannot read $f" >&2; exit 2; }
done

# the free-surface gauge's positions (one flow list in the resolved scene)
positions=$(awk '
    /^  free_surface_gauge:/ { in_gauge = 1; next }
    in_gauge && /^  [^ ]/ { in_gauge = 0 }
    in_gauge && /^    positions:/ {
        sub(/^    positions: *\[/, ""); sub(/\].*$/, ""); gsub(/ /, ""); print; exit
    }' "$run/scene.resolved.yaml")
[ -n "$positions" ] || { echo "lopez-reference: no free_surface_gauge.positions in $run/scene.resolved.yaml" >&2; exit 2; }

awk -F, -v pos="$positions" -v d1="$d1" -v fr1="$fr1" -v gate="$gate" -v weir="$weir" \
    -v roller="$roller" -v times="$times" '
function tanh(x) { return (exp(x) - exp(-x)) / (exp(x) + exp(-x)) }
BEGIN {
    np = split(pos, x, ",")
    nt = split(times, T, " ")
    d2 = d1 * (sqrt(1 + 8 * fr1 * fr1) - 1) / 2
    lr = (roller == "") ? d1 * (160 * tanh(fr1 / 20) - 12) : roller + 0
    mid = (d1 + d2) / 2
    for (k = 1; k <= nt; k++) best[k] = -1
    printf "# d1 = %g m, Fr1 = %g: d2 = %.4f m (Belanger), roller Lr = %.2f m, toe at eta = %.4f m\n", d1, fr1, d2, lr, mid > "/dev/stderr"
}
NR == 1 {
    if ($1 != "time" || NF - 1 != np) {
        printf "lopez-reference: free_surface.csv has %d gauges, the scene %d\n", NF - 1, np > "/dev/stderr"
        bad = 1; exit 2
    }
    next
}
{
    for (k = 1; k <= nt; k++) {
        d = $1 - T[k]; if (d < 0) d = -d
        if (best[k] < 0 || d < dist[k]) { best[k] = NR; dist[k] = d; row[k] = $0 }
    }
}
END {
    if (bad) exit 2
    print "time,x,eta"
    for (k = 1; k <= nt; k++) {
        if (best[k] < 0) { printf "lopez-reference: no row near t = %s\n", T[k] > "/dev/stderr"; exit 2 }
        n = split(row[k], v, ",")
        toe = ""; prevx = ""; preve = ""
        for (i = 1; i <= np; i++) {
            if (x[i] + 0 <= gate + 0 || x[i] + 0 >= weir + 0) continue
            e = v[i + 1]
            if (e == "nan" || e == "-nan") continue
            if (e + 0 > mid) {
                if (prevx == "") toe = x[i] + 0
                else toe = prevx + (mid - preve) / (e - preve) * (x[i] - prevx)
                break
            }
            prevx = x[i] + 0; preve = e + 0
        }
        n1 = 0; n2 = 0
        for (i = 1; i <= np; i++) {
            xi = x[i] + 0
            if (xi <= gate + 0 || xi >= weir + 0) continue
            if (toe == "" || xi < toe) { printf "%s,%s,%.10g\n", T[k], x[i], d1; n1++ }
            else if (xi >= toe + lr) { printf "%s,%s,%.10g\n", T[k], x[i], d2; n2++ }
        }
        printf "# t = %s s (row at %s s): toe %s, %d points at d1, %d at d2\n", T[k], v[1], (toe == "" ? "none (no jump between gate and weir)" : sprintf("x = %.2f m", toe)), n1, n2 > "/dev/stderr"
    }
}' "$run/free_surface.csv"
