#pragma once
// Inputs of `dreamsense batch`: what each command-line argument stands for (a session folder, a
// video file, or a folder holding either), and the output folder name each one gets.

#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::batch {

enum class InputKind { kSession, kVideo };
const char* to_string(InputKind kind);

// What planning decided for one input, before anything runs.
enum class PlanStatus {
  kRun,      // to analyse
  kSkipped,  // not an input (a non-video file in a folder, a duplicate): listed, not a failure
  kFailed,   // given but unusable (missing, empty file, not a session or video): a failure
};
const char* to_string(PlanStatus status);

struct PlannedInput {
  std::string given;           // the argument, or the folder entry it was found as
  std::filesystem::path path;  // absolute, symlinks resolved: the input's identity
  InputKind kind = InputKind::kSession;
  PlanStatus status = PlanStatus::kRun;
  std::string reason;  // why skipped or failed (empty for kRun)
  std::string name;    // output folder name under --out (kRun only; output_name(path))
};

struct InputOptions {
  // Video files are recognised by extension (lower-cased, with the dot).
  std::vector<std::string> video_extensions = {".mp4",  ".avi", ".mov",  ".mkv", ".m4v",
                                               ".webm", ".mpg", ".mpeg", ".wmv", ".ogv",
                                               ".flv",  ".3gp", ".ts",   ".mts"};
  std::string session_manifest = "session.yaml";  // marks a session folder
  Status check() const;
};

bool is_video_file(const std::filesystem::path& path, const InputOptions& options = {});

// Expands the arguments, in order:
//  - a folder with session.yaml: one session;
//  - a file named session.yaml: its folder;
//  - a video file (by extension): one video; a zero-length one fails ("empty file");
//  - any other folder: its entries sorted by name (one level; names starting with '.' ignored):
//    session folders and video files are inputs, other files and folders are skipped with the
//    reason; a folder that yields no input at all fails;
//  - anything else (missing path, other file) fails with the reason.
// The same input reached twice (also through another spelling or a symlink) is kept once; the
// later ones are skipped as duplicates. Every kRun input gets its output name.
std::vector<PlannedInput> expand_inputs(const std::vector<std::string>& arguments,
                                        const InputOptions& options = {});

// Absolute, lexically normal, symlinks resolved, no trailing separator.
std::filesystem::path input_identity(const std::filesystem::path& path);

// A stable output folder name for an input (its identity): "<stem>-<8 hex digits>", the stem
// being the file or folder name without a video extension, reduced to [A-Za-z0-9._-], and the
// digits a hash (FNV-1a) of the whole path. Equal basenames in different folders get different
// names, and the name does not depend on the other inputs, so a rerun finds its outputs.
std::string output_name(const std::filesystem::path& identity, const InputOptions& options = {});

}  // namespace dreamsense::batch
