// A rig in OpenCV YAML, COLMAP text, glTF and an installation sheet (analysis/rig/rig_formats.h,
// docs/tool-chain.md).
#include "analysis/rig/rig_formats.h"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "analysis/geometry/pose.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

using json = nlohmann::json;

// Imported values beyond these are damage, not calibration (scene-format limits where they exist).
constexpr double kMaxFocalPx = 1e7;
constexpr double kMaxPrincipalPx = 1e7;
constexpr double kMaxCoefficient = 1e6;
constexpr int kMaxResolution = 65536;

std::string Num(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v == 0 ? 0.0 : v);  // no "-0"
  return text;
}

// A double as OpenCV writes reals: with a '.' or an exponent, so that it reads back as a real.
std::string Real(double v) {
  std::string s = Num(v);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".";
  return s;
}

// Long double text for COLMAP's principal point (Pandora's + 0.5): 21 digits carry a 64-bit
// mantissa, so that reading back and subtracting 0.5 in long double gives Pandora's value exactly.
std::string LongNum(long double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.21Lg", v);
  return text;
}

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::string line;
  std::istringstream in(text);
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// Strict number: the whole token, finite.
bool ParseDouble(const std::string& token, long double* out) {
  if (token.empty()) return false;
  const char* begin = token.c_str();
  char* end = nullptr;
  errno = 0;
  const long double v = std::strtold(begin, &end);
  if (end == begin || *end != '\0' || errno == ERANGE || !std::isfinite(v)) return false;
  // strtold accepts "nan", "inf", hex floats: only decimal text here.
  for (char c : token)
    if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+' ||
          c == 'e' || c == 'E'))
      return false;
  *out = v;
  return true;
}

bool ParseInt(const std::string& token, long long min, long long max, long long* out) {
  if (token.empty() || token.size() > 18) return false;
  std::size_t i = token[0] == '-' || token[0] == '+' ? 1 : 0;
  if (i == token.size()) return false;
  for (std::size_t j = i; j < token.size(); ++j)
    if (!std::isdigit(static_cast<unsigned char>(token[j]))) return false;
  const long long v = std::stoll(token);
  if (v < min || v > max) return false;
  *out = v;
  return true;
}

// Checks the values every imported camera must have, then builds it. `fail(field, reason)` throws.
template <class Fail>
Camera MakeCamera(const std::string& id, const std::string& name, Intrinsics k, const Mat3& r_cw,
                  const Vec3& t_cw, const Fail& fail) {
  if (!(k.fx > 0 && k.fx <= kMaxFocalPx) || !(k.fy > 0 && k.fy <= kMaxFocalPx))
    fail("focal length",
         "fx and fy must be in (0, 1e7] pixels, got " + Num(k.fx) + ", " + Num(k.fy));
  if (!(std::abs(k.cx) <= kMaxPrincipalPx) || !(std::abs(k.cy) <= kMaxPrincipalPx))
    fail("principal point",
         "cx and cy must be within 1e7 pixels, got " + Num(k.cx) + ", " + Num(k.cy));
  for (double c : {k.k1, k.k2, k.p1, k.p2, k.k3, k.k4})
    if (!(std::abs(c) <= kMaxCoefficient))
      fail("distortion", "coefficient " + Num(c) + " is beyond 1e6 in magnitude");
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(r_cw(i, j))) fail("rotation", "not finite");
  const double orthogonality = (r_cw.transpose() * r_cw - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (!(orthogonality <= 1e-6) || !(r_cw.determinant() > 0))
    fail("rotation", "not a rotation matrix (R^T R differs from I by " + Num(orthogonality) +
                         ", det " + Num(r_cw.determinant()) + ")");
  const Vec3 centre = -(r_cw.transpose() * t_cw);
  if (!(centre.cwiseAbs().maxCoeff() <= SceneLimits::kMaxCoordinate))
    fail("translation", "the camera centre lies beyond 1e7 m");
  // Ids and names become JSON strings of the scene file: printable UTF-8 only.
  if (const std::string bad = CheckPrintableUtf8(id); !bad.empty())
    fail("id", "the camera id holds " + bad);
  if (const std::string bad = CheckPrintableUtf8(name); !bad.empty())
    fail("name", "the camera name holds " + bad);
  Camera camera;
  camera.id = id;
  camera.name = name.empty() ? id : name;
  camera.world_from_camera.linear() = r_cw.transpose();
  camera.world_from_camera.translation() = centre;
  camera.model = CameraModel(k);
  return camera;
}

// ---------------------------------------------------------------------------------------------
// OpenCV YAML: a tree of maps, sequences and scalars, for the block layout FileStorage writes.

struct YNode {
  enum Kind { kScalar, kMap, kSeq } kind = kScalar;
  int line = 0;
  std::string text;
  bool quoted = false;
  std::string tag;
  std::vector<std::pair<std::string, YNode>> map;
  std::vector<YNode> seq;

  const YNode* Find(const std::string& key) const {
    for (const auto& [k, v] : map)
      if (k == key) return &v;
    return nullptr;
  }
};

class YamlReader {
 public:
  YamlReader(const std::string& text, const std::string& path) : path_(path) {
    const std::vector<std::string> raw = SplitLines(text);
    bool header = false;
    for (std::size_t i = 0; i < raw.size(); ++i) {
      std::string s = raw[i];
      if (!s.empty() && s.back() == '\r') s.pop_back();
      const int number = static_cast<int>(i) + 1;
      for (unsigned char c : s)
        if (c < 0x20 && c != '\t') Fail(number, "", "control character in the text");
      if (!header) {
        if (Trim(s).empty()) continue;
        if (s.rfind("%YAML:1.", 0) != 0 && s.rfind("%YAML 1.", 0) != 0)
          Fail(number, "", "not an OpenCV YAML file: the first line must be %YAML:1.0",
               "cv::FileStorage writes YAML starting with %YAML:1.0");
        header = true;
        continue;
      }
      const std::string content = StripComment(s, number);
      if (Trim(content).empty()) continue;
      if (Trim(content) == "---" && lines_.empty()) continue;
      if (Trim(content) == "...") continue;
      const std::size_t indent = content.find_first_not_of(' ');
      if (content[indent] == '\t') Fail(number, "", "tab in the indentation");
      lines_.push_back({number, static_cast<int>(indent), Trim(content)});
    }
    if (!header) Fail(0, "", "empty file", "cv::FileStorage writes YAML starting with %YAML:1.0");
  }

