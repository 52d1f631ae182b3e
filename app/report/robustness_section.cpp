#include "app/report/robustness_section.h"

#include <sstream>

#include "analysis/util/text.h"
#include "app/report/table.h"

namespace pandora::report {
namespace {

std::string Percent(double share) { return Format("%.1f%%", 100 * share); }

std::string Mm(const std::optional<double>& v) {
  return v ? Format("%.3g", *v) : std::string("&ndash;");
}

}  // namespace

std::string RobustnessIntroHtml(int k) {
  return Format(
      "<p class=\"note\">What the rig keeps when any one camera fails (unplugged, bumped, "
      "occluded): each row is the rig with that camera disabled, from the per-voxel camera "
      "sets without re-casting rays (equal to evaluating the rig without it). Shares of the "
      "free region voxels seen by at least 1, 2, 3 and %d cameras; the most critical cameras "
      "first (the largest loss of coverage by %d, then of the triangulable share, then the "
      "largest sigma_max p90).</p>\n",
      k, k);
}

std::string RobustnessCellHtml(const CriticalityTable& t, int rows) {
  std::ostringstream s;
  if (t.worst < 0) return "<p>No enabled camera.</p>\n";
  const CriticalityRow& worst = t.rows[t.worst];
  s << "<p>Seen by &ge; " << t.k << ": intact " << Percent(t.ge_k) << "; worst single failure <b>"
    << HtmlEscape(worst.id) << "</b> " << Percent(worst.ge_k)
    << Format(" (&minus;%.1f points)", 100 * t.worst_loss()) << "; mean over failures "
    << Percent(t.mean_ge_k) << ".</p>\n";
  s << "<div class=\"scroll\"><table class=\"robustness\"><thead><tr><th>fails</th><th>&ge; 1</th>"
       "<th>&ge; 2</th><th>&ge; 3</th>";
  if (t.k > 3) s << "<th>&ge; " << t.k << "</th>";
  if (t.uncertainty) s << "<th>triangulable</th><th>sigma_max p50 mm</th><th>p90 mm</th>";
  s << "</tr></thead><tbody>\n";
  const std::vector<int> order = t.MostCritical();
  for (int i = 0; i < rows && i < static_cast<int>(order.size()); ++i) {
    const CriticalityRow& r = t.rows[order[i]];
    s << "<tr><td>" << HtmlEscape(r.id) << "</td><td>" << Percent(r.ge1) << "</td><td>"
      << Percent(r.ge2) << "</td><td>" << Percent(r.ge3) << "</td>";
    if (t.k > 3) s << "<td>" << Percent(r.ge_k) << "</td>";
    if (t.uncertainty)
      s << "<td>" << Percent(r.triangulable.value_or(0)) << "</td><td>" << Mm(r.sigma_max_p50_mm)
        << "</td><td>" << Mm(r.sigma_max_p90_mm) << "</td>";
    s << "</tr>\n";
  }
  s << "</tbody></table></div>\n";
  return s.str();
}

}  // namespace pandora::report
