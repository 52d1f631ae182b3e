#pragma once
/// \file fields_test_util.h
/// Test helpers: two evaluations' fields compared voxel for voxel and bit for bit (values, active
/// states, tree topology) and their summary statistics. For volume/ tests only.

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "volume/fields.h"
#include "volume/fields_vdb.h"

namespace pandora {
namespace testing {

template <typename GridT>
inline void ExpectSameGrid(const GridT& a, const GridT& b, const std::string& what) {
  ASSERT_TRUE(a.tree().hasSameTopology(b.tree())) << what;
  ASSERT_EQ(a.activeVoxelCount(), b.activeVoxelCount()) << what;
  ASSERT_EQ(a.tree().activeTileCount(), b.tree().activeTileCount()) << what;
  auto acc = b.getConstAccessor();
  for (auto it = a.cbeginValueAll(); it; ++it) {
    const auto value = acc.getValue(it.getCoord());
    // Bit for bit (memcmp, so that -0 and 0 would differ).
    ASSERT_EQ(std::memcmp(&*it, &value, sizeof(value)), 0)
        << what << " at " << it.getCoord() << ": " << *it << " vs " << value;
    ASSERT_EQ(it.isValueOn(), acc.isValueOn(it.getCoord())) << what << " " << it.getCoord();
  }
}

inline void ExpectSameFields(const Fields& inc, const Fields& full, const std::string& step) {
  const Fields::Impl& a = inc.impl();
  const Fields::Impl& b = full.impl();
  ASSERT_EQ(bool(a.coverage), bool(b.coverage));
  if (a.coverage) ExpectSameGrid(*a.coverage, *b.coverage, step + " coverage");
  ASSERT_EQ(a.floats.size(), b.floats.size());
  for (const auto& [name, grid] : b.floats) {
    ASSERT_TRUE(a.Float(name)) << name;
    ExpectSameGrid(*a.Float(name), *grid, step + " " + name);
  }
  ASSERT_EQ(a.visible.size(), b.visible.size()) << step;
  for (std::size_t c = 0; c < a.visible.size(); ++c)
    ExpectSameGrid(*a.visible[c], *b.visible[c], step + " visible/" + std::to_string(c));
  const FieldStats& s = inc.stats;
  const FieldStats& t = full.stats;
  EXPECT_EQ(s.seen_voxels, t.seen_voxels) << step;
  EXPECT_EQ(s.triangulable_voxels, t.triangulable_voxels) << step;
  EXPECT_EQ(s.unobservable_voxels, t.unobservable_voxels) << step;
  EXPECT_EQ(s.coverage_histogram, t.coverage_histogram) << step;
  EXPECT_EQ(s.per_camera_seen, t.per_camera_seen) << step;
  EXPECT_EQ(s.point_camera_tests, t.point_camera_tests) << step;
  EXPECT_EQ(s.rays, t.rays) << step;
  EXPECT_EQ(s.active_set.region_voxels, t.active_set.region_voxels) << step;
  EXPECT_EQ(s.active_set.blocks, t.active_set.blocks) << step;
  EXPECT_EQ(s.active_set.culled_blocks, t.active_set.culled_blocks) << step;
  EXPECT_EQ(s.sigma_max_mm, t.sigma_max_mm) << step;  // same order: blocks, then offsets
  EXPECT_EQ(s.sigma_max_steady_mm, t.sigma_max_steady_mm) << step;
}

}  // namespace testing
}  // namespace pandora
