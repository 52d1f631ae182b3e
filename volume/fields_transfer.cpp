#include "volume/fields_transfer.h"

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "volume/fields_vdb.h"

namespace pandora {
namespace {

constexpr char kMagic[8] = {'P', 'N', 'D', 'R', 'P', 'T', '0', '1'};

class Writer {
 public:
  void Bytes(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  void I64(std::int64_t v) { Bytes(&v, sizeof v); }
  template <typename T>
  void Vector(const std::vector<T>& v) {
    I64(static_cast<std::int64_t>(v.size()));
    if (!v.empty()) Bytes(v.data(), v.size() * sizeof(T));
  }
  std::string& str() { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  explicit Reader(const std::string& in) : in_(in) {}
  void Bytes(void* p, std::size_t n) {
    if (n > in_.size() - at_) throw std::runtime_error("partial fields: truncated");
    std::memcpy(p, in_.data() + at_, n);
    at_ += n;
  }
  std::int64_t I64() {
    std::int64_t v = 0;
    Bytes(&v, sizeof v);
    return v;
  }
  template <typename T>
  std::vector<T> Vector() {
    const std::int64_t n = I64();
    if (n < 0 || std::uint64_t(n) > (in_.size() - at_) / sizeof(T))
      throw std::runtime_error("partial fields: bad length");
    std::vector<T> v(static_cast<std::size_t>(n));
    if (n > 0) Bytes(v.data(), v.size() * sizeof(T));
    return v;
  }
  std::string Rest() const { return in_.substr(at_); }

 private:
  const std::string& in_;
  std::size_t at_ = 0;
};

template <typename GridPtr>
void MergeTree(const GridPtr& into, openvdb::GridBase::Ptr from, const std::string& what) {
  using GridType = typename GridPtr::element_type;
  auto grid = openvdb::gridPtrCast<GridType>(from);
  if (!into || !grid) throw std::runtime_error("partial fields: grid " + what + " does not match");
  into->tree().merge(grid->tree(), openvdb::MERGE_ACTIVE_STATES);
}

}  // namespace

void AddFieldStats(FieldStats* into, const FieldStats& part) {
  const auto add = [](std::vector<std::int64_t>* a, const std::vector<std::int64_t>& b) {
    a->resize(std::max(a->size(), b.size()), 0);
    for (std::size_t i = 0; i < b.size(); ++i) (*a)[i] += b[i];
  };
  into->active_set.region_voxels += part.active_set.region_voxels;
  into->active_set.solid_voxels += part.active_set.solid_voxels;
  into->active_set.blocks += part.active_set.blocks;
  into->active_set.culled_blocks += part.active_set.culled_blocks;
  into->seen_voxels += part.seen_voxels;
  into->triangulable_voxels += part.triangulable_voxels;
  into->unobservable_voxels += part.unobservable_voxels;
  into->point_camera_tests += part.point_camera_tests;
  into->rays += part.rays;
  into->angle_pairs_tried += part.angle_pairs_tried;
  into->angle_pairs_all += part.angle_pairs_all;
  add(&into->coverage_histogram, part.coverage_histogram);
  add(&into->per_camera_seen, part.per_camera_seen);
  into->sigma_max_mm.insert(into->sigma_max_mm.end(), part.sigma_max_mm.begin(),
                            part.sigma_max_mm.end());
  into->sigma_max_steady_mm.insert(into->sigma_max_steady_mm.end(),
                                   part.sigma_max_steady_mm.begin(),
                                   part.sigma_max_steady_mm.end());
  into->seconds += part.seconds;
  into->cpu_seconds += part.cpu_seconds;
  into->active_set_seconds += part.active_set_seconds;
  into->estimated_bytes = std::max(into->estimated_bytes, part.estimated_bytes);
}

std::string SerializePartialFields(const Fields& fields) {
  const FieldStats& s = fields.stats;
  Writer w;
  w.Bytes(kMagic, sizeof kMagic);
  for (std::int64_t v :
       {s.seen_voxels, s.triangulable_voxels, s.unobservable_voxels, s.point_camera_tests, s.rays})
    w.I64(v);
  w.Vector(s.coverage_histogram);
  w.Vector(s.per_camera_seen);
  w.Vector(s.sigma_max_mm);
  w.Vector(s.sigma_max_steady_mm);
  w.I64(fields.lattice.dims.x());
  w.I64(fields.lattice.dims.y());
  w.I64(fields.lattice.dims.z());
  // The grids, named by role: "coverage", "float/<name>", "visible/<camera index>".
  const Fields::Impl& g = fields.impl();
  openvdb::GridPtrVec grids;
  auto add = [&](openvdb::GridBase::Ptr grid, const std::string& name) {
    openvdb::GridBase::Ptr copy = grid->copyGrid();  // own metadata (the name), shared tree
    copy->setName(name);
    grids.push_back(copy);
  };
  if (g.coverage) add(g.coverage, "coverage");
  for (const auto& [name, grid] : g.floats) add(grid, "float/" + name);
  for (std::size_t c = 0; c < g.visible.size(); ++c)
    add(g.visible[c], "visible/" + std::to_string(c));
  std::ostringstream vdb(std::ios::binary);
  openvdb::io::Stream(vdb).write(grids);
  w.str() += vdb.str();
  return std::move(w.str());
}

void MergePartialFields(const std::string& bytes, Fields* fields) {
  openvdb::initialize();  // the grid types, to read them (idempotent)
  Reader r(bytes);
  char magic[sizeof kMagic];
  r.Bytes(magic, sizeof magic);
  if (std::memcmp(magic, kMagic, sizeof kMagic) != 0)
    throw std::runtime_error("partial fields: not a partition");
  FieldStats& s = fields->stats;
  s.seen_voxels += r.I64();
  s.triangulable_voxels += r.I64();
  s.unobservable_voxels += r.I64();
  s.point_camera_tests += r.I64();
  s.rays += r.I64();
  const auto histogram = r.Vector<std::int64_t>();
  const auto per_camera = r.Vector<std::int64_t>();
  if (histogram.size() != s.coverage_histogram.size() ||
      per_camera.size() != s.per_camera_seen.size())
    throw std::runtime_error("partial fields: another camera count");
  for (std::size_t k = 0; k < histogram.size(); ++k) s.coverage_histogram[k] += histogram[k];
  for (std::size_t c = 0; c < per_camera.size(); ++c) s.per_camera_seen[c] += per_camera[c];
  const auto sigma = r.Vector<float>();
  const auto steady = r.Vector<float>();
  s.sigma_max_mm.insert(s.sigma_max_mm.end(), sigma.begin(), sigma.end());
  s.sigma_max_steady_mm.insert(s.sigma_max_steady_mm.end(), steady.begin(), steady.end());
  const std::int64_t nx = r.I64(), ny = r.I64(), nz = r.I64();
  if (nx != fields->lattice.dims.x() || ny != fields->lattice.dims.y() ||
      nz != fields->lattice.dims.z())
    throw std::runtime_error("partial fields: another lattice");

  std::istringstream vdb(r.Rest(), std::ios::binary);
  openvdb::GridPtrVecPtr grids;
  try {
    grids = openvdb::io::Stream(vdb).getGrids();
  } catch (const openvdb::Exception& e) {
    throw std::runtime_error(std::string("partial fields: ") + e.what());
  }
  Fields::Impl& g = fields->impl();
  std::size_t visible = 0;
  for (const openvdb::GridBase::Ptr& grid : *grids) {
    const std::string name = grid->getName();
    if (name == "coverage") {
      MergeTree(g.coverage, grid, name);
    } else if (name.rfind("float/", 0) == 0) {
      MergeTree(g.Float(name.substr(6)), grid, name);
    } else if (name.rfind("visible/", 0) == 0) {
      const std::size_t c = std::stoul(name.substr(8));
      if (c >= g.visible.size()) throw std::runtime_error("partial fields: another camera count");
      MergeTree(g.visible[c], grid, name);
      ++visible;
    } else {
      throw std::runtime_error("partial fields: unknown grid " + name);
    }
  }
  if (visible != g.visible.size()) throw std::runtime_error("partial fields: another camera count");
}

}  // namespace pandora
