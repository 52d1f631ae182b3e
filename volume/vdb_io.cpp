#include "volume/vdb_io.h"

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <istream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <streambuf>

#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "volume/fields_vdb.h"
#include "volume/vdb_writer.h"

namespace pandora {

void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

namespace {

constexpr char kVisiblePrefix[] = "visible/";
constexpr int kMaxCameras = SceneLimits::kMaxCameras;  // per rig, so per fields file

// How the grids' values are stored: see docs/fields.md ("Compression") for the measured trade-off.
constexpr std::uint32_t kCompression =
    openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK;

// Transform::copy() re-derives the map from its matrix (the scale can move by a few ulps); the copy
// constructor keeps it exactly.
openvdb::math::Transform::Ptr ExactCopy(const openvdb::math::Transform& transform) {
  return std::make_shared<openvdb::math::Transform>(transform);
}

// Per-grid description: units and meaning, for people reading `vdb_print -l`.
void Describe(openvdb::GridBase& grid) {
  static const std::map<std::string, std::pair<const char*, const char*>> kDescriptions{
      {"coverage", {"cameras", "number of cameras that see the voxel centre (whole numbers)"}},
      {"resolution",
       {"px/m", "best pixel density among the cameras that see the voxel (det(J J^T)^(1/4))"}},
      {"sigma_max", {"mm", "worst-direction 1-sigma of the static triangulation covariance"}},
      {"sigma_mean", {"mm", "sqrt(trace/3) of the static triangulation covariance"}},
      {"triangulation_angle", {"deg", "largest angle between two rays that see the voxel"}},
      {"condition", {"1", "condition number of the information matrix J"}},
      {"sigma_max_steady", {"mm", "worst-direction 1-sigma of the steady-state Kalman covariance"}},
      {"sigma_mean_steady", {"mm", "sqrt(trace/3) of the steady-state Kalman covariance"}},
      {"coverage_min",
       {"cameras", "fewest cameras that see the voxel over the time samples where it is free"}},
      {"coverage_time_share",
       {"1", "share of the time samples (where the voxel is free) in which enough cameras see it"}},
  };
  auto it = kDescriptions.find(grid.getName());
  if (it == kDescriptions.end()) return;
  grid.insertMeta("value_units", openvdb::StringMetadata(it->second.first));
  grid.insertMeta("description", openvdb::StringMetadata(it->second.second));
}

// Camera ids in rig order from the "rig" metadata (RigToJson); empty when absent or unusable.
std::vector<std::string> CameraIds(const std::map<std::string, std::string>& metadata) {
  auto it = metadata.find("rig");
  if (it == metadata.end()) return {};
  const nlohmann::json rig = nlohmann::json::parse(it->second, nullptr, false);
  if (rig.is_discarded() || !rig.is_object() || !rig.contains("cameras") ||
      !rig["cameras"].is_array())
    return {};
  std::vector<std::string> ids;
  std::set<std::string> unique;
  for (const auto& camera : rig["cameras"]) {
    if (!camera.is_object() || !camera.contains("id") || !camera["id"].is_string()) return {};
    ids.push_back(camera["id"].get<std::string>());
    if (!unique.insert(ids.back()).second) return {};
  }
  return ids;
}

// The per-camera grids as written: named by the camera ids (or by index when the ids do not match
// the grids), with their index and units. They share the trees of the evaluated grids.
openvdb::GridPtrVec CameraGrids(const std::vector<openvdb::BoolGrid::Ptr>& visible,
                                std::vector<std::string> ids) {
  if (ids.size() != visible.size()) {
    ids.clear();
    for (std::size_t c = 0; c < visible.size(); ++c) ids.push_back(std::to_string(c));
  }
  openvdb::GridPtrVec grids;
  for (std::size_t c = 0; c < visible.size(); ++c) {
    auto grid = openvdb::BoolGrid::create(visible[c]->treePtr());
    grid->setName(VisibilityGridName(ids[c]));
    grid->setTransform(ExactCopy(visible[c]->transform()));
    grid->insertMeta("camera_id", openvdb::StringMetadata(ids[c]));
    grid->insertMeta("camera_index", openvdb::Int64Metadata(std::int64_t(c)));
    grid->insertMeta("value_units", openvdb::StringMetadata("bool"));
    grid->insertMeta("description", openvdb::StringMetadata(
                                        "active and true where camera '" + ids[c] +
                                        "' (index camera_index in the rig) sees the voxel centre"));
    grids.push_back(grid);
  }
  return grids;
}

// A read-only stream buffer over bytes in memory, seekable, for openvdb::io::Stream.
class MemoryBuffer : public std::streambuf {
 public:
  MemoryBuffer(const char* data, std::size_t size) {
    char* p = const_cast<char*>(data);
    setg(p, p, p + size);
  }

