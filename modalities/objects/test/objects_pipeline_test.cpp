// The objects analyser in the declared pipeline: what its factory plans (and why it does not),
// and the analyser alone through testing::AnalyzerRunner, with the negative cases (no
// calibration, toys leaving the view).

#include "dreamsense/geometry/plane.hpp"
#include "dreamsense/objects/identification.hpp"
#include "dreamsense/objects/objects_analyzer.hpp"
#include "dreamsense/testing/analyzer_runner.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "synthetic_table.hpp"

namespace dreamsense::objects {
namespace {
namespace fs = std::filesystem;
using testing::Toy;

const AnalyzerFactory& factory() {
  static AnalyzerRegistry registry = [] {
    AnalyzerRegistry r;
    register_analyzers(r);
    return r;
  }();
  const AnalyzerFactory* f = registry.find("objects");
  EXPECT_NE(f, nullptr);
  return *f;
}

StreamDescription top_stream(bool calibrated) {
  StreamDescription s;
  s.id = "top.color";
  s.kind = SensorKind::kColor;
  s.roles = {roles::kTableCamera};
  s.width = 640;
  s.height = 480;
  if (calibrated) s.camera = testing::table_camera();
  return s;
}

fs::path desk_file() {
  const fs::path path = fs::temp_directory_path() / "dreamsense_objects_test_table.yaml";
  auto tf = geometry::table_frame_from_points(
      {{-0.4, 0.30, 0.4}, {0.4, 0.30, 0.4}, {0.0, 0.30, 0.8}}, {0, -0.7, 0.6});
  EXPECT_TRUE(tf) << tf.error().message;
  EXPECT_TRUE(geometry::write_table_frame(path, *tf));
  return path;
}

TEST(ObjectsPlan, SkippedWithAReasonWithoutTableCameraCalibrationOrTablePlane) {
  PlanContext ctx;
  OptionsNode none;
  auto p = factory().plan(ctx, none);
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_TRUE(p->analyzers.empty());
  EXPECT_EQ(p->skipped, "no stream with role table_camera");

  ctx.streams = {top_stream(false)};
  OptionsNode none2;
  p = factory().plan(ctx, none2);
  ASSERT_TRUE(p);
  EXPECT_TRUE(p->analyzers.empty());
  EXPECT_NE(p->skipped.find("top.color has no calibration"), std::string::npos) << p->skipped;

  ctx.streams = {top_stream(true)};
  OptionsNode none3;
  p = factory().plan(ctx, none3);
  ASSERT_TRUE(p);
  EXPECT_TRUE(p->analyzers.empty());
  EXPECT_NE(p->skipped.find("no table plane"), std::string::npos) << p->skipped;
}

TEST(ObjectsPlan, DeskCalibrationOrALiveDepthStreamGiveTheAnalyser) {
  PlanContext ctx;
  ctx.streams = {top_stream(true)};
  OptionsNode options;
  ASSERT_TRUE(options.set("table", desk_file().string()));
  auto p = factory().plan(ctx, options);
  ASSERT_TRUE(p) << p.error().message;
  ASSERT_EQ(p->analyzers.size(), 1u) << p->skipped;
  EXPECT_EQ(p->analyzers[0]->name(), "objects");
  const AnalyzerContract c = p->analyzers[0]->contract();
  EXPECT_EQ(c.required_inputs, std::vector<SensorId>{"top.color"});
  EXPECT_TRUE(c.optional_inputs.empty());
  EXPECT_EQ(c.writes, std::vector<std::string>{keys::kTableObjects.name});
  std::string notes;
  for (const auto& n : p->notes) notes += n + "\n";
  EXPECT_NE(notes.find("desk calibration"), std::string::npos) << notes;
  EXPECT_NE(notes.find("demo_toys.gallery.yaml"), std::string::npos) << notes;
  EXPECT_TRUE(options.unread_keys().empty());

  // Live capture: the front sensor's depth is read when it arrives (optional input).
  StreamDescription depth;
  depth.id = "front.depth";
  depth.kind = SensorKind::kDepth;
  depth.camera = testing::table_camera();
  ctx.streams.push_back(depth);
  ctx.absolute_paths_allowed = true;
  OptionsNode live;
  p = factory().plan(ctx, live);
  ASSERT_TRUE(p) << p.error().message;
  ASSERT_EQ(p->analyzers.size(), 1u) << p->skipped;
  EXPECT_EQ(p->analyzers[0]->contract().optional_inputs, std::vector<SensorId>{"front.depth"});
}

TEST(ObjectsPlan, BadOptionsAreErrorsNamingTheKey) {
  PlanContext ctx;
  ctx.streams = {top_stream(true)};
  OptionsNode options;
  ASSERT_TRUE(options.set("table", desk_file().string()));
  ASSERT_TRUE(options.set("identifier", "sift"));
  auto p = factory().plan(ctx, options);
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().message.find("identifier"), std::string::npos) << p.error().message;

  OptionsNode missing;
  ASSERT_TRUE(missing.set("table", "/nonexistent/table.yaml"));
  p = factory().plan(ctx, missing);
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().message.find("/nonexistent/table.yaml"), std::string::npos)
      << p.error().message;
}

