#include "viewer/core/script.h"

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "analysis/util/error.h"
#include "analysis/util/input_file.h"

namespace pandora::viewer {
namespace {

using nlohmann::json;
using Kind = Action::Kind;

// One action object: typed reads of its keys, each failing with the file and the JSON path.
class Entry {
 public:
  Entry(const json& j, std::string path, const std::string& file)
      : j_(j), path_(std::move(path)), file_(file) {}

  [[noreturn]] void Fail(const std::string& key, const std::string& reason,
                         const std::string& hint = "") const {
    throw InputError(file_, key.empty() ? path_ : path_ + "." + key, reason, hint);
  }
  bool Has(const std::string& key) const { return j_.contains(key); }
  void Keys(std::initializer_list<const char*> allowed) const {
    std::set<std::string> ok(allowed.begin(), allowed.end());
    for (const auto& item : j_.items())
      if (!ok.count(item.key())) {
        std::string list;
        for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
        Fail(item.key(), "unknown key for this action", "keys: " + list);
      }
  }
  double Number(const std::string& key, double lo, double hi) const {
    if (!Has(key)) Fail(key, "missing");
    const json& v = j_.at(key);
    if (!v.is_number()) Fail(key, "expected a number");
    const double x = v.get<double>();
    if (!std::isfinite(x) || x < lo || x > hi)
      Fail(key, "expected a number in [" + Short(lo) + ", " + Short(hi) + "], got " + v.dump());
    return x;
  }
  double Number(const std::string& key, double lo, double hi, double fallback) const {
    return Has(key) ? Number(key, lo, hi) : fallback;
  }
  std::string String(const std::string& key, bool allow_empty = false) const {
    if (!Has(key)) Fail(key, "missing");
    const json& v = j_.at(key);
    if (!v.is_string()) Fail(key, "expected a string");
    std::string s = v.get<std::string>();
    if (s.empty() && !allow_empty) Fail(key, "must not be empty");
    if (s.size() > 4096) Fail(key, "longer than 4096 characters");
    return s;
  }
  std::string OneOf(const std::string& key, std::initializer_list<const char*> values) const {
    const std::string s = String(key);
    for (const char* v : values)
      if (s == v) return s;
    std::string list;
    for (const char* v : values) list += (list.empty() ? "" : ", ") + std::string(v);
    Fail(key, "unknown value '" + s + "'", "use one of " + list);
  }
  Vec3 Vector(const std::string& key, int n = 3) const {
    if (!Has(key)) Fail(key, "missing");
    const json& v = j_.at(key);
    if (!v.is_array() || int(v.size()) != n)
      Fail(key, "expected an array of " + std::to_string(n) + " numbers");
    Vec3 out = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>()) ||
          std::abs(v[i].get<double>()) > 1e7)
        Fail(key + "[" + std::to_string(i) + "]",
             "expected a finite number of at most 1e7 in size");
      out[i] = v[i].get<double>();
    }
    return out;
  }
  // [x0, y0, z0, x1, y1, z1] under `key`, or at index `i` of this (array) value.
  Aabb Box(const std::string& key) const {
    if (!Has(key)) Fail(key, "missing");
    return BoxOf(j_.at(key), key);
  }
  Aabb Box(std::size_t i) const { return BoxOf(j_.at(i), "[" + std::to_string(i) + "]"); }
  // A camera id or a list of them.
  std::vector<std::string> Ids(const std::string& key, bool allow_empty,
                               const std::string& what = "camera") const {
    const json& v = j_.at(key);
    std::vector<std::string> out;
    if (v.is_string()) {
      out.push_back(String(key));
    } else if (v.is_array()) {
      if (v.size() > 10000) Fail(key, "more than 10000 " + what + "s");
      for (std::size_t i = 0; i < v.size(); ++i) {
        if (!v[i].is_string() || v[i].get<std::string>().empty())
          Fail(key + "[" + std::to_string(i) + "]",
               "expected a " + what + " id (a non-empty string)");
        out.push_back(v[i].get<std::string>());
      }
    } else {
      Fail(key, "expected a " + what + " id or an array of ids");
    }
    if (out.empty() && !allow_empty) Fail(key, "name at least one " + what);
    return out;
  }

 private:
  Aabb BoxOf(const json& v, const std::string& key) const {
    // key: a member name ("box": "$[0].box") or an element ("[1]": "$[0].keep_out[1]").
    auto fail = [&](const std::string& sub, const std::string& reason) {
      throw InputError(file_, path_ + (key.rfind("[", 0) == 0 ? "" : ".") + key + sub, reason);
    };
    if (!v.is_array() || v.size() != 6) fail("", "expected a box [x0, y0, z0, x1, y1, z1]");
    Aabb b;
    for (int i = 0; i < 6; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>()) ||
          std::abs(v[i].get<double>()) > 1e7)
        fail("[" + std::to_string(i) + "]", "expected a finite number of at most 1e7 in size");
      (i < 3 ? b.min : b.max)[i % 3] = v[i].get<double>();
    }
    if ((b.min.array() > b.max.array()).any()) fail("", "the box's min exceeds its max");
    return b;
  }
  static std::string Short(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return b;
  }
  const json& j_;
  std::string path_;
  const std::string& file_;
};

