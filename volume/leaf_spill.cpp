#include "volume/leaf_spill.h"

#include <cerrno>
#include <cstring>

#include "analysis/util/error.h"
#include "volume/value_spill.h"

namespace pandora {
namespace {

using Leaf = LeafSpill::Leaf;
constexpr std::size_t kWords = Leaf::NUM_VOXELS / 64;  // the value mask, in 64-bit words

// One leaf as written: origin, value mask, values.
struct Record {
  std::int32_t origin[3];
  std::uint64_t mask[kWords];
  float values[Leaf::NUM_VOXELS];
};

}  // namespace

LeafSpill::LeafSpill(const std::string& folder, const std::string& blame)
    : file_(OpenTemporaryFile(folder, blame)), blame_(blame) {}

LeafSpill::~LeafSpill() {
  if (file_) std::fclose(file_);
}

void LeafSpill::Append(const Leaf& leaf) {
  Record r;
  for (int k = 0; k < 3; ++k) r.origin[k] = leaf.origin()[k];
  for (std::size_t w = 0; w < kWords; ++w)
    r.mask[w] = leaf.getValueMask().template getWord<std::uint64_t>(openvdb::Index(w));
  std::memcpy(r.values, leaf.buffer().data(), sizeof r.values);
  std::lock_guard<std::mutex> lock(mutex_);
  if (std::fwrite(&r, sizeof r, 1, file_) != 1)
    throw InputError(
        blame_, "",
        std::string("cannot write a temporary file of field leaves: ") + std::strerror(errno),
        "free some space, then run again");
  ++leaves_;
}

void LeafSpill::AddTo(openvdb::FloatTree& tree) const {
  if (std::fflush(file_) != 0 || std::fseek(file_, 0, SEEK_SET) != 0)
    throw InputError(
        blame_, "",
        std::string("cannot read back a temporary file of field leaves: ") + std::strerror(errno));
  Record r;
  for (std::int64_t i = 0; i < leaves_; ++i) {
    if (std::fread(&r, sizeof r, 1, file_) != 1)
      throw InputError(blame_, "", "a temporary file of field leaves was cut short");
    auto leaf =
        std::make_unique<Leaf>(openvdb::Coord(r.origin[0], r.origin[1], r.origin[2]), 0.0f, false);
    std::memcpy(leaf->buffer().data(), r.values, sizeof r.values);
    Leaf::NodeMaskType mask;
    for (std::size_t w = 0; w < kWords; ++w)
      mask.template getWord<std::uint64_t>(openvdb::Index(w)) = r.mask[w];
    leaf->setValueMask(mask);
    tree.addLeaf(leaf.release());
  }
  std::fseek(file_, 0, SEEK_END);  // later appends go after the leaves
}

openvdb::FloatGrid::Ptr SpilledGrid::Read() const {
  openvdb::FloatGrid::Ptr out = openvdb::FloatGrid::create(grid->background());
  out->setTransform(grid->transformPtr());
  out->insertMeta(static_cast<const openvdb::MetaMap&>(*grid));  // its name too
  if (leaves) leaves->AddTo(out->tree());
  return out;
}

}  // namespace pandora
