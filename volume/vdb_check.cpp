// Validation of .vdb bytes before OpenVDB parses them. The layout below is OpenVDB 10's (file
// format version 224), read from its sources; the comments name the function that reads each part.
#include "volume/vdb_check.h"

#include <blosc.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "analysis/util/error.h"

namespace pandora {
namespace {

constexpr char kDamagedHint[] =
    "the file is truncated or damaged, or not a fields.vdb written by `pandora analyze`; run "
    "`pandora analyze` again to rewrite it";

// OpenVDB's constants (openvdb/version.h, io/Compression.h, c-blosc's blosc.h).
constexpr std::int64_t kVdbMagic = 0x56444220;
constexpr std::uint32_t kFileVersion = 224;  // OPENVDB_FILE_VERSION of OpenVDB 6 to 12
constexpr std::uint32_t kCompressZip = 0x1, kCompressActiveMask = 0x2, kCompressBlosc = 0x4;
constexpr int kBloscHeader = 16;        // BLOSC_MAX_OVERHEAD / BLOSC_MIN_HEADER_LENGTH
constexpr int kBloscVersionFormat = 2;  // BLOSC_VERSION_FORMAT of c-blosc 1.x
constexpr int kBloscMemcpyed = 0x2, kBloscReservedFlag = 0x08, kBloscDontSplit = 0x10;
constexpr std::int64_t kBloscMaxBlocksize = std::int64_t(1) << 28;  // generous (blosc: 2^31 - 16)
constexpr std::uint64_t kBloscPadBytes = 128;  // points/StreamCompression.cc pads shorter arrays

// The standard tree: root -> InternalNode<5> -> InternalNode<4> -> LeafNode<3>.
constexpr int kLog2Leaf = 3, kLog2Int1 = 4, kLog2Int2 = 5;
constexpr int kLeafDim = 1 << kLog2Leaf;           // 8
constexpr int kInt1Dim = kLeafDim << kLog2Int1;    // 128
constexpr int kInt2Dim = kInt1Dim << kLog2Int2;    // 4096
constexpr int kLeafValues = 1 << (3 * kLog2Leaf);  // 512
constexpr int kInt2Values = 1 << (3 * kLog2Int2);  // 32768

struct TreeKind {
  const char* name;
  int value_size;
  bool is_bool;
};
constexpr TreeKind kTreeKinds[] = {{"Tree_float_5_4_3", 4, false},
                                   {"Tree_int32_5_4_3", 4, false},
                                   {"Tree_int64_5_4_3", 8, false},
                                   {"Tree_bool_5_4_3", 1, true}};

std::string Quote(std::string_view s) {
  std::string out = "'";
  for (unsigned char c : s.substr(0, 80)) {
    if (c >= 0x20 && c < 0x7f) {
      out += char(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  if (s.size() > 80) out += "...";
  return out + "'";
}

// A cursor over the bytes that never reads past their end: every read names what it reads, and
// running out is an InputError saying what was cut off and where.
class Cursor {
 public:
  Cursor(std::string_view bytes, const std::string& path) : bytes_(bytes), path_(path) {}

  std::size_t pos() const { return pos_; }
  std::size_t left() const { return bytes_.size() - pos_; }
  std::size_t size() const { return bytes_.size(); }
  const std::string& path() const { return path_; }

  [[noreturn]] void Fail(const std::string& reason, std::size_t at) const {
    throw InputError(path_, "",
                     "invalid VDB file: " + reason + " (byte " + std::to_string(at) + ")",
                     kDamagedHint);
  }
  [[noreturn]] void Fail(const std::string& reason) const { Fail(reason, pos_); }

  void Need(std::uint64_t n, const std::string& what) const {
    if (n > left())
      Fail("truncated: " + what + " needs " + std::to_string(n) + " bytes, " +
           std::to_string(left()) + " left");
  }
  std::string_view Take(std::uint64_t n, const std::string& what) {
    Need(n, what);
    std::string_view v = bytes_.substr(pos_, n);
    pos_ += n;
    return v;
  }
  void Skip(std::uint64_t n, const std::string& what) { Take(n, what); }
  void Seek(std::size_t at) { pos_ = at; }

  template <typename T>
  T Get(const std::string& what) {
    T v;
    std::memcpy(&v, Take(sizeof(T), what).data(), sizeof(T));
    return v;
  }
  std::uint8_t U8(const std::string& what) { return Get<std::uint8_t>(what); }
  std::uint32_t U32(const std::string& what) { return Get<std::uint32_t>(what); }
  std::int32_t I32(const std::string& what) { return Get<std::int32_t>(what); }
  std::int64_t I64(const std::string& what) { return Get<std::int64_t>(what); }
  double F64(const std::string& what) { return Get<double>(what); }
  bool Bool(const std::string& what) {
    const std::size_t at = pos_;
    const std::uint8_t b = U8(what);
    if (b > 1) Fail(what + " is " + std::to_string(b) + ", not a bool", at);
    return b != 0;
  }
  // util/Name.h readString: a uint32 length, then the bytes.
  std::string String(const std::string& what) {
    const std::uint32_t n = U32(what + " length");
    return std::string(Take(n, what));
  }

 private:
  std::string_view bytes_;
  const std::string& path_;
  std::size_t pos_ = 0;
};

// A node mask of `bits` bits as OpenVDB stores it (util/NodeMasks.h: 64-bit words, bit n of word
// n / 64, little-endian).
struct Mask {
  const unsigned char* data = nullptr;
  int bits = 0;
  bool On(int n) const { return (data[n >> 3] >> (n & 7)) & 1; }
  int Count() const {
    int c = 0;
    for (int w = 0; w < bits / 64; ++w) {
      std::uint64_t word;
      std::memcpy(&word, data + 8 * w, 8);
      c += __builtin_popcountll(word);
    }
    return c;
  }
  bool Intersects(const Mask& o) const {
    for (int i = 0; i < bits / 8; ++i)
      if (data[i] & o.data[i]) return true;
    return false;
  }
  bool Equals(const Mask& o) const { return std::memcmp(data, o.data, bits / 8) == 0; }
};

Mask ReadMask(Cursor& c, int bits, const std::string& what) {
  return Mask{reinterpret_cast<const unsigned char*>(c.Take(bits / 8, what).data()), bits};
}

using Coord = std::array<std::int64_t, 3>;

// Per-grid state of the walk.
struct GridWalk {
  const TreeKind* kind = nullptr;
  std::uint32_t compression = 0;
  const VdbLimits* limits = nullptr;
  VdbGridInfo* info = nullptr;
  std::string name;  // quoted, for messages
};

void AddActiveBox(GridWalk& g, const Coord& lo, std::int64_t dim, std::int64_t voxels) {
  VdbGridInfo& info = *g.info;
  for (int a = 0; a < 3; ++a) {
    info.active_min[a] = info.empty ? lo[a] : std::min(info.active_min[a], lo[a]);
    info.active_max[a] =
        info.empty ? lo[a] + dim - 1 : std::max(info.active_max[a], lo[a] + dim - 1);
  }
  info.empty = false;
  info.active_voxels += voxels;
  ++info.active_tiles;
}

// Bytes decompressed by the validator, reused from chunk to chunk.
std::vector<char>& Scratch(std::size_t bytes) {
  thread_local std::vector<char> scratch;
  if (scratch.size() < bytes) scratch.resize(bytes);
  return scratch;
}

// c-blosc 1.x chunk of `length` bytes that must decompress to `expected` bytes (or to the 128-byte
// padding of points/StreamCompression.cc when `pad_small`): the 16-byte header (version, flags,
// nbytes, blocksize, cbytes) and, unless the chunk is a plain copy, the block start table and every
// split's length, as blosc_run_decompression_with_context and blosc_d read them. Then, when
// `decompress`, the chunk is decompressed: OpenVDB throws on a chunk that fails, and some of its
// readers leak the node they were filling when it does. Returns the decompressed bytes (empty when
// not decompressed).
std::string_view CheckBlosc(Cursor& c, std::uint64_t length, std::uint64_t expected, bool pad_small,
                            const std::string& what, bool decompress = true) {
  const std::size_t start = c.pos();
  if (length < std::uint64_t(kBloscHeader))
    c.Fail(what + ": a Blosc chunk of " + std::to_string(length) +
           " bytes is shorter than its header");
  const std::string_view chunk = c.Take(length, what);
  const auto* b = reinterpret_cast<const unsigned char*>(chunk.data());
  auto i32 = [&](std::size_t at) {
    std::int32_t v;
    std::memcpy(&v, b + at, 4);
    return v;
  };
  const int version = b[0], flags = b[2], typesize = b[3];
  const std::int64_t nbytes = i32(4), blocksize = i32(8), cbytes = i32(12);
  if (version != kBloscVersionFormat)
    c.Fail(what + ": Blosc format version " + std::to_string(version) + ", expected 2", start);
  if (flags & kBloscReservedFlag) c.Fail(what + ": Blosc flags from a future version", start);
  if (cbytes != std::int64_t(length))
    c.Fail(what + ": the Blosc header says " + std::to_string(cbytes) +
               " compressed bytes, the chunk has " + std::to_string(length),
           start);
  const bool padded =
      pad_small && expected < kBloscPadBytes && nbytes == std::int64_t(kBloscPadBytes);
  if (nbytes != std::int64_t(expected) && !padded)
    c.Fail(what + ": the Blosc chunk decompresses to " + std::to_string(nbytes) +
               " bytes, expected " + std::to_string(expected),
           start);
  if (nbytes == 0) return {};  // blosc returns at once
  if (typesize < 1) c.Fail(what + ": Blosc type size 0", start);
  if (blocksize <= 0 || blocksize > nbytes || blocksize > kBloscMaxBlocksize)
    c.Fail(what + ": Blosc block size " + std::to_string(blocksize) + " for " +
               std::to_string(nbytes) + " bytes",
           start);
  const std::int64_t nblocks = (nbytes + blocksize - 1) / blocksize;
  const std::int64_t leftover = nbytes % blocksize;
  if (flags & kBloscMemcpyed) {
    if (cbytes != nbytes + kBloscHeader)
      c.Fail(what + ": a copied Blosc chunk must be its data plus the header", start);
  } else {
    if (nblocks > (cbytes - kBloscHeader) / 4)
      c.Fail(what + ": the Blosc block table does not fit in the chunk", start);
    for (std::int64_t j = 0; j < nblocks; ++j) {
      std::int64_t offset = i32(kBloscHeader + 4 * j);
      const bool last_partial = j == nblocks - 1 && leftover > 0;
      const std::int64_t bsize = last_partial ? leftover : blocksize;
      const bool split =
          !(flags & kBloscDontSplit) && typesize <= 16 && bsize / typesize >= 128 && !last_partial;
      const int nsplits = split ? typesize : 1;
      for (int s = 0; s < nsplits; ++s) {
        if (offset < kBloscHeader + 4 * nblocks || offset > cbytes - 4)
          c.Fail(what + ": Blosc block " + std::to_string(j) + " starts outside the chunk", start);
        const std::int64_t split_bytes = i32(offset);
        offset += 4;
        if (split_bytes < 0 || split_bytes > cbytes - offset)
          c.Fail(what + ": Blosc block " + std::to_string(j) + " runs past the chunk", start);
        offset += split_bytes;
      }
    }
  }
  if (!decompress) return {};
  std::vector<char>& out = Scratch(std::size_t(nbytes));
  const int got = blosc_decompress_ctx(chunk.data(), out.data(), std::size_t(nbytes), 1);
  if (got != nbytes) c.Fail(what + ": the Blosc chunk does not decompress", start);
  return std::string_view(out.data(), std::size_t(nbytes));
}

void CheckBools(const Cursor& c, std::string_view values, const std::string& what, std::size_t at) {
  for (char v : values)
    if (std::uint8_t(v) > 1) c.Fail(what + ": a bool value that is neither 0 nor 1", at);
}

// io::readData of `count` values of `value_size` bytes under `compression`: a Blosc or zip chunk
// behind an int64 size (negative for raw bytes), or the raw values. Compressed chunks are
// decompressed to check that they give exactly the bytes expected.
void CheckData(Cursor& c, const GridWalk& g, std::uint64_t count, const std::string& what) {
  const std::uint64_t expected = count * g.kind->value_size;
  const std::size_t at = c.pos();
  if (!(g.compression & (kCompressBlosc | kCompressZip))) {
    const std::string_view raw = c.Take(expected, what);
    if (g.kind->is_bool) CheckBools(c, raw, what, at);
    return;
  }
  const std::int64_t n = c.I64(what + " size");
  if (n <= 0) {
    // io::bloscFromStream / unzipFromStream read -n bytes into the buffer *before* comparing
    // -n with its size: a mismatch would overrun the heap.
    if (n < -(std::int64_t(1) << 40) || std::uint64_t(-n) != expected)
      c.Fail(what + ": an uncompressed chunk of " +
                 (n < -(std::int64_t(1) << 40) ? std::string("over 2^40") : std::to_string(-n)) +
                 " bytes, expected " + std::to_string(expected),
             at);
    const std::string_view raw = c.Take(expected, what);
    if (g.kind->is_bool) CheckBools(c, raw, what, at);
    return;
  }
  if (std::uint64_t(n) > c.left())
    c.Fail("truncated: " + what + " needs " + std::to_string(n) + " bytes, " +
           std::to_string(c.left()) + " left");
  if (g.compression & kCompressBlosc) {
    const std::string_view values = CheckBlosc(c, std::uint64_t(n), expected, false, what);
    if (g.kind->is_bool) CheckBools(c, values, what, at);
    return;
  }
  // io::zipToStream writes a zip chunk only when it is shorter than the raw values.
  if (std::uint64_t(n) >= expected)
    c.Fail(what + ": a zip chunk of " + std::to_string(n) + " bytes for " +
               std::to_string(expected) + " bytes of values",
           at);
  const std::string_view chunk = c.Take(std::uint64_t(n), what);
  std::vector<char>& out = Scratch(expected);
  uLongf got = uLongf(expected);
  if (uncompress(reinterpret_cast<Bytef*>(out.data()), &got,
                 reinterpret_cast<const Bytef*>(chunk.data()), uLong(n)) != Z_OK ||
      got != expected)
    c.Fail(what + ": the zip chunk does not decompress to " + std::to_string(expected) + " bytes",
           at);
  if (g.kind->is_bool) CheckBools(c, std::string_view(out.data(), expected), what, at);
}

// io::readCompressedValues for a node of `count` values with value mask `mask`: the mask
// compression byte, up to two inactive values, the selection mask, then the (active) values.
void CheckCompressedValues(Cursor& c, const GridWalk& g, int count, const Mask& mask,
                           const std::string& what) {
  const std::size_t at = c.pos();
  const int meta = c.U8(what + " compression byte");
  if (meta > 6) c.Fail(what + ": mask compression code " + std::to_string(meta) + " (0 to 6)", at);
  const int value_size = g.kind->value_size;
  auto value = [&](const std::string& which) {
    if (g.kind->is_bool)
      c.Bool(what + " " + which);
    else
      c.Skip(value_size, what + " " + which);
  };
  if (meta == 2 || meta == 4 || meta == 5) value("inactive value");
  if (meta == 5) value("second inactive value");
  if (meta == 3 || meta == 4 || meta == 5) c.Skip(count / 8, what + " selection mask");
  std::uint64_t stored = count;
  if ((g.compression & kCompressActiveMask) && meta != 6) stored = mask.Count();
  CheckData(c, g, stored, what + " values");
}

std::string CoordText(const Coord& o) {
  return "(" + std::to_string(o[0]) + ", " + std::to_string(o[1]) + ", " + std::to_string(o[2]) +
         ")";
}

// Offset n of a node of 2^log2 children per axis -> child origin
// (InternalNode::offsetToLocalCoord).
Coord ChildOrigin(const Coord& origin, int n, int log2, int child_dim) {
  const int x = n >> (2 * log2), y = (n >> log2) & ((1 << log2) - 1), z = n & ((1 << log2) - 1);
  return {origin[0] + std::int64_t(x) * child_dim, origin[1] + std::int64_t(y) * child_dim,
          origin[2] + std::int64_t(z) * child_dim};
}

// Walks one leaf's buffer (LeafNode::readBuffers, LeafNodeBool::readBuffers) against its topology.
void CheckLeafBuffer(Cursor& buf, const GridWalk& g, const Coord& origin, const Mask& topo_mask) {
  const std::string what = "grid " + g.name + " leaf " + CoordText(origin);
  const std::size_t at = buf.pos();
  const Mask mask = ReadMask(buf, kLeafValues, what + " buffer mask");
  if (!mask.Equals(topo_mask))
    buf.Fail(what + ": the buffer's value mask differs from the topology's", at);
  if (g.kind->is_bool) {
    const std::size_t o_at = buf.pos();
    for (int a = 0; a < 3; ++a)
      if (buf.I32(what + " origin") != origin[a])
        buf.Fail(what + ": the stored origin differs from the leaf's place in the tree", o_at);
    buf.Skip(kLeafValues / 8, what + " values");
    return;
  }
  CheckCompressedValues(buf, g, kLeafValues, mask, what);
}

// Active voxels of a leaf mask: count and index box.
void AddLeafVoxels(GridWalk& g, const Coord& origin, const Mask& mask) {
  const int n = mask.Count();
  if (n == 0) return;
  Coord lo{kLeafDim, kLeafDim, kLeafDim}, hi{-1, -1, -1};
  for (int i = 0; i < kLeafValues; ++i) {
    if (!mask.On(i)) continue;
    const int p[3] = {i >> 6, (i >> 3) & 7, i & 7};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min<std::int64_t>(lo[a], p[a]);
      hi[a] = std::max<std::int64_t>(hi[a], p[a]);
    }
  }
  VdbGridInfo& info = *g.info;
  for (int a = 0; a < 3; ++a) {
    const std::int64_t l = origin[a] + lo[a], h = origin[a] + hi[a];
    info.active_min[a] = info.empty ? l : std::min(info.active_min[a], l);
    info.active_max[a] = info.empty ? h : std::max(info.active_max[a], h);
  }
  info.empty = false;
  info.active_voxels += n;
}

void CheckActiveLimit(const Cursor& c, const GridWalk& g) {
  if (g.info->active_voxels > g.limits->max_active_voxels)
    c.Fail("grid " + g.name + " has more than " + std::to_string(g.limits->max_active_voxels) +
           " active voxels");
}

// InternalNode::readTopology for the node at `origin` of 2^log2 children per axis; `buf` walks the
// leaf buffers in the same order (the tree's buffers follow the same depth-first order).
void CheckInternal(Cursor& c, Cursor& buf, GridWalk& g, const Coord& origin, int log2) {
  const int values = 1 << (3 * log2);
  const int child_dim = log2 == kLog2Int2 ? kInt1Dim : kLeafDim;
  const std::string what = "grid " + g.name + " node " + CoordText(origin);
  const std::size_t at = c.pos();
  const Mask child = ReadMask(c, values, what + " child mask");
  const Mask value = ReadMask(c, values, what + " value mask");
  if (child.Intersects(value)) c.Fail(what + ": a child and an active tile at the same place", at);
  CheckCompressedValues(c, g, values, value, what + " tile values");
  // Active tiles.
  const std::int64_t tile_voxels = std::int64_t(child_dim) * child_dim * child_dim;
  for (int n = 0; n < values; ++n)
    if (value.On(n))
      AddActiveBox(g, ChildOrigin(origin, n, log2, child_dim), child_dim, tile_voxels);
  CheckActiveLimit(c, g);
  for (int n = 0; n < values; ++n) {
    if (!child.On(n)) continue;
    const Coord o = ChildOrigin(origin, n, log2, child_dim);
    if (log2 == kLog2Int2) {
      CheckInternal(c, buf, g, o, kLog2Int1);
    } else {
      const Mask leaf =
          ReadMask(c, kLeafValues, "grid " + g.name + " leaf " + CoordText(o) + " mask");
      ++g.info->leaf_count;
      AddLeafVoxels(g, o, leaf);
      CheckLeafBuffer(buf, g, o, leaf);
    }
  }
  CheckActiveLimit(c, g);
}

// RootNode::readTopology (current format): background, tile and child counts, the tiles, then
// each child's topology; `buf` starts at the grid's buffers.
void CheckTree(Cursor& c, Cursor& buf, GridWalk& g) {
  const std::string what = "grid " + g.name;
  const std::size_t at = c.pos();
  if (c.I32(what + " buffer count") != 1) c.Fail(what + ": a buffer count other than 1", at);
  if (g.kind->is_bool)
    c.Bool(what + " background");
  else
    c.Skip(g.kind->value_size, what + " background");
  const std::uint32_t tiles = c.U32(what + " root tile count");
  const std::uint32_t children = c.U32(what + " root child count");
  const std::uint64_t tile_bytes = 12 + g.kind->value_size + 1;
  // Each child needs its two masks at least: bounds the counts by the bytes left.
  if (std::uint64_t(tiles) * tile_bytes + std::uint64_t(children) * (12 + 2 * kInt2Values / 8) >
      c.left())
    c.Fail(what + ": " + std::to_string(tiles) + " root tiles and " + std::to_string(children) +
               " children cannot fit in the " + std::to_string(c.left()) + " bytes left",
           at);
  auto read_key = [&](const std::string& kind) {
    const std::size_t key_at = c.pos();
    Coord o;
    for (int a = 0; a < 3; ++a) o[a] = c.I32(what + " root " + kind + " origin");
    for (int a = 0; a < 3; ++a)
      if (o[a] % kInt2Dim != 0 || o[a] < 0 || o[a] >= g.limits->max_index)
        c.Fail(what + ": root " + kind + " origin " + CoordText(o) +
                   " is not a multiple of 4096 in [0, " + std::to_string(g.limits->max_index) + ")",
               key_at);
    return std::make_pair(o, key_at);
  };
  std::vector<Coord> keys;
  Coord previous{-1, -1, -1};
  for (std::uint32_t i = 0; i < tiles; ++i) {
    const auto [o, key_at] = read_key("tile");
    if (i > 0 && !(previous < o)) c.Fail(what + ": root tiles out of order or repeated", key_at);
    previous = o;
    keys.push_back(o);
    if (g.kind->is_bool)
      c.Bool(what + " root tile value");
    else
      c.Skip(g.kind->value_size, what + " root tile value");
    if (c.Bool(what + " root tile state"))
      AddActiveBox(g, o, kInt2Dim, std::int64_t(kInt2Dim) * kInt2Dim * kInt2Dim);
    CheckActiveLimit(c, g);
  }
  for (std::uint32_t i = 0; i < children; ++i) {
    const auto [o, key_at] = read_key("child");
    if (i > 0 && !(previous < o)) c.Fail(what + ": root children out of order or repeated", key_at);
    if (std::binary_search(keys.begin(), keys.end(), o))
      c.Fail(what + ": a root child and a root tile at the same place", key_at);
    previous = o;
    CheckInternal(c, buf, g, o, kLog2Int2);
  }
}

// Metadata::read of the registered types OpenVDB writes (TypedMetadata reads sizeof(T) bytes
// whatever the stored size says, so the size must be exact), and DelayedLoadMetadata::readValue.
// The delayed-load record of a grid: its leaf count and its Blosc chunks, decompressed only once
// the tree has shown that count right (the count sizes what they decompress to).
struct DelayedLoad {
  std::int64_t leaves = -1;
  struct Chunk {
    std::size_t pos;
    std::uint64_t length, expected;
    std::string what;
  };
  std::vector<Chunk> chunks;
};

void CheckMetaMap(Cursor& c, const std::string& owner, std::map<std::string, std::string>* strings,
                  std::map<std::string, std::int64_t>* integers, DelayedLoad* delayed) {
  const std::size_t at = c.pos();
  const std::uint32_t count = c.U32(owner + " metadata count");
  if (std::uint64_t(count) * 12 > c.left())
    c.Fail(owner + ": " + std::to_string(count) + " metadata entries cannot fit in the " +
               std::to_string(c.left()) + " bytes left",
           at);
  static const std::map<std::string, std::uint32_t> kFixed{
      {"bool", 1},   {"int32", 4},  {"int64", 8},  {"float", 4},
      {"double", 8}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}};
  std::set<std::string> seen;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::size_t entry_at = c.pos();
    const std::string name = c.String(owner + " metadata name");
    if (name.empty()) c.Fail(owner + ": a metadata entry without a name", entry_at);
    if (!seen.insert(name).second) c.Fail(owner + ": metadata " + Quote(name) + " twice", entry_at);
    const std::string type = c.String(owner + " metadata type");
    const std::uint32_t size = c.U32(owner + " metadata " + Quote(name) + " size");
    const std::string what = owner + " metadata " + Quote(name);
    c.Need(size, what);
    const std::size_t value_at = c.pos();
    if (type == "string") {
      const std::string value(c.Take(size, what));
      if (strings) (*strings)[name] = value;
    } else if (auto it = kFixed.find(type); it != kFixed.end()) {
      if (size != it->second)
        c.Fail(what + " of type " + type + " has " + std::to_string(size) + " bytes, expected " +
                   std::to_string(it->second),
               value_at);
      if (type == "bool") {
        const bool v = c.Bool(what);
        // Grid::saveFloatAsHalf() reads this entry after the descriptor: half floats would change
        // every value size the walk assumes.
        if (name == "is_saved_as_half_float" && v)
          c.Fail(what + ": half-float grids are not read", value_at);
      } else if (type == "int32") {
        const std::int32_t v = c.I32(what);
        if (integers) (*integers)[name] = v;
      } else if (type == "int64") {
        const std::int64_t v = c.I64(what);
        if (integers) (*integers)[name] = v;
      } else {
        c.Skip(size, what);
      }
    } else if (type == "__delayedload") {
      if (!delayed) c.Fail(what + ": delayed-load metadata outside a grid", value_at);
      if (size == 0) continue;
      // DelayedLoadMetadata::readValue: leaf count, a Blosc or raw int8 mask per leaf, then
      // UINT32_MAX or a Blosc or raw int64 compressed size per leaf.
      const std::uint32_t leaves = c.U32(what + " leaf count");
      auto chunk = [&](std::uint32_t bytes, std::uint64_t expected, const std::string& part) {
        if (bytes == 0) return c.Skip(expected, what + " " + part);
        delayed->chunks.push_back({c.pos(), bytes, expected, what + " " + part});
        CheckBlosc(c, bytes, expected, true, what + " " + part, /*decompress=*/false);
      };
      chunk(c.U32(what + " mask size"), leaves, "mask");
      const std::uint32_t size_bytes = c.U32(what + " sizes size");
      if (size_bytes != std::numeric_limits<std::uint32_t>::max())
        chunk(size_bytes, std::uint64_t(leaves) * 8, "sizes");
      if (c.pos() - value_at > size)
        c.Fail(what + ": holds more than its " + std::to_string(size) + " bytes", value_at);
      c.Seek(value_at + size);
      delayed->leaves = leaves;
    } else {
      c.Fail(what + " has type " + Quote(type) + ", which pandora does not read", entry_at);
    }
  }
}

// math::Transform::read of the maps a scale and a translation can be: UniformScaleTranslateMap and
// ScaleTranslateMap (translation, then five Vec3d), UniformScaleMap and ScaleMap (five Vec3d).
void CheckTransform(Cursor& c, VdbGridInfo& info, const std::string& name) {
  const std::string what = "grid " + name + " transform";
  const std::size_t at = c.pos();
  const std::string type = c.String(what + " type");
  const bool translate = type == "UniformScaleTranslateMap" || type == "ScaleTranslateMap";
  if (!translate && type != "UniformScaleMap" && type != "ScaleMap")
    c.Fail(what + ": " + Quote(type) + " is not a scale and a translation", at);
  std::array<double, 3> t{0, 0, 0};
  if (translate)
    for (double& v : t) v = c.F64(what);
  std::array<std::array<double, 3>, 5> v;  // scale, voxel size, 1/s, 1/s^2, 1/(2s)
  for (auto& vec : v)
    for (double& x : vec) x = c.F64(what);
  const double s = v[0][0];
  auto close = [](double a, double b) { return std::abs(a - b) <= 1e-9 * std::abs(b); };
  if (!(std::isfinite(s) && s >= 1e-9 && s <= 1e9))
    c.Fail(what + ": voxel size " + std::to_string(s) + " is not a positive finite length", at);
  for (int a = 0; a < 3; ++a) {
    if (!(v[0][a] == s && v[1][a] == s))
      c.Fail(what + ": the voxel size is not the same along the three axes", at);
    if (!close(v[2][a], 1 / s) || !close(v[3][a], 1 / (s * s)) || !close(v[4][a], 0.5 / s))
      c.Fail(what + ": the stored inverse scales do not match the scale", at);
    if (!(std::isfinite(t[a]) && std::abs(t[a]) <= 1e12))
      c.Fail(what + ": the translation is not finite", at);
  }
  info.voxel_size = s;
  info.translation = t;
}

// One grid: descriptor (GridDescriptor::read), compression (Archive::readGridCompression),
// metadata, transform, topology and buffers (Archive::doReadGrid).
void CheckGrid(Cursor& c, const VdbLimits& limits, VdbGridInfo& info,
               std::set<std::string>& names) {
  const std::size_t at = c.pos();
  info.name = c.String("grid name");
  const std::string name = Quote(info.name);
  if (info.name.empty() || info.name.find('\x1e') != std::string::npos)
    c.Fail("grid name " + name + " is empty or numbered (a duplicate name)", at);
  for (unsigned char ch : info.name)
    if (ch < 0x20 || ch == 0x7f) c.Fail("grid name " + name + " holds control characters", at);
  if (!names.insert(info.name).second) c.Fail("two grids named " + name, at);
  const std::size_t type_at = c.pos();
  info.tree_type = c.String("grid " + name + " type");
  const TreeKind* kind = nullptr;
  for (const TreeKind& k : kTreeKinds)
    if (info.tree_type == k.name) kind = &k;
  if (!kind)
    c.Fail("grid " + name + " has type " + Quote(info.tree_type) +
               ", which pandora does not read (float, bool, int32, int64 5-4-3 trees only)",
           type_at);
  const std::size_t parent_at = c.pos();
  if (!c.String("grid " + name + " instance parent").empty())
    c.Fail("grid " + name + " is an instance of another grid", parent_at);
  const std::size_t offsets_at = c.pos();
  const std::int64_t grid_pos = c.I64("grid offsets"), block_pos = c.I64("grid offsets"),
                     end_pos = c.I64("grid offsets");
  if (grid_pos != std::int64_t(c.pos()) || block_pos <= grid_pos || end_pos < block_pos ||
      std::uint64_t(end_pos) > c.size())
    c.Fail("grid " + name + ": its offsets " + std::to_string(grid_pos) + ", " +
               std::to_string(block_pos) + ", " + std::to_string(end_pos) + " do not fit the file",
           offsets_at);
  GridWalk g;
  g.kind = kind;
  g.limits = &limits;
  g.info = &info;
  g.name = name;
  const std::size_t comp_at = c.pos();
  g.compression = c.U32("grid " + name + " compression");
  const std::uint32_t allowed = kCompressZip | kCompressActiveMask | kCompressBlosc;
  if ((g.compression & ~allowed) ||
      ((g.compression & kCompressZip) && (g.compression & kCompressBlosc)))
    c.Fail("grid " + name + ": compression flags " + std::to_string(g.compression), comp_at);
  info.compression = g.compression;
  DelayedLoad delayed;
  CheckMetaMap(c, "grid " + name, &info.strings, &info.integers, &delayed);
  if (auto it = info.strings.find("name"); it == info.strings.end() || it->second != info.name)
    c.Fail("grid " + name + ": its 'name' metadata differs from its descriptor", at);
  CheckTransform(c, info, name);
  Cursor buf = c;
  buf.Seek(block_pos);
  CheckTree(c, buf, g);
  if (c.pos() != std::size_t(block_pos))
    c.Fail("grid " + name + ": the topology ends at byte " + std::to_string(c.pos()) +
           ", its descriptor says " + std::to_string(block_pos));
  if (buf.pos() != std::size_t(end_pos))
    buf.Fail("grid " + name + ": the buffers end at byte " + std::to_string(buf.pos()) +
             ", its descriptor says " + std::to_string(end_pos));
  if (delayed.leaves >= 0 && delayed.leaves != info.leaf_count)
    c.Fail("grid " + name + ": its delayed-load metadata counts " + std::to_string(delayed.leaves) +
           " leaves, the tree has " + std::to_string(info.leaf_count));
  for (const DelayedLoad::Chunk& chunk : delayed.chunks) {
    Cursor d = c;
    d.Seek(chunk.pos);
    CheckBlosc(d, chunk.length, chunk.expected, true, chunk.what);
  }
  if (!info.empty) {
    std::int64_t dims[3];
    for (int a = 0; a < 3; ++a) dims[a] = info.active_max[a] + 1;
    for (int a = 0; a < 3; ++a)
      if (dims[a] * dims[(a + 1) % 3] > limits.max_face_voxels)
        c.Fail("grid " + name + ": its active voxels span " + std::to_string(dims[0]) + " x " +
               std::to_string(dims[1]) + " x " + std::to_string(dims[2]) +
               " voxels, over the limit");
  }
  c.Seek(end_pos);
}

}  // namespace

VdbFileInfo CheckVdbBytes(std::string_view bytes, const std::string& path,
                          const VdbLimits& limits) {
  Cursor c(bytes, path);
  if (bytes.size() > limits.max_file_bytes)
    c.Fail("the file has " + std::to_string(bytes.size()) + " bytes, over the limit", 0);
  // Archive::readHeader.
  if (c.left() < 8 || c.I64("magic") != kVdbMagic) c.Fail("not a VDB file (wrong magic number)", 0);
  const std::uint32_t version = c.U32("file format version");
  if (version != kFileVersion)
    c.Fail("file format version " + std::to_string(version) + ", expected 224 (OpenVDB 6 to 12)",
           8);
  const std::uint32_t major = c.U32("library version");
  c.U32("library version");
  if (major < 6 || major > 99)
    c.Fail("written by OpenVDB " + std::to_string(major) + ", expected 6 or later", 12);
  if (!c.Bool("grid offsets flag"))
    c.Fail("a stream without grid offsets (pandora writes files)", 20);
  const std::string_view uuid = c.Take(36, "UUID");
  for (int i = 0; i < 36; ++i) {
    const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
    if (dash ? uuid[i] != '-' : !std::isxdigit(static_cast<unsigned char>(uuid[i])))
      c.Fail("the UUID is not 36 characters of hex digits and dashes", 21);
  }
  VdbFileInfo info;
  CheckMetaMap(c, "file", &info.strings, nullptr, nullptr);
  const std::size_t count_at = c.pos();
  const std::int32_t grids = c.I32("grid count");
  if (grids < 0 || grids > limits.max_grids)
    c.Fail(std::to_string(grids) + " grids (0 to " + std::to_string(limits.max_grids) + ")",
           count_at);
  std::set<std::string> names;
  for (std::int32_t i = 0; i < grids; ++i) {
    info.grids.emplace_back();
    CheckGrid(c, limits, info.grids.back(), names);
  }
  if (c.left() != 0) c.Fail(std::to_string(c.left()) + " bytes after the last grid");
  return info;
}

std::string ReadVdbFileBytes(const std::string& path, const VdbLimits& limits) {
  const std::string hint = "pass the fields.vdb that `pandora analyze` wrote";
  // O_NONBLOCK: opening a FIFO must not wait for a writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0)
    throw InputError(
        path, "",
        std::string("cannot read the VDB file: cannot open it (") + std::strerror(errno) + ")",
        hint);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st;
  if (::fstat(fd, &st) != 0)
    throw InputError(path, "", std::string("cannot read the VDB file: ") + std::strerror(errno),
                     hint);
  if (S_ISDIR(st.st_mode))
    throw InputError(path, "", "cannot read the VDB file: it is a folder", hint);
  if (!S_ISREG(st.st_mode))
    throw InputError(
        path, "", "cannot read the VDB file: it is not a regular file (a FIFO, device or socket)",
        hint);
  if (st.st_size == 0) throw InputError(path, "", "cannot read the VDB file: it is empty", hint);
  if (std::uint64_t(st.st_size) > limits.max_file_bytes)
    throw InputError(path, "",
                     "cannot read the VDB file: it has " + std::to_string(st.st_size) +
                         " bytes, over the limit of " + std::to_string(limits.max_file_bytes),
                     hint);
  std::string bytes(std::size_t(st.st_size), '\0');
  std::size_t got = 0;
  while (got < bytes.size()) {
    const ssize_t n = ::read(fd, &bytes[got], bytes.size() - got);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n < 0)
      throw InputError(path, "", std::string("cannot read the VDB file: ") + std::strerror(errno),
                       hint);
    if (n == 0) break;
    got += std::size_t(n);
  }
  char extra;
  if (got != bytes.size() || ::read(fd, &extra, 1) > 0)
    throw InputError(path, "", "cannot read the VDB file: it changed size while it was read",
                     "read it again when it is complete");
  return bytes;
}

