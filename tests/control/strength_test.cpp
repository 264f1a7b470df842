// A target's strength track (control/strength.h): values between and beyond its keys, and the keys' checks.
#include "control/strength.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ff::control {
namespace {

TEST(StrengthTrack, InterpolatesLinearlyAndHoldsTheEndValues) {
  StrengthTrack s;
  EXPECT_EQ(s.at(0.0), 1.0f);  // no keys: full strength
  EXPECT_EQ(s.at(1e6), 1.0f);
  s.keys = {{1.0, 1.0f}, {2.0, 0.0f}, {4.0, 0.5f}};
  EXPECT_EQ(s.at(0.0), 1.0f);
  EXPECT_EQ(s.at(1.0), 1.0f);
  EXPECT_FLOAT_EQ(s.at(1.25), 0.75f);
  EXPECT_EQ(s.at(2.0), 0.0f);  // exactly 0 at a key of 0: the controller then adds nothing
  EXPECT_FLOAT_EQ(s.at(3.0), 0.25f);
  EXPECT_EQ(s.at(4.0), 0.5f);
  EXPECT_EQ(s.at(100.0), 0.5f);
}

TEST(StrengthTrack, KeysMustBeLaterEachTimeAndInRange) {
  StrengthTrack s;
  s.keys = {{1.0, 1.0f}, {2.0, 0.0f}};
  EXPECT_TRUE(s.validate("targets[0]").ok());
  s.keys[1].time = 1.0;
  Status st = s.validate("targets[0]");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("targets[0].strength[1].time"), std::string::npos) << st.error().message;
  s.keys[1].time = 2.0;
  s.keys[1].value = 1.5f;
  st = s.validate("targets[0]");
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.error().message.find("targets[0].strength[1].value"), std::string::npos) << st.error().message;
  s.keys[1].value = NAN;
  EXPECT_FALSE(s.validate("targets[0]").ok());
}

}  // namespace
}  // namespace ff::control
