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
