#include "volume/fields.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <unordered_map>
#include <utility>

#include "analysis/geometry/inside_mesh.h"
#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/scene/ptz.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "volume/fields_vdb.h"
#include "volume/information_sum.h"
#include "volume/solid_trees.h"

namespace pandora {

double SceneStructureBytes(const Scene& scene) {
  // Measured on a 1,002,252-triangle mesh (a subdivided cube, 0.5 M vertices), resident after its
  // import with the freed memory returned (Study::Load): the scene's meshes 26 MiB, the Embree BVH
  // 99 MiB (125 MiB: 131 bytes a triangle). 192 bytes a triangle leaves 61 for a solid's search
  // trees (an AABB tree of its triangles, built for the fields; not measured apart).
  double triangles = 0;
  for (const SceneObject& o : scene.objects) triangles += double(o.mesh.triangles.size());
  // A PTZ head with a tour and a centre offset has its moves' occlusion certified on the triangles
  // in double precision (PtzSweptOccluders: 114 bytes a triangle, measured, with its hierarchy).
  bool swept = false;
  for (const Rig& rig : scene.rigs)
    for (const Camera& c : rig.cameras)
      swept = swept || (c.enabled && c.ptz && c.ptz->TourMovesCentre());
  return (swept ? 192.0 + 114.0 : 192.0) * triangles + 4096.0;
}

// The 8^3 blocks that cover `lattice`.
static double LatticeBlocks(const VoxelLattice& lattice) {
  double n = 1;
  for (int a = 0; a < 3; ++a) n *= std::ceil(double(std::max(lattice.dims[a], 0)) / 8.0);
  return n;
}
// EstimateFieldBytes for a number of voxels (the blocks that hold free voxels, or a box's).
static double EstimateBytesForVoxels(double voxels, const std::vector<std::string>& fields,
                                     int camera_count);
// What each camera adds to that (FieldEvaluator::Update checks both against the budget).
static double PerCameraBytes(const VoxelLattice& lattice, double blocks,
                             const std::vector<std::string>& fields, bool kept);

Fields::Fields() : impl_(std::make_unique<Impl>()) {}
Fields::~Fields() = default;
Fields::Fields(Fields&&) noexcept = default;
Fields& Fields::operator=(Fields&&) noexcept = default;

namespace information {

// From the eigenvalues of J (ascending, three arrays of n) the static statistics into out[row][m].
// Eigenvalues are clipped at 0 (round-off); a voxel is observable when the smallest exceeds
// kRelativeObservability times the largest, which is positive and finite. The other rows are
// meaningless (inf or NaN) where it is not, and never read there.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void StaticStatistics(int n, double* const* eigenvalues, double* const* out) {
  const double* l0p = eigenvalues[0];
  const double* l1p = eigenvalues[1];
  const double* l2p = eigenvalues[2];
  double* __restrict observable = out[kObservable];
  double* __restrict sigma_max = out[kSigmaMaxMm];
  double* __restrict sigma_mean = out[kSigmaMeanMm];
  double* __restrict condition = out[kCond];
  double* __restrict v0 = out[kVar0];
  double* __restrict v1 = out[kVar1];
  double* __restrict v2 = out[kVar2];
  const double kInf = std::numeric_limits<double>::infinity();
#pragma omp simd
  for (int m = 0; m < n; ++m) {
    const double l0 = l0p[m] > 0 ? l0p[m] : 0.0;
    const double l1 = l1p[m] > 0 ? l1p[m] : 0.0;
    const double l2 = l2p[m] > 0 ? l2p[m] : 0.0;
    observable[m] = (l2 > 0 && l2 < kInf && l0 > kRelativeObservability * l2) ? 1.0 : 0.0;
    v0[m] = 1.0 / l0;
    v1[m] = 1.0 / l1;
    v2[m] = 1.0 / l2;
    sigma_max[m] = 1e3 * std::sqrt(v0[m]);
    sigma_mean[m] = 1e3 * std::sqrt((v0[m] + v1[m] + v2[m]) / 3.0);
    condition[m] = l2 / l0;
  }
}

}  // namespace information

using namespace information;

namespace {

bool Wants(const std::vector<std::string>& fields, const std::string& name) {
  return std::find(fields.begin(), fields.end(), name) != fields.end();
}

// The float fields in a fixed order.
enum FloatField {
  kResolution,
  kSigmaMax,
  kSigmaMean,
  kAngle,
  kCondition,
  kSigmaMaxSteady,
  kSigmaMeanSteady,
  kFloatFieldCount
};
const char* const kFloatFieldNames[kFloatFieldCount] = {
    "resolution", "sigma_max",        "sigma_mean",       "triangulation_angle",
    "condition",  "sigma_max_steady", "sigma_mean_steady"};

using FloatLeaf = openvdb::FloatTree::LeafNodeType;

// Bytes per voxel of each grid at full density, leaf masks and node overhead included (an OpenVDB
// leaf of 512 voxels carries ~100 bytes of masks and header).
double BytesPerVoxel(const std::string& field) {
  const double overhead = 0.25;
  if (field == "coverage") return 4 + overhead;
  if (field == "cameras") return 8 + overhead;
  return 4 + overhead;  // float fields
}

// The fields an evaluation holds in memory, for its estimate: without kept state the float fields
// of FieldOptions::spilled_fields go to disk as their blocks finish.
std::vector<std::string> HeldFields(const FieldOptions& opt, bool keep) {
  std::vector<std::string> held;
  for (const std::string& f : opt.fields)
    if (keep || f == "coverage" || f == "cameras" || !Wants(opt.spilled_fields, f))
      held.push_back(f);
  return held;
}

// Steady-state statistics from the steady position variances in rows kVar0..kVar2.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void SteadyStatistics(int n, double* const* rows) {
  const double* v0 = rows[kVar0];
  const double* v1 = rows[kVar1];
  const double* v2 = rows[kVar2];
  double* __restrict steady_max = rows[kSteadyMaxMm];
  double* __restrict steady_mean = rows[kSteadyMeanMm];
#pragma omp simd
  for (int m = 0; m < n; ++m) {
    const double a = v0[m] > v1[m] ? v0[m] : v1[m];
    steady_max[m] = 1e3 * std::sqrt(a > v2[m] ? a : v2[m]);
    steady_mean[m] = 1e3 * std::sqrt((v0[m] + v1[m] + v2[m]) / 3.0);
  }
}

// a where mask is all ones, b where it is 0: on the bits. A select of doubles whose arms GCC
// computes only where taken (a division, a subtraction: traps it may not make unconditional under
// -ftrapping-math) stays a branch, and the loop around it is not vectorised.
inline double SelectBits(std::uint64_t mask, double a, double b) {
  std::uint64_t x, y;
  std::memcpy(&x, &a, sizeof(x));
  std::memcpy(&y, &b, sizeof(y));
  const std::uint64_t r = (x & mask) | (y & ~mask);
  double out;
  std::memcpy(&out, &r, sizeof(out));
  return out;
}
inline std::uint64_t MaskOf(bool b) { return -std::uint64_t(b); }

