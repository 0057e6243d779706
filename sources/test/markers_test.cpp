// Operator markers (markers.jsonl): written line by line, read back in order, a torn last line
// skipped, a bad line an error naming the file and line; `check` counts them.

#include "dreamsense/sources/markers.hpp"

#include "dreamsense/sources/session_check.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <unistd.h>

namespace dreamsense::sources {
namespace {
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(Markers, WrittenAndReadBackInOrder) {
  const fs::path dir = fresh_dir("ds_markers");
  auto none = read_markers(dir);
  ASSERT_TRUE(none) << none.error().message;
  EXPECT_TRUE(none->empty()) << "no markers.jsonl: no markers";
  MarkerWriter w(dir);
  ASSERT_TRUE(w.append({1'500'000'000, "mark", "operator_page", 1}));
  ASSERT_TRUE(w.append({7'250'000'000, "child left", "operator_page", 2}));
  auto read = read_markers(dir);
  ASSERT_TRUE(read) << read.error().message;
  ASSERT_EQ(read->size(), 2u);
  EXPECT_EQ((*read)[0].stamp_ns, 1'500'000'000);
  EXPECT_EQ((*read)[1].label, "child left");
  EXPECT_EQ((*read)[1].n, 2);
  // A crash while writing the third: its torn line is skipped.
  std::ofstream(dir / kMarkersFile, std::ios::app) << R"({"stamp_ns": 9000)";
  read = read_markers(dir);
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read->size(), 2u);
  fs::remove_all(dir);
}

TEST(Markers, BadLineIsAnErrorNamingFileAndLine) {
  const fs::path dir = fresh_dir("ds_markers_bad");
  std::ofstream(dir / kMarkersFile) << R"({"stamp_ns": 1, "label": "mark"})"
                                    << "\n"
                                    << R"({"stamp_ns": -5, "label": "mark"})"
                                    << "\n";
  auto read = read_markers(dir);
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().message.find("markers.jsonl:2"), std::string::npos)
      << read.error().message;
  std::ofstream(dir / kMarkersFile) << "not json\n";
  read = read_markers(dir);
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().message.find("markers.jsonl:1: not a JSON object"), std::string::npos)
      << read.error().message;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dreamsense::sources
