#include "io/json_input.hpp"

#include <gtest/gtest.h>

#include <string>

namespace visvol {
namespace {

std::string nested(int levels, char open, char close) {
  return std::string(static_cast<std::size_t>(levels), open) + std::string(static_cast<std::size_t>(levels), close);
}

TEST(JsonInput, ParsesADocumentWithinTheLimit) {
  const Result<nlohmann::json> j = parse_json_input(R"({"a": [1, {"b": 2}]})", "x.json");
  ASSERT_TRUE(j.ok()) << j.status().message();
  EXPECT_EQ((*j)["a"][1]["b"], 2);
  // exactly the limit: 64 levels of arrays
  EXPECT_TRUE(parse_json_input(nested(kMaxJsonDepth, '[', ']'), "x.json").ok());
}

TEST(JsonInput, RefusesNestingBeyondTheLimitNamingTheInput) {
  for (const std::string& text :
       {nested(kMaxJsonDepth + 1, '[', ']'), "{\"k\":" + nested(2000000, '[', ']') + "}", std::string(3000000, '[')}) {
    const Result<nlohmann::json> j = parse_json_input(text, "deep.json");
    ASSERT_FALSE(j.ok());
    EXPECT_EQ(j.status().code(), Errc::invalid_argument);
    EXPECT_EQ(j.status().message(), "deep.json: JSON nested deeper than 64 levels");
  }
  // objects count as levels too
  std::string objects;
  for (int k = 0; k <= kMaxJsonDepth; ++k) objects += "{\"k\":";
  objects += "1" + std::string(kMaxJsonDepth + 1, '}');
  EXPECT_FALSE(parse_json_input(objects, "o.json").ok());
  EXPECT_TRUE(parse_json_input(objects, "o.json", kMaxJsonDepth + 2).ok());
}

// Brackets inside strings, escaped quotes among them, are text, not levels.
TEST(JsonInput, BracketsInStringsAreNotLevels) {
  const std::string brackets = nested(kMaxJsonDepth + 10, '[', ']') + nested(kMaxJsonDepth + 10, '{', '}');
  const std::string text = R"({"a": "\"[[\\", "b": ")" + brackets + R"(", "c": [[1]]})";
  const Result<nlohmann::json> j = parse_json_input(text, "s.json");
  ASSERT_TRUE(j.ok()) << j.status().message();
  EXPECT_EQ((*j)["a"], "\"[[\\");
  EXPECT_EQ((*j)["b"], brackets);
  EXPECT_EQ((*j)["c"][0][0], 1);
  // a quote escaped inside a string does not end it: the brackets after it are text
  EXPECT_TRUE(parse_json_input(R"(["\")" + nested(kMaxJsonDepth + 1, '[', ']') + R"("])", "e.json").ok());
}

// Many small objects in one array (a QGroundControl plan's mission items):
// the whole array, every object in it. (nlohmann's depth callback made this
// quadratic: 400,000 took 35 s; README.md, "Hostile input".)
TEST(JsonInput, ManyObjectsInOneArrayAreAllRead) {
  constexpr int kObjects = 200000;
  std::string text = "{\"items\":[";
  for (int k = 0; k < kObjects; ++k) text += k == 0 ? "{}" : ",{}";
  text += "]}";
  const Result<nlohmann::json> j = parse_json_input(text, "many.json");
  ASSERT_TRUE(j.ok()) << j.status().message();
  EXPECT_EQ((*j)["items"].size(), static_cast<std::size_t>(kObjects));
}

TEST(JsonInput, NamesTheInputOfTextThatIsNotJson) {
  const Result<nlohmann::json> j = parse_json_input("{\"a\": ", "cut.json");
  ASSERT_FALSE(j.ok());
  EXPECT_NE(j.status().message().find("cut.json: not valid JSON"), std::string::npos) << j.status().message();
}

TEST(JsonInput, ANulByteIsRefusedWhereverItIs) {
  // nlohmann stops at a NUL: a document followed by one and more text read as the document alone
  std::string after = "{\"a\": 1}";
  after.push_back('\0');
  after += "{\"features\": []}";
  const Result<nlohmann::json> j = parse_json_input(after, "nul.json");
  ASSERT_FALSE(j.ok());
  EXPECT_NE(j.status().message().find("nul.json: not valid JSON: a NUL byte at offset 8"), std::string::npos)
      << j.status().message();
  const std::string trailing = std::string("[1]") + std::string(4, '\0');
  EXPECT_FALSE(parse_json_input(trailing, "pad.json").ok());
}

}  // namespace
}  // namespace visvol
