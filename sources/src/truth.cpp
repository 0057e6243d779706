// truth.jsonl reader (docs/truth_format.md).

#include "dreamsense/sources/truth.hpp"

#include <fmt/format.h>

#include <fstream>
#include <string>

namespace dreamsense::sources {

Result<std::vector<nlohmann::json>> read_truth(const std::filesystem::path& truth_jsonl) {
  const std::string name = truth_jsonl.string();
  std::error_code ec;
  if (!std::filesystem::exists(truth_jsonl, ec))
    return make_error(ErrorCode::kNotFound, "{}: missing", name);
  std::ifstream in(truth_jsonl, std::ios::binary);
  if (!in) return make_error(ErrorCode::kIoError, "{}: cannot read", name);
  std::vector<nlohmann::json> records;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(line);
    } catch (const nlohmann::json::exception& e) {
      return make_error(ErrorCode::kCorruptData, "{}: line {}: malformed JSON: {}", name, number,
                        e.what());
    }
    if (!j.is_object())
      return make_error(ErrorCode::kCorruptData, "{}: line {}: expected a JSON object", name,
                        number);
    if (!j.contains("type") || !j["type"].is_string())
      return make_error(ErrorCode::kCorruptData, "{}: line {}: missing string \"type\"", name,
                        number);
    records.push_back(std::move(j));
  }
  if (in.bad()) return make_error(ErrorCode::kIoError, "{}: read failed", name);
  return records;
}

}  // namespace dreamsense::sources
