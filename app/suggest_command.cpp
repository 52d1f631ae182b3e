// `pandora suggest` (nudge the selected cameras within limits; print the before/after table; write
// the suggestion file) and `pandora accept` (write the accepted poses into the scene file, after a
// backup). docs/suggest.md describes both.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "analysis/geometry/ray_caster.h"
#include "analysis/rig/rig_check.h"
#include "analysis/scene/motion.h"
#include "analysis/util/error.h"
#include "analysis/util/json_reader.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/options.h"
#include "app/output.h"
#include "app/report/suggest_comparison.h"
#include "app/session/session.h"
#include "app/suggest_options.h"
#include "suggest/suggestion_file.h"
#include "suggest/suggestion_text.h"

namespace pandora::app {

int RunSuggest(const SuggestArgs& args) {
  if (!args.ptz_preset.empty() || !args.ptz_tour.empty()) return RunSuggestPtz(args);
  if (args.cameras.empty())
    throw InputError("--cameras", "", "which cameras may move?",
                     "give --cameras ID,... (or --ptz-preset / --ptz-tour)");
  if (!args.target_region.empty())
    throw InputError("--target-region", "", "is for --ptz-preset and --ptz-tour",
                     "use --target-surface for camera nudges");
  // Parse and check: the study through the session layer, then every option against it.
  session::Session session(session::Study::Load(args.scene), SuggestSessionOptions(args));
  const Scene& scene = session.study().scene();
  const Rig file_rig = session.rig().rig();
  const std::shared_ptr<SuggestProblem> problem =
      PrepareSuggest(SuggestRequestFromArgs(args), scene, file_rig);
  const SuggestOptions& options = problem->options;
  const std::vector<TargetPoint>& targets = problem->targets;
  std::optional<std::vector<double>> perturbation;
  if (!args.perturb.empty()) {
    perturbation = ParseNumbers("--perturb", args.perturb, 2);
    if ((*perturbation)[0] < 0 || (*perturbation)[1] < 0 || (*perturbation)[1] >= 180)
      throw InputError("--perturb", "", "expected MOVE >= 0 metres and DEG in [0, 180)");
    scene.CheckLength((*perturbation)[0], "--perturb", "the move");
  }

  // The suggestion and the baseline comparison appear together, and replace no input.
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string suggestion_path = output.Stage(args.out, "--out");
  const std::string stem = args.compare_baseline + "/suggest_vs_baseline";
  std::string csv_path, svg_path;
  if (!args.compare_baseline.empty()) {
    csv_path = output.Stage(stem + ".csv", "--compare-baseline");
    svg_path = output.Stage(stem + ".svg", "--compare-baseline");
  }

  // Run: a benchmark perturbation is an edit of the session's rig; the suggestion starts from it.
  std::optional<double> original;
  if (perturbation) {
    original = EvaluateExact(scene, file_rig, session.study().caster(), targets, options.objective,
                             options.sample_casters)
                   .objective;
    const Rig perturbed = PerturbCameras(file_rig, options.cameras, (*perturbation)[0],
                                         (*perturbation)[1], args.seed);
    std::vector<session::EditableRig::Pose> poses;
    for (int c : options.cameras)
      poses.push_back({perturbed.cameras[c].id, perturbed.cameras[c].world_from_camera, 1.0});
    session.rig().SetPoses(poses, "perturb for a benchmark", scene.path);
  }
  const Rig& rig = session.rig().rig();
  const Suggestion s = session.Suggest(targets, options);
  if (!args.quiet) {  // the table first: the baseline comparison takes as long again
    std::fputs(FormatSuggestion(s, {"pandora suggest", scene.path, rig.name}).c_str(), stdout);
    if (original) std::fputs(FormatRecovery(s, *original, args.perturb).c_str(), stdout);
    std::fflush(stdout);
  }
  std::string text = SuggestionToJson(s, scene, rig, options);
  // A perturbed suggestion is not acceptable: its "before" poses are not the scene file's.
  if (perturbation) text.insert(text.find('{') + 1, "\n \"perturbed_for_benchmark\": true,");
  WriteFileAtomically(suggestion_path, text);
  std::optional<report::SuggestComparison> comparison;
  if (!args.compare_baseline.empty()) {
    comparison = report::CompareWithBaselines(scene, rig, session.study().caster(), targets,
                                              options, s, args.seed + 1, original);
    WriteFileAtomically(csv_path, comparison->csv);
    WriteFileAtomically(svg_path, comparison->svg);
  }
  // The rig as the file has it: its warnings, after every input check.
  const std::vector<Warning> warnings =
      args.quiet ? std::vector<Warning>() : CheckRig(scene, file_rig, session.study().caster());
  output.Commit();

  if (!args.quiet) {
    if (comparison) std::printf("\n%s", comparison->table.c_str());
    std::printf("wrote %s%s\n", args.out.c_str(),
                s.improved ? "" : " (no improvement: nothing to accept)");
    if (comparison) std::printf("wrote %s.csv and %s.svg\n", stem.c_str(), stem.c_str());
  }
  std::fflush(stdout);
  for (const Warning& w : warnings)
    std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(scene.path, w).c_str());
  return 0;
}

