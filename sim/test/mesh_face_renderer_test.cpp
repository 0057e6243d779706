#include "dreamsense/sim/demo_session.hpp"
#include "dreamsense/sim/face_renderer.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <unistd.h>

namespace dreamsense::sim {
namespace {

namespace fs = std::filesystem;

bool renderer_media_available() {
  const MeshFaceOptions o;
  return fs::exists(o.portrait) && fs::exists(o.landmarks);
}

const MeshFaceRenderer* shared_face() {
  static std::unique_ptr<MeshFaceRenderer> face = [] {
    std::unique_ptr<MeshFaceRenderer> f;
    if (!renderer_media_available()) return f;
    auto r = MeshFaceRenderer::create({});
    if (r) f = std::move(*r);
    return f;
  }();
  return face.get();
}

#define REQUIRE_FACE()                          \
  const MeshFaceRenderer* face = shared_face(); \
  if (!face) GTEST_SKIP() << "astronaut.png (python3-skimage) or the landmark file missing"

CameraModel camera(int index) { return make_demo_cameras()[static_cast<size_t>(index)]; }

FaceState pose(double yaw, double pitch, double roll) {
  FaceState s;
  s.position_m = {0.0, -0.05, 1.1};
  s.world_from_head = rotation_from_ypr_deg(yaw, pitch, roll);
  s.eye_gaze_dir = s.head_gaze_dir();
  return s;
}

Lighting flat_light() {
  Lighting l;
  l.ambient = 1.0;
  l.diffuse = 0.0;
  return l;
}

// Eye-in-head yaw/pitch (degrees) to a world direction.
cv::Vec3d eye_direction(const FaceState& s, double yaw_deg, double pitch_deg) {
  const double y = yaw_deg * CV_PI / 180, p = pitch_deg * CV_PI / 180;
  return s.world_from_head *
         cv::Vec3d(-std::sin(y) * std::cos(p), std::sin(p), -std::cos(y) * std::cos(p));
}

TEST(MeshFace, MeshHasTheLandmarksAsItsFirstVerticesAndAPlausibleShape) {
  REQUIRE_FACE();
  ASSERT_GE(face->vertices_head().size(), 200u);
  EXPECT_GE(face->triangles().size(), 300u);
  for (int i = 0; i < 68; ++i)
    EXPECT_EQ(face->vertices_px()[static_cast<size_t>(i)],
              face->landmarks_px()[static_cast<size_t>(i)]);
  const auto& v = face->vertices_head();
  // Rest pupils at z = 0, ~70 mm apart, the child's left eye on +x; origin between them.
  const cv::Vec3d l = face->left_eye_head(), r = face->right_eye_head();
  EXPECT_GT(l[0], r[0]);
  EXPECT_NEAR(cv::norm(l - r), 0.068, 0.01);
  EXPECT_NEAR((0.5 * (l + r))[0], 0.0, 1e-12);
  EXPECT_NEAR(l[2], 0.0, 1e-12);
  // Relief: the nose tip (30) in front of the eyes, the nasion (27) too, the jaw corners (0, 16)
  // well behind; the face is ~0.15 m wide.
  EXPECT_LT(v[30][2], -0.02);
  EXPECT_LT(v[27][2], v[30][2] + 0.02);
  EXPECT_GT(v[0][2], 0.01);
  EXPECT_GT(v[16][2], 0.01);
  EXPECT_NEAR(v[16][0] - v[0][0], 0.146, 0.01);
}

TEST(MeshFace, LandmarkVerticesLandWhereTheRendererDrewTheirTexturePoint) {
  REQUIRE_FACE();
  // A synthetic portrait whose colour encodes the texture coordinate: blue = 2 (x - 170), green
  // = 2 (y - 80), red 255 (warm: kept by the renderer's subject mask), exact integers (linear ramps
  // survive bilinear sampling, the pre-blurred levels and the piecewise-affine warp unchanged;
  // valid for x in [170, 297], y in [80, 207], which holds every landmark). Read back at the
  // projection of a landmark vertex, the rendered colour must decode to that landmark's portrait
  // position.
  cv::Mat img(512, 512, CV_8UC3);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x)
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(2 * (x - 170)),
                                          cv::saturate_cast<uchar>(2 * (y - 80)), 255);
  const fs::path path =
      fs::temp_directory_path() / ("ds_mesh_ramp_" + std::to_string(::getpid()) + ".png");
  ASSERT_TRUE(cv::imwrite(path.string(), img));
  MeshFaceOptions o;
  o.portrait = path;
  auto synthetic = MeshFaceRenderer::create(o);
  fs::remove(path);
  ASSERT_TRUE(synthetic) << synthetic.error().to_string();
  const MeshFaceRenderer& m = **synthetic;
  int checked = 0;
  double worst = 0;
  for (int cam_index : {1, 0, 2, 3}) {
    const CameraModel cam = camera(cam_index);
    for (const auto& [yaw, pitch, roll] :
         std::vector<std::array<double, 3>>{{0, 0, 0}, {25, 10, 5}, {-30, -8, -4}, {10, 18, 0}}) {
      const FaceState st = pose(yaw, pitch, roll);
      RenderTarget target = RenderTarget::empty(cam.image_size);
      m.render(cam, st, flat_light(), target);
      // Again on white: where the two differ the face is partly transparent (feathered edges).
      RenderTarget white = RenderTarget::empty(cam.image_size);
      white.bgr.setTo(cv::Scalar::all(255));
      m.render(cam, st, flat_light(), white);
      cv::Mat rendered;
      target.bgr.convertTo(rendered, CV_32FC3);
      for (int k = 0; k < 68; ++k) {
        if (k >= 36 && k < 48) continue;  // eyes: the eyeballs are drawn there
        const cv::Vec3d w = st.to_world(m.vertices_head()[static_cast<size_t>(k)]);
        const auto p = cam.project(w);
        ASSERT_TRUE(p.has_value());
        const int u0 = static_cast<int>(std::floor(p->x)), v0 = static_cast<int>(std::floor(p->y));
        // Only where the vertex is visible (not behind the nose or the cheek).
        bool visible = true;
        for (int dv = 0; dv <= 1; ++dv)
          for (int du = 0; du <= 1; ++du)
            visible =
                visible &&
                std::abs(target.depth.at<float>(v0 + dv, u0 + du) - cam.to_camera(w)[2]) < 0.003 &&
                target.bgr.at<cv::Vec3b>(v0 + dv, u0 + du) ==
                    white.bgr.at<cv::Vec3b>(v0 + dv, u0 + du);
        if (!visible) continue;
        cv::Mat sample;
        cv::getRectSubPix(rendered, cv::Size(1, 1), cv::Point2f(*p), sample);
        const cv::Vec3f c = sample.at<cv::Vec3f>(0, 0);
        const cv::Point2d decoded(c[0] / 2 + 170, c[1] / 2 + 80);
        // Error in image pixels: where the mesh maps the decoded texture point (through the
        // landmark's adjacent triangle that contains it in the portrait), to the vertex.
        double err = 1e9;
        for (const cv::Vec3i& t : m.triangles()) {
          if (t[0] != k && t[1] != k && t[2] != k) continue;
          cv::Point2d tp[3], ip[3];
          for (int i = 0; i < 3; ++i) {
            tp[i] = m.vertices_px()[static_cast<size_t>(t[i])];
            ip[i] = *cam.project(st.to_world(m.vertices_head()[static_cast<size_t>(t[i])]));
          }
          const cv::Matx22d A(tp[1].x - tp[0].x, tp[2].x - tp[0].x, tp[1].y - tp[0].y,
                              tp[2].y - tp[0].y);
          const cv::Vec2d b = A.inv() * cv::Vec2d(decoded.x - tp[0].x, decoded.y - tp[0].y);
          const double slack = -0.25;  // allow slightly outside (quantisation)
          if (b[0] < slack || b[1] < slack || b[0] + b[1] > 1 - slack) continue;
          const cv::Point2d q = ip[0] + b[0] * (ip[1] - ip[0]) + b[1] * (ip[2] - ip[0]);
          err = std::min(err, cv::norm(q - *p));
        }
        EXPECT_LT(err, 1.0) << "landmark " << k << " " << cam.frame << " head " << yaw << ","
                            << pitch << "," << roll << " decoded " << decoded;
        worst = std::max(worst, err);
        ++checked;
      }
    }
  }
  std::printf("[mesh] %d landmark vertices checked, worst %.2f px\n", checked, worst);
  EXPECT_GT(checked, 400);
}