// atan(t) for t >= 0 (+inf allowed) to 2.1e-8 relative (measured against std::atan over
// 1e-12..1e12), branch-free so that it vectorises (both divisions made, SelectBits):
// Cephes' single-precision reduction (t > tan(3 pi/8): pi/2 - atan(1/t); t > tan(pi/8):
// pi/4 + atan((t-1)/(t+1))) and its degree-9 odd minimax polynomial. The angle grid is float.
inline double AtanNonNegative(double t) {
  const std::uint64_t big = MaskOf(t > 2.414213562373095);
  const std::uint64_t mid = MaskOf(t > 0.4142135623730950);
  const double inverse = -1.0 / t, ratio = (t - 1.0) / (t + 1.0);
  const double x = SelectBits(big, inverse, SelectBits(mid, ratio, t));
  const double base = SelectBits(big, 0.5 * kPi, SelectBits(mid, 0.25 * kPi, 0.0));
  const double z = x * x;
  return base +
         (((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z -
          3.33329491539e-1) *
             z * x +
         x;
}

// The camera pairs of a group of voxels in the order TriangulationAngles tries them: by an upper
// bound on the angle a pair can make at any of the voxels, largest first, with the cosine of that
// bound. The voxels lie in a ball (centre, radius); camera a sees it within r_a = asin(radius /
// |C_a - centre|) of the direction u_a to its centre (or anywhere, when the ball reaches the
// camera), so the angle of pair (a, b) at any voxel is at most angle(u_a, u_b) + r_a + r_b (the
// triangle inequality on the sphere). The cosine of that sum comes from the sines and cosines of
// its terms by the angle-addition formulas (no trigonometric call), -1 where the sum reaches pi;
// its rounding (a few 1e-16) is far inside the margin with which TriangulationAngles uses it.
struct PairOrder {
  std::vector<std::int32_t> a, b;
  std::vector<double> cos_bound;  // ascending: the cosine of each pair's largest possible angle
  bool sorted = false;            // false: (a, b) order, every bound -1 (nothing to prune)
};

PairOrder OrderPairs(int camera_count, const Vec3* centres, const Vec3& ball_centre,
                     double ball_radius, const unsigned char* changed, bool exhaustive) {
  PairOrder order;
  // Up to 8 cameras (28 pairs) ordering costs more than it saves: every pair in (a, b) order.
  if (camera_count <= 8 || exhaustive) {
    for (int a = 0; a < camera_count; ++a)
      for (int b = a + 1; b < camera_count; ++b) {
        if (changed && !changed[a] && !changed[b]) continue;
        order.a.push_back(a);
        order.b.push_back(b);
        order.cos_bound.push_back(-1.0);
      }
    return order;
  }
  order.sorted = true;
  struct Cone {
    Vec3 u;
    double cos_r, sin_r;
    bool everywhere;
  };
  std::vector<Cone> cones(camera_count);
  for (int c = 0; c < camera_count; ++c) {
    const Vec3 v = ball_centre - centres[c];
    const double d = v.norm();
    Cone& k = cones[c];
    k.everywhere = !(d > ball_radius * (1 + 1e-9));
    if (k.everywhere) continue;
    k.u = v / d;
    k.sin_r = ball_radius / d;
    k.cos_r = std::sqrt(1 - k.sin_r * k.sin_r);
  }
  struct Entry {
    double cos_bound;
    std::int32_t a, b;
  };
  std::vector<Entry> pairs;
  pairs.reserve(std::size_t(camera_count) * std::max(0, camera_count - 1) / 2);
  for (int a = 0; a < camera_count; ++a)
    for (int b = a + 1; b < camera_count; ++b) {
      if (changed && !changed[a] && !changed[b]) continue;
      const Cone &ka = cones[a], &kb = cones[b];
      double bound = -1.0;
      if (!ka.everywhere && !kb.everywhere) {
        // beta = r_a + r_b (each below pi / 2), then theta + beta.
        const double cos_beta = ka.cos_r * kb.cos_r - ka.sin_r * kb.sin_r;
        const double sin_beta = ka.sin_r * kb.cos_r + ka.cos_r * kb.sin_r;
        const double cos_theta = ka.u.dot(kb.u), sin_theta = ka.u.cross(kb.u).norm();
        const double sin_sum = sin_theta * cos_beta + cos_theta * sin_beta;
        const double cos_sum = cos_theta * cos_beta - sin_theta * sin_beta;
        // The sum lies in [0, 2 pi): past pi where its sine is negative (or zero with cos < 0).
        bound = (sin_sum > 0 || (sin_sum == 0 && cos_sum > 0)) ? cos_sum : -1.0;
      }
      pairs.push_back({bound, a, b});
    }
  std::sort(pairs.begin(), pairs.end(),
            [](const Entry& x, const Entry& y) { return x.cos_bound < y.cos_bound; });
  order.a.reserve(pairs.size());
  order.b.reserve(pairs.size());
  order.cos_bound.reserve(pairs.size());
  for (const Entry& e : pairs) {
    order.a.push_back(e.a);
    order.b.push_back(e.b);
    order.cos_bound.push_back(e.cos_bound);
  }
  return order;
}

// The triangulation angle of `count` voxels at (x, y, z) (block offsets `offset`): the largest
// angle in degrees between two rays from camera centres that see the voxel. `sees[e]` is the
// 512-bit mask of the voxels camera `centres[e]` sees (the block's cameras in rig order). The best
// pair is the one with the smallest dot product of the unit directions, ties to the first pair in
// (a, b) order; it is returned in best_dot / best_a / best_b (indices into `sees`). best_* come in
// as the best pair so far (dot 2 where there is none; with `changed`, the best pair among the
// unchanged cameras), and the pairs of `order` are tried (with `changed`, those with a changed
// camera), keeping the lexicographically smallest (dot, a, b): the same pair, so the same bits, as
// trying all pairs. Pairs come largest bound first, and a tile stops at the first pair whose bound
// cannot beat any of its voxels' best dot (its cosine, less 1e-12 for the dot products' rounding,
// above their largest): every pair left has a dot above each voxel's best, so none would be taken.
// Vectorised over voxels, in tiles of 64 that keep every camera's directions in L1: per camera the
// unit directions (into `dirs`, 3 * 64 per camera, made when a pair first needs them; NaN where the
// camera does not see the voxel, so every comparison with it fails), per camera pair the dot
// product, then the angle as atan2(|cross|, dot) (both keep their relative accuracy, so tiny and
// near-180 degree angles are as exact as at 90). The file is compiled without floating-point
// contraction, so scalar and vector code give the same bits. No per-ray storage. Returns the
// (voxel, pair) dot products computed.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
std::int64_t
TriangulationAngles(int count, const double* x, const double* y, const double* z,
                    const std::int16_t* offset, int camera_count, const std::uint64_t* const* sees,
                    const Vec3* centres, const PairOrder& order, bool from_cache,
                    double* best_dot_io, std::int32_t* best_a_io, std::int32_t* best_b_io,
                    double* dirs, unsigned char* have, float* degrees) {
  constexpr int kTile = 64;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::size_t pair_count = order.a.size();
  std::int64_t tried = 0;
  for (int start = 0; start < count; start += kTile) {
    const int n = std::min(kTile, count - start);
    const double *tx = x + start, *ty = y + start, *tz = z + start;
    const std::int16_t* to = offset + start;
    for (int c = 0; c < camera_count; ++c) have[c] = 0;
    const auto directions = [&](int c) __attribute__((always_inline)) {
      have[c] = 1;
      const double cx = centres[c].x(), cy = centres[c].y(), cz = centres[c].z();
      const std::uint64_t* mask = sees[c];
      double* d = dirs + 3 * kTile * c;
      // The mask bits first, as 0 or NaN to add (GCC vectorises neither the bit gather nor a
      // select after the square root), then the directions in SIMD: 1/|v| + 0 is 1/|v|.
      double unseen[kTile];
      for (int m = 0; m < n; ++m) unseen[m] = (mask[to[m] >> 6] >> (to[m] & 63) & 1) ? 0.0 : nan;
#pragma omp simd
      for (int m = 0; m < n; ++m) {
        const double vx = tx[m] - cx, vy = ty[m] - cy, vz = tz[m] - cz;
        const double inv = 1.0 / std::sqrt(vx * vx + vy * vy + vz * vz) + unseen[m];
        d[m] = vx * inv;
        d[m + kTile] = vy * inv;
        d[m + 2 * kTile] = vz * inv;
      }
    };
    double best_dot[kTile];
    std::int64_t best_a[kTile], best_b[kTile];  // camera indices of the best pair
    double worst = -2.0;                        // the largest best dot of the tile
    for (int m = 0; m < n; ++m) {
      best_dot[m] = best_dot_io[start + m], best_a[m] = best_a_io[start + m],
      best_b[m] = best_b_io[start + m];
      worst = std::max(worst, best_dot[m]);
    }
    for (std::size_t p = 0; p < pair_count; ++p) {
      if (order.cos_bound[p] - 1e-12 > worst) break;
      const std::int64_t a = order.a[p], b = order.b[p];
      if (!have[a]) directions(int(a));
      if (!have[b]) directions(int(b));
      tried += n;
      const double* ad = dirs + 3 * kTile * a;
      const double* bd = dirs + 3 * kTile * b;
      double next_worst = -2.0;
      if (!order.sorted && !from_cache) {
        // Pairs in (a, b) order from no pair: the first pair with the smallest dot is the
        // lexicographically smallest, and `<` alone keeps it.
#pragma omp simd reduction(max : next_worst)
        for (int m = 0; m < n; ++m) {
          const double dot =
              ad[m] * bd[m] + ad[m + kTile] * bd[m + kTile] + ad[m + 2 * kTile] * bd[m + 2 * kTile];
          const bool take = dot < best_dot[m];  // false for NaN: a camera that does not see it
          best_dot[m] = take ? dot : best_dot[m];
          best_a[m] = take ? a : best_a[m];
          best_b[m] = take ? b : best_b[m];
          next_worst = next_worst > best_dot[m] ? next_worst : best_dot[m];
        }
      } else {
#pragma omp simd reduction(max : next_worst)
        for (int m = 0; m < n; ++m) {
          const double dot =
              ad[m] * bd[m] + ad[m + kTile] * bd[m + kTile] + ad[m + 2 * kTile] * bd[m + 2 * kTile];
          const bool take =
              dot < best_dot[m] ||
              (dot == best_dot[m] && (a < best_a[m] || (a == best_a[m] && b < best_b[m])));
          best_dot[m] = take ? dot : best_dot[m];
          best_a[m] = take ? a : best_a[m];
          best_b[m] = take ? b : best_b[m];
          next_worst = next_worst > best_dot[m] ? next_worst : best_dot[m];
        }
      }
      worst = next_worst;
    }
    for (int m = 0; m < n; ++m) {
      if (!have[best_a[m]]) directions(int(best_a[m]));
      if (!have[best_b[m]]) directions(int(best_b[m]));
    }
    // The best pairs' directions gathered first (GCC does not vectorise the indexed loads), then
    // the angles in SIMD.
    double pair_dirs[6][kTile];
    for (int m = 0; m < n; ++m) {
      const double* ad = dirs + 3 * kTile * best_a[m] + m;
      const double* bd = dirs + 3 * kTile * best_b[m] + m;
      for (int k = 0; k < 3; ++k) {
        pair_dirs[k][m] = ad[k * kTile];
        pair_dirs[3 + k][m] = bd[k * kTile];
      }
    }
#pragma omp simd
    for (int m = 0; m < n; ++m) {
      const double ax = pair_dirs[0][m], ay = pair_dirs[1][m], az = pair_dirs[2][m];
      const double bx = pair_dirs[3][m], by = pair_dirs[4][m], bz = pair_dirs[5][m];
      const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
      const double dot = best_dot[m];
      const double angle = AtanNonNegative(std::sqrt(cx * cx + cy * cy + cz * cz) / std::abs(dot));
      const double obtuse = kPi - angle;
      degrees[start + m] =
          static_cast<float>(SelectBits(MaskOf(dot < 0), obtuse, angle) * (180.0 / kPi));
    }
    for (int m = 0; m < n; ++m) {
      best_dot_io[start + m] = best_dot[m];
      best_a_io[start + m] = static_cast<std::int32_t>(best_a[m]);
      best_b_io[start + m] = static_cast<std::int32_t>(best_b[m]);
    }
  }
  return tried;
}

// The compacted camera-frame Jacobians of a camera's seen voxels and their information.
struct InformationScratch {
  alignas(64) double jac[6][512];
  alignas(64) double info[6][512];
  alignas(64) std::uint8_t band[512];
};

// The information contributions of n seen voxels from their Jacobians (s->jac), with whitened
// rotation rw: AddCameraInformation on zeros, the same expressions in the same order (the file is
// compiled without contraction), so the same bits, into s->info; and each one's Band() into
// s->band. Vectorised over the voxels.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void InformationLanes(int n, const double* rw, InformationScratch* s) {
  const double* j0 = s->jac[0];
  const double* j1 = s->jac[1];
  const double* j2 = s->jac[2];
  const double* j3 = s->jac[3];
  const double* j4 = s->jac[4];
  const double* j5 = s->jac[5];
  double* __restrict i0 = s->info[0];
  double* __restrict i1 = s->info[1];
  double* __restrict i2 = s->info[2];
  double* __restrict i3 = s->info[3];
  double* __restrict i4 = s->info[4];
  double* __restrict i5 = s->info[5];
  std::uint8_t* __restrict band = s->band;
  double R[9];
  for (int k = 0; k < 9; ++k) R[k] = rw[k];
#pragma omp simd
  for (int m = 0; m < n; ++m) {
    const double a00 = j0[m] * R[0] + j1[m] * R[3] + j2[m] * R[6];
    const double a01 = j0[m] * R[1] + j1[m] * R[4] + j2[m] * R[7];
    const double a02 = j0[m] * R[2] + j1[m] * R[5] + j2[m] * R[8];
    const double a10 = j3[m] * R[0] + j4[m] * R[3] + j5[m] * R[6];
    const double a11 = j3[m] * R[1] + j4[m] * R[4] + j5[m] * R[7];
    const double a12 = j3[m] * R[2] + j4[m] * R[5] + j5[m] * R[8];
    const double c0 = 0.0 + (a00 * a00 + a10 * a10);
    const double c1 = 0.0 + (a00 * a01 + a10 * a11);
    const double c2 = 0.0 + (a00 * a02 + a10 * a12);
    const double c3 = 0.0 + (a01 * a01 + a11 * a11);
    const double c4 = 0.0 + (a01 * a02 + a11 * a12);
    const double c5 = 0.0 + (a02 * a02 + a12 * a12);
    i0[m] = c0;
    i1[m] = c1;
    i2[m] = c2;
    i3[m] = c3;
    i4[m] = c4;
    i5[m] = c5;
  }
  // The bands in a loop of their own: with their byte stores in the loop above GCC chose vectors
  // by the bytes' width and gave the doubles half of AVX-512's lanes.
#pragma omp simd
  for (int m = 0; m < n; ++m) band[m] = Band(i0[m], i1[m], i2[m], i3[m], i4[m], i5[m]);
}

// ---------------------------------------------------------------------------------------------
// The evaluator's state.

constexpr int kWords = 8;  // 512 voxels of a block as bits

using Bits = std::array<std::uint64_t, kWords>;
inline void SetBit(Bits& b, int o) { b[o >> 6] |= std::uint64_t{1} << (o & 63); }
inline bool TestBit(const Bits& b, int o) { return (b[o >> 6] >> (o & 63) & 1) != 0; }
// Inline population count (no library call, no CPU dispatch) for sparse masked walks.
inline int PopcountInline(std::uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
}

// What one camera sees of one block: the voxels (bits) and, per seen voxel in ascending offset,
// its information contribution A^T A (six doubles, AddCameraInformation on zeros) and pixel
// density.
// An allocator whose value-initialisation leaves trivial types uninitialised: resize() without
// zeroing, for caches that are written before they are read.
template <class T>
struct DefaultInit : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInit<U>;
  };
  DefaultInit() = default;
  template <class U>
  DefaultInit(const DefaultInit<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

struct CameraEntry {
  std::int32_t camera = 0;
  std::int32_t rays = 0;  // occlusion segments cast
  std::int32_t seen = 0;  // bits set
  Bits bits{};
  std::array<std::int16_t, kWords> before{};  // seen voxels in the words before
  // Per seen voxel (ascending offset), each written in full where it is made (Cast, CastAgain):
  // not zero-filled first.
  std::vector<double, DefaultInit<double>> information;       // with an information field
  std::vector<std::uint8_t, DefaultInit<std::uint8_t>> band;  // with one: Band() of each
  std::vector<float, DefaultInit<float>> density;             // with resolution
  double Bytes() const {
    return sizeof(CameraEntry) + information.capacity() * sizeof(double) + band.capacity() +
           density.capacity() * sizeof(float);
  }
};

// The entry of `camera` among `entries` (ascending camera), or nullptr.
const CameraEntry* FindEntry(const std::vector<CameraEntry>& entries, int camera) {
  const auto it = std::lower_bound(entries.begin(), entries.end(), camera,
                                   [](const CameraEntry& e, int c) { return e.camera < c; });
  return it != entries.end() && it->camera == camera ? &*it : nullptr;
}
// The same among pointers to entries (a block's view).
const CameraEntry* FindEntry(const std::vector<const CameraEntry*>& entries, int camera) {
  const auto it = std::lower_bound(entries.begin(), entries.end(), camera,
                                   [](const CameraEntry* e, int c) { return e->camera < c; });
  return it != entries.end() && (*it)->camera == camera ? *it : nullptr;
}

enum VoxelStatus : std::uint8_t { kUnseen, kSeenOnly, kTriangulable, kUnobservable };

struct BlockState {
  std::vector<std::int32_t> candidates;  // cameras whose frustum may meet the block, ascending
  std::vector<CameraEntry> entries;      // cameras that cast rays here, ascending
  // Per-voxel caches by offset (kept with keep_state): coverage, status, sigma_max, steady max.
  std::vector<std::int32_t> coverage;
  std::vector<std::uint8_t> status;
  std::vector<float> sigma_max, sigma_steady;
  // The best camera pair of each triangulable voxel (its smallest direction dot product and the
  // cameras' rig indices; a = -1 where none), with triangulation_angle.
  std::vector<double> pair_dot;
  std::vector<std::int32_t> pair_a, pair_b;
  // With resolution: the best pixel density and a camera that has it (-1: none).
  std::vector<float> best_density;
  std::vector<std::int32_t> best_camera;
  // With an information field: the exact sums, their band (kNotExact: summed in double, or no
  // camera) and how many contributions lie in that band.
  std::vector<SumLimbs, DefaultInit<SumLimbs>> sums;
  std::vector<std::uint8_t> sum_band;
  std::vector<std::int32_t> band_count;
  // Summary.
  std::vector<std::int64_t> histogram;  // [k] = free voxels seen by k cameras
  std::int64_t seen = 0, triangulable = 0, unobservable = 0;
  std::vector<float> sigma_list, steady_list;  // triangulable voxels in ascending offset
  std::vector<Ray> rays;                       // with record_rays
  // Without kept state the entries go as soon as the block is derived; what the statistics need
  // of them stays: per camera that cast rays here, its rays and seen voxels (ascending camera).
  struct CameraCount {
    std::int32_t camera = 0, rays = 0, seen = 0;
  };
  std::vector<CameraCount> counts;
};

// What a rig needs per camera during an update.
struct RigData {
  std::unique_ptr<VisibilityTester> tester;
  std::unique_ptr<FrustumCuller> culler;
  std::vector<std::array<double, 9>> whitened;  // R_camera_from_world / sigma_c
  std::vector<Vec3> centres;
  int enabled = 0;
};

// A block's new leaves, made in the parallel phase and put into the grids in the serial one.
// An update rewrites the grids' own leaves in place where they exist (not owned here).
struct BlockLeaves {
  openvdb::Int32Tree::LeafNodeType* coverage = nullptr;
  bool coverage_owned = false;
  bool coverage_tile = false;
  std::array<FloatLeaf*, kFloatFieldCount> floats{};
  std::array<bool, kFloatFieldCount> float_owned{};
  std::array<bool, kFloatFieldCount> remove_float{};
  std::vector<std::pair<int, openvdb::BoolTree::LeafNodeType*>> visible;  // changed cameras
  // Voxel o of every uncertainty field (those after resolution): inactive, 0.
  void ClearUncertainty(int o) {
    for (int f = kResolution + 1; f < kFloatFieldCount; ++f)
      if (floats[f]) floats[f]->setValueOff(o, 0.0f);
  }
  void Free() {
    if (coverage_owned) delete coverage;
    for (int f = 0; f < kFloatFieldCount; ++f)
      if (float_owned[f]) delete floats[f];
    for (auto& v : visible) delete v.second;
  }
};

// The working arrays of one FieldEvaluator::State::Derive: the dirty voxels' coverage, the voxels
// to re-sum, and the triangulation candidates with their information and statistics.
struct DeriveScratch {
  // Per dirty voxel: coverage, density, information in rig order.
  std::array<std::array<double, 512>, 6> upper;
  std::array<std::array<double, 512>, 3> eigenvalue;
  std::array<unsigned char, 512> converged;
  std::array<std::int16_t, 512> candidate;
  std::array<double, 512> cand_x, cand_y, cand_z;
  std::array<float, 512> angle_deg;
  std::array<std::array<double, 512>, kStatRows> stats;
  int candidate_count = 0;
  std::array<std::int32_t, 512> cover;
  Bits rescan_density{}, rescan_info{};
  // Voxels summed in double (rig order), by offset; rarely any.
  Bits in_double{};
  std::vector<std::array<double, 6>> double_sum;
  std::array<std::int16_t, 512> double_index;
  // One camera's (voxel, contribution index) pairs for AccumulateLimbList.
  std::array<std::int16_t, 512> list_voxel, list_index;
};

// The cone from an eye around a box's bounding ball: the box, the ball's centre less the eye, its
// length and radius, the sine and cosine of the half-angle (the eye inside the ball: `inside`).
// Made once per (eye, box) and compared many times (ConesMayMeet).
struct EyeCone {
  Vec3 eye;
  Aabb box;
  Vec3 axis;
  double length = 0, radius = 0, sine = 0, cosine = 0;
  bool inside = false;
};

EyeCone ConeOf(const Vec3& eye, const Aabb& box) {
  EyeCone c;
  c.eye = eye;
  c.box = box;
  c.axis = 0.5 * (box.min + box.max) - eye;
  c.radius = 0.5 * (box.max - box.min).norm();
  c.length = c.axis.norm();
  c.inside = c.length <= c.radius;
  if (!c.inside) {
    c.sine = c.radius / c.length;
    c.cosine = std::sqrt(std::max(0.0, 1 - c.sine * c.sine));
  }
  return c;
}

// Whether a segment from the eye to a point of `segments`' box can meet `moved`'s box (the same
// eye; conservative): the convex hull of the eye and the box against the moved box, along the
// world axes, and the cones around the two bounding balls. The cones' half-angles a and b (both
// in [0, pi/2)) and the angle t between their axes: they meet when t <= a + b, that is cos t >=
// cos(a + b) = cos a cos b - sin a sin b (cos falls over [0, pi]), with a margin far above the
// round-off.
inline bool ConesMayMeet(const EyeCone& segments, const EyeCone& moved) {
  for (int k = 0; k < 3; ++k) {
    const double lo = std::min(segments.eye[k], segments.box.min[k]),
                 hi = std::max(segments.eye[k], segments.box.max[k]);
    if (hi < moved.box.min[k] || lo > moved.box.max[k]) return false;
  }
  if (segments.inside || moved.inside) return true;  // the eye inside a ball
  if (moved.length - moved.radius > segments.length + segments.radius)
    return false;  // the moved box beyond the segments' ends
  return segments.axis.dot(moved.axis) >=
         (segments.cosine * moved.cosine - segments.sine * moved.sine - 1e-9) *
             (segments.length * moved.length);
}

// Segments from one origin: unit directions and their [t_near, t_far], by point.
struct SegmentArrays {
  const double *dx, *dy, *dz, *t_near, *t_far;
  Vec3 origin;
};

// Per point p in [begin, end) of `batch`: whether its segment (origin, unit direction, [t_near,
// t_far]) meets one of `boxes` (the slab test; points out of view get garbage). Box by box over all
// points, vectorised.
__attribute__((target_clones("avx512f", "avx2", "default"))) void SegmentsMeetBoxes(
    const SegmentArrays& batch, int begin, int end, const std::vector<Aabb>& boxes,
    std::uint8_t* meets) {
  std::fill(meets + begin, meets + end, std::uint8_t{0});
  if (boxes.empty()) return;
  alignas(64) double inv[3][512];
  alignas(64) std::int64_t hit[512];  // lanes as wide as the doubles'
  std::fill(hit + begin, hit + end, std::int64_t{0});
  const double* d[3] = {batch.dx, batch.dy, batch.dz};
  // Through restrict locals: a store to `meets` (bytes) could change `batch`'s pointers, so GCC
  // would reload them per point and not vectorise.
  const double* __restrict t_near = batch.t_near;
  const double* __restrict t_far = batch.t_far;
  std::uint8_t* __restrict out = meets;
  for (int k = 0; k < 3; ++k)
#pragma omp simd
    for (int p = begin; p < end; ++p) inv[k][p] = 1.0 / d[k][p];  // +-inf along an axis
  for (const Aabb& box : boxes) {
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      // Never exactly 0 (an origin on a face, widened outwards by the least double): 0 times an
      // infinite inverse would be NaN.
      const double tiny = std::numeric_limits<double>::denorm_min();
      lo[k] = box.min[k] - batch.origin[k];
      hi[k] = box.max[k] - batch.origin[k];
      if (lo[k] == 0.0) lo[k] = -tiny;
      if (hi[k] == 0.0) hi[k] = tiny;
    }
#pragma omp simd
    for (int p = begin; p < end; ++p) {
      double t0 = t_near[p], t1 = t_far[p];
#pragma GCC unroll 3
      for (int k = 0; k < 3; ++k) {
        // A direction of 0 along k: the slab's times are -inf..inf when the origin is inside it,
        // else both +inf or both -inf (a miss).
        const double ta = lo[k] * inv[k][p], tb = hi[k] * inv[k][p];
        const double near = ta < tb ? ta : tb, far = ta < tb ? tb : ta;
        t0 = near > t0 ? near : t0;
        t1 = far < t1 ? far : t1;
      }
      hit[p] |= std::int64_t(t0 <= t1);
    }
  }
  for (int p = begin; p < end; ++p) out[p] = static_cast<std::uint8_t>(hit[p]);
}

