// MeshFaceRenderer: the portrait as a textured 3-D triangle mesh with ray-cast eyeballs.
// Method and numbers: sim/README.md ("The face").

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/core/opencv_error.hpp"
#include "dreamsense/sim/face_renderer.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "portrait.hpp"
#include "sim_math.hpp"

#ifndef DREAMSENSE_DEMO_DATA_DIR
#define DREAMSENSE_DEMO_DATA_DIR "data/demo"
#endif

namespace dreamsense::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDeg = CV_PI / 180.0;
constexpr int kLandmarks = 68;

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

double gauss2(double dx, double sx, double dy, double sy) {
  return std::exp(-0.5 * ((dx / sx) * (dx / sx) + (dy / sy) * (dy / sy)));
}

double segment_distance(const cv::Point2d& p, const cv::Point2d& a, const cv::Point2d& b) {
  const cv::Point2d ab = b - a;
  const double l2 = ab.dot(ab);
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return cv::norm(p - (a + t * ab));
}

double polyline_distance(const cv::Point2d& p, const cv::Point2d* pts, int n) {
  double d = kInf;
  for (int i = 0; i + 1 < n; ++i) d = std::min(d, segment_distance(p, pts[i], pts[i + 1]));
  return d;
}

bool inside_polygon(const cv::Point2d* poly, int n, const cv::Point2d& p) {
  bool in = false;
  for (int i = 0, j = n - 1; i < n; j = i++) {
    if ((poly[i].y > p.y) != (poly[j].y > p.y) &&
        p.x < (poly[j].x - poly[i].x) * (p.y - poly[i].y) / (poly[j].y - poly[i].y) + poly[i].x)
      in = !in;
  }
  return in;
}

// Bilinear BGRA sample at texture pixel (x, y), clamped to the texture.
inline void sample_bgra(const cv::Mat& tex, double x, double y, double out[4]) {
  x = std::clamp(x, 0.0, tex.cols - 1.0001);
  y = std::clamp(y, 0.0, tex.rows - 1.0001);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const uchar* p0 = tex.ptr<uchar>(y0) + 4 * x0;
  const uchar* p1 = tex.ptr<uchar>(y0 + 1) + 4 * x0;
  for (int k = 0; k < 4; ++k)
    out[k] =
        (1 - fy) * ((1 - fx) * p0[k] + fx * p0[k + 4]) + fy * ((1 - fx) * p1[k] + fx * p1[k + 4]);
}

using detail::normalized;

// Unit gaze direction (head frame) for eye-in-head yaw/pitch (degrees), as look_at_angles.
cv::Vec3d direction_from_angles(double yaw_deg, double pitch_deg) {
  const double y = yaw_deg * kDeg, p = pitch_deg * kDeg;
  return {-std::sin(y) * std::cos(p), std::sin(p), -std::cos(y) * std::cos(p)};
}

}  // namespace

std::filesystem::path default_portrait_landmarks_path() {
  return std::filesystem::path(DREAMSENSE_DEMO_DATA_DIR) / "astronaut_landmarks.yaml";
}

Result<std::vector<cv::Point2d>> read_portrait_landmarks(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path))
    return make_error(ErrorCode::kNotFound,
                      "{}: portrait landmarks not found (data/demo/astronaut_landmarks.yaml of the "
                      "dreamsense source tree)",
                      path.string());
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(path));
  cv::Mat m;
  try {
    fs["landmarks_px"] >> m;
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), opencv_reason(e));
  }
  if (m.rows != kLandmarks || m.cols != 2)
    return make_error(ErrorCode::kCorruptData, "{}: landmarks_px is {}x{}, expected 68x2",
                      path.string(), m.rows, m.cols);
  m.convertTo(m, CV_64F);
  std::vector<cv::Point2d> out;
  for (int i = 0; i < m.rows; ++i) out.emplace_back(m.at<double>(i, 0), m.at<double>(i, 1));
  return out;
}

Status MeshFaceOptions::check() const {
  std::string bad;
  if (!(face_width_px > 0)) bad += " face_width_px must be > 0;";
  if (!(face_width_m > 0)) bad += " face_width_m must be > 0;";
  if (crop_px.width < 8 || crop_px.height < 8) bad += " crop_px too small;";
  if (!(mask_axes_px.width > 8 && mask_axes_px.height > 8)) bad += " mask_axes_px must be > 8;";
  if (!(grid_spacing_px >= 3)) bad += " grid_spacing_px must be >= 3;";
  if (!(eyeball_radius_m > 0.005 && eyeball_radius_m < 0.03))
    bad += " eyeball_radius_m must be in (0.005, 0.03);";
  if (!(pupil_radius_m > 0 && pupil_radius_m < iris_radius_m && iris_radius_m < eyeball_radius_m))
    bad += " need 0 < pupil_radius_m < iris_radius_m < eyeball_radius_m;";
  if (!(eye_opening_scale[0] >= 1 && eye_opening_scale[1] >= 1 && eye_opening_scale[0] < 2 &&
        eye_opening_scale[1] < 2))
    bad += " eye_opening_scale must be in [1, 2);";
  if (!(max_eye_yaw_deg > 0 && max_eye_yaw_deg <= 60 && max_eye_pitch_deg > 0 &&
        max_eye_pitch_deg <= 60))
    bad += " max_eye_yaw_deg / max_eye_pitch_deg must be in (0, 60];";
  if (!(shape.face_a_m > 0 && shape.face_b_m > 0 && shape.face_c_m > 0 && shape.hair_c_m > 0))
    bad += " head shape semi-axes must be > 0;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "MeshFaceOptions:{}", bad);
  return ok_status();
}

MeshFaceRenderer::MeshFaceRenderer(MeshFaceOptions options) : options_(std::move(options)) {
  metres_per_px_ = options_.face_width_m / options_.face_width_px;
}

