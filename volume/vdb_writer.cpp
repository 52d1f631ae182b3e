#include "volume/vdb_writer.h"

#include <openvdb/io/GridDescriptor.h>
#include <openvdb/io/io.h>

#include <fstream>
#include <map>
#include <set>

#include "analysis/util/error.h"

namespace pandora {
namespace {

// openvdb::io::Archive's own sequence (header, file metadata, grid count, then each grid with its
// descriptor and offsets), with the grids made one at a time and the stream checked.
class OneAtATimeWriter : public openvdb::io::Archive {
 public:
  void Write(std::ostream& os, const std::vector<GridToWrite>& grids,
             const openvdb::MetaMap& metadata) const {
    auto stream_metadata = std::make_shared<openvdb::io::StreamMetadata>();
    openvdb::io::setStreamMetadataPtr(os, stream_metadata, /*transfer=*/false);
    openvdb::io::setDataCompression(os, compression());
    openvdb::io::setWriteGridStatsMetadata(os, isGridStatsMetadataEnabled());
    writeHeader(os, /*seekable=*/true);
    metadata.writeMeta(os);
    const std::int32_t count = static_cast<std::int32_t>(grids.size());
    os.write(reinterpret_cast<const char*>(&count), sizeof count);
    std::map<std::string, int> uses;
    for (const GridToWrite& g : grids) ++uses[g.name];
    std::set<std::string> unique;
    for (const GridToWrite& g : grids) {
      std::string name = g.name;
      if (name.empty() || uses[name] > 1) name = openvdb::io::GridDescriptor::addSuffix(name, 0);
      for (int n = 1; unique.count(name); ++n)
        name = openvdb::io::GridDescriptor::addSuffix(g.name, n);
      unique.insert(name);
      openvdb::GridBase::Ptr grid = g.make();
      openvdb::io::GridDescriptor descriptor(name, grid->type(), grid->saveFloatAsHalf());
      writeGrid(descriptor, grid, os, /*seekable=*/true);
      openvdb::io::setDataCompression(os, compression());  // per-grid flags undone
    }
  }
  openvdb::io::Archive::Ptr copy() const override {
    return openvdb::io::Archive::Ptr(new OneAtATimeWriter(*this));
  }
};

}  // namespace

void WriteGridsOneAtATime(const std::string& path, const std::vector<GridToWrite>& grids,
                          const openvdb::MetaMap& metadata, std::uint32_t compression) {
  std::ofstream os(path, std::ios::binary | std::ios::trunc);
  if (!os) throw InputError(path, "", "cannot create the VDB file", "check the output folder");
  OneAtATimeWriter writer;
  writer.setCompression(compression);
  writer.Write(os, grids, metadata);
  os.flush();
  const bool ok = static_cast<bool>(os);
  os.close();
  if (!ok || os.fail())
    throw InputError(path, "", "cannot write the VDB file: the disk is full or the write failed",
                     "free some space, then run again");
}

}  // namespace pandora
