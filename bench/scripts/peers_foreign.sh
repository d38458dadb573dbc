#!/usr/bin/env bash
# The peer benchmark on data the project did not generate (issue 25, item 4; `make bench-peers`):
# the study's workload, environments x objects, each cell one billiard flight with the oracle's
# answers, replayed by tetrapage_bench_peers through FCL, CGAL's AABB tree and tetrapage (every
# shard in memory, and paged under 10 % of the index file) in the same run, REPEATS passes over
# every cell; peers.md gives the median of each figure (peers_table.py), the ratios to the best
# peer and their geometric mean over the cells.
#
#   bench/scripts/peers_foreign.sh [OUT_DIR]     (default: $BUILD/bench-results/peers-foreign)
#
# Environments (ENVS, any of "scene terrain assimp"):
#   scene    the scene generator over the curated CGAL meshes (some copies opened), one scene
#            of each of SCENE_SIZES triangles
#   terrain  the fractal terrain, TERRAIN_TRIANGLES triangles (2880000: the full 1201 x 1201 grid)
#   assimp   the scene generator over Debian's assimp-testmodels: every file under ASSIMP_MODELS
#            that `tetrapage mesh info` reads with at least MIN_TRIANGLES triangles, one per
#            triangle count (the package holds the same model in many formats); native formats
#            linked, the others converted to .ply; ASSIMP_TRIANGLES triangles in all
# Objects (OBJECTS, triangle counts): 4 is the tetrahedron; a count listed in OBJECT_MESHES is
# that CGAL mesh of MESH_DIR as is (320 sphere and 3290 elk, closed; 14859
# lion: open); the generator fails the run if it made anything else. Other counts: whatever
# `generate object` picks.
# Flights: STEPS poses, seed 1, answered by the oracle (`generate flight --answers`). Index:
# `preprocess` with its defaults. Paged budget: 10 % of the index file's bytes.
#
# Environment variables (defaults in brackets; a smaller run for testing:
#   STEPS=300 REPEATS=2 SCENE_SIZES=100000 TERRAIN_TRIANGLES=200000 ASSIMP_TRIANGLES=100000):
#   STEPS [10000]  REPEATS [5]  ENVS [scene terrain assimp]  OBJECTS [4 320 3290 14859]
#   SCENE_SIZES [1000000 5000000]  TERRAIN_TRIANGLES [2880000]  ASSIMP_TRIANGLES [1000000]
#   COLLIDERS [fcl,cgal-surfaces,cgal,tetrapage,tetrapage-paged] (the best peer is the fastest
#     non-tetrapage one of these; embree may be added)
#   DATA [none]: a folder of prepared environments, NAME.ply and NAME.tpi (NAME as in the table:
#     scene1m, scene5m, terrain2880k, assimp1m, ...), linked instead of generated
#   BUILD [build], TETRAPAGE [$BUILD/tools/tetrapage], BENCH [$BUILD/bench/tetrapage_bench_peers],
#   MESH_DIR [$TETRAPAGE_MESH_DIR or $BUILD/meshes], ASSIMP_MODELS [/usr/share/assimp/models],
#   MIN_TRIANGLES [500], OBJECT_MESHES [320:sphere 3290:elk 14859:lion],
#   PREPROCESS_FLAGS [none]: added to `preprocess` (e.g. --threads 1 beside other work)
#
# Everything generated stays in OUT_DIR and is reused by the next run (names carry the sizes and
# STEPS); the runs themselves are redone every time, into OUT_DIR/runs.
set -euo pipefail
BUILD=${BUILD:-build}
OUT=${1:-$BUILD/bench-results/peers-foreign}
TETRAPAGE=${TETRAPAGE:-$BUILD/tools/tetrapage}
BENCH=${BENCH:-$BUILD/bench/tetrapage_bench_peers}
STEPS=${STEPS:-10000}
REPEATS=${REPEATS:-5}
ENVS=${ENVS:-scene terrain assimp}
OBJECTS=${OBJECTS:-4 320 3290 14859}
SCENE_SIZES=${SCENE_SIZES:-1000000 5000000}
TERRAIN_TRIANGLES=${TERRAIN_TRIANGLES:-2880000}
ASSIMP_TRIANGLES=${ASSIMP_TRIANGLES:-1000000}
COLLIDERS=${COLLIDERS:-fcl,cgal-surfaces,cgal,tetrapage,tetrapage-paged}
DATA=${DATA:-}
MESH_DIR=${MESH_DIR:-${TETRAPAGE_MESH_DIR:-$BUILD/meshes}}
ASSIMP_MODELS=${ASSIMP_MODELS:-/usr/share/assimp/models}
MIN_TRIANGLES=${MIN_TRIANGLES:-500}
OBJECT_MESHES=${OBJECT_MESHES:-320:sphere 3290:elk 14859:lion}
PREPROCESS_FLAGS=${PREPROCESS_FLAGS:-}
SCRIPTS=$(cd "$(dirname "$0")" && pwd)

