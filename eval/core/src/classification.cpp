#include "dreamsense/eval/classification.hpp"

#include <algorithm>
#include <random>

namespace dreamsense::eval {

ConfusionMatrix::ConfusionMatrix(std::vector<std::string> labels, std::string other_label)
    : labels_(std::move(labels)), other_label_(std::move(other_label)) {
  for (size_t i = 0; i < labels_.size(); ++i) index_.emplace(labels_[i], i);
  counts_.assign(labels_.size(), std::vector<int64_t>(labels_.size() + 1, 0));
}

size_t ConfusionMatrix::column(const std::string& predicted) const {
  auto it = index_.find(predicted);
  return it == index_.end() ? labels_.size() : it->second;
}

void ConfusionMatrix::add(const std::string& truth, const std::string& predicted) {
  auto t = index_.find(truth);
  if (t == index_.end()) return;  // a truth outside the label set is not scored
  const size_t c = column(predicted);
  counts_[t->second][c]++;
  ++total_;
  if (c == t->second) ++correct_;
}

std::optional<double> ConfusionMatrix::accuracy() const {
  if (total_ == 0) return std::nullopt;
  return static_cast<double>(correct_) / static_cast<double>(total_);
}

std::optional<double> ConfusionMatrix::recall(const std::string& label) const {
  auto it = index_.find(label);
  if (it == index_.end()) return std::nullopt;
  int64_t support = 0;
  for (int64_t n : counts_[it->second]) support += n;
  if (support == 0) return std::nullopt;
  return static_cast<double>(counts_[it->second][it->second]) / static_cast<double>(support);
}

std::optional<double> ConfusionMatrix::precision(const std::string& label) const {
  auto it = index_.find(label);
  if (it == index_.end()) return std::nullopt;
  int64_t predicted = 0;
  for (const auto& row : counts_) predicted += row[it->second];
  if (predicted == 0) return std::nullopt;
  return static_cast<double>(counts_[it->second][it->second]) / static_cast<double>(predicted);
}

std::optional<double> ConfusionMatrix::balanced_accuracy() const {
  double sum = 0;
  int n = 0;
  for (const auto& l : labels_)
    if (auto r = recall(l)) {
      sum += *r;
      ++n;
    }
  if (n == 0) return std::nullopt;
  return sum / n;
}

nlohmann::json ConfusionMatrix::confusion_json() const {
  nlohmann::json predicted = labels_;
  predicted.push_back(other_label_);
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& row : counts_) rows.push_back(row);
  return {{"labels", labels_}, {"predicted_labels", predicted}, {"rows", rows}};
}

nlohmann::json ConfusionMatrix::per_class_json() const {
  nlohmann::json out = nlohmann::json::object();
  for (size_t i = 0; i < labels_.size(); ++i) {
    int64_t support = 0, predicted = 0;
    for (int64_t n : counts_[i]) support += n;
    for (const auto& row : counts_) predicted += row[i];
    if (support == 0 && predicted == 0) continue;
    const auto r = recall(labels_[i]);
    const auto p = precision(labels_[i]);
    out[labels_[i]] = {{"recall", r ? nlohmann::json(*r) : nlohmann::json(nullptr)},
                       {"precision", p ? nlohmann::json(*p) : nlohmann::json(nullptr)},
                       {"support", support}};
  }
  return out;
}

std::vector<std::vector<std::string>> subject_folds(std::vector<std::string> subjects, int k,
                                                    uint64_t seed) {
  std::sort(subjects.begin(), subjects.end());
  subjects.erase(std::unique(subjects.begin(), subjects.end()), subjects.end());
  std::mt19937_64 rng(seed);
  std::shuffle(subjects.begin(), subjects.end(), rng);
  const int n = static_cast<int>(subjects.size());
  k = std::clamp(k, 1, std::max(n, 1));
  std::vector<std::vector<std::string>> folds(static_cast<size_t>(k));
  for (int i = 0; i < n; ++i) folds[static_cast<size_t>(i % k)].push_back(subjects[i]);
  return folds;
}

std::vector<std::vector<std::string>> random_half_splits(std::vector<std::string> subjects,
                                                         int repeat, uint64_t seed) {
  std::sort(subjects.begin(), subjects.end());
  subjects.erase(std::unique(subjects.begin(), subjects.end()), subjects.end());
  std::mt19937_64 rng(seed);
  std::vector<std::vector<std::string>> out;
  for (int r = 0; r < repeat; ++r) {
    std::vector<std::string> s = subjects;
    std::shuffle(s.begin(), s.end(), rng);
    s.resize(s.size() / 2);
    std::sort(s.begin(), s.end());
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace dreamsense::eval
