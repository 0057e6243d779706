#include "dreamsense/export/report.hpp"

#include "dreamsense/core/output_file.hpp"
#include "dreamsense/dream/legacy.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace dreamsense::exporters {
namespace {

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// One SVG line chart: component k of the legacy vector over time (gaps where not ok).
std::string chart(const std::vector<double>& t, const std::vector<std::vector<double>>& v, size_t k,
                  const std::string& label) {
  constexpr double kW = 640, kH = 120, kPad = 4;
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& row : v)
    if (row.size() > k) {
      lo = std::min(lo, row[k]);
      hi = std::max(hi, row[k]);
    }
  if (!std::isfinite(lo) || t.empty()) return "";
  if (hi - lo < 1e-9) {
    lo -= 1;
    hi += 1;
  }
  const double t0 = t.front(), t1 = std::max(t.back(), t0 + 1e-9);
  std::string paths, d;
  for (size_t i = 0; i < t.size(); ++i) {
    if (v[i].size() <= k) {
      if (!d.empty()) paths += fmt::format("<path d=\"{}\"/>", d);
      d.clear();
      continue;
    }
    const double x = kPad + (t[i] - t0) / (t1 - t0) * (kW - 2 * kPad);
    const double y = kH - kPad - (v[i][k] - lo) / (hi - lo) * (kH - 2 * kPad);
    d += fmt::format("{}{:.1f},{:.1f}", d.empty() ? "M" : " L", x, y);
  }
  if (!d.empty()) paths += fmt::format("<path d=\"{}\"/>", d);
  return fmt::format(
      "<figure><figcaption>{} <small>[{:.4g} … {:.4g}], {:.1f}–{:.1f} s</small></figcaption>"
      "<svg width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\"><rect width=\"100%\" height=\"100%\" "
      "fill=\"#fafafa\" stroke=\"#ccc\"/><g fill=\"none\" stroke=\"#1f5fa8\" "
      "stroke-width=\"1.2\">{}</g></svg></figure>\n",
      escape(label), lo, hi, t0, t1, kW, kH, kW, kH, paths);
}

}  // namespace

void HtmlReport::add(const std::vector<primitives::PrimitiveRecord>& records) {
  for (const auto& r : records) {
    const int id = static_cast<int>(r.id);
    status_counts_[id][primitives::to_string(r.status)]++;
    if (r.status == primitives::PrimitiveStatus::kDisabled) continue;
    if (first_stamp_ns_ < 0) first_stamp_ns_ = r.stamp.ns();
    Series& s = series_[id];
    s.t_s.push_back(static_cast<double>(r.stamp.ns() - first_stamp_ns_) * 1e-9);
    s.values.push_back(r.status == primitives::PrimitiveStatus::kOk
                           ? dream::legacy_vector(r).value_or(std::vector<double>{})
                           : std::vector<double>{});
  }
}

std::string HtmlReport::build(const sources::SessionManifest& m,
                              const std::vector<std::string>& summary_lines) const {
  std::string html = fmt::format(
      "<!doctype html><html><head><meta charset=\"utf-8\"><title>dreamsense report: {}</title>"
      "<style>body{{font-family:sans-serif;max-width:60em;margin:2em auto;color:#222}}"
      "table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:2px 8px;"
      "text-align:right}}th{{background:#eee}}td:first-child,td:nth-child(2){{text-align:left}}"
      "figure{{margin:0.5em 0}}figcaption{{font-size:90%}}</style></head><body>\n"
      "<h1>dreamsense analysis: {}</h1>\n<p>participant {}, condition {}, task {}, {} Hz</p>\n<ul>",
      escape(m.name), escape(m.name), m.participant.id, escape(m.condition), escape(m.task),
      m.frame_rate);
  for (const auto& l : summary_lines) html += "<li>" + escape(l) + "</li>";
  html +=
      "</ul>\n<h2>Primitives</h2>\n<table><tr><th>#</th><th>primitive</th><th>ok</th>"
      "<th>no_data</th><th>stale</th><th>sensor_offline</th><th>disabled</th></tr>\n";
  for (const auto& info : primitives::catalogue()) {
    auto it = status_counts_.find(static_cast<int>(info.id));
    auto count = [&](const char* s) {
      if (it == status_counts_.end()) return 0;
      auto c = it->second.find(s);
      return c == it->second.end() ? 0 : c->second;
    };
    html += fmt::format(
        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
        "<td>{}</td></tr>\n",
        info.code, escape(info.name), count("ok"), count("no_data"), count("stale"),
        count("sensor_offline"), count("disabled"));
  }
  html += "</table>\n<h2>Timelines (legacy DREAM values, mm and degrees)</h2>\n";
  for (const auto& [id, s] : series_) {
    const auto& info = primitives::info(static_cast<primitives::PrimitiveId>(id));
    size_t width = 0;
    for (const auto& v : s.values) width = std::max(width, v.size());
    html += fmt::format("<h3>{} {}</h3>\n", info.code, escape(info.name));
    // Long vectors (getBodyPose: 30 numbers) are shown by their first three components.
    for (size_t k = 0; k < std::min<size_t>(width, 4); ++k)
      html += chart(s.t_s, s.values, k, fmt::format("{}[{}]", info.name, k));
  }
  html +=
      "<p><small>Generated by dreamsense from primitives evaluated per tick; gaps are ticks "
      "without an ok status.</small></p></body></html>\n";
  return html;
}

Status HtmlReport::write(const std::filesystem::path& path, const sources::SessionManifest& m,
                         const std::vector<std::string>& summary_lines) const {
  OutputFile f;
  if (auto s = f.open(path); !s) return s;
  if (auto s = f.write(build(m, summary_lines)); !s) return s;
  return f.commit();
}

}  // namespace dreamsense::exporters
