#pragma once
/// \file fields_vdb.h
/// The OpenVDB grids behind Fields. Include only where OpenVDB is needed (volume/, a few render
/// files, tests): it pulls in OpenVDB's headers.

#include <openvdb/openvdb.h>

#include <map>
#include <string>
#include <vector>

#include "volume/fields.h"
#include "volume/leaf_spill.h"

namespace pandora {

/// Grid names as written to fields.vdb (the float fields are named as in FieldNames()).
inline constexpr const char* kCoverageGrid = "coverage";
inline constexpr const char* kCamerasGrid = "cameras";

struct Fields::Impl {
  openvdb::math::Transform::Ptr transform;
  openvdb::Int32Grid::Ptr coverage;  ///< Null unless requested.
  /// With the "cameras" field: per camera of the rig (index c), the voxels it sees (active, true).
  /// Empty when the field was not requested.
  std::vector<openvdb::BoolGrid::Ptr> visible;
  /// resolution, sigma_max, ...: the requested float fields by name.
  std::map<std::string, openvdb::FloatGrid::Ptr> floats;
  /// Grids beyond FieldNames(), written to fields.vdb after the others by name (the fields over
  /// time: "coverage_min", "coverage_time_share"; volume/time_fields.h; "coverage_n1"; the PTZ
  /// grids). Read back as they are (float grids with the fields' transform) for slices and
  /// isosurfaces.
  std::map<std::string, openvdb::FloatGrid::Ptr> extra;
  /// The float fields of FieldOptions::spilled_fields, by name: their leaves are in temporary
  /// files until WriteFieldsVdb reads them back (not in `floats`: Float() does not find them).
  std::map<std::string, SpilledGrid> spilled;

  /// The float grid `name`, or null when it was not requested.
  openvdb::FloatGrid::Ptr Float(const std::string& name) const {
    auto it = floats.find(name);
    return it == floats.end() ? nullptr : it->second;
  }

  /// Whether float field `name` was evaluated: held in `floats` or spilled.
  bool Has(const std::string& name) const { return floats.count(name) || spilled.count(name); }
  /// The float grid `name` for reading: the held one, or a spilled one read back from its file (a
  /// new grid at each call: hold it only while it is read); null when it was not evaluated. The
  /// analyses `pandora analyze` runs after the evaluation read their grids through this, one at a
  /// time.
  openvdb::FloatGrid::Ptr Load(const std::string& name) const {
    if (openvdb::FloatGrid::Ptr grid = Float(name)) return grid;
    auto it = spilled.find(name);
    return it == spilled.end() ? nullptr : it->second.Read();
  }

  /// The non-null field grids (not the per-camera ones), in FieldNames() order.
  openvdb::GridPtrVec Grids() const {
    openvdb::GridPtrVec grids;
    if (coverage) grids.push_back(coverage);
    for (const std::string& name : FieldNames())
      if (auto g = Float(name)) grids.push_back(g);
    return grids;
  }
};

/// Calls fn(coord, value) for every active voxel of `grid`, the voxels of an active tile one by one
/// (the coverage grid stores culled blocks as tiles).
template <typename Grid, typename Fn>
void ForEachActiveVoxel(const Grid& grid, Fn&& fn) {
  for (auto it = grid.cbeginValueOn(); it; ++it) {
    if (it.isVoxelValue()) {
      fn(it.getCoord(), *it);
      continue;
    }
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    for (auto c = box.begin(); c; ++c) fn(*c, *it);
  }
}

}  // namespace pandora
