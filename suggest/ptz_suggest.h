#pragma once
/// \file ptz_suggest.h
/// Suggestions for a PTZ camera's controller (docs/ptz.md, "Suggest"): the pan, tilt and zoom of a
/// preset that best covers a target, and the order of a tour's stops that minimises the longest
/// time a target point goes unwatched. Both are judged exactly on target points (PtzSees at the
/// study's density target plus the occlusion segment from the setting's centre), the person
/// accepts or rejects them (`pandora accept` rewrites the preset or the tour in the scene file,
/// with a backup). Light header (no JSON, no Ceres).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/visibility.h"
#include "analysis/scene/ptz.h"
#include "analysis/scene/scene.h"

namespace pandora {

class JsonNode;

/// Which target points a setting of a PTZ camera sees: PtzSees at `min_px_per_m` and, when it does,
/// the occlusion segment from the setting's centre (cast once per point when the offset is zero:
/// the pivot is every setting's centre).
class PtzPointJudge {
 public:
  /// `tester` holds the rig's cameras; `camera` indexes the PTZ camera among them.
  PtzPointJudge(const VisibilityTester& tester, int camera, const std::vector<Vec3>& points,
                double min_px_per_m);
  const Camera& camera() const { return tester_.cameras()[camera_]; }
  const PtzHead& head() const { return *camera().ptz; }
  /// Points seen from setting `s`.
  int Count(const PtzState& s) const;
  /// Whether point `i` is seen from `s`.
  bool Sees(std::size_t i, const PtzState& s) const;
  std::size_t size() const { return points_.size(); }
  const Vec3& point(std::size_t i) const { return points_[i]; }
  /// Point `i` as PtzSees tests it (WatchTour's exact move events).
  PtzTarget target(std::size_t i) const {
    return {points_[i], min_px_per_m_, nullptr, &tester_, camera_};
  }
  std::int64_t rays() const { return rays_; }

