#include "analysis/util/output_transaction.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "analysis/util/error.h"

namespace pandora {
namespace {

namespace fs = std::filesystem;

constexpr const char* kStagingPrefix = ".pandora-staging-";
constexpr const char* kJournal = "JOURNAL";
constexpr const char* kPrimary = "PRIMARY";
constexpr const char* kRemoved = "-";  // journal: the final path is removed, not replaced

std::string ErrnoText(int error) { return std::strerror(error); }

}  // namespace

std::string NotARegularFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return "";  // nothing there (or a dangling link): a new file
  if (S_ISREG(st.st_mode)) return "";
  if (S_ISDIR(st.st_mode)) return "a folder";
  if (S_ISCHR(st.st_mode)) return "a character device";
  if (S_ISBLK(st.st_mode)) return "a block device";
  if (S_ISFIFO(st.st_mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  return "not a regular file";
}

namespace {

// fsync of a file or folder by path; the errno, or 0.
int SyncPath(const std::string& path, bool folder) {
  const int fd = ::open(path.c_str(), (folder ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) return errno;
  int error = 0;
  if (::fsync(fd) != 0) error = errno;
  ::close(fd);
  // Some file systems cannot sync folders; that is not a failure of ours.
  if (folder && (error == EINVAL || error == EROFS)) error = 0;
  return error;
}

}  // namespace

void WriteNewFile(const std::string& path, const std::string& bytes, unsigned mode,
                  const std::string& blame) {
  const int fd =
      ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, static_cast<mode_t>(mode));
  if (fd < 0)
    throw InputError(blame, "", "cannot create a file there: " + ErrnoText(errno),
                     "check that the output folder is writable");
  std::size_t done = 0;
  int error = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      error = n < 0 ? errno : EIO;
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  if (error == 0 && ::fsync(fd) != 0) error = errno;
  if (::close(fd) != 0 && error == 0) error = errno;
  if (error != 0) {
    ::unlink(path.c_str());
    throw InputError(
        blame, "", "cannot write the file: " + ErrnoText(error),
        error == ENOSPC ? "the disk is full; free some space" : "check the output folder");
  }
}

namespace {

// Test hook: PANDORA_TEST_CRASH_AT=after-journal or after-first-rename kills the process at that
// point of Commit(), as a power cut or `kill -9` would (tests/cli/check_transactions.sh).
void MaybeCrash(const char* point) {
  const char* at = std::getenv("PANDORA_TEST_CRASH_AT");
  if (at != nullptr && std::strcmp(at, point) == 0) ::raise(SIGKILL);
}

bool ProcessAlive(long pid) {
  if (pid <= 0) return false;
  if (pid == static_cast<long>(::getpid())) return true;
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}

// The process id in a staging folder's name ".pandora-staging-PID-N", or -1.
long StagingPid(const std::string& name) {
  const std::string prefix = kStagingPrefix;
  if (name.compare(0, prefix.size(), prefix) != 0) return -1;
  char* end = nullptr;
  const long pid = std::strtol(name.c_str() + prefix.size(), &end, 10);
  return end != nullptr && *end == '-' ? pid : -1;
}

// The process id of a temporary "NAME.tmp-PID", or -1.
long TemporaryPid(const std::string& name) {
  const std::size_t at = name.rfind(".tmp-");
  if (at == std::string::npos || at + 5 >= name.size()) return -1;
  char* end = nullptr;
  const long pid = std::strtol(name.c_str() + at + 5, &end, 10);
  return end != nullptr && *end == '\0' ? pid : -1;
}

std::string ReadSmallFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The journal: one "STAGED\tFINAL" line per output after a header line.
struct JournalEntry {
  std::string staged, final;
};

std::vector<JournalEntry> ParseJournal(const std::string& text) {
  std::vector<JournalEntry> entries;
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != "pandora-journal 1") return entries;
  while (std::getline(in, line)) {
    const std::size_t tab = line.find('\t');
    if (tab == std::string::npos) continue;
    entries.push_back({line.substr(0, tab), line.substr(tab + 1)});
  }
  return entries;
}

// Completes a committed transaction from its journal: renames what is still staged, removes the
// staging folders (secondaries first), then the journal and its folder.
void RollForward(const std::string& journal_path) {
  const std::vector<JournalEntry> entries = ParseJournal(ReadSmallFile(journal_path));
  std::error_code ec;
  std::vector<fs::path> folders;
  for (const JournalEntry& e : entries) {
    if (e.staged == kRemoved) {  // a stale output of an earlier run
      if (fs::is_regular_file(fs::symlink_status(e.final, ec))) fs::remove(e.final, ec);
      continue;
    }
    if (fs::exists(e.staged, ec)) ::rename(e.staged.c_str(), e.final.c_str());
    const fs::path dir = fs::path(e.staged).parent_path();
    if (std::find(folders.begin(), folders.end(), dir) == folders.end()) folders.push_back(dir);
  }
  for (const fs::path& dir : folders) SyncPath(fs::path(dir).parent_path().string(), true);
  const fs::path primary = fs::path(journal_path).parent_path();
  for (const fs::path& dir : folders)
    if (dir != primary) fs::remove_all(dir, ec);
  fs::remove_all(primary, ec);
}

}  // namespace

// -------------------------------------------------------------------------------------------------

void SyncFile(const std::string& path, std::uint64_t min_bytes) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
    throw InputError(path, "", "the output was not written", "check the output folder");
  if (static_cast<std::uint64_t>(st.st_size) < min_bytes)
    throw InputError(path, "",
                     "the output is empty or cut short (" + std::to_string(st.st_size) + " bytes)",
                     "is the disk full?");
  if (const int error = SyncPath(path, false))
    throw InputError(
        path, "", "cannot flush the output to disk: " + ErrnoText(error),
        error == ENOSPC ? "the disk is full; free some space" : "check the output folder");
}

