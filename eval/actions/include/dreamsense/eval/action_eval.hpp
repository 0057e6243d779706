#pragma once
// `dreamsense train actions` / `eval actions`: dataset protocols for the skeleton action
// classifiers (modalities/actions), reported through eval/core's EvalReport (task "actions").
// Protocols (README of modalities/actions has the numbers):
// - utkinect without a model: 10 random half/half subject splits (the Lie-group protocol), the
//   first half of each draw trains (with 5 subjects: 2 train, 3 test); plus leave-one-subject-out;
// - msr-action3d without a model: the standard cross-subject split (odd subjects train, even
//   test) when both are present, otherwise leave-one-subject-out over the subjects present
//   (the shared copy holds only the odd subjects);
// - with a model: every item of the dataset is a test (train elsewhere, test here).
// Each segment / sequence is one window (time-normalised); the closed-set protocols classify
// without rejection (forced choice). Baseline and improved methods are measured in the same run.

#include "dreamsense/actions/action_model.hpp"
#include "dreamsense/eval/action_datasets.hpp"
#include "dreamsense/eval/report.hpp"

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace dreamsense::eval::actions {

struct ActionMethod {
  std::string name;  // "baseline", "pyramid"
  dreamsense::actions::ActionModelOptions options;
};
// The seed's method: relative joint positions at 4 instants of the normalised window, RBF SVM
// (libsvm, as DREAM used).
ActionMethod baseline_method();
// Ours: joint positions and velocities in the body frame, temporal pyramid + Fourier
// magnitudes, linear SVM (liblinear).
ActionMethod pyramid_method();
// Ours, second round: the same descriptor plus pairwise joint distances (mean and spread per
// pyramid cell), linear discriminant analysis with Ledoit-Wolf shrinkage instead of the SVM.
ActionMethod pyramid_lda_method();
// "baseline" | "pyramid" | "pyramid_lda"
Result<ActionMethod> method_by_name(const std::string& name);

struct ActionEvalOptions {
  std::string dataset;  // "utkinect" | "msr-action3d"
  std::filesystem::path dir;
  std::filesystem::path model;  // empty: the dataset's cross-validation protocol
  int splits = 10;              // random half/half draws (utkinect)
  uint64_t seed = 1;
  // Methods compared in the cross-validation; the last one is the reported `accuracy`.
  std::vector<ActionMethod> methods = {baseline_method(), pyramid_method(), pyramid_lda_method()};
  Status check() const;
};

Result<EvalReport> run_action_eval(const ActionEvalOptions& options,
                                   const std::function<void(double)>& progress = nullptr);

struct ActionTrainOptions {
  std::string dataset;
  std::filesystem::path dir;
  ActionMethod method = pyramid_lda_method();
  std::string description;  // saved in the model (e.g. the command line)
};
Result<dreamsense::actions::ActionModel> run_action_train(
    const ActionTrainOptions& options, const std::function<void(double)>& progress = nullptr);

}  // namespace dreamsense::eval::actions
