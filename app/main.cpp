// The `pandora` command: analyze a camera rig in a scene, benchmark the field evaluation, tabulate
// error against run time.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <cstdio>
#include <memory>

#include "analysis/error.h"
#include "app/commands.h"

#ifndef PANDORA_VERSION
#define PANDORA_VERSION "dev"
#endif

int main(int argc, char** argv) {
  using namespace pandora::app;
  CLI::App app{"Pandora: design multi-camera setups (coverage, resolution and uncertainty fields)"};
  app.set_version_flag("--version", PANDORA_VERSION);
  app.require_subcommand(1);
  int threads = 0;
  app.add_option("--threads", threads, "Worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);

  AnalyzeArgs analyze;
  CLI::App* a = app.add_subcommand("analyze", "Evaluate fields over the study region; write fields.vdb and summary.json");
  a->add_option("scene", analyze.scene, "Scene file (JSON)")->required();
  a->add_option("--rig", analyze.rig, "Rig name (default: the first rig)");
  a->add_option("--out", analyze.out, "Output folder")->capture_default_str();
  a->add_option("--voxel-size", analyze.voxel_size, "Voxel size in metres (default: study.voxel_size)");
  a->add_option("--fields", analyze.fields, "Comma-separated fields (default: study.fields)");
  a->add_option("--memory-budget", analyze.memory_budget_mb, "Memory budget in MiB (default: study.memory_budget_mb)");
  a->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  a->add_flag("--quiet,-q", analyze.quiet, "Print nothing but errors");

  BenchArgs bench;
  CLI::App* b = app.add_subcommand("bench", "Time field evaluation against a raw Embree loop over the same rays");
  b->add_option("scene", bench.scene, "Scene file (JSON)")->required();
  b->add_option("--rig", bench.rig, "Rig name (default: the first rig)");
  b->add_option("--voxel-size", bench.voxel_size, "Voxel size in metres (default: study.voxel_size)");
  b->add_option("--repeat", bench.repeat, "Timed repetitions (the best is reported)")->check(CLI::PositiveNumber);
  b->add_option("--json", bench.json_out, "Also write the results to this JSON file");
  b->add_flag("--render", bench.render,
              "Time `pandora render` (1280x720) against raw Embree loops over the same primary and shadow rays");
  b->add_option("--view", bench.view, "With --render: the named view (default: the scene's first view)");
  b->add_option("--size", bench.size, "With --render: image size WxH")->capture_default_str();
  b->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);

  AccuracyArgs accuracy;
  CLI::App* acc = app.add_subcommand(
      "accuracy", "Error against run time: voxel size, Monte Carlo trials, steady-state solvers");
  acc->add_option("scene", accuracy.scene, "Scene file (JSON)")->required();
  acc->add_option("--rig", accuracy.rig, "Rig name (default: the first rig)");
  acc->add_option("--out", accuracy.out, "Output folder")->capture_default_str();
  acc->add_flag("--quick", accuracy.quick, "Fewer voxel sizes, trials and sample points (for tests)");
  acc->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);

  RenderArgs render;
  CLI::App* rn = app.add_subcommand(
      "render", "Render the scene lit by every enabled camera as a projector of its own colour (PNG or EXR)");
  rn->add_option("scene", render.scene, "Scene file (JSON)")->required();
  rn->add_option("--rig", render.rig, "Rig name (default: the first rig)");
  rn->add_option("--view", render.view, "Named view from the scene's \"views\"");
  rn->add_option("--from", render.from, "Eye position X,Y,Z (with --at)");
  rn->add_option("--at", render.at, "Point looked at X,Y,Z (with --from)");
  rn->add_option("--up", render.up, "Up direction X,Y,Z (default 0,0,1)");
  rn->add_option("--camera", render.camera, "Render what this camera (id) images, distortion included");
  rn->add_option("--fov", render.fov, "Horizontal field of view in degrees (default: the view's, else 60)");
  rn->add_option("--size", render.size, "Image size WxH (default 1280x720; the camera's with --camera)");
  rn->add_option("--out", render.out, "Output image: FILE.png or FILE.exr")->capture_default_str();
  rn->add_option("--pattern", render.pattern, "uniform | grid (each camera's pixel grid)")->capture_default_str();
  rn->add_option("--grid", render.grid, "Grid pattern: a line every N camera pixels")->capture_default_str();
  rn->add_option("--surface", render.surface, "material | black | hidden-line | contours")->capture_default_str();
  rn->add_option("--brightness", render.brightness, "Scale of every camera's light (default min(1, 3 / enabled cameras))");
  rn->add_option("--samples", render.samples, "Samples per pixel per axis (antialiasing)")->capture_default_str();
  rn->add_flag("--no-cameras", render.no_cameras, "Do not draw the camera bodies and frusta");
  rn->add_flag("--no-key", render.no_key, "Do not draw the colour key (camera id -> colour)");
  rn->add_option("--fields", render.fields, "fields.vdb from `pandora analyze`, for --slice and --iso");
  rn->add_option("--slice", render.slice, "Show this field on a slice plane (viridis, with a legend)");
  rn->add_option("--slice-axis", render.slice_axis, "x | y | z: the slice plane's normal")->capture_default_str();
  rn->add_option("--slice-at", render.slice_at, "Slice position along its axis in metres (default: the middle)");
  rn->add_option("--iso", render.iso, "Draw the isosurface of this field");
  rn->add_option("--iso-value", render.iso_value, "Iso value (default 1.5: coverage >= 2)");
  rn->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  rn->add_flag("--quiet,-q", render.quiet, "Print nothing but errors");

  ExportSurfaceArgs surface;
  CLI::App* es = app.add_subcommand(
      "export-surface", "Sample the scene's surfaces; write coverage, resolution and sigma_max per sample as PLY");
  es->add_option("scene", surface.scene, "Scene file (JSON)")->required();
  es->add_option("--rig", surface.rig, "Rig name (default: the first rig)");
  es->add_option("--spacing", surface.spacing, "Distance between samples in metres")->capture_default_str();
  es->add_option("--out", surface.out, "Output PLY file")->required();
  es->add_option("--seed", surface.seed, "Seed of the sample positions")->capture_default_str();
  es->add_flag("--all-surfaces", surface.all_surfaces, "Sample every surface, also those facing away from the study region and every camera");
  es->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  es->add_flag("--quiet,-q", surface.quiet, "Print nothing but errors");

  ReportArgs report;
  CLI::App* rep = app.add_subcommand(
      "report", "One self-contained HTML report: renders, field slices, histograms, cameras, rigs side by side");
  rep->add_option("scene", report.scene, "Scene file (JSON)")->required();
  rep->add_option("--rig", report.rigs, "Rig name(s), repeatable or comma-separated (default: every rig)");
  rep->add_option("--out", report.out, "Output folder (report.html is written there)")->capture_default_str();
  rep->add_option("--voxel-size", report.voxel_size, "Voxel size in metres (default: study.voxel_size)");
  rep->add_option("--width", report.width, "Width in pixels of the renders from the named views")
      ->capture_default_str();
  rep->add_option("--camera-width", report.camera_width, "Width in pixels of each camera's own view")
      ->capture_default_str();
  rep->add_option("--brightness", report.brightness, "Scale of every camera's light in the renders (default min(1, 3 / enabled cameras))");
  rep->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  rep->add_flag("--quiet,-q", report.quiet, "Print nothing but errors");
  SuggestArgs suggest;
  CLI::App* sg = app.add_subcommand(
      "suggest", "Nudge the selected cameras within limits to improve an objective; write a suggestion");
  sg->add_option("scene", suggest.scene, "Scene file (JSON)")->required();
  sg->add_option("--rig", suggest.rig, "Rig name (default: the first rig)");
  sg->add_option("--cameras", suggest.cameras, "Comma-separated ids of the cameras that may move")->required();
  sg->add_option("--max-move", suggest.max_move, "Largest move, metres: one value, or one per camera in --cameras order")->capture_default_str();
  sg->add_option("--max-rotate", suggest.max_rotate, "Largest rotation, degrees: one value, or one per camera")->capture_default_str();
  sg->add_option("--objective", suggest.objective,
                 "coverage2 (coverageK), sigma-mean, sigma-p90 (sigma-pNN), resolution, mix")->capture_default_str();
  sg->add_option("--weights", suggest.weights, "Mix weights WC,WS,WR (coverage, sigma, resolution)");
  sg->add_option("--rail", suggest.rail, "Mount: stay on the line through the camera along [ID:]DX,DY,DZ (repeatable)");
  sg->add_option("--plane", suggest.plane, "Mount: stay on the plane through the camera with normal [ID:]NX,NY,NZ (repeatable)");
  sg->add_option("--mount-box", suggest.mount_box, "Mount: stay inside [ID:]XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX, metres in the world frame (repeatable)");
  sg->add_option("--hfov-range", suggest.hfov_range, "Zoom: the horizontal FOV may change within [ID:]MIN,MAX degrees (repeatable)");
  sg->add_option("--keep-out", suggest.keep_out, "Box XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (metres, world frame) no camera centre may enter (repeatable)");
  sg->add_option("--clearance", suggest.clearance, "Keep every suggested camera centre this far from every scene surface, metres (a camera already closer never moves closer)")->capture_default_str();
  sg->add_option("--target-surface", suggest.target_surfaces, "Object whose surface is the target (repeatable)");
  sg->add_flag("--with-region", suggest.with_region, "With --target-surface: region points as well");
  sg->add_option("--points", suggest.points, "Target points")->capture_default_str();
  sg->add_option("--snap-move", suggest.snap_move, "Round moves to multiples of this, metres (0: off)");
  sg->add_option("--snap-rotate", suggest.snap_rotate, "Round yaw/pitch/roll changes to multiples of this, degrees");
  sg->add_option("--outer", suggest.outer_iterations, "Outer iterations (occlusion re-evaluated between)")
      ->check(CLI::PositiveNumber);
  sg->add_option("--out", suggest.out, "Suggestion file")->capture_default_str();
  sg->add_option("--perturb", suggest.perturb, "Benchmark: first move and rotate the selected cameras by MOVE,DEG");
  sg->add_option("--compare-baseline", suggest.compare_baseline,
                 "Also run random local search with the same budget; write CSV and SVG to this folder");
  sg->add_option("--seed", suggest.seed, "Seed for target points and perturbations")->capture_default_str();
  sg->add_option("--threads", threads, "Worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
  sg->add_flag("--quiet,-q", suggest.quiet, "Print nothing but errors");

  AcceptArgs accept;
  CLI::App* ac = app.add_subcommand("accept", "Write a suggestion's poses into the scene file (keeps a backup)");
  ac->add_option("suggestion", accept.suggestion, "Suggestion file from pandora suggest")->required();
  ac->add_option("--cameras", accept.cameras, "Comma-separated ids to accept (default: all)");
  ac->add_flag("--force", accept.force, "Accept even if the scene file changed since");
  ac->add_flag("--quiet,-q", accept.quiet, "Print nothing but errors");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  static_cast<std::size_t>(threads));
  try {
    if (*a) return RunAnalyze(analyze);
    if (*b) return RunBench(bench);
    if (*acc) return RunAccuracy(accuracy);
    if (*rn) return RunRender(render);
    if (*es) return RunExportSurface(surface);
    if (*rep) return RunReport(report);
    if (*sg) return RunSuggest(suggest);
    if (*ac) return RunAccept(accept);
  } catch (const pandora::InputError& e) {
    std::fprintf(stderr, "pandora: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pandora: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
