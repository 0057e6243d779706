#include "dreamsense/batch/output_state.hpp"

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace dreamsense::batch {
namespace {
namespace fs = std::filesystem;
using test::TempDir;
using test::write_text;

const std::vector<std::string> kArgs = {"--overlay"};

void finish(const fs::path& dir, const std::string& input,
            const std::vector<std::string>& args = kArgs) {
  write_text(dir / kSummaryFile, "{\"ticks\": 3}\n");
  ASSERT_TRUE(write_done_record(dir, {input, args, 1.5, utc_now()}));
}

TEST(OutputState, AbsentFolder) {
  TempDir t;
  EXPECT_EQ(check_output(t / "x", "/in", kArgs).state, OutputState::kAbsent);
}

TEST(OutputState, FileInPlaceOfTheFolder) {
  TempDir t;
  write_text(t / "x", "not a folder");
  const auto c = check_output(t / "x", "/in", kArgs);
  EXPECT_EQ(c.state, OutputState::kNotAFolder);
  EXPECT_NE(c.why.find("not a folder"), std::string::npos);
  EXPECT_FALSE(remove_output(t / "x"));  // never removed: it is not ours
  EXPECT_TRUE(fs::exists(t / "x"));
}

TEST(OutputState, FinishedNeedsSummaryAndMatchingDoneRecord) {
  TempDir t;
  const fs::path d = t / "x";
  fs::create_directories(d);
  EXPECT_EQ(check_output(d, "/in", kArgs).state, OutputState::kPartial);
  EXPECT_NE(check_output(d, "/in", kArgs).why.find("summary.json"), std::string::npos);
  write_text(d / kSummaryFile, "{\"ticks\": 3}\n");
  const auto no_done = check_output(d, "/in", kArgs);
  EXPECT_EQ(no_done.state, OutputState::kPartial);
  EXPECT_NE(no_done.why.find(kDoneFile), std::string::npos) << no_done.why;
  finish(d, "/in");
  EXPECT_EQ(check_output(d, "/in", kArgs).state, OutputState::kFinished);
  // Another input's, or other flags': partial (redone).
  EXPECT_EQ(check_output(d, "/other", kArgs).state, OutputState::kPartial);
  const auto flags = check_output(d, "/in", {});
  EXPECT_EQ(flags.state, OutputState::kPartial);
  EXPECT_NE(flags.why.find("flags"), std::string::npos);
}

TEST(OutputState, DamagedSummaryOrDoneRecordIsPartial) {
  TempDir t;
  const fs::path d = t / "x";
  finish(d, "/in");
  write_text(d / kSummaryFile, "{\"ticks\": ");  // truncated
  EXPECT_EQ(check_output(d, "/in", kArgs).state, OutputState::kPartial);
  finish(d, "/in");
  write_text(d / kDoneFile, "[]");
  EXPECT_EQ(check_output(d, "/in", kArgs).state, OutputState::kPartial);
}

TEST(OutputState, DoneRecordRoundTrip) {
  TempDir t;
  ASSERT_TRUE(
      write_done_record(t.path(), {"/a b/c", {"--x", "y z"}, 2.25, "2024-01-02T03:04:05Z"}));
  auto r = read_done_record(t.path());
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->input, "/a b/c");
  EXPECT_EQ(r->analyze_args, (std::vector<std::string>{"--x", "y z"}));
  EXPECT_DOUBLE_EQ(r->seconds, 2.25);
  EXPECT_EQ(r->finished_utc, "2024-01-02T03:04:05Z");
  // Atomic write: no temporary file left beside it.
  size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(t.path())) ++files;
  EXPECT_EQ(files, 1u);
}

TEST(OutputState, RemovePartialFolder) {
  TempDir t;
  write_text(t / "x" / "sub" / "f", "1");
  ASSERT_TRUE(remove_output(t / "x"));
  EXPECT_FALSE(fs::exists(t / "x"));
  EXPECT_TRUE(remove_output(t / "x"));  // absent: nothing to do
}

}  // namespace
}  // namespace dreamsense::batch
