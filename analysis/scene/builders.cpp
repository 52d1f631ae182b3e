#include "analysis/scene/builders.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>

#include "analysis/geometry/primitives.h"
#include "analysis/util/seeded.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

double Cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// Orientation of (a, b, c): > 0 counter-clockwise.
double Orient(const Vec2& a, const Vec2& b, const Vec2& c) { return Cross2(b - a, c - a); }

bool OnSegment(const Vec2& p, const Vec2& a, const Vec2& b, double eps) {
  return std::abs(Orient(a, b, p)) <= eps * (b - a).norm() &&
         (p - a).dot(b - a) >= -eps * (b - a).norm() && (p - b).dot(a - b) >= -eps * (b - a).norm();
}

// Closed segments ab and cd meet (touching counts), with a tolerance of `eps` metres.
bool SegmentsMeet(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d, double eps) {
  const double o1 = Orient(a, b, c), o2 = Orient(a, b, d), o3 = Orient(c, d, a),
               o4 = Orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0)))
    return true;
  return OnSegment(c, a, b, eps) || OnSegment(d, a, b, eps) || OnSegment(a, c, d, eps) ||
         OnSegment(b, c, d, eps);
}

// The wall's outward unit normal (away from the footprint's inside).
Vec2 OutwardNormal(const Vec2& a, const Vec2& b, bool ccw) {
  const Vec2 d = (b - a).normalized();
  return ccw ? Vec2(d.y(), -d.x()) : Vec2(-d.y(), d.x());
}

// The room's outer corners: where the walls' outer faces meet (mitred).
Polygon2 OuterCorners(const RoomSpec& room, std::vector<double>* miter_quality = nullptr) {
  const Polygon2& p = room.footprint;
  const std::size_t n = p.size();
  const bool ccw = SignedArea2(p) > 0;
  Polygon2 outer(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 n_prev = OutwardNormal(p[(i + n - 1) % n], p[i], ccw);
    const Vec2 n_next = OutwardNormal(p[i], p[(i + 1) % n], ccw);
    const double q = 1 + n_prev.dot(n_next);
    if (miter_quality) miter_quality->push_back(q);
    outer[i] = p[i] + room.thickness * (n_prev + n_next) / std::max(q, 1e-9);
  }
  return outer;
}

struct Interval {
  double a, b, z0, z1;
};

// The blocks of wall `w`: full height between the gaps, and below and above each gap.
std::vector<Interval> WallBlocks(const RoomSpec& room, int w) {
  const std::size_t n = room.footprint.size();
  const double length = (room.footprint[(w + 1) % n] - room.footprint[w]).norm();
  std::vector<const WallOpening*> gaps;
  for (const WallOpening& o : room.openings)
    if (o.wall == w) gaps.push_back(&o);
  std::sort(gaps.begin(), gaps.end(),
            [](const WallOpening* x, const WallOpening* y) { return x->offset < y->offset; });
  std::vector<Interval> blocks;
  constexpr double kEps = 1e-6;
  double at = 0;
  for (const WallOpening* g : gaps) {
    if (g->offset > at + kEps) blocks.push_back({at, g->offset, 0, room.height});
    if (g->sill > kEps) blocks.push_back({g->offset, g->offset + g->width, 0, g->sill});
    if (g->sill + g->height < room.height - kEps)
      blocks.push_back({g->offset, g->offset + g->width, g->sill + g->height, room.height});
    at = g->offset + g->width;
  }
  if (length > at + kEps) blocks.push_back({at, length, 0, room.height});
  return blocks;
}

// Body proportions (fractions of the height), after Drillis and Contini (Winter, table 4.1):
// joint heights standing, and half-widths.
struct Body {
  double head_top = 1.0, chin = 0.870, shoulder = 0.818, elbow = 0.630, wrist = 0.485,
         finger = 0.377, hip = 0.530, knee = 0.285, ankle = 0.039, foot = 0.152;
  double shoulder_y = 0.115, hip_y = 0.055;
  // Radii.
  double r_head = 0.065, r_neck = 0.028, r_torso = 0.085, r_pelvis = 0.075, r_upper_arm = 0.026,
         r_forearm = 0.021, r_hand = 0.017, r_thigh = 0.042, r_shank = 0.03, r_foot = 0.02;
};

