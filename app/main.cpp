// The `pandora` command: analyze a camera rig in a scene, benchmark the field evaluation, tabulate
// error against run time.
#include <tbb/global_control.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "app/commands.h"
#include "app/flags.h"
#include "app/mpi_session.h"

#ifndef PANDORA_VERSION
#define PANDORA_VERSION "dev"
#endif

namespace {

std::string Short(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

// A strict number option: the whole text is a finite number (no "nan", "inf", empty text or
// trailing characters), a whole number when `whole`, within [min, max] (min excluded when
// `min_exclusive`). The message names the unit; CLI11 prefixes the option's name.
CLI::Validator Number(double min, double max, const std::string& unit, bool whole = false,
                      bool min_exclusive = false, bool max_exclusive = false) {
  const std::string kind = whole ? "a whole number" : "a number";
  std::string range;
  if (std::isinf(min) && std::isinf(max))
    range = "finite";
  else if (std::isinf(max))
    range = min_exclusive ? "greater than " + Short(min) : "at least " + Short(min);
  else if (std::isinf(min))
    range = max_exclusive ? "less than " + Short(max) : "at most " + Short(max);
  else
    range = std::string("in ") + (min_exclusive ? "(" : "[") + Short(min) + ", " + Short(max) +
            (max_exclusive ? ")" : "]");
  const std::string expected = "must be " + kind + " of " + unit + ", " + range;
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const char* begin = text.c_str();
        char* end = nullptr;
        errno = 0;
        const double v =
            whole ? static_cast<double>(std::strtoll(begin, &end, 10)) : std::strtod(begin, &end);
        if (text.empty() || end == begin || *end != '\0') return expected + ", got '" + text + "'";
        if (errno == ERANGE || !std::isfinite(v)) return expected + ", got " + text;
        if (v < min || v > max || (min_exclusive && v == min) || (max_exclusive && v == max))
          return expected + ", got " + text;
        return "";
      },
      "", "number");
}

// Every option that takes a value refuses an empty one ("--rig ''" is not "the default rig").
void RefuseEmptyValues(CLI::App* app) {
  for (CLI::Option* option : app->get_options()) {
    if (option->get_type_size() == 0) continue;  // a flag
    option->check(CLI::Validator(
        [](std::string& text) -> std::string {
          return text.empty() ? std::string(
                                    "the value is empty (an empty value is not the default; leave "
                                    "the option out)")
                              : std::string();
        },
        "", "non-empty"));
  }
  for (CLI::App* sub : app->get_subcommands({})) RefuseEmptyValues(sub);
}

// A parse error in Pandora's one-line format: what the parser found, and where to read more.
int ReportParseError(const CLI::App& app, const CLI::ParseError& e) {
  std::string message = e.what();
  for (char& c : message)
    if (c == '\n') c = ' ';
  std::string command;
  for (const CLI::App* sub : app.get_subcommands()) command = sub->get_name();
  std::string hint =
      "pandora " + (command.empty() ? std::string() : command + " ") + "--help lists the options";
  // An unknown command: CLI11 calls it an extra argument.
  const bool stray_word = command.empty() && !app.remaining().empty() &&
                          (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr ||
                           dynamic_cast<const CLI::RequiredError*>(&e) != nullptr);
  if (stray_word) {
    std::vector<std::string> names;
    for (const CLI::App* sub : app.get_subcommands({})) names.push_back(sub->get_name());
    const std::string word = app.remaining().empty() ? std::string() : app.remaining().front();
    std::string list, closest;
    std::size_t best = 3;  // suggest a command at most two edits away
    for (const std::string& n : names) {
      list += (list.empty() ? "" : ", ") + n;
      const std::size_t d = pandora::EditDistance(word, n);
      if (d < best) best = d, closest = n;
    }
    const std::string hint = closest.empty()
                                 ? "the commands are " + list
                                 : "did you mean '" + closest + "'? the commands are " + list;
    std::fprintf(stderr, "pandora: error: unknown command '%s' (hint: %s)\n", word.c_str(),
                 hint.c_str());
    return 2;
  }
  if (command.empty() && dynamic_cast<const CLI::RequiredError*>(&e) != nullptr &&
      app.remaining().empty()) {
    std::fprintf(stderr, "pandora: error: no command given (hint: pandora --help lists them)\n");
    return 2;
  }
  std::fprintf(stderr, "pandora: error: %s (hint: %s)\n", message.c_str(), hint.c_str());
  return 2;
}

