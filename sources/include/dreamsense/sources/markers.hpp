#pragma once
// Operator markers of a session (docs/session_format.md "Markers"): moments the person running
// the session marked (the operator page's "mark" button or key M in `live --ui`), stored as
// `markers.jsonl` beside session.yaml, one JSON object per line:
//
//   {"stamp_ns": 12345678901, "label": "mark", "source": "operator_page", "n": 1}
//
// stamp_ns is the session clock (the capture clock of the streams, never the wall clock), n the
// marker's number in the session (1-based). The file is optional (a session without markers has
// none); it is appended line by line and flushed per marker, so a crash loses at most the line
// being written, which the reader then skips (a torn last line without its '\n').

#include "dreamsense/core/status.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

namespace dreamsense::sources {

inline constexpr const char* kMarkersFile = "markers.jsonl";

struct SessionMarker {
  int64_t stamp_ns = 0;  // session clock
  std::string label = "mark";
  std::string source = "operator_page";
  int n = 0;  // 1-based number in the session
};

nlohmann::json to_json(const SessionMarker& marker);

// The markers of `session_dir` in file order (none when there is no markers.jsonl). A bad line
// (not JSON, no integer stamp_ns >= 0, a label that is not a string) is an error naming the file
// and line; a torn last line (no '\n', e.g. a crash while writing it) is skipped.
Result<std::vector<SessionMarker>> read_markers(const std::filesystem::path& session_dir);

// Appends markers to <session_dir>/markers.jsonl (created at the first marker); thread-safe.
class MarkerWriter {
 public:
  explicit MarkerWriter(std::filesystem::path session_dir) : dir_(std::move(session_dir)) {}
  Status append(const SessionMarker& marker);

 private:
  std::filesystem::path dir_;
  std::mutex mutex_;
  std::ofstream out_;
};

}  // namespace dreamsense::sources
