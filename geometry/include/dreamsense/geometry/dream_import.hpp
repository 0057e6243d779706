#pragma once
// Import of the original DREAM calibration files (../shared/spec/original-dream.md §4), OpenCV
// FileStorage XML or YAML. Every known defect is reported as a warning (returned and logged) and
// repaired where possible:
//   - *KMatDMat.xml: DistortionCoeffMat that is a 3x3 copy of K -> distortion set to zero;
//     principal point more than 12 % of the image size from its centre (when the image size is
//     given; DREAM's middle camera, cy = 358 on 960 rows).
//   - *RMatTMat.xml: non-orthonormal RMat -> re-orthonormalised (nearest rotation); tMat in mm ->
//     metres. Read as camera_from_world with world = Kinect0 colour (the deduced convention);
//     Kinect1 (top) files carry a warning that their convention is inconsistent.
//   - ObjectFile.xml: DeskWorld_R_mat non-orthonormal -> re-orthonormalised; mm -> metres.

#include "dreamsense/core/status.hpp"
#include "dreamsense/geometry/transform.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::geometry {

struct DreamIntrinsics {
  cv::Matx33d K = cv::Matx33d::eye();
  cv::Mat distortion = cv::Mat::zeros(1, 5, CV_64F);  // 1xN, zero when the file's was unusable
  std::optional<int> device_id;
  std::vector<std::string> warnings;
};
Result<DreamIntrinsics> read_dream_intrinsics(const std::filesystem::path& path,
                                              std::optional<cv::Size> image_size = std::nullopt);

struct DreamExtrinsics {
  RigidTransform camera_from_world;  // metres; world = Kinect0 colour optical frame
  double orthonormality_error = 0;   // of the file's RMat before repair
  std::vector<std::string> warnings;
};
Result<DreamExtrinsics> read_dream_extrinsics(const std::filesystem::path& path);

struct DreamObjectFile {
  RigidTransform desk_from_world;              // DeskWorld_R_mat / DeskWorld_T_mat (m)
  std::optional<cv::Vec3d> point_c_m;          // Point_C, a desk point (DREAM y-up frame, m)
  std::optional<cv::Vec3d> robot_head_m;       // RobotHead
  std::optional<double> gaze_radius_m;         // GazeRadius
  std::optional<cv::Rect> roi;                 // ROIRect (top-Kinect pixels)
  std::optional<double> object_threshold;      // ObjectThreshold
  std::optional<double> face_size;             // FaceSize
  std::optional<bool> use_cam_mutual_gaze;     // UseCamMutualGazeFlag
  std::optional<cv::Vec4d> mutual_gaze_box_m;  // MutualGazeMinX, MaxX, MinY, MaxY (m)
  std::vector<std::string> warnings;
};
Result<DreamObjectFile> read_dream_object_file(const std::filesystem::path& path);

}  // namespace dreamsense::geometry
