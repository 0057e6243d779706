#include "dreamsense/core/output_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <unistd.h>

namespace dreamsense {
namespace {
namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  auto d = fs::temp_directory_path() / ("ds_core_" + name + std::to_string(::getpid()));
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

}  // namespace
}  // namespace dreamsense

namespace dreamsense {
namespace {
namespace fs = std::filesystem;

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }
std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), {}};
}

TEST(StagedOutputDir, NothingAppearsUntilPublishedThenAllTogether) {
  const auto d = fs::temp_directory_path() / ("ds_core_staged" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  write_text(d / "summary.json", "old");
  write_text(d / "report.html", "old");
  write_text(d / "dream.json", "old");  // an earlier output this run does not write
  {
    auto s = StagedOutputDir::create(d);
    ASSERT_TRUE(s) << s.error().message;
    write_text(s->staged("report.html"), "new");
    write_text(s->staged("summary.json"), "new");
    EXPECT_EQ(read_text(d / "report.html"), "old");
    ASSERT_TRUE(s->publish({"report.html", "dream.json", "summary.json"}, "summary.json"));
  }
  EXPECT_EQ(read_text(d / "report.html"), "new");
  EXPECT_EQ(read_text(d / "summary.json"), "new");
  EXPECT_FALSE(fs::exists(d / "dream.json"));  // old and new never mix
  EXPECT_FALSE(fs::exists(d / StagedOutputDir::kStageName));
  fs::remove_all(d);
}

TEST(StagedOutputDir, AFailedRunLeavesTheFolderAsItWas) {
  const auto parent = fs::temp_directory_path() / ("ds_core_failed" + std::to_string(::getpid()));
  fs::remove_all(parent);
  fs::create_directories(parent / "kept");
  write_text(parent / "kept" / "summary.json", "old");
  {
    auto s = StagedOutputDir::create(parent / "kept");
    ASSERT_TRUE(s);
    write_text(s->staged("summary.json"), "half");
  }  // not published
  EXPECT_EQ(read_text(parent / "kept" / "summary.json"), "old");
  EXPECT_FALSE(fs::exists(parent / "kept" / StagedOutputDir::kStageName));
  {
    auto s = StagedOutputDir::create(parent / "new");
    ASSERT_TRUE(s);
    write_text(s->staged("primitives.jsonl"), "half");
  }
  EXPECT_FALSE(fs::exists(parent / "new"));  // a folder this run created goes again
  fs::remove_all(parent);
}

}  // namespace
}  // namespace dreamsense
