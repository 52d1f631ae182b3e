#pragma once
/// \file active_set.h
/// The sparse active set: which voxels of the study region are evaluated, in blocks of 8^3 voxels
/// (the size of an OpenVDB leaf). Whole blocks outside every camera's frustum or working range,
/// outside the region, or inside a solid are decided before any ray is cast. No OpenVDB here: plain
/// geometry.

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/inside_mesh.h"
#include "analysis/scene/scene.h"

namespace pandora {

/// Voxel lattice over the region: voxel (i, j, k) has its centre at origin + voxel_size * (i, j,
/// k), for 0 <= i < dims.x() and so on; `origin` is region.min + voxel_size / 2.
struct VoxelLattice {
  Vec3 origin = Vec3::Zero();
  double voxel_size = 0;
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();

  Vec3 Center(int i, int j, int k) const { return origin + voxel_size * Vec3(i, j, k); }
  /// Lattice points (MakeLattice bounds it by 2^50, so this cannot overflow).
  std::int64_t voxel_count() const { return std::int64_t(dims.x()) * dims.y() * dims.z(); }
};

/// Builds the lattice for `region` at `voxel_size` (the count per axis is ceil(extent /
/// voxel_size), at least 1; centres beyond the region's max are excluded by BuildActiveSet). Throws
/// InputError (path "$.study.voxel_size") when an axis would need more than 2^30 voxels or the
/// whole lattice more than 2^50.
VoxelLattice MakeLattice(const Aabb& region, double voxel_size, const std::string& scene_path,
                         const std::string& json_path = "$.study.voxel_size");

/// Conservative frustum test of a box against a camera: its working range (distance), its bounding
/// cone (max field angle) and, for fields of view under 180 degrees, the four planes through the
/// centre bounding the (distorted) image. False only when no point of the box can be seen.
class FrustumCuller {
 public:
  explicit FrustumCuller(const std::vector<Camera>& cameras);
  bool MayIntersect(int camera, const Aabb& box) const;

 private:
  struct Planes {
    bool enabled = false;
    bool use_planes = false;
    Eigen::Isometry3d camera_from_world;
    Vec3 axis;  // world, unit
    Vec3 center;
    double near = 0, far = 0, max_angle = 0;
    std::array<Vec3, 4> normals;  // camera frame; inside when n . p >= 0
  };
  std::vector<Planes> cams_;
};

/// What is known about one 8^3 block before any ray is cast.
struct Block {
  Eigen::Vector3i origin;  ///< Index of its first voxel (multiples of 8).
  std::vector<std::int32_t>
      cameras;  ///< Cameras (rig indices, ascending) whose frustum may meet it.
  Eigen::Vector3i extent = Eigen::Vector3i::Constant(8);  ///< Voxels per axis (< 8 at the edge).
  bool full = false;  ///< All 8^3 voxels are free region voxels (no solid, not at the edge).
  /// Per voxel, at Offset(x, y, z): 1 when it is a free region voxel to evaluate. Empty when every
  /// voxel within `extent` is free.
  std::vector<std::uint8_t> mask;

  /// Offset of local voxel (x, y, z) in 0..7, matching OpenVDB's leaf layout (x-major).
  static int Offset(int x, int y, int z) { return 64 * x + 8 * y + z; }
  bool IsFree(int x, int y, int z) const { return mask.empty() || mask[Offset(x, y, z)] != 0; }
  std::int64_t free_voxels = 0;   ///< Region voxels outside solids in this block.
  std::int64_t solid_voxels = 0;  ///< Region voxels inside solids in this block.
};

/// The box of a block's voxel centres, padded by round-off (1e-9 of a voxel): what FrustumCuller
/// tests for the block.
Aabb BlockCentreBox(const VoxelLattice& lattice, const Block& block);

/// Statistics of the active-set pass.
struct ActiveSetStats {
  std::int64_t region_voxels = 0;  ///< Region voxels outside solids (the evaluated domain).
  std::int64_t solid_voxels = 0;   ///< Region voxels inside solid objects (left inactive).
  std::int64_t blocks = 0;         ///< Blocks holding at least one free region voxel.
  std::int64_t culled_blocks = 0;  ///< Of those, blocks no camera can see (no ray cast there).
};

/// A rectangle of block columns: the blocks (bx, by, any bz) with x0 <= bx < x1 and y0 <= by < y1,
/// bx, by counting 8^3 blocks along the lattice's x and y. A streamed evaluation (`pandora analyze
/// --stream`, docs/scale.md) evaluates the region tile by tile, each a rectangle of whole columns.
struct BlockColumns {
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  /// The lattice's voxels these columns hold (clipped to the lattice).
  Eigen::Vector3i VoxelMin() const { return {8 * x0, 8 * y0, 0}; }
  Eigen::Vector3i VoxelEnd(const VoxelLattice& lattice) const {
    return {std::min(8 * x1, lattice.dims.x()), std::min(8 * y1, lattice.dims.y()),
            lattice.dims.z()};
  }
};

/// Splits the lattice into blocks, classifies them against the region (box or mesh) and the solids,
/// and culls cameras per block. Runs in parallel. With `tile`, only the blocks of those columns
/// (clipped to the lattice).
std::vector<Block> BuildActiveSet(const VoxelLattice& lattice, const Region& region,
                                  const std::vector<const InsideMesh*>& solids,
                                  const InsideMesh* region_mesh, const FrustumCuller& culler,
                                  int camera_count, ActiveSetStats* stats,
                                  const BlockColumns* tile = nullptr);

/// The blocks partition `rank` of `count` evaluates (FieldOptions::partition_count): blocks sorted
/// by cost (free voxels times (candidate cameras + 1), plus 64), largest first, each given to the
/// least loaded partition so far (longest-processing-time scheduling: the largest load is within
/// 4/3 of the best possible). Every process computes the same partition. std::logic_error for a
/// bad `count` or `rank`.
std::vector<std::uint8_t> PartitionBlocks(const std::vector<Block>& blocks,
                                          const std::vector<std::vector<std::int32_t>>& candidates,
                                          int count, int rank);

}  // namespace pandora
