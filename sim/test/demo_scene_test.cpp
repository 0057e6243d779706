#include "dreamsense/sim/demo_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace dreamsense::sim {
namespace {

TEST(DemoScene, ActionScheduleTilesTheSessionAndHasEveryActionIn20s) {
  for (uint64_t seed = 0; seed < 200; ++seed) {
    const auto s = make_action_schedule(seed, 20.0);
    ASSERT_FALSE(s.empty());
    EXPECT_DOUBLE_EQ(s.front().start_s, 0.0);
    EXPECT_DOUBLE_EQ(s.back().end_s, 20.0);
    std::set<DemoAction> seen;
    for (size_t i = 0; i < s.size(); ++i) {
      if (i > 0) {
        EXPECT_DOUBLE_EQ(s[i].start_s, s[i - 1].end_s);
      }
      const double len = s[i].end_s - s[i].start_s;
      if (i + 1 < s.size()) {
        if (s[i].action == DemoAction::kNone) {
          EXPECT_GE(len, 0.8);
        } else {
          EXPECT_GE(len, 2.0);
          EXPECT_LE(len, 3.5);
        }
      }
      if (s[i].end_s - s[i].start_s >= 2.0) seen.insert(s[i].action);
    }
    EXPECT_TRUE(seen.count(DemoAction::kWave)) << "seed " << seed;
    EXPECT_TRUE(seen.count(DemoAction::kFly)) << "seed " << seed;
    EXPECT_TRUE(seen.count(DemoAction::kHandsOnHead)) << "seed " << seed;
  }
}

TEST(DemoScene, SeedsChangeTheScript) {
  const DemoScript a(1, 20), b(2, 20);
  EXPECT_NE(a.head_pose(3.0).yaw_deg, b.head_pose(3.0).yaw_deg);
  const auto sa = make_action_schedule(1, 20), sb = make_action_schedule(2, 20);
  EXPECT_NE(sa[1].end_s, sb[1].end_s);
  EXPECT_NE(a.object_states(1.0)[0].position_m, b.object_states(1.0)[0].position_m);
}

TEST(DemoScene, HeadPoseStaysInRangeAndIsSmooth) {
  for (uint64_t seed : {1, 2, 3, 7, 42}) {
    const DemoScript s(seed, 20);
    const auto& g = s.geometry();
    int n = 0;
    cv::Vec3d prev_pos;
    double prev_yaw = 0, prev_pitch = 0, max_yaw = 0;
    for (double t = 0; t < 20; t += 0.04, ++n) {
      const HeadPose hp = s.head_pose(t);
      EXPECT_LE(std::abs(hp.yaw_deg), 55.0 + 1e-9);
      EXPECT_GE(hp.pitch_deg, -15.0 - 1e-9);
      EXPECT_LE(hp.pitch_deg, 22.0 + 1e-9);
      EXPECT_LE(std::abs(hp.roll_deg), 10.0 + 1e-9);
      EXPECT_LT(cv::norm(hp.position_m - g.head_rest_m), 0.06);
      if (n > 0) {  // smooth: < 200 deg/s, < 0.3 m/s
        EXPECT_LT(std::abs(hp.yaw_deg - prev_yaw), 8.0) << "seed " << seed << " t " << t;
        EXPECT_LT(std::abs(hp.pitch_deg - prev_pitch), 8.0) << "seed " << seed << " t " << t;
        EXPECT_LT(cv::norm(hp.position_m - prev_pos), 0.012);
      }
      prev_yaw = hp.yaw_deg;
      prev_pitch = hp.pitch_deg;
      prev_pos = hp.position_m;
      max_yaw = std::max(max_yaw, std::abs(hp.yaw_deg));
    }
    EXPECT_GT(max_yaw, 25.0) << "seed " << seed << ": the head should turn";
  }
}

TEST(DemoScene, FixationsTileTheSessionAndEveryCycleLooksAtTheRobot) {
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    for (double duration : {2.0, 4.0, 20.0}) {
      const DemoScript s(seed, duration);
      const auto& f = s.fixations();
      ASSERT_FALSE(f.empty());
      EXPECT_DOUBLE_EQ(f.front().start_s, 0.0);
      EXPECT_GE(f.back().end_s, duration - 1e-9);
      double robot = 0;
      for (size_t i = 0; i < f.size(); ++i) {
        if (i > 0) {
          EXPECT_DOUBLE_EQ(f[i].start_s, f[i - 1].end_s);
        }
        EXPECT_GE(f[i].end_s - f[i].start_s, 0.5) << "seed " << seed << " fixation " << i;
        if (f[i].kind == GazeTargetKind::kRobot) robot += f[i].end_s - f[i].start_s;
        if (i > 0 && f[i].kind == GazeTargetKind::kRobot) {
          EXPECT_NE(f[i - 1].kind, GazeTargetKind::kRobot);  // consecutive robot looks merge
        }
      }
      EXPECT_GE(robot / duration, 0.35) << "seed " << seed;
      EXPECT_LE(robot / duration, 0.45) << "seed " << seed;
    }
  }
}

