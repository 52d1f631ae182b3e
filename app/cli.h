#pragma once
/// \file cli.h
/// The command line's frame. Each command registers its own subcommand and options in its own file
/// (`AddXxxCommand` beside its `RunXxx`, app/xxx_command.cpp) and returns what runs it; main()
/// only builds the list, parses, and runs the command given. A new command: its `Add...Command`
/// here, its file, and one line in main's list.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace pandora::app {

/// A registered command: its subcommand and what runs it once the command line is parsed (the
/// exit code; InputError and the rest are main's).
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

/// What the commands' registrations share: one thread count, set by `pandora --threads` or a
/// command's own `--threads`, and its check.
struct CommonOptions {
  int threads = 0;
  CLI::Validator threads_check;
};

/// A strict number option: the whole text is a finite number (no "nan", "inf", empty text or
/// trailing characters), a whole number when `whole`, within [min, max] (an end excluded when
/// `min_exclusive` / `max_exclusive`). The message names the unit; CLI11 prefixes the option.
CLI::Validator Number(double min, double max, const std::string& unit, bool whole = false,
                      bool min_exclusive = false, bool max_exclusive = false);

/// Every option of `app` and its subcommands that takes a value refuses an empty one ("--rig ''"
/// is not "the default rig").
void RefuseEmptyValues(CLI::App* app);

/// The commands, in `pandora --help`'s order.
Command AddAnalyzeCommand(CLI::App& app, CommonOptions& common);
/// `--viewer` is listed for --help; main runs pandora-view for it before parsing.
Command AddBenchCommand(CLI::App& app, CommonOptions& common);
Command AddAccuracyCommand(CLI::App& app, CommonOptions& common);
Command AddRenderCommand(CLI::App& app, CommonOptions& common);
Command AddExportSurfaceCommand(CLI::App& app, CommonOptions& common);
Command AddExportRigCommand(CLI::App& app, CommonOptions& common);
Command AddImportRigCommand(CLI::App& app, CommonOptions& common);
Command AddReportCommand(CLI::App& app, CommonOptions& common);
Command AddRigCommand(CLI::App& app, CommonOptions& common);
/// `pandora import-plan`: a scene file from a DXF floor plan (app/import_plan_command.cpp).
Command AddImportPlanCommand(CLI::App& app, CommonOptions& common);
/// `pandora propose`: global layout proposals (app/propose_command.cpp).
Command AddProposeCommand(CLI::App& app, CommonOptions& common);
Command AddSuggestCommand(CLI::App& app, CommonOptions& common);
Command AddAcceptCommand(CLI::App& app, CommonOptions& common);
/// `pandora synth` and `pandora validate` (app/synth_command.cpp, app/validate_command.cpp).
Command AddSynthCommand(CLI::App& app, CommonOptions& common);
Command AddValidateCommand(CLI::App& app, CommonOptions& common);

}  // namespace pandora::app
