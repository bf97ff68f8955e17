#!/bin/sh
# The core's dependency graph (docs/plugin-abi.md, "The core's layout"):
# which folder of core/ calls which, and which file calls which, from the
# functions each file names and the others define (Universal Ctags). Prints
# the folder graph, the file graph and any circle; exits 1 when there is a
# circle among files or folders.
#
#   tools/core-graph.sh            the graph and the circle check
#   tools/core-graph.sh --files    also every file-to-file edge
set -eu
cd "$(dirname "$0")/.."
command -v ctags >/dev/null 2>&1 || { echo "core-graph: needs ctags (apt-get install universal-ctags)" >&2; exit 2; }
ctags --fields=+nS --kinds-C=f -o - -R core | python3 -c '
import collections, re, sys
show_files = "--files" in sys.argv
defs = {}
for line in sys.stdin:
    parts = line.rstrip("\n").split("\t")
    if len(parts) < 3 or not parts[1].endswith(".c") or re.search(r"/\^\s*static\b", parts[2]):
        continue
    defs.setdefault(parts[0], parts[1])
files = sorted(set(defs.values()) | {f for f in __import__("glob").glob("core/**/*.c", recursive=True)})
ident = re.compile(r"(?<![.>\w])[A-Za-z_]\w*")
edges = collections.defaultdict(set)
for f in files:
    text = open(f, errors="replace").read()
    text = re.sub(r"/\*.*?\*/|//[^\n]*", " ", text, flags=re.S)
    text = re.sub(r"\"(?:[^\"\\\n]|\\.)*\"", " ", text)
    for tok in set(ident.findall(text)):
        g = defs.get(tok)
        if g and g != f:
            edges[f].add(g)
folder = lambda f: f.split("/")[1]
fedges = collections.defaultdict(set)
for a, bs in edges.items():
    for b in bs:
        if folder(a) != folder(b):
            fedges[folder(a)].add(folder(b))
def circles(nodes, e):
    index, low, stack, on, out, i = {}, {}, [], set(), [], [0]
    def sc(v):
        index[v] = low[v] = i[0]; i[0] += 1; stack.append(v); on.add(v)
        for w in sorted(e[v]):
            if w not in index:
                sc(w); low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop(); on.discard(w); comp.append(w)
                if w == v: break
            if len(comp) > 1: out.append(sorted(comp))
    for v in nodes:
        if v not in index: sc(v)
    return out
print("folders of core/ and the folders they call:")
for f in sorted({folder(x) for x in files}):
    print("  %-11s -> %s" % (f, ", ".join(sorted(fedges[f])) or "(nothing)"))
if show_files:
    print("files and the files they call:")
    for f in files:
        print("  %s -> %s" % (f, ", ".join(sorted(edges[f])) or "(nothing)"))
fc = circles(files, edges)
dc = circles(sorted({folder(x) for x in files}), fedges)
print("circles among files: " + ("; ".join(" ".join(c) for c in fc) if fc else "none"))
print("circles among folders: " + ("; ".join(" ".join(c) for c in dc) if dc else "none"))
sys.exit(1 if fc or dc else 0)
' "$@"
