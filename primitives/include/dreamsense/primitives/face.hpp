#pragma once
// Primitives answered from the face chain: F1 checkMutualGaze, F5 getEyeGaze, F6 getEyes,
// F7 getFaces, F10 getHead, F11 getHeadGaze, F12 getHeadGaze (plane), F23 trackFace.
//
// getFaces' 3-D positions come from the box size (monocular): distance = fx * face_width_m /
// box_width_px along the ray through the box centre, moved into world with the camera's
// extrinsics. Faces seen by several cameras are one face when their estimates agree within
// same_face_distance_m; the position is the score-weighted mean.

#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/primitives/context.hpp"

#include <map>
#include <optional>
#include <vector>

namespace dreamsense::primitives {

struct FaceGeometryOptions {
  // Physical width that a frontal-cascade box spans. 0.15 m fits an adult face (and the demo's
  // portrait); children's faces are smaller (~0.12-0.13 m): set it per study.
  double face_width_m = 0.15;
  double same_face_distance_m = 0.3;
  Status check() const;
};

// The face family's options block (EvaluatorOptions::families).
struct FacePrimitiveOptions {
  FaceGeometryOptions geometry;  // getFaces' 3-D positions
  // Default query of getHeadGaze (plane), F12: the world plane z = 0 (the front sensor's image
  // plane, where the robot stands).
  PlaneQuery head_gaze_plane;
  // Default query of trackFace (F23): predict the face this far ahead.
  double track_face_dt_s = 0.2;
  Status check() const;
};

// World position of a face from its box in one camera; nullopt for an empty box.
std::optional<cv::Vec3d> face_position_from_box(const CameraModel& camera, const cv::Rect2d& box,
                                                double face_width_m);

// Faces across cameras, best first (the selected camera's face first when there is one).
std::vector<FaceInWorld> associate_faces(const FaceDetections& detections,
                                         const SelectedCamera* selected,
                                         const std::map<SensorId, CameraModel>& cameras,
                                         const FaceGeometryOptions& options);

Answer<MutualGazeValue> check_mutual_gaze(const PrimitiveContext& ctx);
Answer<EyeGazeValue> get_eye_gaze(const PrimitiveContext& ctx, const EyeQuery& query = {});
Answer<EyesValue> get_eyes(const PrimitiveContext& ctx);
Answer<FacesValue> get_faces(const PrimitiveContext& ctx);
Answer<HeadValue> get_head(const PrimitiveContext& ctx);
Answer<HeadGazeValue> get_head_gaze(const PrimitiveContext& ctx);
// The head-gaze ray's intersection with the plane through the query's three points; no_data
// when the ray is parallel to the plane or points away from it.
Answer<HeadGazePlaneValue> get_head_gaze_plane(const PrimitiveContext& ctx,
                                               const PlaneQuery& query);
// trackFace(seed, dt): the face track nearest to the seed, predicted dt ahead (constant
// velocity). Without a query: the newest track (the child's face), dt =
// FacePrimitiveOptions::track_face_dt_s.
Answer<TrackValue> track_face(const PrimitiveContext& ctx,
                              const std::optional<TrackQuery>& query = std::nullopt);

}  // namespace dreamsense::primitives
