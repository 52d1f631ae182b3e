// `pandora propose`: global layout proposals from mounts x aims x lenses (docs/propose.md), and
// `pandora accept PROPOSALS --proposal N`, which writes one of them into the scene as a rig.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/scene/motion.h"
#include "analysis/scene/scene_text.h"
#include "analysis/util/error.h"
#include "analysis/util/json_reader.h"
#include "analysis/util/output_transaction.h"
#include "analysis/util/sha256.h"
#include "analysis/util/text.h"
#include "analysis/util/units.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/options.h"
#include "app/output.h"
#include "suggest/propose.h"
#include "suggest/suggest.h"

namespace pandora::app {
namespace {

using scene_text::ordered_json;

struct ProposeArgs {
  std::string scene, out = "out/propose", objective = "coverage3", mounts = "walls,ceiling";
  std::string heights, objects, points_list, box, catalogue, models, compare, curve, budgets;
  int cameras = 12, proposals = 3, points = 500, aims = 4;
  double budget = 0, spacing = 0.5, clearance = 0.1, seconds = 20;
  std::uint64_t seed = 1;
  std::int64_t iterations = 0;
  bool polish = false;
  bool quiet = false;
};

ordered_json ProposalNumber(double v) { return scene_text::Number(scene_text::Clean(v)); }
ordered_json ProposalPoint(const Vec3& v) {
  return ordered_json::array({ProposalNumber(v.x()), ProposalNumber(v.y()), ProposalNumber(v.z())});
}

// A camera in the scene format (metres): position, look_at 1 m along the axis, up, lens.
ordered_json CameraJson(const Camera& c, const ProposeLens& lens, const std::string& surface) {
  const Vec3 p = c.center(), axis = c.world_from_camera.linear().col(2),
             up = -c.world_from_camera.linear().col(1);
  ordered_json j = {{"id", c.id},
                    {"position", ProposalPoint(p)},
                    {"look_at", ProposalPoint(p + axis)},
                    {"up", ProposalPoint(up)},
                    {"resolution", {lens.intrinsics.width, lens.intrinsics.height}},
                    {"hfov_deg", ProposalNumber(lens.hfov_deg)}};
  if (lens.intrinsics.model != LensModel::kPinhole)
    j["distortion"] = scene_text::DistortionJson(lens.intrinsics);
  if (lens.far < 1e8)
    j["range"] = {{"near", ProposalNumber(lens.near)}, {"far", ProposalNumber(lens.far)}};
  else
    j["range"] = {{"near", ProposalNumber(lens.near)}};
  j["model"] = lens.model.empty() ? "scene" : lens.model;
  j["mount"] = surface;
  return j;
}

ordered_json TermsJson(const std::vector<ProposeTerm>& terms, const Proposal& p) {
  ordered_json out = ordered_json::array();
  for (std::size_t t = 0; t < terms.size(); ++t)
    out.push_back({{"term", terms[t].name},
                   {"weight", terms[t].weight},
                   {"k", terms[t].k},
                   {"n1", terms[t].n1},
                   {"min_px_per_m", terms[t].min_px_per_m},
                   {"value", p.terms[t]}});
  return out;
}

std::vector<ProposeLens> Lenses(const ProposeArgs& args, const Scene& scene) {
  std::vector<ProposeLens> lenses;
  if (!args.catalogue.empty()) {
    lenses = ReadCameraCatalogue(args.catalogue);
    if (!args.models.empty()) {
      const std::vector<std::string> names = SplitList(args.models);
      std::vector<ProposeLens> kept;
      for (const ProposeLens& l : lenses)
        for (const std::string& n : names) kept.insert(kept.end(), n == l.model ? 1 : 0, l);
      for (const std::string& n : names) {
        bool found = false;
        for (const ProposeLens& l : lenses) found |= l.model == n;
        if (!found) throw InputError("--models", "", "no model '" + n + "' in the catalogue");
      }
      lenses = kept;
    }
    return lenses;
  }
  if (!args.models.empty()) throw InputError("--models", "", "--models needs --catalogue");
  // The scene's own camera: the first rig's first fixed camera.
  for (const Camera& c : scene.rigs.front().cameras) {
    if (c.ptz) continue;
    ProposeLens lens;
    lens.intrinsics = c.model.intrinsics();
    lens.hfov_deg =
        HfovFromFocal(lens.intrinsics.fx, lens.intrinsics.width, lens.intrinsics.model) *
        kDegPerRad;
    lens.near = c.near;
    lens.far = std::isfinite(c.far) ? c.far : 1e9;
    return {lens};
  }
  throw InputError("--catalogue", "", "the scene's first rig has no fixed camera to copy",
                   "give --catalogue FILE");
}

std::vector<MountPoint> Mounts(const ProposeArgs& args, const Scene& scene) {
  std::vector<MountPoint> mounts;
  const Aabb& region = scene.study.region.box;
  std::vector<double> heights = {std::max(region.max.z() + 0.2, 2.0),
                                 std::max(region.max.z() + 0.6, 2.4)};
  if (!args.heights.empty())
    heights = ParseNumbers("--mount-heights", args.heights, SplitList(args.heights).size());
  for (const std::string& kind : SplitList(args.mounts)) {
    std::vector<MountPoint> add;
    if (kind == "walls")
      add = WallMounts(scene, heights, args.spacing, args.clearance);
    else if (kind == "ceiling")
      add = CeilingMounts(scene, args.spacing, args.clearance);
    else if (kind == "none")
      continue;
    else
      throw InputError("--mounts", "", "unknown mount kind '" + kind + "'",
                       "walls, ceiling or none (and --mount-objects, --mount-points)");
    mounts.insert(mounts.end(), add.begin(), add.end());
  }
  if (!args.objects.empty()) {
    const std::vector<MountPoint> add =
        ObjectMounts(scene, SplitList(args.objects), args.spacing, args.clearance);
    mounts.insert(mounts.end(), add.begin(), add.end());
  }
  if (!args.box.empty()) {
    const std::vector<double> b = ParseNumbers("--mount-box", args.box, 6);
    Aabb box;
    box.Extend(Vec3(b[0], b[1], b[2]));
    box.Extend(Vec3(b[3], b[4], b[5]));
    const std::vector<MountPoint> add = BoxMounts(scene, box, args.spacing, args.clearance);
    mounts.insert(mounts.end(), add.begin(), add.end());
  }
  if (!args.points_list.empty()) {
    std::istringstream in(args.points_list);
    std::string item;
    while (std::getline(in, item, ';'))
      mounts.push_back({ParseVec3("--mount-points", item), "point"});
  }
  if (mounts.empty())
    throw InputError("--mounts", "", "no mount points were found",
                     "the walls and ceiling need geometry round the region; or give "
                     "--mount-objects, --mount-box or --mount-points");
  return mounts;
}

std::string ProposalPercent(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f %%", 100 * v);
  return b;
}

// The two trade-off curves (cameras, and cost) into the JSON document and the table; the camera
// curve's CSV.
std::string AddCurves(const ProposeResult& result, int cameras, ordered_json* doc_out,
                      std::string* md_out) {
  ordered_json& doc = *doc_out;
  std::string& md = *md_out;
  std::string csv;
  if (!result.curve.empty()) {
    doc["curve"] = ordered_json::array();
    csv = "cameras,objective\n";
    md += "\nTrade-off (greedy + annealing per count):\n\n| Cameras | Objective |\n|---|---|\n";
    for (const auto& [n, v] : result.curve) {
      doc["curve"].push_back({{"cameras", n}, {"objective", v}});
      csv += std::to_string(n) + "," + std::to_string(v) + "\n";
      md += "| " + std::to_string(n) + " | " + ProposalPercent(v) + " |\n";
    }
  }
  if (!result.budget_curve.empty()) {
    doc["budget_curve"] = ordered_json::array();
    md += "\nTrade-off against cost (at most " + std::to_string(cameras) +
          " cameras):\n\n| Budget | Cameras | Price | Objective |\n|---|---|---|---|\n";
    for (const ProposeResult::BudgetPoint& b : result.budget_curve) {
      doc["budget_curve"].push_back({{"budget", b.budget},
                                     {"cameras", b.cameras},
                                     {"price", b.price},
                                     {"objective", b.objective}});
      md += "| " + std::to_string(int(b.budget)) + " | " + std::to_string(b.cameras) + " | " +
            std::to_string(int(b.price)) + " | " + ProposalPercent(b.objective) + " |\n";
    }
  }
  return csv;
}

// The Ceres nudge of `pandora suggest` on every camera of a layout (within 0.3 m and 10 degrees,
// `clearance` from every surface) over the same target points, for the first coverage term; kept
// only when the layout's whole objective, judged again, improves.
bool PolishLayout(const Scene& scene, const RayCaster& caster,
                  const std::vector<const RayCaster*>& casters,
                  const std::vector<TargetPoint>& targets, const std::vector<ProposeTerm>& terms,
                  double clearance, Rig* rig, Proposal* score) {
  const auto first =
      std::find_if(terms.begin(), terms.end(), [](const ProposeTerm& t) { return !t.calibration; });
  if (first == terms.end() || rig->cameras.empty()) return false;
  SuggestOptions o;
  for (std::size_t i = 0; i < rig->cameras.size(); ++i) o.cameras.push_back(int(i));
  CameraLimits limits;
  limits.max_move = 0.3;
  limits.max_rotate_deg = 10;
  o.limits = {limits};
  o.sample_casters = casters;
  o.clearance = clearance;
  o.outer_iterations = 1;
  o.scene_path = scene.path;
  o.objective.kind = first->n1 ? ObjectiveKind::kCoverageN1 : ObjectiveKind::kCoverage;
  o.objective.k = first->k;
  const Suggestion s = Suggest(scene, *rig, caster, targets, o);
  if (!s.improved) return false;
  Rig polished = *rig;
  for (const CameraChange& c : s.cameras)
    polished.cameras[std::size_t(c.index)].world_from_camera = c.after;
  Proposal after = ScoreCameras(scene, caster, casters, targets, polished.cameras, terms);
  if (!(after.objective > score->objective)) return false;
  after.candidates = score->candidates;
  after.price = score->price;
  *rig = polished;
  *score = after;
  return true;
}

// The options' values checked (InputError naming the option); the objective and the curve's range.
void CheckProposeArgs(const ProposeArgs& args, int* curve_from, int* curve_to) {
  if (args.cameras < 1 || args.cameras > 500)
    throw InputError("--cameras", "", "expected 1 to 500 cameras");
  if (args.proposals < 1 || args.proposals > 20)
    throw InputError("--proposals", "", "expected 1 to 20 proposals");
  if (args.points < 10 || args.points > 100000)
    throw InputError("--points", "", "expected 10 to 100000 points");
  if (!(args.spacing >= 0.05 && args.spacing <= 100))
    throw InputError("--spacing", "", "expected 0.05 to 100 m");
  if (!(args.seconds > 0 && args.seconds <= 86400))
    throw InputError("--seconds", "", "expected a positive time up to a day");
  if (!args.curve.empty()) {
    const auto colon = args.curve.find(':');
    const std::vector<double> r =
        colon == std::string::npos
            ? std::vector<double>{}
            : ParseNumbers("--curve",
                           args.curve.substr(0, colon) + "," + args.curve.substr(colon + 1), 2);
    if (r.size() != 2 || !(r[0] >= 1 && r[1] >= r[0] && r[1] <= 200))
      throw InputError("--curve", "", "expected FROM:TO cameras, 1 <= FROM <= TO <= 200");
    *curve_from = int(r[0]), *curve_to = int(r[1]);
  }
}

int RunPropose(const ProposeArgs& args) {
  int curve_from = 0, curve_to = 0;
  CheckProposeArgs(args, &curve_from, &curve_to);
  const std::string text = scene_text::ReadJsonText(args.scene, "scene file");
  const Scene scene = ParseScene(text, args.scene);
  ProposeOptions options;
  options.cameras = args.cameras;
  options.budget = args.budget;
  options.proposals = args.proposals;
  options.terms = ParseProposeObjective(args.objective, scene);
  if (!args.budgets.empty()) {
    options.curve_budgets =
        ParseNumbers("--curve-budgets", args.budgets, SplitList(args.budgets).size());
    for (double b : options.curve_budgets)
      if (!(b > 0 && b < 1e12))
        throw InputError("--curve-budgets", "", "expected positive budgets");
    if (args.catalogue.empty())
      throw InputError("--curve-budgets", "", "budgets need prices: give --catalogue");
  }
  options.aims = args.aims;
  options.seconds = args.seconds;
  options.seed = args.seed;
  if (args.iterations < 0 || args.iterations > 1000000000)
    throw InputError("--iterations", "", "expected 0 to 1e9 swap trials");
  options.iterations = args.iterations;
  options.lenses = Lenses(args, scene);
  options.mounts = Mounts(args, scene);
  if (!args.quiet)
    options.progress = [](const std::string& stage, double f) {
      std::fprintf(stderr, "\r%s %3.0f%%", stage.c_str(), 100 * f);
    };
  // The target points: the study's targets at every time sample, else the region.
  std::vector<TargetPoint> targets;
  std::unique_ptr<RigidPartsRayCaster> parts;
  std::vector<std::unique_ptr<RayCaster>> sample_casters;
  std::vector<const RayCaster*> casters;
  if (scene.study.targets) {
    const std::vector<TimeSample> samples = scene.TimeSamples();
    targets = SampleTimeTargets(scene, samples, args.points, args.seed);
    parts = MakeSceneParts(scene);
    for (const TimeSample& s : samples) {
      sample_casters.push_back(CasterAtSample(*parts, scene, s));
      casters.push_back(sample_casters.back().get());
    }
  } else {
    targets = SampleTargets(scene, args.points, {}, true, args.seed);
  }
  const auto caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const ProposeResult result =
      Propose(scene, *caster, casters, targets, options, curve_from, curve_to);
  if (!args.quiet) std::fprintf(stderr, "\r");

  // Existing rigs judged alike.
  std::vector<std::pair<std::string, Proposal>> compared;
  const std::vector<std::string> names =
      args.compare.empty() ? std::vector<std::string>{} : SplitList(args.compare);
  for (const Rig& rig : scene.rigs)
    if (args.compare == "all" || std::find(names.begin(), names.end(), rig.name) != names.end())
      compared.emplace_back(
          rig.name, ScoreCameras(scene, *caster, casters, targets, rig.cameras, options.terms));
  for (const std::string& n : names)
    if (n != "all") FindRigOption(scene, n);

  ordered_json doc = {
      {"pandora_proposals", 1},
      {"scene", std::filesystem::absolute(args.scene).lexically_normal().string()},
      {"scene_sha256", Sha256Hex(text)},
      {"objective", args.objective},
      {"points", result.points},
      {"samples", std::max<std::size_t>(1, casters.size())},
      {"mounts", options.mounts.size()},
      {"lenses", options.lenses.size()},
      {"candidates", result.candidates.size()},
      {"seconds", {{"visibility", result.visibility_seconds}, {"search", result.search_seconds}}},
      {"proposals", ordered_json::array()},
      {"compared", ordered_json::array()}};
  std::string md = "# Proposals for " + args.scene + "\n\nObjective " + args.objective + " over " +
                   std::to_string(result.points) + " target points; " +
                   std::to_string(result.candidates.size()) + " candidates (" +
                   std::to_string(options.mounts.size()) + " mounts x " +
                   std::to_string(options.aims + 1) + " aims x " +
                   std::to_string(options.lenses.size()) +
                   " lenses).\n\n| Layout | Cameras | Objective | Seen by >= k | N-1 | Price "
                   "|\n|---|---|---|---|---|---|\n";
  for (std::size_t p = 0; p < result.proposals.size(); ++p) {
    Proposal proposal = result.proposals[p];
    const std::string name = "prop" + std::to_string(p + 1);  // ids prop1_12 fit the colour key
    Rig rig = ProposalRig(result, proposal, name);
    const double unpolished = proposal.objective;
    const bool polished =
        args.polish && PolishLayout(scene, *caster, casters, targets, options.terms, args.clearance,
                                    &rig, &proposal);
    if (args.polish && !args.quiet)
      std::fprintf(stderr, "%s: polish %s (%.4f -> %.4f)\n", name.c_str(),
                   polished ? "kept" : "did not improve it", unpolished, proposal.objective);
    ordered_json cameras = ordered_json::array();
    for (std::size_t i = 0; i < rig.cameras.size(); ++i) {
      const int c = proposal.candidates[i];
      cameras.push_back(CameraJson(
          rig.cameras[i], options.lenses[std::size_t(result.candidate_lens[std::size_t(c)])],
          result.candidate_surface[std::size_t(c)]));
    }
    doc["proposals"].push_back({{"name", name},
                                {"objective", proposal.objective},
                                {"polished", polished},
                                {"unpolished_objective", unpolished},
                                {"terms", TermsJson(options.terms, proposal)},
                                {"coverage_k", proposal.coverage_k},
                                {"n1", proposal.n1},
                                {"price", proposal.price},
                                {"cameras", cameras}});
    md += "| " + name + " | " + std::to_string(rig.cameras.size()) + " | " +
          ProposalPercent(proposal.objective) + " | " + ProposalPercent(proposal.coverage_k) +
          " | " + ProposalPercent(proposal.n1) + " | " + std::to_string(int(proposal.price)) +
          " |\n";
  }
  for (const auto& [name, score] : compared) {
    doc["compared"].push_back({{"rig", name},
                               {"objective", score.objective},
                               {"terms", TermsJson(options.terms, score)},
                               {"coverage_k", score.coverage_k},
                               {"n1", score.n1}});
    md += "| " + name + " (in the scene) | " + std::to_string(scene.FindRig(name).enabled_count()) +
          " | " + ProposalPercent(score.objective) + " | " + ProposalPercent(score.coverage_k) +
          " | " + ProposalPercent(score.n1) + " | |\n";
  }
  const std::string csv = AddCurves(result, args.cameras, &doc, &md);
  md += "\nAccept one into the scene as a rig: `pandora accept " + args.out +
        "/proposals.json --proposal N`.\n";
  OutputTransaction transaction;
  transaction.AddInput(args.scene, "scene file");
  if (!args.catalogue.empty()) transaction.AddInput(args.catalogue, "camera catalogue");
  transaction.Write(args.out + "/proposals.json", "--out", doc.dump(2) + "\n");
  transaction.Write(args.out + "/proposals.md", "--out", md);
  if (!csv.empty()) transaction.Write(args.out + "/curve.csv", "--out", csv);
  transaction.Commit();
  if (!args.quiet) {
    std::printf("%s", md.c_str());
    std::printf("candidate visibility %.1f s, search %.1f s; wrote %s/proposals.json\n",
                result.visibility_seconds, result.search_seconds, args.out.c_str());
  }
  return 0;
}

}  // namespace

int AcceptProposal(const std::string& file, int number, const std::string& name, bool force,
                   bool quiet) {
  const nlohmann::json doc = ReadJsonFile(file, "proposals file");
  const JsonNode root = JsonNode::Root(doc, file);
  const std::string scene_path = root.Get("scene").NonEmptyString();
  const JsonNode proposals = root.Get("proposals");
  const std::size_t n = proposals.ArraySize(100, "an array of proposals");
  if (number < 1 || std::size_t(number) > n)
    throw InputError(
        "--proposal", "",
        "expected a proposal from 1 to " + std::to_string(n) + ", got " + std::to_string(number));
  const JsonNode chosen = proposals.At(std::size_t(number - 1));
  const std::string rig_name = name.empty() ? chosen.Get("name").NonEmptyString() : name;
  const std::string text = scene_text::ReadJsonText(scene_path, "scene file");
  if (!force && Sha256Hex(text) != root.Get("scene_sha256").String())
    throw InputError(scene_path, "", "the scene file changed since the proposals were made",
                     "propose again, or --force");
  ordered_json scene = scene_text::ParseOrdered(text, scene_path);
  const double mpu = scene_text::MetresPerUnit(scene, scene_path);
  for (const ordered_json& r : scene["rigs"])
    if (r.is_object() && r.contains("name") && r["name"] == rig_name)
      throw InputError("--name", "", "the scene already has a rig '" + rig_name + "'",
                       "give --name NEW_NAME");
  ordered_json rig = {{"name", rig_name}, {"cameras", ordered_json::array()}};
  const JsonNode cameras = chosen.Get("cameras");
  for (std::size_t i = 0; i < cameras.ArraySize(10000, "an array of cameras"); ++i) {
    const JsonNode camera = cameras.At(i);
    camera.ExpectObject("a camera");
    ordered_json c = ordered_json::parse(camera.value().dump());
    // Lengths in metres, checked here (a damaged file names its own path), written in the file's
    // unit; everything else is checked when the new scene is read.
    for (const char* key : {"position", "look_at"}) {
      const Eigen::VectorXd v = camera.Get(key).Numbers(3);
      c[key] = ordered_json::array();
      for (int a = 0; a < 3; ++a)
        c[key].push_back(scene_text::Number(scene_text::Clean(v[a] / mpu)));
    }
    if (auto range = camera.Find("range")) {
      range->ExpectObject("a range {near, far}");
      for (const auto& item : range->value().items())
        c["range"][item.key()] =
            scene_text::Number(scene_text::Clean(range->Get(item.key()).Number(0, 1e12) / mpu));
    }
    c.erase("model");
    c.erase("mount");
    if (!name.empty()) c["id"] = rig_name + "_" + std::to_string(i + 1);
    rig["cameras"].push_back(c);
  }
  scene["rigs"].push_back(rig);
  const std::string new_text = scene_text::DumpLike(scene, text);
  ParseScene(new_text, scene_path);  // the new file must read
  const std::string backup =
      ReplaceSceneFileWithBackup(scene_path, text, new_text, {{file, "proposals file"}});
  if (!quiet)
    std::printf("added rig %s (%zu cameras) to %s (previous file kept as %s)\n", rig_name.c_str(),
                rig["cameras"].size(), scene_path.c_str(), backup.c_str());
  return 0;
}

// Registers `pandora propose` and its options.
Command AddProposeCommand(CLI::App& app, CommonOptions& /*common*/) {
  auto args = std::make_shared<ProposeArgs>();
  ProposeArgs& a = *args;
  CLI::App* c = app.add_subcommand(
      "propose",
      "Propose whole layouts (how many cameras, which mounts, which lenses) by a global search; "
      "writes proposals to accept");
  c->add_option("scene", a.scene, "Scene file (JSON)")->required();
  c->add_option("--out", a.out, "Output folder")->capture_default_str();
  c->add_option("--cameras", a.cameras, "Cameras per layout (the most, with --budget)")
      ->capture_default_str();
  c->add_option("--budget", a.budget, "Total price limit (the catalogue's prices)");
  c->add_option("--proposals", a.proposals, "How many different layouts")->capture_default_str();
  c->add_option("--objective", a.objective,
                "Terms [W*]coverageK[-n1][@DENSITY] joined by +, DENSITY px/m, a DORI class or a "
                "pixel target (docs/propose.md)")
      ->capture_default_str();
  c->add_option("--points", a.points,
                "Target points (per target and sample with the study's targets, else in the "
                "region)")
      ->capture_default_str();
  c->add_option("--mounts", a.mounts, "Mount surfaces: walls, ceiling (comma-separated) or none")
      ->capture_default_str();
  c->add_option(
      "--mount-heights", a.heights,
      "Heights of wall mounts, metres (default: the region's top + 0.2 and + 0.6, at least 2 and "
      "2.4)");
  c->add_option("--mount-objects", a.objects, "Objects to mount under (trusses), comma-separated");
  c->add_option("--mount-points", a.points_list, "Mount points X,Y,Z;X,Y,Z;...");
  c->add_option("--mount-box", a.box,
                "Mount points filling the box X0,Y0,Z0,X1,Y1,Z1 at --spacing (free space only)");
  c->add_option("--spacing", a.spacing, "Mount spacing, metres")->capture_default_str();
  c->add_option("--clearance", a.clearance, "Mount distance from its surface, metres")
      ->capture_default_str();
  c->add_option("--catalogue", a.catalogue,
                "Camera catalogue (JSON; default: the scene's first camera)");
  c->add_option("--models", a.models, "Catalogue models to use, comma-separated (default: all)");
  c->add_option("--aims", a.aims, "Aim points per mount besides the targets' centre")
      ->capture_default_str();
  c->add_option("--seconds", a.seconds, "Search time, seconds (all layouts and the curve)")
      ->capture_default_str();
  c->add_option("--iterations", a.iterations,
                "Swap trials per layout instead of --seconds (reproducible on any machine)");
  c->add_option("--seed", a.seed, "Seed of the points and the search")->capture_default_str();
  c->add_option("--compare", a.compare,
                "Rigs of the scene to judge alike (comma-separated, or all)");
  c->add_flag("--polish", a.polish,
              "Nudge every layout with suggest's Ceres search (0.3 m, 10 degrees) and keep what "
              "improves it");
  c->add_option("--curve", a.curve, "Trade-off curve FROM:TO cameras");
  c->add_option("--curve-budgets", a.budgets,
                "Trade-off against cost: budgets B1,B2,... (the catalogue's prices; at most "
                "--cameras each)");
  c->add_flag("-q,--quiet", a.quiet, "Print nothing on success");
  return {c, [args] { return RunPropose(*args); }};
}

}  // namespace pandora::app