cv::Point2d MeshFaceRenderer::head_xy(const cv::Point2d& px) const {
  return (px - origin_px_) * metres_per_px_;
}

Result<std::unique_ptr<MeshFaceRenderer>> MeshFaceRenderer::create(const MeshFaceOptions& options) {
  if (auto st = options.check(); !st) return tl::unexpected(st.error());
  if (!std::filesystem::exists(options.portrait))
    return make_error(ErrorCode::kNotFound,
                      "{}: portrait image not found (install the Debian package python3-skimage)",
                      options.portrait.string());
  auto landmarks = read_portrait_landmarks(options.landmarks);
  if (!landmarks) return tl::unexpected(landmarks.error());
  cv::Mat img = detail::read_portrait_image(options.portrait.string());
  if (img.empty())
    return make_error(ErrorCode::kCorruptData, "{}: cannot decode the portrait image",
                      options.portrait.string());
  const cv::Rect image_rect(0, 0, img.cols, img.rows);
  if ((options.crop_px & image_rect) != options.crop_px)
    return make_error(ErrorCode::kInvalidArgument, "{}: crop {}x{}+{}+{} outside the {}x{} image",
                      options.portrait.string(), options.crop_px.width, options.crop_px.height,
                      options.crop_px.x, options.crop_px.y, img.cols, img.rows);
  const cv::Rect2d inner(options.crop_px.x + 1, options.crop_px.y + 1, options.crop_px.width - 2,
                         options.crop_px.height - 2);
  for (const auto& p : *landmarks)
    if (!inner.contains(p))
      return make_error(ErrorCode::kCorruptData,
                        "{}: landmark ({}, {}) outside the texture crop (wrong portrait?)",
                        options.landmarks.string(), p.x, p.y);

  std::unique_ptr<MeshFaceRenderer> r(new MeshFaceRenderer(options));
  r->landmarks_px_ = *landmarks;
  const auto& L = r->landmarks_px_;
  // Eye openings: landmark centroids; the head-frame origin is their midpoint.
  std::array<cv::Point2d, 2> eye_px;
  for (int e = 0; e < 2; ++e) {
    cv::Point2d c(0, 0);
    for (int k = 0; k < 6; ++k) c += L[static_cast<size_t>(36 + 6 * e + k)];
    eye_px[static_cast<size_t>(e)] = c / 6.0;
  }
  r->origin_px_ = 0.5 * (eye_px[0] + eye_px[1]);
  for (int e = 0; e < 2; ++e) {
    const auto ue = static_cast<size_t>(e);
    const cv::Point2d xy = r->head_xy(eye_px[ue]);
    r->eyeball_head_[ue] = cv::Vec3d(xy.x, xy.y, options.eyeball_radius_m);
    std::vector<cv::Point2d> poly;
    for (int k = 0; k < 6; ++k) {
      const cv::Point2d d = L[static_cast<size_t>(36 + 6 * e + k)] - eye_px[ue];
      poly.push_back(eye_px[ue] + cv::Point2d(d.x * options.eye_opening_scale[0],
                                              d.y * options.eye_opening_scale[1]));
    }
    r->eye_opening_px_[ue] = poly;
    // Upper-lid skin colour (for blinks): the band 2..5 px above the upper lid landmarks.
    const cv::Point2d& u1 = L[static_cast<size_t>(37 + 6 * e)];
    const cv::Point2d& u2 = L[static_cast<size_t>(38 + 6 * e)];
    const int y1 = static_cast<int>(std::lround(std::min(u1.y, u2.y) - 2));
    const cv::Rect band(static_cast<int>(std::lround(u1.x)), y1 - 3,
                        std::max(1, static_cast<int>(std::lround(u2.x - u1.x))), 3);
    const cv::Scalar m = cv::mean(img(band & image_rect));
    r->lid_skin_bgr_[ue] = cv::Vec3d(m[0], m[1], m[2]);
  }

  // Surface anchors (head frame).
  const HeadShape& hs = options.shape;
  for (int i = 0; i <= 16; ++i) r->contour_xy_.push_back(r->head_xy(L[static_cast<size_t>(i)]));
  std::sort(r->contour_xy_.begin(), r->contour_xy_.end(),
            [](const cv::Point2d& a, const cv::Point2d& b) { return a.x < b.x; });
  for (int e = 0; e < 2; ++e)
    for (int k = 0; k < 5; ++k)
      r->brow_xy_[static_cast<size_t>(e)].push_back(
          r->head_xy(L[static_cast<size_t>(17 + 5 * e + k)]) + cv::Point2d(0, 0.003));
  r->nasion_xy_ = r->head_xy(L[27]);
  r->nose_tip_xy_ = r->head_xy(L[30]);
  r->subnasale_xy_ = r->head_xy(L[33]);
  r->alar_half_width_m_ = 0.5 * cv::norm(r->head_xy(L[35]) - r->head_xy(L[31]));
  cv::Point2d mouth(0, 0);
  for (int i = 48; i < 68; ++i) mouth += L[static_cast<size_t>(i)];
  r->mouth_xy_ = r->head_xy(mouth / 20.0);
  r->chin_xy_ = r->head_xy(L[8]) - cv::Point2d(0, 0.012);
  r->hair_centre_xy_ = r->head_xy(options.mask_centre_px);
  r->hair_axes_m_ =
      cv::Size2d((options.mask_axes_px.width - hs.hair_inset_px) * r->metres_per_px_,
                 (options.mask_axes_px.height - hs.hair_inset_px) * r->metres_per_px_);
  // F passes through the rest pupils: z = 0 at (+-half the eye distance, 0).
  {
    const double ex = 0.5 * std::abs(r->head_xy(eye_px[1]).x - r->head_xy(eye_px[0]).x);
    const double u = ex / hs.face_a_m, v = (0 - hs.face_centre_y_m) / hs.face_b_m;
    r->face_centre_z_m_ = hs.face_c_m * std::sqrt(std::max(0.0, 1 - u * u - v * v));
  }

  r->texture_levels_ = detail::make_texture_levels(img, options.crop_px, options.mask_centre_px,
                                                   options.mask_axes_px, r->subject_mask(img));
  {  // Mean hair colour: warm pixels of the crown (above the brows, outside the face).
    const cv::Rect crown(options.crop_px.x, options.crop_px.y, options.crop_px.width,
                         static_cast<int>(std::lround(L[19].y)) - 14 - options.crop_px.y);
    cv::Mat hair = img(crown & image_rect);
    std::vector<cv::Mat> ch;
    cv::split(hair, ch);
    cv::Mat warm;
    cv::subtract(ch[2], ch[0], warm, cv::noArray(), CV_16S);
    const cv::Scalar m = cv::mean(hair, warm > 35);
    r->hair_bgr_ =
        cv::Vec3f(static_cast<float>(m[0]), static_cast<float>(m[1]), static_cast<float>(m[2]));
  }
  r->build_mesh();
  if (r->triangles_.size() < 100)
    return make_error(ErrorCode::kInternal, "MeshFaceRenderer: triangulation failed ({} triangles)",
                      r->triangles_.size());
  return r;
}

