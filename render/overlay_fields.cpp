// The only render/ file that includes OpenVDB: slices of the fields and their isosurfaces.
#include "render/overlay_fields.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <limits>

#include "analysis/error.h"
#include "volume/fields_vdb.h"
#include "volume/vdb_io.h"

namespace pandora {
namespace {

// Calls fn(grid) with the typed grid called `name`; throws InputError(option) when missing.
template <typename Fn>
void WithGrid(const Fields& fields, const std::string& name, const char* option, Fn&& fn) {
  const Fields::Impl& g = fields.impl();
  if (name == kCoverageGrid && g.coverage) return fn(*g.coverage);
  if (auto f = g.Float(name)) return fn(*f);
  std::string have;
  for (const auto& grid : g.Grids()) {
    if (grid->getName() == kCamerasGrid) continue;  // a bitmask, not a value to colour
    have += (have.empty() ? "" : ", ") + grid->getName();
  }
  throw InputError(option, "", "the fields have no grid '" + name + "' to show",
                   have.empty() ? std::string("the fields file holds no value grids")
                                : "available: " + have);
}

// Fields whose small values are good (uncertainty); the rest are better when large.
bool LowIsGood(const std::string& name) {
  return name.rfind("sigma_", 0) == 0 || name == "condition";
}

}  // namespace

double SliceImage::Sample(const Vec3& p) const {
  if (nu <= 0 || nv <= 0 || !(spacing > 0)) return std::numeric_limits<double>::quiet_NaN();
  const double fu = (p[u_axis] - u0) / spacing, fv = (p[v_axis] - v0) / spacing;
  if (!(fu >= 0 && fv >= 0 && fu < nu && fv < nv)) return std::numeric_limits<double>::quiet_NaN();
  return values[std::size_t(int(fv)) * nu + int(fu)];
}

SliceImage SampleSlice(const Fields& fields, const std::string& name, int axis, double position) {
  SliceImage s;
  WithGrid(fields, name, "--slice", [&](const auto& grid) {
    const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
    const openvdb::math::Transform& xf = grid.transform();
    const double vs = xf.voxelSize()[0];
    const openvdb::Vec3d o = xf.indexToWorld(openvdb::Vec3d(0, 0, 0));
    const Vec3 origin(o.x(), o.y(), o.z());
    s.axis = axis;
    s.u_axis = (axis + 1) % 3;
    s.v_axis = (axis + 2) % 3;
    s.spacing = vs;
    if (box.empty()) return;
    const int lo = box.min()[axis], hi = box.max()[axis];
    int k = (lo + hi) / 2;
    if (std::isfinite(position)) k = int(std::lround((position - origin[axis]) / vs));
    s.position = std::isfinite(position) ? position : origin[axis] + vs * k;
    const int u_lo = box.min()[s.u_axis], v_lo = box.min()[s.v_axis];
    s.nu = box.max()[s.u_axis] - u_lo + 1;
    s.nv = box.max()[s.v_axis] - v_lo + 1;
    s.u0 = origin[s.u_axis] + vs * (u_lo - 0.5);
    s.v0 = origin[s.v_axis] + vs * (v_lo - 0.5);
    s.values.assign(std::size_t(s.nu) * s.nv, std::numeric_limits<float>::quiet_NaN());
    if (k < lo || k > hi) return;  // the plane misses the fields: an empty slice
    auto acc = grid.getConstAccessor();
    double mn = std::numeric_limits<double>::infinity(), mx = -mn;
    for (int iv = 0; iv < s.nv; ++iv)
      for (int iu = 0; iu < s.nu; ++iu) {
        openvdb::Coord c;
        c[axis] = k;
        c[s.u_axis] = u_lo + iu;
        c[s.v_axis] = v_lo + iv;
        typename std::decay_t<decltype(grid)>::ValueType v;
        if (!acc.probeValue(c, v)) continue;
        const double d = double(v);
        s.values[std::size_t(iv) * s.nu + iu] = float(d);
        mn = std::min(mn, d);
        mx = std::max(mx, d);
      }
    if (mn <= mx) {
      s.min = mn;
      s.max = mx;
    }
  });
  return s;
}

TriangleMesh ExtractIsosurface(const Fields& fields, const std::string& name, double iso) {
  TriangleMesh mesh;
  const bool low_good = LowIsGood(name);
  WithGrid(fields, name, "--iso", [&](const auto& grid) {
    // A float copy in which the set {good} is {value > level}; inactive voxels are well outside.
    const double level = low_good ? -iso : iso;
    const float outside = float(level - std::max(1.0, std::abs(level)));
    openvdb::FloatGrid::Ptr f = openvdb::FloatGrid::create(outside);
    f->setTransform(grid.transform().copy());
    // Tiles first (fill), then voxels through an accessor (fill would invalidate its cache).
    for (auto it = grid.cbeginValueOn(); it; ++it)
      if (!it.isVoxelValue())
        f->fill(it.getBoundingBox(), float(low_good ? -double(*it) : double(*it)), true);
    {
      auto acc = f->getAccessor();
      for (auto it = grid.cbeginValueOn(); it; ++it)
        if (it.isVoxelValue())
          acc.setValueOn(it.getCoord(), float(low_good ? -double(*it) : double(*it)));
    }
    f->tree().voxelizeActiveTiles();
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*f, points, triangles, quads, level, 0.0, true);
    mesh.vertices.reserve(points.size());
    for (const auto& p : points) mesh.vertices.emplace_back(p.x(), p.y(), p.z());
    for (const auto& t : triangles) mesh.triangles.emplace_back(int(t[0]), int(t[1]), int(t[2]));
    for (const auto& q : quads) {
      mesh.triangles.emplace_back(int(q[0]), int(q[1]), int(q[2]));
      mesh.triangles.emplace_back(int(q[0]), int(q[2]), int(q[3]));
    }
  });
  return mesh;
}

}  // namespace pandora
