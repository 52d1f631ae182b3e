// Compares two PNG screenshots: the share of pixels whose 8-bit sRGB value differs by more than
// TOLERANCE in some channel. Exit 0 when that share is at most MAX_PERCENT, 1 when more (or the
// sizes differ), 2 when a file cannot be read. Used by the viewer's reference-image tests.
// Usage: pandora_png_diff A.png B.png MAX_PERCENT [TOLERANCE=8]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "render/render.h"

namespace {

int Srgb8(float linear) { return int(std::lround(255.0 * pandora::SrgbFromLinear(linear))); }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: pandora_png_diff A.png B.png MAX_PERCENT [TOLERANCE]\n");
    return 2;
  }
  const double max_percent = std::atof(argv[3]);
  const int tolerance = argc > 4 ? std::atoi(argv[4]) : 8;
  pandora::Image a, b;
  try {
    a = pandora::ReadPng(argv[1]);
    b = pandora::ReadPng(argv[2]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pandora_png_diff: %s\n", e.what());
    return 2;
  }
  if (a.width != b.width || a.height != b.height) {
    std::printf("%s: %dx%d, %s: %dx%d: the sizes differ\n", argv[1], a.width, a.height, argv[2],
                b.width, b.height);
    return 1;
  }
  const std::size_t n = std::size_t(a.width) * a.height;
  std::size_t differing = 0;
  int largest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    int d = 0;
    for (int k = 0; k < 3; ++k)
      d = std::max(d, std::abs(Srgb8(a.rgb[3 * i + k]) - Srgb8(b.rgb[3 * i + k])));
    largest = std::max(largest, d);
    if (d > tolerance) ++differing;
  }
  const double percent = n ? 100.0 * differing / n : 0.0;
  std::printf(
      "%s vs %s: %.3f%% of %zu pixels differ by more than %d/255 (largest %d/255; allowed "
      "%.3f%%)\n",
      argv[1], argv[2], percent, n, tolerance, largest, max_percent);
  return percent <= max_percent ? 0 : 1;
}
