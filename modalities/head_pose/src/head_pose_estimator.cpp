#include "dreamsense/head_pose/head_pose_estimator.hpp"

#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::head_pose {
namespace {
constexpr double kRadToDeg = 180.0 / CV_PI;

cv::Point2d centroid6(const std::vector<cv::Point2d>& p, size_t first) {
  cv::Point2d c(0, 0);
  for (size_t i = first; i < first + 6; ++i) c += p[i];
  return c * (1.0 / 6);
}
}  // namespace

Status HeadPoseEstimatorOptions::check() const {
  if (auto s = model.check(); !s) return s;
  std::string bad;
  if (!(max_rms_per_interocular > 0)) bad += " max_rms_per_interocular must be > 0;";
  if (!(max_angle_to_camera_deg > 0 && max_angle_to_camera_deg <= 180))
    bad += " max_angle_to_camera_deg must be in (0, 180];";
  if (!bad.empty())
    return make_error(ErrorCode::kInvalidArgument, "HeadPoseEstimatorOptions:{}", bad);
  return ok_status();
}

Result<std::optional<PnpFit>> fit_head_pose(const std::vector<cv::Point2d>& landmarks_px,
                                            const CameraModel& camera,
                                            const HeadPoseEstimatorOptions& options) {
  if (landmarks_px.size() != static_cast<size_t>(kFaceLandmarkCount))
    return make_error(ErrorCode::kInvalidArgument, "fit_head_pose: {} landmarks (need {})",
                      landmarks_px.size(), kFaceLandmarkCount);
  using Out = std::optional<PnpFit>;
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  const FaceModel3d& m = options.model;
  for (size_t i = 0; i < m.landmark_index.size(); ++i) {
    const cv::Point2d& p = landmarks_px[static_cast<size_t>(m.landmark_index[i])];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    obj.push_back(m.points_m[i]);
    img.push_back(p);
  }
  if (obj.size() < 4) return Out{};
  const double iod_px = cv::norm(centroid6(landmarks_px, 36) - centroid6(landmarks_px, 42));
  if (!(iod_px > 1)) return Out{};

  cv::Mat rvec, tvec;
  const cv::Mat K(camera.K);
  try {
    if (!cv::solvePnP(obj, img, K, camera.distortion, rvec, tvec, false, cv::SOLVEPNP_SQPNP))
      return Out{};
    cv::solvePnPRefineLM(obj, img, K, camera.distortion, rvec, tvec);
  } catch (const cv::Exception&) {
    return Out{};  // degenerate point set
  }
  PnpFit fit;
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  fit.camera_from_head = cv::Matx33d(R);
  fit.position_camera_m = cv::Vec3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  fit.points_used = static_cast<int>(obj.size());
  std::vector<cv::Point2d> proj;
  cv::projectPoints(obj, rvec, tvec, K, camera.distortion, proj);
  double ss = 0;
  for (size_t i = 0; i < proj.size(); ++i) {
    const cv::Point2d d = proj[i] - img[i];
    ss += d.dot(d);
  }
  fit.rms_px = std::sqrt(ss / static_cast<double>(proj.size()));

  if (!(fit.position_camera_m[2] > 0)) return Out{};
  const cv::Vec3d forward = fit.camera_from_head * cv::Vec3d(0, 0, -1);
  const cv::Vec3d to_camera = -fit.position_camera_m / cv::norm(fit.position_camera_m);
  const double angle = std::acos(std::clamp(forward.dot(to_camera), -1.0, 1.0)) * kRadToDeg;
  if (angle > options.max_angle_to_camera_deg) return Out{};
  if (fit.rms_px > options.max_rms_per_interocular * iod_px) return Out{};
  return Out{fit};
}

cv::Vec3d ypr_deg_from_rotation(const cv::Matx33d& R) {
  const double pitch = std::asin(std::clamp(-R(1, 2), -1.0, 1.0));
  const double yaw = std::atan2(R(0, 2), R(2, 2));
  const double roll = std::atan2(R(1, 0), R(1, 1));
  return {yaw * kRadToDeg, pitch * kRadToDeg, roll * kRadToDeg};
}

double rotation_angle_deg(const cv::Matx33d& A, const cv::Matx33d& B) {
  cv::Vec3d r;
  cv::Rodrigues(cv::Matx33d(A.t() * B), r);
  return cv::norm(r) * kRadToDeg;
}

void update_derived(HeadPose& pose) {
  const cv::Vec3d ypr = ypr_deg_from_rotation(pose.world_from_head);
  pose.yaw_deg = ypr[0];
  pose.pitch_deg = ypr[1];
  pose.roll_deg = ypr[2];
  pose.gaze_origin_world_m = pose.position_world_m;
  pose.gaze_direction_world = pose.world_from_head * cv::Vec3d(0, 0, -1);
}

HeadPose make_head_pose(const PnpFit& fit, const CameraModel& camera, const SensorId& camera_id,
                        Timestamp frame_stamp) {
  HeadPose p;
  p.camera = camera_id;
  p.frame_stamp = frame_stamp;
  p.camera_from_head = fit.camera_from_head;
  p.position_camera_m = fit.position_camera_m;
  p.world_from_head = camera.R.t() * fit.camera_from_head;
  p.position_world_m = camera.to_world(fit.position_camera_m);
  p.reprojection_rms_px = fit.rms_px;
  p.points_used = fit.points_used;
  update_derived(p);
  return p;
}

}  // namespace dreamsense::head_pose
