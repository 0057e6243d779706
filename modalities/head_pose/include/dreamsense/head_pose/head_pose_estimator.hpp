#pragma once
// Head pose from 2-D landmarks and a 3-D face model by PnP: SQPnP (Terzakis & Lourakis, ECCV
// 2020; global, no initial guess) followed by Levenberg-Marquardt refinement of the reprojection
// error (cv::solvePnPRefineLM), with the camera's intrinsics and distortion; then camera -> world
// through the camera's extrinsics. Method and numbers: modalities/head_pose/README.md.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/head_pose/face_model.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <optional>
#include <vector>

namespace dreamsense::head_pose {

struct HeadPoseEstimatorOptions {
  FaceModel3d model = generic_face_model();
  // Reject fits whose RMS reprojection error exceeds this fraction of the inter-ocular distance
  // in pixels (a wrong landmark fit or a model that does not explain the points).
  double max_rms_per_interocular = 0.15;
  // Reject poses whose face normal points away from the camera by more than this (deg): the
  // camera would not see the face (PnP's mirror solution, a false landmark fit).
  double max_angle_to_camera_deg = 85;
  // Multi-view fit: each view's reprojection residuals are scaled by cos(a)^view_weight_power,
  // a = the angle between the face's direction (at the start pose) and the direction to that
  // camera. dlib's fit of a strongly turned face is pulled towards the frontal mean shape, and
  // with equal weights those views drew the pose's yaw towards themselves: yaw error grew with
  // yaw (slope -0.07...-0.12 on the glasses child, ~0 with one view; README "Multi-view head
  // pose"). 0 = every view counts the same.
  double view_weight_power = 3;
  Status check() const;
};

// The raw PnP fit in one camera's frame.
struct PnpFit {
  cv::Matx33d camera_from_head = cv::Matx33d::eye();
  cv::Vec3d position_camera_m{0, 0, 1};
  double rms_px = 0;
  int points_used = 0;
};

// Fits `options.model` to `landmarks_px` (68 points, pixels of `camera`'s image). nullopt when
// the fit is rejected (see options) or fails; `landmarks_px` of the wrong size is an error.
Result<std::optional<PnpFit>> fit_head_pose(const std::vector<cv::Point2d>& landmarks_px,
                                            const CameraModel& camera,
                                            const HeadPoseEstimatorOptions& options);

// One more calibrated camera's landmarks of the same face at the same tick.
struct PoseView {
  const CameraModel* camera = nullptr;
  const std::vector<cv::Point2d>* landmarks_px = nullptr;  // 68, iBUG order
};
struct MultiViewFit {
  PnpFit fit;          // in the first view's camera frame, as fit_head_pose's
  int views_used = 1;  // the first view and the other views kept
};
// Multi-view head pose (issue 15): one rigid pose of options.model that explains the first
// view and the other views at once (Levenberg-Marquardt on the summed squared reprojection
// errors of all views, started from `start`, the first view's fit_head_pose). With two or more
// cameras the depth and pitch that a single view trades against each other are fixed by the
// baseline. Another view is left out when the start pose reprojects into it beyond
// `view_gate_per_interocular` of its inter-ocular distance (another face, a failed fit), and
// after the fit the worst view beyond options.max_rms_per_interocular is dropped and the fit
// repeated. nullopt when no other view is kept (then the single-view fit stands).
std::optional<MultiViewFit> refine_head_pose_multi_view(const PnpFit& start, const PoseView& first,
                                                        const std::vector<PoseView>& others,
                                                        const HeadPoseEstimatorOptions& options,
                                                        double view_gate_per_interocular = 0.5);
// How squarely a face looks into a camera: the cosine between the face's forward direction
// (head -z, unit) and the direction from the head to the camera, in any one frame (1 = facing
// it).
double facing_cosine(const cv::Vec3d& forward, const cv::Vec3d& head_to_camera);
// Fills the world-frame fields (rotation, position, yaw/pitch/roll, head-gaze ray) of a HeadPose
// from a camera-frame fit and the camera's extrinsics.
HeadPose make_head_pose(const PnpFit& fit, const CameraModel& camera, const SensorId& camera_id,
                        Timestamp frame_stamp);
// Recomputes yaw/pitch/roll and the gaze ray from world_from_head and position_world_m.
void update_derived(HeadPose& pose);

// Inverse of rotation_from_ypr_deg (R = Ry(yaw) Rx(pitch) Rz(roll)): (yaw, pitch, roll) in
// degrees, pitch in [-90, 90].
cv::Vec3d ypr_deg_from_rotation(const cv::Matx33d& R);
// Angle of the rotation A^T B (deg): the angular distance between two orientations.
double rotation_angle_deg(const cv::Matx33d& A, const cv::Matx33d& B);

}  // namespace dreamsense::head_pose
