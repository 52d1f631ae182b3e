#pragma once
/// \file ray_caster.h
/// Ray casting against the scene's triangles behind a small interface: Embree (fast, single
/// precision, used everywhere) and a brute-force double-precision implementation (tests,
/// references).

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "analysis/geometry/geometry.h"

namespace pandora {

/// A ray segment: points origin + t * direction for t in (t_near, t_far). `direction` is unit
/// length, so t is in metres.
struct Ray {
  Vec3 origin;
  Vec3 direction;
  double t_near = 0;
  double t_far = 0;
};

/// The first hit along a ray.
struct RayHit {
  double t = 0;       ///< Metres along the ray.
  int triangle = -1;  ///< Index into the mesh the caster was built from.
  Vec3 normal;        ///< Geometric unit normal of the hit triangle (counter-clockwise front).
};

/// Answers occlusion and first-hit queries against a fixed triangle mesh. Implementations are
/// immutable after construction and safe for concurrent const use from many threads.
class RayCaster {
 public:
  virtual ~RayCaster() = default;

  /// True when the segment hits any triangle (either side).
  virtual bool Occluded(const Ray& ray) const = 0;
  /// The nearest hit in (t_near, t_far), or nullopt.
  virtual std::optional<RayHit> Intersect(const Ray& ray) const = 0;
  /// Occluded() for every ray, in parallel (TBB); `occluded` is resized to rays.size().
  virtual void OccludedBatch(const std::vector<Ray>& rays, std::vector<uint8_t>* occluded) const;
  /// Occluded() for `count` rays on the calling thread; occluded[i] is 1 or 0. Rays that are close
  /// to each other in the array should be coherent (for example, from one camera to neighbouring
  /// voxels): Embree traces them as SIMD packets (16, 8 or 4 wide, whichever the CPU runs
  /// natively).
  virtual void OccludedPacket(const Ray* rays, std::size_t count, uint8_t* occluded) const;

  /// Rays from one origin (a camera's centre), the rest of each ray in arrays: what OccludedFan
  /// traces.
  struct Fan {
    Vec3 origin = Vec3::Zero();
    const double* dx = nullptr;  ///< unit directions
    const double* dy = nullptr;
    const double* dz = nullptr;
    const double* t_near = nullptr;
    const double* t_far = nullptr;
    /// When given, ray k is element index[k] of the arrays (else element k).
    const std::int16_t* index = nullptr;
    std::size_t at(std::size_t k) const { return index ? std::size_t(index[k]) : k; }
  };
  /// OccludedPacket() for `count` rays of one fan: the same answers as OccludedPacket on the same
  /// rays, without building Ray structs (Embree fills its packets straight from the arrays).
  virtual void OccludedFan(const Fan& fan, std::size_t count, uint8_t* occluded) const;

  /// Intersect() for `count` rays on the calling thread into hits[0..count). Neighbouring rays in
  /// the array should be coherent (for example, a row of pixels): Embree traces them as SIMD
  /// packets.
  virtual void IntersectPacket(const Ray* rays, std::size_t count,
                               std::optional<RayHit>* hits) const;

