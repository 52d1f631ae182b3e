#include "volume/slice.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "volume/fields_vdb.h"

namespace pandora {

double FieldSlice::Sample(const Vec3& p) const {
  if (width <= 0 || height <= 0 || !(voxel_size > 0))
    return std::numeric_limits<double>::quiet_NaN();
  const double fu = (p[u_axis()] - u_min) / voxel_size + 0.5,
               fv = (p[v_axis()] - v_min) / voxel_size + 0.5;
  if (!(fu >= 0 && fv >= 0 && fu < width && fv < height))
    return std::numeric_limits<double>::quiet_NaN();
  const std::size_t o = static_cast<std::size_t>(height - 1 - int(fv)) * width + int(fu);
  return has_value[o] ? values[o] : std::numeric_limits<double>::quiet_NaN();
}

FieldSlice SliceField(const Fields& fields, const std::string& field, int axis, double coordinate,
                      bool clamp) {
  if (axis < 0 || axis > 2) throw std::invalid_argument("SliceField: axis must be 0, 1 or 2");
  const Fields::Impl& g = fields.impl();
  if (!g.coverage && field == kCoverageGrid)
    throw std::invalid_argument("SliceField: the coverage grid was not evaluated");
  openvdb::FloatGrid::Ptr float_grid;
  if (field != kCoverageGrid) {
    float_grid = g.Float(field);
    if (!float_grid)
      if (auto it = g.extra.find(field); it != g.extra.end())
        float_grid = it->second;  // a derived grid
    if (!float_grid)
      throw std::invalid_argument("SliceField: field '" + field + "' was not evaluated");
  }
  const VoxelLattice& L = fields.lattice;
  FieldSlice s;
  s.field = field;
  s.axis = axis;
  const int u_axis = s.u_axis();
  const int v_axis = s.v_axis();
  const double h = L.voxel_size;
  s.voxel_size = h;
  const long n_axis = L.dims[axis];
  const double nearest = std::round((coordinate - L.origin[axis]) / h);
  const bool misses = !(nearest >= 0 && nearest <= n_axis - 1);  // NaN misses too
  if (misses && !clamp) {
    s.index = -1;
  } else {
    s.index =
        static_cast<int>(std::clamp<double>(std::isnan(nearest) ? 0 : nearest, 0, n_axis - 1));
  }
  s.coordinate = s.index >= 0 ? L.origin[axis] + h * s.index : coordinate;
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
  if (s.index < 0) return s;  // the plane misses the lattice
  std::optional<openvdb::Int32Grid::ConstAccessor> coverage;
  if (g.coverage) coverage.emplace(g.coverage->getConstAccessor());
  std::optional<openvdb::FloatGrid::ConstAccessor> values;
  if (float_grid) values.emplace(float_grid->getConstAccessor());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int row = 0; row < s.height; ++row)
    for (int col = 0; col < s.width; ++col) {
      openvdb::Coord ijk;
      ijk[axis] = s.index;
      ijk[u_axis] = col;
      ijk[v_axis] = s.height - 1 - row;
      const std::size_t o = static_cast<std::size_t>(row) * s.width + col;
      int cov = 0;
      const bool covered = coverage && coverage->probeValue(ijk, cov);
      if (!float_grid) {
        s.has_value[o] = covered ? 1 : 0;
        s.values[o] = covered ? cov : 0;
      } else {
        float v = 0;
        if (values->probeValue(ijk, v)) {
          s.has_value[o] = 1;
          s.values[o] = v;
        }
      }
      s.inside[o] = coverage ? (covered ? 1 : 0) : s.has_value[o];
      if (s.has_value[o]) {
        lo = std::min(lo, s.values[o]);
        hi = std::max(hi, s.values[o]);
      }
    }
  if (lo <= hi) {
    s.min = lo;
    s.max = hi;
  }
  return s;
}

}  // namespace pandora
