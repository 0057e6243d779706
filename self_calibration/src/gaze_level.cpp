#include "dreamsense/self_calibration/gaze_level.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/statistics.hpp"
#include "dreamsense/gaze/fixation_yaw.hpp"
#include "dreamsense/gaze/gaze_estimator.hpp"
#include "dreamsense/head_pose/head_pose_estimator.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::self_calibration {
namespace {

constexpr double kDegreesPerRadian = 180.0 / CV_PI;

std::optional<cv::Vec3d> model_centroid(const head_pose::FaceModel3d& m, int from, int to) {
  cv::Vec3d s(0, 0, 0);
  for (int i = from; i <= to; ++i) {
    const auto it = std::find(m.landmark_index.begin(), m.landmark_index.end(), i);
    if (it == m.landmark_index.end()) return std::nullopt;
    const cv::Point3d& p = m.points_m[static_cast<size_t>(it - m.landmark_index.begin())];
    s += cv::Vec3d(p.x, p.y, p.z);
  }
  return s * (1.0 / (to - from + 1));
}

// How squarely a fit's face looks into its camera (1 = facing it).
double frontality(const head_pose::PnpFit& fit) {
  return head_pose::facing_cosine(fit.camera_from_head * cv::Vec3d(0, 0, -1),
                                  -fit.position_camera_m);
}

// The gaze's offset from the target (yaw, pitch; head frame, degrees) at one tick, or nullopt
// when no view gives a head pose and the gaze of at least one eye.
std::optional<cv::Vec2d> fixation_offset(const head_pose::MultiViewLandmarks& tick,
                                         const std::vector<EyeCenters>& pupils,
                                         const head_pose::HeadPoseEstimatorOptions& pose_options,
                                         const gaze::GazeEstimatorOptions& gaze_options,
                                         const cv::Vec3d& target_world_m) {
  std::optional<head_pose::PnpFit> best;
  size_t best_view = 0;
  for (size_t v = 0; v < tick.views.size() && v < pupils.size(); ++v) {
    const auto& view = tick.views[v];
    if (view.camera == nullptr || (!pupils[v].right.found && !pupils[v].left.found)) continue;
    auto fit = head_pose::fit_head_pose(view.landmarks_px, *view.camera, pose_options);
    if (!fit || !*fit) continue;
    if (!best || frontality(**fit) > frontality(*best)) {
      best = **fit;
      best_view = v;
    }
  }
  if (!best) return std::nullopt;
  const auto& first = tick.views[best_view];
  // The single view's own pose, as the gaze analyser measures the eyes in the selected image
  // (HeadPose::image): a gaze from another pose than the analysis's would level another gaze.
  const HeadPose head =
      head_pose::make_head_pose(*best, *first.camera, first.camera->frame, Timestamp());
  FaceLandmarks landmarks;
  landmarks.camera = first.camera->frame;
  landmarks.image_size = first.camera->image_size;
  landmarks.points_px = first.landmarks_px;
  const auto g =
      gaze::estimate_gaze(landmarks, pupils[best_view], head, *first.camera, gaze_options);
  if (!g || !g->both.valid) return std::nullopt;
  cv::Vec3d origin(0, 0, 0);
  int eyes = 0;
  for (const GazeRay* r : {&g->right, &g->left})
    if (r->valid) {
      origin += r->origin_world_m;
      ++eyes;
    }
  origin *= 1.0 / eyes;
  const cv::Matx33d head_from_world = head.world_from_head.t();
  return gaze::head_yaw_pitch_deg(head_from_world * (target_world_m - origin)) -
         gaze::head_yaw_pitch_deg(head_from_world * g->both.direction_world);
}

}  // namespace

Status GazeLevelOptions::check() const {
  if (!(max_yaw_deg > 0 && max_yaw_deg <= 45 && max_pitch_deg > 0 && max_pitch_deg <= 45))
    return make_error(ErrorCode::kInvalidArgument,
                      "GazeLevelOptions: max_yaw_deg and max_pitch_deg must be in (0, 45] (got "
                      "{}, {})",
                      max_yaw_deg, max_pitch_deg);
  if (min_ticks < 1 || rounds < 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "GazeLevelOptions: min_ticks and rounds must be >= 1 (got {}, {})", min_ticks,
                      rounds);
  return ok_status();
}

