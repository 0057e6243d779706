// Diagonal GMM: EM recovers well-separated clusters; MAP adaptation moves means towards data.

#include "dreamsense/voice_id/gmm.hpp"

#include <gtest/gtest.h>

#include <random>

namespace dreamsense::voice_id {
namespace {

// n points from N(mean, diag(sd^2)).
cv::Mat sample(int n, cv::Vec2d mean, cv::Vec2d sd, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, 1);
  cv::Mat X(n, 2, CV_64F);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 2; ++d) X.at<double>(i, d) = mean[d] + sd[d] * g(rng);
  return X;
}

TEST(Gmm, EmRecoversTwoWellSeparatedClusters) {
  cv::Mat X;
  cv::vconcat(sample(600, {-3, 0}, {1.0, 0.5}, 1), sample(1400, {4, 2}, {0.5, 1.5}, 2), X);
  GmmTrainOptions o;
  o.components = 2;
  auto g = train_gmm(X, o);
  ASSERT_TRUE(g) << g.error().message;
  ASSERT_EQ(g->components(), 2);
  const int a = g->means().at<double>(0, 0) < g->means().at<double>(1, 0) ? 0 : 1, b = 1 - a;
  EXPECT_NEAR(g->weights().at<double>(0, a), 0.3, 0.02);
  EXPECT_NEAR(g->weights().at<double>(0, b), 0.7, 0.02);
  EXPECT_NEAR(g->means().at<double>(a, 0), -3, 0.1);
  EXPECT_NEAR(g->means().at<double>(a, 1), 0, 0.1);
  EXPECT_NEAR(g->means().at<double>(b, 0), 4, 0.1);
  EXPECT_NEAR(g->means().at<double>(b, 1), 2, 0.1);
  EXPECT_NEAR(g->variances().at<double>(a, 0), 1.0, 0.15);
  EXPECT_NEAR(g->variances().at<double>(a, 1), 0.25, 0.04);
  EXPECT_NEAR(g->variances().at<double>(b, 0), 0.25, 0.04);
  EXPECT_NEAR(g->variances().at<double>(b, 1), 2.25, 0.3);
  // The likelihood is highest at a cluster centre.
  const double centre[2] = {4, 2}, between[2] = {0.5, 1};
  EXPECT_GT(g->log_likelihood(centre), g->log_likelihood(between));
}

TEST(Gmm, ComponentsAreReducedWhenDataIsScarce) {
  GmmTrainOptions o;
  o.components = 64;
  o.min_frames_per_component = 20;
  auto g = train_gmm(sample(200, {0, 0}, {1, 1}, 3), o);
  ASSERT_TRUE(g);
  EXPECT_EQ(g->components(), 10);
  auto none = train_gmm(sample(5, {0, 0}, {1, 1}, 3), o);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("too few"), std::string::npos);
}

TEST(Gmm, MapAdaptationMovesMeansTowardTheData) {
  cv::Mat X;
  cv::vconcat(sample(1000, {-3, 0}, {1, 1}, 4), sample(1000, {3, 0}, {1, 1}, 5), X);
  GmmTrainOptions o;
  o.components = 2;
  auto ubm = train_gmm(X, o);
  ASSERT_TRUE(ubm);
  const int right = ubm->means().at<double>(0, 0) > 0 ? 0 : 1;
  // A "speaker" whose right-hand cluster sits 1 higher in y.
  const cv::Mat few = sample(20, {3, 1}, {1, 1}, 6), many = sample(2000, {3, 1}, {1, 1}, 7);
  MapOptions means_only;
  means_only.adapt_weights = means_only.adapt_variances = false;
  const DiagonalGmm a = map_adapt(*ubm, few, means_only), b = map_adapt(*ubm, many, means_only);
  const double y0 = ubm->means().at<double>(right, 1);
  const double ya = a.means().at<double>(right, 1), yb = b.means().at<double>(right, 1);
  EXPECT_GT(ya, y0 + 0.2) << "20 frames already move the mean (alpha = 20 / 36)";
  EXPECT_LT(ya, yb) << "more data moves it further";
  EXPECT_NEAR(yb, 1.0, 0.1) << "alpha -> 1 with plenty of data";
  // The left component saw (almost) no data and stays put; weights and variances are the UBM's.
  EXPECT_NEAR(a.means().at<double>(1 - right, 1), ubm->means().at<double>(1 - right, 1), 1e-3);
  EXPECT_EQ(cv::norm(a.weights(), ubm->weights()), 0.0);
  EXPECT_EQ(cv::norm(a.variances(), ubm->variances()), 0.0);
  EXPECT_NEAR(ubm->means().at<double>(right, 1), y0, 0.0) << "the UBM itself is unchanged";
  // The adapted model explains the speaker's data better than the UBM.
  double llr = 0;
  const auto la = b.frame_log_likelihoods(many), lu = ubm->frame_log_likelihoods(many);
  for (size_t i = 0; i < la.size(); ++i) llr += la[i] - lu[i];
  EXPECT_GT(llr / static_cast<double>(la.size()), 0.1);
  // No data: the UBM back.
  const DiagonalGmm none = map_adapt(*ubm, cv::Mat(0, 2, CV_64F), MapOptions{});
  EXPECT_EQ(cv::norm(none.means(), ubm->means()), 0.0);
}

