// face_tracks: 3-D observations from boxes and head pose, and the analyser's blackboard behaviour
// (including the negative case: no face, no invented positions).

#include "dreamsense/face_tracks/face_tracks_analyzer.hpp"

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/face_tracks/face_observations.hpp"
#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace dreamsense::face_tracks {
namespace {

constexpr double kFaceWidth = 0.15;

CameraModel camera(const cv::Vec3d& eye, const cv::Vec3d& target) {
  CameraModel c;
  c.image_size = {1280, 960};
  c.K = cv::Matx33d(1100, 0, 640, 0, 1100, 480, 0, 0, 1);
  look_at(eye, target, {0, 1, 0}, c.R, c.t);
  return c;
}

std::map<SensorId, CameraModel> cameras() {
  return {{"camera_middle", camera({0, 0, 0}, {0, 0, 1.5})},
          {"camera_left", camera({-0.6, 0, 0.2}, {0, 0, 1.5})}};
}

// The box a face of width kFaceWidth at `p` (world) would have in `cam` (square, centred).
DetectedFace face_at(const cv::Vec3d& p, const CameraModel& cam, float score = 0.9f) {
  const auto c = cam.project(p);
  const double w = cam.K(0, 0) * kFaceWidth / cam.to_camera(p)[2];
  return DetectedFace{cv::Rect2d(c->x - w / 2, c->y - w / 2, w, w), score};
}

FaceDetections detections(const std::map<SensorId, std::vector<cv::Vec3d>>& faces) {
  const auto cams = cameras();
  FaceDetections d;
  for (const auto& [id, points] : faces) {
    CameraFaces& cf = d.cameras[id];
    cf.image_size = {1280, 960};
    for (const auto& p : points) cf.faces.push_back(face_at(p, cams.at(id)));
  }
  return d;
}

TEST(FaceObservations, BoxSizeGivesThePositionAndCamerasMerge) {
  const auto cams = cameras();
  const cv::Vec3d face(0.1, -0.05, 1.2);
  // Box size alone, also from a half-resolution frame.
  const DetectedFace f = face_at(face, cams.at("camera_middle"));
  auto p = position_from_box(f.box_px, {1280, 960}, cams.at("camera_middle"), kFaceWidth);
  ASSERT_TRUE(p);
  EXPECT_LT(cv::norm(*p - face), 2e-3);
  const cv::Rect2d half(f.box_px.x / 2, f.box_px.y / 2, f.box_px.width / 2, f.box_px.height / 2);
  p = position_from_box(half, {640, 480}, cams.at("camera_middle"), kFaceWidth);
  ASSERT_TRUE(p);
  EXPECT_LT(cv::norm(*p - face), 2e-3);
  EXPECT_FALSE(position_from_box({10, 10, 0, 0}, {1280, 960}, cams.at("camera_middle"), 0.15));

  // The same face in two cameras is one observation; a second face in one camera stays apart.
  const cv::Vec3d other(-0.5, 0.0, 1.6);
  const FaceDetections d = detections({{"camera_middle", {face, other}}, {"camera_left", {face}}});
  auto obs = face_observations(d, nullptr, nullptr, cams, {});
  ASSERT_TRUE(obs) << obs.error().message;
  ASSERT_EQ(obs->size(), 2u);
  std::sort(obs->begin(), obs->end(), [](const auto& a, const auto& b) {
    return a.position_world_m[0] > b.position_world_m[0];
  });
  EXPECT_LT(cv::norm((*obs)[0].position_world_m - face), 5e-3);
  EXPECT_EQ((*obs)[0].views.size(), 2u);
  EXPECT_LT(cv::norm((*obs)[1].position_world_m - other), 5e-3);
  EXPECT_FALSE((*obs)[0].from_head_pose);

  // A camera without a model is a configuration error.
  auto partial = cams;
  partial.erase("camera_left");
  EXPECT_FALSE(face_observations(d, nullptr, nullptr, partial, {}));
}

TEST(FaceObservations, SelectedFaceSitsAtTheHeadPose) {
  const auto cams = cameras();
  const cv::Vec3d face(0.1, -0.05, 1.2), other(-0.5, 0.0, 1.6);
  const FaceDetections d = detections({{"camera_middle", {other, face}}, {"camera_left", {face}}});
  HeadPose head;
  head.camera = "camera_middle";
  head.position_world_m = face + cv::Vec3d(0, -0.02, 0.03);  // the PnP translation
  for (bool with_selection : {true, false}) {
    SelectedCamera sel;
    sel.camera = "camera_middle";
    sel.face_index = 1;
    auto obs = face_observations(d, with_selection ? &sel : nullptr, &head, cams, {});
    ASSERT_TRUE(obs) << obs.error().message;
    ASSERT_EQ(obs->size(), 2u);
    const auto it = std::find_if(obs->begin(), obs->end(),
                                 [](const FaceObservation3d& o) { return o.from_head_pose; });
    ASSERT_NE(it, obs->end()) << "selection " << with_selection;
    EXPECT_EQ(it->position_world_m, head.position_world_m);
    EXPECT_EQ(it->views.size(), 2u) << "the other camera's view merged into it";
  }
}

struct Harness {
  std::unique_ptr<Analyzer> analyzer;
  Blackboard bb;