TEST(DemoScene, EyeGazeDiffersFromHeadGazeWithinTheEyeRange) {
  for (uint64_t seed : {1, 2, 3}) {
    const DemoScript s(seed, 20);
    int n = 0, different = 0;
    std::set<GazeTargetKind> kinds;
    for (double t = 0; t < 20; t += 0.04, ++n) {
      const HeadPose hp = s.head_pose(t);
      const GazeState g = s.gaze(t);
      kinds.insert(g.kind);
      EXPECT_LE(std::abs(g.eye_yaw_deg), DemoScript::kMaxEyeYawDeg + 1e-9);
      EXPECT_LE(std::abs(g.eye_pitch_deg), DemoScript::kMaxEyePitchDeg + 1e-9);
      const cv::Vec3d eye = cv::normalize(g.target_m - hp.position_m);
      const double angle = std::acos(std::clamp(eye.dot(hp.gaze_dir()), -1.0, 1.0)) * 180 / CV_PI;
      if (angle > 5) ++different;
      // The eye-in-head angles are the angle between eye gaze and head gaze.
      EXPECT_NEAR(std::cos(angle * CV_PI / 180),
                  std::cos(g.eye_yaw_deg * CV_PI / 180) * std::cos(g.eye_pitch_deg * CV_PI / 180),
                  1e-6);
    }
    EXPECT_GT(different, n / 3) << "seed " << seed;
    EXPECT_GE(kinds.size(), 3u) << "seed " << seed;
  }
}

TEST(DemoScene, BlinksCloseTheEyesBriefly) {
  const DemoScript s(4, 20);
  ASSERT_GE(s.blink_starts().size(), 3u);
  int closed = 0, n = 0;
  for (double t = 0; t < 20; t += 0.01, ++n) {
    const double c = s.eyelid_closure(t);
    EXPECT_GE(c, 0.0);
    EXPECT_LE(c, 1.0);
    if (c >= 0.5) ++closed;
  }
  EXPECT_GT(closed, 0);
  EXPECT_LT(closed, n / 20);  // < 5 % of the time
  EXPECT_DOUBLE_EQ(s.eyelid_closure(s.blink_starts()[0] + 0.1), 1.0);
  EXPECT_DOUBLE_EQ(s.eyelid_closure(s.blink_starts()[0] - 0.01), 0.0);
}

TEST(DemoScene, TheTherapistIsOnTheSideItSpeaksFrom) {
  int left = 0, right = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const DemoScript s(seed, 20);
    EXPECT_EQ(s.therapist_head_m()[0] > 0, s.therapist_side() > 0);
    (s.therapist_side() > 0 ? right : left)++;
  }
  EXPECT_GT(left, 0);
  EXPECT_GT(right, 0);
}

TEST(DemoScene, HeadPoseZeroLooksAlongMinusZ) {
  HeadPose hp;
  const cv::Vec3d g = hp.gaze_dir();
  EXPECT_NEAR(g[2], -1.0, 1e-12);
  double yaw = 0, pitch = 0;
  look_at_angles({0, -0.05, 1.1}, {0, -0.05, 0.15}, yaw, pitch);
  EXPECT_NEAR(yaw, 0, 1e-9);
  EXPECT_NEAR(pitch, 0, 1e-9);
  look_at_angles({0, 0, 1}, {-1, 0, 0}, yaw, pitch);  // towards -x and -z
  hp.yaw_deg = yaw;
  EXPECT_NEAR(hp.gaze_dir()[0], -std::sqrt(0.5), 1e-9);
}

