#include "dreamsense/export/report.hpp"

#include "dreamsense/core/output_file.hpp"
#include "dreamsense/export/csv_tables.hpp"
#include "dreamsense/export/primitive_json.hpp"

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <set>

namespace dreamsense::exporters {
namespace {
using nlohmann::json;

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

std::string base64(const std::vector<uchar>& bytes) {
  static const char* kChars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const uint32_t n = (uint32_t(bytes[i]) << 16) |
                       (i + 1 < bytes.size() ? uint32_t(bytes[i + 1]) << 8 : 0) |
                       (i + 2 < bytes.size() ? uint32_t(bytes[i + 2]) : 0);
    out += kChars[(n >> 18) & 63];
    out += kChars[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? kChars[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kChars[n & 63] : '=';
  }
  return out;
}

// The unit of a flattened value member, from the first segment (from the end) whose name ends in
// a unit suffix; empty when it has none (unit vectors, ids, counts are not plotted).
std::string unit_of(const std::string& path) {
  static const std::vector<std::pair<std::string, std::string>> kUnits = {
      {"_deg", "degrees"}, {"_mps", "m/s"}, {"_m", "metres"}, {"_s", "seconds"}};
  size_t end = path.size();
  while (true) {
    const size_t dot = path.rfind('.', end == 0 ? 0 : end - 1);
    const size_t begin = dot == std::string::npos || dot >= end ? 0 : dot + 1;
    const std::string seg = path.substr(begin, end - begin);
    for (const auto& [suffix, unit] : kUnits)
      if (seg.size() > suffix.size() &&
          seg.compare(seg.size() - suffix.size(), suffix.size(), suffix) == 0)
        return unit;
    if (begin == 0) return "";
    end = begin - 1;
  }
}

double nice_step(double range, int target) {
  if (!(range > 0)) return 1;
  const double raw = range / target;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (raw <= m * p) return m * p;
  return 10 * p;
}

std::string num(double v) {
  if (std::abs(v) < 1e-12) return "0";
  return fmt::format("{:.4g}", v);
}

const char* kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};

struct Frame {  // the plot area of a chart
  double w = 900, h = 170, left = 64, right = 12, top = 10, bottom = 34;
  double t0 = 0, t1 = 1, lo = 0, hi = 1;
  double x(double t) const { return left + (t - t0) / (t1 - t0) * (w - left - right); }
  double y(double v) const { return top + (hi - v) / (hi - lo) * (h - top - bottom); }
};

// The time axis (seconds) along the bottom of a frame, with grid lines.
std::string time_axis(const Frame& f) {
  std::string out;
  const double step = nice_step(f.t1 - f.t0, 10);
  for (double t = std::ceil(f.t0 / step) * step; t <= f.t1 + 1e-9; t += step)
    out += fmt::format(
        "<line x1=\"{0:.1f}\" x2=\"{0:.1f}\" y1=\"{1}\" y2=\"{2}\" stroke=\"#e3e3e3\"/>"
        "<text x=\"{0:.1f}\" y=\"{3}\" text-anchor=\"middle\" class=\"ax\">{4}</text>",
        f.x(t), f.top, f.h - f.bottom, f.h - f.bottom + 13, num(t));
  out += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" class=\"ax\">time (s)</text>",
                     (f.left + f.w - f.right) / 2, f.h - 3);
  return out;
}

struct NamedSeries {
  std::string name;
  const std::vector<float>* t;
  const std::vector<float>* v;
};

// A line chart of one or more series sharing a unit; lines break where ticks are missing.
std::string line_chart(const std::string& title, const std::string& unit,
                       const std::vector<NamedSeries>& series, double t0, double t1,
                       double tick_s) {
  Frame f;
  f.t0 = t0;
  f.t1 = std::max(t1, t0 + 1e-6);
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& s : series)
    for (float v : *s.v) {
      lo = std::min<double>(lo, v);
      hi = std::max<double>(hi, v);
    }
  if (!std::isfinite(lo)) return "";
  if (hi - lo < 1e-9) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double pad = (hi - lo) * 0.06;
  f.lo = lo - pad;
  f.hi = hi + pad;
  std::string svg = fmt::format(
      "<svg class=\"chart\" viewBox=\"0 0 {} {}\" role=\"img\" aria-label=\"{}\">"
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"#fff\" stroke=\"#bbb\"/>",
      f.w, f.h, escape(title), f.left, f.top, f.w - f.left - f.right, f.h - f.top - f.bottom);
  svg += time_axis(f);
  const double ystep = nice_step(f.hi - f.lo, 4);
  for (double v = std::ceil(f.lo / ystep) * ystep; v <= f.hi + 1e-12; v += ystep)
    svg += fmt::format(
        "<line x1=\"{0}\" x2=\"{1}\" y1=\"{2:.1f}\" y2=\"{2:.1f}\" stroke=\"#eee\"/>"
        "<text x=\"{3}\" y=\"{4:.1f}\" text-anchor=\"end\" class=\"ax\">{5}</text>",
        f.left, f.w - f.right, f.y(v), f.left - 4, f.y(v) + 4, num(v));
  svg += fmt::format(
      "<text transform=\"translate(13,{}) rotate(-90)\" text-anchor=\"middle\" "
      "class=\"ax\">{}</text>",
      (f.top + f.h - f.bottom) / 2, escape(unit));
  std::string legend;
  for (size_t k = 0; k < series.size(); ++k) {
    const auto& s = series[k];
    const size_t n = s.t->size();
    const size_t stride = std::max<size_t>(1, n / 1500);  // at most ~1500 points per line
    std::string d;
    double prev_t = -INFINITY;
    for (size_t i = 0; i < n; i += stride) {
      const double t = (*s.t)[i];
      const bool gap = t - prev_t > tick_s * 1.5 * static_cast<double>(stride);
      d += fmt::format("{}{:.1f},{:.1f}", gap ? "M" : "L", f.x(t), f.y((*s.v)[i]));
      prev_t = t;
    }
    svg += fmt::format(
        "<path d=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1.4\"><title>{}</title></path>",
        d, kPalette[k % 6], escape(s.name));
    legend += fmt::format("<span class=\"key\"><i style=\"background:{}\"></i>{}</span>",
                          kPalette[k % 6], escape(s.name));
  }
  svg += "</svg>";
  return fmt::format("<figure><figcaption>{} <small>({})</small><br>{}</figcaption>{}</figure>\n",
                     escape(title), escape(unit), legend, svg);
}