int RunAccept(const AcceptArgs& args) {
  if (args.proposal > 0) {
    if (!args.cameras.empty())
      throw InputError("--cameras", "", "a proposal is accepted whole, as a new rig");
    return AcceptProposal(args.suggestion, args.proposal, args.name, args.force, args.quiet);
  }
  if (!args.name.empty()) throw InputError("--name", "", "--name goes with --proposal");
  if (ReadJsonFile(args.suggestion, "suggestion file").contains("pandora_proposals"))
    throw InputError("--proposal", "", "a proposals file: which proposal?",
                     "give --proposal N (proposals.md lists them)");
  AcceptOptions options;
  options.force = args.force;
  if (!args.cameras.empty()) options.cameras = SplitList(args.cameras);
  // A suggest run killed while committing its outputs is finished before its suggestion is read.
  RecoverOutputs(std::filesystem::path(args.suggestion).parent_path().string());
  const AcceptResult r = AcceptSuggestion(args.suggestion, options);
  std::string ids;
  for (const std::string& id : r.accepted) ids += (ids.empty() ? "" : ", ") + id;
  if (!args.quiet) {
    std::printf("accepted %s into %s (previous file kept as %s)\n", ids.c_str(),
                r.scene_path.c_str(), r.backup_path.c_str());
    for (const std::string& note : r.notes) std::printf("note: %s\n", note.c_str());
  }
  return 0;
}