  YNode Parse() {
    if (lines_.empty()) Fail(0, "", "no content after the %YAML line");
    std::size_t i = 0;
    YNode root = Block(&i, lines_[0].indent, 0, "");
    if (i != lines_.size()) Fail(lines_[i].number, "", "unexpected indentation");
    return root;
  }

  [[noreturn]] void Fail(int line, const std::string& field, const std::string& reason,
                         const std::string& hint = "") const {
    std::string where = line > 0 ? "line " + std::to_string(line) : "";
    if (!field.empty()) where += (where.empty() ? "" : ": ") + field;
    throw InputError(path_, where, reason, hint);
  }

 private:
  struct Line {
    int number;
    int indent;
    std::string text;
  };

  std::string StripComment(const std::string& s, int number) const {
    char quote = 0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      const char c = s[i];
      if (quote) {
        if (c == '\\' && quote == '"') {
          ++i;
          continue;
        }
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '#' && (i == 0 || s[i - 1] == ' ' || s[i - 1] == '\t')) {
        return s.substr(0, i);
      }
    }
    (void)number;
    return s;
  }

  YNode Block(std::size_t* i, int indent, int depth, const std::string& field) {
    if (depth > 16) Fail(lines_[*i].number, field, "nested too deeply");
    YNode node;
    node.line = lines_[*i].number;
    const bool sequence = lines_[*i].text == "-" || lines_[*i].text.rfind("- ", 0) == 0;
    node.kind = sequence ? YNode::kSeq : YNode::kMap;
    while (*i < lines_.size() && lines_[*i].indent == indent) {
      const Line line = lines_[*i];
      const bool item = line.text == "-" || line.text.rfind("- ", 0) == 0;
      if (item != sequence)
        Fail(line.number, field,
             sequence ? "expected a sequence item '-'" : "expected 'key: value'");
      ++*i;
      if (sequence) {
        const std::string sub = field + "[" + std::to_string(node.seq.size()) + "]";
        if (line.text == "-") {
          if (*i >= lines_.size() || lines_[*i].indent <= indent)
            Fail(line.number, sub, "empty sequence item");
          node.seq.push_back(Block(i, lines_[*i].indent, depth + 1, sub));
        } else {
          node.seq.push_back(Value(Trim(line.text.substr(2)), line.number, i, indent, depth, sub));
        }
      } else {
        const std::size_t colon = FindColon(line.text);
        if (colon == std::string::npos) Fail(line.number, field, "expected 'key: value'");
        const std::string key = Trim(line.text.substr(0, colon));
        const std::string sub = field.empty() ? key : field + "." + key;
        if (key.empty()) Fail(line.number, field, "empty key");
        for (const auto& [k, v] : node.map)
          if (k == key) Fail(line.number, sub, "key '" + key + "' appears twice");
        node.map.emplace_back(
            key, Value(Trim(line.text.substr(colon + 1)), line.number, i, indent, depth, sub));
      }
    }
    if (*i < lines_.size() && lines_[*i].indent > indent)
      Fail(lines_[*i].number, field, "unexpected indentation");
    return node;
  }

  static std::size_t FindColon(const std::string& s) {
    if (!s.empty() && (s[0] == '"' || s[0] == '\'')) return std::string::npos;
    for (std::size_t i = 0; i < s.size(); ++i)
      if (s[i] == ':' && (i + 1 == s.size() || s[i + 1] == ' ')) return i;
    return std::string::npos;
  }

  // The value after "key:" or "- " on line `number`; nested blocks start at line *i.
  YNode Value(std::string rest, int number, std::size_t* i, int indent, int depth,
              const std::string& field) {
    std::string tag;
    if (rest.rfind("!!", 0) == 0) {
      const std::size_t space = rest.find(' ');
      tag = rest.substr(0, space);
      rest = space == std::string::npos ? "" : Trim(rest.substr(space));
      if (tag != "!!opencv-matrix") Fail(number, field, "unsupported tag " + tag);
    }
    if (rest.empty()) {
      if (*i >= lines_.size() || lines_[*i].indent <= indent) Fail(number, field, "missing value");
      YNode node = Block(i, lines_[*i].indent, depth + 1, field);
      node.tag = tag;
      node.line = number;  // the key's line
      return node;
    }
    if (!tag.empty()) Fail(number, field, "a matrix must be a block of rows, cols, dt, data");
    if (rest[0] == '{') Fail(number, field, "flow mappings ({...}) are not supported");
    if (rest[0] == '[') {
      // A flow sequence, possibly continued on more lines.
      while (rest.find(']') == std::string::npos) {
        if (*i >= lines_.size() || lines_[*i].indent <= indent)
          Fail(number, field, "unterminated '[' sequence");
        rest += " " + lines_[*i].text;
        ++*i;
      }
      const std::size_t close = rest.find(']');
      if (Trim(rest.substr(close + 1)) != "") Fail(number, field, "text after ']'");
      if (rest.find('[', 1) != std::string::npos)
        Fail(number, field, "nested sequences are not supported");
      YNode node;
      node.kind = YNode::kSeq;
      node.line = number;
      const std::string inner = Trim(rest.substr(1, close - 1));
      if (!inner.empty()) {
        std::size_t start = 0;
        while (true) {
          const std::size_t comma = inner.find(',', start);
          const std::string item = Trim(inner.substr(start, comma - start));
          if (item.empty()) Fail(number, field, "empty item in a '[...]' sequence");
          node.seq.push_back(Scalar(item, number, field));
          if (comma == std::string::npos) break;
          start = comma + 1;
        }
      }
      return node;
    }
    return Scalar(rest, number, field);
  }

  YNode Scalar(const std::string& text, int number, const std::string& field) const {
    YNode node;
    node.line = number;
    if (text[0] == '"' || text[0] == '\'') {
      const char quote = text[0];
      std::string value;
      std::size_t j = 1;
      for (; j < text.size() && text[j] != quote; ++j) {
        if (text[j] == '\\' && quote == '"') {
          if (++j >= text.size()) break;
          switch (text[j]) {
            case 'n':
              value += '\n';
              break;
            case 't':
              value += '\t';
              break;
            case 'r':
              value += '\r';
              break;
            case '\\':
              value += '\\';
              break;
            case '"':
              value += '"';
              break;
            case '\'':
              value += '\'';
              break;
            default:
              Fail(number, field, std::string("unknown escape \\") + text[j]);
          }
        } else {
          value += text[j];
        }
      }
      if (j >= text.size()) Fail(number, field, "unterminated quoted string");
      if (j + 1 != text.size()) Fail(number, field, "text after the closing quote");
      node.text = value;
      node.quoted = true;
      return node;
    }
    node.text = text;
    return node;
  }

  std::string path_;
  std::vector<Line> lines_;
};

