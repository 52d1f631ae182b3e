// What Pandora refuses to read, and the limits on coordinates and lengths (docs/robustness.md):
// special files, oversized and deeply nested JSON, huge coordinates, budgets beyond the machine,
// and the allocation cap on assimp.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <new>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/scene/scene.h"
#include "analysis/util/allocation_budget.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "tests/temp_dir.h"

namespace pandora {
namespace {

using json = nlohmann::json;
using testing::TempDir;

json BaseScene() {
  return json::parse(R"({
    "objects": [{"name": "block", "box": {"size": [1, 1, 1]}, "position": [0, 0, 0.5]}],
    "rigs": [{"name": "main", "cameras": [
      {"id": "c0", "position": [3, 0, 1], "look_at": [0, 0, 0.5], "resolution": [640, 480],
       "hfov_deg": 60}
    ]}],
    "study": {"region": {"box": {"min": [-1, -1, 0], "max": [1, 1, 2]}}}
  })");
}

// The InputError that parsing `scene` throws; a test failure when it throws none.
InputError ErrorFor(const std::string& text, const std::string& path = "scene.json") {
  try {
    ParseScene(text, path);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted";
  return InputError("", "", "");
}

InputError LoadError(const std::string& path) {
  try {
    LoadScene(path);
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted " << path;
  return InputError("", "", "");
}

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << (haystack)

TEST(InputFile, SpecialFilesAreRefusedBeforeReading) {
  TempDir dir;
  const std::string fifo = dir.File("scene.json");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // Opening a FIFO for reading blocks until a writer comes: the check must come first.
  EXPECT_CONTAINS(LoadError(fifo).reason(), "it is a FIFO");
  EXPECT_CONTAINS(LoadError("/dev/zero").reason(), "it is a character device");
  EXPECT_CONTAINS(LoadError(dir.path().string()).reason(), "it is a folder");
  EXPECT_CONTAINS(LoadError(dir.File("missing.json")).reason(), "no such file");
  EXPECT_CONTAINS(LoadError("").reason(), "the path is empty");
}

TEST(InputFile, MeshFilesAndTheFilesTheyNameMustBeRegular) {
  TempDir dir;
  ASSERT_EQ(::mkfifo(dir.File("fifo.obj").c_str(), 0600), 0);
  json scene = BaseScene();
  scene["objects"] = {{{"name", "m"}, {"mesh", {{"file", "fifo.obj"}}}}};
  dir.Write("scene.json", scene.dump());
  const InputError e = LoadError(dir.File("scene.json"));
  EXPECT_EQ(e.json_path(), "$.objects[0].mesh.file");
  EXPECT_CONTAINS(e.reason(), "it is a FIFO");
  // An OBJ whose material library is a FIFO: assimp is not allowed to open it (it would block);
  // the mesh loads without its materials.
  ASSERT_EQ(::mkfifo(dir.File("fifo.mtl").c_str(), 0600), 0);
  dir.Write("tri.obj", "mtllib fifo.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  scene["objects"] = {{{"name", "m"}, {"mesh", {{"file", "tri.obj"}}}}};
  dir.Write("scene.json", scene.dump());
  const Scene loaded = LoadScene(dir.File("scene.json"));
  ASSERT_EQ(loaded.objects.size(), 1u);
  EXPECT_EQ(loaded.objects[0].mesh.triangles.size(), 1u);
}

TEST(InputFile, OversizedFilesAreRefusedWithoutReadingThem) {
  TempDir dir;
  const std::string big = dir.File("big.json");
  dir.Write("big.json", "{");
  // A sparse file: 64 MiB + 1 byte on paper, nothing on disk.
  ASSERT_EQ(::truncate(big.c_str(), static_cast<off_t>(InputLimits::kJsonBytes + 1)), 0);
  const InputError e = LoadError(big);
  EXPECT_EQ(e.file(), big);
  EXPECT_CONTAINS(e.reason(), "at most 64.0 MiB is read");
  EXPECT_EQ(CheckInputFile(big, InputLimits::kJsonBytes + 1, "file"), InputLimits::kJsonBytes + 1);
}

TEST(InputFile, ReadInputFileReadsRegularFilesWhole) {
  TempDir dir;
  std::string bytes(100000, '\0');
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 7919 % 251);
  dir.Write("data.bin", bytes);
  EXPECT_EQ(ReadInputFile(dir.File("data.bin"), bytes.size(), "file"), bytes);
  EXPECT_THROW(ReadInputFile(dir.File("data.bin"), bytes.size() - 1, "file"), InputError);
}

TEST(JsonLimits, DeepNestingIsRefusedQuicklyWithTheLine) {
  // The outside audit: 200 KB of '[' ended in bad_alloc; 60 KB of nested objects took 25 s and 1.7
  // GB.
  const auto start = std::chrono::steady_clock::now();
  const InputError brackets = ErrorFor(std::string(200000, '['));
  EXPECT_EQ(brackets.json_path(), "$");
  EXPECT_CONTAINS(brackets.reason(), "nested deeper than 64 levels (line 1)");
  std::string objects;
  for (int i = 0; i < 6000; ++i) objects += "{\"a\":\n";
  const InputError nested = ErrorFor(objects + "1" + std::string(6000, '}'));
  EXPECT_CONTAINS(nested.reason(), "nested deeper than 64 levels (line 65)");
  // The check is one linear pass: far below a second for both (not a timing test; a hang fails).
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
}

TEST(JsonLimits, BracketsInsideStringsDoNotCount) {
  json scene = BaseScene();
  scene["rigs"][0]["cameras"][0]["name"] = std::string(1000, '[') + "\\\"{";
  EXPECT_NO_THROW(ParseScene(scene.dump(), "scene.json"));
  // Exactly the limit is fine; one more level is not.
  std::string at_limit = std::string(64, '[') + std::string(64, ']');
  EXPECT_NO_THROW(CheckJsonLimits(at_limit, "x.json"));
  EXPECT_THROW(CheckJsonLimits("[" + at_limit + "]", "x.json"), InputError);
}

TEST(SceneLimits, HugeCoordinatesNameTheirField) {
  json scene = BaseScene();
  scene["rigs"][0]["cameras"][0]["position"] = {1e19, 0, 1};
  InputError e = ErrorFor(scene.dump());
  EXPECT_EQ(e.json_path(), "$.rigs[0].cameras[0].position[0]");
  EXPECT_CONTAINS(e.reason(), "beyond the limit of 1e+07 m");

  scene = BaseScene();
  scene["objects"][0]["scale"] = 1e18;
  e = ErrorFor(scene.dump());
  EXPECT_EQ(e.json_path(), "$.objects[0]");
  EXPECT_CONTAINS(e.reason(), "the object reaches");

  scene = BaseScene();
  scene["study"]["voxel_size"] = 1e300;
  EXPECT_EQ(ErrorFor(scene.dump()).json_path(), "$.study.voxel_size");

  // Millimetres: 2e9 mm is 2e6 m, within the limit; 2e10 mm is not.
  scene = BaseScene();
  scene["units"] = "mm";
  scene["objects"][0]["position"] = {0, 0, 2e9};
  scene["objects"][0]["box"]["size"] = {1000, 1000, 1000};
  scene["study"]["region"]["box"] = {{"min", {-1000, -1000, 0}}, {"max", {1000, 1000, 2e9}}};
  scene["rigs"][0]["cameras"][0]["position"] = {3000, 0, 1000};
  EXPECT_NO_THROW(ParseScene(scene.dump(), "scene.json"));
  scene["objects"][0]["position"] = {0, 0, 2e10};
  EXPECT_EQ(ErrorFor(scene.dump()).json_path(), "$.objects[0].position[2]");
}

TEST(SceneLimits, CamerasAndViewsStayWithinReachOfTheScene) {
  // Geometry and region span a 2 x 2 x 2 m box: diagonal 2 sqrt(3) m, reach 1e4 times that.
  json scene = BaseScene();
  const Scene ok = ParseScene(scene.dump(), "scene.json");
  const double reach = SceneLimits::kReach * 2 * std::sqrt(3.0);
  EXPECT_NEAR(ok.MaxReach(), reach, 1e-9 * reach);
  const Vec3 centre = ok.ContentBounds().center();
  scene["rigs"][0]["cameras"][0]["position"] = {centre.x() + 0.99 * reach, centre.y(), centre.z()};
  EXPECT_NO_THROW(ParseScene(scene.dump(), "scene.json"));
  scene["rigs"][0]["cameras"][0]["position"] = {centre.x() + 1.01 * reach, centre.y(), centre.z()};
  InputError e = ErrorFor(scene.dump());
  EXPECT_EQ(e.json_path(), "$.rigs[0].cameras[0].position");
  EXPECT_CONTAINS(e.reason(), "from the centre of the scene");

  scene = BaseScene();
  scene["views"] = {{"far", {{"from", {2e5, 0, 1}}, {"at", {0, 0, 0}}}}};
  EXPECT_EQ(ErrorFor(scene.dump()).json_path(), "$.views.far.from");

  // Options: the same limits, blamed on the option.
  try {
    ok.CheckReach(Vec3(1e6, 0, 0), "--from", "the eye");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& error) {
    EXPECT_EQ(error.file(), "--from");
    EXPECT_CONTAINS(error.reason(), "the eye is 1e+06 m from the centre");
  }
  EXPECT_THROW(ok.CheckLength(1e19, "--max-move", "the move"), InputError);
  EXPECT_THROW(ok.CheckLength(std::nan(""), "--max-move", "the move"), InputError);
  EXPECT_NO_THROW(ok.CheckLength(30.0, "--max-move", "the move"));
}

TEST(SceneLimits, MemoryBudgetBeyondTheMachineIsRefused) {
  json scene = BaseScene();
  scene["study"]["memory_budget_mb"] = 1e308;
  const InputError e = ErrorFor(scene.dump());
  EXPECT_EQ(e.json_path(), "$.study.memory_budget_mb");
  EXPECT_CONTAINS(e.reason(), "more than this machine's memory");
  scene["study"]["memory_budget_mb"] = 64;
  EXPECT_NO_THROW(ParseScene(scene.dump(), "scene.json"));
}

TEST(AllocationBudget, RefusesRequestsBeyondItAndCreditsFrees) {
  if (!AllocationBudget::enforced()) GTEST_SKIP() << "not enforced under AddressSanitizer";
  AllocationBudget budget(1 << 20);
  std::vector<char>* small = new std::vector<char>(100000);
  EXPECT_FALSE(budget.exceeded());
  EXPECT_GE(budget.peak_bytes(), 100000u);
  EXPECT_THROW(std::vector<char>(2 << 20), std::bad_alloc);
  EXPECT_TRUE(budget.exceeded());
  delete small;
  // What was freed is available again: ten rounds of 900 KB fit in 1 MiB one at a time.
  for (int i = 0; i < 10; ++i) EXPECT_NO_THROW(std::vector<char>(900000));
}

TEST(AllocationBudget, OnlyBindsWhileOpen) {
  { AllocationBudget budget(1000); }
  EXPECT_NO_THROW(std::vector<char>(10 << 20));
}

}  // namespace
}  // namespace pandora