// A limb of two segments hanging from `root` in the x-z plane: `swing` (radians, forward
// positive) at the root and `bend` at the middle joint (forward for arms, backward for legs).
void Limb(const Vec3& root, double l1, double l2, double swing, double bend, bool knee, Vec3* mid,
          Vec3* end) {
  *mid = root + l1 * Vec3(std::sin(swing), 0, -std::cos(swing));
  const double a2 = knee ? swing - bend : swing + bend;
  *end = *mid + l2 * Vec3(std::sin(a2), 0, -std::cos(a2));
}

}  // namespace

double DistanceToSegment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

double SignedArea2(const Polygon2& polygon) {
  double a = 0;
  for (std::size_t i = 0; i < polygon.size(); ++i)
    a += Cross2(polygon[i], polygon[(i + 1) % polygon.size()]);
  return a;
}

std::string PolygonProblem(const Polygon2& polygon) {
  const std::size_t n = polygon.size();
  if (n < 3) return "a polygon needs at least 3 points";
  for (std::size_t i = 0; i < n; ++i)
    if ((polygon[(i + 1) % n] - polygon[i]).norm() < 1e-3)
      return "the edge from point " + std::to_string(i) + " to point " +
             std::to_string((i + 1) % n) + " is shorter than 1 mm";
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      if (j == i + 1 || (i == 0 && j == n - 1)) continue;  // neighbours share a point
      if (SegmentsMeet(polygon[i], polygon[(i + 1) % n], polygon[j], polygon[(j + 1) % n], 1e-9))
        return "edges " + std::to_string(i) + " and " + std::to_string(j) +
               " cross or touch (the polygon must be simple)";
    }
  if (std::abs(SignedArea2(polygon)) < 1e-6) return "the polygon has no area";
  return {};
}

std::vector<Eigen::Vector3i> TriangulatePolygon(const Polygon2& polygon) {
  std::vector<int> left(polygon.size());
  std::iota(left.begin(), left.end(), 0);
  if (SignedArea2(polygon) < 0) std::reverse(left.begin(), left.end());
  std::vector<Eigen::Vector3i> out;
  while (left.size() > 3) {
    const std::size_t m = left.size();
    bool clipped = false;
    for (std::size_t k = 0; k < m && !clipped; ++k) {
      const int a = left[(k + m - 1) % m], b = left[k], c = left[(k + 1) % m];
      const Vec2 &pa = polygon[a], &pb = polygon[b], &pc = polygon[c];
      if (Orient(pa, pb, pc) <= 1e-12) continue;  // reflex or flat: not an ear
      bool empty = true;
      for (int v : left) {
        if (v == a || v == b || v == c) continue;
        const Vec2& p = polygon[v];
        if (Orient(pa, pb, p) >= 0 && Orient(pb, pc, p) >= 0 && Orient(pc, pa, p) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      out.emplace_back(a, b, c);
      left.erase(left.begin() + std::ptrdiff_t(k));
      clipped = true;
    }
    if (!clipped) {  // only flat corners left (collinear points): fan the rest
      for (std::size_t k = 1; k + 1 < left.size(); ++k)
        out.emplace_back(left[0], left[k], left[k + 1]);
      return out;
    }
  }
  out.emplace_back(left[0], left[1], left[2]);
  return out;
}

TriangleMesh ExtrudePolygon(const Polygon2& polygon, double z0, double z1) {
  const int n = int(polygon.size());
  TriangleMesh mesh;
  for (int k = 0; k < 2; ++k)
    for (const Vec2& p : polygon) mesh.vertices.emplace_back(p.x(), p.y(), k ? z1 : z0);
  for (const Eigen::Vector3i& t : TriangulatePolygon(polygon)) {
    mesh.triangles.emplace_back(t[0], t[2], t[1]);              // bottom, facing -z
    mesh.triangles.emplace_back(t[0] + n, t[1] + n, t[2] + n);  // top, facing +z
  }
  const bool ccw = SignedArea2(polygon) > 0;
  for (int i = 0; i < n; ++i) {
    int a = i, b = (i + 1) % n;
    if (!ccw) std::swap(a, b);
    mesh.triangles.emplace_back(a, b, b + n);
    mesh.triangles.emplace_back(a, b + n, a + n);
  }
  return mesh;
}

TriangleMesh CapsuleBetween(const Vec3& a, const Vec3& b, double radius, int segments) {
  const Vec3 d = b - a;
  const double length = d.norm();
  TriangleMesh mesh =
      length > 1e-12 ? MakeCapsule(radius, length, segments) : MakeSphere(radius, segments);
  const Eigen::Quaterniond q = length > 1e-12
                                   ? Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), d / length)
                                   : Eigen::Quaterniond::Identity();
  const Vec3 centre = 0.5 * (a + b);
  for (Vec3& v : mesh.vertices) v = centre + q * v;
  return mesh;
}

