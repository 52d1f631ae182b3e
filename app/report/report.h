#pragma once
/// \file report.h
/// The HTML report of a scene (docs/report.md): one self-contained page with renders from the named
/// views, each camera's own view, field slices and histograms on shared scales, the camera table,
/// the warnings and the headline numbers, the rigs side by side.
///
/// Three steps, so that a front end (the CLI, the viewer) only parses, checks, runs and prints:
///   ReportOptions::Check()  the options alone;
///   ComputeReport()         the fields of every rig and everything the page shows as numbers
///                           (ReportData: summaries, the rig comparison, slices, histograms);
///   StageReport() + WriteReport()  the renders and the page, into an OutputTransaction.
/// Errors name the option (ReportOptions' field, e.g. "view_width") or the scene file's JSON path,
/// never a command-line flag. No OpenVDB, Embree or OpenEXR in this header.

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "analysis/geometry/ray_caster.h"
#include "analysis/rig/rig_check.h"
#include "analysis/scene/scene.h"
#include "analysis/util/output_transaction.h"
#include "volume/fields.h"
#include "volume/rig_comparison.h"
#include "volume/slice.h"
#include "volume/summary.h"

namespace pandora::report {

/// What to report and how large the images are.
struct ReportOptions {
  /// The rigs, by name, in column order; empty: every rig of the scene in file order.
  std::vector<std::string> rigs;
  /// Voxel size of the fields, metres; NaN: the scene's study.voxel_size.
  double voxel_size = std::numeric_limits<double>::quiet_NaN();
  /// Width in pixels of the renders from the named views (their height is 10/16 of it).
  int view_width = 640;
  /// Width in pixels of each camera's own view (its height keeps the camera's aspect).
  int camera_width = 320;
  /// Scale of every camera's light in the renders; NaN: DefaultBrightness (render/render.h).
  double brightness = std::numeric_limits<double>::quiet_NaN();
  /// Called on the calling thread before each rig's fields are evaluated, with the rig's name.
  std::function<void(const std::string& rig)> rig_started;
  /// The fraction of the current rig's evaluation done, from worker threads (thread-safe, cheap).
  std::function<void(double fraction)> progress;
  /// The "Predicted against measured" section (`pandora report --validate`, docs/validation.md):
  /// when set, called once per reported rig while the page is written, with the rig and a function
  /// that embeds an SVG figure (returning its HTML); returns the rig's cell (HTML). The section's
  /// introduction is validation_intro (HTML). Empty: no section.
  std::function<std::string(
      const Rig& rig,
      const std::function<std::string(const std::string& svg, const std::string& alt)>& svg_image)>
      validation;
  std::string validation_intro;

  /// The limits of each option.
  static constexpr int kMinWidth = 16, kMaxWidth = 8192;
  static constexpr double kMaxBrightness = 1e6;

  /// Throws InputError(file = the field's name, json_path "", reason) for a rig name that is empty
  /// or listed twice ("rigs"), a voxel_size that is set and not a positive finite number
  /// ("voxel_size"), a width outside [kMinWidth, kMaxWidth] ("view_width", "camera_width"), or a
  /// brightness that is set and outside (0, kMaxBrightness] ("brightness").
  void Check() const;
  /// Check(), and that every rig named is one of `scene`'s: InputError("rigs", "", "no rig named
  /// 'NAME' in SCENE", hint listing the scene's rigs) otherwise.
  void Check(const Scene& scene) const;
};

/// One rig's evaluation.
struct RigReport {
  Rig rig;        ///< A copy of the scene's rig.
  Fields fields;  ///< coverage, cameras, resolution, sigma_max and the study's fields.
  std::vector<Warning> warnings;  ///< CheckRig's (exact "sees none of the region" from the fields).
  Summary summary;                ///< As `pandora analyze` writes it (summary.json).
};

/// The colour scale of one field's slices, shared by every rig.
struct FieldScale {
  double min = 0, max = 1;
  bool discrete = false;  ///< Whole numbers (coverage): one colour box per value.
  bool open = false;      ///< Values above max take the top colour (the legend says ">= max").
};

/// One field's slices through the centre of the region: per rig, the z then the y voxel plane.
struct FieldSlices {
  std::string field;  ///< "coverage", "resolution" or "sigma_max".
  FieldScale scale;
  std::vector<std::array<FieldSlice, 2>> rigs;
};

/// The coverage histograms on a shared axis: per rig, the share of the free region voxels seen by
/// exactly k cameras, k = 0 .. max_cameras.
struct CoverageHistogram {
  int max_cameras = 0;                      ///< Largest k over the rigs.
  double y_max = 0;                         ///< Largest share over the rigs.
  std::vector<std::vector<double>> shares;  ///< [rig][k].
};

/// The sigma_max histograms: `bins` bins of `bin_width` mm from 0 (a 1-2-5 width: up to 30 bins to
/// the top of the shared colour scale), then one overflow bin (sigma_max >= top); shares of the
/// free region voxels (triangulable voxels only).
struct SigmaHistogram {
  double bin_width = 1, top = 1;  ///< mm; top = bins * bin_width.
  int bins = 1;
  double y_max = 0;
  std::vector<std::vector<double>> shares;  ///< [rig][bin], bins + 1 entries.
};

/// Everything the page shows as numbers.
struct ReportData {
  Study study;                           ///< As evaluated (ReportOptions::voxel_size applied).
  std::vector<std::string> field_names;  ///< The fields evaluated, in FieldNames() order.
  std::vector<RigReport> rigs;           ///< In column order.
  RigComparison comparison;              ///< The headline numbers compared.
  std::vector<FieldSlices> slices;       ///< coverage, resolution, sigma_max.
  CoverageHistogram coverage_histogram;
  SigmaHistogram sigma_histogram;
};

/// Evaluates the fields of every reported rig of `scene` (with `caster` built from
/// scene.AllTriangles()) and computes the report's numbers. Checks `options` first. Throws
/// InputError for bad options (as Check(); an unknown rig names "rigs" and lists the scene's rigs
/// in the hint), and as EvaluateFields for the scene (the memory budget: "$.study.voxel_size", or
/// "voxel_size" when the option set it).
ReportData ComputeReport(const Scene& scene, const RayCaster& caster, const ReportOptions& options);

/// Where the page goes: `path` (DIR/report.html) and the staged file to write.
struct ReportTarget {
  std::string path, staged;
};

/// Declares `dir`/report.html as an output of `output` (OutputTransaction::Stage; `option` names
/// where `dir` came from, in messages). Call it before ComputeReport: an unwritable folder then
/// fails before any work. Throws InputError as Stage.
ReportTarget StageReport(OutputTransaction& output, const std::string& dir,
                         const std::string& option);

/// What WriteReport wrote.
struct ReportFile {
  std::string path;
  int images = 0;         ///< <img> elements (every one a data URI).
  std::size_t bytes = 0;  ///< Size of the page.
};

/// Renders the views and writes the page to `target.staged` (the caller commits the transaction).
/// Renders with `options`' widths and brightness; `data` must come from ComputeReport for this
/// `scene` and `caster`. The page names the program as "pandora VERSION" (the build's version).
ReportFile WriteReport(const Scene& scene, const RayCaster& caster, const ReportData& data,
                       const ReportOptions& options, const ReportTarget& target);

}  // namespace pandora::report
