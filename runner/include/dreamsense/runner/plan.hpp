#pragma once
// The analysis graph of one session: every registered analyser factory (perception/
// analyzer_registry.hpp) plans itself from the session's streams and roles, pipeline.yaml and the
// command line; analysers whose reads have no writer are dropped with the reason; the rest are
// ordered by their contracts. `dreamsense analyze --print-pipeline` prints describe().

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/primitives/context.hpp"
#include "dreamsense/runner/pipeline_config.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense::runner {

// data/subjects of the source tree (calibrations shipped with dreamsense, e.g. the demo child's).
std::filesystem::path default_subjects_dir();

// A command-line override of one analyser option: `value` is YAML text ("camera_plane",
// "[0, -0.05, 0.15]", "false"); `key` may be dotted ("mutual.mode").
struct OptionOverride {
  std::string analyzer;
  std::string key;
  std::string value;
};

// What the planner needs besides the session.
struct PlanOptions {
  std::filesystem::path pipeline_file;    // pipeline.yaml; empty: every analyser's defaults
  std::vector<OptionOverride> overrides;  // applied over pipeline.yaml's options
  std::map<std::string, bool> enable;     // command-line on/off, over pipeline.yaml's
  // The child's calibration: a folder with face_model.yaml, gaze.yaml and/or speech_model/.
  // Empty subject_dir: when subject_from_session is true and the session's metadata `subject`
  // names a folder under subjects_dir, that folder; otherwise none (generic face model,
  // built-in gaze constants).
  std::filesystem::path subject_dir;
  bool subject_from_session = true;
  std::filesystem::path subjects_dir = default_subjects_dir();
  // Explicit files, overriding the subject folder's.
  std::filesystem::path face_model, gaze_model, speech_model;
  // Live capture: the manifest's metadata files are the operator's absolute paths.
  bool absolute_paths_allowed = false;
  // Privacy (--include-names): false = ids only in every output (PlanContext::include_names;
  // docs/outputs.md "Names"), the session's name and metadata values left out of the outputs.
  bool include_names = false;
  // A live analysis (PlanContext::live); set by the runner from the sync policy.
  bool live = false;
  // Assumed intrinsics of colour streams that have no calibration file (a plain video): the
  // factories get them as the stream's camera, flagged approximate_calibration.
  std::map<SensorId, CameraModel> assumed_cameras;
  Status check() const;
};

struct FactoryOutcome {
  std::string name, summary;
  std::vector<std::string> roles;
  std::string skipped;             // why it does not run; empty when it runs
  std::vector<std::string> notes;  // facts about the plan (model files, assumptions)
  std::vector<std::pair<std::string, std::string>> options;  // effective options
  std::vector<std::string> analyzers;                        // the analysers it planned
};

struct PipelinePlan {
  std::vector<std::unique_ptr<Analyzer>> analyzers;  // in execution order
  std::vector<FactoryOutcome> factories;             // in registration order
  std::vector<StreamDescription> streams;
  std::vector<SensorId> used;               // streams some analyser reads
  std::map<SensorId, CameraModel> cameras;  // calibrated colour streams
  primitives::KeySensors key_sensors;       // keys written and the sensors behind them
  SubjectFiles subject;
  std::string config;  // the pipeline.yaml used, or "defaults"
  // The human-readable graph (streams and roles, analysers in order with inputs, reads, writes
  // and effective options, what was not planned and why, the primitives enabled).
  std::string describe() const;
  nlohmann::json to_json() const;
};

// `dir`: the folder the manifest's file references are relative to (the session folder; for a
// live capture the files are absolute).
Result<PipelinePlan> plan_pipeline(const PlanOptions& options,
                                   const sources::SessionManifest& manifest,
                                   const std::filesystem::path& dir);

// The analysers of the factories that use the child's face and gaze models
// (AnalyzerFactory::uses_subject_models), planned again as plan_pipeline plans them but with
// `face_model` and `gaze_model` in place of the subject's: a live analysis swaps them in
// (Pipeline::replace_analyzers) once its self-calibration converged. Only those factories run
// (no other model is loaded again).
Result<std::vector<std::unique_ptr<Analyzer>>> replan_subject_analyzers(
    const PlanOptions& options, const sources::SessionManifest& manifest,
    const std::filesystem::path& dir, const std::filesystem::path& face_model,
    const std::filesystem::path& gaze_model);

}  // namespace dreamsense::runner
