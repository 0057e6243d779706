#include "dreamsense/gaze/eyeball_model.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::gaze {

Status EyeballModel::check() const {
  if (!(std::isfinite(radius_m) && radius_m > 0.003 && radius_m < 0.025))
    return make_error(ErrorCode::kInvalidArgument,
                      "EyeballModel: radius_m must be in (0.003, 0.025) m (got {})", radius_m);
  if (!(std::isfinite(cv::norm(centre_head_m)) && cv::norm(centre_head_m) < 0.1))
    return make_error(ErrorCode::kInvalidArgument,
                      "EyeballModel: centre must be within 0.1 m of the head origin");
  return ok_status();
}

Status AnatomicalEyeOptions::check() const {
  if (!(centre_depth_m > 0 && centre_depth_m < 0.03 && radius_m > 0.003 && radius_m < 0.025 &&
        std::abs(pupil_above_opening_m) < 0.005))
    return make_error(ErrorCode::kInvalidArgument,
                      "AnatomicalEyeOptions: centre_depth_m must be in (0, 30) mm, radius_m in "
                      "(3, 25) mm and |pupil_above_opening_m| < 5 mm");
  return ok_status();
}

EyeballModel anatomical_eyeball(const cv::Vec3d& opening_centroid_head_m,
                                const AnatomicalEyeOptions& options) {
  // Head frame: y down, z backwards.
  return {opening_centroid_head_m +
              cv::Vec3d(0, -options.pupil_above_opening_m, options.centre_depth_m),
          options.radius_m};
}

HeadRay pixel_ray_head(const cv::Point2d& px, const CameraModel& camera,
                       const cv::Matx33d& camera_from_head,
                       const cv::Vec3d& head_position_camera_m) {
  const cv::Matx33d head_from_camera = camera_from_head.t();
  return {head_from_camera * (-head_position_camera_m), head_from_camera * camera.pixel_ray(px)};
}

std::optional<cv::Vec3d> eyeball_direction(const HeadRay& ray, const EyeballModel& eye) {
  const cv::Vec3d oc = eye.centre_head_m - ray.origin_m;
  const double along = ray.direction.dot(oc);
  const double disc = along * along - (oc.dot(oc) - eye.radius_m * eye.radius_m);
  // First intersection (the camera-facing side), or the ray point nearest the centre.
  const double t = disc > 0 ? along - std::sqrt(disc) : along;
  const cv::Vec3d v = ray.origin_m + t * ray.direction - eye.centre_head_m;
  const double n = cv::norm(v);
  if (!(n > 1e-9) || !std::isfinite(n)) return std::nullopt;
  return v / n;
}

namespace {
// Solves the stacked (I - u u^T)[C; r] system over the kept samples; residual per sample = the
// distance of the predicted pupil from the ray.
bool solve(const std::vector<EyeballSample>& s, const std::vector<char>& keep, EyeballModel& m) {
  cv::Matx44d AtA = cv::Matx44d::zeros();
  cv::Vec4d Atb(0, 0, 0, 0);
  int n = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (!keep[i]) continue;
    const cv::Vec3d& u = s[i].pupil_ray.direction;
    const cv::Matx33d P = cv::Matx33d::eye() - u * u.t();
    const cv::Vec3d Pd = P * s[i].truth_direction;
    const cv::Vec3d Po = P * s[i].pupil_ray.origin_m;
    for (int row = 0; row < 3; ++row) {
      const cv::Vec4d a(P(row, 0), P(row, 1), P(row, 2), Pd[row]);
      AtA += a * a.t();
      Atb += a * Po[row];
    }
    ++n;
  }
  if (n < 10) return false;
  cv::Vec4d w;
  cv::eigen(AtA, w);
  if (!(w[3] > 1e-9 * w[0])) return false;  // directions do not vary: r and C confounded
  const cv::Vec4d x = AtA.solve(Atb, cv::DECOMP_CHOLESKY);
  m.centre_head_m = {x[0], x[1], x[2]};
  m.radius_m = x[3];
  return true;
}

double residual(const EyeballSample& s, const EyeballModel& m) {
  const cv::Vec3d p = m.centre_head_m + m.radius_m * s.truth_direction - s.pupil_ray.origin_m;
  return cv::norm(p - s.pupil_ray.direction * p.dot(s.pupil_ray.direction));
}
}  // namespace

Result<EyeballModel> fit_eyeball_model(const std::vector<EyeballSample>& samples) {
  if (samples.size() < 10)
    return make_error(ErrorCode::kInvalidArgument,
                      "eyeball fit: {} samples; at least 10 with known targets are needed",
                      samples.size());
  std::vector<char> keep(samples.size(), 1);
  EyeballModel m;
  if (!solve(samples, keep, m))
    return make_error(ErrorCode::kInvalidArgument,
                      "eyeball fit: the eye directions do not vary enough (degenerate)");
  std::vector<double> res(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) res[i] = residual(samples[i], m);
  std::vector<double> sorted = res;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2),
                   sorted.end());
  const double mad = sorted[sorted.size() / 2];
  for (size_t i = 0; i < samples.size(); ++i) keep[i] = res[i] <= 3.0 * 1.4826 * mad + 1e-12;
  if (!solve(samples, keep, m))
    return make_error(ErrorCode::kInvalidArgument, "eyeball fit: too few samples after trimming");
  if (auto s = m.check(); !s)
    return make_error(s.error().code, "eyeball fit: {} (are the pupils found?)", s.error().message);
  return m;
}

}  // namespace dreamsense::gaze
