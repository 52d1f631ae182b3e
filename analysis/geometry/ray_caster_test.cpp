// Embree against the double-precision brute force on randomized scenes at several scales.
#include "analysis/geometry/ray_caster.h"

#include <gtest/gtest.h>

#include <random>

#include "tests/random_scene.h"

namespace pandora {
namespace {

struct ScaleCase {
  double scale;
  Vec3 offset;
};

class RayCasterAgreement : public ::testing::TestWithParam<ScaleCase> {};

TEST_P(RayCasterAgreement, OcclusionAndFirstHitMatchBruteForce) {
  const ScaleCase sc = GetParam();
  std::mt19937_64 rng(42);
  const TriangleMesh mesh = testing::RandomScene(rng, sc.scale, sc.offset, 40, 60);
  const auto embree = MakeEmbreeRayCaster(mesh);
  const auto brute = MakeBruteForceRayCaster(mesh);
  ASSERT_EQ(embree->triangle_count(), mesh.triangles.size());

  std::uniform_real_distribution<double> u(-0.1, 1.1);
  const double tol = 1e-5 * sc.scale * std::sqrt(3.0);  // grazing tolerance, relative to the scene
  int compared = 0, grazing = 0, occluded = 0, hit_checks = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 a = sc.offset + sc.scale * Vec3(u(rng), u(rng), u(rng));
    const Vec3 b = sc.offset + sc.scale * Vec3(u(rng), u(rng), u(rng));
    const double len = (b - a).norm();
    Ray ray{a, (b - a) / len, 0.0, len};
    const bool e = embree->Occluded(ray);
    const bool f = brute->Occluded(ray);
    if (e != f) {
      ASSERT_TRUE(testing::IsGrazing(mesh, a, b, tol))
          << "disagreement on a non-grazing segment " << i << ": embree " << e << " brute " << f;
      ++grazing;
      continue;
    }
    ++compared;
    occluded += f;
    // First hit along the unbounded ray.
    Ray open = ray;
    open.t_far = std::numeric_limits<double>::infinity();
    const auto he = embree->Intersect(open);
    const auto hb = brute->Intersect(open);
    if (he.has_value() != hb.has_value()) continue;  // grazing along the infinite ray
    if (hb) {
      ++hit_checks;
      EXPECT_NEAR(he->t, hb->t, 1e-5 * sc.scale) << i;
      if (he->triangle == hb->triangle) {
        EXPECT_NEAR(std::abs(he->normal.dot(hb->normal)), 1.0, 1e-5);
      }
    }
  }
  // The scene is dense enough that both outcomes are common, and grazing cases are rare.
  EXPECT_GT(occluded, compared / 5);
  EXPECT_LT(occluded, compared * 9 / 10);
  EXPECT_LT(grazing, 10);
  EXPECT_GT(hit_checks, 1000);
}

INSTANTIATE_TEST_SUITE_P(Scales, RayCasterAgreement,
                         ::testing::Values(ScaleCase{1.0, Vec3::Zero()},
                                           ScaleCase{1e-3, Vec3(0.5, -0.2, 0.1)},
                                           ScaleCase{1e4, Vec3(-5e3, 2e3, 0)},
                                           // Far from the origin: recentring keeps float precise.
                                           ScaleCase{10.0, Vec3(1e5, -2e5, 3e4)}));

TEST(RayCaster, SegmentEndsAreOpen) {
  // One triangle in the plane z = 1.
  TriangleMesh mesh;
  mesh.vertices = {Vec3(-1, -1, 1), Vec3(1, -1, 1), Vec3(0, 1, 1)};
  mesh.triangles = {Eigen::Vector3i(0, 1, 2)};
  for (const auto& caster : {MakeEmbreeRayCaster(mesh), MakeBruteForceRayCaster(mesh)}) {
    const Vec3 up(0, 0, 1);
    EXPECT_TRUE(caster->Occluded(Ray{Vec3(0, 0, 0), up, 0.0, 2.0})) << caster->name();
    EXPECT_FALSE(caster->Occluded(Ray{Vec3(0, 0, 0), up, 0.0, 0.999})) << caster->name();
    EXPECT_FALSE(caster->Occluded(Ray{Vec3(0, 0, 0), up, 1.001, 2.0})) << caster->name();
    // Both sides are hit.
    EXPECT_TRUE(caster->Occluded(Ray{Vec3(0, 0, 2), -up, 0.0, 2.0})) << caster->name();
    const auto hit = caster->Intersect(Ray{Vec3(0, 0, 0), up, 0.0, 10.0});
    ASSERT_TRUE(hit.has_value()) << caster->name();
    EXPECT_NEAR(hit->t, 1.0, 1e-6);
    EXPECT_EQ(hit->triangle, 0);
    EXPECT_NEAR(hit->normal.z(), 1.0, 1e-6);
  }
}

TEST(RayCaster, EmptySceneNeverOccludes) {
  const TriangleMesh empty;
  const auto embree = MakeEmbreeRayCaster(empty);
  EXPECT_FALSE(embree->Occluded(Ray{Vec3::Zero(), Vec3::UnitX(), 0, 1e9}));
  EXPECT_FALSE(embree->Intersect(Ray{Vec3::Zero(), Vec3::UnitX(), 0, 1e9}).has_value());
}

TEST(RayCaster, BatchAndRawLoopMatchSingleQueries) {
  std::mt19937_64 rng(7);
  const TriangleMesh mesh = testing::RandomScene(rng, 1.0, Vec3::Zero(), 30, 30);
  const auto embree = MakeEmbreeRayCaster(mesh);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Ray> rays;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    rays.push_back(Ray{a, (b - a).normalized(), 0.0, (b - a).norm()});
  }
  std::vector<uint8_t> batch;
  embree->OccludedBatch(rays, &batch);
  std::size_t count = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(batch[i] != 0, embree->Occluded(rays[i]));
    count += batch[i];
  }
  const RawOcclusionResult raw = RawEmbreeOcclusion(*embree, rays);
  EXPECT_EQ(raw.rays, rays.size());
  EXPECT_EQ(raw.occluded, count);
  EXPECT_THROW(RawEmbreeOcclusion(*MakeBruteForceRayCaster(mesh), rays), std::invalid_argument);
}

