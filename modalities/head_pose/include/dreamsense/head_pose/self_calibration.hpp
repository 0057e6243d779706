#pragma once
// The subject's 3-D face model from the session itself, with no truth ("self-calibration",
// issue 15): the colour cameras are calibrated, so the 68 landmarks that two or more cameras see
// at the same tick can be triangulated. Method (README.md, "Self-calibration"):
//  1. per tick, each inner landmark (not the jaw contour, which is a silhouette and differs
//     between cameras) is the least-squares point of its cameras' pixel rays; a camera whose
//     landmarks reproject badly (a wrong landmark fit, or a calibration that disagrees with the
//     others) is dropped when >= 2 others remain, and points that still reproject badly are
//     left out;
//  2. the per-tick shapes are aligned rigidly (Kabsch, no scale: the cameras give metric size)
//     to a running robust mean (per-coordinate median) in a few rounds of generalised
//     Procrustes; ticks whose residual after alignment is large (expression, a bad fit) and
//     single points beyond 3 robust sigmas are rejected;
//  3. the head frame: origin between the eye-opening centroids (the convention of HeadPose); x
//     through the two eye-opening centroids; pitch ("straight ahead") from the generic
//     anthropometric face (FrontalReference): nothing in the session says how the child holds
//     the head when looking "straight", so this is a prior, and its error is the calibration's
//     remaining head-pose bias (README.md).
//  Quality: the median per-tick RMS residual (mm) after alignment, ticks used, and a status that
//  says why it did not converge (no tick with two cameras, too few ticks, inconsistent cameras).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/head_pose/face_model.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace dreamsense::head_pose {

// 68 landmarks of the face in one calibrated camera image.
struct CameraLandmarks {
  const CameraModel* camera = nullptr;
  std::vector<cv::Point2d> landmarks_px;  // 68, iBUG order; non-finite = missing
};
// Every camera's landmarks at one tick.
struct MultiViewLandmarks {
  int64_t stamp_ns = 0;
  std::vector<CameraLandmarks> views;
};

struct FaceTriangulationOptions {
  // Landmarks triangulated (iBUG indices); default: the 51 inner points (17-67).
  std::vector<int> landmark_index = generic_face_model(false).landmark_index;
  // A camera whose RMS reprojection error exceeds this fraction of its inter-ocular distance in
  // pixels is dropped (when >= 2 other cameras remain); a point whose error exceeds it in any
  // camera left is missing.
  double max_reprojection_per_interocular = 0.06;
  // Two rays closer in angle than this do not determine depth.
  double min_ray_angle_deg = 8;
  Status check() const;
};

struct TriangulatedFace {
  std::vector<cv::Vec3d> points_world;  // per landmark_index entry; NaN = missing
  int cameras = 0;                      // cameras kept
  int cameras_dropped = 0;              // cameras dropped as disagreeing with the others
  // With >= 3 cameras kept: relative spread of the eye distance triangulated by each camera pair
  // ((max - min) / median); 0 otherwise.
  double pair_scale_spread = 0;
  // With >= 3 cameras: the eye distance (metres) each camera pair triangulates on its own.
  struct PairInterocular {
    const CameraModel* a = nullptr;  // a < b (pointer order)
    const CameraModel* b = nullptr;
    double interocular_m = 0;
  };
  std::vector<PairInterocular> pair_interocular;
  int points = 0;     // finite points
  double rms_px = 0;  // RMS reprojection error over kept cameras and points
};

// nullopt when fewer than 2 cameras have landmarks, the cameras left still disagree (a camera's
// RMS reprojection beyond the limit), or fewer than 4 points triangulate. Views
// without a camera or with a landmark count other than 68 are ignored.
std::optional<TriangulatedFace> triangulate_face(const MultiViewLandmarks& frame,
                                                 const FaceTriangulationOptions& options = {});

enum class SelfCalibrationStatus {
  kConverged,
  kNoMultiView,   // no tick where two cameras saw the face (one camera, or never facing two)
  kTooFewFrames,  // some, but fewer than min_frames usable ticks
  kInconsistent,  // ticks disagree (calibrations that disagree, landmark fits that fail)
};
const char* to_string(SelfCalibrationStatus s);

// How "straight ahead" (the head frame's pitch) is chosen for the self-calibrated shape; x is
// always the axis through the two eye-opening centroids (the transverse axis of the head).
enum class FrontalReference {
  kGenericFace3d,   // pitch of the similarity alignment with the generic 3-D face
  kMeanShape2d,     // the pitch from which the shape looks most like the mean frontal face photo
                    // (dlib's mean 68-point shape, the generic model's x, y)
  kMeanWorldPitch,  // kMeanShape2d, then the head's median pitch relative to the calibrated
                    // world's horizontal over the ticks is taken as level (fails when the child
                    // looks down at the table, or up, for most of the self-calibration stretch)
};

// How "upright" (the head frame's roll about its forward axis) is chosen.
enum class UprightReference {
  kEyeLine,        // x through the two eye-opening centroids: a face whose eyes are not level
                   // (a tilted portrait, an asymmetric face) gets that tilt as a roll bias
  kMeanWorldRoll,  // the head's median roll relative to the calibrated world's vertical over the
                   // self-calibration ticks is zero: people hold their heads upright on average
                   // (fails when the child keeps the head tilted during those seconds, e.g.
                   // lying on one side, or when the world frame's y axis is not vertical)
};

