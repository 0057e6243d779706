#include "dreamsense/export/csv_tables.hpp"

#include "dreamsense/core/output_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <functional>
#include <map>
#include <set>

namespace dreamsense::exporters {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {
// A primitive's name reduced to [A-Za-z0-9_] ("getHeadGaze (plane)" -> "getHeadGaze_plane").
std::string plain_name(const std::string& primitive) {
  std::string name;
  for (char c : primitive) {
    if (std::isalnum(static_cast<unsigned char>(c)))
      name += c;
    else if (!name.empty() && name.back() != '_')
      name += '_';
  }
  while (!name.empty() && name.back() == '_') name.pop_back();
  return name;
}
}  // namespace

std::string csv_table_name(const std::string& code, const std::string& primitive) {
  std::string num = code.size() > 1 ? code.substr(1) : code;
  if (num.size() == 1) num = "0" + num;
  std::string name = plain_name(primitive);
  return fmt::format("{}{}_{}.csv", code.empty() ? "P" : code.substr(0, 1), num, name);
}

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

namespace {

std::string scalar_text(const json& v) {
  if (v.is_null()) return "";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  return v.dump();
}

std::string join(const std::string& prefix, const std::string& name) {
  return prefix.empty() ? name : prefix + "." + name;
}

bool all_numbers(const json& a) {
  return std::all_of(a.begin(), a.end(), [](const json& x) { return x.is_number(); });
}

// Column order: path segments compared one by one, numbers numerically, names by text; a
// shorter path (a prefix) first.
bool column_less(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const size_t ei = std::min(a.find('.', i), a.size());
    const size_t ej = std::min(b.find('.', j), b.size());
    const std::string sa = a.substr(i, ei - i), sb = b.substr(j, ej - j);
    if (sa != sb) {
      const bool na = !sa.empty() && std::all_of(sa.begin(), sa.end(), ::isdigit);
      const bool nb = !sb.empty() && std::all_of(sb.begin(), sb.end(), ::isdigit);
      if (na && nb) return std::stoll(sa) < std::stoll(sb);
      // Axis suffixes in their natural order, not alphabetical (x, y, z, w, h).
      static const std::string kAxes = "xyzwh";
      if (sa.size() == 1 && sb.size() == 1 && kAxes.find(sa[0]) != std::string::npos &&
          kAxes.find(sb[0]) != std::string::npos)
        return kAxes.find(sa[0]) < kAxes.find(sb[0]);
      return sa < sb;
    }
    i = ei + 1;
    j = ej + 1;
  }
  return a.size() < b.size();
}

const std::vector<std::string> kFixedColumns = {"time_s",     "stamp_ns", "status",       "ok",
                                                "confidence", "source",   "data_stamp_ns"};

}  // namespace

void flatten_json(const json& value, const std::string& prefix,
                  std::vector<std::pair<std::string, std::string>>& out, int max_list_items) {
  if (value.is_object()) {
    for (const auto& [k, v] : value.items()) flatten_json(v, join(prefix, k), out, max_list_items);
    return;
  }
  if (value.is_array()) {
    if (all_numbers(value) && value.size() >= 2 && value.size() <= 4) {
      static const char* kXyz[] = {"x", "y", "z"};
      static const char* kBox[] = {"x", "y", "w", "h"};
      // A 4-number box: the member's name, or one it is nested in, says "box" (box_px,
      // boxes.<camera>).
      const bool box = value.size() == 4 && prefix.find("box") != std::string::npos;
      for (size_t i = 0; i < value.size(); ++i)
        out.emplace_back(join(prefix, box                 ? kBox[i]
                                      : value.size() <= 3 ? kXyz[i]
                                                          : std::to_string(i)),
                         scalar_text(value[i]));
      return;
    }
    const bool objects =
        !value.empty() &&
        std::any_of(value.begin(), value.end(), [](const json& x) { return !x.is_primitive(); });
    if (objects) {
      out.emplace_back(join(prefix, "count"), std::to_string(value.size()));
      for (size_t i = 0; i < value.size() && static_cast<int>(i) < max_list_items; ++i)
        flatten_json(value[i], join(prefix, std::to_string(i)), out, max_list_items);
      return;
    }
    if (value.size() == 1) {  // a one-item list of plain values (e.g. a legacy tag)
      out.emplace_back(prefix, scalar_text(value[0]));
      return;
    }
    for (size_t i = 0; i < value.size(); ++i)
      out.emplace_back(join(prefix, std::to_string(i)), scalar_text(value[i]));
    return;
  }
  out.emplace_back(prefix, scalar_text(value));
}

// ---------------------------------------------------------------------------------------------
// Episodes

