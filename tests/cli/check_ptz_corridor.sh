#!/usr/bin/env bash
# The second PTZ example (examples/ptz_corridor, docs/ptz.md): a 24 m corridor watched by two
# ceiling domes. The scene loads; both rigs render in the three trace modes, and `all` differs
# from `single` and, with its budget of 1.5 s, from a budget of 0.01 s; `analyze` runs on both rigs
# and reports the face pixel target with a share seen by >= 1 camera in (0, 1].
# Usage: check_ptz_corridor.sh PANDORA SCENE WORK_DIR
set -u
pandora=$1; scene=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
for rig in tours doorway; do
  for mode in single path all; do
    "$pandora" render "$scene" --rig "$rig" --view overview --ptz "$mode" --size 160x100 \
      --out "$work/${rig}_$mode.png" >"$work/${rig}_$mode.out" 2>&1 ||
      fail "render --rig $rig --ptz $mode: $(cat "$work/${rig}_$mode.out")"
    [ -s "$work/${rig}_$mode.png" ] || fail "no ${rig}_$mode.png"
    grep -q '(2 enabled cameras' "$work/${rig}_$mode.out" || fail "$rig $mode: $(cat "$work/${rig}_$mode.out")"
  done
  cmp -s "$work/${rig}_single.png" "$work/${rig}_all.png" && fail "$rig: all equals single"
done
"$pandora" render "$scene" --rig tours --view overview --ptz all --ptz-time 0.01 --size 160x100 \
  --out "$work/all0.png" -q || fail "--ptz-time 0.01"
cmp -s "$work/all0.png" "$work/tours_all.png" && fail "all: a budget of 0.01 s lights what 1.5 s does"
for rig in tours doorway; do
  "$pandora" analyze "$scene" --rig "$rig" --out "$work/analyze_$rig" -q >"$work/analyze_$rig.out" 2>&1 ||
    fail "analyze --rig $rig: $(cat "$work/analyze_$rig.out")"
  jq -e '.pixel_targets[0].name == "face" and .pixel_targets[0].px_per_m == 250 and
         .pixel_targets[0].share_ge[0] > 0 and .pixel_targets[0].share_ge[0] <= 1' \
    "$work/analyze_$rig/summary.json" >/dev/null || fail "analyze --rig $rig: pixel target face"
done
echo "ok"
