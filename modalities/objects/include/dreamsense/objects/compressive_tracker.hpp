#pragma once
// Compressive tracking (CT) as published: K. Zhang, L. Zhang and M.-H. Yang, "Real-time
// Compressive Tracking", ECCV 2012, LNCS 7574, pp. 864-877. Named `ct` in make_tracker.
//
// What the paper specifies, and where (section numbers of the ECCV paper):
//  - §2.2, §3.1: each sample (a w x h box) is described by the responses of rectangle filters of
//    every size (the multi-scale Haar-like features), compressed by a very sparse random matrix R
//    (Achlioptas / Li et al.): r_ij = sqrt(s) * {+1 w.p. 1/(2s), 0 w.p. 1 - 1/s, -1 w.p. 1/(2s)}
//    with each row holding only c <= 4 non-zeros, so every compressed feature v_i is a signed
//    weighted sum of 2 to 4 rectangle sums at random positions with random sizes inside the box,
//    computed in constant time from an integral image. R is drawn once and kept for the sequence.
//  - §3.2: naive Bayes classifier H(v) = sum_i log(p(v_i|y=1) / p(v_i|y=0)) (uniform prior),
//    p(v_i|y) Gaussian; eq. (6) update with learning parameter lambda:
//      mu1    <- lambda * mu1 + (1 - lambda) * mu1_new
//      sigma1 <- sqrt(lambda * sigma1^2 + (1 - lambda) * sigma1_new^2
//                     + lambda * (1 - lambda) * (mu1 - mu1_new)^2)
//    and the same for the negative class.
//  - §3.3 / Algorithm 1: in frame t+1 every box within radius gamma of the last location is
//    classified and the best H wins; then positives are drawn within alpha of the new location
//    and negatives from the ring zeta < d < beta, and the classifier is updated.
//  - §4 (experimental setup): alpha = 4 (45 positive samples), zeta = 8, beta = 30, 50 random
//    negatives, gamma = 20 (about 1100 candidates), n = 50 features, lambda = 0.85.
//
// Where the paper is silent we follow the authors' released C++ code (CompressiveTracker.cpp,
// 2012) and say so: rectangle positions/sizes are drawn uniformly inside the box as in that code
// (x in [0, w-3), width in (0, w-x-2]); the weight of a rectangle is +-1/sqrt(c) (a per-feature
// scale; it does not change the naive Bayes decision); per-feature log-likelihoods are clamped at
// log(1e-30) like the code's `log(p + 1e-30)`. Initialisation is the paper's natural reading: the
// first frame's sample statistics are the model (the code blends them into mu = 0, sigma = 1).
// CT has no scale adaptation: the box keeps its first size.

#include "dreamsense/objects/tracker.hpp"

#include <cstdint>
#include <random>
#include <vector>

namespace dreamsense::objects {

struct CompressiveTrackerOptions {
  int features = 50;              // n, dimension of the compressed space (§4)
  int min_rects_per_feature = 2;  // non-zeros per row of R: uniformly 2..4, c <= 4 (§2.2)
  int max_rects_per_feature = 4;
  double learning_rate = 0.85;        // lambda of eq. (6) (§3.2, §4)
  double positive_radius = 4;         // alpha: positives at distance < alpha (§4: 45 samples)
  double negative_inner_radius = 8;   // zeta (§4)
  double negative_outer_radius = 30;  // beta (§4)
  int negative_samples = 50;          // drawn at random from the ring (§4)
  double search_radius = 20;          // gamma: candidates at distance < gamma (§4)
  uint64_t seed = 1;                  // of the random matrix and the negative sampling
  Status check() const;
};

// One compressed feature: sum_k weight_k * (pixel sum of rect_k), rect_k relative to the box.
struct CompressedFeature {
  std::vector<cv::Rect> rects;
  std::vector<float> weights;
};

// Gaussian naive Bayes over the compressed features with the paper's update rule (eq. 6).
class NaiveBayesModel {
 public:
  explicit NaiveBayesModel(int features = 0);
  // samples: N x n (CV_32F), one row per sample. The first call sets the model to the samples'
  // mean and standard deviation; later calls apply eq. (6) with `lambda`.
  void update(const cv::Mat& positive, const cv::Mat& negative, double lambda);
  // H(v) of one sample row (n floats).
  double score(const float* v) const;
  bool initialised() const { return initialised_; }
  const std::vector<double>& mu_positive() const { return mu1_; }
  const std::vector<double>& sigma_positive() const { return sigma1_; }
  const std::vector<double>& mu_negative() const { return mu0_; }
  const std::vector<double>& sigma_negative() const { return sigma0_; }

 private:
  int n_ = 0;
  bool initialised_ = false;
  std::vector<double> mu1_, sigma1_, mu0_, sigma0_;
};

// The update of eq. (6) for one Gaussian (exposed for the unit test of the rule).
void naive_bayes_update(double& mu, double& sigma, double mu_new, double sigma_new, double lambda);

class CompressiveTracker : public Tracker {
 public:
  explicit CompressiveTracker(CompressiveTrackerOptions options = {});
  std::string_view name() const override { return "ct"; }
  Status init(const cv::Mat& frame, const cv::Rect2d& box) override;
  Result<TrackerUpdate> update(const cv::Mat& frame) override;

  // For tests: the random projection drawn at init, and the classifier.
  const std::vector<CompressedFeature>& features() const { return features_; }
  const NaiveBayesModel& model() const { return model_; }
  // Compressed features of boxes of the current size at the given top-left corners, computed
  // from the integral image `integral` (CV_64F, one row/column larger than the grey image whose
  // origin is `origin` in frame coordinates). Exposed for tests.
  cv::Mat extract(const cv::Mat& integral, const cv::Point& origin,
                  const std::vector<cv::Point>& corners) const;

 private:
  void learn(const cv::Mat& grey, const cv::Point& at);
  cv::Mat integral_around(const cv::Mat& grey, const cv::Point& at, int radius,
                          cv::Point& origin) const;

  CompressiveTrackerOptions o_;
  std::mt19937_64 rng_;
  std::vector<CompressedFeature> features_;
  NaiveBayesModel model_;
  cv::Size box_size_;
  cv::Point position_;  // top-left corner of the current box (integer pixels)
  cv::Size frame_size_;
  int frame_type_ = -1;
  bool initialised_ = false;
};

}  // namespace dreamsense::objects
