#include "analysis/scene/mesh_io.h"

#include <assimp/DefaultIOSystem.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <sys/stat.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_set>
#include <utility>

#include "analysis/geometry/primitives.h"
#include "analysis/util/allocation_budget.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"

namespace pandora {
namespace {

namespace fs = std::filesystem;

// Reads the material's diffuse colour (glTF's base colour when there is no diffuse one).
bool MaterialColor(const aiMaterial& material, Vec3* color) {
  aiColor4D c;
  if (material.Get(AI_MATKEY_COLOR_DIFFUSE, c) != AI_SUCCESS &&
      material.Get(AI_MATKEY_BASE_COLOR, c) != AI_SUCCESS) {
    return false;
  }
  if (!std::isfinite(c.r) || !std::isfinite(c.g) || !std::isfinite(c.b)) return false;
  *color = Vec3(c.r, c.g, c.b).cwiseMax(0.0).cwiseMin(1.0);
  return true;
}

// Diffuse texture path resolved against `folder`; empty when none or embedded ("*0").
std::string MaterialTexture(const aiMaterial& material, const fs::path& folder) {
  aiString texture;
  if (material.GetTexture(aiTextureType_DIFFUSE, 0, &texture) != AI_SUCCESS &&
      material.GetTexture(aiTextureType_BASE_COLOR, 0, &texture) != AI_SUCCESS) {
    return {};
  }
  const std::string name = texture.C_Str();
  if (name.empty() || name[0] == '*') return {};
  const fs::path path(name);
  return path.is_absolute() ? path.string() : (folder / path).lexically_normal().string();
}

// -------------------------------------------------------------------------------------------------
// Checks before assimp reads a file. Assimp 5.2 trusts some files blindly: its PLY reader hangs or
// crashes when the header has no end_header line or declares more records than the file holds, and
// allocates a list before reading it, whatever count the file gives; its COLLADA reader loops
// forever, growing memory, on a <p> index list holding anything but integers, and reads past the
// end of an array when an accessor asks for more values than the array holds. These checks reject
// such files with a reason; a file that passes them is not necessarily valid. (Its post-processing
// steps trust the imported faces: see CheckImportedScene.)

constexpr uint64_t kMaxUint64 = std::numeric_limits<uint64_t>::max();
// A PLY header longer than this is taken as corrupt (real headers are a few hundred bytes).
constexpr uint64_t kMaxPlyHeaderBytes = uint64_t{16} << 20;

[[noreturn]] void ThrowCorrupt(const std::string& path, const std::string& format,
                               const std::string& detail) {
  throw InputError(path, "", "cannot read mesh file: corrupt " + format + ": " + detail,
                   "the file is damaged or was cut short; export it again");
}

uint64_t SaturatingMul(uint64_t a, uint64_t b) {
  return (a != 0 && b > kMaxUint64 / a) ? kMaxUint64 : a * b;
}
uint64_t SaturatingAdd(uint64_t a, uint64_t b) { return b > kMaxUint64 - a ? kMaxUint64 : a + b; }

// "37 bytes", "1.2 GB".
std::string ByteSize(uint64_t bytes) {
  if (bytes < 1000) return std::to_string(bytes) + (bytes == 1 ? " byte" : " bytes");
  static const char* const kUnits[] = {"kB", "MB", "GB", "TB", "PB", "EB"};
  double value = static_cast<double>(bytes) / 1000;
  int unit = 0;
  while (value >= 999.95 && unit < 5) {
    value /= 1000;
    ++unit;
  }
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f %s", value, kUnits[unit]);
  return text;
}

// `text` for a message: at most 60 characters, anything but printable ASCII as '?'.
std::string Printable(const std::string& text) {
  std::string out = text.substr(0, 60);
  for (char& c : out) {
    if (c < 0x20 || c > 0x7E) c = '?';
  }
  return text.size() > 60 ? out + "..." : out;
}

// Up to `max_bytes` bytes from the start of the file.
std::string ReadStart(const std::string& path, uint64_t max_bytes) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes(static_cast<size_t>(max_bytes), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return bytes;
}

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::vector<std::string> SplitWords(const std::string& line) {
  std::vector<std::string> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsBlank(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !IsBlank(line[i])) ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

// Sequential reads of the bytes of a file from its current position, `size` bytes in all.
class ByteReader {
 public:
  ByteReader(std::istream& in, uint64_t size) : in_(in), unbuffered_(size), buffer_(1 << 16) {}

  uint64_t left() const { return unbuffered_ + (end_ - pos_); }

  // Skips `n` bytes; false (reading nothing) when fewer are left.
  bool Skip(uint64_t n) {
    if (n > left()) return false;
    if (n <= end_ - pos_) {
      pos_ += static_cast<size_t>(n);
      return true;
    }
    n -= end_ - pos_;
    pos_ = end_ = 0;
    in_.seekg(static_cast<std::streamoff>(n), std::ios::cur);
    unbuffered_ -= n;
    return static_cast<bool>(in_);
  }

  // Reads `n` bytes; false when fewer are left.
  bool Read(unsigned char* out, size_t n) {
    if (n > left()) return false;
    for (size_t i = 0; i < n; ++i) {
      if (pos_ == end_ && !Fill()) return false;
      out[i] = static_cast<unsigned char>(buffer_[pos_++]);
    }
    return true;
  }

  // The next line without its line end ("\n", "\r\n" or "\r"); false at the end.
  bool ReadLine(std::string* line) {
    line->clear();
    if (pos_ == end_ && !Fill()) return false;
    while (pos_ < end_ || Fill()) {
      const char* begin = buffer_.data() + pos_;
      const char* limit = buffer_.data() + end_;
      const char* stop = begin;
      while (stop < limit && *stop != '\n' && *stop != '\r') ++stop;
      line->append(begin, stop);
      pos_ += static_cast<size_t>(stop - begin);
      if (stop == limit) continue;
      if (buffer_[pos_++] == '\r' && (pos_ < end_ || Fill()) && buffer_[pos_] == '\n') ++pos_;
      return true;
    }
    return true;  // The last line, without a line end.
  }

 private:
  bool Fill() {
    pos_ = end_ = 0;
    if (unbuffered_ == 0) return false;
    const size_t want = static_cast<size_t>(std::min<uint64_t>(buffer_.size(), unbuffered_));
    in_.read(buffer_.data(), static_cast<std::streamsize>(want));
    end_ = static_cast<size_t>(std::max<std::streamsize>(in_.gcount(), 0));
    // A file that shrank while being read ends here.
    unbuffered_ = end_ < want ? 0 : unbuffered_ - want;
    return end_ > 0;
  }

  std::istream& in_;
  uint64_t unbuffered_;
  std::vector<char> buffer_;
  size_t pos_ = 0, end_ = 0;
};

// --- PLY.

enum class PlyEncoding { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyProperty {
  std::string name;
  std::string type;        // The value's type; for a list, the entries' type.
  std::string count_type;  // A list's count type; empty for a scalar.
  int size = 0;            // Bytes of `type`; 0 when unknown.
  int count_size = 0;      // Bytes of `count_type`.
  bool list() const { return !count_type.empty(); }
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
  bool HasList() const {
    return std::any_of(properties.begin(), properties.end(),
                       [](const PlyProperty& p) { return p.list(); });
  }
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::kAscii;
  std::vector<PlyElement> elements;
  uint64_t data_offset = 0;  // Where the data starts: after the end_header line.
};

// Bytes of a PLY value type (the spec's names and their sized aliases); 0 when unknown.
int PlyTypeSize(const std::string& type) {
  static const std::map<std::string, int> kSizes = {
      {"char", 1},   {"int8", 1},    {"uchar", 1},  {"uint8", 1},  {"short", 2}, {"int16", 2},
      {"ushort", 2}, {"uint16", 2},  {"int", 4},    {"int32", 4},  {"uint", 4},  {"uint32", 4},
      {"float", 4},  {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = kSizes.find(type);
  return it == kSizes.end() ? 0 : it->second;
}

bool IsPlySigned(const std::string& type) {
  return type == "char" || type == "int8" || type == "short" || type == "int16" || type == "int" ||
         type == "int32";
}
bool IsPlyFloat(const std::string& type) {
  return type == "float" || type == "float32" || type == "double" || type == "float64";
}

// "99999999 vertices", "1 face", "3 'edge' records".
std::string PlyRecords(uint64_t n, const std::string& element) {
  const std::string count = std::to_string(n);
  if (element == "vertex") return count + (n == 1 ? " vertex" : " vertices");
  if (element == "face") return count + (n == 1 ? " face" : " faces");
  return count + " '" + Printable(element) + "' record" + (n == 1 ? "" : "s");
}

// "face 8 of 12".
std::string PlyRecord(uint64_t index, const PlyElement& element) {
  const std::string what = element.name == "vertex" || element.name == "face"
                               ? element.name
                               : "'" + Printable(element.name) + "' record";
  return what + " " + std::to_string(index + 1) + " of " + std::to_string(element.count);
}

// Whether assimp reads the file as PLY by its content: "ply" (any case) starts the first line.
bool HasPlyMagic(const std::string& start) {
  return start.size() >= 3 && std::tolower(static_cast<unsigned char>(start[0])) == 'p' &&
         std::tolower(static_cast<unsigned char>(start[1])) == 'l' &&
         std::tolower(static_cast<unsigned char>(start[2])) == 'y';
}

// Parses the header at the start of `head` (the first bytes of a file of `file_size` bytes).
// Returns nothing when the format line is one assimp rejects by itself.
std::optional<PlyHeader> ParsePlyHeader(const std::string& head, uint64_t file_size,
                                        const std::string& path) {
  size_t pos = 0;
  int line_number = 0;
  std::string line;
  // The next line without its line end ("\n", "\r\n" or "\r"); false at the end of `head`.
  auto next_line = [&]() {
    if (pos >= head.size()) return false;
    size_t end = head.find_first_of("\r\n", pos);
    if (end == std::string::npos) end = head.size();
    line = head.substr(pos, end - pos);
    pos = end;
    if (pos < head.size() && head[pos] == '\r') ++pos;
    if (pos < head.size() && head[pos] == '\n' && (pos == end || head[end] == '\r')) ++pos;
    ++line_number;
    return true;
  };
  next_line();  // "ply".
  PlyHeader header;
  // Assimp takes the second line as the format line and rejects the file unless it is one.
  if (!next_line()) return std::nullopt;
  const std::vector<std::string> format = SplitWords(line);
  if (format.size() < 2 || format[0] != "format") return std::nullopt;
  if (format[1] == "ascii") {
    header.encoding = PlyEncoding::kAscii;
  } else if (format[1].rfind("binary_", 0) == 0) {
    // Assimp reads any "binary_b..." as big endian, any other "binary_..." as little endian.
    const bool big = format[1].size() > 7 && (format[1][7] == 'b' || format[1][7] == 'B');
    header.encoding = big ? PlyEncoding::kBinaryBigEndian : PlyEncoding::kBinaryLittleEndian;
  } else {
    return std::nullopt;
  }

  while (next_line()) {
    const std::vector<std::string> words = SplitWords(line);
    if (words.empty()) continue;
    const std::string where =
        "header line " + std::to_string(line_number) + " (\"" + Printable(line) + "\")";
    if (words[0] == "end_header") {
      header.data_offset = pos;
      return header;
    }
    if (words[0] == "element") {
      if (words.size() < 3) ThrowCorrupt(path, "PLY", where + " has no count");
      PlyElement element;
      element.name = words[1];
      for (char c : words[2]) {
        if (c < '0' || c > '9')
          ThrowCorrupt(path, "PLY", where + " has a count that is not a number");
        element.count = SaturatingAdd(SaturatingMul(element.count, 10), uint64_t(c - '0'));
      }
      header.elements.push_back(element);
    } else if (words[0] == "property" && !header.elements.empty()) {
      PlyProperty property;
      if (words.size() >= 2 && words[1] == "list") {
        if (words.size() < 5) ThrowCorrupt(path, "PLY", where + " is incomplete");
        property.count_type = words[2];
        property.type = words[3];
        property.name = words[4];
        property.count_size = PlyTypeSize(property.count_type);
      } else {
        if (words.size() < 3) ThrowCorrupt(path, "PLY", where + " is incomplete");
        property.type = words[1];
        property.name = words[2];
      }
      property.size = PlyTypeSize(property.type);
      header.elements.back().properties.push_back(property);
    }
    // Comments, obj_info and unknown lines carry no data.
  }
  if (head.size() < file_size) {
    ThrowCorrupt(path, "PLY", "no end_header line in the first " + ByteSize(head.size()));
  }
  ThrowCorrupt(path, "PLY", "the header has no end_header line");
}

// What assimp makes of a list count read as `type` from the bits `raw` (little endian, `size`
// bytes): it converts the value to a 32-bit unsigned integer, negative ones wrapping around.
uint64_t PlyBinaryCount(uint64_t raw, const std::string& type, int size) {
  if (type == "float" || type == "float32") {
    float f;
    const uint32_t bits = static_cast<uint32_t>(raw);
    std::memcpy(&f, &bits, sizeof(f));
    return (f >= 0 && f < 4294967296.0f) ? static_cast<uint64_t>(f) : kMaxUint64;
  }
  if (type == "double" || type == "float64") {
    double d;
    std::memcpy(&d, &raw, sizeof(d));
    return (d >= 0 && d < 4294967296.0) ? static_cast<uint64_t>(d) : kMaxUint64;
  }
  if (IsPlySigned(type) && size < 8 && ((raw >> (8 * size - 1)) & 1)) {
    raw |= ~uint64_t{0} << (8 * size);  // Sign-extend.
  }
  return static_cast<uint32_t>(raw);
}

// The same for a list count written as text: assimp reads the leading digits (after a sign for
// signed types) into a 32-bit unsigned integer, or a number for floating-point types.
uint64_t PlyTextCount(std::string_view word, const std::string& type) {
  if (IsPlyFloat(type)) {
    const double d = std::strtod(std::string(word).c_str(), nullptr);
    return (d >= 0 && d < 4294967296.0) ? static_cast<uint64_t>(d) : kMaxUint64;
  }
  size_t i = 0;
  bool negative = false;
  if (IsPlySigned(type) && i < word.size() && (word[i] == '-' || word[i] == '+')) {
    negative = word[i] == '-';
    ++i;
  }
  uint32_t value = 0;
  for (; i < word.size() && word[i] >= '0' && word[i] <= '9'; ++i) {
    value = value * 10 + static_cast<uint32_t>(word[i] - '0');
  }
  return negative ? static_cast<uint32_t>(0u - value) : value;
}

// Walks the records of a binary PLY file, checking that each fits in the file.
void CheckPlyBinaryRecords(const PlyHeader& header, ByteReader& reader, const std::string& path) {
  const bool big_endian = header.encoding == PlyEncoding::kBinaryBigEndian;
  for (const PlyElement& element : header.elements) {
    if (!element.HasList()) {
      uint64_t record = 0;
      for (const PlyProperty& p : element.properties) record += p.size;
      if (!reader.Skip(SaturatingMul(element.count, record))) {
        ThrowCorrupt(path, "PLY",
                     "the file ends inside the " + PlyRecords(element.count, element.name) + " (" +
                         ByteSize(reader.left()) + " left for them)");
      }
      continue;
    }
    for (uint64_t i = 0; i < element.count; ++i) {
      for (const PlyProperty& p : element.properties) {
        if (!p.list()) {
          if (!reader.Skip(p.size)) {
            ThrowCorrupt(path, "PLY", "the file ends inside " + PlyRecord(i, element));
          }
          continue;
        }
        unsigned char bytes[8] = {};
        if (!reader.Read(bytes, p.count_size)) {
          ThrowCorrupt(path, "PLY", "the file ends inside " + PlyRecord(i, element));
        }
        if (big_endian) std::reverse(bytes, bytes + p.count_size);
        uint64_t raw = 0;
        for (int b = 0; b < p.count_size; ++b) raw |= uint64_t{bytes[b]} << (8 * b);
        const uint64_t count = PlyBinaryCount(raw, p.count_type, p.count_size);
        const uint64_t size = SaturatingMul(count, p.size);
        if (!reader.Skip(size)) {
          const std::string entries = count == kMaxUint64 ? "an invalid number of entries"
                                                          : std::to_string(count) + " entries";
          ThrowCorrupt(path, "PLY",
                       PlyRecord(i, element) + " has a list of " + entries +
                           " but the file has only " + ByteSize(reader.left()) + " left");
        }
      }
    }
  }
}

// Walks the lines of an ASCII PLY file (one record a line, as assimp reads them), checking that
// no list count exceeds what the file could hold: assimp allocates the list before reading it.
void CheckPlyTextLists(const PlyHeader& header, ByteReader& reader, uint64_t data_bytes,
                       const std::string& path) {
  std::string line;
  for (const PlyElement& element : header.elements) {
    for (uint64_t i = 0; i < element.count; ++i) {
      do {
        // Missing lines are no danger: assimp gives their values as zeros.
        if (!reader.ReadLine(&line)) return;
      } while (line.find_first_not_of(" \t\r\f\v") == std::string::npos);
      if (!element.HasList()) continue;
      size_t at = 0;
      // The next word of the line; false at its end.
      auto next_word = [&](std::string_view* word) {
        while (at < line.size() && IsBlank(line[at])) ++at;
        if (at == line.size()) return false;
        const size_t begin = at;
        while (at < line.size() && !IsBlank(line[at])) ++at;
        *word = std::string_view(line).substr(begin, at - begin);
        return true;
      };
      std::string_view word;
      for (const PlyProperty& p : element.properties) {
        if (!next_word(&word)) break;
        if (!p.list()) continue;
        const uint64_t count = PlyTextCount(word, p.count_type);
        // Each entry takes at least a digit and a separator.
        if (SaturatingMul(count, 2) > data_bytes + 1) {
          const std::string entries = count == kMaxUint64 ? "an invalid number of entries"
                                                          : std::to_string(count) + " entries";
          ThrowCorrupt(path, "PLY",
                       PlyRecord(i, element) + " has a list of " + entries +
                           " but the file has only " + ByteSize(data_bytes) + " after the header");
        }
        for (uint64_t k = 0; k < count && next_word(&word); ++k) {
        }
      }
    }
  }
}

void CheckPly(const std::string& path, uint64_t file_size) {
  const std::string head = ReadStart(path, std::min(file_size, kMaxPlyHeaderBytes));
  const std::optional<PlyHeader> header = ParsePlyHeader(head, file_size, path);
  if (!header) return;
  const bool binary = header->encoding != PlyEncoding::kAscii;
  const uint64_t data_bytes = file_size - std::min(file_size, header->data_offset);

  // The least the declared records take: in binary, every value at its size and lists empty; as
  // text, a digit and a separator per value (the last line may lack its line end). A record
  // without properties is counted as a byte (a line as text), so that a huge count cannot pass.
  uint64_t least = 0;
  std::string declared;
  for (const PlyElement& element : header->elements) {
    uint64_t record = 0;
    for (const PlyProperty& p : element.properties) {
      if (binary && (p.size == 0 || (p.list() && p.count_size == 0))) {
        throw InputError(path, "",
                         "cannot read mesh file: PLY property '" + Printable(p.name) +
                             "' of element '" + Printable(element.name) +
                             "' has an unknown type ('" +
                             Printable(p.list() ? p.count_type + " " + p.type : p.type) + "')",
                         "binary PLY values must be char, uchar, short, ushort, int, uint, "
                         "float or double");
      }
      record += binary ? (p.list() ? p.count_size : p.size) : 2;
    }
    least = SaturatingAdd(least, SaturatingMul(element.count, std::max<uint64_t>(record, 1)));
    if (element.count > 0) {
      declared += (declared.empty() ? "" : ", ") + PlyRecords(element.count, element.name);
    }
  }
  const uint64_t slack = binary ? 0 : 1;
  if (least > SaturatingAdd(data_bytes, slack)) {
    ThrowCorrupt(path, "PLY",
                 "the header declares " + declared + " (at least " + ByteSize(least) +
                     (binary ? "" : " as text") + ") but the file has " + ByteSize(data_bytes) +
                     " after the header");
  }

  const bool has_lists = std::any_of(header->elements.begin(), header->elements.end(),
                                     [](const PlyElement& element) { return element.HasList(); });
  if (!has_lists) return;  // Without lists the size check above is exact for binary files.
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(header->data_offset));
  if (!in) return;
  ByteReader reader(in, data_bytes);
  if (binary) {
    CheckPlyBinaryRecords(*header, reader, path);
  } else {
    CheckPlyTextLists(*header, reader, data_bytes, path);
  }
}

// --- STL.

// A binary STL file: an 80-byte header, a 32-bit triangle count, 50 bytes a triangle. Assimp reads
// a file as binary only when its size is exactly that, and as ASCII when it starts with "solid";
// anything else it rejects with a vague message. This gives the reason for a binary one.
void CheckBinaryStl(const std::string& path, uint64_t file_size) {
  const std::string head = ReadStart(path, 84);
  const size_t text = head.find_first_not_of(" \t\r\n");
  if (text != std::string::npos && head.compare(text, 5, "solid") == 0) return;  // ASCII.
  if (file_size < 84) {
    ThrowCorrupt(
        path, "STL",
        "a binary STL file starts with an 84-byte header, but the file has " + ByteSize(file_size));
  }
  uint64_t count = 0;
  for (int b = 0; b < 4; ++b) {
    count |= uint64_t{static_cast<unsigned char>(head[80 + b])} << (8 * b);
  }
  const uint64_t size = 84 + 50 * count;
  if (file_size < size) {
    ThrowCorrupt(path, "STL",
                 "the header declares " + std::to_string(count) + " triangles (" + ByteSize(size) +
                     ") but the file has " + ByteSize(file_size));
  }
}

// --- COLLADA.

// A start tag of an XML document: its name, attributes and where its text begins.
struct XmlTag {
  std::string name;
  std::map<std::string, std::string> attributes;
  size_t content = 0;         // Just past the '>'.
  bool self_closing = false;  // <name/>
};

// The next start tag from `pos` in `text`, skipping comments, CDATA, declarations and end tags;
// false when there is none. Leaves `pos` just past the tag.
bool NextXmlTag(const std::string& text, size_t* pos, XmlTag* tag) {
  while ((*pos = text.find('<', *pos)) != std::string::npos) {
    const size_t at = *pos;
    const char* close = nullptr;
    if (text.compare(at, 4, "<!--") == 0)
      close = "-->";
    else if (text.compare(at, 9, "<![CDATA[") == 0)
      close = "]]>";
    else if (at + 1 < text.size() &&
             (text[at + 1] == '?' || text[at + 1] == '!' || text[at + 1] == '/'))
      close = ">";
    if (close != nullptr) {
      const size_t end = text.find(close, at + 1);
      if (end == std::string::npos) return false;
      *pos = end + std::strlen(close);
      continue;
    }
    size_t i = at + 1;
    auto is_space = [](char c) { return IsBlank(c) || c == '\n'; };
    while (i < text.size() && !is_space(text[i]) && text[i] != '>' && text[i] != '/') ++i;
    tag->name = text.substr(at + 1, i - at - 1);
    tag->attributes.clear();
    // Attributes: name="value" or name='value' ('>' may stand in a value).
    while (true) {
      while (i < text.size() && is_space(text[i])) ++i;
      if (i >= text.size()) return false;
      if (text[i] == '>' || text[i] == '/') break;
      const size_t name_begin = i;
      while (i < text.size() && !is_space(text[i]) && text[i] != '=' && text[i] != '>') ++i;
      const std::string name = text.substr(name_begin, i - name_begin);
      while (i < text.size() && is_space(text[i])) ++i;
      if (i >= text.size() || text[i] != '=') continue;
      ++i;
      while (i < text.size() && is_space(text[i])) ++i;
      if (i >= text.size() || (text[i] != '"' && text[i] != '\'')) continue;
      const size_t value_end = text.find(text[i], i + 1);
      if (value_end == std::string::npos) return false;
      tag->attributes[name] = text.substr(i + 1, value_end - i - 1);
      i = value_end + 1;
    }
    const size_t end = text.find('>', i);
    if (end == std::string::npos) return false;
    tag->self_closing = text[end - 1] == '/';
    tag->content = end + 1;
    *pos = end + 1;
    return true;
  }
  return false;
}

// An unsigned attribute as assimp reads it (through pugixml): its leading digits, or `otherwise`
// when it is missing.
uint64_t XmlUnsigned(const XmlTag& tag, const std::string& name, uint64_t otherwise) {
  const auto it = tag.attributes.find(name);
  if (it == tag.attributes.end()) return otherwise;
  const std::string& value = it->second;
  size_t i = value.find_first_not_of(" \t\r\n");
  uint64_t n = 0;
  for (; i < value.size() && value[i] >= '0' && value[i] <= '9'; ++i) {
    n = SaturatingAdd(SaturatingMul(n, 10), uint64_t(value[i] - '0'));
  }
  return n;
}

long LineAt(const std::string& text, size_t pos) {
  return 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(pos), '\n');
}

// Two things assimp takes on trust in COLLADA files:
// - A <p> index list: assimp reads integers until the end of its text; on any other character it
//   stops advancing and appends zeros forever. The schema allows only integers there.
// - An <accessor>: assimp reads `count` units of `stride` values from the array it names, without
//   checking that the array (as many values as its own count says) holds them.
void CheckCollada(const std::string& path, uint64_t file_size) {
  const std::string text = ReadStart(path, file_size);
  struct Accessor {
    std::string array;
    uint64_t last_value;  // Index of the last value read (offset + (count - 1) * stride).
    size_t at;
  };
  std::map<std::string, uint64_t> array_sizes;
  std::vector<Accessor> accessors;
  size_t pos = 0;
  XmlTag tag;
  while (NextXmlTag(text, &pos, &tag)) {
    const bool is_array =
        tag.name.size() > 6 && tag.name.compare(tag.name.size() - 6, 6, "_array") == 0;
    if (is_array && tag.attributes.count("id")) {
      array_sizes[tag.attributes["id"]] = XmlUnsigned(tag, "count", 0);
    } else if (tag.name == "accessor") {
      const uint64_t count = XmlUnsigned(tag, "count", 0);
      std::string source = tag.attributes.count("source") ? tag.attributes["source"] : "";
      if (!source.empty() && source[0] == '#') source.erase(0, 1);
      if (count > 0) {
        const uint64_t last = SaturatingAdd(
            XmlUnsigned(tag, "offset", 0), SaturatingMul(count - 1, XmlUnsigned(tag, "stride", 1)));
        accessors.push_back({source, last, pos});
      }
    } else if (tag.name == "p" && !tag.self_closing) {
      size_t begin = tag.content, end;
      if (text.compare(begin, 9, "<![CDATA[") == 0) {
        begin += 9;
        end = text.find("]]>", begin);
      } else {
        end = text.find('<', begin);
      }
      if (end == std::string::npos) end = text.size();
      for (size_t i = begin; i < end; ++i) {
        const char c = text[i];
        if ((c >= '0' && c <= '9') || c == '-' || c == '+' || c == ' ' || c == '\t' || c == '\r' ||
            c == '\n') {
          continue;
        }
        const unsigned char u = static_cast<unsigned char>(c);
        char shown[16];
        if (u >= 0x21 && u <= 0x7E) {
          std::snprintf(shown, sizeof(shown), "'%c'", c);
        } else {
          std::snprintf(shown, sizeof(shown), "byte 0x%02X", u);
        }
        ThrowCorrupt(path, "COLLADA",
                     "the <p> index list on line " + std::to_string(LineAt(text, i)) + " holds " +
                         shown + "; it may hold only whole numbers");
      }
      pos = end;
    }
  }
  for (const Accessor& accessor : accessors) {
    const auto array = array_sizes.find(accessor.array);
    if (array == array_sizes.end()) continue;  // Assimp reports a missing source itself.
    if (accessor.last_value >= array->second) {
      ThrowCorrupt(path, "COLLADA",
                   "the accessor on line " + std::to_string(LineAt(text, accessor.at)) +
                       " reads value " + std::to_string(accessor.last_value + 1) + " of '" +
                       Printable(accessor.array) + "', which holds " +
                       std::to_string(array->second));
    }
  }
}

// --- glTF skins and animations. Assimp 5.2's glTF 2 reader dereferences a skin's
// inverseBindMatrices accessor without checking that the skin has one (the spec makes it optional),
// and takes skin joints and animation channels' nodes and samplers on trust: such a file crashes
// it.

// The JSON of a .gltf file, or the JSON chunk of a .glb; empty when there is none to read.
std::string GltfJson(const std::string& path, const std::string& extension, uint64_t file_size) {
  if (extension == ".gltf") return ReadStart(path, file_size);
  const std::string head = ReadStart(path, 20);
  if (head.size() < 20 || head.compare(0, 4, "glTF") != 0 || head.compare(16, 4, "JSON") != 0)
    return {};
  uint32_t length = 0;
  std::memcpy(&length, head.data() + 12, 4);
  if (uint64_t(length) + 20 > file_size) return {};
  return ReadStart(path, 20 + uint64_t(length)).substr(20);
}

void CheckGltfSkins(const std::string& path, const std::string& extension, uint64_t file_size) {
  const std::string text = GltfJson(path, extension, file_size);
  if (text.empty()) return;  // no JSON chunk: assimp reports what it cannot parse
  // Parsed strictly: assimp's reader takes invalid UTF-8 and the first of two equal keys, where
  // this check would see another document (a duplicate "skins" key and invalid UTF-8 both crashed
  // it).
  std::vector<std::set<std::string>> keys;
  std::string duplicate;
  const nlohmann::json g = nlohmann::json::parse(
      text,
      [&](int depth, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
        using E = nlohmann::json::parse_event_t;
        if (event == E::object_start)
          keys.emplace_back();
        else if (event == E::object_end && !keys.empty())
          keys.pop_back();
        else if (event == E::key && !keys.empty() &&
                 !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty())
          duplicate = parsed.get<std::string>();
        return true;
      },
      false);
  if (g.is_discarded()) {
    // Not JSON at all (a binary or text file under the wrong name) is assimp's to report; JSON that
    // starts as glTF's does is checked here.
    if (text.find("\"asset\"") == std::string::npos) return;
    ThrowCorrupt(path, "glTF", "its JSON is not valid (bad syntax or invalid UTF-8)");
  }
  if (!duplicate.empty())
    ThrowCorrupt(path, "glTF",
                 "its JSON has the key \"" + duplicate.substr(0, 40) + "\" twice in one object");
  if (!g.is_object()) return;
  auto count = [&](const char* key) {
    const auto it = g.find(key);
    return it != g.end() && it->is_array() ? it->size() : std::size_t(0);
  };
  // An index into g[key]: an unsigned integer below its size.
  auto index_ok = [&](const nlohmann::json& v, const char* key) {
    return v.is_number_unsigned() && v.get<std::uint64_t>() < count(key);
  };
  const auto skins = g.find("skins");
  if (skins != g.end() && skins->is_array()) {
    for (std::size_t i = 0; i < skins->size(); ++i) {
      const nlohmann::json& skin = (*skins)[i];
      const std::string name = "skin " + std::to_string(i);
      if (!skin.is_object()) ThrowCorrupt(path, "glTF", name + " is not an object");
      if (!skin.contains("inverseBindMatrices"))
        throw InputError(
            path, "",
            "cannot read mesh file: glTF " + name +
                " has no inverseBindMatrices, which assimp 5.2 cannot read",
            "export the skin with its inverse bind matrices (Blender's glTF exporter writes them)");
      if (!index_ok(skin["inverseBindMatrices"], "accessors"))
        ThrowCorrupt(path, "glTF", name + "'s inverseBindMatrices names no accessor of the file");
      const auto joints = skin.find("joints");
      if (joints == skin.end() || !joints->is_array() || joints->empty())
        ThrowCorrupt(path, "glTF", name + " has no joints");
      // Assimp reads one 4x4 float matrix per joint from the accessor without bounds checks: the
      // accessor must hold that many, inside its buffer view, inside its buffer.
      const nlohmann::json& acc = g["accessors"][skin["inverseBindMatrices"].get<std::size_t>()];
      const std::string what = name + "'s inverseBindMatrices accessor";
      auto number = [&](const nlohmann::json& o, const char* key,
                        std::uint64_t fallback) -> std::uint64_t {
        if (!o.contains(key)) return fallback;
        if (!o[key].is_number_unsigned())
          ThrowCorrupt(path, "glTF", what + ": " + key + " is not a whole number");
        return o[key].get<std::uint64_t>();
      };
      if (!acc.is_object() || acc.value("type", std::string()) != "MAT4" ||
          number(acc, "componentType", 0) != 5126)
        ThrowCorrupt(path, "glTF", what + " is not of 4x4 float matrices");
      const std::uint64_t matrices = number(acc, "count", 0);
      if (matrices < joints->size())
        ThrowCorrupt(path, "glTF",
                     what + " holds " + std::to_string(matrices) + " matrices for " +
                         std::to_string(joints->size()) + " joints");
      if (!acc.contains("bufferView") || !index_ok(acc["bufferView"], "bufferViews"))
        ThrowCorrupt(path, "glTF", what + " names no buffer view of the file");
      const nlohmann::json& view = g["bufferViews"][acc["bufferView"].get<std::size_t>()];
      if (!view.is_object() || !view.contains("buffer") || !index_ok(view["buffer"], "buffers"))
        ThrowCorrupt(path, "glTF", what + "'s buffer view names no buffer of the file");
      const std::uint64_t stride = std::max<std::uint64_t>(number(view, "byteStride", 64), 64);
      const std::uint64_t need = number(acc, "byteOffset", 0) + (matrices - 1) * stride + 64;
      const std::uint64_t view_length = number(view, "byteLength", 0);
      const nlohmann::json& buffer = g["buffers"][view["buffer"].get<std::size_t>()];
      if (matrices > (std::uint64_t(1) << 32) || need > view_length ||
          number(view, "byteOffset", 0) + view_length >
              (buffer.is_object() ? number(buffer, "byteLength", 0) : 0))
        ThrowCorrupt(path, "glTF", what + " reaches past the end of its buffer view or buffer");
      for (const auto& j : *joints)
        if (!index_ok(j, "nodes"))
          ThrowCorrupt(path, "glTF", name + " has a joint that names no node of the file");
    }
  }
  const auto animations = g.find("animations");
  if (animations != g.end() && animations->is_array()) {
    for (std::size_t i = 0; i < animations->size(); ++i) {
      const nlohmann::json& a = (*animations)[i];
      const std::string name = "animation " + std::to_string(i);
      if (!a.is_object()) ThrowCorrupt(path, "glTF", name + " is not an object");
      const auto samplers = a.find("samplers");
      const std::size_t sampler_count =
          samplers != a.end() && samplers->is_array() ? samplers->size() : 0;
      for (std::size_t k = 0; k < sampler_count; ++k) {
        const nlohmann::json& sm = (*samplers)[k];
        if (!sm.is_object() || !sm.contains("input") || !sm.contains("output") ||
            !index_ok(sm["input"], "accessors") || !index_ok(sm["output"], "accessors"))
          ThrowCorrupt(
              path, "glTF",
              name + ": sampler " + std::to_string(k) + " names no input or output accessor");
      }
      const auto channels = a.find("channels");
      if (channels == a.end() || !channels->is_array()) continue;
      for (std::size_t k = 0; k < channels->size(); ++k) {
        const nlohmann::json& ch = (*channels)[k];
        const std::string where = name + ": channel " + std::to_string(k);
        if (!ch.is_object() || !ch.contains("sampler") || !ch["sampler"].is_number_unsigned() ||
            ch["sampler"].get<std::uint64_t>() >= sampler_count)
          ThrowCorrupt(path, "glTF", where + " names no sampler of its animation");
        const auto target = ch.find("target");
        if (target == ch.end() || !target->is_object() ||
            (target->contains("node") && !index_ok((*target)["node"], "nodes")))
          ThrowCorrupt(path, "glTF", where + " targets no node of the file");
      }
    }
  }
}

// Rejects an empty file, and the damage assimp does not survive in the formats it reads blindly.
// The format is the one assimp will pick: by the extension, or by the content when assimp does not
// know the extension.
void CheckBeforeAssimp(const std::string& path, const Assimp::Importer& importer) {
  std::error_code ec;
  const uint64_t file_size = fs::file_size(path, ec);
  if (ec) return;  // Assimp reports it.
  if (file_size == 0) {
    throw InputError(path, "", "cannot read mesh file: the file is empty (0 bytes)",
                     "the file was cut short; export it again");
  }
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool known = !extension.empty() && importer.IsExtensionSupported(extension);
  const std::string start = ReadStart(path, 4096);
  if (HasPlyMagic(start) && (extension == ".ply" || !known)) {
    CheckPly(path, file_size);
  } else if (extension == ".stl") {
    CheckBinaryStl(path, file_size);
  } else if (extension == ".dae" ||
             ((extension == ".xml" || !known) && start.find("<COLLADA") != std::string::npos)) {
    CheckCollada(path, file_size);
  } else if (extension == ".gltf" || extension == ".glb") {
    CheckGltfSkins(path, extension, file_size);
  }
}

// Checks what assimp's post-processing steps (triangulation, welding, pre-transforming) take on
// trust: faces with vertices, vertex indices within their mesh, node mesh indices within the
// scene. A corrupt file can break each, and the steps then crash or abort.
void CheckImportedScene(const aiScene& scene, const std::string& path) {
  auto fail = [&](const std::string& detail) {
    throw InputError(path, "", "cannot read mesh file: corrupt mesh data: " + detail,
                     "the file is damaged; export it again");
  };
  if (scene.mNumMeshes > 0 && scene.mMeshes == nullptr) fail("the meshes are missing");
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    std::string name = "mesh " + std::to_string(m);
    if (mesh == nullptr) fail(name + " is missing");
    if (mesh->mName.length > 0) name += " ('" + Printable(mesh->mName.C_Str()) + "')";
    if (mesh->mNumVertices > 0 && mesh->mVertices == nullptr) fail(name + " has no positions");
    if (mesh->mNumFaces > 0 && mesh->mFaces == nullptr) fail(name + " has no faces");
    if (scene.mNumMaterials > 0 && mesh->mMaterialIndex >= scene.mNumMaterials) {
      fail(name + " uses material " + std::to_string(mesh->mMaterialIndex) + " of " +
           std::to_string(scene.mNumMaterials));
    }
    // Bones: what joining vertices and our skinning read (vertex ids, weights).
    if (mesh->mNumBones > 0 && mesh->mBones == nullptr) fail(name + " has no bone list");
    for (unsigned b = 0; b < mesh->mNumBones; ++b) {
      const aiBone* bone = mesh->mBones[b];
      if (bone == nullptr) fail(name + ": bone " + std::to_string(b) + " is missing");
      if (bone->mNumWeights > 0 && bone->mWeights == nullptr)
        fail(name + ": bone '" + Printable(bone->mName.C_Str()) + "' has no weights");
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const aiVertexWeight& vw = bone->mWeights[w];
        if (vw.mVertexId >= mesh->mNumVertices)
          fail(name + ": bone '" + Printable(bone->mName.C_Str()) + "' weighs vertex " +
               std::to_string(vw.mVertexId) + " but the mesh has " +
               std::to_string(mesh->mNumVertices) + " vertices");
        if (!std::isfinite(vw.mWeight) || vw.mWeight < 0)
          fail(name + ": bone '" + Printable(bone->mName.C_Str()) +
               "' has a weight that is negative or not finite");
      }
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices == 0 || face.mIndices == nullptr) {
        fail(name + ": face " + std::to_string(f) + " has no vertices");
      }
      for (unsigned k = 0; k < face.mNumIndices; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices) {
          fail(name + ": face " + std::to_string(f) + " refers to vertex " +
               std::to_string(face.mIndices[k]) + " but the mesh has " +
               std::to_string(mesh->mNumVertices) + " vertices");
        }
      }
    }
  }
  std::vector<const aiNode*> stack;
  std::unordered_set<const aiNode*> seen;
  if (scene.mRootNode != nullptr) stack.push_back(scene.mRootNode);
  while (!stack.empty()) {
    const aiNode* node = stack.back();
    stack.pop_back();
    if (!seen.insert(node).second) fail("the node tree has a cycle");
    const std::string name = "node '" + Printable(node->mName.C_Str()) + "'";
    if (node->mNumMeshes > 0 && node->mMeshes == nullptr) fail(name + " has no mesh list");
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      if (node->mMeshes[i] >= scene.mNumMeshes) {
        fail(name + " refers to mesh " + std::to_string(node->mMeshes[i]) + " but the file has " +
             std::to_string(scene.mNumMeshes) + " meshes");
      }
    }
    if (node->mNumChildren > 0 && node->mChildren == nullptr) fail(name + " has no child list");
    for (unsigned i = 0; i < node->mNumChildren; ++i) {
      if (node->mChildren[i] == nullptr) fail(name + " has a missing child");
      stack.push_back(node->mChildren[i]);
    }
  }
}

