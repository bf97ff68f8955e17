#!/bin/sh
# Bitwise comparison of the reference scenes between two builds: the check
# that a refactoring leaves the physics unchanged (docs/performance.md,
# "Refactoring without changing the physics").
#
#   tools/reference-outputs.sh run BUILD_DIR OUT_DIR    runs every reference scene
#   tools/reference-outputs.sh compare DIR_A DIR_B      compares two such runs
#   tools/reference-outputs.sh against REV [BUILD_DIR]  builds REV in a temporary
#       worktree, runs both and compares (default BUILD_DIR: build)
#
# Each scene runs a short stretch (tens to hundreds of steps) on one thread.
# `compare` requires every HDF5 file to be equal dataset by dataset and
# attribute by attribute (h5diff and h5dump, package hdf5-tools; the plugins'
# file paths a checkpoint records may differ between build trees), every
# CSV table and resolved scene byte for byte, and run.json's work figures (steps,
# particles, pair interactions, neighbour-list rebuilds, largest density
# deviation) to be the same; it prints one line per scene and exits 1 when
# any differs. Timings are not compared. A checkpoint at the end holds the
# whole state: every particle field and every plugin's saved state.
set -eu
cd "$(dirname "$0")/.."

# scene:end time (s)
scenes="dam_break_2d:0.05 dam_break_3d:0.02 dam_break_obstacles_2d:0.04 still_water_2d:0.05
seed000_model:0.03 seed001_model:0.03 seed002_model:0.03 seed004_model:0.03
poiseuille_2d:0.02 open_channel_2d:0.02 inclined_channel_2d:0.02 uniform_channel_2d:0.05
hydraulic_jump_jonsson2016:0.03 abrupt_drop_T1:0.03 lopez2010_case1_3d:0.01
stepped_spillway_cheng:0.01 stepped_chute_chanson:0.01"

run_all() {
    build=$1
    out=$2
    [ -x "$build/sluice" ] || { echo "reference-outputs: no $build/sluice (build first)" >&2; exit 2; }
    mkdir -p "$out"
    for spec in $scenes; do
        name=${spec%:*}
        end=${spec#*:}
        rm -rf "${out:?}/$name"
        if "$build/sluice" run "configs/$name.yaml" --out "$out/$name" --threads 1 \
            --set time.end="$end" --set checkpoint.interval="$end" >"$out/$name.log" 2>&1; then
            echo "ran $name to t = $end s"
        else
            echo "ran $name: exit $? (see $out/$name.log)"
        fi
    done
}

# Two HDF5 files hold the same data: every top-level object equal (h5diff,
# datasets, groups and their attributes) and every attribute equal to the
# last bit (h5dump -A with 17 digits), except where a build's plugins lie:
# checkpoints record each plugin's file, so two build trees differ there.
h5_same() {
    for object in $(h5ls "$1" | awk '{print $1}'); do
        h5diff -q "$1" "$2" "/$object" "/$object" >/dev/null 2>&1 || return 1
    done
    [ "$(h5ls "$1" | awk '{print $1}')" = "$(h5ls "$2" | awk '{print $1}')" ] || return 1
    normalised() {
        h5dump -A -m %.17g "$1" | sed -e 1d -e 's|/[^ "]*/plugins/\([a-z0-9_]*\.so\)|PLUGINS/\1|g'
    }
    [ "$(normalised "$1")" = "$(normalised "$2")" ]
}

work_figures() {
    grep -E '"(status|steps|particles_final|pair_interactions|neighbour_list_rebuilds|max_density_deviation|simulated_time)"' "$1" || true
}

compare_all() {
    a=$1
    b=$2
    command -v h5diff >/dev/null 2>&1 || { echo "reference-outputs: h5diff missing (apt-get install hdf5-tools)" >&2; exit 2; }
    differ=0
    for spec in $scenes; do
        name=${spec%:*}
        verdict=same
        if [ ! -d "$a/$name" ] || [ ! -d "$b/$name" ]; then
            verdict="missing in one of the runs"
        else
            files=$( (cd "$a/$name" && ls; cd "$OLDPWD" && cd "$b/$name" && ls) | sort -u)
            for f in $files; do
                [ "$f" = run.json ] && continue
                if [ ! -f "$a/$name/$f" ] || [ ! -f "$b/$name/$f" ]; then
                    verdict="$f only in one run"
                    break
                fi
                case $f in
                *.h5) h5_same "$a/$name/$f" "$b/$name/$f" || { verdict="$f differs"; break; } ;;
                *) cmp -s "$a/$name/$f" "$b/$name/$f" || { verdict="$f differs"; break; } ;;
                esac
            done
            if [ "$verdict" = same ] &&
                [ "$(work_figures "$a/$name/run.json")" != "$(work_figures "$b/$name/run.json")" ]; then
                verdict="run.json work figures differ"
            fi
        fi
        count=$(ls "$a/$name" 2>/dev/null | wc -l)
        echo "$name: $verdict ($count files)"
        [ "$verdict" = same ] || differ=1
    done
    return $differ
}

case ${1:-} in
run) run_all "$2" "$3" ;;
compare) compare_all "$2" "$3" ;;
against)
    rev=$2
    build=${3:-build}
    tmp=$(mktemp -d)
    git worktree add --detach "$tmp/src" "$rev" >/dev/null
    (cd "$tmp/src" && meson setup "$tmp/build" --buildtype=release -Dtests=false >/dev/null &&
        meson compile -C "$tmp/build" >/dev/null)
    # both builds run the scenes of this tree
    run_all "$tmp/build" "$tmp/before"
    run_all "$build" "$tmp/after"
    status=0
    compare_all "$tmp/before" "$tmp/after" || status=1
    git worktree remove --force "$tmp/src"
    rm -rf "$tmp"
    exit $status
    ;;
*)
    sed -n '2,17p' "$0" >&2
    exit 2
    ;;
esac
