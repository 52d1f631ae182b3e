// The HTML report (app/report/report.h). Every figure is an <img> with a base64 data URI (PNG for
// images, SVG for plots and legends); nothing is fetched, and a Content-Security-Policy forbids it.
// When the file has several rigs they are laid out in columns, the same figures per rig on the same
// scales, with the headline numbers compared in one table.
#include "app/report/report.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>
#include <sstream>

#include "analysis/rig/rig_formats.h"
#include "analysis/scene/motion.h"
#include "analysis/scene/surface_targets.h"
#include "analysis/util/allocation_budget.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "app/report/calibration_section.h"
#include "app/report/plot.h"
#include "app/report/report_images.h"
#include "app/report/robustness_section.h"
#include "app/report/table.h"
#include "app/report/time_section.h"
#include "app/session/analyze.h"
#include "render/render.h"
#include "volume/time_fields.h"

#ifndef PANDORA_VERSION
#define PANDORA_VERSION "dev"
#endif

namespace pandora::report {
namespace {

std::string Fmt(const char* format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

std::string Percent(double fraction) { return Fmt("%.1f%%", 100.0 * fraction); }

std::string Swatch(const Camera& cam) {
  return "<span class=\"swatch\" style=\"background:" + HexOfLinear(cam.color) + "\"></span>";
}

// The colour key of a rig: each enabled camera's light colour and id.
std::string ColourKey(const Rig& rig) {
  std::string s = "<div class=\"key\">";
  for (const Camera& cam : rig.cameras)
    if (cam.enabled) s += "<span class=\"entry\">" + Swatch(cam) + HtmlEscape(cam.id) + "</span> ";
  return s + "</div>";
}

// An <img> the page embeds, counted so the page's own check knows how many to expect.
class Figures {
 public:
  std::string Img(const std::string& mime, const std::string& bytes, const std::string& alt,
                  const std::string& css_class = "") {
    ++count_;
    return "<img src=\"" + DataUri(mime, bytes) + "\" alt=\"" + HtmlEscape(alt) + "\"" +
           (css_class.empty() ? "" : " class=\"" + css_class + "\"") + ">";
  }
  std::string Svg(const std::string& svg, const std::string& alt) {
    return Img("image/svg+xml", svg, alt, "plot");
  }
  std::string Png(const Raster& r, const std::string& alt, const std::string& css_class = "") {
    return Img("image/png", EncodePng(r), alt, css_class);
  }
  int count() const { return count_; }

 private:
  int count_ = 0;
};

// A row of one cell per rig.
std::string RigRow(const std::vector<std::string>& cells) {
  std::string s = "<div class=\"rigs\" style=\"grid-template-columns: repeat(" +
                  std::to_string(cells.size()) + ", minmax(0, 1fr))\">\n";
  for (const std::string& c : cells) s += "<div class=\"cell\">" + c + "</div>\n";
  return s + "</div>\n";
}

std::string HeadlineTable(const ReportData& data) {
  const RigComparison& c = data.comparison;
  const std::size_t n = c.rigs.size();
  std::string s = "<table class=\"numbers\"><thead><tr><th></th>";
  for (const std::string& name : c.rigs) s += "<th>" + HtmlEscape(name) + "</th>";
  s += "</tr></thead><tbody>\n";
  s += "<tr><td>Enabled cameras</td>";
  for (int cameras : c.enabled_cameras) s += "<td>" + std::to_string(cameras) + "</td>";
  s += "</tr>\n";
  for (const ComparisonRow& row : c.rows) {
    s += "<tr><td>" + ComparisonHtml(row.label) + "</td>";
    for (std::size_t i = 0; i < n; ++i) {
      const std::string text = ComparisonHtml(row.Text(i));
      s += row.best[i] ? "<td class=\"best\">" + text + "</td>" : "<td>" + text + "</td>";
    }
    s += "</tr>\n";
  }
  s += "<tr><td>Warnings</td>";
  for (std::size_t w : c.warnings) s += "<td>" + std::to_string(w) + "</td>";
  s += "</tr>\n<tr><td>Region voxels (free)</td>";
  for (std::int64_t v : c.region_voxels)
    s += "<td>" + std::to_string(static_cast<long long>(v)) + "</td>";
  s += "</tr>\n<tr><td>Field evaluation (s)</td>";
  for (double t : c.evaluation_seconds) s += "<td>" + Fmt("%.2f", t) + "</td>";
  s += "</tr>\n</tbody></table>\n";
  return s;
}

std::string CameraTable(const RigReport& r, const Study& study) {
  std::string s =
      "<table class=\"cameras\"><thead><tr><th>id</th><th>name</th><th>resolution (px)</th>"
      "<th>FOV h &times; v (&deg;)</th><th>nominal (&deg;)</th><th>unreachable</th>"
      "<th>lens</th><th>region seen</th><th>pixel &sigma; (px)</th></tr></thead><tbody>\n";
  for (std::size_t c = 0; c < r.rig.cameras.size(); ++c) {
    const Camera& cam = r.rig.cameras[c];
    const Intrinsics& k = cam.model.intrinsics();
    const CameraSummary& pc = r.summary.per_camera[c];
    const double seen = pc.visible_fraction;
    const double unreachable = pc.lens.unreachable_fraction;
    const std::string sigma = cam.pixel_sigma > 0 ? Fmt("%g", cam.pixel_sigma)
                                                  : Fmt("%g", study.pixel_sigma) + " (study)";
    s += std::string("<tr") + (cam.enabled ? "" : " class=\"disabled\"") + "><td>" +
         (cam.enabled ? Swatch(cam) : "") + HtmlEscape(cam.id) + "</td><td>" +
         HtmlEscape(cam.name) + "</td><td>" + std::to_string(k.width) + " &times; " +
         std::to_string(k.height) + "</td><td>" + Fmt("%.1f", pc.lens.hfov_deg) + " &times; " +
         Fmt("%.1f", pc.lens.vfov_deg) + "</td><td>" + Fmt("%.1f", pc.lens.nominal_hfov_deg) +
         " &times; " + Fmt("%.1f", pc.lens.nominal_vfov_deg) + "</td><td>" +
         (unreachable > 0 ? Percent(unreachable) : "0") + "</td><td>" + LensModelName(k.model) +
         "</td><td>" + (cam.enabled ? Percent(seen) : "disabled") + "</td><td>" + sigma +
         "</td></tr>\n";
  }
  return s + "</tbody></table>\n";
}

// The rig's warnings as a list (or a line saying there are none).
std::string WarningList(const RigReport& r, const std::string& file) {
  if (r.warnings.empty()) return "<p class=\"note\">No warnings.</p>\n";
  std::string s = "<ul class=\"warnings\">\n";
  for (const Warning& w : r.warnings)
    s += "<li><code>" + HtmlEscape(file + ": " + w.json_path) + "</code>: " + HtmlEscape(w.reason) +
         "</li>\n";
  return s + "</ul>\n";
}

std::string FieldLabel(const std::string& field) {
  if (field == "coverage") return "coverage (cameras that see the point)";
  if (field == "resolution") return "resolution (px/m, best camera)";
  if (field == "sigma_max") return "sigma_max (mm, worst-direction 1-sigma)";
  return field;
}

// The shared scale of a field's slices; resolution's from the slices themselves.
FieldScale ScaleOf(const std::string& field, const std::vector<RigReport>& rigs,
                   const std::vector<std::array<FieldSlice, 2>>& slices) {
  FieldScale s;
  if (field == "coverage") {
    int cameras = 1;
    for (const RigReport& r : rigs) cameras = std::max(cameras, r.rig.enabled_count());
    s.max = cameras;
    s.discrete = true;
    return s;
  }
  if (field == "resolution") {
    double top = 0;
    for (const auto& pair : slices)
      for (const FieldSlice& slice : pair)
        for (std::size_t i = 0; i < slice.values.size(); ++i)
          if (slice.has_value[i]) top = std::max(top, slice.values[i]);
    s.max = NiceTicks(top > 0 ? top : 1.0, 4).back();
    return s;
  }
  // sigma_max: up to the largest p99 over the rigs (so a few outlier voxels do not flatten the
  // scale), rounded up to a nice number; higher values take the top colour.
  double top = 0;
  for (const RigReport& r : rigs)
    if (r.summary.uncertainty && r.summary.uncertainty->sigma_max_mm.p99)
      top = std::max(top, *r.summary.uncertainty->sigma_max_mm.p99);
  if (!(top > 0)) top = 1;
  s.max = NiceTicks(top, 4).back();
  s.open = true;
  return s;
}

void CheckWidth(const char* option, int value) {
  if (value < ReportOptions::kMinWidth || value > ReportOptions::kMaxWidth)
    throw InputError(
        option, "",
        "must be a whole number of pixels, in [" + std::to_string(ReportOptions::kMinWidth) + ", " +
            std::to_string(ReportOptions::kMaxWidth) + "], got " + std::to_string(value));
}

// Name i of `rigs`: not empty, not listed before.
void CheckRigName(const std::vector<std::string>& rigs, std::size_t i) {
  if (rigs[i].empty())
    throw InputError("{rigs}", "", "an empty rig name", "name a rig of the scene");
  if (std::find(rigs.begin(), rigs.begin() + i, rigs[i]) != rigs.begin() + i)
    throw InputError("{rigs}", "", "rig '" + rigs[i] + "' listed twice");
}

}  // namespace

void ReportOptions::Check() const {
  for (std::size_t i = 0; i < rigs.size(); ++i) CheckRigName(rigs, i);
  if (!std::isnan(voxel_size) && !(voxel_size > 0 && std::isfinite(voxel_size)))
    throw InputError("{voxel_size}", "",
                     "must be a number of metres, greater than 0, got " + Fmt("%g", voxel_size));
  CheckWidth("{view_width}", view_width);
  CheckWidth("{camera_width}", camera_width);
  if (!std::isnan(brightness) && !(brightness > 0 && brightness <= kMaxBrightness))
    throw InputError("{brightness}", "",
                     "must be a number of times one camera's light, in (0, " +
                         Fmt("%g", kMaxBrightness) + "], got " + Fmt("%g", brightness));
}

void ReportOptions::Check(const Scene& scene) const {
  // Name by name, as given: the first name that is empty, repeated or unknown is the error.
  for (std::size_t i = 0; i < rigs.size(); ++i) {
    CheckRigName(rigs, i);
    const std::string& name = rigs[i];
    if (std::any_of(scene.rigs.begin(), scene.rigs.end(),
                    [&](const Rig& r) { return r.name == name; }))
      continue;
    std::string names;
    for (const Rig& r : scene.rigs) names += (names.empty() ? "'" : ", '") + r.name + "'";
    throw InputError("{rigs}", "", "no rig named '" + name + "' in " + scene.path,
                     "rigs in this scene: " + names);
  }
  Check();
}

ReportData ComputeReport(const Scene& scene_in, const RayCaster& caster,
                         const ReportOptions& options) {
  options.Check(scene_in);
  std::vector<const Rig*> rigs;
  if (options.rigs.empty())
    for (const Rig& r : scene_in.rigs) rigs.push_back(&r);
  for (const std::string& name : options.rigs)
    rigs.push_back(&*std::find_if(scene_in.rigs.begin(), scene_in.rigs.end(),
                                  [&](const Rig& r) { return r.name == name; }));
  // The voxel size option applies to a copy of the scene (EvaluateFields reads the study's).
  std::optional<Scene> adjusted;
  if (!std::isnan(options.voxel_size)) {
    adjusted = scene_in;
    adjusted->study.voxel_size = options.voxel_size;
  }
  const Scene& scene = adjusted ? *adjusted : scene_in;

  ReportData data;
  data.study = scene.study;
  // Fields: the study's, plus what the figures need.
  {
    std::set<std::string> wanted(scene.study.fields.begin(), scene.study.fields.end());
    wanted.insert({"coverage", "cameras", "resolution", "sigma_max"});
    for (const std::string& f : FieldNames())
      if (wanted.count(f)) data.field_names.push_back(f);
  }
  // Moving objects and surface targets (docs/time.md): the scene's rigid parts, built once for
  // every rig.
  std::unique_ptr<RigidPartsRayCaster> parts;
  if (scene.Animated() || scene.study.targets) parts = MakeSceneParts(scene);
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  for (const Rig* rig : rigs) {
    // The analysis every front end runs (app/session/analyze.h), without the parts the report has
    // no section for yet (pixel targets, DORI, PTZ) and without derived grids.
    session::AnalyzeOptions analysis;
    FieldOptions& field_options = analysis.fields;
    field_options.scene_path = scene.path;
    field_options.fields = data.field_names;
    field_options.memory_budget_bytes = scene.study.memory_budget_bytes;
    if (adjusted) field_options.voxel_size_option = "{voxel_size}";
    field_options.progress = options.progress;
    analysis.threads = threads;
    analysis.time_stage = [&](std::size_t) { return options.progress; };
    analysis.parts = parts.get();
    analysis.pixel_targets = analysis.dori = analysis.ptz = false;
    if (options.rig_started) options.rig_started(rig->name);
    RigReport r;
    r.rig = *rig;
    r.fields = EvaluateFields(scene, *rig, caster, field_options);
    ReleaseFreedMemory();  // the evaluation's freed blocks, before the analyses
    session::RigAnalysis result =
        session::CompleteAnalysis(scene, caster, *rig, r.fields, nullptr, analysis);
    r.summary = std::move(result.summary);
    r.warnings = std::move(result.warnings);
    data.rigs.push_back(std::move(r));
  }

  std::vector<Summary> summaries;
  for (const RigReport& r : data.rigs) summaries.push_back(r.summary);
  data.comparison = CompareRigs(summaries, scene.study);

  // Slices through the centre of the region, z then y, on shared scales.
  const Vec3 centre = scene.study.region.box.center();
  for (const std::string& field :
       {std::string("coverage"), std::string("resolution"), std::string("sigma_max")}) {
    FieldSlices fs;
    fs.field = field;
    for (const RigReport& r : data.rigs)
      fs.rigs.push_back(
          {SliceField(r.fields, field, 2, centre[2]), SliceField(r.fields, field, 1, centre[1])});
    fs.scale = ScaleOf(field, data.rigs, fs.rigs);
    data.slices.push_back(std::move(fs));
  }

  // Coverage histograms on a shared axis.
  {
    CoverageHistogram& h = data.coverage_histogram;
    for (const RigReport& r : data.rigs) {
      const auto& counts = r.fields.stats.coverage_histogram;
      h.max_cameras = std::max(h.max_cameras, static_cast<int>(counts.size()) - 1);
      for (auto c : counts)
        h.y_max = std::max(h.y_max, double(c) / std::max<std::int64_t>(
                                                    1, r.fields.stats.active_set.region_voxels));
    }
    for (const RigReport& r : data.rigs) {
      const auto& counts = r.fields.stats.coverage_histogram;
      const double region = std::max<std::int64_t>(1, r.fields.stats.active_set.region_voxels);
      std::vector<double> shares;
      for (int k = 0; k <= h.max_cameras; ++k)
        shares.push_back(k < static_cast<int>(counts.size()) ? counts[k] / region : 0.0);
      h.shares.push_back(std::move(shares));
    }
  }
  // sigma_max: up to 30 bins of a 1-2-5 width from 0 to the shared scale's top, an overflow bin
  // after, so the bin edges (and the labels on them) are round numbers.
  {
    SigmaHistogram& h = data.sigma_histogram;
    const FieldScale& scale = data.slices[2].scale;
    h.bin_width = NiceStep(scale.max / 30);
    h.bins = std::max(1, static_cast<int>(std::ceil(scale.max / h.bin_width - 1e-9)));
    h.top = h.bins * h.bin_width;
    for (const RigReport& r : data.rigs) {
      std::vector<double> count(h.bins + 1, 0.0);
      for (float v : r.fields.stats.sigma_max_mm)
        count[std::min(h.bins, static_cast<int>(v / h.bin_width))] += 1;
      const double region = std::max<std::int64_t>(1, r.fields.stats.active_set.region_voxels);
      for (double& c : count) {
        c /= region;
        h.y_max = std::max(h.y_max, c);
      }
      h.shares.push_back(std::move(count));
    }
  }
  return data;
}

ReportTarget StageReport(OutputTransaction& output, const std::string& dir,
                         const std::string& option) {
  ReportTarget t;
  t.path = (std::filesystem::path(dir) / "report.html").string();
  t.staged = output.Stage(t.path, option);
  return t;
}

namespace {

// The page being written: its inputs, the rig headers of the column layout, the figures it
// embeds and the body so far; a member per section, each appending to the body in page order.
struct ReportPage {
  ReportPage(const Scene& scene, const RayCaster& caster, const ReportData& data,
             const ReportOptions& options)
      : scene(scene),
        caster(caster),
        data(data),
        options(options),
        reports(data.rigs),
        study(data.study),
        n(reports.size()),
        view_width(options.view_width) {}

