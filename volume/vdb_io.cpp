#include "volume/vdb_io.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <fstream>
#include <cstdio>
#include <map>
#include <mutex>

#include "analysis/atomic_file.h"
#include "analysis/error.h"
#include "volume/fields_vdb.h"

namespace pandora {

void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

namespace {

// Per-grid description: units and meaning, for people reading `vdb_print -l`.
void Describe(openvdb::GridBase& grid) {
  static const std::map<std::string, std::pair<const char*, const char*>> kDescriptions{
      {"coverage", {"cameras", "number of cameras that see the voxel centre"}},
      {"cameras", {"bitmask", "bit c set when camera c (rig order, see rig metadata) sees the voxel centre"}},
      {"resolution", {"px/m", "best pixel density among the cameras that see the voxel (det(J J^T)^(1/4))"}},
      {"sigma_max", {"mm", "worst-direction 1-sigma of the static triangulation covariance"}},
      {"sigma_mean", {"mm", "sqrt(trace/3) of the static triangulation covariance"}},
      {"triangulation_angle", {"deg", "largest angle between two rays that see the voxel"}},
      {"condition", {"1", "condition number of the information matrix J"}},
      {"sigma_max_steady", {"mm", "worst-direction 1-sigma of the steady-state Kalman covariance"}},
      {"sigma_mean_steady", {"mm", "sqrt(trace/3) of the steady-state Kalman covariance"}},
  };
  auto it = kDescriptions.find(grid.getName());
  if (it == kDescriptions.end()) return;
  grid.insertMeta("value_units", openvdb::StringMetadata(it->second.first));
  grid.insertMeta("description", openvdb::StringMetadata(it->second.second));
}

// io::File::write does not check its stream: on a full disk it returns normally over a cut-short
// file. This writes the same archive (seekable, with grid offsets) through a stream it checks.
class CheckedVdbWriter : public openvdb::io::Archive {
 public:
  void Write(const std::string& path, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta) {
    std::ofstream os(path, std::ios::binary | std::ios::trunc);
    if (!os) throw InputError(path, "", "cannot create the VDB file", "check the output folder");
    openvdb::io::Archive::write(os, grids, /*seekable=*/true, meta);
    os.flush();
    const bool ok = static_cast<bool>(os);
    os.close();
    if (!ok || os.fail())
      throw InputError(path, "", "cannot write the VDB file: the disk is full or the write failed",
                       "free some space, then run again");
  }
  openvdb::io::Archive::Ptr copy() const override {
    return openvdb::io::Archive::Ptr(new CheckedVdbWriter(*this));
  }
};

}  // namespace

void WriteFieldsVdb(const Fields& fields, const std::string& path,
                    const std::map<std::string, std::string>& metadata) {
  InitializeOpenVdb();
  openvdb::GridPtrVec grids = fields.impl().Grids();
  openvdb::MetaMap file_meta;
  for (const auto& [key, value] : metadata) file_meta.insertMeta(key, openvdb::StringMetadata(value));
  for (openvdb::GridBase::Ptr& grid : grids) {
    for (const auto& [key, value] : metadata) grid->insertMeta(key, openvdb::StringMetadata(value));
    Describe(*grid);
  }
  const std::string tmp = TemporaryPath(path);
  try {
    CheckedVdbWriter writer;
    writer.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    writer.Write(tmp, grids, file_meta);
  } catch (const openvdb::Exception& e) {
    std::remove(tmp.c_str());
    throw InputError(path, "", std::string("cannot write the VDB file: ") + e.what(),
                     "check that the output folder exists and is writable");
  } catch (const InputError& e) {
    std::remove(tmp.c_str());
    throw InputError(path, "", e.reason(), e.hint());
  }
  CommitTemporary(path);
}

Fields ReadFieldsVdb(const std::string& path) {
  InitializeOpenVdb();
  Fields fields;
  Fields::Impl& g = fields.impl();
  try {
    openvdb::io::File file(path);
    file.open();
    for (auto it = file.beginName(); it != file.endName(); ++it) {
      const std::string name = it.gridName();
      const bool known = std::find(FieldNames().begin(), FieldNames().end(), name) != FieldNames().end();
      if (!known) continue;
      openvdb::GridBase::Ptr base = file.readGrid(name);
      if (name == kCoverageGrid) {
        g.coverage = openvdb::gridPtrCast<openvdb::Int32Grid>(base);
      } else if (name == kCamerasGrid) {
        g.cameras = openvdb::gridPtrCast<openvdb::Int64Grid>(base);
      } else if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(base)) {
        g.floats[name] = f;
      } else {
        continue;  // a known name of an unexpected type: not ours
      }
      if (!g.transform) g.transform = base->transform().copy();
    }
    file.close();
  } catch (const openvdb::Exception& e) {
    throw InputError(path, "", std::string("cannot read the VDB file: ") + e.what(),
                     "pass the fields.vdb that `pandora analyze` wrote");
  } catch (const std::exception& e) {  // a truncated file can fail in the streams or allocation
    throw InputError(path, "", std::string("cannot read the VDB file: ") + e.what(),
                     "pass the fields.vdb that `pandora analyze` wrote");
  }
  const openvdb::GridPtrVec grids = g.Grids();
  if (grids.empty())
    throw InputError(path, "", "the VDB file holds none of Pandora's field grids",
                     "pass the fields.vdb that `pandora analyze` wrote");
  // The lattice: voxel (0, 0, 0) at the transform's origin, extent from the active voxels.
  const double vs = g.transform->voxelSize()[0];
  const openvdb::Vec3d o = g.transform->indexToWorld(openvdb::Vec3d(0, 0, 0));
  fields.lattice.voxel_size = vs;
  fields.lattice.origin = Vec3(o.x(), o.y(), o.z());
  openvdb::CoordBBox box;
  for (const auto& grid : grids) box.expand(grid->evalActiveVoxelBoundingBox());
  if (!box.empty())
    fields.lattice.dims = Eigen::Vector3i(box.max().x() + 1, box.max().y() + 1, box.max().z() + 1);
  return fields;
}

}  // namespace pandora
