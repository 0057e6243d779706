#pragma once
// The child's face in the demo scene, behind a small interface: a flat photo
// (PlanarFaceRenderer) or a textured 3-D mesh with ray-cast eyeballs whose irises follow the
// eye gaze (MeshFaceRenderer, the demo's default). Method and numbers: sim/README.md.
//
// Head frame (metres): origin at the midpoint between the eyes; at head pose (0, 0, 0) its axes
// are the world axes, i.e. x towards the child's LEFT (world +x: the child faces the front
// sensor), y down, z towards the back of the head. The face looks along head -z.

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/sim/scene_renderer.hpp"

#include <opencv2/core.hpp>

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

namespace dreamsense::sim {

struct FaceState {
  cv::Vec3d position_m{0, 0, 1};  // head-frame origin (eye midpoint) in world
  cv::Matx33d world_from_head = cv::Matx33d::eye();
  // Where the eyes look. With `gaze_target_m` both eyes fixate that world point (they
  // converge); without it both look along `eye_gaze_dir` (unit, world). A planar face ignores
  // both (its eyes are painted: eye gaze = head gaze).
  cv::Vec3d eye_gaze_dir{0, 0, -1};
  std::optional<cv::Vec3d> gaze_target_m;
  double eyelid_closure = 0;  // 0 = open .. 1 = closed (blink)
  cv::Vec3d to_world(const cv::Vec3d& head) const { return world_from_head * head + position_m; }
  cv::Vec3d head_gaze_dir() const { return world_from_head * cv::Vec3d(0, 0, -1); }
};

// One eye in world coordinates.
struct EyeState {
  cv::Vec3d centre_m;  // eyeball (rotation) centre
  cv::Vec3d pupil_m;   // pupil centre: where the gaze ray leaves the eyeball
  cv::Vec3d gaze_dir;  // unit; the gaze ray is centre_m + s * gaze_dir
};
struct EyesState {
  EyeState left, right;  // the child's own left / right eye
  bool open = true;      // eyelid closure < 0.5
  // Mean of the two gaze directions (normalised); the eye gaze ray starts at eye_midpoint().
  cv::Vec3d gaze_dir() const;
  cv::Vec3d eye_midpoint() const { return 0.5 * (left.pupil_m + right.pupil_m); }
};

class FaceRenderer {
 public:
  virtual ~FaceRenderer() = default;
  // Eye centres in the head frame (the child's own left and right eye) at rest: for the mesh
  // the pupil centres when looking straight ahead (head -z).
  virtual cv::Vec3d left_eye_head() const = 0;
  virtual cv::Vec3d right_eye_head() const = 0;
  // Points bounding the facial region (eyebrows to chin, cheek to cheek) in the head frame: the
  // bounding box of their projection is the truth face box.
  virtual std::vector<cv::Vec3d> face_region_head() const = 0;
  // The eyes for a state. Default (painted eyes): the rest eye points, both looking along the
  // head gaze, open.
  virtual EyesState eyes(const FaceState& state) const;
  // The back of the head (hair), drawn by the scene as an ellipsoid behind the face: centre and
  // semi-axes along the head axes (head frame), colour. Default: the planar photo's.
  struct BackOfHead {
    cv::Vec3d centre_head{0, 0, 0.10};
    cv::Vec3d radii_m{0.085, 0.105, 0.095};
    cv::Vec3f bgr{70, 105, 130};
  };
  virtual BackOfHead back_of_head() const { return {}; }
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

// ---------------------------------------------------------------- textured 3-D mesh

// data/demo/astronaut_landmarks.yaml of the dreamsense source tree (the path is compiled in).
std::filesystem::path default_portrait_landmarks_path();
// The `landmarks_px` matrix (68 x 2, portrait pixels, iBUG 300-W order) of a landmark file.
Result<std::vector<cv::Point2d>> read_portrait_landmarks(const std::filesystem::path& path);

// The analytic head surface that gives each mesh vertex its depth. It is deliberately NOT the
// head-pose estimator's 3-D face model (modalities/head_pose): the estimator must be tested on a
// shape it does not know. Head frame, metres; the surface is a height field z(x, y) over the
// frontal (portrait) plane, z = depth behind the rest pupils (which are at z = 0):
//   face   = ellipsoid F (semi-axes face_a/b/c, centre (0, face_centre_y, zF), zF such that F
//            passes through the rest pupils) + relief (Gaussian bumps placed on the landmarks:
//            nose ridge from nasion to tip, brow ridges, eye sockets, cheekbones, lips, chin);
//   hair   = ellipsoid H whose frontal outline is the texture mask ellipse shrunk by
//            hair_inset_px (semi-axis hair_c, centre depth hair_centre_z): cranium + hair;
//   z      = min(face, hair) above the jaw line (landmarks 0-16 and beside it), hair below it
//            (where the texture is transparent: the scene draws the neck), hair_centre_z (H's
//            silhouette) outside H's outline.
// F is a flat, wide (child's) face: nose tip ~2.2 cm in front of the pupils, cheek contour
// ~1.4 cm behind them. A deeper F (c = 0.09 m, a = 0.082 m) made the Haar frontal face detector
// lose the face beyond ~35 deg of yaw (numbers in sim/README.md).
struct HeadShape {
  double face_a_m = 0.11, face_b_m = 0.16, face_c_m = 0.07, face_centre_y_m = 0.03;
  double hair_inset_px = 2.0, hair_c_m = 0.10, hair_centre_z_m = 0.115;
  // Relief heights (towards the viewer unless noted), metres.
  double nasion_m = 0.006, nose_tip_m = 0.017, brow_m = 0.004, eye_socket_m = 0.003,
         cheekbone_m = 0.004, lips_m = 0.004, chin_m = 0.006;  // eye_socket: away from viewer
};

struct MeshFaceOptions {
  std::filesystem::path portrait = "/usr/lib/python3/dist-packages/skimage/data/astronaut.png";
  std::filesystem::path landmarks = default_portrait_landmarks_path();
  // Texture crop and feathered elliptic alpha mask: as PlanarFaceOptions (hair included).
  cv::Rect crop_px{140, 8, 170, 196};
  cv::Point2d mask_centre_px{225.0, 97.0};
  cv::Size2d mask_axes_px{75.0, 86.0};
  double face_width_px = 95.0;   // cheek-to-cheek width at eye level in the portrait
  double face_width_m = 0.15;    // physical width it is given in the scene
  double grid_spacing_px = 8.0;  // interior mesh vertices between the landmarks
  HeadShape shape;
  // Eyes: a sphere per eye, centre eyeball_radius behind the eye opening's centroid (so the rest
  // pupil is at z = 0), seen through the opening (landmarks 36-41 / 42-47, scaled about their
  // centroid by eye_opening_scale to reach the lash line).
  double eyeball_radius_m = 0.012;
  double iris_radius_m = 0.006;
  double pupil_radius_m = 0.0022;
  cv::Vec3d iris_bgr{32, 58, 98};  // brown
  cv::Vec3d sclera_bgr{170, 178, 196};
  cv::Vec3d caruncle_bgr{112, 122, 158};   // seen in the eye corners, beside the eyeball
  cv::Vec2d eye_opening_scale{1.0, 1.12};  // horizontal, vertical
  double max_eye_yaw_deg = 35, max_eye_pitch_deg = 30;  // anatomical clamp per eye (head frame)
  Status check() const;
};

// The portrait as a textured triangle mesh over its 68 landmarks (plus interior grid, jaw, hair
// outline and outer ring vertices; cv::Subdiv2D Delaunay once at create()), each vertex lifted to
// the HeadShape surface, rasterised per triangle (perspective-correct barycentrics, back-face
// culling, z-buffer against target.depth, pre-blurred texture level chosen per triangle from its
// magnification, Gouraud-interpolated Lambert shading); then, inside each visible eye opening, a
// ray-cast eyeball (sclera, radially textured iris, pupil, soft limbus, lid shadow, specular
// highlight) whose pupil is where the eye's gaze ray leaves the sphere. Blinks lower the upper
// lid over the opening. render() is const and thread-safe.
class MeshFaceRenderer final : public FaceRenderer {
 public:
  static Result<std::unique_ptr<MeshFaceRenderer>> create(const MeshFaceOptions& options);
  cv::Vec3d left_eye_head() const override;
  cv::Vec3d right_eye_head() const override;
  std::vector<cv::Vec3d> face_region_head() const override;
  EyesState eyes(const FaceState& state) const override;
  // Hair ellipsoid H, 3 % smaller across so that it stays behind the mesh, in the photo's mean
  // hair colour.
  BackOfHead back_of_head() const override;
  void render(const CameraModel& camera, const FaceState& state, const Lighting& lighting,
              RenderTarget& target) const override;

