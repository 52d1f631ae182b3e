#pragma once
/// \file report_images.h
/// 8-bit raster images for the HTML report: field slices coloured with viridis, PNG encoding and
/// base64 data URIs.

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/util/color.h"
#include "analysis/util/text.h"  // Base64
#include "render/render.h"
#include "volume/slice.h"

namespace pandora::report {

/// Row-major 8-bit sRGB, 3 bytes per pixel, row 0 at the top.
struct Raster {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  void Set(int x, int y, Rgb8 c) {
    const std::size_t i = 3 * (static_cast<std::size_t>(y) * width + x);
    rgb[i] = c.r;
    rgb[i + 1] = c.g;
    rgb[i + 2] = c.b;
  }
};

/// Colours of slice pixels that have no value.
inline constexpr Rgb8 kOutsideRegionColor{208, 208, 208};  ///< Not a free region voxel (solid).
inline constexpr Rgb8 kNoValueColor{64, 64, 64};           ///< Unseen, or not triangulable.

/// The slice as an image, each voxel a `scale` x `scale` block: viridis of (value - min) / (max -
/// min) where the field has a value (clamped: values above max get the top colour),
/// kNoValueColor inside the region without a value, kOutsideRegionColor outside.
Raster SliceRaster(const FieldSlice& slice, double min, double max, int scale);

/// PNG bytes of `raster` (8-bit sRGB, encoded in memory as it is; a rendered image's are
/// pandora::EncodePng's, render/render.h).
std::string EncodePng(const Raster& raster);

/// "data:MIME;base64,..." of `bytes`.
std::string DataUri(const std::string& mime, const std::string& bytes);

}  // namespace pandora::report
