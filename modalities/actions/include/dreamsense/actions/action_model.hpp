#pragma once
// A trained action classifier: normalisation + window descriptor + SVM, with open-set rejection
// and calibrated per-class scores, saved as a versioned YAML file. README.md has the method and
// the measured numbers.

#include "dreamsense/actions/features.hpp"
#include "dreamsense/actions/normalization.hpp"
#include "dreamsense/actions/skeleton_sequence.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace dreamsense::actions {

inline constexpr const char* kNoneLabel = "none";

// kShrinkageLda: linear discriminant analysis with Ledoit-Wolf shrinkage (README.md "Method");
// its decision values are log posteriors (<= 0).
enum class ClassifierKind { kLinearSvm, kRbfSvm, kShrinkageLda };
std::string_view to_string(ClassifierKind k);  // "linear_svm", "rbf_svm", "shrinkage_lda"
Result<ClassifierKind> classifier_kind_from_string(std::string_view s);

struct ClassifierOptions {
  ClassifierKind kind = ClassifierKind::kLinearSvm;
  double c = 1.0;      // SVM cost (not used by the LDA)
  double gamma = 0.0;  // RBF kernel width on standardised features; 0 = 1 / dimension
  // Scale each feature to unit variance (true), or all features by one common factor (false:
  // keeps the descriptor's geometry, so dimensions that barely vary stay small).
  bool standardize_each = true;
  bool l1 = false;  // linear: L1-regularised (sparse weights) instead of L2
  // Open set (README.md "Rejection"): cross-validation on the training windows
  // (reject_folds folds) gives held-out decision values; a window is "none" when
  // - its best one-vs-rest decision is below min(0, the reject_quantile quantile of the winning
  //   decisions of correctly classified held-out windows): no class claims it; or
  // - its standardised descriptor is far from everything seen in training (a linear SVM can
  //   score such windows high): the distance to the winning class's centroid, in units of that
  //   class's RMS radius, exceeds novelty_margin x the held-out (1 - reject_quantile) quantile.
  // The same cross-validation fits the score temperature. reject_folds = 0: no rejection,
  // scores with temperature 1.
  int reject_folds = 3;
  double reject_quantile = 0.02;
  double novelty_margin = 1.5;
  Status check() const;
};

struct ActionModelOptions {
  BodyFrameOptions body;
  FeatureOptions features;
  ClassifierOptions classifier;
  // The window of the online classifier (seconds). 0 = the median duration of the training
  // examples (for models trained on whole dataset segments).
  double window_s = 0;
  // Training augmentation (README.md): the mirror image of every example (left/right swapped),
  // and `crops` temporally cropped copies keeping crop_fraction of the example's duration
  // (offsets spread evenly from start to end: label boundaries are never exact).
  bool augment_mirror = false;
  int crops = 0;
  double crop_fraction = 0.85;
  Status check() const;
};

// The answer for one window.
struct ActionScores {
  std::string label = kNoneLabel;  // kNoneLabel: rejected, or no data, or the "none" class
  int index = -1;                  // into ActionModel::labels(); -1 when rejected / no data
  std::vector<double> scores;      // per class (labels() order), >= 0, sum 1; empty if no data
  std::vector<double> decision;    // raw SVM decision values per class
  double best_decision = 0;
  double novelty = 0;     // distance to the winning class's centroid / its RMS radius
  bool rejected = false;  // the best class scored below the open-set threshold
  bool no_data = false;   // the window could not be normalised (no torso joint) or is empty
};

class ActionModel {
 public:
  static constexpr const char* kFormatName = "dreamsense.actions.model";
  static constexpr int kFormatVersion = 1;

  // Trains on labelled windows (each example is one window: a dataset segment, or a slice of a
  // longer recording). Classes = the distinct labels, sorted. Examples that cannot be normalised
  // are skipped (counted in skipped_examples()). Needs at least two classes.
  static Result<ActionModel> train(const std::vector<LabelledSequence>& examples,
                                   const ActionModelOptions& options,
                                   const std::function<void(double)>& progress = nullptr);
  // The same on windows that view frames held elsewhere (e.g. sliding windows over long
  // recordings, without copying them).
  struct WindowRef {
    std::span<const SkeletonFrame> frames;
    std::string label;
    std::string subject;
  };
  static Result<ActionModel> train(const std::vector<WindowRef>& windows,
                                   const ActionModelOptions& options,
                                   const std::function<void(double)>& progress = nullptr);

  // The descriptor of a window (empty: no data).
  std::vector<float> features(std::span<const SkeletonFrame> window) const;
  ActionScores classify(std::span<const SkeletonFrame> window, bool reject = true) const;
  ActionScores classify_features(std::span<const float> features, bool reject = true) const;

  const std::vector<std::string>& labels() const { return labels_; }
  const ActionModelOptions& options() const { return options_; }
  double window_s() const { return window_s_; }  // effective online window
  double reject_threshold() const { return reject_threshold_; }
  double novelty_threshold() const { return novelty_threshold_; }
  double score_temperature() const { return temperature_; }
  int skipped_examples() const { return skipped_; }
  int training_examples() const { return examples_; }
  // Free text saved with the model (training data, command).
  std::string description;

  Status save(const std::filesystem::path& path) const;
  // Errors (one line, naming the file): missing, unreadable/corrupt, another format or version.
  static Result<ActionModel> load(const std::filesystem::path& path);

 private:
  ActionModelOptions options_;
  std::vector<std::string> labels_;
  double window_s_ = 0;
  cv::Mat mean_, inv_std_;  // 1 x D, CV_32F: standardisation
  cv::Mat weights_, bias_;  // linear
  cv::Mat support_vectors_, coef_, rho_, counts_;
  double gamma_ = 0;
  double reject_threshold_ = -1e30;
  cv::Mat centroids_, radii_;  // classes x D (standardised space), classes x 1; CV_32F
  double novelty_threshold_ = 1e30;
  double temperature_ = 1.0;
  int skipped_ = 0, examples_ = 0;
  void decision(const float* standardized, double* out, int* votes) const;
  double novelty(const float* standardized, int cls) const;
};

}  // namespace dreamsense::actions
