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

#include <array>
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