// Replaces this process with pandora-view (beside this program) for `pandora view` and
// `pandora bench --viewer`; returns 2 when it cannot be started.
int ExecViewer(int argc, char** argv, bool viewer_bench) {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::string viewer = (self.parent_path() / "pandora-view").string();
  std::vector<std::string> kept;
  std::string frames = "20";
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (viewer_bench && arg == "--viewer") continue;
    if (viewer_bench && arg == "--repeat" && i + 1 < argc) {
      frames = argv[++i];
      continue;
    }
    kept.push_back(arg);
  }
  if (viewer_bench) kept.insert(kept.end(), {"--bench", frames, "--no-autosave"});
  std::vector<char*> args{const_cast<char*>(viewer.c_str())};
  for (std::string& k : kept) args.push_back(k.data());
  args.push_back(nullptr);
  execv(viewer.c_str(), args.data());
  std::fprintf(
      stderr,
      "pandora: error: cannot start the viewer %s: %s (hint: build the pandora-view target)\n",
      viewer.c_str(), std::strerror(errno));
  return 2;
}

// Registers `pandora analyze` and its options.
CLI::App* AddAnalyzeCommand(CLI::App& app, pandora::app::AnalyzeArgs& analyze, int& threads,
                            const CLI::Validator& threads_check) {
  CLI::App* a = app.add_subcommand(
      "analyze", "Evaluate fields over the study region; write fields.vdb and summary.json");
  a->add_option("scene", analyze.scene, "Scene file (JSON)")->required();
  a->add_option("--rig", analyze.rig, "Rig name (default: the first rig)");
  a->add_option("--disable", analyze.disable,
                "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                "loses when they fail)")
      ->delimiter(',');
  a->add_option("--out", analyze.out, "Output folder")->capture_default_str();
  a->add_option("--voxel-size", analyze.voxel_size,
                "Voxel size in metres (default: study.voxel_size)")
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  a->add_option("--fields", analyze.fields, "Comma-separated fields (default: study.fields)");
  a->add_option("--memory-budget", analyze.memory_budget_mb,
                "Memory budget in MiB (default: study.memory_budget_mb)")
      ->check(Number(0, HUGE_VAL, "MiB", false, true));
  a->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  a->add_flag("--quiet,-q", analyze.quiet, "Print nothing but errors");
  a->add_flag("--mpi", analyze.mpi,
              "Under mpirun: split the blocks over the processes; rank 0 writes (docs/scale.md)");
  a->add_flag("--stream", analyze.stream,
              "Evaluate and write the region tile by tile within the memory budget: "
              "fields/tile_NNNN.vdb (docs/scale.md)");
  a->add_option(
       "--tile-size", analyze.tile_size,
       "With --stream: the tiles' side in metres (default: as few tiles as the budget allows)")
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  return a;
}

