// A live dry run whose cameras are video files (issue 18): one "device" runs out of frames
// mid-session; the analysis goes on with the other camera and marks the ended one
// sensor_offline (summary.json "sensors"), as when a camera is unplugged.

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/videoio.hpp>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include "cli_support.hpp"
#include "demo_video.hpp"

namespace {
namespace fs = std::filesystem;
using nlohmann::json;

using dreamsense::cli_support::run;
using dreamsense::cli_support::RunResult;
using dreamsense::cli_support::slurp;
using dreamsense::cli_support::write_video;

TEST(Live, CameraThatRunsOutIsMarkedOfflineAndTheOtherIsStillAnalysed) {
  const fs::path demo = DREAMSENSE_CLI_DEMO_DIR;
  ASSERT_TRUE(fs::exists(demo / "session.yaml")) << "run the fixture cli_demo_fixture first";
  const fs::path dir = fs::temp_directory_path() / ("ds_live_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_video(demo, "camera_middle", 3, dir / "middle.avi");  // 12 s
  write_video(demo, "camera_left", 1, dir / "left.avi");      // 4 s: ends mid-session
  if (HasFatalFailure()) return;
  std::ofstream(dir / "live.yaml")
      << "session: {name: live-offline, metadata: {subject: demo_child}}\ncameras:\n"
      << "  - {id: camera_middle, device: middle.avi, calibration: "
      << (demo / "calib" / "camera_middle.yaml").string() << "}\n"
      << "  - {id: camera_left, device: left.avi, calibration: "
      << (demo / "calib" / "camera_left.yaml").string() << "}\n";
  // --duration is honoured although every "device" has ended before it (issue 21): the run
  // lasts 14 s of analysis after the models are loaded, the middle video only 12 s from open.
  const std::string cmd = std::string(DREAMSENSE_EXE) + " live --config " +
                          (dir / "live.yaml").string() + " --out " + (dir / "out").string() +
                          " --duration 14 2> " + (dir / "err.txt").string();
  const auto started = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  EXPECT_GE(wall_s, 14.0) << "live ended with its devices, before --duration";
  const std::string err = slurp(dir / "err.txt");
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << err;

  const json summary = json::parse(slurp(dir / "out" / "summary.json"));
  const json& left = summary.at("sensors").at("camera_left");
  const json& middle = summary.at("sensors").at("camera_middle");
  EXPECT_EQ(left["status"], "sensor_offline") << summary["sensors"].dump();
  EXPECT_GT(left["offline_ticks"].get<int>(), 0);
  EXPECT_EQ(middle["status"], "ok") << summary["sensors"].dump();
  EXPECT_NE(err.find("camera_left: no data since"), std::string::npos) << err;
  // The capture's counts (a video that ends is not a lost device).
  const json& capture = summary.at("live_capture").at("streams");
  EXPECT_GT(capture.at("camera_middle").at("frames_captured").get<int>(), 250) << capture.dump();
  EXPECT_TRUE(capture.at("camera_left").at("lost").is_null()) << capture.dump();
  // The analysis went on after the left camera ended: faces from the middle camera more than a
  // second (offline_after) after the left camera's last frame.
  const int64_t left_end =
      left["last_stamp_ns"].is_null() ? int64_t{0} : left["last_stamp_ns"].get<int64_t>();
  int faces_after = 0;
  std::ifstream in(dir / "out" / "primitives.jsonl");
  for (std::string line; std::getline(in, line);) {
    const json r = json::parse(line);
    if (r["primitive"] == "getFaces" && r["status"] == "ok" &&
        r["stamp_ns"].get<int64_t>() > left_end + 1'000'000'000)
      ++faces_after;
  }
  EXPECT_GE(faces_after, 5) << "ticks: " << summary["ticks"];
  fs::remove_all(dir);
}

}  // namespace

namespace {

// Issue 15 in a live session: a child with no calibration folder is self-calibrated while the
// session runs (generic face model until it converges, the child's after); with --record
// --save-subject the recording is self-calibrated after the session and saved as the subject's
// folder, which the next session (live or analyze) then uses from its start.
TEST(Live, NewChildIsSelfCalibratedDuringTheSessionAndSavedForTheNext) {
  const fs::path demo = DREAMSENSE_CLI_DEMO_DIR;
  ASSERT_TRUE(fs::exists(demo / "session.yaml")) << "run the fixture cli_demo_fixture first";
  const fs::path dir =
      fs::temp_directory_path() / ("ds_live_subject_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "subjects");
  std::ofstream config(dir / "live.yaml");
  config << "session: {name: live-new-child, metadata: {subject: new_child}}\ncameras:\n";
  for (const char* id : {"camera_left", "camera_middle", "camera_right"}) {
    write_video(demo, id, 3, dir / (std::string(id) + ".avi"));  // 12 s
    if (HasFatalFailure()) return;
    config << "  - {id: " << id << ", device: " << id
           << ".avi, calibration: " << (demo / "calib" / (std::string(id) + ".yaml")).string()
           << "}\n";
  }
  config.close();
  const std::string live_config = "live --config " + (dir / "live.yaml").string();
  const std::string live = live_config + " --subjects-dir " + (dir / "subjects").string();
  const bool verbose = false;  // the info lines are checked
  // Without --record and without the live self-calibration there is nothing to save: refused
  // before anything starts.
  const RunResult refused =
      run(live + " --duration 1 --out " + (dir / "no").string() + " --save-subject --subject none",
          verbose);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("--save-subject needs --record or the live self-calibration"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "no" / "summary.json"));

  // 14 ticks with two cameras (default 60; 12 are needed to converge), every 2nd tick (default
  // 6th), at the analysis's priority (default: lower), so that the live self-calibration
  // converges within the session also when other tests load the machine: a ctest run beside a
  // heavy test once analysed only 72 ticks in 11 s, and 20 ticks every 3rd did not converge.
  const std::string fast_self_calibration =
      " --set self_calibration.enough_frames=14 --set self_calibration.tick_step=2 --set "
      "self_calibration.live_nice=0";
  const RunResult first =
      run(live + " --duration 11 --out " + (dir / "out").string() + " --record " +
              (dir / "rec").string() + " --save-subject" + fast_self_calibration,
          verbose);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  EXPECT_NE(first.err.find("no calibration for subject 'new_child': self-calibrating during the "
                           "session"),
            std::string::npos)
      << first.err;
  // Self-calibrated during the session: head pose and gaze switched to the child's models.
  EXPECT_NE(first.err.find("the child's face model and gaze constants are used from"),
            std::string::npos)
      << first.err;
  const fs::path saved = dir / "subjects" / "new_child";
  EXPECT_TRUE(fs::exists(saved / "face_model.yaml")) << first.err;
  EXPECT_TRUE(fs::exists(saved / "gaze.yaml")) << first.err;
  const json summary = json::parse(slurp(dir / "out" / "summary.json"));
  ASSERT_TRUE(summary.contains("self_calibration")) << summary.dump();
  EXPECT_EQ(summary["self_calibration"].value("saved_to", ""), saved.string());
  ASSERT_TRUE(summary.contains("live_self_calibration")) << summary.dump();
  const json& during = summary["live_self_calibration"];
  EXPECT_EQ(during.value("state", ""), "converged") << during.dump();
  EXPECT_TRUE(during["used_from_ns"].is_number()) << during.dump();
  EXPECT_TRUE(fs::exists(dir / "out" / "self_calibration" / "face_model.yaml"));
  EXPECT_NE(slurp(dir / "out" / "report.html").find("self-calibrated during the session"),
            std::string::npos);

  // A second session of the same child finds the folder: nothing to self-calibrate or save.
  const RunResult again = run(live + " --out " + (dir / "out2").string() + " --record " +
                                  (dir / "rec2").string() + " --save-subject --duration 2",
                              verbose);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(again.err.find("no calibration for subject"), std::string::npos) << again.err;
  EXPECT_FALSE(json::parse(slurp(dir / "out2" / "summary.json")).contains("live_self_calibration"));
  EXPECT_NE(again.err.find("nothing saved"), std::string::npos) << again.err;

  // No recording: the live self-calibration's own result is saved. 12 s (was 9): the three
  // 1280x960 video "cameras" are decoded by OpenCV at 25 fps each beside the analysis and the
  // search, more than 2 cores deliver, so frames arrive in bursts (seconds without a frame of
  // a camera) and 9 s converged in 3 of 6 runs on an idle 2-core machine (2026-12-01).
  fs::create_directories(dir / "subjects_live");
  const RunResult unrecorded =
      run(live_config + " --subjects-dir " + (dir / "subjects_live").string() + " --out " +
              (dir / "out3").string() + " --duration 12 --save-subject" + fast_self_calibration,
          verbose);
  ASSERT_EQ(unrecorded.exit_code, 0) << unrecorded.err;
  const fs::path saved_live = dir / "subjects_live" / "new_child";
  EXPECT_TRUE(fs::exists(saved_live / "face_model.yaml")) << unrecorded.err;
  EXPECT_TRUE(fs::exists(saved_live / "gaze.yaml")) << unrecorded.err;
  const json live_summary = json::parse(slurp(dir / "out3" / "summary.json"));
  EXPECT_EQ(live_summary["live_self_calibration"].value("saved_to", ""), saved_live.string());
  EXPECT_FALSE(live_summary.contains("self_calibration"));  // no recording was self-calibrated
  // The gaze's learnt sideways correction goes with those eyeballs (none learnt: no key).
  const json& learnt = live_summary["gaze_fixation_yaw_deg"];
  const bool has_correction = learnt.is_number() && learnt.get<double>() != 0;
  EXPECT_EQ(slurp(saved_live / "gaze.yaml").find("fixation_yaw_start_deg") != std::string::npos,
            has_correction);
  EXPECT_EQ(live_summary["live_self_calibration"].contains("saved_fixation_yaw_deg"),
            has_correction);
  fs::remove_all(dir);
}

}  // namespace
