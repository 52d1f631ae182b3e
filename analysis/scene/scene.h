#pragma once
/// \file scene.h
/// The scene file: geometry (meshes and primitives), rigs of cameras, and the study (region, voxel
/// size, fields). The full format reference is docs/scene-format.md.

#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/geometry.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/scene/calibration_spec.h"
#include "analysis/scene/fiducial.h"
#include "analysis/scene/motion.h"
#include "analysis/scene/skinning.h"

namespace pandora {

/// A printed pattern's pixels (a fiducial's print, analysis/scene/fiducial.h): grey levels, 0 ink
/// to 255 paper, row 0 at the top seen from the printed side. Taken as reflectance (255 = the
/// material's colour).
struct PrintedPattern {
  int width = 0, height = 0;
  std::vector<std::uint8_t> grey;
};

/// Surface appearance, kept for rendering.
struct Material {
  std::string name;
  Vec3 color{0.7, 0.7, 0.7};  ///< Linear RGB diffuse colour in [0, 1].
  /// Path of a diffuse texture (resolved against the scene file's folder, or the mesh file's folder
  /// for materials read from mesh files), empty when none.
  std::string texture;
  /// A fiducial's print (validation/print.h fills it; null until then: the sheet shows `color`).
  /// Takes the place of `texture`.
  std::shared_ptr<const PrintedPattern> printed;
};

/// One object of the scene after its instance transform: world coordinates, metres.
struct SceneObject {
  /// The object's name; "object/material" for each part of a mesh file with several materials.
  std::string name;
  std::string source;  ///< "box", "sphere", ..., or the mesh file path as written in the scene.
  TriangleMesh mesh;   ///< World coordinates.
  int material = -1;   ///< Index into Scene::materials, -1 for the default.
  bool solid =
      false;  ///< Closed (checked on load); its inside is filled: voxels there stay inactive.
  /// The moving group it belongs to ("group" in the file; empty: none). A motion named after the
  /// group, or after the object itself, moves it (analysis/scene/motion.h).
  std::string group;
  /// Index into Scene::skins when the object plays a skinned animation ("animation"); else -1.
  int skin = -1;
  /// For a part of a "person": its capsule's axis ends (world frame as placed) and the radius of
  /// the capsule its tessellation surely contains, so that target points inside another part of
  /// the same body are not taken for skin (analysis/scene/surface_targets.cpp).
  struct CapsuleAxis {
    Vec3 a, b;
    double radius = 0;
  };
  std::optional<CapsuleAxis> capsule;

  /// True when a motion or a target named `n` takes this object: its group, its own name, or the
  /// part before the '/' of a mesh file's part ("patient/torso" belongs to "patient").
  bool InGroup(const std::string& n) const {
    return group == n || name == n || name.rfind(n + "/", 0) == 0;
  }
};

/// A named set of cameras.
struct Rig {
  std::string name;
  std::vector<Camera> cameras;