 protected:
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override {
    off_type base = dir == std::ios_base::beg   ? 0
                    : dir == std::ios_base::cur ? gptr() - eback()
                                                : egptr() - eback();
    const off_type target = base + off;
    if (target < 0 || target > egptr() - eback()) return pos_type(off_type(-1));
    setg(eback(), eback() + target, egptr());
    return pos_type(target);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }
};

[[noreturn]] void Refuse(const std::string& path, const std::string& reason) {
  throw InputError(path, "", reason, "pass the fields.vdb that `pandora analyze` wrote");
}

std::string CoordText(const openvdb::Coord& c) {
  return "(" + std::to_string(c.x()) + ", " + std::to_string(c.y()) + ", " + std::to_string(c.z()) +
         ")";
}

// Every value of a coverage grid (active or not, tiles included) a whole number of cameras in
// [0, 64].
template <typename GridT>
void CheckCameraCounts(const GridT& grid, const std::string& path) {
  auto ok = [](auto v) { return v >= 0 && v <= kMaxCameras && v == std::floor(v); };
  if (!ok(grid.background()))
    Refuse(path, "grid 'coverage' has a background that is not a camera count");
  for (auto it = grid.cbeginValueAll(); it; ++it)
    if (!ok(*it))
      Refuse(path, "grid 'coverage' holds " + std::to_string(*it) + " at voxel " +
                       CoordText(it.getCoord()) + ", not a whole number of cameras in [0, " +
                       std::to_string(kMaxCameras) + "]");
}

// Coverage stored as floats back to the in-memory Int32Grid.
openvdb::Int32Grid::Ptr CoverageFromFloat(const openvdb::FloatGrid& grid, const std::string& path) {
  CheckCameraCounts(grid, path);
  auto tree = std::make_shared<openvdb::Int32Tree>(grid.tree());  // converts every value and tile
  auto out = openvdb::Int32Grid::create(tree);
  out->setName(kCoverageGrid);
  out->setTransform(ExactCopy(grid.transform()));
  out->insertMeta(static_cast<const openvdb::MetaMap&>(grid));
  return out;
}

void CheckFinite(const openvdb::FloatGrid& grid, const std::string& path) {
  if (!std::isfinite(grid.background()))
    Refuse(path, "grid '" + grid.getName() + "' has a non-finite background");
  for (auto it = grid.cbeginValueAll(); it; ++it)
    if (!std::isfinite(*it))
      Refuse(path, "grid '" + grid.getName() + "' holds a non-finite value at voxel " +
                       CoordText(it.getCoord()));
}

std::string TypeWord(const std::string& tree_type) {
  if (tree_type == "Tree_float_5_4_3") return "a FloatGrid";
  if (tree_type == "Tree_bool_5_4_3") return "a BoolGrid";
  if (tree_type == "Tree_int32_5_4_3") return "an Int32Grid";
  if (tree_type == "Tree_int64_5_4_3") return "an Int64Grid";
  return tree_type;
}

}  // namespace

namespace {

// The coverage grid as floats, made leaf by leaf from the integer grid, which loses each leaf as
// its float copy is made (the converting copy of the whole tree would hold both at once). Active
// tiles keep their level and value; voxel values and masks are copied as they are.
openvdb::FloatGrid::Ptr TakeCoverageAsFloat(openvdb::Int32Grid& grid) {
  using IntLeaf = openvdb::Int32Tree::LeafNodeType;
  using FloatLeafT = openvdb::FloatTree::LeafNodeType;
  openvdb::Int32Tree& src = grid.tree();
  auto out = openvdb::FloatGrid::create(static_cast<float>(src.background()));
  openvdb::FloatTree& dst = out->tree();
  for (auto it = src.cbeginValueOn(); it; ++it) {
    if (it.isVoxelValue()) continue;
    openvdb::CoordBBox box;
    it.getBoundingBox(box);
    dst.addTile(it.getLevel(), box.min(), static_cast<float>(*it), true);
  }
  std::vector<openvdb::Coord> origins;
  for (auto leaf = src.cbeginLeaf(); leaf; ++leaf) origins.push_back(leaf->origin());
  for (const openvdb::Coord& origin : origins) {
    std::unique_ptr<IntLeaf> leaf(src.stealNode<IntLeaf>(origin, src.background(), false));
    auto* copy = new FloatLeafT(origin, static_cast<float>(src.background()), false);
    for (openvdb::Index i = 0; i < IntLeaf::SIZE; ++i)
      copy->setValueOnly(i, static_cast<float>(leaf->getValue(i)));
    copy->setValueMask(leaf->getValueMask());
    dst.addLeaf(copy);
  }
  return out;
}

// A grid sharing `f`'s tree and transform (copyGrid() would re-derive the transform, see
// ExactCopy).
openvdb::FloatGrid::Ptr SharingTree(const openvdb::FloatGrid::Ptr& f) {
  auto copy = openvdb::FloatGrid::create(f->treePtr());
  copy->setTransform(f->transformPtr());
  return copy;
}

// fields.vdb's grids in order, each made when its turn comes: coverage (as floats), the float
// fields in FieldNames() order (a spilled one read back from its file), the extra grids, then the
// per-camera grids. With `owned` (the fields being consumed, `g` itself), each grid leaves the
// fields as it is made, so that it is freed once written: one grid at a time is held beyond those
// not yet written.
std::vector<GridToWrite> FieldGridsToWrite(const Fields::Impl& g, Fields::Impl* owned,
                                           const std::map<std::string, std::string>& metadata) {
  const auto described = [&metadata](openvdb::GridBase::Ptr grid) {
    for (const auto& [key, value] : metadata) grid->insertMeta(key, openvdb::StringMetadata(value));
    Describe(*grid);
    return grid;
  };
  std::vector<GridToWrite> grids;
  if (g.coverage)
    grids.push_back({kCoverageGrid, [&g, owned, described] {
                       openvdb::math::Transform::Ptr transform = ExactCopy(g.coverage->transform());
                       openvdb::FloatGrid::Ptr coverage;
                       if (owned) {
                         coverage = TakeCoverageAsFloat(*owned->coverage);
                         owned->coverage.reset();
                       } else {
                         coverage = openvdb::FloatGrid::create(
                             std::make_shared<openvdb::FloatTree>(g.coverage->tree()));
                       }
                       coverage->setTransform(transform);
                       coverage->setName(kCoverageGrid);
                       return described(coverage);
                     }});
  for (const std::string& name : FieldNames()) {
    if (g.Float(name)) {
      grids.push_back({name, [&g, owned, described, name] {
                         const openvdb::FloatGrid::Ptr f = g.Float(name);
                         auto copy = SharingTree(f);
                         copy->insertMeta(static_cast<const openvdb::MetaMap&>(*f));
                         if (owned) owned->floats.erase(name);
                         return described(copy);
                       }});
    } else if (g.spilled.count(name)) {
      grids.push_back({name, [&g, owned, described, name] {
                         openvdb::FloatGrid::Ptr grid = g.spilled.at(name).Read();
                         if (owned) owned->spilled.erase(name);  // its file closed
                         return described(grid);
                       }});
    }
  }
  for (const auto& [name, f] : g.extra)
    grids.push_back({name, [&g, owned, described, name = name] {
                       auto copy = SharingTree(g.extra.at(name));
                       copy->setName(name);
                       if (owned) owned->extra.erase(name);
                       return described(copy);
                     }});
  if (!g.visible.empty()) {
    // Shares the trees: cheap to make at once, each dropped (with the fields' own) once written.
    auto cameras =
        std::make_shared<openvdb::GridPtrVec>(CameraGrids(g.visible, CameraIds(metadata)));
    for (std::size_t c = 0; c < cameras->size(); ++c)
      grids.push_back({(*cameras)[c]->getName(), [cameras, c, owned, &metadata] {
                         openvdb::GridBase::Ptr grid = std::move((*cameras)[c]);
                         if (owned) owned->visible[c].reset();
                         for (const auto& [key, value] : metadata)
                           if (key != "rig") grid->insertMeta(key, openvdb::StringMetadata(value));
                         return grid;
                       }});
  }
  return grids;
}

// Writes the grids to a temporary name, then renames it to `path`.
void WriteFieldsVdbWith(const Fields::Impl& g, Fields::Impl* owned, const std::string& path,
                        const std::map<std::string, std::string>& metadata) {
  InitializeOpenVdb();
  const std::vector<GridToWrite> grids = FieldGridsToWrite(g, owned, metadata);
  openvdb::MetaMap file_meta;
  for (const auto& [key, value] : metadata)
    file_meta.insertMeta(key, openvdb::StringMetadata(value));
  const std::string tmp = TemporaryPath(path);
  try {
    WriteGridsOneAtATime(tmp, grids, file_meta, kCompression);
  } catch (const openvdb::Exception& e) {
    std::remove(tmp.c_str());
    throw InputError(path, "", std::string("cannot write the VDB file: ") + e.what(),
                     "check that the output folder exists and is writable");
  } catch (const InputError& e) {
    std::remove(tmp.c_str());
    throw InputError(path, "", e.reason(), e.hint());
  }
  CommitTemporary(path);
}

}  // namespace

void WriteFieldsVdb(Fields&& fields, const std::string& path,
                    const std::map<std::string, std::string>& metadata) {
  WriteFieldsVdbWith(fields.impl(), &fields.impl(), path, metadata);
}

void WriteFieldsVdb(const Fields& fields, const std::string& path,
                    const std::map<std::string, std::string>& metadata) {
  WriteFieldsVdbWith(fields.impl(), nullptr, path, metadata);
}

Fields ReadFieldsVdb(const std::string& path, FieldsProvenance* provenance) {
  return ReadFieldsVdbBytes(ReadVdbFileBytes(path), path, provenance);
}

namespace {

// The grids to keep, by what the validator saw (names are unique, types known).
struct KeptGrids {
  std::map<std::string, const VdbGridInfo*> by_name;
  std::vector<const VdbGridInfo*> cameras_info;
  const VdbGridInfo* first = nullptr;
};

// Chooses the grids to keep from the validator's report; refuses wrong types and transforms.
KeptGrids SelectGrids(const VdbFileInfo& info, const std::string& path) {
  KeptGrids kept;
  std::map<std::string, const VdbGridInfo*>& by_name = kept.by_name;
  std::vector<const VdbGridInfo*>& cameras_info = kept.cameras_info;
  std::set<std::int64_t> indices;
  const VdbGridInfo*& first = kept.first;
  int known =
      0;  // grids of FieldNames(), coverage and cameras (a file of derived grids alone is not ours)
  for (const VdbGridInfo& grid : info.grids) {
    const std::string& name = grid.name;
    std::vector<std::string> expected;
    ++known;
    if (name == kCoverageGrid) {
      expected = {"Tree_float_5_4_3", "Tree_int32_5_4_3"};
    } else if (name == kCamerasGrid) {
      expected = {"Tree_int64_5_4_3"};
    } else if (name.rfind(kVisiblePrefix, 0) == 0) {
      expected = {"Tree_bool_5_4_3"};
    } else if (std::find(FieldNames().begin(), FieldNames().end(), name) != FieldNames().end()) {
      expected = {"Tree_float_5_4_3"};
    } else if (grid.tree_type == "Tree_float_5_4_3") {
      expected = {"Tree_float_5_4_3"};  // a derived grid (coverage_n1, ptz_reach_time, ...):
                                        // Fields::Impl::extra
      --known;
    } else {
      --known;
      continue;  // not ours
    }
    if (std::find(expected.begin(), expected.end(), grid.tree_type) == expected.end())
      Refuse(path, "grid '" + name + "' is " + TypeWord(grid.tree_type) + ", expected " +
                       TypeWord(expected[0]));
    if (name.rfind(kVisiblePrefix, 0) == 0) {
      auto index = grid.integers.find("camera_index");
      if (index == grid.integers.end() || index->second < 0 || index->second >= kMaxCameras ||
          !indices.insert(index->second).second)
        Refuse(path, "grid '" + name + "' lacks a camera_index in [0, " +
                         std::to_string(kMaxCameras) + ") of its own");
      if (grid.active_tiles > 0)
        Refuse(path, "grid '" + name + "' holds active tiles; camera grids hold voxels only");
      cameras_info.push_back(&grid);
    }
    auto same = [&](double a, double b) { return std::abs(a - b) <= 1e-9 * first->voxel_size; };
    if (first && (!same(grid.voxel_size, first->voxel_size) ||
                  !same(grid.translation[0], first->translation[0]) ||
                  !same(grid.translation[1], first->translation[1]) ||
                  !same(grid.translation[2], first->translation[2])))
      Refuse(path, "grids '" + first->name + "' and '" + name + "' have different transforms");
    if (!first) first = &grid;
    by_name[name] = &grid;
  }
  if (by_name.empty() || known <= 0)
    Refuse(path, "the VDB file holds none of Pandora's field grids");
  if (by_name.count(kCamerasGrid) && !cameras_info.empty())
    Refuse(path, "the file holds both a 'cameras' grid and per-camera 'visible/' grids");
  return kept;
}

// Parses every grid of the file from memory; refuses a count other than the validator's.
openvdb::GridPtrVecPtr ParseGrids(const std::string& bytes, const std::string& path,
                                  const VdbFileInfo& info) {
  openvdb::GridPtrVecPtr grids;
  try {
    MemoryBuffer buffer(bytes.data(), bytes.size());
    std::istream in(&buffer);
    openvdb::io::Stream stream(in, /*delayLoad=*/false);
    grids = stream.getGrids();
  } catch (const std::exception& e) {  // openvdb::Exception, std::bad_alloc, ...
    Refuse(path, std::string("cannot read the VDB file: ") + e.what());
  }
  if (!grids || grids->size() != info.grids.size())
    Refuse(path, "OpenVDB read a different number of grids than the file holds");
  return grids;
}

// The earlier layout: one Int64 bitmask of up to 64 cameras, into one BoolGrid per camera.
void ExpandCameraBitmask(const openvdb::Int64Grid& bitmask, const std::string& path,
                         Fields::Impl& g) {
  int count = 0;
  for (auto it = bitmask.cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue()) Refuse(path, "grid 'cameras' holds active tiles; it holds voxels only");
    if (*it) count = std::max(count, 64 - __builtin_clzll(std::uint64_t(*it)));
  }
  for (int c = 0; c < count; ++c) {
    auto grid = openvdb::BoolGrid::create(false);
    grid->setTransform(g.transform);
    g.visible.push_back(grid);
  }
  std::vector<openvdb::BoolGrid::Accessor> acc;
  for (auto& grid : g.visible) acc.push_back(grid->getAccessor());
  for (auto it = bitmask.cbeginValueOn(); it; ++it) {
    const std::uint64_t mask = static_cast<std::uint64_t>(*it);
    const openvdb::CoordBBox box = it.getBoundingBox();
    for (auto xyz = box.begin(); xyz; ++xyz)
      for (int c = 0; c < count; ++c)
        if (mask >> c & 1) acc[c].setValueOn(*xyz, true);
  }
}

// Puts the kept grids of `grids` into `g`: coverage, float fields, derived grids, camera grids.
void TakeGrids(const openvdb::GridPtrVec& grids, KeptGrids& kept, const std::string& path,
               Fields::Impl& g) {
  std::map<std::string, const VdbGridInfo*>& by_name = kept.by_name;
  std::map<std::int64_t, openvdb::BoolGrid::Ptr> visible;
  openvdb::Int64Grid::Ptr bitmask;
  for (const openvdb::GridBase::Ptr& base : grids) {
    const std::string name = base->getName();
    if (!by_name.count(name)) continue;
    if (name == kCoverageGrid) {
      if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(base))
        g.coverage = CoverageFromFloat(*f, path);
      else if ((g.coverage = openvdb::gridPtrCast<openvdb::Int32Grid>(base)))
        CheckCameraCounts(*g.coverage, path);  // the earlier layout
    } else if (name == kCamerasGrid) {
      bitmask = openvdb::gridPtrCast<openvdb::Int64Grid>(base);
    } else if (name.rfind(kVisiblePrefix, 0) == 0) {
      visible[by_name[name]->integers.at("camera_index")] =
          openvdb::gridPtrCast<openvdb::BoolGrid>(base);
    } else {
      auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
      if (!f) Refuse(path, "OpenVDB read a grid of another type than the file declares");
      CheckFinite(*f, path);
      if (std::find(FieldNames().begin(), FieldNames().end(), name) != FieldNames().end())
        g.floats[name] = f;
      else
        g.extra[name] = f;
    }
    if (!g.transform) g.transform = base->transformPtr();
  }
  if ((by_name.count(kCoverageGrid) && !g.coverage) || (by_name.count(kCamerasGrid) && !bitmask) ||
      visible.size() != kept.cameras_info.size())
    Refuse(path, "OpenVDB read a grid of another type than the file declares");
  if (!visible.empty()) {
    // Indices 0..n-1 each once: a rig's cameras.
    if (visible.rbegin()->first != std::int64_t(visible.size()) - 1)
      Refuse(path, "the per-camera 'visible/' grids do not number the cameras 0.." +
                       std::to_string(visible.size() - 1));
    for (const auto& [index, grid] : visible) g.visible.push_back(grid);
  }
  if (bitmask) ExpandCameraBitmask(*bitmask, path, g);
}