// Registers `pandora bench` and its options (`viewer_flag`: --viewer, which main handles).
CLI::App* AddBenchCommand(CLI::App& app, pandora::app::BenchArgs& bench, bool& viewer_flag,
                          int& threads, const CLI::Validator& threads_check) {
  CLI::App* b = app.add_subcommand(
      "bench", "Time field evaluation against a raw Embree loop over the same rays");
  b->add_option("scene", bench.scene, "Scene file (JSON)")->required();
  b->add_option("--rig", bench.rig, "Rig name (default: the first rig)");
  b->add_option("--voxel-size", bench.voxel_size,
                "Voxel size in metres (default: study.voxel_size)")
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  b->add_option("--repeat", bench.repeat, "Timed repetitions (the best is reported)")
      ->check(Number(1, 1000, "repetitions", true));
  b->add_option("--json", bench.json_out, "Also write the results to this JSON file");
  b->add_flag("--render", bench.render,
              "Time `pandora render` (1280x720) against raw Embree loops over the same primary and "
              "shadow rays");
  b->add_option("--view", bench.view,
                "With --render: the named view (default: the scene's first view)");
  b->add_option("--size", bench.size, "With --render: image size WxH")->capture_default_str();
  b->add_flag("--viewer", viewer_flag,
              "Frame rates of `pandora view` (navigating, all cameras moving) against the exact "
              "CPU renderer");
  b->add_flag("--incremental", bench.incremental,
              "Time the field update after moving one camera against a full evaluation");
  b->add_option("--move", bench.move, "With --incremental: how far each camera moves, metres")
      ->check(Number(0, HUGE_VAL, "metres", false, true))
      ->capture_default_str();
  b->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  return b;
}

// Registers `pandora accuracy` and its options.
CLI::App* AddAccuracyCommand(CLI::App& app, pandora::app::AccuracyArgs& accuracy, int& threads,
                             const CLI::Validator& threads_check) {
  CLI::App* acc = app.add_subcommand("accuracy",
                                     "Error against run time: voxel size, Monte Carlo trials, "
                                     "steady-state solvers, coarse-to-fine");
  acc->add_option("scene", accuracy.scene, "Scene file (JSON)")->required();
  acc->add_option("--rig", accuracy.rig, "Rig name (default: the first rig)");
  acc->add_option("--disable", accuracy.disable,
                  "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                  "loses when they fail)")
      ->delimiter(',');
  acc->add_option("--out", accuracy.out, "Output folder")->capture_default_str();
  acc->add_flag("--quick", accuracy.quick,
                "Fewer voxel sizes, trials and sample points (for tests)");
  acc->add_flag("--gpu", accuracy.gpu,
                "Also the GPU renderer of pandora view against the exact one per shadow-map size "
                "(needs a display)");
  acc->add_option("--threads", threads, "Worker threads (default: all cores)")
      ->check(threads_check);
  return acc;
}

