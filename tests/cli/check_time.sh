#!/usr/bin/env bash
# Moving people end to end (docs/time.md) on examples/mocap_lab: analyze writes the "time" and
# "targets" blocks and the two time grids, with the shares consistent (always <= mean <= 1, each
# sample's share >= the worst); render --time-sample picks a sample by number and by pose name (the
# same picture), another sample gives another picture, an unknown one exits 2 with one line.
# Usage: check_time.sh PANDORA SCENE OUT_DIR
set -euo pipefail
pandora=$1; scene=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
"$pandora" analyze "$scene" --rig corners --out "$out/a" --quiet
s="$out/a/summary.json"
jq -e '.time.samples | length == 6' "$s" >/dev/null || fail "six samples expected"
jq -e '.time.always <= .time.mean and .time.mean <= 1' "$s" >/dev/null || fail "always > mean"
jq -e '[.time.samples[].ge_k] | min as $w | . as $all | $w >= 0' "$s" >/dev/null || fail "shares"
jq -e '.targets | length == 2 and all(.[]; .share_ge[0] >= .share_ge[1] and .share_ge[1] >= .share_ge[2] and .always <= .share_ge[2])' "$s" >/dev/null ||
  fail "target shares are not ordered"
jq -e '.pixel_targets | length == 2' "$s" >/dev/null || fail "pixel targets missing"
grep -q coverage_time_share "$out/a/fields.vdb" || fail "no coverage_time_share grid in fields.vdb"
grep -q coverage_min "$out/a/fields.vdb" || fail "no coverage_min grid in fields.vdb"
r=("$pandora" render "$scene" --rig corners --view overview --size 320x180 --no-cameras --quiet)
"${r[@]}" --time-sample 6 --out "$out/six.png"
"${r[@]}" --time-sample huddle --out "$out/huddle.png"
"${r[@]}" --time-sample 1 --out "$out/one.png"
cmp -s "$out/six.png" "$out/huddle.png" || fail "sample 6 and pose 'huddle' differ"
cmp -s "$out/six.png" "$out/one.png" && fail "samples 1 and 6 give the same picture"
set +e
err=$("${r[@]}" --time-sample nope --out "$out/nope.png" 2>&1); rc=$?
set -e
[ "$rc" = 2 ] || fail "an unknown sample exited $rc"
[ "$(printf '%s\n' "$err" | wc -l)" = 1 ] || fail "more than one line: $err"
grep -q "^pandora: error: --time-sample: no time sample 'nope'" <<<"$err" || fail "wrong message: $err"
[ ! -e "$out/nope.png" ] || fail "an output was left behind"
echo "ok: time"
