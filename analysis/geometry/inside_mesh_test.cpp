// InsideMesh's column queries (one search per vertical line, the crossings' parity) against its
// point query (CGAL's Side_of_triangle_mesh), point for point: rotated spheres, capsules and boxes,
// and boxes whose faces, edges and vertices lie exactly on the lattice (the degenerate lines).
#include "analysis/geometry/inside_mesh.h"

#include <gtest/gtest.h>

#include <random>

#include "analysis/geometry/primitives.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

TriangleMesh Moved(TriangleMesh mesh, const Mat3& rotation, const Vec3& offset) {
  for (Vec3& v : mesh.vertices) v = rotation * v + offset;
  return mesh;
}

// Every lattice column through the mesh's bounds (padded), every height: the column answers
// equal the point answers. Returns how many points were inside.
int CompareOnLattice(const InsideMesh& inside, double h, const Vec3& origin, int* degenerate) {
  const Aabb& b = inside.bounds();
  int count = 0;
  const int nx = int((b.max.x() - origin.x()) / h) + 3, ny = int((b.max.y() - origin.y()) / h) + 3;
  const int nz = int((b.max.z() - origin.z()) / h) + 3;
  std::vector<double> z(nz);
  std::vector<unsigned char> got(nz);
  for (int k = 0; k < nz; ++k) z[k] = origin.z() + h * k;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      const double x = origin.x() + h * i, y = origin.y() + h * j;
      const InsideMesh::Column column = inside.ColumnAt(x, y);
      *degenerate += column.degenerate ? 1 : 0;
      inside.InsideOnColumn(column, z.data(), nz, got.data());
      for (int k = 0; k < nz; ++k) {
        const bool expected = inside.Inside(Vec3(x, y, z[k]));
        EXPECT_EQ(got[k] != 0, expected) << "at " << x << " " << y << " " << z[k];
        count += expected ? 1 : 0;
      }
    }
  return count;
}

TEST(InsideMesh, ColumnsAgreeWithPointsOnRotatedShapes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int inside_total = 0, degenerate = 0;
  for (int shape = 0; shape < 6; ++shape) {
    const Mat3 rotation =
        Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized())
            .toRotationMatrix();
    const TriangleMesh mesh = shape % 3 == 0   ? MakeSphere(0.4, 24)
                              : shape % 3 == 1 ? MakeCapsule(0.2, 0.5, 16)
                                               : MakeBox(Vec3(0.7, 0.3, 0.5));
    const InsideMesh inside(Moved(mesh, rotation, Vec3(u(rng), u(rng), u(rng))));
    inside_total +=
        CompareOnLattice(inside, 0.021, inside.bounds().min - Vec3::Constant(0.03), &degenerate);
  }
  EXPECT_GT(inside_total, 20000);
}

TEST(InsideMesh, ColumnsAgreeWithPointsOnLatticeAlignedBoxes) {
  // Faces on lattice planes, edges on lattice lines and vertices on lattice points: every kind of
  // degenerate line, and points exactly on the surface (inside, as Inside() counts the boundary).
  int degenerate = 0;
  const double h = 0.125;  // exact in binary
  const InsideMesh a(
      Moved(MakeBox(Vec3(1.0, 0.5, 0.75)), Mat3::Identity(), Vec3(0.5, 0.25, 0.375)));
  const int inside_a = CompareOnLattice(a, h, Vec3(-0.25, -0.25, -0.25), &degenerate);
  EXPECT_EQ(inside_a, 9 * 5 * 7);  // 0..1, 0..0.5, 0..0.75 in steps of 1/8, boundary included
  EXPECT_GT(degenerate, 0);
  // A box turned 45 degrees about z, its vertical edges on lattice lines.
  const Mat3 turn = Eigen::AngleAxisd(kPi / 4, Vec3::UnitZ()).toRotationMatrix();
  const InsideMesh b(Moved(MakeBox(Vec3(0.5, 0.5, 0.5)), turn, Vec3(0, 0, 0)));
  CompareOnLattice(b, h, Vec3(-0.5, -0.5, -0.5), &degenerate);
}

// Classify (the column grid's face boxes, the centre's column parity) against Inside() at the
// eight corners and four random points of random boxes: a box called inside or outside is so at
// every point tested; boxes of every class occur, and boxes reaching beyond the mesh's bounds.
TEST(InsideMesh, ClassifiedBoxesAgreeWithPoints) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), w(0.005, 0.15);
  const Mat3 rotation = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  std::array<int, 3> classes{};
  for (int shape = 0; shape < 3; ++shape) {
    const TriangleMesh mesh = shape == 0   ? MakeSphere(0.6, 24)
                              : shape == 1 ? MakeCapsule(0.3, 0.8, 16)
                                           : MakeBox(Vec3(0.9, 0.5, 0.7));
    const InsideMesh inside(Moved(mesh, rotation, Vec3(0.1, -0.2, 0.05)));
    for (int trial = 0; trial < 3000; ++trial) {
      const Vec3 centre(u(rng), u(rng), u(rng)), half(w(rng), w(rng), w(rng));
      Aabb box;
      box.Extend(centre - half);
      box.Extend(centre + half);
      const InsideMesh::BoxClass c = inside.Classify(box);
      ++classes[int(c)];
      if (c == InsideMesh::BoxClass::kCrossing) continue;
      const bool expected = c == InsideMesh::BoxClass::kInside;
      std::uniform_real_distribution<double> t(0.0, 1.0);
      for (int k = 0; k < 12; ++k) {
        Vec3 p;
        for (int a = 0; a < 3; ++a)
          p[a] = k < 8 ? ((k >> a & 1) ? box.max[a] : box.min[a])
                       : box.min[a] + t(rng) * (box.max[a] - box.min[a]);
        ASSERT_EQ(inside.Inside(p), expected) << "shape " << shape << " trial " << trial;
      }
    }
  }
  EXPECT_GT(classes[int(InsideMesh::BoxClass::kInside)], 100);
  EXPECT_GT(classes[int(InsideMesh::BoxClass::kOutside)], 100);
  EXPECT_GT(classes[int(InsideMesh::BoxClass::kCrossing)], 100);
}

}  // namespace
}  // namespace pandora