// The photo's background and the space suit must not be wrapped around the head: outside the face
// (jaw contour closed over the forehead) only warm pixels (red - blue >= ~30: skin, hair) are
// kept; the background and suit are neutral grey, white, purple or near black (red - blue < 22).
cv::Mat MeshFaceRenderer::subject_mask(const cv::Mat& img) const {
  const cv::Rect& c = options_.crop_px;
  std::vector<cv::Mat> ch;
  cv::split(img(c), ch);
  cv::Mat rb;
  cv::subtract(ch[2], ch[0], rb, cv::noArray(), CV_32F);
  cv::Mat mask(rb.size(), CV_8U);
  for (int y = 0; y < rb.rows; ++y)
    for (int x = 0; x < rb.cols; ++x)
      mask.at<uchar>(y, x) =
          static_cast<uchar>(std::lround(255 * smoothstep(22, 38, rb.at<float>(y, x))));
  std::vector<cv::Point> face;
  for (int i = 0; i <= 16; ++i)
    face.emplace_back(cv::Point2d(landmarks_px_[static_cast<size_t>(i)]) - cv::Point2d(c.tl()));
  for (int i = 26; i >= 17; --i)
    face.emplace_back(cv::Point2d(landmarks_px_[static_cast<size_t>(i)]) - cv::Point2d(c.tl()) -
                      cv::Point2d(0, 12));
  cv::fillPoly(mask, std::vector<std::vector<cv::Point>>{face}, cv::Scalar(255), cv::LINE_AA);
  // Nothing below the jaw line is kept: the photo's neck would sit on the head's surface and
  // stick out under the chin when the head turns (the scene draws a neck).
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < mask.cols; ++x) {
      const cv::Point2d h = head_xy(cv::Point2d(x + c.x, y + c.y));
      if (below_jaw(h.x, h.y)) mask.at<uchar>(y, x) = 0;
    }
  // Drop specks, fill enclosed holes (light strands and highlights in the hair: background not
  // reachable from the crop border), soften the edge.
  cv::morphologyEx(mask, mask, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(9, 9)));
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN,
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  cv::Mat outside = mask < 128;  // 255 = background candidate
  cv::Mat reached = cv::Mat::zeros(outside.rows + 2, outside.cols + 2, CV_8U);
  for (int x = 0; x < outside.cols; ++x)
    for (int y : {0, outside.rows - 1})
      if (outside.at<uchar>(y, x) == 255 && reached.at<uchar>(y + 1, x + 1) == 0)
        cv::floodFill(outside, reached, cv::Point(x, y), cv::Scalar(255), nullptr, cv::Scalar(),
                      cv::Scalar(), 4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
  for (int y = 0; y < outside.rows; ++y)
    for (int x : {0, outside.cols - 1})
      if (outside.at<uchar>(y, x) == 255 && reached.at<uchar>(y + 1, x + 1) == 0)
        cv::floodFill(outside, reached, cv::Point(x, y), cv::Scalar(255), nullptr, cv::Scalar(),
                      cv::Scalar(), 4 | cv::FLOODFILL_MASK_ONLY | (255 << 8));
  const cv::Mat holes = outside & (reached(cv::Rect(1, 1, outside.cols, outside.rows)) == 0);
  mask.setTo(255, holes);
  cv::GaussianBlur(mask, mask, cv::Size(0, 0), 1.0);
  return mask;
}

bool MeshFaceRenderer::below_jaw(double x, double y) const {
  // Under the contour 0-16 (x increasing); beside it is not "below".
  const auto& c = contour_xy_;
  if (x <= c.front().x || x >= c.back().x) return false;
  for (size_t i = 0; i + 1 < c.size(); ++i)
    if (x <= c[i + 1].x) {
      const double t = (x - c[i].x) / std::max(1e-12, c[i + 1].x - c[i].x);
      return y > c[i].y + t * (c[i + 1].y - c[i].y);
    }
  return false;
}

