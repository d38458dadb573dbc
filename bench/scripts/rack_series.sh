#!/usr/bin/env bash
# Real CAD parts (issue 26, item 8; `make bench-rack`): racks of boards populated with KiCad's
# STEP packages (`tetrapage generate rack`), for each size: generate, then preprocess (STEP read,
# tessellation, index build: the --report's triangles per second), index bytes per triangle, and
# two flights of a real connector (KiCad's 2x05 socket): its insertion into a board's header
# (the generator's poses) and a billiard flight through the rack (`generate flight --index`,
# decided by the exact runtime). Each flight is flown by `tetrapage fly --preload` (in memory)
# and `tetrapage fly` paged under 10 % of the index file, and, up to PEERS_MAX triangles, by
# tetrapage_bench_peers with FCL and CGAL beside tetrapage on the same poses (the flattened rack,
# `mesh convert`; CGAL's run is the harness's oracle and every disagreement is counted).
# REPEATS passes; rack.md gives medians and the spread.
#
#   bench/scripts/rack_series.sh [OUT_DIR]     (default: $BUILD/bench-results/rack)
#
# Environment variables (defaults in brackets; a small run: SIZES=100000 STEPS=300 REPEATS=1):
#   SIZES [1000000 10000000]  REPEATS [3]  STEPS [5000] (billiard poses)  INSERT_STEPS [400]
#   DISPLACEMENT [1] (mm per billiard step)  SEED [1]  PARTS [/usr/share/kicad/3dmodels]
#   PEERS_MAX [10000000]: larger racks are flown by tetrapage alone (FCL and CGAL hold the whole
#     model in memory)  COLLIDERS [fcl,cgal,tetrapage,tetrapage-paged]
#   FLAT [0]: 0 writes the rack as nested manifests (one per board type); 1 runs
#     `generate rack --flat` (one manifest of mesh entries)
#   GENERATE_FLAGS, PREPROCESS_FLAGS [none]: added to those commands
#   BUILD [build], TETRAPAGE [$BUILD/tools/tetrapage], BENCH [$BUILD/bench/tetrapage_bench_peers]
# Racks, indexes and flights are reused by the next run (delete a size's folder to redo it); the
# timed runs are redone every time.
set -euo pipefail
BUILD=${BUILD:-build}
OUT=${1:-$BUILD/bench-results/rack}
TETRAPAGE=${TETRAPAGE:-$BUILD/tools/tetrapage}
BENCH=${BENCH:-$BUILD/bench/tetrapage_bench_peers}
SIZES=${SIZES:-1000000 10000000}
REPEATS=${REPEATS:-3}
STEPS=${STEPS:-5000}
INSERT_STEPS=${INSERT_STEPS:-400}
DISPLACEMENT=${DISPLACEMENT:-1}
SEED=${SEED:-1}
PARTS=${PARTS:-/usr/share/kicad/3dmodels}
PEERS_MAX=${PEERS_MAX:-10000000}
COLLIDERS=${COLLIDERS:-fcl,cgal,tetrapage,tetrapage-paged}
FLAT=${FLAT:-0}
GENERATE_FLAGS=${GENERATE_FLAGS:-}
[ "$FLAT" = 0 ] || GENERATE_FLAGS="--flat $GENERATE_FLAGS"
PREPROCESS_FLAGS=${PREPROCESS_FLAGS:-}
PLUG=$PARTS/Connector_PinSocket_2.54mm.3dshapes/PinSocket_2x05_P2.54mm_Vertical.step
SCRIPTS=$(cd "$(dirname "$0")" && pwd)

say() { echo "rack: $*" >&2; }
die() { say "error: $*"; exit 1; }
loadavg() { cut -d' ' -f1-3 /proc/loadavg; }
short() { local n=$1; if (( n % 1000000 == 0 )); then echo "$((n / 1000000))m"; elif (( n % 1000 == 0 )); then echo "$((n / 1000))k"; else echo "$n"; fi; }
# timed LOG TIMES COMMAND...: output into LOG, "seconds peak_kib" into TIMES; on failure LOG's end
timed() {
  local log=$1 times=$2; shift 2
  /usr/bin/time -f '%e %M' -o "$times" "$@" > "$log" 2>&1 || { tail -5 "$log" >&2; die "failed ($log): $*"; }
}