// Per point in view of `batch` (at `offset` in the block; octant k's points in [start[k],
// start[k + 1])): whether its segment meets one of its octant's moved boxes where they are now
// (`meets_after`), and, only for the points `seen` did not see that none meets now, where they
// were (`meets_before`, gathered; unset for the others, whose answers do not depend on it).
void MeetMovedBoxes(const VisibilityTester::GeometryBatch& batch, const std::int16_t* offset,
                    const std::array<int, 9>& start,
                    const std::array<std::vector<Aabb>, 8>& near_after,
                    const std::array<std::vector<Aabb>, 8>& near_before, const Bits& seen,
                    std::uint8_t* meets_after, std::uint8_t* meets_before) {
  std::array<std::uint8_t, 512> in_view{};
  for (int i = 0; i < batch.count; ++i) in_view[batch.index[i]] = 1;
  const SegmentArrays all{batch.dx, batch.dy, batch.dz, batch.t_near, batch.t_far, batch.origin};
  for (int k = 0; k < 8; ++k) {
    if (start[k + 1] == start[k]) continue;
    SegmentsMeetBoxes(all, start[k], start[k + 1], near_after[k], meets_after);
    if (near_before[k].empty()) continue;
    thread_local std::array<double, 512> gx, gy, gz, gn, gf;
    std::array<std::int16_t, 512> picked;
    int g = 0;
    for (int q = start[k]; q < start[k + 1]; ++q) {
      if (!in_view[q] || meets_after[q] || TestBit(seen, offset[q])) continue;
      gx[g] = batch.dx[q];
      gy[g] = batch.dy[q];
      gz[g] = batch.dz[q];
      gn[g] = batch.t_near[q];
      gf[g] = batch.t_far[q];
      picked[g++] = static_cast<std::int16_t>(q);
    }
    std::array<std::uint8_t, 512> meets;
    SegmentsMeetBoxes(
        SegmentArrays{gx.data(), gy.data(), gz.data(), gn.data(), gf.data(), batch.origin}, 0, g,
        near_before[k], meets.data());
    for (int j = 0; j < g; ++j) meets_before[picked[j]] = meets[j];
  }
}

}  // namespace

struct FieldEvaluator::State {
  // The scene and its caster as of the last update (UpdateScene replaces them).
  const Scene* scene;
  const RayCaster* caster;
  FieldOptions options;
  bool keep = true;
  std::string file;
  double scene_scale = 0;

  std::vector<Block> blocks;  // the active set (free voxels; Block::cameras unused)
  std::vector<BlockState> states;
  std::vector<std::uint8_t> owned;  // with a partition: the blocks this process evaluates
  ActiveSetStats active_stats;
  double active_set_seconds = 0;
  Rig rig;                                                          // as of the last update
  std::array<openvdb::FloatGrid*, kFloatFieldCount> float_grids{};  // in fields, by FloatField
  // FieldOptions::spilled_fields of a one-shot evaluation: where their leaves go, by FloatField.
  std::array<std::shared_ptr<LeafSpill>, kFloatFieldCount> spills{};
  bool evaluated = false;
  Fields fields;

  bool want_coverage = false, want_cameras = false, want_resolution = false;
  bool want_static = false, want_steady = false, want_angle = false;
  bool want_information = false, want_jacobian = false;
  bool list_sigma = true, list_steady = true;  // FieldStats' sigma lists made
  std::array<bool, kFloatFieldCount> want_float{};
  MotionModel motion;
  double frame_period = 0;
  // (voxel, camera pair) dot products of triangulation_angle in the current update, and all the
  // pairs there were to try.
  mutable std::atomic<std::int64_t> angle_pairs_tried{0}, angle_pairs_all{0};
  // With options.time_phases: nanoseconds in each of FieldStats::Phases' steps, in its order.
  enum Phase { kContributions, kSums, kEigenvalues, kAngles, kPhaseCount };
  mutable std::array<std::atomic<std::int64_t>, kPhaseCount> phase_ns{};
  // Adds the time from its construction to its destruction to phase_ns[phase] (when timed).
  class PhaseTimer {
   public:
    PhaseTimer(const State& s, Phase phase)
        : s_(s), phase_(phase), on_(s.options.time_phases), start_(on_ ? Now() : 0) {}
    ~PhaseTimer() {
      if (on_) s_.phase_ns[phase_] += Now() - start_;
    }

   private:
    static std::int64_t Now() {
      return std::chrono::duration_cast<std::chrono::nanoseconds>(
                 std::chrono::steady_clock::now().time_since_epoch())
          .count();
    }
    const State& s_;
    Phase phase_;
    bool on_;
    std::int64_t start_;
  };

  State(const Scene& s, const RayCaster& c) : scene(&s), caster(&c) {}

  RigData Prepare(const Rig& rig) const;
  // A block's free voxels (x, y, z loops, so offsets ascend): their centres in three arrays for
  // the vectorised geometric test, and their offsets in the block.
  struct BlockPoints {
    int count = 0;
    alignas(64) std::array<double, 512> x, y, z;
    std::array<std::int16_t, 512> offset;
    std::array<Aabb, 8> octant;  // of the points in each octant (4^3 voxels) of the block
  };
  void Points(const Block& block, BlockPoints* points) const;
  // A scene update's view of a block cast again: the camera's previous view of it and the moved
  // boxes its segments may meet.
  struct Again {
    // What moved, where it was and where it is: the boxes' cones from the camera (ConeOf).
    const std::vector<EyeCone>* before = nullptr;
    const std::vector<EyeCone>* after = nullptr;
  };
  void Cast(const BlockPoints& points, int camera, const RigData& rd, CameraEntry* entry,
            std::vector<Ray>* rays) const;
  // A scene update's Cast of a camera whose view `was` of the block may have changed: only the
  // block's octants whose segments can meet a moved box are tested again, and of their segments
  // only those whose answer can have changed are cast (returns how many). The contributions of
  // the voxels seen before are copied (the same bits), the newly seen ones' computed; `entry`
  // holds only the bits when nothing is seen differently.
  int CastAgain(const BlockPoints& points, int camera, const RigData& rd, const CameraEntry& was,
                const Again& again, CameraEntry* entry) const;
  // `occlusion_only`: a scene update, whose changed cameras see the voxels they saw before and
  // still see with the same contributions (CastAgain copies them).
  void Derive(const Block& block, const BlockState& old, std::vector<const CameraEntry*> view,
              const Bits& dirty, const std::vector<std::uint8_t>& is_changed,
              const std::vector<Vec3>& centres, BlockState* next, BlockLeaves* leaves,
              bool in_place, bool occlusion_only);
  // Derive's steps, in its order.
  void PrepareCaches(const BlockState& old, bool fresh, bool in_place, BlockState* next) const;
  void PrepareLeaves(const openvdb::Coord& origin, bool in_place, BlockLeaves* leaves);
  void SumChangedCameras(const BlockState& old, const std::vector<const CameraEntry*>& view,
                         const Bits& dirty, const std::vector<std::uint8_t>& is_changed,
                         bool occlusion_only, BlockState* next, DeriveScratch* scratch) const;
  void Rescan(const std::vector<const CameraEntry*>& view, const Bits& dirty, bool fresh,
              BlockState* next, DeriveScratch* scratch) const;
  void WriteDirtyVoxels(const Block& block, const Bits& dirty, BlockState* next,
                        BlockLeaves* leaves, DeriveScratch* scratch) const;
  void CandidateStatistics(const std::vector<const CameraEntry*>& view,
                           const std::vector<std::uint8_t>& is_changed,
                           const std::vector<Vec3>& centres, bool fresh, BlockState* next,
                           DeriveScratch* scratch) const;
  void CandidateAngles(const std::vector<const CameraEntry*>& view,
                       const std::vector<std::uint8_t>& is_changed,
                       const std::vector<Vec3>& centres, bool fresh, BlockState* next,
                       DeriveScratch* scratch) const;
  void PutStatistics(BlockState* next, BlockLeaves* leaves, const DeriveScratch& scratch) const;
  void SummariseBlock(const Block& block, BlockState* next) const;
  void Totals(FieldStats* stats, int camera_count, int enabled) const;
  void ResetGrids(int camera_count);
};

namespace {

template <typename GridPtr>
void MakeGrid(GridPtr& grid, const char* name, const openvdb::math::Transform::Ptr& transform) {
  grid = std::decay_t<decltype(*grid)>::create(typename std::decay_t<decltype(*grid)>::ValueType());
  grid->setName(name);
  grid->setTransform(transform);
}

}  // namespace

void FieldEvaluator::State::ResetGrids(int camera_count) {
  Fields::Impl& g = fields.impl();
  g.transform = openvdb::math::Transform::createLinearTransform(scene->study.voxel_size);
  const VoxelLattice& lattice = fields.lattice;
  g.transform->postTranslate(
      openvdb::Vec3d(lattice.origin.x(), lattice.origin.y(), lattice.origin.z()));
  g.coverage.reset();
  g.floats.clear();
  g.visible.clear();
  if (want_coverage) MakeGrid(g.coverage, kCoverageGrid, g.transform);
  for (int f = 0; f < kFloatFieldCount; ++f) {
    if (!want_float[f]) continue;
    openvdb::FloatGrid::Ptr grid;
    MakeGrid(grid, kFloatFieldNames[f], g.transform);
    g.floats[kFloatFieldNames[f]] = grid;
    float_grids[f] = grid.get();
  }
  g.spilled.clear();
  for (int f = 0; f < kFloatFieldCount; ++f)
    spills[f] = want_float[f] && !keep && Wants(options.spilled_fields, kFloatFieldNames[f])
                    ? std::make_shared<LeafSpill>(options.spill_folder, options.spill_blame)
                    : nullptr;
  if (want_cameras) {
    g.visible.resize(camera_count);
    for (auto& v : g.visible) MakeGrid(v, "visible", g.transform);
  }
}

RigData FieldEvaluator::State::Prepare(const Rig& r) const {
  RigData rd;
  rd.tester = std::make_unique<VisibilityTester>(r.cameras, *caster, scene_scale);
  rd.culler = std::make_unique<FrustumCuller>(r.cameras);
  rd.whitened.resize(r.cameras.size());
  for (std::size_t c = 0; c < r.cameras.size(); ++c) {
    const Camera& cam = r.cameras[c];
    const double sigma = cam.pixel_sigma > 0 ? cam.pixel_sigma : scene->study.pixel_sigma;
    WhitenedRotation(rd.tester->camera_rotation(int(c)), sigma, rd.whitened[c].data());
    rd.centres.push_back(cam.center());
  }
  rd.enabled = r.enabled_count();
  return rd;
}

// Per octant of a block (its box; empty: no free voxel), the moved boxes of `again` (where they
// are, where they were) that the segments from `eye` to it may meet (ConesMayMeet).
static void NearOctantBoxes(const std::array<Aabb, 8>& octants, const Vec3& eye,
                            const FieldEvaluator::State::Again& again,
                            std::array<std::vector<Aabb>, 8>* near_after,
                            std::array<std::vector<Aabb>, 8>* near_before) {
  for (int k = 0; k < 8; ++k) {
    (*near_after)[k].clear();
    (*near_before)[k].clear();
    if (octants[k].empty()) continue;
    const EyeCone octant = ConeOf(eye, octants[k]);
    for (const EyeCone& moved : *again.after)
      if (ConesMayMeet(octant, moved)) (*near_after)[k].push_back(moved.box);
    for (const EyeCone& moved : *again.before)
      if (ConesMayMeet(octant, moved)) (*near_before)[k].push_back(moved.box);
  }
}

// The octant (4^3 voxels) of a block offset.
inline int OctantOf(int o) { return ((o >> 8) << 2) | (((o >> 5) & 1) << 1) | ((o >> 2) & 1); }

void FieldEvaluator::State::Points(const Block& block, BlockPoints* points) const {
  const VoxelLattice& lattice = fields.lattice;
  const Eigen::Vector3i& origin = block.origin;
  const Eigen::Vector3i& extent = block.extent;
  // Centres per axis (Center is per component: the same doubles), then the free voxels'.
  std::array<double, 8> cx{}, cy{}, cz{};
  for (int a = 0; a < 8; ++a) {
    const Vec3 c = lattice.Center(origin.x() + a, origin.y() + a, origin.z() + a);
    cx[a] = c.x();
    cy[a] = c.y();
    cz[a] = c.z();
  }
  int n = 0;
  for (int x = 0; x < extent.x(); ++x)
    for (int y = 0; y < extent.y(); ++y)
      for (int z = 0; z < extent.z(); ++z) {
        if (!block.IsFree(x, y, z)) continue;
        points->x[n] = cx[x];
        points->y[n] = cy[y];
        points->z[n] = cz[z];
        points->offset[n] = static_cast<std::int16_t>(Block::Offset(x, y, z));
        ++n;
      }
  points->count = n;
  // Each octant's box: its free voxels' lowest and highest centres, one extent per axis, in
  // locals octant by octant (updating a per-octant array point by point was a store-forwarding
  // chain).
  for (int k = 0; k < 8; ++k) {
    points->octant[k] = Aabb();
    const int x0 = 4 * (k >> 2), y0 = 4 * ((k >> 1) & 1), z0 = 4 * (k & 1);
    int lo[3] = {8, 8, 8}, hi[3] = {-1, -1, -1};
    for (int x = x0; x < std::min(x0 + 4, extent.x()); ++x)
      for (int y = y0; y < std::min(y0 + 4, extent.y()); ++y)
        for (int z = z0; z < std::min(z0 + 4, extent.z()); ++z) {
          if (!block.IsFree(x, y, z)) continue;
          lo[0] = std::min(lo[0], x), lo[1] = std::min(lo[1], y), lo[2] = std::min(lo[2], z);
          hi[0] = std::max(hi[0], x), hi[1] = std::max(hi[1], y), hi[2] = std::max(hi[2], z);
        }
    if (hi[0] < 0) continue;
    points->octant[k].Extend(Vec3(cx[lo[0]], cy[lo[1]], cz[lo[2]]));
    points->octant[k].Extend(Vec3(cx[hi[0]], cy[hi[1]], cz[hi[2]]));
  }
}

// Camera `camera`'s view of a block: the geometric tests first (vectorised over the block's free
// voxels), then the segments in view traced together as coherent packets (one origin,
// neighbouring directions) straight from the test's arrays.
void FieldEvaluator::State::Cast(const BlockPoints& points, int camera, const RigData& rd,
                                 CameraEntry* entry, std::vector<Ray>* rays) const {
  std::array<std::uint8_t, 512> occluded;
  thread_local VisibilityTester::GeometryBatch batch;  // 46 kB: not on the worker's stack
  rd.tester->TestGeometryBatch(camera, points.count, points.x.data(), points.y.data(),
                               points.z.data(), &batch);
  const std::size_t n = static_cast<std::size_t>(batch.count);
  caster->OccludedFan(batch.fan(), n, occluded.data());
  if (rays)
    for (std::size_t i = 0; i < n; ++i) rays->push_back(batch.segment(int(i)));
  entry->camera = camera;
  entry->rays = static_cast<std::int32_t>(n);
  // Offsets come in ascending order (x, y, z loops, Offset = 64 x + 8 y + z).
  thread_local InformationScratch scratch;  // 49 kB: not on the worker's stack
  const bool want_jacobians = want_information || want_resolution;
  int visible = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (occluded[i]) continue;
    const int p = batch.index[i];
    SetBit(entry->bits, points.offset[p]);
    if (want_jacobians)
      for (int r = 0; r < 6; ++r) scratch.jac[r][visible] = batch.jac[r][p];
    ++visible;
  }
  entry->seen = visible;
  if (want_resolution && visible > 0) {
    const double* const jac[6] = {scratch.jac[0], scratch.jac[1], scratch.jac[2],
                                  scratch.jac[3], scratch.jac[4], scratch.jac[5]};
    entry->density.resize(std::size_t(visible));
    PixelDensityLanes(visible, jac, entry->density.data());
  }
  if (want_information && visible > 0) {
    const PhaseTimer timer(*this, kContributions);
    InformationLanes(visible, rd.whitened[camera].data(), &scratch);
    entry->information.resize(6 * std::size_t(visible));
    entry->band.resize(std::size_t(visible));
    double* info = entry->information.data();
    for (int j = 0; j < visible; ++j)
      for (int r = 0; r < 6; ++r) info[6 * j + r] = scratch.info[r][j];
    std::memcpy(entry->band.data(), scratch.band, std::size_t(visible));
  }
  int before = 0;
  for (int w = 0; w < kWords; ++w) {
    entry->before[w] = static_cast<std::int16_t>(before);
    before += __builtin_popcountll(entry->bits[w]);
  }
}

