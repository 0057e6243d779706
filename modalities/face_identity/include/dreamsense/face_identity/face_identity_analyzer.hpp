#pragma once
// Face identity analyser: keys::kFaceLandmarks (+ the camera frame) -> keys::kFaceIdentity.
//
// Per tick, reads kFaceLandmarks (written earlier in the same tick by face_landmarks):
//  - no landmarks entry stamped with this tick: writes nothing;
//  - absent landmarks (the face is lost; the cached result is forgotten), no frame of the
//    landmarks' camera, or a face that cannot be aligned: absent;
//  - otherwise the gallery's answer (id, or -1 = unknown). A person does not change within a face
//    track, so a track's result is reused for refresh_s of stream time (the track is the newest
//    track of the previous tick's keys::kFaceTracks, read as feedback; -1 without face tracks);
//    this keeps the network descriptor's cost (~40 ms) off most frames. Confidence = the
//    landmarks' confidence.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/face_identity/face_gallery.hpp"

#include <filesystem>
#include <memory>
#include <vector>

namespace dreamsense::face_identity {

struct FaceIdentityAnalyzerOptions {
  std::vector<SensorId> cameras;  // colour streams whose faces may be selected
  std::filesystem::path gallery;  // `dreamsense enroll faces` output (required)
  double refresh_s = 1.0;  // re-identify a track after this much stream time (0: every frame)
  std::filesystem::path face_api_dir;  // empty: vision::default_face_api_model_dir()
  // Privacy (README "Names"): the gallery's name of the person only when set
  // (`--include-names`); by default FaceIdentity::name stays empty and the numeric id identifies.
  bool include_names = false;
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_face_identity_analyzer(
    const FaceIdentityAnalyzerOptions& options);

}  // namespace dreamsense::face_identity