const std::map<std::string, Kind>& Kinds() {
  static const std::map<std::string, Kind> kinds = {{"select", Kind::kSelect},
                                                    {"move", Kind::kMove},
                                                    {"rotate", Kind::kRotate},
                                                    {"aim", Kind::kAim},
                                                    {"orient", Kind::kOrient},
                                                    {"enable", Kind::kEnable},
                                                    {"disable", Kind::kDisable},
                                                    {"hfov", Kind::kHfov},
                                                    {"intrinsics", Kind::kIntrinsics},
                                                    {"range", Kind::kRange},
                                                    {"color", Kind::kColor},
                                                    {"compare", Kind::kCompare},
                                                    {"undo", Kind::kUndo},
                                                    {"redo", Kind::kRedo},
                                                    {"slice", Kind::kSlice},
                                                    {"iso", Kind::kIso},
                                                    {"view", Kind::kView},
                                                    {"orbit", Kind::kOrbit},
                                                    {"pan", Kind::kPan},
                                                    {"dolly", Kind::kDolly},
                                                    {"eye", Kind::kEye},
                                                    {"light", Kind::kLight},
                                                    {"wait", Kind::kWait},
                                                    {"suggest", Kind::kSuggest},
                                                    {"accept", Kind::kAccept},
                                                    {"reject", Kind::kReject},
                                                    {"save", Kind::kSave},
                                                    {"screenshot", Kind::kScreenshot},
                                                    {"size", Kind::kSize},
                                                    {"mouse", Kind::kMouse},
                                                    {"key", Kind::kKey},
                                                    {"scroll", Kind::kScroll},
                                                    {"gamepad", Kind::kGamepad},
                                                    {"frames", Kind::kFrames},
                                                    {"station", Kind::kStation},
                                                    {"ptz", Kind::kPtz},
                                                    {"recentre", Kind::kRecentre},
                                                    {"trace", Kind::kTrace}};
  return kinds;
}

// The action an object names: its one known key.
std::string ActionName(const json& j, const std::string& where, const std::string& file) {
  if (!j.is_object() || j.empty())
    throw InputError(file, where, "expected an object naming one action, e.g. {\"undo\": 1}");
  // The action is the first known key present (objects keep their keys sorted; exactly one action).
  std::string name;
  for (const auto& item : j.items())
    if (Kinds().count(item.key())) {
      if (!name.empty())
        throw InputError(file, where,
                         "two actions in one object ('" + name + "' and '" + item.key() + "')",
                         "give each action its own object");
      name = item.key();
    }
  if (name.empty()) {
    std::string list;
    for (const auto& [k, v] : Kinds()) list += (list.empty() ? "" : ", ") + k;
    throw InputError(file, where, "no known action in this object", "actions: " + list);
  }
  return name;
}

// "select": the cameras to select (none: clear the selection).
void ParseSelect(const Entry& e, Action& a) {
  e.Keys({"select"});
  a.cameras = e.Ids("select", true);
}

// "move": cameras, and 'by' (a move) or 'to' (a position of one camera).
void ParseMove(const Entry& e, const json& j, Action& a) {
  e.Keys({"move", "by", "to", "drag"});
  a.drag = e.Has("drag") && j.at("drag") == true;
  a.cameras = e.Ids("move", false);
  if (e.Has("by") == e.Has("to")) e.Fail("", "give one of 'by' (a move) or 'to' (a position)");
  a.flag = e.Has("to");
  if (a.flag && a.cameras.size() != 1) e.Fail("to", "'to' places one camera; use 'by' for a group");
  a.a = e.Vector(a.flag ? "to" : "by");
  a.has_a = true;
}

