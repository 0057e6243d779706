#include "dreamsense/eval/calibration_eval.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

namespace dreamsense::eval {
namespace {

TEST(DemoExtrinsicsEval, BuiltInCamerasAreRecoveredAndTheReportHasTheContractShape) {
  DemoExtrinsicsEvalOptions o;
  auto r = run_demo_extrinsics_eval(o);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->task, "calibration");
  EXPECT_EQ(r->dataset, "demo");
  EXPECT_GE(r->items, 3u);
  EXPECT_EQ(r->per_class.size(), r->items);
  EXPECT_LT(r->metrics["rot_err_deg_max"].get<double>(), 1.0);
  EXPECT_TRUE(r->metrics["fx_rel_err"].is_null());
  const auto j = r->to_json();
  EXPECT_EQ(j["dataset"]["items"], r->items);
  EXPECT_TRUE(j.contains("timing"));
}

TEST(DemoExtrinsicsEval, BadOptionsAndMissingSessionAreOneLineErrors) {
  DemoExtrinsicsEvalOptions o;
  o.points = 3;
  auto bad = run_demo_extrinsics_eval(o);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("--points >= 6"), std::string::npos);
  o = {};
  o.session = "/nonexistent/session";
  auto missing = run_demo_extrinsics_eval(o);
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().message, "/nonexistent/session: no calib/ folder (not a session?)");
}

TEST(ZhangCalibrationEval, PublishedCalibrationIsMatched) {
  std::filesystem::path dir =
      std::filesystem::path(DREAMSENSE_SOURCE_DIR) / "../shared/data/calib_zhang1998";
  if (const char* d = std::getenv("DREAMSENSE_DATA"))
    dir = std::filesystem::path(d) / "calib_zhang1998";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "Zhang's data absent (" << dir << ")";
  auto r = run_zhang_calibration_eval(dir);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->items, 5u);
  EXPECT_LT(r->metrics["fx_rel_err"].get<double>(), 0.01);
  EXPECT_TRUE(r->extra.contains("published"));
}

}  // namespace
}  // namespace dreamsense::eval
