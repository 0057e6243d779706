// Compressive tracking as published (Zhang, Zhang & Yang, ECCV 2012); see the header for the
// parameters and their sections.

#include "dreamsense/objects/compressive_tracker.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace dreamsense::objects {
namespace {

constexpr double kLogFloor = -69.07755278982137;  // log(1e-30): the authors' log(p + 1e-30) guard
constexpr double kSigmaFloor = 1e-3;

cv::Mat to_grey(const cv::Mat& frame) {
  if (frame.channels() == 1) return frame;
  cv::Mat g;
  cv::cvtColor(frame, g, cv::COLOR_BGR2GRAY);
  return g;
}

// Integer offsets (dx, dy) with inner^2 <= dx^2 + dy^2 < outer^2 (inner = 0: the full disc).
std::vector<cv::Point> offsets_in_ring(double inner, double outer) {
  std::vector<cv::Point> out;
  const int r = static_cast<int>(std::ceil(outer));
  const double in2 = inner * inner, out2 = outer * outer;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      const double d2 = dx * dx + dy * dy;
      if (d2 < out2 && (inner <= 0 || d2 > in2)) out.emplace_back(dx, dy);
    }
  return out;
}

}  // namespace

Status CompressiveTrackerOptions::check() const {
  std::string bad;
  auto need = [&bad](bool ok, const char* what) {
    if (!ok) bad += bad.empty() ? what : std::string("; ") + what;
  };
  need(features >= 1, "features must be >= 1");
  need(min_rects_per_feature >= 1 && max_rects_per_feature >= min_rects_per_feature,
       "rects per feature: need 1 <= min <= max");
  need(learning_rate >= 0 && learning_rate <= 1, "learning_rate must be in [0, 1]");
  need(positive_radius >= 1, "positive_radius must be >= 1");
  need(negative_inner_radius >= 0 && negative_outer_radius > negative_inner_radius + 1,
       "negative radii: need 0 <= inner < outer - 1");
  need(negative_samples >= 1, "negative_samples must be >= 1");
  need(search_radius >= 1, "search_radius must be >= 1");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "ct options: {}", bad);
  return ok_status();
}

void naive_bayes_update(double& mu, double& sigma, double mu_new, double sigma_new, double lambda) {
  const double d = mu - mu_new;
  sigma = std::sqrt(lambda * sigma * sigma + (1 - lambda) * sigma_new * sigma_new +
                    lambda * (1 - lambda) * d * d);
  mu = lambda * mu + (1 - lambda) * mu_new;
}

NaiveBayesModel::NaiveBayesModel(int features)
    : n_(features), mu1_(features), sigma1_(features), mu0_(features), sigma0_(features) {}

void NaiveBayesModel::update(const cv::Mat& positive, const cv::Mat& negative, double lambda) {
  DS_CHECK_EQ(positive.cols, n_);
  DS_CHECK_EQ(negative.cols, n_);
  DS_CHECK(positive.rows > 0 && negative.rows > 0);
  auto stats = [this](const cv::Mat& m, std::vector<double>& mean, std::vector<double>& sd) {
    mean.assign(n_, 0);
    sd.assign(n_, 0);
    for (int r = 0; r < m.rows; ++r) {
      const float* p = m.ptr<float>(r);
      for (int i = 0; i < n_; ++i) mean[i] += p[i];
    }
    for (int i = 0; i < n_; ++i) mean[i] /= m.rows;
    for (int r = 0; r < m.rows; ++r) {
      const float* p = m.ptr<float>(r);
      for (int i = 0; i < n_; ++i) sd[i] += (p[i] - mean[i]) * (p[i] - mean[i]);
    }
    for (int i = 0; i < n_; ++i) sd[i] = std::max(std::sqrt(sd[i] / m.rows), kSigmaFloor);
  };
  std::vector<double> m1, s1, m0, s0;
  stats(positive, m1, s1);
  stats(negative, m0, s0);
  if (!initialised_) {
    mu1_ = m1, sigma1_ = s1, mu0_ = m0, sigma0_ = s0;
    initialised_ = true;
    return;
  }
  for (int i = 0; i < n_; ++i) {
    naive_bayes_update(mu1_[i], sigma1_[i], m1[i], s1[i], lambda);
    naive_bayes_update(mu0_[i], sigma0_[i], m0[i], s0[i], lambda);
  }
}