say() { echo "peers-foreign: $*" >&2; }
die() { say "error: $*"; exit 1; }
loadavg() { cut -d' ' -f1-3 /proc/loadavg; }
# 1000000 -> 1m, 2880000 -> 2880k
short() { local n=$1; if (( n % 1000000 == 0 )); then echo "$((n / 1000000))m"; elif (( n % 1000 == 0 )); then echo "$((n / 1000))k"; else echo "$n"; fi; }
# json FILE EXPRESSION: a Python expression over the report `d`
json() { python3 -c "import json, sys; d = json.load(open(sys.argv[1])); print($2)" "$1"; }
# run LOG COMMAND...: its output into LOG; on failure LOG's end and exit
run() { local log=$1; shift; "$@" > "$log" 2>&1 || { tail -5 "$log" >&2; die "failed ($(basename "$log")): $*"; }; }

[ -x "$TETRAPAGE" ] || die "no $TETRAPAGE (make build, or set BUILD / TETRAPAGE)"
[ -x "$BENCH" ] || die "no $BENCH (make build, or set BUILD / BENCH)"
for n in $STEPS $REPEATS $SCENE_SIZES $TERRAIN_TRIANGLES $ASSIMP_TRIANGLES $OBJECTS $MIN_TRIANGLES; do
  [[ $n =~ ^[1-9][0-9]*$ ]] || die "not a positive count: '$n'"
done
for kind in $ENVS; do
  case $kind in scene | terrain | assimp) ;; *) die "ENVS: unknown environment '$kind' (scene, terrain, assimp)" ;; esac
done
[ -z "$DATA" ] || [ -d "$DATA" ] || die "DATA: no folder '$DATA'"
mkdir -p "$OUT/objects"
load_start=$(loadavg)
start_seconds=$SECONDS

# --- Objects -------------------------------------------------------------------------------
object_mesh() {  # the CGAL mesh OBJECT_MESHES names for a triangle count, or nothing
  local entry
  for entry in $OBJECT_MESHES; do [ "${entry%%:*}" = "$1" ] && echo "${entry#*:}"; done
  return 0
}
for N in $OBJECTS; do
  O="$OUT/objects/object$N"
  mesh=$(object_mesh "$N")
  if [ ! -f "$O.ply" ]; then
    say "object $N: generating"
    if [ -n "$mesh" ]; then
      [ -f "$MESH_DIR/$mesh.off" ] || die "object $N: no $MESH_DIR/$mesh.off (make build unpacks the CGAL meshes; or set MESH_DIR)"
      mkdir -p "$OUT/objects/lib-$mesh"
      ln -sfn "$(realpath "$MESH_DIR/$mesh.off")" "$OUT/objects/lib-$mesh/$mesh.off"
      run "$O.log" "$TETRAPAGE" generate object --triangles "$N" --meshes "$OUT/objects/lib-$mesh" -o "$O.ply" --report "$O.json"
    else
      run "$O.log" "$TETRAPAGE" generate object --triangles "$N" -o "$O.ply" --report "$O.json"
    fi
  fi
  source=$(json "$O.json" 'd["source"]')
  if [ -n "$mesh" ]; then
    [ "$source" = "$mesh as is" ] || die "object $N: generated from '$source', not $mesh as is (delete $O.ply to redo)"
  elif [ "$N" -le 4 ]; then
    [ "$source" = tetrahedron ] || die "object $N: generated from '$source', not the tetrahedron"
  fi
  say "object $N: $source, $(json "$O.json" 'd["triangles"]') triangles"
done