// Registers `pandora render` and its options.
CLI::App* AddRenderCommand(CLI::App& app, pandora::app::RenderArgs& render, int& threads,
                           const CLI::Validator& threads_check) {
  CLI::App* rn = app.add_subcommand(
      "render",
      "Render the scene lit by every enabled camera as a projector of its own colour (PNG or EXR)");
  rn->add_option("scene", render.scene, "Scene file (JSON)")->required();
  rn->add_option("--rig", render.rig, "Rig name (default: the first rig)");
  rn->add_option("--disable", render.disable,
                 "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                 "loses when they fail)")
      ->delimiter(',');
  rn->add_option("--view", render.view, "Named view from the scene's \"views\"");
  rn->add_flag_callback(
      "--plan", [&render]() { render.plan = "plan"; },
      "A plan of the scene from above (orthographic, north up, camera ids labelled)");
  rn->add_option(
      "--elevation", render.plan,
      "An elevation from SIDE: north, south, east or west (orthographic, camera ids labelled)");
  rn->add_option("--cut", render.cut,
                 "With --plan: the cut height; with --elevation: the section's coordinate (metres; "
                 "default: the study region's face on that side)");
  rn->add_option("--from", render.from, "Eye position X,Y,Z (with --at)");
  rn->add_option("--at", render.at, "Point looked at X,Y,Z (with --from)");
  rn->add_option("--up", render.up, "Up direction X,Y,Z (default 0,0,1)");
  rn->add_option("--camera", render.camera,
                 "Render what this camera (id) images, distortion included");
  rn->add_option("--time-sample", render.time_sample,
                 "The scene at one of the study's time samples: its number, pose name or label "
                 "(docs/time.md)");
  rn->add_option(
        "--ptz", render.ptz,
        "PTZ traces: single (current setting), path (home to current, one per second), all "
        "(reachable within --ptz-time)")
      ->capture_default_str();
  rn->add_option("--ptz-time", render.ptz_time,
                 "Time budget of --ptz all, seconds (default: the head's trace_s)")
      ->check(Number(0, 1e6, "seconds", false, true, true));
  rn->add_option("--fov", render.fov,
                 "Horizontal field of view in degrees (default: the view's, else 60)")
      ->check(Number(0, 180, "degrees", false, true, true));
  rn->add_option("--size", render.size,
                 "Image size WxH (default 1280x720; the camera's with --camera)");
  rn->add_option("--out", render.out, "Output image: FILE.png or FILE.exr")->capture_default_str();
  rn->add_option("--pattern", render.pattern, "uniform | grid (each camera's pixel grid)")
      ->capture_default_str();
  rn->add_option("--grid", render.grid, "Grid pattern: a line every N camera pixels")
      ->capture_default_str()
      ->check(Number(1, 100000, "camera pixels", true));
  rn->add_option("--surface", render.surface, "material | black | hidden-line | contours")
      ->capture_default_str();
  rn->add_option("--brightness", render.brightness,
                 "Scale of every camera's light (default min(1, 3 / enabled cameras))")
      ->check(Number(0, 1e6, "times one camera's light", false, true));
  rn->add_option("--samples", render.samples, "Samples per pixel per axis (antialiasing)")
      ->capture_default_str()
      ->check(Number(1, 16, "samples per pixel per axis", true));
  rn->add_flag("--no-cameras", render.no_cameras, "Do not draw the camera bodies and frusta");
  rn->add_flag("--no-key", render.no_key, "Do not draw the colour key (camera id -> colour)");
  rn->add_option("--fields", render.fields,
                 "fields.vdb from `pandora analyze`, for --slice and --iso");
  rn->add_option("--slice", render.slice,
                 "Show this field on a slice plane (viridis, with a legend)");
  rn->add_option("--slice-axis", render.slice_axis, "x | y | z: the slice plane's normal")
      ->capture_default_str();
  rn->add_option("--slice-at", render.slice_at,
                 "Slice position along its axis in metres (default: the middle)")
      ->check(Number(-HUGE_VAL, HUGE_VAL, "metres"));
  rn->add_option("--iso", render.iso, "Draw the isosurface of this field");
  rn->add_option("--iso-value", render.iso_value, "Iso value (default 1.5: coverage >= 2)")
      ->check(Number(-HUGE_VAL, HUGE_VAL, "the field's unit"));
  rn->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  rn->add_flag("--quiet,-q", render.quiet, "Print nothing but errors");
  return rn;
}

// Registers `pandora export-surface` and its options.
CLI::App* AddExportSurfaceCommand(CLI::App& app, pandora::app::ExportSurfaceArgs& surface,
                                  int& threads, const CLI::Validator& threads_check) {
  CLI::App* es = app.add_subcommand(
      "export-surface",
      "Sample the scene's surfaces; write coverage, resolution and sigma_max per sample as PLY");
  es->add_option("scene", surface.scene, "Scene file (JSON)")->required();
  es->add_option("--rig", surface.rig, "Rig name (default: the first rig)");
  es->add_option("--disable", surface.disable,
                 "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                 "loses when they fail)")
      ->delimiter(',');
  es->add_option("--spacing", surface.spacing, "Distance between samples in metres")
      ->capture_default_str()
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  es->add_option("--out", surface.out, "Output PLY file")->required();
  es->add_option("--seed", surface.seed, "Seed of the sample positions")
      ->capture_default_str()
      ->check(Number(0, 9.2e18, "(any whole number)", true));
  es->add_flag(
      "--all-surfaces", surface.all_surfaces,
      "Sample every surface, also those facing away from the study region and every camera");
  es->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  es->add_flag("--quiet,-q", surface.quiet, "Print nothing but errors");
  return es;
}

