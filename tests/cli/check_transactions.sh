#!/usr/bin/env bash
# Outputs commit together or not at all (docs/robustness.md, "Outputs").
#
#   check_transactions.sh kill PANDORA SCENE OUT     kill -9 `pandora analyze` at random moments and at
#                                                    the two points inside the commit; after each kill
#                                                    the folder holds the previous outputs or the new
#                                                    ones, whole and from one run
#   check_transactions.sh full PANDORA SCENE OUT SHIM  a full disk: a small tmpfs (when it can be
#                                                    mounted) and the ENOSPC shim (LD_PRELOAD); the run
#                                                    fails with exit 2 and one line, the previous
#                                                    outputs stay as they were, nothing else is left
#
# SCENE must have two rigs, "pair" and "trio" (the test makes it from tests/data/minimal.json).
set -u
mode=$1; pandora=$2; scene=$3; out=$4; shim=${5:-}
fail() { echo "FAIL: $*"; exit 1; }

# The run id recorded in fields.vdb's metadata and in summary.json.
vdb_run_id() { vdb_print -l "$1" 2>/dev/null | sed -n 's/^ *run_id: *//p' | head -n 1; }
json_run_id() { jq -r '.run_id // empty' "$1" 2>/dev/null; }
vdb_rig() { vdb_print -l "$1" 2>/dev/null | sed -n 's/^ *rig_name: *//p' | head -n 1; }

# The folder's outputs are absent, or whole and from one run. With a journal left by a commit that
# was killed half way, a reader (render --fields) must finish the commit first.
check_folder() {
  local dir=$1 what=$2
  if ls -d "$dir"/.pandora-staging-*/JOURNAL >/dev/null 2>&1; then
    # The rig of the run being committed: its fields.vdb, moved into place or still staged.
    local rig; rig=$(vdb_rig "$(ls "$dir"/.pandora-staging-*/fields.vdb "$dir/fields.vdb" 2>/dev/null | head -n 1)")
    [ -n "$rig" ] || fail "$what: a journal is left but fields.vdb is unreadable"
    "$pandora" render "$scene" --rig "$rig" --fields "$dir/fields.vdb" --from 2,2,2 --at 0,0,0.3 \
      --size 8x8 --out "$dir.probe.png" --quiet 2>"$dir.probe.err" ||
      fail "$what: the reader failed: $(cat "$dir.probe.err")"
    rm -f "$dir.probe.png" "$dir.probe.err"
    ls -d "$dir"/.pandora-staging-* >/dev/null 2>&1 && fail "$what: the reader left the journal"
    recovered=$((recovered + 1))
  fi
  [ -e "$dir/fields.vdb" ] || [ -e "$dir/summary.json" ] || return 0
  [ -e "$dir/fields.vdb" ] && [ -e "$dir/summary.json" ] || fail "$what: one output without the other: $(ls -A "$dir")"
  local a b; a=$(vdb_run_id "$dir/fields.vdb"); b=$(json_run_id "$dir/summary.json")
  [ -n "$a" ] || fail "$what: fields.vdb is not whole (vdb_print cannot read its run id)"
  [ -n "$b" ] || fail "$what: summary.json is not whole"
  [ "$a" = "$b" ] || fail "$what: fields.vdb of run $a beside summary.json of run $b"
  local rig; rig=$(jq -r .rig "$dir/summary.json")
  [ "$(vdb_rig "$dir/fields.vdb")" = "$rig" ] || fail "$what: rigs differ"
  # What a run killed before its commit point staged stays hidden until the next run sweeps it;
  # more than one such folder means a run did not sweep its predecessor's.
  [ "$(ls -d "$dir"/.pandora-staging-* 2>/dev/null | wc -l)" -le 1 ] || fail "$what: staging not swept: $(ls -A "$dir")"
  return 0
}

case "$mode" in
kill)
  rm -rf "$out"; mkdir -p "$out"
  dir="$out/run"; recovered=0; runs=0; killed=0
  # Deterministic kills at the two points inside the commit (test hook in OutputTransaction).
  for point in after-journal after-first-rename; do
    for rig in pair trio; do
      PANDORA_TEST_CRASH_AT=$point "$pandora" analyze "$scene" --rig $rig --out "$dir" --quiet 2>/dev/null
      [ $? -eq 137 ] || fail "the crash hook at $point did not fire"
      killed=$((killed + 1))
      check_folder "$dir" "killed $point ($rig)"
    done
  done
  # Random kills: the run takes about 0.15 s here; delays from 0 to 0.3 s hit every phase.
  RANDOM=7
  for i in $(seq 1 60); do
    rig=$([ $((i % 2)) -eq 0 ] && echo pair || echo trio)
    "$pandora" analyze "$scene" --rig $rig --out "$dir" --quiet 2>/dev/null &
    pid=$!
    sleep "0.$(printf '%03d' $((RANDOM % 300)))"
    kill -9 $pid 2>/dev/null && killed=$((killed + 1))
    wait $pid 2>/dev/null
    runs=$((runs + 1))
    check_folder "$dir" "run $i ($rig)"
  done
  # A last run to completion: the new outputs, whole.
  "$pandora" analyze "$scene" --rig pair --out "$dir" --quiet || fail "the final run failed"
  check_folder "$dir" "final run"
  [ "$(ls -A "$dir" | tr '\n' ' ')" = "fields.vdb summary.json " ] || fail "final run: litter: $(ls -A "$dir")"
  [ "$(jq -r .rig "$dir/summary.json")" = pair ] || fail "the final run's outputs are not there"
  echo "ok: $((runs + 4)) runs, $killed killed, $recovered half-done commits finished by a reader; every folder whole"
  ;;
