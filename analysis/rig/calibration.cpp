// Calibration feasibility (analysis/rig/calibration.h, docs/calibration.md). Poses are drawn on one
// thread from one seeded generator (every random number a pose needs, drawn in a fixed order), then
// judged in parallel into one byte per (pose, camera); the counts and the graph are summed on one
// thread, so a seed gives the same result on any number of threads.
#include "analysis/rig/calibration.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>

#include "analysis/geometry/inside_mesh.h"
#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/scene.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

constexpr int kTriesPerPose = 1000;

// A double uniform in [0, 1) from 53 random bits (the same on every standard library, unlike
// std::uniform_real_distribution).
double Uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1p-53; }

// A unit vector perpendicular to unit `n`.
Vec3 Perpendicular(const Vec3& n) {
  const Vec3 axis = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return n.cross(axis).normalized();
}

// The board frame with front normal `n` (unit), its x axis turned by `roll` radians in its plane.
Mat3 FrameFromNormal(const Vec3& n, double roll) {
  const Vec3 e1 = Perpendicular(n);
  const Vec3 e2 = n.cross(e1);
  Mat3 R;
  R.col(0) = std::cos(roll) * e1 + std::sin(roll) * e2;
  R.col(2) = n;
  R.col(1) = n.cross(R.col(0));
  return R;
}

// The random numbers one pose's orientation needs, drawn in a fixed order whatever is used.
struct OrientationDraw {
  double pick = 0, cos_fraction = 0, azimuth = 0, roll = 0, z = 0, sphere_azimuth = 0;
};

Mat3 UniformOrientation(const OrientationDraw& d) {
  const double z = 2.0 * d.z - 1.0;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double a = 2.0 * kPi * d.sphere_azimuth;
  return FrameFromNormal(Vec3(r * std::cos(a), r * std::sin(a), z), 2.0 * kPi * d.roll);
}

// The board turned toward a camera that sees `position` (uniform among them), tilted from facing it
// by an angle uniform in solid angle within tilt_max; a uniform orientation when none sees it.
Mat3 TowardCameraOrientation(const VisibilityTester& tester, const CalibrationBoard& board,
                             const Vec3& position, const OrientationDraw& d) {
  std::vector<int> seeing;
  for (int c = 0; c < static_cast<int>(tester.cameras().size()); ++c)
    if (tester.Test(c, position) == ViewResult::kSeen) seeing.push_back(c);
  if (seeing.empty()) return UniformOrientation(d);
  const int pick =
      seeing[std::min(seeing.size() - 1, static_cast<std::size_t>(d.pick * seeing.size()))];
  const Vec3 to_camera = tester.cameras()[pick].center() - position;
  if (!(to_camera.norm() > 0)) return UniformOrientation(d);
  const Vec3 n0 = to_camera.normalized();
  const double cos_max = std::cos(board.tilt_max_deg * kRadPerDeg);
  const double cos_t = 1.0 - d.cos_fraction * (1.0 - cos_max);
  const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
  const Vec3 e1 = Perpendicular(n0), e2 = n0.cross(e1);
  const double a = 2.0 * kPi * d.azimuth;
  const Vec3 n = (cos_t * n0 + sin_t * (std::cos(a) * e1 + std::sin(a) * e2)).normalized();
  return FrameFromNormal(n, 2.0 * kPi * d.roll);
}

// Disjoint sets over camera indices.
struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  bool Join(int a, int b) {
    a = Find(a);
    b = Find(b);
    if (a == b) return false;
    parent[std::max(a, b)] = std::min(a, b);
    return true;
  }
};

}  // namespace

const char* BoardViewName(BoardView view) {
  switch (view) {
    case BoardView::kSeen:
      return "seen";
    case BoardView::kDisabled:
      return "disabled";
    case BoardView::kTilted:
      return "tilted";
    case BoardView::kNotInImage:
      return "not_in_image";
    case BoardView::kTooSmall:
      return "too_small";
    case BoardView::kOccluded:
      return "occluded";
  }
  return "unknown";
}

