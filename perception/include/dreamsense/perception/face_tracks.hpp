#pragma once
// 3-D face tracks (modalities/face_tracks): F23 trackFace.
// Blackboard types of one modality (perception layer: below the modalities, which never include
// each other's headers). docs/blackboard.md maps the keys onto DREAM's global buffer (V1-V29).

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

// A tracked face: stable id and a constant-velocity state in world.
struct FaceTrack {
  int id = 0;
  cv::Vec3d position_world_m{0, 0, 0};
  cv::Vec3d velocity_world_mps{0, 0, 0};
  Timestamp last_update;
  int hits = 0;  // observations absorbed
};
struct FaceTracks {
  std::vector<FaceTrack> tracks;  // confirmed tracks, most recently updated first
};

namespace keys {
// Written every tick with face detections (empty list = no tracks).
inline constexpr Key<FaceTracks> kFaceTracks{"face.tracks"};
}  // namespace keys

}  // namespace dreamsense
