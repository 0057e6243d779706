#include "dreamsense/sources/markers.hpp"

#include <fmt/format.h>

#include <sstream>

namespace dreamsense::sources {

namespace fs = std::filesystem;

nlohmann::json to_json(const SessionMarker& m) {
  return {{"stamp_ns", m.stamp_ns}, {"label", m.label}, {"source", m.source}, {"n", m.n}};
}

Result<std::vector<SessionMarker>> read_markers(const fs::path& session_dir) {
  std::vector<SessionMarker> out;
  const fs::path file = session_dir / kMarkersFile;
  std::error_code ec;
  if (!fs::exists(file, ec)) return out;
  std::ifstream in(file, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIoError, "{}: cannot read", file.string());
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  size_t line_no = 0;
  for (size_t pos = 0; pos < text.size();) {
    const size_t end = text.find('\n', pos);
    ++line_no;
    if (end == std::string::npos) break;  // a torn last line: the marker being written
    const std::string line = text.substr(pos, end - pos);
    pos = end + 1;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto j = nlohmann::json::parse(line, nullptr, false);
    auto bad = [&](const std::string& what) {
      return make_error(ErrorCode::kInvalidArgument, "{}:{}: {}", file.string(), line_no, what);
    };
    if (j.is_discarded() || !j.is_object()) return bad("not a JSON object");
    if (!j.contains("stamp_ns") || !j["stamp_ns"].is_number_integer() ||
        j["stamp_ns"].get<int64_t>() < 0)
      return bad("stamp_ns must be an integer >= 0 (session clock, ns)");
    SessionMarker m;
    m.stamp_ns = j["stamp_ns"].get<int64_t>();
    if (j.contains("label")) {
      if (!j["label"].is_string()) return bad("label must be a string");
      m.label = j["label"].get<std::string>();
    }
    if (j.contains("source") && j["source"].is_string()) m.source = j["source"].get<std::string>();
    m.n = j.contains("n") && j["n"].is_number_integer() ? j["n"].get<int>()
                                                        : static_cast<int>(out.size()) + 1;
    out.push_back(std::move(m));
  }
  return out;
}

Status MarkerWriter::append(const SessionMarker& marker) {
  std::lock_guard lock(mutex_);
  const fs::path file = dir_ / kMarkersFile;
  if (!out_.is_open()) {
    out_.open(file, std::ios::binary | std::ios::app);
    if (!out_) return make_error(ErrorCode::kIoError, "{}: cannot write", file.string());
  }
  out_ << to_json(marker).dump() << '\n';
  out_.flush();
  if (!out_) return make_error(ErrorCode::kIoError, "{}: write failed", file.string());
  return ok_status();
}

}  // namespace dreamsense::sources