// Centre of the darkest blob (the pupil) near `guess`: pixels darker than the minimum + 20 grey
// levels, connected to the minimum, weighted by their darkness.
std::optional<cv::Point2d> darkest_blob(const cv::Mat& grey, const cv::Rect& window) {
  cv::Mat w = grey(window);
  double lo = 0;
  cv::Point at;
  cv::minMaxLoc(w, &lo, nullptr, &at);
  cv::Mat mask = w < lo + 20;
  cv::Mat labels;
  cv::connectedComponents(mask, labels, 8);
  const int id = labels.at<int>(at);
  double sw = 0, sx = 0, sy = 0;
  for (int v = 0; v < w.rows; ++v)
    for (int u = 0; u < w.cols; ++u)
      if (labels.at<int>(v, u) == id) {
        const double k = lo + 20 - w.at<uchar>(v, u);
        sw += k, sx += k * u, sy += k * v;
      }
  if (sw <= 0) return std::nullopt;
  return cv::Point2d(window.x + sx / sw, window.y + sy / sw);
}

TEST(MeshFace, PupilTruthPixelIsTheDarkestBlobCentre) {
  REQUIRE_FACE();
  int checked = 0;
  for (int cam_index : {1, 0, 2}) {
    const CameraModel cam = camera(cam_index);
    for (const auto& [yaw, pitch] :
         std::vector<std::array<double, 2>>{{0, 0}, {20, 5}, {-15, -5}, {5, 15}}) {
      for (const auto& [ey, ep] : std::vector<std::array<double, 2>>{
               {0, 0}, {20, 0}, {-20, 0}, {0, 12}, {0, -12}, {15, 10}, {-12, -8}}) {
        FaceState st = pose(yaw, pitch, 0);
        st.eye_gaze_dir = eye_direction(st, ey, ep);
        RenderTarget target = RenderTarget::empty(cam.image_size);
        target.bgr.setTo(cv::Scalar(200, 200, 200));
        face->render(cam, st, Lighting{}, target);
        cv::Mat grey;
        cv::cvtColor(target.bgr, grey, cv::COLOR_BGR2GRAY);
        const EyesState eyes = face->eyes(st);
        ASSERT_TRUE(eyes.open);
        for (int e = 0; e < 2; ++e) {
          // The eye opening's projected bounding box.
          std::vector<cv::Point2f> opening;
          for (int k = 36 + 6 * e; k < 42 + 6 * e; ++k)
            opening.push_back(
                *cam.project(st.to_world(face->vertices_head()[static_cast<size_t>(k)])));
          cv::Rect window = cv::boundingRect(opening);
          window = cv::Rect(window.x - 2, window.y - 3, window.width + 4, window.height + 6);
          const cv::Vec3d pupil = e == 0 ? eyes.right.pupil_m : eyes.left.pupil_m;
          const auto truth = cam.project(pupil);
          ASSERT_TRUE(truth.has_value());
          // The pupil can hide under a lid at the extremes; test only when its centre is inside
          // the (landmark) opening by 2 px or more.
          if (cv::pointPolygonTest(opening, cv::Point2f(*truth), true) < 2.0) continue;
          const auto blob = darkest_blob(grey, window);
          ASSERT_TRUE(blob.has_value());
          EXPECT_NEAR(blob->x, truth->x, 1.0)
              << cam.frame << " head " << yaw << "," << pitch << " eye " << ey << "," << ep;
          EXPECT_NEAR(blob->y, truth->y, 1.0)
              << cam.frame << " head " << yaw << "," << pitch << " eye " << ey << "," << ep;
          ++checked;
        }
      }
    }
  }
  std::printf("[mesh] %d pupils checked\n", checked);
  EXPECT_GT(checked, 80);
}