// "rotate": cameras, an axis and an angle.
void ParseRotate(const Entry& e, const json& j, Action& a) {
  e.Keys({"rotate", "axis", "deg", "drag"});
  a.drag = e.Has("drag") && j.at("drag") == true;
  a.cameras = e.Ids("rotate", false);
  a.a = e.Vector("axis");
  if (!(a.a.norm() > 0)) e.Fail("axis", "the axis must be a non-zero vector");
  a.number = e.Number("deg", -360, 360);
}

// "aim": a camera and the point it looks at.
void ParseAim(const Entry& e, Action& a) {
  e.Keys({"aim", "at"});
  a.cameras = {e.String("aim")};
  a.a = e.Vector("at");
}

// "orient": a camera and its yaw, pitch and roll.
void ParseOrient(const Entry& e, const json& j, Action& a) {
  e.Keys({"orient", "ypr_deg", "drag"});
  a.drag = e.Has("drag") && j.at("drag") == true;
  a.cameras = {e.String("orient")};
  a.a = e.Vector("ypr_deg");
  if (std::abs(a.a.y()) > 90) e.Fail("ypr_deg[1]", "the pitch lies in [-90, 90] degrees");
}

// "hfov": cameras and a horizontal field of view.
void ParseHfov(const Entry& e, Action& a) {
  e.Keys({"hfov", "deg"});
  a.cameras = e.Ids("hfov", false);
  a.number = e.Number("deg", 1, 359);
}

// "intrinsics": cameras and a resolution, a lens model and / or distortion coefficients.
void ParseIntrinsics(const Entry& e, Action& a) {
  e.Keys({"intrinsics", "resolution", "model", "k1", "k2", "p1", "p2", "k3", "k4"});
  a.cameras = e.Ids("intrinsics", false);
  if (e.Has("resolution")) {
    const Vec3 v = e.Vector("resolution", 2);
    if (v.x() < 1 || v.y() < 1 || v.x() > 65536 || v.y() > 65536 || v.x() != std::floor(v.x()) ||
        v.y() != std::floor(v.y()))
      e.Fail("resolution", "expected [width, height], whole numbers of pixels from 1 to 65536");
    a.width = int(v.x());
    a.height = int(v.y());
  }
  if (e.Has("model")) a.lens = e.OneOf("model", {"pinhole", "brown_conrady", "fisheye"});
  bool any = a.width > 0 || !a.lens.empty();
  for (int i = 0; i < 6; ++i) {
    const char* key = kCoefficientNames[i];
    if (!e.Has(key)) continue;
    if (!a.lens.empty() && !LensHasCoefficient(a.lens, i))
      e.Fail(key, "a " + a.lens + " lens has no coefficient " + key,
             a.lens == "pinhole"   ? "pinhole: no distortion"
             : a.lens == "fisheye" ? "fisheye: k1 k2 k3 k4"
                                   : "brown_conrady: k1 k2 p1 p2 k3");
    a.coefficients[i] = e.Number(key, -1000, 1000);
    any = true;
  }
  if (!any)
    e.Fail("", "nothing to change", "give resolution, model or coefficients (k1 k2 p1 p2 k3 k4)");
}

// "range": cameras and a near and / or far distance (far null: unbounded).
void ParseRange(const Entry& e, const json& j, Action& a) {
  e.Keys({"range", "near", "far"});
  a.cameras = e.Ids("range", false);
  if (!e.Has("near") && !e.Has("far"))
    e.Fail("", "nothing to change", "give near, far or both (metres)");
  if (e.Has("near")) a.near = e.Number("near", 0, 1e7);
  if (e.Has("far")) {
    if (j.at("far").is_null())
      a.far = INFINITY;
    else
      a.far = e.Number("far", 1e-9, 1e7);
    if (a.far <= a.near) e.Fail("far", "far must be greater than near");
  }
}

