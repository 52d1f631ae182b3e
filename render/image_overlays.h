#pragma once
/// \file image_overlays.h
/// Internal to render/: what the renderer draws over the shaded image after the rays (camera bodies
/// and frusta, the slice's colour bar, the colour key).

#include <string>

#include "analysis/geometry/camera.h"
#include "analysis/scene/scene.h"
#include "render/render.h"

namespace pandora::internal {

/// Each enabled camera of `rig`: a small box body behind its centre and its frustum (the distorted
/// image border unprojected) out to min(frustum_length, far), antialiased lines in the camera's
/// colour, seen through the pinhole `view`; parts behind the surfaces (image->depth) at 30 %.
void DrawCameraOverlays(const Rig& rig, const Camera& view, const OverlayOptions& ov,
                        const RenderOptions& options, Image* image);

/// Colour bar of the slice overlay with its range and the field's label, lower right corner.
void DrawLegend(const std::string& field, double vmin, double vmax, Image* image);

/// The colour key, upper left corner: a swatch of each enabled camera's light and its id, in as
/// many columns as the height needs; nothing when it would take more than half the width.
void DrawKey(const Rig& rig, Image* image);

}  // namespace pandora::internal
