// fields.vdb: exact round trips of every grid kind, the earlier layout, every compression OpenVDB
// writes, and the validator: truncation at every byte, bit flips, crafted counts and offsets,
// damaged compressed chunks, special files, limits, transforms, value ranges; the provenance check.
#include "volume/vdb_io.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <random>

#include "analysis/util/error.h"
#include "volume/fields_vdb.h"
#include "volume/vdb_check.h"
#include "volume/vdb_writer.h"

namespace pandora {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  const fs::path dir =
      fs::temp_directory_path() / ("pandora_vdb_io_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

openvdb::math::Transform::Ptr LatticeTransform(double voxel_size, const openvdb::Vec3d& origin) {
  auto t = openvdb::math::Transform::createLinearTransform(voxel_size);
  t->postTranslate(origin);
  return t;
}

// Fields with every grid kind: coverage (leaves, an active tile of zeros, inactive voxels), one
// visibility grid per camera (random sets) and two float fields.
Fields MakeFields(int cameras = 64) {
  InitializeOpenVdb();
  Fields f;
  Fields::Impl& g = f.impl();
  g.transform = LatticeTransform(0.05, openvdb::Vec3d(-0.475, -0.475, 0.025));
  g.coverage = openvdb::Int32Grid::create(0);
  g.coverage->setName(kCoverageGrid);
  for (int c = 0; c < cameras; ++c) g.visible.push_back(openvdb::BoolGrid::create(false));
  auto resolution = openvdb::FloatGrid::create(0);
  resolution->setName("resolution");
  auto sigma = openvdb::FloatGrid::create(0);
  sigma->setName("sigma_max");
  for (auto grid : openvdb::GridPtrVec{g.coverage, resolution, sigma})
    grid->setTransform(g.transform);
  for (auto& grid : g.visible) grid->setTransform(g.transform);
  std::mt19937_64 rng(7);
  auto cov = g.coverage->getAccessor();
  auto res = resolution->getAccessor();
  auto sig = sigma->getAccessor();
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 12; ++j)
      for (int k = 0; k < 9; ++k) {
        const openvdb::Coord c(i, j, k);
        if ((i + 2 * j + 3 * k) % 11 == 0) continue;  // outside the region: inactive
        std::vector<int> seen;
        for (int cam = 0; cam < cameras; ++cam)
          if (rng() & 1) seen.push_back(cam);
        if ((i * j + k) % 4 == 0) seen.clear();
        if (i == 19 && j == 11) seen = {cameras - 1};
        const int count = static_cast<int>(seen.size());
        cov.setValueOn(c, count);
        if (seen.empty()) continue;
        for (int cam : seen) g.visible[cam]->tree().setValueOn(c, true);
        res.setValueOn(c, float(std::ldexp(double(rng() % 100000), -7)));
        if (count >= 2) sig.setValueOn(c, float(rng() % 1000) * 0.125f);
      }
  g.coverage->tree().addTile(1, openvdb::Coord(24, 0, 0), 0, true);  // a culled block
  g.floats["resolution"] = resolution;
  g.floats["sigma_max"] = sigma;
  f.lattice.voxel_size = 0.05;
  f.lattice.origin = Vec3(-0.475, -0.475, 0.025);
  f.lattice.dims = Eigen::Vector3i(32, 12, 9);
  return f;
}

// Camera ids with odd bytes, in the rig metadata as RigToJson writes it.
std::map<std::string, std::string> RigMetadata(int cameras) {
  nlohmann::json rig = {{"name", "many"}, {"cameras", nlohmann::json::array()}};
  for (int c = 0; c < cameras; ++c)
    rig["cameras"].push_back(
        {{"id", c % 3 == 0 ? "cam " + std::to_string(c) + "/\xc3\xa9%" : std::to_string(c)}});
  return {{"rig", rig.dump()},     {"rig_name", "many"},    {"scene_sha256", "0123abc"},
          {"tool", "pandora"},     {"tool_version", "9.9"}, {"units", "m"},
          {"scene_file", "s.json"}};
}

std::string WriteBytes(const Fields& f, const std::map<std::string, std::string>& meta,
                       const std::string& name) {
  const fs::path path = TempDir() / name;
  WriteFieldsVdb(f, path.string(), meta);
  return ReadBytes(path);
}

template <typename GridT>
void ExpectSameGrid(const GridT& a, const GridT& b) {
  EXPECT_TRUE(a.tree().hasSameTopology(b.tree())) << a.getName();
  EXPECT_EQ(a.activeVoxelCount(), b.activeVoxelCount()) << a.getName();
  EXPECT_EQ(a.tree().activeTileCount(), b.tree().activeTileCount()) << a.getName();
  EXPECT_EQ(a.background(), b.background()) << a.getName();
  auto acc = b.getConstAccessor();
  for (auto it = a.cbeginValueAll(); it; ++it) {
    ASSERT_EQ(*it, acc.getValue(it.getCoord())) << a.getName() << " " << it.getCoord();
    ASSERT_EQ(it.isValueOn(), acc.isValueOn(it.getCoord())) << a.getName() << " " << it.getCoord();
  }
  EXPECT_EQ(a.transform(), b.transform());
}

void ExpectSameFields(const Fields& a, const Fields& b) {
  ASSERT_TRUE(a.impl().coverage && b.impl().coverage);
  ExpectSameGrid(*a.impl().coverage, *b.impl().coverage);
  ASSERT_EQ(a.impl().visible.size(), b.impl().visible.size());
  for (std::size_t c = 0; c < a.impl().visible.size(); ++c)
    ExpectSameGrid(*a.impl().visible[c], *b.impl().visible[c]);
  ASSERT_EQ(a.impl().floats.size(), b.impl().floats.size());
  for (const auto& [name, grid] : a.impl().floats) {
    ASSERT_TRUE(b.impl().Float(name)) << name;
    ExpectSameGrid(*grid, *b.impl().Float(name));
  }
}

// Beyond the 64 bits of the earlier bitmask: 300 cameras, each its own sparse grid, round trip
// exactly and keep their order and ids.
TEST(VdbIo, ThreeHundredCamerasRoundTrip) {
  const Fields f = MakeFields(300);
  const auto meta = RigMetadata(300);
  const std::string bytes = WriteBytes(f, meta, "many.vdb");
  const Fields back = ReadFieldsVdbBytes(bytes, "many.vdb");
  ExpectSameFields(f, back);
  ASSERT_EQ(back.impl().visible.size(), 300u);
  auto cov = f.impl().coverage->getConstAccessor();
  const openvdb::Coord probe(3, 4, 5);
  int seen = 0;
  for (const auto& grid : back.impl().visible) seen += grid->tree().isValueOn(probe);
  EXPECT_EQ(seen, cov.getValue(probe));
  EXPECT_GT(seen, 100);  // about half of 300 (the random sets draw each camera with p = 1/2)
}

TEST(VdbIo, RoundTripOfEveryGridKindIsExact) {
  const Fields f = MakeFields();
  const auto meta = RigMetadata(64);
  const std::string bytes = WriteBytes(f, meta, "all.vdb");
  FieldsProvenance p;
  const Fields back = ReadFieldsVdbBytes(bytes, "all.vdb", &p);
  ExpectSameFields(f, back);
  EXPECT_EQ(back.lattice.voxel_size, 0.05);
  EXPECT_EQ(back.lattice.origin, f.lattice.origin);
  EXPECT_EQ(back.lattice.dims, Eigen::Vector3i(32, 12, 9));  // the tile reaches x = 31
  EXPECT_EQ(p.rig_name, "many");
  EXPECT_EQ(p.scene_sha256, "0123abc");
  EXPECT_EQ(p.rig_json, meta.at("rig"));
  EXPECT_EQ(p.tool_version, "9.9");
  EXPECT_EQ(p.scene_file, "s.json");
  // The same through a file, and the writing left the in-memory grids' metadata alone.
  const fs::path path = TempDir() / "all_file.vdb";
  WriteFieldsVdb(f, path.string(), meta);
  ExpectSameFields(f, ReadFieldsVdb(path.string()));
  EXPECT_FALSE((*f.impl().coverage)["rig"]);
}

// What `pandora analyze` writes: the fields consumed, the coverage grid converted leaf by leaf.
// It reads back as the const writer's file of the same fields does (every grid, the coverage tile
// included), and the consumed fields lose their coverage grid.
TEST(VdbIo, ConsumingWriterWritesTheSameFile) {
  const auto meta = RigMetadata(64);
  const fs::path a = TempDir() / "const.vdb", b = TempDir() / "consumed.vdb";
  const Fields f = MakeFields();
  WriteFieldsVdb(f, a.string(), meta);
  Fields g = MakeFields();
  WriteFieldsVdb(std::move(g), b.string(), meta);
  ExpectSameFields(ReadFieldsVdb(a.string()), ReadFieldsVdb(b.string()));
  ExpectSameFields(f, ReadFieldsVdb(b.string()));
  EXPECT_FALSE(
      g.impl().coverage);  // NOLINT(bugprone-use-after-move): the writer's documented effect
}

// WriteGridsOneAtATime writes the file openvdb::io::File::write writes from the same grids (names
// used twice and an empty name included), but for the header's random UUID, making each grid only
// when its turn comes.
TEST(VdbIo, OneAtATimeWriterWritesWhatOpenVdbWrites) {
  const Fields f = MakeFields(5);
  const Fields::Impl& g = f.impl();
  auto twin = openvdb::gridPtrCast<openvdb::FloatGrid>(g.Float("sigma_max")->deepCopyGrid());
  twin->setName("resolution");
  const openvdb::GridPtrVec grids{g.Float("resolution"), g.Float("sigma_max"), twin, g.visible[0],
                                  g.visible[3]->deepCopyGrid()};
  openvdb::MetaMap meta;
  meta.insertMeta("units", openvdb::StringMetadata("m"));
  const std::uint32_t compression = openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK;
  const fs::path a = TempDir() / "openvdb.vdb", b = TempDir() / "one_at_a_time.vdb";
  openvdb::io::File file(a.string());
  file.setCompression(compression);
  file.write(grids, meta);
  file.close();
  std::vector<GridToWrite> list;
  std::vector<std::size_t> made;
  for (std::size_t i = 0; i < grids.size(); ++i)
    list.push_back({grids[i]->getName(), [&, i] {
                      made.push_back(i);
                      return grids[i];
                    }});
  WriteGridsOneAtATime(b.string(), list, meta, compression);
  EXPECT_EQ(made, (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  std::string bytes_a = ReadBytes(a), bytes_b = ReadBytes(b);
  ASSERT_GT(bytes_a.size(), 1000u);
  ASSERT_EQ(bytes_a.size(), bytes_b.size());
  EXPECT_NE(bytes_a.substr(21, 36), bytes_b.substr(21, 36));  // the UUIDs, and nothing else
  bytes_a.replace(21, 36, 36, '-');
  bytes_b.replace(21, 36, 36, '-');
  EXPECT_TRUE(bytes_a == bytes_b);
  // A folder that does not exist: the path named.
  try {
    WriteGridsOneAtATime((TempDir() / "no" / "such.vdb").string(), list, meta, compression);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(e.file().find("such.vdb"), std::string::npos);
  }
}

TEST(VdbIo, OneBoolGridPerCameraNamedByItsEncodedId) {
  const Fields f = MakeFields();
  const auto meta = RigMetadata(64);
  const fs::path path = TempDir() / "names.vdb";
  WriteFieldsVdb(f, path.string(), meta);
  openvdb::io::File file(path.string());
  file.open(false);
  const auto grids = file.getGrids();
  file.close();
  const nlohmann::json rig = nlohmann::json::parse(meta.at("rig"));
  int found = 0;
  for (const auto& grid : *grids) {
    if (grid->getName().rfind("visible/", 0) != 0) {
      EXPECT_TRUE(grid->isType<openvdb::FloatGrid>()) << grid->getName();
      continue;
    }
    auto seen = openvdb::gridPtrCast<openvdb::BoolGrid>(grid);
    ASSERT_TRUE(seen);
    const std::int64_t c = seen->metaValue<std::int64_t>("camera_index");
    const std::string id = rig["cameras"][c]["id"];
    EXPECT_EQ(seen->metaValue<std::string>("camera_id"), id);
    EXPECT_EQ(seen->getName(), VisibilityGridName(id));
    EXPECT_FALSE((*seen)["rig"]);  // the rig JSON only on the file and the field grids
    EXPECT_EQ(seen->activeVoxelCount(), f.impl().visible[c]->activeVoxelCount());
    ++found;
  }
  EXPECT_EQ(found, 64);
  EXPECT_EQ(VisibilityGridName("cam 1/\xc3\xa9%"), "visible/cam%201%2F%C3%A9%25");
  EXPECT_EQ(VisibilityGridName("A-z_0.9"), "visible/A-z_0.9");
  EXPECT_EQ(VisibilityGridName(std::string("a\0b", 3)), "visible/a%00b");
}

TEST(VdbIo, CamerasWithoutRigMetadataAreNamedByIndex) {
  const Fields f = MakeFields(5);
  const std::string bytes = WriteBytes(f, {}, "index.vdb");
  const VdbFileInfo info = CheckVdbBytes(bytes, "index.vdb");
  std::vector<std::string> names;
  for (const VdbGridInfo& g : info.grids) names.push_back(g.name);
  EXPECT_EQ(names, (std::vector<std::string>{"coverage", "resolution", "sigma_max", "visible/0",
                                             "visible/1", "visible/2", "visible/3", "visible/4"}));
  ExpectSameFields(f, ReadFieldsVdbBytes(bytes, "index.vdb"));
}

TEST(VdbIo, ReadsTheEarlierLayout) {
  const Fields f = MakeFields();
  const fs::path path = TempDir() / "earlier.vdb";
  openvdb::io::File file(path.string());
  file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
  // The cameras as one Int64 bitmask (bit 63 too, so negative values).
  auto bitmask = openvdb::Int64Grid::create(0);
  bitmask->setName(kCamerasGrid);
  bitmask->setTransform(f.impl().transform);
  for (std::size_t c = 0; c < f.impl().visible.size(); ++c)
    for (auto it = f.impl().visible[c]->cbeginValueOn(); it; ++it)
      bitmask->tree().setValueOn(
          it.getCoord(), std::int64_t(std::uint64_t(bitmask->tree().getValue(it.getCoord())) |
                                      (std::uint64_t{1} << c)));
  file.write(openvdb::GridPtrVec{f.impl().coverage, bitmask, f.impl().floats.at("resolution"),
                                 f.impl().floats.at("sigma_max")});
  file.close();
  ExpectSameFields(f, ReadFieldsVdb(path.string()));
}

// Grids whose leaves need each of OpenVDB's seven mask-compression codes (io/Compression.h),
// written with every compression OpenVDB offers: the validator accepts them all, and the fields
// among them read back exactly.
TEST(VdbIo, AcceptsEveryCompressionAndMaskCode) {
  const Fields f = MakeFields(3);
  openvdb::GridPtrVec grids;
  auto coverage =
      openvdb::FloatGrid::create(std::make_shared<openvdb::FloatTree>(f.impl().coverage->tree()));
  coverage->setName("coverage");
  coverage->setTransform(f.impl().transform);
  grids.push_back(coverage);
  grids.push_back(f.impl().floats.at("resolution"));
  for (int code = 0; code < 7; ++code) {
    auto g = openvdb::FloatGrid::create(5.0f);
    g->setName("extra_" + std::to_string(code));
    g->setTransform(f.impl().transform);
    auto acc = g->getAccessor();
    for (int n = 0; n < 512; ++n) {
      const openvdb::Coord c(n >> 6, (n >> 3) & 7, n & 7);
      if (n % 2 == 0) {
        acc.setValueOn(c, float(n));
        continue;
      }
      const float inactive[7] = {
          5.0f,    -5.0f, 1.0f, n % 3 ? 5.0f : -5.0f, n % 3 ? 5.0f : 2.0f, n % 3 ? 3.0f : 2.0f,
          float(n)};
      acc.setValueOff(c, inactive[code]);
    }
    grids.push_back(g);
  }
  auto bools = openvdb::BoolGrid::create(false);
  bools->setName("extra_bool");
  bools->setTransform(f.impl().transform);
  bools->tree().setValueOn(openvdb::Coord(1, 2, 3), true);
  bools->tree().setValueOff(openvdb::Coord(1, 2, 4), true);
  grids.push_back(bools);
  for (std::uint32_t compression : {0u, 1u, 2u, 3u, 4u, 6u}) {
    const fs::path path = TempDir() / ("compression_" + std::to_string(compression) + ".vdb");
    openvdb::io::File file(path.string());
    file.setCompression(compression);
    file.write(grids);
    file.close();
    const std::string bytes = ReadBytes(path);
    VdbFileInfo info;
    ASSERT_NO_THROW(info = CheckVdbBytes(bytes, path.string())) << compression;
    for (const VdbGridInfo& g : info.grids) EXPECT_EQ(g.compression, compression) << g.name;
    const Fields back = ReadFieldsVdbBytes(bytes, path.string());
    auto cov = back.impl().coverage->getConstAccessor();
    for (auto it = f.impl().coverage->cbeginValueOn(); it; ++it)
      ASSERT_EQ(cov.getValue(it.getCoord()), *it);
    ExpectSameGrid(*f.impl().floats.at("resolution"), *back.impl().Float("resolution"));
  }
}

std::string SmallFile() {
  Fields f;
  InitializeOpenVdb();
  Fields::Impl& g = f.impl();
  g.transform = LatticeTransform(0.1, openvdb::Vec3d(0.05, 0.05, 0.05));
  g.coverage = openvdb::Int32Grid::create(0);
  g.coverage->setName(kCoverageGrid);
  g.coverage->setTransform(g.transform);
  for (int c = 0; c < 2; ++c) {
    g.visible.push_back(openvdb::BoolGrid::create(false));
    g.visible.back()->setTransform(g.transform);
  }
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 5; ++j) {
      const std::uint64_t mask = (i + j) % 4;
      g.coverage->tree().setValueOn(openvdb::Coord(i, j, 1), __builtin_popcountll(mask));
      for (int c = 0; c < 2; ++c)
        if (mask >> c & 1) g.visible[c]->tree().setValueOn(openvdb::Coord(i, j, 1), true);
    }
  return WriteBytes(f, {{"rig_name", "r"}}, "small.vdb");
}

TEST(VdbValidator, TruncationAtEveryByteIsRefused) {
  const std::string bytes = SmallFile();
  ASSERT_NO_THROW(ReadFieldsVdbBytes(bytes, "small.vdb"));
  for (std::size_t n = 0; n < bytes.size(); ++n)
    ASSERT_THROW(ReadFieldsVdbBytes(bytes.substr(0, n), "small.vdb"), InputError) << "cut at " << n;
  ASSERT_THROW(ReadFieldsVdbBytes(bytes + '\0', "small.vdb"), InputError);  // a byte too many
}

TEST(VdbValidator, BitFlipsGiveInputErrorOrFields) {
  const std::string bytes = SmallFile();
  int refused = 0, read = 0;
  for (std::size_t at = 0; at < bytes.size(); ++at) {
    std::string damaged = bytes;
    damaged[at] = char(damaged[at] ^ (1 << (at % 8)));
    bool accepted = false;
    try {
      ReadFieldsVdbBytes(damaged, "flipped.vdb");
      accepted = true;
      ++read;
    } catch (const InputError& e) {
      ++refused;
      ASSERT_EQ(e.file(), "flipped.vdb");
    } catch (...) {
      FAIL() << "a flip at byte " << at << " escaped as something else than InputError";
    }
    // The magic, the file format version and the offsets flag: always refused.
    if (at < 12 || at == 20) {
      ASSERT_FALSE(accepted) << "a flip in the header at byte " << at << " was accepted";
    }
  }
  // Most of the file is structure; what is accepted is values, names and the UUID.
  EXPECT_GT(refused, read);
  EXPECT_EQ(refused + read, int(bytes.size()));
}

void Put32(std::string& b, std::size_t at, std::uint32_t v) { std::memcpy(&b[at], &v, 4); }
void Put64(std::string& b, std::size_t at, std::int64_t v) { std::memcpy(&b[at], &v, 8); }
std::uint32_t Get32(const std::string& b, std::size_t at) {
  std::uint32_t v;
  std::memcpy(&v, &b[at], 4);
  return v;
}
std::int64_t Get64(const std::string& b, std::size_t at) {
  std::int64_t v;
  std::memcpy(&v, &b[at], 8);
  return v;
}

void ExpectRefused(const std::string& bytes, const std::string& reason_part) {
  try {
    ReadFieldsVdbBytes(bytes, "crafted.vdb");
    ADD_FAILURE() << "accepted; expected a refusal with '" << reason_part << "'";
  } catch (const InputError& e) {
    EXPECT_NE(e.reason().find(reason_part), std::string::npos) << e.what();
    EXPECT_EQ(e.file(), "crafted.vdb");
    EXPECT_FALSE(e.hint().empty());
  }
}

TEST(VdbValidator, HugeCountsAndBadOffsetsAreRefused) {
  // No file metadata: the metadata count is at byte 57 and the grid count at byte 61.
  Fields f = MakeFields(3);
  const std::string bytes = WriteBytes(f, {}, "plain.vdb");
  ASSERT_EQ(Get32(bytes, 57), 0u);
  ASSERT_EQ(Get32(bytes, 61), 6u);  // coverage, resolution, sigma_max, visible/0, 1, 2
  std::string b = bytes;
  Put32(b, 61, 1000000000);
  ExpectRefused(b, "grids");
  b = bytes;
  Put32(b, 61, 0xffffffffu);
  ExpectRefused(b, "-1 grids");
  b = bytes;
  Put32(b, 57, 0xffffffffu);
  ExpectRefused(b, "metadata entries cannot fit");
  b = bytes;
  Put32(b, 65, 0x7fffffffu);  // the first grid's name length
  ExpectRefused(b, "truncated: grid name");
  // The first descriptor's offsets, after its name, type and (empty) instance parent strings.
  const std::size_t offsets = 65 + 4 + 8 + 4 + 16 + 4;
  ASSERT_EQ(bytes.substr(69, 8), "coverage");
  ASSERT_EQ(Get64(bytes, offsets), std::int64_t(offsets + 24));
  for (int which = 0; which < 3; ++which)
    for (std::int64_t delta : {std::int64_t(-1), std::int64_t(1), std::int64_t(1) << 40}) {
      b = bytes;
      Put64(b, offsets + 8 * which, Get64(bytes, offsets + 8 * which) + delta);
      ExpectRefused(b, "");
    }
  b = bytes;
  Put64(b, offsets + 16, std::int64_t(bytes.size()) + 1);
  ExpectRefused(b, "do not fit the file");
  // The root node of the first grid: after the transform's type name and its 144 bytes, the buffer
  // count, the background, the tile count and the child count.
  const std::size_t map = bytes.find("UniformScaleTranslateMap");
  ASSERT_NE(map, std::string::npos);
  const std::size_t root = map + 24 + 144;
  ASSERT_EQ(Get32(bytes, root), 1u);
  const std::size_t tiles = root + 8, children = root + 12;
  ASSERT_EQ(Get32(bytes, tiles), 0u);
  ASSERT_EQ(Get32(bytes, children), 1u);
  b = bytes;
  Put32(b, root, 2);
  ExpectRefused(b, "buffer count");
  b = bytes;
  Put32(b, tiles, 0xffffffffu);
  ExpectRefused(b, "cannot fit");
  b = bytes;
  Put32(b, children, 100000);
  ExpectRefused(b, "cannot fit");
  b = bytes;
  Put32(b, children + 4, 8);  // the child's origin, not a multiple of 4096
  ExpectRefused(b, "not a multiple of 4096");
  b = bytes;
  Put32(b, children + 8, std::uint32_t(-4096));
  ExpectRefused(b, "not a multiple of 4096 in [0,");
  b = bytes;
  Put32(b, children + 4, 1u << 21);
  ExpectRefused(b, "not a multiple of 4096 in [0,");
}

// Every Blosc chunk of a file (found by its header: version 2 and a compressed size equal to the
// int64 length before it), damaged in each field the validator checks.
TEST(VdbValidator, DamagedBloscChunksAreRefused) {
  const std::string bytes = WriteBytes(MakeFields(3), {}, "blosc.vdb");
  std::vector<std::size_t> chunks;
  for (std::size_t at = 8; at + 24 < bytes.size(); ++at)
    if (bytes[at + 8] == 2 && Get64(bytes, at) > 16 &&
        Get64(bytes, at) == std::int64_t(Get32(bytes, at + 20)) &&
        std::size_t(Get64(bytes, at)) + at + 8 <= bytes.size())
      chunks.push_back(at);
  ASSERT_GT(chunks.size(), 10u);
  for (std::size_t at : chunks) {
    SCOPED_TRACE("chunk at byte " + std::to_string(at));
    const std::int64_t length = Get64(bytes, at);
    const std::uint32_t nbytes = Get32(bytes, at + 12);
    std::string b = bytes;
    Put32(b, at + 12, nbytes + 4);  // nbytes
    ExpectRefused(b, "decompresses to");
    b = bytes;
    Put32(b, at + 20, std::uint32_t(length + 1));  // cbytes
    ExpectRefused(b, "compressed bytes");
    b = bytes;
    Put32(b, at + 16, 0);  // blocksize
    ExpectRefused(b, "block size");
    b = bytes;
    b[at + 8] = 3;  // format version
    ExpectRefused(b, "format version");
    b = bytes;
    Put64(b, at, -std::int64_t(nbytes) - 64);  // raw values longer than the buffer
    ExpectRefused(b, "uncompressed chunk");
    // Garbage in the compressed stream: refused, or (when it still decompresses to the right
    // length) read with other values; never anything else.
    b = bytes;
    for (std::int64_t k = 16; k < length; ++k) b[at + 8 + k] = char(0xa5 ^ k);
    try {
      ReadFieldsVdbBytes(b, "garbage.vdb");
    } catch (const InputError&) {
    }
  }
}

// The delayed-load record OpenVDB adds to float grids: with more than 48 leaves its per-leaf mask
// and compressed sizes are Blosc chunks, checked once the tree has confirmed the leaf count.
TEST(VdbValidator, DelayedLoadRecordIsChecked) {
  InitializeOpenVdb();
  Fields f;
  Fields::Impl& g = f.impl();
  g.transform = LatticeTransform(0.05, openvdb::Vec3d(0, 0, 0));
  g.coverage = openvdb::Int32Grid::create(0);
  g.coverage->setName(kCoverageGrid);
  g.coverage->setTransform(g.transform);
  for (int i = 0; i < 64; ++i)
    for (int j = 0; j < 64; ++j)
      g.coverage->tree().setValueOn(openvdb::Coord(i, j, (i * j) % 8), (i + j) % 3);
  ASSERT_EQ(g.coverage->tree().leafCount(), 64u);
  const std::string bytes = WriteBytes(f, {}, "delayed.vdb");
  ASSERT_NO_THROW(ReadFieldsVdbBytes(bytes, "delayed.vdb"));
  // "file_delayed_load", its type "__delayedload", the value's size, the leaf count, the mask
  // chunk.
  const std::size_t name = bytes.find("file_delayed_load");
  ASSERT_NE(name, std::string::npos);
  const std::size_t type = name + 17;
  ASSERT_EQ(bytes.substr(type + 4, Get32(bytes, type)), "__delayedload");
  const std::size_t size = type + 4 + 13, count = size + 4, mask = count + 4;
  ASSERT_EQ(Get32(bytes, count), 64u);
  const std::uint32_t mask_bytes = Get32(bytes, mask);
  ASSERT_GT(mask_bytes, 16u);  // a Blosc chunk, not 64 raw bytes
  const std::size_t chunk = mask + 4, sizes = chunk + mask_bytes;
  ASSERT_EQ(Get32(bytes, chunk + 4), 128u);  // nbytes: one int8 per leaf, padded to 128
  std::string b = bytes;
  Put32(b, count, 63);  // the sizes chunk holds 64 int64 values, not 63
  ExpectRefused(b, "decompresses to 512 bytes, expected 504");
  b = bytes;
  Put32(b, chunk + 4, 129);
  ExpectRefused(b, "decompresses to 129 bytes");
  b = bytes;
  for (std::size_t k = 16 + 4; k < mask_bytes; ++k) b[chunk + k] = char(0x5a ^ k);
  ExpectRefused(b, "");
  b = bytes;
  const std::uint32_t sizes_bytes = Get32(bytes, sizes);
  ASSERT_GT(sizes_bytes, 16u);
  ASSERT_LT(sizes_bytes, 0xffffffffu);
  for (std::size_t k = 16 + 4; k < sizes_bytes; ++k) b[sizes + 4 + k] = char(0x33 ^ k);
  ExpectRefused(b, "");
  b = bytes;
  Put32(b, size, 12);  // the record is longer than its stated size
  ExpectRefused(b, "holds more than its 12 bytes");
  // A record of raw bytes (one leaf) that counts no leaf: it fits its size, the tree disagrees.
  std::string small = SmallFile();
  const std::size_t at = small.find("file_delayed_load") + 17 + 4 + 13 + 4;
  ASSERT_EQ(Get32(small, at), 1u);
  Put32(small, at, 0);
  ExpectRefused(small, "counts 0 leaves, the tree has 1");
}

TEST(VdbValidator, SpecialFilesAreRefused) {
  const fs::path dir = TempDir();
  auto refused = [](const std::string& path, const std::string& reason) {
    try {
      ReadFieldsVdb(path);
      ADD_FAILURE() << path << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
      EXPECT_EQ(e.file(), path);
    }
  };
  const fs::path fifo = dir / "fifo.vdb";
  fs::remove(fifo);
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  refused(fifo.string(), "not a regular file");  // and it did not wait for a writer
  refused("/dev/zero", "not a regular file");
  refused(dir.string(), "is a folder");
  const fs::path empty = dir / "empty.vdb";
  std::ofstream(empty).close();
  refused(empty.string(), "empty");
  refused((dir / "missing.vdb").string(), "cannot open");
  const fs::path text = dir / "text.vdb";
  std::ofstream(text) << "not a vdb file at all, just some text that is long enough";
  refused(text.string(), "not a VDB file");
  VdbLimits small;
  small.max_file_bytes = 100;
  const fs::path big = dir / "big.vdb";
  std::ofstream(big) << std::string(101, 'x');
  EXPECT_THROW(ReadVdbFileBytes(big.string(), small), InputError);
}

std::string WriteGrids(const openvdb::GridPtrVec& grids, const std::string& name,
                       std::uint32_t compression = 6) {
  const fs::path path = TempDir() / name;
  openvdb::io::File file(path.string());
  file.setCompression(compression);
  file.write(grids);
  file.close();
  return ReadBytes(path);
}

openvdb::FloatGrid::Ptr Float(const std::string& name, std::initializer_list<openvdb::Coord> on,
                              float value = 1) {
  auto g = openvdb::FloatGrid::create(0);
  g->setName(name);
  g->setTransform(LatticeTransform(0.05, openvdb::Vec3d(0, 0, 0)));
  for (const auto& c : on) g->tree().setValueOn(c, value);
  return g;
}

TEST(VdbValidator, BoundsAndLimitsAreEnforced) {
  InitializeOpenVdb();
  ASSERT_NO_THROW(ReadFieldsVdbBytes(
      WriteGrids({Float("coverage", {{0, 0, 0}, {100, 200, 300}})}, "ok.vdb"), "ok"));
  ExpectRefused(WriteGrids({Float("coverage", {{-1, 0, 0}})}, "negative.vdb"), "in [0, 1048576)");
  ExpectRefused(WriteGrids({Float("coverage", {{0, 1 << 21, 0}})}, "far.vdb"), "in [0, 1048576)");
  ExpectRefused(WriteGrids({Float("coverage", {{0, 0, 0}, {20000, 20000, 0}})}, "face.vdb"),
                "over the limit");
  auto tile = Float("coverage", {});
  tile->tree().addTile(3, openvdb::Coord(0), 1.0f, true);  // a root tile of 4096^3 voxels
  ExpectRefused(WriteGrids({tile}, "tile.vdb"), "active voxels");
  // Limits are parameters.
  const std::string two =
      WriteGrids({Float("coverage", {{0, 0, 0}}), Float("resolution", {{0, 0, 0}})}, "two.vdb");
  VdbLimits limits;
  limits.max_grids = 1;
  EXPECT_THROW(CheckVdbBytes(two, "two.vdb", limits), InputError);
  limits = VdbLimits();
  limits.max_active_voxels = 0;
  EXPECT_THROW(CheckVdbBytes(two, "two.vdb", limits), InputError);
  EXPECT_NO_THROW(CheckVdbBytes(two, "two.vdb"));
}

TEST(VdbValidator, TransformsOtherThanScaleAndTranslationAreRefused) {
  InitializeOpenVdb();
  auto stretched = Float("coverage", {{0, 0, 0}});
  stretched->setTransform(openvdb::math::Transform::createLinearTransform(
      openvdb::math::scale<openvdb::Mat4R>(openvdb::Vec3d(1, 2, 1))));
  ExpectRefused(WriteGrids({stretched}, "stretched.vdb"), "not the same along the three axes");
  auto rotated = Float("coverage", {{0, 0, 0}});
  openvdb::Mat4R m = openvdb::math::rotation<openvdb::Mat4R>(openvdb::math::Z_AXIS, 0.3);
  rotated->setTransform(openvdb::math::Transform::createLinearTransform(m));
  ExpectRefused(WriteGrids({rotated}, "rotated.vdb"), "is not a scale and a translation");
  auto a = Float("coverage", {{0, 0, 0}});
  auto b = Float("resolution", {{0, 0, 0}});
  b->setTransform(LatticeTransform(0.05, openvdb::Vec3d(0.5, 0, 0)));
  ExpectRefused(WriteGrids({a, b}, "two_transforms.vdb"), "different transforms");
}

TEST(VdbValidator, GridTypesAndValuesAreChecked) {
  InitializeOpenVdb();
  ExpectRefused(WriteGrids({Float("coverage", {{0, 0, 0}}, 0.5f)}, "half.vdb"),
                "not a whole number");
  ExpectRefused(WriteGrids({Float("coverage", {{0, 0, 0}}, 10001.0f)}, "many.vdb"),
                "not a whole number");
  ExpectRefused(WriteGrids({Float("coverage", {{0, 0, 0}}, -1.0f)}, "minus.vdb"),
                "not a whole number");
  ExpectRefused(WriteGrids({Float("resolution", {{0, 0, 0}}, std::nanf(""))}, "nan.vdb"),
                "non-finite");
  auto earlier = openvdb::Int32Grid::create(0);  // the earlier layout is held to the same range
  earlier->setName("coverage");
  earlier->tree().setValueOn(openvdb::Coord(1, 1, 1), -3);
  ExpectRefused(WriteGrids({earlier}, "negative_int.vdb"), "not a whole number");
  auto inf = Float("sigma_max", {{0, 0, 0}});
  inf->tree().setValueOff(openvdb::Coord(1, 0, 0), INFINITY);  // inactive values count too
  ExpectRefused(WriteGrids({inf}, "inf.vdb"), "non-finite");
  auto boolean = openvdb::BoolGrid::create(false);
  boolean->setName("coverage");
  ExpectRefused(WriteGrids({boolean}, "bool.vdb"), "expected a FloatGrid");
  auto visible = openvdb::BoolGrid::create(false);
  visible->setName("visible/a");
  visible->tree().setValueOn(openvdb::Coord(0), true);
  ExpectRefused(WriteGrids({Float("coverage", {{0, 0, 0}}), visible}, "no_index.vdb"),
                "camera_index");
  visible->insertMeta("camera_index", openvdb::Int64Metadata(3));
  auto twin = visible->deepCopy();
  twin->setName("visible/b");
  ExpectRefused(WriteGrids({visible, twin}, "twins.vdb"), "camera_index");
  auto tiled = openvdb::BoolGrid::create(false);
  tiled->setName("visible/c");
  tiled->insertMeta("camera_index", openvdb::Int64Metadata(0));
  tiled->tree().addTile(1, openvdb::Coord(0), true, true);
  ExpectRefused(WriteGrids({tiled}, "tiled.vdb"), "active tiles");
  auto old = openvdb::Int64Grid::create(0);
  old->setName("cameras");
  ExpectRefused(WriteGrids({old, visible}, "both.vdb"), "both");
  auto vec = openvdb::Vec3SGrid::create();
  vec->setName("resolution");
  ExpectRefused(WriteGrids({vec}, "vec.vdb"), "pandora does not read");
  auto half = Float("resolution", {{0, 0, 0}});
  half->setSaveFloatAsHalf(true);
  ExpectRefused(WriteGrids({half}, "halffloat.vdb"), "");
  ExpectRefused(WriteGrids({Float("something_else", {{0, 0, 0}})}, "unknown.vdb"),
                "none of Pandora's field grids");
  // Unknown grids of known types are checked and ignored.
  const Fields f = ReadFieldsVdbBytes(
      WriteGrids({Float("resolution", {{1, 2, 3}}, 2.5f), Float("extra", {{0, 0, 0}})},
                 "extra.vdb"),
      "extra");
  ASSERT_TRUE(f.impl().Float("resolution"));
  EXPECT_FALSE(f.impl().Float("extra"));
  EXPECT_EQ(f.impl().Float("resolution")->tree().getValue(openvdb::Coord(1, 2, 3)), 2.5f);
  EXPECT_EQ(f.lattice.dims, Eigen::Vector3i(2, 3, 4));
}

TEST(VdbValidator, ReportsWhatItSaw) {
  const std::string bytes = WriteBytes(MakeFields(), RigMetadata(64), "quick.vdb");
  const VdbFileInfo info = CheckVdbBytes(bytes, "quick.vdb");
  ASSERT_EQ(info.grids.size(), 3u + 64u);
  EXPECT_EQ(info.strings.at("rig_name"), "many");
  const VdbGridInfo& coverage = info.grids[0];
  EXPECT_EQ(coverage.name, "coverage");
  EXPECT_EQ(coverage.tree_type, "Tree_float_5_4_3");
  EXPECT_EQ(coverage.voxel_size, 0.05);
  EXPECT_EQ(coverage.translation, (std::array<double, 3>{-0.475, -0.475, 0.025}));
  EXPECT_EQ(coverage.active_voxels, std::int64_t(MakeFields().impl().coverage->activeVoxelCount()));
  EXPECT_EQ(coverage.active_tiles, 1);
  EXPECT_EQ(coverage.active_min, (std::array<std::int64_t, 3>{0, 0, 0}));
  EXPECT_EQ(coverage.active_max, (std::array<std::int64_t, 3>{31, 11, 8}));
}

// The provenance check against tests/data/minimal.json (the tests run in the source folder).
class Provenance : public ::testing::Test {
 protected:
  void SetUp() override {
    scene = LoadScene("tests/data/minimal.json");
    rig = scene.rigs[0];
    p.scene_sha256 = scene.sha256;
    p.rig_name = rig.name;
    p.rig_json = RigToJson(rig).dump();
    lattice.voxel_size = 0.05;
    lattice.origin = Vec3(-0.475, -0.475, 0.025);
    lattice.dims = Eigen::Vector3i(20, 20, 12);
  }
  Scene scene;
  Rig rig;
  FieldsProvenance p;
  VoxelLattice lattice;
};

TEST_F(Provenance, MatchingFieldsGiveNoWarning) {
  EXPECT_TRUE(CheckFieldsProvenance(p, lattice, scene, rig, "f.vdb").empty());
}

TEST_F(Provenance, AnotherSceneVersionWarns) {
  p.scene_sha256 = std::string(64, '0');
  const auto w = CheckFieldsProvenance(p, lattice, scene, rig, "f.vdb");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("different version of the scene file"), std::string::npos) << w[0];
}

TEST_F(Provenance, AnotherRigIsRefusedWithAHintNamingRig) {
  p.rig_name = "ring";
  try {
    CheckFieldsProvenance(p, lattice, scene, rig, "f.vdb");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "f.vdb");
    EXPECT_NE(e.reason().find("'ring'"), std::string::npos) << e.what();
    EXPECT_NE(e.hint().find("{rig} ring"), std::string::npos) << e.what();
  }
}

