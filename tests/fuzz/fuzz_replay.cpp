// Replays files through the fuzz targets in the normal (GCC) build: each file in a child process,
// which must exit 0 (read) or 2 (InputError), within a time limit; anything else (a signal, another
// exception, a hang) is a failure naming the file.
// Usage: fuzz_replay fields|scene|script|rig [--timeout SECONDS] FILE_OR_FOLDER...
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "analysis/util/error.h"
#include "tests/fuzz/fuzz_targets.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(
        stderr,
        "usage: fuzz_replay fields|scene|script|rig [--timeout SECONDS] FILE_OR_FOLDER...\n");
    return 1;
  }
  const std::string target = argv[1];
  if (target != "fields" && target != "scene" && target != "script" && target != "rig") {
    std::fprintf(stderr, "fuzz_replay: unknown target '%s'\n", target.c_str());
    return 1;
  }
  int timeout = 30;
  std::vector<fs::path> files;
  for (int i = 2; i < argc; ++i) {
    if (std::string(argv[i]) == "--timeout" && i + 1 < argc) {
      timeout = std::atoi(argv[++i]);
      continue;
    }
    const fs::path p(argv[i]);
    if (fs::is_directory(p)) {
      for (const auto& e : fs::recursive_directory_iterator(p))
        if (e.is_regular_file() && e.path().filename().string()[0] != '.')
          files.push_back(e.path());
    } else {
      files.push_back(p);
    }
  }
  std::sort(files.begin(), files.end());
  int read = 0, refused = 0, failed = 0;
  for (const fs::path& file : files) {
    std::fflush(stdout);
    const pid_t pid = fork();
    if (pid < 0) {
      std::perror("fork");
      return 1;
    }
    if (pid == 0) {
      alarm(unsigned(timeout));
      const rlimit memory{rlim_t(4) << 30, rlim_t(4) << 30};  // 4 GiB of address space
      setrlimit(RLIMIT_AS, &memory);
      std::ifstream in(file, std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
      const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data());
      try {
        if (target == "fields")
          pandora::fuzz::FieldsTarget(data, bytes.size());
        else if (target == "scene")
          pandora::fuzz::SceneTarget(data, bytes.size());
        else if (target == "rig")
          pandora::fuzz::RigTarget(data, bytes.size());
        else
          pandora::fuzz::ScriptTarget(data, bytes.size());
      } catch (const pandora::InputError&) {
        std::_Exit(2);
      }
      std::_Exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
      ++read;
    } else if (WIFEXITED(status) && WEXITSTATUS(status) == 2) {
      ++refused;
    } else {
      ++failed;
      if (WIFSIGNALED(status))
        std::printf(
            "FAIL: %s: killed by signal %d (%s)\n", file.c_str(), WTERMSIG(status),
            WTERMSIG(status) == SIGALRM ? "over the time limit" : strsignal(WTERMSIG(status)));
      else
        std::printf("FAIL: %s: exit code %d\n", file.c_str(), WEXITSTATUS(status));
    }
  }
  if (files.empty()) {
    std::printf("FAIL: no files to replay\n");
    return 1;
  }
  std::printf("%s: %zu files: %d read, %d refused with InputError, %d failed\n",
              failed ? "FAIL" : "ok", files.size(), read, refused, failed);
  return failed ? 1 : 0;
}
