#pragma once
/// \file accuracy_tables.h
/// The outputs of `pandora accuracy` from the studies of app/session/accuracy.h: per study a titled
/// table (aligned text for the terminal, Markdown for accuracy_tables.md) with notes, a CSV file
/// and an SVG log-log plot of error against run time.

#include <string>
#include <vector>

#include "app/report/table.h"
#include "app/session/accuracy.h"

namespace pandora::report {

/// One study's outputs.
struct AccuracySection {
  std::string title;
  Table table;
  std::vector<std::string> notes;
  std::string csv_name, csv;  ///< e.g. "accuracy_voxel.csv" and its text.
  std::string svg_name, svg;  ///< e.g. "accuracy_voxel.svg" and its SVG document.

  /// What the terminal shows: a blank line, the title, the table, then "  note: ..." lines.
  std::string Text() const;
  /// The section of accuracy_tables.md: "## title", the table, the notes as a list.
  std::string Markdown() const;
};

/// (a) accuracy_voxel.{csv,svg}: per voxel size its time, the coverage errors in percentage points
/// and the sigma_max percentile errors in percent against the finest size.
AccuracySection VoxelSection(const VoxelStudy& study);

/// (b) accuracy_montecarlo.{csv,svg}: per trial count the time per point and the mean and largest
/// relative errors against J^-1, with the prediction's own time; `threads` is noted (the trials run
/// in parallel, the prediction on one thread).
AccuracySection MonteCarloSection(const MonteCarloStudy& study, int threads);

/// (c) accuracy_steady.{csv,svg}: per case and solver the iterations, time per voxel and error.
AccuracySection SteadySection(const SteadyStudy& study);

/// (e) accuracy_refine.{csv,svg}: per coarse size and tolerance the share of voxels refined, the
/// time against the full evaluation, the voxels whose coverage is wrong and the sigma_max errors.
AccuracySection RefineSection(const RefineStudy& study);
/// (f) accuracy_gate.{csv,svg}: per principal axis (major, middle, minor) the spread of the
/// measured / predicted variance over the sampled voxels and the share within its tolerance, the
/// eigenvector angles where resolvable, the share of voxels passing, the skew where the prediction
/// stops holding; the CSV per voxel; the plot measured against predicted sigma per axis.
AccuracySection GateSection(const GateStudy& study);

/// "# pandora accuracy: SCENE, rig RIG" and a blank line: the head of accuracy_tables.md.
std::string AccuracyTablesHeading(const std::string& scene_path, const std::string& rig);

/// One shadow-map size of the GPU renderer against the exact CPU renderer (pandora_gl_bench --csv).
struct GpuAccuracyRow {
  int map = 0;             ///< Texels per side of each camera's distance map.
  double gpu_ms = 0;       ///< Whole GPU frame, every map drawn.
  double eye_only_ms = 0;  ///< A frame that moves only the eye (maps kept).
  double cpu_ms = 0;       ///< The exact CPU renderer, same view.
  double differ_compared_pct =
      0;                      ///< Pixels whose camera sets differ, off the one-pixel edge band.
  double differ_all_pct = 0;  ///< ... over all pixels.
};

/// Reads pandora_gl_bench's CSV; InputError(file, "", ...) when a line is not six numbers.
std::vector<GpuAccuracyRow> ParseGpuAccuracyCsv(const std::string& text, const std::string& file);

/// (d) accuracy_gpu.{csv,svg}: per map size the share of pixels whose camera sets differ from the
/// exact renderer's against the GPU frame time, the CPU frame as the baseline; `device` names the
/// GL.
AccuracySection GpuSection(const std::vector<GpuAccuracyRow>& rows, const std::string& view_note);

}  // namespace pandora::report
