// The error contract (analysis/util/error.h): no library spells a command-line flag, and every
// option a library names as {field} has its flag in the command line's one table (app/flags.h).
#include "app/flags.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace pandora::app {
namespace {

namespace fs = std::filesystem;

// The string literals of a C++ file (comments skipped), with the line each starts on.
std::vector<std::pair<int, std::string>> StringLiterals(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string t = ss.str();
  std::vector<std::pair<int, std::string>> out;
  int line = 1;
  for (std::size_t i = 0; i < t.size();) {
    if (t.compare(i, 2, "//") == 0) {
      i = t.find('\n', i);
      if (i == std::string::npos) break;
    } else if (t.compare(i, 2, "/*") == 0) {
      const std::size_t end = t.find("*/", i + 2);
      for (std::size_t k = i; k < std::min(end, t.size()); ++k) line += t[k] == '\n';
      i = end == std::string::npos ? t.size() : end + 2;
    } else if (t[i] == '"' || t[i] == '\'') {
      const char quote = t[i];
      std::size_t j = i + 1;
      while (j < t.size() && t[j] != quote && t[j] != '\n') j += t[j] == '\\' ? 2 : 1;
      if (quote == '"') out.emplace_back(line, t.substr(i + 1, j - i - 1));
      i = j + 1;
    } else {
      line += t[i] == '\n';
      ++i;
    }
  }
  return out;
}

// The library sources: everything below the front ends (app/*.cpp, python/, viewer/).
std::vector<std::string> LibrarySources() {
  std::vector<std::string> files;
  for (const char* dir : {"analysis", "volume", "render", "suggest", "app/session", "app/report"})
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      const std::string p = entry.path().string();
      const bool code = entry.path().extension() == ".cpp" || entry.path().extension() == ".h";
      if (code && p.find("_test.cpp") == std::string::npos) files.push_back(p);
    }
  files.push_back("app/suggest_options.cpp");  // shared by the command line, Python and the viewer
  return files;
}

TEST(ErrorContract, NoLibraryNamesACommandLineFlag) {
  const std::regex flag(R"((^|[^A-Za-z0-9-])--[a-z][a-z-]*)");
  const std::vector<std::string> files = LibrarySources();
  ASSERT_GT(files.size(), 100u);
  for (const std::string& file : files)
    for (const auto& [line, text] : StringLiterals(file))
      EXPECT_FALSE(std::regex_search(text, flag))
          << file << ":" << line << ": \"" << text
          << "\" names a flag; name the option's field as {field} (analysis/util/error.h)";
}

TEST(ErrorContract, EveryOptionALibraryNamesHasAFlag) {
  const std::regex placeholder(R"(\{([a-z][a-z0-9_]*)\})");
  std::set<std::string> named;
  for (const std::string& file : LibrarySources())
    for (const auto& [line, text] : StringLiterals(file))
      for (std::sregex_iterator m(text.begin(), text.end(), placeholder), end; m != end; ++m) {
        const std::string field = (*m)[1];
        named.insert(field);
        const std::vector<std::string>& without = FieldsWithoutFlag();
        EXPECT_TRUE(!CommandLineFlag(field).empty() ||
                    std::find(without.begin(), without.end(), field) != without.end())
            << file << ":" << line << ": {" << field
            << "} has no flag in app/flags.cpp (nor is it listed as a field no command sets)";
      }
  // The scan finds what the libraries name (suggest's limits, the render view, the report).
  for (const char* field : {"max_move", "max_rotate_deg", "cameras", "fov_deg", "view_width"})
    EXPECT_TRUE(named.count(field)) << field;
}

TEST(ErrorContract, CommandLineWritesFieldsAsFlags) {
  const InputError e("{max_rotate_deg}", "", "must be in [0, 180) with {max_move} >= 0",
                     "see {target_surfaces}; {unknown_field} and {Not} stay");
  const InputError cli = ForCommandLine(e);
  EXPECT_EQ(cli.file(), "--max-rotate");
  EXPECT_EQ(cli.reason(), "must be in [0, 180) with --max-move >= 0");
  EXPECT_EQ(cli.hint(), "see --target-surface; {unknown_field} and {Not} stay");
  EXPECT_EQ(ForCommandLine(InputError("{look_at}", "", "r")).file(), "look_at");
  EXPECT_STREQ(cli.what(),
               "--max-rotate: must be in [0, 180) with --max-move >= 0 (hint: see "
               "--target-surface; {unknown_field} and {Not} stay)");
  // One flag per field; the table names each field once.
  std::set<std::string> fields;
  for (const auto& [field, flag] : CommandLineFlags()) {
    EXPECT_TRUE(fields.insert(field).second) << field << " listed twice";
    EXPECT_EQ(flag.rfind("--", 0), 0u) << flag;
  }
}

TEST(ErrorContract, EveryFlagInTheTableIsACommandLineOption) {
  // The options the commands register: the first name of each add_option / add_flag literal
  // ("--quiet,-q" registers --quiet) in app/*_command.cpp and app/cli.cpp.
  std::set<std::string> registered;
  for (const auto& entry : fs::directory_iterator("app")) {
    const std::string name = entry.path().filename().string();
    const bool command =
        name.size() > 12 && name.compare(name.size() - 12, 12, "_command.cpp") == 0;
    if (!command && name != "cli.cpp") continue;
    for (const auto& [line, text] : StringLiterals(entry.path().string()))
      if (text.rfind("--", 0) == 0) registered.insert(text.substr(0, text.find(',')));
  }
  ASSERT_GT(registered.size(), 50u);
  for (const auto& [field, flag] : CommandLineFlags())
    EXPECT_TRUE(registered.count(flag))
        << "{" << field << "} -> " << flag << ": no command registers this flag";
}

}  // namespace
}  // namespace pandora::app