// Registers `pandora export-rig` and its options.
CLI::App* AddExportRigCommand(CLI::App& app, pandora::app::ExportRigArgs& export_rig) {
  CLI::App* er = app.add_subcommand("export-rig",
                                    "Write the rig as OpenCV YAML, a COLMAP text model, glTF "
                                    "(meshes + cameras) or an installation sheet (CSV)");
  er->add_option("scene", export_rig.scene, "Scene file (JSON)")->required();
  er->add_option("--rig", export_rig.rig, "Rig name (default: the first rig)");
  er->add_option("--format", export_rig.format, "opencv | colmap | gltf | sheet")->required();
  er->add_option("--out", export_rig.out, "Output file (a folder for colmap)")->required();
  er->add_flag("--quiet,-q", export_rig.quiet, "Print nothing but errors");
  return er;
}

// Registers `pandora import-rig` and its options (`import_from`: the two values of --from).
CLI::App* AddImportRigCommand(CLI::App& app, pandora::app::ImportRigArgs& import_rig,
                              std::vector<std::string>& import_from) {
  CLI::App* ir =
      app.add_subcommand("import-rig",
                         "Write a calibrated rig (OpenCV YAML or COLMAP text model) into the scene "
                         "file (keeps a backup) and compare it with the design");
  ir->add_option("scene", import_rig.scene, "Scene file (JSON), rewritten")->required();
  ir->add_option("--from", import_from, "FORMAT PATH: opencv FILE.yml or colmap FOLDER")
      ->required()
      ->expected(2);
  ir->add_option("--rig", import_rig.rig,
                 "The design rig: replaced by id, or compared with when --as is given")
      ->required();
  ir->add_option("--as", import_rig.as, "Write a new rig of this name instead");
  ir->add_flag("--quiet,-q", import_rig.quiet, "Print nothing but errors");
  return ir;
}

// Registers `pandora report` and its options.
CLI::App* AddReportCommand(CLI::App& app, pandora::app::ReportArgs& report, int& threads,
                           const CLI::Validator& threads_check) {
  CLI::App* rep = app.add_subcommand("report",
                                     "One self-contained HTML report: renders, field slices, "
                                     "histograms, cameras, rigs side by side");
  rep->add_option("scene", report.scene, "Scene file (JSON)")->required();
  rep->add_option("--rig", report.rigs,
                  "Rig name(s), repeatable or comma-separated (default: every rig)");
  rep->add_option("--disable", report.disable,
                  "Camera ids to disable in every rig of the report that has them, comma-separated "
                  "or repeated")
      ->delimiter(',');
  rep->add_option("--out", report.out, "Output folder (report.html is written there)")
      ->capture_default_str();
  rep->add_option("--voxel-size", report.voxel_size,
                  "Voxel size in metres (default: study.voxel_size)")
      ->check(Number(0, HUGE_VAL, "metres", false, true));
  rep->add_option("--width", report.width, "Width in pixels of the renders from the named views")
      ->capture_default_str()
      ->check(Number(16, 8192, "pixels", true));
  rep->add_option("--camera-width", report.camera_width,
                  "Width in pixels of each camera's own view")
      ->capture_default_str()
      ->check(Number(16, 8192, "pixels", true));
  rep->add_option(
         "--brightness", report.brightness,
         "Scale of every camera's light in the renders (default min(1, 3 / enabled cameras))")
      ->check(Number(0, 1e6, "times one camera's light", false, true));
  rep->add_option("--threads", threads, "Worker threads (default: all cores)")
      ->check(threads_check);
  rep->add_flag("--quiet,-q", report.quiet, "Print nothing but errors");
  return rep;
}

