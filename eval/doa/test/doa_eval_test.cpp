#include "dreamsense/eval/doa_eval.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dreamsense::sound_direction {
namespace {

TEST(DoaEval, ParsesAzimuthGrid) {
  DoaEvalOptions o;
  ASSERT_TRUE(parse_azimuth_grid("-30:30:15", o).has_value());
  EXPECT_EQ(o.azimuth_from_deg, -30);
  EXPECT_EQ(o.azimuth_step_deg, 15);
  EXPECT_FALSE(parse_azimuth_grid("-30:30", o).has_value());
  EXPECT_FALSE(parse_azimuth_grid("30:-30:5", o).has_value());
}

TEST(DoaEval, SmallGridMeetsTheContract) {
  DoaEvalOptions o;
  if (!std::filesystem::exists(o.clips_dir / "goforward.raw"))
    GTEST_SKIP() << "pocketsphinx-testdata is not installed";
  o.azimuth_from_deg = -50;
  o.azimuth_to_deg = 50;
  o.azimuth_step_deg = 50;
  o.placements = 1;
  auto r = run_doa_eval(o);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ(r->task, "doa");
  EXPECT_EQ(r->items, 3u);
  EXPECT_LE(r->metrics["mae_deg"].get<double>(), 5.0);
  EXPECT_LE(r->timing["cpu_fraction"].get<double>(), 0.05);
}

}  // namespace
}  // namespace dreamsense::sound_direction
