// The rigs compared on their headline numbers (volume/rig_comparison.h).
#include "volume/rig_comparison.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>

namespace pandora {
namespace {

std::string Fmt(const char* format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

using Getter = std::function<std::optional<double>(const Summary&)>;

std::optional<double> Uncertainty(
    const Summary& s, const std::function<std::optional<double>(const UncertaintySummary&)>& get) {
  return s.uncertainty ? get(*s.uncertainty) : std::nullopt;
}

}  // namespace

std::string ComparisonRow::Text(std::size_t rig) const {
  const std::optional<double>& v = values[rig];
  if (!v || !std::isfinite(*v)) return "-";
  return format.empty() ? Fmt("%.1f%%", 100.0 * *v) : Fmt(format.c_str(), *v);
}

double ComparisonRow::Shown(std::size_t rig) const {
  const double x = values[rig] ? *values[rig] : std::nan("");
  const std::string t = format.empty() ? Fmt("%.1f", 100.0 * x) : Fmt(format.c_str(), x);
  return std::strtod(t.c_str(), nullptr);
}

const ComparisonRow* RigComparison::Find(const std::string& key) const {
  for (const ComparisonRow& row : rows)
    if (row.key == key) return &row;
  return nullptr;
}

RigComparison CompareRigs(const std::vector<Summary>& summaries, const Study& study) {
  struct Spec {
    std::string key, label, format;
    bool higher_better;
    Getter get;
  };
  std::vector<Spec> specs{
      {"coverage_ge1", "Coverage >= 1 camera", "", true,
       [](const Summary& s) { return std::optional(s.coverage.ge1); }},
      {"coverage_ge2", "Coverage >= 2 cameras", "", true,
       [](const Summary& s) { return std::optional(s.coverage.ge2); }},
      {"coverage_ge3", "Coverage >= 3 cameras", "", true,
       [](const Summary& s) { return std::optional(s.coverage.ge3); }},
      {"resolution_p10_px_per_m", "Resolution p10 (px/m)", "%.0f", true,
       [](const Summary& s) {
         return s.resolution_px_per_m ? s.resolution_px_per_m->p10 : std::nullopt;
       }},
      {"resolution_p50_px_per_m", "Resolution p50 (px/m)", "%.0f", true,
       [](const Summary& s) {
         return s.resolution_px_per_m ? s.resolution_px_per_m->p50 : std::nullopt;
       }},
      {"resolution_p90_px_per_m", "Resolution p90 (px/m)", "%.0f", true,
       [](const Summary& s) {
         return s.resolution_px_per_m ? s.resolution_px_per_m->p90 : std::nullopt;
       }},
      {"triangulable", "Triangulable", "", true,
       [](const Summary& s) {
         return Uncertainty(
             s, [](const UncertaintySummary& u) { return std::optional(u.triangulable); });
       }},
      {"sigma_max_p50_mm", "sigma_max p50 (mm)", "%.3f", false,
       [](const Summary& s) {
         return Uncertainty(s, [](const UncertaintySummary& u) { return u.sigma_max_mm.p50; });
       }},
      {"sigma_max_p90_mm", "sigma_max p90 (mm)", "%.3f", false,
       [](const Summary& s) {
         return Uncertainty(s, [](const UncertaintySummary& u) { return u.sigma_max_mm.p90; });
       }},
      {"sigma_max_p99_mm", "sigma_max p99 (mm)", "%.3f", false,
       [](const Summary& s) {
         return Uncertainty(s, [](const UncertaintySummary& u) { return u.sigma_max_mm.p99; });
       }},
  };
  if (study.max_sigma_mm)
    specs.push_back(
        {"meets_max_sigma", "Meets sigma_max <= " + Fmt("%g", *study.max_sigma_mm) + " mm", "",
         true, [](const Summary& s) {
           return Uncertainty(s, [](const UncertaintySummary& u) { return u.meets_max_sigma; });
         }});
  if (study.motion) {
    specs.push_back({"sigma_max_steady_p50_mm", "Steady-state sigma_max p50 (mm)", "%.3f", false,
                     [](const Summary& s) {
                       return Uncertainty(s, [](const UncertaintySummary& u) {
                         return u.sigma_max_steady_mm.p50;
                       });
                     }});
    specs.push_back({"sigma_max_steady_p90_mm", "Steady-state sigma_max p90 (mm)", "%.3f", false,
                     [](const Summary& s) {
                       return Uncertainty(s, [](const UncertaintySummary& u) {
                         return u.sigma_max_steady_mm.p90;
                       });
                     }});
    specs.push_back({"sigma_max_steady_p99_mm", "Steady-state sigma_max p99 (mm)", "%.3f", false,
                     [](const Summary& s) {
                       return Uncertainty(s, [](const UncertaintySummary& u) {
                         return u.sigma_max_steady_mm.p99;
                       });
                     }});
    if (study.max_sigma_mm)
      specs.push_back({"meets_max_sigma_steady",
                       "Steady state meets sigma_max <= " + Fmt("%g", *study.max_sigma_mm) + " mm",
                       "", true, [](const Summary& s) {
                         return Uncertainty(s, [](const UncertaintySummary& u) {
                           return u.meets_max_sigma_steady;
                         });
                       }});
  }
  // Moving objects (people): the numbers over the time samples, which the static fields above
  // (the empty volume) cannot show.
  if (std::any_of(summaries.begin(), summaries.end(),
                  [](const Summary& s) { return s.time.has_value(); })) {
    auto time = [](const std::function<std::optional<double>(const TimeSummary&)>& get) {
      return [get](const Summary& s) { return s.time ? get(*s.time) : std::nullopt; };
    };
    int k = 3;
    for (const Summary& s : summaries)
      if (s.time) k = s.time->min_cameras;
    const std::string cams = " (>= " + std::to_string(k) + " cameras)";
    specs.push_back({"time_always", "Covered at every time sample" + cams, "", true,
                     time([](const TimeSummary& t) { return std::optional(t.always); })});
    specs.push_back({"time_mean", "Covered, mean over the samples" + cams, "", true,
                     time([](const TimeSummary& t) { return std::optional(t.mean); })});
    specs.push_back({"time_worst_sample", "Covered in the worst sample" + cams, "", true,
                     time([](const TimeSummary& t) {
                       return t.samples.empty() ? std::nullopt
                                                : std::optional(t.samples[t.worst_sample].ge_k);
                     })});
    specs.push_back({"time_sigma_max_p90_mm", "sigma_max p90 over time (mm)", "%.3f", false,
                     time([](const TimeSummary& t) { return t.sigma_max_p90; })});
  }

  RigComparison c;
  for (const Summary& s : summaries) {
    c.rigs.push_back(s.rig);
    c.enabled_cameras.push_back(s.cameras);
    c.warnings.push_back(s.warnings.size());
    c.region_voxels.push_back(s.region_voxels);
    c.evaluation_seconds.push_back(s.timing.seconds);
  }
  const std::size_t n = summaries.size();
  for (const Spec& spec : specs) {
    ComparisonRow row;
    row.key = spec.key;
    row.label = spec.label;
    row.format = spec.format;
    row.higher_better = spec.higher_better;
    for (const Summary& s : summaries) row.values.push_back(spec.get(s));
    // Compared as shown: a rig is best when its shown value is the best and some rig's is worse.
    std::vector<double> shown;
    for (std::size_t i = 0; i < n; ++i) shown.push_back(row.Shown(i));
    double best = std::nan(""), worst = std::nan("");
    for (double x : shown)
      if (std::isfinite(x)) {
        best = std::isnan(best) ? x : row.higher_better ? std::max(best, x) : std::min(best, x);
        worst = std::isnan(worst) ? x : row.higher_better ? std::min(worst, x) : std::max(worst, x);
      }
    const bool differ = std::isfinite(best) && best != worst;
    for (std::size_t i = 0; i < n; ++i) {
      const bool finite = row.values[i] && std::isfinite(*row.values[i]);
      row.best.push_back(n > 1 && differ && finite && shown[i] == best);
    }
    c.rows.push_back(std::move(row));
  }
  return c;
}

void to_json(nlohmann::json& j, const RigComparison& c) {
  nlohmann::json rows = nlohmann::json::array();
  for (const ComparisonRow& row : c.rows) {
    nlohmann::json values = nlohmann::json::array();
    for (const std::optional<double>& v : row.values)
      values.push_back(v && std::isfinite(*v) ? nlohmann::json(*v) : nlohmann::json(nullptr));
    rows.push_back({{"key", row.key},
                    {"higher_better", row.higher_better},
                    {"values", values},
                    {"best", row.best}});
  }
  j = {{"rigs", c.rigs},
       {"enabled_cameras", c.enabled_cameras},
       {"warnings", c.warnings},
       {"region_voxels", c.region_voxels},
       {"evaluation_seconds", c.evaluation_seconds},
       {"rows", rows}};
}

}  // namespace pandora
