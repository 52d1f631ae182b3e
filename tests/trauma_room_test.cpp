// The paper's finding (State, Welch and Ilie 2006, Sec. 5) must come out of the numbers: with the
// medics crowding around the patient, the 4x2 grid looking through the opening above the abdomen
// covers the neck region (>= 2 cameras) better than the octagonal ring; without the medics the ring
// does at least as well.
#include <gtest/gtest.h>

#include <cstdio>

#include "analysis/scene/scene.h"
#include "volume/fields.h"

namespace pandora {
namespace {

double CoverageGe2(const Scene& scene, const std::string& rig_name) {
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  FieldOptions options;
  options.fields = {"coverage"};
  const Fields f = EvaluateFields(scene, scene.FindRig(rig_name), *caster, options);
  std::int64_t ge2 = 0;
  for (std::size_t k = 2; k < f.stats.coverage_histogram.size(); ++k)
    ge2 += f.stats.coverage_histogram[k];
  return double(ge2) / double(f.stats.active_set.region_voxels);
}

TEST(TraumaRoom, PapersFindingHolds) {
  const Scene with = LoadScene("examples/trauma_room/scene.json");
  const Scene without = LoadScene("examples/trauma_room/scene_no_medics.json");
  const double grid_with = CoverageGe2(with, "grid4x2");
  const double ring_with = CoverageGe2(with, "octagon");
  const double grid_without = CoverageGe2(without, "grid4x2");
  const double ring_without = CoverageGe2(without, "octagon");
  std::printf(
      "coverage.ge2 of the neck region: with medics grid4x2 %.3f octagon %.3f; "
      "without medics grid4x2 %.3f octagon %.3f\n",
      grid_with, ring_with, grid_without, ring_without);
  EXPECT_GT(grid_with, ring_with);
  EXPECT_GE(ring_without, grid_without);
  // The medics are what hurts the ring.
  EXPECT_LT(ring_with, ring_without);
}

}  // namespace
}  // namespace pandora
