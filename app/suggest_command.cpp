// `pandora suggest` (nudge the selected cameras within limits; print the before/after table; write
// the suggestion file) and `pandora accept` (write the accepted poses into the scene file, after a
// backup). docs/suggest.md describes both.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>

#include "analysis/error.h"
#include "analysis/ray_caster.h"
#include "analysis/rig_check.h"
#include "analysis/scene.h"
#include "app/commands.h"
#include "app/session/study.h"
#include "app/output.h"
#include "app/plot.h"
#include "suggest/suggest.h"
#include "suggest/suggestion_file.h"

namespace pandora::app {
namespace {

std::vector<std::string> SplitComma(const std::string& s) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, ',')) {
    const auto b = item.find_first_not_of(" \t");
    const auto e = item.find_last_not_of(" \t");
    out.push_back(b == std::string::npos ? "" : item.substr(b, e - b + 1));
  }
  return out;
}

std::vector<double> Numbers(const std::string& option, const std::string& value, std::size_t count) {
  std::vector<double> out;
  for (const std::string& s : SplitComma(value)) {
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || !end || *end != '\0' || !std::isfinite(v))
      throw InputError(option, "", "'" + value + "' is not a list of " + std::to_string(count) + " numbers",
                       "separate the numbers with commas");
    out.push_back(v);
  }
  if (out.size() != count)
    throw InputError(option, "", "expected " + std::to_string(count) + " comma-separated numbers, got " +
                                     std::to_string(out.size()));
  return out;
}

Aabb BoxOption(const Scene& scene, const std::string& option, const std::string& value) {
  const std::vector<double> v = Numbers(option, value, 6);
  Aabb b;
  b.min = Vec3(v[0], v[1], v[2]);
  b.max = Vec3(v[3], v[4], v[5]);
  scene.CheckReach(b.min, option, "the box's min corner");
  scene.CheckReach(b.max, option, "the box's max corner");
  if ((b.min.array() > b.max.array()).any())
    throw InputError(option, "", "the box's min exceeds its max", "give XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX");
  return b;
}

