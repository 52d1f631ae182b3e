#!/usr/bin/env bash
# The suggest / accept cycle through the CLI on a copy of tests/data/suggest_ring.json:
# suggest leaves the scene untouched; a partial accept writes a backup and changes only that camera's
# pose, in its look_at form; accepting the rest of the now stale suggestion is refused (exit 2, one line, file unchanged);
# --force accepts it with a second backup.
# Usage: check_suggest_accept.sh PANDORA SCENE WORK_DIR
set -u
pandora=$1; scene=$2; work=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$work"; mkdir -p "$work"
cp "$scene" "$work/scene.json"
orig=$(sha256sum < "$work/scene.json")
"$pandora" suggest "$work/scene.json" --cameras c2,c4 --max-move 0.3 --max-rotate 30 \
  --objective coverage4 --points 300 --out "$work/suggestion.json" > "$work/suggest.txt" || fail "suggest exit $?"
grep -q "coverage4 improved" "$work/suggest.txt" || fail "no improvement reported: $(cat "$work/suggest.txt")"
grep -q "^c4 " "$work/suggest.txt" || fail "table lacks camera c4"
[ "$(sha256sum < "$work/scene.json")" = "$orig" ] || fail "suggest changed the scene file"
[ ! -e "$work/scene.json.bak" ] || fail "suggest wrote a backup"

"$pandora" accept "$work/suggestion.json" --cameras c4 > "$work/accept.txt" || fail "accept exit $?"
cmp -s "$work/scene.json.bak" "$scene" || fail "backup differs from the original"
[ "$(sha256sum < "$work/scene.json")" != "$orig" ] || fail "accept did not change the scene"
python3 - "$scene" "$work/scene.json" <<'PY' || fail "more than c4's pose changed"
import json, sys
a = json.load(open(sys.argv[1])); b = json.load(open(sys.argv[2]))
for j in (a, b):
    cam = j["rigs"][0]["cameras"][3]
    for k in ("position", "look_at", "up", "quaternion"):
        cam.pop(k, None)
assert a == b
# c4 keeps its look_at form (docs/suggest.md, "Accept"); c2 is untouched.
c4 = json.load(open(sys.argv[2]))["rigs"][0]["cameras"][3]
assert "look_at" in c4 and "quaternion" not in c4, c4
assert "look_at" in json.load(open(sys.argv[2]))["rigs"][0]["cameras"][1]
PY
after=$(sha256sum < "$work/scene.json")

err=$("$pandora" accept "$work/suggestion.json" --cameras c2 2>&1 >/dev/null); code=$?
[ "$code" -eq 2 ] || fail "stale accept exit $code, expected 2"
[ "$(printf '%s\n' "$err" | grep -c .)" -eq 1 ] || fail "stale accept printed more than one line: $err"
case "$err" in *"changed since"*) ;; *) fail "stale accept message: $err";; esac
[ "$(sha256sum < "$work/scene.json")" = "$after" ] || fail "refused accept changed the scene"
[ ! -e "$work/scene.json.bak.1" ] || fail "refused accept wrote a backup"

"$pandora" accept "$work/suggestion.json" --cameras c2 --force > /dev/null || fail "forced accept failed"
[ -e "$work/scene.json.bak.1" ] || fail "forced accept wrote no second backup"
"$pandora" suggest "$work/scene.json" --cameras c1 --max-move 0 --max-rotate 0 --objective coverage4 \
  --points 200 --out "$work/zero.json" > "$work/zero.txt" || fail "zero-limit suggest exit $?"
grep -q "limits are zero" "$work/zero.txt" || fail "zero limits message missing"
err=$("$pandora" accept "$work/zero.json" 2>&1 >/dev/null); code=$?
[ "$code" -eq 2 ] || fail "accepting a no-improvement suggestion: exit $code"
"$pandora" suggest "$work/scene.json" --cameras c4 --perturb 0.2,10 --objective coverage4 --points 200 \
  --out "$work/perturbed.json" > /dev/null || fail "perturbed suggest exit $?"
before=$(sha256sum < "$work/scene.json")
err=$("$pandora" accept "$work/perturbed.json" 2>&1 >/dev/null); code=$?
[ "$code" -eq 2 ] || fail "accepting a perturbed suggestion: exit $code"
case "$err" in *"perturbed"*) ;; *) fail "perturbed accept message: $err";; esac
[ "$(sha256sum < "$work/scene.json")" = "$before" ] || fail "refused accept changed the scene"
ls "$work" | grep -q "tmp-" && fail "temporary files left: $(ls "$work")"
echo "ok"
