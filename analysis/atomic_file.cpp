#include "analysis/atomic_file.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "analysis/error.h"

namespace pandora {

std::string TemporaryPath(const std::string& path) {
  // Unique to this process, so two runs writing the same output never interleave and a user's own
  // "NAME.tmp" is never touched.
  return path + ".tmp-" + std::to_string(static_cast<long>(getpid()));
}

void CommitTemporary(const std::string& path) {
  const std::string tmp = TemporaryPath(path);
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw InputError(path, "", "cannot rename the temporary file: " + ec.message(),
                     "check that the output folder is writable");
  }
}

void WriteFileAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = TemporaryPath(path);
  {
    std::ofstream f(tmp, std::ios::binary);
    f << text;
    f.flush();
    if (!f) {
      std::remove(tmp.c_str());
      throw InputError(path, "", "cannot write the file", "check the output folder");
    }
  }
  CommitTemporary(path);
}

}  // namespace pandora
