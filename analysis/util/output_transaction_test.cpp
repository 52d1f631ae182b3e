// OutputTransaction: outputs appear together or not at all, never replace an input, keep the mode
// of what they replace, leave no litter, and a commit killed half way is finished by the next run.
#include "analysis/util/output_transaction.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "tests/temp_dir.h"

namespace pandora {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

std::string Read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The names in `folder`, sorted, as one string ("a b c").
std::string Listing(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(folder))
    names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : " ") + n;
  return out;
}

mode_t Mode(const fs::path& path) {
  struct stat st {};
  EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
  return st.st_mode & 07777;
}

TEST(OutputTransaction, OutputsAppearTogetherAtCommit) {
  TempDir dir;
  dir.Write("b.txt", "old b");
  OutputTransaction t;
  t.Write(dir.File("a.txt"), "--out", "new a");
  t.Write(dir.File("b.txt"), "--out", "new b");
  // Nothing is visible before the commit: a.txt does not exist yet, b.txt is the old one.
  EXPECT_FALSE(fs::exists(dir.File("a.txt")));
  EXPECT_EQ(Read(dir.File("b.txt")), "old b");
  t.Commit();
  EXPECT_EQ(Read(dir.File("a.txt")), "new a");
  EXPECT_EQ(Read(dir.File("b.txt")), "new b");
  EXPECT_EQ(Listing(dir.path()), "a.txt b.txt");  // no staging folder, no journal left
  EXPECT_EQ(t.run_id().size(), 24u);
}

TEST(OutputTransaction, AbandonedOutputsLeaveNothingBehind) {
  TempDir dir;
  dir.Write("b.txt", "old b");
  {
    OutputTransaction t;
    t.Write(dir.File("new/deeper/a.txt"), "--out", "new a");
    t.Write(dir.File("b.txt"), "--out", "new b");
    // No Commit(): an error in the command unwinds through here.
  }
  EXPECT_EQ(Listing(dir.path()), "b.txt");  // the folders it created are gone too
  EXPECT_EQ(Read(dir.File("b.txt")), "old b");
  // A folder that existed before, or that holds something else now, stays.
  fs::create_directories(dir.path() / "keep");
  {
    OutputTransaction t;
    t.Write(dir.File("keep/x/a.txt"), "--out", "a");
  }
  EXPECT_TRUE(fs::is_directory(dir.path() / "keep"));
  EXPECT_FALSE(fs::exists(dir.path() / "keep" / "x"));
}

TEST(OutputTransaction, OutputsNeverResolveToInputs) {
  TempDir dir;
  dir.Write("scene.json", "{}");
  fs::create_symlink(dir.File("scene.json"), dir.File("link.json"));
  fs::create_hard_link(dir.File("scene.json"), dir.File("hard.json"));
  fs::create_directories(dir.path() / "sub");
  for (const std::string& out : {dir.File("scene.json"), dir.File("link.json"),
                                 dir.File("hard.json"), dir.File("sub/../scene.json")}) {
    OutputTransaction t;
    t.AddInput(dir.File("scene.json"), "scene file");
    try {
      t.Stage(out, "--out");
      ADD_FAILURE() << "accepted " << out;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "--out");
      EXPECT_NE(e.reason().find("would overwrite the scene file"), std::string::npos) << e.reason();
    }
  }
  // Two outputs on one path, and an output that is a folder.
  OutputTransaction t;
  t.Stage(dir.File("a.txt"), "--out");
  EXPECT_THROW(t.Stage(dir.File("sub/../a.txt"), "--json"), InputError);
  EXPECT_THROW(t.Stage(dir.File("sub"), "--out"), InputError);
  // The one deliberate replacement.
  OutputTransaction accept;
  accept.AddInput(dir.File("scene.json"), "scene file");
  EXPECT_NO_THROW(accept.StageReplacement(dir.File("scene.json"), ""));
}

TEST(OutputTransaction, ReplacedFilesKeepTheirModeAndBackupsTheSource) {
  TempDir dir;
  dir.Write("scene.json", "scene");
  ASSERT_EQ(::chmod(dir.File("scene.json").c_str(), 0600), 0);
  dir.Write("shared.json", "old");
  ASSERT_EQ(::chmod(dir.File("shared.json").c_str(), 0664), 0);
  const mode_t old_mask = ::umask(022);
  OutputTransaction t;
  t.Write(dir.File("scene.json.bak"), "", "scene", dir.File("scene.json"));
  t.Write(dir.File("shared.json"), "", "new");
  WriteFileAtomically(t.StageReplacement(dir.File("scene.json"), ""), "new scene");
  t.Commit();
  ::umask(old_mask);
  EXPECT_EQ(Mode(dir.File("scene.json.bak")), 0600u);  // not world-readable: the scene file was not
  EXPECT_EQ(Mode(dir.File("scene.json")), 0600u);
  EXPECT_EQ(Mode(dir.File("shared.json")), 0664u);  // the umask would have made it 0644
  EXPECT_EQ(Read(dir.File("scene.json")), "new scene");
}

