#pragma once
/// \file commands.h
/// The `pandora` subcommands. Each returns the process exit code; bad input throws InputError,
/// which main() prints as one line and turns into exit code 2.

#include <limits>
#include <string>
#include <vector>

namespace pandora::app {

/// A numeric option the user did not give.
inline const double kUnset = std::numeric_limits<double>::quiet_NaN();

/// Checks the value of a numeric command-line option: positive and finite, else InputError naming
/// the option. Returns `value`.
double CheckPositiveOption(const char* option, double value, const char* unit);

struct AnalyzeArgs {
  std::string scene;
  std::string rig;
  std::vector<std::string> disable;  ///< --disable: camera ids disabled for this run.
  std::string out = "out";
  double voxel_size = kUnset;        ///< kUnset: the scene's study.voxel_size.
  std::string fields;                ///< Comma-separated; empty: the scene's study.fields.
  double memory_budget_mb = kUnset;  ///< MiB; kUnset: the scene's study.memory_budget_mb.
  bool quiet = false;
  /// `--mpi`: one of the processes of `mpirun -n N pandora analyze ...` (docs/scale.md): each
  /// evaluates its partition of the blocks, rank 0 merges them and writes the outputs.
  bool mpi = false;
  /// `--stream`: evaluate and write the region tile by tile (whole columns of 8^3 blocks), each
  /// tile's fields written to fields/tile_NNNN.vdb and dropped before the next, so the peak memory
  /// is one tile's, within the budget (docs/scale.md). `tile_size`: the tiles' side in metres;
  /// kUnset: as few tiles as the memory budget allows.
  bool stream = false;
  double tile_size = kUnset;
};
int RunAnalyze(const AnalyzeArgs& args);
/// `pandora analyze --stream` (RunAnalyze calls it for --stream).
int RunStreamedAnalyze(const AnalyzeArgs& args);

struct BenchArgs {
  std::string scene;
  std::string rig;
  double voxel_size = kUnset;
  int repeat = 3;
  std::string json_out;
  /// `--render`: time the renderer instead of the fields (bench_render.cpp).
  bool render = false;
  std::string view;               ///< Named view; empty: the scene's first view.
  std::string size = "1280x720";  ///< Image size.
  /// `--incremental`: the time to update the fields after moving one camera, as a ratio to a
  /// full evaluation (bench_incremental.cpp).
  bool incremental = false;
  double move = 0.05;                ///< With --incremental: how far each camera moves, metres.
  double memory_budget_mb = kUnset;  ///< `--memory-budget`; kUnset: the scene's.
};
/// `pandora bench --render`: Render() against raw Embree loops over the very same primary rays
/// (rtcIntersect1) and occlusion segments (rtcOccluded packets and single rays), same run.
int RunRenderBench(const BenchArgs& args);
/// `pandora bench --incremental`: FieldEvaluator::Update after moving each camera in turn against a
/// full EvaluateFields, same run, interleaved.
int RunIncrementalBench(const BenchArgs& args);
int RunBench(const BenchArgs& args);

/// `pandora accuracy`: error against run time (issue 3, point 6) for (a) voxel size against the
/// coverage and uncertainty summaries of the finest size, (b) Monte Carlo trials against the
/// closed-form triangulation covariance, (c) the steady-state Riccati solvers against a long-double
/// reference. Writes accuracy_{voxel,montecarlo,steady}.{csv,svg} and accuracy_tables.md to `out`.
struct AccuracyArgs {
  std::string scene;
  std::string rig;
  std::vector<std::string> disable;  ///< --disable: camera ids disabled for this run.
  std::string out = "out/accuracy";
  bool quick = false;  ///< Fewer voxel sizes, trials and sample points (tests).
  /// Also the GPU renderer against the exact one per shadow-map size (runs pandora_gl_bench, beside
  /// this program; needs a display, e.g. under xvfb-run).
  bool gpu = false;
};
int RunAccuracy(const AccuracyArgs& args);

/// `pandora render`: the scene lit by the rig's cameras as projectors (render/render.h). One
/// viewpoint: a named view, --from/--at, or a camera's own eye (--camera ID).
struct RenderArgs {
  std::string scene;
  std::string rig;
  std::vector<std::string> disable;  ///< --disable: camera ids disabled for this run.
  std::string view;                  ///< Name in the scene's "views".
  /// `--plan` ("plan") or `--elevation SIDE` ("north", "south", "east", "west"): an orthographic
  /// proposal view of the scene's content, camera ids labelled (render/render.h PlanView).
  std::string plan;
  /// The plan's cut height or the elevation's section coordinate (metres); unset: the study
  /// region's face on the eye's side.
  double cut = kUnset;
  std::string from, at, up;  ///< "X,Y,Z" each.
  std::string camera;        ///< Camera id: render what that camera images.
  double fov = kUnset;       ///< Horizontal field of view, degrees.
  std::string size;          ///< "WxH"; empty: 1280x720, or the camera's resolution with --camera.
  std::string out = "render.png";
  std::string pattern = "uniform";   ///< uniform | grid
  std::string surface = "material";  ///< material | black | hidden-line | contours
  double brightness = kUnset;
  int grid = 32;
  int samples = 1;
  bool no_cameras = false;
  bool no_key = false;  ///< `--no-key`: no colour key (camera id -> colour) in the image.
  std::string fields;   ///< fields.vdb for the overlays.
  std::string slice;    ///< Field shown on a slice plane.
  std::string slice_axis = "z";
  double slice_at = kUnset;
  std::string iso;  ///< Field whose isosurface is drawn.
  double iso_value = kUnset;
  /// `--time-sample`: the scene at one of the study's time samples (docs/time.md): its number
  /// (1-based), its pose name or its label; empty: the scene as placed.
  std::string time_sample;
  /// `--ptz`: how PTZ cameras light the scene (docs/ptz.md): "single" (their current setting, as
  /// everywhere), "path" (home to current, one light per second, later darker), "all" (everything
  /// reachable from home within --ptz-time seconds, later seconds darker).
  std::string ptz = "single";
  double ptz_time = kUnset;  ///< `--ptz-time`: the budget of "all" (default: each head's trace_s).
  /// `--gpu`: drawn by the GPU renderer (pandora_gl_render beside this program, headless EGL
  /// without a display), with the agreement with the exact renderer printed (not --no-compare).
  bool gpu = false;
  bool no_compare = false;
  int shadow_map = 2048;  ///< `--shadow-map`: the GPU's shadow-map size per camera.
  bool quiet = false;
};
int RunRender(const RenderArgs& args);

/// `pandora export-surface`: the scene's surfaces sampled every `spacing` metres (area-weighted,
/// deterministic), each sample with coverage, resolution and sigma_max for `rig`, written as a
/// binary PLY point cloud (volume/surface.h, docs/report.md).
struct ExportSurfaceArgs {
  std::string scene;
  std::string rig;
  std::vector<std::string> disable;  ///< --disable: camera ids disabled for this run.
  double spacing = 0.02;  ///< Metres between samples (one per spacing^2 of area on average).
  std::string out;        ///< The .ply file.
  unsigned long long seed = 1;
  /// `--all-surfaces`: every triangle; default: only those whose front faces the study region or
  /// an enabled camera of the rig.
  bool all_surfaces = false;
  bool quiet = false;
};
int RunExportSurface(const ExportSurfaceArgs& args);

/// `pandora report`: one self-contained HTML file (DIR/report.html) with renders, field slices,
/// histograms, the camera table and the summary numbers, the rigs side by side (docs/report.md).
struct ReportArgs {
  std::string scene;
  std::vector<std::string> rigs;     ///< Names (each may be comma-separated); empty: every rig.
  std::vector<std::string> disable;  ///< --disable: camera ids disabled in every rig that has them.
  std::string out = "report";
  double voxel_size = kUnset;  ///< kUnset: the scene's study.voxel_size.
  int width = 640;             ///< Pixels across the renders from the named views.
  int camera_width = 320;      ///< Pixels across each camera's own view.
  double brightness = kUnset;  ///< Scale of every camera's light; kUnset: DefaultBrightness.
  bool quiet = false;
  /// --validate: the "Predicted against measured" section (`pandora validate` per rig, its
  /// defaults, --validate-poses board poses; docs/validation.md).
  bool validate = false;
  int validate_poses = 60;
};
int RunReport(const ReportArgs& args);
/// `pandora suggest` (issue 5): nudge the selected cameras within limits (docs/suggest.md); prints
/// the before/after table and writes the suggestion file. With `compare_baseline` also runs the
/// random local search with the same evaluation budget and writes CSV + SVG of objective against
/// time.
struct SuggestArgs {
  std::string scene;
  std::string rig;
  std::vector<std::string> disable;  ///< --disable: camera ids disabled for this run.
  std::string cameras;               ///< Comma-separated camera ids.
  std::string max_move = "0.3";      ///< Metres: one value, or one per selected camera (commas).
  std::string max_rotate = "10";     ///< Degrees: likewise.
  std::string objective = "coverage2";
  std::string weights;  ///< "wc,ws,wr" for the mix.
  /// Mounts (at most one per camera) and zoom ranges ("MIN,MAX" degrees): each entry applies to all
  /// selected cameras, or to one with an "ID:" prefix.
  std::vector<std::string> rail, plane, mount_box, hfov_range;
  std::vector<std::string> keep_out;  ///< Boxes "x0,y0,z0,x1,y1,z1".
  std::vector<std::string> target_surfaces;
  bool with_region = false;  ///< Region points as well as surface points.
  /// `--over-time`: the targets are the study's surface targets at every time sample (each point
  /// tested against its sample's scene); docs/time.md.
  bool over_time = false;
  int points = 1500;
  double snap_move = 0, snap_rotate = 0;
  double clearance = 0.1;  ///< Metres from every scene surface (`--clearance`).
  int outer_iterations = 4;
  std::string out = "suggestion.json";
  std::string perturb;           ///< "MOVE,DEG": benchmark from perturbed poses.
  std::string compare_baseline;  ///< Output folder for the baseline comparison.
  unsigned long long seed = 1;
  bool quiet = false;
  /// PTZ controller suggestions (docs/ptz.md): "ID:PRESET" (the preset's best setting for the
  /// targets) or "ID" (the tour order with the shortest longest gap); --target-region names one of
  /// the study's regions for the target points.
  std::string ptz_preset, ptz_tour, target_region;
  std::string tour_objective = "mean";  ///< --tour-objective: mean or max (suggest/ptz_suggest.h).
};
int RunSuggest(const SuggestArgs& args);
/// The PTZ part of `pandora suggest` (app/suggest_ptz_command.cpp).
int RunSuggestPtz(const SuggestArgs& args);

/// `pandora rig`: a generated rig written into the scene file (docs/rig-generators.md).
struct RigArgs {
  std::string scene;
  std::string name;
  bool replace = false;
  std::string ring, grid, wall_grid, along;  ///< The layout: exactly one.
  std::string center, rect, wall, z_range, aim, prefix;
  double radius = std::numeric_limits<double>::quiet_NaN();
  double height = std::numeric_limits<double>::quiet_NaN();
  double start_deg = 0, inset = 0.1, hfov_deg = 60;
  int count = 0;
  std::string resolution = "1920x1080";
  bool dry_run = false;
  bool quiet = false;
  bool add = false;              ///< --add: append to the rig of that name (created when absent).
  std::string catalogue, model;  ///< --catalogue F --model NAME: the cameras' lens.
  std::string ptz;               ///< --ptz WIDEST,NARROWEST: PTZ heads.
};
int RunRig(const RigArgs& args);

/// `pandora accept`: writes the suggested poses into the scene file (backup first).
struct AcceptArgs {
  std::string suggestion;
  std::string cameras;  ///< Comma-separated ids; empty: all.
  bool force = false;
  bool quiet = false;
  /// A proposals file (`pandora propose`): which proposal (1-based) to add as a rig, and its name
  /// (default: the proposal's).
  int proposal = 0;
  std::string name;
};
int RunAccept(const AcceptArgs& args);
/// `pandora accept PROPOSALS --proposal N [--name NAME]`: adds proposal N as a rig to the scene the
/// proposals were made for (lock, hash check unless `force`, backup; app/propose_command.cpp).
int AcceptProposal(const std::string& file, int number, const std::string& name, bool force,
                   bool quiet);

}  // namespace pandora::app

namespace pandora::app {

/// `pandora export-rig`: the rig as OpenCV YAML, a COLMAP text model (a folder), glTF (meshes and
/// cameras) or an installation sheet (CSV); analysis/rig/rig_formats.h, docs/tool-chain.md.
struct ExportRigArgs {
  std::string scene;
  std::string rig;
  std::string format;  ///< opencv | colmap | gltf | sheet
  std::string out;     ///< A file; a folder for colmap.
  bool quiet = false;
};
int RunExportRig(const ExportRigArgs& args);

/// `pandora import-rig`: a calibrated rig (OpenCV YAML or a COLMAP text model) into the scene file
/// with a backup, compared with the design (analysis/rig/rig_import.h).
struct ImportRigArgs {
  std::string scene;
  std::string format;  ///< opencv | colmap
  std::string from;
  std::string rig;
  std::string as;
  bool quiet = false;
};
int RunImportRig(const ImportRigArgs& args);

}  // namespace pandora::app
