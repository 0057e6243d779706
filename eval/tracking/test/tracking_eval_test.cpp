// OPE scoring and the harness on synthetic sequences.

#include "dreamsense/eval/tracking_eval.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

#include "../../../modalities/objects/test/synthetic_sequence.hpp"

namespace dreamsense::eval {
namespace {
namespace fs = std::filesystem;

TEST(Scores, SuccessAucPrecisionAndMeans) {
  TrackRun run;
  run.iou = {1.0, 0.5, 0.0, 0.76};
  run.centre_error = {0, 10, 50, 20};
  run.frames = 5;
  run.seconds = 0.5;
  const TrackScores s = score_run(run);
  ASSERT_EQ(s.success.size(), 21u);
  EXPECT_DOUBLE_EQ(s.success[0], 0.75);  // IoU > 0
  EXPECT_DOUBLE_EQ(s.success[10], 0.5);  // IoU > 0.5: 1.0 and 0.76
  EXPECT_DOUBLE_EQ(s.success[20], 0.0);  // IoU > 1
  // AUC = mean over thresholds: 1.0 contributes 20/21, 0.5 10/21, 0.76 16/21, 0 nothing.
  EXPECT_NEAR(s.auc, (20.0 + 10.0 + 16.0) / 21.0 / 4.0, 1e-12);
  EXPECT_DOUBLE_EQ(s.precision20, 0.75);  // <= 20 px
  EXPECT_NEAR(s.mean_iou, 2.26 / 4, 1e-12);
  EXPECT_DOUBLE_EQ(s.mean_center_error_px, 20.0);
  EXPECT_DOUBLE_EQ(s.fps, 10.0);
}

TEST(RunTracker, StartsAtTheFirstLabelledFrameAndSkipsUnlabelled) {
  dreamsense::objects::testing::SyntheticOptions o;
  o.frames = 20;
  o.frame_size = {320, 240};
  o.target_size = {40, 50};
  const auto s = dreamsense::objects::testing::make_synthetic_sequence(o);
  std::vector<std::optional<cv::Rect2d>> truth(s.boxes.begin(), s.boxes.end());
  truth[0].reset();  // the first labelled frame is frame 1
  for (size_t i = 3; i < truth.size(); i += 2) truth[i].reset();
  auto r = run_tracker("dreamsense", s.frames, truth);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->frames, 19u);     // frames 1..19
  EXPECT_EQ(r->iou.size(), 9u);  // labelled frames after frame 1: 2, 4, 6, ..., 18
  EXPECT_GT(score_run(*r).mean_iou, 0.8);
  std::vector<std::optional<cv::Rect2d>> none(s.frames.size());
  EXPECT_FALSE(run_tracker("dreamsense", s.frames, none));
  EXPECT_FALSE(run_tracker("nosuch", s.frames, truth));
}

TEST(TrackingEval, AllTrackersInOneRunWithTheCliKeys) {
  const fs::path dir = fs::temp_directory_path() / "ds_trk_eval_seq";
  fs::remove_all(dir);
  fs::create_directories(dir / "img");
  dreamsense::objects::testing::SyntheticOptions o;
  o.frames = 12;
  o.frame_size = {320, 240};
  o.target_size = {40, 50};
  const auto s = dreamsense::objects::testing::make_synthetic_sequence(o);
  std::ofstream gt(dir / "groundtruth_rect.txt");
  for (size_t i = 0; i < s.frames.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "%04zu.png", i + 1);
    cv::imwrite((dir / "img" / name).string(), s.frames[i]);
    gt << s.boxes[i].x + 1 << '\t' << s.boxes[i].y + 1 << '\t' << s.boxes[i].width << '\t'
       << s.boxes[i].height << '\n';
  }
  gt.close();
  TrackingEvalOptions eo;
  eo.dataset = "otb";
  eo.dir = dir;
  auto r = run_tracking_eval(eo);
  ASSERT_TRUE(r) << r.error().message;
  const auto j = r->to_json();
  EXPECT_EQ(j["task"], "tracking");
  EXPECT_EQ(j["dataset"]["items"], 11);
  for (const auto& name : {"ct", "dreamsense", "kcf", "csrt", "mil", "mosse", "medianflow"})
    for (const auto& key : {"auc", "precision20", "mean_iou", "mean_center_error_px", "fps"})
      EXPECT_TRUE(j["metrics"][name].contains(key)) << name << "." << key;
  EXPECT_GT(j["metrics"]["dreamsense"]["auc"].get<double>(), 0.6);
  TrackingEvalOptions bad = eo;
  bad.trackers = {"nosuch"};
  auto e = run_tracking_eval(bad);
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().message.find("unknown tracker"), std::string::npos);
  bad = eo;
  bad.dataset = "vot";
  EXPECT_FALSE(run_tracking_eval(bad));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dreamsense::eval
