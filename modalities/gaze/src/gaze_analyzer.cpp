#include "dreamsense/gaze/gaze_analyzer.hpp"

#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/gaze.hpp"
#include "dreamsense/perception/head_pose.hpp"

namespace dreamsense::gaze {
namespace {

class GazeAnalyzer : public Analyzer {
 public:
  explicit GazeAnalyzer(GazeAnalyzerOptions o)
      : options_(std::move(o)),
        mutual_(options_.mutual),
        filter_(options_.filter),
        fixation_yaw_(options_.fixation_yaw) {}

  std::string_view name() const override { return "gaze"; }
  AnalyzerContract contract() const override {
    return {{},
            {},
            {keys::kFaceLandmarks.name, keys::kEyeCenters.name, keys::kHeadPose.name},
            {keys::kEyeGaze.name, keys::kMutualGaze.name}};
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto lm = prior.get(keys::kFaceLandmarks);
    if (!lm || lm->stamp != in.stamp) return ok_status();
    const auto eyes = prior.get(keys::kEyeCenters);
    const auto head = prior.get(keys::kHeadPose);
    const bool usable = lm->present() && eyes && eyes->stamp == in.stamp && eyes->present() &&
                        head && head->stamp == in.stamp && head->present() &&
                        eyes->value->frame_stamp == lm->value->frame_stamp &&
                        head->value->camera == lm->value->camera;
    if (!usable) return absent(in.stamp, out);
    const auto cam = options_.cameras.find(lm->value->camera);
    if (cam == options_.cameras.end())
      return make_error(ErrorCode::kNotFound, "gaze: no camera model for '{}'", lm->value->camera);
    // The selected image's own head pose: the eye-in-head angles are measured in that image
    // (HeadPose::image; a multi-view pose made gaze 1-2 degrees worse).
    const HeadPose image_head = head->value->as_image_pose();
    auto g = estimate_gaze(*lm->value, *eyes->value, image_head, cam->second, options_.estimator);
    if (!g) return absent(in.stamp, out);
    smooth(*g, image_head);
    if (options_.mutual.mode == MutualGazeMode::k3d) correct_yaw(*g, image_head);

    double miss = 0;
    bool raw = false;
    if (options_.mutual.mode == MutualGazeMode::k3d) {
      raw = gaze_hits_robot_3d(g->both, options_.mutual, miss);
    } else {
      const SensorId ref =
          options_.reference_camera.empty() ? lm->value->camera : options_.reference_camera;
      const auto rc = options_.cameras.find(ref);
      if (rc == options_.cameras.end())
        return make_error(ErrorCode::kNotFound, "gaze: no camera model for reference '{}'", ref);
      raw = gaze_hits_camera_rect(g->both, rc->second, options_.mutual, miss);
    }
    const EyeCenters& pupils = *eyes->value;
    if (options_.mutual.require_visible_pupil && pupils.pupil_stage && !pupils.right.pupil_found &&
        !pupils.left.pupil_found)
      raw = false;
    const float confidence = std::min(head->confidence, eyes->confidence);
    out.set(keys::kMutualGaze, mutual_.update(in.stamp, raw, miss), in.stamp, confidence);
    out.set(keys::kEyeGaze, std::move(*g), in.stamp, confidence);
    return ok_status();
  }

  void reset() override {
    mutual_.reset();
    filter_.reset();
    fixation_yaw_.reset();
  }

 private:
  // Smooths the fused ray's eye-in-head direction (the head pose is smoothed on its own).
  void smooth(EyeGaze& g, const HeadPose& head) {
    if (!g.both.valid) return;
    const cv::Vec3d in_head =
        filter_.apply(g.frame_stamp, head.world_from_head.t() * g.both.direction_world);
    g.both.direction_world = head.world_from_head * in_head;
    const EyeAngles a = angles_of_head_direction(in_head);
    g.both.theta_deg = a.theta_deg;
    g.both.phi_deg = a.phi_deg;
  }

  // Turns every ray by the yaw learnt from the earlier ticks' fixations on the robot's head
  // (fixation_yaw.hpp), then learns from this tick's uncorrected gaze.
  void correct_yaw(EyeGaze& g, const HeadPose& head) {
    if (!g.both.valid) return;
    const cv::Matx33d head_from_world = head.world_from_head.t();
    const double yaw = fixation_yaw_.correction_deg();
    fixation_yaw_.observe(head_from_world * g.both.direction_world,
                          head_from_world * (options_.mutual.robot_head_m - g.both.origin_world_m));
    g.fixation_yaw_deg = yaw;
    if (yaw == 0) return;
    for (GazeRay* r : {&g.right, &g.left, &g.both}) {
      if (!r->valid) continue;
      const cv::Vec3d turned = turned_yaw(head_from_world * r->direction_world, yaw);
      r->direction_world = head.world_from_head * turned;
      const EyeAngles a = angles_of_head_direction(turned);
      r->theta_deg = a.theta_deg;
      r->phi_deg = a.phi_deg;
    }
  }

  Status absent(Timestamp stamp, BlackboardWriter& out) {
    mutual_.reset();
    filter_.reset();
    out.set_absent(keys::kEyeGaze, stamp);
    out.set_absent(keys::kMutualGaze, stamp);
    return ok_status();
  }

  GazeAnalyzerOptions options_;
  MutualGazeTracker mutual_;
  DirectionFilter filter_;
  FixationYawEstimator fixation_yaw_;
};

}  // namespace

Status GazeAnalyzerOptions::check() const {
  if (cameras.empty())
    return make_error(ErrorCode::kInvalidArgument, "GazeAnalyzerOptions: no camera models");
  for (const auto& [id, c] : cameras)
    if (auto s = c.check(); !s) return s;
  if (!reference_camera.empty() && !cameras.count(reference_camera))
    return make_error(ErrorCode::kInvalidArgument,
                      "GazeAnalyzerOptions: reference camera '{}' has no camera model",
                      reference_camera);
  if (auto s = estimator.check(); !s) return s;
  if (auto s = filter.check(); !s) return s;
  if (auto s = fixation_yaw.check(); !s) return s;
  return mutual.check();
}

Result<std::unique_ptr<Analyzer>> make_gaze_analyzer(const GazeAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  return std::unique_ptr<Analyzer>(new GazeAnalyzer(options));
}

}  // namespace dreamsense::gaze