  /// "embree" or "brute-force".
  virtual const char* name() const = 0;
  /// Bounds of the mesh the caster was built from (world frame). Embree works in single precision
  /// in a frame centred on these bounds; VisibilityTester sizes its tolerance from them.
  virtual const Aabb& bounds() const = 0;
  /// Number of triangles.
  virtual std::size_t triangle_count() const = 0;
};

/// Embree 3 BVH over `mesh` (single precision, robust mode, high build quality). The mesh is
/// recentred on its bounding-box centre before conversion to float, so precision is relative to the
/// scene's size rather than its distance from the world origin. Throws std::runtime_error when
/// Embree fails.
std::unique_ptr<RayCaster> MakeEmbreeRayCaster(const TriangleMesh& mesh);

/// Ray casters for a scene whose parts move rigidly (analysis/scene/motion.h): one BVH per part,
/// built once; At() gives the caster of one time sample by building only a top-level BVH over the
/// parts with their transforms (Embree instancing; microseconds for a few parts); deformable parts
/// (skinned meshes) get their sample's vertices and a refit of their own BVH. At() may be called
/// from several threads, and its casters outlive this object safely.
class RigidPartsRayCaster {
 public:
  virtual ~RigidPartsRayCaster() = default;
  /// The caster with part k moved by transforms[k] (world_from_rest; missing entries: identity).
  /// Hits report the triangle's index as given at construction and the moved normal.
  std::unique_ptr<RayCaster> At(const std::vector<Eigen::Isometry3d>& transforms) const {
    return At(transforms, {});
  }
  /// The same with the vertices of deformable parts replaced: vertices[k], when part k was built
  /// deformable and it has the part's vertex count, is that part's mesh (same triangles) before
  /// transforms[k]; else the part keeps its rest mesh. A deformed part's BVH is refitted to the
  /// new vertices (RTC_BUILD_QUALITY_REFIT), built only when no earlier caster's BVH of that part
  /// is free (the first sample, or casters alive at once); rigid parts keep theirs.
  virtual std::unique_ptr<RayCaster> At(const std::vector<Eigen::Isometry3d>& transforms,
                                        const std::vector<std::vector<Vec3>>& vertices) const = 0;
  virtual std::size_t part_count() const = 0;
};

/// Builds the parts' BVHs (single precision in a frame centred on all parts' rest bounds, robust
/// mode, high quality). `triangle_index[k][i]` is the index hits report for triangle i of part k
/// (e.g. its index in Scene::AllTriangles()); when a part's list is missing or of the wrong size,
/// the parts' triangles are numbered consecutively. Throws std::runtime_error when Embree fails.
/// `deformable[k]` marks part k as one whose vertices At() may replace (a skinned mesh).
std::unique_ptr<RigidPartsRayCaster> MakeEmbreeRigidParts(
    const std::vector<TriangleMesh>& parts,
    const std::vector<std::vector<int>>& triangle_index = {},
    const std::vector<bool>& deformable = {});

/// Double-precision brute force (Moller-Trumbore over every triangle). O(triangles) per ray.
std::unique_ptr<RayCaster> MakeBruteForceRayCaster(const TriangleMesh& mesh);

/// How RawEmbreeOcclusion traces the rays.
enum class RawMode {
  kSingle,  ///< rtcOccluded1, one ray at a time (the usual baseline).
  kPacket,  ///< Consecutive rays as native-width packets (rtcOccluded16/8/4), as OccludedPacket
            ///< does.
};

/// Result of RawEmbreeOcclusion.
struct RawOcclusionResult {
  double seconds = 0;
  std::size_t rays = 0;
  std::size_t occluded = 0;
};

/// The benchmark baseline: a bare loop of Embree occlusion queries over `rays` split across TBB
/// threads, with the rays converted to Embree's layout before the clock starts. `caster` must come
/// from MakeEmbreeRayCaster (throws std::invalid_argument otherwise).
RawOcclusionResult RawEmbreeOcclusion(const RayCaster& caster, const std::vector<Ray>& rays,
                                      RawMode mode = RawMode::kSingle);

/// The same baseline for first-hit queries: a bare TBB loop of rtcIntersect1 (kSingle) or of
/// native-width packets of consecutive rays (kPacket) over `rays` (converted before the clock
/// starts). In the result, `occluded` counts the rays that hit something. `caster` must come from
/// MakeEmbreeRayCaster (throws std::invalid_argument otherwise).
RawOcclusionResult RawEmbreeIntersection(const RayCaster& caster, const std::vector<Ray>& rays,
                                         RawMode mode = RawMode::kSingle);

/// The packet width OccludedPacket uses on this CPU (16, 8, 4, or 1).
int EmbreePacketWidth(const RayCaster& caster);

}  // namespace pandora