std::string RoomProblem(const RoomSpec& room, int* opening) {
  *opening = -1;
  std::string problem = PolygonProblem(room.footprint);
  if (!problem.empty()) return "footprint: " + problem;
  std::vector<double> quality;
  const Polygon2 outer = OuterCorners(room, &quality);
  const std::size_t n = room.footprint.size();
  for (std::size_t i = 0; i < n; ++i)
    if (quality[i] < 1 + std::cos(170.0 * kPi / 180.0))
      return "footprint: the corner at point " + std::to_string(i) +
             " is sharper than 10 degrees (its walls would meet far outside)";
  problem = PolygonProblem(outer);
  if (!problem.empty())
    return "the walls' outer faces (the footprint grown by the wall thickness) are not a simple "
           "polygon: " +
           problem;
  const bool ccw = SignedArea2(room.footprint) > 0;
  for (std::size_t k = 0; k < room.openings.size(); ++k) {
    const WallOpening& o = room.openings[k];
    *opening = int(k);
    if (o.wall < 0 || o.wall >= int(n))
      return "no wall " + std::to_string(o.wall) + " (walls are 0 to " + std::to_string(n - 1) +
             ": wall i runs from footprint point i to the next)";
    const Vec2 a = room.footprint[o.wall], b = room.footprint[(o.wall + 1) % n];
    const Vec2 d = (b - a).normalized();
    const double length = (b - a).norm();
    // The outer face's ends along the wall: a gap must stay between them.
    const double lo = std::max(0.0, (outer[o.wall] - a).dot(d));
    const double hi = std::min(length, length + (outer[(o.wall + 1) % n] - b).dot(d));
    (void)ccw;
    if (o.offset < lo - 1e-9 || o.offset + o.width > hi + 1e-9)
      return "the opening (" + std::to_string(o.offset) + " to " +
             std::to_string(o.offset + o.width) + " m along the wall) is not within the wall's " +
             std::to_string(lo) + " to " + std::to_string(hi) + " m";
    if (o.sill + o.height > room.height + 1e-9)
      return "the opening's top (" + std::to_string(o.sill + o.height) +
             " m) is above the room's height (" + std::to_string(room.height) + " m)";
    for (std::size_t j = 0; j < k; ++j) {
      const WallOpening& p = room.openings[j];
      if (p.wall == o.wall && o.offset < p.offset + p.width - 1e-9 &&
          p.offset < o.offset + o.width - 1e-9)
        return "the opening overlaps opening " + std::to_string(j) + " on the same wall";
    }
  }
  *opening = -1;
  return {};
}