// Assimp's file access, refusing what is not a regular file of bounded size (it would block or
// never end) instead of opening it.
class CheckedIoSystem : public Assimp::DefaultIOSystem {
 public:
  // DefaultIOSystem::Exists opens the file (fopen), which blocks on a FIFO: stat instead.
  bool Exists(const char* file) const override { return Readable(file); }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (file == nullptr) return nullptr;
    const std::string m = mode == nullptr ? "" : mode;
    if (m.find_first_of("wa+") == std::string::npos && !Readable(file))
      return nullptr;  // assimp reports "cannot open"; the main file was checked before
    return Assimp::DefaultIOSystem::Open(file, mode);
  }

 private:
  static bool Readable(const char* file) {
    struct stat st {};
    return file != nullptr && ::stat(file, &st) == 0 && S_ISREG(st.st_mode) &&
           static_cast<std::uint64_t>(st.st_size) <= InputLimits::kMeshBytes;
  }
};

// Bytes assimp may hold at once for a file of `file_size` bytes: 256 MiB plus 64 bytes per byte of
// the file, at most half of the machine's memory.
std::uint64_t AssimpBudgetBytes(std::uint64_t file_size) {
  std::uint64_t budget = (256ull << 20) + 64 * file_size;
  const std::uint64_t physical = PhysicalMemoryBytes();
  if (physical > 0) budget = std::min(budget, physical / 2);
  return budget;
}

