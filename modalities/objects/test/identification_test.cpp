// Identification: enrolment from views, rotation, rejection of an unknown toy, the seed's
// baseline, the gallery file.

#include "dreamsense/objects/identification.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "synthetic_table.hpp"

namespace dreamsense::objects {
namespace {

using testing::Toy;

ObjectView view_of(const Toy& t, uint64_t seed = 1) {
  const cv::Mat img = testing::render_table({t}, {}, seed);
  const cv::Rect box =
      cv::Rect(testing::toy_box(testing::table_camera(), t)) + cv::Size(6, 6) - cv::Point(3, 3);
  auto v = make_view(img, box);
  EXPECT_TRUE(v) << v.error().message;
  return v->crop.empty() ? ObjectView{}
                         : ObjectView{v->crop.clone(), v->mask.clone(), v->footprint};
}

std::vector<LabelledView> enrolment(int classes) {
  std::vector<LabelledView> out;
  for (int k = 0; k < classes; ++k)
    for (int i = 0; i < 6; ++i)
      out.push_back(
          {k, view_of({k, {-0.3 + 0.12 * i, 0.27, 0.55 + 0.02 * i}, -30.0 + 12 * i}, 10 + i)});
  return out;
}

std::vector<ObjectClass> classes(int n) {
  std::vector<ObjectClass> c = dream_toy_classes();
  c.resize(static_cast<size_t>(n));
  return c;
}

TEST(ObjectView, SeparatesTheToyFromTheTable) {
  const Toy t{1, {0.1, 0.27, 0.6}, 20};
  const ObjectView v = view_of(t);
  const double fill = cv::countNonZero(v.mask) / static_cast<double>(v.mask.total());
  EXPECT_GT(fill, 0.5);
  EXPECT_LT(fill, 0.95);  // the table corners of the crop are not the toy
  const double long_side = std::max(v.footprint.size.width, v.footprint.size.height);
  EXPECT_NEAR(long_side, 0.10 * 525 / 0.97, 8.0);  // 10 cm at 0.97 m
  EXPECT_FALSE(make_view(cv::Mat(), {0, 0, 10, 10}));
  EXPECT_FALSE(make_view(cv::Mat(100, 100, CV_8UC3), {98, 98, 10, 10}));
}

TEST(ObjectGallery, IdentifiesNewPosesAndRejectsAToyNobodyEnrolled) {
  auto g = ObjectGallery::enrol(classes(4), enrolment(4));
  ASSERT_TRUE(g) << g.error().message;
  EXPECT_TRUE(g->has_baseline());
  int correct = 0, baseline_correct = 0, n = 0;
  for (int k = 0; k < 4; ++k)
    for (double yaw : {-25.0, 5.0, 35.0, 170.0}) {  // 170: the picture upside down
      const ObjectView v = view_of({k, {0.05, 0.27, 0.7}, yaw}, 99);
      correct += g->identify(v).id == k ? 1 : 0;
      baseline_correct += g->identify_baseline(v).id == k ? 1 : 0;
      ++n;
    }
  EXPECT_EQ(correct, n);
  EXPECT_GE(baseline_correct, n / 2);  // the seed's HOG + SVM, reported beside ours
  // Picture 4 was never enrolled: ours says unknown, the baseline must pick some toy.
  const ObjectView stranger = view_of({4, {0.0, 0.27, 0.6}, 10}, 5);
  const Identification u = g->identify(stranger);
  EXPECT_EQ(u.id, kUnknownObject);
  EXPECT_LT(u.score, 0);
  EXPECT_NE(g->identify_baseline(stranger).id, kUnknownObject);
}

TEST(ObjectGallery, WithoutAClassThatClassBecomesUnknown) {
  auto g = ObjectGallery::enrol(classes(4), enrolment(4));
  ASSERT_TRUE(g);
  auto g3 = g->without(2);
  ASSERT_TRUE(g3);
  EXPECT_EQ(g3->classes().size(), 3u);
  EXPECT_EQ(g3->identify(view_of({2, {0.1, 0.27, 0.6}, 0}, 3)).id, kUnknownObject);
  EXPECT_EQ(g3->identify(view_of({1, {0.1, 0.27, 0.6}, 0}, 3)).id, 1);
  EXPECT_FALSE(g->without(7));
}

TEST(ObjectGallery, AddingAToyKeepsTheOthers) {
  auto g = ObjectGallery::enrol(classes(3), enrolment(3));
  ASSERT_TRUE(g);
  std::vector<LabelledView> more;
  for (int i = 0; i < 4; ++i)
    more.push_back({4, view_of({4, {-0.2 + 0.1 * i, 0.27, 0.6}, 15.0 * i}, 40 + i)});
  ASSERT_TRUE(g->add({{4, "ball", {0.08, 0.08, 0.05}}}, more));
  EXPECT_EQ(g->identify(view_of({4, {0.25, 0.27, 0.65}, 50}, 8)).id, 4);
  EXPECT_EQ(g->identify(view_of({0, {0.25, 0.27, 0.65}, 50}, 8)).id, 0);
  EXPECT_NEAR(g->find(4)->size_m[2], 0.05, 1e-12);
  auto clash = g->add({{4, "kite", {0.1, 0.1, 0.1}}}, more);
  ASSERT_FALSE(clash);
  EXPECT_NE(clash.error().message.find("already 'ball'"), std::string::npos);
}

TEST(ObjectGallery, EnrolmentErrors) {
  EXPECT_FALSE(ObjectGallery::enrol({}, enrolment(1)));
  auto missing = ObjectGallery::enrol(classes(3), enrolment(2));
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("has no view"), std::string::npos);
  std::vector<ObjectClass> dup = {{0, "a"}, {0, "b"}};
  EXPECT_FALSE(ObjectGallery::enrol(dup, enrolment(1)));
  std::vector<LabelledView> stray = enrolment(1);
  stray.push_back({9, stray[0].view});
  EXPECT_FALSE(ObjectGallery::enrol(classes(1), stray));
}

TEST(ObjectGallery, FileRoundTripAndBadFiles) {
  auto g = ObjectGallery::enrol(classes(4), enrolment(4));
  ASSERT_TRUE(g);
  const auto dir = std::filesystem::temp_directory_path() / "ds_objects_gallery_test";
  std::filesystem::create_directories(dir);
  const auto file = dir / "g.yaml";
  ASSERT_TRUE(g->save(file));
  auto back = ObjectGallery::load(file);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->classes().size(), 4u);
  EXPECT_DOUBLE_EQ(back->threshold(), g->threshold());
  EXPECT_TRUE(back->has_baseline());
  const ObjectView v = view_of({3, {0.0, 0.27, 0.6}, 12}, 77);
  EXPECT_EQ(back->identify(v).id, g->identify(v).id);
  EXPECT_NEAR(back->identify(v).distance, g->identify(v).distance, 1e-6);
  EXPECT_EQ(back->identify_baseline(v).id, g->identify_baseline(v).id);