int FieldEvaluator::State::CastAgain(const BlockPoints& points, int camera, const RigData& rd,
                                     const CameraEntry& was, const Again& again,
                                     CameraEntry* entry) const {
  entry->camera = camera;
  entry->rays = was.rays;  // the segments in view: geometry, unchanged
  entry->bits = was.bits;
  // The octants whose segments can meet a moved box; only their points are looked at again.
  // Per octant, the moved boxes (where they are, where they were) its segments may meet; the
  // points of the octants with any, octant by octant (ascending offset within each).
  thread_local std::array<std::vector<Aabb>, 8> near_after, near_before;
  NearOctantBoxes(points.octant, rd.centres[camera], again, &near_after, &near_before);
  std::array<int, 9> start{};
  std::array<int, 8> fill{};
  for (int p = 0; p < points.count; ++p) ++fill[OctantOf(points.offset[p])];
  for (int k = 0; k < 8; ++k) {
    const bool flagged = !near_after[k].empty() || !near_before[k].empty();
    start[k + 1] = start[k] + (flagged ? fill[k] : 0);
    fill[k] = flagged ? start[k] : -1;
  }
  thread_local BlockPoints sub;
  const int m = start[8];
  for (int p = 0; p < points.count; ++p) {
    int& at = fill[OctantOf(points.offset[p])];
    if (at < 0) continue;
    sub.x[at] = points.x[p];
    sub.y[at] = points.y[p];
    sub.z[at] = points.z[p];
    sub.offset[at++] = points.offset[p];
  }
  sub.count = m;
  if (m == 0) return 0;
  thread_local VisibilityTester::GeometryBatch batch;
  rd.tester->TestGeometryBatch(camera, m, sub.x.data(), sub.y.data(), sub.z.data(), &batch);
  const int n = batch.count;
  // Cast only the segments whose answer can have changed: those that meet a moved box where it
  // is now, and the occluded ones that meet one where it was; the others keep their answer.
  std::array<std::uint8_t, 512> meets_after, meets_before, occluded;
  MeetMovedBoxes(batch, sub.offset.data(), start, near_after, near_before, was.bits,
                 meets_after.data(), meets_before.data());
  std::array<std::int16_t, 512> subset, where;
  int cast = 0;
  for (int i = 0; i < n; ++i) {
    const int q = batch.index[i];
    const bool seen = TestBit(was.bits, sub.offset[q]);
    if (meets_after[q] || (!seen && meets_before[q])) {
      subset[cast] = batch.index[i];
      where[cast++] = static_cast<std::int16_t>(i);
    } else {
      occluded[i] = seen ? 0 : 1;
    }
  }
  if (cast > 0) {
    RayCaster::Fan fan = batch.fan();
    fan.index = subset.data();
    std::array<std::uint8_t, 512> answer;
    caster->OccludedFan(fan, std::size_t(cast), answer.data());
    for (int k = 0; k < cast; ++k) occluded[where[k]] = answer[k];
  }
  for (int i = 0; i < n; ++i) {
    const int o = sub.offset[batch.index[i]];
    if (occluded[i])
      entry->bits[o >> 6] &= ~(std::uint64_t{1} << (o & 63));
    else
      SetBit(entry->bits, o);
  }
  if (entry->bits == was.bits) return cast;  // nothing seen differently: the view is kept
  // The newly seen voxels' contributions (in the batch's order, octant by octant: fresh_at maps
  // an offset to its place); the others' are the previous view's, the same bits.
  thread_local InformationScratch scratch;
  std::array<float, 512> density;
  std::array<std::int16_t, 512> fresh_at;
  int fresh = 0;
  for (int i = 0; i < n; ++i) {
    const int q = batch.index[i];
    if (occluded[i] || TestBit(was.bits, sub.offset[q])) continue;
    if (want_information || want_resolution)
      for (int r = 0; r < 6; ++r) scratch.jac[r][fresh] = batch.jac[r][q];
    fresh_at[sub.offset[q]] = static_cast<std::int16_t>(fresh++);
  }
  if (want_resolution && fresh > 0) {
    const double* const jac[6] = {scratch.jac[0], scratch.jac[1], scratch.jac[2],
                                  scratch.jac[3], scratch.jac[4], scratch.jac[5]};
    PixelDensityLanes(fresh, jac, density.data());
  }
  if (want_information && fresh > 0) InformationLanes(fresh, rd.whitened[camera].data(), &scratch);
  int seen = 0;
  for (std::uint64_t w : entry->bits) seen += __builtin_popcountll(w);
  entry->seen = seen;
  if (want_information) {
    entry->information.resize(6 * std::size_t(seen));
    entry->band.resize(std::size_t(seen));
  }
  if (want_resolution) entry->density.resize(std::size_t(seen));
  // The previous view's contributions [old, old + n) kept at [index, index + n).
  const auto keep = [&](int index, int old, int n) {
    if (n == 0) return;
    if (want_information) {
      std::memcpy(&entry->information[6 * std::size_t(index)],
                  &was.information[6 * std::size_t(old)], 6 * sizeof(double) * std::size_t(n));
      std::memcpy(&entry->band[std::size_t(index)], &was.band[std::size_t(old)], std::size_t(n));
    }
    if (want_resolution)
      std::memcpy(&entry->density[std::size_t(index)], &was.density[std::size_t(old)],
                  sizeof(float) * std::size_t(n));
  };
  int index = 0;
  for (int w = 0; w < kWords; ++w) {
    entry->before[w] = static_cast<std::int16_t>(index);
    if (entry->bits[w] == was.bits[w]) {
      // A word seen as before (most of them): its contributions are the previous view's run.
      const int n = PopcountInline(was.bits[w]);
      keep(index, was.before[w], n);
      index += n;
      continue;
    }
    for (std::uint64_t bits = entry->bits[w]; bits; bits &= bits - 1, ++index) {
      const int bit = __builtin_ctzll(bits);
      if (was.bits[w] >> bit & 1) {
        keep(index, was.before[w] + PopcountInline(was.bits[w] & ((std::uint64_t{1} << bit) - 1)),
             1);
      } else {
        const int f = fresh_at[64 * w + bit];
        if (want_information) {
          for (int r = 0; r < 6; ++r) entry->information[6 * index + r] = scratch.info[r][f];
          entry->band[index] = scratch.band[f];
        }
        if (want_resolution) entry->density[index] = density[f];
      }
    }
  }
  return cast;
}

// Calls f(offset, index) for every voxel of `mask` that `e` sees, with its index among e's seen
// voxels (ascending offset).
template <class F>
inline __attribute__((always_inline)) void WalkMasked(const CameraEntry& e, const Bits& mask,
                                                      F&& f) {
  for (int w = 0; w < kWords; ++w) {
    const std::uint64_t seen = e.bits[w], wanted = seen & mask[w];
    if (!wanted) continue;
    if (wanted == seen) {
      int index = e.before[w];
      for (std::uint64_t bits = seen; bits; bits &= bits - 1)
        f(64 * w + __builtin_ctzll(bits), index++);
    } else {
      for (std::uint64_t bits = wanted; bits; bits &= bits - 1) {
        const int bit = __builtin_ctzll(bits);
        f(64 * w + bit, e.before[w] + PopcountInline(seen & ((std::uint64_t{1} << bit) - 1)));
      }
    }
  }
}

// Resets the block's caches (a full evaluation writes every voxel) or copies the old ones (an
// update not in place; in place they stay where they are).
void FieldEvaluator::State::PrepareCaches(const BlockState& old, bool fresh, bool in_place,
                                          BlockState* next) const {
  if (fresh) {
    next->coverage.assign(512, 0);
    next->status.assign(512, kUnseen);
    if (want_information) next->sigma_max.assign(512, 0.0f);
    if (want_steady) next->sigma_steady.assign(512, 0.0f);
    if (want_angle) {
      next->pair_dot.assign(512, 2.0);
      next->pair_a.assign(512, -1);
      next->pair_b.assign(512, -1);
    }
  } else if (!in_place) {
    next->coverage = old.coverage;
    next->status = old.status;
    next->sigma_max = old.sigma_max;
    next->sigma_steady = old.sigma_steady;
    next->pair_dot = old.pair_dot;
    next->pair_a = old.pair_a;
    next->pair_b = old.pair_b;
  }
  if (fresh) {
    if (want_resolution) {
      next->best_density.assign(512, 0.0f);
      next->best_camera.assign(512, -1);
    }
    if (want_information) {
      next->sums.resize(512);  // not zeroed: Rescan clears each voxel it sums
      next->sum_band.assign(512, kNotExact);
      next->band_count.assign(512, 0);
    }
  } else if (!in_place) {
    next->best_density = old.best_density;
    next->best_camera = old.best_camera;
    next->sums = old.sums;
    next->sum_band = old.sum_band;
    next->band_count = old.band_count;
  }
}

// The block's leaves to rewrite: the grids' own ones (`in_place`), copies of them, or new ones.
void FieldEvaluator::State::PrepareLeaves(const openvdb::Coord& origin, bool in_place,
                                          BlockLeaves* leaves) {
  Fields::Impl& g = fields.impl();
  // Leaves to rewrite: copies of the grids' current ones, or new ones.
  // (probeLeaf changes no tree structure, and every block has leaves of its own: the threads
  // never write the same leaf.)
  if (want_coverage) {
    auto* current = g.coverage->tree().probeLeaf(origin);
    if (current && in_place) {
      leaves->coverage = current;
    } else if (current) {
      leaves->coverage = new openvdb::Int32Tree::LeafNodeType(*current);
      leaves->coverage_owned = true;
    } else {
      // None yet, or a tile of zeros (a full block nobody saw): every voxel active at 0.
      const bool tile = g.coverage->tree().isValueOn(origin);
      leaves->coverage = new openvdb::Int32Tree::LeafNodeType(origin, 0, tile);
      leaves->coverage_owned = true;
    }
  }
  for (int f = 0; f < kFloatFieldCount; ++f) {
    if (!want_float[f]) continue;
    FloatLeaf* current = float_grids[f]->tree().probeLeaf(origin);
    if (current && in_place) {
      leaves->floats[f] = current;
    } else {
      leaves->floats[f] = current ? new FloatLeaf(*current) : new FloatLeaf(origin, 0.0f, false);
      leaves->float_owned[f] = true;
    }
  }
}

// An update's coverage, best density and information sums from the cached ones: the changed
// cameras' new views in, their old ones out; marks the voxels to re-sum from every camera.
void FieldEvaluator::State::SumChangedCameras(const BlockState& old,
                                              const std::vector<const CameraEntry*>& view,
                                              const Bits& dirty,
                                              const std::vector<std::uint8_t>& is_changed,
                                              bool occlusion_only, BlockState* next,
                                              DeriveScratch* scratch) const {
  std::array<std::int32_t, 512>& cover = scratch->cover;
  Bits& rescan_density = scratch->rescan_density;
  Bits& rescan_info = scratch->rescan_info;
  const std::array<BandScale, 64>& scales = BandScales();
  // Only the dirty voxels: elsewhere a changed camera's old and new contributions are the same
  // bits (a scene update: its view there did not change), and adding one while taking out the
  // other would change nothing. With `occlusion_only` the same holds voxel by voxel: of a
  // changed camera only the voxels it sees now and did not (new view), or saw and does not (old
  // view), are walked. The result is the same (counts, maxima and exact sums; a best density's
  // camera that still sees its voxel keeps it).
  const auto bits_of = [](const CameraEntry* e) { return e ? e->bits : Bits{}; };
  const auto walk = [&](const CameraEntry& e, const CameraEntry* other, auto&& f)
      __attribute__((always_inline)) {
    if (!occlusion_only) return WalkMasked(e, dirty, f);
    const Bits o = bits_of(other);
    Bits mask;
    for (int w = 0; w < kWords; ++w) mask[w] = dirty[w] & ~o[w];
    WalkMasked(e, mask, f);
  };
  for (int o = 0; o < 512; ++o) cover[o] = next->coverage[o];
  for (const CameraEntry* e : view) {
    if (!is_changed[e->camera]) continue;
    walk(
        *e, occlusion_only ? FindEntry(old.entries, e->camera) : nullptr,
        [&](int o, int index) __attribute__((always_inline)) {  // a changed camera's new view
          ++cover[o];
          if (want_resolution && e->density[index] > next->best_density[o]) {
            next->best_density[o] = e->density[index];
            next->best_camera[o] = e->camera;
          }
          if (want_information && !TestBit(rescan_info, o)) {
            const std::uint8_t b = e->band[index], k = next->sum_band[o];
            if (k == kNotExact || b > k) {
              SetBit(rescan_info, o);
            } else {
              if (b == k) ++next->band_count[o];
              AccumulateLimbs(next->sums[o], &e->information[6 * index], scales[k].down, true);
            }
          }
        });
  }
  for (const CameraEntry& e : old.entries) {
    if (!is_changed[e.camera] || e.seen == 0) continue;
    walk(
        e, occlusion_only ? FindEntry(view, e.camera) : nullptr,
        [&](int o, int index) __attribute__((always_inline)) {  // a changed camera's old view
          --cover[o];
          if (want_resolution && next->best_camera[o] == e.camera) SetBit(rescan_density, o);
          if (want_information && !TestBit(rescan_info, o)) {
            const std::uint8_t b = e.band[index], k = next->sum_band[o];
            if (k == kNotExact || b > k) {
              SetBit(rescan_info, o);
            } else {
              if (b == k) --next->band_count[o];
              AccumulateLimbs(next->sums[o], &e.information[6 * index], scales[k].down, false);
            }
          }
        });
  }
  if (want_information)
    for (int w = 0; w < kWords; ++w)
      for (std::uint64_t bits = dirty[w] & ~rescan_info[w]; bits; bits &= bits - 1) {
        const int o = 64 * w + __builtin_ctzll(bits);
        if (next->band_count[o] <= 0 || cover[o] > kMaxExactCameras) SetBit(rescan_info, o);
      }
}

// Re-sums the voxels to rescan (every dirty voxel of a full evaluation) from every camera.
void FieldEvaluator::State::Rescan(const std::vector<const CameraEntry*>& view, const Bits& dirty,
                                   bool fresh, BlockState* next, DeriveScratch* scratch) const {
  std::array<std::int32_t, 512>& cover = scratch->cover;
  const Bits& rescan_density = scratch->rescan_density;
  const Bits& rescan_info = scratch->rescan_info;
  Bits& in_double = scratch->in_double;
  std::vector<std::array<double, 6>>& double_sum = scratch->double_sum;
  std::array<std::int16_t, 512>& double_index = scratch->double_index;
  // Rescans, camera by camera in rig order: coverage (a full evaluation), best density, the band
  // of the information sum and its count.
  Bits rescan = rescan_density;
  for (int w = 0; w < kWords; ++w) rescan[w] |= rescan_info[w];
  if (fresh) rescan = dirty;
  const auto walk_masked =
      [](const CameraEntry& e, const Bits& mask, auto&& f) __attribute__((always_inline)) {
    WalkMasked(e, mask, f);
  };
  bool any_rescan = false;
  for (std::uint64_t word : rescan) any_rescan |= word != 0;
  if (any_rescan) {
    for (int w = 0; w < kWords; ++w) {
      for (std::uint64_t bits = rescan_density[w]; bits; bits &= bits - 1) {
        const int o = 64 * w + __builtin_ctzll(bits);
        next->best_density[o] = 0.0f;
        next->best_camera[o] = -1;
      }
      for (std::uint64_t bits = rescan_info[w]; bits; bits &= bits - 1) {
        const int o = 64 * w + __builtin_ctzll(bits);
        ClearLimbs(next->sums[o]);
        next->sum_band[o] = 0;
        next->band_count[o] = 0;
      }
    }
    for (const CameraEntry* e : view)
      walk_masked(
          *e, rescan, [&](int o, int index) __attribute__((always_inline)) {
            if (fresh) ++cover[o];
            if (TestBit(rescan_density, o) && e->density[index] > next->best_density[o]) {
              next->best_density[o] = e->density[index];
              next->best_camera[o] = e->camera;
            }
            if (TestBit(rescan_info, o)) {
              const std::uint8_t b = e->band[index];
              if (b > next->sum_band[o]) {
                next->sum_band[o] = b;
                next->band_count[o] = 1;
              } else if (b == next->sum_band[o]) {
                ++next->band_count[o];
              }
            }
          });
    bool any_info = false;
    for (int w = 0; w < kWords; ++w) {
      for (std::uint64_t bits = rescan_info[w]; bits; bits &= bits - 1) {
        const int o = 64 * w + __builtin_ctzll(bits);
        any_info = true;
        if (cover[o] == 0 || cover[o] > kMaxExactCameras || next->sum_band[o] == kNotExact) {
          next->sum_band[o] = kNotExact;
          next->band_count[o] = 0;
          if (cover[o] > 0) {
            SetBit(in_double, o);
            double_index[o] = static_cast<std::int16_t>(double_sum.size());
            double_sum.push_back({0, 0, 0, 0, 0, 0});
          }
        }
      }
    }
    if (any_info) {
      const PhaseTimer timer(*this, kSums);
      for (const CameraEntry* e : view) {
        // The camera's pairs to sum exactly listed first, then summed in one call (SIMD).
        std::array<std::int16_t, 512>& voxels = scratch->list_voxel;
        std::array<std::int16_t, 512>& indices = scratch->list_index;
        int listed = 0;
        walk_masked(
            *e, rescan_info, [&](int o, int index) __attribute__((always_inline)) {
              if (TestBit(in_double, o)) {
                const double* c = &e->information[6 * index];
                std::array<double, 6>& d = double_sum[double_index[o]];
                for (int k = 0; k < 6; ++k) d[k] += c[k];
              } else {
                voxels[listed] = static_cast<std::int16_t>(o);
                indices[listed++] = static_cast<std::int16_t>(index);
              }
            });
        AccumulateLimbList(listed, voxels.data(), indices.data(), e->information.data(),
                           next->sum_band.data(), next->sums.data(), true);
      }
    }
  }
}

