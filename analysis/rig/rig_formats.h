#pragma once
/// \file rig_formats.h
/// A rig in other tools' formats (issue 14, "Pandora in the user's tool chain";
/// docs/tool-chain.md):
///  - OpenCV FileStorage YAML (written and read: a small strict reader for the layouts below),
///  - a COLMAP text model (cameras.txt, images.txt, points3D.txt; written and read),
///  - glTF 2 (the scene's meshes and one camera node per camera; written),
///  - an installation sheet (CSV; written).
/// Frames: Pandora's camera frame is OpenCV's (x right, y down, z forward), so R and T here are
/// OpenCV's world -> camera transform, metres. Readers throw InputError naming the file, the line
/// and field, and the reason; every value they return is finite and within the scene file's limits.

#include <string>

#include "analysis/scene/scene.h"

namespace pandora {

/// The rig as one OpenCV FileStorage YAML document ("%YAML:1.0"): `rig` (name), `camera_count`, and
/// `cameras`, a sequence of maps with id, name, image_width, image_height, camera_matrix (3x3),
/// distortion_model ("pinhole", "brown_conrady", "fisheye"), distortion_coefficients (1x5
/// k1 k2 p1 p2 k3; 1x4 k1..k4 for fisheye; zeros for pinhole), R (3x3, world -> camera) and T
/// (3x1, metres). Numbers with 17 significant digits (round trip exact). Throws InputError when an
/// id holds a control character other than tab or newline.
std::string RigToOpenCvYaml(const Rig& rig);

/// Reads a rig from OpenCV FileStorage YAML: the layout RigToOpenCvYaml writes, or one camera as
/// calibration tools write it (top-level camera_matrix, distortion_coefficients, image_width,
/// image_height, and its pose as R (3x3) or rvec (3x1 Rodrigues) with T or tvec; its id is the file
/// name without extension). Aliases: K / cameraMatrix for camera_matrix, D / dist_coeffs /
/// distCoeffs for distortion_coefficients. Distortion vectors of 4 (k1 k2 p1 p2) or 5 coefficients,
/// or 8, 12 or 14 whose extra (rational, thin-prism, tilt) terms are zero; with distortion_model
/// "fisheye" exactly 4. Matrices dt d or f. `path` names the file in messages; the rig's name is
/// the file's `rig` or the file name.
Rig ParseOpenCvYaml(const std::string& text, const std::string& path);

/// A COLMAP text model.
struct ColmapText {
  std::string cameras, images, points3d;
};

/// The rig as a COLMAP text model: one camera (CAMERA_ID 1..N: PINHOLE, OPENCV, FULL_OPENCV when
/// k3 != 0, or OPENCV_FISHEYE) and one image (IMAGE_ID 1..N, world -> camera QW QX QY QZ TX TY TZ,
/// NAME = the id percent-encoded + ".png", an empty POINTS2D line) per Pandora camera; points3D
/// empty. COLMAP's principal point is Pandora's + 0.5 (COLMAP puts the centre of the top-left
/// pixel at (0.5, 0.5), Pandora and OpenCV at (0, 0)).
ColmapText RigToColmap(const Rig& rig);
/// The image NAME RigToColmap gives `camera`: its id percent-encoded (letters, digits, - _ . kept)
/// + ".png"; `pandora synth` names its images so.
std::string ColmapImageName(const Camera& camera);

/// Reads cameras.txt and images.txt of a COLMAP text model: one Pandora camera per image, its id
/// the image NAME percent-decoded without its image extension. Camera models SIMPLE_PINHOLE,
/// PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV (k4..k6 zero) and OPENCV_FISHEYE.
Rig ParseColmap(const std::string& cameras_text, const std::string& cameras_path,
                const std::string& images_text, const std::string& images_path,
                const std::string& rig_name);

/// The scene's meshes (one node and mesh per object, its material's colour as baseColorFactor)
/// and one perspective camera node per camera of `rig`, named by its id, as a .gltf JSON document
/// with the buffer embedded (base64). glTF is Y up: world (x, y, z) -> (x, z, -y); a glTF camera
/// looks down its -Z with +Y up. yfov = 2 atan(h / (2 fy)), aspectRatio = (w fy) / (h fx),
/// znear = the camera's near (0.01 m when 0), zfar its far when finite. With `binary`, the same as
/// one .glb file (JSON chunk and BIN chunk).
std::string SceneToGltf(const Scene& scene, const Rig& rig, bool binary = false);

/// The installation sheet as CSV, one row per camera (docs/tool-chain.md): id, name, colour
/// (#rrggbb), mount point in cm, pan/tilt/roll in degrees (the scene file's euler_deg yaw, pitch,
/// roll), hfov/vfov (degrees, nominal, without distortion), focal lengths (px), lens model,
/// resolution, enabled.
std::string RigToSheetCsv(const Rig& rig);

}  // namespace pandora
