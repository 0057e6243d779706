#include "dreamsense/voice_id/gmm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dreamsense::voice_id {

namespace {
constexpr double kLog2Pi = 1.8378770664093453;

double log_sum_exp(const double* v, int n) {
  double m = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < n; ++i) m = std::max(m, v[i]);
  if (!std::isfinite(m)) return m;
  double s = 0;
  for (int i = 0; i < n; ++i) s += std::exp(v[i] - m);
  return m + std::log(s);
}
}  // namespace

Result<DiagonalGmm> DiagonalGmm::create(cv::Mat weights, cv::Mat means, cv::Mat variances) {
  if (weights.empty() || means.empty() || variances.empty())
    return make_error(ErrorCode::kInvalidArgument, "gmm: empty weights, means or variances");
  weights.convertTo(weights, CV_64F);
  means.convertTo(means, CV_64F);
  variances.convertTo(variances, CV_64F);
  weights = weights.reshape(1, 1);
  const int K = means.rows, D = means.cols;
  if (weights.cols != K || variances.rows != K || variances.cols != D)
    return make_error(ErrorCode::kInvalidArgument,
                      "gmm: shapes disagree (weights {}, means {}x{}, variances {}x{})",
                      weights.cols, K, D, variances.rows, variances.cols);
  double sum = 0, min_w = 0, min_v = 0;
  cv::minMaxLoc(weights, &min_w);
  cv::minMaxLoc(variances, &min_v);
  sum = cv::sum(weights)[0];
  if (!(min_w >= 0) || std::abs(sum - 1.0) > 1e-6)
    return make_error(ErrorCode::kInvalidArgument,
                      "gmm: weights must be >= 0 and sum to 1 (min {}, sum {})", min_w, sum);
  if (!(min_v > 0))
    return make_error(ErrorCode::kInvalidArgument, "gmm: variances must be > 0 (min {})", min_v);
  if (!cv::checkRange(means))
    return make_error(ErrorCode::kInvalidArgument, "gmm: means are not finite");
  DiagonalGmm g;
  g.weights_ = weights.clone();
  g.means_ = means.clone();
  g.variances_ = variances.clone();
  g.precompute();
  return g;
}

void DiagonalGmm::precompute() {
  const int K = components(), D = dimension();
  inv_var_ = cv::Mat(K, D, CV_64F);
  log_c_.assign(static_cast<size_t>(K), 0.0);
  for (int k = 0; k < K; ++k) {
    double log_det = 0;
    for (int d = 0; d < D; ++d) {
      const double v = variances_.at<double>(k, d);
      inv_var_.at<double>(k, d) = 1.0 / v;
      log_det += std::log(v);
    }
    const double w = weights_.at<double>(0, k);
    log_c_[k] = (w > 0 ? std::log(w) : -1e300) - 0.5 * (D * kLog2Pi + log_det);
  }
}

double DiagonalGmm::posteriors(const double* x, double* gamma) const {
  const int K = components(), D = dimension();
  for (int k = 0; k < K; ++k) {
    const double* mu = means_.ptr<double>(k);
    const double* iv = inv_var_.ptr<double>(k);
    double q = 0;
    for (int d = 0; d < D; ++d) {
      const double e = x[d] - mu[d];
      q += e * e * iv[d];
    }
    gamma[k] = log_c_[static_cast<size_t>(k)] - 0.5 * q;
  }
  const double lse = log_sum_exp(gamma, K);
  for (int k = 0; k < K; ++k) gamma[k] = std::exp(gamma[k] - lse);
  return lse;
}

double DiagonalGmm::log_likelihood(const double* x) const {
  std::vector<double> g(static_cast<size_t>(components()));
  return posteriors(x, g.data());
}

std::vector<double> DiagonalGmm::frame_log_likelihoods(const cv::Mat& X) const {
  DS_CHECK_EQ(X.type(), CV_64F);
  DS_CHECK_EQ(X.cols, dimension());
  std::vector<double> out(static_cast<size_t>(X.rows));
  std::vector<double> g(static_cast<size_t>(components()));
  for (int t = 0; t < X.rows; ++t) out[t] = posteriors(X.ptr<double>(t), g.data());
  return out;
}

