#pragma once
// The held-out demo child's 20 s session (seed 502), cached for the self-calibration tests: its
// head leans beyond the upright face cascade's reach (the portrait is tilted 13 degrees).

#include "dreamsense/sim/demo_children.hpp"
#include "dreamsense/testing/demo_cache.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dreamsense::self_calibration {

inline std::filesystem::path held_out_child_session() {
  sim::DemoOptions o;
  o.seed = 502;
  o.duration_s = 20;
  o.child = sim::kHeldOutDemoChild;
  auto dir = testing::cached_demo_session("held_out_child_s502", o);
  EXPECT_TRUE(dir) << dir.error().to_string();
  return dir ? *dir : std::filesystem::path();
}

}  // namespace dreamsense::self_calibration