# --- Debian's assimp-testmodels: the models our reader loads --------------------------------
ASSIMP_DIR="$OUT/assimp-models"
if [[ " $ENVS " == *" assimp "* ]] && [ ! -f "$ASSIMP_DIR/.complete" ]; then
  [ -d "$ASSIMP_MODELS" ] || die "no $ASSIMP_MODELS: install Debian's assimp-testmodels (make deps)"
  say "assimp-testmodels: reading every file under $ASSIMP_MODELS with \`tetrapage mesh info\`"
  rm -rf "$ASSIMP_DIR" "$OUT"/assimp[0-9]* && mkdir -p "$ASSIMP_DIR"  # its scenes are stale too
  scan="$OUT/assimp-scan.tsv"  # status, triangles, file, reason
  printf 'status\ttriangles\tfile\treason\n' > "$scan"
  tmp="$OUT/assimp-scan.tmp"
  while IFS= read -r -d '' file; do
    status=0
    # (in a subshell whose stderr is dropped: a crash is reported below, not by bash's job notice)
    (timeout 60 "$TETRAPAGE" mesh info "$file" --report "$tmp.json" > "$tmp.log" 2>&1; exit $?) 2> /dev/null || status=$?
    if [ "$status" = 0 ]; then
      printf 'read\t%s\t%s\t\n' "$(json "$tmp.json" 'd["files"][0]["triangles"]')" "$file" >> "$scan"
    else
      case $status in
        124) reason="timed out after 60 s" ;;
        1) reason=$(tail -1 "$tmp.log" | sed 's/^tetrapage: //') ;;
        *) reason="crashed (exit $status$( ((status > 128)) && echo ", signal $((status - 128))"))" ;;
      esac
      printf 'failed\t\t%s\t%s\n' "$file" "$reason" >> "$scan"
    fi
  done < <(find "$ASSIMP_MODELS" -type f -print0 | sort -z)
  rm -f "$tmp.json" "$tmp.log"
  # One file per model: sorted by triangles, a file within 0.2 % of the triangles of the one
  # kept before it is taken for the same model in another format (our own readers' formats
  # preferred, then the path's order).
  python3 - "$scan" "$MIN_TRIANGLES" > "$OUT/assimp-candidates.tsv" <<'PY'
import csv, os, sys
rows = [r for r in csv.DictReader(open(sys.argv[1]), delimiter="\t") if r["status"] == "read"]
rows = [r for r in rows if int(r["triangles"]) >= int(sys.argv[2])]
native = lambda path: os.path.splitext(path)[1].lower() in (".off", ".ply", ".obj", ".stl")
rows.sort(key=lambda r: (int(r["triangles"]), not native(r["file"]), r["file"]))
kept = []
for r in rows:
    if kept and int(r["triangles"]) <= int(kept[-1]["triangles"]) * 1.002:
        continue
    kept.append(r)
for r in kept:
    print(f"{r['triangles']}\t{r['file']}")
PY
  : > "$OUT/assimp-models.tsv"  # triangles, file, what the folder holds
  while IFS=$'\t' read -r triangles file; do
    rel=${file#"$ASSIMP_MODELS"/}
    name=$(echo "${rel%.*}" | tr '/ ' '__')
    ext=$(echo "${file##*.}" | tr 'A-Z' 'a-z')
    case $ext in
      off | ply | obj | stl)
        ln -sfn "$file" "$ASSIMP_DIR/$name.$ext"
        printf '%s\t%s\t%s\n' "$triangles" "$file" "$name.$ext (link)" >> "$OUT/assimp-models.tsv" ;;
      *)
        if "$TETRAPAGE" mesh convert "$file" -o "$ASSIMP_DIR/$name-$ext.ply" > "$OUT/assimp-convert.log" 2>&1; then
          printf '%s\t%s\t%s\n' "$triangles" "$file" "$name-$ext.ply (converted)" >> "$OUT/assimp-models.tsv"
        else
          say "assimp-testmodels: $rel read but not converted, left out: $(tail -1 "$OUT/assimp-convert.log")"
        fi ;;
    esac
  done < "$OUT/assimp-candidates.tsv"
  rm -f "$OUT/assimp-convert.log"
  touch "$ASSIMP_DIR/.complete"
fi
if [[ " $ENVS " == *" assimp "* ]]; then
  say "assimp-testmodels: $(wc -l < "$OUT/assimp-models.tsv") models of at least $MIN_TRIANGLES triangles kept of" \
    "$(grep -c '^read' "$OUT/assimp-scan.tsv") files read ($(grep -c '^failed' "$OUT/assimp-scan.tsv") not read; $OUT/assimp-scan.tsv says why)"
fi

# --- Environments, indexes, flights ----------------------------------------------------------
envs=()
for kind in $ENVS; do
  case $kind in
    scene) for N in $SCENE_SIZES; do envs+=("scene:$N"); done ;;
    terrain) envs+=("terrain:$TERRAIN_TRIANGLES") ;;
    assimp) envs+=("assimp:$ASSIMP_TRIANGLES") ;;
  esac
