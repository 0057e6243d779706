#include "dreamsense/core/file_storage_check.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <tinyxml2.h>

namespace dreamsense {

namespace {

// As OpenCV 4.6 decides the format of a file it reads (persistence.cpp): the first bytes after an
// optional UTF-8 byte-order mark, "<?xml" = XML.
bool parsed_as_xml(std::string_view content) {
  constexpr std::string_view kBom = "\xEF\xBB\xBF";
  if (content.substr(0, kBom.size()) == kBom) content.remove_prefix(kBom.size());
  return content.substr(0, 5) == "<?xml";
}

// The number after a key `name` as OpenCV writes a matrix's size in its three formats (YAML
// `rows: 3`, XML `<rows>3</rows>`, JSON `"rows": 3`), from `pos` (just after the name); -1 when no
// number follows.
double declared_number(std::string_view content, size_t pos) {
  while (pos < content.size() && std::strchr(" \t\"':>=", content[pos]) != nullptr) ++pos;
  if (pos >= content.size() || content[pos] < '0' || content[pos] > '9') return -1;
  double v = 0;
  for (; pos < content.size() && content[pos] >= '0' && content[pos] <= '9'; ++pos)
    v = v * 10 + (content[pos] - '0');
  return v;
}

// A matrix cannot hold more elements than its file has bytes (each element takes at least one
// byte of text), yet OpenCV allocates a matrix's declared rows x cols before it reads the data
// (fuzz/README.md finding 3: 2^31 declared rows = 17 GB of address space). The first
// rows/cols pair that claims more is reported.
Status check_declared_sizes(std::string_view content, std::string_view where) {
  const auto limit = static_cast<double>(content.size());
  double rows = -1;
  for (size_t pos = 0; pos + 4 <= content.size(); ++pos) {
    const std::string_view key = content.substr(pos, 4);
    if (key != "rows" && key != "cols") continue;
    const double v = declared_number(content, pos + 4);
    if (v < 0) continue;
    const double elements = key == "rows" || rows < 0 ? v : rows * v;
    if (elements > limit)
      return make_error(ErrorCode::kCorruptData,
                        "{}: a matrix declares {} elements ({} {}), more than the file's {} bytes "
                        "can hold",
                        where, elements, key, v, content.size());
    if (key == "rows") rows = v;
  }
  return ok_status();
}

}  // namespace

Status check_file_storage_text(std::string_view content, std::string_view where) {
  if (const size_t nul = content.find('\0'); nul != std::string_view::npos)
    return make_error(ErrorCode::kCorruptData,
                      "{}: not a YAML/XML/JSON text file (NUL byte at offset {})", where, nul);
  if (auto sizes = check_declared_sizes(content, where); !sizes) return sizes;
  if (!parsed_as_xml(content)) return ok_status();
  tinyxml2::XMLDocument doc;
  if (doc.Parse(content.data(), content.size()) != tinyxml2::XML_SUCCESS) {
    return make_error(ErrorCode::kCorruptData, "{}: line {}: malformed XML ({})", where,
                      doc.ErrorLineNum(), doc.ErrorName());
  }
  return ok_status();
}

Status check_file_storage_input(const std::filesystem::path& path) {
  const std::string where = path.string();
  if (path.extension() == ".gz")
    return make_error(ErrorCode::kUnsupported,
                      "{}: compressed FileStorage files are not read (decompress it first)", where);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    return make_error(ErrorCode::kIoError, "{}: cannot read ({})", where, std::strerror(errno));
  const std::string content{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) return make_error(ErrorCode::kIoError, "{}: read error", where);
  return check_file_storage_text(content, where);
}

}  // namespace dreamsense
