#!/usr/bin/env bash
# Rig warnings on the command line (docs/user-guide.md, "Warnings"): a camera inside the solid block
# of tests/data/minimal.json and one looking away. Checks, for analyze, render, report and
# export-surface: exit code 0, one stderr line per warning in the form
#   pandora: warning: FILE: JSON_PATH: REASON
# and, for analyze, the same warnings in summary.json; with --quiet nothing on stderr but the same
# summary.json; and on bad input (here --voxel-size 0 and a bad --out) the one-line error alone.
# Usage: check_warnings.sh PANDORA MINIMAL_JSON WORK_DIR
set -u
pandora=$1; minimal=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }
scene="$work/scene.json"
jq '.rigs[0].cameras += [
      {"id": "boxed", "position": [0, 0, 0.2], "look_at": [1, 0, 0.2], "resolution": [64, 48], "hfov_deg": 60},
      {"id": "away", "position": [0, -2, 1], "look_at": [0, -4, 1], "resolution": [64, 48], "hfov_deg": 60}]' \
  "$minimal" >"$scene"
expected_lines=(
  "pandora: warning: $scene: \$.rigs[0].cameras[2].position: camera 'boxed' is inside the solid object 'block'"
  "pandora: warning: $scene: \$.rigs[0].cameras[3]: camera 'away' sees none of ")

check_stderr() {  # FILE WHAT
  local n
  n=$(grep -c . "$1")
  [ "$n" -eq 2 ] || fail "$2: $n stderr lines, expected 2: $(cat "$1")"
  for i in 0 1; do
    sed -n "$((i + 1))p" "$1" | grep -qF "${expected_lines[$i]}" || fail "$2: line $((i + 1)) is '$(sed -n "$((i + 1))p" "$1")'"
  done
}

"$pandora" analyze "$scene" --out "$work/a" >/dev/null 2>"$work/a.err" || fail "analyze exit code $?"
check_stderr "$work/a.err" analyze
[ "$(jq '.warnings | length' "$work/a/summary.json")" -eq 2 ] || fail "summary.json has no 2 warnings"
[ "$(jq -r '.warnings[0].kind + " " + .warnings[0].path' "$work/a/summary.json")" = 'inside_solid $.rigs[0].cameras[2].position' ] ||
  fail "summary.json warning 0: $(jq -c '.warnings[0]' "$work/a/summary.json")"
[ "$(jq -r '.warnings[1].kind' "$work/a/summary.json")" = sees_no_region ] || fail "summary.json warning 1"

"$pandora" analyze "$scene" --out "$work/q" --quiet >"$work/q.out" 2>"$work/q.err" || fail "analyze --quiet exit code $?"
[ ! -s "$work/q.err" ] && [ ! -s "$work/q.out" ] || fail "--quiet printed something: $(cat "$work/q.err")"
cmp -s <(jq -S .warnings "$work/a/summary.json") <(jq -S .warnings "$work/q/summary.json") ||
  fail "--quiet changed the warnings in summary.json"

"$pandora" render "$scene" --from 3,-3,2 --at 0,0,0.3 --size 64x48 --out "$work/r.png" >/dev/null 2>"$work/r.err" || fail "render exit code $?"
check_stderr "$work/r.err" render
"$pandora" export-surface "$scene" --spacing 0.1 --out "$work/s.ply" >/dev/null 2>"$work/s.err" || fail "export-surface exit code $?"
check_stderr "$work/s.err" export-surface
"$pandora" report "$scene" --out "$work/rep" --width 64 --camera-width 32 >/dev/null 2>"$work/rep.err" || fail "report exit code $?"
check_stderr "$work/rep.err" report
grep -q "camera &#39;boxed&#39; is inside\|camera 'boxed' is inside" "$work/rep/report.html" || fail "the report does not list the warning"

# Bad input: exactly the one error line, no warning.
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/bad1" "--voxel-size: must be a number of metres, greater than 0" -- \
  analyze "$scene" --voxel-size 0 --out "$work/bad1" >/dev/null || fail "analyze --voxel-size 0"
bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/bad2" "output folder" -- \
  render "$scene" --from 3,-3,2 --at 0,0,0.3 --size 8x8 --out /proc/pandora_cannot_write_here/a.png >/dev/null ||
  fail "render to an unwritable folder"
echo "ok: warnings on stderr (analyze, render, export-surface, report), in summary.json, quiet with --quiet, absent on bad input"
