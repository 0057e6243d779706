#include "dreamsense/head_pose/head_pose_analyzer.hpp"

#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace dreamsense::head_pose {
namespace {

class HeadPoseAnalyzer : public Analyzer {
 public:
  explicit HeadPoseAnalyzer(HeadPoseAnalyzerOptions o)
      : options_(std::move(o)), filter_(options_.filter), image_filter_(options_.filter) {}

  std::string_view name() const override { return "head_pose"; }
  AnalyzerContract contract() const override {
    // The other views are read for the multi-view fit and for frontal_camera.
    return {
        {}, {}, {keys::kFaceLandmarks.name, keys::kFaceLandmarkViews.name}, {keys::kHeadPose.name}};
  }

  Status process(const MultiFrame& in, const BlackboardView& prior,
                 BlackboardWriter& out) override {
    const auto lm = prior.get(keys::kFaceLandmarks);
    if (!lm || lm->stamp != in.stamp) return ok_status();
    if (!lm->present()) {
      out.set_absent(keys::kHeadPose, in.stamp);
      return ok_status();
    }
    const FaceLandmarks& l = *lm->value;
    const auto cam = options_.cameras.find(l.camera);
    if (cam == options_.cameras.end())
      return make_error(ErrorCode::kNotFound, "head_pose: no camera model for '{}'", l.camera);
    auto fit = fit_head_pose(l.points_px, cam->second, options_.estimator);
    if (!fit) return tl::unexpected(fit.error());
    if (!*fit) {
      out.set_absent(keys::kHeadPose, in.stamp);
      return ok_status();
    }
    // The fit is in the face model's frame; the subject calibration turns it into the head's.
    auto pose_of = [&](PnpFit f) {
      f.camera_from_head = f.camera_from_head * options_.model_from_head;
      return make_head_pose(f, cam->second, l.camera, l.frame_stamp);
    };
    // The same face in the other cameras this tick (null: none).
    const auto views_entry = prior.get(keys::kFaceLandmarkViews);
    const FaceLandmarkViews* others =
        views_entry && views_entry->stamp == in.stamp && views_entry->present()
            ? views_entry->value.get()
            : nullptr;
    std::optional<HeadPose::ImagePose> image;
    int views = 1;
    if (options_.multi_view) {
      // Kept on every tick: the two filters' states differ after a multi-view tick.
      HeadPose single = pose_of(**fit);
      image_filter_.apply(single);
      image = HeadPose::ImagePose{single.camera_from_head, single.position_camera_m,
                                  single.world_from_head, single.position_world_m};
      views = refine_with_other_views(others, l, cam->second, **fit);
    }
    HeadPose pose = pose_of(**fit);
    filter_.apply(pose);
    pose.views_used = views;
    pose.image = image;
    pose.frontal_camera = frontal_camera(others, l.camera, pose.gaze_direction_world);
    const double iod = cv::norm(l.right_eye_px() - l.left_eye_px());
    const double quality = std::clamp(
        1.0 - pose.reprojection_rms_px / (options_.estimator.max_rms_per_interocular * iod), 0.0,
        1.0);
    out.set(keys::kHeadPose, std::move(pose), in.stamp,
            static_cast<float>(lm->confidence * quality));
    return ok_status();
  }

  void reset() override {
    filter_.reset();
    image_filter_.reset();
  }

 private:
  // Of `fitted` and the cameras of this tick's other landmark views, the one with the smallest
  // |yaw| of `gaze_world` (ties: the first in that order).
  SensorId frontal_camera(const FaceLandmarkViews* others, const SensorId& fitted,
                          const cv::Vec3d& gaze_world) const {
    std::vector<SensorId> seen{fitted};
    if (others != nullptr)
      for (const FaceLandmarks& o : others->others) seen.push_back(o.camera);
    SensorId best;
    double best_yaw = 0;
    for (const SensorId& id : seen) {
      const auto c = options_.cameras.find(id);
      if (c == options_.cameras.end()) continue;
      const double yaw = std::abs(c->second.yaw_towards_deg(gaze_world));
      if (best.empty() || yaw < best_yaw) best = id, best_yaw = yaw;
    }
    return best;
  }

  // Issue 15: the other cameras that see the face this tick refine the selected camera's fit;
  // returns the number of views the fit explains.
  int refine_with_other_views(const FaceLandmarkViews* views, const FaceLandmarks& selected,
                              const CameraModel& camera, PnpFit& fit) const {
    if (views == nullptr) return 1;
    std::vector<PoseView> others;
    for (const FaceLandmarks& o : views->others) {
      const auto c = options_.cameras.find(o.camera);
      if (c != options_.cameras.end()) others.push_back({&c->second, &o.points_px});
    }
    if (others.empty()) return 1;
    auto multi = refine_head_pose_multi_view(fit, {&camera, &selected.points_px}, others,
                                             options_.estimator);
    if (!multi) return 1;
    fit = multi->fit;
    return multi->views_used;
  }

  HeadPoseAnalyzerOptions options_;
  PoseFilter filter_;
  PoseFilter
      image_filter_;  // with multi_view: the same filter on the single view (HeadPose::image)
};

}  // namespace

Status HeadPoseAnalyzerOptions::check() const {
  if (cameras.empty())
    return make_error(ErrorCode::kInvalidArgument, "HeadPoseAnalyzerOptions: no camera models");
  for (const auto& [id, c] : cameras)
    if (auto s = c.check(); !s)
      return make_error(ErrorCode::kInvalidArgument, "HeadPoseAnalyzerOptions: camera '{}': {}", id,
                        s.error().message);
  if (auto s = estimator.check(); !s) return s;
  return filter.check();
}

Result<std::unique_ptr<Analyzer>> make_head_pose_analyzer(const HeadPoseAnalyzerOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  return std::unique_ptr<Analyzer>(new HeadPoseAnalyzer(options));
}

}  // namespace dreamsense::head_pose
