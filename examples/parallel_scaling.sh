#!/usr/bin/env bash
# Scaling of the distributed solvers, as the paper reports it.
#
# Strong scaling, one mesh on more and more ranks: Table 1 (initialization by stage), Table 2
# (communication) and Figs. 3/5 (solve time, efficiency T1 / (p Tp)):
#   examples/parallel_scaling.sh MESH [ITERATIONS] [RANKS...]      (default: 40 iterations, ranks 1 2)
#
# Weak scaling, a mesh that grows with the ranks so that each rank keeps about the same number
# of elements (Table 3; efficiency T1 / Tp, T the time per iteration):
#   examples/parallel_scaling.sh --weak SURFACE.off ELEMENTS_PER_RANK [ITERATIONS] [RANKS...]
# For p ranks it makes a mesh of about p x ELEMENTS_PER_RANK tetrahedra with
# `tetgen -pq1.4a<volume>QF SURFACE.off`, the volume bound found in a few tries (TetGen is
# deterministic, so the same arguments give the same meshes), and improves it with the global
# solver through `paloverde run` on p ranks.
#
# Writes one JSON per run and a Markdown table to $OUT (default: scaling/). Launcher flags come
# from the build's MPIEXEC_PREFLAGS; one OpenMP thread per rank. On a 2-core machine, runs of
# more than 2 ranks count communication and check results; their times mean nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${PALOVERDE_BUILD_DIR:-build}
OUT=${OUT:-scaling}
preflags=$(sed -n 's/^MPIEXEC_PREFLAGS:STRING=//p' "$BUILD/CMakeCache.txt" | tr ';' ' ')
mkdir -p "$OUT"