std::vector<Vec3> BoardCorners(const CalibrationBoard& board, const CalibrationPose& pose) {
  std::vector<Vec3> corners;
  corners.reserve(std::size_t(board.squares_x + 1) * (board.squares_y + 1));
  const Vec3 x = pose.orientation.col(0), y = pose.orientation.col(1);
  for (int j = 0; j <= board.squares_y; ++j)
    for (int i = 0; i <= board.squares_x; ++i)
      corners.push_back(pose.position + board.square_m * ((i - 0.5 * board.squares_x) * x +
                                                          (j - 0.5 * board.squares_y) * y));
  return corners;
}

BoardView TestBoard(const VisibilityTester& tester, int camera, const CalibrationBoard& board,
                    const CalibrationPose& pose, double* min_edge_px) {
  if (min_edge_px) *min_edge_px = std::numeric_limits<double>::quiet_NaN();
  const Camera& cam = tester.cameras()[camera];
  if (!cam.enabled) return BoardView::kDisabled;
  // Tilt: the angle between the front normal and the direction from the centre to the camera.
  const Vec3 normal = pose.orientation.col(2);
  const Vec3 to_camera = cam.center() - pose.position;
  const double distance = to_camera.norm();
  if (!(distance > 0)) return BoardView::kNotInImage;
  const double cos_tilt = std::clamp(normal.dot(to_camera) / distance, -1.0, 1.0);
  if (!(std::acos(cos_tilt) <= board.tilt_max_deg * kRadPerDeg)) return BoardView::kTilted;
  // Every corner projects into the image, within range, on the front face.
  const std::vector<Vec3> corners = BoardCorners(board, pose);
  std::vector<Ray> segments(corners.size());
  std::vector<Vec2> pixels(corners.size());
  for (std::size_t k = 0; k < corners.size(); ++k) {
    const ViewResult r = tester.TestGeometry(camera, corners[k], &normal, &segments[k]);
    if (r == ViewResult::kBackFacing) return BoardView::kTilted;
    if (r != ViewResult::kSeen) return BoardView::kNotInImage;
    const std::optional<Vec2> px = cam.Project(corners[k]);
    if (!px) return BoardView::kNotInImage;
    pixels[k] = *px;
  }
  // The smallest projected edge between neighbouring corners.
  const int nx = board.squares_x + 1;
  double min_edge = std::numeric_limits<double>::infinity();
  for (int j = 0; j <= board.squares_y; ++j) {
    for (int i = 0; i < nx; ++i) {
      const Vec2& p = pixels[std::size_t(j) * nx + i];
      if (i + 1 < nx)
        min_edge = std::min(min_edge, (pixels[std::size_t(j) * nx + i + 1] - p).norm());
      if (j < board.squares_y)
        min_edge = std::min(min_edge, (pixels[std::size_t(j + 1) * nx + i] - p).norm());
    }
  }
  if (min_edge_px) *min_edge_px = min_edge;
  if (!(min_edge >= board.min_px_per_square)) return BoardView::kTooSmall;
  // Occlusion of every corner by the scene (segments shorter than the tolerance are not cast).
  std::vector<Ray> cast;
  cast.reserve(segments.size());
  for (const Ray& s : segments)
    if (s.t_far > s.t_near) cast.push_back(s);
  std::vector<std::uint8_t> occluded(cast.size(), 0);
  if (!cast.empty()) tester.caster().OccludedPacket(cast.data(), cast.size(), occluded.data());
  for (std::uint8_t o : occluded)
    if (o) return BoardView::kOccluded;
  return BoardView::kSeen;
}

BoardView ViewOfPose(const VisibilityTester& tester, int camera, const CalibrationSpec& spec,
                     const CalibrationPose& pose) {
  if (spec.target == CalibrationSpec::Target::kBoard)
    return TestBoard(tester, camera, spec.board, pose);
  switch (tester.Test(camera, pose.position)) {
    case ViewResult::kSeen:
      return BoardView::kSeen;
    case ViewResult::kDisabled:
      return BoardView::kDisabled;
    case ViewResult::kOccluded:
      return BoardView::kOccluded;
    default:
      return BoardView::kNotInImage;
  }
}

