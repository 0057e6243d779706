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

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::optional<double> median(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  const auto mid = static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  if (values.size() % 2 == 1) return values[mid];
  const double hi = values[mid];
  const double lo = *std::max_element(values.begin(), values.begin() + mid);
  return (lo + hi) / 2;
}

nlohmann::json number_or_null(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

double Stopwatch::stop() {
  const double ms = ms_since(t0_);
  samples_ms_.push_back(ms);
  return ms;
}

std::optional<double> Stopwatch::median_ms() const { return median(samples_ms_); }

}  // namespace dreamsense::eval