  auto missing = ObjectGallery::load(dir / "none.yaml");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("none.yaml"), std::string::npos);
  {
    std::ofstream f(dir / "other.yaml");
    f << "%YAML:1.0\n---\nformat: \"something_else\"\nformat_version: 1\n";
  }
  auto other = ObjectGallery::load(dir / "other.yaml");
  ASSERT_FALSE(other);
  EXPECT_NE(other.error().message.find("not an object gallery"), std::string::npos);
  {
    std::ofstream f(dir / "v2.yaml");
    f << "%YAML:1.0\n---\nformat: \"dreamsense.object_gallery\"\nformat_version: 2\n";
  }
  auto v2 = ObjectGallery::load(dir / "v2.yaml");
  ASSERT_FALSE(v2);
  EXPECT_EQ(v2.error().code, ErrorCode::kUnsupported);
  std::filesystem::remove_all(dir);
}

TEST(ObjectGallery, ShippedDemoGalleryLoads) {
  auto g = ObjectGallery::load(default_gallery_path());
  ASSERT_TRUE(g) << g.error().message;
  ASSERT_EQ(g->classes().size(), 4u);
  EXPECT_EQ(g->find(0)->label, "car");
  EXPECT_EQ(g->find(3)->label, "plane");
  EXPECT_TRUE(g->has_baseline());
  // None of the synthetic pictures is a demo toy: all rejected by ours.
  for (int k = 0; k < 5; ++k)
    EXPECT_EQ(g->identify(view_of({k, {0.0, 0.27, 0.6}, 0}, 3)).id, kUnknownObject) << k;
}

// Found by fuzzing (issue 18, fuzz/README.md): on this 12-byte file OpenCV's YAML parser throws
// std::length_error, which used to escape the reader and end the program; it must be an error.
TEST(FuzzRegression, ObjectGalleryOpenCvCannotParseIsAnError) {
  const std::filesystem::path p =
      std::filesystem::path(::testing::TempDir()) / "ds_fuzz_objects.yaml";
  std::ofstream(p) << "%YAML:1.\n{ :";
  EXPECT_FALSE(ObjectGallery::load(p));
  // fuzz/findings/opencv_xml_segv.calibration without its selector byte (finding 4): OpenCV's XML
  // reader dereferenced null on it; open_file_storage makes it an error.
  constexpr char kXmlSegv[] = "<?xml?>\n<open-----------------------ml ve=\0%";
  std::ofstream(p, std::ios::binary).write(kXmlSegv, sizeof kXmlSegv - 1);
  EXPECT_FALSE(ObjectGallery::load(p));
  std::filesystem::remove(p);
}

}  // namespace
}  // namespace dreamsense::objects
