#!/usr/bin/env bash
# `pandora propose` and `pandora accept --proposal` on the lab built from a room
# (examples/lab_from_room: two walking people, their bodies the targets): three different layouts,
# the best at least as good as the file's ring judged alike, nothing written into the scene until
# accept; accept adds the rig (backup kept) and `analyze` runs it; a changed scene, a proposal out
# of range and bad options are one line and exit 2.
# Usage: check_propose.sh PANDORA EXAMPLE_DIR WORK_DIR
set -u
pandora=$1; example=$2; work=$3
here=$(cd "$(dirname "$0")" && pwd)
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$work"; mkdir -p "$work"
cp -r "$example" "$work/lab"
scene="$work/lab/scene.json"
before=$(sha256sum "$scene" | cut -d' ' -f1)
"$pandora" propose "$scene" --cameras 8 --points 150 --iterations 20000 --compare all --curve 4:6 \
  --out "$work/prop" > "$work/log" || fail "propose exit $?"
cat "$work/log"
test "$(sha256sum "$scene" | cut -d' ' -f1)" = "$before" || fail "propose wrote the scene"
p=$work/prop/proposals.json
jq -e '(.proposals | length) == 3 and ([.proposals[].cameras | length] | all(. == 8))' "$p" > /dev/null || fail "three layouts of 8"
jq -e '[.proposals[] | [.cameras[].position] | tostring] | unique | length == 3' "$p" > /dev/null || fail "layouts not different"
jq -e '.proposals[0].objective >= .proposals[1].objective and .proposals[1].objective >= .proposals[2].objective' "$p" > /dev/null || fail "order"
jq -e '.proposals[0].objective > 0.5 and (.compared | length) == 1 and .compared[0].rig == "ring"' "$p" > /dev/null || fail "objective / compared"
jq -e '[.curve[].cameras] == [4, 5, 6]' "$p" > /dev/null || fail "curve"
test -s "$work/prop/proposals.md" && test -s "$work/prop/curve.csv" || fail "md / csv"
# --polish: suggest's Ceres nudge on each layout, kept only where it improves the objective.
"$pandora" propose "$scene" --cameras 8 --points 100 --iterations 5000 --proposals 1 --polish \
  --out "$work/polish" -q || fail "polish exit $?"
jq -e '.proposals[0] | .objective >= .unpolished_objective and (.polished | type) == "boolean"
       and (.polished == (.objective > .unpolished_objective))' "$work/polish/proposals.json" > /dev/null || fail "polish"
# The same seed and iterations give the same proposals.
"$pandora" propose "$scene" --cameras 8 --points 150 --iterations 20000 --out "$work/again" -q || fail "again"
test "$(jq -c '[.proposals[].cameras[].position]' "$p")" = "$(jq -c '[.proposals[].cameras[].position]' "$work/again/proposals.json")" || fail "not reproducible"
# Accept: a new rig, the old file kept.
bash "$here/expect_error.sh" "$pandora" "$work/none" "which proposal?" -- accept "$p" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/none" "expected a proposal from 1 to 3" -- accept "$p" --proposal 4 || exit 1
"$pandora" accept "$p" --proposal 2 --name picked || fail "accept exit $?"
test "$(sha256sum "$scene.bak" | cut -d' ' -f1)" = "$before" || fail "no backup"
jq -e '[.rigs[].name] == ["ring", "picked"] and ([.rigs[1].cameras[].id] | .[0]) == "picked_1"' "$scene" > /dev/null || fail "rig not added"
"$pandora" analyze "$scene" --rig picked --out "$work/picked" --quiet || fail "analyze picked"
jq -e '.cameras == 8' "$work/picked/summary.json" > /dev/null || fail "8 cameras"
# The scene changed since: refused (unless --force).
bash "$here/expect_error.sh" "$pandora" "$work/none" "changed since the proposals" -- accept "$p" --proposal 1 || exit 1
# A damaged proposals file: one line naming its JSON path, the scene untouched.
jq '.proposals[0].cameras[1].position[2] = "high"' "$p" > "$work/damaged.json"
jq '.scene_sha256 = "'"$(sha256sum "$scene" | cut -d' ' -f1)"'"' "$work/damaged.json" > "$work/damaged2.json"
bash "$here/expect_error.sh" "$pandora" "$work/none" '$.proposals[0].cameras[1].position[2]' -- accept "$work/damaged2.json" --proposal 1 || exit 1
printf '{"pandora_proposals": 1, "proposals": [' > "$work/truncated.json"
bash "$here/expect_error.sh" "$pandora" "$work/none" "malformed JSON" -- accept "$work/truncated.json" --proposal 1 || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o1" "coverageK" -- propose "$scene" --objective sigma-mean --out "$work/o1" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o2" "no model 'x'" -- propose "$scene" --catalogue "$example/cameras.json" --models x --out "$work/o2" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o5" "needs --catalogue" -- propose "$scene" --models x --out "$work/o5" || exit 1
# A catalogue and a budget: the layout's price within it, models from the catalogue.
"$pandora" propose "$scene" --catalogue "$example/cameras.json" --cameras 10 --budget 9000 --points 100 \
  --iterations 5000 --proposals 1 --out "$work/budget" -q || fail "budget exit $?"
jq -e '.proposals[0].price <= 9000 and .proposals[0].price > 0 and .lenses == 5' "$work/budget/proposals.json" > /dev/null || fail "budget"
# The trade-off against cost: every budget's layout within it, more money never fewer cameras here.
"$pandora" propose "$scene" --catalogue "$example/cameras.json" --cameras 10 --points 100 --iterations 3000 \
  --proposals 1 --curve-budgets 2000,6000,20000 --out "$work/costs" -q || fail "curve-budgets exit $?"
jq -e '(.budget_curve | length) == 3 and ([.budget_curve[] | .price <= .budget] | all)
       and .budget_curve[0].cameras < .budget_curve[2].cameras' "$work/costs/proposals.json" > /dev/null || fail "budget curve"
bash "$here/expect_error.sh" "$pandora" "$work/o6" "give --catalogue" -- propose "$scene" --curve-budgets 1000 --out "$work/o6" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o3" "unknown mount kind" -- propose "$scene" --mounts floor --out "$work/o3" || exit 1
bash "$here/expect_error.sh" "$pandora" "$work/o4" "FROM:TO" -- propose "$scene" --curve 5 --out "$work/o4" || exit 1
echo "ok: three layouts proposed, one accepted as a rig and analysed"
