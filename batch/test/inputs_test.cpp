#include "dreamsense/batch/inputs.hpp"

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace dreamsense::batch {
namespace {
namespace fs = std::filesystem;
using test::make_session;
using test::TempDir;
using test::write_text;

const PlannedInput* find(const std::vector<PlannedInput>& v, const std::string& filename) {
  for (const auto& p : v)
    if (p.path.filename() == filename) return &p;
  return nullptr;
}

TEST(Inputs, SessionFolderIsOneSession) {
  TempDir t;
  make_session(t / "s1");
  const auto v = expand_inputs({(t / "s1").string()});
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].kind, InputKind::kSession);
  EXPECT_EQ(v[0].status, PlanStatus::kRun);
  EXPECT_EQ(v[0].path, fs::canonical(t / "s1"));
  EXPECT_EQ(v[0].name.rfind("s1-", 0), 0u) << v[0].name;
}

TEST(Inputs, SessionYamlStandsForItsFolder) {
  TempDir t;
  make_session(t / "s1");
  const auto v = expand_inputs({(t / "s1" / "session.yaml").string()});
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].kind, InputKind::kSession);
  EXPECT_EQ(v[0].path, fs::canonical(t / "s1"));
}

TEST(Inputs, VideoFilesByExtensionAnyCase) {
  TempDir t;
  write_text(t / "a.mp4", "x");
  write_text(t / "b.AVI", "x");
  const auto v = expand_inputs({(t / "a.mp4").string(), (t / "b.AVI").string()});
  ASSERT_EQ(v.size(), 2u);
  for (const auto& p : v) {
    EXPECT_EQ(p.kind, InputKind::kVideo);
    EXPECT_EQ(p.status, PlanStatus::kRun);
  }
  EXPECT_EQ(v[0].name.rfind("a-", 0), 0u) << v[0].name;
  EXPECT_EQ(v[1].name.rfind("b-", 0), 0u) << v[1].name;
}

TEST(Inputs, ZeroLengthVideoFails) {
  TempDir t;
  write_text(t / "empty.mp4", "");
  const auto v = expand_inputs({(t / "empty.mp4").string()});
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].status, PlanStatus::kFailed);
  EXPECT_NE(v[0].reason.find("empty file"), std::string::npos) << v[0].reason;
  EXPECT_TRUE(v[0].name.empty());
}

TEST(Inputs, MissingPathAndOtherFilesFailWithReason) {
  TempDir t;
  write_text(t / "notes.txt", "hello");
  const auto v = expand_inputs({(t / "nope").string(), (t / "notes.txt").string()});
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v[0].status, PlanStatus::kFailed);
  EXPECT_NE(v[0].reason.find("no such file"), std::string::npos) << v[0].reason;
  EXPECT_EQ(v[1].status, PlanStatus::kFailed);
  EXPECT_NE(v[1].reason.find("session.yaml"), std::string::npos) << v[1].reason;
  EXPECT_NE(v[1].reason.find(".mp4"), std::string::npos) << v[1].reason;
}

TEST(Inputs, FolderOfVideosListsTheRestAsSkipped) {
  TempDir t;
  const fs::path d = t / "videos";
  write_text(d / "b.mp4", "x");
  write_text(d / "a.mkv", "x");
  write_text(d / "notes.txt", "x");
  write_text(d / "README", "x");
  write_text(d / ".hidden.mp4", "x");
  fs::create_directories(d / "thumbs");
  make_session(d / "s9");
  const auto v = expand_inputs({d.string()});
  // Sorted by name: README, a.mkv, b.mp4, notes.txt, s9, thumbs; the hidden file is ignored.
  ASSERT_EQ(v.size(), 6u);
  EXPECT_EQ(v[0].path.filename(), "README");
  EXPECT_EQ(v[0].status, PlanStatus::kSkipped);
  EXPECT_NE(v[0].reason.find("no extension"), std::string::npos);
  EXPECT_EQ(v[1].path.filename(), "a.mkv");
  EXPECT_EQ(v[1].kind, InputKind::kVideo);
  EXPECT_EQ(v[1].status, PlanStatus::kRun);
  EXPECT_EQ(v[2].path.filename(), "b.mp4");
  EXPECT_EQ(v[2].status, PlanStatus::kRun);
  EXPECT_EQ(v[3].path.filename(), "notes.txt");
  EXPECT_EQ(v[3].status, PlanStatus::kSkipped);
  EXPECT_NE(v[3].reason.find(".txt"), std::string::npos) << v[3].reason;
  EXPECT_EQ(v[4].path.filename(), "s9");
  EXPECT_EQ(v[4].kind, InputKind::kSession);
  EXPECT_EQ(v[4].status, PlanStatus::kRun);
  EXPECT_EQ(v[5].path.filename(), "thumbs");
  EXPECT_EQ(v[5].status, PlanStatus::kSkipped);
  EXPECT_EQ(find(v, ".hidden.mp4"), nullptr);
}

