#pragma once
// Eye-in-head angles from the pupil offset, D4.2 eq. (4):
//   theta = atan(gamma   * d * cos(alpha) / L)
//   phi   = atan(epsilon * d * cos(beta)  / H)
// d: distance from the eye-corner midpoint to the pupil centre; alpha: angle between the
// eye-corner line and that offset (beta its complement), so d cos(alpha) and d cos(beta) are the
// offset's components along and across the corner line; L: eye-corner distance; H: eye height.
// gamma and epsilon are fitted from frames with known gaze targets (fit_eye_angle_model);
// DREAM's values were never published. We measure the offset from the pupil's rest position
// (x0, y0: where the pupil sits when the eye looks straight ahead, fitted too; it is not exactly
// the corner midpoint, the corners sit higher than the pupil) and take H = L, because the lid
// aperture (the only other "height" of an eye) changes with vertical gaze and blinks.
//
// Offsets can be measured in the image (DREAM) or in the head's frontal plane: the pixel rays of
// the corners and the pupil are intersected with the plane z = 0 of the head frame given by the
// head pose, which removes the foreshortening of a turned head (ours, the default).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <vector>

namespace dreamsense::gaze {

// Eye-corner and pupil positions of one eye. Corner order does not matter.
struct EyeObservation {
  cv::Point2d corner_a_px;
  cv::Point2d corner_b_px;
  cv::Point2d pupil_px;
};

enum class OffsetPlane {
  kImage,      // D4.2: pixels in the camera image
  kHeadPlane,  // the head's frontal plane (needs the head pose)
};

// Normalised pupil offset (x along the corner line towards the subject's LEFT = head +x, y across
// it, downwards), i.e. (d cos(alpha) / L, d cos(beta) / H) with H = L. nullopt when the corners
// coincide or a ray misses the head plane.
std::optional<cv::Vec2d> pupil_offset_image(const EyeObservation& eye);
std::optional<cv::Vec2d> pupil_offset_head_plane(const EyeObservation& eye,
                                                 const CameraModel& camera,
                                                 const cv::Matx33d& camera_from_head,
                                                 const cv::Vec3d& head_position_camera_m);

// The fitted constants of eq. (4) (+ our offsets), per eye. Angles in degrees, convention of
// dreamsense::GazeRay (positive theta = towards the subject's right, positive phi = down).
struct EyeAngleModel {
  double gamma = 2.0;    // tan(theta) per unit normalised horizontal offset
  double epsilon = 2.0;  // tan(phi) per unit normalised vertical offset
  double rest_x = 0;     // normalised pupil offset when looking straight ahead
  double rest_y = 0;
  Status check() const;  // gamma, epsilon > 0 and finite; rests within +-0.5
};

struct EyeAngles {
  double theta_deg = 0;
  double phi_deg = 0;
};

// Eq. (4): the pupil moves towards the subject's right (head -x) when the eye turns right, so
// theta = atan(-gamma * (x - rest_x)) and phi = atan(epsilon * (y - rest_y)).
EyeAngles eye_angles(const cv::Vec2d& offset, const EyeAngleModel& model);

// Eye-in-head direction (head frame) of the angles, and the angles of a head-frame direction.
cv::Vec3d eye_direction_head(const EyeAngles& a);
EyeAngles angles_of_head_direction(const cv::Vec3d& direction_head);

// One calibration sample: a normalised offset and the true eye-in-head angles.
struct EyeAngleSample {
  cv::Vec2d offset;
  EyeAngles truth;
};

// Least-squares fit of tan(theta) = -gamma * x + gamma * rest_x (a line in x) and of
// tan(phi) = epsilon * y - epsilon * rest_y, with one round of trimming (samples whose residual
// exceeds 3 median absolute deviations are dropped). Needs >= 10 samples with some spread.
Result<EyeAngleModel> fit_eye_angle_model(const std::vector<EyeAngleSample>& samples);

}  // namespace dreamsense::gaze
