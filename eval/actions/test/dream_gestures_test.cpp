// The shipped DREAM-gesture model on fresh demo seeds (per-tick accuracy with edge tolerance,
// rest time reported as a gesture), its robustness to body size and missing/NaN joints, the
// open set (movements it was not trained on), and custom gestures taught by three
// demonstrations recorded in a session (train gestures).

#include "dreamsense/eval/dream_gestures.hpp"

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>

namespace dreamsense::eval::actions {
namespace {

namespace fs = std::filesystem;
using dreamsense::actions::ActionModel;
using dreamsense::actions::OnlineActionClassifier;

const fs::path kModel =
    fs::path(DREAMSENSE_SOURCE_DIR) / "modalities/actions/models/dream_gestures.yaml";

TEST(DreamGestures, ShippedModelOnFreshSeeds) {
  DreamEvalOptions o;
  o.seeds = *parse_seeds("1200-1209");  // never used for training (model card: 300-399)
  o.model = kModel;
  o.tolerance_s = 0.3;
  auto r = run_dream_eval(o);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_GE(r->metrics["action_accuracy"].get<double>(), 0.95) << r->per_class.dump();
  EXPECT_LE(r->metrics["rest_false_positive_rate"].get<double>(), 0.05);
  EXPECT_EQ(r->items, 10u * 1800u);
  for (const char* label :
       {"none", "wave", "cover_eyes", "hands_on_head", "fly", "drive_car", "drink"})
    EXPECT_GE(r->per_class[label]["recall"].get<double>(), 0.95) << label;
}

// Per-tick accuracy outside the edge zones of one recording after `edit` changed its frames.
double accuracy_after(const std::function<void(DemoRecording&)>& edit, uint64_t seed) {
  auto model = std::make_shared<const ActionModel>(*ActionModel::load(kModel));
  DemoGestureData data;
  data.duration_s = 40;
  DemoRecording r = demo_recording(seed, data);
  edit(r);
  auto c = OnlineActionClassifier::create(model, nullptr);
  int n = 0, ok = 0;
  for (const auto& f : r.frames) {
    const auto answer = c->push(f);
    const double t = static_cast<double>(f.stamp_ns) * 1e-9;
    for (const auto& s : r.truth)
      if (t >= s.start_s + 0.6 && t < s.end_s) {
        ++n;
        ok += answer.label == s.label;
      }
  }
  return n ? static_cast<double>(ok) / n : 0.0;
}

TEST(DreamGestures, RobustToBodySizeAndMissingJoints) {
  // An adult (x1.5) and a smaller child (x0.8): the body scaled about its hip centre.
  for (double scale : {1.5, 0.8}) {
    const double acc = accuracy_after(
        [scale](DemoRecording& r) {
          for (auto& f : r.frames) {
            const cv::Vec3d hip = f.joint(JointId::kHipCenter).position_m;
            for (auto& j : f.joints) j.position_m = hip + scale * (j.position_m - hip);
          }
        },
        1300);
    std::printf("scale %.1f: accuracy %.4f\n", scale, acc);
    EXPECT_GE(acc, 0.95) << "scale " << scale;
  }
  // 15 % of the joints missing, 3 % NaN, the legs never tracked.
  const double acc = accuracy_after(
      [](DemoRecording& r) {
        std::mt19937_64 rng(7);
        std::uniform_real_distribution<double> u(0, 1);
        for (auto& f : r.frames)
          for (int j = 0; j < kJointCount; ++j) {
            auto& o = f.joints[static_cast<size_t>(j)];
            const double x = u(rng);
            if (j >= static_cast<int>(JointId::kKneeLeft) &&
                j != static_cast<int>(JointId::kHipRight))
              o.confidence = 0.f;
            else if (x < 0.15)
              o.confidence = 0.f;
            else if (x < 0.18)
              o.position_m[1] = std::numeric_limits<double>::quiet_NaN();
          }
      },
      1301);
  std::printf("missing/NaN joints: accuracy %.4f\n", acc);
  EXPECT_GE(acc, 0.95);
}

std::vector<sim::CustomGesture> new_gestures() {
  sim::CustomGesture circle;
  circle.label = "circle";  // the right wrist draws a circle in front of the right shoulder
  circle.period_s = 1.2;
  for (int k = 0; k < 8; ++k) {
    const double a = 2 * CV_PI * k / 8;
    circle.right_wrist.push_back({-0.05 + 0.12 * std::cos(a), -0.05 + 0.12 * std::sin(a), -0.28});
  }
  sim::CustomGesture point;
  point.label = "point";  // the right arm stretched towards the robot
  point.period_s = 2.0;
  point.right_wrist = {{-0.02, 0.0, -0.38}, {-0.03, -0.02, -0.37}};
  return {circle, point};
}

DemoGestureData custom_data(int gesture, double duration = 5.0) {
  DemoGestureData d;
  d.duration_s = duration;
  d.script.custom = new_gestures();
  d.script.schedule = {{0, 1.0, sim::DemoAction::kNone, -1},
                       {1.0, duration - 1.0, sim::DemoAction::kCustom, gesture},
                       {duration - 1.0, duration, sim::DemoAction::kNone, -1}};
  return d;
}

TEST(DreamGestures, MovementsOutsideTheModelAreMostlyRejected) {
  auto model = std::make_shared<const ActionModel>(*ActionModel::load(kModel));
  // Pointing at the robot is none of the DREAM gestures: the open set answers none.
  int n = 0, none = 0;
  for (uint64_t seed = 1400; seed < 1405; ++seed) {
    const DemoRecording r = demo_recording(seed, custom_data(1, 7.0));
    auto c = OnlineActionClassifier::create(model, nullptr);
    for (const auto& f : r.frames) {
      const auto a = c->push(f);
      if (f.stamp_ns > 2'500'000'000 && f.stamp_ns < 6'000'000'000) {
        ++n;
        none += a.label == "none";
      }
    }
  }
  std::printf("pointing answered none: %.4f\n", static_cast<double>(none) / n);
  EXPECT_GE(static_cast<double>(none) / n, 0.9);
}

// A skeleton-only session holding the recordings one after the other (stamps shifted).
void write_session(const fs::path& dir, const std::vector<DemoRecording>& parts,
                   std::vector<double>& offsets_s) {
  fs::remove_all(dir);
  sources::SessionManifest m;
  m.name = "gesture-demos";
  sources::StreamEntry s;
  s.id = "front.skeleton";
  s.kind = SensorKind::kSkeleton;
  s.encoding = "jsonl";
  s.rate_hz = 30;
  m.streams.push_back(s);
  auto w = sources::SessionWriter::create(dir, m);
  ASSERT_TRUE(w) << w.error().message;
  int64_t offset = 0;
  uint64_t seq = 0;
  for (const auto& part : parts) {
    offsets_s.push_back(static_cast<double>(offset) * 1e-9);
    for (const auto& f : part.frames) {
      Skeleton sk;
      SkeletonBody b;
      b.joints = f.joints;
      sk.bodies.push_back(b);
      ASSERT_TRUE((*w)->write(
          *make_frame("front.skeleton", Timestamp::from_ns(f.stamp_ns + offset), seq++, sk)));
    }
    offset += part.frames.back().stamp_ns + 33'333'333;
  }
  ASSERT_TRUE((*w)->close());
}

TEST(DreamGestures, ThreeDemonstrationsTeachANewGestureThatRejectsTheOthers) {
  const fs::path dir = fs::temp_directory_path() / "dreamsense_train_gestures_test";
  fs::create_directories(dir);
  // Three demonstrations of "circle" by the demo child (seeds 1500-1502), recorded in one
  // session; the segments file marks one cycle of each.
  std::vector<DemoRecording> demos;
  for (uint64_t seed = 1500; seed < 1503; ++seed)
    demos.push_back(demo_recording(seed, custom_data(0)));
  std::vector<double> offsets;
  write_session(dir / "session", demos, offsets);
  {
    std::ofstream seg(dir / "segments.txt");
    seg << "# start_s end_s label\n";
    for (double o : offsets) seg << o + 1.7 << " " << o + 2.9 << " circle\n";
  }
  auto trained = train_gestures_from_session(dir / "session", dir / "segments.txt");
  ASSERT_TRUE(trained) << trained.error().message;
  ASSERT_EQ(trained->model.labels(), std::vector<std::string>{"circle"});
  ASSERT_TRUE(trained->model.save(dir / "gestures.yaml"));
  auto gestures = std::make_shared<const dreamsense::actions::GestureModel>(
      *dreamsense::actions::GestureModel::load(dir / "gestures.yaml"));
  auto model = std::make_shared<const ActionModel>(*ActionModel::load(kModel));

  // A fourth demonstration (another seed): recognised once a full cycle has been seen.
  const DemoRecording fourth = demo_recording(1503, custom_data(0));
  auto c = OnlineActionClassifier::create(model, gestures);
  ASSERT_TRUE(c);
  int n = 0, hits = 0;
  for (const auto& f : fourth.frames) {
    const auto a = c->push(f);
    const double t = static_cast<double>(f.stamp_ns) * 1e-9;
    if (t > 1.0 + 1.2 + 0.6 && t < 4.0) {
      ++n;
      hits += a.label == "circle";
      if (a.label == "circle") {
        EXPECT_EQ(a.dream_id, 7);  // the first custom trajectory
        EXPECT_TRUE(a.custom);
      }
    }
  }
  std::printf("fourth demonstration recognised on %d of %d ticks\n", hits, n);
  EXPECT_GE(static_cast<double>(hits) / n, 0.8) << hits << " of " << n;

  // The DREAM gestures, rests and pointing are never taken for "circle".
  int others = 0, false_hits = 0;
  DemoGestureData dream;
  dream.duration_s = 30;
  for (const DemoRecording& r : {demo_recording(1510, dream), demo_recording(1511, dream),
                                 demo_recording(1512, custom_data(1, 7.0))}) {
    auto d = OnlineActionClassifier::create(nullptr, gestures);
    for (const auto& f : r.frames) {
      ++others;
      false_hits += d->push(f).label == "circle";
    }
  }
  std::printf("other movements taken for the new gesture: %d of %d ticks\n", false_hits, others);
  EXPECT_LE(static_cast<double>(false_hits) / others, 0.01) << false_hits << " of " << others;
}

TEST(DreamGestures, TrainGesturesErrors) {
  const fs::path dir = fs::temp_directory_path() / "dreamsense_train_gestures_test";
  fs::create_directories(dir);
  std::ofstream(dir / "late.txt") << "100 101 circle\n";  // after the session's end: no frames
  std::vector<DemoRecording> demos = {demo_recording(1500, custom_data(0))};
  std::vector<double> offsets;
  write_session(dir / "one", demos, offsets);
  auto r = train_gestures_from_session(dir / "one", dir / "late.txt");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("late.txt:1"), std::string::npos) << r.error().message;
  EXPECT_FALSE(train_gestures_from_session(dir / "absent", dir / "late.txt"));
}

}  // namespace
}  // namespace dreamsense::eval::actions
