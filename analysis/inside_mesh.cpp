// The only translation unit that includes CGAL.
#include "analysis/inside_mesh.h"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <vector>
#include <stdexcept>

namespace pandora {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Traits = CGAL::AABB_traits<Kernel, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;
using Side = CGAL::Side_of_triangle_mesh<Mesh, Kernel, CGAL::Default, Tree>;

}  // namespace

struct InsideMesh::Impl {
  Mesh mesh;
  Tree tree;
  // Side_of_triangle_mesh keeps mutable state (a random generator for degenerate rays), so each
  // thread uses its own, all sharing the one tree.
  mutable tbb::enumerable_thread_specific<std::unique_ptr<Side>> sides;

  const Side& side() const {
    std::unique_ptr<Side>& s = sides.local();
    if (!s) s = std::make_unique<Side>(tree);
    return *s;
  }
};

InsideMesh::InsideMesh(const TriangleMesh& closed_mesh) : impl_(std::make_unique<Impl>()) {
  std::vector<Point> points;
  points.reserve(closed_mesh.vertices.size());
  for (const Vec3& v : closed_mesh.vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<std::array<std::size_t, 3>> polygons;
  polygons.reserve(closed_mesh.triangles.size());
  for (const Eigen::Vector3i& t : closed_mesh.triangles)
    polygons.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, impl_->mesh);
  if (impl_->mesh.number_of_faces() == 0)
    throw std::invalid_argument("InsideMesh: the mesh has no faces");
  impl_->tree.insert(CGAL::faces(impl_->mesh).first, CGAL::faces(impl_->mesh).second, impl_->mesh);
  impl_->tree.build();
  bounds_ = closed_mesh.Bounds();
}

InsideMesh::~InsideMesh() = default;

bool InsideMesh::Inside(const Vec3& p) const {
  if (!bounds_.Contains(p)) return false;
  return impl_->side()(Point(p.x(), p.y(), p.z())) != CGAL::ON_UNBOUNDED_SIDE;
}

InsideMesh::Column InsideMesh::ColumnAt(double x, double y) const {
  Column column;
  column.x = x;
  column.y = y;
  if (!(x >= bounds_.min.x() && x <= bounds_.max.x() && y >= bounds_.min.y() && y <= bounds_.max.y()))
    return column;
  column.outside = false;
  // The vertical segment through the whole mesh; every face it meets.
  const double pad = 1 + (bounds_.max.z() - bounds_.min.z());
  const Kernel::Segment_3 line(Point(x, y, bounds_.min.z() - pad), Point(x, y, bounds_.max.z() + pad));
  std::vector<Primitive::Id> faces;
  impl_->tree.all_intersected_primitives(line, std::back_inserter(faces));
  const Kernel::Point_2 q(x, y);
  const auto degenerate = [&column] {
    column.degenerate = true;
    column.crossings.clear();
    return column;
  };
  for (const Primitive::Id f : faces) {
    std::array<Point, 3> v;
    int k = 0;
    for (const auto vertex : CGAL::vertices_around_face(impl_->mesh.halfedge(f), impl_->mesh))
      if (k < 3) v[k++] = impl_->mesh.point(vertex);
    const Kernel::Point_2 a(v[0].x(), v[0].y()), b(v[1].x(), v[1].y()), c(v[2].x(), v[2].y());
    const CGAL::Orientation o0 = CGAL::orientation(a, b, q), o1 = CGAL::orientation(b, c, q),
                            o2 = CGAL::orientation(c, a, q);
    // Through an edge or a vertex in projection (or in a vertical face's plane): the parity along
    // this line is ambiguous; Side_of_triangle_mesh's own degeneracy handling decides.
    if (o0 == CGAL::COLLINEAR || o1 == CGAL::COLLINEAR || o2 == CGAL::COLLINEAR) return degenerate();
    if (o0 != o1 || o1 != o2) continue;  // the line passes beside the face
    Column::Crossing crossing;
    crossing.a = Vec3(v[0].x(), v[0].y(), v[0].z());
    crossing.b = Vec3(v[1].x(), v[1].y(), v[1].z());
    crossing.c = Vec3(v[2].x(), v[2].y(), v[2].z());
    crossing.up = o0 == CGAL::COUNTERCLOCKWISE ? 1 : -1;
    // The plane n . (p - a) = 0 at (x, y): n_z != 0 since the projection is a proper triangle.
    const Vec3 n = (crossing.b - crossing.a).cross(crossing.c - crossing.a);
    // A face within 1e-6 rad of vertical: its rounded height could miss by more than the margin
    // below; ask Inside() per point.
    if (!(std::abs(n.z()) > 1e-6 * n.norm())) return degenerate();
    crossing.z = crossing.a.z() - (n.x() * (x - crossing.a.x()) + n.y() * (y - crossing.a.y())) / n.z();
    column.crossings.push_back(crossing);
  }
  std::sort(column.crossings.begin(), column.crossings.end(),
            [](const Column::Crossing& p, const Column::Crossing& q) { return p.z < q.z; });
  return column;
}

void InsideMesh::InsideOnColumn(const Column& column, const double* z, int count,
                                unsigned char* inside) const {
  if (column.outside) {
    std::fill(inside, inside + count, 0);
    return;
  }
  if (column.degenerate) {
    for (int i = 0; i < count; ++i) inside[i] = Inside(Vec3(column.x, column.y, z[i])) ? 1 : 0;
    return;
  }
  // The rounded crossing heights decide where a point is clearly away from them (a margin far above
  // their round-off); within it, the exact orientation of the point against the face.
  const double margin = 1e-9 * (1 + bounds_.diagonal());
  for (int i = 0; i < count; ++i) {
    int below = 0;
    bool on_surface = false;
    for (const Column::Crossing& c : column.crossings) {
      if (z[i] > c.z + margin) {
        ++below;
        continue;
      }
      if (z[i] < c.z - margin) break;  // ascending: every later crossing is above too
      const CGAL::Orientation side =
          CGAL::orientation(Point(c.a.x(), c.a.y(), c.a.z()), Point(c.b.x(), c.b.y(), c.b.z()),
                            Point(c.c.x(), c.c.y(), c.c.z()), Point(column.x, column.y, z[i]));
      if (side == CGAL::COPLANAR) {
        on_surface = true;  // Inside() counts the boundary
        break;
      }
      if ((side == CGAL::POSITIVE ? 1 : -1) == c.up) ++below;
    }
    inside[i] = (on_surface || (below & 1)) ? 1 : 0;
  }
}

InsideMesh::BoxClass InsideMesh::Classify(const Aabb& box) const {
  const bool disjoint = (box.max.array() < bounds_.min.array()).any() ||
                        (box.min.array() > bounds_.max.array()).any();
  if (disjoint) return BoxClass::kOutside;
  const CGAL::Bbox_3 b(box.min.x(), box.min.y(), box.min.z(), box.max.x(), box.max.y(),
                       box.max.z());
  if (impl_->tree.do_intersect(b)) return BoxClass::kCrossing;
  // No triangle meets the box: it is all inside or all outside; its centre decides.
  return Inside(box.center()) ? BoxClass::kInside : BoxClass::kOutside;
}

}  // namespace pandora
