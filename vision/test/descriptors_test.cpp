#include "dreamsense/vision/descriptors.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace dreamsense::vision {
namespace {

cv::Mat textured(int w, int h, int seed = 1) {
  cv::Mat m(h, w, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 40, 120);
  cv::GaussianBlur(m, m, cv::Size(0, 0), 1.0);
  return m;
}

TEST(TanTriggs, BoundedAndInvariantToAGlobalGain) {
  const cv::Mat a = textured(64, 64);
  cv::Mat b;
  a.convertTo(b, CV_8U, 2.0);  // twice as bright (40..240, no saturation)
  const cv::Mat ta = tan_triggs(a), tb = tan_triggs(b);
  ASSERT_EQ(ta.size(), a.size());
  double lo, hi;
  cv::minMaxLoc(ta, &lo, &hi);
  EXPECT_GT(lo, -10.0);
  EXPECT_LT(hi, 10.0);
  EXPECT_LT(cv::norm(ta, tb, cv::NORM_INF), 0.05);  // gamma + DoG + normalisation cancel the gain
  EXPECT_FALSE((TanTriggsOptions{0.2, 2.0, 1.0}.check().has_value()));
}

TEST(Hog, LengthFollowsTheCellLayoutAndSizesAreChecked) {
  HogOptions o;
  EXPECT_EQ(hog_length(cv::Size(64, 64), o), 7u * 7u * 36u);
  std::vector<float> d;
  hog_descriptor(textured(64, 64), o, d);
  EXPECT_EQ(d.size(), hog_length(cv::Size(64, 64), o));
  EXPECT_FALSE(o.check(cv::Size(60, 64)).has_value());
  // A vertical edge puts its energy in the horizontal-gradient orientation bin.
  cv::Mat edge(64, 64, CV_8UC1, cv::Scalar(0));
  edge(cv::Rect(32, 0, 32, 64)).setTo(200);
  std::vector<float> e;
  hog_descriptor(edge, o, e);
  const size_t block = (3 * 7 + 3) * 36;  // block (3, 3) straddles the edge
  EXPECT_GT(e[block + 0], e[block + 4]);  // bin 0 (0 deg) beats bin 4 (80-100 deg)
}

TEST(LandmarkGeometry, CentredCoordinatesOrZeros) {
  std::vector<float> out;
  landmark_geometry(std::vector<cv::Point2d>(68, cv::Point2d(32, 16)), 64, 0.25, out);
  ASSERT_EQ(out.size(), kLandmarkGeometryLength);
  EXPECT_FLOAT_EQ(out[0], 0.0f);
  EXPECT_FLOAT_EQ(out[1], 0.0f);
  landmark_geometry({}, 64, 0.25, out);
  ASSERT_EQ(out.size(), 2 * kLandmarkGeometryLength);
  EXPECT_FLOAT_EQ(out.back(), 0.0f);
}

}  // namespace
}  // namespace dreamsense::vision