Status GmmTrainOptions::check() const {
  std::string bad;
  if (components < 1 || components > 4096) bad += " components must be in [1, 4096];";
  if (min_frames_per_component < 1) bad += " min_frames_per_component must be >= 1;";
  if (iterations_per_split < 1 || final_iterations < 1) bad += " iterations must be >= 1;";
  if (!(tolerance >= 0)) bad += " tolerance must be >= 0;";
  if (!(variance_floor > 0 && variance_floor < 1)) bad += " variance_floor must be in (0, 1);";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "GmmTrainOptions:" + bad);
  return ok_status();
}

Status MapOptions::check() const {
  if (!(relevance > 0) || !(variance_floor > 0 && variance_floor <= 1))
    return make_error(ErrorCode::kInvalidArgument,
                      "MapOptions: relevance must be > 0 and variance_floor in (0, 1]");
  return ok_status();
}

namespace {

struct Params {
  cv::Mat w, mu, var;  // 1xK, KxD, KxD
};

// One EM iteration; returns the average log-likelihood under the parameters before the update.
double em_step(const cv::Mat& X, Params& p, const cv::Mat& var_floor) {
  const int K = p.mu.rows, D = p.mu.cols, N = X.rows;
  auto g = DiagonalGmm::create(p.w, p.mu, p.var);
  DS_CHECK(g.has_value());
  cv::Mat n(1, K, CV_64F, cv::Scalar(0)), sx(K, D, CV_64F, cv::Scalar(0)),
      sxx(K, D, CV_64F, cv::Scalar(0));
  std::vector<double> gamma(static_cast<size_t>(K));
  double total = 0;
  for (int t = 0; t < N; ++t) {
    const double* x = X.ptr<double>(t);
    total += g->posteriors(x, gamma.data());
    for (int k = 0; k < K; ++k) {
      const double gk = gamma[k];
      if (gk < 1e-10) continue;
      n.at<double>(0, k) += gk;
      double* a = sx.ptr<double>(k);
      double* b = sxx.ptr<double>(k);
      for (int d = 0; d < D; ++d) {
        a[d] += gk * x[d];
        b[d] += gk * x[d] * x[d];
      }
    }
  }
  for (int k = 0; k < K; ++k) {
    const double nk = n.at<double>(0, k);
    if (nk < 1e-3) continue;  // empty component: keep it as it was (weight -> ~0 below)
    for (int d = 0; d < D; ++d) {
      const double m = sx.at<double>(k, d) / nk;
      p.mu.at<double>(k, d) = m;
      p.var.at<double>(k, d) =
          std::max(sxx.at<double>(k, d) / nk - m * m, var_floor.at<double>(0, d));
    }
  }
  // Weights, with a tiny floor so that no component dies completely.
  for (int k = 0; k < K; ++k) p.w.at<double>(0, k) = std::max(n.at<double>(0, k) / N, 1e-8);
  p.w /= cv::sum(p.w)[0];
  return total / N;
}

void run_em(const cv::Mat& X, Params& p, const cv::Mat& var_floor, int iterations, double tol) {
  double last = -std::numeric_limits<double>::infinity();
  // A split starts near a saddle point, where the first iterations gain little: the tolerance
  // only applies after a few of them.
  for (int i = 0; i < iterations; ++i) {
    const double ll = em_step(X, p, var_floor);
    if (i >= 4 && ll - last < tol) break;
    last = ll;
  }
}

// Hard-assignment (k-means, distance scaled by the global variance) refinement of the means, then
// weights and variances from the clusters: the LBG step that moves split components apart fast
// (EM alone crawls away from a split, where both halves still have the parent's variance).
void kmeans_refine(const cv::Mat& X, Params& p, const cv::Mat& global_var, const cv::Mat& var_floor,
                   int iterations) {
  const int K = p.mu.rows, D = p.mu.cols, N = X.rows;
  std::vector<int> label(static_cast<size_t>(N), 0);
  cv::Mat inv_g(1, D, CV_64F);
  for (int d = 0; d < D; ++d) inv_g.at<double>(0, d) = 1.0 / global_var.at<double>(0, d);
  const double* ig = inv_g.ptr<double>(0);
  for (int it = 0; it < iterations; ++it) {
    bool changed = false;
    for (int t = 0; t < N; ++t) {
      const double* x = X.ptr<double>(t);
      int best = 0;
      double best_d = std::numeric_limits<double>::infinity();
      for (int k = 0; k < K; ++k) {
        const double* mu = p.mu.ptr<double>(k);
        double dist = 0;
        for (int d = 0; d < D && dist < best_d; ++d) {
          const double e = x[d] - mu[d];
          dist += e * e * ig[d];
        }
        if (dist < best_d) best_d = dist, best = k;
      }
      if (label[t] != best || it == 0) changed = true;
      label[t] = best;
    }
    cv::Mat sum(K, D, CV_64F, cv::Scalar(0));
    std::vector<int> count(static_cast<size_t>(K), 0);
    for (int t = 0; t < N; ++t) {
      sum.row(label[t]) += X.row(t);
      count[label[t]]++;
    }
    for (int k = 0; k < K; ++k)
      if (count[k] > 0) p.mu.row(k) = sum.row(k) / count[k];
    if (!changed) break;
  }
  cv::Mat sq(K, D, CV_64F, cv::Scalar(0));
  std::vector<int> count(static_cast<size_t>(K), 0);
  for (int t = 0; t < N; ++t) {
    const int k = label[t];
    const double* x = X.ptr<double>(t);
    const double* mu = p.mu.ptr<double>(k);
    double* s = sq.ptr<double>(k);
    for (int d = 0; d < D; ++d) s[d] += (x[d] - mu[d]) * (x[d] - mu[d]);
    count[k]++;
  }
  for (int k = 0; k < K; ++k) {
    for (int d = 0; d < D; ++d)
      p.var.at<double>(k, d) =
          count[k] > 1 ? std::max(sq.at<double>(k, d) / count[k], var_floor.at<double>(0, d))
                       : global_var.at<double>(0, d);
    p.w.at<double>(0, k) = std::max(static_cast<double>(count[k]) / N, 1e-8);
  }
  p.w /= cv::sum(p.w)[0];
}

// Splits component k into two (means +- 0.2 sigma), each with half the weight.
void split(Params& p, int k) {
  const int D = p.mu.cols;
  cv::Mat mu_row = p.mu.row(k).clone(), var_row = p.var.row(k).clone();
  cv::Mat plus = mu_row.clone(), minus = mu_row.clone();
  for (int d = 0; d < D; ++d) {
    const double s = 0.2 * std::sqrt(var_row.at<double>(0, d));
    plus.at<double>(0, d) += s;
    minus.at<double>(0, d) -= s;
  }
  const double w = p.w.at<double>(0, k) / 2;
  p.w.at<double>(0, k) = w;
  plus.copyTo(p.mu.row(k));
  p.mu.push_back(minus);
  p.var.push_back(var_row);
  cv::Mat wcol = p.w.t();
  wcol.push_back(w);
  p.w = wcol.t();
}

}  // namespace

