#include "volume/fields.h"

#include <openvdb/openvdb.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <ctime>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include "analysis/error.h"
#include "analysis/inside_mesh.h"
#include "analysis/uncertainty.h"
#include "analysis/visibility.h"
#include "volume/fields_vdb.h"

namespace pandora {

Fields::Fields() : impl_(std::make_unique<Impl>()) {}
Fields::~Fields() = default;
Fields::Fields(Fields&&) noexcept = default;
Fields& Fields::operator=(Fields&&) noexcept = default;

namespace {

bool Wants(const std::vector<std::string>& fields, const std::string& name) {
  return std::find(fields.begin(), fields.end(), name) != fields.end();
}

// The float fields in a fixed order; index into BlockResult::floats.
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

// Results of one block, before they become OpenVDB leaves.
struct BlockResult {
  openvdb::Int32Tree::LeafNodeType* coverage = nullptr;
  openvdb::Int64Tree::LeafNodeType* cameras = nullptr;
  std::array<FloatLeaf*, kFloatFieldCount> floats{};
  bool coverage_tile = false;  // A whole leaf of zeros: stored as a tile.
  std::vector<Ray> rays;
  std::array<std::int64_t, 65> histogram{};
  std::vector<std::int64_t> per_camera;
  std::int64_t tests = 0, ray_count = 0, seen = 0, triangulable = 0, unobservable = 0;
  std::vector<float> sigma_max, sigma_max_steady;
};

// Rows of the per-candidate statistics arrays.
enum StatRow {
  kObservable,    // 1 or 0
  kSigmaMaxMm,    // sqrt of the largest variance, mm
  kSigmaMeanMm,   // sqrt(trace / 3), mm
  kCond,          // largest / smallest eigenvalue of J
  kVar0,          // variances 1 / lambda_k, m^2 (descending); the steady pass overwrites them
  kVar1,
  kVar2,
  kSteadyMaxMm,
  kSteadyMeanMm,
  kStatRows
};

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

// atan(t) for t >= 0 (+inf allowed) to 2.1e-8 relative (measured against std::atan over
// 1e-12..1e12), branch-free so that it vectorises:
// Cephes' single-precision reduction (t > tan(3 pi/8): pi/2 - atan(1/t); t > tan(pi/8):
// pi/4 + atan((t-1)/(t+1))) and its degree-9 odd minimax polynomial. The angle grid is float.
inline double AtanNonNegative(double t) {
  const bool big = t > 2.414213562373095;
  const bool mid = t > 0.4142135623730950;
  const double x = big ? -1.0 / t : (mid ? (t - 1.0) / (t + 1.0) : t);
  const double base = big ? M_PI_2 : (mid ? M_PI_4 : 0.0);
  const double z = x * x;
  return base +
         (((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z -
          3.33329491539e-1) * z * x +
         x;
}

// The triangulation angle of `count` voxels at (x, y, z) seen by the cameras in mask[m]: the
// largest angle in degrees between two rays from camera centres that see the voxel. Vectorised
// over voxels, in tiles of 64 that keep every camera's directions in L1: per camera the unit
// directions (into `dirs`, 3 * 64 per camera; NaN where the camera does not see the voxel, so every
// comparison with it fails), per camera pair the dot product, keeping the pair with the smallest,
// then the angle as atan2(|cross|, dot) (both keep their relative
// accuracy, so tiny and near-180 degree angles are as exact as at 90). No per-ray storage.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx512f", "avx2", "default")))
#endif
void TriangulationAngles(int count, const double* x, const double* y, const double* z,
                         const std::uint64_t* mask, const std::vector<Vec3>& centres,
                         std::uint64_t cameras, double* dirs, float* degrees) {
  constexpr int kTile = 64;
  const int camera_count = static_cast<int>(centres.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int start = 0; start < count; start += kTile) {
    const int n = std::min(kTile, count - start);
    const double *tx = x + start, *ty = y + start, *tz = z + start;
    const std::uint64_t* tmask = mask + start;
    for (int c = 0; c < camera_count; ++c) {
      if (!(cameras >> c & 1)) continue;
      const double cx = centres[c].x(), cy = centres[c].y(), cz = centres[c].z();
      double* d = dirs + 3 * kTile * c;
#pragma omp simd
      for (int m = 0; m < n; ++m) {
        const double vx = tx[m] - cx, vy = ty[m] - cy, vz = tz[m] - cz;
        const double inv =
            (tmask[m] >> c & 1) != 0 ? 1.0 / std::sqrt(vx * vx + vy * vy + vz * vz) : nan;
        d[m] = vx * inv;
        d[m + kTile] = vy * inv;
        d[m + 2 * kTile] = vz * inv;
      }
    }
    double best_dot[kTile];
    std::int64_t best_a[kTile], best_b[kTile];  // camera indices of the best pair
    for (int m = 0; m < kTile; ++m) best_dot[m] = 2.0, best_a[m] = 0, best_b[m] = 0;
    for (int a = 0; a < camera_count; ++a) {
      if (!(cameras >> a & 1)) continue;
      const double* ad = dirs + 3 * kTile * a;
      for (int b = a + 1; b < camera_count; ++b) {
        if (!(cameras >> b & 1)) continue;
        const double* bd = dirs + 3 * kTile * b;
#pragma omp simd
        for (int m = 0; m < n; ++m) {
          const double dot =
              ad[m] * bd[m] + ad[m + kTile] * bd[m + kTile] + ad[m + 2 * kTile] * bd[m + 2 * kTile];
          const bool take = dot < best_dot[m];  // false for NaN: a camera that does not see it
          best_dot[m] = take ? dot : best_dot[m];
          best_a[m] = take ? a : best_a[m];
          best_b[m] = take ? b : best_b[m];
        }
      }
    }
#pragma omp simd
    for (int m = 0; m < n; ++m) {
      const double* ad = dirs + 3 * kTile * best_a[m] + m;
      const double* bd = dirs + 3 * kTile * best_b[m] + m;
      const double ax = ad[0], ay = ad[kTile], az = ad[2 * kTile];
      const double bx = bd[0], by = bd[kTile], bz = bd[2 * kTile];
      const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
      const double dot = best_dot[m];
      const double angle = AtanNonNegative(std::sqrt(cx * cx + cy * cy + cz * cz) / std::abs(dot));
      degrees[start + m] = static_cast<float>((dot < 0 ? M_PI - angle : angle) * (180.0 / M_PI));
    }
  }
}

}  // namespace

double EstimateFieldBytes(const VoxelLattice& lattice, const std::vector<std::string>& fields,
                          int camera_count) {
  const double voxels = static_cast<double>(lattice.voxel_count());
  const double blocks = voxels / 512.0 + 1.0;
  // Active-set pass: one Block record per 8^3 block, a 512-byte mask where a block is partial.
  double bytes = blocks * (sizeof(Block) + 512.0 + sizeof(BlockResult));
  for (const std::string& f : fields) bytes += voxels * BytesPerVoxel(f);
  return bytes + 64.0 * camera_count;
}

Fields EvaluateFields(const Scene& scene, const Rig& rig, const RayCaster& caster,
                      const FieldOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  const std::string& file = options.scene_path.empty() ? scene.path : options.scene_path;
  if (auto problem = CheckFieldList(options.fields, scene.study.motion.has_value()))
    throw InputError(file, "$.study.fields[" + std::to_string(problem->index) + "]", problem->reason,
                     problem->hint);
  if (options.fields.empty())
    throw InputError(file, "$.study.fields", "no field requested", "ask for at least 'coverage'");
  const int camera_count = static_cast<int>(rig.cameras.size());
  if (camera_count > 64)
    throw InputError(file, "$.rigs", "rig '" + rig.name + "' has " + std::to_string(camera_count) +
                                         " cameras; fields support at most 64",
                     "split the rig or disable cameras in a copy of it");

  Fields out;
  const Study& study = scene.study;
  // Errors about the voxel size name where it came from: the scene file or a command-line option.
  const std::string size_file = options.voxel_size_option.empty() ? file : options.voxel_size_option;
  const std::string size_path = options.voxel_size_option.empty() ? "$.study.voxel_size" : "";
  out.lattice = MakeLattice(study.region.box, study.voxel_size, size_file, size_path);
  const double estimate = EstimateFieldBytes(out.lattice, options.fields, camera_count);
  out.stats.estimated_bytes = estimate;
  if (estimate > options.memory_budget_bytes) {
    // Memory scales with 1/h^3: the smallest voxel size that fits.
    const double h_min =
        study.voxel_size * std::cbrt(estimate / options.memory_budget_bytes) * 1.01;
    std::ostringstream reason, hint;
    reason << "the region needs about " << std::llround(estimate / 1048576.0) << " MiB at voxel size "
           << study.voxel_size << " m, over the budget of "
           << std::llround(options.memory_budget_bytes / 1048576.0) << " MiB";
    hint << "use voxel_size >= " << h_min << " m, a smaller region, or raise the budget "
         << "(--memory-budget or study.memory_budget_mb)";
    if (options.voxel_size_option.empty() && !options.memory_budget_option.empty())
      throw InputError(options.memory_budget_option, "", reason.str(), hint.str());
    throw InputError(size_file, size_path, reason.str(), hint.str());
  }

  // Solids and the region mesh.
  std::vector<std::unique_ptr<InsideMesh>> solid_meshes;
  std::vector<const InsideMesh*> solids;
  for (const SceneObject& o : scene.objects) {
    if (!o.solid || o.mesh.triangles.empty()) continue;
    // Solids that cannot contain a region voxel cost nothing.
    const Aabb b = o.mesh.Bounds();
    if ((b.max.array() < study.region.box.min.array()).any() ||
        (b.min.array() > study.region.box.max.array()).any())
      continue;
    {
      solid_meshes.push_back(std::make_unique<InsideMesh>(o.mesh));
      solids.push_back(solid_meshes.back().get());
    }
  }
  std::unique_ptr<InsideMesh> region_mesh;
  if (study.region.kind == Region::Kind::kMesh)
    region_mesh = std::make_unique<InsideMesh>(study.region.mesh);

  const FrustumCuller culler(rig.cameras);
  const std::vector<Block> blocks = BuildActiveSet(out.lattice, study.region, solids,
                                                   region_mesh.get(), culler, camera_count,
                                                   &out.stats.active_set);
  out.stats.active_set_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const bool want_coverage = Wants(options.fields, "coverage");
  const bool want_cameras = Wants(options.fields, "cameras");
  std::array<bool, kFloatFieldCount> want_float{};
  for (int f = 0; f < kFloatFieldCount; ++f) want_float[f] = Wants(options.fields, kFloatFieldNames[f]);
  const bool want_resolution = want_float[kResolution];
  const bool want_static = want_float[kSigmaMax] || want_float[kSigmaMean] || want_float[kCondition];
  const bool want_steady = want_float[kSigmaMaxSteady] || want_float[kSigmaMeanSteady];
  const bool want_angle = want_float[kAngle];
  // Any uncertainty field needs the triangulability decision, so J is built for all of them.
  const bool want_information = want_static || want_steady || want_angle;
  const bool want_jacobian = want_resolution || want_information;
  const int enabled = rig.enabled_count();
  const VisibilityTester tester(rig.cameras, caster, scene.ContentBounds().diagonal());
  std::vector<double> pixel_sigma(camera_count);  // pixels
  for (int c = 0; c < camera_count; ++c)
    pixel_sigma[c] = rig.cameras[c].pixel_sigma > 0 ? rig.cameras[c].pixel_sigma : study.pixel_sigma;
  std::vector<Vec3> centres;
  for (const Camera& cam : rig.cameras) centres.push_back(cam.center());
  const MotionModel motion = study.motion.value_or(MotionModel{});
  const double frame_period = 1.0 / motion.rate_hz;

  std::vector<BlockResult> results(blocks.size());
  std::atomic<std::size_t> done{0};
  const std::size_t report_every = std::max<std::size_t>(1, blocks.size() / 200);

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 1), [&](const auto& range) {
    // Scratch for the blocks of this TBB range (the information accumulators are 24 KB).
    std::array<Ray, 512> segments;
    std::array<std::int16_t, 512> where;
    std::array<Mat23, 512> segment_jacobian;  // camera frame
    std::array<std::uint8_t, 512> occluded;
    std::array<std::array<double, 6>, 512> information;  // xx xy xz yy yz zz, 1/m^2; set by a voxel's first ray
    // Triangulation angle scratch: candidate positions and camera masks, per-camera directions.
    std::array<double, 512> cand_x, cand_y, cand_z;
    std::array<std::uint64_t, 512> cand_mask;
    std::array<float, 512> angle_deg;
    // One tile of directions per camera; left uninitialised (a vector would clear it per block).
    std::unique_ptr<double[]> directions(want_angle ? new double[3 * 64 * camera_count] : nullptr);
    // Per-candidate statistics (StatRow) for the block's vectorised passes.
    std::array<std::array<double, 512>, kStatRows> stats;
    double* stats_ptr[kStatRows];
    for (int k = 0; k < kStatRows; ++k) stats_ptr[k] = stats[k].data();
    // Information matrices of the voxels seen by two or more cameras, as six arrays (xx xy xz yy
    // yz zz), their eigenvalues as three (ascending), for one vectorised pass per block.
    std::array<std::array<double, 512>, 6> upper;
    std::array<std::array<double, 512>, 3> eigenvalue;
    std::array<unsigned char, 512> converged;
    std::array<std::int16_t, 512> candidate;
    const double* upper_ptr[6];
    for (int k = 0; k < 6; ++k) upper_ptr[k] = upper[k].data();
    double* eigen_ptr[3] = {eigenvalue[0].data(), eigenvalue[1].data(), eigenvalue[2].data()};
    for (std::size_t bi = range.begin(); bi != range.end(); ++bi) {
      const Block& block = blocks[bi];
      BlockResult& res = results[bi];
      res.per_camera.assign(camera_count, 0);
      res.tests = block.free_voxels * enabled;
      const openvdb::Coord origin(block.origin.x(), block.origin.y(), block.origin.z());

      std::array<std::int32_t, 512> coverage{};
      std::array<std::uint64_t, 512> seen_by{};
      std::array<float, 512> density{};
      if (block.cameras != 0) {
        // Per camera: the geometric tests first, then the surviving segments traced together as
        // coherent packets (one origin, neighbouring directions).
        for (int c = 0; c < camera_count; ++c) {
          if (!(block.cameras >> c & 1)) continue;
          std::size_t n = 0;
          for (int x = 0; x < block.extent.x(); ++x)
            for (int y = 0; y < block.extent.y(); ++y)
              for (int z = 0; z < block.extent.z(); ++z) {
                if (!block.IsFree(x, y, z)) continue;
                const Vec3 p = out.lattice.Center(block.origin.x() + x, block.origin.y() + y,
                                                  block.origin.z() + z);
                // The Jacobian stays in the camera frame here: rotating it to the world frame is
                // left to the segments that turn out unoccluded.
                if (tester.TestGeometryCameraFrame(c, p, nullptr, &segments[n],
                                                   want_jacobian ? &segment_jacobian[n] : nullptr) !=
                    ViewResult::kSeen)
                  continue;
                where[n] = static_cast<std::int16_t>(Block::Offset(x, y, z));
                ++n;
              }
          caster.OccludedPacket(segments.data(), n, occluded.data());
          double Rw[9];  // R_camera_from_world / sigma_c
          WhitenedRotation(tester.camera_rotation(c), pixel_sigma[c], Rw);
          res.ray_count += static_cast<std::int64_t>(n);
          if (options.record_rays) res.rays.insert(res.rays.end(), segments.begin(), segments.begin() + n);
          for (std::size_t i = 0; i < n; ++i) {
            if (occluded[i]) continue;
            const int o = where[i];
            ++coverage[o];
            seen_by[o] |= std::uint64_t{1} << c;
            ++res.per_camera[c];
            const Mat23& Jc = segment_jacobian[i];  // d pixel / d camera-frame point
            // Pixel density is rotation invariant: the camera-frame Jacobian gives it directly.
            if (want_resolution)
              density[o] = std::max(density[o], static_cast<float>(PixelDensity(Jc)));
            if (want_information) {
              // The voxel's first ray sets its entry, so the 24 KB array is never cleared.
              std::array<double, 6>& I = information[o];
              if (coverage[o] == 1) I.fill(0.0);
              AddCameraInformation(Jc, Rw, I.data());
            }
          }
        }
      }

      // Statistics and leaves.
      const bool any_seen = block.cameras != 0;
      if (want_coverage && !any_seen && block.full) res.coverage_tile = true;
      if (want_coverage && !res.coverage_tile)
        res.coverage = new openvdb::Int32Tree::LeafNodeType(origin, 0, false);
      if (any_seen && want_cameras)
        res.cameras = new openvdb::Int64Tree::LeafNodeType(origin, 0, false);
      if (any_seen)
        for (int f = 0; f < kFloatFieldCount; ++f)
          if (want_float[f]) res.floats[f] = new FloatLeaf(origin, 0.0f, false);
      // Float values straight into the leaf buffers (setValueOn re-checks out-of-core loading on
      // every call).
      std::array<float*, kFloatFieldCount> float_data{};
      for (int f = 0; f < kFloatFieldCount; ++f)
        if (res.floats[f]) float_data[f] = res.floats[f]->buffer().data();
      const auto put = [&](int field, int offset, float value) {
        float_data[field][offset] = value;
        res.floats[field]->getValueMask().setOn(offset);
      };
      int candidate_count = 0;
      for (int x = 0; x < block.extent.x(); ++x)
        for (int y = 0; y < block.extent.y(); ++y)
          for (int z = 0; z < block.extent.z(); ++z) {
            if (!block.IsFree(x, y, z)) continue;
            const int o = Block::Offset(x, y, z);
            ++res.histogram[coverage[o]];
            if (res.coverage) res.coverage->setValueOn(o, coverage[o]);
            if (coverage[o] == 0) continue;
            ++res.seen;
            if (res.cameras) res.cameras->setValueOn(o, static_cast<std::int64_t>(seen_by[o]));
            if (res.floats[kResolution]) res.floats[kResolution]->setValueOn(o, density[o]);
            if (coverage[o] < 2) continue;  // not triangulable: no uncertainty work at all
            if (!want_information) continue;
            // Gathered for the block's batched eigenvalue pass.
            for (int k = 0; k < 6; ++k) upper[k][candidate_count] = information[o][k];
            if (want_angle) {
              const Vec3 p = out.lattice.Center(block.origin.x() + x, block.origin.y() + y,
                                                block.origin.z() + z);
              cand_x[candidate_count] = p.x();
              cand_y[candidate_count] = p.y();
              cand_z[candidate_count] = p.z();
              cand_mask[candidate_count] = seen_by[o];
            }
            candidate[candidate_count++] = static_cast<std::int16_t>(o);
          }
      if (candidate_count > 0) {
        res.sigma_max.reserve(candidate_count);
        if (want_steady) res.sigma_max_steady.reserve(candidate_count);
        SymmetricEigenvalues3(upper_ptr, eigen_ptr, converged.data(), candidate_count);
        if (want_angle)
          TriangulationAngles(candidate_count, cand_x.data(), cand_y.data(), cand_z.data(),
                              cand_mask.data(), centres, block.cameras, directions.get(),
                              angle_deg.data());
      }
      // Static statistics and measurement variances for all candidates in one vectorised pass,
      // the steady state in another; then the leaves (unobservable voxels are skipped there).
      if (candidate_count > 0)
        StaticStatistics(candidate_count, eigen_ptr, stats_ptr);
      if (want_steady && candidate_count > 0) {
        for (int k = 0; k < 3; ++k)
          SteadyPositionVariances(motion.q, frame_period, stats[kVar0 + k].data(),
                                  stats[kVar0 + k].data(), candidate_count, study.steady_prior);
        SteadyStatistics(candidate_count, stats_ptr);
      }
      for (int m = 0; m < candidate_count; ++m) {
        const int o = candidate[m];
        if (stats[kObservable][m] == 0.0) {
          ++res.unobservable;
          continue;
        }
        ++res.triangulable;
        if (want_angle) put(kAngle, o, angle_deg[m]);
        const float sigma_max_mm = static_cast<float>(stats[kSigmaMaxMm][m]);
        res.sigma_max.push_back(sigma_max_mm);
        if (want_float[kSigmaMax]) put(kSigmaMax, o, sigma_max_mm);
        if (want_float[kSigmaMean]) put(kSigmaMean, o, static_cast<float>(stats[kSigmaMeanMm][m]));
        if (want_float[kCondition]) put(kCondition, o, static_cast<float>(stats[kCond][m]));
        if (want_steady) {
          const float steady_max = static_cast<float>(stats[kSteadyMaxMm][m]);
          res.sigma_max_steady.push_back(steady_max);
          if (want_float[kSigmaMaxSteady]) put(kSigmaMaxSteady, o, steady_max);
          if (want_float[kSigmaMeanSteady])
            put(kSigmaMeanSteady, o, static_cast<float>(stats[kSteadyMeanMm][m]));
        }
      }
      if (res.cameras && res.cameras->isEmpty()) {
        delete res.cameras;
        res.cameras = nullptr;
      }
      for (FloatLeaf*& leaf : res.floats)
        if (leaf && leaf->isEmpty()) {
          delete leaf;
          leaf = nullptr;
        }
      const std::size_t n = done.fetch_add(1) + 1;
      if (options.progress && (n % report_every == 0 || n == blocks.size()))
        options.progress(double(n) / double(blocks.size()));
    }
  });