std::string QuoteYaml(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\')
      out += '\\', out += c;
    else if (c == '\n')
      out += "\\n";
    else if (c == '\t')
      out += "\\t";
    else if (static_cast<unsigned char>(c) < 0x20)
      throw InputError("", "", "camera id or name " + json(s).dump() + " holds a control character",
                       "OpenCV YAML cannot carry it; rename the camera");
    else
      out += c;
  }
  return out + "\"";
}

void WriteMatrix(std::string& out, const std::string& indent, const std::string& key, int rows,
                 int cols, const std::vector<double>& data) {
  out += indent + key + ": !!opencv-matrix\n";
  out += indent + "   rows: " + std::to_string(rows) + "\n";
  out += indent + "   cols: " + std::to_string(cols) + "\n";
  out += indent + "   dt: d\n";
  out += indent + "   data: [ ";
  for (std::size_t i = 0; i < data.size(); ++i) {
    out += Real(data[i]);
    if (i + 1 < data.size()) out += (i % 3 == 2) ? ",\n" + indent + "       " : ", ";
  }
  out += " ]\n";
}

class OpenCvCameraReader {
 public:
  OpenCvCameraReader(const YamlReader& reader, const YNode& node, std::string field)
      : reader_(reader), node_(node), field_(std::move(field)) {}

  const YNode* FindAny(std::initializer_list<const char*> keys, std::string* used = nullptr) const {
    const YNode* found = nullptr;
    for (const char* k : keys)
      if (const YNode* n = node_.Find(k)) {
        if (found) reader_.Fail(n->line, Sub(k), "given twice under different names");
        found = n;
        if (used) *used = k;
      }
    return found;
  }
  const YNode& Get(std::initializer_list<const char*> keys, std::string* used) const {
    const YNode* n = FindAny(keys, used);
    if (!n) reader_.Fail(node_.line, Sub(*keys.begin()), "missing field");
    return *n;
  }
  std::string Sub(const std::string& key) const {
    return field_.empty() ? key : field_ + "." + key;
  }

  long long Int(const YNode& n, const std::string& field, long long min, long long max) const {
    long long v = 0;
    if (n.kind != YNode::kScalar || n.quoted || !ParseInt(n.text, min, max, &v))
      reader_.Fail(n.line, field,
                   "expected a whole number in [" + std::to_string(min) + ", " +
                       std::to_string(max) + "], got " + Describe(n));
    return v;
  }
  double Real(const YNode& n, const std::string& field) const {
    long double v = 0;
    if (n.kind != YNode::kScalar || n.quoted || !ParseDouble(n.text, &v) ||
        !std::isfinite(static_cast<double>(v)))
      reader_.Fail(n.line, field, "expected a finite number, got " + Describe(n));
    return static_cast<double>(v);
  }
  std::string String(const YNode& n, const std::string& field) const {
    if (n.kind != YNode::kScalar) reader_.Fail(n.line, field, "expected a string");
    return n.text;
  }
  static std::string Describe(const YNode& n) {
    if (n.kind == YNode::kMap) return "a map";
    if (n.kind == YNode::kSeq) return "a sequence";
    return "'" + n.text.substr(0, 40) + "'";
  }

  // An !!opencv-matrix: returns rows, cols and the data.
  std::vector<double> Matrix(const YNode& m, const std::string& field, int* rows, int* cols) const {
    if (m.kind != YNode::kMap || m.tag != "!!opencv-matrix")
      reader_.Fail(m.line, field, "expected an !!opencv-matrix");
    for (const auto& [k, v] : m.map)
      if (k != "rows" && k != "cols" && k != "dt" && k != "data")
        reader_.Fail(v.line, field + "." + k, "unknown matrix field (rows, cols, dt, data)");
    const YNode* r = m.Find("rows");
    const YNode* c = m.Find("cols");
    const YNode* dt = m.Find("dt");
    const YNode* data = m.Find("data");
    if (!r || !c || !dt || !data)
      reader_.Fail(m.line, field, "a matrix needs rows, cols, dt and data");
    *rows = static_cast<int>(Int(*r, field + ".rows", 1, 16));
    *cols = static_cast<int>(Int(*c, field + ".cols", 1, 16));
    const std::string type = String(*dt, field + ".dt");
    if (type != "d" && type != "f")
      reader_.Fail(dt->line, field + ".dt", "expected d or f (a real matrix), got '" + type + "'");
    if (data->kind != YNode::kSeq)
      reader_.Fail(data->line, field + ".data", "expected a '[...]' sequence of numbers");
    const std::size_t n = static_cast<std::size_t>(*rows) * static_cast<std::size_t>(*cols);
    if (data->seq.size() != n)
      reader_.Fail(data->line, field + ".data",
                   "expected " + std::to_string(n) + " numbers (rows x cols), got " +
                       std::to_string(data->seq.size()));
    std::vector<double> values;
    for (std::size_t i = 0; i < n; ++i)
      values.push_back(Real(data->seq[i], field + ".data[" + std::to_string(i) + "]"));
    return values;
  }

