#!/usr/bin/env bash
# Installs Pandora's build and test dependencies from Debian 12 packages.
# Non-interactive and idempotent: does nothing when every package is already installed.
# Runs as root, or through sudo when not root.
set -euo pipefail

PACKAGES=(
  cmake ninja-build ccache g++ pkg-config git
  libopenvdb-dev libopenvdb-tools libembree-dev libcgal-dev libceres-dev libglm-dev
  libopenexr-dev openexr libpng-dev libassimp-dev libtbb-dev libeigen3-dev nlohmann-json3-dev libcli11-dev
  libspdlog-dev libgtest-dev libgmock-dev libbenchmark-dev libboost-iostreams-dev
  chromium libxml2-utils jq python3-openvdb
  # The style checks (scripts/check_style.py, ctest style.*): formatting and function sizes.
  clang-format universal-ctags
  # pandora analyze --mpi and its tests (docs/scale.md).
  libopenmpi-dev openmpi-bin
  # python/ (import pandora) and its tests.
  pybind11-dev python3-dev python3-numpy python3-pytest
  # viewer/ (the only code that links GL): window, GL loader, UI; headless tests through EGL
  # (libegl-mesa0: Mesa's software EGL device) and under Xvfb, with Mesa's llvmpipe (GL 4.5).
  libglfw3-dev libepoxy-dev libimgui-dev xvfb xauth libgl1-mesa-dri mesa-utils libegl1 libegl-mesa0
  # OpenCV (validation/: fiducial prints with aruco, detection, calibration; cv::FileStorage reads
  # the rig exports back in ctest rigio.*OpenCV*). contrib holds aruco in Debian 12's OpenCV 4.6.
  libopencv-dev libopencv-contrib-dev
  # pandora import-plan: floor plans from DXF.
  libdxflib-dev
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: not root and sudo is missing; run as root" >&2; exit 1; }
  SUDO="sudo"
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
${SUDO:+$SUDO -E} apt-get install -y -qq --no-install-recommends "${missing[@]}"
