#include "dreamsense/geometry/synthetic.hpp"

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <numeric>
#include <random>

namespace dreamsense::geometry {

SyntheticPnp make_synthetic_correspondences(const CameraModel& truth,
                                            const SyntheticPnpOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uu(0, truth.image_size.width - 1.0);
  std::uniform_real_distribution<double> uv(0, truth.image_size.height - 1.0);
  std::uniform_real_distribution<double> ud(o.min_depth_m, o.max_depth_m);
  std::normal_distribution<double> noise(0, o.noise_px);
  SyntheticPnp s;
  const int n = std::max(1, o.points);
  for (int i = 0; i < n; ++i) {
    const cv::Point2d px(uu(rng), uv(rng));
    const cv::Vec3d ray = truth.pixel_ray(px);  // through the distorted pixel
    const cv::Vec3d cam = ray * (ud(rng) / ray[2]);
    const cv::Vec3d w = truth.to_world(cam);
    s.world.emplace_back(w[0], w[1], w[2]);
  }
  // Project with the full model (the pixel_ray/undistort round trip is not exact).
  cv::Mat rvec;
  cv::Rodrigues(cv::Mat(truth.R), rvec);
  cv::projectPoints(s.world, rvec, cv::Mat(truth.t), cv::Mat(truth.K), truth.distortion, s.pixels);
  for (auto& p : s.pixels) p += cv::Point2d(noise(rng), noise(rng));
  s.is_outlier.assign(static_cast<size_t>(n), false);
  const int n_out = static_cast<int>(std::round(o.outlier_fraction * n));
  std::vector<int> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  for (int k = 0; k < n_out; ++k) {
    const size_t i = static_cast<size_t>(order[static_cast<size_t>(k)]);
    cv::Point2d p;
    do {
      p = cv::Point2d(uu(rng), uv(rng));
    } while (cv::norm(p - s.pixels[i]) < o.min_outlier_px);
    s.pixels[i] = p;
    s.is_outlier[i] = true;
  }
  return s;
}

}  // namespace dreamsense::geometry
