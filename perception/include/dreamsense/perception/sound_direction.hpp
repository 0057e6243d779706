#pragma once
// Sound direction (modalities/sound_direction): V17.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

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
}  // namespace keys

}  // namespace dreamsense
