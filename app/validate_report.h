#pragma once
// The validation study's shared outputs (docs/validation.md): the measured-against-predicted plot,
// the verdict, and a rig's cell of the report's "Predicted against measured" section
// (`pandora report --validate`).
#include <functional>
#include <string>

#include "validation/validate.h"

namespace pandora::app {

/// Measured against predicted RMS per bin of predicted sigma and axis (log-log, the identity
/// dashed), SVG.
std::string ValidationPlotSvg(const ValidateResult& r);

/// Whether every bin of predicted sigma holding >= min_bin corners has every axis's ratio within
/// `tolerance` of 1 (false when there is no bin).
bool ValidationPasses(const ValidateResult& r, int min_bin, double tolerance);

/// The rig's cell of the report section: the board, corners, noise, verdict, the bins' table and
/// the plot (through `svg_image`, which embeds an SVG figure and returns its HTML).
std::string ValidationCellHtml(
    const ValidateResult& r, int min_bin, double tolerance,
    const std::function<std::string(const std::string& svg, const std::string& alt)>& svg_image);

}  // namespace pandora::app
