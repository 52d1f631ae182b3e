// `pandora view SCENE` (the `pandora` command runs this program, pandora-view, beside it): the
// interactive simulator (docs/viewer.md). With --script it replays actions (viewer/core/script.h)
// in a window, writes --screenshot and --log, and exits: what the CI's scripted session does.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "analysis/util/output_transaction.h"
#include "app/flags.h"
#include "app/session/autosave.h"
#include "app/session/study.h"
#include "viewer/core/model.h"
#include "viewer/core/script.h"
#include "viewer/window/viewer_app.h"

namespace {

std::pair<int, int> ParseSize(const std::string& text) {
  int w = 0, h = 0;
  char x = 0, rest = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &rest) != 3 || (x != 'x' && x != 'X') ||
      w < 320 || h < 240 || w > 8192 || h > 8192)
    throw pandora::InputError("--size", "", "expected WxH, each from 320x240 to 8192",
                              "e.g. --size 1280x720");
  return {w, h};
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// `pandora bench --viewer`: whole frames of the window (GPU light, overlays, panels, swap) while
// the eye orbits (each camera's shadow maps reused) and while every camera moves (maps redrawn each
// frame, the fields updating in the background), against the exact CPU renderer of the same view.
int Bench(pandora::viewer::ViewerModel& model, pandora::viewer::ViewerApp& window, int frames,
          double scale, double target_hz) {
  using pandora::viewer::Action;
  model.session().WaitFields();
  window.Frame();  // first frame: programs, maps
  std::vector<double> scales;
  std::vector<pandora::viewer::FrameTransfer> transfer;  // per run: the largest of its frames
  auto run = [&](bool move_cameras) {
    std::vector<double> times;
    pandora::viewer::FrameTransfer most;
    // Adaptive: 8 frames untimed first, as the scale settles.
    const int warm = target_hz > 0 ? 8 : 0;
    for (int i = 0; i < warm + frames; ++i) {
      if (move_cameras) {
        Action a;
        a.kind = Action::Kind::kMove;
        a.where = "bench";
        for (const auto& c : model.rig().cameras) a.cameras.push_back(c.id);
        a.a = pandora::Vec3(i % 2 ? -0.002 : 0.002, 0, 0);
        a.drag = true;
        model.Do(a, nullptr);
      } else {
        model.view.Orbit(2.0, 0.0);
      }
      const auto t0 = std::chrono::steady_clock::now();
      window.Frame();
      if (i >= warm) {
        times.push_back(Seconds(t0));
        const pandora::viewer::FrameTransfer t = window.LastFrameTransfer();
        most.readback_bytes = std::max(most.readback_bytes, t.readback_bytes);
        most.upload_bytes = std::max(most.upload_bytes, t.upload_bytes);
        most.map_cpu_seconds = std::max(most.map_cpu_seconds, t.map_cpu_seconds);
      }
    }
    transfer.push_back(most);
    scales.push_back(window.MotionScaleNow());
    std::sort(times.begin(), times.end());
    return times[times.size() / 2];
  };
  const double navigate = run(false);
  const double moving = run(true);
  model.session().WaitFields();
  pandora::RenderOptions options = model.display;
  options.layers = false;
  double cpu = 1e300;
  for (int i = 0; i < 3; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    model.session().Render(model.MainView(), options);
    cpu = std::min(cpu, Seconds(t0));
  }
  char how[160];
  if (target_hz > 0)
    std::snprintf(how, sizeof how,
                  "while moving drawn at an adaptive scale aiming at %.0f Hz (reached %.2f "
                  "navigating, %.2f cameras moving)",
                  target_hz, scales[0], scales[1]);
  else
    std::snprintf(how, sizeof how, "while moving drawn at %.2f of the resolution", scale);
  std::printf(
      "pandora bench --viewer: %s, rig %s (%d enabled cameras), %dx%d, %d frames each (median); "
      "%s\n",
      model.scene().path.c_str(), model.rig().name.c_str(), model.rig().enabled_count(),
      model.width, model.height, frames, how);
  std::printf("  navigating (eye orbits, shadow maps reused)       %8.1f ms  %6.2f frames/s\n",
              1000 * navigate, 1 / navigate);
  std::printf("  all cameras moving (maps redrawn, fields live)    %8.1f ms  %6.2f frames/s\n",
              1000 * moving, 1 / moving);
  std::printf("  exact CPU renderer, same view (best of 3)         %8.1f ms  %6.2f frames/s\n",
              1000 * cpu, 1 / cpu);
  std::printf("  ratio window frame / CPU frame: navigating %.3f, cameras moving %.3f\n",
              navigate / cpu, moving / cpu);
  // The main picture stays on the GPU; what a frame still moves is the exact CPU renderer's
  // insets (camera's-eye views), uploaded when they change.
  std::printf(
      "  picture bytes per frame, most of any timed frame: navigating read back %lld, uploaded "
      "%lld; cameras moving read back %lld, uploaded %lld\n",
      static_cast<long long>(transfer[0].readback_bytes),
      static_cast<long long>(transfer[0].upload_bytes),
      static_cast<long long>(transfer[1].readback_bytes),
      static_cast<long long>(transfer[1].upload_bytes));
  std::printf(
      "  CPU preparing shadow maps (their depth ranges), most of any timed frame: navigating "
      "%.3f ms, cameras moving %.3f ms\n",
      1e3 * transfer[0].map_cpu_seconds, 1e3 * transfer[1].map_cpu_seconds);
  return 0;
}

