#include "volume/active_set.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "analysis/util/error.h"
#include "analysis/util/units.h"

namespace pandora {

VoxelLattice MakeLattice(const Aabb& region, double voxel_size, const std::string& scene_path,
                         const std::string& json_path) {
  VoxelLattice lattice;
  lattice.voxel_size = voxel_size;
  lattice.origin = region.min + Vec3::Constant(0.5 * voxel_size);
  const Vec3 extent = region.size();
  double total = 1;
  for (int a = 0; a < 3; ++a) {
    // Voxel centres sit at min + (i + 1/2) h and must lie inside the region: a region thinner than
    // half a voxel would hold none, and the study would end with nothing evaluated.
    if (!(extent[a] >= 0.5 * voxel_size)) {
      char reason[200], hint[120];
      std::snprintf(reason, sizeof reason,
                    "the region is %.4g m along %c, less than half a voxel (voxel size %.4g m): no "
                    "voxel centre lies inside it",
                    extent[a], "xyz"[a], voxel_size);
      std::snprintf(hint, sizeof hint, "use a voxel size of at most %.4g m, or a larger region",
                    2 * extent[a]);
      throw InputError(scene_path, json_path, reason, hint);
    }
    const double n = std::max(1.0, std::ceil(extent[a] / voxel_size - 1e-9));
    if (!(n <= double(1 << 30)))
      throw InputError(scene_path, json_path,
                       "the region needs more than 2^30 voxels along one axis",
                       "use a larger voxel_size or a smaller region");
    lattice.dims[a] = static_cast<int>(n);
    total *= n;
  }
  // Far beyond any memory budget, and beyond what 64-bit voxel and block counts may hold safely.
  if (!(total <= std::ldexp(1.0, 50))) {
    char count[32];
    std::snprintf(count, sizeof count, "%.3g", total);
    throw InputError(scene_path, json_path,
                     std::string("the region needs about ") + count + " voxels (more than 2^50)",
                     "use a larger voxel_size or a smaller region");
  }
  return lattice;
}

FrustumCuller::FrustumCuller(const std::vector<Camera>& cameras) {
  cams_.resize(cameras.size());
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    const Camera& cam = cameras[c];
    Planes& p = cams_[c];
    p.enabled = cam.enabled;
    p.camera_from_world = cam.camera_from_world();
    p.axis = cam.world_from_camera.linear().col(2).normalized();
    p.center = cam.center();
    p.near = cam.near;
    p.far = cam.far;
    p.max_angle = cam.model.max_field_angle();
    p.use_planes = p.max_angle < 0.5 * kPi - 1e-9;
    if (p.use_planes) {
      const Eigen::Vector4d& b = cam.model.normalized_bounds();  // x_min, x_max, y_min, y_max
      p.normals[0] = Vec3(1, 0, -b[0]);
      p.normals[1] = Vec3(-1, 0, b[1]);
      p.normals[2] = Vec3(0, 1, -b[2]);
      p.normals[3] = Vec3(0, -1, b[3]);
    }
  }
}

bool FrustumCuller::MayIntersect(int camera, const Aabb& box) const {
  const Planes& p = cams_[camera];
  if (!p.enabled) return false;
  // Working range: nearest and farthest points of the box from the centre.
  const Vec3 nearest = p.center.cwiseMax(box.min).cwiseMin(box.max);
  const double d_min = (nearest - p.center).norm();
  if (d_min > p.far) return false;
  const Vec3 far_corner((p.center.x() < box.center().x()) ? box.max.x() : box.min.x(),
                        (p.center.y() < box.center().y()) ? box.max.y() : box.min.y(),
                        (p.center.z() < box.center().z()) ? box.max.z() : box.min.z());
  if ((far_corner - p.center).norm() < p.near) return false;
  // Bounding cone around the optical axis, against the box's bounding sphere.
  const Vec3 m = box.center() - p.center;
  const double dist = m.norm();
  const double radius = 0.5 * box.diagonal();
  if (dist > radius) {
    const double angle = std::acos(std::clamp(m.dot(p.axis) / dist, -1.0, 1.0));
    if (angle - std::asin(radius / dist) > p.max_angle) return false;
  }
  if (!p.use_planes) return true;
  // The pyramid through the centre that bounds the image: outside when all corners are outside one
  // plane.
  std::array<Vec3, 8> corners;
  for (int i = 0; i < 8; ++i) {
    const Vec3 w((i & 1) ? box.max.x() : box.min.x(), (i & 2) ? box.max.y() : box.min.y(),
                 (i & 4) ? box.max.z() : box.min.z());
    corners[i] = p.camera_from_world * w;
  }
  for (const Vec3& n : p.normals) {
    bool all_outside = true;
    for (const Vec3& q : corners)
      if (n.dot(q) >= 0.0) {
        all_outside = false;
        break;
      }
    if (all_outside) return false;
  }
  return true;
}