std::string Value(double v, const char* fmt = "%.4g") {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (std::isnan(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

void PrintTable(const Suggestion& s, const Scene& scene, const Rig& rig, const std::string& title) {
  std::printf("%s: scene %s, rig %s, objective %s (%s is better), %d target points\n", title.c_str(),
              scene.path.c_str(), rig.name.c_str(), ObjectiveName(s.objective).c_str(),
              ObjectiveHigherIsBetter(s.objective) ? "higher" : "lower", s.target_points);
  std::printf("\n%-10s %9s %12s  %-28s %-28s\n", "camera", "move (m)", "rotate (deg)", "position before",
              "position after");
  for (const CameraChange& c : s.cameras) {
    const Vec3 a = c.before.translation(), b = c.after.translation();
    char pa[64], pb[64];
    std::snprintf(pa, sizeof pa, "(%.3f, %.3f, %.3f)", a.x(), a.y(), a.z());
    std::snprintf(pb, sizeof pb, "(%.3f, %.3f, %.3f)", b.x(), b.y(), b.z());
    std::printf("%-10s %9.3f %12.2f  %-28s %-28s\n", c.id.c_str(), c.move_m, c.rotate_deg, pa, pb);
    if (c.focal_scale != 1.0)
      std::printf("           zoom: horizontal field of view %.2f -> %.2f deg\n", c.hfov_before_deg,
                  c.hfov_after_deg);
    if (std::isfinite(c.surface_distance_after) && c.surface_distance_after < 1.0)
      std::printf("           nearest surface: %.3f m -> %.3f m\n", c.surface_distance_before,
                  c.surface_distance_after);
    if (!c.note.empty()) std::printf("           note: %s\n", c.note.c_str());
  }
  auto row = [](const char* name, double a, double b) {
    std::printf("%-26s %14s %14s\n", name, Value(a).c_str(), Value(b).c_str());
  };
  std::printf("\n%-26s %14s %14s\n", "measure", "before", "after");
  row(("objective " + ObjectiveName(s.objective)).c_str(), s.before.objective, s.after.objective);
  row("coverage >= 2 (share)", s.before.coverage2, s.after.coverage2);
  if (s.objective.k != 2) {
    const std::string name = "coverage >= " + std::to_string(s.objective.k) + " (share)";
    row(name.c_str(), s.before.coverage_k, s.after.coverage_k);
  }
  row("sigma_max p50 (mm)", s.before.sigma_p50, s.after.sigma_p50);
  row("sigma_max p90 (mm)", s.before.sigma_p90, s.after.sigma_p90);
  row("sigma_max p95 (mm)", s.before.sigma_p95, s.after.sigma_p95);
  row("untriangulable (share)", s.before.untriangulable, s.after.untriangulable);
  row("min resolution (px/m)", s.before.min_resolution, s.after.min_resolution);
  if (s.unsnapped)
    std::printf("(before snapping the optimum had objective %s)\n", Value(s.unsnapped->objective).c_str());
  std::printf("\n");
  if (s.screened > 0)
    std::printf("screening: %d exact evaluations, best %s; then ", s.screened, Value(s.screened_objective).c_str());
  std::printf("%d iterations (%d outer), %lld evaluations, %.3f s\n%s\n", s.iterations,
              s.outer_iterations, static_cast<long long>(s.evaluations), s.seconds, s.message.c_str());
  if (scene.study.region.box.diagonal() > 0 && s.before.untriangulable > 0)
    std::printf("(inf: the percentile falls on a point that is not triangulable)\n");
}

// Time at which a trace first reaches `score` (objective, oriented), or +inf.
double TimeToReach(const std::vector<TracePoint>& trace, double target, bool higher) {
  for (const TracePoint& t : trace)
    if (higher ? t.objective >= target : t.objective <= target) return t.seconds;
  return std::numeric_limits<double>::infinity();
}

}  // namespace

int RunSuggest(const SuggestArgs& args) {
  // The study (scene and its ray caster, built once) through the session layer.
  const auto study = session::Study::Load(args.scene);
  const Scene& scene = study->scene();
  const Rig& file_rig = study->FindRig(args.rig, "--rig");
  SuggestOptions options;
  options.scene_path = scene.path;

  // Selection by camera id.
  for (const std::string& id : SplitComma(args.cameras)) {
    int found = -1;
    for (std::size_t c = 0; c < file_rig.cameras.size(); ++c)
      if (file_rig.cameras[c].id == id) found = static_cast<int>(c);
    if (found < 0) {
      std::string ids;
      for (const Camera& c : file_rig.cameras) ids += (ids.empty() ? "" : ", ") + c.id;
      throw InputError("--cameras", "", "no camera '" + id + "' in rig '" + file_rig.name + "'",
                       "cameras: " + ids);
    }
    options.cameras.push_back(found);
  }
  // Limits per selected camera: one value for all, or one per camera in --cameras order; mounts and
  // zoom ranges apply to all, or to one camera with an "ID:" prefix (repeatable).
  const std::size_t nsel = options.cameras.size();
  auto per_camera = [&](const char* option, const std::string& value) {
    const std::vector<std::string> items = SplitComma(value);
    if (items.size() != 1 && items.size() != nsel)
      throw InputError(option, "", "give one value, or one per selected camera (" + std::to_string(nsel) + ")");
    std::vector<double> out;
    for (const std::string& item : items) out.push_back(Numbers(option, item, 1)[0]);
    out.resize(nsel, out.back());
    return out;
  };
  const std::vector<double> moves = per_camera("--max-move", args.max_move);
  const std::vector<double> rotations = per_camera("--max-rotate", args.max_rotate);
  options.limits.assign(nsel, CameraLimits());
  for (std::size_t c = 0; c < nsel; ++c) {
    if (!(moves[c] >= 0)) throw InputError("--max-move", "", "must be a finite length >= 0 in metres");
    scene.CheckLength(moves[c], "--max-move", "the move");
    if (!(rotations[c] >= 0) || !(rotations[c] < 180))
      throw InputError("--max-rotate", "", "must be an angle in [0, 180) degrees");
    options.limits[c].max_move = moves[c];
    options.limits[c].max_rotate_deg = rotations[c];
  }
  // "ID:VALUE" or "VALUE": the selected cameras it applies to, and the value.
  auto targets_of = [&](const char* option, const std::string& entry, std::string* value) {
    std::vector<std::size_t> which;
    const std::size_t colon = entry.find(':');
    if (colon == std::string::npos) {
      *value = entry;
      for (std::size_t c = 0; c < nsel; ++c) which.push_back(c);
      return which;
    }
    const std::string id = entry.substr(0, colon);
    *value = entry.substr(colon + 1);
    for (std::size_t c = 0; c < nsel; ++c)
      if (file_rig.cameras[options.cameras[c]].id == id) which.push_back(c);
    if (which.empty())
      throw InputError(option, "", "camera '" + id + "' is not among the selected cameras (--cameras)");
    return which;
  };
  std::vector<int> mounts(nsel, 0);
  auto add_mount = [&](const char* option, const std::string& entry, MountConstraint::Kind kind) {
    std::string value;
    for (std::size_t c : targets_of(option, entry, &value)) {
      MountConstraint& m = options.limits[c].mount;
      m.kind = kind;
      if (kind == MountConstraint::Kind::kBox) {
        m.box = BoxOption(scene, option, value);
      } else {
        const std::vector<double> v = Numbers(option, value, 3);
        m.axis = Vec3(v[0], v[1], v[2]);
        if (!(m.axis.norm() > 0)) throw InputError(option, "", "the direction must be a non-zero vector");
      }
      if (++mounts[c] > 1)
        throw InputError(option, "", "give at most one of --rail, --plane, --mount-box per camera");
    }
  };
  for (const std::string& e : args.rail) add_mount("--rail", e, MountConstraint::Kind::kLine);
  for (const std::string& e : args.plane) add_mount("--plane", e, MountConstraint::Kind::kPlane);
  for (const std::string& e : args.mount_box) add_mount("--mount-box", e, MountConstraint::Kind::kBox);
  for (const std::string& e : args.hfov_range) {
    std::string value;
    for (std::size_t c : targets_of("--hfov-range", e, &value)) {
      const std::vector<double> v = Numbers("--hfov-range", value, 2);
      if (!(v[0] > 0) || !(v[1] >= v[0]))
        throw InputError("--hfov-range", "", "expected MIN,MAX degrees with 0 < MIN <= MAX");
      options.limits[c].min_hfov_deg = v[0];
      options.limits[c].max_hfov_deg = v[1];
    }
  }
  for (const std::string& box : args.keep_out) options.keep_out.push_back(BoxOption(scene, "--keep-out", box));
  const std::optional<Objective> objective = ParseObjective(args.objective);
  if (!objective)
    throw InputError("--objective", "", "unknown objective '" + args.objective + "'",
                     "use coverage2 (or coverageK), sigma-mean, sigma-p90 (any percentile), resolution or mix");
  options.objective = *objective;
  if (!args.weights.empty()) {
    const std::vector<double> w = Numbers("--weights", args.weights, 3);
    if (w[0] < 0 || w[1] < 0 || w[2] < 0 || w[0] + w[1] + w[2] <= 0)
      throw InputError("--weights", "", "the weights must be >= 0 and not all zero");
    options.objective.w_coverage = w[0];
    options.objective.w_sigma = w[1];
    options.objective.w_resolution = w[2];
  }
  if (args.points < 1 || args.points > 1000000)
    throw InputError("--points", "", "must be in 1..1000000");
  options.snap_move = args.snap_move;
  options.snap_rotate_deg = args.snap_rotate;
  if (!(options.snap_move >= 0) || !std::isfinite(options.snap_move))
    throw InputError("--snap-move", "", "must be a finite length >= 0 in metres");
  scene.CheckLength(options.snap_move, "--snap-move", "the snap step");
  if (!(options.snap_rotate_deg >= 0) || !std::isfinite(options.snap_rotate_deg))
    throw InputError("--snap-rotate", "", "must be a finite angle >= 0 in degrees");
  options.outer_iterations = args.outer_iterations;
  options.clearance = args.clearance;
  if (!(options.clearance >= 0) || !std::isfinite(options.clearance))
    throw InputError("--clearance", "", "must be a finite length >= 0 in metres");
  scene.CheckLength(options.clearance, "--clearance", "the clearance");

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

  Rig rig = file_rig;
  bool perturbed = false;
  if (!args.perturb.empty()) {
    const std::vector<double> p = Numbers("--perturb", args.perturb, 2);
    if (p[0] < 0 || p[1] < 0 || p[1] >= 180)
      throw InputError("--perturb", "", "expected MOVE >= 0 metres and DEG in [0, 180)");
    scene.CheckLength(p[0], "--perturb", "the move");
    rig = PerturbCameras(file_rig, options.cameras, p[0], p[1], args.seed);
    perturbed = true;
  }

  const RayCaster* caster = &study->caster();
  const std::vector<TargetPoint> targets =
      SampleTargets(scene, args.points, args.target_surfaces, args.with_region, args.seed);

  std::optional<Metrics> original;
  if (perturbed) original = EvaluateExact(scene, file_rig, *caster, targets, options.objective);

  const Suggestion s = Suggest(scene, rig, *caster, targets, options);
  if (!args.quiet) {
    PrintTable(s, scene, rig, "pandora suggest");
    if (original) {
      const double lost = original->objective - s.before.objective;
      const double regained = s.after.objective - s.before.objective;
      std::printf("perturbed by %s: objective at the original poses %s; recovered %s of the lost %s (%.0f%%)\n",
                  args.perturb.c_str(), Value(original->objective).c_str(), Value(regained).c_str(),
                  Value(lost).c_str(), lost != 0 ? 100.0 * regained / lost : 0.0);
    }
  }
  std::string text = SuggestionToJson(s, scene, rig, options);
  if (perturbed) {
    // Not acceptable: its "before" poses are not the scene file's.
    const std::size_t pos = text.find('{');
    text.insert(pos + 1, "\n \"perturbed_for_benchmark\": true,");
  }
  WriteFileAtomically(suggestion_path, text);
  // The rig as the file has it: its warnings, after every input check.
  const std::vector<Warning> warnings = args.quiet ? std::vector<Warning>() : CheckRig(scene, file_rig, *caster);

  if (!args.compare_baseline.empty()) {
    // The same evaluation budget as the suggestion used (screening, surrogate and exact evaluations).
    const Suggestion b = BaselineSearch(scene, rig, *caster, targets, options, s.evaluations, args.seed + 1, false);
    const Suggestion ba = BaselineSearch(scene, rig, *caster, targets, options, s.evaluations, args.seed + 1, true);
    const bool higher = ObjectiveHigherIsBetter(options.objective);
    const std::vector<std::pair<std::string, const Suggestion*>> runs{
        {"ceres", &s}, {"random", &b}, {"random_adaptive", &ba}};
    std::string csv = "method,seconds,evaluations,best_objective\n";
    for (const auto& [name, sug] : runs)
      for (const TracePoint& t : sug->trace) {
        char line[160];
        std::snprintf(line, sizeof line, "%s,%.6f,%lld,%.9g\n", name.c_str(), t.seconds,
                      static_cast<long long>(t.evaluations), t.objective);
        csv += line;
      }
    WriteFileAtomically(csv_path, csv);
    LogLogPlot plot;
    plot.title = "Suggestion (screening + Ceres nudge) vs random local search: " + rig.name + ", " + ObjectiveName(options.objective);
    plot.x_label = "seconds";
    // Coverage is plotted as the share still short of k cameras (1 - coverage), which a log axis shows.
    const bool shortfall = options.objective.kind == ObjectiveKind::kCoverage;
    auto y_of = [&](double v) { return shortfall ? 1.0 - v : v; };
    plot.y_label = shortfall ? "share of targets seen by < " + std::to_string(options.objective.k) +
                                   " cameras (1 - best exact " + ObjectiveName(options.objective) + ")"
                             : "best exact " + ObjectiveName(options.objective);
    plot.note = std::to_string(s.target_points) + " target points; same evaluation budget (" +
                std::to_string(s.evaluations) + " evaluations)";
    const char* labels[] = {"screening + Ceres nudge", "random search, fixed step", "random search, 1/5 rule"};
    for (std::size_t r = 0; r < runs.size(); ++r) {
      PlotSeries series;
      series.label = labels[r];
      series.markers = false;
      for (const TracePoint& t : runs[r].second->trace) {
        series.x.push_back(std::max(t.seconds, 1e-4));
        series.y.push_back(y_of(t.objective));
      }
      plot.series.push_back(series);
    }
    if (original) {
      PlotSeries ref;
      ref.label = "original poses";
      ref.dashed = true;
      ref.markers = false;
      ref.x = {1e-3, std::max({s.seconds, b.seconds, ba.seconds, 1e-2})};
      ref.y = {y_of(original->objective), y_of(original->objective)};
      plot.series.push_back(ref);
    }
    WriteFileAtomically(svg_path, RenderLogLogSvg(plot));
    if (!args.quiet) {
      // Targets: the suggestion's final objective, and the better baseline's final objective.
      double best_base = b.after.objective;
      if (higher ? ba.after.objective > best_base : ba.after.objective < best_base) best_base = ba.after.objective;
      std::printf("\n%-27s %9s %9s %7s %13s %13s %13s\n", "method (same budget)", "final", "seconds", "evals",
                  ("at " + Value(s.seconds, "%.2f") + " s").c_str(), "to sugg. fin.", "to best base");
      for (std::size_t r = 0; r < runs.size(); ++r) {
        const Suggestion& x = *runs[r].second;
        double at = x.before.objective;
        for (const TracePoint& t : x.trace)
          if (t.seconds <= s.seconds) at = t.objective;
        std::printf("%-27s %9s %9.3f %7lld %13s %13s %13s\n", labels[r], Value(x.after.objective).c_str(),
                    x.seconds, static_cast<long long>(x.evaluations), Value(at).c_str(),
                    Value(TimeToReach(x.trace, s.after.objective, higher), "%.3f").c_str(),
                    Value(TimeToReach(x.trace, best_base, higher), "%.3f").c_str());
      }
      std::printf("(times in seconds to reach the suggestion's final %s and the better baseline's final %s; inf: never)\n",
                  Value(s.after.objective).c_str(), Value(best_base).c_str());
    }
  }
  output.Commit();
  if (!args.quiet) {
    std::printf("wrote %s%s\n", args.out.c_str(), s.improved ? "" : " (no improvement: nothing to accept)");
    if (!args.compare_baseline.empty()) std::printf("wrote %s.csv and %s.svg\n", stem.c_str(), stem.c_str());
  }
  std::fflush(stdout);
  for (const Warning& w : warnings)
    std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(scene.path, w).c_str());
  return 0;
}

int RunAccept(const AcceptArgs& args) {
  AcceptOptions options;
  options.force = args.force;
  if (!args.cameras.empty()) options.cameras = SplitComma(args.cameras);
  // A suggest run killed while committing its outputs is finished before its suggestion is read.
  RecoverOutputs(std::filesystem::path(args.suggestion).parent_path().string());
  const AcceptResult r = AcceptSuggestion(args.suggestion, options);
  std::string ids;
  for (const std::string& id : r.accepted) ids += (ids.empty() ? "" : ", ") + id;
  if (!args.quiet) {
    std::printf("accepted %s into %s (previous file kept as %s)\n", ids.c_str(), r.scene_path.c_str(),
                r.backup_path.c_str());
    for (const std::string& note : r.notes) std::printf("note: %s\n", note.c_str());
  }
  return 0;
}

}  // namespace pandora::app
