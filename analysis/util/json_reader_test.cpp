#include "analysis/util/json_reader.h"

#include <gtest/gtest.h>

#include <string>

#include "analysis/util/error.h"

namespace pandora {
namespace {

// The InputError `read` throws: its JSON path and its whole message.
template <class Read>
std::pair<std::string, std::string> Failure(Read read) {
  try {
    read();
  } catch (const InputError& e) {
    return {e.json_path(), e.what()};
  }
  ADD_FAILURE() << "expected an InputError";
  return {};
}

const std::string kFile = "f.json";

TEST(JsonReader, PathsNameMembersAndElements) {
  EXPECT_EQ(JsonMemberPath("$", "rigs"), "$.rigs");
  EXPECT_EQ(JsonMemberPath("$.a", "odd key"), "$.a[\"odd key\"]");
  EXPECT_EQ(JsonMemberPath("$", "2d"), "$[\"2d\"]");
  EXPECT_EQ(JsonElementPath("$.rigs", 3), "$.rigs[3]");
}

TEST(JsonReader, DuplicateKeysAndMalformedTextNameWhere) {
  auto [path, what] = Failure([] { ParseJson(R"({"a": [1, {"b": 1, "b": 2}]})", kFile); });
  EXPECT_EQ(path, "$.a[1].b");
  EXPECT_NE(what.find("duplicate key 'b'"), std::string::npos) << what;
  std::tie(path, what) = Failure([] { ParseJson(R"({"a": [1, 2,, 3]})", kFile); });
  EXPECT_EQ(path, "$");
  EXPECT_NE(what.find("malformed JSON"), std::string::npos) << what;
  EXPECT_NE(what.find("inside $.a[2]"), std::string::npos) << what;
  std::tie(path, what) = Failure([] { ParseJson(R"({"x": 1e400})", kFile); });
  EXPECT_EQ(path, "$.x");
}

TEST(JsonReader, AccessorsCheckTypeAndRange) {
  const nlohmann::json j =
      ParseJson(R"({"n": 5, "s": "grid", "v": [1, 2, "x"], "b": true, "i": 2.5, "e": ""})", kFile);
  const JsonNode root = JsonNode::Root(j, kFile);
  EXPECT_EQ(root.Get("n").Number(0, 10), 5.0);
  EXPECT_TRUE(root.Get("b").Bool());
  EXPECT_EQ(root.Get("s").Enum({"uniform", "grid"}), "grid");
  EXPECT_FALSE(root.Find("missing").has_value());

  auto [path, what] = Failure([&] { root.Get("n").Number(6, 10); });
  EXPECT_EQ(path, "$.n");
  EXPECT_NE(what.find("must be between 6 and 10, got 5"), std::string::npos) << what;
  std::tie(path, what) = Failure([&] { root.Get("missing"); });
  EXPECT_EQ(path, "$");
  EXPECT_NE(what.find("missing required key 'missing'"), std::string::npos) << what;
  std::tie(path, what) = Failure([&] { root.Get("v").Numbers(3); });
  EXPECT_EQ(path, "$.v[2]");
  EXPECT_NE(what.find("expected a number, got a string"), std::string::npos) << what;
  std::tie(path, what) = Failure([&] { root.Get("v").Numbers(2); });
  EXPECT_EQ(path, "$.v");
  std::tie(path, what) = Failure([&] { root.Get("i").Integer(0, 9); });
  EXPECT_NE(what.find("expected an integer, got 2.5"), std::string::npos) << what;
  std::tie(path, what) = Failure([&] { root.Get("s").Enum({"uniform", "grit"}); });
  EXPECT_NE(what.find("did you mean 'grit'?"), std::string::npos) << what;
  std::tie(path, what) = Failure([&] { root.Get("e").NonEmptyString(); });
  EXPECT_EQ(path, "$.e");
  std::tie(path, what) = Failure([&] { root.Get("v").ArraySize(2, "values"); });
  EXPECT_NE(what.find("more than 2 values"), std::string::npos) << what;
}

TEST(JsonReader, UnknownKeysSuggestTheClosestAndOneOfRefusesTwo) {
  const nlohmann::json j = ParseJson(R"({"colr": 1, "to": 1, "by": 2})", kFile);
  const JsonNode root = JsonNode::Root(j, kFile);
  auto [path, what] = Failure([&] { root.CheckKeys({"color", "to", "by"}); });
  EXPECT_EQ(path, "$.colr");
  EXPECT_NE(what.find("did you mean 'color'?"), std::string::npos) << what;
  std::tie(path, what) = Failure([&] { root.OneOf({"to", "by"}, "move"); });
  EXPECT_EQ(path, "$.by");
  EXPECT_NE(what.find("both 'to' and 'by' are given"), std::string::npos) << what;
}

}  // namespace
}  // namespace pandora