void RecoverOutputs(const std::string& folder) {
  std::error_code ec;
  fs::directory_iterator it(folder.empty() ? "." : folder, ec);
  if (ec) return;
  std::vector<fs::path> entries;
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) return;
    entries.push_back(it->path());
  }
  for (const fs::path& entry : entries) {
    const std::string name = entry.filename().string();
    if (const long pid = StagingPid(name); pid > 0) {
      if (ProcessAlive(pid)) continue;
      const fs::path journal = entry / kJournal, primary = entry / kPrimary;
      if (fs::exists(journal, ec)) {
        RollForward(journal.string());
      } else if (fs::exists(primary, ec)) {
        const std::string primary_journal = ReadSmallFile(primary.string());
        if (!primary_journal.empty() && fs::exists(primary_journal, ec))
          RollForward(primary_journal);
        else
          fs::remove_all(entry, ec);
      } else {
        fs::remove_all(entry, ec);
      }
    } else if (const long tmp_pid = TemporaryPid(name); tmp_pid > 0) {
      if (!ProcessAlive(tmp_pid) && fs::is_regular_file(entry, ec)) fs::remove(entry, ec);
    }
  }
}

// -------------------------------------------------------------------------------------------------

struct OutputTransaction::Impl {
  struct Input {
    std::string path, what;
  };
  struct Output {
    std::string final, staged, option, mode_from;
  };
  struct Staging {
    fs::path folder;   // The output folder.
    fs::path staging;  // Its staging folder.
  };
  std::vector<Input> inputs;
  std::vector<Output> outputs;
  std::vector<std::string> removals;  // stale outputs removed at Commit()
  std::vector<Staging> stagings;
  std::vector<fs::path> created_folders;  // Deepest last.
  bool committed = false;
  int number = 0;

  const Staging& StagingFor(const fs::path& folder, const std::string& blame);
  std::string StageImpl(const std::string& path, const std::string& option,
                        const std::string& mode_from, bool replacement);
};

namespace {
std::atomic<int> g_transactions{0};

// Whether `a` and `b` name the same file (both exist), or the same path once made absolute and
// normal (when one does not exist yet).
bool SameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  if (fs::equivalent(a, b, ec)) return true;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec), ec);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b, ec), ec);
  return !ca.empty() && ca == cb;
}
}  // namespace

OutputTransaction::OutputTransaction() : impl_(std::make_unique<Impl>()) {
  impl_->number = g_transactions++;
  std::random_device device;
  std::mt19937_64 rng(
      (static_cast<std::uint64_t>(device()) << 32) ^ device() ^
      static_cast<std::uint64_t>(std::chrono::system_clock::now().time_since_epoch().count()));
  char id[40];
  std::snprintf(id, sizeof id, "%016llx%08lx", static_cast<unsigned long long>(rng()),
                static_cast<unsigned long>(::getpid()));
  run_id_ = id;
}

OutputTransaction::~OutputTransaction() {
  if (!impl_->committed) Abandon();
}

void OutputTransaction::AddInput(const std::string& path, const std::string& what) {
  if (!path.empty()) impl_->inputs.push_back({path, what});
}

