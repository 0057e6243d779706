#include "model_file.hpp"

#include "dreamsense/core/file_storage_check.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace dreamsense::actions {
namespace fs = std::filesystem;

Error model_corrupt(const ModelFileKind& kind, const fs::path& path, const std::string& reason) {
  std::string w = reason;
  std::replace(w.begin(), w.end(), '\n', ' ');
  return Error{ErrorCode::kCorruptData,
               fmt::format("{}: not a valid {} ({})", path.string(), kind.what, w)};
}

Result<cv::FileStorage> open_model_file(const ModelFileKind& kind, const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    return make_error(ErrorCode::kNotFound, "{}: {} missing (write one with `{}`)", path.string(),
                      kind.what, kind.train_command);
  DS_ASSIGN_OR_RETURN(cv::FileStorage f, open_file_storage(path));
  std::string format;
  if (f["format"].isString()) f["format"] >> format;
  if (format != kind.format_name)
    return tl::unexpected(model_corrupt(
        kind, path, fmt::format("format is '{}', expected '{}'", format, kind.format_name)));
  if (!f["version"].isInt()) return tl::unexpected(model_corrupt(kind, path, "no version key"));
  int version = 0;
  f["version"] >> version;
  if (version != kind.format_version)
    return make_error(ErrorCode::kUnsupported,
                      "{}: {} format version {} is not supported (this build reads version {}; "
                      "retrain with `{}`)",
                      path.string(), kind.what, version, kind.format_version, kind.train_command);
  return f;
}

Status rename_model_file(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", path.string(), ec.message());
  return ok_status();
}

}  // namespace dreamsense::actions
