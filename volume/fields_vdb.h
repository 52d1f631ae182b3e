#pragma once
/// \file fields_vdb.h
/// The OpenVDB grids behind Fields. Include only where OpenVDB is needed (volume/, a few render
/// files, tests): it pulls in OpenVDB's headers.

#include <openvdb/openvdb.h>

#include "volume/fields.h"

namespace pandora {

/// Grid names as written to fields.vdb.
inline constexpr const char* kCoverageGrid = "coverage";
inline constexpr const char* kCamerasGrid = "cameras";
inline constexpr const char* kResolutionGrid = "resolution";

struct Fields::Impl {
  openvdb::math::Transform::Ptr transform;
  openvdb::Int32Grid::Ptr coverage;    ///< Null unless requested.
  openvdb::Int64Grid::Ptr cameras;     ///< Null unless requested.
  openvdb::FloatGrid::Ptr resolution;  ///< Null unless requested.

  /// The non-null grids, in a fixed order.
  openvdb::GridPtrVec Grids() const {
    openvdb::GridPtrVec grids;
    if (coverage) grids.push_back(coverage);
    if (cameras) grids.push_back(cameras);
    if (resolution) grids.push_back(resolution);
    return grids;
  }
};

}  // namespace pandora
