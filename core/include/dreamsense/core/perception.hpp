#pragma once
// Core perception types that analysers exchange through the blackboard, and their keys.
// Analysers never include each other's headers: they agree on these types only.
// docs/blackboard.md maps the keys onto DREAM's global buffer (D4.2 V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

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

// Direction of the dominant sound source (speech) seen from a microphone array.
// Array frame: azimuth 0 = broadside (+z), positive towards the array's +x; elevation positive
// upwards. A linear array (Kinect v1) cannot measure elevation (nullopt) and cannot tell front
// from back: its azimuth is in [-90, 90] and its direction assumes elevation 0.
struct SoundDirection {
  double azimuth_deg = 0;
  std::optional<double> elevation_deg;
  cv::Vec3d direction_array{0, 0, 1};  // unit vector, array frame
  cv::Vec3d direction_world{0, 0, 1};  // unit vector, world (through the array's extrinsics)
  double srp_power = 0;                // SRP-PHAT at the peak (mean pair coherence, <= 1)
  SensorId sensor;                     // the audio stream it came from
};

namespace keys {
// V17: sound direction (null entry: the analyser ran and heard no voice).
inline constexpr Key<SoundDirection> kSoundDirection{"audio.sound_direction"};
// V20/V29: skeleton joints of the child and their history (history via the blackboard).
inline constexpr Key<BodyState> kChildBody{"body.child"};
}  // namespace keys

}  // namespace dreamsense
