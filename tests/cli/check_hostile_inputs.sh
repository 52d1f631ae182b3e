#!/usr/bin/env bash
# Inputs made on the spot that the outside audit used: 200 KB of '[' (ended in bad_alloc), 6,000
# nested objects (25 s and 1.7 GB), a FIFO as the scene file (blocked forever) and empty option
# values (taken as "unset"). Each must end in exit 2 and one line (expect_error.sh); `timeout`
# turns a hang into a failure. Usage: check_hostile_inputs.sh PANDORA SCENE OUT_DIR
set -eu
pandora=$1; scene=$2; out=$3
expect="$(dirname "$0")/expect_error.sh"
rm -rf "$out"; mkdir -p "$out/in"
python3 -c "print('[' * 200000)" > "$out/in/brackets.json"
python3 -c "print('{\"a\":' * 6000 + '1' + '}' * 6000)" > "$out/in/objects.json"
mkfifo "$out/in/fifo.json"
run() { timeout 20 bash "$expect" "$pandora" "$out/run" "$@"; }
run 'brackets.json: $: arrays and objects nested deeper than 64 levels (line 1)' -- analyze "$out/in/brackets.json" --out "$out/run"
run 'objects.json: $: arrays and objects nested deeper than 64 levels (line 1)' -- analyze "$out/in/objects.json" --out "$out/run"
run 'fifo.json: cannot read the scene file: it is a FIFO' -- analyze "$out/in/fifo.json" --out "$out/run"
run '--rig: the value is empty' -- analyze "$scene" --rig "" --out "$out/run"
run '--fields: the value is empty' -- render "$scene" --from 3,0,2 --at 0,0,0 --fields "" --out "$out/run/a.png"
run '--fields: the value is empty' -- analyze "$scene" --fields "" --out "$out/run"
run '--out: the value is empty' -- analyze "$scene" --out ""
run '--voxel-size: must be a number of metres, greater than 0, got ' -- analyze "$scene" --voxel-size "" --out "$out/run"
echo "ok: deep JSON, a FIFO and empty values each end in one line and exit 2"
