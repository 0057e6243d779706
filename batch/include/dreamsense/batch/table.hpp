#pragma once
// batch.csv: one row per input. Fixed columns first (input, output, status, reason, seconds),
// then the figures of each analysis' summary.json flattened into columns; the figure columns are
// the union over all rows, sorted by name, and a row without a figure leaves its cell empty.
//
// Flattening (flatten_json): nested objects give dotted names (status_counts.sessionDetect.ok);
// numbers, strings and booleans (true/false) are cells, null an empty cell; an array of scalars is
// one cell with its items joined by ';'; arrays holding objects or arrays are per-item detail, not
// figures, and give no column. A figure whose name equals a fixed column is prefixed "summary.".
// Quoting is RFC 4180 (a cell with a comma, a double quote or a line break is quoted, quotes
// doubled); rows end with "\n".

#include "dreamsense/core/status.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense::batch {

struct TableRow {
  std::string input;              // the input's absolute path
  std::string output;             // its output folder name under the batch folder (empty when none)
  std::string status;             // ok, failed or skipped
  std::string reason;             // failed/skipped: why
  std::optional<double> seconds;  // analysis wall time, when it ran
  std::map<std::string, std::string> figures;  // flattened summary.json
};

inline const std::vector<std::string>& fixed_columns() {
  static const std::vector<std::string> k = {"input", "output", "status", "reason", "seconds"};
  return k;
}

std::string csv_cell(std::string_view text);
std::string csv_row(const std::vector<std::string>& cells);  // ends with "\n"

// Adds the figures of `j` (an object) to `out` under `prefix`.
void flatten_json(const nlohmann::json& j, std::map<std::string, std::string>& out,
                  const std::string& prefix = "");

std::vector<std::string> table_columns(const std::vector<TableRow>& rows);
std::string format_table(const std::vector<TableRow>& rows);

}  // namespace dreamsense::batch
