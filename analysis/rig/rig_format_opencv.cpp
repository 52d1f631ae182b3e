// A rig in OpenCV FileStorage YAML, written and read (analysis/rig/rig_formats.h,
// docs/tool-chain.md).
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
#include "analysis/rig/rig_format_text.h"
#include "analysis/rig/rig_formats.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "analysis/util/units.h"

namespace pandora {
namespace {

using namespace rig_format;  // NOLINT: the formats' shared helpers

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

}  // namespace pandora
