#!/usr/bin/env bash
# A user's scene file keeps its mode through `pandora accept`, and the backup gets the same mode (a
# mode-600 scene must not get a world-readable .bak); an output replacing a file keeps that file's
# mode. Usage: check_permissions.sh PANDORA SCENE OUT_DIR
set -eu
pandora=$1; scene=$2; out=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$out"; mkdir -p "$out"
umask 022
cp "$scene" "$out/scene.json"
chmod 600 "$out/scene.json"
"$pandora" suggest "$out/scene.json" --cameras c2,c4 --max-move 0.3 --max-rotate 30 --objective coverage4 --points 300 --out "$out/s.json" --quiet || fail "suggest failed"
jq -e .improved "$out/s.json" >/dev/null || fail "no improvement to accept"
chmod 640 "$out/s.json"
"$pandora" suggest "$out/scene.json" --cameras c2,c4 --max-move 0.3 --max-rotate 30 --objective coverage4 --points 300 --out "$out/s.json" --quiet || fail "suggest failed"
[ "$(stat -c %a "$out/s.json")" = 640 ] || fail "the replaced suggestion lost its mode: $(stat -c %a "$out/s.json")"
"$pandora" accept "$out/s.json" --quiet || fail "accept failed"
[ "$(stat -c %a "$out/scene.json")" = 600 ] || fail "scene mode $(stat -c %a "$out/scene.json"), expected 600"
[ "$(stat -c %a "$out/scene.json.bak")" = 600 ] || fail "backup mode $(stat -c %a "$out/scene.json.bak"), expected 600"
if ls -A "$out" | grep -q '\.pandora-staging\|\.tmp-'; then fail "litter: $(ls -A "$out")"; fi
echo "ok: scene 600 and its backup 600 after accept; a replaced output keeps 640"
