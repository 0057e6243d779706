// The face-api.js networks as loaded by our C++ against an independent NumPy implementation of
// the package's TypeScript graph (reference values below; script in the README), on a fixed
// synthetic pattern. Skipped when the npm package is not installed.
#include "dreamsense/vision/face_api_net.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace dreamsense::vision {
namespace {

cv::Mat pattern(int n) {
  cv::Mat m(n, n, CV_8UC1);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) m.at<uint8_t>(y, x) = static_cast<uint8_t>((x * 7 + y * 13) % 256);
  return m;
}

bool have_weights() {
  return std::filesystem::exists(default_face_api_model_dir() /
                                 "face_expression_model-weights_manifest.json");
}

TEST(FaceApiNet, ExpressionLogitsMatchReferenceImplementation) {
  if (!have_weights()) GTEST_SKIP() << "npm @vladmandic/face-api not installed (tools/setup.sh)";
  auto net = FaceApiExpressionNet::load(default_face_api_model_dir());
  ASSERT_TRUE(net.has_value()) << net.error().message;
  const FaceApiOutput out = net->run(pattern(kFaceApiInputPx));
  ASSERT_EQ(out.features.size(), static_cast<size_t>(kFaceApiFeatures));
  const float expected[7] = {1.6723f, 0.5778f, -0.2866f, -5.6377f, -8.8719f, -9.0844f, -4.2358f};
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(out.logits[k], expected[k], 2e-3) << k;
  EXPECT_EQ(net->weights_hash().size(), 16u);
}

TEST(FaceApiNet, RecognitionDescriptorMatchesReferenceImplementation) {
  if (!have_weights()) GTEST_SKIP() << "npm @vladmandic/face-api not installed (tools/setup.sh)";
  auto net = FaceApiRecognitionNet::load(default_face_api_model_dir());
  ASSERT_TRUE(net.has_value()) << net.error().message;
  const std::vector<float> d = net->describe(pattern(kFaceApiRecognitionInputPx));
  ASSERT_EQ(d.size(), static_cast<size_t>(kFaceApiDescriptorLength));
  const float expected[8] = {-0.0759f, 0.1180f,  0.0383f,  -0.0390f,
                             -0.0442f, -0.0603f, -0.0833f, -0.0077f};
  for (int k = 0; k < 8; ++k) EXPECT_NEAR(d[k], expected[k], 1e-3) << k;
  double n = 0;
  for (float v : d) n += v * v;
  EXPECT_NEAR(std::sqrt(n), 1.3288, 2e-3);
}

TEST(FaceApiNet, MissingOrCorruptWeightsAreErrorsNamingTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_face_api_bad";
  std::filesystem::create_directories(dir);
  auto missing = FaceApiExpressionNet::load(dir);
  ASSERT_FALSE(missing.has_value());
  EXPECT_NE(missing.error().message.find("face_expression_model-weights_manifest.json"),
            std::string::npos);
  std::ofstream(dir / "face_expression_model-weights_manifest.json")
      << "[{\"paths\": [\"x.bin\"], \"weights\": [";
  auto corrupt = FaceApiExpressionNet::load(dir);
  ASSERT_FALSE(corrupt.has_value());
  EXPECT_EQ(corrupt.error().code, ErrorCode::kCorruptData);
  std::ofstream(dir / "face_expression_model-weights_manifest.json")
      << R"([{"paths": ["x.bin"], "weights": [{"name": "dense0/conv0/filters", "shape": [3, 3, 3, 32], "dtype": "float32"}]}])";
  std::ofstream(dir / "x.bin") << "short";
  auto truncated = FaceApiExpressionNet::load(dir);
  ASSERT_FALSE(truncated.has_value());
  EXPECT_NE(truncated.error().message.find("too short"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(FaceApiNet, CropIsTheLandmarkBoxGrownByTenPercent) {
  std::vector<cv::Point2d> pts(68, cv::Point2d(50, 50));
  pts[0] = {40, 30};
  pts[1] = {60, 70};
  const cv::Rect r = face_api_crop(pts, cv::Size(200, 200));
  EXPECT_EQ(r, cv::Rect(38, 26, 24, 48));
  EXPECT_TRUE(face_api_crop({}, cv::Size(10, 10)).empty());
}

}  // namespace
}  // namespace dreamsense::vision
