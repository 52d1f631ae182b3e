#!/usr/bin/env bash
# Outputs of another run never sit beside a new run's summary (docs/robustness.md): a streamed run
# with fewer tiles removes the surplus tiles and any fields.vdb, an in-memory run removes every tile,
# in the same transaction as its outputs; render --fields refuses fields whose run id differs from
# the summary.json beside them. An output path naming a FIFO or a character device is refused
# (exit 2, one line) and left as it was (as root, `--out /dev/null` once replaced /dev/null).
# usage: check_stale_outputs.sh PANDORA SCENE OUT_DIR
set -uo pipefail
pandora=$1 scene=$2 out=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$out"
mkdir -p "$out"
d="$out/run"
tiles() { ls "$d/fields" 2> /dev/null | grep -c '^tile_.*\.vdb$'; }

"$pandora" analyze "$scene" --stream --fields coverage,resolution --tile-size 0.4 --out "$d" --quiet || fail "streamed run 1"
n1=$(tiles)
[ "$n1" -ge 3 ] || fail "expected at least 3 tiles, got $n1"
"$pandora" analyze "$scene" --stream --fields coverage,resolution --tile-size 1.0 --out "$d" --quiet || fail "streamed run 2"
n2=$(tiles)
want=$(jq '.stream.tile_count' "$d/summary.json")
[ "$n2" -eq "$want" ] && [ "$n2" -lt "$n1" ] || fail "after a run of $want tiles, $n2 tiles remain (were $n1)"
"$pandora" analyze "$scene" --out "$d" --quiet || fail "in-memory run"
[ "$(tiles)" -eq 0 ] || fail "an in-memory run left $(tiles) streamed tiles"
test -s "$d/fields.vdb" || fail "no fields.vdb"
"$pandora" analyze "$scene" --stream --fields coverage,resolution --tile-size 1.0 --out "$d" --quiet || fail "streamed run 3"
[ ! -e "$d/fields.vdb" ] || fail "a streamed run left the earlier in-memory run's fields.vdb"

# A fields.vdb of another run than the summary beside it: refused with one line.
"$pandora" analyze "$scene" --out "$out/a" --quiet || fail "run a"
"$pandora" analyze "$scene" --out "$out/b" --quiet || fail "run b"
cp "$out/a/fields.vdb" "$out/b/fields.vdb"
"$pandora" render "$scene" --plan --fields "$out/b/fields.vdb" --slice coverage --out "$out/r.png" --quiet 2> "$out/err"
rc=$?
[ $rc -eq 2 ] || fail "render of another run's fields exited $rc"
grep -q 'another run than' "$out/err" && [ "$(wc -l < "$out/err")" -eq 1 ] || fail "message: $(cat "$out/err")"
[ ! -e "$out/r.png" ] || fail "render wrote an image from stale fields"
# The same file beside its own summary renders.
"$pandora" render "$scene" --plan --fields "$out/a/fields.vdb" --slice coverage --out "$out/r.png" --quiet ||
  fail "render of a run's own fields"

# Output paths that are not regular files: a FIFO, and (where mknod is allowed) a character device.
mkfifo "$out/pipe.png"
timeout 60 "$pandora" render "$scene" --plan --out "$out/pipe.png" --quiet 2> "$out/err"
rc=$?
[ $rc -eq 2 ] || fail "render --out FIFO exited $rc"
[ -p "$out/pipe.png" ] || fail "the FIFO was replaced"
grep -q 'FIFO' "$out/err" || fail "message: $(cat "$out/err")"
if mknod "$out/null" c 1 3 2> /dev/null; then
  timeout 60 "$pandora" render "$scene" --plan --out "$out/null" --quiet 2> "$out/err"
  rc=$?
  [ $rc -eq 2 ] || fail "render --out a character device exited $rc"
  [ -c "$out/null" ] || fail "the character device was replaced by a file"
  mkdir -p "$out/dev_out"
  ln -s "$out/null" "$out/dev_out/summary.json"
  timeout 60 "$pandora" analyze "$scene" --out "$out/dev_out" --quiet 2> "$out/err"
  rc=$?
  [ $rc -eq 2 ] || fail "analyze with summary.json a link to a device exited $rc"
  [ -c "$out/null" ] || fail "the character device behind a link was replaced"
  echo "character device refused"
fi
echo "ok: stale outputs removed and refused; FIFO and device outputs refused"
