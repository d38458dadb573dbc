#!/usr/bin/env bash
# The paged-runtime flight series (issue 5): one generated scene, the study's six object sizes,
# a 10,000-step billiard flight each, flown with everything resident and with a budget of a
# fraction of the index's shard bytes; the reference oracle's replay on the same poses beside.
#
#   bench/scripts/flight_series.sh [TRIANGLES] [OUT_DIR] [BUDGET_FRACTION]
#
# PREPROCESS_FLAGS adds flags to the preprocess (e.g. "--compression none", whose page-ins
# decompress nothing: docs/BENCHMARKS.md, "A page-in, phase by phase").
#
# Writes OUT_DIR/series.md (a Markdown table) and the JSON reports it was made from.
set -euo pipefail
TRIANGLES=${1:-10000000}
OUT=${2:-out/flight-series}
FRACTION=${3:-0.10}
TETRAPAGE=${TETRAPAGE:-build/tools/tetrapage}
STEPS=${STEPS:-10000}
mkdir -p "$OUT"

if [ ! -f "$OUT/scene.ply" ]; then
  "$TETRAPAGE" generate scene --triangles "$TRIANGLES" --seed 1 -o "$OUT/scene.ply"
fi
if [ ! -f "$OUT/scene.tpi" ]; then
  /usr/bin/time -v "$TETRAPAGE" preprocess "$OUT/scene.ply" -o "$OUT/scene.tpi" ${PREPROCESS_FLAGS:-} \
    --report "$OUT/preprocess.json" 2> "$OUT/preprocess.time"
fi
"$TETRAPAGE" inspect "$OUT/scene.tpi" --report "$OUT/inspect.json"
SHARD_BYTES=$(python3 -c "import json; print(json.load(open('$OUT/inspect.json'))['shard_decoded_bytes'])")
BUDGET=$(python3 -c "print(int($SHARD_BYTES * $FRACTION))")
ALL=$(python3 -c "print(int($SHARD_BYTES * 2 + (64 << 20)))")

for SIZE in 4 116 500 2000 5000 15000; do
  [ -f "$OUT/object$SIZE.ply" ] || "$TETRAPAGE" generate object --triangles $SIZE -o "$OUT/object$SIZE.ply"
  [ -f "$OUT/flight$SIZE.csv" ] || "$TETRAPAGE" generate flight --env "$OUT/scene.ply" --object "$OUT/object$SIZE.ply" \
    --steps "$STEPS" --seed $SIZE --displacement 0.005 -o "$OUT/flight$SIZE.csv" --answers "$OUT/answers$SIZE.csv"
  "$TETRAPAGE" replay "$OUT/scene.ply" --object "$OUT/object$SIZE.ply" --path "$OUT/flight$SIZE.csv" \
    --report "$OUT/replay$SIZE.json" > /dev/null 2>&1
  "$TETRAPAGE" fly "$OUT/scene.tpi" --object "$OUT/object$SIZE.ply" --path "$OUT/flight$SIZE.csv" \
    --memory "$ALL" --check "$OUT/answers$SIZE.csv" --report "$OUT/fly-all$SIZE.json" > /dev/null 2>&1
  "$TETRAPAGE" fly "$OUT/scene.tpi" --object "$OUT/object$SIZE.ply" --path "$OUT/flight$SIZE.csv" \
    --memory "$BUDGET" --check "$OUT/answers$SIZE.csv" --report "$OUT/fly-budget$SIZE.json" > /dev/null 2>&1
  echo "object $SIZE done" >&2
done

python3 - "$OUT" "$FRACTION" <<'PY'
import json, sys
out, fraction = sys.argv[1], float(sys.argv[2])
rows = ["| object | run | steps/s | p50 us | p99 us | max us | collisions | page-ins | hit rate | peak shard MiB | budget MiB | disagreements |",
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
for size in [4, 116, 500, 2000, 5000, 15000]:
    r = json.load(open(f"{out}/replay{size}.json"))
    rows.append(f"| {size} | oracle (CGAL AABB tree, in core) | {r['steps_per_second']:.0f} | {r['latency_us']['p50']:.1f} | {r['latency_us']['p99']:.1f} | {r['latency_us']['max']:.0f} | {r['collisions']} | - | - | - | - | - |")
    for name, label in (("all", "fly, all resident"), ("budget", f"fly, budget {fraction:.0%} of shards")):
        f = json.load(open(f"{out}/fly-{name}{size}.json"))
        rows.append(f"| {size} | {label} | {f['steps_per_second']:.0f} | {f['latency_us']['p50']:.1f} | {f['latency_us']['p99']:.1f} | {f['latency_us']['max']:.0f} | {f['collisions']} | {f['page_ins']} | {f['cache_hit_rate']:.4f} | {f['peak_resident_shard_bytes']/2**20:.1f} | {f['budget_bytes']/2**20:.1f} | {f['disagreements']} |")
open(f"{out}/series.md", "w").write("\n".join(rows) + "\n")
print("\n".join(rows))
PY
