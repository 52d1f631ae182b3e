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
  try {
    SyncFile(tmp);
  } catch (const InputError& e) {
    std::remove(tmp.c_str());
    throw InputError(path, "", e.reason(), e.hint());
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw InputError(path, "", "cannot rename the temporary file: " + ec.message(),
                     "check that the output folder is writable");
  }
}

}  // namespace pandora
