#pragma once
// Actions analyser (F20 identifyTrajectory): a thin adapter that feeds the child's body
// (keys::kChildBody, written by the body analyser earlier in the same tick) to the online
// classifier and writes the answer (keys::kChildAction, perception/actions.hpp). Registered with
// the declared pipeline in src/register.cpp.

#include "dreamsense/actions/online.hpp"
#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/perception/actions.hpp"
#include "dreamsense/perception/body.hpp"

#include <filesystem>
#include <memory>

namespace dreamsense::actions {

struct ActionAnalyzerOptions {
  // Shipped DREAM-gesture model (modalities/actions/models/dream_gestures.yaml) or any model of
  // `train actions`; empty = none (then a gestures model is required).
  std::filesystem::path model;
  std::filesystem::path gestures;  // `train gestures` output; empty = no custom gestures
  OnlineOptions online;
  Status check() const;
};

// Errors: missing/corrupt model files (one line naming the file).
Result<std::unique_ptr<Analyzer>> make_action_analyzer(const ActionAnalyzerOptions& options);
// The same with models already in memory (tests, tools).
Result<std::unique_ptr<Analyzer>> make_action_analyzer(std::shared_ptr<const ActionModel> model,
                                                       std::shared_ptr<const GestureModel> gestures,
                                                       const OnlineOptions& online = {});

// The shipped DREAM-gesture model (modalities/actions/models/dream_gestures.yaml).
std::filesystem::path default_action_model_path();

}  // namespace dreamsense::actions
