#include "analysis/atomic_file.h"

#include <sys/stat.h>
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

void WriteFileAtomically(const std::string& path, const std::string& text) {
  unsigned mode = 0666;
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (exists) mode = st.st_mode & 07777;
  const std::string tmp = TemporaryPath(path);
  WriteNewFile(tmp, text, mode, path);
  if (exists) ::chmod(tmp.c_str(), mode);  // open() applied the umask
  CommitTemporary(path);
}

}  // namespace pandora
