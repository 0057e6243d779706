// Self-calibration during a live session (issue 15): the ticks a live analysis offers are
// searched on the calibration's own thread; the converged files are handed over once.

#include "dreamsense/self_calibration/live.hpp"

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include "held_out_session.hpp"

namespace dreamsense::self_calibration {
namespace {

namespace fs = std::filesystem;
constexpr int64_t kSameTickNs = 10'000'000;

// The session's three cameras as the live ticks would bring them: frames within 10 ms form one
// tick. `each` gets every tick; reading stops when it returns false.
void for_each_tick(const fs::path& session, const std::function<bool(const MultiFrame&)>& each) {
  sources::SessionReaderOptions ro;
  ro.only = {"camera_left", "camera_middle", "camera_right"};
  auto reader = sources::SessionReader::open(session, ro);
  ASSERT_TRUE(reader) << reader.error().to_string();
  MultiFrame tick;
  for (auto f = (*reader)->next(); f; f = (*reader)->next()) {
    if (!tick.frames.empty() && (*f)->stamp.ns() - tick.stamp.ns() > kSameTickNs) {
      if (!each(tick)) return;
      tick = MultiFrame{};
    }
    if (tick.frames.empty()) tick.stamp = (*f)->stamp;
    tick.frames[(*f)->sensor] = *f;
  }
  if (!tick.frames.empty()) each(tick);
}

// A live self-calibration of the held-out child's session with `o` (its work folder fresh).
std::unique_ptr<LiveSelfCalibration> start_on(const fs::path& session,
                                              LiveSelfCalibrationOptions& o,
                                              const std::string& name) {
  o.wait_when_busy = true;  // every tick_step-th tick searched, as on the recording
  o.work_dir = fs::temp_directory_path() / (name + std::to_string(::getpid()));
  fs::remove_all(o.work_dir);
  auto manifest = sources::read_manifest(session);
  EXPECT_TRUE(manifest);
  if (!manifest) return nullptr;
  auto live = LiveSelfCalibration::start(*manifest, session, o);
  EXPECT_TRUE(live) << live.error().to_string();
  return live ? std::move(*live) : nullptr;
}

TEST(LiveSelfCalibration, ConvergesOnTheOfferedTicksAsOnTheRecordingAndHandsTheFilesOverOnce) {
  const fs::path session = held_out_child_session();
  ASSERT_FALSE(session.empty());
  LiveSelfCalibrationOptions o;
  o.search.enough_frames = 20;
  auto live = start_on(session, o, "ds_live_selfcal_");
  ASSERT_TRUE(live);
  std::optional<SubjectFiles> handed;
  int ticks = 0, handed_at = -1, handed_again = 0;
  for_each_tick(session, [&](const MultiFrame& tick) {
    ++ticks;
    if (auto files = live->offer(tick)) {
      if (handed) ++handed_again;
      handed = files;
      handed_at = ticks;
    }
    return ticks < handed_at + 50 || handed_at < 0;
  });
  ASSERT_TRUE(handed) << live->status().dump();
  EXPECT_EQ(handed_again, 0);
  EXPECT_TRUE(fs::exists(handed->face_model));
  EXPECT_TRUE(fs::exists(handed->gaze_model));
  const nlohmann::json status = live->status();
  EXPECT_EQ(status.value("state", ""), "converged");
  EXPECT_EQ(status.value("ticks_skipped_busy", -1), 0);
  EXPECT_EQ(status.value("attempts", 0), 1);

  // The recording's self-calibration with the same options searches the same ticks.
  SessionSelfCalibrationOptions so = o.search;
  const auto recorded = self_calibrate_session(session, so);
  ASSERT_TRUE(recorded) << recorded.error().to_string();
  ASSERT_TRUE(recorded->face.converged());
  EXPECT_EQ(status.value("ticks_searched", 0), recorded->ticks_searched);
  EXPECT_NEAR(status.value("interocular_mm", 0.0), 1000 * recorded->face.interocular_m, 1e-6);
  fs::remove_all(o.work_dir);
}

TEST(LiveSelfCalibration, OneCameraDoesNotConvergeAndHandsNothingOver) {
  const fs::path session = held_out_child_session();
  ASSERT_FALSE(session.empty());
  LiveSelfCalibrationOptions o;
  o.search.cameras = {"camera_middle"};  // triangulation needs two
  o.search.max_seconds = 2;
  o.attempts = 2;
  auto live = start_on(session, o, "ds_live_selfcal_one_");
  ASSERT_TRUE(live);
  bool handed = false;
  for_each_tick(session, [&](const MultiFrame& tick) {
    handed = handed || live->offer(tick).has_value();
    return live->status().value("state", "") == "searching";
  });
  live->wait();
  const nlohmann::json status = live->status();
  EXPECT_FALSE(handed);
  EXPECT_EQ(status.value("state", ""), "not_converged") << status.dump();
  EXPECT_EQ(status.value("attempts", 0), 2);
  EXPECT_FALSE(status.value("converged", true));
  EXPECT_FALSE(fs::exists(o.work_dir / "face_model.yaml"));
  fs::remove_all(o.work_dir);

  LiveSelfCalibrationOptions bad = o;
  bad.attempts = 0;
  EXPECT_FALSE(bad.check());
  bad = o;
  bad.work_dir.clear();
  EXPECT_FALSE(LiveSelfCalibration::start(*sources::read_manifest(session), session, bad));
}

}  // namespace
}  // namespace dreamsense::self_calibration
