#pragma once
// Each verb is a thin layer: flags -> library options -> run -> exit code.

#include "dreamsense/core/status.hpp"
#include "dreamsense/runner/analysis.hpp"
#include "dreamsense/self_calibration/analysis.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace dreamsense::app {

struct GlobalFlags {
  bool quiet = false;
  bool verbose = false;
};

// Exit codes.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  // bad input or a failed run (one-line reason on stderr)

// Prints "error: <message>" on one line and returns kExitFailure.
int fail(const Error& e);
int fail(const std::string& message);

// Runs a session analysis with a progress bar (cmd_analyze.cpp); used by analyze, demo, eval.
Result<runner::AnalysisSummary> run_analysis_with_progress(const runner::AnalysisOptions& o,
                                                           bool quiet);

// Writes JSON to a file, or to stdout for "-". Empty target: does nothing.
Status write_json(const std::string& target, const nlohmann::json& j);

void add_demo(CLI::App& app, const GlobalFlags& g, int& exit_code);
void add_analyze(CLI::App& app, const GlobalFlags& g, int& exit_code);
void add_eval(CLI::App& app, const GlobalFlags& g, int& exit_code);
void add_bench(CLI::App& app, const GlobalFlags& g, int& exit_code);
void add_record(CLI::App& app, const GlobalFlags& g, int& exit_code);  // cmd_record.cpp
void add_live(CLI::App& app, const GlobalFlags& g, int& exit_code);    // cmd_analyze.cpp
void add_batch(CLI::App& app, const GlobalFlags& g, int& exit_code);   // cmd_batch.cpp
void add_check(CLI::App& app, const GlobalFlags& g, int& exit_code);   // cmd_check.cpp

// Verbs of other modules, each in its own file (cmd_<module>.cpp).
void add_calibrate(CLI::App& app, const GlobalFlags& g, int& exit_code);  // cmd_calibrate.cpp
void add_eval_calibration(CLI::App& eval, const GlobalFlags& g,
                          int& exit_code);                                     // cmd_calibrate.cpp
void add_eval_doa(CLI::App& eval, const GlobalFlags& g, int& exit_code);       // cmd_audio.cpp
void add_eval_speech(CLI::App& eval, const GlobalFlags& g, int& exit_code);    // cmd_speech.cpp
void add_train_speech(CLI::App& train, const GlobalFlags& g, int& exit_code);  // cmd_speech.cpp
void add_eval_eyes(CLI::App& eval, const GlobalFlags& g, int& exit_code);      // cmd_eyes.cpp
// cmd_objects.cpp: `eval tracking`, `eval objects` and `enroll objects` (toys on the table).
void add_eval_tracking(CLI::App& eval, const GlobalFlags& g, int& exit_code);
void add_enroll_objects(CLI::App& enroll, const GlobalFlags& g, int& exit_code);
void add_eval_objects(CLI::App& eval, const GlobalFlags& g, int& exit_code);

// cmd_voices.cpp: `train voices` (under the `train` verb of main.cpp) and `eval voices`.
void add_train_voices(CLI::App& train, const GlobalFlags& g, int& exit_code);
void add_eval_voices(CLI::App& eval, const GlobalFlags& g, int& exit_code);

// cmd_actions.cpp: `train actions`, `train gestures` (under `train`) and `eval actions`.
void add_train_actions(CLI::App& train, const GlobalFlags& g, int& exit_code);
void add_train_gestures(CLI::App& train, const GlobalFlags& g, int& exit_code);
void add_eval_actions(CLI::App& eval, const GlobalFlags& g, int& exit_code);

// cmd_faces.cpp: `train expression`, `eval expression`, `enroll faces`, `eval faces`.
void add_train_expression(CLI::App& train, const GlobalFlags& g, int& exit_code);
void add_eval_expression(CLI::App& eval, const GlobalFlags& g, int& exit_code);
void add_eval_faces(CLI::App& eval, const GlobalFlags& g, int& exit_code);
void add_enroll_faces(CLI::App& enroll, const GlobalFlags& g, int& exit_code);

// cmd_landmarks.cpp: `eval landmarks` (issue 20: face detection + 68 landmarks on 300-W faces).
void add_eval_landmarks(CLI::App& eval, const GlobalFlags& g, int& exit_code);

// The declared pipeline's flags (cmd_analyze.cpp; analyze, live, bench pipeline): --pipeline FILE,
// --set ANALYSER.KEY=VALUE, --enable/--disable ANALYSER.
struct PipelineFlags {
  std::string pipeline;          // pipeline.yaml
  std::vector<std::string> set;  // ANALYSER.KEY=VALUE
  std::vector<std::string> enable, disable;
  int threads = 0;  // --threads: runner::AnalysisOptions::threads
};
void add_pipeline_flags(CLI::App& cmd, PipelineFlags& flags);
Status apply_pipeline_flags(const PipelineFlags& flags, runner::PlanOptions& plan);

// The child's calibration for analyses (cmd_analyze.cpp): --subject DIR|none, --face-model,
// --gaze-model, --speech-model.
struct SubjectFlags {
  std::string subject, face_model, gaze_model, speech_model, subjects_dir;
};
void add_subject_flags(CLI::App& cmd, SubjectFlags& flags);
void apply_subject_flags(const SubjectFlags& flags, runner::AnalysisOptions& o);
// Self-calibration (issue 15, library self_calibration/): `--subject auto` always; by default
// when the session's subject has no calibration folder (and no explicit model file); never with
// `--subject none` or a subject folder. run_analysis_with_progress runs it first, uses its files
// and adds its status to summary.json.
using self_calibration::SelfCalibrationMode;
SelfCalibrationMode self_calibration_mode(const SubjectFlags& flags);  // cmd_selfcal.cpp
Result<runner::AnalysisSummary> run_analysis_with_progress(const runner::AnalysisOptions& o,
                                                           bool quiet, SelfCalibrationMode mode,
                                                           bool save_subject = false);

// cmd_gaze.cpp: `train face` (the child's 3-D face model) and `train gaze` (subject calibration:
// head-model offset and D4.2 eq. 4 constants).
void add_train_gaze(CLI::App& train, const GlobalFlags& g, int& exit_code);
void add_train_face(CLI::App& train, const GlobalFlags& g, int& exit_code);

}  // namespace dreamsense::app