// Runs `body` in a child process that is expected to kill itself (SIGKILL) inside Commit().
void RunKilledChild(const std::function<void()>& body, const char* crash_at) {
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::setenv("PANDORA_TEST_CRASH_AT", crash_at, 1);
    try {
      body();
    } catch (...) {
    }
    ::_exit(3);  // not reached when the hook fires
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "child exited normally with " << WEXITSTATUS(status);
  ASSERT_EQ(WTERMSIG(status), SIGKILL);
}

TEST(OutputTransaction, ACommitKilledAfterItsJournalIsFinishedByTheNextRun) {
  TempDir dir;
  TempDir other;
  dir.Write("a.txt", "old a");
  dir.Write("b.txt", "old b");
  auto write_all = [&] {
    OutputTransaction t;
    t.Write(dir.File("a.txt"), "--out", "new a");
    t.Write(dir.File("b.txt"), "--out", "new b");
    t.Write(other.File("c.txt"), "--out", "new c");  // a second folder
    t.Commit();
  };
  RunKilledChild(write_all, "after-first-rename");
  // Killed between two renames: a.txt is new, b.txt still old, the journal is there.
  EXPECT_EQ(Read(dir.File("a.txt")), "new a");
  EXPECT_EQ(Read(dir.File("b.txt")), "old b");
  EXPECT_NE(Listing(dir.path()).find(".pandora-staging-"), std::string::npos);
  // Any later run that writes in the folder (or reads from it) finishes the commit first.
  RecoverOutputs(dir.path().string());
  EXPECT_EQ(Read(dir.File("b.txt")), "new b");
  EXPECT_EQ(Read(other.File("c.txt")), "new c");
  EXPECT_EQ(Listing(dir.path()), "a.txt b.txt");
  EXPECT_EQ(Listing(other.path()), "c.txt");
}

TEST(OutputTransaction, ACommitKilledBeforeItsJournalIsRolledBack) {
  TempDir dir;
  TempDir other;
  dir.Write("a.txt", "old a");
  auto write_all = [&] {
    OutputTransaction t;
    t.Write(dir.File("a.txt"), "--out", "new a");
    t.Write(other.File("c.txt"), "--out", "new c");
    ::raise(SIGKILL);  // while the outputs are being written
  };
  RunKilledChild(write_all, "never");
  EXPECT_EQ(Read(dir.File("a.txt")), "old a");
  // The secondary folder's staging is found through either folder; both are swept.
  RecoverOutputs(other.path().string());
  EXPECT_EQ(Listing(other.path()), "");
  RecoverOutputs(dir.path().string());
  EXPECT_EQ(Listing(dir.path()), "a.txt");
  EXPECT_EQ(Read(dir.File("a.txt")), "old a");
}

TEST(OutputTransaction, StaleTemporariesOfDeadProcessesAreSwept) {
  TempDir dir;
  // A process id that is not running: a child that has exited and been reaped.
  const pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string stale = "fields.vdb.tmp-" + std::to_string(dead);
  const std::string live = "fields.vdb.tmp-" + std::to_string(::getppid());
  dir.Write(stale, "half a file");
  dir.Write(live, "another run's file in progress");
  dir.Write("notes.tmp-draft", "a user's file");
  OutputTransaction t;
  t.Write(dir.File("summary.json"), "--out", "{}");
  t.Commit();
  EXPECT_EQ(Listing(dir.path()), live + " notes.tmp-draft summary.json");
}

TEST(OutputTransaction, EmptyStagedOutputIsRefused) {
  TempDir dir;
  dir.Write("a.txt", "old");
  OutputTransaction t;
  const std::string staged = t.Stage(dir.File("a.txt"), "--out");
  std::ofstream(staged).close();  // a writer that produced nothing (a full disk)
  EXPECT_THROW(t.Commit(), InputError);
  EXPECT_EQ(Read(dir.File("a.txt")), "old");
}

}  // namespace
}  // namespace pandora
