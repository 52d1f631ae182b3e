#pragma once
/// \file fiducial.h
/// Printed fiducials in the scene (docs/scene-format.md, "marker" and "board" objects): an ArUco
/// marker, a ChArUco board or a checkerboard printed on a thin sheet that is placed by pose like
/// any object and moves with its group. What a detector reports of them (corner ids and their
/// points) is defined here, without OpenCV; the printed pixels come from OpenCV's own drawing
/// (validation/print.h), which fills Material::printed.
///
/// Pattern frame: the sheet's object frame, origin at the pattern's centre, x to the right and y up
/// as seen from the printed (front) side, z out of the front (a single marker's frame in OpenCV;
/// OpenCV 4.6's ChArUco frame has its origin at the top-left and y down the print). The sheet's
/// back is plain.

#include <cstdint>
#include <string>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora {

struct Scene;
struct SceneObject;

/// One of OpenCV's predefined ArUco / AprilTag dictionaries.
struct ArucoDictionaryInfo {
  const char* name;  ///< OpenCV's enum name, e.g. "DICT_4X4_50".
  int opencv_id;     ///< cv::aruco::PREDEFINED_DICTIONARY_NAME value.
  int bits;          ///< Marker bits per side (the black border adds one cell each side).
  int size;          ///< Markers in the dictionary: ids 0 .. size - 1.
};
/// The dictionary called `name`, or nullptr.
const ArucoDictionaryInfo* FindArucoDictionary(const std::string& name);
/// Every dictionary's name, in OpenCV's order.
std::vector<std::string> ArucoDictionaryNames();

/// A printed fiducial.
struct Fiducial {
  enum class Kind { kMarker, kCharuco, kCheckerboard };
  Kind kind = Kind::kMarker;
  std::string name;        ///< Its object's name.
  int object = -1;         ///< Scene::objects index of its sheet.
  int material = -1;       ///< Scene::materials index of its print.
  std::string dictionary;  ///< ArUco dictionary (empty for a checkerboard).
  int id = 0;              ///< Marker: its id. ChArUco: the first marker's id (OpenCV's order).
  int squares_x = 1, squares_y = 1;  ///< Boards: squares across (x) and up (y).
  /// Marker: the black square's side (its border included), metres. Boards: a square's edge.
  double square_m = 0;
  double marker_m = 0;     ///< ChArUco: a marker's side, metres (< square_m).
  double margin_m = 0;     ///< White margin around the pattern, metres.
  double thickness_m = 0;  ///< The sheet's back lies this far behind its front.

  double PatternWidth() const { return kind == Kind::kMarker ? square_m : squares_x * square_m; }
  double PatternHeight() const { return kind == Kind::kMarker ? square_m : squares_y * square_m; }
  double SheetWidth() const { return PatternWidth() + 2 * margin_m; }
  double SheetHeight() const { return PatternHeight() + 2 * margin_m; }
  /// Markers printed: 1, a ChArUco board's white squares (OpenCV: squares_x * squares_y / 2), 0.
  int Markers() const;
  /// The pattern's size in print texels, whole squares: a marker 12 texels per cell (its bits and
  /// the black border); a ChArUco square the whole number of texels that gives its marker at least
  /// 12 per cell; a checkerboard square 24.
  int PatternTexelsX() const;
  int PatternTexelsY() const;
  /// Texels per metre of the print: PatternTexelsX() / PatternWidth().
  double TexelsPerMetre() const { return PatternTexelsX() / PatternWidth(); }
  /// The margin in whole texels; the reader snaps margin_m to it (a change below half a texel).
  int MarginTexels() const;
};

const char* FiducialKindName(Fiducial::Kind kind);  ///< "marker", "charuco", "checkerboard".

/// A point a detector reports: a marker's corner (id = 4 * marker id + k, k = 0 .. 3 in OpenCV's
/// order: top-left, top-right, bottom-right, bottom-left seen from the front) or a board's inner
/// chessboard corner (id = y * (squares_x - 1) + x, OpenCV's CharucoBoard::chessboardCorners
/// order: x to the right and y down the printed image from its top-left inner corner, as
/// CharucoBoard::draw prints them).
struct FiducialCorner {
  int id = 0;
  Vec2 xy = Vec2::Zero();  ///< In the pattern frame, metres.
};
std::vector<FiducialCorner> FiducialCorners(const Fiducial& fiducial);

/// The sheet's mesh in the pattern frame: the front (2 triangles, normal +z, texture coordinates
/// into a print of `texture_width` x `texture_height` texels whose outermost ring of texels is
/// white) and the back (2 triangles at z = -thickness_m, facing -z, coordinates on that white
/// ring's corner texel). Vertices 0..3 are the front's corners (-x -y, +x -y, +x +y, -x +y).
TriangleMesh FiducialSheet(const Fiducial& fiducial, int texture_width, int texture_height);
/// The print's size in texels: the pattern, the margin each side and a 1-texel white ring.
void FiducialTextureSize(const Fiducial& fiducial, int* width, int* height);

/// Adds `fiducial` to `scene` placed by `world_from_pattern` (an affine map; the scene reader
/// refuses scale): its sheet as a new object named fiducial.name in `group`, its own white
/// material for the print (Material::printed empty), and the fiducial itself with `object` and
/// `material` set. Returns its index in Scene::fiducials.
int AddFiducial(Scene* scene, Fiducial fiducial, const Eigen::Affine3d& world_from_pattern,
                const std::string& group = {});

/// A pattern-frame point of `fiducial` in the world, from its sheet's current front vertices in
/// `scene` (so a moved group's fiducial moves with it: SceneAtSample).
Vec3 FiducialPoint(const Scene& scene, const Fiducial& fiducial, const Vec2& xy);
/// The unit normal of its printed face in the world.
Vec3 FiducialNormal(const Scene& scene, const Fiducial& fiducial);

}  // namespace pandora