  void Intro();
  void Numbers();
  void RigHeads();
  void Warnings();
  void Plan();
  void Views();
  void CameraViews();
  void Slices();
  void Histograms();
  void Cameras();
  void Sheet();
  void Calibration();
  void OverTime();
  void Robustness();
  void Validation();
  std::string Html() const;

  const Scene& scene;
  const RayCaster& caster;
  const ReportData& data;
  const ReportOptions& options;
  const std::vector<RigReport>& reports;
  const Study& study;
  const std::size_t n;
  const int view_width;
  Figures fig;
  std::ostringstream body;
  std::vector<std::string> heads;
};

// The CSV's rows as a table (fields may be quoted: "a, b" and "" inside quotes).
std::string SheetTable(const std::string& csv) {
  std::string table = "<table class=\"sheet\">";
  std::size_t line = 0;
  for (std::size_t at = 0; at < csv.size();) {
    const std::size_t end = csv.find('\n', at);
    const std::string row = csv.substr(at, end - at);
    at = end == std::string::npos ? csv.size() : end + 1;
    std::vector<std::string> fields(1);
    bool quoted = false;
    for (std::size_t i = 0; i < row.size(); ++i) {
      const char ch = row[i];
      if (quoted && ch == '"' && i + 1 < row.size() && row[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (ch == '"') {
        quoted = !quoted;
      } else if (ch == ',' && !quoted) {
        fields.emplace_back();
      } else {
        fields.back() += ch;
      }
    }
    const char* cell = line++ == 0 ? "th" : "td";
    table += "<tr>";
    for (const std::string& f : fields)
      table += std::string("<") + cell + ">" + HtmlEscape(f) + "</" + cell + ">";
    table += "</tr>";
  }
  table += "</table>";
  return table;
}

// The title, the scene and study line, and the image check.
void ReportPage::Intro() {
  body << "<h1>Pandora report: "
       << HtmlEscape(std::filesystem::path(scene.path).filename().string())
       << "</h1>\n<p class=\"meta\">Scene <code>" << HtmlEscape(scene.path)
       << "</code> (SHA-256 <code>" << scene.sha256.substr(0, 16) << "&hellip;</code>), pandora "
       << PANDORA_VERSION << ". Voxel size "
       << Fmt("%g", reports[0].fields.lattice.voxel_size * 1e3) << " mm; region "
       << (study.region.kind == Region::Kind::kBox ? "box" : "mesh") << " "
       << Fmt("%.3f", study.region.box.min.x()) << "&ndash;"
       << Fmt("%.3f", study.region.box.max.x()) << " &times; "
       << Fmt("%.3f", study.region.box.min.y()) << "&ndash;"
       << Fmt("%.3f", study.region.box.max.y()) << " &times; "
       << Fmt("%.3f", study.region.box.min.z()) << "&ndash;"
       << Fmt("%.3f", study.region.box.max.z()) << " m; pixel noise "
       << Fmt("%g", study.pixel_sigma) << " px";
  if (study.motion)
    body << "; motion q = " << Fmt("%g", study.motion->q) << " m&sup2;/s&sup3; at "
         << Fmt("%g", study.motion->rate_hz) << " Hz ("
         << (study.steady_prior ? "prior" : "posterior") << " covariance)";
  body << ". Rigs: ";
  for (std::size_t i = 0; i < n; ++i)
    body << (i ? ", " : "") << "<b>" << HtmlEscape(reports[i].rig.name) << "</b>";
  body << ".</p>\n<p id=\"image-check\" class=\"pending\">checking images&hellip;</p>\n";
}

// The headline numbers, compared when there are several rigs.
void ReportPage::Numbers() {
  body << "<h2 id=\"numbers\">" << (n > 1 ? "Rigs compared" : "Summary") << "</h2>\n"
       << "<p class=\"note\">Fractions are of the free region voxels (inside the region, outside "
          "solids); &sigma;<sub>max</sub> percentiles are over the triangulable voxels."
       << (n > 1 ? " The better value of each row is in bold, compared as shown (no bold where all "
                   "rigs show the same value)."
                 : "")
       << "</p>\n"
       << HeadlineTable(data);
}

// Rig headers for the column layout.
void ReportPage::RigHeads() {
  for (const RigReport& r : reports)
    heads.push_back("<h3 class=\"rig\">" + HtmlEscape(r.rig.name) + " &mdash; " +
                    std::to_string(r.rig.enabled_count()) + " cameras</h3>");
}

// Warnings (as `pandora analyze` prints them): nonsense placements and lenses.
void ReportPage::Warnings() {
  std::size_t total = 0;
  for (const RigReport& r : reports) total += r.warnings.size();
  body << "<h2 id=\"warnings\">Warnings</h2>\n<p class=\"note\">Checks of each enabled camera: "
          "inside a solid object, outside the modelled room, seeing none of the region, a lens "
          "model that folds back inside the image (docs/user-guide.md, "
          "&ldquo;Warnings&rdquo;).</p>\n";
  if (total == 0) {
    body << "<p>No warnings.</p>\n";
  } else {
    std::vector<std::string> cells;
    for (const RigReport& r : reports) cells.push_back(WarningList(r, scene.path));
    body << RigRow(heads) << RigRow(cells);
  }
}

// The plan: the proposal's first picture (orthographic, cut at the region's top, ids labelled).
void ReportPage::Plan() {
  const int height = std::max(1, static_cast<int>(std::lround(view_width * 10.0 / 16.0)));
  double mpp = 0;
  const std::optional<RenderView> plan =
      PlanView(scene.ContentBounds(), "plan", view_width, height, study.region.box.max.z(), &mpp);
  char note[256];
  std::snprintf(
      note, sizeof note,
      "From above, north up, orthographic (to %.1f %%), cut at the study region's top (%.2f m): "
      "1 px = %.3g cm. Each camera is drawn with its id.",
      100.0 / kPlanDistance, study.region.box.max.z(), 100.0 * mpp);
  body << "<h2 id=\"plan\">Plan</h2>\n<p class=\"note\">" << note << "</p>\n" << RigRow(heads);
  std::vector<std::string> cells;
  for (const RigReport& r : reports) {
    RenderOptions render;
    render.pixel_sigma = study.pixel_sigma;
    render.brightness = options.brightness;
    render.layers = false;
    render.overlays.labels = true;
    render.overlays.frustum_length = 0.04 * mpp * view_width;
    const Image image = Render(scene, r.rig, caster, *plan, render);
    cells.push_back(
        "<figure>" +
        fig.Img("image/png", pandora::EncodePng(image), r.rig.name + " plan", "render") +
        "<figcaption>plan</figcaption></figure>");
  }
  body << RigRow(cells);
}

// Renders: the named views (here), then each camera's own view (CameraViews), per rig.
void ReportPage::Views() {
  if (!scene.views.empty()) {
    body << "<h2 id=\"views\">Views</h2>\n<p class=\"note\">Each enabled camera projects light of "
            "its own colour; where several see a surface their colours add, and surfaces no camera "
            "sees stay dark (visibility rules: range, image, facing, occlusion). Camera bodies and "
            "frusta are drawn in their colours.</p>\n"
         << RigRow(heads);
    {
      std::vector<std::string> keys;
      for (const RigReport& r : reports) keys.push_back(ColourKey(r.rig));
      body << RigRow(keys);
    }
    const int height = std::max(1, static_cast<int>(std::lround(view_width * 10.0 / 16.0)));
    // The field slices come as images below: an overlay in these views is often hidden by the
    // very occluders the report is about (the medics in the trauma room), so the views stay plain.
    for (const auto& [name, view] : scene.views) {
      std::vector<std::string> cells;
      for (const RigReport& r : reports) {
        RenderOptions render;
        render.pixel_sigma = study.pixel_sigma;
        render.brightness = options.brightness;
        render.layers = false;  // PNG only: no resolution / sigma_max per pixel
        const Image image =
            Render(scene, r.rig, caster, ViewFromScene(view, view_width, height), render);
        cells.push_back("<figure>" +
                        fig.Img("image/png", pandora::EncodePng(image),
                                r.rig.name + " view " + name, "render") +
                        "<figcaption>view <b>" + HtmlEscape(name) + "</b></figcaption></figure>");
      }
      body << RigRow(cells);
    }
  }
}

// Each camera's own view, per rig.
void ReportPage::CameraViews() {
  body << "<h2 id=\"camera-views\">What each camera sees</h2>\n<p class=\"note\">Each camera's "
          "own image (its lens model, distortion included), lit by every camera of its rig.</p>\n"
       << RigRow(heads);
  std::vector<std::string> cells;
  for (const RigReport& r : reports) {
    std::string cell = ColourKey(r.rig) + "<div class=\"thumbs\">";
    for (std::size_t c = 0; c < r.rig.cameras.size(); ++c) {
      const Camera& cam = r.rig.cameras[c];
      if (!cam.enabled) continue;
      RenderView view;
      view.camera = static_cast<int>(c);
      view.width = options.camera_width;
      view.height =
          std::max(1, static_cast<int>(std::lround(double(options.camera_width) *
                                                   cam.model.height() / cam.model.width())));
      RenderOptions render;
      render.pixel_sigma = study.pixel_sigma;
      render.brightness = options.brightness;
      render.layers = false;  // PNG only: no resolution / sigma_max per pixel
      render.overlays.cameras = false;
      render.overlays.key = false;  // the key is above the views, once per rig
      const Image image = Render(scene, r.rig, caster, view, render);
      cell += "<figure>" +
              fig.Img("image/png", pandora::EncodePng(image), r.rig.name + " camera " + cam.id,
                      "thumb") +
              "<figcaption>" + HtmlEscape(cam.id) +
              (cam.name != cam.id ? " (" + HtmlEscape(cam.name) + ")" : "") +
              "</figcaption></figure>";
    }
    cells.push_back(cell + "</div>");
  }
  body << RigRow(cells);
}

// Field slices on shared scales.
void ReportPage::Slices() {
  body << "<h2 id=\"slices\">Field slices</h2>\n<p class=\"note\">Voxel planes through the centre "
          "of "
          "the region, one pixel block per voxel. Light grey: not a free region voxel (inside a "
          "solid); dark grey: no camera sees it (coverage, resolution) or not triangulable "
          "(sigma_max). Each field has one colour scale for all rigs.</p>\n"
       << RigRow(heads);
  for (const FieldSlices& fs : data.slices) {
    const std::string& field = fs.field;
    Colorbar bar;
    bar.label = FieldLabel(field);
    bar.min = fs.scale.min;
    bar.max = fs.scale.max;
    bar.discrete = fs.scale.discrete;
    bar.max_is_open = fs.scale.open;
    if (field != "coverage")
      bar.swatches.push_back(
          {HexColor(kNoValueColor).data(), field == "sigma_max" ? "not triangulable" : "unseen"});
    bar.swatches.push_back({HexColor(kOutsideRegionColor).data(), "outside region"});
    body << "<h3>" << HtmlEscape(field) << "</h3>\n";
    const std::string legend = fig.Svg(RenderColorbarSvg(bar), field + " colour scale");
    body << "<div class=\"legend\">" << legend << "</div>\n";
    std::vector<std::string> cells;
    for (std::size_t i = 0; i < n; ++i) {
      std::string cell = "<div class=\"pair\">";
      for (const FieldSlice& s : fs.rigs[i]) {
        const int axis = s.axis;
        const int scale_px = std::max(1, 320 / std::max(s.width, s.height));
        const char* v = axis == 2 ? "y" : "z";
        const std::string caption =
            std::string(axis == 2 ? "z" : "y") + " = " + Fmt("%.3f", s.coordinate) + " m; x " +
            Fmt("%.3f", s.u_min) + "&rarr;" + Fmt("%.3f", s.u_max) + " m left to right, " + v +
            " " + Fmt("%.3f", s.v_min) + "&rarr;" + Fmt("%.3f", s.v_max) + " m bottom to top";
        cell += "<figure>" +
                fig.Png(SliceRaster(s, fs.scale.min, fs.scale.max, scale_px),
                        reports[i].rig.name + " " + field + " slice " + (axis == 2 ? "z" : "y"),
                        "slice") +
                "<figcaption>" + caption + "</figcaption></figure>";
      }
      cells.push_back(cell + "</div>");
    }
    body << RigRow(cells);
  }
}

// Histograms on shared axes.
void ReportPage::Histograms() {
  body << "<h2 id=\"histograms\">Histograms</h2>\n" << RigRow(heads);
  {
    const CoverageHistogram& h = data.coverage_histogram;
    std::vector<std::string> cells;
    for (std::size_t i = 0; i < n; ++i) {
      const std::string& name = reports[i].rig.name;
      BarChart chart;
      chart.title = "Coverage: " + name;
      chart.x_label = "cameras that see the voxel";
      chart.y_label = "share of region voxels";
      chart.percent = true;
      chart.y_max = h.y_max;
      chart.bin_width = 1;  // whole cameras: labels thinned to 1-2-5 steps
      BarSeries s;
      s.label = name;
      for (int k = 0; k <= h.max_cameras; ++k) chart.categories.push_back(std::to_string(k));
      s.values = h.shares[i];
      s.color = "#3b528b";
      chart.series.push_back(s);
      cells.push_back(fig.Svg(RenderBarChartSvg(chart), name + " coverage histogram"));
    }
    body << RigRow(cells);
  }
  {
    const SigmaHistogram& h = data.sigma_histogram;
    std::vector<std::string> cells;
    for (std::size_t i = 0; i < n; ++i) {
      BarChart chart;
      chart.title = "sigma_max: " + reports[i].rig.name;
      chart.x_label = "sigma_max (mm), bins of " + Fmt("%g", h.bin_width) + " mm";
      chart.y_label = "share of region voxels";
      chart.note =
          "triangulable voxels only; bins labelled by their lower edge; the last bar: sigma_max "
          ">= " +
          Fmt("%g", h.top) + " mm";
      chart.edge_labels = true;
      chart.bin_width = h.bin_width;
      chart.percent = true;
      chart.y_max = h.y_max;
      for (int b = 0; b < h.bins; ++b) chart.categories.push_back(Fmt("%g", b * h.bin_width));
      chart.categories.push_back(">=" + Fmt("%g", h.top));
      chart.series.push_back({reports[i].rig.name, h.shares[i], "#21918c"});
      if (study.max_sigma_mm) {
        chart.marker = std::min(*study.max_sigma_mm / h.bin_width, double(h.bins));
        chart.marker_label = "target " + Fmt("%g", *study.max_sigma_mm) + " mm";
      }
      cells.push_back(
          fig.Svg(RenderBarChartSvg(chart), reports[i].rig.name + " sigma_max histogram"));
    }
    body << RigRow(cells);
  }
}

// Cameras.
void ReportPage::Cameras() {
  body
      << "<h2 id=\"cameras\">Cameras</h2>\n<p class=\"note\">The swatch is the colour of the "
         "camera's light in the renders. FOV: edge to edge of the image along the rows and columns "
         "through the principal point, with the lens distortion; nominal FOV: from the focal "
         "length "
         "alone (distortion ignored); unreachable pixels: share of the image beyond the distortion "
         "model's valid domain; region seen: share of the free region voxels the camera sees "
         "(visibility rules, occlusion included).</p>\n"
      << RigRow(heads);
  std::vector<std::string> cells;
  for (const RigReport& r : reports)
    cells.push_back("<div class=\"scroll\">" + CameraTable(r, study) + "</div>");
  body << RigRow(cells);
}

// The installation sheet: what an installer needs per camera, with the CSV to download
// (analysis/rig/rig_formats.h RigToSheetCsv, the same as `pandora export-rig --format sheet`).
void ReportPage::Sheet() {
  body << "<h2 id=\"sheet\">Installation sheet</h2>\n<p class=\"note\">Mount point (the centre of "
          "projection) in centimetres, pan, tilt and roll in degrees (the scene file's euler_deg: "
          "pan "
          "about +z from +x, tilt up from horizontal, roll about the optical axis), lens and "
          "resolution. The link holds the whole sheet as CSV.</p>\n"
       << RigRow(heads);
  std::vector<std::string> cells;
  for (const RigReport& r : reports) {
    const std::string csv = RigToSheetCsv(r.rig);
    const std::string table = SheetTable(csv);
    cells.push_back("<div class=\"scroll\">" + table + "</div><p><a download=\"" +
                    HtmlEscape(r.rig.name) + "_sheet.csv\" href=\"" + DataUri("text/csv", csv) +
                    "\">" + HtmlEscape(r.rig.name) + "_sheet.csv</a></p>");
  }
  body << RigRow(cells);
}

// Calibration feasibility (app/report/calibration_section.h), when the study asks for it.
void ReportPage::Calibration() {
  if (study.calibration) {
    body << "<h2 id=\"calibration\">Calibration</h2>\n"
         << CalibrationIntroHtml(*study.calibration) << RigRow(heads);
    const auto svg_image = [&](const std::string& svg, const std::string& alt) {
      return fig.Svg(svg, alt);
    };
    std::vector<std::string> cells;
    for (const RigReport& r : reports)
      cells.push_back(CalibrationCellHtml(*r.summary.calibration, r.rig.name, svg_image));
    body << RigRow(cells);
  }
}

// Over time and on bodies (app/report/time_section.h), with moving objects or targets.
void ReportPage::OverTime() {
  std::vector<const Summary*> summaries;
  std::vector<std::string> names;
  for (const RigReport& r : reports) {
    summaries.push_back(&r.summary);
    names.push_back(r.rig.name);
  }
  body << TimeSectionHtml(summaries, names);
}

// N-1 robustness (app/report/robustness_section.h): the most critical cameras of each rig.
void ReportPage::Robustness() {
  if (std::all_of(reports.begin(), reports.end(),
                  [](const RigReport& r) { return r.summary.robustness; })) {
    body << "<h2 id=\"robustness\">Robustness</h2>\n"
         << RobustnessIntroHtml(reports[0].summary.robustness->k) << RigRow(heads);
    std::vector<std::string> cells;
    for (const RigReport& r : reports) cells.push_back(RobustnessCellHtml(*r.summary.robustness));
    body << RigRow(cells);
  }
}

// Predicted against measured (ReportOptions::validation): each rig's cell from the caller.
void ReportPage::Validation() {
  if (!options.validation) return;
  body << "<h2 id=\"validation\">Predicted against measured</h2>\n<p class=\"note\">"
       << options.validation_intro << "</p>\n"
       << RigRow(heads);
  const auto svg_image = [&](const std::string& svg, const std::string& alt) {
    return fig.Svg(svg, alt);
  };
  std::vector<std::string> cells;
  for (const RigReport& r : reports) cells.push_back(options.validation(r.rig, svg_image));
  body << RigRow(cells);
}

// The whole page: head and style, the body, each rig's summary.json and the image check.
std::string ReportPage::Html() const {
  // summary.json of each rig (as `pandora analyze` writes it), for readers and tools; not executed.
  std::string summaries;
  for (const RigReport& r : reports) {
    std::string json = nlohmann::json(r.summary).dump();
    for (std::size_t p = json.find("</"); p != std::string::npos; p = json.find("</", p + 2))
      json.replace(p, 2, "<\\/");
    summaries += "<script type=\"application/json\" class=\"summary\" data-rig=\"" +
                 HtmlEscape(r.rig.name) + "\">" + json + "</script>\n";
  }
  std::ostringstream page;
  page
      << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src "
         "data:; "
         "style-src 'unsafe-inline'; script-src 'unsafe-inline'\">\n"
      << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      << "<meta name=\"generator\" content=\"pandora " << PANDORA_VERSION << "\">\n"
      << "<title>Pandora report: " << HtmlEscape(scene.path) << "</title>\n<style>\n"
      << "body{font-family:'DejaVu Sans',Arial,Helvetica,sans-serif;margin:24px auto;max-width:"
      << (n > 1 ? 1500 : 900)
      << "px;padding:0 16px;color:#222;font-size:14px}\n"
         "h1{font-size:22px}h2{font-size:18px;border-bottom:1px solid "
         "#ccc;padding-bottom:4px;margin-top:32px}\n"
         "h3{font-size:15px;margin:14px 0 "
         "6px}h3.rig{text-align:center;background:#f2f2f2;padding:6px}\n"
         ".rigs{display:grid;gap:16px;align-items:start}.cell{min-width:0}\n"
         "figure{margin:0 0 10px}figcaption{font-size:11px;color:#555}\n"
         "img{max-width:100%;height:auto;display:block}img.slice{image-rendering:pixelated;width:"
         "100%}\n"
         ".pair{display:grid;grid-template-columns:1fr 1fr;gap:8px}\n"
         ".thumbs{display:grid;grid-template-columns:repeat(auto-fill,minmax(160px,1fr));gap:6px}\n"
         "img.render{width:100%}.legend img{max-width:440px}\n"
         "table{border-collapse:collapse;font-size:13px;margin:6px 0}td,th{border:1px solid #ccc;"
         "padding:3px "
         "8px;text-align:right}th{background:#f2f2f2}td:first-child,th:first-child{text-align:left}"
         "\n"
         "table.cameras "
         "td:nth-child(2){text-align:left}tr.disabled{color:#999}td.best{font-weight:bold}\n"
         ".swatch{display:inline-block;width:12px;height:12px;margin-right:4px;vertical-align:-1px;"
         "border:1px solid #555}.key{font-size:12px;margin:4px 0 8px}.key "
         ".entry{white-space:nowrap;"
         "margin-right:8px}ul.warnings{color:#8a4b00}ul.warnings code{color:#555}\n"
         ".scroll{overflow-x:auto}table.cameras td{white-space:nowrap}\n"
         ".meta,.note{color:#555}#image-check{font-size:12px}#image-check.bad{color:#b00;font-"
         "weight:bold}\n"
         "#image-check.ok{color:#070}tr.uncalibratable,.calib-bad{color:#c00000}\n"
         "</style>\n</head>\n<body data-expected-images=\""
      << fig.count() << "\">\n"
      << body.str() << summaries
      << "<script>\n"
         "// Marks the page when an image failed to decode (also used by the test suite).\n"
         "window.addEventListener('load', function () {\n"
         "  var images = document.images, bad = [];\n"
         "  for (var i = 0; i < images.length; ++i)\n"
         "    if (!images[i].complete || images[i].naturalWidth === 0) bad.push(images[i].alt || "
         "('image ' + i));\n"
         "  var expected = parseInt(document.body.getAttribute('data-expected-images'), 10);\n"
         "  var status = document.getElementById('image-check');\n"
         "  if (bad.length === 0 && images.length === expected) {\n"
         "    status.textContent = 'images ok: ' + images.length + ' of ' + expected + ' "
         "decoded';\n"
         "    status.className = 'ok';\n"
         "  } else {\n"
         "    status.textContent = 'images FAILED: ' + images.length + ' found, ' + expected +\n"
         "        ' expected; not decoded: ' + (bad.join(', ') || 'none');\n"
         "    status.className = 'bad';\n"
         "  }\n"
         "});\n</script>\n</body>\n</html>\n";
  return page.str();
}

}  // namespace

ReportFile WriteReport(const Scene& scene, const RayCaster& caster, const ReportData& data,
                       const ReportOptions& options, const ReportTarget& target) {
  ReportPage page(scene, caster, data, options);
  page.Intro();
  page.Numbers();
  page.RigHeads();
  page.Warnings();
  page.Plan();
  page.Views();
  page.CameraViews();
  page.Slices();
  page.Histograms();
  page.Cameras();
  page.Sheet();
  page.Calibration();
  page.OverTime();
  page.Robustness();
  page.Validation();
  const std::string html = page.Html();
  WriteFileAtomically(target.staged, html);
  ReportFile file;
  file.path = target.path;
  file.images = page.fig.count();
  file.bytes = html.size();
  return file;
}

}  // namespace pandora::report
