#pragma once
// Classification scores shared by the classification tasks (expression, faces, actions, objects,
// speech): a confusion matrix over named labels with accuracy, per-class recall/precision and the
// cli.md JSON shapes, and subject-disjoint splits for cross-validation.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::eval {

class ConfusionMatrix {
 public:
  // `labels`: the classes in report order. A prediction outside them (e.g. "unknown", "none",
  // a rejection) is counted in an extra column named by `other_label` and is always wrong.
  explicit ConfusionMatrix(std::vector<std::string> labels, std::string other_label = "other");
  void add(const std::string& truth, const std::string& predicted);
  size_t total() const { return total_; }
  size_t correct() const { return correct_; }
  std::optional<double> accuracy() const;
  std::optional<double> recall(const std::string& label) const;     // of truth `label`
  std::optional<double> precision(const std::string& label) const;  // of predicted `label`
  // Mean of the per-class recalls over classes that occur in the truth.
  std::optional<double> balanced_accuracy() const;
  // {"labels": [...], "predicted_labels": [... + other], "rows": [[...]]} (rows = truth).
  nlohmann::json confusion_json() const;
  // {label: {"recall", "precision", "support"}} for every label with support or predictions.
  nlohmann::json per_class_json() const;
  const std::vector<std::string>& labels() const { return labels_; }

 private:
  size_t column(const std::string& predicted) const;
  std::vector<std::string> labels_;
  std::string other_label_;
  std::map<std::string, size_t> index_;
  std::vector<std::vector<int64_t>> counts_;  // [truth][predicted], last column = other
  size_t total_ = 0, correct_ = 0;
};

// Splits `subjects` (distinct ids, any order) into `k` folds of near-equal size after a
// deterministic shuffle by `seed`; every subject is in exactly one fold. k is clamped to
// [1, subjects.size()].
std::vector<std::vector<std::string>> subject_folds(std::vector<std::string> subjects, int k,
                                                    uint64_t seed);
// A random half/half split of `subjects` (the first half trains): `repeat` draws, seeded.
std::vector<std::vector<std::string>> random_half_splits(std::vector<std::string> subjects,
                                                         int repeat, uint64_t seed);

}  // namespace dreamsense::eval
