#include "dreamsense/core/file_storage_check.hpp"

#include "dreamsense/core/opencv_error.hpp"
#include "dreamsense/core/text.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
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

bool is_base64_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '+' || c == '/' || c == '=';
}

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  return c == '+' ? 62 : (c == '/' ? 63 : 0);
}

// What the top level of a YAML document is, from yaml-cpp's parse events (no nodes are built).
class TopLevelKind final : public YAML::EventHandler {
 public:
  bool is_map() const { return kind_ == Kind::kMap; }
  void OnDocumentStart(const YAML::Mark& /*mark*/) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& /*mark*/, YAML::anchor_t /*anchor*/) override { top(Kind::kOther); }
  void OnAlias(const YAML::Mark& /*mark*/, YAML::anchor_t /*anchor*/) override {
    top(Kind::kOther);
  }
  void OnScalar(const YAML::Mark& /*mark*/, const std::string& /*tag*/, YAML::anchor_t /*anchor*/,
                const std::string& /*value*/) override {
    top(Kind::kOther);
  }
  void OnSequenceStart(const YAML::Mark& /*mark*/, const std::string& /*tag*/,
                       YAML::anchor_t /*anchor*/, YAML::EmitterStyle::value /*style*/) override {
    top(Kind::kOther);
    ++depth_;
  }
  void OnSequenceEnd() override { --depth_; }
  void OnMapStart(const YAML::Mark& /*mark*/, const std::string& /*tag*/, YAML::anchor_t /*anchor*/,
                  YAML::EmitterStyle::value /*style*/) override {
    top(Kind::kMap);
    ++depth_;
  }
  void OnMapEnd() override { --depth_; }

 private:
  enum class Kind { kNone, kMap, kOther };
  void top(Kind kind) {
    if (depth_ == 0 && kind_ == Kind::kNone) kind_ = kind;
  }
  Kind kind_ = Kind::kNone;
  int depth_ = 0;
};

// OpenCV 4.6's YAML reader loops for ever when its first document ends before the file does and
// what follows is not a document marker (after the root collection it skips three characters
// and expects "---"; fuzz/README.md findings 8, 11 and 12), and refuses a top level that is not a
// collection anyway. So a YAML or JSON file must first be, for yaml-cpp, one document whose top
// level is a map (OpenCV's "%YAML:1.0" first line is not YAML and is left out). The documents are
// asked for one at a time: yaml-cpp's LoadAll loops for ever on a stray ',' (finding 13).
Status check_yaml_structure(std::string_view content, std::string_view where) {
  std::string yaml(content);
  if (yaml.rfind("%YAML", 0) == 0) yaml.replace(0, yaml.find('\n'), "");
  std::istringstream in(yaml);
  try {
    YAML::Parser parser(in);
    TopLevelKind first;
    if (!parser.HandleNextDocument(first) || !first.is_map())
      return make_error(ErrorCode::kCorruptData,
                        "{}: not a YAML/JSON document with a map at its top level", where);
    TopLevelKind second;
    if (parser.HandleNextDocument(second))
      return make_error(ErrorCode::kCorruptData, "{}: more than one YAML document", where);
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: line {}: malformed YAML/JSON ({})", where,
                      e.mark.line + 1, e.msg);
  }
  return ok_status();
}

// The values per element of a format as OpenCV writes one ("f" = 1, "3d" = 3, "2f3i" = 5: type
// letters, each after an optional count of at least 1); nullopt for anything else.
std::optional<double> values_per_element(std::string_view dt) {
  double total = 0;
  int count = -1;
  for (const char c : dt) {
    if (c >= '0' && c <= '9') {
      count = (count < 0 ? 0 : count * 10) + (c - '0');
      if (count > 1'000'000) return std::nullopt;
    } else if (c != '\0' && std::strchr("ucwsifdhr", c) != nullptr && count != 0) {
      total += count < 0 ? 1 : count;
      count = -1;
    } else {
      return std::nullopt;
    }
  }
  if (total == 0 || count >= 0) return std::nullopt;
  return total;
}