TEST(DemoScene, SkeletonIsConsistent) {
  const DemoScript s(5, 20);
  for (double t = 0.05; t < 20; t += 0.1) {
    const auto j = s.joints(t);
    auto J = [&](JointId id) { return j[static_cast<size_t>(id)]; };
    const HeadPose hp = s.head_pose(t);
    EXPECT_LT(cv::norm(J(JointId::kHead) - hp.position_m), 0.12);
    EXPECT_GT(J(JointId::kShoulderCenter)[1], J(JointId::kHead)[1]);  // below the head
    bool transition = false;
    for (const auto& seg : s.actions())
      if (t >= seg.start_s && t < seg.start_s + 0.5) transition = true;
    if (transition) continue;
    for (bool left : {true, false}) {
      const auto sh = J(left ? JointId::kShoulderLeft : JointId::kShoulderRight);
      const auto el = J(left ? JointId::kElbowLeft : JointId::kElbowRight);
      const auto wr = J(left ? JointId::kWristLeft : JointId::kWristRight);
      EXPECT_NEAR(cv::norm(el - sh), 0.21, 0.005) << t;
      EXPECT_NEAR(cv::norm(wr - el), 0.19, 0.005) << t;
    }
    const DemoAction a = s.action_at(t);
    const auto hl = J(JointId::kHandLeft), hr = J(JointId::kHandRight);
    const auto sl = J(JointId::kShoulderLeft), sr = J(JointId::kShoulderRight);
    switch (a) {
      case DemoAction::kNone:
        EXPECT_NEAR(hl[1], s.geometry().table_top_y_m, 0.05);
        EXPECT_NEAR(hr[1], s.geometry().table_top_y_m, 0.05);
        break;
      case DemoAction::kWave:
        EXPECT_LT(hr[1], sr[1] - 0.15);  // right hand well above the shoulder
        break;
      case DemoAction::kFly:
        EXPECT_GT(hl[0] - sl[0], 0.3);
        EXPECT_LT(hr[0] - sr[0], -0.3);
        break;
      case DemoAction::kHandsOnHead:
        EXPECT_LT(cv::norm(hl - J(JointId::kHead)), 0.16);
        EXPECT_LT(cv::norm(hr - J(JointId::kHead)), 0.16);
        break;
      default:
        ADD_FAILURE() << "the default demo performs only wave, fly and hands_on_head";
        break;
    }
  }
}

TEST(DemoScene, DreamGestureSetHasAllSixGesturesIn30s) {
  for (uint64_t seed = 0; seed < 100; ++seed) {
    const auto s = make_action_schedule(seed, 30.0, DemoScriptOptions::GestureSet::kDream);
    std::set<DemoAction> seen;
    for (size_t i = 0; i < s.size(); ++i) {
      if (i > 0) {
        EXPECT_DOUBLE_EQ(s[i].start_s, s[i - 1].end_s);
      }
      if (s[i].end_s - s[i].start_s >= 2.0) seen.insert(s[i].action);
    }
    for (DemoAction a : {DemoAction::kWave, DemoAction::kFly, DemoAction::kHandsOnHead,
                         DemoAction::kCoverEyes, DemoAction::kDriveCar, DemoAction::kDrink})
      EXPECT_TRUE(seen.count(a)) << "seed " << seed << " " << action_label(a);
    EXPECT_FALSE(seen.count(DemoAction::kCustom));
  }
  EXPECT_EQ(action_dream_id(DemoAction::kCoverEyes), 2);
  EXPECT_EQ(action_dream_id(DemoAction::kDriveCar), 5);
  EXPECT_EQ(action_dream_id(DemoAction::kDrink), 6);
}

