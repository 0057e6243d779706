#pragma once
// CSV tables of an analysis (`analyze --csv`, docs/outputs.md), made from primitives.jsonl so
// that every primitive, also one added later, gets its table without code here:
//
//   tables/F01_checkMutualGaze.csv ... one file per primitive that was evaluated (not disabled):
//       one row per tick; fixed columns time_s, stamp_ns, status, ok (1/0: the success flag),
//       confidence, source, data_stamp_ns; then the record's "query" and "value" flattened
//       (query.*, then the value's members by name; nested objects joined with '.', numeric
//       arrays of 2/3 as .x .y (.z), 4-number boxes (a name with "box") as .x .y .w .h, other
//       arrays by index, lists of objects as NAME.count plus the first 5 items NAME.0.* ...
//       NAME.4.*). Units are the JSON's: names end in _m, _deg, _px, _s, _ns, _mps (primitives.md).
//       The value columns are the union over the session in a fixed order (path segments
//       compared by name, numbers numerically); a cell is empty when the row has no such value.
//   tables/ticks.csv: the per-primitive tables side by side, one row per tick: time_s, stamp_ns,
//       then per evaluated primitive (catalogue order) <name>.ok, <name>.confidence and its value
//       columns as <name>.<column> (name reduced to [A-Za-z0-9_], e.g. getHeadGaze.yaw_deg).
//   tables/events.csv: episodes (type, label, start_s, end_s, duration_s, source, detail), see
//       write_csv_tables.
//   tables/tables.json: the files, their columns, and approximate_calibration.
// RFC 4180 quoting, '\n' line ends, '.' decimal point. pandas: pd.read_csv(path).

#include "dreamsense/core/status.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace dreamsense::exporters {

struct CsvTablesOptions {
  // The camera intrinsics were assumed (a plain video without calibration): 3-D values are
  // approximate. Written into tables.json.
  bool approximate_calibration = false;
  int max_list_items = 5;  // items of a list of objects given their own columns
  // What mutual gaze is with: empty = the record's own `target` ("robot"); "camera" for a video.
  std::string mutual_gaze_target;
  // Operator markers (live --ui "mark", a session's markers.jsonl): events.csv rows of type
  // "marker" at their stamp (duration 0).
  struct Marker {
    int64_t stamp_ns = 0;  // session clock
    std::string label, source, detail;
  };
  std::vector<Marker> markers;
};

// The file name of a primitive's table: "F<NN>_<name>.csv" with the name reduced to
// [A-Za-z0-9_] (e.g. "F12_getHeadGaze_plane.csv").
std::string csv_table_name(const std::string& code, const std::string& primitive);

// The flattened cells of a JSON value under `prefix` (rules above), in column order.
void flatten_json(const nlohmann::json& value, const std::string& prefix,
                  std::vector<std::pair<std::string, std::string>>& out, int max_list_items = 5);

// One CSV cell, quoted when needed (RFC 4180).
std::string csv_cell(const std::string& text);

// Reads primitives.jsonl (twice: columns, then rows) and writes the tables into `dir`
// (created), each atomically. events.csv holds, in start order:
//   mutual_gaze   checkMutualGaze: a run of ticks with value.mutual true (the hold rule's state)
//   speech        recognizeSpeech: each utterance (start_ns..end_ns), label = its text
//   speaker       identifyVoice: each utterance's speaker (label = name or speaker_id)
//   <primitive>   any primitive whose value has a string "label" (gestures, expressions, ...):
//                 a run of ticks with the same label other than "none"/"unknown"
//   marker        options.markers: the operator's marks (label, source; duration 0)
// Returns the files written.
Result<std::vector<std::filesystem::path>> write_csv_tables(
    const std::filesystem::path& primitives_jsonl, const std::filesystem::path& dir,
    const CsvTablesOptions& options = {});

// Episodes (events.csv rows) as JSON objects {type, label, start_s, end_s, duration_s, source,
// detail}, from primitive records in their JSON form (for the report). Times are seconds since
// the first record's tick; a run of ticks t_a..t_b lasts until t_b plus one tick.
class EpisodeCollector {
 public:
  void add(const nlohmann::json& record);  // one primitives.jsonl record, in file order
  // Labels mutual-gaze episodes "looking at <target>" instead of the records' own target.
  void set_mutual_gaze_target(std::string target) { mutual_gaze_target_ = std::move(target); }
  // Closes open runs at the last tick seen and returns every episode, sorted by start.
  std::vector<nlohmann::json> finish();

 private:
  struct Run {
    std::string label, source, detail;
    int64_t start_ns = 0, last_ns = 0;
    bool open = false;
  };
  void close(const std::string& type, Run& run, int64_t end_ns);
  std::map<std::string, Run> runs_;  // by type
  std::set<std::string> intervals_seen_;
  std::string mutual_gaze_target_;
  std::vector<nlohmann::json> episodes_;
  int64_t first_stamp_ns_ = -1;  // times are seconds since the first tick
  int64_t last_stamp_ns_ = 0;
  int64_t tick_ns_ = 0;  // the spacing of ticks (a run ends one tick after its last tick)
};

}  // namespace dreamsense::exporters
