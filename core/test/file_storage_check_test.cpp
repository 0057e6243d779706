// check_file_storage_input (issue 18, fuzz/README.md finding 4): what may reach cv::FileStorage.
#include "dreamsense/core/file_storage_check.hpp"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace dreamsense {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& content) {
  const fs::path p = fs::path(::testing::TempDir()) / name;
  std::ofstream(p, std::ios::binary) << content;
  return p;
}

std::string finding_without_selector() {
  std::ifstream in(fs::path(DREAMSENSE_SOURCE_DIR) / "fuzz/findings/opencv_xml_segv.calibration",
                   std::ios::binary);
  std::string s{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  return s.empty() ? s : s.substr(1);
}

TEST(FileStorageCheck, FilesOpenCvWritesPass) {
  for (const char* name : {"ok.yaml", "ok.xml", "ok.json"}) {
    const fs::path p = fs::path(::testing::TempDir()) / name;
    {
      cv::FileStorage out(p.string(), cv::FileStorage::WRITE);
      out << "format"
          << "test"
          << "m" << cv::Mat::eye(3, 3, CV_64F);
    }
    EXPECT_TRUE(check_file_storage_input(p)) << name;
    fs::remove(p);
  }
  // A UTF-8 byte-order mark before the XML declaration, as OpenCV accepts it.
  EXPECT_TRUE(check_file_storage_text(
      "\xEF\xBB\xBF<?xml version=\"1.0\"?>\n<opencv_storage><a>1</a></opencv_storage>\n", "x"));
}

// The finding itself: a NUL byte inside an XML attribute after a cut tag.
TEST(FileStorageCheck, OpenCvXmlCrashFindingIsAnErrorNamingTheFile) {
  const std::string finding = finding_without_selector();
  ASSERT_EQ(finding.size(), 44u) << "fuzz/findings/opencv_xml_segv.calibration missing or changed";
  const fs::path p = write("ds_finding4.xml", finding);
  auto s = check_file_storage_input(p);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::kCorruptData);
  EXPECT_NE(s.error().message.find(p.string()), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("NUL byte at offset 42"), std::string::npos)
      << s.error().message;
  EXPECT_EQ(s.error().message.find('\n'), std::string::npos);
  // The same file without its NUL byte is still cut inside a tag: malformed XML, with its line.
  std::string no_nul = finding;
  no_nul.erase(no_nul.find('\0'), 1);
  s = check_file_storage_text(no_nul, "cut.xml");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message.rfind("cut.xml: line 2: malformed XML (", 0), 0u)
      << s.error().message;
  fs::remove(p);
}

TEST(FileStorageCheck, MalformedXmlIsRefusedOtherFormatsAreLeftToOpenCv) {
  EXPECT_FALSE(check_file_storage_text("<?xml version=\"1.0\"?>\n<a><b></a>\n", "x.xml"));
  EXPECT_FALSE(check_file_storage_text("<?xml version=\"1.0\"?>\n<a>\n", "x.xml"));
  // Not XML for OpenCV (no "<?xml" at the start): its YAML/JSON parsers report their own errors.
  EXPECT_TRUE(check_file_storage_text("%YAML:1.0\n{ :", "x.yaml"));
  EXPECT_TRUE(check_file_storage_text("{ \"a\": ", "x.json"));
  // But no format may hold a NUL byte.
  EXPECT_FALSE(check_file_storage_text(std::string("%YAML:1.0\na: 1\0\n", 16), "x.yaml"));
}

TEST(FileStorageCheck, UnreadableAndCompressedFilesAreErrors) {
  const auto missing = check_file_storage_input(fs::path(::testing::TempDir()) / "ds_nothing.yaml");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kIoError);
  const fs::path gz = write("ds_model.yaml.gz", "%YAML:1.0\n");
  const auto compressed = check_file_storage_input(gz);
  ASSERT_FALSE(compressed);
  EXPECT_EQ(compressed.error().code, ErrorCode::kUnsupported);
  fs::remove(gz);
}

// fuzz/README.md finding 3: OpenCV allocates a declared rows x cols before reading the data.
TEST(FileStorageCheck, MatrixDeclaringMoreElementsThanTheFileHoldsIsRefused) {
  for (const char* name : {"big.yaml", "big.xml", "big.json"}) {
    const fs::path p = fs::path(::testing::TempDir()) / name;
    {  // what OpenCV writes, a 40 x 30 matrix: passes
      cv::FileStorage out(p.string(), cv::FileStorage::WRITE);
      out << "m" << cv::Mat(40, 30, CV_32F, cv::Scalar(1.5));
    }
    EXPECT_TRUE(check_file_storage_input(p)) << name;
    fs::remove(p);
  }
  const auto huge_rows = check_file_storage_text(
      "%YAML:1.0\nK: !!opencv-matrix\n  rows: 2147483648\n  cols: 2\n  dt: d\n  data: [ 1 ]\n",
      "cam.yaml");
  ASSERT_FALSE(huge_rows);
  EXPECT_EQ(huge_rows.error().code, ErrorCode::kCorruptData);
  EXPECT_NE(huge_rows.error().message.find("cam.yaml"), std::string::npos);
  EXPECT_NE(huge_rows.error().message.find("2147483648"), std::string::npos);
  // Each size small, the product not.
  EXPECT_FALSE(check_file_storage_text(
      "<?xml version=\"1.0\"?>\n<opencv_storage><K type_id=\"opencv-matrix\"><rows>60000</rows>"
      "<cols>60000</cols><dt>d</dt><data>1</data></K></opencv_storage>\n",
      "cam.xml"));
}

}  // namespace
}  // namespace dreamsense
