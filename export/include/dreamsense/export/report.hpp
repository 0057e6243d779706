#pragma once
// report.html: a self-contained page (no scripts, no network) summarising an analysis for a
// researcher: session metadata, per-primitive status counts, and SVG timelines of every numeric
// legacy value of the enabled primitives.

#include "dreamsense/core/status.hpp"
#include "dreamsense/primitives/catalogue.hpp"
#include "dreamsense/sources/session.hpp"

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace dreamsense::exporters {

class HtmlReport {
 public:
  void add(const std::vector<primitives::PrimitiveRecord>& records);
  // `summary_lines`: free text lines shown at the top (timing, analysers).
  std::string build(const sources::SessionManifest& manifest,
                    const std::vector<std::string>& summary_lines) const;
  Status write(const std::filesystem::path& path, const sources::SessionManifest& manifest,
               const std::vector<std::string>& summary_lines) const;

 private:
  struct Series {
    std::vector<double> t_s;
    std::vector<std::vector<double>> values;  // per tick, the legacy vector (empty if not ok)
  };
  std::map<int, std::map<std::string, int>> status_counts_;  // primitive id -> status -> n
  std::map<int, Series> series_;
  int64_t first_stamp_ns_ = -1;
};

}  // namespace dreamsense::exporters