full)
  rm -rf "$out"; mkdir -p "$out"
  checked=0
  # 1. The ENOSPC shim: the first run succeeds, the second runs out of space part way.
  dir="$out/shim"
  "$pandora" analyze "$scene" --rig pair --out "$dir" --quiet || fail "first run failed"
  cp -a "$dir" "$out/shim.before"
  for after in 0 1000 30000 56000; do
    err=$(PANDORA_ENOSPC_AFTER=$after LD_PRELOAD="$shim" "$pandora" analyze "$scene" --rig trio --out "$dir" --quiet 2>&1 >/dev/null)
    code=$?
    [ $code -eq 2 ] || fail "shim, $after bytes: exit $code, expected 2 ($err)"
    [ "$(printf '%s\n' "$err" | grep -c .)" -eq 1 ] || fail "shim, $after bytes: expected one line: $err"
    diff -r "$out/shim.before" "$dir" >/dev/null || fail "shim, $after bytes: the previous outputs changed: $(ls -A "$dir")"
    checked=$((checked + 1))
  done
  # The disk fills while fields.vdb is written and has room again for summary.json: the torn
  # fields.vdb must be caught (OpenVDB itself does not check its writes).
  for after in 100 8000 20000 50000; do
    err=$(PANDORA_ENOSPC_FILE=fields.vdb PANDORA_ENOSPC_AFTER=$after LD_PRELOAD="$shim" "$pandora" analyze "$scene" --rig trio --out "$dir" --quiet 2>&1 >/dev/null)
    code=$?
    [ $code -eq 2 ] || fail "shim, fields.vdb cut at $after bytes: exit $code, expected 2 ($err)"
    diff -r "$out/shim.before" "$dir" >/dev/null || fail "shim, fields.vdb cut at $after bytes: the previous outputs changed"
    checked=$((checked + 1))
  done
  # A new folder on a full disk: the command fails and leaves no folder behind.
  err=$(PANDORA_ENOSPC_AFTER=0 LD_PRELOAD="$shim" "$pandora" analyze "$scene" --out "$out/shim_new/deeper" --quiet 2>&1 >/dev/null)
  [ $? -eq 2 ] || fail "shim, new folder: expected exit 2 ($err)"
  [ ! -e "$out/shim_new" ] || fail "shim, new folder: left $(find "$out/shim_new")"
  echo "shim: $checked full-disk runs refused with the previous outputs intact; no folder left"
  # 2. A real full disk: a 96 KiB tmpfs in a private mount namespace (needs root).
  if unshare -m true 2>/dev/null; then
    export pandora scene out
    unshare -m bash -c '
      set -u; fail() { echo "FAIL: $*"; exit 1; }
      d="$out/tmpfs"; mkdir -p "$d"
      mount -t tmpfs -o size=96k tmpfs "$d" || { echo "skipped: cannot mount a tmpfs"; exit 0; }
      "$pandora" analyze "$scene" --rig pair --out "$d/run" --quiet || fail "tmpfs: first run failed"
      cp -a "$d/run" "$out/tmpfs.before"
      err=$("$pandora" analyze "$scene" --rig trio --out "$d/run" --quiet 2>&1 >/dev/null); code=$?
      [ $code -eq 2 ] || fail "tmpfs: exit $code, expected 2 ($err)"
      case "$err" in *"disk is full"*|*"No space left"*|*"cut short"*) ;; *) fail "tmpfs: unclear message: $err";; esac
      diff -r "$out/tmpfs.before" "$d/run" >/dev/null || fail "tmpfs: previous outputs changed: $(ls -A "$d/run")"
      [ "$(ls -A "$d/run" | tr "\n" " ")" = "fields.vdb summary.json " ] || fail "tmpfs: litter: $(ls -A "$d/run")"
      echo "tmpfs: the run on a full 96 KiB disk failed with: $err"
      umount "$d"
    ' || exit 1
  else
    echo "tmpfs: skipped (no private mount namespace here)"
  fi
  echo "ok: full disk never leaves a torn or half-replaced output"
  ;;
*) fail "unknown mode $mode" ;;
esac
