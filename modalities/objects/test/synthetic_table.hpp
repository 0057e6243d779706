#pragma once
// A synthetic top-camera view of a table with toys, for tests and benchmarks: the demo's
// geometry (camera 1 m above the table plane y = 0.30, looking straight down, f = 525 px), a
// brown table on a grey floor, and boxes of 10 x 7.5 x 3 cm whose top faces carry one of a few
// synthetic pictures (the side faces are darker). Optionally a skin-coloured arm reaching in
// from the child's side of the table.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/geometry/plane.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <array>
#include <cmath>
#include <vector>

namespace dreamsense::objects::testing {

inline CameraModel table_camera() {
  CameraModel c;
  c.frame = "top.color";
  c.image_size = {640, 480};
  c.K = cv::Matx33d(525, 0, 319.5, 0, 525, 239.5, 0, 0, 1);
  look_at(cv::Vec3d(0, -0.70, 0.595), cv::Vec3d(0, 0.30, 0.595), cv::Vec3d(0, 0, 1), c.R, c.t);
  return c;
}

inline geometry::Plane table_plane() {
  geometry::Plane p;
  p.normal = cv::Vec3d(0, -1, 0);  // up = world -y
  p.offset = 0.30;                 // -y + 0.30 = 0 on the table
  return p;
}

// Picture k (0..4) of a toy's top face, 200 x 150 px.
inline cv::Mat toy_picture(int k) {
  cv::Mat p(150, 200, CV_8UC3);
  switch (k) {
    case 0:  // blue/yellow vertical stripes
      for (int x = 0; x < 200; ++x)
        p.col(x).setTo((x / 25) % 2 ? cv::Scalar(200, 60, 20) : cv::Scalar(20, 220, 230));
      break;
    case 1:  // green with a red disc
      p.setTo(cv::Scalar(40, 170, 40));
      cv::circle(p, {100, 75}, 50, cv::Scalar(30, 30, 210), cv::FILLED);
      break;
    case 2:  // white with a black cross and purple corners
      p.setTo(cv::Scalar(235, 235, 235));
      cv::line(p, {0, 0}, {199, 149}, cv::Scalar(10, 10, 10), 16);
      cv::line(p, {199, 0}, {0, 149}, cv::Scalar(10, 10, 10), 16);
      cv::rectangle(p, {0, 0, 40, 40}, cv::Scalar(160, 40, 150), cv::FILLED);
      cv::rectangle(p, {160, 110, 40, 40}, cv::Scalar(160, 40, 150), cv::FILLED);
      break;
    case 3:  // grey-blue checkerboard
      for (int y = 0; y < 150; ++y)
        for (int x = 0; x < 200; ++x)
          p.at<cv::Vec3b>(y, x) =
              ((x / 25 + y / 25) % 2) ? cv::Vec3b(150, 140, 130) : cv::Vec3b(70, 60, 50);
      break;
    default:  // magenta horizontal bands (a toy nobody enrolled)
      for (int y = 0; y < 150; ++y)
        p.row(y).setTo((y / 30) % 2 ? cv::Scalar(200, 40, 200) : cv::Scalar(240, 200, 240));
  }
  return p;
}

struct Toy {
  int picture = 0;
  cv::Vec3d centre_m;  // top face centre (world)
  double yaw_deg = 0;
  cv::Vec3d size_m{0.10, 0.075, 0.03};
};

// The 8 corners of a toy (0-3 top face, 4-7 bottom).
inline std::array<cv::Vec3d, 8> toy_corners(const Toy& t) {
  const double a = t.yaw_deg * CV_PI / 180.0;
  const cv::Vec3d u(std::cos(a), 0, std::sin(a)), v(-std::sin(a), 0, std::cos(a));
  const double l = 0.5 * t.size_m[0], w = 0.5 * t.size_m[1], h = t.size_m[2];
  std::array<cv::Vec3d, 8> c;
  const cv::Vec3d top[4] = {t.centre_m - l * u - w * v, t.centre_m + l * u - w * v,
                            t.centre_m + l * u + w * v, t.centre_m - l * u + w * v};
  for (int i = 0; i < 4; ++i) {
    c[static_cast<size_t>(i)] = top[i];
    c[static_cast<size_t>(i + 4)] = top[i] + cv::Vec3d(0, h, 0);  // y down: the bottom is lower
  }
  return c;
}

// The box bounding the projected corners (what the demo truth calls top_box).
inline cv::Rect2d toy_box(const CameraModel& cam, const Toy& t) {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const auto& p : toy_corners(t)) {
    const auto px = cam.project(p);
    x0 = std::min(x0, px->x), y0 = std::min(y0, px->y);
    x1 = std::max(x1, px->x), y1 = std::max(y1, px->y);
  }
  return {x0, y0, x1 - x0, y1 - y0};
}

