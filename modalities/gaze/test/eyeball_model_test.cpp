// eyeball_model: exact recovery of (C, r) from synthetic pupils, direction from a pupil ray, noise
// behaviour, negative cases, and the gaze model file's eyeball section.

#include "dreamsense/gaze/eyeball_model.hpp"

#include "dreamsense/gaze/gaze_estimator.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <tuple>

namespace dreamsense::gaze {
namespace {

// A camera 1.1 m in front of the head (head frame = camera frame rotated to face it).
struct Scene {
  CameraModel camera;
  cv::Matx33d camera_from_head;
  cv::Vec3d head_position_camera{0.01, -0.02, 1.1};
  Scene(double head_yaw_deg, double head_pitch_deg) {
    camera.image_size = {1280, 960};
    camera.K = cv::Matx33d(1075, 0, 640, 0, 1075, 480, 0, 0, 1);
    // A frontal face has the camera's axes (x to the subject's left = image right, y down, the
    // face looking along -z towards the camera); the head then turns by yaw and pitch.
    camera_from_head = rotation_from_ypr_deg(head_yaw_deg, head_pitch_deg, 0);
  }
  // Pixel of a head-frame point.
  cv::Point2d pixel(const cv::Vec3d& p_head) const {
    return *camera.project_camera_point(camera_from_head * p_head + head_position_camera);
  }
};

const EyeballModel kEye{{-0.031, 0.002, 0.011}, 0.0118};

TEST(EyeballModel, DirectionOfAnExactPupilIsTheEyeDirection) {
  for (double yaw : {-30.0, 0.0, 25.0})
    for (double eye_theta : {-20.0, 0.0, 15.0}) {
      const Scene s(yaw, 5);
      const cv::Vec3d d = rotation_from_ypr_deg(eye_theta, -8, 0) * cv::Vec3d(0, 0, -1);
      const cv::Point2d px = s.pixel(kEye.centre_head_m + kEye.radius_m * d);
      const auto got = eyeball_direction(
          pixel_ray_head(px, s.camera, s.camera_from_head, s.head_position_camera), kEye);
      ASSERT_TRUE(got);
      EXPECT_LT(std::acos(std::clamp(got->dot(d), -1.0, 1.0)) * 180 / CV_PI, 0.01)
          << "head yaw " << yaw << " eye " << eye_theta;
    }
}

// getEyes' 3-D eye positions are the per-eye rays' origins: with the eyeball method the pupil on
// the eyeball, i.e. the point the pupil's pixel shows, on the ray from the centre.
TEST(EyeballModel, EyeRayStartsAtThePupilItsPixelShows) {
  const Scene s(15, 5);
  const EyeballModel left{{0.031, 0.002, 0.011}, 0.0118};
  const cv::Vec3d d = rotation_from_ypr_deg(-10, 6, 0) * cv::Vec3d(0, 0, -1);
  EyeCenters pupils;
  pupils.right = {true, s.pixel(kEye.centre_head_m + kEye.radius_m * d), 1};
  pupils.left = {true, s.pixel(left.centre_head_m + left.radius_m * d), 1};
  FaceLandmarks lm;
  lm.camera = "cam";
  lm.points_px.assign(kFaceLandmarkCount, {640, 480});
  HeadPose head;  // the camera is the world
  head.camera_from_head = head.world_from_head = s.camera_from_head;
  head.position_camera_m = head.position_world_m = s.head_position_camera;
  GazeEstimatorOptions o;
  o.method = GazeMethod::kEyeball;
  o.right_eyeball = kEye;
  o.left_eyeball = left;
  const auto g = estimate_gaze(lm, pupils, head, s.camera, o);
  ASSERT_TRUE(g);
  for (const auto& [ray, eye, px] : {std::tuple{g->right, kEye, pupils.right.center_px},
                                     std::tuple{g->left, left, pupils.left.center_px}}) {
    ASSERT_TRUE(ray.valid);
    const cv::Vec3d pupil_world =
        s.camera_from_head * (eye.centre_head_m + eye.radius_m * d) + s.head_position_camera;
    EXPECT_LT(cv::norm(ray.origin_world_m - pupil_world), 1e-6);
    const auto shown = s.camera.project_camera_point(ray.origin_world_m);
    ASSERT_TRUE(shown);
    EXPECT_LT(cv::norm(*shown - px), 1e-6);
    EXPECT_NEAR(ray.direction_world.dot(s.camera_from_head * d), 1.0, 1e-9);
  }
}

TEST(EyeballModel, FitRecoversCentreAndRadius) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> head_yaw(-35, 35), eye_t(-25, 25), eye_p(-18, 18);
  std::normal_distribution<double> px_noise(0, 0.3);
  auto samples = [&](double noise_scale) {
    std::vector<EyeballSample> out;
    for (int i = 0; i < 400; ++i) {
      const Scene s(head_yaw(rng), 0);
      const cv::Vec3d d = rotation_from_ypr_deg(eye_t(rng), eye_p(rng), 0) * cv::Vec3d(0, 0, -1);
      cv::Point2d px = s.pixel(kEye.centre_head_m + kEye.radius_m * d);
      px += noise_scale * cv::Point2d(px_noise(rng), px_noise(rng));
      out.push_back({pixel_ray_head(px, s.camera, s.camera_from_head, s.head_position_camera), d});
    }
    return out;
  };
  auto exact = fit_eyeball_model(samples(0));
  ASSERT_TRUE(exact) << exact.error().message;
  EXPECT_LT(cv::norm(exact->centre_head_m - kEye.centre_head_m), 1e-6);
  EXPECT_NEAR(exact->radius_m, kEye.radius_m, 1e-6);
  auto noisy = fit_eyeball_model(samples(1));  // 0.3 px pupil noise
  ASSERT_TRUE(noisy) << noisy.error().message;
  EXPECT_LT(cv::norm(noisy->centre_head_m - kEye.centre_head_m), 0.0015);
  EXPECT_NEAR(noisy->radius_m, kEye.radius_m, 0.0015);
}

TEST(EyeballModel, NegativeCases) {
  const Scene s(0, 0);
  const cv::Vec3d d(0, 0, -1);
  const EyeballSample same{pixel_ray_head(s.pixel(kEye.centre_head_m + kEye.radius_m * d), s.camera,
                                          s.camera_from_head, s.head_position_camera),
                           d};
  // One direction only: centre and radius are confounded along it.
  auto r = fit_eyeball_model(std::vector<EyeballSample>(50, same));
  ASSERT_FALSE(r);
  EXPECT_FALSE(fit_eyeball_model(std::vector<EyeballSample>(5, same)));  // too few
  EXPECT_FALSE((EyeballModel{{0, 0, 0}, 0.1}).check());                  // 10 cm eyeball
  EXPECT_FALSE((EyeballModel{{0, 0, 0.5}, 0.012}).check());              // far from the head
  // A ray that misses the sphere still gives a unit direction (the nearest point).
  const auto miss = eyeball_direction({{0.1, 0, -1}, {0, 0, 1}}, kEye);
  ASSERT_TRUE(miss);
  EXPECT_NEAR(cv::norm(*miss), 1.0, 1e-12);
}

TEST(GazeModelFile, EyeballsRoundTripAndMustComeInPairs) {
  const auto dir = std::filesystem::temp_directory_path() / "ds_eyeball_model_test";
  std::filesystem::create_directories(dir);
  GazeModelFile m;
  m.right_eyeball = kEye;
  m.left_eyeball = EyeballModel{{0.031, 0.002, 0.011}, 0.012};
  m.fixation_yaw = true;
  m.fixation_yaw_start_deg = -6.25;
  ASSERT_TRUE(write_gaze_model(dir / "g.yaml", m));
  auto back = read_gaze_model(dir / "g.yaml");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_TRUE(back->fixation_yaw);
  EXPECT_EQ(back->fixation_yaw_start_deg, -6.25);
  ASSERT_TRUE(back->right_eyeball && back->left_eyeball);
  EXPECT_LT(cv::norm(back->right_eyeball->centre_head_m - kEye.centre_head_m), 1e-12);
  EXPECT_NEAR(back->left_eyeball->radius_m, 0.012, 1e-12);
  GazeModelFile eq4_only;
  ASSERT_TRUE(write_gaze_model(dir / "eq4.yaml", eq4_only));
  auto plain = read_gaze_model(dir / "eq4.yaml");
  ASSERT_TRUE(plain);
  EXPECT_FALSE(plain->right_eyeball);
  EXPECT_FALSE(plain->fixation_yaw);
  EXPECT_EQ(plain->fixation_yaw_start_deg, 0);
  std::ifstream in(dir / "g.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  // A start correction beyond the plausible range: corrupt.
  const size_t start = text.find("fixation_yaw_start_deg: ");
  ASSERT_NE(start, std::string::npos);
  std::ofstream(dir / "far.yaml") << text.substr(0, start) << "fixation_yaw_start_deg: 45.\n";
  auto far = read_gaze_model(dir / "far.yaml");
  ASSERT_FALSE(far);
  EXPECT_EQ(far.error().code, ErrorCode::kCorruptData);
  // Only one eyeball: corrupt.
  text = text.substr(0, text.find("left_eyeball"));
  std::ofstream(dir / "one.yaml") << text;
  auto one = read_gaze_model(dir / "one.yaml");
  ASSERT_FALSE(one);
  EXPECT_EQ(one.error().code, ErrorCode::kCorruptData);
  std::filesystem::remove_all(dir);
}

// Issue 15: the anatomical eyeball sits behind the eye opening (head +z), slightly raised, and
// a pupil seen straight ahead on it reads as looking along the head's -z.
TEST(AnatomicalEyeball, BehindTheOpeningAndStraightAhead) {
  const cv::Vec3d opening(0.031, 0.0, 0.0);
  const AnatomicalEyeOptions o;
  ASSERT_TRUE(o.check());
  const EyeballModel e = anatomical_eyeball(opening, o);
  ASSERT_TRUE(e.check());
  EXPECT_NEAR(e.centre_head_m[2], 0.0115, 1e-12);
  EXPECT_NEAR(e.centre_head_m[1], -0.0005, 1e-12);  // y down: raised
  EXPECT_NEAR(e.radius_m, 0.0105, 1e-12);
  // A camera 1 m in front sees the pupil at the front of the sphere: direction -z.
  const cv::Vec3d pupil = e.centre_head_m + cv::Vec3d(0, 0, -e.radius_m);
  const cv::Vec3d cam(0.031, -0.0005, -1.0);
  const HeadRay ray{cam, cv::normalize(pupil - cam)};
  auto d = eyeball_direction(ray, e);
  ASSERT_TRUE(d);
  EXPECT_LT(cv::norm(*d - cv::Vec3d(0, 0, -1)), 1e-6);
  AnatomicalEyeOptions bad;
  bad.radius_m = 0.05;
  EXPECT_FALSE(bad.check());
}

// Found by fuzzing (issue 18, fuzz/README.md): on this 12-byte file OpenCV's YAML parser throws
// std::length_error, which used to escape the reader and end the program; it must be an error.
TEST(FuzzRegression, GazeModelOpenCvCannotParseIsAnError) {
  const std::filesystem::path p = std::filesystem::path(::testing::TempDir()) / "ds_fuzz_gaze.yaml";
  std::ofstream(p) << "%YAML:1.\n{ :";
  EXPECT_FALSE(read_gaze_model(p));
  // fuzz/findings/opencv_xml_segv.calibration without its selector byte (finding 4): OpenCV's XML
  // reader dereferenced null on it; open_file_storage makes it an error.
  constexpr char kXmlSegv[] = "<?xml?>\n<open-----------------------ml ve=\0%";
  std::ofstream(p, std::ios::binary).write(kXmlSegv, sizeof kXmlSegv - 1);
  EXPECT_FALSE(read_gaze_model(p));
  std::filesystem::remove(p);
}

}  // namespace
}  // namespace dreamsense::gaze