  int enabled_count() const {
    int n = 0;
    for (const Camera& c : cameras) n += c.enabled ? 1 : 0;
    return n;
  }
  /// Index in `cameras` of the camera with id `id`, or -1 when there is none (ids are unique in a
  /// loaded rig; otherwise the first match).
  int FindCamera(const std::string& id) const {
    for (std::size_t c = 0; c < cameras.size(); ++c)
      if (cameras[c].id == id) return static_cast<int>(c);
    return -1;
  }
  /// The camera ids in rig order, comma-separated ("c0, c1, c2"), for the hint of an error about an
  /// unknown id.
  std::string CameraIds() const {
    std::string ids;
    for (const Camera& c : cameras) ids += (ids.empty() ? "" : ", ") + c.id;
    return ids;
  }
};

/// The region of interest: a box, or a closed mesh (voxels whose centre is inside it).
struct Region {
  enum class Kind { kBox, kMesh };
  Kind kind = Kind::kBox;
  Aabb box;           ///< The box, or the bounds of the mesh.
  TriangleMesh mesh;  ///< Closed mesh when kind == kMesh.
  std::string
      file;  ///< The mesh file (resolved against the scene file's folder) when kind == kMesh.
};

/// Surface targets ("study": {"targets": ...}): points spread over named objects' surfaces
/// (analysis/scene/surface_targets.h).
struct SurfaceTargets {
  std::vector<std::string> names;  ///< Groups or objects, in file order.
  int points = 2000;               ///< Points per target.
  std::uint64_t seed = 1;
};

/// A pixel-size target ("study": {"pixel_targets": [...]}): an object of `size_m` metres must span
/// at least `min_px` pixels (a 14 mm marker over 4 px, a face over 80 px), i.e. a camera's pixel
/// density at the point must be at least min_px / size_m px/m (volume/pixel_targets.h).
struct PixelTarget {
  std::string name;
  double size_m = 0.014;
  double min_px = 4;
  double px_per_m() const { return min_px / size_m; }
};

/// The PTZ fields' settings ("study": {"ptz": ...}; volume/ptz_fields.h, docs/ptz.md).
struct PtzStudy {
  /// A PTZ camera sees a point only at a zoom meeting this density, px/m (0: any zoom). Default:
  /// the study's first pixel target.
  double min_px_per_m = 0;
  std::string pixel_target;                   ///< Its name when it came from a pixel target.
  std::vector<double> within_s{1, 2, 5, 10};  ///< Budgets for the shares reachable within them.
};

/// What to compute and where.
struct Study {
  Region region;
  double voxel_size = 0.05;  ///< Metres.
  std::vector<std::string> fields{"coverage", "cameras", "resolution"};
  double pixel_sigma =
      0.5;  ///< Pixel noise 1-sigma, pixels, for cameras that do not set their own.
  /// Motion model for the steady-state fields ("*_steady"); none when the file has no "motion".
  std::optional<MotionModel> motion;
  /// Steady-state fields report the prior (predicted, before a frame's update) covariance instead
  /// of the posterior (after it); "covariance": "prior" in the file.
  bool steady_prior = false;
  /// Target worst-direction 1-sigma (mm); summary.json reports the share of the region meeting it.
  std::optional<double> max_sigma_mm;
  /// Refuse regions whose grids would exceed this. The file gives it in MiB ("memory_budget_mb",
  /// default 4096); stored in bytes.
  double memory_budget_bytes = 4096.0 * 1024.0 * 1024.0;
  /// The time axis for moving objects ("time"); unset: inferred from the motions
  /// (Scene::TimeSamples).
  std::optional<TimeStudy> time;
  /// Surface targets; unset: none.
  std::optional<SurfaceTargets> targets;
  /// Named sub-regions ("regions"), each summarised from the same fields (its free voxels: centres
  /// inside it and inside the study region), in file order.
  std::vector<std::pair<std::string, Region>> regions;
  /// Pixel-size targets, in file order (at most 16).
  std::vector<PixelTarget> pixel_targets;
  /// Surveillance DORI classes (EN 62676-4: detection 25, observation 62.5, recognition 125,
  /// identification 250 px/m of the best camera) as a field and summary ("dori": true).
  bool dori = false;
  PtzStudy ptz;
  /// Calibration feasibility to simulate ("calibration", docs/calibration.md); none when absent.
  std::optional<CalibrationSpec> calibration;
};

/// Every field name a study may ask for, in output order:
/// coverage, cameras, resolution, sigma_max, sigma_mean, triangulation_angle, condition,
/// sigma_max_steady, sigma_mean_steady. docs/fields.md defines each.
const std::vector<std::string>& FieldNames();

/// True for the fields that need the triangulation uncertainty (all but the first three).
bool IsUncertaintyField(const std::string& name);

/// The first problem with a list of field names, wherever it came from (scene file, command line,
/// library caller): an unknown name (the hint suggests the closest), a name listed twice, or a
/// steady-state field without a motion model. `index` is the offending entry.
struct FieldListProblem {
  std::size_t index = 0;
  std::string reason, hint;
};
std::optional<FieldListProblem> CheckFieldList(const std::vector<std::string>& fields,
                                               bool has_motion);

/// Throws InputError(file, json_path, ...) when a memory budget of `mib` MiB is more than this
/// machine's physical memory: a budget the machine cannot honour would end in an allocation failure
/// after minutes of work. For a command-line option, `file` is the option and `json_path` empty.
void CheckMemoryBudget(double mib, const std::string& file, const std::string& json_path);

/// A named viewpoint for rendering ("views" in the scene file). World frame, metres.
struct View {
  Vec3 from = Vec3::Zero();  ///< Eye position.
  Vec3 at = Vec3::UnitX();   ///< Point looked at (differs from `from`).
  Vec3 up = Vec3::UnitZ();   ///< Up direction (not parallel to at - from).
  /// Horizontal field of view in degrees, in (0, 180); unset means the renderer's default.
  std::optional<double> fov_deg;
};

/// A viewing station (the Pandora paper's Section 5): a flat display placed in the scene that shows
/// the scene as a viewer's eye would see it through the display (a head-tracked window), and
/// optionally a head tracker with its angular range. The display's image is an off-axis perspective
/// from `eye` through the display rectangle (viewer/core/station.h).
struct ViewingStation {
  Vec3 display_center = Vec3::Zero();
  Vec3 display_normal = Vec3::UnitX();  ///< Unit; points to the side the viewer stands on.
  Vec3 display_up = Vec3::UnitZ();      ///< Unit, in the display's plane.
  double display_width = 0.5, display_height = 0.3;  ///< Metres.
  int pixels_wide = 640, pixels_high = 384;          ///< The simulated display image.
  Vec3 eye = Vec3::Zero();                           ///< The viewer's eye, in front of the display.
  /// The head tracker (world_from_tracker: z along its axis, y down as a camera), its full
  /// angular range and working distances; absent when `has_tracker` is false.
  bool has_tracker = false;
  Eigen::Isometry3d tracker_pose = Eigen::Isometry3d::Identity();
  double tracker_hfov_deg = 0, tracker_vfov_deg = 0, tracker_near = 0, tracker_far = 0;
};

/// Limits on coordinates and lengths, checked when a scene is loaded and on every length given as
/// an option (docs/robustness.md). Embree casts rays in single precision, and OpenVDB indexes
/// voxels with 32-bit integers: beyond these a finite number can still abort a library or mean
/// nothing.
struct SceneLimits {
  /// Metres: any coordinate, object extent or length in a scene file (a camera's far range aside).
  static constexpr double kMaxCoordinate = 1e7;
  /// Cameras, viewpoints and lengths given as options stay within this many times the diagonal of
  /// the scene's geometry and region of that content's centre (Scene::MaxReach()). At that
  /// distance a float ray's rounding is about 1e-3 of the scene's size.
  static constexpr double kReach = 1e4;
  /// Cameras in one rig: large surveillance sites and mocap stages use 100-1000; the fields file
  /// holds one grid per camera.
  static constexpr int kMaxCameras = 10000;
};

/// A loaded, validated scene file.
struct Scene {
  std::string path;    ///< As given on the command line.
  std::string sha256;  ///< Hex SHA-256 of the file's bytes.
  std::vector<Material> materials;
  std::vector<SceneObject> objects;
  std::vector<Rig> rigs;  ///< In file order; at least one.
  Study study;
  std::map<std::string, View> views;               ///< Named viewpoints, by name.
  std::map<std::string, ViewingStation> stations;  ///< Viewing stations, by name.
  /// Moving groups ("motions"), in file order; empty for a static scene.
  std::vector<ObjectMotion> motions;
  /// The "person" objects, in file order: name (their parts are "NAME/head", ...), height,
  /// heading as placed (degrees counter-clockwise from +x) and their parts' indices in `objects`.
  struct Person {
    std::string name, pose;
    double height = 0, facing_deg = 0;
    std::vector<int> objects;
  };
  std::vector<Person> people;
  /// Printed fiducials ("marker" and "board" objects), in object order; empty when none.
  std::vector<Fiducial> fiducials;
  /// Objects that play a skinned animation ("animation" on a mesh object), in object order; empty
  /// when none. Their meshes in `objects` are the rest pose (analysis/scene/skinning.h).
  std::vector<SkinnedObject> skins;