// "color": cameras and a linear RGB colour.
void ParseColor(const Entry& e, Action& a) {
  e.Keys({"color", "rgb"});
  a.cameras = e.Ids("color", false);
  a.a = e.Vector("rgb");
  for (int i = 0; i < 3; ++i)
    if (a.a[i] < 0 || a.a[i] > 1)
      e.Fail("rgb[" + std::to_string(i) + "]", "colour components are linear RGB in [0, 1]");
}

// "compare": up to 8 different rigs.
void ParseCompare(const Entry& e, Action& a) {
  e.Keys({"compare"});
  a.cameras = e.Ids("compare", false);
  if (a.cameras.size() > 8) e.Fail("compare", "compare with at most 8 rigs");
  for (std::size_t i = 0; i < a.cameras.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (a.cameras[i] == a.cameras[k])
        e.Fail("compare[" + std::to_string(i) + "]", "'" + a.cameras[i] + "' is named twice");
}

// "slice": a field (empty: none), an axis and a position.
void ParseSlice(const Entry& e, Action& a) {
  e.Keys({"slice", "axis", "at"});
  a.text = e.String("slice", true);
  a.flag = a.text.empty();
  a.text2 = e.Has("axis") ? e.OneOf("axis", {"x", "y", "z"}) : "z";
  a.number = e.Has("at") ? e.Number("at", -1e7, 1e7) : NAN;
}

// "iso": a field (empty: none) and its value.
void ParseIso(const Entry& e, Action& a) {
  e.Keys({"iso", "value"});
  a.text = e.String("iso", true);
  a.flag = a.text.empty();
  if (!a.flag) a.number = e.Number("value", -1e30, 1e30);
}

// "view": a plan, an elevation (with its side) or a view of the scene.
void ParseView(const Entry& e, Action& a) {
  // "plan" and "elevation" (with "side") are the orthographic proposal views; any other name
  // is one of the scene's views.
  e.Keys({"view", "side"});
  a.text = e.String("view");
  if (a.text == "elevation")
    a.text2 = e.OneOf("side", {"north", "south", "east", "west"});
  else if (e.Has("side"))
    e.Fail("side", "only with \"view\": \"elevation\"");
}

// "dolly": the steps towards the point looked at.
void ParseDolly(const Entry& e, Action& a) {
  e.Keys({"dolly"});
  a.number = e.Number("dolly", -100, 100);
}

// "eye": the eye, the point it looks at and the field of view.
void ParseEye(const Entry& e, Action& a) {
  e.Keys({"eye", "at", "fov"});
  a.a = e.Vector("eye");
  a.b = e.Vector("at");
  if ((a.a - a.b).norm() == 0) e.Fail("at", "the eye and the point looked at coincide");
  a.number = e.Number("fov", 1, 170, 50);
}

// "light": the pattern, grid size, brightness and surface.
void ParseLight(const Entry& e, Action& a) {
  e.Keys({"light", "grid", "brightness", "surface"});
  a.text = e.OneOf("light", {"uniform", "grid"});
  a.number = e.Number("grid", 1, 100000, 32);
  a.number2 = e.Has("brightness") ? e.Number("brightness", 1e-6, 1e6) : NAN;
  a.text2 = e.Has("surface") ? e.OneOf("surface", {"material", "black", "hidden-line", "contours"})
                             : "material";
}

// "wait": the job waited for.
void ParseWait(const Entry& e, Action& a) {
  e.Keys({"wait"});
  a.text = e.OneOf("wait", {"fields", "suggest", "render"});
}

// "suggest": cameras, the objective, limits, mounts, keep-out boxes and targets.
void ParseSuggest(const Entry& e, const json& j, const std::string& where, const std::string& file,
                  Action& a) {
  e.Keys({"suggest", "objective", "max_move", "max_rotate", "points", "seed", "rail", "plane",
          "box", "keep_out", "clearance", "hfov_range", "weights", "snap_move", "snap_rotate",
          "outer", "target_surface", "with_region", "over_time"});
  a.cameras = e.Ids("suggest", false);
  a.text = e.Has("objective") ? e.String("objective") : "coverage2";
  a.number = e.Number("max_move", 0, 1e4, 0.3);
  a.number2 = e.Number("max_rotate", 0, 179.999, 10);
  a.number3 = e.Number("points", 1, 1e6, 1500);  // pandora suggest's --points
  if (e.Has("weights")) {
    a.weights = e.Vector("weights");
    if ((a.weights.array() < 0).any() || a.weights.sum() <= 0)
      e.Fail("weights", "the weights must be >= 0 and not all zero");
  }
  a.snap_move = e.Number("snap_move", 0, 1e4, 0);
  a.snap_rotate = e.Number("snap_rotate", 0, 180, 0);
  a.outer_iterations = int(e.Number("outer", 1, 100, 4));
  if (e.Has("target_surface")) a.target_surfaces = e.Ids("target_surface", false, "surface");
  for (const char* key : {"with_region", "over_time"})
    if (e.Has(key) && !j.at(key).is_boolean()) e.Fail(key, "expected true or false");
  a.with_region = e.Has("with_region") && j.at("with_region").get<bool>();
  a.over_time = e.Has("over_time") && j.at("over_time").get<bool>();
  if (a.over_time && !a.target_surfaces.empty())
    e.Fail("over_time", "takes the study's targets; 'target_surface' is for a static scene",
           "give one of them");
  a.seed = static_cast<unsigned long long>(e.Number("seed", 0, 9e15, 1));
  if (int(e.Has("rail")) + int(e.Has("plane")) + int(e.Has("box")) > 1)
    e.Fail("", "give at most one mount: 'rail', 'plane' or 'box'");
  for (const char* mount : {"rail", "plane"})
    if (e.Has(mount)) {
      a.mount = mount;
      a.a = e.Vector(mount);
      if (!(a.a.norm() > 0)) e.Fail(mount, "the direction must be a non-zero vector");
    }
  if (e.Has("box")) {
    a.mount = "box";
    a.mount_box = e.Box("box");
  }
  if (e.Has("keep_out")) {
    const json& boxes = j.at("keep_out");
    if (!boxes.is_array() || boxes.size() > 1000)
      e.Fail("keep_out", "expected an array of boxes [x0, y0, z0, x1, y1, z1]");
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const Entry box(boxes, where + ".keep_out", file);
      a.keep_out.push_back(box.Box(i));
    }
  }
  if (e.Has("clearance")) a.clearance = e.Number("clearance", 0, 1e4);
  if (e.Has("hfov_range")) {
    const Vec3 r = e.Vector("hfov_range", 2);
    if (!(r.x() > 0 && r.x() <= r.y() && r.y() < 360))
      e.Fail("hfov_range", "expected [min, max] degrees, 0 < min <= max < 360");
    a.min_hfov = r.x();
    a.max_hfov = r.y();
  }
}