// Writes the dirty voxels' coverage and best density into the caches and the leaves, clears their
// other fields, and collects the triangulation candidates with their information and centres.
void FieldEvaluator::State::WriteDirtyVoxels(const Block& block, const Bits& dirty,
                                             BlockState* next, BlockLeaves* leaves,
                                             DeriveScratch* scratch) const {
  const VoxelLattice& lattice = fields.lattice;
  const std::array<BandScale, 64>& scales = BandScales();
  FloatLeaf* resolution = leaves->floats[kResolution];
  const std::array<std::int32_t, 512>& cover = scratch->cover;
  const Bits& in_double = scratch->in_double;
  const std::vector<std::array<double, 6>>& double_sum = scratch->double_sum;
  const std::array<std::int16_t, 512>& double_index = scratch->double_index;
  std::array<std::array<double, 512>, 6>& upper = scratch->upper;
  std::array<double, 512>& cand_x = scratch->cand_x;
  std::array<double, 512>& cand_y = scratch->cand_y;
  std::array<double, 512>& cand_z = scratch->cand_z;
  std::array<std::int16_t, 512>& candidate = scratch->candidate;
  int& candidate_count = scratch->candidate_count;
  for (int w = 0; w < kWords; ++w) {
    for (std::uint64_t bits = dirty[w]; bits; bits &= bits - 1) {
      const int o = 64 * w + __builtin_ctzll(bits);
      const int coverage = cover[o];
      const float density = want_resolution ? next->best_density[o] : 0.0f;
      next->coverage[o] = coverage;
      next->status[o] = coverage == 0 ? kUnseen : kSeenOnly;
      if (leaves->coverage) leaves->coverage->setValueOn(o, coverage);
      if (resolution) {
        if (coverage > 0)
          resolution->setValueOn(o, density);
        else
          resolution->setValueOff(o, 0.0f);
      }
      if (!want_information || coverage < 2) {  // not triangulable: no uncertainty work
        leaves->ClearUncertainty(o);
        if (want_angle) next->pair_a[o] = next->pair_b[o] = -1;
        continue;
      }
      // A candidate's uncertainty fields are written by PutStatistics: on where it is
      // triangulable (every one of them), off where it is not.
      if (TestBit(in_double, o)) {
        for (int k = 0; k < 6; ++k) upper[k][candidate_count] = double_sum[double_index[o]][k];
      } else {
        double entry[6];
        SumLimbsToDoubles(next->sums[o], scales[next->sum_band[o]].up, entry);
        for (int k = 0; k < 6; ++k) upper[k][candidate_count] = entry[k];
      }
      if (want_angle) {
        const int x = o >> 6, y = (o >> 3) & 7, z = o & 7;
        const Vec3 p =
            lattice.Center(block.origin.x() + x, block.origin.y() + y, block.origin.z() + z);
        cand_x[candidate_count] = p.x();
        cand_y[candidate_count] = p.y();
        cand_z[candidate_count] = p.z();
      }
      candidate[candidate_count++] = static_cast<std::int16_t>(o);
    }
  }
}

// The candidates' static statistics (eigenvalues of the information), triangulation angles and
// steady-state statistics.
void FieldEvaluator::State::CandidateStatistics(const std::vector<const CameraEntry*>& view,
                                                const std::vector<std::uint8_t>& is_changed,
                                                const std::vector<Vec3>& centres, bool fresh,
                                                BlockState* next, DeriveScratch* scratch) const {
  const int candidate_count = scratch->candidate_count;
  std::array<std::array<double, 512>, kStatRows>& stats = scratch->stats;
  double* stats_ptr[kStatRows];
  for (int k = 0; k < kStatRows; ++k) stats_ptr[k] = stats[k].data();
  const double* upper_ptr[6];
  for (int k = 0; k < 6; ++k) upper_ptr[k] = scratch->upper[k].data();
  double* eigen_ptr[3] = {scratch->eigenvalue[0].data(), scratch->eigenvalue[1].data(),
                          scratch->eigenvalue[2].data()};
  {
    const PhaseTimer timer(*this, kEigenvalues);
    SymmetricEigenvalues3(upper_ptr, eigen_ptr, scratch->converged.data(), candidate_count);
  }
  StaticStatistics(candidate_count, eigen_ptr, stats_ptr);
  if (want_angle) {
    const PhaseTimer timer(*this, kAngles);
    CandidateAngles(view, is_changed, centres, fresh, next, scratch);
  }
  if (want_steady) {
    const double frame = frame_period;
    for (int k = 0; k < 3; ++k)
      SteadyPositionVariances(motion.q, frame, stats[kVar0 + k].data(), stats[kVar0 + k].data(),
                              candidate_count, scene->study.steady_prior);
    SteadyStatistics(candidate_count, stats_ptr);
  }
}

// The candidates' triangulation angles and best camera pairs (into the pair caches).
void FieldEvaluator::State::CandidateAngles(const std::vector<const CameraEntry*>& view,
                                            const std::vector<std::uint8_t>& is_changed,
                                            const std::vector<Vec3>& centres, bool fresh,
                                            BlockState* next, DeriveScratch* scratch) const {
  const int candidate_count = scratch->candidate_count;
  const std::array<std::int16_t, 512>& candidate = scratch->candidate;
  const std::array<double, 512>& cand_x = scratch->cand_x;
  const std::array<double, 512>& cand_y = scratch->cand_y;
  const std::array<double, 512>& cand_z = scratch->cand_z;
  std::array<float, 512>& angle_deg = scratch->angle_deg;
  std::vector<const std::uint64_t*> sees;
  std::vector<Vec3> entry_centres;
  std::vector<unsigned char> entry_changed;
  sees.reserve(view.size());
  entry_centres.reserve(view.size());
  for (const CameraEntry* e : view) {
    sees.push_back(e->bits.data());
    entry_centres.push_back(centres[e->camera]);
    entry_changed.push_back(is_changed[e->camera]);
  }
  // Camera -> its place in `view`: a table, not a binary search per lookup (two per voxel whose
  // best pair is kept: about 100,000 voxels an update on the capture stage).
  thread_local std::vector<std::int32_t> entry_index;
  entry_index.assign(view.empty() ? 0 : std::size_t(view.back()->camera) + 1, 0);
  for (std::size_t i = 0; i < view.size(); ++i)
    entry_index[std::size_t(view[i]->camera)] = static_cast<std::int32_t>(i);
  const auto entry_of = [&](std::int32_t camera) { return entry_index[std::size_t(camera)]; };
  // Two groups: voxels whose cached best pair involves no changed camera try only the pairs
  // with a changed one; the others (new candidates, a changed camera in the pair) try all.
  std::array<int, 512> group_of;  // candidate -> index within its group
  std::array<std::int16_t, 512> offsets[2];
  std::array<double, 512> gx[2], gy[2], gz[2], dot[2];
  std::array<std::int32_t, 512> pa[2], pb[2];
  std::array<float, 512> degrees[2];
  int size[2] = {0, 0};
  std::array<unsigned char, 512> which;
  for (int m = 0; m < candidate_count; ++m) {
    const int o = candidate[m];
    const std::int32_t ca = next->pair_a[o], cb = next->pair_b[o];
    const int g = (!fresh && ca >= 0 && !is_changed[ca] && !is_changed[cb]) ? 1 : 0;
    const int k = size[g]++;
    which[m] = static_cast<unsigned char>(g);
    group_of[m] = k;
    offsets[g][k] = static_cast<std::int16_t>(o);
    gx[g][k] = cand_x[m];
    gy[g][k] = cand_y[m];
    gz[g][k] = cand_z[m];
    if (g == 1) {
      dot[g][k] = next->pair_dot[o];
      pa[g][k] = entry_of(ca);
      pb[g][k] = entry_of(cb);
    }
  }
  // Scratch, every entry written before it is read: no zero fill (36 KiB for 24 cameras).
  const std::unique_ptr<double[]> directions(new double[3 * 64 * view.size()]);
  const std::unique_ptr<unsigned char[]> have(new unsigned char[view.size()]);
  for (int g = 0; g < 2; ++g) {
    if (size[g] == 0) continue;
    if (g == 0)
      for (int k = 0; k < size[g]; ++k) dot[g][k] = 2.0, pa[g][k] = 0, pb[g][k] = 0;
    // The group's voxels in a ball: their bounding box's centre and half diagonal.
    Vec3 lo(gx[g][0], gy[g][0], gz[g][0]), hi = lo;
    for (int k = 1; k < size[g]; ++k) {
      const Vec3 p(gx[g][k], gy[g][k], gz[g][k]);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const PairOrder order =
        OrderPairs(static_cast<int>(view.size()), entry_centres.data(), 0.5 * (lo + hi),
                   0.5 * (hi - lo).norm(), g == 1 ? entry_changed.data() : nullptr,
                   options.exhaustive_angle_pairs);
    angle_pairs_tried += TriangulationAngles(
        size[g], gx[g].data(), gy[g].data(), gz[g].data(), offsets[g].data(),
        static_cast<int>(view.size()), sees.data(), entry_centres.data(), order, g == 1,
        dot[g].data(), pa[g].data(), pb[g].data(), directions.get(), have.get(), degrees[g].data());
    angle_pairs_all += std::int64_t(size[g]) * std::int64_t(order.a.size());
  }
  for (int m = 0; m < candidate_count; ++m) {
    const int g = which[m], k = group_of[m], o = candidate[m];
    angle_deg[m] = degrees[g][k];
    next->pair_dot[o] = dot[g][k];
    next->pair_a[o] = view[pa[g][k]]->camera;
    next->pair_b[o] = view[pb[g][k]]->camera;
  }
}

// Puts the candidates' statistics into the caches and the float leaves.
void FieldEvaluator::State::PutStatistics(BlockState* next, BlockLeaves* leaves,
                                          const DeriveScratch& scratch) const {
  const int candidate_count = scratch.candidate_count;
  const std::array<std::int16_t, 512>& candidate = scratch.candidate;
  const std::array<std::array<double, 512>, kStatRows>& stats = scratch.stats;
  const std::array<float, 512>& angle_deg = scratch.angle_deg;
  const auto put = [&](int field, int offset, float value) {
    if (leaves->floats[field]) leaves->floats[field]->setValueOn(offset, value);
  };
  for (int m = 0; m < candidate_count; ++m) {
    const int o = candidate[m];
    if (stats[kObservable][m] == 0.0) {
      next->status[o] = kUnobservable;
      leaves->ClearUncertainty(o);
      continue;
    }
    next->status[o] = kTriangulable;
    const float sigma_max_mm = static_cast<float>(stats[kSigmaMaxMm][m]);
    next->sigma_max[o] = sigma_max_mm;
    if (want_angle) put(kAngle, o, angle_deg[m]);
    put(kSigmaMax, o, sigma_max_mm);
    put(kSigmaMean, o, static_cast<float>(stats[kSigmaMeanMm][m]));
    put(kCondition, o, static_cast<float>(stats[kCond][m]));
    if (want_steady) {
      const float steady_max = static_cast<float>(stats[kSteadyMaxMm][m]);
      next->sigma_steady[o] = steady_max;
      put(kSigmaMaxSteady, o, steady_max);
      put(kSigmaMeanSteady, o, static_cast<float>(stats[kSteadyMeanMm][m]));
    }
  }
}

// The block's summary from its caches (every free voxel, ascending offset).
void FieldEvaluator::State::SummariseBlock(const Block& block, BlockState* next) const {
  next->histogram.clear();
  next->seen = next->triangulable = next->unobservable = 0;
  next->sigma_list.clear();
  next->steady_list.clear();
  {
    int triangulable = 0;
    for (int o = 0; o < 512; ++o) triangulable += next->status[o] == kTriangulable ? 1 : 0;
    if (list_sigma) next->sigma_list.reserve(triangulable);
    if (want_steady && list_steady) next->steady_list.reserve(triangulable);
  }
  for (int x = 0; x < block.extent.x(); ++x)
    for (int y = 0; y < block.extent.y(); ++y)
      for (int z = 0; z < block.extent.z(); ++z) {
        if (!block.IsFree(x, y, z)) continue;
        const int o = Block::Offset(x, y, z);
        const int k = next->coverage[o];
        if (int(next->histogram.size()) <= k) next->histogram.resize(k + 1, 0);
        ++next->histogram[k];
        if (k > 0) ++next->seen;
        if (next->status[o] == kUnobservable) ++next->unobservable;
        if (next->status[o] != kTriangulable) continue;
        ++next->triangulable;
        if (list_sigma) next->sigma_list.push_back(next->sigma_max[o]);
        if (want_steady && list_steady) next->steady_list.push_back(next->sigma_steady[o]);
      }
}

// Recomputes the voxels in `dirty` from the block's camera entries (`view`, ascending camera:
// the kept ones and the re-cast ones) and the kept caches, and makes the block's new leaves:
// copies of the current ones with the dirty voxels rewritten, or (`in_place`, an update that can
// no longer be cancelled; `next` is then `old`) the grids' own leaves rewritten in place, new
// leaves only where the grid has none. The same arithmetic for a full evaluation (every voxel
// dirty) and an update, so both give the same bits.
void FieldEvaluator::State::Derive(const Block& block, const BlockState& old,
                                   std::vector<const CameraEntry*> view, const Bits& dirty,
                                   const std::vector<std::uint8_t>& is_changed,
                                   const std::vector<Vec3>& centres, BlockState* next,
                                   BlockLeaves* leaves, bool in_place, bool occlusion_only) {
  // Entries that see nothing take no part.
  view.erase(
      std::remove_if(view.begin(), view.end(), [](const CameraEntry* e) { return e->seen == 0; }),
      view.end());
  const openvdb::Coord origin(block.origin.x(), block.origin.y(), block.origin.z());

  // Caches: the old ones (an update) or fresh ones (a full evaluation writes every voxel).
  const bool fresh = old.coverage.empty();
  if (in_place && next != &old) throw std::logic_error("Derive in place: next must be old");
  PrepareCaches(old, fresh, in_place, next);
  PrepareLeaves(origin, in_place, leaves);

  DeriveScratch scratch;
  // Coverage, best density and information of the dirty voxels. A full evaluation sums every
  // camera of every voxel. An update starts from the cached values and takes out the changed
  // cameras' old contributions and puts in their new ones: coverage is a count, the density a
  // maximum and the information an exact fixed-point sum (see Sum6 and SumLimbs), so the result has
  // the bits of a full evaluation. A voxel whose best density came from a changed camera, or whose
  // sum's band changes (or that is summed in double), is re-summed from every camera ("rescan").
  if (fresh) {
    scratch.cover.fill(0);
    if (want_resolution) scratch.rescan_density = dirty;
    if (want_information) scratch.rescan_info = dirty;
  } else {
    SumChangedCameras(old, view, dirty, is_changed, occlusion_only, next, &scratch);
  }
  Rescan(view, dirty, fresh, next, &scratch);
  WriteDirtyVoxels(block, dirty, next, leaves, &scratch);
  if (scratch.candidate_count > 0)
    CandidateStatistics(view, is_changed, centres, fresh, next, &scratch);
  PutStatistics(next, leaves, scratch);

  SummariseBlock(block, next);

  // Leaves: a full block nobody sees keeps its coverage as a tile; empty float leaves go.
  if (leaves->coverage && block.full && next->seen == 0) {
    if (leaves->coverage_owned) delete leaves->coverage;
    leaves->coverage = nullptr;
    leaves->coverage_owned = false;
    leaves->coverage_tile = true;
  }
  for (int f = 0; f < kFloatFieldCount; ++f)
    if (leaves->floats[f] && leaves->floats[f]->isEmpty()) {
      if (leaves->float_owned[f]) delete leaves->floats[f];
      leaves->floats[f] = nullptr;
      leaves->float_owned[f] = false;
      leaves->remove_float[f] = true;
    }
}

void FieldEvaluator::State::Totals(FieldStats* st, int camera_count, int enabled) const {
  const ActiveSetStats active = st->active_set;
  *st = FieldStats{};
  st->active_set = active;
  st->active_set.culled_blocks = 0;
  st->coverage_histogram.assign(camera_count + 1, 0);
  st->per_camera_seen.assign(camera_count, 0);
  // The lists' sizes first: one allocation each, not a doubling per block (an update's Totals
  // gathers every block's list, 81,000 values on the trauma room).
  std::size_t sigma_count = 0, steady_count = 0;
  for (const BlockState& s : states) {
    sigma_count += s.sigma_list.size();
    steady_count += s.steady_list.size();
  }
  st->sigma_max_mm.reserve(sigma_count);
  st->sigma_max_steady_mm.reserve(steady_count);
  for (std::size_t b = 0; b < states.size(); ++b) {
    const BlockState& s = states[b];
    if (s.candidates.empty()) ++st->active_set.culled_blocks;
    for (std::size_t k = 0; k < s.histogram.size(); ++k)
      st->coverage_histogram[k] += s.histogram[k];
    st->seen_voxels += s.seen;
    st->triangulable_voxels += s.triangulable;
    st->unobservable_voxels += s.unobservable;
    st->sigma_max_mm.insert(st->sigma_max_mm.end(), s.sigma_list.begin(), s.sigma_list.end());
    st->sigma_max_steady_mm.insert(st->sigma_max_steady_mm.end(), s.steady_list.begin(),
                                   s.steady_list.end());
    for (const CameraEntry& e : s.entries) {
      st->per_camera_seen[e.camera] += e.seen;
      st->rays += e.rays;
    }
    for (const BlockState::CameraCount& e : s.counts) {
      st->per_camera_seen[e.camera] += e.seen;
      st->rays += e.rays;
    }
    if (owned.empty() || owned[b]) st->point_camera_tests += blocks[b].free_voxels * enabled;
  }
}

void FieldOptions::Check(const Scene& scene) const {
  const std::string file = scene_path.empty() ? scene.path : scene_path;
  // A list from an option is named by the option; the scene file's by its JSON path.
  const auto fail = [&](const std::string& path, const std::string& reason,
                        const std::string& hint) {
    if (!fields_option.empty()) throw InputError(fields_option, "", reason, hint);
    throw InputError(file, path, reason, hint);
  };
  if (auto problem = CheckFieldList(fields, scene.study.motion.has_value()))
    fail("$.study.fields[" + std::to_string(problem->index) + "]", problem->reason, problem->hint);
  if (fields.empty()) fail("$.study.fields", "no field requested", "ask for at least 'coverage'");
  if (!(memory_budget_bytes > 0)) {
    if (!memory_budget_option.empty())
      throw InputError(memory_budget_option, "", "the memory budget must be > 0");
    throw InputError(file, "$.study.memory_budget_mb", "the memory budget must be > 0");
  }
  if (partition_count < 1 || partition_rank < 0 || partition_rank >= partition_count)
    throw InputError("{partition_count}", "",
                     "partition " + std::to_string(partition_rank) + " of " +
                         std::to_string(partition_count) + " does not exist",
                     "ranks are 0 .. partition_count - 1");
}

namespace {

// The scene's solid objects that can contain a region voxel (the others cost nothing).
std::vector<const SceneObject*> RegionSolids(const Scene& scene) {
  const Study& study = scene.study;
  std::vector<const SceneObject*> solid_objects;
  for (const SceneObject& o : scene.objects) {
    if (!o.solid || o.mesh.triangles.empty()) continue;
    const Aabb b = o.mesh.Bounds();
    if ((b.max.array() < study.region.box.min.array()).any() ||
        (b.min.array() > study.region.box.max.array()).any())
      continue;
    solid_objects.push_back(&o);
  }
  return solid_objects;
}

// The active set of `scene` into S.blocks and S.active_stats: the free region voxels (its solids
// and region mesh classified, no cameras), with FieldOptions::tile and voxel_filter applied.
// `check_budget`, when set, is called with the fields' estimate for the blocks kept.
void BuildBlocks(FieldEvaluator::State& S, const Scene& scene,
                 const std::vector<const SceneObject*>& solid_objects,
                 const std::function<void(double)>& check_budget) {
  const FieldOptions& opt = S.options;
  const Study& study = scene.study;
  // The active set without cameras: which voxels are free region voxels (solids and the region
  // mesh are classified once; cameras are culled per update).
  // Their search trees: the study's kept ones (built at first use), else built here, in parallel
  // (a crowd of finely tessellated people: ~100 trees).
  std::vector<std::unique_ptr<InsideMesh>> solid_meshes(solid_objects.size());
  std::vector<const InsideMesh*> solids(solid_objects.size(), nullptr);
  const SolidTrees* kept = S.options.solid_trees;
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, solid_objects.size(), 1), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          if (kept)
            solids[i] = kept->Object(scene, std::size_t(solid_objects[i] - scene.objects.data()));
          if (solids[i]) continue;
          solid_meshes[i] = std::make_unique<InsideMesh>(solid_objects[i]->mesh);
          solids[i] = solid_meshes[i].get();
        }
      });
  std::unique_ptr<InsideMesh> own_region_mesh;
  const InsideMesh* region_mesh = nullptr;
  if (study.region.kind == Region::Kind::kMesh) {
    if (kept) region_mesh = kept->RegionMesh(scene);
    if (!region_mesh) {
      own_region_mesh = std::make_unique<InsideMesh>(study.region.mesh);
      region_mesh = own_region_mesh.get();
    }
  }
  const FrustumCuller no_cameras(std::vector<Camera>{});
  S.blocks = BuildActiveSet(S.fields.lattice, study.region, solids, region_mesh, no_cameras, 0,
                            &S.active_stats, opt.tile ? &*opt.tile : nullptr);
  if (check_budget)
    check_budget(
        EstimateBytesForVoxels(512.0 * double(S.blocks.size()), HeldFields(opt, S.keep), 0));
  if (opt.voxel_filter) {
    // Only the voxels the filter keeps: cleared from the blocks' masks, empty blocks dropped.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, S.blocks.size(), 4),
                      [&](const auto& range) {
                        for (std::size_t b = range.begin(); b != range.end(); ++b) {
                          Block& block = S.blocks[b];
                          std::vector<std::uint8_t> mask(512, 0);
                          block.free_voxels = 0;
                          for (int x = 0; x < block.extent.x(); ++x)
                            for (int y = 0; y < block.extent.y(); ++y)
                              for (int z = 0; z < block.extent.z(); ++z)
                                if (block.IsFree(x, y, z) &&
                                    opt.voxel_filter(block.origin.x() + x, block.origin.y() + y,
                                                     block.origin.z() + z)) {
                                  mask[Block::Offset(x, y, z)] = 1;
                                  ++block.free_voxels;
                                }
                          block.mask = std::move(mask);
                          block.full = false;
                        }
                      });
    std::vector<Block> kept_blocks;
    S.active_stats.region_voxels = 0;
    for (Block& block : S.blocks) {
      if (block.free_voxels == 0) continue;
      S.active_stats.region_voxels += block.free_voxels;
      kept_blocks.push_back(std::move(block));
    }
    S.blocks = std::move(kept_blocks);
    S.active_stats.blocks = static_cast<std::int64_t>(S.blocks.size());
  }
}

}  // namespace

