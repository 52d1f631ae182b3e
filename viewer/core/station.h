#pragma once
/// \file station.h
/// Viewing-station design (the Pandora paper's Section 5): the display placed in the scene shows
/// the scene as the viewer's eye sees it through the display rectangle (an off-axis perspective, as
/// a head-tracked display renders it), and the head tracker's angular range is drawn as a
/// wireframe.

#include <array>

#include "analysis/scene/scene.h"

namespace pandora::viewer {

/// The display's corners in the world: top left, top right, bottom right, bottom left as the viewer
/// in front of it sees them.
std::array<Vec3, 4> DisplayCorners(const ViewingStation& station);

/// A pinhole camera at the station's eye whose image is exactly the display rectangle at
/// pixels_wide x pixels_high (image corners -0.5 and width - 0.5 on the display's corners): render
/// its camera's-eye view to get what the display shows. Disabled (it lights nothing), id "display".
Camera DisplayCamera(const ViewingStation& station);

/// The tracker's working volume: the corners of its near rectangle (top left, top right, bottom
/// right, bottom left) then of its far one, from its angular range and distances.
std::array<Vec3, 8> TrackerCorners(const ViewingStation& station);

}  // namespace pandora::viewer
