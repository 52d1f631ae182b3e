// `pandora render`: the scene from a viewpoint lit by every enabled camera as a projector of its
// own colour (render/render.h), written as PNG or multi-layer OpenEXR.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "analysis/rig/rig_check.h"
#include "analysis/scene/ptz.h"
#include "analysis/util/error.h"
#include "analysis/util/text.h"
#include "analysis/util/units.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/helper_program.h"
#include "app/options.h"
#include "app/output.h"
#include "app/session/ptz_edit.h"
#include "app/session/session.h"
#include "render/prepared_scene.h"
#include "render/render.h"
#include "volume/fields.h"
#include "volume/vdb_io.h"

namespace pandora::app {
namespace {

// Checks that the options name exactly one viewpoint, and only the options that go with it.
void CheckViewpoint(const RenderArgs& args) {
  const bool have_from = !args.from.empty() || !args.at.empty();
  const int viewpoints = int(!args.view.empty()) + int(have_from) + int(!args.camera.empty()) +
                         int(!args.plan.empty());
  if (viewpoints > 1)
    throw InputError(!args.view.empty() ? "--view" : (have_from ? "--from" : "--plan"), "",
                     "give one viewpoint: --view NAME, --from X,Y,Z --at X,Y,Z, --camera ID, "
                     "--plan or --elevation SIDE");
  if (viewpoints == 0)
    throw InputError(
        "--view", "", "no viewpoint given",
        "give --view NAME, --from X,Y,Z --at X,Y,Z, --camera ID, --plan or --elevation SIDE");
  if (args.plan.empty() && !std::isnan(args.cut))
    throw InputError("--cut", "", "is for --plan and --elevation");
  if (!args.plan.empty() && !std::isnan(args.fov))
    throw InputError("--fov", "", "a plan or elevation frames the scene itself", "leave out --fov");
  if (have_from && (args.from.empty() || args.at.empty()))
    throw InputError(args.from.empty() ? "--from" : "--at", "", "--from and --at go together");
  if (!std::isnan(args.fov) && !(args.fov > 0 && args.fov < 180))
    throw InputError("--fov", "", "must be in (0, 180) degrees");
}

// The render options from the command line (pattern, surface, overlays), each checked.
RenderOptions ParseRenderOptions(const RenderArgs& args) {
  RenderOptions options;
  if (!std::isnan(args.brightness))
    options.brightness =
        CheckPositiveOption("--brightness", args.brightness, "times one camera's light");
  const std::string pattern = Lower(args.pattern);
  const std::optional<Pattern> p = PatternFromName(pattern);
  if (!p)
    throw InputError("--pattern", "", "unknown pattern '" + args.pattern + "'",
                     DidYouMean(pattern, PatternNames(), "patterns"));
  options.pattern = *p;
  const std::string surface = Lower(args.surface);
  const std::optional<Surface> mode = SurfaceFromName(surface);
  if (!mode)
    throw InputError("--surface", "", "unknown surface mode '" + args.surface + "'",
                     DidYouMean(surface, SurfaceNames(), "surface modes"));
  options.surface = *mode;
  options.grid_pixels = args.grid;
  options.samples = args.samples;
  options.overlays.cameras = !args.no_cameras;
  options.overlays.key = !args.no_key;
  if (!args.slice.empty() || !args.iso.empty()) {
    if (args.fields.empty())
      throw InputError(!args.slice.empty() ? "--slice" : "--iso", "", "needs --fields FILE.vdb",
                       "run `pandora analyze` first and pass its fields.vdb");
  }
  options.overlays.slice_field = args.slice;
  const std::string axis = Lower(args.slice_axis);
  if (axis == "x")
    options.overlays.slice_axis = 0;
  else if (axis == "y")
    options.overlays.slice_axis = 1;
  else if (axis == "z")
    options.overlays.slice_axis = 2;
  else
    throw InputError("--slice-axis", "", "must be x, y or z");
  options.overlays.slice_position = args.slice_at;
  if (!std::isnan(args.slice_at) && !(std::abs(args.slice_at) <= SceneLimits::kMaxCoordinate))
    throw InputError("--slice-at", "", "is beyond the limit of 1e7 m on coordinates");
  options.overlays.iso_field = args.iso;
  if (!std::isnan(args.iso_value)) {
    if (!std::isfinite(args.iso_value)) throw InputError("--iso-value", "", "must be finite");
    options.overlays.iso_value = args.iso_value;
  }
  options.Check();  // the library's ranges ({grid_pixels} is --grid, {samples} --samples)
  return options;
}

// The study of --scene, moved to --time-sample when that is given.
std::shared_ptr<const session::Study> LoadRenderStudy(const RenderArgs& args) {
  std::shared_ptr<const session::Study> study = session::Study::Load(args.scene);
  if (!args.time_sample.empty()) {
    // The scene moved to one time sample: by number, pose name or label.
    const Scene& placed = study->scene();
    const std::vector<TimeSample> samples = placed.TimeSamples();
    if (samples.empty())
      throw InputError("--time-sample", "", "the scene has no moving objects",
                       "add \"motions\" or an \"animation\" (docs/time.md)");
    int pick = -1;
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (samples[i].label == args.time_sample ||
          samples[i].label == "pose '" + args.time_sample + "'" ||
          std::to_string(i + 1) == args.time_sample)
        pick = int(i);
    if (pick < 0) {
      std::string labels;
      for (std::size_t i = 0; i < samples.size(); ++i)
        labels += (labels.empty() ? "" : ", ") + std::to_string(i + 1) + " " + samples[i].label;
      throw InputError("--time-sample", "", "no time sample '" + args.time_sample + "'",
                       "the samples: " + labels);
    }
    study = session::Study::FromScene(SceneAtSample(placed, samples[pick]), study->text());
  }
  return study;
}

// The viewpoint: --camera, --view, --plan / --elevation (setting `plan_scale` and the plan's
// overlays) or --from / --at; then --fov and --size.
RenderView ChooseView(const RenderArgs& args, const Scene& scene, const Rig& rig,
                      RenderOptions& options, double& plan_scale) {
  RenderView view;
  if (!args.camera.empty()) {
    view.camera = CameraOption(rig, "--camera", args.camera);
    view.width = rig.cameras[view.camera].model.width();
    view.height = rig.cameras[view.camera].model.height();
  } else if (!args.view.empty()) {
    view = NamedView(scene, "--view", args.view, 1280, 720);
  } else if (!args.plan.empty()) {
    int w = 1280, h = 720;
    if (!args.size.empty()) std::tie(w, h) = ParseImageSize("--size", args.size);
    const std::string side = Lower(args.plan);
    const Aabb& region = scene.study.region.box;
    double cut = args.cut;
    if (std::isnan(cut)) cut = PlanDefaultCut(region, side);
    const std::optional<RenderView> plan =
        PlanView(scene.ContentBounds(), side, w, h, cut, &plan_scale);
    if (!plan)
      throw InputError("--elevation", "", "unknown side '" + args.plan + "'",
                       "use north, south, east or west (or --plan)");
    view = *plan;
    options.overlays.labels = true;
    // Frusta long enough to read on the plan: 4 % of the framed width.
    options.overlays.frustum_length = 0.04 * plan_scale * w;
  } else {
    view.from = ParseVec3("--from", args.from);
    view.at = ParseVec3("--at", args.at);
    if (!args.up.empty()) view.up = ParseVec3("--up", args.up);
    scene.CheckReach(view.from, "--from", "the eye");
    scene.CheckReach(view.at, "--at", "the point looked at");
    if (!LookAt(view.from, view.at, view.up))
      throw InputError("--at", "",
                       "--at equals --from, or --up is parallel to the viewing direction");
  }
  if (!std::isnan(args.fov)) view.fov_deg = args.fov;
  if (!args.size.empty()) std::tie(view.width, view.height) = ParseImageSize("--size", args.size);
  return view;
}

// The fields of --fields for the overlays (null without it), their provenance checked.
std::unique_ptr<Fields> ReadOverlayFields(const RenderArgs& args, const Scene& scene,
                                          const Rig& rig) {
  std::unique_ptr<Fields> fields;
  if (!args.fields.empty()) {
    // A run killed while committing its outputs is finished before they are read.
    RecoverOutputs(std::filesystem::path(args.fields).parent_path().string());
    FieldsProvenance provenance;
    fields = std::make_unique<Fields>(ReadFieldsVdb(args.fields, &provenance));
    for (const std::string& w :
         CheckFieldsProvenance(provenance, fields->lattice, scene, rig, args.fields))
      std::fprintf(stderr, "pandora: warning: %s\n", w.c_str());
  }
  return fields;
}

// --gpu: what the GPU renderer draws of a request (the rest is the exact renderer's), refused
// naming the option otherwise.
void CheckGpuRequest(const RenderArgs& args, const std::string& ext) {
  if (!args.gpu) {
    if (args.no_compare) throw InputError("--no-compare", "", "is for --gpu");
    return;
  }
  const char* hint = "the exact renderer draws it: leave out --gpu";
  if (ext != ".png") throw InputError("--out", "", "--gpu writes PNG only (no layers)", hint);
  if (!args.fields.empty())
    throw InputError("--fields", "", "overlays are not drawn by --gpu", hint);
  if (args.samples != 1) throw InputError("--samples", "", "--gpu draws one sample a pixel", hint);
  if (!args.time_sample.empty())
    throw InputError("--time-sample", "", "cannot be combined with --gpu", hint);
  if (Lower(args.ptz) != "single")
    throw InputError("--ptz", "", "PTZ traces are not drawn by --gpu", hint);
  if (args.shadow_map < 512 || args.shadow_map > 4096)
    throw InputError("--shadow-map", "", "must be 512 .. 4096 texels");
}

// --gpu: pandora_gl_render (beside this program; the only code that links GL is outside it)
// draws `view` into `staged` and prints its time and its agreement with the exact renderer.
void RenderOnGpu(const RenderArgs& args, const Rig& rig, const RenderView& view,
                 const std::string& staged) {
  const std::string tool = HelperProgram("pandora_gl_render", "--gpu", "the GPU renderer");
  auto number = [](double v) {
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return std::string(text);
  };
  auto triple = [&](const Vec3& v) {
    return number(v.x()) + "," + number(v.y()) + "," + number(v.z());
  };
  std::vector<std::string> a{
      tool,     args.scene,
      "--rig",  rig.name,
      "--out",  staged,
      "--size", std::to_string(view.width) + "x" + std::to_string(view.height)};
  if (view.camera >= 0) {
    a.insert(a.end(), {"--camera-index", std::to_string(view.camera)});
  } else {
    a.insert(a.end(),
             {"--from", triple(view.from), "--at", triple(view.at), "--up", triple(view.up),
              "--fov", number(view.fov_deg), "--clip-near", number(view.clip_near)});
  }
  std::string disabled;
  for (std::size_t c = 0; c < rig.cameras.size(); ++c)
    if (!rig.cameras[c].enabled) disabled += (disabled.empty() ? "" : ",") + std::to_string(c);
  if (!disabled.empty()) a.insert(a.end(), {"--disabled", disabled});
  a.insert(a.end(),
           {"--pattern", Lower(args.pattern), "--grid", std::to_string(args.grid), "--surface",
            Lower(args.surface), "--shadow-map", std::to_string(args.shadow_map)});
  if (!std::isnan(args.brightness)) a.insert(a.end(), {"--brightness", number(args.brightness)});
  if (args.no_compare) a.push_back("--no-compare");
  const int status = RunHelperProgram(std::move(a), false);
  if (status != 0)
    throw InputError(
        "--gpu", "",
        "the GPU renderer failed (exit " + std::to_string(status) + "; its message is above)",
        "without a display it needs EGL: install libegl1 and libegl-mesa0, or leave "
        "out --gpu");
}

}  // namespace

int RunRender(const RenderArgs& args) {
  // Options that need no scene first, so typos fail fast.
  const std::string ext = Lower(std::filesystem::path(args.out).extension().string());
  if (ext != ".png" && ext != ".exr")
    throw InputError("--out", "", "unsupported image type '" + ext + "'",
                     "name the output FILE.png (8-bit sRGB) or FILE.exr (float RGB and layers)");
  CheckViewpoint(args);
  CheckGpuRequest(args, ext);
  RenderOptions options = ParseRenderOptions(args);

  // The study (scene, ray caster and prepared scene, built once) through the session layer.
  session::SessionOptions session_options;
  session_options.rig = args.rig;
  session_options.rig_option = "--rig";
  session_options.disable = args.disable;
  std::shared_ptr<const session::Study> study = LoadRenderStudy(args);
  const session::Session session(study, session_options);
  const Scene& scene = session.study().scene();
  const Rig& rig = session.rig().rig();
  OutputTransaction output;
  AddSceneInputs(output, scene);
  output.AddInput(args.fields, "fields file");
  const std::string staged = output.Stage(args.out, "--out");
  options.pixel_sigma = scene.study.pixel_sigma;

  double plan_scale = 0;  // metres per pixel of a plan or elevation
  RenderView view = ChooseView(args, scene, rig, options, plan_scale);

  if (args.gpu) {
    // A camera's-eye view of a lens reaching 75 degrees off its axis (a wide fisheye, whose maps
    // are cubes) is the exact renderer's (GlDrawsCameraEye): refused here in one line.
    if (view.camera >= 0 &&
        rig.cameras[std::size_t(view.camera)].model.max_field_angle() >= 75.0 * kPi / 180.0)
      throw InputError("--gpu", "",
                       "camera " + rig.cameras[std::size_t(view.camera)].id +
                           "'s lens reaches 75 degrees or more off its axis: its view is drawn "
                           "by the exact renderer only",
                       "leave out --gpu");
    RenderOnGpu(args, rig, view, staged);
    output.Commit();
    if (!args.quiet)
      std::printf(
          "wrote %s: %dx%d on the GPU, rig %s (%d enabled cameras); no overlays (camera "
          "bodies, key and labels are the exact renderer's)\n",
          args.out.c_str(), view.width, view.height, rig.name.c_str(), rig.enabled_count());
    return 0;
  }
  const std::unique_ptr<Fields> fields = ReadOverlayFields(args, scene, rig);

  // One BVH for the image and the rig checks: the study's, under its prepared scene.
  std::unique_ptr<PreparedOverlays> overlays;
  if (fields) overlays = std::make_unique<PreparedOverlays>(*fields, options.overlays);
  options.layers = ext == ".exr";  // the PNG has no room for them
  RenderStats stats;
  // PTZ traces: the lights of the rig's PTZ cameras (docs/ptz.md).
  const std::string ptz_mode = Lower(args.ptz);
  if (ptz_mode != "single" && ptz_mode != "path" && ptz_mode != "all")
    throw InputError("--ptz", "", "unknown mode '" + args.ptz + "'", "use single, path or all");
  if (ptz_mode != "single" && std::isnan(options.brightness))
    options.brightness = DefaultBrightness(rig.enabled_count());  // the rig's, not its traces'
  bool any = false;
  const Rig traced = session::PtzTracedRig(rig, ptz_mode, args.ptz_time, &options.ptz_all, &any);
  if (ptz_mode != "single" && !any)
    throw InputError("--ptz", "", "rig '" + rig.name + "' has no enabled PTZ camera",
                     "add a \"ptz\" block to a camera (docs/ptz.md)");
  const Image image = ptz_mode == "single" ? session.Render(view, options, overlays.get(), &stats)
                                           : RenderWithStats(session.study().prepared(), traced,
                                                             view, options, overlays.get(), &stats);
  if (ext == ".png")
    WritePng(image, staged);
  else
    WriteExr(image, staged, int(rig.cameras.size()));
  output.Commit();
  const std::vector<Warning> warnings =
      args.quiet ? std::vector<Warning>() : CheckRig(scene, rig, session.study().caster());
  if (!args.quiet) {
    const double brightness = std::isnan(options.brightness)
                                  ? DefaultBrightness(rig.enabled_count())
                                  : options.brightness;
    std::printf(
        "wrote %s: %dx%d, rig %s (%d enabled cameras, brightness %.3g%s), %zu triangles, %.3f s\n",
        args.out.c_str(), image.width, image.height, rig.name.c_str(), rig.enabled_count(),
        brightness, std::isnan(options.brightness) ? " by default" : "",
        session.study().caster().triangle_count(), stats.seconds);
    if (plan_scale > 0)
      std::printf(
          "%s: 1 px = %.3g cm, orthographic to %.2g %% (the eye %.0f times the scene's size "
          "away)\n",
          args.plan.c_str(), 100 * plan_scale, 100.0 / kPlanDistance, kPlanDistance);
    std::fflush(stdout);
    for (const Warning& w : warnings)
      std::fprintf(stderr, "pandora: warning: %s\n", FormatWarning(scene.path, w).c_str());
  }
  return 0;
}

// Registers `pandora render` and its options.
Command AddRenderCommand(CLI::App& app, CommonOptions& common) {
  auto args = std::make_shared<RenderArgs>();
  RenderArgs& render = *args;
  int& threads = common.threads;
  const CLI::Validator& threads_check = common.threads_check;
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
  rn->add_flag("--gpu", render.gpu,
               "Draw with the GPU renderer (pandora_gl_render; headless EGL without a display): "
               "PNG, no overlays; prints its agreement with the exact renderer");
  rn->add_flag("--no-compare", render.no_compare,
               "With --gpu: skip the exact renderer's picture and the comparison");
  rn->add_option("--shadow-map", render.shadow_map,
                 "With --gpu: shadow-map size per camera, 512 to 4096")
      ->capture_default_str();
  rn->add_flag("--quiet,-q", render.quiet, "Print nothing but errors");
  return {rn, [args] { return RunRender(*args); }};
}

}  // namespace pandora::app
