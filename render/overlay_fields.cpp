// The only render/ file that includes OpenVDB: slices of the fields and their isosurfaces.
#include "render/overlay_fields.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <cmath>
#include <limits>

#include "analysis/util/error.h"
#include "render/isosurface.h"
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
  if (auto it = g.extra.find(name); it != g.extra.end() && it->second) return fn(*it->second);
  std::string have;
  for (const auto& grid : g.Grids()) {
    if (grid->getName() == kCamerasGrid) continue;  // a bitmask, not a value to colour
    have += (have.empty() ? "" : ", ") + grid->getName();
  }
  for (const auto& [extra, grid] : g.extra) have += (have.empty() ? "" : ", ") + extra;
  throw InputError(
      option, "", "the fields have no grid '" + name + "' to show",
      have.empty() ? std::string("the fields file holds no value grids") : "available: " + have);
}

// Fields whose small values are good (uncertainty); the rest are better when large.
bool LowIsGood(const std::string& name) {
  return name.rfind("sigma_", 0) == 0 || name == "condition" ||
         name.rfind("ptz_reach_time", 0) == 0 || name.rfind("ptz_gap", 0) == 0;
}

}  // namespace

FieldSlice SampleSlice(const Fields& fields, const std::string& name, int axis, double position,
                       double* plane) {
  WithGrid(fields, name, "{slice_field}", [&](const auto& grid) {
    if (std::isfinite(position)) return;
    // The middle plane of the active voxels (of the lattice when there are none).
    const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
    const int k =
        box.empty() ? fields.lattice.dims[axis] / 2 : (box.min()[axis] + box.max()[axis]) / 2;
    position = fields.lattice.origin[axis] + fields.lattice.voxel_size * k;
  });
  *plane = position;
  return SliceField(fields, name, axis, position, false);
}

TriangleMesh ExtractIsosurface(const Fields& fields, const std::string& name, double iso) {
  TriangleMesh mesh;
  const bool low_good = LowIsGood(name);
  WithGrid(fields, name, "{iso_field}", [&](const auto& grid) {
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

TriangleMesh FieldIsosurface(const Fields& fields, const std::string& name, double iso) {
  return ExtractIsosurface(fields, name, iso);
}

}  // namespace pandora