void EpisodeCollector::close(const std::string& type, Run& run, int64_t end_ns) {
  if (!run.open) return;
  run.open = false;
  const double start_s = (run.start_ns - first_stamp_ns_) * 1e-9;
  const double end_s = (end_ns - first_stamp_ns_) * 1e-9;
  episodes_.push_back({{"type", type},
                       {"label", run.label},
                       {"start_s", start_s},
                       {"end_s", end_s},
                       {"duration_s", end_s - start_s},
                       {"source", run.source},
                       {"detail", run.detail}});
}

void EpisodeCollector::add(const json& r) {
  const int64_t stamp = r.value("stamp_ns", int64_t{0});
  if (first_stamp_ns_ < 0) first_stamp_ns_ = stamp;
  if (stamp > last_stamp_ns_ && tick_ns_ == 0 && last_stamp_ns_ >= first_stamp_ns_ &&
      stamp != first_stamp_ns_)
    tick_ns_ = stamp - last_stamp_ns_;
  last_stamp_ns_ = std::max(last_stamp_ns_, stamp);
  const std::string primitive = r.value("primitive", "");
  const bool ok = r.value("status", "") == "ok";
  const json& v = r.contains("value") ? r.at("value") : json();
  const std::string source = r.contains("source") && r["source"].is_string() ? r["source"] : "";

  // Utterances (and who spoke them): one episode each, from their own start/end.
  if (ok && v.is_object() && v.contains("start_ns") && v.contains("end_ns") &&
      v["start_ns"].is_number() && v["end_ns"].is_number()) {
    const bool speech = v.contains("text");
    const std::string type =
        speech ? "speech"
               : (v.contains("speaker_id") || v.contains("name") ? "speaker" : primitive);
    std::string label = speech ? scalar_text(v["text"])
                               : scalar_text(v.value("name", json(v.value("speaker_id", json()))));
    const std::string key = fmt::format("{}|{}|{}", type, v["start_ns"].dump(), label);
    if (intervals_seen_.insert(key).second) {
      const double start_s = (v["start_ns"].get<int64_t>() - first_stamp_ns_) * 1e-9;
      const double end_s = (v["end_ns"].get<int64_t>() - first_stamp_ns_) * 1e-9;
      std::string detail;
      if (v.contains("confidence")) detail = "confidence " + scalar_text(v["confidence"]);
      if (v.contains("score")) detail = "score " + scalar_text(v["score"]);
      if (speech && v.contains("tag") && v["tag"] != v["text"])
        detail += (detail.empty() ? "" : "; ") + ("tag " + scalar_text(v["tag"]));
      episodes_.push_back({{"type", type},
                           {"label", label},
                           {"start_s", start_s},
                           {"end_s", end_s},
                           {"duration_s", end_s - start_s},
                           {"source", source},
                           {"detail", detail}});
    }
    return;
  }

  // Runs of ticks: mutual gaze (a boolean state) and any labelled value (gestures, expressions).
  std::string type, label;
  bool in_run = false;
  if (v.is_object() && v.contains("mutual") && v["mutual"].is_boolean()) {
    type = "mutual_gaze";
    label = "looking at " + v.value("target", std::string("robot"));
    in_run = ok && v["mutual"].get<bool>();
  } else if (v.is_object() && v.contains("label") && v["label"].is_string()) {
    type = primitive;
    label = v["label"].get<std::string>();
    in_run = ok && label != "none" && label != "unknown" && !label.empty();
  } else if (!ok && runs_.count(primitive) > 0) {
    type = primitive;  // a labelled primitive without an answer this tick
  } else if (!ok && primitive == "checkMutualGaze") {
    type = "mutual_gaze";
  } else {
    return;
  }
  Run& run = runs_[type];
  if (run.open && (!in_run || run.label != label)) close(type, run, stamp);
  if (in_run && !run.open) {
    run.open = true;
    run.label = label;
    run.source = source;
    run.start_ns = stamp;
    run.detail.clear();
  }
  if (in_run) run.last_ns = stamp;
}

std::vector<json> EpisodeCollector::finish() {
  for (auto& [type, run] : runs_) close(type, run, run.last_ns + tick_ns_);
  if (!mutual_gaze_target_.empty())
    for (auto& e : episodes_)
      if (e["type"] == "mutual_gaze") e["label"] = "looking at " + mutual_gaze_target_;
  std::stable_sort(episodes_.begin(), episodes_.end(), [](const json& a, const json& b) {
    return a["start_s"].get<double>() < b["start_s"].get<double>();
  });
  return episodes_;
}

// ---------------------------------------------------------------------------------------------
// Tables