int Run(int argc, char** argv) {
  CLI::App app{
      "Pandora's interactive simulator: move cameras, watch their light, fields and suggestions"};
  app.name("pandora view");
  std::string scene, rig, fields, script, screenshot, log, size = "1280x720";
  bool hidden = false, recover = false, discard = false, no_autosave = false;
  int shadow_map = 2048, bench_frames = 0;
  double target_hz = 30;
  app.add_option("scene", scene, "Scene file (JSON)")->required();
  app.add_option("--rig", rig, "Rig to edit (default: the first)");
  std::vector<std::string> disable;
  app.add_option("--disable", disable,
                 "Camera ids to disable for this session, comma-separated or repeated "
                 "(not saved)")
      ->delimiter(',');
  app.add_option("--fields", fields,
                 "Live fields, comma-separated (default: coverage,cameras,resolution,sigma_max)");
  app.add_option("--script", script,
                 "Replay these actions (a JSON array; docs/viewer.md), then exit");
  app.add_option("--screenshot", screenshot, "With --script: the window at the end, as PNG");
  app.add_option("--log", log, "With --script: the state after each action, as JSON");
  app.add_option("--size", size, "Window size WxH")->capture_default_str();
  app.add_option("--shadow-map", shadow_map, "Shadow map size per camera, 512 to 4096")
      ->capture_default_str()
      ->check(CLI::Range(512, 4096));
  app.add_option("--target-hz", target_hz,
                 "While the view or cameras move, draw at a resolution adapted to this frame rate "
                 "(0: a fixed half resolution); full resolution 0.3 s after it stops")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 240.0));
  app.add_flag("--hidden", hidden,
               "No visible window (scripts, tests); without a display (or with PANDORA_GL=egl) "
               "drawn offscreen through headless EGL");
  app.add_option("--bench", bench_frames,
                 "Measure frame rates over this many frames (navigating; all cameras moving) "
                 "against the exact CPU renderer, print them and exit")
      ->check(CLI::Range(2, 10000));
  app.add_flag("--recover", recover, "Apply the autosave of a session that ended without saving");
  app.add_flag("--discard-autosave", discard, "Delete that autosave and start from the scene file");
  app.add_flag("--no-autosave", no_autosave, "Do not write the autosave file");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "pandora view: error: %s\n", e.what());
    return 2;
  }
  const auto [width, height] = ParseSize(size);
  if ((!screenshot.empty() || !log.empty()) && script.empty())
    throw pandora::InputError(screenshot.empty() ? "--log" : "--screenshot", "", "needs --script");
  std::vector<pandora::viewer::Action> actions;
  if (!script.empty()) actions = pandora::viewer::LoadScript(script);  // refused before any window

  const auto study = pandora::session::Study::Load(scene);
  pandora::viewer::ViewerOptions vo;
  vo.rig = rig;
  vo.disable = disable;
  vo.width = width;
  vo.height = height;
  if (!fields.empty()) {
    std::stringstream ss(fields);
    for (std::string f; std::getline(ss, f, ',');)
      if (!f.empty()) vo.fields.push_back(f);
  }
  const std::string autosave = pandora::session::AutosavePath(study->scene().path);
  if (!no_autosave) vo.autosave_path = autosave;
  const auto saved = pandora::session::ReadAutosave(autosave, *study);
  if (saved && !recover && !discard)
    throw pandora::InputError(
        autosave, "", "unsaved edits of an earlier session are kept here",
        "start with --recover to apply them, or --discard-autosave to delete them");
  pandora::viewer::ViewerModel model(study, vo);
  if (saved && recover) {
    const auto ids = pandora::session::RecoverAutosave(model.session(), *saved, autosave);
    model.status = "recovered " + std::to_string(ids.size()) + " cameras from " + autosave;
  }
  if (saved && discard) std::filesystem::remove(autosave);

  pandora::viewer::AppOptions ao;
  ao.width = width;
  ao.height = height;
  ao.visible = !hidden;
  ao.shadow_map_size = shadow_map;
  ao.target_hz = target_hz;
  ao.show_timing = script.empty();
  if (!script.empty())
    ao.motion_scale = 1.0;  // every scripted frame in full: reproducible pictures
  if (bench_frames > 0) ao.visible = false, ao.show_timing = false, ao.motion_scale = 1.0;
  if (bench_frames > 0) {
    // Full resolution throughout, then as interaction draws it (reduced while moving).
    pandora::viewer::ViewerApp window(model, ao);
    std::printf("pandora bench --viewer: GL %s\n", window.GlDescription().c_str());
    // Full resolution throughout, a fixed half, then what the window does: adaptive, 30 Hz.
    for (const auto& [scale, hz] :
         {std::pair{1.0, 0.0}, std::pair{0.5, 0.0}, std::pair{0.5, 30.0}}) {
      window.SetMotionScale(scale, hz);
      Bench(model, window, bench_frames, scale, hz);
    }
    return 0;
  }
  pandora::viewer::ViewerApp window(model, ao);
  if (script.empty()) {
    window.Loop();
    return 0;
  }
  // The log, like the screenshots, never replaces an input and appears whole (also after an error).
  pandora::OutputTransaction log_output;
  for (const auto& [path, what] : model.scene().InputFiles()) log_output.AddInput(path, what);
  log_output.AddInput(script, "script");
  const std::string staged_log = log.empty() ? "" : log_output.Stage(log, "--log");
  nlohmann::json states = nlohmann::json::array();
  auto write_log = [&] {
    if (log.empty()) return;
    pandora::WriteFileAtomically(staged_log, states.dump(1) + "\n");
    log_output.Commit();
  };
  try {
    window.Frame();
    for (const auto& a : actions) {
      model.Do(a, &window);
      window.Frame();
      nlohmann::json s = model.StateJson();
      s["action"] = a.where;
      states.push_back(std::move(s));
    }
    model.session().WaitFields();
    if (!screenshot.empty()) {
      pandora::viewer::Action shot;
      shot.kind = pandora::viewer::Action::Kind::kScreenshot;
      shot.where = "--screenshot";
      shot.text = screenshot;
      model.Do(shot, &window);
    }
  } catch (...) {
    write_log();
    throw;
  }
  write_log();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(argc, argv);
  } catch (const pandora::InputError& e) {
    std::fprintf(stderr, "pandora view: error: %s\n", pandora::app::ForCommandLine(e).what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pandora view: error: %s\n", e.what());
    return 1;
  }
}