double MeshFaceRenderer::surface_z(double x, double y) const {
  const HeadShape& hs = options_.shape;
  // Hair / cranium ellipsoid H (its silhouette depth outside its outline).
  double zh = hs.hair_centre_z_m;
  {
    const double u = (x - hair_centre_xy_.x) / hair_axes_m_.width;
    const double v = (y - hair_centre_xy_.y) / hair_axes_m_.height;
    const double q = 1 - u * u - v * v;
    if (q > 0) zh = hs.hair_centre_z_m - hs.hair_c_m * std::sqrt(q);
  }
  // Below the jaw line (transparent in the texture; the mesh vertices there take the jaw line's
  // depth, see build_mesh): hair ellipsoid.
  if (below_jaw(x, y)) return zh;
  // Face ellipsoid F + relief.
  const double u = x / hs.face_a_m, v = (y - hs.face_centre_y_m) / hs.face_b_m;
  const double q = 1 - u * u - v * v;
  if (q <= 0) return zh;
  double z = face_centre_z_m_ - hs.face_c_m * std::sqrt(q);
  // Nose: a ridge along the midline, growing from the nasion to the tip, falling to the
  // subnasale; Gaussian cross-section widening towards the alae.
  {
    const double y0 = nasion_xy_.y, y1 = nose_tip_xy_.y, y2 = subnasale_xy_.y + 0.006;
    if (y > y0 - 0.012 && y < y2) {
      double h = 0, sigma = 0, mx = 0;
      if (y < y0) {
        h = hs.nasion_m * smoothstep(y0 - 0.012, y0, y);
        sigma = 0.0055;
        mx = nasion_xy_.x;
      } else if (y < y1) {
        const double t = (y - y0) / (y1 - y0);
        h = hs.nasion_m + (hs.nose_tip_m - hs.nasion_m) * std::pow(t, 1.5);
        sigma = 0.0055 + t * 0.003;
        mx = nasion_xy_.x + t * (nose_tip_xy_.x - nasion_xy_.x);
      } else {
        const double t = (y - y1) / (y2 - y1);
        h = hs.nose_tip_m * (1 - smoothstep(0, 1, t));
        sigma = 0.0085 + t * std::max(0.0, 0.8 * alar_half_width_m_ - 0.0085);
        mx = nose_tip_xy_.x + t * (subnasale_xy_.x - nose_tip_xy_.x);
      }
      z -= h * std::exp(-0.5 * ((x - mx) / sigma) * ((x - mx) / sigma));
    }
  }
  // Brow ridges (just below the brow landmarks) and the glabella between them.
  for (const auto& brow : brow_xy_) {
    const double d = polyline_distance({x, y}, brow.data(), static_cast<int>(brow.size()));
    z -= hs.brow_m * std::exp(-0.5 * (d / 0.0065) * (d / 0.0065));
  }
  z -= hs.brow_m * gauss2(x - nasion_xy_.x, 0.01, y - (nasion_xy_.y - 0.012), 0.008);
  // Eye sockets (pushed back) around the eyeball centres.
  for (const auto& e : eyeball_head_)
    z += hs.eye_socket_m * gauss2(x - e[0], 0.012, y - e[1], 0.0075);
  // Cheekbones, lips, chin.
  for (double side : {-1.0, 1.0})
    z -= hs.cheekbone_m * gauss2(x - side * 0.042, 0.013, y - 0.028, 0.012);
  z -= hs.lips_m * gauss2(x - mouth_xy_.x, 0.019, y - mouth_xy_.y, 0.007);
  z -= hs.chin_m * gauss2(x - chin_xy_.x, 0.016, y - chin_xy_.y, 0.011);
  return std::min(z, zh);
}

cv::Vec3d MeshFaceRenderer::surface_point(const cv::Point2d& px) const {
  const cv::Point2d xy = head_xy(px);
  return {xy.x, xy.y, surface_z(xy.x, xy.y)};
}