// The open ScopedMeshImportBudget (0 bytes: none).
double g_import_budget = 0;
std::string g_import_budget_where;

[[noreturn]] void ThrowOverBudget(const std::string& path, std::uint64_t file_size) {
  if (g_import_budget > 0 && g_import_budget < double(AssimpBudgetBytes(file_size)))
    throw InputError(path, "",
                     "reading the mesh file needs more than the memory budget of " +
                         std::to_string(std::llround(g_import_budget / 1048576.0)) + " MiB (" +
                         g_import_budget_where + ")",
                     "raise the budget, or simplify or split the mesh");
  throw InputError(path, "",
                   "cannot read mesh file: reading it needs more than " +
                       ByteSize(AssimpBudgetBytes(file_size)) + " of memory for a file of " +
                       ByteSize(file_size) + "; the file is damaged",
                   "export it again");
}

// Reads `path` with assimp after the checks above, runs the post-processing steps `steps` and
// hands the result to `use` while the import's memory budget is open. Throws InputError as
// LoadMeshFile documents.
template <typename Use>
auto ReadCheckedFile(const std::string& path, unsigned steps, Use&& use) {
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    throw InputError(path, "", "mesh file not found",
                     "mesh paths are relative to the folder of the scene file");
  }
  const std::uint64_t file_size = CheckInputFile(path, InputLimits::kMeshBytes, "mesh file");
  // Only formats whose readers survived our damage tests (scene_test, MeshFileRobustnessTest and
  // the fuzzing recorded in docs/robustness.md). Assimp reads more, but some of its readers crash
  // or allocate without bound on damaged files: X3D crashes, and DirectX .x crashes or takes more
  // than 11 GB from a 3 KB file. A scene loader must never crash.
  static const std::set<std::string> kSupported{".obj", ".gltf", ".glb", ".ply",
                                                ".stl", ".dae",  ".fbx", ".3ds"};
  std::string extension = fs::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (!kSupported.count(extension)) {
    throw InputError(path, "", "unsupported mesh format '" + extension + "'",
                     "convert it to OBJ, glTF/GLB, PLY, STL, COLLADA (.dae), FBX or 3DS "
                     "(e.g. with Blender)");
  }

  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  auto fail = [&]() {
    std::string message = importer.GetErrorString();
    if (message.empty()) message = "unknown error";
    // What assimp says when removing points and lines (aiProcess_SortByPType) leaves nothing.
    if (message.find("No meshes remaining") != std::string::npos) {
      throw InputError(path, "", "mesh file has no triangles (only points or lines)",
                       "export the surfaces as polygons");
    }
    throw InputError(path, "", "cannot read mesh file: " + message,
                     "check that the file is a valid OBJ, glTF/GLB, PLY, STL, COLLADA or FBX file");
  };
  // Every file assimp opens (the mesh, an OBJ's .mtl, a glTF's buffers) must be a regular file of
  // bounded size: a FIFO or /dev/zero named inside a mesh file would block or never end.
  importer.SetIOHandler(new CheckedIoSystem());
  CheckBeforeAssimp(path, importer);
  // What assimp may hold at once while it reads and post-processes: far above what a valid file
  // of this size needs (measured in docs/robustness.md), far below what a damaged file's sizes
  // could make it ask for.
  AllocationBudget budget(
      g_import_budget > 0
          ? std::min<std::uint64_t>(AssimpBudgetBytes(file_size), std::uint64_t(g_import_budget))
          : AssimpBudgetBytes(file_size));
  const aiScene* scene = nullptr;
  try {
    // Read first, check what the post-processing steps trust, then run them.
    const aiScene* raw = importer.ReadFile(path, 0);
    if (raw == nullptr && budget.exceeded())
      ThrowOverBudget(path, file_size);  // assimp caught the bad_alloc
    if (raw == nullptr) fail();
    CheckImportedScene(*raw, path);
    scene = importer.ApplyPostProcessing(steps);
    if (scene == nullptr && budget.exceeded()) ThrowOverBudget(path, file_size);
  } catch (const std::bad_alloc&) {
    ThrowOverBudget(path, file_size);
  }
  if (budget.exceeded()) ThrowOverBudget(path, file_size);  // assimp caught the bad_alloc itself
  if (scene == nullptr) fail();
  try {
    return use(*scene);
  } catch (const std::bad_alloc&) {
    ThrowOverBudget(path, file_size);  // a damaged file's counts asked for more than the budget
  }
}

