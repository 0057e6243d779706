#pragma once
// A synthetic tracking sequence for tests and benchmarks: a textured patch moving smoothly over a
// textured background (both seeded noise, smoothed), optionally changing size, optionally
// covered by a grey occluder for a stretch of frames.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

namespace dreamsense::objects::testing {

struct SyntheticSequence {
  std::vector<cv::Mat> frames;
  std::vector<cv::Rect2d> boxes;
};

struct SyntheticOptions {
  cv::Size frame_size{640, 480};
  cv::Size target_size{60, 80};
  int frames = 60;
  double speed_px = 3;                     // per frame, along a Lissajous path
  double scale_per_frame = 1;              // multiplicative size change per frame
  int occlude_from = -1, occlude_to = -1;  // frames fully covering the target
  bool colour = true;
  uint64_t seed = 7;
};

inline cv::Mat smooth_noise(cv::Size size, int type, double sigma_px, uint64_t seed) {
  cv::Mat n(size, CV_32FC(CV_MAT_CN(type)));
  cv::RNG rng(seed);
  rng.fill(n, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(n, n, cv::Size(), sigma_px);
  cv::normalize(n.reshape(1), n.reshape(1), 0, 255, cv::NORM_MINMAX);
  cv::Mat out;
  n.convertTo(out, type);
  return out;
}

inline SyntheticSequence make_synthetic_sequence(const SyntheticOptions& o) {
  const int type = o.colour ? CV_8UC3 : CV_8UC1;
  const cv::Mat background = smooth_noise(o.frame_size, type, 6, o.seed);
  cv::Mat texture = smooth_noise(cv::Size(200, 200), type, 2, o.seed + 1);
  // A distinct look: brighter, with a dark cross.
  texture = texture * 0.6 + cv::Scalar::all(100);
  cv::line(texture, {0, 100}, {199, 100}, cv::Scalar::all(0), 12);
  cv::line(texture, {100, 0}, {100, 199}, cv::Scalar::all(0), 12);
  SyntheticSequence seq;
  const cv::Point2d c0(0.5 * o.frame_size.width, 0.5 * o.frame_size.height);
  const double ax = 0.25 * o.frame_size.width, ay = 0.2 * o.frame_size.height;
  double phase = 0, scale = 1;
  for (int i = 0; i < o.frames; ++i) {
    const cv::Point2d c(c0.x + ax * std::sin(phase), c0.y + ay * std::sin(1.7 * phase));
    // Advance the phase so that the centre moves about speed_px per frame.
    const double vx = ax * std::cos(phase), vy = 1.7 * ay * std::cos(1.7 * phase);
    phase += o.speed_px / std::max(1.0, std::hypot(vx, vy));
    const cv::Size2d sz(o.target_size.width * scale, o.target_size.height * scale);
    scale *= o.scale_per_frame;
    cv::Mat f = background.clone();
    const cv::Rect2d box(c.x - 0.5 * sz.width, c.y - 0.5 * sz.height, sz.width, sz.height);
    const cv::Rect r = cv::Rect(box) & cv::Rect(0, 0, f.cols, f.rows);
    cv::Mat t;
    cv::resize(texture, t, cv::Rect(box).size());
    const cv::Rect tr(r.x - cv::Rect(box).x, r.y - cv::Rect(box).y, r.width, r.height);
    t(tr).copyTo(f(r));
    if (i >= o.occlude_from && i <= o.occlude_to)
      cv::rectangle(f, cv::Rect(box) + cv::Size(20, 20) - cv::Point(10, 10), cv::Scalar::all(128),
                    cv::FILLED);
    seq.frames.push_back(f);
    seq.boxes.push_back(box);
  }
  return seq;
}

}  // namespace dreamsense::objects::testing
