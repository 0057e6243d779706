#pragma once
// Actions analyser (F20 identifyTrajectory): a thin adapter that feeds the child's body
// (keys::kChildBody, written by the body analyser earlier in the same tick) to the online
// classifier and writes the answer. Not wired into the runner yet: the blackboard type lives
// here until the perception/ layer takes it (issue 19).

#include "dreamsense/actions/online.hpp"
#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/perception/body.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace dreamsense {

// The child's body action over the last window. `label` is "none" when nothing matches, the
// window is not full yet, or the child is not in view.
struct ActionState {
  std::string label = "none";
  int dream_id = 0;  // F20 index: 0 none, 1 wave, 2 cover_eyes, 3 hands_on_head, 4 fly,
                     // 5 drive_car, 6 drink, 7-11 custom gestures; -1 outside DREAM's classes
  std::vector<std::pair<std::string, double>> scores;  // per class
  bool ready = false;                                  // a full window was classified
  bool custom = false;                                 // from the custom-gesture model
};

namespace keys {
inline constexpr Key<ActionState> kChildAction{"body.action"};
}  // namespace keys

namespace actions {

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

}  // namespace actions
}  // namespace dreamsense
