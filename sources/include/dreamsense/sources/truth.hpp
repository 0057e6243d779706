#pragma once
// Ground truth of a session (truth.jsonl): one JSON object per line, each with a "type".
// The record types are documented in docs/truth_format.md.

#include "dreamsense/core/status.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

namespace dreamsense::sources {

Result<std::vector<nlohmann::json>> read_truth(const std::filesystem::path& truth_jsonl);

}  // namespace dreamsense::sources
