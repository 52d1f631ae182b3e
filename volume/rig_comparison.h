#pragma once
/// \file rig_comparison.h
/// The rigs of a scene compared on their headline numbers (the report's "Rigs compared" table): a
/// typed value built from each rig's Summary (volume/summary.h), with the best rig of each row
/// decided on the values as shown, and its JSON form. Labels and values are plain ASCII text (the
/// viewer shows them as they are; the report writes ">=", "<=" and "sigma_max" as HTML).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "analysis/scene/scene.h"
#include "volume/summary.h"

namespace pandora {

/// One headline number across the rigs.
struct ComparisonRow {
  std::string key;    ///< Stable name, e.g. "coverage_ge2", "sigma_max_p50_mm".
  std::string label;  ///< Plain text, e.g. "Coverage >= 2 cameras", "sigma_max p50 (mm)".
  /// printf format of a value ("%.3f"), or empty: a fraction shown as a percentage with one
  /// decimal.
  std::string format;
  bool higher_better = true;
  std::vector<std::optional<double>> values;  ///< One per rig; nullopt: the rig has none.
  /// One per rig: true where the rig's value, rounded as shown, is the best of the row while some
  /// rig shows a worse one (never with a single rig, never where every rig shows the same).
  std::vector<bool> best;

  /// The value as the table prints it: Format(format, v), or "12.3%" for a fraction; "-" for none
  /// or a non-finite value.
  std::string Text(std::size_t rig) const;
  /// The value rounded to the precision printed (what "best" compares); NaN for none.
  double Shown(std::size_t rig) const;
};

/// The comparison of one or more rigs (columns in the given order).
struct RigComparison {
  std::vector<std::string> rigs;            ///< Names.
  std::vector<int> enabled_cameras;         ///< Per rig.
  std::vector<ComparisonRow> rows;          ///< Coverage, resolution, uncertainty, targets.
  std::vector<std::size_t> warnings;        ///< Per rig: CheckRig warnings.
  std::vector<std::int64_t> region_voxels;  ///< Per rig: free region voxels.
  std::vector<double> evaluation_seconds;   ///< Per rig: field evaluation wall time.

  /// The row called `key`, or nullptr.
  const ComparisonRow* Find(const std::string& key) const;
};

/// Compares `summaries` (one per rig, same study). Rows: coverage >= 1, 2, 3 cameras (fractions);
/// resolution p10, p50, p90 (px/m); triangulable (fraction); sigma_max p50, p90, p99 (mm, lower is
/// better); with a target sigma (study.max_sigma_mm) the share meeting it; with a motion model
/// (study.motion) the steady-state sigma_max p50, p90, p99 and, with a target, the share meeting
/// it.
RigComparison CompareRigs(const std::vector<Summary>& summaries, const Study& study);

/// {"rigs": [names], "enabled_cameras": [...], "warnings": [...], "region_voxels": [...],
/// "evaluation_seconds": [...], "rows": [{"key", "higher_better", "values": [number or null],
/// "best": [bool]}]} (labels and formats are presentation and stay out).
void to_json(nlohmann::json& j, const RigComparison& comparison);

}  // namespace pandora