bool ObservesPose(const VisibilityTester& tester, int camera, const CalibrationSpec& spec,
                  const CalibrationPose& pose) {
  return ViewOfPose(tester, camera, spec, pose) == BoardView::kSeen;
}

CalibrationGraph BuildCalibrationGraph(const std::vector<std::vector<std::int64_t>>& shared,
                                       const std::vector<bool>& enabled, std::int64_t min_shared) {
  const int n = static_cast<int>(enabled.size());
  CalibrationGraph g;
  std::vector<CalibrationLink> edges;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (enabled[a] && enabled[b] && shared[a][b] >= min_shared)
        edges.push_back({a, b, shared[a][b]});
  // Kruskal: heavier first, ties by (a, b), so the forest is one well-defined set of edges.
  std::stable_sort(
      edges.begin(), edges.end(),
      [](const CalibrationLink& x, const CalibrationLink& y) { return x.shared > y.shared; });
  UnionFind sets(n);
  for (const CalibrationLink& e : edges)
    if (sets.Join(e.a, e.b)) g.weakest_links.push_back(e);
  std::stable_sort(
      g.weakest_links.begin(), g.weakest_links.end(),
      [](const CalibrationLink& x, const CalibrationLink& y) { return x.shared < y.shared; });
  // Components, numbered in rig order of their first camera.
  g.component.assign(n, -1);
  std::vector<int> index_of_root(n, -1);
  for (int c = 0; c < n; ++c) {
    if (!enabled[c]) continue;
    const int root = sets.Find(c);
    if (index_of_root[root] < 0) {
      index_of_root[root] = static_cast<int>(g.components.size());
      g.components.emplace_back();
    }
    g.component[c] = index_of_root[root];
    g.components[index_of_root[root]].push_back(c);
  }
  for (int k = 0; k < static_cast<int>(g.components.size()); ++k)
    if (g.largest < 0 || g.components[k].size() > g.components[g.largest].size()) g.largest = k;
  for (int c = 0; c < n; ++c)
    if (enabled[c] && (g.component[c] != g.largest || shared[c][c] < min_shared))
      g.uncalibratable.push_back(c);
  return g;
}

std::vector<CalibrationPose> SampleCalibrationPoses(const Scene& scene,
                                                    const VisibilityTester& tester,
                                                    const CalibrationSpec& spec) {
  const Region& region = scene.study.region;
  std::vector<std::unique_ptr<InsideMesh>> solids;
  for (const SceneObject& o : scene.objects)
    if (o.solid && !o.mesh.triangles.empty())
      solids.push_back(std::make_unique<InsideMesh>(o.mesh));
  std::unique_ptr<InsideMesh> region_mesh;
  if (region.kind == Region::Kind::kMesh && !region.mesh.triangles.empty())
    region_mesh = std::make_unique<InsideMesh>(region.mesh);
  const auto free = [&](const Vec3& p) {
    if (region.kind == Region::Kind::kMesh && (!region_mesh || !region_mesh->Inside(p)))
      return false;
    for (const auto& s : solids)
      if (s->bounds().Contains(p) && s->Inside(p)) return false;
    return true;
  };

  std::mt19937_64 rng(spec.seed);
  std::vector<CalibrationPose> poses;
  std::vector<OrientationDraw> draws;
  const Vec3 size = region.box.max - region.box.min;
  for (int i = 0; i < spec.samples; ++i) {
    bool placed = false;
    Vec3 p;
    for (int t = 0; t < kTriesPerPose && !placed; ++t) {
      const double u = Uniform(rng), v = Uniform(rng), w = Uniform(rng);
      p = region.box.min + Vec3(u * size.x(), v * size.y(), w * size.z());
      placed = free(p);
    }
    if (!placed) continue;
    OrientationDraw d;
    d.pick = Uniform(rng);
    d.cos_fraction = Uniform(rng);
    d.azimuth = Uniform(rng);
    d.roll = Uniform(rng);
    d.z = Uniform(rng);
    d.sphere_azimuth = Uniform(rng);
    CalibrationPose pose;
    pose.position = p;
    poses.push_back(pose);
    draws.push_back(d);
  }
  if (spec.target == CalibrationSpec::Target::kBoard) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, poses.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i)
                          poses[i].orientation =
                              spec.orientation == CalibrationSpec::Orientation::kUniform
                                  ? UniformOrientation(draws[i])
                                  : TowardCameraOrientation(tester, spec.board, poses[i].position,
                                                            draws[i]);
                      });
  }
  return poses;
}

