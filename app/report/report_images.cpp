#include "app/report/report_images.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "analysis/util/text.h"

namespace pandora::report {

Raster SliceRaster(const FieldSlice& slice, double min, double max, int scale) {
  scale = std::max(1, scale);
  Raster r;
  r.width = slice.width * scale;
  r.height = slice.height * scale;
  r.rgb.assign(3 * static_cast<std::size_t>(r.width) * r.height, 0);
  const double span = max > min ? max - min : 1.0;
  for (int row = 0; row < slice.height; ++row)
    for (int col = 0; col < slice.width; ++col) {
      const std::size_t o = static_cast<std::size_t>(row) * slice.width + col;
      Rgb8 c = kOutsideRegionColor;
      if (slice.inside[o])
        c = slice.has_value[o] ? Viridis((slice.values[o] - min) / span) : kNoValueColor;
      for (int dy = 0; dy < scale; ++dy)
        for (int dx = 0; dx < scale; ++dx) r.Set(col * scale + dx, row * scale + dy, c);
    }
  return r;
}

std::string PngBytes(const Image& image) {
  // A private temporary name (process id and a counter), removed whatever happens.
  static std::atomic<int> counter{0};
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      ("pandora-report-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".png");
  struct Remove {
    std::filesystem::path p;
    ~Remove() {
      std::error_code ec;
      std::filesystem::remove(p, ec);
    }
  } remove{path};
  WritePng(image, path.string());
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (!in) throw std::runtime_error("cannot read back " + path.string());
  return bytes.str();
}

std::string EncodePng(const Raster& raster) {
  if (raster.width <= 0 || raster.height <= 0 ||
      raster.rgb.size() != 3 * static_cast<std::size_t>(raster.width) * raster.height)
    throw std::invalid_argument("EncodePng: empty raster or wrong buffer size");
  // Inverse sRGB transfer curve per 8-bit value (analysis/util/color.h).
  static const std::array<float, 256> linear = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = static_cast<float>(LinearFromSrgb(i / 255.0));
    return t;
  }();
  Image image;
  image.width = raster.width;
  image.height = raster.height;
  image.rgb.resize(raster.rgb.size());
  for (std::size_t i = 0; i < raster.rgb.size(); ++i) image.rgb[i] = linear[raster.rgb[i]];
  return PngBytes(image);
}

std::string DataUri(const std::string& mime, const std::string& bytes) {
  return "data:" + mime + ";base64," + Base64(bytes);
}

}  // namespace pandora::report
