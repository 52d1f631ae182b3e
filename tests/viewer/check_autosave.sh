#!/usr/bin/env bash
# The viewer's autosave: a scripted session edits a camera and ends without saving (as a crash
# would); the next start is refused (exit 2, one line naming the autosave) until the person chooses;
# --recover applies the edit as one undo step and leaves the scene file untouched until saved;
# --discard-autosave deletes it.
# Usage: check_autosave.sh PANDORA OUT_DIR
set -euo pipefail
pandora=$1; out=$2
src=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$out"; mkdir -p "$out"
cp "$src"/examples/trauma_room/scene.json "$out"/scene.json
view() { "$(dirname "$0")"/with_xvfb.sh "$pandora" view "$out"/scene.json --hidden --size 640x360 "$@"; }
fail() { echo "FAIL: $*"; exit 1; }
echo '[{"move": "o2", "by": [0, 0, 0.25]}, {"wait": "fields"}]' > "$out"/edit.json
echo '[{"wait": "fields"}]' > "$out"/idle.json
view --script "$out"/edit.json
[ -f "$out"/scene.json.autosave.json ] || fail "no autosave after an edit"
cmp -s "$out"/scene.json "$src"/examples/trauma_room/scene.json || fail "the scene file changed without a save"
set +e
err=$(view --script "$out"/idle.json 2>&1 >/dev/null); code=$?
set -e
[ "$code" -eq 2 ] || fail "a start with an autosave exited $code, expected 2"
case "$err" in *"scene.json.autosave.json"*"--recover"*) ;; *) fail "unexpected message: $err";; esac
view --script "$out"/idle.json --recover --log "$out"/log.json
jq -e '.[0].undo == "recover autosave (1 cameras)" and .[0].unsaved == 1 and
       ([.[0].cameras[] | select(.id == "o2") | .position[2]] | .[0] > 2.29)' "$out"/log.json >/dev/null ||
  fail "recovery did not restore the moved camera: $(jq -c '.[0] | {undo, unsaved}' "$out"/log.json)"
cmp -s "$out"/scene.json "$src"/examples/trauma_room/scene.json || fail "recovery wrote the scene file"
view --script "$out"/idle.json --discard-autosave
[ ! -e "$out"/scene.json.autosave.json ] || fail "--discard-autosave left the autosave"
echo "ok: autosave, refusal, recovery, discard"
