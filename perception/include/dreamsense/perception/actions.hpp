#pragma once
// The child's body action (modalities/actions): F20 identifyTrajectory, classified from the
// history of the child's skeleton (V29, keys::kChildBody) over a sliding window.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers).

#include "dreamsense/core/blackboard.hpp"

#include <string>
#include <utility>
#include <vector>

namespace dreamsense {

// The child's body action over the last window. `label` is "none" when nothing matches (open-set
// rejection), when the window is not full yet, or when the child is not in view (then `ready` is
// false: there was nothing to classify).
struct ActionState {
  std::string label = "none";
  int dream_id = 0;  // F20 index: 0 none, 1 wave, 2 cover_eyes, 3 hands_on_head, 4 fly,
                     // 5 drive_car, 6 drink, 7-11 custom gestures; -1 outside DREAM's classes
  std::vector<std::pair<std::string, double>> scores;  // per class
  bool ready = false;                                  // a full window was classified
  bool custom = false;                                 // from the custom-gesture model
  double window_s = 0;                                 // the classifier's window
};

namespace keys {
// F20: the child's body action (label, F20 id, per-class scores).
inline constexpr Key<ActionState> kChildAction{"body.action"};
}  // namespace keys

}  // namespace dreamsense
