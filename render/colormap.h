#pragma once
/// \file colormap.h
/// Internal to render/: the viridis colormap and a tiny bitmap font for legends.

#include <string>

#include "analysis/geometry.h"
#include "analysis/palette.h"

namespace pandora {

/// Viridis (van der Walt and Smith, matplotlib's default), sRGB-encoded components in [0, 1], for
/// t in [0, 1] (clamped): volume/colormap.h's ViridisUnit (nine stops of the published table,
/// piecewise linear; within 5 8-bit steps of the table), so renders, report images and PLY colours
/// agree. render_test checks the table's end points and middle.
Vec3 ViridisSrgb(double t);

/// The same colour in linear RGB (what the renderer composites in).
Vec3 ViridisLinear(double t);

/// sRGB transfer curve, per channel, on [0, 1] (its inverse, LinearFromSrgb, is in analysis/palette.h).
double SrgbFromLinear(double v);

/// Draws `text` with a 3x5 pixel font scaled by `scale`, top-left corner at (x, y), into a linear
/// RGB buffer of width x height (3 floats per pixel). Characters: digits, a-z, . - + / _ % = < > [ ] ( ) , :
/// and space; others are drawn as a box. Returns the width drawn in pixels.
int DrawText(float* rgb, int width, int height, int x, int y, const std::string& text,
             const Vec3& color, int scale);

/// Width in pixels DrawText would use.
int TextWidth(const std::string& text, int scale);

}  // namespace pandora
