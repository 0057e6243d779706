#include "dreamsense/batch/output_state.hpp"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <system_error>
#include <unistd.h>

namespace dreamsense::batch {
namespace fs = std::filesystem;

const char* to_string(OutputState state) {
  switch (state) {
    case OutputState::kAbsent:
      return "absent";
    case OutputState::kFinished:
      return "finished";
    case OutputState::kPartial:
      return "partial";
    case OutputState::kNotAFolder:
      return "not a folder";
  }
  return "?";
}

namespace {

Result<nlohmann::json> read_json_object(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot read", path.string());
  std::stringstream text;
  text << in.rdbuf();
  auto j = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object())
    return make_error(ErrorCode::kCorruptData, "{}: not a JSON object", path.string());
  return j;
}

}  // namespace

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

Status write_file_atomically(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0)
    return make_error(ErrorCode::kIoError, "{}: cannot write: {}", path.string(),
                      std::strerror(errno));
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      return make_error(ErrorCode::kIoError, "{}: write failed: {}", path.string(),
                        std::strerror(e));
    }
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    ::unlink(tmp.c_str());
    return make_error(ErrorCode::kIoError, "{}: write failed: {}", path.string(),
                      std::strerror(errno));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    return make_error(ErrorCode::kIoError, "{}: cannot rename into place: {}", path.string(),
                      std::strerror(e));
  }
  return ok_status();
}

OutputCheck check_output(const fs::path& dir, const std::string& input,
                         const std::vector<std::string>& analyze_args) {
  std::error_code ec;
  const auto st = fs::symlink_status(dir, ec);
  if (!fs::exists(st)) return {OutputState::kAbsent, ""};
  if (!fs::is_directory(st))
    return {OutputState::kNotAFolder, dir.string() + " exists and is not a folder"};
  if (!fs::is_regular_file(dir / kSummaryFile, ec))
    return {OutputState::kPartial, std::string("no ") + kSummaryFile};
  if (auto s = read_json_object(dir / kSummaryFile); !s)
    return {OutputState::kPartial, s.error().message};
  auto done = read_done_record(dir);
  if (!done) return {OutputState::kPartial, done.error().message};
  if (done->input != input)
    return {OutputState::kPartial,
            fmt::format("{} names another input ({})", kDoneFile, done->input)};
  if (done->analyze_args != analyze_args)
    return {OutputState::kPartial, "made with other analyze flags"};
  return {OutputState::kFinished, ""};
}

Status write_done_record(const fs::path& dir, const DoneRecord& r) {
  const nlohmann::json j = {{"input", r.input},
                            {"analyze_args", r.analyze_args},
                            {"seconds", r.seconds},
                            {"finished_utc", r.finished_utc}};
  return write_file_atomically(dir / kDoneFile, j.dump(2) + "\n");
}

Result<DoneRecord> read_done_record(const fs::path& dir) {
  const fs::path path = dir / kDoneFile;
  std::error_code ec;
  if (!fs::exists(path, ec)) return make_error(ErrorCode::kNotFound, "no {}", kDoneFile);
  auto j = read_json_object(path);
  if (!j) return tl::unexpected(j.error());
  DoneRecord r;
  try {
    r.input = j->at("input").get<std::string>();
    r.analyze_args = j->at("analyze_args").get<std::vector<std::string>>();
    r.seconds = j->at("seconds").get<double>();
    r.finished_utc = j->value("finished_utc", "");
  } catch (const nlohmann::json::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: {}", path.string(), e.what());
  }
  return r;
}

Status remove_output(const fs::path& dir) {
  std::error_code ec;
  const auto st = fs::symlink_status(dir, ec);
  if (!fs::exists(st)) return ok_status();
  if (!fs::is_directory(st))
    return make_error(ErrorCode::kFailedPrecondition, "{}: exists and is not a folder",
                      dir.string());
  fs::remove_all(dir, ec);
  if (ec)
    return make_error(ErrorCode::kIoError, "{}: cannot remove partial output: {}", dir.string(),
                      ec.message());
  return ok_status();
}

}  // namespace dreamsense::batch
