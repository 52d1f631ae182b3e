#pragma once
/// \file suggest_options.h
/// `pandora suggest`'s options turned into the library's SuggestOptions: the selection by camera
/// id, per-camera limits ("one value, or one per selected camera"), mounts and zoom ranges ("ID:"
/// prefixes), keep-out boxes, the objective. Every error names the option as its field
/// (`{max_move}`), which each front end writes its own way (analysis/util/error.h).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "app/commands.h"
#include "app/session/session.h"
#include "suggest/suggest.h"

namespace pandora::app {

/// The session of a suggest run: the scene file, --rig and --disable.
session::SessionOptions SuggestSessionOptions(const SuggestArgs& args);

/// A value for one selected camera (`camera`: its id) or, with `camera` empty, for every one.
template <typename T>
struct ForCamera {
  std::string camera;
  T value;
};

/// A camera suggestion asked for in values, as every front end holds it: `pandora suggest` parses
/// its options into one (SuggestRequestFromArgs), Python's suggest() and the viewer's Suggest panel
/// fill one from their own values (no text on the way). PrepareSuggest checks it against the scene
/// and rig, naming the field at fault (`{max_move}`), and builds the problem.
struct SuggestRequest {
  std::vector<std::string> cameras;  ///< Ids of the cameras that may move.
  /// Metres and degrees: one value for all selected cameras, or one each in `cameras` order.
  std::vector<double> max_move{0.3}, max_rotate_deg{10.0};
  std::string objective = "coverage2";       ///< ParseObjective's names.
  std::optional<Vec3> weights;               ///< The mix's (coverage, sigma, resolution) weights.
  std::vector<ForCamera<Vec3>> rail, plane;  ///< Mount directions; at most one mount per camera.
  std::vector<ForCamera<Aabb>> mount_box;
  std::vector<ForCamera<std::array<double, 2>>> hfov_range;  ///< Zoom range, degrees.
  std::vector<Aabb> keep_out;
  std::vector<std::string> target_surfaces;
  bool with_region = false;
  bool over_time = false;
  int points = 1500;
  double snap_move = 0, snap_rotate_deg = 0;
  double clearance = 0.1;
  int outer_iterations = 4;
  std::uint64_t seed = 1;
};

/// `pandora suggest`'s option text as values (numbers, "ID:" prefixes, boxes); InputError naming
/// the option at fault.
SuggestRequest SuggestRequestFromArgs(const SuggestArgs& args);

/// The library's options for `request` on `rig` of `scene`, every value checked (its field named).
SuggestOptions SuggestOptionsOf(const SuggestRequest& request, const Scene& scene, const Rig& rig);

/// Everything a camera suggestion runs on: the options and the target points and, over time
/// (`--over-time`), the moving parts and one ray caster per time sample (options.sample_casters
/// points into them, so the problem is kept whole while a suggestion runs).
struct SuggestProblem {
  SuggestOptions options;
  std::vector<TargetPoint> targets;
  std::unique_ptr<RigidPartsRayCaster> parts;
  std::vector<std::unique_ptr<RayCaster>> sample_casters;
};

/// The one door to a camera suggestion's problem: `pandora suggest`, Python's suggest() and the
/// viewer's Suggest panel all build it here from the same options, so that they optimise the same
/// objective over the same points (region, named surfaces, or the study's targets at every time
/// sample). Throws InputError naming the option ({cameras}, {over_time}, {target_surfaces}, ...).
std::shared_ptr<SuggestProblem> PrepareSuggest(const SuggestRequest& request, const Scene& scene,
                                               const Rig& rig);

/// The enabled PTZ camera `id` of `rig` (its index), or InputError naming `option` with the rig's
/// PTZ cameras as the hint.
int PtzCameraOption(const Rig& rig, const std::string& option, const std::string& id);

/// SampleTargets over the study region, or over the study's region `region` when it is not empty
/// (InputError naming `option` and the study's regions when there is none of that name).
std::vector<TargetPoint> SampleTargetsInRegion(const Scene& scene, const std::string& option,
                                               const std::string& region, int points,
                                               const std::vector<std::string>& surfaces,
                                               bool with_region, std::uint64_t seed);

}  // namespace pandora::app