// Appends a triangle face of an assimp mesh to `out` (vertex v becomes index(v)) with its corner
// texture coordinates (earlier triangles of the part without any get zeros); skips points and
// lines.
template <class Index>
void AppendTriangle(const aiMesh& mesh, const aiFace& face, const std::string& path, Index index,
                    TriangleMesh* out) {
  if (face.mNumIndices != 3) return;  // Points and lines, if any are left.
  if (std::max({face.mIndices[0], face.mIndices[1], face.mIndices[2]}) >= mesh.mNumVertices)
    throw InputError(path, "",
                     "cannot read mesh file: corrupt mesh data: a triangle refers "
                     "to a vertex past the end of its mesh");
  out->triangles.emplace_back(index(face.mIndices[0]), index(face.mIndices[1]),
                              index(face.mIndices[2]));
  if (mesh.mTextureCoords[0] != nullptr) {
    out->corner_uvs.resize(out->triangles.size() - 1);
    std::array<Eigen::Vector2d, 3> uv;
    for (int k = 0; k < 3; ++k) {
      const aiVector3D& t = mesh.mTextureCoords[0][face.mIndices[k]];
      uv[k] = std::isfinite(t.x) && std::isfinite(t.y) ? Eigen::Vector2d(t.x, t.y)
                                                       : Eigen::Vector2d::Zero();
    }
    out->corner_uvs.push_back(uv);
  } else if (!out->corner_uvs.empty()) {
    out->corner_uvs.resize(out->triangles.size());
  }
}

}  // namespace