// Registers `pandora suggest` and its options.
Command AddSuggestCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<SuggestArgs>();
  SuggestArgs& suggest = *args;
  int& threads = common.threads;
  const CLI::Validator& threads_check = common.threads_check;
  CLI::App* sg = app.add_subcommand(
      "suggest",
      "Nudge the selected cameras within limits to improve an objective; write a suggestion");
  sg->add_option("scene", suggest.scene, "Scene file (JSON)")->required();
  sg->add_option("--rig", suggest.rig, "Rig name (default: the first rig)");
  sg->add_option("--disable", suggest.disable,
                 "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                 "loses when they fail)")
      ->delimiter(',');
  sg->add_option("--cameras", suggest.cameras,
                 "Comma-separated ids of the cameras that may move (or --ptz-preset / --ptz-tour)");
  sg->add_option(
      "--ptz-preset", suggest.ptz_preset,
      "PTZ: ID:PRESET, the pan, tilt and zoom of that preset that best cover the targets");
  sg->add_option("--ptz-tour", suggest.ptz_tour,
                 "PTZ: ID, the order of its tour's stops with the shortest longest unwatched gap "
                 "over the targets");
  sg->add_option("--tour-objective", suggest.tour_objective,
                 "With --ptz-tour: minimise the mean of the points' longest unwatched gaps (mean) "
                 "or the longest of all (max)")
      ->capture_default_str();
  sg->add_option("--target-region", suggest.target_region,
                 "Target points in this named region of the study (study.regions) instead of the "
                 "whole region");
  sg->add_option("--max-move", suggest.max_move,
                 "Largest move, metres: one value, or one per camera in --cameras order")
      ->capture_default_str();
  sg->add_option("--max-rotate", suggest.max_rotate,
                 "Largest rotation, degrees: one value, or one per camera")
      ->capture_default_str();
  sg->add_option("--objective", suggest.objective,
                 "coverage2 (coverageK), sigma-mean, sigma-p90 (sigma-pNN), resolution, mix, "
                 "coverage3-n1 (coverageK-n1, after the worst camera failure), calibration "
                 "(study.calibration)")
      ->capture_default_str();
  sg->add_option("--weights", suggest.weights,
                 "Mix weights WC,WS,WR (coverage, sigma, resolution)");
  sg->add_option("--rail", suggest.rail,
                 "Mount: stay on the line through the camera along [ID:]DX,DY,DZ (repeatable)");
  sg->add_option(
      "--plane", suggest.plane,
      "Mount: stay on the plane through the camera with normal [ID:]NX,NY,NZ (repeatable)");
  sg->add_option("--mount-box", suggest.mount_box,
                 "Mount: stay inside [ID:]XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX, metres in the world frame "
                 "(repeatable)");
  sg->add_option("--hfov-range", suggest.hfov_range,
                 "Zoom: the horizontal FOV may change within [ID:]MIN,MAX degrees (repeatable)");
  sg->add_option("--keep-out", suggest.keep_out,
                 "Box XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (metres, world frame) no camera centre may "
                 "enter (repeatable)");
  sg->add_option("--clearance", suggest.clearance,
                 "Keep every suggested camera centre this far from every scene surface, metres (a "
                 "camera already closer never moves closer)")
      ->capture_default_str()
      ->check(Number(0, HUGE_VAL, "metres"));
  sg->add_option("--target-surface", suggest.target_surfaces,
                 "Object whose surface is the target (repeatable)");
  sg->add_flag("--with-region", suggest.with_region,
               "With --target-surface: region points as well");
  sg->add_flag("--over-time", suggest.over_time,
               "Target the study's surface targets at every time sample (moving people; --points "
               "per target)");
  sg->add_option("--points", suggest.points, "Target points")
      ->capture_default_str()
      ->check(Number(1, 1000000, "target points", true));
  sg->add_option("--snap-move", suggest.snap_move,
                 "Round moves to multiples of this, metres (0: off)")
      ->check(Number(0, HUGE_VAL, "metres (0: off)"));
  sg->add_option("--snap-rotate", suggest.snap_rotate,
                 "Round yaw/pitch/roll changes to multiples of this, degrees")
      ->check(Number(0, 180, "degrees (0: off)"));
  sg->add_option("--outer", suggest.outer_iterations,
                 "Outer iterations (occlusion re-evaluated between)")
      ->check(Number(1, 1000, "outer iterations", true));
  sg->add_option("--out", suggest.out, "Suggestion file")->capture_default_str();
  sg->add_option("--perturb", suggest.perturb,
                 "Benchmark: first move and rotate the selected cameras by MOVE,DEG");
  sg->add_option(
      "--compare-baseline", suggest.compare_baseline,
      "Also run random local search with the same budget; write CSV and SVG to this folder");
  sg->add_option("--seed", suggest.seed, "Seed for target points and perturbations")
      ->capture_default_str()
      ->check(Number(0, 9.2e18, "(any whole number)", true));
  sg->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  sg->add_flag("--quiet,-q", suggest.quiet, "Print nothing but errors");
  return {sg, [args] { return RunSuggest(*args); }};
}

// Registers `pandora accept` and its options.
Command AddAcceptCommand(CLI::App& app, CommonOptions& /*common*/) {
  auto args = std::make_shared<AcceptArgs>();
  AcceptArgs& accept = *args;
  CLI::App* ac = app.add_subcommand(
      "accept",
      "Write a suggestion's poses, or a proposal as a new rig, into the scene file (keeps a "
      "backup)");
  ac->add_option("suggestion", accept.suggestion, "Suggestion file from pandora suggest")
      ->required();
  ac->add_option("--cameras", accept.cameras, "Comma-separated ids to accept (default: all)");
  ac->add_flag("--force", accept.force, "Accept even if the scene file changed since");
  ac->add_option("--proposal", accept.proposal,
                 "With a proposals file (pandora propose): add proposal N as a rig");
  ac->add_option("--name", accept.name, "With --proposal: the new rig's name");
  ac->add_flag("--quiet,-q", accept.quiet, "Print nothing but errors");
  return {ac, [args] { return RunAccept(*args); }};
}

}  // namespace pandora::app
