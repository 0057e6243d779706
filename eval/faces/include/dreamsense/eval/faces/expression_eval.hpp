#pragma once
// `dreamsense train expression` and `dreamsense eval expression` (spec/cli.md, task
// "expression").
//
// Every image goes through the same path as in the pipeline's crop handling: vision's
// FaceCropAligner with the project's cascade and dlib landmarks (dreamsense::vision_locate),
// falling back to landmarks on the whole crop and then to the crop's own geometry
// (extra.alignment counts each path; an image with no usable face - flat, tiny - is predicted
// "no_face", an error).
//
// eval without a model: 10-fold subject-disjoint cross-validation (eval::subject_folds over the
// dataset's subjects; FER2013 has no subject ids, so every image is its own subject). Every
// method of `methods` is trained and tested on the same folds in the same run; the first one's
// metrics are at the top level (accuracy, balanced_accuracy, confusion, per_class), every
// method's under metrics.<method>. eval with a model: every image of DIR is a test item.
// Timing: ms_per_face_median = what the analyser pays per face once the landmarks are known
// (warp to the canonical crop + descriptors + classifier), single-threaded;
// ms_alignment_median = the dataset crop path (cascade + landmarks on the crop), which the
// pipeline's own detection and landmark analysers pay instead.

#include "dreamsense/core/status.hpp"
#include "dreamsense/eval/report.hpp"
#include "dreamsense/expression/expression_model.hpp"
#include "dreamsense/vision/face_crops.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace dreamsense::eval::faces {

using Progress = std::function<void(double)>;

struct ExpressionEvalOptions {
  std::string dataset;  // ckplus48 | fer2013
  std::filesystem::path dir;
  std::filesystem::path model;  // empty: cross-validation
  std::vector<std::string> methods{"lbp_hog", "lbp_svm"};
  int folds = 10;
  uint64_t seed = 12;
  vision::FaceCropOptions crop;  // its alignment is replaced by each method's
  Status check() const;
};

// Dataset classes (canonical labels, expression::canonical_label of the folder names) that the
// model's labels lack, in dataset order: the classes a model-only evaluation counts as wrong.
std::vector<std::string> classes_missing_from_model(const std::vector<std::string>& dataset_labels,
                                                    const std::vector<std::string>& model_labels);

// The dataset's own spelling of each canonical label it uses ({"anger": "angry", ...} for
// fer2013; the identity for ckplus48): reported beside per_class so that both names are found.
std::map<std::string, std::string> dataset_class_names(const std::string& dataset);

Result<EvalReport> run_expression_eval(const ExpressionEvalOptions& options,
                                       const Progress& progress = {});

struct ExpressionTrainOptions {
  std::string dataset;
  std::filesystem::path dir;
  std::string method = "lbp_hog";
  vision::FaceCropOptions crop;
  std::string note;  // stored in the model (e.g. the command line)
  Status check() const;
};

struct ExpressionTrainSummary {
  size_t images = 0, used = 0;  // used: images with a face
  std::map<std::string, size_t> per_label;
};

Result<expression::ExpressionModel> run_expression_train(const ExpressionTrainOptions& options,
                                                         ExpressionTrainSummary* summary = nullptr,
                                                         const Progress& progress = {});

}  // namespace dreamsense::eval::faces
