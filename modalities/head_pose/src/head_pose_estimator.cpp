#include "dreamsense/head_pose/head_pose_estimator.hpp"

#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::head_pose {
namespace {
constexpr double kRadToDeg = 180.0 / CV_PI;

// The model points and their landmarks in one view (finite landmarks only).
struct ViewPoints {
  const CameraModel* camera = nullptr;
  std::vector<cv::Point3d> model;
  std::vector<cv::Point2d> image;
  double iod_px = 0;
  double weight = 1;  // scale of this view's residuals in the multi-view fit
};

std::optional<ViewPoints> view_points(const PoseView& v, const FaceModel3d& m) {
  if (v.camera == nullptr || v.landmarks_px == nullptr ||
      v.landmarks_px->size() != static_cast<size_t>(kFaceLandmarkCount))
    return std::nullopt;
  ViewPoints out;
  out.camera = v.camera;
  for (size_t i = 0; i < m.landmark_index.size(); ++i) {
    const cv::Point2d& p = (*v.landmarks_px)[static_cast<size_t>(m.landmark_index[i])];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    out.model.push_back(m.points_m[i]);
    out.image.push_back(p);
  }
  out.iod_px = cv::norm(eye_contour_centroid(*v.landmarks_px, 36) -
                        eye_contour_centroid(*v.landmarks_px, 42));
  if (out.model.size() < 4 || !(out.iod_px > 1)) return std::nullopt;
  return out;
}
}  // namespace

Status HeadPoseEstimatorOptions::check() const {
  if (auto s = model.check(); !s) return s;
  std::string bad;
  if (!(max_rms_per_interocular > 0)) bad += " max_rms_per_interocular must be > 0;";
  if (!(max_angle_to_camera_deg > 0 && max_angle_to_camera_deg <= 180))
    bad += " max_angle_to_camera_deg must be in (0, 180];";
  if (!(view_weight_power >= 0 && view_weight_power <= 10))
    bad += " view_weight_power must be in [0, 10];";
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
  const auto view = view_points({&camera, &landmarks_px}, options.model);
  if (!view) return Out{};  // < 4 finite points, or no inter-ocular distance
  const std::vector<cv::Point3d>& obj = view->model;
  const std::vector<cv::Point2d>& img = view->image;
  const double iod_px = view->iod_px;

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
  const double facing =
      facing_cosine(fit.camera_from_head * cv::Vec3d(0, 0, -1), -fit.position_camera_m);
  const double angle = std::acos(std::clamp(facing, -1.0, 1.0)) * kRadToDeg;
  if (angle > options.max_angle_to_camera_deg) return Out{};
  if (fit.rms_px > options.max_rms_per_interocular * iod_px) return Out{};
  return Out{fit};
}