// Registers `pandora rig` and its options.
CLI::App* AddRigCommand(CLI::App& app, pandora::app::RigArgs& rig_args) {
  CLI::App* rg = app.add_subcommand("rig",
                                    "Generate a rig (ring, ceiling or wall grid, cameras along "
                                    "walls) and write it into the scene file (keeps a backup)");
  rg->add_option("scene", rig_args.scene, "Scene file (JSON)")->required();
  rg->add_option("--name", rig_args.name, "Name of the new rig")->required();
  rg->add_flag("--replace", rig_args.replace, "Overwrite the rig of that name");
  rg->add_option(
      "--ring", rig_args.ring,
      "Layout: N cameras on a horizontal circle (--radius, --height, --center X,Y,Z, --start-deg)");
  rg->add_option("--grid", rig_args.grid,
                 "Layout: NX,NY cameras over a ceiling rectangle (--rect X0,Y0,X1,Y1, --height), "
                 "looking down unless --aim");
  rg->add_option(
      "--wall-grid", rig_args.wall_grid,
      "Layout: NU,NZ cameras over a wall (--wall X0,Y0,X1,Y1, --z-range Z0,Z1, --inset)");
  rg->add_option(
      "--along", rig_args.along,
      "Layout: --count cameras evenly along walls X0,Y0,X1,Y1[,X2,Y2...] (--height, --inset)");
  rg->add_option("--count", rig_args.count, "With --along: how many cameras");
  rg->add_option("--radius", rig_args.radius, "Ring radius, metres");
  rg->add_option("--height", rig_args.height, "Camera height, metres");
  rg->add_option("--center", rig_args.center, "Ring centre X,Y (default: the region's centre)");
  rg->add_option("--start-deg", rig_args.start_deg,
                 "Ring: the first camera's angle from +x, degrees");
  rg->add_option("--rect", rig_args.rect, "Ceiling grid rectangle X0,Y0,X1,Y1, metres");
  rg->add_option("--wall", rig_args.wall, "Wall grid: the wall segment X0,Y0,X1,Y1, metres");
  rg->add_option("--z-range", rig_args.z_range, "Wall grid: heights Z0,Z1, metres");
  rg->add_option("--inset", rig_args.inset, "Distance in from the wall, metres")
      ->capture_default_str();
  rg->add_option("--aim", rig_args.aim,
                 "Point every camera looks at X,Y,Z (default: the region's centre)");
  rg->add_option("--resolution", rig_args.resolution, "Image size WxH")->capture_default_str();
  rg->add_option("--hfov", rig_args.hfov_deg, "Horizontal field of view, degrees")
      ->capture_default_str();
  rg->add_option("--prefix", rig_args.prefix, "Camera id prefix (default: the rig's name and _)");
  rg->add_flag("--dry-run", rig_args.dry_run, "Print the new scene file instead of writing it");
  rg->add_flag("-q,--quiet", rig_args.quiet, "Print nothing on success");
  return rg;
}

