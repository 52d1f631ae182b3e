#pragma once
/// \file commands.h
/// The `pandora` subcommands. Each returns the process exit code; bad input throws InputError, which
/// main() prints as one line and turns into exit code 2.

#include <limits>
#include <string>
#include <vector>

namespace pandora::app {

/// A numeric option the user did not give.
inline const double kUnset = std::numeric_limits<double>::quiet_NaN();

/// Checks the value of a numeric command-line option: positive and finite, else InputError naming
/// the option. Returns `value`.
double CheckPositiveOption(const char* option, double value, const char* unit);

struct AnalyzeArgs {
  std::string scene;
  std::string rig;
  std::string out = "out";
  double voxel_size = kUnset;  ///< kUnset: the scene's study.voxel_size.
  std::string fields;     ///< Comma-separated; empty: the scene's study.fields.
  double memory_budget_mb = kUnset;  ///< MiB; kUnset: the scene's study.memory_budget_mb.
  bool quiet = false;
};
int RunAnalyze(const AnalyzeArgs& args);

struct BenchArgs {
  std::string scene;
  std::string rig;
  double voxel_size = kUnset;
  int repeat = 3;
  std::string json_out;
};
int RunBench(const BenchArgs& args);

/// `pandora accuracy`: error against run time (issue 3, point 6) for (a) voxel size against the
/// coverage and uncertainty summaries of the finest size, (b) Monte Carlo trials against the
/// closed-form triangulation covariance, (c) the steady-state Riccati solvers against a long-double
/// reference. Writes accuracy_{voxel,montecarlo,steady}.{csv,svg} and accuracy_tables.md to `out`.
struct AccuracyArgs {
  std::string scene;
  std::string rig;
  std::string out = "out/accuracy";
  bool quick = false;  ///< Fewer voxel sizes, trials and sample points (tests).
};
int RunAccuracy(const AccuracyArgs& args);

/// `pandora suggest` (issue 5): nudge the selected cameras within limits (docs/suggest.md); prints the
/// before/after table and writes the suggestion file. With `compare_baseline` also runs the random
/// local search with the same evaluation budget and writes CSV + SVG of objective against time.
struct SuggestArgs {
  std::string scene;
  std::string rig;
  std::string cameras;            ///< Comma-separated camera ids.
  std::string max_move = "0.3";   ///< Metres: one value, or one per selected camera (commas).
  std::string max_rotate = "10";  ///< Degrees: likewise.
  std::string objective = "coverage2";
  std::string weights;            ///< "wc,ws,wr" for the mix.
  /// Mounts (at most one per camera) and zoom ranges ("MIN,MAX" degrees): each entry applies to all
  /// selected cameras, or to one with an "ID:" prefix.
  std::vector<std::string> rail, plane, mount_box, hfov_range;
  std::vector<std::string> keep_out;   ///< Boxes "x0,y0,z0,x1,y1,z1".
  std::vector<std::string> target_surfaces;
  bool with_region = false;       ///< Region points as well as surface points.
  int points = 1500;
  double snap_move = 0, snap_rotate = 0;
  int outer_iterations = 4;
  std::string out = "suggestion.json";
  std::string perturb;            ///< "MOVE,DEG": benchmark from perturbed poses.
  std::string compare_baseline;   ///< Output folder for the baseline comparison.
  unsigned long long seed = 1;
  bool quiet = false;
};
int RunSuggest(const SuggestArgs& args);

/// `pandora accept`: writes the suggested poses into the scene file (backup first).
struct AcceptArgs {
  std::string suggestion;
  std::string cameras;  ///< Comma-separated ids; empty: all.
  bool force = false;
  bool quiet = false;
};
int RunAccept(const AcceptArgs& args);

}  // namespace pandora::app
