// Compressive tracking: the measurement matrix, the features and the paper's update rule.

#include "dreamsense/objects/compressive_tracker.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

#include "synthetic_sequence.hpp"

namespace dreamsense::objects {
namespace {

TEST(NaiveBayesUpdate, FollowsEquationSix) {
  double mu = 2, sigma = 1;
  naive_bayes_update(mu, sigma, 4, 3, 0.85);
  // sigma' = sqrt(0.85 * 1 + 0.15 * 9 + 0.85 * 0.15 * (2 - 4)^2), mu' = 0.85 * 2 + 0.15 * 4.
  EXPECT_NEAR(sigma, std::sqrt(0.85 + 0.15 * 9 + 0.85 * 0.15 * 4), 1e-12);
  EXPECT_NEAR(mu, 2.3, 1e-12);
  double m2 = 5, s2 = 2;
  naive_bayes_update(m2, s2, 1, 1, 1.0);  // lambda = 1: nothing learnt
  EXPECT_DOUBLE_EQ(m2, 5);
  EXPECT_DOUBLE_EQ(s2, 2);
}

TEST(NaiveBayesModel, FirstUpdateIsTheSampleStatisticsThenEquationSix) {
  NaiveBayesModel m(1);
  cv::Mat pos = (cv::Mat_<float>(2, 1) << 1, 3);   // mean 2, sd 1
  cv::Mat neg = (cv::Mat_<float>(2, 1) << -2, 2);  // mean 0, sd 2
  m.update(pos, neg, 0.85);
  EXPECT_NEAR(m.mu_positive()[0], 2, 1e-9);
  EXPECT_NEAR(m.sigma_positive()[0], 1, 1e-9);
  EXPECT_NEAR(m.mu_negative()[0], 0, 1e-9);
  EXPECT_NEAR(m.sigma_negative()[0], 2, 1e-9);
  cv::Mat pos2 = (cv::Mat_<float>(2, 1) << 3, 5);  // mean 4, sd 1
  m.update(pos2, neg, 0.85);
  EXPECT_NEAR(m.mu_positive()[0], 0.85 * 2 + 0.15 * 4, 1e-9);
  EXPECT_NEAR(m.sigma_positive()[0], std::sqrt(0.85 + 0.15 + 0.85 * 0.15 * 4), 1e-9);
  // A value at the positive mean scores higher than one at the negative mean.
  const float at_pos = static_cast<float>(m.mu_positive()[0]), at_neg = 0.f;
  EXPECT_GT(m.score(&at_pos), m.score(&at_neg));
}

TEST(CompressiveTracker, MeasurementMatrixIsVerySparseAndInsideTheBox) {
  CompressiveTracker t;
  const cv::Mat frame(240, 320, CV_8UC1, cv::Scalar(100));
  ASSERT_TRUE(t.init(frame, {100, 80, 40, 50}));
  ASSERT_EQ(t.features().size(), 50u);  // n = 50 (§4)
  for (const auto& f : t.features()) {
    ASSERT_GE(f.rects.size(), 2u);  // c <= 4 non-zeros per row (§2.2)
    ASSERT_LE(f.rects.size(), 4u);
    const float w = 1.f / std::sqrt(static_cast<float>(f.rects.size()));
    for (size_t k = 0; k < f.rects.size(); ++k) {
      EXPECT_NEAR(std::abs(f.weights[k]), w, 1e-6);
      EXPECT_TRUE((cv::Rect(0, 0, 40, 50) & f.rects[k]) == f.rects[k]);
      EXPECT_GT(f.rects[k].area(), 0);
    }
  }
}

TEST(CompressiveTracker, FeaturesAreWeightedRectangleSums) {
  CompressiveTracker t;
  cv::Mat img(120, 160, CV_8UC1);
  cv::randu(img, 0, 256);
  ASSERT_TRUE(t.init(img, {30, 20, 30, 40}));
  cv::Mat integral;
  cv::integral(img, integral, CV_32S);
  const std::vector<cv::Point> corners = {{30, 20}, {35, 27}};
  const cv::Mat v = t.extract(integral, {0, 0}, corners);
  for (size_t s = 0; s < corners.size(); ++s)
    for (size_t i = 0; i < t.features().size(); ++i) {
      const auto& f = t.features()[i];
      double expect = 0;
      for (size_t k = 0; k < f.rects.size(); ++k)
        expect += f.weights[k] * cv::sum(img(f.rects[k] + corners[s]))[0];
      EXPECT_NEAR(v.at<float>(static_cast<int>(s), static_cast<int>(i)), expect,
                  1e-3 * std::abs(expect) + 1e-2);
    }
}

TEST(CompressiveTracker, ModelSeparatesTargetFromBackground) {
  testing::SyntheticOptions o;
  o.frames = 1;
  const auto s = testing::make_synthetic_sequence(o);
  CompressiveTracker t;
  ASSERT_TRUE(t.init(s.frames[0], s.boxes[0]));
  ASSERT_TRUE(t.model().initialised());
  cv::Mat grey, integral;
  cv::cvtColor(s.frames[0], grey, cv::COLOR_BGR2GRAY);
  cv::integral(grey, integral, CV_32S);
  const cv::Point at(static_cast<int>(std::lround(s.boxes[0].x)),
                     static_cast<int>(std::lround(s.boxes[0].y)));
  const cv::Mat v = t.extract(integral, {0, 0}, {at, at + cv::Point(25, 0)});
  EXPECT_GT(t.model().score(v.ptr<float>(0)), t.model().score(v.ptr<float>(1)));
}

TEST(CompressiveTracker, KeepsItsFirstSize) {
  testing::SyntheticOptions o;
  o.frames = 10;
  o.scale_per_frame = 1.03;
  const auto s = testing::make_synthetic_sequence(o);
  CompressiveTracker t;
  ASSERT_TRUE(t.init(s.frames[0], s.boxes[0]));
  for (size_t i = 1; i < s.frames.size(); ++i) {
    auto u = t.update(s.frames[i]);
    ASSERT_TRUE(u);
    EXPECT_NEAR(u->box.width, s.boxes[0].width, 1.0);  // no scale adaptation in CT
  }
}

TEST(CompressiveTracker, OptionsAreChecked) {
  CompressiveTrackerOptions o;
  o.learning_rate = 1.5;
  o.negative_outer_radius = 5;  // inside the inner radius
  auto s = o.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("learning_rate"), std::string::npos);
  EXPECT_NE(s.error().message.find("negative radii"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::objects
