#include "app/report/suggest_comparison.h"

#include <algorithm>
#include <limits>

#include "analysis/util/text.h"
#include "app/report/plot.h"
#include "suggest/suggestion_text.h"

namespace pandora::report {

double TimeToReach(const std::vector<TracePoint>& trace, double target, bool higher_is_better) {
  for (const TracePoint& t : trace)
    if (higher_is_better ? t.objective >= target : t.objective <= target) return t.seconds;
  return std::numeric_limits<double>::infinity();
}

SuggestComparison CompareWithBaselines(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                       const std::vector<TargetPoint>& targets,
                                       const SuggestOptions& options, const Suggestion& suggestion,
                                       std::uint64_t seed,
                                       std::optional<double> original_objective) {
  SuggestComparison out;
  out.runs.push_back({"ceres", "screening + Ceres nudge", suggestion});
  out.runs.push_back(
      {"random", "random search, fixed step",
       BaselineSearch(scene, rig, caster, targets, options, suggestion.evaluations, seed, false)});
  out.runs.push_back(
      {"random_adaptive", "random search, 1/5 rule",
       BaselineSearch(scene, rig, caster, targets, options, suggestion.evaluations, seed, true)});
  const Objective& objective = options.objective;
  const bool higher = ObjectiveHigherIsBetter(objective);

  out.csv = "method,seconds,evaluations,best_objective\n";
  for (const SuggestRun& run : out.runs)
    for (const TracePoint& t : run.result.trace)
      out.csv += Format("%s,%.6f,%lld,%.9g\n", run.name.c_str(), t.seconds,
                        static_cast<long long>(t.evaluations), t.objective);

  LogLogPlot plot;
  plot.title = "Suggestion (screening + Ceres nudge) vs random local search: " + rig.name + ", " +
               ObjectiveName(objective);
  plot.x_label = "seconds";
  // Coverage is plotted as the share still short of k cameras (1 - coverage), which a log axis
  // shows.
  const bool shortfall = objective.kind == ObjectiveKind::kCoverage;
  auto y_of = [&](double v) { return shortfall ? 1.0 - v : v; };
  plot.y_label = shortfall ? "share of targets seen by < " + std::to_string(objective.k) +
                                 " cameras (1 - best exact " + ObjectiveName(objective) + ")"
                           : "best exact " + ObjectiveName(objective);
  plot.note = std::to_string(suggestion.target_points) +
              " target points; same evaluation budget (" + std::to_string(suggestion.evaluations) +
              " evaluations)";
  double longest = 1e-2;
  for (const SuggestRun& run : out.runs) {
    PlotSeries series;
    series.label = run.label;
    series.markers = false;
    for (const TracePoint& t : run.result.trace) {
      series.x.push_back(std::max(t.seconds, 1e-4));
      series.y.push_back(y_of(t.objective));
    }
    plot.series.push_back(series);
    longest = std::max(longest, run.result.seconds);
  }
  if (original_objective) {
    PlotSeries ref;
    ref.label = "original poses";
    ref.dashed = true;
    ref.markers = false;
    ref.x = {1e-3, longest};
    ref.y = {y_of(*original_objective), y_of(*original_objective)};
    plot.series.push_back(ref);
  }
  out.svg = RenderLogLogSvg(plot);

  // The suggestion's final objective, and the better baseline's.
  const double final_objective = suggestion.after.objective;
  double best_base = out.runs[1].result.after.objective;
  const double adaptive = out.runs[2].result.after.objective;
  if (higher ? adaptive > best_base : adaptive < best_base) best_base = adaptive;
  out.table =
      Format("%-27s %9s %9s %7s %13s %13s %13s\n", "method (same budget)", "final", "seconds",
             "evals", ("at " + TableValue(suggestion.seconds, "%.2f") + " s").c_str(),
             "to sugg. fin.", "to best base");
  for (const SuggestRun& run : out.runs) {
    const Suggestion& x = run.result;
    double at = x.before.objective;  // the best so far when the suggestion had finished
    for (const TracePoint& t : x.trace)
      if (t.seconds <= suggestion.seconds) at = t.objective;
    out.table += Format("%-27s %9s %9.3f %7lld %13s %13s %13s\n", run.label.c_str(),
                        TableValue(x.after.objective).c_str(), x.seconds,
                        static_cast<long long>(x.evaluations), TableValue(at).c_str(),
                        TableValue(TimeToReach(x.trace, final_objective, higher), "%.3f").c_str(),
                        TableValue(TimeToReach(x.trace, best_base, higher), "%.3f").c_str());
  }
  out.table += Format(
      "(times in seconds to reach the suggestion's final %s and the better baseline's "
      "final %s; inf: never)\n",
      TableValue(final_objective).c_str(), TableValue(best_base).c_str());
  return out;
}

}  // namespace pandora::report
