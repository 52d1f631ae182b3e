// `pandora report`: one self-contained HTML page per scene (docs/report.md). Every figure is an
// <img> with a base64 data URI (PNG for images, SVG for plots and legends); nothing is fetched, and
// a Content-Security-Policy forbids it. When the file has several rigs they are laid out in columns,
// the same figures per rig on the same scales, with the headline numbers compared in one table.
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "analysis/error.h"
#include "analysis/ray_caster.h"
#include "analysis/rig_check.h"
#include "analysis/scene.h"
#include "app/commands.h"
#include "app/output.h"
#include "app/plot.h"
#include "app/report_images.h"
#include "render/colormap.h"
#include "render/render.h"
#include "volume/fields.h"
#include "volume/slice.h"
#include "volume/summary.h"

#ifndef PANDORA_VERSION
#define PANDORA_VERSION "dev"
#endif

namespace pandora::app {
namespace {

std::string Html(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string Fmt(const char* format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

std::string Percent(double fraction) { return Fmt("%.1f%%", 100.0 * fraction); }

std::vector<std::string> SplitList(const std::vector<std::string>& items) {
  std::vector<std::string> out;
  for (const std::string& item : items) {
    std::stringstream ss(item);
    std::string part;
    while (std::getline(ss, part, ','))
      if (!part.empty()) out.push_back(part);
  }
  return out;
}

// Everything computed for one rig.
struct RigReport {
  const Rig* rig = nullptr;
  Fields fields;
  std::vector<Warning> warnings;
  nlohmann::json summary;
};

// "#rrggbb" of a linear-RGB light colour (clamped), as the PNGs show it.
std::string HexOfLinear(const Vec3& c) {
  char b[8];
  int v[3];
  for (int k = 0; k < 3; ++k) v[k] = static_cast<int>(std::lround(255.0 * SrgbFromLinear(c[k])));
  std::snprintf(b, sizeof b, "#%02x%02x%02x", v[0], v[1], v[2]);
  return b;
}

std::string Swatch(const Camera& cam) {
  return "<span class=\"swatch\" style=\"background:" + HexOfLinear(cam.color) + "\"></span>";
}

// The colour key of a rig: each enabled camera's light colour and id.
std::string ColourKey(const Rig& rig) {
  std::string s = "<div class=\"key\">";
  for (const Camera& cam : rig.cameras)
    if (cam.enabled) s += "<span class=\"entry\">" + Swatch(cam) + Html(cam.id) + "</span> ";
  return s + "</div>";
}

// An <img> the page embeds, counted so the page's own check knows how many to expect.
class Figures {
 public:
  std::string Img(const std::string& mime, const std::string& bytes, const std::string& alt,
                  const std::string& css_class = "") {
    ++count_;
    return "<img src=\"" + DataUri(mime, bytes) + "\" alt=\"" + Html(alt) + "\"" +
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

double JsonNumber(const nlohmann::json& j, const std::vector<std::string>& path) {
  const nlohmann::json* p = &j;
  for (const std::string& key : path) {
    if (!p->is_object() || !p->contains(key)) return std::nan("");
    p = &(*p)[key];
  }
  return p->is_number() ? p->get<double>() : std::nan("");
}

// The headline numbers, as in summary.json.
struct Headline {
  std::string label;
  std::vector<std::string> path;
  const char* format;  // printf format of the value; nullptr: a fraction shown as a percentage
  bool higher_better;  // for highlighting the best rig
};

std::string HeadlineText(const Headline& h, double x) {
  if (!std::isfinite(x)) return "&mdash;";
  return h.format ? Fmt(h.format, x) : Percent(x);
}

// The value as shown (rounded to the precision printed), so that rigs that look equal are equal.
double Shown(const Headline& h, double x) {
  const std::string t = h.format ? Fmt(h.format, x) : Fmt("%.1f", 100.0 * x);
  return std::strtod(t.c_str(), nullptr);
}

std::string HeadlineTable(const std::vector<RigReport>& rigs, const Study& study) {
  std::vector<Headline> rows{
      {"Coverage &ge; 1 camera", {"coverage", "ge1"}, nullptr, true},
      {"Coverage &ge; 2 cameras", {"coverage", "ge2"}, nullptr, true},
      {"Coverage &ge; 3 cameras", {"coverage", "ge3"}, nullptr, true},
      {"Resolution p10 (px/m)", {"resolution_px_per_m", "p10"}, "%.0f", true},
      {"Resolution p50 (px/m)", {"resolution_px_per_m", "p50"}, "%.0f", true},
      {"Resolution p90 (px/m)", {"resolution_px_per_m", "p90"}, "%.0f", true},
      {"Triangulable", {"uncertainty", "triangulable"}, nullptr, true},
      {"&sigma;<sub>max</sub> p50 (mm)", {"uncertainty", "sigma_max_mm", "p50"}, "%.3f", false},
      {"&sigma;<sub>max</sub> p90 (mm)", {"uncertainty", "sigma_max_mm", "p90"}, "%.3f", false},
      {"&sigma;<sub>max</sub> p99 (mm)", {"uncertainty", "sigma_max_mm", "p99"}, "%.3f", false},
  };
  if (study.max_sigma_mm)
    rows.push_back({"Meets &sigma;<sub>max</sub> &le; " + Fmt("%g", *study.max_sigma_mm) + " mm",
                    {"uncertainty", "meets_max_sigma"}, nullptr, true});
  if (study.motion) {
    rows.push_back({"Steady-state &sigma;<sub>max</sub> p50 (mm)", {"uncertainty", "sigma_max_steady_mm", "p50"}, "%.3f", false});
    rows.push_back({"Steady-state &sigma;<sub>max</sub> p90 (mm)", {"uncertainty", "sigma_max_steady_mm", "p90"}, "%.3f", false});
    rows.push_back({"Steady-state &sigma;<sub>max</sub> p99 (mm)", {"uncertainty", "sigma_max_steady_mm", "p99"}, "%.3f", false});
    if (study.max_sigma_mm)
      rows.push_back({"Steady state meets &sigma;<sub>max</sub> &le; " + Fmt("%g", *study.max_sigma_mm) + " mm",
                      {"uncertainty", "meets_max_sigma_steady"}, nullptr, true});
  }
  std::string s = "<table class=\"numbers\"><thead><tr><th></th>";
  for (const RigReport& r : rigs) s += "<th>" + Html(r.rig->name) + "</th>";
  s += "</tr></thead><tbody>\n";
  s += "<tr><td>Enabled cameras</td>";
  for (const RigReport& r : rigs) s += "<td>" + std::to_string(r.rig->enabled_count()) + "</td>";
  s += "</tr>\n";
  for (const Headline& h : rows) {
    // Compared as shown: a rig is bold when its shown value is the best and some rig's is worse.
    std::vector<double> shown;
    for (const RigReport& r : rigs) shown.push_back(Shown(h, JsonNumber(r.summary, h.path)));
    double best = std::nan(""), worst = std::nan("");
    for (double x : shown)
      if (std::isfinite(x)) {
        best = std::isnan(best) ? x : h.higher_better ? std::max(best, x) : std::min(best, x);
        worst = std::isnan(worst) ? x : h.higher_better ? std::min(worst, x) : std::max(worst, x);
      }
    const bool differ = std::isfinite(best) && best != worst;
    s += "<tr><td>" + h.label + "</td>";
    for (std::size_t i = 0; i < rigs.size(); ++i) {
      const double x = JsonNumber(rigs[i].summary, h.path);
      const std::string text = HeadlineText(h, x);
      const bool is_best = rigs.size() > 1 && differ && std::isfinite(x) && shown[i] == best;
      s += is_best ? "<td class=\"best\">" + text + "</td>" : "<td>" + text + "</td>";
    }
    s += "</tr>\n";
  }
  s += "<tr><td>Warnings</td>";
  for (const RigReport& r : rigs) s += "<td>" + std::to_string(r.warnings.size()) + "</td>";
  s += "</tr>\n<tr><td>Region voxels (free)</td>";
  for (const RigReport& r : rigs) s += "<td>" + std::to_string(r.summary["region_voxels"].get<long long>()) + "</td>";
  s += "</tr>\n<tr><td>Field evaluation (s)</td>";
  for (const RigReport& r : rigs) s += "<td>" + Fmt("%.2f", r.summary["timing"]["seconds"].get<double>()) + "</td>";
  s += "</tr>\n</tbody></table>\n";
  return s;
}

std::string CameraTable(const RigReport& r, const Study& study) {
  std::string s =
      "<table class=\"cameras\"><thead><tr><th>id</th><th>name</th><th>resolution (px)</th>"
      "<th>FOV h &times; v (&deg;)</th><th>nominal (&deg;)</th><th>unreachable</th>"
      "<th>lens</th><th>region seen</th><th>pixel &sigma; (px)</th></tr></thead><tbody>\n";
  const nlohmann::json& per_camera = r.summary["per_camera"];
  for (std::size_t c = 0; c < r.rig->cameras.size(); ++c) {
    const Camera& cam = r.rig->cameras[c];
    const Intrinsics& k = cam.model.intrinsics();
    const nlohmann::json& pc = per_camera[c];
    const auto& eff = pc["fov_deg"]["effective"];
    const auto& nom = pc["fov_deg"]["nominal"];
    const double seen = pc["visible_fraction"].get<double>();
    const double unreachable = pc["unreachable_pixels"].get<double>();
    const std::string sigma = cam.pixel_sigma > 0 ? Fmt("%g", cam.pixel_sigma)
                                                  : Fmt("%g", study.pixel_sigma) + " (study)";
    s += std::string("<tr") + (cam.enabled ? "" : " class=\"disabled\"") + "><td>" +
         (cam.enabled ? Swatch(cam) : "") + Html(cam.id) + "</td><td>" + Html(cam.name) + "</td><td>" +
         std::to_string(k.width) + " &times; " + std::to_string(k.height) + "</td><td>" +
         Fmt("%.1f", eff[0].get<double>()) + " &times; " + Fmt("%.1f", eff[1].get<double>()) +
         "</td><td>" + Fmt("%.1f", nom[0].get<double>()) + " &times; " +
         Fmt("%.1f", nom[1].get<double>()) + "</td><td>" +
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
    s += "<li><code>" + Html(file + ": " + w.json_path) + "</code>: " + Html(w.reason) + "</li>\n";
  return s + "</ul>\n";
}

// The colour scale of one field, shared by every rig's slices.
struct Scale {
  double min = 0, max = 1;
  bool discrete = false, open = false;
};

Scale FieldScale(const std::string& field, const std::vector<RigReport>& rigs) {
  Scale s;
  if (field == "coverage") {
    int cameras = 1;
    for (const RigReport& r : rigs) cameras = std::max(cameras, r.rig->enabled_count());
    s.max = cameras;
    s.discrete = true;
    return s;
  }
  // sigma_max: up to the largest p99 over the rigs (so a few outlier voxels do not flatten the
  // scale), rounded up to a nice number; higher values take the top colour.
  double top = 0;
  for (const RigReport& r : rigs)
    top = std::max(top, JsonNumber(r.summary, {"uncertainty", "sigma_max_mm", "p99"}));
  if (!(top > 0)) top = 1;
  s.max = NiceTicks(top, 4).back();
  s.open = true;
  return s;
}

std::string FieldLabel(const std::string& field) {
  if (field == "coverage") return "coverage (cameras that see the point)";
  if (field == "resolution") return "resolution (px/m, best camera)";
  if (field == "sigma_max") return "sigma_max (mm, worst-direction 1-sigma)";
  return field;
}

}  // namespace

int RunReport(const ReportArgs& args) {
  Scene scene = LoadScene(args.scene);
  std::vector<const Rig*> rigs;
  const std::vector<std::string> names = SplitList(args.rigs);
  if (names.empty())
    for (const Rig& r : scene.rigs) rigs.push_back(&r);
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (std::find(names.begin(), names.begin() + i, names[i]) != names.begin() + i)
      throw InputError("--rig", "", "rig '" + names[i] + "' listed twice");
    rigs.push_back(&FindRigOption(scene, names[i]));
  }
  if (!std::isnan(args.voxel_size))
    scene.study.voxel_size = CheckPositiveOption("--voxel-size", args.voxel_size, "metres");
  for (auto [option, value] : {std::pair<const char*, int>{"--width", args.width},
                               std::pair<const char*, int>{"--camera-width", args.camera_width}})
    if (value < 16 || value > 8192)
      throw InputError(option, "", "must be 16 to 8192 pixels, not " + std::to_string(value));
  if (!std::isnan(args.brightness)) CheckPositiveOption("--brightness", args.brightness, "times one camera's light");
  const int view_width = args.width;
  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string path = (std::filesystem::path(args.out) / "report.html").string();
  const std::string staged = output.Stage(path, "--out");

  // Fields: the study's, plus what the figures need.
  std::vector<std::string> field_names;
  {
    std::set<std::string> wanted(scene.study.fields.begin(), scene.study.fields.end());
    wanted.insert({"coverage", "cameras", "resolution", "sigma_max"});
    for (const std::string& f : FieldNames())
      if (wanted.count(f)) field_names.push_back(f);
  }
  const std::unique_ptr<RayCaster> caster = MakeEmbreeRayCaster(scene.AllTriangles());
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  std::vector<RigReport> reports;
  for (const Rig* rig : rigs) {
    FieldOptions options;
    options.scene_path = scene.path;
    options.fields = field_names;
    options.memory_budget_bytes = scene.study.memory_budget_bytes;
    if (!std::isnan(args.voxel_size)) options.voxel_size_option = "--voxel-size";
    ProgressBar bar("report " + rig->name, !args.quiet);
    options.progress = [&bar](double f) { bar.Update(f); };
    RigReport r;
    r.rig = rig;
    r.fields = EvaluateFields(scene, *rig, *caster, options);
    bar.Finish();
    RigCheckOptions check;
    check.visible_voxels = r.fields.stats.per_camera_seen;
    r.warnings = CheckRig(scene, *rig, *caster, check);
    r.summary = MakeSummary(scene, *rig, r.fields, field_names, threads, r.warnings);
    reports.push_back(std::move(r));
  }

  Figures fig;
  std::ostringstream body;
  const Study& study = scene.study;
  const std::size_t n = reports.size();
  body << "<h1>Pandora report: " << Html(std::filesystem::path(scene.path).filename().string())
       << "</h1>\n<p class=\"meta\">Scene <code>" << Html(scene.path) << "</code> (SHA-256 <code>"
       << scene.sha256.substr(0, 16) << "&hellip;</code>), pandora " << PANDORA_VERSION
       << ". Voxel size " << Fmt("%g", reports[0].fields.lattice.voxel_size * 1e3)
       << " mm; region " << (study.region.kind == Region::Kind::kBox ? "box" : "mesh") << " "
       << Fmt("%.3f", study.region.box.min.x()) << "&ndash;" << Fmt("%.3f", study.region.box.max.x())
       << " &times; " << Fmt("%.3f", study.region.box.min.y()) << "&ndash;"
       << Fmt("%.3f", study.region.box.max.y()) << " &times; " << Fmt("%.3f", study.region.box.min.z())
       << "&ndash;" << Fmt("%.3f", study.region.box.max.z()) << " m; pixel noise "
       << Fmt("%g", study.pixel_sigma) << " px";
  if (study.motion)
    body << "; motion q = " << Fmt("%g", study.motion->q) << " m&sup2;/s&sup3; at "
         << Fmt("%g", study.motion->rate_hz) << " Hz (" << (study.steady_prior ? "prior" : "posterior")
         << " covariance)";
  body << ". Rigs: ";
  for (std::size_t i = 0; i < n; ++i) body << (i ? ", " : "") << "<b>" << Html(reports[i].rig->name) << "</b>";
  body << ".</p>\n<p id=\"image-check\" class=\"pending\">checking images&hellip;</p>\n";

  body << "<h2 id=\"numbers\">" << (n > 1 ? "Rigs compared" : "Summary") << "</h2>\n"
       << "<p class=\"note\">Fractions are of the free region voxels (inside the region, outside "
          "solids); &sigma;<sub>max</sub> percentiles are over the triangulable voxels."
       << (n > 1 ? " The better value of each row is in bold, compared as shown (no bold where all "
                  "rigs show the same value)." : "") << "</p>\n"
       << HeadlineTable(reports, study);

  // Warnings (as `pandora analyze` prints them): nonsense placements and lenses.
  {
    std::size_t total = 0;
    for (const RigReport& r : reports) total += r.warnings.size();
    body << "<h2 id=\"warnings\">Warnings</h2>\n<p class=\"note\">Checks of each enabled camera: "
            "inside a solid object, outside the modelled room, seeing none of the region, a lens "
            "model that folds back inside the image (docs/user-guide.md, "
            "&ldquo;Warnings&rdquo;).</p>\n";
    if (total == 0) {
      body << "<p>No warnings.</p>\n";
    } else {
      std::vector<std::string> heads, cells;
      for (const RigReport& r : reports) {
        heads.push_back("<h3 class=\"rig\">" + Html(r.rig->name) + " &mdash; " +
                        std::to_string(r.rig->enabled_count()) + " cameras</h3>");
        cells.push_back(WarningList(r, scene.path));
      }
      body << RigRow(heads) << RigRow(cells);
    }
  }

  // Rig headers for the column layout.
  std::vector<std::string> heads;
  for (const RigReport& r : reports)
    heads.push_back("<h3 class=\"rig\">" + Html(r.rig->name) + " &mdash; " +
                    std::to_string(r.rig->enabled_count()) + " cameras</h3>");

  // Renders: the named views, then each camera's own view, per rig.
  if (!scene.views.empty()) {
    body << "<h2 id=\"views\">Views</h2>\n<p class=\"note\">Each enabled camera projects light of "
            "its own colour; where several see a surface their colours add, and surfaces no camera "
            "sees stay dark (visibility rules: range, image, facing, occlusion). Camera bodies and "
            "frusta are drawn in their colours.</p>\n"
         << RigRow(heads);
    {
      std::vector<std::string> keys;
      for (const RigReport& r : reports) keys.push_back(ColourKey(*r.rig));
      body << RigRow(keys);
    }
    const int height = std::max(1, static_cast<int>(std::lround(view_width * 10.0 / 16.0)));
    auto render_views = [&](const std::string& name, const View& view) {
      std::vector<std::string> cells;
      for (const RigReport& r : reports) {
        RenderOptions options;
        options.pixel_sigma = study.pixel_sigma;
        options.brightness = args.brightness;
        options.layers = false;  // PNG only: no resolution / sigma_max per pixel
        const Image image = Render(scene, *r.rig, *caster, ViewFromScene(view, view_width, height), options);
        cells.push_back("<figure>" +
                        fig.Img("image/png", PngBytes(image), r.rig->name + " view " + name, "render") +
                        "<figcaption>view <b>" + Html(name) + "</b></figcaption></figure>");
      }
      body << RigRow(cells);
    };
    // The field slices come as images below: an overlay in these views is often hidden by the
    // very occluders the report is about (the medics in the trauma room), so the views stay plain.
    for (const auto& [name, view] : scene.views) render_views(name, view);
  }
  body << "<h2 id=\"camera-views\">What each camera sees</h2>\n<p class=\"note\">Each camera's "
          "own image (its lens model, distortion included), lit by every camera of its rig.</p>\n"
       << RigRow(heads);
  {
    std::vector<std::string> cells;
    for (const RigReport& r : reports) {
      std::string cell = ColourKey(*r.rig) + "<div class=\"thumbs\">";
      for (std::size_t c = 0; c < r.rig->cameras.size(); ++c) {
        const Camera& cam = r.rig->cameras[c];
        if (!cam.enabled) continue;
        RenderView view;
        view.camera = static_cast<int>(c);
        view.width = args.camera_width;
        view.height = std::max(1, static_cast<int>(std::lround(double(args.camera_width) *
                                                              cam.model.height() / cam.model.width())));
        RenderOptions options;
        options.pixel_sigma = study.pixel_sigma;
        options.brightness = args.brightness;
        options.layers = false;  // PNG only: no resolution / sigma_max per pixel
        options.overlays.cameras = false;
        options.overlays.key = false;  // the key is above the views, once per rig
        const Image image = Render(scene, *r.rig, *caster, view, options);
        cell += "<figure>" + fig.Img("image/png", PngBytes(image), r.rig->name + " camera " + cam.id, "thumb") +
                "<figcaption>" + Html(cam.id) + (cam.name != cam.id ? " (" + Html(cam.name) + ")" : "") +
                "</figcaption></figure>";
      }
      cells.push_back(cell + "</div>");
    }
    body << RigRow(cells);
  }

  // Field slices on shared scales.
  body << "<h2 id=\"slices\">Field slices</h2>\n<p class=\"note\">Voxel planes through the centre of "
          "the region, one pixel block per voxel. Light grey: not a free region voxel (inside a "
          "solid); dark grey: no camera sees it (coverage, resolution) or not triangulable "
          "(sigma_max). Each field has one colour scale for all rigs.</p>\n"
       << RigRow(heads);
  const Vec3 centre = study.region.box.center();
  for (const std::string& field : {std::string("coverage"), std::string("resolution"), std::string("sigma_max")}) {
    Scale scale;
    if (field == "resolution") {
      double top = 0;
      for (const RigReport& r : reports)
        for (int axis : {2, 1}) {
          const FieldSlice s = SliceField(r.fields, field, axis, centre[axis]);
          for (std::size_t i = 0; i < s.values.size(); ++i)
            if (s.has_value[i]) top = std::max(top, s.values[i]);
        }
      scale.max = NiceTicks(top > 0 ? top : 1.0, 4).back();
    } else {
      scale = FieldScale(field, reports);
    }
    Colorbar bar;
    bar.label = FieldLabel(field);
    bar.min = scale.min;
    bar.max = scale.max;
    bar.discrete = scale.discrete;
    bar.max_is_open = scale.open;
    if (field != "coverage")
      bar.swatches.push_back({HexColor(kNoValueColor).data(), field == "sigma_max" ? "not triangulable" : "unseen"});
    bar.swatches.push_back({HexColor(kOutsideRegionColor).data(), "outside region"});
    body << "<h3>" << Html(field) << "</h3>\n";
    const std::string legend = fig.Svg(RenderColorbarSvg(bar), field + " colour scale");
    body << "<div class=\"legend\">" << legend << "</div>\n";
    std::vector<std::string> cells;
    for (const RigReport& r : reports) {
      std::string cell = "<div class=\"pair\">";
      for (int axis : {2, 1}) {
        const FieldSlice s = SliceField(r.fields, field, axis, centre[axis]);
        const int scale_px = std::max(1, 320 / std::max(s.width, s.height));
        const char* v = axis == 2 ? "y" : "z";
        const std::string caption =
            std::string(axis == 2 ? "z" : "y") + " = " + Fmt("%.3f", s.coordinate) + " m; x " +
            Fmt("%.3f", s.u_min) + "&rarr;" + Fmt("%.3f", s.u_max) + " m left to right, " + v + " " +
            Fmt("%.3f", s.v_min) + "&rarr;" + Fmt("%.3f", s.v_max) + " m bottom to top";
        cell += "<figure>" +
                fig.Png(SliceRaster(s, scale.min, scale.max, scale_px),
                        r.rig->name + " " + field + " slice " + (axis == 2 ? "z" : "y"), "slice") +
                "<figcaption>" + caption + "</figcaption></figure>";
      }
      cells.push_back(cell + "</div>");
    }
    body << RigRow(cells);
  }

  // Histograms on shared axes.
  body << "<h2 id=\"histograms\">Histograms</h2>\n" << RigRow(heads);
  {
    int max_k = 0;
    double y_max = 0;
    for (const RigReport& r : reports) {
      const auto& h = r.fields.stats.coverage_histogram;
      max_k = std::max(max_k, static_cast<int>(h.size()) - 1);
      for (auto c : h) y_max = std::max(y_max, double(c) / std::max<std::int64_t>(1, r.fields.stats.active_set.region_voxels));
    }
    std::vector<std::string> cells;
    for (const RigReport& r : reports) {
      BarChart chart;
      chart.title = "Coverage: " + r.rig->name;
      chart.x_label = "cameras that see the voxel";
      chart.y_label = "share of region voxels";
      chart.percent = true;
      chart.y_max = y_max;
      chart.bin_width = 1;  // whole cameras: labels thinned to 1-2-5 steps
      BarSeries s;
      s.label = r.rig->name;
      const auto& h = r.fields.stats.coverage_histogram;
      const double region = std::max<std::int64_t>(1, r.fields.stats.active_set.region_voxels);
      for (int k = 0; k <= max_k; ++k) {
        chart.categories.push_back(std::to_string(k));
        s.values.push_back(k < static_cast<int>(h.size()) ? h[k] / region : 0.0);
      }
      s.color = "#3b528b";
      chart.series.push_back(s);
      cells.push_back(fig.Svg(RenderBarChartSvg(chart), r.rig->name + " coverage histogram"));
    }
    body << RigRow(cells);
  }
  {
    // sigma_max: up to 30 bins of a 1-2-5 width from 0 to the shared scale's top, an overflow bin
    // after, so the bin edges (and the labels on them) are round numbers.
    const Scale scale = FieldScale("sigma_max", reports);
    const double width = NiceStep(scale.max / 30);
    const int bins = std::max(1, static_cast<int>(std::ceil(scale.max / width - 1e-9)));
    const double top = bins * width;
    std::vector<std::vector<double>> shares;
    double y_max = 0;
    for (const RigReport& r : reports) {
      std::vector<double> count(bins + 1, 0.0);
      for (float v : r.fields.stats.sigma_max_mm) count[std::min(bins, static_cast<int>(v / width))] += 1;
      const double region = std::max<std::int64_t>(1, r.fields.stats.active_set.region_voxels);
      for (double& c : count) {
        c /= region;
        y_max = std::max(y_max, c);
      }
      shares.push_back(count);
    }
    std::vector<std::string> cells;
    for (std::size_t i = 0; i < n; ++i) {
      BarChart chart;
      chart.title = "sigma_max: " + reports[i].rig->name;
      chart.x_label = "sigma_max (mm), bins of " + Fmt("%g", width) + " mm";
      chart.y_label = "share of region voxels";
      chart.note = "triangulable voxels only; bins labelled by their lower edge; the last bar: sigma_max >= " +
                   Fmt("%g", top) + " mm";
      chart.edge_labels = true;
      chart.bin_width = width;
      chart.percent = true;
      chart.y_max = y_max;
      for (int b = 0; b < bins; ++b) chart.categories.push_back(Fmt("%g", b * width));
      chart.categories.push_back(">=" + Fmt("%g", top));
      chart.series.push_back({reports[i].rig->name, shares[i], "#21918c"});
      if (study.max_sigma_mm) {
        chart.marker = std::min(*study.max_sigma_mm / width, double(bins));
        chart.marker_label = "target " + Fmt("%g", *study.max_sigma_mm) + " mm";
      }
      cells.push_back(fig.Svg(RenderBarChartSvg(chart), reports[i].rig->name + " sigma_max histogram"));
    }
    body << RigRow(cells);
  }

  // Cameras.
  body << "<h2 id=\"cameras\">Cameras</h2>\n<p class=\"note\">The swatch is the colour of the "
          "camera's light in the renders. FOV: edge to edge of the image along the rows and columns "
          "through the principal point, with the lens distortion; nominal FOV: from the focal length "
          "alone (distortion ignored); unreachable pixels: share of the image beyond the distortion "
          "model's valid domain; region seen: share of the free region voxels the camera sees "
          "(visibility rules, occlusion included).</p>\n"
       << RigRow(heads);
  {
    std::vector<std::string> cells;
    for (const RigReport& r : reports) cells.push_back("<div class=\"scroll\">" + CameraTable(r, study) + "</div>");
    body << RigRow(cells);
  }

  // summary.json of each rig (as `pandora analyze` writes it), for readers and tools; not executed.
  std::string summaries;
  for (const RigReport& r : reports) {
    std::string json = r.summary.dump();
    for (std::size_t p = json.find("</"); p != std::string::npos; p = json.find("</", p + 2))
      json.replace(p, 2, "<\\/");
    summaries += "<script type=\"application/json\" class=\"summary\" data-rig=\"" + Html(r.rig->name) +
                 "\">" + json + "</script>\n";
  }
  std::ostringstream page;
  page << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
       << "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; img-src data:; "
          "style-src 'unsafe-inline'; script-src 'unsafe-inline'\">\n"
       << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
       << "<meta name=\"generator\" content=\"pandora " << PANDORA_VERSION << "\">\n"
       << "<title>Pandora report: " << Html(scene.path) << "</title>\n<style>\n"
       << "body{font-family:'DejaVu Sans',Arial,Helvetica,sans-serif;margin:24px auto;max-width:"
       << (n > 1 ? 1500 : 900) << "px;padding:0 16px;color:#222;font-size:14px}\n"
          "h1{font-size:22px}h2{font-size:18px;border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:32px}\n"
          "h3{font-size:15px;margin:14px 0 6px}h3.rig{text-align:center;background:#f2f2f2;padding:6px}\n"
          ".rigs{display:grid;gap:16px;align-items:start}.cell{min-width:0}\n"
          "figure{margin:0 0 10px}figcaption{font-size:11px;color:#555}\n"
          "img{max-width:100%;height:auto;display:block}img.slice{image-rendering:pixelated;width:100%}\n"
          ".pair{display:grid;grid-template-columns:1fr 1fr;gap:8px}\n"
          ".thumbs{display:grid;grid-template-columns:repeat(auto-fill,minmax(160px,1fr));gap:6px}\n"
          "img.render{width:100%}.legend img{max-width:440px}\n"
          "table{border-collapse:collapse;font-size:13px;margin:6px 0}td,th{border:1px solid #ccc;"
          "padding:3px 8px;text-align:right}th{background:#f2f2f2}td:first-child,th:first-child{text-align:left}\n"
          "table.cameras td:nth-child(2){text-align:left}tr.disabled{color:#999}td.best{font-weight:bold}\n"
          ".swatch{display:inline-block;width:12px;height:12px;margin-right:4px;vertical-align:-1px;"
          "border:1px solid #555}.key{font-size:12px;margin:4px 0 8px}.key .entry{white-space:nowrap;"
          "margin-right:8px}ul.warnings{color:#8a4b00}ul.warnings code{color:#555}\n"
          ".scroll{overflow-x:auto}table.cameras td{white-space:nowrap}\n"
          ".meta,.note{color:#555}#image-check{font-size:12px}#image-check.bad{color:#b00;font-weight:bold}\n"
          "#image-check.ok{color:#070}\n</style>\n</head>\n<body data-expected-images=\""
       << fig.count() << "\">\n"
       << body.str() << summaries
       << "<script>\n"
          "// Marks the page when an image failed to decode (also used by the test suite).\n"
          "window.addEventListener('load', function () {\n"
          "  var images = document.images, bad = [];\n"
          "  for (var i = 0; i < images.length; ++i)\n"
          "    if (!images[i].complete || images[i].naturalWidth === 0) bad.push(images[i].alt || ('image ' + i));\n"
          "  var expected = parseInt(document.body.getAttribute('data-expected-images'), 10);\n"
          "  var status = document.getElementById('image-check');\n"
          "  if (bad.length === 0 && images.length === expected) {\n"
          "    status.textContent = 'images ok: ' + images.length + ' of ' + expected + ' decoded';\n"
          "    status.className = 'ok';\n"
          "  } else {\n"
          "    status.textContent = 'images FAILED: ' + images.length + ' found, ' + expected +\n"
          "        ' expected; not decoded: ' + (bad.join(', ') || 'none');\n"
          "    status.className = 'bad';\n"
          "  }\n"
          "});\n</script>\n</body>\n</html>\n";
  WriteFileAtomically(staged, page.str());
  output.Commit();
  if (!args.quiet) {
    std::printf("wrote %s (%d images, %.1f MiB)\n", path.c_str(), fig.count(),
                page.str().size() / 1048576.0);
    std::fflush(stdout);
    for (const RigReport& r : reports)
      for (const Warning& w : r.warnings)
        std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(scene.path, w).c_str());
  }
  return 0;
}

}  // namespace pandora::app
