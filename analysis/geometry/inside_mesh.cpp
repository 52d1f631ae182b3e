// The only translation unit that includes CGAL.
#include "analysis/geometry/inside_mesh.h"

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
#include <cstdint>
#include <iterator>
#include <mutex>
#include <stdexcept>
#include <vector>

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

// The faces bucketed by their bounding boxes over a uniform grid of the mesh's (x, y) extent, for
// ColumnAt: a vertical line looks at its cell's faces only. A face is in every cell its (x, y)
// bounding box meets; cells are found with the same rounded expression for boxes and lines, and
// rounding is monotone, so a line's cell holds every face whose closed box contains the line.
struct ColumnGrid {
  double x0 = 0, y0 = 0, cw = 1, ch = 1;
  int nx = 1, ny = 1;
  std::vector<std::uint32_t> start;  // per cell, into faces; nx * ny + 1
  std::vector<std::uint32_t> faces;
  std::vector<std::array<Point, 3>> corners;  // per face, as given (the mesh's triangles, in order)
  std::vector<Aabb> boxes;                    // per face, its bounding box

  int Cell(double v, double v0, double w, int n) const {
    return static_cast<int>(std::clamp(std::floor((v - v0) / w), 0.0, double(n - 1)));
  }
  int CellX(double x) const { return Cell(x, x0, cw, nx); }
  int CellY(double y) const { return Cell(y, y0, ch, ny); }

  void Build(const TriangleMesh& mesh, const Aabb& bounds) {
    corners.clear();
    corners.reserve(mesh.triangles.size());
    boxes.reserve(mesh.triangles.size());
    for (const Eigen::Vector3i& t : mesh.triangles) {
      std::array<Point, 3> v;
      Aabb box;
      for (int k = 0; k < 3; ++k) {
        const Vec3& p = mesh.vertices[std::size_t(t[k])];
        v[k] = Point(p.x(), p.y(), p.z());
        box.Extend(p);
      }
      corners.push_back(v);
      boxes.push_back(box);
    }
    const double n = static_cast<double>(corners.size());
    const double wx = bounds.max.x() - bounds.min.x(), wy = bounds.max.y() - bounds.min.y();
    x0 = bounds.min.x();
    y0 = bounds.min.y();
    // About one face per cell (a closed surface projects onto its footprint twice), at most 1024
    // cells a side; coarser while large faces would fill too many cells.
    double cells = std::max(1.0, n);
    // The cells each face's (x, y) box meets (columns i0..i1, rows j0..j1), for the passes below.
    std::vector<std::array<int, 4>> ranges(boxes.size());
    for (;;) {
      const double aspect = wy > 0 && wx > 0 ? wx / wy : 1.0;
      nx = wx > 0 ? static_cast<int>(std::clamp(std::round(std::sqrt(cells * aspect)), 1.0, 1024.0))
                  : 1;
      ny = wy > 0 ? static_cast<int>(std::clamp(std::round(std::sqrt(cells / aspect)), 1.0, 1024.0))
                  : 1;
      cw = wx > 0 ? wx / nx : 1.0;
      ch = wy > 0 ? wy / ny : 1.0;
      std::size_t entries = 0;
      for (std::size_t f = 0; f < boxes.size(); ++f) {
        const Aabb& b = boxes[f];
        ranges[f] = {CellX(b.min.x()), CellX(b.max.x()), CellY(b.min.y()), CellY(b.max.y())};
        const auto [i0, i1, j0, j1] = ranges[f];
        entries += std::size_t(i1 - i0 + 1) * std::size_t(j1 - j0 + 1);
      }
      if (entries <= 16 * corners.size() + 4096 || (nx == 1 && ny == 1)) break;
      cells /= 4;
    }
    start.assign(std::size_t(nx) * ny + 1, 0);
    const auto each_cell = [&](std::size_t f, auto&& fn) {
      const auto [i0, i1, j0, j1] = ranges[f];
      for (int i = i0; i <= i1; ++i)
        for (int j = j0; j <= j1; ++j) fn(std::size_t(i) * ny + j);
    };
    for (std::size_t f = 0; f < corners.size(); ++f)
      each_cell(f, [&](std::size_t c) { ++start[c + 1]; });
    for (std::size_t c = 0; c + 1 < start.size(); ++c) start[c + 1] += start[c];
    faces.assign(start.back(), 0);
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < corners.size(); ++f)
      each_cell(f, [&](std::size_t c) { faces[fill[c]++] = static_cast<std::uint32_t>(f); });
  }
};

// CGAL's mesh and AABB tree are built only when a query needs them (a point query, a column
// through an edge or a vertex, a box over many grid cells): a moving solid re-made at every time
// sample is usually classified by its column grid alone.
struct InsideMesh::Impl {
  std::vector<Point> points;
  std::vector<std::array<std::size_t, 3>> polygons;
  std::once_flag built;
  Mesh mesh;
  Tree tree;
  ColumnGrid columns;
  // Side_of_triangle_mesh keeps mutable state (a random generator for degenerate rays), so each
  // thread uses its own, all sharing the one tree.
  mutable tbb::enumerable_thread_specific<std::unique_ptr<Side>> sides;

