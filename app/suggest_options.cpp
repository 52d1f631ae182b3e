#include "app/suggest_options.h"

#include <cmath>

#include "analysis/scene/motion.h"
#include "analysis/util/error.h"
#include "app/options.h"

namespace pandora::app {
namespace {

// One value for every selected camera, or one each in the selection's order.
std::vector<double> PerCamera(const char* option, const std::vector<double>& values,
                              std::size_t selected) {
  if (values.size() != 1 && values.size() != selected)
    throw InputError(
        option, "",
        "give one value, or one per selected camera (" + std::to_string(selected) + ")");
  std::vector<double> out = values;
  if (!out.empty()) out.resize(selected, out.back());
  return out;
}

// The positions in the selection that `camera` ("": all) names.
std::vector<std::size_t> Targets(const char* option, const std::string& camera, const Rig& rig,
                                 const std::vector<int>& selection) {
  std::vector<std::size_t> which;
  for (std::size_t c = 0; c < selection.size(); ++c)
    if (camera.empty() || rig.cameras[selection[c]].id == camera) which.push_back(c);
  if (which.empty() && !camera.empty())
    throw InputError(option, "",
                     "camera '" + camera + "' is not among the selected cameras ({cameras})");
  return which;
}

// An "ID:VALUE" or "VALUE" option entry: the camera ("" for all) and VALUE parsed by `parse`.
template <typename T, typename Parse>
std::vector<ForCamera<T>> Entries(const std::vector<std::string>& entries, Parse parse) {
  std::vector<ForCamera<T>> out;
  for (const std::string& entry : entries) {
    const std::size_t colon = entry.find(':');
    ForCamera<T> e;
    if (colon != std::string::npos) e.camera = entry.substr(0, colon);
    e.value = parse(colon == std::string::npos ? entry : entry.substr(colon + 1));
    out.push_back(std::move(e));
  }
  return out;
}

std::vector<double> NumberList(const char* option, const std::string& text) {
  std::vector<double> out;
  for (const std::string& item : SplitList(text)) {
    try {
      out.push_back(ParseNumbers(option, item, 1)[0]);
    } catch (const InputError&) {
      throw InputError(option, "", "'" + item + "' is not a number",
                       "give one value, or one per selected camera, separated by commas");
    }
  }
  return out;
}

Vec3 Vector(const char* option, const std::string& text) {
  const std::vector<double> v = ParseNumbers(option, text, 3);
  return Vec3(v[0], v[1], v[2]);
}

Aabb Box(const char* option, const std::string& text) {
  const std::vector<double> v = ParseNumbers(option, text, 6);
  Aabb b;
  b.min = Vec3(v[0], v[1], v[2]);
  b.max = Vec3(v[3], v[4], v[5]);
  return b;
}

std::string Names(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "none" : out;
}

}  // namespace

int PtzCameraOption(const Rig& rig, const std::string& option, const std::string& id) {
  const int c = rig.FindCamera(id);
  std::vector<std::string> ptz;
  for (const Camera& cam : rig.cameras)
    if (cam.ptz && cam.enabled) ptz.push_back(cam.id);
  if (c < 0)
    throw InputError(option, "", "no camera '" + id + "' in rig '" + rig.name + "'",
                     "PTZ cameras: " + Names(ptz));
  if (!rig.cameras[c].ptz)
    throw InputError(option, "", "camera '" + id + "' has no PTZ head",
                     "PTZ cameras: " + Names(ptz));
  if (!rig.cameras[c].enabled) throw InputError(option, "", "camera '" + id + "' is disabled");
  return c;
}

std::vector<TargetPoint> SampleTargetsInRegion(const Scene& scene, const std::string& option,
                                               const std::string& region, int points,
                                               const std::vector<std::string>& surfaces,
                                               bool with_region, std::uint64_t seed) {
  if (region.empty()) return SampleTargets(scene, points, surfaces, with_region, seed);
  std::vector<std::string> names;
  for (const auto& [name, r] : scene.study.regions) {
    names.push_back(name);
    if (name == region) {
      Scene sub = scene;
      sub.study.region = r;
      return SampleTargets(sub, points, surfaces, with_region, seed);
    }
  }
  throw InputError(option, "", "no region '" + region + "' in the study",
                   "study.regions: " + Names(names));
}

session::SessionOptions SuggestSessionOptions(const SuggestArgs& args) {
  session::SessionOptions o;
  o.rig = args.rig;
  o.rig_option = "{rig}";
  o.disable = args.disable;
  return o;
}

SuggestRequest SuggestRequestFromArgs(const SuggestArgs& args) {
  SuggestRequest r;
  r.cameras = SplitList(args.cameras);
  r.max_move = NumberList("{max_move}", args.max_move);
  r.max_rotate_deg = NumberList("{max_rotate_deg}", args.max_rotate);
  r.objective = args.objective;
  if (!args.weights.empty()) {
    const std::vector<double> w = ParseNumbers("{weights}", args.weights, 3);
    r.weights = Vec3(w[0], w[1], w[2]);
  }
  const auto vector = [](const char* option) {
    return [option](const std::string& text) { return Vector(option, text); };
  };
  r.rail = Entries<Vec3>(args.rail, vector("{rail}"));
  r.plane = Entries<Vec3>(args.plane, vector("{plane}"));
  r.mount_box = Entries<Aabb>(args.mount_box,
                              [](const std::string& text) { return Box("{mount_box}", text); });
  r.hfov_range = Entries<std::array<double, 2>>(args.hfov_range, [](const std::string& text) {
    const std::vector<double> v = ParseNumbers("{hfov_range}", text, 2);
    return std::array<double, 2>{v[0], v[1]};
  });
  for (const std::string& box : args.keep_out) r.keep_out.push_back(Box("{keep_out}", box));
  r.target_surfaces = args.target_surfaces;
  r.with_region = args.with_region;
  r.over_time = args.over_time;
  r.points = args.points;
  r.snap_move = args.snap_move;
  r.snap_rotate_deg = args.snap_rotate;
  r.clearance = args.clearance;
  r.outer_iterations = args.outer_iterations;
  r.seed = args.seed;
  return r;
}

namespace {

// The selection's limits: moves and rotations, mounts, zoom ranges.
std::vector<CameraLimits> LimitsOf(const SuggestRequest& r, const Scene& scene, const Rig& rig,
                                   const std::vector<int>& selection) {
  const std::size_t n = selection.size();
  const std::vector<double> moves = PerCamera("{max_move}", r.max_move, n);
  const std::vector<double> rotations = PerCamera("{max_rotate_deg}", r.max_rotate_deg, n);
  std::vector<CameraLimits> limits(n);
  for (std::size_t c = 0; c < n; ++c) {
    if (!(moves[c] >= 0))
      throw InputError("{max_move}", "", "must be a finite length >= 0 in metres");
    scene.CheckLength(moves[c], "{max_move}", "the move");
    if (!(rotations[c] >= 0) || !(rotations[c] < 180))
      throw InputError("{max_rotate_deg}", "", "must be an angle in [0, 180) degrees");
    limits[c].max_move = moves[c];
    limits[c].max_rotate_deg = rotations[c];
  }

  std::vector<int> mounts(n, 0);
  const auto add_mount = [&](const char* option, const std::string& camera,
                             MountConstraint::Kind kind, const Vec3& axis, const Aabb& box) {
    for (std::size_t c : Targets(option, camera, rig, selection)) {
      MountConstraint& m = limits[c].mount;
      m.kind = kind;
      if (kind == MountConstraint::Kind::kBox) {
        CheckBox(scene, option, box);
        m.box = box;
      } else {
        if (!(axis.norm() > 0) || !axis.allFinite())
          throw InputError(option, "", "the direction must be a non-zero vector");
        m.axis = axis;
      }
      if (++mounts[c] > 1)
        throw InputError(option, "", "give at most one of {rail}, {plane}, {mount_box} per camera");
    }
  };
  for (const ForCamera<Vec3>& e : r.rail)
    add_mount("{rail}", e.camera, MountConstraint::Kind::kLine, e.value, Aabb());
  for (const ForCamera<Vec3>& e : r.plane)
    add_mount("{plane}", e.camera, MountConstraint::Kind::kPlane, e.value, Aabb());
  for (const ForCamera<Aabb>& e : r.mount_box)
    add_mount("{mount_box}", e.camera, MountConstraint::Kind::kBox, Vec3::Zero(), e.value);
  for (const ForCamera<std::array<double, 2>>& e : r.hfov_range) {
    for (std::size_t c : Targets("{hfov_range}", e.camera, rig, selection)) {
      const auto& [lo, hi] = e.value;
      if (!(lo > 0) || !(hi >= lo) || !std::isfinite(hi))
        throw InputError("{hfov_range}", "", "expected MIN,MAX degrees with 0 < MIN <= MAX");
      limits[c].min_hfov_deg = lo;
      limits[c].max_hfov_deg = hi;
    }
  }
  return limits;
}

Objective ObjectiveOf(const SuggestRequest& r) {
  std::optional<Objective> objective = ParseObjective(r.objective);
  if (!objective)
    throw InputError(
        "{objective}", "", "unknown objective '" + r.objective + "'",
        "use coverage2 (or coverageK), sigma-mean, sigma-p90 (any percentile), resolution, mix, "
        "coverage3-n1 (coverageK-n1: after the worst camera failure) or calibration");
  if (r.weights) {
    const Vec3& w = *r.weights;
    if (!w.allFinite() || (w.array() < 0).any() || w.sum() <= 0)
      throw InputError("{weights}", "", "the weights must be >= 0 and not all zero");
    objective->w_coverage = w[0];
    objective->w_sigma = w[1];
    objective->w_resolution = w[2];
  }
  return *objective;
}

}  // namespace

SuggestOptions SuggestOptionsOf(const SuggestRequest& r, const Scene& scene, const Rig& rig) {
  SuggestOptions options;
  options.scene_path = scene.path;
  for (const std::string& id : r.cameras)
    options.cameras.push_back(CameraOption(rig, "{cameras}", id));
  options.limits = LimitsOf(r, scene, rig, options.cameras);
  for (const Aabb& box : r.keep_out) {
    CheckBox(scene, "{keep_out}", box);
    options.keep_out.push_back(box);
  }
  options.objective = ObjectiveOf(r);
  // The CLI checks the number options' ranges as it parses them (app/suggest_command.cpp); the
  // same here for every front end, and lengths against the scene's scale.
  if (!(r.points >= 1 && r.points <= 1000000))
    throw InputError("{points}", "", "must be a whole number in [1, 1000000]");
  if (!(r.snap_move >= 0)) throw InputError("{snap_move}", "", "must be >= 0 metres (0: off)");
  if (!(r.snap_rotate_deg >= 0 && r.snap_rotate_deg <= 180))
    throw InputError("{snap_rotate_deg}", "", "must be in [0, 180] degrees (0: off)");
  if (!(r.clearance >= 0)) throw InputError("{clearance}", "", "must be >= 0 metres");
  if (!(r.outer_iterations >= 1 && r.outer_iterations <= 1000))
    throw InputError("{outer_iterations}", "", "must be a whole number in [1, 1000]");
  options.snap_move = r.snap_move;
  options.snap_rotate_deg = r.snap_rotate_deg;
  scene.CheckLength(options.snap_move, "{snap_move}", "the snap step");
  options.outer_iterations = r.outer_iterations;
  options.clearance = r.clearance;
  scene.CheckLength(options.clearance, "{clearance}", "the clearance");
  return options;
}

std::shared_ptr<SuggestProblem> PrepareSuggest(const SuggestRequest& args, const Scene& scene,
                                               const Rig& rig) {
  if (args.cameras.empty())
    throw InputError("{cameras}", "", "which cameras may move?",
                     "give {cameras} ID,... (or {ptz_preset} / {ptz_tour})");
  auto problem = std::make_shared<SuggestProblem>();
  problem->options = SuggestOptionsOf(args, scene, rig);
  if (args.over_time) {
    // The study's surface targets at every sample, each against its sample's caster.
    if (!args.target_surfaces.empty())
      throw InputError("{over_time}", "",
                       "takes the study's targets; {target_surfaces} is for a static scene",
                       "give one of them");
    const std::vector<TimeSample> samples = scene.TimeSamples();
    problem->targets = SampleTimeTargets(scene, samples, args.points, args.seed);
    problem->parts = MakeSceneParts(scene);
    for (const TimeSample& s : samples) {
      problem->sample_casters.push_back(
          CasterAtSample(*problem->parts, scene, s));  // skinned parts posed too
      problem->options.sample_casters.push_back(problem->sample_casters.back().get());
    }
  } else {
    problem->targets =
        SampleTargets(scene, args.points, args.target_surfaces, args.with_region, args.seed);
  }
  return problem;
}

}  // namespace pandora::app