 private:
  const VisibilityTester& tester_;
  int camera_;
  std::vector<Vec3> points_;
  double min_px_per_m_;
  mutable std::vector<signed char> pivot_clear_;  // zero offset: -1 unknown, 0 blocked, 1 clear
  mutable std::int64_t rays_ = 0;
};

struct PtzPresetSuggestion {
  std::string camera, preset;
  PtzState before, after;
  int points = 0;
  int seen_before = 0, seen_after = 0;  ///< Target points seen from the preset.
  int evaluations = 0;                  ///< Settings judged.
  double seconds = 0;
  bool improved() const { return seen_after > seen_before; }
};

/// The setting of preset `preset` of rig camera `camera` that sees the most target points at the
/// density target: candidates centred on the target points (their centring pan and tilt, a sample
/// of up to 64 and their mean direction) at 12 zooms from the widest to the narrowest, then a
/// pattern search in pan, tilt and log-focal from the best few, halving its steps to 0.01 degree.
/// Ties go to the wider zoom, then the smaller move from the preset as it is. Within the head's
/// ranges. Single-threaded, deterministic.
PtzPresetSuggestion SuggestPtzPreset(const VisibilityTester& tester, int camera, int preset,
                                     const std::vector<Vec3>& points, double min_px_per_m);

/// What a tour order minimises over the watchable points.
enum class TourObjective {
  kMean,  ///< The mean of each point's longest unwatched stretch (then the longest of all).
  kMax,   ///< The longest unwatched stretch of any point (then the mean).
};
/// The names of the tour objectives, in enum order ("mean", "max"): the command's
/// --tour-objective, Python's objective=, the suggestion file's "objective".
inline const std::vector<std::string>& TourObjectiveNames() {
  static const std::vector<std::string> kNames{"mean", "max"};
  return kNames;
}
inline const std::string& TourObjectiveName(TourObjective objective) {
  return TourObjectiveNames()[static_cast<std::size_t>(objective)];
}
/// The objective TourObjectiveName calls `name`; nullopt for any other text.
inline std::optional<TourObjective> TourObjectiveFromName(const std::string& name) {
  for (std::size_t i = 0; i < TourObjectiveNames().size(); ++i)
    if (TourObjectiveNames()[i] == name) return static_cast<TourObjective>(i);
  return std::nullopt;
}

struct PtzTourSuggestion {
  std::string camera;
  TourObjective objective = TourObjective::kMean;
  std::vector<int> before, after;  ///< Stop orders (indices into the head's tour).
  int points = 0;
  /// Target points some stop watches while it dwells (the others are left out: a point only
  /// glimpsed while the head moves is not watched by design, and one that only one stop watches has
  /// the same gap in every order).
  int watchable = 0;
  /// Over the watchable points: the longest unwatched stretch of any point and the mean of each
  /// point's longest stretch, seconds (the moves' glimpses count as watching).
  double gap_max_before = 0, gap_max_after = 0, gap_mean_before = 0, gap_mean_after = 0;
  double period_before = 0, period_after = 0;
  std::int64_t orders = 0;  ///< Orders judged.
  bool exhaustive =
      false;  ///< Every order was judged (at most 8 stops), else 2-opt from every rotation.
  double seconds = 0;
  bool improved() const {
    return Better(gap_max_after, gap_mean_after, gap_max_before, gap_mean_before);
  }
  /// True when (max, mean) a beats b under the objective (by more than 1e-9 s).
  bool Better(double max_a, double mean_a, double max_b, double mean_b) const {
    const double a1 = objective == TourObjective::kMax ? max_a : mean_a,
                 a2 = objective == TourObjective::kMax ? mean_a : max_a;
    const double b1 = objective == TourObjective::kMax ? max_b : mean_b,
                 b2 = objective == TourObjective::kMax ? mean_b : max_b;
    return a1 < b1 - 1e-9 || (a1 <= b1 + 1e-9 && a2 < b2 - 1e-9);
  }
};

/// The order of the tour's stops of rig camera `camera` (a cycle: the first stop stays first) that
/// minimises `objective` over the watchable target points. Each
/// point's watched intervals are computed once per preset (dwells) and per ordered pair of presets
/// (moves, as PtzTourWatch samples them); an order is then judged by concatenating them. Every
/// order for up to 8 stops, else a 2-opt descent.
PtzTourSuggestion SuggestPtzTour(const VisibilityTester& tester, int camera,
                                 const std::vector<Vec3>& points, double min_px_per_m,
                                 TourObjective objective = TourObjective::kMean);

/// The longest unwatched stretch of each point for tour order `order` of `judge`'s head, judged as
/// PtzTourWatch does (the reference for SuggestPtzTour's fast path).
std::vector<double> PtzTourGaps(const PtzPointJudge& judge, const std::vector<int>& order);

/// The suggestion file of a PTZ suggestion (docs/ptz.md): {"pandora_suggestion": 1, "kind":
/// "ptz_preset" | "ptz_tour", scene {path, sha256}, rig, improved, cameras: [], ptz {...}}.
std::string PtzPresetSuggestionToJson(const PtzPresetSuggestion& s, const Scene& scene,
                                      const Rig& rig);
std::string PtzTourSuggestionToJson(const PtzTourSuggestion& s, const Scene& scene, const Rig& rig);

/// The scene file text with preset `preset` of camera `camera` in rig `rig` set to `state`
/// (pan_deg, tilt_deg, and hfov_deg when the head zooms) or, with `tour_order` non-empty, its
/// tour's stops reordered; everything else kept (re-serialised with the file's indentation). Throws
/// InputError (file = scene_path) when the rig, camera, preset or tour is not there.
std::string ReplacePtzPreset(const std::string& scene_text, const std::string& scene_path,
                             const std::string& rig, const std::string& camera,
                             const std::string& preset, const PtzState& state, double hfov_deg);
std::string ReplacePtzTour(const std::string& scene_text, const std::string& scene_path,
                           const std::string& rig, const std::string& camera,
                           const std::vector<int>& tour_order);

/// `pandora accept` of a PTZ suggestion file (already parsed, `suggestion` its root): checks it as
/// AcceptSuggestion does (improved, scene unchanged unless `force`), rewrites the preset or the
/// tour, parses the result back and checks that exactly that changed, then replaces the scene file
/// with a backup. Returns the backup path; `what` receives e.g. "dome preset window".
std::string AcceptPtzSuggestion(const JsonNode& suggestion, bool force, std::string* scene_path,
                                std::string* what);

}  // namespace pandora