// One base64 block (`payload`, starting on line `line`): only base64 characters and white space,
// whole 4-character groups, and a header (the first 24 bytes) naming a valid element format.
Status check_base64_block(std::string_view payload, std::string_view where, size_t line) {
  std::string text;
  for (const char c : payload) {
    if (is_base64_char(c)) {
      text += c;
    } else if (std::isspace(static_cast<unsigned char>(c)) == 0) {
      return make_error(ErrorCode::kCorruptData, "{}: line {}: damaged base64 data ('{}')", where,
                        line, c);
    }
  }
  constexpr size_t kHeaderChars = 32;  // 24 bytes
  if (text.size() % 4 != 0 || text.size() < kHeaderChars)
    return make_error(ErrorCode::kCorruptData, "{}: line {}: damaged base64 data (length {})",
                      where, line, text.size());
  std::string header;
  for (size_t i = 0; i < kHeaderChars; i += 4) {
    const int v = (base64_value(text[i]) << 18) | (base64_value(text[i + 1]) << 12) |
                  (base64_value(text[i + 2]) << 6) | base64_value(text[i + 3]);
    header += static_cast<char>((v >> 16) & 0xFF);
    header += static_cast<char>((v >> 8) & 0xFF);
    header += static_cast<char>(v & 0xFF);
  }
  const std::string_view dt =
      std::string_view(header).substr(0, std::min(header.find(' '), header.find('\0')));
  if (!values_per_element(dt))
    return make_error(ErrorCode::kCorruptData,
                      "{}: line {}: damaged base64 data (no element format in its header)", where,
                      line);
  return ok_status();
}

// OpenCV's base64 decoder loops for ever on some damaged blocks (fuzz/README.md finding 10), so
// every block is checked before OpenCV sees it: YAML `!!binary |` and the lines indented below
// it, XML `type_id="binary">` up to the next tag, JSON `"$base64$` up to the closing quote.
Status check_base64_blocks(std::string_view content, std::string_view where) {
  for (const std::string_view marker : {"!!binary", "type_id=\"binary\">", "$base64$"}) {
    for (size_t at = content.find(marker); at != std::string_view::npos;
         at = content.find(marker, at + 1)) {
      size_t begin = at + marker.size();
      size_t end = content.size();
      if (marker == "!!binary") {
        // The block: the rest of the marker's line after '|', then every following line that is
        // blank or indented deeper than the marker's line.
        const size_t newline = content.rfind('\n', at);
        const size_t line_start = newline == std::string_view::npos ? 0 : newline + 1;
        const size_t indent = content.find_first_not_of(" \t", line_start) - line_start;
        begin = std::min(content.find_first_not_of(" \t", begin), content.size());
        if (begin < content.size() && content[begin] == '|') ++begin;
        end = std::min(content.find('\n', begin), content.size());
        while (end < content.size()) {
          const size_t next = end + 1;
          const size_t eol = std::min(content.find('\n', next), content.size());
          const size_t first = content.find_first_not_of(" \t\r", next);
          if (first < eol && first - next <= indent) break;
          end = eol;
        }
      } else {
        end = std::min(end, content.find(marker[0] == '$' ? '"' : '<', begin));
      }
      DS_RETURN_IF_ERROR(check_base64_block(content.substr(begin, end - begin), where,
                                            line_of_offset(content, begin)));
    }
  }
  return ok_status();
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
  const auto per_element = values_per_element(node["dt"].isString() ? node["dt"].string() : "");
  if (!per_element)
    return make_error(ErrorCode::kCorruptData, "{}: matrix '{}' has no valid element format (dt)",
                      where, node.name());
  double declared = *per_element;
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
  } else {
    DS_RETURN_IF_ERROR(check_yaml_structure(content, where));
  }
  DS_RETURN_IF_ERROR(check_base64_blocks(content, where));
  // Only now may OpenCV parse it (its XML reader crashes on malformed XML).
  cv::FileStorage fs;
  try {
    if (!fs.open(std::string(content), cv::FileStorage::READ | cv::FileStorage::MEMORY))
      return make_error(ErrorCode::kCorruptData, "{}: not a YAML/XML/JSON file", where);
    // Walking the tree throws too on some (fuzz/README.md finding 9: a nameless node's name).
    DS_RETURN_IF_ERROR(check_matrices(fs.root(), where, 0));
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: not a readable YAML/XML/JSON file ({})", where,
                      opencv_reason(e));
  }
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
