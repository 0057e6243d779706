// The shrinkage LDA of the actions classifier (src/shrinkage_lda.cpp) against the textbook.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../src/svm_backends.hpp"

namespace dreamsense::actions::detail {
namespace {

cv::Mat gaussian_rows(int n, int p, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> g;
  cv::Mat x(n, p, CV_32F);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < p; ++k) x.at<float>(i, k) = g(rng);
  return x;
}

// Ledoit & Wolf (2004) as the paper writes it: S = X'X / n, m = tr(S) / p,
// d2 = |S - mI|^2 / p, b2 = min(sum_i |x_i x_i' - S|^2 / n^2 / p, d2), shrinkage = b2 / d2.
double paper_shrinkage(const cv::Mat& xf) {
  cv::Mat x;
  xf.convertTo(x, CV_64F);
  const int n = x.rows, p = x.cols;
  const cv::Mat s = x.t() * x / n;
  const double m = cv::trace(s)[0] / p;
  const double d2 = std::pow(cv::norm(s - m * cv::Mat::eye(p, p, CV_64F)), 2) / p;
  double b2 = 0;
  for (int i = 0; i < n; ++i) b2 += std::pow(cv::norm(x.row(i).t() * x.row(i) - s), 2);
  b2 = std::min(b2 / n / n / p, d2);
  return b2 / d2;
}

TEST(ShrinkageLda, LedoitWolfIntensityIsThePapers) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    cv::Mat x = gaussian_rows(12, 7, seed);
    x.col(1) += 2 * x.col(0);  // some correlation
    cv::Mat mean;
    cv::reduce(x, mean, 0, cv::REDUCE_AVG);
    for (int i = 0; i < x.rows; ++i) x.row(i) -= mean;
    EXPECT_NEAR(ledoit_wolf_shrinkage(x), paper_shrinkage(x), 1e-9) << "seed " << seed;
  }
  // Few samples of an isotropic Gaussian: trust the identity. Many samples of a strongly
  // correlated one: trust the data.
  EXPECT_GT(ledoit_wolf_shrinkage(gaussian_rows(10, 50, 4)), 0.8);
  cv::Mat c = gaussian_rows(4000, 4, 5);
  c.col(1) = 3 * c.col(0) + 0.1 * c.col(1);
  c.col(3) = -2 * c.col(2) + 0.1 * c.col(3);
  EXPECT_LT(ledoit_wolf_shrinkage(c), 0.05);
}

TEST(ShrinkageLda, TwoGaussiansGiveTheBayesDirection) {
  // Shared covariance diag(1, 9) rotated 30 degrees; means 0 and (2, 1). Bayes: w ~ S^-1 (m1 - m0).
  const double a = CV_PI / 6;
  const cv::Matx22d r(std::cos(a), -std::sin(a), std::sin(a), std::cos(a));
  const cv::Matx22d cov = r * cv::Matx22d(1, 0, 0, 9) * r.t();
  const cv::Matx22d l = r * cv::Matx22d(1, 0, 0, 3);  // l l' = cov
  cv::Mat z = gaussian_rows(4000, 2, 6), x(4000, 2, CV_32F);
  std::vector<int> y(4000);
  for (int i = 0; i < 4000; ++i) {
    y[static_cast<size_t>(i)] = i % 2;
    const cv::Vec2d v = l * cv::Vec2d(z.at<float>(i, 0), z.at<float>(i, 1)) +
                        (i % 2 ? cv::Vec2d(2, 1) : cv::Vec2d());
    x.at<float>(i, 0) = static_cast<float>(v[0]);
    x.at<float>(i, 1) = static_cast<float>(v[1]);
  }
  std::vector<double> shrinkage;
  const LinearSvm m = train_shrinkage_lda(x, y, 2, &shrinkage);
  const cv::Vec2d bayes = cov.inv() * cv::Vec2d(2, 1);
  const cv::Vec2d w(m.weights.at<float>(1, 0) - m.weights.at<float>(0, 0),
                    m.weights.at<float>(1, 1) - m.weights.at<float>(0, 1));
  EXPECT_GT(w.dot(bayes) / cv::norm(w) / cv::norm(bayes), 0.995);
  for (double s : shrinkage) EXPECT_LT(s, 0.05);  // 2000 samples per class: little shrinkage
  // The midpoint of the means lies on the boundary (equal priors).
  double d[2];
  const float mid[2] = {1.f, 0.5f};
  linear_decision(m, mid, d);
  EXPECT_NEAR(d[0], d[1], 0.1);
  // A class with no examples can never win.
  const LinearSvm m3 = train_shrinkage_lda(x, y, 3);
  double d3[3];
  linear_decision(m3, mid, d3);
  EXPECT_LT(d3[2], std::min(d3[0], d3[1]) - 100);
}

TEST(ShrinkageLda, OneExamplePerClassStillSolves) {
  const cv::Mat x = gaussian_rows(3, 20, 7);
  const LinearSvm m = train_shrinkage_lda(x, {0, 1, 2}, 3);
  for (int k = 0; k < 3; ++k) {  // each example is its own class's mean: it must win there
    double d[3];
    linear_decision(m, x.ptr<float>(k), d);
    for (int j = 0; j < 3; ++j) {
      if (j != k) {
        EXPECT_GT(d[k], d[j]);
      }
    }
    for (double v : d) EXPECT_TRUE(std::isfinite(v));
  }
}

}  // namespace
}  // namespace dreamsense::actions::detail
