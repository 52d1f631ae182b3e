#!/usr/bin/env bash
# Behaviour unchanged, checked (issue 28: a reorganisation must not change one output). Two modes:
#
#   scripts/same_outputs.sh run PANDORA OUT_DIR
#       every bundled example as a user runs it (tests/cli/check_example.sh: analyze every rig with
#       the fields its file asks for, render every view plain and with a coverage slice, report,
#       suggest + accept on a copy and analyze after), plus examples/python_study.py when the
#       Python module is built beside PANDORA, each into OUT_DIR/<example>.
#   scripts/same_outputs.sh compare BEFORE_DIR AFTER_DIR
#       exit 0 when the two runs agree: every fields.vdb voxel for voxel and every summary.json but
#       for timings and run ids (tests/cli/same_fields.py), every PNG and EXR byte for byte, the
#       suggestion files and the accepted scene files equal but for timings, run ids and the output
#       folder, the report's embedded summaries the same way and the rest of its HTML but for its
#       timing rows, the Python study's printout but for timings (scripts/same_text.py). Prints
#       every difference, then exits 1.
#
# Typical use: build the commit before the change into build-before/, the change into build/, then
#   scripts/same_outputs.sh run build-before/pandora /tmp/before
#   scripts/same_outputs.sh run build/pandora /tmp/after
#   scripts/same_outputs.sh compare /tmp/before /tmp/after
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
# Debian's Python has numpy and pyopenvdb (scripts/setup.sh); a python3 earlier on PATH may not.
python=${PYTHON:-$(test -x /usr/bin/python3 && echo /usr/bin/python3 || echo python3)}

examples="trauma_room/scene.json trauma_room/scene_no_medics.json trauma_room/viewing_station.json
capture_stage/scene.json mocap_lab/scene.json ptz_corridor/scene.json ptz_home/scene.json render_bench/scene.json"

case ${1:-} in
run)
  pandora=$(cd "$(dirname "$2")" && pwd)/$(basename "$2")
  out=$3
  mkdir -p "$out"
  out=$(cd "$out" && pwd)
  for e in $examples; do
    dir=${e%%/*} file=${e#*/}
    name="${dir}_${file%.json}"
    echo "== $name"
    # Run from OUT_DIR with a relative folder: the paths written into the outputs (the scene's, in
    # summaries, suggestion files and reports) are then the same for every OUT_DIR.
    (cd "$out" && bash "$root/tests/cli/check_example.sh" "$pandora" "$root/examples/$dir" "$file" "$name" > "$name.log" 2>&1) ||
      { cat "$out/$name.log"; echo "failed: $name"; exit 1; }
  done
  module=$(dirname "$pandora")/python
  if [ -d "$module" ] && ls "$module"/pandora*.so > /dev/null 2>&1; then
    echo "== python_study"
    mkdir -p "$out/python_study"
    (cd "$out/python_study" && PYTHONPATH="$module" "$python" "$root/examples/python_study.py" > printout.txt 2>&1) ||
      { cat "$out/python_study/printout.txt"; echo "failed: python_study"; exit 1; }
  fi
  echo "ok: outputs in $out"
  ;;
compare)
  a=$(cd "$2" && pwd) b=$(cd "$3" && pwd)
  differ=0
  note() { echo "differs: $*"; differ=1; }
  # The same files on both sides.
  (cd "$a" && find . -type f ! -name '*.log' ! -name '*.err' ! -name '*.bak*' | sort) > /tmp/same_outputs_a.$$
  (cd "$b" && find . -type f ! -name '*.log' ! -name '*.err' ! -name '*.bak*' | sort) > /tmp/same_outputs_b.$$
  if ! cmp -s /tmp/same_outputs_a.$$ /tmp/same_outputs_b.$$; then
    note "the file lists: $(diff /tmp/same_outputs_a.$$ /tmp/same_outputs_b.$$ | grep '^[<>]' | head -5 | tr '\n' ' ')"
  fi
  # Fields and summaries, per analyzed folder.
  while read -r d; do
    [ -d "$b/$d" ] || continue
    "$python" "$root/tests/cli/same_fields.py" "$a/$d" "$b/$d" > /tmp/same_outputs_f.$$ 2>&1 || note "$d: $(head -1 /tmp/same_outputs_f.$$)"
  done < <(cd "$a" && find . -name summary.json ! -path '*/report/*' -printf '%h\n' | sort)
  # Pictures byte for byte; JSON, HTML and text but for timings, run ids and the output folder
  # (scripts/same_text.py).
  while read -r f; do
    [ -f "$b/$f" ] || continue
    case $f in
      */fields.vdb|*/summary.json) ;;
      *.png|*.exr|*.vdb) cmp -s "$a/$f" "$b/$f" || note "$f (bytes)" ;;
      *.json|*.html|*.txt|*.csv)
        "$python" "$here/same_text.py" "$a/$f" "$b/$f" "$a" "$b" > /tmp/same_outputs_f.$$ 2>&1 ||
          note "$f: $(head -1 /tmp/same_outputs_f.$$)" ;;
      *) cmp -s "$a/$f" "$b/$f" || note "$f (bytes)" ;;
    esac
  done < /tmp/same_outputs_a.$$
  rm -f /tmp/same_outputs_[abf].$$
  [ $differ -eq 0 ] && echo "ok: the same outputs" || { echo "outputs differ"; exit 1; }
  ;;
*)
  sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
  ;;
esac
