#include "dreamsense/core/output_file.hpp"

#include <algorithm>
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

Result<StagedOutputDir> StagedOutputDir::create(const std::filesystem::path& out_dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  StagedOutputDir d;
  d.out_ = out_dir;
  d.created_out_ = !fs::exists(out_dir, ec);
  if (auto s = ensure_writable_dir(out_dir); !s) return tl::unexpected(s.error());
  d.stage_ = out_dir / kStageName;
  fs::remove_all(d.stage_, ec);
  if (!fs::create_directory(d.stage_, ec) || ec)
    return make_error(ErrorCode::kIoError, "{}: cannot create a staging folder: {}",
                      out_dir.string(), ec ? ec.message() : "it already exists");
  return d;
}

StagedOutputDir::StagedOutputDir(StagedOutputDir&& other) noexcept
    : out_(std::move(other.out_)),
      stage_(std::move(other.stage_)),
      created_out_(other.created_out_) {
  other.stage_.clear();
  other.out_.clear();
}

StagedOutputDir& StagedOutputDir::operator=(StagedOutputDir&& other) noexcept {
  if (this != &other) {
    discard();
    out_ = std::move(other.out_);
    stage_ = std::move(other.stage_);
    created_out_ = other.created_out_;
    other.stage_.clear();
    other.out_.clear();
  }
  return *this;
}

StagedOutputDir::~StagedOutputDir() { discard(); }

void StagedOutputDir::discard() {
  namespace fs = std::filesystem;
  if (stage_.empty()) return;
  std::error_code ec;
  fs::remove_all(stage_, ec);
  if (created_out_ && fs::is_empty(out_, ec)) fs::remove(out_, ec);
  stage_.clear();
}

Status StagedOutputDir::publish(const std::vector<std::string>& replaced, const std::string& last) {
  namespace fs = std::filesystem;
  if (stage_.empty())
    return make_error(ErrorCode::kFailedPrecondition, "{}: outputs already published or discarded",
                      out_.string());
  std::error_code ec;
  // The marker of completeness goes first, so a reader never sees an old one beside new files.
  if (!last.empty()) fs::remove(out_ / last, ec);
  for (const auto& name : replaced) {
    fs::remove_all(out_ / name, ec);
    if (ec)
      return make_error(ErrorCode::kIoError, "{}: cannot replace the earlier output: {}",
                        (out_ / name).string(), ec.message());
  }
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(stage_, ec)) entries.push_back(e.path());
  if (ec)
    return make_error(ErrorCode::kIoError, "{}: cannot list: {}", stage_.string(), ec.message());
  std::stable_partition(entries.begin(), entries.end(),
                        [&](const fs::path& p) { return p.filename() != last; });
  for (const auto& from : entries) {
    const fs::path to = out_ / from.filename();
    fs::remove_all(to, ec);
    fs::rename(from, to, ec);
    if (ec)
      return make_error(ErrorCode::kIoError, "{}: cannot move into place: {}", to.string(),
                        ec.message());
  }
  fs::remove_all(stage_, ec);
  stage_.clear();
  return ok_status();
}

}  // namespace dreamsense
