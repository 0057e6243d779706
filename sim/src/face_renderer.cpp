#include "dreamsense/sim/face_renderer.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fcntl.h>
#include <unistd.h>

#include "portrait.hpp"

namespace dreamsense::sim {

Status PlanarFaceOptions::check() const {
  std::string bad;
  if (!(face_width_px > 0)) bad += " face_width_px must be > 0;";
  if (!(face_width_m > 0)) bad += " face_width_m must be > 0;";
  if (crop_px.width < 8 || crop_px.height < 8) bad += " crop_px too small;";
  if (!(mask_axes_px.width > 0 && mask_axes_px.height > 0)) bad += " mask_axes_px must be > 0;";
  if (cv::norm(left_eye_px - right_eye_px) < 1) bad += " eyes coincide;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "PlanarFaceOptions:{}", bad);
  return ok_status();
}

PlanarFaceRenderer::PlanarFaceRenderer(PlanarFaceOptions options) : options_(std::move(options)) {
  metres_per_px_ = options_.face_width_m / options_.face_width_px;
  origin_px_ = 0.5 * (options_.left_eye_px + options_.right_eye_px);
}

namespace detail {

cv::Mat read_portrait_image(const std::string& path) {
  std::fflush(stderr);
  const int saved = ::dup(STDERR_FILENO);
  const int devnull = ::open("/dev/null", O_WRONLY);
  if (saved >= 0 && devnull >= 0) ::dup2(devnull, STDERR_FILENO);
  cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
  if (saved >= 0) {
    ::dup2(saved, STDERR_FILENO);
    ::close(saved);
  }
  if (devnull >= 0) ::close(devnull);
  return img;
}

std::vector<cv::Mat> make_texture_levels(const cv::Mat& img, const cv::Rect& c,
                                         const cv::Point2d& mask_centre,
                                         const cv::Size2d& mask_axes, const cv::Mat& subject) {
  cv::Mat crop = img(c).clone();
  cv::Mat alpha(crop.size(), CV_8U, cv::Scalar(0));
  cv::ellipse(alpha,
              cv::RotatedRect(cv::Point2f(static_cast<float>(mask_centre.x - c.x),
                                          static_cast<float>(mask_centre.y - c.y)),
                              cv::Size2f(static_cast<float>(2 * mask_axes.width),
                                         static_cast<float>(2 * mask_axes.height)),
                              0.f),
              cv::Scalar(255), cv::FILLED, cv::LINE_AA);
  cv::GaussianBlur(alpha, alpha, cv::Size(0, 0), 2.5);
  if (!subject.empty()) cv::multiply(alpha, subject, alpha, 1.0 / 255);
  cv::Mat bgra;
  cv::merge(std::vector<cv::Mat>{crop, alpha}, bgra);
  std::vector<cv::Mat> levels;
  for (double sigma : {0.0, 0.7, 1.2, 2.0, 3.0}) {
    if (sigma == 0) {
      levels.push_back(bgra);
    } else {
      cv::Mat b;
      cv::GaussianBlur(bgra, b, cv::Size(0, 0), sigma);
      levels.push_back(b);
    }
  }
  return levels;
}

int texture_level(double scale) {
  if (scale < 0.25) return 4;
  if (scale < 0.4) return 3;
  if (scale < 0.6) return 2;
  if (scale < 0.85) return 1;
  return 0;
}

}  // namespace detail

cv::Vec3d EyesState::gaze_dir() const {
  const cv::Vec3d s = left.gaze_dir + right.gaze_dir;
  const double n = cv::norm(s);
  return n > 1e-12 ? s / n : left.gaze_dir;
}

EyesState FaceRenderer::eyes(const FaceState& state) const {
  EyesState e;
  const cv::Vec3d g = state.head_gaze_dir();
  const cv::Vec3d l = state.to_world(left_eye_head()), r = state.to_world(right_eye_head());
  e.left = {l, l, g};
  e.right = {r, r, g};
  e.open = state.eyelid_closure < 0.5;
  return e;
}

Result<std::unique_ptr<PlanarFaceRenderer>> PlanarFaceRenderer::create(
    const PlanarFaceOptions& options) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  if (!std::filesystem::exists(options.portrait))
    return make_error(ErrorCode::kNotFound,
                      "{}: portrait image not found (install the Debian package python3-skimage)",
                      options.portrait.string());
  cv::Mat img = detail::read_portrait_image(options.portrait.string());
  if (img.empty())
    return make_error(ErrorCode::kCorruptData, "{}: cannot decode the portrait image",
                      options.portrait.string());
  if ((options.crop_px & cv::Rect(0, 0, img.cols, img.rows)) != options.crop_px)
    return make_error(ErrorCode::kInvalidArgument, "{}: crop {}x{}+{}+{} outside the {}x{} image",
                      options.portrait.string(), options.crop_px.width, options.crop_px.height,
                      options.crop_px.x, options.crop_px.y, img.cols, img.rows);
  std::unique_ptr<PlanarFaceRenderer> r(new PlanarFaceRenderer(options));
  r->texture_levels_ = detail::make_texture_levels(img, options.crop_px, options.mask_centre_px,
                                                   options.mask_axes_px);
  return r;
}