// The provenance strings of the file's metadata.
FieldsProvenance ReadProvenance(const VdbFileInfo& info) {
  FieldsProvenance p;
  p.metadata = info.strings;
  auto get = [&](const char* key) {
    auto it = info.strings.find(key);
    return it == info.strings.end() ? std::string() : it->second;
  };
  p.scene_file = get("scene_file");
  p.scene_sha256 = get("scene_sha256");
  p.rig_name = get("rig_name");
  p.rig_json = get("rig");
  p.tool = get("tool");
  p.tool_version = get("tool_version");
  return p;
}

}  // namespace

Fields ReadFieldsVdbBytes(const std::string& bytes, const std::string& path,
                          FieldsProvenance* provenance) {
  const VdbFileInfo info = CheckVdbBytes(bytes, path);
  InitializeOpenVdb();

  // Which grids to keep, by what the validator saw (names are unique, types known).
  KeptGrids kept = SelectGrids(info, path);
  const VdbGridInfo* first = kept.first;

  const openvdb::GridPtrVecPtr grids = ParseGrids(bytes, path, info);

  Fields fields;
  TakeGrids(*grids, kept, path, fields.impl());

  // The lattice: voxel (0, 0, 0) at the transform's origin, extent from the active voxels.
  fields.lattice.voxel_size = first->voxel_size;
  fields.lattice.origin = Vec3(first->translation[0], first->translation[1], first->translation[2]);
  for (const auto& [name, grid] : kept.by_name)
    if (!grid->empty)
      for (int a = 0; a < 3; ++a)
        fields.lattice.dims[a] =
            std::max<int>(fields.lattice.dims[a], int(grid->active_max[a] + 1));

  if (provenance) *provenance = ReadProvenance(info);
  return fields;
}

}  // namespace pandora