TEST(RayCaster, IntersectPacketMatchesSingleQueriesAndBruteForce) {
  std::mt19937_64 rng(11);
  const TriangleMesh mesh = testing::RandomScene(rng, 1.0, Vec3::Zero(), 30, 30);
  const auto embree = MakeEmbreeRayCaster(mesh);
  const auto brute = MakeBruteForceRayCaster(mesh);
  std::uniform_real_distribution<double> u(0, 1);
  // Coherent rays from one eye through a grid (as a renderer's rows), plus an odd count so the last
  // packet is partly filled.
  std::vector<Ray> rays;
  const Vec3 eye(-0.5, 0.5, 0.5);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 43; ++x) {
      const Vec3 target(1.5, x / 42.0, y / 39.0);
      rays.push_back(Ray{eye, (target - eye).normalized(), 0.0, 10.0});
    }
  std::vector<std::optional<RayHit>> packet(rays.size()), reference(rays.size());
  embree->IntersectPacket(rays.data(), rays.size(), packet.data());
  brute->IntersectPacket(rays.data(), rays.size(), reference.data());
  std::size_t hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const auto single = embree->Intersect(rays[i]);
    ASSERT_EQ(packet[i].has_value(), single.has_value()) << i;
    ASSERT_EQ(reference[i].has_value(), single.has_value()) << i;
    if (!single) continue;
    ++hits;
    EXPECT_EQ(packet[i]->triangle, single->triangle);
    EXPECT_NEAR(packet[i]->t, single->t, 1e-6);
    EXPECT_LT((packet[i]->normal - single->normal).norm(), 1e-6);
    EXPECT_EQ(reference[i]->triangle, single->triangle);
    EXPECT_NEAR(reference[i]->t, single->t, 1e-5);
  }
  EXPECT_GT(hits, rays.size() / 4);
  const RawOcclusionResult raw = RawEmbreeIntersection(*embree, rays);
  const RawOcclusionResult raw_packets = RawEmbreeIntersection(*embree, rays, RawMode::kPacket);
  EXPECT_EQ(raw.occluded, hits);
  EXPECT_EQ(raw_packets.occluded, hits);
  EXPECT_THROW(RawEmbreeIntersection(*brute, rays), std::invalid_argument);
}

}  // namespace
}  // namespace pandora