std::string VisibilityGridName(const std::string& camera_id) {
  std::string name = "visible/";
  for (unsigned char ch : camera_id) {
    if (std::isalnum(ch) || ch == '_' || ch == '.' || ch == '-') {
      name += char(ch);
    } else {
      char buf[4];
      std::snprintf(buf, sizeof buf, "%%%02X", ch);
      name += buf;
    }
  }
  return name;
}

void CheckSameRunAsSummary(const FieldsProvenance& p, const std::string& path) {
  const auto run = p.metadata.find("run_id");
  if (run == p.metadata.end() || run->second.empty()) return;  // an older file: nothing to compare
  // The summary.json written with it: beside a fields.vdb, one folder up from a streamed tile.
  std::string folder =
      path.substr(0, path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/'));
  if (folder.empty() && path.find('/') == std::string::npos) folder = ".";
  const std::string name =
      path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
  std::string summary = folder + "/summary.json";
  if (name.rfind("tile_", 0) == 0) summary = folder + "/../summary.json";
  struct stat st {};
  if (::stat(summary.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > (64 << 20)) return;
  std::FILE* f = std::fopen(summary.c_str(), "rb");
  if (!f) return;
  std::string text(static_cast<std::size_t>(st.st_size), '\0');
  const std::size_t got = std::fread(text.data(), 1, text.size(), f);
  std::fclose(f);
  text.resize(got);
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("run_id") || !j["run_id"].is_string())
    return;
  const std::string other = j["run_id"].get<std::string>();
  if (other != run->second)
    throw InputError(
        path, "",
        "the fields belong to another run than " + summary + " beside them (run ids " +
            run->second + " and " + other + "): one of the two is stale",
        "run pandora analyze again into that folder, or give fields with their own summary");
}

std::vector<std::string> CheckFieldsProvenance(const FieldsProvenance& p,
                                               const VoxelLattice& lattice, const Scene& scene,
                                               const Rig& rig, const std::string& path) {
  std::vector<std::string> warnings;
  CheckSameRunAsSummary(p, path);
  if (p.scene_sha256.empty() && p.rig_name.empty() && p.rig_json.empty()) {
    warnings.push_back(
        path +
        " says nothing of the scene and rig it was computed for; it cannot be checked against " +
        scene.path);
  }
  if (!p.rig_name.empty() && p.rig_name != rig.name)
    throw InputError(path, "",
                     "the fields were computed for rig " + Quote(p.rig_name) + ", not for rig " +
                         Quote(rig.name),
                     "render with {rig} " + p.rig_name + ", or analyze " + scene.path +
                         " with {rig} " + rig.name + " for these fields");
  if (!p.scene_sha256.empty() && p.scene_sha256 != scene.sha256)
    warnings.push_back(path + " was computed from a different version of the scene file (SHA-256 " +
                       p.scene_sha256.substr(0, 12) + "..., " + scene.path + " is " +
                       scene.sha256.substr(0, 12) +
                       "...); run `pandora analyze` again if the fields are stale");
  if (!p.rig_json.empty()) {
    nlohmann::json file_rig = nlohmann::json::parse(p.rig_json, nullptr, false);
    const nlohmann::json now = nlohmann::json::parse(RigToJson(rig).dump());
    if (file_rig.is_discarded() || !file_rig.is_object() || !file_rig.contains("cameras") ||
        !file_rig["cameras"].is_array()) {
      warnings.push_back(path +
                         ": its rig metadata is not a rig in JSON; the cameras cannot be compared");
    } else {
      std::map<std::string, const nlohmann::json*> before, after;
      std::vector<std::string> order_before, order_after;
      for (const auto& cam : file_rig["cameras"]) {
        const std::string id = cam.is_object() && cam.contains("id") && cam["id"].is_string()
                                   ? cam["id"].get<std::string>()
                                   : cam.dump();
        before[id] = &cam;
        order_before.push_back(id);
      }
      for (const auto& cam : now["cameras"]) {
        after[cam["id"].get<std::string>()] = &cam;
        order_after.push_back(cam["id"].get<std::string>());
      }
      std::string changed, added, removed, disabled, enabled;
      auto add = [](std::string& list, const std::string& id) {
        list += (list.empty() ? "" : ", ") + Quote(id);
      };
      // On or off (--disable) and nothing else: said so.
      auto enabled_of = [](const nlohmann::json& cam) {
        return !(cam.is_object() && cam.contains("enabled") && cam["enabled"] == false);
      };
      auto without_enabled = [](nlohmann::json cam) {
        if (cam.is_object()) cam.erase("enabled");
        return cam;
      };
      for (const auto& [id, cam] : after) {
        auto it = before.find(id);
        if (it == before.end())
          add(added, id);
        else if (*it->second != *cam && without_enabled(*it->second) == without_enabled(*cam))
          add(enabled_of(*cam) ? enabled : disabled, id);
        else if (*it->second != *cam)
          add(changed, id);
      }
      for (const auto& [id, cam] : before)
        if (!after.count(id)) add(removed, id);
      std::string what;
      if (!changed.empty()) what += "changed " + changed;
      if (!added.empty()) what += std::string(what.empty() ? "" : "; ") + "added " + added;
      if (!removed.empty()) what += std::string(what.empty() ? "" : "; ") + "removed " + removed;
      if (!disabled.empty())
        what += std::string(what.empty() ? "" : "; ") + "off here, on for the fields: " + disabled;
      if (!enabled.empty())
        what += std::string(what.empty() ? "" : "; ") + "on here, off for the fields: " + enabled;
      if (what.empty() && order_before != order_after) what = "the same cameras in another order";
      if (!what.empty())
        warnings.push_back("the cameras of rig '" + rig.name + "' differ from those " + path +
                           " was computed for (" + what +
                           "); run `pandora analyze` again to update the fields");
    }
  }
  // The lattice: voxel (0, 0, 0) and the far corner's centre within the region, give or take one
  // voxel.
  const Aabb& region = scene.study.region.box;
  const double tol = lattice.voxel_size * (1 + 1e-6);
  const Vec3 first = lattice.origin;
  const Vec3 last =
      lattice.origin + lattice.voxel_size * (lattice.dims.cast<double>() - Vec3::Ones());
  for (int a = 0; a < 3; ++a) {
    if (lattice.dims[a] <= 0) continue;
    if (first[a] < region.min[a] - tol || last[a] > region.max[a] + tol) {
      char buf[256];
      std::snprintf(
          buf, sizeof buf,
          "the field lattice spans %.6g..%.6g m along %c, outside the study region's %.6g..%.6g m",
          first[a] - 0.5 * lattice.voxel_size, last[a] + 0.5 * lattice.voxel_size, "xyz"[a],
          region.min[a], region.max[a]);
      throw InputError(path, "", buf,
                       "these fields belong to another scene or region; run `pandora analyze` on " +
                           scene.path + " again");
    }
  }
  return warnings;
}

}  // namespace pandora
