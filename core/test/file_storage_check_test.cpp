// open_file_storage (issue 18, fuzz/README.md finding 4): what may reach cv::FileStorage.
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

// A reproducer of fuzz/findings without the selector byte the harness reads first.
std::string finding_without_selector(const std::string& name) {
  std::ifstream in(fs::path(DREAMSENSE_SOURCE_DIR) / "fuzz/findings" / name, std::ios::binary);
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
    EXPECT_TRUE(open_file_storage(p)) << name;
    fs::remove(p);
  }
  // A UTF-8 byte-order mark before the XML declaration, as OpenCV accepts it.
  EXPECT_TRUE(parse_file_storage(
      "\xEF\xBB\xBF<?xml version=\"1.0\"?>\n<opencv_storage><a>1</a></opencv_storage>\n", "x"));
}

// The finding itself: a NUL byte inside an XML attribute after a cut tag.
TEST(FileStorageCheck, OpenCvXmlCrashFindingIsAnErrorNamingTheFile) {
  const std::string finding = finding_without_selector("opencv_xml_segv.calibration");
  ASSERT_EQ(finding.size(), 44u) << "fuzz/findings/opencv_xml_segv.calibration missing or changed";
  const fs::path p = write("ds_finding4.xml", finding);
  auto s = open_file_storage(p);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::kCorruptData);
  EXPECT_NE(s.error().message.find(p.string()), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("NUL byte at offset 42"), std::string::npos)
      << s.error().message;
  EXPECT_EQ(s.error().message.find('\n'), std::string::npos);
  // The same file without its NUL byte is still cut inside a tag: malformed XML, with its line.
  std::string no_nul = finding;
  no_nul.erase(no_nul.find('\0'), 1);
  s = parse_file_storage(no_nul, "cut.xml");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message.rfind("cut.xml: line 2: malformed XML (", 0), 0u)
      << s.error().message;
  fs::remove(p);
}

TEST(FileStorageCheck, MalformedFilesAreOneLineErrors) {
  EXPECT_FALSE(parse_file_storage("<?xml version=\"1.0\"?>\n<a><b></a>\n", "x.xml"));
  EXPECT_FALSE(parse_file_storage("<?xml version=\"1.0\"?>\n<a>\n", "x.xml"));
  // Not XML for OpenCV (no "<?xml" at the start): its YAML/JSON parsers' errors, on one line.
  for (const auto& [content, where] :
       {std::pair{"%YAML:1.0\n{ :", "x.yaml"}, std::pair{"{ \"a\": ", "x.json"},
        std::pair{"plain words", "x.txt"}}) {
    const auto s = parse_file_storage(content, where);
    ASSERT_FALSE(s) << content;
    EXPECT_EQ(s.error().code, ErrorCode::kCorruptData);
    EXPECT_EQ(s.error().message.rfind(where, 0), 0u) << s.error().message;
    EXPECT_EQ(s.error().message.find('\n'), std::string::npos) << s.error().message;
  }
  // No format may hold a NUL byte.
  EXPECT_FALSE(parse_file_storage(std::string("%YAML:1.0\na: 1\0\n", 16), "x.yaml"));
}

