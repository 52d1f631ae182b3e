#pragma once
/// \file helper_program.h
/// The GL helpers `pandora` runs (pandora_gl_bench for `accuracy --gpu`, pandora_gl_render for
/// `render --gpu`): programs installed beside it, so that the only code linking GL stays out of
/// `pandora` itself.

#include <string>
#include <vector>

namespace pandora::app {

/// The path of program `name` beside this one; InputError naming `option` (and the target to
/// build) when it is not there.
std::string HelperProgram(const std::string& name, const std::string& option,
                          const std::string& what);

/// Runs `args` (args[0] the program) and waits: its exit code, or -1 when it did not exit (a
/// signal). Its stderr is ours; its stdout too unless `quiet`.
int RunHelperProgram(std::vector<std::string> args, bool quiet);

}  // namespace pandora::app