Aabb BlockCentreBox(const VoxelLattice& lattice, const Block& block) {
  const Eigen::Vector3i last = block.origin + block.extent - Eigen::Vector3i::Ones();
  Aabb box;
  box.Extend(lattice.Center(block.origin.x(), block.origin.y(), block.origin.z()));
  box.Extend(lattice.Center(last.x(), last.y(), last.z()));
  box.min -= Vec3::Constant(1e-9 * lattice.voxel_size);
  box.max += Vec3::Constant(1e-9 * lattice.voxel_size);
  return box;
}

std::vector<Block> BuildActiveSet(const VoxelLattice& lattice, const Region& region,
                                  const std::vector<const InsideMesh*>& solids,
                                  const InsideMesh* region_mesh, const FrustumCuller& culler,
                                  int camera_count, ActiveSetStats* stats,
                                  const BlockColumns* tile) {
  const Eigen::Vector3i nb = (lattice.dims + Eigen::Vector3i::Constant(7)) / 8;
  // The columns to build: all, or the tile's (clipped to the lattice).
  BlockColumns cols{0, nb.x(), 0, nb.y()};
  if (tile) {
    cols.x0 = std::clamp(tile->x0, 0, nb.x());
    cols.x1 = std::clamp(tile->x1, cols.x0, nb.x());
    cols.y0 = std::clamp(tile->y0, 0, nb.y());
    cols.y1 = std::clamp(tile->y1, cols.y0, nb.y());
  }
  const int cols_y = cols.y1 - cols.y0;
  const std::int64_t block_columns = std::int64_t(cols.x1 - cols.x0) * cols_y;
  const std::int64_t block_count = block_columns * nb.z();
  std::vector<Block> all(static_cast<std::size_t>(block_count));
  std::vector<std::uint8_t> keep(all.size(), 0);
  const double h = lattice.voxel_size;

  // By columns of blocks (bx, by), bottom to top: a mesh's crossings along a voxel column are
  // searched once for the whole column of blocks (InsideMesh::ColumnAt) and reused by each block
  // that needs them.
  Aabb region_box = region.box;  // padded by round-off
  region_box.min -= Vec3::Constant(1e-9 * h);
  region_box.max += Vec3::Constant(1e-9 * h);
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, block_columns, 1), [&](const auto& range) {
    for (std::int64_t bc = range.begin(); bc != range.end(); ++bc) {
      // Per mesh (the solids, then the region's mesh), per voxel column (x, y) of this block
      // column.
      std::vector<std::vector<std::optional<InsideMesh::Column>>> columns(solids.size() + 1);
      const auto column = [&](std::size_t mesh, int x, int y) -> const InsideMesh::Column& {
        std::vector<std::optional<InsideMesh::Column>>& c = columns[mesh];
        if (c.empty()) c.resize(64);
        std::optional<InsideMesh::Column>& slot = c[8 * (x & 7) + (y & 7)];
        if (!slot) {
          const Vec3 foot = lattice.Center(x, y, 0);
          slot = (mesh < solids.size() ? solids[mesh] : region_mesh)->ColumnAt(foot.x(), foot.y());
        }
        return *slot;
      };
      const int bx = cols.x0 + static_cast<int>(bc / cols_y);
      const int by = cols.y0 + static_cast<int>(bc % cols_y);
      for (int bz = 0; bz < nb.z(); ++bz) {
        const std::int64_t b = bc * nb.z() + bz;
        Block& block = all[b];
        block.origin = Eigen::Vector3i(8 * bx, 8 * by, 8 * bz);
        const Eigen::Vector3i last = (block.origin + Eigen::Vector3i::Constant(7))
                                         .cwiseMin(lattice.dims - Eigen::Vector3i::Ones());
        // Box of the voxel centres of this block (only centres are evaluated).
        Aabb box;
        box.Extend(lattice.Center(block.origin.x(), block.origin.y(), block.origin.z()));
        box.Extend(lattice.Center(last.x(), last.y(), last.z()));

        // Region. A box region's last voxel centres can lie up to half a voxel beyond its max (the
        // lattice rounds the extent up): such blocks test each centre against the box.
        InsideMesh::BoxClass region_class = InsideMesh::BoxClass::kInside;
        if (region.kind == Region::Kind::kMesh) {
          region_class = region_mesh->Classify(box);
        } else if (!region_box.Contains(box.max)) {
          region_class = InsideMesh::BoxClass::kCrossing;
        }
        if (region_class == InsideMesh::BoxClass::kOutside) continue;
        // Solids.
        bool all_solid = false;
        std::vector<std::size_t> crossing;
        for (std::size_t s = 0; s < solids.size(); ++s) {
          const InsideMesh::BoxClass c = solids[s]->Classify(box);
          if (c == InsideMesh::BoxClass::kInside) {
            all_solid = true;
            break;
          }
          if (c == InsideMesh::BoxClass::kCrossing) crossing.push_back(s);
        }

        block.extent = last - block.origin + Eigen::Vector3i::Ones();
        const std::int64_t n_vox =
            std::int64_t(block.extent.x()) * block.extent.y() * block.extent.z();
        if (region_class == InsideMesh::BoxClass::kInside && crossing.empty()) {
          // Fast path: the whole block is one thing, no per-voxel test.
          (all_solid ? block.solid_voxels : block.free_voxels) = n_vox;
        } else {
          block.mask.assign(512, 0);
          // Column by column along z: one search of each crossing mesh per column (its crossings'
          // parity, InsideMesh::InsideOnColumn) rather than one per voxel.
          const int nz = last.z() - block.origin.z() + 1;
          std::array<double, 8> zs;
          std::array<unsigned char, 8> in_region, in_solid, in_this;
          for (int x = block.origin.x(); x <= last.x(); ++x)
            for (int y = block.origin.y(); y <= last.y(); ++y) {
              for (int k = 0; k < nz; ++k) zs[k] = lattice.Center(x, y, block.origin.z() + k).z();
              in_region.fill(1);
              if (region_class == InsideMesh::BoxClass::kCrossing) {
                if (region.kind == Region::Kind::kMesh) {
                  region_mesh->InsideOnColumn(column(solids.size(), x, y), zs.data(), nz,
                                              in_region.data());
                } else {
                  for (int k = 0; k < nz; ++k)
                    in_region[k] = region_box.Contains(lattice.Center(x, y, block.origin.z() + k));
                }
              }
              in_solid.fill(all_solid ? 1 : 0);
              for (std::size_t s = 0; !all_solid && s < crossing.size(); ++s) {
                solids[crossing[s]]->InsideOnColumn(column(crossing[s], x, y), zs.data(), nz,
                                                    in_this.data());
                for (int k = 0; k < nz; ++k) in_solid[k] |= in_this[k];
              }
              for (int k = 0; k < nz; ++k) {
                if (!in_region[k]) continue;
                if (in_solid[k]) {
                  ++block.solid_voxels;
                } else {
                  block.mask[Block::Offset(x - block.origin.x(), y - block.origin.y(), k)] = 1;
                  ++block.free_voxels;
                }
              }
            }
          if (block.free_voxels == n_vox) std::vector<std::uint8_t>().swap(block.mask);
        }
        if (block.free_voxels == 0 && block.solid_voxels == 0) continue;
        keep[b] = 1;
        block.full = block.mask.empty() && n_vox == 512;
        if (block.free_voxels == 0) continue;
        // Cameras: the box padded by round-off only.
        const Aabb padded = BlockCentreBox(lattice, block);
        for (int c = 0; c < camera_count; ++c)
          if (culler.MayIntersect(c, padded)) block.cameras.push_back(c);
      }
    }
  });

  std::vector<Block> blocks;
  ActiveSetStats s;
  for (std::size_t b = 0; b < all.size(); ++b) {
    if (!keep[b]) continue;
    s.region_voxels += all[b].free_voxels;
    s.solid_voxels += all[b].solid_voxels;
    if (all[b].free_voxels == 0) continue;
    ++s.blocks;
    if (all[b].cameras.empty()) ++s.culled_blocks;
    blocks.push_back(std::move(all[b]));
  }
  if (stats) *stats = s;
  return blocks;
}

std::vector<std::uint8_t> PartitionBlocks(const std::vector<Block>& blocks,
                                          const std::vector<std::vector<std::int32_t>>& candidates,
                                          int count, int rank) {
  if (count < 1 || rank < 0 || rank >= count)
    throw std::logic_error("PartitionBlocks: bad partition");
  // Cost of a block: its (voxel, candidate camera) pairs plus a constant for the block's own work
  // (deriving, leaves), so culled blocks are spread too.
  std::vector<std::pair<std::int64_t, std::size_t>> cost(blocks.size());
  for (std::size_t b = 0; b < blocks.size(); ++b)
    cost[b] = {std::int64_t(blocks[b].free_voxels) * std::int64_t(candidates[b].size() + 1) + 64,
               b};
  std::sort(cost.begin(), cost.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });
  // Largest first, each to the least loaded partition (ties: the lowest index): deterministic.
  std::vector<std::int64_t> load(count, 0);
  std::vector<std::uint8_t> mine(blocks.size(), 0);
  for (const auto& [c, b] : cost) {
    const int to = int(std::min_element(load.begin(), load.end()) - load.begin());
    load[to] += c;
    if (to == rank) mine[b] = 1;
  }
  return mine;
}

}  // namespace pandora