std::vector<MeshPart> LoadMeshFile(const std::string& path) {
  return ReadCheckedFile(
      path,
      aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
          aiProcess_SortByPType,
      [&](const aiScene& imported) {
        const aiScene* scene = &imported;
        // A scene left without meshes (AI_SCENE_FLAGS_INCOMPLETE) is reported below as having no
        // triangles.
        const fs::path folder = fs::path(path).parent_path();
        // Material index -> part; std::map keeps the file's material order.
        std::map<unsigned, MeshPart> parts;
        for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
          const aiMesh& mesh = *scene->mMeshes[m];
          if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
          MeshPart& part = parts[mesh.mMaterialIndex];
          TriangleMesh& out = part.mesh;
          const int offset = static_cast<int>(out.vertices.size());
          for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
            const aiVector3D& p = mesh.mVertices[v];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
              throw InputError(path, "",
                               "cannot read mesh file: a vertex has non-finite coordinates");
            }
            out.vertices.emplace_back(p.x, p.y, p.z);
          }
          for (unsigned f = 0; f < mesh.mNumFaces; ++f)
            AppendTriangle(
                mesh, mesh.mFaces[f], path,
                [offset](unsigned v) { return offset + static_cast<int>(v); }, &out);
        }

        std::vector<MeshPart> result;
        for (auto& [material_index, part] : parts) {
          part.mesh = WeldVertices(part.mesh);
          if (part.mesh.triangles.empty()) continue;
          part.material_name = "material" + std::to_string(material_index);
          if (material_index < scene->mNumMaterials) {
            const aiMaterial& material = *scene->mMaterials[material_index];
            aiString name;
            if (material.Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length > 0) {
              part.material_name = name.C_Str();
            }
            part.has_material = part.material_name != AI_DEFAULT_MATERIAL_NAME;
            if (part.has_material) {
              MaterialColor(material, &part.color);
              part.texture = MaterialTexture(material, folder);
            }
          }
          result.push_back(std::move(part));
        }
        if (result.empty()) {
          throw InputError(path, "", "mesh file has no triangles",
                           "points and lines are ignored; export the surfaces as polygons");
        }
        return result;
      });
}

