#include "dreamsense/dream/legacy.hpp"
#include "dreamsense/dream/writers.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <unistd.h>

namespace dreamsense::dream {
namespace {
using namespace primitives;

PrimitiveRecord ok(PrimitiveId id, PrimitiveValue v) {
  PrimitiveRecord r;
  r.id = id;
  r.status = PrimitiveStatus::kOk;
  r.value = std::move(v);
  return r;
}

TEST(DreamIds, CamerasLabelsAndPorts) {
  EXPECT_EQ(camera_id("camera_middle"), 0);
  EXPECT_EQ(camera_id("camera_left"), 1);
  EXPECT_EQ(camera_id("camera_right"), 2);
  EXPECT_EQ(camera_id("front.color"), -1);
  EXPECT_EQ(expression_id("fear"), 3);
  EXPECT_EQ(expression_id("surprise"), -1) << "not in DREAM's five";
  EXPECT_EQ(trajectory_id("drink"), 6);
  EXPECT_EQ(trajectory_id("custom5"), 11);
  EXPECT_EQ(object_id("plane"), 3);
  EXPECT_STREQ(port(PrimitiveId::kGetHeadGaze), "getHeadGaze:o");
  EXPECT_STREQ(port(PrimitiveId::kGetHeadGazePlane), "getHeadGaze_plane:o") << "F12 told from F11";
  EXPECT_STREQ(port(PrimitiveId::kGetObjectsCircle), "getObjects_circle:o") << "F14 from F13";
  // Every primitive has its own port name.
  std::set<std::string> names;
  for (int i = 1; i <= kPrimitiveCount; ++i) names.insert(port(static_cast<PrimitiveId>(i)));
  EXPECT_EQ(names.size(), static_cast<size_t>(kPrimitiveCount));
  EXPECT_STREQ(port(PrimitiveId::kTrackObject), "trackObject:o") << "not the trackHand port";
}

TEST(DreamLegacy, LayoutsInMillimetres) {
  FacesValue faces;
  faces.faces.push_back({{0.1, -0.2, 1.0}, 0.9f, "camera_left", {}});
  const auto f = legacy_vector(ok(PrimitiveId::kGetFaces, faces));
  ASSERT_TRUE(f);
  ASSERT_EQ(f->size(), 16u) << "N + 5 faces x xyz";
  EXPECT_EQ((*f)[0], 1);
  EXPECT_DOUBLE_EQ((*f)[2], -200);
  EXPECT_EQ((*f)[15], 0);

  ArmAnglesValue one_arm;
  one_arm.left = ArmAngle{10, 20};
  EXPECT_FALSE(legacy_vector(ok(PrimitiveId::kGetArmAngle, one_arm)))
      << "DREAM's four numbers need both arms";
  one_arm.right = ArmAngle{30, 40};
  EXPECT_EQ(*legacy_vector(ok(PrimitiveId::kGetArmAngle, one_arm)),
            (std::vector<double>{20, 10, 40, 30}));

  ClassLabelValue wave{"wave", 1, {}};
  const auto t = legacy_vector(ok(PrimitiveId::kIdentifyTrajectory, wave));
  ASSERT_TRUE(t);
  ASSERT_EQ(t->size(), 12u);
  EXPECT_EQ((*t)[1], 1);
  ClassLabelValue sad{"sad", 1, {}};
  EXPECT_EQ(*legacy_vector(ok(PrimitiveId::kIdentifyFaceExpression, sad)), std::vector<double>{1});

  EyeGazeValue g;
  g.both.direction = {0, 0, -1};
  g.camera = "camera_right";
  EXPECT_EQ((*legacy_vector(ok(PrimitiveId::kGetEyeGaze, g)))[3], 2);

  SpeechValue s{"go forward ten meters", "FORWARD_10", 0.8, 0, 1};
  EXPECT_FALSE(legacy_vector(ok(PrimitiveId::kRecognizeSpeech, s)));
  EXPECT_EQ(*legacy_text(ok(PrimitiveId::kRecognizeSpeech, s)), "FORWARD_10");
}

TEST(DreamLegacy, NothingUnlessOkExceptNoFace) {
  PrimitiveRecord r;
  r.id = PrimitiveId::kCheckMutualGaze;
  r.status = PrimitiveStatus::kNoData;
  EXPECT_EQ(*legacy_vector(r), std::vector<double>{-1}) << "DREAM's 'no face'";
  r.status = PrimitiveStatus::kStale;
  EXPECT_FALSE(legacy_vector(r));
  r.id = PrimitiveId::kGetHead;
  r.status = PrimitiveStatus::kNoData;
  EXPECT_FALSE(legacy_vector(r));
}

namespace fs = std::filesystem;
fs::path temp_dir(const std::string& name) {
  auto d = fs::temp_directory_path() / ("ds_dream_" + name + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(EventLog, OkRecordsPublishLegacyValuesStatusChangesOnce) {
  auto d = temp_dir("events");
  EventLogWriter w;
  ASSERT_TRUE(w.open(d / "events.log", 0));
  for (int t = 0; t < 3; ++t) {
    primitives::PrimitiveRecord ok, off;
    ok.stamp = off.stamp = Timestamp::from_ns(t * 40'000'000LL);
    ok.id = primitives::PrimitiveId::kGetBody;
    ok.status = primitives::PrimitiveStatus::kOk;
    ok.value = primitives::BodyValue{{0.001, 0.002, 0.003}, 1};
    off.id = primitives::PrimitiveId::kGetFaces;
    off.status = primitives::PrimitiveStatus::kDisabled;
    ASSERT_TRUE(w.write({ok, off}));
  }
  ASSERT_TRUE(w.commit());
  std::ifstream in(d / "events.log");
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0].rfind("getBody:o;", 0), 0u);
  EXPECT_NE(lines[0].find(";1.000000;2.000000;3.000000"), std::string::npos);
  EXPECT_NE(lines[1].find("getFaces:o;"), std::string::npos);
  EXPECT_NE(lines[1].find(";disabled"), std::string::npos);
  fs::remove_all(d);
}

TEST(DreamExport, FrameAlignedArraysWithNullsAndDreamJointNames) {
  DreamExport e;
  SkeletonBody b;
  b.joint(JointId::kHead) = {{0.1, -0.2, 1.1}, 1.f};
  e.add({b, cv::Vec3d(0, 0, -2), std::nullopt});
  e.add({std::nullopt, std::nullopt, std::nullopt});
  sources::SessionManifest m;
  m.participant.id = 3;
  m.condition = "RET";
  m.task = "TT";
  auto j = e.build(m);
  EXPECT_EQ(j["skeleton"]["head"]["x"][0], 100.0);
  EXPECT_TRUE(j["skeleton"]["head"]["x"][1].is_null());
  EXPECT_TRUE(j["skeleton"].contains("sholder_left"));
  EXPECT_EQ(j["head_gaze"]["rz"][0], -1.0) << "unit vector";
  EXPECT_TRUE(j["eye_gaze"]["rx"][0].is_null());
  EXPECT_EQ(j["participant"]["id"], 3);
  EXPECT_EQ(j["skeleton"]["hand_right"]["confidence"].size(), 2u);
}

// F20 (issue 13): custom gestures carry their own labels; the one-hot follows the value's F20 id.
TEST(DreamLegacy, TrajectoryOneHotFollowsTheF20Id) {
  const auto none =
      legacy_vector(ok(PrimitiveId::kIdentifyTrajectory, ClassLabelValue{"none", 0, {}}));
  ASSERT_TRUE(none);
  EXPECT_EQ(*none, (std::vector<double>{1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}));
  const auto circle =
      legacy_vector(ok(PrimitiveId::kIdentifyTrajectory, ClassLabelValue{"circle", 8, {}}));
  ASSERT_TRUE(circle);
  EXPECT_EQ((*circle)[8], 1) << "second custom trajectory";
  EXPECT_EQ(std::count(circle->begin(), circle->end(), 1.0), 1);
  const auto other =
      legacy_vector(ok(PrimitiveId::kIdentifyTrajectory, ClassLabelValue{"walk", -1, {}}));
  ASSERT_TRUE(other);
  EXPECT_EQ(std::count(other->begin(), other->end(), 0.0), 12) << "outside DREAM's classes";
}

}  // namespace
}  // namespace dreamsense::dream