FieldEvaluator::FieldEvaluator(const Scene& scene, const RayCaster& caster, FieldOptions options,
                               bool keep_state)
    : state_(std::make_unique<State>(scene, caster)) {
  const auto t0 = std::chrono::steady_clock::now();
  State& S = *state_;
  S.options = std::move(options);
  S.keep = keep_state;
  const FieldOptions& opt = S.options;
  S.file = opt.scene_path.empty() ? scene.path : opt.scene_path;
  opt.Check(scene);

  const Study& study = scene.study;
  // Errors about the voxel size name where it came from: the scene file or a command-line option.
  const std::string size_file = opt.voxel_size_option.empty() ? S.file : opt.voxel_size_option;
  const std::string size_path = opt.voxel_size_option.empty() ? "$.study.voxel_size" : "";
  S.fields.lattice = MakeLattice(study.region.box, study.voxel_size, size_file, size_path);
  VoxelLattice estimated = S.fields.lattice;  // a tile's own box when streamed
  if (opt.tile) estimated.dims = (opt.tile->VoxelEnd(estimated) - opt.tile->VoxelMin()).cwiseMax(0);
  const std::vector<const SceneObject*> solid_objects = RegionSolids(scene);
  // The memory budget, against the voxels that hold fields: the blocks with free voxels. Known
  // before anything is allocated for a box region no solid meets (its box); otherwise checked in
  // two steps: what building the active set needs (a record and a mask per block of the box)
  // before, the fields' estimate from the blocks it keeps after (a mesh region or large solids can
  // leave most of the box out).
  const bool sparse = study.region.kind == Region::Kind::kMesh || !solid_objects.empty();
  const auto check_budget = [&](double estimate) {
    S.fields.stats.estimated_bytes = estimate;
    if (estimate <= opt.memory_budget_bytes) return;
    // Memory scales with 1/h^3: the smallest voxel size that fits.
    const double h_min = study.voxel_size * std::cbrt(estimate / opt.memory_budget_bytes) * 1.01;
    std::ostringstream reason, hint;
    reason << (opt.tile ? "one streamed tile of the region needs about "
                        : "the region needs about ")
           << std::llround(estimate / 1048576.0) << " MiB at voxel size " << study.voxel_size
           << " m, over the budget of " << std::llround(opt.memory_budget_bytes / 1048576.0)
           << " MiB";
    hint << "use voxel_size >= " << h_min << " m, a smaller region, or raise the budget "
         << "({memory_budget_mb} or study.memory_budget_mb)";
    if (opt.voxel_size_option.empty() && !opt.memory_budget_option.empty())
      throw InputError(opt.memory_budget_option, "", reason.str(), hint.str());
    throw InputError(size_file, size_path, reason.str(), hint.str());
  };
  // Memory goes by 8^3 blocks (an OpenVDB leaf holds 512 values however few are active): a region
  // one voxel thick needs as many blocks as one eight voxels thick (issue 27: a 2 cm slab over a
  // floor peaked at 1.4 GB under a 700 MiB budget when voxels were counted).
  const double box_blocks = LatticeBlocks(estimated);
  check_budget(sparse ? box_blocks * (sizeof(Block) + 513.0)
                      : EstimateBytesForVoxels(512.0 * box_blocks, HeldFields(opt, S.keep), 0));

  S.want_coverage = Wants(opt.fields, "coverage");
  S.want_cameras = Wants(opt.fields, "cameras");
  for (int f = 0; f < kFloatFieldCount; ++f)
    S.want_float[f] = Wants(opt.fields, kFloatFieldNames[f]);
  S.want_resolution = S.want_float[kResolution];
  S.want_static = S.want_float[kSigmaMax] || S.want_float[kSigmaMean] || S.want_float[kCondition];
  S.want_steady = S.want_float[kSigmaMaxSteady] || S.want_float[kSigmaMeanSteady];
  S.want_angle = S.want_float[kAngle];
  // Any uncertainty field needs the triangulability decision, so J is built for all of them.
  S.want_information = S.want_static || S.want_steady || S.want_angle;
  S.want_jacobian = S.want_resolution || S.want_information;
  // One evaluation whose sigma_max (steady) grid holds the very values of its list can leave
  // the list out (FieldOptions::value_lists).
  S.list_sigma = opt.value_lists || keep_state || !S.want_float[kSigmaMax];
  S.list_steady = opt.value_lists || keep_state || !S.want_float[kSigmaMaxSteady];
  S.motion = study.motion.value_or(MotionModel{});
  S.frame_period = 1.0 / S.motion.rate_hz;
  S.scene_scale = scene.ContentBounds().diagonal();

  std::function<void(double)> blocks_budget;
  if (sparse) blocks_budget = check_budget;
  BuildBlocks(S, scene, solid_objects, blocks_budget);
  S.active_set_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

FieldEvaluator::~FieldEvaluator() = default;
FieldEvaluator::FieldEvaluator(FieldEvaluator&&) noexcept = default;
FieldEvaluator& FieldEvaluator::operator=(FieldEvaluator&&) noexcept = default;

const Fields& FieldEvaluator::fields() const { return state_->fields; }

void FieldEvaluator::SetCallbacks(std::function<void(double)> progress,
                                  const std::atomic<bool>* cancel) {
  state_->options.progress = std::move(progress);
  state_->options.cancel = cancel;
}

Fields FieldEvaluator::TakeFields() {
  State& S = *state_;
  Fields out = std::move(S.fields);
  S.fields = Fields();
  S.fields.lattice = out.lattice;
  S.states.clear();
  S.evaluated = false;
  return out;
}

double FieldEvaluator::state_bytes() const {
  const State& S = *state_;
  double bytes = double(S.states.capacity()) * sizeof(BlockState);
  for (const BlockState& s : S.states) {
    bytes += s.candidates.capacity() * sizeof(std::int32_t) + s.coverage.capacity() * 4 +
             s.status.capacity() + (s.sigma_max.capacity() + s.sigma_steady.capacity()) * 4 +
             s.histogram.capacity() * 8 + (s.sigma_list.capacity() + s.steady_list.capacity()) * 4 +
             s.pair_dot.capacity() * 8 + (s.pair_a.capacity() + s.pair_b.capacity()) * 4 +
             (s.best_density.capacity() + s.best_camera.capacity()) * 4 +
             s.sums.capacity() * sizeof(SumLimbs) + s.sum_band.capacity() +
             s.band_count.capacity() * 4;
    for (const CameraEntry& e : s.entries) bytes += e.Bytes();
  }
  return bytes;
}

namespace {

using State = FieldEvaluator::State;

// The working data of one FieldEvaluator::Update: the changed cameras, the blocks to visit and
// what the parallel phase makes for each of them (by index into `dirty`).
struct UpdatePass {
  std::vector<int> changed;
  std::vector<std::uint8_t> is_changed;  // by rig index, 1 for a changed camera
  std::vector<std::vector<std::int32_t>> candidates;
  std::vector<std::size_t> dirty;
  bool in_place = false;
  std::vector<BlockState> next;
  std::vector<std::vector<CameraEntry>> cast;
  std::vector<BlockLeaves> leaves;
  std::atomic<std::size_t> done{0};
  std::atomic<std::int64_t> dirty_voxels{0};
  std::atomic<std::int64_t> rays{0};  // occlusion segments cast
  std::atomic<bool> cancelled{false};
  // Grids that InsertLeaves gave inactive tiles (where leaves went): the only ones a camera update
  // has to prune (the others are as pruned as before it).
  std::array<std::uint8_t, kFloatFieldCount> tiled_float{};
  std::vector<std::uint8_t> tiled_visible;
  // A scene update (FieldEvaluator::UpdateScene): the cameras change per block, not for the whole
  // rig. block_changed[i] (ascending) are dirty block i's cameras to re-cast, then those whose
  // view of it changed.
  bool per_block = false;
  std::vector<std::vector<int>> block_changed;
  // A scene update, per camera: the cones (ConeOf) from it around each moved box (padded),
  // where it was and where it is.
  std::vector<std::vector<EyeCone>> before_cones, after_cones;
  bool Changed(std::size_t i, int camera) const {
    if (!per_block) return is_changed[camera] != 0;
    return std::binary_search(block_changed[i].begin(), block_changed[i].end(), camera);
  }
};

// Throws InputError when the fields with `new_count` cameras and the scene's structures exceed the
// memory budget.
void CheckCameraBudget(const State& S, int new_count) {
  const FieldOptions& opt = S.options;
  // The memory budget with the cameras counted (the evaluator learns them only now): each camera's
  // own grid for "cameras" (an OpenVDB tree's internal nodes, ~300 kB per camera even over a few
  // blocks) and its per-block counts. 2,000 cameras over 4,096
  // voxels peaked at 675 MB under a 256 MiB budget before (issue 27).
  const double blocks = double(S.blocks.size());
  // The budget bounds the process's data: the evaluation, every camera's share, and the scene's
  // structures held for the run (its meshes, the Embree BVH and the solids' search trees:
  // SceneStructureBytes). The program itself (code and libraries, about 45 MiB resident before
  // any input) comes on top; summary.json's timing.peak_rss_mib shows the whole.
  const double scene_bytes = SceneStructureBytes(*S.scene);
  const double need =
      S.fields.stats.estimated_bytes + scene_bytes +
      double(new_count) * PerCameraBytes(S.fields.lattice, blocks, opt.fields, S.keep);
  if (need > opt.memory_budget_bytes) {
    std::ostringstream reason;
    reason << "the run needs about " << std::llround(need / 1048576.0)
           << " MiB (the region's fields with the rig's " << new_count << " cameras";
    if (scene_bytes >= 1048576.0)
      reason << ", the scene's meshes and BVH " << std::llround(scene_bytes / 1048576.0)
             << " MiB of it";
    reason << "), over the budget of " << std::llround(opt.memory_budget_bytes / 1048576.0)
           << " MiB";
    const std::string hint =
        Wants(opt.fields, "cameras")
            ? "leave the per-camera 'cameras' field out, raise the budget, or use fewer cameras"
            : "raise the budget ({memory_budget_mb} or study.memory_budget_mb), or use fewer "
              "cameras";
    if (!opt.memory_budget_option.empty())
      throw InputError(opt.memory_budget_option, "", reason.str(), hint);
    throw InputError(S.file, "$.study.memory_budget_mb", reason.str(), hint);
  }
}

// The blocks' new candidate lists and the blocks to visit (into `u`): those a changed camera's old
// or new frustum meets (all of them the first time), of this process's partition.
void VisitBlocks(State& S, const RigData& rd, int new_count, int old_count, UpdatePass* u) {
  const FieldOptions& opt = S.options;
  const std::vector<int>& changed = u->changed;
  std::vector<std::vector<std::int32_t>>& candidates = u->candidates;
  candidates.resize(S.blocks.size());
  std::vector<std::uint8_t> dirty_block(S.blocks.size(), 0);
  u->is_changed = [&] {
    std::vector<std::uint8_t> v(std::max(new_count, old_count) + 1, 0);
    for (int c : changed) v[c] = 1;
    return v;
  }();
  const std::vector<std::uint8_t>& is_changed = u->is_changed;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, S.blocks.size(), 16),
                    [&](const auto& range) {
                      for (std::size_t b = range.begin(); b != range.end(); ++b) {
                        const BlockState& s = S.states[b];
                        std::vector<std::int32_t>& next = candidates[b];
                        bool dirty = !S.evaluated;
                        for (std::int32_t c : s.candidates) {
                          if (is_changed[c]) {
                            dirty = true;
                            continue;
                          }
                          next.push_back(c);
                        }
                        const Aabb box = BlockCentreBox(S.fields.lattice, S.blocks[b]);
                        for (int c : changed)
                          if (c < new_count && rd.culler->MayIntersect(c, box)) {
                            next.push_back(c);
                            dirty = true;
                          }
                        std::sort(next.begin(), next.end());
                        dirty_block[b] = dirty;
                      }
                    });
  if (opt.partition_count > 1) {
    if (S.evaluated || S.keep)
      throw std::logic_error(
          "FieldEvaluator: a partitioned evaluation is one full update without kept state");
    S.owned = PartitionBlocks(S.blocks, candidates, opt.partition_count, opt.partition_rank);
    for (std::size_t b = 0; b < S.blocks.size(); ++b) dirty_block[b] &= S.owned[b];
  }
  std::vector<std::size_t>& dirty = u->dirty;
  for (std::size_t b = 0; b < S.blocks.size(); ++b)
    if (dirty_block[b]) dirty.push_back(b);
}

