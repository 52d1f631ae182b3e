#!/usr/bin/env bash
# PTZ traces on the command line (docs/ptz.md): examples/ptz_home renders in the three modes; the
# path mode lights one camera per second; --ptz all with a budget of 0.01 s lights
# what the home setting sees, so it differs from the current setting's picture; a bad mode and a rig
# without a PTZ camera are one-line errors with exit code 2, and so is selecting a PTZ camera in
# suggest (its file pose is its home, not its current setting).
# Usage: check_ptz.sh PANDORA SCENE WORK_DIR
set -u
pandora=$1; scene=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
for mode in single path all; do
  "$pandora" render "$scene" --rig home_path --view overview --ptz "$mode" --size 160x100 \
    --out "$work/$mode.png" >"$work/$mode.out" 2>&1 || fail "render --ptz $mode: $(cat "$work/$mode.out")"
  [ -s "$work/$mode.png" ] || fail "no $mode.png"
done
grep -q '(1 enabled cameras' "$work/path.out" || fail "path: $(cat "$work/path.out")"
"$pandora" render "$scene" --rig home_path --view overview --ptz all --ptz-time 0.01 --size 160x100 \
  --out "$work/all0.png" -q || fail "--ptz-time 0.01"
"$pandora" render "$scene" --rig home --view overview --size 160x100 --out "$work/home.png" -q || fail "home rig"
cmp -s "$work/all0.png" "$work/single.png" && fail "all with a zero budget equals the current setting's picture"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/bad" '--ptz' -- \
  render "$scene" --rig home --view overview --ptz sideways --out "$work/bad/x.png" >/dev/null || fail "bad mode"
jq 'del(.rigs[0].cameras[0].ptz)' "$scene" >"$work/noptz.json"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/bad2" 'no enabled PTZ camera' -- \
  render "$work/noptz.json" --rig home --view overview --ptz all --out "$work/bad2/x.png" >/dev/null || fail "no PTZ"
jq '.rigs[0].cameras[0].ptz.pan_deg = 400' "$scene" >"$work/badpan.json"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/bad3" '$.rigs[0].cameras[0].ptz.pan_deg' -- \
  render "$work/badpan.json" --rig home --view overview --out "$work/bad3/x.png" >/dev/null || fail "bad pan"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/bad4" "is a PTZ camera" -- \
  suggest "$scene" --rig home --cameras dome --out "$work/bad4/s.json" >/dev/null || fail "suggest took a PTZ camera"
echo "ok"
