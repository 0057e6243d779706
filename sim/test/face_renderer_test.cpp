#include "dreamsense/sim/face_renderer.hpp"

#include "dreamsense/sim/demo_scene.hpp"
#include "dreamsense/sim/demo_session.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>

namespace dreamsense::sim {
namespace {

std::unique_ptr<PlanarFaceRenderer> make_face() {
  auto r = PlanarFaceRenderer::create({});
  if (!r) return nullptr;
  return std::move(*r);
}

cv::Point2d apply(const cv::Matx33d& H, const cv::Point2d& p) {
  const cv::Vec3d q = H * cv::Vec3d(p.x, p.y, 1);
  return {q[0] / q[2], q[1] / q[2]};
}

TEST(FaceRenderer, HomographyPutsEyesWhereTheCameraProjectsThem) {
  auto face = make_face();
  if (!face) GTEST_SKIP() << "astronaut.png missing (python3-skimage)";
  const auto cameras = make_demo_cameras();
  const DemoScript script(7, 20);
  for (double t = 0; t < 20; t += 0.7) {
    const HeadPose hp = script.head_pose(t);
    FaceState st;
    st.position_m = hp.position_m;
    st.world_from_head = hp.rotation();
    for (const auto& cam : cameras) {
      const cv::Matx33d H = face->homography(cam, st);
      for (const auto& [px, head] :
           {std::pair{face->options().left_eye_px, face->left_eye_head()},
            std::pair{face->options().right_eye_px, face->right_eye_head()}}) {
        const auto expected = cam.project(st.to_world(head));
        ASSERT_TRUE(expected.has_value());
        const cv::Point2d got = apply(H, px);
        EXPECT_NEAR(got.x, expected->x, 1.0) << cam.frame << " t=" << t;
        EXPECT_NEAR(got.y, expected->y, 1.0) << cam.frame << " t=" << t;
      }
    }
  }
}

TEST(FaceRenderer, EyesAreSeventyMillimetresApartAndLeftIsWorldPlusX) {
  auto face = make_face();
  if (!face) GTEST_SKIP() << "astronaut.png missing (python3-skimage)";
  const cv::Vec3d l = face->left_eye_head(), r = face->right_eye_head();
  EXPECT_GT(l[0], r[0]);  // the child's left eye is on world +x at pose 0
  EXPECT_NEAR(cv::norm(l - r), 0.068, 0.01);
  EXPECT_NEAR(0.5 * (l + r)[0], 0.0, 1e-12);
}

TEST(FaceRenderer, RenderedPixelsShowTheTextureAtTheProjectedPoints) {
  auto face = make_face();
  if (!face) GTEST_SKIP() << "astronaut.png missing (python3-skimage)";
  const auto cameras = make_demo_cameras();
  const CameraModel& cam = cameras[1];  // camera_middle
  FaceState st;
  st.position_m = {0.0, -0.05, 1.1};
  st.world_from_head = rotation_from_ypr_deg(10, -5, 3);
  Lighting flat;
  flat.ambient = 1.0;
  flat.diffuse = 0.0;
  RenderTarget target = RenderTarget::empty(cam.image_size);
  face->render(cam, st, flat, target);
  const cv::Mat portrait = cv::imread(face->options().portrait.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(portrait.empty());
  cv::Mat smooth;
  cv::GaussianBlur(portrait, smooth, cv::Size(0, 0), 1.0);
  cv::Mat rendered_smooth;
  cv::GaussianBlur(target.bgr, rendered_smooth, cv::Size(0, 0), 2.0);  // ~2x magnification
  double total = 0;
  int n = 0;
  for (int y = 70; y <= 170; y += 10)
    for (int x = 185; x <= 265; x += 10) {
      const auto p = cam.project(st.to_world(face->head_point({double(x), double(y)})));
      ASSERT_TRUE(p.has_value());
      const cv::Vec3b a = rendered_smooth.at<cv::Vec3b>(cvRound(p->y), cvRound(p->x));
      const cv::Vec3b b = smooth.at<cv::Vec3b>(y, x);
      for (int k = 0; k < 3; ++k) total += std::abs(int(a[k]) - int(b[k]));
      n += 3;
      // Depth of a face pixel is the plane's depth.
      const float z = target.depth.at<float>(cvRound(p->y), cvRound(p->x));
      EXPECT_NEAR(z, cam.to_camera(st.to_world(face->head_point({double(x), double(y)})))[2], 0.01);
    }
  EXPECT_LT(total / n, 12.0);
}

TEST(FaceRenderer, FaceSeenFromBehindIsNotDrawn) {
  auto face = make_face();
  if (!face) GTEST_SKIP() << "astronaut.png missing (python3-skimage)";
  const auto cameras = make_demo_cameras();
  FaceState st;
  st.position_m = {0.0, -0.05, 1.1};
  st.world_from_head = rotation_from_ypr_deg(180, 0, 0);
  RenderTarget target = RenderTarget::empty(cameras[3].image_size);
  face->render(cameras[3], st, Lighting{}, target);
  EXPECT_EQ(cv::countNonZero(target.depth < 100), 0);
}

TEST(FaceRenderer, MissingPortraitNamesThePackage) {
  PlanarFaceOptions o;
  o.portrait = "/nonexistent/astronaut.png";
  auto r = PlanarFaceRenderer::create(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("python3-skimage"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::sim
