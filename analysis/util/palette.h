#pragma once
/// \file palette.h
/// Camera colours that stay apart: a 24-colour palette for the cameras' lights, picked for
/// distinguishability (greedy farthest-point selection under CIEDE2000 among saturated sRGB colours
/// with L* >= 45 and chroma >= 45, so every colour shows as light on a dark surface), and the
/// CIELAB / CIEDE2000 arithmetic its test checks it with. docs/rendering.md ("Camera colours")
/// gives the table and the measured distances. The scene loader gives every camera without a
/// "color" in the file the palette colour of its index in the rig.

#include "analysis/util/color.h"

namespace pandora {

/// Number of distinct palette colours; camera i gets colour i % kCameraPaletteSize.
inline constexpr int kCameraPaletteSize = 24;

/// The palette's colour `index` (taken modulo kCameraPaletteSize) as "#rrggbb" (sRGB).
const char* CameraPaletteHex(int index);

/// The same colour in linear RGB (what Camera::color holds).
Vec3 CameraPaletteColor(int index);

/// CIELAB (D65 white, 2-degree observer) of a linear-RGB colour (sRGB primaries).
Vec3 LabFromLinearRgb(const Vec3& rgb);

/// CIEDE2000 colour difference of two CIELAB colours (Sharma, Wu and Dalal 2005, kL = kC = kH = 1).
double DeltaE2000(const Vec3& lab1, const Vec3& lab2);

}  // namespace pandora
