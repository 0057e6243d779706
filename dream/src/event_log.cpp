#include "dreamsense/dream/legacy.hpp"
#include "dreamsense/dream/writers.hpp"

#include <fmt/format.h>

#include <ctime>

namespace dreamsense::dream {

std::string format_local_time(int64_t unix_ns) {
  const std::time_t secs = static_cast<std::time_t>(unix_ns / 1'000'000'000LL);
  const int ms = static_cast<int>((unix_ns % 1'000'000'000LL) / 1'000'000LL);
  std::tm tm{};
  localtime_r(&secs, &tm);
  return fmt::format("{:04d}-{:02d}-{:02d} {:02d}:{:02d}:{:02d}.{:03d}", tm.tm_year + 1900,
                     tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, ms);
}

Status EventLogWriter::open(const std::filesystem::path& path, int64_t clock_origin_unix_ns) {
  origin_ns_ = clock_origin_unix_ns;
  last_status_.clear();
  return file_.open(path);
}

Status EventLogWriter::write(const std::vector<primitives::PrimitiveRecord>& records) {
  std::string text;
  for (const auto& r : records) {
    const char* port_name = port(r.id);
    const int key = static_cast<int>(r.id);
    const std::string time = format_local_time(origin_ns_ + r.stamp.ns());
    const auto legacy = legacy_vector(r);
    const auto legacy_string = legacy_text(r);
    if (r.status == primitives::PrimitiveStatus::kOk && legacy_string) {
      text += fmt::format("{};{};{}\n", port_name, time, *legacy_string);
    } else if (r.status == primitives::PrimitiveStatus::kOk && legacy) {
      text += fmt::format("{};{}", port_name, time);
      for (double v : *legacy) text += fmt::format(";{:.6f}", v);
      text += '\n';
    } else if (r.status != primitives::PrimitiveStatus::kOk) {
      auto it = last_status_.find(key);
      if (it == last_status_.end() || it->second != r.status)
        text += fmt::format("{};{};{}\n", port_name, time, primitives::to_string(r.status));
    }
    last_status_[key] = r.status;
  }
  return file_.write(text);
}

}  // namespace dreamsense::dream
