#pragma once
/// \file colormap.h
/// Internal to render/: a tiny bitmap font for legends. The colours (viridis, the sRGB curve) are
/// analysis/util/color.h, included here for the renderer's files.

#include <string>

#include "analysis/geometry/geometry.h"
#include "analysis/util/color.h"
#include "analysis/util/palette.h"

namespace pandora {

/// Draws `text` with a 3x5 pixel font scaled by `scale`, top-left corner at (x, y), into a linear
/// RGB buffer of width x height (3 floats per pixel). Characters: digits, a-z, . - + / _ % = < > [
/// ] ( ) , : and space; others are drawn as a box. Returns the width drawn in pixels.
int DrawText(float* rgb, int width, int height, int x, int y, const std::string& text,
             const Vec3& color, int scale);

/// Width in pixels DrawText would use.
int TextWidth(const std::string& text, int scale);

}  // namespace pandora