  // Head-frame point of the head surface under a portrait pixel (the analytic surface; the mesh
  // interpolates it between vertices).
  cv::Vec3d surface_point(const cv::Point2d& portrait_px) const;
  // Mesh: vertex i < 68 is landmark i; texture coordinates are portrait pixels.
  const std::vector<cv::Vec3d>& vertices_head() const { return vertices_head_; }
  const std::vector<cv::Point2d>& vertices_px() const { return vertices_px_; }
  const std::vector<cv::Vec3i>& triangles() const { return triangles_; }
  const std::vector<cv::Point2d>& landmarks_px() const { return landmarks_px_; }
  // Eyeball centres in the head frame.
  cv::Vec3d left_eyeball_head() const { return eyeball_head_[1]; }
  cv::Vec3d right_eyeball_head() const { return eyeball_head_[0]; }
  const MeshFaceOptions& options() const { return options_; }

 private:
  explicit MeshFaceRenderer(MeshFaceOptions options);
  cv::Point2d head_xy(const cv::Point2d& px) const;  // frontal-plane coordinates (metres)
  double surface_z(double x, double y) const;
  bool below_jaw(double x, double y) const;
  cv::Mat subject_mask(const cv::Mat& portrait) const;
  void build_mesh();
  void render_eye(int eye, const CameraModel& camera, const FaceState& state, const EyeState& es,
                  const Lighting& lighting, const cv::Rect& roi, const cv::Mat& owner,
                  RenderTarget& target) const;