Result<DiagonalGmm> train_gmm(const cv::Mat& X_in, const GmmTrainOptions& o,
                              const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  cv::Mat X;
  X_in.convertTo(X, CV_64F);
  if (X.rows < o.min_frames_per_component || X.rows < 2)
    return make_error(ErrorCode::kInvalidArgument,
                      "gmm: {} frames are too few to train a model (need >= {})", X.rows,
                      std::max(2, o.min_frames_per_component));
  if (!cv::checkRange(X))
    return make_error(ErrorCode::kInvalidArgument, "gmm: training data is not finite");
  const int K = std::max(1, std::min(o.components, X.rows / o.min_frames_per_component));
  cv::Mat mean, var(1, X.cols, CV_64F);
  cv::reduce(X, mean, 0, cv::REDUCE_AVG);
  for (int d = 0; d < X.cols; ++d) {
    cv::Mat c = X.col(d) - mean.at<double>(0, d);
    var.at<double>(0, d) = std::max(c.dot(c) / X.rows, 1e-12);
  }
  const cv::Mat var_floor = var * o.variance_floor;
  Params p{cv::Mat(1, 1, CV_64F, cv::Scalar(1.0)), mean.clone(), var.clone()};
  int splits = 0, total_splits = 0;
  for (int k = 1; k < K; k *= 2) ++total_splits;
  while (p.mu.rows < K) {
    const int now = p.mu.rows;
    if (2 * now <= K) {
      for (int k = 0; k < now; ++k) split(p, k);
    } else {
      // Last partial round: split the heaviest components.
      std::vector<int> order(static_cast<size_t>(now));
      for (int k = 0; k < now; ++k) order[k] = k;
      std::stable_sort(order.begin(), order.end(),
                       [&](int a, int b) { return p.w.at<double>(0, a) > p.w.at<double>(0, b); });
      for (int i = 0; i < K - now; ++i) split(p, order[static_cast<size_t>(i)]);
    }
    kmeans_refine(X, p, var, var_floor, 10);
    run_em(X, p, var_floor, o.iterations_per_split, o.tolerance);
    ++splits;
    if (progress) progress(0.8 * splits / std::max(1, total_splits));
  }
  run_em(X, p, var_floor, o.final_iterations, o.tolerance);
  if (progress) progress(1.0);
  return DiagonalGmm::create(p.w, p.mu, p.var);
}

