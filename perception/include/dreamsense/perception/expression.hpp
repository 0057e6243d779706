#pragma once
// Facial expression of the selected face (modalities/expression): V24, F18 identifyFaceExpression.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <string>

namespace dreamsense {

// The smoothed expression of the selected camera's face (per face track).
struct FaceExpression {
  std::string label;       // anger, contempt, disgust, fear, happy, sadness, surprise
                           // (+ neutral when the model has it)
  double probability = 0;  // smoothed probability of `label`
  std::map<std::string, double> probabilities;  // smoothed, per model label
  std::string raw_label;                        // this frame's own (unsmoothed) prediction
  int track_id = -1;                            // face track the smoothing belongs to (-1: none)
  SensorId camera;
  Timestamp frame_stamp;
};

namespace keys {
// Written in ticks with a landmarks entry; absent when there are no landmarks.
inline constexpr Key<FaceExpression> kFaceExpression{"face.expression"};
}  // namespace keys

}  // namespace dreamsense