struct Arm {
  cv::Point2d hand_px;  // where the hand is; the arm comes from the image bottom
  double radius_px = 22;
};

inline cv::Mat render_table(const std::vector<Toy>& toys, const std::vector<Arm>& arms = {},
                            uint64_t noise_seed = 1) {
  const CameraModel cam = table_camera();
  cv::Mat img(480, 640, CV_8UC3, cv::Scalar(110, 112, 115));
  // Table top x in [-0.55, 0.55], z in [0.30, 0.95] at y = 0.30.
  std::vector<cv::Point> table;
  for (const auto& c : {cv::Vec3d(-0.55, 0.3, 0.3), cv::Vec3d(0.55, 0.3, 0.3),
                        cv::Vec3d(0.55, 0.3, 0.95), cv::Vec3d(-0.55, 0.3, 0.95)}) {
    const auto p = cam.project(c);
    table.emplace_back(static_cast<int>(std::lround(p->x)), static_cast<int>(std::lround(p->y)));
  }
  cv::fillConvexPoly(img, table, cv::Scalar(80, 125, 170));
  for (const auto& t : toys) {
    const auto c = toy_corners(t);
    std::vector<cv::Point> all;
    std::vector<cv::Point2f> top;
    for (size_t i = 0; i < 8; ++i) {
      const auto p = cam.project(c[i]);
      all.emplace_back(static_cast<int>(std::lround(p->x)), static_cast<int>(std::lround(p->y)));
      if (i < 4) top.emplace_back(static_cast<float>(p->x), static_cast<float>(p->y));
    }
    const cv::Mat pic = toy_picture(t.picture);
    const cv::Scalar mean = cv::mean(pic);
    std::vector<cv::Point> hull;
    cv::convexHull(all, hull);
    cv::fillConvexPoly(img, hull, mean * 0.6);
    const std::vector<cv::Point2f> src = {{0, 0}, {199, 0}, {199, 149}, {0, 149}};
    const cv::Mat H = cv::getPerspectiveTransform(src, top);
    cv::Mat warped, mask;
    cv::warpPerspective(pic, warped, H, img.size());
    cv::warpPerspective(cv::Mat(pic.size(), CV_8U, cv::Scalar(255)), mask, H, img.size(),
                        cv::INTER_NEAREST);
    warped.copyTo(img, mask);
  }
  for (const auto& a : arms) {
    const cv::Point hand(static_cast<int>(a.hand_px.x), static_cast<int>(a.hand_px.y));
    cv::line(img, hand, cv::Point(hand.x + 40, 479), cv::Scalar(120, 150, 215),
             static_cast<int>(1.6 * a.radius_px));
    cv::circle(img, hand, static_cast<int>(a.radius_px), cv::Scalar(125, 160, 225), cv::FILLED);
  }
  cv::Mat noise(img.size(), CV_16SC3);
  cv::RNG rng(noise_seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, 3);
  cv::Mat out;
  img.convertTo(out, CV_16SC3);
  out += noise;
  out.convertTo(img, CV_8UC3);
  return img;
}

}  // namespace dreamsense::objects::testing
