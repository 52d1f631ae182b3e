#include "viewer/core/script.h"

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "analysis/geometry/camera.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "analysis/util/json_reader.h"
#include "analysis/util/text.h"
#include "render/render.h"

namespace pandora::viewer {
namespace {

using nlohmann::json;
using Kind = Action::Kind;

// One action object: typed reads of its keys through the one JSON reader
// (analysis/util/json_reader.h), each failing with the file and the JSON path.
class Entry {
 public:
  explicit Entry(JsonNode node) : node_(std::move(node)) {}

  const JsonNode& node() const { return node_; }
  // Member `key` (fails when it is missing).
  JsonNode Get(const std::string& key) const { return node_.Get(key); }

  // Fails at `key` (at the action itself when empty).
  [[noreturn]] void Fail(const std::string& key, const std::string& reason,
                         const std::string& hint = "") const {
    if (key.empty() || !Has(key)) node_.Fail(reason, hint);
    Get(key).Fail(reason, hint);
  }
  bool Has(const std::string& key) const { return node_.Has(key); }
  // Whether `key` is given as true ("drag": true).
  bool Flag(const std::string& key) const { return Has(key) && node_.value().at(key) == true; }
  void Keys(std::initializer_list<const char*> allowed) const {
    node_.CheckKeys(std::vector<std::string>(allowed.begin(), allowed.end()));
  }
  double Number(const std::string& key, double lo, double hi) const {
    return Get(key).Number(lo, hi);
  }
  double Number(const std::string& key, double lo, double hi, double fallback) const {
    return Has(key) ? Number(key, lo, hi) : fallback;
  }
  std::string String(const std::string& key, bool allow_empty = false) const {
    return Text(Get(key), allow_empty);
  }
  std::string OneOf(const std::string& key, std::initializer_list<const char*> values) const {
    return Get(key).Enum(std::vector<std::string>(values.begin(), values.end()));
  }
  // `n` (2 or 3) numbers of at most 1e7 in size.
  Vec3 Vector(const std::string& key, int n = 3) const {
    const JsonNode v = Get(key);
    v.Numbers(n);
    Vec3 out = Vec3::Zero();
    for (int i = 0; i < n; ++i) out[i] = v.At(i).Number(-kMaxCoordinate, kMaxCoordinate);
    return out;
  }
  // [x0, y0, z0, x1, y1, z1].
  static Aabb Box(const JsonNode& v) {
    if (!v.value().is_array() || v.value().size() != 6)
      v.Fail("expected a box [x0, y0, z0, x1, y1, z1], got " + v.TypeName());
    Aabb b;
    for (int i = 0; i < 6; ++i)
      (i < 3 ? b.min : b.max)[i % 3] = v.At(i).Number(-kMaxCoordinate, kMaxCoordinate);
    if ((b.min.array() > b.max.array()).any()) v.Fail("the box's min exceeds its max");
    return b;
  }
  // A camera id or a list of them.
  std::vector<std::string> Ids(const std::string& key, bool allow_empty,
                               const std::string& what = "camera") const {
    const JsonNode v = Get(key);
    std::vector<std::string> out;
    if (v.value().is_string()) {
      out.push_back(Text(v, false));
    } else if (v.value().is_array()) {
      const std::size_t n = v.ArraySize(10000, what + "s");
      for (std::size_t i = 0; i < n; ++i) out.push_back(Text(v.At(i), false));
    } else {
      v.Fail("expected a " + what + " id or an array of ids, got " + v.TypeName());
    }
    if (out.empty() && !allow_empty) v.Fail("name at least one " + what);
    return out;
  }

 private:
  // Coordinates, lengths and steps in a script are within 1e7.
  static constexpr double kMaxCoordinate = 1e7;

  static std::string Text(const JsonNode& v, bool allow_empty) {
    std::string s = allow_empty ? v.String() : v.NonEmptyString();
    if (s.size() > 4096) v.Fail("longer than 4096 characters");
    return s;
  }

