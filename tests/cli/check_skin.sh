#!/usr/bin/env bash
# Skinned animation end to end (docs/time.md "Skinned people"): a generated two-bone glTF bar bends
# over three time samples. analyze writes the time and target blocks with one row per sample;
# render --time-sample shows different poses at t=0 and t=1 (and the same picture for the same
# sample by number and label); an unknown clip exits 2 with one line naming its JSON path.
# Usage: check_skin.sh PANDORA MAKE_SKINNED_BAR OUT_DIR
set -euo pipefail
pandora=$1; make_bar=$2; out=$3
rm -rf "$out"; mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
"$make_bar" "$out"
"$pandora" analyze "$out/scene.json" --out "$out/a" --quiet
s="$out/a/summary.json"
jq -e '.time.samples | length == 3' "$s" >/dev/null || fail "three samples expected"
jq -e '.targets | length == 1 and .[0].share_ge[0] > 0' "$s" >/dev/null || fail "the bar's target is not seen"
# The bending bar shades different voxels at each sample.
jq -e '[.time.samples[].ge3] | unique | length == 3' "$s" >/dev/null || fail "the samples' shares do not change"
r=("$pandora" render "$out/scene.json" --view top --size 240x180 --no-cameras --quiet)
"${r[@]}" --time-sample 1 --out "$out/first.png"
"${r[@]}" --time-sample 3 --out "$out/last.png"
"${r[@]}" --time-sample "t=1 s" --out "$out/last_by_label.png"
cmp -s "$out/first.png" "$out/last.png" && fail "t=0 and t=1 give the same picture"
cmp -s "$out/last.png" "$out/last_by_label.png" || fail "sample 3 and 't=1 s' differ"
sed 's/"clip": "bend"/"clip": "walk"/' "$out/scene.json" > "$out/bad.json"
set +e
err=$("$pandora" analyze "$out/bad.json" --out "$out/bad" --quiet 2>&1); rc=$?
set -e
[ "$rc" = 2 ] || fail "an unknown clip exited $rc"
[ "$(printf '%s\n' "$err" | wc -l)" = 1 ] || fail "more than one line: $err"
grep -q "\$.objects\[0\].animation.clip: no clip 'walk'" <<<"$err" || fail "wrong message: $err"
grep -q "'bend'" <<<"$err" || fail "the clips are not listed: $err"
echo "ok: skin"
