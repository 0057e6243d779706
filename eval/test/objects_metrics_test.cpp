// `eval session`'s objects group on hand-made records and truth: matching by box overlap, the
// three accuracy metrics and the six primitives' ok fraction.

#include "dreamsense/eval/session_metrics.hpp"

#include <gtest/gtest.h>

namespace dreamsense::eval {
namespace {
using primitives::PrimitiveId;
using primitives::PrimitiveRecord;
using primitives::PrimitiveStatus;

nlohmann::json truth_toy(int64_t stamp, int label, std::vector<double> box, cv::Vec3d p) {
  return {{"type", "object"},
          {"stamp_ns", stamp},
          {"label", label},
          {"top_box", box},
          {"position_m", {p[0], p[1], p[2]}}};
}

PrimitiveRecord record(PrimitiveId id, int64_t tick, int64_t frame, PrimitiveStatus status,
                       primitives::PrimitiveValue value = std::monostate{}) {
  PrimitiveRecord r;
  r.id = id;
  r.stamp = Timestamp::from_ns(tick);
  r.data_stamp = Timestamp::from_ns(frame);
  r.status = status;
  r.value = std::move(value);
  return r;
}

TEST(ObjectMetrics, MatchByOverlapScoreEveryTruthPair) {
  SessionData d;
  // Frame 0: car and cup; frame 100: the same toys moved; frame 200: no analysis saw it.
  for (int64_t f : {0, 100, 200}) {
    d.truth.push_back(truth_toy(f, 0, {100.0 + f, 100, 50, 40}, {-0.2, 0.27, 0.6}));
    d.truth.push_back(truth_toy(f, 1, {300, 200, 50, 40}, {0.1, 0.27, 0.5}));
  }
  auto obj = [](int id, cv::Rect2d box, cv::Vec3d p) {
    primitives::ObjectValue o;
    o.id = id;
    o.box_px = box;
    o.position_m = p;
    return o;
  };
  // Frame 0: both found (the cup 4 mm off); frame 100: the car found with the wrong id, the cup
  // missed.
  // A hand taken for a toy at frame 0 overlaps nothing.
  primitives::ObjectsValue f0{{obj(0, {100, 100, 50, 40}, {-0.2, 0.27, 0.6}),
                               obj(1, {300, 200, 50, 40}, {0.1, 0.27, 0.504}),
                               obj(-1, {500, 400, 40, 40}, {0.3, 0.27, 0.4})}};
  primitives::ObjectsValue f1{{obj(3, {200, 100, 50, 40}, {-0.2, 0.27, 0.61})}};
  d.records.push_back(record(PrimitiveId::kGetObjects, 10, 0, PrimitiveStatus::kOk, f0));
  d.records.push_back(record(PrimitiveId::kGetObjects, 110, 100, PrimitiveStatus::kOk, f1));
  // The other five: ok at tick 10, no_data at tick 110 (F14 only where a toy is in its circle).
  for (PrimitiveId id : {PrimitiveId::kGetGripLocation, PrimitiveId::kGetObjectsCircle,
                         PrimitiveId::kGetObjectTableDistance, PrimitiveId::kIdentifyObject,
                         PrimitiveId::kTrackObject}) {
    d.records.push_back(record(id, 10, 0, PrimitiveStatus::kOk));
    d.records.push_back(record(id, 110, 100, PrimitiveStatus::kNoData));
  }
  nlohmann::json metrics = nlohmann::json::object(), not_evaluated = nlohmann::json::object();
  object_metrics().compute(d, metrics, not_evaluated);
  EXPECT_TRUE(not_evaluated.empty()) << not_evaluated.dump();
  // Pairs: 4 (frame 200 unseen). IoU 1, 1, 1, 0; positions 0, 4 mm, 10 mm; ids right 2 of 4.
  EXPECT_DOUBLE_EQ(metrics["object_track_mean_iou"].get<double>(), 0.75);
  EXPECT_NEAR(metrics["object_position_median_m"].get<double>(), 0.004, 1e-9);
  EXPECT_DOUBLE_EQ(metrics["object_identification_accuracy"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(metrics["object_false_objects_per_frame"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(metrics["object_primitives_ok_fraction"].get<double>(), 0.5);
}

TEST(ObjectMetrics, NoTruthObjectsIsNotEvaluatedWithAReason) {
  SessionData d;
  d.records.push_back(record(PrimitiveId::kGetObjects, 10, 0, PrimitiveStatus::kNoData));
  nlohmann::json metrics = nlohmann::json::object(), not_evaluated = nlohmann::json::object();
  object_metrics().compute(d, metrics, not_evaluated);
  EXPECT_TRUE(metrics.empty());
  ASSERT_TRUE(not_evaluated.contains("object_track_mean_iou"));
  EXPECT_NE(not_evaluated["object_track_mean_iou"].get<std::string>().find("truth"),
            std::string::npos);
}

}  // namespace
}  // namespace dreamsense::eval
