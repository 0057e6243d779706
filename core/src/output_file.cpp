#include "dreamsense/core/output_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>

namespace dreamsense {

OutputFile::~OutputFile() { abandon(); }

Status OutputFile::open(const std::filesystem::path& final_path) {
  abandon();
  final_ = final_path;
  partial_ = final_path;
  partial_ += ".partial";
  std::error_code ec;
  std::filesystem::remove(final_path, ec);  // never leave an older complete file behind
  file_ = std::fopen(partial_.c_str(), "wb");
  if (file_ == nullptr)
    return make_error(ErrorCode::kIoError, "{}: cannot write: {}", final_.string(),
                      std::strerror(errno));
  return ok_status();
}

Status OutputFile::write(std::string_view text) {
  if (file_ == nullptr)
    return make_error(ErrorCode::kFailedPrecondition, "{}: not open", final_.string());
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size())
    return make_error(ErrorCode::kIoError, "{}: write failed: {}", final_.string(),
                      std::strerror(errno));
  return ok_status();
}

Status OutputFile::commit() {
  if (file_ == nullptr)
    return make_error(ErrorCode::kFailedPrecondition, "{}: not open", final_.string());
  const bool flushed = std::fflush(file_) == 0;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!flushed || !closed)
    return make_error(ErrorCode::kIoError, "{}: write failed: {}", final_.string(),
                      std::strerror(errno));
  std::error_code ec;
  std::filesystem::rename(partial_, final_, ec);
  if (ec)
    return make_error(ErrorCode::kIoError, "{}: cannot rename: {}", final_.string(), ec.message());
  partial_.clear();
  return ok_status();
}

void OutputFile::abandon() {
  if (file_ != nullptr) {
    std::fclose(file_);
    file_ = nullptr;
  }
  if (!partial_.empty()) {
    std::error_code ec;
    std::filesystem::remove(partial_, ec);
    partial_.clear();
  }
}

Status ensure_writable_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
    return make_error(ErrorCode::kIoError, "{}: output folder is not a directory", dir.string());
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return make_error(ErrorCode::kIoError, "{}: cannot create output folder: {}", dir.string(),
                      ec.message());
  const auto probe = dir / ".dreamsense_write_test";
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (f == nullptr)
    return make_error(ErrorCode::kIoError, "{}: output folder is not writable: {}", dir.string(),
                      std::strerror(errno));
  std::fclose(f);
  std::filesystem::remove(probe, ec);
  return ok_status();
}

}  // namespace dreamsense
