#!/usr/bin/env bash
# The peer comparison of issue 5: one scene and its index, the study's object sizes, a
# 10,000-step billiard flight each with the oracle's answers, replayed by tetrapage_bench_peers
# through FCL, CGAL's AABB tree and tetrapage (in memory, and paged under BUDGET), REPEATS times.
# Writes OUT/peers.md: per object size and collider, the median of each timing over the
# repetitions (and the spread of steps/s), next to the answers' disagreements.
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
    --object "$OUT/object$SIZE.ply" --steps "$STEPS" --seed 1 -o "$OUT/flight$SIZE.csv" \
    --answers "$OUT/answers$SIZE.csv" --report "$OUT/flight$SIZE.json"
  for R in $(seq 1 "$REPEATS"); do
    "$BENCH" "$SCENE_DIR/scene.ply" "$OUT/object$SIZE.ply" "$OUT/flight$SIZE.csv" "$OUT/answers$SIZE.csv" \
      "$SCENE_DIR/scene.tpi" --memory "$BUDGET" --report "$OUT/peers$SIZE-$R.json" > "$OUT/peers$SIZE-$R.md" \
      2> /dev/null
    echo "object $SIZE: repetition $R of $REPEATS done (load average $(cut -d' ' -f1 /proc/loadavg))" >&2
  done
done

python3 - "$OUT" "$REPEATS" "$SIZES" <<'PY'
import json, statistics, sys
out, repeats, sizes = sys.argv[1], int(sys.argv[2]), [int(s) for s in sys.argv[3].split()]
rows = ["| object | collider | build s | build RSS MiB | structures MiB | peak RSS MiB | steps/s (min-max) | p50 us | p95 us | p99 us | max us | collisions | FN / FP vs oracle | FN / FP vs exact, same question |",
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
ratios = ["| object | tetrapage in memory / best peer: steps/s | p99 | best peer | paged / in memory: steps/s |",
          "|---:|---:|---:|---|---:|"]
def text(d, key):
    if key not in d: return "-"
    return f"{d[key]['false_negatives']} / {d[key]['false_positives']}"
for size in sizes:
    reports = [json.load(open(f"{out}/peers{size}-{r}.json")) for r in range(1, repeats + 1)]
    names = [run["collider"] for run in reports[0]["runs"]]
    median = {}
    for i, name in enumerate(names):
        runs = [rep["runs"][i] for rep in reports]
        med = lambda f: statistics.median(f(run) for run in runs)
        rates = [run["steps_per_second"] for run in runs]
        median[name] = {"rate": med(lambda r: r["steps_per_second"]), "p99": med(lambda r: r["latency_us"]["p99"])}
        answers = {(r["collisions"], text(r["disagreements"], "oracle"), text(r["disagreements"], "same_question")) for r in runs}
        collisions, oracle, same = sorted(answers)[0] if len(answers) == 1 else ("varies", "varies", "varies")
        structures = med(lambda r: r['structure_bytes'])
        structures = f"{structures / 2**20:.1f}" if structures > 0 else "-"
        rows.append(f"| {size} | {name} | {med(lambda r: r['build_seconds']):.2f} | {med(lambda r: r['build_rss_growth_bytes']) / 2**20:.1f} | {structures} | "
                    f"{med(lambda r: r['peak_rss_bytes']) / 2**20:.1f} | {statistics.median(rates):.0f} ({min(rates):.0f}-{max(rates):.0f}) | "
                    f"{med(lambda r: r['latency_us']['p50']):.1f} | {med(lambda r: r['latency_us']['p95']):.1f} | "
                    f"{med(lambda r: r['latency_us']['p99']):.1f} | {med(lambda r: r['latency_us']['max']):.0f} | "
                    f"{collisions} | {oracle} | {same} |")
    peers = [n for n in names if not n.startswith("tetrapage")]
    best = max(peers, key=lambda n: median[n]["rate"])
    if "tetrapage" in median:
        paged = f"{median['tetrapage-paged']['rate'] / median['tetrapage']['rate']:.2f}x" if "tetrapage-paged" in median else "-"
        ratios.append(f"| {size} | {median['tetrapage']['rate'] / median[best]['rate']:.2f}x | "
                      f"{median['tetrapage']['p99'] / median[best]['p99']:.2f}x | {best} | {paged} |")
text_out = "\n".join(rows) + "\n\n" + "\n".join(ratios) + "\n"
open(f"{out}/peers.md", "w").write(text_out)
print(text_out)
PY
