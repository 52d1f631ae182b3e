// `pandora suggest` (nudge the selected cameras within limits; print the before/after table; write
// the suggestion file) and `pandora accept` (write the accepted poses into the scene file, after a
// backup). docs/suggest.md describes both.
#include <cstdio>
#include <filesystem>
#include <optional>

#include "analysis/geometry/ray_caster.h"
#include "analysis/rig/rig_check.h"
#include "analysis/scene/motion.h"
#include "analysis/util/error.h"
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
  const std::shared_ptr<SuggestProblem> problem = PrepareSuggest(args, scene, file_rig);
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

}  // namespace pandora::app
