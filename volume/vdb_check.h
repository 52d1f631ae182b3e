#pragma once
/// \file vdb_check.h
/// Validation of a .vdb file's bytes before OpenVDB parses them, and the provenance check of a
/// fields file against the scene it is rendered with. No OpenVDB in this header or its .cpp: the
/// validator reads the bytes itself, following OpenVDB 10's file format (io/Archive.cc,
/// io/Compression.h, tree/RootNode.h, InternalNode.h, LeafNode.h, LeafNodeBool.h).

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/scene/scene.h"
#include "volume/active_set.h"

namespace pandora {

/// Bounds the validator enforces. A file beyond them is refused before anything is allocated for
/// it, so a damaged or hostile file can neither exhaust memory nor make the reader loop for long.
struct VdbLimits {
  std::uint64_t max_file_bytes = std::uint64_t(1) << 32;  ///< 4 GiB.
  int max_grids =
      SceneLimits::kMaxCameras + 16;  ///< 9 fields + a rig's cameras, with room to spare.
  std::int64_t max_index = 1 << 20;   ///< Every node lies in [0, max_index)^3 (index space).
  /// Product of any two extents of a grid's active index box [0, max]: bounds a slice image.
  std::int64_t max_face_voxels = std::int64_t(1) << 28;
  /// Active voxels of a grid, tiles counted voxel by voxel: bounds anything that densifies.
  std::int64_t max_active_voxels = std::int64_t(1) << 31;
};

/// What the validator learned about one grid.
struct VdbGridInfo {
  std::string name;               ///< The descriptor's (and the "name" metadata's) grid name.
  std::string tree_type;          ///< "Tree_float_5_4_3", "Tree_bool_5_4_3", ...
  std::uint32_t compression = 0;  ///< OpenVDB's COMPRESS_* flags of this grid.
  std::map<std::string, std::string> strings;    ///< String metadata of the grid.
  std::map<std::string, std::int64_t> integers;  ///< int32 / int64 metadata of the grid.
  double voxel_size = 0;                         ///< Metres (the uniform scale of the transform).
  std::array<double, 3> translation{};           ///< World position of index (0, 0, 0), metres.
  bool empty = true;                             ///< No active value at all.
  std::array<std::int64_t, 3> active_min{}, active_max{};  ///< Active index box (inclusive).
  std::int64_t active_voxels = 0;                          ///< Tiles counted voxel by voxel.
  std::int64_t active_tiles = 0;                           ///< Active tiles at any level.
  std::int64_t leaf_count = 0;
};

/// What the validator learned about the file.
struct VdbFileInfo {
  std::map<std::string, std::string> strings;  ///< The file's string metadata.
  std::vector<VdbGridInfo> grids;              ///< In file order.
};

/// Checks that `bytes` hold a VDB file that OpenVDB 10 can parse with bounded work and memory:
/// the header (magic, file format version 224, grid offsets present, UUID), the file's and every
/// grid's metadata (known types of their exact sizes, lengths within the file, the delayed-load
/// record's Blosc chunks), the grid descriptors (offsets consistent with the bytes, one of the
/// tree types Pandora reads: float, bool, int32, int64 with the standard 5-4-3 layout, no
/// half floats, no instancing), the transform (a uniform positive finite scale and a finite
/// translation), and the tree: node origins aligned, sorted and inside `limits`, masks
/// consistent, every compressed chunk's declared sizes consistent with what it decompresses to
/// (Blosc headers and block tables; zip and raw sizes) and within the remaining bytes, and the
/// active index box and voxel count within `limits`. Nothing may follow the last grid.
/// Throws InputError (file = `path`, no JSON path) saying what is wrong and at which byte.
VdbFileInfo CheckVdbBytes(std::string_view bytes, const std::string& path,
                          const VdbLimits& limits = {});

/// Reads the whole file at `path` for CheckVdbBytes. Refuses, with InputError (file = `path`), a
/// path that cannot be opened, anything that is not a regular file (folder, FIFO, device,
/// socket), an empty file, a file over `limits.max_file_bytes`, and a file that changes size
/// while it is read. Never blocks on a FIFO.
std::string ReadVdbFileBytes(const std::string& path, const VdbLimits& limits = {});

/// Where a fields file came from: its metadata as `pandora analyze` writes it. Empty strings for
/// keys the file lacks.
struct FieldsProvenance {
  std::string scene_file;    ///< The scene path given to analyze.
  std::string scene_sha256;  ///< Hex SHA-256 of that scene file's bytes.
  std::string rig_name;
  std::string rig_json;  ///< RigToJson() of the rig, serialized.
  std::string tool;      ///< "pandora".
  std::string tool_version;
  std::map<std::string, std::string> metadata;  ///< Every string metadata entry of the file.
};

/// Throws InputError (file = `path`) when the fields carry a run id and the summary.json written
/// beside them (in the same folder; one folder up from a streamed tile) carries another: the two
/// outputs come from different runs, and one is stale. Nothing happens without either run id.
void CheckSameRunAsSummary(const FieldsProvenance& provenance, const std::string& path);

/// Compares a fields file read from `path` with the scene and rig it is about to be used with.
/// Refuses fields of another run than the summary beside them (CheckSameRunAsSummary).
/// Returns one-line warnings (without a "warning:" prefix): the scene file's SHA-256 differs, the
/// rig's cameras differ from those the fields were computed for (naming the cameras), or the file
/// carries no provenance at all. Throws InputError (file = `path`) when the file's rig name differs
/// from `rig` (the hint names `--rig`), or when the lattice of `fields` (index box [0, dims) at
/// `origin`, `voxel_size`) does not lie within the scene's study region, give or take one voxel.
std::vector<std::string> CheckFieldsProvenance(const FieldsProvenance& provenance,
                                               const VoxelLattice& lattice, const Scene& scene,
                                               const Rig& rig, const std::string& path);

/// The grid name that holds which voxels camera `id` sees: "visible/" followed by the id with every
/// byte outside [A-Za-z0-9_.-] written as %XX (upper-case hex), so any id gives a distinct,
/// printable, ASCII name ("visible/cam%201" for "cam 1").
std::string VisibilityGridName(const std::string& camera_id);

}  // namespace pandora