[ -x "$TETRAPAGE" ] || die "no $TETRAPAGE (make build, or set BUILD / TETRAPAGE)"
[ -d "$PARTS" ] || die "no $PARTS: install Debian's kicad-packages3d (make bench-rack does)"
[ -f "$PLUG" ] || die "no $PLUG (the flying connector)"
for n in $SIZES $REPEATS $STEPS $INSERT_STEPS; do [[ $n =~ ^[1-9][0-9]*$ ]] || die "not a positive count: '$n'"; done
mkdir -p "$OUT"
load_start=$(loadavg)
start_seconds=$SECONDS

names=()
for N in $SIZES; do
  name=rack$(short "$N"); D="$OUT/$name"; names+=("$name")
  mkdir -p "$D"
  if [ ! -f "$D/generate.json" ]; then
    say "$name: generating ($N triangles, seed $SEED)"
    timed "$D/generate.log" "$D/generate.time" "$TETRAPAGE" generate rack --triangles "$N" --seed "$SEED" \
      --parts-folder "$PARTS" -o "$D/rack.json" --report "$D/generate.json" $GENERATE_FLAGS
  fi
  if [ ! -f "$D/preprocess.json" ]; then
    say "$name: preprocessing (STEP read, tessellation, index)"
    timed "$D/preprocess.log" "$D/preprocess.time" "$TETRAPAGE" preprocess "$D/rack.json" -o "$D/rack.tpi" \
      --report "$D/preprocess.json" $PREPROCESS_FLAGS
  fi
  if (( N <= PEERS_MAX )) && [ ! -f "$D/rack.ply" ] && [ -x "$BENCH" ]; then
    say "$name: flattening to rack.ply for the peers"
    timed "$D/convert.log" "$D/convert.time" "$TETRAPAGE" mesh convert "$D/rack.json" -o "$D/rack.ply"
  fi
  if [ ! -f "$D/billiard-$STEPS.csv" ]; then
    say "$name: billiard flight of the socket, $STEPS steps of $DISPLACEMENT mm (the runtime decides)"
    timed "$D/billiard.log" "$D/billiard.time" "$TETRAPAGE" generate flight --index "$D/rack.tpi" --memory 4G \
      --object "$PLUG" --steps "$STEPS" --seed 1 --displacement "$DISPLACEMENT" -o "$D/billiard-$STEPS.csv" \
      --report "$D/billiard.json"
  fi
  [ -f "$D/rack-insert.csv" ] || die "$name: the generator wrote no insertion flight"
done

for R in $(seq 1 "$REPEATS"); do
  for name in "${names[@]}"; do
    D="$OUT/$name"; N=$(python3 -c "import json; print(json.load(open('$D/generate.json'))['target_triangles'])")
    budget=$(( $(stat -c %s "$D/rack.tpi") / 10 ))
    for flight in insert billiard; do
      F=$D/rack-insert.csv; [ $flight = insert ] || F=$D/billiard-$STEPS.csv
      P="$D/runs/$flight-$R"; mkdir -p "$D/runs"
      say "pass $R/$REPEATS, $name, $flight: tetrapage fly in memory and paged under $budget bytes (load $(loadavg))"
      timed "$P.mem.log" "$P.mem.time" "$TETRAPAGE" fly "$D/rack.tpi" --object "$PLUG" --path "$F" --preload --memory 1T \
        --answers "$P.mem.answers.csv" --report "$P.mem.json"
      timed "$P.paged.log" "$P.paged.time" "$TETRAPAGE" fly "$D/rack.tpi" --object "$PLUG" --path "$F" \
        --memory "$budget" --check "$P.mem.answers.csv" --report "$P.paged.json"
      if (( N <= PEERS_MAX )) && [ -x "$BENCH" ]; then
        say "pass $R/$REPEATS, $name, $flight: peers ($COLLIDERS)"
        timed "$P.peers.log" "$P.peers.time" "$BENCH" "$D/rack.ply" "$PLUG" "$F" "$D/rack.tpi" --memory "$budget" \
          --colliders="$COLLIDERS" --warmup --prefetch --report "$D/runs/peers-$flight-$R.json"
      fi
    done
  done
done

commit=$(git -C "$SCRIPTS" rev-parse --short HEAD 2> /dev/null || echo unknown)
[ -z "$(git -C "$SCRIPTS" status --porcelain --untracked-files=no 2> /dev/null)" ] || commit="$commit (with uncommitted changes)"
python3 "$SCRIPTS/rack_table.py" "$OUT" "$REPEATS" "$STEPS" \
  "$commit" "$load_start" "$(loadavg)" "$((SECONDS - start_seconds))" "${names[@]}" > "$OUT/rack.md"
say "wrote $OUT/rack.md"
cat "$OUT/rack.md"
