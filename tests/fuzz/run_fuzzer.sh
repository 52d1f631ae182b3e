#!/usr/bin/env bash
# Runs a libFuzzer target for a bounded time over a fresh copy of its seed corpus.
# Usage: run_fuzzer.sh FUZZER SEED_DIR WORK_DIR SECONDS [DICTIONARY]
# Exits 0 when the fuzzer ran its time without a crash, leak, time-out or memory bomb; otherwise
# prints the reproducer libFuzzer wrote (WORK_DIR/crash-*, leak-*, timeout-*, oom-*) and exits 1.
set -u
fuzzer=$1; seeds=$2; work=$3; seconds=$4; dict=${5:+-dict=$5}
rm -rf "$work"; mkdir -p "$work/corpus"
cp "$seeds"/* "$work/corpus/"
log="$work/fuzz.log"
# -seed=1: the same exploration every run, so the test does not flake; longer runs with other seeds
# are in docs/robustness.md. Reproducers of what they find go to tests/fuzz/crashes/<target>/.
"$fuzzer" -seed=1 -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 \
  -max_len=80000 -print_final_stats=1 -artifact_prefix="$work/" $dict "$work/corpus" >"$log" 2>&1
code=$?
runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$')
cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1)
if [ "$code" -ne 0 ]; then
  echo "FAIL: $(basename "$fuzzer") exited with $code; reproducer: $(ls "$work"/crash-* "$work"/leak-* "$work"/timeout-* "$work"/oom-* 2>/dev/null | head -1)"
  grep -E "ERROR|SUMMARY|==[0-9]+==" "$log" | head -20
  exit 1
fi
echo "ok: $(basename "$fuzzer") ran ${runs:-?} inputs in $seconds s without a failure ($cov)"