  MeshFaceOptions options_;
  double metres_per_px_ = 0;
  cv::Point2d origin_px_;  // eye midpoint (centroid of the two eye openings) in portrait pixels
  std::vector<cv::Point2d> landmarks_px_;
  std::vector<cv::Vec3d> vertices_head_, normals_head_;
  std::vector<cv::Point2d> vertices_px_;
  std::vector<cv::Vec3i> triangles_;
  std::vector<cv::Matx22d> texture_edges_inv_;      // per triangle: inverse of its texture edges
  std::array<std::vector<uchar>, 2> eye_triangle_;  // per triangle: part of eye 0 (right) / 1
  std::array<cv::Vec3d, 2> eyeball_head_;           // 0 = right eye (36-41), 1 = left (42-47)
  std::array<std::vector<cv::Point2d>, 2> eye_opening_px_;  // scaled openings (6 points)
  std::array<cv::Vec3d, 2> lid_skin_bgr_;
  cv::Vec3f hair_bgr_{70, 105, 130};
  std::vector<cv::Mat> texture_levels_;  // BGRA crop, progressively pre-blurred
  // Surface anchors (head frame, metres) taken from the landmarks.
  std::vector<cv::Point2d> contour_xy_;  // landmarks 0-16 (x increasing)
  std::array<std::vector<cv::Point2d>, 2> brow_xy_;
  cv::Point2d nasion_xy_, nose_tip_xy_, subnasale_xy_, mouth_xy_, chin_xy_;
  double alar_half_width_m_ = 0.015;
  cv::Point2d hair_centre_xy_;
  cv::Size2d hair_axes_m_;
  double face_centre_z_m_ = 0;
};

}  // namespace dreamsense::sim