std::vector<BuiltPart> BuildRoom(const RoomSpec& room) {
  const Polygon2& p = room.footprint;
  const std::size_t n = p.size();
  const Polygon2 outer = OuterCorners(room);
  const bool ccw = SignedArea2(p) > 0;
  std::vector<BuiltPart> parts;
  for (std::size_t w = 0; w < n; ++w) {
    const Vec2 a = p[w], b = p[(w + 1) % n];
    const double length = (b - a).norm();
    const Vec2 d = (b - a) / length, out = OutwardNormal(a, b, ccw);
    BuiltPart part{"wall" + std::to_string(w), {}, Vec3::Zero(), Vec3::Zero(), 0};
    for (const Interval& block : WallBlocks(room, int(w))) {
      const Vec2 inner0 = a + block.a * d, inner1 = a + block.b * d;
      const Vec2 outer0 = block.a <= 1e-9 ? outer[w] : inner0 + room.thickness * out;
      const Vec2 outer1 =
          block.b >= length - 1e-9 ? outer[(w + 1) % n] : inner1 + room.thickness * out;
      part.mesh.Append(ExtrudePolygon({inner0, inner1, outer1, outer0}, block.z0, block.z1));
    }
    if (!part.mesh.triangles.empty()) parts.push_back(std::move(part));
  }
  const Vec3 o = Vec3::Zero();
  if (room.floor) parts.push_back({"floor", ExtrudePolygon(outer, -room.slab, 0), o, o, 0});
  if (room.ceiling)
    parts.push_back(
        {"ceiling", ExtrudePolygon(outer, room.height, room.height + room.slab), o, o, 0});
  return parts;
}

bool FurnitureSize(const std::string& type, Vec3* size) {
  static const std::map<std::string, Vec3> kSizes = {
      {"desk", {1.6, 0.8, 0.75}},       {"table", {1.8, 0.9, 0.75}},   {"chair", {0.5, 0.5, 0.9}},
      {"stool", {0.4, 0.4, 0.65}},      {"cabinet", {0.8, 0.45, 1.9}}, {"shelf", {1.0, 0.35, 2.0}},
      {"bed", {2.1, 0.95, 0.65}},       {"sofa", {2.0, 0.9, 0.85}},    {"counter", {2.0, 0.6, 0.9}},
      {"workbench", {1.8, 0.75, 0.9}},  {"rack", {0.6, 1.0, 2.0}},     {"cart", {0.9, 0.55, 1.0}},
      {"monitor_cart", {0.6, 0.6, 1.5}}};
  const auto it = kSizes.find(type);
  if (it == kSizes.end()) return false;
  *size = it->second;
  return true;
}

std::vector<std::string> FurnitureTypes() {
  std::vector<std::string> types;
  for (const char* t : {"bed", "cabinet", "cart", "chair", "counter", "desk", "monitor_cart",
                        "rack", "shelf", "sofa", "stool", "table", "workbench"})
    types.push_back(t);
  return types;
}

const std::vector<std::string>& PersonPoses() {
  static const std::vector<std::string> kPoses = {"standing", "sitting", "walking"};
  return kPoses;
}

