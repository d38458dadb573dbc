#!/usr/bin/env bash
# Tessellation as a knob of the accuracy trade (issue 26, item 2; `make bench-deflection`): a STEP
# environment and a STEP flying object tessellated at each of DEFLECTIONS, indexed and flown
# along one billiard flight; the answers are compared with the reference oracle's over the
# finest tessellation (REFERENCE), which stands for the exact B-rep. Per deflection: the
# triangles, the index's bytes per triangle and on disk, steps per second in memory (median of
# REPEATS passes), false negatives (the reference collides, the coarser model does not) and
# false positives.
#
#   bench/scripts/deflection_series.sh [OUT_DIR]   (default: $BUILD/bench-results/deflection)
#
# Environment variables (defaults in brackets):
#   ENV [occt-misc's linkrods.step]  OBJECT [occt-misc's bearing.iges]
#   DEFLECTIONS [1% 0.3% 0.1% 0.05%]  REFERENCE [0.02%]  STEPS [5000]  REPEATS [3]
#   DISPLACEMENT [1 % of the environment's diagonal]  BUILD [build]
#   TETRAPAGE [$BUILD/tools/tetrapage]
set -euo pipefail
BUILD=${BUILD:-build}
OUT=${1:-$BUILD/bench-results/deflection}
TETRAPAGE=${TETRAPAGE:-$BUILD/tools/tetrapage}
ENV=${ENV:-/usr/share/opencascade/data/step/linkrods.step}
OBJECT=${OBJECT:-/usr/share/opencascade/data/iges/bearing.iges}
DEFLECTIONS=${DEFLECTIONS:-"1% 0.3% 0.1% 0.05%"}
REFERENCE=${REFERENCE:-0.02%}
STEPS=${STEPS:-5000}
REPEATS=${REPEATS:-3}
mkdir -p "$OUT"

echo "reference: $ENV and $OBJECT at --deflection $REFERENCE"
"$TETRAPAGE" mesh convert "$ENV" --deflection "$REFERENCE" -o "$OUT/reference_env.ply" >/dev/null
"$TETRAPAGE" mesh convert "$OBJECT" --deflection "$REFERENCE" -o "$OUT/reference_object.ply" >/dev/null
"$TETRAPAGE" mesh info "$OUT/reference_env.ply" --report "$OUT/reference_env.json" >/dev/null
DISPLACEMENT=${DISPLACEMENT:-$(python3 -c "
import json, math
b = json.load(open('$OUT/reference_env.json'))['files'][0]['bounds']
print(0.01 * math.dist(b['lo'], b['hi']))")}
echo "flight: $STEPS poses, displacement $DISPLACEMENT, answered by the oracle over the reference"
"$TETRAPAGE" generate flight --env "$OUT/reference_env.ply" --object "$OUT/reference_object.ply" \
  --steps "$STEPS" --seed 1 --displacement "$DISPLACEMENT" -o "$OUT/flight.csv" \
  --answers "$OUT/reference_answers.csv" >/dev/null

for d in $DEFLECTIONS; do
  name=${d//%/pct}
  "$TETRAPAGE" preprocess "$ENV" --deflection "$d" -o "$OUT/env_$name.tpi" \
    --report "$OUT/preprocess_$name.json" >/dev/null
  "$TETRAPAGE" mesh info "$OBJECT" --deflection "$d" --report "$OUT/object_$name.json" >/dev/null
  for r in $(seq 1 "$REPEATS"); do
    "$TETRAPAGE" fly "$OUT/env_$name.tpi" --object "$OBJECT" --deflection "$d" --path "$OUT/flight.csv" \
      --preload --memory 8G --answers "$OUT/answers_$name.csv" --report "$OUT/fly_${name}_$r.json" >/dev/null
  done
  echo "deflection $d done"
done

python3 - "$OUT" "$REPEATS" $DEFLECTIONS <<'EOF'
import csv, json, statistics, sys
out, repeats, deflections = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
def answers(path):
    with open(path) as f:
        return [int(row['collides']) for row in csv.DictReader(f)]
reference = answers(f'{out}/reference_answers.csv')
collisions = sum(reference)
rows = ['| deflection | used (mm) | env triangles | object triangles | index bytes/triangle | index MB | steps/s in memory | false negatives | false positives |',
        '|---|---:|---:|---:|---:|---:|---:|---:|---:|']
for d in deflections:
    name = d.replace('%', 'pct')
    pre = json.load(open(f'{out}/preprocess_{name}.json'))
    obj = json.load(open(f'{out}/object_{name}.json'))['files'][0]
    rates = [json.load(open(f'{out}/fly_{name}_{r}.json'))['steps_per_second'] for r in range(1, repeats + 1)]
    got = answers(f'{out}/answers_{name}.csv')
    fn = sum(1 for a, b in zip(reference, got) if a and not b)
    fp = sum(1 for a, b in zip(reference, got) if b and not a)
    rows.append(f"| {d} | {pre['tessellation_deflection']:.4g} | {pre['triangles_read']:,} | {obj['triangles']:,} | "
                f"{pre['bytes_per_triangle']:.1f} | {pre['bytes_written'] / 1e6:.2f} | {statistics.median(rates):,.0f} | "
                f"{fn} ({fn / max(collisions, 1):.2%}) | {fp} ({fp / max(len(reference) - collisions, 1):.2%}) |")
text = '\n'.join(rows)
text += f"\n\n{len(reference)} poses, {collisions} colliding by the reference; false negatives as a share of those, false positives of the free ones.\n"
open(f'{out}/deflection.md', 'w').write(text)
print(text)
EOF
