#pragma once
/// \file rig_check.h
/// Plausibility checks of a rig in its scene: setups that load fine but make no sense (a camera
/// inside a cabinet, outside the room, looking at nothing, or with a lens model that folds back
/// inside the image). They are warnings, never errors: the commands print one line each on stderr
/// (`pandora: warning: FILE: JSON_PATH: REASON`) after all input has been validated, and list them
/// in summary.json and the report. docs/user-guide.md ("Warnings") explains each test.
///
/// Also the lens's effective field of view with distortion, beside the nominal one.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/inside_mesh.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/scene.h"

namespace pandora {

/// One warning about one camera.
struct Warning {
  enum class Kind {
    kInsideSolid,   ///< The camera centre is inside a solid object.
    kOutsideRoom,   ///< The centre lies outside the walls that enclose the region.
    kSeesNoRegion,  ///< The camera sees none of the study region.
    kLensDomain,    ///< The distortion's valid (monotonic) domain ends inside the image.
    kOnSurface,  ///< The centre lies on (within 1 mm of) a surface: its side decides what it sees.
    kImplausible,  ///< A value of the file that is valid but almost surely a mistake (units,
                   ///< radians).
  };
  Kind kind = Kind::kSeesNoRegion;
  std::string camera;     ///< Camera id.
  std::string json_path;  ///< Of the camera (or its key), e.g. "$.rigs[0].cameras[3].position".
  std::string reason;     ///< One line, without the file name.
};

/// "inside_solid", "outside_room", "sees_no_region", "lens_domain".
const char* WarningKindName(Warning::Kind kind);

/// `FILE: JSON_PATH: REASON`, the form printed after "pandora: warning: ".
std::string FormatWarning(const std::string& file, const Warning& warning);

/// A lens's field of view, nominal and with distortion, and the part of the image it cannot reach.
struct LensCoverage {
  /// Nominal (HfovFromFocal: the pinhole angle for pinhole and Brown-Conrady lenses, the
  /// equidistant one for fisheye), distortion ignored; degrees, edge to edge of the image.
  double nominal_hfov_deg = 0, nominal_vfov_deg = 0;
  /// With distortion: the angle between the rays through the two ends of the image row (column)
  /// through the principal point, edge to edge (pixel edges -0.5 and width - 0.5), in degrees. The
  /// two half-angles from the optical axis are added when the principal point lies inside the image
  /// (so a fisheye over 180 degrees is reported as such). Where an end lies beyond the image of the
  /// lens's valid domain the last reachable point of that row (column) stands in for it.
  double hfov_deg = 0, vfov_deg = 0;
  /// Share of the image area (pixels) that no ray reaches: outside the image of the distortion's
  /// monotonic domain (CameraModel::Unproject fails there). 0 for a pinhole lens.
  double unreachable_fraction = 0;
  /// Some corner pixel is unreachable: the domain ends inside the image.
  bool domain_ends_inside_image = false;
};

/// Computes LensCoverage. The unreachable share is integrated row by row (up to 1024 rows, each
/// reachable interval found by bisection to 1e-3 pixel from the principal point's column outward;
/// the domain's image is star-shaped around the principal point), so it is exact to about 0.1 % of
/// the image for the radial models.
LensCoverage ComputeLensCoverage(const CameraModel& model);

struct RigCheckOptions {
  /// Region voxels each rig camera sees, from the volume fields (FieldStats::per_camera_seen, in
  /// rig order), for an exact "sees none of the region" test; empty: judged on sample points.
  std::vector<std::int64_t> visible_voxels;
  /// Sample points of the region per axis (a lattice of cell centres; mesh regions keep the points
  /// inside, and points inside solids are dropped).
  int region_samples_per_axis = 16;
  /// Point-in-solid trees built already (a study's, volume/solid_trees.h): the tree of
  /// scene.objects[object], and of the region's mesh; nullptr (or no function): CheckRig builds
  /// its own where it needs one (a CGAL AABB tree of the object's triangles).
  std::function<const InsideMesh*(std::size_t object)> object_tree;
  std::function<const InsideMesh*()> region_tree;
};

/// Checks every enabled camera of `rig` (which must be one of scene.rigs, for the JSON paths) and
/// returns the warnings in rig order. `caster` must be built from scene.AllTriangles(). Per camera:
///  - inside a solid object (the loader's closed meshes; InsideMesh): strictly inside, a centre on
///    the surface (within 1e-6 of the scene's size) does not count;
///  - outside the room: only where the scene encloses the region (all 16 horizontal rays from the
///    free region sample nearest the region's centre, the reference point, hit geometry: walls), a
///    camera is outside when its centre lies outside the bounding box of all objects' triangles, or
///    when the segment from the reference point to the camera crosses a surface, the ray goes on
///    beyond the camera without meeting anything (the camera is past the last wall in that
///    direction; a camera behind a pillar inside the room has the room's wall behind it), and no
///    line of sight from the camera to a region sample is free;
///  - sees none of the region (from `options.visible_voxels` when given, else from the samples),
///    with the commonest reason among the samples (outside the image, behind it, out of range,
///    blocked by an object);
///  - the lens's valid domain ends inside the image (ComputeLensCoverage), with the unreachable
///    share of the pixels.
/// Before the cameras, values of the file that are valid but almost surely mistakes (kImplausible):
/// a scene (geometry, region and cameras) under 0.5 m or over 20 km on its longest side (units: a
/// file in metres read as cm), a field of view under 3.2 degrees (radians written as degrees), a
/// named region that does not meet the study region, a pixel target over 2 m (a marker), a moving
/// group that leaves the study region at a time sample or whose centre passes through a still solid
/// between two keyframed samples. The placement warnings are the most specific: a camera inside a
/// solid or outside the room gets no "sees none" warning on top. Never throws for a valid scene;
/// cheap (a few thousand segments per camera).
std::vector<Warning> CheckRig(const Scene& scene, const Rig& rig, const RayCaster& caster,
                              const RigCheckOptions& options = {});

}  // namespace pandora
