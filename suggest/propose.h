#pragma once
/// \file propose.h
/// Global layout proposals (`pandora propose`, docs/propose.md): how many cameras, which mounts,
/// which lenses. From a candidate set (mount points on the walls, the ceiling, named objects or a
/// list, times aim points, times lenses), every candidate's visibility of the target points is
/// computed once (the exact tests of VisibilityTester, at every time sample); a greedy selection
/// on the soft objective (sum of min(cameras, k)) starts each proposal and a simulated annealing
/// of swaps (one camera out, one candidate in) over the exact objective finishes it. Several
/// proposals are kept different by a penalty on the candidates earlier ones took. The suggest
/// nudge (Ceres) can polish each one after. Nothing here writes files.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/scene/scene.h"
#include "suggest/suggest.h"

namespace pandora {

/// A camera model at one zoom: what a catalogue entry offers.
struct ProposeLens {
  std::string model;  ///< The catalogue's name ("" for the scene's own camera).
  Intrinsics intrinsics;
  double hfov_deg = 0;
  double price = 0;
  double near = 0.3, far = 1e9;
};

/// A catalogue of camera models (JSON, docs/propose.md): each model's sensor, resolution, focal
/// range (or field-of-view range), distortion and price; zoom lenses give `zooms` settings over
/// their range. Throws InputError naming the file and the JSON path.
std::vector<ProposeLens> ReadCameraCatalogue(const std::string& path, int zooms = 3);

/// A point a camera may be mounted at, and what it is on ("wall", "ceiling", "point", an object's
/// name).
struct MountPoint {
  Vec3 position = Vec3::Zero();
  std::string surface;
};

/// Mount points on the static scene's walls (rays cast horizontally from the study region's
/// centre at each height, one per `spacing` metres of the walls' perimeter as seen from there) and
/// ceiling (rays cast up from the region's top over a grid of the static scene's plan, kept where
/// they meet a downward face), each `clearance` in from the surface it hit (along the surface's
/// normal). Moving objects are left out.
std::vector<MountPoint> WallMounts(const Scene& scene, const std::vector<double>& heights,
                                   double spacing, double clearance);
std::vector<MountPoint> CeilingMounts(const Scene& scene, double spacing, double clearance);
/// Mount points under the named objects (a truss, a rail): a grid over the bottom face of each
/// one's bounds, `clearance` below it. Throws InputError(scene.path, "", ...) for an unknown name.
std::vector<MountPoint> ObjectMounts(const Scene& scene, const std::vector<std::string>& names,
                                     double spacing, double clearance);

/// Mount points filling a box (free space a frame or a rig of poles may hold cameras in): a grid at
/// `spacing`, without the points closer than `clearance` to any surface of the scene as placed.
std::vector<MountPoint> BoxMounts(const Scene& scene, const Aabb& box, double spacing,
                                  double clearance);

/// One term of a proposal's objective: `weight` times the share of target points seen by at least
/// `k` cameras, each at `min_px_per_m` or more (0: any density), after the worst single camera
/// failure when `n1`.
struct ProposeTerm {
  double weight = 1;
  int k = 3;
  bool n1 = false;
  double min_px_per_m = 0;
  /// Instead of coverage: the calibration chain's strength (the study's "calibration": board or
  /// wand poses through the region; the weakest edge of the maximum spanning tree of the selected
  /// cameras' shared poses) over its min_shared, at most 1: 1 when every camera links to the rest
  /// through at least min_shared poses (docs/calibration.md).
  bool calibration = false;
  std::string name;  ///< As written ("coverage3", "coverage1@identification", "calibration").
};

/// Parses an objective: terms joined by '+', each "[W*]coverageK[-n1][@DENSITY]" or
/// "[W*]calibration" (which needs the study's "calibration"), DENSITY a number
/// of px/m, a DORI class of EN 62676-4 (detection 25, observation 62.5, recognition 125,
/// identification 250) or a pixel target of the scene's study (its min_px / size_m), e.g.
/// "coverage3", "coverage3-n1", "0.7*coverage3+0.3*coverage1@identification". Throws
/// InputError("--objective", ...) naming what is wrong.
std::vector<ProposeTerm> ParseProposeObjective(const std::string& text, const Scene& scene);

struct ProposeOptions {
  int cameras = 12;   ///< Cameras per proposal (the most, with a budget).
  double budget = 0;  ///< > 0: the total price may not exceed it.
  int proposals = 3;  ///< How many different layouts.
  std::vector<ProposeTerm> terms = {ProposeTerm()};  ///< The objective: their weighted sum.
  std::vector<MountPoint> mounts;
  std::vector<ProposeLens> lenses;  ///< At least one.
  int aims = 4;                     ///< Aim points per mount besides the targets' centroid.
  double seconds = 20;              ///< The annealing's time, all proposals together.
  /// > 0: the annealing takes this many swap trials per layout instead of a time (reproducible
  /// whatever the machine's speed; `seconds` is then ignored).
  std::int64_t iterations = 0;
  double diversity = 0.004;  ///< Objective penalty per candidate an earlier proposal took.
  std::uint64_t seed = 1;
  /// The trade-off against cost: a layout of at most `cameras` per budget (the lenses' prices).
  std::vector<double> curve_budgets;
  std::function<void(const std::string& stage, double fraction)> progress;
};

struct Proposal {
  std::vector<int> candidates;  ///< Indices into ProposeResult::candidates.
  double objective = 0;         ///< Exact: the terms' weighted sum over the target points.
  std::vector<double> terms;    ///< Each term's value (share, 0..1), in ProposeOptions order.
  double coverage_k = 0;        ///< The first term's share seen by >= k cameras (at its density).
  double n1 = 0;                ///< The first term's share after the worst single failure.
  double price = 0;
};

struct ProposeResult {
  std::vector<Camera> candidates;
  std::vector<int> candidate_lens;  ///< Index into ProposeOptions::lenses per candidate.
  std::vector<std::string> candidate_surface;
  std::vector<Proposal> proposals;
  int points = 0;
  double visibility_seconds = 0, search_seconds = 0;
  /// Greedy + annealing per camera count (ProposeCurve): (cameras, objective).
  std::vector<std::pair<int, double>> curve;
  /// Per budget of ProposeOptions::curve_budgets: the best layout of at most `cameras` within it.
  struct BudgetPoint {
    double budget = 0, price = 0, objective = 0;
    int cameras = 0;
  };
  std::vector<BudgetPoint> budget_curve;
};

/// The candidates (mount x aim x lens, looking at the aim, level) and their visibility of
/// `targets` (each against sample_casters[target.sample], or `caster`), then the proposals.
/// Throws InputError(scene.path, ...) when there are no mounts or lenses, or no candidate sees any
/// target point.
ProposeResult Propose(const Scene& scene, const RayCaster& caster,
                      const std::vector<const RayCaster*>& sample_casters,
                      const std::vector<TargetPoint>& targets, const ProposeOptions& options,
                      int curve_from = 0, int curve_to = 0);

/// Fixed cameras (an existing rig's enabled ones) judged as Propose judges its proposals, over the
/// same target points: for the comparison beside them.
Proposal ScoreCameras(const Scene& scene, const RayCaster& caster,
                      const std::vector<const RayCaster*>& sample_casters,
                      const std::vector<TargetPoint>& targets, const std::vector<Camera>& cameras,
                      const std::vector<ProposeTerm>& terms);

/// A proposal as a rig named `name` with ids NAME_1, ... and the candidates' colours.
Rig ProposalRig(const ProposeResult& result, const Proposal& proposal, const std::string& name);

}  // namespace pandora
