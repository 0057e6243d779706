// Self-calibration of a whole session (issue 15) on the held-out demo child, whose head leans
// beyond the upright face cascade's reach (the portrait is tilted 13 degrees): the rotated
// search finds the faces that the upright searches lose, so fewer ticks are searched for the
// same number of multi-camera ticks, and the calibration converges either way.

#include "dreamsense/self_calibration/session.hpp"

#include <gtest/gtest.h>

#include "held_out_session.hpp"

namespace dreamsense::self_calibration {
namespace {

TEST(SessionSelfCalibration, RolledSearchFindsATiltedChildsFaceInFewerTicks) {
  const auto dir = held_out_child_session();
  ASSERT_FALSE(dir.empty());
  SessionSelfCalibrationOptions upright;
  upright.rolled_search_min_deg = 0;
  const auto a = self_calibrate_session(dir, upright);
  ASSERT_TRUE(a) << a.error().to_string();
  const auto b = self_calibrate_session(dir, SessionSelfCalibrationOptions{});
  ASSERT_TRUE(b) << b.error().to_string();
  EXPECT_TRUE(a->face.converged()) << a->face.reason;
  EXPECT_TRUE(b->face.converged()) << b->face.reason;
  // Measured: 79 ticks searched upright only, 60 with the rotated search.
  EXPECT_LT(b->ticks_searched, a->ticks_searched - 10)
      << "upright " << a->ticks_searched << ", rotated " << b->ticks_searched;
  SessionSelfCalibrationOptions bad;
  bad.rolled_search_min_deg = -1;
  EXPECT_FALSE(bad.check());
}

}  // namespace
}  // namespace dreamsense::self_calibration