namespace {

Eigen::Matrix4d ToEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out(r, c) = m[r][c];
  return out;
}

bool Finite(const Eigen::Matrix4d& m) { return m.allFinite(); }

// The node tree, parents before children; `index` maps each node to its position.
void ReadNodes(const aiNode* root, Skeleton* skeleton, std::map<const aiNode*, int>* index) {
  std::vector<std::pair<const aiNode*, int>> stack{{root, -1}};
  while (!stack.empty()) {
    const auto [node, parent] = stack.back();
    stack.pop_back();
    const int self = int(skeleton->nodes.size());
    (*index)[node] = self;
    SkeletonNode n;
    n.name = node->mName.C_Str();
    n.parent = parent;
    n.rest_local = ToEigen(node->mTransformation);
    skeleton->nodes.push_back(std::move(n));
    for (unsigned i = node->mNumChildren; i-- > 0;) stack.push_back({node->mChildren[i], self});
  }
}

// A material's vertices of a skinned mesh file: its mesh, its binding to the skeleton, and the
// welding of vertices with equal positions and influences.
struct SkinnedPart {
  MeshPart part;
  SkinBinding binding;
  std::map<std::vector<double>, int> weld;
};

// Animation `a` of a skinned mesh file as a clip: key times in seconds, quaternions normalised in
// double.
template <class Corrupt, class FindNode>
SkinClip ReadSkinClip(const aiAnimation* anim, unsigned a, const Corrupt& corrupt,
                      const FindNode& find_node) {
  if (anim == nullptr) corrupt("animation " + std::to_string(a) + " is missing");
  const std::string clip_name = "animation " + std::to_string(a);
  const double ticks = anim->mTicksPerSecond > 0 && std::isfinite(anim->mTicksPerSecond)
                           ? anim->mTicksPerSecond
                           : 25.0;
  SkinClip clip;
  clip.name = anim->mName.C_Str();
  if (!std::isfinite(anim->mDuration) || anim->mDuration < 0)
    corrupt(clip_name + " has a duration that is not finite");
  clip.duration_s = anim->mDuration / ticks;
  if (anim->mNumChannels > 0 && anim->mChannels == nullptr)
    corrupt(clip_name + " has no channel list");
  double last_key = 0;
  for (unsigned c = 0; c < anim->mNumChannels; ++c) {
    const aiNodeAnim* ch = anim->mChannels[c];
    if (ch == nullptr) corrupt(clip_name + ": channel " + std::to_string(c) + " is missing");
    NodeChannel channel;
    channel.node = find_node(ch->mNodeName);
    if (channel.node < 0) continue;  // keys for a node the file does not have: nothing moves
    if ((ch->mNumPositionKeys > 0 && !ch->mPositionKeys) ||
        (ch->mNumRotationKeys > 0 && !ch->mRotationKeys) ||
        (ch->mNumScalingKeys > 0 && !ch->mScalingKeys))
      corrupt(clip_name + ": channel of node '" + Printable(ch->mNodeName.C_Str()) +
              "' has no keys");
    auto time_of = [&](double ticks_value) {
      if (!std::isfinite(ticks_value)) corrupt(clip_name + " has a key time that is not finite");
      last_key = std::max(last_key, ticks_value / ticks);
      return ticks_value / ticks;
    };
    auto vec = [&](const aiVector3D& v) {
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        corrupt(clip_name + " has a key value that is not finite");
      return Vec3(v.x, v.y, v.z);
    };
    for (unsigned k = 0; k < ch->mNumPositionKeys; ++k)
      channel.position.emplace_back(time_of(ch->mPositionKeys[k].mTime),
                                    vec(ch->mPositionKeys[k].mValue));
    for (unsigned k = 0; k < ch->mNumScalingKeys; ++k)
      channel.scaling.emplace_back(time_of(ch->mScalingKeys[k].mTime),
                                   vec(ch->mScalingKeys[k].mValue));
    for (unsigned k = 0; k < ch->mNumRotationKeys; ++k) {
      const aiQuaternion& q = ch->mRotationKeys[k].mValue;
      Eigen::Quaterniond e(q.w, q.x, q.y, q.z);
      if (!e.coeffs().allFinite() || !(e.norm() > 1e-6))
        corrupt(clip_name + " has a rotation key that is not a rotation");
      channel.rotation.emplace_back(time_of(ch->mRotationKeys[k].mTime), e.normalized());
    }
    auto by_time = [](const auto& x, const auto& y) { return x.first < y.first; };
    std::stable_sort(channel.position.begin(), channel.position.end(), by_time);
    std::stable_sort(channel.rotation.begin(), channel.rotation.end(), by_time);
    std::stable_sort(channel.scaling.begin(), channel.scaling.end(), by_time);
    clip.channels.push_back(std::move(channel));
  }
  if (!(clip.duration_s > 0)) clip.duration_s = last_key;
  return clip;
}

