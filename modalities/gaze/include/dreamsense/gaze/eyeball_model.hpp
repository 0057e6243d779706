#pragma once
// Eye direction from a 3-D eyeball in the head frame (a model-based gaze method: Ishikawa, Baker,
// Matthews & Kanade, "Passive driver gaze tracking with active appearance models", 2004; the
// eyeball centre is rigid with the head, the pupil lies on the eyeball's surface):
//   the pupil pixel's ray, expressed in the head frame by the head pose, is intersected with the
//   eyeball sphere (centre C, radius r); the eye looks along (P - C) / r.
// Compared with D4.2 eq. (4) (eye_angles.hpp), the reference is the whole head pose (51
// landmarks) instead of the two eye-corner landmarks, which move with the lids and the iris, and
// the geometry is exact for any head rotation (no foreshortening model).
// Calibration (fit_eyeball_model): with known eye directions d (targets), the 3-D pupil C + r d
// must lie on the pupil ray (o, u): (I - u u^T)(C + r d - o) = 0, linear in (C, r).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace dreamsense::gaze {

struct EyeballModel {
  cv::Vec3d centre_head_m{0, 0, 0.012};  // head frame (origin between the eyes, z backwards)
  double radius_m = 0.012;               // centre to pupil (an adult eyeball: ~12 mm)
  Status check() const;                  // finite, radius in (3, 25) mm, centre within 10 cm
};

// A pixel's viewing ray in the head frame: origin = camera centre, direction unit.
struct HeadRay {
  cv::Vec3d origin_m, direction;
};
// `camera_from_head` and `head_position_camera_m`: the head pose in this camera.
HeadRay pixel_ray_head(const cv::Point2d& px, const CameraModel& camera,
                       const cv::Matx33d& camera_from_head,
                       const cv::Vec3d& head_position_camera_m);

// Unit eye direction (head frame) of a pupil ray. A ray that misses the sphere (noise) uses the
// ray point nearest the centre; nullopt only for a degenerate ray.
std::optional<cv::Vec3d> eyeball_direction(const HeadRay& pupil_ray, const EyeballModel& eye);

// An eyeball from anatomy, with no calibration (issue 15, README.md "Gaze without known
// targets"): the centre of rotation lies `centre_depth_m` behind the centroid of the eye opening
// (the six lid/canthus landmarks 36-41 or 42-47, in the head frame) along the head's optical
// direction (+z: the eye at rest looks along the head's -z), and the pupil lies `radius_m` from
// it. Defaults from the literature: centre of rotation 13.5 mm behind the corneal apex (Fry &
// Hill 1962), entrance pupil 3.0 mm behind the apex (Le Grand's schematic eye), so centre to
// pupil 10.5 mm; the lid opening's centroid taken 2 mm behind the apex (lids rest on the globe
// at the limbus), so the centre 11.5 mm behind it. Vertically the pupil at rest sits above the
// middle of the opening: upper lid margin 4-4.5 mm above it, lower 5-5.5 mm below (the margin
// reflex distances MRD1/MRD2 of the oculoplastic literature), so the six-point centroid
// (two upper-lid points, two lower-lid points, two canthi near pupil height) lies about 0.5 mm
// below the pupil.
struct AnatomicalEyeOptions {
  double centre_depth_m = 0.0115;
  double radius_m = 0.0105;
  double pupil_above_opening_m = 0.0005;
  Status check() const;
};
EyeballModel anatomical_eyeball(const cv::Vec3d& opening_centroid_head_m,
                                const AnatomicalEyeOptions& options = {});

struct EyeballSample {
  HeadRay pupil_ray;
  cv::Vec3d truth_direction;  // unit, head frame
};
// Least squares for (C, r), refitted once without samples whose residual (distance of the
// predicted pupil from its ray) exceeds 3 x 1.4826 x the median residual. Errors: < 10
// samples, directions that do not vary (degenerate), a result that fails check().
Result<EyeballModel> fit_eyeball_model(const std::vector<EyeballSample>& samples);

}  // namespace dreamsense::gaze
