#pragma once
/// \file leaf_spill.h
/// Float leaves kept out of memory until they are written. A one-shot evaluation hands the leaves
/// of the fields nothing reads before fields.vdb (FieldOptions::spilled_fields: `pandora analyze`'s
/// sigma_mean, triangulation_angle, condition, sigma_mean_steady) to an unnamed temporary file as
/// each block finishes, instead of holding every block's leaf until the end; WriteFieldsVdb reads
/// them back one grid at a time. Include only where OpenVDB is needed.

#include <openvdb/openvdb.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>

namespace pandora {

class LeafSpill {
 public:
  using Leaf = openvdb::FloatTree::LeafNodeType;

  /// Opens an unnamed temporary file in `folder` (volume/value_spill.h). Throws InputError(blame,
  /// "", ...) when it cannot.
  LeafSpill(const std::string& folder, const std::string& blame);
  ~LeafSpill();
  LeafSpill(const LeafSpill&) = delete;
  LeafSpill& operator=(const LeafSpill&) = delete;

  /// Appends `leaf` whole: its origin, value mask and all 512 values (the inactive ones too), so
  /// that AddTo rebuilds it bit for bit. Thread-safe. Throws InputError(blame, ...) when the file
  /// cannot be written (a full disk).
  void Append(const Leaf& leaf);
  /// Adds every appended leaf to `tree`, which holds none at their origins. A tree's layout is a
  /// function of its leaves' origins, so the order of the appends does not matter.
  void AddTo(openvdb::FloatTree& tree) const;
  std::int64_t leaves() const { return leaves_; }

 private:
  std::FILE* file_ = nullptr;
  std::string blame_;
  std::int64_t leaves_ = 0;
  std::mutex mutex_;
};

/// A float field whose leaves were spilled: its grid (name, transform, metadata; an empty tree) and
/// the leaves. Read() returns the grid with every leaf in it (a new grid each call).
struct SpilledGrid {
  openvdb::FloatGrid::Ptr grid;
  std::shared_ptr<LeafSpill> leaves;
  openvdb::FloatGrid::Ptr Read() const;
};

}  // namespace pandora