// "accept": "all" or the cameras to take.
void ParseAccept(const Entry& e, const json& j, Action& a) {
  e.Keys({"accept"});
  if (j.at("accept").is_string() && j.at("accept") == "all") return;  // every suggested camera
  a.cameras = e.Ids("accept", false);
}

// "save": forced ("force") or not.
void ParseSave(const Entry& e, const json& j, Action& a) {
  e.Keys({"save"});
  a.flag = j.at("save").is_string() && j.at("save") == "force";
}

// "screenshot": the file and, optionally, the camera whose view it shows.
void ParseScreenshot(const Entry& e, Action& a) {
  e.Keys({"screenshot", "camera"});
  a.text = e.String("screenshot");
  if (e.Has("camera")) a.text2 = e.String("camera");
}

// "size": the main view's width and height.
void ParseSize(const Entry& e, Action& a) {
  e.Keys({"size"});
  const Vec3 v = e.Vector("size", 2);
  if (v.x() < 16 || v.y() < 16 || v.x() > 8192 || v.y() > 8192 || v.x() != std::floor(v.x()) ||
      v.y() != std::floor(v.y()))
    e.Fail("size", "expected [width, height], whole numbers of pixels from 16 to 8192");
  a.a = v;
}

// "mouse": press, release or move, a button, and the pointer (pixels, a world point or a handle).
void ParseMouse(const Entry& e, Action& a) {
  e.Keys({"mouse", "button", "x", "y", "at", "gizmo", "by"});
  a.text = e.OneOf("mouse", {"press", "release", "move"});
  a.text2 = e.Has("button") ? e.OneOf("button", {"left", "right", "middle"}) : "left";
  if (int(e.Has("x") || e.Has("y")) + int(e.Has("at")) + int(e.Has("gizmo")) != 1)
    e.Fail("",
           "give the pointer as one of 'x' and 'y' (pixels), 'at' (a world point) or 'gizmo' "
           "(a handle)");
  if (e.Has("at")) {
    a.a = e.Vector("at");
    a.has_a = true;
  } else if (e.Has("gizmo")) {
    const std::string h = e.OneOf("gizmo", {"x", "y", "z", "rx", "ry", "rz"});
    a.gizmo = (h[0] == 'r' ? 3 : 0) + (h.back() - 'x');
    a.number = e.Number("by", -1e4, 1e4, 0);
  } else {
    a.number3 = e.Number("x", -1e5, 1e5);
    a.number2 = e.Number("y", -1e5, 1e5);
  }
  if (e.Has("by") && !e.Has("gizmo")) e.Fail("by", "'by' goes with 'gizmo'");
}