  // Commits the upstream entries of one tick, runs the analyser, returns whether it wrote.
  bool run(Timestamp t, const std::optional<FaceDetections>& det, bool write_detections = true) {
    BlackboardWriter up("face_detection");
    if (write_detections) {
      if (det)
        up.set(keys::kFaceDetections, *det, t, 0.9f);
      else
        up.set_absent(keys::kFaceDetections, t);
    }
    bb.commit(up, t);
    MultiFrame mf;
    mf.stamp = t;
    BlackboardWriter w("face_tracks");
    auto s = analyzer->process(mf, bb.snapshot(), w);
    EXPECT_TRUE(s) << s.error().message;
    const bool wrote = !w.empty();
    bb.commit(w, t);
    return wrote;
  }
  FaceTracks tracks() const {
    const auto e = bb.snapshot().get(keys::kFaceTracks);
    return e && e->present() ? *e->value : FaceTracks{};
  }
};

Harness make_harness(bool use_head_pose = true) {
  FaceTracksAnalyzerOptions o;
  o.cameras = cameras();
  o.use_head_pose = use_head_pose;
  o.tracker.max_unseen_s = 0.5;
  auto a = make_face_tracks_analyzer(o);
  EXPECT_TRUE(a) << a.error().message;
  return Harness{std::move(*a), Blackboard{}};
}

TEST(FaceTracksAnalyzer, ContractAndOptions) {
  FaceTracksAnalyzerOptions o;
  EXPECT_FALSE(make_face_tracks_analyzer(o)) << "no cameras";
  o.cameras = cameras();
  auto a = make_face_tracks_analyzer(o);
  ASSERT_TRUE(a);
  const AnalyzerContract c = (*a)->contract();
  EXPECT_EQ(c.writes, std::vector<std::string>{keys::kFaceTracks.name});
  EXPECT_NE(std::find(c.reads.begin(), c.reads.end(), keys::kHeadPose.name), c.reads.end());
  EXPECT_NE(std::find(c.reads.begin(), c.reads.end(), keys::kFaceDetections.name), c.reads.end());
  o.use_head_pose = false;
  const AnalyzerContract c2 = (*make_face_tracks_analyzer(o))->contract();
  EXPECT_EQ(std::find(c2.reads.begin(), c2.reads.end(), keys::kHeadPose.name), c2.reads.end());
}

TEST(FaceTracksAnalyzer, NoFaceMeansNoTrackAndNothingInvented) {
  Harness h = make_harness();
  // No detections entry this tick (no camera frame): nothing written.
  EXPECT_FALSE(h.run(Timestamp::from_seconds(1), std::nullopt, /*write_detections=*/false));
  EXPECT_FALSE(h.bb.snapshot().get(keys::kFaceTracks));
  // Absent detections (frames, no face): an empty list, every tick.
  for (int i = 0; i < 10; ++i) {
    const Timestamp t = Timestamp::from_seconds(1.04 + i * 0.04);
    EXPECT_TRUE(h.run(t, std::nullopt));
    const auto e = h.bb.snapshot().get(keys::kFaceTracks);
    ASSERT_TRUE(e && e->present());
    EXPECT_EQ(e->stamp, t);
    EXPECT_TRUE(e->value->tracks.empty());
    EXPECT_EQ(e->confidence, 0.f);
  }
  // Detections with an empty face list (looked, found nothing): also an empty list.
  FaceDetections none;
  none.cameras["camera_middle"].image_size = {1280, 960};
  EXPECT_TRUE(h.run(Timestamp::from_seconds(2), none));
  EXPECT_TRUE(h.tracks().tracks.empty());
}

TEST(FaceTracksAnalyzer, TracksAFaceThenDropsItAfterItLeaves) {
  Harness h = make_harness();
  const cv::Vec3d start(-0.2, -0.05, 1.3), v(0.2, 0, 0);
  Timestamp t;
  for (int i = 0; i < 25; ++i) {
    t = Timestamp::from_seconds(1 + i * 0.04);
    const cv::Vec3d p = start + v * (i * 0.04);
    ASSERT_TRUE(h.run(t, detections({{"camera_middle", {p}}, {"camera_left", {p}}})));
  }
  FaceTracks tr = h.tracks();
  ASSERT_EQ(tr.tracks.size(), 1u);
  EXPECT_EQ(tr.tracks[0].id, 1);
  EXPECT_LT(cv::norm(tr.tracks[0].position_world_m - (start + v * 0.96)), 0.01);
  EXPECT_LT(cv::norm(tr.tracks[0].velocity_world_mps - v), 0.05);
  const FaceTrack last = tr.tracks[0];
  // The face leaves: the track is listed unchanged (its last state) until max_unseen_s, then
  // the list is empty.
  for (int i = 1; i <= 15; ++i) {
    const Timestamp ti = t + Duration::from_ms(40 * i);
    ASSERT_TRUE(h.run(ti, std::nullopt));
    tr = h.tracks();
    if (i * 0.04 <= 0.5 + 1e-9) {
      ASSERT_EQ(tr.tracks.size(), 1u) << i;
      EXPECT_EQ(tr.tracks[0].position_world_m, last.position_world_m);
      EXPECT_EQ(tr.tracks[0].last_update, t);
    } else {
      EXPECT_TRUE(tr.tracks.empty()) << i;
    }
  }
}

TEST(FaceTracksAnalyzer, UsesTheHeadPoseOfThisTickOnly) {
  Harness h = make_harness();
  const cv::Vec3d face(0.0, -0.05, 1.3);
  const cv::Vec3d pnp = face + cv::Vec3d(0.0, 0.0, 0.1);  // PnP disagrees with the box by 10 cm
  for (int i = 0; i < 5; ++i) {
    const Timestamp t = Timestamp::from_seconds(1 + i * 0.04);
    BlackboardWriter up("head_pose");
    HeadPose head;
    head.camera = "camera_middle";
    head.position_world_m = pnp;
    // Written one tick late: a stale head pose must not be used.
    up.set(keys::kHeadPose, head, i < 4 ? t : t - Duration::from_ms(40), 0.9f);
    h.bb.commit(up, t);
    ASSERT_TRUE(h.run(t, detections({{"camera_middle", {face}}})));
    if (i == 3) {
      ASSERT_EQ(h.tracks().tracks.size(), 1u);
      EXPECT_LT(cv::norm(h.tracks().tracks[0].position_world_m - pnp), 1e-3);
    }
  }
  // Last tick: box position (1.3 m) pulls the filter away from the PnP depth (1.4 m).
  EXPECT_LT(h.tracks().tracks[0].position_world_m[2], pnp[2] - 0.02);
}

}  // namespace
}  // namespace dreamsense::face_tracks