// fuzz/README.md findings 8, 11 and 12: OpenCV 4.6's YAML reader never returns on these (the
// first only when it reads a file, the others from memory too); all are refused before it sees
// them (a hang would fail this test by ctest's timeout).
TEST(FileStorageCheck, YamlThatIsNotOneMapDocumentIsRefused) {
  const fs::path p = write("ds_finding8.yaml", "%YAML:1.\n   cols: 0\n  <!-- :dt:May)\n");
  const auto finding8 = open_file_storage(p);
  ASSERT_FALSE(finding8);
  EXPECT_NE(finding8.error().message.find("more than one YAML document"), std::string::npos)
      << finding8.error().message;
  fs::remove(p);
  for (const char* content : {"%YAML:1.\n s:4\n<!--\n)", "%YAML:1.\n s:\xcb\n<H--\n.",
                              "%YAML:1.0\na: 1\n...\n-x\n", "%YAML:1.0\n- 1\n- 2\n",
                              // finding 13: yaml-cpp's LoadAll looped on these
                              "\xEF\xBB\xBF,", "%YAML:1.0\n---\n,\nb: 1\n", ","}) {
    const auto s = parse_file_storage(content, "mic_array.yaml");
    ASSERT_FALSE(s) << content;
    EXPECT_EQ(s.error().code, ErrorCode::kCorruptData);
  }
  // In XML a comment is fine; a YAML string may hold '#' and "<!--"; JSON is one map.
  EXPECT_TRUE(parse_file_storage(
      "<?xml version=\"1.0\"?>\n<opencv_storage><!-- c --><a>1</a></opencv_storage>\n", "c.xml"));
  EXPECT_TRUE(parse_file_storage("%YAML:1.0\n---\na: \"x # y <!--\"\n", "hash.yaml"));
  EXPECT_TRUE(parse_file_storage("{\n  \"a\": [1, 2]\n}\n", "a.json"));
}

TEST(FileStorageCheck, UnreadableAndCompressedFilesAreErrors) {
  const auto missing = open_file_storage(fs::path(::testing::TempDir()) / "ds_nothing.yaml");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kIoError);
  const fs::path gz = write("ds_model.yaml.gz", "%YAML:1.0\n");
  const auto compressed = open_file_storage(gz);
  ASSERT_FALSE(compressed);
  EXPECT_EQ(compressed.error().code, ErrorCode::kUnsupported);
  fs::remove(gz);
}

// fuzz/README.md findings 3 and 7: OpenCV allocates a declared rows x cols before reading the
// data, and takes a size that is not a number for INT_MAX.
TEST(FileStorageCheck, MatrixDeclaringMoreValuesThanItHoldsIsRefused) {
  for (const char* name : {"big.yaml", "big.xml", "big.json"}) {
    const fs::path p = fs::path(::testing::TempDir()) / name;
    {  // what OpenCV writes, a 40 x 30 matrix of 3 channels and an empty one: passes
      cv::FileStorage out(p.string(), cv::FileStorage::WRITE);
      out << "m" << cv::Mat(40, 30, CV_32FC3, cv::Scalar(1.5, 2, 3)) << "empty" << cv::Mat();
      out << "nested"
          << "{"
          << "n" << cv::Mat::eye(3, 3, CV_64F) << "}";
    }
    EXPECT_TRUE(open_file_storage(p)) << name;
    fs::remove(p);
  }
  const auto huge_rows = parse_file_storage(
      "%YAML:1.0\nK: !!opencv-matrix\n  rows: 2147483647\n  cols: 2\n  dt: d\n  data: [ 1 ]\n",
      "cam.yaml");
  ASSERT_FALSE(huge_rows);
  EXPECT_EQ(huge_rows.error().code, ErrorCode::kCorruptData);
  EXPECT_NE(huge_rows.error().message.find("cam.yaml"), std::string::npos);
  EXPECT_NE(huge_rows.error().message.find("matrix 'K'"), std::string::npos);
  // Each size small, the product not.
  EXPECT_FALSE(parse_file_storage(
      "<?xml version=\"1.0\"?>\n<opencv_storage><K type_id=\"opencv-matrix\"><rows>60000</rows>"
      "<cols>60000</cols><dt>d</dt><data>1</data></K></opencv_storage>\n",
      "cam.xml"));
  // A size that is not a number (read as INT_MAX), or is not an integer.
  for (const char* rows : {"\xff\xff"
                           "3",
                           "abc", "3.0e8", "-3"}) {
    const auto odd = parse_file_storage(
        std::string("<?xml version=\"1.0\"?>\n<opencv_storage><T type_id=\"x\"><rows>") + rows +
            "</rows><cols>1</cols><dt>d</dt><data>0 0 0</data></T></opencv_storage>\n",
        "obj.xml");
    ASSERT_FALSE(odd) << rows;
    EXPECT_NE(odd.error().message.find("not a non-negative integer"), std::string::npos) << rows;
  }
  // An element format OpenCV does not know, or with a zero count.
  for (const char* dt : {"q", "0d", "3", ""}) {
    EXPECT_FALSE(parse_file_storage(
        std::string("%YAML:1.0\nK: { rows: 1, cols: 1, dt: \"") + dt + "\", data: [ 1 ] }\n",
        "dt.yaml"))
        << dt;
  }
  // No data at all.
  EXPECT_FALSE(parse_file_storage("%YAML:1.0\nK: { rows: 60000, cols: 60000, dt: d }\n", "k.yaml"));
  // Sizes that agree with the data pass, in any map.
  EXPECT_TRUE(parse_file_storage(
      "%YAML:1.0\nouter:\n  - T: !!opencv-matrix\n      rows: 3\n      cols: 1\n      dt: d\n"
      "      data: [ 0., 0., 0. ]\n",
      "list.yaml"));
}

