#pragma once
// Offline analysis of a recorded session (`dreamsense analyze`): opens and validates the session,
// builds the analysers its streams support, runs the pipeline and writes
//   primitives.jsonl, events.log, dream.json, summary.json
// into the output folder. Outputs appear under their final names only when complete.

#include "dreamsense/core/pipeline.hpp"
#include "dreamsense/gaze/mutual_gaze.hpp"
#include "dreamsense/primitives/evaluator.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <string>

namespace dreamsense::sources {
class LiveCapture;
}

namespace dreamsense::runner {

// data/subjects of the source tree (calibrations shipped with dreamsense, e.g. the demo child's).
std::filesystem::path default_subjects_dir();

struct AnalysisOptions {
  std::filesystem::path session_dir;
  std::filesystem::path out_dir;             // empty: run without writing outputs (benchmarks)
  SyncPolicy policy = SyncPolicy::kSettled;  // replay: settled (deterministic)
  bool pace_source = true;                   // live policy only
  primitives::EvaluatorOptions evaluator;
  // Grammar for recognizeSpeech (JSGF or SRGS .grxml). Empty: the session's own
  // (metadata speech_grammar, relative to the session folder), else speech recognition is off.
  std::filesystem::path speech_grammar;
  // Speaker identification (identifyVoice, modalities/voice_id), chosen explicitly:
  //  "gmm_ubm": speaker models, from voice_model (a file from `train voices`) or, when that is
  //    empty, trained here from the session's enrolment audio (metadata voice_enroll: a folder,
  //    relative to the session, with one subfolder of recordings per speaker); with neither,
  //    identifyVoice is disabled (never a silent switch to the direction rule);
  //  "direction_rule": DREAM's rule on the sound direction, no speaker models;
  //  "off".
  std::string voice_method = "gmm_ubm";
  std::filesystem::path voice_model;
  // The child's calibration: a folder with face_model.yaml (the 3-D landmark shape for head pose,
  // `dreamsense train face`), gaze.yaml (gaze constants, `dreamsense train gaze`) and/or
  // speech_model/ (an acoustic model adapted to the child's voice, `dreamsense train speech`).
  // Empty subject_dir: when subject_from_session is true and the session's metadata `subject`
  // names a folder under subjects_dir, that folder; otherwise no calibration (the generic face
  // model and the built-in gaze constants, modalities/head_pose and gaze READMEs).
  std::filesystem::path subject_dir;
  bool subject_from_session = true;
  std::filesystem::path subjects_dir = default_subjects_dir();
  // Explicit files, overriding the subject folder's.
  std::filesystem::path face_model;
  std::filesystem::path gaze_model;
  std::filesystem::path speech_model;  // a model folder for recognizeSpeech
  // Mutual gaze (F1). Its robot_head_m is replaced by the session's metadata `robot_head_m`
  // ("x y z" in metres, world) when the session has one and robot_head_from_session is true.
  gaze::MutualGazeOptions mutual_gaze;
  bool robot_head_from_session = true;
  // Also write overlay.mp4 (boxes, landmarks, head axes, gaze rays, selected camera).
  bool overlay = false;
  // Called with every tick's primitive records as they are produced (e.g. DDS publishing in
  // `live --publish dds`); an error ends the analysis.
  std::function<Status(const std::vector<primitives::PrimitiveRecord>&)> on_records;
  // Called with every tick's frames before its primitives (e.g. the operator page's cameras).
  std::function<void(const MultiFrame&)> on_tick_frames;
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

// Live analysis (`dreamsense live`): the analysers the capture's streams support, run on its
// frames as they arrive (latest-within-tolerance policy with the flow limiter: a slow analyser
// drops ticks, counted, instead of falling behind), with the same outputs as analyze_session.
// options.session_dir is not used (the capture's manifest describes the streams). Returns when
// the capture has ended (LiveCapture::stop()); the caller then calls capture.finish().
Result<AnalysisSummary> analyze_live(const AnalysisOptions& options, sources::LiveCapture& capture);

}  // namespace dreamsense::runner
