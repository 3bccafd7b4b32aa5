#!/bin/sh
# Runs the libFuzzer targets of the fuzz preset one after the other, each for SECONDS (default
# 600), niced, and prints per target its run time, executions, executions per second and the
# result (ok, or the crash, hang or out-of-memory input libFuzzer saved). Build first:
#   cmake --preset fuzz && cmake --build --preset fuzz
# Usage: tools/fuzz.sh [SECONDS] [TARGET ...]   (targets: the names of tests/fuzz/corpus/*)
# The seeds in tests/fuzz/corpus/<target>/ are read only; what a run adds goes to
# build/fuzz/corpus/<target>/, its log and any finding to build/fuzz/findings/.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-600}
[ $# -gt 0 ] && shift
targets=${*:-$(ls "$root/tests/fuzz/corpus")}
bin=$root/build/fuzz/tests/fuzz
findings=$root/build/fuzz/findings
mkdir -p "$findings"
status=0
printf '%-18s %8s %12s %10s  %s\n' target seconds executions execs/s result
for target in $targets; do
  fuzzer=$bin/fuzz_$target
  if [ ! -x "$fuzzer" ]; then
    printf '%-18s not built (%s)\n' "$target" "$fuzzer"
    status=1
    continue
  fi
  corpus=$root/build/fuzz/corpus/$target
  mkdir -p "$corpus"
  log=$findings/$target.log
  rm -f "$findings/$target-"*
  ASAN_OPTIONS=detect_leaks=0 nice -n 10 "$fuzzer" -max_total_time="$seconds" -print_final_stats=1 \
    -timeout=10 -rss_limit_mb=2048 -artifact_prefix="$findings/$target-" "$corpus" "$root/tests/fuzz/corpus/$target" \
    > "$log" 2>&1
  code=$?
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  time=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$log" | tail -1)
  finding=$(ls "$findings/$target-"* 2> /dev/null | head -1)
  if [ "$code" -eq 0 ] && [ -z "$finding" ]; then
    result=ok
  else
    result="FOUND (exit $code): ${finding:-see $log}"
    status=1
  fi
  printf '%-18s %8s %12s %10s  %s\n' "$target" "${time:-?}" "${runs:-?}" "${rate:-?}" "$result"
done
exit $status
