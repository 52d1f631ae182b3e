#!/usr/bin/env bash
# What a user runs on a bundled example, end to end (docs/robustness.md, "Examples end to end"):
# every rig through `analyze` with the fields the file asks for, `report`, `render` of every view
# (plain and with the fields' coverage slice), and `suggest` + `accept` on a copy of the example.
# Each command must finish (ctest's TIMEOUT turns a hang into a failure) with exit 0 and its outputs.
# usage: check_example.sh PANDORA EXAMPLE_DIR SCENE_FILE OUT_DIR
set -euo pipefail
pandora=$1 example=$2 scene_name=$3 out=$4
rm -rf "$out"
mkdir -p "$out"
cp -r "$example" "$out/example"  # suggest/accept rewrite the scene: never the bundled file
scene="$out/example/$scene_name"
step() { echo "+ $*"; "$@"; }

rigs=$(jq -r '.rigs[].name' "$scene")
views=$(jq -r '(.views // {}) | if type == "array" then .[].name else keys[] end' "$scene")
for rig in $rigs; do
  d="$out/analyze_$rig"
  step "$pandora" analyze "$scene" --rig "$rig" --out "$d" --quiet
  test -s "$d/fields.vdb" && test -s "$d/summary.json"
  # The summary holds the fields the file asks for (the default set when it names none), each finite.
  for f in $(jq -r '(.study.fields // ["coverage", "cameras", "resolution"])[]' "$scene"); do
    case $f in
      coverage) jq -e '.coverage.ge1 | numbers' "$d/summary.json" > /dev/null ;;
      sigma_max) jq -e '.uncertainty.sigma_max_mm.p50 | numbers' "$d/summary.json" > /dev/null ;;
    esac
  done
  jq -e --arg r "$(jq -r .run_id "$d/summary.json")" '.run_id == $r' "$d/summary.json" > /dev/null
  for v in $views; do
    step "$pandora" render "$scene" --rig "$rig" --view "$v" --size 320x180 --out "$out/${rig}_$v.png" --quiet
    step "$pandora" render "$scene" --rig "$rig" --view "$v" --size 320x180 --fields "$d/fields.vdb" \
      --slice coverage --out "$out/${rig}_${v}_coverage.png" --quiet
    test -s "$out/${rig}_$v.png" && test -s "$out/${rig}_${v}_coverage.png"
  done
done
step "$pandora" report "$scene" --out "$out/report" --quiet
test -s "$out/report/report.html"

# suggest + accept on the copy: the first rig's first two fixed cameras (PTZ heads are suggested
# through their own options, tested in cli.ptz).
rig=$(jq -r '.rigs[0].name' "$scene")
cams=$(jq -r '[.rigs[0].cameras[] | select(has("ptz") | not) | .id][0:2] | join(",")' "$scene")
if [ -n "$cams" ]; then
  before=$(sha256sum "$scene" | cut -d' ' -f1)
  step "$pandora" suggest "$scene" --rig "$rig" --cameras "$cams" --objective sigma-mean --points 300 --outer 1 \
    --out "$out/suggestion.json" --quiet
  test -s "$out/suggestion.json"
  set +e
  "$pandora" accept "$out/suggestion.json" --quiet 2> "$out/accept.err"
  rc=$?
  set -e
  cat "$out/accept.err"
  if [ $rc -eq 0 ]; then
    # Applied: the scene changed and its backup holds the old text.
    test "$(sha256sum "$scene" | cut -d' ' -f1)" != "$before"
    test "$(sha256sum "$scene.bak" | cut -d' ' -f1)" = "$before"
    step "$pandora" analyze "$scene" --rig "$rig" --out "$out/after_accept" --quiet
  else
    # Refused (a suggestion that improves nothing): one line, exit 2, the scene untouched.
    test $rc -eq 2 && test "$(wc -l < "$out/accept.err")" -eq 1
    test "$(sha256sum "$scene" | cut -d' ' -f1)" = "$before"
  fi
fi
echo "ok: $(basename "$example")/$scene_name end to end"
