#pragma once
/// \file slice.h
/// Axis-aligned slices through evaluated fields: the one slice type of Pandora, for the report's
/// figures (`pandora report`), the renderer's slice overlay (`pandora render --slice`) and the
/// viewer's slice planes.

#include <string>
#include <vector>

#include "volume/fields.h"

namespace pandora {

/// A plane of voxels. Image convention: `width` columns along the first in-plane axis (x for
/// z- and y-slices, y for x-slices), `height` rows along the second (y for z-slices, z otherwise),
/// row 0 at the largest coordinate (the top of a figure).
struct FieldSlice {
  std::string field;
  int axis = 2;           ///< Normal of the plane: 0 x, 1 y, 2 z.
  int index = 0;          ///< Voxel index along `axis`.
  double coordinate = 0;  ///< World coordinate of the plane (voxel centres), m.
  int width = 0, height = 0;
  double u_min = 0, u_max = 0, v_min = 0, v_max = 0;  ///< In-plane extent of the voxel centres, m.
  /// Row-major width * height. `inside`: the voxel is a free region voxel (the coverage grid has it
  /// active). `has_value`: the field grid has it active (seen, or triangulable for uncertainty
  /// fields). `values`: the grid value there, 0 elsewhere.
  std::vector<unsigned char> inside, has_value;
  std::vector<double> values;
  double voxel_size = 0;    ///< The lattice's, m.
  double min = 0, max = 0;  ///< Range of `values` where has_value (0, 0 when none).

  int u_axis() const { return axis == 0 ? 1 : 0; }
  int v_axis() const { return axis == 2 ? 1 : 2; }
  /// The value of the voxel whose cell (the cube of edge voxel_size around its centre) holds the
  /// world point `p` projected along `axis` onto the plane; NaN outside the slice or where the
  /// field has no value.
  double Sample(const Vec3& p) const;
};

/// The slice of grid `field` (a FieldNames() entry that was evaluated) through the voxel plane
/// nearest `coordinate` along `axis`. With `clamp` a plane beyond the lattice is clamped to its
/// first or last plane (a figure always shows something); without, such a slice has no value
/// anywhere (an overlay plane that misses the fields shows nothing). `inside` needs the coverage
/// grid; without it, it equals `has_value`. Throws std::invalid_argument for a field that was not
/// evaluated or an axis other than 0, 1, 2.
FieldSlice SliceField(const Fields& fields, const std::string& field, int axis, double coordinate,
                      bool clamp = true);

}  // namespace pandora
