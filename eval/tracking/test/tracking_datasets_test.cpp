// OTB / MIL readers: separators, unlabelled frames, malformed files (one-line errors naming the
// file and line), frame offsets.

#include "dreamsense/eval/tracking_datasets.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

namespace dreamsense::eval {
namespace {
namespace fs = std::filesystem;

class TempDir {
 public:
  explicit TempDir(const std::string& name) : dir_(fs::temp_directory_path() / ("ds_trk_" + name)) {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() { fs::remove_all(dir_); }
  const fs::path& path() const { return dir_; }

 private:
  fs::path dir_;
};

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

void images(const fs::path& dir, const std::string& pattern, int first, int n) {
  fs::create_directories(dir);
  for (int i = first; i < first + n; ++i) {
    char name[64];
    std::snprintf(name, sizeof name, pattern.c_str(), i);
    cv::imwrite((dir / name).string(), cv::Mat(24, 32, CV_8UC3, cv::Scalar(i * 10 % 255)));
  }
}

TEST(BoxLine, CommasTabsAndSpaces) {
  for (const std::string line :
       {"10,20,30,40", "10\t20\t30\t40", "10 20 30 40", "10, 20,\t30  40\r", " 10.5,20,30,40 "}) {
    auto b = parse_box_line(line, "gt.txt", 1, 1.0);
    ASSERT_TRUE(b) << line << ": " << b.error().message;
    ASSERT_TRUE(b->has_value());
    EXPECT_NEAR((*b)->x, line.find("10.5") != std::string::npos ? 9.5 : 9.0, 1e-12);  // 1-based
    EXPECT_DOUBLE_EQ((*b)->y, 19.0);
    EXPECT_DOUBLE_EQ((*b)->width, 30.0);
    EXPECT_DOUBLE_EQ((*b)->height, 40.0);
  }
  auto unlabelled = parse_box_line("0,0,0,0", "gt.txt", 3, 0.0);
  ASSERT_TRUE(unlabelled);
  EXPECT_FALSE(unlabelled->has_value());
}

TEST(BoxLine, MalformedLinesNameFileAndLine) {
  for (const std::string line :
       {"10,20,30", "10,20,30,40,50", "10,abc,30,40", "10,20,-3,40", "", "nan,1,2,3"}) {
    auto b = parse_box_line(line, "seq/groundtruth_rect.txt", 17, 1.0);
    ASSERT_FALSE(b) << line;
    EXPECT_EQ(b.error().code, ErrorCode::kCorruptData);
    EXPECT_EQ(b.error().message.rfind("seq/groundtruth_rect.txt:17: ", 0), 0u) << b.error().message;
    EXPECT_EQ(b.error().message.find('\n'), std::string::npos);
  }
}

TEST(OtbReader, ReadsASequenceWithMixedSeparators) {
  TempDir t("otb");
  images(t.path() / "img", "%04d.jpg", 1, 4);
  write(t.path() / "groundtruth_rect.txt", "1,1,10,12\n2\t2\t10\t12\n3 3 10 12\n4, 4,10,12\n\n");
  auto s = read_otb_sequence(t.path());
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->frames.size(), 4u);
  EXPECT_EQ(s->labelled(), 4u);
  EXPECT_DOUBLE_EQ(s->truth[2]->x, 2.0);
  EXPECT_EQ(s->frames[3].filename(), "0004.jpg");
  EXPECT_TRUE(s->warnings.empty());
}

TEST(OtbReader, FewerBoxesThanImagesAndStartFrame) {
  TempDir t("otb_start");
  images(t.path() / "img", "%04d.jpg", 1, 6);
  write(t.path() / "groundtruth_rect.txt", "1,1,10,12\n2,2,10,12\n");
  auto s = read_otb_sequence(t.path());
  ASSERT_TRUE(s);
  EXPECT_EQ(s->frames.size(), 2u);
  EXPECT_FALSE(s->warnings.empty());
  auto later = read_otb_sequence(t.path(), 5);
  ASSERT_TRUE(later);
  EXPECT_EQ(later->frames[0].filename(), "0005.jpg");
}

TEST(OtbReader, MalformedGroundTruthIsAnErrorNamingTheLine) {
  TempDir t("otb_bad");
  images(t.path() / "img", "%04d.jpg", 1, 3);
  write(t.path() / "groundtruth_rect.txt", "1,1,10,12\n2;2;10;12\n3,3,10,12\n");
  auto s = read_otb_sequence(t.path());
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("groundtruth_rect.txt:2:"), std::string::npos)
      << s.error().message;
  fs::remove(t.path() / "groundtruth_rect.txt");
  auto none = read_otb_sequence(t.path());
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().code, ErrorCode::kNotFound);
}

TEST(MilReader, UnlabelledFramesAndFrameRange) {
  TempDir t("mil");
  images(t.path() / "imgs", "img%05d.png", 1, 6);
  write(t.path() / "toy_gt.txt", "5,6,10,12\n0,0,0,0\n0,0,0,0\n0,0,0,0\n0,0,0,0\n7,8,10,12\n");
  write(t.path() / "toy_frames.txt", "1,6\n");
  auto s = read_mil_sequence(t.path());
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s->name, "toy");
  EXPECT_EQ(s->frames.size(), 6u);
  EXPECT_EQ(s->labelled(), 2u);
  EXPECT_FALSE(s->truth[1].has_value());
  EXPECT_DOUBLE_EQ(s->truth[0]->x, 5.0);  // 0-based
}

TEST(MilReader, BadFiles) {
  TempDir t("mil_bad");
  images(t.path() / "imgs", "img%05d.png", 1, 3);
  write(t.path() / "toy_gt.txt", "5,6,10,12\n0,0,0,0\n1,2,3\n");
  write(t.path() / "toy_frames.txt", "1,3\n");
  auto s = read_mil_sequence(t.path());
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("toy_gt.txt:3:"), std::string::npos);
  write(t.path() / "toy_gt.txt", "5,6,10,12\n0,0,0,0\n1,2,3,4\n");
  write(t.path() / "toy_frames.txt", "1 to 3\n");
  auto f = read_mil_sequence(t.path());
  ASSERT_FALSE(f);
  EXPECT_NE(f.error().message.find("toy_frames.txt:1:"), std::string::npos);
  write(t.path() / "toy_frames.txt", "1,5\n");  // frames 4 and 5 have no image
  auto g = read_mil_sequence(t.path());
  ASSERT_FALSE(g);
  EXPECT_NE(g.error().message.find("frame 4"), std::string::npos);
}

TEST(TrackingDataset, FolderOfSequencesAndErrors) {
  TempDir t("many");
  for (const std::string n : {"b", "a"}) {
    images(t.path() / n / "img", "%04d.jpg", 1, 2);
    write(t.path() / n / "groundtruth_rect.txt", "1,1,10,12\n2,2,10,12\n");
  }
  auto all = read_tracking_dataset("otb", t.path());
  ASSERT_TRUE(all) << all.error().message;
  ASSERT_EQ(all->size(), 2u);
  EXPECT_EQ((*all)[0].name, "a");
  EXPECT_FALSE(read_tracking_dataset("vot", t.path()));
  auto none = read_tracking_dataset("mil", t.path());
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().code, ErrorCode::kNotFound);
  EXPECT_FALSE(read_tracking_dataset("otb", t.path() / "missing"));
}

}  // namespace
}  // namespace dreamsense::eval
