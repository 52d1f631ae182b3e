#include "app/report/time_section.h"

#include <algorithm>
#include <cstdio>
#include <optional>

#include "app/report/table.h"

namespace pandora::report {
namespace {

std::string SpacedPercent(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f %%", 100 * v);
  return b;
}

// One row: a label and one optional share per rig, the largest in bold.
std::string Row(const std::string& label, const std::vector<std::optional<double>>& values,
                const std::vector<std::string>& notes = {}) {
  double best = -1;
  for (const auto& v : values)
    if (v) best = std::max(best, *v);
  std::string out = "<tr><th>" + label + "</th>";
  for (std::size_t i = 0; i < values.size(); ++i) {
    std::string cell = values[i] ? SpacedPercent(*values[i]) : "&ndash;";
    if (values[i] && values.size() > 1 && *values[i] == best) cell = "<b>" + cell + "</b>";
    if (i < notes.size() && !notes[i].empty())
      cell += " <span class=\"note\">" + HtmlEscape(notes[i]) + "</span>";
    out += "<td>" + cell + "</td>";
  }
  return out + "</tr>\n";
}

}  // namespace

std::string TimeSectionHtml(const std::vector<const Summary*>& summaries,
                            const std::vector<std::string>& rig_names) {
  bool any = false;
  int k = 3;
  std::size_t samples = 0;
  std::vector<std::string> labels, targets;
  for (const Summary* s : summaries) {
    if (s->time) {
      any = true;
      k = s->time->min_cameras;
      samples = std::max(samples, s->time->samples.size());
    }
    if (!s->targets.empty()) any = true;
    if (s->sample_labels.size() > labels.size()) labels = s->sample_labels;
    for (const SurfaceTargetResult& t : s->targets)
      if (std::find(targets.begin(), targets.end(), t.name) == targets.end())
        targets.push_back(t.name);
  }
  if (!any) return "";
  const std::string ks = std::to_string(k);
  std::string html = "<h2 id=\"time\">Over time and on bodies</h2>\n<p>";
  if (samples > 0)
    html += "The fields at each of the study's " + std::to_string(samples) +
            " time samples, the moving objects where they are then; ";
  html +=
      "surface targets: points spread over each named object's surface, moving with it, each "
      "tested against every camera as a surface point (facing it, not hidden, the body itself "
      "included). k = " +
      ks +
      " cameras. The volume as placed is under <a href=\"#numbers\">the numbers</a> above.</p>\n";
  html += "<table class=\"compare\"><tr><th></th>";
  for (const std::string& name : rig_names) html += "<th>" + HtmlEscape(name) + "</th>";
  html += "</tr>\n";
  auto each = [&](auto get) {
    std::vector<std::optional<double>> v;
    for (const Summary* s : summaries) v.push_back(get(*s));
    return v;
  };
  if (samples > 0) {
    html += Row("Volume seen by &ge; " + ks + " in every sample", each([](const Summary& s) {
                  return s.time ? std::optional<double>(s.time->always) : std::nullopt;
                }));
    html += Row("Volume seen by &ge; " + ks + ", mean over samples", each([](const Summary& s) {
                  return s.time ? std::optional<double>(s.time->mean) : std::nullopt;
                }));
    std::vector<std::string> worst;
    for (const Summary* s : summaries)
      worst.push_back(s->time && !s->time->samples.empty()
                          ? s->time->samples[s->time->worst_sample].label
                          : "");
    html += Row("Volume, worst sample", each([](const Summary& s) {
                  return s.time && !s.time->samples.empty()
                             ? std::optional<double>(s.time->samples[s.time->worst_sample].ge_k)
                             : std::nullopt;
                }),
                worst);
  }
  for (const std::string& target : targets) {
    auto find = [&](const Summary& s) -> const SurfaceTargetResult* {
      for (const SurfaceTargetResult& t : s.targets)
        if (t.name == target) return &t;
      return nullptr;
    };
    const std::string name = HtmlEscape(target);
    for (int j = 1; j <= 3; ++j)
      html += Row(name + ": points seen by &ge; " + std::to_string(j), each([&](const Summary& s) {
                    const SurfaceTargetResult* t = find(s);
                    return t && int(t->share_ge.size()) >= j
                               ? std::optional<double>(t->share_ge[j - 1])
                               : std::nullopt;
                  }));
    html += Row(name + ": seen by &ge; " + ks + " in every sample", each([&](const Summary& s) {
                  const SurfaceTargetResult* t = find(s);
                  return t ? std::optional<double>(t->always) : std::nullopt;
                }));
    if (labels.size() > 1) {
      std::vector<std::string> worst;
      for (const Summary* s : summaries) {
        const SurfaceTargetResult* t = find(*s);
        worst.push_back(t && t->worst_sample < int(s->sample_labels.size())
                            ? s->sample_labels[t->worst_sample]
                            : "");
      }
      html += Row(name + ": worst sample", each([&](const Summary& s) {
                    const SurfaceTargetResult* t = find(s);
                    return t && !t->sample_share.empty()
                               ? std::optional<double>(t->sample_share[t->worst_sample])
                               : std::nullopt;
                  }),
                  worst);
    }
  }
  html += "</table>\n";
  // Sample by sample.
  if (labels.size() > 1) {
    html += "<h3>Sample by sample (share seen by &ge; " + ks +
            " cameras)</h3>\n<div class=\"scroll\"><table class=\"compare\"><tr><th>Sample</th>";
    for (const std::string& name : rig_names) {
      if (samples > 0) html += "<th>" + HtmlEscape(name) + ": volume</th>";
      for (const std::string& target : targets)
        html += "<th>" + HtmlEscape(name) + ": " + HtmlEscape(target) + "</th>";
    }
    html += "</tr>\n";
    for (std::size_t i = 0; i < labels.size(); ++i) {
      html += "<tr><th>" + HtmlEscape(labels[i]) + "</th>";
      for (const Summary* s : summaries) {
        if (samples > 0)
          html += "<td>" +
                  (s->time && i < s->time->samples.size() ? SpacedPercent(s->time->samples[i].ge_k)
                                                          : "&ndash;") +
                  "</td>";
        for (const std::string& target : targets) {
          std::string cell = "&ndash;";
          for (const SurfaceTargetResult& t : s->targets)
            if (t.name == target && i < t.sample_share.size())
              cell = SpacedPercent(t.sample_share[i]);
          html += "<td>" + cell + "</td>";
        }
      }
      html += "</tr>\n";
    }
    html += "</table></div>\n";
  }
  return html;
}

}  // namespace pandora::report
