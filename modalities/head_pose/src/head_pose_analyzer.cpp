#include "dreamsense/head_pose/head_pose_analyzer.hpp"

#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <algorithm>

namespace dreamsense::head_pose {
namespace {

class HeadPoseAnalyzer : public Analyzer {
 public:
  explicit HeadPoseAnalyzer(HeadPoseAnalyzerOptions o)
      : options_(std::move(o)), filter_(options_.filter) {}

  std::string_view name() const override { return "head_pose"; }
  AnalyzerContract contract() const override {
    return {{}, {}, {keys::kFaceLandmarks.name}, {keys::kHeadPose.name}};
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
    (*fit)->camera_from_head = (*fit)->camera_from_head * options_.model_from_head;
    HeadPose pose = make_head_pose(**fit, cam->second, l.camera, l.frame_stamp);
    filter_.apply(pose);
    const double iod = cv::norm(l.right_eye_px() - l.left_eye_px());
    const double quality = std::clamp(
        1.0 - pose.reprojection_rms_px / (options_.estimator.max_rms_per_interocular * iod), 0.0,
        1.0);
    out.set(keys::kHeadPose, std::move(pose), in.stamp,
            static_cast<float>(lm->confidence * quality));
    return ok_status();
  }

  void reset() override { filter_.reset(); }

 private:
  HeadPoseAnalyzerOptions options_;
  PoseFilter filter_;
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
