// fHOG: sizes, a flat image, and orientation selectivity.

#include "dreamsense/objects/fhog.hpp"

#include <gtest/gtest.h>

namespace dreamsense::objects {
namespace {

TEST(Fhog, CellGridAndChannelCount) {
  std::vector<cv::Mat> ch;
  compute_fhog(cv::Mat(50, 34, CV_8UC1, cv::Scalar(7)), 4, ch);
  ASSERT_EQ(ch.size(), static_cast<size_t>(kFhogChannels));
  EXPECT_EQ(ch[0].size(), cv::Size(8, 12));
  for (const auto& c : ch) EXPECT_EQ(cv::countNonZero(c), 0);  // flat: no gradient anywhere
}

TEST(Fhog, AVerticalEdgeFillsTheHorizontalGradientBins) {
  cv::Mat img(32, 32, CV_8UC1, cv::Scalar(0));
  img.colRange(16, 32).setTo(200);  // gradient along +x: orientation 0
  std::vector<cv::Mat> ch;
  compute_fhog(img, 4, ch);
  // Contrast-insensitive bin 0 (channel 18) dominates bin 4 (orthogonal, channel 22) at the edge.
  EXPECT_GT(ch[18].at<float>(3, 3), 0.1f);
  EXPECT_LT(ch[22].at<float>(3, 3), 0.02f);
  // Truncation: every channel value is bounded (4 normalisations x 0.2 x 0.5).
  for (const auto& c : ch) {
    double mx;
    cv::minMaxLoc(c, nullptr, &mx);
    EXPECT_LE(mx, 0.4 + 1e-6);
  }
}

TEST(Fhog, TooSmallForOneCellGivesEmptyMaps) {
  std::vector<cv::Mat> ch;
  compute_fhog(cv::Mat(3, 3, CV_8UC1, cv::Scalar(1)), 4, ch);
  ASSERT_EQ(ch.size(), static_cast<size_t>(kFhogChannels));
  EXPECT_TRUE(ch[0].empty());
}

}  // namespace
}  // namespace dreamsense::objects
