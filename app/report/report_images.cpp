#include "app/report/report_images.h"

#include <algorithm>
#include <array>
#include <cmath>
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

std::string EncodePng(const Raster& raster) {
  return EncodePngSrgb8(raster.width, raster.height, raster.rgb);  // checks the size
}

std::string DataUri(const std::string& mime, const std::string& bytes) {
  return "data:" + mime + ";base64," + Base64(bytes);
}

}  // namespace pandora::report