  Camera Read(const std::string& default_id) const {
    for (const auto& [k, v] : node_.map) {
      static const std::set<std::string> known = {
          "id", "name", "image_width", "image_height", "camera_matrix", "K", "cameraMatrix",
          "distortion_model", "distortion_coefficients", "D", "dist_coeffs", "distCoeffs", "R", "T",
          "rvec", "tvec",
          // What calibration tools add beside the camera: kept out of the rig.
          "calibration_time", "calibrationDate", "nframes", "nr_of_frames", "board_width",
          "board_height", "square_size", "flags", "fix_aspect_ratio", "avg_reprojection_error",
          "rms", "per_view_reprojection_errors", "extrinsic_parameters", "image_points",
          "grid_points", "rig", "camera_count"};
      if (!known.count(k))
        reader_.Fail(
            v.line, Sub(k), "unknown field '" + k + "'",
            "the fields of a camera are id, name, image_width, image_height, camera_matrix, "
            "distortion_model, distortion_coefficients, R, T (docs/tool-chain.md)");
    }
    std::string id = default_id, name;
    if (const YNode* n = node_.Find("id")) {
      id = String(*n, Sub("id"));
      if (id.empty()) reader_.Fail(n->line, Sub("id"), "empty camera id");
    }
    if (const YNode* n = node_.Find("name")) name = String(*n, Sub("name"));
    Intrinsics k;
    k.width =
        static_cast<int>(Int(Get({"image_width"}, nullptr), Sub("image_width"), 1, kMaxResolution));
    k.height = static_cast<int>(
        Int(Get({"image_height"}, nullptr), Sub("image_height"), 1, kMaxResolution));
    std::string used;
    int rows = 0, cols = 0;
    const YNode& km = Get({"camera_matrix", "K", "cameraMatrix"}, &used);
    const std::vector<double> m = Matrix(km, Sub(used), &rows, &cols);
    if (rows != 3 || cols != 3) reader_.Fail(km.line, Sub(used), "expected a 3x3 matrix");
    if (m[1] != 0 || m[3] != 0 || m[6] != 0 || m[7] != 0 || m[8] != 1)
      reader_.Fail(km.line, Sub(used),
                   "expected [fx 0 cx; 0 fy cy; 0 0 1] (no skew), got a different layout");
    k.fx = m[0];
    k.cx = m[2];
    k.fy = m[4];
    k.cy = m[5];

    std::string model = "brown_conrady";
    const YNode* model_node = node_.Find("distortion_model");
    if (model_node) model = String(*model_node, Sub("distortion_model"));
    if (model != "pinhole" && model != "brown_conrady" && model != "fisheye")
      reader_.Fail(
          model_node->line, Sub("distortion_model"), "unknown distortion model '" + model + "'",
          "pinhole, brown_conrady (OpenCV's k1 k2 p1 p2 k3) or fisheye (cv::fisheye k1..k4)");
    const YNode* d = FindAny({"distortion_coefficients", "D", "dist_coeffs", "distCoeffs"}, &used);
    std::vector<double> coefficients;
    if (d) {
      coefficients = Matrix(*d, Sub(used), &rows, &cols);
      if (rows != 1 && cols != 1) reader_.Fail(d->line, Sub(used), "expected a 1xN or Nx1 vector");
    } else if (model != "pinhole") {
      reader_.Fail(node_.line, Sub("distortion_coefficients"), "missing field");
    }
    const std::size_t n = coefficients.size();
    const int line = d ? d->line : node_.line;
    if (model == "pinhole") {
      k.model = LensModel::kPinhole;
      for (double c : coefficients)
        if (c != 0) reader_.Fail(line, Sub(used), "a pinhole camera's coefficients must be zero");
    } else if (model == "fisheye") {
      k.model = LensModel::kFisheye;
      if (n != 4)
        reader_.Fail(line, Sub(used),
                     "a fisheye lens has 4 coefficients, got " + std::to_string(n));
      k.k1 = coefficients[0], k.k2 = coefficients[1], k.k3 = coefficients[2],
      k.k4 = coefficients[3];
    } else {
      k.model = LensModel::kBrownConrady;
      if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
        reader_.Fail(line, Sub(used),
                     "OpenCV distortion vectors have 4, 5, 8, 12 or 14 coefficients, got " +
                         std::to_string(n));
      for (std::size_t i = 5; i < n; ++i)
        if (coefficients[i] != 0)
          reader_.Fail(line, Sub(used),
                       "coefficient " + std::to_string(i) +
                           " (rational, thin-prism or tilt term) is not "
                           "zero: Pandora models k1 k2 p1 p2 k3 only");
      k.k1 = coefficients[0], k.k2 = coefficients[1], k.p1 = coefficients[2],
      k.p2 = coefficients[3];
      if (n > 4) k.k3 = coefficients[4];
    }

    Mat3 r;
    const YNode* rn = FindAny({"R"});
    const YNode* rv = FindAny({"rvec"});
    if (rn && rv) reader_.Fail(rv->line, Sub("rvec"), "give R or rvec, not both");
    if (rn) {
      const std::vector<double> v = Matrix(*rn, Sub("R"), &rows, &cols);
      if (rows != 3 || cols != 3) reader_.Fail(rn->line, Sub("R"), "expected a 3x3 matrix");
      r << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
    } else if (rv) {
      const std::vector<double> v = Matrix(*rv, Sub("rvec"), &rows, &cols);
      if (v.size() != 3) reader_.Fail(rv->line, Sub("rvec"), "expected a 3x1 Rodrigues vector");
      const Vec3 w(v[0], v[1], v[2]);
      if (!(w.norm() <= 1e3)) reader_.Fail(rv->line, Sub("rvec"), "rotation angle beyond 1000 rad");
      r = w.norm() > 0 ? Mat3(Eigen::AngleAxisd(w.norm(), w.normalized())) : Mat3::Identity();
    } else {
      reader_.Fail(node_.line, Sub("R"), "missing field (the camera's pose: R or rvec, and T)");
    }
    const YNode& tn = Get({"T", "tvec"}, &used);
    const std::vector<double> t = Matrix(tn, Sub(used), &rows, &cols);
    if (t.size() != 3 || (rows != 3 && cols != 3))
      reader_.Fail(tn.line, Sub(used), "expected a 3x1 vector");
    // Each check names the field it concerns, at that field's line.
    const int d_line = d ? d->line : node_.line;
    const YNode* pose = rn ? rn : rv;
    const auto fail = [&](const std::string& what, const std::string& reason) {
      std::string key = "camera_matrix";
      int at = km.line;
      if (what == "rotation") key = rn ? "R" : "rvec", at = pose->line;
      if (what == "translation") key = used, at = tn.line;
      if (what == "distortion") key = "distortion_coefficients", at = d_line;
      reader_.Fail(at, Sub(key), reason);
    };
    return MakeCamera(id, name, k, r, Vec3(t[0], t[1], t[2]), fail);
  }

 private:
  const YamlReader& reader_;
  const YNode& node_;
  std::string field_;
};

// ---------------------------------------------------------------------------------------------
// COLMAP

std::string PercentEncode(const std::string& s) {
  std::string out;
  for (unsigned char c : s) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.') {
      out += static_cast<char>(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

bool PercentDecode(const std::string& s, std::string* out) {
  out->clear();
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '%') {
      *out += s[i];
      continue;
    }
    if (i + 2 >= s.size() || !std::isxdigit(static_cast<unsigned char>(s[i + 1])) ||
        !std::isxdigit(static_cast<unsigned char>(s[i + 2])))
      return false;
    *out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
    i += 2;
  }
  return true;
}

std::vector<std::string> Tokens(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  std::string t;
  while (in >> t) out.push_back(t);
  return out;
}

