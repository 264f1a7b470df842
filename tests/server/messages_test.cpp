// Client messages: the commands the viewer sends are accepted, everything malformed is refused (never thrown).
#include "server/messages.h"

#include <gtest/gtest.h>

namespace ff::server {
namespace {

TEST(Messages, Commands) {
  auto c = parse_command(R"({"type":"pose","target":1,"translate":[0.1,0,-0.2],"rotate":[0,45,0],"scale":1.5})");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->kind, Command::Kind::Pose);
  EXPECT_EQ(c->target, 1u);
  EXPECT_FLOAT_EQ(c->pose.translate.x(), 0.1f);
  EXPECT_FLOAT_EQ(c->pose.rotate_deg.y(), 45.0f);
  EXPECT_FLOAT_EQ(c->pose.scale, 1.5f);
  c = parse_command(R"({"type":"pose","target":0,"translate":[1,2,3]})");
  ASSERT_TRUE(c);
  EXPECT_FLOAT_EQ(c->pose.scale, 1.0f);
  c = parse_command(R"({"type":"controller","name":"pbfc"})");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->name, "pbfc");
  EXPECT_EQ(parse_command(R"({"type":"pause"})")->kind, Command::Kind::Pause);
  EXPECT_EQ(parse_command(R"({"type":"restart"})")->kind, Command::Kind::Restart);
  EXPECT_EQ(parse_command(R"({"type":"mesh","target":0,"mesh":2})")->mesh, 2u);
  c = parse_command(R"({"type":"surface","on":true})");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->kind, Command::Kind::Surface);
  EXPECT_TRUE(c->on);
  EXPECT_FALSE(parse_command(R"({"type":"surface","on":false})")->on);
  c = parse_command(R"({"type":"seek","frame":12})");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->kind, Command::Kind::Seek);
  EXPECT_EQ(c->frame, 12u);
  EXPECT_FALSE(parse_command(R"({"type":"seek","frame":-1})"));
  EXPECT_FALSE(parse_command(R"({"type":"seek"})"));
}

TEST(Messages, GarbageIsRefused) {
  for (const char* bad :
       {"", "garbage", "{", "[]", "null", "42", R"({"type":1})", R"({"type":"launch"})", R"({"no":"type"})",
        R"({"type":"pose"})", R"({"type":"pose","target":-1,"translate":[0,0,0]})",
        R"({"type":"pose","target":0,"translate":[0,0]})", R"({"type":"pose","target":0,"translate":["a",0,0]})",
        R"({"type":"pose","target":0,"translate":[1e300,0,0]})", R"({"type":"pose","target":0,"translate":[0,0,0],"scale":0})",
        R"({"type":"pose","target":0.5,"translate":[0,0,0]})", R"({"type":"controller"})", R"({"type":"controller","name":7})",
        R"({"type":"mesh","target":0})", R"({"type":"surface"})", R"({"type":"surface","on":1})",
        "\xff\xfe\x00garbage"})
    EXPECT_FALSE(parse_command(bad)) << bad;
  EXPECT_FALSE(parse_command(std::string(kMaxClientMessage + 1, ' ')));
}

}  // namespace
}  // namespace ff::server
