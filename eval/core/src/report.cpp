#include "dreamsense/eval/report.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <system_error>

namespace dreamsense::eval {
namespace fs = std::filesystem;

nlohmann::json EvalReport::to_json() const {
  nlohmann::json j = extra.is_object() ? extra : nlohmann::json::object();
  j["task"] = task;
  j["dataset"] = {{"name", dataset}, {"items", items}};
  j["protocol"] = protocol;
  j["metrics"] = metrics;
  j["timing"] = timing;
  j["per_class"] = per_class;
  return j;
}

Status write_json_document(const nlohmann::json& document, const std::string& target) {
  if (target.empty()) return ok_status();
  std::string text;
  try {
    text = document.dump(2) + "\n";
  } catch (const nlohmann::json::exception& e) {
    return make_error(ErrorCode::kInvalidArgument, "{}: cannot encode the report: {}", target,
                      e.what());
  }
  if (target == "-") {
    std::cout << text << std::flush;
    return std::cout ? ok_status()
                     : make_error(ErrorCode::kIoError, "standard output: write failed");
  }
  const fs::path final_path(target);
  fs::path partial = final_path;
  partial += ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) return make_error(ErrorCode::kIoError, "{}: cannot write", target);
    out << text;
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(partial, ec);
      return make_error(ErrorCode::kIoError, "{}: write failed (disk full?)", target);
    }
  }
  std::error_code ec;
  fs::rename(partial, final_path, ec);
  if (ec) {
    fs::remove(partial, ec);
    return make_error(ErrorCode::kIoError, "{}: cannot rename the finished report", target);
  }
  return ok_status();
}

Status write_report(const EvalReport& report, const std::string& target) {
  return write_json_document(report.to_json(), target);
}

double Stopwatch::stop() {
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
  samples_ms_.push_back(ms);
  return ms;
}

std::optional<double> Stopwatch::median_ms() const {
  if (samples_ms_.empty()) return std::nullopt;
  std::vector<double> v = samples_ms_;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  if (v.size() % 2 == 1) return v[mid];
  const double hi = v[mid];
  const double lo = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return (lo + hi) / 2;
}

}  // namespace dreamsense::eval