const char* kColmapImageExtensions[] = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".exr"};

}  // namespace

std::string RigToOpenCvYaml(const Rig& rig) {
  std::string out = "%YAML:1.0\n---\n";
  out += "rig: " + QuoteYaml(rig.name) + "\n";
  out += "camera_count: " + std::to_string(rig.cameras.size()) + "\n";
  out += "cameras:\n";
  for (const Camera& camera : rig.cameras) {
    const Intrinsics& k = camera.model.intrinsics();
    const std::string in = "      ";
    out += "   -\n";
    out += in + "id: " + QuoteYaml(camera.id) + "\n";
    out += in + "name: " + QuoteYaml(camera.name) + "\n";
    out += in + "image_width: " + std::to_string(k.width) + "\n";
    out += in + "image_height: " + std::to_string(k.height) + "\n";
    WriteMatrix(out, in, "camera_matrix", 3, 3, {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1});
    out += in + "distortion_model: " + LensModelName(k.model) + "\n";
    if (k.model == LensModel::kFisheye)
      WriteMatrix(out, in, "distortion_coefficients", 1, 4, {k.k1, k.k2, k.k3, k.k4});
    else if (k.model == LensModel::kBrownConrady)
      WriteMatrix(out, in, "distortion_coefficients", 1, 5, {k.k1, k.k2, k.p1, k.p2, k.k3});
    else
      WriteMatrix(out, in, "distortion_coefficients", 1, 5, {0, 0, 0, 0, 0});
    const Eigen::Isometry3d cw = camera.camera_from_world();
    const Mat3 r = cw.linear();
    const Vec3 t = cw.translation();
    WriteMatrix(out, in, "R", 3, 3,
                {r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)});
    WriteMatrix(out, in, "T", 3, 1, {t.x(), t.y(), t.z()});
  }
  return out;
}

Rig ParseOpenCvYaml(const std::string& text, const std::string& path) {
  YamlReader reader(text, path);
  const YNode root = reader.Parse();
  if (root.kind != YNode::kMap) reader.Fail(root.line, "", "expected a map at the top level");
  Rig rig;
  rig.name = std::filesystem::path(path).stem().string();
  const YNode* cameras = root.Find("cameras");
  if (!cameras) {
    // One camera as calibration tools write it.
    OpenCvCameraReader camera(reader, root, "");
    rig.cameras.push_back(camera.Read(rig.name.empty() ? "0" : rig.name));
    return rig;
  }
  for (const auto& [k, v] : root.map)
    if (k != "rig" && k != "camera_count" && k != "cameras")
      reader.Fail(v.line, k, "unknown field '" + k + "' beside 'cameras'",
                  "the top level holds rig, camera_count and cameras (docs/tool-chain.md)");
  if (const YNode* n = root.Find("rig")) {
    if (n->kind != YNode::kScalar || n->text.empty())
      reader.Fail(n->line, "rig", "expected the rig's name");
    rig.name = n->text;
  }
  if (cameras->kind != YNode::kSeq || cameras->seq.empty())
    reader.Fail(cameras->line, "cameras", "expected a non-empty sequence of cameras");
  if (static_cast<long long>(cameras->seq.size()) > SceneLimits::kMaxCameras)
    reader.Fail(cameras->line, "cameras", "more than 10000 cameras");
  if (const YNode* n = root.Find("camera_count")) {
    long long count = 0;
    if (n->kind != YNode::kScalar || !ParseInt(n->text, 1, SceneLimits::kMaxCameras, &count))
      reader.Fail(n->line, "camera_count", "expected a whole number in [1, 10000]");
    if (count != static_cast<long long>(cameras->seq.size()))
      reader.Fail(n->line, "camera_count",
                  "says " + std::to_string(count) + " cameras but 'cameras' holds " +
                      std::to_string(cameras->seq.size()));
  }
  for (std::size_t i = 0; i < cameras->seq.size(); ++i) {
    const YNode& c = cameras->seq[i];
    const std::string field = "cameras[" + std::to_string(i) + "]";
    if (c.kind != YNode::kMap) reader.Fail(c.line, field, "expected a map (a camera)");
    if (!c.Find("id")) reader.Fail(c.line, field + ".id", "missing field");
    Camera camera = OpenCvCameraReader(reader, c, field).Read("");
    if (rig.FindCamera(camera.id) >= 0)
      reader.Fail(c.Find("id")->line, field + ".id", "camera id '" + camera.id + "' appears twice");
    rig.cameras.push_back(std::move(camera));
  }
  return rig;
}

ColmapText RigToColmap(const Rig& rig) {
  ColmapText out;
  const std::size_t n = rig.cameras.size();
  out.cameras =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: " +
      std::to_string(n) + "\n";
  out.images =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: " +
      std::to_string(n) + ", mean observations per image: 0\n";
  out.points3d =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: 0, mean track length: 0\n";
  for (std::size_t i = 0; i < n; ++i) {
    const Camera& camera = rig.cameras[i];
    const Intrinsics& k = camera.model.intrinsics();
    const std::string id = std::to_string(i + 1);
    const std::string cx = LongNum(static_cast<long double>(k.cx) + 0.5L);
    const std::string cy = LongNum(static_cast<long double>(k.cy) + 0.5L);
    std::string line = id + " ";
    const std::string common = std::to_string(k.width) + " " + std::to_string(k.height) + " " +
                               Num(k.fx) + " " + Num(k.fy) + " " + cx + " " + cy;
    if (k.model == LensModel::kPinhole) {
      line += "PINHOLE " + common;
    } else if (k.model == LensModel::kFisheye) {
      line += "OPENCV_FISHEYE " + common + " " + Num(k.k1) + " " + Num(k.k2) + " " + Num(k.k3) +
              " " + Num(k.k4);
    } else if (k.k3 == 0) {
      line += "OPENCV " + common + " " + Num(k.k1) + " " + Num(k.k2) + " " + Num(k.p1) + " " +
              Num(k.p2);
    } else {
      line += "FULL_OPENCV " + common + " " + Num(k.k1) + " " + Num(k.k2) + " " + Num(k.p1) + " " +
              Num(k.p2) + " " + Num(k.k3) + " 0 0 0";
    }
    out.cameras += line + "\n";
    const Eigen::Isometry3d cw = camera.camera_from_world();
    Eigen::Quaterniond q(cw.linear());
    q.normalize();
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    const Vec3 t = cw.translation();
    out.images += id + " " + Num(q.w()) + " " + Num(q.x()) + " " + Num(q.y()) + " " + Num(q.z()) +
                  " " + Num(t.x()) + " " + Num(t.y()) + " " + Num(t.z()) + " " + id + " " +
                  PercentEncode(camera.id) + ".png\n\n";
  }
  return out;
}