done
names=()
for env in "${envs[@]}"; do
  kind=${env%%:*}; N=${env#*:}; name=$kind$(short "$N"); D="$OUT/$name"
  names+=("$name")
  mkdir -p "$D"
  if [ ! -f "$D/model.ply" ]; then
    if [ -n "$DATA" ] && [ -f "$DATA/$name.ply" ]; then
      say "$name: linking $DATA/$name.ply"
      ln -sfn "$(realpath "$DATA/$name.ply")" "$D/model.ply"
      [ ! -f "$DATA/$name.tpi" ] || ln -sfn "$(realpath "$DATA/$name.tpi")" "$D/model.tpi"
    else
      say "$name: generating $kind of $N triangles"
      case $kind in
        scene) run "$D/generate.log" "$TETRAPAGE" generate scene --triangles "$N" --seed 1 -o "$D/model.ply" --report "$D/generate.json" ;;
        terrain) run "$D/generate.log" "$TETRAPAGE" generate terrain --triangles "$N" --seed 1 -o "$D/model.ply" --report "$D/generate.json" ;;
        assimp) run "$D/generate.log" "$TETRAPAGE" generate scene --meshes "$ASSIMP_DIR" --triangles "$N" --seed 1 -o "$D/model.ply" --report "$D/generate.json" ;;
      esac
    fi
  fi
  if [ ! -f "$D/model.tpi" ]; then
    say "$name: preprocessing"
    run "$D/preprocess.log" "$TETRAPAGE" preprocess "$D/model.ply" -o "$D/model.tpi" --report "$D/preprocess.json" $PREPROCESS_FLAGS
  fi
  [ -f "$D/info.json" ] || run "$D/info.log" "$TETRAPAGE" mesh info "$D/model.ply" --report "$D/info.json"
  for N in $OBJECTS; do
    F="$D/flight-object$N-$STEPS"
    if [ ! -f "$F.csv" ] || [ ! -f "$F.answers.csv" ]; then
      say "$name: flight of object $N, $STEPS steps (the oracle answers)"
      run "$F.log" "$TETRAPAGE" generate flight --env "$D/model.ply" --object "$OUT/objects/object$N.ply" \
        --steps "$STEPS" --seed 1 --displacement 0.005 -o "$F.tmp.csv" --answers "$F.answers.tmp.csv" --report "$F.json"
      mv "$F.answers.tmp.csv" "$F.answers.csv" && mv "$F.tmp.csv" "$F.csv"
    fi
  done
done

