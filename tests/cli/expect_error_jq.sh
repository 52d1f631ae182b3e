#!/usr/bin/env bash
# A damaged copy of a scene (jq FILTER applied to SOURCE), then expect_error.sh on
# `pandora analyze` of it: exit 2, one line holding EXPECTED, nothing written.
# Usage: expect_error_jq.sh PANDORA SOURCE FILTER WORK_DIR EXPECTED
set -eu
pandora=$1 source=$2 filter=$3 work=$4 expected=$5
rm -rf "$work"
mkdir -p "$work"
jq "$filter" "$source" > "$work/scene.json"
exec bash "$(dirname "$0")/expect_error.sh" "$pandora" "$work/out" "$expected" -- analyze "$work/scene.json" --out "$work/out"
