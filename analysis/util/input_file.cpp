#include "analysis/util/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "analysis/util/error.h"

namespace pandora {
namespace {

std::string ByteSize(std::uint64_t bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB"};
  double v = static_cast<double>(bytes);
  int u = 0;
  while (v >= 1024 && u < 4) {
    v /= 1024;
    ++u;
  }
  char text[48];
  if (u == 0)
    std::snprintf(text, sizeof text, "%llu bytes", static_cast<unsigned long long>(bytes));
  else
    std::snprintf(text, sizeof text, "%.1f %s", v, units[u]);
  return text;
}

// The kind of a file that is not a regular one, for the message; empty for a regular file.
std::string SpecialKind(mode_t mode) {
  if (S_ISREG(mode)) return "";
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

void CheckStat(const std::string& path, const struct stat& st, std::uint64_t max_bytes,
               const std::string& what) {
  const std::string kind = SpecialKind(st.st_mode);
  if (!kind.empty())
    throw InputError(path, "", "cannot read the " + what + ": it is " + kind,
                     "give the path of a regular file");
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (size > max_bytes)
    throw InputError(
        path, "",
        "the " + what + " is " + ByteSize(size) + "; at most " + ByteSize(max_bytes) + " is read",
        "is this the right file?");
}

[[noreturn]] void ThrowOpenError(const std::string& path, int error, const std::string& what) {
  if (error == ENOENT || error == ENOTDIR)
    throw InputError(path, "", "cannot open the " + what + ": no such file", "check the path");
  if (error == EACCES || error == EPERM)
    throw InputError(path, "", "cannot open the " + what + ": permission denied",
                     "check the file's permissions");
  throw InputError(path, "", "cannot open the " + what + ": " + std::strerror(error));
}

}  // namespace

std::uint64_t CheckInputFile(const std::string& path, std::uint64_t max_bytes,
                             const std::string& what) {
  if (path.empty()) throw InputError(path, "", "no " + what + " given (the path is empty)");
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) ThrowOpenError(path, errno, what);
  CheckStat(path, st, max_bytes, what);
  if (::access(path.c_str(), R_OK) != 0) ThrowOpenError(path, errno, what);
  return static_cast<std::uint64_t>(st.st_size);
}

std::string ReadInputFile(const std::string& path, std::uint64_t max_bytes,
                          const std::string& what) {
  CheckInputFile(path, max_bytes, what);
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) ThrowOpenError(path, errno, what);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) ThrowOpenError(path, errno, what);
  CheckStat(path, st, max_bytes, what);
  std::string bytes;
  bytes.resize(static_cast<std::size_t>(st.st_size));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(path, "", "cannot read the " + what + ": " + std::strerror(errno));
    if (n == 0) break;  // The file shrank while being read: take what is there.
    done += static_cast<std::size_t>(n);
  }
  bytes.resize(done);
  return bytes;
}

void CheckJsonLimits(const std::string& text, const std::string& file) {
  if (text.size() > InputLimits::kJsonBytes)
    throw InputError(file, "$",
                     "the JSON text is " + ByteSize(text.size()) + "; at most " +
                         ByteSize(InputLimits::kJsonBytes) + " is read",
                     "is this the right file?");
  int depth = 0;
  bool in_string = false, escaped = false;
  std::size_t line = 1;
  for (const char c : text) {
    if (c == '\n') ++line;
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > InputLimits::kJsonDepth)
        throw InputError(file, "$",
                         "arrays and objects nested deeper than " +
                             std::to_string(InputLimits::kJsonDepth) + " levels (line " +
                             std::to_string(line) + ")",
                         "a Pandora file needs at most 6 levels; is this the right file?");
    } else if (c == ']' || c == '}') {
      if (depth > 0) --depth;  // Unbalanced brackets are the parser's to report.
    }
  }
}

}  // namespace pandora
