#!/usr/bin/env bash
# The viewer's Suggest and `pandora suggest` are one door (app::PrepareSuggest): on a copy of the
# mocap lab (two people moving through six poses), the same options give the same suggestion in
# both -- over time (the study's targets at every sample), on a person's surface with region points,
# and in the static region with the mix objective: the objective before and after to 1e-12
# (relative) and every suggested camera centre to 1e-9 m. A suggestion that does not improve is
# refused by the viewer's accept as by `pandora accept` (exit 2, one line, the file unchanged). The
# viewer's Compare of the scene with people gives the numbers over time that `pandora analyze` does.
# Usage: check_suggest_parity.sh PANDORA OUT_DIR
set -euo pipefail
pandora=$1; out=$2
src=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$out"; mkdir -p "$out"
cp "$src"/examples/mocap_lab/scene.json "$out"/scene.json
fail() { echo "FAIL: $*"; exit 1; }
view() {  # view SCRIPT LOG
  local run=("$(dirname "$0")"/with_xvfb.sh "$pandora" view "$out"/scene.json --script "$1"
             --hidden --size 320x240 --log "$2")
  "${run[@]}"
}

# case NAME 'CLI OPTIONS' 'SCRIPT KEYS'
check() {
  local name=$1 cli=$2 keys=$3
  # shellcheck disable=SC2086
  "$pandora" suggest "$out"/scene.json --cameras r1,r5 --max-move 0.2 --max-rotate 15 --points 300 --seed 3 \
    $cli --out "$out/$name.json" --quiet
  echo "[{\"suggest\": [\"r1\", \"r5\"], \"max_move\": 0.2, \"max_rotate\": 15, \"points\": 300, \"seed\": 3 $keys},
        {\"wait\": \"suggest\"}]" > "$out/$name.script.json"
  view "$out/$name.script.json" "$out/$name.log.json"
  python3 - "$out/$name.json" "$out/$name.log.json" "$name" <<'PY'
import json, sys
cli = json.load(open(sys.argv[1]))
log = json.load(open(sys.argv[2]))
v = [e for e in log if "suggestion" in e][-1]["suggestion"]
name = sys.argv[3]
def close(a, b, rel):
    return abs(a - b) <= rel * max(1.0, abs(a), abs(b))
o = cli["objective"]
assert o["name"] == v["objective"], (name, o["name"], v["objective"])
for k in ("before", "after"):
    assert close(o[k], v[k], 1e-12), (name, k, o[k], v[k])
assert cli["improved"] == v["improved"], (name, cli["improved"], v["improved"])
cams = {c["id"]: c["after"]["position"] for c in cli["cameras"]}
assert sorted(cams) == sorted(v["positions"]), (name, sorted(cams), sorted(v["positions"]))
for i, p in cams.items():
    q = v["positions"][i]
    assert max(abs(a - b) for a, b in zip(p, q)) <= 1e-9, (name, i, p, q)
print(f"{name}: {o['name']} {o['before']:.6g} -> {o['after']:.6g} in both; {len(cams)} centres equal; "
      f"viewer: over {v['targets']}")
PY
}
check over_time "--over-time" ', "over_time": true'
check surface "--target-surface a_torso --target-surface a_head --with-region --objective sigma-mean" \
  ', "target_surface": ["a_torso", "a_head"], "with_region": true, "objective": "sigma-mean"'
check mix "--objective mix --weights 1,0.5,0.2 --outer 2" ', "objective": "mix", "weights": [1, 0.5, 0.2], "outer": 2'

# Nothing may move: no improvement. `pandora accept` and the viewer's accept both refuse it.
"$pandora" suggest "$out"/scene.json --cameras r1 --max-move 0 --max-rotate 0 --points 200 --out "$out"/none.json --quiet
jq -e '.improved == false' "$out"/none.json >/dev/null || fail "a suggestion without freedom improved"
set +e
"$pandora" accept "$out"/none.json 2> "$out"/accept.err; rc_cli=$?
echo '[{"suggest": ["r1"], "max_move": 0, "max_rotate": 0, "points": 200}, {"wait": "suggest"},
       {"accept": "all"}, {"save": 1}]' > "$out"/none.script.json
view "$out"/none.script.json "$out"/none.log.json 2> "$out"/view.err; rc_view=$?
set -e
[ "$rc_cli" = 2 ] && [ "$(wc -l < "$out"/accept.err)" = 1 ] || fail "pandora accept: exit $rc_cli, $(cat "$out"/accept.err)"
[ "$rc_view" = 2 ] || fail "the viewer accepted a suggestion without improvement (exit $rc_view)"
grep -q "offers no improvement" "$out"/view.err || fail "the viewer's refusal does not say why: $(cat "$out"/view.err)"
cmp -s "$out"/scene.json "$src"/examples/mocap_lab/scene.json || fail "the scene file changed"
# The viewer's numbers of a scene with people are the numbers over time, as `pandora analyze` gives
# them (its live fields alone are the empty volume's): Compare against the analyze summary.
"$pandora" analyze "$out"/scene.json --out "$out"/analyze --quiet
echo '[{"wait": "fields"}, {"compare": "saved"}]' > "$out"/compare.script.json
view "$out"/compare.script.json "$out"/compare.log.json
python3 - "$out"/analyze/summary.json "$out"/compare.log.json <<'PY'
import json, sys
t = json.load(open(sys.argv[1]))["time"]
log = json.load(open(sys.argv[2]))
rows = {r["key"]: r["values"] for r in [e for e in log if "comparison" in e][-1]["comparison"]["rows"]}
live = log[0]["fields"].get("time")  # the Fields panel's numbers with the people, after "wait"
assert live and live["always"] == t["always"] and live["mean"] == t["mean"], ("live numbers over time", live)
worst = min(s["ge_k"] for s in t["samples"])
for key, want in (("time_always", t["always"]), ("time_mean", t["mean"]), ("time_worst_sample", worst),
                  ("time_sigma_max_p90_mm", t["sigma_max_mm"]["p90"])):
    assert key in rows, ("the viewer's Compare has no row", key)
    assert abs(rows[key][0] - want) <= 1e-12 * max(1, abs(want)), (key, rows[key][0], want)
print(f"viewer Compare over time = analyze: always {t['always']:.4f}, mean {t['mean']:.4f}, worst sample {worst:.4f}")
PY
echo "ok: the viewer's suggest equals pandora suggest; both refuse a suggestion without improvement"
