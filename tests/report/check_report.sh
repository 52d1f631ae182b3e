#!/usr/bin/env bash
# Checks `pandora report` output (docs/report.md, "How the test checks it").
#
#   check_report.sh run PANDORA SCENE OUT_DIR RIGS [ARGS...]
#       Runs `pandora report SCENE --out OUT_DIR ARGS...`, then checks OUT_DIR/report.html with both
#       checkers below and that it has one column per rig in RIGS (comma-separated) with each rig's
#       name in the column headers.
#   check_report.sh numbers PANDORA SCENE HTML RIGS WORK_DIR
#       Runs `pandora analyze` for each rig and requires the summary embedded in the report for that
#       rig to equal analyze's summary.json (coverage, uncertainty, region and per-camera numbers;
#       jq -S), and the numbers table to show analyze's coverage >= 2 and sigma_max p50 values.
#   check_report.sh negative HTML WORK_DIR
#       Proves the checkers can fail: makes copies of HTML with one PNG corrupted, one SVG truncated,
#       and one external image added, and requires each checker to reject each copy it covers.
#
# Static checker (no Python): only data: URIs in src attributes, no external references, the <img>
# count equals the page's data-expected-images, every data URI base64-decodes, PNGs have the PNG
# signature, an IHDR chunk first and an IEND chunk last, SVGs are well-formed XML (xmllint) with an
# <svg> root.
# Browser checker: headless Chromium loads the page from file:// with the network off; the page's own
# script (run on the load event) must report "images ok: N of N decoded" (every <img> complete with
# naturalWidth > 0, N the expected count), and Chromium must log no console message at all (the page
# logs nothing; a blocked external load or a script error would log one).
set -uo pipefail

fail() { echo "FAIL: $*"; return 1; }

static_check() {
  local html=$1 tmp n=0 expected imgs uri mime
  tmp=$(mktemp -d)
  expected=$(grep -o 'data-expected-images="[0-9]*"' "$html" | grep -o '[0-9]*')
  [ -n "$expected" ] || { rm -rf "$tmp"; fail "no data-expected-images"; return 1; }
  imgs=$(grep -o '<img ' "$html" | wc -l)
  [ "$imgs" -eq "$expected" ] || { rm -rf "$tmp"; fail "$imgs <img> tags, $expected expected"; return 1; }
  if grep -qiE '(src|href)="(https?:|//|file:|[a-z0-9_./-]+\.(png|svg|js|css)")|<link |@import|url\((https?:|//)' "$html"; then
    rm -rf "$tmp"; fail "external reference: $(grep -oiE '(src|href)="[^"]{0,60}' "$html" | grep -v '="data:' | head -1)"; return 1
  fi
  local srcs
  srcs=$(grep -o 'src="[^"]*"' "$html" | wc -l)
  [ "$srcs" -eq "$imgs" ] || { rm -rf "$tmp"; fail "$srcs src attributes for $imgs images"; return 1; }
  while IFS= read -r uri; do
    n=$((n + 1))
    mime=${uri%%;base64,*}
    mime=${mime#data:}
    if ! printf '%s' "${uri#*;base64,}" | base64 -d >"$tmp/img" 2>/dev/null; then
      rm -rf "$tmp"; fail "image $n ($mime): base64 does not decode"; return 1
    fi
    case "$mime" in
      image/png)
        [ "$(head -c 8 "$tmp/img" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] ||
          { rm -rf "$tmp"; fail "image $n: no PNG signature"; return 1; }
        [ "$(head -c 16 "$tmp/img" | tail -c 4)" = "IHDR" ] ||
          { rm -rf "$tmp"; fail "image $n: PNG without IHDR first"; return 1; }
        [ "$(tail -c 12 "$tmp/img" | od -An -tx1 | tr -d ' \n')" = "0000000049454e44ae426082" ] ||
          { rm -rf "$tmp"; fail "image $n: PNG does not end with IEND"; return 1; }
        ;;
      image/svg+xml)
        xmllint --noout "$tmp/img" 2>/dev/null ||
          { rm -rf "$tmp"; fail "image $n: SVG is not well-formed XML"; return 1; }
        [ "$(xmllint --xpath 'local-name(/*)' "$tmp/img" 2>/dev/null)" = "svg" ] ||
          { rm -rf "$tmp"; fail "image $n: root element is not <svg>"; return 1; }
        ;;
      *) rm -rf "$tmp"; fail "image $n: unexpected type '$mime'"; return 1 ;;
    esac
  done < <(grep -o 'src="data:[^"]*"' "$html" | sed 's/^src="//; s/"$//')
  rm -rf "$tmp"
  [ "$n" -eq "$expected" ] || { fail "$n data URIs, $expected expected"; return 1; }
  echo "static: $n images decode"
}

browser_check() {
  local html=$1 profile dom log status console
  profile=$(mktemp -d)
  dom=$(mktemp); log=$(mktemp)
  timeout 120 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync \
    --user-data-dir="$profile" --enable-logging=stderr --v=0 --virtual-time-budget=10000 \
    --dump-dom "file://$(realpath "$html")" >"$dom" 2>"$log"
  local code=$?
  status=$(grep -o '<p id="image-check"[^>]*>[^<]*' "$dom" | sed 's/.*>//')
  console=$(grep ':CONSOLE' "$log" | head -3)
  rm -rf "$profile" "$dom" "$log"
  [ "$code" -eq 0 ] || { fail "chromium exit code $code"; return 1; }
  [ -z "$console" ] || { fail "console messages: $console"; return 1; }
  case "$status" in
    "images ok: "*) echo "browser: $status" ;;
    *) fail "page status: '${status:-none}'"; return 1 ;;
  esac
}

