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
