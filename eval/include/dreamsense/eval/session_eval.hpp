#pragma once
// `dreamsense eval session`: compares an analysis (primitives.jsonl) with the session's
// truth.jsonl. Writes the evaluation JSON of cli.md (task "session"). Metrics whose primitives
// were disabled or not covered by the truth are null, with the reason under "not_evaluated".

#include "dreamsense/core/status.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace dreamsense::eval {

struct SessionEvalOptions {
  std::filesystem::path session_dir;
  std::filesystem::path analysis_dir;  // holds primitives.jsonl
  Status check() const;
};

Result<nlohmann::json> evaluate_session(const SessionEvalOptions& options);

}  // namespace dreamsense::eval
