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
  std::size_t pixels = 0;  ///< width * height (CompareSampled: the pixels sampled).
  /// CompareSampled: the image's pixels the sample was drawn from (0: Compare, every pixel).
  std::size_t sampled_from = 0;
  std::size_t excluded = 0;  ///< In the band around an edge of the CPU image (see Compare).
  std::size_t compared = 0;  ///< pixels - excluded.
  /// Of pixels / of compared: those showing a surface in the CPU image (the background's sets
  /// are empty on both sides and agree trivially).
  std::size_t surface = 0, compared_surface = 0;
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
  /// Per (pixel, camera) pair: rigs of many cameras cover a floor with footprint and shadow
  /// edges (a 200-camera stage leaves half its pixels within one pixel of some camera's edge), so
  /// each camera is also compared on its own: pair (p, c) is excluded when camera c's CPU bit
  /// changes within the band around p (c's own footprint or shadow edge) or p is excluded for a
  /// silhouette (every camera). Over the compared pairs: those the CPU lights, and those where
  /// the GPU leaves out a camera the CPU has (a false shadow) or adds one (light leaking).
  std::size_t lit_pairs = 0, pairs_missing = 0, pairs_extra = 0;
  std::size_t lit_pairs_all = 0;  ///< Pairs the CPU lights, excluded or not.
  /// The same two per rig camera (64 per word of the GPU's camera sets).
  std::vector<std::size_t> gpu_missing, gpu_extra;
  double pair_share() const {
    return lit_pairs ? double(pairs_missing + pairs_extra) / double(lit_pairs) : 0.0;
  }
  double compared_pair_share() const {
    return lit_pairs_all ? double(lit_pairs) / double(lit_pairs_all) : 0.0;
  }

  double mask_share() const { return compared ? double(mask_differ) / compared : 0.0; }
  double mask_share_all() const { return pixels ? double(mask_differ_all) / pixels : 0.0; }
  double excluded_share() const { return pixels ? double(excluded) / pixels : 0.0; }
  /// Share of the surface pixels that are compared.
  double compared_surface_share() const {
    return surface ? double(compared_surface) / surface : 0.0;
  }
};

/// Compares `gpu` with `cpu` (same size; `cpu` rendered with layers: cameras, object, depth).
/// Edges: between horizontally or vertically adjacent pixels of the CPU image with another camera
/// set (footprint and shadow edges), another object, or depths more than 5 % apart (silhouettes);
/// both pixels of such a pair are edge pixels, and so is a pixel where the two renderers disagree
/// on whether it shows a surface. Excluded: the pixels within `band` - 1 pixels (Chebyshev) of an
/// edge pixel; band 1 excludes the edge pixels themselves, the one-pixel band either side. Pairs
/// (pixel, camera) likewise, with only camera c's bit deciding c's footprint and shadow edges.
/// Throws std::invalid_argument when the sizes differ or `cpu` has no camera sets (rigs of over
/// Image::kMaxMaskCameras cameras: use CompareSampled).
GlComparison Compare(const Image& cpu, const GlImage& gpu, int band = 1);

/// Compare for rigs of any size, on `samples` pixels of the image (all of them when samples >=
/// width * height; else a fixed low-discrepancy sequence: sample i is pixel floor(frac(0.5 + i
/// phi) width height), phi the golden ratio's fractional part): the CPU's camera set of a pixel
/// is `picker`'s exact one (PixelPicker over the same scene, rig and view as `cpu`), picked for
/// the sampled pixel and the neighbours its edge test needs; objects, depths and colours are
/// `cpu`'s layers, as in Compare, so on a rig of at most 64 cameras both give the same counts
/// over the same pixels (but where a pick's lone ray resolves a shared triangle edge to the other
/// triangle). Picks run in parallel (TBB). Throws std::invalid_argument when the sizes differ.
GlComparison CompareSampled(const PixelPicker& picker, const Image& cpu, const GlImage& gpu,
                            std::size_t samples, int band = 1);

/// Writes `cpu` and `gpu` side by side (CPU left) above a map of where their camera sets differ
/// (red: differs, compared; dark grey: differs, excluded band; black otherwise), as an 8-bit sRGB
/// PNG at `path`. Rigs of at most 64 cameras (std::invalid_argument otherwise, or for other sizes).
void WriteComparisonPng(const Image& cpu, const GlImage& gpu, const std::string& path,
                        int band = 1);

}  // namespace pandora