// "key": the key pressed.
void ParseKey(const Entry& e, Action& a) {
  e.Keys({"key"});
  a.text = e.String("key");
}

// "scroll": the steps and the pointer.
void ParseScroll(const Entry& e, Action& a) {
  e.Keys({"scroll", "x", "y"});
  a.number = e.Number("scroll", -100, 100);
  a.number3 = e.Number("x", -1e5, 1e5, 0);
  a.number2 = e.Number("y", -1e5, 1e5, 0);
}

// "gamepad": a camera, the sticks' positions and how long they are held.
void ParseGamepad(const Entry& e, const json& j, Action& a) {
  e.Keys({"gamepad", "left", "right", "seconds", "drag"});
  a.drag = e.Has("drag") && j.at("drag") == true;
  a.cameras = {e.String("gamepad")};
  a.a = e.Has("left") ? e.Vector("left", 2) : Vec3::Zero();
  a.b = e.Has("right") ? e.Vector("right", 2) : Vec3::Zero();
  if (a.a.cwiseAbs().maxCoeff() > 1 || a.b.cwiseAbs().maxCoeff() > 1)
    e.Fail(a.a.cwiseAbs().maxCoeff() > 1 ? "left" : "right", "stick positions lie in [-1, 1]");
  a.number = e.Number("seconds", 0, 60);
}

// "station": a viewing station and its eye's or display's new position.
void ParseStation(const Entry& e, Action& a) {
  e.Keys({"station", "eye_at", "display_at"});
  a.text = e.String("station");
  if (e.Has("eye_at") == e.Has("display_at"))
    e.Fail("", "give one of 'eye_at' or 'display_at' (a position)");
  a.flag = e.Has("display_at");
  a.a = e.Vector(a.flag ? "display_at" : "eye_at");
}

// "ptz": a camera and a preset, or its pan, tilt and / or field of view.
void ParsePtz(const Entry& e, const json& j, Action& a) {
  e.Keys({"ptz", "pan_deg", "tilt_deg", "hfov_deg", "preset", "drag"});
  a.drag = e.Has("drag") && j.at("drag") == true;
  a.cameras = {e.String("ptz")};
  if (e.Has("preset")) {
    if (e.Has("pan_deg") || e.Has("tilt_deg") || e.Has("hfov_deg"))
      e.Fail("preset", "give a preset or angles, not both");
    a.preset = e.String("preset");
    return;
  }
  if (!e.Has("pan_deg") && !e.Has("tilt_deg") && !e.Has("hfov_deg"))
    e.Fail("", "nothing to change", "give pan_deg, tilt_deg, hfov_deg or a preset");
  a.pan_deg = e.Number("pan_deg", -360, 360, NAN);
  a.tilt_deg = e.Number("tilt_deg", -180, 180, NAN);
  a.hfov_deg = e.Number("hfov_deg", 0.01, 359, NAN);
}

// "recentre": the PTZ camera.
void ParseRecentre(const Entry& e, Action& a) {
  e.Keys({"recentre"});
  a.cameras = {e.String("recentre")};
}

// "trace": the kind of PTZ trace and its time budget.
void ParseTrace(const Entry& e, Action& a) {
  e.Keys({"trace", "seconds"});
  a.text = e.OneOf("trace", {"single", "path", "all"});
  a.number = e.Number("seconds", 0, 3600, NAN);
}

// "frames": how many frames to run.
void ParseFrames(const Entry& e, Action& a) {
  e.Keys({"frames"});
  a.number = e.Number("frames", 0, 10000);
}