std::string percent(double part, double whole) {
  return whole > 0 ? fmt::format("{:.1f}&nbsp;%", 100.0 * part / whole) : "–";
}

std::string seconds_text(double s) {
  if (s >= 120) return fmt::format("{:.0f} min {:.0f} s", std::floor(s / 60), std::fmod(s, 60));
  return fmt::format("{:.1f} s", s);
}

}  // namespace

HtmlReport::HtmlReport() : episodes_(std::make_unique<EpisodeCollector>()) {}
HtmlReport::~HtmlReport() = default;

void HtmlReport::add(const std::vector<primitives::PrimitiveRecord>& records) {
  if (records.empty()) return;
  const int64_t stamp = records.front().stamp.ns();
  if (first_stamp_ns_ < 0) first_stamp_ns_ = stamp;
  if (tick_ns_ == 0 && last_stamp_ns_ >= 0 && stamp > last_stamp_ns_)
    tick_ns_ = stamp - last_stamp_ns_;
  last_stamp_ns_ = std::max(last_stamp_ns_, stamp);
  ++ticks_;
  const float t = static_cast<float>((stamp - first_stamp_ns_) * 1e-9);
  std::vector<std::pair<std::string, std::string>> cells;
  for (const auto& r : records) {
    PrimitiveData& p = primitives_[static_cast<int>(r.id)];
    p.status_counts[primitives::to_string(r.status)]++;
    if (r.status == primitives::PrimitiveStatus::kDisabled) continue;
    const json j = to_json(r);
    episodes_->add(j);
    if (!r.ok()) continue;
    if (r.id == primitives::PrimitiveId::kGetFaces) face_found_t_s_.push_back(t);
    cells.clear();
    flatten_json(j["value"], "", cells, 0);
    for (const auto& [name, text] : cells) {
      if (std::count(name.begin(), name.end(), '.') > 1 || unit_of(name).empty()) continue;
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (text.empty() || end == text.c_str() || *end != '\0' || !std::isfinite(v)) continue;
      Series& s = p.series[name];
      s.t_s.push_back(t);
      s.v.push_back(static_cast<float>(v));
    }
  }
}

