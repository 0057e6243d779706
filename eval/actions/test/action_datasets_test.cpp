// Readers of the skeleton action datasets on small files written here, including malformed ones
// (one-line errors naming the file and line), and the seeds / segments parsers.

#include "dreamsense/eval/action_datasets.hpp"

#include "dreamsense/eval/dream_gestures.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace dreamsense::eval::actions {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / "dreamsense_action_datasets_test" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

// One UTKinect line: frame id, then 20 joints in Kinect SDK order (hip centre first), y up.
std::string utk_line(int id, double dx = 0) {
  std::string s = std::to_string(id);
  for (int j = 0; j < 20; ++j) {
    const double y = j == 3 ? 0.7 : j == 2 ? 0.5 : j == 1 ? 0.25 : j == 0 ? 0.0 : 0.3;
    const double x = (j == 4 || j == 12 ? -0.2 : j == 8 || j == 16 ? 0.2 : 0.0) + dx;
    s += " " + std::to_string(x) + " " + std::to_string(y) + " 2.5";
  }
  return s + "\n";
}

std::string utk_frames(int first, int last) {
  std::string s;
  for (int id = first; id <= last; id += 2) s += utk_line(id, 0.001 * id);
  return s;
}

TEST(UtkinectReader, ReadsSegmentsFromTheLabelsAndConvertsAxes) {
  const fs::path d = fresh_dir("utk_ok");
  write(d / "joints_s01_e01.txt", utk_frames(10, 60) + utk_line(60));  // a repeated id
  write(d / "joints_s02_e01.txt", utk_frames(10, 60));
  write(d / "actionLabel.txt",
        "s01_e01\nwalk: 10 30\nwave: 32 60\ns02_e01\nwalk: 12 28\nwave:  NaN NaN\n"
        "s09_e01\nwalk: 1 5\n");
  auto r = read_utkinect(d);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->items.size(), 3u);
  EXPECT_EQ(r->skipped, 1);
  EXPECT_EQ(r->labels, (std::vector<std::string>{"walk", "wave"}));
  EXPECT_EQ(r->items[0].subject, "s01");
  EXPECT_EQ(r->items[0].frames.size(), 11u);  // ids 10, 12, ..., 30
  EXPECT_EQ(r->items[1].frames.size(), 15u);  // 32..60, the repeated 60 dropped
  EXPECT_EQ(r->items[0].frames[1].stamp_ns - r->items[0].frames[0].stamp_ns, 66'666'667);
  // Kinect (y up, x to the sensor's left) -> optical (y down, x right): the head is above.
  const auto& f = r->items[0].frames[0];
  EXPECT_LT(f.joint(JointId::kHead).position_m[1], f.joint(JointId::kHipCenter).position_m[1]);
  EXPECT_NEAR(f.joint(JointId::kShoulderLeft).position_m[0], 0.2 - 0.01, 1e-6);
  EXPECT_NE(r->note.find("actionLabel.txt"), std::string::npos);
  // The corrected label file wins when present.
  write(d / "actionLabel_modified.txt", "s01_e01\nwalk: 10 20\n");
  auto m = read_utkinect(d);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->items.size(), 1u);
  EXPECT_NE(m->note.find("actionLabel_modified.txt"), std::string::npos);
}

TEST(UtkinectReader, MalformedFilesNameFileAndLine) {
  const fs::path d = fresh_dir("utk_bad");
  write(d / "actionLabel.txt", "s01_e01\nwalk: 10 30\n");
  write(d / "joints_s01_e01.txt", utk_line(10) + "12 0.1 0.2\n");  // truncated line
  auto r = read_utkinect(d);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("joints_s01_e01.txt:2:"), std::string::npos)
      << r.error().message;
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos);

  std::string bad_number = utk_line(10);
  bad_number.replace(bad_number.find("2.5"), 3, "2.x");
  write(d / "joints_s01_e01.txt", bad_number);
  r = read_utkinect(d);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find(":1: joint 1: '2.x' is not a number"), std::string::npos)
      << r.error().message;

  write(d / "joints_s01_e01.txt", utk_line(20) + utk_line(10));
  r = read_utkinect(d);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find(":2: frame id 10 after 20"), std::string::npos);

  write(d / "joints_s01_e01.txt", utk_frames(10, 30));
  write(d / "actionLabel.txt", "s01_e01\nwalk 10 30\n");
  r = read_utkinect(d);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("actionLabel.txt:2:"), std::string::npos);
  write(d / "actionLabel.txt", "walk: 10 30\n");
  r = read_utkinect(d);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("actionLabel.txt:1: segment before any"), std::string::npos);
  write(d / "actionLabel.txt", "s01_e01\nwalk: 30 10\n");
  EXPECT_FALSE(read_utkinect(d));

  EXPECT_FALSE(read_utkinect(d / "missing"));
  EXPECT_FALSE(read_action_dataset("kth", d));
}