std::vector<BuiltPart> BuildPerson(const PersonSpec& person) {
  const Body f;
  const double h = person.height, g = person.girth * h;
  const int s = person.segments;
  // Joint chains in the person's frame (standing heights), then posed.
  const double upper_arm = (f.shoulder - f.elbow) * h, forearm = (f.elbow - f.wrist) * h,
               hand = (f.wrist - f.finger) * h, thigh = (f.hip - f.knee) * h,
               shank = (f.knee - f.ankle) * h;
  double hip_swing_l = 0, hip_swing_r = 0, knee_l = 0, knee_r = 0, arm_l = 0, arm_r = 0,
         elbow = 0.15, pelvis_z = f.hip * h;
  const double deg = kPi / 180;
  if (person.pose == "walking") {  // mid-stride: left leg forward, right arm forward
    hip_swing_l = 22 * deg, hip_swing_r = -15 * deg, knee_r = 20 * deg, knee_l = 3 * deg;
    arm_l = -20 * deg, arm_r = 20 * deg, elbow = 25 * deg;
  } else if (person.pose == "sitting") {  // thighs level at knee height, shanks down, hands on lap
    hip_swing_l = hip_swing_r = 90 * deg, knee_l = knee_r = 90 * deg;
    pelvis_z = f.knee * h + f.r_thigh * g;
    arm_l = arm_r = 10 * deg, elbow = 70 * deg;
  }
  const double lift = pelvis_z - f.hip * h;  // the trunk moves with the pelvis
  const Vec3 hip_l(0, f.hip_y * h, pelvis_z), hip_r(0, -f.hip_y * h, pelvis_z);
  const Vec3 shoulder_l(0, f.shoulder_y * h, f.shoulder * h + lift),
      shoulder_r(0, -f.shoulder_y * h, f.shoulder * h + lift);
  Vec3 knee_pl, ankle_l, knee_pr, ankle_r, elbow_l, wrist_l, elbow_r, wrist_r;
  Limb(hip_l, thigh, shank, hip_swing_l, knee_l, true, &knee_pl, &ankle_l);
  Limb(hip_r, thigh, shank, hip_swing_r, knee_r, true, &knee_pr, &ankle_r);
  Limb(shoulder_l, upper_arm, forearm, arm_l, elbow, false, &elbow_l, &wrist_l);
  Limb(shoulder_r, upper_arm, forearm, arm_r, elbow, false, &elbow_r, &wrist_r);
  // Arms hang a little away from the body.
  elbow_l.y() += f.r_torso * g * 0.35, wrist_l.y() += f.r_torso * g * 0.45;
  elbow_r.y() -= f.r_torso * g * 0.35, wrist_r.y() -= f.r_torso * g * 0.45;
  const Vec3 hand_dir_l = (wrist_l - elbow_l).normalized(),
             hand_dir_r = (wrist_r - elbow_r).normalized();
  // Feet flat on the floor, pointing forward, from the heel (under the ankle) to the toes.
  auto foot = [&](const Vec3& ankle) {
    const Vec3 heel(ankle.x() - 0.25 * f.foot * h, ankle.y(), f.r_foot * g);
    return std::make_pair(heel, Vec3(heel.x() + f.foot * h - 2 * f.r_foot * g, heel.y(), heel.z()));
  };
  const auto [heel_l, toe_l] = foot(ankle_l);
  const auto [heel_r, toe_r] = foot(ankle_r);
  std::vector<BuiltPart> parts;
  auto add = [&](const char* name, const Vec3& a, const Vec3& b, double r) {
    // The kept radius is that of the capsule the tessellation surely contains (its rings and
    // stacks cut inside the true surface by up to cos(pi / segments) twice over).
    const double inner = r * g * std::pow(std::cos(kPi / s), 2);
    parts.push_back({name, CapsuleBetween(a, b, r * g, s), a, b, inner});
  };
  const double chin = f.chin * h + lift, head_c = (f.head_top - f.r_head * person.girth) * h + lift;
  add("head", Vec3(0, 0, head_c), Vec3(0, 0, head_c), f.r_head);
  add("neck", Vec3(0, 0, f.shoulder * h + lift), Vec3(0, 0, chin + 0.01 * h), f.r_neck);
  add("torso", Vec3(0, 0, pelvis_z + 0.06 * h), Vec3(0, 0, f.shoulder * h + lift - 0.06 * h),
      f.r_torso);
  add("pelvis", Vec3(0, f.hip_y * h * 0.6, pelvis_z + 0.015 * h),
      Vec3(0, -f.hip_y * h * 0.6, pelvis_z + 0.015 * h), f.r_pelvis);
  add("upper_arm_l", shoulder_l, elbow_l, f.r_upper_arm);
  add("forearm_l", elbow_l, wrist_l, f.r_forearm);
  add("hand_l", wrist_l, wrist_l + hand * hand_dir_l, f.r_hand);
  add("upper_arm_r", shoulder_r, elbow_r, f.r_upper_arm);
  add("forearm_r", elbow_r, wrist_r, f.r_forearm);
  add("hand_r", wrist_r, wrist_r + hand * hand_dir_r, f.r_hand);
  add("thigh_l", hip_l, knee_pl, f.r_thigh);
  add("shank_l", knee_pl, ankle_l, f.r_shank);
  add("foot_l", heel_l, toe_l, f.r_foot);
  add("thigh_r", hip_r, knee_pr, f.r_thigh);
  add("shank_r", knee_pr, ankle_r, f.r_shank);
  add("foot_r", heel_r, toe_r, f.r_foot);
  // Standing on the floor: the lowest point of the body at z = 0.
  double low = 1e300;
  for (const BuiltPart& p : parts)
    for (const Vec3& v : p.mesh.vertices) low = std::min(low, v.z());
  if (person.pose != "sitting")
    for (BuiltPart& p : parts) {
      for (Vec3& v : p.mesh.vertices) v.z() -= low;
      p.axis_a.z() -= low, p.axis_b.z() -= low;
    }
  return parts;
}

