#!/usr/bin/env bash
# scripts/same_text.py (behind scripts/same_outputs.sh) tells apart what a reorganisation may change
# (timings, run ids, the output folder) from what it may not: two outputs that differ only there
# compare equal, one changed value or one changed word does not.
# usage: check_same_text.sh PYTHON OUT_DIR
set -euo pipefail
python=$1 out=$2
here=$(cd "$(dirname "$0")" && pwd)
tool="$here/../../scripts/same_text.py"
rm -rf "$out" && mkdir -p "$out/a" "$out/b"
same() { "$python" "$tool" "$out/a/$1" "$out/b/$1" "$out/a" "$out/b" || { echo "FAIL: $1 should compare equal"; exit 1; }; }
differ() { if "$python" "$tool" "$out/a/$1" "$out/b/$1" "$out/a" "$out/b"; then echo "FAIL: $1 should differ"; exit 1; fi; }

# JSON: timings at any depth, a table's timing column, the run id and the folder.
echo '{"run_id": "1f2e", "path": "'"$out/a"'/x/scene.json", "seconds": 0.5, "inner": {"cpu_seconds": 3, "ge1": 0.25},
       "trace": {"columns": ["seconds", "evaluations"], "rows": [[0.1, 4], [0.2, 9]]}}' > "$out/a/s.json"
echo '{"run_id": "9c9c", "path": "'"$out/b"'/x/scene.json", "seconds": 0.7, "inner": {"cpu_seconds": 5, "ge1": 0.25},
       "trace": {"columns": ["seconds", "evaluations"], "rows": [[0.3, 4], [0.9, 9]]}}' > "$out/b/s.json"
same s.json
sed -i 's/"ge1": 0.25/"ge1": 0.2500001/' "$out/b/s.json"
differ s.json
sed -i 's/"ge1": 0.2500001/"ge1": 0.25/; s/\[0.9, 9\]/[0.9, 8]/' "$out/b/s.json"
differ s.json

# HTML: the embedded summaries as JSON, timing rows and timings in the text masked.
html() {  # $1 folder, $2 seconds, $3 coverage, $4 text
  printf '<html><title>%s/x/scene.json</title>\n<script type="application/json" class="summary">{"seconds": %s, "ge1": %s}</script>\n<tr><td>Field evaluation (s)</td><td>%s</td></tr>\n<p>%s (simulated in %s ms).</p>\n' \
    "$1" "$2" "$3" "$2" "$4" "$2" > "$1/r.html"
}
html "$out/a" 0.06 0.5 "1604 of 2000 poses"
html "$out/b" 0.05 0.5 "1604 of 2000 poses"
same r.html
html "$out/b" 0.05 0.6 "1604 of 2000 poses"
differ r.html
html "$out/b" 0.05 0.5 "1605 of 2000 poses"
differ r.html
echo "ok: same_text masks timings, run ids and folders, and nothing else"