std::vector<std::string> OutputTransaction::outputs() const {
  std::vector<std::string> out;
  for (const Impl::Output& o : impl_->outputs) out.push_back(o.final);
  return out;
}

const OutputTransaction::Impl::Staging& OutputTransaction::Impl::StagingFor(
    const fs::path& folder, const std::string& blame) {
  for (const Staging& s : stagings)
    if (s.folder == folder) return s;
  std::error_code ec;
  // Create the missing folders, deepest last, remembering them for Abandon().
  std::vector<fs::path> missing;
  for (fs::path p = folder; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (!fs::create_directory(*it, ec) && ec)
      throw InputError(blame, "",
                       "cannot create the output folder " + it->string() + ": " + ec.message(),
                       "choose another output path");
    created_folders.push_back(*it);
  }
  if (!fs::is_directory(folder, ec))
    throw InputError(blame, "",
                     "the output folder " + folder.string() + " exists and is not a folder",
                     "choose another output path");
  RecoverOutputs(folder.string());
  const fs::path staging = folder / (std::string(kStagingPrefix) + std::to_string(::getpid()) +
                                     "-" + std::to_string(number));
  if (::mkdir(staging.c_str(), 0700) != 0 && errno != EEXIST)
    throw InputError(
        blame, "", "the output folder " + folder.string() + " is not writable: " + ErrnoText(errno),
        "choose another output path");
  if (!stagings.empty()) {
    // A secondary staging folder: recovery finds the transaction's journal through this.
    const std::string journal = (stagings.front().staging / kJournal).string();
    WriteNewFile((staging / kPrimary).string(), journal, 0600, blame);
  }
  stagings.push_back({folder, staging});
  return stagings.back();
}

std::string OutputTransaction::Impl::StageImpl(const std::string& path, const std::string& option,
                                               const std::string& mode_from, bool replacement) {
  const std::string blame = option.empty() ? path : option;
  if (committed) throw std::logic_error("OutputTransaction: Stage after Commit");
  if (path.empty()) throw InputError(blame, "", "the output path is empty", "give a file name");
  std::error_code ec;
  const fs::path final = fs::absolute(path, ec).lexically_normal();
  if (final.filename().empty() || fs::is_directory(final, ec))
    throw InputError(blame, "", "'" + path + "' names a folder, not a file", "give a file name");
  if (const std::string kind = NotARegularFile(final.string()); !kind.empty())
    throw InputError(blame, "",
                     "'" + path + "' is " + kind +
                         ", not a regular file; an output only replaces a regular file",
                     "give the path of a file");
  if (!replacement) {
    for (const Input& in : inputs)
      if (SameFile(final, in.path))
        throw InputError(
            blame, "",
            "the output '" + path + "' would overwrite the " + in.what + " '" + in.path + "'",
            "write the output to another file");
  }
  for (const Output& o : outputs)
    if (SameFile(final, o.final))
      throw InputError(blame, "", "the output '" + path + "' is also written as " + o.final,
                       "give each output its own path");
  const Staging& s = StagingFor(final.parent_path(), blame);
  Output out;
  out.final = final.string();
  out.staged = (s.staging / final.filename()).string();
  out.option = option;
  out.mode_from = mode_from;
  outputs.push_back(out);
  return out.staged;
}

std::string OutputTransaction::Stage(const std::string& path, const std::string& option,
                                     const std::string& mode_from) {
  return impl_->StageImpl(path, option, mode_from, false);
}

std::string OutputTransaction::StageReplacement(const std::string& path,
                                                const std::string& option) {
  return impl_->StageImpl(path, option, "", true);
}

void OutputTransaction::Write(const std::string& path, const std::string& option,
                              const std::string& bytes, const std::string& mode_from) {
  const std::string staged = Stage(path, option, mode_from);
  const Impl::Output& out = impl_->outputs.back();
  // Created with the final mode: the replaced file's, or the default one.
  mode_t mode = 0666;
  struct stat st {};
  const std::string& source = out.mode_from.empty() ? out.final : out.mode_from;
  if (::stat(source.c_str(), &st) == 0) mode = st.st_mode & 07777;
  WriteNewFile(staged, bytes, mode, path);
}

