#!/bin/sh
# Runs libFuzzer targets for a while each (`make fuzz`; docs/RELIABILITY.md).
# Usage: tests/fuzz/run_fuzzers.sh BUILD_DIR SECONDS TARGET...   (TARGET: ply, obj, ..., index)
# Each target grows its own corpus under BUILD_DIR/fuzz/corpus/TARGET from the seeds in
# tests/fuzz/corpus/TARGET (never written to), logs to BUILD_DIR/fuzz/logs/TARGET.log and keeps
# a crashing input in BUILD_DIR/fuzz/crashes/TARGET/. Exits non-zero if any target found one.
set -u
build=$1
seconds=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
# The targets write each input to a temporary file: in memory when the machine has /dev/shm.
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi
# HDF5's own leaks on damaged files are not ours to fix (lsan.supp says which).
export LSAN_OPTIONS="suppressions=$here/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
status=0
for target in "$@"; do
  corpus=$build/fuzz/corpus/$target
  crashes=$build/fuzz/crashes/$target
  log=$build/fuzz/logs/$target.log
  mkdir -p "$corpus" "$crashes" "$build/fuzz/logs"
  echo "fuzz_$target: ${seconds} s, log $log"
  # index_data's inputs are lists of edits: long ones from the start.
  options=""
  [ "$target" = index_data ] && options="-max_len=1024 -len_control=0"
  # STEP and IGES targets also start from OpenCASCADE's samples where Debian's occt-misc is
  # installed (read there, never copied): inputs are cut at 128 KiB.
  seeds=""
  case "$target" in
    step_scan|step) [ -d /usr/share/opencascade/data/step ] && seeds=/usr/share/opencascade/data/step ;;
    iges) [ -d /usr/share/opencascade/data/iges ] && seeds=/usr/share/opencascade/data/iges ;;
  esac
  case "$target" in step_scan|step|iges) options="-max_len=131072" ;; esac
  own_seeds="$here/corpus/$target"
  [ -d "$own_seeds" ] || own_seeds=""
  "$build/tests/fuzz/fuzz_$target" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=2048 $options \
    -print_final_stats=1 -artifact_prefix="$crashes/" "$corpus" $own_seeds $seeds >"$log" 2>&1
  result=$?
  # libFuzzer's last status line (executions, cov: edges, ft: features, corp: corpus) and stats.
  grep -E '^#[0-9]+' "$log" | tail -n 1
  grep -E '^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)' "$log" | tr '\n' ' '
  echo
  if [ "$result" -ne 0 ]; then
    echo "fuzz_$target FAILED (exit $result): the input is kept in $crashes/; see $log" >&2
    grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$log" | head -n 3 >&2
    status=1
  fi
done
exit $status
