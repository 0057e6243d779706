// Table plane from depth, pixel lifting, the table-top detector, grip / distance / prediction.

#include "dreamsense/objects/table_detector.hpp"
#include "dreamsense/objects/table_geometry.hpp"
#include "dreamsense/objects/table_top_objects.hpp"
#include "dreamsense/objects/tracker.hpp"

#include <gtest/gtest.h>

#include "synthetic_table.hpp"

namespace dreamsense::objects {
namespace {

using testing::Toy;

// Depth (mm) a camera sees of a plane, with a box standing on it.
cv::Mat render_depth(const CameraModel& cam, const geometry::Plane& plane) {
  cv::Mat d(cam.image_size, CV_16UC1, cv::Scalar(0));
  for (int v = 0; v < d.rows; ++v)
    for (int u = 0; u < d.cols; ++u) {
      const cv::Vec3d ray = cam.pixel_ray({static_cast<double>(u), static_cast<double>(v)});
      const cv::Vec3d dir = cam.R.t() * ray;
      auto p = geometry::intersect({cam.centre_world(), dir}, plane);
      if (!p) continue;
      const cv::Vec3d c = cam.to_camera(*p);
      // A 20 cm block 10 cm above the plane in the middle of the image: not the table.
      const double z = (std::abs(u - 320) < 60 && std::abs(v - 240) < 60) ? c[2] - 0.10 : c[2];
      d.at<uint16_t>(v, u) = static_cast<uint16_t>(std::lround(z * 1000));
    }
  return d;
}

TEST(TablePlane, FitsTheTableSeenFromAbove) {
  const CameraModel cam = testing::table_camera();
  const geometry::Plane truth = testing::table_plane();
  auto fit = fit_table_plane_from_depth(render_depth(cam, truth), cam);
  ASSERT_TRUE(fit) << fit.error().message;
  EXPECT_GT(fit->plane.normal.dot(truth.normal), std::cos(0.5 * CV_PI / 180));
  EXPECT_NEAR(fit->plane.offset, truth.offset, 0.003);
  EXPECT_LT(fit->rms_m, 0.002);
}

TEST(TablePlane, NoPlaneMatchingThePriorIsAnError) {
  const CameraModel cam = testing::table_camera();
  TablePlaneFitOptions o;
  o.up_prior = cv::Vec3d(1, 0, 0);  // the table is not vertical
  auto fit = fit_table_plane_from_depth(render_depth(cam, testing::table_plane()), cam, o);
  ASSERT_FALSE(fit);
  EXPECT_EQ(fit.error().code, ErrorCode::kNotFound);
  EXPECT_FALSE(fit_table_plane_from_depth(cv::Mat(10, 10, CV_8UC1), cam));
  EXPECT_FALSE(fit_table_plane_from_depth(cv::Mat::zeros(480, 640, CV_16UC1), cam));
}

TEST(PixelOnPlane, LiftsTheProjectionOfAPointBack) {
  const CameraModel cam = testing::table_camera();
  const cv::Vec3d p(0.2, 0.27, 0.7);  // 3 cm above the table
  const auto px = cam.project(p);
  auto back = pixel_on_plane(cam, *px, testing::table_plane(), 0.03);
  ASSERT_TRUE(back);
  EXPECT_LT(cv::norm(*back - p), 1e-6);
}

TEST(TableTopDetector, FindsTheToysAndNothingOnAnEmptyTable) {
  const CameraModel cam = testing::table_camera();
  const std::vector<Toy> toys = {
      {0, {-0.3, 0.27, 0.6}, 10}, {1, {0.0, 0.27, 0.55}, -20}, {2, {0.3, 0.27, 0.65}, 30}};
  TableTopDetector d;
  auto empty = d.detect(testing::render_table({}));
  ASSERT_TRUE(empty) << empty.error().message;
  EXPECT_TRUE(empty->empty());
  d.reset();
  auto c = d.detect(testing::render_table(toys));
  ASSERT_TRUE(c) << c.error().message;
  ASSERT_EQ(c->size(), toys.size());
  for (const auto& t : toys) {
    const cv::Rect2d truth = testing::toy_box(cam, t);
    double best = 0;
    for (const auto& k : *c) best = std::max(best, iou(cv::Rect2d(k.box), truth));
    EXPECT_GT(best, 0.8);
  }
  for (const auto& k : *c) EXPECT_FALSE(k.touches_edge);
}

TEST(TableTopDetector, AnArmFromTheEdgeTouchesTheEdge) {
  TableTopDetector d;
  ASSERT_TRUE(d.detect(testing::render_table({})));
  auto c = d.detect(testing::render_table({}, {{{320, 330}}}));
  ASSERT_TRUE(c);
  ASSERT_EQ(c->size(), 1u);
  EXPECT_TRUE((*c)[0].touches_edge);
}

TEST(TableTopDetector, BadInput) {
  TableTopDetector d;
  EXPECT_FALSE(d.detect(cv::Mat()));
  EXPECT_FALSE(d.detect(cv::Mat(480, 640, CV_8UC1)));
  auto none = d.detect(cv::Mat(480, 640, CV_8UC3, cv::Scalar(0, 0, 0)) + cv::Scalar(0, 0, 0));
  // A uniform image is one big "table": no toys, no error.
  ASSERT_TRUE(none);
  EXPECT_TRUE(none->empty());
  ASSERT_TRUE(d.detect(testing::render_table({})));
  EXPECT_FALSE(d.detect(cv::Mat(240, 320, CV_8UC3)));  // another size than the first frame
  TableTopDetectorOptions o;
  o.downscale = 3;
  EXPECT_FALSE(TableTopDetector(o).detect(testing::render_table({})));
}

ObjectState resting_toy(double yaw_deg) {
  ObjectState s;
  s.position_m = cv::Vec3d(0.1, 0.27, 0.6);
  const double a = yaw_deg * CV_PI / 180;
  s.axis_m = cv::Vec3d(std::cos(a), 0, std::sin(a));
  s.size_m = {0.10, 0.075, 0.03};
  return s;
}

TEST(ObjectGeometry, TableDistanceOfARestingToy) {
  auto d = table_distance(resting_toy(0), testing::table_plane());
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->top_m, 0.03, 1e-9);
  EXPECT_NEAR(d->lift_m, 0.0, 1e-9);
  EXPECT_FALSE(d->measured);
  ObjectState lifted = resting_toy(0);
  lifted.position_m = cv::Vec3d(0.1, 0.17, 0.6);
  EXPECT_NEAR(table_distance(lifted, testing::table_plane())->lift_m, 0.10, 1e-9);
  EXPECT_FALSE(table_distance(ObjectState{}, testing::table_plane()));
}

TEST(ObjectGeometry, GripAcrossTheShortSideAtMidHeight) {
  auto g = grip_location(resting_toy(30), testing::table_plane());
  ASSERT_TRUE(g);
  EXPECT_LT(cv::norm(g->point_m - cv::Vec3d(0.1, 0.285, 0.6)), 1e-9);
  EXPECT_LT(cv::norm(g->approach - cv::Vec3d(0, 1, 0)), 1e-9);  // downwards (world +y)
  const double a = 30 * CV_PI / 180;
  EXPECT_NEAR(std::abs(g->closing_axis.dot(cv::Vec3d(-std::sin(a), 0, std::cos(a)))), 1.0, 1e-9);
  EXPECT_NEAR(g->opening_m, 0.095, 1e-9);
  GripOptions narrow;
  narrow.max_opening_m = 0.05;  // fits neither side
  EXPECT_FALSE(grip_location(resting_toy(0), testing::table_plane(), narrow));
}

TEST(ObjectGeometry, ConstantVelocityPrediction) {
  std::deque<ObjectState> h;
  for (int i = 0; i < 10; ++i) {
    ObjectState s = resting_toy(0);
    s.stamp_ns = i * 40'000'000LL;                               // 25 Hz
    s.position_m = cv::Vec3d(0.1 + 0.05 * i * 0.04, 0.27, 0.6);  // 5 cm/s along x
    h.push_back(s);
  }
  EXPECT_NEAR(estimate_velocity(h, 0.5)[0], 0.05, 1e-9);
  auto p = predict_position(h, 2.0, 0.5, testing::table_plane());
  ASSERT_TRUE(p);
  EXPECT_NEAR((*p)[0], 0.1 + 0.05 * 0.36 + 0.1, 1e-9);
  EXPECT_NEAR((*p)[1], 0.27, 1e-9);
  EXPECT_FALSE(predict_position({}, 1.0));
}

TEST(ObjectGeometry, ObjectsInACircleOnTheTable) {
  std::vector<ObjectState> objs(3, resting_toy(0));
  objs[0].position_m = cv::Vec3d(0.0, 0.27, 0.6);
  objs[1].position_m = cv::Vec3d(0.3, 0.27, 0.6);
  objs[2].position_m = cv::Vec3d(0.05, 0.10, 0.6);  // lifted, but within the circle in the plane
  objs[0].track_id = 0, objs[1].track_id = 1, objs[2].track_id = 2;
  auto in = objects_in_circle(objs, {0.0, 0.30, 0.6}, 0.1, testing::table_plane());
  ASSERT_EQ(in.size(), 2u);
  EXPECT_EQ(in[0].track_id, 0);
  EXPECT_EQ(in[1].track_id, 2);
}

}  // namespace
}  // namespace dreamsense::objects