double NaiveBayesModel::score(const float* v) const {
  double h = 0;
  for (int i = 0; i < n_; ++i) {
    const double d1 = (v[i] - mu1_[i]) / sigma1_[i];
    const double d0 = (v[i] - mu0_[i]) / sigma0_[i];
    const double l1 = std::max(-0.5 * d1 * d1 - std::log(sigma1_[i]), kLogFloor);
    const double l0 = std::max(-0.5 * d0 * d0 - std::log(sigma0_[i]), kLogFloor);
    h += l1 - l0;
  }
  return h;
}

CompressiveTracker::CompressiveTracker(CompressiveTrackerOptions options)
    : o_(options), rng_(options.seed) {}

cv::Mat CompressiveTracker::integral_around(const cv::Mat& grey, const cv::Point& at, int radius,
                                            cv::Point& origin) const {
  const cv::Rect want(at.x - radius, at.y - radius, box_size_.width + 2 * radius + 1,
                      box_size_.height + 2 * radius + 1);
  const cv::Rect roi = want & cv::Rect(0, 0, grey.cols, grey.rows);
  origin = roi.tl();
  cv::Mat integral;
  cv::integral(grey(roi), integral, CV_32S);
  return integral;
}

cv::Mat CompressiveTracker::extract(const cv::Mat& integral, const cv::Point& origin,
                                    const std::vector<cv::Point>& corners) const {
  const int n = static_cast<int>(features_.size());
  cv::Mat out(static_cast<int>(corners.size()), n, CV_32F);
  const int step = static_cast<int>(integral.step1());
  const int* base = integral.ptr<int>(0);
  for (size_t s = 0; s < corners.size(); ++s) {
    const int ox = corners[s].x - origin.x, oy = corners[s].y - origin.y;
    float* row = out.ptr<float>(static_cast<int>(s));
    for (int i = 0; i < n; ++i) {
      const auto& f = features_[static_cast<size_t>(i)];
      float v = 0;
      for (size_t k = 0; k < f.rects.size(); ++k) {
        const cv::Rect& r = f.rects[k];
        const int x0 = ox + r.x, y0 = oy + r.y, x1 = x0 + r.width, y1 = y0 + r.height;
        const int sum = base[y1 * step + x1] - base[y0 * step + x1] - base[y1 * step + x0] +
                        base[y0 * step + x0];
        v += f.weights[k] * static_cast<float>(sum);
      }
      row[i] = v;
    }
  }
  return out;
}

void CompressiveTracker::learn(const cv::Mat& grey, const cv::Point& at) {
  const int radius = static_cast<int>(std::ceil(o_.negative_outer_radius)) + 1;
  cv::Point origin;
  const cv::Mat integral = integral_around(grey, at, radius, origin);
  const cv::Rect inside(0, 0, grey.cols - box_size_.width + 1, grey.rows - box_size_.height + 1);
  std::vector<cv::Point> pos, neg;
  for (const auto& d : offsets_in_ring(0, o_.positive_radius))
    if (inside.contains(at + d)) pos.push_back(at + d);
  for (const auto& d : offsets_in_ring(o_.negative_inner_radius, o_.negative_outer_radius))
    if (inside.contains(at + d)) neg.push_back(at + d);
  if (pos.empty()) pos.push_back(at);
  if (neg.empty()) return;  // box as large as the frame: nothing to learn from
  // A random subset of the ring (§4: 50 negatives).
  const size_t keep = std::min(neg.size(), static_cast<size_t>(o_.negative_samples));
  for (size_t i = 0; i < keep; ++i) {
    std::uniform_int_distribution<size_t> pick(i, neg.size() - 1);
    std::swap(neg[i], neg[pick(rng_)]);
  }
  neg.resize(keep);
  model_.update(extract(integral, origin, pos), extract(integral, origin, neg), o_.learning_rate);
}