CalibrationResult EvaluateCalibration(const VisibilityTester& tester, const CalibrationSpec& spec,
                                      const std::vector<CalibrationPose>& poses) {
  const std::size_t n = tester.cameras().size();
  CalibrationResult result;
  result.spec = spec;
  for (const Camera& c : tester.cameras()) {
    result.camera_ids.push_back(c.id);
    result.enabled.push_back(c.enabled);
  }
  result.poses = static_cast<std::int64_t>(poses.size());
  std::vector<std::uint8_t> seen(poses.size() * n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, poses.size(), 8),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        for (std::size_t c = 0; c < n; ++c)
                          seen[i * n + c] = static_cast<std::uint8_t>(
                              ViewOfPose(tester, static_cast<int>(c), spec, poses[i]));
                    });
  result.observed.assign(n, 0);
  result.missed.assign(n, {});
  result.shared.assign(n, std::vector<std::int64_t>(n, 0));
  std::vector<int> who;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    who.clear();
    for (std::size_t c = 0; c < n; ++c) {
      const std::uint8_t view = seen[i * n + c];
      if (view == static_cast<std::uint8_t>(BoardView::kSeen))
        who.push_back(static_cast<int>(c));
      else if (view != static_cast<std::uint8_t>(BoardView::kDisabled))
        ++result.missed[c][view];
    }
    result.poses_observed += who.empty() ? 0 : 1;
    result.poses_shared += who.size() >= 2 ? 1 : 0;
    for (int a : who)
      for (int b : who) ++result.shared[a][b];
  }
  for (std::size_t c = 0; c < n; ++c) result.observed[c] = result.shared[c][c];
  result.graph = BuildCalibrationGraph(result.shared, result.enabled, spec.min_shared);
  const bool any_enabled =
      std::find(result.enabled.begin(), result.enabled.end(), true) != result.enabled.end();
  result.calibratable =
      any_enabled && result.graph.components.size() == 1 && result.graph.uncalibratable.empty();
  return result;
}