std::optional<std::pair<gaze::EyeballModel, gaze::EyeballModel>> anatomical_eyeballs(
    const head_pose::FaceModel3d& model, const gaze::AnatomicalEyeOptions& eyes, double shift_x_m) {
  const auto right = model_centroid(model, 36, 41), left = model_centroid(model, 42, 47);
  if (!right || !left) return std::nullopt;
  std::pair out{gaze::anatomical_eyeball(*right, eyes), gaze::anatomical_eyeball(*left, eyes)};
  out.first.centre_head_m[0] += shift_x_m;
  out.second.centre_head_m[0] += shift_x_m;
  return out;
}

head_pose::FaceModel3d pitched(const head_pose::FaceModel3d& model, double pitch_deg) {
  head_pose::FaceModel3d out = model;
  const cv::Matx33d R = rotation_from_ypr_deg(0, pitch_deg, 0);
  for (cv::Point3d& p : out.points_m) {
    const cv::Vec3d q = R * cv::Vec3d(p.x, p.y, p.z);
    p = {q[0], q[1], q[2]};
  }
  return out;
}

GazeLevel level_from_gaze_fixations(const head_pose::FaceModel3d& model,
                                    const std::vector<head_pose::MultiViewLandmarks>& ticks,
                                    const std::vector<std::vector<EyeCenters>>& pupils,
                                    const cv::Vec3d& target_world_m,
                                    const gaze::AnatomicalEyeOptions& eyes,
                                    const GazeLevelOptions& options) {
  GazeLevel out;
  if (!options.enabled || ticks.size() != pupils.size()) return out;
  double c = 0, shift_x = 0, yaw_centre = 0;
  for (int round = 0; round < options.rounds; ++round) {
    head_pose::HeadPoseEstimatorOptions pose_options;
    pose_options.model = pitched(model, c);
    const auto eyeballs = anatomical_eyeballs(pose_options.model, eyes, shift_x);
    if (!eyeballs) return {};
    gaze::GazeEstimatorOptions gaze_options;
    gaze_options.method = gaze::GazeMethod::kEyeball;
    gaze_options.right_eyeball = eyeballs->first;
    gaze_options.left_eyeball = eyeballs->second;
    std::vector<cv::Vec2d> offsets;
    for (size_t i = 0; i < ticks.size(); ++i)
      if (const auto offset =
              fixation_offset(ticks[i], pupils[i], pose_options, gaze_options, target_world_m))
        offsets.push_back(*offset);
    out.ticks_with_gaze = static_cast<int>(offsets.size());
    const bool follow = options.follow_yaw_bias && !options.eye_yaw;
    if (follow && round == 0) {
      // A first centre from the looks within twice the window sideways (a biased gaze on the
      // target may sit beyond the window itself).
      std::vector<double> near_yaw;
      for (const cv::Vec2d& o : offsets)
        if (std::abs(o[0]) <= 2 * options.max_yaw_deg && std::abs(o[1]) <= options.max_pitch_deg)
          near_yaw.push_back(o[0]);
      if (!near_yaw.empty())
        yaw_centre = std::clamp(upper_median(near_yaw), -options.max_yaw_deg, options.max_yaw_deg);
    }
    std::vector<double> facing_yaw, facing_pitch;
    for (const cv::Vec2d& o : offsets)
      if (std::abs(o[0] - yaw_centre) <= options.max_yaw_deg &&
          std::abs(o[1]) <= options.max_pitch_deg) {
        facing_yaw.push_back(o[0]);
        facing_pitch.push_back(o[1]);
      }
    out.fixation_ticks = static_cast<int>(facing_pitch.size());
    if (out.fixation_ticks < options.min_ticks) return out;  // not applied
    // Pitching the frame by c adds c to the target's head-frame pitch while the eye-in-head
    // pitch barely moves, so the offsets grow by about c: c takes away their median.
    c -= upper_median(facing_pitch);
    if (follow)
      yaw_centre = std::clamp(upper_median(facing_yaw), -options.max_yaw_deg, options.max_yaw_deg);
    // Moving both eyeballs by dx along the head's x turns the gaze of an eye looking ahead by
    // -dx / radius (rad) in yaw, so the yaw offsets grow by dx / radius.
    if (options.eye_yaw) shift_x -= eyes.radius_m * upper_median(facing_yaw) / kDegreesPerRadian;
  }
  out.applied = true;
  out.correction_deg = c;
  out.eyeball_shift_x_m = shift_x;
  out.yaw_centre_deg = yaw_centre;
  return out;
}

}  // namespace dreamsense::self_calibration
