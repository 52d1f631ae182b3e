#pragma once
/// \file robustness_section.h
/// The report's "Robustness" section (docs/report.md, docs/failures.md): per rig the N-1 numbers
/// (volume/robustness.h) and a table of its most critical cameras. Plain strings: no OpenVDB here.

#include <string>

#include "volume/robustness.h"

namespace pandora::report {

/// A note for the top of the section: what a row means.
std::string RobustnessIntroHtml(int k);

/// One rig's cell: the intact share seen by >= k cameras, the worst single failure and the mean
/// over failures, then the `rows` most critical cameras (coverage >= 1, 2, 3 and k after each
/// fails, and with the uncertainty the triangulable share and sigma_max p50 / p90).
std::string RobustnessCellHtml(const CriticalityTable& table, int rows = 5);

}  // namespace pandora::report
