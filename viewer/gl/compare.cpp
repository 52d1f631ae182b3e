// Agreement of a GPU frame with the CPU renderer's (viewer/gl/compare.h).
#include "viewer/gl/compare.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace pandora {
namespace {

// Per pixel: excluded from the comparison (near an edge of the CPU image).
std::vector<uint8_t> ExcludedBand(const Image& cpu, const GlImage& gpu, int band) {
  const int W = cpu.width, H = cpu.height;
  std::vector<uint8_t> edge(std::size_t(W) * H, 0);
  auto index = [W](int x, int y) { return std::size_t(y) * W + x; };
  // An edge between horizontally or vertically adjacent pixels marks both.
  auto differ = [&](std::size_t a, std::size_t b) {
    if (cpu.cameras[a] != cpu.cameras[b] || cpu.object[a] != cpu.object[b]) return true;
    const float da = cpu.depth[a], db = cpu.depth[b];
    if (std::isfinite(da) != std::isfinite(db)) return true;
    return std::isfinite(da) && std::abs(da - db) > 0.05f * std::min(da, db);
  };
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t p = index(x, y);
      if (x + 1 < W && differ(p, index(x + 1, y))) edge[p] = edge[index(x + 1, y)] = 1;
      if (y + 1 < H && differ(p, index(x, y + 1))) edge[p] = edge[index(x, y + 1)] = 1;
      // Where the renderers disagree on hitting a surface, the pixel lies on a silhouette.
      if (bool(gpu.hit[p]) != std::isfinite(cpu.depth[p])) edge[p] = 1;
    }
  // Dilate by band - 1: the pixels on either side of an edge are the one-pixel band.
  std::vector<uint8_t> out = edge;
  const int r = std::max(0, band - 1);
  if (r > 0)
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        if (!edge[index(x, y)]) continue;
        for (int j = std::max(0, y - r); j <= std::min(H - 1, y + r); ++j)
          for (int i = std::max(0, x - r); i <= std::min(W - 1, x + r); ++i) out[index(i, j)] = 1;
      }
  return out;
}

}  // namespace

GlComparison Compare(const Image& cpu, const GlImage& gpu, int band) {
  if (cpu.width != gpu.width || cpu.height != gpu.height)
    throw std::invalid_argument("Compare: the CPU and GPU images differ in size");
  const std::size_t n = std::size_t(cpu.width) * cpu.height;
  if (cpu.cameras.size() != n || gpu.cameras.size() != n || cpu.object.size() != n ||
      cpu.depth.size() != n)
    throw std::invalid_argument("Compare: both images need their per-pixel camera sets");
  const std::vector<uint8_t> excluded = ExcludedBand(cpu, gpu, band);
  GlComparison c;
  c.pixels = n;
  c.gpu_missing.assign(64, 0);
  c.gpu_extra.assign(64, 0);
  double sum = 0, sum_all = 0;
  std::size_t agreeing = 0;
  for (std::size_t p = 0; p < n; ++p) {
    const bool same = cpu.cameras[p] == gpu.cameras[p];
    double diff = 0;
    for (int k = 0; k < 3; ++k)
      diff = std::max(diff, double(std::abs(cpu.rgb[3 * p + k] - gpu.rgb[3 * p + k])));
    for (int k = 0; k < 3; ++k) sum_all += std::abs(cpu.rgb[3 * p + k] - gpu.rgb[3 * p + k]);
    c.mask_differ_all += !same;
    if (excluded[p]) {
      ++c.excluded;
      continue;
    }
    ++c.compared;
    if (!same) {
      ++c.mask_differ;
      const uint64_t missing = cpu.cameras[p] & ~gpu.cameras[p];
      const uint64_t extra = gpu.cameras[p] & ~cpu.cameras[p];
      for (int b = 0; b < 64; ++b) {
        c.gpu_missing[b] += (missing >> b) & 1;
        c.gpu_extra[b] += (extra >> b) & 1;
      }
      continue;
    }
    ++agreeing;
    c.rgb_over += diff > 1e-3;
    if (diff > c.rgb_max) {
      c.rgb_max = diff;
      c.rgb_max_x = int(p % cpu.width);
      c.rgb_max_y = int(p / cpu.width);
    }
    for (int k = 0; k < 3; ++k) sum += std::abs(cpu.rgb[3 * p + k] - gpu.rgb[3 * p + k]);
  }
  c.rgb_mean = agreeing ? sum / (3.0 * agreeing) : 0.0;
  c.rgb_mean_all = n ? sum_all / (3.0 * n) : 0.0;
  return c;
}

void WriteComparisonPng(const Image& cpu, const GlImage& gpu, const std::string& path, int band) {
  const int W = cpu.width, H = cpu.height;
  const std::vector<uint8_t> excluded = ExcludedBand(cpu, gpu, band);
  Image out;
  out.width = 2 * W;
  out.height = 2 * H;
  out.rgb.assign(3 * std::size_t(out.width) * out.height, 0.0f);
  auto put = [&](int x, int y, float r, float g, float b) {
    const std::size_t q = 3 * (std::size_t(y) * out.width + x);
    out.rgb[q] = r;
    out.rgb[q + 1] = g;
    out.rgb[q + 2] = b;
  };
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t p = std::size_t(y) * W + x;
      put(x, y, cpu.rgb[3 * p], cpu.rgb[3 * p + 1], cpu.rgb[3 * p + 2]);
      put(W + x, y, gpu.rgb[3 * p], gpu.rgb[3 * p + 1], gpu.rgb[3 * p + 2]);
      const bool differs = cpu.cameras[p] != gpu.cameras[p];
      const float v = !differs ? 0.0f : excluded[p] ? 0.05f : 1.0f;
      put(W / 2 + x, H + y, v, excluded[p] && differs ? v : 0.0f,
          excluded[p] && differs ? v : 0.0f);
    }
  WritePng(out, path);
}

}  // namespace pandora