void OutputTransaction::Remove(const std::string& path, const std::string& option) {
  Impl& m = *impl_;
  const std::string blame = option.empty() ? path : option;
  if (m.committed) throw std::logic_error("OutputTransaction: Remove after Commit");
  std::error_code ec;
  const fs::path final = fs::absolute(path, ec).lexically_normal();
  const fs::file_status st = fs::symlink_status(final, ec);
  if (!fs::exists(st)) return;
  if (!fs::is_regular_file(st))
    throw InputError(blame, "",
                     "'" + path + "' is in the way of this run's outputs and is not a regular file",
                     "move it away, then run again");
  for (const Impl::Input& in : m.inputs)
    if (SameFile(final, in.path))
      throw InputError(blame, "",
                       "'" + path +
                           "' is an output of an earlier run to be removed, but it is the " +
                           in.what + " of this one",
                       "write the outputs to another folder");
  m.removals.push_back(final.string());
}

void OutputTransaction::Commit() {
  Impl& m = *impl_;
  if (m.committed) return;
  // 1. Every staged file whole and on disk, with the mode and owner of what it replaces.
  for (const Impl::Output& o : m.outputs) {
    SyncFile(o.staged, 1);
    struct stat st {};
    const std::string& source = o.mode_from.empty() ? o.final : o.mode_from;
    if (::stat(source.c_str(), &st) == 0) {
      if (::chmod(o.staged.c_str(), st.st_mode & 07777) != 0)
        throw InputError(o.final, "", "cannot set the output's permissions: " + ErrnoText(errno));
      // Keeping the owner needs privileges when it is another user's file; then the new file is
      // the caller's, as any editor's save would be.
      if (::chown(o.staged.c_str(), st.st_uid, st.st_gid) != 0 && errno != EPERM) {
        throw InputError(o.final, "", "cannot set the output's owner: " + ErrnoText(errno));
      }
    }
  }
  for (const Impl::Staging& s : m.stagings)
    if (const int error = SyncPath(s.staging.string(), true))
      throw InputError(s.folder.string(), "",
                       "cannot flush the staged outputs: " + ErrnoText(error));
  if (m.outputs.empty()) {
    Abandon();
    m.committed = true;
    return;
  }
  // An output path that became something else than a regular file since Stage() (a device node
  // made meanwhile) is refused before the commit point: rename() would replace it.
  for (const Impl::Output& o : m.outputs)
    if (const std::string kind = NotARegularFile(o.final); !kind.empty())
      throw InputError(
          o.final, "",
          "the output path is now " + kind + ", not a regular file; nothing was written",
          "give the path of a file");
  // 2. The commit point: the journal, written whole under a temporary name and renamed.
  std::string journal = "pandora-journal 1\n";
  for (const Impl::Output& o : m.outputs) journal += o.staged + "\t" + o.final + "\n";
  for (const std::string& r : m.removals) journal += std::string(kRemoved) + "\t" + r + "\n";
  const fs::path primary = m.stagings.front().staging;
  const std::string journal_tmp = (primary / "JOURNAL.tmp").string();
  const std::string journal_path = (primary / kJournal).string();
  WriteNewFile(journal_tmp, journal, 0600, m.outputs.front().final);
  if (::rename(journal_tmp.c_str(), journal_path.c_str()) != 0)
    throw InputError(m.outputs.front().final, "", "cannot commit the outputs: " + ErrnoText(errno));
  SyncPath(primary.string(), true);
  m.committed = true;
  MaybeCrash("after-journal");
  // 3. Into place. From here on, a failure is finished by RecoverOutputs on the next run.
  for (const Impl::Output& o : m.outputs) {
    if (::rename(o.staged.c_str(), o.final.c_str()) != 0)
      throw InputError(o.final, "",
                       "cannot move the output into place: " + ErrnoText(errno) +
                           "; the next pandora run in this folder finishes it",
                       "check the output folder's permissions");
    MaybeCrash("after-first-rename");
  }
  std::error_code ec;
  for (const std::string& r : m.removals) fs::remove(r, ec);
  for (const Impl::Staging& s : m.stagings) SyncPath(s.folder.string(), true);
  for (std::size_t i = 1; i < m.stagings.size(); ++i) fs::remove_all(m.stagings[i].staging, ec);
  fs::remove_all(primary, ec);
}

void OutputTransaction::Abandon() noexcept {
  Impl& m = *impl_;
  std::error_code ec;
  if (!m.committed) {
    for (const Impl::Staging& s : m.stagings) fs::remove_all(s.staging, ec);
    // Folders this transaction created, deepest first, when nothing else was put there.
    for (auto it = m.created_folders.rbegin(); it != m.created_folders.rend(); ++it)
      if (fs::is_empty(*it, ec)) fs::remove(*it, ec);
  }
  m.stagings.clear();
  m.outputs.clear();
  m.removals.clear();
  m.created_folders.clear();
}

}  // namespace pandora
