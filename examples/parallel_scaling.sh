#!/usr/bin/env bash
# Strong scaling of the distributed solvers on one mesh: the paper's Table 1 (initialization by
# stage), Table 2 (communication) and Figs. 3/5 (solve time, efficiency T1 / (p Tp)).
#   examples/parallel_scaling.sh MESH [ITERATIONS] [RANKS...]      (default: 40 iterations, ranks 1 2)
# Writes one JSON per run and a Markdown table to $OUT (default: scaling/). Launcher flags come
# from the build's MPIEXEC_PREFLAGS. On a 2-core machine, runs of more than 2 ranks count
# communication and check results; their times mean nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${PALOVERDE_BUILD_DIR:-build}
OUT=${OUT:-scaling}
mesh=$1
iterations=${2:-40}
shift $(( $# >= 2 ? 2 : 1 ))
ranks=${*:-1 2}
preflags=$(sed -n 's/^MPIEXEC_PREFLAGS:STRING=//p' "$BUILD/CMakeCache.txt" | tr ';' ' ')
mkdir -p "$OUT"
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