// A gallery of the synthetic pictures 0 and 1 (DREAM's car and cup, 10 x 7.5 x 3 cm).
std::shared_ptr<const ObjectGallery> gallery2() {
  std::vector<LabelledView> views;
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < 5; ++i) {
      const Toy t{k, {-0.25 + 0.12 * i, 0.27, 0.5 + 0.04 * i}, -40.0 + 20 * i};
      const cv::Mat img = testing::render_table({t}, {}, 100 + static_cast<uint64_t>(i));
      const cv::Rect box =
          cv::Rect(testing::toy_box(testing::table_camera(), t)) + cv::Size(6, 6) - cv::Point(3, 3);
      auto v = make_view(img, box);
      EXPECT_TRUE(v);
      views.push_back({k, {v->crop.clone(), v->mask.clone(), v->footprint}});
    }
  std::vector<ObjectClass> c = dream_toy_classes();
  c.resize(2);
  auto g = ObjectGallery::enrol(c, views);
  EXPECT_TRUE(g) << g.error().message;
  return std::make_shared<const ObjectGallery>(std::move(*g));
}

FramePtr top_frame(int k, const cv::Mat& img) {
  return make_frame("top.color", Timestamp::from_ns(k * 40'000'000LL), static_cast<uint64_t>(k),
                    ColorImage{img});
}

TEST(ObjectsAnalyzerRunner, ToysOnTheTableThenLeavingTheViewEmptyTheList) {
  ObjectsAnalyzerOptions o;
  o.camera_model = testing::table_camera();
  o.table = testing::table_plane();
  o.objects.max_missing_frames = 10;
  auto a = ObjectsAnalyzer::create(o, gallery2());
  ASSERT_TRUE(a) << a.error().message;
  dreamsense::testing::AnalyzerRunner runner(std::move(*a));
  const std::vector<Toy> toys = {{0, {-0.2, 0.27, 0.6}, 0}, {1, {0.2, 0.27, 0.6}, 20}};
  int k = 0;
  for (; k < 8; ++k) {
    const double s = 0.004 * k;  // toy 0 slides right at 10 cm/s
    std::vector<Toy> now = toys;
    now[0].centre_m[0] += s;
    ASSERT_TRUE(runner.run(Timestamp::from_ns(k * 40'000'000LL),
                           {top_frame(k, testing::render_table(now, {}, 3 + k))}));
  }
  auto e = runner.output(keys::kTableObjects);
  ASSERT_TRUE(e && e->present());
  const TableObjects& v = *e->value;
  ASSERT_TRUE(v.table);
  EXPECT_NEAR(v.table->offset, 0.30, 1e-9);
  EXPECT_EQ(v.camera, "top.color");
  ASSERT_EQ(v.objects.size(), 2u);
  EXPECT_LT(v.objects[0].track_id, v.objects[1].track_id);  // by track id
  for (const auto& obj : v.objects) {
    EXPECT_TRUE(obj.label == "car" || obj.label == "cup") << obj.label;
    ASSERT_TRUE(obj.position_m);
    ASSERT_TRUE(obj.height_m);
    EXPECT_NEAR(*obj.height_m, 0.03, 0.01);  // top face of a resting 3-cm toy
    EXPECT_NEAR(obj.lift_m, 0.0, 1e-9);
    ASSERT_TRUE(obj.grip);
    EXPECT_NEAR(obj.grip->point_m[1], obj.position_m->operator[](1) + 0.015, 0.005);
    EXPECT_GE(obj.trajectory.size(), 4u);
    EXPECT_EQ(obj.trajectory.back().stamp, obj.stamp);
  }
  // The sliding toy moves along +x at about 10 cm/s.
  const TableObject& sliding =
      (*v.objects[0].position_m)[0] < (*v.objects[1].position_m)[0] ? v.objects[0] : v.objects[1];
  EXPECT_NEAR(sliding.velocity_mps[0], 0.10, 0.03);

  // Both toys are taken off the table: carried for at most max_missing_frames (reported as not
  // detected), then the list is empty (a value, not an absent entry).
  const cv::Mat empty = testing::render_table({}, {}, 99);
  int emptied_after = -1;
  for (int n = 0; n < 30 && emptied_after < 0; ++n, ++k) {
    ASSERT_TRUE(runner.run(Timestamp::from_ns(k * 40'000'000LL), {top_frame(k, empty)}));
    e = runner.output(keys::kTableObjects);
    ASSERT_TRUE(e && e->present());
    for (const auto& obj : e->value->objects) EXPECT_FALSE(obj.detected);
    if (e->value->objects.empty()) emptied_after = n + 1;
  }
  EXPECT_GT(emptied_after, 0);
  EXPECT_LE(emptied_after, 12);
  // A tick without a top frame writes nothing.
  ASSERT_TRUE(runner.run(Timestamp::from_ns(k * 40'000'000LL), {}));
  EXPECT_TRUE(runner.last_writes().empty());
}

TEST(ObjectsAnalyzerRunner, WithoutCalibrationBoxesButNoPositions) {
  ObjectsAnalyzerOptions o;  // no camera model, no table
  auto a = ObjectsAnalyzer::create(o, nullptr);
  ASSERT_TRUE(a);
  dreamsense::testing::AnalyzerRunner runner(std::move(*a));
  const std::vector<Toy> toys = {{0, {-0.2, 0.27, 0.6}, 0}};
  for (int k = 0; k < 5; ++k)
    ASSERT_TRUE(runner.run(Timestamp::from_ns(k * 40'000'000LL),
                           {top_frame(k, testing::render_table(toys, {}, 5 + k))}));
  auto e = runner.output(keys::kTableObjects);
  ASSERT_TRUE(e && e->present());
  EXPECT_FALSE(e->value->table);
  ASSERT_EQ(e->value->objects.size(), 1u);
  EXPECT_FALSE(e->value->objects[0].position_m);
  EXPECT_FALSE(e->value->objects[0].height_m);
  EXPECT_FALSE(e->value->objects[0].grip);
  EXPECT_GT(e->value->objects[0].box_px.area(), 1000.0);
}

}  // namespace
}  // namespace dreamsense::objects
