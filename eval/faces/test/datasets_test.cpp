// Readers of the face datasets on layouts written here (no real data needed), including the
// wrong layouts that must fail with a message naming the offending path.
#include "dreamsense/eval/faces/datasets.hpp"

#include "dreamsense/vision/image_io.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace dreamsense::eval::faces {
namespace {
namespace fs = std::filesystem;

class Layout : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("ds_faces_layout_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  void image(const fs::path& p) {
    fs::create_directories(p.parent_path());
    cv::Mat m(48, 48, CV_8UC1, cv::Scalar(100));
    cv::imwrite(p.string(), m);
  }
  void gif(const fs::path& p) {
    fs::create_directories(p.parent_path());
    ASSERT_TRUE(vision::write_gif_grey(p, cv::Mat(20, 20, CV_8UC1, cv::Scalar(50))).has_value());
  }
  fs::path root_;
};

TEST(NaturalOrder, NumbersCompareAsNumbers) {
  EXPECT_TRUE(natural_less("s2", "s10"));
  EXPECT_FALSE(natural_less("s10", "s2"));
  EXPECT_TRUE(natural_less("2.pgm", "10.pgm"));
  EXPECT_TRUE(natural_less("subject02", "subject10"));
  EXPECT_TRUE(natural_less("a", "b"));
  EXPECT_TRUE(natural_less("s1", "s1a"));
  EXPECT_FALSE(natural_less("s1", "s1"));
}

TEST_F(Layout, CkPlus48SubjectsFromFileNames) {
  image(root_ / "happy" / "S010_006_00000013.png");
  image(root_ / "happy" / "S011_001_00000014.png");
  image(root_ / "anger" / "S010_004_00000017.png");
  std::ofstream(root_ / "SOURCE.txt") << "notes are ignored";
  auto items = read_ckplus48(root_);
  ASSERT_TRUE(items.has_value()) << items.error().message;
  ASSERT_EQ(items->size(), 3u);
  EXPECT_EQ((*items)[0].label, "anger");
  EXPECT_EQ((*items)[0].subject, "S010");
  EXPECT_EQ((*items)[2].subject, "S011");
}

TEST_F(Layout, CkPlus48WrongLayoutsNameTheOffendingPath) {
  image(root_ / "happy" / "face1.png");
  auto bad_name = read_ckplus48(root_);
  ASSERT_FALSE(bad_name.has_value());
  EXPECT_NE(bad_name.error().message.find("face1.png"), std::string::npos);
  fs::remove_all(root_ / "happy");
  image(root_ / "bored" / "S010_006_00000013.png");
  auto bad_class = read_ckplus48(root_);
  ASSERT_FALSE(bad_class.has_value());
  EXPECT_NE(bad_class.error().message.find("bored"), std::string::npos);
  fs::remove_all(root_ / "bored");
  image(root_ / "S010_006_00000013.png");  // images straight in DIR: not class folders
  EXPECT_FALSE(read_ckplus48(root_).has_value());
  fs::remove_all(root_);
  EXPECT_EQ(read_ckplus48(root_).error().code, ErrorCode::kNotFound);
}

TEST_F(Layout, Fer2013ClassFoldersMapToProjectLabels) {
  image(root_ / "angry" / "PublicTest_1.jpg");
  image(root_ / "sad" / "PublicTest_2.jpg");
  image(root_ / "neutral" / "PublicTest_3.jpg");
  auto items = read_fer2013(root_);
  ASSERT_TRUE(items.has_value()) << items.error().message;
  ASSERT_EQ(items->size(), 3u);
  EXPECT_EQ((*items)[0].label, "anger");
  EXPECT_EQ((*items)[1].label, "neutral");
  EXPECT_EQ((*items)[2].label, "sadness");
  EXPECT_NE((*items)[0].subject, (*items)[1].subject);  // every image its own subject
  EXPECT_FALSE(read_expression_dataset("jaffe", root_).has_value());
}

TEST_F(Layout, AttSubjectsAndImagesInNaturalOrder) {
  for (const char* s : {"s2", "s10"})
    for (const char* i : {"1.pgm", "2.pgm", "10.pgm"}) image(root_ / s / i);
  auto items = read_att(root_);
  ASSERT_TRUE(items.has_value()) << items.error().message;
  ASSERT_EQ(items->size(), 6u);
  EXPECT_EQ((*items)[0].subject, "s2");
  EXPECT_EQ((*items)[2].path.filename(), "10.pgm");
  EXPECT_EQ((*items)[3].subject, "s10");
  image(root_ / "extra" / "1.pgm");
  auto bad = read_att(root_);
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("extra"), std::string::npos);
}

TEST_F(Layout, YaleConditionsSortedAndTheUcsdQuirk) {
  for (const char* c : {"happy", "glasses", "centerlight"})
    gif(root_ / (std::string("subject02.") + c));
  gif(root_ / "subject01.gif");  // the UCSD archive's subject01.centerlight
  gif(root_ / "subject01.wink");
  gif(root_ / "subject10.sad.gif");
  std::ofstream(root_ / "Readme.txt") << "ignored";
  auto items = read_yale(root_);
  ASSERT_TRUE(items.has_value()) << items.error().message;
  ASSERT_EQ(items->size(), 6u);
  EXPECT_EQ((*items)[0].path.filename(), "subject01.gif");  // centerlight < wink
  EXPECT_EQ((*items)[1].path.filename(), "subject01.wink");
  EXPECT_EQ((*items)[2].path.filename(), "subject02.centerlight");
  EXPECT_EQ((*items)[3].path.filename(), "subject02.glasses");
  EXPECT_EQ((*items)[5].subject, "subject10");
  auto img = vision::read_grey_image((*items)[0].path);
  ASSERT_TRUE(img.has_value());
  EXPECT_EQ(img->size(), cv::Size(20, 20));
  gif(root_ / "subject01.centerlight");  // now two centerlight images of subject01
  EXPECT_FALSE(read_yale(root_).has_value());
  fs::remove(root_ / "subject01.centerlight");
  gif(root_ / "person3.happy");
  auto bad = read_yale(root_);
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("person3.happy"), std::string::npos);
  EXPECT_FALSE(read_identity_dataset("lfw", root_).has_value());
}

}  // namespace
}  // namespace dreamsense::eval::faces