  const Tree& Built() {
    std::call_once(built, [this] {
      CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, polygons, mesh);
      tree.insert(CGAL::faces(mesh).first, CGAL::faces(mesh).second, mesh);
      tree.build();
    });
    return tree;
  }
  const Side& side() {
    std::unique_ptr<Side>& s = sides.local();
    if (!s) s = std::make_unique<Side>(Built());
    return *s;
  }
};

InsideMesh::InsideMesh(const TriangleMesh& closed_mesh) : impl_(std::make_unique<Impl>()) {
  if (closed_mesh.triangles.empty())
    throw std::invalid_argument("InsideMesh: the mesh has no faces");
  impl_->points.reserve(closed_mesh.vertices.size());
  for (const Vec3& v : closed_mesh.vertices) impl_->points.emplace_back(v.x(), v.y(), v.z());
  impl_->polygons.reserve(closed_mesh.triangles.size());
  for (const Eigen::Vector3i& t : closed_mesh.triangles)
    impl_->polygons.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  bounds_ = closed_mesh.Bounds();
  impl_->columns.Build(closed_mesh, bounds_);
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
  if (!(x >= bounds_.min.x() && x <= bounds_.max.x() && y >= bounds_.min.y() &&
        y <= bounds_.max.y()))
    return column;
  column.outside = false;
  // The faces whose (x, y) bounding box may hold the line: its cell's (ColumnGrid).
  const ColumnGrid& grid = impl_->columns;
  const std::size_t cell = std::size_t(grid.CellX(x)) * grid.ny + grid.CellY(y);
  const Kernel::Point_2 q(x, y);
  const auto degenerate = [&column] {
    column.degenerate = true;
    column.crossings.clear();
    return column;
  };
  for (std::uint32_t i = grid.start[cell]; i < grid.start[cell + 1]; ++i) {
    const std::array<Point, 3>& v = grid.corners[grid.faces[i]];
    const Kernel::Point_2 a(v[0].x(), v[0].y()), b(v[1].x(), v[1].y()), c(v[2].x(), v[2].y());
    const CGAL::Orientation o0 = CGAL::orientation(a, b, q), o1 = CGAL::orientation(b, c, q),
                            o2 = CGAL::orientation(c, a, q);
    // Strictly on both sides of the face's edges: the line passes beside the face (exact).
    const bool left = o0 == CGAL::LEFT_TURN || o1 == CGAL::LEFT_TURN || o2 == CGAL::LEFT_TURN;
    const bool right = o0 == CGAL::RIGHT_TURN || o1 == CGAL::RIGHT_TURN || o2 == CGAL::RIGHT_TURN;
    if (left && right) continue;
    // Through an edge or a vertex in projection (or in a vertical face's plane): the parity along
    // this line is ambiguous; Side_of_triangle_mesh's own degeneracy handling decides.
    if (o0 == CGAL::COLLINEAR || o1 == CGAL::COLLINEAR || o2 == CGAL::COLLINEAR)
      return degenerate();
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
    crossing.z =
        crossing.a.z() - (n.x() * (x - crossing.a.x()) + n.y() * (y - crossing.a.y())) / n.z();
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
  // The faces whose bounding box meets the box are in the grid cells of the box's (x, y) range
  // (rounding to cells is monotone). One meeting it: kCrossing (conservative, as documented).
  const ColumnGrid& grid = impl_->columns;
  const int i0 = grid.CellX(box.min.x()), i1 = grid.CellX(box.max.x());
  const int j0 = grid.CellY(box.min.y()), j1 = grid.CellY(box.max.y());
  const std::size_t span = std::size_t(grid.start[std::size_t(i1) * grid.ny + j1 + 1]) -
                           grid.start[std::size_t(i0) * grid.ny + j0];
  if (span > 8 * grid.corners.size() + 4096) {
    // A box over most of a large mesh: the tree's exact triangle test.
    const CGAL::Bbox_3 b(box.min.x(), box.min.y(), box.min.z(), box.max.x(), box.max.y(),
                         box.max.z());
    if (impl_->Built().do_intersect(b)) return BoxClass::kCrossing;
  } else {
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) {
        const std::size_t cell = std::size_t(i) * grid.ny + j;
        for (std::uint32_t k = grid.start[cell]; k < grid.start[cell + 1]; ++k) {
          const Aabb& f = grid.boxes[grid.faces[k]];
          if ((f.max.array() >= box.min.array()).all() && (f.min.array() <= box.max.array()).all())
            return BoxClass::kCrossing;
        }
      }
  }
  // No face meets the box: it is all inside or all outside; its centre decides (the column's
  // parity, equal to Inside()).
  const Vec3 c = box.center();
  unsigned char in = 0;
  InsideOnColumn(ColumnAt(c.x(), c.y()), &c.z(), 1, &in);
  return in ? BoxClass::kInside : BoxClass::kOutside;
}

}  // namespace pandora
