#!/usr/bin/env bash
# The peer comparison of issue 5: one scene and its index, the study's object sizes, a
# 10,000-step billiard flight each with the oracle's answers, replayed by tetrapage_bench_peers
# through FCL, CGAL's AABB tree and tetrapage (in memory, and paged under BUDGET), REPEATS times.
# Writes OUT/peers.md (peers_table.py): per object size and collider, the median of each timing
# over the repetitions (and the spread of steps/s), next to the answers' disagreements.
#
#   bench/scripts/peers_series.sh SCENE_DIR OUT_DIR [BUDGET] [REPEATS] [SIZES]
#
# SCENE_DIR holds scene.ply and scene.tpi (`make demo` makes them in out/demo); objects and
# flights are generated into OUT_DIR when missing (seed 1, as `make demo` does). SCENE_DIR is
# only read.
set -euo pipefail
SCENE_DIR=${1:?SCENE_DIR}
OUT=${2:?OUT_DIR}
BUDGET=${3:-8M}
REPEATS=${4:-3}
SIZES=${5:-4 116 500 2000 5000}
BUILD=${BUILD:-build}
TETRAPAGE=${TETRAPAGE:-$BUILD/tools/tetrapage}
BENCH=${BENCH:-$BUILD/bench/tetrapage_bench_peers}
STEPS=${STEPS:-10000}
mkdir -p "$OUT"

for SIZE in $SIZES; do
  [ -f "$OUT/object$SIZE.ply" ] || "$TETRAPAGE" generate object --triangles "$SIZE" -o "$OUT/object$SIZE.ply"
  [ -f "$OUT/flight$SIZE.csv" ] || "$TETRAPAGE" generate flight --env "$SCENE_DIR/scene.ply" \
    --object "$OUT/object$SIZE.ply" --steps "$STEPS" --seed 1 --displacement 0.005 -o "$OUT/flight$SIZE.csv" \
    --answers "$OUT/answers$SIZE.csv" --report "$OUT/flight$SIZE.json"
  for R in $(seq 1 "$REPEATS"); do
    "$BENCH" "$SCENE_DIR/scene.ply" "$OUT/object$SIZE.ply" "$OUT/flight$SIZE.csv" "$OUT/answers$SIZE.csv" \
      "$SCENE_DIR/scene.tpi" --memory "$BUDGET" --report "$OUT/peers$SIZE-$R.json" > "$OUT/peers$SIZE-$R.md" \
      2> /dev/null
    echo "object $SIZE: repetition $R of $REPEATS done (load average $(cut -d' ' -f1 /proc/loadavg))" >&2
  done
done

cells=()
for SIZE in $SIZES; do cells+=(--cell "$OUT/peers$SIZE" "$SIZE"); done
python3 "$(dirname "$0")/peers_table.py" "$OUT/peers.md" --repeats "$REPEATS" "${cells[@]}"
