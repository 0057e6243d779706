#include "dreamsense/geometry/transform.hpp"

#include <gtest/gtest.h>

namespace dreamsense::geometry {
namespace {

RigidTransform make(double yaw, double pitch, double roll, cv::Vec3d t) {
  return {rotation_from_ypr_deg(yaw, pitch, roll), t};
}

void expect_near(const cv::Vec3d& a, const cv::Vec3d& b, double tol = 1e-9) {
  EXPECT_LT(cv::norm(a - b), tol) << a << " vs " << b;
}

TEST(RigidTransform, ComposeAndInverseRoundTrip) {
  const RigidTransform a = make(30, -10, 5, {0.1, -0.2, 0.3});
  const RigidTransform b = make(-70, 25, 40, {1.0, 0.5, -2.0});
  const cv::Vec3d p(0.3, -1.2, 2.5);
  expect_near((a * b).apply(p), a.apply(b.apply(p)));
  expect_near(a.inverse().apply(a.apply(p)), p);
  const RigidTransform i = a * a.inverse();
  EXPECT_LT(cv::norm(i.R - cv::Matx33d::eye()), 1e-12);
  expect_near(i.t, {0, 0, 0});
  EXPECT_NEAR(rotation_angle_deg(a.R, (a * make(12, 0, 0, {0, 0, 0})).R), 12, 1e-9);
}

TEST(RigidTransform, NearestRotationRepairsADreamLikeMatrix) {
  // ObjectFile.xml's DeskWorld_R_mat: a rotation about x by 28.2 deg with a stray -0.025.
  const cv::Matx33d M(1, 0, 0, -0.025, 0.881, -0.472, 0, 0.472, 0.881);
  EXPECT_GT(orthonormality_error(M), 1e-3);
  const cv::Matx33d R = nearest_rotation(M);
  EXPECT_LT(orthonormality_error(R), 1e-12);
  EXPECT_NEAR(cv::determinant(R), 1, 1e-12);
  EXPECT_LT(rotation_angle_deg(R, rotation_from_ypr_deg(0, 28.2, 0)), 1.5);
}

class TreeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(tree.add(frames::kWorld, frames::kFrontColor, RigidTransform::identity()));
    ASSERT_TRUE(tree.add(frames::kFrontColor, frames::kFrontDepth,
                         RigidTransform{cv::Matx33d::eye(), {-0.0277, 0.0032, 0.0005}}));
    ASSERT_TRUE(tree.add(frames::kWorld, frames::kCameraLeft, left));
    ASSERT_TRUE(tree.add(frames::kWorld, frames::kTable, table));
    ASSERT_TRUE(tree.add(frames::kTable, frames::kRobotHead, head));
  }
  TransformTree tree;
  RigidTransform left = make(35, 20, 0, {-0.4, -0.7, 0.4});  // world_from_camera_left
  RigidTransform table = make(0, 28.2, 0, {0, 0.3, 0.6});    // world_from_table
  RigidTransform head = make(180, 0, 0, {0, 0.35, -0.45});   // table_from_robot_head
};

TEST_F(TreeTest, LookupComposesThroughTheRootAndInverts) {
  auto lh = tree.lookup(frames::kCameraLeft, frames::kRobotHead);
  ASSERT_TRUE(lh);
  const cv::Vec3d p(0.05, 0.1, 0.2);
  expect_near(lh->apply(p), left.inverse().apply(table.apply(head.apply(p))));
  auto hl = tree.lookup(frames::kRobotHead, frames::kCameraLeft);
  ASSERT_TRUE(hl);
  expect_near(hl->apply(lh->apply(p)), p);
  auto self = tree.lookup(frames::kTable, frames::kTable);
  ASSERT_TRUE(self);
  expect_near(self->apply(p), p);
}

TEST_F(TreeTest, TheSeedsFourOperationsRoundTrip) {
  const cv::Vec3d p(0.2, -0.1, 1.3);
  auto g = tree.point_local_to_global(frames::kRobotHead, p);
  ASSERT_TRUE(g);
  expect_near(*g, table.apply(head.apply(p)));
  auto l = tree.point_global_to_local(frames::kRobotHead, *g);
  ASSERT_TRUE(l);
  expect_near(*l, p);
  const cv::Matx33d R_local = rotation_from_ypr_deg(10, 20, 30);
  auto Rg = tree.rotation_local_to_global(frames::kCameraLeft, R_local);
  ASSERT_TRUE(Rg);
  EXPECT_LT(cv::norm(*Rg - left.R * R_local), 1e-12);
  auto Rl = tree.rotation_global_to_local(frames::kCameraLeft, *Rg);
  ASSERT_TRUE(Rl);
  EXPECT_LT(cv::norm(*Rl - R_local), 1e-12);
  // A direction rotated to global equals the rotated point difference.
  const cv::Vec3d d(0, 0, 1);
  expect_near(*Rg * d, left.R * (R_local * d));
}

TEST_F(TreeTest, UnknownFramesDuplicatesAndNonRotationsAreErrors) {
  EXPECT_FALSE(tree.lookup("camera_nowhere", frames::kWorld));
  EXPECT_FALSE(tree.point_local_to_global("camera_nowhere", {0, 0, 0}));
  EXPECT_FALSE(tree.add(frames::kWorld, frames::kCameraLeft, RigidTransform{}));
  EXPECT_FALSE(tree.add("nowhere", "x", RigidTransform{}));
  RigidTransform bad;
  bad.R = cv::Matx33d(1, 0, 0, 0, 1, 0, 0, 0, 2);
  EXPECT_FALSE(tree.add(frames::kWorld, frames::kTopColor, bad));
  EXPECT_TRUE(tree.update(frames::kTable, RigidTransform{}));
  EXPECT_FALSE(tree.update(frames::kWorld, RigidTransform{}));
  EXPECT_EQ(tree.frame_names().front(), "world");
  EXPECT_EQ(tree.frame_names().size(), 6u);
}

TEST(TransformTree, FromCamerasUsesCameraFromWorld) {
  CameraModel cam;
  cam.frame = frames::kCameraRight;
  look_at({0.4, -0.7, 0.5}, {0, 0, 1.1}, {0, 1, 0}, cam.R, cam.t);
  auto tree = TransformTree::from_cameras({cam});
  ASSERT_TRUE(tree);
  auto c = tree->point_local_to_global(frames::kCameraRight, {0, 0, 0});
  ASSERT_TRUE(c);
  expect_near(*c, {0.4, -0.7, 0.5});
  cam.frame = "world";
  EXPECT_FALSE(TransformTree::from_cameras({cam}));
}

}  // namespace
}  // namespace dreamsense::geometry
