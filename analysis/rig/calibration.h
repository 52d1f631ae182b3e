#pragma once
/// \file calibration.h
/// Calibration feasibility at design time (docs/calibration.md): a calibration target (a wand's
/// single marker, or a planar checkerboard / ChArUco board) is moved through the study region in
/// random poses, and each pose counts for the cameras that would detect it. From the counts: which
/// camera pairs share enough poses to be calibrated together (the co-visibility graph), its
/// connected components, the cameras that cannot be calibrated with the rest, and the weakest links
/// of the calibration chain (the maximum spanning tree's edges, weakest first).
///
/// Light header: no Embree, CGAL or OpenVDB. Scene, Rig and VisibilityTester are declared here
/// only; the scene file's "study.calibration" section (docs/scene-format.md) reads into
/// CalibrationSpec.

#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"
#include "analysis/scene/calibration_spec.h"

namespace pandora {

struct Scene;
struct Rig;
class RayCaster;
class VisibilityTester;

/// One pose of the target: the wand's marker or the board's centre, and the board's frame
/// (columns: its x axis along squares_x, its y axis, its front normal; ignored for a wand).
struct CalibrationPose {
  Vec3 position = Vec3::Zero();
  Mat3 orientation = Mat3::Identity();
};

/// Why a board pose is or is not detected by a camera, in the order the tests run (cheapest first).
enum class BoardView : std::uint8_t {
  kSeen = 0,
  kDisabled,    ///< The camera is disabled.
  kTilted,      ///< Front face turned away, or beyond tilt_max_deg from facing the camera.
  kNotInImage,  ///< A corner projects outside the image, out of range or behind the camera.
  kTooSmall,    ///< A projected square edge is shorter than min_px_per_square.
  kOccluded,    ///< The segment from the camera to a corner hits scene geometry.
};

constexpr int kBoardViewCount = 6;

/// "seen", "disabled", "tilted", "not_in_image", "too_small", "occluded".
const char* BoardViewName(BoardView view);

/// The board's grid corners in world coordinates for `pose`: (squares_x + 1) x (squares_y + 1)
/// points, row by row (x fastest), centred on pose.position.
std::vector<Vec3> BoardCorners(const CalibrationBoard& board, const CalibrationPose& pose);

/// Whether camera `camera` of `tester` detects the board in `pose` (see BoardView). With
/// `min_edge_px` set it receives the smallest projected square edge (pixels) when the test reached
/// that rule, NaN otherwise.
BoardView TestBoard(const VisibilityTester& tester, int camera, const CalibrationBoard& board,
                    const CalibrationPose& pose, double* min_edge_px = nullptr);

/// What camera `camera` makes of the target in `pose`: for a board TestBoard's answer; for a wand
/// VisibilityTester::Test's, as kSeen, kDisabled, kOccluded, or kNotInImage (out of range, behind
/// the camera, outside the image).
BoardView ViewOfPose(const VisibilityTester& tester, int camera, const CalibrationSpec& spec,
                     const CalibrationPose& pose);

/// ViewOfPose(...) == BoardView::kSeen.
bool ObservesPose(const VisibilityTester& tester, int camera, const CalibrationSpec& spec,
                  const CalibrationPose& pose);

/// An edge of the co-visibility graph: cameras a < b (rig indices) and the poses both observe.
struct CalibrationLink {
  int a = 0, b = 0;
  std::int64_t shared = 0;
};

/// The co-visibility graph of a shared-count matrix.
struct CalibrationGraph {
  /// Per camera (rig order) its component index, -1 for a disabled camera. Components are numbered
  /// in rig order of their first camera.
  std::vector<int> component;
  /// The components' cameras (rig indices, ascending), in component order.
  std::vector<std::vector<int>> components;
  /// The component with the most cameras (the first such on a tie); -1 when no camera is enabled.
  int largest = -1;
  /// Enabled cameras outside the largest component or observing fewer than min_shared poses.
  std::vector<int> uncalibratable;
  /// The maximum spanning forest (Kruskal on shared counts >= min_shared, heavier first, ties by
  /// (a, b)), its edges sorted by shared count ascending (ties by (a, b)): the bottlenecks first.
  std::vector<CalibrationLink> weakest_links;
};

/// The graph of `shared` (a symmetric matrix, [a][a] = poses camera a observes): an edge joins
/// enabled cameras a != b when shared[a][b] >= min_shared.
CalibrationGraph BuildCalibrationGraph(const std::vector<std::vector<std::int64_t>>& shared,
                                       const std::vector<bool>& enabled, std::int64_t min_shared);

/// The result of one simulation over one rig.
struct CalibrationResult {
  CalibrationSpec spec;
  std::vector<std::string> camera_ids;  ///< Rig order, disabled cameras included.
  std::vector<bool> enabled;
  std::int64_t poses = 0;              ///< Poses placed in the region's free space.
  std::int64_t poses_observed = 0;     ///< Observed by at least one camera.
  std::int64_t poses_shared = 0;       ///< Observed by at least two cameras.
  std::vector<std::int64_t> observed;  ///< Per camera, poses it observes.
  /// Per camera, the poses it misses by the first rule that fails: [camera][BoardView] (kSeen and
  /// kDisabled entries stay 0; a wand has only kNotInImage and kOccluded).
  std::vector<std::array<std::int64_t, kBoardViewCount>> missed;
  std::vector<std::vector<std::int64_t>> shared;  ///< [a][b] poses both observe; [a][a] = observed.
  CalibrationGraph graph;
  /// Every enabled camera in one component, none uncalibratable, at least one camera enabled.
  bool calibratable = false;
  double seconds = 0;  ///< Wall time of the simulation (sampling included).
};

/// `samples` poses, seeded: positions uniform in the study region's box, kept when inside the
/// region (a mesh region's inside test) and outside every solid object (rejection sampling, at
/// most 1000 tries per pose: fewer poses come back when the free space is tiny or empty); board
/// orientations per spec.orientation, using `tester` for "which camera sees the centre". The same
/// seed gives the same poses, whatever the number of threads.
std::vector<CalibrationPose> SampleCalibrationPoses(const Scene& scene,
                                                    const VisibilityTester& tester,
                                                    const CalibrationSpec& spec);

/// Counts what each camera of `tester` observes of `poses` (in parallel over poses; the result does
/// not depend on the number of threads) and builds the graph. `camera_ids` and `seconds` are left
/// to the caller (SimulateCalibration fills them).
CalibrationResult EvaluateCalibration(const VisibilityTester& tester, const CalibrationSpec& spec,
                                      const std::vector<CalibrationPose>& poses);

/// SampleCalibrationPoses then EvaluateCalibration for `rig` in `scene`, with `caster` built from
/// scene.AllTriangles() (the fields' ray caster: the scene occludes the target).
CalibrationResult SimulateCalibration(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                      const CalibrationSpec& spec);

/// summary.json's "calibration": target, samples, seed, min_shared, orientation, [board {squares,
/// square_m, tilt_max_deg, min_px_per_square}], poses, poses_observed, poses_shared, cameras (ids),
/// per_camera [{id, enabled, observed, component, missed {tilted, not_in_image, too_small,
/// occluded} (a wand: not_in_image, occluded)}], shared (matrix, rig order), components (lists
/// of ids), uncalibratable (ids), weakest_links [{a, b, shared}] (ids), calibratable, seconds.
/// Every number is a finite integer but board sizes and seconds; a disabled camera's component is
/// null.
void to_json(nlohmann::json& j, const CalibrationResult& result);

/// A few lines for the terminal: the target and poses, the components, the uncalibratable cameras
/// and the three weakest links. Lines end in '\n'.
std::string FormatCalibration(const CalibrationResult& result);

}  // namespace pandora
