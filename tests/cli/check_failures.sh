#!/usr/bin/env bash
# N-1 robustness on the command line (docs/failures.md): the trauma room's octagon at 1 cm. analyze
# prints the N-1 table and writes summary.json's "robustness"; `analyze --disable W` (W: the worst
# camera it names) gives exactly that row's coverage shares, triangulable share and sigma_max
# percentiles; render and report take --disable; an unknown id or an empty value is the one-line
# error with exit code 2, naming the option, the id and the rig's ids.
# Usage: check_failures.sh PANDORA TRAUMA_ROOM_JSON WORK_DIR
set -u
pandora=$1; scene=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
common=(--rig octagon --voxel-size 0.01 --fields coverage,cameras,sigma_max)

"$pandora" analyze "$scene" "${common[@]}" --out "$work/a" >"$work/a.out" 2>/dev/null || fail "analyze exit code $?"
grep -q '^N-1 (one camera fails), seen by >= 3: intact' "$work/a.out" || fail "no N-1 line: $(cat "$work/a.out")"
s="$work/a/summary.json"
[ "$(jq '.robustness.per_camera | length' "$s")" -eq 8 ] || fail "rows: $(jq -c .robustness "$s")"
[ "$(jq '.robustness.k' "$s")" -eq 3 ] || fail "k"
# Every value a finite number (the octagon triangulates everywhere it sees, so nothing is null).
[ "$(jq '[.robustness.per_camera[] | .ge1, .ge2, .ge3, .ge_k, .triangulable, .sigma_max_p50_mm, .sigma_max_p90_mm
          | type == "number"] | all' "$s")" = true ] || fail "a value is not a number"
[ "$(jq '.robustness.ge_k == .coverage.ge3' "$s")" = true ] || fail "intact ge_k differs from coverage.ge3"
worst=$(jq -r '.robustness.worst.camera' "$s")
row=$(jq -c --arg w "$worst" '.robustness.per_camera[] | select(.id == $w)' "$s")
[ -n "$row" ] || fail "no row for the worst camera $worst"
# The worst failure costs coverage, and the worst row has the lowest ge_k.
[ "$(jq '.robustness.worst.loss > 0' "$s")" = true ] || fail "no loss: $(jq -c .robustness.worst "$s")"
[ "$(jq '([.robustness.per_camera[].ge_k] | min) == .robustness.worst.ge_k' "$s")" = true ] || fail "worst is not the min"

"$pandora" analyze "$scene" "${common[@]}" --disable "$worst" --out "$work/d" -q || fail "analyze --disable exit code $?"
d="$work/d/summary.json"
[ "$(jq --arg w "$worst" '.per_camera[] | select(.id == $w) | .enabled' "$d")" = false ] || fail "$worst not disabled"
[ "$(jq '.cameras' "$d")" -eq 7 ] || fail "enabled cameras"
for key in ge1 ge2 ge3; do
  a=$(jq ".$key" <<<"$row"); b=$(jq ".coverage.$key" "$d")
  [ "$a" = "$b" ] || fail "$key: N-1 row $a, analyze --disable $worst $b"
done
a=$(jq '.triangulable' <<<"$row"); b=$(jq '.uncertainty.triangulable' "$d")
[ "$a" = "$b" ] || fail "triangulable: row $a, --disable $b"
for p in 50 90; do
  a=$(jq ".sigma_max_p${p}_mm" <<<"$row"); b=$(jq ".uncertainty.sigma_max_mm.p$p" "$d")
  [ "$a" = "$b" ] || fail "sigma_max p$p: row $a, --disable $b"
done

"$pandora" render "$scene" --rig octagon --disable o1,o2 --view overview --size 64x40 --out "$work/r.png" -q ||
  fail "render --disable exit code $?"
"$pandora" report "$scene" --rig octagon --disable "$worst" --voxel-size 0.02 --width 64 --camera-width 32 \
  --out "$work/report" -q || fail "report --disable exit code $?"
grep -q '<h2 id="robustness">Robustness</h2>' "$work/report/report.html" || fail "no robustness section"
# The disabled camera has no row; the other seven do, the table shows the five most critical.
[ "$(grep -c '<tr><td>o[1-8]</td><td>[0-9.]*%</td>' "$work/report/report.html")" -eq 5 ] || fail "robustness rows"
grep -q "<tr><td>$worst</td><td>[0-9.]*%</td>" "$work/report/report.html" && fail "disabled $worst has a row"

err() { bash "$(dirname "$0")/expect_error.sh" "$pandora" "$@" >/dev/null || fail "bad --disable: $*"; }
err "$work/bad1" "--disable: no camera 'zz' in rig 'octagon' (hint: cameras: o1, o2" -- \
  analyze "$scene" --rig octagon --disable o1,zz --out "$work/bad1"
err "$work/bad2" "--disable: the value is empty" -- analyze "$scene" --rig octagon --disable "" --out "$work/bad2"
err "$work/bad3" "--disable: no camera 'zz' in rig 'octagon'" -- \
  render "$scene" --rig octagon --disable zz --view overview --out "$work/bad3/r.png"
err "$work/bad4" "--disable: no camera 'zz' in rig 'octagon', 'grid4x2'" -- report "$scene" --disable zz --out "$work/bad4"
err "$work/bad5" "--disable: no camera 'zz' in rig 'octagon'" -- \
  suggest "$scene" --rig octagon --disable zz --cameras o1 --out "$work/bad5/s.json"
echo "ok"
