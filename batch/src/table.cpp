#include "dreamsense/batch/table.hpp"

#include <algorithm>
#include <set>

namespace dreamsense::batch {

std::string csv_cell(std::string_view text) {
  if (text.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(text);
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

std::string csv_row(const std::vector<std::string>& cells) {
  std::string line;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (i > 0) line += ',';
    line += csv_cell(cells[i]);
  }
  line += '\n';
  return line;
}

namespace {

std::string scalar_cell(const nlohmann::json& v) {
  if (v.is_null()) return "";
  if (v.is_string()) return v.get<std::string>();
  return v.dump();  // numbers (shortest round-trip form), true/false
}

bool is_fixed(const std::string& name) {
  const auto& f = fixed_columns();
  return std::find(f.begin(), f.end(), name) != f.end();
}

}  // namespace

void flatten_json(const nlohmann::json& j, std::map<std::string, std::string>& out,
                  const std::string& prefix) {
  if (!j.is_object()) return;
  for (const auto& [key, v] : j.items()) {
    const std::string name = prefix.empty() ? key : prefix + "." + key;
    if (v.is_object()) {
      flatten_json(v, out, name);
    } else if (v.is_array()) {
      const bool scalars = std::all_of(v.begin(), v.end(), [](const nlohmann::json& e) {
        return !e.is_object() && !e.is_array();
      });
      if (!scalars) continue;
      std::string cell;
      for (size_t i = 0; i < v.size(); ++i) cell += (i ? ";" : "") + scalar_cell(v[i]);
      out[prefix.empty() && is_fixed(name) ? "summary." + name : name] = cell;
    } else {
      out[prefix.empty() && is_fixed(name) ? "summary." + name : name] = scalar_cell(v);
    }
  }
}

std::vector<std::string> table_columns(const std::vector<TableRow>& rows) {
  std::set<std::string> figures;
  for (const auto& r : rows)
    for (const auto& [k, v] : r.figures) figures.insert(k);
  std::vector<std::string> columns = fixed_columns();
  columns.insert(columns.end(), figures.begin(), figures.end());
  return columns;
}

std::string format_table(const std::vector<TableRow>& rows) {
  const auto columns = table_columns(rows);
  const size_t fixed = fixed_columns().size();
  std::string text = csv_row(columns);
  for (const auto& r : rows) {
    std::vector<std::string> cells = {r.input, r.output, r.status, r.reason,
                                      r.seconds ? fmt::format("{:.3f}", *r.seconds) : ""};
    for (size_t c = fixed; c < columns.size(); ++c) {
      auto it = r.figures.find(columns[c]);
      cells.push_back(it == r.figures.end() ? "" : it->second);
    }
    text += csv_row(cells);
  }
  return text;
}

}  // namespace dreamsense::batch
