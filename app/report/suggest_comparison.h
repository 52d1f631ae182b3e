#pragma once
/// \file suggest_comparison.h
/// `pandora suggest --compare-baseline`: the suggestion (screening + Ceres nudge) against two
/// random local searches given the same evaluation budget, as the best exact objective over time: a
/// CSV of the traces, a log-log SVG plot and a text table (docs/suggest.md, "Against a baseline").

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "suggest/suggest.h"

namespace pandora::report {

struct SuggestRun {
  std::string name;   ///< CSV method: "ceres", "random", "random_adaptive".
  std::string label;  ///< Legend and table: "screening + Ceres nudge", ...
  Suggestion result;
};

struct SuggestComparison {
  std::vector<SuggestRun> runs;  ///< The suggestion first, then the two baselines.
  std::string csv;               ///< method,seconds,evaluations,best_objective: every trace point.
  std::string svg;    ///< Best exact objective (coverage: the share still short) against seconds.
  std::string table;  ///< Final values, time to reach the suggestion's and the better baseline's.
};

/// Runs BaselineSearch with a fixed and with an adaptive step (seed `seed`) from `rig` for as many
/// evaluations as `suggestion` spent, and lays the three traces side by side. `original_objective`
/// (a perturbation benchmark: the objective at the unperturbed poses) is drawn as a dashed line.
SuggestComparison CompareWithBaselines(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                       const std::vector<TargetPoint>& targets,
                                       const SuggestOptions& options, const Suggestion& suggestion,
                                       std::uint64_t seed,
                                       std::optional<double> original_objective = std::nullopt);

/// Seconds at which a trace first reaches `target` (higher or lower is better), or +inf.
double TimeToReach(const std::vector<TracePoint>& trace, double target, bool higher_is_better);

}  // namespace pandora::report