TEST(Gmm, FullMapAdaptationAlsoMovesWeightsAndVariances) {
  cv::Mat X;
  cv::vconcat(sample(1000, {-3, 0}, {1, 1}, 4), sample(1000, {3, 0}, {1, 1}, 5), X);
  GmmTrainOptions o;
  o.components = 2;
  auto ubm = train_gmm(X, o);
  ASSERT_TRUE(ubm);
  const int right = ubm->means().at<double>(0, 0) > 0 ? 0 : 1;
  // All of the speaker's frames are on the right, with a narrower spread in y.
  const DiagonalGmm s = map_adapt(*ubm, sample(2000, {3, 0}, {1, 0.5}, 8), MapOptions{});
  // Reynolds' eq. 11: w = g [alpha n / T + (1 - alpha) w]; the unused component keeps
  // (1 - alpha) of its weight (alpha ~ 4 / 20 here) before renormalisation.
  EXPECT_GT(s.weights().at<double>(0, right), 0.65);
  EXPECT_NEAR(cv::sum(s.weights())[0], 1.0, 1e-12);
  EXPECT_NEAR(s.variances().at<double>(right, 1), 0.25, 0.05) << "the speaker's narrower spread";
  EXPECT_NEAR(s.variances().at<double>(right, 0), ubm->variances().at<double>(right, 0), 0.15);
  // Statistics add up: two halves give the same model as the whole.
  const cv::Mat h1 = sample(500, {3, 0}, {1, 1}, 9), h2 = sample(500, {3, 0.5}, {1, 1}, 10);
  cv::Mat both;
  cv::vconcat(h1, h2, both);
  GmmStats st = accumulate_stats(*ubm, h1);
  st += accumulate_stats(*ubm, h2);
  const DiagonalGmm x = map_adapt(*ubm, st, MapOptions{}), y = map_adapt(*ubm, both, MapOptions{});
  EXPECT_LT(cv::norm(x.means(), y.means(), cv::NORM_INF), 1e-9);
  EXPECT_LT(cv::norm(x.variances(), y.variances(), cv::NORM_INF), 1e-9);
}

TEST(Gmm, CreateRejectsInconsistentParameters) {
  cv::Mat w = (cv::Mat_<double>(1, 2) << 0.5, 0.5), mu = cv::Mat::zeros(2, 3, CV_64F),
          var = cv::Mat::ones(2, 3, CV_64F);
  EXPECT_TRUE(DiagonalGmm::create(w, mu, var));
  EXPECT_FALSE(DiagonalGmm::create(w, mu, cv::Mat::ones(3, 3, CV_64F)));
  EXPECT_FALSE(DiagonalGmm::create((cv::Mat_<double>(1, 2) << 0.5, 0.6), mu, var));
  EXPECT_FALSE(DiagonalGmm::create(w, mu, cv::Mat::zeros(2, 3, CV_64F)));
}

}  // namespace
}  // namespace dreamsense::voice_id