for tool in chromium xmllint jq base64 od; do
  command -v "$tool" >/dev/null || { echo "FAIL: $tool is not installed (bash scripts/setup.sh installs it)"; exit 1; }
done

mode=$1; shift
case "$mode" in
  run)
    pandora=$1 scene=$2 out=$3 rigs=$4; shift 4
    rm -rf "$out"
    "$pandora" report "$scene" --out "$out" --quiet "$@" || { fail "pandora report exit code $?"; exit 1; }
    html="$out/report.html"
    [ -f "$html" ] || { fail "no $html"; exit 1; }
    leftover=$(find "$out" -name '*.tmp-*' | head -1)
    [ -z "$leftover" ] || { fail "temporary file left: $leftover"; exit 1; }
    static_check "$html" || exit 1
    browser_check "$html" || exit 1
    IFS=, read -ra names <<<"$rigs"
    grep -q "grid-template-columns: repeat(${#names[@]}, " "$html" || { fail "no ${#names[@]}-column layout"; exit 1; }
    for r in "${names[@]}"; do
      [ "$(grep -c "<h3 class=\"rig\">$r &mdash;" "$html")" -ge 3 ] || { fail "rig '$r' has no column header"; exit 1; }
      grep -q "<th>$r</th>" "$html" || { fail "rig '$r' missing from the numbers table"; exit 1; }
    done
    echo "ok: report with ${#names[@]} rig column(s), $(stat -c %s "$html") bytes"
    ;;
  numbers)
    pandora=$1 scene=$2 html=$3 rigs=$4 work=$5
    rm -rf "$work"; mkdir -p "$work"
    IFS=, read -ra names <<<"$rigs"
    keys='{coverage, uncertainty, region_voxels, solid_voxels, active_voxels, per_camera, voxel_size_m, rig, cameras}'
    for r in "${names[@]}"; do
      "$pandora" analyze "$scene" --rig "$r" --out "$work/$r" --quiet || { fail "analyze $r"; exit 1; }
      jq -S "$keys" "$work/$r/summary.json" >"$work/$r/analyze.json"
      grep -o "<script type=\"application/json\" class=\"summary\" data-rig=\"$r\">.*</script>" "$html" |
        sed 's/^<script[^>]*>//; s#</script>$##' | jq -S "$keys" >"$work/$r/report.json" ||
        { fail "no embedded summary for rig $r"; exit 1; }
      diff -u "$work/$r/analyze.json" "$work/$r/report.json" || { fail "rig $r: the report's numbers differ from analyze"; exit 1; }
      ge2=$(jq -r '.coverage.ge2 * 1000 | round / 10' "$work/$r/summary.json")
      p50=$(jq -r '.uncertainty.sigma_max_mm.p50' "$work/$r/summary.json")
      ge2_text=$(printf '%.1f%%' "$ge2"); p50_text=$(printf '%.3f' "$p50")
      grep "Coverage &ge; 2 cameras" "$html" | grep -q "$ge2_text" || { fail "rig $r: table lacks coverage >= 2 of $ge2_text"; exit 1; }
      grep "p50 (mm)" "$html" | head -1 | grep -q "$p50_text" || { fail "rig $r: table lacks sigma_max p50 $p50_text"; exit 1; }
      echo "rig $r: report numbers equal analyze's (coverage >= 2 $ge2_text, sigma_max p50 $p50_text mm)"
    done
    echo "ok: numbers match for ${#names[@]} rig(s)"
    ;;
  negative)
    html=$1 work=$2
    rm -rf "$work"; mkdir -p "$work"
    static_check "$html" >/dev/null && browser_check "$html" >/dev/null || { fail "the original does not pass"; exit 1; }
    # 1. The first PNG's payload replaced by base64 of bytes that are not a PNG.
    bad=$(printf 'this is not a PNG image' | base64 -w0)
    sed "0,/data:image\/png;base64,[^\"]*/s//data:image\/png;base64,$bad/" "$html" >"$work/png.html"
    # 2. The first SVG cut to its first 200 bytes (still valid base64).
    svg=$(grep -o 'data:image/svg+xml;base64,[^"]*' "$html" | head -1 | sed 's/.*;base64,//' | base64 -d | head -c 200 | base64 -w0)
    sed "0,/data:image\/svg+xml;base64,[^\"]*/s//data:image\/svg+xml;base64,$svg/" "$html" >"$work/svg.html"
    # 3. One more image, from the network, counted in data-expected-images.
    n=$(grep -o 'data-expected-images="[0-9]*"' "$html" | grep -o '[0-9]*')
    sed "s/data-expected-images=\"$n\"/data-expected-images=\"$((n + 1))\"/; s#<h1>#<img src=\"http://example.invalid/x.png\" alt=\"external\"><h1>#" \
      "$html" >"$work/external.html"
    status=0
    for f in png svg external; do
      cmp -s "$html" "$work/$f.html" && { fail "$f: the copy was not modified"; status=1; continue; }
      if out=$(static_check "$work/$f.html"); then fail "static check accepted $f.html"; status=1
      else echo "static rejects $f.html: $out"; fi
      if out=$(browser_check "$work/$f.html"); then fail "browser check accepted $f.html"; status=1
      else echo "browser rejects $f.html: $out"; fi
    done
    [ "$status" -eq 0 ] && echo "ok: both checkers reject every corrupted copy"
    exit "$status"
    ;;
  *) echo "usage: check_report.sh run|negative ..."; exit 2 ;;
esac
