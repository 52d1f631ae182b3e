#include "volume/slice.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "volume/fields_vdb.h"

namespace pandora {

FieldSlice SliceField(const Fields& fields, const std::string& field, int axis, double coordinate) {
  if (axis < 0 || axis > 2) throw std::invalid_argument("SliceField: axis must be 0, 1 or 2");
  const Fields::Impl& g = fields.impl();
  if (!g.coverage) throw std::invalid_argument("SliceField: the coverage grid was not evaluated");
  openvdb::FloatGrid::Ptr float_grid;
  if (field != kCoverageGrid) {
    float_grid = g.Float(field);
    if (!float_grid) throw std::invalid_argument("SliceField: field '" + field + "' was not evaluated");
  }
  const VoxelLattice& L = fields.lattice;
  FieldSlice s;
  s.field = field;
  s.axis = axis;
  const int u_axis = axis == 0 ? 1 : 0;
  const int v_axis = axis == 2 ? 1 : 2;
  const double h = L.voxel_size;
  const long n_axis = L.dims[axis];
  s.index = static_cast<int>(
      std::clamp<long>(std::lround((coordinate - L.origin[axis]) / h), 0, n_axis - 1));
  s.coordinate = L.origin[axis] + h * s.index;
  s.width = L.dims[u_axis];
  s.height = L.dims[v_axis];
  s.u_min = L.origin[u_axis];
  s.u_max = L.origin[u_axis] + h * (s.width - 1);
  s.v_min = L.origin[v_axis];
  s.v_max = L.origin[v_axis] + h * (s.height - 1);
  const std::size_t n = static_cast<std::size_t>(s.width) * s.height;
  s.inside.assign(n, 0);
  s.has_value.assign(n, 0);
  s.values.assign(n, 0.0);
  auto coverage = g.coverage->getConstAccessor();
  std::optional<openvdb::FloatGrid::ConstAccessor> values;
  if (float_grid) values.emplace(float_grid->getConstAccessor());
  for (int row = 0; row < s.height; ++row)
    for (int col = 0; col < s.width; ++col) {
      openvdb::Coord ijk;
      ijk[axis] = s.index;
      ijk[u_axis] = col;
      ijk[v_axis] = s.height - 1 - row;
      const std::size_t o = static_cast<std::size_t>(row) * s.width + col;
      int cov = 0;
      s.inside[o] = coverage.probeValue(ijk, cov) ? 1 : 0;
      if (!float_grid) {
        s.has_value[o] = s.inside[o];
        s.values[o] = s.inside[o] ? cov : 0;
      } else {
        float v = 0;
        if (values->probeValue(ijk, v)) {
          s.has_value[o] = 1;
          s.values[o] = v;
        }
      }
    }
  return s;
}

}  // namespace pandora
