#include "dreamsense/gaze/gaze_analyzer.hpp"

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/gaze.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <gtest/gtest.h>

namespace dreamsense::gaze {
namespace {

CameraModel camera() {
  CameraModel c;
  c.image_size = {1280, 960};
  c.K = cv::Matx33d(1000, 0, 640, 0, 1000, 480, 0, 0, 1);
  return c;
}

struct Inputs {
  FaceLandmarks lm;
  EyeCenters eyes;
  HeadPose head;
};

// A frontal head 0.8 m in front of the camera, pupils centred between the corners.
Inputs frontal(Timestamp t) {
  Inputs in;
  in.lm.camera = "cam";
  in.lm.frame_stamp = t;
  in.lm.points_px.assign(kFaceLandmarkCount, {0, 0});
  in.lm.points_px[36] = {570, 480};
  in.lm.points_px[39] = {610, 480};
  in.lm.points_px[42] = {670, 480};
  in.lm.points_px[45] = {710, 480};
  in.eyes.camera = "cam";
  in.eyes.frame_stamp = t;
  in.eyes.right = {true, {590, 480}, 0.9};
  in.eyes.left = {true, {690, 480}, 0.9};
  in.head.camera = "cam";
  in.head.frame_stamp = t;
  in.head.position_world_m = in.head.position_camera_m = {0, 0, 0.8};
  in.head.gaze_origin_world_m = in.head.position_world_m;
  return in;
}

void commit_inputs(Blackboard& bb, const Inputs& in, Timestamp t) {
  BlackboardWriter w("upstream");
  w.set(keys::kFaceLandmarks, in.lm, t, 0.9f);
  w.set(keys::kEyeCenters, in.eyes, t, 0.9f);
  w.set(keys::kHeadPose, in.head, t, 0.8f);
  bb.commit(w, t);
}

// One tick: the inputs committed, the gaze analyser run on them, its writes committed.
void process_tick(Analyzer& a, Blackboard& bb, const Inputs& in, Timestamp t) {
  commit_inputs(bb, in, t);
  MultiFrame mf;
  mf.stamp = t;
  BlackboardWriter w("gaze");
  EXPECT_TRUE(a.process(mf, bb.snapshot(), w));
  bb.commit(w, t);
}

TEST(GazeAnalyzer, WritesGazeAndMutualGazeOrAbsence) {
  GazeAnalyzerOptions o;
  EXPECT_FALSE(o.check()) << "no cameras";
  o.cameras["cam"] = camera();
  o.estimator.plane = OffsetPlane::kHeadPlane;
  o.mutual.robot_head_m = {0, 0, 0};  // the robot sits at the camera
  o.mutual.onset_s = 0;
  auto a = make_gaze_analyzer(o);
  ASSERT_TRUE(a) << a.error().message;

  Blackboard bb;
  const Timestamp t0 = Timestamp::from_seconds(1);
  MultiFrame mf;
  mf.stamp = t0;
  {  // nothing upstream in this tick: nothing written
    BlackboardWriter w("gaze");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    EXPECT_TRUE(w.empty());
  }
  commit_inputs(bb, frontal(t0), t0);
  {
    BlackboardWriter w("gaze");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    bb.commit(w, t0);
    const auto g = bb.snapshot().get(keys::kEyeGaze);
    ASSERT_TRUE(g && g->present());
    EXPECT_NEAR(g->value->both.direction_world[2], -1.0, 1e-6);  // towards the camera
    const auto m = bb.snapshot().get(keys::kMutualGaze);
    ASSERT_TRUE(m && m->present());
    EXPECT_TRUE(m->value->mutual);
    EXPECT_EQ(m->value->mode, "3d");
  }
  // Negative case: the head turned 60 deg away (eyes centred): no mutual gaze.
  const Timestamp t1 = t0 + Duration::from_ms(40);
  mf.stamp = t1;
  Inputs away = frontal(t1);
  away.head.world_from_head = away.head.camera_from_head = rotation_from_ypr_deg(60, 0, 0);
  commit_inputs(bb, away, t1);
  {
    BlackboardWriter w("gaze");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    bb.commit(w, t1);
    const auto m = bb.snapshot().get(keys::kMutualGaze);
    ASSERT_TRUE(m && m->present());
    EXPECT_FALSE(m->value->raw);
    EXPECT_GT(m->value->miss_distance_m, 0.3);
  }
  // No face (absent landmarks): both outputs absent, never a made-up gaze.
  const Timestamp t2 = t1 + Duration::from_ms(40);
  mf.stamp = t2;
  {
    BlackboardWriter l("face_landmarks");
    l.set_absent(keys::kFaceLandmarks, t2);
    bb.commit(l, t2);
    BlackboardWriter w("gaze");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    bb.commit(w, t2);
    const auto g = bb.snapshot().get(keys::kEyeGaze);
    ASSERT_TRUE(g);
    EXPECT_FALSE(g->present());
    const auto m = bb.snapshot().get(keys::kMutualGaze);
    ASSERT_TRUE(m);
    EXPECT_FALSE(m->present());
  }
}

// Eye contact shows the pupils: a gaze ray on the robot from eyes whose locator looked for the
// pupil and found it in neither eye (hidden under the lids) is not mutual gaze; one eye's pupil
// is enough; a locator without a pupil stage is not held to it; the option switches it off.
TEST(GazeAnalyzer, MutualGazeNeedsAVisiblePupil) {
  auto mutual_of = [](const GazeAnalyzerOptions& o, bool stage, bool right, bool left) {
    auto a = make_gaze_analyzer(o);
    EXPECT_TRUE(a) << a.error().message;
    Blackboard bb;
    const Timestamp t = Timestamp::from_seconds(1);
    Inputs in = frontal(t);
    in.eyes.pupil_stage = stage;
    in.eyes.right.pupil_found = right;
    in.eyes.left.pupil_found = left;
    process_tick(**a, bb, in, t);
    const auto m = bb.snapshot().get(keys::kMutualGaze);
    EXPECT_TRUE(m && m->present());
    return m && m->present() && m->value->raw;
  };
  GazeAnalyzerOptions o;
  o.cameras["cam"] = camera();
  o.mutual.robot_head_m = {0, 0, 0};
  o.mutual.onset_s = 0;
  EXPECT_TRUE(mutual_of(o, true, true, true));
  EXPECT_TRUE(mutual_of(o, true, false, true));
  EXPECT_FALSE(mutual_of(o, true, false, false));
  EXPECT_TRUE(mutual_of(o, false, false, false));
  o.mutual.require_visible_pupil = false;
  EXPECT_TRUE(mutual_of(o, true, false, false));
}

// Pupils 2 px to the image's right of centre in both eyes: every gaze passes beside the robot
// by the same yaw. With fixation_yaw on, the analyser learns that bias from the ticks that look
// near the robot and turns the rays towards it; off (the default), the rays stay as measured.
TEST(GazeAnalyzer, FixationYawTurnsABiasedGazeTowardsTheRobot) {
  auto run = [](bool enabled) {
    GazeAnalyzerOptions o;
    o.cameras["cam"] = camera();
    o.mutual.robot_head_m = {0, 0, 0};
    o.fixation_yaw.enabled = enabled;
    auto a = make_gaze_analyzer(o);
    EXPECT_TRUE(a) << a.error().message;
    Blackboard bb;
    std::vector<EyeGaze> out;
    for (int i = 0; i < 30; ++i) {
      const Timestamp t = Timestamp::from_seconds(1) + Duration::from_ms(40 * i);
      Inputs in = frontal(t);
      in.eyes.right.center_px.x += 2;
      in.eyes.left.center_px.x += 2;
      process_tick(**a, bb, in, t);
      const auto g = bb.snapshot().get(keys::kEyeGaze);
      EXPECT_TRUE(g && g->present());
      if (g && g->present()) out.push_back(*g->value);
    }
    return out;
  };
  auto miss_deg = [](const EyeGaze& g) {  // angle between the ray and the robot (at the origin)
    const cv::Vec3d to_robot = -g.both.origin_world_m;
    return std::acos(g.both.direction_world.dot(to_robot) / cv::norm(to_robot)) * 180 / CV_PI;
  };
  const auto off = run(false), on = run(true);
  ASSERT_EQ(off.size(), 30U);
  ASSERT_EQ(on.size(), 30U);
  EXPECT_EQ(off.back().fixation_yaw_deg, 0);
  EXPECT_GT(miss_deg(off.back()), 3);         // the bias this test builds
  EXPECT_EQ(on.front().fixation_yaw_deg, 0);  // still learning
  EXPECT_NE(on.back().fixation_yaw_deg, 0);
  EXPECT_LT(miss_deg(on.back()), miss_deg(off.back()) - 1.5);
  EXPECT_NEAR(miss_deg(on.front()), miss_deg(off.front()), 1e-9);
}

}  // namespace
}  // namespace dreamsense::gaze
