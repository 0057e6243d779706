#include "dreamsense/perception/body.hpp"
#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/head_pose.hpp"
#include "dreamsense/perception/sound_direction.hpp"
#include "dreamsense/perception/voice_id.hpp"
#include "dreamsense/primitives/audio.hpp"
#include "dreamsense/primitives/body.hpp"
#include "dreamsense/primitives/evaluator.hpp"
#include "dreamsense/primitives/registry.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <set>

#include "test_time.hpp"

namespace dreamsense::primitives {
namespace {

using test::ms;

SkeletonBody child_with_right_hand(cv::Vec3d hand) {
  SkeletonBody b;
  for (int i = 0; i < kDreamJointCount; ++i) b.joints[i] = {{0.01 * i, -0.1, 1.1}, 1.f};
  b.joint(JointId::kSpine) = {{0, 0.1, 1.1}, 1.f};
  b.joint(JointId::kShoulderLeft) = {{0.15, -0.05, 1.1}, 1.f};
  b.joint(JointId::kShoulderRight) = {{-0.15, -0.05, 1.1}, 1.f};
  b.joint(JointId::kShoulderCenter) = {{0, -0.05, 1.1}, 1.f};
  b.joint(JointId::kHandRight) = {hand, 1.f};
  return b;
}

TEST(Catalogue, HasTwentyFiveDistinctNamesInTableOrder) {
  std::set<std::string> names;
  int n = 1;
  for (const auto& i : catalogue()) {
    EXPECT_EQ(static_cast<int>(i.id), n);
    EXPECT_EQ(std::string(i.code), fmt::format("F{}", n));
    names.insert(i.name);
    ++n;
  }
  EXPECT_EQ(names.size(), 25u);
  EXPECT_STREQ(info(PrimitiveId::kGetHeadGazePlane).name, "getHeadGaze (plane)");
}

TEST(PredictHand, ConstantVelocityIsExtrapolated) {
  std::vector<Entry<BodyState>> history;  // newest first, hand moving +0.5 m/s in x
  for (int i = 0; i < 8; ++i) {
    const double t = (7 - i) * 0.04;
    history.push_back({std::make_shared<const BodyState>(
                           BodyState{child_with_right_hand({-0.3 + 0.5 * t, 0, 1.0})}),
                       ms((7 - i) * 40), 1.f, "body"});
  }
  auto p = predict_hand(history, {-0.15, 0, 1.0}, 0.2);
  ASSERT_TRUE(p);
  EXPECT_FALSE(p->left);
  EXPECT_NEAR(p->velocity_mps[0], 0.5, 1e-9);
  EXPECT_NEAR(p->position_m[0], -0.3 + 0.5 * 0.28 + 0.1, 1e-9);
  EXPECT_GE(p->samples, 7);
}

TEST(Evaluator, DisabledPrimitivesCarryNoValues) {
  Evaluator ev({}, {});
  MultiFrame tick;
  tick.stamp = ms(0);
  auto recs = ev.evaluate(tick, BlackboardView());
  ASSERT_EQ(recs.size(), 25u);
  for (const auto& r : recs) {
    EXPECT_EQ(r.status, PrimitiveStatus::kDisabled);
    EXPECT_TRUE(std::holds_alternative<std::monostate>(r.value));
    EXPECT_TRUE(std::holds_alternative<std::monostate>(r.query));
  }
}

TEST(Evaluator, BodyPrimitivesOkNoDataStaleAndOffline) {
  Evaluator ev({}, {{"body.child", {"skel"}}});
  Blackboard bb;
  auto tick = [&](int64_t t, bool with_frame) {
    MultiFrame mf;
    mf.stamp = ms(t);
    if (with_frame) mf.frames["skel"] = make_frame("skel", ms(t), 0, Skeleton{});
    return mf;
  };
  auto status = [&](const std::vector<PrimitiveRecord>& r, PrimitiveId id) {
    return r[static_cast<int>(id) - 1].status;
  };
  // Nothing written yet.
  auto r = ev.evaluate(tick(0, true), bb.snapshot());
  EXPECT_EQ(status(r, PrimitiveId::kGetBody), PrimitiveStatus::kNoData);
  // A body observed.
  BlackboardWriter w("body");
  w.set(keys::kChildBody, BodyState{child_with_right_hand({-0.3, 0, 1})}, ms(40), 0.9f);
  bb.commit(w, ms(40));
  r = ev.evaluate(tick(40, true), bb.snapshot());
  EXPECT_EQ(status(r, PrimitiveId::kGetBody), PrimitiveStatus::kOk);
  EXPECT_EQ(status(r, PrimitiveId::kGetFaces), PrimitiveStatus::kDisabled);
  const auto& pose = r[static_cast<int>(PrimitiveId::kGetBodyPose) - 1];
  ASSERT_NE(pose.value_as<BodyPoseValue>(), nullptr);
  EXPECT_EQ(pose.value_as<BodyPoseValue>()->joints.size(), 10u);
  EXPECT_NEAR(pose.value_as<BodyPoseValue>()->joints[0].position_m[2], 1.1, 1e-9) << "metres";
  EXPECT_EQ(pose.source, "skel");
  EXPECT_NEAR(*pose.confidence, 0.9, 1e-6);
  // 200 ms later without a new observation: stale, and no value is repeated.
  r = ev.evaluate(tick(240, true), bb.snapshot());
  EXPECT_EQ(status(r, PrimitiveId::kGetHands), PrimitiveStatus::kStale);
  EXPECT_TRUE(std::holds_alternative<std::monostate>(
      r[static_cast<int>(PrimitiveId::kGetHands) - 1].value));
  // The analyser looked and found nobody.
  w.set_absent(keys::kChildBody, ms(280));
  bb.commit(w, ms(280));
  r = ev.evaluate(tick(280, true), bb.snapshot());
  EXPECT_EQ(status(r, PrimitiveId::kGetBody), PrimitiveStatus::kNoData);
  // The skeleton stream goes silent for more than a second.
  r = ev.evaluate(tick(1400, false), bb.snapshot());
  EXPECT_EQ(status(r, PrimitiveId::kGetBody), PrimitiveStatus::kSensorOffline);
}

// getFaces' selected camera: face detection's choice (made from the previous tick's pose), or
// the most frontal camera of this tick's head pose when that pose exists and the camera has a
// detection this tick.
TEST(Evaluator, GetFacesSelectsTheFrontalCameraOfThisTicksHeadPose) {
  Evaluator ev({}, {{keys::kFaceDetections.name, {"camera_middle", "camera_right"}}});
  ASSERT_TRUE(ev.enabled(PrimitiveId::kGetFaces));
  Blackboard bb;
  DetectedFace face{{600, 400, 120, 120}, 0.9f};
  FaceDetections detections;
  detections.cameras["camera_middle"].faces = {face};
  detections.cameras["camera_right"].faces = {face};
  auto faces_at = [&](int64_t t) {
    MultiFrame mf;
    mf.stamp = ms(t);
    for (const char* id : {"camera_middle", "camera_right"})
      mf.frames[id] = make_frame(id, ms(t), 0, ColorImage{});
    const auto r = ev.evaluate(mf, bb.snapshot());
    return r[static_cast<int>(PrimitiveId::kGetFaces) - 1];
  };
  auto detect = [&](int64_t t) {
    BlackboardWriter w("face_detection");
    w.set(keys::kFaceDetections, detections, ms(t), 0.9f);
    w.set(keys::kSelectedCamera, SelectedCamera{"camera_middle", 0, face, 0.8f}, ms(t), 0.9f);
    bb.commit(w, ms(t));
  };
  auto pose = [&](int64_t t, const SensorId& frontal) {
    BlackboardWriter w("head_pose");
    HeadPose p;
    p.camera = "camera_middle";
    p.frontal_camera = frontal;
    w.set(keys::kHeadPose, p, ms(t), 0.8f);
    bb.commit(w, ms(t));
  };
  detect(0);
  auto r = faces_at(0);
  ASSERT_NE(r.value_as<FacesValue>(), nullptr);
  EXPECT_EQ(r.value_as<FacesValue>()->selected_camera, "camera_middle") << "no head pose yet";
  pose(0, "camera_right");
  r = faces_at(0);
  EXPECT_EQ(r.value_as<FacesValue>()->selected_camera, "camera_right");
  EXPECT_EQ(r.source, "camera_right");
  detect(40);  // the pose is the previous tick's: detection's choice stands
  EXPECT_EQ(faces_at(40).value_as<FacesValue>()->selected_camera, "camera_middle");
  pose(40, "camera_left");  // a camera without a detection this tick is not reported
  EXPECT_EQ(faces_at(40).value_as<FacesValue>()->selected_camera, "camera_middle");
}

TEST(Evaluator, IdentifyVoiceIsOkOnceAtTheUtterance) {
  Evaluator ev({}, {{"audio.speaker", {"mic"}}});
  Blackboard bb;
  auto tick = [&](int64_t t) {
    MultiFrame mf;
    mf.stamp = ms(t);
    mf.chunks["mic"].push_back(make_frame("mic", ms(t), 0, AudioChunk{}));
    return mf;
  };
  auto voice = [](const std::vector<PrimitiveRecord>& r) {
    return r[static_cast<int>(PrimitiveId::kIdentifyVoice) - 1];
  };
  EXPECT_EQ(voice(ev.evaluate(tick(0), bb.snapshot())).status, PrimitiveStatus::kNoData);
  int64_t t = 40;
  for (const char* who : {"child", "therapist", "unknown"}) {
    BlackboardWriter w("voice_id");
    w.set(keys::kSpeakerIdentity,
          SpeakerIdentity{who, who, 0.8, ms(t - 1000), ms(t - 500), "mic", "gmm_ubm"}, ms(t), 0.8f);
    bb.commit(w, ms(t));
    const auto r = voice(ev.evaluate(tick(t), bb.snapshot()));
    ASSERT_EQ(r.status, PrimitiveStatus::kOk) << who;
    const VoiceValue* v = r.value_as<VoiceValue>();
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(v->speaker_id, who);
    EXPECT_EQ(v->method, "gmm_ubm");
    EXPECT_EQ(v->start_ns, ms(t - 1000).ns());
    EXPECT_EQ(r.source, "mic");
    // The next tick repeats nothing.
    EXPECT_EQ(voice(ev.evaluate(tick(t + 40), bb.snapshot())).status, PrimitiveStatus::kNoData);
    t += 80;
  }
}

TEST(Evaluator, EnabledExactlyWhenEveryKeyReadHasAWriter) {
  const Evaluator none({}, {});
  const Evaluator faces({}, {{"face.detections", {"cam"}}, {"face.head_pose", {"cam"}}});
  EXPECT_FALSE(none.enabled(PrimitiveId::kGetFaces));
  EXPECT_TRUE(faces.enabled(PrimitiveId::kGetFaces));
  EXPECT_TRUE(faces.enabled(PrimitiveId::kGetHeadGazePlane));
  EXPECT_FALSE(faces.enabled(PrimitiveId::kCheckMutualGaze)) << "no gaze writer";
  for (const auto& i : catalogue()) EXPECT_FALSE(keys_read(i.id).empty()) << i.name;
}

// Every primitive has exactly one row, registered by its family; a second row is refused.
TEST(PrimitiveRegistry, EveryPrimitiveHasOneRowFromItsFamily) {
  for (const auto& i : catalogue()) {
    const PrimitiveRow* row = builtin_primitives().find(i.id);
    ASSERT_NE(row, nullptr) << i.code << " " << i.name;
    EXPECT_EQ(row->id, i.id);
    EXPECT_TRUE(static_cast<bool>(row->evaluate)) << i.name;
  }
  PrimitiveRegistry r;
  r.add(PrimitiveId::kGetBody, {"body.child"}, get_body);
  EXPECT_THROW(r.add(PrimitiveId::kGetBody, {"body.child"}, get_body), CheckFailure);
  EXPECT_THROW(r.add(PrimitiveId::kGetHands, {}, get_hands), CheckFailure) << "reads nothing";
  // An evaluator over a registry without a row answers that primitive as disabled.
  const Evaluator ev({}, {{"body.child", {"skel"}}}, {}, r);
  EXPECT_TRUE(ev.enabled(PrimitiveId::kGetBody));
  EXPECT_FALSE(ev.enabled(PrimitiveId::kGetHands)) << "no row";
}

// The default query of a parametrised primitive comes from its family's options block.
TEST(Evaluator, DefaultQueryComesFromTheFamilyOptions) {
  EvaluatorOptions o;
  o.families.set(AudioPrimitiveOptions{ThresholdQuery{0.7}});
  Evaluator ev(o, {{"audio.sound_direction", {"mic"}}});
  Blackboard bb;
  BlackboardWriter w("sound");
  w.set(keys::kSoundDirection, SoundDirection{20, std::nullopt, {0, 0, 1}, {0, 0, 1}, 0.3, "mic"},
        ms(200), 0.6f);
  bb.commit(w, ms(200));
  MultiFrame mf;
  mf.stamp = ms(200);
  mf.chunks["mic"].push_back(make_frame("mic", ms(200), 0, AudioChunk{}));
  // The records are kept: a reference into the returned temporary would dangle (ASan found it).
  const auto records = ev.evaluate(mf, bb.snapshot());
  const auto& sd = records[static_cast<int>(PrimitiveId::kGetSoundDirection) - 1];
  EXPECT_EQ(sd.status, PrimitiveStatus::kNoData) << "0.6 is below the family's 0.7";
  ASSERT_NE(std::get_if<ThresholdQuery>(&sd.query), nullptr);
  EXPECT_DOUBLE_EQ(std::get<ThresholdQuery>(sd.query).threshold, 0.7);
}

// Parametrised primitives answer any query through the C++ API, not only the evaluator's
// default one.
TEST(Evaluator, ParametrisedPrimitivesTakeTheirQuery) {
  Evaluator ev({}, {{"body.child", {"skel"}}, {"audio.sound_direction", {"mic"}}});
  Blackboard bb;
  for (int i = 0; i < 6; ++i) {
    BlackboardWriter w("body");
    w.set(keys::kChildBody, BodyState{child_with_right_hand({-0.3 + 0.02 * i, 0, 1})}, ms(40 * i),
          1.f);
    bb.commit(w, ms(40 * i));
  }
  BlackboardWriter w("sound");
  w.set(keys::kSoundDirection, SoundDirection{20, std::nullopt, {0, 0, 1}, {0, 0, 1}, 0.3, "mic"},
        ms(200), 0.6f);
  bb.commit(w, ms(200));
  MultiFrame mf;
  mf.stamp = ms(200);
  mf.frames["skel"] = make_frame("skel", ms(200), 0, Skeleton{});
  mf.chunks["mic"].push_back(make_frame("mic", ms(200), 0, AudioChunk{}));
  const auto records = ev.evaluate(mf, bb.snapshot());
  const auto ctx = ev.context(bb.snapshot(), ms(200));
  const auto far = track_hand(ctx, TrackQuery{{-0.2, 0, 1}, 1.0});
  const auto near = track_hand(ctx, TrackQuery{{-0.2, 0, 1}, 0.0});
  ASSERT_TRUE(far.ok() && near.ok());
  EXPECT_NEAR(far.value->position_m[0] - near.value->position_m[0], 0.5, 1e-6)
      << "0.5 m/s for one more second";
  EXPECT_TRUE(get_sound_direction(ctx, ThresholdQuery{0.5}).ok());
  EXPECT_EQ(get_sound_direction(ctx, ThresholdQuery{0.7}).status, PrimitiveStatus::kNoData)
      << "a stricter threshold";
  const auto& sd = records[static_cast<int>(PrimitiveId::kGetSoundDirection) - 1];
  ASSERT_NE(std::get_if<ThresholdQuery>(&sd.query), nullptr) << "the record carries its query";
  EXPECT_DOUBLE_EQ(std::get<ThresholdQuery>(sd.query).threshold, 0.5);
}

}  // namespace
}  // namespace dreamsense::primitives
