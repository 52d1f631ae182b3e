#pragma once
/// \file commands.h
/// The `pandora` subcommands. Each returns the process exit code; bad input throws InputError, which
/// main() prints as one line and turns into exit code 2.

#include <string>

namespace pandora::app {

struct AnalyzeArgs {
  std::string scene;
  std::string rig;
  std::string out = "out";
  double voxel_size = 0;  ///< 0: the scene's study.voxel_size.
  std::string fields;     ///< Comma-separated; empty: the scene's study.fields.
  double memory_budget_mb = 0;  ///< 0: the scene's study.memory_budget_mb.
  bool quiet = false;
};
int RunAnalyze(const AnalyzeArgs& args);

struct BenchArgs {
  std::string scene;
  std::string rig;
  double voxel_size = 0;
  int repeat = 3;
  std::string json_out;
};
int RunBench(const BenchArgs& args);

}  // namespace pandora::app