void MeshFaceRenderer::build_mesh() {
  const MeshFaceOptions& o = options_;
  const cv::Rect& crop = o.crop_px;
  std::vector<cv::Point2d> pts(landmarks_px_.begin(), landmarks_px_.end());
  auto far_from_all = [&](const cv::Point2d& p, double d) {
    for (const auto& q : pts)
      if (cv::norm(p - q) < d) return false;
    return true;
  };
  const cv::Point2d nose_tip = landmarks_px_[30];
  // Jaw: a row 3 px outside the contour (keeps the jaw line's triangles small).
  for (int i = 0; i <= 16; ++i) {
    if (i == 0 || i == 16) {
      pts.push_back(landmarks_px_[static_cast<size_t>(i)] + cv::Point2d(i == 0 ? -3.0 : 3.0, 0));
      continue;
    }
    const cv::Point2d t =
        landmarks_px_[static_cast<size_t>(i + 1)] - landmarks_px_[static_cast<size_t>(i - 1)];
    cv::Point2d n(t.y, -t.x);
    n *= 1.0 / std::max(1e-9, cv::norm(n));
    if (n.dot(landmarks_px_[static_cast<size_t>(i)] - nose_tip) < 0) n = -n;
    pts.push_back(landmarks_px_[static_cast<size_t>(i)] + 3.0 * n);
  }
  const cv::Point2d mc = o.mask_centre_px;
  const double ax = o.mask_axes_px.width, ay = o.mask_axes_px.height;
  const double inset = o.shape.hair_inset_px;
  auto clamp_crop = [&](cv::Point2d p) {
    p.x = std::clamp(p.x, crop.x + 0.0, crop.x + crop.width - 1.0);
    p.y = std::clamp(p.y, crop.y + 0.0, crop.y + crop.height - 1.0);
    return p;
  };
  // Hair outline (H's silhouette) and an outer ring beyond the feathered mask edge.
  for (int k = 0; k < 40; ++k) {
    const double a = 2 * CV_PI * k / 40;
    const cv::Point2d p =
        clamp_crop(mc + cv::Point2d((ax - inset) * std::cos(a), (ay - inset) * std::sin(a)));
    if (far_from_all(p, 4.0)) pts.push_back(p);
  }
  for (int k = 0; k < 40; ++k) {
    const double a = 2 * CV_PI * (k + 0.5) / 40;
    const cv::Point2d p =
        clamp_crop(mc + cv::Point2d((ax + 9) * std::cos(a), (ay + 9) * std::sin(a)));
    if (far_from_all(p, 4.0)) pts.push_back(p);
  }
  // Interior grid (staggered rows), away from the landmarks and out of the eye openings.
  const double g = o.grid_spacing_px;
  int row = 0;
  for (double y = crop.y + 0.5 * g; y < crop.y + crop.height; y += g * 0.866, ++row) {
    for (double x = crop.x + (row % 2 ? 0.5 * g : 0.0); x < crop.x + crop.width; x += g) {
      const cv::Point2d p(x, y);
      const double u = (x - mc.x) / (ax - inset - 3), v = (y - mc.y) / (ay - inset - 3);
      if (u * u + v * v >= 1) continue;
      bool in_eye = false;
      for (const auto& poly : eye_opening_px_) {
        const double d = cv::pointPolygonTest(std::vector<cv::Point2f>{poly.begin(), poly.end()},
                                              cv::Point2f(p), true);
        if (d > -2.0) in_eye = true;
      }
      if (in_eye || !far_from_all(p, 0.55 * g)) continue;
      pts.push_back(p);
    }
  }

  cv::Subdiv2D sub(cv::Rect(crop.x - 4, crop.y - 4, crop.width + 8, crop.height + 8));
  std::map<std::pair<int64_t, int64_t>, int> index;
  auto key = [](float x, float y) {
    return std::make_pair(static_cast<int64_t>(std::llround(x * 1000.0)),
                          static_cast<int64_t>(std::llround(y * 1000.0)));
  };
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2f p(static_cast<float>(pts[i].x), static_cast<float>(pts[i].y));
    index[key(p.x, p.y)] = static_cast<int>(i);
    sub.insert(p);
  }
  std::vector<cv::Vec6f> tris;
  sub.getTriangleList(tris);
  vertices_px_ = pts;
  for (const auto& t : tris) {
    int id[3];
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const auto it = index.find(key(t[2 * k], t[2 * k + 1]));
      if (it == index.end()) {
        ok = false;
        break;
      }
      id[k] = it->second;
    }
    if (!ok) continue;
    const cv::Point2d a = pts[static_cast<size_t>(id[0])], b = pts[static_cast<size_t>(id[1])],
                      c = pts[static_cast<size_t>(id[2])];
    const double area = 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
    if (std::abs(area) < 1e-3) continue;
    if (area < 0) std::swap(id[1], id[2]);
    triangles_.emplace_back(id[0], id[1], id[2]);
    const cv::Point2d p0 = pts[static_cast<size_t>(id[0])], p1 = pts[static_cast<size_t>(id[1])],
                      p2 = pts[static_cast<size_t>(id[2])];
    texture_edges_inv_.push_back(
        cv::Matx22d(p1.x - p0.x, p2.x - p0.x, p1.y - p0.y, p2.y - p0.y).inv());
  }
  // Vertices on the surface; area-weighted vertex normals (front side: towards head -z).
  vertices_head_.clear();
  for (const auto& p : pts) vertices_head_.push_back(surface_point(p));
  // Under the jaw the photo is transparent (see subject_mask), and a vertex there at the hair
  // depth would pull the triangles it shares with the chin far back (and flip them, leaving holes
  // above the jaw line): vertices under the jaw take the jaw line's depth at their x instead.
  std::vector<cv::Vec3d> jaw(vertices_head_.begin(), vertices_head_.begin() + 17);
  std::sort(jaw.begin(), jaw.end(),
            [](const cv::Vec3d& a, const cv::Vec3d& b) { return a[0] < b[0]; });
  for (size_t i = kLandmarks; i < vertices_head_.size(); ++i) {
    cv::Vec3d& v = vertices_head_[i];
    if (!below_jaw(v[0], v[1])) continue;
    for (size_t k = 0; k + 1 < jaw.size(); ++k)
      if (v[0] <= jaw[k + 1][0]) {
        const double t =
            std::clamp((v[0] - jaw[k][0]) / std::max(1e-12, jaw[k + 1][0] - jaw[k][0]), 0.0, 1.0);
        v[2] = jaw[k][2] + t * (jaw[k + 1][2] - jaw[k][2]);
        break;
      }
  }
  normals_head_.assign(pts.size(), cv::Vec3d(0, 0, 0));
  for (const auto& t : triangles_) {
    const cv::Vec3d& a = vertices_head_[static_cast<size_t>(t[0])];
    const cv::Vec3d n = -(vertices_head_[static_cast<size_t>(t[1])] - a)
                             .cross(vertices_head_[static_cast<size_t>(t[2])] - a);
    for (int k = 0; k < 3; ++k) normals_head_[static_cast<size_t>(t[k])] += n;
  }
  for (auto& n : normals_head_) n = normalized(n);
  // Triangles of each eye opening (and the lid triangles along it): >= 2 eye landmarks.
  for (int e = 0; e < 2; ++e) {
    auto& flags = eye_triangle_[static_cast<size_t>(e)];
    flags.assign(triangles_.size(), 0);
    for (size_t i = 0; i < triangles_.size(); ++i) {
      int n = 0;
      for (int k = 0; k < 3; ++k)
        if (triangles_[i][k] >= 36 + 6 * e && triangles_[i][k] < 42 + 6 * e) ++n;
      flags[i] = n >= 2;
    }
  }
}

cv::Vec3d MeshFaceRenderer::right_eye_head() const {
  return eyeball_head_[0] - cv::Vec3d(0, 0, options_.eyeball_radius_m);
}
cv::Vec3d MeshFaceRenderer::left_eye_head() const {
  return eyeball_head_[1] - cv::Vec3d(0, 0, options_.eyeball_radius_m);
}

std::vector<cv::Vec3d> MeshFaceRenderer::face_region_head() const {
  // Jaw contour and brows, plus three forehead points (portrait y = 80): cheek to cheek,
  // forehead to chin.
  std::vector<cv::Vec3d> out(vertices_head_.begin(), vertices_head_.begin() + 27);
  for (double x : {186.0, 225.0, 265.0}) out.push_back(surface_point({x, 80.0}));
  return out;
}