TEST(DemoScene, DreamGesturesHaveTheirPosesAndKeepTheBones) {
  DemoScriptOptions o;
  o.gestures = DemoScriptOptions::GestureSet::kDream;
  int checked = 0;
  for (uint64_t seed : {3, 11}) {
    const DemoScript s(seed, 40, DemoGeometry{}, o);
    for (double t = 0.05; t < 40; t += 0.1) {
      const ActionSegment& seg = s.segment_at(t);
      if (t < seg.start_s + 0.5) continue;  // blending from the previous pose
      const auto j = s.joints(t);
      auto J = [&](JointId id) { return j[static_cast<size_t>(id)]; };
      for (bool left : {true, false}) {
        const auto sh = J(left ? JointId::kShoulderLeft : JointId::kShoulderRight);
        const auto el = J(left ? JointId::kElbowLeft : JointId::kElbowRight);
        const auto wr = J(left ? JointId::kWristLeft : JointId::kWristRight);
        EXPECT_NEAR(cv::norm(el - sh), 0.21, 0.005) << t;
        EXPECT_NEAR(cv::norm(wr - el), 0.19, 0.005) << t;
      }
      const HeadPose hp = s.head_pose(t);
      const auto hl = J(JointId::kHandLeft), hr = J(JointId::kHandRight);
      const auto sc = J(JointId::kShoulderCenter);
      const double table = s.geometry().table_top_y_m;
      switch (seg.action) {
        case DemoAction::kCoverEyes:  // both palms within a few cm of the eyes
          EXPECT_LT(cv::norm(hl - hp.position_m), 0.09) << t;
          EXPECT_LT(cv::norm(hr - hp.position_m), 0.09) << t;
          ++checked;
          break;
        case DemoAction::kDriveCar:  // both hands in front of the chest, off the table
          EXPECT_LT(hl[2], sc[2] - 0.15) << t;
          EXPECT_LT(hr[2], sc[2] - 0.15) << t;
          EXPECT_LT(hl[1], table - 0.05) << t;
          EXPECT_GT(hl[0], hr[0]) << t;
          ++checked;
          break;
        case DemoAction::kDrink:  // right hand at the mouth, left hand on the table
          EXPECT_LT(cv::norm(hr - (hp.position_m + cv::Vec3d(0, 0.07, -0.08))), 0.08) << t;
          EXPECT_NEAR(hl[1], table, 0.05) << t;
          ++checked;
          break;
        default:
          break;
      }
    }
  }
  EXPECT_GT(checked, 150);
}

TEST(DemoScene, CustomGestureFollowsItsScriptedLoop) {
  DemoScriptOptions o;
  CustomGesture g;
  g.label = "circle";
  g.period_s = 1.0;
  // Right wrist around a circle in front of the right shoulder.
  for (int k = 0; k < 8; ++k) {
    const double a = 2 * CV_PI * k / 8;
    g.right_wrist.push_back(
        cv::Vec3d(-0.05 + 0.12 * std::cos(a), -0.05 + 0.12 * std::sin(a), -0.25));
  }
  o.custom = {g};
  o.schedule = {{0.0, 1.0, DemoAction::kNone, -1},
                {1.0, 4.0, DemoAction::kCustom, 0},
                {4.0, 5.0, DemoAction::kNone, -1}};
  ASSERT_TRUE(o.check());
  const DemoScript s(1, 5, DemoGeometry{}, o);
  EXPECT_EQ(s.segment_label(s.actions()[1]), "circle");
  EXPECT_EQ(s.segment_dream_id(s.actions()[1]), 7);
  for (int k = 0; k < 8; ++k) {
    const double t = 2.0 + k / 8.0;  // key point k of the loop (u = t - start)
    const auto j = s.joints(t);
    const cv::Vec3d wrist = j[static_cast<size_t>(JointId::kWristRight)] -
                            j[static_cast<size_t>(JointId::kShoulderRight)];
    EXPECT_LT(cv::norm(wrist - g.right_wrist[static_cast<size_t>(k)]), 1e-6) << k;
    // The left arm rests on the table.
    EXPECT_NEAR(j[static_cast<size_t>(JointId::kHandLeft)][1], s.geometry().table_top_y_m, 0.05);
  }
  DemoScriptOptions bad = o;
  bad.schedule[1].custom = 3;
  EXPECT_FALSE(bad.check());
  bad = o;
  bad.schedule[2].start_s = 4.5;  // a hole
  EXPECT_FALSE(bad.check());
}

TEST(DemoScene, TableObjectsNeverOverlapAndStayOnTheTable) {
  for (uint64_t seed : {1, 9, 123}) {
    const DemoScript s(seed, 20);
    const auto& g = s.geometry();
    for (double t = 0; t < 20; t += 0.05) {
      const auto st = s.object_states(t);
      ASSERT_GE(st.size(), 2u);
      for (size_t i = 0; i < st.size(); ++i) {
        for (const auto& c : st[i].corners) {
          EXPECT_GT(c[0], g.table_x_min_m);
          EXPECT_LT(c[0], g.table_x_max_m);
          EXPECT_GT(c[2], g.table_z_min_m);
          EXPECT_LT(c[2], g.table_z_max_m);
        }
        for (size_t k = i + 1; k < st.size(); ++k) {
          // Bounding discs (half-diagonal 0.0625 m) are disjoint.
          cv::Vec3d d = st[i].position_m - st[k].position_m;
          d[1] = 0;
          EXPECT_GT(cv::norm(d), 0.125);
        }
      }
    }
  }
}

}  // namespace
}  // namespace dreamsense::sim
