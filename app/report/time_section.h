#pragma once
/// \file time_section.h
/// The report's "Over time and on bodies" section (docs/time.md): for scenes with moving objects or
/// surface targets, a table with one column per rig of the volume over the time samples (covered
/// by k cameras always, on average, in the worst sample) and of each target (body points seen by
/// >= 1, 2, 3 cameras over all samples, by k in every sample, the worst sample), then the shares
/// sample by sample. Plain HTML; the best value of each row in bold.

#include <string>
#include <vector>

#include "volume/summary.h"

namespace pandora::report {

/// Empty when no summary has a time block or targets.
std::string TimeSectionHtml(const std::vector<const Summary*>& summaries,
                            const std::vector<std::string>& rig_names);

}  // namespace pandora::report
