// The GL helper programs beside `pandora` (app/helper_program.h).
#include "app/helper_program.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "analysis/util/error.h"

namespace pandora::app {

std::string HelperProgram(const std::string& name, const std::string& option,
                          const std::string& what) {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::string path = (self.parent_path() / name).string();
  if (!std::filesystem::exists(path))
    throw InputError(option, "", what + " " + path + " is not built",
                     "build the " + name + " target");
  return path;
}

int RunHelperProgram(std::vector<std::string> args, bool quiet) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid == 0) {
    if (quiet) std::freopen("/dev/null", "w", stdout);
    execv(argv[0], argv.data());
    std::_Exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace pandora::app