struct SelfCalibrationOptions {
  FaceTriangulationOptions triangulation;
  FrontalReference frontal = FrontalReference::kMeanWorldPitch;
  UprightReference upright = UprightReference::kMeanWorldRoll;
  // kMeanWorldRoll is used only when the rolls of the used ticks (eye-line frame) have a robust
  // spread (1.4826 x median absolute deviation) of at most this; otherwise the eye line is kept
  // (a head rolling all over says little about its upright; SelfCalibration::upright says so).
  double max_roll_spread_deg = 15;
  int min_points_per_frame = 40;  // triangulated points a tick needs to be used
  int min_frames = 12;            // usable ticks needed to converge
  int rounds = 4;                 // generalised Procrustes rounds
  // A tick whose RMS residual after rigid alignment exceeds max(this, 3 robust sigmas over the
  // ticks) is rejected.
  double max_frame_rms_m = 0.004;
  // The calibration converges only when the median tick residual is at most this.
  double max_median_rms_m = 0.003;
  // Plausible inter-ocular distances (eye-opening centroids) of a child or an adult; outside:
  // inconsistent (a calibration in other units, a wrong baseline).
  double min_interocular_m = 0.040, max_interocular_m = 0.080;
  // Ticks with three or more cameras: when the camera pairs' eye distances disagree by more than
  // this, a calibration is off along a baseline (which two-view triangulation turns into a wrong
  // scale with no reprojection error): inconsistent. With only two cameras such an error cannot
  // be seen. The disagreement is that of each pair's median eye distance over the ticks
  // ((max - min) / median of the pairs' medians): a calibration error is the same at every tick,
  // landmark noise is not (the per-tick range of three noisy pairs reached 9 % on a sound demo
  // session with a child wearing glasses). Pairs with fewer than min_pair_ticks ticks do not
  // count.
  double max_pair_scale_spread = 0.08;
  int min_pair_ticks = 5;
  // Level from fixations (with kMeanWorldPitch): a point in the world frame that the child faces
  // with the head from time to time during the self-calibration stretch, e.g. the robot's head
  // (session metadata robot_head_m), the social partner of robot-assisted therapy. After the
  // world-level pitch, the ticks whose head direction passes within fixation_max_yaw_deg
  // (sideways) and fixation_max_pitch_deg (up/down) of the target are taken as facing it, and
  // the median pitch offset between head direction and target over them is made zero (4 rounds,
  // the selection following the correction). It replaces the world-level assumption "the child
  // holds the head level on average", which the gaze at toys on the table biases (demo children
  // 1 and 2: 4-7 deg). Needs min_fixation_ticks such ticks; otherwise the world level stays
  // (SelfCalibration::level says which).
  std::optional<cv::Vec3d> fixation_target_world_m;
  double fixation_max_yaw_deg = 10;
  double fixation_max_pitch_deg = 12;
  int min_fixation_ticks = 8;
  Status check() const;
};

struct SelfCalibration {
  SelfCalibrationStatus status = SelfCalibrationStatus::kNoMultiView;
  std::string reason;                   // one line: what was found, and why it did not converge
  FaceModel3d model;                    // head frame; empty points unless converged
  int frames_offered = 0;               // ticks given
  int frames_multi_view = 0;            // ticks with landmarks in two or more cameras
  int frames_triangulated = 0;          // of them, triangulated consistently
  int views_dropped = 0;                // camera views dropped in triangulated ticks
  double median_pair_scale_spread = 0;  // TriangulatedFace::pair_scale_spread, median over ticks
  // Relative spread of the camera pairs' median eye distances (what max_pair_scale_spread bounds)
  double pair_median_scale_spread = 0;
  int frames_used = 0;      // after outlier rejection
  double median_rms_m = 0;  // median per-tick residual after alignment
  double median_reprojection_px = 0;
  double interocular_m = 0;  // between the eye-opening centroids
  // Upright: "eye_line" or "mean_world_roll"; the roll added to the eye-line frame (deg; the
  // median roll of the eye-line head frame over the used ticks), and the robust spread of the
  // ticks' rolls (deg).
  std::string upright = "eye_line";
  double upright_roll_correction_deg = 0;
  double roll_spread_deg = 0;
  // FrontalReference::kMeanWorldPitch: the pitch added to the kMeanShape2d frame (deg), and the
  // robust spread of the ticks' pitches (deg).
  double level_pitch_correction_deg = 0;
  double pitch_spread_deg = 0;
  // How "level" (pitch 0) was chosen: "generic_face", "mean_shape", "world_pitch" or
  // "target_fixations" (then fixation_ticks ticks faced the target and fixation_correction_deg
  // was added after the world-level pitch; both are also set when there were too few).
  std::string level = "generic_face";
  int fixation_ticks = 0;
  double fixation_correction_deg = 0;
  bool converged() const { return status == SelfCalibrationStatus::kConverged; }
};

SelfCalibration self_calibrate_face(const std::vector<MultiViewLandmarks>& frames,
                                    const SelfCalibrationOptions& options = {});

// Rigid (optionally similarity) alignment of corresponding points: dst ~ s R src + t (Umeyama,
// IEEE PAMI 1991). Returns false when fewer than 3 pairs or degenerate.
struct RigidTransform {
  cv::Matx33d R = cv::Matx33d::eye();
  cv::Vec3d t{0, 0, 0};
  double scale = 1;
  cv::Vec3d apply(const cv::Vec3d& x) const { return scale * (R * x) + t; }
};
bool align_points(const std::vector<cv::Vec3d>& src, const std::vector<cv::Vec3d>& dst,
                  bool with_scale, RigidTransform& out);

}  // namespace dreamsense::head_pose
