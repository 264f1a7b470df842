// The strict JSON object reader (io/json_reader.h): types, absent keys, unknown keys with the closest valid key.
#include "io/json_reader.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::io {
namespace {
using nlohmann::json;

TEST(JsonReader, ClosestKey) {
  EXPECT_EQ(closest_key("iteratons", {"iterations", "cfl"}), "iterations");
  EXPECT_EQ(closest_key("xyz", {"iterations", "cfl"}), "");
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
}

TEST(JsonReader, ReadsEachTypeAndLeavesAbsentKeys) {
  const json j = json::parse(R"({"f": 0.5, "d": 2, "i": 3.0, "b": true, "s": "x", "v": [1, 2, 3], "u": 4})");
  JsonObject o(j, "p");
  float f = 9, absent = 7;
  double d = 0;
  int i = 0;
  bool b = false;
  std::string s;
  Vec3f v = Vec3f::Zero(), u = Vec3f::Zero();
  ASSERT_TRUE(o.check_object().ok());
  EXPECT_TRUE(o.get("f", f).ok());
  EXPECT_TRUE(o.get("d", d).ok());
  EXPECT_TRUE(o.get("i", i).ok());  // an integral float is an integer
  EXPECT_TRUE(o.get("b", b).ok());
  EXPECT_TRUE(o.get("s", s).ok());
  EXPECT_TRUE(o.get("v", v).ok());
  EXPECT_TRUE(o.get("u", u, /*allow_scalar=*/true).ok());
  EXPECT_TRUE(o.get("missing", absent).ok());
  EXPECT_EQ(f, 0.5f);
  EXPECT_EQ(d, 2.0);
  EXPECT_EQ(i, 3);
  EXPECT_TRUE(b);
  EXPECT_EQ(s, "x");
  EXPECT_EQ(v, Vec3f(1, 2, 3));
  EXPECT_EQ(u, Vec3f::Constant(4));
  EXPECT_EQ(absent, 7.0f);
  EXPECT_TRUE(o.finish().ok());
}

TEST(JsonReader, WrongTypesAndUnknownKeysNameTheirPath) {
  const json j = json::parse(R"({"n": "four", "k": 2.5, "big": 1e300, "vec": [1, 2], "iteratons": 1})");
  JsonObject o(j, "solver");
  double n = 0;
  int k = 0, iterations = 0;
  float big = 0;
  Vec3f vec;
  EXPECT_EQ(o.get("n", n).error().message, "solver.n: expected a number, got \"four\"");
  EXPECT_NE(o.get("k", k).error().message.find("expected an integer"), std::string::npos);
  EXPECT_NE(o.get("big", big).error().message.find("too large"), std::string::npos);
  EXPECT_NE(o.get("vec", vec).error().message.find("an array of 3 numbers"), std::string::npos);
  EXPECT_TRUE(o.get("iterations", iterations).ok());
  EXPECT_EQ(o.finish().error().message, "solver.iteratons: unknown key (did you mean 'iterations'?)");
  EXPECT_NE(JsonObject(json::array(), "x").check_object().error().message.find("expected a JSON object"),
            std::string::npos);
}

}  // namespace
}  // namespace ff::io
