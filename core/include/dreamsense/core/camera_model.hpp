#pragma once
// Pinhole camera with distortion and extrinsics, stored as OpenCV FileStorage YAML.
//
// Convention (explicit, used everywhere): extrinsics are camera_from_world, i.e. a world point X
// (metres) maps to camera coordinates Xc = R * X + t; camera axes are OpenCV's (x right, y down,
// z forward). The default world frame is the front depth sensor's optical frame.
//
// File keys: image_width, image_height, camera_matrix (3x3), distortion_coefficients (1xN),
// camera_from_world_R (3x3), camera_from_world_t (3x1, metres), frame (string).

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>

namespace dreamsense {

struct CameraModel {
  std::string frame;  // e.g. "camera_left"
  cv::Size image_size;
  cv::Matx33d K = cv::Matx33d::eye();
  cv::Mat distortion = cv::Mat::zeros(1, 5, CV_64F);
  cv::Matx33d R = cv::Matx33d::eye();  // camera_from_world rotation
  cv::Vec3d t{0, 0, 0};                // camera_from_world translation (m)

  cv::Vec3d to_camera(const cv::Vec3d& world) const { return R * world + t; }
  cv::Vec3d to_world(const cv::Vec3d& cam) const { return R.t() * (cam - t); }
  cv::Vec3d centre_world() const { return -(R.t() * t); }
  // Pixel of a camera-frame point (with distortion); nullopt if behind the camera.
  std::optional<cv::Point2d> project_camera_point(const cv::Vec3d& cam) const;
  std::optional<cv::Point2d> project(const cv::Vec3d& world) const {
    return project_camera_point(to_camera(world));
  }
  // Unit ray in camera coordinates through an (undistorted) pixel.
  cv::Vec3d pixel_ray(const cv::Point2d& px) const;
  // Yaw (deg) of a world direction relative to this camera: 0 when it points straight at the
  // camera, positive when it turns to the camera's -x (the demo truth's and D4.2's head yaw).
  double yaw_towards_deg(const cv::Vec3d& direction_world) const;
  Status check() const;
};

Result<CameraModel> read_camera_model(const std::filesystem::path& path);
Status write_camera_model(const std::filesystem::path& path, const CameraModel& model);
// Writes the keys above into an open FileStorage (for files that add keys of their own).
void write_camera_model_keys(cv::FileStorage& fs, const CameraModel& model);

// Rotation matrix from yaw (about y), pitch (about x), roll (about z), degrees, applied as
// R = Ry(yaw) * Rx(pitch) * Rz(roll).
cv::Matx33d rotation_from_ypr_deg(double yaw, double pitch, double roll);
// Rotation that turns a camera so that its optical axis (z) points from `eye` towards `target`,
// with image "down" (y) as close as possible to world `down`. Returned as camera_from_world R, t.
void look_at(const cv::Vec3d& eye, const cv::Vec3d& target, const cv::Vec3d& down,
             cv::Matx33d& R_cam_from_world, cv::Vec3d& t_cam_from_world);
// A point written as text, e.g. session metadata such as robot_head_m: "x y z" (spaces and/or
// commas); nullopt unless exactly three finite numbers.
std::optional<cv::Vec3d> parse_vec3(std::string text);

}  // namespace dreamsense
