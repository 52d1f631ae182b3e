#include "analysis/util/atomic_file.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "analysis/util/error.h"

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
  if (const std::string kind = NotARegularFile(path); !kind.empty()) {
    std::remove(tmp.c_str());
    throw InputError(path, "",
                     "the output path is now " + kind + ", not a regular file; nothing was written",
                     "give the path of a file");
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
  if (const std::string kind = NotARegularFile(path); !kind.empty())
    throw InputError(path, "",
                     "the output path is " + kind +
                         ", not a regular file; an output only replaces a regular file",
                     "give the path of a file");
  unsigned mode = 0666;
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (exists) mode = st.st_mode & 07777;
  const std::string tmp = TemporaryPath(path);
  WriteNewFile(tmp, text, mode, path);
  if (exists) ::chmod(tmp.c_str(), mode);  // open() applied the umask
  CommitTemporary(path);
}

FolderLock::FolderLock(const std::string& path, double timeout_s) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::path folder = fs::absolute(path, ec).parent_path();
  if (folder.empty()) folder = ".";
  fd_ = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0)
    throw InputError(path, "",
                     std::string("cannot open its folder to lock it: ") + std::strerror(errno),
                     "check that the folder exists and is readable");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    if (error != EWOULDBLOCK && error != EINTR) {
      ::close(fd_);
      fd_ = -1;
      throw InputError(path, "", std::string("cannot lock its folder: ") + std::strerror(error));
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ::close(fd_);
      fd_ = -1;
      throw InputError(path, "",
                       "another program has held the lock on its folder for over " +
                           std::to_string(int(timeout_s)) + " s",
                       "wait for the other pandora command to finish, then try again");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the lock
}

}  // namespace pandora