  /// True when the scene changes over time: moving groups or skinned animations.
  bool Animated() const { return !motions.empty() || !skins.empty(); }

  /// The study's time samples: each motion's pose at each sample (analysis/scene/motion.h). Empty
  /// for a static scene. Consistent by construction: LoadScene refuses motions the time axis cannot
  /// evaluate (a keyframed motion with pose names, a named-pose motion without a pose asked for).
  std::vector<TimeSample> TimeSamples() const;
  /// The camera count the time summaries count against (study.time.min_cameras, default 3).
  int TimeMinCameras() const { return study.time ? study.time->min_cameras : 3; }

  /// All triangles of all objects, for ray casting. Also returns, per triangle, its object index.
  TriangleMesh AllTriangles(std::vector<int>* triangle_object = nullptr) const;
  /// Bounds of geometry, cameras of every rig, and the region.
  Aabb Bounds() const;
  /// Bounds of the geometry and the region (no cameras): what the scene is about.
  Aabb ContentBounds() const;
  /// SceneLimits::kReach times the diagonal of ContentBounds(), metres (infinity when it is empty).
  double MaxReach() const;
  /// Throws InputError(option, "", ...) when `point` lies farther than MaxReach() from the centre
  /// of ContentBounds(). `what` names the point in the message ("the eye").
  void CheckReach(const Vec3& point, const std::string& option, const std::string& what) const;
  /// Throws InputError(option, "", ...) when `metres` is not finite or its magnitude exceeds
  /// MaxReach(). `what` names the length in the message ("the move").
  void CheckLength(double metres, const std::string& option, const std::string& what) const;
  /// Every file the scene was read from, as (path, kind) pairs: the scene file ("scene file"), its
  /// mesh files and region mesh ("mesh file") and textures ("texture"). Outputs must not replace
  /// any.
  std::vector<std::pair<std::string, std::string>> InputFiles() const;
  /// The rig called `name`, or the first rig when `name` is empty. Throws InputError (path
  /// "$.rigs") naming the available rigs when there is none of that name.
  const Rig& FindRig(const std::string& name) const;
};

/// The scene at one time sample: every skinned object in its pose at the sample
/// (ObjectVerticesAt), every moving group's objects transformed by its pose (their meshes, hence
/// AllTriangles(), ContentBounds() and solids, follow); no motions or skins left (a static scene).
/// Rigs, study, views and stations are those of `scene`.
Scene SceneAtSample(const Scene& scene, const TimeSample& sample);

/// Options for LoadScene.
struct LoadOptions {
  /// When false, mesh files are not read (objects keep empty meshes, one object per mesh entry; a
  /// mesh region keeps an empty mesh and box); used by tools that only need the cameras.
  bool load_meshes = true;
};

/// Reads and validates a scene file. Throws InputError naming the file, the JSON path of the first
/// bad field, the reason and a hint. Mesh paths are relative to the scene file's folder.
Scene LoadScene(const std::string& path, const LoadOptions& options = {});

/// Parses a scene from JSON text; `path` is used for messages and to resolve relative mesh paths.
Scene ParseScene(const std::string& json_text, const std::string& path,
                 const LoadOptions& options = {});

/// Serializes a rig back to the scene file's JSON form (position + quaternion pose, focal lengths
/// in pixels, distortion by OpenCV names). Used as metadata in outputs and by `pandora accept`.
nlohmann::json RigToJson(const Rig& rig);

/// Reads a rig in the scene file's form (metres; RigToJson's output reads back), e.g. from a
/// viewer's autosave file: the same checks as a rig in a scene file, with errors (InputError)
/// naming `path` and the JSON path below `json_path` (e.g. "$.rig").
Rig ParseRigJson(const nlohmann::json& rig, const std::string& path, const std::string& json_path);

}  // namespace pandora