GmmStats& GmmStats::operator+=(const GmmStats& o) {
  n += o.n;
  sx += o.sx;
  sxx += o.sxx;
  frames += o.frames;
  return *this;
}

GmmStats GmmStats::operator-(const GmmStats& o) const {
  return GmmStats{n - o.n, sx - o.sx, sxx - o.sxx, frames - o.frames};
}

GmmStats accumulate_stats(const DiagonalGmm& ubm, const cv::Mat& X_in) {
  const int K = ubm.components(), D = ubm.dimension();
  GmmStats st{cv::Mat(1, K, CV_64F, cv::Scalar(0)), cv::Mat(K, D, CV_64F, cv::Scalar(0)),
              cv::Mat(K, D, CV_64F, cv::Scalar(0)), 0.0};
  if (X_in.rows == 0) return st;
  cv::Mat X;
  X_in.convertTo(X, CV_64F);
  DS_CHECK_EQ(X.cols, D);
  st.frames = X.rows;
  std::vector<double> gamma(static_cast<size_t>(K));
  for (int t = 0; t < X.rows; ++t) {
    const double* x = X.ptr<double>(t);
    ubm.posteriors(x, gamma.data());
    for (int k = 0; k < K; ++k) {
      const double g = gamma[k];
      if (g < 1e-12) continue;
      st.n.at<double>(0, k) += g;
      double* a = st.sx.ptr<double>(k);
      double* b = st.sxx.ptr<double>(k);
      for (int d = 0; d < D; ++d) {
        a[d] += g * x[d];
        b[d] += g * x[d] * x[d];
      }
    }
  }
  return st;
}

DiagonalGmm map_adapt(const DiagonalGmm& ubm, const GmmStats& st, const MapOptions& o) {
  const int K = ubm.components(), D = ubm.dimension();
  DS_CHECK_EQ(st.n.cols, K);
  DS_CHECK_EQ(st.sx.rows, K);
  DS_CHECK_EQ(st.sxx.rows, K);
  if (st.frames <= 0) return ubm;
  cv::Mat w = ubm.weights().clone(), mu = ubm.means().clone(), var = ubm.variances().clone();
  for (int k = 0; k < K; ++k) {
    const double nk = std::max(0.0, st.n.at<double>(0, k));
    const double alpha = nk / (nk + o.relevance);
    if (o.adapt_weights)
      w.at<double>(0, k) = alpha * nk / st.frames + (1 - alpha) * w.at<double>(0, k);
    if (nk <= 1e-10) continue;
    for (int d = 0; d < D; ++d) {
      const double m0 = mu.at<double>(k, d), v0 = var.at<double>(k, d);
      const double m1 = alpha * (st.sx.at<double>(k, d) / nk) + (1 - alpha) * m0;
      mu.at<double>(k, d) = m1;
      if (o.adapt_variances)
        var.at<double>(k, d) =
            std::max(o.variance_floor * v0, alpha * (st.sxx.at<double>(k, d) / nk) +
                                                (1 - alpha) * (v0 + m0 * m0) - m1 * m1);
    }
  }
  w /= cv::sum(w)[0];
  auto g = DiagonalGmm::create(w, mu, var);
  DS_CHECK(g.has_value());
  return std::move(*g);
}

DiagonalGmm map_adapt(const DiagonalGmm& ubm, const cv::Mat& X, const MapOptions& o) {
  if (X.rows == 0) return ubm;
  return map_adapt(ubm, accumulate_stats(ubm, X), o);
}

}  // namespace dreamsense::voice_id
