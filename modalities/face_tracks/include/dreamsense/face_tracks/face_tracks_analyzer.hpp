#pragma once
// Face tracks analyser: keys::kFaceDetections (+ kSelectedCamera, kHeadPose) -> keys::kFaceTracks.
//
// Per tick, reads kFaceDetections (written earlier in the same tick by face_detection):
//  - no detections entry stamped with this tick (no camera frame): writes nothing;
//  - an absent (null) entry (frames, no face): the tracker is updated with no observation and
//    kFaceTracks lists the confirmed tracks still alive (their last state; nothing is invented),
//    confidence 0;
//  - otherwise every face becomes a 3-D observation (face_observations.hpp: the selected face at
//    the head pose position when kHeadPose of this tick is present, the others from their box
//    size), the tracker is updated, and kFaceTracks lists the confirmed tracks, confidence = the
//    detections' confidence (best face score).
// kFaceTracks is thus written every tick with a kFaceDetections entry (an empty list = no track).
// Contract: reads kFaceDetections and kSelectedCamera, and kHeadPose when options.use_head_pose
// (then the head pose analyser must run first). A face camera without a CameraModel is an error.

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/face_tracks/face_observations.hpp"
#include "dreamsense/face_tracks/face_tracker_3d.hpp"

#include <map>
#include <memory>

namespace dreamsense::face_tracks {

struct FaceTracksAnalyzerOptions {
  std::map<SensorId, CameraModel> cameras;  // intrinsics + camera_from_world per colour stream
  FaceObservationOptions observations;
  FaceTrackerOptions tracker;
  bool use_head_pose = true;  // place the selected face at keys::kHeadPose (reads it)
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_face_tracks_analyzer(
    const FaceTracksAnalyzerOptions& options);

}  // namespace dreamsense::face_tracks
