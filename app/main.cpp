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
#include "app/cli.h"
#include "app/flags.h"
#include "app/mpi_session.h"

#ifndef PANDORA_VERSION
#define PANDORA_VERSION "dev"
#endif

namespace {

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
  CommonOptions common;
  common.threads_check = Number(0, 4096, "threads (0: all cores)", true);
  app.add_option("--threads", common.threads, "Worker threads (default: all cores)")
      ->check(common.threads_check);
  // Each command registers its options in its own file (app/cli.h), in --help's order.
  const std::vector<Command> commands = {
      AddAnalyzeCommand(app, common),       AddBenchCommand(app, common),
      AddAccuracyCommand(app, common),      AddRenderCommand(app, common),
      AddExportSurfaceCommand(app, common), AddExportRigCommand(app, common),
      AddImportRigCommand(app, common),     AddReportCommand(app, common),
      AddRigCommand(app, common),           AddImportPlanCommand(app, common),
      AddProposeCommand(app, common),       AddSuggestCommand(app, common),
      AddAcceptCommand(app, common),        AddSynthCommand(app, common),
      AddValidateCommand(app, common)};

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
  if (common.threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  static_cast<std::size_t>(common.threads));
  try {
    for (const Command& command : commands)
      if (*command.app) return command.run();
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