// Throws InputError when the kept state's upper bound (every candidate camera sees every free
// voxel) exceeds the memory budget.
void CheckKeptBudget(const State& S, const Rig& rig,
                     const std::vector<std::vector<std::int32_t>>& candidates) {
  const FieldOptions& opt = S.options;
  const double per_pair = (S.want_information ? 49.0 : 0.0) + (S.want_resolution ? 4.0 : 0.0);
  // Per voxel caches: coverage, status, sigmas, best pair, best density, exact sums.
  const double per_voxel = 13 + (S.want_angle ? 16 : 0) + (S.want_resolution ? 8 : 0) +
                           (S.want_information ? sizeof(SumLimbs) + 5 : 0);
  double bytes = 0;
  for (std::size_t b = 0; b < S.blocks.size(); ++b)
    bytes += 512.0 * per_voxel + double(candidates[b].size()) *
                                     (sizeof(CameraEntry) + per_pair * S.blocks[b].free_voxels);
  const double total = bytes + S.fields.stats.estimated_bytes + SceneStructureBytes(*S.scene);
  if (total > opt.memory_budget_bytes) {
    std::ostringstream reason;
    reason << "incremental updates of rig '" << rig.name << "' need up to "
           << std::llround(total / 1048576.0) << " MiB, over the budget of "
           << std::llround(opt.memory_budget_bytes / 1048576.0) << " MiB";
    throw InputError(opt.memory_budget_option.empty() ? S.file : opt.memory_budget_option,
                     opt.memory_budget_option.empty() ? "$.study.memory_budget_mb" : "",
                     reason.str(),
                     "use a coarser voxel_size, a smaller region, or raise the budget");
  }
}

// A leaf per re-cast camera of `cast` that sees part of the block, for the camera grids.
void CameraLeaves(const Block& block, const std::vector<CameraEntry>& cast, BlockLeaves* leaves) {
  for (const CameraEntry& e : cast) {
    if (e.seen == 0) continue;
    const openvdb::Coord origin(block.origin.x(), block.origin.y(), block.origin.z());
    auto* leaf = new openvdb::BoolTree::LeafNodeType(origin, false, false);
    // Word by word: the leaf's value mask and its values are both these bits (OpenVDB's
    // 512-bit masks number voxels as Block::Offset does).
    openvdb::BoolTree::LeafNodeType::NodeMaskType& mask = leaf->getValueMask();
    auto* values = leaf->buffer().data();
    for (int w = 0; w < kWords; ++w) {
      mask.getWord<openvdb::Index64>(w) = e.bits[w];
      values[w] = e.bits[w];
    }
    leaves->visible.emplace_back(e.camera, leaf);
  }
}

// Without kept state: drops block i's entries, per-pair data and caches (see there).
void DropPairData(BlockState& old, UpdatePass* u, std::size_t i) {
  const bool in_place = u->in_place;
  std::vector<std::vector<CameraEntry>>& cast = u->cast;
  std::vector<BlockState>& next = u->next;
  // One evaluation only: keep the summary (the per-camera counts), drop the entries, the
  // per-pair data and the caches now, block by block, so that they never add up.
  BlockState& n = in_place ? old : next[i];
  n.counts.clear();
  for (const CameraEntry& e : cast[i]) n.counts.push_back({e.camera, e.rays, e.seen});
  std::sort(n.counts.begin(), n.counts.end(),
            [](const BlockState::CameraCount& a, const BlockState::CameraCount& b) {
              return a.camera < b.camera;
            });
  std::vector<CameraEntry>().swap(cast[i]);
  std::vector<std::int32_t>().swap(next[i].coverage);
  std::vector<std::uint8_t>().swap(next[i].status);
  std::vector<float>().swap(next[i].sigma_max);
  std::vector<float>().swap(next[i].sigma_steady);
  std::vector<double>().swap(next[i].pair_dot);
  std::vector<std::int32_t>().swap(next[i].pair_a);
  std::vector<std::int32_t>().swap(next[i].pair_b);
  std::vector<float>().swap(next[i].best_density);
  std::vector<std::int32_t>().swap(next[i].best_camera);
  decltype(next[i].sums)().swap(next[i].sums);
  std::vector<std::uint8_t>().swap(next[i].sum_band);
  std::vector<std::int32_t>().swap(next[i].band_count);
}

// A scene update: drops block i's re-cast views that equal the kept ones (nothing changed for
// that camera there), from the cast and from the block's changed cameras.
void DropUnchangedViews(const BlockState& old, UpdatePass* u, std::size_t i) {
  std::vector<CameraEntry>& cast = u->cast[i];
  std::vector<int>& changed = u->block_changed[i];
  std::size_t kept = 0;
  for (std::size_t k = 0; k < cast.size(); ++k) {
    const CameraEntry* was = FindEntry(old.entries, cast[k].camera);
    if (was && was->bits == cast[k].bits) {
      changed.erase(std::find(changed.begin(), changed.end(), cast[k].camera));
      continue;
    }
    if (kept != k) cast[kept] = std::move(cast[k]);
    ++kept;
  }
  cast.resize(kept);
}

// Derives block i of `dirty` from its kept and re-cast entries, and makes its camera leaves.
void DeriveBlock(State& S, const RigData& rd, UpdatePass* u, std::size_t i) {
  // A scene update's changed cameras are the block's own.
  thread_local std::vector<std::uint8_t> block_is_changed;
  if (u->per_block) {
    block_is_changed.assign(rd.centres.size() + 1, 0);
    for (int c : u->block_changed[i]) block_is_changed[c] = 1;
  }
  const std::vector<std::uint8_t>& is_changed = u->per_block ? block_is_changed : u->is_changed;
  std::vector<std::vector<CameraEntry>>& cast = u->cast;
  std::vector<BlockState>& next = u->next;
  std::vector<BlockLeaves>& leaves = u->leaves;
  const bool in_place = u->in_place;
  const std::size_t b = u->dirty[i];
  const Block& block = S.blocks[b];
  BlockState& old = S.states[b];
  // Dirty voxels: where a changed camera saw or sees.
  Bits voxels{};
  if (old.coverage.empty()) {
    for (int x = 0; x < block.extent.x(); ++x)
      for (int y = 0; y < block.extent.y(); ++y)
        for (int z = 0; z < block.extent.z(); ++z)
          if (block.IsFree(x, y, z)) SetBit(voxels, Block::Offset(x, y, z));
  } else if (u->per_block) {
    // Only the occlusion changed: the voxels a camera sees now and did not, or the reverse. The
    // others' contributions are the same bits (the same expressions, lane by lane), so their sums
    // and everything derived from them stay.
    for (const CameraEntry& e : cast[i]) {
      const CameraEntry* was = FindEntry(old.entries, e.camera);
      for (int w = 0; w < kWords; ++w) voxels[w] |= e.bits[w] ^ (was ? was->bits[w] : 0);
    }
  } else {
    for (const CameraEntry& e : old.entries)
      if (is_changed[e.camera])
        for (int w = 0; w < kWords; ++w) voxels[w] |= e.bits[w];
    for (const CameraEntry& e : cast[i])
      for (int w = 0; w < kWords; ++w) voxels[w] |= e.bits[w];
  }
  std::int64_t count = 0;
  for (std::uint64_t w : voxels) count += PopcountInline(w);
  u->dirty_voxels += count;
  std::vector<const CameraEntry*> view;
  view.reserve(old.entries.size() + cast[i].size());
  for (const CameraEntry& e : old.entries)
    if (!is_changed[e.camera]) view.push_back(&e);
  for (const CameraEntry& e : cast[i]) view.push_back(&e);
  std::sort(view.begin(), view.end(),
            [](const CameraEntry* a, const CameraEntry* b) { return a->camera < b->camera; });
  if (count > 0 || old.coverage.empty())
    S.Derive(block, old, std::move(view), voxels, is_changed, rd.centres,
             in_place ? &old : &next[i], &leaves[i], in_place, u->per_block);
  // Spilled fields: the block's leaf to its file, out of memory (FieldOptions::spilled_fields).
  BlockLeaves& l = leaves[i];
  for (int f = 0; f < kFloatFieldCount; ++f)
    if (S.spills[f] && l.floats[f]) {
      S.spills[f]->Append(*l.floats[f]);
      if (l.float_owned[f]) delete l.floats[f];
      l.floats[f] = nullptr;
      l.float_owned[f] = false;
    }
  // Camera grids: a leaf per re-cast camera that sees part of the block.
  if (S.want_cameras) CameraLeaves(block, cast[i], &leaves[i]);
  if (!S.keep) DropPairData(old, u, i);
}

// Casts dirty block i's changed cameras (a camera update: those that may see it now; a scene
// update: the block's own, again where the block is kept, then drops the views that did not
// change).
void CastBlock(State& S, const RigData& rd, UpdatePass* u, std::size_t i) {
  const FieldOptions& opt = S.options;
  const std::size_t b = u->dirty[i];
  const std::vector<std::int32_t>& candidates = u->candidates[b];
  std::vector<CameraEntry>& cast = u->cast[i];
  std::vector<Ray>* rays = opt.record_rays ? &u->next[i].rays : nullptr;
  const bool again = u->per_block && !S.states[b].coverage.empty();
  thread_local State::BlockPoints points;
  points.count = -1;
  const Aabb box = again ? BlockCentreBox(S.fields.lattice, S.blocks[b]) : Aabb();
  for (int c : u->per_block ? u->block_changed[i] : u->changed) {
    if (!u->per_block && !std::binary_search(candidates.begin(), candidates.end(), c)) continue;
    if (points.count < 0) S.Points(S.blocks[b], &points);
    cast.emplace_back();
    const CameraEntry* was = again ? FindEntry(S.states[b].entries, c) : nullptr;
    if (!was) {
      S.Cast(points, c, rd, &cast.back(), rays);
      u->rays += cast.back().rays;
      continue;
    }
    // The moved boxes this camera's segments to the block may meet.
    thread_local std::vector<EyeCone> before, after;
    const EyeCone segments = ConeOf(rd.centres[c], box);
    const auto near = [&](const std::vector<EyeCone>& all, std::vector<EyeCone>* out) {
      out->clear();
      for (const EyeCone& moved : all)
        if (ConesMayMeet(segments, moved)) out->push_back(moved);
    };
    near(u->before_cones[std::size_t(c)], &before);
    near(u->after_cones[std::size_t(c)], &after);
    u->rays += S.CastAgain(points, c, rd, *was, State::Again{&before, &after}, &cast.back());
  }
  if (again) DropUnchangedViews(S.states[b], u, i);
}

// The parallel phase: casts the changed cameras and derives the dirty blocks (`u->dirty`).
// Returns false, with nothing derived in place, when cancelled.
bool CastAndDerive(State& S, const RigData& rd, UpdatePass* u) {
  const FieldOptions& opt = S.options;
  const std::vector<std::size_t>& dirty = u->dirty;
  u->in_place = S.evaluated;
  const bool in_place = u->in_place;
  u->next.resize(dirty.size());
  u->cast.resize(dirty.size());
  u->leaves.resize(dirty.size());
  std::atomic<std::size_t>& done = u->done;
  std::atomic<bool>& cancelled = u->cancelled;
  const std::size_t report_every = std::max<std::size_t>(1, dirty.size() / 200);
  const double phases = in_place ? 2.0 : 1.0;
  const auto derive = [&](std::size_t i) { DeriveBlock(S, rd, u, i); };
  const auto report = [&](double base) {
    const std::size_t n = done.fetch_add(1) + 1;
    if (opt.progress && (n % report_every == 0 || n == dirty.size()))
      opt.progress((base + double(n) / double(dirty.size())) / phases);
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, dirty.size(), 1), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      if (cancelled.load(std::memory_order_relaxed)) return;
      if (opt.cancel && opt.cancel->load(std::memory_order_relaxed)) {
        cancelled = true;
        return;
      }
      CastBlock(S, rd, u, i);
      if (!in_place) derive(i);
      report(0.0);
    }
  });
  if (cancelled) return false;
  if (in_place) {
    done = 0;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, dirty.size(), 1), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        derive(i);
        report(1.0);
      }
    });
  }
  return true;
}

// Puts the new leaves into the grids, a task per grid (the trees are independent).
void InsertLeaves(State& S, int new_count, UpdatePass* u) {
  const std::vector<std::size_t>& dirty = u->dirty;
  std::vector<BlockLeaves>& leaves = u->leaves;
  Fields::Impl& g = S.fields.impl();
  if (S.want_cameras && new_count != static_cast<int>(g.visible.size())) {
    const std::size_t had = g.visible.size();
    g.visible.resize(new_count);
    for (std::size_t c = had; c < g.visible.size(); ++c)
      MakeGrid(g.visible[c], "visible", g.transform);
  }
  // Each grid's leaves go in by a task of their own (the trees are independent), then the states.
  std::vector<std::function<void()>> grid_tasks;
  const auto origin_of = [&](std::size_t i) {
    const Block& block = S.blocks[dirty[i]];
    return openvdb::Coord(block.origin.x(), block.origin.y(), block.origin.z());
  };
  grid_tasks.emplace_back([&] {
    for (std::size_t i = 0; i < dirty.size(); ++i) {
      BlockLeaves& l = leaves[i];
      if (l.coverage_tile) g.coverage->tree().addTile(1, origin_of(i), 0, true);
      if (l.coverage && l.coverage_owned) g.coverage->tree().addLeaf(l.coverage);
    }
  });
  for (int f = 0; f < kFloatFieldCount; ++f) {
    if (!S.want_float[f]) continue;
    grid_tasks.emplace_back([&, f] {
      openvdb::FloatTree& tree = S.float_grids[f]->tree();
      for (std::size_t i = 0; i < dirty.size(); ++i) {
        BlockLeaves& l = leaves[i];
        if (l.floats[f] && l.float_owned[f])
          tree.addLeaf(l.floats[f]);
        else if (l.floats[f])
          ;  // rewritten in place
        else if (l.remove_float[f] && tree.probeConstLeaf(origin_of(i))) {
          tree.addTile(1, origin_of(i), 0.0f, false);
          u->tiled_float[f] = 1;
        }
      }
    });
  }
  // Per camera: the blocks where a changed camera's old leaf goes, and its new leaves.
  std::vector<std::vector<std::size_t>> camera_removed(S.want_cameras ? new_count : 0);
  std::vector<std::vector<openvdb::BoolTree::LeafNodeType*>> camera_added(camera_removed.size());
  u->tiled_visible.assign(camera_removed.size(), 0);
  if (S.want_cameras) {
    for (std::size_t i = 0; i < dirty.size(); ++i) {
      for (const CameraEntry& e : S.states[dirty[i]].entries)
        if (u->Changed(i, e.camera) && e.camera < new_count && e.seen > 0)
          camera_removed[e.camera].push_back(i);
      for (auto& [camera, leaf] : leaves[i].visible) camera_added[camera].push_back(leaf);
    }
    for (int c = 0; c < new_count; ++c)
      if (!camera_removed[c].empty() || !camera_added[c].empty())
        grid_tasks.emplace_back([&, c] {
          openvdb::BoolTree& tree = g.visible[c]->tree();
          for (std::size_t i : camera_removed[c])
            if (tree.probeConstLeaf(origin_of(i))) {
              tree.addTile(1, origin_of(i), false, false);
              u->tiled_visible[c] = 1;
            }
          for (auto* leaf : camera_added[c]) tree.addLeaf(leaf);
        });
  }
  tbb::parallel_for(std::size_t(0), grid_tasks.size(), [&](std::size_t t) { grid_tasks[t](); });
}

// Puts the new candidate lists, entries and caches into the state.
void StoreStates(State& S, UpdatePass* u) {
  const std::vector<std::size_t>& dirty = u->dirty;
  std::vector<std::vector<std::int32_t>>& candidates = u->candidates;
  std::vector<std::vector<CameraEntry>>& cast = u->cast;
  std::vector<BlockState>& next = u->next;
  for (std::size_t b = 0; b < S.blocks.size(); ++b)
    S.states[b].candidates = std::move(candidates[b]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, dirty.size(), 16), [&](const auto& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      BlockState& s = S.states[dirty[i]];
      // Entries: the kept ones and the re-cast ones, in camera order.
      std::vector<CameraEntry> entries;
      entries.reserve(s.entries.size() + cast[i].size());
      for (CameraEntry& e : s.entries)
        if (!u->Changed(i, e.camera)) entries.push_back(std::move(e));
      for (CameraEntry& e : cast[i]) entries.push_back(std::move(e));
      std::sort(entries.begin(), entries.end(),
                [](const CameraEntry& a, const CameraEntry& b) { return a.camera < b.camera; });
      BlockState& n = next[i];
      if (!n.histogram.empty() || s.coverage.empty()) {
        n.candidates = std::move(s.candidates);
        n.entries = std::move(entries);
        s = std::move(n);
      } else {
        s.entries = std::move(entries);  // nothing seen changed: caches and summary stay
        s.rays = std::move(n.rays);
      }
    }
  });
}