TEST(MeshFace, EyesConvergeOnTheTargetWithinTheirRange) {
  REQUIRE_FACE();
  FaceState st = pose(10, -5, 3);
  st.gaze_target_m = cv::Vec3d(0.1, 0.0, 0.6);
  const EyesState e = face->eyes(st);
  for (const EyeState* s : {&e.left, &e.right}) {
    EXPECT_LT(ray_point_distance(s->centre_m, s->gaze_dir, *st.gaze_target_m), 1e-9);
    EXPECT_NEAR(cv::norm(s->pupil_m - s->centre_m), face->options().eyeball_radius_m, 1e-12);
  }
  EXPECT_GT(e.left.gaze_dir.dot(e.right.gaze_dir), std::cos(10 * CV_PI / 180));
  EXPECT_LT(e.left.gaze_dir.dot(e.right.gaze_dir), 1 - 1e-6);  // converging, not parallel
  // The mean ray passes (almost) through the target.
  EXPECT_LT(ray_point_distance(e.eye_midpoint(), e.gaze_dir(), *st.gaze_target_m), 0.002);
  // A target far to the side: clamped to the anatomical range.
  st.gaze_target_m = st.to_world(cv::Vec3d(-2.0, 0, -0.3));
  const EyesState c = face->eyes(st);
  const cv::Vec3d dh = st.world_from_head.t() * c.left.gaze_dir;
  EXPECT_NEAR(std::atan2(-dh[0], -dh[2]) * 180 / CV_PI, face->options().max_eye_yaw_deg, 1e-6);
}

