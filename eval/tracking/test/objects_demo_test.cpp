// The toys of the CLI test's demo session (seed 3, 4 s; label pipeline, fixture cli_demo) against
// its truth, with the shipped gallery (trained on seeds 901-903 only).

#include "dreamsense/eval/objects_session_eval.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace dreamsense::eval {
namespace {

ObjectsSessionEvalOptions options() {
  ObjectsSessionEvalOptions o;
  o.session = DREAMSENSE_CLI_DEMO_DIR;
  o.gallery = objects::default_gallery_path();
  return o;
}

TEST(ObjectsDemo, ToysFoundIdentifiedAndPlacedOnTheTable) {
  if (!std::filesystem::exists(std::filesystem::path(DREAMSENSE_CLI_DEMO_DIR) / "session.yaml"))
    GTEST_SKIP() << "the cli_demo fixture did not run";
  auto r = run_objects_session_eval(options());
  ASSERT_TRUE(r) << r.error().message;
  const auto& m = r->metrics;
  EXPECT_GE(m["object_track_mean_iou"].get<double>(), 0.75);
  EXPECT_LE(m["object_position_median_m"].get<double>(), 0.02);
  EXPECT_GE(m["object_identification_accuracy"].get<double>(), 0.95);
  EXPECT_LT(m["false_objects_per_frame"].get<double>(), 0.3);
  EXPECT_GT(r->items, 400u);  // 4 toys x 120 top frames
}

TEST(ObjectsDemo, AToyLeftOutOfTheGalleryIsRejectedOnlyByOurs) {
  if (!std::filesystem::exists(std::filesystem::path(DREAMSENSE_CLI_DEMO_DIR) / "session.yaml"))
    GTEST_SKIP() << "the cli_demo fixture did not run";
  auto o = options();
  o.unknown = 2;
  o.max_frames = 40;
  auto ours = run_objects_session_eval(o);
  ASSERT_TRUE(ours) << ours.error().message;
  EXPECT_GE(ours->metrics["unknown_reject_rate"].get<double>(), 0.9);
  EXPECT_GE(ours->metrics["object_identification_accuracy"].get<double>(), 0.95);
  o.identifier = "hog_svm";
  auto seed = run_objects_session_eval(o);
  ASSERT_TRUE(seed) << seed.error().message;
  EXPECT_LE(seed->metrics["unknown_reject_rate"].get<double>(), 0.1);  // no rejection at all
}

TEST(ObjectsDemo, BadInput) {
  auto o = options();
  o.session = "/nonexistent/session";
  EXPECT_FALSE(run_objects_session_eval(o));
  o = options();
  o.gallery = "/nonexistent/gallery.yaml";
  if (std::filesystem::exists(std::filesystem::path(DREAMSENSE_CLI_DEMO_DIR) / "session.yaml")) {
    auto r = run_objects_session_eval(o);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().message.find("gallery.yaml"), std::string::npos);
  }
  o = options();
  o.identifier = "sift";
  EXPECT_FALSE(run_objects_session_eval(o));
}

}  // namespace
}  // namespace dreamsense::eval