// The influences of each vertex of `mesh`, as bone indices of the part; adds the mesh's bones to
// the part's binding.
template <class Corrupt, class FindNode>
std::vector<std::vector<std::pair<int, double>>> MeshInfluences(const aiMesh& mesh,
                                                                const Corrupt& corrupt,
                                                                const FindNode& find_node,
                                                                SkinnedPart* part) {
  SkinnedPart& p = *part;
  std::vector<std::vector<std::pair<int, double>>> infl(mesh.mNumVertices);
  for (unsigned b = 0; b < mesh.mNumBones; ++b) {
    const aiBone& bone = *mesh.mBones[b];
    const int bone_node = find_node(bone.mName);
    if (bone_node < 0)
      corrupt("bone '" + Printable(bone.mName.C_Str()) + "' names no node of the file");
    const Eigen::Matrix4d offset = ToEigen(bone.mOffsetMatrix);
    if (!Finite(offset))
      corrupt("bone '" + Printable(bone.mName.C_Str()) +
              "' has an offset matrix that is not finite");
    const int index = int(p.binding.bones.size());
    p.binding.bones.emplace_back(bone_node, offset);
    if (bone.mNumWeights > 0 && bone.mWeights == nullptr)
      corrupt("bone '" + Printable(bone.mName.C_Str()) + "' has no weights");
    for (unsigned w = 0; w < bone.mNumWeights; ++w) {
      // Checked before post-processing, and again: assimp's steps keep damaged weights.
      const aiVertexWeight& vw = bone.mWeights[w];
      if (vw.mVertexId >= mesh.mNumVertices || !std::isfinite(vw.mWeight) || vw.mWeight < 0)
        corrupt("bone '" + Printable(bone.mName.C_Str()) +
                "' weighs a vertex past the end of its mesh, or by a "
                "negative or non-finite weight");
      if (vw.mWeight > 0) infl[vw.mVertexId].emplace_back(index, vw.mWeight);
    }
  }
  return infl;
}

