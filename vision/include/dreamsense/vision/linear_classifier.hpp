#pragma once
// Linear classifiers trained in the project: multinomial logistic regression (softmax, L2,
// L-BFGS; calibrated class probabilities) and one-vs-rest linear SVMs (L2-regularised hinge loss,
// dual coordinate descent: C.-J. Hsieh et al., ICML 2008; dlib's svm_c_linear_dcd_trainer).
// Deterministic: the same data gives bit-identical weights (single thread, fixed order).

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace dreamsense::vision {

// Per-feature centring and scaling to unit variance (constant features get scale 1).
struct Standardizer {
  std::vector<float> mean, inv_std;
  static Standardizer fit(const cv::Mat& samples);  // rows = samples, CV_32F
  void apply(cv::Mat& samples) const;               // in place, rows = samples
  void apply(std::vector<float>& sample) const;
  bool empty() const { return mean.empty(); }
};

// scores = weights * x + bias (one row per class).
struct LinearClassifier {
  cv::Mat weights;  // classes x dims, CV_32F
  std::vector<float> bias;
  int classes() const { return weights.rows; }
  int dims() const { return weights.cols; }
  std::vector<float> scores(const std::vector<float>& x) const;
};

// Probabilities from scores (numerically stable softmax).
std::vector<float> softmax(const std::vector<float>& scores);

struct SoftmaxOptions {
  // Objective: mean (optionally class-weighted) cross-entropy + l2 / 2 |W|^2 (bias free).
  double l2 = 1e-3;
  // Weight samples by N / (classes x N_class) so that rare classes count as much as common ones.
  bool balance_classes = true;
  int max_iterations = 400;
  double tolerance = 1e-8;  // stop when the objective changes less than this (relative)
  Status check() const;
};
// `samples`: rows = samples (CV_32F); `labels` in [0, classes). Every class needs a sample.
Result<LinearClassifier> train_softmax(const cv::Mat& samples, const std::vector<int>& labels,
                                       int classes, const SoftmaxOptions& options = {});

struct SvmOptions {
  double c = 0.1;         // DREAM's FaceIDClassifier.xml: C_SVC, linear, C = 0.1
  double epsilon = 1e-3;  // dual stopping tolerance
  int max_iterations = 10000;
  Status check() const;
};
// One binary SVM per class (that class against all others).
Result<LinearClassifier> train_one_vs_rest_svm(const cv::Mat& samples,
                                               const std::vector<int>& labels, int classes,
                                               const SvmOptions& options = {});

// OpenCV FileStorage round trip (weights and bias stored exactly).
void write_linear(cv::FileStorage& fs, const std::string& name, const LinearClassifier& c);
Result<LinearClassifier> read_linear(const cv::FileNode& node, const std::string& what);
void write_standardizer(cv::FileStorage& fs, const std::string& name, const Standardizer& s);
Result<Standardizer> read_standardizer(const cv::FileNode& node, const std::string& what);

}  // namespace dreamsense::vision
