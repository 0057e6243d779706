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

}  // namespace

Status check_file_storage_text(std::string_view content, std::string_view where) {
  if (const size_t nul = content.find('\0'); nul != std::string_view::npos)
    return make_error(ErrorCode::kCorruptData,
                      "{}: not a YAML/XML/JSON text file (NUL byte at offset {})", where, nul);
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
