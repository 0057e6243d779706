#include "dreamsense/gaze/eye_angles.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::gaze {
namespace {

constexpr double kDeg = 180.0 / M_PI;

// (x, y) of the pupil relative to the corner midpoint, in units of the corner distance, with x
// along the corner line oriented towards +x of the frame the points are given in.
std::optional<cv::Vec2d> normalised_offset(cv::Point2d a, cv::Point2d b, cv::Point2d p) {
  if (a.x > b.x) std::swap(a, b);
  const cv::Point2d axis = b - a;
  const double length = std::hypot(axis.x, axis.y);
  if (!(length > 1e-9)) return std::nullopt;
  const cv::Point2d u = axis * (1.0 / length);
  const cv::Point2d n(-u.y, u.x);  // u rotated by +90 deg: points "down" when u points right
  const cv::Point2d d = p - (a + b) * 0.5;
  return cv::Vec2d(d.dot(u) / length, d.dot(n) / length);
}

// Head-frame (x, y) where the pixel's ray meets the head plane z = 0.
std::optional<cv::Point2d> on_head_plane(const CameraModel& camera, const cv::Point2d& px,
                                         const cv::Matx33d& camera_from_head,
                                         const cv::Vec3d& head_position_camera_m) {
  const cv::Vec3d ray = camera.pixel_ray(px);
  const cv::Vec3d normal = camera_from_head * cv::Vec3d(0, 0, 1);
  const double denom = normal.dot(ray);
  if (std::abs(denom) < 1e-6) return std::nullopt;
  const double t = normal.dot(head_position_camera_m) / denom;
  if (!(t > 0)) return std::nullopt;
  const cv::Vec3d head = camera_from_head.t() * (ray * t - head_position_camera_m);
  return cv::Point2d(head[0], head[1]);
}

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Least-squares line y = a x + b over the kept samples.
bool fit_line(const std::vector<double>& x, const std::vector<double>& y,
              const std::vector<char>& keep, double& a, double& b) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!keep[i]) continue;
    n += 1;
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  const double det = n * sxx - sx * sx;
  if (n < 3 || !(det > 1e-12 * n * n)) return false;
  a = (n * sxy - sx * sy) / det;
  b = (sy - a * sx) / n;
  return true;
}

// Fits y = a x + b, drops samples beyond 3 MADs of the residuals, refits.
bool robust_line(const std::vector<double>& x, const std::vector<double>& y, double& a, double& b) {
  std::vector<char> keep(x.size(), 1);
  if (!fit_line(x, y, keep, a, b)) return false;
  std::vector<double> res(x.size());
  for (size_t i = 0; i < x.size(); ++i) res[i] = std::abs(y[i] - (a * x[i] + b));
  const double mad = median_of(res);
  for (size_t i = 0; i < x.size(); ++i) keep[i] = res[i] <= 3.0 * 1.4826 * mad + 1e-9;
  return fit_line(x, y, keep, a, b);
}

}  // namespace

std::optional<cv::Vec2d> pupil_offset_image(const EyeObservation& eye) {
  return normalised_offset(eye.corner_a_px, eye.corner_b_px, eye.pupil_px);
}

std::optional<cv::Vec2d> pupil_offset_head_plane(const EyeObservation& eye,
                                                 const CameraModel& camera,
                                                 const cv::Matx33d& camera_from_head,
                                                 const cv::Vec3d& head_position_camera_m) {
  const auto a = on_head_plane(camera, eye.corner_a_px, camera_from_head, head_position_camera_m);
  const auto b = on_head_plane(camera, eye.corner_b_px, camera_from_head, head_position_camera_m);
  const auto p = on_head_plane(camera, eye.pupil_px, camera_from_head, head_position_camera_m);
  if (!a || !b || !p) return std::nullopt;
  return normalised_offset(*a, *b, *p);
}

Status EyeAngleModel::check() const {
  if (!(std::isfinite(gamma) && gamma > 0 && std::isfinite(epsilon) && epsilon > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "EyeAngleModel: gamma and epsilon must be finite and > 0 (got {}, {})", gamma,
                      epsilon);
  if (!(std::abs(rest_x) <= 0.5 && std::abs(rest_y) <= 0.5))
    return make_error(ErrorCode::kInvalidArgument,
                      "EyeAngleModel: rest offsets must be within +-0.5 (got {}, {})", rest_x,
                      rest_y);
  return ok_status();
}

EyeAngles eye_angles(const cv::Vec2d& offset, const EyeAngleModel& model) {
  return {std::atan(-model.gamma * (offset[0] - model.rest_x)) * kDeg,
          std::atan(model.epsilon * (offset[1] - model.rest_y)) * kDeg};
}

cv::Vec3d eye_direction_head(const EyeAngles& a) {
  return rotation_from_ypr_deg(a.theta_deg, a.phi_deg, 0) * cv::Vec3d(0, 0, -1);
}

EyeAngles angles_of_head_direction(const cv::Vec3d& d) {
  // d = Ry(theta) Rx(phi) (0, 0, -1) = (-sin(theta) cos(phi), sin(phi), -cos(theta) cos(phi))
  const cv::Vec3d u = d / cv::norm(d);
  return {std::atan2(-u[0], -u[2]) * kDeg, std::asin(std::clamp(u[1], -1.0, 1.0)) * kDeg};
}

Result<EyeAngleModel> fit_eye_angle_model(const std::vector<EyeAngleSample>& samples) {
  if (samples.size() < 10)
    return make_error(ErrorCode::kInvalidArgument,
                      "gaze fit: {} samples; at least 10 with known targets are needed",
                      samples.size());
  std::vector<double> x, tx, y, ty;
  for (const auto& s : samples) {
    x.push_back(s.offset[0]);
    tx.push_back(std::tan(s.truth.theta_deg / kDeg));
    y.push_back(s.offset[1]);
    ty.push_back(std::tan(s.truth.phi_deg / kDeg));
  }
  double ah = 0, bh = 0, av = 0, bv = 0;
  if (!robust_line(x, tx, ah, bh) || !robust_line(y, ty, av, bv))
    return make_error(ErrorCode::kInvalidArgument,
                      "gaze fit: the samples do not spread in both directions (degenerate)");
  EyeAngleModel m;
  m.gamma = -ah;  // tan(theta) = -gamma x + gamma rest_x
  m.epsilon = av;
  if (!(m.gamma > 0 && m.epsilon > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "gaze fit: pupil offsets do not follow the targets (gamma {:.3g}, epsilon "
                      "{:.3g}); are the eye centres found?",
                      m.gamma, m.epsilon);
  m.rest_x = bh / m.gamma;
  m.rest_y = -bv / m.epsilon;
  if (auto s = m.check(); !s) return tl::unexpected(s.error());
  return m;
}

}  // namespace dreamsense::gaze
