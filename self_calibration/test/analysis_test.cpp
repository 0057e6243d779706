#include "dreamsense/self_calibration/analysis.hpp"

#include "dreamsense/gaze/fixation_yaw.hpp"
#include "dreamsense/gaze/gaze_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <optional>

namespace dreamsense::self_calibration {
namespace {
namespace fs = std::filesystem;

// A saved subject folder with the self-calibration's gaze.yaml (anatomical eyeballs).
fs::path saved_folder(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("ds_self_calibration_analysis_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  gaze::GazeModelFile m;
  m.right_eyeball = gaze::EyeballModel{{-0.031, 0, 0.0115}, 0.0105};
  m.left_eyeball = gaze::EyeballModel{{0.031, 0, 0.0115}, 0.0105};
  m.fixation_yaw = true;
  EXPECT_TRUE(gaze::write_gaze_model(dir / "gaze.yaml", m));
  return dir;
}

double saved_start_deg(const fs::path& dir) {
  auto m = gaze::read_gaze_model(dir / "gaze.yaml");
  EXPECT_TRUE(m) << m.error().message;
  return m ? m->fixation_yaw_start_deg : std::nan("");
}

TEST(SaveLearntFixationYaw, TheAnalysisCorrectionGoesIntoTheSavedFolder) {
  const fs::path dir = saved_folder("saved");
  nlohmann::json status = {{"status", "converged"}, {"saved_to", dir.string()}};
  runner::AnalysisSummary summary;
  summary.gaze_fixation_yaw_deg = -5.5;
  ASSERT_TRUE(save_learnt_fixation_yaw(status, summary));
  EXPECT_EQ(saved_start_deg(dir), -5.5);
  EXPECT_EQ(status.value("saved_fixation_yaw_deg", 0.0), -5.5);
  auto back = gaze::read_gaze_model(dir / "gaze.yaml");
  ASSERT_TRUE(back);
  EXPECT_TRUE(back->fixation_yaw);  // the rest of the file is kept
  EXPECT_TRUE(back->right_eyeball && back->left_eyeball);
  fs::remove_all(dir);
}

TEST(SaveLearntFixationYaw, NothingWrittenWithoutAFolderACorrectionOrAPlausibleOne) {
  const fs::path dir = saved_folder("nothing");
  runner::AnalysisSummary summary;
  summary.gaze_fixation_yaw_deg = 4.0;
  nlohmann::json not_saved = {{"status", "converged"}};  // no --save-subject
  ASSERT_TRUE(save_learnt_fixation_yaw(not_saved, summary));
  EXPECT_FALSE(not_saved.contains("saved_fixation_yaw_deg"));
  nlohmann::json status = {{"saved_to", dir.string()}};
  for (const std::optional<double> yaw : {std::optional<double>(), std::optional<double>(0.0),
                                          std::optional<double>(gaze::kMaxFixationYawDeg + 5)}) {
    summary.gaze_fixation_yaw_deg = yaw;
    ASSERT_TRUE(save_learnt_fixation_yaw(status, summary));
    EXPECT_EQ(saved_start_deg(dir), 0);
    EXPECT_FALSE(status.contains("saved_fixation_yaw_deg"));
  }
  // A saved folder whose gaze.yaml is gone: an error, not a silent success.
  fs::remove(dir / "gaze.yaml");
  summary.gaze_fixation_yaw_deg = 3.0;
  EXPECT_FALSE(save_learnt_fixation_yaw(status, summary));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dreamsense::self_calibration
