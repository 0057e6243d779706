#pragma once
// The child's body (modalities/body): V20 skeleton joints, V29 their history.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// The tracked child's skeleton in world (metres), chosen among the bodies a tracker reports.
struct BodyState {
  SkeletonBody body;       // joints in world
  SensorId sensor;         // the skeleton stream it came from
  int bodies_in_view = 0;  // how many bodies the tracker reported
};

namespace keys {
// V20/V29: skeleton joints of the child and their history (history via the blackboard).
inline constexpr Key<BodyState> kChildBody{"body.child"};
}  // namespace keys

}  // namespace dreamsense