namespace {

// The smallest cosine a view's weight is computed from (an 87-degree view keeps a little say).
constexpr double kMinViewFacing = 0.05;

// Reprojection residuals (x, y per point) of the pose world_from_model = (R, t) in one view,
// times `w`.
void add_residuals(const ViewPoints& v, const cv::Matx33d& R, const cv::Vec3d& t, double w,
                   std::vector<double>& r) {
  const cv::Matx33d Rc = v.camera->R * R;
  const cv::Vec3d tc = v.camera->R * t + v.camera->t;
  cv::Vec3d rvec;
  cv::Rodrigues(Rc, rvec);
  std::vector<cv::Point2d> proj;
  cv::projectPoints(v.model, rvec, tc, cv::Mat(v.camera->K), v.camera->distortion, proj);
  for (size_t i = 0; i < proj.size(); ++i) {
    r.push_back(w * (proj[i].x - v.image[i].x));
    r.push_back(w * (proj[i].y - v.image[i].y));
  }
}

double sum_squares(const std::vector<double>& r) {
  double s = 0;
  for (double x : r) s += x * x;
  return s;
}

// Unweighted: the view's own reprojection error in its pixels.
double view_rms(const ViewPoints& v, const cv::Matx33d& R, const cv::Vec3d& t) {
  std::vector<double> r;
  add_residuals(v, R, t, 1.0, r);
  return std::sqrt(2 * sum_squares(r) / static_cast<double>(r.size()));
}

// The pose after a step: a rotation vector applied on the world side, and a translation.
void apply_step(const cv::Vec<double, 6>& d, cv::Matx33d& R, cv::Vec3d& t) {
  cv::Matx33d dR;
  cv::Rodrigues(cv::Vec3d(d[0], d[1], d[2]), dR);
  R = dR * R;
  t += cv::Vec3d(d[3], d[4], d[5]);
}

std::vector<double> all_residuals(const std::vector<ViewPoints>& views, const cv::Matx33d& R,
                                  const cv::Vec3d& t) {
  std::vector<double> r;
  for (const auto& v : views) add_residuals(v, R, t, v.weight, r);
  return r;
}

// Levenberg-Marquardt over the 6 pose parameters, forward-difference Jacobian.
void fit_views(const std::vector<ViewPoints>& views, cv::Matx33d& R, cv::Vec3d& t) {
  std::vector<double> r = all_residuals(views, R, t);
  double cost = sum_squares(r), lambda = 1e-3;
  constexpr double kStep[6] = {1e-6, 1e-6, 1e-6, 1e-7, 1e-7, 1e-7};
  for (int iter = 0; iter < 20; ++iter) {
    cv::Matx<double, 6, 6> JtJ = cv::Matx<double, 6, 6>::zeros();
    cv::Vec<double, 6> Jtr = cv::Vec<double, 6>::all(0);
    std::vector<std::vector<double>> J(6);
    for (int k = 0; k < 6; ++k) {
      cv::Vec<double, 6> d = cv::Vec<double, 6>::all(0);
      d[k] = kStep[k];
      cv::Matx33d Rk = R;
      cv::Vec3d tk = t;
      apply_step(d, Rk, tk);
      std::vector<double>& column = J[static_cast<size_t>(k)];
      column = all_residuals(views, Rk, tk);
      for (size_t i = 0; i < r.size(); ++i) column[i] = (column[i] - r[i]) / kStep[k];
    }
    for (int a = 0; a < 6; ++a) {
      for (size_t i = 0; i < r.size(); ++i) Jtr[a] += J[static_cast<size_t>(a)][i] * r[i];
      for (int b = a; b < 6; ++b) {
        double s = 0;
        for (size_t i = 0; i < r.size(); ++i)
          s += J[static_cast<size_t>(a)][i] * J[static_cast<size_t>(b)][i];
        JtJ(a, b) = JtJ(b, a) = s;
      }
    }
    bool improved = false;
    for (int tries = 0; tries < 8 && !improved; ++tries) {
      cv::Matx<double, 6, 6> A = JtJ;
      for (int k = 0; k < 6; ++k) A(k, k) *= 1 + lambda;
      cv::Vec<double, 6> step;
      if (!cv::solve(A, -Jtr, step, cv::DECOMP_CHOLESKY)) break;
      cv::Matx33d Rn = R;
      cv::Vec3d tn = t;
      apply_step(step, Rn, tn);
      std::vector<double> rn = all_residuals(views, Rn, tn);
      const double cn = sum_squares(rn);
      if (cn < cost) {
        improved = true;
        const bool converged = cost - cn < 1e-10 * cost;
        R = Rn;
        t = tn;
        r = std::move(rn);
        cost = cn;
        lambda = std::max(lambda * 0.1, 1e-9);
        if (converged) return;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) return;
  }
}

}  // namespace

std::optional<MultiViewFit> refine_head_pose_multi_view(const PnpFit& start, const PoseView& first,
                                                        const std::vector<PoseView>& others,
                                                        const HeadPoseEstimatorOptions& options,
                                                        double view_gate_per_interocular) {
  auto first_points = view_points(first, options.model);
  if (!first_points) return std::nullopt;
  cv::Matx33d R = first.camera->R.t() * start.camera_from_head;
  cv::Vec3d t = first.camera->to_world(start.position_camera_m);
  std::vector<ViewPoints> views{std::move(*first_points)};
  for (const PoseView& o : others) {
    if (o.camera == first.camera) continue;
    auto v = view_points(o, options.model);
    if (v && view_rms(*v, R, t) <= view_gate_per_interocular * v->iod_px)
      views.push_back(std::move(*v));
  }
  if (options.view_weight_power > 0) {
    const cv::Vec3d forward = R * cv::Vec3d(0, 0, -1);  // the face's direction at the start pose
    for (ViewPoints& v : views) {
      const double facing = facing_cosine(forward, v.camera->centre_world() - t);
      v.weight = std::pow(std::max(facing, kMinViewFacing), options.view_weight_power);
    }
  }
  while (views.size() >= 2) {
    cv::Matx33d Rf = R;
    cv::Vec3d tf = t;
    fit_views(views, Rf, tf);
    // The worst view beyond the limit (the first view is the analysis' own: never dropped).
    size_t worst = 0;
    double worst_excess = 1;
    for (size_t i = 1; i < views.size(); ++i) {
      const double excess =
          view_rms(views[i], Rf, tf) / (options.max_rms_per_interocular * views[i].iod_px);
      if (excess > worst_excess) worst = i, worst_excess = excess;
    }
    if (worst != 0) {
      views.erase(views.begin() + static_cast<std::ptrdiff_t>(worst));
      continue;
    }
    const double first_rms = view_rms(views[0], Rf, tf);
    if (first_rms > options.max_rms_per_interocular * views[0].iod_px) return std::nullopt;
    MultiViewFit out;
    out.fit.camera_from_head = first.camera->R * Rf;
    out.fit.position_camera_m = first.camera->to_camera(tf);
    out.fit.rms_px = first_rms;
    out.fit.points_used = 0;
    for (const auto& v : views) out.fit.points_used += static_cast<int>(v.model.size());
    out.views_used = static_cast<int>(views.size());
    if (!(out.fit.position_camera_m[2] > 0)) return std::nullopt;
    return out;
  }
  return std::nullopt;
}

double facing_cosine(const cv::Vec3d& forward, const cv::Vec3d& head_to_camera) {
  return forward.dot(head_to_camera) / cv::norm(head_to_camera);
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