if [[ ${1:-} == --weak ]]; then
  surface=$2
  per_rank=$3
  iterations=${4:-40}
  shift $(( $# >= 4 ? 4 : 3 ))
  ranks=${*:-1 2}
  command -v tetgen > /dev/null || { echo "weak scaling needs tetgen (Debian package tetgen)" >&2; exit 1; }
  stem=$(basename "$surface" .off)
  for p in $ranks; do
    dir="$OUT/weak_${stem}_$p"
    mkdir -p "$dir"
    rm -f "$dir/$stem.off" && cat "$surface" > "$dir/$stem.off"
    # The volume bound for about p x per_rank elements: a first guess from the enclosed volume,
    # then fitted to what TetGen gave, elements = F + C / bound (F: what the quality bound
    # alone makes near the surface), until within 10%.
    python3 - "$dir/$stem.off" $(( p * per_rank )) <<'PY'
import subprocess, sys
off, target = sys.argv[1], int(sys.argv[2])
words = open(off).read().split()
assert words[0] == "OFF", off + ": not an OFF file"
nv, nf = int(words[1]), int(words[2])
xyz = [tuple(map(float, words[4 + 3 * i:7 + 3 * i])) for i in range(nv)]
at, volume = 4 + 3 * nv, 0.0
for _ in range(nf):
    k = int(words[at])
    f = [int(w) for w in words[at + 1:at + 1 + k]]
    at += 1 + k
    for i in range(1, k - 1):  # fan triangles; divergence theorem
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = xyz[f[0]], xyz[f[i]], xyz[f[i + 1]]
        volume += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6.0

def tetgen(bound):
    subprocess.run(["tetgen", f"-pq1.4a{bound:.6g}QF", off], check=True, stdout=subprocess.DEVNULL)
    elements = int(open(off[:-4] + ".1.ele").readline().split()[0])
    print(f"  tetgen -pq1.4a{bound:.6g}QF: {elements} elements (target {target})", file=sys.stderr)
    return elements

tries = []
bound = abs(volume) / target * 2.5  # TetGen's elements average about 0.4 of the bound
for attempt in range(6):
    tries.append((bound, tetgen(bound)))
    if abs(tries[-1][1] - target) <= 0.1 * target:
        break
    if len(tries) == 1:
        bound *= tries[-1][1] / target
        continue
    (b0, n0), (b1, n1) = tries[-2], tries[-1]
    c = (n0 - n1) / (1 / b0 - 1 / b1) if b0 != b1 else 0.0
    floor = n1 - c / b1
    if c <= 0 or target <= floor * 1.05:
        print(f"  the surface alone gives about {int(floor)} elements with q1.4; ask for more per rank", file=sys.stderr)
        break
    bound = c / (target - floor)
bound, elements = min(tries, key=lambda t: abs(t[1] - target))
if tries[-1][0] != bound:
    tetgen(bound)  # the closest try is the mesh to run
open(off[:-4] + ".bound", "w").write(f"{bound:.6g}\n")
PY
    echo "== global on $p rank(s)" >&2
    # output.pieces makes even the 1-rank run a distributed one: every row runs the same code.
    OMP_NUM_THREADS=1 mpiexec -n "$p" $preflags "$BUILD/bin/paloverde" run --json -q \
      --set input.mesh="$dir/$stem.1.node" --set threads=1 --set partition.parts="$p" \
      --set "queue=[improve: {name: global, termination: {max_iterations: $iterations, min_progress: 0}}]" \
      --set output.pieces="$dir/pieces.pvtu" > "$OUT/weak_$p.json"
  done
  python3 - "$OUT" "$surface" $ranks <<'PY'
import json, sys
out, surface, ranks = sys.argv[1], sys.argv[2], [int(r) for r in sys.argv[3:]]
stem = surface.rsplit("/", 1)[-1][:-4]
rows = ["| ranks | tetgen bound | elements | elements per rank | iterations | solve s | s/iteration | weak efficiency T1/Tp | ghost copies | messages | worst before | worst after |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|"]
base = None
for p in ranks:
    j = json.load(open(f"{out}/weak_{p}.json"))
    par = j["parallel"]
    bound = open(f"{out}/weak_{stem}_{p}/{stem}.bound").read().strip()
    solve, iterations = par["seconds"]["solve"], max(1, j["iterations"])
    per_iteration = solve / iterations
    if base is None:
        base = per_iteration
    rows.append(f"| {p} | {bound} | {par['elements']:,} | {par['elements'] // p:,} | {j['iterations']} | {solve:.2f} | "
                f"{per_iteration:.4f} | {base / per_iteration:.2f} | {par['ghost_copies']} | "
                f"{par['messages_per_exchange']} | {j['worst_before']:.4f} | {j['worst_after']:.4f} |")
open(f"{out}/weak_scaling.md", "w").write("\n".join(rows) + "\n")
print("\n".join(rows))
PY
  exit 0
fi

mesh=$1
iterations=${2:-40}
shift $(( $# >= 2 ? 2 : 1 ))
ranks=${*:-1 2}
for method in global local; do
  for p in $ranks; do
    echo "== $method on $p rank(s)" >&2
    OMP_NUM_THREADS=1 mpiexec -n "$p" $preflags "$BUILD/bin/paloverde_parallel_benchmark" "$mesh" \
      --method "$method" --iterations "$iterations" > "$OUT/${method}_$p.json"
  done
done
python3 - "$OUT" $ranks <<'PY'
import json, sys
out, ranks = sys.argv[1], [int(r) for r in sys.argv[2:]]
rows = ["| method | ranks | read s | partition s | distribute s | schedule s | solve s | s/iteration | efficiency T1/(p Tp) | ghost copies | messages | colors | worst before | worst after |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
for method in ("global", "local"):
    base = None
    for p in ranks:
        j = json.load(open(f"{out}/{method}_{p}.json"))
        par, sec = j["parallel"], j["parallel"]["seconds"]
        solve = sec["solve"]
        if p == ranks[0]:
            base = solve * p
        iterations = max(1, j["iterations"])
        rows.append(f"| {method} | {p} | {sec['read']:.2f} | {sec['partition']:.2f} | {sec['distribute']:.2f} | "
                    f"{sec['schedule']:.3f} | {solve:.2f} | {solve / iterations:.3f} | {base / (p * solve):.2f} | "
                    f"{par['ghost_copies']} | {par['messages_per_exchange']} | {par['colors']} | "
                    f"{j['worst_before']:.4f} | {j['worst_after']:.4f} |")
open(f"{out}/scaling.md", "w").write("\n".join(rows) + "\n")
print("\n".join(rows))
PY