namespace {

// A COLMAP camera: its intrinsics and the line of cameras.txt that gives them.
struct ColmapCamera {
  Intrinsics k;
  int line = 0;
};

// Throws the InputError of a line (and field) of a COLMAP text file.
void ColmapFail(const std::string& path, int line, const std::string& field,
                const std::string& reason, const std::string& hint = "") {
  throw InputError(path, "line " + std::to_string(line) + (field.empty() ? "" : ": " + field),
                   reason, hint);
}

// The intrinsics of a cameras.txt line from its model `m`, parameters `p` and size.
Intrinsics ColmapIntrinsics(const std::string& m, const std::vector<long double>& p, long long w,
                            long long h, const std::string& cameras_path, int number) {
  Intrinsics k;
  k.width = static_cast<int>(w);
  k.height = static_cast<int>(h);
  std::size_t next;
  if (m == "SIMPLE_PINHOLE" || m == "SIMPLE_RADIAL" || m == "RADIAL") {
    k.fx = k.fy = static_cast<double>(p[0]);
    k.cx = static_cast<double>(p[1] - 0.5L);
    k.cy = static_cast<double>(p[2] - 0.5L);
    next = 3;
  } else {
    k.fx = static_cast<double>(p[0]);
    k.fy = static_cast<double>(p[1]);
    k.cx = static_cast<double>(p[2] - 0.5L);
    k.cy = static_cast<double>(p[3] - 0.5L);
    next = 4;
  }
  const auto c = [&](std::size_t j) { return static_cast<double>(p[next + j]); };
  if (m == "SIMPLE_RADIAL" || m == "RADIAL") {
    k.model = LensModel::kBrownConrady;
    k.k1 = c(0);
    if (m == "RADIAL") k.k2 = c(1);
  } else if (m == "OPENCV" || m == "FULL_OPENCV") {
    k.model = LensModel::kBrownConrady;
    k.k1 = c(0), k.k2 = c(1), k.p1 = c(2), k.p2 = c(3);
    if (m == "FULL_OPENCV") {
      k.k3 = c(4);
      if (c(5) != 0 || c(6) != 0 || c(7) != 0)
        ColmapFail(
            cameras_path, number, "PARAMS[9..11]",
            "k4 k5 k6 (the rational model) are not zero: Pandora models k1 k2 p1 p2 k3 only");
    }
  } else if (m == "OPENCV_FISHEYE") {
    k.model = LensModel::kFisheye;
    k.k1 = c(0), k.k2 = c(1), k.k3 = c(2), k.k4 = c(3);
  }
  return k;
}

// The cameras of cameras.txt by CAMERA_ID.
std::map<long long, ColmapCamera> ReadColmapCameras(const std::string& cameras_text,
                                                    const std::string& cameras_path) {
  std::map<long long, ColmapCamera> cams;
  const std::vector<std::string> camera_lines = SplitLines(cameras_text);
  for (std::size_t i = 0; i < camera_lines.size(); ++i) {
    const int number = static_cast<int>(i) + 1;
    const std::string line = Trim(camera_lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> t = Tokens(line);
    if (t.size() < 4)
      ColmapFail(cameras_path, number, "", "expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    long long id = 0, w = 0, h = 0;
    if (!ParseInt(t[0], 0, 2147483647LL, &id))
      ColmapFail(cameras_path, number, "CAMERA_ID",
                 "expected a whole number, got '" + t[0].substr(0, 40) + "'");
    if (cams.count(id))
      ColmapFail(cameras_path, number, "CAMERA_ID", "camera " + t[0] + " appears twice");
    if (!ParseInt(t[2], 1, kMaxResolution, &w))
      ColmapFail(cameras_path, number, "WIDTH",
                 "expected a whole number in [1, 65536], got '" + t[2].substr(0, 40) + "'");
    if (!ParseInt(t[3], 1, kMaxResolution, &h))
      ColmapFail(cameras_path, number, "HEIGHT",
                 "expected a whole number in [1, 65536], got '" + t[3].substr(0, 40) + "'");
    static const std::map<std::string, std::size_t> kParams = {
        {"SIMPLE_PINHOLE", 3}, {"PINHOLE", 4},      {"SIMPLE_RADIAL", 4}, {"RADIAL", 5},
        {"OPENCV", 8},         {"FULL_OPENCV", 12}, {"OPENCV_FISHEYE", 8}};
    const auto model = kParams.find(t[1]);
    if (model == kParams.end())
      ColmapFail(
          cameras_path, number, "MODEL", "unsupported camera model '" + t[1].substr(0, 40) + "'",
          "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV, OPENCV_FISHEYE");
    if (t.size() - 4 != model->second)
      ColmapFail(cameras_path, number, "PARAMS",
                 model->first + " has " + std::to_string(model->second) + " parameters, got " +
                     std::to_string(t.size() - 4));
    std::vector<long double> p;
    for (std::size_t j = 4; j < t.size(); ++j) {
      long double v = 0;
      if (!ParseDouble(t[j], &v) || !(std::fabs(v) <= 1e300L))
        ColmapFail(cameras_path, number, "PARAMS[" + std::to_string(j - 4) + "]",
                   "expected a finite number, got '" + t[j].substr(0, 40) + "'");
      p.push_back(v);
    }
    const Intrinsics k = ColmapIntrinsics(model->first, p, w, h, cameras_path, number);
    cams[id] = {k, number};
  }
  if (cams.empty())
    ColmapFail(cameras_path, static_cast<int>(camera_lines.size()), "", "no cameras");
  return cams;
}

// The camera id an image line's NAME gives: percent-decoded, without an image extension.
std::string ColmapImageId(const std::vector<std::string>& t, const std::string& images_path,
                          int number) {
  std::string name = t[9], id;
  if (!PercentDecode(name, &id))
    ColmapFail(images_path, number, "NAME", "bad percent escape in '" + name.substr(0, 40) + "'");
  for (const char* ext : kColmapImageExtensions) {
    const std::size_t n = std::strlen(ext);
    if (id.size() > n) {
      std::string tail = id.substr(id.size() - n);
      for (char& ch : tail) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      if (tail == ext) {
        id.resize(id.size() - n);
        break;
      }
    }
  }
  if (id.empty()) ColmapFail(images_path, number, "NAME", "empty image name");
  if (const std::string bad = CheckPrintableUtf8(id); !bad.empty())
    ColmapFail(images_path, number, "NAME", "the image name (a camera id) holds " + bad);
  return id;
}

// Checks the POINTS2D line that follows image line `number`.
void CheckColmapPoints2d(const std::string& points_line, const std::string& images_path,
                         int number) {
  const std::vector<std::string> pts = Tokens(points_line);
  if (pts.size() % 3 != 0)
    ColmapFail(
        images_path, number + 1, "POINTS2D",
        "expected (X, Y, POINT3D_ID) triples, got " + std::to_string(pts.size()) + " numbers");
  for (std::size_t j = 0; j < pts.size(); ++j) {
    long double x = 0;
    long long pid = 0;
    const bool ok =
        j % 3 == 2 ? ParseInt(pts[j], -1, 9223372036854775807LL, &pid) : ParseDouble(pts[j], &x);
    if (!ok)
      ColmapFail(images_path, number + 1, "POINTS2D[" + std::to_string(j) + "]",
                 "expected a number, got '" + pts[j].substr(0, 40) + "'");
  }
}

}  // namespace

Rig ParseColmap(const std::string& cameras_text, const std::string& cameras_path,
                const std::string& images_text, const std::string& images_path,
                const std::string& rig_name) {
  std::map<long long, ColmapCamera> cams = ReadColmapCameras(cameras_text, cameras_path);

  Rig rig;
  rig.name = rig_name;
  std::set<long long> image_ids;
  const std::vector<std::string> image_lines = SplitLines(images_text);
  for (std::size_t i = 0; i < image_lines.size(); ++i) {
    const int number = static_cast<int>(i) + 1;
    const std::string line = Trim(image_lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> t = Tokens(line);
    if (t.size() != 10)
      ColmapFail(images_path, number, "",
                 "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (10 fields), got " +
                     std::to_string(t.size()));
    long long image_id = 0, camera_id = 0;
    if (!ParseInt(t[0], 0, 2147483647LL, &image_id))
      ColmapFail(images_path, number, "IMAGE_ID",
                 "expected a whole number, got '" + t[0].substr(0, 40) + "'");
    if (!image_ids.insert(image_id).second)
      ColmapFail(images_path, number, "IMAGE_ID", "image " + t[0] + " appears twice");
    static const char* kNames[] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
    double v[7];
    for (int j = 0; j < 7; ++j) {
      long double x = 0;
      if (!ParseDouble(t[1 + j], &x) || !(std::fabs(x) <= 1e300L))
        ColmapFail(images_path, number, kNames[j],
                   "expected a finite number, got '" + t[1 + j].substr(0, 40) + "'");
      v[j] = static_cast<double>(x);
    }
    if (!ParseInt(t[8], 0, 2147483647LL, &camera_id) || !cams.count(camera_id))
      ColmapFail(images_path, number, "CAMERA_ID",
                 "no camera '" + t[8].substr(0, 40) + "' in the cameras file");
    Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
    if (!(std::abs(q.norm() - 1) <= 1e-6))
      ColmapFail(images_path, number, "QW QX QY QZ",
                 "not a unit quaternion (norm " + Num(q.norm()) + ")");
    q.normalize();
    const std::string id = ColmapImageId(t, images_path, number);
    if (rig.FindCamera(id) >= 0)
      ColmapFail(images_path, number, "NAME", "two images give the camera id '" + id + "'");
    // The POINTS2D line follows directly (COLMAP reads it even when empty).
    if (i + 1 >= image_lines.size())
      ColmapFail(images_path, number, "POINTS2D", "missing the POINTS2D line after the image line");
    ++i;
    CheckColmapPoints2d(image_lines[i], images_path, number);
    if (static_cast<long long>(rig.cameras.size()) >= SceneLimits::kMaxCameras)
      ColmapFail(images_path, number, "", "more than 10000 images");
    const auto bad = [&](const std::string& what, const std::string& reason) {
      const int at = what == "rotation" || what == "translation" ? number : cams[camera_id].line;
      ColmapFail(what == "rotation" || what == "translation" ? images_path : cameras_path, at, what,
                 reason);
    };
    rig.cameras.push_back(
        MakeCamera(id, "", cams[camera_id].k, q.toRotationMatrix(), Vec3(v[4], v[5], v[6]), bad));
  }
  if (rig.cameras.empty())
    ColmapFail(images_path, static_cast<int>(image_lines.size()), "", "no images (one per camera)");
  return rig;
}

namespace {

template <class T>
void Append(std::string& buffer, T value) {
  buffer.append(reinterpret_cast<const char*>(&value), sizeof value);
}

// Pandora world (Z up) to glTF (Y up).
Mat3 GltfFromWorld() {
  Mat3 c;
  c << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return c;
}

}  // namespace

std::string SceneToGltf(const Scene& scene, const Rig& rig, bool binary) {
  const Mat3 c = GltfFromWorld();
  std::string buffer;
  json accessors = json::array(), views = json::array(), meshes = json::array(),
       materials = json::array(), nodes = json::array(), cameras = json::array();
  std::map<int, int> material_index;
  const auto material_of = [&](int m) {
    auto it = material_index.find(m);
    if (it != material_index.end()) return it->second;
    const Vec3 colour =
        m >= 0 ? scene.materials[static_cast<std::size_t>(m)].color : Vec3(0.7, 0.7, 0.7);
    materials.push_back(
        {{"name", m >= 0 ? scene.materials[static_cast<std::size_t>(m)].name : "default"},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {colour.x(), colour.y(), colour.z(), 1.0}},
           {"metallicFactor", 0.0},
           {"roughnessFactor", 1.0}}}});
    const int index = static_cast<int>(materials.size()) - 1;
    material_index[m] = index;
    return index;
  };
  for (const SceneObject& object : scene.objects) {
    if (object.mesh.triangles.empty()) continue;
    // Positions (float, glTF frame), then indices (uint32); each view 4-byte aligned.
    const std::size_t position_offset = buffer.size();
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f hi = -lo;
    for (const Vec3& v : object.mesh.vertices) {
      const Eigen::Vector3f p = (c * v).cast<float>();
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      Append(buffer, p.x()), Append(buffer, p.y()), Append(buffer, p.z());
    }
    const std::size_t index_offset = buffer.size();
    for (const Eigen::Vector3i& t : object.mesh.triangles)
      for (int j = 0; j < 3; ++j) Append(buffer, static_cast<std::uint32_t>(t[j]));
    const int view = static_cast<int>(views.size());
    views.push_back({{"buffer", 0},
                     {"byteOffset", position_offset},
                     {"byteLength", index_offset - position_offset},
                     {"target", 34962}});
    views.push_back({{"buffer", 0},
                     {"byteOffset", index_offset},
                     {"byteLength", buffer.size() - index_offset},
                     {"target", 34963}});
    const int accessor = static_cast<int>(accessors.size());
    accessors.push_back({{"bufferView", view},
                         {"componentType", 5126},
                         {"count", object.mesh.vertices.size()},
                         {"type", "VEC3"},
                         {"min", {lo.x(), lo.y(), lo.z()}},
                         {"max", {hi.x(), hi.y(), hi.z()}}});
    accessors.push_back({{"bufferView", view + 1},
                         {"componentType", 5125},
                         {"count", object.mesh.triangles.size() * 3},
                         {"type", "SCALAR"}});
    meshes.push_back({{"name", object.name},
                      {"primitives",
                       {{{"attributes", {{"POSITION", accessor}}},
                         {"indices", accessor + 1},
                         {"material", material_of(object.material)}}}}});
    nodes.push_back({{"name", object.name}, {"mesh", meshes.size() - 1}});
  }
  Mat3 flip = Mat3::Identity();
  flip(1, 1) = flip(2, 2) =
      -1;  // OpenCV camera (y down, z forward) -> glTF camera (y up, -z forward)
  for (const Camera& camera : rig.cameras) {
    const Intrinsics& k = camera.model.intrinsics();
    json perspective = {{"yfov", 2.0 * std::atan(0.5 * k.height / k.fy)},
                        {"aspectRatio", (double(k.width) * k.fy) / (double(k.height) * k.fx)},
                        {"znear", camera.near > 0 ? camera.near : 0.01}};
    if (std::isfinite(camera.far)) perspective["zfar"] = camera.far;
    cameras.push_back({{"name", camera.id}, {"type", "perspective"}, {"perspective", perspective}});
    const Mat3 r = c * camera.world_from_camera.linear() * flip;
    Eigen::Quaterniond q(r);
    q.normalize();
    const Vec3 p = c * camera.center();
    nodes.push_back({{"name", camera.id},
                     {"camera", cameras.size() - 1},
                     {"translation", {p.x(), p.y(), p.z()}},
                     {"rotation", {q.x(), q.y(), q.z(), q.w()}}});
  }
  json scene_nodes = json::array();
  for (std::size_t i = 0; i < nodes.size(); ++i) scene_nodes.push_back(i);
  json doc = {{"asset", {{"version", "2.0"}, {"generator", "pandora export-rig"}}},
              {"scene", 0},
              {"scenes", {{{"name", scene.path}, {"nodes", scene_nodes}}}},
              {"nodes", nodes}};
  if (!cameras.empty()) doc["cameras"] = cameras;
  if (!meshes.empty()) {
    doc["meshes"] = meshes;
    doc["materials"] = materials;
    doc["accessors"] = accessors;
    doc["bufferViews"] = views;
    doc["buffers"] = {{{"byteLength", buffer.size()}}};
    if (!binary)
      doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + Base64(buffer);
  }
  if (!binary) return doc.dump(1) + "\n";
  // GLB: a 12-byte header, a JSON chunk padded with spaces and a BIN chunk padded with zeros, each
  // a multiple of 4 bytes (glTF 2.0, "Binary glTF Layout").
  std::string text = doc.dump();
  while (text.size() % 4) text += ' ';
  while (buffer.size() % 4) buffer += '\0';
  std::string glb;
  const bool has_bin = !meshes.empty();
  const std::uint32_t total =
      static_cast<std::uint32_t>(12 + 8 + text.size() + (has_bin ? 8 + buffer.size() : 0));
  Append(glb, std::uint32_t{0x46546C67});  // "glTF"
  Append(glb, std::uint32_t{2});
  Append(glb, total);
  Append(glb, static_cast<std::uint32_t>(text.size()));
  Append(glb, std::uint32_t{0x4E4F534A});  // "JSON"
  glb += text;
  if (has_bin) {
    Append(glb, static_cast<std::uint32_t>(buffer.size()));
    Append(glb, std::uint32_t{0x004E4942});  // "BIN\0"
    glb += buffer;
  }
  return glb;
}