TEST(MeshFace, ClosedEyesHideThePupil) {
  REQUIRE_FACE();
  const CameraModel cam = camera(1);
  double darkest[2] = {0, 0};
  for (int closed = 0; closed < 2; ++closed) {
    FaceState st = pose(0, 0, 0);
    st.eyelid_closure = closed;
    RenderTarget target = RenderTarget::empty(cam.image_size);
    face->render(cam, st, Lighting{}, target);
    cv::Mat grey;
    cv::cvtColor(target.bgr, grey, cv::COLOR_BGR2GRAY);
    std::vector<cv::Point2f> opening;
    for (int k = 36; k < 42; ++k)
      opening.push_back(*cam.project(st.to_world(face->vertices_head()[static_cast<size_t>(k)])));
    const cv::Rect r = cv::boundingRect(opening);
    cv::minMaxLoc(grey(r), &darkest[closed]);
    EXPECT_EQ(face->eyes(st).open, closed == 0);
  }
  EXPECT_LT(darkest[0], 25);
  EXPECT_GT(darkest[1], darkest[0] + 25);
}

TEST(MeshFace, DepthShowsTheRelief) {
  REQUIRE_FACE();
  const CameraModel cam = camera(4);  // front.depth
  const FaceState st = pose(0, 0, 0);
  RenderTarget target = RenderTarget::empty(cam.image_size);
  face->render(cam, st, Lighting{}, target);
  auto depth_at = [&](int vertex) {
    const cv::Vec3d w = st.to_world(face->vertices_head()[static_cast<size_t>(vertex)]);
    const auto p = cam.project(w);
    return std::pair{static_cast<double>(target.depth.at<float>(cvRound(p->y), cvRound(p->x))),
                     cam.to_camera(w)[2]};
  };
  for (int k : {19, 24, 27, 30, 33, 48, 57}) {
    const auto [drawn, vertex] = depth_at(k);
    EXPECT_NEAR(drawn, vertex, 0.004) << "landmark " << k;
  }
  // The nose tip is > 2 cm nearer than the cheek contour.
  EXPECT_LT(depth_at(30).first, depth_at(2).first - 0.02);
}

TEST(MeshFace, HaarFindsTheFaceFrontallyAndTurned) {
  REQUIRE_FACE();
  const std::string cascade = "/usr/share/opencv4/haarcascades/haarcascade_frontalface_alt2.xml";
  if (!fs::exists(cascade)) GTEST_SKIP() << "opencv-data missing";
  cv::CascadeClassifier haar(cascade);
  const CameraModel cam = camera(1);
  for (double yaw : {0.0, -25.0, 25.0}) {
    const FaceState st = pose(yaw, 0, 0);
    RenderTarget target = RenderTarget::empty(cam.image_size);
    target.bgr.setTo(cv::Scalar(195, 205, 212));
    face->render(cam, st, Lighting{}, target);
    cv::Mat grey;
    cv::cvtColor(target.bgr, grey, cv::COLOR_BGR2GRAY);
    std::vector<cv::Rect> found;
    haar.detectMultiScale(grey, found, 1.1, 3, 0, cv::Size(60, 60));
    ASSERT_EQ(found.size(), 1u) << "yaw " << yaw;
    const auto nose = cam.project(st.to_world(face->vertices_head()[30]));
    EXPECT_TRUE(cv::Rect2d(found[0]).contains(*nose)) << "yaw " << yaw;
  }
}

TEST(MeshFace, SeenFromBehindDrawsNothing) {
  REQUIRE_FACE();
  const CameraModel cam = camera(3);
  const FaceState st = pose(180, 0, 0);
  RenderTarget target = RenderTarget::empty(cam.image_size);
  face->render(cam, st, Lighting{}, target);
  EXPECT_EQ(cv::countNonZero(target.depth < 100), 0);
}

TEST(MeshFace, MissingLandmarkFileAndBadOptionsAreErrors) {
  MeshFaceOptions o;
  o.landmarks = "/nonexistent/astronaut_landmarks.yaml";
  if (fs::exists(o.portrait)) {
    auto r = MeshFaceRenderer::create(o);
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error().code, ErrorCode::kNotFound);
    EXPECT_NE(r.error().message.find("/nonexistent/astronaut_landmarks.yaml"), std::string::npos);
  }
  MeshFaceOptions bad;
  bad.pupil_radius_m = 0.008;  // larger than the iris
  bad.grid_spacing_px = 1;
  const Status s = bad.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("pupil_radius_m"), std::string::npos);
  EXPECT_NE(s.error().message.find("grid_spacing_px"), std::string::npos);
  EXPECT_TRUE(MeshFaceOptions{}.check());
}

}  // namespace
}  // namespace dreamsense::sim
