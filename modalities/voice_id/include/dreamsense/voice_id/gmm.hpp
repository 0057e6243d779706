#pragma once
// Diagonal-covariance Gaussian mixture models: EM training by binary splitting (the usual
// universal background model recipe) and MAP adaptation of the means to one speaker
// (Reynolds, Quatieri & Dunn 2000, section 2.3, eq. 11-14).

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <functional>
#include <vector>

namespace dreamsense::voice_id {

// weights 1 x K (sum 1), means K x D, variances K x D (all > 0), all CV_64F.
class DiagonalGmm {
 public:
  DiagonalGmm() = default;
  // Error when the shapes disagree, a weight is negative, the weights do not sum to 1 or a
  // variance is not positive.
  static Result<DiagonalGmm> create(cv::Mat weights, cv::Mat means, cv::Mat variances);

  int components() const { return means_.rows; }
  int dimension() const { return means_.cols; }
  const cv::Mat& weights() const { return weights_; }
  const cv::Mat& means() const { return means_; }
  const cv::Mat& variances() const { return variances_; }

  // log p(x) of one frame (x: dimension() values).
  double log_likelihood(const double* x) const;
  // log p(x_t) of every row of X (N x D, CV_64F).
  std::vector<double> frame_log_likelihoods(const cv::Mat& X) const;
  // Posterior of each component for one frame (responsibilities, summing to 1); returns log p(x).
  double posteriors(const double* x, double* gamma) const;

 private:
  void precompute();
  cv::Mat weights_, means_, variances_;
  cv::Mat inv_var_;            // K x D
  std::vector<double> log_c_;  // log w_k - 0.5 (D log 2 pi + sum log var_k)
};

struct GmmTrainOptions {
  int components = 64;  // target K (the UBM recipe: 64-2048 Gaussians; small data wants few)
  // K is reduced to frames / this when data is scarce: 10 FSDD digits for each of 3 speakers
  // (~11 s of speech) give 13 Gaussians, 10 s of enrolment for each of 2 speakers 25.
  int min_frames_per_component = 80;
  int iterations_per_split = 8;  // EM iterations after each split (after 10 k-means passes)
  int final_iterations = 20;     // EM iterations at the final size
  double tolerance = 1e-4;       // stop when the average log-likelihood gains less
  double variance_floor = 0.01;  // variances >= this x the global variance of each dimension
  Status check() const;
};

// LBG-style growth from a single Gaussian: split every component (means +- 0.2 sigma along
// each dimension; the heaviest ones in the last round), move the halves apart with k-means, run
// EM; repeat until `components`, then EM to convergence. Deterministic. X: N x D CV_64F.
// Error: too few frames.
// `progress` (optional) receives fractions in [0, 1].
Result<DiagonalGmm> train_gmm(const cv::Mat& X, const GmmTrainOptions& options,
                              const std::function<void(double)>& progress = {});

struct MapOptions {
  // r: adaptation coefficient alpha_k = n_k / (n_k + r), n_k = the speaker's soft frame count
  // in component k (Reynolds et al. 2000, eq. 14; their value).
  double relevance = 16;
  // Reynolds et al. adapt the means only (best with a UBM of hundreds of speakers). With the
  // background pooled from the few enrolled speakers, adapting weights and variances as well
  // (their eq. 11 and 13) is clearly better: FSDD, 10 digits per speaker, 0.93 -> 0.97.
  bool adapt_weights = true;
  bool adapt_variances = true;
  double variance_floor = 0.01;  // adapted variances >= this x the UBM component's variance
  Status check() const;
};

// Zeroth-, first- and second-order statistics of frames under a model's posteriors:
// n_k = sum_t gamma_k(t) (1 x K), sx_k = sum_t gamma_k(t) x_t and sxx_k = sum_t gamma_k(t) x_t^2
// (K x D). They add up over frames.
struct GmmStats {
  cv::Mat n, sx, sxx;
  double frames = 0;
  GmmStats& operator+=(const GmmStats& o);
  GmmStats operator-(const GmmStats& o) const;
};
GmmStats accumulate_stats(const DiagonalGmm& ubm, const cv::Mat& X);

// MAP adaptation of the UBM to X (one speaker's frames), Reynolds et al. 2000 eq. 11-14:
//   w_k = g [alpha_k n_k / T + (1 - alpha_k) w_k]           (g: the weights sum to 1)
//   mu_k = alpha_k E_k[x] + (1 - alpha_k) mu_k
//   var_k = alpha_k E_k[x^2] + (1 - alpha_k)(var_k + mu_k^2) - new mu_k^2
// (weights and variances only if the options say so). Zero rows give the UBM back.
DiagonalGmm map_adapt(const DiagonalGmm& ubm, const cv::Mat& X, const MapOptions& options);
// The same from statistics (accumulate_stats of the speaker's frames).
DiagonalGmm map_adapt(const DiagonalGmm& ubm, const GmmStats& stats, const MapOptions& options);

}  // namespace dreamsense::voice_id
