#!/bin/sh
# Sluice against DualSPHysics' CPU solver on DualSPHysics' own 3D dam break
# (examples/main/01_DamBreak; Sluice: configs/dam_break_dualsphysics_3d.yaml),
# side by side: the same spacing and end time, 1 and 2 threads, R repeats,
# the two codes interleaved. Prints particle-steps per CPU second and per wall
# second (medians) and the ratio Sluice / DualSPHysics.
#
#   DUALSPHYSICS_DIR=DIR tools/bench-dualsphysics-3d.sh [-d DP] [-t END]
#       [-r REPEATS] [-j "1 2"] [-b BUILD_DIR] [-o OUT_DIR]
#
# DIR holds DualSPHysics5.4CPU_linux64 and GenCase_linux64, or the case
# writer built by tools/peers/dualsphysics-dam-break-3d --build-writer SRC.
# Defaults: DP = 0.017 m (twice the example's 0.0085: about 16k fluid
# particles), END = 0.05 s (about 300 steps), 5 repeats, build/,
# runs/bench-dualsphysics-3d. CPU time is each process's own (getrusage of
# the child), wall time the process's start to end, set-up included, for
# both codes. c0 is DualSPHysics' (coefsound 20 sqrt(g hswl) at this DP),
# passed to Sluice. Both run with OMP_WAIT_POLICY unset unless the caller
# sets it.
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DP=0.017 END=0.05 REPEATS=5 THREADS="1 2" BUILD=$ROOT/build OUT=$ROOT/runs/bench-dualsphysics-3d
while getopts d:t:r:j:b:o: opt; do
    case $opt in
        d) DP=$OPTARG ;; t) END=$OPTARG ;; r) REPEATS=$OPTARG ;; j) THREADS=$OPTARG ;;
        b) BUILD=$OPTARG ;; o) OUT=$OPTARG ;; *) sed -n 2,20p "$0"; exit 2 ;;
    esac
done
: "${DUALSPHYSICS_DIR:?set DUALSPHYSICS_DIR to the directory of DualSPHysics' CPU solver}"
PY=/usr/bin/python3
PEER=$ROOT/tools/peers/dualsphysics-dam-break-3d
mkdir -p "$OUT"
RESULTS=$OUT/results.jsonl
: > "$RESULTS"

# Sluice: the process's CPU time from getrusage of the child, as the peer does
sluice_run() { # threads run_dir c0
    $PY - "$BUILD/sluice" "$ROOT/configs/dam_break_dualsphysics_3d.yaml" "$1" "$2" "$DP" "$END" "$3" <<'EOF'
import json, os, resource, subprocess, sys, time
sluice, scene, threads, run_dir, dp, end, c0 = sys.argv[1:]
cmd = [sluice, "run", scene, "--out", run_dir, "--overwrite", "-q", "--threads", threads,
       "--set", "particles.spacing=" + dp, "--set", "time.end=" + end,
       "--set", "plugins.tait.speed_of_sound=" + c0, "--set", "plugins.hdf5.interval=1e9"]
before = resource.getrusage(resource.RUSAGE_CHILDREN)
start = time.time()
code = subprocess.call(cmd)
wall = time.time() - start
after = resource.getrusage(resource.RUSAGE_CHILDREN)
if code != 0:
    sys.exit("sluice failed (exit %d): %s" % (code, " ".join(cmd)))
run = json.load(open(os.path.join(run_dir, "run.json")))
cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
print(json.dumps({"code": "Sluice", "threads": int(threads), "particles": run["particles_initial"],
                  "steps": run["steps"], "particle_steps": run["particle_steps_this_run"],
                  "cpu_seconds": cpu, "wall_seconds": wall}))
EOF
}

dsph_run() { # threads run_dir
    "$PEER" "$2" --dsph "$DUALSPHYSICS_DIR" --dp "$DP" --end "$END" --threads "$1" >/dev/null ||
        { echo "DualSPHysics failed: $2/run.json" >&2; exit 1; }
    $PY -c 'import json,sys; r=json.load(open(sys.argv[1])); print(json.dumps({k: r[k] for k in
        ("code","threads","particles","steps","particle_steps","cpu_seconds","wall_seconds")}))' "$2/run.json"
}

C0=
for r in $(seq 1 "$REPEATS"); do
    for t in $THREADS; do
        dsph_run "$t" "$OUT/dsph-t$t" >> "$RESULTS"
        [ -n "$C0" ] || C0=$($PY -c 'import json,sys; print(json.load(open(sys.argv[1]))["speed_of_sound"])' "$OUT/dsph-t$t/run.json")
        sluice_run "$t" "$OUT/sluice-t$t" "$C0" >> "$RESULTS"
        echo "repeat $r, $t thread(s): done" >&2
    done
done

$PY - "$RESULTS" "$DP" "$END" "$C0" <<'EOF'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
print("DualSPHysics 01_DamBreak, dp = %s m, end = %s s, c0 = %.3f m/s, %d repeats (medians)"
      % (sys.argv[2], sys.argv[3], float(sys.argv[4]), len(rows) // 2 // len({r["threads"] for r in rows})))
print("| threads | code | particles | steps | particle-steps / CPU s | particle-steps / wall s |")
print("|---|---|---|---|---|---|")
ratio = []
for t in sorted({r["threads"] for r in rows}):
    med = {}
    for code in ("DualSPHysics", "Sluice"):
        sel = [r for r in rows if r["threads"] == t and r["code"] == code]
        cpu = statistics.median(r["particle_steps"] / r["cpu_seconds"] for r in sel)
        wall = statistics.median(r["particle_steps"] / r["wall_seconds"] for r in sel)
        med[code] = (cpu, wall)
        print("| %d | %s | %d | %d | %.3g | %.3g |" % (t, code, sel[0]["particles"],
              statistics.median(r["steps"] for r in sel), cpu, wall))
    ratio.append((t, med["Sluice"][0] / med["DualSPHysics"][0], med["Sluice"][1] / med["DualSPHysics"][1]))
print()
print("| threads | Sluice / DualSPHysics per CPU s | per wall s |")
print("|---|---|---|")
for t, c, w in ratio:
    print("| %d | %.2f | %.2f |" % (t, c, w))
EOF
