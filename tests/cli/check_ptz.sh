#!/usr/bin/env bash
# PTZ traces on the command line (docs/ptz.md): examples/ptz_home renders in the three modes; the
# path mode lights one camera per second; --ptz all with a budget of 0.01 s lights
# what the home setting sees, so it differs from the current setting's picture; a bad mode and a rig
# without a PTZ camera are one-line errors with exit code 2, and so is selecting a PTZ camera in
# suggest (its file pose is its home, not its current setting). analyze writes the PTZ block of
# summary.json (reach shares that grow with the budget, the tour's period = dwells + moves) and the
# PTZ grids; suggest --ptz-preset / --ptz-tour write suggestions that accept applies to a copy of the
# scene (only that preset or the tour changes, a backup is kept); bad PTZ options are one-line errors.
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
# analyze: the ptz block and grids.
"$pandora" analyze "$scene" --rig home --out "$work/an" -q || fail "analyze"
jq -e '.ptz.cameras[0].id == "dome" and .ptz.min_px_per_m == 250 and .ptz.pixel_target == "face"' "$work/an/summary.json" >/dev/null ||
  fail "ptz summary: $(jq -c .ptz "$work/an/summary.json")"
jq -e '.ptz.cameras[0].within as $w | ($w | length) == 4 and $w[0] <= $w[1] and $w[1] <= $w[2] and $w[2] <= $w[3] and $w[0] > 0 and $w[3] <= .ptz.cameras[0].reachable_share' \
  "$work/an/summary.json" >/dev/null || fail "within shares: $(jq -c .ptz.cameras[0] "$work/an/summary.json")"
# The period: 6 + 3 + 6 + 3 s of dwells and the four moves (63 deg of pan at 45 deg/s, zoom 30 <-> 40 deg).
jq -e '.ptz.cameras[0].tour.period_s > 18 and .ptz.cameras[0].tour.period_s < 30 and .ptz.cameras[0].tour.watched_mean > 0' \
  "$work/an/summary.json" >/dev/null || fail "tour: $(jq -c .ptz.cameras[0].tour "$work/an/summary.json")"
strings "$work/an/fields.vdb" | grep -q 'ptz_reach_time/dome' || fail "no ptz_reach_time/dome grid"
strings "$work/an/fields.vdb" | grep -q 'ptz_gap/dome' || fail "no ptz_gap/dome grid"
# suggest + accept on a copy.
cp "$scene" "$work/copy.json"
"$pandora" suggest "$work/copy.json" --rig home --ptz-preset dome:west_door --target-region west_door --points 400 \
  --out "$work/sp.json" -q || fail "suggest --ptz-preset"
jq -e '.kind == "ptz_preset" and .improved and .ptz.seen_after > .ptz.seen_before' "$work/sp.json" >/dev/null ||
  fail "preset suggestion: $(jq -c .ptz "$work/sp.json")"
"$pandora" accept "$work/sp.json" -q || fail "accept preset"
[ -f "$work/copy.json.bak" ] || fail "no backup"
cmp -s "$work/copy.json.bak" "$scene" || fail "the backup is not the original"
jq -e --slurpfile s "$work/sp.json" '.rigs[0].cameras[0].ptz.presets[1] as $p | ($p.pan_deg - $s[0].ptz.after.pan_deg | fabs) < 1e-9 and ($p.tilt_deg - $s[0].ptz.after.tilt_deg | fabs) < 1e-9' \
  "$work/copy.json" >/dev/null || fail "preset not written: $(jq -c .rigs[0].cameras[0].ptz.presets[1] "$work/copy.json")"
[ "$(jq -c 'del(.rigs[0].cameras[0].ptz.presets[1])' "$work/copy.json")" = "$(jq -c 'del(.rigs[0].cameras[0].ptz.presets[1])' "$scene")" ] ||
  fail "accept changed more than the preset"
"$pandora" suggest "$work/copy.json" --rig home --ptz-tour dome --points 400 --out "$work/st.json" -q || fail "suggest --ptz-tour"
jq -e '.kind == "ptz_tour" and (.ptz.tour_after | sort) == [0, 1, 2, 3]' "$work/st.json" >/dev/null || fail "tour suggestion"
if jq -e .improved "$work/st.json" >/dev/null; then
  "$pandora" accept "$work/st.json" -q || fail "accept tour"
  jq -e --slurpfile s "$work/st.json" '[.rigs[0].cameras[0].ptz.tour[].preset] == $s[0].ptz.presets_after' "$work/copy.json" >/dev/null ||
    fail "tour not written"
fi
err() { bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/e$1" "$2" -- "${@:3}" >/dev/null || fail "error $1 ($2)"; }
err 1 "has no preset 'porch'" suggest "$scene" --rig home --ptz-preset dome:porch --out "$work/e1/s.json"
err 2 "tour stops" suggest "$scene" --rig home_path --ptz-tour dome --out "$work/e2/s.json"
err 3 "--tour-objective" suggest "$scene" --rig home --ptz-tour dome --tour-objective longest --out "$work/e3/s.json"
err 4 "--cameras" suggest "$scene" --rig home --ptz-tour dome --cameras dome --out "$work/e4/s.json"
err 5 "no region 'garage'" suggest "$scene" --rig home --ptz-preset dome:window --target-region garage --out "$work/e5/s.json"
err 6 "expected ID:PRESET" suggest "$scene" --rig home --ptz-preset dome --out "$work/e6/s.json"
err 7 "no camera 'cam9'" suggest "$scene" --rig home --ptz-tour cam9 --out "$work/e7/s.json"
jq '.study.ptz.pixel_target = "badge"' "$scene" >"$work/badtarget.json"
err 8 '$.study.ptz.pixel_target' analyze "$work/badtarget.json" --rig home --out "$work/e8/out"
echo "ok"
