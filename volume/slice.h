#pragma once
/// \file slice.h
/// Axis-aligned slices through evaluated fields, for figures (`pandora report`).

#include <string>
#include <vector>

#include "volume/fields.h"

namespace pandora {

/// A plane of voxels. Image convention: `width` columns along the first in-plane axis (x for
/// z- and y-slices, y for x-slices), `height` rows along the second (y for z-slices, z otherwise),
/// row 0 at the largest coordinate (the top of a figure).
struct FieldSlice {
  std::string field;
  int axis = 2;             ///< Normal of the plane: 0 x, 1 y, 2 z.
  int index = 0;            ///< Voxel index along `axis`.
  double coordinate = 0;    ///< World coordinate of the plane (voxel centres), m.
  int width = 0, height = 0;
  double u_min = 0, u_max = 0, v_min = 0, v_max = 0;  ///< In-plane extent of the voxel centres, m.
  /// Row-major width * height. `inside`: the voxel is a free region voxel (the coverage grid has it
  /// active). `has_value`: the field grid has it active (seen, or triangulable for uncertainty
  /// fields). `values`: the grid value there, 0 elsewhere.
  std::vector<unsigned char> inside, has_value;
  std::vector<double> values;
};

/// The slice of grid `field` (a FieldNames() entry that was evaluated; "coverage" must have been
/// evaluated too, for `inside`) through the voxel plane nearest `coordinate` along `axis` (clamped
/// into the lattice). Throws std::invalid_argument for a field that was not evaluated.
FieldSlice SliceField(const Fields& fields, const std::string& field, int axis, double coordinate);

}  // namespace pandora