// Finding 7 as the fuzzer found it (selector 4, a DREAM ObjectFile.xml): refused at once.
TEST(FileStorageCheck, Finding7IsRefusedQuickly) {
  const std::string finding = finding_without_selector("opencv_int_max_rows.calibration");
  ASSERT_GT(finding.size(), 0U);
  const auto status = parse_file_storage(finding, "ObjectFile.xml");
  ASSERT_FALSE(status);
  EXPECT_NE(status.error().message.find("DeskWorld_T_mat"), std::string::npos);
}

// Finding 9: walking the parsed tree threw (a nameless node's name): an error, not a crash.
TEST(FileStorageCheck, Finding9IsAnErrorNotACrash) {
  const auto s = parse_file_storage(
      "%YAML:1.1.\xfd"
      "3\n   dt: =up",
      "mic_array.yaml");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::kCorruptData);
}

// Finding 10: OpenCV's base64 decoder loops for ever on some damaged blocks, so every block is
// checked first; the blocks OpenCV writes (YAML, XML, JSON) pass.
TEST(FileStorageCheck, DamagedBase64IsRefusedWrittenBase64Passes) {
  for (const char* name : {"b64.yaml", "b64.xml", "b64.json"}) {
    const fs::path p = fs::path(::testing::TempDir()) / name;
    {
      cv::FileStorage out(p.string(), cv::FileStorage::WRITE | cv::FileStorage::BASE64);
      out << "m" << cv::Mat(20, 128, CV_32F, cv::Scalar(0.25)) << "small"
          << cv::Mat::eye(2, 2, CV_64F);
    }
    const auto opened = open_file_storage(p);
    ASSERT_TRUE(opened) << name << ": " << opened.error().to_string();
    cv::Mat m;
    (*opened)["m"] >> m;
    EXPECT_EQ(m.rows, 20) << name;
    fs::remove(p);
  }
  const std::string finding = finding_without_selector("opencv_base64_hang.models");
  ASSERT_GT(finding.size(), 0U);
  const auto hang = parse_file_storage(finding, "face_gallery.yaml");
  ASSERT_FALSE(hang);
  EXPECT_NE(hang.error().message.find("face_gallery.yaml: line 14: damaged base64 data"),
            std::string::npos)
      << hang.error().message;
  // A header whose element format has a zero count, and a cut block.
  const std::string zero_count = "MGYgICAgICAgICAgICAgICAgICAgICAgAADAPw==";  // "0f" + spaces
  EXPECT_FALSE(parse_file_storage(
      "{\n \"m\": { \"rows\": 1, \"cols\": 1, \"dt\": \"f\", \"data\": \"$base64$" + zero_count +
          "\" }\n}\n",
      "zero.json"));
  EXPECT_FALSE(parse_file_storage(
      "%YAML:1.0\nm: !!opencv-matrix\n   rows: 1\n   cols: 1\n   dt: f\n   data: !!binary |\n"
      "      MWYgICAgICAg\n",
      "cut.yaml"));
}

}  // namespace
}  // namespace dreamsense
