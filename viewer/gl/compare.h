#pragma once
/// \file compare.h
/// How far a GPU frame (viewer/gl/renderer.h) is from the exact CPU renderer's (render/render.h)
/// for the same rig, view and size: the per-pixel camera sets and the colours, away from the
/// edges where a shadow map or a rasterised silhouette cannot agree with a ray to the pixel centre.
/// Used by the viewer's test and by pandora_gl_bench (docs/viewer.md).

#include <cstddef>
#include <string>
#include <vector>

#include "render/render.h"
#include "viewer/gl/renderer.h"

namespace pandora {

struct GlComparison {
  std::size_t pixels = 0;           ///< width * height.
  std::size_t excluded = 0;         ///< In the band around an edge of the CPU image (see Compare).
  std::size_t compared = 0;         ///< pixels - excluded.
  std::size_t mask_differ = 0;      ///< Compared pixels whose camera sets differ.
  std::size_t mask_differ_all = 0;  ///< The same over every pixel, edges included.
  /// Colour over the compared pixels whose camera sets agree: largest and mean absolute difference
  /// of a channel (linear RGB).
  double rgb_max = 0, rgb_mean = 0;
  int rgb_max_x = -1, rgb_max_y = -1;  ///< Where rgb_max is.
  /// Of those pixels, how many differ by more than 1e-3 in a channel (a pixel centre on an edge
  /// between two triangles of one object, resolved to the other triangle: another normal, so
  /// another ambient shade).
  std::size_t rgb_over = 0;
  double rgb_over_share() const { return compared ? double(rgb_over) / compared : 0.0; }
  /// Mean absolute channel difference over every pixel (edges and differing sets included).
  double rgb_mean_all = 0;
  /// Per camera (index < 64), over the compared pixels: the GPU leaves out a camera the CPU has
  /// (a false shadow) / adds one the CPU does not have (light leaking).
  std::vector<std::size_t> gpu_missing, gpu_extra;

  double mask_share() const { return compared ? double(mask_differ) / compared : 0.0; }
  double mask_share_all() const { return pixels ? double(mask_differ_all) / pixels : 0.0; }
  double excluded_share() const { return pixels ? double(excluded) / pixels : 0.0; }
};

/// Compares `gpu` with `cpu` (same size; `cpu` rendered with layers: cameras, object, depth).
/// Edges: between horizontally or vertically adjacent pixels of the CPU image with another camera
/// set (footprint and shadow edges), another object, or depths more than 5 % apart (silhouettes);
/// both pixels of such a pair are edge pixels, and so is a pixel where the two renderers disagree
/// on whether it shows a surface. Excluded: the pixels within `band` - 1 pixels (Chebyshev) of an
/// edge pixel; band 1 excludes the edge pixels themselves, the one-pixel band either side.
/// Throws std::invalid_argument when the sizes differ or `cpu` has no camera sets.
GlComparison Compare(const Image& cpu, const GlImage& gpu, int band = 1);

/// Writes `cpu` and `gpu` side by side (CPU left) above a map of where their camera sets differ
/// (red: differs, compared; dark grey: differs, excluded band; black otherwise), as an 8-bit sRGB
/// PNG at `path`.
void WriteComparisonPng(const Image& cpu, const GlImage& gpu, const std::string& path,
                        int band = 1);

}  // namespace pandora
