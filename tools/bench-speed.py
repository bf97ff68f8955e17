#!/usr/bin/python3
"""Speed of whole runs (docs/performance.md): particle-steps per CPU second
and per second, bytes per particle and the share of the pair passes spent
on wall targets, for the 3D dam break, seed 002's dam break over an
obstacle (coarse) and the 2D dam break at 86k and 6.5k particles; one
thread and two, OpenMP's active and passive wait policies, medians of
REPEAT runs, the builds given interleaved run by run (so that a busy spell
of a shared machine falls on every build alike).

    tools/bench-speed.py [--repeat N] [--threads 1,2] [--wait active,passive]
                         [--cases a,b] [--out DIR] [BUILD_DIR ...]

Default: build/, 5 repeats, threads 1 and 2, active, every case,
runs/bench-speed/.
Writes DIR/bench.csv (one row per run) and DIR/summary.md (medians). Never
a test: timings depend on the machine.
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# name: (scene, extra arguments); outputs pushed past the end, short runs of
# the flow's first stage (every wall particle present, most still dry)
CASES = {
    # 1 x 0.5 x 2 m column, dx = 0.03 m: 37k fluid of 122k particles
    "dam_break_3d": ("configs/dam_break_3d.yaml",
                     ["--set", "particles.spacing=0.03", "--set", "time.end=0.01",
                      "--set", "plugins.hdf5.interval=1e9",
                      "--set", "plugins.front_gauge.interval=1e9"]),
    # 22k fluid of 74k particles
    "obstacle_3d": ("configs/dam_break_obstacle_3d.yaml",
                    ["--variant", "coarse", "--set", "time.end=0.01",
                     "--set", "plugins.hdf5.interval=1e9"]),
    # dx = 0.005 m: 80k fluid of 86k particles
    "dam_break_2d": ("configs/dam_break_2d.yaml",
                     ["--set", "particles.spacing=0.005", "--set", "time.end=0.02",
                      "--set", "plugins.hdf5.interval=1e9",
                      "--set", "plugins.front_gauge.interval=1e9"]),
    # the scene's own dx = 0.02 m: 5k fluid of 6.5k particles
    "dam_break_2d_small": ("configs/dam_break_2d.yaml",
                           ["--set", "time.end=0.25", "--set", "plugins.hdf5.interval=1e9",
                            "--set", "plugins.front_gauge.interval=1e9"]),
}


def run_once(build, case, threads, wait, work):
    scene, extra = CASES[case]
    out = os.path.join(work, "run")
    cmd = [os.path.join(build, "sluice"), "run", os.path.join(ROOT, scene), "--out", out,
           "--overwrite", "-q", "--threads", str(threads)] + extra
    # sluice run keeps a wait policy set in the environment
    env = dict(os.environ, OMP_WAIT_POLICY=wait)
    usage0 = os.times()
    proc = subprocess.run(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)
    usage1 = os.times()
    if proc.returncode != 0:
        sys.exit("bench-speed: %s failed:\n%s" % (" ".join(cmd), proc.stderr))
    with open(os.path.join(out, "run.json")) as f:
        run = json.load(f)
    cpu = (usage1.children_user - usage0.children_user) + \
          (usage1.children_system - usage0.children_system)
    steps = run["particle_steps_this_run"]
    # absent from builds before these figures: nan
    nan = float("nan")
    kinds = run.get("pair_seconds_by_target_kind", {"wall": nan, "fluid": nan})
    kind_pairs = run.get("pair_interactions_by_target_kind", {"wall": nan, "fluid": nan})
    pair_seconds = sum(kinds.values())
    return {
        "build": build, "case": case, "threads": threads, "wait": wait,
        "particles": run["particles_initial"], "steps": run["steps"],
        "wall_s": run["wall_seconds"], "cpu_s": cpu,
        "particle_steps_per_s": run["particle_steps_per_second"],
        # the process's CPU time, set-up included (small against the steps)
        "particle_steps_per_cpu_s": steps / cpu if cpu > 0 else 0,
        "pairs_per_s": run["pair_interactions_per_second"],
        "bytes_per_particle": run["state_bytes_per_particle"],
        "wall_pairs_share": kind_pairs["wall"] / max(1, sum(kind_pairs.values())),
        # thread-seconds of the pair passes on wall targets over the run's
        # thread-seconds
        "wall_target_share": kinds["wall"] / (run["wall_seconds"] * threads),
        "pair_pass_share": pair_seconds / (run["wall_seconds"] * threads),
        "rebuilds": run["neighbour_list_rebuilds"],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("builds", nargs="*", default=["build"])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--wait", default="active")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--out", default=os.path.join(ROOT, "runs", "bench-speed"))
    a = ap.parse_args()
    cases = a.cases.split(",")
    for c in cases:
        if c not in CASES:
            sys.exit("bench-speed: unknown case '%s' (cases: %s)" % (c, ", ".join(CASES)))
    threads = [int(t) for t in a.threads.split(",")]
    waits = a.wait.split(",")
    for w in waits:
        if w not in ("active", "passive"):
            sys.exit("bench-speed: --wait takes active and/or passive")
    for b in a.builds:
        if not os.access(os.path.join(b, "sluice"), os.X_OK):
            sys.exit("bench-speed: no %s/sluice; build first (meson compile -C %s)" % (b, b))
    os.makedirs(a.out, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-speed.") as work:
        for r in range(a.repeat):
            for case in cases:
                for t in threads:
                    for wait in waits:
                        for b in a.builds:
                            row = run_once(b, case, t, wait, work)
                            row["repeat"] = r
                            rows.append(row)
                            print("%s %s %d thread(s) %s #%d: %.3g particle-steps per CPU s, "
                                  "%.3g per s" % (b, case, t, wait, r,
                                                  row["particle_steps_per_cpu_s"],
                                                  row["particle_steps_per_s"]), flush=True)
    fields = list(rows[0].keys())
    with open(os.path.join(a.out, "bench.csv.tmp"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
    os.replace(os.path.join(a.out, "bench.csv.tmp"), os.path.join(a.out, "bench.csv"))
    lines = ["| build | case | threads | wait | particles | particle-steps / CPU s | particle-steps / s"
             " | pairs / s | bytes / particle | pair passes: share of the run | wall targets:"
             " share of the run | wall targets: share of pairs |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for case, t, wait, b in [(c, t, w, b) for c in cases for t in threads for w in waits
                             for b in a.builds]:
        sel = [x for x in rows if x["case"] == case and x["threads"] == t and x["wait"] == wait
               and x["build"] == b]
        med = {k: statistics.median(x[k] for x in sel) for k in
               ("particle_steps_per_cpu_s", "particle_steps_per_s", "pairs_per_s",
                "bytes_per_particle", "pair_pass_share", "wall_target_share", "wall_pairs_share")}
        lines.append("| %s | %s | %d | %s | %d | %.3g | %.3g | %.3g | %.0f | %.2f | %.2f | %.2f |" %
                     (b, case, t, wait, sel[0]["particles"], med["particle_steps_per_cpu_s"],
                      med["particle_steps_per_s"], med["pairs_per_s"], med["bytes_per_particle"],
                      med["pair_pass_share"], med["wall_target_share"], med["wall_pairs_share"]))
    text = "\n".join(lines) + "\n"
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write(text)
    print(text)


if __name__ == "__main__":
    main()
