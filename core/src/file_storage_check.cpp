#include "dreamsense/core/file_storage_check.hpp"

#include "dreamsense/core/opencv_error.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <tinyxml2.h>
#include <vector>

namespace dreamsense {

namespace {

// As OpenCV 4.6 decides the format of a file it reads (persistence.cpp): the first bytes after an
// optional UTF-8 byte-order mark, "<?xml" = XML.
bool parsed_as_xml(std::string_view content) {
  constexpr std::string_view kBom = "\xEF\xBB\xBF";
  if (content.substr(0, kBom.size()) == kBom) content.remove_prefix(kBom.size());
  return content.substr(0, 5) == "<?xml";
}

// The values a matrix's dt declares per element ("3d" = 3, "d" = 1, "2f3i" = 5).
double values_per_element(const std::string& dt) {
  double total = 0;
  double count = 0;
  for (const char c : dt) {
    if (c >= '0' && c <= '9') {
      count = count * 10 + (c - '0');
    } else {
      total += count > 0 ? count : 1;
      count = 0;
    }
  }
  return total > 0 ? total : 1;
}

// A matrix (a map with `dt`, all cv::read(Mat) needs: rows and cols, or the `sizes` of an
// n-dimensional one) must hold the values its size declares. OpenCV 4.6 allocates the declared rows
// x cols before it compares them with the data, and reads a size that is not a number as INT_MAX: a
// file declaring 2^31 rows (fuzz/README.md finding 3), or rows "\xff3" (finding 7), asked for 17 GB
// of address space, which ASan took seconds to map and release.
Status check_matrix(const cv::FileNode& node, std::string_view where) {
  std::vector<cv::FileNode> sizes;
  if (!node["rows"].empty()) {
    sizes = {node["rows"], node["cols"]};
  } else if (const cv::FileNode nd = node["sizes"]; nd.isSeq()) {
    for (const auto& n : nd) sizes.push_back(n);
  } else {
    sizes.push_back(nd);
  }
  double declared = values_per_element(node["dt"].isString() ? node["dt"].string() : "");
  for (const auto& n : sizes) {
    if (!n.isInt() || static_cast<int>(n) < 0)
      return make_error(ErrorCode::kCorruptData,
                        "{}: matrix '{}' has a size that is not a non-negative integer", where,
                        node.name());
    declared *= static_cast<int>(n);
  }
  const cv::FileNode data = node["data"];
  const auto held = static_cast<double>(data.isSeq() ? data.size() : (data.isNone() ? 0 : 1));
  if (declared != held)
    return make_error(ErrorCode::kCorruptData, "{}: matrix '{}' declares {} values but holds {}",
                      where, node.name(), declared, held);
  return ok_status();
}

// Every matrix of the tree under `node`; nesting deeper than a FileStorage file of ours ever
// goes is not followed.
Status check_matrices(const cv::FileNode& node, std::string_view where, int depth) {
  constexpr int kMaxDepth = 64;
  if (depth > kMaxDepth || !(node.isMap() || node.isSeq())) return ok_status();
  if (node.isMap() && !node["dt"].empty()) return check_matrix(node, where);
  for (const auto& child : node) DS_RETURN_IF_ERROR(check_matrices(child, where, depth + 1));
  return ok_status();
}

}  // namespace

Result<cv::FileStorage> parse_file_storage(std::string_view content, std::string_view where) {
  if (const size_t nul = content.find('\0'); nul != std::string_view::npos)
    return make_error(ErrorCode::kCorruptData,
                      "{}: not a YAML/XML/JSON text file (NUL byte at offset {})", where, nul);
  if (parsed_as_xml(content)) {
    tinyxml2::XMLDocument doc;
    if (doc.Parse(content.data(), content.size()) != tinyxml2::XML_SUCCESS) {
      return make_error(ErrorCode::kCorruptData, "{}: line {}: malformed XML ({})", where,
                        doc.ErrorLineNum(), doc.ErrorName());
    }
  }
  // Only now may OpenCV parse it (its XML reader crashes on malformed XML).
  cv::FileStorage fs;
  try {
    if (!fs.open(std::string(content), cv::FileStorage::READ | cv::FileStorage::MEMORY))
      return make_error(ErrorCode::kCorruptData, "{}: not a YAML/XML/JSON file", where);
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: not a readable YAML/XML/JSON file ({})", where,
                      opencv_reason(e));
  }
  DS_RETURN_IF_ERROR(check_matrices(fs.root(), where, 0));
  return fs;
}

Result<cv::FileStorage> open_file_storage(const std::filesystem::path& path) {
  const std::string where = path.string();
  if (path.extension() == ".gz")
    return make_error(ErrorCode::kUnsupported,
                      "{}: compressed FileStorage files are not read (decompress it first)", where);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return make_error(ErrorCode::kIoError, "{}: cannot read ({})", where, std::strerror(errno));
  const std::string content{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) return make_error(ErrorCode::kIoError, "{}: read error", where);
  return parse_file_storage(content, where);
}

}  // namespace dreamsense
