#pragma once
/// \file suggest_run.h
/// Private to suggest/: one Suggest call's shared state (SuggestRun) and its stages. Suggest()
/// (suggest_search.cpp) orchestrates: the exact screening and the levelling there, the Ceres nudge
/// (FindActive, Polish and the smooth surrogate they minimise) in suggest_ceres.cpp, the only file
/// that includes Ceres.

#include <chrono>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "suggest/suggest.h"
#include "suggest/suggest_internal.h"

namespace pandora::suggest_detail {

constexpr double kInf = std::numeric_limits<double>::infinity();
// The share of SuggestOptions::progress the screening reports (the nudge the rest).
constexpr double kScreeningShare = 0.3;

// Seconds on the steady clock since `t0`.
inline double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The smooth surrogate of the objective the nudge minimises (suggest_ceres.cpp).
class Surrogate;
struct SurrogateDeleter {
  void operator()(Surrogate* surrogate) const;
};
std::unique_ptr<Surrogate, SurrogateDeleter> MakeSurrogate(const ExactEvaluator& ev,
                                                           bool need_info);
std::int64_t SurrogateEvaluations(const Surrogate& surrogate);

// What the stages of one Suggest call share: the inputs, the exact evaluator, the surrogate, the
// parameters and the best pose so far (Suggest's own), the suggestion being filled, and what the
// screening and the polish keep between their steps.
struct SuggestRun {
  SuggestRun(const SuggestOptions& options, const ExactEvaluator& ev, const Placement& placement,
             const std::vector<PoseChart>& charts, const std::vector<Eigen::Isometry3d>& start,
             Suggestion& s, Surrogate& surrogate, std::chrono::steady_clock::time_point t0,
             double start_score, std::vector<std::vector<double>>& x,
             std::vector<std::vector<double>>& best_x, Metrics& best_m, double& best_score)
      : options(options),
        ev(ev),
        placement(placement),
        charts(charts),
        start(start),
        s(s),
        surrogate(surrogate),
        t0(t0),
        nsel(options.cameras.size()),
        start_score(start_score),
        x(x),
        best_x(best_x),
        best_m(best_m),
        best_score(best_score) {}

  // Seconds since Suggest began.
  double Elapsed() const { return SecondsSince(t0); }

  // Whether the caller asked the search to stop (SuggestOptions::cancel).
  bool Stopped() const { return options.cancel && options.cancel->load(std::memory_order_relaxed); }
  // Reports the fraction done (SuggestOptions::progress).
  void Progress(double fraction) const {
    if (options.progress) options.progress(fraction);
  }

  // The suggestion with `message`, the evaluations and the time taken.
  Suggestion Finish(const std::string& message) {
    s.message = message;
    s.evaluations = ev.evaluations() + SurrogateEvaluations(surrogate);
    s.seconds = Elapsed();
    return s;
  }

  // How far the occlusion slopes of selected camera c look (a fraction of its move limit).
  double OcclusionDelta(std::size_t c) const;

  void FindActive();
  std::vector<double> Sample(const PoseChart& chart, const std::vector<double>& centre,
                             double radius);
  void TryMove(const std::vector<int>& group, std::vector<std::vector<double>>& xs);
  void ScreenChain(int candidates, int joint_candidates);
  void Screen();
  std::pair<std::vector<Eigen::Isometry3d>, bool> PosesOf(std::vector<std::vector<double>>& xs);
  void JudgeStep();
  void Polish();
  void LevelPoses(std::vector<Eigen::Isometry3d>& best_poses,
                  const std::vector<double>& best_scales);

  const SuggestOptions& options;
  const ExactEvaluator& ev;
  const Placement& placement;
  const std::vector<PoseChart>& charts;
  const std::vector<Eigen::Isometry3d>& start;
  Suggestion& s;
  Surrogate& surrogate;
  const std::chrono::steady_clock::time_point t0;
  const std::size_t nsel;
  const double start_score;
  std::vector<std::vector<double>>& x;
  std::vector<std::vector<double>>& best_x;
  Metrics& best_m;
  double& best_score;

  std::vector<int> movable;  // the selected cameras with limits that let them move
  std::vector<int> active;   // the cameras the nudge moves
  std::vector<std::vector<double>> screened_x;  // the screening's best, when it beat the start
  double screened_score = -kInf;
  // The screening's random draws (fixed seed), and one chain's current poses, views and score.
  std::mt19937_64 rng{0x5eedULL};
  std::uniform_real_distribution<double> uniform{-1.0, 1.0};
  std::vector<std::vector<double>> cur_x;
  std::vector<CameraView> cur_view;
  std::vector<const CameraView*> ptrs;
  double cur_score = -kInf;
  // The focal scales of the poses PosesOf took last.
  std::vector<double> scales;
  // The polish's best pose so far (best_x is the best of all, the screening's included).
  std::vector<std::vector<double>> run_x;
  double run_score = -kInf;
};

}  // namespace pandora::suggest_detail
