#!/usr/bin/env bash
# Benchmark meshes at the seed paper's scale, made reproducibly with TetGen from the CAD surface
# ../shared/data/surfaces/fandisk.off (TetGen is deterministic: the same flags give the same mesh):
#   examples/benchmark_meshes.sh [SIZE...]          SIZE: 100k 1M 2M 9M (default: 100k 2M)
# For each size writes to $OUT (default: bench/):
#   fandisk-SIZE.node/.ele     the mesh (TetGen -pq1.4a<volume>QF: quality 1.4, volume bound)
#   fandisk-SIZE-boundary.vtu  tangled as the paper did: 5% of the boundary vertices moved by up to
#                              0.3 local edge lengths (seed 1), so that some elements invert
#   fandisk-SIZE-interior.vtu  tangled inside: 30% of the interior vertices moved by up to 0.5
#                              local edge lengths (seed 1)
# and prints each mesh's vertices, elements and inverted elements. Meshes are generated, never
# committed. 9M takes about 2 GB and a few minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${PALOVERDE_BUILD_DIR:-build}
OUT=${OUT:-bench}
SURFACE=${SURFACE:-../shared/data/surfaces/fandisk.off}
sizes=${*:-100k 2M}

# The volume bound for each size, measured on fandisk.off. Large meshes have about 0.3 / bound
# tets; small ones more, as the surface's own triangles and the quality bound add tets.
volume_bound() {
  case $1 in
    100k) echo 2e-5 ;;    # 99,997 tets
    1M) echo 3.2e-7 ;;    # 1,073,114 tets
    2M) echo 1.6e-7 ;;    # 1,966,509 tets (the paper's "support": 1.87M)
    9M) echo 3e-8 ;;      # 9,369,607 tets (the paper's "flange": 8.9M)
    *) echo "unknown size '$1' (known: 100k 1M 2M 9M)" >&2; return 2 ;;
  esac
}

command -v tetgen >/dev/null || { echo "tetgen is missing: apt-get install tetgen (scripts/setup.sh does)" >&2; exit 1; }
[ -x "$BUILD/bin/paloverde" ] || { echo "$BUILD/bin/paloverde is missing: bash scripts/setup.sh build" >&2; exit 1; }
mkdir -p "$OUT"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
for size in $sizes; do
  bound=$(volume_bound "$size")
  mesh="$OUT/fandisk-$size"
  if [ ! -s "$mesh.ele" ]; then
    echo "== fandisk-$size: tetgen -pq1.4a${bound}QF" >&2
    cp "$SURFACE" "$scratch/fandisk.off"
    tetgen -pq1.4a"${bound}"QF "$scratch/fandisk.off" >&2
    # Written to the scratch folder, then moved: an interrupted run leaves no half mesh behind.
    mv "$scratch/fandisk.1.node" "$mesh.node"
    mv "$scratch/fandisk.1.ele" "$mesh.ele"
  fi
  "$BUILD/bin/paloverde" perturb "$mesh.node" -o "$mesh-boundary.vtu" --only-boundary --fraction 0.05 \
    --amount 0.3 --seed 1 --json > "$scratch/boundary.json"
  "$BUILD/bin/paloverde" perturb "$mesh.node" -o "$mesh-interior.vtu" --fraction 0.3 --amount 0.5 \
    --seed 1 --json > "$scratch/interior.json"
  python3 - "$mesh" "$scratch" <<'PY'
import json, sys
mesh, scratch = sys.argv[1], sys.argv[2]
for variant in ("boundary", "interior"):
    j = json.load(open(f"{scratch}/{variant}.json"))
    print(f"{mesh}-{variant}.vtu: {j['elements']} elements, {j['moved']} vertices moved, {j['inverted']} inverted")
PY
done
