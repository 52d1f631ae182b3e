#pragma once
/// \file overlay_fields.h
/// Internal to render/: what the renderer needs from the OpenVDB fields, without OpenVDB in the
/// header (overlay_fields.cpp is the only render file that includes OpenVDB).

#include <string>
#include <vector>

#include "analysis/geometry.h"

namespace pandora {

class Fields;

/// A field sampled on an axis-aligned plane at the voxel spacing: value of the voxel containing
/// each point (nearest voxel centre, the cells a voxel grid holds), NaN where the voxel is inactive.
struct SliceImage {
  int axis = 2;         ///< The plane is perpendicular to this axis.
  double position = 0;  ///< Coordinate along `axis`.
  int u_axis = 0, v_axis = 1;
  double u0 = 0, v0 = 0;  ///< World coordinate of cell (0, 0)'s lower corner along u_axis, v_axis.
  double spacing = 0;
  int nu = 0, nv = 0;
  std::vector<float> values;   ///< nu * nv, index iv * nu + iu.
  double min = 0, max = 0;     ///< Range of the finite values (0, 0 when none).

  /// The value at world point p on the plane; NaN outside the slice or where inactive.
  double Sample(const Vec3& p) const;
};

/// Samples field `name` on the plane axis = position (NaN: the middle of the fields' lattice).
/// Throws InputError (file "--slice") when the fields lack that grid.
SliceImage SampleSlice(const Fields& fields, const std::string& name, int axis, double position);

/// The isosurface value = `iso` of field `name` (OpenVDB volumeToMesh, triangles and split quads),
/// world coordinates. Inactive voxels count as outside the set {value >= iso} for coverage-like
/// fields and as outside {value <= iso} for uncertainty fields (sigma_*, condition), i.e. they never
/// pass. Throws InputError (file "--iso") when the fields lack that grid.
TriangleMesh ExtractIsosurface(const Fields& fields, const std::string& name, double iso);

}  // namespace pandora