# --- The runs: REPEATS passes over every cell ------------------------------------------------
rm -rf "$OUT/runs" && mkdir -p "$OUT/runs"
cells=$(( ${#names[@]} * $(wc -w <<< "$OBJECTS") ))
say "$cells cells x $REPEATS passes, colliders $COLLIDERS (load average $load_start)"
for R in $(seq 1 "$REPEATS"); do
  cell=0
  for name in "${names[@]}"; do
    D="$OUT/$name"
    budget=$(( $(stat -L -c %s "$D/model.tpi") / 10 ))
    for N in $OBJECTS; do
      cell=$((cell + 1))
      F="$D/flight-object$N-$STEPS"
      P="$OUT/runs/$name-object$N-$R"
      t0=$SECONDS
      "$BENCH" "$D/model.ply" "$OUT/objects/object$N.ply" "$F.csv" "$F.answers.csv" "$D/model.tpi" \
        --memory "$budget" --colliders="$COLLIDERS" --warmup --prefetch --report "$P.json" > "$P.md" 2> "$P.log" ||
        { tail -5 "$P.log" >&2; die "$name x object $N, pass $R: tetrapage_bench_peers failed ($P.log)"; }
      ratio=$(json "$P.json" '"%.2fx the best peer (%s)" % (d["ratios"]["in_memory_over_best_peer_steps_per_second"], d["ratios"]["best_peer"]) if "best_peer" in d["ratios"] else "no ratio"')
      say "pass $R/$REPEATS, cell $cell/$cells ($name x object $N): $((SECONDS - t0)) s, tetrapage in memory $ratio (load average $(loadavg))"
    done
  done
done
load_end=$(loadavg)

# --- peers.md --------------------------------------------------------------------------------
commit=$(git -C "$SCRIPTS" rev-parse --short HEAD 2> /dev/null || echo unknown)
[ -z "$(git -C "$SCRIPTS" status --porcelain --untracked-files=no 2> /dev/null)" ] || commit="$commit (with uncommitted changes)"
{
  echo "# Peers on foreign data"
  echo
  echo "\`bench/scripts/peers_foreign.sh\` (\`make bench-peers\`), $(date -u '+%Y-%m-%d %H:%M UTC'), $((SECONDS - start_seconds)) s."
  echo
  first_report=$(ls "$OUT"/runs/*-1.json | head -1)
  json "$first_report" '"- machine: {processor}, {logical_cores} logical cores, {memory}, {kernel}".format(**d["machine"])'
  echo "- commit: $commit; binaries: $TETRAPAGE, $BENCH"
  echo "- load average (1, 5, 15 min) at the run's start: $load_start; at its end: $load_end"
  json "$first_report" '"\n".join("- build of %s: %s" % (b["code"], (b["compiler"] + ", " + b["build_type"] + " (" + b["flags"] + ")") if "compiler" in b else (b["version"] + ", " + b["package"] + ", built by " + b["built_by"] + ": " + b["flags"])) for b in d["builds"])'
  echo "- $STEPS-pose billiard flights (seed 1) with the oracle's answers; $REPEATS passes over every cell," \
    "figures are medians over the passes; colliders $COLLIDERS, each single-threaded in a process of its own," \
    "the in-memory colliders timed on a second pass over the flight (warm); tetrapage-paged under 10 % of the index" \
    "file's bytes, from an empty shard cache, with its prefetch thread (a second thread)"
  echo
  echo "Environments:"
  echo
  for name in "${names[@]}"; do
    D="$OUT/$name"
    line="- $name: $(json "$D/info.json" '"{:,} triangles".format(d["files"][0]["triangles"])'), index $(( $(stat -L -c %s "$D/model.tpi") >> 10 )) KiB, paged budget $(( $(stat -L -c %s "$D/model.tpi") / 10 )) bytes"
    if [ -f "$D/generate.json" ]; then
      line="$line; $(json "$D/generate.json" 'd["command"] + " --seed " + str(d["seed"]) + ("" if "copies_per_mesh" not in d else
        ", meshes of %s (copies: %s; %d of %d opened)" % (d["meshes_folder"], ", ".join(f"{k} {v}" for k, v in sorted(d["copies_per_mesh"].items())), d["open_copies"], d["copies"]))')"
    else
      line="$line; linked from $(readlink -f "$D/model.ply") (no generator report)"
    fi
    echo "$line"
  done
  echo
  echo "Objects (fitted in a cube of side 0.05):"
  echo
  for N in $OBJECTS; do
    echo "- object $N: $(json "$OUT/objects/object$N.json" '"{} ({} triangles, {})".format(d["source"], d["triangles"], "closed" if d["closed"] else "open")')"
  done
  if [[ " $ENVS " == *" assimp "* ]]; then
    echo
    echo "assimp-testmodels ($ASSIMP_MODELS): $(grep -c '^read' "$OUT/assimp-scan.tsv") of" \
      "$(( $(wc -l < "$OUT/assimp-scan.tsv") - 1 )) files read by \`tetrapage mesh info\`; of those with at least" \
      "$MIN_TRIANGLES triangles, one file per triangle count (the same model in other formats left out):"
    echo
    while IFS=$'\t' read -r triangles file held; do
      echo "- ${file#"$ASSIMP_MODELS"/}: $triangles triangles, as $held"
    done < "$OUT/assimp-models.tsv"
    echo
    echo "Not read (reasons in $OUT/assimp-scan.tsv):"
    echo
    awk -F'\t' '$1 == "failed" {
        r = $4
        if (r ~ /no mesh reader for the extension/) r = "not a mesh format we read (images, materials, ...)"
        else if ($3 ~ /\/invalid\//) r = "the package'"'"'s deliberately invalid files (invalid/), refused with a reason"
        else if (r ~ /Assimp cannot import it/) r = "Assimp cannot import it"
        else if (r ~ /no triangle/) r = "no triangle (points, lines, cameras, lights)"
        else if (r ~ /^crashed/) r = r " [" $3 "]"
        else r = "our reader rejects it: " r
        n[r]++ } END { for (r in n) printf "%d\t%s\n", n[r], r }' "$OUT/assimp-scan.tsv" | sort -k1,1nr -k2 |
      awk -F'\t' '{ printf "- %d: %s\n", $1, $2 }'
  fi
} > "$OUT/preamble.md"

args=()
for name in "${names[@]}"; do
  for N in $OBJECTS; do args+=(--cell "$OUT/runs/$name-object$N" "$name" "$N ($(json "$OUT/objects/object$N.json" 'd["source"].split()[0]'))"); done
done
python3 "$SCRIPTS/peers_table.py" "$OUT/peers.md" --repeats "$REPEATS" --columns environment object \
  --preamble "$OUT/preamble.md" --summary "${args[@]}" > /dev/null
say "wrote $OUT/peers.md"
cat "$OUT/peers.md"