  JsonNode node_;
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
std::string ActionName(const JsonNode& node) {
  const json& j = node.value();
  if (!j.is_object() || j.empty())
    node.Fail("expected an object naming one action, e.g. {\"undo\": 1}");
  // The action is the first known key present (objects keep their keys sorted; exactly one action).
  std::string name;
  for (const auto& item : j.items())
    if (Kinds().count(item.key())) {
      if (!name.empty())
        node.Fail("two actions in one object ('" + name + "' and '" + item.key() + "')",
                  "give each action its own object");
      name = item.key();
    }
  if (name.empty()) {
    std::vector<std::string> names;
    for (const auto& [k, v] : Kinds()) names.push_back(k);
    std::string nearest;
    for (const auto& item : j.items()) nearest = item.key();
    node.Fail("no known action in this object", DidYouMean(nearest, names, "actions"));
  }
  return name;
}

// "select": the cameras to select (none: clear the selection).
void ParseSelect(const Entry& e, Action& a) {
  e.Keys({"select"});
  a.cameras = e.Ids("select", true);
}

// "move": cameras, and 'by' (a move) or 'to' (a position of one camera).
void ParseMove(const Entry& e, Action& a) {
  e.Keys({"move", "by", "to", "drag"});
  a.drag = e.Flag("drag");
  a.cameras = e.Ids("move", false);
  if (e.Has("by") == e.Has("to")) e.Fail("", "give one of 'by' (a move) or 'to' (a position)");
  a.flag = e.Has("to");
  if (a.flag && a.cameras.size() != 1) e.Fail("to", "'to' places one camera; use 'by' for a group");
  a.a = e.Vector(a.flag ? "to" : "by");
  a.has_a = true;
}

// "rotate": cameras, an axis and an angle.
void ParseRotate(const Entry& e, Action& a) {
  e.Keys({"rotate", "axis", "deg", "drag"});
  a.drag = e.Flag("drag");
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
void ParseOrient(const Entry& e, Action& a) {
  e.Keys({"orient", "ypr_deg", "drag"});
  a.drag = e.Flag("drag");
  a.cameras = {e.String("orient")};
  a.a = e.Vector("ypr_deg");
  if (std::abs(a.a.y()) > 90) e.Get("ypr_deg").At(1).Fail("the pitch lies in [-90, 90] degrees");
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
  if (e.Has("model")) {
    std::vector<std::string> models;
    for (LensModel m : {LensModel::kPinhole, LensModel::kBrownConrady, LensModel::kFisheye})
      models.push_back(LensModelName(m));
    a.lens = e.Get("model").Enum(models);
  }
  bool any = a.width > 0 || !a.lens.empty();
  for (int i = 0; i < 6; ++i) {
    const char* key = kLensCoefficientNames[i];
    if (!e.Has(key)) continue;
    if (!a.lens.empty() && !LensHasCoefficient(*LensModelFromName(a.lens), i))
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
void ParseRange(const Entry& e, Action& a) {
  e.Keys({"range", "near", "far"});
  a.cameras = e.Ids("range", false);
  if (!e.Has("near") && !e.Has("far"))
    e.Fail("", "nothing to change", "give near, far or both (metres)");
  if (e.Has("near")) a.near = e.Number("near", 0, 1e7);
  if (e.Has("far")) {
    if (e.Get("far").IsNull())
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
      e.Get("rgb").At(i).Fail("colour components are linear RGB in [0, 1]");
}

// "compare": up to 8 different rigs.
void ParseCompare(const Entry& e, Action& a) {
  e.Keys({"compare"});
  a.cameras = e.Ids("compare", false);
  if (a.cameras.size() > 8) e.Fail("compare", "compare with at most 8 rigs");
  for (std::size_t i = 0; i < a.cameras.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (a.cameras[i] == a.cameras[k])
        e.Get("compare").At(i).Fail("'" + a.cameras[i] + "' is named twice");
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
  a.text = e.Get("light").Enum(PatternNames());
  a.number = e.Number("grid", 1, 100000, 32);
  a.number2 = e.Has("brightness") ? e.Number("brightness", 1e-6, 1e6) : NAN;
  a.text2 =
      e.Has("surface") ? e.Get("surface").Enum(SurfaceNames()) : SurfaceName(Surface::kMaterial);
}

// "wait": the job waited for.
void ParseWait(const Entry& e, Action& a) {
  e.Keys({"wait"});
  a.text = e.OneOf("wait", {"fields", "suggest", "render"});
}

// "suggest": cameras, the objective, limits, mounts, keep-out boxes and targets.
void ParseSuggest(const Entry& e, Action& a) {
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
  a.with_region = e.Has("with_region") && e.Get("with_region").Bool();
  a.over_time = e.Has("over_time") && e.Get("over_time").Bool();
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
    a.mount_box = Entry::Box(e.Get("box"));
  }
  if (e.Has("keep_out")) {
    const JsonNode boxes = e.Get("keep_out");
    const std::size_t n = boxes.ArraySize(1000, "boxes [x0, y0, z0, x1, y1, z1]");
    for (std::size_t i = 0; i < n; ++i) a.keep_out.push_back(Entry::Box(boxes.At(i)));
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
void ParseAccept(const Entry& e, Action& a) {
  e.Keys({"accept"});
  if (e.Get("accept").value() == "all") return;  // every suggested camera
  a.cameras = e.Ids("accept", false);
}

// "save": forced ("force") or not.
void ParseSave(const Entry& e, Action& a) {
  e.Keys({"save"});
  a.flag = e.Get("save").value() == "force";
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
void ParseGamepad(const Entry& e, Action& a) {
  e.Keys({"gamepad", "left", "right", "seconds", "drag"});
  a.drag = e.Flag("drag");
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
void ParsePtz(const Entry& e, Action& a) {
  e.Keys({"ptz", "pan_deg", "tilt_deg", "hfov_deg", "preset", "drag"});
  a.drag = e.Flag("drag");
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

Action ParseAction(const JsonNode& node) {
  const std::string name = ActionName(node);
  const Entry e(node);
  Action a;
  a.kind = Kinds().at(name);
  a.where = node.path();
  switch (a.kind) {
    case Kind::kSelect:
      ParseSelect(e, a);
      break;
    case Kind::kMove:
      ParseMove(e, a);
      break;
    case Kind::kRotate:
      ParseRotate(e, a);
      break;
    case Kind::kAim:
      ParseAim(e, a);
      break;
    case Kind::kOrient:
      ParseOrient(e, a);
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
      ParseRange(e, a);
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
      ParseSuggest(e, a);
      break;
    case Kind::kAccept:
      ParseAccept(e, a);
      break;
    case Kind::kSave:
      ParseSave(e, a);
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
      ParseGamepad(e, a);
      break;
    case Kind::kStation:
      ParseStation(e, a);
      break;
    case Kind::kPtz:
      ParsePtz(e, a);
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

std::vector<Action> ParseScript(const std::string& text, const std::string& path) {
  const json j = ParseJson(text, path);
  const JsonNode root = JsonNode::Root(j, path);
  if (!j.is_array()) root.Fail("a script is an array of actions", "e.g. [{\"undo\": 1}]");
  const std::size_t n = root.ArraySize(100000, "actions");
  std::vector<Action> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) out.push_back(ParseAction(root.At(i)));
  return out;
}

std::vector<Action> LoadScript(const std::string& path) {
  return ParseScript(ReadInputFile(path, InputLimits::kJsonBytes, "script"), path);
}

}  // namespace pandora::viewer
