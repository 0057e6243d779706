#pragma once
// Offline analysis of a recorded session (`dreamsense analyze`): opens and validates the session,
// builds the analysers its streams support, runs the pipeline and writes
//   primitives.jsonl, events.log, dream.json, summary.json
// into the output folder. Outputs appear under their final names only when complete.

#include "dreamsense/core/pipeline.hpp"
#include "dreamsense/primitives/evaluator.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <string>

namespace dreamsense::runner {

struct AnalysisOptions {
  std::filesystem::path session_dir;
  std::filesystem::path out_dir;             // empty: run without writing outputs (benchmarks)
  SyncPolicy policy = SyncPolicy::kSettled;  // replay: settled (deterministic)
  bool pace_source = true;                   // live policy only
  primitives::EvaluatorOptions evaluator;
  // Grammar for recognizeSpeech (JSGF or SRGS .grxml). Empty: the session's own
  // (metadata speech_grammar, relative to the session folder), else speech recognition is off.
  std::filesystem::path speech_grammar;
  Status check() const;
};

struct AnalysisSummary {
  PipelineStats pipeline;
  std::vector<std::string> analyzers;  // names of the analysers that ran
  std::map<std::string, std::map<std::string, int>> status_counts;  // primitive -> status -> n
  std::vector<std::filesystem::path> outputs;
  nlohmann::json to_json() const;
};

using AnalysisProgress = std::function<void(double fraction)>;

Result<AnalysisSummary> analyze_session(const AnalysisOptions& options,
                                        const AnalysisProgress& progress = nullptr);

}  // namespace dreamsense::runner