// The serial phase of an update: the new leaves into the grids, the new entries and caches into
// the state, then the statistics.
void FinishUpdate(State& S, const Rig& rig, const RigData& rd, UpdatePass* u, FieldUpdate* update,
                  std::chrono::steady_clock::time_point t0, std::clock_t cpu0) {
  const FieldOptions& opt = S.options;
  const int new_count = static_cast<int>(rig.cameras.size());
  InsertLeaves(S, new_count, u);
  StoreStates(S, u);
  Fields::Impl& g = S.fields.impl();
  for (int f = 0; f < kFloatFieldCount; ++f)
    if (S.spills[f]) {  // the (empty) grid moves beside its leaves' file
      const std::string name = kFloatFieldNames[f];
      g.spilled[name] = SpilledGrid{g.floats.at(name), std::move(S.spills[f])};
      g.floats.erase(name);
      S.float_grids[f] = nullptr;
    }
  if (S.want_cameras && new_count < static_cast<int>(g.visible.size())) g.visible.resize(new_count);
  if (S.evaluated) {
    // A scene update may have removed blocks from every grid (RemoveBlockLeaves): all pruned.
    // A camera update tiled only some grids; the others are as pruned as before it (the first
    // evaluation adds no inactive tiles). Pruning all of them again (24 camera grids and 7 float
    // grids on the capture stage) took about 0.9 ms of a 30 ms update.
    if (u->per_block && g.coverage) openvdb::tools::pruneInactive(g.coverage->tree());
    for (int f = 0; f < kFloatFieldCount; ++f)
      if (S.float_grids[f] && (u->per_block || u->tiled_float[f]))
        openvdb::tools::pruneInactive(S.float_grids[f]->tree());
    for (std::size_t c = 0; c < g.visible.size(); ++c)
      if (u->per_block || (c < u->tiled_visible.size() && u->tiled_visible[c]))
        openvdb::tools::pruneInactive(g.visible[c]->tree());
  }

  S.rig = rig;
  S.evaluated = true;
  update->dirty_voxels = u->dirty_voxels;
  update->rays = u->rays;
  FieldStats& st = S.fields.stats;
  const double estimated = st.estimated_bytes;
  S.Totals(&st, new_count, rd.enabled);
  if (!S.keep) {
    // One evaluation: the blocks' lists are in the totals now, so freed. (A one-shot command hands
    // the freed pages back after the evaluation: ReleaseFreedMemory.)
    for (BlockState& s : S.states) {
      std::vector<float>().swap(s.sigma_list);
      std::vector<float>().swap(s.steady_list);
    }
  }
  st.estimated_bytes = estimated;
  st.angle_pairs_tried = S.angle_pairs_tried;
  st.angle_pairs_all = S.angle_pairs_all;
  st.phases.contributions = 1e-9 * double(S.phase_ns[State::kContributions]);
  st.phases.sums = 1e-9 * double(S.phase_ns[State::kSums]);
  st.phases.eigenvalues = 1e-9 * double(S.phase_ns[State::kEigenvalues]);
  st.phases.angles = 1e-9 * double(S.phase_ns[State::kAngles]);
  st.active_set_seconds = update->full || u->per_block ? S.active_set_seconds : 0.0;
  if (opt.record_rays && update->full) {
    // Joined in block order; without kept state each block's own copy goes as it is joined.
    std::size_t count = 0;
    for (const BlockState& s : S.states) count += s.rays.size();
    S.fields.recorded_rays.clear();
    S.fields.recorded_rays.reserve(count);
    for (BlockState& s : S.states) {
      S.fields.recorded_rays.insert(S.fields.recorded_rays.end(), s.rays.begin(), s.rays.end());
      if (!S.keep) std::vector<Ray>().swap(s.rays);
    }
  }
  update->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  st.seconds = update->seconds + (update->full ? S.active_set_seconds : 0.0);
  st.cpu_seconds = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
}

}  // namespace

FieldUpdate FieldEvaluator::Update(const Rig& rig) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  State& S = *state_;
  FieldUpdate update;
  if (S.evaluated && !S.keep) TakeFields();  // nothing kept: evaluate again in full

  // Which cameras changed (by index; cameras added or removed at the end count as changed).
  UpdatePass u;
  const int new_count = static_cast<int>(rig.cameras.size());
  const int old_count = S.evaluated ? static_cast<int>(S.rig.cameras.size()) : 0;
  std::vector<int>& changed = u.changed;
  for (int c = 0; c < std::max(new_count, old_count); ++c)
    if (!S.evaluated || c >= old_count || c >= new_count ||
        !SameCameraGeometry(S.rig.cameras[c], rig.cameras[c]))
      changed.push_back(c);
  update.full = !S.evaluated;
  update.changed_cameras = static_cast<int>(changed.size());
  if (S.evaluated && changed.empty()) {
    S.rig = rig;  // names, colours and ids may differ
    update.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return update;
  }
  if (!S.evaluated || new_count > old_count) CheckCameraBudget(S, new_count);
  const RigData rd = S.Prepare(rig);
  S.angle_pairs_tried = 0;
  S.angle_pairs_all = 0;
  for (auto& ns : S.phase_ns) ns = 0;

  // New candidate lists; the blocks to visit are those a changed camera's old or new frustum
  // meets (all of them the first time).
  if (!S.evaluated) {
    S.states.assign(S.blocks.size(), BlockState{});
    S.ResetGrids(new_count);
    S.fields.stats.active_set = S.active_stats;
  }
  VisitBlocks(S, rd, new_count, old_count, &u);
  update.dirty_blocks = static_cast<std::int64_t>(u.dirty.size());

  // Kept state: an upper bound (every candidate camera sees every free voxel) against the budget.
  if (S.keep) CheckKeptBudget(S, rig, u.candidates);

  // The parallel phase: cast the changed cameras, derive the dirty voxels, make leaves. A full
  // evaluation does both per block (the per-pair data is dropped block by block without kept
  // state). An update casts every changed camera first, where it can still be cancelled, then
  // derives in place: into the kept caches and the grids' own leaves, no copies.
  if (!CastAndDerive(S, rd, &u)) {
    for (BlockLeaves& l : u.leaves) l.Free();
    if (!S.evaluated) {
      S.states.clear();
      S.fields.impl() = Fields::Impl();
    }
    update.cancelled = true;
    update.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return update;
  }

  FinishUpdate(S, rig, rd, &u, &update, t0, cpu0);
  return update;
}

namespace {

// A block's key for matching blocks by origin (lattice indices below 2^21).
std::uint64_t OriginKey(const Block& block) {
  return (std::uint64_t(block.origin.x()) << 42) | (std::uint64_t(block.origin.y()) << 21) |
         std::uint64_t(block.origin.z());
}

// Whether two blocks at the same origin hold the same free voxels.
bool SameVoxels(const Block& a, const Block& b) {
  if (a.extent != b.extent || a.free_voxels != b.free_voxels) return false;
  if (a.mask.empty() && b.mask.empty()) return true;
  for (int x = 0; x < a.extent.x(); ++x)
    for (int y = 0; y < a.extent.y(); ++y)
      for (int z = 0; z < a.extent.z(); ++z)
        if (a.IsFree(x, y, z) != b.IsFree(x, y, z)) return false;
  return true;
}

// Removes a block's leaves from every grid (its voxels leave the region or are evaluated anew).
void RemoveBlockLeaves(State& S, const Block& block) {
  Fields::Impl& g = S.fields.impl();
  const openvdb::Coord origin(block.origin.x(), block.origin.y(), block.origin.z());
  if (g.coverage) g.coverage->tree().addTile(1, origin, 0, false);
  for (int f = 0; f < kFloatFieldCount; ++f)
    if (S.want_float[f]) S.float_grids[f]->tree().addTile(1, origin, 0.0f, false);
  for (auto& v : g.visible) v->tree().addTile(1, origin, false, false);
}

}  // namespace

FieldUpdate FieldEvaluator::UpdateScene(const Scene& scene, const RayCaster& caster,
                                        const SceneChange& moved) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  State& S = *state_;
  const double scale = scene.ContentBounds().diagonal();
  if (!S.evaluated || !S.keep || scale != S.scene_scale) {
    // Nothing kept, or the visibility tolerance (a share of the scene's size) changes with it:
    // the new scene evaluated in full.
    const bool evaluated = S.evaluated;
    const Rig rig = S.rig;
    const double estimated = S.fields.stats.estimated_bytes;
    if (evaluated) TakeFields();
    S.scene = &scene;
    S.caster = &caster;
    S.scene_scale = scale;
    BuildBlocks(S, scene, RegionSolids(scene), {});
    S.active_set_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    S.fields.stats.estimated_bytes = estimated;
    if (!evaluated) return FieldUpdate{};
    FieldUpdate update = Update(rig);
    update.seconds += S.active_set_seconds;
    return update;
  }
  FieldUpdate update;
  // The new active set; blocks matched to the old ones by origin.
  std::vector<Block> old_blocks = std::move(S.blocks);
  std::vector<BlockState> old_states = std::move(S.states);
  S.scene = &scene;
  S.caster = &caster;
  BuildBlocks(S, scene, RegionSolids(scene), {});
  S.active_set_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::unordered_map<std::uint64_t, std::size_t> old_index;
  old_index.reserve(old_blocks.size());
  for (std::size_t i = 0; i < old_blocks.size(); ++i)
    old_index.emplace(OriginKey(old_blocks[i]), i);

  const Rig& rig = S.rig;
  const RigData rd = S.Prepare(rig);
  S.angle_pairs_tried = 0;
  S.angle_pairs_all = 0;
  for (auto& ns : S.phase_ns) ns = 0;
  // Boxes padded for round-off: a segment that misses one cannot meet what moved inside it.
  const double pad = 1e-6 * scale + 1e-9;
  const auto padded = [pad](const std::vector<Aabb>& in) {
    std::vector<Aabb> out;
    for (Aabb b : in) {
      if (b.empty()) continue;
      b.min.array() -= pad;
      b.max.array() += pad;
      out.push_back(b);
    }
    return out;
  };
  UpdatePass u;
  const std::vector<Aabb> moved_before = padded(moved.before), moved_after = padded(moved.after);
  u.per_block = true;
  u.candidates.resize(S.blocks.size());
  S.states.resize(S.blocks.size());
  std::vector<std::vector<int>> recast(S.blocks.size());
  std::vector<std::uint8_t> dirty_block(S.blocks.size(), 0), old_kept(old_blocks.size(), 0);
  const int count = static_cast<int>(rig.cameras.size());
  u.before_cones.resize(static_cast<std::size_t>(count));
  u.after_cones.resize(static_cast<std::size_t>(count));
  for (int c = 0; c < count; ++c) {
    for (const Aabb& m : moved_before)
      u.before_cones[std::size_t(c)].push_back(ConeOf(rd.centres[c], m));
    for (const Aabb& m : moved_after)
      u.after_cones[std::size_t(c)].push_back(ConeOf(rd.centres[c], m));
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, S.blocks.size(), 16), [&](const auto& r) {
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      const Block& block = S.blocks[b];
      const Aabb box = BlockCentreBox(S.fields.lattice, block);
      const auto it = old_index.find(OriginKey(block));
      if (it != old_index.end() && SameVoxels(old_blocks[it->second], block)) {
        // The same voxels: re-cast the cameras whose segments to them can meet what moved.
        old_kept[it->second] = 1;
        S.states[b] = std::move(old_states[it->second]);
        u.candidates[b] = S.states[b].candidates;
        for (int c : u.candidates[b]) {
          const EyeCone segments = ConeOf(rd.centres[c], box);
          const auto meets = [&segments](const std::vector<EyeCone>& cones) {
            for (const EyeCone& m : cones)
              if (ConesMayMeet(segments, m)) return true;
            return false;
          };
          if (meets(u.before_cones[std::size_t(c)]) || meets(u.after_cones[std::size_t(c)]))
            recast[b].push_back(c);
        }
        dirty_block[b] = !recast[b].empty();
      } else {
        // New or other voxels (a moved solid came or went): evaluated anew.
        S.states[b] = BlockState{};
        for (int c = 0; c < count; ++c)
          if (rd.culler->MayIntersect(c, box)) u.candidates[b].push_back(c);
        recast[b] = u.candidates[b];
        dirty_block[b] = 1;
      }
    }
  });
  for (std::size_t i = 0; i < old_blocks.size(); ++i)
    if (!old_kept[i]) RemoveBlockLeaves(S, old_blocks[i]);
  old_states.clear();
  for (std::size_t b = 0; b < S.blocks.size(); ++b)
    if (dirty_block[b]) {
      u.dirty.push_back(b);
      u.block_changed.push_back(std::move(recast[b]));
    }
  update.dirty_blocks = static_cast<std::int64_t>(u.dirty.size());
  S.fields.stats.active_set = S.active_stats;
  // Not cancellable: the blocks are already the new scene's.
  const std::atomic<bool>* cancel = S.options.cancel;
  S.options.cancel = nullptr;
  CastAndDerive(S, rd, &u);
  S.options.cancel = cancel;
  std::vector<std::uint8_t> camera_changed(rig.cameras.size(), 0);
  for (const std::vector<int>& changed : u.block_changed)
    for (int c : changed) camera_changed[c] = 1;
  for (std::uint8_t c : camera_changed) update.changed_cameras += c;
  FinishUpdate(S, rig, rd, &u, &update, t0, cpu0);
  return update;
}

double EstimateFieldBytes(const VoxelLattice& lattice, const std::vector<std::string>& fields,
                          int camera_count) {
  return EstimateBytesForVoxels(512.0 * LatticeBlocks(lattice), fields, camera_count);
}

static double PerCameraBytes(const VoxelLattice& lattice, double blocks,
                             const std::vector<std::string>& fields, bool kept) {
  // Per block while evaluated: two candidate indices, a count, the per-camera statistics record.
  double bytes =
      1.15 * blocks *
          (2.0 * sizeof(std::int32_t) + sizeof(std::int64_t) + sizeof(BlockState::CameraCount)) +
      64.0;
  if (Wants(fields, "cameras")) {
    // One BoolGrid per camera: the grid, its root, metadata and writing (20 kB; 2,000 cameras
    // measured 16), every internal node the region touches (32^3 and 16^3 entries of 8 bytes and
    // their masks), and at most one 192-byte leaf per block (where the camera sees it).
    auto nodes = [&](int span) {
      double n = 1;
      for (int a = 0; a < 3; ++a)
        n *= std::ceil(double(std::max(lattice.dims[a], 1)) / span);  // index 0 starts a node
      return n;
    };
    bytes += 20480.0 + nodes(4096) * (32768.0 * 8 + 2 * 4096) +
             nodes(128) * (4096.0 * 8 + 2 * 512) + blocks * 192.0;
  }
  // Kept state (sessions) is bounded apart, at each update (its entries cover only the blocks a
  // camera's frustum meets): "incremental updates of rig ... need up to".
  (void)kept;
  return bytes;
}

static double EstimateBytesForVoxels(double voxels, const std::vector<std::string>& fields,
                                     int camera_count) {
  const double blocks = voxels / 512.0 + 1.0;
  // Per 8^3 block while it is evaluated: its Block record and a 512-byte mask where it is partial,
  // its state and the next one (both arrays live until the serial phase), its new leaves' record,
  // and the heap behind their vectors (candidate lists twice, histogram, per-camera counts, with
  // the allocator's headers), plus 15 % for the allocator's rounding. Measured against the
  // 10^9-voxel hall of docs/scale.md (coverage alone): 8.22 bytes per voxel at the peak, this
  // estimate 8.6.
  const double per_block =
      sizeof(Block) + 512.0 + 2.0 * sizeof(BlockState) + sizeof(BlockLeaves) + 256.0 +
      (2.0 * sizeof(std::int32_t) + sizeof(std::int64_t) + sizeof(BlockState::CameraCount)) *
          camera_count;
  double bytes = blocks * 1.15 * per_block;
  for (const std::string& f : fields) bytes += voxels * BytesPerVoxel(f);
  return bytes + 64.0 * camera_count;
}

std::vector<BlockColumns> PlanTiles(const VoxelLattice& lattice,
                                    const std::vector<std::string>& fields, double budget_bytes,
                                    double tile_side) {
  const int nbx = (lattice.dims.x() + 7) / 8, nby = (lattice.dims.y() + 7) / 8;
  int sx = 1, sy = 1;  // tile size in block columns
  if (tile_side > 0) {
    const double blocks = tile_side / (8.0 * lattice.voxel_size);
    sx = sy = static_cast<int>(std::clamp(std::round(blocks), 1.0, double(std::max(nbx, nby))));
  } else {
    VoxelLattice column = lattice;
    column.dims = Eigen::Vector3i(8, 8, lattice.dims.z());
    const double per_column = EstimateFieldBytes(column, fields, 0);
    const double columns = std::max(1.0, std::floor(0.5 * budget_bytes / per_column));
    if (columns >= double(nbx) * nby) {
      sx = nbx;
      sy = nby;
    } else {
      // As square as the lattice allows: a side of sqrt(columns), the other side filling the rest.
      sx = std::clamp(static_cast<int>(std::sqrt(columns)), 1, nbx);
      sy = std::clamp(static_cast<int>(columns / sx), 1, nby);
      if (sy == nby) sx = std::clamp(static_cast<int>(columns / sy), 1, nbx);
    }
  }
  std::vector<BlockColumns> tiles;
  for (int x = 0; x < nbx; x += sx)
    for (int y = 0; y < nby; y += sy)
      tiles.push_back({x, std::min(x + sx, nbx), y, std::min(y + sy, nby)});
  return tiles;
}

Fields EvaluateFields(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const FieldOptions& options) {
  FieldEvaluator evaluator(scene, caster, options, /*keep_state=*/false);
  evaluator.Update(rig);
  return evaluator.TakeFields();
}

}  // namespace pandora