cv::Vec3d PlanarFaceRenderer::head_point(const cv::Point2d& px) const {
  return {(px.x - origin_px_.x) * metres_per_px_, (px.y - origin_px_.y) * metres_per_px_, 0.0};
}
cv::Vec3d PlanarFaceRenderer::left_eye_head() const { return head_point(options_.left_eye_px); }
cv::Vec3d PlanarFaceRenderer::right_eye_head() const { return head_point(options_.right_eye_px); }

std::vector<cv::Vec3d> PlanarFaceRenderer::face_region_head() const {
  const cv::Rect2d& f = options_.face_region_px;
  return {head_point(f.tl()), head_point({f.x + f.width, f.y}), head_point(f.br()),
          head_point({f.x, f.y + f.height})};
}

cv::Matx33d PlanarFaceRenderer::homography(const CameraModel& camera,
                                           const FaceState& state) const {
  // Crop pixel (x, y) -> portrait pixel (x + crop.x, y + crop.y) -> head point -> camera.
  const cv::Matx33d A = camera.R * state.world_from_head;
  const double s = metres_per_px_;
  const cv::Vec3d a0(A(0, 0), A(1, 0), A(2, 0)), a1(A(0, 1), A(1, 1), A(2, 1));
  const cv::Vec3d c = camera.to_camera(state.position_m) +
                      s * (options_.crop_px.x - origin_px_.x) * a0 +
                      s * (options_.crop_px.y - origin_px_.y) * a1;
  const cv::Matx33d M(s * a0[0], s * a1[0], c[0], s * a0[1], s * a1[1], c[1], s * a0[2], s * a1[2],
                      c[2]);
  const cv::Matx33d from_portrait(1, 0, -options_.crop_px.x, 0, 1, -options_.crop_px.y, 0, 0, 1);
  return camera.K * M * from_portrait;
}

void PlanarFaceRenderer::render(const CameraModel& camera, const FaceState& state,
                                const Lighting& lighting, RenderTarget& target) const {
  DS_CHECK(target.bgr.size() == camera.image_size);
  const cv::Vec3d n_world = state.world_from_head * cv::Vec3d(0, 0, -1);  // face normal (front)
  const cv::Vec3d to_cam = camera.centre_world() - state.position_m;
  const double facing = n_world.dot(to_cam) / cv::norm(to_cam);
  if (facing < 0.05) return;  // seen from behind or edge-on: the head ellipsoid shows instead

  const cv::Rect& c = options_.crop_px;
  std::vector<cv::Vec3d> corners = {
      state.to_world(head_point({double(c.x), double(c.y)})),
      state.to_world(head_point({double(c.x + c.width), double(c.y)})),
      state.to_world(head_point({double(c.x + c.width), double(c.y + c.height)})),
      state.to_world(head_point({double(c.x), double(c.y + c.height)}))};
  const cv::Rect roi = projected_bounds(camera, corners, target.bgr.size(), 2);
  if (roi.empty()) return;

  // Texture level from the magnification at the face centre.
  const double z = camera.to_camera(state.position_m)[2];
  if (z <= 0.05) return;
  const double scale = camera.K(0, 0) * metres_per_px_ / z * std::sqrt(std::max(facing, 0.1));
  const int level = detail::texture_level(scale);
  const cv::Mat& tex = texture_levels_[static_cast<size_t>(level)];

  const cv::Matx33d H_crop = homography(camera, state) *
                             cv::Matx33d(1, 0, c.x, 0, 1, c.y, 0, 0, 1);  // crop px -> image px
  const cv::Matx33d to_roi(1, 0, -roi.x, 0, 1, -roi.y, 0, 0, 1);
  cv::Mat patch;
  cv::warpPerspective(tex, patch, cv::Mat(to_roi * H_crop), roi.size(), cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT, cv::Scalar::all(0));

  // Plane depth per pixel: z = (n . o) / (n . d) in camera coordinates, d = (x', y', 1).
  const cv::Vec3d n_cam = camera.R * n_world;
  const double no = n_cam.dot(camera.to_camera(state.position_m));
  const double shade = lambert_shade(n_world, -to_cam, lighting);
  const double fx = camera.K(0, 0), fy = camera.K(1, 1), cx = camera.K(0, 2), cy = camera.K(1, 2);
  for (int v = 0; v < roi.height; ++v) {
    const cv::Vec4b* prow = patch.ptr<cv::Vec4b>(v);
    cv::Vec3b* out = target.bgr.ptr<cv::Vec3b>(v + roi.y) + roi.x;
    float* zb = target.depth.ptr<float>(v + roi.y) + roi.x;
    const double dy = (v + roi.y - cy) / fy;
    for (int u = 0; u < roi.width; ++u) {
      const cv::Vec4b& p = prow[u];
      if (p[3] == 0) continue;
      const double dx = (u + roi.x - cx) / fx;
      const double den = n_cam[0] * dx + n_cam[1] * dy + n_cam[2];
      if (std::abs(den) < 1e-12) continue;
      const double zp = no / den;
      if (zp <= 0.02 || zp >= zb[u]) continue;
      const double a = p[3] / 255.0;
      for (int k = 0; k < 3; ++k)
        out[u][k] = cv::saturate_cast<uchar>(a * p[k] * shade + (1 - a) * out[u][k]);
      if (p[3] >= 128) zb[u] = static_cast<float>(zp);
    }
  }
}

}  // namespace dreamsense::sim
