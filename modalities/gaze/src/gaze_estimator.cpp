#include "dreamsense/gaze/gaze_estimator.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/core/opencv_error.hpp"
#include "dreamsense/gaze/fixation_yaw.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/gaze.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <opencv2/core/persistence.hpp>

#include <cmath>
#include <exception>
#include <fstream>
#include <optional>
#include <utility>
#include <vector>

namespace dreamsense::gaze {
namespace {

// dlib-68 eye corners: the subject's right eye 36 (outer) / 39 (inner), left eye 42 / 45.
constexpr int kRightCorners[2] = {36, 39};
constexpr int kLeftCorners[2] = {42, 45};

std::optional<cv::Vec2d> offset_of(const FaceLandmarks& lm, const int corners[2],
                                   const EyeCenter& pupil, const HeadPose& head,
                                   const CameraModel& camera, OffsetPlane plane) {
  if (!pupil.found || lm.points_px.size() < static_cast<size_t>(kFaceLandmarkCount))
    return std::nullopt;
  const EyeObservation eye{lm.points_px[static_cast<size_t>(corners[0])],
                           lm.points_px[static_cast<size_t>(corners[1])], pupil.center_px};
  if (plane == OffsetPlane::kImage) return pupil_offset_image(eye);
  return pupil_offset_head_plane(eye, camera, head.camera_from_head, head.position_camera_m);
}

GazeRay ray_of(const std::optional<cv::Vec2d>& offset, const EyeAngleModel& model,
               const HeadPose& head, double eye_x_head_m) {
  GazeRay r;
  if (!offset) return r;
  const EyeAngles a = eye_angles(*offset, model);
  r.valid = true;
  r.features = *offset;
  r.theta_deg = a.theta_deg;
  r.phi_deg = a.phi_deg;
  r.direction_world = head.world_from_head * eye_direction_head(a);
  r.origin_world_m = head.position_world_m + head.world_from_head * cv::Vec3d(eye_x_head_m, 0, 0);
  return r;
}

GazeRay eyeball_ray_of(const EyeCenter& pupil, const std::optional<cv::Vec2d>& offset,
                       const EyeballModel& eye, const HeadPose& head, const CameraModel& camera) {
  GazeRay r;
  if (!pupil.found) return r;
  // The (smoothed) world head pose seen from this camera.
  const cv::Matx33d camera_from_head = camera.R * head.world_from_head;
  const cv::Vec3d position_camera = camera.R * head.position_world_m + camera.t;
  const auto d = eyeball_direction(
      pixel_ray_head(pupil.center_px, camera, camera_from_head, position_camera), eye);
  if (!d) return r;
  const EyeAngles a = angles_of_head_direction(*d);
  r.valid = true;
  r.features = offset.value_or(cv::Vec2d(0, 0));
  r.theta_deg = a.theta_deg;
  r.phi_deg = a.phi_deg;
  r.direction_world = head.world_from_head * *d;
  // The ray starts at the pupil on the eyeball (C + r d: the same line as from the centre), so
  // getEyes' 3-D position is the point its pixel centre shows, not the centre of rotation 10-12 mm
  // behind it.
  r.origin_world_m =
      head.position_world_m + head.world_from_head * (eye.centre_head_m + eye.radius_m * *d);
  return r;
}

}  // namespace

Status GazeEstimatorOptions::check() const {
  if (auto s = right_eye.check(); !s) return s;
  if (auto s = left_eye.check(); !s) return s;
  if (auto s = right_eyeball.check(); !s) return s;
  if (auto s = left_eyeball.check(); !s) return s;
  if (!(half_ipd_m > 0 && half_ipd_m < 0.1))
    return make_error(ErrorCode::kInvalidArgument,
                      "GazeEstimatorOptions: half_ipd_m must be in (0, 0.1) m (got {})",
                      half_ipd_m);
  return ok_status();
}

EyeOffsets eye_offsets(const FaceLandmarks& landmarks, const EyeCenters& pupils,
                       const HeadPose& head, const CameraModel& camera, OffsetPlane plane) {
  return {offset_of(landmarks, kRightCorners, pupils.right, head, camera, plane),
          offset_of(landmarks, kLeftCorners, pupils.left, head, camera, plane)};
}

std::optional<EyeGaze> estimate_gaze(const FaceLandmarks& landmarks, const EyeCenters& pupils,
                                     const HeadPose& head, const CameraModel& camera,
                                     const GazeEstimatorOptions& options) {
  const EyeOffsets o = eye_offsets(landmarks, pupils, head, camera, options.plane);
  EyeGaze g;
  g.camera = landmarks.camera;
  g.frame_stamp = landmarks.frame_stamp;
  if (options.method == GazeMethod::kEyeball) {
    g.method = "eyeball_3d";
    g.right = eyeball_ray_of(pupils.right, o.right, options.right_eyeball, head, camera);
    g.left = eyeball_ray_of(pupils.left, o.left, options.left_eyeball, head, camera);
  } else {
    g.method = options.plane == OffsetPlane::kImage ? "d42_eq4_image" : "d42_eq4_head_plane";
    g.right = ray_of(o.right, options.right_eye, head, -options.half_ipd_m);
    g.left = ray_of(o.left, options.left_eye, head, options.half_ipd_m);
  }
  if (!g.right.valid && !g.left.valid) return std::nullopt;
  cv::Vec3d sum(0, 0, 0);
  cv::Vec2d features(0, 0);
  int n = 0;
  for (const GazeRay* r : {&g.right, &g.left}) {
    if (!r->valid) continue;
    sum += r->direction_world;
    features += r->features;
    ++n;
  }
  g.both.valid = true;
  g.both.origin_world_m = head.position_world_m;
  g.both.direction_world = sum / cv::norm(sum);
  g.both.features = features * (1.0 / n);
  const EyeAngles a = angles_of_head_direction(head.world_from_head.t() * g.both.direction_world);
  g.both.theta_deg = a.theta_deg;
  g.both.phi_deg = a.phi_deg;
  return g;
}

namespace {
constexpr const char* kGazeModelFormat = "dreamsense-gaze-model";
void write_eye(cv::FileStorage& fs, const char* name, const EyeAngleModel& m) {
  fs << name << "{"
     << "gamma" << m.gamma << "epsilon" << m.epsilon << "rest_x" << m.rest_x << "rest_y" << m.rest_y
     << "}";
}
void write_eyeball(cv::FileStorage& fs, const char* name, const EyeballModel& m) {
  fs << name << "{"
     << "centre_head_m"
     << std::vector<double>{m.centre_head_m[0], m.centre_head_m[1], m.centre_head_m[2]}
     << "radius_m" << m.radius_m << "}";
}
std::optional<EyeballModel> read_eyeball(const cv::FileNode& n) {
  if (n.empty() || n["radius_m"].empty()) return std::nullopt;
  std::vector<double> c;
  n["centre_head_m"] >> c;
  if (c.size() != 3) return std::nullopt;
  return EyeballModel{{c[0], c[1], c[2]}, static_cast<double>(n["radius_m"])};
}
bool read_eye(const cv::FileNode& n, EyeAngleModel& m) {
  if (n.empty() || n["gamma"].empty() || n["epsilon"].empty()) return false;
  m.gamma = static_cast<double>(n["gamma"]);
  m.epsilon = static_cast<double>(n["epsilon"]);
  m.rest_x = n["rest_x"].empty() ? 0.0 : static_cast<double>(n["rest_x"]);
  m.rest_y = n["rest_y"].empty() ? 0.0 : static_cast<double>(n["rest_y"]);
  return true;
}
}  // namespace

Status write_gaze_model(const std::filesystem::path& path, const GazeModelFile& model) {
  const std::filesystem::path partial = path.string() + ".partial";
  try {
    cv::FileStorage fs(partial.string(), cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened())
      return make_error(ErrorCode::kIoError, "{}: cannot write the gaze model", path.string());
    fs << "format" << kGazeModelFormat << "version" << 1;
    fs << "plane" << (model.plane == OffsetPlane::kImage ? "image" : "head_plane");
    fs << "model_from_head" << cv::Mat(model.model_from_head);
    write_eye(fs, "right_eye", model.right_eye);
    write_eye(fs, "left_eye", model.left_eye);
    if (model.right_eyeball && model.left_eyeball) {
      write_eyeball(fs, "right_eyeball", *model.right_eyeball);
      write_eyeball(fs, "left_eyeball", *model.left_eyeball);
    }
    fs << "samples" << model.samples << "provenance" << model.provenance;
    fs << "fixation_yaw" << static_cast<int>(model.fixation_yaw);
    if (model.fixation_yaw_start_deg != 0)
      fs << "fixation_yaw_start_deg" << model.fixation_yaw_start_deg;
    fs.release();
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kIoError, "{}: {}", path.string(), opencv_reason(e));
  }
  std::error_code ec;
  std::filesystem::rename(partial, path, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", path.string(), ec.message());
  return ok_status();
}

Result<GazeModelFile> read_gaze_model(const std::filesystem::path& path) {
  if (!std::ifstream(path))
    return make_error(ErrorCode::kNotFound, "{}: gaze model not found", path.string());
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(path));
  GazeModelFile m;
  try {
    if (static_cast<std::string>(fs["format"]) != kGazeModelFormat)
      return make_error(ErrorCode::kCorruptData, "{}: not a dreamsense gaze model (format: {})",
                        path.string(), kGazeModelFormat);
    if (static_cast<int>(fs["version"]) != 1)
      return make_error(ErrorCode::kUnsupported, "{}: gaze model version {} (this build reads 1)",
                        path.string(), static_cast<int>(fs["version"]));
    const std::string plane = fs["plane"];
    if (plane != "image" && plane != "head_plane")
      return make_error(ErrorCode::kCorruptData, "{}: unknown plane '{}'", path.string(), plane);
    m.plane = plane == "image" ? OffsetPlane::kImage : OffsetPlane::kHeadPlane;
    if (!read_eye(fs["right_eye"], m.right_eye) || !read_eye(fs["left_eye"], m.left_eye))
      return make_error(ErrorCode::kCorruptData, "{}: right_eye/left_eye need gamma and epsilon",
                        path.string());
    if (!fs["model_from_head"].empty()) {
      cv::Mat R;
      fs["model_from_head"] >> R;
      if (R.rows != 3 || R.cols != 3 || R.type() != CV_64F)
        return make_error(ErrorCode::kCorruptData, "{}: model_from_head must be a 3x3 matrix",
                          path.string());
      m.model_from_head = cv::Matx33d(R);
      if (cv::norm(cv::Mat(m.model_from_head * m.model_from_head.t() - cv::Matx33d::eye())) >
              1e-6 ||
          cv::determinant(m.model_from_head) < 0)
        return make_error(ErrorCode::kCorruptData, "{}: model_from_head is not a rotation",
                          path.string());
    }
    for (auto [name, eyeball] : {std::pair{"right_eyeball", &m.right_eyeball},
                                 std::pair{"left_eyeball", &m.left_eyeball}}) {
      if (fs[name].empty()) continue;
      *eyeball = read_eyeball(fs[name]);
      if (!*eyeball)
        return make_error(ErrorCode::kCorruptData,
                          "{}: {} needs centre_head_m [x, y, z] and radius_m", path.string(), name);
      if (auto s = (*eyeball)->check(); !s)
        return make_error(ErrorCode::kCorruptData, "{}: {}: {}", path.string(), name,
                          s.error().message);
    }
    if (m.right_eyeball.has_value() != m.left_eyeball.has_value())
      return make_error(ErrorCode::kCorruptData, "{}: give both right_eyeball and left_eyeball",
                        path.string());
    m.samples = fs["samples"].empty() ? 0 : static_cast<int>(fs["samples"]);
    m.provenance = fs["provenance"].empty() ? "" : static_cast<std::string>(fs["provenance"]);
    m.fixation_yaw = !fs["fixation_yaw"].empty() && static_cast<int>(fs["fixation_yaw"]) != 0;
    if (!fs["fixation_yaw_start_deg"].empty()) {
      m.fixation_yaw_start_deg = static_cast<double>(fs["fixation_yaw_start_deg"]);
      if (!(std::abs(m.fixation_yaw_start_deg) <= kMaxFixationYawDeg))
        return make_error(ErrorCode::kCorruptData,
                          "{}: fixation_yaw_start_deg must be within +-{} deg (got {})",
                          path.string(), kMaxFixationYawDeg, m.fixation_yaw_start_deg);
    }
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), opencv_reason(e));
  }
  for (const EyeAngleModel* e : {&m.right_eye, &m.left_eye})
    if (auto s = e->check(); !s)
      return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), s.error().message);
  return m;
}

}  // namespace dreamsense::gaze