// ---- Walks.

namespace {

double WrapDegrees(double d) {
  d = std::fmod(d + 180.0, 360.0);
  if (d < 0) d += 360.0;
  return d - 180.0;
}

double HeadingDeg(const Vec2& from, const Vec2& to) {
  return std::atan2(to.y() - from.y(), to.x() - from.x()) * 180.0 / kPi;
}

GroupPose PoseAt(const Vec2& p, const Vec3& anchor, double yaw) {
  GroupPose pose;
  pose.move = Vec3(p.x() - anchor.x(), p.y() - anchor.y(), 0);
  pose.yaw_deg = yaw;
  return pose;
}

// Appends a turn to `heading` (the yaw taking the shorter way) and a leg to `to`.
void AppendLeg(std::vector<std::pair<double, GroupPose>>* frames, double* t, double* yaw,
               const Vec2& from, const Vec2& to, const Vec3& anchor, double facing, double speed,
               double turn_s) {
  const double target = HeadingDeg(from, to) - facing;
  const double next = *yaw + WrapDegrees(target - *yaw);
  if (std::abs(next - *yaw) > 1e-9) {
    *t += turn_s;
    *yaw = next;
    frames->emplace_back(*t, PoseAt(from, anchor, *yaw));
  }
  *t += (to - from).norm() / speed;
  frames->emplace_back(*t, PoseAt(to, anchor, *yaw));
}

}  // namespace

std::vector<std::pair<double, GroupPose>> WalkKeyframes(const WalkSpec& walk, const Vec3& anchor,
                                                        double facing_deg) {
  std::vector<Vec2> path = walk.path;
  if (walk.closed) path.push_back(path.front());
  std::vector<std::pair<double, GroupPose>> frames;
  double t = walk.start_s;
  // Facing the first leg from the start (turned before the walk begins).
  double yaw = path.size() > 1 ? WrapDegrees(HeadingDeg(path[0], path[1]) - facing_deg) : 0;
  frames.emplace_back(t, PoseAt(path[0], anchor, yaw));
  for (std::size_t i = 1; i < path.size(); ++i)
    AppendLeg(&frames, &t, &yaw, path[i - 1], path[i], anchor, facing_deg, walk.speed, walk.turn_s);
  return frames;
}

double Footprint2::Distance(const Vec2& p) const {
  double best = 1e300;
  for (const auto& t : triangles) {
    const double o1 = Orient(t[0], t[1], p), o2 = Orient(t[1], t[2], p), o3 = Orient(t[2], t[0], p);
    if ((o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0)) return 0;
    for (int k = 0; k < 3; ++k) best = std::min(best, DistanceToSegment(p, t[k], t[(k + 1) % 3]));
  }
  return best;
}

