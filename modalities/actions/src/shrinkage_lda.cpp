// Shrinkage LDA (svm_backends.hpp): Ledoit-Wolf covariance per class, pooled with the priors.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "svm_backends.hpp"

namespace dreamsense::actions::detail {
namespace {

using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

Matrix to_eigen(const cv::Mat& m) {
  Matrix out(m.rows, m.cols);
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c) out(r, c) = m.at<float>(r, c);
  return out;
}

// Ledoit & Wolf (2004), eq. 14-15 as written for centred data z (n x p): the optimal weight of
// the scaled identity mu*I against the sample covariance E = z'z / n.
double shrinkage_of(const Matrix& z, const Matrix& e, double* mu_out) {
  const double n = static_cast<double>(z.rows()), p = static_cast<double>(z.cols());
  const double trace = e.trace();
  const double mu = trace / p;
  if (mu_out) *mu_out = mu;
  const double delta_sum = e.squaredNorm();                                  // sum of (z'z / n)^2
  const double beta_sum = z.rowwise().squaredNorm().array().square().sum();  // sum_i |z_i|^4
  double beta = (beta_sum / n - delta_sum) / (p * n);
  const double delta = (delta_sum - 2.0 * mu * trace + p * mu * mu) / p;
  beta = std::min(beta, delta);
  return beta <= 0 || delta <= 0 ? 0.0 : beta / delta;
}

}  // namespace

double ledoit_wolf_shrinkage(const cv::Mat& z, double* mu) {
  const Matrix a = to_eigen(z);
  const Matrix e = a.transpose() * a / static_cast<double>(std::max<Eigen::Index>(a.rows(), 1));
  return shrinkage_of(a, e, mu);
}

LinearSvm train_shrinkage_lda(const cv::Mat& x, const std::vector<int>& y, int classes,
                              std::vector<double>* shrinkage) {
  CV_Assert(x.type() == CV_32F && x.rows == static_cast<int>(y.size()) && classes >= 2);
  const int n = x.rows, d = x.cols;
  const Matrix all = to_eigen(x);
  Matrix means = Matrix::Zero(classes, d);
  std::vector<int> count(static_cast<size_t>(classes), 0);
  for (int i = 0; i < n; ++i) {
    means.row(y[static_cast<size_t>(i)]) += all.row(i);
    ++count[static_cast<size_t>(y[static_cast<size_t>(i)])];
  }
  if (shrinkage) shrinkage->assign(static_cast<size_t>(classes), 0.0);
  Matrix pooled = Matrix::Zero(d, d);
  for (int k = 0; k < classes; ++k) {
    const int nk = count[static_cast<size_t>(k)];
    if (nk == 0) continue;
    means.row(k) /= nk;
    // The class's examples, centred and standardised (a constant feature keeps scale 1).
    Matrix z(nk, d);
    for (int i = 0, r = 0; i < n; ++i)
      if (y[static_cast<size_t>(i)] == k) z.row(r++) = all.row(i) - means.row(k);
    Eigen::VectorXd sd = (z.colwise().squaredNorm() / nk).cwiseSqrt().transpose();
    for (Eigen::Index c = 0; c < d; ++c)
      if (!(sd(c) > 0)) sd(c) = 1.0;
    z = z * sd.cwiseInverse().asDiagonal();
    Matrix e = z.transpose() * z / static_cast<double>(nk);
    double mu = 0;
    const double s = shrinkage_of(z, e, &mu);
    if (shrinkage) (*shrinkage)[static_cast<size_t>(k)] = s;
    e *= 1.0 - s;
    e.diagonal().array() += s * mu;
    const double prior = static_cast<double>(nk) / n;
    pooled.noalias() += prior * (sd.asDiagonal() * e * sd.asDiagonal());
  }
  // S w_k = mu_k. S is positive definite when any class shrinks; a tiny ridge covers the rest
  // (e.g. every class one example: S = 0).
  Eigen::LDLT<Matrix> ldlt(pooled);
  if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-12) {
    pooled.diagonal().array() += 1e-6 * std::max(pooled.trace() / d, 1e-12);
    ldlt.compute(pooled);
  }
  const Matrix w = ldlt.solve(means.transpose());  // d x classes
  LinearSvm out;
  out.weights = cv::Mat::zeros(classes, d, CV_32F);
  out.bias = cv::Mat::zeros(classes, 1, CV_32F);
  for (int k = 0; k < classes; ++k) {
    const int nk = count[static_cast<size_t>(k)];
    if (nk == 0) {
      out.bias.at<float>(k, 0) = -1e3f;
      continue;
    }
    for (int f = 0; f < d; ++f) out.weights.at<float>(k, f) = static_cast<float>(w(f, k));
    out.bias.at<float>(k, 0) = static_cast<float>(-0.5 * means.row(k).dot(w.col(k).transpose()) +
                                                  std::log(static_cast<double>(nk) / n));
  }
  return out;
}

}  // namespace dreamsense::actions::detail