TEST_F(Provenance, ChangedCamerasWarnNamingThem) {
  Rig moved = rig;
  moved.cameras[1].world_from_camera.translation() += Vec3(0.01, 0, 0);
  auto w = CheckFieldsProvenance(p, lattice, scene, moved, "f.vdb");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("changed 'b'"), std::string::npos) << w[0];
  Rig more = rig;
  more.cameras.push_back(rig.cameras[0]);
  more.cameras.back().id = "c";
  more.cameras.erase(more.cameras.begin());
  w = CheckFieldsProvenance(p, lattice, scene, more, "f.vdb");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("added 'c'; removed 'a'"), std::string::npos) << w[0];
  Rig swapped = rig;
  std::swap(swapped.cameras[0], swapped.cameras[1]);
  w = CheckFieldsProvenance(p, lattice, scene, swapped, "f.vdb");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("another order"), std::string::npos) << w[0];
  // On or off alone (--disable) is said so, both ways; with a move too it is a change.
  Rig off = rig;
  off.cameras[0].enabled = false;
  w = CheckFieldsProvenance(p, lattice, scene, off, "f.vdb");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("off here, on for the fields: 'a'"), std::string::npos) << w[0];
  off.cameras[0].world_from_camera.translation() += Vec3(0.01, 0, 0);
  w = CheckFieldsProvenance(p, lattice, scene, off, "f.vdb");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("changed 'a'"), std::string::npos) << w[0];
}

TEST_F(Provenance, ALatticeOutsideTheRegionIsRefused) {
  VoxelLattice shifted = lattice;
  shifted.origin.x() += 0.05;  // one voxel: tolerated
  EXPECT_NO_THROW(CheckFieldsProvenance(p, shifted, scene, rig, "f.vdb"));
  shifted.origin.x() += 0.06;
  EXPECT_THROW(CheckFieldsProvenance(p, shifted, scene, rig, "f.vdb"), InputError);
  VoxelLattice longer = lattice;
  longer.dims.z() += 3;
  EXPECT_THROW(CheckFieldsProvenance(p, longer, scene, rig, "f.vdb"), InputError);
  VoxelLattice below = lattice;
  below.origin.z() = -0.2;
  EXPECT_THROW(CheckFieldsProvenance(p, below, scene, rig, "f.vdb"), InputError);
}

TEST_F(Provenance, FilesWithoutProvenanceWarn) {
  const auto w = CheckFieldsProvenance(FieldsProvenance{}, lattice, scene, rig, "f.vdb");
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("says nothing of the scene"), std::string::npos) << w[0];
}

}  // namespace
}  // namespace pandora
