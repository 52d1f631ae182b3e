// Agreement of a GPU frame with the CPU renderer's (viewer/gl/compare.h).
#include "viewer/gl/compare.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <vector>

namespace pandora {
namespace {

constexpr int kDx[4] = {1, -1, 0, 0}, kDy[4] = {0, 0, 1, -1};

// Whether CPU pixels a and b lie on either side of a silhouette: another object, or depths more
// than 5 % apart (or a surface beside the background).
bool Silhouette(const Image& cpu, std::size_t a, std::size_t b) {
  if (cpu.object[a] != cpu.object[b]) return true;
  const float da = cpu.depth[a], db = cpu.depth[b];
  if (std::isfinite(da) != std::isfinite(db)) return true;
  return std::isfinite(da) && std::abs(da - db) > 0.05f * std::min(da, db);
}

// The edge bits of pixel (x, y), `words` words into `out`: the cameras whose CPU bit changes
// between it and a 4-neighbour, every bit where it lies on a silhouette or the renderers disagree
// on a surface there. set(x, y) gives a pixel's CPU camera set (`words` words).
template <class SetOf>
void EdgeBits(const Image& cpu, const GlImage& gpu, int x, int y, std::size_t words, SetOf&& set,
              uint64_t* out) {
  const int W = cpu.width, H = cpu.height;
  const std::size_t q = std::size_t(y) * W + x;
  std::fill(out, out + words, uint64_t(0));
  bool all = bool(gpu.hit[q]) != std::isfinite(cpu.depth[q]);
  const uint64_t* s = set(x, y);
  for (int k = 0; k < 4 && !all; ++k) {
    const int xn = x + kDx[k], yn = y + kDy[k];
    if (xn < 0 || yn < 0 || xn >= W || yn >= H) continue;
    if (Silhouette(cpu, q, std::size_t(yn) * W + xn)) {
      all = true;
      break;
    }
    const uint64_t* n = set(xn, yn);
    for (std::size_t w = 0; w < words; ++w) out[w] |= s[w] ^ n[w];
  }
  if (all) std::fill(out, out + words, ~uint64_t(0));
}

// One pixel's contribution: colours, its camera sets, and the cameras excluded there.
struct PixelResult {
  bool excluded = false, same = false, surface = false;
  double diff = 0, sum = 0;  // largest and summed absolute channel difference
  std::vector<uint64_t> cpu, gpu, excluded_bits;
};

PixelResult Measure(const Image& cpu, const GlImage& gpu, std::size_t p, const uint64_t* cpu_set,
                    std::vector<uint64_t> excluded_bits) {
  PixelResult r;
  const std::size_t words = std::size_t(gpu.camera_words);
  r.surface = std::isfinite(cpu.depth[p]);
  for (int k = 0; k < 3; ++k) {
    const double d = std::abs(double(cpu.rgb[3 * p + k]) - double(gpu.rgb[3 * p + k]));
    r.diff = std::max(r.diff, d);
    r.sum += d;
  }
  r.cpu.assign(cpu_set, cpu_set + words);
  r.gpu.assign(gpu.cameras.begin() + std::ptrdiff_t(p * words),
               gpu.cameras.begin() + std::ptrdiff_t((p + 1) * words));
  r.same = r.cpu == r.gpu;
  r.excluded = false;
  for (uint64_t e : excluded_bits) r.excluded = r.excluded || e != 0;
  r.excluded_bits = std::move(excluded_bits);
  return r;
}

void Add(const PixelResult& r, std::size_t p, int width, GlComparison* c, double* sum,
         double* sum_all, std::size_t* agreeing) {
  *sum_all += r.sum;
  c->mask_differ_all += !r.same;
  c->surface += r.surface;
  for (std::size_t w = 0; w < r.cpu.size(); ++w) {
    const uint64_t keep = ~r.excluded_bits[w];
    const uint64_t missing = r.cpu[w] & ~r.gpu[w] & keep, extra = r.gpu[w] & ~r.cpu[w] & keep;
    c->lit_pairs += std::size_t(__builtin_popcountll(r.cpu[w] & keep));
    c->lit_pairs_all += std::size_t(__builtin_popcountll(r.cpu[w]));
    c->pairs_missing += std::size_t(__builtin_popcountll(missing));
    c->pairs_extra += std::size_t(__builtin_popcountll(extra));
    for (int b = 0; (missing | extra) && b < 64; ++b) {
      c->gpu_missing[64 * w + b] += (missing >> b) & 1;
      c->gpu_extra[64 * w + b] += (extra >> b) & 1;
    }
  }
  if (r.excluded) {
    ++c->excluded;
    return;
  }
  ++c->compared;
  c->compared_surface += r.surface;
  if (!r.same) {
    ++c->mask_differ;
    return;
  }
  ++*agreeing;
  c->rgb_over += r.diff > 1e-3;
  if (r.diff > c->rgb_max) {
    c->rgb_max = r.diff;
    c->rgb_max_x = int(p % width);
    c->rgb_max_y = int(p / width);
  }
  *sum += r.sum;
}

GlComparison Start(std::size_t pixels, std::size_t words) {
  GlComparison c;
  c.pixels = pixels;
  c.gpu_missing.assign(64 * words, 0);
  c.gpu_extra.assign(64 * words, 0);
  return c;
}

void Finish(double sum, double sum_all, std::size_t agreeing, GlComparison* c) {
  c->rgb_mean = agreeing ? sum / (3.0 * agreeing) : 0.0;
  c->rgb_mean_all = c->pixels ? sum_all / (3.0 * c->pixels) : 0.0;
}

// Per pixel of a rig of at most 64 cameras: the edge bits dilated by band - 1 (Chebyshev), the
// cameras excluded there (a pixel is excluded where any is).
std::vector<uint64_t> ExcludedBits(const Image& cpu, const GlImage& gpu, int band) {
  const int W = cpu.width, H = cpu.height;
  std::vector<uint64_t> edge(std::size_t(W) * H, 0);
  auto set = [&](int x, int y) { return &cpu.cameras[std::size_t(y) * W + x]; };
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) EdgeBits(cpu, gpu, x, y, 1, set, &edge[std::size_t(y) * W + x]);
  const int r = std::max(0, band - 1);
  if (r == 0) return edge;
  std::vector<uint64_t> out(edge.size(), 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      for (int j = std::max(0, y - r); j <= std::min(H - 1, y + r); ++j)
        for (int i = std::max(0, x - r); i <= std::min(W - 1, x + r); ++i)
          out[std::size_t(y) * W + x] |= edge[std::size_t(j) * W + i];
  return out;
}

void CheckSingleWord(const Image& cpu, const GlImage& gpu, const char* who) {
  if (cpu.width != gpu.width || cpu.height != gpu.height)
    throw std::invalid_argument(std::string(who) + ": the CPU and GPU images differ in size");
  const std::size_t n = std::size_t(cpu.width) * cpu.height;
  if (cpu.cameras.size() != n || gpu.camera_words != 1 || gpu.cameras.size() != n ||
      cpu.object.size() != n || cpu.depth.size() != n || gpu.hit.size() != n)
    throw std::invalid_argument(std::string(who) +
                                ": both images need their per-pixel camera sets (rigs of over 64 "
                                "cameras: CompareSampled)");
}

}  // namespace

GlComparison Compare(const Image& cpu, const GlImage& gpu, int band) {
  CheckSingleWord(cpu, gpu, "Compare");
  const std::size_t n = std::size_t(cpu.width) * cpu.height;
  const std::vector<uint64_t> excluded = ExcludedBits(cpu, gpu, band);
  GlComparison c = Start(n, 1);
  double sum = 0, sum_all = 0;
  std::size_t agreeing = 0;
  for (std::size_t p = 0; p < n; ++p)
    Add(Measure(cpu, gpu, p, &cpu.cameras[p], {excluded[p]}), p, cpu.width, &c, &sum, &sum_all,
        &agreeing);
  Finish(sum, sum_all, agreeing, &c);
  return c;
}

GlComparison CompareSampled(const PixelPicker& picker, const Image& cpu, const GlImage& gpu,
                            std::size_t samples, int band) {
  const int W = cpu.width, H = cpu.height;
  if (W != gpu.width || H != gpu.height)
    throw std::invalid_argument("CompareSampled: the CPU and GPU images differ in size");
  const std::size_t n = std::size_t(W) * H, words = std::size_t(gpu.camera_words);
  if (words == 0 || gpu.cameras.size() != n * words || cpu.object.size() != n ||
      cpu.depth.size() != n || gpu.hit.size() != n || cpu.rgb.size() != 3 * n)
    throw std::invalid_argument("CompareSampled: the images need their layers and camera sets");
  const double phi = 0.6180339887498949;  // the golden ratio's fractional part
  std::vector<std::size_t> pixels;
  if (samples >= n) {
    for (std::size_t p = 0; p < n; ++p) pixels.push_back(p);
  } else {
    for (std::size_t i = 0; i < samples; ++i) {
      const double u = 0.5 + double(i) * phi;
      pixels.push_back(std::min(n - 1, std::size_t((u - std::floor(u)) * double(n))));
    }
  }
  const int reach = std::max(1, band);  // edges within band - 1, and their neighbours
  std::vector<PixelResult> results(pixels.size());
  tbb::parallel_for(std::size_t(0), pixels.size(), [&](std::size_t i) {
    const int x0 = int(pixels[i] % W), y0 = int(pixels[i] / W), side = 2 * reach + 1;
    // The CPU's camera set (words) of window pixel (x, y), picked once.
    std::vector<std::optional<std::vector<uint64_t>>> picked(std::size_t(side) * side);
    auto set = [&](int x, int y) -> const uint64_t* {
      auto& s = picked[std::size_t(y - y0 + reach) * side + std::size_t(x - x0 + reach)];
      if (!s) {
        s.emplace(words, 0);
        if (const auto pick = picker.Pick(x, y))
          for (int c : pick->cameras)
            if (std::size_t(c / 64) < words) (*s)[std::size_t(c / 64)] |= uint64_t(1) << (c % 64);
      }
      return s->data();
    };
    std::vector<uint64_t> excluded(words, 0), edge(words);
    for (int y = std::max(0, y0 - (band - 1)); y <= std::min(H - 1, y0 + band - 1); ++y)
      for (int x = std::max(0, x0 - (band - 1)); x <= std::min(W - 1, x0 + band - 1); ++x) {
        EdgeBits(cpu, gpu, x, y, words, set, edge.data());
        for (std::size_t w = 0; w < words; ++w) excluded[w] |= edge[w];
      }
    results[i] = Measure(cpu, gpu, pixels[i], set(x0, y0), std::move(excluded));
  });
  GlComparison c = Start(pixels.size(), words);
  c.sampled_from = n;
  double sum = 0, sum_all = 0;
  std::size_t agreeing = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i)
    Add(results[i], pixels[i], W, &c, &sum, &sum_all, &agreeing);
  Finish(sum, sum_all, agreeing, &c);
  return c;
}

void WriteComparisonPng(const Image& cpu, const GlImage& gpu, const std::string& path, int band) {
  CheckSingleWord(cpu, gpu, "WriteComparisonPng");
  const int W = cpu.width, H = cpu.height;
  const std::vector<uint64_t> excluded = ExcludedBits(cpu, gpu, band);
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
      const bool differs = cpu.cameras[p] != gpu.cameras[p], band_pixel = excluded[p] != 0;
      const float v = !differs ? 0.0f : band_pixel ? 0.05f : 1.0f;
      put(W / 2 + x, H + y, v, band_pixel && differs ? v : 0.0f, band_pixel && differs ? v : 0.0f);
    }
  WritePng(out, path);
}

}  // namespace pandora