CalibrationResult SimulateCalibration(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                      const CalibrationSpec& spec) {
  const auto start = std::chrono::steady_clock::now();
  const VisibilityTester tester(rig.cameras, caster,
                                std::max(scene.ContentBounds().diagonal(), 1e-9));
  const std::vector<CalibrationPose> poses = SampleCalibrationPoses(scene, tester, spec);
  CalibrationResult result = EvaluateCalibration(tester, spec, poses);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void to_json(nlohmann::json& j, const CalibrationResult& r) {
  const auto ids = [&](const std::vector<int>& cameras) {
    nlohmann::json list = nlohmann::json::array();
    for (int c : cameras) list.push_back(r.camera_ids[c]);
    return list;
  };
  j = nlohmann::json::object();
  j["target"] = CalibrationTargetName(r.spec.target);
  j["samples"] = r.spec.samples;
  j["seed"] = r.spec.seed;
  j["min_shared"] = r.spec.min_shared;
  if (r.spec.target == CalibrationSpec::Target::kBoard) {
    const CalibrationBoard& b = r.spec.board;
    j["orientation"] = CalibrationOrientationName(r.spec.orientation);
    j["board"] = {{"squares", {b.squares_x, b.squares_y}},
                  {"square_m", b.square_m},
                  {"tilt_max_deg", b.tilt_max_deg},
                  {"min_px_per_square", b.min_px_per_square}};
  }
  j["poses"] = r.poses;
  j["poses_observed"] = r.poses_observed;
  j["poses_shared"] = r.poses_shared;
  j["cameras"] = r.camera_ids;
  nlohmann::json per_camera = nlohmann::json::array();
  for (std::size_t c = 0; c < r.camera_ids.size(); ++c) {
    nlohmann::json e = {
        {"id", r.camera_ids[c]}, {"enabled", bool(r.enabled[c])}, {"observed", r.observed[c]}};
    e["component"] =
        r.graph.component[c] >= 0 ? nlohmann::json(r.graph.component[c]) : nlohmann::json();
    nlohmann::json missed = nlohmann::json::object();
    for (BoardView v :
         {BoardView::kTilted, BoardView::kNotInImage, BoardView::kTooSmall, BoardView::kOccluded})
      if (r.spec.target == CalibrationSpec::Target::kBoard || v == BoardView::kNotInImage ||
          v == BoardView::kOccluded)
        missed[BoardViewName(v)] = r.missed[c][static_cast<int>(v)];
    e["missed"] = std::move(missed);
    per_camera.push_back(std::move(e));
  }
  j["per_camera"] = std::move(per_camera);
  j["shared"] = r.shared;
  nlohmann::json components = nlohmann::json::array();
  for (const std::vector<int>& comp : r.graph.components) components.push_back(ids(comp));
  j["components"] = std::move(components);
  j["uncalibratable"] = ids(r.graph.uncalibratable);
  nlohmann::json links = nlohmann::json::array();
  for (const CalibrationLink& l : r.graph.weakest_links)
    links.push_back({{"a", r.camera_ids[l.a]}, {"b", r.camera_ids[l.b]}, {"shared", l.shared}});
  j["weakest_links"] = std::move(links);
  j["calibratable"] = r.calibratable;
  j["seconds"] = std::isfinite(r.seconds) ? r.seconds : 0.0;
}

std::string FormatCalibration(const CalibrationResult& r) {
  std::string s;
  char line[256];
  std::snprintf(line, sizeof line,
                "calibration (%s): %lld poses, %lld seen by >= 1 camera, %lld by >= 2; %s\n",
                CalibrationTargetName(r.spec.target), static_cast<long long>(r.poses),
                static_cast<long long>(r.poses_observed), static_cast<long long>(r.poses_shared),
                r.calibratable ? "calibratable as one rig" : "NOT calibratable as one rig");
  s += line;
  const auto names = [&](const std::vector<int>& cameras) {
    std::string t;
    for (int c : cameras) t += (t.empty() ? "" : ", ") + r.camera_ids[c];
    return t;
  };
  std::string observed;
  for (std::size_t c = 0; c < r.camera_ids.size(); ++c)
    if (r.enabled[c])
      observed +=
          (observed.empty() ? "" : "  ") + r.camera_ids[c] + " " + std::to_string(r.observed[c]);
  s += "  poses per camera  " + observed + "\n";
  std::snprintf(line, sizeof line, "  components (shared >= %d): %zu", r.spec.min_shared,
                r.graph.components.size());
  s += line;
  for (const std::vector<int>& comp : r.graph.components) s += "  [" + names(comp) + "]";
  s += "\n";
  if (!r.graph.uncalibratable.empty())
    s += "  uncalibratable: " + names(r.graph.uncalibratable) + "\n";
  for (int c : r.graph.uncalibratable) {
    s += "    " + r.camera_ids[c] + ": " + std::to_string(r.observed[c]) + " poses; missed";
    for (int v = 0; v < kBoardViewCount; ++v)
      if (r.missed[c][v] > 0)
        s += std::string(" ") + BoardViewName(static_cast<BoardView>(v)) + " " +
             std::to_string(r.missed[c][v]);
    s += "\n";
  }
  if (!r.graph.weakest_links.empty()) {
    s += "  weakest links:";
    for (std::size_t k = 0; k < r.graph.weakest_links.size() && k < 3; ++k) {
      const CalibrationLink& l = r.graph.weakest_links[k];
      s += "  " + r.camera_ids[l.a] + "-" + r.camera_ids[l.b] + " " + std::to_string(l.shared);
    }
    s += "\n";
  }
  return s;
}

}  // namespace pandora
