#pragma once
// Eye (pupil) centres of the selected face (modalities/eye_centers): V4, V14-V15.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// Centre of one eye's pupil/iris in the image, or found = false (eye closed, too small, ...).
struct EyeCenter {
  bool found = false;
  cv::Point2d center_px;  // full-resolution pixels of the camera image
  double confidence = 0;  // [0, 1]
  // The locator's pupil stage found a pupil inside the iris (EyeCenters::pupil_stage); a pupil
  // hidden under a lid is not found, and center_px is then the iris centre.
  bool pupil_found = false;
};

// Pupil centres of the selected face, from the landmarks' eye regions in the same frame.
struct EyeCenters {
  SensorId camera;  // = FaceLandmarks::camera
  Timestamp frame_stamp;
  uint64_t frame_sequence = 0;
  EyeCenter right;           // the subject's right eye (landmarks 36-41)
  EyeCenter left;            // the subject's left eye (landmarks 42-47)
  std::string method;        // which locator produced them (e.g. "improved_integro_differential")
  bool pupil_stage = false;  // the method looks for the pupil: pupil_found is meaningful
};

namespace keys {
// Absent entry when there are no landmarks in this tick.
inline constexpr Key<EyeCenters> kEyeCenters{"face.eye_centers"};
}  // namespace keys

}  // namespace dreamsense
