#pragma once
// What the two model files of this library (actions model, gestures model) share: the error for a
// damaged file, the versioned header every file starts with, and the rename that publishes a
// finished write. Internal to modalities/actions.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>

namespace dreamsense::actions {

// Describes one model kind, e.g. {"actions model", "dreamsense-actions", 1, "dreamsense train
// actions"}.
struct ModelFileKind {
  const char* what;         // in messages: "actions model"
  const char* format_name;  // the `format` key
  int format_version;       // the `version` key this build reads
  const char* train_command;
};

// "<path>: not a valid <what> (<reason>)", on one line.
Error model_corrupt(const ModelFileKind& kind, const std::filesystem::path& path,
                    const std::string& reason);

// Opens `path` and checks its `format` and `version` keys (missing file: kNotFound naming the
// train command; other version: kUnsupported; wrong format: kCorruptData). OpenCV exceptions are
// left to the caller's try block, which also covers the rest of the file.
Result<cv::FileStorage> open_model_file(const ModelFileKind& kind,
                                        const std::filesystem::path& path);

// Moves a completely written `tmp` to `path`.
Status rename_model_file(const std::filesystem::path& tmp, const std::filesystem::path& path);

}  // namespace dreamsense::actions
