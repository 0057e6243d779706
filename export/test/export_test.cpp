#include "dreamsense/export/writers.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace dreamsense::exporters {
namespace {
namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  auto d = fs::temp_directory_path() / ("ds_export_" + name + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(OutputFile, IsInvisibleUntilCommitted) {
  auto d = temp_dir("commit");
  {
    OutputFile f;
    ASSERT_TRUE(f.open(d / "a.txt"));
    ASSERT_TRUE(f.write("hello"));
    EXPECT_FALSE(fs::exists(d / "a.txt"));
    ASSERT_TRUE(f.commit());
  }
  EXPECT_TRUE(fs::exists(d / "a.txt"));
  {
    OutputFile f;
    ASSERT_TRUE(f.open(d / "b.txt"));
    ASSERT_TRUE(f.write("half"));
  }  // abandoned: a failed run leaves nothing that looks complete
  EXPECT_FALSE(fs::exists(d / "b.txt"));
  EXPECT_FALSE(fs::exists(d / "b.txt.partial"));
  fs::remove_all(d);
}

TEST(OutputFile, UnwritableFolderIsAClearError) {
  auto d = temp_dir("unwritable");
  std::ofstream(d / "file") << "x";
  auto s = ensure_writable_dir(d / "file" / "sub");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("file/sub"), std::string::npos);
  fs::remove_all(d);
}

TEST(EventLog, OkRecordsPublishLegacyValuesStatusChangesOnce) {
  auto d = temp_dir("events");
  EventLogWriter w;
  ASSERT_TRUE(w.open(d / "events.log", 0));
  for (int t = 0; t < 3; ++t) {
    primitives::PrimitiveRecord ok, off;
    ok.stamp = off.stamp = Timestamp::from_ns(t * 40'000'000LL);
    ok.id = primitives::PrimitiveId::kGetBody;
    ok.status = primitives::PrimitiveStatus::kOk;
    ok.legacy = std::vector<double>{1, 2, 3};
    off.id = primitives::PrimitiveId::kGetFaces;
    off.status = primitives::PrimitiveStatus::kDisabled;
    ASSERT_TRUE(w.write({ok, off}));
  }
  ASSERT_TRUE(w.commit());
  std::ifstream in(d / "events.log");
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0].rfind("getBody:o;", 0), 0u);
  EXPECT_NE(lines[0].find(";1.000000;2.000000;3.000000"), std::string::npos);
  EXPECT_NE(lines[1].find("getFaces:o;"), std::string::npos);
  EXPECT_NE(lines[1].find(";disabled"), std::string::npos);
  fs::remove_all(d);
}

TEST(DreamExport, FrameAlignedArraysWithNullsAndDreamJointNames) {
  DreamExport e;
  SkeletonBody b;
  b.joint(JointId::kHead) = {{0.1, -0.2, 1.1}, 1.f};
  e.add({b, cv::Vec3d(0, 0, -2), std::nullopt});
  e.add({std::nullopt, std::nullopt, std::nullopt});
  sources::SessionManifest m;
  m.participant.id = 3;
  m.condition = "RET";
  m.task = "TT";
  auto j = e.build(m);
  EXPECT_EQ(j["skeleton"]["head"]["x"][0], 100.0);
  EXPECT_TRUE(j["skeleton"]["head"]["x"][1].is_null());
  EXPECT_TRUE(j["skeleton"].contains("sholder_left"));
  EXPECT_EQ(j["head_gaze"]["rz"][0], -1.0) << "unit vector";
  EXPECT_TRUE(j["eye_gaze"]["rx"][0].is_null());
  EXPECT_EQ(j["participant"]["id"], 3);
  EXPECT_EQ(j["skeleton"]["hand_right"]["confidence"].size(), 2u);
}

}  // namespace
}  // namespace dreamsense::exporters

#include "dreamsense/export/report.hpp"

namespace dreamsense::exporters {
namespace {

TEST(HtmlReport, HasStatusTableAndTimelinesOfEnabledPrimitivesOnly) {
  HtmlReport report;
  for (int t = 0; t < 10; ++t) {
    primitives::PrimitiveRecord ok, off;
    ok.stamp = off.stamp = Timestamp::from_ns(t * 40'000'000LL);
    ok.id = primitives::PrimitiveId::kGetBody;
    ok.status = t == 5 ? primitives::PrimitiveStatus::kNoData : primitives::PrimitiveStatus::kOk;
    ok.legacy = std::vector<double>{1.0 * t, 2, 3};
    off.id = primitives::PrimitiveId::kGetFaces;
    off.status = primitives::PrimitiveStatus::kDisabled;
    report.add({ok, off});
  }
  sources::SessionManifest m;
  m.name = "a<b";
  const std::string html = report.build(m, {"10 ticks"});
  EXPECT_NE(html.find("a&lt;b"), std::string::npos) << "escaped";
  EXPECT_NE(html.find("<td>F3</td><td>getBody</td><td>9</td><td>1</td>"), std::string::npos);
  EXPECT_NE(html.find("getBody[0]"), std::string::npos);
  EXPECT_EQ(html.find("getFaces[0]"), std::string::npos) << "no timeline for a disabled one";
  EXPECT_NE(html.find("<svg"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::exporters
