#include "dreamsense/vision/linear_classifier.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <numeric>

namespace dreamsense::vision {
namespace {

// Three Gaussian blobs in 5-D, well separated.
void blobs(cv::Mat& x, std::vector<int>& y, int per_class, uint64_t seed) {
  cv::RNG rng(seed);
  x = cv::Mat(3 * per_class, 5, CV_32F);
  y.clear();
  for (int c = 0; c < 3; ++c)
    for (int i = 0; i < per_class; ++i) {
      float* row = x.ptr<float>(c * per_class + i);
      for (int j = 0; j < 5; ++j)
        row[j] = static_cast<float>(rng.gaussian(0.5) + (j == c ? 4.0 : 0.0));
      y.push_back(c);
    }
}

double accuracy(const LinearClassifier& c, const cv::Mat& x, const std::vector<int>& y) {
  int ok = 0;
  for (int i = 0; i < x.rows; ++i) {
    const auto s = c.scores(std::vector<float>(x.ptr<float>(i), x.ptr<float>(i) + x.cols));
    ok += static_cast<int>(std::max_element(s.begin(), s.end()) - s.begin()) == y[i];
  }
  return static_cast<double>(ok) / x.rows;
}

TEST(LinearClassifier, SoftmaxSeparatesBlobsWithCalibratedProbabilities) {
  cv::Mat x, xt;
  std::vector<int> y, yt;
  blobs(x, y, 40, 1);
  blobs(xt, yt, 40, 2);
  auto c = train_softmax(x, y, 3);
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_GE(accuracy(*c, xt, yt), 0.98);
  const auto p = softmax(c->scores(std::vector<float>(xt.ptr<float>(0), xt.ptr<float>(0) + 5)));
  EXPECT_NEAR(std::accumulate(p.begin(), p.end(), 0.0), 1.0, 1e-5);
  EXPECT_GT(p[0], 0.8);
}

TEST(LinearClassifier, OneVsRestSvmSeparatesBlobs) {
  cv::Mat x, xt;
  std::vector<int> y, yt;
  blobs(x, y, 40, 3);
  blobs(xt, yt, 40, 4);
  auto c = train_one_vs_rest_svm(x, y, 3);
  ASSERT_TRUE(c.has_value()) << c.error().message;
  EXPECT_EQ(c->classes(), 3);
  EXPECT_GE(accuracy(*c, xt, yt), 0.98);
}

TEST(LinearClassifier, TrainingIsDeterministic) {
  cv::Mat x;
  std::vector<int> y;
  blobs(x, y, 30, 5);
  auto a = train_softmax(x, y, 3), b = train_softmax(x, y, 3);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(cv::norm(a->weights, b->weights, cv::NORM_INF), 0.0);
  auto s = train_one_vs_rest_svm(x, y, 3), t = train_one_vs_rest_svm(x, y, 3);
  ASSERT_TRUE(s && t);
  EXPECT_EQ(cv::norm(s->weights, t->weights, cv::NORM_INF), 0.0);
}

TEST(LinearClassifier, BadTrainingSetsAreErrors) {
  cv::Mat x;
  std::vector<int> y;
  blobs(x, y, 10, 6);
  EXPECT_FALSE(train_softmax(x, y, 4).has_value());                       // class 3 has no sample
  EXPECT_FALSE(train_softmax(x, std::vector<int>(5, 0), 3).has_value());  // label count
  EXPECT_FALSE(train_one_vs_rest_svm(cv::Mat(), {}, 3).has_value());
  EXPECT_FALSE(train_softmax(x, y, 3, SoftmaxOptions{-1.0}).has_value());
}

TEST(LinearClassifier, FileStorageRoundTripIsExact) {
  cv::Mat x;
  std::vector<int> y;
  blobs(x, y, 20, 7);
  Standardizer s = Standardizer::fit(x);
  auto c = train_softmax(x, y, 3);
  ASSERT_TRUE(c.has_value());
  const auto path = std::filesystem::temp_directory_path() / "ds_linear_roundtrip.yaml";
  {
    cv::FileStorage fs(path.string(), cv::FileStorage::WRITE | cv::FileStorage::BASE64);
    write_linear(fs, "classifier", *c);
    write_standardizer(fs, "standardizer", s);
  }
  cv::FileStorage fs(path.string(), cv::FileStorage::READ);
  auto c2 = read_linear(fs["classifier"], "test");
  auto s2 = read_standardizer(fs["standardizer"], "test");
  ASSERT_TRUE(c2 && s2);
  EXPECT_EQ(cv::norm(c->weights, c2->weights, cv::NORM_INF), 0.0);
  EXPECT_EQ(c->bias, c2->bias);
  EXPECT_EQ(s.mean, s2->mean);
  EXPECT_FALSE(read_linear(fs["missing"], "test").has_value());
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace dreamsense::vision
