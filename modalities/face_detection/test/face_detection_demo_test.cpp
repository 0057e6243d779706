// Recall / false positives / camera selection of the face detection analyser on a full 20 s demo
// session: $DREAMSENSE_FACE_DEMO_SESSION if set (e.g. the output of `dreamsense demo --seed 2
// --no-analyze`), else a 20 s seed-1 demo generated into a temporary folder (~40 s).

#include "dreamsense/face_detection/face_detection_analyzer.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <unistd.h>

#include "demo_frames.hpp"

namespace dreamsense::face_detection {
namespace {

TEST(FaceDetectionDemo, TwentySecondSession) {
  const char* env = std::getenv("DREAMSENSE_FACE_DEMO_SESSION");
  const std::filesystem::path dir = env != nullptr
                                        ? std::filesystem::path(env)
                                        : std::filesystem::temp_directory_path() /
                                              ("ds_face_demo_test_" + std::to_string(getpid()));
  ASSERT_TRUE(testing::ensure_demo(dir, 20.0, 1));
  const auto truth = testing::read_face_truth(dir);
  auto a = make_face_detection_analyzer();
  ASSERT_TRUE(a);
  Blackboard bb;
  testing::FaceMetrics m;
  double busy_ms = 0;
  size_t ticks = 0;
  auto s = testing::for_each_tick(dir, [&](const MultiFrame& mf) {
    BlackboardWriter w("face_detection");
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    busy_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++ticks;
    bb.commit(w, mf.stamp);
    auto det = bb.snapshot().get(keys::kFaceDetections);
    auto sel = bb.snapshot().get(keys::kSelectedCamera);
    std::vector<SensorId> searched;
    for (const auto& [id, f] : mf.frames) searched.push_back(id);
    testing::accumulate(m, truth.at(mf.stamp.ns()), searched,
                        det && det->stamp == mf.stamp ? det->value.get() : nullptr,
                        sel && sel->stamp == mf.stamp ? sel->value.get() : nullptr);
  });
  if (env == nullptr) std::filesystem::remove_all(dir);
  ASSERT_TRUE(s) << s.error().to_string();
  std::printf(
      "%s: %zu ticks, recall(|yaw|<=45) %.4f (%d/%d), false-positive frames %.4f (%d/%d), "
      "camera selection exact %.4f, within 10 deg %.4f (%d ticks), %.1f ms/tick\n",
      dir.filename().c_str(), ticks, m.recall(), m.hits, m.positives, m.false_positive_rate(),
      m.fp_frames, m.camera_frames, m.selection_exact_rate(), m.selection_accuracy(),
      m.selection_ticks, busy_ms / std::max<size_t>(1, ticks));
  EXPECT_GE(m.recall(), 0.98);
  EXPECT_LE(m.false_positive_rate(), 0.01);
  // Selection here uses the frontalness proxy only (no head pose in this test): a regression
  // guard measured at 0.874 on the mesh demo; the pipeline selects by head yaw (eval session).
  EXPECT_GE(m.selection_accuracy(), 0.85);
}

}  // namespace
}  // namespace dreamsense::face_detection