// Registers `pandora suggest` and its options.
CLI::App* AddSuggestCommand(CLI::App& app, pandora::app::SuggestArgs& suggest, int& threads,
                            const CLI::Validator& threads_check) {
  CLI::App* sg = app.add_subcommand(
      "suggest",
      "Nudge the selected cameras within limits to improve an objective; write a suggestion");
  sg->add_option("scene", suggest.scene, "Scene file (JSON)")->required();
  sg->add_option("--rig", suggest.rig, "Rig name (default: the first rig)");
  sg->add_option("--disable", suggest.disable,
                 "Camera ids to disable for this run, comma-separated or repeated (what the rig "
                 "loses when they fail)")
      ->delimiter(',');
  sg->add_option("--cameras", suggest.cameras,
                 "Comma-separated ids of the cameras that may move (or --ptz-preset / --ptz-tour)");
  sg->add_option(
      "--ptz-preset", suggest.ptz_preset,
      "PTZ: ID:PRESET, the pan, tilt and zoom of that preset that best cover the targets");
  sg->add_option("--ptz-tour", suggest.ptz_tour,
                 "PTZ: ID, the order of its tour's stops with the shortest longest unwatched gap "
                 "over the targets");
  sg->add_option("--tour-objective", suggest.tour_objective,
                 "With --ptz-tour: minimise the mean of the points' longest unwatched gaps (mean) "
                 "or the longest of all (max)")
      ->capture_default_str();
  sg->add_option("--target-region", suggest.target_region,
                 "Target points in this named region of the study (study.regions) instead of the "
                 "whole region");
  sg->add_option("--max-move", suggest.max_move,
                 "Largest move, metres: one value, or one per camera in --cameras order")
      ->capture_default_str();
  sg->add_option("--max-rotate", suggest.max_rotate,
                 "Largest rotation, degrees: one value, or one per camera")
      ->capture_default_str();
  sg->add_option("--objective", suggest.objective,
                 "coverage2 (coverageK), sigma-mean, sigma-p90 (sigma-pNN), resolution, mix, "
                 "coverage3-n1 (coverageK-n1, after the worst camera failure), calibration "
                 "(study.calibration)")
      ->capture_default_str();
  sg->add_option("--weights", suggest.weights,
                 "Mix weights WC,WS,WR (coverage, sigma, resolution)");
  sg->add_option("--rail", suggest.rail,
                 "Mount: stay on the line through the camera along [ID:]DX,DY,DZ (repeatable)");
  sg->add_option(
      "--plane", suggest.plane,
      "Mount: stay on the plane through the camera with normal [ID:]NX,NY,NZ (repeatable)");
  sg->add_option("--mount-box", suggest.mount_box,
                 "Mount: stay inside [ID:]XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX, metres in the world frame "
                 "(repeatable)");
  sg->add_option("--hfov-range", suggest.hfov_range,
                 "Zoom: the horizontal FOV may change within [ID:]MIN,MAX degrees (repeatable)");
  sg->add_option("--keep-out", suggest.keep_out,
                 "Box XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (metres, world frame) no camera centre may "
                 "enter (repeatable)");
  sg->add_option("--clearance", suggest.clearance,
                 "Keep every suggested camera centre this far from every scene surface, metres (a "
                 "camera already closer never moves closer)")
      ->capture_default_str()
      ->check(Number(0, HUGE_VAL, "metres"));
  sg->add_option("--target-surface", suggest.target_surfaces,
                 "Object whose surface is the target (repeatable)");
  sg->add_flag("--with-region", suggest.with_region,
               "With --target-surface: region points as well");
  sg->add_flag("--over-time", suggest.over_time,
               "Target the study's surface targets at every time sample (moving people; --points "
               "per target)");
  sg->add_option("--points", suggest.points, "Target points")
      ->capture_default_str()
      ->check(Number(1, 1000000, "target points", true));
  sg->add_option("--snap-move", suggest.snap_move,
                 "Round moves to multiples of this, metres (0: off)")
      ->check(Number(0, HUGE_VAL, "metres (0: off)"));
  sg->add_option("--snap-rotate", suggest.snap_rotate,
                 "Round yaw/pitch/roll changes to multiples of this, degrees")
      ->check(Number(0, 180, "degrees (0: off)"));
  sg->add_option("--outer", suggest.outer_iterations,
                 "Outer iterations (occlusion re-evaluated between)")
      ->check(Number(1, 1000, "outer iterations", true));
  sg->add_option("--out", suggest.out, "Suggestion file")->capture_default_str();
  sg->add_option("--perturb", suggest.perturb,
                 "Benchmark: first move and rotate the selected cameras by MOVE,DEG");
  sg->add_option(
      "--compare-baseline", suggest.compare_baseline,
      "Also run random local search with the same budget; write CSV and SVG to this folder");
  sg->add_option("--seed", suggest.seed, "Seed for target points and perturbations")
      ->capture_default_str()
      ->check(Number(0, 9.2e18, "(any whole number)", true));
  sg->add_option("--threads", threads, "Worker threads (default: all cores)")->check(threads_check);
  sg->add_flag("--quiet,-q", suggest.quiet, "Print nothing but errors");
  return sg;
}