namespace {

std::string Csv(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string Fixed(double v, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, v);
  std::string s = text;
  // No "-0.0".
  if (s.find_first_not_of("-0.") == std::string::npos && s[0] == '-') s.erase(0, 1);
  return s;
}

}  // namespace

std::string RigToSheetCsv(const Rig& rig) {
  std::string out =
      "id,name,colour,x_cm,y_cm,z_cm,pan_deg,tilt_deg,roll_deg,hfov_deg,vfov_deg,fx_px,fy_px,"
      "cx_px,cy_px,lens,width_px,height_px,enabled\n";
  for (const Camera& camera : rig.cameras) {
    const Intrinsics& k = camera.model.intrinsics();
    const Vec3 p = camera.center() * 100.0;
    const Vec3 ypr = YawPitchRollDeg(camera.world_from_camera.linear());
    char colour[8];
    const auto byte = [](double linear) {
      return static_cast<int>(std::lround(std::clamp(SrgbFromLinear(linear), 0.0, 1.0) * 255.0));
    };
    std::snprintf(colour, sizeof colour, "#%02x%02x%02x", byte(camera.color.x()),
                  byte(camera.color.y()), byte(camera.color.z()));
    out += Csv(camera.id) + "," + Csv(camera.name) + "," + colour + "," + Fixed(p.x(), 1) + "," +
           Fixed(p.y(), 1) + "," + Fixed(p.z(), 1) + "," + Fixed(ypr.x(), 2) + "," +
           Fixed(ypr.y(), 2) + "," + Fixed(ypr.z(), 2) + "," +
           Fixed(HfovFromFocal(k.fx, k.width, k.model) * 180.0 / kPi, 2) + "," +
           Fixed(HfovFromFocal(k.fy, k.height, k.model) * 180.0 / kPi, 2) + "," + Fixed(k.fx, 1) +
           "," + Fixed(k.fy, 1) + "," + Fixed(k.cx, 1) + "," + Fixed(k.cy, 1) + "," +
           LensModelName(k.model) + "," + std::to_string(k.width) + "," + std::to_string(k.height) +
           "," + (camera.enabled ? "yes" : "no") + "\n";
  }
  return out;
}

}  // namespace pandora
