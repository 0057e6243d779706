#pragma once
// The evaluation JSON every `dreamsense eval` task writes (../shared/spec/cli.md):
//   { "task", "dataset": {"name", "items"}, "protocol", "metrics", "timing", "per_class" }
// plus optional further top-level keys (`extra`, e.g. "not_evaluated", "curve", "folds").
// One type and one writer, so no evaluation builds the shape by hand.

#include "dreamsense/core/status.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::eval {

struct EvalReport {
  std::string task;      // "expression", "actions", "tracking", ...
  std::string dataset;   // the --dataset NAME ("ckplus48", "utkinect", ...)
  size_t items = 0;      // what the protocol counted (images, windows, frames, clips)
  std::string protocol;  // one line: how the numbers were obtained
  nlohmann::json metrics = nlohmann::json::object();
  nlohmann::json timing = nlohmann::json::object();
  nlohmann::json per_class = nlohmann::json::object();
  nlohmann::json extra = nlohmann::json::object();  // further top-level keys
  nlohmann::json to_json() const;
};

// Writes the report as indented JSON: "-" = stdout; otherwise the file is written under a
// temporary name and renamed, so a failed write leaves nothing under the final name. An empty
// target writes nothing.
Status write_report(const EvalReport& report, const std::string& target);
// The same for any JSON document (reports of tasks with their own shape, e.g. session).
Status write_json_document(const nlohmann::json& document, const std::string& target);

// Milliseconds since `t0` on the steady clock.
double ms_since(std::chrono::steady_clock::time_point t0);
// The median (the mean of the two middle values for an even count); nullopt when empty.
std::optional<double> median(std::vector<double> values);
// A JSON number, or null when there is none.
nlohmann::json number_or_null(const std::optional<double>& v);

// Wall-clock samples of one timed step, reported as a median (e.g. ms_per_face_median).
class Stopwatch {
 public:
  void start() { t0_ = std::chrono::steady_clock::now(); }
  // Adds the milliseconds since start() as one sample and returns them.
  double stop();
  void add_ms(double ms) { samples_ms_.push_back(ms); }
  const std::vector<double>& samples_ms() const { return samples_ms_; }
  std::optional<double> median_ms() const;

 private:
  std::chrono::steady_clock::time_point t0_{};
  std::vector<double> samples_ms_;
};

}  // namespace dreamsense::eval
