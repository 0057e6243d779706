#include "dreamsense/vision/lbp.hpp"

#include <gtest/gtest.h>

#include <numeric>
#include <set>

namespace dreamsense::vision {
namespace {

TEST(Lbp, FiftyEightUniformPatternsAndOneBinForTheRest) {
  std::set<int> labels;
  int uniform = 0;
  for (unsigned c = 0; c < 256; ++c) {
    labels.insert(uniform_lbp_label(c));
    uniform += uniform_lbp_label(c) < kUniformLbpBins - 1;
  }
  EXPECT_EQ(uniform, 58);
  EXPECT_EQ(labels.size(), static_cast<size_t>(kUniformLbpBins));
  EXPECT_EQ(uniform_lbp_label(0), 0);
  EXPECT_EQ(uniform_lbp_label(255), 57);
  EXPECT_EQ(uniform_lbp_label(0b01010101), 58);  // 8 transitions
  EXPECT_EQ(uniform_lbp_label(0b00000001), 1);   // the next uniform code after 0
}

TEST(Lbp, FlatPatchSetsEveryBit) {
  cv::Mat flat(3, 3, CV_8UC1, cv::Scalar(77));
  const cv::Mat codes = lbp_codes(flat, 1.0);
  ASSERT_EQ(codes.size(), cv::Size(1, 1));
  EXPECT_EQ(codes.at<uint8_t>(0, 0), 255);  // neighbour >= centre (the seed's elbp)
  EXPECT_EQ(uniform_lbp_labels(flat).at<uint8_t>(0, 0), 57);
}

TEST(Lbp, BrightCentreClearsEveryBit) {
  cv::Mat m(3, 3, CV_8UC1, cv::Scalar(10));
  m.at<uint8_t>(1, 1) = 200;
  EXPECT_EQ(lbp_codes(m).at<uint8_t>(0, 0), 0);
}

TEST(Lbp, VerticalEdgeGivesTheInterpolatedCode) {
  // Columns 0 | 50 | 100, centre 50: neighbours n = 0 (right), 1 (up-right, interpolated 85),
  // 2 (up, 50 = centre), 6 (down), 7 (down-right) are >= 50; 3, 4, 5 (left side) are not.
  cv::Mat m = (cv::Mat_<uint8_t>(3, 3) << 0, 50, 100, 0, 50, 100, 0, 50, 100);
  EXPECT_EQ(lbp_codes(m).at<uint8_t>(0, 0), 0b11000111);
  cv::Mat f;
  m.convertTo(f, CV_32F);
  EXPECT_EQ(lbp_codes(f).at<uint8_t>(0, 0), 0b11000111);  // float input, same codes
}

TEST(Lbp, RadiusTwoShrinksTheMapByTwoOnEachSide) {
  cv::Mat m(20, 30, CV_8UC1);
  cv::randu(m, 0, 255);
  EXPECT_EQ(lbp_codes(m, 2.0).size(), cv::Size(26, 16));
  EXPECT_TRUE(lbp_codes(cv::Mat(3, 3, CV_8UC1), 2.0).empty());
}

TEST(Lbp, GridHistogramsAreNormalisedPerCell) {
  cv::Mat m(34, 34, CV_8UC1);
  cv::randu(m, 0, 255);
  const cv::Mat labels = uniform_lbp_labels(m);
  std::vector<float> h;
  grid_histograms(labels, kUniformLbpBins, 4, 2, false, h);
  ASSERT_EQ(h.size(), static_cast<size_t>(4 * 2 * kUniformLbpBins));
  for (int cell = 0; cell < 8; ++cell)
    EXPECT_NEAR(std::accumulate(h.begin() + cell * kUniformLbpBins,
                                h.begin() + (cell + 1) * kUniformLbpBins, 0.0),
                1.0, 1e-5);
  std::vector<float> s;
  grid_histograms(labels, kUniformLbpBins, 4, 2, true, s);
  for (size_t i = 0; i < h.size(); ++i) EXPECT_NEAR(s[i] * s[i], h[i], 1e-6);
}

}  // namespace
}  // namespace dreamsense::vision
