#include "app/suggest_options.h"

#include <cmath>

#include "analysis/scene/motion.h"
#include "analysis/util/error.h"
#include "app/options.h"

namespace pandora::app {
namespace {

// One value for every selected camera, or one each in --cameras order.
std::vector<double> PerCamera(const char* option, const std::string& value, std::size_t selected) {
  const std::vector<std::string> items = SplitList(value);
  if (items.size() != 1 && items.size() != selected)
    throw InputError(
        option, "",
        "give one value, or one per selected camera (" + std::to_string(selected) + ")");
  std::vector<double> out;
  for (const std::string& item : items) out.push_back(ParseNumbers(option, item, 1)[0]);
  out.resize(selected, out.back());
  return out;
}

// "ID:VALUE" or "VALUE": the positions in the selection it applies to; *value gets VALUE.
std::vector<std::size_t> Targets(const char* option, const std::string& entry, const Rig& rig,
                                 const std::vector<int>& selection, std::string* value) {
  std::vector<std::size_t> which;
  const std::size_t colon = entry.find(':');
  *value = colon == std::string::npos ? entry : entry.substr(colon + 1);
  for (std::size_t c = 0; c < selection.size(); ++c)
    if (colon == std::string::npos || rig.cameras[selection[c]].id == entry.substr(0, colon))
      which.push_back(c);
  if (which.empty() && colon != std::string::npos)
    throw InputError(
        option, "",
        "camera '" + entry.substr(0, colon) + "' is not among the selected cameras ({cameras})");
  return which;
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

SuggestOptions SuggestOptionsFromArgs(const SuggestArgs& args, const Scene& scene, const Rig& rig) {
  SuggestOptions options;
  options.scene_path = scene.path;
  for (const std::string& id : SplitList(args.cameras))
    options.cameras.push_back(CameraOption(rig, "{cameras}", id));
  const std::size_t n = options.cameras.size();

  const std::vector<double> moves = PerCamera("{max_move}", args.max_move, n);
  const std::vector<double> rotations = PerCamera("{max_rotate_deg}", args.max_rotate, n);
  options.limits.assign(n, CameraLimits());
  for (std::size_t c = 0; c < n; ++c) {
    if (!(moves[c] >= 0))
      throw InputError("{max_move}", "", "must be a finite length >= 0 in metres");
    scene.CheckLength(moves[c], "{max_move}", "the move");
    if (!(rotations[c] >= 0) || !(rotations[c] < 180))
      throw InputError("{max_rotate_deg}", "", "must be an angle in [0, 180) degrees");
    options.limits[c].max_move = moves[c];
    options.limits[c].max_rotate_deg = rotations[c];
  }

  std::vector<int> mounts(n, 0);
  auto add_mount = [&](const char* option, const std::string& entry, MountConstraint::Kind kind) {
    std::string value;
    for (std::size_t c : Targets(option, entry, rig, options.cameras, &value)) {
      MountConstraint& m = options.limits[c].mount;
      m.kind = kind;
      if (kind == MountConstraint::Kind::kBox) {
        m.box = ParseBox(scene, option, value);
      } else {
        const std::vector<double> v = ParseNumbers(option, value, 3);
        m.axis = Vec3(v[0], v[1], v[2]);
        if (!(m.axis.norm() > 0))
          throw InputError(option, "", "the direction must be a non-zero vector");
      }
      if (++mounts[c] > 1)
        throw InputError(option, "", "give at most one of {rail}, {plane}, {mount_box} per camera");
    }
  };
  for (const std::string& e : args.rail) add_mount("{rail}", e, MountConstraint::Kind::kLine);
  for (const std::string& e : args.plane) add_mount("{plane}", e, MountConstraint::Kind::kPlane);
  for (const std::string& e : args.mount_box)
    add_mount("{mount_box}", e, MountConstraint::Kind::kBox);
  for (const std::string& e : args.hfov_range) {
    std::string value;
    for (std::size_t c : Targets("{hfov_range}", e, rig, options.cameras, &value)) {
      const std::vector<double> v = ParseNumbers("{hfov_range}", value, 2);
      if (!(v[0] > 0) || !(v[1] >= v[0]))
        throw InputError("{hfov_range}", "", "expected MIN,MAX degrees with 0 < MIN <= MAX");
      options.limits[c].min_hfov_deg = v[0];
      options.limits[c].max_hfov_deg = v[1];
    }
  }
  for (const std::string& box : args.keep_out)
    options.keep_out.push_back(ParseBox(scene, "{keep_out}", box));

  const std::optional<Objective> objective = ParseObjective(args.objective);
  if (!objective)
    throw InputError(
        "{objective}", "", "unknown objective '" + args.objective + "'",
        "use coverage2 (or coverageK), sigma-mean, sigma-p90 (any percentile), resolution, mix, "
        "coverage3-n1 (coverageK-n1: after the worst camera failure) or calibration");
  options.objective = *objective;
  if (!args.weights.empty()) {
    const std::vector<double> w = ParseNumbers("{weights}", args.weights, 3);
    if (w[0] < 0 || w[1] < 0 || w[2] < 0 || w[0] + w[1] + w[2] <= 0)
      throw InputError("{weights}", "", "the weights must be >= 0 and not all zero");
    options.objective.w_coverage = w[0];
    options.objective.w_sigma = w[1];
    options.objective.w_resolution = w[2];
  }
  // The number options' ranges are checked as they are parsed (app/main.cpp); lengths against the
  // scene's scale here.
  options.snap_move = args.snap_move;
  options.snap_rotate_deg = args.snap_rotate;
  scene.CheckLength(options.snap_move, "{snap_move}", "the snap step");
  options.outer_iterations = args.outer_iterations;
  options.clearance = args.clearance;
  scene.CheckLength(options.clearance, "{clearance}", "the clearance");
  return options;
}

std::shared_ptr<SuggestProblem> PrepareSuggest(const SuggestArgs& args, const Scene& scene,
                                               const Rig& rig) {
  if (args.cameras.empty())
    throw InputError("{cameras}", "", "which cameras may move?",
                     "give {cameras} ID,... (or {ptz_preset} / {ptz_tour})");
  auto problem = std::make_shared<SuggestProblem>();
  problem->options = SuggestOptionsFromArgs(args, scene, rig);
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
