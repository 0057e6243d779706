#pragma once
// A tiny ray caster for the demo scene: textured quads, capsules and ellipsoids seen by pinhole
// cameras (distortion is ignored: the demo cameras have zero distortion).
//
// Renders into a RenderTarget: an 8-bit BGR image plus a CV_32F depth buffer holding the camera
// z (metres; +inf = nothing). Primitives are z-tested against the buffer, so a target can be
// pre-filled with a cached static background and then receive the moving primitives.
// Only the pixels inside each primitive's projected bounding box are visited.

#include "dreamsense/core/camera_model.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <variant>
#include <vector>

namespace dreamsense::sim {

// Flat parallelogram origin + a * edge_u + b * edge_v, (a, b) in [0,1]^2. With a texture
// (CV_8UC3 BGR or CV_8UC4 BGRA, alpha < 128 = hole), texel (a * cols - 0.5, b * rows - 0.5)
// is shown (bilinear); otherwise `bgr`.
struct Quad {
  cv::Vec3d origin{0, 0, 0};
  cv::Vec3d edge_u{1, 0, 0};
  cv::Vec3d edge_v{0, 1, 0};
  cv::Vec3f bgr{128, 128, 128};
  std::shared_ptr<const cv::Mat> texture;
};

// Segment a-b swept by a sphere of `radius`.
struct Capsule {
  cv::Vec3d a{0, 0, 0};
  cv::Vec3d b{0, 0, 0};
  double radius = 0.05;
  cv::Vec3f bgr{128, 128, 128};
};

// Ellipsoid with semi-axes `radii` along the columns of `axes` (a rotation, world from local).
struct Ellipsoid {
  cv::Vec3d centre{0, 0, 0};
  cv::Matx33d axes = cv::Matx33d::eye();
  cv::Vec3d radii{0.1, 0.1, 0.1};
  cv::Vec3f bgr{128, 128, 128};
};

using Primitive = std::variant<Quad, Capsule, Ellipsoid>;

struct RenderTarget {
  cv::Mat bgr;    // CV_8UC3
  cv::Mat depth;  // CV_32F camera z in metres, +inf where empty
  // A target of the camera's image size: black, infinitely far.
  static RenderTarget empty(const cv::Size& size);
  RenderTarget clone() const { return {bgr.clone(), depth.clone()}; }
};

struct Lighting {
  cv::Vec3d direction{0.3, 1.0, 0.5};  // direction the light travels (world), normalised inside
  double ambient = 0.55;               // final shade = ambient + diffuse * max(0, n . -dir)
  double diffuse = 0.45;
};

// Ray-casts the primitives into `target` (z-tested). Preconditions: target matches the
// camera's image size; camera has zero distortion (not checked: distortion is ignored).
void render_primitives(const CameraModel& camera, const std::vector<Primitive>& primitives,
                       const Lighting& lighting, RenderTarget& target);

// Shade factor for a surface with world normal n (either side faces the viewer).
double lambert_shade(const cv::Vec3d& normal, const cv::Vec3d& view_dir, const Lighting& lighting);

// Pixel rectangle covering the projection of the given world points, clipped to `size`;
// the full image if any point is behind (or very close to) the camera.
cv::Rect projected_bounds(const CameraModel& camera, const std::vector<cv::Vec3d>& points,
                          const cv::Size& size, int margin = 2);

}  // namespace dreamsense::sim