void HtmlReport::set_span(Timestamp start, Timestamp end) {
  span_start_ = start;
  span_end_ = end;
}

bool HtmlReport::wants_key_frame(Timestamp stamp) const {
  if (!span_start_.is_set() || !span_end_.is_set() || !(span_end_ > span_start_)) return false;
  const size_t k = key_frames_.size();
  if (k >= 5) return false;
  const double at = span_start_.seconds() + (0.1 + 0.2 * k) * (span_end_ - span_start_).seconds();
  return stamp.seconds() >= at;
}

void HtmlReport::add_key_frame(Timestamp stamp, const std::string& camera, const cv::Mat& picture) {
  std::vector<uchar> jpeg;
  if (picture.empty() || !cv::imencode(".jpg", picture, jpeg, {cv::IMWRITE_JPEG_QUALITY, 80}))
    return;
  const double t0 = first_stamp_ns_ >= 0 ? first_stamp_ns_ * 1e-9 : span_start_.seconds();
  key_frames_.push_back({stamp.seconds() - t0, camera, base64(jpeg)});
}

std::string HtmlReport::build(const sources::SessionManifest& m, const ReportContext& c) const {
  const json input = c.input.is_object() ? c.input : json::object();
  const json plan = c.plan.is_object() ? c.plan : json::object();
  EpisodeCollector episodes_copy = *episodes_;  // finished on a copy: build() stays const
  if (input.value("kind", "") == "video") episodes_copy.set_mutual_gaze_target("the camera");
  const std::vector<json> episodes = episodes_copy.finish();
  const double tick_s = tick_ns_ > 0 ? tick_ns_ * 1e-9 : 1.0 / std::max(m.frame_rate, 1.0);
  const double duration_s = ticks_ > 0 ? (last_stamp_ns_ - first_stamp_ns_) * 1e-9 + tick_s : 0.0;
  const double ticks = static_cast<double>(ticks_);
  auto count = [&](primitives::PrimitiveId id, const char* status) {
    auto it = primitives_.find(static_cast<int>(id));
    if (it == primitives_.end()) return 0;
    auto s = it->second.status_counts.find(status);
    return s == it->second.status_counts.end() ? 0 : s->second;
  };
  auto enabled = [&](primitives::PrimitiveId id) {
    return ticks_ > 0 && count(id, "disabled") < static_cast<int>(ticks_);
  };
  const bool is_video = input.value("kind", "") == "video";
  const bool approximate =
      input.value("approximate_calibration", false) ||
      (plan.contains("approximate_calibration") && !plan["approximate_calibration"].empty());
  const std::string target = is_video ? "the camera" : "the robot";

  // Mutual gaze figures.
  std::vector<double> mutual_lengths;
  int utterances = 0;
  std::map<std::string, int> labelled;
  for (const auto& e : episodes) {
    if (e["type"] == "mutual_gaze")
      mutual_lengths.push_back(e["duration_s"].get<double>());
    else if (e["type"] == "speech")
      ++utterances;
    else if (e["type"] != "speaker")
      labelled[e["type"].get<std::string>()]++;
  }
  double mutual_total = 0;
  for (double d : mutual_lengths) mutual_total += d;
  std::vector<double> sorted = mutual_lengths;
  std::sort(sorted.begin(), sorted.end());
  const bool gaze_on = enabled(primitives::PrimitiveId::kCheckMutualGaze);
  const bool faces_on = enabled(primitives::PrimitiveId::kGetFaces);
  const double face_ticks = count(primitives::PrimitiveId::kGetFaces, "ok");
  const double gaze_ok_ticks = count(primitives::PrimitiveId::kCheckMutualGaze, "ok");

  std::string h = fmt::format(
      "<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\">"
      "<title>dreamsense report: {0}</title><style>"
      "body{{font-family:system-ui,sans-serif;max-width:62em;margin:1.5em auto;padding:0 1em;"
      "color:#222;line-height:1.4}}h1{{font-size:1.6em;margin-bottom:0.2em}}"
      "h2{{border-bottom:2px solid #ddd;margin-top:1.6em}}"
      "table{{border-collapse:collapse;margin:0.5em 0}}td,th{{border:1px solid #ccc;"
      "padding:2px 8px;text-align:right}}th{{background:#f0f0f0}}td.l,th.l{{text-align:left}}"
      ".cards{{display:flex;flex-wrap:wrap;gap:0.6em}}.card{{border:1px solid #ccc;"
      "border-radius:6px;padding:0.5em 0.9em;min-width:10em;background:#fafafa}}"
      ".card b{{display:block;font-size:1.5em}}.card span{{font-size:85%;color:#555}}"
      ".warn{{background:#fff4d6;border:1px solid #e0b440;padding:0.6em 0.9em;border-radius:6px}}"
      "svg.chart,svg.lanes,svg.bars{{width:100%;height:auto;font-size:11px}}.ax{{fill:#555}}"
      "figure{{margin:0.8em 0}}figcaption{{font-weight:600}}figcaption small{{font-weight:normal}}"
      ".key{{font-weight:normal;font-size:85%;margin-right:1em}}.key i{{display:inline-block;"
      "width:1.4em;height:0.35em;margin-right:0.3em;vertical-align:middle}}"
      ".frames{{display:flex;flex-wrap:wrap;gap:0.5em}}.frames figure{{margin:0;width:32%}}"
      ".frames img{{width:100%}}.muted{{color:#777}}</style></head><body>\n"
      "<h1>Session report: {0}</h1>\n<p class=\"muted\">",
      escape(m.name));
  if (is_video)
    h += fmt::format("Video {} ({}×{}, {} fps, codec {}), analysed as a one-camera session.",
                     escape(input.value("path", std::string())), input.value("width", 0),
                     input.value("height", 0), num(input.value("nominal_fps", 0.0)),
                     escape(input.value("codec", std::string())));
  else
    h += fmt::format("Participant {}{}{}; {} Hz ticks.", m.participant.id,
                     m.condition.empty() ? "" : ", condition " + escape(m.condition),
                     m.task.empty() ? "" : ", task " + escape(m.task), num(m.frame_rate));
  for (const auto& l : c.summary_lines) h += " " + escape(l) + ".";
  h += "</p>\n";
  if (!c.calibration_lines.empty()) {
    h += "<p><b>Child calibration.</b>";
    for (const auto& l : c.calibration_lines) h += " " + escape(l) + ".";
    h += "</p>\n";
  }
  if (approximate)
    h += fmt::format(
        "<p class=\"warn\"><b>Approximate camera intrinsics.</b> This recording has no camera "
        "calibration: the focal length was assumed from the image size (fx = fy = 500 × "
        "width / 640 = {} px, principal point at the image centre). Face detection and angles "
        "relative to the camera are usable; 3-D positions and distances (metres) are "
        "approximate. Give <code>--calibration cam.yaml</code> for exact 3-D.</p>\n",
        num(input.value("fx_px", 0.0)));

  h += "<p class=\"muted\">Contents: <a href=\"#summary\">summary</a> · <a href=\"#gaze\">where "
       "the child looked</a> · <a href=\"#timeline\">timeline</a> · <a href=\"#frames\">key "
       "frames</a> · <a href=\"#quality\">data quality</a> · <a href=\"#availability\">"
       "availability</a> · <a href=\"#plots\">measurements</a> · <a href=\"#episodes\">"
       "episodes</a></p>\n";
  // 1. Summary cards.
  h += "<h2 id=\"summary\">Summary</h2>\n<div class=\"cards\">";
  auto card = [&](const std::string& value, const std::string& what) {
    h += fmt::format("<div class=\"card\"><b>{}</b><span>{}</span></div>", value, what);
  };
  card(seconds_text(duration_s), fmt::format("analysed ({} ticks)", ticks_));
  if (faces_on) card(percent(face_ticks, ticks), "of the time a face was found");
  if (gaze_on) {
    card(percent(mutual_total, duration_s), "of the time looking at " + target + " (mutual gaze)");
    card(std::to_string(mutual_lengths.size()), "mutual-gaze episodes");
    if (!sorted.empty())
      card(fmt::format("{:.1f} s", sorted[sorted.size() / 2]),
           fmt::format("median episode (mean {:.1f} s, longest {:.1f} s)",
                       mutual_total / sorted.size(), sorted.back()));
  }
  if (enabled(primitives::PrimitiveId::kRecognizeSpeech))
    card(std::to_string(utterances), "utterances recognised");
  for (const auto& [type, n] : labelled) card(std::to_string(n), escape(type) + " episodes");
  h += "</div>\n";
  if (!gaze_on)
    h += "<p class=\"muted\">Mutual gaze was not analysed (no gaze analyser ran: see Data "
         "quality).</p>\n";

  // 2. Where the child looked.
  if (gaze_on || faces_on) {
    h += "<h2 id=\"gaze\">Where the child looked</h2>\n";
    struct Bar {
      std::string label;
      double share;
      const char* colour;
    };
    const double mutual_ticks_share = duration_s > 0 ? mutual_total / duration_s : 0;
    std::vector<Bar> bars;
    if (gaze_on) bars.push_back({"at " + target + " (mutual gaze)", mutual_ticks_share, "#2ca02c"});
    if (gaze_on)
      bars.push_back({"elsewhere (face found, gaze away)",
                      std::max(0.0, gaze_ok_ticks / ticks - mutual_ticks_share), "#1f77b4"});
    const double no_face = faces_on ? 1.0 - face_ticks / ticks : 1.0;
    if (gaze_on)
      bars.push_back({"unknown (face found, no gaze estimate)",
                      std::max(0.0, 1.0 - no_face - gaze_ok_ticks / ticks), "#dddddd"});
    bars.push_back({"unknown (no face found)", no_face, "#bbbbbb"});
    const double bw = 900, row = 26, label_w = 290;
    h += fmt::format(
        "<svg class=\"bars\" viewBox=\"0 0 {} {}\" role=\"img\" "
        "aria-label=\"gaze targets\">",
        bw, row * bars.size() + 24);
    for (size_t i = 0; i < bars.size(); ++i) {
      const double w = std::clamp(bars[i].share, 0.0, 1.0) * (bw - label_w - 70);
      h += fmt::format(
          "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text><rect x=\"{}\" y=\"{}\" "
          "width=\"{:.1f}\" height=\"{}\" fill=\"{}\"/><text x=\"{:.1f}\" y=\"{}\">{:.1f} "
          "%</text>",
          label_w - 6, i * row + 17, escape(bars[i].label), label_w, i * row + 4, w, row - 8,
          bars[i].colour, label_w + w + 5, i * row + 17, 100 * bars[i].share);
    }
    h += fmt::format("<text x=\"{}\" y=\"{}\" class=\"ax\">share of the analysed time</text>",
                     label_w, row * bars.size() + 18);
    h += "</svg>\n<p class=\"muted\">Gaze at each toy is not computed yet (it needs the table "
         "camera's objects and the gaze ray's intersection with them).</p>\n";
  }

  // 3. Event timeline.
  h += "<h2 id=\"timeline\">Timeline</h2>\n";
  {
    std::vector<std::string> lanes;
    if (faces_on) lanes.push_back("face found");
    std::set<std::string> seen;
    for (const char* t : {"mutual_gaze", "speech", "speaker"})
      for (const auto& e : episodes)
        if (e["type"] == t && seen.insert(t).second) lanes.push_back(t);
    for (const auto& e : episodes)
      if (seen.insert(e["type"].get<std::string>()).second) lanes.push_back(e["type"]);
    if (gaze_on && seen.count("mutual_gaze") == 0)
      lanes.insert(lanes.begin() + (faces_on ? 1 : 0), "mutual_gaze");
    Frame f;
    f.left = 110;
    f.t0 = 0;
    f.t1 = std::max(duration_s, 1e-3);
    const double lane_h = 24;
    f.h = f.top + lane_h * lanes.size() + f.bottom;
    h += fmt::format(
        "<svg class=\"lanes\" viewBox=\"0 0 {} {}\" role=\"img\" "
        "aria-label=\"event timeline\">",
        f.w, f.h);
    h += time_axis(f);
    auto lane_y = [&](size_t i) { return f.top + lane_h * i; };
    for (size_t i = 0; i < lanes.size(); ++i)
      h += fmt::format(
          "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text><line x1=\"{}\" x2=\"{}\" "
          "y1=\"{}\" y2=\"{}\" stroke=\"#ddd\"/>",
          f.left - 6, lane_y(i) + 16, escape(lanes[i] == "mutual_gaze" ? "mutual gaze" : lanes[i]),
          f.left, f.w - f.right, lane_y(i) + lane_h, lane_y(i) + lane_h);
    auto lane_of = [&](const std::string& name) {
      return static_cast<size_t>(std::find(lanes.begin(), lanes.end(), name) - lanes.begin());
    };
    if (faces_on) {  // runs of ticks with a face
      double start = -1, prev = -1;
      auto flush = [&] {
        if (start >= 0)
          h += fmt::format(
              "<rect x=\"{:.1f}\" y=\"{}\" width=\"{:.1f}\" height=\"{}\" "
              "fill=\"#9ecae1\"/>",
              f.x(start), lane_y(0) + 5, std::max(0.5, f.x(prev + tick_s) - f.x(start)),
              lane_h - 10);
      };
      for (double t : face_found_t_s_) {
        if (start < 0 || t - prev > tick_s * 1.5) {
          flush();
          start = t;
        }
        prev = t;
      }
      flush();
    }
    for (const auto& e : episodes) {
      const size_t lane = lane_of(e["type"]);
      if (lane >= lanes.size()) continue;
      const double x0 = f.x(e["start_s"].get<double>());
      const double x1 = std::max(x0 + 1.5, f.x(e["end_s"].get<double>()));
      const char* colour = e["type"] == "mutual_gaze" ? "#2ca02c"
                           : e["type"] == "speech"    ? "#ff7f0e"
                           : e["type"] == "speaker"   ? "#9467bd"
                                                      : "#d62728";
      const std::string label = e["label"].get<std::string>();
      h += fmt::format(
          "<g><title>{} {:.2f}–{:.2f} s: {}</title><rect x=\"{:.1f}\" y=\"{}\" width=\"{:.1f}\" "
          "height=\"{}\" fill=\"{}\" opacity=\"0.85\"/>",
          escape(e["type"].get<std::string>()), e["start_s"].get<double>(),
          e["end_s"].get<double>(), escape(label), x0, lane_y(lane) + 4, x1 - x0, lane_h - 8,
          colour);
      if (e["type"] != "mutual_gaze" && x1 - x0 > 30)
        h += fmt::format("<text x=\"{:.1f}\" y=\"{}\" fill=\"#000\">{}</text>", x0 + 3,
                         lane_y(lane) + 16,
                         escape(label.size() > static_cast<size_t>((x1 - x0) / 6.5)
                                    ? label.substr(0, static_cast<size_t>((x1 - x0) / 6.5)) + "…"
                                    : label));
      h += "</g>";
    }
    h += "</svg>\n";
    if (lanes.empty()) h += "<p class=\"muted\">No events: nothing was analysed over time.</p>\n";
  }

  // 4. Key frames.
  if (!key_frames_.empty()) {
    h += "<h2 id=\"frames\">Key frames</h2>\n<p class=\"muted\">The selected camera at 10, 30, 50, "
         "70 and "
         "90 % of the session, with the analysis drawn on it (face box, landmarks, head axes, "
         "gaze rays, mutual-gaze state).</p>\n<div class=\"frames\">";
    for (const auto& k : key_frames_)
      h += fmt::format(
          "<figure><img alt=\"{1} at {0:.1f} s\" src=\"data:image/jpeg;base64,{2}\">"
          "<figcaption><small>{0:.1f} s, {1}</small></figcaption></figure>",
          k.t_s, escape(k.camera), k.jpeg_base64);
    h += "</div>\n";
  }

  // 5. Data quality.
  h += "<h2 id=\"quality\">Data quality</h2>\n<table>";
  auto qrow = [&](const std::string& k, const std::string& v) {
    h += fmt::format("<tr><th class=\"l\">{}</th><td class=\"l\">{}</td></tr>", k, v);
  };
  if (faces_on) qrow("face found", percent(face_ticks, ticks) + " of ticks");
  qrow("dropped frames", std::to_string(c.dropped_frames));
  if (c.wall_seconds > 0)
    qrow("processing",
         fmt::format("{:.1f} s for {} ticks ({:.1f} ticks/s, {:.1f}× real time)", c.wall_seconds,
                     ticks_, ticks / c.wall_seconds, duration_s / c.wall_seconds));
  qrow("camera calibration",
       approximate ? "<b>approximate</b> (assumed from the image size, see above)"
       : is_video  ? "from " + escape(input.value("calibration", std::string()))
                   : "from the session's calibration files");
  if (is_video) qrow("sound track", escape(input.value("audio", std::string())));
  std::string ran;
  for (const auto& a : c.analyzers) ran += (ran.empty() ? "" : ", ") + escape(a);
  qrow("analysers that ran", ran.empty() ? "none" : ran);
  if (plan.contains("not_running"))
    for (const auto& [name, why] : plan["not_running"].items())
      qrow("not run: " + escape(name), escape(why.get<std::string>()));
  h += "</table>\n";

  // 6. Availability.
  h += "<h2 id=\"availability\">Primitives: availability</h2>\n<p class=\"muted\">Share of ticks "
       "with each status: "
       "<b>ok</b> answered; <b>no_data</b> nothing detected (e.g. no face); <b>stale</b> last "
       "value too old; <b>sensor_offline</b> its sensor delivered nothing; <b>disabled</b> no "
       "analyser for it in this recording (missing sensor or analyser switched off).</p>\n"
       "<table><tr><th>#</th><th class=\"l\">primitive</th><th>ok</th><th>no_data</th>"
       "<th>stale</th><th>sensor_offline</th><th>disabled</th><th class=\"l\">ok share</th></tr>\n";
  for (const auto& info : primitives::catalogue()) {
    auto pct = [&](const char* s) { return percent(count(info.id, s), ticks); };
    const double ok = ticks > 0 ? count(info.id, "ok") / ticks : 0;
    h += fmt::format(
        "<tr><td>{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
        "<td>{}</td><td class=\"l\"><svg width=\"100\" height=\"10\"><rect width=\"100\" "
        "height=\"10\" fill=\"#eee\"/><rect width=\"{:.1f}\" height=\"10\" fill=\"#2ca02c\"/>"
        "</svg></td></tr>\n",
        info.code, escape(info.name), pct("ok"), pct("no_data"), pct("stale"),
        pct("sensor_offline"), pct("disabled"), 100 * ok);
  }
  h += "</table>\n";

  // 7. Plots.
  h += "<h2 id=\"plots\">Measurements over time</h2>\n<p class=\"muted\">The answered primitives' "
       "quantities "
       "with their units (names as in primitives.jsonl and the CSV tables); gaps are ticks "
       "without an answer. 3-D positions are in the session's world frame" +
       std::string(is_video ? " (for a video: the camera's frame, x right, y down, z forward)"
                            : "") +
       ".</p>\n";
  bool any_plot = false;
  for (const auto& info : primitives::catalogue()) {
    auto it = primitives_.find(static_cast<int>(info.id));
    if (it == primitives_.end() || it->second.series.empty()) continue;
    std::map<std::string, std::vector<NamedSeries>> by_unit;
    for (const auto& [name, s] : it->second.series) {
      // A quantity that never changes (e.g. held_s while there is no mutual gaze) says nothing
      // a chart would show better than the summary.
      if (std::all_of(s.v.begin(), s.v.end(),
                      [&values = s.v](float v) { return v == values.front(); }))
        continue;  // (init-capture: clang 14 cannot capture a structured binding)
      auto& list = by_unit[unit_of(name)];
      if (list.size() < 6) list.push_back({name, &s.t_s, &s.v});
    }
    for (const auto& [unit, list] : by_unit) {
      h += line_chart(fmt::format("{} {}", info.code, info.name), unit, list, 0,
                      std::max(duration_s, tick_s), tick_s);
      any_plot = true;
    }
  }
  if (!any_plot) h += "<p class=\"muted\">No primitive answered with a measurement.</p>\n";

  // 8. Episodes.
  h += "<h2 id=\"episodes\">Episodes</h2>\n";
  if (episodes.empty()) {
    h += "<p class=\"muted\">None (no mutual gaze, utterance, gesture or expression episode was "
         "found).</p>\n";
  } else {
    h += "<table><tr><th class=\"l\">type</th><th class=\"l\">label</th><th>start (s)</th>"
         "<th>end (s)</th><th>duration (s)</th><th class=\"l\">detail</th></tr>\n";
    size_t shown = 0;
    for (const auto& e : episodes) {
      if (++shown > 500) break;
      h += fmt::format(
          "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{:.2f}</td><td>{:.2f}</td>"
          "<td>{:.2f}</td><td class=\"l\">{}</td></tr>\n",
          escape(e["type"].get<std::string>()), escape(e["label"].get<std::string>()),
          e["start_s"].get<double>(), e["end_s"].get<double>(), e["duration_s"].get<double>(),
          escape(e["detail"].get<std::string>()));
    }
    h += "</table>\n";
    if (episodes.size() > 500)
      h += fmt::format("<p class=\"muted\">… and {} more: see tables/events.csv.</p>\n",
                       episodes.size() - 500);
  }
  h += "<p class=\"muted\"><small>Generated by dreamsense. Times are seconds from the first "
       "analysed tick. Per-tick values: primitives.jsonl, or the CSV tables "
       "(<code>--csv</code>).</small></p></body></html>\n";
  return h;
}

Status HtmlReport::write(const std::filesystem::path& path, const sources::SessionManifest& m,
                         const ReportContext& context) const {
  OutputFile f;
  if (auto s = f.open(path); !s) return s;
  if (auto s = f.write(build(m, context)); !s) return s;
  return f.commit();
}

}  // namespace dreamsense::exporters