TEST(Inputs, FolderWithoutAnyInputFails) {
  TempDir t;
  write_text(t / "docs" / "a.pdf", "x");
  const auto v = expand_inputs({(t / "docs").string()});
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v[0].status, PlanStatus::kFailed);
  EXPECT_EQ(v[0].path.filename(), "docs");
  EXPECT_NE(v[0].reason.find("no session.yaml"), std::string::npos) << v[0].reason;
  EXPECT_EQ(v[1].status, PlanStatus::kSkipped);
}

TEST(Inputs, DuplicatesAreKeptOnce) {
  TempDir t;
  make_session(t / "s1");
  fs::create_directory_symlink(t / "s1", t / "link");
  const auto v =
      expand_inputs({(t / "s1").string(), (t / "s1/").string(), (t / "s1" / ".." / "s1").string(),
                     (t / "link").string(), t.path().string()});
  // The folder argument expands to link and s1 again.
  ASSERT_EQ(v.size(), 6u);
  EXPECT_EQ(v[0].status, PlanStatus::kRun);
  for (size_t i = 1; i < v.size(); ++i) {
    EXPECT_EQ(v[i].status, PlanStatus::kSkipped) << i;
    EXPECT_NE(v[i].reason.find("duplicate of " + (t / "s1").string()), std::string::npos)
        << v[i].reason;
  }
}

TEST(Inputs, EqualBasenamesGetDifferentStableNames) {
  TempDir t;
  make_session(t / "a" / "rec");
  make_session(t / "b" / "rec");
  write_text(t / "c" / "rec.mp4", "x");
  const auto v = expand_inputs(
      {(t / "a" / "rec").string(), (t / "b" / "rec").string(), (t / "c" / "rec.mp4").string()});
  ASSERT_EQ(v.size(), 3u);
  EXPECT_NE(v[0].name, v[1].name);
  EXPECT_NE(v[0].name, v[2].name);
  EXPECT_NE(v[1].name, v[2].name);
  for (const auto& p : v) EXPECT_EQ(p.name.rfind("rec-", 0), 0u) << p.name;
  // A name depends only on its own input: alone, or after other inputs, it is the same.
  const auto alone = expand_inputs({(t / "b" / "rec").string()});
  EXPECT_EQ(alone[0].name, v[1].name);
  EXPECT_EQ(output_name(v[1].path), v[1].name);
}

TEST(Inputs, OutputNameIsSafeForAFolder) {
  const std::string n = output_name("/data/my session (1)/.x\xc3\xa9");
  EXPECT_EQ(n.rfind("_x__-", 0), 0u) << n;
  for (char c : n)
    EXPECT_TRUE(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')
        << n;
  EXPECT_EQ(output_name("/data/clip.mp4").rfind("clip-", 0), 0u);
  EXPECT_EQ(output_name("/data/clip.mp4").size(), std::string("clip-").size() + 8);
  EXPECT_NE(output_name("/data/clip.mp4"), output_name("/data/clip.avi"));
}

TEST(Inputs, OptionsCheck) {
  InputOptions o;
  EXPECT_TRUE(o.check());
  o.video_extensions = {"mp4"};
  EXPECT_FALSE(o.check());
}

}  // namespace
}  // namespace dreamsense::batch
