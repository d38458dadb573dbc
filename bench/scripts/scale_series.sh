#!/usr/bin/env bash
# The out-of-core scale series (issue 8): generated assemblies (the study's scene generator at
# scale, streamed to a manifest of parts) and a terrain, preprocessed, then flown with the
# study's object sizes under budgets from 64 MiB to everything resident, prefetch on and off.
# Flights are judged by tetrapage's exact runtime (`generate flight --index`): the in-core oracle
# would need ~150 B a triangle; the 1M and 10M series check the runtime against it.
#
#   bench/scripts/scale_series.sh OUT_DIR [SIZE...]        (default sizes: 1000000 10000000)
#   OBJECTS="4 15000" STEPS=10000 TERRAIN=10000000 bench/scripts/scale_series.sh out/scale 100000000
#
# Writes OUT_DIR/scale.md (Markdown), OUT_DIR/preprocess.md, OUT_DIR/scale.csv and OUT_DIR/plots/*.png (scale_table.py),
# from the JSON reports beside them.
set -euo pipefail
OUT=${1:?usage: scale_series.sh OUT_DIR [SIZE...]}
shift
SIZES=${*:-1000000 10000000}
TETRAPAGE=${TETRAPAGE:-build/tools/tetrapage}
OBJECTS=${OBJECTS:-4 116 500 2000 5000 15000}
STEPS=${STEPS:-10000}
TERRAIN=${TERRAIN:-}           # also a terrain of this many triangles
MEMORY=${MEMORY:-2G}           # preprocess working memory
REGION=${REGION:-}             # --region-triangles (default: preprocess's own); names the folder
mkdir -p "$OUT"

models=()
for N in $SIZES; do models+=("scene:$N"); done
[ -n "$TERRAIN" ] && models+=("terrain:$TERRAIN")

for model in "${models[@]}"; do
  kind=${model%%:*}; N=${model##*:}; D="$OUT/$kind$N${REGION:+-r$REGION}"
  mkdir -p "$D"
  if [ ! -f "$D/model.tpi" ]; then
    if [ "$kind" = scene ]; then
      input="$OUT/$kind$N/model.json"  # one scene for every region size
      mkdir -p "$OUT/$kind$N"
      [ -f "$input" ] || "$TETRAPAGE" generate scene --triangles "$N" --seed 1 -o "$input"
    else
      input="$OUT/$kind$N/model.ply"
      mkdir -p "$OUT/$kind$N"
      [ -f "$input" ] || "$TETRAPAGE" generate terrain --triangles "$N" --seed 1 -o "$input"
    fi
    /usr/bin/time -v "$TETRAPAGE" preprocess "$input" -o "$D/model.tpi" --memory "$MEMORY" \
      ${REGION:+--region-triangles "$REGION"} \
      --report "$D/preprocess.json" 2> "$D/preprocess.time"
  fi
  "$TETRAPAGE" inspect "$D/model.tpi" --stabbing-segments 0 --report "$D/inspect.json" > /dev/null
  # "Under 10 % of the index": 9.5 % of the index file (its decoded shards are larger still).
  file_bytes=$(python3 -c "import json; print(json.load(open('$D/inspect.json'))['file_bytes'])")
  ten_percent=$(( file_bytes * 95 / 1000 ))
  all=64G  # a bound, not an allocation: --preload loads what the shards really take
  for size in $OBJECTS; do
    [ -f "$OUT/object$size.ply" ] || "$TETRAPAGE" generate object --triangles "$size" -o "$OUT/object$size.ply" > /dev/null
    [ -f "$D/flight$size.csv" ] || "$TETRAPAGE" generate flight --index "$D/model.tpi" --memory 1G \
      --object "$OUT/object$size.ply" --steps "$STEPS" --seed "$size" --displacement 0.005 -o "$D/flight$size.csv" \
      --answers "$D/answers$size.csv" > "$D/flight$size.log" 2>&1
    fly() {  # fly NAME MEMORY [flags...]
      local name=$1 memory=$2; shift 2
      "$TETRAPAGE" fly "$D/model.tpi" --object "$OUT/object$size.ply" --path "$D/flight$size.csv" \
        --memory "$memory" --check "$D/answers$size.csv" --report "$D/fly-$name-$size.json" "$@" \
        > "$D/fly-$name-$size.log" 2>&1 || { tail -3 "$D/fly-$name-$size.log" >&2; exit 1; }
    }
    fly all "$all" --preload
    fly 10pct "$ten_percent"
    fly 10pct-noprefetch "$ten_percent" --no-prefetch
    [ "$ten_percent" -gt $((64 << 20)) ] && fly 64m 64M
    echo "$kind $N: object $size done" >&2
  done
done

python3 "$(dirname "$0")/scale_table.py" "$OUT"
