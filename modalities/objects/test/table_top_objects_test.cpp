// TableTopObjects on synthetic table scenes (label analyzer): toys with the right ids and
// positions, an arm reaching over a toy, and the negative cases.

#include "dreamsense/objects/table_top_objects.hpp"

#include "dreamsense/objects/tracker.hpp"

#include <gtest/gtest.h>

#include "synthetic_table.hpp"

namespace dreamsense::objects {
namespace {

using testing::Toy;

std::shared_ptr<const ObjectGallery> gallery3() {
  std::vector<LabelledView> views;
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 5; ++i) {
      const Toy t{k, {-0.25 + 0.12 * i, 0.27, 0.5 + 0.04 * i}, -40.0 + 20 * i};
      const cv::Mat img = testing::render_table({t}, {}, 100 + static_cast<uint64_t>(i));
      const cv::Rect box =
          cv::Rect(testing::toy_box(testing::table_camera(), t)) + cv::Size(6, 6) - cv::Point(3, 3);
      auto v = make_view(img, box);
      views.push_back({k, {v->crop.clone(), v->mask.clone(), v->footprint}});
    }
  std::vector<ObjectClass> c = dream_toy_classes();
  c.resize(3);
  auto g = ObjectGallery::enrol(c, views);
  EXPECT_TRUE(g) << g.error().message;
  return std::make_shared<const ObjectGallery>(std::move(*g));
}

std::vector<Toy> scene(int frame) {
  const double s = 0.004 * frame;  // 10 cm/s at 25 Hz
  return {{0, {-0.30 + s, 0.27, 0.58}, 10},
          {1, {0.0, 0.27, 0.62 - s}, -15},
          {2, {0.30, 0.27, 0.55}, 25.0 + frame}};
}

TEST(TableTopObjects, ToysKeepTheirIdsPositionsAndBoxesWhileAnArmPassesOverOne) {
  const CameraModel cam = testing::table_camera();
  auto p = TableTopObjects::create({}, gallery3(), cam, testing::table_plane());
  ASSERT_TRUE(p) << p.error().message;
  const int frames = 40;
  double worst_position = 0, occluded_iou = 1;
  int occluded_reported = 0, track_of_toy0 = -1;
  for (int f = 0; f < frames; ++f) {
    const auto toys = scene(f);
    std::vector<testing::Arm> arms;
    const bool arm_over = f >= 20 && f < 30;
    if (arm_over) {
      const auto px = cam.project(toys[1].centre_m);
      arms.push_back({{px->x, px->y}, 26});  // the hand covers toy 1
    }
    auto out = (*p)->process(testing::render_table(toys, arms, 7 + static_cast<uint64_t>(f)),
                             f * 40'000'000LL);
    ASSERT_TRUE(out) << out.error().message;
    int known = 0;
    for (const auto& o : *out) {
      if (o.id == kUnknownObject) continue;
      ++known;
      if (o.id == 0) track_of_toy0 = o.track_id;
      ASSERT_GE(o.id, 0);
      ASSERT_LT(o.id, 3);
      const Toy& t = toys[static_cast<size_t>(o.id)];
      const cv::Rect2d truth = testing::toy_box(cam, t);
      ASSERT_TRUE(o.position_m);
      if (o.detected) {
        worst_position = std::max(worst_position, cv::norm(*o.position_m - t.centre_m));
        EXPECT_GT(iou(o.box, truth), 0.75) << "frame " << f << " toy " << o.id;
      } else if (o.id == 1 && arm_over) {
        ++occluded_reported;
        occluded_iou = std::min(occluded_iou, iou(o.box, truth));
      }
    }
    EXPECT_EQ(known, 3) << "frame " << f;  // the arm is never taken for a known toy
  }
  EXPECT_LT(worst_position, 0.015);
  EXPECT_GE(occluded_reported, 5);  // carried through the occlusion, flagged as not detected
  EXPECT_GT(occluded_iou, 0.3);
  // A history with a velocity: toy 0 moves at 10 cm/s along +x.
  const auto& h = (*p)->history(track_of_toy0);
  ASSERT_GT(h.size(), 10u);
  EXPECT_NEAR(h.back().velocity_mps[0], 0.10, 0.03);
}

TEST(TableTopObjects, EmptyTableGivesNoObjects) {
  auto p = TableTopObjects::create({}, gallery3(), testing::table_camera(), testing::table_plane());
  ASSERT_TRUE(p);
  for (int f = 0; f < 5; ++f) {
    auto out =
        (*p)->process(testing::render_table({}, {}, static_cast<uint64_t>(f)), f * 40'000'000LL);
    ASSERT_TRUE(out);
    EXPECT_TRUE(out->empty());
  }
}

TEST(TableTopObjects, AnArmAloneIsNotAToy) {
  auto p = TableTopObjects::create({}, gallery3(), testing::table_camera(), testing::table_plane());
  ASSERT_TRUE(p);
  for (int f = 0; f < 10; ++f) {
    auto out =
        (*p)->process(testing::render_table({}, {{{300.0 + 5 * f, 330}}}, static_cast<uint64_t>(f)),
                      f * 40'000'000LL);
    ASSERT_TRUE(out);
    for (const auto& o : *out) EXPECT_EQ(o.id, kUnknownObject);
    EXPECT_TRUE(out->empty()) << "an arm reaching in over the edge is no object";
  }
}

TEST(TableTopObjects, WithoutGalleryOrCalibration) {
  auto p = TableTopObjects::create({}, nullptr, std::nullopt, std::nullopt);
  ASSERT_TRUE(p);
  std::vector<ObjectState> out;
  for (int f = 0; f < 4; ++f) {
    auto r = (*p)->process(testing::render_table(scene(f), {}, static_cast<uint64_t>(f)),
                           f * 40'000'000LL);
    ASSERT_TRUE(r);
    out = *r;
  }
  ASSERT_EQ(out.size(), 3u);  // unknown blobs, reported after confirm_frames
  for (const auto& o : out) {
    EXPECT_EQ(o.id, kUnknownObject);
    EXPECT_FALSE(o.position_m);  // no calibration: image boxes only
  }
}

TEST(TableTopObjects, BadInputAndOptions) {
  auto p = TableTopObjects::create({}, nullptr, std::nullopt, std::nullopt);
  ASSERT_TRUE(p);
  EXPECT_FALSE((*p)->process(cv::Mat(), 0));
  EXPECT_FALSE((*p)->process(cv::Mat(480, 640, CV_8UC1), 0));
  TableTopObjectsOptions o;
  o.identifier = "sift";
  EXPECT_FALSE(TableTopObjects::create(o, nullptr, std::nullopt, std::nullopt));
}

}  // namespace
}  // namespace dreamsense::objects