// Registers `pandora accept` and its options.
CLI::App* AddAcceptCommand(CLI::App& app, pandora::app::AcceptArgs& accept) {
  CLI::App* ac = app.add_subcommand(
      "accept", "Write a suggestion's poses into the scene file (keeps a backup)");
  ac->add_option("suggestion", accept.suggestion, "Suggestion file from pandora suggest")
      ->required();
  ac->add_option("--cameras", accept.cameras, "Comma-separated ids to accept (default: all)");
  ac->add_flag("--force", accept.force, "Accept even if the scene file changed since");
  ac->add_flag("--quiet,-q", accept.quiet, "Print nothing but errors");
  return ac;
}

}  // namespace

int main(int argc, char** argv) {
  // `pandora view`: the interactive viewer is its own program (the only one that links GL),
  // pandora-view beside this one; it gets the remaining arguments.
  // `pandora bench --viewer SCENE [--repeat N]` is `pandora-view SCENE --bench N` (frame rates).
  bool viewer_bench = false;
  if (argc >= 2 && std::string(argv[1]) == "bench")
    for (int i = 2; i < argc; ++i) viewer_bench |= std::string(argv[i]) == "--viewer";
  if (argc >= 2 && (std::string(argv[1]) == "view" || viewer_bench))
    return ExecViewer(argc, argv, viewer_bench);
  using namespace pandora::app;
  CLI::App app{"Pandora: design multi-camera setups (coverage, resolution and uncertainty fields)"};
  app.set_version_flag("--version", PANDORA_VERSION);
  app.require_subcommand(1);
  int threads = 0;
  const CLI::Validator kThreads = Number(0, 4096, "threads (0: all cores)", true);
  app.add_option("--threads", threads, "Worker threads (default: all cores)")->check(kThreads);

  AnalyzeArgs analyze;
  CLI::App* a = AddAnalyzeCommand(app, analyze, threads, kThreads);
  BenchArgs bench;
  bool viewer_flag = false;  // handled above (pandora-view); listed for --help
  CLI::App* b = AddBenchCommand(app, bench, viewer_flag, threads, kThreads);
  AccuracyArgs accuracy;
  CLI::App* acc = AddAccuracyCommand(app, accuracy, threads, kThreads);
  RenderArgs render;
  CLI::App* rn = AddRenderCommand(app, render, threads, kThreads);
  ExportSurfaceArgs surface;
  CLI::App* es = AddExportSurfaceCommand(app, surface, threads, kThreads);
  ExportRigArgs export_rig;
  CLI::App* er = AddExportRigCommand(app, export_rig);
  ImportRigArgs import_rig;
  std::vector<std::string> import_from;
  CLI::App* ir = AddImportRigCommand(app, import_rig, import_from);
  ReportArgs report;
  CLI::App* rep = AddReportCommand(app, report, threads, kThreads);
  RigArgs rig_args;
  CLI::App* rg = AddRigCommand(app, rig_args);
  SuggestArgs suggest;
  CLI::App* sg = AddSuggestCommand(app, suggest, threads, kThreads);
  AcceptArgs accept;
  CLI::App* ac = AddAcceptCommand(app, accept);

  RefuseEmptyValues(&app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return ReportParseError(app, e);
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
    if (*er) return RunExportRig(export_rig);
    if (*ir) {
      import_rig.format = import_from.at(0);
      import_rig.from = import_from.at(1);
      return RunImportRig(import_rig);
    }
    if (*rep) return RunReport(report);
    if (*sg) return RunSuggest(suggest);
    if (*ac) return RunAccept(accept);
    if (*rg) return RunRig(rig_args);
  } catch (const pandora::InputError& e) {
    if (!pandora::app::MpiQuietErrors())
      std::fprintf(stderr, "pandora: error: %s\n", pandora::app::ForCommandLine(e).what());
    return 2;
  } catch (const std::bad_alloc&) {
    // Budgets are checked before the work starts; this is what is left: another process took the
    // memory meanwhile, or an estimate fell short (a bug then, to report).
    std::fprintf(
        stderr,
        "pandora: error: out of memory (hint: close other programs, or lower the work: a larger "
        "--voxel-size, a smaller region or image)\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pandora: internal error: %s\n", e.what());
    return 1;
  }
  return 0;
}
