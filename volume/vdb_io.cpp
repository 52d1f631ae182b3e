#include "volume/vdb_io.h"

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <cstdio>
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
  const std::string name = grid.getName();
  std::string units, meaning;
  if (name == kCoverageGrid) {
    units = "cameras";
    meaning = "number of cameras that see the voxel centre";
  } else if (name == kCamerasGrid) {
    units = "bitmask";
    meaning = "bit c set when camera c (rig order, see rig metadata) sees the voxel centre";
  } else if (name == kResolutionGrid) {
    units = "px/m";
    meaning = "best pixel density among the cameras that see the voxel (det(J J^T)^(1/4))";
  }
  grid.insertMeta("value_units", openvdb::StringMetadata(units));
  grid.insertMeta("description", openvdb::StringMetadata(meaning));
}

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
    openvdb::io::File file(tmp);
    file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    file.write(grids, file_meta);
    file.close();
  } catch (const openvdb::Exception& e) {
    std::remove(tmp.c_str());
    throw InputError(path, "", std::string("cannot write the VDB file: ") + e.what(),
                     "check that the output folder exists and is writable");
  }
  CommitTemporary(path);
}

}  // namespace pandora