namespace {

struct Table {
  std::string name, code, file;
  std::set<std::string, decltype(&column_less)> columns{&column_less};
  bool enabled = false;
};

Status for_each_record(const fs::path& path, const std::function<Status(const json&)>& f) {
  std::ifstream in(path);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot read", path.string());
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    json r = json::parse(line, nullptr, false);
    if (r.is_discarded() || !r.is_object() || !r.contains("primitive"))
      return make_error(ErrorCode::kCorruptData, "{}: line {}: not a primitive record",
                        path.string(), n);
    DS_RETURN_IF_ERROR(f(r));
  }
  return ok_status();
}

std::vector<std::pair<std::string, std::string>> value_cells(const json& r, int max_items) {
  std::vector<std::pair<std::string, std::string>> cells;
  if (r.contains("query") && !r["query"].is_null())
    flatten_json(r["query"], "query", cells, max_items);
  if (r.contains("value") && !r["value"].is_null()) flatten_json(r["value"], "", cells, max_items);
  return cells;
}

std::string format_time(int64_t ns) { return fmt::format("{:.3f}", ns * 1e-9); }

}  // namespace

Result<std::vector<fs::path>> write_csv_tables(const fs::path& primitives_jsonl,
                                               const fs::path& dir,
                                               const CsvTablesOptions& options) {
  // Pass 1: which primitives were evaluated and the union of their value columns.
  std::map<std::string, Table> tables;  // by primitive name
  std::vector<std::string> order;       // primitive names in file (= catalogue) order
  int64_t first_stamp = -1;
  DS_RETURN_IF_ERROR(for_each_record(primitives_jsonl, [&](const json& r) -> Status {
    const std::string name = r["primitive"].get<std::string>();
    Table& t = tables[name];
    if (t.name.empty()) {
      order.push_back(name);
      t.name = name;
      t.code = r.value("id", "");
      t.file = csv_table_name(t.code, name);
    }
    if (first_stamp < 0) first_stamp = r.value("stamp_ns", int64_t{0});
    if (r.value("status", "") != "disabled") t.enabled = true;
    for (const auto& [k, v] : value_cells(r, options.max_list_items)) t.columns.insert(k);
    return ok_status();
  }));
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec)
    return make_error(ErrorCode::kInvalidArgument, "{}: cannot create the folder: {}", dir.string(),
                      ec.message());

  // Pass 2: rows, and episodes.
  std::map<std::string, std::unique_ptr<OutputFile>> files;
  std::map<std::string, std::map<std::string, size_t>> column_index;
  json index = {{"approximate_calibration", options.approximate_calibration},
                {"time_origin", "time_s is seconds since the first tick (stamp_ns " +
                                    std::to_string(std::max<int64_t>(first_stamp, 0)) + ")"},
                {"tables", json::object()}};
  for (auto& [name, t] : tables) {
    if (!t.enabled) continue;
    auto f = std::make_unique<OutputFile>();
    DS_RETURN_IF_ERROR(f->open(dir / t.file));
    std::string header;
    std::vector<std::string> cols = kFixedColumns;
    cols.insert(cols.end(), t.columns.begin(), t.columns.end());
    for (size_t i = 0; i < cols.size(); ++i) {
      header += (i ? "," : "") + csv_cell(cols[i]);
      if (i >= kFixedColumns.size()) column_index[name][cols[i]] = i - kFixedColumns.size();
    }
    DS_RETURN_IF_ERROR(f->write(header + "\n"));
    index["tables"][t.file] = {{"primitive", name}, {"code", t.code}, {"columns", cols}};
    files[name] = std::move(f);
  }
  // ticks.csv: every table side by side, one row per tick; a primitive's columns are prefixed
  // with its plain name (getHeadGaze.yaw_deg), each with its .ok flag and .confidence.
  OutputFile wide;
  DS_RETURN_IF_ERROR(wide.open(dir / "ticks.csv"));
  std::map<std::string, size_t> wide_offset;  // primitive -> index of its .ok cell
  std::vector<std::string> wide_cols = {"time_s", "stamp_ns"};
  for (const auto& name : order) {
    const Table& t = tables[name];
    if (!t.enabled) continue;
    const std::string p = plain_name(name);
    wide_offset[name] = wide_cols.size() - 2;
    wide_cols.push_back(p + ".ok");
    wide_cols.push_back(p + ".confidence");
    for (const auto& c : t.columns) wide_cols.push_back(p + "." + c);
  }
  {
    std::string header;
    for (size_t i = 0; i < wide_cols.size(); ++i) header += (i ? "," : "") + csv_cell(wide_cols[i]);
    DS_RETURN_IF_ERROR(wide.write(header + "\n"));
  }
  index["tables"]["ticks.csv"] = {{"columns", wide_cols}};
  std::vector<std::string> wide_cells(wide_cols.size() - 2);
  int64_t wide_stamp = 0;
  bool wide_pending = false;
  auto flush_wide = [&]() -> Status {
    if (!wide_pending) return ok_status();
    std::string line = format_time(wide_stamp - first_stamp) + "," + std::to_string(wide_stamp);
    for (auto& c : wide_cells) {
      line += "," + c;
      c.clear();
    }
    wide_pending = false;
    return wide.write(line + "\n");
  };

  EpisodeCollector episodes;
  episodes.set_mutual_gaze_target(options.mutual_gaze_target);
  std::string row;
  DS_RETURN_IF_ERROR(for_each_record(primitives_jsonl, [&](const json& r) -> Status {
    episodes.add(r);
    const std::string name = r["primitive"].get<std::string>();
    auto f = files.find(name);
    if (f == files.end()) return ok_status();
    const int64_t stamp = r.value("stamp_ns", int64_t{0});
    const std::string status = r.value("status", "");
    if (wide_pending && stamp != wide_stamp) DS_RETURN_IF_ERROR(flush_wide());
    wide_stamp = stamp;
    wide_pending = true;
    const size_t w0 = wide_offset.at(name);
    wide_cells[w0] = status == "ok" ? "1" : "0";
    wide_cells[w0 + 1] = r.contains("confidence") ? scalar_text(r["confidence"]) : "";
    row = format_time(stamp - first_stamp) + "," + std::to_string(stamp) + "," + status + "," +
          (status == "ok" ? "1" : "0") + "," +
          (r.contains("confidence") ? scalar_text(r["confidence"]) : "") + "," +
          csv_cell(r.contains("source") ? scalar_text(r["source"]) : "") + "," +
          (r.contains("data_stamp_ns") ? scalar_text(r["data_stamp_ns"]) : "");
    const auto& idx = column_index[name];
    std::vector<std::string> cells(idx.size());
    for (const auto& [k, v] : value_cells(r, options.max_list_items))
      if (auto it = idx.find(k); it != idx.end()) cells[it->second] = csv_cell(v);
    for (size_t i = 0; i < cells.size(); ++i) {
      row += "," + cells[i];
      wide_cells[w0 + 2 + i] = cells[i];
    }
    row += "\n";
    return f->second->write(row);
  }));

  DS_RETURN_IF_ERROR(flush_wide());
  DS_RETURN_IF_ERROR(wide.commit());
  std::vector<fs::path> written = {dir / "ticks.csv"};
  for (auto& [name, f] : files) {
    DS_RETURN_IF_ERROR(f->commit());
    written.push_back(dir / tables[name].file);
  }
  OutputFile ev;
  DS_RETURN_IF_ERROR(ev.open(dir / "events.csv"));
  DS_RETURN_IF_ERROR(ev.write("type,label,start_s,end_s,duration_s,source,detail\n"));
  std::vector<json> rows = episodes.finish();
  for (const auto& m : options.markers) {
    const double t = static_cast<double>(m.stamp_ns - std::max<int64_t>(first_stamp, 0)) * 1e-9;
    rows.push_back({{"type", "marker"},
                    {"label", m.label},
                    {"start_s", t},
                    {"end_s", t},
                    {"duration_s", 0.0},
                    {"source", m.source},
                    {"detail", m.detail}});
  }
  std::stable_sort(rows.begin(), rows.end(), [](const json& a, const json& b) {
    return a["start_s"].get<double>() < b["start_s"].get<double>();
  });
  for (const auto& e : rows)
    DS_RETURN_IF_ERROR(ev.write(fmt::format(
        "{},{},{:.3f},{:.3f},{:.3f},{},{}\n", csv_cell(e["type"].get<std::string>()),
        csv_cell(e["label"].get<std::string>()), e["start_s"].get<double>(),
        e["end_s"].get<double>(), e["duration_s"].get<double>(),
        csv_cell(e["source"].get<std::string>()), csv_cell(e["detail"].get<std::string>()))));
  DS_RETURN_IF_ERROR(ev.commit());
  written.push_back(dir / "events.csv");
  index["tables"]["events.csv"] = {
      {"columns", {"type", "label", "start_s", "end_s", "duration_s", "source", "detail"}}};
  OutputFile ix;
  DS_RETURN_IF_ERROR(ix.open(dir / "tables.json"));
  DS_RETURN_IF_ERROR(ix.write(index.dump(2) + "\n"));
  DS_RETURN_IF_ERROR(ix.commit());
  written.push_back(dir / "tables.json");
  return written;
}

}  // namespace dreamsense::exporters
