#!/usr/bin/env bash
# Two writers of one scene file at once never lose a write (docs/robustness.md, "Concurrent
# writers"): PAIRS times, two `pandora accept` of two different suggestions made from the same scene
# run at the same moment. Exactly one must apply and the other be refused (exit 2, one line): the
# file then holds the applied suggestion's cameras, and every backup has its own name and holds the
# scene as it was before. Before the lock, 1 in 4 pairs both printed "accepted" and one was lost.
# usage: check_concurrent_accept.sh PANDORA EXAMPLE_DIR OUT_DIR [PAIRS]
set -uo pipefail
pandora=$1 example=$2 out=$3 pairs=${4:-50}
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$out"
mkdir -p "$out"
cp -r "$example" "$out/example"
scene="$out/example/scene.json"
cp "$scene" "$out/original.json"
rig=$(jq -r '.rigs[0].name' "$scene")
ids=($(jq -r '.rigs[0].cameras[0:2][].id' "$scene"))
for k in 0 1; do
  "$pandora" suggest "$scene" --rig "$rig" --cameras "${ids[$k]}" --objective sigma-mean --points 300 --outer 1 \
    --out "$out/s$k.json" --quiet || fail "suggest ${ids[$k]}"
  jq -e '.improved == true' "$out/s$k.json" > /dev/null || fail "suggestion $k improves nothing: the test needs two that apply"
done
# Where each suggestion puts its camera (the scene after applying it alone).
for k in 0 1; do
  "$pandora" accept "$out/s$k.json" --quiet || fail "accept s$k alone"
  cp "$scene" "$out/applied$k.json"
  cp "$out/original.json" "$scene"
done
rm -f "$scene".bak*
applied=(0 0)
for ((p = 0; p < pairs; ++p)); do
  cp "$out/original.json" "$scene"
  "$pandora" accept "$out/s0.json" --quiet 2> "$out/e0" &
  a=$!
  "$pandora" accept "$out/s1.json" --quiet 2> "$out/e1" &
  b=$!
  wait $a; r0=$?
  wait $b; r1=$?
  if [ $r0 -eq 0 ] && [ $r1 -eq 0 ]; then fail "pair $p: both accepts applied (one write lost)"; fi
  if [ $r0 -ne 0 ] && [ $r1 -ne 0 ]; then fail "pair $p: both refused ($r0, $r1): $(cat "$out/e0" "$out/e1")"; fi
  w=0; l=1; [ $r1 -eq 0 ] && { w=1; l=0; }
  rl=$([ $l -eq 0 ] && echo $r0 || echo $r1)
  [ "$rl" -eq 2 ] || fail "pair $p: the refused accept exited $rl, not 2"
  [ "$(wc -l < "$out/e$l")" -eq 1 ] || fail "pair $p: the refusal is not one line: $(cat "$out/e$l")"
  cmp -s "$scene" "$out/applied$w.json" || fail "pair $p: the scene file is not suggestion $w applied"
  applied[$w]=$((applied[$w] + 1))
done
# One backup per applied accept, each its own name, each the scene as it was before.
n=$(ls "$scene".bak* | wc -l)
[ "$n" -eq "$pairs" ] || fail "$n backups for $pairs applied accepts"
for f in "$scene".bak*; do cmp -s "$f" "$out/original.json" || fail "backup $f is not the scene before"; done
echo "ok: $pairs concurrent pairs, each one applied and one refused (${applied[0]} / ${applied[1]}), $n backups"
