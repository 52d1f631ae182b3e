#pragma once
/// \file suggestion_text.h
/// A suggestion as the text `pandora suggest` prints: per selected camera its move, rotation and
/// positions, then the exact measures before and after, then what the optimisation spent. The
/// viewer shows the same numbers (docs/suggest.md, "Reading the table").

#include <string>

#include "suggest/suggest.h"

namespace pandora {

/// A value for a table: "inf" / "-inf" for infinities, "n/a" for NaN, else printf(`format`).
std::string TableValue(double value, const char* format = "%.4g");

/// Where a suggestion was computed, for the table's first line.
struct SuggestionContext {
  std::string title = "pandora suggest";
  std::string scene_path;
  std::string rig_name;
};

/// The table, lines ending in '\n'. Percentiles that fall on an untriangulable point read "inf",
/// explained in a last line.
std::string FormatSuggestion(const Suggestion& suggestion, const SuggestionContext& context);

/// "perturbed by MOVE,DEG: ... recovered X of the lost Y (P%)": how much of what a perturbation
/// lost (`original_objective` at the unperturbed poses) the suggestion won back.
std::string FormatRecovery(const Suggestion& suggestion, double original_objective,
                           const std::string& perturbation);

}  // namespace pandora