Status CompressiveTracker::init(const cv::Mat& frame, const cv::Rect2d& box) {
  if (auto s = o_.check(); !s) return s;
  if (auto s = check_init_box(frame, box); !s) return s;
  frame_size_ = frame.size();
  frame_type_ = frame.type();
  // CT samples whole boxes inside the frame: clamp the box into it.
  box_size_ = cv::Size(std::clamp(static_cast<int>(std::lround(box.width)), 4, frame.cols),
                       std::clamp(static_cast<int>(std::lround(box.height)), 4, frame.rows));
  position_ =
      cv::Point(std::clamp(static_cast<int>(std::lround(box.x)), 0, frame.cols - box_size_.width),
                std::clamp(static_cast<int>(std::lround(box.y)), 0, frame.rows - box_size_.height));
  // The random measurement matrix (§2.2, §3.1), drawn once per sequence.
  rng_.seed(o_.seed);
  features_.assign(static_cast<size_t>(o_.features), {});
  const int w = box_size_.width, h = box_size_.height;
  std::uniform_int_distribution<int> count(o_.min_rects_per_feature, o_.max_rects_per_feature);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (auto& f : features_) {
    const int c = count(rng_);
    for (int k = 0; k < c; ++k) {
      // As in the authors' code: x in [0, w-3), width in (0, w-x-2] (at least 1 px).
      const int x = static_cast<int>(std::floor(unit(rng_) * std::max(w - 3, 1)));
      const int y = static_cast<int>(std::floor(unit(rng_) * std::max(h - 3, 1)));
      const int rw = std::max(1, static_cast<int>(std::ceil(unit(rng_) * std::max(w - x - 2, 1))));
      const int rh = std::max(1, static_cast<int>(std::ceil(unit(rng_) * std::max(h - y - 2, 1))));
      f.rects.emplace_back(x, y, std::min(rw, w - x), std::min(rh, h - y));
      f.weights.push_back(static_cast<float>((unit(rng_) < 0.5 ? -1.0 : 1.0) / std::sqrt(c)));
    }
  }
  model_ = NaiveBayesModel(o_.features);
  learn(to_grey(frame), position_);
  initialised_ = true;
  return ok_status();
}

Result<TrackerUpdate> CompressiveTracker::update(const cv::Mat& frame) {
  if (!initialised_)
    return make_error(ErrorCode::kFailedPrecondition, "ct: update() before init()");
  if (auto s = check_update_frame(frame, frame_size_, frame_type_); !s)
    return tl::unexpected(s.error());
  const cv::Mat grey = to_grey(frame);
  const int radius = static_cast<int>(std::ceil(o_.search_radius)) + 1;
  cv::Point origin;
  const cv::Mat integral = integral_around(grey, position_, radius, origin);
  const cv::Rect inside(0, 0, grey.cols - box_size_.width + 1, grey.rows - box_size_.height + 1);
  std::vector<cv::Point> candidates;
  for (const auto& d : offsets_in_ring(0, o_.search_radius))
    if (inside.contains(position_ + d)) candidates.push_back(position_ + d);
  const cv::Mat v = extract(integral, origin, candidates);
  double best = -std::numeric_limits<double>::infinity();
  cv::Point best_at = position_;
  for (int i = 0; i < v.rows; ++i) {
    const double h = model_.score(v.ptr<float>(i));
    if (h > best) best = h, best_at = candidates[static_cast<size_t>(i)];
  }
  position_ = best_at;
  learn(grey, position_);
  TrackerUpdate u;
  u.box = cv::Rect2d(position_.x, position_.y, box_size_.width, box_size_.height);
  u.confidence = 1.0 / (1.0 + std::exp(-best / std::max(1, o_.features)));
  return u;
}

}  // namespace dreamsense::objects