// Adds the vertices (welded) and triangles of `mesh`, placed by node `mesh_node`, to a part.
template <class Corrupt, class FindNode>
void AddSkinnedMesh(const aiMesh& mesh, int mesh_node, const std::string& path,
                    const Corrupt& corrupt, const FindNode& find_node, SkinnedPart* part) {
  SkinnedPart& p = *part;
  // Influences of each vertex of this mesh, as bone indices of the part.
  std::vector<std::vector<std::pair<int, double>>> infl =
      MeshInfluences(mesh, corrupt, find_node, &p);
  std::vector<int> remap(mesh.mNumVertices);
  for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
    const aiVector3D& x = mesh.mVertices[v];
    if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
      throw InputError(path, "", "cannot read mesh file: a vertex has non-finite coordinates");
    auto& list = infl[v];
    double sum = 0;
    for (const auto& [b, w] : list) sum += w;
    if (!(sum > 0)) {
      // No weight: the vertex hangs rigidly on its mesh's node.
      list.clear();
      int bone = -1;
      for (std::size_t b = 0; b < p.binding.bones.size(); ++b)
        if (p.binding.bones[b].first == mesh_node &&
            p.binding.bones[b].second == Eigen::Matrix4d::Identity())
          bone = int(b);
      if (bone < 0) {
        bone = int(p.binding.bones.size());
        p.binding.bones.emplace_back(mesh_node, Eigen::Matrix4d::Identity());
      }
      list.emplace_back(bone, 1.0);
    } else {
      for (auto& bw : list) bw.second /= sum;
    }
    std::sort(list.begin(), list.end());
    std::vector<double> key{double(x.x), double(x.y), double(x.z)};
    for (const auto& [b, w] : list) {
      // Bones are keyed by node and offset, so equal influences from two meshes weld.
      key.push_back(double(p.binding.bones[b].first));
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) key.push_back(p.binding.bones[b].second(r, c));
      key.push_back(w);
    }
    auto [it, added] = p.weld.emplace(std::move(key), int(p.binding.mesh_vertices.size()));
    if (added) {
      p.binding.mesh_vertices.emplace_back(x.x, x.y, x.z);
      if (p.binding.first.empty()) p.binding.first.push_back(0);
      p.binding.influences.insert(p.binding.influences.end(), list.begin(), list.end());
      p.binding.first.push_back(int(p.binding.influences.size()));
    }
    remap[v] = it->second;
  }
  TriangleMesh& out = p.part.mesh;
  for (unsigned f = 0; f < mesh.mNumFaces; ++f)
    AppendTriangle(
        mesh, mesh.mFaces[f], path, [&remap](unsigned v) { return remap[v]; }, &out);
}

}  // namespace

SkinnedMeshFile LoadSkinnedMeshFile(const std::string& path) {
  return ReadCheckedFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType,
      [&](const aiScene& scene) {
        auto corrupt = [&](const std::string& detail) {
          throw InputError(path, "", "cannot read mesh file: corrupt animation data: " + detail,
                           "the file is damaged; export it again");
        };
        auto skeleton = std::make_shared<Skeleton>();
        std::map<const aiNode*, int> node_index;
        if (scene.mRootNode == nullptr) corrupt("the file has no node tree");
        ReadNodes(scene.mRootNode, skeleton.get(), &node_index);
        for (const SkeletonNode& n : skeleton->nodes)
          if (!Finite(n.rest_local))
            corrupt("node '" + Printable(n.name) + "' has a transform that is not finite");
        auto find_node = [&](const aiString& name) {
          for (std::size_t i = 0; i < skeleton->nodes.size(); ++i)
            if (skeleton->nodes[i].name == name.C_Str()) return int(i);
          return -1;
        };

        // Clips: key times in seconds, quaternions normalised in double.
        if (scene.mNumAnimations == 0 || scene.mAnimations == nullptr)
          throw InputError(
              path, "", "mesh file has no animation",
              "\"animation\" needs a file with an animation clip (glTF, FBX, COLLADA with bones "
              "and keyframes); remove \"animation\" for a still object");
        for (unsigned a = 0; a < scene.mNumAnimations; ++a) {
          const aiAnimation* anim = scene.mAnimations[a];
          SkinClip clip = ReadSkinClip(anim, a, corrupt, find_node);
          skeleton->clips.push_back(std::move(clip));
        }

        // Vertices per material: the file's mesh-space positions and their influences; welded where
        // both the position and the influences are equal.
        std::map<unsigned, SkinnedPart> parts;
        const fs::path folder = fs::path(path).parent_path();
        // Nodes in the skeleton's order (depth first, file order), each mesh where a node places
        // it.
        std::vector<const aiNode*> order(node_index.size());
        for (const auto& [node, i] : node_index) order[i] = node;
        for (const aiNode* node : order) {
          const int mesh_node = node_index.at(node);
          for (unsigned n = 0; n < node->mNumMeshes; ++n) {
            if (node->mMeshes[n] >= scene.mNumMeshes || scene.mMeshes[node->mMeshes[n]] == nullptr)
              corrupt("node '" + Printable(node->mName.C_Str()) +
                      "' names a mesh the file does not have");
            const aiMesh& mesh = *scene.mMeshes[node->mMeshes[n]];
            if (!(mesh.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
            if (mesh.mNumBones > 0 && mesh.mBones == nullptr) corrupt("a mesh has no bone list");
            for (unsigned b = 0; b < mesh.mNumBones; ++b)
              if (mesh.mBones[b] == nullptr) corrupt("a mesh has a missing bone");
            SkinnedPart& p = parts[mesh.mMaterialIndex];
            AddSkinnedMesh(mesh, mesh_node, path, corrupt, find_node, &p);
          }
        }

        SkinnedMeshFile result;
        const std::vector<Eigen::Matrix4d> rest = skeleton->Globals(-1, 0);
        for (auto& [material_index, p] : parts) {
          if (p.part.mesh.triangles.empty()) continue;
          p.part.mesh.vertices = p.binding.Skin(rest);
          for (const Vec3& v : p.part.mesh.vertices)
            if (!v.allFinite()) corrupt("the rest pose has a vertex that is not finite");
          p.part.material_name = "material" + std::to_string(material_index);
          if (material_index < scene.mNumMaterials) {
            const aiMaterial& material = *scene.mMaterials[material_index];
            aiString name;
            if (material.Get(AI_MATKEY_NAME, name) == AI_SUCCESS && name.length > 0)
              p.part.material_name = name.C_Str();
            p.part.has_material = p.part.material_name != AI_DEFAULT_MATERIAL_NAME;
            if (p.part.has_material) {
              MaterialColor(material, &p.part.color);
              p.part.texture = MaterialTexture(material, folder);
            }
          }
          result.parts.push_back(std::move(p.part));
          result.bindings.push_back(std::make_shared<const SkinBinding>(std::move(p.binding)));
        }
        if (result.parts.empty())
          throw InputError(path, "", "mesh file has no triangles",
                           "points and lines are ignored; export the surfaces as polygons");
        result.skeleton = std::move(skeleton);
        return result;
      });
}

ScopedMeshImportBudget::ScopedMeshImportBudget(double bytes, std::string where)
    : previous_bytes_(g_import_budget), previous_where_(g_import_budget_where) {
  g_import_budget = bytes > 0 && std::isfinite(bytes) ? bytes : 0;
  g_import_budget_where = std::move(where);
}

ScopedMeshImportBudget::~ScopedMeshImportBudget() {
  g_import_budget = previous_bytes_;
  g_import_budget_where = previous_where_;
}

bool ScopedMeshImportBudget::active() { return g_import_budget > 0; }

}  // namespace pandora
