#pragma once
/// \file calibration_section.h
/// The report's "Calibration" section (docs/report.md, docs/calibration.md): per rig the
/// co-visibility matrix as an SVG heat map and a table of the cameras, components and weakest
/// links of the simulated calibration (analysis/rig/calibration.h). Plain strings: no OpenVDB,
/// Embree or image library here.

#include <functional>
#include <string>

#include "analysis/rig/calibration.h"

namespace pandora::report {

/// The co-visibility matrix of `result` as a standalone SVG document: one cell per camera pair in
/// rig order, camera ids on both axes. Off-diagonal cells are coloured by the poses both cameras
/// observe (viridis from 0 to the largest off-diagonal count) when that is at least min_shared
/// (a link of the graph), light grey below it, white at 0; diagonal cells show each camera's own
/// count. A band of colour beside each id marks its component (uncalibratable ids in red);
/// the maximum spanning tree's links are outlined in black, the weakest one in red. Counts are
/// written in the cells when they are large enough to read.
std::string CalibrationMatrixSvg(const CalibrationResult& result, const std::string& title);

/// A note for the top of the section: the target, its rules and the simulation's settings.
std::string CalibrationIntroHtml(const CalibrationSpec& spec);

/// One rig's cell of the section: the verdict, the heat map (through `svg_image`, which turns an
/// SVG document and its alt text into an <img>), and a table of cameras (component, poses
/// observed, why the others were missed) and of the weakest links.
std::string CalibrationCellHtml(
    const CalibrationResult& result, const std::string& rig_name,
    const std::function<std::string(const std::string& svg, const std::string& alt)>& svg_image);

}  // namespace pandora::report
