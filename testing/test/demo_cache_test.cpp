#include "dreamsense/testing/demo_cache.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

namespace dreamsense::testing {
namespace {

namespace fs = std::filesystem;

sim::DemoOptions short_demo() {
  sim::DemoOptions o;
  o.seed = 7;
  o.duration_s = 0.3;
  return o;
}

TEST(DemoCache, GeneratesOnceAndReusesTheSession) {
  auto first = cached_demo_session("cache_test_s7", short_demo());
  ASSERT_TRUE(first) << first.error().to_string();
  ASSERT_TRUE(fs::exists(*first / "session.yaml"));
  const auto made = fs::last_write_time(*first / "session.yaml");
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  auto second = cached_demo_session("cache_test_s7", short_demo());
  ASSERT_TRUE(second) << second.error().to_string();
  EXPECT_EQ(*second, *first);
  EXPECT_EQ(fs::last_write_time(*second / "session.yaml"), made) << "generated twice";
}

TEST(DemoCache, AnUnfinishedSessionIsGeneratedAgain) {
  auto dir = cached_demo_session("cache_test_unfinished", short_demo());
  ASSERT_TRUE(dir) << dir.error().to_string();
  // What a test killed during the generation leaves: the session without its `.done` mark.
  fs::remove(dir->parent_path() / "cache_test_unfinished.done");
  fs::remove(*dir / "session.yaml");
  auto again = cached_demo_session("cache_test_unfinished", short_demo());
  ASSERT_TRUE(again) << again.error().to_string();
  EXPECT_TRUE(fs::exists(*again / "session.yaml"));
}

}  // namespace
}  // namespace dreamsense::testing
