#pragma once
// The child's face in the demo scene, behind a small interface so that the planar photo face can
// later be replaced by a textured 3-D mesh with moving irises.
//
// Head frame (metres): origin at the midpoint between the eyes; at head pose (0, 0, 0) its axes
// are the world axes, i.e. x towards the child's LEFT (world +x: the child faces the front
// sensor), y down, z towards the back of the head. The face looks along head -z.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/sim/scene_renderer.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <memory>
#include <vector>

namespace dreamsense::sim {

struct FaceState {
  cv::Vec3d position_m{0, 0, 1};  // head-frame origin (eye midpoint) in world
  cv::Matx33d world_from_head = cv::Matx33d::eye();
  cv::Vec3d eye_gaze_dir{0, 0, -1};  // unit, world (a planar face ignores it)
  cv::Vec3d to_world(const cv::Vec3d& head) const { return world_from_head * head + position_m; }
  cv::Vec3d head_gaze_dir() const { return world_from_head * cv::Vec3d(0, 0, -1); }
};

class FaceRenderer {
 public:
  virtual ~FaceRenderer() = default;
  // Eye centres in the head frame (the child's own left and right eye).
  virtual cv::Vec3d left_eye_head() const = 0;
  virtual cv::Vec3d right_eye_head() const = 0;
  // Corners of the facial region (eyebrows to chin, cheek to cheek) in the head frame: its
  // projection gives the truth face box.
  virtual std::vector<cv::Vec3d> face_region_head() const = 0;
  // Composites the face into `target` (z-tested against target.depth, which it updates).
  virtual void render(const CameraModel& camera, const FaceState& state, const Lighting& lighting,
                      RenderTarget& target) const = 0;
};

// The public-domain NASA portrait of Eileen Collins shipped by Debian's python3-skimage
// (skimage/data/astronaut.png, 512x512). Pixel coordinates below are in that image (pixel
// centres at integers). They were found by hand once: the image was cropped to x 190..260,
// y 90..115, magnified 12x with a 2-pixel grid, and the centre of each dark iris was read off.
struct PlanarFaceOptions {
  std::filesystem::path portrait = "/usr/lib/python3/dist-packages/skimage/data/astronaut.png";
  cv::Point2d right_eye_px{203.0, 101.0};  // the subject's right eye (image left)
  cv::Point2d left_eye_px{246.0, 102.0};   // the subject's left eye (image right)
  // Texture crop (hair included) and an elliptic, feathered alpha mask inside it.
  cv::Rect crop_px{140, 8, 170, 196};
  cv::Point2d mask_centre_px{225.0, 97.0};
  cv::Size2d mask_axes_px{75.0, 86.0};
  // Facial region (for the face box): cheek to cheek x 178..272, eyebrows to chin y 80..180.
  cv::Rect2d face_region_px{178.0, 80.0, 94.0, 100.0};
  double face_width_px = 95.0;  // cheek-to-cheek width at eye level, measured on the grid
  double face_width_m = 0.15;   // physical width it is given in the scene
  Status check() const;
};

class PlanarFaceRenderer final : public FaceRenderer {
 public:
  static Result<std::unique_ptr<PlanarFaceRenderer>> create(const PlanarFaceOptions& options);
  cv::Vec3d left_eye_head() const override;
  cv::Vec3d right_eye_head() const override;
  std::vector<cv::Vec3d> face_region_head() const override;
  void render(const CameraModel& camera, const FaceState& state, const Lighting& lighting,
              RenderTarget& target) const override;

  // Head-frame point of a portrait pixel (on the plane z = 0).
  cv::Vec3d head_point(const cv::Point2d& portrait_px) const;
  // Homography from portrait pixels to image pixels of `camera` (zero distortion).
  cv::Matx33d homography(const CameraModel& camera, const FaceState& state) const;
  const PlanarFaceOptions& options() const { return options_; }

 private:
  explicit PlanarFaceRenderer(PlanarFaceOptions options);
  PlanarFaceOptions options_;
  double metres_per_px_ = 0;
  cv::Point2d origin_px_;                // eye midpoint in portrait pixels
  std::vector<cv::Mat> texture_levels_;  // BGRA crop, progressively pre-blurred for minification
};

}  // namespace dreamsense::sim
