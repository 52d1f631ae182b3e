#!/usr/bin/env bash
# The GPU renderer measured on a headless GPU machine (issue 30; docs/viewer.md, "Frame time").
#
#   bash bench/gpu_device.sh pack [BUILD] [PACK]   here: BUILD's pandora_gl_bench, gl_renderer_test, pandora-view
#                                                  with every shared library they load (but the GL and
#                                                  EGL of the machine they run on) into PACK
#                                                  (default build/gpu_pack.tar.xz)
#   bash bench/gpu_device.sh run [PACK] [OUT]      there, in a copy of this repository (its examples):
#                                                  the GL tests and the bench through headless EGL,
#                                                  logs and tables into OUT (default $OUT or gpu_out)
#
# `run` needs the machine's EGL (libEGL.so.1 with its vendor library, e.g. NVIDIA's) and no
# display. It writes gl_renderer_test.log, the bench tables per scene (bench_*.md: the trauma room,
# the capture stage with its 24 cameras, 64 and 200), the whole window's frame rates headless
# (bench_viewer_*.txt) and device.txt.
# Here (no GPU) the same `run` goes through Mesa's software EGL device: a rehearsal (QUICK=1 for
# small frames).
set -euo pipefail
cd "$(dirname "$0")/.."

pack() {
  local build=${1:-build} pack=${2:-build/gpu_pack.tar.xz}
  local stage
  stage=$(mktemp -d)
  trap 'rm -rf "$stage"' RETURN
  mkdir -p "$stage/bin" "$stage/lib"
  for exe in pandora_gl_bench gl_renderer_test pandora-view pandora_gl_render; do
    [ -x "$build/$exe" ] || { echo "gpu_device.sh: $build/$exe is not built" >&2; return 2; }
    cp "$build/$exe" "$stage/bin/"
    # Every library the loader resolves, but those that must be the target's own: the C library
    # and loader, and GL / EGL / GLX with their dispatch (the target's driver provides them).
    ldd "$build/$exe" | awk '$3 ~ /^\// { print $3 }' | while read -r lib; do
      case "$(basename "$lib")" in
        libc.so*|libm.so*|libdl.so*|libpthread.so*|librt.so*|ld-linux*) ;;
        libGL*|libEGL*|libGLX*|libGLdispatch*|libOpenGL*|libgbm*|libdrm*) ;;
        *) cp -L -n "$lib" "$stage/lib/" ;;
      esac
    done
  done
  mkdir -p "$(dirname "$pack")"
  tar -C "$stage" -cJf "$pack" bin lib
  echo "gpu_device.sh: $pack ($(du -h "$pack" | cut -f1)): $(ls "$stage/lib" | wc -l) libraries"
}

run() {
  local pack=${1:-build/gpu_pack.tar.xz} out=${2:-${OUT:-gpu_out}}
  [ -f "$pack" ] || { echo "gpu_device.sh: no pack $pack (run 'pack' first)" >&2; return 2; }
  mkdir -p "$out"
  local dir
  dir=$(mktemp -d)
  tar -C "$dir" -xJf "$pack"
  export LD_LIBRARY_PATH="$dir/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  export PANDORA_GL=egl
  unset DISPLAY WAYLAND_DISPLAY
  { nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null || true
    nproc; } > "$out/device.txt"
  # The GL tests against the exact CPU renderer, through EGL (their PNGs beside the log).
  PANDORA_TEST_OUT="$out/gl_tests" "$dir/bin/gl_renderer_test" > "$out/gl_renderer_test.log" 2>&1 \
    && echo "gl_renderer_test: passed" || echo "gl_renderer_test: FAILED (see $out/gl_renderer_test.log)"
  # The frame-time tables of issue 30: 1920 x 1080, maps 2048 (and the others).
  local bench=(--size 1920x1080 --maps 1024,2048,4096 --frames 10 --cpu-frames 3)
  # QUICK=1: a rehearsal on a machine without a GPU (small frames, one map size).
  [ "${QUICK:-0}" = 1 ] && bench=(--size 320x180 --maps 1024 --frames 1 --cpu-frames 1)
  "$dir/bin/pandora_gl_bench" examples/trauma_room/scene.json --rig octagon "${bench[@]}" \
    > "$out/bench_trauma_room.md" 2>&1 || echo "bench trauma room failed" >&2
  "$dir/bin/pandora_gl_bench" examples/capture_stage/scene.json "${bench[@]}" \
    > "$out/bench_capture_stage.md" 2>&1 || echo "bench capture stage failed" >&2
  # Rigs of 64 and 200 cameras: the stage's 24 turned about its axis (--cameras); above 64 the
  # camera sets are compared on sampled pixels.
  for n in 64 200; do
    "$dir/bin/pandora_gl_bench" examples/capture_stage/scene.json --cameras "$n" "${bench[@]}" \
      > "$out/bench_capture_stage_$n.md" 2>&1 || echo "bench capture stage $n failed" >&2
  done
  # The whole window headless (a hidden window is an offscreen framebuffer on EGL): frames
  # navigating and with every camera moving, panels and overlays included (`pandora bench --viewer`).
  local view=(--bench 20 --size 1920x1080 --shadow-map 2048)
  [ "${QUICK:-0}" = 1 ] && view=(--bench 2 --size 480x270 --shadow-map 1024)
  for scene in trauma_room capture_stage; do
    "$dir/bin/pandora-view" "examples/$scene/scene.json" --no-autosave "${view[@]}" \
      > "$out/bench_viewer_$scene.txt" 2>&1 || echo "viewer bench $scene failed" >&2
  done
  # A camera's native view (the capture stage's c01, 2048 x 1088) on the GPU against the exact
  # renderer (`pandora render --gpu`).
  "$dir/bin/pandora_gl_render" examples/capture_stage/scene.json --camera-index 0 \
    --size "$([ "${QUICK:-0}" = 1 ] && echo 512x272 || echo 2048x1088)" --out "$out/c01_gpu.png" \
    > "$out/render_camera_view.txt" 2>&1 || echo "camera view failed" >&2
  head -n 1 "$out/bench_trauma_room.md" >> "$out/device.txt"
  cat "$out/device.txt"
  rm -rf "$dir"
}

case "${1:-}" in
  pack) shift; pack "$@" ;;
  run) shift; run "$@" ;;
  *) sed -n '2,14p' "$0" >&2; exit 2 ;;
esac