FaceRenderer::BackOfHead MeshFaceRenderer::back_of_head() const {
  BackOfHead b;
  b.centre_head = {hair_centre_xy_.x, hair_centre_xy_.y, options_.shape.hair_centre_z_m};
  b.radii_m = {0.97 * hair_axes_m_.width, 0.97 * hair_axes_m_.height, options_.shape.hair_c_m};
  b.bgr = hair_bgr_;
  return b;
}

EyesState MeshFaceRenderer::eyes(const FaceState& state) const {
  EyesState out;
  const cv::Matx33d& R = state.world_from_head;
  for (int e = 0; e < 2; ++e) {
    EyeState s;
    s.centre_m = state.to_world(eyeball_head_[static_cast<size_t>(e)]);
    cv::Vec3d d = state.gaze_target_m ? normalized(*state.gaze_target_m - s.centre_m)
                                      : normalized(state.eye_gaze_dir);
    // Clamp the eye-in-head rotation to the anatomical range.
    const cv::Vec3d dh = R.t() * d;
    const double yaw = std::atan2(-dh[0], -dh[2]) / kDeg;
    const double pitch = std::asin(std::clamp(dh[1], -1.0, 1.0)) / kDeg;
    const double cy = std::clamp(yaw, -options_.max_eye_yaw_deg, options_.max_eye_yaw_deg);
    const double cp = std::clamp(pitch, -options_.max_eye_pitch_deg, options_.max_eye_pitch_deg);
    if (cy != yaw || cp != pitch) d = R * direction_from_angles(cy, cp);
    s.gaze_dir = d;
    s.pupil_m = s.centre_m + options_.eyeball_radius_m * d;
    (e == 0 ? out.right : out.left) = s;
  }
  out.open = state.eyelid_closure < 0.5;
  return out;
}

void MeshFaceRenderer::render(const CameraModel& camera, const FaceState& state,
                              const Lighting& lighting, RenderTarget& target) const {
  DS_CHECK(target.bgr.size() == camera.image_size);
  const size_t n = vertices_head_.size();
  const cv::Matx33d A = camera.R * state.world_from_head;
  const cv::Vec3d b = camera.to_camera(state.position_m);
  const double fx = camera.K(0, 0), fy = camera.K(1, 1), cx = camera.K(0, 2), cy = camera.K(1, 2);
  const cv::Vec3d l = normalized(lighting.direction);
  struct V {
    double u, v, invz, shade;
  };
  std::vector<V> vs(n);
  double u0 = kInf, v0 = kInf, u1 = -kInf, v1 = -kInf;
  for (size_t i = 0; i < n; ++i) {
    const cv::Vec3d p = A * vertices_head_[i] + b;
    if (p[2] < 0.05) return;  // the head is at (or behind) the camera
    V& q = vs[i];
    q.invz = 1.0 / p[2];
    q.u = fx * p[0] * q.invz + cx;
    q.v = fy * p[1] * q.invz + cy;
    const cv::Vec3d nw = state.world_from_head * normals_head_[i];
    q.shade = lighting.ambient + lighting.diffuse * std::max(0.0, -nw.dot(l));
    u0 = std::min(u0, q.u), v0 = std::min(v0, q.v), u1 = std::max(u1, q.u), v1 = std::max(v1, q.v);
  }
  const cv::Rect image(0, 0, target.bgr.cols, target.bgr.rows);
  const cv::Rect roi =
      cv::Rect(
          cv::Point(static_cast<int>(std::floor(u0)) - 1, static_cast<int>(std::floor(v0)) - 1),
          cv::Point(static_cast<int>(std::ceil(u1)) + 2, static_cast<int>(std::ceil(v1)) + 2)) &
      image;
  if (roi.empty()) return;
  cv::Mat owner(roi.size(), CV_32S, cv::Scalar(-1));  // triangle that last wrote a pixel
  const double tx0 = options_.crop_px.x, ty0 = options_.crop_px.y;

  for (size_t t = 0; t < triangles_.size(); ++t) {
    const cv::Vec3i& tri = triangles_[t];
    const V& a = vs[static_cast<size_t>(tri[0])];
    const V& bb = vs[static_cast<size_t>(tri[1])];
    const V& c = vs[static_cast<size_t>(tri[2])];
    const double area = (bb.u - a.u) * (c.v - a.v) - (bb.v - a.v) * (c.u - a.u);
    if (area <= 1e-9) continue;  // back-facing or edge-on (portrait winding is positive)
    // Texture level from the triangle's largest magnification (singular value of the texture ->
    // image Jacobian): blur only where both directions are minified, so that steep triangles
    // near silhouettes do not get a blurrier level (and a different alpha edge) than their
    // neighbours.
    const cv::Matx22d I(bb.u - a.u, c.u - a.u, bb.v - a.v, c.v - a.v);
    const cv::Matx22d J = I * texture_edges_inv_[t];
    const cv::Matx22d JtJ = J.t() * J;
    const double tr = JtJ(0, 0) + JtJ(1, 1), det = JtJ(0, 0) * JtJ(1, 1) - JtJ(0, 1) * JtJ(1, 0);
    const double scale = std::sqrt(0.5 * (tr + std::sqrt(std::max(0.0, tr * tr - 4 * det))));
    const cv::Mat& tex = texture_levels_[static_cast<size_t>(detail::texture_level(scale))];
    const int xa = std::max(roi.x, static_cast<int>(std::ceil(std::min({a.u, bb.u, c.u}))));
    const int xb =
        std::min(roi.x + roi.width - 1, static_cast<int>(std::floor(std::max({a.u, bb.u, c.u}))));
    const int ya = std::max(roi.y, static_cast<int>(std::ceil(std::min({a.v, bb.v, c.v}))));
    const int yb =
        std::min(roi.y + roi.height - 1, static_cast<int>(std::floor(std::max({a.v, bb.v, c.v}))));
    if (xa > xb || ya > yb) continue;
    const cv::Point2d ta = vertices_px_[static_cast<size_t>(tri[0])];
    const cv::Point2d tb = vertices_px_[static_cast<size_t>(tri[1])];
    const cv::Point2d tc = vertices_px_[static_cast<size_t>(tri[2])];
    // Edge functions: weight of a = E(b, c), of b = E(c, a), of c = E(a, b); linear in (x, y).
    auto edge = [](const V& p, const V& q, double x, double y) {
      return (q.u - p.u) * (y - p.v) - (q.v - p.v) * (x - p.u);
    };
    const double dwa = -(c.v - bb.v), dwb = -(a.v - c.v), dwc = -(bb.v - a.v);  // d/dx
    for (int y = ya; y <= yb; ++y) {
      // The row's span where all three edge functions are >= 0 (one pixel of slack each side;
      // the per-pixel test below decides).
      double lo = xa, hi = xb;
      for (const auto& [w0, dw] :
           {std::pair{edge(bb, c, xa, y), dwa}, std::pair{edge(c, a, xa, y), dwb},
            std::pair{edge(a, bb, xa, y), dwc}}) {
        if (dw > 1e-12)
          lo = std::max(lo, xa - w0 / dw - 1);
        else if (dw < -1e-12)
          hi = std::min(hi, xa - w0 / dw + 1);
        else if (w0 < 0)
          hi = lo - 1;
      }
      if (lo > hi) continue;
      const int x0 = static_cast<int>(std::ceil(lo)), x1 = static_cast<int>(std::floor(hi));
      double wa = edge(bb, c, x0, y), wb = edge(c, a, x0, y), wc = edge(a, bb, x0, y);
      cv::Vec3b* out = target.bgr.ptr<cv::Vec3b>(y);
      float* zb = target.depth.ptr<float>(y);
      int* own = owner.ptr<int>(y - roi.y) - roi.x;
      for (int x = x0; x <= x1; ++x, wa += dwa, wb += dwb, wc += dwc) {
        if (wa < 0 || wb < 0 || wc < 0) continue;
        const double qa = wa * a.invz, qb = wb * bb.invz, qc = wc * c.invz;
        const double qs = qa + qb + qc;
        // z = 1 / sum(b_i / z_i) with b_i = w_i / area; z-test without dividing first.
        if (qs <= 0 || area >= qs * zb[x]) continue;
        const double inv = 1.0 / qs;
        const double z = area * inv;
        const double ka = qa * inv, kb = qb * inv, kc = qc * inv;  // perspective-correct weights
        double s[4];
        sample_bgra(tex, ka * ta.x + kb * tb.x + kc * tc.x - tx0,
                    ka * ta.y + kb * tb.y + kc * tc.y - ty0, s);
        if (s[3] < 0.5) continue;
        const double alpha = s[3] / 255.0;
        const double shade = ka * a.shade + kb * bb.shade + kc * c.shade;
        for (int k = 0; k < 3; ++k)
          out[x][k] = cv::saturate_cast<uchar>(alpha * s[k] * shade + (1 - alpha) * out[x][k]);
        if (s[3] >= 128) {
          zb[x] = static_cast<float>(z);
          own[x] = static_cast<int>(t);
        }
      }
    }
  }

  const EyesState es = eyes(state);
  render_eye(0, camera, state, es.right, lighting, roi, owner, target);
  render_eye(1, camera, state, es.left, lighting, roi, owner, target);
}

