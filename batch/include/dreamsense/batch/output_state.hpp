#pragma once
// The state of one input's output folder OUT/<name>, which decides what a (re)run does with it.
//
// An analysis is finished only when its folder holds the analysis' summary.json AND the batch's
// done record (batch_done.json), written atomically after the analysis exited with success and
// naming the same input and the same analyze flags. Anything else is partial (an interrupted or
// failed analysis, or one made with other flags) and is removed and redone.

#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::batch {

inline constexpr const char* kSummaryFile = "summary.json";
inline constexpr const char* kDoneFile = "batch_done.json";

enum class OutputState {
  kAbsent,      // nothing there yet
  kFinished,    // summary.json + a matching done record
  kPartial,     // a folder that is not finished (reason in OutputCheck::why)
  kNotAFolder,  // a file (or other non-folder) where the folder should be
};
const char* to_string(OutputState state);

struct DoneRecord {
  std::string input;                      // the input's identity (absolute path)
  std::vector<std::string> analyze_args;  // extra flags given to analyze
  double seconds = 0;                     // wall time of the analysis
  std::string finished_utc;               // ISO 8601
};

struct OutputCheck {
  OutputState state = OutputState::kAbsent;
  std::string why;  // for kPartial / kNotAFolder: what is missing or different
};

OutputCheck check_output(const std::filesystem::path& dir, const std::string& input,
                         const std::vector<std::string>& analyze_args);

// Written last, atomically (temporary file + rename), after the analysis succeeded.
Status write_done_record(const std::filesystem::path& dir, const DoneRecord& record);
Result<DoneRecord> read_done_record(const std::filesystem::path& dir);

// Removes a partial output folder (and only a folder).
Status remove_output(const std::filesystem::path& dir);

// Writes `text` to `path` atomically (a temporary file beside it, then rename).
Status write_file_atomically(const std::filesystem::path& path, const std::string& text);

// The current UTC time as "YYYY-MM-DDTHH:MM:SSZ".
std::string utc_now();

}  // namespace dreamsense::batch
