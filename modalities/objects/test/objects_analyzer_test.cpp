// The objects Analyzer adapter on synthetic frames: contract, writes, the plane from depth, and
// ticks without a top frame.

#include "dreamsense/objects/objects_analyzer.hpp"

#include "dreamsense/core/blackboard.hpp"

#include <gtest/gtest.h>

#include "synthetic_table.hpp"

namespace dreamsense::objects {
namespace {

MultiFrame tick(int k, const cv::Mat* top, const cv::Mat* depth = nullptr) {
  MultiFrame m;
  m.stamp = Timestamp::from_ns(k * 40'000'000LL);
  m.tick = static_cast<uint64_t>(k);
  if (top)
    m.frames["top.color"] =
        make_frame("top.color", m.stamp, static_cast<uint64_t>(k), ColorImage{*top});
  if (depth)
    m.frames["top.depth"] =
        make_frame("top.depth", m.stamp, static_cast<uint64_t>(k), DepthImage{*depth, true});
  return m;
}

cv::Mat depth_of_table(const CameraModel& cam) {
  cv::Mat d(cam.image_size, CV_16UC1);
  for (int v = 0; v < d.rows; ++v)
    for (int u = 0; u < d.cols; ++u) {
      const cv::Vec3d dir =
          cam.R.t() * cam.pixel_ray({static_cast<double>(u), static_cast<double>(v)});
      const auto p = geometry::intersect({cam.centre_world(), dir}, testing::table_plane());
      d.at<uint16_t>(v, u) = static_cast<uint16_t>(std::lround(cam.to_camera(*p)[2] * 1000));
    }
  return d;
}

TEST(ObjectsAnalyzer, WritesTheToysOnceThePlaneIsKnown) {
  const CameraModel cam = testing::table_camera();
  ObjectsAnalyzerOptions o;
  o.camera_model = cam;
  o.depth = "top.depth";
  o.depth_model = cam;
  auto a = ObjectsAnalyzer::create(o, nullptr);
  ASSERT_TRUE(a) << a.error().message;
  const auto c = (*a)->contract();
  EXPECT_EQ(c.required_inputs, std::vector<SensorId>{"top.color"});
  EXPECT_EQ(c.optional_inputs, std::vector<SensorId>{"top.depth"});
  EXPECT_EQ(c.writes, std::vector<std::string>{"objects.table"});

  const std::vector<testing::Toy> toys = {{0, {-0.2, 0.27, 0.6}, 0}, {1, {0.2, 0.27, 0.6}, 20}};
  const cv::Mat depth = depth_of_table(cam);
  Blackboard board;
  for (int k = 0; k < 5; ++k) {
    const cv::Mat img = testing::render_table(toys, {}, static_cast<uint64_t>(k));
    BlackboardWriter w("objects");
    ASSERT_TRUE((*a)->process(tick(k, &img, k == 0 ? &depth : nullptr), board.snapshot(), w));
    board.commit(w, Timestamp::from_ns(k * 40'000'000LL));
  }
  auto e = board.snapshot().get(keys::kTableObjects);
  ASSERT_TRUE(e && e->present());
  ASSERT_TRUE(e->value->table);
  EXPECT_NEAR(e->value->table->offset, 0.30, 0.005);
  ASSERT_EQ(e->value->objects.size(), 2u);  // unknown toys (no gallery), confirmed
  for (const auto& s : e->value->objects) EXPECT_TRUE(s.position_m);
}

TEST(ObjectsAnalyzer, NoTopFrameNoWriteAndBadStreams) {
  auto a = ObjectsAnalyzer::create({}, nullptr);
  ASSERT_TRUE(a);
  BlackboardWriter w("objects");
  ASSERT_TRUE((*a)->process(tick(0, nullptr), BlackboardView(), w));
  EXPECT_TRUE(w.empty());
  const cv::Mat grey(480, 640, CV_8UC1, cv::Scalar(3));
  EXPECT_FALSE((*a)->process(tick(1, &grey), BlackboardView(), w));
  ObjectsAnalyzerOptions o;
  o.depth = "front.depth";  // no calibration for it
  auto bad = ObjectsAnalyzer::create(o, nullptr);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("front.depth"), std::string::npos);
}

TEST(ObjectsAnalyzer, EmptyTableIsAnEmptyListNotAnError) {
  ObjectsAnalyzerOptions o;
  o.camera_model = testing::table_camera();
  o.table = testing::table_plane();
  auto a = ObjectsAnalyzer::create(o, nullptr);
  ASSERT_TRUE(a);
  const cv::Mat img = testing::render_table({});
  BlackboardWriter w("objects");
  ASSERT_TRUE((*a)->process(tick(0, &img), BlackboardView(), w));
  EXPECT_EQ(w.size(), 1u);
}

}  // namespace
}  // namespace dreamsense::objects