void MeshFaceRenderer::render_eye(int e, const CameraModel& camera, const FaceState& state,
                                  const EyeState& es, const Lighting& lighting, const cv::Rect& roi,
                                  const cv::Mat& owner, RenderTarget& target) const {
  const auto ue = static_cast<size_t>(e);
  const std::vector<uchar>& mine = eye_triangle_[ue];
  // Upper lid: blink closure, and it follows the eye down when looking down.
  const cv::Vec3d dh = state.world_from_head.t() * es.gaze_dir;
  const double look_down =
      std::clamp(std::asin(std::clamp(dh[1], -1.0, 1.0)) / (20 * kDeg), 0.0, 1.0);
  const double closure = std::clamp(std::max(state.eyelid_closure, 0.3 * look_down), 0.0, 1.0);
  const auto& full_px = eye_opening_px_[ue];  // order: corner, upper, upper, corner, lower, lower
  std::vector<cv::Point2d> open_px = full_px;
  open_px[1] = full_px[1] + closure * (full_px[5] - full_px[1]);
  open_px[2] = full_px[2] + closure * (full_px[4] - full_px[2]);
  cv::Point2d full[6], open[6];
  for (int k = 0; k < 6; ++k) {
    auto p = camera.project(state.to_world(surface_point(full_px[static_cast<size_t>(k)])));
    auto q = camera.project(state.to_world(surface_point(open_px[static_cast<size_t>(k)])));
    if (!p || !q) return;
    full[k] = *p;
    open[k] = *q;
  }
  double bx0 = kInf, by0 = kInf, bx1 = -kInf, by1 = -kInf;
  for (const auto& p : full) {
    bx0 = std::min(bx0, p.x), by0 = std::min(by0, p.y);
    bx1 = std::max(bx1, p.x), by1 = std::max(by1, p.y);
  }
  const cv::Rect box =
      cv::Rect(
          cv::Point(static_cast<int>(std::floor(bx0)) - 1, static_cast<int>(std::floor(by0)) - 1),
          cv::Point(static_cast<int>(std::ceil(bx1)) + 2, static_cast<int>(std::ceil(by1)) + 2)) &
      roi;
  if (box.empty()) return;
  const cv::Point2d upper[4] = {open[0], open[1], open[2], open[3]};
  const cv::Point2d lower[4] = {open[3], open[4], open[5], open[0]};

  const double fx = camera.K(0, 0), fy = camera.K(1, 1), cx = camera.K(0, 2), cy = camera.K(1, 2);
  const cv::Vec3d C = camera.to_camera(es.centre_m);
  const double r = options_.eyeball_radius_m;
  const cv::Vec3d g = camera.R * es.gaze_dir;
  const cv::Vec3d hx = camera.R * (state.world_from_head * cv::Vec3d(1, 0, 0));
  const cv::Vec3d ax_u = normalized(hx - hx.dot(g) * g), ax_v = g.cross(ax_u);
  const cv::Vec3d l_world = normalized(lighting.direction);
  const cv::Vec3d l = camera.R * l_world;
  const cv::Vec3d face_n = state.world_from_head * cv::Vec3d(0, 0, -1);
  const double shade = lighting.ambient + lighting.diffuse * std::max(0.0, -face_n.dot(l_world));
  const double px_per_mm = fx / std::max(C[2], 1e-3) * 1e-3;
  const double th_iris = std::asin(options_.iris_radius_m / r);
  const double th_pupil = std::asin(options_.pupil_radius_m / r);
  const cv::Vec3d sclera = options_.sclera_bgr, iris = options_.iris_bgr;
  const cv::Vec3d pupil(10, 10, 12);
  const cv::Vec3d skin = lid_skin_bgr_[ue];

  // Colour seen along the camera ray through pixel p (inside the opening); z = camera depth of
  // the hit (0 if the ray misses the sphere).
  auto eyeball = [&](const cv::Point2d& p, double& z) -> cv::Vec3d {
    const cv::Vec3d d = normalized({(p.x - cx) / fx, (p.y - cy) / fy, 1.0});
    const double bd = d.dot(C);
    const double disc = bd * bd - (C.dot(C) - r * r);
    const double du = polyline_distance(p, upper, 4) / px_per_mm;  // mm to the upper lid
    const double dl = polyline_distance(p, lower, 4) / px_per_mm;
    const double lid = (1 - 0.5 * std::exp(-du / 0.8)) * (1 - 0.2 * std::exp(-dl / 0.5));
    if (disc < 0) {  // beside the eyeball, in the eye corners: caruncle / shadow
      z = 0;
      return options_.caruncle_bgr * (shade * lid);
    }
    const double s = bd - std::sqrt(disc);
    const cv::Vec3d P = s * d;
    z = P[2];
    const cv::Vec3d q = (P - C) / r;
    const double th = std::acos(std::clamp(q.dot(g), -1.0, 1.0));
    const double rho = th / th_iris;
    const double phi = std::atan2(q.dot(ax_v), q.dot(ax_u));
    // Iris: radial streaks, a lighter collarette, a darker limbal ring.
    const double streak = 0.5 + 0.22 * std::sin(11 * phi + 0.7) + 0.16 * std::sin(23 * phi + 2.1) +
                          0.12 * std::sin(37 * phi + 4.0 + 3 * rho);
    double m = (0.72 + 0.5 * streak * (0.55 + 0.45 * rho)) +
               0.22 * std::exp(-((rho - 0.45) / 0.08) * ((rho - 0.45) / 0.08));
    m *= 1 - 0.5 * smoothstep(0.8, 1.0, rho);
    cv::Vec3d col = iris * m;
    const double tp = 1 - smoothstep(th_pupil - 0.02, th_pupil + 0.02, th);
    col = (1 - tp) * col + tp * pupil;
    const double ti = 1 - smoothstep(th_iris - 0.045, th_iris + 0.025, th);
    // The sclera darkens where the eyeball turns away from the viewer.
    const cv::Vec3d white = sclera * (0.6 + 0.4 * std::max(0.0, -q.dot(d)));
    col = (1 - ti) * white + ti * col;
    col *= shade * lid;
    // Specular highlight of the light on the (spherical) cornea.
    const cv::Vec3d h = normalized(-l - d);
    const double spec = std::pow(std::max(0.0, q.dot(h)), 350.0) * 235.0 * lid;
    return col + cv::Vec3d(spec, spec, spec);
  };

  static const double kSub[4][2] = {{-0.25, -0.25}, {0.25, -0.25}, {-0.25, 0.25}, {0.25, 0.25}};
  for (int v = box.y; v < box.y + box.height; ++v) {
    cv::Vec3b* out = target.bgr.ptr<cv::Vec3b>(v);
    float* zb = target.depth.ptr<float>(v);
    const int* own = owner.ptr<int>(v - roi.y) - roi.x;
    for (int u = box.x; u < box.x + box.width; ++u) {
      if (own[u] < 0 || !mine[static_cast<size_t>(own[u])]) continue;
      cv::Vec3d acc(0, 0, 0);
      int inside = 0;
      for (const auto& sp : kSub) {
        const cv::Point2d p(u + sp[0], v + sp[1]);
        if (!inside_polygon(full, 6, p)) {
          acc += cv::Vec3d(out[u][0], out[u][1], out[u][2]);
          continue;
        }
        ++inside;
        if (inside_polygon(open, 6, p)) {
          double z = 0;
          acc += eyeball(p, z);
        } else {  // closed part of the lid, with the lash line along its edge
          const double d = polyline_distance(p, upper, 4) / px_per_mm;
          acc += skin * (0.88 * shade * (1 - 0.65 * std::exp(-(d / 0.5) * (d / 0.5))));
        }
      }
      if (inside == 0) continue;
      for (int k = 0; k < 3; ++k) out[u][k] = cv::saturate_cast<uchar>(acc[k] / 4);
      const cv::Point2d pc(u, v);
      if (inside_polygon(open, 6, pc)) {
        double z = 0;
        eyeball(pc, z);
        if (z > 0) zb[u] = static_cast<float>(z);
      }
    }
  }
}

}  // namespace dreamsense::sim