  // Assemble the grids serially (adding leaves is cheap; building them was the work).
  Fields::Impl& g = out.impl();
  g.transform = openvdb::math::Transform::createLinearTransform(study.voxel_size);
  g.transform->postTranslate(openvdb::Vec3d(out.lattice.origin.x(), out.lattice.origin.y(),
                                            out.lattice.origin.z()));
  if (want_coverage) {
    g.coverage = openvdb::Int32Grid::create(0);
    g.coverage->setName(kCoverageGrid);
    g.coverage->setTransform(g.transform);
  }
  if (want_cameras) {
    g.cameras = openvdb::Int64Grid::create(0);
    g.cameras->setName(kCamerasGrid);
    g.cameras->setTransform(g.transform);
  }
  for (int f = 0; f < kFloatFieldCount; ++f) {
    if (!want_float[f]) continue;
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(kFloatFieldNames[f]);
    grid->setTransform(g.transform);
    g.floats[kFloatFieldNames[f]] = grid;
  }
  FieldStats& st = out.stats;
  st.coverage_histogram.assign(camera_count + 1, 0);
  st.per_camera_seen.assign(camera_count, 0);
  std::size_t total_rays = 0;
  for (const BlockResult& r : results) total_rays += r.rays.size();
  if (options.record_rays) out.recorded_rays.reserve(total_rays);
  for (std::size_t bi = 0; bi < results.size(); ++bi) {
    BlockResult& r = results[bi];
    const openvdb::Coord origin(blocks[bi].origin.x(), blocks[bi].origin.y(), blocks[bi].origin.z());
    if (r.coverage_tile) g.coverage->tree().addTile(1, origin, 0, true);
    if (r.coverage) g.coverage->tree().addLeaf(r.coverage);
    if (r.cameras) g.cameras->tree().addLeaf(r.cameras);
    for (int f = 0; f < kFloatFieldCount; ++f)
      if (r.floats[f]) g.floats[kFloatFieldNames[f]]->tree().addLeaf(r.floats[f]);
    st.triangulable_voxels += r.triangulable;
    st.unobservable_voxels += r.unobservable;
    st.sigma_max_mm.insert(st.sigma_max_mm.end(), r.sigma_max.begin(), r.sigma_max.end());
    st.sigma_max_steady_mm.insert(st.sigma_max_steady_mm.end(), r.sigma_max_steady.begin(),
                                  r.sigma_max_steady.end());
    for (int k = 0; k <= camera_count; ++k) st.coverage_histogram[k] += r.histogram[k];
    for (int c = 0; c < camera_count; ++c) st.per_camera_seen[c] += r.per_camera[c];
    st.point_camera_tests += r.tests;
    st.rays += r.ray_count;
    st.seen_voxels += r.seen;
    if (options.record_rays)
      out.recorded_rays.insert(out.recorded_rays.end(), r.rays.begin(), r.rays.end());
  }
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  st.cpu_seconds = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  return out;
}

}  // namespace pandora
