// enroll objects from labelled crops: label -> id mapping, new toys, --class, errors.

#include "dreamsense/eval/object_enrolment.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>

#include "../../../modalities/objects/test/synthetic_table.hpp"

namespace dreamsense::eval {
namespace {
namespace fs = std::filesystem;
using objects::testing::Toy;

void write_crops(const fs::path& dir, const std::string& label, int picture) {
  fs::create_directories(dir / label);
  for (int i = 0; i < 4; ++i) {
    const Toy t{picture, {-0.2 + 0.1 * i, 0.27, 0.6}, -30.0 + 20 * i};
    const cv::Mat img = objects::testing::render_table({t}, {}, 20 + static_cast<uint64_t>(i));
    const cv::Rect box = cv::Rect(objects::testing::toy_box(objects::testing::table_camera(), t)) +
                         cv::Size(10, 10) - cv::Point(5, 5);
    cv::imwrite((dir / label / ("view" + std::to_string(i) + ".png")).string(), img(box));
  }
}

TEST(ObjectEnrolment, CropsOfAKnownAndANewToy) {
  const fs::path dir = fs::temp_directory_path() / "ds_enrol_crops";
  fs::remove_all(dir);
  write_crops(dir, "car", 0);
  write_crops(dir, "ball", 1);
  ObjectEnrolmentOptions o;
  o.crops = dir;
  auto r = enrol_objects(o);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->gallery.classes().size(), 2u);
  EXPECT_EQ(r->gallery.find(0)->label, "car");   // a DREAM toy keeps its id
  EXPECT_EQ(r->gallery.find(4)->label, "ball");  // a new toy gets the next free id
  auto k = parse_object_class("ball=7:0.06x0.06x0.05");
  ASSERT_TRUE(k);
  o.classes = {*k};
  auto r2 = enrol_objects(o);
  ASSERT_TRUE(r2);
  ASSERT_TRUE(r2->gallery.find(7));
  EXPECT_NEAR(r2->gallery.find(7)->size_m[2], 0.05, 1e-12);
  fs::remove_all(dir);
}

TEST(ObjectEnrolment, Errors) {
  EXPECT_FALSE(enrol_objects({}));  // neither crops nor sessions
  ObjectEnrolmentOptions o;
  o.crops = "/nonexistent/crops";
  auto r = enrol_objects(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("/nonexistent/crops"), std::string::npos);
  for (const std::string bad :
       {"ball", "=3", "ball=x", "ball=-1", "ball=3:0.1x0.1", "ball=3:axbxc"})
    EXPECT_FALSE(parse_object_class(bad)) << bad;
}

}  // namespace
}  // namespace dreamsense::eval
