#pragma once
// An output file that is only presented as complete when it is: it is written as
// "<name>.partial" and renamed to <name> by commit(). A run that fails leaves no file under the
// final name (the destructor removes an uncommitted partial file).

#include "dreamsense/core/status.hpp"

#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense {

class OutputFile {
 public:
  OutputFile() = default;
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  Status open(const std::filesystem::path& final_path);
  Status write(std::string_view text);
  Status commit();  // flush, close, rename
  void abandon();   // close and delete the partial file
  bool is_open() const { return file_ != nullptr; }
  const std::filesystem::path& path() const { return final_; }

 private:
  std::FILE* file_ = nullptr;
  std::filesystem::path final_, partial_;
};

// Output files that appear together or not at all (an analysis: primitives.jsonl, events.log,
// report.html, summary.json, ...). They are written into a staging folder inside the output
// folder (same file system, so the final moves are renames) and moved to their final names by
// publish(). A run that fails before publish() leaves the output folder as it was: the staging
// folder is removed, and an output folder this run created is removed again when empty.
class StagedOutputDir {
 public:
  static constexpr const char* kStageName = ".dreamsense-partial";

  // Creates `out_dir` if needed (checking it is a writable folder) and an empty staging folder in
  // it (a stale one from a killed run is removed first).
  static Result<StagedOutputDir> create(const std::filesystem::path& out_dir);

  StagedOutputDir() = default;
  StagedOutputDir(StagedOutputDir&& other) noexcept;
  StagedOutputDir& operator=(StagedOutputDir&& other) noexcept;
  StagedOutputDir(const StagedOutputDir&) = delete;
  StagedOutputDir& operator=(const StagedOutputDir&) = delete;
  ~StagedOutputDir();

  // Where to write the file or folder `name` now.
  std::filesystem::path staged(const std::string& name) const { return stage_ / name; }
  const std::filesystem::path& out_dir() const { return out_; }

  // Removes every entry of `replaced` from the output folder (an earlier run's outputs, even those
  // this run does not write, so old and new never mix), then moves every staged entry to the
  // output folder, `last` last (the file a reader takes as "the run is complete").
  Status publish(const std::vector<std::string>& replaced, const std::string& last);
  // Removes the staging folder (and the output folder if this run created it and it is empty).
  void discard();

 private:
  std::filesystem::path out_, stage_;
  bool created_out_ = false;
};

// Checks that `dir` exists (creating it) and that a file can be created in it.
Status ensure_writable_dir(const std::filesystem::path& dir);

}  // namespace dreamsense