Action ParseAction(const json& j, const std::string& where, const std::string& file) {
  const std::string name = ActionName(j, where, file);
  const Entry e(j, where, file);
  Action a;
  a.kind = Kinds().at(name);
  a.where = where;
  switch (a.kind) {
    case Kind::kSelect:
      ParseSelect(e, a);
      break;
    case Kind::kMove:
      ParseMove(e, j, a);
      break;
    case Kind::kRotate:
      ParseRotate(e, j, a);
      break;
    case Kind::kAim:
      ParseAim(e, a);
      break;
    case Kind::kOrient:
      ParseOrient(e, j, a);
      break;
    case Kind::kEnable:
    case Kind::kDisable:
      e.Keys({name.c_str()});
      a.cameras = e.Ids(name, false);
      break;
    case Kind::kHfov:
      ParseHfov(e, a);
      break;
    case Kind::kIntrinsics:
      ParseIntrinsics(e, a);
      break;
    case Kind::kRange:
      ParseRange(e, j, a);
      break;
    case Kind::kColor:
      ParseColor(e, a);
      break;
    case Kind::kCompare:
      ParseCompare(e, a);
      break;
    case Kind::kUndo:
    case Kind::kRedo:
    case Kind::kReject:
      e.Keys({name.c_str()});
      break;
    case Kind::kSlice:
      ParseSlice(e, a);
      break;
    case Kind::kIso:
      ParseIso(e, a);
      break;
    case Kind::kView:
      ParseView(e, a);
      break;
    case Kind::kOrbit:
    case Kind::kPan:
      e.Keys({name.c_str()});
      a.a = e.Vector(name, 2);
      break;
    case Kind::kDolly:
      ParseDolly(e, a);
      break;
    case Kind::kEye:
      ParseEye(e, a);
      break;
    case Kind::kLight:
      ParseLight(e, a);
      break;
    case Kind::kWait:
      ParseWait(e, a);
      break;
    case Kind::kSuggest:
      ParseSuggest(e, j, where, file, a);
      break;
    case Kind::kAccept:
      ParseAccept(e, j, a);
      break;
    case Kind::kSave:
      ParseSave(e, j, a);
      break;
    case Kind::kScreenshot:
      ParseScreenshot(e, a);
      break;
    case Kind::kSize:
      ParseSize(e, a);
      break;
    case Kind::kMouse:
      ParseMouse(e, a);
      break;
    case Kind::kKey:
      ParseKey(e, a);
      break;
    case Kind::kScroll:
      ParseScroll(e, a);
      break;
    case Kind::kGamepad:
      ParseGamepad(e, j, a);
      break;
    case Kind::kStation:
      ParseStation(e, a);
      break;
    case Kind::kPtz:
      ParsePtz(e, j, a);
      break;
    case Kind::kRecentre:
      ParseRecentre(e, a);
      break;
    case Kind::kTrace:
      ParseTrace(e, a);
      break;
    case Kind::kFrames:
      ParseFrames(e, a);
      break;
  }
  return a;
}

}  // namespace

const char* const kCoefficientNames[6] = {"k1", "k2", "p1", "p2", "k3", "k4"};

bool LensHasCoefficient(const std::string& model, int i) {
  if (model == "brown_conrady") return i <= 4;
  if (model == "fisheye") return i == 0 || i == 1 || i == 4 || i == 5;
  return false;
}

std::vector<Action> ParseScript(const std::string& text, const std::string& path) {
  CheckJsonLimits(text, path);
  json j;
  try {
    j = json::parse(text);
  } catch (const std::exception& e) {
    throw InputError(path, "$", std::string("malformed JSON: ") + e.what());
  }
  if (!j.is_array())
    throw InputError(path, "$", "a script is an array of actions", "e.g. [{\"undo\": 1}]");
  if (j.size() > 100000) throw InputError(path, "$", "more than 100000 actions");
  std::vector<Action> out;
  out.reserve(j.size());
  for (std::size_t i = 0; i < j.size(); ++i)
    out.push_back(ParseAction(j[i], "$[" + std::to_string(i) + "]", path));
  return out;
}

std::vector<Action> LoadScript(const std::string& path) {
  return ParseScript(ReadInputFile(path, InputLimits::kJsonBytes, "script"), path);
}

}  // namespace pandora::viewer