TEST(UtkinectReader, NanJointsAreMissingNotAnError) {
  const fs::path d = fresh_dir("utk_nan");
  std::string line = utk_line(10);
  line.replace(line.find("2.5"), 3, "nan");
  write(d / "joints_s01_e01.txt", line + utk_frames(12, 20));
  write(d / "actionLabel.txt", "s01_e01\nwalk: 10 20\n");
  auto r = read_utkinect(d);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->items[0].frames[0].joint(JointId::kHipCenter).confidence, 0.f);
  EXPECT_EQ(r->items[0].frames[0].joint(JointId::kSpine).confidence, 1.f);
}

std::string msr_frame(double dx) {
  std::string s;
  for (int j = 0; j < 20; ++j) s += std::to_string(0.1 * j + dx) + " 0.5 2.6 1.0\n";
  return s;
}

TEST(MsrAction3dReader, ReadsSequencesAndRejectsTruncatedOnes) {
  const fs::path d = fresh_dir("msr");
  write(d / "a01_s01_e01_skeleton3D.txt", msr_frame(0) + msr_frame(0.01) + msr_frame(0.02));
  std::string zeros;
  for (int j = 0; j < 40; ++j) zeros += "0 0 0 0\n";
  write(d / "a13_s09_e02_skeleton3D.txt", zeros);  // the known all-zero file
  auto r = read_msr_action3d(d);
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->items.size(), 1u);
  EXPECT_EQ(r->skipped, 1);
  EXPECT_EQ(r->items[0].label, "high_arm_wave");
  EXPECT_EQ(r->items[0].subject, "s01");
  EXPECT_EQ(r->items[0].frames.size(), 3u);
  // MSR joint 20 is the head, joint 1 the left shoulder.
  EXPECT_NEAR(r->items[0].frames[0].joint(JointId::kHead).position_m[0], -1.9, 1e-9);
  EXPECT_NEAR(r->items[0].frames[0].joint(JointId::kShoulderLeft).position_m[0], 0.0, 1e-9);

  write(d / "a02_s01_e01_skeleton3D.txt", msr_frame(0) + "0.1 0.2 2.5 1\n");
  auto t = read_msr_action3d(d);
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().message.find("a02_s01_e01_skeleton3D.txt:21: truncated"), std::string::npos)
      << t.error().message;
  write(d / "a02_s01_e01_skeleton3D.txt", msr_frame(0) + "0.1 0.2 2.5\n");
  t = read_msr_action3d(d);
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().message.find(":21: expected 'x y z c'"), std::string::npos);
}

TEST(Parsers, SeedsAndGestureSegments) {
  EXPECT_EQ(*parse_seeds("3-5,9"), (std::vector<uint64_t>{3, 4, 5, 9}));
  EXPECT_EQ(*parse_seeds("7"), (std::vector<uint64_t>{7}));
  EXPECT_FALSE(parse_seeds("5-3"));
  EXPECT_FALSE(parse_seeds("a-b"));
  EXPECT_FALSE(parse_seeds(""));

  const fs::path d = fresh_dir("segments");
  write(d / "ok.txt", "# demonstrations\n1.0 2.5 spin\n\n3 4.25 spin  # second\n");
  auto s = read_gesture_segments(d / "ok.txt");
  ASSERT_TRUE(s) << s.error().message;
  ASSERT_EQ(s->size(), 2u);
  EXPECT_EQ((*s)[1].label, "spin");
  EXPECT_DOUBLE_EQ((*s)[1].end_s, 4.25);
  EXPECT_EQ((*s)[1].line, 4);
  write(d / "bad.txt", "1.0 2.5 spin\n2.0 spin\n");
  auto b = read_gesture_segments(d / "bad.txt");
  ASSERT_FALSE(b);
  EXPECT_NE(b.error().message.find("bad.txt:2:"), std::string::npos);
  write(d / "reversed.txt", "3.0 2.0 spin\n");
  EXPECT_FALSE(read_gesture_segments(d / "reversed.txt"));
  EXPECT_FALSE(read_gesture_segments(d / "absent.txt"));
}

}  // namespace
}  // namespace dreamsense::eval::actions
