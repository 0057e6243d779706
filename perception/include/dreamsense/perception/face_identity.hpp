#pragma once
// Who the selected face is (modalities/face_identity): V23, F17 identifyFace.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <string>

namespace dreamsense {

// Identity of the selected camera's face against the enrolment gallery.
struct FaceIdentity {
  int id = -1;         // enrolled person id; -1 = unknown (rejected by the gallery's threshold)
  std::string name;    // from the gallery's name map (empty: ids only)
  double score = 0;    // the matcher's score of the best person (method-specific scale)
  int best_id = -1;    // best enrolled person even when rejected
  int track_id = -1;   // face track the result belongs to (-1: no track)
  std::string method;  // gallery method: face_api | lbp_tt | lbp_svm
  SensorId camera;
  Timestamp frame_stamp;   // of the frame the face was identified in (older when reused)
  bool refreshed = false;  // true when computed on this tick's frame (else the track's last)
};

namespace keys {
// Written in ticks with a landmarks entry; absent when there are no landmarks.
inline constexpr Key<FaceIdentity> kFaceIdentity{"face.identity"};
}  // namespace keys

}  // namespace dreamsense