double Footprint2::SegmentDistance(const Vec2& a, const Vec2& b) const {
  double best = std::min(Distance(a), Distance(b));
  for (const auto& t : triangles)
    for (int k = 0; k < 3 && best > 0; ++k) {
      const Vec2 &c = t[k], &d = t[(k + 1) % 3];
      if (SegmentsMeet(a, b, c, d, 0)) return 0;
      best = std::min({best, DistanceToSegment(c, a, b), DistanceToSegment(d, a, b),
                       DistanceToSegment(a, c, d), DistanceToSegment(b, c, d)});
    }
  return best;
}

Vec2 OtherWalker::At(double t) const {
  GroupPose pose;
  if (!keyframes.empty()) {
    if (t <= keyframes.front().first) {
      pose = keyframes.front().second;
    } else if (t >= keyframes.back().first) {
      pose = keyframes.back().second;
    } else {
      const auto it = std::upper_bound(
          keyframes.begin(), keyframes.end(), t,
          [](double v, const std::pair<double, GroupPose>& k) { return v < k.first; });
      const auto& [t1, p1] = *it;
      const auto& [t0, p0] = *(it - 1);
      const double w = (t - t0) / (t1 - t0);
      pose.move = (1 - w) * p0.move + w * p1.move;
    }
  }
  return Vec2(anchor.x() + pose.move.x(), anchor.y() + pose.move.y());
}

std::vector<std::pair<double, GroupPose>> WanderKeyframes(const WanderSpec& wander,
                                                          const Vec3& anchor, double facing_deg,
                                                          const Footprint2& obstacles,
                                                          const std::vector<OtherWalker>& others) {
  constexpr double kStep = 0.05;  // seconds between clearance checks along a leg
  auto clear_at = [&](const Vec2& p, double t) {
    if (obstacles.Distance(p) < wander.radius) return false;
    for (const OtherWalker& o : others)
      if ((o.At(t) - p).norm() < 2 * wander.radius) return false;
    return true;
  };
  Vec2 at(anchor.x(), anchor.y());
  if (!clear_at(at, 0))
    throw std::invalid_argument("the walker's start (where the file places it) is within " +
                                std::to_string(wander.radius) +
                                " m of a solid or of another walker");
  std::vector<std::pair<double, GroupPose>> frames;
  double t = 0, yaw = 0;
  frames.emplace_back(t, PoseAt(at, anchor, yaw));
  const Vec3 lo = wander.region.min, size = wander.region.max - wander.region.min;
  for (std::uint64_t leg = 0; t < wander.duration_s; ++leg) {
    bool moved = false;
    for (std::uint64_t draw = 0; draw < 200 && !moved; ++draw) {
      const Vec2 goal(lo.x() + size.x() * SeededUniform(wander.seed, leg, draw, 0),
                      lo.y() + size.y() * SeededUniform(wander.seed, leg, draw, 1));
      const double length = (goal - at).norm();
      if (length < 0.5) continue;
      const double target = HeadingDeg(at, goal) - facing_deg;
      const double turn = std::abs(WrapDegrees(target - yaw)) > 1e-9 ? wander.turn_s : 0;
      const double walk_s = length / wander.speed;
      // The static solids once for the whole leg (exactly), then the other walkers along it.
      bool free = obstacles.SegmentDistance(at, goal) >= wander.radius;
      for (double s = 0; s <= walk_s + 1e-12 && free; s += kStep)
        free = clear_at(at + (goal - at) * (s / walk_s), t + turn + s);
      for (double s = 0; s <= wander.pause_s && free; s += kStep)
        free = clear_at(goal, t + turn + walk_s + s);
      if (!free) continue;
      AppendLeg(&frames, &t, &yaw, at, goal, anchor, facing_deg, wander.speed, wander.turn_s);
      if (wander.pause_s > 0) {
        t += wander.pause_s;
        frames.emplace_back(t, PoseAt(goal, anchor, yaw));
      }
      at = goal;
      moved = true;
    }
    if (!moved) {
      t += 1.0;
      frames.emplace_back(t, PoseAt(at, anchor, yaw));
    }
  }
  return frames;
}

}  // namespace pandora
